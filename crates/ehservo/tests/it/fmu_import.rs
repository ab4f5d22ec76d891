//! `[plant] model = "fmu"`: a plant exported by `ehservo fmu --plant` and
//! imported back runs as the native plant does, to the bit, under `run` and
//! under `sweep` on any number of threads; what is wrong with an FMU or its
//! mapping is refused with exit 2 and one line naming the file, the key and
//! the reason; an FMU that fails during a run ends that run as a result.
//!
//! The FMU's binary is the `ehservo-ffi` cdylib beside the `ehservo` these
//! tests built (`cargo build -p ehservo-ffi`); without it the tests that
//! need it print a SKIPPED line, as `.ci/run` does for a missing tool.

use crate::common::{ehservo, rejected, succeeded};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The native scenario: a PID on the paper's third-order servo with its
/// load, 4 RK4 sub-steps a 1 ms sample.
const NATIVE: &str = r#"
name = "rt-native"
[simulation]
horizon = 1.0
step = 0.001
substeps = 4
[controller]
kind = "pid"
design_pole = 30.0
design_damping = 0.7
[load]
amplitude = 2.0
wavenumber = 4.0
"#;

/// The same loop with the plant read from `plant.fmu`.
fn imported(extra: &str) -> String {
    format!(
        r#"{}
[plant]
model = "fmu"
path = "plant.fmu"
command = "u"
position = "theta"
velocity = "theta_dot"
acceleration = "theta_ddot"
{extra}
"#,
        NATIVE.replace("rt-native", "rt-imported")
    )
}

/// `ehservo fmu --plant` of `scenario` into `dir/plant.fmu`; `None` (and a
/// SKIPPED line) when the FMU's binary was not built.
fn export(dir: &Path, scenario: &str) -> Option<PathBuf> {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_ehservo"));
    if !bin.with_file_name("libehservo_ffi.so").is_file() {
        eprintln!(
            "SKIPPED: libehservo_ffi.so is not built beside ehservo (cargo build -p ehservo-ffi)"
        );
        return None;
    }
    let src = dir.join("native.toml");
    std::fs::write(&src, scenario).unwrap();
    let fmu = dir.join("plant.fmu");
    let o = ehservo()
        .args(["fmu", "--plant"])
        .arg(&src)
        .arg("--out")
        .arg(&fmu)
        .output()
        .unwrap();
    succeeded("fmu --plant", &o);
    Some(fmu)
}

/// The column `col` of a CSV file.
fn column(path: &Path, col: &str) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = head
        .iter()
        .position(|h| *h == col)
        .unwrap_or_else(|| panic!("{col} in {head:?}"));
    lines
        .map(|l| l.split(',').nth(i).unwrap().to_string())
        .collect()
}

fn run(dir: &Path, name: &str, text: &str) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let out = dir.join(format!("out-{name}"));
    let o = ehservo()
        .args(["run", "--no-plot", "-q"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    succeeded(name, &o);
    out
}

#[test]
fn an_exported_plant_imported_back_gives_the_native_trace_to_the_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let Some(_) = export(tmp.path(), NATIVE) else {
        return;
    };
    let native = run(tmp.path(), "native-run", NATIVE);
    let fmu = run(tmp.path(), "imported", &imported(""));
    for col in ["theta_deg", "theta_dot_deg_s", "theta_ddot_deg_s2", "u_V"] {
        let (a, b) = (
            column(&native.join("trace.csv"), col),
            column(&fmu.join("trace.csv"), col),
        );
        assert_eq!(a.len(), 1001, "{col}");
        // The same plant and the same RK4 sub-steps, inside the FMU's
        // doStep: the same bits, not just close ones.
        assert_eq!(a, b, "{col}");
    }
    // And the run moved: the comparison is not of two zero traces.
    let theta = column(&native.join("trace.csv"), "theta_deg");
    assert!(theta.iter().any(|v| v.parse::<f64>().unwrap().abs() > 1.0));
}

