//! The linear controllers as state-space models, derived from each core
//! law's equations, and the linear observers of `[estimator]`.
//!
//! A controller's model has the inputs the law reads — the measured θ and
//! the reference `z = (θd, θ̇d, θ̈d, θ⃛d)` — and its command u as output:
//! `ξ̇ = A·ξ + B·(θm, z)`, `u = C·ξ + D·(θm, z)` for the law itself (what
//! the continuous mode integrates), and its sampled form
//! `(I + h·A, h·B, C, D)`: the sampled loop evaluates the law and then
//! steps ξ by forward Euler (`ehservo_core::sampled`). A law is linear
//! while its output limit does not act (`u_limit`, and the valve range);
//! the tests step each core controller in its `SampledController` on a
//! random input sequence and compare its commands with the model's to
//! round-off.
//!
//! - **PID** (`control/pid.rs`): ξ = (I, θf),
//!   `u = ff + kp·(θd − θm) + I + kd·(θ̇d − (θm − θf)/Tf)`,
//!   `İ = ki·(θd − θm)`, `θ̇f = (θm − θf)/Tf`,
//!   `ff = (θ⃛d + ā1·θd + ā2·θ̇d + ā3·θ̈d)/b̄0` (when `feedforward`). Its
//!   feedback path is `kp + ki/s + kd·s/(1 + Tf·s)`.
//! - **ADRC** (`control/adrc.rs`): the observer ξ = (z1, z2, z3, z4) with
//!   inputs (θm, u) — `ż1 = z2 + β1·ε`, `ż2 = z3 + β2·ε`,
//!   `ż3 = z4 + f̄ + b0·u + β3·ε`, `ż4 = β4·ε`, `ε = θm − z1`,
//!   `f̄ = −ā·z` with the model, else 0 — and the static law
//!   `u = (k1(θd − z1) + k2(θ̇d − z2) + k3(θ̈d − z3) + θ⃛d − z4 − f̄)/b0`; the
//!   law feeds its own u to the observer at the same instant, so together
//!   `ż3 = u0 + β3·ε` (u0 the PD part).
//! - **State feedback** (`control/state_feedback.rs`): ξ = I, inputs
//!   (θm, θ̇m, θ̈m, z) — the one law that reads more than θm
//!   ([`ControllerModel::measured`]) —
//!   `u = (ff·z + k1·(θd − θm) + k2·(θ̇d − θ̇m) + k3·(θ̈d − θ̈m) + I)/b0`,
//!   `İ = ki·(θd − θm)`; with `compensate` the law divides by b(x, sgn v),
//!   which the loop puts in at its operating point
//!   ([`ControllerModel::divided_by`]).
//! - **Luenberger and Kalman observers** (`ehservo_core::estimate::
//!   LinearObserver`): discrete by construction. With the state
//!   `ξ_k = x̂_{k−1}` and inputs `(θ_k, u_{k−1})`:
//!   `x̂_k = M·Φ·ξ_k + M·Γ·u_{k−1} + K·θ_k`, `M = I − K·C`, `ξ_{k+1} = x̂_k`.

use super::ss::{Quantity, StateSpace};
use crate::scenario::{ControllerCfg, ControllerConfig, Visit};
use ehservo_core::control::{Design, LinearForm};
use ehservo_core::error::ParamError;
use ehservo_core::estimate::LinearObserver;
use nalgebra::DMatrix;

/// The controller's inputs: the measured θ, then the reference z.
pub fn controller_inputs() -> Vec<Quantity> {
    vec![
        Quantity::new("theta_m", "rad"),
        Quantity::new("theta_d", "rad"),
        Quantity::new("theta_d_dot", "rad/s"),
        Quantity::new("theta_d_ddot", "rad/s²"),
        Quantity::new("theta_d_dddot", "rad/s³"),
    ]
}

fn u_out() -> Vec<Quantity> {
    vec![Quantity::new("u", "V")]
}

