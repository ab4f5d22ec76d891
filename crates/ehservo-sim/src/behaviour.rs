//! What a run did besides its error metrics, so that a verdict says it:
//! end-stop contacts, the share of samples at the command's limit, and a
//! sustained oscillation of the error after the transient. Computed online
//! by [`crate::metrics::MetricsAccumulator`] (the oscillation from a
//! bounded, evenly thinned copy of the error after the transient).
//!
//! With samples k at t_k = k·h, t_s the end of the transient (`settle`):
//!
//! | key | definition |
//! |---|---|
//! | `end_stops.contacts` | times the true position x₀ entered the stops' region (x₀ below the lower stop or above the upper one), a run that starts there counting one |
//! | `end_stops.first_s` | t_k of the first sample in contact (null: none) |
//! | `end_stops.time_s` | samples in contact × h (s) |
//! | `saturation_share` | share of all samples whose command u is at its limit: \|u\| ≥ the actuator's `saturation`, or the law or `[fault] u_limit` clamped it (the `saturated` flag); null when the loop has no limit |
//! | `oscillation` | the error after t_s, de-meaned, cut into cycles at its upward zero crossings (with a hysteresis of a tenth of the tolerance); see [`detect_oscillation`] |
//!
//! `end_stops` is null for a plant without end stops (only the cylinder
//! has them: `Plant::end_stops`). Contacts are seen at the samples: a
//! bounce shorter than h between two samples is not counted.

use serde::{Deserialize, Serialize};

/// The amplitude (in the axis's display unit: ° or mm) above which an
/// oscillation of the error counts as sustained: half a degree on a
/// rotary axis, half a millimetre on a linear one. Every tracking error of
/// the paper's scenarios stays below it (at most 0.42°).
pub const OSCILLATION_TOLERANCE: f64 = 0.5;

/// Fewest whole cycles after the transient for an oscillation to be
/// judged at all.
pub const OSCILLATION_MIN_CYCLES: usize = 3;

/// An oscillation "does not decay" when its last cycle's amplitude is at
/// least this share of its first cycle's (after the transient).
pub const OSCILLATION_DECAY_FLOOR: f64 = 0.5;

/// A period within this relative distance of the reference's period
/// divided by 1, 2, 3 or 4 is the reference's forced response, not an
/// oscillation of the loop's own.
pub const FORCED_PERIOD_TOLERANCE: f64 = 0.1;

/// What the reference does after the transient, for [`detect_oscillation`]:
/// the frequencies at which the error's forced response cycles, so that
/// it is not taken for an oscillation of the loop's own.
///
/// ```
/// use ehservo_core::reference::Chirp;
/// use ehservo_sim::behaviour::Forcing;
///
/// // A 2 Hz sine forces cycles of 0.5 s (and 0.25 s, 0.1667 s, 0.125 s).
/// let sine = Forcing::Tones(vec![2.0]);
/// assert!(sine.forces(0.5, 0.0) && sine.forces(0.25, 9.0) && !sine.forces(0.4, 0.0));
/// // A sweep from 1 to 11 Hz over 10 s is at 6 Hz at t = 5 s.
/// let chirp = Forcing::Chirp { chirp: Chirp::try_new(1.0, 1.0, 11.0, 10.0).unwrap(), t0: 2.0 };
/// assert!(chirp.forces(1.0 / 6.0, 3.0) && !chirp.forces(1.0 / 6.0, 7.0));
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Forcing {
    /// Nothing after the transient forces a cycle (a step, a ramp), or
    /// what does is not known (a CSV table): every cycle is the loop's own.
    #[default]
    None,
    /// Tones present throughout (Hz): a sine's or a square wave's
    /// frequency, a multisine's components.
    Tones(Vec<f64>),
    /// A linear sweep: at time t the forced cycles are those of its
    /// instantaneous frequency. `t0` is the time (s) of the error window's
    /// first sample on the reference's clock.
    Chirp {
        /// The sweep.
        chirp: ehservo_core::reference::Chirp,
        /// The window's start (s).
        t0: f64,
    },
}

