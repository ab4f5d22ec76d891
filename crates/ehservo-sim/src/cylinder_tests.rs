//! The cylinder's physics, each check against a value derived by hand.

use super::*;
use crate::force::ForceCfg;
use crate::supply::SupplyCfg;
use crate::valve::{Edges, ValveCfg};
use ehservo_core::rk4::rk4_step;

/// A context with nothing outside the plant.
fn ctx() -> PlantContext {
    PlantContext {
        load: None,
        load_given: false,
        uncertainty: UncertaintySpec::NONE,
        x0: [0.0; 3],
        base_dir: None,
        reference_range: None,
        quantity: Default::default(),
    }
}

/// A single-rod cylinder (63/36 mm, 0.5 m stroke) on a fixed 200 bar
/// supply, a critically centred valve, no friction: numbers for the tests,
/// not a product.
fn single_rod() -> CylinderCfg {
    CylinderCfg {
        cylinder: CylinderGeom {
            bore: Some(0.063),
            rod_diameter: Some(0.036),
            stroke: 0.5,
            dead_volume_a: 2e-4,
            dead_volume_b: 2e-4,
            ..Default::default()
        },
        fluid: FluidCfg {
            density: 870.0,
            bulk_modulus: 1.4e9,
            // A vanishing laminar region: the turbulent law to ~1e-12.
            viscosity: 1e-12,
        },
        valve: ValveCfg {
            spool_limit: 5e-4,
            gain: Some(5e-5),
            discharge_coefficient: Some(0.65),
            area_gradient: Some(Edges::All(0.02)),
            ..Default::default()
        },
        supply: SupplyCfg::Fixed {
            pressure: 2e7,
            tank_pressure: 0.0,
        },
        load: LoadCfg {
            mass: 250.0,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn build(c: &CylinderCfg) -> CylinderPlant {
    c.build(&ctx()).expect("valid test cylinder")
}

const ONE: CylinderVariation = CylinderVariation { f: Factors::ONE };

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Steady flow: at constant extension speed v against a constant force F,
/// chamber A takes A_A·v, chamber B gives A_B·v, so (Ps − p_A)/p_B =
/// (A_A/A_B)² = r², and the force balance A_A·p_A − A_B·p_B = F gives
/// p_B = (A_A·Ps − F)/(A_A·r² + A_B); the spool opening follows from
/// Q_B = k·x·√p_B, k = Cd·w·√(2/ρ). At that state every derivative but ẏ
/// is zero.
#[test]
fn steady_flow_balance() {
    let mut cfg = single_rod();
    let f_ext = 8e3;
    cfg.load.force = Some(ForceCfg::Constant { value: f_ext });
    let p = build(&cfg);
    let c = p.cylinder();
    let [aa, ab] = c.area;
    let ps = 2e7;
    let k = 0.65 * 0.02 * (2.0 / 870.0_f64).sqrt();
    for &v in &[0.05, 0.2] {
        let r2 = (aa / ab) * (aa / ab);
        let pb = (aa * ps - f_ext) / (aa * r2 + ab);
        let pa = ps - r2 * pb;
        let x = ab * v / (k * pb.sqrt());
        let u = x / 5e-5;
        let s = [0.25, v, pa, pb, ps, 0.0];
        let mut ds = [0.0; 6];
        p.deriv(0.0, &s, u, &ONE, &mut ds);
        assert_eq!(ds[0], v);
        // Scales: the pressure force per mass, βe/V·A·v.
        let acc = aa * ps / c.mass;
        let prate = 1.4e9 / 2e-4 * aa * v;
        assert!(ds[1].abs() <= 1e-10 * acc, "ÿ = {}", ds[1]);
        assert!(ds[2].abs() <= 1e-9 * prate, "ṗ_A = {}", ds[2]);
        assert!(ds[3].abs() <= 1e-9 * prate, "ṗ_B = {}", ds[3]);
    }
}

/// Each physical factor scales its own parameter and nothing else, each
/// against the closed form of the one term it enters (a state at rest, or
/// moving, with the valve closed or open):
/// - mass f_m on a vertical axis with the chambers holding the nominal
///   weight: ÿ = (M·g − f_m·M·g)/(f_m·M) = g·(1 − f_m)/f_m (the weight is
///   the mass's);
/// - bulk modulus f_β: ṗ_A = f_β·βe/V_A·(−A_A·ẏ) with the valve closed;
/// - leakage f_l: ṗ_A = −βe/V_A·f_l·C_l·(p_A − p_B) at rest, valve closed;
/// - supply pressure f_s: Q_A = k·x·√(f_s·Ps − p_A) through the open P→A
///   edge (turbulent), so ṗ_A at rest is in the ratio √((f_s·Ps − p_A)/(Ps − p_A));
/// - friction f_f: a viscous B_p·ẏ becomes f_f·B_p·ẏ;
/// - load f_L: a spring K·(y − y_K) becomes f_L·K·(y − y_K).
#[test]
fn each_physical_factor_scales_its_parameter() {
    let var = |f: Factors| CylinderVariation { f };
    let g = STANDARD_GRAVITY;
    let mut cfg = single_rod();
    cfg.load.incline_deg = 90.0;
    cfg.cylinder.leakage = 1e-12;
    cfg.cylinder.viscous = 2e3;
    cfg.load.spring = 1e5;
    cfg.load.spring_origin = 0.1;
    let p = build(&cfg);
    let c = p.cylinder().clone();
    let [aa, ab] = c.area;
    let (m, y) = (250.0, 0.1);
    let [va, _] = c.volumes(y);
    // Mass: at rest at the spring's origin, p_B = 5 MPa, p_A holding M·g.
    let pb = 5e6;
    let pa = (m * g + ab * pb) / aa;
    let rest = [y, 0.0, pa, pb, 2e7, 0.0];
    let mut ds = [0.0; 6];
    p.deriv(0.0, &rest, 0.0, &ONE, &mut ds);
    // Nominal: the leakage term alone moves p_A (checked below); no force.
    assert!(ds[1].abs() <= 1e-9 * g, "nominal ÿ = {}", ds[1]);
    for fm in [0.8, 1.25] {
        let f = Factors {
            mass: fm,
            ..Factors::ONE
        };
        p.deriv(0.0, &rest, 0.0, &var(f), &mut ds);
        let want = g * (1.0 - fm) / fm;
        assert!(close(ds[1], want, 1e-9), "mass {fm}: ÿ {} vs {want}", ds[1]);
    }
    // Leakage at rest, valve closed (critically centred: no flow at u = 0).
    for fl in [1.0, 3.0] {
        let f = Factors {
            leakage: fl,
            ..Factors::ONE
        };
        p.deriv(0.0, &rest, 0.0, &var(f), &mut ds);
        let want = -1.4e9 / va * fl * 1e-12 * (pa - pb);
        assert!(
            close(ds[2], want, 1e-12),
            "leakage {fl}: ṗ_A {} vs {want}",
            ds[2]
        );
    }
    // Bulk modulus, moving at 0.1 m/s with equal pressures (no leakage flow).
    let moving = [y, 0.1, pb, pb, 2e7, 0.0];
    for fb in [0.7, 1.0] {
        let f = Factors {
            bulk_modulus: fb,
            ..Factors::ONE
        };
        p.deriv(0.0, &moving, 0.0, &var(f), &mut ds);
        let want = -fb * 1.4e9 / va * aa * 0.1;
        assert!(
            close(ds[2], want, 1e-12),
            "βe {fb}: ṗ_A {} vs {want}",
            ds[2]
        );
    }
    // Friction and load: the force at the moving state, against its parts
    // (A_A·p − A_B·p − f_f·B_p·ẏ − f_L·K·(y − y_K) − f_m·M·g; y = y_K).
    let y1 = 0.3;
    let moved = [y1, 0.1, pb, pb, 2e7, 0.0];
    for (ff, fload) in [(1.0, 1.0), (1.5, 1.0), (1.0, 0.6)] {
        let f = Factors {
            friction: ff,
            load: fload,
            ..Factors::ONE
        };
        p.deriv(0.0, &moved, 0.0, &var(f), &mut ds);
        let force = (aa - ab) * pb - ff * 2e3 * 0.1 - fload * 1e5 * (y1 - 0.1) - m * g;
        assert!(
            close(ds[1], force / m, 1e-12),
            "friction {ff}, load {fload}: ÿ {} vs {}",
            ds[1],
            force / m
        );
    }
    // Supply pressure: valve open (u > 0: P→A), at rest, p_A = p_B = 5 MPa.
    let open = [y, 0.0, pb, pb, 2e7, 0.0];
    let rate = |fs: f64| {
        let mut d = [0.0; 6];
        let f = Factors {
            supply_pressure: fs,
            ..Factors::ONE
        };
        p.deriv(0.0, &open, 1.0, &var(f), &mut d);
        d[2]
    };
    let want = ((0.8 * 2e7 - pb) / (2e7 - pb)).sqrt();
    assert!(
        close(rate(0.8) / rate(1.0), want, 1e-9),
        "supply ratio {} vs {want}",
        rate(0.8) / rate(1.0)
    );
}

/// H's rate along the vector field, by a central difference of H itself
/// (independent of the power terms below).
fn storage_rate(p: &CylinderPlant, s: &[f64; 6], ds: &[f64; 6]) -> f64 {
    let e = 1e-7;
    let plus: [f64; 6] = core::array::from_fn(|i| s[i] + e * ds[i]);
    let minus: [f64; 6] = core::array::from_fn(|i| s[i] - e * ds[i]);
    (p.storage(0.0, &plus) - p.storage(0.0, &minus)) / (2.0 * e)
}

/// Energy, pointwise: dH/dt = π_s·Q_P − π_t·Q_T − F(t)·ẏ − losses, the
/// losses (valve edges, leakage, viscous, friction, the stop's damper)
/// each ≥ 0, at random states without cavitation, at the stops too.
#[test]
fn power_balance_at_random_states() {
    let mut cfg = single_rod();
    cfg.cylinder.leakage = 2e-12;
    cfg.cylinder.viscous = 300.0;
    cfg.load.spring = 4e4;
    cfg.load.spring_origin = 0.1;
    cfg.load.incline_deg = 30.0;
    cfg.load.friction = Some(Friction {
        coulomb: 200.0,
        stiction: 300.0,
        stribeck_velocity: 0.01,
        viscous: 100.0,
        smoothing: 1e-3,
    });
    cfg.load.force = Some(ForceCfg::Constant { value: 1500.0 });
    cfg.supply = SupplyCfg::Fixed {
        pressure: 2e7,
        tank_pressure: 3e5,
    };
    cfg.fluid.viscosity = 46e-6;
    let p = build(&cfg);
    let mut z = 0x2545_F491_4F6C_DD1D_u64;
    let mut uni = |lo: f64, hi: f64| {
        z ^= z << 13;
        z ^= z >> 7;
        z ^= z << 17;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    };
    for _ in 0..20_000 {
        let s = [
            uni(-0.002, 0.502),
            uni(-0.5, 0.5),
            uni(1e5, 2.2e7),
            uni(1e5, 2.2e7),
            2e7,
            0.0,
        ];
        let u = uni(-12.0, 12.0);
        let mut ds = [0.0; 6];
        p.deriv(0.0, &s, u, &ONE, &mut ds);
        let rate = storage_rate(&p, &s, &ds);
        let (port, loss) = p.power(0.0, &s, u);
        assert!(loss >= 0.0, "losses {loss} at {s:?}");
        let scale = port.abs() + loss + (p.cylinder().area[0] * s[1] * 2e7).abs() + 1.0;
        assert!(
            (rate - (port - loss)).abs() <= 1e-6 * scale,
            "dH/dt {rate} vs {} at {s:?}, u = {u}",
            port - loss
        );
    }
}

/// Energy over a run: with an open-loop spool signal, ∫(port − losses) dt
/// equals H(T) − H(0) to the integrator's tolerance (RK4 at 10 µs, the
/// integral by the trapezoid rule on the same grid).
#[test]
fn energy_balance_over_a_run() {
    let mut cfg = single_rod();
    cfg.cylinder.leakage = 1e-12;
    cfg.cylinder.viscous = 500.0;
    cfg.load.spring = 2e4;
    cfg.fluid.viscosity = 46e-6;
    let p = build(&cfg);
    let mut s = p.initial_state([0.2, 0.0, 0.0], &ONE);
    let h0 = p.storage(0.0, &s);
    let h = 1e-5;
    let u = |t: f64| 6.0 * (2.0 * core::f64::consts::PI * 2.0 * t).sin();
    let (mut work, mut prev) = (0.0, {
        let (a, b) = p.power(0.0, &s, u(0.0));
        a - b
    });
    let mut gross = 0.0;
    for k in 0..50_000 {
        let t = k as f64 * h;
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, u(tt), &ONE, d),
            t,
            &mut s,
            h,
        );
        let (a, b) = p.power(t + h, &s, u(t + h));
        let now = a - b;
        work += 0.5 * h * (prev + now);
        gross += 0.5 * h * (a.abs() + b);
        prev = now;
        assert!(s[2] > 0.0 && s[3] > 0.0, "no cavitation in this run");
    }
    let dh = p.storage(0.0, &s) - h0;
    assert!(gross > 1e3, "the run does work ({gross} J)");
    assert!(
        (dh - work).abs() <= 1e-5 * gross,
        "ΔH {dh} J vs ∫ {work} J (of {gross} J)"
    );
}

/// With the valve closed, a small velocity rings at the oil column's
/// frequency ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M) (no damping, no spring).
#[test]
fn ringing_frequency_with_the_valve_closed() {
    let cfg = single_rod();
    let p = build(&cfg);
    let c = p.cylinder().clone();
    let y0 = 0.15;
    let [va, vb] = c.volumes(y0);
    let [aa, ab] = c.area;
    let wh = (1.4e9 * (aa * aa / va + ab * ab / vb) / 250.0).sqrt();
    // Pressures balanced (no force), a 1 mm/s kick.
    let pm = 1e7;
    let pb = pm;
    let pa = ab * pb / aa;
    let mut s = [y0, 1e-3, pa, pb, 2e7, 0.0];
    let h = 1e-6;
    let mut crossings = Vec::new();
    let mut prev = s[1];
    for k in 0..200_000 {
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, 0.0, &ONE, d),
            k as f64 * h,
            &mut s,
            h,
        );
        if prev > 0.0 && s[1] <= 0.0 {
            // Linear interpolation of the crossing time.
            let frac = prev / (prev - s[1]);
            crossings.push((k as f64 + frac) * h);
        }
        prev = s[1];
    }
    assert!(crossings.len() >= 5, "{} crossings", crossings.len());
    let n = crossings.len() - 1;
    let period = (crossings[n] - crossings[0]) / n as f64;
    let want = 2.0 * core::f64::consts::PI / wh;
    assert!(
        close(period, want, 2e-4),
        "period {period} vs 2π/ω_h = {want}"
    );
}

