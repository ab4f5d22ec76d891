//! Joining the outputs of shards into one.
//!
//! Nothing of a shard is taken on trust: its study.json must be a study
//! record whose range fits its shard, the records must be of one study and
//! cover its runs exactly once, and every shard's results.csv must hold
//! exactly the rows its range promises — the study's header, run indices
//! in order, each run's own seed, finite numbers — before anything is
//! written. A shard that fails any of this is bad input (exit 2), named in
//! a one-line message.

use super::plan::{derive_seed, shard_range};
use super::results::header;
use super::{StudyRecord, MAX_RUNS, METRIC_COLUMNS};
use crate::error::InputError;
use crate::output::{write_atomic, Staging};
use anyhow::{anyhow, Context, Result};
use std::path::{Path, PathBuf};

/// Checks a record on its own: a run count within the limit and a range
/// that is the one of its shard.
fn check_record(p: &Path, r: &StudyRecord) -> Result<()> {
    let [lo, hi] = r.range;
    if r.runs == 0 || r.runs > MAX_RUNS {
        crate::bad_input!(
            "{}: {} runs is not between 1 and {MAX_RUNS}: not a study record",
            p.display(),
            r.runs
        );
    }
    if lo > hi || hi > r.runs {
        crate::bad_input!(
            "{}: range {lo}..{hi} does not fit in the study's {} runs",
            p.display(),
            r.runs
        );
    }
    let expected = match r.shard {
        Some([k, n]) if n == 0 || k >= n => crate::bad_input!(
            "{}: shard {k}/{n} is not a shard (need 0 ≤ K < N)",
            p.display()
        ),
        Some([k, n]) => shard_range(r.runs, k, n),
        None => 0..r.runs,
    };
    if expected != (lo..hi) {
        crate::bad_input!(
            "{}: range {lo}..{hi} is not that of {} ({}..{})",
            p.display(),
            match r.shard {
                Some([k, n]) => format!("shard {k}/{n}"),
                None => "a whole study".into(),
            },
            expected.start,
            expected.end
        );
    }
    Ok(())
}

/// Checks row `rec` (at `line`) of a shard's results.csv: run `i` with its
/// seed, varied values that are no NaN or ∞, metrics empty (undefined) or
/// finite numbers.
fn check_row(
    shown: &str,
    rec: &csv::StringRecord,
    line: u64,
    i: u64,
    seed: u64,
    head: &[String],
    n_values: usize,
) -> Result<()> {
    let run = rec.get(0).unwrap_or_default();
    if run != i.to_string() {
        crate::bad_input!(
            "{shown}: line {line}: run {run:?} where run {i} belongs: rows are out of order, duplicated or missing"
        );
    }
    let finite = |c: &str| c.parse::<f64>().is_ok_and(f64::is_finite);
    for (k, c) in rec.iter().enumerate().skip(1).take(n_values) {
        if c.parse::<f64>().is_ok_and(|x| !x.is_finite()) {
            crate::bad_input!(
                "{shown}: line {line}: `{}` = {c} is not a finite number",
                head[k]
            );
        }
    }
    let s = rec.get(1 + n_values).unwrap_or_default();
    if s != derive_seed(seed, i).to_string() {
        crate::bad_input!(
            "{shown}: line {line}: seed {s:?} is not run {i}'s seed: the row was altered or is of another study"
        );
    }
    for (name, c) in METRIC_COLUMNS
        .iter()
        .zip(rec.iter().skip(2 + n_values))
        .filter(|(_, c)| !c.is_empty())
    {
        let ok = match *name {
            "diverged" => c == "true" || c == "false",
            "samples" => c.parse::<u64>().is_ok(),
            _ => finite(c),
        };
        if !ok {
            crate::bad_input!(
                "{shown}: line {line}: `{name}` = {c:?} is not {}",
                match *name {
                    "diverged" => "true or false",
                    "samples" => "a whole number",
                    _ => "a finite number",
                }
            );
        }
    }
    Ok(())
}

