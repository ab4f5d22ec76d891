//! Logged experiments: a CSV file with one header row of named columns,
//! read into SI units and checked before any work.
//!
//! The columns are found by name (`--time`, `--input`, `--output`,
//! `--reference`, `--pressure`, `--velocity` choose others); a name's unit
//! is its suffix (`theta_rad`, `theta_deg`, `y_m`, `y_mm`, `u_V`, `p_load_Pa`,
//! `p_load_bar`, `theta_dot_rad_s`, …) and every value is converted to SI:
//! rad, m, V, Pa, rad/s, m/s, s. ehservo's own `trace.csv` is read as it is:
//! its measured angle `theta_meas_deg` when the sensors were not exact,
//! else `theta_deg`; its command `u_V`; its reference `theta_d_deg`; its
//! load pressure `p_load_Pa`.
//!
//! Refused, with the file, the line and row, the column and the reason
//! (exit code 2): a missing column, a field that is not a number, NaN or
//! infinity, time that does not increase, a sample period that is not
//! uniform (beyond `tolerance` of a period: loggers that print rounded
//! times stay within it), too few rows, a command, a position or a
//! pressure that never moves, and a period the fits cannot work with
//! ([`check_period`]): not a normal positive number, outside
//! [[`MIN_PERIOD`], [`MAX_PERIOD`]], or below what the times' own
//! resolution tells apart ([`TIME_RESOLUTION`]).

use crate::error::InputError;
use std::path::Path;

/// Which kind of motion the output measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Axis {
    /// An angle (rad): the paper's rotary servo.
    Rotary,
    /// A displacement (m): a cylinder.
    Linear,
}

impl Axis {
    /// The SI unit of a position on this axis.
    pub fn unit(self) -> &'static str {
        match self {
            Axis::Rotary => "rad",
            Axis::Linear => "m",
        }
    }
}

/// What a column measures, from its name's suffix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    /// The SI unit the values are converted to.
    pub si: &'static str,
    /// The factor from the logged unit to SI.
    pub factor: f64,
    /// The axis a position column implies.
    pub axis: Option<Axis>,
}

/// Suffixes and their units, longest first so that `_rad_s` wins over `_s`.
const SUFFIXES: &[(&str, &str, f64, Option<Axis>)] = &[
    ("_rad_s", "rad/s", 1.0, Some(Axis::Rotary)),
    (
        "_deg_s",
        "rad/s",
        std::f64::consts::PI / 180.0,
        Some(Axis::Rotary),
    ),
    ("_mm_s", "m/s", 1e-3, Some(Axis::Linear)),
    ("_m_s", "m/s", 1.0, Some(Axis::Linear)),
    ("_rad", "rad", 1.0, Some(Axis::Rotary)),
    (
        "_deg",
        "rad",
        std::f64::consts::PI / 180.0,
        Some(Axis::Rotary),
    ),
    ("_um", "m", 1e-6, Some(Axis::Linear)),
    ("_mm", "m", 1e-3, Some(Axis::Linear)),
    ("_m", "m", 1.0, Some(Axis::Linear)),
    ("_mV", "V", 1e-3, None),
    ("_V", "V", 1.0, None),
    ("_mA", "A", 1e-3, None),
    ("_A", "A", 1.0, None),
    ("_MPa", "Pa", 1e6, None),
    ("_kPa", "Pa", 1e3, None),
    ("_bar", "Pa", 1e5, None),
    ("_Pa", "Pa", 1.0, None),
    ("_ms", "s", 1e-3, None),
    ("_s", "s", 1.0, None),
];

/// The unit of a column from its name; `None` when the name carries none
/// (the values are then taken as SI).
pub fn unit_of(name: &str) -> Option<Unit> {
    SUFFIXES
        .iter()
        .find(|(s, ..)| name.ends_with(s) && name.len() > s.len())
        .map(|&(_, si, factor, axis)| Unit { si, factor, axis })
}

/// Which columns hold what. `None`: the first of the defaults that the
/// file has; `Some("none")`: do not use that channel.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ColumnMap {
    /// Time (default `t_s`, `t`, `time_s`, `time`).
    pub time: Option<String>,
    /// The command (default `u_V`, `u`).
    pub input: Option<String>,
    /// The measured position (default `theta_meas_rad`, `theta_meas_deg`,
    /// `theta_rad`, `theta_deg`, `y_m`, `y_mm`, `position_m`).
    pub output: Option<String>,
    /// The reference of a closed-loop experiment (default `reference_rad`,
    /// `reference_deg`, `theta_d_rad`, `theta_d_deg`, `reference_m`, `r_m`).
    pub reference: Option<String>,
    /// The load pressure (default `p_load_Pa`, `p_load_bar`, `p_load_MPa`).
    pub pressure: Option<String>,
    /// A measured velocity (none by default: `trace.csv`'s `theta_dot_deg_s`
    /// is the true one, not a sensor's).
    pub velocity: Option<String>,
}

