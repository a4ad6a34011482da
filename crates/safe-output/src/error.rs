//! The crate's errors and the notices its clean-up reports.

use std::fmt;
use std::path::PathBuf;

use thiserror::Error;

/// How errors name an output and the option that lets a run replace it, in the caller's words
/// (a command line's flags, a function's argument names). The library knows no command line.
///
/// ```
/// let names = safe_output::Names { output: "out", replace: "overwrite=True" };
/// assert_eq!(names.output, "out");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Names<'a> {
    /// What the output is called (`out`, a flag).
    pub output: &'a str,
    /// What allows replacing an existing output (`overwrite=True`, a flag).
    pub replace: &'a str,
}

/// How an output overlaps one of the run's inputs ([`Error::Overlaps`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overlap {
    /// The output is the input.
    Is,
    /// The output lies inside the input (a folder).
    LiesInside,
    /// The output (a folder) holds the input.
    Holds,
}

impl fmt::Display for Overlap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Overlap::Is => "is",
            Overlap::LiesInside => "lies inside",
            Overlap::Holds => "holds",
        })
    }
}

/// Errors of safe-output. Each names the path it concerns (and, for an output, the caller's
/// name for it, [`Names`]); I/O errors are kept as sources.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// A file-system operation failed: `action` says which (`cannot write`, `cannot create
    /// folder`, …), `path` where.
    #[error("{action} {}", path.display())]
    Io {
        /// What was being done.
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The path to write (or the file a symlink there names) is a folder, FIFO, socket or
    /// device: writing would replace the node.
    #[error(
        "{}{} is {kind}: refusing to write there; name a regular file",
        path.display(),
        target.as_ref().map_or(String::new(), |t| format!(" (the link's target {})", t.display()))
    )]
    NotRegular {
        /// The path asked for.
        path: PathBuf,
        /// Where its symlinks lead, when that is another path.
        target: Option<PathBuf>,
        /// `a folder`, `a FIFO`, `a device`, `a socket` or `not a regular file`.
        kind: &'static str,
    },
    /// Over 40 symbolic links in a row.
    #[error("{}: too many levels of symbolic links", path.display())]
    TooManyLinks {
        /// The path asked for.
        path: PathBuf,
    },
    /// The output's state could not be read.
    #[error("{label} {}", path.display())]
    Inspect {
        /// The output's name.
        label: String,
        /// The output.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Another running process holds the output's lock.
    #[error(
        "{label} {}: another maobi run (process {pid}) is writing it (lock file {}); wait for it to finish",
        out.display(),
        lock.display()
    )]
    Locked {
        /// The output's name.
        label: String,
        /// The output.
        out: PathBuf,
        /// The process holding the lock.
        pid: u32,
        /// The lock file.
        lock: PathBuf,
    },
    /// The lock was taken by other runs at every attempt.
    #[error("{label} {}: cannot take the lock {} (other runs keep taking it)", out.display(), lock.display())]
    LockContended {
        /// The output's name.
        label: String,
        /// The output.
        out: PathBuf,
        /// The lock file.
        lock: PathBuf,
    },
    /// A single-file output exists and replacing was not allowed.
    #[error("{label} {}: already exists; give {replace} to replace it", path.display())]
    FileExists {
        /// The output's name.
        label: String,
        /// What allows replacing.
        replace: String,
        /// The output.
        path: PathBuf,
    },
    /// An output folder exists and is not empty, and replacing was not allowed.
    #[error(
        "{label} {}: already exists and is not empty; give {replace} to replace it (a run never mixes with an older one)",
        out.display()
    )]
    NotEmpty {
        /// The output's name.
        label: String,
        /// What allows replacing.
        replace: String,
        /// The output.
        out: PathBuf,
    },
    /// An output folder to replace is not a folder.
    #[error("{label} {}: exists and is not a folder; {replace} replaces folders only", out.display())]
    NotAFolder {
        /// The output's name.
        label: String,
        /// What allows replacing.
        replace: String,
        /// The output.
        out: PathBuf,
    },
    /// An output folder to replace holds files no run wrote ([`crate::foreign_files`]).
    #[error(
        "{label} {}: holds {} file(s) maobi did not write ({}{}); {replace} replaces only what maobi wrote there: move them away, or name another folder",
        out.display(),
        files.len(),
        files.iter().take(5).map(String::as_str).collect::<Vec<_>>().join(", "),
        if files.len() > 5 { format!(" and {} more", files.len() - 5) } else { String::new() }
    )]
    Foreign {
        /// The output's name.
        label: String,
        /// What allows replacing.
        replace: String,
        /// The output.
        out: PathBuf,
        /// The foreign files, relative `/`-separated paths, sorted.
        files: Vec<String>,
    },
    /// The output appeared while the run worked, and replacing was not allowed.
    #[error(
        "{label} {}: appeared while this run was working and is not empty; nothing was replaced (give {replace} to replace it)",
        out.display()
    )]
    Appeared {
        /// The output's name.
        label: String,
        /// What allows replacing.
        replace: String,
        /// The output.
        out: PathBuf,
    },
    /// The output is one of the run's inputs, lies inside one or holds one.
    #[error(
        "{label} {}: {how} the input {input_label} {} (writing there would replace what this run reads): name another output",
        out.display(),
        input.display()
    )]
    Overlaps {
        /// The output's name.
        label: String,
        /// The output.
        out: PathBuf,
        /// How they overlap.
        how: Overlap,
        /// The input's name.
        input_label: String,
        /// The input.
        input: PathBuf,
    },
    /// A relative path given to [`crate::write_under`] could leave its root.
    #[error("refusing to write {} outside the output folder {}", rel.display(), root.display())]
    Outside {
        /// The relative path.
        rel: PathBuf,
        /// The root.
        root: PathBuf,
    },
    /// Moving the old output aside failed (nothing changed).
    #[error("cannot move the old {} aside to {}", out.display(), old.display())]
    MoveAside {
        /// The output.
        out: PathBuf,
        /// Where it was to go.
        old: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A killed run's old output could not be put back.
    #[error("cannot put back {} as {}", old.display(), out.display())]
    PutBack {
        /// The old output.
        old: PathBuf,
        /// The output.
        out: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A swap failed and the old output could not be put back either: it lies at `old`.
    #[error(
        "and cannot put the old {} back from {} ({restore}); rename it back by hand",
        out.display(),
        old.display()
    )]
    NotRestored {
        /// The output.
        out: PathBuf,
        /// Where the old output lies.
        old: PathBuf,
        /// Why it could not be renamed back.
        restore: std::io::Error,
        /// Why the swap failed.
        #[source]
        source: Box<Error>,
    },
    /// A swap failed after the new output was in place, and it could not be taken out again.
    #[error("and cannot take the new {} out again ({restore})", out.display())]
    NotTakenOut {
        /// The output.
        out: PathBuf,
        /// Why it could not be moved back.
        restore: std::io::Error,
        /// Why the swap failed.
        #[source]
        source: Box<Error>,
    },
    /// A new file of a [`crate::FileSet`] could not be renamed onto its target.
    #[error("cannot move the new {} into place", path.display())]
    MoveIntoPlace {
        /// The target.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Two files of one [`crate::FileSet`] would be written to the same place.
    #[error("{}: named twice in one set of files", path.display())]
    NamedTwice {
        /// The file (through symlinks, as [`crate::output_target`] resolves it).
        path: PathBuf,
    },
    /// A signal arrived ([`crate::record_signal`]) during a swap, which was undone, or while a
    /// [`crate::FileSet`] was written, which replaced nothing.
    #[error("interrupted")]
    Interrupted,
    /// A failure injected by [`crate::test_hook`].
    #[error("{step}: No space left on device (injected by MAOBI_TEST_HOOK)")]
    Injected {
        /// The step that failed.
        step: String,
    },
}

