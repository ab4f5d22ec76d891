//! The cylinder's Jacobians against central differences of the simulator's
//! own derivative, its trims and its linear model against hand-derived
//! values (Merritt, Hydraulic Control Systems, 1967, ch. 2 and 5).

use super::super::finite_difference;
use super::*;
use ehservo_sim::cylinder::CylinderCfg;
use ehservo_sim::plant::{PlantConfig, PlantContext, UncertaintySpec};

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

fn build(toml_text: &str) -> CylinderLin {
    let cfg: CylinderCfg = toml::from_str(toml_text).expect("a valid test cylinder");
    CylinderLin::new(cfg.build(&ctx()).expect("builds"), Factors::ONE, 0.0)
}

/// A single-rod cylinder after Chrono's (80/35 mm), lifting 500 kg
/// vertically, with Stribeck friction and a spring, on a fixed supply with
/// leakage: numbers for the tests, not a product.
const SINGLE_ROD: &str = r#"
[cylinder]
bore = 0.08
rod_diameter = 0.035
stroke = 0.284
dead_volume_a = 7e-5
dead_volume_b = 1.1e-4
viscous = 2e3
leakage = 1e-13
[fluid]
density = 850.0
bulk_modulus = 8.4e8
[valve]
rated_flow = 4e-4
rated_drop = 7e6
spool_limit = 1e-3
rated_signal = 10.0
[supply]
kind = "fixed"
pressure = 7.6e6
tank_pressure = 1e5
[load]
mass = 500.0
incline_deg = 90.0
spring = 2e4
spring_origin = 0.1
[load.friction]
coulomb = 150.0
stiction = 200.0
stribeck_velocity = 0.01
viscous = 0.0
smoothing = 0.002
"#;

/// Hopsan's Position Servo's cylinder (scenarios/hopsan/position-servo.toml):
/// a double rod, overlapped valve, pump, relief and line volume.
const PUMP_FED: &str = r#"
[cylinder]
area_a = 1e-3
area_b = 1e-3
stroke = 1.0
dead_volume_a = 3e-4
dead_volume_b = 3e-4
[fluid]
density = 890.0
bulk_modulus = 1e9
[valve]
spool_limit = 0.01
rated_signal = 10.0
discharge_coefficient = 0.67
spool_diameter = 0.01
lap = 1e-4
[supply]
kind = "pump"
displacement = 25e-5
speed = 200.0
leakage = 1e-12
volume = 1e-3
bulk_modulus = 1e9
relief_pressure = 2e7
relief_time_constant = 1e-3
relief_k_cs = 1e-8
relief_k_cf = 1e-8
relief_q_nom = 0.01
tank_pressure = 1e5
[load]
mass = 100.0
spring = 100.0
"#;

/// Entry by entry, `|analytic − fd| ≤ 1e-5·(|fd| + 1e-3·(the row's largest
/// |fd|))`: central differences at the steps of [`finite_difference`] are
/// accurate to about 1e-8 relative; the row term absorbs an entry that is
/// a difference of large terms (the pressure rows reach 1e13 Pa/(s·m)).
fn close(an: &DMatrix<f64>, fd: &DMatrix<f64>, what: &str) {
    for i in 0..an.nrows() {
        let row = (0..an.ncols()).fold(0.0f64, |m, j| m.max(fd[(i, j)].abs()));
        for j in 0..an.ncols() {
            let (a, f) = (an[(i, j)], fd[(i, j)]);
            assert!(
                (a - f).abs() <= 1e-5 * (f.abs() + 1e-3 * row) + 1e-12,
                "{what}[{i},{j}]: analytic {a:e} vs finite difference {f:e}"
            );
        }
    }
}

fn check(lin: &CylinderLin, x: &[f64], u: f64, what: &str) {
    let p = Point {
        x,
        u,
        v: crate::plant::Variation::NONE,
    };
    assert!(lin.kinks(&p).is_empty(), "{what}: a kink at {x:?}, u = {u}");
    let an = lin.jacobian(&p, Side::Plus);
    let fd = finite_difference(lin, &p);
    close(&an.a, &fd.a, &format!("{what} A"));
    close(&an.b, &fd.b, &format!("{what} B"));
    close(&an.c, &fd.c, &format!("{what} C"));
}

