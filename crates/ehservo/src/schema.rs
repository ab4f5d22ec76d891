//! JSON Schemas of the file formats (scenario, study, tune, league) and
//! their reference pages, both generated from the serde types and their
//! doc comments: `ehservo schema [--markdown] FORMAT`.
//!
//! The schemas are draft-07 (what taplo and the common TOML editor
//! plugins read). A `[controller]` table is one of the registered kinds,
//! chosen by its `kind` (`oneOf`, each branch with `kind` as a `const`; the
//! default kind's branch without `kind` required), and a `[plant]` table one
//! of the registered models by its `model`. TOML has no null, so the
//! `Option`s of the types are written as their values alone. The reference
//! pages (docs/reference/*.md) are drawn from the same schemas: every key
//! with its type, unit (from its doc comment), default (the types'
//! `Default`, serialised) and doc.

use crate::output::escape::{md_cell, md_code};
use crate::scenario::json_schema::resolve;
use crate::scenario::{ControllerCfg, Scenario};
use schemars::generate::SchemaSettings;
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde_json::{json, Map, Value};
use std::borrow::Cow;
use std::collections::BTreeSet;
use std::fmt::Write as _;

/// A file format with a schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A scenario file (`ehservo run`).
    Scenario,
    /// A study file (`ehservo sweep`).
    Study,
    /// A tune file (`ehservo tune`).
    Tune,
    /// A league suite file (`ehservo league`).
    League,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 4] = [Self::Scenario, Self::Study, Self::Tune, Self::League];

    /// Its name, as given to `ehservo schema`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Scenario => "scenario",
            Self::Study => "study",
            Self::Tune => "tune",
            Self::League => "league",
        }
    }

    /// The committed schema's file name under docs/reference/.
    pub fn schema_file(self) -> String {
        format!("{}.schema.json", self.name())
    }

    /// The committed reference page's file name under docs/reference/.
    pub fn page_file(self) -> String {
        format!("{}.md", self.name())
    }

    fn title(self) -> &'static str {
        match self {
            Self::Scenario => "ehservo scenario file",
            Self::Study => "ehservo study file",
            Self::Tune => "ehservo tune file",
            Self::League => "ehservo league suite file",
        }
    }

    fn command(self) -> &'static str {
        match self {
            Self::Scenario => "ehservo run",
            Self::Study => "ehservo sweep",
            Self::Tune => "ehservo tune",
            Self::League => "ehservo league",
        }
    }
}

/// The JSON Schema of `format`.
pub fn schema(format: Format) -> Value {
    let mut g = SchemaSettings::draft07().into_generator();
    let root = match format {
        Format::Scenario => g.root_schema_for::<Scenario>(),
        Format::Study => g.root_schema_for::<crate::study::Study>(),
        Format::Tune => g.root_schema_for::<crate::tune::TuneFile>(),
        Format::League => g.root_schema_for::<crate::league::SuiteFile>(),
    };
    let mut v = root.to_value();
    strip_null(&mut v);
    prune(&mut v);
    strip_code(&mut v);
    if let Some(o) = v.as_object_mut() {
        o.insert("title".into(), format.title().into());
    }
    v
}

/// Removes the code blocks (a type's runnable rustdoc example) from every
/// description: a schema and its page say what a key means to a user, not
/// how the Rust API is called.
fn strip_code(v: &mut Value) {
    match v {
        Value::Object(o) => {
            for (k, x) in o.iter_mut() {
                match x {
                    Value::String(d) if k == "description" => *d = without_code(d),
                    _ => strip_code(x),
                }
            }
        }
        Value::Array(a) => a.iter_mut().for_each(strip_code),
        _ => {}
    }
}

