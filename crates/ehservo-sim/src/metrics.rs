//! Metrics of one run, SPEC §9, computed online (no trace kept).
//!
//! With samples k = 0..N at t_k = k·h, t_s the end of the transient
//! (`settle`, 2 s by default: the paper's "after the transient") and T the
//! last sample's time:
//!
//! | key | definition |
//! |---|---|
//! | `e_max_deg` | max \|e\| over t_k ∈ [t_s, T], degrees |
//! | `e_final_deg` | max \|e\| over the last period of the reference, t_k ∈ [T − 1/f, T] (absent if the run diverged) |
//! | `e_rms_deg` | RMS of e over t_k ≥ t_s (the L2 measure, per sample), degrees |
//!
//! The error metrics are in the axis's display unit ([`Axis`]): on a
//! rotary axis in degrees with the keys above; on a linear axis in
//! millimetres as `e_max`, `e_final`, `e_rms`, with `"unit": "mm"` beside
//! them in JSON. (A rotary axis's `e_max` is also read as `e_max_deg`.)
//! | `u_max` | max \|u\| over the whole run (the transient included: Fig. 5 is about it), V |
//! | `u_rms` | RMS of u over t_k ≥ t_s, V |
//! | `chattering` | c\[u\] = sqrt(Σ Δu_k²)/sqrt(Σ u_k²) over t_k ≥ t_s, Δu_k = u_k − u_{k−1} |
//! | `u_tv_per_s` | Σ \|Δu_k\| over t_k ≥ t_s, divided by T − t_s, V/s |
//! | `w_norm_max`, `w_norm_final` | max and last ‖W‖ over the run |
//! | `dead_zone_fraction` | share of samples with σΔ = 0 over t_k ≥ t_s (NNBVSC only) |
//! | `diverged`, `diverged_at_s` | the run ended early, and when |
//!
//! A value that is undefined (no sample after t_s, a run with u ≡ 0) is
//! `None` (JSON `null`), never NaN.
//!
//! Beside them, [`Metrics::behaviour`] ([`crate::behaviour`]): end-stop
//! contacts, the share of samples at the command's limit and the error's
//! oscillation after t_s, which the verdicts name. They are not among the
//! keys above (summary.json writes them as `behaviour`, results.csv as
//! columns of their own), so the metrics of the paper's scenarios are
//! the keys they always were.

use crate::axis::Axis;
use crate::behaviour::OSCILLATION_TOLERANCE;
use crate::behaviour::{detect_oscillation, Behaviour, EndStops, ErrorWindow, Forcing};
use crate::simulation::{Divergence, Sample};
use ehservo_core::control::flags;
use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};

/// The metrics of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// max |e| after the transient (the axis's unit: deg or mm).
    pub e_max: Option<f64>,
    /// max |e| over the last period of the reference (deg or mm).
    pub e_final: Option<f64>,
    /// RMS of e after the transient (deg or mm).
    pub e_rms: Option<f64>,
    /// max |u| over the run (V).
    pub u_max: Option<f64>,
    /// RMS of u after the transient (V).
    pub u_rms: Option<f64>,
    /// Chattering index L2\[Δu\]/L2\[u\] after the transient.
    pub chattering: Option<f64>,
    /// Total variation of u per second after the transient (V/s).
    pub u_tv_per_s: Option<f64>,
    /// max ‖W‖.
    pub w_norm_max: Option<f64>,
    /// Last ‖W‖.
    pub w_norm_final: Option<f64>,
    /// Share of samples after the transient inside the dead zone (σΔ = 0); NNBVSC only.
    pub dead_zone_fraction: Option<f64>,
    /// The run ended early.
    pub diverged: bool,
    /// When it ended early (s).
    pub diverged_at_s: Option<f64>,
    /// Samples in the run.
    pub samples: u64,
    /// The axis the errors are measured on (their unit).
    pub axis: Axis,
    /// What the run did besides its errors (end stops, saturation,
    /// oscillation): not one of the keys of the table.
    pub behaviour: Behaviour,
}

