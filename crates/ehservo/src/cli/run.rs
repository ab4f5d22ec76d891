//! `ehservo run`, `pil`, `analyze` and `check`: one scenario, simulated (here
//! or with its controller on a board), analysed or checked; and the summary
//! `run` and `pil` print.

use super::{default_out, load, StdoutError};
use crate::output;
use crate::run::Keep;
use crate::scenario::Loop;
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `ehservo run`.
#[derive(clap::Args)]
pub(super) struct RunArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// Output directory (default: out/<scenario name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a key, e.g. --set controller.gamma1=200 (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Do not write trace.png.
    #[arg(long)]
    no_plot: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// The controller's float type: f64 (the simulator's own) or f32
    /// (the PIL board's code, computed here: what `ehservo pil` must
    /// match to the bit).
    #[arg(long, default_value = "f64", value_parser = ["f32", "f64"])]
    float: String,
}

/// `ehservo pil`.
#[derive(clap::Args)]
pub(super) struct PilArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// Output directory (default: out/<scenario name>-pil).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Start QEMU (mps2-an386) with the PIL firmware, and stop it at the end.
    #[arg(long, conflicts_with = "port")]
    qemu: bool,
    /// A real board's serial port (e.g. /dev/ttyACM0).
    #[arg(long)]
    port: Option<String>,
    /// The serial port's rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Reach the board over TCP at HOST:PORT (a proxy, a QEMU started elsewhere, a serial server).
    #[arg(long, value_name = "HOST:PORT")]
    connect: Option<String>,
    /// With --qemu: listen here for QEMU's UART (or a proxy in front of it) to connect.
    #[arg(long, value_name = "HOST:PORT")]
    listen: Option<String>,
    /// With --qemu: QEMU's -serial backend, verbatim (e.g. tcp:127.0.0.1:5556,server=on,wait=on with --connect to a proxy).
    #[arg(long, value_name = "SPEC")]
    qemu_serial: Option<String>,
    /// The firmware ELF (default: target/thumbv7em-none-eabihf/release/ehservo-firmware-pil).
    #[arg(long)]
    firmware: Option<PathBuf>,
    /// The float type the board computes in.
    #[arg(long, default_value = "f32", value_parser = ["f32", "f64"])]
    float: String,
    /// How long to wait for each reply (ms) before applying the fault policy.
    #[arg(long, default_value_t = 200.0)]
    timeout_ms: f64,
    /// How long to wait for the board to connect and answer the handshake (s), 0 < S <= 3600.
    #[arg(long, value_name = "SECONDS", default_value_t = 20.0)]
    handshake_timeout: f64,
    /// Inject a fault between host and board at sample K (testing): KIND@K with KIND one of corrupt-request, corrupt-reply, drop-request, drop-reply, late-reply, reset-board (repeatable).
    #[arg(long, value_name = "KIND@K")]
    inject: Vec<String>,
    /// Do not write trace.png.
    #[arg(long)]
    no_plot: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

/// `ehservo analyze`.
#[derive(clap::Args)]
pub(super) struct AnalyzeArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Also run the scenario and report condition 4) of Theorem 3 and the dead zone along the run.
    #[arg(long)]
    run: bool,
}

/// `ehservo check`.
#[derive(clap::Args)]
pub(super) struct CheckArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
}

/// `ehservo run`.
pub(super) fn run(a: RunArgs, w: &mut impl Write) -> Result<()> {
    let RunArgs {
        scenario,
        out,
        set,
        no_plot,
        quiet,
        float,
    } = a;
    let lp = load(&scenario, &set)?;
    if !quiet {
        warn(&scenario, &lp);
    }
    let s = lp.scenario();
    let dir = match out {
        Some(d) => d,
        None => default_out(&s.name)?,
    };
    let start = Instant::now();
    let rows = lp.sim().steps / s.output.decimate.max(1) as u64 + 1;
    if rows > 2_000_000 && !quiet {
        note!(
            "note: trace.csv will have {rows} rows (about {} MB); set output.decimate to thin it",
            rows * 300 / 1_000_000
        );
    }
    let plot = s.output.plot && !no_plot;
    let (r, files) = if float == "f32" {
        let opts = crate::pil::Options::in_process(ehservo_wire_float(&float));
        let (r, files, _) = crate::pil::run_to_dir(&dir, &lp, plot, opts)?;
        (r, files)
    } else {
        output::run_to_dir(&dir, &lp, plot)?
    };
    let elapsed = start.elapsed();
    if !quiet {
        print_summary(w, &lp, &r, elapsed.as_secs_f64())?;
        if float == "f32" {
            out!(
                w,
                "  controller in f32 (the PIL board's code, on this host)"
            );
        }
        let names: Vec<String> = files
            .iter()
            .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        out!(w, "wrote {}/{{{}}}", dir.display(), names.join(", "));
    }
    Ok(())
}

