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

/// One sample of the executed TCP path.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraceEntry {
    /// Time since the simulator started executing, s (at the commanded speeds).
    #[serde(default)]
    pub t_s: f64,
    /// The move this sample belongs to (`moveLine` or `moveJoint`).
    pub kind: TraceKind,
    /// TCP pose at this instant.
    pub pose: Pose,
}

/// Largest TCP travel between two trace samples, m.
pub const TRACE_STEP_M: f64 = 0.2e-3;
/// Largest time between two trace samples, s.
pub const TRACE_STEP_S: f64 = 0.005;
/// Largest tool rotation between two trace samples, rad.
pub const TRACE_STEP_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Executes a linear move as the simulator does: the TCP position moves in a straight line and
/// the orientation turns by slerp, both at constant speed `v_m_s` along the path (accelerations
/// and blending are not modelled: a stated simplification, see docs/robot.md). Returns the
/// samples after `from` up to and including `to`, at most [`TRACE_STEP_M`] of travel,
/// [`TRACE_STEP_RAD`] of rotation and [`TRACE_STEP_S`] apart, with their times after `t0_s`.
pub fn line_motion(from: &Pose, to: &Pose, v_m_s: f64, t0_s: f64) -> Vec<TraceEntry> {
    let (a, b) = (from.to_iso(), to.to_iso());
    let d = (b.translation.vector - a.translation.vector).norm();
    let turn = a.rotation.angle_to(&b.rotation);
    let v = if v_m_s > 0.0 { v_m_s } else { 1.0 };
    // Rotations in place run at an angular speed of v per 0.1 m (a stated choice).
    let duration = (d / v).max(turn * 0.1 / v);
    let n = (d / TRACE_STEP_M).max(turn / TRACE_STEP_RAD).max(duration / TRACE_STEP_S).ceil().clamp(1.0, 1e7) as usize;
    (1..=n)
        .map(|k| {
            let f = k as f64 / n as f64;
            let pose = if k == n {
                *to
            } else {
                let t = a.translation.vector.lerp(&b.translation.vector, f);
                let r = a.rotation.try_slerp(&b.rotation, f, 1e-12).unwrap_or(if f < 0.5 {
                    a.rotation
                } else {
                    b.rotation
                });
                Pose::from_iso(&nalgebra::Isometry3::from_parts(nalgebra::Translation3::from(t), r))
            };
            TraceEntry { t_s: t0_s + f * duration, kind: TraceKind::Line, pose }
        })
        .collect()
}

/// Executes a joint move: joints interpolated linearly at joint speed `v_rad_s`, the TCP pose by
/// forward kinematics, sampled as [`line_motion`].
pub fn joint_motion(
    from: &[f64; 6],
    to: &[f64; 6],
    v_rad_s: f64,
    tcp: &nalgebra::Isometry3<f64>,
    t0_s: f64,
) -> Vec<TraceEntry> {
    let dq = from.iter().zip(to).map(|(a, b)| (b - a).abs()).fold(0.0, f64::max);
    let duration = dq / if v_rad_s > 0.0 { v_rad_s } else { 1.0 };
    let n = (dq / TRACE_STEP_RAD).max(duration / TRACE_STEP_S).ceil().clamp(1.0, 1e7) as usize;
    (1..=n)
        .map(|k| {
            let f = k as f64 / n as f64;
            let q: [f64; 6] = std::array::from_fn(|j| from[j] + f * (to[j] - from[j]));
            TraceEntry {
                t_s: t0_s + f * duration,
                kind: TraceKind::Joint,
                pose: Pose::from_iso(&kinematics::forward(&q, tcp)),
            }
        })
        .collect()
}

