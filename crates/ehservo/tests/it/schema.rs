//! The JSON Schemas and reference pages of the file formats
//! (docs/reference/), and the shipped files against them.
//!
//! The committed schemas and pages must be what `ehservo schema` prints
//! today (regenerate with `EHSERVO_BLESS=1 cargo test -p ehservo --test it
//! schema`); every shipped file under scenarios/ starts with the `#:schema`
//! line of its format, and validates against that schema (the `jsonschema`
//! crate, draft 7); and the schemas agree with the serde types on files
//! that the types refuse for reasons a schema can express.

use crate::common::{ehservo, repo};
use ehservo::scenario::{ControllerCfg, PlantCfg, Scenario};
use ehservo::schema::{markdown, schema, schema_text, Format};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn reference_dir() -> PathBuf {
    repo().join("docs/reference")
}

/// The committed file `name` is `want`, or (EHSERVO_BLESS=1) is made so.
fn fresh(name: &str, want: &str) -> Option<String> {
    let path = reference_dir().join(name);
    if std::env::var_os("EHSERVO_BLESS").is_some_and(|v| v == "1") {
        std::fs::create_dir_all(reference_dir()).unwrap();
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, want).unwrap();
        std::fs::rename(&tmp, &path).unwrap();
        return None;
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    (have != want).then(|| format!("docs/reference/{name}"))
}

#[test]
fn committed_schemas_and_pages_are_fresh() {
    let mut stale = Vec::new();
    for f in Format::ALL {
        stale.extend(fresh(&f.schema_file(), &schema_text(f)));
        stale.extend(fresh(&f.page_file(), &markdown(f)));
    }
    assert!(
        stale.is_empty(),
        "stale (regenerate with EHSERVO_BLESS=1 cargo test -p ehservo --test it schema): {stale:?}"
    );
}

#[test]
fn the_command_prints_them() {
    let o = ehservo().args(["schema", "study"]).output().unwrap();
    assert!(o.status.success());
    assert_eq!(
        String::from_utf8(o.stdout).unwrap(),
        schema_text(Format::Study)
    );
    let o = ehservo()
        .args(["schema", "--markdown", "league"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert_eq!(
        String::from_utf8(o.stdout).unwrap(),
        markdown(Format::League)
    );
    let o = ehservo().args(["schema", "manifest"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("manifest") && err.contains("scenario"),
        "{err}"
    );
}

/// The format of a shipped file by what it holds (not by its `#:schema`
/// line): a study names a `base`, a tune file its `scenarios`, a suite
/// its `[[controller]]`s and `[tuning]`; None for a reproduction manifest,
/// which has no schema.
fn format_of(path: &Path, t: &toml::Table) -> Option<Format> {
    if t.contains_key("case") || t.contains_key("claim") || t.contains_key("reading") {
        return None;
    }
    if t.contains_key("base") {
        Some(Format::Study)
    } else if t.contains_key("tuning") || t.get("controller").is_some_and(|c| c.is_array()) {
        Some(Format::League)
    } else if t.contains_key("scenarios") {
        Some(Format::Tune)
    } else {
        assert!(!path.ends_with("manifest.toml"), "{}", path.display());
        Some(Format::Scenario)
    }
}

fn shipped() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "toml") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&repo().join("scenarios"), &mut out);
    out.sort();
    assert!(out.len() >= 50, "found only {} shipped files", out.len());
    out
}

fn validator(f: Format) -> jsonschema::Validator {
    let text = std::fs::read_to_string(reference_dir().join(f.schema_file())).unwrap();
    let s: Value = serde_json::from_str(&text).unwrap();
    jsonschema::draft7::new(&s).unwrap()
}

fn as_json(t: &toml::Table) -> Value {
    serde_json::to_value(t).unwrap()
}

