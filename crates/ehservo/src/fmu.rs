//! `ehservo fmu`: a scenario's controller (or its whole closed loop, or its
//! plant with its actuator) as an FMI 3.0 co-simulation FMU.
//!
//! The FMU is a zip holding `modelDescription.xml` (written here),
//! `binaries/x86_64-linux/ehservo.so` (the `ehservo-ffi` cdylib, whose
//! `fmi3*` functions are the FMI entry points) and
//! `resources/scenario.toml` (the scenario with every default filled in and
//! the `--set` overrides applied: what the FMU builds its controller from).
//! The instantiation token names the kind of FMU and a hash of that file,
//! so the binary knows which FMU it is and refuses resources that are not
//! the ones it was exported with.
//!
//! The variables, their value references and units are the tables below
//! ([`variables`]); the binary serves the same tables. Angles are in rad
//! (SI, as everywhere in the C ABI); `e_deg` and `e_max_deg` are in degrees
//! as `summary.json` gives them. On a linear axis ([`variables_on`]) the
//! position is `y` in m and the error's display `e_mm` and metric `e_max`
//! are in mm, at the same value references.

use crate::scenario::{Loop, ReferenceKind};
use crate::simulation::Mode;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;

pub use ehservo_scenario::fmi::*;

/// The scenario as the FMU's `resources/scenario.toml`: every default
/// filled in, the overrides applied. Refuses what the FMU could not
/// rebuild from that file alone.
pub fn resource_toml(lp: &Loop, kind: FmuKind) -> Result<String> {
    let s = lp.scenario();
    if s.reference.kind == ReferenceKind::Csv {
        crate::bad_input!(
            "`reference.kind` = \"csv\": an FMU carries only its scenario.toml, not the reference's table; use another kind of reference"
        );
    }
    if kind == FmuKind::Controller && s.simulation.mode != Mode::Sampled {
        crate::bad_input!(
            "`simulation.mode` = \"continuous\": a controller FMU is the sampled controller; set simulation.mode = \"sampled\" (or export --closed-loop)"
        );
    }
    if s.plant.steps_itself() {
        crate::bad_input!(
            "`plant.model` = \"{}\": the FMU's binary cannot load another FMU as its plant; export a scenario with one of ehservo's own plants",
            s.plant.model()
        );
    }
    if kind == FmuKind::Plant && s.simulation.solver != crate::simulation::SolverKind::Rk4 {
        crate::bad_input!(
            "`simulation.solver` = \"{}\": the plant FMU integrates each communication step with rk4 sub-steps; set simulation.solver = \"rk4\" (or export --closed-loop)",
            s.simulation.solver.as_str()
        );
    }
    let text = s.to_toml();
    // The FMU rebuilds its controller from this text: check that it does,
    // to the same scenario, before shipping it.
    let back = Loop::parse(&text)
        .map_err(|e| anyhow::anyhow!("the filled-in scenario does not parse back: {e}"))?;
    let mut expected = s.clone();
    expected.base_dir = None;
    if back.scenario().resolved_table() != expected.resolved_table() {
        anyhow::bail!("the filled-in scenario does not read back as the same scenario");
    }
    Ok(text)
}