/// `text` without its Rust code blocks (a fence with no language or
/// `rust`; a `text` block, a formula, stays), and with rustdoc's escaped
/// brackets (`\[6\]`, which keep a citation from reading as a link) as
/// plain brackets.
fn without_code(text: &str) -> String {
    let mut out: Vec<&str> = Vec::new();
    let mut code = false;
    let mut other = false;
    for line in text.lines() {
        let t = line.trim_start();
        if let Some(lang) = t.strip_prefix("```") {
            if code {
                code = false;
                continue;
            }
            if !other && (lang.is_empty() || lang.starts_with("rust")) {
                code = true;
                continue;
            }
            other = !other;
        }
        if !code {
            out.push(line);
        }
    }
    out.join("\n")
        .trim_end()
        .replace("\\[", "[")
        .replace("\\]", "]")
}

/// The schema as the committed file holds it: pretty JSON and a newline.
pub fn schema_text(format: Format) -> String {
    let mut s = serde_json::to_string_pretty(&schema(format)).unwrap_or_default();
    s.push('\n');
    s
}

/// A controller kind's name: one of the registered kinds (a league's
/// `[[controller]] kind`, a tune file's `controller`).
pub fn controller_kind(_: &mut SchemaGenerator) -> Schema {
    schemars::json_schema!({ "type": "string", "enum": ControllerCfg::KINDS })
}

/// A TOML value of any type (a study's listed values).
pub struct TomlValue;

impl JsonSchema for TomlValue {
    fn schema_name() -> Cow<'static, str> {
        "TomlValue".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        schemars::json_schema!({ "description": "Any TOML value." })
    }
}

/// A TOML table of any keys (a league controller's `params`).
pub struct TomlTable;

impl JsonSchema for TomlTable {
    fn schema_name() -> Cow<'static, str> {
        "TomlTable".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        schemars::json_schema!({ "type": "object" })
    }
}

/// Removes `null` from every type list and `anyOf`, and null defaults:
/// TOML has no null (an `Option` is a key left out).
fn strip_null(v: &mut Value) {
    match v {
        Value::Object(o) => {
            if let Some(Value::Array(types)) = o.get_mut("type") {
                types.retain(|t| t != "null");
                if types.len() == 1 {
                    let t = types[0].clone();
                    o.insert("type".into(), t);
                }
            }
            if o.get("default").is_some_and(Value::is_null) {
                o.remove("default");
            }
            for key in ["anyOf", "oneOf"] {
                let single = if let Some(Value::Array(a)) = o.get_mut(key) {
                    a.retain(|s| s.get("type").is_none_or(|t| t != "null"));
                    (a.len() == 1).then(|| a[0].clone())
                } else {
                    None
                };
                if let Some(Value::Object(inner)) = single {
                    o.remove(key);
                    for (k, x) in inner {
                        o.entry(k).or_insert(x);
                    }
                }
            }
            for x in o.values_mut() {
                strip_null(x);
            }
        }
        Value::Array(a) => a.iter_mut().for_each(strip_null),
        _ => {}
    }
}

/// Removes the definitions nothing refers to (a controller kind's and a
/// plant model's, inlined in their `oneOf`).
fn prune(root: &mut Value) {
    fn refs(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::Object(o) => {
                if let Some(r) = o.get("$ref").and_then(Value::as_str) {
                    out.push(r.rsplit('/').next().unwrap_or(r).to_string());
                }
                o.values().for_each(|x| refs(x, out));
            }
            Value::Array(a) => a.iter().for_each(|x| refs(x, out)),
            _ => {}
        }
    }
    let Some(defs) = root.get("definitions").and_then(Value::as_object).cloned() else {
        return;
    };
    let mut body = root.clone();
    if let Some(o) = body.as_object_mut() {
        o.remove("definitions");
    }
    let mut todo = Vec::new();
    refs(&body, &mut todo);
    let mut seen = BTreeSet::new();
    while let Some(n) = todo.pop() {
        if seen.insert(n.clone()) {
            if let Some(d) = defs.get(&n) {
                refs(d, &mut todo);
            }
        }
    }
    if let Some(o) = root.get_mut("definitions").and_then(Value::as_object_mut) {
        o.retain(|k, _| seen.contains(k));
    }
}

