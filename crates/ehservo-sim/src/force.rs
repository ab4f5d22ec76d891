//! An external force on a linear axis as a signal of time: constant, a
//! step, a sine or a table read from a CSV file (`[plant.load.force]`),
//! with its time derivative (the lumped-uncertainty diagnostic needs Ḟ).
//!
//! | kind | keys | F(t) (N) |
//! |---|---|---|
//! | `constant` | `value` | value |
//! | `step` | `value`, `start` (0), `initial` (0) | initial, then value from `start` |
//! | `sine` | `amplitude`, `frequency_hz`, `phase_deg` (0), `offset` (0) | offset + amplitude·sin(2πft + phase) |
//! | `csv` | `file` | the file's rows `t_s,force_N`, linearly interpolated, held outside |
//!
//! A positive force pushes the rod in the −y direction (it opposes
//! extension, as a load being lifted does).

use crate::error::{finite, KeyError};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

/// Most rows a force table may have.
pub const MAX_ROWS: usize = 200_000;

/// `[plant.load.force]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ForceCfg {
    /// A constant force.
    Constant {
        /// F (N).
        value: f64,
    },
    /// A step.
    Step {
        /// F after the step (N).
        value: f64,
        /// F before the step (N). Default 0.
        #[serde(default)]
        initial: f64,
        /// When (s). Default 0.
        #[serde(default)]
        start: f64,
    },
    /// A sine.
    Sine {
        /// Amplitude (N).
        amplitude: f64,
        /// Frequency (Hz).
        frequency_hz: f64,
        /// Phase (deg). Default 0.
        #[serde(default)]
        phase_deg: f64,
        /// Offset (N). Default 0.
        #[serde(default)]
        offset: f64,
    },
    /// A table in a CSV file with the header `t_s,force_N`.
    Csv {
        /// The file (relative to the scenario file's directory).
        file: String,
    },
}

/// The validated force signal.
///
/// ```
/// use ehservo_sim::force::{Force, ForceCfg};
///
/// // 50 N + 100 N·sin(2π·2t + 90°), as `[plant.load.force]`.
/// let cfg: ForceCfg = toml::from_str(
///     "kind = \"sine\"\namplitude = 100.0\nfrequency_hz = 2.0\nphase_deg = 90.0\noffset = 50.0",
/// )
/// .unwrap();
/// let f = Force::try_new(&cfg, None).unwrap();
/// // t = 0: F = 50 + 100·sin 90° = 150 N at its peak, so Ḟ = 100·4π·cos 90° = 0.
/// let (force, rate) = f.at(0.0);
/// assert!((force - 150.0).abs() < 1e-12 && rate.abs() < 1e-9);
/// // The nominal model knows the constant part only: the offset.
/// assert_eq!(f.static_part(), 50.0);
/// // A step of 1 kN at 0.5 s.
/// let cfg = ForceCfg::Step { value: 1e3, initial: 0.0, start: 0.5 };
/// let step = Force::try_new(&cfg, None).unwrap();
/// assert_eq!((step.at(0.49).0, step.at(0.5).0), (0.0, 1e3));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum Force {
    /// None.
    Zero,
    /// Constant.
    Constant(f64),
    /// initial before `start`, then `value`.
    Step {
        /// Before.
        initial: f64,
        /// After.
        value: f64,
        /// When.
        start: f64,
    },
    /// offset + amplitude·sin(ω t + φ).
    Sine {
        /// Amplitude.
        amplitude: f64,
        /// ω (rad/s).
        omega: f64,
        /// φ (rad).
        phase: f64,
        /// Offset.
        offset: f64,
    },
    /// (t, F) rows, strictly increasing in t.
    Table(Arc<Vec<(f64, f64)>>),
}

impl Force {
    /// Validates the signal; a CSV file is read from `base_dir` when its
    /// path is relative. The error is the key inside the force's table (or
    /// the file with its row) and the reason.
    pub fn try_new(c: &ForceCfg, base_dir: Option<&Path>) -> Result<Force, KeyError> {
        Ok(match c {
            ForceCfg::Constant { value } => Force::Constant(finite("value", *value)?),
            ForceCfg::Step {
                value,
                initial,
                start,
            } => Force::Step {
                initial: finite("initial", *initial)?,
                value: finite("value", *value)?,
                start: finite("start", *start)?,
            },
            ForceCfg::Sine {
                amplitude,
                frequency_hz,
                phase_deg,
                offset,
            } => {
                let f = finite("frequency_hz", *frequency_hz)?;
                if f <= 0.0 {
                    return Err(KeyError::new(
                        "frequency_hz",
                        format!("must be > 0 (got {f:?})"),
                    ));
                }
                Force::Sine {
                    amplitude: finite("amplitude", *amplitude)?,
                    omega: 2.0 * core::f64::consts::PI * f,
                    phase: finite("phase_deg", *phase_deg)?.to_radians(),
                    offset: finite("offset", *offset)?,
                }
            }
            ForceCfg::Csv { file } => {
                let path = match base_dir {
                    Some(d) if Path::new(file).is_relative() => d.join(file),
                    _ => std::path::PathBuf::from(file),
                };
                Force::Table(Arc::new(read_table(&path)?))
            }
        })
    }