/// `ehservo pil`.
pub(super) fn pil(a: PilArgs, w: &mut impl Write) -> Result<()> {
    let PilArgs {
        scenario,
        out,
        set,
        qemu,
        port,
        baud,
        connect,
        listen,
        qemu_serial,
        firmware,
        float,
        timeout_ms,
        handshake_timeout,
        inject,
        no_plot,
        quiet,
    } = a;
    use crate::pil::{Options, Target};
    // The link's flags first: a board address that cannot be one is
    // refused before any work (it was once retried to the deadline).
    if let Some(addr) = &connect {
        crate::pil::check_address(addr)?;
    }
    if !(handshake_timeout.is_finite() && handshake_timeout > 0.0 && handshake_timeout <= 3600.0) {
        crate::bad_input!(
            "--handshake-timeout {handshake_timeout}: must be > 0 and at most 3600 s"
        );
    }
    let lp = load(&scenario, &set)?;
    if !quiet {
        warn(&scenario, &lp);
    }
    let s = lp.scenario();
    let dir = match out {
        Some(d) => d,
        None => default_out(&format!("{}-pil", s.name))?,
    };
    if !(timeout_ms.is_finite() && timeout_ms > 0.0 && timeout_ms <= 60_000.0) {
        crate::bad_input!("--timeout-ms {timeout_ms}: must be > 0 and at most 60000");
    }
    let mut plan = Vec::new();
    for i in &inject {
        match crate::pil::transport::Inject::parse(i) {
            Some(p) => plan.push((p.1, p.0)),
            None => crate::bad_input!(
                "--inject {i}: expected KIND@K, KIND one of corrupt-request, corrupt-reply, drop-request, drop-reply, late-reply, reset-board"
            ),
        }
    }
    if !qemu && (listen.is_some() || qemu_serial.is_some() || firmware.is_some()) {
        crate::bad_input!("--listen, --qemu-serial and --firmware go with --qemu");
    }
    let target = match (qemu, port, connect) {
        (true, None, connect) => Target::Qemu {
            firmware,
            serial: qemu_serial,
            connect,
            listen,
        },
        (false, Some(path), None) => Target::Port { path, baud },
        (false, None, Some(addr)) => Target::Connect(addr),
        (false, Some(_), Some(_)) => {
            crate::bad_input!("--port and --connect: give one board")
        }
        _ => crate::bad_input!(
            "say where the board is: --qemu, --port /dev/ttyX or --connect HOST:PORT"
        ),
    };
    let opts = Options {
        target,
        float: ehservo_wire_float(&float),
        timeout: std::time::Duration::from_secs_f64(timeout_ms / 1e3),
        handshake_timeout: std::time::Duration::from_secs_f64(handshake_timeout),
        inject: plan,
    };
    let start = Instant::now();
    let (r, files, rep) = crate::pil::run_to_dir(&dir, &lp, s.output.plot && !no_plot, opts)?;
    let elapsed = start.elapsed();
    let o = &rep.offboard;
    if !quiet {
        print_summary(w, &lp, &r, elapsed.as_secs_f64())?;
        out!(
            w,
            "  PIL over {}: {} ({} samples in {:.2} s: {:.0} samples/s; round trip mean {:.0} µs, max {:.0} µs)",
            o["transport"].as_str().unwrap_or("?"),
            o["firmware"].as_str().unwrap_or("?"),
            o["samples"],
            o["wall_s"].as_f64().unwrap_or(0.0),
            o["samples_per_s"].as_f64().unwrap_or(0.0),
            o["rtt_us"]["mean"].as_f64().unwrap_or(0.0),
            o["rtt_us"]["max"].as_f64().unwrap_or(0.0),
        );
        out!(
            w,
            "  board step ({}): mean {:.0} cycles, max {:.0} cycles",
            o["float"].as_str().unwrap_or("?"),
            o["step_cycles"]["mean"].as_f64().unwrap_or(0.0),
            o["step_cycles"]["max"].as_f64().unwrap_or(0.0),
        );
        let names: Vec<String> = files
            .iter()
            .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        out!(w, "wrote {}/{{{}}}", dir.display(), names.join(", "));
    }
    if let Some(events) = o["events"].as_array() {
        for e in events.iter().take(20) {
            note!(
                "link fault at k = {}: {} ({})",
                e["k"],
                e["fault"].as_str().unwrap_or("?"),
                e["detail"].as_str().unwrap_or("")
            );
        }
        if events.len() > 20 {
            note!(
                "… {} link faults in all: see summary.json",
                o["link_faults"]
            );
        }
    }
    if let Some(lost) = o["link_lost"].as_str() {
        anyhow::bail!(
            "the link to the board was lost ({lost}); the outputs in {} record the run with the fault policy's command from then on",
            dir.display()
        );
    }
    Ok(())
}

