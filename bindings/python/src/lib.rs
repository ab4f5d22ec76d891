//! `ehservo._ehservo`: the Rust half of the Python package `ehservo`.
//!
//! Thin on purpose: every number comes from the same functions the command
//! line calls (`formats::load` with `--set` overrides, `run::run_observed`,
//! `output::TraceLayout`, `study::execute`/`study::sweep`,
//! `stepper::ControllerStepper`, as the C ABI and the FMU; `freq::linearise`), so the Python results are the CLI's
//! bits. The Python side (`python/ehservo/__init__.py`) turns the keyword
//! overrides into `key=value` strings and the columns into a DataFrame.
//!
//! Trace columns are filled in Rust as `Vec<f64>` during the run and handed
//! to numpy without a copy (`PyArray1::from_vec` takes the buffer).

mod freq;

use ehservo::metrics::Metrics;
use ehservo::output::TraceLayout;
use ehservo::scenario::{Loop, ScenarioError as RsScenarioError};
use ehservo::stepper::ControllerStepper;
use ehservo::study::Plan;
use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{
    PyKeyboardInterrupt, PyMemoryError, PyOSError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::time::Duration;

create_exception!(
    ehservo,
    ScenarioError,
    PyValueError,
    "A bad scenario, study or override: the message is the command line's \
     (file, line:column when known, the key and the reason)."
);

/// The Python exception for a scenario error, with its parts as attributes.
fn scenario_error(py: Python<'_>, e: &RsScenarioError) -> PyErr {
    let err = ScenarioError::new_err(e.to_string());
    let v = err.value(py);
    let key = (!e.key.is_empty()).then(|| e.key.clone());
    // Setting attributes on a fresh exception instance cannot fail short of
    // memory exhaustion; the message above carries everything anyway.
    let _ = v.setattr("file", e.file.clone());
    let _ = v.setattr("key", key);
    let _ = v.setattr("line", e.line_col.map(|(l, _)| l));
    let _ = v.setattr("column", e.line_col.map(|(_, c)| c));
    let _ = v.setattr("reason", e.reason.to_string());
    err
}

/// A study error (one line naming the file and the key) as the Python
/// exception, with `key` and `line` unknown.
fn study_error(py: Python<'_>, msg: String) -> PyErr {
    let err = ScenarioError::new_err(msg.clone());
    let v = err.value(py);
    let _ = v.setattr("file", py.None());
    let _ = v.setattr("key", py.None());
    let _ = v.setattr("line", py.None());
    let _ = v.setattr("column", py.None());
    let _ = v.setattr("reason", msg);
    err
}

/// How often a call that computes looks for Python's signals (Ctrl-C).
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// Runs `work` on a thread of its own, without the GIL, while this thread
/// looks for signals every [`SIGNAL_POLL`] (`Python::check_signals`: the
/// interpreter runs its handlers, Ctrl-C's raises `KeyboardInterrupt`). On
/// an interrupt the work is asked to stop (`ehservo::cancel`: the run in
/// progress stops at its next chunk, no new run starts, nothing is
/// committed), and the exception is raised once it has: within a fraction
/// of a second. A call interrupted this way returns no result.
fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    F: FnOnce() -> T + Send,
    T: Send,
{
    use std::sync::mpsc::{channel, RecvTimeoutError};
    let _scope = ehservo::cancel::Scope::enter();
    std::thread::scope(|sc| {
        let (tx, rx) = channel::<()>();
        let handle = sc.spawn(move || {
            let r = work();
            let _ = tx.send(());
            r
        });
        // Behind a mutex: only a Sync value crosses into `detach`.
        let rx = std::sync::Mutex::new(rx);
        let mut interrupt = None;
        loop {
            let waited = py.detach(|| match rx.lock() {
                Ok(r) => r.recv_timeout(SIGNAL_POLL),
                Err(_) => Err(RecvTimeoutError::Disconnected),
            });
            match waited {
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        ehservo::cancel::request();
                        interrupt = Some(e);
                        break;
                    }
                }
                _ => break,
            }
        }
        let joined = py.detach(|| handle.join());
        if let Some(e) = interrupt {
            return Err(e);
        }
        let r = joined.map_err(|_| {
            PyRuntimeError::new_err("internal error: ehservo's computation panicked (a bug)")
        })?;
        // Another thread's Ctrl-C stopped this call too: its result may
        // be cut short.
        if ehservo::cancel::requested() {
            return Err(PyKeyboardInterrupt::new_err(
                "interrupted: ehservo's computation was stopped",
            ));
        }
        Ok(r)
    })
}

