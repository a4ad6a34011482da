//! A set of files replaced together: each written whole beside its target, then all renamed
//! into place with the clean-up after a signal held off until the last rename.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::folder::{name_of, parent_of};
use crate::interrupt::{TempGuard, output_gate, signal_count, test_hook};
use crate::{Error, output_target};

/// What writes one file's bytes.
type Fill<'a> = Box<dyn FnOnce(&mut dyn Write) -> std::io::Result<()> + 'a>;

/// Files that belong together (a model's weights and its config, a run's log and its plot),
/// replaced together by [`FileSet::install`]: a failure while any of them is written (a full
/// disk), or a signal, replaces none of them.
///
/// Each file is written to a hidden temporary file beside its target,
/// `.NAME.maobi-partial-PID` (`NAME` the target's file name, `PID` this process), and renamed
/// onto the target once every file is written. Targets are followed through symlinks and
/// folders, FIFOs, sockets and devices refused, as [`output_target`] says, before anything is
/// written.
///
/// # Examples
/// ```
/// use std::io::Write;
/// let dir = std::env::temp_dir().join(format!("safe-output-doc-set-{}", std::process::id()));
/// let mut set = safe_output::FileSet::new();
/// set.add(dir.join("model.json"), b"{}\n".to_vec());
/// set.add_with(dir.join("loss.csv"), |w| writeln!(w, "step,loss\n1,0.5"));
/// set.install("save-model")?;
/// assert_eq!(std::fs::read_to_string(dir.join("loss.csv"))?, "step,loss\n1,0.5\n");
///
/// // A file that cannot be written leaves the others as they were.
/// let mut set = safe_output::FileSet::new();
/// set.add(dir.join("model.json"), b"{\"new\": 1}\n".to_vec());
/// set.add_with(dir.join("loss.csv"), |_| Err(std::io::Error::other("disk full")));
/// assert!(set.install("save-model").is_err());
/// assert_eq!(std::fs::read_to_string(dir.join("model.json"))?, "{}\n");
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Default)]
pub struct FileSet<'a> {
    files: Vec<(PathBuf, Fill<'a>)>,
}

impl std::fmt::Debug for FileSet<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.files.iter().map(|(p, _)| p)).finish()
    }
}

impl<'a> FileSet<'a> {
    /// An empty set.
    pub fn new() -> Self {
        FileSet { files: Vec::new() }
    }

    /// Adds `target`, to be replaced by `bytes`.
    pub fn add(&mut self, target: impl Into<PathBuf>, bytes: Vec<u8>) -> &mut Self {
        self.add_with(target, move |w| w.write_all(&bytes))
    }

    /// Adds `target`, to be replaced by what `fill` writes into a buffered writer (as
    /// [`crate::write_atomic_with`]; turn another error into an I/O error with
    /// `std::io::Error::other`). `fill` runs in [`FileSet::install`], in the order added.
    pub fn add_with(
        &mut self,
        target: impl Into<PathBuf>,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()> + 'a,
    ) -> &mut Self {
        self.files.push((target.into(), Box::new(fill)));
        self
    }

    /// Writes every file to its temporary file, then renames them all onto their targets. The
    /// whole install holds the [`crate::output_gate`], so a signal's clean-up
    /// ([`crate::freeze_outputs`]) waits until the last rename or the removal of the
    /// temporaries; they are registered for [`crate::remove_temporaries`] meanwhile. Missing
    /// folders are created; the files get mode 0644 on Unix. [`test_hook`]`(step)` runs after
    /// the last file is written, before the first rename.
    ///
    /// On an error, or when a signal ([`crate::record_signal`]) came since the install began,
    /// every temporary is removed and no target has changed, except when a rename itself fails
    /// ([`Error::MoveIntoPlace`]: the files renamed before it stay replaced; each temporary lies
    /// beside its target on the same file system, so only a failing disk or a racing process
    /// gets there).
    ///
    /// # Errors
    /// As [`output_target`] for a target; [`Error::NamedTwice`] when two targets are one file;
    /// [`Error::Io`] naming the target when its folder or its temporary file cannot be created
    /// or written (`fill`'s error is the source); [`Error::Injected`] from [`test_hook`];
    /// [`Error::Interrupted`]; [`Error::MoveIntoPlace`].
    pub fn install(self, step: &str) -> Result<(), Error> {
        let signals = signal_count();
        let _gate = output_gate();
        let mut targets: Vec<PathBuf> = Vec::with_capacity(self.files.len());
        for (target, _) in &self.files {
            let t = output_target(target)?;
            if targets.contains(&t) {
                return Err(Error::NamedTwice { path: t });
            }
            targets.push(t);
        }
        let temps: Vec<PathBuf> = targets
            .iter()
            .map(|t| parent_of(t).join(format!(".{}.maobi-partial-{}", name_of(t), std::process::id())))
            .collect();
        let _guards: Vec<TempGuard> = temps.iter().map(|t| TempGuard::new(t)).collect();
        let result = (|| {
            for (((_, fill), target), temp) in self.files.into_iter().zip(&targets).zip(&temps) {
                write_temporary(temp, target, fill)?;
            }
            test_hook(step)?;
            if signal_count() != signals {
                return Err(Error::Interrupted);
            }
            for (temp, target) in temps.iter().zip(&targets) {
                std::fs::rename(temp, target)
                    .map_err(|source| Error::MoveIntoPlace { path: target.clone(), source })?;
            }
            Ok(())
        })();
        if result.is_err() {
            for t in &temps {
                let _ = std::fs::remove_file(t);
            }
        }
        result
    }
}

