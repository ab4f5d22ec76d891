//! The plant FMU through its `fmi3*` entry points, called as an importer
//! calls them: against `ehservo run` of the same scenario, and against the
//! valve's flow equation solved by hand.
#![allow(clippy::float_cmp)] // bit-identical results are the point

use super::*;
use ehservo_scenario::fmi::{token, vr};
use ehservo_scenario::run::{run, Keep};
use std::ptr::null_mut;

/// A plant FMU instance of `scenario` (its text as `resources/scenario.toml`).
struct PlantFmu {
    p: *mut c_void,
    _dir: tempfile::TempDir,
}

impl PlantFmu {
    fn new(scenario: &str) -> Self {
        // The scenario's own error first, clearer than a null instance.
        if let Err(e) = Loop::parse(scenario) {
            panic!("{e}");
        }
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scenario.toml"), scenario).unwrap();
        let tok = CString::new(token(FmuKind::Plant, scenario)).unwrap();
        let res = CString::new(dir.path().to_str().unwrap()).unwrap();
        // SAFETY: valid NUL-terminated strings; no callbacks.
        let p = unsafe {
            fmi3InstantiateCoSimulation(
                c"plant".as_ptr(),
                tok.as_ptr(),
                res.as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                null_mut(),
                None,
                std::ptr::null(),
            )
        };
        assert!(!p.is_null(), "instantiation failed");
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(
                fmi3EnterInitializationMode(p, false, 0.0, 0.0, false, 0.0),
                OK
            );
            assert_eq!(fmi3ExitInitializationMode(p), OK);
        }
        Self { p, _dir: dir }
    }

    fn set(&self, r: u32, v: f64) -> Status {
        // SAFETY: one value for one reference.
        unsafe { fmi3SetFloat64(self.p, &r, 1, &v, 1) }
    }

    fn get(&self, r: u32) -> f64 {
        let mut v = f64::NAN;
        // SAFETY: as above.
        assert_eq!(unsafe { fmi3GetFloat64(self.p, &r, 1, &mut v, 1) }, OK);
        v
    }

    fn x(&self) -> [f64; 3] {
        [vr::THETA, vr::THETA_DOT, vr::THETA_DDOT].map(|r| self.get(r))
    }

    fn step(&self, t: f64, h: f64) -> Status {
        let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
        // SAFETY: writable outputs.
        unsafe {
            fmi3DoStep(
                self.p, t, h, true, &mut ev, &mut term, &mut early, &mut last,
            )
        }
    }
}

impl Drop for PlantFmu {
    fn drop(&mut self) {
        // SAFETY: freed once.
        unsafe { fmi3FreeInstance(self.p) }
    }
}

fn read(rel: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    std::fs::read_to_string(p).unwrap()
}

/// Fed the commands of `ehservo run`, the plant FMU gives the run's x at
/// every sample, to the bit (the same held-command integration): the
/// paper's third-order servo, the physical one, and the slide's cylinder
/// with its 80 Hz spool and 10 RK4 sub-steps a sample.
#[test]
fn the_plant_fed_a_runs_commands_gives_the_runs_trace() {
    let fig2 = read("scenarios/paper/fig2.toml").replace("horizon = 10.0", "horizon = 2.0");
    let physical = format!("{fig2}\n[plant]\nmodel = \"physical\"\n");
    let slide = read("scenarios/cylinders/slide.toml").replace("horizon = 2.0", "horizon = 0.4");
    for text in [fig2, physical, slide] {
        let lp = Loop::parse(&text).unwrap();
        let r = run(&lp, Keep::Every(1));
        assert!(!r.metrics.diverged && r.trace.len() > 100);
        let fmu = PlantFmu::new(&text);
        let h = lp.sim().step;
        let mut worst: f64 = 0.0;
        for (k, smp) in r.trace.iter().enumerate() {
            assert_eq!(fmu.get(vr::TIME), smp.t, "k = {k}");
            assert_eq!(fmu.x(), smp.x, "{}: k = {k}", lp.scenario().name);
            worst = worst.max((fmu.get(vr::THETA) - smp.x[0]).abs());
            assert_eq!(fmu.set(vr::U, smp.u), OK);
            assert_eq!(fmu.get(vr::U_PLANT), smp.u_plant, "k = {k}");
            if k + 1 < r.trace.len() {
                assert_eq!(fmu.step(smp.t, h), OK, "k = {k}");
            }
        }
        assert_eq!(worst, 0.0);
    }
}

