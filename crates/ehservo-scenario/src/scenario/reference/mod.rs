//! `[reference]`: the desired trajectory, by `kind` (default `"sine"`, the
//! paper's `θd = amplitude·sin(2π·f·t)`).
//!
//! | kind | keys (defaults) | θd |
//! |---|---|---|
//! | `sine` | `amplitude_deg` (5), `frequency_hz` (1) | A·sin(2πft), analytic |
//! | `step` | `amplitude_deg` (5), `start` (0), `prefilter_tau` | 0 → A at `start`, prefiltered |
//! | `ramp` | `slope_deg_per_s`, `start` (0), `prefilter_tau` | slope·(t − start)⁺, prefiltered |
//! | `square` | `amplitude_deg` (5), `frequency_hz` (1), `prefilter_tau` | 0 before t = 0, then +A, −A each half period, prefiltered |
//! | `chirp` | `amplitude_deg` (5), `f0_hz`, `f1_hz`, `duration` | A·sin φ, f0 → f1 linearly over `duration`, then f1 |
//! | `multisine` | `components` = [{`amplitude_deg`, `frequency_hz`, `phase_deg` (0)}, …] (1 to 8) | Σ A·sin(2πft + p), analytic |
//! | `csv` | `file`, `prefilter_tau` | the file's rows, linearly interpolated, prefiltered |
//!
//! "Prefiltered" is [`Prefiltered`]: four identical first-order lags of
//! time constant `prefilter_tau` (s), so that θd is C³ and θ⃛d exists; it
//! delays a ramp by 4·τ. `prefilter_tau = 0` is no prefilter: the pieces
//! themselves, with their slopes as θ̇d and zero θ̈d, θ⃛d (a raw step, as a
//! signal generator gives it; only a law without the reference's
//! derivatives, a PI, follows it sensibly). A CSV file has the header
//! `t,theta_deg` and at least two rows with strictly increasing times (s);
//! its path is relative to the scenario file's directory. Before its first
//! row θd is the first row's value, after its last the last's.
//!
//! **Units follow the plant's axis.** On a rotary axis the keys are in
//! degrees (`amplitude_deg`, `slope_deg_per_s`, `offset_deg`, a CSV's
//! `theta_deg`); on a linear axis (a cylinder) the same keys in
//! millimetres (`amplitude_mm`, `slope_mm_per_s`, `offset_mm`, a CSV's
//! `y_mm`), and a key of the other unit is refused. `offset_*` (default 0)
//! is added to every kind: a step then goes from the offset to offset +
//! amplitude.
//!
//! The window over which `e_final_deg` is measured ([`ReferenceCfg::period`]):
//! 1/f for `sine` and `square`, the slowest component's period for
//! `multisine`, 1/f at the horizon for `chirp`, and the last second (the
//! horizon if shorter) for `step`, `ramp` and `csv`, which have no period.

use ehservo_core::math::DR;
use ehservo_core::reference::{
    Chirp, Component, Knot, LagState, Multisine, Prefiltered, Reference, Sine, MAX_COMPONENTS,
};
use ehservo_sim::axis::{Axis, Quantity};
use ehservo_sim::error::{KeyError, Reason};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod build;
mod table;
mod trajectory;

pub use table::{read_csv, read_csv_on, CsvError, Table};
pub use trajectory::AnyReference;

/// Amplitude (deg) of a kind that has one, when not given.
pub const DEFAULT_AMPLITUDE_DEG: f64 = 5.0;
/// Frequency (Hz) of `sine` and `square`, when not given.
pub const DEFAULT_FREQUENCY_HZ: f64 = 1.0;
/// Most knots a generated or read piecewise-linear reference may have.
pub const MAX_KNOTS: usize = 200_000;

/// `reference.kind`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// A·sin(2πft) (the paper).
    #[default]
    Sine,
    /// A prefiltered step.
    Step,
    /// A prefiltered ramp.
    Ramp,
    /// A prefiltered square wave.
    Square,
    /// A linear frequency sweep.
    Chirp,
    /// A sum of sines.
    Multisine,
    /// A prefiltered table read from a CSV file.
    Csv,
}

