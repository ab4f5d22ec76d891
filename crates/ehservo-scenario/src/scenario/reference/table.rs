//! A reference read from a CSV table, and the piecewise-linear trajectory
//! through the prefilter that it (and a square wave) becomes.

use super::*;

/// A reference CSV refused: the file, where in it, and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CsvError {
    /// The file could not be read.
    #[error("the reference file {file} {source}")]
    Read {
        /// The file.
        file: String,
        /// Why.
        source: crate::input::ReadError,
    },
    /// Its content: the file, the line and data row when one is at fault.
    #[error("{file}: {}{reason}", at(*.line, *.row))]
    Content {
        /// The file.
        file: String,
        /// The 1-based line of the file.
        line: Option<usize>,
        /// The 1-based data row (after the header).
        row: Option<usize>,
        /// Why.
        reason: String,
    },
}

/// `line L (row R): `, `line L: ` or nothing.
fn at(line: Option<usize>, row: Option<usize>) -> String {
    match (line, row) {
        (Some(l), Some(r)) => format!("line {l} (row {r}): "),
        (Some(l), None) => format!("line {l}: "),
        _ => String::new(),
    }
}

/// The rows of a reference CSV (`t,theta_deg`) as knots (s, rad). The
/// error names the file, the line and the data row.
pub fn read_csv(path: &Path) -> Result<Vec<Knot>, CsvError> {
    read_csv_on(path, Axis::Rotary)
}

/// The rows of a reference CSV on `axis` (`t,theta_deg` or `t,y_mm`) as
/// knots (s, SI).
pub fn read_csv_on(path: &Path, axis: Axis) -> Result<Vec<Knot>, CsvError> {
    let col = axis.column("", "");
    let col = col.as_str();
    let name = path.display().to_string();
    let text = crate::input::read_text(path).map_err(|source| CsvError::Read {
        file: name.clone(),
        source,
    })?;
    let fail = |line: Option<usize>, row: Option<usize>, reason: String| CsvError::Content {
        file: name.clone(),
        line,
        row,
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let Some((hl, header)) = lines.next() else {
        return Err(fail(
            None,
            None,
            format!("is empty: expected the header `t,{col}` and at least two rows"),
        ));
    };
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    if cols != ["t", col] {
        return Err(fail(
            Some(hl),
            None,
            format!(
                "expected the header `t,{col}`, got {}",
                crate::input::quote_start(header)
            ),
        ));
    }
    let mut knots: Vec<Knot> = Vec::new();
    for (row, (line, l)) in lines.enumerate() {
        let bad = |reason: String| Err(fail(Some(line), Some(row + 1), reason));
        if knots.len() >= MAX_KNOTS {
            return bad(format!("more than {MAX_KNOTS} rows"));
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        if fields.len() != 2 {
            return bad(format!(
                "expected 2 columns (t, {col}), got {}",
                fields.len()
            ));
        }
        let mut v = [0.0; 2];
        for (j, col) in ["t", col].iter().enumerate() {
            let Ok(x) = fields[j].parse::<f64>() else {
                return bad(format!(
                    "cannot read {} in column {col} as a number",
                    crate::input::quote_start(fields[j])
                ));
            };
            if x.is_nan() {
                return bad(format!("NaN in column {col}"));
            }
            if !x.is_finite() {
                return bad(format!("{x} in column {col}: values must be finite"));
            }
            v[j] = x;
        }
        if let Some(prev) = knots.last() {
            if v[0] <= prev.t {
                return bad(format!(
                    "non-monotonic time: t = {:?} after {:?} (times must strictly increase)",
                    v[0], prev.t
                ));
            }
            // The interpolation divides by the rows' time step and
            // measures time from the first row: both must be finite.
            if !(v[0] - knots[0].t).is_finite() {
                return bad(format!(
                    "t = {:e} is too far from the first row's t = {:e}: the time span overflows",
                    v[0], knots[0].t
                ));
            }
            let slope = (v[1] * DR - prev.v) / (v[0] - prev.t);
            if !slope.is_finite() {
                return bad(format!(
                    "θd changes by {:e}° in {:e} s from the row before: the slope overflows",
                    v[1] - prev.v / DR,
                    v[0] - prev.t
                ));
            }
        }
        knots.push(Knot {
            t: v[0],
            v: axis.to_si(v[1]),
        });
    }
    match knots.len() {
        0 => Err(fail(
            None,
            None,
            "no data rows: a CSV reference needs at least two".into(),
        )),
        1 => Err(fail(
            None,
            None,
            "a single data row: a CSV reference needs at least two".into(),
        )),
        _ => Ok(knots),
    }
}

/// A piecewise-linear reference through the prefilter, owning its knots
/// and the filter's state at each.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub(super) knots: Vec<Knot>,
    states: Vec<LagState>,
    pub(super) tau: f64,
}

impl Table {
    /// The knots through four lags of `tau`, as a reference.
    pub(super) fn reference(knots: Vec<Knot>, tau: f64) -> Result<AnyReference, Bad> {
        if tau == 0.0 {
            // No prefilter: the pieces' slopes are θ̇d, and must be numbers.
            for w in knots.windows(2) {
                let dt = w[1].t - w[0].t;
                if dt > 0.0 && !(w[1].v / dt - w[0].v / dt).is_finite() {
                    return Err(KeyError::new(
                        "reference",
                        format!(
                            "the reference changes by more than a double can hold per second at t = {}",
                            w[1].t
                        ),
                    ));
                }
            }
            return Ok(AnyReference::Pieces(Arc::new(knots)));
        }
        let mut states = vec![[0.0; 4]; knots.len()];
        Prefiltered::fill_states(&knots, tau, &mut states)
            .map_err(|e| KeyError::new("reference", e.to_string()))?;
        Ok(AnyReference::Table(Arc::new(Table { knots, states, tau })))
    }

    /// The core's view of it.
    pub fn prefiltered(&self) -> Prefiltered<'_> {
        Prefiltered::new(&self.knots, &self.states, self.tau)
            .expect("Table::new filled one state per knot with tau > 0")
    }

    /// The knots (s, rad).
    pub fn knots(&self) -> &[Knot] {
        &self.knots
    }
}