impl Forcing {
    /// Whether a cycle of period `period` (s) whose middle is `t` seconds
    /// into the window is the forced response: `period` within
    /// [`FORCED_PERIOD_TOLERANCE`] of 1/(n·f), n = 1…4, for a frequency f
    /// of the reference at that time.
    pub fn forces(&self, period: f64, t: f64) -> bool {
        let near = |f: f64| {
            f > 0.0
                && (1..=4).any(|n| {
                    let tn = 1.0 / (n as f64 * f);
                    ((period - tn) / tn).abs() <= FORCED_PERIOD_TOLERANCE
                })
        };
        match self {
            Self::None => false,
            Self::Tones(fs) => fs.iter().any(|&f| near(f)),
            Self::Chirp { chirp, t0 } => near(chirp.frequency_at(t0 + t)),
        }
    }
}

/// The share of samples at the command's limit above which a run counts
/// as saturated (the verdict, sweeps, leagues; `ehservo tune`'s default
/// rejection).
pub const SATURATION_SHARE_LIMIT: f64 = 0.2;

/// Most samples of the error after the transient that the oscillation
/// detector keeps: beyond it the kept copy is thinned by two (every other
/// sample), as often as needed.
pub const OSCILLATION_BUFFER: usize = 1 << 16;

/// End-stop contacts of a run.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct EndStops {
    /// Times the plant entered a stop.
    pub contacts: u64,
    /// When it first did (s).
    pub first_s: Option<f64>,
    /// Time in contact (s): samples in contact × h.
    pub time_s: f64,
}

/// The error's oscillation after the transient ([`detect_oscillation`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Oscillation {
    /// Whole cycles found (between the first and last upward crossings).
    pub cycles: u64,
    /// Half the peak-to-peak of the de-meaned error, the mean over the
    /// last half of the cycles (over the whole window with fewer than
    /// [`OSCILLATION_MIN_CYCLES`] cycles), in the axis's display unit.
    pub amplitude: f64,
    /// The mean period of the cycles (s); null with none.
    pub period_s: Option<f64>,
    /// The last cycle's amplitude over the first's; null with none.
    pub decay: Option<f64>,
    /// The loop's forced response to a moving reference ([`Forcing`]):
    /// the mean period is a tone's (or a half, third, quarter of it), or,
    /// under a sweep, at least half of the cycles are, each at its time.
    pub forced: bool,
    /// Sustained: at least [`OSCILLATION_MIN_CYCLES`] cycles, an
    /// amplitude ≥ [`OSCILLATION_TOLERANCE`], a decay ≥
    /// [`OSCILLATION_DECAY_FLOOR`], and not forced.
    pub sustained: bool,
}

/// The run's behaviour: what the verdict names.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Behaviour {
    /// End-stop contacts (null: the plant has no end stops).
    pub end_stops: Option<EndStops>,
    /// Share of the samples at the command's limit (null: no limit).
    pub saturation_share: Option<f64>,
    /// The error's oscillation after the transient (null: fewer than
    /// eight samples after it).
    pub oscillation: Option<Oscillation>,
}

/// One finding of a verdict, in the order the verdict names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Finding {
    /// The run diverged (ended early).
    Unbounded,
    /// The plant hit an end stop.
    HitEndStop,
    /// The error oscillates after the transient, and does not decay.
    Oscillating,
    /// The command sat at its limit for more than
    /// [`SATURATION_SHARE_LIMIT`] of the samples.
    Saturated,
}

impl Finding {
    /// Every finding, in order.
    pub const ALL: [Finding; 4] = [
        Finding::Unbounded,
        Finding::HitEndStop,
        Finding::Oscillating,
        Finding::Saturated,
    ];

    /// The name a verdict, a CSV and a summary use: `unbounded`,
    /// `hit-end-stop`, `oscillating`, `saturated`.
    pub fn name(self) -> &'static str {
        match self {
            Finding::Unbounded => "unbounded",
            Finding::HitEndStop => "hit-end-stop",
            Finding::Oscillating => "oscillating",
            Finding::Saturated => "saturated",
        }
    }
}