/// The single rod's speeds under the same opening in each direction, with
/// a viscous load B. On a fixed supply (pressure-fed, both edges the same):
/// the force balance with the orifice drops, A·Ps − c·v²·(A_A³ + A_B³) = B·v
/// with c = 1/(k·x)², A = A_A extending and A_B retracting, a quadratic
/// solved here; at B = 0 it gives v_ext/v_ret = √(A_A/A_B). From a pump
/// whose flow Q the relief does not divert (flow-fed, a large valve):
/// v_ext = Q/A_A, v_ret = Q/A_B, so v_ret/v_ext = A_A/A_B.
#[test]
fn single_rod_velocity_ratios() {
    let settle = |p: &CylinderPlant, u: f64, y0: f64, ps0: f64| {
        let mut s = [y0, 0.0, 1e7, 1e7, ps0, 0.0];
        // 0.4 s: the start's jolt rings down (ζ ≈ 0.13 at ω_h ≈ 300 rad/s).
        let h = 2e-6;
        for k in 0..200_000 {
            rk4_step(
                |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, u, &ONE, d),
                k as f64 * h,
                &mut s,
                h,
            );
        }
        s[1]
    };
    let b = 2e4;
    let mut cfg = single_rod();
    cfg.cylinder.viscous = b;
    let p = build(&cfg);
    let [aa, ab] = p.cylinder().area;
    let (ve, vr) = (settle(&p, 4.0, 0.1, 2e7), settle(&p, -4.0, 0.4, 2e7));
    let kx = 0.65 * 0.02 * (2.0 / 870.0_f64).sqrt() * (4.0 * 5e-5);
    let (c, sum) = (1.0 / (kx * kx), aa.powi(3) + ab.powi(3));
    let speed = |a: f64| (-b + (b * b + 4.0 * c * sum * a * 2e7).sqrt()) / (2.0 * c * sum);
    assert!(close(ve, speed(aa), 1e-4), "v_ext {ve} vs {}", speed(aa));
    assert!(
        close(-vr, speed(ab), 1e-4),
        "v_ret {} vs {}",
        -vr,
        speed(ab)
    );
    // B → 0: the ratio of the closed forms is √(A_A/A_B).
    let at0 = |a: f64| (a * 2e7 / (c * sum)).sqrt();
    assert!(close(at0(aa) / at0(ab), (aa / ab).sqrt(), 1e-12));
    // Flow-fed: a 10 l/min pump, a relief far above what the motion needs.
    cfg.valve.area_gradient = Some(Edges::All(0.2));
    let q = 10e-3 / 60.0;
    cfg.supply = SupplyCfg::Pump {
        displacement: q * 2.0 * core::f64::consts::PI / 100.0,
        speed: 100.0,
        leakage: 0.0,
        volume: 1e-4,
        bulk_modulus: None,
        relief_pressure: 3e7,
        relief_time_constant: Some(1e-3),
        relief_k_cs: Some(1e-8),
        relief_k_cf: Some(1e-8),
        relief_q_nom: Some(1e-3),
        relief_full_flow_pressure: None,
        relief_rated_flow: None,
        relief_response_time: None,
        tank_pressure: 0.0,
        initial_pressure: Some(1e6),
        accumulator: None,
    };
    let p = build(&cfg);
    let (ve, vr) = (settle(&p, 10.0, 0.1, 1e6), settle(&p, -10.0, 0.4, 1e6));
    assert!(close(ve, q / aa, 1e-3), "v_ext {ve} vs Q/A_A {}", q / aa);
    assert!(
        close(-vr / ve, aa / ab, 1e-3),
        "v_ret/v_ext {} vs {}",
        -vr / ve,
        aa / ab
    );
}

