//! `[scenario.box]` of a suite's `[[scenario]]`: the worst case over a box
//! of scenario keys. The scenario is run at every corner of the box (2^k
//! runs for k keys) and at `draws` points drawn uniformly inside it; each
//! point is a set of overrides of the scenario's keys, run as one more
//! draw of the scenario, so the report's worst e_max over the scenario's
//! runs is the worst over the box (one code path with the uncertainty
//! draws: a run is a seed and a point).
//!
//! ```toml
//! [[scenario]]
//! file = "nominal.toml"
//! [scenario.box]
//! keys = { "plant.B" = [9000.0, 16000.0], "plant.m" = [0.05, 0.3] }
//! corners = true     # default
//! draws = 20         # points inside, uniform (default 0)
//! seed = 1           # of those draws (default 0)
//! ```
//!
//! The points are a pure function of the table (keys in name order; the
//! draws from a ChaCha8 stream seeded by `seed`), so a league is the same
//! on any thread count.

use super::{build_with, Case, MAX_DRAWS};
use crate::scenario::ControllerCfg;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The most keys a box may vary (2^12 = 4096 corners).
pub const MAX_BOX_KEYS: usize = 12;

/// `[scenario.box]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxCfg {
    /// Each varied key (a scenario key path) with its `[low, high]`.
    pub keys: BTreeMap<String, [f64; 2]>,
    /// Run the 2^k corners (default true).
    #[serde(default = "yes")]
    pub corners: bool,
    /// Points drawn uniformly inside the box (default 0).
    #[serde(default)]
    pub draws: u64,
    /// The seed of those draws (default 0).
    #[serde(default)]
    pub seed: u64,
}

fn yes() -> bool {
    true
}

/// One point of a box: each key with its value.
pub type Point = Vec<(String, f64)>;

impl BoxCfg {
    /// Checks the table: at least one key and at most [`MAX_BOX_KEYS`],
    /// each `low ≤ high` finite, and some point asked for. The error is
    /// the key inside `box` and the reason.
    pub fn check(&self) -> Result<(), (String, String)> {
        if self.keys.is_empty() || self.keys.len() > MAX_BOX_KEYS {
            return Err((
                "keys".into(),
                format!("vary 1 to {MAX_BOX_KEYS} keys (got {})", self.keys.len()),
            ));
        }
        for (k, [lo, hi]) in &self.keys {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err((
                    format!("keys.{k}"),
                    format!("must be [low, high], finite, low <= high (got [{lo}, {hi}])"),
                ));
            }
        }
        if !self.corners && self.draws == 0 {
            return Err((
                "draws".into(),
                "no point to run: set corners = true or draws > 0".into(),
            ));
        }
        Ok(())
    }

    /// The points, corners first (corner i takes key j's high end where bit
    /// j of i is set), then the draws. Assumes [`BoxCfg::check`] passed.
    pub fn points(&self) -> Vec<Point> {
        let keys: Vec<(&String, &[f64; 2])> = self.keys.iter().collect();
        let mut out = Vec::new();
        if self.corners {
            for i in 0..(1usize << keys.len()) {
                out.push(
                    keys.iter()
                        .enumerate()
                        .map(|(j, (k, r))| ((*k).clone(), r[(i >> j) & 1]))
                        .collect(),
                );
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        for _ in 0..self.draws {
            out.push(
                keys.iter()
                    .map(|(k, [lo, hi])| {
                        let r: f64 = rng.random();
                        ((*k).clone(), lo + (hi - lo) * r)
                    })
                    .collect(),
            );
        }
        out
    }
}

impl Case {
    /// Its runs: every seed at every point.
    pub fn runs(&self) -> usize {
        self.seeds.len() * self.points.len()
    }

    /// Run `d`'s seed and point (the points vary fastest).
    pub fn run(&self, d: usize) -> (Option<u64>, &[(String, f64)]) {
        let n = self.points.len();
        (self.seeds[d / n], &self.points[d % n])
    }
}

/// The points of `b` on the case `case`, each checked to build on its
/// scenario (a key that is no scenario key, a value its plant refuses);
/// the error is the key inside `box` and the reason.
pub(super) fn checked_points(b: &BoxCfg, case: &Case) -> Result<Vec<Point>, (String, String)> {
    b.check()?;
    let corners = if b.corners { 1u64 << b.keys.len() } else { 0 };
    let runs = (case.seeds.len() as u64).saturating_mul(corners.saturating_add(b.draws));
    if runs > MAX_DRAWS {
        return Err((
            String::new(),
            format!("{runs} runs (draws × (corners + box draws)) is more than {MAX_DRAWS}"),
        ));
    }
    let points = b.points();
    let table = ControllerCfg::default().to_table();
    for p in &points {
        let mut c = case.clone();
        c.points = vec![p.clone()];
        build_with(&c, &table, 0)
            .map_err(|r| ("keys".to_string(), format!("at {}: {r}", point_text(p))))?;
    }
    Ok(points)
}

/// `key=value;…`: a point as `ehservo run --set` overrides (runs.csv).
pub fn point_text(p: &[(String, f64)]) -> String {
    p.iter()
        .map(|(k, v)| format!("{k}={v:?}"))
        .collect::<Vec<_>>()
        .join(";")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two keys: 4 corners in binary order, then draws inside, the same
    /// for the same seed.
    #[test]
    fn corners_then_draws_inside() {
        let mut keys = BTreeMap::new();
        keys.insert("plant.B".to_string(), [9000.0, 16000.0]);
        keys.insert("plant.m".to_string(), [0.05, 0.3]);
        let b = BoxCfg {
            keys,
            corners: true,
            draws: 50,
            seed: 3,
        };
        b.check().unwrap();
        let p = b.points();
        assert_eq!(p.len(), 4 + 50);
        let v = |i: usize| (p[i][0].1, p[i][1].1);
        assert_eq!(v(0), (9000.0, 0.05));
        assert_eq!(v(1), (16000.0, 0.05));
        assert_eq!(v(2), (9000.0, 0.3));
        assert_eq!(v(3), (16000.0, 0.3));
        for q in &p[4..] {
            assert!((9000.0..16000.0).contains(&q[0].1) && (0.05..0.3).contains(&q[1].1));
        }
        assert_eq!(b.points(), p);
        assert_eq!(point_text(&p[1]), "plant.B=16000.0;plant.m=0.05");
        let bad = BoxCfg {
            keys: BTreeMap::from([("plant.B".to_string(), [2.0, 1.0])]),
            ..b
        };
        assert_eq!(bad.check().unwrap_err().0, "keys.plant.B");
    }
}
