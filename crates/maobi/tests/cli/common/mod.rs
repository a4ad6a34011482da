//! Helpers shared by the CLI tests: run `maobi`, check success or a one-line exit-2 error.

#![allow(dead_code)]

pub mod calib_world;
pub mod world;

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

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

/// A free loopback port (bound once, then released for the process under test).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// `maobi robot sim` with `args`, once its first port accepts connections (at most 5 s);
/// stopped (killed and waited for) when dropped.
pub struct Sim(Child);

impl Sim {
    /// Starts the simulator on `port` with `args`.
    pub fn start(port: u16, args: &[&str]) -> Sim {
        let child = Command::new(env!("CARGO_BIN_EXE_maobi"))
            .args(["robot", "sim", "--port", &port.to_string()])
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let sim = Sim(child);
        for _ in 0..250 {
            if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
                return sim;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("the simulator did not start");
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
