//! The cylinder plant family from scenario files: keys, their checks, the
//! nominal model it hands the controller, and the shipped scenarios.

use ehservo::cylinder::CylinderPlant;
use ehservo::plant::Plant;
use ehservo::run::{run, Keep};
use ehservo::scenario::{PlantModel, Scenario};
use ehservo_core::cylinder::CylinderParams;
use std::path::Path;

fn err(text: &str) -> (String, String) {
    let e = Scenario::parse_with(text, "bad.toml", &[]).unwrap_err();
    (e.key, e.reason)
}

#[test]
fn a_bare_cylinder_scenario_uses_the_typical_set() {
    let s = Scenario::parse("[plant]\nmodel = \"cylinder\"\n").unwrap();
    assert_eq!(s.plant.model, PlantModel::Cylinder);
    let c = CylinderParams::typical();
    assert_eq!(s.cylinder(), c);
    // The controller's nominal model is the cylinder's equivalent.
    assert_eq!(s.servo(), c.nominal_servo_params());
    let setup = s.setup().unwrap();
    assert_eq!(setup.model.params, c.nominal_servo_params());
    assert_eq!(*CylinderPlant::new(c, s.load).nominal(), setup.model);
    // The run diverges at the end of the stroke.
    assert_eq!(setup.sim.theta_limit.to_bits(), c.stroke_angle().to_bits());
    // Round trip through TOML.
    assert_eq!(Scenario::parse(&s.to_toml()).unwrap(), s);
}

#[test]
fn cylinder_keys_are_checked_with_their_path() {
    let cyl = "[plant]\nmodel = \"cylinder\"\n[plant.cylinder]\n";
    let (k, r) = err(&format!("{cyl}A = -1e-4\n"));
    assert_eq!(k, "plant.cylinder.A");
    assert!(r.contains("> 0"), "{r}");
    let (k, r) = err(&format!("{cyl}V0 = 2e-5\n"));
    assert_eq!(k, "plant.cylinder.V0");
    assert!(r.contains("A·stroke/2"), "{r}");
    let (k, r) = err(&format!("{cyl}Area = 1e-4\n"));
    assert_eq!(k, "plant.cylinder.Area");
    assert!(r.contains("unknown field"), "{r}");
    let (k, _) = err(&format!(
        "{cyl}[plant.cylinder.friction]\nsmoothing = 0.0\n"
    ));
    assert_eq!(k, "plant.cylinder.friction.smoothing");
    // ±50 mm on r = 0.1 m is ±28.6°: a 30° reference leaves the stroke.
    let (k, r) = err(&format!("{cyl}[reference]\namplitude_deg = 30.0\n"));
    assert_eq!(k, "reference.amplitude_deg");
    assert!(r.contains("stroke"), "{r}");
    let (k, r) = err(&format!("{cyl}r = 1.0\n"));
    assert_eq!(
        k, "reference.amplitude_deg",
        "{r}: on r = 1 m the stroke is ±2.9°"
    );
    let (k, _) = err("[plant]\nmodel = \"cylinder\"\n[simulation]\nx0 = [0.6, 0.0, 0.0]\n");
    assert_eq!(k, "simulation.x0");
}

#[test]
fn cylinder_and_paper_params_do_not_mix() {
    let (k, r) = err("[plant]\nmodel = \"cylinder\"\n[plant.params]\nJt = 0.1\n");
    assert_eq!(k, "plant.params");
    assert!(r.contains("[plant.cylinder]"), "{r}");
    let (k, r) = err("[plant]\nmodel = \"physical\"\n[plant.cylinder]\nM = 10.0\n");
    assert_eq!(k, "plant.cylinder");
    assert!(r.contains("plant.model"), "{r}");
}

/// The shipped scenarios run, bounded, with the errors the notes report
/// (docs/cylinder.md): NNBVSC with the paper's gains tracks to a few
/// tenths of a degree, the hand-tuned PID to a few hundredths.
#[test]
fn shipped_cylinder_scenarios_run_bounded() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/realistic");
    for (file, bound) in [("cylinder.toml", 0.35), ("cylinder-pid.toml", 0.06)] {
        let s = Scenario::load(&dir.join(file), &[]).unwrap();
        assert_eq!(s.plant.model, PlantModel::Cylinder);
        let r = run(&s, Keep::Nothing).unwrap();
        assert!(r.outcome.diverged.is_none(), "{file} diverged");
        let e = r.metrics.e_max_deg.expect("a settled window");
        assert!(e < bound, "{file}: e_max {e}°");
    }
}