/// The Jacobian against central differences of `Plant::deriv` at the trims
/// of both directions (extending and retracting are separate points: the
/// metering edges, the areas they feed and the drops differ) at three rod
/// positions and two speeds (20 and 50 mm/s), and at points off the trim (pressures and
/// speed moved, the command moved), for the single rod on a fixed supply
/// and the pump-fed double rod; and under physical factors.
#[test]
fn jacobian_matches_central_differences_in_both_directions() {
    let factors = Factors {
        mass: 1.2,
        bulk_modulus: 0.8,
        leakage: 1.5,
        supply_pressure: 0.95,
        friction: 1.3,
        load: 0.9,
    };
    for (text, what) in [(SINGLE_ROD, "single rod"), (PUMP_FED, "pump-fed")] {
        for f in [Factors::ONE, factors] {
            let base = build(text);
            let lin = CylinderLin::new(base.plant.clone(), f, 0.0);
            let stroke = lin.c().stroke;
            for frac in [0.2, 0.5, 0.8] {
                for v0 in [0.02, -0.02, 0.05, -0.05] {
                    let dir = if v0 > 0.0 { "extending" } else { "retracting" };
                    let (x, u, _) = lin
                        .trim(frac * stroke, v0, Side::Plus)
                        .unwrap_or_else(|e| panic!("{what} {dir} at {frac}: {e}"));
                    let tag = format!("{what}, {dir} at {frac} of the stroke, v = {v0}");
                    check(&lin, &x, u, &tag);
                    let mut off = x.clone();
                    off[1] *= 1.3;
                    off[2] *= 1.04;
                    off[3] *= 0.97;
                    check(&lin, &off, u * 1.1, &format!("{tag}, off the trim"));
                }
            }
        }
    }
}

/// With an environment the rod's row gains its spring and damper while it
/// pushes (−k/M, −c/M): the Jacobian against central differences at the
/// trims of [`SINGLE_ROD`] against a preloaded spring (pulling at the
/// stroke's start, pushing at its end) and against a specimen it is
/// pressing into (touched at y = 0.05 m, before every trim).
#[test]
fn jacobian_with_an_environment_matches_central_differences() {
    for (env, what) in [
        (
            "[environment]\nkind = \"spring\"\nstiffness = 1e5\ndamping = 500.0\npreload = 1e3\nposition = 0.14\n",
            "spring",
        ),
        (
            "[environment]\nkind = \"specimen\"\nstiffness = 1e5\ndamping = 500.0\nposition = 0.05\n",
            "specimen",
        ),
    ] {
        let lin = build(&format!("{SINGLE_ROD}{env}"));
        let stroke = lin.c().stroke;
        for frac in [0.2, 0.5, 0.8] {
            for v0 in [0.02, -0.02] {
                let (x, u, _) = lin
                    .trim(frac * stroke, v0, Side::Plus)
                    .unwrap_or_else(|e| panic!("{what} at {frac}, v = {v0}: {e}"));
                check(&lin, &x, u, &format!("{what} at {frac} of the stroke, v = {v0}"));
            }
        }
    }
}

