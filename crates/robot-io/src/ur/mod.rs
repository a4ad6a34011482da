//! Universal Robots e-Series arms (UR3e, UR5e, …), driven live: [`UrArm`] sends the checked
//! program as one URScript program on the script port (30002), follows it over RTDE (30004:
//! the TCP pose, the program's state, the robot and safety modes, the count of finished strokes
//! the program writes into output register 24) and stops it through the dashboard server
//! (29999, `stop`). The arm's own kinematics solve every pose (no joint angle is sent).
//!
//! The RTDE protocol is in [`rtde`] and the dashboard client is [`Dashboard`] (each usable
//! alone); the simulator that stands in for a UR5e is [`crate::sim::UrSimulator`].

mod dashboard;
pub mod rtde;

pub use dashboard::{Dashboard, MAX_DASHBOARD_LINE_BYTES};

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::RobotError;
use crate::controller::{
    Controller, Plan, Position, Preflight, Prepared, Progress, RunSummary, Watch, expected_seconds,
};
use crate::follow::{Commanded, Expect, Sent, check_pose_from, distance_m, lift_words, program_box, run_stopped, show};
use crate::kinematics::DhParams;
use crate::pose::Pose;
use crate::program::{Program, RobotConfig, compact_program};
use rtde::{RtdeClient, Value};

/// UR's script port (the secondary interface): a program sent here replaces the one running.
pub const SCRIPT_PORT: u16 = 30002;
/// UR's RTDE port.
pub const RTDE_PORT: u16 = 30004;
/// UR's dashboard server port.
pub const DASHBOARD_PORT: u16 = 29999;
/// The oldest URControl maobi drives, `(major, minor)`: an e-Series 5.4 (`safety_status` and the
/// output registers 24–47 for external RTDE clients).
pub const MIN_CONTROL_VERSION: (u32, u32) = (5, 4);
/// The RTDE output frequency maobi asks for, Hz.
pub const RTDE_FREQUENCY_HZ: f64 = 125.0;
/// How far the controller's TCP offset may lie from the program's, m and rad.
pub const TCP_TOLERANCE_M: f64 = 1e-4;
/// See [`TCP_TOLERANCE_M`].
pub const TCP_TOLERANCE_RAD: f64 = 1e-3;
/// How far the controller's payload may lie from `robot.json`'s `payload_kg`, kg.
pub const PAYLOAD_TOLERANCE_KG: f64 = 0.05;
/// How long the controller has to start a program it was sent (`runtime_state` PLAYING).
pub const START_WAIT: Duration = Duration::from_secs(5);

/// What reports the pose maobi checks, for messages.
const RTDE_POSE: &str = "RTDE actual_TCP_pose";

/// The RTDE outputs maobi follows a run with, in recipe order.
const RECIPE: [&str; 9] = [
    "timestamp",
    "actual_TCP_pose",
    "runtime_state",
    "robot_mode",
    "safety_status_bits",
    "tcp_offset",
    "payload",
    "output_int_register_24",
    "actual_q",
];

/// `runtime_state`: the program is stopped.
pub const RUNTIME_STOPPED: u32 = 1;
/// `runtime_state`: the program is playing.
pub const RUNTIME_PLAYING: u32 = 2;
/// `robot_mode`: powered, brakes released, ready to move.
pub const ROBOT_MODE_RUNNING: i32 = 7;

/// The `safety_status_bits` that stop a run, with their names (UR's RTDE guide; bit 0 is
/// "normal mode", bit 1 "reduced mode").
pub const SAFETY_STOP_BITS: [(u32, &str); 8] = [
    (2, "a protective stop"),
    (3, "recovery mode"),
    (4, "a safeguard stop"),
    (5, "a system emergency stop"),
    (6, "a robot emergency stop"),
    (7, "an emergency stop"),
    (8, "a safety violation"),
    (9, "a safety fault"),
];

