//! The seam between `maobi robot send` and the machines it drives: one trait, [`Controller`],
//! that every controller implements in its own module (AUBO over JSON-RPC and over its script
//! port in [`crate::aubo`], Universal Robots in `crate::ur`, a GRBL brush plotter in
//! `crate::grbl`), and the types that cross it.
//!
//! A send is three steps, in this order, each of which can refuse:
//!
//! 1. [`Controller::prepare`]: the checked [`Plan`] written in the form this controller runs (a
//!    list of moves, a script, G-code lines) and checked *as written* (read back by its own
//!    parser and compared with the plan). Nothing connects; `--dry-run` stops here.
//! 2. [`Controller::connect`]: the connection and the checks before anything moves (the
//!    controller's version, its tool and payload, its settings, that it is idle and where it
//!    is). Nothing moves; a mismatch is refused saying what to change.
//! 3. [`Controller::run`]: the prepared program sent (at once, or streamed with
//!    acknowledgements) and followed to its end, with [`Progress`] after each stroke. When
//!    [`Watch::stop`] is set (Ctrl-C), or the controller reports something the plan does not
//!    explain (a protective stop, a pose far from the planned one, a program that ended early),
//!    the run stops the machine the safe way for it (an arm finishes or halts its motion and
//!    lifts the brush out of the paper; a plotter holds its feed and raises its pen) and returns
//!    [`RobotError::RunStopped`] naming the cause, how far it got and where it stopped.
//!
//! ```
//! use std::sync::atomic::AtomicBool;
//! use robot_io::{Controller, Plan, Watch};
//!
//! /// Prepares, connects and runs `plan` on any controller, printing progress.
//! fn send(c: &mut dyn Controller, plan: &Plan<'_>, stop: &AtomicBool) -> Result<(), robot_io::RobotError> {
//!     let prepared = c.prepare(plan)?;
//!     println!("{}: {}", c.describe(), prepared.summary);
//!     let preflight = c.connect()?;
//!     println!("{}", preflight.checks.join("; "));
//!     let mut show = |p: &robot_io::Progress| println!("{} of {} strokes", p.strokes_done, p.strokes_total);
//!     let summary = c.run(&mut Watch { stop, progress: &mut show })?;
//!     println!("{} of {} strokes completed", summary.strokes_completed.len(), summary.strokes_total);
//!     Ok(())
//! }
//! ```

use std::sync::atomic::AtomicBool;

use brush_model::Track;
use serde::Serialize;

use crate::RobotError;
use crate::pose::Pose;
use crate::program::{Move, Program, RobotConfig};
use crate::timing::ProgramTiming;

/// What a controller is asked to write: the program checked by
/// [`build_program`](crate::build_program) (the safety envelope, every pose), the settings it was
/// built with, and the track it came from (a plotter writes in paper millimetres from the
/// track's points; an arm from the program's poses).
#[derive(Clone, Copy, Debug)]
pub struct Plan<'a> {
    /// The checked program: the start move, then per stroke its dip, approach, pressed moves
    /// and lift (poses in the robot base frame, m and rad).
    pub program: &'a Program,
    /// `robot.json`: speeds, limits, the ink station, the timing.
    pub config: &'a RobotConfig,
    /// The track the program was built from (paper mm), stroke for stroke.
    pub track: &'a Track,
    /// For a sheet, the character of each stroke (the ink reload rule `before_each_char`).
    pub stroke_chars: Option<&'a [usize]>,
    /// A title for the program's first comment (the character); made inert for each target.
    pub title: &'a str,
}

/// What [`Controller::prepare`] made of a plan.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Prepared {
    /// The program in words, for a person: "21 motion calls, 5 path buffers",
    /// "295 moves (279 movep)", "304 lines of G-code".
    pub summary: String,
    /// Strokes in the program.
    pub strokes: usize,
    /// The expected time of the whole run, s (the start move, every stroke and its dip), at the
    /// program's speed fraction; `None` where the controller plans the timing itself and maobi
    /// cannot say.
    pub expected_s: Option<f64>,
}

/// What [`Controller::connect`] found before anything moved.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Preflight {
    /// The controller as it names itself: its software version, robot or firmware.
    pub controller: String,
    /// Each check passed, in words ("controller 5.15.2 (at least 5.4)", "TCP offset
    /// p[0, 0, 0.2, 0, 0, 0] as the program needs", "idle at [..]").
    pub checks: Vec<String>,
}

