//! Writing outputs whole or not at all: a staging folder beside the
//! destination, renamed into place on commit, removed on failure or signal.

use anyhow::{Context, Result};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The files that mark a folder as an ehservo output: only such a folder,
/// or an empty one, is replaced. The one list every writer registers with:
/// [`Staging::commit`] refuses a folder that holds none of them, so a new
/// command's output cannot go without its marker (and then be refused
/// when it is written again).
pub const OUTPUT_MARKERS: [&str; 10] = [
    "summary.json",       // ehservo run, ehservo pil
    "study.json",         // ehservo sweep, ehservo merge
    "report.md",          // ehservo reproduce
    "claims.csv",         // ehservo reproduce
    "tune.json",          // ehservo tune
    "league.json",        // ehservo league
    "identify.json",      // ehservo identify
    "excite.json",        // ehservo excite
    "freq.json",          // ehservo freq
    "linearization.json", // ehservo linearize
];

/// How long a commit waits for another process's commit into the same
/// folder to finish (each holds the parent folder's lock for a rename or
/// two and the removal of the old output).
const LOCK_WAIT: std::time::Duration = std::time::Duration::from_secs(120);

/// A lock on the folder that holds outputs (`flock` on the directory
/// itself: nothing is created, and it is released when the process ends,
/// however it ends). Shared while a destination is checked, exclusive while
/// one is replaced, so that no check sees a folder half-way through
/// another process's replace. Where the file system cannot lock (some
/// network file systems), it is not taken.
struct ParentLock {
    #[cfg(unix)]
    _lock: Option<nix::fcntl::Flock<fs::File>>,
}

impl ParentLock {
    fn take(parent: &Path, exclusive: bool) -> Result<Self> {
        #[cfg(unix)]
        {
            use nix::errno::Errno;
            use nix::fcntl::{Flock, FlockArg};
            let Ok(mut dir) = fs::File::open(parent) else {
                // Not there (nothing to race over) or unreadable: no lock.
                return Ok(Self { _lock: None });
            };
            let arg = if exclusive {
                FlockArg::LockExclusiveNonblock
            } else {
                FlockArg::LockSharedNonblock
            };
            let start = std::time::Instant::now();
            loop {
                match Flock::lock(dir, arg) {
                    Ok(l) => return Ok(Self { _lock: Some(l) }),
                    Err((d, Errno::EWOULDBLOCK | Errno::EINTR)) => {
                        if start.elapsed() > LOCK_WAIT {
                            anyhow::bail!(
                                "{}: another process has been replacing an output in this folder for over {} s; nothing was written (try again when it is done)",
                                parent.display(),
                                LOCK_WAIT.as_secs()
                            );
                        }
                        dir = d;
                        std::thread::sleep(std::time::Duration::from_millis(5));
                    }
                    // The file system does not lock: go on without.
                    Err(_) => return Ok(Self { _lock: None }),
                }
            }
        }
        #[cfg(not(unix))]
        {
            let _ = (parent, exclusive);
            Ok(Self {})
        }
    }
}

