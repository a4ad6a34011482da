//! The simulated controller behind every connection: its state, who owns motion, the trace
//! (a bounded window in memory, all of it streamed to the trace file), and the answer to each
//! JSON-RPC request.

use std::collections::VecDeque;
use std::io::Write as _;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

use nalgebra::Isometry3;
use serde_json::{Value, json};

use super::blend::{BlendMove, blended_line_motion, check_blend};
use super::{MIN_MOVE_SPEED, MIN_SPEED_FRACTION, MOTION_OWNED, SIM_ROBOT, SimOptions};
use crate::RobotError;
use crate::exec::{TraceEntry, joint_motion, line_motion};
use crate::kinematics;
use crate::pose::Pose;
use crate::program::{
    CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_SPEED_FRACTION,
    CONTROLLER_MAX_TCP_OFFSET_M,
};
use crate::wire;

/// The arm and its bookkeeping, behind one lock that is never held while a move is computed.
#[derive(Debug)]
struct State {
    tcp: Isometry3<f64>,
    speed_fraction: f64,
    joints: [f64; 6],
    pose: Pose,
    time_s: f64,
    moves_seen: usize,
    dropped: bool,
    /// The session that owns motion.
    owner: Option<u64>,
    /// The latest trace samples.
    window: VecDeque<TraceEntry>,
    recorded: u64,
    trace_error: Option<String>,
    /// The path buffers by name.
    buffers: std::collections::BTreeMap<String, PathBuffer>,
    /// Blended `moveLine`s accepted but not yet executed (a blend needs the next move): run by
    /// [`Shared::flush`] when a move without a blend arrives, or any other request, or the
    /// owner's connection closes. `pose`/`joints` stay where the chain starts until then.
    chain: Vec<Pending>,
}

/// A `moveLine` waiting in the chain: the move and the joints it ends at.
#[derive(Debug)]
struct Pending {
    m: BlendMove,
    q: [f64; 6],
}

/// Most blended moves the simulator holds before it executes them (its look-ahead): a longer
/// chain is executed up to there and the arm comes to rest (a bound on what a client can make
/// it hold).
pub const MAX_BLEND_CHAIN: usize = 500;

/// A path buffer (`pathBufferAlloc`): joint waypoints, and once evaluated the interval and
/// the limits they were checked against.
#[derive(Debug)]
struct PathBuffer {
    /// The waypoints the allocation allows.
    size: usize,
    waypoints: Vec<[f64; 6]>,
    /// The interval, s, once `pathBufferEval` accepted the buffer.
    valid_interval_s: Option<f64>,
}

/// The trace file while it is written.
struct TraceFile {
    path: String,
    out: std::io::BufWriter<std::fs::File>,
    /// Bytes written so far.
    written: u64,
}

/// What every connection of one simulator shares.
pub(super) struct Shared {
    state: Mutex<State>,
    owner_changed: Condvar,
    trace_file: Mutex<Option<TraceFile>>,
    pub(super) options: SimOptions,
    login_digest: String,
    next_session: AtomicU64,
    pub(super) connections: AtomicUsize,
    /// The script port's runtime: whether a script runs, its named variables, its stop request.
    pub(super) script: super::script::ScriptState,
}

/// What to do with a request's answer.
pub(super) enum Reply {
    /// Send it.
    Answer(Value),
    /// Close the connection without answering (an injected fault).
    Drop,
}

