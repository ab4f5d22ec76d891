//! The corpus of bad scenario files in `tests/bad-input/`: each must be
//! rejected with exit code 2, a message naming the file and containing the
//! fragment of its `# expect:` first line, no panic, and no output.

use std::path::Path;
use std::process::Command;

#[test]
fn every_bad_file_is_rejected_clearly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad-input");
    let tmp = tempfile::tempdir().unwrap();
    let mut n = 0;
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for p in files {
        let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).into_owned();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{}: no `# expect:` line", p.display()));
        let out = tmp.path().join(p.file_stem().unwrap());
        let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
            .arg("run")
            .arg(&p)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let name = p.file_name().unwrap().to_string_lossy();
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expect), "{name}: expected {expect:?} in {err}");
        assert!(
            err.contains(&*name),
            "{name}: the message names the file: {err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
            "{name}: {err}"
        );
        assert_eq!(
            err.trim().lines().count(),
            1,
            "{name}: one clear line: {err}"
        );
        assert!(!out.exists(), "{name}: output written for bad input");
        n += 1;
    }
    assert!(n >= 120, "the corpus has {n} files");
    // Nothing was left behind in the parent either (no staging directories).
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}
