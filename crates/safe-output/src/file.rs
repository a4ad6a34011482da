//! Single files: where a write must go, atomic writes, writes kept under a root, and the check
//! before replacing an existing file.

use std::fs::File;
use std::io::Write;
use std::path::{Component, Path, PathBuf};

use crate::interrupt::{TempGuard, output_gate};
use crate::{Error, Names};

/// Where writing `path` must go: the path itself, or, through any symlinks, the file they point
/// to (a link is written through, never replaced).
///
/// # Errors
/// [`Error::NotRegular`] for a folder, FIFO, socket or device (writing would replace the node),
/// [`Error::TooManyLinks`], [`Error::Io`] when a link or the path's metadata cannot be read.
///
/// # Examples
/// ```
/// let dir = std::env::temp_dir();
/// // A path that does not exist yet is written as it is; a folder is refused.
/// let new = dir.join("safe-output-doc-target.txt");
/// assert_eq!(safe_output::output_target(&new).unwrap(), new);
/// assert!(safe_output::output_target(&dir).is_err());
/// ```
pub fn output_target(path: &Path) -> Result<PathBuf, Error> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(p),
            Err(e) => return Err(Error::Io { action: "cannot write", path: path.to_path_buf(), source: e }),
            Ok(m) if m.file_type().is_symlink() => {
                let t = std::fs::read_link(&p).map_err(Error::io("cannot read the link", &p))?;
                p = match p.parent() {
                    Some(dir) if t.is_relative() => dir.join(t),
                    _ => t,
                };
            }
            Ok(m) if m.is_file() => return Ok(p),
            Ok(m) => {
                let target = (p != path).then_some(p);
                return Err(Error::NotRegular { path: path.to_path_buf(), target, kind: node_kind(&m.file_type()) });
            }
        }
    }
    Err(Error::TooManyLinks { path: path.to_path_buf() })
}

/// What a node that is not a regular file is, for [`Error::NotRegular`].
fn node_kind(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            "a FIFO"
        } else if ft.is_char_device() || ft.is_block_device() {
            "a device"
        } else if ft.is_socket() {
            "a socket"
        } else if ft.is_dir() {
            "a folder"
        } else {
            "not a regular file"
        }
    }
    #[cfg(not(unix))]
    {
        if ft.is_dir() { "a folder" } else { "not a regular file" }
    }
}

/// A temporary file `.tmpXXXXXXXX.tmp` (private to its owner where the platform knows modes),
/// removed when dropped unless renamed away.
struct TempFile {
    path: PathBuf,
    file: File,
    renamed: bool,
}

impl TempFile {
    /// Creates a new temporary file in `dir`, a name no other file has.
    fn new_in(dir: &Path) -> std::io::Result<Self> {
        use std::hash::{BuildHasher, Hasher};
        static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let mut last = None;
        for _ in 0..100 {
            // A randomly keyed hash of the process, a counter and the time: unguessable enough
            // for a name that `create_new` claims anyway.
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_u32(std::process::id());
            h.write_u64(COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed));
            h.write_u128(
                std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos()),
            );
            let path = dir.join(format!(".tmp{:08x}.tmp", h.finish() as u32));
            let mut open = std::fs::OpenOptions::new();
            open.write(true).create_new(true);
            #[cfg(unix)]
            std::os::unix::fs::OpenOptionsExt::mode(&mut open, 0o600);
            match open.open(&path) {
                Ok(file) => return Ok(TempFile { path, file, renamed: false }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or_else(|| std::io::Error::from(std::io::ErrorKind::AlreadyExists)))
    }

