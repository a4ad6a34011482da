//! Opening the files maobi reads as input.

use std::fs::File;
use std::path::Path;

/// Opens `path` for reading if it is a regular file (following links). A device, FIFO or
/// folder is refused before it is opened: opening a FIFO blocks until a writer comes, and a
/// device such as `/dev/zero` never ends. Read the file through `take(max + 1)` so that one
/// growing while it is read still cannot exceed a bound.
///
/// # Examples
/// ```
/// let err = brush_model::open_regular(std::path::Path::new("/dev/null")).unwrap_err();
/// assert!(err.to_string().contains("not a regular file"));
/// ```
///
/// # Errors
/// The metadata or open error, or [`std::io::ErrorKind::InvalidInput`] for anything but a
/// regular file.
pub fn open_regular(path: &Path) -> std::io::Result<File> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() { "a folder" } else { "a device, FIFO or socket" };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("not a regular file ({what}): expected a file"),
        ));
    }
    File::open(path)
}

/// Reads a regular file ([`open_regular`]) of at most `max_bytes`; `Ok(None)` when it holds
/// more (only `max_bytes + 1` bytes are read to tell).
///
/// # Errors
/// As [`open_regular`], and the read's error.
pub fn read_regular(path: &Path, max_bytes: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read;
    let file = open_regular(path)?;
    let mut bytes = Vec::new();
    file.take(max_bytes.saturating_add(1)).read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= max_bytes).then_some(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_folders_are_refused_and_files_are_bounded() {
        let dir = std::env::temp_dir();
        assert!(open_regular(&dir).unwrap_err().to_string().contains("a folder"));
        assert!(read_regular(Path::new("/dev/zero"), 10).unwrap_err().to_string().contains("a device"));
        let f = dir.join(format!("brush-model-input-{}.txt", std::process::id()));
        std::fs::write(&f, b"12345").unwrap();
        let (fits, over) = (read_regular(&f, 5).unwrap(), read_regular(&f, 4).unwrap());
        std::fs::remove_file(&f).unwrap();
        assert_eq!(fits.as_deref(), Some(&b"12345"[..]));
        assert_eq!(over, None);
    }
}