/// The metrics, one line each: the field, what it is (an error in the
/// axis's unit, a number in a fixed unit, the divergence flag, the sample
/// count), in the order of tables and CSV columns. Every list of names, the
/// units and the lookup by name are generated from it.
macro_rules! metric_table {
    ($($field:ident: $kind:ident $($unit:literal)?),* $(,)?) => {
        impl Metrics {
            /// The names of the metrics on a rotary axis, in the order of
            /// tables and CSV columns (errors in degrees: `e_max_deg`).
            pub const NAMES: [&'static str; 13] = [$(metric_table!(@rotary $field $kind)),*];

            /// The names of a linear axis's metrics ([`Metrics::NAMES`]
            /// without the `_deg`; the unit, mm, is beside them).
            pub const NAMES_LINEAR: [&'static str; 13] = [$(stringify!($field)),*];

            /// The columns of a linear axis's metrics in a CSV (results.csv):
            /// the errors with their unit in the name (`e_max_mm`), as a rotary
            /// axis's say `_deg`, so that a table read into pandas or MATLAB
            /// carries its unit.
            pub const CSV_LINEAR: [&'static str; 13] = [$(metric_table!(@csv $field $kind)),*];

            /// The columns of a force loop's metrics in a CSV: `e_max_kN` …
            pub const CSV_FORCE: [&'static str; 13] = [$(metric_table!(@csvu $field $kind "_kN")),*];

            /// The columns of a load-pressure loop's metrics in a CSV: `e_max_bar` …
            pub const CSV_PRESSURE: [&'static str; 13] = [$(metric_table!(@csvu $field $kind "_bar")),*];

            /// The unit of a metric on `axis` (`""` for a ratio, a count or a flag).
            pub fn unit_of(name: &str, axis: Axis) -> &'static str {
                $(
                    if name == stringify!($field) {
                        return metric_table!(@unit axis $kind $($unit)?);
                    }
                    if name == metric_table!(@rotary $field $kind) {
                        return metric_table!(@unit Axis::Rotary $kind $($unit)?);
                    }
                    if name == metric_table!(@csv $field $kind) {
                        return metric_table!(@unit Axis::Linear $kind $($unit)?);
                    }
                    if name == metric_table!(@csvu $field $kind "_kN") {
                        return metric_table!(@unit Axis::Force $kind $($unit)?);
                    }
                    if name == metric_table!(@csvu $field $kind "_bar") {
                        return metric_table!(@unit Axis::Pressure $kind $($unit)?);
                    }
                )*
                ""
            }

            /// A metric by name, as a number (`diverged` is 1 or 0): any
            /// axis's bare name, or the error's name in this axis's unit.
            pub fn get(&self, name: &str) -> Option<f64> {
                let own = Self::csv_names(self.axis);
                let i = Self::NAMES_LINEAR
                    .iter()
                    .position(|n| *n == name)
                    .or_else(|| own.iter().position(|n| *n == name))?;
                let mut k = 0;
                $(
                    if i == k {
                        return metric_table!(@get self $field $kind);
                    }
                    k += 1;
                )*
                let _ = k;
                None
            }
        }
    };
    (@rotary $field:ident error) => { concat!(stringify!($field), "_deg") };
    (@rotary $field:ident $kind:ident) => { stringify!($field) };
    (@csv $field:ident error) => { concat!(stringify!($field), "_mm") };
    (@csv $field:ident $kind:ident) => { stringify!($field) };
    (@csvu $field:ident error $s:literal) => { concat!(stringify!($field), $s) };
    (@csvu $field:ident $kind:ident $s:literal) => { stringify!($field) };
    (@unit $axis:ident error) => { $axis.unit() };
    (@unit $axis:ident value $unit:literal) => { $unit };
    (@unit $axis:ident $kind:ident) => { "" };
    (@unit $a:ident :: $b:ident error) => { Axis::$b.unit() };
    (@unit $a:ident :: $b:ident value $unit:literal) => { $unit };
    (@unit $a:ident :: $b:ident $kind:ident) => { "" };
    (@get $s:ident $field:ident flag) => { Some(if $s.$field { 1.0 } else { 0.0 }) };
    (@get $s:ident $field:ident count) => { Some($s.$field as f64) };
    (@get $s:ident $field:ident $kind:ident) => { $s.$field };
}

metric_table! {
    e_max: error,
    e_final: error,
    e_rms: error,
    u_max: value "V",
    u_rms: value "V",
    chattering: ratio,
    u_tv_per_s: value "V/s",
    w_norm_max: ratio,
    w_norm_final: ratio,
    dead_zone_fraction: ratio,
    diverged: flag,
    diverged_at_s: value "s",
    samples: count,
}

impl Metrics {
    /// The metric columns of `axis` in a CSV: [`Metrics::NAMES`] on a
    /// rotary axis, [`Metrics::CSV_LINEAR`] on a linear one.
    pub fn csv_names(axis: Axis) -> &'static [&'static str; 13] {
        match axis {
            Axis::Rotary => &Self::NAMES,
            Axis::Linear => &Self::CSV_LINEAR,
            Axis::Force => &Self::CSV_FORCE,
            Axis::Pressure => &Self::CSV_PRESSURE,
        }
    }

    /// The metric keys of `axis` (summary.json, the bindings): rotary
    /// `e_max_deg`, linear `e_max` (with the unit beside it).
    pub fn names(axis: Axis) -> &'static [&'static str; 13] {
        match axis {
            Axis::Rotary => &Self::NAMES,
            Axis::Linear | Axis::Force | Axis::Pressure => &Self::NAMES_LINEAR,
        }
    }

    /// A metric by name as a CSV cell: shortest round-trip decimal, empty
    /// when undefined, `true`/`false` for `diverged`, an integer for
    /// `samples`.
    pub fn cell(&self, name: &str) -> String {
        match name {
            "diverged" => self.diverged.to_string(),
            "samples" => self.samples.to_string(),
            _ => self.get(name).map(|v| format!("{v}")).unwrap_or_default(),
        }
    }
}

impl Serialize for Metrics {
    /// The keys of [`Metrics::names`] for the axis, in that order, and on a
    /// linear axis `"unit": "mm"` after the errors (`"kN"`, `"bar"` on a
    /// force or pressure loop).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let linear = self.axis != Axis::Rotary;
        let mut m = s.serialize_map(Some(13 + usize::from(linear)))?;
        let names = Self::names(self.axis);
        for (i, name) in names.iter().enumerate() {
            match *name {
                "diverged" => m.serialize_entry(name, &self.diverged)?,
                "samples" => m.serialize_entry(name, &self.samples)?,
                _ => m.serialize_entry(name, &self.get(name))?,
            }
            if linear && i == 2 {
                m.serialize_entry("unit", self.axis.unit())?;
            }
        }
        m.end()
    }
}

/// What [`Metrics`] reads: either axis's keys.
#[derive(Deserialize)]
struct MetricsRaw {
    #[serde(alias = "e_max_deg")]
    e_max: Option<f64>,
    #[serde(alias = "e_final_deg")]
    e_final: Option<f64>,
    #[serde(alias = "e_rms_deg")]
    e_rms: Option<f64>,
    #[serde(default)]
    unit: Option<String>,
    u_max: Option<f64>,
    u_rms: Option<f64>,
    chattering: Option<f64>,
    u_tv_per_s: Option<f64>,
    w_norm_max: Option<f64>,
    w_norm_final: Option<f64>,
    dead_zone_fraction: Option<f64>,
    diverged: bool,
    diverged_at_s: Option<f64>,
    samples: u64,
}

impl<'de> Deserialize<'de> for Metrics {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = MetricsRaw::deserialize(d)?;
        Ok(Metrics {
            e_max: r.e_max,
            e_final: r.e_final,
            e_rms: r.e_rms,
            u_max: r.u_max,
            u_rms: r.u_rms,
            chattering: r.chattering,
            u_tv_per_s: r.u_tv_per_s,
            w_norm_max: r.w_norm_max,
            w_norm_final: r.w_norm_final,
            dead_zone_fraction: r.dead_zone_fraction,
            diverged: r.diverged,
            diverged_at_s: r.diverged_at_s,
            samples: r.samples,
            axis: match r.unit.as_deref() {
                Some("mm") => Axis::Linear,
                Some("kN") => Axis::Force,
                Some("bar") => Axis::Pressure,
                _ => Axis::Rotary,
            },
            behaviour: Behaviour::default(),
        })
    }
}

