//! The fault-tolerant program runner: a program sent stroke by stroke over an [`AuboClient`],
//! reconnecting after a dropped link or a timeout within a retry budget, lifting the brush
//! straight out of the paper before resuming or giving up.
//!
//! The runner trusts nothing the controller reports. Every TCP pose it reads is checked (finite,
//! within reach, near this program, and within [`crate::POSE_TOLERANCE_M`] of what was commanded)
//! before it is acted on; motion it did not queue is an error; every wait for motion to finish
//! is bounded by the time the queued moves need.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::RobotError;
use crate::aubo::{AuboClient, Link, io_at};
use crate::controller::Position;
use crate::follow::{Commanded, Expect, Sent, check_pose, distance_m, program_box, show};
use crate::pose::Pose;
use crate::program::{Move, Program, StrokeProgram};
use crate::timing::{PATH_TOLERANCE_M, PATH_TOLERANCE_RAD, TimedStroke};

/// How far the controller's forward kinematics of a waypoint may lie from ours with the
/// parameters it reported, m and rad.
pub const CONTROLLER_FK_TOLERANCE_M: f64 = 1e-4;
/// See [`CONTROLLER_FK_TOLERANCE_M`].
pub const CONTROLLER_FK_TOLERANCE_RAD: f64 = 1e-3;
/// How long the runner waits for a path buffer to become valid after `pathBufferEval`.
pub const PATH_VALID_WAIT: Duration = Duration::from_secs(5);

/// A stroke whose lift move was sent counts as done after a fault when the TCP is this close
/// to the lift's end, m.
const DONE_M: f64 = 0.0005;

/// How the runner behaves on faults.
#[derive(Clone)]
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
    /// Shortest wait for queued motion to finish (the floor of the limit derived from the
    /// moves' expected duration).
    pub min_wait: Duration,
    /// Longest wait for one stroke's motion (or the start move, or a lift) to finish, unless
    /// its expected duration alone needs more (then 1.5 × that).
    pub max_wait_per_stroke: Duration,
    /// Safe height above the paper to lift to after a fault or a stop, m.
    pub lift_m: f64,
    /// The transport and credentials.
    pub link: Link,
    /// `Some(cfg)`: every pressed stroke goes to the controller as one path buffer of joint
    /// waypoints, timed with `cfg` ([`crate::time_program`]) on the controller's own kinematics
    /// (`getKinematicsParam`), checked before anything moves; `None`: a `moveLine` per point.
    pub path_buffer: Option<crate::program::RobotConfig>,
    /// Time the path buffers on maobi's nominal AUBO-i5 parameters
    /// ([`DhParams::AUBO_I5`](crate::kinematics::DhParams::AUBO_I5)) instead of the ones the
    /// controller reports; refused unless `accept_nominal_kinematics`.
    pub nominal_kinematics: bool,
    /// Accept path-buffer waypoints computed from the nominal parameters (when asked for, or
    /// when the controller does not answer `getKinematicsParam`); the controller's own forward
    /// kinematics must still agree with them before anything moves.
    pub accept_nominal_kinematics: bool,
    /// Set (for example by Ctrl-C) to stop: the runner sends no further stroke, waits for the
    /// controller to finish what it queued, lifts the brush and returns
    /// [`RobotError::Interrupted`] inside [`RobotError::RunStopped`].
    pub stop: &'a AtomicBool,
}

