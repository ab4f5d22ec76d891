//! The `ehservo` command line.
//!
//! Exit codes:
//! - 0: done;
//! - 1: the machine failed: an output that cannot be written, a full
//!   disk, standard output that cannot be written (`> /dev/full`: one line,
//!   `error: writing to stdout: …`) or that was closed by its reader
//!   (`| head -1`, `| true`: no message at all, the reader has gone);
//! - 2: bad input (a scenario, a flag, an output folder that is not ours,
//!   an input file that is missing, unreadable, not a file or too large);
//! - 130: interrupted by `SIGINT`, `SIGTERM` or `SIGHUP`; the staging
//!   folders of the outputs being written are removed, the previous outputs
//!   stay as they were ([`ehservo::interrupt`]).

use clap::Parser;
use ehservo::cli::{closed_stdout, dispatch, Cli, StdoutError};
use std::io::Write;
use std::process::ExitCode;

/// A line on standard error; if even that fails there is nowhere left to
/// say so.
macro_rules! note {
    ($($arg:tt)*) => {
        let _ = writeln!(std::io::stderr(), $($arg)*);
    };
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version go to stdout (and follow its rules),
            // usage errors to stderr (exit 2 whatever becomes of them).
            let printed = e.print().and_then(|()| std::io::stdout().flush());
            return match printed {
                Err(io) if !e.use_stderr() => {
                    if io.kind() != std::io::ErrorKind::BrokenPipe {
                        note!("error: writing to stdout: {io}");
                    }
                    ExitCode::from(1)
                }
                _ => ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2)),
            };
        }
    };
    // Without it a signal still ends the process, but leaves the staging
    // folders; that is all a failure here costs.
    if let Err(e) = ehservo::interrupt::install() {
        note!("warning: no handler for Ctrl-C and SIGTERM: {e}");
    }
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    let done = dispatch(cli, &mut w).and_then(|()| Ok(w.flush().map_err(StdoutError)?));
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if closed_stdout(&e) => ExitCode::from(1),
        Err(e) => {
            // An error a signal caused: the handler's exit code, 130.
            ehservo::interrupt::exit_if_signalled();
            note!("{}", ehservo::error::one_line(&format!("error: {e:#}")));
            ExitCode::from(ehservo::error::exit_code(&e))
        }
    }
}
