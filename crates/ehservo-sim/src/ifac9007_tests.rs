//! The benchmark's plant against hand arithmetic from the source's
//! matrices (`jl:N` = line N of prob9007-hydraulicPositioningSystem.jl at
//! f11f4a98, module doc).

use super::*;
use crate::error::Reason;
use crate::uncertainty::{PhysicalSpec, Spread};
use ehservo_core::rk4::rk4_step;

fn ctx(spec: UncertaintySpec) -> PlantContext {
    PlantContext {
        load: None,
        load_given: false,
        uncertainty: spec,
        x0: [0.0; 3],
        base_dir: None,
        reference_range: None,
        quantity: Default::default(),
    }
}

fn nominal(fl: f64) -> Ifac9007Plant {
    Ifac9007Plant::new(Ifac9007Params::NOMINAL, fl)
}

const NONE: Ifac9007Variation = Ifac9007Variation { f: Factors::ONE };

/// Runs the plant from rest under a constant command for `t` s (RK4, h =
/// 1e-4 s: |λ|·h ≈ 240·1e-4 = 0.024, far inside RK4's region).
fn settle(p: &Ifac9007Plant, u: f64, t: f64) -> [f64; 3] {
    let h = 1e-4;
    let mut s = [0.0; 3];
    let n = (t / h).round() as u64;
    for k in 0..n {
        rk4_step(
            |t, y: &[f64; 3], d: &mut [f64; 3]| p.deriv(t, y, u, &NONE, d),
            k as f64 * h,
            &mut s,
            h,
        );
    }
    s
}

/// The nominal point by hand (jl:30–38):
/// R + 4Rc/π = 0.15 + 0.04/π = 0.15 + 0.0127324 = 0.1627324;
/// 4B/V = 56000/874 = 64.073227; σ + KL = 0.242;
/// a3 = 0.1627324/0.1287 + 64.073227·0.242 = 1.264432 + 15.505721 = 16.770153;
/// a2 = 64.073227·10.75²/0.1287 + 15.505721·1.264432
///    = 64.073227·115.5625/0.1287 + 19.6059 = 57532.73 + 19.61 = 57552.34;
/// b = 64.073227·10.75/0.1287 = 688.78719/0.1287 = 5351.882.
#[test]
fn nominal_model_is_the_source_matrices_in_the_papers_form() {
    let m = *nominal(0.0).nominal();
    let c = m.coeffs;
    assert_eq!(c.a1, 0.0);
    assert!((c.a2 - 57552.34).abs() < 0.01, "a2 = {}", c.a2);
    assert!((c.a3 - 16.770153).abs() < 1e-6, "a3 = {}", c.a3);
    let b = m.b_at_rest();
    assert!((b - 5351.882).abs() < 1e-3, "b = {b}");
    // The valve root is flat: at the largest pressure the box reaches,
    // 866/(0.001 + 0.000103) ≈ 7.85e5, b moves by < 1e-9 relative.
    let pl = 866.0 / (0.001 + 0.000103);
    let x = [0.0, 0.0, 10.75 * pl / 0.1287];
    let (bp, _) = m.b(&x, 1.0);
    assert!((bp / b - 1.0).abs() < 1e-9, "{}", bp / b - 1.0);
}

/// ẋ2 = ẋ3 = 0 with FL = 0 (jl:81–84): (R + 4Rc/π)·v = A·p and
/// A·v + (σ + KL)·p = u, so v = u·A/(A² + (σ + KL)·(R + 4Rc/π))
/// = 100·10.75/(115.5625 + 0.242·0.1627324) = 1075/115.601881 = 9.299157.
#[test]
fn steady_velocity_under_a_constant_input_is_the_closed_form() {
    let s = settle(&nominal(0.0), 100.0, 3.0);
    assert!((s[1] - 9.299157).abs() < 1e-5, "v = {}", s[1]);
    // p = 0.1627324·9.299157/10.75 = 0.140768.
    assert!((s[2] - 0.140768).abs() < 1e-5, "p = {}", s[2]);
    // Beyond the bound the input saturates (jl:104): 2000 moves as 866.
    let sat = settle(&nominal(0.0), 2000.0, 3.0);
    let lim = settle(&nominal(0.0), INPUT_LIMIT, 3.0);
    assert_eq!(sat, lim);
    assert!((lim[1] - 8.66 * 9.299157).abs() < 1e-3, "{}", lim[1]);
}

/// u = 0, FL constant (jl:100): (R + 4Rc/π)·v = A·p − FL and
/// A·v + (σ + KL)·p = 0, so v = −FL·(σ + KL)/(A² + (σ + KL)·(R + 4Rc/π))
/// = −800·0.242/115.601881 = −1.674713 (the gain −0.00209339 per unit FL).
/// A positive FL pushes the carriage back.
#[test]
fn load_disturbance_dc_gain_is_the_closed_form() {
    let s = settle(&nominal(800.0), 0.0, 3.0);
    assert!((s[1] + 1.674713).abs() < 1e-5, "v = {}", s[1]);
    // To hold the carriage still against FL the pressure must carry it,
    // p = FL/A, which takes u = (σ + KL)·FL/A = 0.242·800/10.75 = 18.0093.
    let hold = settle(&nominal(800.0), 18.0093, 3.0);
    assert!(hold[1].abs() < 1e-4, "v = {}", hold[1]);
    assert!((hold[2] - 800.0 / 10.75).abs() < 1e-3, "p = {}", hold[2]);
}

