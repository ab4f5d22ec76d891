//! What a run writes: `trace.csv`, `summary.json`, `trace.png`; all into a
//! staging directory first, moved into place only when complete.

use crate::metrics::Metrics;
use crate::run::Decimate;
use crate::run::RunResult;
use crate::scenario::{Loop, Scenario};
use crate::simulation::{Divergence, Sample};
use anyhow::{Context, Result};
use ehservo_sim::axis::Axis;
use serde::Serialize;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

mod decimal;
pub mod escape;
mod figure;
mod staging;
pub use figure::{
    a_variation, b_convention, b_size, b_variation, clip_diverged, trace_figure, variation_footer,
};
pub(crate) use figure::{num, panel};
pub use staging::{check_destination, probe_destination, write_atomic, Staging, OUTPUT_MARKERS};

/// The software that produced an output.
#[derive(Debug, Clone, Serialize)]
pub struct Software {
    /// Crate name.
    pub name: &'static str,
    /// Crate version.
    pub version: &'static str,
}

/// This build's name and version.
pub const SOFTWARE: Software = Software {
    name: env!("CARGO_PKG_NAME"),
    version: env!("CARGO_PKG_VERSION"),
};

/// The columns every trace of a rotary axis starts with (a linear axis's
/// are `t_s, y_d_mm, y_mm, e_mm, u_V`: [`TraceLayout::prefix`]).
pub const TRACE_PREFIX: [&str; 5] = ["t_s", "theta_d_deg", "theta_deg", "e_deg", "u_V"];

/// The columns of a run's `trace.csv`: the prefix, the controller's
/// signals that have a column, `u_plant_V` when an actuator stands between
/// the command and the plant; then the plant's physical state — θ̇, θ̈ and
/// the plant's own states (a load pressure, chamber pressures) —, the spool
/// position with spool dynamics, what the sensors measured (the measured
/// channels, when the sensors are not exact) and the estimator's estimate.
/// The physical-state columns come after the older ones, so a trace's
/// first columns read as they always did.
#[derive(Debug, Clone)]
pub struct TraceLayout {
    /// Column names.
    pub columns: Vec<String>,
    /// The axis: the position columns are in its display unit.
    pub axis: Axis,
    parts: Vec<usize>,
    actuator: bool,
    states: usize,
    spool: bool,
    measured: [bool; 3],
    estimated: bool,
}

/// The columns of the position, velocity and acceleration with the
/// stem `stem` (`""`, `"_meas"`, `"_est"`): `theta_meas_deg`,
/// `theta_dot_meas_deg_s`, … on a rotary axis, `y_meas_mm` … on a linear.
/// On a force or pressure loop x is (q, ẏ, ÿ): `f_meas_kN`, then the
/// rod's `y_dot_meas_mm_s`, `y_ddot_meas_mm_s2` ([`Axis::motion`]).
fn channels(axis: Axis, stem: &str) -> [String; 3] {
    let motion = axis.motion();
    [
        axis.column(stem, ""),
        motion.column(&format!("_dot{stem}"), "_s"),
        motion.column(&format!("_ddot{stem}"), "_s2"),
    ]
}

/// x in its display units: x₀ in the axis's, x₁ and x₂ in its motion's.
#[inline]
fn shown(axis: Axis, i: usize, v: f64) -> f64 {
    if i == 0 {
        axis.display(v)
    } else {
        axis.motion().display(v)
    }
}

/// What a trace carries beside the controller's signals.
#[derive(Debug, Clone, Copy, Default)]
pub struct TraceExtras {
    /// An actuator stands between command and plant.
    pub actuator: bool,
    /// The plant's physical states beside x.
    pub states: &'static [ehservo_core::control::Signal],
    /// The actuator has spool dynamics.
    pub spool: bool,
    /// The channels the sensors measure, when they are not exact.
    pub measured: Option<[bool; 3]>,
    /// An estimator runs.
    pub estimated: bool,
    /// The plant's axis (rotary by default).
    pub axis: Axis,
}

