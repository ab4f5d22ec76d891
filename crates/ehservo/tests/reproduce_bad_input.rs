//! Bad reproduction manifests (`tests/bad-input-reproduce/`): each is
//! refused by `ehservo reproduce --paper-dir` with exit 2, one line naming
//! the manifest and containing the fragment of its `# expect:` line, no
//! panic, and no output folder — before any case is run.

use std::path::Path;
use std::process::Command;

#[test]
fn every_bad_manifest_is_refused_clearly() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = repo.join("tests/bad-input-reproduce");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 15,
        "the corpus has {} manifests",
        files.len()
    );
    for p in files {
        let tmp = tempfile::tempdir().unwrap();
        // The paper's case files beside the bad manifest.
        for e in std::fs::read_dir(repo.join("scenarios/paper")).unwrap() {
            let e = e.unwrap().path();
            if e.file_name().is_some_and(|n| n != "manifest.toml") {
                std::fs::copy(&e, tmp.path().join(e.file_name().unwrap())).unwrap();
            }
        }
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(tmp.path().join("manifest.toml"), &text).unwrap();
        let expect = text
            .lines()
            .next()
            .unwrap()
            .strip_prefix("# expect: ")
            .unwrap();
        let out = tmp.path().join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
            .args(["reproduce", "--quiet", "--paper-dir"])
            .arg(tmp.path())
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let name = p.file_name().unwrap().to_string_lossy();
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expect), "{name}: expected {expect:?} in {err}");
        assert_eq!(err.trim().lines().count(), 1, "{name}: one line: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(!out.exists(), "{name}: output written");
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .collect();
        assert!(left.is_empty(), "{name}: staging left behind");
    }
}