/// The nominal model of a double-rod cylinder at mid-stroke is the
/// paper's (9) of Dm = A, Jt = M, Vt = 2·V (V each chamber's volume
/// there), Kce = C_l, Ag = w, written out by hand.
#[test]
fn nominal_model_of_a_double_rod_at_mid_stroke() {
    let mut cfg = single_rod();
    cfg.cylinder.rods = Some(2);
    cfg.cylinder.leakage = 3e-12;
    cfg.cylinder.viscous = 800.0;
    cfg.load.spring = 1e4;
    let p = build(&cfg);
    let c = p.cylinder();
    let a = c.area[0];
    let v = 2e-4 + a * 0.25;
    let (m, b, k, be, cl, vt) = (250.0, 800.0, 1e4, 1.4e9, 3e-12, 2.0 * v);
    let a1 = 4.0 * be * cl * k / (vt * m);
    let a2 = k / m + 4.0 * be * a * a / (vt * m) + 4.0 * be * cl * b / (vt * m);
    let a3 = b / m + 4.0 * be * cl / vt;
    let got = p.nominal().coeffs.as_array();
    for (i, want) in [a1, a2, a3].iter().enumerate() {
        assert!(
            close(got[i], *want, 1e-12),
            "a{} {} vs {want}",
            i + 1,
            got[i]
        );
    }
    // b at rest: 4βe·A·Kq·Kv/(Vt·M), Kq = Cd·w·√(Ps/ρ).
    let kq = 0.65 * 0.02 * (2e7 / 870.0_f64).sqrt();
    let b0 = 4.0 * be * a * kq * 5e-5 / (vt * m);
    assert!(close(p.nominal().b_at_rest(), b0, 1e-12));
    assert_eq!(p.nominal().offset(), 0.0, "symmetric: no offset");
}