impl ReferenceKind {
    /// As written in a scenario.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sine => "sine",
            Self::Step => "step",
            Self::Ramp => "ramp",
            Self::Square => "square",
            Self::Chirp => "chirp",
            Self::Multisine => "multisine",
            Self::Csv => "csv",
        }
    }

    /// The keys this kind uses (besides `kind` and `offset_*`), with
    /// their rotary unit (a linear axis's are the same in mm).
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            Self::Sine => &["amplitude_deg", "frequency_hz"],
            Self::Step => &["amplitude_deg", "start", "prefilter_tau"],
            Self::Ramp => &["slope_deg_per_s", "start", "prefilter_tau"],
            Self::Square => &["amplitude_deg", "frequency_hz", "prefilter_tau"],
            Self::Chirp => &["amplitude_deg", "f0_hz", "f1_hz", "duration"],
            Self::Multisine => &["components"],
            Self::Csv => &["file", "prefilter_tau"],
        }
    }

    /// Whether this kind's `[reference]` takes `key`, as a file writes it
    /// on either axis (`kind` and the offsets always).
    pub fn takes(self, key: &str) -> bool {
        let rotary = match key {
            "amplitude_mm" | "amplitude_kN" | "amplitude_bar" => "amplitude_deg",
            "slope_mm_per_s" => "slope_deg_per_s",
            k => k,
        };
        key == "kind"
            || key == "quantity"
            || key.starts_with("offset_")
            || self.keys().contains(&rotary)
    }

    fn is_sine(&self) -> bool {
        *self == Self::Sine
    }
}

/// One `reference.components` entry of a `multisine`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComponentCfg {
    /// Amplitude (deg) on a rotary axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude_deg: Option<f64>,
    /// Amplitude (mm) on a linear axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude_mm: Option<f64>,
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// Phase (deg). Default 0.
    #[serde(default)]
    pub phase_deg: f64,
}

/// `[reference]`: `kind` and that kind's keys (see the module's table).
/// Every key is optional here; [`ReferenceCfg::build`] checks that the
/// kind's required keys are given and that no other kind's key is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(from = "ReferenceRaw")]
pub struct ReferenceCfg {
    /// Default `"sine"`.
    #[serde(skip_serializing_if = "ReferenceKind::is_sine")]
    pub kind: ReferenceKind,
    /// What the loop closes on: `"position"` (the default), `"force"`
    /// (the environment's force on a cylinder's rod, keys in kN) or
    /// `"load-pressure"` (p_L = p_A − α·p_B, keys in bar).
    #[serde(default, skip_serializing_if = "Quantity::is_position")]
    pub quantity: Quantity,
    /// Amplitude (deg): sine, step, square, chirp, on a rotary axis
    /// (default 5 there); refused on a linear axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude_deg: Option<f64>,
    /// Amplitude (mm): sine, step, square, chirp, on a linear axis, where
    /// it is required (no default); refused on a rotary axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude_mm: Option<f64>,
    /// Offset added to every kind (deg; a rotary axis). Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_deg: Option<f64>,
    /// Offset added to every kind (mm; a linear axis). Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_mm: Option<f64>,
    /// Amplitude (kN): sine, step, square, chirp, on a force loop, where
    /// it is required.
    #[serde(rename = "amplitude_kN", skip_serializing_if = "Option::is_none")]
    pub amplitude_kn: Option<f64>,
    /// Offset added to every kind (kN; a force loop). Default 0.
    #[serde(rename = "offset_kN", skip_serializing_if = "Option::is_none")]
    pub offset_kn: Option<f64>,
    /// Amplitude (bar): sine, step, square, chirp, on a load-pressure
    /// loop, where it is required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude_bar: Option<f64>,
    /// Offset added to every kind (bar; a load-pressure loop). Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_bar: Option<f64>,
    /// Frequency (Hz): sine, square.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// Time of the step or of the ramp's start (s). Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    /// The prefilter's time constant τ (s): step, ramp, square, csv.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prefilter_tau: Option<f64>,
    /// The ramp's slope (deg/s; a rotary axis).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slope_deg_per_s: Option<f64>,
    /// The ramp's slope (mm/s; a linear axis).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slope_mm_per_s: Option<f64>,
    /// The chirp's start frequency (Hz).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f0_hz: Option<f64>,
    /// The chirp's end frequency (Hz).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f1_hz: Option<f64>,
    /// The chirp's sweep duration (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// The multisine's components.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub components: Option<Vec<ComponentCfg>>,
    /// The CSV file (relative to the scenario file's directory): the
    /// header line `t,theta_deg` on a rotary axis or `t,y_mm` on a linear
    /// one, then at least two rows, times (s) strictly increasing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
}

