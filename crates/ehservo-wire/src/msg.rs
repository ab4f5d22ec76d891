//! The messages, as serde types (postcard-encoded by [`crate::frame`]).
//!
//! A session, host on the left:
//!
//! ```text
//! (reset)                                ◀── Boot { protocol }
//! Hello { protocol, scenario_hash, … } ──▶
//!                                        ◀── Welcome { … }  |  Refused { … }
//! Sample { k = 0, acc, x, z }          ──▶
//!                                        ◀── Reply { k = 0, u, flags, ticks, parts }
//! Sample { k = 1, acc, x, z }          ──▶   …  (one reply per sample, lock-step)
//!                                        ◀── Fault { k?, code }   (a frame it could not use)
//! Stop { k }                           ──▶
//!                                        ◀── Stopped { steps, … }
//! ```
//!
//! Every float of a session is in its float type `F` (the handshake's
//! [`FloatType`]): the host rounds its measurements to `F` once, so the
//! board computes exactly what a host computing in `F` would.

use crate::config::WireController;
use ehservo_core::servo::{Load, ServoParams};
use heapless::{String, Vec};
use serde::{Deserialize, Serialize};

/// Most signals a reply carries (the simulator's `MAX_PARTS`).
pub const MAX_PARTS: usize = 32;

/// The float type a board computes in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FloatType {
    /// IEEE single precision (a Cortex-M4F's FPU).
    F32,
    /// IEEE double precision (software on a Cortex-M4F).
    F64,
}

impl FloatType {
    /// `"f32"` or `"f64"`.
    pub fn as_str(self) -> &'static str {
        match self {
            FloatType::F32 => "f32",
            FloatType::F64 => "f64",
        }
    }

    /// Bytes of one value.
    pub fn size(self) -> usize {
        match self {
            FloatType::F32 => 4,
            FloatType::F64 => 8,
        }
    }
}

/// What the controller is told of the plant, as the inputs of
/// `NominalModel::new` (the one constructor the board calls).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModelInputs {
    /// Physical parameters (SI).
    pub params: ServoParams,
    /// The load model.
    pub load: Load,
    /// The valve's load-pressure offset (Pa; 0 for the paper's servo, a
    /// single-rod cylinder's direction-dependent gain otherwise):
    /// `NominalModel::with_offset`.
    pub offset: f64,
}

/// The fault policy of the scenario (`[fault]`), in f64.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WirePolicy {
    /// On a bad step: hold the last good command (`true`) or command zero.
    pub hold_last: bool,
    /// |θ|, |θ̇|, |θ̈| limits (rad, rad/s, rad/s²; infinite: none).
    pub limits_x: [f64; 3],
    /// The valve range ±u (V; infinite: none).
    pub limit_u: f64,
}

/// The host's opening: everything the board needs to build the controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    /// [`crate::PROTOCOL_VERSION`] of the host.
    pub protocol: u16,
    /// FNV-1a (64 bits) of the scenario as run (its resolved TOML).
    pub scenario_hash: u64,
    /// The float type the board is to compute in.
    pub float: FloatType,
    /// The sample period h (s): t_k = k·h.
    pub dt: f64,
    /// The controller kind and its parameters (a scenario's `[controller]`).
    pub controller: WireController,
    /// The nominal model's inputs.
    pub model: ModelInputs,
    /// The switching surface's p1, p2, p3.
    pub surface: [f64; 3],
    /// The sampled loop's fault policy.
    pub policy: WirePolicy,
    /// How many signals the host expects in each reply (the kind's parts).
    pub signals: u8,
}

/// How the board times its step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TickSource {
    /// The DWT cycle counter (one tick per CPU cycle).
    Dwt,
    /// SysTick on the processor clock (a 24-bit down-counter).
    SysTick,
    /// No counter: ticks are 0.
    None,
}

/// The board's clock, as it measured it at boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClockInfo {
    /// Which counter.
    pub source: TickSource,
    /// Its nominal rate (Hz).
    pub tick_hz: u32,
    /// CPU cycles per tick × 1000, measured at boot with a counted loop of
    /// known instruction count (1000 for DWT; under QEMU's
    /// `-icount shift=0`, where an instruction is one 1 ns cycle and
    /// SysTick runs at 25 MHz, 40 000).
    pub cycles_per_tick_milli: u32,
}

