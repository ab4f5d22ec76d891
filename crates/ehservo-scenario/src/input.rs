//! Reading input files with a bound: a scenario, study or manifest is a
//! small text file, so a device (`/dev/zero`), a directory or a file of
//! hundreds of megabytes is refused before it is read into memory; a file
//! that holds a NUL byte is not text, and is refused at the first chunk
//! that shows one, before the rest is read.
//!
//! A message that quotes what a file holds quotes its start only
//! ([`quote_start`]): no error line grows with the input.

use std::io::Read;
use std::path::Path;

/// Largest input file read (bytes): 1 MiB, some thousand times a real
/// scenario, study or manifest.
pub const MAX_INPUT_BYTES: u64 = 1 << 20;

/// Why an input file was refused; its message reads after the file's
/// name ("… scenario.toml is not a regular file").
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ReadError {
    /// The system could not read it.
    #[error("cannot be read: {0}")]
    Io(String),
    /// A directory, a device, a pipe.
    #[error("is not a regular file")]
    NotRegular,
    /// Larger than the bound.
    #[error("is {size} bytes; an input file is at most {max} bytes")]
    TooLarge {
        /// Its size (bytes).
        size: u64,
        /// The bound (bytes).
        max: u64,
    },
    /// It grew beyond the bound while it was read.
    #[error("is larger than {max} bytes")]
    Grew {
        /// The bound (bytes).
        max: u64,
    },
    /// Not UTF-8.
    #[error("is not UTF-8 text: {0}")]
    NotUtf8(String),
    /// A NUL byte: a binary file, not text.
    #[error("is not text: byte {offset} is NUL (0x00)")]
    Binary {
        /// The 0-based offset of the first NUL byte.
        offset: u64,
    },
}

pub use ehservo_sim::error::{quote_start, QUOTE_CHARS};

/// The text of `path`, refused (with the reason) when it is not a regular
/// file, is larger than [`MAX_INPUT_BYTES`], or is not UTF-8.
///
/// ```
/// use ehservo_scenario::input::{read_text, ReadError};
/// assert_eq!(read_text(std::path::Path::new("/")), Err(ReadError::NotRegular));
/// ```
pub fn read_text(path: &Path) -> Result<String, ReadError> {
    read_text_at_most(path, MAX_INPUT_BYTES)
}

/// Largest logged data file `ehservo identify` reads (bytes): 256 MiB,
/// some minutes of a rig's log at 1 kHz with a dozen columns.
pub const MAX_DATA_BYTES: u64 = 256 << 20;

/// [`read_text`] with another bound (a logged data file is larger than a
/// scenario).
pub fn read_text_at_most(path: &Path, limit: u64) -> Result<String, ReadError> {
    let max = limit;
    let meta = std::fs::metadata(path).map_err(|e| ReadError::Io(e.to_string()))?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular);
    }
    if meta.len() > max {
        return Err(ReadError::TooLarge {
            size: meta.len(),
            max,
        });
    }
    let bytes = read_bounded(path, max)?;
    String::from_utf8(bytes).map_err(|e| ReadError::NotUtf8(e.to_string()))
}

/// The bytes of `path`, at most `max`, read a chunk at a time: a NUL byte
/// stops the read at the chunk that holds it.
fn read_bounded(path: &Path, max: u64) -> Result<Vec<u8>, ReadError> {
    let io = |e: std::io::Error| ReadError::Io(e.to_string());
    let mut f = std::fs::File::open(path).map_err(io)?.take(max + 1);
    let mut bytes = Vec::new();
    let mut chunk = vec![0u8; 64 << 10];
    loop {
        let n = match f.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        if let Some(i) = chunk[..n].iter().position(|b| *b == 0) {
            return Err(ReadError::Binary {
                offset: (bytes.len() + i) as u64,
            });
        }
        bytes.extend_from_slice(&chunk[..n]);
    }
    if bytes.len() as u64 > max {
        return Err(ReadError::Grew { max });
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_huge_files_are_refused() {
        assert_eq!(
            read_text(Path::new("/dev/zero")),
            Err(ReadError::NotRegular)
        );
        assert_eq!(read_text(Path::new("/")), Err(ReadError::NotRegular));
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.toml");
        std::fs::write(&big, vec![b'#'; (MAX_INPUT_BYTES + 1) as usize]).unwrap();
        assert_eq!(
            read_text(&big),
            Err(ReadError::TooLarge {
                size: MAX_INPUT_BYTES + 1,
                max: MAX_INPUT_BYTES
            })
        );
        assert!(read_text(&big).unwrap_err().to_string().contains("at most"));
        let bin = dir.path().join("bin.toml");
        std::fs::write(&bin, [0xff, 0xfe]).unwrap();
        assert!(matches!(read_text(&bin), Err(ReadError::NotUtf8(_))));
        // A NUL byte: refused at the first chunk, with where it is.
        let nul = dir.path().join("nul.csv");
        let mut text = b"t,theta_deg\n".to_vec();
        text.extend(vec![0u8; 200_000]);
        std::fs::write(&nul, &text).unwrap();
        assert_eq!(read_text(&nul), Err(ReadError::Binary { offset: 12 }));
        let ok = dir.path().join("ok.toml");
        std::fs::write(&ok, "name = \"x\"\n").unwrap();
        assert_eq!(read_text(&ok).unwrap(), "name = \"x\"\n");
    }
}