    /// F(t) and Ḟ(t) (N, N/s); Ḟ is the slope of a table's piece and 0 at
    /// a step (its jump is not a rate).
    #[inline]
    pub fn at(&self, t: f64) -> (f64, f64) {
        match self {
            Force::Zero => (0.0, 0.0),
            Force::Constant(v) => (*v, 0.0),
            Force::Step {
                initial,
                value,
                start,
            } => (if t >= *start { *value } else { *initial }, 0.0),
            Force::Sine {
                amplitude,
                omega,
                phase,
                offset,
            } => {
                let (s, c) = (omega * t + phase).sin_cos();
                (offset + amplitude * s, amplitude * omega * c)
            }
            Force::Table(rows) => {
                let i = rows.partition_point(|r| r.0 <= t);
                if i == 0 {
                    (rows[0].1, 0.0)
                } else if i == rows.len() {
                    (rows[i - 1].1, 0.0)
                } else {
                    let (a, b) = (rows[i - 1], rows[i]);
                    let dt = b.0 - a.0;
                    // Two divisions rather than (b − a)/dt: no overflow at
                    // any finite table.
                    let slope = b.1 / dt - a.1 / dt;
                    // (1 − w)·a + w·b: no difference of the two values, so
                    // no overflow either.
                    let w = (t - a.0) / dt;
                    ((1.0 - w) * a.1 + w * b.1, slope)
                }
            }
        }
    }

    /// The largest |F(t)| over all t (N): what can press the rod into a
    /// stop ([`crate::cylinder::Cylinder::stated_penetration`]).
    pub fn peak(&self) -> f64 {
        match self {
            Force::Zero => 0.0,
            Force::Constant(v) => v.abs(),
            Force::Step { initial, value, .. } => initial.abs().max(value.abs()),
            Force::Sine {
                amplitude, offset, ..
            } => offset.abs() + amplitude.abs(),
            Force::Table(rows) => rows.iter().fold(0.0, |m, r| m.max(r.1.abs())),
        }
    }

    /// The constant part the nominal model can know: the value of a
    /// constant force, the initial value of a step, a sine's offset, a
    /// table's first row (N).
    pub fn static_part(&self) -> f64 {
        match self {
            Force::Zero => 0.0,
            Force::Constant(v) => *v,
            Force::Step { initial, .. } => *initial,
            Force::Sine { offset, .. } => *offset,
            Force::Table(rows) => rows[0].1,
        }
    }
}

/// The rows of a force table (`t_s,force_N`), strictly increasing in time.
/// The error is the force table's key `file`, with a reason that names the
/// file, the line and the column.
///
/// ```
/// use ehservo_sim::force::{read_table, Force, ForceCfg};
///
/// let path = std::env::temp_dir().join(format!("ehservo-force-doc-{}.csv", std::process::id()));
/// std::fs::write(&path, "t_s,force_N\n0.0,0.0\n1.0,200.0\n").unwrap();
/// assert_eq!(read_table(&path).unwrap(), [(0.0, 0.0), (1.0, 200.0)]);
/// // As `kind = "csv"`: linear between rows, so 100 N at 0.5 s, rising 200 N/s.
/// let cfg = ForceCfg::Csv { file: path.to_string_lossy().into_owned() };
/// let f = Force::try_new(&cfg, None).unwrap();
/// assert_eq!(f.at(0.5), (100.0, 200.0));
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_table(path: &Path) -> Result<Vec<(f64, f64)>, KeyError> {
    read_columns(path, "force", "force_N")
}

