//! Errors by kind. Input the user can fix is one of three types, one per
//! layer that reads input: [`InputError`] (a study, a tune or league file,
//! a manifest, a shard, a flag, an input file that is missing or
//! unreadable; the study's `StudyError` is this type under another name),
//! the scenario's structured [`ScenarioError`](crate::scenario::ScenarioError)
//! (file, key, line and column, reason), and the `no_std` core's
//! [`ParamError`](ehservo_core::error::ParamError) (a law's parameters,
//! which cannot depend on std's `Error`). A new kind of bad input is an
//! [`InputError`] (or carries one in its chain): it needs no new line here.
//! Everything else is a failure of the machine (an output that cannot be
//! written, a full disk). The command line's exit code follows the kind
//! found in the error's chain, never the place it was raised: bad input 2,
//! anything else 1.

use std::fmt;

/// Input the user can fix, with the file, key and reason in its message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputError(pub String);

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InputError {}

/// `Err(InputError(format!(...)))` as an `anyhow::Error`.
#[macro_export]
macro_rules! bad_input {
    ($($arg:tt)*) => {
        return Err(anyhow::Error::from($crate::error::InputError(format!($($arg)*))))
    };
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
        let bad = anyhow::Error::from(InputError("shard 2 of 3 missing".into()));
        assert_eq!(exit_code(&bad), 2);
        // Context added on the way up does not change the kind.
        let wrapped = Err::<(), _>(bad).context("merging").unwrap_err();
        assert_eq!(exit_code(&wrapped), 2);
        let f = || -> anyhow::Result<()> { bad_input!("`{}`: must be > 0", "x") };
        assert_eq!(exit_code(&f().unwrap_err()), 2);
    }
}
