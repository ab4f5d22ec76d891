//! QEMU's `mps2-an386` with the PIL firmware, started and stopped by its
//! process id.

use super::transport::Reset;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The firmware's ELF, where `cargo build --release` in
/// `examples/firmware-pil` puts it.
pub const FIRMWARE_RELPATH: &str = "thumbv7em-none-eabihf/release/ehservo-firmware-pil";

/// Where to look for the firmware: beside this program's target folder
/// (`target/release/ehservo` → `target/thumbv7em-none-eabihf/…`), then
/// `$CARGO_TARGET_DIR`, then `target/` of the working directory.
pub fn default_firmware() -> Option<PathBuf> {
    let mut c = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        // target/<profile>/ehservo, or target/<profile>/deps/<test binary>.
        for up in exe.ancestors().skip(2).take(2) {
            c.push(up.join(FIRMWARE_RELPATH));
        }
    }
    if let Some(d) = std::env::var_os("CARGO_TARGET_DIR") {
        c.push(PathBuf::from(d).join(FIRMWARE_RELPATH));
    }
    c.push(PathBuf::from("target").join(FIRMWARE_RELPATH));
    c.into_iter().find(|p| p.is_file())
}

/// A running QEMU; killed (by its process id) when dropped.
pub struct Qemu {
    child: Option<Child>,
    pid: u32,
    dir: tempfile_dir::TempDir,
    monitor: PathBuf,
}

/// A small temporary folder (QEMU's logs and monitor socket).
mod tempfile_dir {
    use std::path::{Path, PathBuf};

    /// Removed when dropped.
    pub struct TempDir(PathBuf);

    impl TempDir {
        pub fn new() -> std::io::Result<Self> {
            let base = std::env::temp_dir();
            for i in 0..1000u32 {
                let p = base.join(format!("ehservo-qemu-{}-{i}", std::process::id()));
                match std::fs::create_dir(&p) {
                    Ok(()) => return Ok(Self(p)),
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                    Err(e) => return Err(e),
                }
            }
            Err(std::io::Error::other("no free temporary folder name"))
        }
        pub fn path(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

impl Qemu {
    /// Starts `qemu-system-arm` with `firmware` and its UART0 on `serial`
    /// (a QEMU `-serial` backend, e.g. `tcp:127.0.0.1:5555,nodelay=on`),
    /// under `-icount shift=0` (one instruction per 1 ns: the firmware's
    /// SysTick ticks then count instructions, 40 a tick).
    pub fn start(firmware: &Path, serial: &str) -> Result<Self> {
        let dir = tempfile_dir::TempDir::new().context("a temporary folder for QEMU")?;
        let monitor = dir.path().join("monitor.sock");
        let log = std::fs::File::create(dir.path().join("qemu.log"))?;
        let child = Command::new("qemu-system-arm")
            .args(["-cpu", "cortex-m4", "-machine", "mps2-an386"])
            .args(["-display", "none"])
            .arg("-monitor")
            .arg(format!("unix:{},server=on,wait=off", monitor.display()))
            .args(["-icount", "shift=0,align=off,sleep=off"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .args(["-serial", serial])
            .arg("-kernel")
            .arg(firmware)
            .stdin(Stdio::null())
            .stdout(log.try_clone()?)
            .stderr(log)
            .spawn()
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    anyhow::anyhow!(
                        "qemu-system-arm is not installed (Debian: apt-get install qemu-system-arm)"
                    )
                } else {
                    anyhow::Error::from(e).context("starting qemu-system-arm")
                }
            })?;
        let pid = child.id();
        crate::interrupt::add_child(pid);
        Ok(Self {
            child: Some(child),
            pid,
            dir,
            monitor,
        })
    }

    /// Its process id.
    pub fn pid(&self) -> u32 {
        self.pid
    }

    /// Whether it has exited, with what it printed.
    pub fn exited(&mut self) -> Option<String> {
        let c = self.child.as_mut()?;
        match c.try_wait() {
            Ok(Some(status)) => Some(format!("QEMU exited ({status}): {}", self.log_tail())),
            _ => None,
        }
    }

    /// The last lines QEMU (and the firmware's semihosting) printed.
    pub fn log_tail(&self) -> String {
        let s = std::fs::read_to_string(self.dir.path().join("qemu.log")).unwrap_or_default();
        let lines: Vec<&str> = s.lines().rev().take(5).collect();
        let t: Vec<&str> = lines.into_iter().rev().collect();
        if t.is_empty() {
            "(it printed nothing)".into()
        } else {
            t.join(" | ")
        }
    }

    /// A handle that resets the emulated board (QEMU's `system_reset`).
    pub fn resetter(&self) -> Box<dyn Reset> {
        Box::new(MonitorReset(self.monitor.clone()))
    }

    /// Stops QEMU: SIGKILL to its process id, then waits for it.
    pub fn stop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
            crate::interrupt::remove_child(self.pid);
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        self.stop();
    }
}

struct MonitorReset(PathBuf);

impl Reset for MonitorReset {
    fn reset(&mut self) -> std::io::Result<()> {
        let mut s = std::os::unix::net::UnixStream::connect(&self.0)?;
        s.write_all(b"system_reset\n")?;
        // The monitor acts on the line as it reads it; give it the moment.
        let until = Instant::now() + Duration::from_millis(50);
        while Instant::now() < until {
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    }
}
