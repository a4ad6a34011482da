//! Ctrl-C and SIGTERM: the handler, the exit that cleans up (safe-output keeps the temporaries,
//! the output gate and the count of signals), and commands that stop by themselves.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result};

pub use safe_output::signal_count;

/// Set by commands that stop by themselves at a consistent point when [`interrupted`] says so.
static COOPERATIVE: AtomicBool = AtomicBool::new(false);

/// Installs the Ctrl-C / SIGTERM handler of every command but `robot` (which has its own):
/// temporary files are removed and the process exits with status 130 saying `interrupted`.
/// A command that called [`stop_on_interrupt`] is asked to stop instead (a second signal still
/// exits at once).
pub fn install_interrupt_handler() -> Result<()> {
    ctrlc::set_handler(|| {
        let n = safe_output::record_signal();
        if COOPERATIVE.load(Ordering::SeqCst) && n == 0 {
            return;
        }
        exit_interrupted();
    })
    .context("cannot install the Ctrl-C handler")
}

/// Removes the registered temporaries and exits with status 130 saying `interrupted`: once
/// every write or swap in flight has finished (waiting at most 10 s for them), and only once
/// per process (a second caller waits here until the process is gone).
pub fn exit_interrupted() -> ! {
    safe_output::freeze_outputs(std::time::Duration::from_secs(10));
    static EXITING: Mutex<()> = Mutex::new(());
    let _once = EXITING.lock().unwrap_or_else(|e| e.into_inner());
    safe_output::remove_temporaries();
    eprintln!("error: interrupted");
    std::process::exit(130);
}

/// Asks the Ctrl-C handler to let this command stop by itself: it polls [`interrupted`].
pub fn stop_on_interrupt() {
    COOPERATIVE.store(true, Ordering::SeqCst);
}

/// Whether Ctrl-C (or SIGTERM) arrived.
pub fn interrupted() -> bool {
    signal_count() > 0
}