impl Behaviour {
    /// The plant hit an end stop.
    pub fn hit_end_stop(&self) -> bool {
        self.end_stops.is_some_and(|s| s.contacts > 0)
    }

    /// The error oscillates after the transient without decaying.
    pub fn oscillating(&self) -> bool {
        self.oscillation.is_some_and(|o| o.sustained)
    }

    /// The command was at its limit in more than `share` of the samples.
    pub fn saturated_above(&self, share: f64) -> bool {
        self.saturation_share.is_some_and(|s| s > share)
    }

    /// The findings of a run that `diverged` or not, with
    /// [`SATURATION_SHARE_LIMIT`]: empty for a run bounded over its horizon
    /// with none of them.
    pub fn findings(&self, diverged: bool) -> Vec<Finding> {
        self.findings_with(diverged, SATURATION_SHARE_LIMIT)
    }

    /// [`Behaviour::findings`] with the saturation share `share` allowed.
    pub fn findings_with(&self, diverged: bool, share: f64) -> Vec<Finding> {
        let mut v = Vec::new();
        if diverged {
            v.push(Finding::Unbounded);
        }
        if self.hit_end_stop() {
            v.push(Finding::HitEndStop);
        }
        if self.oscillating() {
            v.push(Finding::Oscillating);
        }
        if self.saturated_above(share) {
            v.push(Finding::Saturated);
        }
        v
    }
}

/// The columns a table of runs (results.csv, a league's runs.csv) gives
/// the behaviour, after the metrics: the verdict, the end stops' contacts,
/// first contact and time in contact, the saturation share, the
/// oscillation's amplitude (in the axis's unit) and period.
pub fn columns(axis: crate::axis::Axis) -> [&'static str; 7] {
    [
        "verdict",
        "end_stop_contacts",
        "end_stop_first_s",
        "end_stop_time_s",
        "saturation_share",
        match axis {
            crate::axis::Axis::Rotary => "oscillation_amplitude_deg",
            crate::axis::Axis::Linear => "oscillation_amplitude_mm",
            crate::axis::Axis::Force => "oscillation_amplitude_kN",
            crate::axis::Axis::Pressure => "oscillation_amplitude_bar",
        },
        "oscillation_period_s",
    ]
}

/// The verdict's cell: `bounded`, or the findings' names joined by `+`
/// (`hit-end-stop+saturated`).
pub fn verdict_cell(findings: &[Finding]) -> String {
    if findings.is_empty() {
        "bounded".to_string()
    } else {
        findings
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join("+")
    }
}

impl Behaviour {
    /// The cells of [`columns`] for a run that `diverged` or not: numbers
    /// as the shortest decimal that reads back, empty when undefined (no
    /// end stops, no limit, no oscillation found).
    pub fn cells(&self, diverged: bool) -> [String; 7] {
        let num = |v: Option<f64>| match v {
            Some(x) if x.is_finite() => format!("{x:?}"),
            _ => String::new(),
        };
        let osc = self.oscillation.filter(|o| o.cycles > 0);
        [
            verdict_cell(&self.findings(diverged)),
            self.end_stops
                .map(|e| e.contacts.to_string())
                .unwrap_or_default(),
            num(self.end_stops.and_then(|e| e.first_s)),
            num(self.end_stops.map(|e| e.time_s)),
            num(self.saturation_share),
            num(osc.map(|o| o.amplitude)),
            num(osc.and_then(|o| o.period_s)),
        ]
    }
}

/// Runs under each finding of [`Finding::ALL`] (unbounded, hit an end
/// stop, oscillating, saturated), from each run's findings: a run counts
/// under every finding it has.
pub fn tally<'a>(runs: impl IntoIterator<Item = &'a [Finding]>) -> [usize; 4] {
    let mut n = [0; 4];
    for f in runs {
        for (i, k) in Finding::ALL.iter().enumerate() {
            n[i] += usize::from(f.contains(k));
        }
    }
    n
}

