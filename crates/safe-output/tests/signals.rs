//! The clean-up before a program exits on a signal, in a process of its own: it removes every
//! registered temporary of the process and freezes its outputs for good.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use safe_output::{
    Stage, TempGuard, freeze_outputs, output_gate, record_signal, remove_on_interrupt, remove_temporaries, signal_count,
};

#[test]
fn the_clean_up_waits_for_writes_removes_what_is_registered_and_stops_later_writes() {
    let d = std::env::temp_dir().join(format!("safe-output-signals-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();

    // Registered temporaries, files and folders, are removed; unregistered files are not.
    let stage = Stage::new(&d.join("o")).unwrap();
    safe_output::write_atomic(&stage.path().join("a/b.txt"), b"x").unwrap();
    std::fs::write(d.join("guarded.tmp"), "x").unwrap();
    let _guard = TempGuard::new(&d.join("guarded.tmp"));
    std::fs::write(d.join("listed.tmp"), "x").unwrap();
    remove_on_interrupt(&d.join("listed.tmp"));
    std::fs::write(d.join("kept.txt"), "x").unwrap();

    let before = signal_count();
    assert_eq!(record_signal(), before);
    assert_eq!(signal_count(), before + 1);

    // A write in flight holds the gate: the freeze waits for it (not for its whole timeout).
    let (held_tx, held_rx) = mpsc::channel();
    let writer = std::thread::spawn(move || {
        let _gate = output_gate();
        held_tx.send(()).unwrap();
        std::thread::sleep(Duration::from_millis(300));
    });
    held_rx.recv().unwrap();
    let t0 = Instant::now();
    freeze_outputs(Duration::from_secs(20));
    let waited = t0.elapsed();
    writer.join().unwrap();
    assert!(waited >= Duration::from_millis(200) && waited < Duration::from_secs(15), "{waited:?}");

    remove_temporaries();
    assert!(!stage.path().exists() && !d.join("guarded.tmp").exists() && !d.join("listed.tmp").exists());
    assert!(d.join("kept.txt").exists());

    // After the freeze no write starts.
    let (tx, rx) = mpsc::channel();
    let late = d.join("late.txt");
    std::thread::spawn(move || tx.send(safe_output::write_atomic(&late, b"late").is_ok()));
    assert!(rx.recv_timeout(Duration::from_millis(300)).is_err(), "a write ran after the freeze");
    assert!(!d.join("late.txt").exists());
    drop(stage);
    let _ = std::fs::remove_dir_all(&d);
}
