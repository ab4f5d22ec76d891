//! The grey-box fit: the paper's physical model (1)–(6) in (θ, θ̇, P_l),
//! simulated through `ehservo_sim::plant::PhysicalPlant`, its physical
//! parameters fitted by output error.
//!
//! **What the data can identify.** Write q = Dm·P_l/Jt. Then (4)–(5) read
//!
//! ```text
//! θ̈ = q − (Bm/Jt)·θ̇ − (G/Jt)·θ − Tl(θ, θ̇)/Jt
//! q̇ = (4βe/Vt)·(Dm·Kg·Kv/Jt)·u − (4βe/Vt)·(Dm²/Jt)·θ̇ − (4βe·Kce/Vt)·q
//! ```
//!
//! With c1 = Bm/Jt, c2 = G/Jt, c4 = 4βe·Dm²/(Vt·Jt) (ω_h²), c5 = 4βe·Kce/Vt
//! and b = 4βe·Dm·Kg·Kv/(Vt·Jt), the transfer function from u to θ without a
//! load is b/(s³ + (c1 + c5)s² + (c2 + c4 + c1·c5)s + c2·c5): from (θ, u)
//! alone the data fix its four coefficients (a3, a2, b, and a1 only when
//! the spring is stiff enough), not the five groups, and not the physical
//! parameters behind them. βe and Vt enter only as βe/Vt; Cd, Ag, Kv and
//! √(Ps/ρ) only as their product (except through the valve root's
//! √(1 − sgn(u)·P_l/Ps), which is weak unless P_l approaches Ps); Dm only
//! with Jt; and the split of a3 between the damping c1 and the leakage c5
//! is free. Two things fix more: a known load (`[load]` of the prior,
//! A·sin kθ with A in N·m) enters as Tl/Jt and fixes the scale Jt, and
//! through d's 4βe·Kce·Tl/(Vt·Jt) the leakage; a load-pressure channel
//! (P_l in Pa, `p_load_Pa`) measures q·Jt/Dm directly, and with Dm known
//! makes Jt, Bm, βe and Kce identifiable (the test
//! `a_pressure_channel_makes_jt_identifiable` shows both). The default free
//! set is `beta_e, Kce, Jt, Bm, Kv, G` (Vt, Dm, Ps, ρ, Cd, Ag and the
//! load held at the prior); `--free` and `--fix` change it, and the
//! identifiability test of [`super::fit`] names whatever the data cannot
//! fix (e.g. the paper's G = 1.13·10⁻³ N·m/rad, 10⁻⁴ of its load's
//! stiffness A·k = 8 N·m/rad).

use super::data::Experiment;
use super::fit::Param;
use super::model::{divergence_limit, spectral_radius, substeps, Model, SimOut};
use super::oe::rk4;
use ehservo_core::servo::{Friction, Load, ServoParams};

/// Every grey-box key with its unit.
pub const KEYS: &[(&str, &str)] = &[
    ("Ps", "Pa"),
    ("beta_e", "Pa"),
    ("Vt", "m^3"),
    ("Kce", "m^3/(s*Pa)"),
    ("Dm", "m^3/rad"),
    ("Jt", "N*m*s^2"),
    ("Bm", "N*m*s"),
    ("Kv", "m/V"),
    ("G", "N*m/rad"),
    ("rho", "kg/m^3"),
    ("Cd", ""),
    ("Ag", "m"),
    ("load.amplitude", "N*m"),
    ("load.wavenumber", "1/rad"),
    ("friction.coulomb", "N*m"),
    ("friction.stiction", "N*m"),
    ("friction.viscous", "N*m*s"),
    ("friction.stribeck_velocity", "rad/s"),
];

/// The default free set.
pub const DEFAULT_FREE: &[&str] = &["beta_e", "Kce", "Jt", "Bm", "Kv", "G"];

/// The physical parameters and load as one vector in [`KEYS`] order
/// (friction zeros when the load has none).
pub fn to_vec(p: &ServoParams, l: &Load) -> Vec<f64> {
    let f = l.friction.unwrap_or(Friction {
        coulomb: 0.0,
        stiction: 0.0,
        stribeck_velocity: 0.05,
        viscous: 0.0,
        smoothing: 0.005,
    });
    vec![
        p.ps,
        p.beta_e,
        p.vt,
        p.kce,
        p.dm,
        p.jt,
        p.bm,
        p.kv,
        p.g,
        p.rho,
        p.cd,
        p.ag,
        l.amplitude,
        l.wavenumber,
        f.coulomb,
        f.stiction,
        f.viscous,
        f.stribeck_velocity,
    ]
}

/// The inverse of [`to_vec`]: friction is kept when the prior `l` has it.
pub fn from_vec(v: &[f64], l: &Load) -> (ServoParams, Load) {
    let p = ServoParams {
        ps: v[0],
        beta_e: v[1],
        vt: v[2],
        kce: v[3],
        dm: v[4],
        jt: v[5],
        bm: v[6],
        kv: v[7],
        g: v[8],
        rho: v[9],
        cd: v[10],
        ag: v[11],
    };
    let load = Load {
        amplitude: v[12],
        wavenumber: v[13],
        friction: l.friction.map(|f| Friction {
            coulomb: v[14],
            stiction: v[15],
            viscous: v[16],
            stribeck_velocity: v[17],
            smoothing: f.smoothing,
        }),
    };
    (p, load)
}

