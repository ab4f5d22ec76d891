//! The simulator's sampled mode is exactly the hardware loop of the core:
//! `SampledController::step` once per sample, plant integrated under the
//! held command. Same numbers, bit for bit.

use ehservo::plant::{Plant, ThirdOrderPlant, UncertaintySpec, Varying};
use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use ehservo_core::prelude::*;

#[test]
fn sampled_mode_equals_the_core_fixed_rate_loop() {
    let s = Loop::parse("[simulation]\nhorizon = 2.0\nsubsteps = 4\n").unwrap();
    let sim = run(&s, Keep::Every(1));

    let params = ServoParams::paper();
    let plant = ThirdOrderPlant::new(params, Load::paper());
    let nn = NnVsc::try_new(
        *plant.nominal(),
        SwitchingSurface::paper(),
        NnVscParams::paper(),
        Rbf::paper(),
    )
    .unwrap();
    let mut ctl = SampledController::new(nn, 0.01).unwrap();
    let reference = Sine::paper();
    let mut unc = Varying::new(
        &plant,
        UncertaintySpec {
            a_bias: 1.0,
            b_bias: 0.5,
            ..UncertaintySpec::NONE
        },
    );
    let mut x = [0.0; 3];
    for (k, smp) in sim.trace.iter().enumerate() {
        let t = k as f64 * 0.01;
        let out = ctl.step(t, x, reference.z(t));
        assert_eq!(out.u.to_bits(), smp.u.to_bits(), "u differs at k = {k}");
        for j in 0..4 {
            let ts = t + j as f64 * 0.0025;
            let v = unc.at(&plant, ts);
            rk4_step(
                |tt, y: &[f64; 3], dy: &mut [f64; 3]| plant.deriv(tt, y, out.u, &v, dy),
                ts,
                &mut x,
                0.0025,
            );
        }
    }
    assert_eq!(sim.trace.len(), 201);
}
