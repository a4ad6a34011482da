//! The fault-tolerant program runner: a program sent stroke by stroke over an [`AuboClient`],
//! reconnecting after a dropped link or a timeout within a retry budget, lifting the brush
//! straight out of the paper before resuming or giving up.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::RobotError;
use crate::aubo::{AuboClient, Link, io_at};
use crate::program::{Move, Program, StrokeProgram};

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
    /// The transport and credentials.
    pub link: Link,
    /// Set (for example by Ctrl-C) to stop: the runner sends no further stroke, waits for the
    /// controller to finish what it queued, lifts the brush and returns
    /// [`RobotError::Interrupted`] inside [`RobotError::RunStopped`].
    pub stop: &'a AtomicBool,
}

impl<'a> RunOptions<'a> {
    /// The defaults `maobi robot send` uses: 2 s per call, 5 connection attempts per fault,
    /// 3 faults per stroke, 10 per run, backoff 200 ms doubling to 5 s, lift 20 mm, the framed
    /// transport with the default user and password ([`Link::default`]).
    pub fn new(stop: &'a AtomicBool) -> Self {
        Self {
            timeout: Duration::from_secs(2),
            max_reconnects: 5,
            max_retries_per_stroke: 3,
            max_retries_total: 10,
            backoff: Duration::from_millis(200),
            max_backoff: Duration::from_secs(5),
            lift_m: 0.02,
            link: Link::default(),
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
    matches!(e, RobotError::Io { .. } | RobotError::Timeout(_))
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
    let report = RunReport { strokes_total: program.strokes.len(), ..RunReport::default() };
    let idle_limit = opts.timeout * 100;
    let session = open(addr, program, opts, robot_name)?;
    let mut run = Runner { addr, program, robot_name, opts, idle_limit, session: Some(session), report };
    match run.drive(&mut progress) {
        Ok(()) => Ok(run.report),
        Err(cause) => Err(run.retreat(cause)),
    }
}

/// A run in progress: where it sends, what, and how far it got.
struct Runner<'a, 'o> {
    addr: &'a str,
    program: &'a Program,
    robot_name: Option<&'a str>,
    opts: &'a RunOptions<'o>,
    /// How long to wait for the controller to finish the moves it was sent.
    idle_limit: Duration,
    /// The open connection (`None` after a fault, until reconnected).
    session: Option<Session>,
    report: RunReport,
}

/// The fault budget of the stroke being written.
struct StrokeFaults {
    /// Faults on this stroke.
    count: usize,
    /// The wait before the next reconnection attempt.
    backoff: Duration,
}

impl Runner<'_, '_> {
    /// The run after the connection is open; any error returned leaves the retreat to
    /// [`Runner::retreat`].
    fn drive(&mut self, progress: &mut impl FnMut(&RunReport)) -> Result<(), RobotError> {
        {
            let s = self.session.as_mut().expect("open");
            s.client.send_move(&s.robot, &self.program.start)?;
            s.client.wait_idle(&s.robot, self.idle_limit)?;
        }
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
                None => {
                    let s = self.session.as_mut().expect("connected");
                    run_stroke(s, st, self.idle_limit, self.opts.stop).map(|()| true)
                }
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

    /// After fault `e` on stroke `st`: counts it against the budgets, reconnects, and sees
    /// where the brush is. `Ok(true)`: the stroke had finished (its lift pose is where the
    /// brush is); `Ok(false)`: the brush was lifted and the stroke is to run again.
    fn recover(&mut self, st: &StrokeProgram, faults: &mut StrokeFaults, e: RobotError) -> Result<bool, RobotError> {
        self.report.faults += 1;
        faults.count += 1;
        self.session = None;
        let over_budget =
            faults.count > self.opts.max_retries_per_stroke || self.report.faults > self.opts.max_retries_total;
        if over_budget {
            return Err(self.gave_up(st, faults, 0, e));
        }
        let s = self.reconnect(st, faults)?;
        self.report.reconnects += 1;
        let s = self.session.insert(s);
        // Did the stroke finish before the fault? Then its lift pose is where we are.
        let here = s.client.tcp_pose(&s.robot)?;
        let Move::Line { pose: end, .. } = st.lift else { unreachable!("a stroke's lift is a line move") };
        let done = here.position().iter().zip(end.position()).all(|(a, b)| (a - b).abs() < 1e-6);
        if !done {
            lift(s, self.program, self.opts.lift_m, self.idle_limit)?;
            self.report.strokes_resumed += 1;
        }
        Ok(done)
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

    /// After the run stopped on `cause`: lifts the brush on the open link, or (if it is down or
    /// fails) on a fresh one, and says how far the run got.
    fn retreat(mut self, cause: RobotError) -> RobotError {
        let (program, opts, idle_limit) = (self.program, self.opts, self.idle_limit);
        let mut outcome = match self.session.as_mut() {
            Some(s) => lift(s, program, opts.lift_m, idle_limit),
            None => Err(io_at("lift", std::io::Error::new(std::io::ErrorKind::NotConnected, "not connected"))),
        };
        // A broken stream (a fault, or bytes out of frame) is left for a fresh connection.
        if outcome.as_ref().is_err_and(|e| is_fault(e) || matches!(e, RobotError::Framing(_))) {
            outcome = open(self.addr, program, opts, self.robot_name)
                .and_then(|mut s| lift(&mut s, program, opts.lift_m, idle_limit));
        }
        let (lifted, lift) = match outcome {
            Ok(words) => (true, words),
            Err(e) => (false, format!("could not lift the brush ({}): it may still touch the paper", with_causes(&e))),
        };
        RobotError::RunStopped {
            cause: Box::new(cause),
            completed: self.report.strokes_completed.len(),
            total: self.report.strokes_total,
            reconnects: self.report.reconnects,
            lifted,
            lift,
        }
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
