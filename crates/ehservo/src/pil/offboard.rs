//! The controller the simulator runs when the law is off-board: each
//! sample's `law_euler` is one exchange with the board.

use super::session::Session;
use crate::run::MapController;
use crate::scenario::ControllerConfig;
use ehservo_core::control::{
    flags, Config, Controller, Measurement, Output, Signal, Signals, Truth,
};
use ehservo_core::rk4::OdeState;
use ehservo_core::sampled::SafeCommand;
use ehservo_wire::law::{AnyLaw, FAULT_FLAGS};
use ehservo_wire::msg::MAX_PARTS;
use std::cell::RefCell;
use std::marker::PhantomData;
use std::rc::Rc;

/// The host's copy of the board's controller, never stepped: it fills the
/// diagnostics that need the true plant from the board's parts.
pub enum Shadow {
    /// In f32.
    F32(Box<AnyLaw<f32>>),
    /// In f64.
    F64(Box<AnyLaw<f64>>),
}

/// The session and what the host keeps beside it.
pub struct Link {
    /// The session with the board.
    pub session: Session,
    shadow: Shadow,
    slots: [bool; MAX_PARTS],
    safe: SafeCommand,
    last_u: f64,
}

impl Link {
    /// Over an open session; `shadow` built from the same Hello, `safe` the
    /// scenario's fault policy.
    pub fn new(session: Session, shadow: Shadow, safe: SafeCommand) -> Self {
        let slots = match &shadow {
            Shadow::F32(l) => l.truth_slots(),
            Shadow::F64(l) => l.truth_slots(),
        };
        Self {
            session,
            shadow,
            slots,
            safe,
            last_u: 0.0,
        }
    }

    /// Whether some of the kind's signals need the true plant and its
    /// parts cannot be rebuilt on the host (then the run is refused).
    pub fn cannot_annotate(&self) -> bool {
        let rebuilds = match &self.shadow {
            Shadow::F32(l) => l.rebuilds(),
            Shadow::F64(l) => l.rebuilds(),
        };
        self.slots.iter().any(|&s| s) && !rebuilds
    }

    fn annotate(&self, u: f64, fl: u8, values: &mut [f64; MAX_PARTS], truth: &dyn Truth) {
        match &self.shadow {
            Shadow::F32(l) => {
                let mut v = values.map(|x| x as f32);
                l.annotate_host(u as f32, fl, &mut v, &self.slots, truth);
                *values = v.map(f64::from);
            }
            Shadow::F64(l) => l.annotate_host(u, fl, values, &self.slots, truth),
        }
    }
}

/// A kind's parts as values, relayed from the board: the kind's signals.
pub struct Relay<K> {
    v: [f64; MAX_PARTS],
    _k: PhantomData<fn() -> K>,
}

impl<K> Clone for Relay<K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<K> Copy for Relay<K> {}

impl<K> Default for Relay<K> {
    fn default() -> Self {
        Self {
            v: [0.0; MAX_PARTS],
            _k: PhantomData,
        }
    }
}

impl<K: ControllerConfig> Signals for Relay<K> {
    const SIGNALS: &'static [Signal] =
        <<<K as Config>::Controller as Controller>::Parts as Signals>::SIGNALS;
    fn write(&self, out: &mut [f64]) {
        let n = Self::SIGNALS.len().min(out.len());
        out[..n].copy_from_slice(&self.v[..n]);
    }
}

/// Kind `K`'s controller on a board.
pub struct Offboard<K> {
    link: Rc<RefCell<Link>>,
    network: bool,
    _k: PhantomData<fn() -> K>,
}

impl<K> Clone for Offboard<K> {
    fn clone(&self) -> Self {
        Self {
            link: Rc::clone(&self.link),
            network: self.network,
            _k: PhantomData,
        }
    }
}

/// A stand-in weight: the weights are on the board. Code that asks
/// *whether* there is a network (the metrics' ‖W‖ statistics, read from
/// the samples' `w_norm`) gets the truth; there are no values to read.
static ON_THE_BOARD: [f64; 1] = [f64::NAN];

impl<K: ControllerConfig> Controller for Offboard<K> {
    /// The board holds the state; the simulator's copy is a placeholder.
    type State = [f64; 1];
    type Parts = Relay<K>;

    fn initial_state(&self) -> [f64; 1] {
        [0.0]
    }

    /// The continuous mode has no samples to exchange: refused before a
    /// run starts (`ehservo pil` needs `simulation.mode = "sampled"`); here
    /// a non-finite command would end the run.
    fn law(&self, _m: &Measurement, _s: &[f64; 1], _ds: &mut [f64; 1]) -> Output<Relay<K>> {
        Output {
            u: f64::NAN,
            flags: flags::NON_FINITE_CONTROL,
            parts: Relay::default(),
        }
    }

    fn law_euler(
        &self,
        m: &Measurement,
        s: &[f64; 1],
        next: &mut [f64; 1],
        dt: f64,
    ) -> (Output<Relay<K>>, bool) {
        *next = *s;
        let mut l = self.link.borrow_mut();
        // t_k = k·h exactly, so the quotient rounds to k.
        let k = (m.t / dt).round() as u32;
        match l.session.exchange(k, m.x, m.z) {
            Ok(a) => {
                l.last_u = a.u;
                (
                    Output {
                        u: a.u,
                        flags: a.flags,
                        parts: Relay {
                            v: a.values,
                            _k: PhantomData,
                        },
                    },
                    true,
                )
            }
            Err(_) => {
                // The fault is recorded by the session; the policy acts.
                let u = match l.safe {
                    SafeCommand::HoldLast => l.last_u,
                    SafeCommand::Zero => 0.0,
                };
                (
                    Output {
                        u,
                        flags: flags::LINK_FAULT,
                        parts: Relay::default(),
                    },
                    true,
                )
            }
        }
    }

    fn weights<'a>(&self, _s: &'a [f64; 1]) -> &'a [f64] {
        if self.network {
            &ON_THE_BOARD
        } else {
            &[]
        }
    }

    fn annotate(&self, _s: &[f64; 1], out: &mut Output<Relay<K>>, truth: &dyn Truth) {
        if out.flags & (FAULT_FLAGS | flags::LINK_FAULT) == 0 {
            let (u, fl) = (out.u, out.flags);
            self.link.borrow().annotate(u, fl, &mut out.parts.v, truth);
        }
    }
}

/// Puts the scenario's controller on the board behind `link`.
pub struct OnBoard(pub Rc<RefCell<Link>>);

impl MapController for OnBoard {
    type Out<K: ControllerConfig> = Offboard<K>;
    fn map<K: ControllerConfig>(self, _cfg: &K, built: K::Controller) -> Offboard<K> {
        let zero = <<K::Controller as Controller>::State as OdeState>::zero();
        Offboard {
            link: self.0,
            network: !built.weights(&zero).is_empty(),
            _k: PhantomData,
        }
    }
}
