//! The sensor stage between the plant and the controller: what the
//! controller measures of x = (θ, θ̇, θ̈), and when.
//!
//! ```text
//! x_m[i](t_k) = q_i(x[i](t_{k−delay}) + bias[i] + noise[i]·n_i,k),
//!     q_i(v) = resolution[i]·round(v/resolution[i])   (resolution > 0)
//!     q_i(v) = v                                      (resolution = 0)
//!     n_i,k  ~ N(0, 1), one seeded stream per channel
//! ```
//!
//! Only the channels in `measured` reach the controller; the others come
//! from the loop's estimator (`[estimator]`), which sees the measured θ.
//! Noise and a delay live on the samples of the sampled loop (a continuous
//! law has no samples to draw them at): a scenario with them must be
//! sampled. Bias and quantisation are pure functions of x and apply in
//! both modes. The identity by default (the paper's Assumption A4: x
//! measured exactly and at once). The metrics and the trace's θ and e are
//! always of the true plant.

use crate::error::Reason;
use ehservo_core::error::ParamError;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// The channels of x by their scenario names.
pub const CHANNELS: [&str; 3] = ["theta", "theta_dot", "theta_ddot"];

/// Longest measurement delay, in samples.
pub const MAX_DELAY: u32 = 64;

/// A set of channels of x, written as a list of names in a scenario
/// (`measured = ["theta"]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Channels(pub [bool; 3]);

impl Default for Channels {
    fn default() -> Self {
        Channels([true; 3])
    }
}

impl Channels {
    /// Every channel.
    pub const ALL: Channels = Channels([true; 3]);

    /// Every channel is in the set.
    pub fn is_all(&self) -> bool {
        *self == Self::ALL
    }

    /// Whether channel `i` is in the set.
    pub fn has(&self, i: usize) -> bool {
        self.0[i]
    }

    /// The names not in the set.
    pub fn missing(&self) -> Vec<&'static str> {
        (0..3)
            .filter(|&i| !self.0[i])
            .map(|i| CHANNELS[i])
            .collect()
    }
}

/// The error is the reason alone: the list's key is the caller's (serde
/// places it).
impl TryFrom<Vec<String>> for Channels {
    type Error = Reason;
    fn try_from(v: Vec<String>) -> Result<Self, Reason> {
        let mut c = [false; 3];
        for name in &v {
            let Some(i) = CHANNELS.iter().position(|n| n == name) else {
                return Err(Reason::Other(format!(
                    "unknown channel `{name}`: expected some of {CHANNELS:?}"
                )));
            };
            if c[i] {
                return Err(Reason::Other(format!("channel `{name}` is listed twice")));
            }
            c[i] = true;
        }
        if !c[0] {
            return Err(Reason::Other(format!(
                "must include \"theta\": every estimator works from the measured angle (got {v:?})"
            )));
        }
        Ok(Channels(c))
    }
}

impl From<Channels> for Vec<String> {
    fn from(c: Channels) -> Self {
        (0..3)
            .filter(|&i| c.0[i])
            .map(|i| CHANNELS[i].to_string())
            .collect()
    }
}

impl Serialize for Channels {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Vec::<String>::from(*self).serialize(s)
    }
}

impl<'de> Deserialize<'de> for Channels {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<String>::deserialize(d)?;
        Channels::try_from(v).map_err(serde::de::Error::custom)
    }
}

/// A list of channel names, each once, θ among them.
impl schemars::JsonSchema for Channels {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Channels".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "Channel names, each once, \"theta\" among them.",
            "type": "array",
            "items": { "type": "string", "enum": CHANNELS },
            "uniqueItems": true,
            "contains": { "const": CHANNELS[0] }
        })
    }
}

/// `[sensor]`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Constant offset added to (θ, θ̇, θ̈) (rad, rad/s, rad/s²). Default 0.
    #[serde(with = "crate::triple")]
    #[schemars(with = "[f64; 3]")]
    pub bias: [f64; 3],
    /// Quantisation step of each channel (0: exact). An encoder of N counts
    /// per revolution has a θ step of 2π/N rad. Default 0.
    #[serde(with = "crate::triple")]
    #[schemars(with = "[f64; 3]")]
    pub resolution: [f64; 3],
    /// Which channels the controller gets from the sensors (default all);
    /// the rest come from the estimator.
    #[serde(skip_serializing_if = "Channels::is_all")]
    pub measured: Channels,
    /// Standard deviation of white Gaussian noise per channel (rad, rad/s,
    /// rad/s²), drawn once per sample. Default 0.
    #[serde(skip_serializing_if = "is_zero3", with = "crate::triple")]
    #[schemars(with = "[f64; 3]")]
    pub noise: [f64; 3],
    /// Seed of the noise (channel i draws from its own stream, seed + i).
    #[serde(skip_serializing_if = "is_zero_u64")]
    pub seed: u64,
    /// Whole samples between the plant and the measurement. Default 0.
    #[serde(skip_serializing_if = "is_zero_u32")]
    pub delay: u32,
}

