//! The corpus of bad scenario files in `tests/bad-input/`: each must be
//! rejected with exit code 2, a message naming the file and containing the
//! fragment of its `# expect:` first line, no panic, and no output.

use crate::common;
use std::process::Command;

#[test]
fn every_bad_file_is_rejected_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    for c in common::corpus("bad-input", 120) {
        let out = tmp.path().join(c.path.file_stem().unwrap());
        let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
            .arg("run")
            .arg(&c.path)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = common::rejected_naming(&c.name, &o, &c.expect);
        // One short line: at most 300 characters besides the file's path
        // (a figure is quoted as 1e300, never as its 301 digits).
        let rest = err.trim().replace(&c.path.display().to_string(), "");
        assert!(
            rest.chars().count() <= 300,
            "{}: {} characters besides the path: {err}",
            c.name,
            rest.chars().count()
        );
        assert!(!out.exists(), "{}: output written for bad input", c.name);
    }
    // Nothing was left behind in the parent either (no staging directories).
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}
