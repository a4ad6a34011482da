//! A loopback AUBO JSON-RPC simulator: serves the SDK's framed transport (with its login), the
//! line-delimited form and JSON-RPC over HTTP; validates every request (named or positional
//! params), executes moves on a model of the arm, answers `getExecId`, `isSteady`,
//! `getTcpPose` and `getJointPositions`, injects faults, and records the executed TCP path.

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
use crate::program::{
    CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_SPEED_FRACTION,
    CONTROLLER_MAX_TCP_OFFSET_M, tcp_iso,
};
use crate::wire;
pub use crate::wire::Transport;

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
            crate::program::Move::JointPose { pose: p1, v, .. } => {
                // Solved as the controller would, from the present joints; a checked program's
                // poses are reachable, so the straight line is only a fallback.
                match kinematics::inverse(&p1, &tcp, Some(&q)) {
                    Some(q1) => {
                        let s = joint_motion(&q, &q1, v * f, &tcp, t);
                        q = q1;
                        s
                    }
                    None => line_motion(&pose, &p1, v * f, t),
                }
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

/// The simulator's joint positions at start, rad (controller convention): the tool points
/// straight down with the flange 0.44 m above the base, in front of the arm.
pub const HOME_JOINTS: [f64; 6] = [0.0, -0.3, 1.2, -0.0708, std::f64::consts::FRAC_PI_2, 0.0];

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

/// What the simulator answers to besides its listeners: the faults to inject and the one user
/// who may log in over the framed transport.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SimOptions {
    /// Faults to inject.
    pub faults: Faults,
    /// The user the framed login accepts.
    pub user: String,
    /// The password the framed login accepts (compared by its digest, as a controller would).
    pub password: String,
}

impl Default for SimOptions {
    /// No faults; the controller's default user `aubo`, password `123456`.
    fn default() -> Self {
        Self { faults: Faults::default(), user: wire::DEFAULT_USER.into(), password: wire::DEFAULT_PASSWORD.into() }
    }
}

/// One port the simulator listens on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Listen {
    /// The address to bind, for example `127.0.0.1:30004` (`:0` for any free port).
    pub bind: String,
    /// The transport it serves; `None` serves all three, told apart by each connection's first
    /// byte (`S` of `SOF`: framed; `{` or `[`: lines; a capital letter, as in `POST`: HTTP).
    pub transport: Option<Transport>,
}

