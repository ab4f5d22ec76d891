//! Axes and ticks: a panel's data range (padded), the plotting box a line
//! is clipped to, tick labels for linear and logarithmic axes, and text as
//! drawn.

/// Contiguous runs of finite points.
pub(crate) type Runs = Vec<Vec<(f64, f64)>>;

/// The plotting area in data coordinates; y in log10 when `log_y`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    pub(crate) x0: f64,
    pub(crate) x1: f64,
    pub(crate) y0: f64,
    pub(crate) y1: f64,
    pub(crate) log_y: bool,
}

impl Bounds {
    fn plot_coords(&self, p: (f64, f64)) -> (f64, f64) {
        (p.0, if self.log_y { p.1.log10() } else { p.1 })
    }

    pub(crate) fn data_coords(&self, p: (f64, f64)) -> (f64, f64) {
        (p.0, if self.log_y { 10f64.powf(p.1) } else { p.1 })
    }

    pub(crate) fn inside(&self, p: (f64, f64)) -> bool {
        let q = self.plot_coords(p);
        q.0 >= self.x0 && q.0 <= self.x1 && q.1 >= self.y0 && q.1 <= self.y1
    }

    /// Liang–Barsky: the part of the segment a→b inside the box, as
    /// parameters 0 ≤ t0 ≤ t1 ≤ 1 (None: wholly outside).
    fn clip_segment(&self, a: (f64, f64), b: (f64, f64)) -> Option<(f64, f64)> {
        let (d0, d1) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-d0, a.0 - self.x0),
            (d0, self.x1 - a.0),
            (-d1, a.1 - self.y0),
            (d1, self.y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The visible pieces of a polyline: a piece ends where the line leaves
    /// the box and a new one starts where it comes back.
    pub(crate) fn clip(&self, run: &[(f64, f64)]) -> Runs {
        let mut out: Runs = Vec::new();
        if run.len() == 1 {
            if self.inside(run[0]) {
                out.push(run.to_vec());
            }
            return out;
        }
        let mut cur: Vec<(f64, f64)> = Vec::new();
        for w in run.windows(2) {
            let (a, b) = (self.plot_coords(w[0]), self.plot_coords(w[1]));
            let lerp = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            match self.clip_segment(a, b) {
                Some((t0, t1)) => {
                    if cur.is_empty() || t0 > 0.0 {
                        if !cur.is_empty() {
                            out.push(std::mem::take(&mut cur));
                        }
                        cur.push(self.data_coords(lerp(t0)));
                    }
                    cur.push(self.data_coords(lerp(t1)));
                    if t1 < 1.0 {
                        out.push(std::mem::take(&mut cur));
                    }
                }
                None => {
                    if !cur.is_empty() {
                        out.push(std::mem::take(&mut cur));
                    }
                }
            }
        }
        if !cur.is_empty() {
            out.push(cur);
        }
        out
    }
}

pub(crate) fn range(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo.is_finite() && hi.is_finite() {
        Some((lo, hi))
    } else {
        None
    }
}

pub(crate) fn pad(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo {
        let m = 0.05 * (hi - lo);
        (lo - m, hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - m, hi + m)
    }
}

/// Text as drawn: plotters places no combining marks, so "b̄" (b and a
/// combining macron) is spelt out; Markdown code quotes are dropped.
pub(crate) fn typeset(s: &str) -> String {
    s.replace("b\u{304}", "nominal b").replace('`', "")
}

/// Decimals enough to tell the ticks `at` apart (and no more).
fn tick_decimals(at: &[f64]) -> usize {
    (0..=9)
        .find(|&d| {
            let s = 10f64.powi(d as i32);
            at.iter()
                .all(|v| (v * s - (v * s).round()).abs() < 1e-6 * s.max(1.0))
        })
        .unwrap_or(9)
}

/// A tick label: `decimals` after the point, scientific notation for very
/// large or very small steps, and never "−0".
fn tick_label(v: f64, decimals: usize, sci: bool) -> String {
    let s = if sci && v == 0.0 {
        "0".to_string()
    } else if sci {
        format!("{v:.1e}")
    } else {
        format!("{v:.decimals$}")
    };
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| matches!(c, '0' | '.' | 'e')) => rest.to_string(),
        _ => s,
    }
}

/// A tick formatter for the linear axis whose ticks are `at`.
pub(crate) fn linear_ticks(at: Vec<f64>) -> impl Fn(&f64) -> String {
    let big = at.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = tick_decimals(&at);
    let sci = big >= 1e5 || d > 5;
    // A tick computed as 0 ± rounding prints as 0.
    move |v| {
        let v = if v.abs() <= 1e-9 * big { 0.0 } else { *v };
        tick_label(v, d, sci)
    }
}

/// A tick formatter for a logarithmic axis.
pub(crate) fn log_tick(v: &f64) -> String {
    let e = v.log10();
    if (e - e.round()).abs() < 1e-9 && !(-3.0..=4.0).contains(&e.round()) {
        format!("1e{}", e.round() as i32)
    } else if *v >= 1e-3 && *v < 1e5 {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_never_read_negative_zero() {
        // Ticks −0.1, −0.05, 0, 0.05: two decimals; 0 computed as −1e-17.
        let f = linear_ticks(vec![-0.1, -0.05, -1e-17, 0.05]);
        assert_eq!(f(&-1e-17), "0.00");
        assert_eq!(f(&-0.05), "-0.05");
        let f = linear_ticks(vec![-2.0, 0.0, 2.0]);
        assert_eq!(f(&-0.0), "0");
        assert_eq!(f(&2.0), "2");
        // Ticks 0, 0.25, 0.5: two decimals, not one ("0.3").
        assert_eq!(linear_ticks(vec![0.0, 0.25, 0.5])(&0.25), "0.25");
        // Scientific notation for large ticks, but a plain 0.
        let f = linear_ticks(vec![-2e5, -1e-11, 2e5]);
        assert_eq!(f(&-1e-11), "0");
        assert_eq!(f(&2e5), "2.0e5");
    }

    #[test]
    fn lines_are_clipped_to_the_box() {
        let b = Bounds {
            x0: 0.0,
            x1: 10.0,
            y0: -1.0,
            y1: 1.0,
            log_y: false,
        };
        // Up through y = 1 at x = 1, out to y = 3, back in at x = 3.
        let runs = b.clip(&[(0.0, 0.0), (2.0, 2.0), (4.0, 0.0)]);
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], vec![(0.0, 0.0), (1.0, 1.0)]);
        assert_eq!(runs[1], vec![(3.0, 1.0), (4.0, 0.0)]);
        assert!(b.clip(&[(0.0, 5.0), (10.0, 5.0)]).is_empty());
    }
}