impl TraceLayout {
    /// The layout for samples carrying `signals`.
    pub fn new(signals: &[ehservo_core::control::Signal], x: TraceExtras) -> Self {
        let axis = x.axis;
        let parts: Vec<usize> = (0..signals.len())
            .filter(|&i| !signals[i].column.is_empty())
            .collect();
        let mut columns: Vec<String> = Self::prefix(axis).to_vec();
        columns.extend(parts.iter().map(|&i| axis.si_name(signals[i].column)));
        if x.actuator {
            columns.push("u_plant_V".into());
        }
        let [_, dot, ddot] = channels(axis, "");
        columns.extend([dot, ddot]);
        columns.extend(x.states.iter().map(|s| s.column.to_string()));
        if x.spool {
            columns.push("spool_V".into());
        }
        let measured = x.measured.unwrap_or([false; 3]);
        let meas = channels(axis, "_meas");
        columns.extend((0..3).filter(|&i| measured[i]).map(|i| meas[i].clone()));
        if x.estimated {
            columns.extend(channels(axis, "_est"));
        }
        Self {
            columns,
            axis,
            parts,
            actuator: x.actuator,
            states: x.states.len(),
            spool: x.spool,
            measured,
            estimated: x.estimated,
        }
    }

    /// The first five columns on `axis`: time, the reference, the
    /// position, the error (in the axis's display unit) and the command.
    pub fn prefix(axis: Axis) -> [String; 5] {
        [
            "t_s".into(),
            axis.column("_d", ""),
            axis.column("", ""),
            format!("e_{}", axis.unit()),
            "u_V".into(),
        ]
    }

    /// The layout of a loop's runs.
    pub fn of(lp: &Loop) -> Self {
        let s = lp.scenario();
        let signals = s.controller.visit(SignalsOf);
        let exact = s.sensor.is_exact();
        Self::new(
            signals,
            TraceExtras {
                actuator: !s.actuator.is_identity(),
                states: lp.plant().states(),
                spool: lp.stages().actuator.has_lag(),
                measured: (!exact || s.estimator.is_some()).then_some(s.sensor.measured.0),
                estimated: s.estimator.is_some(),
                axis: lp.axis(),
            },
        )
    }

    /// A sample's row, in the order of [`TraceLayout::columns`], as
    /// numbers (`trace.csv` prints them; the Python bindings hand them to
    /// numpy column by column).
    pub fn row(&self, s: &Sample, out: &mut Vec<f64>) {
        out.clear();
        let a = self.axis;
        out.extend([
            s.t,
            a.display(s.z[0]),
            a.display(s.x[0]),
            a.display(s.e),
            s.u,
        ]);
        out.extend(self.parts.iter().map(|&i| s.values[i]));
        if self.actuator {
            out.push(s.u_plant);
        }
        out.extend([shown(a, 1, s.x[1]), shown(a, 2, s.x[2])]);
        out.extend(&s.states[..self.states]);
        if self.spool {
            out.push(s.spool);
        }
        out.extend(
            (0..3)
                .filter(|&i| self.measured[i])
                .map(|i| shown(a, i, s.x_ctrl[i])),
        );
        if self.estimated {
            out.extend((0..3).map(|i| shown(a, i, s.x_est[i])));
        }
    }
}

/// The signals a controller kind logs.
struct SignalsOf;

impl crate::scenario::Visit for SignalsOf {
    type Out = &'static [ehservo_core::control::Signal];
    fn visit<K: crate::scenario::ControllerConfig>(self, _: &K) -> Self::Out {
        use ehservo_core::control::{Config, Controller, Signals};
        <<K as Config>::Controller as Controller>::Parts::SIGNALS
    }
}

/// Streams samples into `trace.csv`: the header through the csv crate,
/// the rows (numbers only, which never need quoting) straight into the
/// writer, each number printed as `{}` prints it ([`decimal`]).
struct TraceWriter<W: std::io::Write> {
    w: W,
    layout: TraceLayout,
    row: Vec<f64>,
    line: Vec<u8>,
    scratch: Vec<u8>,
}

impl<W: std::io::Write> TraceWriter<W> {
    fn new(inner: W, layout: TraceLayout) -> Result<Self> {
        let mut w = csv::Writer::from_writer(inner);
        w.write_record(&layout.columns)?;
        let w = w
            .into_inner()
            .map_err(|e| anyhow::anyhow!("writing trace.csv: {e}"))?;
        Ok(Self {
            w,
            layout,
            row: Vec::new(),
            line: Vec::new(),
            scratch: Vec::new(),
        })
    }

