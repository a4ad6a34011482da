//! maobi's framed client sends, call for call, the bytes the official AUBO SDK client sends
//! (golden captures in `tests/golden/`, made by `capture_sdk.py`), ids aside; and the login
//! digest is the SDK's for every captured password.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use robot_io::aubo::AuboClient;
use robot_io::wire::Transport;
use robot_io::{Move, Pose};
use serde_json::{Value, json};

fn golden() -> Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/sdk_frames.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn unhex(s: &str) -> Vec<u8> {
    (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap()).collect()
}

/// The frame with its JSON-RPC id replaced by `<id>` and the length recomputed; checks the
/// header on the way.
fn without_id(frame: &[u8]) -> Vec<u8> {
    assert_eq!(&frame[..4], b"SOF\x01", "frame header");
    let len = u32::from_be_bytes(frame[4..8].try_into().unwrap()) as usize;
    assert_eq!(len, frame.len() - 8, "length field counts the payload only");
    let text = String::from_utf8(frame[8..].to_vec()).unwrap();
    let text = match text.strip_prefix("{\"id\":\"") {
        Some(rest) => {
            let end = rest.find('"').unwrap();
            format!("{{\"id\":\"<id>{}", &rest[end..])
        }
        None => text,
    };
    let mut out = b"SOF\x01".to_vec();
    out.extend_from_slice(&(text.len() as u32).to_be_bytes());
    out.extend_from_slice(text.as_bytes());
    out
}

/// A loopback controller that records every frame and answers like the capture's server.
struct Recorder {
    addr: String,
    frames: Arc<Mutex<Vec<Vec<u8>>>>,
    taken: usize,
}

impl Recorder {
    fn start() -> Recorder {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let frames = Arc::new(Mutex::new(Vec::new()));
        let rec = frames.clone();
        std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
            let mut buf = Vec::new();
            let mut chunk = [0u8; 4096];
            let end = Instant::now() + Duration::from_secs(30);
            while Instant::now() < end {
                while buf.len() >= 8 {
                    let n = u32::from_be_bytes(buf[4..8].try_into().unwrap()) as usize;
                    if buf.len() < 8 + n {
                        break;
                    }
                    let frame: Vec<u8> = buf.drain(..8 + n).collect();
                    let payload = &frame[8..];
                    rec.lock().unwrap().push(frame.clone());
                    let reply = if payload.starts_with(b"__login__") {
                        b"__login__\nSUCCEED".to_vec()
                    } else {
                        let r: Value = serde_json::from_slice(payload).unwrap();
                        let result = match r["method"].as_str().unwrap() {
                            "SystemInfo.getInterfaceVersionCode" => json!(24000),
                            "getRobotNames" => json!(["rob1"]),
                            "getAxisNames" => json!([]),
                            "rob1.MotionControl.getExecId" => json!(-1),
                            "rob1.RobotState.isSteady" => json!(true),
                            "rob1.RobotState.getTcpPose" => json!([0.4, 0.1, 0.3, std::f64::consts::PI, 0.0, 0.0]),
                            "rob1.RobotState.getJointPositions" => json!([0.0, 0.3, 1.6, 0.3, 1.57, 0.0]),
                            _ => json!(0),
                        };
                        serde_json::to_vec(&json!({"id": r["id"], "jsonrpc": "2.0", "result": result})).unwrap()
                    };
                    let mut out = b"SOF\x01".to_vec();
                    out.extend_from_slice(&(reply.len() as u32).to_be_bytes());
                    out.extend_from_slice(&reply);
                    if s.write_all(&out).is_err() {
                        return;
                    }
                }
                match s.read(&mut chunk) {
                    Ok(0) | Err(_) => return,
                    Ok(n) => buf.extend_from_slice(&chunk[..n]),
                }
            }
        });
        Recorder { addr, frames, taken: 0 }
    }

    /// The frames received since the last call.
    fn new_frames(&mut self) -> Vec<Vec<u8>> {
        let all = self.frames.lock().unwrap();
        let new = all[self.taken..].to_vec();
        self.taken = all.len();
        new
    }
}

fn six(v: &Value) -> [f64; 6] {
    serde_json::from_value(v.clone()).unwrap()
}