/// The state holds x(0) and gives it back: the pressure that makes the
/// acceleration.
#[test]
fn initial_state_and_measure_round_trip() {
    let p = nominal(300.0);
    let x0 = [0.5, 2.0, 40.0];
    let s = p.initial_state(x0, &NONE);
    let x = p.measure(0.0, &s, &NONE);
    for i in 0..3 {
        assert!((x[i] - x0[i]).abs() < 1e-12, "{x:?}");
    }
}

/// With FL = 0 and no variation the nominal model is the plant: the
/// lumped uncertainty vanishes (to the flat root's 1e-9).
#[test]
fn lumped_uncertainty_vanishes_on_the_nominal_plant() {
    let p = nominal(0.0);
    let s = [0.1, 3.0, 20.0];
    let x = p.measure(0.0, &s, &NONE);
    let b = p.nominal().b_at_rest();
    let l = p.lumped_uncertainty(&s, &x, 50.0, 50.0, b, &NONE);
    assert!(l.abs() < 1e-6 * b * 50.0, "{l}");
    // A 20 % heavier carriage is not the model.
    let heavy = Ifac9007Variation {
        f: Factors {
            mass: 1.2,
            ..Factors::ONE
        },
    };
    let x = p.measure(0.0, &s, &heavy);
    assert!(p.lumped_uncertainty(&s, &x, 50.0, 50.0, b, &heavy).abs() > 1.0);
}

#[test]
fn bad_parameters_are_refused_by_key() {
    let c = ctx(UncertaintySpec::NONE);
    let bad = |f: &dyn Fn(&mut Ifac9007Cfg)| {
        let mut cfg = Ifac9007Cfg::default();
        f(&mut cfg);
        cfg.build(&c).unwrap_err()
    };
    // B = 20000 is outside [9000, 16000] (jl:49).
    let e = bad(&|c| c.b = 20000.0);
    assert_eq!(e.key, "plant.B");
    assert!(matches!(e.reason, Reason::OutsideBox { high, .. } if high == 16000.0));
    // FL = 900 is outside [0, 800] (jl:107).
    assert_eq!(bad(&|c| c.fl = 900.0).key, "plant.FL");
    // Widened, a non-positive m, V or A is still refused.
    for (key, f) in [
        (
            "plant.m",
            &(|c: &mut Ifac9007Cfg| c.m = 0.0) as &dyn Fn(&mut Ifac9007Cfg),
        ),
        ("plant.V", &|c: &mut Ifac9007Cfg| c.v = 0.0),
        ("plant.A", &|c: &mut Ifac9007Cfg| c.a = -1.0),
    ] {
        let e = bad(&|c| {
            c.widen_box = true;
            f(c)
        });
        assert_eq!(e.key, key);
        assert!(matches!(e.reason, Reason::NotPositive(_)), "{e}");
    }
    let e = bad(&|c| c.sigma = f64::NAN);
    assert_eq!(e.key, "plant.sigma");
    // Every corner of the box is inside it.
    let mut cfg = Ifac9007Cfg::default();
    (cfg.b, cfg.m, cfg.kl, cfg.fl) = (16000.0, 0.05, 0.000103, 800.0);
    assert!(cfg.build(&c).is_ok());
    // No supply pressure to vary.
    let spec = UncertaintySpec {
        physical: PhysicalSpec {
            supply_pressure: Spread {
                bias: 0.1,
                random: 0.0,
            },
            ..PhysicalSpec::default()
        },
        ..UncertaintySpec::NONE
    };
    let e = Ifac9007Cfg::default().build(&ctx(spec)).unwrap_err();
    assert_eq!(e.key, "uncertainty.physical.supply_pressure");
}

/// The physical factors reach the parameters they name: a 20 % bias on
/// the bulk modulus is B = 16800 in a3's pressure term,
/// 4·16800·0.242/874 = 18.606865 (against 15.505721).
#[test]
fn factors_vary_the_named_parameters() {
    let f = Factors {
        bulk_modulus: 1.2,
        ..Factors::ONE
    };
    let p = Ifac9007Params::NOMINAL.varied(&f);
    let c = p.servo_params().coefficients();
    assert!((c.a3 - (1.264432 + 18.606865)).abs() < 1e-5, "{}", c.a3);
    let p = nominal(100.0).with_factors(&Factors {
        load: 0.5,
        ..Factors::ONE
    });
    assert_eq!(p.fl, 50.0);
}