    fn write(&mut self, s: &Sample) -> Result<()> {
        self.layout.row(s, &mut self.row);
        // The loop stops before a non-finite sample is logged; this is the
        // last line of defence for the "never NaN in a CSV" rule.
        if self.row.iter().any(|v| !v.is_finite()) {
            anyhow::bail!(
                "internal error: non-finite value in the trace at t = {}",
                s.t
            );
        }
        self.line.clear();
        for (i, &v) in self.row.iter().enumerate() {
            if i > 0 {
                self.line.push(b',');
            }
            decimal::push_display(&mut self.line, v, &mut self.scratch);
        }
        self.line.push(b'\n');
        self.w.write_all(&self.line)?;
        Ok(())
    }

    fn finish(self) -> Result<W> {
        Ok(self.w)
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary<'a> {
    /// Name and version of the software.
    pub software: Software,
    /// The scenario as run (defaults and overrides resolved).
    pub scenario: &'a Scenario,
    /// SPEC §9 metrics.
    pub metrics: Metrics,
    /// How the run ended early, if it did.
    pub divergence: Option<DivergenceInfo>,
    /// Numerical guards that fired.
    pub faults: Faults,
    /// What the run did besides its errors ([`crate::behaviour`]):
    /// end-stop contacts, the saturation share, the error's oscillation
    /// after the transient.
    pub behaviour: crate::behaviour::Behaviour,
    /// The verdict: `["bounded"]`, or the findings in order (`unbounded`,
    /// `hit-end-stop`, `oscillating`, `saturated`), as `ehservo run`
    /// prints them.
    pub verdict: Vec<&'static str>,
    /// Quantities derived from the scenario.
    pub derived: Derived,
    /// What the theory says about the scenario (`ehservo analyze`).
    pub analysis: crate::analysis::Analysis,
    /// Condition 4) of Theorem 3 and the dead zone along this run (NNBVSC,
    /// when the trace was kept).
    pub diagnostics: Option<crate::analysis::RunDiagnostics>,
    /// How the plant was integrated: the solver, and an adaptive one's
    /// tolerances and step counts.
    pub solver: SolverInfo,
    /// Where the controller ran when not in the simulator itself: the
    /// float type, the board, the link's faults ([`crate::pil`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offboard: Option<serde_json::Value>,
}

/// `summary.json`'s `solver`: `{"kind": "rk4"}`, or an adaptive solver
/// with its tolerances as run and its steps.
#[derive(Debug, Clone, Serialize)]
pub struct SolverInfo {
    /// `"rk4"`, `"dopri5"`, `"bs32"`.
    pub kind: &'static str,
    /// The relative tolerance (adaptive).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// The absolute tolerance: one value, or one per plant state (adaptive).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atol: Option<Vec<f64>>,
    /// The largest step (s) (adaptive).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
    /// Steps accepted over the run (adaptive).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accepted_steps: Option<u64>,
    /// Steps tried and rejected over the run (adaptive).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rejected_steps: Option<u64>,
    /// Where a stiff method's Jacobian comes from: `"finite-difference"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jacobian: Option<&'static str>,
}

/// How summary.json and the run's line name a Jacobian by differences.
pub const JACOBIAN_FD: &str = "finite-difference";

impl SolverInfo {
    /// The solver of `lp` and the steps of the run that ended in `outcome`.
    pub fn of(lp: &Loop, outcome: &crate::simulation::Outcome) -> Self {
        match lp.settings().adaptive() {
            None => Self {
                kind: lp.scenario().simulation.solver.as_str(),
                rtol: None,
                atol: None,
                max_step: None,
                accepted_steps: None,
                rejected_steps: None,
                jacobian: None,
            },
            Some(a) => Self {
                kind: a.kind().as_str(),
                rtol: Some(a.rtol()),
                atol: Some(a.atol().values().to_vec()),
                max_step: Some(a.max_step()),
                accepted_steps: Some(outcome.solver_steps.accepted),
                rejected_steps: Some(outcome.solver_steps.rejected),
                jacobian: a.scheme().needs_jacobian().then_some(JACOBIAN_FD),
            },
        }
    }
}

/// A divergence, with a sentence.
#[derive(Debug, Clone, Serialize)]
pub struct DivergenceInfo {
    /// When (s).
    pub t: f64,
    /// Machine-readable reason.
    pub reason: crate::simulation::DivergenceReason,
    /// Human sentence.
    pub message: String,
}

impl From<Divergence> for DivergenceInfo {
    fn from(d: Divergence) -> Self {
        Self {
            t: d.t,
            reason: d.reason,
            message: format!("unbounded at t = {:.4} s: {}", d.t, d.reason.describe()),
        }
    }
}

/// Counts of guarded numerical faults.
#[derive(Debug, Clone, Serialize)]
pub struct Faults {
    /// Samples where Ps − sgn(u)·Pl < 0 in the law's valve root (clamped).
    pub valve_root_clamped_samples: u64,
    /// Samples where ‖E‖ = 0 (σΔ, μ, ξ set to 0).
    pub zero_error_norm_samples: u64,
    /// Samples where the command exceeded the valve range (only when there is one).
    #[serde(skip_serializing_if = "is_zero")]
    pub saturated_samples: u64,
    /// Samples where the sampled loop refused a measurement (only when any did).
    #[serde(skip_serializing_if = "is_zero")]
    pub measurement_fault_samples: u64,
}

fn is_zero(v: &u64) -> bool {
    *v == 0
}

/// Derived quantities worth having next to the results.
#[derive(Debug, Clone, Serialize)]
pub struct Derived {
    /// ā1, ā2, ā3.
    pub a_nominal: [f64; 3],
    /// b̄ at Pl = 0 (s⁻³V⁻¹).
    pub b_at_rest: f64,
    /// p1, p2, p3 of the surface.
    pub p: [f64; 3],
    /// Number of steps N.
    pub steps: u64,
}

/// Builds the summary of a run (its diagnostics from the run's trace).
pub fn summary<'a>(lp: &'a Loop, run: &RunResult) -> Summary<'a> {
    summary_with(
        lp,
        run,
        crate::analysis::diagnostics(lp.scenario(), &run.trace),
    )
}

