//! The protocol: frames, round trips of every message and kind, the
//! board's handshake, steps and rollback.
#![allow(clippy::float_cmp)] // bit-for-bit equality is the point

use ehservo_core::control::adrc::AdrcConfig;
use ehservo_core::control::arc::ArcConfig;
use ehservo_core::control::backstepping::BacksteppingConfig;
use ehservo_core::control::nn_robust::{NnRobustConfig, RobustParts};
use ehservo_core::control::pid::PidConfig;
use ehservo_core::control::sliding::{
    NnVscConfig, SlidingConfig, SlidingParts, VscConfig, VscSatConfig,
};
use ehservo_core::control::sta::StaConfig;
use ehservo_core::control::{Config, Design, Signals};
use ehservo_core::prelude::*;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand};
use ehservo_core::servo::Friction;
use ehservo_wire::board::{token, Board};
use ehservo_wire::config::WireController;
use ehservo_wire::frame::{self, Deframer, FrameError, Pushed, MAX_FRAME};
use ehservo_wire::law::NoTicks;
use ehservo_wire::msg::*;
use ehservo_wire::PROTOCOL_VERSION;
use proptest::prelude::*;

fn hello(controller: WireController, float: FloatType) -> Hello {
    Hello {
        protocol: PROTOCOL_VERSION,
        scenario_hash: 0x0123_4567_89ab_cdef,
        float,
        dt: 1e-3,
        controller,
        model: ModelInputs {
            params: ServoParams::paper(),
            load: Load::paper(),
            offset: 0.0,
        },
        surface: SwitchingSurface::paper().p(),
        policy: WirePolicy {
            hold_last: true,
            limits_x: [f64::INFINITY; 3],
            limit_u: f64::INFINITY,
        },
        signals: 16,
    }
}

fn every_kind() -> Vec<WireController> {
    vec![
        WireController::Nnvsc(NnVscConfig::default()),
        WireController::Vsc(VscConfig::default()),
        WireController::VscSat(VscSatConfig::default()),
        WireController::Pid(PidConfig::default()),
        WireController::NnRobust(NnRobustConfig::default()),
        WireController::Adrc(AdrcConfig::default()),
        WireController::Sta(StaConfig::default()),
        WireController::Arc(ArcConfig::default()),
        WireController::Backstepping(BacksteppingConfig::default()),
        WireController::OpenLoop(ehservo_core::control::open_loop::OpenLoopConfig::default()),
    ]
}

fn round_trip<T>(msg: &T) -> T
where
    T: serde::Serialize + serde::de::DeserializeOwned,
{
    let mut out = [0u8; MAX_FRAME];
    let n = frame::seal(msg, &mut out).expect("fits a frame");
    assert_eq!(out[n - 1], 0, "a frame ends in its zero");
    assert!(
        !out[..n - 1].contains(&0),
        "COBS leaves no zero inside a frame"
    );
    let payload = frame::open(&mut out[..n - 1]).expect("opens");
    frame::decode(payload).expect("decodes")
}

/// The CRC is the catalogue's CRC-16/IBM-SDLC (X.25): its check value over
/// the ASCII digits "123456789" is 0x906E (Williams' catalogue, "check").
#[test]
fn the_crc_is_the_catalogues() {
    assert_eq!(frame::CRC16.checksum(b"123456789"), 0x906E);
}