fn is_zero3(v: &[f64; 3]) -> bool {
    v.iter().all(|&x| x == 0.0)
}
fn is_zero_u64(v: &u64) -> bool {
    *v == 0
}
fn is_zero_u32(v: &u32) -> bool {
    *v == 0
}

impl SensorConfig {
    /// No effect at all.
    pub fn is_identity(&self) -> bool {
        *self == Self::default()
    }

    /// The controller gets x exactly, at once (it may still get only some
    /// channels: see `measured`).
    pub fn is_exact(&self) -> bool {
        is_zero3(&self.bias) && is_zero3(&self.resolution) && !self.is_sampled()
    }

    /// Whether the stage needs samples (noise or delay).
    pub fn is_sampled(&self) -> bool {
        self.noise.iter().any(|&s| s != 0.0) || self.delay > 0
    }
}

/// The validated stage, with its noise streams and delay line.
///
/// ```
/// use ehservo_sim::sensor::{Sensor, SensorConfig};
///
/// // A 4096-count encoder on θ, θ̇ and θ̈ exact, two samples late, as `[sensor]`.
/// let step = 2.0 * std::f64::consts::PI / 4096.0;
/// let cfg = SensorConfig { resolution: [step, 0.0, 0.0], delay: 2, ..SensorConfig::default() };
/// let mut s = Sensor::try_new(&cfg)?;
/// // 0.01 rad is 6.52 counts: read as 7 counts.
/// assert!((s.measure([0.01, 0.5, 0.0])[0] - 7.0 * step).abs() < 1e-15);
/// // Delayed by two samples; before them, the first measurement.
/// let xs = [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 3.0, 0.0], [0.0, 4.0, 0.0]];
/// let seen: Vec<f64> = xs.iter().map(|&x| s.sample(x)[1]).collect();
/// assert_eq!(seen, [1.0, 1.0, 1.0, 2.0]);
/// # Ok::<(), ehservo_sim::core::error::ParamError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Sensor {
    cfg: SensorConfig,
    identity: bool,
    pure: bool,
    rng: [ChaCha8Rng; 3],
    /// The last `delay + 1` noisy, quantised measurements, a ring.
    line: [[f64; 3]; MAX_DELAY as usize + 1],
    head: usize,
    filled: bool,
}

/// The largest bias or noise of a channel: 1e300 (rad, rad/s, rad/s²).
/// Traces write angles in degrees (×57.3), which overflows beyond 3e306.
pub const MAX_MAGNITUDE: f64 = 1e300;

/// 2⁵²: beyond this many steps of the resolution a value is left as it is
/// (quantising it could not move it by a whole spacing of doubles).
const QUANTISE_EXACT: f64 = 4_503_599_627_370_496.0;

impl Sensor {
    /// Exact measurement.
    pub fn identity() -> Sensor {
        Self::try_new(&SensorConfig::default()).expect("the default sensor is valid")
    }

    /// Validates the keys (`bias` finite, `resolution` finite and ≥ 0,
    /// `noise` finite and ≥ 0, `delay` ≤ [`MAX_DELAY`]).
    pub fn try_new(c: &SensorConfig) -> Result<Self, ParamError> {
        for &b in &c.bias {
            if !b.is_finite() {
                return Err(ParamError::new("bias", "must be finite", b));
            }
            if b.abs() > MAX_MAGNITUDE {
                return Err(ParamError::new(
                    "bias",
                    "must be within ±1e300 (rad, rad/s, rad/s²: beyond, the measurement in degrees overflows)",
                    b,
                ));
            }
        }
        for &r in &c.resolution {
            if !(r.is_finite() && r >= 0.0) {
                return Err(ParamError::new("resolution", "must be finite and >= 0", r));
            }
            // A subnormal step has fewer significant bits than the values
            // it would quantise (v/r overflows for |v| > 4e-308/r ≥ 1).
            if r > 0.0 && r < f64::MIN_POSITIVE {
                return Err(ParamError::new(
                    "resolution",
                    "must be 0 (exact) or at least 2.2250738585072014e-308 (a normal double)",
                    r,
                ));
            }
        }
        for &s in &c.noise {
            if !(s.is_finite() && s >= 0.0) {
                return Err(ParamError::new("noise", "must be finite and >= 0", s));
            }
            if s > MAX_MAGNITUDE {
                return Err(ParamError::new(
                    "noise",
                    "must be at most 1e300 (rad, rad/s, rad/s²: beyond, the measurement in degrees overflows)",
                    s,
                ));
            }
        }
        if c.delay > MAX_DELAY {
            return Err(ParamError::new(
                "delay",
                "must be at most 64 samples",
                f64::from(c.delay),
            ));
        }
        Ok(Self {
            cfg: *c,
            identity: is_zero3(&c.bias) && is_zero3(&c.resolution),
            pure: !c.is_sampled(),
            rng: core::array::from_fn(|i| ChaCha8Rng::seed_from_u64(c.seed.wrapping_add(i as u64))),
            line: [[0.0; 3]; MAX_DELAY as usize + 1],
            head: 0,
            filled: false,
        })
    }

