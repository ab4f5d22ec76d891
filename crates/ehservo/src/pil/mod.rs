//! Processor-in-the-loop: the scenario's controller on a board (QEMU's
//! emulated Cortex-M4F, or a real one on a serial port), everything else
//! — plant, valve, sensors, estimator, delays — simulated here, in
//! lock-step, one frame each way per sample (`ehservo pil`). The same
//! machinery with the board's code in this process is the host's f32 mode
//! (`ehservo run --float f32`), the trace a PIL run must give to the bit.
//!
//! How it fits the simulator: the [`Simulation`](crate::simulation) runs
//! as always; its controller is an [`offboard::Offboard`], whose
//! `law_euler` is one exchange ([`session::Session::exchange`]). The
//! board runs the scenario's `SampledController` (the fault policy's
//! checks and clamp in the board's float type); the simulator's own loop
//! keeps only the finiteness check, with the same safe command. A link
//! fault (corrupted, dropped or late frame, a board reset) gives the safe
//! command, flagged [`flags::LINK_FAULT`], and the board undoes the step
//! whose reply was not used ([`ehservo_wire::board`]). The protocol, the
//! byte budget and the commands: docs/pil.md.

pub mod offboard;
pub mod qemu;
pub mod session;
pub mod transport;

use crate::metrics::Metrics;
use crate::output::RunHooks;
use crate::run::RunResult;
use crate::scenario::{ControllerCfg, ControllerConfig, Loop, Scenario, Visit};
use crate::simulation::{Mode, Outcome, Sample};
use anyhow::{Context, Result};
use ehservo_core::control::{flags, Config, Controller, Signals};
use ehservo_core::sampled::{Limits, SafeCommand};
use ehservo_core::servo::NominalModel;
use ehservo_core::surface::SwitchingSurface;
use ehservo_wire::config::WireController;
use ehservo_wire::law::AnyLaw;
use ehservo_wire::msg::{FloatType, Hello, ModelInputs, TickSource, WirePolicy};
use ehservo_wire::{fnv1a, PROTOCOL_VERSION};
use offboard::{Link, OnBoard, Shadow};
use session::{Record, Session};
use std::cell::RefCell;
use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};
use transport::{Faulty, InProcess, Inject, Transport};

/// The registry's kind as the wire carries it (generated from the one
/// list of kinds, as the wire's enum is).
pub fn wire_controller(c: &ControllerCfg) -> WireController {
    c.wire()
}

struct SignalCount;

impl Visit for SignalCount {
    type Out = usize;
    fn visit<K: ControllerConfig>(self, _: &K) -> usize {
        <<K as Config>::Controller as Controller>::Parts::SIGNALS.len()
    }
}

/// The scenario's fingerprint in the handshake: FNV-1a of its resolved
/// TOML (what `ehservo check` prints).
pub fn scenario_hash(s: &Scenario) -> u64 {
    fnv1a(s.to_toml().as_bytes())
}

/// The handshake of a built scenario: the controller, what it is designed
/// from (the nominal model's constructor inputs, the surface, the sample
/// period), the fault policy. Fails when the scenario cannot run off-board
/// (the continuous mode) or when the design has something the wire does
/// not carry.
pub fn hello(lp: &Loop, float: FloatType) -> Result<Hello> {
    if lp.sim().mode != Mode::Sampled {
        crate::bad_input!(
            "`simulation.mode` = \"{}\": an off-board controller runs in the sampled loop; set simulation.mode = \"sampled\"",
            lp.sim().mode.as_str()
        );
    }
    let d = lp.design();
    // The wire carries the model as its constructor's inputs: the board
    // must rebuild exactly the model the host designs with.
    let model = ModelInputs {
        params: d.model.params,
        load: d.model.load,
        offset: d.model.offset(),
    };
    anyhow::ensure!(
        NominalModel::with_offset(model.params, model.load, model.offset) == d.model,
        "internal: the nominal model has inputs the PIL handshake does not carry (ehservo_wire::msg::ModelInputs)"
    );
    anyhow::ensure!(
        SwitchingSurface::try_new(d.surface.p()).ok() == Some(d.surface),
        "internal: the switching surface is more than its p1, p2, p3"
    );
    // (Design::dt is the simulation step: t_k = k·h on both sides.)
    anyhow::ensure!(
        d.dt.to_bits() == lp.sim().step.to_bits(),
        "internal: the design's sample period differs from the simulation step"
    );
    let p = &lp.stages().policy;
    let signals = lp.controller().visit(SignalCount);
    Ok(Hello {
        protocol: PROTOCOL_VERSION,
        scenario_hash: scenario_hash(lp.scenario()),
        float,
        dt: lp.sim().step,
        controller: lp.controller().wire(),
        model,
        surface: d.surface.p(),
        policy: WirePolicy {
            hold_last: p.safe == SafeCommand::HoldLast,
            limits_x: p.limits.x,
            limit_u: p.limits.u,
        },
        signals: u8::try_from(signals).context("too many signals for the wire")?,
    })
}

