//! The cylinder against its environment (issue #49, item 8): each check
//! against a value derived by hand or a closed form, not from the code.
//!
//! The test cylinder is [`single_rod`]: 63/36 mm, so
//! A_A = π/4·0.063² = 3.1172e-3 m², A_B = π/4·(0.063² − 0.036²) =
//! 2.0994e-3 m²; dead volumes 2e-4 m³, βe = 1.4e9 Pa, M = 250 kg, a fixed
//! 200 bar supply at 0 bar tank, a critically centred valve (no flow at
//! u = 0), no leakage unless a test sets it.

use super::*;
use crate::environment::{Contact, Environment};
use std::sync::Arc;

/// The test cylinder from `cfg` with `env` attached.
fn with_env(cfg: &CylinderCfg, env: Environment) -> CylinderPlant {
    let mut c = build(cfg).cylinder().clone();
    c.environment = Some(env);
    CylinderPlant::new(c, 0.25)
}

fn env(contact: Contact, k: f64, c: f64, f0: f64, x: f64, motion: Force) -> Environment {
    Environment {
        contact,
        stiffness: k,
        damping: c,
        preload: f0,
        position: x,
        motion,
    }
}

/// RK4 from `s` over `n` steps of `h` under the constant command `u`,
/// calling `each(t, s)` after every step.
fn run(
    p: &CylinderPlant,
    s: &mut [f64; 6],
    u: f64,
    h: f64,
    n: usize,
    mut each: impl FnMut(f64, &[f64; 6]),
) {
    for k in 0..n {
        let t = k as f64 * h;
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, u, &ONE, d),
            t,
            s,
            h,
        );
        each(t + h, s);
    }
}

fn env_force(p: &CylinderPlant, t: f64, s: &[f64; 6]) -> f64 {
    let mut out = [0.0; MAX_STATES];
    p.states(t, s, &[0.0; 3], &mut out);
    out[6]
}

/// Steady state against a stiff specimen whose mount recedes at v₀ =
/// 0.05 m/s: the rod follows at v₀ with a constant compression, so ÿ = 0
/// and the contact force is the load pressure times the areas minus the
/// friction, F = p_A·A_A − p_B·A_B − B·v₀ − g(v₀).
///
/// By hand, with the valve open at u = 2 V (x_v = 5e-5·2 = 1e-4 m) and
/// k_o = Cd·w·√(2/ρ) = 0.65·0.02·√(2/870) = 6.2330e-4, the steady flows
/// Q_A = A_A·v₀ = 1.5586e-4 m³/s and Q_B = A_B·v₀ = 1.0497e-4 m³/s give
/// Ps − p_A = (Q_A/(k_o·x_v))² = 2500.6² = 6.2530e6 Pa, so
/// p_A = 1.37470e7 Pa, and p_B = (Q_B/(k_o·x_v))² = 1684.1² = 2.8362e6 Pa;
/// A_A·p_A − A_B·p_B = 42 852 − 5 954 = 36 898 N. The friction: B·v₀ =
/// 2000·0.05 = 100 N and the Coulomb level g(v₀) = 500 N (v₀ = 10·v_s, so
/// the Stribeck term's e^{−100} is nil): F = 36 898 − 600 = 36 298 N.
#[test]
fn steady_contact_force_is_load_pressure_times_area_minus_friction() {
    let mut cfg = single_rod();
    cfg.cylinder.viscous = 2000.0;
    cfg.load.friction = Some(Friction {
        coulomb: 500.0,
        stiction: 800.0,
        stribeck_velocity: 0.005,
        viscous: 0.0,
        smoothing: 1e-3,
    });
    let v0 = 0.05;
    // The mount recedes from t = 0 at v₀: x_e = v₀·t.
    let motion = Force::Table(Arc::new(vec![(0.0, 0.0), (10.0, 10.0 * v0)]));
    let p = with_env(&cfg, env(Contact::Unilateral, 1e7, 2e4, 0.0, 0.1, motion));
    let mut s = p.initial_state([0.1, 0.0, 0.0], &ONE);
    // 3 s: the force builds through the compression with a time constant
    // of about 0.14 s (the run's own), and the rod ends near y = 0.25 m.
    run(&p, &mut s, 2.0, 1e-5, 300_000, |_, _| {});
    let c = p.cylinder();
    let [aa, ab] = c.area;
    let q = std::f64::consts::PI / 4.0;
    assert!(
        close(aa, q * 0.063 * 0.063, 1e-12)
            && close(ab, q * (0.063f64.powi(2) - 0.036f64.powi(2)), 1e-12)
    );
    // The rod has reached the mount's speed and stays in contact.
    assert!((s[1] - v0).abs() < 1e-6 * v0, "ẏ = {} m/s", s[1]);
    let f_env = env_force(&p, 3.0, &s);
    let ko = 0.65 * 0.02 * (2.0 / 870.0f64).sqrt();
    let kx = ko * 1e-4;
    let pa = 2e7 - (aa * v0 / kx).powi(2);
    let pb = (ab * v0 / kx).powi(2);
    let want = aa * pa - ab * pb - 2000.0 * v0 - 500.0;
    assert!(close(want, 36_298.0, 1e-3), "hand value {want}");
    assert!(
        close(s[2], pa, 1e-6) && close(s[3], pb, 1e-5),
        "p_A {} vs {pa}, p_B {} vs {pb}",
        s[2],
        s[3]
    );
    assert!(close(f_env, want, 1e-6), "F_env {f_env} N vs {want} N");
    // And the same force read from the specimen's side: k·δ (δ̇ = 0).
    let delta = s[0] - 0.1 - v0 * 3.0;
    assert!(close(f_env, 1e7 * delta, 1e-6), "k·δ = {}", 1e7 * delta);
}