/// What the file holds; a sine's missing keys are filled in
/// [`ReferenceCfg`], so that the paper's scenario reads as it always did.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct ReferenceRaw {
    kind: ReferenceKind,
    quantity: Quantity,
    amplitude_deg: Option<f64>,
    amplitude_mm: Option<f64>,
    offset_deg: Option<f64>,
    offset_mm: Option<f64>,
    #[serde(rename = "amplitude_kN")]
    amplitude_kn: Option<f64>,
    #[serde(rename = "offset_kN")]
    offset_kn: Option<f64>,
    amplitude_bar: Option<f64>,
    offset_bar: Option<f64>,
    frequency_hz: Option<f64>,
    start: Option<f64>,
    prefilter_tau: Option<f64>,
    slope_deg_per_s: Option<f64>,
    slope_mm_per_s: Option<f64>,
    f0_hz: Option<f64>,
    f1_hz: Option<f64>,
    duration: Option<f64>,
    components: Option<Vec<ComponentCfg>>,
    file: Option<String>,
}

/// What a file may hold (every key of [`ReferenceCfg`] optional, no
/// other): `ReferenceCfg`'s keys with their docs, as it writes them, made
/// strict, with the kind's default. (`ReferenceCfg` is read through this
/// type, so its derived schema for reading is this one's.)
impl schemars::JsonSchema for ReferenceRaw {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "ReferenceCfg".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        // The nested types as read, in `g`'s own definitions.
        g.subschema_for::<ReferenceKind>();
        g.subschema_for::<ComponentCfg>();
        g.subschema_for::<Quantity>();
        let mut writing = g.settings().clone().for_serialize().into_generator();
        let mut s = <ReferenceCfg as schemars::JsonSchema>::json_schema(&mut writing);
        s.insert("additionalProperties".into(), false.into());
        s.remove("required");
        if let Some(kind) = s
            .get_mut("properties")
            .and_then(|p| p.get_mut("kind"))
            .and_then(|k| k.as_object_mut())
        {
            kind.insert("default".into(), ReferenceKind::default().name().into());
        }
        s
    }
}

impl From<ReferenceRaw> for ReferenceCfg {
    fn from(r: ReferenceRaw) -> Self {
        let sine = r.kind == ReferenceKind::Sine;
        let fill = |v: Option<f64>, d: f64| if sine { v.or(Some(d)) } else { v };
        // The paper's 5° is a rotary default: a sine in millimetres keeps
        // its own amplitude.
        let own = [r.amplitude_mm, r.amplitude_kn, r.amplitude_bar];
        let amplitude_deg = if own.iter().any(Option::is_some) {
            r.amplitude_deg
        } else {
            fill(r.amplitude_deg, DEFAULT_AMPLITUDE_DEG)
        };
        Self {
            kind: r.kind,
            quantity: r.quantity,
            amplitude_deg,
            amplitude_mm: r.amplitude_mm,
            offset_deg: r.offset_deg,
            offset_mm: r.offset_mm,
            amplitude_kn: r.amplitude_kn,
            offset_kn: r.offset_kn,
            amplitude_bar: r.amplitude_bar,
            offset_bar: r.offset_bar,
            frequency_hz: fill(r.frequency_hz, DEFAULT_FREQUENCY_HZ),
            start: r.start,
            prefilter_tau: r.prefilter_tau,
            slope_deg_per_s: r.slope_deg_per_s,
            slope_mm_per_s: r.slope_mm_per_s,
            f0_hz: r.f0_hz,
            f1_hz: r.f1_hz,
            duration: r.duration,
            components: r.components,
            file: r.file,
        }
    }
}