/// A cylinder as `scenarios/cylinders/slide.toml`'s, with no spool
/// dynamics (no `[actuator]`: the valve takes u as it is), at y(0) = `y0`,
/// with the seals' viscous friction `viscous` (N·s/m).
fn cylinder(y0: f64, viscous: f64) -> String {
    format!(
        r#"name = "cylinder-physics"
[simulation]
horizon = 4.0
step = 1e-3
substeps = 10
x0 = [{y0:?}, 0.0, 0.0]
[plant]
model = "cylinder"
[plant.cylinder]
bore = 0.063
rod_diameter = 0.045
stroke = 0.4
dead_volume_a = 1.571e-4
dead_volume_b = 1.571e-4
viscous = {viscous:?}
leakage = 0.0
[plant.fluid]
density = 870.0
bulk_modulus = 8e8
[plant.valve]
rated_flow = 1.6666666666666667e-3
rated_drop = 7e6
spool_limit = 1e-3
rated_signal = 10.0
lap = 0.0
[plant.supply]
kind = "fixed"
pressure = 2.1e7
tank_pressure = 0.0
[plant.load]
mass = 1200.0
incline_deg = 0.0
[reference]
kind = "step"
offset_mm = 180.0
amplitude_mm = 20.0
prefilter_tau = 0.02
[controller]
kind = "state-feedback"
"#
    )
}

/// Runs the plant FMU with `u` and `f_load` held for `seconds`, 1 ms a
/// step; the outputs at the end.
fn hold(fmu: &PlantFmu, u: f64, f_load: f64, seconds: f64) -> [f64; 3] {
    assert_eq!(fmu.set(vr::U, u), OK);
    assert_eq!(fmu.set(vr::F_LOAD, f_load), OK);
    let n = (seconds / 1e-3).round() as u64;
    let t0 = fmu.get(vr::TIME);
    for k in 0..n {
        assert_eq!(fmu.step(t0 + k as f64 * 1e-3, 1e-3), OK, "k = {k}");
    }
    fmu.x()
}

/// Under a constant command, with no load, the rod extends at the speed
/// the valve's flow equation gives, solved by hand:
///
/// A land's turbulent flow is q = Cd·w·x_v·√(2Δp/ρ), and the rated flow
/// fixes Cd·w = Q_n/(x_max·√(Δp_n/ρ)) (docs/cylinder.md, the valve's
/// module doc): q = K·√Δp with K = Q_n·(u/u_rated)·√(2/Δp_n). At u = 1 V of
/// 10: K = (1/600 m³/s)·0.1·√(2/7e6 Pa) = 1.6667e-4·5.3452e-4
/// = 8.9087e-8 m³/(s·√Pa).
///
/// In steady extension at speed v (chambers no longer compressing, tank at
/// 0): P→A passes A_A·v = K·√(Ps − p_A), B→T passes A_B·v = K·√p_B, so
/// p_A = Ps − (A_A·v/K)², p_B = (A_B·v/K)²; the rod's force balance with
/// no load and the seals' viscous B is p_A·A_A − p_B·A_B = B·v, i.e.
/// c·v² + B·v − Ps·A_A = 0 with c = (A_A³ + A_B³)/K², whose positive root
/// is v = (−B + √(B² + 4·c·Ps·A_A))/(2c). With A_A = π/4·0.063²
/// = 3.1172e-3 m², A_B = A_A − π/4·0.045² = 1.5268e-3 m², Ps = 21 MPa,
/// B = 2000 N·s/m: c = (3.0290e-8 + 3.5590e-9)/7.9365e-15 = 4.2650e6,
/// Ps·A_A = 65 461 N, v = (−2000 + √(4e6 + 1.1168e12))/8.5300e6
/// = 0.12366 m/s (0.12389 m/s without the seals).
#[test]
fn a_constant_command_extends_the_rod_at_the_valves_steady_speed() {
    let (qn, dpn, u_ratio, ps, rho_b) = (1.0 / 600.0, 7e6_f64, 0.1, 2.1e7, 2000.0);
    let area_a = std::f64::consts::FRAC_PI_4 * 0.063 * 0.063;
    let area_b = area_a - std::f64::consts::FRAC_PI_4 * 0.045 * 0.045;
    let k = qn * u_ratio * (2.0 / dpn).sqrt();
    let c = (area_a.powi(3) + area_b.powi(3)) / (k * k);
    let v = (-rho_b + (rho_b * rho_b + 4.0 * c * ps * area_a).sqrt()) / (2.0 * c);
    assert!((v - 0.12366).abs() < 1e-4, "the hand figure: {v}");
    let fmu = PlantFmu::new(&cylinder(0.02, rho_b));
    // 1.5 s from y = 20 mm: about 0.2 m of the 0.4 m stroke.
    let x = hold(&fmu, 1.0, 0.0, 1.5);
    assert!(
        (x[1] - v).abs() < 1e-5 * v && x[2].abs() < 1e-3,
        "ẏ = {} m/s, ÿ = {} m/s², the flow equation's v = {v} m/s",
        x[1],
        x[2]
    );
    // The chamber pressures are the ones the flows need.
    let (pa, pb) = (fmu.get(vr::PRESSURE), fmu.get(vr::PRESSURE + 1));
    let (pa_hand, pb_hand) = (ps - (area_a * v / k).powi(2), (area_b * v / k).powi(2));
    assert!(
        (pa - pa_hand).abs() < 1e-4 * pa_hand,
        "p_A {pa} vs {pa_hand}"
    );
    assert!(
        (pb - pb_hand).abs() < 1e-4 * pb_hand,
        "p_B {pb} vs {pb_hand}"
    );
}