const TIME: &[&str] = &["t_s", "t", "time_s", "time"];
const INPUT: &[&str] = &["u_V", "u"];
const OUTPUT: &[&str] = &[
    "theta_meas_rad",
    "theta_meas_deg",
    "theta_rad",
    "theta_deg",
    "y_m",
    "y_mm",
    "position_m",
    "position_mm",
];
const REFERENCE: &[&str] = &[
    "reference_rad",
    "reference_deg",
    "theta_d_rad",
    "theta_d_deg",
    "reference_m",
    "reference_mm",
    "r_m",
];
const PRESSURE: &[&str] = &["p_load_Pa", "p_load_bar", "p_load_MPa"];

/// One channel of an experiment, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// The column it was read from.
    pub column: String,
    /// Its SI unit (empty when the name carried none).
    pub unit: &'static str,
    /// The values, one per sample.
    pub values: Vec<f64>,
}

/// A logged experiment on a uniform time grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// The file (as given).
    pub file: String,
    /// The first sample's time (s).
    pub t0: f64,
    /// The sample period h (s), from the first and last times.
    pub h: f64,
    /// The command, held over each period (zero-order hold).
    pub u: Channel,
    /// The measured position.
    pub y: Channel,
    /// The reference (closed loop).
    pub reference: Option<Channel>,
    /// The load pressure.
    pub pressure: Option<Channel>,
    /// A measured velocity.
    pub velocity: Option<Channel>,
    /// Rotary or linear, from the output's unit.
    pub axis: Axis,
}

impl Experiment {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.y.values.len()
    }

    /// Whether there are no samples (never, once read).
    pub fn is_empty(&self) -> bool {
        self.y.values.is_empty()
    }

    /// The sample times t0 + k·h (s).
    pub fn times(&self) -> Vec<f64> {
        (0..self.len())
            .map(|k| self.t0 + k as f64 * self.h)
            .collect()
    }
}

fn bad(msg: String) -> anyhow::Error {
    anyhow::Error::from(InputError::Request(msg))
}

/// Reading options beside the column map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadOptions {
    /// Largest |t_k − (t0 + k·h)| accepted, as a fraction of h.
    pub tolerance: f64,
    /// Fewest rows accepted.
    pub min_rows: usize,
    /// Only the rows with t in [from, to] (s) are used (`--from`, `--to`):
    /// the whole file is still checked for increasing time, the window for
    /// a uniform period, its length and a moving command.
    pub window: Option<[f64; 2]>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            tolerance: 0.05,
            min_rows: 64,
            window: None,
        }
    }
}

/// Most rows read from one file.
pub const MAX_ROWS: usize = 5_000_000;

/// Shortest sample period accepted (s): 1 ns, a 1 GHz logger. Below it
/// the frequency grid (ω up to π/h) makes ω³ in the frequency fit overflow
/// its scale, and no servo is logged so fast.
pub const MIN_PERIOD: f64 = 1e-9;
/// Longest sample period accepted (s): 1000 s, where a servo's dynamics
/// (tens of Hz) are long past any Nyquist frequency.
pub const MAX_PERIOD: f64 = 1e3;
/// The times' resolution must be finer than this share of a period:
/// ulp(max |t|) = max |t|·ε ≤ 10⁻³·h, or t0 + k·h cannot be told from
/// its neighbours to a thousandth of a period (a Unix time stamp in s at
/// 1 kHz keeps 2.4·10⁻⁴ of a period: accepted).
pub const TIME_RESOLUTION: f64 = 1e-3;