impl Shared {
    /// A controller at the home position; creates the trace file.
    pub(super) fn new(options: SimOptions) -> Result<Self, RobotError> {
        let trace_file = match &options.trace_path {
            Some(p) => {
                let path = p.display().to_string();
                let f = std::fs::File::create(p)
                    .map_err(|source| RobotError::Io { context: format!("trace file {path}"), source })?;
                Some(TraceFile { path, out: std::io::BufWriter::new(f), written: 0 })
            }
            None => None,
        };
        let tcp = Isometry3::identity();
        let q0 = crate::exec::HOME_JOINTS;
        let home = Pose::from_iso(&options.kinematics.forward(&q0, &tcp));
        Ok(Self {
            state: Mutex::new(State {
                tcp,
                speed_fraction: 1.0,
                joints: q0,
                pose: home,
                time_s: 0.0,
                moves_seen: 0,
                dropped: false,
                owner: None,
                window: VecDeque::new(),
                recorded: 0,
                trace_error: None,
                buffers: std::collections::BTreeMap::new(),
                chain: Vec::new(),
            }),
            owner_changed: Condvar::new(),
            trace_file: Mutex::new(trace_file),
            login_digest: wire::login_digest(&options.password),
            options,
            next_session: AtomicU64::new(1),
            connections: AtomicUsize::new(0),
            script: super::script::ScriptState::default(),
        })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// A new session's number.
    pub(super) fn new_session(&self) -> u64 {
        self.next_session.fetch_add(1, Ordering::SeqCst)
    }

    /// Whether `user` and `digest` are the login's.
    pub(super) fn login_ok(&self, user: &str, digest: &str) -> bool {
        user == self.options.user && digest == self.login_digest
    }

    /// Ends `session`: if it owned motion, motion is free (its moves have all been executed:
    /// the arm is idle).
    pub(super) fn release(&self, session: u64) {
        self.flush();
        let mut st = self.lock();
        if st.owner == Some(session) {
            st.owner = None;
            self.owner_changed.notify_all();
        }
    }

    pub(super) fn trace(&self) -> Vec<TraceEntry> {
        self.flush();
        self.lock().window.iter().copied().collect()
    }

    pub(super) fn samples_recorded(&self) -> u64 {
        self.lock().recorded
    }

    pub(super) fn trace_error(&self) -> Option<String> {
        self.lock().trace_error.clone()
    }

    pub(super) fn connections(&self) -> usize {
        self.connections.load(Ordering::SeqCst)
    }

    /// What every motion command does first: takes motion for `session` ([`Shared::claim`]) and
    /// counts the move, answering with the injected fault when one is due (a dropped link or a
    /// full queue); the locked state otherwise.
    fn start_move(&self, session: u64, id: &Value) -> Result<MutexGuard<'_, State>, Reply> {
        let mut st = self.claim(self.lock(), session, id)?;
        match st.move_fault(&self.options.faults) {
            Some(MoveFault::Drop) => Err(Reply::Drop),
            Some(MoveFault::QueueFull) => Err(ok(id, json!(crate::aubo::QUEUE_FULL))),
            None => Ok(st),
        }
    }

    /// Takes motion for `session` (or finds it already its own), waiting up to
    /// [`SimOptions::owner_wait`] for another owner to go; the refusal otherwise.
    fn claim<'a>(
        &'a self,
        st: MutexGuard<'a, State>,
        session: u64,
        id: &Value,
    ) -> Result<MutexGuard<'a, State>, Reply> {
        let (mut st, _) = self
            .owner_changed
            .wait_timeout_while(st, self.options.owner_wait, |s| s.owner.is_some_and(|o| o != session))
            .unwrap_or_else(PoisonError::into_inner);
        match st.owner {
            Some(o) if o != session => Err(err(
                id,
                MOTION_OWNED,
                &format!(
                    "motion is owned by another session (connection #{o}): the controller runs one program at a \
                     time; motion is free once that connection closes"
                ),
            )),
            _ => {
                st.owner = Some(session);
                Ok(st)
            }
        }
    }

    /// Executes the blended moves waiting in the chain (the last one ends at rest on its
    /// target): the arm's pose and joints move to the chain's end at once (so every read
    /// answered after this sees them), the samples are computed unlocked and recorded.
    pub(super) fn flush(&self) {
        let (from, chain, t0) = {
            let mut st = self.lock();
            if st.chain.is_empty() {
                return;
            }
            let chain = std::mem::take(&mut st.chain);
            let from = st.pose;
            let last = chain.last().expect("not empty");
            st.joints = last.q;
            st.pose = last.m.pose;
            (from, chain, st.time_s)
        };
        let moves: Vec<BlendMove> = chain.iter().map(|p| p.m).collect();
        let samples = blended_line_motion(&from, &moves, t0);
        if let Some(last) = samples.last() {
            // Reserve the time at once, so a concurrent move starts after this chain.
            let mut st = self.lock();
            st.time_s = st.time_s.max(last.t_s);
        }
        self.record(&samples);
    }

    /// Records a move's samples: into the window, and to the trace file (a failed write stops
    /// the file and is kept as the trace error; the state goes on).
    fn record(&self, samples: &[TraceEntry]) {
        {
            let mut st = self.lock();
            if let Some(last) = samples.last() {
                st.time_s = last.t_s;
            }
            let cap = self.options.trace_window;
            let keep = samples.len().min(cap);
            let excess = (st.window.len() + keep).saturating_sub(cap);
            st.window.drain(..excess);
            st.window.extend(&samples[samples.len() - keep..]);
            st.recorded += samples.len() as u64;
        }
        let mut file = self.trace_file.lock().unwrap_or_else(PoisonError::into_inner);
        let Some(f) = file.as_mut() else { return };
        let max = self.options.trace_max_bytes;
        let mut full = false;
        let mut line = Vec::new();
        let written = samples
            .iter()
            .try_for_each(|t| {
                if full {
                    return Ok(());
                }
                line.clear();
                serde_json::to_writer(&mut line, t).map_err(std::io::Error::from)?;
                line.push(b'\n');
                if f.written + line.len() as u64 > max {
                    full = true;
                    return Ok(());
                }
                f.written += line.len() as u64;
                f.out.write_all(&line)
            })
            .and_then(|()| f.out.flush());
        let message = match written {
            Err(e) => {
                format!("trace file {}: {e}; it ends here (its last line may be cut), the simulator goes on", f.path)
            }
            Ok(()) if full => format!(
                "trace file {}: reached its size limit of {} MiB ({} bytes); it ends there, the simulator goes on",
                f.path,
                max >> 20,
                f.written
            ),
            Ok(()) => return,
        };
        *file = None;
        self.lock().trace_error = Some(message);
    }
}