/// `*m ← max(*m, v)` by one comparison: as `f64::max` for a running
/// maximum that starts at 0 (a NaN `v` is ignored, as `max` ignores it; on
/// a tie the first is kept), without `max`'s NaN blend, which costs five
/// more instructions per sample and maximum.
#[inline(always)]
fn keep_max(m: &mut f64, v: f64) {
    if v > *m {
        *m = v;
    }
}

/// Accumulates [`Metrics`] sample by sample.
///
/// ```
/// use ehservo_sim::core::math::DR;
/// use ehservo_sim::metrics::MetricsAccumulator;
/// use ehservo_sim::simulation::Sample;
///
/// // A 1-s run, metrics after t = 0.5 s, a reference of period 0.5 s.
/// let mut acc = MetricsAccumulator::new(1.0, 0.5, 0.5, false);
/// // Five samples of (t, e in degrees, u in volts).
/// let rows = [
///     (0.0, 5.0, 10.0),
///     (0.25, 4.0, 0.0),
///     (0.5, 1.0, 1.0),
///     (0.75, -3.0, -1.0),
///     (1.0, 2.0, 1.0),
/// ];
/// for (k, &(t, e_deg, u)) in rows.iter().enumerate() {
///     acc.push(&Sample { k: k as u64, t, e: e_deg * DR, u, ..Sample::default() });
/// }
/// let m = acc.finish(None);
/// assert_eq!(m.samples, 5);
/// // After t = 0.5: max |e| = max(1, 3, 2) = 3°; RMS of u = √((1 + 1 + 1)/3) = 1.
/// assert!((m.e_max.unwrap() - 3.0).abs() < 1e-12);
/// assert!((m.u_rms.unwrap() - 1.0).abs() < 1e-12);
/// // max |u| is over the whole run, the transient's 10 V included.
/// assert_eq!(m.u_max, Some(10.0));
/// // Read by name, as summary.json writes it on a rotary axis.
/// assert_eq!(m.get("e_max_deg"), m.e_max);
/// ```
#[derive(Debug, Clone)]
pub struct MetricsAccumulator {
    settle: f64,
    final_from: f64,
    has_network: bool,
    n: u64,
    n_after: u64,
    e_max: f64,
    e_final: f64,
    e_sq: f64,
    u_max: f64,
    u_sq: f64,
    du_sq: f64,
    du_abs: f64,
    prev_u: Option<f64>,
    t_first_after: Option<f64>,
    t_last: f64,
    w_max: f64,
    w_last: f64,
    dead: u64,
    saw_final: bool,
    i_w_norm: Option<usize>,
    i_sigma_delta: Option<usize>,
    axis: Axis,
    checks: Checks,
    t_first: f64,
    in_contact: bool,
    contacts: u64,
    first_contact: Option<f64>,
    contact_samples: u64,
    at_limit: u64,
    window: ErrorWindow,
}

