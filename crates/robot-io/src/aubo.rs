//! The AUBO ARCS JSON-RPC 2.0 client (TCP port 30004) and the fault-tolerant program runner.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::RobotError;
use crate::pose::Pose;
use crate::program::{Move, Program, StrokeProgram};

/// The controller's JSON-RPC port.
pub const RPC_PORT: u16 = 30004;
/// The controller's script port.
pub const SCRIPT_PORT: u16 = 30002;

/// A JSON-RPC 2.0 connection to an AUBO controller (or the simulator). Responses are parsed
/// incrementally from the byte stream (no reliance on newlines); every call has a timeout.
pub struct AuboClient {
    stream: TcpStream,
    buf: Vec<u8>,
    next_id: u64,
    timeout: Duration,
}

/// Result code the controller returns when its motion queue is full.
pub const QUEUE_FULL: i64 = 2;

impl AuboClient {
    /// Connects with `timeout` for the connection and for every later call.
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address does not resolve or the connection fails.
    pub fn connect(addr: &str, timeout: Duration) -> Result<Self, RobotError> {
        let addrs: Vec<SocketAddr> =
            addr.to_socket_addrs().map_err(|e| RobotError::Io(format!("{addr}: {e}")))?.collect();
        let mut last = None;
        for a in addrs {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => {
                    stream.set_read_timeout(Some(timeout)).map_err(|e| RobotError::Io(e.to_string()))?;
                    stream.set_write_timeout(Some(timeout)).map_err(|e| RobotError::Io(e.to_string()))?;
                    let _ = stream.set_nodelay(true);
                    return Ok(Self { stream, buf: Vec::new(), next_id: 1, timeout });
                }
                Err(e) => last = Some(e),
            }
        }
        Err(RobotError::Io(format!("{addr}: {}", last.map_or("no address".to_string(), |e| e.to_string()))))
    }

    /// Calls `method` with `params` and returns the `result`.
    ///
    /// # Errors
    /// [`RobotError::Timeout`], [`RobotError::Io`] (connection lost), [`RobotError::Protocol`]
    /// (not JSON-RPC), [`RobotError::Rpc`] (a JSON-RPC `error` object).
    pub fn call(&mut self, method: &str, params: Value) -> Result<Value, RobotError> {
        let id = self.next_id;
        self.next_id += 1;
        let req = json!({"jsonrpc": "2.0", "method": method, "params": params, "id": id});
        let mut bytes = serde_json::to_vec(&req).expect("serialisable");
        bytes.push(b'\n');
        self.stream.write_all(&bytes).map_err(|e| io_err(method, e))?;
        let deadline = Instant::now() + self.timeout;
        loop {
            let v = self.read_value(method, deadline)?;
            if v.get("id").and_then(Value::as_u64) != Some(id) {
                continue; // a notification or a stale answer
            }
            if let Some(err) = v.get("error") {
                return Err(RobotError::Rpc {
                    method: method.to_string(),
                    code: err.get("code").and_then(Value::as_i64).unwrap_or(0),
                    message: err.get("message").and_then(Value::as_str).unwrap_or("").to_string(),
                });
            }
            return v
                .get("result")
                .cloned()
                .ok_or_else(|| RobotError::Protocol(format!("{method}: answer has neither result nor error")));
        }
    }

    fn read_value(&mut self, method: &str, deadline: Instant) -> Result<Value, RobotError> {
        loop {
            let start = self.buf.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(self.buf.len());
            self.buf.drain(..start);
            if !self.buf.is_empty() {
                let mut it = serde_json::Deserializer::from_slice(&self.buf).into_iter::<Value>();
                match it.next() {
                    Some(Ok(v)) => {
                        let used = it.byte_offset();
                        self.buf.drain(..used);
                        return Ok(v);
                    }
                    Some(Err(e)) if e.is_eof() => {}
                    Some(Err(e)) => {
                        return Err(RobotError::Protocol(format!("{method}: malformed JSON from the controller: {e}")));
                    }
                    None => {}
                }
            }
            if Instant::now() >= deadline {
                return Err(RobotError::Timeout(method.to_string()));
            }
            let mut chunk = [0u8; 4096];
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(RobotError::Io(format!("{method}: connection closed by the controller"))),
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) => return Err(io_err(method, e)),
            }
        }
    }

    /// Calls a method whose result is a status code: `< 0` is an error, `> 0` a warning that
    /// is returned for the caller to act on (for example [`QUEUE_FULL`]).
    ///
    /// # Errors
    /// As [`AuboClient::call`], plus [`RobotError::Controller`] for a negative code.
    pub fn call_status(&mut self, method: &str, params: Value) -> Result<i64, RobotError> {
        let r = self.call(method, params)?;
        let code =
            r.as_i64().ok_or_else(|| RobotError::Protocol(format!("{method}: expected an integer result, got {r}")))?;
        if code < 0 {
            return Err(RobotError::Controller { method: method.to_string(), code });
        }
        Ok(code)
    }

    /// `getRobotNames`.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn robot_names(&mut self) -> Result<Vec<String>, RobotError> {
        let r = self.call("getRobotNames", json!([]))?;
        serde_json::from_value(r).map_err(|e| RobotError::Protocol(format!("getRobotNames: {e}")))
    }

    /// `<robot>.MotionControl.getExecId`: the running motion's id, −1 when idle.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn exec_id(&mut self, robot: &str) -> Result<i64, RobotError> {
        let m = format!("{robot}.MotionControl.getExecId");
        let r = self.call(&m, json!([]))?;
        r.as_i64().ok_or_else(|| RobotError::Protocol(format!("{m}: expected an integer")))
    }

    /// `<robot>.RobotState.getTcpPose`.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn tcp_pose(&mut self, robot: &str) -> Result<Pose, RobotError> {
        let m = format!("{robot}.RobotState.getTcpPose");
        let r = self.call(&m, json!([]))?;
        let v: Vec<f64> = serde_json::from_value(r).map_err(|e| RobotError::Protocol(format!("{m}: {e}")))?;
        let a: [f64; 6] = v.try_into().map_err(|_| RobotError::Protocol(format!("{m}: expected 6 numbers")))?;
        Ok(Pose(a))
    }

    /// Sends one motion command, waiting and retrying while the queue is full (bounded).
    ///
    /// # Errors
    /// As [`AuboClient::call_status`]; [`RobotError::Timeout`] if the queue stays full.
    pub fn send_move(&mut self, robot: &str, m: &Move) -> Result<(), RobotError> {
        let (method, params) = match m {
            Move::Joint { q, a, v } => (format!("{robot}.MotionControl.moveJoint"), json!([q, a, v, 0.0, 0.0])),
            Move::Line { pose, a, v, blend_m } => {
                (format!("{robot}.MotionControl.moveLine"), json!([pose.0, a, v, blend_m, 0.0]))
            }
        };
        for attempt in 0..200 {
            match self.call_status(&method, params.clone())? {
                QUEUE_FULL => std::thread::sleep(Duration::from_millis(5 + attempt.min(20) * 5)),
                _ => return Ok(()),
            }
        }
        Err(RobotError::Timeout(format!("{method}: the motion queue stayed full")))
    }

    /// Waits until the controller is idle (`getExecId` = −1), polling.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Timeout`] after `limit`.
    pub fn wait_idle(&mut self, robot: &str, limit: Duration) -> Result<(), RobotError> {
        let end = Instant::now() + limit;
        while self.exec_id(robot)? != -1 {
            if Instant::now() > end {
                return Err(RobotError::Timeout(format!("{robot}: motion did not finish")));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        Ok(())
    }
}

fn io_err(method: &str, e: std::io::Error) -> RobotError {
    match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => RobotError::Timeout(method.to_string()),
        _ => RobotError::Io(format!("{method}: {e}")),
    }
}