/// The rows of a two-column table `t_s,<value>` of the signal `what`
/// (`"force"`, `"motion"`), strictly increasing in time: [`read_table`]
/// for any value column. The error is the key `file`.
pub fn read_columns(path: &Path, what: &str, value: &str) -> Result<Vec<(f64, f64)>, KeyError> {
    let file = |r: String| KeyError::new("file", r);
    let name = path.display();
    let meta = std::fs::metadata(path).map_err(|e| file(format!("the {what} file {name}: {e}")))?;
    if !meta.is_file() {
        return Err(file(format!(
            "the {what} file {name} is not a regular file"
        )));
    }
    if meta.len() > 16 << 20 {
        return Err(file(format!(
            "the {what} file {name} is larger than 16 MiB"
        )));
    }
    let text =
        std::fs::read_to_string(path).map_err(|e| file(format!("the {what} file {name}: {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let Some((hl, header)) = lines.next() else {
        return Err(file(format!(
            "{name}: is empty: expected the header `t_s,{value}` and rows"
        )));
    };
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    if cols != ["t_s", value] {
        return Err(file(format!(
            "{name}: line {hl}: expected the header `t_s,{value}`, got {}",
            crate::error::quote_start(header)
        )));
    }
    let mut rows: Vec<(f64, f64)> = Vec::new();
    for (line, l) in lines {
        if rows.len() >= MAX_ROWS {
            return Err(file(format!(
                "{name}: line {line}: more than {MAX_ROWS} rows"
            )));
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if f.len() != 2 {
            return Err(file(format!(
                "{name}: line {line}: expected 2 columns (t_s, {value}), got {}",
                f.len()
            )));
        }
        let mut v = [0.0; 2];
        for (j, col) in ["t_s", value].iter().enumerate() {
            let x: f64 = f[j].parse().map_err(|_| {
                file(format!(
                    "{name}: line {line}, column {col}: cannot read {} as a number",
                    crate::error::quote_start(f[j])
                ))
            })?;
            if !x.is_finite() {
                return Err(file(format!(
                    "{name}: line {line}, column {col}: {x:?}: values must be finite"
                )));
            }
            v[j] = x;
        }
        if let Some(prev) = rows.last() {
            if v[0] <= prev.0 {
                return Err(file(format!(
                    "{name}: line {line}, column t_s: time not increasing: {} after {}",
                    v[0], prev.0
                )));
            }
            let dt = v[0] - prev.0;
            if !(dt.is_finite() && (v[1] / dt - prev.1 / dt).is_finite()) {
                return Err(file(format!(
                    "{name}: line {line}: the {what} changes by more than a double can hold per second from the row before"
                )));
            }
        }
        rows.push((v[0], v[1]));
    }
    if rows.is_empty() {
        return Err(file(format!("{name}: no data rows")));
    }
    Ok(rows)
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point
mod tests {
    use super::*;

    #[test]
    fn signals_and_their_rates() {
        let s = Force::Sine {
            amplitude: 3.0,
            omega: 2.0,
            phase: 0.0,
            offset: 1.0,
        };
        let (f, r) = s.at(0.25);
        assert_eq!(f, 1.0 + 3.0 * 0.5_f64.sin());
        assert_eq!(r, 6.0 * 0.5_f64.cos());
        let st = Force::Step {
            initial: -1.0,
            value: 4.0,
            start: 1.0,
        };
        assert_eq!(st.at(0.999).0, -1.0);
        assert_eq!(st.at(1.0).0, 4.0);
        let t = Force::Table(Arc::new(vec![(0.0, 0.0), (2.0, 10.0), (3.0, 10.0)]));
        assert_eq!(t.at(1.0), (5.0, 5.0));
        assert_eq!(t.at(-1.0), (0.0, 0.0));
        assert_eq!(t.at(9.0), (10.0, 0.0));
        // Rows 1e308 apart: the value stays finite (the table's reader
        // refuses a slope that overflows, `tables_are_checked`).
        let big = Force::Table(Arc::new(vec![(0.0, -1e308), (1.0, 1e308)]));
        assert!(big.at(0.5).0.is_finite());
    }

    #[test]
    fn tables_are_checked() {
        let dir = std::env::temp_dir().join(format!("ehservo-force-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("f.csv");
        std::fs::write(&p, "t_s,force_N\n0,1\n1,2\n0.5,3\n").unwrap();
        let e = read_table(&p).unwrap_err();
        assert_eq!(e.key, "file");
        assert_eq!(
            e.reason.to_string(),
            format!(
                "{}: line 4, column t_s: time not increasing: 0.5 after 1",
                p.display()
            )
        );
        let err = |text: &str| {
            std::fs::write(&p, text).unwrap();
            read_table(&p).unwrap_err().reason.to_string()
        };
        assert!(err("t,F\n0,1\n").contains("header"));
        assert!(err("t_s,force_N\n0,nan\n").contains("finite"));
        assert!(err("t_s,force_N\n0,-1e308\n1,1e308\n").contains("line 3"));
        std::fs::write(&p, "t_s,force_N\n0,1\n2,3\n").unwrap();
        assert_eq!(read_table(&p).unwrap(), vec![(0.0, 1.0), (2.0, 3.0)]);
        std::fs::remove_dir_all(&dir).ok();
    }
}