/// What the accumulator needs to know of the loop for
/// [`Metrics::behaviour`]; by default none of it (no end stops, no limit,
/// no periodic reference).
#[derive(Debug, Clone, PartialEq)]
pub struct Checks {
    /// The plant's end stops (`Plant::end_stops`).
    pub end_stops: Option<[f64; 2]>,
    /// The command's limit (V): the actuator's saturation; infinite for
    /// none. A sample whose `saturated` flag is set counts as at the limit
    /// whatever it is.
    pub limit: f64,
    /// The loop's command has a limit (the actuator's or `[fault]`'s
    /// valve range): otherwise the saturation share is undefined unless
    /// the law itself flagged a sample saturated (ADRC's `u_limit`).
    pub has_limit: bool,
    /// What the reference does after the transient, whose forced
    /// response is not an oscillation (a chirp's `t0` is filled in with
    /// the window's first sample time).
    pub forcing: Forcing,
    /// The amplitude of a sustained oscillation (the axis's display unit).
    pub tolerance: f64,
    /// The loop closes on the position. False for an open loop, whose
    /// reference is a command (`volts_per_mm`·r), not a position: it has
    /// no tracking error (`e_max`, `e_final`, `e_rms` are null) and its
    /// response follows the command, so no oscillation is its own.
    pub tracking: bool,
}

impl Default for Checks {
    fn default() -> Self {
        Self {
            end_stops: None,
            limit: f64::INFINITY,
            has_limit: false,
            forcing: Forcing::None,
            tolerance: OSCILLATION_TOLERANCE,
            tracking: true,
        }
    }
}

