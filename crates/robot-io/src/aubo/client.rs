//! The AUBO ARCS JSON-RPC 2.0 client.
//!
//! The client speaks one of three [`Transport`]s: the official SDK's framed protocol on port
//! 30004 (the default: named params, string ids, version query and login first), maobi's
//! earlier line-delimited form (positional params), or JSON-RPC over HTTP on port 9012.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::RobotError;
use crate::pose::Pose;
use crate::program::Move;
use crate::wire::{self, FrameDecoder, Transport};

/// How to reach and log in to a controller: the transport and the credentials (used by the
/// framed transport only).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Link {
    /// The transport.
    pub transport: Transport,
    /// The user for the login.
    pub user: String,
    /// The password for the login.
    pub password: String,
}

impl Default for Link {
    /// The framed transport with the controller's default user `aubo`, password `123456`.
    fn default() -> Self {
        Self::new(Transport::Framed)
    }
}

impl Link {
    /// `transport` with the default credentials.
    pub fn new(transport: Transport) -> Self {
        Self { transport, user: wire::DEFAULT_USER.into(), password: wire::DEFAULT_PASSWORD.into() }
    }
}

/// A JSON-RPC 2.0 connection to an AUBO controller (or the simulator). Answers are read
/// incrementally from the byte stream (frames, HTTP messages or JSON values may arrive in any
/// pieces or several at once); every call has a timeout.
pub struct AuboClient {
    stream: TcpStream,
    transport: Transport,
    host: String,
    buf: Vec<u8>,
    frames: FrameDecoder,
    next_id: u64,
    client_no: u64,
    timeout: Duration,
    interface_version: Option<i64>,
    /// Ids of calls that timed out (their answers may still come), oldest first.
    stale: Vec<Value>,
    /// Answers with ids that did not match, on this connection.
    foreign: usize,
    /// The last such id (shown) and the count then, while the call it came in waits.
    last_foreign: Option<(String, usize)>,
}

/// Answers with an id this client never used (or whose call had not timed out) tolerated on one
/// connection: the third is a [`RobotError::Protocol`] error naming the ids. A call that gets
/// such an answer and then none with its own id fails with [`RobotError::Protocol`] naming both
/// ids, not with a timeout.
pub const MAX_ID_MISMATCHES: usize = 3;

/// Ids of calls that timed out whose late answers are skipped without counting.
const MAX_STALE_IDS: usize = 16;

/// Longest robot name accepted from `getRobotNames` (it goes into every method name), bytes.
pub const MAX_ROBOT_NAME_LEN: usize = 64;

/// Result code the controller returns when its motion queue is full.
pub const QUEUE_FULL: i64 = 2;

/// Most waypoints one `pathBufferAppend` carries (about 100 KB of JSON, well within a frame).
pub const PATH_APPEND_WAYPOINTS: usize = 1000;

/// Distinguishes the ids of clients made by one process.
static CLIENTS: AtomicU64 = AtomicU64::new(0);

const ID_ALPHABET: &[u8; 62] = b"0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz";

/// A string id shaped like the SDK's (`xxxxxxxx-xxxx-xxxx`, 18 characters from 0–9, A–Z,
/// a–z, so a frame is as long as the SDK's), made from the process, the client and the call
/// number: different for every call in practice (answers are matched to calls by it).
fn string_id(client: u64, n: u64) -> String {
    let mix = numerics::SplitMix64::mix;
    let mut x = mix((u64::from(std::process::id()) << 44) ^ (client << 28) ^ n);
    let mut s = String::with_capacity(18);
    for i in 0..16 {
        if i == 8 || i == 12 {
            s.push('-');
        }
        if i == 10 {
            x = mix(x);
        }
        s.push(char::from(ID_ALPHABET[(x % 62) as usize]));
        x /= 62;
    }
    s
}

impl AuboClient {
    /// Connects with the line-delimited transport (positional params, no login: maobi's earlier
    /// form), with `timeout` for the connection and every later call. [`AuboClient::open`]
    /// speaks the controller's own protocol.
    ///
    /// # Examples
    /// ```no_run
    /// use std::time::Duration;
    /// use robot_io::aubo::AuboClient;
    /// // A controller on the local network (the line-delimited transport).
    /// let client = AuboClient::connect("192.168.1.10:8899", Duration::from_secs(5))?;
    /// # drop(client);
    /// # Ok::<(), robot_io::RobotError>(())
    /// ```
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address does not resolve or the connection fails.
    pub fn connect(addr: &str, timeout: Duration) -> Result<Self, RobotError> {
        Self::connect_with(addr, Transport::Lines, timeout)
    }

