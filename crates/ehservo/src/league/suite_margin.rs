//! The league file's `[margin]` checks, apart from the rest of the suite's
//! loading (suite.rs was beyond the house's 650 code lines).

use super::*;

impl Loader<'_> {
    /// `[margin]`: its bracket checked, its scenario loaded, its error
    /// limit in the scenario's unit, its keys numeric on every controller.
    pub(super) fn margin(
        &self,
        m: &MarginCfg,
        contestants: &[Contestant],
    ) -> Result<Margin, InputError> {
        self.check_bracket(m)?;
        let scenario = self
            .load("margin.file", &m.scenario, &m.set)
            .map_err(|e| match e {
                InputError::Key {
                    file,
                    line_col,
                    key,
                    reason,
                } => InputError::Key {
                    file,
                    line_col,
                    key: key.replace("margin.file", "margin.scenario"),
                    reason,
                },
                other => other,
            })?;
        self.check_limit(m, &scenario)?;
        let table = self.table_of("margin", &scenario)?;
        let margin = Margin {
            cfg: m.clone(),
            scenario,
            table,
        };
        // The keys must exist and take a number at both ends.
        for k in &m.keys {
            if let Some(v) = lookup(&margin.table, k) {
                crate::tune::numeric(v).map_err(|what| {
                    self.bad(
                        "margin.keys",
                        format!("`{k}` is {what}, not a real number: a margin varies numeric keys"),
                    )
                })?;
            }
        }
        for x in [m.low, m.high] {
            for c in contestants {
                if let Err(e) = margin.build(&c.table, x) {
                    let r = e.to_string();
                    if r.contains("unknown") || crate::tune::not_a_result(&e.reason) {
                        return Err(self.bad("margin.keys", r));
                    }
                }
            }
        }
        Ok(margin)
    }

    /// The margin's keys, bracket, tolerance and scale, before its scenario
    /// is loaded.
    pub(super) fn check_bracket(&self, m: &MarginCfg) -> Result<(), InputError> {
        if m.keys.is_empty() {
            return Err(self.bad("margin.keys", "is empty: name the keys to vary".into()));
        }
        if !(m.low.is_finite() && m.high.is_finite() && m.low < m.high) {
            return Err(self.bad(
                "margin.high",
                format!("low = {} must be < high = {}, both finite", m.low, m.high),
            ));
        }
        if !(m.high - m.low).is_finite() {
            return Err(self.bad(
                "margin.high",
                format!(
                    "high − low = {:e} − {:e} overflows: narrow the bracket",
                    m.high, m.low
                ),
            ));
        }
        crate::bisection::check_tolerance(m.low, m.high, m.tolerance)
            .map_err(|r| self.bad("margin.tolerance", r.to_string()))?;
        if !(m.scale.is_finite() && m.scale != 0.0) {
            return Err(self.bad(
                "margin.scale",
                format!("must be finite and nonzero (got {:?})", m.scale),
            ));
        }
        if !((m.scale * m.low).is_finite() && (m.scale * m.high).is_finite()) {
            return Err(self.bad(
                "margin.scale",
                format!(
                    "scale·low and scale·high must be finite (got {:?}·[{:e}, {:e}])",
                    m.scale, m.low, m.high
                ),
            ));
        }
        Ok(())
    }

    /// The margin's error limit: its key says its unit, the one of the
    /// scenario's axis, and it is finite and positive.
    pub(super) fn check_limit(&self, m: &MarginCfg, scenario: &Loop) -> Result<(), InputError> {
        let (own, other) = match scenario.axis() {
            crate::axis::Axis::Rotary => {
                (("e_limit_deg", m.e_limit_deg), ("e_limit_mm", m.e_limit_mm))
            }
            crate::axis::Axis::Linear => {
                (("e_limit_mm", m.e_limit_mm), ("e_limit_deg", m.e_limit_deg))
            }
            other => {
                return Err(self.bad(
                    "margin.scenario",
                    format!(
                        "the margin's scenario is a {} loop: a league's margin runs on a position loop in this version",
                        other.name()
                    ),
                ))
            }
        };
        if other.1.is_some() {
            return Err(self.bad(
                &format!("margin.{}", other.0),
                format!(
                    "the margin's scenario is on a {} axis: give its error limit as `{}`",
                    scenario.axis().name(),
                    own.0
                ),
            ));
        }
        if let Some(l) = own.1 {
            if !(l.is_finite() && l > 0.0) {
                return Err(self.bad(
                    &format!("margin.{}", own.0),
                    format!("must be finite and > 0 (got {l:?})"),
                ));
            }
        }
        Ok(())
    }

    /// The league's axis. One league, one unit: every scenario (the
    /// margin's too) on the first one's axis.
    pub(super) fn one_axis(
        &self,
        cases: &[Case],
        margin: Option<&Margin>,
    ) -> Result<crate::axis::Axis, InputError> {
        let axis = cases[0].scenario.axis();
        let mut axes: Vec<(String, &Loop)> = cases
            .iter()
            .enumerate()
            .map(|(i, c)| (format!("scenario[{i}].file"), &c.scenario))
            .collect();
        if let Some(m) = margin {
            axes.push(("margin.scenario".into(), &m.scenario));
        }
        if let Some((key, s)) = axes.iter().find(|(_, s)| s.axis() != axis) {
            return Err(self.bad(
                key,
                format!(
                    "`{}` is on a {} axis, `{}` on a {} one: a league's errors share one unit",
                    s.name(),
                    s.axis().name(),
                    cases[0].scenario.name(),
                    axis.name()
                ),
            ));
        }
        Ok(axis)
    }
}
