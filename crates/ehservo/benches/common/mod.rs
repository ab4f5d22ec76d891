//! Shared by the benches: the Fig. 2 case and its recorded measurements.

use ehservo::plant::{Plant, ThirdOrderPlant, Variation, Varying};
use ehservo::scenario::Loop;
use ehservo_core::prelude::*;

/// The Fig. 2 case: plant, the two controllers, reference, uncertainty.
pub struct Fig2 {
    /// The third-order plant with the scenario's load.
    pub plant: ThirdOrderPlant,
    /// The NNBVSC of Theorem 3 with the paper's gains.
    pub nn: NnVsc,
    /// The traditional VSC of Theorem 1 with the paper's bounds.
    pub vsc: Vsc,
    /// θd = 5° sin 2πt.
    pub reference: Sine,
    /// The true variation (a_bias = 1, b_bias = 0.5).
    pub unc: Varying<Variation>,
}

/// The default scenario (the paper's Fig. 2 case), built as `run::run` does.
pub fn fig2() -> Fig2 {
    let s = Loop::parse("").expect("the default scenario is Fig. 2");
    let plant = ThirdOrderPlant::new(s.model().params, s.model().load);
    let model = *plant.nominal();
    let surface = s.design().surface;
    let gains = SlidingConfig::default();
    let nn = NnVsc::try_new(
        model,
        surface,
        gains.nnvsc(),
        gains.rbf.build().expect("paper RBF"),
    )
    .expect("paper gains");
    let vsc = Vsc::try_new(model, surface, gains.vsc(false)).expect("paper bounds");
    let unc = Varying::new(&plant, s.stages().uncertainty);
    Fig2 {
        plant,
        nn,
        vsc,
        reference: *s.reference().as_sine().expect("a sine"),
        unc,
    }
}

/// The sample period (s).
pub const H: f64 = 0.01;
/// Samples after t = 0 (10 s).
pub const N: usize = 1000;
/// The sample of the fixed measurement: t = 5 s, weights trained.
pub const K_FIXED: usize = 500;

/// The recorded Fig. 2 loop.
pub struct Recording {
    /// Every measurement (t, x, z), k = 0..=N.
    pub measurements: Vec<Measurement>,
    /// The measurement at K_FIXED.
    pub fixed: Measurement,
    /// The NNBVSC state (∫e, W) at K_FIXED, before that sample's update.
    pub state: NnState,
}

/// Runs the Fig. 2 loop (sampled at 0.01 s, one RK4 sub-step) with the
/// hardware controller and records what it measured.
pub fn record() -> Recording {
    let mut f = fig2();
    let mut ctl = SampledController::new(f.nn, H).expect("dt > 0");
    let mut x = [0.0; 3];
    let mut measurements = Vec::with_capacity(N + 1);
    let mut fixed = None;
    for k in 0..=N {
        let t = k as f64 * H;
        let m = Measurement {
            t,
            x,
            z: f.reference.z(t),
        };
        if k == K_FIXED {
            fixed = Some((m, *ctl.state()));
        }
        measurements.push(m);
        let out = ctl.step(t, x, m.z);
        let v = f.unc.at(&f.plant, t);
        let plant = &f.plant;
        rk4_step(
            |tt, y: &[f64; 3], dy: &mut [f64; 3]| plant.deriv(tt, y, out.u, &v, dy),
            t,
            &mut x,
            H,
        );
    }
    let (fixed, state) = fixed.expect("K_FIXED <= N");
    assert!(
        state.w.iter().any(|w| *w != 0.0),
        "weights trained at t = 5 s"
    );
    Recording {
        measurements,
        fixed,
        state,
    }
}