/// `modelDescription.xml`.
pub fn model_description(kind: FmuKind, lp: &Loop, scenario_toml: &str) -> String {
    let s = lp.scenario();
    let cfg = lp.sim();
    let horizon = cfg.steps as f64 * cfg.step;
    let what = match kind {
        FmuKind::Controller => format!(
            "The {} controller of scenario {:?}, sampled every {} s (inputs {}; output u in V)",
            s.controller.kind(),
            s.name,
            cfg.step,
            match lp.axis() {
                crate::axis::Axis::Rotary => "theta, theta_dot, theta_ddot in rad, rad/s, rad/s2",
                crate::axis::Axis::Linear => "y, y_dot, y_ddot in m, m/s, m/s2",
                crate::axis::Axis::Force => "f, y_dot, y_ddot in N, m/s, m/s2",
                crate::axis::Axis::Pressure => "p_l, y_dot, y_ddot in Pa, m/s, m/s2",
            }
        ),
        FmuKind::ClosedLoop => format!(
            "The closed loop of scenario {:?} ({} controller, {} plant), sampled every {} s, horizon {} s",
            s.name,
            s.controller.kind(),
            s.plant.model(),
            cfg.step,
            horizon
        ),
        FmuKind::Plant => format!(
            "The {} plant of scenario {:?} with its actuator (input u in V, held over each step of {} s; {} RK4 sub-steps a step)",
            s.plant.model(),
            s.name,
            cfg.step,
            cfg.substeps.max(1)
        ),
    };
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    x.push_str(&format!(
        "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"{}\" instantiationToken=\"{}\" description=\"{}\" generationTool=\"ehservo {}\" variableNamingConvention=\"flat\">\n",
        crate::output::escape::html(&format!("ehservo-{}-{}", s.name, kind.as_str())),
        token(kind, scenario_toml),
        crate::output::escape::html(&what),
        env!("CARGO_PKG_VERSION"),
    ));
    x.push_str(&format!(
        "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" fixedInternalStepSize=\"{:?}\" canGetAndSetFMUState=\"false\" canSerializeFMUState=\"false\" hasEventMode=\"false\"/>\n",
        cfg.step
    ));
    x.push_str(concat!(
        "  <UnitDefinitions>\n",
        "    <Unit name=\"s\"><BaseUnit s=\"1\"/></Unit>\n",
        "    <Unit name=\"rad\"><BaseUnit rad=\"1\"/></Unit>\n",
        "    <Unit name=\"rad/s\"><BaseUnit s=\"-1\" rad=\"1\"/></Unit>\n",
        "    <Unit name=\"rad/s2\"><BaseUnit s=\"-2\" rad=\"1\"/></Unit>\n",
        "    <Unit name=\"deg\"><BaseUnit rad=\"1\" factor=\"0.017453292519943295\"/></Unit>\n",
        "    <Unit name=\"m\"><BaseUnit m=\"1\"/></Unit>\n",
        "    <Unit name=\"m/s\"><BaseUnit m=\"1\" s=\"-1\"/></Unit>\n",
        "    <Unit name=\"m/s2\"><BaseUnit m=\"1\" s=\"-2\"/></Unit>\n",
        "    <Unit name=\"mm\"><BaseUnit m=\"1\" factor=\"0.001\"/></Unit>\n",
        "    <Unit name=\"V\"><BaseUnit kg=\"1\" m=\"2\" s=\"-3\" A=\"-1\"/></Unit>\n",
        "    <Unit name=\"N\"><BaseUnit kg=\"1\" m=\"1\" s=\"-2\"/></Unit>\n",
        "    <Unit name=\"N.m\"><BaseUnit kg=\"1\" m=\"2\" s=\"-2\"/></Unit>\n",
        "    <Unit name=\"Pa\"><BaseUnit kg=\"1\" m=\"-1\" s=\"-2\"/><DisplayUnit name=\"bar\" factor=\"1e-05\"/></Unit>\n",
        "  </UnitDefinitions>\n",
        "  <LogCategories>\n",
        "    <Category name=\"logStatusError\" description=\"Errors: bad calls, bad values\"/>\n",
        "    <Category name=\"logStatusWarning\" description=\"Warnings: the run diverged\"/>\n",
        "  </LogCategories>\n",
    ));
    x.push_str(&format!(
        "  <DefaultExperiment startTime=\"0\" stopTime=\"{horizon:?}\" stepSize=\"{:?}\"/>\n",
        cfg.step
    ));
    x.push_str("  <ModelVariables>\n");
    let vars = match kind {
        FmuKind::Plant => {
            let p = crate::stepper::PlantStepper::new(lp);
            plant_variables(p.axis(), p.states(), p.takes_external_load())
        }
        _ => variables_on(kind, lp.axis()),
    };
    for v in &vars {
        let (causality, rest) = match v.causality {
            Causality::Independent => ("independent", String::new()),
            Causality::Input => ("input", " start=\"0\"".to_string()),
            Causality::Output => ("output", String::new()),
        };
        let variability = if v.vr == vr::U && kind != FmuKind::Plant {
            "discrete"
        } else {
            "continuous"
        };
        let display = if v.unit == "Pa" {
            " displayUnit=\"bar\""
        } else {
            ""
        };
        x.push_str(&format!(
            "    <Float64 name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{causality}\" variability=\"{variability}\" unit=\"{}\"{display}{rest}/>\n",
            v.name,
            v.vr,
            crate::output::escape::html(v.description),
            v.unit
        ));
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    for tag in ["Output", "InitialUnknown"] {
        for v in vars.iter().filter(|v| v.causality == Causality::Output) {
            let on = direct_inputs(kind, v.vr, &vars);
            let deps = on.join(" ");
            let kinds = if on.is_empty() {
                String::new()
            } else {
                format!(
                    " dependenciesKind=\"{}\"",
                    vec!["dependent"; on.len()].join(" ")
                )
            };
            x.push_str(&format!(
                "    <{tag} valueReference=\"{}\" dependencies=\"{deps}\"{kinds}/>\n",
                v.vr
            ));
        }
    }
    x.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    x
}

/// The inputs an output depends on directly (its value at a time changes
/// when they are set): the controller's u on its measurements (the law at
/// the current sample); the plant's u_plant on u (through the actuator)
/// and its acceleration on the external load (the force balance); nothing
/// else on any input.
fn direct_inputs(kind: FmuKind, output: u32, vars: &[Variable]) -> Vec<String> {
    let inputs = vars.iter().filter(|v| v.causality == Causality::Input);
    let on: Vec<u32> = match (kind, output) {
        (FmuKind::Controller, vr::U) => inputs.map(|v| v.vr).collect(),
        (FmuKind::Plant, vr::U_PLANT) => vec![vr::U],
        (FmuKind::Plant, vr::THETA_DDOT) => {
            inputs.map(|v| v.vr).filter(|r| *r == vr::F_LOAD).collect()
        }
        _ => Vec::new(),
    };
    on.iter().map(u32::to_string).collect()
}

/// Where `ehservo fmu` looks for the FMU's binary when `--binary` is not
/// given: `libehservo_ffi.so` beside the running `ehservo` (both are in
/// `target/<profile>/` after `cargo build -p ehservo -p ehservo-ffi`).
pub fn default_binary() -> Option<std::path::PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?;
    // `target/debug/deps/ehservo-…` when run by `cargo test`.
    [dir.to_path_buf(), dir.parent()?.to_path_buf()]
        .into_iter()
        .map(|d| d.join("libehservo_ffi.so"))
        .find(|p| p.is_file())
}