impl Default for ReferenceCfg {
    fn default() -> Self {
        ReferenceRaw::default().into()
    }
}

/// A checked error: the key (under `reference.`) and the reason.
type Bad = KeyError;

fn bad<T>(key: &str, reason: impl Into<Reason>) -> Result<T, Bad> {
    Err(KeyError::new(format!("reference.{key}"), reason))
}

fn finite(key: &str, v: f64) -> Result<f64, Bad> {
    ehservo_sim::error::finite(key, v).map_err(|e| e.under("reference"))
}

fn positive(key: &str, v: f64) -> Result<f64, Bad> {
    ehservo_sim::error::positive(key, v).map_err(|e| e.under("reference"))
}

fn non_negative(key: &str, v: f64) -> Result<f64, Bad> {
    ehservo_sim::error::non_negative(key, v).map_err(|e| e.under("reference"))
}

fn required(kind: ReferenceKind, key: &str, v: Option<f64>) -> Result<f64, Bad> {
    v.map_or_else(
        || bad(key, format!("is required by kind `{}`", kind.name())),
        Ok,
    )
}

impl ReferenceCfg {
    /// The keys that are set, by name.
    fn set_keys(&self) -> Vec<&'static str> {
        let f = |k: &'static str, set: bool| set.then_some(k);
        [
            f("amplitude_deg", self.amplitude_deg.is_some()),
            f("amplitude_deg", self.amplitude_mm.is_some()),
            f("amplitude_deg", self.amplitude_kn.is_some()),
            f("amplitude_deg", self.amplitude_bar.is_some()),
            f("frequency_hz", self.frequency_hz.is_some()),
            f("start", self.start.is_some()),
            f("prefilter_tau", self.prefilter_tau.is_some()),
            f("slope_deg_per_s", self.slope_deg_per_s.is_some()),
            f("slope_deg_per_s", self.slope_mm_per_s.is_some()),
            f("f0_hz", self.f0_hz.is_some()),
            f("f1_hz", self.f1_hz.is_some()),
            f("duration", self.duration.is_some()),
            f("components", self.components.is_some()),
            f("file", self.file.is_some()),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The sine's amplitude (deg), or the default.
    fn amplitude(&self) -> f64 {
        self.amplitude_deg.unwrap_or(DEFAULT_AMPLITUDE_DEG)
    }

    /// The keys set in the unit that is not `axis`'s: the first one.
    fn foreign_key(&self, axis: Axis) -> Option<&'static str> {
        let comps = self.components.iter().flatten();
        let deg = comps.clone().any(|c| c.amplitude_deg.is_some());
        let mm = comps.clone().any(|c| c.amplitude_mm.is_some());
        [
            ("amplitude_mm", Axis::Linear, self.amplitude_mm.is_some()),
            ("offset_mm", Axis::Linear, self.offset_mm.is_some()),
            (
                "slope_mm_per_s",
                Axis::Linear,
                self.slope_mm_per_s.is_some(),
            ),
            ("components", Axis::Linear, mm),
            ("amplitude_deg", Axis::Rotary, self.amplitude_deg.is_some()),
            ("offset_deg", Axis::Rotary, self.offset_deg.is_some()),
            (
                "slope_deg_per_s",
                Axis::Rotary,
                self.slope_deg_per_s.is_some(),
            ),
            ("components", Axis::Rotary, deg),
            ("amplitude_kN", Axis::Force, self.amplitude_kn.is_some()),
            ("offset_kN", Axis::Force, self.offset_kn.is_some()),
            (
                "amplitude_bar",
                Axis::Pressure,
                self.amplitude_bar.is_some(),
            ),
            ("offset_bar", Axis::Pressure, self.offset_bar.is_some()),
        ]
        .into_iter()
        .find_map(|(k, unit, set)| (set && unit != axis).then_some(k))
    }