/// The sample period `h` of times from `t0` to `t_last` checked for what
/// the fits need (module doc): a normal positive number within
/// [[`MIN_PERIOD`], [`MAX_PERIOD`]], resolved by the times themselves.
pub fn check_period(file: &str, tname: &str, h: f64, t0: f64, t_last: f64) -> anyhow::Result<()> {
    if !(h.is_finite() && h.is_normal() && h > 0.0) {
        return Err(bad(format!(
            "{file}: column `{tname}`: the sample period {h:e} s is not a normal positive number (subnormal, zero or not finite)"
        )));
    }
    if !(MIN_PERIOD..=MAX_PERIOD).contains(&h) {
        return Err(bad(format!(
            "{file}: column `{tname}`: the sample period {h:e} s is outside [{MIN_PERIOD:e}, {MAX_PERIOD:e}] s: check the time column's unit suffix (`_s`, `_ms`)"
        )));
    }
    let tmax = t0.abs().max(t_last.abs());
    let ulp = tmax * f64::EPSILON;
    if ulp > TIME_RESOLUTION * h {
        return Err(bad(format!(
            "{file}: column `{tname}`: times up to {tmax:e} s are resolved to {ulp:e} s, more than {TIME_RESOLUTION:e} of the period {h:e} s: subtract the start time from the column"
        )));
    }
    Ok(())
}

/// Reads and checks one experiment.
pub fn read(path: &Path, map: &ColumnMap, opts: ReadOptions) -> anyhow::Result<Experiment> {
    let file = path.display().to_string();
    let text = crate::input::read_text_at_most(path, crate::input::MAX_DATA_BYTES)
        .map_err(|r| bad(format!("{file}: the data file {r}")))?;
    parse(&text, &file, map, opts)
}

/// Most characters of the header that an error quotes: a log with
/// hundreds of columns (or a binary file read as one) is named by its
/// first columns and its count, on one short line.
const HEADER_QUOTED: usize = 120;

/// The header's names for an error: all of them when short, else the
/// first ones that fit in [`HEADER_QUOTED`] characters (each cut to it),
/// then how many there are.
fn header_list(header: &[&str]) -> String {
    let all = header.join(", ");
    if all.chars().count() <= HEADER_QUOTED {
        return all;
    }
    let mut out = String::new();
    for h in header {
        let h: String = h.chars().take(HEADER_QUOTED).collect();
        if !out.is_empty() && out.chars().count() + h.chars().count() + 2 > HEADER_QUOTED {
            break;
        }
        if !out.is_empty() {
            out.push_str(", ");
        }
        out.push_str(&h);
    }
    let n = header.len();
    format!("{out}, … ({n} column{})", if n == 1 { "" } else { "s" })
}

/// Finds a column: the one asked for, or the first default present.
fn pick(
    header: &[&str],
    file: &str,
    what: &str,
    flag: &str,
    asked: &Option<String>,
    defaults: &[&str],
    required: bool,
) -> anyhow::Result<Option<usize>> {
    match asked.as_deref() {
        Some("none") if !required => Ok(None),
        Some(name) => match header.iter().position(|h| *h == name) {
            Some(i) => Ok(Some(i)),
            None => Err(bad(format!(
                "{file}: line 1: no column `{name}` ({flag}); the header has: {}",
                header_list(header)
            ))),
        },
        None => {
            let found = defaults
                .iter()
                .find_map(|d| header.iter().position(|h| h == d));
            if found.is_none() && required {
                return Err(bad(format!(
                    "{file}: line 1: no {what} column: expected one of {} (or name it with {flag}); the header has: {}",
                    defaults.join(", "),
                    header_list(header)
                )));
            }
            Ok(found)
        }
    }
}

/// Parses and checks the text of one experiment.
pub fn parse(
    text: &str,
    file: &str,
    map: &ColumnMap,
    opts: ReadOptions,
) -> anyhow::Result<Experiment> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hl, header_line)) = lines.next() else {
        return Err(bad(format!(
            "{file}: is empty: expected a header row of named columns (t_s, u_V, theta_rad, …)"
        )));
    };
    let header: Vec<&str> = header_line.split(',').map(str::trim).collect();
    if header.iter().all(|h| h.parse::<f64>().is_ok()) {
        return Err(bad(format!(
            "{file}: line {hl}: the first row is numbers, not a header: name the columns (t_s, u_V, theta_rad, …)"
        )));
    }
    let c = columns(&header, file, map)?;
    let cols: Vec<(usize, &str)> = [Some(c.ti), Some(c.ui), Some(c.yi), c.ri, c.pi, c.vi]
        .into_iter()
        .flatten()
        .map(|i| (i, header[i]))
        .collect();
    let (data, line_of) = read_rows(lines, file, header.len(), &cols)?;
    let n = line_of.len();
    if n < opts.min_rows.max(2) {
        return Err(bad(format!(
            "{file}: {n} data rows: at least {} are needed",
            opts.min_rows.max(2)
        )));
    }
    // Time: strictly increasing and uniform.
    let tname = header[c.ti];
    let tf = unit_of(tname).map_or(1.0, |u| u.factor);
    let t: Vec<f64> = data[0].iter().map(|v| v * tf).collect();
    for k in 1..n {
        if t[k] <= t[k - 1] {
            return Err(bad(format!(
                "{file}: line {} (row {}), column `{tname}`: time does not increase (t = {} after {})",
                line_of[k],
                k + 1,
                data[0][k],
                data[0][k - 1]
            )));
        }
    }
    let rows = Rows {
        t,
        data,
        row_of: (1..=n).collect(),
        line_of,
    };
    let rows = match opts.window {
        None => rows,
        Some(w) => rows.window(w, file, tname, opts.min_rows.max(2))?,
    };
    let h = rows.uniform_period(file, tname, opts.tolerance)?;
    experiment(file, &cols, &rows, h, &c)
}