pub(super) fn err(id: &Value, code: i64, message: &str) -> Reply {
    Reply::Answer(json!({"jsonrpc": "2.0", "id": id, "error": {"code": code, "message": message}}))
}

fn ok(id: &Value, result: Value) -> Reply {
    Reply::Answer(json!({"jsonrpc": "2.0", "id": id, "result": result}))
}

pub(super) fn parse_error(message: &str) -> Value {
    json!({"jsonrpc": "2.0", "id": null, "error": {"code": -32700, "message": format!("parse error: {message}")}})
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
pub(super) const NOT_LOGGED_IN: i64 = -32000;

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
    /// Acceleration, m/s² or rad/s².
    a: f64,
    /// Blend radius, m.
    blend: f64,
}

impl MoveArgs {
    /// Parses the params, `None` when they are not what the controller accepts (the names or
    /// count, the ranges of acceleration, speed and blend radius; a speed below
    /// [`MIN_MOVE_SPEED`]).
    fn parse(params: &Value, joint: bool) -> Option<Self> {
        let target = if joint { "q" } else { "pose" };
        if !arity(params, &[target, "a", "v", "blend_radius", "duration"], &["duration"]) {
            return None;
        }
        let num = |name: &str, pos: usize| arg(params, name, pos).and_then(Value::as_f64);
        let (a, v, blend) = (num("a", 1)?, num("v", 2)?, num("blend_radius", 3)?);
        let accepted = a > 0.0
            && a <= CONTROLLER_MAX_ACC
            && (MIN_MOVE_SPEED..=CONTROLLER_MAX_SPEED).contains(&v)
            && (0.0..=CONTROLLER_MAX_BLEND_M).contains(&blend);
        if !accepted {
            return None;
        }
        let target = arg(params, target, 0).and_then(numbers::<6>)?;
        Some(Self { joint, target, v, a, blend })
    }
}

impl State {
    /// Counts a move request and says whether a fault is injected on it.
    fn move_fault(&mut self, faults: &super::Faults) -> Option<MoveFault> {
        self.moves_seen += 1;
        let n = self.moves_seen;
        if faults.drop_after_moves == Some(n) && !self.dropped {
            self.dropped = true;
            return Some(MoveFault::Drop);
        }
        match faults.queue_full_every {
            Some(k) if k > 0 && n % k == 0 => Some(MoveFault::QueueFull),
            _ => None,
        }
    }
}

/// A TCP offset the controller accepts: `[x, y, z, rx, ry, rz]` (m, rad), the translation
/// shorter than [`CONTROLLER_MAX_TCP_OFFSET_M`], each rotation within ±2π.
fn tcp_offset(params: &Value) -> Option<Isometry3<f64>> {
    if !arity(params, &["offset"], &[]) {
        return None;
    }
    let o = arg(params, "offset", 0).and_then(numbers::<6>)?;
    let reach = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
    let turn_ok = o[3..].iter().all(|r| r.abs() <= std::f64::consts::TAU);
    (reach < CONTROLLER_MAX_TCP_OFFSET_M && turn_ok).then(|| Pose(o).to_iso())
}

/// Executes a move for `session`, which owns motion: the motion is computed with the state
/// unlocked (only the owner moves the arm, so nothing changes it meanwhile). Returns the status
/// (0, or [`UNREACHABLE`]).
fn execute(shared: &Shared, m: &MoveArgs, v: f64) -> i64 {
    let dh = &shared.options.kinematics;
    let (joints, pose, tcp, t0) = {
        let st = shared.lock();
        (st.joints, st.pose, st.tcp, st.time_s)
    };
    let (q, to, samples) = if m.joint {
        let q = m.target;
        if q.iter().any(|x| x.abs() > kinematics::JOINT_LIMIT_RAD) {
            return UNREACHABLE;
        }
        let samples = ramped_joint_motion(dh, &joints, &q, v, m.a, &tcp, t0);
        (q, Pose::from_iso(&dh.forward(&q, &tcp)), samples)
    } else {
        let to = Pose(m.target);
        let Some(q) = dh.inverse(&to, &tcp, Some(&joints)) else { return UNREACHABLE };
        (q, to, ramped_line_motion(&pose, &to, v, m.a, t0))
    };
    {
        let mut st = shared.lock();
        st.joints = q;
        st.pose = to;
    }
    shared.record(&samples);
    0
}

