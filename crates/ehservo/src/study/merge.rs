//! Joining the outputs of shards into one.

use super::StudyRecord;
use crate::output::{write_atomic, Staging};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Joins shard outputs into one results.csv (rows in run order), refusing
/// shards of different studies, overlaps and gaps.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<u64> {
    if dirs.is_empty() {
        crate::bad_input!("nothing to merge");
    }
    let mut records: Vec<(PathBuf, StudyRecord)> = Vec::new();
    for d in dirs {
        let p = d.join("study.json");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let r: StudyRecord =
            serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
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
    records.sort_by_key(|(_, r)| r.range[0]);
    let mut next = 0u64;
    for (d, r) in &records {
        if r.range[0] != next {
            crate::bad_input!(
                "runs {}..{} are {} (at {}): shards overlap or one is missing",
                next,
                r.range[0],
                if r.range[0] > next {
                    "missing"
                } else {
                    "duplicated"
                },
                d.display()
            );
        }
        next = r.range[1];
    }
    if next != first.runs {
        crate::bad_input!("runs {next}..{} are missing: a shard is absent", first.runs);
    }
    let mut out_bytes: Vec<u8> = Vec::new();
    let mut header: Option<String> = None;
    for (d, _) in &records {
        let p = d.join("results.csv");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let mut lines = text.split_inclusive('\n');
        let h = lines.next().unwrap_or_default().to_string();
        match &header {
            None => {
                out_bytes.extend_from_slice(h.as_bytes());
                header = Some(h);
            }
            Some(h0) if *h0 != h => crate::bad_input!("{}: a different header", p.display()),
            _ => {}
        }
        for l in lines {
            out_bytes.extend_from_slice(l.as_bytes());
        }
    }
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
    Ok(first.runs)
}
