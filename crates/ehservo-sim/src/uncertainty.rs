//! What the controller does not know: the true plant's variation from the
//! nominal, as a bias and a random part held over `hold` seconds.
//!
//! Two forms, both fractions, drawn from one seeded stream:
//!
//! - **the paper's** (the third-order family only: `ThirdOrderPlant`,
//!   `PhysicalPlant`): `Δa_i = |ā_i|·(a_bias + a_random·r_i)` and
//!   `Δb = b_ref·b̄·(b_bias + b_random·r_b)`, i.e. fractions of the paper's
//!   reference sizes α_i = |ā_i| and β = b_ref·|b̄| with b_ref = 0.5 (SPEC
//!   §2: β = 0.5|b̄|), whatever bounds the controller is told. The Fig. 2
//!   case is `a_bias = 1, b_bias = 0.5` (true a = 2ā, true b = 1.25·b̄);
//!   Fig. 8 is `a_bias = a_random = 0.5`, `b_bias = b_random = 0.25`;
//! - **physical** (`[uncertainty.physical]`, any plant that has the
//!   parameter): each of mass (or inertia), bulk modulus, leakage, supply
//!   pressure, friction and load scaled by `1 + bias + random·r`, so that
//!   `mass = { bias = 0.2 }` is a plant 20 % heavier than its model. Each
//!   plant says how it carries them (its module doc).
//!
//! `r` is uniform on [−1, 1), drawn once per `hold` seconds (0.01 s) from a
//! seeded ChaCha8 stream and held: the same signal whatever the
//! integration step. A hold interval draws the paper's four numbers
//! (r_1, r_2, r_3, r_b), and the six physical ones after them only when a
//! physical random part is set, so that the paper's runs draw exactly the
//! stream they always drew.

use crate::error::{finite, KeyError};
use crate::plant::Plant;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A bias and a random part, as fractions of a parameter's nominal value.
///
/// ```
/// use ehservo_sim::uncertainty::{PhysicalSpec, Spread};
///
/// // `mass = { bias = 0.2, random = 0.1 }`: 20 % heavier, ±10 % drawn.
/// let mass = Spread { bias: 0.2, random: 0.1 };
/// assert!((mass.factor(0.5) - 1.25).abs() < 1e-15); // 1 + 0.2 + 0.1·0.5
/// assert!((mass.min_factor() - 1.1).abs() < 1e-15);
/// // A mass that a draw could make zero is refused, by key.
/// let spec = PhysicalSpec { mass: Spread { bias: -0.5, random: 0.5 }, ..PhysicalSpec::default() };
/// assert_eq!(spec.validate().unwrap_err().key, "mass.bias");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Spread {
    /// The constant part: the true value is `nominal·(1 + bias + random·r)`.
    pub bias: f64,
    /// The random part's size (r uniform on [−1, 1), held over `hold`).
    pub random: f64,
}

impl Spread {
    /// None.
    pub const NONE: Spread = Spread {
        bias: 0.0,
        random: 0.0,
    };

    /// The factor `1 + bias + random·r`.
    #[inline]
    pub fn factor(&self, r: f64) -> f64 {
        1.0 + self.bias + self.random * r
    }

    /// Neither part is set.
    pub fn is_none(&self) -> bool {
        self.bias == 0.0 && self.random == 0.0
    }

    /// The smallest factor any draw can give.
    pub fn min_factor(&self) -> f64 {
        1.0 + self.bias - self.random.abs()
    }
}

/// The physical parameters a variation can scale (`[uncertainty.physical]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct PhysicalSpec {
    /// The moving mass (a cylinder's load mass, its weight on an inclined
    /// axis with it; the motor's inertia Jt).
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub mass: Spread,
    /// The effective bulk modulus βe.
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub bulk_modulus: Spread,
    /// The leakage coefficient (cross-piston Cl; the motor's Kce).
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub leakage: Spread,
    /// The supply pressure (a fixed supply's Ps; a pump's relief setting).
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub supply_pressure: Spread,
    /// Every friction force (Coulomb, stiction, viscous).
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub friction: Spread,
    /// The external load (its force or torque: a cylinder's spring and
    /// force signal; the weight goes with the mass).
    #[serde(skip_serializing_if = "Spread::is_none")]
    pub load: Spread,
}

