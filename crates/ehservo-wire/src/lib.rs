//! # ehservo-wire
//!
//! The processor-in-the-loop protocol between `ehservo pil` (the host,
//! which simulates the plant, the valve, the sensors and the delays) and a
//! board that runs the scenario's controller: `no_std`, no allocation,
//! shared by the host and the firmware (`examples/firmware-pil`).
//!
//! - [`msg`]: the messages, as serde types — the handshake ([`msg::Hello`]:
//!   protocol version, scenario hash, the controller's kind and parameters,
//!   the nominal model, the surface, the sample period, the float type, the
//!   fault policy), the per-sample measurement and reply (the command, the
//!   law's named parts and the step's timer ticks), faults and the stop.
//! - [`frame`]: postcard, then a CRC-16, then COBS and a zero byte.
//! - [`config`]: the controller's configuration (the core's `Config` types,
//!   carried as they are through [`noskip`]).
//! - [`law`]: any kind's `SampledController` in f32 or f64, built from a
//!   Hello.
//! - [`board`]: the board's side of a session (the firmware's loop, and the
//!   host's `--float f32` run in-process).
//!
//! The byte budget per sample and the whole protocol are in `docs/pil.md`.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod board;
pub mod config;
pub mod frame;
pub mod law;
pub mod msg;
pub mod noskip;

use ehservo_core::math::Real;
use msg::FloatType;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// The protocol's version: a host and a board that differ refuse each
/// other at the handshake.
pub const PROTOCOL_VERSION: u16 = 1;

/// A float type the wire carries.
pub trait WireFloat: Real + Serialize + DeserializeOwned {
    /// Its tag in the handshake.
    const FLOAT: FloatType;
}

impl WireFloat for f32 {
    const FLOAT: FloatType = FloatType::F32;
}

impl WireFloat for f64 {
    const FLOAT: FloatType = FloatType::F64;
}

/// FNV-1a, 64 bits (the scenario fingerprint of `ehservo fmu` too): catches
/// a handshake answered for other bytes than the ones sent; not a security
/// measure.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[cfg(test)]
mod fnv1a_tests {
    #[test]
    fn fnv1a_gives_the_published_test_vectors() {
        assert_eq!(super::fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(super::fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(super::fnv1a(b"foobar"), 0x85944171f73967e8);
    }
}