/// Joins shard outputs into one results.csv (rows in run order), refusing
/// shards of different studies, overlaps and gaps, and rows that are not
/// exactly those the shards' study.json promise. Returns the runs written.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<u64> {
    if dirs.is_empty() {
        crate::bad_input!("nothing to merge");
    }
    // The same directory given twice, by whatever spelling.
    let mut seen: Vec<(PathBuf, &PathBuf)> = Vec::new();
    for d in dirs {
        if let Ok(c) = d.canonicalize() {
            if let Some((_, first)) = seen.iter().find(|(s, _)| *s == c) {
                crate::bad_input!(
                    "{} is given twice (also as {}): refusing to merge a shard with itself",
                    d.display(),
                    first.display()
                );
            }
            seen.push((c, d));
        }
    }
    if let Ok(o) = out.canonicalize() {
        if let Some((_, d)) = seen.iter().find(|(c, _)| *c == o) {
            crate::bad_input!(
                "--out {}: is the shard {} being merged: refusing to overwrite it",
                out.display(),
                d.display()
            );
        }
    }

    let mut records: Vec<(PathBuf, StudyRecord)> = Vec::new();
    for d in dirs {
        let p = d.join("study.json");
        // A shard folder without its study.json is a wrong argument, like a
        // scenario file that is not there: bad input.
        let text = match crate::input::read_text(&p) {
            Ok(t) => t,
            Err(r) => crate::bad_input!("{}: not a shard output: study.json {r}", d.display()),
        };
        let r: StudyRecord = match serde_json::from_str(&text) {
            Ok(r) => r,
            Err(e) => crate::bad_input!("{}: not a study record: {e}", p.display()),
        };
        check_record(&p, &r)?;
        records.push((d.clone(), r));
    }
    let (first_dir, first) = records[0].clone();
    for (d, r) in &records[1..] {
        if r.study != first.study || r.base != first.base || r.runs != first.runs {
            crate::bad_input!(
                "{} and {} are outputs of different studies: refusing to merge",
                first_dir.display(),
                d.display()
            );
        }
        if r.version != first.version {
            crate::bad_input!(
                "{} was written by {} {} and {} by {}: refusing to merge",
                first_dir.display(),
                first.software,
                first.version,
                d.display(),
                r.version
            );
        }
    }
    records.sort_by_key(|(_, r)| r.range);
    let mut next = 0u64;
    let mut prev: Option<&Path> = None;
    for (d, r) in &records {
        let [lo, hi] = r.range;
        if lo > next {
            crate::bad_input!(
                "runs {next}..{lo} are missing (before {}): a shard is absent",
                d.display()
            );
        }
        if lo < next {
            crate::bad_input!(
                "runs {lo}..{} are in both {} and {}: shards overlap or one is given twice",
                next.min(hi),
                prev.map_or_else(|| "?".into(), |p| p.display().to_string()),
                d.display()
            );
        }
        next = hi;
        prev = Some(d);
    }
    if next != first.runs {
        crate::bad_input!(
            "runs {next}..{} are missing (after {}): a shard is absent",
            first.runs,
            prev.map_or_else(|| "?".into(), |p| p.display().to_string())
        );
    }

    // The rows, each checked, rewritten through one writer (the bytes a
    // whole run writes).
    let columns = first.study.columns();
    let n_values = columns.len();
    let head = header(columns);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&head)?;
    let mut written = 0u64;
    for (d, r) in &records {
        let p = d.join("results.csv");
        let shown = p.display().to_string();
        let bytes = std::fs::read(&p).with_context(|| format!("reading {shown}"))?;
        if bytes.is_empty() {
            crate::bad_input!("{shown}: is empty: not a results.csv");
        }
        if !bytes.ends_with(b"\n") {
            crate::bad_input!("{shown}: does not end with a line break: truncated");
        }
        let mut rd = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(&bytes[..]);
        let mut rows = rd.records();
        let bad_csv = |e: csv::Error| {
            anyhow::Error::from(InputError(format!(
                "{shown}: {}: truncated or corrupted",
                e.to_string().lines().next().unwrap_or_default()
            )))
        };
        let h = rows
            .next()
            .ok_or_else(|| anyhow!(InputError(format!("{shown}: no header"))))?
            .map_err(bad_csv)?;
        if h.iter().ne(head.iter()) {
            crate::bad_input!(
                "{shown}: its header is not the one of study `{}` (expected {})",
                first.study.name,
                head.join(",")
            );
        }
        let [lo, hi] = r.range;
        let mut i = lo;
        for rec in rows {
            let rec = rec.map_err(bad_csv)?;
            let line = rec.position().map_or(0, |p| p.line());
            if i >= hi {
                crate::bad_input!(
                    "{shown}: line {line}: more rows than the {} runs {lo}..{hi} its study.json promises",
                    hi - lo
                );
            }
            check_row(&shown, &rec, line, i, first.study.seed, &head, n_values)?;
            w.write_record(&rec)?;
            i += 1;
            written += 1;
        }
        if i < hi {
            crate::bad_input!(
                "{shown}: {} of the {} rows its study.json promises (runs {lo}..{hi}): truncated or incomplete",
                i - lo,
                hi - lo
            );
        }
    }
    if written != first.runs {
        // The checks above make this impossible; never write a short merge.
        anyhow::bail!("internal error: {written} rows for {} runs", first.runs);
    }
    let out_bytes = w.into_inner().map_err(|e| anyhow!("{e}"))?;
    let stage = Staging::new(out)?;
    write_atomic(&stage.path().join("results.csv"), &out_bytes)?;
    let merged = StudyRecord {
        shard: None,
        range: [0, first.runs],
        ..first.clone()
    };
    write_atomic(
        &stage.path().join("study.json"),
        serde_json::to_string_pretty(&merged)?.as_bytes(),
    )?;
    stage.commit()?;
    Ok(written)
}