/// `ehservo analyze`.
pub(super) fn analyze(a: AnalyzeArgs, w: &mut impl Write) -> Result<()> {
    let AnalyzeArgs {
        scenario,
        set,
        json,
        run: with_run,
    } = a;
    let lp = load(&scenario, &set)?;
    let s = lp.scenario();
    let a = crate::analysis::analyze(&lp);
    let diag = if with_run {
        // Diagnostics over at most MAX_KEPT samples (every one for runs up to that).
        let stride = (lp.sim().steps + 1).div_ceil(output::MAX_KEPT).max(1);
        let r = crate::run::run(&lp, Keep::Every(stride as u32));
        Some((
            crate::analysis::diagnostics(s, &r.trace),
            r.outcome.diverged,
        ))
    } else {
        None
    };
    if json {
        let v = serde_json::json!({
            "scenario": s.name,
            "analysis": a,
            "diagnostics": diag.as_ref().and_then(|d| d.0.clone()),
            "diverged_at_s": diag.as_ref().and_then(|d| d.1.map(|x| x.t)),
        });
        out!(w, "{}", serde_json::to_string_pretty(&v)?);
    } else {
        out!(w, "{} ({})\n", s.name, scenario.display());
        put!(w, "{}", a.to_text());
        match diag {
            Some((Some(d), div)) => {
                out!(w);
                put!(w, "{}", d.to_text());
                if let Some(dv) = div {
                    out!(w, "  (the run was unbounded at t = {:.4} s)", dv.t);
                }
            }
            Some((None, _)) => out!(w, "\n(--run: condition 4) concerns the NNBVSC only)"),
            None => {}
        }
    }
    Ok(())
}

/// `ehservo check`.
pub(super) fn check(a: CheckArgs, w: &mut impl Write) -> Result<()> {
    let CheckArgs { scenario, set } = a;
    let lp = load(&scenario, &set)?;
    warn(&scenario, &lp);
    put!(w, "{}", lp.scenario().to_toml());
    // What the design filled in, as comments: the file stays the same
    // scenario (a comment does not pin gains to this plant).
    let designed = lp.designed();
    if !designed.is_empty() {
        put!(
            w,
            "# [controller] as designed on this axis's nominal model (not written, derived at each build):\n"
        );
        for (k, v) in &designed {
            put!(
                w,
                "#   {k} = {v:e}  # {}\n",
                designed_unit(k, lp.axis().si_unit())
            );
        }
    }
    note!("{}: ok ({} steps)", scenario.display(), lp.sim().steps);
    note!("{}", axis_line(&lp));
    Ok(())
}

/// The unit of a designed controller key ([`Loop::designed`]) on an axis
/// whose position is in `si` (rad or m).
pub(crate) fn designed_unit(key: &str, si: &str) -> String {
    match key {
        "kp" => format!("V/{si}"),
        "ki" => format!("V/({si}·s)"),
        "kd" => format!("V·s/{si}"),
        "filter_time" | "tracking_time" => "s".into(),
        "omega_c" | "omega_o" | "frequency" => "rad/s".into(),
        "pole" => "1/s".into(),
        "b0" => format!("{si}/(V·s³)"),
        _ => "as the kind's reference gives it".into(),
    }
}

/// The nominal third-order model the designs start from, in one line
/// ([`Loop::model_summary`]), with ω_h·h: the sample period against the
/// resonance (above 1 no sampled law can act on it).
pub(crate) fn axis_line(lp: &Loop) -> String {
    let a2 = lp.model().coeffs.as_array()[1];
    let mut s = lp.model_summary();
    if a2 > 0.0 && a2.is_finite() {
        s.push_str(&format!(", ω_h·h = {:.3}", a2.sqrt() * lp.design().dt));
    }
    s
}

/// The scenario's warnings ([`Loop::warnings`]) on stderr, one line each.
fn warn(file: &std::path::Path, lp: &Loop) {
    for wn in lp.warnings() {
        note!("warning: {}: {wn}", file.display());
    }
}

/// `--float`'s value (checked by clap).
fn ehservo_wire_float(s: &str) -> ehservo_wire::msg::FloatType {
    crate::pil::parse_float(s).unwrap_or(ehservo_wire::msg::FloatType::F64)
}

fn fmt_opt(v: Option<f64>, digits: usize, unit: &str) -> String {
    match v {
        Some(x) => format!("{x:.digits$}{unit}"),
        None => "—".into(),
    }
}