/// The single rod's nominal gain in each direction is the plant's own:
/// at rest with the steady pressure split of each direction (module doc),
/// ∂y⃛/∂u at a small opening (by a finite difference of the plant's jerk)
/// is b(x = 0, ±1); their ratio at no load is √(A_A/A_B).
#[test]
fn single_rod_direction_dependent_gain() {
    let mut cfg = single_rod();
    cfg.nominal.position = Some(0.2);
    let p = build(&cfg);
    let c = p.cylinder();
    let [aa, ab] = c.area;
    let ps = 2e7;
    let m = p.nominal();
    let x = [0.0; 3];
    let (bp, bm) = (m.b(&x, 1.0).0, m.b(&x, -1.0).0);
    assert!(close(bp / bm, (aa / ab).sqrt(), 1e-12), "b+/b− {}", bp / bm);
    let jerk = |s: &[f64; 6], u: f64| {
        let mut d = [0.0; 6];
        p.deriv(0.0, s, u, &ONE, &mut d);
        (aa * d[2] - ab * d[3]) / c.mass
    };
    let den = aa.powi(3) + ab.powi(3);
    // Extending: (Ps − p_A)/p_B = (A_A/A_B)², A_A·p_A = A_B·p_B.
    let pb = ab * ab * aa * ps / den;
    let pa = ps - (aa / ab).powi(2) * pb;
    let s = [0.2, 0.0, pa, pb, ps, 0.0];
    let du = 1e-3;
    let g = (jerk(&s, du) - jerk(&s, 0.0)) / du;
    assert!(close(g, bp, 1e-6), "∂y⃛/∂u {g} vs b+ {bp}");
    // Retracting: (Ps − p_B)/p_A = (A_B/A_A)².
    let pa = aa * aa * ab * ps / den;
    let pb = ps - (ab / aa).powi(2) * pa;
    let s = [0.2, 0.0, pa, pb, ps, 0.0];
    let g = (jerk(&s, 0.0) - jerk(&s, -du)) / du;
    assert!(close(g, bm, 1e-6), "∂y⃛/∂u {g} vs b− {bm}");
}

