//! The cylinder's friction (Karnopp's stick–slip, bounded) and its end
//! stops' stated penetration, each against a closed form by hand.

use super::*;

/// The single rod with Karnopp friction F_c = coulomb, F_s = stiction,
/// v_s = 10 mm/s, started at rest at y = 0.25 m with p_A = 3.5 MPa,
/// p_B = 5 MPa. With the valve closed (critically centred, no leakage)
/// nothing flows while the rod is still, so the pressures stay and the
/// other forces on the rod are the closed form
/// F_d = A_A·p_A − A_B·p_B = 3.117245e-3·3.5e6 − 2.099369e-3·5e6 = 413.512 N
/// (A_A = π/4·0.063², A_B = π/4·(0.063² − 0.036²)).
fn held(coulomb: f64, stiction: f64) -> (CylinderPlant, [f64; 6]) {
    let mut cfg = single_rod();
    cfg.load.friction = Some(Friction {
        coulomb,
        stiction,
        stribeck_velocity: 0.01,
        viscous: 0.0,
        smoothing: 1e-3,
    });
    cfg.initial = InitialCfg {
        pressure_a: Some(3.5e6),
        pressure_b: Some(5e6),
    };
    let p = build(&cfg);
    let s = p.initial_state([0.25, 0.0, 0.0], &ONE);
    (p, s)
}

/// F_d of [`held`], by hand.
const F_HELD: f64 = 413.512_133;

/// Integrates as the sampled loop does (simulation/sampled.rs): the
/// plant's stiffness splits each step of `hs` into RK4 steps, the state
/// limited after each; `each` sees the state after every step.
fn run(
    p: &CylinderPlant,
    s: &mut [f64; 6],
    u: f64,
    hs: f64,
    steps: u32,
    each: &mut dyn FnMut(&[f64; 6]),
) {
    for k in 0..steps {
        let t = f64::from(k) * hs;
        let n = crate::plant::refinement(p.stiffness(t, s, u, &ONE), hs);
        let hr = hs / f64::from(n);
        for i in 0..n {
            rk4_step(
                |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, u, &ONE, d),
                t + f64::from(i) * hr,
                s,
                hr,
            );
            p.limit_state(s);
        }
        each(s);
    }
}

/// Issue 46: a static force balance decides stick or slip. With F_s above
/// F_d = 413.5 N the rod stays where it is — position change below 1e-9 m
/// over 0.5 s — at every friction level from 1e3 to 1e12 N (F_c = F_s/2),
/// and the integrator takes no extra steps to hold it.
#[test]
fn friction_above_the_drive_holds_the_rod_at_any_magnitude() {
    let (p, s) = held(0.0, 0.0);
    let [_, _, pa, pb, _, _] = s;
    let [aa, ab] = p.cylinder().area;
    assert!(
        close(aa * pa - ab * pb, F_HELD, 1e-8),
        "the closed form's F_d"
    );
    for e in 3..=12 {
        let fs = 10f64.powi(e);
        let (p, mut s) = held(0.5 * fs, fs);
        let y0 = s[0];
        let mut worst = 0.0f64;
        run(&p, &mut s, 0.0, 1e-4, 5_000, &mut |x| {
            worst = worst.max((x[0] - y0).abs())
        });
        assert!(worst <= 1e-9, "F_s = {fs:e}: the rod moved {worst:e} m");
        assert!(s[1].abs() <= 1e-12, "F_s = {fs:e}: ẏ = {:e}", s[1]);
        // Held at the rate 1/τ = ω_h the step already resolves: one RK4
        // step per 0.1 ms (a tanh-smoothed sign's slope F_s/v₀ would ask
        // for the most, 4 096).
        let lam = p.stiffness(0.0, &s, 0.0, &ONE);
        assert_eq!(
            crate::plant::refinement(lam, 1e-4),
            1,
            "F_s = {fs:e}: λ = {lam:e}"
        );
    }
}