#[test]
fn shipped_files_carry_their_schema_line_and_validate() {
    let validators: Vec<(Format, jsonschema::Validator)> =
        Format::ALL.into_iter().map(|f| (f, validator(f))).collect();
    let mut counts = [0usize; 4];
    for path in shipped() {
        let name = path.strip_prefix(repo()).unwrap().display().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        let table: toml::Table = toml::from_str(&text).unwrap();
        let first = text.lines().next().unwrap_or_default();
        let Some(f) = format_of(&path, &table) else {
            assert!(
                !first.starts_with("#:schema"),
                "{name}: a manifest has no schema"
            );
            continue;
        };
        // The path from the file's folder to docs/reference/.
        let depth = path.strip_prefix(repo()).unwrap().components().count() - 1;
        let want = format!(
            "#:schema {}docs/reference/{}",
            "../".repeat(depth),
            f.schema_file()
        );
        assert_eq!(first, want, "{name}: the first line");
        let target = path.parent().unwrap().join(&want["#:schema ".len()..]);
        assert!(target.is_file(), "{name}: {} is missing", target.display());
        let v = &validators.iter().find(|(g, _)| *g == f).unwrap().1;
        let errors: Vec<String> = v
            .iter_errors(&as_json(&table))
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        assert!(errors.is_empty(), "{name} against {want}: {errors:?}");
        // And the types read it as that format.
        match f {
            Format::Scenario => {
                ehservo::scenario::Loop::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
            }
            Format::Study => {
                toml::from_str::<ehservo::study::Study>(&text).unwrap();
            }
            Format::Tune => {
                toml::from_str::<ehservo::tune::TuneFile>(&text).unwrap();
            }
            Format::League => {
                toml::from_str::<ehservo::league::SuiteFile>(&text).unwrap();
            }
        }
        counts[f as usize] += 1;
    }
    // Each format is shipped and so checked.
    assert!(counts.iter().all(|&n| n > 0), "{counts:?}");
}

fn accepts(v: &jsonschema::Validator, text: &str) -> bool {
    v.is_valid(&as_json(&toml::from_str(text).unwrap()))
}

/// Files the types refuse for reasons a schema can say, and files they
/// read: the scenario schema agrees on each.
#[test]
fn the_scenario_schema_agrees_with_the_types() {
    let v = validator(Format::Scenario);
    let cases: &[&str] = &[
        "",
        "name = \"x\"",
        "[simulation]\nstep = 0.001\nmode = \"continuous\"",
        "[simulation]\nstepp = 0.001",
        "[simulation]\nstep = \"fast\"",
        "[simulation]\nmode = \"discrete\"",
        "[simulation]\nx0 = [0.0, 0.0]",
        "[simulation]\nx0 = [0.0, 0.0, 0.0, 0.0]",
        "[simulation]\nsubsteps = -1",
        "[controller]\ngamma1 = 200.0",
        "[controller]\nkind = \"vsc\"\ngamma1 = 200.0",
        "[controller]\nkind = \"pid\"\ngamma1 = 200.0",
        "[controller]\nkind = \"pid\"\nkp = 20.0",
        "[controller]\nkind = \"lqr\"",
        "[controller]\ngama1 = 3",
        "[controller]\nmu_rule = \"literal-33\"",
        "[controller]\nmu_rule = \"literal-34\"",
        "[controller.rbf]\nnodes = 3",
        "[plant]\nmodel = \"fourth-order\"",
        "[plant]\nmodel = \"cylinder\"\n[plant.params]\nJt = 1.0",
        "[plant.params]\nJt = 0.05",
        "[plant.params]\nJtt = 0.05",
        "[reference]\nkind = \"step\"\namplitude_deg = 2.0",
        "[reference]\nkind = \"stair\"",
        "[reference]\nwavelength = 1.0",
        "[sensor]\nmeasured = [\"theta\"]",
        "[sensor]\nmeasured = [\"theta_dot\"]",
        "[sensor]\nmeasured = [\"theta\", \"phi\"]",
        "[estimator]\nkind = \"kalman\"\nprocess_noise = 1e4",
        "[estimator]\nkind = \"kalman\"",
        "[estimator]\nkind = \"levant\"\nlipschitz = 1.0\npoles = [1.0, 2.0, 3.0]",
        "[fault]\nsafe_command = \"zero\"",
        "[fault]\nsafe_command = \"panic\"",
        "[output]\nplot = \"yes\"",
        "colour = \"blue\"",
    ];
    let mut refused = 0;
    for text in cases {
        // serde's verdict alone (no value checks): the schema's business.
        let by_types = toml::from_str::<Scenario>(text).is_ok();
        refused += usize::from(!by_types);
        assert_eq!(
            accepts(&v, text),
            by_types,
            "{text:?}: the types say {by_types}"
        );
    }
    assert!(refused >= 15, "only {refused} refused cases");
}

