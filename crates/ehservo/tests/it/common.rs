//! What the test modules share: the repository root, the `ehservo` command
//! built with them, the corpora of `tests/bad-input*/` (each file's first
//! line is `# expect: <fragment of the message>`) and the check that a
//! refusal is clear.

use std::path::{Path, PathBuf};
use std::process::Output;

/// One bad file of a corpus.
pub struct Case {
    pub path: PathBuf,
    /// The file name, which the message must name.
    pub name: String,
    /// The fragment its message must contain.
    pub expect: String,
    pub text: String,
}

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The `ehservo` command line built with these tests.
pub fn ehservo() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_ehservo"))
}

/// The `.toml` files of `tests/<dir>`, sorted, with their `# expect:` line;
/// at least `min` of them (a corpus that shrank by accident fails).
pub fn corpus(dir: &str, min: usize) -> Vec<Case> {
    let dir = repo().join("tests").join(dir);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= min,
        "{}: {} files, expected at least {min}",
        dir.display(),
        files.len()
    );
    files
        .into_iter()
        .map(|path| {
            let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
            let expect = text
                .lines()
                .next()
                .and_then(|l| l.strip_prefix("# expect: "))
                .unwrap_or_else(|| panic!("{}: no `# expect:` line", path.display()))
                .to_string();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            Case {
                path,
                name,
                expect,
                text,
            }
        })
        .collect()
}

/// A clear refusal: exit 2, one line on stderr containing `expect`, no
/// panic. Returns stderr.
pub fn rejected(name: &str, o: &Output, expect: &str) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{name}: {err}");
    assert!(err.contains(expect), "{name}: expected {expect:?} in {err}");
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{name}: {err}"
    );
    assert_eq!(
        err.trim().lines().count(),
        1,
        "{name}: one clear line: {err}"
    );
    err
}

/// [`rejected`], and the message names the file.
pub fn rejected_naming(name: &str, o: &Output, expect: &str) -> String {
    let err = rejected(name, o, expect);
    assert!(
        err.contains(name),
        "{name}: the message names the file: {err}"
    );
    err
}

/// An open-loop `ehservo excite` experiment on Fig. 2's servo (`excite`'s
/// arguments given), simulated by `ehservo run` into `dir`: the trace.csv
/// that `identify` reads.
pub fn excited_trace(dir: &Path, excite: &[&str]) -> PathBuf {
    let ex = dir.join("ex");
    let data = dir.join("data");
    for args in [
        [&["excite"][..], excite, &["--out"]].concat(),
        vec![
            "run",
            ex.join("scenario.toml").to_str().unwrap(),
            "--no-plot",
            "-q",
            "--out",
        ],
    ] {
        let target = if args[0] == "excite" { &ex } else { &data };
        let o = ehservo().args(&args).arg(target).output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    data.join("trace.csv")
}

/// A command that must have succeeded: exit 0, or fail naming `what` and
/// showing its stderr.
pub fn succeeded(what: &str, o: &Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}
