//! What an interrupted process leaves behind: nothing.
//!
//! Every [`Staging`](crate::output::Staging) directory that is alive (made,
//! not yet committed or dropped) is listed here, with the parent folders it
//! had to create. The command line calls [`install`] once: on `SIGINT`,
//! `SIGTERM` or `SIGHUP` (Ctrl-C, a cluster's time limit, a closed
//! terminal) the handler removes every listed directory and ends the process
//! with [`EXIT_CODE`]. A commit holds the list's lock while it moves the
//! output into place, so a signal that arrives then waits for the commit to
//! finish: the output folder is either the old one or the new one, whole.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// The exit code after a signal, whichever of `SIGINT`, `SIGTERM` or
/// `SIGHUP` it was (the handler is not told which): 130, the shells'
/// "interrupted".
pub const EXIT_CODE: i32 = 130;

/// A live staging directory and the folders made for it, deepest first.
#[derive(Debug)]
#[cfg_attr(not(feature = "cli"), allow(dead_code))] // read by the handler
struct Entry {
    id: u64,
    tmp: PathBuf,
    created: Vec<PathBuf>,
}

/// The live staging directories.
#[derive(Debug)]
pub(crate) struct Registry {
    next: u64,
    live: Vec<Entry>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    next: 0,
    live: Vec::new(),
});

/// Child processes to stop with the command (`ehservo pil --qemu`'s QEMU),
/// by process id.
static CHILDREN: Mutex<Vec<u32>> = Mutex::new(Vec::new());

/// Lists a child process for the handler to kill.
pub(crate) fn add_child(pid: u32) {
    CHILDREN.lock().unwrap_or_else(|e| e.into_inner()).push(pid);
}

/// Takes a child off the list (it has been stopped and waited for).
pub(crate) fn remove_child(pid: u32) {
    CHILDREN
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|&p| p != pid);
}

/// Kills the listed children (SIGKILL, by process id).
#[cfg(all(feature = "cli", unix))]
fn kill_children() {
    let pids = CHILDREN.lock().unwrap_or_else(|e| e.into_inner()).clone();
    for pid in pids {
        if let Ok(p) = i32::try_from(pid) {
            let _ =
                nix::sys::signal::kill(nix::unistd::Pid::from_raw(p), nix::sys::signal::SIGKILL);
        }
    }
}

/// The registry, locked (a panic elsewhere does not make it unusable).
pub(crate) fn registry() -> MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

impl Registry {
    /// Lists `tmp` (and the parents `created` for it, deepest first);
    /// returns the key for [`Registry::remove`].
    pub(crate) fn add(&mut self, tmp: PathBuf, created: Vec<PathBuf>) -> u64 {
        self.next += 1;
        self.live.push(Entry {
            id: self.next,
            tmp,
            created,
        });
        self.next
    }

    /// Takes an entry off the list (after a commit, or after its own
    /// cleanup).
    pub(crate) fn remove(&mut self, id: u64) {
        self.live.retain(|e| e.id != id);
    }

    /// Removes every listed directory from the disk and empties the list.
    #[cfg_attr(not(feature = "cli"), allow(dead_code))]
    fn clean_all(&mut self) {
        for e in self.live.drain(..) {
            remove_tree(&e.tmp);
            remove_created(&e.created);
        }
    }
}

/// Removes a directory tree (or a single file: `ehservo fmu`'s temporary
/// archive); retried because a thread still writing into it may add an
/// entry between the listing and the final `rmdir`.
pub(crate) fn remove_tree(dir: &std::path::Path) {
    if std::fs::symlink_metadata(dir).is_ok_and(|m| !m.is_dir()) {
        let _ = std::fs::remove_file(dir);
        return;
    }
    for _ in 0..5 {
        match std::fs::remove_dir_all(dir) {
            Ok(()) => return,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return,
            Err(_) => {}
        }
    }
}

/// Removes folders made for a staging directory, deepest first, each only
/// while empty (someone else may have put something there meanwhile).
pub(crate) fn remove_created(created: &[PathBuf]) {
    for d in created {
        if std::fs::remove_dir(d).is_err() {
            break;
        }
    }
}

/// A temporary file (not a staging folder) that a signal must remove:
/// listed until the guard is dropped.
#[derive(Debug)]
pub struct TempFile {
    id: u64,
}

impl TempFile {
    /// Lists `path` for removal on a signal.
    pub fn register(path: std::path::PathBuf) -> TempFile {
        TempFile {
            id: registry().add(path, Vec::new()),
        }
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        registry().remove(self.id);
    }
}

/// Installs the handler for `SIGINT`, `SIGTERM` and `SIGHUP`: remove every
/// live staging directory, then exit with [`EXIT_CODE`]. Call once, early.
///
/// It also makes `SIGXFSZ` (a file-size limit, `ulimit -f`, reached)
/// ignored: a write beyond the limit then fails with `EFBIG`, which is
/// reported and cleaned up as a full disk is (exit 1), instead of the
/// signal killing the process with its staging folder half-written.
#[cfg(feature = "cli")]
pub fn install() -> Result<(), ctrlc::Error> {
    ignore_sigxfsz();
    ctrlc::set_handler(|| {
        SIGNALLED.store(true, std::sync::atomic::Ordering::SeqCst);
        #[cfg(unix)]
        kill_children();
        // Waits for a commit in progress; never released: the process ends.
        let mut reg = registry();
        reg.clean_all();
        std::process::exit(EXIT_CODE);
    })
}

/// `SIGXFSZ` ignored (see [`install`]).
#[cfg(all(feature = "cli", unix))]
#[allow(unsafe_code)]
fn ignore_sigxfsz() {
    use nix::sys::signal::{signal, SigHandler, Signal};
    // SAFETY: SIG_IGN installs no handler code, so nothing can run in a
    // signal context; the call only changes the disposition.
    let _ = unsafe { signal(Signal::SIGXFSZ, SigHandler::SigIgn) };
}

#[cfg(all(feature = "cli", not(unix)))]
fn ignore_sigxfsz() {}

/// Set by the handler of [`install`] as it starts.
static SIGNALLED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a signal that ends the run (`SIGINT`, `SIGTERM`, `SIGHUP`) has
/// reached the handler.
pub fn signalled() -> bool {
    SIGNALLED.load(std::sync::atomic::Ordering::SeqCst)
}

/// When a signal has reached the handler, this never returns: the
/// handler removes the staging folders and exits with [`EXIT_CODE`] (this
/// waits for it on the registry it holds), or, should this take the
/// registry first, this does the same. Called by `main` before it
/// reports an error, so that the error a signal caused (a read cut
/// short) never beats the handler's exit code.
pub fn exit_if_signalled() {
    if signalled() {
        #[cfg(all(feature = "cli", unix))]
        kill_children();
        let mut reg = registry();
        reg.clean_all();
        std::process::exit(EXIT_CODE);
    }
}

/// How many staging directories are alive (for tests).
pub fn live_staging_dirs() -> usize {
    registry().live.len()
}
