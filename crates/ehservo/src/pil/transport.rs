//! Byte streams to a board: a TCP socket (QEMU's UART, a proxy, a serial
//! server), a serial port, or a board in this process.

use ehservo_wire::board::Board;
use ehservo_wire::frame::{Deframer, Pushed, MAX_FRAME};
use ehservo_wire::law::NoTicks;
use ehservo_wire::msg::{ClockInfo, TickSource};
use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// A byte stream to a board.
pub trait Transport {
    /// Sends every byte.
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Reads what has arrived (at least one byte) before `deadline`; 0 when
    /// the deadline passed first; an error when the link is closed or
    /// failed.
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;
    /// Where it leads, for people.
    fn describe(&self) -> String;
    /// The next frame sent is sample `k`'s, or not a sample's (`None`): a
    /// fault injector ([`Faulty`]) acts on it; others ignore it.
    fn at(&mut self, _k: Option<u32>) {}
}

/// What is left until `deadline`, at least 1 µs (a zero timeout would mean
/// "block" to the socket).
fn left(deadline: Instant) -> Option<Duration> {
    let now = Instant::now();
    (now < deadline).then(|| (deadline - now).max(Duration::from_micros(1)))
}

/// After a read interrupted by a signal: an error of kind `Interrupted`
/// when the signal is one that ends the run (its handler then exits with
/// 130, which `main` waits for), else nothing (read on).
fn interrupted() -> io::Result<()> {
    if crate::interrupt::signalled() {
        Err(io::Error::new(
            io::ErrorKind::Interrupted,
            "interrupted by a signal",
        ))
    } else {
        Ok(())
    }
}

/// A TCP connection (Nagle off: a frame goes out as it is written).
pub struct Tcp {
    stream: TcpStream,
    peer: String,
}

impl Tcp {
    /// Over a connected stream.
    pub fn new(stream: TcpStream) -> io::Result<Self> {
        stream.set_nodelay(true)?;
        let peer = stream
            .peer_addr()
            .map(|a| a.to_string())
            .unwrap_or_else(|_| "?".into());
        Ok(Self { stream, peer })
    }
}

impl Transport for Tcp {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.write_all(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        // A signal interrupts the read (EINTR): read on until the deadline
        // (a signal that ends the run is the handler's to act on, exit
        // 130), never report the deadline passed before it has.
        loop {
            let Some(t) = left(deadline) else {
                return Ok(0);
            };
            self.stream.set_read_timeout(Some(t))?;
            match self.stream.read(buf) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the board closed the connection",
                    ))
                }
                r => match read_outcome(r) {
                    Some(out) => return out,
                    None => continue,
                },
            }
        }
    }
    fn describe(&self) -> String {
        format!("tcp {}", self.peer)
    }
}

/// A serial port (8N1, no flow control).
pub struct Serial {
    port: Box<dyn serialport::SerialPort>,
    name: String,
    baud: u32,
}

impl Serial {
    /// Opens `path` at `baud`.
    pub fn open(path: &str, baud: u32) -> Result<Self, serialport::Error> {
        let port = serialport::new(path, baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(10))
            .open()?;
        // What an earlier session left in the buffers is not ours.
        let _ = port.clear(serialport::ClearBuffer::All);
        Ok(Self {
            port,
            name: path.to_string(),
            baud,
        })
    }
}

impl Transport for Serial {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.write_all(bytes)?;
        self.port.flush()
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        // EINTR: read on until the deadline (as [`Tcp`]'s).
        loop {
            let Some(t) = left(deadline) else {
                return Ok(0);
            };
            self.port
                .set_timeout(t)
                .map_err(|e| io::Error::other(e.to_string()))?;
            if let Some(out) = read_outcome(self.port.read(buf)) {
                return out;
            }
        }
    }
    fn describe(&self) -> String {
        format!("serial {} at {} baud", self.name, self.baud)
    }
}

/// The board's own code in this process: every frame the host sends is
/// handled at once by an [`ehservo_wire::board::Board`], and its answer is
/// there to read. `ehservo run --float f32` runs on one; tests put a
/// [`Faulty`] around it.
pub struct InProcess {
    board: Board,
    rx: Deframer<MAX_FRAME>,
    outbox: VecDeque<u8>,
}

/// The name the in-process board gives itself.
pub const IN_PROCESS: &str = concat!("ehservo ", env!("CARGO_PKG_VERSION"), " in-process board");