/// Where the machine is, as its controller reports it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Position {
    /// An arm's tool centre point in its base frame, `[x, y, z, rx, ry, rz]` (m, rotation vector
    /// in rad; AUBO's poses are `[x, y, z, rx, ry, rz]` with RPY angles, see [`Pose`]).
    Tcp(Pose),
    /// A plotter's position in the program's work coordinates (paper mm; Z up from where the
    /// brush tip touches the paper).
    Plotter {
        /// X, mm.
        x_mm: f64,
        /// Y, mm.
        y_mm: f64,
        /// Z, mm.
        z_mm: f64,
    },
}

impl std::fmt::Display for Position {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Position::Tcp(p) => {
                let [x, y, z, a, b, c] = p.0;
                write!(f, "TCP [{x:.4}, {y:.4}, {z:.4}] m, [{a:.4}, {b:.4}, {c:.4}] rad")
            }
            Position::Plotter { x_mm, y_mm, z_mm } => write!(f, "X{x_mm:.3} Y{y_mm:.3} Z{z_mm:.3} mm"),
        }
    }
}

/// How far a run has got, reported after each stroke (and, where the controller streams its
/// state, as it moves).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Progress {
    /// Strokes finished (the brush lifted off at their end).
    pub strokes_done: usize,
    /// Strokes in the program.
    pub strokes_total: usize,
    /// Seconds since the run started.
    pub elapsed_s: f64,
    /// The expected time left, s, where the controller can say.
    pub remaining_s: Option<f64>,
    /// Where the machine was last reported.
    pub at: Option<Position>,
    /// Program lines acknowledged and in the program, `[done, total]`, where the controller
    /// streams the program line by line (a G-code plotter); `None` for the arms.
    pub lines: Option<[usize; 2]>,
}

impl Progress {
    /// An arm's progress once `done` of `total` strokes are finished, `elapsed_s` into the run,
    /// with the TCP at `pose`: the time left is the expected seconds (`strokes_s`, one per
    /// stroke) of the strokes not yet done.
    pub(crate) fn of_arm(done: usize, total: usize, strokes_s: &[f64], elapsed_s: f64, pose: Pose) -> Progress {
        Progress {
            strokes_done: done,
            strokes_total: total,
            elapsed_s,
            remaining_s: Some(strokes_s.iter().skip(done).sum()),
            at: Some(Position::Tcp(pose)),
            lines: None,
        }
    }
}

/// What a run is watched by: the stop request and the progress callback.
pub struct Watch<'a> {
    /// Set (by Ctrl-C, or another thread) to stop: the controller stops the machine the safe
    /// way for it and [`Controller::run`] returns [`RobotError::RunStopped`] with
    /// [`RobotError::Interrupted`] as the cause.
    pub stop: &'a AtomicBool,
    /// Called with the progress after each stroke (and more often where the controller reports
    /// more often). It must return quickly: it runs on the thread that follows the machine.
    pub progress: &'a mut dyn FnMut(&Progress),
}

/// What a finished run did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RunSummary {
    /// Strokes in the program.
    pub strokes_total: usize,
    /// The zero-based indices of the strokes completed, in order.
    pub strokes_completed: Vec<usize>,
    /// Seconds from the start of the run to its end.
    pub elapsed_s: f64,
    /// Where the machine was at the end, as last reported.
    pub at: Option<Position>,
    /// Counts particular to the controller, each a short clause ("1 reconnect(s), 1 stroke(s)
    /// resumed", "12 controller calls, 5 path buffer(s)"), for one line after the stroke count.
    pub counts: Vec<String>,
    /// Remarks particular to the controller, each a sentence ("the path buffers were timed on
    /// the controller's kinematics").
    pub notes: Vec<String>,
}

/// A machine `maobi robot send` can drive. Implementations live each in their own module and
/// keep their protocol to themselves; see the module documentation for the order of the calls
/// and what each may do.
pub trait Controller {
    /// The controller and where it is, for messages: "AUBO JSON-RPC (framed) at
    /// 10.0.0.2:30004", "UR (URScript 30002, RTDE 30004, dashboard 29999) at 10.0.0.5".
    fn describe(&self) -> String;