// ---------------------------------------------------------------------------
// The reference pages.

/// The reference page of `format` (Markdown), drawn from its schema.
pub fn markdown(format: Format) -> String {
    let root = schema(format);
    let defs = root
        .get("definitions")
        .and_then(Value::as_object)
        .cloned()
        .unwrap_or_default();
    let mut page = Page {
        defs: &defs,
        out: String::new(),
    };
    let name = format.name();
    let _ = write!(
        page.out,
        "# The {name} file\n\n\
         <!-- Generated by `ehservo schema --markdown {name}` from the serde types and their \
         doc comments (EHSERVO_BLESS=1 cargo test -p ehservo --test it schema); do not edit. -->\n\n\
         The keys of a {name} file (TOML, read by `{cmd}`), with their type, unit, default and \
         meaning. Its JSON Schema is [{file}]({file}) (`ehservo schema {name}`); a file whose first \
         line is `#:schema` and the schema's path gets completion and checking in editors that \
         read it (taplo, Even Better TOML). A key marked *required* must be given; `—` as a \
         default means that leaving the key out has the meaning its description gives. Units are \
         those named in the descriptions.\n",
        cmd = format.command(),
        file = format.schema_file(),
    );
    if let Some(d) = root.get("description").and_then(Value::as_str) {
        let _ = write!(page.out, "\n{d}\n");
    }
    page.table(&root, "", 2, &Value::Null);
    if format == Format::Tune {
        declared_tunables(&mut page.out);
    }
    page.out
}

/// The tune page's table of every kind's declared tunables
/// (`Config::TUNABLE`), in registry order.
fn declared_tunables(out: &mut String) {
    let _ = write!(
        out,
        "\n## What each kind searches by default\n\n\
         Without `[[param]]`, a tune searches the kind's declared tunables over these ranges \
         (`Config::TUNABLE`; a log scale searches log10 of the value). Units are those of the \
         key in [scenario.md](scenario.md) `[controller]`, on the axis of the scenarios \
         (rad or m).\n\n| kind | key | low | high | scale |\n|---|---|---|---|---|\n"
    );
    for kind in crate::scenario::ControllerCfg::KINDS {
        let list = crate::tune::declared(kind).unwrap_or(&[]);
        if list.is_empty() {
            let _ = writeln!(out, "| `{kind}` | — (nothing to tune) | | | |");
        }
        for t in list {
            let _ = writeln!(
                out,
                "| `{kind}` | `{}` | {} | {} | {} |",
                t.key,
                t.low,
                t.high,
                if t.log { "log" } else { "linear" }
            );
        }
    }
}

struct Page<'a> {
    defs: &'a Map<String, Value>,
    out: String,
}

/// How a key's value reads: a table (a section), a list of tables, a
/// choice of tables by a tag, or a plain value (a row).
enum Shape {
    Table(Value),
    TableList(Value),
    Tagged(Value),
    Plain(Value),
}

