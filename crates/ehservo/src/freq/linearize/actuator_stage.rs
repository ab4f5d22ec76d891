//! The actuator stage's analytic Jacobian: saturation, a first- or
//! second-order spool with its rate limit, the dead band and the null
//! bias, with their kinks and one-sided slopes; and the spool's replay and
//! the trim's inversion the operating point uses.

use super::{Jacobian, Kink, Linearize, Point, Side, AT_KINK};
use crate::actuator::{Actuator, ActuatorConfig, Dynamics as Spool};
use crate::freq::ss::Quantity;
use ehservo_core::error::ParamError;
use ehservo_sim::error::KeyError;

/// The actuator stage: command (V) → saturation → spool → dead band and
/// null bias → the plant's input (V). Its states are the spool's: none,
/// `v` (first order) or `(v, v̇)` (second order).
///
/// ```text
/// sat'(u) = 1 for |u| < limit, 0 beyond (kink at |u| = limit)
/// first:  v̇ = (sat(u) − v)/τ          A = −1/τ, B = sat'/τ   (|v̇| < rate_limit; 0 beyond)
/// second: v̇ = w, ẇ = ωn²(sat(u) − v) − 2ζωn·w
///         A = [[0, 1], [−ωn², −2ζωn]], B = (0, ωn²·sat')     (|w| < rate_limit)
/// output: db(v + null_bias), slope 1 outside the dead band, 0 inside (kink at its edge)
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorStage {
    act: Actuator,
    limit: f64,
    rate: f64,
    spool: Spool,
    dead_band: f64,
    null_bias: f64,
}

impl ActuatorStage {
    /// The stage of the simulator's actuator (its spool dynamics as
    /// `Actuator::try_new` derived them from `[actuator]`).
    pub fn new(act: &Actuator) -> Self {
        Self {
            act: *act,
            limit: act.limit(),
            rate: act.rate_limit(),
            spool: act.dynamics(),
            dead_band: act.dead_band(),
            null_bias: act.null_bias(),
        }
    }

    /// The stage of `[actuator]`, validated as `Actuator::try_new` does.
    pub fn of_config(c: &ActuatorConfig) -> Result<Self, ParamError> {
        Actuator::try_new(c).map(|a| Self::new(&a))
    }

    /// The simulator's stage.
    pub fn actuator(&self) -> &Actuator {
        &self.act
    }

    /// The spool state `(v, w)` of the simulator from this stage's states.
    fn full(&self, x: &[f64]) -> [f64; 2] {
        [
            x.first().copied().unwrap_or(0.0),
            x.get(1).copied().unwrap_or(0.0),
        ]
    }

    /// The number of states.
    pub fn n(&self) -> usize {
        match self.spool {
            Spool::None => 0,
            Spool::First { .. } => 1,
            Spool::Second { .. } => 2,
        }
    }

    /// The stage's state at a logged sample: the spool position, and for a
    /// second-order spool its rate, which a sample does not carry (`w`
    /// comes from [`ActuatorStage::replay`]).
    pub fn state_from(&self, spool: f64, rate: f64) -> Vec<f64> {
        match self.spool {
            Spool::None => Vec::new(),
            Spool::First { .. } => vec![spool],
            Spool::Second { .. } => vec![spool, rate],
        }
    }

    /// The spool's state after the held commands `u` (one per sample of
    /// `h`, integrated by `substeps` RK4 steps each, from rest): the
    /// simulator integrates the spool with the plant in one RK4 state, but
    /// the spool's derivative does not depend on the plant, so its
    /// components of that step are this stage's RK4 step alone.
    pub fn replay(&self, u: &[f64], h: f64, substeps: u32) -> [f64; 2] {
        let mut s = self.act.initial_state();
        if self.spool == Spool::None {
            return s;
        }
        let m = substeps.max(1);
        let hs = h / f64::from(m);
        let act = &self.act;
        for &uk in u {
            for _ in 0..m {
                ehservo_core::rk4::rk4_step(
                    |_t, y: &[f64; 2], dy: &mut [f64; 2]| act.deriv(y, uk, dy),
                    0.0,
                    &mut s,
                    hs,
                );
            }
        }
        s
    }

    /// The steady state that delivers the plant input `p`: the spool at
    /// rest where the dead band and null bias give `p`, the command that
    /// holds it there. An error names the key that makes it impossible.
    pub fn invert(&self, p: f64) -> Result<(Vec<f64>, f64), KeyError> {
        let v = if p == 0.0 {
            0.0 - self.null_bias
        } else {
            p + self.dead_band * p.signum() - self.null_bias
        };
        if v.abs() > self.limit {
            return Err(KeyError::new(
                "actuator.limit",
                format!(
                    "the trim needs a spool at {v:.6} V (the plant's input {p:.6} V), beyond the saturation ±{} V",
                    self.limit
                ),
            ));
        }
        Ok((self.state_from(v, 0.0), v))
    }

    /// The saturation's slope on `side` at `u`.
    fn sat_slope(&self, u: f64, side: Side) -> f64 {
        let over = u.abs() - self.limit;
        if self.limit.is_infinite() || over < -AT_KINK * self.limit {
            1.0
        } else if over > AT_KINK * self.limit {
            0.0
        } else {
            // At the limit: inside from below at +limit, from above at −limit.
            let inside = (u > 0.0) == (side == Side::Minus);
            if inside {
                1.0
            } else {
                0.0
            }
        }
    }