/// Where the board is.
#[derive(Debug, Clone)]
pub enum Target {
    /// The board's code in this process (`ehservo run --float`).
    InProcess,
    /// QEMU started here with the PIL firmware.
    Qemu {
        /// The firmware ELF (default: [`qemu::default_firmware`]).
        firmware: Option<PathBuf>,
        /// QEMU's `-serial` backend, verbatim (default: a connection to
        /// this process's listener).
        serial: Option<String>,
        /// Connect here to reach the board (a proxy in front of QEMU's
        /// own server) instead of listening.
        connect: Option<String>,
        /// Listen here for QEMU, or a proxy, to connect (default: an
        /// ephemeral port on 127.0.0.1).
        listen: Option<String>,
    },
    /// A serial port.
    Port {
        /// Its device.
        path: String,
        /// Its rate.
        baud: u32,
    },
    /// A board reached over TCP (QEMU started elsewhere, a serial server).
    Connect(String),
}

/// How an off-board run goes.
#[derive(Debug, Clone)]
pub struct Options {
    /// Where the board is.
    pub target: Target,
    /// The float type the board computes in.
    pub float: FloatType,
    /// The reply deadline per sample.
    pub timeout: Duration,
    /// The handshake's deadline.
    pub handshake_timeout: Duration,
    /// Faults to inject between host and board (tests, CI).
    pub inject: Vec<(u32, Inject)>,
}

impl Options {
    /// The host's own f32 (or f64) computation of the board's controller.
    pub fn in_process(float: FloatType) -> Self {
        Self {
            target: Target::InProcess,
            float,
            timeout: Duration::from_millis(200),
            handshake_timeout: Duration::from_secs(10),
            inject: Vec::new(),
        }
    }
}

/// A `--connect` address as `HOST:PORT` with a port from 1 to 65535 that
/// resolves, or bad input naming the flag (exit 2, before any work: it
/// was once retried until the handshake's deadline).
///
/// ```
/// use ehservo::pil::check_address;
/// assert!(check_address("127.0.0.1:5555").is_ok());
/// for bad in ["127.0.0.1:99999", "127.0.0.1", "127.0.0.1:0", "[::1]:x"] {
///     let e = check_address(bad).unwrap_err();
///     assert!(e.to_string().starts_with(&format!("--connect {bad}: ")), "{e}");
/// }
/// ```
pub fn check_address(addr: &str) -> Result<(), crate::error::InputError> {
    use std::net::ToSocketAddrs;
    let bad = |why: String| {
        crate::error::InputError::Request(format!(
            "--connect {}: {why}",
            crate::input::quote_start(addr).trim_matches('`')
        ))
    };
    let Some((host, port)) = addr.rsplit_once(':') else {
        return Err(bad("expected HOST:PORT (e.g. 127.0.0.1:5555)".into()));
    };
    match port.parse::<u16>() {
        Ok(p) if p > 0 => {}
        _ => {
            return Err(bad(format!(
                "the port `{}` is not a number from 1 to 65535",
                port.chars().take(20).collect::<String>()
            )))
        }
    }
    if host.is_empty() {
        return Err(bad("expected HOST:PORT: the host is empty".into()));
    }
    match addr.to_socket_addrs().map(|mut a| a.next()) {
        Ok(Some(_)) => Ok(()),
        Ok(None) => Err(bad("resolves to no address".into())),
        Err(e) => Err(bad(format!("not an address: {e}"))),
    }
}

