//! Writing outputs whole or not at all: a staging folder beside the
//! destination, renamed into place on commit, removed on failure or signal.

use anyhow::{Context, Result};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files that mark a folder as an ehservo output (of `run`, `sweep` or
/// `merge`, `reproduce`): only such a folder, or an empty one, is replaced.
pub const OUTPUT_MARKERS: [&str; 6] = [
    "summary.json",
    "study.json",
    "report.md",
    "claims.csv",
    "identify.json",
    "excite.json",
];

/// Checks that `dest` may receive an output, which replaces it whole: it
/// does not exist yet (and names a folder), or it is a directory that is
/// empty or holds an earlier ehservo output ([`OUTPUT_MARKERS`]). Refused as
/// bad input: a file, a directory with anything else in it, `/`, the current
/// directory or one of its parents. Returns the path to write (lexically
/// normalised; resolved through symbolic links when it exists).
pub fn check_destination(dest: &Path) -> Result<PathBuf> {
    // `a/./b/` → `a/b`, so that parent and file name are the real ones.
    let norm: PathBuf = dest.components().collect();
    if norm.as_os_str().is_empty() {
        crate::bad_input!("--out: an empty path");
    }
    let meta = match fs::symlink_metadata(&norm) {
        Ok(m) => m,
        // Not there, or under a file: `Staging::new` says which.
        Err(e) if is_absent(&e) => {
            if norm.file_name().is_none() {
                crate::bad_input!("--out {}: not a folder name", dest.display());
            }
            return Ok(norm);
        }
        Err(e) => return Err(e).with_context(|| format!("--out {}", dest.display())),
    };
    let real = match fs::canonicalize(&norm) {
        Ok(r) => r,
        Err(_) if meta.file_type().is_symlink() => {
            crate::bad_input!("--out {}: a symbolic link to nothing", dest.display())
        }
        Err(e) => return Err(e).with_context(|| format!("--out {}", dest.display())),
    };
    if !real.is_dir() {
        crate::bad_input!(
            "--out {}: exists and is not a directory: refusing to replace it",
            dest.display()
        );
    }
    let holds_cwd = std::env::current_dir()
        .and_then(fs::canonicalize)
        .is_ok_and(|cwd| cwd.starts_with(&real));
    if real.parent().is_none() || holds_cwd {
        crate::bad_input!(
            "--out {}: is the root, the current directory or one of its parents: refusing to replace it",
            dest.display()
        );
    }
    let mut entries = fs::read_dir(&real).with_context(|| format!("reading {}", dest.display()))?;
    let empty = entries.next().is_none();
    if !empty && !OUTPUT_MARKERS.iter().any(|m| real.join(m).is_file()) {
        crate::bad_input!(
            "--out {} exists and is not an ehservo output folder (it has none of {}): refusing to replace it",
            dest.display(),
            OUTPUT_MARKERS.join(", ")
        );
    }
    Ok(real)
}

/// Whether a lookup failed because the path is not there (`ENOENT`) or
/// cannot be, a file standing for one of its folders (`ENOTDIR`).
fn is_absent(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
    )
}

/// Checks that an output can go to `dest` before the work that makes it
/// (a reproduction, a sweep): [`check_destination`], then a staging
/// directory made beside it and a file written into it, all removed again.
pub fn probe_destination(dest: &Path) -> Result<()> {
    let stage = Staging::new(dest)?;
    let probe = stage.path().join(".probe");
    fs::write(&probe, b"probe").with_context(|| format!("writing {}", probe.display()))?;
    Ok(())
}

/// A directory written under a temporary name and moved into place on
/// [`Staging::commit`], replacing the destination whole. Dropped without
/// commit (an error, a panic) it is removed, and so are the parent folders
/// it had to create; on a signal, [`crate::signals`] removes them: a failed
/// or interrupted run leaves nothing half-written.
#[derive(Debug)]
pub struct Staging {
    dest: PathBuf,
    tmp: PathBuf,
    /// Folders created for `dest`'s parent, deepest first.
    created: Vec<PathBuf>,
    id: u64,
    committed: bool,
}

