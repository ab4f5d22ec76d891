//! Keys, positions and overrides: `--set key.path=value` on a TOML
//! document, and the line and column of a key in the text it came from.

use ehservo_sim::error::KeyError;

/// 1-based line and column of a byte offset in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rsplit('\n')
        .next()
        .map(|l| l.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}

/// Line and column of the value of `key` (a dotted path) in `text`, when
/// the file sets it (a default has no position).
pub(crate) fn locate(text: &str, key: &str) -> Option<(usize, usize)> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut segs = key.split('.');
    let first = segs.next()?;
    let mut cur = root
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == first)
        .map(|(_, v)| v)?;
    for seg in segs {
        cur = cur.get_ref().get(seg)?;
    }
    Some(line_col(text, cur.span().start))
}

/// Strips toml's own location prefix and snippet from a message.
pub(crate) fn first_line(msg: &str) -> String {
    msg.lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or(msg)
        .trim()
        .to_string()
}

/// serde_path_to_error writes `?` for the root and `a.b` for fields.
pub(crate) fn clean_path(p: &str) -> String {
    if p == "." || p == "?" {
        String::new()
    } else {
        p.to_string()
    }
}

/// Reads the value of a `key.path=value` override as a TOML value (`200`,
/// `1e-3`, `true`, `[1, 2, 3]`, `"text"`); a bare word that is not TOML
/// (`vsc`, `continuous`) is taken as a string.
pub fn parse_value(raw: &str) -> toml::Value {
    let raw = raw.trim();
    match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// Deepest key path accepted by [`set_path`].
pub const MAX_KEY_DEPTH: usize = 8;

/// Sets `path` (dotted) to `value` in a TOML document, creating tables on
/// the way. Errors name the path and the reason.
pub fn set_path(table: &mut toml::Table, path: &str, value: toml::Value) -> Result<(), KeyError> {
    let path = path.trim();
    if path.is_empty() || path.split('.').any(|p| p.trim().is_empty()) {
        return Err(KeyError::new(path, "empty key in key.path=value"));
    }
    let parts: Vec<&str> = path.split('.').map(str::trim).collect();
    // No scenario or study key is deeper than four levels; a deep path
    // would only build deeply nested tables (and recursion) for nothing.
    if parts.len() > MAX_KEY_DEPTH {
        return Err(KeyError::new(
            format!("{}…", parts[..MAX_KEY_DEPTH].join(".")),
            format!(
                "a key path of {} levels: no key is deeper than {MAX_KEY_DEPTH}",
                parts.len()
            ),
        ));
    }
    let mut cur = table;
    for (i, part) in parts.iter().enumerate() {
        if i + 1 == parts.len() {
            cur.insert(part.to_string(), value);
            return Ok(());
        }
        let entry = cur
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err(KeyError::new(
                    parts[..=i].join("."),
                    "is a value, not a table: cannot set a key below it",
                ))
            }
        };
    }
    Ok(())
}

/// Applies one `key.path=value` to a TOML document.
pub fn apply_override(table: &mut toml::Table, spec: &str) -> Result<(), KeyError> {
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| KeyError::new(spec, "expected key.path=value"))?;
    set_path(table, path, parse_value(raw))
}