/// The columns of an experiment, by index into the header: time, command
/// and position, and the optional reference, pressure and velocity.
struct Columns {
    ti: usize,
    ui: usize,
    yi: usize,
    ri: Option<usize>,
    pi: Option<usize>,
    vi: Option<usize>,
    /// Rotary or linear, from the position's unit.
    axis: Axis,
}

/// Finds the columns the map asks for (or the defaults) in the header; the
/// position must be an angle or a length.
fn columns(header: &[&str], file: &str, map: &ColumnMap) -> anyhow::Result<Columns> {
    let ti = pick(header, file, "time", "--time", &map.time, TIME, true)?.unwrap_or(0);
    let ui = pick(header, file, "command", "--input", &map.input, INPUT, true)?.unwrap_or(0);
    let yi = pick(
        header,
        file,
        "position",
        "--output",
        &map.output,
        OUTPUT,
        true,
    )?
    .unwrap_or(0);
    let ri = pick(
        header,
        file,
        "reference",
        "--reference",
        &map.reference,
        REFERENCE,
        false,
    )?;
    let pi = pick(
        header,
        file,
        "pressure",
        "--pressure",
        &map.pressure,
        PRESSURE,
        false,
    )?;
    let vi = match &map.velocity {
        None => None,
        v => pick(header, file, "velocity", "--velocity", v, &[], false)?,
    };
    let y_unit = unit_of(header[yi]);
    let axis = y_unit.and_then(|u| u.axis).unwrap_or(Axis::Rotary);
    if let Some(u) = y_unit {
        if u.si != "rad" && u.si != "m" {
            return Err(bad(format!(
                "{file}: column `{}`: a position must be in rad, deg, m or mm (its unit is {})",
                header[yi], u.si
            )));
        }
    }
    Ok(Columns {
        ti,
        ui,
        yi,
        ri,
        pi,
        vi,
        axis,
    })
}

