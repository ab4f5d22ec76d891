//! `linearize` and `freq`: the frequency domain's two commands (lib.rs
//! was beyond the house's 650 code lines).

use super::{check_threads, interruptible, load, scenario_error, work_error};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};

/// Linearises a scenario's loop as `ehservo linearize` does: its JSON text.
/// `at`: a time along the run (s); `trim`: the position of a trim point in
/// the axis's unit (θ0 in degrees on a rotary axis, mm on a linear one);
/// with neither, a trim at θd(0). `side` ("minus"/"plus"): the one-sided model
/// at a point that is not differentiable. `discretise`: "zoh" or "rk4".
#[pyfunction]
#[pyo3(signature = (path, text, overrides, at=None, trim=None, side=None, discretise="zoh"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn linearize(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    overrides: Vec<String>,
    at: Option<f64>,
    trim: Option<f64>,
    side: Option<String>,
    discretise: &str,
) -> PyResult<String> {
    use ehservo::freq::cli;
    let file = path
        .as_ref()
        .map_or("<string>".to_string(), |p| p.display().to_string());
    let s = load(path, text, &overrides).map_err(|e| scenario_error(py, &e))?;
    check_choices(side.as_deref(), discretise)?;
    let l = ehservo::freq::linearise(
        &s,
        &file,
        cli::operating_point_on(s.axis(), at, trim.map(Some), None, None),
        cli::side(side.as_deref()),
        cli::discretisation(discretise),
    )
    .map_err(|e| scenario_error(py, &e))?;
    if !ehservo::freq::all_finite(&l) {
        return Err(PyValueError::new_err(format!(
            "{file}: the linearised models are not finite"
        )));
    }
    serde_json::to_string(&ehservo::freq::linearisation_json(&l))
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// `ehservo freq` into `out`: the computed responses and margins about an
/// operating point, and the `measure`d ones (a list of "sine",
/// "multisine", "chirp"; empty: none). `trim` and `amplitude` are in the
/// axis's unit (degrees; mm on a linear axis). Returns freq.json's text.
#[pyfunction]
#[pyo3(signature = (path, text, overrides, out, at=None, trim=None, side=None, discretise="zoh", measure=vec!["sine".to_string()], points=None, amplitude=None, threads=None, plot=true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn freq(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    overrides: Vec<String>,
    out: PathBuf,
    at: Option<f64>,
    trim: Option<f64>,
    side: Option<String>,
    discretise: &str,
    measure: Vec<String>,
    points: Option<usize>,
    amplitude: Option<f64>,
    threads: Option<usize>,
    plot: bool,
) -> PyResult<String> {
    use ehservo::freq::cli;
    check_threads(threads)?;
    let file = path
        .as_ref()
        .map_or("<string>".to_string(), |p| p.display().to_string());
    let s = load(path, text, &overrides).map_err(|e| scenario_error(py, &e))?;
    check_choices(side.as_deref(), discretise)?;
    let mut o = ehservo::freq::report::FreqOptions::defaults();
    o.at = cli::operating_point_on(s.axis(), at, trim.map(Some), None, None);
    o.side = cli::side(side.as_deref());
    o.discretisation = cli::discretisation(discretise);
    o.methods = cli::methods(&measure, &file).map_err(|e| scenario_error(py, &e))?;
    if let Some(n) = points {
        o.points = n;
    }
    (o.settings.amplitude, o.amplitude_flag) =
        cli::amplitude(s.axis(), amplitude, None, &file).map_err(|e| scenario_error(py, &e))?;
    o.plots = plot;
    let r = interruptible(py, || -> anyhow::Result<String> {
        ehservo::output::probe_destination(&out)?;
        cli::freq_cmd(&s, Path::new(&file), &o, &out, threads)?;
        Ok(std::fs::read_to_string(out.join("freq.json"))?)
    })?;
    r.map_err(|e| work_error(py, e))
}

/// The `side` and `discretise` arguments' spellings.
fn check_choices(side: Option<&str>, discretise: &str) -> PyResult<()> {
    if !matches!(side, None | Some("minus") | Some("plus")) {
        return Err(PyValueError::new_err(
            "side: expected \"minus\" or \"plus\"",
        ));
    }
    if !matches!(discretise, "zoh" | "rk4") {
        return Err(PyValueError::new_err(
            "discretise: expected \"zoh\" or \"rk4\"",
        ));
    }
    Ok(())
}
