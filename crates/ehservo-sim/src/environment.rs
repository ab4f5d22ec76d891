//! What a cylinder's rod works against beyond its own load
//! (`[plant.environment]`): a specimen it presses on, or a spring with a
//! preload always attached, either of which may be carried by a moving
//! mount (the load simulator's case: the contact point moves under the
//! actuator). docs/environments.md has the keys and the physics.
//!
//! With δ = y − x_c − x_e(t) the compression (m) and δ̇ = ẏ − ẋ_e(t):
//!
//! ```text
//! specimen:  F_env = max(0, k·δ + c·δ̇)   for δ > 0,   0 for δ ≤ 0   (contact and lift-off; it never pulls)
//! spring:    F_env = F₀ + k·δ + c·δ̇                                  (always attached; F₀ the preload at δ = 0)
//! ```
//!
//! F_env opposes extension, as `[plant.load.force]` does: it enters the
//! rod's balance as M·ÿ = … − F_env. x_e(t) is a signal of time
//! (`[plant.environment.motion]`: a sine, or a table `t_s,position_m`),
//! read by the machinery of [`crate::force`].
//!
//! **Energy.** The environment stores E(δ) = ½·k·max(δ, 0)² (specimen) or
//! F₀·δ + ½·k·δ² (spring); its mount delivers −F_env·ẋ_e; it dissipates
//! D = (F_env − E′(δ))·δ̇, which is c·δ̇² ≥ 0 in contact, and −k·δ·δ̇ > 0 for
//! a specimen that lifts off faster than it relaxes (k·δ + c·δ̇ < 0 with
//! δ > 0, so δ̇ < 0): the environment is passive in every case
//! ([`Environment::power`]).

use crate::error::{finite, non_negative, positive, KeyError};
use crate::force::{read_columns, Force, ForceCfg};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

/// `[plant.environment.motion]`: the mount's motion x_e(t) (m), added to
/// the contact point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MotionCfg {
    /// offset + amplitude·sin(2πft + phase).
    Sine {
        /// Amplitude (m).
        amplitude: f64,
        /// Frequency (Hz).
        frequency_hz: f64,
        /// Phase (deg). Default 0.
        #[serde(default)]
        phase_deg: f64,
        /// Offset (m). Default 0.
        #[serde(default)]
        offset: f64,
    },
    /// A table in a CSV file with the header `t_s,position_m`, linear
    /// between rows, held outside them.
    Csv {
        /// The file (relative to the scenario file's directory).
        file: String,
    },
}

/// `[plant.environment]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum EnvironmentCfg {
    /// A specimen of stiffness k and damping c touched at y = position:
    /// it pushes only while compressed, and never pulls.
    Specimen {
        /// k (N/m).
        stiffness: f64,
        /// c (N·s/m). Default 0.
        #[serde(default)]
        damping: f64,
        /// The contact point x_c: the rod's extension y (m) at which the
        /// specimen is touched, inside the stroke.
        position: f64,
        /// `[plant.environment.motion]`: x_e(t), the contact point's motion.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        motion: Option<MotionCfg>,
    },
    /// A spring of stiffness k and damping c always attached, pushing
    /// `preload` at y = position.
    Spring {
        /// k (N/m).
        stiffness: f64,
        /// c (N·s/m). Default 0.
        #[serde(default)]
        damping: f64,
        /// F₀ (N), the force at y = position (opposing extension when > 0).
        /// Default 0.
        #[serde(default)]
        preload: f64,
        /// The rod's extension y (m) at which the spring pushes F₀, inside
        /// the stroke.
        position: f64,
        /// `[plant.environment.motion]`: x_e(t), the mount's motion.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        motion: Option<MotionCfg>,
    },
}

/// Whether the environment can pull.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Contact {
    /// A specimen: force only while compressed, never pulling.
    Unilateral,
    /// A spring: always attached.
    Attached,
}