/// [`summary`] with the run's diagnostics given (as a
/// [`crate::analysis::DiagRecorder`] collected them).
pub fn summary_with<'a>(
    lp: &'a Loop,
    run: &RunResult,
    diagnostics: Option<crate::analysis::RunDiagnostics>,
) -> Summary<'a> {
    let model = lp.model();
    Summary {
        software: SOFTWARE,
        scenario: lp.scenario(),
        metrics: run.metrics,
        divergence: run.outcome.diverged.map(Into::into),
        faults: Faults {
            valve_root_clamped_samples: run.outcome.valve_root_clamped,
            zero_error_norm_samples: run.outcome.zero_error_norm,
            saturated_samples: run.outcome.saturated,
            measurement_fault_samples: run.outcome.measurement_faults,
        },
        behaviour: run.metrics.behaviour,
        verdict: verdict(&run.metrics),
        derived: Derived {
            a_nominal: model.coeffs.as_array(),
            b_at_rest: model.b_at_rest(),
            p: lp.design().surface.p(),
            steps: lp.sim().steps,
        },
        analysis: crate::analysis::analyze(lp),
        diagnostics,
        solver: SolverInfo::of(lp, &run.outcome),
        offboard: None,
    }
}

/// The verdict of a run's metrics: `["bounded"]` or the names of its
/// findings ([`crate::behaviour::Behaviour::findings`]).
pub fn verdict(m: &Metrics) -> Vec<&'static str> {
    let f = m.behaviour.findings(m.diverged);
    if f.is_empty() {
        vec!["bounded"]
    } else {
        f.iter().map(|f| f.name()).collect()
    }
}

/// Most samples kept in memory by [`run_to_dir`] (for the plot and the
/// run diagnostics); the CSV gets every `output.decimate`-th sample however
/// long the run.
pub const MAX_KEPT: u64 = 200_000;

/// Runs a scenario and writes its outputs into `dir` as it goes: the trace
/// is streamed to `trace.csv` (so a run of millions of steps needs no
/// memory for it), a bounded subsample is kept for `trace.png` and the
/// diagnostics. Returns the result and the files; the result's trace is
/// the kept subsample when `plot`, else empty (without a plot only the
/// few numbers of each kept sample that the diagnostics read are kept,
/// [`crate::analysis::DiagRecorder`]: the same summary.json).
pub fn run_to_dir(dir: &Path, lp: &Loop, plot: bool) -> Result<(RunResult, Vec<PathBuf>)> {
    run_to_dir_with(dir, lp, plot, &mut InSimulator)
}