/// Every kind's defaults, and with each optional key given, come back as
/// they were (postcard does not skip a field: `noskip` writes None).
#[test]
fn every_kind_round_trips() {
    for c in every_kind() {
        let h = hello(c.clone(), FloatType::F32);
        let m: ToBoard<f32> = ToBoard::Hello(h.clone());
        assert_eq!(round_trip(&m), m, "{}", c.kind());
    }
    // The options present (None is the default of each).
    let pid = PidConfig {
        kp: Some(12.5),
        ki: Some(0.25),
        kd: Some(3.0e-3),
        ..PidConfig::default()
    };
    let adrc = AdrcConfig {
        omega_c: Some(80.0),
        u_limit: Some(5.0),
        ..AdrcConfig::default()
    };
    let sta = StaConfig {
        k1: Some(4.0),
        ..StaConfig::default()
    };
    let arc = ArcConfig {
        k_s: Some(30.0),
        eps: Some(2.0),
        gamma: Some([1.0, 2.0, 3.0, 4.0]),
        ..ArcConfig::default()
    };
    for c in [
        WireController::Pid(pid),
        WireController::Adrc(adrc),
        WireController::Sta(sta),
        WireController::Arc(arc),
    ] {
        let m: ToBoard<f64> = ToBoard::Hello(hello(c, FloatType::F64));
        assert_eq!(round_trip(&m), m);
    }
    // A load with friction (an optional table).
    let mut h = hello(
        WireController::Nnvsc(NnVscConfig::default()),
        FloatType::F32,
    );
    h.model.load.friction = Some(Friction::default());
    let m: ToBoard<f32> = ToBoard::Hello(h);
    assert_eq!(round_trip(&m), m);
}

#[test]
fn the_other_messages_round_trip() {
    let s: ToBoard<f32> = ToBoard::Sample(Sample {
        k: 123_456,
        acc: 7,
        x: [0.1, -2.5, 1e30],
        z: [f32::MIN_POSITIVE, -0.0, 3.0, f32::MAX],
    });
    assert_eq!(round_trip(&s), s);
    let mut parts = heapless::Vec::new();
    for i in 0..16 {
        parts.push(i as f64 * 0.1 - 0.7).unwrap();
    }
    let r: FromBoard<f64> = FromBoard::Reply(Reply {
        k: 9,
        u: -0.25,
        flags: 16,
        ticks: 58,
        parts,
    });
    assert_eq!(round_trip(&r), r);
    for m in [
        FromBoard::<f32>::Fault(Fault {
            k: None,
            code: FaultCode::BadFrame,
        }),
        FromBoard::Stopped(Stopped {
            steps: 10_001,
            faults: 2,
            rollbacks: 3,
            max_ticks: 61,
        }),
    ] {
        assert_eq!(round_trip(&m), m);
    }
}

/// The byte budget of docs/pil.md, counted: a sample frame of f32 values
/// at k = 5 000 and the Fig. 2 reply (16 parts).
#[test]
fn the_frames_are_as_long_as_the_budget_says() {
    let mut out = [0u8; MAX_FRAME];
    let s: ToBoard<f32> = ToBoard::Sample(Sample {
        k: 5_000,
        acc: 0x89,
        x: [0.1; 3],
        z: [0.2; 4],
    });
    // tag 1 + k 2 (varint of 5000) + acc 1 + 7·4 floats + CRC 2 = 34 bytes,
    // + 1 COBS overhead byte + the zero = 36.
    assert_eq!(frame::seal(&s, &mut out).unwrap(), 36);
    let mut parts = heapless::Vec::new();
    for _ in 0..16 {
        parts.push(0.5f32).unwrap();
    }
    let r: FromBoard<f32> = FromBoard::Reply(Reply {
        k: 5_000,
        u: 1.0,
        flags: 0,
        ticks: 60,
        parts,
    });
    // tag 1 + k 2 + u 4 + flags 1 + ticks 1 + length 1 + 16·4 + CRC 2 = 76,
    // + 1 + 1 = 78.
    assert_eq!(frame::seal(&r, &mut out).unwrap(), 78);
    // f64: 1 + 2 + 1 + 7·8 + 2 = 62 (+ 2) and 1 + 2 + 8 + 1 + 1 + 1 + 16·8
    // + 2 = 144 (+ 2).
    let s64: ToBoard<f64> = ToBoard::Sample(Sample {
        k: 5_000,
        acc: 0x89,
        x: [0.1; 3],
        z: [0.2; 4],
    });
    assert_eq!(frame::seal(&s64, &mut out).unwrap(), 64);
    let mut parts = heapless::Vec::new();
    for _ in 0..16 {
        parts.push(0.5f64).unwrap();
    }
    let r64: FromBoard<f64> = FromBoard::Reply(Reply {
        k: 5_000,
        u: 1.0,
        flags: 0,
        ticks: 60,
        parts,
    });
    assert_eq!(frame::seal(&r64, &mut out).unwrap(), 146);
}