#[test]
fn the_other_schemas_agree_with_the_types() {
    let study = validator(Format::Study);
    let cases: &[(&str, bool)] = &[
        ("name = \"s\"\nbase = \"b.toml\"", true),
        ("name = \"s\"", false),
        (
            "name = \"s\"\nbase = \"b.toml\"\n[[axis]]\nkey = \"controller.gamma1\"\nvalues = [1, 2]",
            true,
        ),
        (
            "name = \"s\"\nbase = \"b.toml\"\n[[axis]]\nkey = \"k\"\nvalues = { from = 0.0, to = 1.0, n = 3, scale = \"log\" }",
            true,
        ),
        (
            "name = \"s\"\nbase = \"b.toml\"\n[[axis]]\nkey = \"k\"\nvalues = { from = 0.0, to = 1.0, n = 3, scale = \"exp\" }",
            false,
        ),
        ("name = \"s\"\nbase = \"b.toml\"\n[monte_carlo]\nruns = 4\n[[monte_carlo.draw]]\nkey = \"k\"\ndist = \"normal\"", true),
        ("name = \"s\"\nbase = \"b.toml\"\n[monte_carlo]\nruns = 4\n[[monte_carlo.draw]]\nkey = \"k\"\ndist = \"cauchy\"", false),
        ("name = \"s\"\nbase = \"b.toml\"\nseeds = 3", false),
    ];
    for (text, ok) in cases {
        assert_eq!(
            toml::from_str::<ehservo::study::Study>(text).is_ok(),
            *ok,
            "{text}"
        );
        assert_eq!(accepts(&study, text), *ok, "{text}");
    }
    let tune = validator(Format::Tune);
    let cases: &[(&str, bool)] = &[
        ("scenarios = [\"a.toml\"]", true),
        ("budget = 10", false),
        ("scenarios = [\"a.toml\"]\nobjective = \"worst\"\n[[param]]\nkey = \"kp\"\nlow = 1.0\nhigh = 2.0\nscale = \"log\"", true),
        ("scenarios = [\"a.toml\"]\nobjective = \"median\"", false),
        ("scenarios = [\"a.toml\"]\n[penalty]\nchatter = 1.0", false),
    ];
    for (text, ok) in cases {
        assert_eq!(
            toml::from_str::<ehservo::tune::TuneFile>(text).is_ok(),
            *ok,
            "{text}"
        );
        assert_eq!(accepts(&tune, text), *ok, "{text}");
    }
    let league = validator(Format::League);
    let cases: &[(&str, bool)] = &[
        (
            "[[controller]]\nkind = \"pid\"\ntune = false\nparams = { kp = 1.0 }",
            true,
        ),
        ("[[controller]]\nname = \"x\"", false),
        ("[[controller]]\nkind = \"sta\"", true),
        ("[[scenario]]\nfile = \"a.toml\"\ndraws = 3", true),
        ("[[scenario]]\nfile = \"a.toml\"\nruns = 3", false),
        (
            "[margin]\nscenario = \"a.toml\"\nkeys = [\"k\"]\nhigh = 2.0",
            true,
        ),
        ("[margin]\nscenario = \"a.toml\"\nkeys = [\"k\"]", false),
    ];
    for (text, ok) in cases {
        assert_eq!(
            toml::from_str::<ehservo::league::SuiteFile>(text).is_ok(),
            *ok,
            "{text}"
        );
        assert_eq!(accepts(&league, text), *ok, "{text}");
    }
    // A kind is a string to the types (checked when the suite or the tune
    // is loaded); the schemas name the registered kinds.
    assert!(!accepts(&league, "[[controller]]\nkind = \"lqr\""));
    assert!(!accepts(
        &tune,
        "scenarios = [\"a.toml\"]\ncontroller = \"lqr\""
    ));
    for kind in ControllerCfg::KINDS {
        let text = format!("scenarios = [\"a.toml\"]\ncontroller = \"{kind}\"");
        assert!(accepts(&tune, &text), "{text}");
    }
}