/// Sends a Lua script to the controller's script port, framed by `\r\n\r\n`.
///
/// # Errors
/// [`RobotError::Io`].
pub fn send_script(addr: &str, script: &str, timeout: Duration) -> Result<(), RobotError> {
    let c = AuboClient::connect(addr, timeout)?;
    let mut s = c.stream;
    s.write_all(script.as_bytes()).and_then(|_| s.write_all(b"\r\n\r\n")).map_err(|e| RobotError::Io(e.to_string()))
}

/// How the runner behaves on faults.
pub struct RunOptions<'a> {
    /// Per-call timeout.
    pub timeout: Duration,
    /// Connection attempts after one fault before giving up.
    pub max_reconnects: usize,
    /// Faults tolerated while one stroke runs (each restarts it from its first point) before
    /// giving up.
    pub max_retries_per_stroke: usize,
    /// Faults tolerated over the whole run before giving up.
    pub max_retries_total: usize,
    /// First wait before reconnecting (doubles with every fault on the same stroke and every
    /// failed attempt, up to `max_backoff`).
    pub backoff: Duration,
    /// Longest wait before reconnecting.
    pub max_backoff: Duration,
    /// Safe height above the paper to lift to after a fault or a stop, m.
    pub lift_m: f64,
    /// Set (for example by Ctrl-C) to stop: the runner sends no further stroke, waits for the
    /// controller to finish what it queued, lifts the brush and returns
    /// [`RobotError::Interrupted`] inside [`RobotError::RunStopped`].
    pub stop: &'a AtomicBool,
}

