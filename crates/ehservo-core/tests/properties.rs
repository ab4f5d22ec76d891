//! Property tests of the control laws and the hardware loop (bounded run
//! time: they run in CI).

// σΔ = 0 exactly inside the dead zone is the point of one property.
#![allow(clippy::float_cmp)]

use ehservo_core::control::flags;
use ehservo_core::prelude::*;
use proptest::prelude::*;

fn model() -> NominalModel {
    NominalModel::new(ServoParams::paper(), Load::paper())
}

fn nn(p: NnVscParams) -> NnVsc {
    NnVsc::try_new(model(), SwitchingSurface::paper(), p, Rbf::paper()).unwrap()
}

/// Any f64 at all, the special values included.
fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3f64..1e3,
        1 => proptest::num::f64::ANY,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(f64::MAX),
        1 => Just(-f64::MIN_POSITIVE),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    /// Whatever the sensors say, the command is finite and in the valve
    /// range, and the weights stay finite.
    #[test]
    fn the_hardware_step_is_always_finite(
        seq in proptest::collection::vec((any_f64(), any_f64(), any_f64(), any_f64(), any_f64()), 1..60),
        hold in any::<bool>(),
    ) {
        let policy = FaultPolicy {
            safe: if hold { SafeCommand::HoldLast } else { SafeCommand::Zero },
            limits: Limits { x: [f64::INFINITY; 3], u: 10.0 },
        };
        let mut c = SampledController::with_policy(nn(NnVscParams::paper()), 1e-3, policy).unwrap();
        let r = Sine::paper();
        for (k, (a, b, d, z0, z3)) in seq.into_iter().enumerate() {
            let t = k as f64 * 1e-3;
            let mut z = r.z(t);
            z[0] += if z0.is_finite() { z0.clamp(-1.0, 1.0) } else { z0 };
            z[3] = z3;
            let o = c.step(t, [a, b, d], z);
            prop_assert!(o.u.is_finite() && o.u.abs() <= 10.0, "u = {}", o.u);
            prop_assert!(c.state().all_finite());
            if !(a.is_finite() && b.is_finite() && d.is_finite() && z[0].is_finite() && z3.is_finite()) {
                prop_assert!(o.flags & flags::MEASUREMENT_FAULT != 0);
            }
        }
    }

    /// For any finite measurement the law's u is finite or flagged; through
    /// the hardware loop it is always finite.
    #[test]
    fn finite_measurements_give_finite_commands(
        x in proptest::array::uniform3(-1e6f64..1e6),
        z in proptest::array::uniform4(-1e6f64..1e6),
        w in proptest::collection::vec(-1e3f64..1e3, 130),
        int_e in -1e3f64..1e3,
    ) {
        let c = nn(NnVscParams::paper());
        let mut s = NnState::zero();
        s.w.copy_from_slice(&w);
        s.int_e = int_e;
        let mut ds = NnState::zero();
        let o = c.law(&Measurement { t: 0.0, x, z }, &s, &mut ds);
        prop_assert!(o.u.is_finite(), "u = {} at x = {x:?}", o.u);
        prop_assert!(ds.all_finite());
    }

    /// σΔ = 0 exactly inside the dead zone |σ| ≤ ᾱ‖E‖ (27): no learning
    /// (Ẇ = 0 exactly) and no switching (u = u_eq).
    #[test]
    fn the_dead_zone_is_exact(
        x in proptest::array::uniform3(-0.5f64..0.5),
        ed in -0.5f64..0.5,
        int_e in -0.5f64..0.5,
        frac in -0.999f64..0.999,
        w in proptest::collection::vec(-10f64..10.0, 130),
    ) {
        let c = nn(NnVscParams::paper());
        let surf = SwitchingSurface::paper();
        // Choose θ̈d so that σ = frac·ᾱ‖E‖ (inside the dead zone).
        let mut z = [0.3 * x[0], x[1] + ed, 0.0, 1.0];
        let st = surf.evaluate(&x, &z, int_e);
        let target = frac * 5.0 * st.norm_e;
        z[2] += target - st.sigma;
        let st = surf.evaluate(&x, &z, int_e);
        prop_assume!(st.sigma.abs() < 5.0 * st.norm_e);
        let mut s = NnState::zero();
        s.w.copy_from_slice(&w);
        s.int_e = int_e;
        let mut ds = NnState::zero();
        let o = c.law(&Measurement { t: 0.0, x, z }, &s, &mut ds);
        prop_assert_eq!(o.sigma_delta, 0.0);
        prop_assert_eq!(o.u_sw, 0.0);
        prop_assert!(ds.w.iter().all(|d| *d == 0.0));
    }

    /// With η > 0 the weight law (26) keeps W inside the ball
    /// ‖W‖ ≤ max(‖W(0)‖, sup‖Φ‖/η) — the invariant set that bounds W without
    /// persistent excitation (Remark 6 states it for W̃ = W̄ − W, which needs
    /// the unknown W̄). Forward Euler preserves it while h·η·|σΔ| ≤ 1; the
    /// random runs keep to that and check it at every step.
    #[test]
    fn weights_stay_in_the_invariant_set(
        seq in proptest::collection::vec(proptest::array::uniform3(-1.0f64..1.0), 100..400),
        eta in 0.05f64..1.0,
    ) {
        let p = NnVscParams { eta, ..NnVscParams::paper() };
        let c = nn(p);
        let h = 1e-4;
        let mut ctl = SampledController::new(c, h).unwrap();
        let r = Sine::paper();
        let mut phi_max: f64 = 0.0;
        for (k, u) in seq.iter().enumerate() {
            let t = k as f64 * h;
            let z = r.z(t);
            // A measured state near the reference, perturbed.
            let x = [z[0] + 0.02 * u[0], z[1] + 0.2 * u[1], z[2] + 2.0 * u[2]];
            let o = ctl.step(t, x, z);
            phi_max = phi_max.max(o.phi_norm);
            prop_assert!(h * eta * o.sigma_delta.abs() <= 1.0, "precondition");
            let w = ctl.state().w.iter().map(|v| v * v).sum::<f64>().sqrt();
            prop_assert!(w <= phi_max / eta * (1.0 + 1e-12), "‖W‖ = {w} > {}", phi_max / eta);
        }
    }
}
