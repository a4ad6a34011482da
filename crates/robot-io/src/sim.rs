//! A loopback AUBO JSON-RPC simulator: validates every request, executes moves on a model of
//! the arm, answers `getExecId`/`getTcpPose`, injects faults, and records the executed TCP path.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::RobotError;
use crate::kinematics;
use crate::pose::Pose;
use crate::program::tcp_iso;

/// Faults to inject.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Faults {
    /// Close the connection (once) when the N-th move request arrives, without executing it.
    pub drop_after_moves: Option<usize>,
    /// Delay every answer by this many milliseconds.
    pub delay_ms: Option<u64>,
    /// Answer every K-th move request with 2 (queue full) without executing it.
    pub queue_full_every: Option<usize>,
}

/// The robot name the simulator answers to.
pub const SIM_ROBOT: &str = "rob1";

/// One executed move in the trace.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraceEntry {
    /// `moveLine` or `moveJoint`.
    pub kind: TraceKind,
    /// TCP pose reached.
    pub pose: Pose,
}

/// Kind of executed move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TraceKind {
    /// A joint move.
    Joint,
    /// A linear move.
    Line,
}

#[derive(Debug)]
struct State {
    tcp_offset_m: f64,
    speed_fraction: f64,
    joints: [f64; 6],
    pose: Pose,
    trace: Vec<TraceEntry>,
    moves_seen: usize,
    dropped: bool,
    faults: Faults,
}

/// A running simulator.
pub struct Simulator {
    /// The address it listens on.
    pub addr: std::net::SocketAddr,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Simulator {
    /// Starts a simulator on `bind` (for example `127.0.0.1:0` for any free port).
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address cannot be bound.
    pub fn start(bind: &str, faults: Faults) -> Result<Self, RobotError> {
        let listener = TcpListener::bind(bind).map_err(|e| RobotError::Io(format!("{bind}: {e}")))?;
        let addr = listener.local_addr().map_err(|e| RobotError::Io(e.to_string()))?;
        listener.set_nonblocking(true).map_err(|e| RobotError::Io(e.to_string()))?;
        let q0 = [0.0, 0.3, 1.6, 0.3, 1.57, 0.0];
        let tcp = tcp_iso(0.0);
        let state = Arc::new(Mutex::new(State {
            tcp_offset_m: 0.0,
            speed_fraction: 1.0,
            joints: q0,
            pose: Pose::from_iso(&kinematics::forward(&q0, &tcp)),
            trace: Vec::new(),
            moves_seen: 0,
            dropped: false,
            faults,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (st, sp) = (state.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !sp.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        let st = st.clone();
                        let sp = sp.clone();
                        std::thread::spawn(move || serve(stream, st, sp));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(5)),
                }
            }
        });
        Ok(Simulator { addr, state, stop, thread: Some(thread) })
    }

    /// The executed TCP path so far.
    pub fn trace(&self) -> Vec<TraceEntry> {
        self.state.lock().expect("sim state").trace.clone()
    }

    /// Stops accepting connections.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Simulator {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn serve(mut stream: TcpStream, state: Arc<Mutex<State>>, stop: Arc<AtomicBool>) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = [0u8; 4096];
    while !stop.load(Ordering::SeqCst) {
        // Answer every complete request in the buffer.
        loop {
            let start = buf.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(buf.len());
            buf.drain(..start);
            if buf.is_empty() {
                break;
            }
            let mut it = serde_json::Deserializer::from_slice(&buf).into_iter::<Value>();
            let v = match it.next() {
                Some(Ok(v)) => {
                    let used = it.byte_offset();
                    buf.drain(..used);
                    v
                }
                Some(Err(e)) if e.is_eof() => break,
                _ => {
                    let _ = write_json(
                        &mut stream,
                        &json!({"jsonrpc": "2.0", "id": null, "error": {"code": -32700, "message": "parse error"}}),
                    );
                    return;
                }
            };
            match handle(&v, &state) {
                Reply::Answer(a) => {
                    let delay = state.lock().expect("sim state").faults.delay_ms;
                    if let Some(ms) = delay {
                        std::thread::sleep(Duration::from_millis(ms));
                    }
                    if write_json(&mut stream, &a).is_err() {
                        return;
                    }
                }
                Reply::Drop => return,
            }
        }
        match stream.read(&mut chunk) {
            Ok(0) => return,
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(_) => return,
        }
    }
}