/// A tally as text: `2 unbounded, 1 hit an end stop, 0 oscillating, 3
/// saturated`.
pub fn tally_text(n: &[usize; 4]) -> String {
    format!(
        "{} unbounded, {} hit an end stop, {} oscillating, {} saturated",
        n[0], n[1], n[2], n[3]
    )
}

/// Whether `c` is a verdict's cell ([`verdict_cell`]).
pub fn is_verdict_cell(c: &str) -> bool {
    c == "bounded"
        || c.split('+')
            .all(|p| Finding::ALL.iter().any(|f| f.name() == p))
}

/// Detects a sustained oscillation in `e`, the error after the transient
/// sampled every `dt` seconds, in the axis's display unit, against the
/// amplitude `tolerance`; `forcing` is what the reference does there
/// ([`Forcing`]), whose forced response is not counted.
///
/// 1. d = e − mean(e) over the window.
/// 2. Upward zero crossings of d, each at the linear interpolation
///    between the samples around it; a crossing counts only after d was
///    below −tolerance/10 and before it rises above +tolerance/10 (a
///    hysteresis: noise and round-off about zero make no cycles).
/// 3. A cycle runs from one counted crossing to the next: its amplitude is
///    half its peak-to-peak, its period its length.
/// 4. `amplitude` is the mean amplitude of the last half of the cycles;
///    `period_s` the mean period; `decay` the last cycle's amplitude over
///    the first's.
/// 5. `sustained` when there are at least [`OSCILLATION_MIN_CYCLES`]
///    cycles, `amplitude` ≥ `tolerance`, `decay` ≥
///    [`OSCILLATION_DECAY_FLOOR`] (a growing oscillation has decay > 1),
///    and the oscillation is not forced: for steady tones, the mean period
///    is not within [`FORCED_PERIOD_TOLERANCE`] of 1/(n·f), n = 1…4, for
///    a tone f; for a sweep, fewer than half of the cycles (each by its
///    own period, at its middle's time) are ([`Forcing::forces`]).
///
/// None with fewer than eight samples, or a non-finite one (a run that
/// diverged has no window to judge).
///
/// ```
/// use ehservo_sim::behaviour::detect_oscillation;
///
/// // 2 sin(2π·5t) over 2 s at 1 ms: 10 cycles of period 0.2 s.
/// let dt = 1e-3;
/// let e: Vec<f64> = (0..=2000)
///     .map(|k| 2.0 * (2.0 * std::f64::consts::PI * 5.0 * k as f64 * dt).sin())
///     .collect();
/// let o = detect_oscillation(&e, dt, 0.5, &Default::default()).unwrap();
/// assert!(o.sustained);
/// assert!((o.period_s.unwrap() - 0.2).abs() < 1e-6);
/// assert!((o.amplitude - 2.0).abs() < 1e-3);
/// ```
pub fn detect_oscillation(
    e: &[f64],
    dt: f64,
    tolerance: f64,
    forcing: &Forcing,
) -> Option<Oscillation> {
    if e.len() < 8 || !e.iter().all(|v| v.is_finite()) || dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    let band = 0.1 * tolerance;
    // The counted upward crossings: (time, sample index after it).
    let mut crossings: Vec<(f64, usize)> = Vec::new();
    let mut armed = false;
    let mut candidate: Option<(f64, usize)> = None;
    let mut prev: Option<f64> = None;
    for (i, v) in e.iter().enumerate() {
        let d = v - mean;
        if d < -band {
            armed = true;
            candidate = None;
        }
        if let Some(p) = prev {
            if armed && p < 0.0 && d >= 0.0 {
                let t = (i - 1) as f64 * dt + dt * p / (p - d);
                candidate = Some((t, i));
            }
        }
        prev = Some(d);
        if d > band && armed {
            if let Some(c) = candidate.take() {
                crossings.push(c);
            }
            armed = false;
        }
    }
    let half_range = |a: usize, b: usize| {
        let (lo, hi) = e[a..b]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        0.5 * (hi - lo)
    };
    let cycles = crossings.len().saturating_sub(1);
    if cycles == 0 {
        return Some(Oscillation {
            amplitude: half_range(0, e.len()),
            ..Oscillation::default()
        });
    }
    let amps: Vec<f64> = crossings
        .windows(2)
        .map(|w| half_range(w[0].1, w[1].1))
        .collect();
    let period = (crossings[cycles].0 - crossings[0].0) / cycles as f64;
    let last_half = &amps[cycles / 2..];
    let amplitude = last_half.iter().sum::<f64>() / last_half.len() as f64;
    let decay = (amps[0] > 0.0).then(|| amps[cycles - 1] / amps[0]);
    // Steady tones are judged by the mean period (a limit cycle's cycles
    // scatter about its own period, some of them into a tone's band); a
    // sweep, whose forced period moves, cycle by cycle at each one's time.
    let forced = match forcing {
        Forcing::Chirp { .. } => {
            let by_cycle = crossings
                .windows(2)
                .filter(|w| forcing.forces(w[1].0 - w[0].0, 0.5 * (w[0].0 + w[1].0)))
                .count();
            2 * by_cycle >= cycles
        }
        _ => forcing.forces(period, 0.0),
    };
    let sustained = cycles >= OSCILLATION_MIN_CYCLES
        && amplitude >= tolerance
        && decay.is_some_and(|r| r >= OSCILLATION_DECAY_FLOOR)
        && !forced;
    Some(Oscillation {
        cycles: cycles as u64,
        amplitude,
        period_s: Some(period),
        decay,
        forced,
        sustained,
    })
}

