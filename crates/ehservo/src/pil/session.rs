//! The host's side of a session: the handshake, one exchange per sample
//! with every fault detected and named, the stop.

use super::transport::Transport;
use ehservo_wire::board::token;
use ehservo_wire::frame::{self, Deframer, Pushed, MAX_FRAME, MAX_PAYLOAD};
use ehservo_wire::msg::{
    FaultCode, FloatType, FromBoard, Hello, RefuseReason, Sample, Stop, Stopped, ToBoard, Welcome,
    MAX_PARTS,
};
use ehservo_wire::{fnv1a, WireFloat, PROTOCOL_VERSION};
use serde::Serialize;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// What went wrong with one sample's exchange.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinkFault {
    /// The reply failed its COBS, CRC or decoding, or was not this
    /// sample's.
    CorruptReply,
    /// The board could not read the sample's frame (it said so).
    CorruptRequest,
    /// No reply by the deadline (a frame dropped either way).
    NoReply,
    /// The reply came after the deadline (found when it arrived; it was
    /// not used).
    LateReply,
    /// The board had reset: it had no session, or announced its boot.
    BoardReset,
    /// The board refused the sample (out of order).
    BoardRefused,
    /// The link is lost (closed, failed, or too many faults in a row): no
    /// exchange was tried.
    Lost,
}

impl LinkFault {
    /// Its name in outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            LinkFault::CorruptReply => "corrupt-reply",
            LinkFault::CorruptRequest => "corrupt-request",
            LinkFault::NoReply => "no-reply",
            LinkFault::LateReply => "late-reply",
            LinkFault::BoardReset => "board-reset",
            LinkFault::BoardRefused => "board-refused",
            LinkFault::Lost => "link-lost",
        }
    }
}

/// One sample's exchange, as pil.csv records it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// The sample index.
    pub k: u32,
    /// From the send to the reply (or to the deadline), µs.
    pub rtt_us: f64,
    /// The board's timer ticks for the step (when a reply was used).
    pub ticks: Option<u32>,
    /// `None`: the reply was used.
    pub fault: Option<LinkFault>,
}

/// A fault, for summary.json and stderr.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// The sample index.
    pub k: u32,
    /// What.
    pub fault: LinkFault,
    /// Details.
    pub detail: String,
}

/// The command and parts of a reply that was used.
#[derive(Debug, Clone, Copy)]
pub struct Answer {
    /// u (V).
    pub u: f64,
    /// The board's flags.
    pub flags: u8,
    /// The parts, widened to f64 (exact).
    pub values: [f64; MAX_PARTS],
}

/// Faults in a row after which the link is declared lost.
pub const MAX_FAULTS_IN_A_ROW: u32 = 32;
/// Exchanges kept before their record is final (a late reply can still
/// turn a no-reply into a late-reply within this many samples).
const WINDOW: usize = 64;
/// Most events kept in full (all are counted).
const MAX_EVENTS: usize = 1000;

/// An open session.
pub struct Session {
    link: Box<dyn Transport>,
    hello: Hello,
    float: FloatType,
    welcome: Option<Welcome>,
    rx: Deframer<MAX_FRAME>,
    buf: Vec<u8>,
    pos: usize,
    len: usize,
    /// Reply deadline per sample.
    pub timeout: Duration,
    /// Handshake deadline.
    pub handshake_timeout: Duration,
    accepted: Option<u32>,
    last_sent: Option<u32>,
    records: VecDeque<Record>,
    /// Faults seen (the first [`MAX_EVENTS`] in full).
    pub events: Vec<Event>,
    /// Faults by kind.
    pub counts: std::collections::BTreeMap<&'static str, u64>,
    in_a_row: u32,
    lost: Option<String>,
    /// Sessions opened (1 + re-handshakes after resets).
    pub sessions: u32,
    /// Rollbacks and steps the board reported at each stop.
    pub stopped: Option<Stopped>,
}

/// Why a handshake failed (one line for the user).
#[derive(Debug)]
pub struct HandshakeError(pub String);

impl std::fmt::Display for HandshakeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for HandshakeError {}

impl Session {
    /// Opens a session over `link`: sends `hello` and checks the answer.
    pub fn open(
        link: Box<dyn Transport>,
        hello: Hello,
        timeout: Duration,
        handshake_timeout: Duration,
    ) -> Result<Self, HandshakeError> {
        let mut s = Self {
            link,
            float: hello.float,
            hello,
            welcome: None,
            rx: Deframer::new(),
            buf: vec![0; 4096],
            pos: 0,
            len: 0,
            timeout,
            handshake_timeout,
            accepted: None,
            last_sent: None,
            records: VecDeque::new(),
            events: Vec::new(),
            counts: Default::default(),
            in_a_row: 0,
            lost: None,
            sessions: 0,
            stopped: None,
        };
        s.handshake()?;
        Ok(s)
    }

