//! Building a `[reference]` into its trajectory: one code path for a rotary
//! axis (keys in degrees) and a linear one (millimetres), each in SI.

use super::*;

impl ReferenceCfg {
    /// The kind on `axis`, its keys in the axis's display unit (degrees or
    /// millimetres), its trajectory in SI: one code path for both axes. A
    /// position limit (`theta_limit`, SI; infinite for a plant with end
    /// stops) is checked where the kind's peak is known. On a rotary axis
    /// the amplitude defaults to the paper's 5° (and must be ≥ 0 for a
    /// sine, as the paper's checks had it); on a linear one it is required.
    pub(super) fn build_kind(
        &self,
        axis: Axis,
        horizon: f64,
        theta_limit: f64,
        base_dir: Option<&Path>,
    ) -> Result<AnyReference, Bad> {
        let kind = self.kind;
        let si = |v: f64| axis.to_si(v);
        let amp_key = Self::unit_key(axis, "amplitude_deg");
        let slope_key = Self::unit_key(axis, "slope_deg_per_s");
        // |position| ≤ `peak` (SI) over the run, checked against the limit.
        let within = |key: &str, peak: f64| -> Result<(), Bad> {
            if peak >= theta_limit {
                bad(
                    key,
                    "the reference reaches simulation.theta_limit: every run would count as diverged",
                )
            } else {
                Ok(())
            }
        };
        let amplitude = || -> Result<f64, Bad> {
            let given = match axis {
                Axis::Rotary => return finite(amp_key, self.amplitude()),
                Axis::Linear => self.amplitude_mm,
                Axis::Force => self.amplitude_kn,
                Axis::Pressure => self.amplitude_bar,
            };
            finite(amp_key, required(kind, amp_key, given)?)
        };
        let tau = || {
            let t = required(kind, "prefilter_tau", self.prefilter_tau)?;
            if t.is_finite() && t >= 0.0 {
                Ok(t)
            } else {
                bad(
                    "prefilter_tau",
                    format!("must be finite and >= 0 (got {t:?})"),
                )
            }
        };
        let start = || finite("start", self.start.unwrap_or(0.0));
        match kind {
            ReferenceKind::Sine => {
                let a = match axis {
                    Axis::Rotary => non_negative(amp_key, self.amplitude())?,
                    _ => amplitude()?,
                };
                within(amp_key, si(a))?;
                let f = positive("frequency_hz", self.frequency())?;
                let mut s = Sine::from_deg_hz(0.0, f);
                s.amplitude = si(a);
                Ok(AnyReference::Sine(s))
            }
            ReferenceKind::Step => {
                let a = amplitude()?;
                within(amp_key, si(a.abs()))?;
                let t0 = start()?;
                Table::reference(
                    vec![Knot { t: t0, v: 0.0 }, Knot { t: t0, v: si(a) }],
                    tau()?,
                )
            }
            ReferenceKind::Ramp => {
                let given = match axis {
                    Axis::Rotary => self.slope_deg_per_s,
                    Axis::Linear => self.slope_mm_per_s,
                    // Refused before (`build_on`): no slope key in kN or bar.
                    Axis::Force | Axis::Pressure => None,
                };
                let slope = finite(slope_key, required(kind, slope_key, given)?)?;
                let t0 = start()?;
                within(slope_key, si(slope.abs() * (horizon - t0).max(0.0)))?;
                let end = horizon.max(t0) + 1.0;
                Table::reference(
                    vec![
                        Knot { t: t0, v: 0.0 },
                        Knot {
                            t: end,
                            v: si(slope) * (end - t0),
                        },
                    ],
                    tau()?,
                )
            }
            ReferenceKind::Square => {
                let a = amplitude()?;
                within(amp_key, si(a.abs()))?;
                let f = positive("frequency_hz", self.frequency())?;
                Table::reference(square_knots(si(a), f, horizon)?, tau()?)
            }
            ReferenceKind::Chirp => {
                let a = amplitude()?;
                within(amp_key, si(a.abs()))?;
                let f0 = positive("f0_hz", required(kind, "f0_hz", self.f0_hz)?)?;
                let f1 = positive("f1_hz", required(kind, "f1_hz", self.f1_hz)?)?;
                let d = positive("duration", required(kind, "duration", self.duration)?)?;
                let c = Chirp::try_new(si(a), f0, f1, d)
                    .map_err(|e| KeyError::new("reference", format!("{}: {}", e.name, e.reason)))?;
                Ok(AnyReference::Chirp(c))
            }
            ReferenceKind::Multisine => {
                let comps = self.components(axis)?;
                within(
                    "components",
                    comps.iter().map(|c| c.amplitude.abs()).sum::<f64>(),
                )?;
                let m = Multisine::try_new(&comps)
                    .map_err(|e| KeyError::new("reference.components", e.to_string()))?;
                Ok(AnyReference::Multisine(m))
            }
            ReferenceKind::Csv => {
                let Some(file) = &self.file else {
                    return bad("file", "is required by kind `csv`");
                };
                let tau = tau()?;
                let path = match base_dir {
                    Some(d) if Path::new(file).is_relative() => d.join(file),
                    _ => PathBuf::from(file),
                };
                let knots = read_csv_on(&path, axis)
                    .map_err(|e| KeyError::new("reference.file", e.to_string()))?;
                let peak = knots.iter().map(|k| k.v.abs()).fold(0.0, f64::max);
                within("file", peak).map_err(|e| {
                    let r = format!("{}: {}", path.display(), e.reason);
                    KeyError::new(e.key, r)
                })?;
                Table::reference(knots, tau)
            }
        }
    }