/// The `i`-th candidate name for a hidden folder in `parent`,
/// `.ehservo.{what}-{pid}-{i}`: short and bounded whatever the length of the
/// output's own name (which may be up to the 255-byte limit).
fn sibling(parent: &Path, what: &str, i: u32) -> PathBuf {
    parent.join(format!(".ehservo.{what}-{}-{i}", std::process::id()))
}

impl Staging {
    /// Checks `dest` ([`check_destination`]), then creates the staging
    /// directory beside it (and `dest`'s parent folders if need be).
    pub fn new(dest: &Path) -> Result<Self> {
        let dest = check_destination(dest)?;
        let parent = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        // The folders that do not exist yet, deepest first; the first that
        // does must be a directory.
        let mut created = Vec::new();
        for a in parent.ancestors().filter(|a| !a.as_os_str().is_empty()) {
            match fs::metadata(a) {
                Ok(m) if m.is_dir() => break,
                Ok(_) => crate::bad_input!(
                    "--out {}: {} is not a directory",
                    dest.display(),
                    a.display()
                ),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => created.push(a.to_path_buf()),
                // Under a file: the file is found further up.
                Err(e) if is_absent(&e) => {}
                Err(e) => return Err(e).with_context(|| format!("--out {}", dest.display())),
            }
        }
        // Created and listed under the registry's lock: a signal sees both
        // or neither.
        let mut reg = crate::signals::registry();
        if let Err(e) = fs::create_dir_all(&parent) {
            crate::signals::remove_created(&created);
            return Err(e).with_context(|| format!("creating {}", parent.display()));
        }
        let mut i = 0u32;
        let tmp = loop {
            let cand = sibling(&parent, "tmp", i);
            match fs::create_dir(&cand) {
                Ok(()) => break cand,
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && i < 1000 => i += 1,
                Err(e) => {
                    crate::signals::remove_created(&created);
                    return Err(e).with_context(|| format!("creating {}", cand.display()));
                }
            }
        };
        let id = reg.add(tmp.clone(), created.clone());
        Ok(Self {
            dest,
            tmp,
            created,
            id,
            committed: false,
        })
    }

    /// Where to write.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Moves the staging directory into place. An existing destination is
    /// checked again ([`check_destination`]: its content may have changed
    /// during the run), renamed aside, replaced and then removed: no file of
    /// an earlier output survives.
    pub fn commit(mut self) -> Result<()> {
        // A signal arriving now waits until the output is in place.
        let mut reg = crate::signals::registry();
        let moved = self.move_into_place();
        if moved.is_ok() {
            self.committed = true;
            reg.remove(self.id);
        }
        drop(reg);
        moved
    }

    fn move_into_place(&self) -> Result<()> {
        let dest = check_destination(&self.dest)?;
        let moving = || format!("moving {} to {}", self.tmp.display(), dest.display());
        if fs::symlink_metadata(&dest).is_err() {
            return fs::rename(&self.tmp, &dest).with_context(moving);
        }
        // Beside `dest`: renaming it aside never crosses a file system.
        let parent = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let mut i = 0u32;
        let aside = loop {
            let cand = sibling(parent, "old", i);
            if fs::symlink_metadata(&cand).is_err() || i >= 1000 {
                break cand;
            }
            i += 1;
        };
        fs::rename(&dest, &aside)
            .with_context(|| format!("moving the previous {} aside", dest.display()))?;
        if let Err(e) = fs::rename(&self.tmp, &dest) {
            fs::rename(&aside, &dest).ok();
            return Err(e).with_context(moving);
        }
        crate::signals::remove_tree(&aside);
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let mut reg = crate::signals::registry();
            crate::signals::remove_tree(&self.tmp);
            crate::signals::remove_created(&self.created);
            reg.remove(self.id);
        }
    }
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!(
        "{}.tmp-{}",
        path.extension().and_then(|e| e.to_str()).unwrap_or(""),
        std::process::id()
    ));
    {
        let mut f =
            fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        f.write_all(bytes)?;
        f.sync_all().ok();
    }
    fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}