impl Page<'_> {
    fn resolve(&self, s: &Value) -> Value {
        resolve(self.defs, s)
    }

    /// A section's text: its key's doc, then its type's when that says
    /// more.
    fn section_doc(&self, field: &Value) -> Option<String> {
        let mut bare = field.clone();
        if let Some(o) = bare.as_object_mut() {
            o.remove("description");
            o.remove("title");
        }
        let of_type = description(&self.resolve(&bare)).filter(|d| !names_only(d));
        let of_key = field
            .get("description")
            .and_then(Value::as_str)
            .filter(|d| !names_only(d));
        match (of_key, of_type) {
            (Some(k), Some(t)) if t.contains(k.trim_end_matches('.')) => Some(t),
            (Some(k), Some(t)) if k.contains(t.trim_end_matches('.')) => Some(k.to_string()),
            (Some(k), Some(t)) => Some(format!("{k}\n\n{t}")),
            (Some(k), None) => Some(k.to_string()),
            (None, t) => t,
        }
    }

    fn shape(&self, s: &Value) -> Shape {
        let s = self.resolve(s);
        if s.get("properties").is_some() {
            return Shape::Table(s);
        }
        if let Some(branches) = s.get("oneOf").and_then(Value::as_array) {
            let all_tables = branches
                .iter()
                .all(|b| self.resolve(b).get("properties").is_some());
            if all_tables && tag_of(&self.resolve(&branches[0])).is_some() {
                return Shape::Tagged(s);
            }
        }
        if s.get("type") == Some(&json!("array")) {
            if let Some(items) = s.get("items") {
                if self.resolve(items).get("properties").is_some() {
                    return Shape::TableList(s);
                }
            }
        }
        Shape::Plain(s)
    }

    /// The rows of the table `s` (path `path`, e.g. `simulation.`), then
    /// its sub-tables as sections. `outer` is the table's default as its
    /// parent's `Default` writes it: a key without a default of its own
    /// (a generic type's) takes it from there.
    fn table(&mut self, s: &Value, path: &str, level: usize, outer: &Value) {
        let s = self.resolve(s);
        let own = s.get("default").unwrap_or(outer).clone();
        let empty = Map::new();
        let props = s
            .get("properties")
            .and_then(Value::as_object)
            .unwrap_or(&empty);
        let required: BTreeSet<&str> = s
            .get("required")
            .and_then(Value::as_array)
            .map(|r| r.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        let mut rows = Vec::new();
        let mut sections = Vec::new();
        for (key, p) in props {
            match self.shape(p) {
                Shape::Plain(r) => rows.push((key.clone(), r, required.contains(key.as_str()))),
                other => sections.push((key.clone(), other, p.clone())),
            }
        }
        if !rows.is_empty() {
            self.out.push_str(
                "\n| key | type | unit | default | description |\n|---|---|---|---|---|\n",
            );
            for (key, r, req) in rows {
                let desc = description(&r).unwrap_or_default();
                let default = if req {
                    "*required*".to_string()
                } else {
                    r.get("default")
                        .or_else(|| own.get(&key))
                        .map_or("—".into(), |d| md_code(&toml_text(d)))
                };
                let _ = writeln!(
                    self.out,
                    "| `{key}` | {} | {} | {default} | {} |",
                    self.type_text(&r),
                    cell(&unit(&desc).unwrap_or_default()),
                    cell(&desc),
                );
            }
        }
        for (key, shape, field) in sections {
            let full = format!("{path}{key}");
            let hashes = "#".repeat(level.min(6));
            let field_doc = self.section_doc(&field);
            let inner = field
                .get("default")
                .or_else(|| own.get(&key))
                .cloned()
                .unwrap_or(Value::Null);
            match shape {
                Shape::Table(t) => {
                    let _ = write!(self.out, "\n{hashes} `[{full}]`\n");
                    if let Some(d) = field_doc {
                        let _ = write!(self.out, "\n{d}\n");
                    }
                    self.table(&t, &format!("{full}."), level + 1, &inner);
                }
                Shape::TableList(t) => {
                    let _ = write!(self.out, "\n{hashes} `[[{full}]]`\n");
                    if let Some(d) = field_doc {
                        let _ = write!(self.out, "\n{d}\n");
                    }
                    let items = t.get("items").cloned().unwrap_or_default();
                    self.table(&items, &format!("{full}."), level + 1, &Value::Null);
                }
                Shape::Tagged(t) => {
                    let _ = write!(self.out, "\n{hashes} `[{full}]`\n");
                    if let Some(d) = field_doc.or_else(|| description(&t)) {
                        let _ = write!(self.out, "\n{d}\n");
                    }
                    let branches = t.get("oneOf").and_then(Value::as_array).cloned();
                    for b in branches.unwrap_or_default() {
                        let b = self.resolve(&b);
                        let Some((tag, name, default)) = tag_of(&b) else {
                            continue;
                        };
                        let note = if default { " (the default)" } else { "" };
                        let _ = write!(
                            self.out,
                            "\n{hashes}# `[{full}]` {tag} = \"{name}\"{note}\n"
                        );
                        if let Some(d) = description(&b) {
                            let _ = write!(self.out, "\n{d}\n");
                        }
                        self.table(&b, &format!("{full}."), level + 2, &Value::Null);
                    }
                }
                Shape::Plain(_) => {}
            }
        }
    }

    fn type_text(&self, s: &Value) -> String {
        let s = self.resolve(s);
        if let Some(c) = s.get("const") {
            return md_code(&toml_text(c));
        }
        if let Some(e) = s.get("enum").and_then(Value::as_array) {
            return e
                .iter()
                .map(|x| md_code(&toml_text(x)))
                .collect::<Vec<_>>()
                .join(" \\| ");
        }
        for key in ["oneOf", "anyOf"] {
            if let Some(a) = s.get(key).and_then(Value::as_array) {
                let all_const = a.iter().all(|x| self.resolve(x).get("const").is_some());
                return a
                    .iter()
                    .map(|x| self.type_text(x))
                    .collect::<Vec<_>>()
                    .join(if all_const { " \\| " } else { " or " });
            }
        }
        if let Some(props) = s.get("properties").and_then(Value::as_object) {
            let keys: Vec<&str> = props.keys().map(String::as_str).collect();
            return format!("table {{{}}}", keys.join(", "));
        }
        let base = match s.get("type") {
            Some(Value::String(t)) => t.as_str(),
            Some(Value::Array(ts)) => {
                return ts
                    .iter()
                    .filter_map(Value::as_str)
                    .map(type_word)
                    .collect::<Vec<_>>()
                    .join(" or ")
            }
            _ => return "any".into(),
        };
        if base == "array" {
            let item = s
                .get("items")
                .map_or("any".to_string(), |i| self.type_text(i));
            let n = match (s.get("minItems"), s.get("maxItems")) {
                (Some(a), Some(b)) if a == b => format!("{a} × "),
                _ => String::new(),
            };
            return format!("array of {n}{item}");
        }
        let unsigned = s
            .get("minimum")
            .and_then(Value::as_f64)
            .is_some_and(|m| m >= 0.0);
        if base == "integer" && unsigned {
            "integer ≥ 0".into()
        } else {
            type_word(base).to_string()
        }
    }
}