/// Accepts one connection before `deadline`, watching QEMU.
fn accept(l: &TcpListener, deadline: Instant, qemu: &mut Option<qemu::Qemu>) -> Result<TcpStream> {
    l.set_nonblocking(true)?;
    loop {
        match l.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(false)?;
                return Ok(s);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.into()),
        }
        if let Some(q) = qemu.as_mut() {
            if let Some(why) = q.exited() {
                anyhow::bail!("QEMU did not connect: {why}");
            }
        }
        if Instant::now() > deadline {
            anyhow::bail!("no connection on {} before the deadline", l.local_addr()?);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Connects to `addr`, retrying until `deadline` (QEMU's server or a proxy
/// may take a moment to listen).
fn connect(addr: &str, deadline: Instant, qemu: &mut Option<qemu::Qemu>) -> Result<TcpStream> {
    loop {
        match TcpStream::connect(addr) {
            Ok(s) => return Ok(s),
            Err(e) => {
                if let Some(q) = qemu.as_mut() {
                    if let Some(why) = q.exited() {
                        anyhow::bail!("QEMU stopped before {addr} answered: {why}");
                    }
                }
                if Instant::now() > deadline {
                    return Err(anyhow::Error::from(e).context(format!("connecting to {addr}")));
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}

/// The transport to the board, and QEMU if it was started here.
fn open_transport(opts: &Options) -> Result<(Box<dyn Transport>, Option<qemu::Qemu>)> {
    let deadline = Instant::now() + opts.handshake_timeout;
    let with_faults = |t: Box<dyn Transport>, reset: Option<Box<dyn transport::Reset>>| {
        if opts.inject.is_empty() {
            return t;
        }
        let f = Faulty::new(t, opts.inject.clone());
        Box::new(match reset {
            Some(r) => f.with_reset(r),
            None => f,
        }) as Box<dyn Transport>
    };
    match &opts.target {
        Target::InProcess => {
            let b = Rc::new(RefCell::new(InProcess::new()));
            let t = Box::new(transport::ResettableInProcess(Rc::clone(&b)));
            Ok((with_faults(t, Some(Box::new(b))), None))
        }
        Target::Port { path, baud } => {
            let p = transport::Serial::open(path, *baud)
                .map_err(|e| crate::error::InputError::Request(format!("--port {path}: {e}")))?;
            Ok((with_faults(Box::new(p), None), None))
        }
        Target::Connect(addr) => {
            let s = connect(addr, deadline, &mut None)?;
            Ok((with_faults(Box::new(transport::Tcp::new(s)?), None), None))
        }
        Target::Qemu {
            firmware,
            serial,
            connect: to,
            listen,
        } => {
            let fw = match firmware.clone().or_else(qemu::default_firmware) {
                Some(f) if f.is_file() => f,
                Some(f) => crate::bad_input!("--firmware {}: not found", f.display()),
                None => crate::bad_input!(
                    "the PIL firmware is not built: run `cargo build --release` in examples/firmware-pil (it needs `rustup target add thumbv7em-none-eabihf`), or pass --firmware PATH"
                ),
            };
            // This process listens unless it is told where to connect.
            let listener = match to {
                Some(_) => None,
                None => {
                    let addr = listen.as_deref().unwrap_or("127.0.0.1:0");
                    Some(TcpListener::bind(addr).map_err(|e| {
                        crate::error::InputError::Request(format!("--listen {addr}: {e}"))
                    })?)
                }
            };
            let spec = match (serial, &listener) {
                (Some(s), _) => s.clone(),
                (None, Some(l)) => format!("tcp:{},nodelay=on", l.local_addr()?),
                (None, None) => crate::bad_input!(
                    "--connect with --qemu: give QEMU's UART a server with --qemu-serial (e.g. tcp:127.0.0.1:5556,server=on,wait=on) for the proxy at --connect to reach"
                ),
            };
            let mut q = Some(qemu::Qemu::start(&fw, &spec)?);
            let stream = match (&listener, to) {
                (Some(l), _) => accept(l, deadline, &mut q)?,
                (None, Some(addr)) => connect(addr, deadline, &mut q)?,
                (None, None) => unreachable!(),
            };
            let reset = q.as_ref().map(|q| q.resetter());
            Ok((
                with_faults(Box::new(transport::Tcp::new(stream)?), reset),
                q,
            ))
        }
    }
}

/// What an off-board run adds to `run_to_dir`.
pub struct Hooks {
    opts: Options,
    link: Option<Rc<RefCell<Link>>>,
    qemu: Option<qemu::Qemu>,
    csv: Option<std::io::BufWriter<std::fs::File>>,
    step: f64,
    started: Option<Instant>,
    wall: f64,
    samples: u64,
    max_ticks: u32,
    sum_ticks: f64,
    n_ticks: u64,
    rtt_sum: f64,
    rtt_max: f64,
    n_rtt: u64,
    error: Option<anyhow::Error>,
}

impl Hooks {
    /// For `opts`.
    pub fn new(opts: Options) -> Self {
        Self {
            opts,
            link: None,
            qemu: None,
            csv: None,
            step: 0.0,
            started: None,
            wall: 0.0,
            samples: 0,
            max_ticks: 0,
            sum_ticks: 0.0,
            n_ticks: 0,
            rtt_sum: 0.0,
            rtt_max: 0.0,
            n_rtt: 0,
            error: None,
        }
    }

    fn is_board(&self) -> bool {
        !matches!(self.opts.target, Target::InProcess)
    }

    fn write_records(&mut self, recs: Vec<Record>) {
        let cpt = self.cycles_per_tick();
        for r in recs {
            self.n_rtt += 1;
            self.rtt_sum += r.rtt_us;
            self.rtt_max = self.rtt_max.max(r.rtt_us);
            if let Some(t) = r.ticks {
                self.max_ticks = self.max_ticks.max(t);
                self.sum_ticks += f64::from(t);
                self.n_ticks += 1;
            }
            if let Some(w) = self.csv.as_mut() {
                let (ticks, cycles) = match r.ticks {
                    Some(t) => (t.to_string(), format!("{:.0}", f64::from(t) * cpt)),
                    None => (String::new(), String::new()),
                };
                let res = writeln!(
                    w,
                    "{},{},{:.1},{},{},{}",
                    r.k,
                    f64::from(r.k) * self.step,
                    r.rtt_us,
                    ticks,
                    cycles,
                    r.fault.map(|f| f.as_str()).unwrap_or("ok")
                );
                if let Err(e) = res {
                    self.error.get_or_insert(e.into());
                }
            }
        }
    }

    /// CPU cycles per tick of the board's clock (the firmware measured it).
    fn cycles_per_tick(&self) -> f64 {
        self.link
            .as_ref()
            .and_then(|l| {
                l.borrow()
                    .session
                    .welcome()
                    .map(|w| f64::from(w.clock.cycles_per_tick_milli) / 1000.0)
            })
            .unwrap_or(0.0)
    }
}

/// The pil.csv header: one row per sample exchanged.
pub const PIL_COLUMNS: &str = "k,t_s,rtt_us,board_ticks,board_cycles,link";

impl RunHooks for Hooks {
    fn run(
        &mut self,
        lp: &Loop,
        stage: &Path,
        observe: &mut dyn FnMut(&Sample),
    ) -> Result<(Outcome, Metrics)> {
        let h = hello(lp, self.opts.float)?;
        // The shadow (the diagnostics' controller) is built here from the
        // same Hello, with the board's code: a Hello it refuses is refused
        // here first, with the key named.
        let shadow = match self.opts.float {
            FloatType::F32 => AnyLaw::<f32>::build(&h).map(|l| Shadow::F32(Box::new(l))),
            FloatType::F64 => AnyLaw::<f64>::build(&h).map(|l| Shadow::F64(Box::new(l))),
        }
        .map_err(|e| {
            crate::error::InputError::Request(format!(
                "`controller.{}`: {} (in {})",
                e.name,
                e.reason,
                self.opts.float.as_str()
            ))
        })?;
        let (t, q) = open_transport(&self.opts)?;
        self.qemu = q;
        let session =
            Session::open(t, h, self.opts.timeout, self.opts.handshake_timeout).map_err(|e| {
                let extra = self
                    .qemu
                    .as_mut()
                    .and_then(|q| q.exited())
                    .map(|w| format!(" ({w})"))
                    .unwrap_or_default();
                anyhow::anyhow!("{e}{extra}")
            })?;
        let link = Link::new(session, shadow, lp.stages().policy.safe);
        if link.cannot_annotate() {
            anyhow::bail!(
                "internal: kind `{}` has diagnostics that need the plant, and its parts cannot be rebuilt on the host (Signals::rebuild)",
                lp.controller().kind()
            );
        }
        let link = Rc::new(RefCell::new(link));
        self.link = Some(Rc::clone(&link));
        if self.is_board() {
            let path = stage.join("pil.csv");
            let f = std::fs::File::create(&path)
                .with_context(|| format!("creating {}", path.display()))?;
            let mut w = std::io::BufWriter::new(f);
            writeln!(w, "{PIL_COLUMNS}")?;
            self.csv = Some(w);
        }
        self.step = lp.sim().step;
        // The board applies the limits (in its float type); the
        // simulator's loop keeps its finiteness check and the same safe
        // command.
        let lp = lp
            .with_limits(Limits::NONE)
            .context("internal: a policy without limits is valid")?;
        self.started = Some(Instant::now());
        let mut samples = 0u64;
        let (outcome, metrics) = {
            let link2 = Rc::clone(&link);
            let mut pending = Vec::new();
            let r = crate::run::run_mapped(&lp, OnBoard(link), &mut |smp| {
                samples += 1;
                observe(smp);
                pending.extend(link2.borrow_mut().session.settled(false));
            });
            self.write_records(pending);
            r
        };
        self.samples = samples;
        self.wall = self
            .started
            .map(|t| t.elapsed().as_secs_f64())
            .unwrap_or(0.0);
        Ok((outcome, metrics))
    }

    fn finish(&mut self, stage: &Path) -> Result<(Vec<&'static str>, Option<serde_json::Value>)> {
        let Some(link) = self.link.clone() else {
            return Ok((Vec::new(), None));
        };
        let rest = link.borrow_mut().session.settled(true);
        self.write_records(rest);
        let stopped = link.borrow_mut().session.stop();
        if let Some(q) = self.qemu.as_mut() {
            q.stop();
        }
        let mut files = Vec::new();
        if let Some(mut w) = self.csv.take() {
            w.flush()?;
            files.push("pil.csv");
        }
        if let Some(e) = self.error.take() {
            return Err(e.context(format!("writing {}", stage.join("pil.csv").display())));
        }
        let l = link.borrow();
        let s = &l.session;
        let w = s.welcome();
        let cpt = self.cycles_per_tick();
        let faults: u64 = s.counts.values().sum();
        let json = serde_json::json!({
            "where": if self.is_board() { "board" } else { "host (the board's code in-process)" },
            "float": self.opts.float.as_str(),
            "transport": s.describe(),
            "protocol": PROTOCOL_VERSION,
            "scenario_hash": w.map(|w| format!("{:016x}", w.scenario_hash)),
            "firmware": w.map(|w| w.firmware.as_str().to_string()),
            "clock": w.map(|w| serde_json::json!({
                "source": match w.clock.source { TickSource::Dwt => "dwt", TickSource::SysTick => "systick", TickSource::None => "none" },
                "tick_Hz": w.clock.tick_hz,
                "cycles_per_tick": f64::from(w.clock.cycles_per_tick_milli) / 1000.0,
            })),
            "reply_timeout_ms": self.opts.timeout.as_secs_f64() * 1e3,
            "sessions": s.sessions,
            "samples": self.samples,
            "wall_s": self.wall,
            "samples_per_s": if self.wall > 0.0 { self.samples as f64 / self.wall } else { 0.0 },
            "rtt_us": {
                "mean": if self.n_rtt > 0 { self.rtt_sum / self.n_rtt as f64 } else { 0.0 },
                "max": self.rtt_max,
            },
            "step_cycles": {
                "mean": if self.n_ticks > 0 { self.sum_ticks / self.n_ticks as f64 * cpt } else { 0.0 },
                "max": f64::from(self.max_ticks) * cpt,
                "max_ticks": self.max_ticks,
            },
            "link_faults": faults,
            "link_faults_by_kind": s.counts,
            "link_fault_flag": flags::LINK_FAULT,
            "events": s.events,
            "link_lost": s.lost(),
            "board_stopped": stopped.map(|b| serde_json::json!({
                "steps_kept": b.steps, "policy_faults": b.faults, "rollbacks": b.rollbacks, "max_ticks": b.max_ticks,
            })),
        });
        Ok((files, Some(json)))
    }
}

/// What the command line prints after an off-board run.
#[derive(Debug, Clone)]
pub struct Report {
    /// The summary's `offboard` section.
    pub offboard: serde_json::Value,
}

/// Runs `s` with its controller off-board and writes the run's outputs
/// (plus pil.csv from a board) into `dir`.
pub fn run_to_dir(
    dir: &Path,
    lp: &Loop,
    plot: bool,
    opts: Options,
) -> Result<(RunResult, Vec<PathBuf>, Report)> {
    let mut hooks = Hooks::new(opts);
    let r = crate::output::run_to_dir_with(dir, lp, plot, &mut hooks);
    if let Some(q) = hooks.qemu.as_mut() {
        q.stop();
    }
    let (run, files) = r?;
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json"))?)?;
    Ok((
        run,
        files,
        Report {
            offboard: summary["offboard"].clone(),
        },
    ))
}

/// Parses `--float`.
pub fn parse_float(s: &str) -> Option<FloatType> {
    match s {
        "f32" => Some(FloatType::F32),
        "f64" => Some(FloatType::F64),
        _ => None,
    }
}