/// The `robot_mode` names (UR's client library, `RobotMode`).
fn robot_mode_name(m: i32) -> &'static str {
    match m {
        -1 => "NO_CONTROLLER",
        0 => "DISCONNECTED",
        1 => "CONFIRM_SAFETY",
        2 => "BOOTING",
        3 => "POWER_OFF",
        4 => "POWER_ON",
        5 => "IDLE",
        6 => "BACKDRIVE",
        7 => "RUNNING",
        8 => "UPDATING_FIRMWARE",
        _ => "unknown",
    }
}

/// The `runtime_state` names (UR's client library, `RUNTIME_STATE`).
fn runtime_name(s: u32) -> &'static str {
    match s {
        0 => "STOPPING",
        1 => "STOPPED",
        2 => "PLAYING",
        3 => "PAUSING",
        4 => "PAUSED",
        5 => "RESUMING",
        _ => "unknown",
    }
}

/// The ports of a UR controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UrPorts {
    /// The script port (30002).
    pub script: u16,
    /// RTDE (30004).
    pub rtde: u16,
    /// The dashboard server (29999).
    pub dashboard: u16,
}

impl Default for UrPorts {
    fn default() -> Self {
        Self { script: SCRIPT_PORT, rtde: RTDE_PORT, dashboard: DASHBOARD_PORT }
    }
}

/// One RTDE sample of the recipe maobi follows a run with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UrState {
    /// The controller's time, s.
    pub timestamp_s: f64,
    /// The TCP pose (AUBO-style `[x, y, z, rx, ry, rz]` RPY, converted from UR's rotation vector).
    pub pose: Pose,
    /// `runtime_state`.
    pub runtime_state: u32,
    /// `robot_mode`.
    pub robot_mode: i32,
    /// `safety_status_bits`.
    pub safety_bits: u32,
    /// The active TCP offset (position, rotation vector).
    pub tcp_offset: [f64; 6],
    /// The payload, kg.
    pub payload_kg: f64,
    /// Output integer register 24: strokes finished.
    pub strokes_done: i32,
    /// The joints, rad.
    pub joints: [f64; 6],
}

impl UrState {
    /// Reads a package of [`RECIPE`].
    fn from_values(v: &[Value]) -> Result<Self, RobotError> {
        let bad = || RobotError::Protocol(format!("RTDE data package not of maobi's recipe: {v:?}"));
        let (
            [
                Value::Double(timestamp_s),
                Value::Vector6d(pose),
                Value::Uint32(runtime_state),
                Value::Int32(robot_mode),
                Value::Uint32(safety_bits),
                Value::Vector6d(tcp_offset),
                Value::Double(payload_kg),
                Value::Int32(strokes_done),
                Value::Vector6d(joints),
            ],
        ) = (<[Value; 9]>::try_from(v.to_vec()).map_err(|_| bad())?,)
        else {
            return Err(bad());
        };
        Ok(UrState {
            timestamp_s,
            pose: pose_from_ur(&pose),
            runtime_state,
            robot_mode,
            safety_bits,
            tcp_offset,
            payload_kg,
            strokes_done,
            joints,
        })
    }

    /// What stops a run in these bits, in words.
    fn safety_stop(&self) -> Option<&'static str> {
        SAFETY_STOP_BITS.iter().find(|(b, _)| self.safety_bits & (1 << b) != 0).map(|(_, n)| *n)
    }
}

/// A UR pose `[x, y, z, rx, ry, rz]` (m, rotation vector) as a [`Pose`] (RPY).
pub fn pose_from_ur(p: &[f64; 6]) -> Pose {
    let r = UnitQuaternion::from_scaled_axis(Vector3::new(p[3], p[4], p[5]));
    Pose::from_iso(&Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), r))
}

/// A [`Pose`] as UR writes it: position and rotation vector.
pub fn pose_to_ur(p: &Pose) -> [f64; 6] {
    let [x, y, z] = p.position();
    let [a, b, c] = p.rotation_vector();
    [x, y, z, a, b, c]
}

