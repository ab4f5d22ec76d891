//! The hardware loop under arbitrary measurements (finite, infinite, NaN,
//! huge): the command is always finite and within the valve range, and the
//! controller state never becomes non-finite.
#![no_main]

use ehservo_core::prelude::*;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let model = NominalModel::new(ServoParams::paper(), Load::paper());
    let nn = NnVsc::try_new(model, SwitchingSurface::paper(), NnVscParams::paper(), Rbf::paper()).unwrap();
    let policy = FaultPolicy {
        safe: SafeCommand::HoldLast,
        limits: Limits {
            x: [10.0, 1e3, 1e5],
            u: 10.0,
        },
    };
    let mut ctl = SampledController::with_policy(nn, 1e-3, policy).unwrap();
    let vsc = Vsc::try_new(model, SwitchingSurface::paper(), VscParams::paper()).unwrap();
    let mut ctl2 = SampledController::with_policy(vsc, 1e-3, policy).unwrap();
    for (k, chunk) in data.chunks_exact(64).enumerate() {
        let f = |i: usize| f64::from_le_bytes(chunk[8 * i..8 * i + 8].try_into().unwrap());
        let x = [f(0), f(1), f(2)];
        let z = [f(3), f(4), f(5), f(6)];
        let t = k as f64 * 1e-3 + if f(7).is_finite() { f(7).clamp(-1.0, 1.0) * 1e-4 } else { 0.0 };
        for out in [ctl.step(t, x, z), ctl2.step(t, x, z)] {
            assert!(out.u.is_finite() && out.u.abs() <= 10.0, "u = {}", out.u);
        }
        assert!(ctl.state().all_finite(), "the weights were poisoned");
    }
});