/// Merritt's closed form, derived by hand from this model's equations for
/// a symmetric (double-rod) cylinder at mid-stroke, a critically centred
/// valve, no leakage, Pt = 0: the trim holds p_A = p_B = Ps/2 (no load);
/// the linearised chamber equations are `(V/βe)·ṗ_A = K_q·x_v − A·ẏ`,
/// `(V/βe)·ṗ_B = −K_q·x_v + A·ẏ` with Merritt's null flow gain
/// `K_q = Cd·w·√(Ps/ρ)` and `K_c = 0` (ch. 2, the critically centred
/// valve), so the oil column's natural frequency is
/// `ω_h² = (βe/M)·(A²/V_A + A²/V_B)` = Merritt's `4βe·A²/(V_t·M)` with
/// V_t = 2V (ch. 5, the valve-controlled piston), and the viscous B damps
/// it: the poles are `−B/(2M) ± j·√(ω_h² − (B/2M)²)`, with two at 0 (the
/// position's integrator and the pressures' common mode). Both valve
/// directions give the same gain here, so there is no kink.
#[test]
fn symmetric_cylinder_at_centre_has_merritts_natural_frequency() {
    let (d, rod, stroke, v0) = (0.063, 0.036, 0.5, 2e-4);
    let (rho, beta, mass, visc) = (870.0, 1.4e9, 250.0, 3000.0);
    let (ps, cd, w, kv) = (2e7, 0.65, 0.02, 5e-5);
    let text = format!(
        "[cylinder]\nbore = {d}\nrod_diameter = {rod}\nrods = 2\nstroke = {stroke}\ndead_volume_a = {v0}\ndead_volume_b = {v0}\nviscous = {visc}\n\
         [fluid]\ndensity = {rho}\nbulk_modulus = {beta}\n\
         [valve]\nspool_limit = 5e-4\ngain = {kv}\ndischarge_coefficient = {cd}\narea_gradient = {w}\n\
         [supply]\nkind = \"fixed\"\npressure = {ps}\n[load]\nmass = {mass}\n"
    );
    let lin = build(&text);
    let (x, u, _) = lin.trim(0.5 * stroke, 0.0, Side::Plus).unwrap();
    assert!((x[2] - ps / 2.0).abs() <= 1e-9 * ps, "p_A = {}", x[2]);
    assert!((x[3] - ps / 2.0).abs() <= 1e-9 * ps, "p_B = {}", x[3]);
    assert_eq!(u, 0.0);
    let p = Point {
        x: &x,
        u,
        v: crate::plant::Variation::NONE,
    };
    assert!(lin.kinks(&p).is_empty(), "{:?}", lin.kinks(&p));
    let area = std::f64::consts::PI / 4.0 * (d * d - rod * rod);
    let vol = v0 + area * stroke / 2.0;
    let kq = cd * w * (ps / rho).sqrt();
    let j = lin.jacobian(&p, Side::Plus);
    let want_b = beta / vol * kq * kv;
    assert!(
        (j.b[(2, 0)] - want_b).abs() <= 1e-12 * want_b,
        "{}",
        j.b[(2, 0)]
    );
    assert!(
        (j.b[(3, 0)] + want_b).abs() <= 1e-12 * want_b,
        "{}",
        j.b[(3, 0)]
    );
    let wh2 = beta / mass * (area * area / vol + area * area / vol);
    let sigma = visc / (2.0 * mass);
    let g = lin.model(&p, Side::Plus);
    let poles = g.poles().unwrap();
    let pair: Vec<_> = poles.iter().filter(|z| z.im.abs() > 1.0).collect();
    assert_eq!(pair.len(), 2, "{poles:?}");
    for z in pair {
        assert!(
            (z.norm_sqr() - wh2).abs() <= 1e-7 * wh2,
            "|p|² {} vs ω_h² {wh2}",
            z.norm_sqr()
        );
        assert!(
            (z.re + sigma).abs() <= 1e-7 * wh2.sqrt(),
            "Re {} vs {}",
            z.re,
            -sigma
        );
    }
    let origin: Vec<_> = poles
        .iter()
        .filter(|z| z.norm() <= 1e-6 * wh2.sqrt())
        .collect();
    assert_eq!(origin.len(), 2, "{poles:?}");
    // The same equations eliminated by hand: with p_L = p_A − p_B,
    // ṗ_L = (2βe/V)·(K_q·x_v − A·ẏ) and M·ÿ = A·p_L − B·ẏ give
    // y/u = Kv·(K_q/A) / (s·(1 + s·B/(M·ω_h²) + s²/ω_h²)).
    for wr in [1.0, 30.0, 300.0, 3000.0] {
        let s = ss_j(wr);
        let one = crate::freq::ss::C64::new(1.0, 0.0);
        let want = kv * kq / area / (s * (one + s * (visc / (mass * wh2)) + s * s / wh2));
        let got = g.response(wr).unwrap();
        assert!(
            (got - want).norm() <= 1e-8 * want.norm(),
            "ω = {wr}: {got} vs {want}"
        );
    }
}