impl<'a> RunOptions<'a> {
    /// The defaults `maobi robot send` uses: 2 s per call, 5 connection attempts per fault,
    /// 3 faults per stroke, 10 per run, backoff 200 ms doubling to 5 s, lift 20 mm.
    pub fn new(stop: &'a AtomicBool) -> Self {
        Self {
            timeout: Duration::from_secs(2),
            max_reconnects: 5,
            max_retries_per_stroke: 3,
            max_retries_total: 10,
            backoff: Duration::from_millis(200),
            max_backoff: Duration::from_secs(5),
            lift_m: 0.02,
            stop,
        }
    }
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RunReport {
    /// Strokes in the program.
    pub strokes_total: usize,
    /// Indices of the strokes completed, in order.
    pub strokes_completed: Vec<usize>,
    /// Reconnections after faults.
    pub reconnects: usize,
    /// Strokes restarted from their first point after a fault.
    pub strokes_resumed: usize,
    /// Faults met (dropped connections, timeouts).
    pub faults: usize,
}

struct Session {
    client: AuboClient,
    robot: String,
}

fn open(addr: &str, program: &Program, opts: &RunOptions<'_>, robot_name: Option<&str>) -> Result<Session, RobotError> {
    let mut client = AuboClient::connect(addr, opts.timeout)?;
    let names = client.robot_names()?;
    let robot = match robot_name {
        Some(n) if names.iter().any(|x| x == n) => n.to_string(),
        Some(n) => {
            return Err(RobotError::Config {
                file: "robot.json".into(),
                message: format!("robot `{n}` is not on the controller (it has {names:?})"),
            });
        }
        None => names.first().cloned().ok_or_else(|| RobotError::Protocol("getRobotNames: no robots".into()))?,
    };
    client.call_status(
        &format!("{robot}.RobotConfig.setTcpOffset"),
        json!([[0.0, 0.0, program.tcp_offset_m, 0.0, 0.0, 0.0]]),
    )?;
    client.call_status(&format!("{robot}.MotionControl.setSpeedFraction"), json!([program.speed_fraction]))?;
    Ok(Session { client, robot })
}

/// Lifts the brush straight out of the paper (along its normal) to `lift_m` above it, unless
/// it is there already. Returns what it did, in words.
fn lift(s: &mut Session, program: &Program, lift_m: f64, idle_limit: Duration) -> Result<String, RobotError> {
    let here = s.client.tcp_pose(&s.robot)?;
    let depth_mm = program.depth_mm(here.position());
    if depth_mm <= -lift_m * 1000.0 + 0.5 {
        return Ok(format!("the brush is at the safe height ({:.1} mm above the paper)", -depth_mm));
    }
    let pose = program.lifted_out(&here, lift_m);
    let m = Move::Line { pose, a: program.retreat_acc_m_s2, v: program.retreat_speed_m_s, blend_m: 0.0 };
    s.client.send_move(&s.robot, &m)?;
    s.client.wait_idle(&s.robot, idle_limit)?;
    Ok(format!(
        "brush lifted from {depth_mm:.1} mm below the paper to the safe height ({:.1} mm above it)",
        lift_m * 1000.0
    ))
}

/// Sleeps `d`, waking early when `stop` is set.
fn sleep_unless(d: Duration, stop: &AtomicBool) {
    let end = Instant::now() + d;
    while !stop.load(Ordering::SeqCst) {
        let now = Instant::now();
        if now >= end {
            return;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(20)));
    }
}

