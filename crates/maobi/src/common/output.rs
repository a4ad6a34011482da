//! Output files and folders through safe-output, in the CLI's words: the flag that names an
//! output, `--force` to replace one, the clean-up's notes on stderr, and exit 130 when a signal
//! stops a folder swap.

use std::path::Path;

use anyhow::Result;
use safe_output::{Names, Notice};

pub use safe_output::{FileSet, output_is_vacant, test_hook, write_atomic, write_atomic_with, write_under};

use super::interrupt::{exit_interrupted, signal_count};

/// An output named by `flag`, replaced with `--force`.
fn names(flag: &str) -> Names<'_> {
    Names { output: flag, replace: "--force" }
}

/// Shows what the output clean-up did, on stderr.
fn show(n: Notice) {
    eprintln!("{}: {n}", if n.is_warning() { "warning" } else { "note" });
}

/// [`safe_output::check_output_folder`], replaced with `--force`.
pub fn check_output_folder(flag: &str, out: &Path, force: bool) -> Result<()> {
    Ok(safe_output::check_output_folder(names(flag), out, force)?)
}

/// [`safe_output::check_output_file`], replaced with `--force`.
pub fn check_output_file(flag: &str, path: &Path, force: bool) -> Result<()> {
    Ok(safe_output::check_output_file(names(flag), path, force)?)
}

/// [`safe_output::check_output_apart`].
pub fn check_output_apart(out_flag: &str, out: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    Ok(safe_output::check_output_apart(out_flag, out, inputs)?)
}

/// [`safe_output::recover_leftovers`], each note on stderr.
pub fn recover_leftovers(out: &Path) -> Result<()> {
    Ok(safe_output::recover_leftovers(out, &mut show)?)
}

/// [`safe_output::OutputLock`]: one run per output.
pub struct OutputLock {
    _held: safe_output::OutputLock,
}

impl OutputLock {
    /// Takes the lock of `out` (`flag` names it in errors); a note on stderr when a dead run's
    /// lock is taken over.
    pub fn acquire(flag: &str, out: &Path) -> Result<Self> {
        Ok(OutputLock { _held: safe_output::OutputLock::acquire(flag, out, &mut show)? })
    }
}

/// [`safe_output::Stage`]: a staging folder swapped in at the end.
pub struct Stage(safe_output::Stage);

impl Stage {
    /// Creates the staging folder of `out`.
    pub fn new(out: &Path) -> Result<Self> {
        Ok(Stage(safe_output::Stage::new(out)?))
    }

    /// The staging folder.
    pub fn path(&self) -> &Path {
        self.0.path()
    }

    /// Puts the staged folder in place of `out` ([`safe_output::Stage::install`], `flag` names
    /// it, replaced with `--force`); a failure that a signal caused exits 130.
    pub fn install(self, flag: &str, out: &Path, replace: bool) -> Result<()> {
        let signals = signal_count();
        let result = self.0.install(names(flag), out, replace, &mut show);
        if result.is_err() && signal_count() != signals {
            exit_interrupted();
        }
        Ok(result?)
    }
}

/// Replaces the files of `files` together ([`safe_output::FileSet::install`], `step` its name for
/// `MAOBI_TEST_HOOK`); a failure that a signal caused exits 130.
pub fn install_files(files: FileSet<'_>, step: &str) -> Result<()> {
    let signals = signal_count();
    let result = files.install(step);
    if result.is_err() && signal_count() != signals {
        exit_interrupted();
    }
    Ok(result?)
}