fn ss_j(w: f64) -> crate::freq::ss::C64 {
    crate::freq::ss::C64::new(0.0, w)
}

/// A single rod at rest on a closed-centre valve without leakage: the two
/// directions' operating points by hand. Extending, P→A and B→T meter
/// `A_A·ẏ` and `A_B·ẏ` through the same opening, so `(Ps − p_A) =
/// r·(p_B − Pt)` with r = (A_A/A_B)² (equal lands), and `A_A·p_A − A_B·p_B
/// = M·g` holds the load; retracting, `(Ps − p_B) = (A_B/A_A)²·(p_A − Pt)`.
/// The edges' one-sided gains differ: a kink, whose one-sided ∂ṗ_A/∂u are
/// the turbulent `(βe/V_A)·Cd·w·√(2·Δp/ρ)·Kv` of the edge that opens, and
/// the one-sided difference quotient of the simulator's derivative over a
/// command beyond the laminar region agrees with it.
#[test]
fn single_rod_at_rest_has_two_operating_points() {
    let text = SINGLE_ROD
        .replace("leakage = 1e-13", "leakage = 0.0")
        .replace("[load.friction]", "[unused]")
        .replace("spring = 2e4", "spring = 0.0");
    let text = text.split("[unused]").next().unwrap().to_string();
    let lin = build(&text);
    let c = lin.c().clone();
    let [aa, ab] = c.area;
    let (ps, pt) = (7.6e6, 1e5);
    let force = 500.0 * 9.80665; // M·g·sin 90°, exactly as the model's
    let y0 = 0.142;
    let (xp, up, _) = lin.trim(y0, 0.0, Side::Plus).unwrap();
    let (xm, um, _) = lin.trim(y0, 0.0, Side::Minus).unwrap();
    assert_eq!((up, um), (0.0, 0.0));
    let r = (aa / ab).powi(2);
    let pb = (aa * ps + aa * r * pt - force) / (aa * r + ab);
    let pa = ps - r * (pb - pt);
    assert!(
        (xp[2] - pa).abs() <= 1e-9 * ps && (xp[3] - pb).abs() <= 1e-9 * ps,
        "{xp:?}"
    );
    assert!((aa * xp[2] - ab * xp[3] - force).abs() <= 1e-6 * force);
    let r = (ab / aa).powi(2);
    let pa = (force + ab * ps + ab * r * pt) / (aa + ab * r);
    let pb = ps - r * (pa - pt);
    assert!(
        (xm[2] - pa).abs() <= 1e-9 * ps && (xm[3] - pb).abs() <= 1e-9 * ps,
        "{xm:?}"
    );
    // Each point is an equilibrium of the simulator's derivative.
    for x in [&xp, &xm] {
        let mut dx = [0.0; 4];
        lin.eval(
            &Point {
                x,
                u: 0.0,
                v: crate::plant::Variation::NONE,
            },
            &mut dx,
        );
        assert!(dx[1].abs() < 1e-9 && dx[2] == 0.0 && dx[3] == 0.0, "{dx:?}");
    }
    // The kink and its one-sided gains.
    for (x, side, edge_drop) in [
        (&xp, Side::Plus, ps - xp[2]),
        (&xm, Side::Minus, xm[2] - pt),
    ] {
        let p = Point {
            x,
            u: 0.0,
            v: crate::plant::Variation::NONE,
        };
        let k = lin.kinks(&p);
        assert_eq!(k.len(), 1, "{k:?}");
        assert_eq!(k[0].quantity, "u_plant");
        assert!(!lin.notes(&p).is_empty());
        let [va, _] = c.volumes(y0);
        let want = c.beta / va * c.valve.cdw[0] * (2.0 * edge_drop / 850.0).sqrt() * c.valve.kv;
        let got = lin.jacobian(&p, side).b[(2, 0)];
        assert!((got.abs() - want).abs() <= 1e-12 * want, "{got} vs {want}");
        // The simulator over +-1e-2 V (1 µm of spool, 100 times its laminar
        // region at these drops): the quotient is the turbulent gain to
        // O((p_cr/Δp)²).
        let h = 1e-2 * side.sign();
        let mut d0 = [0.0; 4];
        let mut d1 = [0.0; 4];
        lin.eval(&p, &mut d0);
        lin.eval(&Point { u: h, ..p }, &mut d1);
        let quotient = (d1[2] - d0[2]) / h;
        assert!((quotient - got).abs() <= 1e-3 * want, "{quotient} vs {got}");
    }
}