/// An error of a long call (sweep, tune, league) as a Python exception:
/// bad input is `ScenarioError`, an interruption `KeyboardInterrupt`, the
/// rest (an output that cannot be written) `OSError`.
fn work_error(py: Python<'_>, e: anyhow::Error) -> PyErr {
    if ehservo::cancel::is_cancelled(&e) {
        PyKeyboardInterrupt::new_err(e.to_string())
    } else if ehservo::error::is_bad_input(&e) {
        study_error(py, format!("{e:#}"))
    } else {
        PyOSError::new_err(format!("{e:#}"))
    }
}

/// `threads`, when given, within 1..=1024 (as `--threads`).
fn check_threads(threads: Option<usize>) -> PyResult<()> {
    match threads {
        Some(t) if !(1..=1024).contains(&t) => Err(PyValueError::new_err(format!(
            "threads={t}: must be between 1 and 1024"
        ))),
        _ => Ok(()),
    }
}

/// Why a run gave no result.
enum RunFailure {
    Memory(String),
}

/// The scenario of a file (`path`) or of TOML text, with the CLI's
/// `--set key=value` overrides.
fn load(
    path: Option<PathBuf>,
    text: Option<String>,
    overrides: &[String],
) -> Result<Loop, RsScenarioError> {
    let unnamed = |s: Loop, name: &str| {
        if s.name().is_empty() {
            s.named(name)
        } else {
            s
        }
    };
    match (path, text) {
        (Some(p), _) => ehservo::formats::load(&p, overrides),
        (None, Some(t)) => Ok(unnamed(
            ehservo::formats::parse_in(&t, "<string>", overrides, None)?,
            "scenario",
        )),
        // The defaults: the paper's Fig. 2 case, overrides applied.
        (None, None) => Ok(unnamed(
            Loop::parse_with("", "<defaults>", overrides)?,
            "defaults",
        )),
    }
}

/// The metrics as summary.json writes them: `None` for an undefined one,
/// `diverged` a bool, `samples` an int; on a linear axis the errors are
/// `e_max`, `e_final`, `e_rms` with `unit = "mm"` beside them (a rotary
/// axis's say `e_max_deg`).
fn metrics_dict<'py>(py: Python<'py>, m: &Metrics) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if m.axis == ehservo::axis::Axis::Linear {
        d.set_item("unit", m.axis.unit())?;
    }
    for name in Metrics::names(m.axis).iter().copied() {
        match name {
            "diverged" => d.set_item(name, m.diverged)?,
            "samples" => d.set_item(name, m.samples)?,
            _ => d.set_item(name, m.get(name))?,
        }
    }
    Ok(d)
}