/// A Universal Robots e-Series arm driven live (see the module documentation).
///
/// [`Controller::prepare`] times the program on the UR5e's published kinematics (only the tool
/// speeds are used: every pose is solved by the arm) and writes it as URScript, checked as
/// written ([`crate::export::urscript`]). [`Controller::connect`] reads the controller's
/// version, mode, safety state, TCP offset, payload and pose over RTDE and asks the dashboard
/// whether the arm is in remote control, refusing what does not fit with what to change.
/// [`Controller::run`] sends the program and follows it.
///
/// # Examples
/// ```no_run
/// use std::time::Duration;
/// use robot_io::Controller;
/// use robot_io::ur::{UrArm, UrPorts};
/// let c = UrArm::new("192.168.1.20", UrPorts::default(), Duration::from_secs(2));
/// assert!(c.describe().contains("30002"));
/// ```
pub struct UrArm {
    host: String,
    ports: UrPorts,
    timeout: Duration,
    ready: Option<UrReady>,
    conn: Option<UrConn>,
}

/// A prepared program.
struct UrReady {
    script: String,
    program: Program,
    /// The program whose moves the URScript makes (pressed strokes compacted), for the checks.
    compact: Program,
    config: RobotConfig,
    strokes_s: Vec<f64>,
    expected_s: f64,
    /// The box of the program's positions, m.
    near: ([f64; 3], [f64; 3]),
}

/// An open, checked connection.
struct UrConn {
    rtde: RtdeClient,
    dashboard: Dashboard,
    state: UrState,
}

impl UrArm {
    /// A controller at `host` on `ports`, `timeout` per connection and answer.
    pub fn new(host: &str, ports: UrPorts, timeout: Duration) -> Self {
        Self { host: host.to_string(), ports, timeout, ready: None, conn: None }
    }

    fn addr(&self, port: u16) -> String {
        format!("{}:{port}", self.host)
    }
}

impl Controller for UrArm {
    fn describe(&self) -> String {
        format!(
            "UR (URScript {}, RTDE {}, dashboard {}) at {}",
            self.ports.script, self.ports.rtde, self.ports.dashboard, self.host
        )
    }

    fn prepare(&mut self, plan: &Plan<'_>) -> Result<Prepared, RobotError> {
        let cfg = plan.config;
        let timing = crate::timing::time_program(plan.program, &DhParams::UR5E, cfg)?;
        let script = crate::export::urscript(plan.program, &timing, cfg, plan.title)?;
        let compact = compact_program(plan.program, cfg);
        // The pressed strokes take their timing's time (the `movep` speeds come from it).
        let (start_s, strokes_s) = expected_seconds(plan.program, Some(&timing));
        let expected_s = start_s + strokes_s.iter().sum::<f64>();
        let moves = script.lines().filter(|l| l.starts_with("  move")).count();
        let movep = script.lines().filter(|l| l.starts_with("  movep(")).count();
        let prepared = Prepared {
            summary: format!("{moves} moves ({movep} movep) in one URScript program"),
            strokes: plan.program.strokes.len(),
            expected_s: Some(expected_s),
        };
        self.ready = Some(UrReady {
            near: program_box(plan.program),
            script,
            program: plan.program.clone(),
            compact,
            config: cfg.clone(),
            strokes_s,
            expected_s,
        });
        self.conn = None;
        Ok(prepared)
    }