/// A linear controller's models.
#[derive(Debug, Clone)]
pub struct ControllerModel {
    /// `controller.kind`.
    pub kind: &'static str,
    /// The law in continuous time (inputs [`controller_inputs`], output u).
    pub law: StateSpace,
    /// Its parts, named (the ADRC's observer and static law).
    pub parts: Vec<(&'static str, StateSpace)>,
    /// The output limit under which it is linear (V; infinite: none).
    pub u_limit: f64,
    /// How many of the law's first inputs are measured: 1 (θm), or 3
    /// (θm, θ̇m, θ̈m: the state feedback's). The reference z follows them.
    pub measured: usize,
    /// The valve gain b̄0 the law divides by, when it divides by the gain
    /// at the measured state instead (`compensate`: the state feedback's
    /// flow linearisation); [`ControllerModel::divided_by`] puts that gain
    /// in at an operating point.
    pub compensated_b0: Option<f64>,
}

impl ControllerModel {
    /// The model the loop runs: the law itself in continuous mode, its
    /// forward-Euler map of period `h` in sampled mode.
    pub fn for_mode(&self, h: Option<f64>) -> StateSpace {
        Self::to_mode(&self.law, h)
    }

    /// The parts in the loop's time base: a dynamic part by forward Euler
    /// of period `h` (as the sampled loop steps it), a static one as it is.
    pub fn parts_for_mode(&self, h: Option<f64>) -> Vec<(&'static str, StateSpace)> {
        self.parts
            .iter()
            .map(|(n, m)| (*n, Self::to_mode(m, h)))
            .collect()
    }

    /// The law dividing by `b` where its model divides by b̄0 (a
    /// compensating law linearised at a point whose gain is `b`): its
    /// output scaled by b̄0/b. Unchanged for a law that does not compensate.
    pub fn divided_by(mut self, b: f64) -> Self {
        if let Some(b0) = self.compensated_b0 {
            let k = b0 / b;
            self.law.c *= k;
            self.law.d *= k;
        }
        self
    }

    fn to_mode(m: &StateSpace, h: Option<f64>) -> StateSpace {
        match h {
            None => m.clone(),
            Some(h) => m.euler(h).expect("a finite continuous law"),
        }
    }
}

/// The model of the scenario's controller when its kind is linear (its
/// `Config::linear` gives its [`LinearForm`]: PID, ADRC); None for a
/// nonlinear kind.
pub fn controller_model(
    cfg: &ControllerCfg,
    design: &Design,
) -> Option<Result<ControllerModel, ParamError>> {
    let form = cfg.visit(Linear(design))?;
    Some(form.map(|f| model_of(cfg.kind(), f)))
}

/// A kind's linear form ([`Config::linear`]).
struct Linear<'a>(&'a Design);

impl Visit for Linear<'_> {
    type Out = Option<Result<LinearForm, ParamError>>;
    fn visit<K: ControllerConfig>(self, cfg: &K) -> Self::Out {
        cfg.linear(self.0)
    }
}

/// The models of a linear form (module doc).
pub fn model_of(kind: &'static str, form: LinearForm) -> ControllerModel {
    match form {
        LinearForm::Pid {
            kp,
            ki,
            kd,
            tf,
            feedforward,
            u_limit,
        } => pid_model(kind, [kp, ki, kd], tf, feedforward, u_limit),
        LinearForm::Eso {
            k,
            beta,
            b0,
            a,
            u_limit,
        } => eso_model(kind, k, beta, b0, a, u_limit),
        LinearForm::StateFeedback {
            k,
            feedforward,
            b0,
            compensate,
            u_limit,
        } => {
            let mut m = state_feedback_model(kind, k, feedforward, b0, u_limit);
            m.compensated_b0 = compensate.then_some(b0);
            m
        }
    }
}

/// The state feedback's inputs: the measured (θm, θ̇m, θ̈m), then z.
pub fn state_feedback_inputs() -> Vec<Quantity> {
    let mut v = vec![
        Quantity::new("theta_m", "rad"),
        Quantity::new("theta_dot_m", "rad/s"),
        Quantity::new("theta_ddot_m", "rad/s²"),
    ];
    v.extend(controller_inputs().into_iter().skip(1));
    v
}