    /// What the board said at the handshake.
    pub fn welcome(&self) -> Option<&Welcome> {
        self.welcome.as_ref()
    }

    /// The transport, for people.
    pub fn describe(&self) -> String {
        self.link.describe()
    }

    /// Why the link is lost, if it is.
    pub fn lost(&self) -> Option<&str> {
        self.lost.as_deref()
    }

    fn hello_frame(&self) -> (Vec<u8>, u64) {
        let msg: ToBoard<f64> = ToBoard::Hello(self.hello.clone());
        let mut payload = [0u8; MAX_PAYLOAD + 2];
        let n = frame::payload(&msg, &mut payload).expect("a Hello fits a frame");
        let digest = fnv1a(&payload[..n]);
        let mut out = [0u8; MAX_FRAME];
        let m = frame::seal_payload(&mut payload, n, &mut out).expect("a Hello fits a frame");
        (out[..m].to_vec(), digest)
    }

    /// Sends the Hello and waits for the Welcome, skipping the boot
    /// announcement and anything left from before.
    fn handshake(&mut self) -> Result<(), HandshakeError> {
        let (bytes, digest) = self.hello_frame();
        self.link.at(None);
        // A zero first ends whatever partial frame the board holds.
        self.link
            .send(&[0])
            .and_then(|()| self.link.send(&bytes))
            .map_err(|e| HandshakeError(format!("sending the handshake: {e}")))?;
        let deadline = Instant::now() + self.handshake_timeout;
        loop {
            let mut copy = [0u8; MAX_FRAME];
            let frame = match self.next_frame(deadline) {
                Ok(Some(f)) => {
                    let n = f.len();
                    copy[..n].copy_from_slice(f);
                    &mut copy[..n]
                }
                Ok(None) => {
                    return Err(HandshakeError(format!(
                        "no answer to the handshake within {:.1} s over {} (is the board running the PIL firmware, examples/firmware-pil?)",
                        self.handshake_timeout.as_secs_f64(),
                        self.link.describe()
                    )))
                }
                Err(e) => return Err(HandshakeError(format!("during the handshake: {e}"))),
            };
            let msg = match decode_frame::<f32>(frame) {
                Ok(m) => m,
                Err(_) => continue, // noise before the board's first frame
            };
            match msg {
                FromBoard::Welcome(w) => {
                    self.check_welcome(&w, digest)?;
                    self.welcome = Some(w);
                    self.sessions += 1;
                    self.accepted = None;
                    self.last_sent = None;
                    return Ok(());
                }
                FromBoard::Refused(r) => {
                    return Err(HandshakeError(match r.reason {
                        RefuseReason::Protocol => format!(
                            "handshake mismatch: the board speaks protocol version {}, this host {}",
                            r.protocol, PROTOCOL_VERSION
                        ),
                        RefuseReason::Param { name, reason } => format!(
                            "the board refused the controller: `controller.{name}`: {reason}"
                        ),
                        RefuseReason::Signals { board } => format!(
                            "handshake mismatch: the board's {} controller writes {board} signals, this host expects {}",
                            self.hello.controller.kind(),
                            self.hello.signals
                        ),
                    }))
                }
                // The boot announcement, faults and replies of an earlier
                // session: not an answer to this Hello.
                _ => continue,
            }
        }
    }

    fn check_welcome(&self, w: &Welcome, digest: u64) -> Result<(), HandshakeError> {
        let h = &self.hello;
        if w.protocol != PROTOCOL_VERSION {
            return Err(HandshakeError(format!(
                "handshake mismatch: the board speaks protocol version {}, this host {}",
                w.protocol, PROTOCOL_VERSION
            )));
        }
        if w.scenario_hash != h.scenario_hash {
            return Err(HandshakeError(format!(
                "handshake mismatch: the board answered for scenario {:016x}, this run is scenario {:016x} (another scenario's session)",
                w.scenario_hash, h.scenario_hash
            )));
        }
        if w.hello_digest != digest {
            return Err(HandshakeError(format!(
                "handshake mismatch: the board built from a handshake of digest {:016x}, the host sent {digest:016x}",
                w.hello_digest
            )));
        }
        if w.float != h.float || w.signals != h.signals {
            return Err(HandshakeError(format!(
                "handshake mismatch: the board runs {} with {} signals, the host asked for {} with {}",
                w.float.as_str(),
                w.signals,
                h.float.as_str(),
                h.signals
            )));
        }
        Ok(())
    }

