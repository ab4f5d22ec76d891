//! A loop's computed stability in one call, for the tools that judge many
//! candidates (`ehservo tune`, the league): the linear controller's loop
//! linearised at the trim at the reference's start (as `ehservo freq`
//! does by default, one-sided `plus` at a kink), whether it is closed-loop
//! stable, and its gain and phase margins with python-control's
//! conventions ([`super::margins`]) over the band `ehservo freq` searches
//! by default: from the loop's slowest pole or zero to just below Nyquist
//! (sampled), or 0.99·π/h (continuous).

use super::linearize::Side;
use super::margins;
use super::response::Discretisation;
use crate::scenario::Loop;
use serde::Serialize;

/// Grid points per decade of the margins' search here: a sixteenth of
/// `ehservo freq`'s [`margins::POINTS_PER_DECADE`], for the cost of a
/// tune (the crossings are refined by bisection either way, to the same
/// figures). A pair of crossings closer than 9.6 % in frequency can be
/// missed: a lightly damped resonance whose peak pokes above |L| = 1 in a
/// band of about 2ζ; its phase passes −180° there, and that phase
/// crossover's gain margin (below 0 dB) still rejects the loop.
pub const GRID_PER_DECADE: usize = 25;

/// The computed stability of a loop with a linear law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stability {
    /// Every closed-loop pole inside the stability region (None: not
    /// decided, 1 + D = 0).
    pub closed_loop_stable: Option<bool>,
    /// The reported gain margin (dB; None: no phase crossover, infinite).
    #[serde(rename = "gain_margin_dB")]
    pub gain_margin_db: Option<f64>,
    /// Its frequency (Hz).
    pub gain_margin_f_hz: Option<f64>,
    /// The reported phase margin (°; None: no gain crossover).
    pub phase_margin_deg: Option<f64>,
    /// Its frequency (Hz).
    pub phase_margin_f_hz: Option<f64>,
}

impl Stability {
    /// Why the loop falls short of `gain_db` (dB) and `phase_deg` (°), or
    /// None: unstable closed loop, a gain margin below `gain_db`, a phase
    /// margin below `phase_deg`. A margin that does not exist (no
    /// crossover) is infinite and passes.
    pub fn short_of(&self, gain_db: f64, phase_deg: f64) -> Option<String> {
        if self.closed_loop_stable == Some(false) {
            return Some("closed loop unstable (computed)".into());
        }
        let mut why = Vec::new();
        if let Some(g) = self.gain_margin_db.filter(|&g| g < gain_db) {
            why.push(format!("gain margin {g:.2} dB < {gain_db} dB"));
        }
        if let Some(p) = self.phase_margin_deg.filter(|&p| p < phase_deg) {
            why.push(format!("phase margin {p:.1}° < {phase_deg}°"));
        }
        (!why.is_empty()).then(|| why.join(", "))
    }
}