fn write_json(s: &mut TcpStream, v: &Value) -> std::io::Result<()> {
    let mut b = serde_json::to_vec(v).expect("serialisable");
    b.push(b'\n');
    s.write_all(&b)
}

enum Reply {
    Answer(Value),
    Drop,
}

fn err(id: &Value, code: i64, message: &str) -> Reply {
    Reply::Answer(json!({"jsonrpc": "2.0", "id": id, "error": {"code": code, "message": message}}))
}

fn ok(id: &Value, result: Value) -> Reply {
    Reply::Answer(json!({"jsonrpc": "2.0", "id": id, "result": result}))
}

fn numbers<const N: usize>(v: &Value) -> Option<[f64; N]> {
    let a = v.as_array()?;
    if a.len() != N {
        return None;
    }
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().filter(|f| f.is_finite())?;
    }
    Some(out)
}

/// Status codes the simulator returns for rejected motions.
const INVALID_ARGUMENT: i64 = -5;
const UNREACHABLE: i64 = -10;

fn handle(v: &Value, state: &Mutex<State>) -> Reply {
    let id = v.get("id").cloned().unwrap_or(Value::Null);
    if v.get("jsonrpc") != Some(&json!("2.0"))
        || !v.get("method").is_some_and(Value::is_string)
        || v.get("id").is_none()
    {
        return err(&id, -32600, "invalid request: need jsonrpc \"2.0\", a method and an id");
    }
    let Some(params) = v.get("params").and_then(Value::as_array) else {
        return err(&id, -32602, "params must be an array");
    };
    let method = v["method"].as_str().expect("checked");
    let mut st = state.lock().expect("sim state");
    if method == "getRobotNames" {
        return ok(&id, json!([SIM_ROBOT]));
    }
    let Some((robot, rest)) = method.split_once('.') else {
        return err(&id, -32601, "method not found");
    };
    if robot != SIM_ROBOT {
        return err(&id, -32601, &format!("unknown robot `{robot}`"));
    }
    match rest {
        "RobotConfig.setTcpOffset" => match params.first().and_then(numbers::<6>) {
            Some(o) if o[2] >= 0.0 && o[2] < 0.5 => {
                st.tcp_offset_m = o[2];
                let q = st.joints;
                st.pose = Pose::from_iso(&kinematics::forward(&q, &tcp_iso(o[2])));
                ok(&id, json!(0))
            }
            _ => ok(&id, json!(INVALID_ARGUMENT)),
        },
        "MotionControl.setSpeedFraction" => match params.first().and_then(Value::as_f64) {
            Some(f) if f > 0.0 && f <= 1.0 => {
                st.speed_fraction = f;
                ok(&id, json!(0))
            }
            _ => ok(&id, json!(INVALID_ARGUMENT)),
        },
        "MotionControl.getExecId" => ok(&id, json!(-1)),
        "RobotState.getTcpPose" => ok(&id, json!(st.pose.0)),
        "MotionControl.moveJoint" | "MotionControl.moveLine" => {
            st.moves_seen += 1;
            let n = st.moves_seen;
            if let Some(k) = st.faults.drop_after_moves {
                if n == k && !st.dropped {
                    st.dropped = true;
                    return Reply::Drop;
                }
            }
            if let Some(k) = st.faults.queue_full_every {
                if k > 0 && n % k == 0 {
                    return ok(&id, json!(crate::aubo::QUEUE_FULL));
                }
            }
            if params.len() != 5 {
                return ok(&id, json!(INVALID_ARGUMENT));
            }
            let (a, vv, blend) = (params[1].as_f64(), params[2].as_f64(), params[3].as_f64());
            let (Some(a), Some(vv), Some(blend)) = (a, vv, blend) else { return ok(&id, json!(INVALID_ARGUMENT)) };
            if !(a > 0.0 && a <= 20.0 && vv > 0.0 && vv <= 3.2 && (0.0..=0.1).contains(&blend)) {
                return ok(&id, json!(INVALID_ARGUMENT));
            }
            let tcp = tcp_iso(st.tcp_offset_m);
            if rest == "MotionControl.moveJoint" {
                let Some(q) = params.first().and_then(numbers::<6>) else { return ok(&id, json!(INVALID_ARGUMENT)) };
                if q.iter().any(|x| x.abs() > kinematics::JOINT_LIMIT_RAD) {
                    return ok(&id, json!(UNREACHABLE));
                }
                st.joints = q;
                st.pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
                let pose = st.pose;
                st.trace.push(TraceEntry { kind: TraceKind::Joint, pose });
            } else {
                let Some(p) = params.first().and_then(numbers::<6>) else { return ok(&id, json!(INVALID_ARGUMENT)) };
                let pose = Pose(p);
                let seed = st.joints;
                let Some(q) = kinematics::inverse(&pose, &tcp, Some(&seed)) else { return ok(&id, json!(UNREACHABLE)) };
                st.joints = q;
                st.pose = pose;
                st.trace.push(TraceEntry { kind: TraceKind::Line, pose });
            }
            ok(&id, json!(0))
        }
        _ => err(&id, -32601, &format!("method not found: {method}")),
    }
}