/// Writes the FMU of `s` to `out` (a temporary sibling renamed into place).
pub fn write_fmu(out: &Path, kind: FmuKind, lp: &Loop, binary: &Path) -> Result<()> {
    // The destination and the binary first: no work is done for an FMU
    // that could not be written.
    let dir = check_out(out)?;
    let so = read_binary(binary)?;
    let toml_text = resource_toml(lp, kind)?;
    let xml = model_description(kind, lp, &toml_text);
    let tmp = tempfile_in(&dir, out)?;
    // On SIGINT/SIGTERM the handler removes it (crate::interrupt).
    let _listed = crate::interrupt::TempFile::register(tmp.clone());
    let result = (|| -> Result<()> {
        let f =
            std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        let mut zip = zip::ZipWriter::new(std::io::BufWriter::new(f));
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        zip.start_file("modelDescription.xml", opts)?;
        zip.write_all(xml.as_bytes())?;
        zip.start_file("resources/scenario.toml", opts)?;
        zip.write_all(toml_text.as_bytes())?;
        zip.start_file(
            format!("binaries/{PLATFORM}/{MODEL_IDENTIFIER}.so"),
            opts.unix_permissions(0o755),
        )?;
        zip.write_all(&so)?;
        let w = zip.finish()?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        Ok(())
    })();
    let result = result
        .map_err(|e| e.context(format!("writing {}", out.display())))
        .and_then(|()| {
            std::fs::rename(&tmp, out)
                .with_context(|| format!("renaming {} to {}", tmp.display(), out.display()))
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Largest FMU binary read: 1 GiB (libehservo_ffi.so is some tens of MB).
pub const MAX_BINARY_BYTES: u64 = 1 << 30;

/// `--out` of an FMU, checked before any work: not a directory or another
/// non-file, in a folder that exists. Returns that folder.
pub fn check_out(out: &Path) -> Result<std::path::PathBuf> {
    let dir = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    match std::fs::metadata(out) {
        Ok(m) if m.is_dir() => crate::bad_input!(
            "--out {}: is a directory: name the .fmu file to write",
            out.display()
        ),
        Ok(m) if !m.is_file() => crate::bad_input!(
            "--out {}: exists and is not a regular file: refusing to replace it",
            out.display()
        ),
        _ => {}
    }
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => Ok(dir),
        Ok(_) => crate::bad_input!(
            "--out {}: {} is not a directory",
            out.display(),
            dir.display()
        ),
        Err(e) => crate::bad_input!(
            "--out {}: the folder {} cannot be used: {e}",
            out.display(),
            dir.display()
        ),
    }
}

/// The FMU's binary: a regular file of at most [`MAX_BINARY_BYTES`],
/// starting as an ELF file does (a device or a directory is refused before
/// it is read).
fn read_binary(binary: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let bad = |why: String| -> Result<Vec<u8>> {
        crate::bad_input!("--binary {}: {why}", binary.display())
    };
    let meta = match std::fs::metadata(binary) {
        Ok(m) => m,
        Err(e) => return bad(format!("cannot be read: {e}")),
    };
    if !meta.is_file() {
        return bad("is not a regular file (the FMU's binary is libehservo_ffi.so)".into());
    }
    if meta.len() > MAX_BINARY_BYTES {
        return bad(format!(
            "is {} bytes; the FMU's binary is at most {MAX_BINARY_BYTES} bytes",
            meta.len()
        ));
    }
    let mut so = Vec::new();
    std::fs::File::open(binary)
        .and_then(|f| f.take(MAX_BINARY_BYTES + 1).read_to_end(&mut so))
        .with_context(|| format!("reading the FMU's binary {}", binary.display()))?;
    if so.len() as u64 > MAX_BINARY_BYTES {
        return bad(format!("is larger than {MAX_BINARY_BYTES} bytes"));
    }
    if !so.starts_with(b"\x7fELF") {
        return bad("not an ELF shared library (the FMU's binary is libehservo_ffi.so)".into());
    }
    Ok(so)
}

/// A fresh temporary file name beside `out`.
fn tempfile_in(dir: &Path, out: &Path) -> Result<std::path::PathBuf> {
    let stem = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "fmu".into());
    let p = dir.join(format!(".{stem}.tmp-{}", std::process::id()));
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_name_the_kind_and_the_exact_scenario_text() {
        let t = token(FmuKind::Controller, "name = \"a\"\n");
        assert!(
            t.starts_with("{ehservo-controller-") && t.ends_with('}'),
            "{t}"
        );
        assert_eq!(check_token(&t, "name = \"a\"\n"), Ok(FmuKind::Controller));
        assert!(check_token(&t, "name = \"b\"\n").is_err());
        let c = token(FmuKind::ClosedLoop, "x");
        assert_eq!(check_token(&c, "x"), Ok(FmuKind::ClosedLoop));
    }

    #[test]
    fn the_model_description_lists_every_variable_once_with_its_unit() {
        let s = Loop::parse("name = \"fig2\"").unwrap();
        let toml_text = resource_toml(&s, FmuKind::Controller).unwrap();
        let x = model_description(FmuKind::Controller, &s, &toml_text);
        for v in variables(FmuKind::Controller) {
            let tag = format!("name=\"{}\" valueReference=\"{}\"", v.name, v.vr);
            assert_eq!(x.matches(&tag).count(), 1, "{tag}");
        }
        assert!(x.contains("<Output valueReference=\"4\" dependencies=\"1 2 3\""));
        assert!(x.contains("stopTime=\"10.0\" stepSize=\"0.01\""));
        assert!(x.contains(&token(FmuKind::Controller, &toml_text)));
    }

    #[test]
    fn a_plant_fmu_declares_its_inputs_outputs_and_units_by_plant() {
        // The cylinder: u and the load force in, y in m, pressures in Pa
        // shown in bar; the acceleration depends on the force directly.
        let cyl = Loop::load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../scenarios/cylinders/slide.toml"),
            &[],
        )
        .unwrap();
        let text = resource_toml(&cyl, FmuKind::Plant).unwrap();
        let x = model_description(FmuKind::Plant, &cyl, &text);
        for tag in [
            "name=\"u\" valueReference=\"4\"",
            "name=\"f_load\" valueReference=\"10\"",
            "name=\"y\" valueReference=\"1\"",
            "name=\"p_a\" valueReference=\"16\"",
            "name=\"p_b\" valueReference=\"17\"",
        ] {
            assert_eq!(x.matches(tag).count(), 1, "{tag}");
        }
        assert!(x.contains("causality=\"input\" variability=\"continuous\" unit=\"N\""));
        assert!(x.contains("unit=\"Pa\" displayUnit=\"bar\""));
        assert!(x.contains("<DisplayUnit name=\"bar\" factor=\"1e-05\"/>"));
        assert!(x.contains("<Output valueReference=\"3\" dependencies=\"10\""));
        assert!(x.contains("<Output valueReference=\"9\" dependencies=\"4\""));
        assert!(!x.contains("name=\"theta"), "no angle on a linear axis");
        assert!(x.contains(&token(FmuKind::Plant, &text)));
        assert_eq!(
            check_token(&token(FmuKind::Plant, &text), &text),
            Ok(FmuKind::Plant)
        );
        // The paper's servo: theta in rad, its load pressure, no load input.
        let s = Loop::parse("name = \"fig2\"").unwrap();
        let text = resource_toml(&s, FmuKind::Plant).unwrap();
        let x = model_description(FmuKind::Plant, &s, &text);
        assert!(x.contains("name=\"theta\" valueReference=\"1\""));
        assert!(x.contains("name=\"p_load\" valueReference=\"16\""));
        assert!(!x.contains("f_load"));
        assert!(x.contains("<Output valueReference=\"3\" dependencies=\"\"/>"));
    }

    #[test]
    fn what_an_fmu_cannot_carry_is_refused() {
        let s = Loop::parse("[simulation]\nmode = \"continuous\"\n").unwrap();
        let e = resource_toml(&s, FmuKind::Controller).unwrap_err();
        assert!(e.to_string().contains("`simulation.mode`"), "{e}");
        assert!(resource_toml(&s, FmuKind::ClosedLoop).is_ok());
    }
}