    fn connect(&mut self) -> Result<Preflight, RobotError> {
        let Some(ready) = &self.ready else {
            return Err(RobotError::Protocol("connect before prepare: nothing to run".into()));
        };
        let mut rtde = RtdeClient::connect(&self.addr(self.ports.rtde), self.timeout)?;
        let version = rtde.controller_version()?;
        if (version.major, version.minor) < MIN_CONTROL_VERSION {
            return Err(RobotError::Config {
                file: "controller".into(),
                message: format!(
                    "the controller runs URControl {version}: maobi drives UR e-Series controllers from {}.{} on (update the controller's software)",
                    MIN_CONTROL_VERSION.0, MIN_CONTROL_VERSION.1
                ),
            });
        }
        rtde.setup_outputs(RTDE_FREQUENCY_HZ, &RECIPE)?;
        rtde.start()?;
        let state = UrState::from_values(&rtde.next_data()?)?;
        let mut checks =
            vec![format!("URControl {version} (at least {}.{})", MIN_CONTROL_VERSION.0, MIN_CONTROL_VERSION.1)];
        if state.robot_mode != ROBOT_MODE_RUNNING {
            return Err(RobotError::UnexpectedState(format!(
                "the arm is not ready to move (robot_mode {} {}): power it on and release the brakes, then send again",
                state.robot_mode,
                robot_mode_name(state.robot_mode)
            )));
        }
        if let Some(stop) = state.safety_stop() {
            return Err(RobotError::UnexpectedState(format!(
                "the controller reports {stop} (safety_status_bits {:#x}): clear it on the pendant, then send again",
                state.safety_bits
            )));
        }
        if state.runtime_state != RUNTIME_STOPPED {
            return Err(RobotError::UnexpectedState(format!(
                "a program is {} on the controller (runtime_state {}): stop it first (maobi's program would replace it)",
                runtime_name(state.runtime_state),
                state.runtime_state
            )));
        }
        checks.push("robot mode RUNNING, safety normal, no program running".into());
        // The TCP offset the program needs: its tool along the flange axis.
        let want_tcp = [0.0, 0.0, ready.program.tcp_offset_m, 0.0, 0.0, 0.0];
        let got = pose_from_ur(&state.tcp_offset).to_iso();
        let want = pose_from_ur(&want_tcp).to_iso();
        let (dm, dr) =
            ((got.translation.vector - want.translation.vector).norm(), got.rotation.angle_to(&want.rotation));
        if !(dm <= TCP_TOLERANCE_M && dr <= TCP_TOLERANCE_RAD) {
            return Err(RobotError::Config {
                file: "controller".into(),
                message: format!(
                    "the controller's TCP is p{} (m, rotation vector), the program's tool is p[0, 0, {}, 0, 0, 0] (the brush's length_mm): set the installation's TCP to it (Installation › General › TCP), or use the brush profile of the mounted brush",
                    show(&state.tcp_offset),
                    ready.program.tcp_offset_m
                ),
            });
        }
        checks.push(format!("TCP offset p[0, 0, {}, 0, 0, 0] as the program needs", ready.program.tcp_offset_m));
        match ready.config.payload_kg {
            Some(m) if (state.payload_kg - m).abs() > PAYLOAD_TOLERANCE_KG => {
                return Err(RobotError::Config {
                    file: "controller".into(),
                    message: format!(
                        "the controller's payload is {:.3} kg, robot.json's payload_kg {m} kg: set the installation's payload to the brush and holder's mass (Installation › General › Payload), or correct payload_kg",
                        state.payload_kg
                    ),
                });
            }
            Some(m) => checks.push(format!("payload {:.3} kg (robot.json: {m} kg)", state.payload_kg)),
            None => {
                checks.push(format!("payload {:.3} kg not checked (robot.json has no payload_kg)", state.payload_kg))
            }
        }
        check_pose_from(&state.pose, &Expect::Reach, None, "before the run", RTDE_POSE)?;
        checks.push(format!("at {} within reach", Position::Tcp(state.pose)));
        let mut dashboard = Dashboard::connect(&self.addr(self.ports.dashboard), self.timeout)?;
        let remote = dashboard.command("is in remote control")?;
        match remote.as_str() {
            "true" => checks.push("in remote control".into()),
            "false" => {
                return Err(RobotError::UnexpectedState(
                    "the arm is in local control: the script port runs no program then; switch the pendant to Remote Control (top right)".into(),
                ));
            }
            other => checks.push(format!("remote control not known (the dashboard answered {other:?})")),
        }
        let software = dashboard.command("PolyscopeVersion").unwrap_or_default();
        let controller =
            if software.is_empty() { format!("UR, URControl {version}") } else { format!("UR, {software}") };
        self.conn = Some(UrConn { rtde, dashboard, state });
        Ok(Preflight { controller, checks })
    }