impl<'a> RunOptions<'a> {
    /// The defaults `maobi robot send` uses: 2 s per call, 5 connection attempts per fault,
    /// 3 faults per stroke, 10 per run, backoff 200 ms doubling to 5 s, waits for motion of
    /// at least 10 s and at most 2 min per stroke, lift 20 mm, the framed transport with the
    /// default user and password ([`Link::default`]).
    pub fn new(stop: &'a AtomicBool) -> Self {
        Self {
            timeout: Duration::from_secs(2),
            max_reconnects: 5,
            max_retries_per_stroke: 3,
            max_retries_total: 10,
            backoff: Duration::from_millis(200),
            max_backoff: Duration::from_secs(5),
            min_wait: Duration::from_secs(10),
            max_wait_per_stroke: Duration::from_secs(120),
            lift_m: 0.02,
            link: Link::default(),
            path_buffer: None,
            nominal_kinematics: false,
            accept_nominal_kinematics: false,
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
    /// JSON-RPC calls made over every connection (the login frames aside).
    pub calls: u64,
    /// Strokes sent as path buffers.
    pub path_buffers: usize,
    /// Whether the path buffers were timed on maobi's nominal parameters (accepted).
    pub nominal_kinematics: bool,
    /// Whether the controller reported a kinematics compensation (`getKinematicsCompensate`)
    /// and its nominal parameters plus it were checked against its forward kinematics.
    pub compensation_checked: bool,
}

struct Session {
    client: AuboClient,
    robot: String,
}

fn open(addr: &str, program: &Program, opts: &RunOptions<'_>, robot_name: Option<&str>) -> Result<Session, RobotError> {
    let (mut client, names) = AuboClient::open(addr, &opts.link, opts.timeout)?;
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
    client.set_tcp_offset(&robot, [0.0, 0.0, program.tcp_offset_m, 0.0, 0.0, 0.0])?;
    client.set_speed_fraction(&robot, program.speed_fraction)?;
    Ok(Session { client, robot })
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

fn is_fault(e: &RobotError) -> bool {
    matches!(e, RobotError::Io { .. } | RobotError::Timeout(_))
}

/// Runs a program on a controller (or the simulator) at `addr`, stroke by stroke.
///
/// Before the first move the controller must be idle (`getExecId` −1: no motion this run did
/// not queue) and report a finite pose within reach; after the start move and after every
/// stroke the reported TCP pose must be the commanded one within [`crate::POSE_TOLERANCE_M`] and
/// [`crate::ORIENTATION_TOLERANCE_RAD`] (and near the program's poses), and before every stroke the
/// controller must be idle and at the pose the last stroke left it. Every wait for motion to
/// finish is bounded: twice the expected duration of what was queued, at least `min_wait`, at
/// most `max_wait_per_stroke` (unless the moves alone need more: then 1.5 × their duration),
/// and the run's waiting as a whole by twice the sum of those limits.
///
/// On a dropped connection or a timeout it reconnects (at most `max_reconnects` attempts per
/// fault, waiting `backoff`, doubling up to `max_backoff`), waits for the controller to finish
/// what it was sent, checks the reported pose against the path commanded since the arm was
/// last seen, lifts the brush straight out of the paper to the safe height, and restarts the
/// interrupted stroke from its first point; a stroke whose lift was sent and has finished (the
/// TCP is at its end) counts as done and is never written twice. At most
/// `max_retries_per_stroke` faults per stroke and `max_retries_total` in the run are tolerated,
/// so a flaky link ends in bounded time.
///
/// # Errors
/// Without `opts.path_buffer`, a program whose pressed moves a blending controller refuses
/// ([`crate::program::check_blends`]: a zero-length move, a blend more than half a
/// neighbouring move), before connecting. Before anything moved (connecting, the robot name, setting the tool, motion or a pose the
/// controller should not report, the controller's kinematics refusing the start pose): the
/// error as it is. After that, any error (a controller error code, a JSON-RPC error, a spent
/// retry budget, [`RobotError::GaveUp`]; a reported state that disagrees with what was
/// commanded or motion that does not finish, [`RobotError::UnexpectedState`]; `opts.stop` set,
/// [`RobotError::Interrupted`]) first lifts the brush straight out of the paper to `opts.lift_m`
/// above it if the link allows (reconnecting once if it is down): from the reported pose if it
/// lies on the commanded path, otherwise from the last commanded pose; then returns
/// [`RobotError::RunStopped`] with the cause, the strokes completed and whether the brush was
/// seen at the safe height.
pub fn run_program(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
    progress: impl FnMut(&RunReport),
) -> Result<RunReport, RobotError> {
    if opts.path_buffer.is_none() {
        // A move per point: the blends must be ones a controller accepts.
        crate::program::check_blends(program)?;
    }
    let session = open(addr, program, opts, robot_name)?;
    run_opened(addr, program, robot_name, opts, session, progress)
}

/// A connection opened and checked before a run ([`preflight`]): the session, the controller's
/// interface version, and where the arm was.
pub(super) struct Opened {
    session: Session,
    /// `SystemInfo.getInterfaceVersionCode` (not asked on the line-delimited transport).
    pub(super) interface_version: Option<i64>,
    /// The robot driven.
    pub(super) robot: String,
    /// The TCP pose reported, checked to be finite and within reach.
    pub(super) pose: Pose,
}

/// Opens the connection as [`run_program`] does (the handshake, the robot name, the tool offset
/// and speed fraction set) and checks what [`run_program`] checks before its first move: the
/// controller idle (`getExecId` −1) and a finite pose within reach. Nothing moves.
///
/// # Errors
/// As [`run_program`] before anything moved.
pub(super) fn preflight(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
) -> Result<Opened, RobotError> {
    let mut session = open(addr, program, opts, robot_name)?;
    let id = session.client.exec_id(&session.robot)?;
    if id != -1 {
        return Err(RobotError::UnexpectedState(format!(
            "before the run: getExecId reported motion {id} though this run has nothing queued (is another client driving the arm?)"
        )));
    }
    let pose = session.client.tcp_pose(&session.robot)?;
    check_pose(&pose, &Expect::Reach, None, "before the run")?;
    let interface_version = session.client.interface_version();
    let robot = session.robot.clone();
    Ok(Opened { session, interface_version, robot, pose })
}

/// [`run_program`] on a connection [`preflight`] opened.
///
/// # Errors
/// As [`run_program`] after the connection is open.
pub(super) fn run_preflighted(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
    opened: Opened,
    progress: impl FnMut(&RunReport),
) -> Result<RunReport, RobotError> {
    run_opened(addr, program, robot_name, opts, opened.session, progress)
}

fn run_opened(
    addr: &str,
    program: &Program,
    robot_name: Option<&str>,
    opts: &RunOptions<'_>,
    session: Session,
    mut progress: impl FnMut(&RunReport),
) -> Result<RunReport, RobotError> {
    let report = RunReport { strokes_total: program.strokes.len(), ..RunReport::default() };
    let mut run = Runner {
        addr,
        program,
        robot_name,
        opts,
        session: Some(session),
        report,
        commanded: Commanded::default(),
        moved: false,
        started: false,
        near: program_box(program),
        wait_left: Duration::ZERO,
        timing: Vec::new(),
        confirmed: 0,
    };
    run.wait_left = run.wait_budget();
    match run.drive(&mut progress) {
        Ok(()) => {
            run.drop_session();
            Ok(run.report)
        }
        Err(cause) if !run.moved => Err(cause),
        Err(cause) => Err(run.retreat(cause)),
    }
}

/// A run in progress: where it sends, what, and how far it got.
struct Runner<'a, 'o> {
    addr: &'a str,
    program: &'a Program,
    robot_name: Option<&'a str>,
    opts: &'a RunOptions<'o>,
    /// The open connection (`None` after a fault, until reconnected).
    session: Option<Session>,
    report: RunReport,
    /// What was commanded since the arm was last seen where expected.
    commanded: Commanded,
    /// Whether any move was sent (or may have been).
    moved: bool,
    /// Whether the arm was seen at the start pose (then the program's neighbourhood applies).
    started: bool,
    /// The box of the program's commanded positions, m.
    near: ([f64; 3], [f64; 3]),
    /// What is left of the run's budget for waiting on motion.
    wait_left: Duration,
    /// The timed strokes sent as path buffers (empty: every stroke as moves).
    timing: Vec<TimedStroke>,
    /// Moves of the stroke being written already seen done (a path buffer's stroke is settled
    /// after its approach): with the moves commanded since, the stroke's whole count.
    confirmed: usize,
}

/// The temperature the kinematics compensation is read at, °C (the SDK's default).
pub const REF_TEMPERATURE_C: f64 = 20.0;

/// The parameters `a` with the increments `b` added, array by array.
fn plus(a: &crate::kinematics::DhParams, b: &crate::kinematics::DhParams) -> crate::kinematics::DhParams {
    let add = |x: &[f64; 6], y: &[f64; 6]| -> [f64; 6] { std::array::from_fn(|i| x[i] + y[i]) };
    crate::kinematics::DhParams {
        a_m: add(&a.a_m, &b.a_m),
        alpha_rad: add(&a.alpha_rad, &b.alpha_rad),
        d_m: add(&a.d_m, &b.d_m),
        theta_rad: add(&a.theta_rad, &b.theta_rad),
    }
}

/// The fault budget of the stroke being written.
struct StrokeFaults {
    /// Faults on this stroke.
    count: usize,
    /// The wait before the next reconnection attempt.
    backoff: Duration,
}

impl Runner<'_, '_> {
    fn session(&mut self) -> &mut Session {
        self.session.as_mut().expect("connected")
    }

    /// Closes the session (if any), counting its calls.
    fn drop_session(&mut self) {
        if let Some(s) = self.session.take() {
            self.report.calls += s.client.calls();
        }
    }

    /// Times the pressed strokes on the controller's kinematics for path buffers (when asked):
    /// its parameters read (`getKinematicsParam`), every stroke timed and checked from `seed`
    /// (the joints the start move goes to), and its own forward kinematics of the first,
    /// middle and last waypoints compared with ours and with the path, before anything moves.
    fn plan_path_buffers(&mut self, seed: Option<&[f64; 6]>) -> Result<(), RobotError> {
        let Some(cfg) = &self.opts.path_buffer else { return Ok(()) };
        let program = self.program;
        let opts = self.opts;
        let s = self.session.as_mut().expect("connected");
        let reported = if opts.nominal_kinematics {
            Err("nominal parameters were asked for".to_string())
        } else {
            match s.client.kinematics_params(&s.robot, true) {
                Ok(k) => Ok(k),
                Err(RobotError::Rpc { code: crate::aubo::METHOD_NOT_FOUND, method, message }) => {
                    Err(format!("the controller does not answer {method}: {message}"))
                }
                Err(e) => return Err(e),
            }
        };
        // Where the controller reports a compensation, its nominal parameters plus it must
        // describe the same arm as its calibrated ones and its own forward kinematics.
        let nominal = reported.is_err();
        let (kin, compensated) = match reported {
            Ok(k) => match s.client.kinematics_compensate(&s.robot, REF_TEMPERATURE_C)? {
                Some(c) => (k, Some(plus(&s.client.kinematics_params(&s.robot, false)?, &c))),
                None => (k, None),
            },
            Err(_) if opts.accept_nominal_kinematics => (crate::kinematics::DhParams::AUBO_I5, None),
            Err(reason) => return Err(RobotError::NominalKinematics { reason }),
        };
        let timing = crate::timing::time_program_from(program, &kin, cfg, seed)?;
        let tcp = program.tcp();
        let mut probes = Vec::new();
        if let (Some(first), Some(last)) = (timing.strokes.first(), timing.strokes.last()) {
            probes = vec![(first, 0), (first, first.joints.len() / 2), (last, last.joints.len() - 1)];
        }
        for (t, k) in probes {
            let q = t.joints[k];
            let theirs = s.client.forward_kinematics(&s.robot, &q)?.to_iso();
            let ours = kin.forward(&q, &tcp);
            let want = t.poses[k].to_iso();
            let d = |a: &nalgebra::Isometry3<f64>, b: &nalgebra::Isometry3<f64>| {
                ((a.translation.vector - b.translation.vector).norm(), a.rotation.angle_to(&b.rotation))
            };
            let (dm, dr) = d(&theirs, &ours);
            let (pm, pr) = d(&ours, &want);
            if let Some(kc) = &compensated {
                let (cm, cr) = d(&theirs, &kc.forward(&q, &tcp));
                if cm > CONTROLLER_FK_TOLERANCE_M || cr > CONTROLLER_FK_TOLERANCE_RAD {
                    return Err(RobotError::Unsafe {
                        stroke: Some(t.stroke),
                        point: None,
                        reason: format!(
                            "waypoint {k} of the path buffer: the controller's nominal parameters plus its compensation at {REF_TEMPERATURE_C} °C (getKinematicsCompensate) put the TCP {:.4} mm and {cr:.5} rad from its own forward kinematics (at most {} mm, {CONTROLLER_FK_TOLERANCE_RAD} rad): its reported parameters do not describe one arm; nothing was moved",
                            cm * 1e3,
                            CONTROLLER_FK_TOLERANCE_M * 1e3
                        ),
                    });
                }
            }
            if dm > CONTROLLER_FK_TOLERANCE_M
                || dr > CONTROLLER_FK_TOLERANCE_RAD
                || pm > PATH_TOLERANCE_M
                || pr > PATH_TOLERANCE_RAD
            {
                return Err(RobotError::Unsafe {
                    stroke: Some(t.stroke),
                    point: None,
                    reason: format!(
                        "waypoint {k} of the path buffer: the controller's forward kinematics put the TCP {:.4} mm and {dr:.5} rad from ours (at most {} mm, {CONTROLLER_FK_TOLERANCE_RAD} rad), ours {:.4} mm and {pr:.5} rad from the path (at most {} mm, {PATH_TOLERANCE_RAD} rad); nothing was moved",
                        dm * 1e3,
                        CONTROLLER_FK_TOLERANCE_M * 1e3,
                        pm * 1e3,
                        PATH_TOLERANCE_M * 1e3
                    ),
                });
            }
        }
        self.timing = timing.strokes;
        self.report.nominal_kinematics = nominal;
        self.report.compensation_checked = compensated.is_some();
        Ok(())
    }

    /// The wait limit for `expected_s` seconds of queued motion ([`wait_limit`]).
    fn wait_limit(&self, expected_s: f64) -> Duration {
        wait_limit(expected_s, self.opts.min_wait, self.opts.max_wait_per_stroke)
    }

    /// Twice the sum of the wait limits of the start move and every stroke: room for each
    /// stroke to run twice.
    fn wait_budget(&self) -> Duration {
        let f = self.program.speed_fraction;
        let start = Commanded { from: None, sent: vec![Sent::of(&self.program.start)] };
        let mut total = self.wait_limit(start.duration_s(f));
        let mut at = start_pose(self.program);
        for st in &self.program.strokes {
            let c = Commanded { from: at, sent: st.moves().map(Sent::of).collect() };
            total += self.wait_limit(c.duration_s(f));
            at = c.last_pose();
        }
        total * 2
    }

    /// Waits until the controller has executed what was commanded (`what`), within the limit
    /// for its expected duration and what is left of the run's budget (not counted against
    /// the budget for a `retreat`).
    fn wait_done(&mut self, what: &str, retreat: bool) -> Result<(), RobotError> {
        let expected_s = self.commanded.duration_s(self.program.speed_fraction);
        let per = self.wait_limit(expected_s);
        let by_budget = !retreat && self.wait_left < per;
        let limit = if by_budget { self.wait_left } else { per };
        let s = self.session();
        let t0 = Instant::now();
        let r = s.client.wait_idle(&s.robot, limit);
        if !retreat {
            self.wait_left = self.wait_left.saturating_sub(t0.elapsed());
        }
        r.map(|_| ()).map_err(|e| match e {
            RobotError::UnexpectedState(inner) => {
                let why = if by_budget {
                    "what was left of the run's waiting budget".to_string()
                } else {
                    format!(
                        "2 × the expected time, at least {:.1} s, at most {:.1} s per stroke unless its moves need more",
                        self.opts.min_wait.as_secs_f64(),
                        self.opts.max_wait_per_stroke.as_secs_f64()
                    )
                };
                RobotError::UnexpectedState(format!(
                    "{what}: {inner}; {expected_s:.1} s of motion was queued (limit: {why})"
                ))
            }
            e => e,
        })
    }

    /// Fails unless the controller is idle: motion now is motion this run did not queue.
    fn expect_idle(&mut self, when: &str) -> Result<(), RobotError> {
        let s = self.session();
        let id = s.client.exec_id(&s.robot)?;
        if id == -1 {
            return Ok(());
        }
        Err(RobotError::UnexpectedState(format!(
            "{when}: getExecId reported motion {id} though this run has nothing queued (is another client driving the arm?)"
        )))
    }

    /// Reads the TCP pose and checks it against `expect`.
    fn read_pose(&mut self, expect: Expect<'_>, when: &str) -> Result<Pose, RobotError> {
        let near = if self.started { Some(self.near) } else { None };
        let s = self.session.as_mut().expect("connected");
        let here = s.client.tcp_pose(&s.robot)?;
        check_pose(&here, &expect, near.as_ref(), when)?;
        Ok(here)
    }

    /// Waits for what was commanded to finish, then checks the arm is at its end; the arm is
    /// then seen there.
    fn settle(&mut self, what: &str) -> Result<Pose, RobotError> {
        self.wait_done(what, false)?;
        let expect = self.commanded.last_pose();
        let when = format!("after {what}");
        let here = match expect {
            Some(p) => self.read_pose(Expect::At(p), &when)?,
            None => self.read_pose(Expect::Reach, &when)?,
        };
        self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        Ok(here)
    }

    /// Sends one move, recording it first (if its answer is lost it may still run).
    fn send(&mut self, m: &Move) -> Result<(), RobotError> {
        self.send_recorded(m, Sent::of(m))
    }

    fn send_recorded(&mut self, m: &Move, sent: Sent) -> Result<(), RobotError> {
        self.moved = true;
        self.commanded.sent.push(sent);
        let s = self.session();
        s.client.send_move(&s.robot, m)
    }

    /// The start move, then the arm seen at the start pose. A joint move to a pose is solved
    /// by the controller first (its inverse kinematics from the joints it reports, checked by
    /// its forward kinematics); a pose it cannot solve is refused before anything moves.
    fn start(&mut self) -> Result<(), RobotError> {
        let start = self.program.start;
        match start {
            Move::JointPose { pose, a, v } => {
                let s = self.session();
                let solved = s
                    .client
                    .joint_positions(&s.robot)
                    .and_then(|q0| Ok((q0, s.client.solve_joint_pose_near(&s.robot, &q0, &pose)?)));
                let (q0, q) = solved.map_err(|e| match e {
                    e if is_fault(&e) => e,
                    e => RobotError::Unsafe {
                        stroke: None,
                        point: None,
                        reason: format!(
                            "the controller gave no joints for the start pose {} that its own kinematics confirm ({}); nothing was moved",
                            show(&pose.0),
                            with_causes(&e)
                        ),
                    },
                })?;
                self.plan_path_buffers(Some(&q))?;
                let travel = q0.iter().zip(&q).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                let sent = Sent {
                    target: Some(pose),
                    joint: true,
                    joint_travel_rad: Some(travel),
                    v,
                    a,
                    blend_m: 0.0,
                    fixed_s: None,
                };
                self.send_recorded(&Move::Joint { q, a, v }, sent)?;
            }
            m => {
                self.plan_path_buffers(None)?;
                self.send(&m)?;
            }
        }
        self.settle("the move to the start pose")?;
        self.started = true;
        Ok(())
    }

    /// The run after the connection is open; any error returned leaves the retreat to
    /// [`Runner::retreat`].
    fn drive(&mut self, progress: &mut impl FnMut(&RunReport)) -> Result<(), RobotError> {
        self.expect_idle("before the run")?;
        let here = self.read_pose(Expect::Reach, "before the run")?;
        self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        self.start()?;
        let program = self.program;
        let mut k = 0;
        let mut faults = StrokeFaults { count: 0, backoff: self.opts.backoff };
        let mut fault: Option<RobotError> = None;
        while k < program.strokes.len() {
            if self.opts.stop.load(Ordering::SeqCst) {
                return Err(RobotError::Interrupted);
            }
            let st = &program.strokes[k];
            let result = match fault.take() {
                Some(e) => self.recover(st, &mut faults, e),
                None => self.run_stroke(st).map(|()| true),
            };
            match result {
                Ok(true) => {
                    self.report.strokes_completed.push(st.index);
                    progress(&self.report);
                    k += 1;
                    faults = StrokeFaults { count: 0, backoff: self.opts.backoff };
                }
                Ok(false) => {} // recovered: run the stroke again
                Err(e) if is_fault(&e) => fault = Some(e),
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// One stroke: the controller idle, the stroke's moves (stopping early, after the move in
    /// flight, when `stop` is set), then the arm seen at the stroke's end.
    fn run_stroke(&mut self, st: &StrokeProgram) -> Result<(), RobotError> {
        let what = format!("stroke {}", st.index + 1);
        let before = format!("before {what}");
        self.expect_idle(&before)?;
        if let Some(at) = self.commanded.from {
            let here = self.read_pose(Expect::At(at), &before)?;
            self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        }
        self.confirmed = 0;
        if let Some(t) = self.timing.iter().find(|t| t.stroke == st.index).cloned() {
            return self.run_path_buffer_stroke(st, &t, &what);
        }
        for m in st.moves() {
            if self.opts.stop.load(Ordering::SeqCst) {
                return Err(RobotError::Interrupted);
            }
            self.send(m)?;
        }
        self.settle(&what)?;
        Ok(())
    }

    /// A stroke through the path buffer: the dip and approach moves, the arm seen at the first
    /// point and at the buffer's first waypoint, the pressed path as one path buffer on its
    /// timing, the lift, the arm seen at its end; then the buffer freed.
    fn run_path_buffer_stroke(&mut self, st: &StrokeProgram, t: &TimedStroke, what: &str) -> Result<(), RobotError> {
        for m in st.dip.iter().chain(&st.approach) {
            if self.opts.stop.load(Ordering::SeqCst) {
                return Err(RobotError::Interrupted);
            }
            self.send(m)?;
        }
        self.settle(&format!("the approach of {what}"))?;
        self.confirmed = st.dip.len() + st.approach.len();
        if self.opts.stop.load(Ordering::SeqCst) {
            return Err(RobotError::Interrupted);
        }
        let s = self.session();
        let q = s.client.joint_positions(&s.robot)?;
        let off = q.iter().zip(&t.joints[0]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if !(off <= crate::timing::PATH_START_TOLERANCE_RAD) {
            return Err(RobotError::UnexpectedState(format!(
                "before the path buffer of {what}: the controller reports joints {q:?} rad, {off:.4} rad from the buffer's first waypoint (at most {} rad): another branch of the inverse kinematics",
                crate::timing::PATH_START_TOLERANCE_RAD
            )));
        }
        let n = st.press.len();
        for (i, m) in st.press.iter().enumerate() {
            let mut sent = Sent::of(m);
            sent.fixed_s = Some(if i + 1 == n { t.duration_s } else { 0.0 });
            self.commanded.sent.push(sent);
        }
        self.moved = true;
        let lim = match &self.opts.path_buffer {
            Some(cfg) => cfg.limits,
            None => crate::program::Limits::default(),
        };
        let name = format!("maobi_stroke_{}", st.index + 1);
        let s = self.session();
        s.client.run_path_buffer(
            &s.robot,
            &name,
            &t.joints,
            t.interval_s,
            lim.max_joint_speed_rad_s,
            lim.max_joint_acc_rad_s2,
            PATH_VALID_WAIT,
        )?;
        self.send(&st.lift)?;
        self.settle(what)?;
        self.report.path_buffers += 1;
        let s = self.session();
        // The stroke is done; a buffer left behind is replaced by the next of its name.
        let _ = s.client.path_buffer_free(&s.robot, &name);
        Ok(())
    }

    /// After fault `e` on stroke `st`: counts it against the budgets, reconnects, waits for the
    /// controller to finish what it was sent and checks where the arm is. `Ok(true)`: the
    /// stroke had finished (its lift was sent and the TCP is at its end); `Ok(false)`: the
    /// brush was lifted and the stroke is to run again.
    fn recover(&mut self, st: &StrokeProgram, faults: &mut StrokeFaults, e: RobotError) -> Result<bool, RobotError> {
        self.report.faults += 1;
        faults.count += 1;
        self.drop_session();
        let over_budget =
            faults.count > self.opts.max_retries_per_stroke || self.report.faults > self.opts.max_retries_total;
        if over_budget {
            return Err(self.gave_up(st, faults, 0, e));
        }
        let s = self.reconnect(st, faults)?;
        self.report.reconnects += 1;
        self.session = Some(s);
        let what = format!("stroke {} (after a fault)", st.index + 1);
        self.wait_done(&what, false)?;
        let commanded = self.commanded.clone();
        let here = self.read_pose(Expect::Along(&commanded), &format!("after reconnecting on {what}"))?;
        let Move::Line { pose: end, .. } = st.lift else { unreachable!("a stroke's lift is a line move") };
        let lift_sent = commanded.sent.len() + self.confirmed == st.moves().count()
            && commanded.sent.last().and_then(|s| s.target).is_some_and(|t| t == end);
        self.confirmed = 0;
        if lift_sent && distance_m(&here, &end) < DONE_M {
            self.commanded = Commanded { from: Some(here), sent: Vec::new() };
            return Ok(true);
        }
        self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        self.lift_from(here, false)?;
        self.report.strokes_resumed += 1;
        Ok(false)
    }

    /// Lifts the brush straight out of the paper from `from` (the arm is there, or was last
    /// commanded there), unless that pose is at the safe height already; waits for the lift and
    /// checks the arm is at its end. Returns what it did, in words.
    fn lift_from(&mut self, from: Pose, retreat: bool) -> Result<String, RobotError> {
        let (program, lift_m) = (self.program, self.opts.lift_m);
        let depth_mm = program.depth_mm(from.position());
        if depth_mm <= -lift_m * 1000.0 + 0.5 {
            return Ok(format!("the brush is at the safe height ({:.1} mm above the paper)", -depth_mm));
        }
        let pose = program.lifted_out(&from, lift_m);
        let m = Move::Line { pose, a: program.retreat_acc_m_s2, v: program.retreat_speed_m_s, blend_m: 0.0 };
        self.send(&m)?;
        if retreat {
            self.wait_done("the lift", true)?;
            let here = self.read_pose(Expect::At(pose), "after the lift")?;
            self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        } else {
            self.settle("the lift")?;
        }
        Ok(format!(
            "brush lifted from {depth_mm:.1} mm below the paper to the safe height ({:.1} mm above it)",
            lift_m * 1000.0
        ))
    }

    /// Reconnects, waiting the back-off (doubled each time, up to the maximum) before each of
    /// at most `max_reconnects` attempts.
    fn reconnect(&mut self, st: &StrokeProgram, faults: &mut StrokeFaults) -> Result<Session, RobotError> {
        let opts = self.opts;
        let mut attempt = 0;
        loop {
            sleep_unless(faults.backoff, opts.stop);
            faults.backoff = (faults.backoff * 2).min(opts.max_backoff);
            if opts.stop.load(Ordering::SeqCst) {
                return Err(RobotError::Interrupted);
            }
            attempt += 1;
            match open(self.addr, self.program, opts, self.robot_name) {
                Ok(s) => return Ok(s),
                Err(e) if is_fault(&e) && attempt < opts.max_reconnects => continue,
                Err(e) if is_fault(&e) => return Err(self.gave_up(st, faults, attempt, e)),
                Err(e) => return Err(e),
            }
        }
    }

    /// [`RobotError::GaveUp`] on stroke `st` with the budgets as they stand.
    fn gave_up(
        &self,
        st: &StrokeProgram,
        faults: &StrokeFaults,
        reconnect_attempts: usize,
        last: RobotError,
    ) -> RobotError {
        RobotError::GaveUp {
            stroke: st.index,
            faults_stroke: faults.count,
            max_stroke: self.opts.max_retries_per_stroke,
            faults_total: self.report.faults,
            max_total: self.opts.max_retries_total,
            reconnect_attempts,
            last: Box::new(last),
        }
    }

    /// The retreat on the open session: waits for the queued motion, then lifts from the
    /// reported pose if it lies on the commanded path (and the controller's reports were not
    /// already found wrong: `distrust`), otherwise from the last commanded pose.
    /// `Ok((seen at the safe height, words))`.
    fn retreat_here(&mut self, distrust: bool) -> Result<(bool, String), RobotError> {
        self.wait_done("the moves queued before the stop", true)?;
        let commanded = self.commanded.clone();
        let reported = if distrust {
            Err(RobotError::UnexpectedState("the controller's reports disagreed with what was commanded".into()))
        } else {
            self.read_pose(Expect::Along(&commanded), "before the lift")
        };
        let here = match reported {
            Ok(here) => here,
            Err(RobotError::UnexpectedState(why)) => {
                let Some(last) = commanded.last_pose() else {
                    return Ok((
                        false,
                        format!("the pose is not trusted ({why}) and no commanded pose is known: nothing sent"),
                    ));
                };
                self.commanded = Commanded { from: Some(last), sent: Vec::new() };
                let depth_mm = self.program.depth_mm(last.position());
                if depth_mm <= -self.opts.lift_m * 1000.0 + 0.5 {
                    return Ok((
                        false,
                        format!(
                            "the pose is not trusted ({why}); the last commanded pose {} is at the safe height, so nothing was sent: check the arm",
                            show(&last.0)
                        ),
                    ));
                }
                return match self.lift_from(last, true) {
                    Ok(words) => {
                        Ok((true, format!("the pose was not trusted ({why}); from the last commanded pose, {words}")))
                    }
                    Err(e) => Ok((
                        false,
                        format!(
                            "the pose is not trusted ({why}); a lift from the last commanded pose {} was sent, but then: {}",
                            show(&last.0),
                            with_causes(&e)
                        ),
                    )),
                };
            }
            Err(e) => return Err(e),
        };
        self.commanded = Commanded { from: Some(here), sent: Vec::new() };
        self.lift_from(here, true).map(|w| (true, w))
    }

    /// After the run stopped on `cause`: lifts the brush on the open link, or (if it is down or
    /// fails) on a fresh one, and says how far the run got.
    fn retreat(mut self, cause: RobotError) -> RobotError {
        let distrust = matches!(cause, RobotError::UnexpectedState(_));
        let mut outcome = match self.session {
            Some(_) => self.retreat_here(distrust),
            None => Err(io_at("lift", std::io::Error::new(std::io::ErrorKind::NotConnected, "not connected"))),
        };
        // A broken stream (a fault, or bytes out of frame) is left for a fresh connection.
        if outcome.as_ref().is_err_and(|e| is_fault(e) || matches!(e, RobotError::Framing(_))) {
            outcome = match open(self.addr, self.program, self.opts, self.robot_name) {
                Ok(s) => {
                    self.session = Some(s);
                    self.retreat_here(distrust)
                }
                Err(e) => Err(e),
            };
        }
        let (lifted, lift) = match outcome {
            Ok(r) => r,
            Err(e) => (false, format!("could not lift the brush ({}): it may still touch the paper", with_causes(&e))),
        };
        RobotError::RunStopped {
            cause: Box::new(cause),
            completed: self.report.strokes_completed.len(),
            total: self.report.strokes_total,
            reconnects: self.report.reconnects,
            lifted,
            lift,
            at: if lifted { self.commanded.from.map(|p| Box::new(Position::Tcp(p))) } else { None },
        }
    }
}

/// How long to wait for `expected_s` seconds of queued motion: twice that, at least
/// `min_wait`, at most `cap` unless the motion alone needs more (then 1.5 × it).
fn wait_limit(expected_s: f64, min_wait: Duration, cap: Duration) -> Duration {
    let cap = cap.as_secs_f64().max(1.5 * expected_s);
    Duration::from_secs_f64((2.0 * expected_s).min(cap).max(min_wait.as_secs_f64()))
}

/// The TCP pose the start move ends at, when the program says (not for joints).
fn start_pose(program: &Program) -> Option<Pose> {
    match program.start {
        Move::Line { pose, .. } | Move::JointPose { pose, .. } => Some(pose),
        Move::Joint { .. } => None,
    }
}

/// An error and its causes on one line, `: `-separated (for a message that keeps a second
/// error beside the one returned).
fn with_causes(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cause = c.source();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: fn(f64) -> Duration = Duration::from_secs_f64;

    #[test]
    fn wait_limits_follow_the_queued_motion_within_the_floor_and_the_cap() {
        // (expected s, floor s, cap s, limit s)
        for (expected, floor, cap, want) in [
            (0.0, 10.0, 120.0, 10.0),    // nothing queued: the floor
            (3.0, 10.0, 120.0, 10.0),    // 2 × 3 s under the floor
            (20.0, 10.0, 120.0, 40.0),   // 2 × the expected time
            (70.0, 10.0, 120.0, 120.0),  // capped
            (100.0, 10.0, 120.0, 150.0), // the moves alone need more than the cap: 1.5 ×
        ] {
            let got = wait_limit(expected, S(floor), S(cap)).as_secs_f64();
            assert!((got - want).abs() < 1e-9, "{expected} s: {got} s, not {want} s");
        }
    }
}