/// A closed, critically centred valve (u = 0) with no leakage traps the
/// oil: the rod holds its position; an external force then compresses the
/// oil columns by F/k_h, k_h = βe·(A_A²/V_A + A_B²/V_B) (the columns'
/// stiffness, linear for F·/A ≪ βe). At mid-stroke y = 0.2 m: V_A
/// = 1.571e-4 + 3.1172e-3·0.2 = 7.8055e-4 m³, V_B = 1.571e-4 + 1.5268e-3·0.2
/// = 4.6246e-4 m³, k_h = 8e8·(1.24489e-2 + 5.0407e-3) = 1.39917e7 N/m: a
/// force of 1 kN opposing extension moves the rod by −71.47 µm.
#[test]
fn a_closed_valve_holds_the_rod_and_the_oil_column_takes_the_load() {
    // Damped well (ζ ≈ 0.5 of the column's 108 rad/s) so it settles.
    let fmu = PlantFmu::new(&cylinder(0.2, 1.3e5));
    let x = hold(&fmu, 0.0, 0.0, 1.0);
    assert!((x[0] - 0.2).abs() < 1e-9 && x[1].abs() < 1e-9, "{x:?}");
    let area_a = std::f64::consts::FRAC_PI_4 * 0.063 * 0.063;
    let area_b = area_a - std::f64::consts::FRAC_PI_4 * 0.045 * 0.045;
    let (va, vb) = (1.571e-4 + area_a * 0.2, 1.571e-4 + area_b * 0.2);
    let kh = 8e8 * (area_a * area_a / va + area_b * area_b / vb);
    assert!((kh - 1.39917e7).abs() < 1e-4 * kh, "the hand figure: {kh}");
    let x = hold(&fmu, 0.0, 1000.0, 2.0);
    let dy = x[0] - 0.2;
    assert!(
        (dy + 1000.0 / kh).abs() < 1e-3 * 1000.0 / kh,
        "Δy = {dy} m, −F/k_h = {} m",
        -1000.0 / kh
    );
}

/// A step that is not whole sample periods is refused (fmi3Error) and
/// leaves the plant where it was; a plant without an external load input
/// (the paper's servo) refuses `f_load`, and a non-finite u is refused.
#[test]
fn what_the_plant_cannot_do_is_refused_and_changes_nothing() {
    let fmu = PlantFmu::new(&cylinder(0.2, 2000.0));
    assert_eq!(fmu.set(vr::U, 1.0), OK);
    let x0 = fmu.x();
    assert_eq!(fmu.step(0.0, 1.5e-3), ERROR);
    assert_eq!((fmu.get(vr::TIME), fmu.x()), (0.0, x0));
    assert_eq!(fmu.set(vr::U, f64::NAN), ERROR);
    assert_eq!(fmu.get(vr::U), 1.0);
    // Two periods at once: the same as two steps of one.
    let other = PlantFmu::new(&cylinder(0.2, 2000.0));
    assert_eq!(other.set(vr::U, 1.0), OK);
    assert_eq!(fmu.step(0.0, 2e-3), OK);
    assert_eq!((other.step(0.0, 1e-3), other.step(1e-3, 1e-3)), (OK, OK));
    assert_eq!(fmu.x(), other.x());
    assert!(fmu.x()[1] > 0.0);
    let fig2 = PlantFmu::new(&read("scenarios/paper/fig2.toml"));
    assert_eq!(fig2.set(vr::F_LOAD, 1.0), ERROR);
}
