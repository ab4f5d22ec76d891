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
    /// Assumption A5 and Remark 6's set against the run.
    pub weights: WeightCheck,
}

/// Assumption A5 ((19) with (21)–(22)) and Remark 6's invariant set, checked
/// against the samples of a run.
///
/// (19) says the lumped uncertainty Δ = W̄ᵀΦ + ε with ‖W̄‖ ≤ Wmax (21) and
/// |ε| ≤ ε0‖Φ‖ + ε1 (22). By Cauchy–Schwarz, |Δ| ≤ ‖W̄‖‖Φ‖ + ε0‖Φ‖ + ε1 at
/// every sample, so any W̄ that meets (19) and (22) along the run has
/// ‖W̄‖ ≥ max_k (|Δ_k| − ε1)/‖Φ_k‖ − ε0: when that exceeds Wmax, A5 fails
/// with the stated Wmax. Remark 6 keeps ‖W̄ − W‖ below
/// r(‖Φ‖) = Wmax/2 + sqrt(Wmax²/4 + (ε0‖Φ‖ + ε1)/η), hence
/// ‖W‖ ≤ Wmax + r(‖Φ‖); a sample with a larger ‖W‖ lies outside that set.
#[derive(Debug, Clone, Serialize)]
pub struct WeightCheck {
    /// max |Δ| over the samples (the "uncertainty" signal, s⁻³ units of θ⃛).
    pub uncertainty_max: f64,
    /// max ‖Φ‖ over the samples.
    pub phi_norm_max: f64,
    /// The least ‖W̄‖ any W̄ meeting (19) and (22) along the run can have.
    pub w_bar_required: f64,
    /// Wmax of the scenario (21).
    pub w_max: f64,
    /// `w_bar_required ≤ w_max`.
    pub a5_holds: bool,
    /// max ‖W‖ over the samples.
    pub w_norm_max: f64,
    /// Wmax + r(‖Φ‖) at the sample of the largest ‖W‖ (None: η = 0, the
    /// set is unbounded).
    pub remark6_bound_at_w_max: Option<f64>,
    /// First time ‖W‖ > Wmax + r(‖Φ‖) (None: never, or η = 0).
    pub remark6_left_at_s: Option<f64>,
    /// Share of the samples outside Remark 6's set.
    pub remark6_outside_share: f64,
    /// In words.
    pub note: String,
}

