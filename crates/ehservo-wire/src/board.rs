//! The board's side of a session: a frame in, a frame out.
//!
//! The firmware feeds every frame it reads to [`Board::on_frame`] and sends
//! the frame it returns; the host's `--float f32` run does exactly the same
//! in-process, so both compute with the same code.
//!
//! **Rollback.** A step whose reply the host did not use (corrupted, lost,
//! late) must not count: the host applied the fault policy's command for
//! that sample, so the controller's state must be as if the sample had been
//! a measurement fault — untouched. Each step keeps the loop as it was
//! before; the next frame's acceptance token ([`Sample::acc`]) says
//! whether the host used the reply, and if not the board goes back to that
//! copy before anything else. One copy suffices because the host sends one
//! sample at a time and says, with each, what became of the last.

use crate::law::{AnyLaw, Ticks};
use crate::msg::{
    Boot, ClockInfo, Fault, FaultCode, FloatType, FromBoard, Hello, Refusal, RefuseReason, Reply,
    Sample, Stop, Stopped, ToBoard, Welcome,
};
use crate::{fnv1a, frame, WireFloat, PROTOCOL_VERSION};
use core::fmt::Write as _;
use ehservo_core::math::Real;
use heapless::String;
use serde::Serialize;

/// The acceptance token for "the host used the reply of sample `k`".
pub fn token(k: Option<u32>) -> u8 {
    match k {
        None => 0,
        Some(k) => (k.wrapping_add(1) & 0xFF) as u8,
    }
}

struct Run<F: Real> {
    law: AnyLaw<F>,
    /// The last step not yet confirmed: its k and the loop before it.
    pending: Option<(u32, AnyLaw<F>)>,
    last_k: Option<u32>,
    dt: f64,
    steps: u32,
    rollbacks: u32,
    max_ticks: u32,
}

impl<F: Real> Run<F> {
    fn new(law: AnyLaw<F>, dt: f64) -> Self {
        Self {
            law,
            pending: None,
            last_k: None,
            dt,
            steps: 0,
            rollbacks: 0,
            max_ticks: 0,
        }
    }

    /// Keeps or undoes the pending step, as the host's token says.
    fn settle(&mut self, acc: u8) {
        if let Some((j, before)) = self.pending.take() {
            if acc == token(Some(j)) {
                self.steps += 1;
            } else {
                self.law = before;
                self.rollbacks += 1;
            }
        }
    }

    fn sample<T: Ticks>(&mut self, s: &Sample<F>, clock: &mut T) -> FromBoard<F> {
        if self.last_k.is_some_and(|j| s.k <= j) {
            return FromBoard::Fault(Fault {
                k: Some(s.k),
                code: FaultCode::OutOfOrder,
            });
        }
        self.settle(s.acc);
        // t_k = k·h in f64, as the host's simulator computes it.
        let t = F::of(f64::from(s.k) * self.dt);
        let (r, before) = self.law.step(t, s.x, s.z, clock);
        self.pending = Some((s.k, before));
        self.last_k = Some(s.k);
        self.max_ticks = self.max_ticks.max(r.ticks);
        FromBoard::Reply(Reply {
            k: s.k,
            u: r.u,
            flags: r.flags,
            ticks: r.ticks,
            parts: r.parts,
        })
    }

    fn stop(&mut self, s: &Stop) -> Stopped {
        self.settle(s.acc);
        Stopped {
            steps: self.steps,
            faults: self.law.fault_count().min(u64::from(u32::MAX)) as u32,
            rollbacks: self.rollbacks,
            max_ticks: self.max_ticks,
        }
    }
}

// No allocation on a board: the one session lives in place.
#[allow(clippy::large_enum_variant)]
enum Session {
    F32(Run<f32>),
    F64(Run<f64>),
}

/// A board: idle until a [`Hello`], then one session at a time.
pub struct Board {
    firmware: &'static str,
    clock: ClockInfo,
    session: Option<Session>,
    /// The protocol version this board speaks ([`PROTOCOL_VERSION`]; other
    /// values only in tests of the handshake).
    protocol: u16,
}

fn name<const N: usize>(s: &str) -> String<N> {
    let mut out = String::new();
    for c in s.chars() {
        if out.push(c).is_err() {
            break;
        }
    }
    out
}

impl Board {
    /// A board named `firmware` (name and version) timing its steps with
    /// `clock`.
    pub fn new(firmware: &'static str, clock: ClockInfo) -> Self {
        Self {
            firmware,
            clock,
            session: None,
            protocol: PROTOCOL_VERSION,
        }
    }

    /// A board speaking another protocol version (handshake tests).
    pub fn with_protocol(mut self, protocol: u16) -> Self {
        self.protocol = protocol;
        self
    }

    /// Whether a session is open.
    pub fn in_session(&self) -> bool {
        self.session.is_some()
    }

    /// The frame a board sends at reset.
    pub fn boot_frame(&self, out: &mut [u8]) -> usize {
        let msg: FromBoard<f32> = FromBoard::Boot(Boot {
            protocol: self.protocol,
            firmware: name(self.firmware),
        });
        frame::seal(&msg, out).unwrap_or(0)
    }

