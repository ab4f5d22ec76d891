//! After a run: f of (29)–(31), condition 4) of Theorem 3 and the dead zone
//! along a trace ([`RunDiagnostics`]).

use super::{paper_law, PaperLaw};
use crate::scenario::Scenario;
use crate::simulation::Sample;
use ehservo_core::control::sliding::SlidingConfig;
use serde::Serialize;

/// Condition 4) and the dead zone along a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunDiagnostics {
    /// Samples examined (those kept in the trace).
    pub samples: usize,
    /// Samples with t ≥ settle.
    pub samples_after_settle: usize,
    /// Share where condition 4) holds (both halves).
    pub condition4: f64,
    /// Share where f + ᾱ‖E‖ < α‖E‖.
    pub condition4_left: f64,
    /// Share where α‖E‖ < c/γ1 + ᾱ‖E‖.
    pub condition4_right: f64,
    /// Share in the dead zone (σΔ = 0).
    pub dead_zone: f64,
    /// The same four after the transient (t ≥ settle).
    pub after_settle: [f64; 4],
    /// Median ‖E‖ over the samples.
    pub norm_e_median: f64,
    /// Median over the samples of c/(γ1·(α − ᾱ)): the right half holds iff
    /// ‖E‖ is below it.
    pub right_half_limit_median: f64,
}

/// f of (29)–(31) for one sample, with the μ(t), γ2(t) and ‖Φ‖ the
/// controller used. f = sqrt(f1² + f2) − f1 is evaluated as
/// f2/(sqrt(f1² + f2) + f1) when f1 > 0 (no cancellation when f2 ≪ f1²).
/// NaN when f1² + f2 < 0 (a negative μ, `mu_rule = "literal-33"`).
pub fn f_of(s: &Scenario, smp: &Sample) -> f64 {
    match paper_law(s) {
        Some((PaperLaw::Nnvsc, c)) => {
            f_with(c, smp.part("mu"), smp.part("gain"), smp.part("phi_norm"))
        }
        _ => f64::NAN,
    }
}

fn f_with(c: &SlidingConfig, mu: f64, gain: f64, phi_norm: f64) -> f64 {
    let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * phi_norm + c.eps1;
    let f1 = (mu + gain / c.gamma1 - cc / c.gamma1) / 2.0;
    let f2 = cc * mu / c.gamma1;
    let root = (f1 * f1 + f2).sqrt();
    if f1 > 0.0 {
        f2 / (root + f1)
    } else {
        root - f1
    }
}

/// The signals the diagnostics read, looked up by key once per trace
/// rather than once per sample (a sample of another controller, were one
/// mixed in, is looked up by key).
struct Parts {
    signals: &'static [ehservo_core::control::Signal],
    index: [Option<usize>; 5],
}