/// Runs a scenario: (name, metrics, column names, columns, outcome JSON).
///
/// The columns are trace.csv's (every `output.decimate`-th sample, as the
/// CLI writes them); with `raw`, seven more in SI units: z (θd and its
/// three derivatives) and the x the controller was given, which a Python
/// loop can replay through `Controller.step` exactly.
#[pyfunction]
#[pyo3(signature = (path, text, overrides, raw=false))]
#[allow(clippy::type_complexity)]
fn run<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    text: Option<String>,
    overrides: Vec<String>,
    raw: bool,
) -> PyResult<(
    String,
    Bound<'py, PyDict>,
    Vec<String>,
    Vec<Bound<'py, PyArray1<f64>>>,
    String,
)> {
    // Built (so checked) before any work, and before any memory is asked for.
    let lp = load(path, text, &overrides).map_err(|e| scenario_error(py, &e))?;
    let s = lp.scenario();
    let result = interruptible(py, || -> Result<_, RunFailure> {
        let layout = TraceLayout::of(&lp);
        let mut names: Vec<String> = layout.columns.iter().map(|c| c.to_string()).collect();
        if raw {
            names.extend(RAW_COLUMNS.iter().map(|c| c.to_string()));
        }
        let decimate = s.output.decimate.max(1) as u64;
        let rows = (lp.sim().steps / decimate + 1) as usize;
        // The whole trace, asked for up front and fallibly: a run too long
        // for the memory there is raises MemoryError before it starts
        // (an infallible allocation would abort the interpreter), and the
        // pushes below never reallocate.
        let mut cols: Vec<Vec<f64>> = Vec::new();
        for _ in 0..names.len() {
            let mut c = Vec::new();
            if c.try_reserve_exact(rows).is_err() {
                return Err(RunFailure::Memory(format!(
                    "the trace of {rows} rows × {} columns needs {} MB, which cannot be had: set output.decimate to keep fewer rows",
                    names.len(),
                    rows as u64 * names.len() as u64 * 8 / 1_000_000
                )));
            }
            cols.push(c);
        }
        let mut row = Vec::with_capacity(names.len());
        let (outcome, metrics) = ehservo::run::run_observed(&lp, &mut |smp| {
            if smp.k % decimate != 0 {
                return;
            }
            layout.row(smp, &mut row);
            if raw {
                row.extend(smp.z);
                row.extend(smp.x_ctrl);
            }
            for (c, v) in cols.iter_mut().zip(&row) {
                // Within the capacity reserved above (at most `rows`).
                if c.len() < c.capacity() {
                    c.push(*v);
                }
            }
        });
        let info = serde_json::json!({
            "divergence": outcome.diverged.map(ehservo::output::DivergenceInfo::from),
            "faults": ehservo::output::Faults {
                valve_root_clamped_samples: outcome.valve_root_clamped,
                zero_error_norm_samples: outcome.zero_error_norm,
                saturated_samples: outcome.saturated,
                measurement_fault_samples: outcome.measurement_faults,
            },
        });
        Ok((names, cols, metrics, info.to_string()))
    });
    let (names, cols, metrics, info) = result?.map_err(|e| match e {
        RunFailure::Memory(m) => PyMemoryError::new_err(m),
    })?;
    let arrays = cols
        .into_iter()
        .map(|c| PyArray1::from_vec(py, c))
        .collect();
    Ok((
        s.name.clone(),
        metrics_dict(py, &metrics)?,
        names,
        arrays,
        info,
    ))
}

/// The extra columns of `run(..., raw=True)`.
const RAW_COLUMNS: [&str; 7] = [
    "z0_rad",
    "z1_rad_s",
    "z2_rad_s2",
    "z3_rad_s3",
    "x0_ctrl_rad",
    "x1_ctrl_rad_s",
    "x2_ctrl_rad_s2",
];

/// Checks the scenario and returns it with every default filled in, as
/// TOML (what `ehservo check` prints).
#[pyfunction]
#[pyo3(signature = (path, text, overrides))]
fn check(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    overrides: Vec<String>,
) -> PyResult<String> {
    let lp = load(path, text, &overrides).map_err(|e| scenario_error(py, &e))?;
    Ok(lp.scenario().to_toml())
}

/// A column of results.csv as Python data.
enum Column {
    Int(Vec<i64>),
    UInt(Vec<u64>),
    Float(Vec<f64>),
    Bool(Vec<bool>),
    Text(Vec<Option<String>>),
    /// Booleans or integers with gaps (`None`): an object column.
    Sparse(Vec<Option<Py<PyAny>>>),
}

impl Column {
    fn into_py(self, py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
        Ok(match self {
            Column::Int(v) => PyArray1::from_vec(py, v).into_any(),
            Column::UInt(v) => PyArray1::from_vec(py, v).into_any(),
            Column::Float(v) => PyArray1::from_vec(py, v).into_any(),
            Column::Bool(v) => PyArray1::from_vec(py, v).into_any(),
            Column::Text(v) => PyList::new(py, v)?.into_any(),
            Column::Sparse(v) => PyList::new(py, v)?.into_any(),
        })
    }
}

fn pybool(py: Python<'_>, b: bool) -> Py<PyAny> {
    pyo3::types::PyBool::new(py, b)
        .to_owned()
        .into_any()
        .unbind()
}

fn pyint(py: Python<'_>, n: u64) -> PyResult<Py<PyAny>> {
    Ok(n.into_pyobject(py)?.into_any().unbind())
}