    /// Handles one frame (`raw`: its bytes without the final zero, decoded
    /// in place) and writes the answer's frame into `out` (at least
    /// [`frame::MAX_FRAME`] bytes); returns its length.
    pub fn on_frame<T: Ticks>(&mut self, raw: &mut [u8], clock: &mut T, out: &mut [u8]) -> usize {
        let Ok(payload) = frame::open(raw) else {
            return self.fault(None, FaultCode::BadFrame, out);
        };
        match &mut self.session {
            None | Some(Session::F32(_)) => match frame::decode::<ToBoard<f32>>(payload) {
                Ok(m) => self.handle(m, payload, clock, out),
                Err(_) => self.maybe_hello(payload, clock, out),
            },
            Some(Session::F64(_)) => match frame::decode::<ToBoard<f64>>(payload) {
                Ok(m) => self.handle(m, payload, clock, out),
                Err(_) => self.maybe_hello(payload, clock, out),
            },
        }
    }

    /// A frame that did not decode in the session's float type: a Hello
    /// decodes in either, anything else is a bad frame.
    fn maybe_hello<T: Ticks>(&mut self, payload: &[u8], clock: &mut T, out: &mut [u8]) -> usize {
        match frame::decode::<ToBoard<f64>>(payload) {
            Ok(m @ ToBoard::Hello(_)) => self.handle(m, payload, clock, out),
            _ => self.fault(None, FaultCode::BadFrame, out),
        }
    }

    /// Answers a frame longer than the firmware's buffer.
    pub fn overrun(&mut self, out: &mut [u8]) -> usize {
        self.fault(None, FaultCode::Overrun, out)
    }

    fn fault(&self, k: Option<u32>, code: FaultCode, out: &mut [u8]) -> usize {
        send::<f32>(&FromBoard::Fault(Fault { k, code }), out)
    }

    fn handle<F: WireFloat, T: Ticks>(
        &mut self,
        m: ToBoard<F>,
        payload: &[u8],
        clock: &mut T,
        out: &mut [u8],
    ) -> usize {
        match m {
            ToBoard::Hello(h) => self.hello(&h, payload, out),
            ToBoard::Sample(s) => match (&mut self.session, F::FLOAT) {
                (Some(Session::F32(r)), FloatType::F32) => {
                    let s = Sample {
                        k: s.k,
                        acc: s.acc,
                        x: s.x.map(|v| v.to_f64() as f32),
                        z: s.z.map(|v| v.to_f64() as f32),
                    };
                    send(&r.sample(&s, clock), out)
                }
                (Some(Session::F64(r)), FloatType::F64) => {
                    let s = Sample {
                        k: s.k,
                        acc: s.acc,
                        x: s.x.map(|v| v.to_f64()),
                        z: s.z.map(|v| v.to_f64()),
                    };
                    send(&r.sample(&s, clock), out)
                }
                _ => self.fault(Some(s.k), FaultCode::NoSession, out),
            },
            ToBoard::Stop(s) => {
                let stopped = match &mut self.session {
                    Some(Session::F32(r)) => r.stop(&s),
                    Some(Session::F64(r)) => r.stop(&s),
                    None => return self.fault(Some(s.k), FaultCode::NoSession, out),
                };
                self.session = None;
                send::<f32>(&FromBoard::Stopped(stopped), out)
            }
        }
    }

    fn hello(&mut self, h: &Hello, payload: &[u8], out: &mut [u8]) -> usize {
        // A new Hello ends any session.
        self.session = None;
        let protocol = self.protocol;
        let refuse = |reason, out: &mut [u8]| {
            send::<f32>(&FromBoard::Refused(Refusal { protocol, reason }), out)
        };
        if h.protocol != self.protocol {
            return refuse(RefuseReason::Protocol, out);
        }
        let built = match h.float {
            FloatType::F32 => AnyLaw::<f32>::build(h).map(|l| {
                let n = l.signals().len();
                (Session::F32(Run::new(l, h.dt)), n)
            }),
            FloatType::F64 => AnyLaw::<f64>::build(h).map(|l| {
                let n = l.signals().len();
                (Session::F64(Run::new(l, h.dt)), n)
            }),
        };
        let (session, n) = match built {
            Ok(b) => b,
            Err(e) => {
                let mut reason: String<96> = String::new();
                let _ = write!(reason, "{}", e.reason);
                if !e.value.is_nan() {
                    let _ = write!(reason, " (got {:?})", e.value);
                }
                return refuse(
                    RefuseReason::Param {
                        name: name(e.name),
                        reason,
                    },
                    out,
                );
            }
        };
        if n != usize::from(h.signals) {
            return refuse(RefuseReason::Signals { board: n as u8 }, out);
        }
        self.session = Some(session);
        send::<f32>(
            &FromBoard::Welcome(Welcome {
                protocol: self.protocol,
                scenario_hash: h.scenario_hash,
                hello_digest: fnv1a(payload),
                float: h.float,
                signals: n as u8,
                clock: self.clock,
                firmware: name(self.firmware),
            }),
            out,
        )
    }
}

fn send<F: Serialize>(m: &FromBoard<F>, out: &mut [u8]) -> usize {
    // Every answer fits a frame (its parts are bounded by MAX_PARTS).
    frame::seal(m, out).unwrap_or(0)
}