    fn run(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError> {
        let (Some(ready), Some(conn)) = (&self.ready, self.conn.take()) else {
            return Err(RobotError::Protocol("run before connect: no connection checked".into()));
        };
        let mut run = UrRun {
            ready,
            conn,
            script_addr: self.addr(self.ports.script),
            timeout: self.timeout,
            t0: Instant::now(),
            done: 0,
            started: false,
            packages: 0,
        };
        run.drive(watch)
    }
}

/// A run in progress.
struct UrRun<'a> {
    ready: &'a UrReady,
    conn: UrConn,
    script_addr: String,
    timeout: Duration,
    t0: Instant,
    /// Strokes finished, as the program last published.
    done: usize,
    /// Whether the arm was seen at the start pose.
    started: bool,
    packages: u64,
}

/// Why a run stops early, and whether the reported pose may be acted on (a lift).
struct Stop {
    cause: RobotError,
    /// The controller's reports are not trusted (or the arm cannot move): nothing more is sent.
    no_lift: Option<String>,
}

impl UrRun<'_> {
    fn total(&self) -> usize {
        self.ready.program.strokes.len()
    }

    /// The next RTDE sample.
    fn sample(&mut self) -> Result<UrState, RobotError> {
        let s = UrState::from_values(&self.conn.rtde.next_data()?)?;
        self.packages += 1;
        self.conn.state = s;
        Ok(s)
    }

    /// Sends a URScript program on the script port: connect, write it and a line end, close
    /// (reading and dropping what the port streams meanwhile, bounded).
    fn send_script(&self, text: &str) -> Result<(), RobotError> {
        let mut s = rtde::connect_stream(&self.script_addr, self.timeout)?;
        let what = format!("sending the program to {}", self.script_addr);
        s.write_all(text.as_bytes()).and_then(|()| s.write_all(b"\n")).map_err(|e| rtde::io_error(&what, e))?;
        let _ = s.shutdown(std::net::Shutdown::Write);
        let end = Instant::now() + Duration::from_millis(200);
        let _ = s.set_read_timeout(Some(Duration::from_millis(50)));
        let mut chunk = [0u8; 4096];
        while Instant::now() < end && matches!(s.read(&mut chunk), Ok(n) if n > 0) {}
        Ok(())
    }

    fn drive(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError> {
        self.send_script(&self.ready.script)?;
        // Until PLAYING nothing has moved: a program the controller refuses ends here.
        let deadline = Instant::now() + START_WAIT;
        loop {
            let s = self.sample()?;
            if s.runtime_state == RUNTIME_PLAYING {
                break;
            }
            if let Some(stop) = s.safety_stop() {
                return Err(RobotError::UnexpectedState(format!(
                    "the controller reports {stop} before the program started"
                )));
            }
            if Instant::now() >= deadline {
                return Err(RobotError::UnexpectedState(format!(
                    "the controller did not start the program within {:.0} s (runtime_state stays {}): PolyScope's log says why (a script it refused, local control)",
                    START_WAIT.as_secs_f64(),
                    runtime_name(s.runtime_state)
                )));
            }
        }
        match self.follow(watch) {
            Ok(()) => {
                let s = self.conn.state;
                Ok(RunSummary {
                    strokes_total: self.total(),
                    strokes_completed: (0..self.total()).collect(),
                    elapsed_s: self.t0.elapsed().as_secs_f64(),
                    at: Some(Position::Tcp(s.pose)),
                    counts: vec![format!("{} RTDE samples", self.packages)],
                    notes: vec![format!(
                        "the program ran as one URScript program; the expected time was {:.1} s",
                        self.ready.expected_s
                    )],
                })
            }
            Err(stop) => Err(self.stop(stop)),
        }
    }

    /// Follows the program to its end: every sample's safety state, program state, published
    /// stroke count and pose checked.
    fn follow(&mut self, watch: &mut Watch<'_>) -> Result<(), Stop> {
        let trusted = |cause| Stop { cause, no_lift: None };
        let total = self.total();
        let limit = Duration::from_secs_f64((2.0 * self.ready.expected_s).max(30.0));
        loop {
            if watch.stop.load(std::sync::atomic::Ordering::SeqCst) {
                return Err(trusted(RobotError::Interrupted));
            }
            if self.t0.elapsed() > limit {
                return Err(trusted(RobotError::UnexpectedState(format!(
                    "the program has not finished after {:.0} s (2 × the expected {:.1} s)",
                    limit.as_secs_f64(),
                    self.ready.expected_s
                ))));
            }
            let s = match self.sample() {
                Ok(s) => s,
                Err(e) => return Err(trusted(e)),
            };
            if let Some(stop) = s.safety_stop() {
                return Err(Stop {
                    cause: RobotError::UnexpectedState(format!(
                        "the controller reports {stop} (safety_status_bits {:#x}) at {}",
                        s.safety_bits,
                        Position::Tcp(s.pose)
                    )),
                    no_lift: Some(format!(
                        "the arm is stopped by its safety system ({stop}): clear it on the pendant and lift the brush by hand (it may still touch the paper)"
                    )),
                });
            }
            if s.robot_mode != ROBOT_MODE_RUNNING {
                return Err(Stop {
                    cause: RobotError::UnexpectedState(format!(
                        "the robot left RUNNING (robot_mode {} {})",
                        s.robot_mode,
                        robot_mode_name(s.robot_mode)
                    )),
                    no_lift: Some("the arm cannot move (not RUNNING): nothing sent".into()),
                });
            }
            let k = usize::try_from(s.strokes_done).ok().filter(|&k| k >= self.done && k <= total);
            let Some(k) = k else {
                return Err(Stop {
                    cause: RobotError::UnexpectedState(format!(
                        "output_int_register_24 reads {} after {} of {total} strokes: not this program's count (another program writing it?)",
                        s.strokes_done, self.done
                    )),
                    no_lift: Some(
                        "the controller runs something else than maobi's program: nothing more sent; check the arm"
                            .into(),
                    ),
                });
            };
            if let Err(e) = self.check(&s, k) {
                return Err(Stop {
                    cause: e,
                    no_lift: Some("the arm's reported pose is not trusted: the program was stopped, nothing more sent; check the arm".into()),
                });
            }
            if k > self.done {
                self.done = k;
                let elapsed_s = self.t0.elapsed().as_secs_f64();
                (watch.progress)(&Progress::of_arm(k, total, &self.ready.strokes_s, elapsed_s, s.pose));
            }
            if s.runtime_state != RUNTIME_PLAYING {
                if k == total && s.runtime_state == RUNTIME_STOPPED {
                    let end = self
                        .ready
                        .compact
                        .strokes
                        .last()
                        .map_or(start_pose(&self.ready.compact), |st| st.lift.target());
                    if let Some(end) = end {
                        check_pose_from(
                            &s.pose,
                            &Expect::At(end),
                            Some(&self.ready.near),
                            "after the program",
                            RTDE_POSE,
                        )
                        .map_err(|cause| Stop {
                            cause,
                            no_lift: Some("the program ended away from its last pose: check the arm".into()),
                        })?;
                    }
                    return Ok(());
                }
                return Err(trusted(RobotError::UnexpectedState(format!(
                    "the program stopped after {k} of {total} strokes (runtime_state {}) without maobi stopping it: PolyScope's log says why",
                    runtime_name(s.runtime_state)
                ))));
            }
        }
    }

    /// Checks a sample's pose against what the program commands while `k` strokes are done:
    /// before the arm reached the start pose, anywhere within reach (the start is a joint move);
    /// then on stroke `k`'s commanded path (from the end of the stroke before), within the
    /// tolerances and the program's neighbourhood.
    fn check(&mut self, s: &UrState, k: usize) -> Result<(), RobotError> {
        let compact = &self.ready.compact;
        let start = start_pose(compact);
        if !self.started {
            check_pose_from(&s.pose, &Expect::Reach, None, "on the move to the start pose", RTDE_POSE)?;
            if start.is_some_and(|p| distance_m(&p, &s.pose) <= crate::POSE_TOLERANCE_M) {
                self.started = true;
            }
            return Ok(());
        }
        let Some(st) = compact.strokes.get(k) else {
            // Every stroke done: the arm stays at the last lift.
            let end = compact.strokes.last().and_then(|st| st.lift.target());
            return match end {
                Some(p) => {
                    check_pose_from(&s.pose, &Expect::At(p), Some(&self.ready.near), "after the last stroke", RTDE_POSE)
                }
                None => Ok(()),
            };
        };
        let from = if k == 0 { start } else { compact.strokes[k - 1].lift.target() };
        let commanded = Commanded { from, sent: st.moves().map(Sent::of).collect() };
        check_pose_from(
            &s.pose,
            &Expect::Along(&commanded),
            Some(&self.ready.near),
            &format!("during stroke {}", k + 1),
            RTDE_POSE,
        )
    }

    /// Stops the program (dashboard `stop`), then, when the reports are trusted, lifts the brush
    /// straight out of the paper from where the arm stopped; says how far the run got.
    fn stop(&mut self, stop: Stop) -> RobotError {
        let Stop { cause, no_lift } = stop;
        let stopped = self.conn.dashboard.command("stop");
        let words = match &stopped {
            Ok(a) if a.starts_with("Stopped") => "the program was stopped (dashboard `stop`)".to_string(),
            Ok(a) => format!("the dashboard answered {a:?} to `stop`"),
            Err(e) => format!("the dashboard `stop` failed ({e})"),
        };
        // Wait (bounded) for the program to stop and the arm to settle.
        let mut last = self.conn.state;
        let end = Instant::now() + Duration::from_secs(2);
        // A pose reported after the stop: a lift is planned from nothing older (the arm may
        // have moved on for a whole time-out since the last sample before it).
        let mut fresh: Result<(), RobotError> = Err(RobotError::Timeout("no sample".into()));
        while Instant::now() < end {
            match self.sample() {
                Ok(s) => {
                    fresh = Ok(());
                    let still = distance_m(&s.pose, &last.pose) < 1e-5;
                    last = s;
                    if s.runtime_state == RUNTIME_STOPPED && still {
                        break;
                    }
                }
                Err(e) => {
                    fresh = Err(e);
                    break;
                }
            }
        }
        let no_lift = no_lift.or_else(|| {
            fresh.err().map(|e| {
                format!(
                    "no pose was reported after the stop ({e}): nothing sent, the brush may still touch the paper; check the arm"
                )
            })
        });
        let lift = match no_lift {
            Some(why) => Err(why),
            None => self
                .lift(&last)
                .map(|w| (w, self.conn.state.pose))
                .map_err(|e| format!("could not lift the brush ({e}): it may still touch the paper")),
        };
        let seen = last.pose;
        match run_stopped(cause, self.done, self.total(), words, lift) {
            // Not lifted: still where the arm was last seen.
            RobotError::RunStopped { cause, completed, total, reconnects, lifted, lift, at: None } => {
                RobotError::RunStopped {
                    cause,
                    completed,
                    total,
                    reconnects,
                    lifted,
                    lift,
                    at: Some(Box::new(Position::Tcp(seen))),
                }
            }
            e => e,
        }
    }

    /// Lifts the brush out of the paper from `s`'s pose (which must lie near the program), by a
    /// one-move program on the script port, and checks the arm arrived.
    fn lift(&mut self, s: &UrState) -> Result<String, RobotError> {
        let program = &self.ready.program;
        let lift_m = self.ready.config.lift_mm / 1000.0;
        check_pose_from(&s.pose, &Expect::Reach, Some(&self.ready.near), "before the lift", RTDE_POSE)?;
        let depth_mm = program.depth_mm(s.pose.position());
        if depth_mm <= -self.ready.config.lift_mm + 0.5 {
            return Ok(format!("the brush is at the safe height ({:.1} mm above the paper)", -depth_mm));
        }
        let to = program.lifted_out(&s.pose, lift_m);
        let text = crate::export::urscript_lift(
            program.tcp_offset_m,
            &to,
            program.retreat_acc_m_s2,
            program.retreat_speed_m_s,
        )?;
        self.send_script(&text)?;
        let end = Instant::now() + Duration::from_secs_f64(10.0 + 4.0 * (lift_m + 0.05) / program.retreat_speed_m_s);
        let mut playing = false;
        loop {
            let s = self.sample()?;
            if let Some(stop) = s.safety_stop() {
                return Err(RobotError::UnexpectedState(format!("{stop} during the lift")));
            }
            playing |= s.runtime_state == RUNTIME_PLAYING;
            if s.runtime_state == RUNTIME_STOPPED && (playing || distance_m(&s.pose, &to) < crate::POSE_TOLERANCE_M) {
                check_pose_from(&s.pose, &Expect::At(to), Some(&self.ready.near), "after the lift", RTDE_POSE)?;
                return Ok(lift_words(depth_mm, self.ready.config.lift_mm));
            }
            if Instant::now() > end {
                return Err(RobotError::Timeout("the lift".into()));
            }
        }
    }
}