/// The computed stability of `lp`'s loop; None when its law is not linear
/// (no model of it: the sliding laws, the neural ones; a state feedback
/// whose channels come from an estimator) or when the loop cannot be linearised at
/// the trim (no trim found, a model that is not finite there): then only
/// the run's own findings judge it.
///
/// ```
/// use ehservo::freq::stability::computed;
/// use ehservo::scenario::Loop;
///
/// // The paper's servo under its default PID design: a stable loop.
/// let lp = Loop::parse("[controller]\nkind = \"pid\"").unwrap();
/// let st = computed(&lp).expect("the PID is linear");
/// assert_eq!(st.closed_loop_stable, Some(true));
/// assert!(st.phase_margin_deg.is_some_and(|p| p > 0.0));
/// ```
pub fn computed(lp: &Loop) -> Option<Stability> {
    let l = super::linearise(lp, "", None, Some(Side::Plus), Discretisation::Zoh).ok()?;
    let m = &l.lp;
    let h = m.h;
    let hi = if m.sampled() {
        m.nyquist() * (1.0 - 1e-9)
    } else {
        0.99 * m.nyquist()
    };
    // L as `ehservo freq` evaluates it (the controller's and the plant's
    // responses composed): a Hessenberg form of the loop's state space
    // (Laub 1981, tried and removed) lost 1e-4 of L on the slide's
    // discrete loop (its A spans 1 to 10¹²) and 2 % at its resonance,
    // enough to move a 0.91 dB gain margin to 0.98 dB or to none.
    m.loop_l.as_ref()?;
    let stable = m.closed_loop_stable();
    if stable == Some(false) {
        // Rejected whatever its margins: not worth their search.
        return Some(Stability {
            closed_loop_stable: stable,
            gain_margin_db: None,
            gain_margin_f_hz: None,
            phase_margin_deg: None,
            phase_margin_f_hz: None,
        });
    }
    let (lo, features) = m.search_band();
    let mg = margins::margins_on(
        &|w| m.loop_at(w),
        lo,
        hi,
        m.sampled().then_some(h),
        GRID_PER_DECADE,
        false,
        &features,
    );
    Some(Stability {
        closed_loop_stable: stable,
        gain_margin_db: mg.gain_margin.map(|g| g.gain_margin_db),
        gain_margin_f_hz: mg.gain_margin.map(|g| g.f_hz),
        phase_margin_deg: mg.phase_margin.map(|p| p.phase_margin_deg),
        phase_margin_f_hz: mg.phase_margin.map(|p| p.f_hz),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::servo::ServoParams;

    /// A lightly damped axis (the slide from its datasheets, ζ_h = 0.01)
    /// under a PID whose phase crosses −180° at the 13 Hz resonance: the
    /// tune's coarse grid must find that crossover as `ehservo freq`'s
    /// 400 points per decade do (it once reported "no crossover" for a
    /// loop with 0.9 dB of gain margin).
    #[test]
    fn a_resonances_crossover_is_not_missed() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/cylinders/slide-datasheet.toml"
        );
        let set: Vec<String> = [
            "controller.kind=pid",
            "controller.kp=12.111649",
            "controller.ki=11.523129",
            "controller.kd=0.000347",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let lp = Loop::load(std::path::Path::new(path), &set).unwrap();
        let st = computed(&lp).expect("a PID is linear");
        let l =
            super::super::linearise(&lp, "", None, Some(Side::Plus), Discretisation::Zoh).unwrap();
        let m = &l.lp;
        let fine = margins::margins(
            &|w| m.loop_at(w),
            m.lowest(),
            m.nyquist() * (1.0 - 1e-9),
            Some(m.h),
        );
        let g = fine.gain_margin.expect("a phase crossover");
        let got = st.gain_margin_db.expect("found by the tune's grid");
        assert!(
            (got - g.gain_margin_db).abs() < 1e-6,
            "{got} vs {}",
            g.gain_margin_db
        );
    }

    /// A P law u = kp·(θd − θ) on the nominal servo (the third-order plant
    /// without load or variation, continuous mode):
    /// L(s) = kp·b̄/(s³ + ā3·s² + ā2·s + ā1). Im L(jω) = 0 at ω² = ā2, where L = kp·b̄/(ā1 − ā3ā2):
    /// the gain margin is (ā3ā2 − ā1)/(kp·b̄). With kp a quarter of the
    /// critical gain, 20·log10(4) = 12.041 dB at √ā2 rad/s; the closed
    /// loop is stable (Routh: ā3ā2 > ā1 + kp·b̄).
    #[test]
    fn a_p_laws_gain_margin_is_the_closed_form() {
        let p = ServoParams::paper();
        let c = p.coefficients();
        // b̄ = 4βe·Dm·Kv·Cd·Ag·√(Ps/ρ)/(Vt·Jt), the valve's gain at Pl = 0.
        let b = p.b_per_kg() * p.flow_gain(0.0, 1.0).0;
        let kp = (c.a3 * c.a2 - c.a1) / (4.0 * b);
        let text = format!(
            "[simulation]\nmode = \"continuous\"\nstep = 0.001\n\
             [load]\namplitude = 0.0\nwavenumber = 0.0\n\
             [uncertainty]\na_bias = 0.0\nb_bias = 0.0\n\
             [controller]\nkind = \"pid\"\nkp = {kp}\nki = 0.0\nkd = 0.0\nfeedforward = false\n"
        );
        let lp = Loop::parse(&text).unwrap();
        let s = computed(&lp).expect("a PID is linear");
        assert_eq!(s.closed_loop_stable, Some(true));
        let gm = s.gain_margin_db.unwrap();
        assert!((gm - 20.0 * 4f64.log10()).abs() < 1e-6, "{gm}");
        let f = s.gain_margin_f_hz.unwrap();
        let f0 = c.a2.sqrt() / (2.0 * std::f64::consts::PI);
        assert!((f - f0).abs() < 1e-6 * f0, "{f} Hz against {f0}");
        // Asked for 13 dB it falls short, for 12 it passes; and four times
        // the critical gain is unstable.
        assert!(s
            .short_of(13.0, 0.0)
            .unwrap()
            .contains("gain margin 12.04 dB < 13 dB"));
        assert_eq!(s.short_of(12.0, 0.0), None);
        let lp = Loop::parse(&text.replace(&format!("kp = {kp}"), &format!("kp = {}", 16.0 * kp)))
            .unwrap();
        let s = computed(&lp).unwrap();
        assert_eq!(s.closed_loop_stable, Some(false));
        assert_eq!(
            s.short_of(0.0, 0.0).as_deref(),
            Some("closed loop unstable (computed)")
        );
    }

    /// A nonlinear law has no computed stability.
    #[test]
    fn a_sliding_law_has_none() {
        let lp = Loop::parse("[controller]\nkind = \"vsc\"").unwrap();
        assert_eq!(computed(&lp), None);
    }
}