/// A trim in steady motion by hand: extending at ẏ through a critically
/// centred valve (no leakage, no friction but viscous B), the opening x
/// passes `A_A·ẏ` at `Ps − p_A` and `A_B·ẏ` at `p_B − Pt`, and
/// `A_A·p_A − A_B·p_B = M·g + B·ẏ + K·(y − y_K)`; retracting alike with
/// the other two edges. The laminar region is negligible at these
/// openings (its correction is O((p_cr/Δp)²) < 1e-9).
#[test]
fn trim_in_motion_by_hand() {
    let text = SINGLE_ROD.replace("leakage = 1e-13", "leakage = 0.0");
    let text = text.split("[load.friction]").next().unwrap().to_string();
    let lin = build(&text);
    let c = lin.c().clone();
    let [aa, ab] = c.area;
    let (ps, pt, y0) = (7.6e6, 1e5, 0.15);
    for v0 in [0.03, -0.03] {
        let (x, u, _) = lin.trim(y0, v0, Side::Plus).unwrap();
        let xv = c.valve.kv * u;
        assert!(xv * v0 > 0.0, "the spool opens in the direction of motion");
        let q = |i: usize, dp: f64| c.valve.cdw[i] * xv.abs() * (2.0 * dp / 850.0).sqrt();
        let (qa, qb) = if v0 > 0.0 {
            (q(0, ps - x[2]), q(3, x[3] - pt))
        } else {
            (q(2, x[2] - pt), q(1, ps - x[3]))
        };
        assert!(
            (qa - aa * v0.abs()).abs() <= 1e-7 * qa,
            "{qa} vs {}",
            aa * v0.abs()
        );
        assert!(
            (qb - ab * v0.abs()).abs() <= 1e-7 * qb,
            "{qb} vs {}",
            ab * v0.abs()
        );
        let load = 500.0 * 9.80665 + 2e3 * v0 + 2e4 * (y0 - 0.1);
        assert!((aa * x[2] - ab * x[3] - load).abs() <= 1e-6 * load);
        assert_eq!(x[1], v0);
    }
}

/// Bad trims are refused naming `--trim`: outside the stroke, and a load
/// the supply cannot hold in the asked direction.
#[test]
fn bad_trims_are_refused() {
    let lin = build(SINGLE_ROD);
    let e = lin.trim(0.3, 0.0, Side::Plus).unwrap_err();
    assert_eq!(e.key, "--trim");
    assert!(
        e.reason.to_string().contains("outside its stroke"),
        "{}",
        e.reason
    );
    // A load the supply cannot hold (the file's own is checked when it is
    // built: here a mass factor of `[uncertainty.physical]` makes it 100
    // times heavier).
    let heavy = CylinderLin::new(
        lin.plant.clone(),
        Factors {
            mass: 100.0,
            ..Factors::ONE
        },
        0.0,
    );
    let e = heavy.trim(0.1, 0.0, Side::Plus).unwrap_err();
    assert_eq!(e.key, "--trim");
    assert!(
        e.reason.to_string().contains("no trim point"),
        "{}",
        e.reason
    );
}