fn type_word(t: &str) -> &str {
    match t {
        "number" => "float",
        "object" => "table",
        other => other,
    }
}

/// The tag of a branch of a tagged choice: its key, name and whether it
/// is the default.
fn tag_of(b: &Value) -> Option<(String, String, bool)> {
    let props = b.get("properties")?.as_object()?;
    props.iter().find_map(|(k, p)| {
        let name = p.get("const")?.as_str()?;
        let default = p.get("default").is_some();
        Some((k.clone(), name.to_string(), default))
    })
}

/// A doc that only names its table (`` `[plant.fluid]`. ``): the heading says it.
fn names_only(d: &str) -> bool {
    let d = d.trim().trim_end_matches('.');
    d.starts_with("`[") && d.ends_with("]`") && !d[1..d.len() - 1].contains('`')
}

/// A schema's title and description as one text.
fn description(s: &Value) -> Option<String> {
    let title = s.get("title").and_then(Value::as_str);
    let desc = s.get("description").and_then(Value::as_str);
    let text = match (title, desc) {
        (Some(t), Some(d)) if !t.contains(" = \"") => format!("{t}\n\n{d}"),
        (Some(t), None) if !t.contains(" = \"") => t.to_string(),
        (_, Some(d)) => d.to_string(),
        _ => return None,
    };
    Some(text)
}

/// A description as one table cell.
fn cell(d: &str) -> String {
    md_cell(&d.split_whitespace().collect::<Vec<_>>().join(" "))
}