/// The state feedback's model (module doc): ξ = I, `İ = ki·(θd − θm)`,
/// `u = (ff·z + k1·(θd − θm) + k2·(θ̇d − θ̇m) + k3·(θ̈d − θ̈m) + I)/b0`.
fn state_feedback_model(
    kind: &'static str,
    [k3, k2, k1, ki]: [f64; 4],
    ff: [f64; 4],
    b0: f64,
    u_limit: f64,
) -> ControllerModel {
    let am = DMatrix::zeros(1, 1);
    let bm = DMatrix::from_row_slice(1, 7, &[-ki, 0.0, 0.0, ki, 0.0, 0.0, 0.0]);
    let cm = DMatrix::from_element(1, 1, 1.0 / b0);
    let d = [-k1, -k2, -k3, k1 + ff[0], k2 + ff[1], k3 + ff[2], ff[3]];
    let dm = DMatrix::from_fn(1, 7, |_, j| d[j] / b0);
    let law = StateSpace::new(
        am,
        bm,
        cm,
        dm,
        None,
        (
            vec![Quantity::new("integral", "rad/s³")],
            state_feedback_inputs(),
            u_out(),
        ),
    );
    ControllerModel {
        kind,
        law,
        parts: Vec::new(),
        u_limit,
        measured: 3,
        compensated_b0: None,
    }
}

/// The PID's model (module doc): gains (kp, ki, kd), the derivative
/// filter's `tf` and the reference feed-forward's weights.
fn pid_model(
    kind: &'static str,
    [kp, ki, kd]: [f64; 3],
    tf: f64,
    ff: [f64; 4],
    u_limit: f64,
) -> ControllerModel {
    let am = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, -1.0 / tf]);
    let bm = DMatrix::from_row_slice(
        2,
        5,
        &[-ki, ki, 0.0, 0.0, 0.0, 1.0 / tf, 0.0, 0.0, 0.0, 0.0],
    );
    let cm = DMatrix::from_row_slice(1, 2, &[1.0, kd / tf]);
    let dm = DMatrix::from_row_slice(1, 5, &[-kp - kd / tf, kp + ff[0], kd + ff[1], ff[2], ff[3]]);
    let law = StateSpace::new(
        am,
        bm,
        cm,
        dm,
        None,
        (
            vec![
                Quantity::new("integral", "V"),
                Quantity::new("theta_f", "rad"),
            ],
            controller_inputs(),
            u_out(),
        ),
    );
    ControllerModel {
        kind,
        law,
        parts: Vec::new(),
        u_limit,
        measured: 1,
        compensated_b0: None,
    }
}

fn adrc_states() -> Vec<Quantity> {
    vec![
        Quantity::new("z1", "rad"),
        Quantity::new("z2", "rad/s"),
        Quantity::new("z3", "rad/s²"),
        Quantity::new("z4", "rad/s³"),
    ]
}

/// The ADRC's models (module doc): the observer, the static law, and the
/// two together.
fn eso_model(
    kind: &'static str,
    [k1, k2, k3]: [f64; 3],
    [b1, b2, b3, b4]: [f64; 4],
    b0: f64,
    a: [f64; 3],
    u_limit: f64,
) -> ControllerModel {
    // The observer: inputs (θm, u), outputs z.
    let ao = DMatrix::from_row_slice(
        4,
        4,
        &[
            -b1,
            1.0,
            0.0,
            0.0, //
            -b2,
            0.0,
            1.0,
            0.0, //
            -b3 - a[0],
            -a[1],
            -a[2],
            1.0, //
            -b4,
            0.0,
            0.0,
            0.0,
        ],
    );
    let bo = DMatrix::from_row_slice(4, 2, &[b1, 0.0, b2, 0.0, b3, b0, b4, 0.0]);
    let observer = StateSpace::new(
        ao,
        bo,
        DMatrix::identity(4, 4),
        DMatrix::zeros(4, 2),
        None,
        (
            adrc_states(),
            vec![Quantity::new("theta_m", "rad"), Quantity::new("u", "V")],
            adrc_states(),
        ),
    );
    // The static law: inputs (z1..z4, θd, θ̇d, θ̈d, θ⃛d), output u;
    // u = (u0 − z4 − f̄)/b0 with f̄ = −a·z.
    let lz = [
        (a[0] - k1) / b0,
        (a[1] - k2) / b0,
        (a[2] - k3) / b0,
        -1.0 / b0,
    ];
    let lr = [k1 / b0, k2 / b0, k3 / b0, 1.0 / b0];
    let mut law_in = adrc_states();
    law_in.extend(controller_inputs().into_iter().skip(1));
    let static_law = StateSpace::gain(
        DMatrix::from_row_slice(
            1,
            8,
            &[lz[0], lz[1], lz[2], lz[3], lr[0], lr[1], lr[2], lr[3]],
        ),
        None,
        law_in,
        u_out(),
    );
    // Together: ż = A_o z + B_θ θm + B_u (Lz z + Lr r).
    let mut a_cl = observer.a.clone();
    let mut b_cl = DMatrix::zeros(4, 5);
    for i in 0..4 {
        b_cl[(i, 0)] = observer.b[(i, 0)];
        for j in 0..4 {
            a_cl[(i, j)] += observer.b[(i, 1)] * lz[j];
            b_cl[(i, 1 + j)] = observer.b[(i, 1)] * lr[j];
        }
    }
    let c_cl = DMatrix::from_row_slice(1, 4, &lz);
    let mut d_cl = DMatrix::zeros(1, 5);
    for j in 0..4 {
        d_cl[(0, 1 + j)] = lr[j];
    }
    let law = StateSpace::new(
        a_cl,
        b_cl,
        c_cl,
        d_cl,
        None,
        (adrc_states(), controller_inputs(), u_out()),
    );
    ControllerModel {
        kind,
        law,
        parts: vec![("observer", observer), ("law", static_law)],
        u_limit,
        measured: 1,
        compensated_b0: None,
    }
}