/// The error after the transient, kept for [`detect_oscillation`]: at most
/// [`OSCILLATION_BUFFER`] samples, thinned by two each time it fills, so
/// that its memory is allocated once, before the run.
#[derive(Debug, Clone)]
pub(crate) struct ErrorWindow {
    kept: Vec<f64>,
    stride: u64,
    seen: u64,
}

impl Default for ErrorWindow {
    fn default() -> Self {
        Self {
            kept: Vec::new(),
            stride: 1,
            seen: 0,
        }
    }
}

impl ErrorWindow {
    /// For about `expected` samples after the transient.
    pub(crate) fn with_capacity(expected: u64) -> Self {
        let cap = (expected.min(OSCILLATION_BUFFER as u64) as usize).max(8);
        Self {
            kept: Vec::with_capacity(cap),
            stride: 1,
            seen: 0,
        }
    }

    /// Offers the next sample after the transient.
    #[inline]
    pub(crate) fn push(&mut self, e: f64) {
        if self.seen % self.stride == 0 {
            if self.kept.len() == OSCILLATION_BUFFER {
                let mut j = 0;
                for i in (0..self.kept.len()).step_by(2) {
                    self.kept[j] = self.kept[i];
                    j += 1;
                }
                self.kept.truncate(j);
                self.stride *= 2;
            }
            if self.seen % self.stride == 0 {
                self.kept.push(e);
            }
        }
        self.seen += 1;
    }