/// Reads the data rows: each one's values of the columns `cols` (finite
/// numbers, as many fields as the header has), and each row's line.
fn read_rows<'a>(
    lines: impl Iterator<Item = (usize, &'a str)>,
    file: &str,
    fields_in_header: usize,
    cols: &[(usize, &str)],
) -> anyhow::Result<(Vec<Vec<f64>>, Vec<usize>)> {
    let mut data: Vec<Vec<f64>> = vec![Vec::new(); cols.len()];
    let mut line_of: Vec<usize> = Vec::new();
    for (row, (line, l)) in lines.enumerate() {
        let row = row + 1;
        if row > MAX_ROWS {
            return Err(bad(format!(
                "{file}: line {line} (row {row}): more than {MAX_ROWS} rows"
            )));
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        if fields.len() != fields_in_header {
            return Err(bad(format!(
                "{file}: line {line} (row {row}): {} fields, the header has {}",
                fields.len(),
                fields_in_header
            )));
        }
        for (j, &(c, name)) in cols.iter().enumerate() {
            let v: f64 = fields[c].parse().map_err(|_| {
                bad(format!(
                    "{file}: line {line} (row {row}), column `{name}`: `{}` is not a number",
                    fields[c]
                ))
            })?;
            if v.is_nan() {
                return Err(bad(format!(
                    "{file}: line {line} (row {row}), column `{name}`: NaN (a logged value must be a number)"
                )));
            }
            if !v.is_finite() {
                return Err(bad(format!(
                    "{file}: line {line} (row {row}), column `{name}`: {v} (values must be finite)"
                )));
            }
            data[j].push(v);
        }
        line_of.push(line);
    }
    Ok((data, line_of))
}

/// The rows kept: the times (s), the columns' values as read, and each
/// row's line in the file and its number among the data rows.
struct Rows {
    t: Vec<f64>,
    data: Vec<Vec<f64>>,
    line_of: Vec<usize>,
    row_of: Vec<usize>,
}

impl Rows {
    /// The rows with t in the window [a, b] (`--from`, `--to`), at least
    /// `min_rows` of them.
    fn window(
        self,
        [a, b]: [f64; 2],
        file: &str,
        tname: &str,
        min_rows: usize,
    ) -> anyhow::Result<Rows> {
        let (t, n) = (&self.t, self.t.len());
        let keep: Vec<usize> = (0..n).filter(|&k| t[k] >= a && t[k] <= b).collect();
        if keep.len() < min_rows {
            return Err(bad(format!(
                "{file}: column `{tname}`: the window [{a}, {b}] s (--from, --to) keeps {} rows of {n} (t from {} to {} s): at least {} are needed",
                keep.len(),
                t[0],
                t[n - 1],
                min_rows
            )));
        }
        let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        Ok(Rows {
            t: pick(t),
            data: self.data.iter().map(|c| pick(c)).collect(),
            line_of: keep.iter().map(|&k| self.line_of[k]).collect(),
            row_of: keep.iter().map(|&k| k + 1).collect(),
        })
    }

    /// The sample period h from the first and last times; every time must
    /// lie within `tolerance`·h of the uniform grid.
    fn uniform_period(&self, file: &str, tname: &str, tolerance: f64) -> anyhow::Result<f64> {
        let (t, n) = (&self.t, self.t.len());
        let h = (t[n - 1] - t[0]) / (n - 1) as f64;
        check_period(file, tname, h, t[0], t[n - 1])?;
        for k in 0..n {
            let dev = t[k] - (t[0] + k as f64 * h);
            if dev.abs() > tolerance * h {
                return Err(bad(format!(
                    "{file}: line {} (row {}), column `{tname}`: non-uniform sample period: t = {} s where a uniform grid of period {h:.6e} s puts {:.6e} s (off by {:.1} % of a period; the limit is {:.1} %)",
                    self.line_of[k],
                    self.row_of[k],
                    t[k],
                    t[0] + k as f64 * h,
                    100.0 * dev.abs() / h,
                    100.0 * tolerance
                )));
            }
        }
        Ok(h)
    }
}

/// The experiment from its rows: each channel in SI units; the command
/// must move and a pressure be in Pa.
fn experiment(
    file: &str,
    cols: &[(usize, &str)],
    rows: &Rows,
    h: f64,
    c: &Columns,
) -> anyhow::Result<Experiment> {
    let data = &rows.data;
    let channel = |j: usize| -> Channel {
        let name = cols[j].1;
        let u = unit_of(name);
        let f = u.map_or(1.0, |u| u.factor);
        Channel {
            column: name.to_string(),
            unit: u.map_or("", |u| u.si),
            values: data[j].iter().map(|v| v * f).collect(),
        }
    };
    let u = channel(1);
    let y = channel(2);
    for (ch, what, j) in [(&u, "the command", 1), (&y, "the position", 2)] {
        if !moves(&ch.values) {
            return Err(bad(format!(
                "{file}: column `{}`: {what} never moves (every row is {}): nothing can be identified",
                ch.column, data[j][0]
            )));
        }
    }
    let mut j = 3;
    let mut next = |present: bool| {
        if present {
            j += 1;
            Some(channel(j - 1))
        } else {
            None
        }
    };
    let reference = next(c.ri.is_some());
    let pressure = next(c.pi.is_some());
    let velocity = next(c.vi.is_some());
    if let Some(p) = &pressure {
        if !moves(&p.values) {
            return Err(bad(format!(
                "{file}: column `{}`: the pressure never moves (every row is {}): a sensor that reads nothing (leave it out with --pressure none)",
                p.column, p.values[0]
            )));
        }
        if !p.unit.is_empty() && p.unit != "Pa" {
            return Err(bad(format!(
                "{file}: column `{}`: a pressure must be in Pa, kPa, bar or MPa",
                p.column
            )));
        }
    }
    Ok(Experiment {
        file: file.to_string(),
        t0: rows.t[0],
        h,
        u,
        y,
        reference,
        pressure,
        velocity,
        axis: c.axis,
    })
}

/// Whether a signal moves: its range is more than 10⁻¹² of its size (a
/// constant logged as text, or rounding of one, does not).
fn moves(v: &[f64]) -> bool {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    hi - lo > 1e-12 * hi.abs().max(lo.abs()) && hi > lo
}

#[cfg(test)]
#[path = "data_tests.rs"]
mod tests;
