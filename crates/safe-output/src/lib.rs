//! # safe-output
//!
//! Writing results without half-writes. A run that fails, is killed or is interrupted leaves
//! every output either as it was or whole, never a mix, never half a file:
//!
//! * [`write_atomic`] / [`write_atomic_with`]: a file written to a temporary file beside it,
//!   then renamed; symlinks written through; folders, FIFOs, sockets and devices refused
//!   ([`output_target`]); [`write_under`] keeps a path from an untrusted name under its root.
//! * [`Stage`]: an output folder written into a hidden staging folder and swapped in whole by
//!   [`Stage::install`], which lists what the run wrote ([`MANIFEST`]) so that a later forced
//!   run replaces only that ([`foreign_files`], [`check_output_folder`]).
//! * [`FileSet`]: several files that belong together (a model's weights and its config)
//!   written beside their targets and renamed into place together, or none of them.
//! * [`OutputLock`]: one run per output; [`recover_leftovers`] cleans up after runs that died.
//! * [`check_output_file`], [`check_output_folder`], [`check_output_apart`]: the refusals
//!   before a run starts (an existing output, an output that is one of the inputs).
//! * Signals: the program's handler counts them ([`record_signal`]); swaps in flight undo
//!   themselves; [`freeze_outputs`] and [`remove_temporaries`] clean up before an exit. Every
//!   temporary this crate makes is registered, and [`TempGuard`] registers others'.
//!
//! The library knows no command line: errors name an output and the option that allows
//! replacing it in the caller's words ([`Names`]), and what the clean-up did comes back as
//! [`Notice`]s for the caller to show. It prints nothing, exits nothing and installs no signal
//! handler. Depends on std and thiserror only.
//!
//! ```
//! use safe_output::{Names, OutputLock, Stage, check_output_folder, recover_leftovers, write_atomic};
//!
//! let out = std::env::temp_dir().join(format!("safe-output-doc-lib-{}", std::process::id()));
//! let names = Names { output: "out", replace: "overwrite=True" };
//! let mut show = |n: safe_output::Notice| eprintln!("note: {n}");
//! let _lock = OutputLock::acquire(names.output, &out, &mut show)?;
//! recover_leftovers(&out, &mut show)?;
//! check_output_folder(names, &out, false)?;
//! let stage = Stage::new(&out)?;
//! write_atomic(&stage.path().join("result.txt"), b"42\n")?;
//! stage.install(names, &out, false, &mut show)?;
//! assert_eq!(std::fs::read_to_string(out.join("result.txt"))?, "42\n");
//! # std::fs::remove_dir_all(&out)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod error;
mod file;
mod folder;
mod interrupt;
mod set;

pub use error::{Error, Names, Notice, Overlap};
pub use file::{check_output_file, output_target, write_atomic, write_atomic_with, write_under};
pub use folder::{
    MANIFEST, OutputLock, Stage, check_output_apart, check_output_folder, foreign_files, output_is_vacant,
    recover_leftovers,
};
pub use interrupt::{
    GateGuard, TempGuard, freeze_outputs, output_gate, record_signal, remove_on_interrupt, remove_temporaries,
    signal_count, test_hook,
};
pub use set::FileSet;

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    /// An empty folder of this test process's own under the temporary folder.
    pub(crate) fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("safe-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// The names in `dir`, sorted.
    pub(crate) fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }
}