    /// The kept samples and their spacing in samples.
    pub(crate) fn kept(&self) -> (&[f64], u64) {
        (&self.kept, self.stride)
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // the kept samples are whole numbers, compared exactly
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A chirp's forced response is not an oscillation of the loop's own:
    /// the error 2·(1 + t)·sin φ(t) of a sweep from 1 to 11 Hz over 10 s,
    /// φ(t) = 2π(f0·t + (f1 − f0)t²/(2T)) (its instantaneous frequency
    /// f0 + (f1 − f0)t/T), seen from t0 = 2 s, grows (decay > 1) and has
    /// no steady period: it is forced, not sustained. The loop's own 25 Hz
    /// limit cycle under the same sweep (well away from its 3 to 11 Hz)
    /// still is sustained.
    #[test]
    fn a_chirps_forced_response_is_not_an_oscillation() {
        let (dt, t0) = (1e-3, 2.0);
        let chirp = ehservo_core::reference::Chirp::try_new(1.0, 1.0, 11.0, 10.0).unwrap();
        let forcing = Forcing::Chirp { chirp, t0 };
        let phase = |t: f64| 2.0 * PI * (t + 10.0 * t * t / 20.0);
        let forced: Vec<f64> = (0..8000)
            .map(|k| {
                let t = t0 + k as f64 * dt;
                2.0 * (1.0 + t) * phase(t).sin()
            })
            .collect();
        let o = detect_oscillation(&forced, dt, 0.5, &forcing).unwrap();
        assert!(o.forced && !o.sustained && o.decay.unwrap() > 1.0, "{o:?}");
        // Without knowing the sweep the same error is flagged: what a
        // chirp's run reported before.
        assert!(
            detect_oscillation(&forced, dt, 0.5, &Forcing::None)
                .unwrap()
                .sustained
        );
        let own = sine(1.0, 1.0 / 25.0, dt, 8000, 0.0);
        let o = detect_oscillation(&own, dt, 0.5, &forcing).unwrap();
        assert!(!o.forced && o.sustained, "{o:?}");
    }

    fn sine(amp: f64, period: f64, dt: f64, n: usize, decay_rate: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                amp * (-decay_rate * t).exp() * (2.0 * PI * t / period).sin()
            })
            .collect()
    }

    /// A pure sine A·sin(2πt/P) + c, sampled at dt = P/200 over 10
    /// periods (t = 0 … 10P): found with its period P (the crossings are
    /// interpolated linearly, and a sine's curvature at a zero crossing is
    /// 0) and its amplitude A (a sampled peak is within A·(1 − cos(π·dt/P))
    /// of A), whatever the offset c. The crossing at t = 0 is not counted
    /// (the error was not below the band before it) nor the one at 10P
    /// (nothing after it rises above the band): crossings at P … 9P, 8
    /// cycles.
    #[test]
    fn a_pure_sine_is_found_with_its_amplitude_and_period() {
        let (amp, period) = (3.0, 0.0588);
        let dt = period / 200.0;
        let bound = amp * (1.0 - (PI * dt / period).cos());
        for offset in [0.0, 7.5, -2.0] {
            let e: Vec<f64> = sine(amp, period, dt, 2001, 0.0)
                .iter()
                .map(|v| v + offset)
                .collect();
            let o = detect_oscillation(&e, dt, 0.5, &Forcing::None).unwrap();
            assert!(o.sustained, "{o:?}");
            assert!(!o.forced);
            assert_eq!(o.cycles, 8, "{o:?}");
            assert!(
                (o.period_s.unwrap() - period).abs() < 1e-9 * period,
                "{o:?}"
            );
            assert!((o.amplitude - amp).abs() <= bound + 1e-12, "{o:?}");
            assert!((o.decay.unwrap() - 1.0).abs() < 1e-9);
        }
    }

    /// A·e^{−t/τ}·sin(2πt/P) with τ = 3P: each cycle is e^{−1/3} of the one
    /// before, so the last of n cycles over the first is e^{−(n−1)/3}, far
    /// below 1/2 over 10 periods: not sustained, although every cycle is
    /// above the tolerance.
    #[test]
    fn a_decaying_sine_is_not_sustained() {
        let (amp, period) = (50.0, 0.2);
        let dt = period / 100.0;
        let e = sine(amp, period, dt, 1001, 1.0 / (3.0 * period));
        let o = detect_oscillation(&e, dt, 0.5, &Forcing::None).unwrap();
        assert!(!o.sustained, "{o:?}");
        assert!(o.cycles >= OSCILLATION_MIN_CYCLES as u64, "{o:?}");
        assert!(o.amplitude > 0.5, "{o:?}");
        let d = o.decay.unwrap();
        let want = (-(o.cycles as f64 - 1.0) / 3.0).exp();
        assert!(d < OSCILLATION_DECAY_FLOOR, "{d}");
        // The window's mean (not 0 for a decaying sine) moves the
        // crossings a little: within 5 %.
        assert!((d / want - 1.0).abs() < 0.05, "{d} vs {want}");
    }

    /// A growing sine (as an unstable loop's) is sustained: decay > 1.
    #[test]
    fn a_growing_sine_is_sustained() {
        let period = 1.0 / 17.0;
        let dt = 1e-3;
        let e = sine(0.2, period, dt, 2000, -1.0);
        let o = detect_oscillation(&e, dt, 0.5, &Forcing::None).unwrap();
        assert!(o.sustained, "{o:?}");
        assert!(o.decay.unwrap() > 1.0);
        assert!((o.period_s.unwrap() - period).abs() < 1e-3 * period);
    }

    /// Below the tolerance, at the reference's period or a harmonic of it,
    /// or with too few cycles: not sustained.
    #[test]
    fn small_forced_or_short_oscillations_are_not_sustained() {
        let dt = 1e-3;
        let small =
            detect_oscillation(&sine(0.4, 0.1, dt, 2000, 0.0), dt, 0.5, &Forcing::None).unwrap();
        assert!(!small.sustained && (small.amplitude - 0.4).abs() < 1e-3);
        for n in [1.0, 2.0, 3.0] {
            let e = sine(5.0, 0.5 / n, dt, 4000, 0.0);
            let o = detect_oscillation(&e, dt, 0.5, &Forcing::Tones(vec![2.0])).unwrap();
            assert!(o.forced && !o.sustained, "{n}: {o:?}");
        }
        let short =
            detect_oscillation(&sine(5.0, 1.0, dt, 2500, 0.0), dt, 0.5, &Forcing::None).unwrap();
        assert_eq!(short.cycles, 2);
        assert!(!short.sustained);
        // A constant or a ramp has no crossing; NaN or too few samples: none.
        let ramp: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let o = detect_oscillation(&ramp, dt, 0.5, &Forcing::None).unwrap();
        assert_eq!((o.cycles, o.sustained), (0, false));
        assert_eq!(detect_oscillation(&[1.0; 7], dt, 0.5, &Forcing::None), None);
        let mut nan = vec![0.0; 10];
        nan[3] = f64::NAN;
        assert_eq!(detect_oscillation(&nan, dt, 0.5, &Forcing::None), None);
    }

    /// Noise of ±0.04 about a constant (inside the hysteresis band of
    /// 0.05) makes no cycle.
    #[test]
    fn noise_inside_the_band_makes_no_cycles() {
        let e: Vec<f64> = (0..1000)
            .map(|k| if k % 2 == 0 { 0.04 } else { -0.04 })
            .collect();
        let o = detect_oscillation(&e, 1e-3, 0.5, &Forcing::None).unwrap();
        assert_eq!(o.cycles, 0);
    }

    /// The window keeps every sample up to its size, then every other,
    /// then every fourth: the samples kept are those whose index is a
    /// multiple of the stride.
    #[test]
    fn the_window_thins_evenly() {
        let n = 3 * OSCILLATION_BUFFER as u64 + 5;
        let mut w = ErrorWindow::with_capacity(n);
        for k in 0..n {
            w.push(k as f64);
        }
        let (kept, stride) = w.kept();
        assert_eq!(stride, 4);
        assert!(kept.len() <= OSCILLATION_BUFFER);
        for (i, v) in kept.iter().enumerate() {
            assert_eq!(*v, (i as u64 * stride) as f64);
        }
        assert_eq!(*kept.last().unwrap(), ((n - 1) / 4 * 4) as f64);
    }

    #[test]
    fn findings_in_order() {
        let b = Behaviour {
            end_stops: Some(EndStops {
                contacts: 2,
                first_s: Some(0.5),
                time_s: 0.1,
            }),
            saturation_share: Some(0.3),
            oscillation: Some(Oscillation {
                sustained: true,
                ..Oscillation::default()
            }),
        };
        assert_eq!(b.findings(true), Finding::ALL.to_vec());
        assert_eq!(
            b.findings_with(false, 0.5),
            vec![Finding::HitEndStop, Finding::Oscillating]
        );
        assert!(Behaviour::default().findings(false).is_empty());
    }
}