    /// The dead band's slope on `side` at spool `v`.
    fn db_slope(&self, v: f64, side: Side) -> f64 {
        if self.dead_band == 0.0 {
            return 1.0;
        }
        let q = v + self.null_bias;
        let over = q.abs() - self.dead_band;
        if over > AT_KINK * self.dead_band {
            1.0
        } else if over < -AT_KINK * self.dead_band {
            0.0
        } else {
            // At the edge: outside from above at +db, from below at −db.
            let outside = (q > 0.0) == (side == Side::Plus);
            if outside {
                1.0
            } else {
                0.0
            }
        }
    }

    /// Whether a slew `r` is below the rate limit, on `side` at the limit.
    fn under_rate(&self, r: f64, side: Side) -> bool {
        if self.rate.is_infinite() {
            return true;
        }
        let over = r.abs() - self.rate;
        if over < -AT_KINK * self.rate {
            true
        } else if over > AT_KINK * self.rate {
            false
        } else {
            (r > 0.0) == (side == Side::Minus)
        }
    }
}

impl Linearize for ActuatorStage {
    fn states(&self) -> Vec<Quantity> {
        match self.spool {
            Spool::None => Vec::new(),
            Spool::First { .. } => vec![Quantity::new("spool", "V")],
            Spool::Second { .. } => vec![
                Quantity::new("spool", "V"),
                Quantity::new("spool_rate", "V/s"),
            ],
        }
    }
    fn input(&self) -> Quantity {
        Quantity::new("u", "V")
    }
    fn output(&self) -> Quantity {
        Quantity::new("u_plant", "V")
    }
    fn scales(&self) -> Vec<f64> {
        match self.spool {
            Spool::None => Vec::new(),
            // The spool's position is a command in V: 1 V is its typical
            // size; its rate in V/s scales with the natural frequency.
            Spool::First { .. } => vec![1.0],
            Spool::Second { wn2, .. } => vec![1.0, wn2.sqrt()],
        }
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let s = self.full(p.x);
        let mut d = [0.0; 2];
        self.act.deriv(&s, p.u, &mut d);
        let n = self.n();
        dx[..n].copy_from_slice(&d[..n]);
        self.act.output(&s, p.u)
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let n = self.n();
        let mut j = Jacobian::zeros(n);
        let sat = self.sat_slope(p.u, side);
        let uc = self.act.saturate(p.u);
        let s = self.full(p.x);
        match self.spool {
            Spool::None => {
                j.d[(0, 0)] = self.db_slope(uc, side) * sat;
            }
            Spool::First { tau } => {
                let r = (uc - s[0]) / tau;
                if self.under_rate(r, side) {
                    j.a[(0, 0)] = -1.0 / tau;
                    j.b[(0, 0)] = sat / tau;
                }
                j.c[(0, 0)] = self.db_slope(s[0], side);
            }
            Spool::Second { wn2, two_zeta_wn } => {
                let w = s[1];
                let acc = wn2 * (uc - s[0]) - two_zeta_wn * w;
                if self.under_rate(w, side) {
                    j.a[(0, 1)] = 1.0;
                    j.a[(1, 0)] = -wn2;
                    j.a[(1, 1)] = -two_zeta_wn;
                    j.b[(1, 0)] = wn2 * sat;
                } else if acc * w <= 0.0 {
                    // Held at the rate limit, accelerating back inward.
                    j.a[(1, 0)] = -wn2;
                    j.a[(1, 1)] = -two_zeta_wn;
                    j.b[(1, 0)] = wn2 * sat;
                }
                j.c[(0, 0)] = self.db_slope(s[0], side);
            }
        }
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        let mut out = Vec::new();
        if self.limit.is_finite() && (p.u.abs() - self.limit).abs() <= AT_KINK * self.limit {
            out.push(Kink {
                what: format!(
                    "the saturation at its limit (u = {} V, actuator.limit = {} V): slope 1 inside, 0 beyond",
                    p.u, self.limit
                ),
                quantity: "u".into(),
            });
        }
        let s = self.full(p.x);
        let uc = self.act.saturate(p.u);
        let slew = match self.spool {
            Spool::None => None,
            Spool::First { tau } => Some((uc - s[0]) / tau),
            Spool::Second { .. } => Some(s[1]),
        };
        if let Some(r) = slew {
            if self.rate.is_finite() && (r.abs() - self.rate).abs() <= AT_KINK * self.rate {
                out.push(Kink {
                    what: format!(
                        "the spool at its rate limit (slew {r} V/s, actuator.rate_limit = {} V/s)",
                        self.rate
                    ),
                    quantity: "spool".into(),
                });
            }
        }
        if self.dead_band > 0.0 {
            let v = if self.spool == Spool::None { uc } else { s[0] };
            let q = v + self.null_bias;
            if (q.abs() - self.dead_band).abs() <= AT_KINK * self.dead_band {
                out.push(Kink {
                    what: format!(
                        "the dead band's edge (spool + null bias = {q} V, actuator.dead_band = {} V): slope 0 inside, 1 outside",
                        self.dead_band
                    ),
                    quantity: "spool".into(),
                });
            }
        }
        out
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        let mut out = Vec::new();
        if p.u.abs() > self.limit * (1.0 + AT_KINK) {
            out.push(format!(
                "the command {} V is saturated at ±{} V (actuator.limit): the stage's gain is 0",
                p.u, self.limit
            ));
        }
        let s = self.full(p.x);
        let v = if self.spool == Spool::None {
            self.act.saturate(p.u)
        } else {
            s[0]
        };
        if self.dead_band > 0.0 && (v + self.null_bias).abs() < self.dead_band * (1.0 - AT_KINK) {
            out.push(format!(
                "the spool + null bias ({} V) is inside the dead band ±{} V (actuator.dead_band): the stage's gain is 0",
                v + self.null_bias,
                self.dead_band
            ));
        }
        out
    }
}