/// A cavity: a chamber state below 0 acts as 0 on the piston and the
/// edges, and the state keeps integrating the net flow.
#[test]
fn cavitation_holds_the_acting_pressure_at_zero() {
    let p = build(&single_rod());
    let c = p.cylinder();
    let s = [0.2, -0.3, -2e5, 1e7, 2e7, 0.0];
    let x = p.measure(0.0, &s, &ONE);
    let want = (-c.area[1] * 1e7) / c.mass;
    assert!(close(x[2], want, 1e-14), "ÿ {} vs {want}", x[2]);
    let mut ds = [0.0; 6];
    p.deriv(0.0, &s, 0.0, &ONE, &mut ds);
    // The retracting rod still grows the cavity: dp̃_A/dt = −βe/V_A·A_A·ẏ > 0.
    let [va, _] = c.volumes(0.2);
    assert!(close(ds[2], -1.4e9 / va * c.area[0] * -0.3, 1e-14));
}

/// End stops push back and let go: a rod driven into the bottom rests
/// there (the run goes on, finite), and one driven out leaves it.
#[test]
fn end_stops_hold_and_release() {
    let p = build(&single_rod());
    let mut s = p.initial_state([0.05, 0.0, 0.0], &ONE);
    let h = 1e-5;
    for k in 0..60_000 {
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, -10.0, &ONE, d),
            k as f64 * h,
            &mut s,
            h,
        );
        assert!(s.iter().all(|v| v.is_finite()), "finite at step {k}");
    }
    assert!(s[0] < 0.0 && s[0] > -1e-3, "at the stop: y = {}", s[0]);
    assert!(s[1].abs() < 1e-3, "at rest: ẏ = {}", s[1]);
    for k in 0..20_000 {
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, 10.0, &ONE, d),
            k as f64 * h,
            &mut s,
            h,
        );
    }
    assert!(s[0] > 0.01, "released: y = {}", s[0]);
}

