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
