//! `include/ehservo.h` is what cbindgen makes of `src/lib.rs` today.
//!
//! The header is committed (rather than written by a build script) so
//! that a C programmer reads and uses it without building Rust, the source
//! tree is never written by a build, and cbindgen is needed by this test
//! only. `EHSERVO_UPDATE_HEADER=1 cargo test -p ehservo-ffi --test header`
//! rewrites it.

use std::path::Path;

#[test]
fn the_committed_header_is_up_to_date() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen parses src/lib.rs")
        .write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = dir.join("include/ehservo.h");
    if std::env::var_os("EHSERVO_UPDATE_HEADER").is_some() {
        let tmp = path.with_extension("h.tmp");
        std::fs::write(&tmp, &generated).unwrap();
        std::fs::rename(&tmp, &path).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "include/ehservo.h is out of date: run EHSERVO_UPDATE_HEADER=1 cargo test -p ehservo-ffi --test header"
    );
}

/// `EhservoSample.flags` is documented by the constants themselves: the
/// header defines `EHSERVO_FLAG_<NAME>` with the law's value for every flag
/// of `ehservo_scenario::core::control::flags::ALL` (and no other), and docs/flags.md
/// lists each with that value and bit. (The header once said "bit 0
/// saturated" while saturated was bit 4.)
#[test]
fn the_header_the_constants_and_the_docs_agree_on_the_flags() {
    use ehservo_scenario::core::control::flags::ALL;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let header = std::fs::read_to_string(dir.join("include/ehservo.h")).unwrap();
    let defined: Vec<(String, u32)> = header
        .lines()
        .filter_map(|l| l.strip_prefix("#define EHSERVO_FLAG_"))
        .map(|rest| {
            let mut it = rest.split_whitespace();
            let name = it.next().unwrap().to_string();
            let value = it.next().unwrap().parse().unwrap();
            (name, value)
        })
        .collect();
    let want: Vec<(String, u32)> = ALL
        .iter()
        .map(|(n, v, _)| (n.to_string(), u32::from(*v)))
        .collect();
    assert_eq!(defined, want, "the header's EHSERVO_FLAG_* constants");
    for ((name, value), (c_name, c_value)) in want.iter().zip(ehservo_ffi::FLAGS) {
        assert_eq!(
            (format!("EHSERVO_FLAG_{name}"), *value),
            (c_name.to_string(), c_value)
        );
    }
    assert!(
        !header.contains("bit 0 saturated"),
        "the old, wrong bit list is back in the header"
    );
    // docs/flags.md: a row `| `EHSERVO_FLAG_<NAME>` | `<value>` | <bit> | …`.
    let docs = std::fs::read_to_string(dir.join("../../docs/flags.md")).unwrap();
    let rows: Vec<(String, u32, u32)> = docs
        .lines()
        .filter(|l| l.starts_with("| `EHSERVO_FLAG_"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(|c| c.trim().trim_matches('`')).collect();
            (
                cells[1].trim_start_matches("EHSERVO_FLAG_").to_string(),
                cells[2].parse().unwrap(),
                cells[3].parse().unwrap(),
            )
        })
        .collect();
    let want_rows: Vec<(String, u32, u32)> = want
        .iter()
        .map(|(n, v)| (n.clone(), *v, v.trailing_zeros()))
        .collect();
    assert_eq!(rows, want_rows, "docs/flags.md's table");
}
