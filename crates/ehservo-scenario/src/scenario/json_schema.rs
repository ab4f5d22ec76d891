//! The JSON Schema of a `[controller]` and a `[plant]` table: one `oneOf`
//! branch per registered kind or model, chosen by its tag (what
//! `ehservo schema scenario` prints and docs/reference/ is drawn from).

use super::{ControllerCfg, PlantCfg, DEFAULT_KIND, DEFAULT_MODEL};
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde_json::{json, Map, Value};
use std::borrow::Cow;

/// One `oneOf` branch per registered variant: its keys' schema, inlined,
/// with `key = "name"` (optional for the default variant).
fn tagged(
    g: &mut SchemaGenerator,
    key: &str,
    default: &str,
    description: &str,
    variants: Vec<(&'static str, Schema)>,
    default_of: impl Fn(&str) -> Option<toml::Table>,
) -> Schema {
    let defs = g.definitions().clone();
    let branches: Vec<Value> = variants
        .into_iter()
        .map(|(name, s)| {
            let mut b = resolve(&defs, s.as_value());
            let o = b.as_object_mut().expect("a parameter type is a table");
            o.insert("title".into(), format!("{key} = \"{name}\"").into());
            // The variant's `Default`, as it writes its table.
            if let Some(d) = default_of(name).and_then(|t| serde_json::to_value(t).ok()) {
                o.insert("default".into(), d);
            }
            let props = o
                .entry("properties")
                .or_insert_with(|| json!({}))
                .as_object_mut()
                .expect("properties is an object");
            let mut tag = json!({
                "const": name,
                "description": format!("Selects these keys (`{key} = \"{name}\"`)."),
            });
            if name == default {
                tag["default"] = name.into();
                tag["description"] =
                    format!("Selects these keys (`{key} = \"{name}\"`, the default).").into();
            }
            props.insert(key.into(), tag);
            if name != default {
                let req = o.entry("required").or_insert_with(|| json!([]));
                if let Some(r) = req.as_array_mut() {
                    r.insert(0, key.into());
                }
            }
            b
        })
        .collect();
    Schema::try_from(json!({
        "description": description,
        "type": "object",
        "oneOf": branches,
    }))
    .expect("an object")
}

impl JsonSchema for ControllerCfg {
    fn schema_name() -> Cow<'static, str> {
        "ControllerCfg".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let kinds = ControllerCfg::kind_schemas(g);
        tagged(
            g,
            "kind",
            DEFAULT_KIND,
            "Controller: `kind` (default `\"nnvsc\"`) and that kind's parameters.",
            kinds,
            |k| ControllerCfg::default_of(k).map(|c| c.to_table()),
        )
    }
}

impl ControllerCfg {
    /// The keys a kind's `[controller]` table takes (`kind` among them),
    /// from its JSON Schema; `None` for an unregistered kind.
    pub fn keys_of(kind: &str) -> Option<Vec<String>> {
        let mut g = SchemaGenerator::default();
        let (_, s) = Self::kind_schemas(&mut g)
            .into_iter()
            .find(|(name, _)| *name == kind)?;
        let v = resolve(g.definitions(), s.as_value());
        let mut keys: Vec<String> = v
            .get("properties")
            .and_then(Value::as_object)
            .map(|p| p.keys().cloned().collect())
            .unwrap_or_default();
        keys.push("kind".into());
        Some(keys)
    }
}

impl JsonSchema for PlantCfg {
    fn schema_name() -> Cow<'static, str> {
        "PlantCfg".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let models = PlantCfg::model_schemas(g);
        tagged(
            g,
            "model",
            DEFAULT_MODEL,
            "The plant: `model` (default `\"third-order\"`) and that model's keys.",
            models,
            |m| PlantCfg::default_of(m).map(|p| p.to_table()),
        )
    }
}

/// `s` with its `$ref`s (and one-element `allOf`s) replaced by what they
/// name, recursively at the top only; the wrapper's own keys (a field's
/// description, default) win.
pub fn resolve(defs: &Map<String, Value>, s: &Value) -> Value {
    let Some(o) = s.as_object() else {
        return s.clone();
    };
    let inner = if let Some(r) = o.get("$ref").and_then(Value::as_str) {
        let name = r.rsplit('/').next().unwrap_or(r);
        defs.get(name).map(|d| resolve(defs, d))
    } else {
        match o.get("allOf").and_then(Value::as_array) {
            Some(a) if a.len() == 1 => Some(resolve(defs, &a[0])),
            _ => None,
        }
    };
    let Some(mut inner) = inner else {
        return s.clone();
    };
    if let Some(io) = inner.as_object_mut() {
        for (k, v) in o {
            if k != "$ref" && k != "allOf" {
                io.insert(k.clone(), v.clone());
            }
        }
    }
    inner
}