impl Default for InProcess {
    fn default() -> Self {
        Self::new()
    }
}

impl InProcess {
    /// A board that has just booted (its Boot frame waits to be read).
    pub fn new() -> Self {
        let board = Board::new(
            IN_PROCESS,
            ClockInfo {
                source: TickSource::None,
                tick_hz: 0,
                cycles_per_tick_milli: 0,
            },
        );
        let mut out = [0u8; MAX_FRAME];
        let n = board.boot_frame(&mut out);
        Self {
            board,
            rx: Deframer::new(),
            outbox: out[..n].iter().copied().collect(),
        }
    }

    /// The same board, speaking another protocol version (tests).
    pub fn with_protocol(mut self, v: u16) -> Self {
        self.board =
            std::mem::replace(&mut self.board, Board::new(IN_PROCESS, CLOCK0)).with_protocol(v);
        self
    }

    /// The board resets: its session is gone, it says Boot again.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

const CLOCK0: ClockInfo = ClockInfo {
    source: TickSource::None,
    tick_hz: 0,
    cycles_per_tick_milli: 0,
};

impl Transport for InProcess {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let mut out = [0u8; MAX_FRAME];
        for &b in bytes {
            let n = match self.rx.push(b) {
                Pushed::Nothing => continue,
                Pushed::Frame(len) => {
                    self.board
                        .on_frame(self.rx.frame(len), &mut NoTicks, &mut out)
                }
                Pushed::Overrun => self.board.overrun(&mut out),
            };
            self.outbox.extend(&out[..n]);
        }
        Ok(())
    }
    fn recv(&mut self, buf: &mut [u8], _deadline: Instant) -> io::Result<usize> {
        let n = buf.len().min(self.outbox.len());
        for (o, b) in buf.iter_mut().zip(self.outbox.drain(..n)) {
            *o = b;
        }
        Ok(n)
    }
    fn describe(&self) -> String {
        IN_PROCESS.to_string()
    }
}

/// A fault to put between host and board, at one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inject {
    /// Flip a bit of the sample's frame on its way to the board.
    CorruptRequest,
    /// Flip a bit of the reply on its way back.
    CorruptReply,
    /// Lose the sample's frame.
    DropRequest,
    /// Lose the reply.
    DropReply,
    /// Hold the reply back until after the host's deadline.
    LateReply,
    /// Reset the board as the sample's frame reaches it (in-process and
    /// QEMU boards).
    ResetBoard,
}

impl Inject {
    /// The spelling of `--inject`.
    pub const NAMES: [(&'static str, Inject); 6] = [
        ("corrupt-request", Inject::CorruptRequest),
        ("corrupt-reply", Inject::CorruptReply),
        ("drop-request", Inject::DropRequest),
        ("drop-reply", Inject::DropReply),
        ("late-reply", Inject::LateReply),
        ("reset-board", Inject::ResetBoard),
    ];

    /// Parses `KIND@K` (a sample index).
    pub fn parse(s: &str) -> Option<(Inject, u32)> {
        let (name, k) = s.split_once('@')?;
        let k = k.trim().parse().ok()?;
        Self::NAMES
            .iter()
            .find(|(n, _)| *n == name.trim())
            .map(|&(_, i)| (i, k))
    }
}

/// How a board resets on request (for [`Inject::ResetBoard`]).
pub trait Reset {
    /// Resets the board now.
    fn reset(&mut self) -> io::Result<()>;
}

/// A transport that injects faults at chosen samples. The host tells it
/// which sample it is sending ([`Faulty::at`]); the faults act on whole
/// frames of the byte stream.
pub struct Faulty<T: Transport> {
    inner: T,
    plan: Vec<(u32, Inject)>,
    reset: Option<Box<dyn Reset>>,
    k: Option<u32>,
    /// Replies held back ([`Inject::LateReply`]): released at the next send.
    held: Vec<u8>,
    /// The current sample's reply bytes seen so far (to drop or corrupt it
    /// whole).
    reply: Vec<u8>,
    active: Option<Inject>,
    ready: VecDeque<u8>,
}

impl<T: Transport> Faulty<T> {
    /// `inner` with the faults of `plan` (sample index, fault).
    pub fn new(inner: T, plan: Vec<(u32, Inject)>) -> Self {
        Self {
            inner,
            plan,
            reset: None,
            k: None,
            held: Vec::new(),
            reply: Vec::new(),
            active: None,
            ready: VecDeque::new(),
        }
    }