    /// The multisine's components on `axis`, checked, in SI.
    pub(super) fn components(&self, axis: Axis) -> Result<Vec<Component>, Bad> {
        let Some(cs) = &self.components else {
            return bad("components", "is required by kind `multisine`");
        };
        if cs.is_empty() || cs.len() > MAX_COMPONENTS {
            return bad(
                "components",
                format!(
                    "must hold 1 to {MAX_COMPONENTS} components (got {})",
                    cs.len()
                ),
            );
        }
        let akey = Self::unit_key(axis, "amplitude_deg");
        let mut comps = Vec::with_capacity(cs.len());
        for (i, c) in cs.iter().enumerate() {
            let n = i + 1;
            let what = |k: &str, r: &str, v: f64| {
                bad::<Component>("components", format!("component {n}: {k} {r} (got {v:?})"))
            };
            let a = match axis {
                Axis::Rotary => c.amplitude_deg,
                Axis::Linear => c.amplitude_mm,
                // Refused before (`build_on`): no component key in kN or bar.
                Axis::Force | Axis::Pressure => None,
            };
            let Some(a) = a else {
                return bad("components", format!("component {n}: {akey} is required"));
            };
            if !a.is_finite() {
                what(akey, "must be finite", a)?;
            }
            if !(c.frequency_hz.is_finite() && c.frequency_hz > 0.0) {
                what("frequency_hz", "must be finite and > 0", c.frequency_hz)?;
            }
            if !c.phase_deg.is_finite() {
                what("phase_deg", "must be finite", c.phase_deg)?;
            }
            comps.push(Component {
                amplitude: axis.to_si(a),
                frequency: c.frequency_hz,
                phase: c.phase_deg * DR,
            });
        }
        Ok(comps)
    }
}

/// The knots of a square wave of amplitude `v` (SI) and frequency `f`
/// over `horizon`: 0 before t = 0, then +v, −v each half period.
pub(super) fn square_knots(v: f64, f: f64, horizon: f64) -> Result<Vec<Knot>, Bad> {
    let edges = (2.0 * f * horizon).ceil() + 1.0;
    if 2.0 * edges + 2.0 > MAX_KNOTS as f64 {
        return bad(
            "frequency_hz",
            format!(
                "{edges:.3e} edges over the horizon, more than the limit of {}",
                MAX_KNOTS / 2 - 1
            ),
        );
    }
    let mut knots = vec![Knot { t: 0.0, v: 0.0 }, Knot { t: 0.0, v }];
    let mut level = v;
    for m in 1..=edges as u64 {
        let t = m as f64 / (2.0 * f);
        knots.push(Knot { t, v: level });
        level = -level;
        knots.push(Knot { t, v: level });
    }
    Ok(knots)
}
