//! Reading input files with a bound: a scenario, study or manifest is a
//! small text file, so a device (`/dev/zero`), a directory or a file of
//! hundreds of megabytes is refused before it is read into memory.

use std::io::Read;
use std::path::Path;

/// Largest input file read (bytes): 1 MiB, some thousand times a real
/// scenario, study or manifest.
pub const MAX_INPUT_BYTES: u64 = 1 << 20;

/// The text of `path`, refused (with the reason) when it is not a regular
/// file, is larger than [`MAX_INPUT_BYTES`], or is not UTF-8.
pub fn read_text(path: &Path) -> Result<String, String> {
    read_text_at_most(path, MAX_INPUT_BYTES)
}

/// Largest logged data file `ehservo identify` reads (bytes): 256 MiB,
/// some minutes of a rig's log at 1 kHz with a dozen columns.
pub const MAX_DATA_BYTES: u64 = 256 << 20;

/// [`read_text`] with another bound (a logged data file is larger than a
/// scenario).
pub fn read_text_at_most(path: &Path, limit: u64) -> Result<String, String> {
    let max = limit;
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot be read: {e}"))?;
    if !meta.is_file() {
        return Err("is not a regular file".into());
    }
    if meta.len() > max {
        return Err(format!(
            "is {} bytes; an input file is at most {max} bytes",
            meta.len()
        ));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(max + 1).read_to_end(&mut bytes))
        .map_err(|e| format!("cannot be read: {e}"))?;
    if bytes.len() as u64 > max {
        return Err(format!("is larger than {max} bytes"));
    }
    String::from_utf8(bytes).map_err(|e| format!("is not UTF-8 text: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_huge_files_are_refused() {
        assert!(read_text(Path::new("/dev/zero"))
            .unwrap_err()
            .contains("regular"));
        assert!(read_text(Path::new("/")).unwrap_err().contains("regular"));
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.toml");
        std::fs::write(&big, vec![b'#'; (MAX_INPUT_BYTES + 1) as usize]).unwrap();
        assert!(read_text(&big).unwrap_err().contains("at most"));
        let bin = dir.path().join("bin.toml");
        std::fs::write(&bin, [0xff, 0xfe]).unwrap();
        assert!(read_text(&bin).unwrap_err().contains("UTF-8"));
        let ok = dir.path().join("ok.toml");
        std::fs::write(&ok, "name = \"x\"\n").unwrap();
        assert_eq!(read_text(&ok).unwrap(), "name = \"x\"\n");
    }
}