#[test]
fn every_call_sends_the_sdks_bytes() {
    let g = golden();
    let calls = g["calls"].as_array().unwrap();
    let want = |name: &str, nth: usize| -> (&Value, Vec<Vec<u8>>) {
        let c = calls.iter().filter(|c| c["call"] == name).nth(nth).unwrap_or_else(|| panic!("no capture of {name}"));
        (&c["args"], c["frames"].as_array().unwrap().iter().map(|f| unhex(f.as_str().unwrap())).collect())
    };
    let mut rec = Recorder::start();
    let mut c = AuboClient::connect_with(&rec.addr, Transport::Framed, Duration::from_secs(5)).unwrap();
    let check = |rec: &mut Recorder, what: &str, sdk: Vec<Vec<u8>>| {
        let ours = rec.new_frames();
        assert_eq!(ours.len(), sdk.len(), "{what}: frames sent");
        for (o, s) in ours.iter().zip(&sdk) {
            // Our ids have the SDK's shape: the raw frames are as long as the SDK's.
            assert_eq!(o.len(), s.len(), "{what}: frame length");
            assert_eq!(
                String::from_utf8_lossy(&without_id(o)),
                String::from_utf8_lossy(&without_id(s)),
                "{what}: bytes differ from the SDK's"
            );
        }
    };
    // The SDK's connect() asks for the version; its login() logs in, then asks for the robot and
    // axis names. maobi's handshake sends the same four frames in the same order.
    let (_, connect) = want("connect", 0);
    let (login_args, login) = want("login", 0);
    let (_, names) = want("getRobotNames", 0);
    assert!(names.is_empty(), "the SDK answers getRobotNames after login from what login fetched");
    let robots = c.handshake(login_args["user"].as_str().unwrap(), login_args["password"].as_str().unwrap()).unwrap();
    assert_eq!(robots, vec!["rob1".to_string()]);
    assert_eq!(c.interface_version(), Some(24000));
    check(&mut rec, "connect + login", connect.into_iter().chain(login).collect());

    let (args, sdk) = want("setTcpOffset", 0);
    assert_eq!(c.set_tcp_offset("rob1", six(&args["offset"])).unwrap(), 0);
    check(&mut rec, "setTcpOffset", sdk);
    let (args, sdk) = want("setSpeedFraction", 0);
    assert_eq!(c.set_speed_fraction("rob1", args["fraction"].as_f64().unwrap()).unwrap(), 0);
    check(&mut rec, "setSpeedFraction", sdk);
    let (args, sdk) = want("moveJoint", 0);
    let m = Move::Joint { q: six(&args["q"]), a: args["a"].as_f64().unwrap(), v: args["v"].as_f64().unwrap() };
    c.send_move("rob1", &m).unwrap();
    check(&mut rec, "moveJoint", sdk);
    for nth in 0..2 {
        let (args, sdk) = want("moveLine", nth);
        let m = Move::Line {
            pose: Pose(six(&args["pose"])),
            a: args["a"].as_f64().unwrap(),
            v: args["v"].as_f64().unwrap(),
            blend_m: args["blend_radius"].as_f64().unwrap(),
        };
        c.send_move("rob1", &m).unwrap();
        check(&mut rec, &format!("moveLine {}", nth + 1), sdk);
    }
    let (_, sdk) = want("getExecId", 0);
    assert_eq!(c.exec_id("rob1").unwrap(), -1);
    check(&mut rec, "getExecId", sdk);
    let (_, sdk) = want("isSteady", 0);
    assert!(c.is_steady("rob1").unwrap());
    check(&mut rec, "isSteady", sdk);
    let (_, sdk) = want("getTcpPose", 0);
    assert_eq!(c.tcp_pose("rob1").unwrap().0[3], std::f64::consts::PI);
    check(&mut rec, "getTcpPose", sdk);
    let (_, sdk) = want("getJointPositions", 0);
    assert_eq!(c.joint_positions("rob1").unwrap(), [0.0, 0.3, 1.6, 0.3, 1.57, 0.0]);
    check(&mut rec, "getJointPositions", sdk);
}

#[test]
fn the_login_digest_is_the_sdks_for_every_captured_password() {
    let g = golden();
    let digests = g["digests"].as_array().unwrap();
    assert!(digests.len() >= 8);
    for d in digests {
        let (user, pw) = (d["user"].as_str().unwrap(), d["password"].as_str().unwrap());
        assert_eq!(robot_io::wire::login_digest(pw), d["digest"].as_str().unwrap(), "password {pw:?}");
        // The whole login frame, byte for byte (it carries no id).
        let frame = robot_io::wire::encode_frame(&robot_io::wire::login_payload(user, pw).unwrap()).unwrap();
        assert_eq!(frame, unhex(d["frame"].as_str().unwrap()), "login frame for {user:?} / {pw:?}");
    }
}
