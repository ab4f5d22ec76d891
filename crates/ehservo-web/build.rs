//! Embeds the scenarios the page offers — every scenario file (not a
//! study, tune or league file: those name another `#:schema`) of
//! `scenarios/paper` (but the manifest), `scenarios/realistic`,
//! `scenarios/cylinders` and `scenarios/hopsan` — as
//! `include_str!` entries, so the list follows the folders without a
//! hand-kept copy.

use std::fmt::Write as _;
use std::path::Path;

/// The folders of `scenarios/` the page offers.
const GROUPS: [&str; 4] = ["paper", "realistic", "cylinders", "hopsan"];

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut out = String::from("&[\n");
    for group in GROUPS {
        let dir = root.join(group);
        println!("cargo:rerun-if-changed={}", dir.display());
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .filter(|p| p.file_stem().is_some_and(|s| s != "manifest"))
            .filter(|p| {
                let text = std::fs::read_to_string(p).unwrap_or_default();
                !text.lines().any(|l| l.trim() == "[[axis]]")
                    && !text
                        .lines()
                        .any(|l| l.starts_with("#:schema") && !l.ends_with("scenario.schema.json"))
            })
            .collect();
        files.sort();
        for path in files {
            println!("cargo:rerun-if-changed={}", path.display());
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            let full = path.canonicalize().expect("a listed file exists");
            writeln!(
                out,
                "    BaseScenario {{ id: {:?}, path: {:?}, text: include_str!({:?}) }},",
                format!("{group}/{stem}"),
                format!("scenarios/{group}/{stem}.toml"),
                full.display().to_string()
            )
            .unwrap();
        }
    }
    out.push(']');
    let dest = Path::new(&std::env::var("OUT_DIR").unwrap()).join("scenarios.rs");
    std::fs::write(dest, out).expect("writing OUT_DIR/scenarios.rs");
}
