//! Frames: a message's postcard bytes, their CRC-16 appended, COBS-encoded
//! and ended by a zero byte.
//!
//! ```text
//! frame = COBS( postcard(message) ‖ CRC-16/IBM-SDLC(postcard(message)), little-endian ) ‖ 0x00
//! ```
//!
//! COBS leaves no zero inside a frame, so a reader that lost its place
//! (a dropped or corrupted byte) is back in step at the next zero; the CRC
//! (the X.25/HDLC polynomial 0x1021, reflected, init and xor-out 0xFFFF;
//! every error of up to 3 bits, and every burst of up to 16 bits, in a frame
//! of this size is detected) refuses what COBS alone would pass. The
//! encoding is the `postcard`, `cobs` and `crc` crates'.

use crate::noskip::Filled;
use crc::{Crc, CRC_16_IBM_SDLC};
use serde::{Deserialize, Serialize};

/// The CRC of every frame.
pub const CRC16: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_SDLC);

/// The longest message (postcard bytes).
pub const MAX_PAYLOAD: usize = 768;

/// The longest frame: the payload and its CRC, COBS-encoded, and the zero.
pub const MAX_FRAME: usize = cobs::max_encoding_length(MAX_PAYLOAD + 2) + 1;

/// Why a frame could not be made or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// The message does not fit [`MAX_PAYLOAD`] or the output buffer.
    TooLong,
    /// The bytes are not COBS (a zero where none can be, a short block).
    Cobs,
    /// Fewer bytes than a CRC.
    Short,
    /// The CRC does not match: corrupted.
    Crc,
    /// The CRC matches but the bytes are not a message of this protocol.
    Decode,
}

impl FrameError {
    /// A few words for people.
    pub fn as_str(self) -> &'static str {
        match self {
            FrameError::TooLong => "message too long for a frame",
            FrameError::Cobs => "not a COBS frame",
            FrameError::Short => "frame shorter than its CRC",
            FrameError::Crc => "CRC mismatch",
            FrameError::Decode => "CRC good but not a message of this protocol",
        }
    }
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(feature = "std")]
impl std::error::Error for FrameError {}

/// A message's postcard bytes in `out`; returns their length.
pub fn payload<T: Serialize>(msg: &T, out: &mut [u8]) -> Result<usize, FrameError> {
    let cap = out.len().min(MAX_PAYLOAD);
    postcard::to_slice(&Filled(msg), &mut out[..cap])
        .map(|b| b.len())
        .map_err(|_| FrameError::TooLong)
}

/// The frame of `msg` in `out` (at least [`MAX_FRAME`] bytes to be sure);
/// returns its length, the final zero included.
pub fn seal<T: Serialize>(msg: &T, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut buf = [0u8; MAX_PAYLOAD + 2];
    let n = payload(msg, &mut buf)?;
    seal_payload(&mut buf, n, out)
}

/// The frame of the `n` payload bytes at the start of `buf` (which has 2
/// bytes to spare after them for the CRC).
pub fn seal_payload(buf: &mut [u8], n: usize, out: &mut [u8]) -> Result<usize, FrameError> {
    if buf.len() < n + 2 {
        return Err(FrameError::TooLong);
    }
    let crc = CRC16.checksum(&buf[..n]).to_le_bytes();
    buf[n..n + 2].copy_from_slice(&crc);
    let m = cobs::try_encode(&buf[..n + 2], out).map_err(|_| FrameError::TooLong)?;
    if m >= out.len() {
        return Err(FrameError::TooLong);
    }
    out[m] = 0;
    Ok(m + 1)
}

/// Decodes a frame in place (`frame` without its final zero) and checks its
/// CRC; returns the payload.
pub fn open(frame: &mut [u8]) -> Result<&[u8], FrameError> {
    let n = cobs::decode_in_place(frame).map_err(|_| FrameError::Cobs)?;
    if n < 3 {
        return Err(FrameError::Short);
    }
    let (body, crc) = frame[..n].split_at(n - 2);
    if CRC16.checksum(body).to_le_bytes() != [crc[0], crc[1]] {
        return Err(FrameError::Crc);
    }
    Ok(body)
}

/// The message of a payload; every byte must be used.
pub fn decode<'a, T: Deserialize<'a>>(payload: &'a [u8]) -> Result<T, FrameError> {
    match postcard::take_from_bytes(payload) {
        Ok((v, [])) => Ok(v),
        _ => Err(FrameError::Decode),
    }
}

/// What [`Deframer::push`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pushed {
    /// Nothing yet.
    Nothing,
    /// A frame of this many bytes (without the zero) is in
    /// [`Deframer::frame`], until the next push.
    Frame(usize),
    /// A frame longer than the buffer ended: it was dropped.
    Overrun,
}

/// Splits a byte stream at its zeros.
#[derive(Debug, Clone)]
pub struct Deframer<const N: usize> {
    buf: [u8; N],
    len: usize,
    overrun: bool,
    done: bool,
}

impl<const N: usize> Default for Deframer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Deframer<N> {
    /// Empty.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            overrun: false,
            done: false,
        }
    }

    /// One byte of the stream.
    pub fn push(&mut self, b: u8) -> Pushed {
        if self.done {
            self.len = 0;
            self.done = false;
        }
        if b == 0 {
            self.done = true;
            if self.overrun {
                self.overrun = false;
                return Pushed::Overrun;
            }
            if self.len == 0 {
                // Two zeros in a row (a sender's resynchronising zero).
                return Pushed::Nothing;
            }
            return Pushed::Frame(self.len);
        }
        if self.len < N {
            self.buf[self.len] = b;
            self.len += 1;
        } else {
            self.overrun = true;
        }
        Pushed::Nothing
    }

    /// The frame [`Deframer::push`] reported (`n` bytes).
    pub fn frame(&mut self, n: usize) -> &mut [u8] {
        &mut self.buf[..n.min(N)]
    }

    /// Forgets a partial frame.
    pub fn clear(&mut self) {
        self.len = 0;
        self.overrun = false;
        self.done = false;
    }

    /// Bytes of the frame being read.
    pub fn pending(&self) -> usize {
        if self.done {
            0
        } else {
            self.len
        }
    }
}
