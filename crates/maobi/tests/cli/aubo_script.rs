//! AUBO's script form end to end (issue 41): `robot send --transport script` sends 永 as one Lua
//! script (AUBO's documented `return function(api) local _ENV = require('aubo')…` form) to
//! `robot sim --script-port`, which runs it in Lua 5.4, and follows it over JSON-RPC; the
//! official SDK's `ScriptClient` sends the exported script the same way while its `RpcClient`
//! follows the runtime (`RuntimeMachine.getStatus`, `RegisterControl.getInt32`); what the arm
//! executed inks like the plan.

use crate::common::{Sim, fails, free_port, maobi, ok, s};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

fn paper() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json")
}

/// The CSIM of `trace` rendered against `out/render.png`.
fn executed_csim(trace: &Path, out: &Path, dir: &Path) -> f64 {
    let img = dir.join("trace.png");
    let (t, p, tr) = (out.join("track.json"), paper(), trace.to_path_buf());
    ok(&maobi(&["robot", "render-trace", s(&tr), "--track", s(&t), "--paper", s(&p), "--size", "128", "-o", s(&img)]));
    let j: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["compare", s(&out.join("render.png")), s(&img), "--json"]))).unwrap();
    j["csim"].as_f64().unwrap()
}

#[test]
fn send_over_the_script_port_writes_yong_through_real_lua() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--size", "128", "--out", s(&out)]));
    let track = out.join("track.json");
    let (rpc, script) = (free_port(), free_port().to_string());
    let trace = dir.path().join("trace.jsonl");
    let sim = Sim::start(rpc, &["--script-port", &script, "--trace", s(&trace)]);
    let paper_json = paper();
    let rpc_s = rpc.to_string();
    let send = |extra: &[&str]| {
        let mut args = vec!["robot", "send", s(&track), "--paper", s(&paper_json), "--host", "127.0.0.1"];
        args.extend_from_slice(&["--port", &rpc_s, "--transport", "script", "--script-port", &script]);
        args.extend_from_slice(extra);
        maobi(&args)
    };
    let sent = ok(&send(&[]));
    assert!(sent.contains("5 of 5 strokes completed") && sent.contains("one Lua script"), "{sent}");
    assert!(sent.contains("the path buffers' joints on the controller's kinematics"), "{sent}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    drop(sim);
    assert!(executed_csim(&trace, &out, dir.path()) > 0.95);
    // Nominal joints are refused unless accepted, before anything is sent.
    let sim = Sim::start(rpc, &["--script-port", &script]);
    fails(&send(&["--nominal-kinematics"]), "pass --accept-nominal-kinematics");
    // A move per point runs too.
    let sent = ok(&send(&["--motion", "moves"]));
    assert!(sent.contains("5 of 5 strokes completed"), "{sent}");
    drop(sim);
}

/// The official SDK's clients (pyaubo_sdk 0.24.1): `ScriptClient.sendString` appends the
/// `\r\n\r\n` itself; `RpcClient` reads the runtime's state and the stroke count.
const SDK_SCRIPT: &str = r#"
import sys, time
import pyaubo_sdk
rpc_port, script_port, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rpc = pyaubo_sdk.RpcClient()
rpc.setRequestTimeout(2000)
rpc.connect("127.0.0.1", rpc_port)
rpc.login("aubo", "123456")
assert rpc.getRuntimeMachine().getStatus() == pyaubo_sdk.RuntimeState.Stopped
sc = pyaubo_sdk.ScriptClient()
sc.connect("127.0.0.1", script_port)
sc.login("aubo", "123456")
assert sc.sendString(open(path).read()) == 0
end = time.time() + 60
strokes = -1
while time.time() < end:
    time.sleep(0.05)
    strokes = rpc.getRegisterControl().getInt32("maobi_strokes", -1)
    if strokes >= 0 and rpc.getRuntimeMachine().getStatus() == pyaubo_sdk.RuntimeState.Stopped:
        break
print("strokes", strokes, flush=True)
sc.disconnect()
rpc.disconnect()
"#;

#[test]
fn the_official_sdk_sends_the_exported_script_and_follows_it() {
    let have = Command::new("python3").args(["-c", "import pyaubo_sdk"]).output().is_ok_and(|o| o.status.success());
    if !have {
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the_official_sdk_sends_the_exported_script_and_follows_it: python3 cannot import pyaubo_sdk"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--size", "128", "--out", s(&out)]));
    let (track, paper_json) = (out.join("track.json"), paper());
    let lua = dir.path().join("yong.lua");
    ok(&maobi(&[
        "robot",
        "export",
        s(&track),
        "--paper",
        s(&paper_json),
        "--format",
        "aubo-lua",
        "--accept-nominal-kinematics",
        "-o",
        s(&lua),
    ]));
    let (rpc, script) = (free_port(), free_port());
    let trace = dir.path().join("trace.jsonl");
    let sim = Sim::start(rpc, &["--script-port", &script.to_string(), "--trace", s(&trace)]);
    let o = Command::new("python3")
        .args(["-c", SDK_SCRIPT, &rpc.to_string(), &script.to_string(), s(&lua)])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && stdout.contains("strokes 5"), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    std::thread::sleep(std::time::Duration::from_millis(300));
    drop(sim);
    assert!(executed_csim(&trace, &out, dir.path()) > 0.95);
}