proptest! {
    /// Any Sample round-trips, and any single corrupted byte (or bit) of its
    /// frame is refused: the frame never opens to another message.
    #[test]
    fn samples_round_trip_and_corruption_is_refused(
        k in any::<u32>(), acc in any::<u8>(),
        x in prop::array::uniform3(any::<f32>()), z in prop::array::uniform4(any::<f32>()),
        at in any::<prop::sample::Index>(), flip in 1u8..=255,
    ) {
        let m: ToBoard<f32> = ToBoard::Sample(Sample { k, acc, x, z });
        let mut out = [0u8; MAX_FRAME];
        let n = frame::seal(&m, &mut out).unwrap();
        let mut a = out;
        let back: ToBoard<f32> = frame::decode(frame::open(&mut a[..n - 1]).unwrap()).unwrap();
        // Bit-for-bit (NaNs included).
        let bits = |m: &ToBoard<f32>| match m {
            ToBoard::Sample(s) => (s.k, s.acc, s.x.map(f32::to_bits), s.z.map(f32::to_bits)),
            _ => unreachable!(),
        };
        prop_assert_eq!(bits(&back), bits(&m));
        let i = at.index(n - 1);
        let mut b = out;
        b[i] ^= flip;
        if b[i] != 0 {
            let opened = frame::open(&mut b[..n - 1]);
            prop_assert!(opened.is_err(), "byte {} ^ {:#x} passed", i, flip);
        }
    }

    /// Any Hello of the paper's laws with random gains round-trips.
    #[test]
    fn hellos_round_trip(gamma1 in 0.0f64..1e4, eta in 0.0f64..10.0, dt in 1e-6f64..1.0,
                         hash in any::<u64>(), zero in any::<bool>(), f64_ in any::<bool>()) {
        let c = SlidingConfig { gamma1, eta, ..SlidingConfig::default() };
        let mut h = hello(WireController::Nnvsc(NnVscConfig(c)), if f64_ { FloatType::F64 } else { FloatType::F32 });
        h.dt = dt;
        h.scenario_hash = hash;
        h.policy.hold_last = !zero;
        let m: ToBoard<f64> = ToBoard::Hello(h);
        prop_assert_eq!(round_trip(&m), m);
    }
}

/// The reader finds the frames in a stream with noise between them, and
/// refuses the noise.
#[test]
fn the_deframer_resynchronises() {
    let s: ToBoard<f32> = ToBoard::Stop(Stop { k: 3, acc: 4 });
    let mut out = [0u8; MAX_FRAME];
    let n = frame::seal(&s, &mut out).unwrap();
    let mut stream = vec![7u8, 9, 200, 0]; // noise ended by a zero
    stream.extend_from_slice(&out[..n]);
    stream.extend_from_slice(&[0, 0]); // idle zeros
    stream.extend_from_slice(&out[..n]);
    let mut d: Deframer<MAX_FRAME> = Deframer::new();
    let (mut good, mut bad) = (0, 0);
    for &b in &stream {
        if let Pushed::Frame(len) = d.push(b) {
            match frame::open(d.frame(len)) {
                Ok(p) => {
                    assert_eq!(frame::decode::<ToBoard<f32>>(p).unwrap(), s);
                    good += 1;
                }
                Err(_) => bad += 1,
            }
        }
    }
    assert_eq!((good, bad), (2, 1));
    // A frame longer than the buffer is reported as such.
    let long: ToBoard<f32> = ToBoard::Sample(Sample {
        k: 1,
        acc: 1,
        x: [1.0; 3],
        z: [1.0; 4],
    });
    let n = frame::seal(&long, &mut out).unwrap();
    let mut small: Deframer<8> = Deframer::new();
    let pushed: Vec<Pushed> = out[..n].iter().map(|&b| small.push(b)).collect();
    assert_eq!(pushed.last(), Some(&Pushed::Overrun));
}

