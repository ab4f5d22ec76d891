//! The runs of a study: its plan, how run `i` is expanded from the axes
//! and draws, its seed, and shards.

use super::schema::{Axis, Dist, Draw, Study};
use crate::scenario::Loop;
use crate::scenario::Reason;

/// SplitMix64: the seed of run `i` of a study with seed `seed`.
pub fn derive_seed(seed: u64, i: u64) -> u64 {
    let mut z = seed
        ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A small deterministic stream of uniforms on [0, 1) from a run seed.
struct Stream(u64);

impl Stream {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let z = derive_seed(self.0, 0);
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

impl Draw {
    fn sample(&self, s: &mut Stream) -> toml::Value {
        let (lo, hi) = (self.low.unwrap_or(0.0), self.high.unwrap_or(1.0));
        // The plan checked that the bounds and their width are finite; the
        // clamp keeps rounding (at the top of the range, or in exp∘ln) from
        // stepping outside them, so a draw is always finite.
        match self.dist {
            Dist::Uniform => toml::Value::Float((lo + (hi - lo) * s.next()).clamp(lo, hi)),
            Dist::Loguniform => toml::Value::Float(
                (lo.ln() + (hi.ln() - lo.ln()) * s.next())
                    .exp()
                    .clamp(lo, hi),
            ),
            Dist::Normal => {
                // Box–Muller from two uniforms (1 − u keeps the log finite).
                let (u1, u2) = (1.0 - s.next(), s.next());
                let z = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
                toml::Value::Float(self.mean.unwrap_or(0.0) + self.sd.unwrap_or(0.0) * z)
            }
            Dist::Choice => {
                let i = ((s.next() * self.values.len() as f64) as usize).min(self.values.len() - 1);
                self.values[i].clone()
            }
        }
    }
}

/// A study, checked, with its base scenario and expanded axes.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The study file, as its errors name it.
    pub file: String,
    /// The study as written.
    pub study: Study,
    /// The base scenario with `set` applied, built.
    pub base: Loop,
    /// Expanded values of every axis.
    pub axes: Vec<(Axis, Vec<toml::Value>)>,
    /// Replicates per grid point (1 without Monte Carlo).
    pub replicates: u64,
    /// Total runs.
    pub runs: u64,
    /// `base` as a TOML table, made once for every run to start from
    /// (None if it could not be made: each run then reports why).
    pub(crate) base_table: Option<toml::Table>,
    /// Whether `base` survives its TOML round trip unchanged (checked
    /// once): then a run that changes only `uncertainty.seed` (a Monte
    /// Carlo study over the seed alone) sets it on a clone of `base`
    /// instead of rebuilding the scenario from the table.
    pub(crate) seed_only_typed: bool,
}

impl Plan {
    /// The axis of the base scenario's plant: the unit of the study's errors.
    pub fn axis(&self) -> crate::axis::Axis {
        self.base.axis()
    }

    /// The varied columns of results.csv, in order: axes, then drawn keys.
    pub fn columns(&self) -> Vec<String> {
        self.study.columns()
    }

    /// The values of run `i`: (column values, scenario overrides, seed).
    pub fn run_values(&self, i: u64) -> (Vec<toml::Value>, Vec<(String, toml::Value)>, u64) {
        let seed = derive_seed(self.study.seed, i);
        let mut g = i / self.replicates;
        let mut idx = vec![0usize; self.axes.len()];
        for (k, (_, vals)) in self.axes.iter().enumerate().rev() {
            let n = vals.len() as u64;
            idx[k] = (g % n) as usize;
            g /= n;
        }
        let mut cols = Vec::new();
        let mut sets = Vec::new();
        for (k, (a, vals)) in self.axes.iter().enumerate() {
            let v = vals[idx[k]].clone();
            for key in a.keys() {
                sets.push((key, v.clone()));
            }
            cols.push(v);
        }
        if let Some(mc) = &self.study.monte_carlo {
            sets.push((
                "uncertainty.seed".into(),
                toml::Value::Integer((seed >> 1) as i64),
            ));
            let mut s = Stream(seed);
            for d in &mc.draw {
                let v = d.sample(&mut s);
                sets.push((d.key.clone(), v.clone()));
                cols.push(v);
            }
        }
        (cols, sets, seed)
    }

    /// Run `i`'s loop, built from the base with the run's overrides `sets`.
    pub fn build_run(
        &self,
        sets: &[(String, toml::Value)],
    ) -> Result<Loop, crate::scenario::ScenarioError> {
        if let [(key, toml::Value::Integer(seed))] = sets {
            if self.seed_only_typed && key.trim() == "uncertainty.seed" && *seed >= 0 {
                return self.base.with_seed(*seed as u64);
            }
        }
        match &self.base_table {
            Some(t) => self.base.with_values_on(t.clone(), sets),
            None => self.base.with_values(sets),
        }
    }

    /// The run indices of shard `k` of `n` (contiguous).
    pub fn shard_range(&self, k: u64, n: u64) -> std::ops::Range<u64> {
        shard_range(self.runs, k, n)
    }
}

/// The run indices of shard `k` of `n` (contiguous) of `runs` runs
/// (`k < n`).
pub(super) fn shard_range(runs: u64, k: u64, n: u64) -> std::ops::Range<u64> {
    let lo = (runs as u128 * k as u128 / n as u128) as u64;
    let hi = (runs as u128 * (k as u128 + 1) / n as u128) as u64;
    lo..hi
}

/// Parses `K/N` (0 ≤ K < N).
pub fn parse_shard(s: &str) -> Result<(u64, u64), Reason> {
    let (k, n) = s.split_once('/').ok_or("expected K/N, e.g. 0/4")?;
    let k: u64 = k
        .trim()
        .parse()
        .map_err(|_| format!("K in {s} is not a whole number"))?;
    let n: u64 = n
        .trim()
        .parse()
        .map_err(|_| format!("N in {s} is not a whole number"))?;
    if n == 0 || k >= n {
        return Err(Reason::Other(format!(
            "need 0 ≤ K < N (got {k}/{n}); K counts from 0"
        )));
    }
    Ok((k, n))
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::study::as_f64;

    fn plan(text: &str) -> Plan {
        let study: Study = toml::from_str(text).unwrap();
        Plan::build(study, Loop::parse("").unwrap(), "t.toml").unwrap()
    }

    /// A seed-only run set on the typed base is the run the TOML round
    /// trip builds, for every scenario file the repository ships with a
    /// random part or not (the plan falls back when a base does not
    /// survive the round trip; every shipped one does).
    #[test]
    fn seed_only_runs_are_the_round_trip() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let mut files = 0;
        for dir in ["paper", "examples", "realistic", "league"] {
            for e in std::fs::read_dir(root.join(dir)).unwrap() {
                let path = e.unwrap().path();
                if path.extension().is_none_or(|x| x != "toml") {
                    continue;
                }
                let Ok(base) = Loop::load(&path, &[]) else {
                    continue; // (a study or tuning file, not a scenario)
                };
                let study: Study = toml::from_str(
                    "name = \"t\"\nbase = \"x\"\nseed = 5\n[monte_carlo]\nruns = 3\n",
                )
                .unwrap();
                let p = Plan::build(study, base, "t.toml").unwrap();
                assert!(p.seed_only_typed, "{}", path.display());
                for i in 0..3 {
                    let (_, sets, _) = p.run_values(i);
                    let fast = p.build_run(&sets).unwrap();
                    let slow = p.base.with_values(&sets).unwrap();
                    assert_eq!(
                        fast.scenario(),
                        slow.scenario(),
                        "{} run {i}",
                        path.display()
                    );
                    assert_ne!(
                        fast.scenario().uncertainty.seed,
                        p.base.scenario().uncertainty.seed
                    );
                }
                files += 1;
            }
        }
        assert!(files >= 20, "only {files} scenario files");
    }

    #[test]
    fn grid_order_and_values() {
        let p = plan(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = { from = 50.0, to = 150.0, step = 50.0 }
[[axis]]
keys = ["uncertainty.a_bias", "uncertainty.b_bias"]
name = "bias"
values = [0.0, 0.5]
"#,
        );
        assert_eq!(p.runs, 6);
        assert_eq!(p.columns(), vec!["controller.gamma1", "bias"]);
        // Row-major: the last axis varies fastest.
        let (c, sets, _) = p.run_values(3);
        assert_eq!(c, vec![toml::Value::Float(100.0), toml::Value::Float(0.5)]);
        assert_eq!(sets.len(), 3);
        assert_eq!(sets[1].0, "uncertainty.a_bias");
        assert_eq!(sets[2].0, "uncertainty.b_bias");
    }

    #[test]
    fn log_axis_and_shards() {
        let p = plan(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = { from = 10.0, to = 1000.0, n = 3, scale = "log" }
"#,
        );
        let v: Vec<f64> = (0..3)
            .map(|i| as_f64(&p.run_values(i).0[0]).unwrap())
            .collect();
        assert!((v[1] - 100.0).abs() < 1e-9 && (v[2] - 1000.0).abs() < 1e-9);
        // 3 runs in 2 shards: 0..1 and 1..3.
        assert_eq!(p.shard_range(0, 2), 0..1);
        assert_eq!(p.shard_range(1, 2), 1..3);
        assert_eq!(parse_shard("1/2"), Ok((1, 2)));
        assert!(parse_shard("2/2").is_err());
    }

    #[test]
    fn draws_are_seeded_and_in_range() {
        let p = plan(
            r#"name = "t"
base = "x"
seed = 7
[monte_carlo]
runs = 200
[[monte_carlo.draw]]
key = "controller.gamma1"
dist = "uniform"
low = 50.0
high = 200.0
[[monte_carlo.draw]]
key = "controller.eta"
dist = "normal"
mean = 0.25
sd = 0.01
"#,
        );
        let draws: Vec<f64> = (0..200)
            .map(|i| as_f64(&p.run_values(i).0[0]).unwrap())
            .collect();
        assert!(draws.iter().all(|g| (50.0..200.0).contains(g)));
        let mean = draws.iter().sum::<f64>() / 200.0;
        assert!((mean - 125.0).abs() < 10.0, "{mean}");
        // The same run gives the same draw and seed, whoever asks.
        assert_eq!(p.run_values(17), p.run_values(17));
        assert_ne!(p.run_values(17).2, p.run_values(18).2);
        let eta: Vec<f64> = (0..200)
            .map(|i| as_f64(&p.run_values(i).0[1]).unwrap())
            .collect();
        let m = eta.iter().sum::<f64>() / 200.0;
        let sd = (eta.iter().map(|e| (e - m) * (e - m)).sum::<f64>() / 199.0).sqrt();
        assert!(
            (m - 0.25).abs() < 0.003 && (sd - 0.01).abs() < 0.002,
            "{m} {sd}"
        );
    }

    #[test]
    fn draws_at_the_edges_of_the_floats_stay_finite() {
        // The widest ranges the plan accepts: every draw is finite and
        // inside its range.
        let p = plan(
            r#"name = "t"
base = "x"
[monte_carlo]
runs = 2000
[[monte_carlo.draw]]
key = "controller.eta"
dist = "uniform"
low = -8.9e307
high = 8.9e307
[[monte_carlo.draw]]
key = "controller.gamma1"
dist = "loguniform"
low = 5e-324
high = 1.7976931348623157e308
[[monte_carlo.draw]]
key = "uncertainty.a_bias"
dist = "normal"
mean = 0.0
sd = 1.9e307
"#,
        );
        for i in 0..p.runs {
            let v: Vec<f64> = p.run_values(i).0.iter().filter_map(as_f64).collect();
            assert_eq!(v.len(), 3);
            assert!(v.iter().all(|x| x.is_finite()), "run {i}: {v:?}");
            assert!((-8.9e307..=8.9e307).contains(&v[0]), "{v:?}");
            assert!(v[1] > 0.0, "{v:?}");
        }
    }
}
