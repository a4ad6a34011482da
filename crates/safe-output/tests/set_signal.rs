//! A signal while a `FileSet` is written, in a process of its own (the count of signals is
//! process-wide): nothing is replaced, and the temporaries are registered for the clean-up.

use std::path::Path;

use safe_output::{Error, FileSet, record_signal, remove_temporaries};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

fn pair<'a>(d: &Path, text: &'a str) -> FileSet<'a> {
    let mut set = FileSet::new();
    set.add(d.join("a.txt"), text.as_bytes().to_vec());
    set.add_with(d.join("b.txt"), move |w| w.write_all(text.as_bytes()));
    set
}

#[test]
fn a_signal_while_the_files_are_written_replaces_none() {
    let d = std::env::temp_dir().join(format!("safe-output-set-signal-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let temp_a = d.join(format!(".a.txt.maobi-partial-{}", std::process::id()));
    pair(&d, "old").install("t").unwrap();

    // The temporaries are what a signal's clean-up removes while they are written.
    let mut set = pair(&d, "new");
    set.add_with(d.join("c.txt"), |w| {
        assert!(temp_a.exists());
        remove_temporaries();
        assert!(!temp_a.exists(), "the temporary of a.txt is registered");
        w.write_all(b"c")
    });
    assert!(set.install("t").is_err());
    assert_eq!(names(&d), ["a.txt", "b.txt"]);

    // A signal before the renames: nothing moves, the temporaries go.
    let mut set = pair(&d, "new");
    set.add_with(d.join("c.txt"), |w| {
        record_signal();
        w.write_all(b"c")
    });
    assert!(matches!(set.install("t"), Err(Error::Interrupted)));
    assert_eq!(names(&d), ["a.txt", "b.txt"]);
    assert_eq!(std::fs::read_to_string(d.join("a.txt")).unwrap(), "old");
    assert_eq!(std::fs::read_to_string(d.join("b.txt")).unwrap(), "old");
    std::fs::remove_dir_all(&d).unwrap();
}