    /// Writes `plan` in this controller's form and checks it as written; connects to nothing.
    /// A later [`Controller::run`] sends exactly what this prepared.
    ///
    /// # Errors
    /// [`RobotError::Unsafe`] for a program this controller cannot run as checked (a blend it
    /// refuses, a stroke it cannot time, a text that does not read back as the plan).
    fn prepare(&mut self, plan: &Plan<'_>) -> Result<Prepared, RobotError>;

    /// Connects and checks everything that can be checked before the first move; nothing moves.
    ///
    /// # Errors
    /// [`RobotError::Io`] or [`RobotError::Timeout`] when the controller cannot be reached;
    /// [`RobotError::Config`] or [`RobotError::Unsafe`] naming what to change (the version, the
    /// tool, the payload, a setting); [`RobotError::UnexpectedState`] for a controller that is
    /// not idle, not powered or in a protective stop; [`RobotError::Protocol`] for answers out of
    /// its protocol. Calling it before [`Controller::prepare`] is
    /// [`RobotError::Protocol`].
    fn connect(&mut self) -> Result<Preflight, RobotError>;

    /// Sends the prepared program and follows it to its end.
    ///
    /// # Errors
    /// Before anything moved, the error as it is. After that, [`RobotError::RunStopped`]: the
    /// cause (a fault, a disagreement, [`RobotError::Interrupted`]), the strokes completed, what
    /// the safe stop did and where the machine was. Calling it before [`Controller::connect`]
    /// is [`RobotError::Protocol`].
    fn run(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError>;
}

/// The expected duration of each part of an arm program, s, at its speed fraction: the start
/// move, then each stroke with its dip (index by index). A timed stroke's pressed moves take its
/// timing's duration ([`ProgramTiming`], when given); every other move its length (or its turn
/// in place at the speed per 0.1 m, or for a joint move to a pose 1 rad) at its speed, plus the
/// time a trapezoidal profile loses ramping up and down (v / a). An estimate for progress
/// ("time left"), not a bound.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, build_program, expected_seconds, level_frame_in_front};
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &BrushProfile::builtin("pen1").unwrap(), &frame, &RobotConfig::default()).unwrap();
/// let (start_s, strokes_s) = expected_seconds(&program, None);
/// // 20 mm at the write speed of 20 mm/s is at least a second.
/// assert!(start_s > 0.0 && strokes_s.len() == 1 && strokes_s[0] > 1.0);
/// ```
pub fn expected_seconds(program: &Program, timing: Option<&ProgramTiming>) -> (f64, Vec<f64>) {
    let f = program.speed_fraction.max(1e-9);
    let mut at: Option<Pose> = None;
    let start = move_seconds(&program.start, &mut at, f);
    let strokes = program
        .strokes
        .iter()
        .map(|st| {
            let timed = timing.and_then(|t| t.strokes.iter().find(|t| t.stroke == st.index));
            let mut s: f64 = st.dip.iter().chain(&st.approach).map(|m| move_seconds(m, &mut at, f)).sum();
            match timed {
                Some(t) => {
                    s += t.duration_s;
                    // The pressed moves end where the timing ends: the last pressed pose.
                    if let Some(Move::Line { pose, .. }) = st.press.last() {
                        at = Some(*pose);
                    }
                }
                None => s += st.press.iter().map(|m| move_seconds(m, &mut at, f)).sum::<f64>(),
            }
            s + move_seconds(&st.lift, &mut at, f)
        })
        .collect();
    (start, strokes)
}

/// One move's expected duration from `at` (then its end) at speed fraction `f`, s.
fn move_seconds(m: &Move, at: &mut Option<Pose>, f: f64) -> f64 {
    let (v, a) = match *m {
        Move::Joint { a, v, .. } | Move::JointPose { a, v, .. } | Move::Line { a, v, .. } => (v, a),
    };
    let v = (v * f).max(1e-9);
    let path = match (*m, *at) {
        (Move::Line { pose, .. }, Some(from)) => {
            let (p, q) = (from.position(), pose.position());
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            d.max(0.1 * from.to_iso().rotation.angle_to(&pose.to_iso().rotation))
        }
        _ => 1.0,
    };
    *at = match *m {
        Move::Line { pose, .. } | Move::JointPose { pose, .. } => Some(pose),
        Move::Joint { .. } => None,
    };
    path / v + v / a.max(1e-9)
}