/// How [`run_to_dir_with`] runs the loop, and what it adds to the output:
/// the hook of the off-board runs ([`crate::pil`]: `ehservo run --float
/// f32`, `ehservo pil`).
pub trait RunHooks {
    /// Runs `lp`, handing every sample to `observe`; `stage` is the staging
    /// folder, for files written as the run goes.
    fn run(
        &mut self,
        lp: &Loop,
        stage: &Path,
        observe: &mut dyn FnMut(&Sample),
    ) -> Result<(crate::simulation::Outcome, Metrics)>;
    /// After the run: writes its own files into `stage` and returns their
    /// names and the summary's `offboard` section.
    fn finish(&mut self, stage: &Path) -> Result<(Vec<&'static str>, Option<serde_json::Value>)>;
}

/// The ordinary run: the scenario's loop in the simulator.
struct InSimulator;

impl RunHooks for InSimulator {
    fn run(
        &mut self,
        lp: &Loop,
        _stage: &Path,
        observe: &mut dyn FnMut(&Sample),
    ) -> Result<(crate::simulation::Outcome, Metrics)> {
        Ok(crate::run::run_observed(lp, observe))
    }
    fn finish(&mut self, _stage: &Path) -> Result<(Vec<&'static str>, Option<serde_json::Value>)> {
        Ok((Vec::new(), None))
    }
}

/// [`run_to_dir`] with the loop run by `hooks`, and their files and
/// summary section added.
pub fn run_to_dir_with(
    dir: &Path,
    lp: &Loop,
    plot: bool,
    hooks: &mut dyn RunHooks,
) -> Result<(RunResult, Vec<PathBuf>)> {
    let s = lp.scenario();
    let stage = Staging::new(dir)?;
    let csv_path = stage.path().join("trace.csv");
    let file =
        fs::File::create(&csv_path).with_context(|| format!("creating {}", csv_path.display()))?;
    let mut w = TraceWriter::new(
        std::io::BufWriter::with_capacity(1 << 16, file),
        TraceLayout::of(lp),
    )?;
    let decimate = s.output.decimate.max(1) as u64;
    let steps = lp.sim().steps;
    let keep_every = decimate.max((steps + 1).div_ceil(MAX_KEPT));
    let capacity = ((steps + 1) / keep_every + 2) as usize;
    // The samples the plot and the diagnostics see: every keep_every-th
    // and the last. Whole samples only for the plot (about 460 bytes
    // each, most of a short run's memory); the diagnostics' numbers of
    // each in any case.
    let mut kept = Vec::with_capacity(if plot { capacity } else { 0 });
    let mut diag = crate::analysis::DiagRecorder::new(s, capacity);
    let mut keep = Decimate::every(keep_every);
    let mut failure: Option<anyhow::Error> = None;
    let (outcome, metrics) = hooks.run(lp, stage.path(), &mut |smp| {
        if failure.is_none() && smp.k % decimate == 0 {
            if let Err(e) = w.write(smp) {
                failure = Some(e.context(format!("writing {}", dir.join("trace.csv").display())));
            }
        }
        if let Some(smp) = keep.offer(smp) {
            if plot {
                kept.push(*smp);
            }
            diag.push(smp);
        }
    })?;
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(l) = keep.finish() {
        if plot {
            kept.push(l);
        }
        diag.push(&l);
    }
    let writing = || format!("writing {}", dir.join("trace.csv").display());
    let mut inner = w.finish().with_context(writing)?;
    inner.flush().with_context(writing)?;
    let run = RunResult {
        outcome,
        metrics,
        trace: kept,
    };
    let mut files = vec!["trace.csv", "summary.json"];
    let (extra, offboard) = hooks.finish(stage.path())?;
    files.extend(extra);
    let mut summary = summary_with(lp, &run, diag.finish(s));
    summary.offboard = offboard;
    let json = serde_json::to_string_pretty(&summary)?;
    // Straight into the staging folder, which is what makes the output
    // whole or absent (write_atomic's own temporary file, rename and fsync
    // would add nothing to that, and its fsync cost more than the rest of
    // the file system work; trace.csv beside it is not synced either).
    let summary_path = stage.path().join("summary.json");
    fs::write(&summary_path, json.as_bytes())
        .with_context(|| format!("writing {}", summary_path.display()))?;
    if plot {
        trace_figure(lp, &run).png(&stage.path().join("trace.png"))?;
        files.push("trace.png");
    }
    stage.commit()?;
    Ok((run, files.iter().map(|f| dir.join(f)).collect()))
}