/// A closed valve (u = 0, critically centred: no flow) against a spring
/// preloaded to F₀ = 30 kN holds F₀: without leakage to the integrator's
/// rounding; with a cross-piston leakage C_l, the force creeps at the
/// quasi-static rate of the oil column and the spring in series.
///
/// By hand: the initial state holds F₀ about p_m = 1e7 Pa:
/// p_A = (F₀ + 2·A_B·p_m)/(A_A + A_B) = (3e4 + 41 988)/5.2166e-3 =
/// 1.3800e7 Pa and p_B = 6.200e6 Pa. The leak Q_l = C_l·(p_A − p_B)
/// alone (rod held) would drop the hydraulic force at
/// r₀ = βe·Q_l·(A_A/V_A + A_B/V_B); with the rod on the spring k, the force balance
/// −k_h·ẏ − r₀ = k·ẏ gives dF/dt = −r₀·k/(k + k_h), k_h = βe·(A_A²/V_A +
/// A_B²/V_B). At y = 0.25 m, V_A = 2e-4 + 3.1172e-3·0.25 = 9.793e-4 m³,
/// V_B = 2e-4 + 2.0994e-3·0.25 = 7.249e-4 m³; C_l = 1e-12 m³/(s·Pa):
/// r₀ = 1.4e9·7.6e-6·(3.183 + 2.896) = 6.47e4 N/s, k_h = 2.24e7 N/m,
/// so with k = 1e6 N/m the force falls by about 2.77 kN/s.
#[test]
fn closed_valve_against_a_spring_holds_its_force() {
    let f0 = 3e4;
    let spring = || env(Contact::Attached, 1e6, 0.0, f0, 0.25, Force::Zero);
    let mut cfg = single_rod();
    cfg.cylinder.viscous = 2000.0;
    let p = with_env(&cfg, spring());
    let mut s = p.initial_state([0.25, 0.0, 0.0], &ONE);
    let mut worst = 0.0f64;
    run(&p, &mut s, 0.0, 1e-5, 50_000, |t, s| {
        worst = worst.max((env_force(&p, t, s) - f0).abs());
    });
    assert!(worst < 1e-6 * f0, "no leakage: F drifts by {worst} N");
    // With leakage.
    cfg.cylinder.leakage = 1e-12;
    let p = with_env(&cfg, spring());
    let mut s = p.initial_state([0.25, 0.0, 0.0], &ONE);
    let (pa, pb) = (s[2], s[3]);
    let [aa, ab] = p.cylinder().area;
    let (va, vb) = (2e-4 + aa * 0.25, 2e-4 + ab * 0.25);
    assert!(close(pa, (f0 + 2.0 * ab * 1e7) / (aa + ab), 1e-12));
    let r0 = 1.4e9 * 1e-12 * (pa - pb) * (aa / va + ab / vb);
    let kh = 1.4e9 * (aa * aa / va + ab * ab / vb);
    let rate = r0 * 1e6 / (1e6 + kh);
    assert!(close(rate, 2770.0, 0.01), "hand rate {rate} N/s");
    let t_end = 0.2;
    run(&p, &mut s, 0.0, 1e-5, 20_000, |_, _| {});
    let drop = f0 - env_force(&p, t_end, &s);
    // The bound: never more than the rod-held rate r₀; the quasi-static
    // rate within the ringing's few per cent.
    assert!(
        drop > 0.0 && drop <= r0 * t_end,
        "drop {drop} N, bound {} N",
        r0 * t_end
    );
    assert!(
        close(drop, rate * t_end, 0.05),
        "drop {drop} N vs {} N",
        rate * t_end
    );
}