fn start_pose(p: &Program) -> Option<Pose> {
    p.start.target()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ur_poses_convert_both_ways() {
        let p = Pose([0.4, -0.1, 0.2, std::f64::consts::PI, 0.1, -0.3]);
        let back = pose_from_ur(&pose_to_ur(&p));
        assert!(distance_m(&p, &back) < 1e-12 && p.to_iso().rotation.angle_to(&back.to_iso().rotation) < 1e-12);
    }

    #[test]
    fn the_ur5e_table_regrouped_is_urs_standard_dh_chain() {
        // UR's standard DH rows (FAQ 45257), chained as Rz(θ)·Tz(d)·Tx(a)·Rx(α).
        let d = [0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996];
        let a = [0.0, -0.425, -0.3922, 0.0, 0.0, 0.0];
        let alpha =
            [std::f64::consts::FRAC_PI_2, 0.0, 0.0, std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2, 0.0];
        for q in [[0.0; 6], [0.3, -1.2, 1.4, -1.7, -1.5, 0.4], crate::kinematics::UR_HOME_JOINTS] {
            let mut t = Isometry3::identity();
            for i in 0..6 {
                t =
                    t * Isometry3::from_parts(
                        Translation3::identity(),
                        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[i]),
                    ) * Isometry3::from_parts(Translation3::new(a[i], 0.0, d[i]), UnitQuaternion::identity())
                        * Isometry3::from_parts(
                            Translation3::identity(),
                            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha[i]),
                        );
            }
            let ours = DhParams::UR5E.forward(&q, &Isometry3::identity());
            assert!((ours.translation.vector - t.translation.vector).norm() < 1e-12, "{q:?}");
            assert!(ours.rotation.angle_to(&t.rotation) < 1e-12, "{q:?}");
        }
        // At zero the arm lies along −x: 0.425 + 0.3922 m out, d4 + d6 in −y, d1 − d5 up.
        let zero = DhParams::UR5E.forward(&[0.0; 6], &Isometry3::identity()).translation.vector;
        assert!((zero - Vector3::new(-0.8172, -0.2329, 0.0628)).norm() < 1e-9, "{zero}");
    }
}