    /// A key's name in `axis`'s unit (`amplitude_deg` → `amplitude_mm`).
    fn unit_key(axis: Axis, rotary: &'static str) -> &'static str {
        match (axis, rotary) {
            (Axis::Rotary, k) => k,
            (Axis::Linear, "amplitude_deg") => "amplitude_mm",
            (Axis::Linear, "slope_deg_per_s") => "slope_mm_per_s",
            (Axis::Linear, "offset_deg") => "offset_mm",
            (Axis::Force, "amplitude_deg") => "amplitude_kN",
            (Axis::Force, "offset_deg") => "offset_kN",
            (Axis::Pressure, "amplitude_deg") => "amplitude_bar",
            (Axis::Pressure, "offset_deg") => "offset_bar",
            (_, k) => k,
        }
    }

    /// The sine's or square's frequency (Hz), or the default.
    pub(crate) fn frequency(&self) -> f64 {
        self.frequency_hz.unwrap_or(DEFAULT_FREQUENCY_HZ)
    }

    /// The window (s) over which `e_final_deg` is measured: the period of
    /// a periodic reference (see the module's notes for the others).
    pub fn period(&self, horizon: f64) -> f64 {
        match self.kind {
            ReferenceKind::Sine | ReferenceKind::Square => 1.0 / self.frequency(),
            ReferenceKind::Multisine => {
                let f = self
                    .components
                    .iter()
                    .flatten()
                    .map(|c| c.frequency_hz)
                    .fold(f64::INFINITY, f64::min);
                if f.is_finite() && f > 0.0 {
                    1.0 / f
                } else {
                    horizon.min(1.0)
                }
            }
            ReferenceKind::Chirp => {
                match Chirp::try_new(
                    1.0,
                    self.f0_hz.unwrap_or(1.0),
                    self.f1_hz.unwrap_or(1.0),
                    self.duration.unwrap_or(1.0),
                ) {
                    Ok(c) => 1.0 / c.frequency_at(horizon),
                    Err(_) => horizon.min(1.0),
                }
            }
            ReferenceKind::Step | ReferenceKind::Ramp | ReferenceKind::Csv => horizon.min(1.0),
        }
    }

    /// The reference's (fundamental) frequency (Hz): `frequency_hz` for a
    /// sine, else 1/[`ReferenceCfg::period`].
    pub fn base_frequency_hz(&self, horizon: f64) -> f64 {
        match self.kind {
            ReferenceKind::Sine => self.frequency(),
            _ => 1.0 / self.period(horizon),
        }
    }

    /// Checks every key and builds the reference for a run of `horizon` (s)
    /// on a rotary axis whose |θ| limit is `theta_limit` (rad); a CSV file
    /// is read from `base_dir` (the scenario file's directory) when its
    /// path is relative.
    pub fn build(
        &self,
        horizon: f64,
        theta_limit: f64,
        base_dir: Option<&Path>,
    ) -> Result<AnyReference, Bad> {
        self.build_on(Axis::Rotary, horizon, theta_limit, base_dir)
    }

    /// [`ReferenceCfg::build`] on `axis`: its keys in the axis's unit, its
    /// values in the axis's SI unit (rad or m).
    pub fn build_on(
        &self,
        axis: Axis,
        horizon: f64,
        theta_limit: f64,
        base_dir: Option<&Path>,
    ) -> Result<AnyReference, Bad> {
        let kind = self.kind;
        let keys = || -> Vec<&'static str> {
            kind.keys()
                .iter()
                .map(|k| Self::unit_key(axis, k))
                .collect()
        };
        if let Some(k) = self
            .set_keys()
            .into_iter()
            .find(|k| !kind.keys().contains(k))
        {
            return bad(
                Self::unit_key(axis, k),
                format!(
                    "not used by kind `{}` (its keys: {})",
                    kind.name(),
                    keys().join(", ")
                ),
            );
        }
        // The paper's 5° fills a sine's amplitude when the file gives none
        // (`ReferenceRaw`): a rotary default, never a linear axis's. There
        // the amplitude in millimetres is required, and the error says so
        // rather than blame a key in degrees the file does not have.
        let own_amplitude = match axis {
            Axis::Rotary => self.amplitude_deg,
            Axis::Linear => self.amplitude_mm,
            Axis::Force => self.amplitude_kn,
            Axis::Pressure => self.amplitude_bar,
        };
        if axis != Axis::Rotary
            && kind == ReferenceKind::Sine
            && own_amplitude.is_none()
            && self.amplitude_deg == Some(DEFAULT_AMPLITUDE_DEG)
        {
            return bad(
                Self::unit_key(axis, "amplitude_deg"),
                format!(
                    "is required by kind `sine` on a {} axis (the default of 5 is the paper's degrees)",
                    axis.name()
                ),
            );
        }
        if !axis.is_position() && matches!(kind, ReferenceKind::Ramp | ReferenceKind::Multisine) {
            return bad(
                "kind",
                format!(
                    "kind `{}` is not offered on a {} loop in this version (step, sine, square, chirp and csv are)",
                    kind.name(),
                    axis.name()
                ),
            );
        }
        if let Some(k) = self.foreign_key(axis) {
            let (this, other) = match axis {
                Axis::Rotary => ("rotary (in degrees)", "_deg"),
                Axis::Linear => ("linear (in millimetres)", "_mm"),
                Axis::Force => ("a force (in kN)", "_kN"),
                Axis::Pressure => ("a load pressure (in bar)", "_bar"),
            };
            return bad(
                k,
                format!("the plant's axis is {this}: give the {other} form of this key"),
            );
        }
        let offset = match axis {
            Axis::Rotary => finite("offset_deg", self.offset_deg.unwrap_or(0.0))?,
            Axis::Linear => finite("offset_mm", self.offset_mm.unwrap_or(0.0))?,
            Axis::Force => finite("offset_kN", self.offset_kn.unwrap_or(0.0))?,
            Axis::Pressure => finite("offset_bar", self.offset_bar.unwrap_or(0.0))?,
        };
        let built = self.build_kind(axis, horizon, theta_limit, base_dir)?;
        Ok(if offset == 0.0 {
            built
        } else {
            built.shifted(axis.to_si(offset))
        })
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    fn cfg(text: &str) -> ReferenceCfg {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn sine_is_the_paper_by_default_and_bit_identical() {
        let c = cfg("");
        assert_eq!(c, ReferenceCfg::default());
        assert_eq!(c.amplitude_deg, Some(5.0));
        let r = c.build(10.0, 1.0, None).unwrap();
        let s = Sine::from_deg_hz(5.0, 1.0);
        for t in [0.0, 0.123, 7.77] {
            assert_eq!(r.z(t), s.z(t));
        }
        assert_eq!(c.period(10.0), 1.0);
        assert_eq!(
            toml::to_string(&c).unwrap(),
            "amplitude_deg = 5.0\nfrequency_hz = 1.0\n"
        );
    }

    #[test]
    fn keys_of_another_kind_and_missing_keys_are_named() {
        let e = cfg("kind = \"step\"\nfrequency_hz = 2\nprefilter_tau = 0.02")
            .build(10.0, 1.0, None)
            .unwrap_err();
        assert_eq!(e.key, "reference.frequency_hz");
        assert!(
            e.reason.to_string().contains("not used by kind `step`"),
            "{e:?}"
        );
        let e = cfg("kind = \"step\"").build(10.0, 1.0, None).unwrap_err();
        assert_eq!(e.key, "reference.prefilter_tau");
        assert!(e.reason.to_string().contains("required"), "{e:?}");
        let e = cfg("kind = \"ramp\"\nslope_deg_per_s = 10\nprefilter_tau = 0.02")
            .build(10.0, 1.0, None)
            .unwrap_err();
        assert!(e.reason.to_string().contains("theta_limit"), "{e:?}");
        assert!(toml::from_str::<ReferenceCfg>("kind = \"trapezoid\"").is_err());
    }

    /// A ramp of 10°/s from 0.5 s through τ = 0.02: far after the start,
    /// θd = slope·(t − 0.5 − 4τ) and θ̇d = slope.
    #[test]
    fn ramp_lags_by_four_tau() {
        let r = cfg("kind = \"ramp\"\nslope_deg_per_s = 10\nstart = 0.5\nprefilter_tau = 0.02")
            .build(5.0, 1.0, None)
            .unwrap();
        let z = r.z(3.0);
        let slope = 10f64.to_radians();
        assert!((z[0] - slope * (3.0 - 0.5 - 0.08)).abs() < 1e-12, "{z:?}");
        assert!((z[1] - slope).abs() < 1e-12);
        assert_eq!(r.z(0.4), [0.0; 4]);
    }

    /// A sine sampled every 1 ms in a CSV: linear interpolation is within
    /// A·ω²·Δt²/8 ≈ 4.3e-7 rad of the sine, and the same prefilter is a
    /// linear operation of unit gain, so the CSV reference is within that of
    /// the prefiltered sine (here the prefiltered sine itself is built from
    /// 0.1 ms knots, within 4.3e-9 rad of the sine).
    #[test]
    fn csv_of_a_sampled_sine_is_the_prefiltered_sine() {
        let dir = tempfile::tempdir().unwrap();
        let (a_deg, w) = (5.0, std::f64::consts::TAU);
        let mut text = String::from("t,theta_deg\n");
        for i in 0..=3000 {
            let t = i as f64 * 1e-3;
            text += &format!("{t},{}\n", a_deg * (w * t).sin());
        }
        std::fs::write(dir.path().join("s.csv"), text).unwrap();
        let c = cfg("kind = \"csv\"\nfile = \"s.csv\"\nprefilter_tau = 0.02");
        let r = c.build(3.0, 1.0, Some(dir.path())).unwrap();
        let fine: Vec<Knot> = (0..=30000)
            .map(|i| {
                let t = i as f64 * 1e-4;
                Knot {
                    t,
                    v: a_deg.to_radians() * (w * t).sin(),
                }
            })
            .collect();
        let exact = Table::reference(fine, 0.02).unwrap();
        for t in [0.3, 1.0, 2.2, 2.9] {
            let (z, e) = (r.z(t), exact.z(t));
            assert!((z[0] - e[0]).abs() < 4.5e-7, "t = {t}: {z:?} vs {e:?}");
            // The derivatives through the same prefilter: u's error is at
            // most ~Aω·Δt in slope, smoothed by the lags.
            assert!((z[1] - e[1]).abs() < 1e-4, "t = {t}: {z:?} vs {e:?}");
        }
        // And the prefiltered sine lags the sine by about 4τ in phase
        // (|H(jω)| = (1 + (ωτ)²)⁻², arg = −4·atan(ωτ)).
        let t = 2.5;
        let (g, ph) = (
            (1.0 + (w * 0.02f64).powi(2)).powi(-2),
            -4.0 * (w * 0.02f64).atan(),
        );
        let want = a_deg.to_radians() * g * (w * t + ph).sin();
        assert!((r.z(t)[0] - want).abs() < 1e-6, "{} vs {want}", r.z(t)[0]);
    }

    #[test]
    fn bad_csv_files_are_named_by_line_and_row() {
        let dir = tempfile::tempdir().unwrap();
        let check = |body: &str, want: &str| {
            let p = dir.path().join("r.csv");
            std::fs::write(&p, body).unwrap();
            let e = read_csv(&p).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        };
        check("t,theta_deg\n0,1\n", "single data row");
        check("t,theta_deg\n", "no data rows");
        check("time,theta\n0,1\n1,2\n", "header");
        check(
            "t,theta_deg\n0,1\n0.5,2\n0.4,3\n",
            "line 4 (row 3): non-monotonic time",
        );
        check(
            "t,theta_deg\n0,1\n0.5,NaN\n",
            "line 3 (row 2): NaN in column theta_deg",
        );
        check("t,theta_deg\n0,1\n0.5,inf\n", "column theta_deg");
        check("t,theta_deg\n0,1\n0.5,x\n", "cannot read `x`");
        check("t,theta_deg\n0,1\n0.5\n", "expected 2 columns");
        let e = read_csv(&dir.path().join("nope.csv")).unwrap_err();
        assert!(matches!(
            e,
            CsvError::Read {
                source: crate::input::ReadError::Io(_),
                ..
            }
        ));
        assert!(e.to_string().contains("cannot be read"), "{e}");
    }

    #[test]
    fn square_chirp_multisine_build() {
        let sq =
            cfg("kind = \"square\"\namplitude_deg = 2\nfrequency_hz = 0.5\nprefilter_tau = 0.01")
                .build(4.0, 1.0, None)
                .unwrap();
        // Settled at +A late in the first half period, −A in the second.
        assert!((sq.z(0.9)[0] - 2f64.to_radians()).abs() < 1e-9);
        assert!((sq.z(1.9)[0] + 2f64.to_radians()).abs() < 1e-9);
        let c = cfg("kind = \"chirp\"\nf0_hz = 0.1\nf1_hz = 5\nduration = 10");
        assert!(c.build(10.0, 1.0, None).is_ok());
        assert!((c.period(10.0) - 0.2).abs() < 1e-12);
        let m = cfg("kind = \"multisine\"\ncomponents = [{amplitude_deg = 2, frequency_hz = 0.5}, {amplitude_deg = 1, frequency_hz = 2, phase_deg = 90}]");
        let r = m.build(10.0, 1.0, None).unwrap();
        assert!((r.z(0.0)[0] - 1f64.to_radians()).abs() < 1e-15);
        assert_eq!(m.period(10.0), 2.0);
        let e = cfg("kind = \"multisine\"\ncomponents = []")
            .build(10.0, 1.0, None)
            .unwrap_err();
        assert_eq!(e.key, "reference.components");
    }

    /// A linear axis has no default amplitude: the paper's 5° is not
    /// applied there, and the key to give is named in millimetres; a key
    /// in degrees that the file does give is refused with the _mm form.
    #[test]
    fn a_linear_axis_has_no_default_in_degrees() {
        let inf = f64::INFINITY;
        for text in ["", "kind = \"sine\"", "kind = \"sine\"\nfrequency_hz = 2"] {
            let e = cfg(text)
                .build_on(Axis::Linear, 10.0, inf, None)
                .unwrap_err();
            assert_eq!(e.key, "reference.amplitude_mm", "{text:?}");
            assert!(e.reason.to_string().contains("required"), "{e}");
        }
        let e = cfg("kind = \"step\"")
            .build_on(Axis::Linear, 10.0, inf, None)
            .unwrap_err();
        assert_eq!(e.key, "reference.amplitude_mm");
        let e = cfg("amplitude_deg = 3")
            .build_on(Axis::Linear, 10.0, inf, None)
            .unwrap_err();
        assert_eq!(e.key, "reference.amplitude_deg");
        assert!(e.reason.to_string().contains("_mm"), "{e}");
        let r = cfg("amplitude_mm = 10")
            .build_on(Axis::Linear, 10.0, inf, None)
            .unwrap();
        assert!((r.z(0.25)[0] - 0.01).abs() < 1e-15);
        // The rotary axis keeps the paper's default.
        assert!(cfg("").build(10.0, 1.0, None).is_ok());
    }
}