fn weight_check(c: &SlidingConfig, trace: &[DiagSample]) -> WeightCheck {
    let read = |smp: &DiagSample| (smp.uncertainty, smp.phi_norm, smp.w_norm);
    let bound = |phi: f64| {
        super::weights::invariant_radius(c.eta, c.w_max, c.eps0, c.eps1, phi).map(|r| c.w_max + r)
    };
    let (mut unc_max, mut phi_max, mut req) = (0.0f64, 0.0f64, f64::NEG_INFINITY);
    let (mut w_max_run, mut w_at) = (f64::NEG_INFINITY, None);
    let (mut left_at, mut outside) = (None, 0usize);
    for smp in trace {
        let (unc, phi, w) = read(smp);
        unc_max = unc_max.max(unc.abs());
        phi_max = phi_max.max(phi);
        // ‖Φ‖ ≥ 1 (its first entry is 1); guard a zero all the same.
        if phi > 0.0 {
            req = req.max((unc.abs() - c.eps1) / phi - c.eps0);
        }
        if w > w_max_run {
            w_max_run = w;
            w_at = bound(phi);
        }
        if bound(phi).is_some_and(|b| w > b) {
            outside += 1;
            left_at.get_or_insert(smp.t);
        }
    }
    let req = req.max(0.0);
    let a5_holds = req <= c.w_max;
    let share = outside as f64 / trace.len().max(1) as f64;
    let mut note = if a5_holds {
        format!(
            "A5 is consistent with the run: a W̄ with ‖W̄‖ ≥ {req:.3} ≤ Wmax = {} can meet (19) and (22).",
            c.w_max
        )
    } else {
        format!(
            "A5 fails with Wmax = {}: the lumped uncertainty of (19) reaches {unc_max:.4} while ‖Φ‖ ≤ {phi_max:.4}, \
so any W̄ meeting (19) and (22) along this run needs ‖W̄‖ ≥ {req:.4} > Wmax ((21) is violated; the theorems' \
hypotheses do not hold).",
            c.w_max
        )
    };
    match (left_at, w_at) {
        (Some(t), Some(b)) => note.push_str(&format!(
            " The run leaves Remark 6's set: ‖W‖ reaches {w_max_run:.4} (the set bounds it by {b:.4} there), \
first outside at t = {t:.4} s, {:.1} % of the samples outside.",
            100.0 * share
        )),
        (None, Some(_)) => note.push_str(&format!(
            " ‖W‖ stays inside Remark 6's set (max {w_max_run:.4})."
        )),
        _ => note.push_str(" η = 0: Remark 6's set is unbounded, it constrains nothing."),
    }
    WeightCheck {
        uncertainty_max: unc_max,
        phi_norm_max: phi_max,
        w_bar_required: req,
        w_max: c.w_max,
        a5_holds,
        w_norm_max: w_max_run,
        remark6_bound_at_w_max: w_at,
        remark6_left_at_s: left_at,
        remark6_outside_share: share,
        note,
    }
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
#[derive(Debug, Clone, Copy)]
struct Parts {
    signals: &'static [ehservo_core::control::Signal],
    index: [Option<usize>; 7],
}

impl Parts {
    /// The keys, in the order of [`DiagSample`]'s fields after `t`.
    const KEYS: [&'static str; 7] = [
        "mu",
        "gain",
        "phi_norm",
        "norm_e",
        "sigma_delta",
        "uncertainty",
        "w_norm",
    ];

    fn of(first: &Sample) -> Self {
        Self {
            signals: first.signals,
            index: Self::KEYS.map(|k| first.index_of(k)),
        }
    }

    /// What the diagnostics read of a sample, as [`Sample::part`] gives it.
    fn read(&self, smp: &Sample) -> DiagSample {
        let v = if std::ptr::eq(smp.signals, self.signals) {
            self.index.map(|i| i.map_or(0.0, |i| smp.values[i]))
        } else {
            Self::KEYS.map(|k| smp.part(k))
        };
        let [mu, gain, phi_norm, norm_e, sigma_delta, uncertainty, w_norm] = v;
        DiagSample {
            t: smp.t,
            mu,
            gain,
            phi_norm,
            norm_e,
            sigma_delta,
            uncertainty,
            w_norm,
        }
    }
}

/// The numbers of one sample that [`diagnostics`] reads: its time and
/// seven of the controller's signals (0 for one the controller does not
/// log, as [`Sample::part`] gives it). A run that needs only the
/// diagnostics keeps these (64 bytes a sample) instead of whole samples
/// ([`DiagRecorder`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagSample {
    t: f64,
    mu: f64,
    gain: f64,
    phi_norm: f64,
    norm_e: f64,
    sigma_delta: f64,
    /// The lumped uncertainty.
    uncertainty: f64,
    w_norm: f64,
}

/// Collects what [`diagnostics`] needs of a run's samples as they are
/// produced: `DiagRecorder::new(s)`, [`DiagRecorder::push`] each sample
/// that would be kept, then [`DiagRecorder::finish`] gives what
/// `diagnostics(s, &kept)` gives for those samples, the same bits.
#[derive(Debug, Clone)]
pub struct DiagRecorder {
    /// None when the scenario's controller has no diagnostics (not the
    /// NNBVSC): nothing is recorded.
    rows: Option<Vec<DiagSample>>,
    parts: Option<Parts>,
}

impl DiagRecorder {
    /// A recorder for a run of `s`, with room for `capacity` samples.
    pub fn new(s: &Scenario, capacity: usize) -> Self {
        let wanted = matches!(paper_law(s), Some((PaperLaw::Nnvsc, _)));
        Self {
            rows: wanted.then(|| Vec::with_capacity(capacity)),
            parts: None,
        }
    }

    /// Records a sample (the signals are looked up on the first).
    pub fn push(&mut self, smp: &Sample) {
        if let Some(rows) = &mut self.rows {
            let parts = self.parts.get_or_insert_with(|| Parts::of(smp));
            rows.push(parts.read(smp));
        }
    }