/// A `moveLine` that blends into the next move or ends a chain of blended moves: refused (−5)
/// when its blend radius is more than half its length or the blend before it more than half
/// of it ([`check_blend`]: a zero-length move cannot blend), [`UNREACHABLE`] when its target
/// is; otherwise added to the chain, which runs ([`Shared::flush`]) when this move has no
/// blend or the chain holds [`MAX_BLEND_CHAIN`] moves. Returns the status.
fn chain_line(shared: &Shared, st: MutexGuard<'_, State>, m: &MoveArgs, v: f64) -> i64 {
    let (from, q0, before) = st.chain.last().map_or((st.pose, st.joints, 0.0), |p| (p.m.pose, p.q, p.m.blend_m));
    let tcp = st.tcp;
    drop(st);
    let to = Pose(m.target);
    let len = (nalgebra::Vector3::from(to.position()) - nalgebra::Vector3::from(from.position())).norm();
    if check_blend(m.blend, len, f64::INFINITY).is_err() || check_blend(before, f64::INFINITY, len).is_err() {
        return INVALID_ARGUMENT;
    }
    let Some(q) = shared.options.kinematics.inverse(&to, &tcp, Some(&q0)) else { return UNREACHABLE };
    let full = {
        let mut st = shared.lock();
        st.chain.push(Pending { m: BlendMove { pose: to, v_m_s: v, a_m_s2: m.a, blend_m: m.blend }, q });
        m.blend <= 0.0 || st.chain.len() >= MAX_BLEND_CHAIN
    };
    if full {
        shared.flush();
    }
    0
}

/// The trapezoidal time law of a move of length `len` (m or rad) at speed `v` and
/// acceleration `a` from rest to rest: its duration, and the distance covered at time `t`.
fn trapezoid(len: f64, v: f64, a: f64) -> (f64, impl Fn(f64) -> f64) {
    let (v, a) = (v.max(1e-12), a.max(1e-12));
    let (ta, cruise_v) = if v * v / a >= len { ((len / a).sqrt(), (a * len).sqrt()) } else { (v / a, v) };
    let da = 0.5 * a * ta * ta;
    let total = 2.0 * ta + (len - 2.0 * da).max(0.0) / cruise_v;
    let at = move |t: f64| {
        if t <= ta {
            0.5 * a * t * t
        } else if t >= total - ta {
            len - 0.5 * a * (total - t).powi(2)
        } else {
            da + cruise_v * (t - ta)
        }
        .clamp(0.0, len)
    };
    (total, at)
}

/// How many samples, evenly in time over `total` s, keep the steps within the trace's limits:
/// at most [`crate::exec::TRACE_STEP_S`] apart, and at the top speed `v` along a path of
/// length `len` (m, or rad for joints) that moves the TCP `d` and turns it (or the joints)
/// `turn`, within [`crate::exec::TRACE_STEP_M`] and [`crate::exec::TRACE_STEP_RAD`].
fn timed_count(total: f64, v: f64, len: f64, d: f64, turn: f64) -> usize {
    use crate::exec::{MAX_SAMPLES_PER_MOVE, TRACE_STEP_M, TRACE_STEP_RAD, TRACE_STEP_S};
    let per = total * v / len;
    let steps = (total / TRACE_STEP_S).max(per * d / TRACE_STEP_M).max(per * turn / TRACE_STEP_RAD);
    if steps.is_nan() { 1 } else { steps.ceil().clamp(1.0, MAX_SAMPLES_PER_MOVE as f64) as usize }
}

/// A `moveLine` as the simulator executes it: the path of [`line_motion`] (a straight line,
/// the orientation by slerp; a turn in place counts 0.1 m per radian), on a trapezoidal time
/// law (from rest, at acceleration `a_m_s2` up to `v_m_s`, and down to rest), sampled evenly
/// in time (at most [`crate::exec::TRACE_STEP_S`] apart, and at the top speed at most
/// [`crate::exec::TRACE_STEP_M`] and [`crate::exec::TRACE_STEP_RAD`]; at most
/// [`crate::exec::MAX_SAMPLES_PER_MOVE`] samples). The plan's executed figure
/// ([`crate::exec::execute_program`]) keeps constant speed.
pub fn ramped_line_motion(from: &Pose, to: &Pose, v_m_s: f64, a_m_s2: f64, t0_s: f64) -> Vec<TraceEntry> {
    let (a, b) = (from.to_iso(), to.to_iso());
    let d = (b.translation.vector - a.translation.vector).norm();
    let turn = a.rotation.angle_to(&b.rotation);
    let len = d.max(turn * 0.1);
    if len <= 0.0 {
        return line_motion(from, to, v_m_s, t0_s);
    }
    let (total, at) = trapezoid(len, v_m_s, a_m_s2);
    let n = timed_count(total, v_m_s, len, d, turn);
    (1..=n)
        .map(|k| {
            let t = total * k as f64 / n as f64;
            let f = at(t) / len;
            let pose = if k == n { *to } else { crate::exec::pose_between(&a, &b, f) };
            TraceEntry { t_s: t0_s + t, kind: crate::exec::TraceKind::Line, pose }
        })
        .collect()
}

