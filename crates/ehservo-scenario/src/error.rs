//! Errors by kind. Input the user can fix is one of three types, one per
//! layer that reads input: [`InputError`] (a study, a tune or league file,
//! a manifest, a shard, a flag, an input file that is missing or
//! unreadable),
//! the scenario's structured [`ScenarioError`](crate::scenario::ScenarioError)
//! (file, key, line and column, reason), and the `no_std` core's
//! [`ParamError`](ehservo_core::error::ParamError) (a law's parameters,
//! which cannot depend on std's `Error`). A new kind of bad input is an
//! [`InputError`] (or carries one in its chain): it needs no new line here.
//! Everything else is a failure of the machine (an output that cannot be
//! written, a full disk). The command line's exit code follows the kind
//! found in the error's chain, never the place it was raised: bad input 2,
//! anything else 1.

use ehservo_sim::error::Reason;

/// Input the user can fix, other than a scenario: a study, tune, league
/// or manifest file's key, such a file as a whole, or a command line's
/// flag. Every variant is bad input (exit code 2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// A key of an input file.
    #[error("{file}{}: `{key}`: {reason}", at(*.line_col))]
    Key {
        /// The file.
        file: String,
        /// 1-based line and column of the key, when known.
        line_col: Option<(usize, usize)>,
        /// The key path in it (`tuning.budget`, `axis[0].values`).
        key: String,
        /// Why.
        reason: Reason,
    },
    /// An input file as a whole (unreadable, not TOML, a base scenario that
    /// does not build).
    #[error("{file}{}: {reason}", at(*.line_col))]
    File {
        /// The file.
        file: String,
        /// 1-based line and column, when known.
        line_col: Option<(usize, usize)>,
        /// Why.
        reason: Reason,
    },
    /// A command-line request: the sentence names the flag and its value.
    #[error("{0}")]
    Request(String),
}

/// `:line:column` or nothing.
fn at(line_col: Option<(usize, usize)>) -> String {
    line_col
        .map(|(l, c)| format!(":{l}:{c}"))
        .unwrap_or_default()
}

impl InputError {
    /// Key `key` of `file` refused for `reason`.
    pub fn key(file: impl Into<String>, key: impl Into<String>, reason: impl Into<Reason>) -> Self {
        Self::Key {
            file: file.into(),
            line_col: None,
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// `file` refused as a whole for `reason`.
    pub fn file(file: impl Into<String>, reason: impl Into<Reason>) -> Self {
        Self::File {
            file: file.into(),
            line_col: None,
            reason: reason.into(),
        }
    }

    /// The key at fault, if one is.
    pub fn key_path(&self) -> Option<&str> {
        match self {
            Self::Key { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// `Err(InputError::Request(format!(...)))` as an `anyhow::Error`.
#[macro_export]
macro_rules! bad_input {
    ($($arg:tt)*) => {
        return Err(anyhow::Error::from($crate::error::InputError::Request(format!($($arg)*))))
    };
}

/// The longest error line the command line prints (characters): a net
/// under the messages, which are written to stay under about 300 (their
/// quotes of a file's content cut at the source, [`quote_start`](ehservo_sim::error::quote_start));
/// a few name a long path and list the known keys, so the net is wider.
pub const MAX_ERROR_CHARS: usize = 1000;

/// An error message as the command line prints it: a line longer than
/// [`MAX_ERROR_CHARS`] (one that quotes too much of what a file holds,
/// where the quote was not cut at its source by
/// [`quote_start`](ehservo_sim::error::quote_start)) keeps its start (the
/// file, the key) and its end (what to do), and says how long it was.
///
/// ```
/// use ehservo_scenario::error::{one_line, MAX_ERROR_CHARS};
/// assert_eq!(one_line("x.csv: line 1: bad"), "x.csv: line 1: bad");
/// let long = format!(
///     "x.csv: the header has: {}; name it with --time",
///     "a,".repeat(10_000)
/// );
/// let l = one_line(&long);
/// assert!(l.chars().count() <= MAX_ERROR_CHARS, "{l}");
/// assert!(l.starts_with("x.csv: the header has: a,a,"));
/// // 23 + 2·10000 + 21 characters.
/// assert!(l.contains("[20044 characters, cut]"), "{l}");
/// assert!(l.ends_with("a,a,; name it with --time"), "{l}");
/// ```
pub fn one_line(msg: &str) -> String {
    msg.split('\n').map(cut).collect::<Vec<_>>().join("\n")
}

/// One line cut to [`MAX_ERROR_CHARS`]: its start and its last 300
/// characters.
fn cut(line: &str) -> String {
    const TAIL: usize = 300;
    let n = line.chars().count();
    if n <= MAX_ERROR_CHARS {
        return line.to_string();
    }
    let mid = format!(" … [{n} characters, cut] … ");
    let head = MAX_ERROR_CHARS - TAIL - mid.chars().count();
    let start: String = line.chars().take(head).collect();
    let end: String = line.chars().skip(n - TAIL).collect();
    start + &mid + &end
}

/// Whether any cause in the chain is bad input.
pub fn is_bad_input(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.is::<InputError>()
            || c.is::<crate::scenario::ScenarioError>()
            || c.is::<ehservo_core::error::ParamError>()
    })
}

/// The process exit code for an error: 2 for bad input, 1 otherwise.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    if is_bad_input(e) {
        2
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn the_kind_decides_the_code_wherever_it_was_raised() {
        let io: anyhow::Error = std::io::Error::other("disk full").into();
        assert_eq!(exit_code(&io), 1);
        let bad = anyhow::Error::from(InputError::file("merge.toml", "shard 2 of 3 missing"));
        assert_eq!(exit_code(&bad), 2);
        // Context added on the way up does not change the kind.
        let wrapped = Err::<(), _>(bad).context("merging").unwrap_err();
        assert_eq!(exit_code(&wrapped), 2);
        let f = || -> anyhow::Result<()> { bad_input!("`{}`: must be > 0", "x") };
        assert_eq!(exit_code(&f().unwrap_err()), 2);
    }
}