    /// The diagnostics of the samples pushed.
    pub fn finish(self, s: &Scenario) -> Option<RunDiagnostics> {
        diagnostics_of(s, &self.rows?)
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
    let mut rec = DiagRecorder::new(s, trace.len());
    for smp in trace {
        rec.push(smp);
    }
    rec.finish(s)
}

/// [`diagnostics`] of the samples' rows.
fn diagnostics_of(s: &Scenario, trace: &[DiagSample]) -> Option<RunDiagnostics> {
    let Some((PaperLaw::Nnvsc, c)) = paper_law(s) else {
        return None;
    };
    if trace.is_empty() {
        return None;
    }
    let tol = 1e-9 * s.simulation.horizon.max(1.0);
    let cc_of = |phi_norm: f64| c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * phi_norm + c.eps1;
    let eval = |smp: &DiagSample| {
        let (mu, gain, phi_norm, norm_e) = (smp.mu, smp.gain, smp.phi_norm, smp.norm_e);
        let cc = cc_of(phi_norm);
        let left = f_with(c, mu, gain, phi_norm) + c.alpha_bar * norm_e < c.alpha * norm_e;
        let right = c.alpha * norm_e < cc / c.gamma1 + c.alpha_bar * norm_e;
        [left && right, left, right, smp.sigma_delta == 0.0]
    };
    let share = |it: &mut dyn Iterator<Item = &DiagSample>| {
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
        norm_e_median: median(trace.iter().map(|smp| smp.norm_e).collect()),
        right_half_limit_median: median(
            trace
                .iter()
                .map(|x| cc_of(x.phi_norm) / (c.gamma1 * (c.alpha - c.alpha_bar)))
                .collect(),
        ),
        weights: weight_check(c, trace),
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
        crate::scenario::Loop::parse_with("", "<unit>", &set)
            .unwrap()
            .scenario()
            .clone()
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

    /// The diagnostics' numbers of samples, as `diagnostics` reads them.
    fn rows(trace: &[Sample]) -> Vec<DiagSample> {
        let parts = Parts::of(&trace[0]);
        trace.iter().map(|x| parts.read(x)).collect()
    }

    #[test]
    fn a5_and_remark6_against_hand_values() {
        let s = paper_scenario(&[]);
        let c = super::paper_law(&s).unwrap().1;
        // Fig. 2: η = 0.25, Wmax = 4, ε0 = ε1 = 0.1.
        let mut a = sample(SlidingParts {
            uncertainty: -3000.0,
            phi_norm: 21.7,
            w_norm: 1.0,
            ..Default::default()
        });
        a.t = 0.5;
        // r(1) = 2 + sqrt(4 + 0.2/0.25) = 4.19089023, so ‖W‖ ≤ 8.19089023 at ‖Φ‖ = 1.
        let mut b = sample(SlidingParts {
            uncertainty: 1.0,
            phi_norm: 1.0,
            w_norm: 8.2,
            ..Default::default()
        });
        b.t = 1.5;
        let w = weight_check(c, &rows(&[a, b]));
        // (3000 − 0.1)/21.7 − 0.1 = 138.1442396…
        assert!((w.w_bar_required - (2999.9 / 21.7 - 0.1)).abs() < 1e-9);
        assert!(!w.a5_holds);
        assert_eq!(w.remark6_left_at_s, Some(1.5));
        assert!((w.remark6_outside_share - 0.5).abs() < 1e-15);
        assert!((w.remark6_bound_at_w_max.unwrap() - (6.0 + 4.8f64.sqrt())).abs() < 1e-12);
        // Inside: a small uncertainty and ‖W‖ under the bound.
        let mut a = sample(SlidingParts {
            uncertainty: 10.0,
            phi_norm: 21.7,
            w_norm: 1.0,
            ..Default::default()
        });
        a.t = 0.5;
        let b = sample(SlidingParts {
            uncertainty: 1.0,
            phi_norm: 1.0,
            w_norm: 8.19,
            ..Default::default()
        });
        let w = weight_check(c, &rows(&[a, b]));
        assert!(w.a5_holds && w.remark6_left_at_s.is_none());
    }

    #[test]
    fn medians() {
        assert!(median(Vec::new()).is_nan());
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