/// Turns an executed TCP path back into a brush track on the paper, so it can be rendered and
/// compared with the planned render: poses below the paper surface are presses (depth = H), the
/// tool axis gives α and, when tilted, β; for an upright brush (α ≈ 0) β cannot be seen in the
/// pose and is taken from the motion as a dragged brush would leave it: the footprint points back
/// at the executed path point one footprint length behind (`footprint_len(h)`, mm), or at the
/// stroke's first point when the stroke is shorter, and forward for a stroke's first point.
/// Consecutive presses form a stroke; any pose at or above the paper ends it.
pub fn trace_to_track(
    trace: &[TraceEntry],
    frame: &crate::frame::PaperFrame,
    footprint_len: impl Fn(f64) -> f64,
) -> brush_model::Track {
    use brush_model::{Stroke, Track, TrackPoint};
    let mut strokes: Vec<Stroke> = Vec::new();
    let mut cur: Vec<TrackPoint> = Vec::new();
    let inv = frame.iso.rotation.inverse();
    for t in trace.iter().filter(|t| t.kind == TraceKind::Line) {
        let p = frame.to_paper(t.pose.position());
        if p[2] <= 1e-6 {
            if !cur.is_empty() {
                strokes.push(Stroke { points: std::mem::take(&mut cur) });
            }
            continue;
        }
        let z = inv * (t.pose.to_iso().rotation * nalgebra::Vector3::z());
        let alpha = z.z.clamp(-1.0, 1.0).acos();
        let beta = if alpha > 1e-6 { z.y.atan2(z.x) } else { f64::NAN };
        cur.push(TrackPoint { x_mm: p[0], y_mm: p[1], h_mm: p[2], alpha_rad: alpha, beta_rad: beta });
    }
    if !cur.is_empty() {
        strokes.push(Stroke { points: cur });
    }
    for s in &mut strokes {
        let n = s.points.len();
        for i in 0..n {
            if s.points[i].beta_rad.is_nan() {
                let here = s.points[i];
                let len = footprint_len(here.h_mm);
                let far = |q: &TrackPoint| (q.x_mm - here.x_mm).hypot(q.y_mm - here.y_mm) >= len;
                let other = if i > 0 {
                    s.points[..i].iter().rev().find(|q| far(q)).copied().unwrap_or(s.points[0])
                } else {
                    s.points[1..].iter().find(|q| far(q)).copied().or(s.points.get(n - 1).copied()).unwrap_or(here)
                };
                let (dx, dy) = (other.x_mm - here.x_mm, other.y_mm - here.y_mm);
                s.points[i].beta_rad = if dx == 0.0 && dy == 0.0 { 0.0 } else { dy.atan2(dx) };
            }
        }
    }
    Track { strokes }
}