    /// The next whole frame before `deadline` (its bytes, without the
    /// zero), `None` at the deadline.
    fn next_frame(&mut self, deadline: Instant) -> std::io::Result<Option<&mut [u8]>> {
        loop {
            while self.pos < self.len {
                let b = self.buf[self.pos];
                self.pos += 1;
                if let Pushed::Frame(n) = self.rx.push(b) {
                    return Ok(Some(self.rx.frame(n)));
                }
                // An overrun is a frame too long for any message: skipped.
            }
            let n = self.link.recv(&mut self.buf, deadline)?;
            if n == 0 {
                return Ok(None);
            }
            self.pos = 0;
            self.len = n;
        }
    }

    /// Exchanges sample `k`: the measurement `x` and reference `z` go to
    /// the board (rounded to the session's float type), its reply comes
    /// back. A fault is recorded and returned; the caller applies the
    /// fault policy.
    pub fn exchange(&mut self, k: u32, x: [f64; 3], z: [f64; 4]) -> Result<Answer, LinkFault> {
        let start = Instant::now();
        let r = match self.float {
            FloatType::F32 => self.exchange_in::<f32>(k, x, z, start),
            FloatType::F64 => self.exchange_in::<f64>(k, x, z, start),
        };
        let rtt_us = start.elapsed().as_secs_f64() * 1e6;
        let (ticks, fault) = match &r {
            Ok((_, t)) => (Some(*t), None),
            Err((f, _)) => (None, Some(*f)),
        };
        self.records.push_back(Record {
            k,
            rtt_us,
            ticks,
            fault,
        });
        match r {
            Ok((a, _)) => {
                self.in_a_row = 0;
                Ok(a)
            }
            Err((f, detail)) => {
                self.note(k, f, detail);
                if f != LinkFault::Lost {
                    self.in_a_row += 1;
                    if self.in_a_row >= MAX_FAULTS_IN_A_ROW && self.lost.is_none() {
                        self.lost = Some(format!(
                            "{MAX_FAULTS_IN_A_ROW} faults in a row, the last at k = {k}"
                        ));
                    }
                }
                if f == LinkFault::BoardReset && self.lost.is_none() {
                    // A new session for the samples to come; the board's
                    // controller starts again from its initial state.
                    if let Err(e) = self.handshake() {
                        self.lost = Some(format!("after the board reset at k = {k}: {e}"));
                    } else {
                        self.note(
                            k,
                            LinkFault::BoardReset,
                            format!(
                                "session {} opened: the controller restarts from its initial state at k = {}",
                                self.sessions,
                                k + 1
                            ),
                        );
                    }
                }
                Err(f)
            }
        }
    }

    fn note(&mut self, k: u32, fault: LinkFault, detail: String) {
        *self.counts.entry(fault.as_str()).or_default() += 1;
        if self.events.len() < MAX_EVENTS {
            self.events.push(Event { k, fault, detail });
        }
    }

    #[allow(clippy::type_complexity)]
    fn exchange_in<F: WireFloat>(
        &mut self,
        k: u32,
        x: [f64; 3],
        z: [f64; 4],
        start: Instant,
    ) -> Result<(Answer, u32), (LinkFault, String)> {
        if let Some(why) = &self.lost {
            return Err((LinkFault::Lost, why.clone()));
        }
        let msg: ToBoard<F> = ToBoard::Sample(Sample {
            k,
            acc: token(self.accepted),
            x: x.map(F::of),
            z: z.map(F::of),
        });
        let mut out = [0u8; MAX_FRAME];
        let n = frame::seal(&msg, &mut out).expect("a sample fits a frame");
        self.link.at(Some(k));
        if let Err(e) = self.link.send(&out[..n]) {
            self.lost = Some(format!("sending sample {k}: {e}"));
            return Err((LinkFault::Lost, format!("sending: {e}")));
        }
        self.last_sent = Some(k);
        let deadline = start + self.timeout;
        loop {
            let got = match self.next_frame(deadline) {
                Ok(Some(f)) => {
                    let mut copy = [0u8; MAX_FRAME];
                    let n = f.len();
                    copy[..n].copy_from_slice(f);
                    Some((copy, n))
                }
                Ok(None) => None,
                Err(e) => {
                    self.lost = Some(format!("reading the reply to sample {k}: {e}"));
                    return Err((LinkFault::Lost, format!("{e}")));
                }
            };
            let Some((mut f, n)) = got else {
                return Err((
                    LinkFault::NoReply,
                    format!("no reply within {:.1} ms", self.timeout.as_secs_f64() * 1e3),
                ));
            };
            let msg = match decode_frame::<F>(&mut f[..n]) {
                Ok(m) => m,
                Err(e) => return Err((LinkFault::CorruptReply, e.as_str().to_string())),
            };
            match msg {
                FromBoard::Reply(r) if r.k == k => {
                    if r.parts.len() != usize::from(self.hello.signals) {
                        return Err((
                            LinkFault::CorruptReply,
                            format!("{} parts, {} expected", r.parts.len(), self.hello.signals),
                        ));
                    }
                    let mut values = [0.0; MAX_PARTS];
                    for (v, p) in values.iter_mut().zip(&r.parts) {
                        *v = p.to_f64();
                    }
                    self.accepted = Some(k);
                    return Ok((
                        Answer {
                            u: r.u.to_f64(),
                            flags: r.flags,
                            values,
                        },
                        r.ticks,
                    ));
                }
                FromBoard::Reply(r) if r.k < k => {
                    // A reply that missed its deadline: never used. Its
                    // sample's no-reply becomes a late reply.
                    self.late(r.k, k);
                }
                FromBoard::Reply(r) => {
                    return Err((
                        LinkFault::CorruptReply,
                        format!("a reply for sample {} (not sent yet)", r.k),
                    ))
                }
                FromBoard::Fault(fl) => {
                    if fl.k.is_some_and(|j| j != k) {
                        continue; // about an earlier frame
                    }
                    return Err(match fl.code {
                        FaultCode::BadFrame | FaultCode::Overrun => (
                            LinkFault::CorruptRequest,
                            "the board could not read the sample's frame".into(),
                        ),
                        FaultCode::NoSession => (
                            LinkFault::BoardReset,
                            "the board has no session (it reset)".into(),
                        ),
                        FaultCode::OutOfOrder => (
                            LinkFault::BoardRefused,
                            "the board refused the sample as out of order".into(),
                        ),
                    });
                }
                FromBoard::Boot(b) => {
                    return Err((
                        LinkFault::BoardReset,
                        format!("the board booted again ({})", b.firmware.as_str()),
                    ))
                }
                // Not an answer to a sample: ignored.
                FromBoard::Welcome(_) | FromBoard::Refused(_) | FromBoard::Stopped(_) => {}
            }
        }
    }