impl MetricsAccumulator {
    /// For a run of horizon `horizon` (s), transient end `settle` (s), a
    /// reference of period `period` (s), and whether the controller has a
    /// network (for ‖W‖ and the dead-zone share, read from the samples'
    /// `w_norm` and `sigma_delta` signals).
    pub fn new(horizon: f64, settle: f64, period: f64, has_network: bool) -> Self {
        // A relative tolerance keeps t_k = k·h on the right side of the
        // window edges despite rounding.
        let tol = 1e-9 * horizon.max(1.0);
        Self {
            settle: settle - tol,
            final_from: horizon - period - tol,
            has_network,
            n: 0,
            n_after: 0,
            e_max: 0.0,
            e_final: 0.0,
            e_sq: 0.0,
            u_max: 0.0,
            u_sq: 0.0,
            du_sq: 0.0,
            du_abs: 0.0,
            prev_u: None,
            t_first_after: None,
            t_last: 0.0,
            w_max: 0.0,
            w_last: 0.0,
            dead: 0,
            saw_final: false,
            i_w_norm: None,
            i_sigma_delta: None,
            axis: Axis::Rotary,
            checks: Checks::default(),
            t_first: 0.0,
            in_contact: false,
            contacts: 0,
            first_contact: None,
            contact_samples: 0,
            at_limit: 0,
            window: ErrorWindow::default(),
        }
    }

    /// The same accumulator with what it checks of the loop
    /// ([`Metrics::behaviour`]), for about `expected_after` samples after
    /// the transient (the error's window is allocated for them once).
    pub fn with_checks(mut self, checks: Checks, expected_after: u64) -> Self {
        self.checks = checks;
        self.window = ErrorWindow::with_capacity(expected_after);
        self
    }

    /// The same accumulator for errors measured on `axis` (rotary by
    /// default).
    pub fn on(mut self, axis: Axis) -> Self {
        self.axis = axis;
        self
    }

    /// Takes one sample.
    pub fn push(&mut self, s: &Sample) {
        if self.n == 0 && self.has_network {
            self.i_w_norm = s.index_of("w_norm");
            self.i_sigma_delta = s.index_of("sigma_delta");
        }
        let e = self.axis.display(s.e.abs());
        let u = s.u;
        let w_norm = self.i_w_norm.map_or(0.0, |i| s.values[i]);
        if self.n == 0 {
            self.t_first = s.t;
        }
        self.n += 1;
        self.t_last = s.t;
        keep_max(&mut self.u_max, u.abs());
        if s.flags & flags::SATURATED != 0 || u.abs() >= self.checks.limit {
            self.at_limit += 1;
        }
        if let Some([lo, hi]) = self.checks.end_stops {
            let p = s.x[0];
            let contact = p < lo || p > hi;
            if contact {
                if !self.in_contact {
                    self.contacts += 1;
                    if self.first_contact.is_none() {
                        self.first_contact = Some(s.t);
                    }
                }
                self.contact_samples += 1;
            }
            self.in_contact = contact;
        }
        keep_max(&mut self.w_max, w_norm);
        self.w_last = w_norm;
        if s.t >= self.settle {
            if self.i_sigma_delta.is_some_and(|i| s.values[i] == 0.0) {
                self.dead += 1;
            }
            if self.t_first_after.is_none() {
                self.t_first_after = Some(s.t);
            }
            self.n_after += 1;
            // Signed, in the display unit, for the oscillation.
            self.window.push(self.axis.display(s.e));
            keep_max(&mut self.e_max, e);
            self.e_sq += e * e;
            self.u_sq += u * u;
            if let Some(p) = self.prev_u {
                let du = u - p;
                self.du_sq += du * du;
                self.du_abs += du.abs();
            }
        }
        if s.t >= self.final_from {
            self.saw_final = true;
            keep_max(&mut self.e_final, e);
        }
        self.prev_u = Some(u);
    }