/// How many physical parameters a variation can scale.
pub const PHYSICAL: usize = 6;

impl PhysicalSpec {
    /// The spreads in the order of [`Draw::physical`]: mass, bulk modulus,
    /// leakage, supply pressure, friction, load.
    pub fn spreads(&self) -> [Spread; PHYSICAL] {
        [
            self.mass,
            self.bulk_modulus,
            self.leakage,
            self.supply_pressure,
            self.friction,
            self.load,
        ]
    }

    /// The scenario keys, in the same order.
    pub const KEYS: [&'static str; PHYSICAL] = [
        "mass",
        "bulk_modulus",
        "leakage",
        "supply_pressure",
        "friction",
        "load",
    ];

    /// Nothing set.
    pub fn is_none(&self) -> bool {
        self.spreads().iter().all(Spread::is_none)
    }

    /// Some random part is set.
    pub fn is_random(&self) -> bool {
        self.spreads().iter().any(|s| s.random != 0.0)
    }

    /// The factors for the draw `r`.
    #[inline]
    pub fn factors(&self, r: &[f64; PHYSICAL]) -> Factors {
        let s = self.spreads();
        Factors {
            mass: s[0].factor(r[0]),
            bulk_modulus: s[1].factor(r[1]),
            leakage: s[2].factor(r[2]),
            supply_pressure: s[3].factor(r[3]),
            friction: s[4].factor(r[4]),
            load: s[5].factor(r[5]),
        }
    }