/// A linear observer of `[estimator]` as a discrete-time model of period
/// `h` (module doc): inputs `(θ_k, u_{k−1})`, outputs `x̂_k`.
pub fn observer_model(obs: &LinearObserver, h: f64) -> StateSpace {
    let phi = DMatrix::from_fn(3, 3, |i, j| obs.phi()[i][j]);
    let gamma = DMatrix::from_fn(3, 1, |i, _| obs.gamma()[i]);
    let k = DMatrix::from_fn(3, 1, |i, _| obs.gain()[i]);
    let mut c = DMatrix::zeros(1, 3);
    c[(0, 0)] = 1.0;
    let m = DMatrix::identity(3, 3) - &k * &c;
    let a = &m * &phi;
    let mg = &m * &gamma;
    let mut b = DMatrix::zeros(3, 2);
    b.column_mut(0).copy_from(&k.column(0));
    b.column_mut(1).copy_from(&mg.column(0));
    let est = vec![
        Quantity::new("theta_hat", "rad"),
        Quantity::new("theta_dot_hat", "rad/s"),
        Quantity::new("theta_ddot_hat", "rad/s²"),
    ];
    let states = vec![
        Quantity::new("theta_hat_prev", "rad"),
        Quantity::new("theta_dot_hat_prev", "rad/s"),
        Quantity::new("theta_ddot_hat_prev", "rad/s²"),
    ];
    StateSpace::new(
        a.clone(),
        b.clone(),
        a,
        b,
        Some(h),
        (
            states,
            vec![
                Quantity::new("theta_m", "rad"),
                Quantity::new("u_prev", "V"),
            ],
            est,
        ),
    )
}