#[test]
fn a_frame_too_short_for_its_crc_is_refused() {
    let mut two = [3u8, 1, 1]; // COBS of [1, 0]... decoded: 2 bytes
    assert!(matches!(
        frame::open(&mut two),
        Err(FrameError::Short | FrameError::Cobs)
    ));
}

/// Rebuilding the sliding laws' parts from their values inverts `write`:
/// each slot is its own field (distinct values, so a swap shows).
#[test]
fn rebuild_inverts_write() {
    let n = SlidingParts::<f32>::SIGNALS.len();
    let v: Vec<f32> = (0..n).map(|i| 1.5 + i as f32).collect();
    let p = SlidingParts::<f32>::rebuild(&v).unwrap();
    let mut w = vec![0.0f64; n];
    p.write(&mut w);
    assert_eq!(w, v.iter().map(|&x| f64::from(x)).collect::<Vec<_>>());
    let n = RobustParts::<f64>::SIGNALS.len();
    let v: Vec<f64> = (0..n).map(|i| -0.25 * i as f64).collect();
    let p = RobustParts::<f64>::rebuild(&v).unwrap();
    let mut w = vec![0.0f64; n];
    p.write(&mut w);
    assert_eq!(w, v);
}

fn clock() -> ClockInfo {
    ClockInfo {
        source: TickSource::None,
        tick_hz: 0,
        cycles_per_tick_milli: 0,
    }
}

/// Sends `m` to `b` and decodes the answer.
fn ask<F: ehservo_wire::WireFloat>(b: &mut Board, m: &ToBoard<F>) -> FromBoard<F> {
    let mut out = [0u8; MAX_FRAME];
    let n = frame::seal(m, &mut out).unwrap();
    let mut back = [0u8; MAX_FRAME];
    let r = b.on_frame(&mut out[..n - 1], &mut NoTicks, &mut back);
    frame::decode(frame::open(&mut back[..r - 1]).unwrap()).unwrap()
}

fn welcome(b: &mut Board, h: &Hello) -> Welcome {
    match ask::<f32>(b, &ToBoard::Hello(h.clone())) {
        FromBoard::Welcome(w) => w,
        other => panic!("expected a welcome, got {other:?}"),
    }
}

/// The paper's Fig. 2 NNBVSC built independently: f64 design, cast to f32,
/// in the sampled loop at 1 kHz with the default policy.
fn reference_nnvsc() -> SampledController<NnVsc<f32>, f32> {
    let model = NominalModel::new(ServoParams::paper(), Load::paper());
    let nn = NnVsc::try_new(
        model,
        SwitchingSurface::paper(),
        NnVscParams::paper(),
        Rbf::paper(),
    )
    .unwrap();
    SampledController::new(nn.cast::<f32>().unwrap(), 1e-3f32).unwrap()
}

fn x_at(k: u32) -> [f32; 3] {
    let t = f64::from(k) * 1e-3;
    [(0.01 * t) as f32, (0.02 * t) as f32, (-0.5 * t) as f32]
}