/// A varied column: integers if every value is one, numbers (float64) if
/// every value is a number, booleans if every value is one, else text as
/// results.csv writes it.
fn varied_column(values: Vec<&toml::Value>) -> Column {
    use toml::Value as V;
    if values.iter().all(|v| matches!(v, V::Integer(_))) {
        return Column::Int(
            values
                .iter()
                .map(|v| v.as_integer().unwrap_or_default())
                .collect(),
        );
    }
    if values
        .iter()
        .all(|v| matches!(v, V::Integer(_) | V::Float(_)))
    {
        return Column::Float(
            values
                .iter()
                .map(|v| ehservo::study::as_f64(v).unwrap_or(f64::NAN))
                .collect(),
        );
    }
    if values.iter().all(|v| matches!(v, V::Boolean(_))) {
        return Column::Bool(
            values
                .iter()
                .map(|v| v.as_bool().unwrap_or_default())
                .collect(),
        );
    }
    Column::Text(
        values
            .iter()
            .map(|v| {
                Some(match v {
                    V::String(s) => s.clone(),
                    other => other.to_string(),
                })
            })
            .collect(),
    )
}

/// Runs a study: (column names, columns) of results.csv, in run order. With
/// `out`, also writes the CLI's output folder (results.csv, study.json,
/// plots).
#[pyfunction]
#[pyo3(signature = (path, threads=None, out=None))]
fn sweep<'py>(
    py: Python<'py>,
    path: PathBuf,
    threads: Option<usize>,
    out: Option<PathBuf>,
) -> PyResult<(Vec<String>, Vec<Bound<'py, PyAny>>)> {
    check_threads(threads)?;
    let plan = Plan::load(&path).map_err(|e| study_error(py, e.to_string()))?;
    // The rows and the columns made of them, asked for before any run: a
    // study too large for the memory there raises MemoryError up front
    // rather than aborting the interpreter when the rows are collected.
    let per_row = std::mem::size_of::<ehservo::study::RunRow>()
        + 2 * plan.columns().len() * std::mem::size_of::<toml::Value>()
        + 2 * 8 * (Metrics::NAMES.len() + 3);
    let bytes = (plan.runs as usize).saturating_mul(per_row);
    if Vec::<u8>::new().try_reserve_exact(bytes).is_err() {
        return Err(PyMemoryError::new_err(format!(
            "the results of {} runs need about {} MB, which cannot be had: shard the study (ehservo sweep --shard)",
            plan.runs,
            bytes / 1_000_000
        )));
    }
    let rows = interruptible(py, || -> anyhow::Result<Vec<ehservo::study::RunRow>> {
        match &out {
            Some(dir) => {
                ehservo::output::probe_destination(dir)?;
                let opts = ehservo::study::SweepOptions {
                    out: dir.clone(),
                    shard: None,
                    threads,
                    progress: false,
                    plots: true,
                };
                ehservo::study::sweep(&plan, &opts)
            }
            None => ehservo::study::execute(
                &plan,
                0..plan.runs,
                threads,
                &indicatif::ProgressBar::hidden(),
            ),
        }
    });
    let rows = rows?.map_err(|e| work_error(py, e))?;

    let mut names: Vec<String> = vec!["run".into()];
    let varied = plan.columns();
    names.extend(varied.iter().cloned());
    names.push("seed".into());
    // The metric columns of results.csv on the study's axis (e_max_mm on
    // a linear one).
    let metric_names = Metrics::csv_names(plan.axis());
    names.extend(metric_names.iter().map(|s| s.to_string()));
    // The behaviour's columns after them, as results.csv has them.
    let behaviour_names = ehservo::behaviour::columns(plan.axis());
    names.extend(behaviour_names.iter().map(|s| s.to_string()));
    names.push("error".into());

    let mut cols: Vec<Column> = vec![Column::Int(rows.iter().map(|r| r.index as i64).collect())];
    for j in 0..varied.len() {
        cols.push(varied_column(rows.iter().map(|r| &r.values[j]).collect()));
    }
    cols.push(Column::UInt(rows.iter().map(|r| r.seed).collect()));
    for name in metric_names.iter().copied() {
        cols.push(match name {
            // An invalid run has no metrics: diverged is then missing too,
            // which results.csv writes as an empty cell.
            "diverged" if rows.iter().all(|r| r.metrics.is_some()) => Column::Bool(
                rows.iter()
                    .map(|r| r.metrics.is_some_and(|m| m.diverged))
                    .collect(),
            ),
            "samples" if rows.iter().all(|r| r.metrics.is_some()) => Column::UInt(
                rows.iter()
                    .map(|r| r.metrics.map(|m| m.samples).unwrap_or_default())
                    .collect(),
            ),
            "diverged" => Column::Sparse(
                rows.iter()
                    .map(|r| r.metrics.map(|m| pybool(py, m.diverged)))
                    .collect(),
            ),
            "samples" => Column::Sparse(
                rows.iter()
                    .map(|r| r.metrics.map(|m| pyint(py, m.samples)).transpose())
                    .collect::<PyResult<_>>()?,
            ),
            _ => Column::Float(
                rows.iter()
                    .map(|r| r.metrics.and_then(|m| m.get(name)).unwrap_or(f64::NAN))
                    .collect(),
            ),
        });
    }
    // The behaviour's cells as results.csv writes them: the verdict as
    // text, the numbers read back (shortest decimals: the same bits), NaN
    // where a cell is empty.
    let cells: Vec<Option<[String; 7]>> = rows
        .iter()
        .map(|r| r.metrics.map(|m| m.behaviour.cells(m.diverged)))
        .collect();
    for k in 0..behaviour_names.len() {
        let cell = |c: &Option<[String; 7]>| c.as_ref().map(|c| c[k].clone());
        cols.push(match k {
            0 => Column::Text(cells.iter().map(cell).collect()),
            _ => Column::Float(
                cells
                    .iter()
                    .map(|c| cell(c).and_then(|v| v.parse().ok()).unwrap_or(f64::NAN))
                    .collect(),
            ),
        });
    }
    cols.push(Column::Text(rows.iter().map(|r| r.error.clone()).collect()));
    let cols = cols
        .into_iter()
        .map(|c| c.into_py(py))
        .collect::<PyResult<Vec<_>>>()?;
    Ok((names, cols))
}