    /// Renames the file to `to` (replacing what is there).
    fn rename_to(mut self, to: &Path) -> std::io::Result<()> {
        std::fs::rename(&self.path, to)?;
        self.renamed = true;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.renamed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder, then renamed,
/// so a failure never leaves a half-written output. Creates the parent folder if needed. A
/// symlink is written through (its target is replaced, the link stays); folders, FIFOs, sockets
/// and devices are refused ([`output_target`]). The file gets mode 0644 on Unix. While it is
/// written the temporary file is registered for [`crate::remove_temporaries`], and the write
/// holds the [`crate::output_gate`].
///
/// # Errors
/// As [`output_target`]; [`Error::Io`] naming the folder or the file when one cannot be
/// created, written or renamed.
///
/// # Examples
/// ```
/// let dir = std::env::temp_dir().join(format!("safe-output-doc-atomic-{}", std::process::id()));
/// let path = dir.join("sub/result.json");
/// safe_output::write_atomic(&path, b"{}\n").unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"{}\n");
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// As [`write_atomic`], the bytes written by `fill` into a buffered writer (a large output is
/// never held whole in memory).
///
/// # Errors
/// As [`write_atomic`]; `fill`'s error as the source of [`Error::Io`] `cannot write` (turn
/// another error into an I/O error with `std::io::Error::other`).
///
/// # Examples
/// ```
/// use std::io::Write;
/// let path = std::env::temp_dir().join(format!("safe-output-doc-with-{}.csv", std::process::id()));
/// safe_output::write_atomic_with(&path, |w| {
///     for i in 0..3 {
///         writeln!(w, "{i},{}", i * i)?;
///     }
///     Ok(())
/// })
/// .unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "0,0\n1,1\n2,4\n");
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_atomic_with(path: &Path, fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<(), Error> {
    let target = output_target(path)?;
    let path = target.as_path();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // Held until the file is in place: the clean-up after a signal never removes a staging
    // folder while this re-creates it.
    let _gate = output_gate();
    std::fs::create_dir_all(dir).map_err(Error::io("cannot create folder", dir))?;
    let mut tmp = TempFile::new_in(dir).map_err(Error::io("cannot create a temporary file in", dir))?;
    let _guard = TempGuard::new(&tmp.path);
    {
        let mut w = std::io::BufWriter::new(&mut tmp.file);
        fill(&mut w).and_then(|()| w.flush()).map_err(Error::io("cannot write", path))?;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Temporary files are created private; outputs get the usual permissions.
        let _ = tmp.file.set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    tmp.rename_to(path).map_err(Error::io("cannot write", path))
}

/// Writes `bytes` to `root/rel` ([`write_atomic`]) after checking that `rel` is a relative path
/// of plain names (no `..`, no root, no prefix), so that the file stays under `root` whatever
/// `rel` came from (a name read from an untrusted file).
///
/// # Errors
/// [`Error::Outside`] for a `rel` that could leave `root`; as [`write_atomic`].
///
/// # Examples
/// ```
/// let root = std::env::temp_dir().join(format!("safe-output-doc-under-{}", std::process::id()));
/// safe_output::write_under(&root, "a/b.txt".as_ref(), b"ok").unwrap();
/// assert!(safe_output::write_under(&root, "../escape.txt".as_ref(), b"no").is_err());
/// # std::fs::remove_dir_all(&root).unwrap();
/// ```
pub fn write_under(root: &Path, rel: &Path, bytes: &[u8]) -> Result<(), Error> {
    if rel.as_os_str().is_empty() || !rel.components().all(|c| matches!(c, Component::Normal(_))) {
        return Err(Error::Outside { rel: rel.to_path_buf(), root: root.to_path_buf() });
    }
    write_atomic(&root.join(rel), bytes)
}

/// Refuses to replace an existing single-file output unless `force` (an existing output is
/// never replaced silently). A symlink is followed to the file it names ([`output_target`]).
///
/// # Errors
/// [`Error::FileExists`] when `path` (or the file it links to) exists and `force` is not given,
/// naming the output and the option as `names` says; as [`output_target`].
///
/// # Examples
/// ```
/// use safe_output::{Names, check_output_file};
/// let names = Names { output: "out", replace: "overwrite=True" };
/// let path = std::env::temp_dir().join(format!("safe-output-doc-check-{}.txt", std::process::id()));
/// check_output_file(names, &path, false).unwrap();
/// std::fs::write(&path, "old").unwrap();
/// let e = check_output_file(names, &path, false).unwrap_err();
/// assert!(e.to_string().ends_with("already exists; give overwrite=True to replace it"));
/// check_output_file(names, &path, true).unwrap();
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn check_output_file(names: Names<'_>, path: &Path, force: bool) -> Result<(), Error> {
    // Through symlinks to the file that would be written; special files are refused there.
    let target = output_target(path)?;
    if !force && target.is_file() {
        return Err(Error::FileExists {
            label: names.output.into(),
            replace: names.replace.into(),
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::names;

    fn scratch(name: &str) -> PathBuf {
        crate::tests::scratch(&format!("file-{name}"))
    }

    #[test]
    fn a_failed_fill_leaves_the_old_file_and_no_temporary() {
        let d = scratch("fail");
        let p = d.join("out.txt");
        write_atomic(&p, b"old").unwrap();
        let e = write_atomic_with(&p, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), format!("cannot write {}", p.display()));
        assert_eq!(std::error::Error::source(&e).unwrap().to_string(), "disk full");
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(names(&d), ["out.txt"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_and_special_files_are_refused() {
        use std::os::unix::fs::PermissionsExt;
        let d = scratch("links");
        std::fs::create_dir(d.join("real")).unwrap();
        std::os::unix::fs::symlink("real/f.txt", d.join("link.txt")).unwrap();
        write_atomic(&d.join("link.txt"), b"through").unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.txt")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(d.join("real/f.txt")).unwrap(), b"through");
        assert_eq!(std::fs::metadata(d.join("real/f.txt")).unwrap().permissions().mode() & 0o777, 0o644);
        // A folder, and a link to one, are refused naming what they are.
        let e = write_atomic(&d.join("real"), b"x").unwrap_err();
        assert!(e.to_string().ends_with("real is a folder: refusing to write there; name a regular file"), "{e}");
        std::os::unix::fs::symlink("real", d.join("to-dir")).unwrap();
        let e = write_atomic(&d.join("to-dir"), b"x").unwrap_err();
        assert!(e.to_string().contains("(the link's target"), "{e}");
        // A loop of links ends.
        std::os::unix::fs::symlink("loop-b", d.join("loop-a")).unwrap();
        std::os::unix::fs::symlink("loop-a", d.join("loop-b")).unwrap();
        assert!(matches!(output_target(&d.join("loop-a")), Err(Error::TooManyLinks { .. })));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn writes_under_a_root_take_plain_names_only() {
        let d = scratch("under");
        write_under(&d, Path::new("a/b.png"), b"x").unwrap();
        assert_eq!(std::fs::read(d.join("a/b.png")).unwrap(), b"x");
        for bad in ["", "..", "a/../../x", "/etc/x", "./x"] {
            let e = write_under(&d, Path::new(bad), b"x").unwrap_err();
            assert!(matches!(e, Error::Outside { .. }), "{bad}: {e}");
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn an_existing_file_is_replaced_only_when_forced() {
        let d = scratch("exists");
        let p = d.join("x.txt");
        let names = Names { output: "-o", replace: "-f" };
        check_output_file(names, &p, false).unwrap();
        std::fs::write(&p, b"x").unwrap();
        let e = check_output_file(names, &p, false).unwrap_err();
        assert_eq!(e.to_string(), format!("-o {}: already exists; give -f to replace it", p.display()));
        check_output_file(names, &p, true).unwrap();
        std::fs::remove_dir_all(&d).unwrap();
    }
}