/// A board's steps are the f32 sampled loop's, to the bit, and a step whose
/// reply the host did not use is undone.
#[test]
fn the_board_steps_the_f32_loop_and_rolls_back() {
    let mut b = Board::new("test 0", clock());
    let h = hello(
        WireController::Nnvsc(NnVscConfig::default()),
        FloatType::F32,
    );
    let w = welcome(&mut b, &h);
    assert_eq!(
        (w.scenario_hash, w.signals, w.float),
        (h.scenario_hash, 16, FloatType::F32)
    );
    let mut reference = reference_nnvsc();
    let sine = Sine::paper();
    let mut accepted = None;
    for k in 0..40u32 {
        let x = x_at(k);
        let z = sine.z(f64::from(k) * 1e-3).map(|v| v as f32);
        let r = match ask(
            &mut b,
            &ToBoard::Sample(Sample {
                k,
                acc: token(accepted),
                x,
                z,
            }),
        ) {
            FromBoard::Reply(r) => r,
            other => panic!("k = {k}: {other:?}"),
        };
        assert_eq!(r.k, k);
        // The host uses every reply but those of k = 10 and 11 (lost).
        if k == 10 || k == 11 {
            continue;
        }
        let want = reference.step((f64::from(k) * 1e-3) as f32, x, z);
        assert_eq!(r.u.to_bits(), want.u.to_bits(), "k = {k}");
        assert_eq!(r.parts[2].to_bits(), want.sigma.to_bits(), "σ at k = {k}");
        accepted = Some(k);
    }
    match ask::<f32>(
        &mut b,
        &ToBoard::Stop(Stop {
            k: 39,
            acc: token(accepted),
        }),
    ) {
        FromBoard::Stopped(s) => assert_eq!((s.steps, s.rollbacks), (38, 2)),
        other => panic!("{other:?}"),
    }
    assert!(!b.in_session());
}

#[test]
fn the_handshake_refuses_what_it_cannot_run() {
    let mut b = Board::new("test 0", clock());
    // Another protocol.
    let mut h = hello(
        WireController::Nnvsc(NnVscConfig::default()),
        FloatType::F32,
    );
    h.protocol = PROTOCOL_VERSION + 1;
    match ask::<f32>(&mut b, &ToBoard::Hello(h)) {
        FromBoard::Refused(r) => {
            assert_eq!(r.protocol, PROTOCOL_VERSION);
            assert_eq!(r.reason, RefuseReason::Protocol);
        }
        other => panic!("{other:?}"),
    }
    // A board of another protocol refuses ours.
    let mut old = Board::new("test 0", clock()).with_protocol(PROTOCOL_VERSION + 7);
    let h = hello(
        WireController::Nnvsc(NnVscConfig::default()),
        FloatType::F32,
    );
    assert!(matches!(
        ask::<f32>(&mut old, &ToBoard::Hello(h.clone())),
        FromBoard::Refused(Refusal { protocol, reason: RefuseReason::Protocol }) if protocol == PROTOCOL_VERSION + 7
    ));
    // Parameters that do not build, named.
    let bad = SlidingConfig {
        gamma1: -1.0,
        ..SlidingConfig::default()
    };
    let h2 = hello(WireController::Nnvsc(NnVscConfig(bad)), FloatType::F32);
    match ask::<f32>(&mut b, &ToBoard::Hello(h2)) {
        FromBoard::Refused(Refusal {
            reason: RefuseReason::Param { name, .. },
            ..
        }) => assert_eq!(name.as_str(), "gamma1"),
        other => panic!("{other:?}"),
    }
    // The wrong number of signals.
    let mut h3 = h.clone();
    h3.signals = 3;
    assert!(matches!(
        ask::<f32>(&mut b, &ToBoard::Hello(h3)),
        FromBoard::Refused(Refusal {
            reason: RefuseReason::Signals { board: 16 },
            ..
        })
    ));
    // Samples outside a session, and out of order.
    let s = |k| {
        ToBoard::Sample(Sample {
            k,
            acc: 0,
            x: [0.0f32; 3],
            z: [0.0; 4],
        })
    };
    assert!(matches!(
        ask(&mut b, &s(0)),
        FromBoard::Fault(Fault {
            code: FaultCode::NoSession,
            k: Some(0)
        })
    ));
    welcome(&mut b, &h);
    assert!(matches!(ask(&mut b, &s(5)), FromBoard::Reply(_)));
    assert!(matches!(
        ask(&mut b, &s(5)),
        FromBoard::Fault(Fault {
            code: FaultCode::OutOfOrder,
            ..
        })
    ));
    // A corrupted frame is reported without a k.
    let mut out = [0u8; MAX_FRAME];
    let n = frame::seal(&s(6), &mut out).unwrap();
    out[3] ^= 0x40;
    let mut back = [0u8; MAX_FRAME];
    let r = b.on_frame(&mut out[..n - 1], &mut NoTicks, &mut back);
    assert_eq!(
        frame::decode::<FromBoard<f32>>(frame::open(&mut back[..r - 1]).unwrap()).unwrap(),
        FromBoard::Fault(Fault {
            k: None,
            code: FaultCode::BadFrame
        })
    );
}