/// Sends a stroke's moves, stopping early (after the move in flight) when `stop` is set, then
/// waits until the controller has executed what it was sent.
fn run_stroke(s: &mut Session, st: &StrokeProgram, idle_limit: Duration, stop: &AtomicBool) -> Result<(), RobotError> {
    for m in st.moves() {
        if stop.load(Ordering::SeqCst) {
            s.client.wait_idle(&s.robot, idle_limit)?;
            return Err(RobotError::Interrupted);
        }
        s.client.send_move(&s.robot, m)?;
    }
    s.client.wait_idle(&s.robot, idle_limit)
}

fn is_fault(e: &RobotError) -> bool {
    matches!(e, RobotError::Io(_) | RobotError::Timeout(_))
}

/// Runs a program on a controller (or the simulator) at `addr`, stroke by stroke.
///
/// On a dropped connection or a timeout it reconnects (at most `max_reconnects` attempts per
/// fault, waiting `backoff`, doubling up to `max_backoff`), lifts the brush to the safe height
/// first, and restarts the interrupted stroke from its first point; a stroke whose lift already
/// finished (the TCP is at its end pose) counts as done and is never written twice. At most
/// `max_retries_per_stroke` faults per stroke and `max_retries_total` in the run are tolerated,
/// so a flaky link ends in bounded time.
///
/// # Errors
/// Before anything moved (connecting, the robot name, setting the tool): the error as it is.
/// After that, any error (a controller error code, a JSON-RPC error, a spent retry budget,
/// [`RobotError::GaveUp`]; `opts.stop` set, [`RobotError::Interrupted`]) first lifts the brush
/// straight out of the paper to `opts.lift_m` above it if the link allows (reconnecting once if
/// it is down), then returns [`RobotError::RunStopped`] with the cause, the strokes completed
/// and whether the brush was lifted.
pub fn run_program(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
    mut progress: impl FnMut(&RunReport),
) -> Result<RunReport, RobotError> {
    let mut report = RunReport { strokes_total: program.strokes.len(), ..RunReport::default() };
    let idle_limit = opts.timeout * 100;
    let session = open(addr, program, opts, robot_name)?;
    let mut session = Some(session);
    match drive(addr, program, robot_name, opts, &mut session, &mut report, &mut progress, idle_limit) {
        Ok(()) => Ok(report),
        Err(cause) => {
            // Lift on the open link; if it is down (or fails), reconnect once and lift.
            let mut outcome = match session.as_mut() {
                Some(s) => lift(s, program, opts.lift_m, idle_limit),
                None => Err(RobotError::Io("not connected".into())),
            };
            if outcome.as_ref().is_err_and(is_fault) {
                outcome = open(addr, program, opts, robot_name)
                    .and_then(|mut s| lift(&mut s, program, opts.lift_m, idle_limit));
            }
            let (lifted, lift) = match outcome {
                Ok(words) => (true, words),
                Err(e) => (false, format!("could not lift the brush ({e}): it may still touch the paper")),
            };
            Err(RobotError::RunStopped {
                cause: Box::new(cause),
                completed: report.strokes_completed.len(),
                total: report.strokes_total,
                reconnects: report.reconnects,
                lifted,
                lift,
            })
        }
    }
}