/// A running simulator.
pub struct Simulator {
    /// The address it listens on (the first listener's).
    pub addr: std::net::SocketAddr,
    addrs: Vec<(Option<Transport>, std::net::SocketAddr)>,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Simulator {
    /// Starts a simulator on `bind` (for example `127.0.0.1:0` for any free port) serving every
    /// transport on that one port, with the default login.
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address cannot be bound.
    pub fn start(bind: &str, faults: Faults) -> Result<Self, RobotError> {
        Self::start_with(
            &[Listen { bind: bind.to_string(), transport: None }],
            SimOptions { faults, ..SimOptions::default() },
        )
    }

    /// Starts a simulator listening on every address of `listen` (one shared arm).
    ///
    /// # Errors
    /// [`RobotError::Io`] if an address cannot be bound; [`RobotError::Config`] if `listen` is
    /// empty.
    pub fn start_with(listen: &[Listen], options: SimOptions) -> Result<Self, RobotError> {
        if listen.is_empty() {
            return Err(RobotError::Config { file: "simulator".into(), message: "no port to listen on".into() });
        }
        let mut listeners = Vec::new();
        let mut addrs = Vec::new();
        for l in listen {
            let io = |source| RobotError::Io { context: l.bind.to_string(), source };
            let listener = TcpListener::bind(&l.bind).map_err(io)?;
            let addr = listener.local_addr().map_err(io)?;
            listener.set_nonblocking(true).map_err(io)?;
            addrs.push((l.transport, addr));
            listeners.push((listener, l.transport));
        }
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
            faults: options.faults,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let login = Arc::new((options.user, wire::login_digest(&options.password)));
        let (st, sp) = (state.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !sp.load(Ordering::SeqCst) {
                let mut idle = true;
                for (listener, transport) in &listeners {
                    if let Ok((stream, _)) = listener.accept() {
                        idle = false;
                        let (st, sp, login, t) = (st.clone(), sp.clone(), login.clone(), *transport);
                        std::thread::spawn(move || serve(stream, t, &st, &sp, &login));
                    }
                }
                if idle {
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        });
        Ok(Simulator { addr: addrs[0].1, addrs, state, stop, thread: Some(thread) })
    }

    /// Every listener: the transport it serves (`None`: all, by the first byte) and its address.
    pub fn addrs(&self) -> &[(Option<Transport>, std::net::SocketAddr)] {
        &self.addrs
    }

    /// The first address serving `transport` (a listener for it, or one serving all).
    pub fn addr_of(&self, transport: Transport) -> Option<std::net::SocketAddr> {
        self.addrs.iter().find(|(t, _)| t.is_none_or(|t| t == transport)).map(|(_, a)| *a)
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

/// One connection: its stream, the bytes read and not yet used, and the stop flag.
struct Conn<'a> {
    stream: TcpStream,
    buf: Vec<u8>,
    stop: &'a AtomicBool,
    state: &'a Mutex<State>,
}

impl Conn<'_> {
    /// Reads more bytes into `buf`; false when the peer closed, the read failed or the
    /// simulator stops.
    fn read_more(&mut self) -> bool {
        let mut chunk = [0u8; 16 * 1024];
        while !self.stop.load(Ordering::SeqCst) {
            match self.stream.read(&mut chunk) {
                Ok(0) => return false,
                Ok(n) => {
                    self.buf.extend_from_slice(&chunk[..n]);
                    return true;
                }
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(_) => return false,
            }
        }
        false
    }

    /// Writes one message in one piece after the configured delay; false if the write failed.
    fn send(&mut self, bytes: &[u8]) -> bool {
        let delay = self.state.lock().expect("sim state").faults.delay_ms;
        if let Some(ms) = delay {
            std::thread::sleep(Duration::from_millis(ms));
        }
        self.stream.write_all(bytes).is_ok()
    }
}

fn serve(
    stream: TcpStream,
    mode: Option<Transport>,
    state: &Mutex<State>,
    stop: &AtomicBool,
    login: &(String, String),
) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    let _ = stream.set_nodelay(true);
    let mut c = Conn { stream, buf: Vec::new(), stop, state };
    let transport = match mode {
        Some(t) => t,
        None => loop {
            match c.buf.iter().copied().find(|b| !b.is_ascii_whitespace()) {
                Some(b'S') => break Transport::Framed,
                Some(b'{' | b'[') => break Transport::Lines,
                Some(b'A'..=b'Z') => break Transport::Http,
                Some(_) => return, // none of the three: hang up
                None if !c.read_more() => return,
                None => {}
            }
        },
    };
    match transport {
        Transport::Framed => serve_framed(c, login),
        Transport::Lines => serve_lines(c),
        Transport::Http => serve_http(c),
    }
}

fn serve_lines(mut c: Conn<'_>) {
    loop {
        // Answer every complete request in the buffer.
        loop {
            let start = c.buf.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(c.buf.len());
            c.buf.drain(..start);
            if c.buf.is_empty() {
                break;
            }
            let mut it = serde_json::Deserializer::from_slice(&c.buf).into_iter::<Value>();
            let v = match it.next() {
                Some(Ok(v)) => {
                    let used = it.byte_offset();
                    c.buf.drain(..used);
                    v
                }
                Some(Err(e)) if e.is_eof() && c.buf.len() <= wire::MAX_FRAME_BYTES => break,
                _ => {
                    let _ = c.send(&line(&parse_error()));
                    return;
                }
            };
            match handle(&v, c.state) {
                Reply::Answer(a) => {
                    if !c.send(&line(&a)) {
                        return;
                    }
                }
                Reply::Drop => return,
            }
        }
        if !c.read_more() {
            return;
        }
    }
}

fn line(v: &Value) -> Vec<u8> {
    let mut b = serde_json::to_vec(v).unwrap_or_default();
    b.push(b'\n');
    b
}

fn parse_error() -> Value {
    json!({"jsonrpc": "2.0", "id": null, "error": {"code": -32700, "message": "parse error"}})
}

/// The framed transport: the login first (only the version query is answered before it),
/// then JSON-RPC requests, every answer one frame of type 1. A frame that breaks the framing
/// (bad magic or type, a length beyond the limit) closes the connection.
fn serve_framed(mut c: Conn<'_>, login: &(String, String)) {
    let mut frames = wire::FrameDecoder::default();
    let mut logged_in = false;
    loop {
        frames.push(&std::mem::take(&mut c.buf));
        loop {
            let payload = match frames.next_frame() {
                Ok(Some(p)) => p,
                Ok(None) => break,
                Err(_) => return,
            };
            let answer = if let Some(req) = wire::parse_login(&payload) {
                logged_in = req.user == login.0 && req.digest == login.1;
                wire::login_reply(logged_in)
            } else {
                let reply = match serde_json::from_slice::<Value>(&payload) {
                    Err(_) => Reply::Answer(parse_error()),
                    Ok(v) if !logged_in && v.get("method") != Some(&json!("SystemInfo.getInterfaceVersionCode")) => {
                        err(
                            &v.get("id").cloned().unwrap_or(Value::Null),
                            NOT_LOGGED_IN,
                            "not logged in: send the __login__ message first",
                        )
                    }
                    Ok(v) => handle(&v, c.state),
                };
                match reply {
                    Reply::Answer(a) => wire::sdk_json(&a).into_bytes(),
                    Reply::Drop => return,
                }
            };
            let Ok(frame) = wire::encode_frame(&answer) else { return };
            if !c.send(&frame) {
                return;
            }
        }
        if !c.read_more() {
            return;
        }
    }
}

/// JSON-RPC over HTTP/1.1: `POST` (any path) with a `Content-Length` JSON body, answered
/// `200 OK` with the JSON-RPC answer; keep-alive unless the request says `Connection: close`.
/// Anything else is answered 400 (malformed), 405 (not a POST) or 411 (no length) and closed.
fn serve_http(mut c: Conn<'_>) {
    loop {
        loop {
            let (head, body) = match wire::take_http_message(&mut c.buf, false) {
                Ok(Some(m)) => m,
                Ok(None) => break,
                Err(e) => {
                    let body = json!({"error": e.to_string()}).to_string();
                    let _ = c.send(&wire::http_response(400, "Bad Request", body.as_bytes(), true));
                    return;
                }
            };
            if !head.start.starts_with("POST ") {
                let body = json!({"error": "JSON-RPC requests are POSTed"}).to_string();
                let _ = c.send(&wire::http_response(405, "Method Not Allowed", body.as_bytes(), true));
                return;
            }
            if head.header("content-length").is_none() {
                let body = json!({"error": "send the JSON-RPC request with a Content-Length"}).to_string();
                let _ = c.send(&wire::http_response(411, "Length Required", body.as_bytes(), true));
                return;
            }
            let close = head.header("connection").is_some_and(|v| v.eq_ignore_ascii_case("close"));
            let reply = match serde_json::from_slice::<Value>(&body) {
                Err(_) => Reply::Answer(parse_error()),
                Ok(v) => handle(&v, c.state),
            };
            let Reply::Answer(a) = reply else { return };
            if !c.send(&wire::http_response(200, "OK", wire::sdk_json(&a).as_bytes(), close)) || close {
                return;
            }
        }
        if !c.read_more() {
            return;
        }
    }
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
/// The values of a refused `(values, status)` answer.
const NO_VALUES: [f64; 6] = [0.0; 6];
/// JSON-RPC error code for a framed call before the login (an assumption).
const NOT_LOGGED_IN: i64 = -32000;

/// The argument `name` (named params) or at `pos` (positional params).
fn arg<'a>(params: &'a Value, name: &str, pos: usize) -> Option<&'a Value> {
    match params {
        Value::Object(m) => m.get(name),
        Value::Array(a) => a.get(pos),
        _ => None,
    }
}

