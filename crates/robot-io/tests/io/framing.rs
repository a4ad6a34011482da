//! The framed transport's edge cases, on loopback, both ways (maobi's client reading a scripted
//! peer, and the simulator reading scripted bytes): a frame split at every byte offset, two
//! frames in one read, a frame over 1 MB, a bad magic, a length beyond the limit, a connection
//! dropped mid-frame, a peer that never answers. Each ends in the answer or in a clear error,
//! in bounded time.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};

use robot_io::RobotError;
use robot_io::aubo::AuboClient;
use robot_io::sim::{Faults, Simulator};
use robot_io::wire::Transport;
use robot_io::wire::{FrameDecoder, MAX_FRAME_BYTES, encode_frame};
use serde_json::{Value, json};

const T: Duration = Duration::from_millis(500);

/// Reads one type-1 frame's payload from `s` (test side), within 5 s.
fn read_frame(s: &mut TcpStream) -> Option<Vec<u8>> {
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut head = [0u8; 8];
    s.read_exact(&mut head).ok()?;
    assert_eq!(&head[..4], b"SOF\x01");
    let mut p = vec![0u8; u32::from_be_bytes(head[4..8].try_into().unwrap()) as usize];
    s.read_exact(&mut p).ok()?;
    Some(p)
}

/// A peer that accepts `n` connections one after another and runs `script` on each with the
/// first request frame's JSON (the version query of a handshake-less client call).
fn peer(n: usize, script: impl Fn(usize, &mut TcpStream, Value) + Send + 'static) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        for i in 0..n {
            let Ok((mut s, _)) = listener.accept() else { return };
            s.set_nodelay(true).unwrap();
            let Some(req) = read_frame(&mut s) else { continue };
            script(i, &mut s, serde_json::from_slice(&req).unwrap());
            // Keep the connection until the client is done with it.
            let mut sink = [0u8; 64];
            s.set_read_timeout(Some(Duration::from_secs(3))).unwrap();
            while matches!(s.read(&mut sink), Ok(k) if k > 0) {}
        }
    });
    addr
}

fn answer(req: &Value, result: Value) -> Vec<u8> {
    encode_frame(&serde_json::to_vec(&json!({"jsonrpc": "2.0", "id": req["id"], "result": result})).unwrap()).unwrap()
}

fn client(addr: &str) -> AuboClient {
    AuboClient::connect_with(addr, Transport::Framed, T).unwrap()
}

#[test]
fn an_answer_split_at_every_byte_offset_is_read_whole() {
    // The length of the answer frame is fixed by the id's length (18) and the result.
    let len = answer(&json!({"id": "xxxxxxxx-xxxx-xxxx"}), json!(-1)).len();
    let addr = peer(len - 1, |i, s, req| {
        let f = answer(&req, json!(-1));
        s.write_all(&f[..=i]).unwrap();
        s.flush().unwrap();
        std::thread::sleep(Duration::from_millis(3));
        s.write_all(&f[i + 1..]).unwrap();
    });
    for k in 1..len {
        assert_eq!(client(&addr).exec_id("rob1").unwrap(), -1, "split after {k} bytes");
    }
    // The decoder alone, fed one byte at a time, gives the frame once, at its last byte.
    let f = answer(&json!({"id": "a"}), json!([1, 2]));
    let mut d = FrameDecoder::default();
    for (i, b) in f.iter().enumerate() {
        d.push(&[*b]);
        assert_eq!(d.next_frame().unwrap().is_some(), i == f.len() - 1, "byte {i}");
    }
}

