//! Ctrl-C and SIGTERM: temporary files removed, the output gate that keeps clean-up from
//! racing a write, and commands that stop by themselves.

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, RwLock, RwLockReadGuard};

use anyhow::{Context, Result};

/// Temporary files being written now: removed by the Ctrl-C handler.
pub(super) static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Set once Ctrl-C (SIGINT) or SIGTERM arrived.
pub(super) static INTERRUPTED: AtomicBool = AtomicBool::new(false);
/// Set by commands that stop by themselves at a consistent point when [`interrupted`] says so.
pub(super) static COOPERATIVE: AtomicBool = AtomicBool::new(false);
pub(super) static SIGNALS: AtomicUsize = AtomicUsize::new(0);

/// Removes every registered temporary file.
pub(super) fn remove_temps() {
    let temps = TEMPS.lock().unwrap_or_else(|e| e.into_inner());
    for t in temps.iter() {
        // A staging folder (`maobi write`) or a temporary file.
        if t.is_dir() {
            let _ = std::fs::remove_dir_all(t);
        } else {
            let _ = std::fs::remove_file(t);
        }
    }
}

/// Installs the Ctrl-C / SIGTERM handler of every command but `robot` (which has its own):
/// temporary files are removed and the process exits with status 130 saying `interrupted`.
/// A command that called [`stop_on_interrupt`] is asked to stop instead (a second signal still
/// exits at once).
pub fn install_interrupt_handler() -> Result<()> {
    ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        let n = SIGNALS.fetch_add(1, Ordering::SeqCst);
        if COOPERATIVE.load(Ordering::SeqCst) && n == 0 {
            return;
        }
        exit_interrupted();
    })
    .context("cannot install the Ctrl-C handler")
}

/// Held (shared) by every write into an output or staging folder and across a whole folder
/// swap; [`exit_interrupted`] takes it exclusively, so the clean-up never races a write (which
/// could re-create a folder just removed) and never cuts a swap in half.
pub(super) static GATE: RwLock<()> = RwLock::new(());

thread_local! {
    /// How many [`GateGuard`]s this thread holds (only the first one locks).
    static GATE_DEPTH: Cell<usize> = const { Cell::new(0) };
}

/// A shared hold on the output gate; see [`output_gate`].
pub struct GateGuard {
    _guard: Option<RwLockReadGuard<'static, ()>>,
}

impl Drop for GateGuard {
    fn drop(&mut self) {
        GATE_DEPTH.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Holds off the Ctrl-C clean-up while a step that writes outputs runs (re-entrant within a
/// thread): a signal arriving meanwhile is acted on once the guard is dropped.
pub fn output_gate() -> GateGuard {
    let depth = GATE_DEPTH.with(|d| {
        let v = d.get();
        d.set(v + 1);
        v
    });
    GateGuard { _guard: (depth == 0).then(|| GATE.read().unwrap_or_else(|e| e.into_inner())) }
}

/// Removes the registered temporaries and exits with status 130 saying `interrupted`: once
/// every write or swap in flight has finished (waiting at most 10 s for them), and only once
/// per process (a second caller waits here until the process is gone).
pub fn exit_interrupted() -> ! {
    // A helper thread waits for the gate (writers go first: no new write starts once it waits)
    // and keeps it until the process is gone; this one waits for that at most 10 s.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _gate = GATE.write().unwrap_or_else(|e| e.into_inner());
        let _ = tx.send(());
        loop {
            std::thread::park();
        }
    });
    let _ = rx.recv_timeout(std::time::Duration::from_secs(10));
    static EXITING: Mutex<()> = Mutex::new(());
    let _once = EXITING.lock().unwrap_or_else(|e| e.into_inner());
    remove_temps();
    eprintln!("error: interrupted");
    std::process::exit(130);
}

/// Asks the Ctrl-C handler to let this command stop by itself: it polls [`interrupted`].
pub fn stop_on_interrupt() {
    COOPERATIVE.store(true, Ordering::SeqCst);
}

/// How many times Ctrl-C (or SIGTERM) arrived so far: a step compares it before and after to
/// tell whether a signal came meanwhile.
pub fn signal_count() -> usize {
    SIGNALS.load(Ordering::SeqCst)
}

/// Whether Ctrl-C (or SIGTERM) arrived.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Puts a temporary file that a library writes (and renames) on the list the Ctrl-C handler
/// removes, for the rest of the run.
pub fn remove_on_interrupt(p: &Path) {
    TEMPS.lock().unwrap_or_else(|e| e.into_inner()).push(p.to_path_buf());
}

/// Keeps a temporary file on the list the Ctrl-C handler removes, while it lives.
pub struct TempGuard(PathBuf);

impl TempGuard {
    /// Registers `p` (a file or a folder) for removal by the Ctrl-C handler until dropped.
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