    /// The metrics, given how the run ended.
    pub fn finish(&self, diverged: Option<Divergence>) -> Metrics {
        let after = self.n_after > 0;
        let tracked = after && self.checks.tracking;
        let some_if = |c: bool, v: f64| if c && v.is_finite() { Some(v) } else { None };
        let span = self.t_first_after.map(|t0| self.t_last - t0).unwrap_or(0.0);
        Metrics {
            e_max: some_if(tracked, self.e_max),
            e_final: some_if(
                self.checks.tracking && self.saw_final && diverged.is_none(),
                self.e_final,
            ),
            e_rms: some_if(tracked, (self.e_sq / self.n_after.max(1) as f64).sqrt()),
            u_max: some_if(self.n > 0, self.u_max),
            u_rms: some_if(after, (self.u_sq / self.n_after.max(1) as f64).sqrt()),
            chattering: some_if(after && self.u_sq > 0.0, (self.du_sq / self.u_sq).sqrt()),
            u_tv_per_s: some_if(after && span > 0.0, self.du_abs / span),
            w_norm_max: some_if(self.has_network && self.n > 0, self.w_max),
            w_norm_final: some_if(self.has_network && self.n > 0, self.w_last),
            dead_zone_fraction: some_if(
                self.has_network && after,
                self.dead as f64 / self.n_after.max(1) as f64,
            ),
            diverged: diverged.is_some(),
            diverged_at_s: diverged.map(|d| d.t),
            samples: self.n,
            axis: self.axis,
            behaviour: self.behaviour(diverged.is_some()),
        }
    }

    /// The sample period, from the samples (they are evenly spaced); 0
    /// with fewer than two.
    fn sample_period(&self) -> f64 {
        if self.n > 1 {
            (self.t_last - self.t_first) / (self.n - 1) as f64
        } else {
            0.0
        }
    }

