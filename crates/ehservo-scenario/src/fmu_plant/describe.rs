//! An FMU's archive unpacked and its `modelDescription.xml` read: the FMI
//! version, the instantiation token, the co-simulation and model-exchange
//! model identifiers, and every variable's name, value reference, type,
//! causality and unit (the variable's own `unit`, else its declared
//! type's).
//!
//! Read with `xmlparser` (a tokenizer) rather than the `fmi` crate's
//! schema: `fmi-schema` 0.8.0 declares `Float64` without FMI 3.0's
//! `quantity`, `unit`, `displayUnit` and `nominal` attributes and parses
//! strictly, so it refuses the very units this import reads (and every
//! FMU that states them), and `fmi` itself generates its C bindings with
//! bindgen, which needs a libclang that neither this machine nor CI has.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Largest FMU archive read: 1 GiB (bounded as every input is).
const MAX_ARCHIVE: u64 = 1 << 30;
/// Largest `modelDescription.xml` read: 16 MiB.
const MAX_DESCRIPTION: u64 = 16 << 20;

/// One variable of `modelDescription.xml`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Variable {
    pub name: String,
    pub value_reference: u32,
    /// The element's name: `Float64`, `Int32`, `Boolean`, …
    pub ty: String,
    /// `input`, `output`, `parameter`, … (`local` when not given).
    pub causality: String,
    /// The unit, if the variable or its declared type states one.
    pub unit: Option<String>,
}

/// What this import reads of `modelDescription.xml`.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Description {
    /// `fmiVersion` ("3.0", "2.0", …).
    pub fmi_version: String,
    /// `instantiationToken` (FMI 3.0) or `guid` (FMI 2.0).
    pub token: String,
    /// `<CoSimulation modelIdentifier=…>`, if the FMU offers it.
    pub co_simulation: Option<String>,
    /// `<ModelExchange modelIdentifier=…>`, if the FMU offers it.
    pub model_exchange: Option<String>,
    pub variables: Vec<Variable>,
}