    /// How to reset the board for [`Inject::ResetBoard`].
    pub fn with_reset(mut self, r: Box<dyn Reset>) -> Self {
        self.reset = Some(r);
        self
    }

    fn fault_now(&self) -> Option<Inject> {
        let k = self.k?;
        self.plan.iter().find(|(j, _)| *j == k).map(|&(_, i)| i)
    }
}

/// Flips one bit in the middle of a frame (never its final zero).
fn flip(frame: &mut [u8]) {
    if frame.len() > 2 {
        let i = frame.len() / 2;
        frame[i] ^= 0x10;
        if frame[i] == 0 {
            frame[i] = 0x10;
        }
    }
}

impl<T: Transport> Transport for Faulty<T> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        // A held reply is released now: it reaches the host after its
        // deadline, before the next reply.
        let held = std::mem::take(&mut self.held);
        self.ready.extend(held);
        self.reply.clear();
        self.active = self.fault_now();
        match self.active {
            Some(Inject::DropRequest) => Ok(()),
            Some(Inject::CorruptRequest) => {
                let mut b = bytes.to_vec();
                flip(&mut b);
                self.inner.send(&b)
            }
            Some(Inject::ResetBoard) => {
                if let Some(r) = self.reset.as_mut() {
                    r.reset()?;
                }
                self.inner.send(bytes)
            }
            _ => self.inner.send(bytes),
        }
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        loop {
            if !self.ready.is_empty() {
                let n = buf.len().min(self.ready.len());
                for (o, b) in buf.iter_mut().zip(self.ready.drain(..n)) {
                    *o = b;
                }
                return Ok(n);
            }
            let mut tmp = [0u8; 512];
            let n = self.inner.recv(&mut tmp, deadline)?;
            if n == 0 {
                return Ok(0);
            }
            match self.active {
                Some(f @ (Inject::DropReply | Inject::CorruptReply | Inject::LateReply)) => {
                    self.reply.extend_from_slice(&tmp[..n]);
                    // Act once the reply's frame is whole.
                    if let Some(end) = self.reply.iter().position(|&b| b == 0) {
                        let mut frame: Vec<u8> = self.reply.drain(..=end).collect();
                        let rest = std::mem::take(&mut self.reply);
                        self.active = None;
                        match f {
                            Inject::DropReply => {}
                            Inject::CorruptReply => {
                                flip(&mut frame);
                                self.ready.extend(frame);
                            }
                            _ => self.held.extend(frame),
                        }
                        self.ready.extend(rest);
                    }
                }
                _ => self.ready.extend(&tmp[..n]),
            }
        }
    }
    fn describe(&self) -> String {
        format!("{} with injected faults", self.inner.describe())
    }
    fn at(&mut self, k: Option<u32>) {
        self.k = k;
    }
}

/// An in-process board resets through this handle ([`Faulty::with_reset`]
/// needs the board itself: the transport is then built around it).
pub struct ResettableInProcess(pub std::rc::Rc<std::cell::RefCell<InProcess>>);

impl Transport for ResettableInProcess {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.0.borrow_mut().send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.0.borrow_mut().recv(buf, deadline)
    }
    fn describe(&self) -> String {
        self.0.borrow().describe()
    }
}

impl Reset for std::rc::Rc<std::cell::RefCell<InProcess>> {
    fn reset(&mut self) -> io::Result<()> {
        self.borrow_mut().reset();
        Ok(())
    }
}

impl Transport for Box<dyn Transport> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        (**self).send(bytes)
    }
    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        (**self).recv(buf, deadline)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
    fn at(&mut self, k: Option<u32>) {
        (**self).at(k)
    }
}

/// A timed read's result as `recv` returns it: the bytes read, a timeout
/// as 0 bytes, an error as it is; `None` to read on, when a signal
/// interrupted the read and no SIGINT is pending (with one, the
/// cancellation's error).
fn read_outcome(r: io::Result<usize>) -> Option<io::Result<usize>> {
    match r {
        Ok(n) => Some(Ok(n)),
        Err(e) if e.kind() == io::ErrorKind::Interrupted => interrupted().err().map(Err),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
            ) =>
        {
            Some(Ok(0))
        }
        Err(e) => Some(Err(e)),
    }
}