/// Each controller kind's and plant model's branch holds every key its
/// type writes, and each default in the schema is the value the types'
/// `Default` writes at that key.
#[test]
fn every_kind_and_model_and_their_defaults() {
    let s = schema(Format::Scenario);
    let defs = s["definitions"].as_object().unwrap();
    // A key's schema: through its `allOf` wrapper and `$ref`s.
    let by_ref = |v: &Value| -> Value {
        let mut v = v.clone();
        loop {
            v = match (v.get("$ref").and_then(Value::as_str), v.get("allOf")) {
                (Some(r), _) => defs[r.rsplit('/').next().unwrap()].clone(),
                (None, Some(a)) => a[0].clone(),
                _ => return v,
            };
        }
    };
    let branches = |key: &str| -> Vec<Value> {
        by_ref(&s["properties"][key])["oneOf"]
            .as_array()
            .unwrap()
            .clone()
    };
    let controllers = branches("controller");
    assert_eq!(controllers.len(), ControllerCfg::KINDS.len());
    for (kind, b) in ControllerCfg::KINDS.iter().zip(&controllers) {
        let props = b["properties"].as_object().unwrap();
        assert_eq!(props["kind"]["const"], *kind);
        let table = ControllerCfg::default_of(kind).unwrap().to_table();
        for (k, v) in &table {
            let p = props.get(k).unwrap_or_else(|| panic!("{kind}: no `{k}`"));
            if let Some(d) = p.get("default") {
                assert_eq!(*d, serde_json::to_value(v).unwrap(), "{kind}.{k}");
            }
        }
    }
    let plants = branches("plant");
    assert_eq!(plants.len(), PlantCfg::MODELS.len());
    for (model, b) in PlantCfg::MODELS.iter().zip(&plants) {
        let props = b["properties"].as_object().unwrap();
        assert_eq!(props["model"]["const"], *model);
        for k in PlantCfg::default_of(model).unwrap().to_table().keys() {
            assert!(props.contains_key(k), "{model}: no `{k}`");
        }
    }
    // The sections' defaults: what `ehservo defaults` writes.
    let written = serde_json::to_value(Scenario::default().table().unwrap()).unwrap();
    let mut checked = 0;
    for section in ["simulation", "uncertainty", "output", "fault", "sensor"] {
        let d = by_ref(&s["properties"][section]);
        for (k, p) in d["properties"].as_object().unwrap() {
            if let (Some(want), Some(have)) = (written[section].get(k), p.get("default")) {
                assert_eq!(have, want, "{section}.{k}");
                checked += 1;
            }
        }
    }
    assert!(checked >= 12, "only {checked} defaults checked");
}