    /// Connects with `transport`, without any handshake (see [`AuboClient::handshake`]).
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address does not resolve or the connection fails.
    pub fn connect_with(addr: &str, transport: Transport, timeout: Duration) -> Result<Self, RobotError> {
        let addrs: Vec<SocketAddr> = addr.to_socket_addrs().map_err(|e| io_at(addr, e))?.collect();
        let mut last = None;
        for a in addrs {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => {
                    stream.set_read_timeout(Some(timeout)).map_err(|e| io_at(addr, e))?;
                    stream.set_write_timeout(Some(timeout)).map_err(|e| io_at(addr, e))?;
                    let _ = stream.set_nodelay(true);
                    return Ok(Self {
                        stream,
                        transport,
                        host: addr.to_string(),
                        buf: Vec::new(),
                        frames: FrameDecoder::default(),
                        next_id: 1,
                        client_no: CLIENTS.fetch_add(1, Ordering::Relaxed),
                        timeout,
                        interface_version: None,
                        stale: Vec::new(),
                        foreign: 0,
                        last_foreign: None,
                    });
                }
                Err(e) => last = Some(e),
            }
        }
        let e = last.unwrap_or_else(|| std::io::Error::new(std::io::ErrorKind::AddrNotAvailable, "no address"));
        Err(io_at(addr, e))
    }

    /// Connects as `link` says and does the handshake ([`AuboClient::handshake`]); returns the
    /// client and the controller's robot names.
    ///
    /// # Errors
    /// As [`AuboClient::connect_with`] and [`AuboClient::handshake`].
    pub fn open(addr: &str, link: &Link, timeout: Duration) -> Result<(Self, Vec<String>), RobotError> {
        let mut c = Self::connect_with(addr, link.transport, timeout)?;
        let names = c.handshake(&link.user, &link.password)?;
        Ok((c, names))
    }

    /// The transport this client speaks.
    pub fn transport(&self) -> Transport {
        self.transport
    }

    /// The controller's interface version, once the handshake asked for it.
    pub fn interface_version(&self) -> Option<i64> {
        self.interface_version
    }

    /// The handshake the SDK does, returning the robot names. Framed:
    /// `SystemInfo.getInterfaceVersionCode`, the login, `getRobotNames`, `getAxisNames`.
    /// HTTP: the version query and `getRobotNames`. Lines: `getRobotNames`.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Login`] if the controller refuses the login;
    /// [`RobotError::Protocol`] if the version is not an integer.
    pub fn handshake(&mut self, user: &str, password: &str) -> Result<Vec<String>, RobotError> {
        if self.transport != Transport::Lines {
            let m = "SystemInfo.getInterfaceVersionCode";
            let v = self.call(m, Value::Null)?;
            let code = v.as_i64().ok_or_else(|| RobotError::Protocol(format!("{m}: expected an integer, got {v}")))?;
            self.interface_version = Some(code);
        }
        if self.transport == Transport::Framed {
            self.login(user, password)?;
        }
        let names = self.robot_names()?;
        if self.transport == Transport::Framed {
            self.call("getAxisNames", Value::Null)?;
        }
        Ok(names)
    }

    /// Sends the framed login message (`__login__`, the user, the password digest, the SDK
    /// version) and waits for `SUCCEED` or `FAILED`.
    ///
    /// # Errors
    /// [`RobotError::Login`] when refused; [`RobotError::Protocol`] if the transport is not
    /// framed or the answer is not a login answer; as [`AuboClient::call`] otherwise.
    pub fn login(&mut self, user: &str, password: &str) -> Result<(), RobotError> {
        if self.transport != Transport::Framed {
            return Err(RobotError::Protocol(format!("login: the {} transport has no login", self.transport)));
        }
        let payload = wire::login_payload(user, password)?;
        self.send_frame("login", &payload)?;
        let deadline = Instant::now() + self.timeout;
        loop {
            let reply = self.read_frame("login", deadline)?;
            if reply.first() == Some(&b'{') {
                continue; // a notification
            }
            let text = String::from_utf8_lossy(&reply);
            let text = text.trim_end();
            if !text.starts_with("__login__") {
                return Err(RobotError::Protocol(format!(
                    "login: expected an answer beginning `__login__`, got {}",
                    wire::show_bytes(&reply[..reply.len().min(40)])
                )));
            }
            if text.ends_with("SUCCEED") {
                return Ok(());
            }
            let message = if text.ends_with("FAILED") {
                "the controller answered FAILED (wrong user or password?)".to_string()
            } else {
                format!("unexpected answer {text:?}")
            };
            return Err(RobotError::Login { user: user.to_string(), message });
        }
    }

    /// The request text for `method` with `params` and `id` as this transport writes it (the
    /// payload, before framing). `Value::Null` params are left out.
    fn request_text(&self, method: &str, params: &Value, id: &Value) -> Vec<u8> {
        match self.transport {
            Transport::Lines => {
                let req = json!({"jsonrpc": "2.0", "method": method, "params": params, "id": id});
                let mut b = serde_json::to_vec(&req).unwrap_or_default();
                b.push(b'\n');
                b
            }
            Transport::Framed | Transport::Http => {
                let mut m = serde_json::Map::new();
                m.insert("id".into(), id.clone());
                m.insert("jsonrpc".into(), json!("2.0"));
                m.insert("method".into(), json!(method));
                if !params.is_null() {
                    m.insert("params".into(), params.clone());
                }
                wire::sdk_json(&Value::Object(m)).into_bytes()
            }
        }
    }

    /// Calls `method` with `params` (an array, an object, or `Value::Null` for none) and
    /// returns the `result`. Params are sent as given, whatever the transport.
    ///
    /// # Errors
    /// [`RobotError::Timeout`], [`RobotError::Io`] (connection lost), [`RobotError::Framing`]
    /// (not the transport's format), [`RobotError::Protocol`] (not JSON-RPC),
    /// [`RobotError::Rpc`] (a JSON-RPC `error` object).
    pub fn call(&mut self, method: &str, params: Value) -> Result<Value, RobotError> {
        let n = self.next_id;
        self.next_id += 1;
        let id = match self.transport {
            Transport::Lines => json!(n),
            _ => json!(string_id(self.client_no, n)),
        };
        let text = self.request_text(method, &params, &id);
        match self.transport {
            Transport::Lines => self.stream.write_all(&text).map_err(|e| io_err(method, e))?,
            Transport::Framed => self.send_frame(method, &text)?,
            Transport::Http => {
                let msg = wire::http_post(&self.host, &text);
                self.stream.write_all(&msg).map_err(|e| io_err(method, e))?;
            }
        }
        let deadline = Instant::now() + self.timeout;
        self.last_foreign = None;
        loop {
            let v = match self.read_value(method, deadline) {
                Ok(v) => v,
                Err(RobotError::Timeout(m)) => {
                    if let Some((got, n)) = &self.last_foreign {
                        // Answers came, with the wrong id: say so rather than "timeout".
                        let e = RobotError::Protocol(format!(
                            "{method}: the controller answered id {got}, expected {id} (none with the expected id within {:.1} s; {n} answer(s) on this connection with ids that did not match)",
                            self.timeout.as_secs_f64()
                        ));
                        self.last_foreign = None;
                        return Err(e);
                    }
                    // A late answer to this call is stale, not foreign.
                    if self.stale.len() >= MAX_STALE_IDS {
                        self.stale.remove(0);
                    }
                    self.stale.push(id);
                    return Err(RobotError::Timeout(m));
                }
                Err(e) => return Err(e),
            };
            let is_answer = v.get("result").is_some() || v.get("error").is_some();
            match v.get("id") {
                Some(got) if got == &id => {}
                // An error the controller could not attach to an id (a parse error): ours, since
                // one call is in flight at a time.
                Some(Value::Null) | None if v.get("error").is_some() => {}
                Some(got) if is_answer && !got.is_null() => {
                    if let Some(i) = self.stale.iter().position(|s| s == got) {
                        self.stale.remove(i); // the late answer to a call that timed out
                        continue;
                    }
                    self.foreign += 1;
                    self.last_foreign = Some((show_value(got), self.foreign));
                    if self.foreign >= MAX_ID_MISMATCHES {
                        return Err(RobotError::Protocol(format!(
                            "{method}: the controller answered id {}, expected {id} ({} answers on this connection with ids that did not match)",
                            show_value(got),
                            self.foreign
                        )));
                    }
                    continue;
                }
                _ => continue, // a notification
            }
            self.last_foreign = None;
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

    fn send_frame(&mut self, method: &str, payload: &[u8]) -> Result<(), RobotError> {
        // One write per frame: the SDK cannot take a header split inside its length field.
        let frame = wire::encode_frame(payload)?;
        self.stream.write_all(&frame).map_err(|e| io_err(method, e))
    }

    /// Reads more bytes, waiting at most until `deadline`.
    fn fill(&mut self, method: &str, deadline: Instant) -> Result<Vec<u8>, RobotError> {
        let now = Instant::now();
        if now >= deadline {
            return Err(RobotError::Timeout(method.to_string()));
        }
        let wait = (deadline - now).max(Duration::from_millis(1));
        self.stream.set_read_timeout(Some(wait)).map_err(|e| io_err(method, e))?;
        let mut chunk = vec![0u8; 64 * 1024];
        match self.stream.read(&mut chunk) {
            Ok(0) => {
                let what = match self.frames.incomplete() {
                    Some(what) if self.transport == Transport::Framed => what,
                    _ if !self.buf.is_empty() => {
                        format!("the connection closed in the middle of an answer ({} bytes)", self.buf.len())
                    }
                    _ => "connection closed by the controller".to_string(),
                };
                Err(io_at(method, std::io::Error::new(std::io::ErrorKind::UnexpectedEof, what)))
            }
            Ok(n) => {
                chunk.truncate(n);
                Ok(chunk)
            }
            // A signal (Ctrl-C: the runner stops at its next safe point) cut the wait short:
            // nothing was read; the caller waits again until its deadline.
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(Vec::new()),
            Err(e) => Err(io_err(method, e)),
        }
    }

    fn read_frame(&mut self, method: &str, deadline: Instant) -> Result<Vec<u8>, RobotError> {
        loop {
            if let Some(p) = self.frames.next_frame()? {
                return Ok(p);
            }
            let more = self.fill(method, deadline)?;
            self.frames.push(&more);
        }
    }

    fn read_value(&mut self, method: &str, deadline: Instant) -> Result<Value, RobotError> {
        match self.transport {
            Transport::Framed => {
                let p = self.read_frame(method, deadline)?;
                serde_json::from_slice(&p).map_err(|source| RobotError::BadJson {
                    context: format!("{method}: the frame is not JSON: {}", wire::show_bytes(&p[..p.len().min(40)])),
                    source,
                })
            }
            Transport::Http => loop {
                if let Some((head, body)) = wire::take_http_message(&mut self.buf, true)? {
                    let status = head.start.split_whitespace().nth(1).unwrap_or("");
                    if !head.start.starts_with("HTTP/1.") || status != "200" {
                        return Err(RobotError::Protocol(format!(
                            "{method}: HTTP answer `{}` (expected 200 OK): {}",
                            head.start,
                            wire::show_bytes(&body[..body.len().min(80)])
                        )));
                    }
                    return serde_json::from_slice(&body)
                        .map_err(|source| bad_json(method, "the HTTP body is not JSON", source));
                }
                let more = self.fill(method, deadline)?;
                self.buf.extend_from_slice(&more);
            },
            Transport::Lines => loop {
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
                            return Err(bad_json(method, "malformed JSON from the controller", e));
                        }
                        None => {}
                    }
                }
                if self.buf.len() > wire::MAX_FRAME_BYTES {
                    return Err(RobotError::Framing(format!(
                        "{method}: an answer longer than {} bytes",
                        wire::MAX_FRAME_BYTES
                    )));
                }
                let more = self.fill(method, deadline)?;
                self.buf.extend_from_slice(&more);
            },
        }
    }

    /// Params for this transport: `named` (an object, or `Value::Null` for none) on the framed
    /// and HTTP transports, `positional` (an array) on lines.
    fn params(&self, named: Value, positional: Value) -> Value {
        if self.transport.named_params() { named } else { positional }
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
        let p = self.params(Value::Null, json!([]));
        let r = self.call("getRobotNames", p)?;
        let names: Vec<String> =
            serde_json::from_value(r).map_err(|e| bad_json("getRobotNames", "expected a list of names", e))?;
        for n in &names {
            check_robot_name(n).map_err(|why| RobotError::Protocol(format!("getRobotNames: {why}")))?;
        }
        Ok(names)
    }

    /// `<robot>.RobotConfig.setTcpOffset`: the tool centre point in the flange frame
    /// `[x, y, z, rx, ry, rz]` (m, rad). Returns the status code.
    ///
    /// # Errors
    /// As [`AuboClient::call_status`].
    pub fn set_tcp_offset(&mut self, robot: &str, offset: [f64; 6]) -> Result<i64, RobotError> {
        let p = self.params(json!({"offset": offset}), json!([offset]));
        self.call_status(&robot_method(robot, "RobotConfig.setTcpOffset")?, p)
    }

    /// `<robot>.MotionControl.setSpeedFraction`: the fraction (0, 1] of the commanded speeds.
    ///
    /// # Errors
    /// As [`AuboClient::call_status`].
    pub fn set_speed_fraction(&mut self, robot: &str, fraction: f64) -> Result<i64, RobotError> {
        let p = self.params(json!({"fraction": fraction}), json!([fraction]));
        self.call_status(&robot_method(robot, "MotionControl.setSpeedFraction")?, p)
    }

    /// `<robot>.MotionControl.getExecId`: the running motion's id, −1 when idle.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn exec_id(&mut self, robot: &str) -> Result<i64, RobotError> {
        let m = robot_method(robot, "MotionControl.getExecId")?;
        let p = self.params(Value::Null, json!([]));
        let r = self.call(&m, p)?;
        r.as_i64().ok_or_else(|| RobotError::Protocol(format!("{m}: expected an integer")))
    }

    /// `<robot>.RobotState.isSteady`: whether the arm stands still.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Protocol`] if the result is not a bool.
    pub fn is_steady(&mut self, robot: &str) -> Result<bool, RobotError> {
        let m = robot_method(robot, "RobotState.isSteady")?;
        let p = self.params(Value::Null, json!([]));
        let r = self.call(&m, p)?;
        r.as_bool().ok_or_else(|| RobotError::Protocol(format!("{m}: expected a bool, got {r}")))
    }

    fn six(&mut self, m: &str) -> Result<[f64; 6], RobotError> {
        let p = self.params(Value::Null, json!([]));
        let r = self.call(m, p)?;
        let v: Vec<f64> = serde_json::from_value(r).map_err(|e| bad_json(m, "expected numbers", e))?;
        v.try_into().map_err(|_| RobotError::Protocol(format!("{m}: expected 6 numbers")))
    }

    /// `<robot>.RobotState.getTcpPose`.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn tcp_pose(&mut self, robot: &str) -> Result<Pose, RobotError> {
        Ok(Pose(self.six(&robot_method(robot, "RobotState.getTcpPose")?)?))
    }

    /// `<robot>.RobotState.getJointPositions`: the six joint angles, rad.
    ///
    /// # Errors
    /// As [`AuboClient::call`].
    pub fn joint_positions(&mut self, robot: &str) -> Result<[f64; 6], RobotError> {
        self.six(&robot_method(robot, "RobotState.getJointPositions")?)
    }

    /// The method and params of one motion command for this transport: `moveJoint` with
    /// `{q, a, v, blend_radius, duration}` or `moveLine` with `{pose, a, v, blend_radius,
    /// duration}` (positional in that order on lines); duration 0 (the controller times it).
    /// `None` for a [`Move::JointPose`], which is no single request: [`AuboClient::send_move`]
    /// has the controller solve it first ([`AuboClient::solve_joint_pose`]).
    pub fn move_request(&self, robot: &str, m: &Move) -> Option<(String, Value)> {
        match m {
            Move::Joint { q, a, v } => Some((
                format!("{robot}.MotionControl.moveJoint"),
                self.params(
                    json!({"q": q, "a": a, "v": v, "blend_radius": 0.0, "duration": 0.0}),
                    json!([q, a, v, 0.0, 0.0]),
                ),
            )),
            Move::Line { pose, a, v, blend_m } => Some((
                format!("{robot}.MotionControl.moveLine"),
                self.params(
                    json!({"pose": pose.0, "a": a, "v": v, "blend_radius": blend_m, "duration": 0.0}),
                    json!([pose.0, a, v, blend_m, 0.0]),
                ),
            )),
            Move::JointPose { .. } => None,
        }
    }

    /// The joints at which the controller puts the TCP at `pose`: its own inverse kinematics
    /// (`RobotAlgorithm.inverseKinematics`) from the present joints
    /// (`RobotState.getJointPositions`), checked by its own forward kinematics
    /// (`RobotAlgorithm.forwardKinematics`), which must reproduce `pose` within
    /// [`JOINT_POSE_TOLERANCE_M`] and [`JOINT_POSE_TOLERANCE_RAD`].
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Controller`] when the controller reports that it
    /// cannot solve the pose; [`RobotError::Protocol`] for an answer that is not six finite
    /// joints within the joint limits or whose forward kinematics misses the pose.
    pub fn solve_joint_pose(&mut self, robot: &str, pose: &Pose) -> Result<[f64; 6], RobotError> {
        let qnear = self.joint_positions(robot)?;
        self.solve_joint_pose_near(robot, &qnear, pose)
    }

    /// [`AuboClient::solve_joint_pose`] from joints `qnear` (rad) already read, which must be
    /// six finite angles within the joint limits.
    ///
    /// # Errors
    /// As [`AuboClient::solve_joint_pose`]; [`RobotError::UnexpectedState`] for `qnear` out of
    /// the joint limits or not finite.
    pub fn solve_joint_pose_near(
        &mut self,
        robot: &str,
        qnear: &[f64; 6],
        pose: &Pose,
    ) -> Result<[f64; 6], RobotError> {
        if !qnear.iter().all(|v| v.is_finite() && v.abs() <= crate::kinematics::JOINT_LIMIT_RAD + JOINT_READ_SLACK_RAD)
        {
            return Err(RobotError::UnexpectedState(format!(
                "{robot}.RobotState.getJointPositions reported {qnear:?} rad: not six finite angles within the joint limits (±{:.0}°)",
                crate::kinematics::JOINT_LIMIT_RAD.to_degrees()
            )));
        }
        let m = robot_method(robot, "RobotAlgorithm.inverseKinematics")?;
        let p = self.params(json!({"qnear": qnear, "pose": pose.0}), json!([qnear, pose.0]));
        let q = six_with_status(&m, self.call(&m, p)?)?;
        if q.iter().any(|v| v.abs() > crate::kinematics::JOINT_LIMIT_RAD) {
            return Err(RobotError::Protocol(format!("{m}: joints {q:?} rad are beyond the joint limits")));
        }
        let mf = robot_method(robot, "RobotAlgorithm.forwardKinematics")?;
        let p = self.params(json!({"q": q}), json!([q]));
        let back = Pose(six_with_status(&mf, self.call(&mf, p)?)?);
        let (want, got) = (pose.to_iso(), back.to_iso());
        let dp = (want.translation.vector - got.translation.vector).norm();
        let dr = want.rotation.angle_to(&got.rotation);
        if dp > JOINT_POSE_TOLERANCE_M || dr > JOINT_POSE_TOLERANCE_RAD {
            return Err(RobotError::Protocol(format!(
                "{m}: the controller's forward kinematics of its answer {q:?} is {:.3} mm and {dr:.5} rad from the pose asked for",
                dp * 1000.0
            )));
        }
        Ok(q)
    }

    /// Sends one motion command, waiting and retrying while the queue is full (bounded). A
    /// [`Move::JointPose`] is solved by the controller first ([`AuboClient::solve_joint_pose`])
    /// and sent as `moveJoint`.
    ///
    /// # Errors
    /// As [`AuboClient::call_status`]; [`RobotError::Timeout`] if the queue stays full; as
    /// [`AuboClient::solve_joint_pose`].
    pub fn send_move(&mut self, robot: &str, m: &Move) -> Result<(), RobotError> {
        robot_method(robot, "MotionControl")?;
        let solved;
        let m = match *m {
            Move::JointPose { pose, a, v } => {
                solved = Move::Joint { q: self.solve_joint_pose(robot, &pose)?, a, v };
                &solved
            }
            _ => m,
        };
        let Some((method, params)) = self.move_request(robot, m) else {
            return Err(RobotError::Protocol("a joint move to a pose reached the wire unsolved".into()));
        };
        for attempt in 0..200 {
            match self.call_status(&method, params.clone())? {
                QUEUE_FULL => std::thread::sleep(Duration::from_millis(5 + attempt.min(20) * 5)),
                _ => return Ok(()),
            }
        }
        Err(RobotError::Timeout(format!("{method}: the motion queue stayed full")))
    }

    /// The JSON-RPC calls this client has made (the login frame aside).
    pub fn calls(&self) -> u64 {
        self.next_id - 1
    }

    /// `<robot>.RobotConfig.getKinematicsParam(real)`: the arm's modified-DH parameters as
    /// the controller reports them (`real`: the calibrated ones), validated.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Protocol`] for an answer that is not four arrays
    /// `a`, `alpha`, `d`, `theta` of six finite numbers within ±2 m / ±2π.
    pub fn kinematics_params(&mut self, robot: &str, real: bool) -> Result<crate::kinematics::DhParams, RobotError> {
        let m = robot_method(robot, "RobotConfig.getKinematicsParam")?;
        let p = self.params(json!({"real": real}), json!([real]));
        let r = self.call(&m, p)?;
        dh_rows(&m, &r)
    }

    /// The arm's calibrated parameters as `arm.json` records them: `robot`'s
    /// `RobotConfig.getKinematicsParam(true)` ([`AuboClient::kinematics_params`]), `real`, with
    /// where they were read (this connection's address and transport) as their source.
    ///
    /// # Errors
    /// As [`AuboClient::kinematics_params`].
    pub fn arm_kinematics(&mut self, robot: &str) -> Result<crate::ArmKinematics, RobotError> {
        let kinematics = self.kinematics_params(robot, true)?;
        let source = format!("{} ({}): RobotConfig.getKinematicsParam(true)", self.host, self.transport);
        Ok(crate::ArmKinematics { robot: robot.into(), source, real: true, kinematics })
    }

    /// `<robot>.RobotConfig.getKinematicsCompensate(ref_temperature)`: the compensation the
    /// controller adds to its nominal modified-DH parameters at `ref_temperature_c` (°C), as
    /// four arrays of increments `a`, `alpha`, `d`, `theta` (m, rad; a `beta` array, which
    /// maobi's model has no place for, must be zero). `Ok(None)` when the controller does not
    /// have the method (JSON-RPC −32601). Named params `{"ref_temperature"}` (checked with
    /// `pyaubo_sdk` 0.24.1).
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Protocol`] for an answer that is not four arrays
    /// of six finite numbers within ±2 m / ±2π, or a non-zero `beta`.
    pub fn kinematics_compensate(
        &mut self,
        robot: &str,
        ref_temperature_c: f64,
    ) -> Result<Option<crate::kinematics::DhParams>, RobotError> {
        let m = robot_method(robot, "RobotConfig.getKinematicsCompensate")?;
        let p = self.params(json!({"ref_temperature": ref_temperature_c}), json!([ref_temperature_c]));
        let r = match self.call(&m, p) {
            Ok(r) => r,
            Err(RobotError::Rpc { code: METHOD_NOT_FOUND, .. }) => return Ok(None),
            Err(e) => return Err(e),
        };
        if let Some(beta) = r.get("beta") {
            let beta: Vec<f64> =
                serde_json::from_value(beta.clone()).map_err(|e| bad_json(&m, "expected `beta`: six numbers", e))?;
            if beta.iter().any(|b| *b != 0.0) {
                return Err(RobotError::Protocol(format!(
                    "{m}: `beta` = {beta:?} is not zero (a twist about the y axis that maobi's kinematics do not model)"
                )));
            }
        }
        Ok(Some(dh_rows(&m, &r)?))
    }

    /// `<robot>.RobotAlgorithm.forwardKinematics(q)`: the TCP pose the controller computes for
    /// joints `q` (rad) with the tool offset set.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::Controller`] for a non-zero status.
    pub fn forward_kinematics(&mut self, robot: &str, q: &[f64; 6]) -> Result<Pose, RobotError> {
        let m = robot_method(robot, "RobotAlgorithm.forwardKinematics")?;
        let p = self.params(json!({"q": q}), json!([q]));
        Ok(Pose(six_with_status(&m, self.call(&m, p)?)?))
    }

    /// Runs joint waypoints `waypoints` (rad, `interval_s` apart) as one path buffer named
    /// `name` of type 2 (a cubic spline through the waypoints at a fixed interval), as the SDK
    /// does it: `pathBufferAlloc(name, 2, n)`, `pathBufferAppend` in pieces of at most
    /// [`PATH_APPEND_WAYPOINTS`], `pathBufferEval(name, a, v, interval_s)` with the joint
    /// limits `acc_rad_s2` and `speed_rad_s`, then `pathBufferValid` polled (every 10 ms, at
    /// most `valid_wait`), then `movePathBuffer(name)` (retried while the queue is full). The
    /// buffer is not freed: [`AuboClient::path_buffer_free`] once the motion is done.
    ///
    /// # Errors
    /// As [`AuboClient::call_status`]; [`RobotError::UnexpectedState`] when the buffer does not
    /// become valid in time.
    #[allow(clippy::too_many_arguments, reason = "the SDK's calls' arguments, each named")]
    pub fn run_path_buffer(
        &mut self,
        robot: &str,
        name: &str,
        waypoints: &[[f64; 6]],
        interval_s: f64,
        speed_rad_s: f64,
        acc_rad_s2: f64,
        valid_wait: Duration,
    ) -> Result<(), RobotError> {
        let mc = |rest: &str| robot_method(robot, &format!("MotionControl.{rest}"));
        let n = waypoints.len();
        let p = self.params(json!({"name": name, "type": 2, "size": n}), json!([name, 2, n]));
        self.call_status(&mc("pathBufferAlloc")?, p)?;
        for chunk in waypoints.chunks(PATH_APPEND_WAYPOINTS) {
            let p = self.params(json!({"name": name, "waypoints": chunk}), json!([name, chunk]));
            self.call_status(&mc("pathBufferAppend")?, p)?;
        }
        let (a, v) = ([acc_rad_s2; 6], [speed_rad_s; 6]);
        let p = self.params(json!({"name": name, "a": a, "v": v, "t": interval_s}), json!([name, a, v, interval_s]));
        self.call_status(&mc("pathBufferEval")?, p)?;
        let valid = mc("pathBufferValid")?;
        let t0 = Instant::now();
        loop {
            let p = self.params(json!({"name": name}), json!([name]));
            match self.call(&valid, p)? {
                Value::Bool(true) => break,
                Value::Bool(false) if t0.elapsed() < valid_wait => std::thread::sleep(Duration::from_millis(10)),
                Value::Bool(false) => {
                    return Err(RobotError::UnexpectedState(format!(
                        "{valid}: path buffer `{name}` did not become valid within {:.1} s",
                        valid_wait.as_secs_f64()
                    )));
                }
                r => return Err(RobotError::Protocol(format!("{valid}: expected a bool, got {r}"))),
            }
        }
        let mv = mc("movePathBuffer")?;
        for attempt in 0..200 {
            let p = self.params(json!({"name": name}), json!([name]));
            match self.call_status(&mv, p)? {
                QUEUE_FULL => std::thread::sleep(Duration::from_millis(5 + attempt.min(20) * 5)),
                _ => return Ok(()),
            }
        }
        Err(RobotError::Timeout(format!("{mv}: the motion queue stayed full")))
    }

    /// `<robot>.MotionControl.pathBufferFree(name)`.
    ///
    /// # Errors
    /// As [`AuboClient::call_status`].
    pub fn path_buffer_free(&mut self, robot: &str, name: &str) -> Result<i64, RobotError> {
        let p = self.params(json!({"name": name}), json!([name]));
        self.call_status(&robot_method(robot, "MotionControl.pathBufferFree")?, p)
    }

    /// Waits until the controller is idle (`getExecId` = −1), polling every 10 ms; returns how
    /// long it waited.
    ///
    /// # Errors
    /// As [`AuboClient::call`]; [`RobotError::UnexpectedState`] when the controller still
    /// reports motion after `limit`, saying how long it waited and the last id.
    pub fn wait_idle(&mut self, robot: &str, limit: Duration) -> Result<Duration, RobotError> {
        let t0 = Instant::now();
        loop {
            let id = self.exec_id(robot)?;
            if id == -1 {
                return Ok(t0.elapsed());
            }
            if t0.elapsed() > limit {
                return Err(RobotError::UnexpectedState(format!(
                    "{robot}: motion did not finish: waited {:.1} s (limit {:.1} s), getExecId still {id}",
                    t0.elapsed().as_secs_f64(),
                    limit.as_secs_f64()
                )));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// Whether `name` can go into a method name: 1 to [`MAX_ROBOT_NAME_LEN`] characters from
/// `[A-Za-z0-9_]`. The error says why not, naming the name (shortened).
///
/// # Errors
/// A one-line description of what is wrong.
pub fn check_robot_name(name: &str) -> Result<(), String> {
    let ok_chars = name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_');
    if !name.is_empty() && name.len() <= MAX_ROBOT_NAME_LEN && ok_chars {
        return Ok(());
    }
    let shown: String = name.chars().take(80).collect();
    let more = if name.chars().count() > 80 { format!(" (… {} bytes)", name.len()) } else { String::new() };
    Err(format!(
        "robot name {shown:?}{more} is not a plain identifier of 1 to {MAX_ROBOT_NAME_LEN} characters from A–Z, a–z, 0–9 and _: refused (it would go into method names)"
    ))
}

/// `<robot>.<rest>`, refusing a robot name [`check_robot_name`] refuses.
fn robot_method(robot: &str, rest: &str) -> Result<String, RobotError> {
    check_robot_name(robot).map_err(RobotError::Protocol)?;
    Ok(format!("{robot}.{rest}"))
}

/// A JSON value for a message, shortened to 80 characters.
fn show_value(v: &Value) -> String {
    let s = v.to_string();
    if s.chars().count() <= 80 {
        s
    } else {
        format!("{}… ({} bytes)", s.chars().take(80).collect::<String>(), s.len())
    }
}

/// How far the controller's forward kinematics of its inverse-kinematics answer may lie from
/// the pose asked for, m.
pub const JOINT_POSE_TOLERANCE_M: f64 = 0.5e-3;
/// How far the orientation may turn likewise, rad.
pub const JOINT_POSE_TOLERANCE_RAD: f64 = 1e-3;
/// How far beyond the joint limits a joint position read from the controller may lie (encoder
/// noise at a limit), rad.
const JOINT_READ_SLACK_RAD: f64 = 0.02;

/// The result of an SDK method returning `(std::vector<double>, int)`: a JSON array
/// `[[six numbers], status]`; a status other than 0 is [`RobotError::Controller`].
fn six_with_status(method: &str, r: Value) -> Result<[f64; 6], RobotError> {
    let (v, code): (Vec<f64>, i64) =
        serde_json::from_value(r).map_err(|e| bad_json(method, "expected [[six numbers], status]", e))?;
    if code != 0 {
        return Err(RobotError::Controller { method: method.to_string(), code });
    }
    let q: [f64; 6] = v.try_into().map_err(|_| RobotError::Protocol(format!("{method}: expected six numbers")))?;
    if !q.iter().all(|x| x.is_finite()) {
        return Err(RobotError::Protocol(format!("{method}: {q:?} has a value that is not finite")));
    }
    Ok(q)
}

fn io_err(method: &str, e: std::io::Error) -> RobotError {
    match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => RobotError::Timeout(method.to_string()),
        _ => io_at(method, e),
    }
}

/// [`RobotError::Io`] while doing `context` (an address or a method).
pub(crate) fn io_at(context: &str, source: std::io::Error) -> RobotError {
    RobotError::Io { context: context.to_string(), source }
}

/// JSON-RPC's code for a method the server does not have.
pub const METHOD_NOT_FOUND: i64 = -32601;

/// The modified-DH arrays `a`, `alpha`, `d`, `theta` of `method`'s answer `r` (extra keys
/// ignored), validated.
fn dh_rows(method: &str, r: &Value) -> Result<crate::kinematics::DhParams, RobotError> {
    let row = |k: &str| -> Result<[f64; 6], RobotError> {
        let v: Vec<f64> = serde_json::from_value(r.get(k).cloned().unwrap_or(Value::Null))
            .map_err(|e| bad_json(method, &format!("expected `{k}`: six numbers"), e))?;
        v.try_into().map_err(|_| RobotError::Protocol(format!("{method}: `{k}` is not six numbers")))
    };
    let k = crate::kinematics::DhParams {
        a_m: row("a")?,
        alpha_rad: row("alpha")?,
        d_m: row("d")?,
        theta_rad: row("theta")?,
    };
    k.validate().map_err(|why| RobotError::Protocol(format!("{method}: {why}")))?;
    Ok(k)
}

/// [`RobotError::BadJson`]: `method`'s answer, and what was wrong with it.
fn bad_json(method: &str, what: &str, source: serde_json::Error) -> RobotError {
    RobotError::BadJson { context: format!("{method}: {what}"), source }
}

/// Sends a Lua script to the controller's script port, framed by `\r\n\r\n`. A script that
/// contains `\r\n\r\n` (the port would run it as two scripts) or a NUL byte is refused
/// before connecting.
///
/// # Errors
/// [`RobotError::Unsafe`] for such a script, naming the line; [`RobotError::Io`].
pub fn send_script(addr: &str, script: &str, timeout: Duration) -> Result<(), RobotError> {
    check_script(script)?;
    let c = AuboClient::connect(addr, timeout)?;
    let mut s = c.stream;
    s.write_all(script.as_bytes()).and_then(|_| s.write_all(b"\r\n\r\n")).map_err(|e| io_at(addr, e))
}

/// Refuses a script the script port would not take as one script: one containing the
/// terminator `\r\n\r\n` or a NUL byte.
pub(crate) fn check_script(script: &str) -> Result<(), RobotError> {
    let line_of = |at: usize| script[..at].matches('\n').count() + 1;
    let (at, what) = if let Some(at) = script.find("\r\n\r\n") {
        (at, "the script terminator \"\\r\\n\\r\\n\" (the script port would run what follows as a second script)")
    } else if let Some(at) = script.find('\0') {
        (at, "a NUL byte")
    } else {
        return Ok(());
    };
    Err(RobotError::Unsafe {
        stroke: None,
        point: None,
        reason: format!("the script contains {what} at byte {at} (line {}); nothing was sent", line_of(at)),
    })
}