/// A moving mount under a closed valve: the extra force of x_e = a·sin ωt
/// is the trapped oil's stiffness k_h = βe·(A_A²/V_A + A_B²/V_B) in
/// series with the spring's k. The linear model M·ÿ + B·ẏ + (k_h + k)·y =
/// k·x_e gives F − F₀ = k·(y − x_e) of amplitude
/// k·a·|k_h − Mω² + jBω|/|k_h + k − Mω² + jBω|, which at ω → 0 is
/// k_eff·a, k_eff = k·k_h/(k + k_h). By hand at y = 0.25 m: k_h = 1.4e9·
/// (3.1172e-3²/9.793e-4 + 2.0994e-3²/7.249e-4) = 1.4e9·(9.922e-3 +
/// 6.080e-3) = 2.2403e7 N/m; with k = 1e7 N/m, k_eff = 1e7·2.2403e7/
/// 3.2403e7 = 6.914e6 N/m, so a = 0.1 mm at 2 Hz gives about 691 N.
#[test]
fn moving_mount_under_a_closed_valve_sees_the_trapped_oil_stiffness() {
    let mut cfg = single_rod();
    cfg.cylinder.viscous = 2e4;
    let (k, a, hz, f0) = (1e7, 1e-4, 2.0, 1e4);
    let w = 2.0 * std::f64::consts::PI * hz;
    let motion = Force::Sine {
        amplitude: a,
        omega: w,
        phase: 0.0,
        offset: 0.0,
    };
    let p = with_env(&cfg, env(Contact::Attached, k, 0.0, f0, 0.25, motion));
    let mut s = p.initial_state([0.25, 0.0, 0.0], &ONE);
    let [aa, ab] = p.cylinder().area;
    let (va, vb) = (2e-4 + aa * 0.25, 2e-4 + ab * 0.25);
    let kh = 1.4e9 * (aa * aa / va + ab * ab / vb);
    let k_eff = k * kh / (k + kh);
    assert!(
        close(kh, 2.2403e7, 1e-3) && close(k_eff, 6.914e6, 1e-3),
        "k_h {kh}, k_eff {k_eff}"
    );
    // The extra force's component at ω over the last two periods, after
    // the start's ringing (ζ = B/(2√(M·(k + k_h))) = 0.11) has died out.
    let h = 1e-5;
    let (mut re, mut im, mut n) = (0.0, 0.0, 0usize);
    run(&p, &mut s, 0.0, h, 150_000, |t, s| {
        if t > 0.5 + 0.5 * h {
            let df = env_force(&p, t, s) - f0;
            re += df * (w * t).cos();
            im += df * (w * t).sin();
            n += 1;
        }
    });
    let amp = 2.0 * re.hypot(im) / n as f64;
    let (m, b) = (250.0, 2e4);
    let num = (kh - m * w * w).hypot(b * w);
    let den = (kh + k - m * w * w).hypot(b * w);
    let want = k * a * num / den;
    assert!(
        close(amp, want, 2e-3),
        "amplitude {amp} N vs closed form {want} N"
    );
    assert!(
        close(amp, k_eff * a, 0.01),
        "amplitude {amp} N vs k_eff·a = {} N",
        k_eff * a
    );
    // No oil column (a valve that would hold position perfectly would be
    // k_h → ∞): the whole spring's k·a. Here the oil gives way by a third.
    assert!(amp < 0.75 * k * a);
}