#[test]
fn the_pages_hold_every_key_with_its_unit() {
    let page = markdown(Format::Scenario);
    for needle in [
        "| `horizon` | float | s | `10.0` |",
        "| `step` | float | s | `0.01` |",
        "`[controller]` kind = \"pid\"",
        "`[controller]` kind = \"nnvsc\" (the default)",
        "`[plant]` model = \"cylinder\"",
        "`[estimator]` kind = \"kalman\"",
        "`[plant.params]`",
    ] {
        assert!(page.contains(needle), "the scenario page lacks {needle:?}");
    }
    for kind in ControllerCfg::KINDS {
        assert!(page.contains(&format!("kind = \"{kind}\"")), "{kind}");
    }
    // The plant's parameters (a generic type's keys) with the defaults the
    // default plant writes.
    let plant = PlantCfg::default().to_table();
    let params = plant["params"].as_table().unwrap();
    assert!(params.len() >= 12);
    for (k, v) in params {
        let row = format!("| `{k}` | float | ");
        let line = page.lines().find(|l| l.starts_with(&row));
        let line = line.unwrap_or_else(|| panic!("no row of plant.params.{k}"));
        assert!(line.contains(&format!("| `{v}` |")), "{line} lacks {v}");
    }
    let study = markdown(Format::Study);
    assert!(study.contains("`[[axis]]`") && study.contains("`[monte_carlo]`"));
}

/// Issue 46, item 7: the units of every load and friction key follow the
/// plant's axis. The same friction parameters serve both: on the paper's
/// rotary servo (`[load.friction]`) in N·m and rad/s, on a cylinder
/// (`[plant.load.friction]`) in N and m/s; and no key of a cylinder's
/// `[plant.load…]` is in a rotary unit.
#[test]
fn load_and_friction_units_follow_the_axis() {
    let page = markdown(Format::Scenario);
    // Each section's rows: (heading, [(key, unit)]).
    let mut sections: Vec<(String, Vec<(String, String)>)> = Vec::new();
    for line in page.lines() {
        if line.starts_with('#') {
            sections.push((line.trim_start_matches('#').trim().to_string(), Vec::new()));
        } else if let (Some(last), Some(row)) = (sections.last_mut(), line.strip_prefix("| `")) {
            let cells: Vec<&str> = row.split(" | ").collect();
            if cells.len() >= 3 {
                let key = cells[0].trim_end_matches('`').to_string();
                last.1.push((key, cells[2].trim().to_string()));
            }
        }
    }
    let rows = |heading: &str| -> Vec<(String, String)> {
        sections
            .iter()
            .find(|(h, _)| h == heading)
            .unwrap_or_else(|| panic!("no section {heading}"))
            .1
            .clone()
    };
    let expect = |heading: &str, want: &[(&str, &str)]| {
        let got = rows(heading);
        for (k, u) in want {
            let g = got.iter().find(|(key, _)| key == k).map(|r| r.1.as_str());
            assert_eq!(g, Some(*u), "{heading} {k}");
        }
    };
    expect(
        "`[load.friction]`",
        &[
            ("coulomb", "N·m"),
            ("stiction", "N·m"),
            ("stribeck_velocity", "rad/s"),
            ("viscous", "N·m·s"),
            ("smoothing", "rad/s"),
        ],
    );
    expect(
        "`[plant.load.friction]`",
        &[
            ("coulomb", "N"),
            ("stiction", "N"),
            ("stribeck_velocity", "m/s"),
            ("viscous", "N·s/m"),
            ("smoothing", "m/s"),
        ],
    );
    let linear: Vec<&(String, Vec<(String, String)>)> = sections
        .iter()
        .filter(|(h, _)| h.starts_with("`[plant.load"))
        .collect();
    assert!(
        linear.len() >= 2,
        "{:?}",
        linear.iter().map(|s| &s.0).collect::<Vec<_>>()
    );
    for (h, rows) in linear {
        for (k, u) in rows {
            assert!(!u.contains("rad") && !u.contains("N·m"), "{h} {k}: {u}");
        }
    }
}
