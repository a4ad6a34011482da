//! Clean-up after a signal, process-wide: the temporaries a signal handler removes, the output
//! gate that keeps that clean-up from racing a write, the count of signals, and the test hook.
//!
//! This crate installs no handler: the program's own handler calls [`record_signal`] and, to
//! exit, [`freeze_outputs`] then [`remove_temporaries`].

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, RwLock, RwLockReadGuard};
use std::time::Duration;

use crate::Error;

/// Temporary files and folders being written now: removed by [`remove_temporaries`].
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// How many signals [`record_signal`] counted.
static SIGNALS: AtomicUsize = AtomicUsize::new(0);
/// Held (shared) by every write into an output or staging folder and across a whole folder
/// swap; [`freeze_outputs`] takes it exclusively.
static GATE: RwLock<()> = RwLock::new(());

thread_local! {
    /// How many [`GateGuard`]s this thread holds (only the first one locks).
    static GATE_DEPTH: Cell<usize> = const { Cell::new(0) };
}

/// Counts a signal (Ctrl-C, SIGTERM): call it first thing in the program's handler. Returns how
/// many came before this one. A folder swap in flight ([`crate::Stage::install`]) sees the count
/// change, undoes itself and fails with [`Error::Interrupted`].
///
/// # Examples
/// ```
/// let before = safe_output::signal_count();
/// assert_eq!(safe_output::record_signal(), before);
/// assert_eq!(safe_output::signal_count(), before + 1);
/// ```
pub fn record_signal() -> usize {
    SIGNALS.fetch_add(1, Ordering::SeqCst)
}

/// How many signals [`record_signal`] counted so far: a step compares it before and after to
/// tell whether a signal came meanwhile.
pub fn signal_count() -> usize {
    SIGNALS.load(Ordering::SeqCst)
}

/// Removes every registered temporary ([`TempGuard`], [`remove_on_interrupt`]): files and
/// folders alike, errors ignored. For a signal handler about to exit, after [`freeze_outputs`].
pub fn remove_temporaries() {
    let temps = TEMPS.lock().unwrap_or_else(|e| e.into_inner());
    for t in temps.iter() {
        // A staging folder or a temporary file.
        if t.is_dir() {
            let _ = std::fs::remove_dir_all(t);
        } else {
            let _ = std::fs::remove_file(t);
        }
    }
}

/// A shared hold on the output gate; see [`output_gate`].
#[derive(Debug)]
pub struct GateGuard {
    _guard: Option<RwLockReadGuard<'static, ()>>,
}

impl Drop for GateGuard {
    fn drop(&mut self) {
        GATE_DEPTH.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Holds off [`freeze_outputs`] while a step that writes outputs runs (re-entrant within a
/// thread): every write and swap of this crate holds it, and a caller may hold it across
/// several steps that must not be cut apart.
pub fn output_gate() -> GateGuard {
    let depth = GATE_DEPTH.with(|d| {
        let v = d.get();
        d.set(v + 1);
        v
    });
    GateGuard { _guard: (depth == 0).then(|| GATE.read().unwrap_or_else(|e| e.into_inner())) }
}

/// Waits until no write or swap holds the [`output_gate`] (at most `timeout`), then keeps every
/// later one from starting for the rest of the process (a helper thread holds the gate). For a
/// signal handler about to exit: what it removes next is not re-created behind it, and no swap
/// is cut in half.
pub fn freeze_outputs(timeout: Duration) {
    // Writers go first: no new write starts once the helper waits for the gate.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _gate = GATE.write().unwrap_or_else(|e| e.into_inner());
        let _ = tx.send(());
        loop {
            std::thread::park();
        }
    });
    let _ = rx.recv_timeout(timeout);
}

/// Puts a temporary file or folder that someone else writes (and renames) on the list
/// [`remove_temporaries`] removes, for the rest of the run.
pub fn remove_on_interrupt(p: &Path) {
    TEMPS.lock().unwrap_or_else(|e| e.into_inner()).push(p.to_path_buf());
}

/// Keeps a temporary file or folder on the list [`remove_temporaries`] removes, while it lives.
#[derive(Debug)]
pub struct TempGuard(PathBuf);

impl TempGuard {
    /// Registers `p` (a file or a folder) until dropped.
    pub fn new(p: &Path) -> Self {
        TEMPS.lock().unwrap_or_else(|e| e.into_inner()).push(p.to_path_buf());
        TempGuard(p.to_path_buf())
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        let mut t = TEMPS.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = t.iter().position(|p| *p == self.0) {
            t.swap_remove(i);
        }
    }
}

/// A fault-injection hook for tests of whole programs, read only in debug builds from the
/// environment variable `MAOBI_TEST_HOOK`: `fail:STEP` makes `step` fail as a full disk would
/// ([`Error::Injected`]); `pause:STEP` creates the file named by `MAOBI_TEST_HOOK_MARKER` and
/// waits (at most 60 s) until the test removes it or a signal arrives ([`record_signal`]).
/// Release builds ignore both. [`crate::Stage::install`] calls it before each of its steps
/// (`swap-aside`, `swap-install`, `swap-cleanup`); a program may call it at its own steps.
///
/// # Errors
/// [`Error::Injected`]; [`Error::Io`] when the marker cannot be created.
///
/// # Examples
/// ```
/// // Without MAOBI_TEST_HOOK in the environment every step passes.
/// safe_output::test_hook("any-step").unwrap();
/// ```
pub fn test_hook(step: &str) -> Result<(), Error> {
    if !cfg!(debug_assertions) {
        return Ok(());
    }
    let Ok(hook) = std::env::var("MAOBI_TEST_HOOK") else { return Ok(()) };
    if hook.strip_prefix("fail:") == Some(step) {
        return Err(Error::Injected { step: step.to_string() });
    }
    if hook.strip_prefix("pause:") == Some(step) {
        let marker = PathBuf::from(std::env::var("MAOBI_TEST_HOOK_MARKER").unwrap_or_default());
        let signals = signal_count();
        std::fs::write(&marker, step).map_err(Error::io("MAOBI_TEST_HOOK_MARKER", &marker))?;
        let t0 = std::time::Instant::now();
        while marker.exists() && signal_count() == signals && t0.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_guard_registers_its_path_while_it_lives() {
        let p = PathBuf::from("/nonexistent/safe-output-guard-test");
        let listed = || TEMPS.lock().unwrap().iter().filter(|t| **t == p).count();
        {
            let _g = TempGuard::new(&p);
            assert_eq!(listed(), 1);
        }
        assert_eq!(listed(), 0);
    }

    #[test]
    fn the_gate_is_reentrant_within_a_thread() {
        let a = output_gate();
        // A second hold on the same thread neither deadlocks nor takes the lock again.
        let b = output_gate();
        assert!(b._guard.is_none());
        drop(b);
        drop(a);
        assert_eq!(GATE_DEPTH.with(Cell::get), 0);
    }
}
