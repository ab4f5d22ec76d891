//! Names the commit in `ehservo --version`: `EHSERVO_COMMIT` is
//! `git rev-parse --short HEAD` (the commit checked out: uncommitted
//! changes are not marked), or "unknown" outside a git checkout (a source
//! archive, a build context without `.git`) or without git.

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(dir)
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let here = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let commit = git(&here, &["rev-parse", "--short", "HEAD"]);
    if commit.is_some() {
        // Rebuilt when HEAD moves: HEAD itself (a checkout), the branch's
        // ref (a commit) and packed-refs (where a ref may live instead).
        let abs = |p: String| {
            let p = PathBuf::from(p);
            if p.is_absolute() {
                p
            } else {
                here.join(p)
            }
        };
        let mut watch = Vec::new();
        if let Some(d) = git(&here, &["rev-parse", "--git-dir"]) {
            watch.push(abs(d).join("HEAD"));
        }
        if let Some(common) = git(&here, &["rev-parse", "--git-common-dir"]).map(abs) {
            if let Some(r) = git(&here, &["symbolic-ref", "-q", "HEAD"]) {
                watch.push(common.join(r));
            }
            watch.push(common.join("packed-refs"));
        }
        for p in watch.iter().filter(|p| p.exists()) {
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
    println!(
        "cargo:rustc-env=EHSERVO_COMMIT={}",
        commit.as_deref().unwrap_or("unknown")
    );
}