/// The run after the connection is open; any error returned leaves the retreat to the caller.
#[allow(clippy::too_many_arguments)]
fn drive(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
    session: &mut Option<Session>,
    report: &mut RunReport,
    progress: &mut impl FnMut(&RunReport),
    idle_limit: Duration,
) -> Result<(), RobotError> {
    {
        let s = session.as_mut().expect("open");
        s.client.send_move(&s.robot, &program.start)?;
        s.client.wait_idle(&s.robot, idle_limit)?;
    }
    let mut k = 0;
    let mut faults_stroke = 0;
    let mut backoff = opts.backoff;
    let mut fault: Option<RobotError> = None;
    while k < program.strokes.len() {
        if opts.stop.load(Ordering::SeqCst) {
            return Err(RobotError::Interrupted);
        }
        let st = &program.strokes[k];
        let result = match fault.take() {
            // Recover from the last fault: reconnect, then see where the brush is.
            Some(e) => {
                report.faults += 1;
                faults_stroke += 1;
                *session = None;
                if faults_stroke > opts.max_retries_per_stroke || report.faults > opts.max_retries_total {
                    return Err(RobotError::GaveUp {
                        stroke: st.index,
                        faults_stroke,
                        max_stroke: opts.max_retries_per_stroke,
                        faults_total: report.faults,
                        max_total: opts.max_retries_total,
                        last: Box::new(e),
                    });
                }
                let mut attempt = 0;
                let s = loop {
                    sleep_unless(backoff, opts.stop);
                    backoff = (backoff * 2).min(opts.max_backoff);
                    if opts.stop.load(Ordering::SeqCst) {
                        return Err(RobotError::Interrupted);
                    }
                    attempt += 1;
                    match open(addr, program, opts, robot_name) {
                        Ok(s) => break s,
                        Err(e2) if is_fault(&e2) && attempt < opts.max_reconnects => continue,
                        Err(e2) if is_fault(&e2) => {
                            return Err(RobotError::GaveUp {
                                stroke: st.index,
                                faults_stroke,
                                max_stroke: opts.max_retries_per_stroke,
                                faults_total: report.faults,
                                max_total: opts.max_retries_total,
                                last: Box::new(RobotError::Io(format!(
                                    "{attempt} connection attempt(s) failed, the last: {e2}"
                                ))),
                            });
                        }
                        Err(e2) => return Err(e2),
                    }
                };
                report.reconnects += 1;
                let s = session.insert(s);
                // Did the stroke finish before the fault? Then its lift pose is where we are.
                s.client.tcp_pose(&s.robot).and_then(|here| {
                    let Move::Line { pose: end, .. } = st.lift else { unreachable!("lift is a line move") };
                    let done = here.position().iter().zip(end.position()).all(|(a, b)| (a - b).abs() < 1e-6);
                    if done {
                        Ok(true)
                    } else {
                        lift(s, program, opts.lift_m, idle_limit)?;
                        report.strokes_resumed += 1;
                        Ok(false)
                    }
                })
            }
            None => {
                let s = session.as_mut().expect("connected");
                run_stroke(s, st, idle_limit, opts.stop).map(|()| true)
            }
        };
        match result {
            Ok(true) => {
                report.strokes_completed.push(st.index);
                progress(report);
                k += 1;
                faults_stroke = 0;
                backoff = opts.backoff;
            }
            Ok(false) => {} // recovered: run the stroke again
            Err(e) if is_fault(&e) => fault = Some(e),
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