    /// Checks that every part is finite and that no factor can reach 0 or
    /// below (a mass, a bulk modulus, a supply pressure must stay > 0;
    /// leakage, friction and load may vanish but not change sign). The
    /// error is the key (inside `[uncertainty.physical]`) and the reason.
    pub fn validate(&self) -> Result<(), KeyError> {
        for (key, s) in Self::KEYS.iter().zip(self.spreads()) {
            for (part, v) in [("bias", s.bias), ("random", s.random)] {
                finite(&format!("{key}.{part}"), v)?;
            }
            let must_stay_positive = matches!(*key, "mass" | "bulk_modulus" | "supply_pressure");
            let low = s.min_factor();
            if (must_stay_positive && low <= 0.0) || low < 0.0 {
                return Err(KeyError::new(
                    format!("{key}.bias"),
                    format!(
                        "the true value nominal·(1 + bias ± random) can reach {low:.3} of the nominal: it must stay {}",
                        if must_stay_positive { "> 0" } else { ">= 0" }
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The multipliers of one hold interval's physical variation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Factors {
    /// Mass or inertia.
    pub mass: f64,
    /// Bulk modulus.
    pub bulk_modulus: f64,
    /// Leakage.
    pub leakage: f64,
    /// Supply pressure.
    pub supply_pressure: f64,
    /// Friction.
    pub friction: f64,
    /// External load.
    pub load: f64,
}

impl Factors {
    /// All 1: the nominal plant.
    pub const ONE: Factors = Factors {
        mass: 1.0,
        bulk_modulus: 1.0,
        leakage: 1.0,
        supply_pressure: 1.0,
        friction: 1.0,
        load: 1.0,
    };
}

/// Sizes of the variation: a scenario's `[uncertainty]`, resolved for its
/// plant (the scenario's own table leaves the paper's keys unset for a
/// plant outside the third-order family).
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::plant::{Draw, Plant, ThirdOrderPlant, UncertaintySpec, Variation};
///
/// // The default is Fig. 2: a_bias = 1, b_bias = 0.5 of β = 0.5·b̄.
/// let spec = UncertaintySpec::default();
/// assert!(spec.paper_is_set() && !spec.is_random());
/// let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
/// let abar = plant.nominal().coeffs.as_array();
/// // Δa_i = |ā_i|·1 (true a = 2ā), δb = 0.5·0.5 = 0.25 (true b = 1.25·b̄).
/// let v = Variation::of(&spec, &abar, &Draw::default());
/// assert_eq!(v.da, abar.map(f64::abs));
/// assert_eq!(v.db_rel, 0.25);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct UncertaintySpec {
    /// Bias fraction of α_i = |ā_i|.
    pub a_bias: f64,
    /// Random fraction of α_i.
    pub a_random: f64,
    /// Bias fraction of β = 0.5·|b̄|.
    pub b_bias: f64,
    /// Random fraction of β.
    pub b_random: f64,
    /// The size the b fractions refer to, as a multiple of b̄ (0.5: β).
    pub b_reference: f64,
    /// Seed of the random signal.
    pub seed: u64,
    /// Hold period of the random signal (s).
    pub hold: f64,
    /// The physical form.
    #[serde(skip_serializing_if = "PhysicalSpec::is_none")]
    pub physical: PhysicalSpec,
}

/// The paper's Fig. 2 case: Δa_i = α_i, Δb = 0.5β (SPEC §2), seed 0, held
/// 0.01 s.
impl Default for UncertaintySpec {
    fn default() -> Self {
        Self {
            a_bias: 1.0,
            b_bias: 0.5,
            ..Self::NONE
        }
    }
}

impl UncertaintySpec {
    /// No variation at all.
    pub const NONE: UncertaintySpec = UncertaintySpec {
        a_bias: 0.0,
        a_random: 0.0,
        b_bias: 0.0,
        b_random: 0.0,
        b_reference: 0.5,
        seed: 0,
        hold: 0.01,
        physical: PhysicalSpec {
            mass: Spread::NONE,
            bulk_modulus: Spread::NONE,
            leakage: Spread::NONE,
            supply_pressure: Spread::NONE,
            friction: Spread::NONE,
            load: Spread::NONE,
        },
    };

    /// A random part of the paper's form is set.
    pub fn paper_is_random(&self) -> bool {
        self.a_random != 0.0 || self.b_random != 0.0
    }

    /// The paper's form is set at all.
    pub fn paper_is_set(&self) -> bool {
        self.a_bias != 0.0 || self.a_random != 0.0 || self.b_bias != 0.0 || self.b_random != 0.0
    }

    /// Some random part (either form) is set: a draw per hold interval.
    pub fn is_random(&self) -> bool {
        self.paper_is_random() || self.physical.is_random()
    }
}

/// One hold interval's random numbers, each uniform on [−1, 1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Draw {
    /// r_1, r_2, r_3 (the Δa_i) and r_b (Δb): the paper's form.
    pub paper: [f64; 4],
    /// Mass, bulk modulus, leakage, supply pressure, friction, load.
    pub physical: [f64; PHYSICAL],
}

/// The random numbers, held over hold intervals of a seeded stream.
///
/// ```
/// use ehservo_sim::plant::{UncertaintySignal, UncertaintySpec};
///
/// // Fig. 8's random part, drawn every 0.01 s.
/// let spec = UncertaintySpec { a_random: 0.5, b_random: 0.25, seed: 7, ..UncertaintySpec::NONE };
/// let mut sig = UncertaintySignal::new(spec);
/// // t = 0.025 s is in hold interval 2 (of [0.02, 0.03)).
/// assert_eq!(sig.interval_at(0.025), 2);
/// let d2 = *sig.draw_at(2);
/// assert!(d2.paper.iter().all(|r| (-1.0..1.0).contains(r)));
/// // Held: the same interval gives the same numbers; the next one others.
/// assert_eq!(*sig.draw_at(2), d2);
/// assert_ne!(*sig.draw_at(3), d2);
/// // The same seed, the same stream.
/// assert_eq!(*UncertaintySignal::new(spec).draw_at(2), d2);
/// ```
#[derive(Debug, Clone)]
pub struct UncertaintySignal {
    spec: UncertaintySpec,
    rng: ChaCha8Rng,
    drawn: u64,
    draw: Draw,
    random: bool,
    physical: bool,
}

impl UncertaintySignal {
    /// The signal of `spec`.
    pub fn new(spec: UncertaintySpec) -> Self {
        Self {
            spec,
            rng: ChaCha8Rng::seed_from_u64(spec.seed),
            drawn: 0,
            draw: Draw::default(),
            random: spec.is_random(),
            physical: spec.physical.is_random(),
        }
    }

    /// The spec.
    pub fn spec(&self) -> &UncertaintySpec {
        &self.spec
    }

    /// Whether anything is drawn (else every interval is the bias alone).
    pub fn is_random(&self) -> bool {
        self.random
    }

    /// One uniform draw on [−1, 1): 53 random bits, portable across
    /// platforms and `rand` versions.
    fn uniform(&mut self) -> f64 {
        let bits = self.rng.next_u64() >> 11;
        (bits as f64) * (2.0 / (1u64 << 53) as f64) - 1.0
    }

    /// The hold interval of time `t ≥ 0`; the tiny offset keeps t = k·hold
    /// in interval k despite rounding of k·h.
    pub fn interval_at(&self, t: f64) -> u64 {
        (t / self.spec.hold + 1e-9).floor().max(0.0) as u64
    }

    /// How many (sub)steps of `hs` seconds make one hold interval, when the
    /// hold is a whole number of them (to 1e-9): the simulator then finds a
    /// (sub)step's interval by integer division, exact however long the run.
    pub fn steps_per_hold(&self, hs: f64) -> Option<u64> {
        let r = self.spec.hold / hs;
        let n = r.round();
        ((1.0..9.0e15).contains(&n) && (r - n).abs() <= 1e-9 * n).then_some(n as u64)
    }

    /// The hold interval of the `j`-th (sub)step of `hs` seconds: `j / n`
    /// in integers when a hold is `n` (sub)steps, else from the time.
    pub fn interval(&self, j: u64, hs: f64, per_hold: Option<u64>) -> u64 {
        match per_hold {
            Some(n) => j / n,
            None => ((j as f64 * hs) / self.spec.hold + 1e-9).floor().max(0.0) as u64,
        }
    }

    /// The numbers of hold interval `j` (intervals never go backwards; all
    /// zero when nothing is random).
    pub fn draw_at(&mut self, j: u64) -> &Draw {
        if self.random {
            while self.drawn <= j {
                for i in 0..4 {
                    self.draw.paper[i] = self.uniform();
                }
                if self.physical {
                    for i in 0..PHYSICAL {
                        self.draw.physical[i] = self.uniform();
                    }
                }
                self.drawn += 1;
            }
        }
        &self.draw
    }
}

/// A plant's variation over time: the signal's draws turned into the
/// plant's variation once per hold interval.
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec, Varying};
///
/// let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
/// // Fig. 8's a_i: a bias and a random part, drawn every 0.01 s and held.
/// let spec = UncertaintySpec { a_bias: 0.5, a_random: 0.5, ..UncertaintySpec::NONE };
/// let mut var = Varying::new(&plant, spec);
/// let (v0, v1, v2) = (var.at(&plant, 0.0), var.at(&plant, 0.004), var.at(&plant, 0.012));
/// assert_eq!(v0, v1); // one hold interval
/// assert_ne!(v1, v2); // the next
/// // Δa1 = |ā1|·(0.5 + 0.5·r) with r in [−1, 1): within [0, |ā1|).
/// let a1 = plant.nominal().coeffs.a1.abs();
/// assert!((0.0..a1).contains(&v2.da[0]));
/// ```
#[derive(Debug, Clone)]
pub struct Varying<V: Copy> {
    signal: UncertaintySignal,
    bias: V,
    current: V,
    at: u64,
}

impl<V: Copy> Varying<V> {
    /// For the plant `plant` under `spec`.
    pub fn new<P: Plant<Variation = V>>(plant: &P, spec: UncertaintySpec) -> Self {
        let signal = UncertaintySignal::new(spec);
        let bias = plant.variation(&spec, &Draw::default());
        Self {
            signal,
            bias,
            current: bias,
            at: u64::MAX,
        }
    }

    /// The signal underneath.
    pub fn signal(&self) -> &UncertaintySignal {
        &self.signal
    }

    /// The variation over the `j`-th (sub)step of `hs` seconds (it starts
    /// at `j·hs`), with `per_hold = steps_per_hold(hs)`.
    #[inline]
    pub fn at_step<P: Plant<Variation = V>>(
        &mut self,
        plant: &P,
        j: u64,
        hs: f64,
        per_hold: Option<u64>,
    ) -> V {
        if !self.signal.random {
            return self.bias;
        }
        let i = self.signal.interval(j, hs, per_hold);
        self.at_interval(plant, i)
    }

    /// The variation at time `t ≥ 0` (times must not go back across hold
    /// intervals).
    pub fn at<P: Plant<Variation = V>>(&mut self, plant: &P, t: f64) -> V {
        if !self.signal.random {
            return self.bias;
        }
        let i = self.signal.interval_at(t);
        self.at_interval(plant, i)
    }

    fn at_interval<P: Plant<Variation = V>>(&mut self, plant: &P, i: u64) -> V {
        if i != self.at {
            let spec = self.signal.spec;
            let draw = *self.signal.draw_at(i);
            self.current = plant.variation(&spec, &draw);
            self.at = i;
        }
        self.current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draws are held over each interval however often they are asked for,
    /// lie in [−1, 1), and a physical random part draws six more numbers
    /// per interval after the paper's four (the paper's stream unchanged).
    #[test]
    fn draws_are_held_and_the_papers_stream_is_kept() {
        let paper = UncertaintySpec {
            a_random: 1.0,
            seed: 7,
            ..UncertaintySpec::NONE
        };
        let both = UncertaintySpec {
            physical: PhysicalSpec {
                mass: Spread {
                    bias: 0.0,
                    random: 0.5,
                },
                ..Default::default()
            },
            ..paper
        };
        let mut a = UncertaintySignal::new(paper);
        let mut b = UncertaintySignal::new(both);
        // The same seed: b's stream is a's four numbers, then six more.
        let mut raw = UncertaintySignal::new(paper);
        let first_ten: Vec<f64> = (0..10).map(|_| raw.uniform()).collect();
        let da = *a.draw_at(0);
        let db = *b.draw_at(0);
        assert_eq!(da.paper.to_vec(), first_ten[..4].to_vec());
        assert_eq!(db.paper.to_vec(), first_ten[..4].to_vec());
        assert_eq!(db.physical.to_vec(), first_ten[4..].to_vec());
        assert_eq!(*a.draw_at(0), da, "held within the interval");
        let next = *a.draw_at(1);
        assert_ne!(next, da);
        assert!(first_ten.iter().all(|v| (-1.0..1.0).contains(v)));
    }

    #[test]
    fn physical_spreads_are_checked() {
        let mut p = PhysicalSpec::default();
        assert!(p.validate().is_ok());
        p.mass = Spread {
            bias: -0.5,
            random: 0.5,
        };
        let e = p.validate().unwrap_err();
        assert_eq!(e.key, "mass.bias");
        assert_eq!(
            e.reason.to_string(),
            "the true value nominal·(1 + bias ± random) can reach 0.000 of the nominal: it must stay > 0"
        );
        p.mass = Spread::NONE;
        p.friction = Spread {
            bias: -1.0,
            random: 0.0,
        };
        assert!(p.validate().is_ok(), "friction may vanish");
        p.friction.bias = -1.5;
        assert_eq!(p.validate().unwrap_err().key, "friction.bias");
        p.friction.bias = 0.0;
        p.load.random = f64::NAN;
        let e = p.validate().unwrap_err();
        assert_eq!(e.key, "load.random");
        assert_eq!(e.to_string(), "`load.random`: must be finite (got NaN)");
    }
}