/// The folder `dest` is written in.
fn parent_of(dest: &Path) -> &Path {
    match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The folder whose lock guards `dest` (normalised): the real parent of
/// what it resolves to, so that two paths to one folder (a symbolic link)
/// share the lock.
fn lock_dir(norm: &Path) -> PathBuf {
    fs::canonicalize(norm)
        .ok()
        .and_then(|r| r.parent().map(Path::to_path_buf))
        .unwrap_or_else(|| parent_of(norm).to_path_buf())
}

/// Checks that `dest` may receive an output, which replaces it whole: it
/// does not exist yet (and names a folder), or it is a directory that is
/// empty or holds an earlier ehservo output ([`OUTPUT_MARKERS`]). Refused as
/// bad input: a file, a directory with anything else in it, `/`, the current
/// directory or one of its parents. Returns the path to write (lexically
/// normalised; resolved through symbolic links when it exists).
pub fn check_destination(dest: &Path) -> Result<PathBuf> {
    // `a/./b/` → `a/b`, so that parent and file name are the real ones.
    let norm: PathBuf = dest.components().collect();
    // No other process is half-way through replacing an output here.
    let _lock = ParentLock::take(&lock_dir(&norm), false)?;
    check_unlocked(dest, norm)
}

/// [`check_destination`] of `dest` (normalised as `norm`) under a lock the
/// caller holds.
fn check_unlocked(dest: &Path, norm: PathBuf) -> Result<PathBuf> {
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

/// Whether a rename failed because its target is taken (`EEXIST`,
/// `ENOTEMPTY`, `ENOTDIR`, `EISDIR`): someone else put something there.
fn is_occupied(e: &std::io::Error) -> bool {
    use std::io::ErrorKind as K;
    matches!(
        e.kind(),
        K::AlreadyExists | K::DirectoryNotEmpty | K::NotADirectory | K::IsADirectory
    )
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
/// it had to create; on a signal, [`crate::interrupt`] removes them: a failed
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
        let mut reg = crate::interrupt::registry();
        if let Err(e) = fs::create_dir_all(&parent) {
            crate::interrupt::remove_created(&created);
            return Err(e).with_context(|| format!("creating {}", parent.display()));
        }
        let mut i = 0u32;
        let tmp = loop {
            let cand = sibling(&parent, "tmp", i);
            match fs::create_dir(&cand) {
                Ok(()) => break cand,
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && i < 1000 => i += 1,
                Err(e) => {
                    crate::interrupt::remove_created(&created);
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
        // Every output carries its marker (registered in OUTPUT_MARKERS):
        // otherwise it could not be replaced by its own command later.
        if !OUTPUT_MARKERS.iter().any(|m| self.tmp.join(m).is_file()) {
            anyhow::bail!(
                "internal error: the output for {} holds none of {}: its writer must write (and register in output::OUTPUT_MARKERS) its marker file",
                self.dest.display(),
                OUTPUT_MARKERS.join(", ")
            );
        }
        // A Python call interrupted by Ctrl-C leaves nothing behind.
        if crate::cancel::requested() {
            return Err(crate::cancel::Cancelled.into());
        }
        // A signal arriving now waits until the output is in place.
        let mut reg = crate::interrupt::registry();
        let moved = self.move_into_place();
        if moved.is_ok() {
            self.committed = true;
            reg.remove(self.id);
        }
        drop(reg);
        moved
    }

    /// Under the parent folder's exclusive lock: the destination checked
    /// again, the old output renamed aside, the new one renamed in, the old
    /// one removed. Two ehservo processes replacing one folder take turns
    /// (the last one's output stays); a change made meanwhile by anything
    /// else is an I/O error (exit 1) that says what happened, and leaves
    /// the folder as that change left it.
    fn move_into_place(&self) -> Result<()> {
        let norm: PathBuf = self.dest.components().collect();
        let lock = ParentLock::take(&lock_dir(&norm), true)?;
        let dest = match check_unlocked(&self.dest, norm) {
            Ok(d) => d,
            // It was a valid destination when the command began
            // (Staging::new): something else changed it during the run.
            Err(e) if crate::error::is_bad_input(&e) => anyhow::bail!(
                "{} was changed by another process while this command ran ({e:#}): this output was not written",
                self.dest.display()
            ),
            Err(e) => return Err(e),
        };
        let moving = || format!("moving {} to {}", self.tmp.display(), dest.display());
        let lost = |e: std::io::Error| {
            anyhow::anyhow!(
                "{}: another process wrote this folder while this one was putting its output there ({e}): this output was not written",
                dest.display()
            )
        };
        if fs::symlink_metadata(&dest).is_err() {
            return fs::rename(&self.tmp, &dest).map_err(|e| {
                if is_occupied(&e) {
                    lost(e)
                } else {
                    anyhow::Error::from(e).context(moving())
                }
            });
        }
        // Beside `dest`: renaming it aside never crosses a file system.
        let parent = parent_of(&dest);
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
            // Put the previous output back; if something took its place
            // meanwhile, keep the previous one rather than strand it.
            return match fs::rename(&aside, &dest) {
                Ok(()) if is_occupied(&e) => Err(lost(e)),
                Ok(()) => Err(anyhow::Error::from(e).context(moving())),
                Err(back) => {
                    crate::interrupt::remove_tree(&aside);
                    Err(lost(e).context(format!(
                        "the previous output could not be put back ({back}) and was removed"
                    )))
                }
            };
        }
        drop(lock);
        crate::interrupt::remove_tree(&aside);
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let mut reg = crate::interrupt::registry();
            crate::interrupt::remove_tree(&self.tmp);
            crate::interrupt::remove_created(&self.created);
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