/// Steps a discrete model from rest: the outputs for each input vector.
pub fn simulate(s: &StateSpace, inputs: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut x = nalgebra::DVector::zeros(s.n());
    inputs
        .iter()
        .map(|u| {
            let u = nalgebra::DVector::from_column_slice(u);
            let y = &s.c * &x + &s.d * &u;
            x = &s.a * &x + &s.b * &u;
            y.iter().copied().collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::control::adrc::AdrcConfig;
    use ehservo_core::control::pid::PidConfig;
    use ehservo_core::control::state_feedback::StateFeedbackConfig;
    use ehservo_core::control::{Config, Controller};
    use ehservo_core::estimate::Estimator;
    use ehservo_core::sampled::SampledController;
    use ehservo_core::servo::{Load, NominalModel, ServoParams};
    use ehservo_core::surface::SwitchingSurface;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn design(dt: f64) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt,
        }
    }

    /// A random input sequence: θm and z of the sizes a run sees.
    fn inputs(n: usize, seed: u64) -> Vec<Vec<f64>> {
        measured_inputs(n, seed, 1)
    }

    /// The first `measured` of (θm, θ̇m, θ̈m), then z, of a run's sizes.
    fn measured_inputs(n: usize, seed: u64, measured: usize) -> Vec<Vec<f64>> {
        let mut r = ChaCha8Rng::seed_from_u64(seed);
        let x = [0.1, 0.6, 4.0];
        let z = [0.1, 0.6, 4.0, 25.0];
        (0..n)
            .map(|_| {
                x[..measured]
                    .iter()
                    .chain(&z)
                    .map(|&a| r.random_range(-a..a))
                    .collect()
            })
            .collect()
    }

    /// The core controller in its sampled loop against the model, sample
    /// by sample: the same commands to round-off (1e-9 of the largest).
    fn against_law<C: Controller + Clone>(c: C, model: &StateSpace, h: f64, what: &str) {
        let measured = model.inputs.len() - 4;
        let ins = measured_inputs(400, 5, measured);
        let mut sc = SampledController::new(c, h).unwrap();
        let want: Vec<f64> = ins
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let mut x = [0.0; 3];
                x[..measured].copy_from_slice(&v[..measured]);
                let z = &v[measured..];
                sc.step(k as f64 * h, x, [z[0], z[1], z[2], z[3]]).u
            })
            .collect();
        let got = simulate(model, &ins);
        let big = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, (w, g)) in want.iter().zip(&got).enumerate() {
            assert!(
                (w - g[0]).abs() <= 1e-9 * big,
                "{what} sample {k}: law {w} vs model {}",
                g[0]
            );
        }
    }

    /// The kinds with a linear form are the PID, the ADRC and the state
    /// feedback; every other registered kind has none (and `linearize`
    /// names it as nonlinear).
    #[test]
    fn the_linear_kinds_are_the_pid_the_adrc_and_the_state_feedback() {
        let d = design(0.01);
        let linear: Vec<&str> = ControllerCfg::KINDS
            .iter()
            .copied()
            .filter(|k| controller_model(&ControllerCfg::default_of(k).unwrap(), &d).is_some())
            .collect();
        assert_eq!(linear, ["pid", "adrc", "state-feedback"]);
    }

    #[test]
    fn pid_model_is_the_sampled_law() {
        for (dt, cfg) in [
            (0.01, PidConfig::default()),
            (
                0.001,
                PidConfig {
                    kp: Some(48.5),
                    ki: Some(847.0),
                    kd: Some(0.86),
                    filter_time: Some(0.004),
                    ..PidConfig::default()
                },
            ),
            (
                0.001,
                PidConfig {
                    feedforward: false,
                    ..PidConfig::default()
                },
            ),
        ] {
            let d = design(dt);
            let m = model_of("pid", cfg.linear(&d).unwrap().unwrap());
            against_law(cfg.build(&d).unwrap(), &m.for_mode(Some(dt)), dt, "pid");
        }
    }

    #[test]
    fn adrc_model_is_the_sampled_law() {
        for (dt, model_assisted) in [(0.01, true), (0.001, false), (0.001, true)] {
            let cfg = AdrcConfig {
                model_assisted,
                ..AdrcConfig::default()
            };
            let d = design(dt);
            let m = model_of("adrc", cfg.linear(&d).unwrap().unwrap());
            against_law(cfg.build(&d).unwrap(), &m.for_mode(Some(dt)), dt, "adrc");
            // The observer and the static law, closed through u, are the
            // combined model: compare their composition sample by sample.
            let (obs, law) = (&m.parts[0].1, &m.parts[1].1);
            let obs_d = obs.euler(dt).unwrap();
            let mut z = nalgebra::DVector::zeros(4);
            let whole = simulate(&m.for_mode(Some(dt)), &inputs(100, 9));
            for (k, v) in inputs(100, 9).iter().enumerate() {
                let mut lin = z.iter().copied().collect::<Vec<_>>();
                lin.extend_from_slice(&v[1..]);
                let u = (&law.d * nalgebra::DVector::from_vec(lin))[0];
                assert!((u - whole[k][0]).abs() <= 1e-9 * u.abs().max(1.0), "{k}");
                let inp = nalgebra::DVector::from_vec(vec![v[0], u]);
                z = &obs_d.a * &z + &obs_d.b * inp;
            }
        }
    }

    /// The state feedback without its flow linearisation is linear: its
    /// model is the sampled law, with and without the feed-forward and the
    /// integral, at two periods.
    #[test]
    fn state_feedback_model_is_the_sampled_law() {
        for (dt, feedforward, integral) in [
            (0.001, true, true),
            (0.002, false, true),
            (0.001, true, false),
        ] {
            let cfg = StateFeedbackConfig {
                compensate: false,
                feedforward,
                integral,
                ..StateFeedbackConfig::default()
            };
            let d = design(dt);
            let m = model_of("state-feedback", cfg.linear(&d).unwrap().unwrap());
            assert_eq!(m.measured, 3);
            against_law(
                cfg.build(&d).unwrap(),
                &m.for_mode(Some(dt)),
                dt,
                "state-feedback",
            );
        }
    }

    /// The state feedback's feedback paths by hand at s = j·ω, with
    /// poles −1, −2, −3, −4 on the paper's ā (k3 = 10 − ā3, k2 = 35 − ā2,
    /// k1 = 50 − ā1, ki = 24: the quartic (s+1)(s+2)(s+3)(s+4)):
    /// −u/θm = (k1 + ki/s)/b̄0, −u/θ̇m = k2/b̄0, −u/θ̈m = k3/b̄0.
    #[test]
    fn state_feedback_paths_by_hand() {
        let cfg = StateFeedbackConfig {
            poles: Some([-1.0, -2.0, -3.0, -4.0]),
            compensate: false,
            ..StateFeedbackConfig::default()
        };
        let d = design(0.001);
        let a = d.model.coeffs.as_array();
        let b0 = d.model.b_at_rest();
        let m = model_of("state-feedback", cfg.linear(&d).unwrap().unwrap());
        let w = 3.0;
        let j = super::super::ss::C64::new(0.0, w);
        let want = [
            (50.0 - a[0] + 24.0 / j) / b0,
            (35.0 - a[1]) / b0 + 0.0 * j,
            (10.0 - a[2]) / b0 + 0.0 * j,
        ];
        for (i, want) in want.iter().enumerate() {
            let got = -m.law.siso(0, i).response(w).unwrap();
            assert!(
                (got - want).norm() < 1e-12 * want.norm(),
                "input {i}: {got} vs {want}"
            );
        }
    }

    /// The PID's feedback path by hand at s = j·ω: −u/θm =
    /// kp + ki/(jω) + kd·jω/(1 + jω·Tf).
    #[test]
    fn pid_feedback_path_by_hand() {
        let cfg = PidConfig {
            kp: Some(2.0),
            ki: Some(3.0),
            kd: Some(0.5),
            filter_time: Some(0.1),
            ..PidConfig::default()
        };
        let m = model_of("pid", cfg.linear(&design(0.01)).unwrap().unwrap());
        let c = m.law.siso(0, 0);
        let w = 4.0;
        let j = super::super::ss::C64::new(0.0, w);
        let want = -(2.0 + 3.0 / j + 0.5 * j / (1.0 + j * 0.1));
        let got = c.response(w).unwrap();
        assert!((got - want).norm() < 1e-12, "{got} vs {want}");
    }

    /// Luenberger and Kalman observers: the model's outputs are
    /// `LinearObserver::update`'s estimates, sample by sample.
    #[test]
    fn observer_models_are_the_observers() {
        let m = NominalModel::new(ServoParams::paper(), Load::paper());
        for h in [0.01, 0.001] {
            let obs = [
                crate::observer_design::luenberger(&m, [-60.0, -70.0, -80.0], h).unwrap(),
                crate::observer_design::kalman(&m, 1e3, 1e-8, h).unwrap(),
            ];
            for o in obs {
                let model = observer_model(&o, h);
                let mut live = o;
                live.reset(0.0);
                let mut r = ChaCha8Rng::seed_from_u64(3);
                let ins: Vec<Vec<f64>> = (0..300)
                    .map(|_| vec![r.random_range(-0.1..0.1), r.random_range(-1.0..1.0)])
                    .collect();
                let got = simulate(&model, &ins);
                let want: Vec<[f64; 3]> = ins.iter().map(|v| live.update(v[0], v[1])).collect();
                for i in 0..3 {
                    let big = want.iter().fold(0.0f64, |m, w| m.max(w[i].abs()));
                    for (k, w) in want.iter().enumerate() {
                        assert!(
                            (w[i] - got[k][i]).abs() <= 1e-9 * big,
                            "h = {h}, sample {k}, x̂{i}: {} vs {}",
                            w[i],
                            got[k][i]
                        );
                    }
                }
            }
        }
    }
}