/// A `moveJoint` as the simulator executes it: the joints interpolated linearly (the TCP by
/// forward kinematics with `dh`) on a trapezoidal time law at `v_rad_s` and `a_rad_s2` over the
/// largest joint travel, sampled as [`ramped_line_motion`].
pub fn ramped_joint_motion(
    dh: &kinematics::DhParams,
    from: &[f64; 6],
    to: &[f64; 6],
    v_rad_s: f64,
    a_rad_s2: f64,
    tcp: &Isometry3<f64>,
    t0_s: f64,
) -> Vec<TraceEntry> {
    let dq = from.iter().zip(to).map(|(a, b)| (b - a).abs()).fold(0.0, f64::max);
    if dq <= 0.0 {
        return joint_motion(dh, from, to, v_rad_s, tcp, t0_s);
    }
    let (total, at) = trapezoid(dq, v_rad_s, a_rad_s2);
    let n = timed_count(total, v_rad_s, dq, 0.0, dq);
    (1..=n)
        .map(|k| {
            let t = total * k as f64 / n as f64;
            let f = if k == n { 1.0 } else { at(t) / dq };
            let q: [f64; 6] = std::array::from_fn(|j| from[j] + f * (to[j] - from[j]));
            TraceEntry {
                t_s: t0_s + t,
                kind: crate::exec::TraceKind::Joint,
                pose: Pose::from_iso(&dh.forward(&q, tcp)),
            }
        })
        .collect()
}

/// Answers one JSON-RPC request from `session`.
pub(super) fn handle(v: &Value, shared: &Shared, session: u64) -> Reply {
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
    // Blended moves wait for the next move; anything else runs them first (the arm is idle and
    // steady between other requests).
    if !method.ends_with(".MotionControl.moveLine") {
        shared.flush();
    }
    // The script runtime's calls (RuntimeMachine, RegisterControl).
    match super::script::handle(method, params, shared) {
        Some(Ok(r)) => return ok(&id, r),
        Some(Err(m)) => return err(&id, -32602, &m),
        None => {}
    }
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
        // Reads: for every session. Moves execute at once: the arm is always idle and steady
        // between requests.
        "MotionControl.getExecId" => ok(&id, json!(-1)),
        "RobotState.isSteady" => ok(&id, json!(true)),
        "RobotState.getTcpPose" => ok(&id, json!(shared.lock().pose.0)),
        "RobotState.getJointPositions" => ok(&id, json!(shared.lock().joints)),
        // The controller's kinematics services, as the SDK names them and their params (checked
        // with pyaubo_sdk 0.24.1): results are the SDK's `(values, status)` tuples, which it
        // reads as two-element JSON arrays; computed with the TCP offset set.
        "RobotAlgorithm.inverseKinematics" => {
            let qnear = arg(params, "qnear", 0).and_then(numbers::<6>);
            let pose = arg(params, "pose", 1).and_then(numbers::<6>);
            match (qnear, pose) {
                (Some(qnear), Some(pose)) if arity(params, &["qnear", "pose"], &[]) => {
                    let tcp = shared.lock().tcp;
                    match shared.options.kinematics.inverse(&Pose(pose), &tcp, Some(&qnear)) {
                        Some(q) => ok(&id, json!([q, 0])),
                        None => ok(&id, json!([qnear, UNREACHABLE])),
                    }
                }
                _ => ok(&id, json!([NO_VALUES, INVALID_ARGUMENT])),
            }
        }
        "RobotAlgorithm.forwardKinematics" => match arg(params, "q", 0).and_then(numbers::<6>) {
            Some(q) if arity(params, &["q"], &[]) => {
                let tcp = shared.lock().tcp;
                ok(&id, json!([Pose::from_iso(&shared.options.kinematics.forward(&q, &tcp)).0, 0]))
            }
            _ => ok(&id, json!([NO_VALUES, INVALID_ARGUMENT])),
        },
        "RobotConfig.getKinematicsParam" | "RobotConfig.getKinematicsCompensate"
            if !shared.options.kinematics_param =>
        {
            err(&id, -32601, &format!("method not found: {method}"))
        }
        // `real`: the calibrated parameters (true: the simulator's arm) or the nominal ones (the
        // i5's table); the compensation is their difference (at any temperature), `beta` zero.
        "RobotConfig.getKinematicsParam" => match arg(params, "real", 0) {
            Some(Value::Bool(real)) if arity(params, &["real"], &[]) => {
                let k = if *real { &shared.options.kinematics } else { &kinematics::DhParams::AUBO_I5 };
                ok(&id, json!({"a": k.a_m, "alpha": k.alpha_rad, "d": k.d_m, "theta": k.theta_rad, "beta": NO_VALUES}))
            }
            _ => err(&id, -32602, "getKinematicsParam takes one argument, `real` (a bool)"),
        },
        "RobotConfig.getKinematicsCompensate" => match arg(params, "ref_temperature", 0).and_then(Value::as_f64) {
            Some(_) if arity(params, &["ref_temperature"], &[]) => {
                let (k, n) = (&shared.options.kinematics, &kinematics::DhParams::AUBO_I5);
                let diff = |x: &[f64; 6], y: &[f64; 6]| -> [f64; 6] { std::array::from_fn(|i| x[i] - y[i]) };
                ok(
                    &id,
                    json!({
                        "a": diff(&k.a_m, &n.a_m),
                        "alpha": diff(&k.alpha_rad, &n.alpha_rad),
                        "d": diff(&k.d_m, &n.d_m),
                        "theta": diff(&k.theta_rad, &n.theta_rad),
                        "beta": NO_VALUES,
                    }),
                )
            }
            _ => err(&id, -32602, "getKinematicsCompensate takes one argument, `ref_temperature` (°C, a number)"),
        },
        // What changes motion: for the session that owns it.
        "RobotConfig.setTcpOffset" => set_tcp_offset(shared, session, params, &id),
        "MotionControl.setSpeedFraction" => set_speed_fraction(shared, session, params, &id),
        "MotionControl.moveJoint" | "MotionControl.moveLine" => {
            move_one(shared, session, params, &id, rest == "MotionControl.moveJoint")
        }
        "MotionControl.pathBufferAlloc"
        | "MotionControl.pathBufferAppend"
        | "MotionControl.pathBufferEval"
        | "MotionControl.pathBufferFree"
        | "MotionControl.pathBufferList"
        | "MotionControl.pathBufferValid" => path_buffer(shared, rest, params, &id),
        "MotionControl.movePathBuffer" => move_path_buffer(shared, session, params, &id),
        _ => err(&id, -32601, &format!("method not found: {method}")),
    }
}