impl Parts {
    const KEYS: [&'static str; 5] = ["mu", "gain", "phi_norm", "norm_e", "sigma_delta"];

    fn of(first: &Sample) -> Self {
        Self {
            signals: first.signals,
            index: Self::KEYS.map(|k| first.index_of(k)),
        }
    }

    /// (μ, gain, ‖Φ‖, ‖E‖, σΔ) of a sample, as [`Sample::part`] gives them.
    fn read(&self, smp: &Sample) -> [f64; 5] {
        if std::ptr::eq(smp.signals, self.signals) {
            self.index.map(|i| i.map_or(0.0, |i| smp.values[i]))
        } else {
            Self::KEYS.map(|k| smp.part(k))
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    // The middle order statistics by selection: the same values a full
    // sort would put there, in linear time.
    let n = v.len();
    let (lower, &mut hi, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = lower.iter().copied().max_by(f64::total_cmp).unwrap_or(hi);
        0.5 * (lo + hi)
    }
}

/// Condition 4) of Theorem 3,
/// f(t) + ᾱ‖E‖ < α‖E‖ < c/γ1 + ᾱ‖E‖ with c = ηW²max/4 + ε0‖Φ‖ + ε1,
/// and the dead zone along a trace (NNBVSC; None for the VSC or an empty
/// trace). The shares are over the samples of the trace (a decimated trace
/// gives the shares of its samples), and again over t ≥ settle.
pub fn diagnostics(s: &Scenario, trace: &[Sample]) -> Option<RunDiagnostics> {
    let Some((PaperLaw::Nnvsc, c)) = paper_law(s) else {
        return None;
    };
    if trace.is_empty() {
        return None;
    }
    let tol = 1e-9 * s.simulation.horizon.max(1.0);
    let parts = Parts::of(&trace[0]);
    let cc_of = |phi_norm: f64| c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * phi_norm + c.eps1;
    let eval = |smp: &Sample| {
        let [mu, gain, phi_norm, norm_e, sigma_delta] = parts.read(smp);
        let cc = cc_of(phi_norm);
        let left = f_with(c, mu, gain, phi_norm) + c.alpha_bar * norm_e < c.alpha * norm_e;
        let right = c.alpha * norm_e < cc / c.gamma1 + c.alpha_bar * norm_e;
        [left && right, left, right, sigma_delta == 0.0]
    };
    let share = |it: &mut dyn Iterator<Item = &Sample>| {
        let mut n = 0usize;
        let mut k = [0usize; 4];
        for smp in it {
            n += 1;
            for (slot, v) in k.iter_mut().zip(eval(smp)) {
                *slot += usize::from(v);
            }
        }
        let nn = n.max(1) as f64;
        (n, k.map(|x| x as f64 / nn))
    };
    let (n, all) = share(&mut trace.iter());
    let (n_after, after) = share(&mut trace.iter().filter(|x| x.t >= s.simulation.settle - tol));
    Some(RunDiagnostics {
        samples: n,
        samples_after_settle: n_after,
        condition4: all[0],
        condition4_left: all[1],
        condition4_right: all[2],
        dead_zone: all[3],
        after_settle: after,
        norm_e_median: median(trace.iter().map(|x| parts.read(x)[3]).collect()),
        right_half_limit_median: median(
            trace
                .iter()
                .map(|x| cc_of(parts.read(x)[2]) / (c.gamma1 * (c.alpha - c.alpha_bar)))
                .collect(),
        ),
    })
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use ehservo_core::control::sliding::SlidingParts;
    use ehservo_core::control::Signals;

    fn sample(p: SlidingParts) -> Sample {
        let mut s = Sample {
            signals: SlidingParts::<f64>::SIGNALS,
            ..Sample::default()
        };
        p.write(&mut s.values);
        s
    }

    fn paper_scenario(set: &[&str]) -> Scenario {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        Scenario::parse_with("", "<unit>", &set).unwrap()
    }

    /// f of (31) is the positive root of F(s) = s² + 2f1·s − f2 (A5), and
    /// with Remark 7's μ it is below (α − ᾱ)‖E‖.
    #[test]
    fn f_is_the_root_of_a5() {
        let s = paper_scenario(&[]);
        let c = super::paper_law(&s).unwrap().1;
        let phi = 5.0;
        let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * phi + c.eps1; // 1 + 0.5 + 0.1 = 1.6
        assert!((cc - 1.6).abs() < 1e-12);
        for norm_e in [1e-6, 1e-4, 1e-2, 1.0] {
            let mu = (c.alpha - c.alpha_bar) * norm_e * c.eps2 / cc;
            let smp = sample(SlidingParts {
                mu,
                gain: cc + c.eps2,
                phi_norm: phi,
                norm_e,
                ..Default::default()
            });
            let f = f_of(&s, &smp);
            let f1 = (mu + c.eps2 / c.gamma1) / 2.0;
            let f2 = cc * mu / c.gamma1;
            assert!(
                (f * f + 2.0 * f1 * f - f2).abs() <= 1e-12 * f2.max(1e-300),
                "{norm_e}"
            );
            assert!(f > 0.0 && f < (c.alpha - c.alpha_bar) * norm_e);
        }
        // μ = 0: f = 0.
        let smp = sample(SlidingParts {
            gain: cc + c.eps2,
            phi_norm: phi,
            ..Default::default()
        });
        assert!(f_of(&s, &smp).abs() < 1e-300);
    }

    #[test]
    fn medians() {
        assert!(median(Vec::new()).is_nan());
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