/// Executes a whole program without a connection, as the simulator would if it were sent: the
/// first joint move from the simulator's home position, then every move in order. Returns the
/// executed path ([`line_motion`], [`joint_motion`]).
pub fn execute_program(program: &crate::program::Program) -> Vec<TraceEntry> {
    let tcp = program.tcp();
    let mut q = HOME_JOINTS;
    let mut out = Vec::new();
    let mut pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
    let mut t = 0.0;
    let f = program.speed_fraction;
    let mut run = |m: &crate::program::Move, out: &mut Vec<TraceEntry>| {
        let samples = match *m {
            crate::program::Move::Joint { q: q1, v, .. } => {
                let s = joint_motion(&q, &q1, v * f, &tcp, t);
                q = q1;
                s
            }
            crate::program::Move::Line { pose: p1, v, .. } => line_motion(&pose, &p1, v * f, t),
        };
        if let Some(last) = samples.last() {
            pose = last.pose;
            t = last.t_s;
        }
        out.extend(samples);
    };
    run(&program.start, &mut out);
    for m in program.strokes.iter().flat_map(|s| s.moves()) {
        run(m, &mut out);
    }
    out
}

/// The simulator's joint positions at start, rad.
pub const HOME_JOINTS: [f64; 6] = [0.0, 0.3, 1.6, 0.3, 1.57, 0.0];

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
    time_s: f64,
    moves_seen: usize,
    dropped: bool,
    faults: Faults,
}

impl State {
    fn record(&mut self, samples: Vec<TraceEntry>) {
        if let Some(last) = samples.last() {
            self.time_s = last.t_s;
        }
        self.trace.extend(samples);
    }
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
        let q0 = HOME_JOINTS;
        let tcp = tcp_iso(0.0);
        let state = Arc::new(Mutex::new(State {
            tcp_offset_m: 0.0,
            speed_fraction: 1.0,
            joints: q0,
            pose: Pose::from_iso(&kinematics::forward(&q0, &tcp)),
            trace: Vec::new(),
            time_s: 0.0,
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

    /// The executed TCP path from sample `from` on (for appending to a trace file as it grows).
    pub fn trace_since(&self, from: usize) -> Vec<TraceEntry> {
        let st = self.state.lock().expect("sim state");
        st.trace.get(from..).map(<[TraceEntry]>::to_vec).unwrap_or_default()
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
                let samples = joint_motion(&st.joints, &q, vv * st.speed_fraction, &tcp, st.time_s);
                st.joints = q;
                st.pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
                st.record(samples);
            } else {
                let Some(p) = params.first().and_then(numbers::<6>) else { return ok(&id, json!(INVALID_ARGUMENT)) };
                let pose = Pose(p);
                let seed = st.joints;
                let Some(q) = kinematics::inverse(&pose, &tcp, Some(&seed)) else { return ok(&id, json!(UNREACHABLE)) };
                let samples = line_motion(&st.pose, &pose, vv * st.speed_fraction, st.time_s);
                st.joints = q;
                st.pose = pose;
                st.record(samples);
            }
            ok(&id, json!(0))
        }
        _ => err(&id, -32601, &format!("method not found: {method}")),
    }
}

/// Turns an executed TCP path back into commanded brush states on the paper, for the forward
/// model (`brush_model::ForwardModel`): the position where the tool axis meets the paper, the
/// depth below it (H; negative above the paper, where the brush leaves nothing), the tilt α of
/// the tool axis from the paper normal and the direction β it leans towards. Joint moves are
/// included (they happen above the paper). The result is one sequence: the forward model ends a
/// contact wherever H ≤ 0.
pub fn trace_to_states(trace: &[TraceEntry], frame: &crate::frame::PaperFrame) -> Vec<brush_model::TrackPoint> {
    let inv = frame.iso.rotation.inverse();
    trace
        .iter()
        .map(|t| {
            let p = frame.to_paper(t.pose.position());
            let z = inv * (t.pose.to_iso().rotation * nalgebra::Vector3::z());
            let alpha = z.z.clamp(-1.0, 1.0).acos();
            let beta = if z.x.hypot(z.y) > 1e-12 { z.y.atan2(z.x) } else { 0.0 };
            // Round-off of a pose at the surface must not count as contact.
            let h = if p[2].abs() < 1e-6 { 0.0 } else { p[2] };
            brush_model::TrackPoint { x_mm: p[0], y_mm: p[1], h_mm: h, alpha_rad: alpha, beta_rad: beta }
        })
        .collect()
}