/// Every kind builds on the board in both float types, with the fault
/// policy applied in the board's type.
#[test]
fn every_kind_builds_in_both_float_types() {
    for c in every_kind() {
        for f in [FloatType::F32, FloatType::F64] {
            let mut b = Board::new("test 0", clock());
            let design = Design {
                model: NominalModel::new(ServoParams::paper(), Load::paper()),
                surface: SwitchingSurface::paper(),
                dt: 1e-3,
            };
            let n = match &c {
                WireController::Pid(p) => signals_of(p, &design),
                WireController::Adrc(p) => signals_of(p, &design),
                WireController::Sta(p) => signals_of(p, &design),
                WireController::Arc(p) => signals_of(p, &design),
                WireController::Backstepping(p) => signals_of(p, &design),
                WireController::NnRobust(p) => signals_of(p, &design),
                WireController::OpenLoop(p) => signals_of(p, &design),
                _ => 16,
            };
            let mut h = hello(c.clone(), f);
            h.signals = n as u8;
            h.policy = WirePolicy {
                hold_last: false,
                limits_x: [1.0, 10.0, 1e3],
                limit_u: 0.125,
            };
            let w = welcome(&mut b, &h);
            assert_eq!(w.signals as usize, n, "{}", c.kind());
            let s = Sample::<f64> {
                k: 0,
                acc: 0,
                x: [0.0; 3],
                z: Sine::paper().z(0.0),
            };
            let r = match f {
                FloatType::F64 => match ask(&mut b, &ToBoard::Sample(s)) {
                    FromBoard::Reply(r) => (r.u, r.flags),
                    o => panic!("{o:?}"),
                },
                FloatType::F32 => {
                    let s = Sample::<f32> {
                        k: 0,
                        acc: 0,
                        x: [0.0; 3],
                        z: s.z.map(|v| v as f32),
                    };
                    match ask(&mut b, &ToBoard::Sample(s)) {
                        FromBoard::Reply(r) => (f64::from(r.u), r.flags),
                        o => panic!("{o:?}"),
                    }
                }
            };
            assert!(r.0.abs() <= 0.125, "{} {:?}: {r:?}", c.kind(), f);
            // |θ| = 2 rad > 1 rad: a measurement fault, the zero command.
            let bad = |k| Sample::<f32> {
                k,
                acc: 1,
                x: [2.0, 0.0, 0.0],
                z: [0.0; 4],
            };
            if f == FloatType::F32 {
                match ask(&mut b, &ToBoard::Sample(bad(1))) {
                    FromBoard::Reply(r) => {
                        assert_eq!(r.u, 0.0);
                        assert_ne!(r.flags & ehservo_core::control::flags::MEASUREMENT_FAULT, 0);
                    }
                    o => panic!("{o:?}"),
                }
            }
        }
    }
    fn signals_of<K: Config>(_: &K, _: &Design) -> usize {
        use ehservo_core::control::Controller;
        <<K::Controller as Controller>::Parts as Signals>::SIGNALS.len()
    }
}

/// A policy that holds the last command, cast to f32 as the board does.
#[test]
fn the_policy_is_the_scenarios() {
    let p = FaultPolicy::<f64> {
        safe: SafeCommand::HoldLast,
        limits: Limits {
            x: [1.0, 2.0, 3.0],
            u: 10.0,
        },
    };
    assert_eq!(p.limits.cast::<f32>().x, [1.0f32, 2.0, 3.0]);
}