/// `RobotConfig.setTcpOffset`, for the session that owns motion.
fn set_tcp_offset(shared: &Shared, session: u64, params: &Value, id: &Value) -> Reply {
    let st = match shared.claim(shared.lock(), session, id) {
        Ok(st) => st,
        Err(refused) => return refused,
    };
    let mut st = st;
    match tcp_offset(params) {
        Some(tcp) => {
            st.tcp = tcp;
            let q = st.joints;
            st.pose = Pose::from_iso(&shared.options.kinematics.forward(&q, &tcp));
            ok(id, json!(0))
        }
        None => ok(id, json!(INVALID_ARGUMENT)),
    }
}

/// `MotionControl.setSpeedFraction`, for the session that owns motion.
fn set_speed_fraction(shared: &Shared, session: u64, params: &Value, id: &Value) -> Reply {
    let mut st = match shared.claim(shared.lock(), session, id) {
        Ok(st) => st,
        Err(refused) => return refused,
    };
    match arg(params, "fraction", 0).and_then(Value::as_f64) {
        Some(f)
            if arity(params, &["fraction"], &[])
                && (MIN_SPEED_FRACTION..=CONTROLLER_MAX_SPEED_FRACTION).contains(&f) =>
        {
            st.speed_fraction = f;
            ok(id, json!(0))
        }
        _ => ok(id, json!(INVALID_ARGUMENT)),
    }
}

/// `MotionControl.moveJoint` (`joint`) or `moveLine`, for the session that owns motion: a joint
/// move or an unblended line executes at once, a blended line waits in the chain.
fn move_one(shared: &Shared, session: u64, params: &Value, id: &Value, joint: bool) -> Reply {
    let st = match shared.start_move(session, id) {
        Ok(st) => st,
        Err(reply) => return reply,
    };
    let Some(m) = MoveArgs::parse(params, joint) else {
        return ok(id, json!(INVALID_ARGUMENT));
    };
    let v = m.v * st.speed_fraction;
    if v < MIN_MOVE_SPEED {
        return ok(id, json!(INVALID_ARGUMENT));
    }
    if joint || (m.blend <= 0.0 && st.chain.is_empty()) {
        drop(st);
        return ok(id, json!(execute(shared, &m, v)));
    }
    ok(id, json!(chain_line(shared, st, &m, v)))
}