/// Below the drive the rod breaks away: at rest (in the stick window) the
/// friction is F_s, so ÿ = (F_d − F_s)/M = (413.512 − 300)/250 =
/// 0.454049 m/s²; sliding at ẏ = ±10·v_s the Stribeck term is
/// 100·e^{−100} ≈ 4e-42 N, so ÿ = (F_d ∓ F_c)/M = (413.512 − 200)/250 =
/// 0.854049 m/s² extending and (413.512 + 200)/250 = 2.454049 m/s²
/// retracting. Run from rest, the rod extends.
#[test]
fn friction_below_the_drive_slips_with_the_closed_form_acceleration() {
    let (p, s) = held(200.0, 300.0);
    let m = 250.0;
    let mut ds = [0.0; 6];
    p.deriv(0.0, &s, 0.0, &ONE, &mut ds);
    assert!(
        close(ds[1], (F_HELD - 300.0) / m, 1e-8),
        "break-away ÿ = {}",
        ds[1]
    );
    for (v, want) in [(0.1, (F_HELD - 200.0) / m), (-0.1, (F_HELD + 200.0) / m)] {
        let moving = [s[0], v, s[2], s[3], s[4], s[5]];
        p.deriv(0.0, &moving, 0.0, &ONE, &mut ds);
        // The moving rod also compresses a chamber, but ÿ is of the state.
        assert!(close(ds[1], want, 1e-8), "ẏ = {v}: ÿ = {} vs {want}", ds[1]);
    }
    let mut s = s;
    run(&p, &mut s, 0.0, 1e-4, 100, &mut |_| {});
    assert!(
        s[0] - 0.25 > 1e-7 && s[1] > 0.0,
        "slipped: y = {}, ẏ = {}",
        s[0],
        s[1]
    );
}

/// The stops and the stroke hold under any friction: a rod moving at
/// 0.5 m/s toward a stop with F_s = F_c = 1e12 N, the valve driving it on,
/// is held: friction never exceeds the force that stops it within
/// τ = 1/ω_h, so ÿ = −ẏ/τ and it travels v₀·τ·(1 − e^{−t/τ}). By hand
/// ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M) at mid-stroke (V = 2e-4 + A·0.25):
/// 1.4e9·(9.717e-6/9.793e-4 + 4.407e-6/7.248e-4)/250 = 89 616 s⁻², ω_h =
/// 299.360 rad/s, so the rod stops 0.5/299.36 = 1.670 mm on: inside the
/// stroke from 2 mm off either stop.
#[test]
fn huge_friction_stops_a_moving_rod_inside_the_stroke() {
    let wh = 299.359_993;
    for (y0, v0, u) in [(0.002, -0.5, -10.0), (0.498, 0.5, 10.0)] {
        let (p, mut s) = held(1e12, 1e12);
        assert!(close(p.cylinder().stick_rate, wh, 1e-8));
        s[0] = y0;
        s[1] = v0;
        let (hs, steps) = (1e-4, 1_000);
        let mut k = 0;
        run(&p, &mut s, u, hs, steps, &mut |x| {
            k += 1;
            let t = f64::from(k) * hs;
            let want = y0 + v0 / wh * (1.0 - (-wh * t).exp());
            assert!(
                (x[0] - want).abs() <= 1e-9,
                "t = {t}: y = {} vs {want}",
                x[0]
            );
            assert!(x[0] > 0.0 && x[0] < 0.5, "inside the stroke: y = {}", x[0]);
        });
        assert!(s[1].abs() < 1e-6 * v0.abs(), "stopped: ẏ = {}", s[1]);
    }
}

/// The stops' stated penetration δ, by hand for the single rod: the
/// largest force pressing on a stop is A_A·Ps = 3.117245e-3·2e7 =
/// 62 344.9 N (no gravity, spring or F(t)); k_s = 100·k_h = 100·89 616·250
/// = 2.240410e9 N/m; δ = (F + √(F² + 2·k_s·F·L))/k_s with L = 0.5 m:
/// (62 344.9 + √(3.887e9 + 1.396810e14))/2.240410e9 = 5.30307e-3 m.
/// Beyond it the rod is a divergence; a factor scales δ by at most itself.
#[test]
fn stated_penetration_bounds_the_stroke() {
    let p = build(&single_rod());
    let c = p.cylinder();
    let d = 5.303_074e-3;
    assert!(close(c.stated_penetration(&Factors::ONE), d, 1e-6));
    assert!(!c.beyond_stops(-0.999 * d, &Factors::ONE));
    assert!(!c.beyond_stops(0.5 + 0.999 * d, &Factors::ONE));
    assert!(c.beyond_stops(-1.001 * d, &Factors::ONE));
    assert!(c.beyond_stops(0.5 + 1.001 * d, &Factors::ONE));
    let big = Factors {
        supply_pressure: 1.5,
        ..Factors::ONE
    };
    assert!(close(c.stated_penetration(&big), 1.5 * d, 1e-6));
    // A stop driven into at full opening rests well inside δ.
    let mut s = p.initial_state([0.05, 0.0, 0.0], &ONE);
    run(&p, &mut s, -10.0, 1e-4, 6_000, &mut |x| {
        assert!(!c.beyond_stops(x[0], &Factors::ONE), "y = {}", x[0]);
    });
    assert!(s[0] < 0.0, "at the stop: y = {}", s[0]);
}