#[test]
fn bad_geometry_is_named() {
    let bad = |f: &dyn Fn(&mut CylinderCfg)| {
        let mut c = single_rod();
        f(&mut c);
        c.build(&ctx()).unwrap_err()
    };
    assert_eq!(
        bad(&|c| c.cylinder.rod_diameter = Some(0.063)).key,
        "plant.cylinder.rod_diameter"
    );
    assert_eq!(
        bad(&|c| c.cylinder.dead_volume_a = 0.0).key,
        "plant.cylinder.dead_volume_a"
    );
    assert_eq!(
        bad(&|c| {
            c.cylinder.bore = None;
            c.cylinder.rod_diameter = None;
            c.cylinder.area_a = Some(1e-3);
            c.cylinder.area_b = Some(2e-3);
        })
        .key,
        "plant.cylinder.area_b"
    );
    assert_eq!(
        bad(&|c| c.valve.lap = Some(Edges::All(1e-3))).key,
        "plant.valve.lap"
    );
    assert_eq!(
        bad(&|c| {
            c.load.incline_deg = 90.0;
            c.load.mass = 1e5;
        })
        .key,
        "plant.supply.pressure"
    );
    // The reasons read as before: the key path, then the sentence.
    assert_eq!(
        bad(&|c| c.load.mass = -1.0).to_string(),
        "`plant.load.mass`: must be finite and > 0 (got -1.0)"
    );
    assert!(matches!(
        bad(&|c| c.fluid.viscosity = f64::NAN).reason,
        crate::error::Reason::NotPositive(v) if v.is_nan()
    ));
    assert_eq!(
        bad(&|c| c.load.friction = Some(Friction {
            coulomb: f64::NAN,
            ..Friction::default()
        }))
        .to_string(),
        "`plant.load.friction.coulomb`: must be finite and >= 0 (got NaN)"
    );
    assert_eq!(
        bad(&|c| c.load.force = Some(ForceCfg::Constant {
            value: f64::INFINITY
        }))
        .to_string(),
        "`plant.load.force.value`: must be finite (got inf)"
    );
    assert_eq!(
        bad(&|c| c.supply = SupplyCfg::Fixed {
            pressure: 1e7,
            tank_pressure: 1e7,
        })
        .to_string(),
        "`plant.supply.tank_pressure`: must be below the supply pressure 10000000.0 Pa (got 10000000.0)"
    );
}