/// A JSON value as TOML writes it.
fn toml_text(v: &Value) -> String {
    match toml::Value::try_from(v) {
        Ok(t) => t.to_string(),
        Err(_) => v.to_string(),
    }
}

/// The unit a description names: the first parenthesised group made of
/// unit symbols only (`(s)`, `(V)`, `(rad, rad/s, rad/s²)`, `(m³/s/Pa)`).
pub fn unit(desc: &str) -> Option<String> {
    let mut rest = desc;
    while let Some(open) = rest.find('(') {
        let after = &rest[open + 1..];
        // The group up to its matching close (one level of nesting).
        let mut depth = 1;
        let mut end = None;
        for (i, c) in after.char_indices() {
            match c {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        end = Some(i);
                        break;
                    }
                }
                _ => {}
            }
        }
        let Some(end) = end else { break };
        let group = &after[..end];
        // A unit stands apart: `value(s)` is a plural.
        let apart = rest[..open]
            .chars()
            .next_back()
            .is_none_or(char::is_whitespace);
        if apart && is_unit_list(group) {
            let units = group.split(';').next().unwrap_or_default();
            return Some(units.split_whitespace().collect::<Vec<_>>().join(" "));
        }
        rest = &after[end..];
    }
    None
}

const UNIT_ATOMS: &[&str] = &[
    "s", "ms", "µs", "us", "min", "h", "V", "mV", "A", "mA", "Pa", "kPa", "MPa", "bar", "rad",
    "deg", "°", "Hz", "kHz", "m", "mm", "µm", "um", "cm", "L", "kg", "g", "N", "W", "J", "K",
];

/// `rad, rad/s, rad/s²`, or `deg/s; a rotary axis` (what follows a `;`
/// is a note).
fn is_unit_list(group: &str) -> bool {
    let group = group.split(';').next().unwrap_or_default();
    let pieces: Vec<&str> = group.split(',').map(str::trim).collect();
    !pieces.is_empty() && pieces.iter().all(|p| is_unit(p))
}

/// `rad/s²`, `N·m`, `m³/s/Pa`, `(rad/s³)²·s`, `°/V`, `1/s`: atoms with
/// powers joined by `/`, `·` or `*`.
fn is_unit(p: &str) -> bool {
    if p.is_empty() {
        return false;
    }
    let cleaned: String = p
        .chars()
        .map(|c| match c {
            '(' | ')' | '²' | '³' | '⁻' | '¹' | '^' | '2' | '3' => ' ',
            '/' | '·' | '*' => '|',
            c => c,
        })
        .collect();
    let mut atoms = 0;
    for atom in cleaned.split('|').map(str::trim) {
        if atom.is_empty() || atom == "1" {
            continue;
        }
        if !UNIT_ATOMS.contains(&atom) {
            return false;
        }
        atoms += 1;
    }
    atoms > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_are_read_from_descriptions() {
        assert_eq!(unit("Horizon T (s), a whole number").as_deref(), Some("s"));
        assert_eq!(
            unit("Offset (rad, rad/s, rad/s²). Default 0.").as_deref(),
            Some("rad, rad/s, rad/s²")
        );
        assert_eq!(
            unit("Intensity q ((rad/s³)²·s).").as_deref(),
            Some("(rad/s³)²·s")
        );
        assert_eq!(unit("Weight (°/V) on u_max").as_deref(), Some("°/V"));
        assert_eq!(unit("Offset (deg; a rotary axis).").as_deref(), Some("deg"));
        assert_eq!(unit("Slope (m/s; a\n linear axis)").as_deref(), Some("m/s"));
        assert_eq!(unit("Some value(s) of (s)").as_deref(), Some("s"));
        assert_eq!(unit("Coefficients (p1, p2, p3) of (10)."), None);
        assert_eq!(unit("Which channels (default all)."), None);
        assert_eq!(unit("The mass (kg) of (10)").as_deref(), Some("kg"));
    }
}