/// Passivity: with the specimen's damping and no valve flow, the
/// environment only dissipates, (F − E′(δ))·δ̇ ≥ 0, at random states in
/// and out of contact, lift-off faster than the specimen relaxes included;
/// and over a run with a moving mount, ∫(port − losses) dt is the change
/// of the stored energy (oil, mass, specimen).
#[test]
fn the_environment_is_passive() {
    let e = env(Contact::Unilateral, 2e6, 5e3, 0.0, 0.2, Force::Zero);
    let mut z = 0x9E37_79B9_7F4A_7C15_u64;
    let mut uni = |lo: f64, hi: f64| {
        z ^= z << 13;
        z ^= z >> 7;
        z ^= z << 17;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut lifted = 0;
    for _ in 0..10_000 {
        let (y, v) = (uni(0.19, 0.21), uni(-1.0, 1.0));
        let (_, loss) = e.power(0.0, y, v);
        assert!(loss >= 0.0, "dissipation {loss} W at y = {y}, ẏ = {v}");
        // E′(δ) by a central difference of the stored energy.
        let d = 1e-9;
        let de = (e.stored(0.0, y + d) - e.stored(0.0, y - d)) / (2.0 * d);
        let f = e.force(0.0, y, v);
        let scale = (f.abs() + 2e6 * (y - 0.2).abs() + 1.0) * v.abs().max(1.0);
        assert!(
            (loss - (f - de) * v).abs() <= 1e-6 * scale,
            "dissipation {loss} W vs (F − E′)·δ̇ = {} W",
            (f - de) * v
        );
        if y > 0.2 && f == 0.0 {
            lifted += 1;
        }
    }
    assert!(lifted > 100, "lift-off states visited: {lifted}");
    // A run: the mount oscillates 2 mm at 5 Hz into a specimen the rod
    // rests on, valve closed; the balance closes to the integrator's
    // tolerance and the specimen's share of the losses is positive.
    let mut cfg = single_rod();
    cfg.cylinder.viscous = 500.0;
    let motion = Force::Sine {
        amplitude: 2e-3,
        omega: 2.0 * std::f64::consts::PI * 5.0,
        phase: 0.0,
        offset: 0.0,
    };
    let p = with_env(&cfg, env(Contact::Unilateral, 2e6, 5e3, 0.0, 0.2, motion));
    let mut s = p.initial_state([0.2, 0.0, 0.0], &ONE);
    let h0 = p.storage(0.0, &s);
    let h = 1e-5;
    let (mut work, mut gross, mut env_loss) = (0.0, 0.0, 0.0);
    let mut prev = p.power(0.0, &s, 0.0);
    run(&p, &mut s, 0.0, h, 40_000, |t, s| {
        let now = p.power(t, s, 0.0);
        work += 0.5 * h * ((prev.0 - prev.1) + (now.0 - now.1));
        gross += 0.5 * h * (now.0.abs() + now.1);
        env_loss += h * p
            .cylinder()
            .environment
            .as_ref()
            .unwrap()
            .power(t, s[0], s[1])
            .1;
        prev = now;
    });
    let dh = p.storage(0.4, &s) - h0;
    assert!(gross > 1.0, "the mount does work ({gross} J)");
    assert!(env_loss > 0.0, "the specimen dissipates ({env_loss} J)");
    assert!(
        (dh - work).abs() <= 1e-4 * gross,
        "ΔH {dh} J vs ∫ {work} J (of {gross} J)"
    );
}

/// The force an environment can hold the rod on a stop with (issue #46,
/// round four), by hand on a 0.4 m stroke with the mount moving ±1 mm:
/// - a spring k = 2e6 N/m, F₀ = 1e4 N at x_c = 0.2: at 0 it presses by
///   F₀ + k·(1e-3 − 0.2) = 1e4 − 3.98e5 < 0, at 0.4 by
///   −F₀ − k·(0.4 − 0.2 − 1e-3) = −1e4 − 3.98e5 < 0: 0 (it holds the rod
///   off both stops, however stiff: k = 1e15 N/m gives 0 too);
/// - F₀ = −1e12 N: at 0.4, 1e12 − 3.98e5 = 9.99999602e11 N;
/// - a specimen at x_c = 0.19: never at 0 (its face stays above 0.189),
///   never at 0.4 (it pushes towards retraction): 0; at x_c = 5e-4 its
///   face reaches −5e-4, k·5e-4 = 1e3 N at k = 2e6.
#[test]
fn the_environment_holds_the_rod_on_a_stop_only_past_its_reach() {
    let mm = Force::Sine {
        amplitude: 1e-3,
        omega: 4.0 * std::f64::consts::PI,
        phase: 0.0,
        offset: 0.0,
    };
    let spring = |k: f64, f0: f64| env(Contact::Attached, k, 0.0, f0, 0.2, mm.clone());
    assert_eq!(spring(2e6, 1e4).stop_force(0.4), 0.0);
    assert_eq!(spring(1e15, 1e4).stop_force(0.4), 0.0);
    let f = spring(2e6, -1e12).stop_force(0.4);
    assert!((f - 9.99999602e11).abs() < 1e-3, "{f}");
    let spec = |x: f64| env(Contact::Unilateral, 2e6, 0.0, 0.0, x, mm.clone());
    assert_eq!(spec(0.19).stop_force(0.4), 0.0);
    let f = spec(5e-4).stop_force(0.4);
    assert!((f - 1e3).abs() < 1e-9, "{f}");
}