/// Tunes a controller as `ehservo tune` does: the result's JSON (tune.json's
/// `result`). With `out`, also writes the CLI's output folder.
#[pyfunction]
#[pyo3(signature = (path, threads=None, out=None, plot=true))]
fn tune(
    py: Python<'_>,
    path: PathBuf,
    threads: Option<usize>,
    out: Option<PathBuf>,
    plot: bool,
) -> PyResult<String> {
    check_threads(threads)?;
    let t = ehservo::tune::Tune::load(&path).map_err(|e| study_error(py, e.to_string()))?;
    let r = interruptible(py, || -> anyhow::Result<String> {
        let hidden = indicatif::ProgressBar::hidden();
        let r = match &out {
            Some(dir) => {
                ehservo::output::probe_destination(dir)?;
                ehservo::tune::tune_to_dir(&t, dir, threads, &hidden, plot)?
            }
            None => ehservo::tune::search(&t, threads, &hidden)?,
        };
        Ok(serde_json::to_string(&r)?)
    })?;
    r.map_err(|e| work_error(py, e))
}

/// Runs a league as `ehservo league` does: JSON with the standings and
/// league.csv's rows. With `out`, also writes the CLI's output folder.
#[pyfunction]
#[pyo3(signature = (path, threads=None, out=None, plot=true))]
fn league(
    py: Python<'_>,
    path: PathBuf,
    threads: Option<usize>,
    out: Option<PathBuf>,
    plot: bool,
) -> PyResult<String> {
    check_threads(threads)?;
    let l = ehservo::league::League::load(&path).map_err(|e| study_error(py, e.to_string()))?;
    let r = interruptible(py, || -> anyhow::Result<String> {
        let hidden = indicatif::ProgressBar::hidden();
        let r = match &out {
            Some(dir) => {
                ehservo::output::probe_destination(dir)?;
                ehservo::league::league_to_dir(&l, dir, threads, &hidden, plot)?
            }
            None => ehservo::league::play(&l, threads, &hidden, None, false)?,
        };
        let rows = ehservo::league::report::rows(&l, &r);
        Ok(serde_json::to_string(&serde_json::json!({
            "standings": r.standings,
            "rows": rows,
        }))?)
    })?;
    r.map_err(|e| work_error(py, e))
}

/// A scenario's controller as a sampled-data system (the Rust half of
/// `ehservo.Controller`): `ehservo::stepper::ControllerStepper`, which the
/// C ABI and the FMU hold too. The controller types are plain data (Send
/// and Sync), so a controller made on one thread may be stepped on
/// another; two threads stepping one controller at once get Python's
/// "Already borrowed" RuntimeError for the second, never a panic.
#[pyclass(module = "ehservo._ehservo")]
struct RawController {
    ctrl: ControllerStepper,
    kind: &'static str,
    name: String,
    buf: Vec<f64>,
}

