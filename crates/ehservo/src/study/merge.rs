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
use super::{StudyRecord, MAX_RUNS};
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
    // The metric columns: after run, the values and seed, before error.
    let metrics = &head[(2 + n_values).min(head.len())..head.len().saturating_sub(1)];
    for (name, c) in metrics
        .iter()
        .zip(rec.iter().skip(2 + n_values))
        .filter(|(_, c)| !c.is_empty())
    {
        let ok = match name.as_str() {
            "diverged" => c == "true" || c == "false",
            "samples" | "end_stop_contacts" => c.parse::<u64>().is_ok(),
            "verdict" => crate::behaviour::is_verdict_cell(c),
            _ => finite(c),
        };
        if !ok {
            crate::bad_input!(
                "{shown}: line {line}: `{name}` = {c:?} is not {}",
                match name.as_str() {
                    "diverged" => "true or false",
                    "samples" | "end_stop_contacts" => "a whole number",
                    "verdict" => "a verdict (bounded, or unbounded, hit-end-stop, oscillating, saturated joined by +)",
                    _ => "a finite number",
                }
            );
        }
    }
    Ok(())
}

/// Reads and checks a shard folder's study.json (its text and the record).
fn read_record_text(d: &Path) -> Result<(String, StudyRecord)> {
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
    Ok((text, r))
}

/// Reads and checks a shard folder's study.json.
fn read_record(d: &Path) -> Result<StudyRecord> {
    read_record_text(d).map(|(_, r)| r)
}

/// The longest row of a shard's results.csv read (bytes).
const MAX_ROW_BYTES: u64 = 16 << 10;

/// The rows of shard folder `d`'s results.csv, each checked against its
/// record `r` (the rows its range promises, in order, with their seeds,
/// under the study's header).
fn shard_rows(d: &Path, r: &StudyRecord) -> Result<Vec<csv::StringRecord>> {
    let columns = r.study.columns();
    let n_values = columns.len();
    let head = header(columns, r.axis);
    let p = d.join("results.csv");
    let shown = p.display().to_string();
    // A regular file of a bounded size (a device or a FIFO in its place
    // would be read until memory runs out): a row of results.csv is far
    // below 16 KiB.
    let most = (r.range[1].saturating_sub(r.range[0]) + 1).saturating_mul(MAX_ROW_BYTES);
    match std::fs::metadata(&p) {
        Ok(m) if !m.is_file() => crate::bad_input!("{shown}: is not a regular file"),
        Ok(m) if m.len() > most => crate::bad_input!(
            "{shown}: is {} bytes, more than {most} for the {} rows its study.json promises",
            m.len(),
            r.range[1].saturating_sub(r.range[0])
        ),
        _ => {}
    }
    let bytes = match std::fs::read(&p) {
        Ok(b) => b,
        // study.json without results.csv: not a whole shard.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            crate::bad_input!("{shown}: is not there: the shard is incomplete")
        }
        Err(e) => return Err(e).with_context(|| format!("reading {shown}")),
    };
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
        anyhow::Error::from(InputError::Request(format!(
            "{shown}: {}: truncated or corrupted",
            e.to_string().lines().next().unwrap_or_default()
        )))
    };
    let h = rows
        .next()
        .ok_or_else(|| anyhow!(InputError::file(&shown, "no header")))?
        .map_err(bad_csv)?;
    if h.iter().ne(head.iter()) {
        crate::bad_input!(
            "{shown}: its header is not the one of study `{}` (expected {})",
            r.study.name,
            head.join(",")
        );
    }
    let [lo, hi] = r.range;
    let mut i = lo;
    let mut out = Vec::new();
    for rec in rows {
        let rec = rec.map_err(bad_csv)?;
        let line = rec.position().map_or(0, |p| p.line());
        if i >= hi {
            crate::bad_input!(
                "{shown}: line {line}: more rows than the {} runs {lo}..{hi} its study.json promises",
                hi - lo
            );
        }
        check_row(&shown, &rec, line, i, r.study.seed, &head, n_values)?;
        out.push(rec);
        i += 1;
    }
    if i < hi {
        crate::bad_input!(
            "{shown}: {} of the {} rows its study.json promises (runs {lo}..{hi}): truncated or incomplete",
            i - lo,
            hi - lo
        );
    }
    Ok(out)
}