    /// Sample `j`'s reply arrived during sample `k`'s exchange.
    fn late(&mut self, j: u32, k: u32) {
        let rec = self.records.iter_mut().rev().find(|r| r.k == j);
        let detail =
            format!("the reply to sample {j} arrived during sample {k}'s exchange, unused");
        match rec {
            Some(r) if r.fault == Some(LinkFault::NoReply) => {
                r.fault = Some(LinkFault::LateReply);
                // The event recorded as no-reply is the late one.
                if let Some(e) = self
                    .events
                    .iter_mut()
                    .rev()
                    .find(|e| e.k == j && e.fault == LinkFault::NoReply)
                {
                    e.fault = LinkFault::LateReply;
                    e.detail = detail;
                }
                if let Some(c) = self.counts.get_mut(LinkFault::NoReply.as_str()) {
                    *c -= 1;
                }
                *self
                    .counts
                    .entry(LinkFault::LateReply.as_str())
                    .or_default() += 1;
            }
            _ => {
                // Its sample's fault was another (or is out of the window):
                // noted, still unused.
                self.note(j, LinkFault::LateReply, detail);
            }
        }
    }

    /// The records no late reply can change any more (all of them with
    /// `all`).
    pub fn settled(&mut self, all: bool) -> Vec<Record> {
        let keep = if all { 0 } else { WINDOW };
        let n = self.records.len().saturating_sub(keep);
        self.records.drain(..n).collect()
    }

    /// Ends the session: the board settles its last step and reports.
    pub fn stop(&mut self) -> Option<Stopped> {
        if self.lost.is_some() {
            return None;
        }
        let msg: ToBoard<f32> = ToBoard::Stop(Stop {
            k: self.last_sent.unwrap_or(0),
            acc: token(self.accepted),
        });
        let mut out = [0u8; MAX_FRAME];
        let n = frame::seal(&msg, &mut out).ok()?;
        self.link.at(None);
        self.link.send(&out[..n]).ok()?;
        let deadline = Instant::now() + self.handshake_timeout;
        loop {
            let f = self.next_frame(deadline).ok()??;
            let mut copy = [0u8; MAX_FRAME];
            let len = f.len();
            copy[..len].copy_from_slice(f);
            let m = match self.float {
                FloatType::F32 => decode_frame::<f32>(&mut copy[..len]).ok().map(strip),
                FloatType::F64 => decode_frame::<f64>(&mut copy[..len]).ok().map(strip),
            };
            if let Some(Some(s)) = m {
                self.stopped = Some(s);
                return Some(s);
            }
        }
    }
}

fn decode_frame<F: WireFloat>(frame: &mut [u8]) -> Result<FromBoard<F>, frame::FrameError> {
    frame::decode(frame::open(frame)?)
}

fn strip<F>(m: FromBoard<F>) -> Option<Stopped> {
    match m {
        FromBoard::Stopped(s) => Some(s),
        _ => None,
    }
}