/// Whether `params` holds exactly the arguments `names` (by name or, positionally, by count);
/// `optional` names may be left out of named params.
fn arity(params: &Value, names: &[&str], optional: &[&str]) -> bool {
    match params {
        Value::Object(m) => {
            m.keys().all(|k| names.contains(&k.as_str()))
                && names.iter().all(|n| optional.contains(n) || m.contains_key(*n))
        }
        Value::Array(a) => a.len() == names.len(),
        _ => names.is_empty(),
    }
}

/// A fault the simulator injects on a move request.
enum MoveFault {
    /// Drop the connection without answering.
    Drop,
    /// Answer that the motion queue is full.
    QueueFull,
}

/// The arguments of `moveJoint` (`target`: joints, rad) or `moveLine` (`target`: the TCP pose).
struct MoveArgs {
    joint: bool,
    target: [f64; 6],
    /// Speed, m/s or rad/s.
    v: f64,
}

impl MoveArgs {
    /// Parses the params, `None` when they are not what the controller accepts (the names or
    /// count, the ranges of acceleration, speed and blend radius).
    fn parse(params: &Value, joint: bool) -> Option<Self> {
        let target = if joint { "q" } else { "pose" };
        if !arity(params, &[target, "a", "v", "blend_radius", "duration"], &["duration"]) {
            return None;
        }
        let num = |name: &str, pos: usize| arg(params, name, pos).and_then(Value::as_f64);
        let (a, v, blend) = (num("a", 1)?, num("v", 2)?, num("blend_radius", 3)?);
        let accepted = a > 0.0
            && a <= CONTROLLER_MAX_ACC
            && v > 0.0
            && v <= CONTROLLER_MAX_SPEED
            && (0.0..=CONTROLLER_MAX_BLEND_M).contains(&blend);
        if !accepted {
            return None;
        }
        let target = arg(params, target, 0).and_then(numbers::<6>)?;
        Some(Self { joint, target, v })
    }
}