/// Checks a shard output folder whole — its study.json and every row of
/// its results.csv, as [`merge`] does — and returns the text of its
/// study.json. An error says what is wrong (bad input).
pub fn check_shard(dir: &Path) -> Result<String> {
    let (text, r) = read_record_text(dir)?;
    shard_rows(dir, &r)?;
    Ok(text)
}

/// The shards `k` of `n` (of a study of `runs` runs) holding runs and lying
/// inside runs `lo..hi`.
fn shards_within(runs: u64, n: u64, lo: u64, hi: u64) -> Vec<u64> {
    (0..n)
        .filter(|&k| {
            let r = shard_range(runs, k, n);
            !r.is_empty() && r.start >= lo && r.end <= hi
        })
        .collect()
}

/// "runs lo..hi are missing" told as the shards to rerun when every shard
/// given is one of `n` and the gap is made of whole shards.
fn missing_message(runs: u64, split: Option<u64>, lo: u64, hi: u64, place: &str) -> String {
    if let Some(n) = split {
        let ks = shards_within(runs, n, lo, hi);
        let covered: u64 = ks
            .iter()
            .map(|&k| shard_range(runs, k, n))
            .map(|r| r.end - r.start)
            .sum();
        if let ([k], true) = (&ks[..], covered == hi - lo) {
            return format!(
                "shard {k}/{n} (runs {lo}..{hi}) is missing ({place}): rerun it with --shard {k}/{n}"
            );
        }
        if !ks.is_empty() && covered == hi - lo {
            return format!(
                "shards K/{n} for K in {} (runs {lo}..{hi}) are missing ({place}): rerun each with --shard K/{n} (`ehservo merge --missing` lists every index to resubmit)",
                index_list(&ks)
            );
        }
    }
    format!("runs {lo}..{hi} are missing ({place}): a shard is absent")
}

/// Indices as Slurm's `--array=` takes them: ascending, runs of three or
/// more as `a-b`, the rest separated by commas (`0,2,5-9`).
pub fn index_list(ks: &[u64]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < ks.len() {
        let mut j = i;
        while j + 1 < ks.len() && ks[j + 1] == ks[j] + 1 {
            j += 1;
        }
        if j >= i + 2 {
            parts.push(format!("{}-{}", ks[i], ks[j]));
        } else {
            parts.extend(ks[i..=j].iter().map(u64::to_string));
        }
        i = j + 1;
    }
    parts.join(",")
}

/// The split every record is a shard of: `Some(n)` if each is a shard of
/// `n`, the same `n` for all.
fn common_split<'a>(records: impl IntoIterator<Item = &'a StudyRecord>) -> Option<u64> {
    let mut n = None;
    for r in records {
        match (r.shard, n) {
            (Some([_, m]), None) => n = Some(m),
            (Some([_, m]), Some(k)) if m == k => {}
            _ => return None,
        }
    }
    n
}

/// What `ehservo merge --missing` finds: the split, the shard indices
/// missing from it, and why each folder that was given but not counted was
/// set aside.
#[derive(Debug, Clone, PartialEq)]
pub struct Missing {
    /// N of the split.
    pub n: u64,
    /// The indices K (of N) that no whole shard holds, ascending.
    pub missing: Vec<u64>,
    /// Folders given that are not whole shards, each with the reason.
    pub set_aside: Vec<(PathBuf, String)>,
}

/// The shards of a split that are not among `dirs` whole: each folder is
/// checked as [`merge`] checks it, and one that fails is set aside (its
/// shard counts as missing). The split N is read from the whole shards,
/// which must be shards of one study and one N (bad input otherwise, and
/// when there is no whole shard to read it from).
pub fn missing(dirs: &[PathBuf]) -> Result<Missing> {
    let mut whole: Vec<(PathBuf, StudyRecord)> = Vec::new();
    let mut set_aside = Vec::new();
    for d in dirs {
        let checked = read_record(d).and_then(|r| shard_rows(d, &r).map(|_| r));
        match checked {
            Ok(r) => whole.push((d.clone(), r)),
            Err(e) if crate::error::is_bad_input(&e) => {
                set_aside.push((d.clone(), format!("{e:#}")))
            }
            Err(e) => return Err(e),
        }
    }
    let Some((first_dir, first)) = whole.first().cloned() else {
        crate::bad_input!(
            "none of the {} folder(s) given is a whole shard, so the split N is unknown: rerun every shard",
            dirs.len()
        );
    };
    for (d, r) in &whole[1..] {
        if r.study != first.study || r.base != first.base || r.runs != first.runs {
            crate::bad_input!(
                "{} and {} are outputs of different studies: refusing to list their missing shards",
                first_dir.display(),
                d.display()
            );
        }
    }
    let Some(n) = common_split(whole.iter().map(|(_, r)| r)) else {
        crate::bad_input!(
            "{}: the outputs given are not all shards K/N of one N (a whole-study output, or shards of different splits): cannot list missing shards",
            first_dir.display()
        );
    };
    let present: std::collections::BTreeSet<u64> = whole
        .iter()
        .filter_map(|(_, r)| r.shard.map(|[k, _]| k))
        .collect();
    Ok(Missing {
        n,
        missing: (0..n).filter(|k| !present.contains(k)).collect(),
        set_aside,
    })
}