/// The board's acceptance of a [`Hello`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Welcome {
    /// The board's [`crate::PROTOCOL_VERSION`].
    pub protocol: u16,
    /// The [`Hello::scenario_hash`] it built from.
    pub scenario_hash: u64,
    /// FNV-1a of the Hello's payload bytes as the board received them.
    pub hello_digest: u64,
    /// The float type it computes in.
    pub float: FloatType,
    /// The number of signals its controller writes.
    pub signals: u8,
    /// Its step timer.
    pub clock: ClockInfo,
    /// Its name and version.
    pub firmware: String<40>,
}

/// Why a board refused a [`Hello`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum RefuseReason {
    /// It speaks another protocol version ([`Refusal::protocol`]).
    Protocol,
    /// The controller's parameters do not build: the parameter and why.
    Param {
        /// The parameter's name.
        name: String<32>,
        /// Why.
        reason: String<96>,
    },
    /// The host expects another number of signals than the kind writes.
    Signals {
        /// The kind's.
        board: u8,
    },
}

/// A refused handshake.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Refusal {
    /// The board's [`crate::PROTOCOL_VERSION`].
    pub protocol: u16,
    /// Why.
    pub reason: RefuseReason,
}

/// One sample's measurement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sample<F> {
    /// The sample index k (t_k = k·h, computed on the board in f64 from
    /// [`Hello::dt`], as the host computes it).
    pub k: u32,
    /// The host's acceptance token: (1 + the last k whose reply the host
    /// used) mod 256, 0 before any. A board whose last step's reply was
    /// not used restores its state from before that step
    /// ([`crate::board::Board`]).
    pub acc: u8,
    /// What the controller measures: x = (θ, θ̇, θ̈) after the sensors and
    /// the estimator (rad, rad/s, rad/s²).
    pub x: [F; 3],
    /// The reference z = (θd, θ̇d, θ̈d, θ⃛d).
    pub z: [F; 4],
}

/// The end of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stop {
    /// The last sample index sent.
    pub k: u32,
    /// The host's acceptance token, as in [`Sample::acc`].
    pub acc: u8,
}

/// Host to board.
// A message is built, sent and dropped: no allocation to box the Hello.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ToBoard<F> {
    /// Open (or reopen) a session.
    Hello(Hello),
    /// One sample.
    Sample(Sample<F>),
    /// End the session.
    Stop(Stop),
}

/// The board's answer to a [`Sample`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reply<F> {
    /// The sample index answered.
    pub k: u32,
    /// The command u (V), after the fault policy and the valve range.
    pub u: F,
    /// The step's flags (`ehservo_core::control::flags`).
    pub flags: u8,
    /// Ticks of [`Welcome::clock`] the step (`SampledController::step`)
    /// took.
    pub ticks: u32,
    /// The law's named parts, in its `Signals::SIGNALS` order; the
    /// diagnostics that need the true plant are the host's to fill.
    pub parts: Vec<F, MAX_PARTS>,
}

/// A frame the board could not use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FaultCode {
    /// COBS, CRC or decoding failed: the sample (if any) was not stepped.
    BadFrame,
    /// A frame longer than the board's buffer.
    Overrun,
    /// A sample outside a session: the board has reset since the Hello.
    NoSession,
    /// A sample index not after the last one stepped.
    OutOfOrder,
}

/// The board's fault report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fault {
    /// The sample index, when the frame was readable.
    pub k: Option<u32>,
    /// What was wrong.
    pub code: FaultCode,
}

/// The board's end of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stopped {
    /// Samples stepped and kept (rolled-back ones excluded).
    pub steps: u32,
    /// Steps whose command was the fault policy's (the board's own checks).
    pub faults: u32,
    /// Steps rolled back because their reply was not used.
    pub rollbacks: u32,
    /// The most ticks a step took.
    pub max_ticks: u32,
}

/// The board's announcement at reset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Boot {
    /// Its [`crate::PROTOCOL_VERSION`].
    pub protocol: u16,
    /// Its name and version.
    pub firmware: String<40>,
}

/// Board to host.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FromBoard<F> {
    /// Sent once at reset.
    Boot(Boot),
    /// The handshake accepted.
    Welcome(Welcome),
    /// The handshake refused.
    Refused(Refusal),
    /// A sample's answer.
    Reply(Reply<F>),
    /// A frame it could not use.
    Fault(Fault),
    /// The session ended.
    Stopped(Stopped),
}