    /// The settings.
    pub fn config(&self) -> &SensorConfig {
        &self.cfg
    }

    /// Which channels the controller gets from the sensors.
    pub fn measured(&self) -> Channels {
        self.cfg.measured
    }

    /// Whether the stage draws noise or delays (needs the sampled loop).
    pub fn is_sampled(&self) -> bool {
        !self.pure
    }

    /// Bias and quantisation of `x`: the stage's pure part, what the
    /// continuous loop's law sees in every RK4 stage.
    #[inline]
    pub fn measure(&self, x: [f64; 3]) -> [f64; 3] {
        if self.identity {
            return x;
        }
        core::array::from_fn(|i| self.quantise(i, x[i] + self.cfg.bias[i]))
    }

    #[inline]
    fn quantise(&self, i: usize, v: f64) -> f64 {
        let r = self.cfg.resolution[i];
        if r > 0.0 {
            let n = v / r;
            // From 2⁵² steps on, r is below the spacing of doubles at v: v
            // is already the nearest double to a multiple of r (and v/r
            // may overflow, which r·round(v/r) would turn into ±∞).
            if n.abs() < QUANTISE_EXACT {
                r * n.round()
            } else {
                v
            }
        } else {
            v
        }
    }

    /// The measurement at a sample of the sampled loop, from the true `x`
    /// at that sample: noise drawn, quantised, then delayed by `delay`
    /// samples (before the first `delay` samples: the first measurement).
    /// Call once per sample, in order.
    #[inline]
    pub fn sample(&mut self, x: [f64; 3]) -> [f64; 3] {
        if self.pure {
            return self.measure(x);
        }
        self.sample_drawn(x)
    }

