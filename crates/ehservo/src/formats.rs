//! The lab's TOML files told apart: a scenario, a study, a tune file, a
//! league suite and the reproduction's manifest each have top-level keys
//! the others do not. A scenario given where another file belongs (or the
//! other way round) is named with the command that takes it, instead of
//! serde's "unknown field `axis`". The scenario crate knows only scenarios;
//! the lab adds these hints when it loads one ([`load`], [`parse_in`]).

use crate::scenario::{Loop, Reason, ScenarioError};
use std::path::Path;

/// [`Loop::load`], with the hint of [`other_format`] when the file is
/// another of the lab's files. What the `--set`s did that the user should
/// know of (the keys a `--set controller.kind=K` dropped) is printed on
/// stderr, one line each, `note: FILE: …`.
pub fn load(path: &Path, set: &[String]) -> Result<Loop, ScenarioError> {
    let lp = load_quiet(path, set)?;
    for n in &lp.scenario().notes {
        eprintln!("note: {}: {n}", path.display());
    }
    Ok(lp)
}

/// [`load`] without printing its notes.
fn load_quiet(path: &Path, set: &[String]) -> Result<Loop, ScenarioError> {
    Loop::load(path, set).map_err(|e| {
        let file = path.display().to_string();
        match crate::input::read_text(path)
            .ok()
            .and_then(|text| other_format(&text, &file))
        {
            Some(hint) => hinted(file, hint),
            None => e,
        }
    })
}

/// [`Loop::parse_in`], with the hint of [`other_format`].
pub fn parse_in(
    text: &str,
    file: &str,
    set: &[String],
    base_dir: Option<std::path::PathBuf>,
) -> Result<Loop, ScenarioError> {
    Loop::parse_in(text, file, set, base_dir).map_err(|e| match other_format(text, file) {
        Some(hint) => hinted(file.to_string(), hint),
        None => e,
    })
}

fn hinted(file: String, hint: String) -> ScenarioError {
    ScenarioError {
        file,
        key: String::new(),
        line_col: None,
        reason: Reason::Other(hint),
    }
}

/// What a TOML file that does not read as a scenario is instead, from its
/// top-level keys (which a scenario never has), and the command that takes
/// it: the reason `ehservo run` gives for a study, tune, league file or the
/// reproduction's manifest, instead of "unknown field `axis`".
pub fn other_format(text: &str, file: &str) -> Option<String> {
    let t: toml::Table = toml::from_str(text).ok()?;
    let has = |k: &str| t.contains_key(k);
    let (what, key, command) =
        if let Some(k) = ["axis", "monte_carlo", "base"].into_iter().find(|k| has(k)) {
            ("a study", k, "ehservo sweep FILE --out DIR")
        } else if let Some(k) = ["tuning", "margin", "scenario"]
            .into_iter()
            .find(|k| has(k))
            .or_else(|| {
                t.get("controller")
                    .filter(|c| c.is_array())
                    .map(|_| "controller")
            })
        {
            ("a league suite", k, "ehservo league FILE --out DIR")
        } else if let Some(k) = ["scenarios", "budget", "particles", "penalty", "param"]
            .into_iter()
            .find(|k| has(k))
            .or_else(|| {
                t.get("controller")
                    .filter(|c| c.is_str())
                    .map(|_| "controller")
            })
        {
            ("a tune file", k, "ehservo tune FILE --out DIR")
        } else if let Some(k) = ["reading", "case", "claim", "convergence"]
            .into_iter()
            .find(|k| has(k))
        {
            (
                "the reproduction's manifest",
                k,
                "ehservo reproduce --paper-dir ITS-FOLDER",
            )
        } else {
            return None;
        };
    let shown = match t.get(key) {
        Some(toml::Value::Array(a)) if a.iter().all(toml::Value::is_table) => format!("[[{key}]]"),
        Some(toml::Value::Table(_)) => format!("[{key}]"),
        _ => format!("`{key}`"),
    };
    Some(format!(
        "this is {what} (it has {shown}), not a scenario: run it with `{}`",
        command.replace("FILE", file)
    ))
}