/// `MotionControl.movePathBuffer`, for the session that owns motion: the buffer executed from
/// where the arm is.
fn move_path_buffer(shared: &Shared, session: u64, params: &Value, id: &Value) -> Reply {
    let st = match shared.start_move(session, id) {
        Ok(st) => st,
        Err(reply) => return reply,
    };
    let name = match arg(params, "name", 0).and_then(Value::as_str) {
        Some(n) if arity(params, &["name"], &[]) => n,
        _ => return ok(id, json!(INVALID_ARGUMENT)),
    };
    let Some(b) = st.buffers.get(name) else { return ok(id, json!(INVALID_ARGUMENT)) };
    let Some(interval) = b.valid_interval_s else { return ok(id, json!(INVALID_ARGUMENT)) };
    // The buffer starts where the arm is: a controller does not jump to its first waypoint.
    let from = st.joints;
    if b.waypoints[0].iter().zip(&from).any(|(a, b)| (a - b).abs() > PATH_START_TOLERANCE_RAD) {
        return ok(id, json!(INVALID_ARGUMENT));
    }
    let waypoints = b.waypoints.clone();
    let (tcp, t0) = (st.tcp, st.time_s);
    drop(st);
    let dh = &shared.options.kinematics;
    let samples = path_motion(dh, &waypoints, interval, &tcp, t0);
    let last = *waypoints.last().expect("a valid buffer has waypoints");
    {
        let mut st = shared.lock();
        st.joints = last;
        st.pose = Pose::from_iso(&dh.forward(&last, &tcp));
    }
    shared.record(&samples);
    ok(id, json!(0))
}

/// Most path buffers the simulator holds at once.
pub const MAX_PATH_BUFFERS: usize = 16;
/// Most waypoints one path buffer holds (about 5 MB).
pub const MAX_BUFFER_WAYPOINTS: usize = 100_000;
/// Most waypoints all path buffers hold together (about 19 MB).
pub const MAX_TOTAL_WAYPOINTS: usize = 400_000;
/// Longest path buffer name, bytes.
pub const MAX_BUFFER_NAME: usize = 64;
/// The only path buffer type the simulator executes: 2, a cubic spline through joint
/// waypoints at a fixed interval.
pub const PATH_BUFFER_SPLINE: i64 = 2;
use crate::timing::PATH_START_TOLERANCE_RAD;

/// The path buffer services: the SDK's names and params (`pyaubo_sdk` 0.24.1: `pathBufferAlloc`
/// `{name, size, type}`, `pathBufferAppend` `{name, waypoints}`, `pathBufferEval`
/// `{name, a, v, t}`, `pathBufferValid`/`pathBufferFree` `{name}`, `pathBufferList` none).
/// Buffers are shared by every session, like a controller's; their count and sizes are capped.
fn path_buffer(shared: &Shared, rest: &str, params: &Value, id: &Value) -> Reply {
    let name = arg(params, "name", 0).and_then(Value::as_str);
    let mut st = shared.lock();
    let status = |s: i64| ok(id, json!(s));
    match rest {
        "MotionControl.pathBufferList" => {
            if !arity(params, &[], &[]) {
                return err(id, -32602, "pathBufferList takes no arguments");
            }
            ok(id, json!(st.buffers.keys().collect::<Vec<_>>()))
        }
        "MotionControl.pathBufferValid" => {
            let valid = arity(params, &["name"], &[])
                && name.and_then(|n| st.buffers.get(n)).is_some_and(|b| b.valid_interval_s.is_some());
            ok(id, json!(valid))
        }
        "MotionControl.pathBufferFree" => match name {
            Some(n) if arity(params, &["name"], &[]) && st.buffers.remove(n).is_some() => status(0),
            _ => status(INVALID_ARGUMENT),
        },
        "MotionControl.pathBufferAlloc" => {
            if !arity(params, &["name", "type", "size"], &[]) {
                return status(INVALID_ARGUMENT);
            }
            let kind = arg(params, "type", 1).and_then(Value::as_i64);
            let size = arg(params, "size", 2).and_then(Value::as_u64);
            let (Some(n), Some(PATH_BUFFER_SPLINE), Some(size)) = (name, kind, size) else {
                return status(INVALID_ARGUMENT);
            };
            let size = usize::try_from(size).unwrap_or(usize::MAX);
            let name_ok = !n.is_empty() && n.len() <= MAX_BUFFER_NAME && n.chars().all(|c| !c.is_control());
            let held: usize = st.buffers.iter().filter(|(k, _)| k.as_str() != n).map(|(_, b)| b.size).sum();
            let others = st.buffers.len() - usize::from(st.buffers.contains_key(n));
            if !name_ok
                || !(2..=MAX_BUFFER_WAYPOINTS).contains(&size)
                || held + size > MAX_TOTAL_WAYPOINTS
                || others >= MAX_PATH_BUFFERS
            {
                return status(INVALID_ARGUMENT);
            }
            // Allocating a name again replaces that buffer.
            st.buffers.insert(n.to_string(), PathBuffer { size, waypoints: Vec::new(), valid_interval_s: None });
            status(0)
        }
        "MotionControl.pathBufferAppend" => {
            let Some(b) =
                name.filter(|_| arity(params, &["name", "waypoints"], &[])).and_then(|n| st.buffers.get_mut(n))
            else {
                return status(INVALID_ARGUMENT);
            };
            let Some(list) = arg(params, "waypoints", 1).and_then(Value::as_array) else {
                return status(INVALID_ARGUMENT);
            };
            if b.waypoints.len() + list.len() > b.size {
                return status(INVALID_ARGUMENT);
            }
            let mut add = Vec::with_capacity(list.len());
            for w in list {
                match numbers::<6>(w) {
                    Some(q) if q.iter().all(|x| x.abs() <= kinematics::JOINT_LIMIT_RAD) => add.push(q),
                    _ => return status(INVALID_ARGUMENT),
                }
            }
            b.waypoints.extend(add);
            // Appending after an evaluation needs a new one.
            b.valid_interval_s = None;
            status(0)
        }
        "MotionControl.pathBufferEval" => {
            let Some(b) =
                name.filter(|_| arity(params, &["name", "a", "v", "t"], &[])).and_then(|n| st.buffers.get_mut(n))
            else {
                return status(INVALID_ARGUMENT);
            };
            let a = arg(params, "a", 1).and_then(numbers::<6>);
            let v = arg(params, "v", 2).and_then(numbers::<6>);
            let t = arg(params, "t", 3).and_then(Value::as_f64);
            let (Some(a), Some(v), Some(t)) = (a, v, t) else { return status(INVALID_ARGUMENT) };
            let in_range = |x: &f64| *x > 0.0 && *x <= CONTROLLER_MAX_SPEED;
            let limits_ok = v.iter().all(in_range) && a.iter().all(|x| *x > 0.0 && *x <= CONTROLLER_MAX_ACC);
            if !limits_ok || !(1e-3..=0.1).contains(&t) || b.waypoints.len() < 2 {
                b.valid_interval_s = None;
                return status(INVALID_ARGUMENT);
            }
            b.valid_interval_s = path_within(&b.waypoints, &v, &a, t).then_some(t);
            status(if b.valid_interval_s.is_some() { 0 } else { INVALID_ARGUMENT })
        }
        _ => err(id, -32601, "method not found"),
    }
}

