//! The house keeps its rooms (issue #40): no source file grows beyond the
//! size a reader can hold, and the bindings stand on the crates they need,
//! not on the lab.

use std::path::{Path, PathBuf};

/// Most code lines a source file may have outside its tests.
const MAX_CODE_LINES: usize = 650;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Code lines: not blank, not a `//` comment, before the first
/// `#[cfg(test)]` (the unit tests that sit at a file's end).
fn code_lines(text: &str) -> usize {
    text.lines()
        .take_while(|l| l.trim() != "#[cfg(test)]")
        .filter(|l| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with("//")
        })
        .count()
}

#[test]
fn code_lines_are_counted_as_documented() {
    let text = "//! doc\n\nuse x;\n// note\nfn a() {\n    1\n}\n#[cfg(test)]\nmod tests {\n    fn b() {}\n}\n";
    // `use x;`, `fn a() {`, `1`, `}`: four.
    assert_eq!(code_lines(text), 4);
}

#[test]
fn no_source_file_is_beyond_the_limit() {
    let root = repo();
    let mut files = Vec::new();
    for dir in ["crates", "bindings/python/src", "examples"] {
        rust_files(&root.join(dir), &mut files);
    }
    // The tests themselves and the build's outputs are not the house's rooms.
    files.retain(|p| {
        let s = p.to_string_lossy();
        !s.contains("/tests/") && !s.contains("/target/") && !s.contains("/benches/")
    });
    assert!(files.len() > 50, "found only {} source files", files.len());
    let mut big: Vec<String> = files
        .iter()
        .filter_map(|p| {
            let n = code_lines(&std::fs::read_to_string(p).unwrap());
            (n > MAX_CODE_LINES)
                .then(|| format!("{} ({n})", p.strip_prefix(&root).unwrap_or(p).display()))
        })
        .collect();
    big.sort();
    assert!(
        big.is_empty(),
        "source files above {MAX_CODE_LINES} code lines outside tests (split each along its seam): {big:?}"
    );
}

/// The C ABI, the FMU's binary and the browser build on `ehservo-scenario`
/// (the scenario, a run, the stepper), not on the lab and its plotting,
/// fitting and archive crates.
#[test]
fn the_bindings_stand_on_the_scenario_crate_not_the_lab() {
    for krate in ["crates/ehservo-ffi", "crates/ehservo-web"] {
        let path = repo().join(krate).join("Cargo.toml");
        let manifest: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
        let deps = manifest["dependencies"].as_table().unwrap();
        assert!(deps.contains_key("ehservo-scenario"), "{krate}: {deps:?}");
        for lab in ["ehservo", "plotters", "argmin", "zip", "rayon", "clap"] {
            assert!(!deps.contains_key(lab), "{krate} depends on {lab}");
        }
    }
}