    /// [`Sensor::sample`] with noise or a delay: behind a call, so that the
    /// pure stage's test and `measure` inline into the simulator's loop.
    #[inline(never)]
    fn sample_drawn(&mut self, x: [f64; 3]) -> [f64; 3] {
        let m: [f64; 3] = core::array::from_fn(|i| {
            let s = self.cfg.noise[i];
            let n = if s > 0.0 {
                let z: f64 = StandardNormal.sample(&mut self.rng[i]);
                s * z
            } else {
                0.0
            };
            self.quantise(i, x[i] + self.cfg.bias[i] + n)
        });
        let d = self.cfg.delay as usize;
        if d == 0 {
            return m;
        }
        let len = d + 1;
        if !self.filled {
            self.line[..len].fill(m);
            self.filled = true;
        }
        self.line[self.head] = m;
        self.head = (self.head + 1) % len;
        // The oldest of the last d + 1 entries is the one d samples back.
        self.line[self.head]
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn identity_and_quantisation() {
        let x = [0.123456, -2.5, 7.0];
        assert_eq!(Sensor::identity().measure(x), x);
        // A 4096-count encoder: step 2π/4096 = 1.5339808e-3 rad;
        // 0.123456/1.5339808e-3 = 80.48 → 80 counts = 0.1227185 rad.
        let s = Sensor::try_new(&SensorConfig {
            bias: [0.0, 0.5, 0.0],
            resolution: [2.0 * std::f64::consts::PI / 4096.0, 0.0, 0.0],
            ..Default::default()
        })
        .unwrap();
        let m = s.measure(x);
        assert!((m[0] - 0.1227185).abs() < 1e-7, "{}", m[0]);
        assert_eq!(m[1], -2.0);
        assert_eq!(m[2], 7.0);
        assert_eq!(
            Sensor::try_new(&SensorConfig {
                resolution: [-1.0, 0.0, 0.0],
                ..Default::default()
            })
            .unwrap_err()
            .name,
            "resolution"
        );
    }

    /// A subnormal resolution is refused; the smallest normal one
    /// (2⁻¹⁰²²) quantises without overflow: 1e10/2⁻¹⁰²² overflows to ∞,
    /// where r·round(v/r) gave ∞, and v is returned as it is; 1.5 with a
    /// step of 2⁻¹⁰²² is 1.5·2¹⁰²² steps (> 2⁵²), also left as it is; a
    /// step of 0.25 still rounds 1.3 to 1.25.
    #[test]
    fn tiny_resolutions_never_overflow() {
        let sub = SensorConfig {
            resolution: [f64::from_bits(1), 0.0, 0.0],
            ..Default::default()
        };
        assert_eq!(Sensor::try_new(&sub).unwrap_err().name, "resolution");
        let s = Sensor::try_new(&SensorConfig {
            resolution: [f64::MIN_POSITIVE, f64::MIN_POSITIVE, 0.25],
            ..Default::default()
        })
        .unwrap();
        assert_eq!(s.measure([1e10, 1.5, 1.3]), [1e10, 1.5, 1.25]);
    }

    /// 200 000 samples of σ = (1e-3, 0.02, 0): the sample mean is within
    /// 4σ/√n of 0 and the sample std within 1 % of σ (its relative
    /// standard error is 1/√(2n) = 0.16 %); the channels are uncorrelated
    /// (|ρ| < 4/√n = 0.009) and the noiseless channel is exact.
    #[test]
    fn noise_statistics_match_the_configured_sigma() {
        let sig = [1e-3, 0.02, 0.0];
        let mut s = Sensor::try_new(&SensorConfig {
            noise: sig,
            seed: 42,
            ..Default::default()
        })
        .unwrap();
        let n = 200_000;
        let x = [0.1, -0.3, 2.0];
        let (mut sum, mut sq, mut cross) = ([0.0; 3], [0.0; 3], 0.0);
        for _ in 0..n {
            let m = s.sample(x);
            let d: [f64; 3] = core::array::from_fn(|i| m[i] - x[i]);
            for i in 0..3 {
                sum[i] += d[i];
                sq[i] += d[i] * d[i];
            }
            cross += d[0] * d[1];
        }
        let nf = n as f64;
        for i in 0..2 {
            let mean = sum[i] / nf;
            let std = (sq[i] / nf - mean * mean).sqrt();
            assert!(
                mean.abs() < 4.0 * sig[i] / nf.sqrt(),
                "channel {i}: mean {mean}"
            );
            assert!((std / sig[i] - 1.0).abs() < 0.01, "channel {i}: std {std}");
        }
        assert_eq!(sq[2], 0.0);
        let rho = cross / nf / (sig[0] * sig[1]);
        assert!(rho.abs() < 4.0 / nf.sqrt(), "{rho}");
    }

    /// Each channel has its own stream: changing θ̇'s σ leaves θ's noise
    /// exactly as it was; the same seed gives the same numbers.
    #[test]
    fn channels_draw_from_their_own_streams() {
        let run = |sig: [f64; 3]| {
            let mut s = Sensor::try_new(&SensorConfig {
                noise: sig,
                seed: 7,
                ..Default::default()
            })
            .unwrap();
            (0..100).map(|_| s.sample([0.0; 3])).collect::<Vec<_>>()
        };
        let a = run([1e-3, 0.0, 0.0]);
        let b = run([1e-3, 5.0, 0.0]);
        assert!(a.iter().zip(&b).all(|(p, q)| p[0] == q[0]));
        assert_eq!(a, run([1e-3, 0.0, 0.0]));
    }

    /// A delay of 3 samples returns the measurement of 3 samples back
    /// (the first one until then); quantisation applies to the noisy value.
    #[test]
    fn delay_of_whole_samples() {
        let mut s = Sensor::try_new(&SensorConfig {
            delay: 3,
            ..Default::default()
        })
        .unwrap();
        let got: Vec<f64> = (0..8).map(|k| s.sample([k as f64, 0.0, 0.0])[0]).collect();
        assert_eq!(got, [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0]);
        let e = Sensor::try_new(&SensorConfig {
            delay: 65,
            ..Default::default()
        })
        .unwrap_err();
        assert_eq!(e.name, "delay");
    }

    #[test]
    fn measured_channels_parse_and_refuse() {
        let ok = Channels::try_from(vec!["theta".to_string()]).unwrap();
        assert_eq!(ok.0, [true, false, false]);
        assert_eq!(ok.missing(), ["theta_dot", "theta_ddot"]);
        assert_eq!(
            Channels::try_from(vec![]).unwrap_err().to_string(),
            "must include \"theta\": every estimator works from the measured angle (got [])"
        );
        assert!(Channels::try_from(vec!["theta_dot".into()]).is_err());
        assert!(Channels::try_from(vec!["theta".into(), "theta".into()]).is_err());
        assert_eq!(
            Channels::try_from(vec!["theta".into(), "jerk".into()])
                .unwrap_err()
                .to_string(),
            "unknown channel `jerk`: expected some of [\"theta\", \"theta_dot\", \"theta_ddot\"]"
        );
    }
}