#[test]
fn the_simulator_reads_a_request_split_at_every_byte_offset() {
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let req = encode_frame(br#"{"id":"v","jsonrpc":"2.0","method":"SystemInfo.getInterfaceVersionCode"}"#).unwrap();
    for k in 1..req.len() {
        let mut s = TcpStream::connect(sim.addr).unwrap();
        s.set_nodelay(true).unwrap();
        s.write_all(&req[..k]).unwrap();
        s.flush().unwrap();
        std::thread::sleep(Duration::from_millis(2));
        s.write_all(&req[k..]).unwrap();
        let v: Value = serde_json::from_slice(&read_frame(&mut s).expect("an answer")).unwrap();
        assert_eq!(v["result"], 24000, "split after {k} bytes");
    }
}

#[test]
fn two_frames_in_one_read_are_both_used() {
    // A stale answer and the right one, in one write; then a type-0 frame (2-byte length).
    let addr = peer(1, |_, s, req| {
        let mut both = answer(&json!({"id": "stale-answer"}), json!(7));
        both.extend(answer(&req, json!(-1)));
        s.write_all(&both).unwrap();
        let next: Value = serde_json::from_slice(&read_frame(s).unwrap()).unwrap();
        let body = serde_json::to_vec(&json!({"jsonrpc": "2.0", "id": next["id"], "result": true})).unwrap();
        let mut short = b"SOF\x00".to_vec();
        short.extend_from_slice(&(body.len() as u16).to_be_bytes());
        short.extend_from_slice(&body);
        s.write_all(&short).unwrap();
    });
    let mut c = client(&addr);
    assert_eq!(c.exec_id("rob1").unwrap(), -1);
    assert!(c.is_steady("rob1").unwrap());
    // The simulator answers two requests written at once, in order.
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut s = TcpStream::connect(sim.addr).unwrap();
    let mut two = encode_frame(br#"{"id":"1","jsonrpc":"2.0","method":"SystemInfo.getInterfaceVersionCode"}"#).unwrap();
    two.extend(encode_frame(br#"{"id":"2","jsonrpc":"2.0","method":"SystemInfo.getInterfaceVersionCode"}"#).unwrap());
    s.write_all(&two).unwrap();
    for id in ["1", "2"] {
        let v: Value = serde_json::from_slice(&read_frame(&mut s).unwrap()).unwrap();
        assert_eq!((v["id"].as_str(), &v["result"]), (Some(id), &json!(24000)));
    }
}

#[test]
fn frames_over_a_megabyte_pass_both_ways() {
    let big = "x".repeat(1_500_000);
    let name = big.clone();
    let addr = peer(1, move |_, s, req| s.write_all(&answer(&req, json!([name.clone()]))).unwrap());
    let mut c = AuboClient::connect_with(&addr, Transport::Framed, Duration::from_secs(5)).unwrap();
    // A raw call: `robot_names` refuses a name that is not a short identifier (issue 26).
    let names = c.call("getRobotNames", Value::Null).unwrap();
    assert_eq!(names.as_array().map(Vec::len), Some(1));
    assert_eq!(names[0].as_str().map(str::len), Some(1_500_000));
    // The simulator takes a request just under its 1 MiB limit (the version query ignores its
    // params), and refuses the 1.5 MB one, saying so before it closes.
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let req = |pad: &str| {
        let r = json!({"id": "big", "jsonrpc": "2.0", "method": "SystemInfo.getInterfaceVersionCode", "params": {"pad": pad}});
        encode_frame(&serde_json::to_vec(&r).unwrap()).unwrap()
    };
    let mut s = TcpStream::connect(sim.addr).unwrap();
    s.write_all(&req(&"x".repeat(1_000_000))).unwrap();
    let v: Value = serde_json::from_slice(&read_frame(&mut s).unwrap()).unwrap();
    assert_eq!(v["result"], 24000);
    let mut s = TcpStream::connect(sim.addr).unwrap();
    let _ = s.write_all(&req(&big));
    let v: Value = serde_json::from_slice(&read_frame(&mut s).unwrap()).unwrap();
    let m = v["error"]["message"].as_str().unwrap();
    assert!(m.contains("exceeds the limit of 1048576 bytes"), "{v}");
    assert_eq!(s.read(&mut [0u8; 16]).unwrap(), 0, "closed after the error");
}

#[test]
fn a_bad_magic_is_a_framing_error() {
    let addr = peer(1, |_, s, req| {
        let mut f = answer(&req, json!(-1));
        f[..3].copy_from_slice(b"XOF");
        s.write_all(&f).unwrap();
    });
    let t0 = Instant::now();
    let e = client(&addr).exec_id("rob1").unwrap_err();
    assert!(matches!(&e, RobotError::Framing(m) if m.contains("expected a frame starting with \"SOF\"")), "{e}");
    assert!(t0.elapsed() < T, "no waiting for more bytes");
    // An unknown frame type too.
    let addr = peer(1, |_, s, req| {
        let mut f = answer(&req, json!(-1));
        f[3] = 7;
        s.write_all(&f).unwrap();
    });
    let e = client(&addr).exec_id("rob1").unwrap_err();
    assert!(e.to_string().contains("frame type 7"), "{e}");
    // The simulator hangs up on a bad magic (the stream cannot be resynchronised).
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut s = TcpStream::connect(sim.addr).unwrap();
    s.write_all(b"SOX\x01\x00\x00\x00\x02{}").unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut buf = [0u8; 16];
    assert_eq!(s.read(&mut buf).unwrap(), 0, "closed without an answer");
}

#[test]
fn a_length_beyond_the_limit_is_refused_at_once() {
    let addr = peer(1, |_, s, _| s.write_all(b"SOF\x01\xff\xff\xff\xff{").unwrap());
    let t0 = Instant::now();
    let e = client(&addr).exec_id("rob1").unwrap_err();
    assert!(
        matches!(&e, RobotError::Framing(m) if m.contains("4294967295 bytes exceeds the limit of 8388608 bytes")),
        "{e}"
    );
    assert!(t0.elapsed() < T);
    assert!(encode_frame(&vec![0u8; MAX_FRAME_BYTES + 1]).is_err());
    // The simulator closes the connection instead of waiting for 2 GB, saying why.
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut s = TcpStream::connect(sim.addr).unwrap();
    s.write_all(b"SOF\x01\x7f\xff\xff\xff{").unwrap();
    let v: Value = serde_json::from_slice(&read_frame(&mut s).unwrap()).unwrap();
    assert!(v["error"]["message"].as_str().unwrap().contains("exceeds the limit of 1048576 bytes"), "{v}");
    let mut buf = [0u8; 16];
    assert_eq!(s.read(&mut buf).unwrap(), 0);
}

#[test]
fn a_connection_dropped_mid_frame_says_so() {
    let addr = peer(1, |_, s, req| {
        let f = answer(&req, json!(-1));
        s.write_all(&f[..f.len() / 2]).unwrap();
        s.shutdown(std::net::Shutdown::Both).unwrap();
    });
    let e = client(&addr).exec_id("rob1").unwrap_err();
    assert!(
        matches!(&e, RobotError::Io { source, .. } if source.to_string().contains("closed in the middle of a frame")),
        "{e}"
    );
    // Dropped inside the header.
    let addr = peer(1, |_, s, _| {
        s.write_all(b"SOF\x01\x00").unwrap();
        s.shutdown(std::net::Shutdown::Both).unwrap();
    });
    let e = client(&addr).exec_id("rob1").unwrap_err();
    let cause = std::error::Error::source(&e).map(ToString::to_string).unwrap_or_default();
    assert!(cause.contains("middle of a frame header (5 bytes)"), "{e}: {cause}");
}

#[test]
fn a_peer_that_never_answers_times_out() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let hold = std::thread::spawn(move || {
        let (s, _) = listener.accept().unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        drop(s);
    });
    let t0 = Instant::now();
    let e = client(&addr).exec_id("rob1").unwrap_err();
    let took = t0.elapsed();
    assert!(matches!(&e, RobotError::Timeout(m) if m.contains("getExecId")), "{e}");
    assert!(took >= T && took < T * 2, "{took:?}");
    hold.join().unwrap();
}