fn as3(v: &[f64], what: &str) -> PyResult<[f64; 3]> {
    v.try_into().map_err(|_| {
        PyValueError::new_err(format!(
            "{what}: expected 3 values (θ, θ̇, θ̈ in rad, rad/s, rad/s²), got {}",
            v.len()
        ))
    })
}

fn as4(v: &[f64], what: &str) -> PyResult<[f64; 4]> {
    v.try_into().map_err(|_| {
        PyValueError::new_err(format!(
            "{what}: expected 4 values (θd, θ̇d, θ̈d, θ⃛d in rad, rad/s, rad/s², rad/s³), got {}",
            v.len()
        ))
    })
}

impl RawController {
    fn output<'py>(&self, py: Python<'py>, u: f64, flags: u8) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("u", u)?;
        d.set_item("flags", flags)?;
        for (s, v) in self.ctrl.signals().iter().zip(&self.buf) {
            d.set_item(s.key, *v)?;
        }
        Ok(d)
    }
}

#[pymethods]
impl RawController {
    #[new]
    #[pyo3(signature = (path, text, overrides))]
    fn new(
        py: Python<'_>,
        path: Option<PathBuf>,
        text: Option<String>,
        overrides: Vec<String>,
    ) -> PyResult<Self> {
        let s = load(path, text, &overrides).map_err(|e| scenario_error(py, &e))?;
        let ctrl = ControllerStepper::new(&s).map_err(|e| scenario_error(py, &e))?;
        let kind = ctrl.kind();
        let n = ctrl.signals().len();
        Ok(Self {
            ctrl,
            kind,
            name: s.name().to_string(),
            buf: vec![0.0; n],
        })
    }

    /// One sample: the command and the law's parts; the state advances.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        x: Vec<f64>,
        z: Vec<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (x, z) = (as3(&x, "x")?, as4(&z, "z")?);
        let o = self.ctrl.step_parts(t, x, z, &mut self.buf);
        self.output(py, o.u, o.flags)
    }

    /// The command `step` would return now, without advancing the state.
    fn peek(&self, t: f64, x: Vec<f64>, z: Vec<f64>) -> PyResult<(f64, u8)> {
        let (x, z) = (as3(&x, "x")?, as4(&z, "z")?);
        let o = self.ctrl.peek(t, x, z);
        Ok((o.u, o.flags))
    }

    /// z = (θd, θ̇d, θ̈d, θ⃛d) of the scenario's reference at `t`.
    fn reference(&self, t: f64) -> [f64; 4] {
        self.ctrl.reference(t)
    }

    /// Back to the initial state.
    fn reset(&mut self) {
        self.ctrl.reset();
    }

    /// (key, trace.csv column or "", unit, description) of each part.
    fn signals(&self) -> Vec<(&'static str, &'static str, &'static str, &'static str)> {
        self.ctrl
            .signals()
            .iter()
            .map(|s| (s.key, s.column, s.unit, s.doc))
            .collect()
    }

    #[getter]
    fn kind(&self) -> &'static str {
        self.kind
    }

    #[getter]
    fn dt(&self) -> f64 {
        self.ctrl.period()
    }

    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    #[getter]
    fn faults(&self) -> u64 {
        self.ctrl.faults()
    }

    /// The network weights W of the current state (empty without a network).
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.ctrl.weights())
    }
}

/// Whether `p` is a regular file (the Python side's path/text choice).
#[pyfunction]
fn is_file(p: PathBuf) -> bool {
    Path::new(&p).is_file()
}

#[pymodule]
fn _ehservo(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ScenarioError", m.py().get_type::<ScenarioError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(tune, m)?)?;
    m.add_function(wrap_pyfunction!(league, m)?)?;
    // The flags of a sample (docs/flags.md): name → value.
    let flags = PyDict::new(m.py());
    for (name, value, _) in ehservo_core::control::flags::ALL {
        flags.set_item(name, value)?;
    }
    m.add("FLAGS", flags)?;
    m.add_function(wrap_pyfunction!(is_file, m)?)?;
    m.add_function(wrap_pyfunction!(freq::linearize, m)?)?;
    m.add_function(wrap_pyfunction!(freq::freq, m)?)?;
    m.add_class::<RawController>()?;
    Ok(())
}
