//! The built reference of any kind: θd and its first three derivatives at
//! a time, as the controllers and the metrics read them.

use super::*;

/// A built reference of any kind.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyReference {
    /// The paper's kind, evaluated exactly as [`Sine::z`].
    Sine(Sine),
    /// A frequency sweep.
    Chirp(Chirp),
    /// A sum of sines.
    Multisine(Multisine),
    /// Step, ramp, square and CSV: knots through the prefilter (shared, so
    /// that cloning a set-up is cheap).
    Table(Arc<Table>),
    /// Piecewise-linear knots without a prefilter (`prefilter_tau = 0`).
    Pieces(Arc<Vec<Knot>>),
    /// Another reference plus a constant offset (`offset_deg`, `offset_mm`).
    Shifted(Arc<AnyReference>, f64),
}

impl AnyReference {
    /// The sine, for the theory that holds for the paper's reference only.
    pub fn as_sine(&self) -> Option<&Sine> {
        match self {
            Self::Sine(s) => Some(s),
            _ => None,
        }
    }
}

impl AnyReference {
    /// A multisine's tones or a chirp's sweep (through an offset), for the
    /// oscillation check ([`crate::Loop::forcing`]).
    pub(crate) fn forcing(&self) -> Option<ehservo_sim::behaviour::Forcing> {
        use ehservo_sim::behaviour::Forcing;
        match self {
            Self::Multisine(m) => Some(Forcing::Tones(
                m.components().iter().map(|c| c.frequency).collect(),
            )),
            Self::Chirp(c) => Some(Forcing::Chirp { chirp: *c, t0: 0.0 }),
            Self::Shifted(r, _) => r.forcing(),
            _ => None,
        }
    }
}

impl From<Sine> for AnyReference {
    fn from(s: Sine) -> Self {
        Self::Sine(s)
    }
}

impl Reference<f64> for AnyReference {
    /// The sine (the paper's reference) inline in the simulator's loop,
    /// the others behind a call.
    #[inline]
    fn z(&self, t: f64) -> [f64; 4] {
        match self {
            Self::Sine(s) => s.z(t),
            _ => self.z_other(t),
        }
    }
}

impl AnyReference {
    #[inline(never)]
    fn z_other(&self, t: f64) -> [f64; 4] {
        match self {
            Self::Sine(s) => s.z(t),
            Self::Chirp(c) => c.z(t),
            Self::Multisine(m) => m.z(t),
            Self::Table(tb) => tb.prefiltered().z(t),
            Self::Pieces(k) => pieces(k, t),
            Self::Shifted(r, offset) => {
                let mut z = r.z(t);
                z[0] += offset;
                z
            }
        }
    }

    /// This reference plus a constant `offset` (SI). A table's knots take
    /// it themselves (the same z to round-off, no cost per evaluation).
    pub fn shifted(self, offset: f64) -> AnyReference {
        match self {
            Self::Table(tb) => {
                let knots = tb.knots.iter().map(|k| Knot {
                    t: k.t,
                    v: k.v + offset,
                });
                Table::reference(knots.collect(), tb.tau)
                    .unwrap_or_else(|_| Self::Shifted(Arc::new(Self::Table(tb.clone())), offset))
            }
            Self::Pieces(k) => Self::Pieces(Arc::new(
                k.iter()
                    .map(|k| Knot {
                        t: k.t,
                        v: k.v + offset,
                    })
                    .collect(),
            )),
            other => Self::Shifted(Arc::new(other), offset),
        }
    }
}

/// Linear interpolation of `k` at `t` (held before the first knot and
/// after the last; at a repeated time, the later knot), with its slope.
fn pieces(k: &[Knot], t: f64) -> [f64; 4] {
    let i = k.partition_point(|p| p.t <= t);
    if i == 0 {
        return [k[0].v, 0.0, 0.0, 0.0];
    }
    if i == k.len() {
        return [k[i - 1].v, 0.0, 0.0, 0.0];
    }
    let (a, b) = (k[i - 1], k[i]);
    let dt = b.t - a.t;
    if dt.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return [b.v, 0.0, 0.0, 0.0];
    }
    // (b.v − a.v)/dt as two divisions, so a span of ±1e308 cannot overflow.
    let slope = b.v / dt - a.v / dt;
    let w = (t - a.t) / dt;
    [(1.0 - w) * a.v + w * b.v, slope, 0.0, 0.0]
}