impl State {
    /// Counts a move request and says whether a fault is injected on it.
    fn move_fault(&mut self) -> Option<MoveFault> {
        self.moves_seen += 1;
        let n = self.moves_seen;
        if self.faults.drop_after_moves == Some(n) && !self.dropped {
            self.dropped = true;
            return Some(MoveFault::Drop);
        }
        match self.faults.queue_full_every {
            Some(k) if k > 0 && n % k == 0 => Some(MoveFault::QueueFull),
            _ => None,
        }
    }

    /// Executes a move at once, recording its trace; returns the status (0, or
    /// [`UNREACHABLE`]).
    fn execute(&mut self, m: &MoveArgs) -> i64 {
        let tcp = tcp_iso(self.tcp_offset_m);
        let v = m.v * self.speed_fraction;
        if m.joint {
            let q = m.target;
            if q.iter().any(|x| x.abs() > kinematics::JOINT_LIMIT_RAD) {
                return UNREACHABLE;
            }
            let samples = joint_motion(&self.joints, &q, v, &tcp, self.time_s);
            self.joints = q;
            self.pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
            self.record(samples);
        } else {
            let pose = Pose(m.target);
            let seed = self.joints;
            let Some(q) = kinematics::inverse(&pose, &tcp, Some(&seed)) else { return UNREACHABLE };
            let samples = line_motion(&self.pose, &pose, v, self.time_s);
            self.joints = q;
            self.pose = pose;
            self.record(samples);
        }
        0
    }
}