/// The grey-box model on a set of experiments.
#[derive(Debug, Clone)]
pub struct Physical {
    /// The prior load (for its friction's presence and smoothing).
    pub load: Load,
    /// RK4 steps per sample, per experiment.
    pub substeps: Vec<usize>,
    /// |θ| beyond which a run has diverged.
    pub limit: f64,
}

/// The linearised coefficients of the effective third-order polynomial:
/// (9)'s a1, a2, a3 with the load's stiffness A·k and damping added as the
/// paper's d linearises at θ = 0: a1 + c_T·A·k and a2 + A·k/Jt.
/// Friction is left out (its slope at rest, Ts/v0, is not the damping it
/// gives in motion).
pub fn effective(p: &ServoParams, l: &Load) -> [f64; 3] {
    let c = p.coefficients();
    let ak = l.amplitude * l.wavenumber;
    [c.a1 + p.d_per_torque() * ak, c.a2 + ak / p.jt, c.a3]
}

impl Physical {
    /// The model for `experiments`, with substeps from the start values `v`.
    pub fn new(experiments: &[Experiment], load: Load, v: &[f64]) -> Self {
        let (p, l) = from_vec(v, &load);
        // Friction's slope at rest (Ts/v0 for the regularised sign) is
        // the stiffest rate it can add.
        let friction = l.friction.map_or(0.0, |f| f.slope(0.0).abs() / p.jt);
        let rho = spectral_radius(effective(&p, &l)).max(friction);
        Self {
            load,
            substeps: experiments.iter().map(|e| substeps(e.h, rho)).collect(),
            limit: divergence_limit(experiments),
        }
    }
}

/// The one place the grey-box calls the plant: `Plant::initial_state` and
/// `Plant::deriv` of [`ehservo_sim::plant::PhysicalPlant`], without
/// parameter variation. The plant family's redesign changes the trait's
/// signature; only this adapter follows it.
pub mod adapter {
    use ehservo_core::servo::{Load, ServoParams};
    use ehservo_sim::physical::PhysicalVariation;
    use ehservo_sim::plant::{Factors, PhysicalPlant, Plant, Variation};

    /// No variation, in the physical plant's form.
    const NONE: PhysicalVariation = PhysicalVariation {
        paper: Variation::NONE,
        factors: Factors::ONE,
    };

    /// The physical plant, as the grey-box sees it.
    pub struct Adapter(PhysicalPlant);

    impl Adapter {
        /// From parameters and load (validated by the caller).
        pub fn new(p: ServoParams, l: Load) -> Self {
            Self(PhysicalPlant::new(p, l))
        }

        /// The state (θ, θ̇, P_l) at rest at θ0: P_l from the torque balance.
        pub fn at_rest(&self, theta0: f64) -> [f64; 3] {
            self.0.initial_state([theta0, 0.0, 0.0], &NONE)
        }

        /// d(θ, θ̇, P_l)/dt under the valve command `u` (V).
        #[inline]
        pub fn deriv(&self, s: &[f64; 3], u: f64) -> [f64; 3] {
            let mut ds = [0.0; 3];
            self.0.deriv(0.0, s, u, &NONE, &mut ds);
            ds
        }
    }
}

impl Model for Physical {
    fn simulate(&self, v: &[f64], i: usize, e: &Experiment, out: &mut SimOut) -> bool {
        let nk = KEYS.len();
        let u_off = v[nk];
        let theta0 = v[nk + 1 + i];
        let (p, l) = from_vec(&v[..nk], &self.load);
        if p.validate().is_err() || l.validate().is_err() {
            return false;
        }
        let plant = adapter::Adapter::new(p, l);
        let m = self.substeps[i];
        let hs = e.h / m as f64;
        let n = e.len();
        out.y.clear();
        out.v.clear();
        out.p.clear();
        let mut s = plant.at_rest(theta0);
        for k in 0..n {
            out.y.push(s[0]);
            out.v.push(s[1]);
            out.p.push(s[2]);
            if k + 1 == n {
                break;
            }
            let u = e.u.values[k] + u_off;
            for _ in 0..m {
                s = rk4(&s, hs, |x| plant.deriv(x, u));
            }
            if !(s.iter().all(|x| x.is_finite()) && s[0].abs() <= self.limit) {
                return false;
            }
        }
        true
    }

    fn has_pressure(&self) -> bool {
        true
    }
}

/// The grey-box parameters: every key at its prior, those in `free` free
/// (log-scaled, positive), the rest fixed.
pub fn params(prior: &[f64], free: &[String]) -> Vec<Param> {
    KEYS.iter()
        .zip(prior)
        .map(|(&(k, unit), &v)| {
            let mut p = Param::new(k, unit, v, v.abs().max(1.0));
            if !free.iter().any(|f| f == k) {
                p.status = super::fit::Status::Fixed;
            }
            p
        })
        .collect()
}