#[path = "cylinder_friction_tests.rs"]
mod friction;

/// Flow-fed by a pressure-compensated pump with an accumulator on its
/// line: in steady extension the valve passes A_A·v from the line (the
/// P→A edge alone is open, no chamber leakage, ṗ_A = 0), so the pump's
/// delivery is A_A·v plus its leakage and the line sits at the
/// compensator's closed form
/// p = (p_set + P_t + r_p·(C_lp·P_t − A_A·v))/(1 + r_p·C_lp) with
/// r_p = band/q_max (ehservo_sim::pc_pump). The
/// accumulator, the pressure steady, takes no flow (a small one, 10 cm³:
/// a larger one softens the line and slows the regulator's loop beyond
/// the 1.5 s the rod has before its stop).
#[test]
fn a_pc_pump_feeds_the_cylinder_at_its_closed_form() {
    let mut cfg = single_rod();
    cfg.cylinder.viscous = 2e4;
    let q_max = 6e-4;
    cfg.supply = toml::from_str(&format!(
        "kind = \"pc-pump\"\ndisplacement = {q_max}\nspeed = 6.283185307179586\n\
         leakage = 1e-12\nvolume = 1e-4\ncompensator_pressure = 2e7\n\
         compensator_band = 1e6\ntank_pressure = 1e5\ninitial_pressure = 1.9e7\n\
         accumulator = {{ precharge = 1e7, volume = 1e-5, exponent = 1.4 }}\n"
    ))
    .unwrap();
    let p = build(&cfg);
    let c = p.cylinder();
    let Supply::PcPump(pump) = c.supply else {
        unreachable!()
    };
    let mut s = c.initial_state(0.1, 0.0, 0.0, &Factors::ONE);
    let h = 5e-6;
    for k in 0..300_000 {
        rk4_step(
            |tt, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(tt, x, 4.0, &ONE, d),
            k as f64 * h,
            &mut s,
            h,
        );
        p.limit_state(&mut s);
    }
    let v = s[1];
    let q = c.area[0] * v;
    assert!(v > 0.0 && q < q_max, "v = {v}");
    let r_p = 1e6 / q_max;
    let want = (2e7 + 1e5 + r_p * (1e-12 * 1e5 - q)) / (1.0 + r_p * 1e-12);
    assert!(close(s[4], want, 1e-9), "p_s {} vs {want}", s[4]);
    assert!(close(pump.steady_pressure(1e5, q, 1.0), want, 1e-12));
    let mut ds = [0.0; 6];
    p.deriv(1.0, &s, 4.0, &ONE, &mut ds);
    assert!(ds[4].abs() < 1e-3 * want, "ṗ_s = {}", ds[4]);
}

#[path = "cylinder_env_tests.rs"]
mod env;