/// The validated environment.
///
/// ```
/// use ehservo_sim::environment::{Environment, EnvironmentCfg};
///
/// // A 1 MN/m specimen touched at y = 0.2 m, with 2 kN·s/m of damping.
/// let cfg: EnvironmentCfg = toml::from_str(
///     "kind = \"specimen\"\nstiffness = 1e6\ndamping = 2e3\nposition = 0.2",
/// )
/// .unwrap();
/// let e = Environment::try_new(&cfg, 0.5, None).unwrap();
/// // 1 mm into it, at rest: k·δ = 1e6·1e-3 = 1 kN.
/// assert!((e.force(0.0, 0.201, 0.0) - 1e3).abs() < 1e-9);
/// // 1 mm short of it: nothing.
/// assert_eq!(e.force(0.0, 0.199, 0.0), 0.0);
/// // 1 mm in but leaving at 1 m/s: k·δ + c·δ̇ = 1000 − 2000 < 0, lifted off.
/// assert_eq!(e.force(0.0, 0.201, -1.0), 0.0);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Specimen or spring.
    pub contact: Contact,
    /// k (N/m).
    pub stiffness: f64,
    /// c (N·s/m).
    pub damping: f64,
    /// F₀ (N); 0 for a specimen.
    pub preload: f64,
    /// x_c (m).
    pub position: f64,
    /// x_e(t) (m) and its rate.
    pub motion: Force,
}

impl Environment {
    /// Validates the table for a cylinder of stroke `stroke`; a motion
    /// table is read from `base_dir` when its path is relative. The error
    /// is the key inside `[plant.environment]` and the reason.
    pub fn try_new(
        c: &EnvironmentCfg,
        stroke: f64,
        base_dir: Option<&Path>,
    ) -> Result<Self, KeyError> {
        let (contact, k, d, f0, x, m) = match c {
            EnvironmentCfg::Specimen {
                stiffness,
                damping,
                position,
                motion,
            } => (
                Contact::Unilateral,
                stiffness,
                damping,
                &0.0,
                position,
                motion,
            ),
            EnvironmentCfg::Spring {
                stiffness,
                damping,
                preload,
                position,
                motion,
            } => (
                Contact::Attached,
                stiffness,
                damping,
                preload,
                position,
                motion,
            ),
        };
        let stiffness = positive("stiffness", *k)?;
        let damping = non_negative("damping", *d)?;
        let preload = finite("preload", *f0)?;
        let position = finite("position", *x)?;
        if !(0.0..=stroke).contains(&position) {
            return Err(KeyError::new(
                "position",
                format!(
                    "the contact point must be within the stroke [0, {stroke:?}] m (got {position:?})"
                ),
            ));
        }
        let motion = match m {
            None => Force::Zero,
            Some(m) => motion(m, base_dir).map_err(|e| e.under("motion"))?,
        };
        Ok(Self {
            contact,
            stiffness,
            damping,
            preload,
            position,
            motion,
        })
    }

    /// δ and δ̇ at time `t` for the rod at `y` moving at `v`.
    #[inline]
    fn compression(&self, t: f64, y: f64, v: f64) -> (f64, f64) {
        let (xe, ve) = self.motion.at(t);
        (y - self.position - xe, v - ve)
    }

    /// F_env (N, opposing extension) at time `t` for the rod at `y`
    /// moving at `v`.
    #[inline]
    pub fn force(&self, t: f64, y: f64, v: f64) -> f64 {
        let (d, dd) = self.compression(t, y, v);
        let f = self.stiffness * d + self.damping * dd;
        match self.contact {
            Contact::Unilateral if d > 0.0 => f.max(0.0),
            Contact::Unilateral => 0.0,
            Contact::Attached => self.preload + f,
        }
    }

    /// (∂F_env/∂y, ∂F_env/∂ẏ): (k, c) while the environment pushes (a
    /// spring always, a specimen while its force is > 0), else (0, 0); a
    /// linearisation's terms.
    #[inline]
    pub fn slopes(&self, t: f64, y: f64, v: f64) -> (f64, f64) {
        let pushing = match self.contact {
            Contact::Unilateral => self.force(t, y, v) > 0.0,
            Contact::Attached => true,
        };
        if pushing {
            (self.stiffness, self.damping)
        } else {
            (0.0, 0.0)
        }
    }