#[test]
fn an_imported_plant_sweeps_to_the_same_bits_on_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let Some(_) = export(tmp.path(), NATIVE) else {
        return;
    };
    std::fs::write(tmp.path().join("imported.toml"), imported("")).unwrap();
    std::fs::write(tmp.path().join("native.toml"), NATIVE).unwrap();
    let study = |base: &str| {
        format!(
            "name = \"s\"\nbase = \"{base}\"\nseed = 1\n[[axis]]\nkey = \"controller.design_pole\"\nvalues = [20.0, 25.0, 30.0, 35.0]\n"
        )
    };
    let mut results = Vec::new();
    for (base, threads) in [
        ("imported.toml", "1"),
        ("imported.toml", "2"),
        ("native.toml", "2"),
    ] {
        let file = tmp.path().join(format!("study-{base}-{threads}.toml"));
        std::fs::write(&file, study(base)).unwrap();
        let out = tmp.path().join(format!("sweep-{base}-{threads}"));
        let o = ehservo()
            .args(["sweep", "-q", "--no-plot", "--threads", threads])
            .arg(&file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        succeeded("sweep", &o);
        results.push(column(&out.join("results.csv"), "e_final_deg"));
    }
    assert_eq!(results[0].len(), 4);
    assert_eq!(results[0], results[1], "1 and 2 threads");
    assert_eq!(results[0], results[2], "imported and native");
}

/// What [`rezip`] does to an entry (its name and bytes): new bytes, or
/// `None` to drop it.
type Edit = dyn Fn(&str, Vec<u8>) -> Option<Vec<u8>>;

/// A copy of the FMU `src` as `dst`, each entry through `edit` (which may
/// change its bytes, or drop it with `None`).
fn rezip(src: &Path, dst: &Path, edit: impl Fn(&str, Vec<u8>) -> Option<Vec<u8>>) {
    let mut zin = zip::ZipArchive::new(std::fs::File::open(src).unwrap()).unwrap();
    let mut zout = zip::ZipWriter::new(std::fs::File::create(dst).unwrap());
    for i in 0..zin.len() {
        let mut e = zin.by_index(i).unwrap();
        let name = e.name().to_string();
        let mut bytes = Vec::new();
        e.read_to_end(&mut bytes).unwrap();
        if let Some(b) = edit(&name, bytes) {
            zout.start_file(name, zip::write::SimpleFileOptions::default())
                .unwrap();
            zout.write_all(&b).unwrap();
        }
    }
    zout.finish().unwrap();
}

/// The description of an FMU with `from` replaced by `to`.
fn edit_xml(from: &'static str, to: &'static str) -> impl Fn(&str, Vec<u8>) -> Option<Vec<u8>> {
    move |name, b| {
        if name != "modelDescription.xml" {
            return Some(b);
        }
        let text = String::from_utf8(b).unwrap();
        assert!(text.contains(from), "{from} in the description");
        Some(text.replacen(from, to, 1).into_bytes())
    }
}

