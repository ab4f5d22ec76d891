//! Building a `[reference]` into its trajectory: the kinds on a rotary axis
//! (degrees) and on a linear one (millimetres), each in SI.

use super::*;

impl ReferenceCfg {
    /// The kinds on a linear axis, in millimetres.
    pub(super) fn build_linear(
        &self,
        horizon: f64,
        base_dir: Option<&Path>,
    ) -> Result<AnyReference, Bad> {
        let kind = self.kind;
        let mm = |v: f64| v / 1e3;
        let amplitude = || -> Result<f64, Bad> {
            let a = required(kind, "amplitude_mm", self.amplitude_mm)?;
            finite("amplitude_mm", a)
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
                let a = amplitude()?;
                let f = positive("frequency_hz", self.frequency())?;
                let mut s = Sine::from_deg_hz(0.0, f);
                s.amplitude = mm(a);
                Ok(AnyReference::Sine(s))
            }
            ReferenceKind::Step => {
                let (a, t0) = (amplitude()?, start()?);
                Table::reference(
                    vec![Knot { t: t0, v: 0.0 }, Knot { t: t0, v: mm(a) }],
                    tau()?,
                )
            }
            ReferenceKind::Ramp => {
                let slope = finite(
                    "slope_mm_per_s",
                    required(kind, "slope_mm_per_s", self.slope_mm_per_s)?,
                )?;
                let t0 = start()?;
                let end = horizon.max(t0) + 1.0;
                Table::reference(
                    vec![
                        Knot { t: t0, v: 0.0 },
                        Knot {
                            t: end,
                            v: mm(slope) * (end - t0),
                        },
                    ],
                    tau()?,
                )
            }
            ReferenceKind::Square => {
                let a = amplitude()?;
                let f = positive("frequency_hz", self.frequency())?;
                Table::reference(square_knots(mm(a), f, horizon)?, tau()?)
            }
            ReferenceKind::Chirp => {
                let a = amplitude()?;
                let f0 = positive("f0_hz", required(kind, "f0_hz", self.f0_hz)?)?;
                let f1 = positive("f1_hz", required(kind, "f1_hz", self.f1_hz)?)?;
                let d = positive("duration", required(kind, "duration", self.duration)?)?;
                let c = Chirp::try_new(mm(a), f0, f1, d)
                    .map_err(|e| KeyError::new("reference", format!("{}: {}", e.name, e.reason)))?;
                Ok(AnyReference::Chirp(c))
            }
            ReferenceKind::Multisine => {
                let comps = self.components(Axis::Linear)?;
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
                let knots = read_csv_on(&path, Axis::Linear)
                    .map_err(|e| KeyError::new("reference.file", e.to_string()))?;
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
                amplitude: match axis {
                    Axis::Rotary => a * DR,
                    Axis::Linear => a / 1e3,
                },
                frequency: c.frequency_hz,
                phase: c.phase_deg * DR,
            });
        }
        Ok(comps)
    }

    /// The paper's kinds, in degrees, with their checks in their order.
    pub(super) fn build_rotary(
        &self,
        horizon: f64,
        theta_limit: f64,
        base_dir: Option<&Path>,
    ) -> Result<AnyReference, Bad> {
        let kind = self.kind;
        // |θd| ≤ `peak` (rad) over the run, checked against the limit.
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
                // The paper's checks, in their order, with their words.
                let (a, f) = (self.amplitude(), self.frequency());
                if !(a.is_finite() && a >= 0.0) {
                    return bad(
                        "amplitude_deg",
                        format!("must be finite and >= 0 (got {a:?})"),
                    );
                }
                within("amplitude_deg", a.to_radians())?;
                if !(f.is_finite() && f > 0.0) {
                    return bad(
                        "frequency_hz",
                        format!("must be finite and > 0 (got {f:?})"),
                    );
                }
                Ok(AnyReference::Sine(Sine::from_deg_hz(a, f)))
            }
            ReferenceKind::Step => {
                let a = finite("amplitude_deg", self.amplitude())?;
                within("amplitude_deg", a.abs().to_radians())?;
                let t0 = start()?;
                let v = a * DR;
                Table::reference(vec![Knot { t: t0, v: 0.0 }, Knot { t: t0, v }], tau()?)
            }
            ReferenceKind::Ramp => {
                let slope = finite(
                    "slope_deg_per_s",
                    required(kind, "slope_deg_per_s", self.slope_deg_per_s)?,
                )?;
                let t0 = start()?;
                within(
                    "slope_deg_per_s",
                    (slope.abs() * (horizon - t0).max(0.0)).to_radians(),
                )?;
                let end = horizon.max(t0) + 1.0;
                Table::reference(
                    vec![
                        Knot { t: t0, v: 0.0 },
                        Knot {
                            t: end,
                            v: slope * DR * (end - t0),
                        },
                    ],
                    tau()?,
                )
            }
            ReferenceKind::Square => {
                let a = finite("amplitude_deg", self.amplitude())?;
                within("amplitude_deg", a.abs().to_radians())?;
                let f = positive("frequency_hz", self.frequency())?;
                Table::reference(square_knots(a * DR, f, horizon)?, tau()?)
            }
            ReferenceKind::Chirp => {
                let a = finite("amplitude_deg", self.amplitude())?;
                within("amplitude_deg", a.abs().to_radians())?;
                let f0 = positive("f0_hz", required(kind, "f0_hz", self.f0_hz)?)?;
                let f1 = positive("f1_hz", required(kind, "f1_hz", self.f1_hz)?)?;
                let d = positive("duration", required(kind, "duration", self.duration)?)?;
                let c = Chirp::try_new(a * DR, f0, f1, d)
                    .map_err(|e| KeyError::new("reference", format!("{}: {}", e.name, e.reason)))?;
                Ok(AnyReference::Chirp(c))
            }
            ReferenceKind::Multisine => {
                let comps = self.components(Axis::Rotary)?;
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
                let knots =
                    read_csv(&path).map_err(|e| KeyError::new("reference.file", e.to_string()))?;
                let peak = knots.iter().map(|k| k.v.abs()).fold(0.0, f64::max);
                within("file", peak).map_err(|e| {
                    let r = format!("{}: {}", path.display(), e.reason);
                    KeyError::new(e.key, r)
                })?;
                Table::reference(knots, tau)
            }
        }
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
