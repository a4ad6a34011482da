//! Helpers shared by the CLI tests: run `maobi`, check success or a one-line exit-2 error.

#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `maobi` binary with `args`.
pub fn maobi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_maobi")).args(args).output().expect("maobi runs")
}

/// Asserts success and returns stdout.
pub fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts success and parses stdout as JSON (null when it is not JSON).
pub fn ok_json(o: &Output) -> serde_json::Value {
    serde_json::from_str(&ok(o)).unwrap_or(serde_json::Value::Null)
}

/// Asserts exit status 2 with a one-line error containing `needle`.
pub fn fails(o: &Output, needle: &str) {
    assert_eq!(o.status.code(), Some(2), "expected exit 2: {}", String::from_utf8_lossy(&o.stderr));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains(needle), "stderr lacks {needle:?}: {e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
}

/// A path as `&str`.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