/// Whether the waypoints at interval `t` keep every joint within its speed `v` and
/// acceleration `a` (first and second differences; 1e-9 relative slack for rounding).
fn path_within(w: &[[f64; 6]], v: &[f64; 6], a: &[f64; 6], t: f64) -> bool {
    let slack = 1.0 + 1e-9;
    let speeds = w.windows(2).all(|p| (0..6).all(|j| (p[1][j] - p[0][j]).abs() <= v[j] * t * slack));
    // The path starts and ends at rest: the first and last steps count as accelerations too.
    let ends = [[w[0], w[0], w[1]], [w[w.len() - 2], w[w.len() - 1], w[w.len() - 1]]];
    let accs = w
        .windows(3)
        .map(|p| [p[0], p[1], p[2]])
        .chain(ends)
        .all(|p| (0..6).all(|j| (p[2][j] - 2.0 * p[1][j] + p[0][j]).abs() <= a[j] * t * t * slack));
    speeds && accs
}

/// The executed motion of a path buffer: the waypoints at their times (one sample each, `t`
/// apart), and one more halfway between each pair on the cubic (Catmull-Rom) spline through
/// them, so the trace is sampled by time at `t / 2`.
pub(super) fn path_motion(
    dh: &kinematics::DhParams,
    w: &[[f64; 6]],
    t: f64,
    tcp: &Isometry3<f64>,
    t0: f64,
) -> Vec<TraceEntry> {
    let at = |q: &[f64; 6], time: f64| TraceEntry {
        t_s: time,
        kind: crate::exec::TraceKind::PathBuffer,
        pose: Pose::from_iso(&dh.forward(q, tcp)),
    };
    let mut out = Vec::with_capacity(2 * w.len());
    out.push(at(&w[0], t0));
    for k in 1..w.len() {
        let p0 = w[k.saturating_sub(2)];
        let (p1, p2) = (w[k - 1], w[k]);
        let p3 = w[(k + 1).min(w.len() - 1)];
        let mid: [f64; 6] = std::array::from_fn(|j| (-p0[j] + 9.0 * p1[j] + 9.0 * p2[j] - p3[j]) / 16.0);
        out.push(at(&mid, t0 + (k as f64 - 0.5) * t));
        out.push(at(&p2, t0 + k as f64 * t));
    }
    out
}