/// Writes `temp` (the temporary file of `target`, which errors name) with `fill`: a stale file of
/// that name (a dead process's with this one's id) is removed first and the new one created
/// private, then given the usual permissions.
fn write_temporary(temp: &Path, target: &Path, fill: Fill<'_>) -> Result<(), Error> {
    let dir = parent_of(temp);
    std::fs::create_dir_all(&dir).map_err(Error::io("cannot create folder", &dir))?;
    let _ = std::fs::remove_file(temp);
    let mut open = std::fs::OpenOptions::new();
    open.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut open, 0o600);
    let mut file = open.open(temp).map_err(Error::io("cannot write", target))?;
    {
        let mut w = std::io::BufWriter::new(&mut file);
        fill(&mut w).and_then(|()| w.flush()).map_err(Error::io("cannot write", target))?;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = file.set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::names;

    fn scratch(name: &str) -> PathBuf {
        crate::tests::scratch(&format!("set-{name}"))
    }

    /// A set of `a.txt` and `b.txt` in `d` holding `text`.
    fn pair<'a>(d: &Path, text: &'a str) -> FileSet<'a> {
        let mut set = FileSet::new();
        set.add(d.join("a.txt"), text.as_bytes().to_vec());
        set.add_with(d.join("b.txt"), move |w| w.write_all(text.as_bytes()));
        set
    }

    #[test]
    fn every_file_is_replaced_together() {
        let d = scratch("all");
        pair(&d, "one").install("t").unwrap();
        assert_eq!(names(&d), ["a.txt", "b.txt"]);
        pair(&d, "two").install("t").unwrap();
        assert_eq!(std::fs::read_to_string(d.join("a.txt")).unwrap(), "two");
        assert_eq!(std::fs::read_to_string(d.join("b.txt")).unwrap(), "two");
        // Missing folders are created.
        let mut set = FileSet::new();
        set.add(d.join("sub/deeper/c.txt"), b"c".to_vec());
        set.install("t").unwrap();
        assert_eq!(std::fs::read(d.join("sub/deeper/c.txt")).unwrap(), b"c");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_failed_file_replaces_none_and_leaves_no_temporary() {
        let d = scratch("fail");
        pair(&d, "old").install("t").unwrap();
        let mut set = pair(&d, "new");
        set.add_with(d.join("c.txt"), |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        let e = set.install("t").unwrap_err();
        assert_eq!(e.to_string(), format!("cannot write {}", d.join("c.txt").display()));
        assert_eq!(std::error::Error::source(&e).unwrap().to_string(), "disk full");
        assert_eq!(names(&d), ["a.txt", "b.txt"]);
        assert_eq!(std::fs::read_to_string(d.join("a.txt")).unwrap(), "old");
        assert_eq!(std::fs::read_to_string(d.join("b.txt")).unwrap(), "old");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_target_named_twice_or_a_folder_is_refused_before_anything_is_written() {
        let d = scratch("refuse");
        let mut set = pair(&d, "x");
        set.add(d.join("a.txt"), b"again".to_vec());
        assert!(matches!(set.install("t"), Err(Error::NamedTwice { .. })));
        std::fs::create_dir(d.join("folder")).unwrap();
        let mut set = pair(&d, "x");
        set.add(d.join("folder"), b"x".to_vec());
        let e = set.install("t").unwrap_err();
        assert!(matches!(e, Error::NotRegular { .. }), "{e}");
        assert_eq!(names(&d), ["folder"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_and_its_temporary_lies_beside_the_file() {
        use std::os::unix::fs::PermissionsExt;
        let d = scratch("links");
        std::fs::create_dir(d.join("real")).unwrap();
        std::os::unix::fs::symlink("real/f.txt", d.join("link.txt")).unwrap();
        let mut set = FileSet::new();
        set.add(d.join("link.txt"), b"through".to_vec());
        set.add_with(d.join("other.txt"), |w| {
            // The link's temporary is beside the file it names, not beside the link.
            assert_eq!(names(&d.join("real")), [format!(".f.txt.maobi-partial-{}", std::process::id())]);
            w.write_all(b"o")
        });
        set.install("t").unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.txt")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(d.join("real/f.txt")).unwrap(), b"through");
        assert_eq!(std::fs::metadata(d.join("real/f.txt")).unwrap().permissions().mode() & 0o777, 0o644);
        assert_eq!(names(&d.join("real")), ["f.txt"]);
        // A link to itself through another name is the same file twice.
        let mut set = FileSet::new();
        set.add(d.join("link.txt"), b"1".to_vec());
        set.add(d.join("real/f.txt"), b"2".to_vec());
        assert!(matches!(set.install("t"), Err(Error::NamedTwice { .. })));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