    /// dF_env/dt at the rod's acceleration `a`, the mount's acceleration
    /// left out (an approximation the lumped-uncertainty diagnostic
    /// states); 0 out of contact.
    #[inline]
    pub fn rate(&self, t: f64, y: f64, v: f64, a: f64) -> f64 {
        let (_, dd) = self.compression(t, y, v);
        let (ky, kv) = self.slopes(t, y, v);
        ky * dd + kv * a
    }

    /// E(δ) at time `t` for the rod at `y` (J): the energy the spring holds.
    pub fn stored(&self, t: f64, y: f64) -> f64 {
        let (d, _) = self.compression(t, y, 0.0);
        match self.contact {
            Contact::Unilateral => 0.5 * self.stiffness * d.max(0.0).powi(2),
            Contact::Attached => (self.preload + 0.5 * self.stiffness * d) * d,
        }
    }

    /// `(port, dissipation)` (W): the power the mount delivers, −F_env·ẋ_e,
    /// and the power the environment dissipates, (F_env − E′(δ))·δ̇ ≥ 0
    /// (the module doc), so that dE/dt = F_env·ẏ + port − dissipation.
    pub fn power(&self, t: f64, y: f64, v: f64) -> (f64, f64) {
        let (d, dd) = self.compression(t, y, v);
        let (_, ve) = self.motion.at(t);
        let f = self.force(t, y, v);
        let spring = match self.contact {
            Contact::Unilateral => self.stiffness * d.max(0.0),
            Contact::Attached => self.preload + self.stiffness * d,
        };
        (-f * ve, (f - spring) * dd)
    }

    /// The largest force the environment's spring can press the rod with
    /// anywhere in [0, stroke] (N): |F₀| + k·(stroke + max|x_e|) (its
    /// damping is left out: a bound on the work the stops must absorb,
    /// [`crate::cylinder::Cylinder::stated_penetration`]).
    pub fn peak(&self, stroke: f64) -> f64 {
        self.preload.abs() + self.stiffness * (stroke + self.motion.peak())
    }

    /// The largest force the spring can hold the rod on an end stop with
    /// (N, ≥ 0), the mount anywhere within ±max|x_e|: at y = 0 it presses
    /// by F₀ + k·(max|x_e| − x_c) (a specimen by k·(max|x_e| − x_c) when
    /// positive: it touches the rod at 0 only if the mount has moved its
    /// face below 0), at y = stroke (towards extension) by
    /// −F₀ − k·(stroke − x_c − max|x_e|) (a specimen never: it only
    /// pushes towards retraction). Its damping is left out, as in
    /// [`Environment::peak`].
    pub fn stop_force(&self, stroke: f64) -> f64 {
        let (k, xc, xe) = (self.stiffness, self.position, self.motion.peak());
        let (bottom, top) = match self.contact {
            Contact::Unilateral => (k * (xe - xc), 0.0),
            Contact::Attached => (
                self.preload + k * (xe - xc),
                -self.preload - k * (stroke - xc - xe),
            ),
        };
        bottom.max(top).max(0.0)
    }
}

/// The motion's signal: a sine as [`ForceCfg::Sine`] would have it, or a
/// `t_s,position_m` table.
fn motion(m: &MotionCfg, base_dir: Option<&Path>) -> Result<Force, KeyError> {
    match m {
        MotionCfg::Sine {
            amplitude,
            frequency_hz,
            phase_deg,
            offset,
        } => Force::try_new(
            &ForceCfg::Sine {
                amplitude: *amplitude,
                frequency_hz: *frequency_hz,
                phase_deg: *phase_deg,
                offset: *offset,
            },
            None,
        ),
        MotionCfg::Csv { file } => {
            let path = match base_dir {
                Some(d) if Path::new(file).is_relative() => d.join(file),
                _ => std::path::PathBuf::from(file),
            };
            Ok(Force::Table(Arc::new(read_columns(
                &path,
                "motion",
                "position_m",
            )?)))
        }
    }
}
