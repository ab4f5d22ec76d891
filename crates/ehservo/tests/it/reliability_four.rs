//! Issue #46, reliability round four: hostile input files refused in one
//! short line (item 4). The work limits are in `freq`, PIL in `pil`.

use crate::common;
use std::path::Path;
use std::process::Output;

/// Exit 2, one line on stderr of at most `max` characters containing
/// `expect`, and the output folder `out` absent.
fn refused_short(what: &str, o: &Output, expect: &str, out: &Path, max: usize) {
    let err = common::rejected(what, o, expect);
    let n = err.trim_end().chars().count();
    assert!(n <= max, "{what}: {n} characters: {err}");
    assert!(!out.exists(), "{what}: output written for bad input");
}

/// A 1 MiB file of NUL bytes, and a 500 000-character header, given to
/// `identify` and as a reference CSV: once refused with a line quoting
/// the whole "header" (209 million characters for 200 MiB); now the read
/// stops at the first NUL, and a header is quoted by its start and its
/// length.
#[test]
fn huge_or_binary_csv_files_are_refused_in_one_short_line() {
    let tmp = tempfile::tempdir().unwrap();
    let nul = tmp.path().join("nul.csv");
    std::fs::write(&nul, vec![0u8; 1 << 20]).unwrap();
    let long = tmp.path().join("long.csv");
    std::fs::write(&long, format!("{}\n0,1\n", "x".repeat(500_000))).unwrap();
    let out = tmp.path().join("out");
    // The NUL file is refused by the read (under 300 characters); the
    // long header by identify's own message, which quotes the header's
    // first 120 characters and its count of columns.
    for (file, expect, max) in [
        (&nul, "is not text: byte 0 is NUL", 300),
        (&long, "… (1 column)", 300),
    ] {
        let o = common::ehservo()
            .arg("identify")
            .arg(file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        refused_short("identify", &o, expect, &out, max);
    }
    // A reference CSV: its header quoted by its first 60 characters.
    for (file, expect) in [
        (&nul, "is not text: byte 0 is NUL"),
        (
            &long,
            &format!("got `{}…` (500000 characters)", "x".repeat(60)),
        ),
    ] {
        let scenario = tmp.path().join("s.toml");
        std::fs::write(
            &scenario,
            format!(
                "name = \"r\"\n[reference]\nkind = \"csv\"\nprefilter_tau = 0.05\nfile = \"{}\"\n",
                file.display()
            ),
        )
        .unwrap();
        let o = common::ehservo()
            .arg("run")
            .arg(&scenario)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        refused_short("a reference CSV", &o, expect, &out, 300);
    }
}