/// Joins shard outputs into one results.csv (rows in run order), refusing
/// shards of different studies, overlaps and gaps, and rows that are not
/// exactly those the shards' study.json promise. Returns the runs written.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<u64> {
    if dirs.is_empty() {
        crate::bad_input!("nothing to merge");
    }
    check_distinct(dirs, out)?;
    let mut records = read_records(dirs)?;
    let first = records[0].1.clone();
    records.sort_by_key(|(_, r)| r.range);
    check_coverage(&records, first.runs)?;

    // The rows, each checked, rewritten through one writer (the bytes a
    // whole run writes).
    let head = header(first.study.columns(), first.axis);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&head)?;
    let mut written = 0u64;
    for (d, r) in &records {
        for rec in shard_rows(d, r)? {
            w.write_record(&rec)?;
            written += 1;
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

/// No directory given twice (by whatever spelling), and `out` none of
/// them.
fn check_distinct(dirs: &[PathBuf], out: &Path) -> Result<()> {
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
    Ok(())
}

/// Each directory's study.json, in the order given; all of one study,
/// written by one version.
fn read_records(dirs: &[PathBuf]) -> Result<Vec<(PathBuf, StudyRecord)>> {
    let mut records: Vec<(PathBuf, StudyRecord)> = Vec::new();
    for d in dirs {
        records.push((d.clone(), read_record(d)?));
    }
    let (first_dir, first) = &records[0];
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
    Ok(records)
}

/// The records' ranges, in order, cover runs 0..`runs` once: no gap (named
/// as the missing shard when the split is known) and no overlap.
fn check_coverage(records: &[(PathBuf, StudyRecord)], runs: u64) -> Result<()> {
    let split = common_split(records.iter().map(|(_, r)| r));
    let mut next = 0u64;
    let mut prev: Option<&Path> = None;
    for (d, r) in records {
        let [lo, hi] = r.range;
        if lo > next {
            crate::bad_input!(
                "{}",
                missing_message(runs, split, next, lo, &format!("before {}", d.display()))
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
    if next != runs {
        crate::bad_input!(
            "{}",
            missing_message(
                runs,
                split,
                next,
                runs,
                &format!(
                    "after {}",
                    prev.map_or_else(|| "?".into(), |p| p.display().to_string())
                )
            )
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_lists_are_slurm_arrays() {
        assert_eq!(index_list(&[]), "");
        assert_eq!(index_list(&[3]), "3");
        assert_eq!(index_list(&[1, 2]), "1,2");
        assert_eq!(index_list(&[0, 2, 5, 6, 7, 8, 9]), "0,2,5-9");
        assert_eq!(index_list(&[1, 2, 3, 7, 8, 10]), "1-3,7,8,10");
    }

    #[test]
    fn gaps_of_whole_shards_are_named_as_shards() {
        // 10 runs in 4 shards: 0..2, 2..5, 5..7, 7..10.
        let m = missing_message(10, Some(4), 2, 5, "before x");
        assert_eq!(
            m,
            "shard 1/4 (runs 2..5) is missing (before x): rerun it with --shard 1/4"
        );
        let m = missing_message(10, Some(4), 5, 10, "after y");
        assert!(
            m.starts_with("shards K/4 for K in 2,3 (runs 5..10) are missing (after y)"),
            "{m}"
        );
        // Not a split of whole shards, or no common split: runs only.
        assert_eq!(
            missing_message(10, Some(4), 3, 5, "before x"),
            "runs 3..5 are missing (before x): a shard is absent"
        );
        assert_eq!(
            missing_message(10, None, 2, 5, "before x"),
            "runs 2..5 are missing (before x): a shard is absent"
        );
    }
}