    fn behaviour(&self, diverged: bool) -> Behaviour {
        let h = self.sample_period();
        let end_stops = self.checks.end_stops.map(|_| EndStops {
            contacts: self.contacts,
            first_s: self.first_contact,
            time_s: self.contact_samples as f64 * h,
        });
        let saturation_share = ((self.checks.has_limit || self.at_limit > 0) && self.n > 0)
            .then(|| self.at_limit as f64 / self.n as f64);
        let (kept, stride) = self.window.kept();
        let oscillation = if diverged || h <= 0.0 || !self.checks.tracking {
            None
        } else {
            let forcing = match &self.checks.forcing {
                Forcing::Chirp { chirp, .. } => Forcing::Chirp {
                    chirp: *chirp,
                    t0: self.t_first_after.unwrap_or(0.0),
                },
                f => f.clone(),
            };
            detect_oscillation(kept, h * stride as f64, self.checks.tolerance, &forcing)
        };
        Behaviour {
            end_stops,
            saturation_share,
            oscillation,
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use ehservo_core::control::sliding::SlidingParts;
    use ehservo_core::control::Signals;
    use ehservo_core::math::DR;

    fn sample(k: u64, h: f64, e_deg: f64, u: f64) -> Sample {
        let parts = SlidingParts {
            sigma_delta: if k % 2 == 0 { 0.0 } else { 1.0 },
            w_norm: k as f64,
            ..Default::default()
        };
        let mut s = Sample {
            k,
            t: k as f64 * h,
            e: e_deg * DR,
            u,
            signals: SlidingParts::<f64>::SIGNALS,
            ..Default::default()
        };
        parts.write(&mut s.values);
        s
    }

    /// Ten samples at h = 1 s, settle 5 s, period 2 s, horizon 9 s:
    /// e_k = k degrees, u alternating ±1 after k = 5.
    /// e_max = 9 (k = 9); e_final over t ≥ 7: 9; RMS over k = 5..9:
    /// sqrt((25+36+49+64+81)/5) = sqrt(51) = 7.1414284.
    /// u: k=5..9 → −1, +1, −1, +1, −1 (u_k = (−1)^k); Δu over k = 5..9 is
    /// ±2 each (k = 5 has u_4 = +1 before it): Σ Δu² = 5·4 = 20; Σu² = 5;
    /// c = sqrt(20/5) = 2. TV = 5·2 = 10 over 9 − 5 = 4 s → 2.5 V/s.
    /// Dead zone: σΔ = 0 at even k; after t_s (k = 5..9) that is k = 6, 8: 2 of 5.
    #[test]
    fn metrics_by_hand() {
        let mut m = MetricsAccumulator::new(9.0, 5.0, 2.0, true);
        for k in 0..10 {
            let u = if k % 2 == 0 { 1.0 } else { -1.0 };
            m.push(&sample(k, 1.0, k as f64, u));
        }
        let r = m.finish(None);
        let close = |a: Option<f64>, b: f64| assert!((a.unwrap() - b).abs() < 1e-9, "{a:?} vs {b}");
        close(r.e_max, 9.0);
        close(r.e_final, 9.0);
        close(r.e_rms, 51f64.sqrt());
        close(r.u_max, 1.0);
        close(r.chattering, 2.0);
        close(r.u_tv_per_s, 2.5);
        close(r.w_norm_max, 9.0);
        close(r.w_norm_final, 9.0);
        close(r.dead_zone_fraction, 0.4);
        assert!(!r.diverged);
        assert_eq!(r.samples, 10);
    }

    /// keep_max is f64::max for a maximum running from +0: −0 and
    /// negative values leave +0 as it is, a peak in the middle is kept,
    /// NaN and smaller values leave it, +∞ takes it.
    /// The lists generated from the one table, against the names and units
    /// written out: the errors carry the axis's unit in every form, the
    /// rest their own.
    #[test]
    fn names_units_and_lookup_come_from_one_table() {
        assert_eq!(
            Metrics::NAMES[..3],
            ["e_max_deg", "e_final_deg", "e_rms_deg"]
        );
        assert_eq!(
            Metrics::CSV_LINEAR[..3],
            ["e_max_mm", "e_final_mm", "e_rms_mm"]
        );
        assert_eq!(Metrics::NAMES_LINEAR[..3], ["e_max", "e_final", "e_rms"]);
        assert_eq!(Metrics::NAMES[3..], Metrics::NAMES_LINEAR[3..]);
        assert_eq!(Metrics::NAMES[12], "samples");
        for (name, axis, unit) in [
            ("e_max_deg", Axis::Linear, "deg"),
            ("e_rms_mm", Axis::Rotary, "mm"),
            ("e_final", Axis::Linear, "mm"),
            ("e_final", Axis::Rotary, "deg"),
            ("u_rms", Axis::Linear, "V"),
            ("u_tv_per_s", Axis::Rotary, "V/s"),
            ("diverged_at_s", Axis::Rotary, "s"),
            ("chattering", Axis::Rotary, ""),
            ("samples", Axis::Linear, ""),
            ("nonsense", Axis::Linear, ""),
        ] {
            assert_eq!(Metrics::unit_of(name, axis), unit, "{name}");
        }
        let mut m = sample_metrics(Axis::Linear);
        assert_eq!(m.get("e_max"), Some(1.5));
        assert_eq!(m.get("e_max_mm"), Some(1.5));
        assert_eq!(m.get("e_max_deg"), None, "a rotary name on a linear axis");
        assert_eq!(m.get("u_tv_per_s"), Some(7.0));
        assert_eq!(m.get("diverged"), Some(1.0));
        assert_eq!(m.get("samples"), Some(42.0));
        m.axis = Axis::Rotary;
        assert_eq!(m.get("e_max_deg"), Some(1.5));
        assert_eq!(m.get("e_max_mm"), None);
    }

    fn sample_metrics(axis: Axis) -> Metrics {
        Metrics {
            e_max: Some(1.5),
            e_final: None,
            e_rms: None,
            u_max: None,
            u_rms: None,
            chattering: None,
            u_tv_per_s: Some(7.0),
            w_norm_max: None,
            w_norm_final: None,
            dead_zone_fraction: None,
            diverged: true,
            diverged_at_s: Some(0.5),
            samples: 42,
            axis,
            behaviour: Behaviour::default(),
        }
    }

    /// End stops at x₀ ∈ [0, 1], h = 0.1 s: positions 0.5, 1.2, 1.3, 0.9,
    /// −0.1, −0.2, 0.0, 0.5, 1.01: three entries (k = 1, 4, 8), the first
    /// at 0.1 s, five samples in contact: 0.5 s. The commands 0, 2, −2, 1.9,
    /// 2.5 and four zeros against a limit of 2: three at it (|u| ≥ 2), one
    /// flagged by the law (k = 5): 4 of 9.
    #[test]
    fn end_stops_and_saturation_by_hand() {
        let xs = [0.5, 1.2, 1.3, 0.9, -0.1, -0.2, 0.0, 0.5, 1.01];
        let us = [0.0, 2.0, -2.0, 1.9, 2.5, 0.0, 0.0, 0.0, 0.0];
        let checks = Checks {
            end_stops: Some([0.0, 1.0]),
            limit: 2.0,
            has_limit: true,
            ..Checks::default()
        };
        let mut m = MetricsAccumulator::new(0.8, 0.0, 0.8, false).with_checks(checks, 9);
        for (k, (&x, &u)) in xs.iter().zip(&us).enumerate() {
            m.push(&Sample {
                k: k as u64,
                t: k as f64 * 0.1,
                x: [x, 0.0, 0.0],
                u,
                flags: if k == 5 { flags::SATURATED } else { 0 },
                ..Sample::default()
            });
        }
        let b = m.finish(None).behaviour;
        let e = b.end_stops.unwrap();
        assert_eq!(e.contacts, 3);
        assert_eq!(e.first_s, Some(0.1));
        assert!((e.time_s - 0.5).abs() < 1e-12, "{e:?}");
        assert_eq!(b.saturation_share, Some(4.0 / 9.0));
        assert!(b.hit_end_stop());
        assert!(b.saturated_above(0.2) && !b.saturated_above(0.5));
        // Without stops or a limit: both undefined, not zero.
        let mut plain = MetricsAccumulator::new(0.8, 0.0, 0.8, false);
        plain.push(&Sample::default());
        let b = plain.finish(None).behaviour;
        assert_eq!((b.end_stops, b.saturation_share), (None, None));
    }

    /// The error 2·sin(2π·5t) degrees after the transient is found as an
    /// oscillation of 2° at 0.2 s; the same run diverged has none.
    #[test]
    fn the_error_window_finds_the_oscillation() {
        let h = 1e-3;
        let mut m =
            MetricsAccumulator::new(3.0, 1.0, 3.0, false).with_checks(Checks::default(), 2001);
        for k in 0..=3000u64 {
            let t = k as f64 * h;
            let e = if t < 1.0 {
                50.0
            } else {
                2.0 * (2.0 * std::f64::consts::PI * 5.0 * t).sin()
            };
            m.push(&Sample {
                k,
                t,
                e: e * DR,
                ..Sample::default()
            });
        }
        let o = m.finish(None).behaviour.oscillation.unwrap();
        assert!(o.sustained, "{o:?}");
        assert!((o.period_s.unwrap() - 0.2).abs() < 1e-6, "{o:?}");
        assert!((o.amplitude - 2.0).abs() < 1e-3, "{o:?}");
        let d = Divergence {
            t: 3.0,
            reason: crate::simulation::DivergenceReason::ThetaLimit,
        };
        assert_eq!(m.finish(Some(d)).behaviour.oscillation, None);
    }

    #[test]
    fn keep_max_is_a_running_max() {
        let seq = [
            -0.0,
            -1.0,
            0.5,
            3.0,
            f64::NAN,
            2.0,
            3.0,
            1e-300,
            7.25,
            0.0,
            f64::INFINITY,
            1.0,
        ];
        let (mut a, mut b) = (0.0f64, 0.0f64);
        for v in seq {
            keep_max(&mut a, v);
            b = b.max(v);
            assert_eq!(a.to_bits(), b.to_bits(), "after {v}");
        }
        assert_eq!(a, f64::INFINITY);
    }

    #[test]
    fn early_divergence_leaves_metrics_undefined_not_nan() {
        let mut m = MetricsAccumulator::new(10.0, 2.0, 1.0, false);
        m.push(&sample(0, 0.01, 0.5, 0.0));
        let r = m.finish(Some(Divergence {
            t: 0.01,
            reason: crate::simulation::DivergenceReason::ThetaLimit,
        }));
        assert_eq!(r.e_max, None);
        assert_eq!(r.e_final, None);
        assert_eq!(r.chattering, None);
        assert_eq!(r.w_norm_max, None);
        assert!(r.diverged);
        assert_eq!(r.diverged_at_s, Some(0.01));
    }
}