impl Error {
    /// An [`Error::Io`] maker for `map_err`.
    pub(crate) fn io(action: &'static str, path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Error {
        let path = path.into();
        move |source| Error::Io { action, path, source }
    }
}

/// What the clean-up did or could not do, for the caller to show (this crate prints nothing).
/// `Display` gives the sentence; [`Notice::is_warning`] tells a warning from a note.
#[derive(Debug)]
#[non_exhaustive]
pub enum Notice {
    /// A lock whose process no longer runs was taken over.
    LockTakenOver {
        /// The lock file.
        lock: PathBuf,
        /// The process that held it, when its file could be read.
        pid: Option<u32>,
    },
    /// A killed run's old output was put back: the run stopped in the middle of its swap.
    PutBack {
        /// The output.
        out: PathBuf,
        /// Where the old output lay.
        old: PathBuf,
        /// The run that stopped.
        pid: u32,
    },
    /// A killed run's old output was removed: the run had installed its new one.
    RemovedOld {
        /// Where the old output lay.
        old: PathBuf,
        /// The output.
        out: PathBuf,
        /// The run that stopped.
        pid: u32,
    },
    /// A killed run's staging folder was removed.
    RemovedPartial {
        /// The staging folder.
        partial: PathBuf,
        /// The run that stopped.
        pid: u32,
    },
    /// After a swap the old output could not be removed (the next run removes it).
    OldNotRemoved {
        /// Where the old output lies.
        old: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
}

impl Notice {
    /// Whether this is a warning (something was left undone) rather than a note.
    pub fn is_warning(&self) -> bool {
        matches!(self, Notice::OldNotRemoved { .. })
    }
}

impl fmt::Display for Notice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Notice::LockTakenOver { lock, pid } => {
                let who = pid.map_or("an unreadable process id".into(), |p| format!("process {p}"));
                write!(f, "taking over the lock {} of a maobi run that no longer runs ({who})", lock.display())
            }
            Notice::PutBack { out, old, pid } => write!(
                f,
                "put back {} from {}: a maobi run (process {pid}) stopped in the middle of replacing it",
                out.display(),
                old.display()
            ),
            Notice::RemovedOld { old, out, pid } => write!(
                f,
                "removed {}, the old {} a maobi run (process {pid}) had replaced before it stopped",
                old.display(),
                out.display()
            ),
            Notice::RemovedPartial { partial, pid } => write!(
                f,
                "removed {}, the unfinished output of a maobi run (process {pid}) that stopped",
                partial.display()
            ),
            Notice::OldNotRemoved { old, source } => {
                write!(f, "cannot remove the old outputs {}: {source} (the next run removes them)", old.display())
            }
        }
    }
}