impl Description {
    /// The variable named `name`.
    pub fn find(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

/// `&quot;` and its kin back to text (names and units rarely hold them).
fn unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Reads the XML text of a model description; the error is the reason.
pub(crate) fn parse(xml: &str) -> Result<Description, String> {
    let mut d = Description::default();
    let mut types: HashMap<String, String> = HashMap::new();
    let mut stack: Vec<String> = Vec::new();
    let mut attrs: HashMap<String, String> = HashMap::new();
    let mut pending: Option<String> = None;
    let mut root_seen = false;
    // FMI 2.0's `<SimpleType name=…>`, whose `<Real unit=…/>` follows.
    let mut simple_type = String::new();
    for token in xmlparser::Tokenizer::from(xml) {
        let token = token.map_err(|e| format!("modelDescription.xml is not XML: {e}"))?;
        match token {
            xmlparser::Token::ElementStart { local, .. } => {
                pending = Some(local.as_str().to_string());
                attrs.clear();
            }
            xmlparser::Token::Attribute { local, value, .. } => {
                attrs.insert(local.as_str().to_string(), unescape(value.as_str()));
            }
            xmlparser::Token::ElementEnd { end, .. } => {
                if let Some(name) = pending.take() {
                    let parent = stack.last().map(String::as_str).unwrap_or("");
                    root_seen |= name == "fmiModelDescription";
                    if name == "SimpleType" {
                        simple_type = attrs.get("name").cloned().unwrap_or_default();
                    }
                    element(&mut d, &mut types, (parent, &simple_type), &name, &attrs)?;
                    if matches!(end, xmlparser::ElementEnd::Open) {
                        stack.push(name);
                    }
                } else if matches!(end, xmlparser::ElementEnd::Close(..)) {
                    stack.pop();
                }
            }
            _ => {}
        }
    }
    if !root_seen {
        return Err("modelDescription.xml has no <fmiModelDescription> element".into());
    }
    Ok(d)
}

/// One element with its attributes, under `parent`.
fn element(
    d: &mut Description,
    types: &mut HashMap<String, String>,
    (parent, simple_type): (&str, &str),
    name: &str,
    a: &HashMap<String, String>,
) -> Result<(), String> {
    let get = |k: &str| a.get(k).cloned();
    match (parent, name) {
        // FMI 2.0: `<SimpleType name="T"><Real unit="m"/></SimpleType>`.
        ("SimpleType", "Real") => {
            if let Some(u) = get("unit") {
                types.insert(simple_type.to_string(), u);
            }
        }
        // FMI 2.0: `<ScalarVariable …><Real unit=… declaredType=…/>`, the
        // type and unit of the variable just read.
        ("ScalarVariable", ty) => {
            if let Some(v) = d.variables.last_mut() {
                v.ty = if ty == "Real" {
                    "Float64".into()
                } else {
                    ty.into()
                };
                v.unit = get("unit")
                    .or_else(|| get("declaredType").and_then(|t| types.get(&t).cloned()));
            }
        }
        (_, "fmiModelDescription") => {
            d.fmi_version = get("fmiVersion").unwrap_or_default();
            d.token = get("instantiationToken")
                .or(get("guid"))
                .unwrap_or_default();
        }
        ("fmiModelDescription", "CoSimulation") => d.co_simulation = get("modelIdentifier"),
        ("fmiModelDescription", "ModelExchange") => d.model_exchange = get("modelIdentifier"),
        // A type is declared before the variables that use it
        // (`<TypeDefinitions>` precedes `<ModelVariables>`).
        ("TypeDefinitions", _) => {
            if let (Some(n), Some(u)) = (get("name"), get("unit")) {
                types.insert(n, u);
            }
        }
        ("ModelVariables", ty) => {
            let name = get("name").ok_or_else(|| format!("a <{ty}> variable has no name"))?;
            let vr = get("valueReference")
                .and_then(|v| v.trim().parse::<u32>().ok())
                .ok_or_else(|| format!("variable {name:?} has no valid valueReference"))?;
            let unit =
                get("unit").or_else(|| get("declaredType").and_then(|t| types.get(&t).cloned()));
            d.variables.push(Variable {
                name,
                value_reference: vr,
                ty: ty.to_string(),
                causality: get("causality").unwrap_or_else(|| "local".into()),
                unit,
            });
        }
        _ => {}
    }
    Ok(())
}

/// An FMU unpacked into a directory of its own (removed when dropped),
/// with its description read.
#[derive(Debug)]
pub(crate) struct Unpacked {
    pub dir: tempfile::TempDir,
    pub description: Description,
}

impl Unpacked {
    /// The `resources/` directory, as FMI 3.0 hands it to an instance
    /// (absolute, with a trailing separator).
    pub fn resources(&self) -> String {
        let mut s = self.dir.path().join("resources").display().to_string();
        s.push(std::path::MAIN_SEPARATOR);
        s
    }

    /// The binary of `model_identifier` for this platform, if the FMU has
    /// it: `binaries/<arch>-<os>/<id>.<so|dylib|dll>` in FMI 3.0,
    /// `binaries/<os><32|64>/…` in FMI 2.0.
    pub fn binary(&self, model_identifier: &str) -> Result<PathBuf, String> {
        let os = match std::env::consts::OS {
            "macos" => "darwin",
            "windows" => "win",
            o => o,
        };
        let platform = if self.description.fmi_version.starts_with("2.") {
            format!("{os}{}", usize::BITS)
        } else {
            let os = if os == "win" { "windows" } else { os };
            format!("{}-{os}", std::env::consts::ARCH)
        };
        let file = format!("{model_identifier}.{}", std::env::consts::DLL_EXTENSION);
        let p = self.dir.path().join("binaries").join(&platform).join(&file);
        if p.is_file() {
            Ok(p)
        } else {
            Err(format!(
                "has no binary for this platform (binaries/{platform}/{file})"
            ))
        }
    }
}

/// Opens the FMU at `path`, a zip archive, and reads its
/// `modelDescription.xml`. The error is the reason, to follow the file's
/// name.
fn open(path: &Path) -> Result<(zip::ZipArchive<std::fs::File>, Description), String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot be read ({e})"))?;
    if !meta.is_file() {
        return Err("is not a regular file".into());
    }
    if meta.len() > MAX_ARCHIVE {
        return Err(format!("is larger than {MAX_ARCHIVE} bytes"));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read ({e})"))?;
    let mut zip = zip::ZipArchive::new(file)
        .map_err(|e| format!("is not a zip archive (an FMU is one): {e}"))?;
    let xml = {
        let entry = zip
            .by_name("modelDescription.xml")
            .map_err(|_| "holds no modelDescription.xml".to_string())?;
        if entry.size() > MAX_DESCRIPTION {
            return Err("has a modelDescription.xml larger than 16 MiB".into());
        }
        let mut text = String::new();
        std::io::Read::read_to_string(&mut std::io::Read::take(entry, MAX_DESCRIPTION), &mut text)
            .map_err(|e| format!("has an unreadable modelDescription.xml ({e})"))?;
        text
    };
    let description = parse(&xml)?;
    Ok((zip, description))
}

/// The description of the FMU at `path`, without unpacking the rest.
pub(crate) fn peek(path: &Path) -> Result<Description, String> {
    open(path).map(|(_, d)| d)
}

/// The FMU at `path` unpacked into a temporary directory of its own.
pub(crate) fn unpack(path: &Path) -> Result<Unpacked, String> {
    let (mut zip, description) = open(path)?;
    let dir = tempfile::Builder::new()
        .prefix("ehservo-fmu-")
        .tempdir()
        .map_err(|e| format!("cannot be unpacked (temporary directory: {e})"))?;
    // `extract` keeps every entry inside `dir` (it refuses names that
    // would leave it).
    zip.extract(dir.path())
        .map_err(|e| format!("cannot be unpacked ({e})"))?;
    Ok(Unpacked { dir, description })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_variables_with_their_own_or_their_types_unit() {
        let xml = r#"<?xml version="1.0"?>
<fmiModelDescription fmiVersion="3.0" modelName="m" instantiationToken="{tok}">
  <CoSimulation modelIdentifier="servo"/>
  <TypeDefinitions><Float64Type name="Angle" unit="rad"/></TypeDefinitions>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent"/>
    <Float64 name="u" valueReference="1" causality="input" unit="V"/>
    <Float64 name="theta" valueReference="2" causality="output" declaredType="Angle"/>
    <Int32 name="n" valueReference="3" causality="parameter"/>
  </ModelVariables>
</fmiModelDescription>"#;
        let d = parse(xml).unwrap();
        assert_eq!((d.fmi_version.as_str(), d.token.as_str()), ("3.0", "{tok}"));
        assert_eq!(d.co_simulation.as_deref(), Some("servo"));
        assert_eq!(d.model_exchange, None);
        let theta = d.find("theta").unwrap();
        assert_eq!(
            (theta.value_reference, theta.unit.as_deref()),
            (2, Some("rad"))
        );
        assert_eq!(d.find("u").unwrap().unit.as_deref(), Some("V"));
        let n = d.find("n").unwrap();
        assert_eq!(
            (n.ty.as_str(), n.causality.as_str()),
            ("Int32", "parameter")
        );
        assert_eq!(d.find("time").unwrap().unit, None);
    }

    #[test]
    fn reads_an_fmi2_description_with_its_simple_types() {
        let xml = r#"<fmiModelDescription fmiVersion="2.0" modelName="m" guid="{g}">
  <CoSimulation modelIdentifier="servo"/>
  <TypeDefinitions><SimpleType name="Length"><Real unit="m"/></SimpleType></TypeDefinitions>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="0" causality="input"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="x" valueReference="1" causality="output"><Real declaredType="Length"/></ScalarVariable>
    <ScalarVariable name="v" valueReference="2" causality="output"><Real unit="m/s"/></ScalarVariable>
    <ScalarVariable name="n" valueReference="3" causality="parameter"><Integer start="1"/></ScalarVariable>
  </ModelVariables>
</fmiModelDescription>"#;
        let d = parse(xml).unwrap();
        assert_eq!((d.fmi_version.as_str(), d.token.as_str()), ("2.0", "{g}"));
        let x = d.find("x").unwrap();
        assert_eq!(
            (x.ty.as_str(), x.unit.as_deref(), x.value_reference),
            ("Float64", Some("m"), 1)
        );
        assert_eq!(d.find("v").unwrap().unit.as_deref(), Some("m/s"));
        assert_eq!(d.find("u").unwrap().unit, None);
        assert_eq!(d.find("n").unwrap().ty, "Integer");
    }

    #[test]
    fn a_file_without_the_root_element_or_not_xml_is_refused() {
        assert!(parse("<other/>")
            .unwrap_err()
            .contains("fmiModelDescription"));
        assert!(parse("<fmiModelDescription <")
            .unwrap_err()
            .contains("not XML"));
    }
}