/// `ehservo run` of `scenario` in `dir` is refused with `expect`, naming
/// the scenario file and `key`, and writes nothing.
fn refused(dir: &Path, scenario: &str, key: &str, expect: &str) {
    let file = dir.join("bad.toml");
    std::fs::write(&file, scenario).unwrap();
    let out = dir.join("out-bad");
    let o = ehservo()
        .args(["run", "--no-plot"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = rejected(key, &o, expect);
    assert!(err.contains("bad.toml") && err.contains(key), "{err}");
    assert!(!out.exists(), "{key}: nothing written");
}

#[test]
fn a_bad_fmu_or_mapping_is_refused_with_the_file_the_key_and_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Needs no binary: a file that is missing, or not a zip.
    let missing = imported("").replace("plant.fmu", "none.fmu");
    refused(d, &missing, "plant.path", "cannot be read");
    std::fs::write(d.join("text.fmu"), "not a zip").unwrap();
    refused(
        d,
        &imported("").replace("plant.fmu", "text.fmu"),
        "plant.path",
        "is not a zip archive",
    );
    let Some(fmu) = export(d, NATIVE) else {
        return;
    };
    let variant = |name: &str, edit: &Edit| {
        rezip(&fmu, &d.join(name), edit);
        imported("").replace("plant.fmu", name)
    };
    let no_xml = variant("noxml.fmu", &|n, b| {
        (n != "modelDescription.xml").then_some(b)
    });
    refused(d, &no_xml, "plant.path", "holds no modelDescription.xml");
    let no_bin = variant("nobin.fmu", &|n, b| {
        (!n.starts_with("binaries/")).then_some(b)
    });
    refused(d, &no_bin, "plant.path", "has no binary for this platform");
    let furlong = variant(
        "unit.fmu",
        &edit_xml("unit=\"rad\"/>", "unit=\"furlong\"/>"),
    );
    refused(d, &furlong, "plant.position", "has unit \"furlong\"");
    let deg_s = variant(
        "dunit.fmu",
        &edit_xml("unit=\"rad/s\"/>", "unit=\"deg/s\"/>"),
    );
    refused(d, &deg_s, "plant.velocity", "expected rad/s");
    // The binary refuses a token that is not its own: instantiate fails.
    let token = variant(
        "token.fmu",
        &edit_xml("instantiationToken=\"{", "instantiationToken=\"{x"),
    );
    refused(d, &token, "plant.path", "fmi3InstantiateCoSimulation");
    // The mapping: a name that is not there, or of the wrong causality.
    refused(
        d,
        &imported("").replace("\"u\"", "\"valve\""),
        "plant.command",
        "no variable \"valve\"",
    );
    refused(
        d,
        &imported("").replace("position = \"theta\"", "position = \"u\""),
        "plant.position",
        "causality \"input\"",
    );
    refused(
        d,
        &imported("parameters = { theta = 1.0 }"),
        "plant.parameters.theta",
        "causality \"output\"",
    );
    // An FMU plant cannot be exported in turn (the FMU's binary has no
    // FMU import).
    std::fs::write(d.join("again.toml"), imported("")).unwrap();
    let o = ehservo()
        .args(["fmu", "--plant"])
        .arg(d.join("again.toml"))
        .arg("--out")
        .arg(d.join("again.fmu"))
        .output()
        .unwrap();
    rejected("fmu of an fmu plant", &o, "cannot load another FMU");
    assert!(!d.join("again.fmu").exists());
    // What a co-simulation FMU cannot do.
    refused(
        d,
        &imported("").replace("substeps = 4", "substeps = 4\nsolver = \"dopri5\""),
        "simulation.solver",
        "steps itself",
    );
}

#[test]
fn an_fmu_that_fails_during_a_run_ends_that_run_as_a_result() {
    let tmp = tempfile::tempdir().unwrap();
    // The exported plant stops (terminateSimulation, with its message) once
    // |θ| passes 0.05 rad (its scenario's 2° reference stays inside it);
    // the importing loop follows the default 5° sine (0.087 rad) with the
    // default limit, far wider: it is the FMU that ends the run.
    let tight = NATIVE.replace("substeps = 4", "substeps = 4\ntheta_limit = 0.05")
        + "[reference]\namplitude_deg = 2.0\n";
    let Some(_) = export(tmp.path(), &tight) else {
        return;
    };
    let file = tmp.path().join("imported.toml");
    std::fs::write(&file, imported("")).unwrap();
    let out = tmp.path().join("out");
    let o = ehservo()
        .args(["run", "--no-plot"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stdout.contains("UNBOUNDED") && stdout.contains("FMU"),
        "{stdout}"
    );
    assert!(
        stderr.contains("the plant diverged"),
        "the FMU's message: {stderr}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(
        summary.contains("plant-failed") || summary.contains("PlantFailed"),
        "{summary}"
    );
}