fn print_summary(
    w: &mut impl Write,
    lp: &Loop,
    r: &crate::run::RunResult,
    secs: f64,
) -> Result<()> {
    let s = lp.scenario();
    let m = &r.metrics;
    let unit = m.axis.suffix();
    let sim = &s.simulation;
    // What the run did besides diverging: the verdict names each.
    let findings = m.behaviour.findings(false);
    out!(
        w,
        "{}: {} on the {} plant, {} (h = {} s{}), horizon {} s",
        s.name,
        s.controller.kind(),
        s.plant.model(),
        sim.mode.as_str(),
        sim.step,
        if sim.mode == crate::simulation::Mode::Sampled
            && sim.solver == crate::simulation::SolverKind::Rk4
        {
            format!(", {} RK4 substep(s)", sim.substeps)
        } else if sim.mode == crate::simulation::Mode::Sampled {
            format!(
                ", {}: {} steps accepted, {} rejected{}",
                sim.solver.as_str(),
                r.outcome.solver_steps.accepted,
                r.outcome.solver_steps.rejected,
                if sim.solver.scheme().is_some_and(|s| s.needs_jacobian()) {
                    format!(", {} Jacobian", crate::output::JACOBIAN_FD)
                } else {
                    String::new()
                }
            )
        } else {
            String::new()
        },
        sim.horizon
    );
    match r.outcome.diverged {
        Some(d) => {
            out!(
                w,
                "  UNBOUNDED at t = {:.4} s: {}",
                d.t,
                d.reason.describe()
            );
            // The hint `ehservo analyze` gives: is the scheme itself unstable?
            if let Some(warning) = crate::analysis::analyze(lp).closed_loop.warning {
                out!(w, "  hint: {warning}");
            }
        }
        // A run with findings is not called bounded: they are its verdict.
        None if findings.is_empty() => out!(w, "  bounded over the horizon"),
        None => {}
    }
    for line in behaviour_lines(&m.behaviour, &findings, unit) {
        out!(w, "  {line}");
    }
    if lp.is_open() {
        out!(
            w,
            "  open loop: the reference is a command (u = volts_per_{} · r), not a position: no tracking error, and no oscillation is the loop's own",
            m.axis.unit()
        );
    }
    out!(
        w,
        "  e_max   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_max, 4, unit)
    );
    out!(w, "  e_final (last period) {}", fmt_opt(m.e_final, 4, unit));
    out!(
        w,
        "  e_rms   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_rms, 4, unit)
    );
    out!(w, "  u_max                 {}", fmt_opt(m.u_max, 3, " V"));
    out!(
        w,
        "  chattering c[u]       {}",
        fmt_opt(m.chattering, 4, "")
    );
    if m.w_norm_max.is_some() {
        out!(
            w,
            "  ‖W‖ max / final       {} / {}",
            fmt_opt(m.w_norm_max, 3, ""),
            fmt_opt(m.w_norm_final, 3, "")
        );
        out!(
            w,
            "  dead-zone share       {}",
            fmt_opt(m.dead_zone_fraction.map(|f| 100.0 * f), 1, " %")
        );
    }
    out!(
        w,
        "  {} samples simulated in {:.1} ms",
        m.samples,
        secs * 1e3
    );
    Ok(())
}

/// One line per finding of a run's verdict (after its first line), naming
/// the numbers: the end stops' contacts, the oscillation's amplitude and
/// period, the saturation share.
pub(crate) fn behaviour_lines(
    b: &crate::behaviour::Behaviour,
    findings: &[crate::behaviour::Finding],
    unit: &str,
) -> Vec<String> {
    use crate::behaviour::Finding;
    let mut v = Vec::new();
    for f in findings {
        match f {
            Finding::HitEndStop => {
                if let Some(e) = b.end_stops {
                    v.push(format!(
                        "HIT AN END STOP: {} contact(s), the first at t = {} s, {:.4} s in contact",
                        e.contacts,
                        fmt_opt(e.first_s, 4, ""),
                        e.time_s
                    ));
                }
            }
            Finding::Oscillating => {
                if let Some(o) = b.oscillation {
                    v.push(format!(
                        "SUSTAINED OSCILLATION after the transient: amplitude {:.4}{unit}, period {} s ({} Hz), {} cycles, last/first amplitude {}",
                        o.amplitude,
                        fmt_opt(o.period_s, 4, ""),
                        fmt_opt(o.period_s.map(|p| 1.0 / p), 2, ""),
                        o.cycles,
                        fmt_opt(o.decay, 3, "")
                    ));
                }
            }
            Finding::Saturated => {
                if let Some(sh) = b.saturation_share {
                    v.push(format!(
                        "SATURATED: the command at its limit in {:.1} % of the samples (more than {:.0} %)",
                        100.0 * sh,
                        100.0 * crate::behaviour::SATURATION_SHARE_LIMIT
                    ));
                }
            }
            Finding::Unbounded => {}
        }
    }
    v
}
