//! Bad reproduction manifests (`tests/bad-input-reproduce/`): each is
//! refused by `ehservo reproduce --paper-dir` with exit 2, one line naming
//! the manifest and containing the fragment of its `# expect:` line, no
//! panic, and no output folder — before any case is run.

use crate::common;
use std::process::Command;

#[test]
fn every_bad_manifest_is_refused_clearly() {
    let repo = common::repo();
    for c in common::corpus("bad-input-reproduce", 15) {
        let tmp = tempfile::tempdir().unwrap();
        // The paper's case files beside the bad manifest.
        for e in std::fs::read_dir(repo.join("scenarios/paper")).unwrap() {
            let e = e.unwrap().path();
            if e.file_name().is_some_and(|n| n != "manifest.toml") {
                std::fs::copy(&e, tmp.path().join(e.file_name().unwrap())).unwrap();
            }
        }
        std::fs::write(tmp.path().join("manifest.toml"), &c.text).unwrap();
        let out = tmp.path().join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
            .args(["reproduce", "--quiet", "--paper-dir"])
            .arg(tmp.path())
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let name = &c.name;
        common::rejected(name, &o, &c.expect);
        assert!(!out.exists(), "{name}: output written");
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .collect();
        assert!(left.is_empty(), "{name}: staging left behind");
    }
}