fn handle(v: &Value, state: &Mutex<State>) -> Reply {
    let id = v.get("id").cloned().unwrap_or(Value::Null);
    if v.get("jsonrpc") != Some(&json!("2.0"))
        || !v.get("method").is_some_and(Value::is_string)
        || v.get("id").is_none()
    {
        return err(&id, -32600, "invalid request: need jsonrpc \"2.0\", a method and an id");
    }
    // Params: positional (an array), named (an object) or none (no `params` key, or null).
    let params = v.get("params").unwrap_or(&Value::Null);
    if !matches!(params, Value::Array(_) | Value::Object(_) | Value::Null) {
        return err(&id, -32602, "params must be an array or an object");
    }
    let method = v["method"].as_str().unwrap_or_default();
    let mut st = state.lock().expect("sim state");
    match method {
        "getRobotNames" => return ok(&id, json!([SIM_ROBOT])),
        "getAxisNames" => return ok(&id, json!([])),
        "SystemInfo.getInterfaceVersionCode" => return ok(&id, json!(wire::INTERFACE_VERSION)),
        _ => {}
    }
    let Some((robot, rest)) = method.split_once('.') else {
        return err(&id, -32601, "method not found");
    };
    if robot != SIM_ROBOT {
        return err(&id, -32601, &format!("unknown robot `{robot}`"));
    }
    match rest {
        "RobotConfig.setTcpOffset" => match arg(params, "offset", 0).and_then(numbers::<6>) {
            Some(o) if arity(params, &["offset"], &[]) && (0.0..CONTROLLER_MAX_TCP_OFFSET_M).contains(&o[2]) => {
                st.tcp_offset_m = o[2];
                let q = st.joints;
                st.pose = Pose::from_iso(&kinematics::forward(&q, &tcp_iso(o[2])));
                ok(&id, json!(0))
            }
            _ => ok(&id, json!(INVALID_ARGUMENT)),
        },
        "MotionControl.setSpeedFraction" => match arg(params, "fraction", 0).and_then(Value::as_f64) {
            Some(f) if arity(params, &["fraction"], &[]) && f > 0.0 && f <= CONTROLLER_MAX_SPEED_FRACTION => {
                st.speed_fraction = f;
                ok(&id, json!(0))
            }
            _ => ok(&id, json!(INVALID_ARGUMENT)),
        },
        // Moves execute at once: the arm is always idle and steady between requests.
        "MotionControl.getExecId" => ok(&id, json!(-1)),
        "RobotState.isSteady" => ok(&id, json!(true)),
        "RobotState.getTcpPose" => ok(&id, json!(st.pose.0)),
        "RobotState.getJointPositions" => ok(&id, json!(st.joints)),
        // The controller's kinematics services, as the SDK names them; results are the SDK's
        // `(values, status)` pairs.
        "RobotAlgorithm.inverseKinematics" => {
            let qnear = arg(params, "qnear", 0).and_then(numbers::<6>);
            let pose = arg(params, "pose", 1).and_then(numbers::<6>);
            match (qnear, pose) {
                (Some(qnear), Some(pose)) if arity(params, &["qnear", "pose"], &[]) => {
                    let tcp = tcp_iso(st.tcp_offset_m);
                    match kinematics::inverse(&Pose(pose), &tcp, Some(&qnear)) {
                        Some(q) => ok(&id, json!([q, 0])),
                        None => ok(&id, json!([qnear, UNREACHABLE])),
                    }
                }
                _ => ok(&id, json!([NO_VALUES, INVALID_ARGUMENT])),
            }
        }
        "RobotAlgorithm.forwardKinematics" => match arg(params, "q", 0).and_then(numbers::<6>) {
            Some(q) if arity(params, &["q"], &[]) => {
                let pose = Pose::from_iso(&kinematics::forward(&q, &tcp_iso(st.tcp_offset_m)));
                ok(&id, json!([pose.0, 0]))
            }
            _ => ok(&id, json!([NO_VALUES, INVALID_ARGUMENT])),
        },
        "RobotConfig.getKinematicsParam" => {
            let k = kinematics::DhParams::AUBO_I5;
            ok(&id, json!({"a": k.a_m, "alpha": k.alpha_rad, "d": k.d_m, "theta": k.theta_rad}))
        }
        "MotionControl.moveJoint" | "MotionControl.moveLine" => {
            let joint = rest == "MotionControl.moveJoint";
            if let Some(fault) = st.move_fault() {
                return match fault {
                    MoveFault::Drop => Reply::Drop,
                    MoveFault::QueueFull => ok(&id, json!(crate::aubo::QUEUE_FULL)),
                };
            }
            let Some(m) = MoveArgs::parse(params, joint) else {
                return ok(&id, json!(INVALID_ARGUMENT));
            };
            ok(&id, json!(st.execute(&m)))
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
