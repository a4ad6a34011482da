//! # robot-io
//!
//! From a maobi brush track to a robot arm, safely. No image or ML dependencies.
//!
//! Every item has one path. The crate's own items are at the root; the controller families and
//! the pieces whose names only read right qualified are public modules, with their items only
//! there: [`aubo`], [`ur`] (with [`ur::rtde`]), [`sim`] and [`wire`].
//!
//! * The paper frame: [`PaperFrame`], the paper's pose in the robot base frame, fitted (Kabsch,
//!   SVD) from three or more touched points ([`PaperFile`], `paper.json`), with its residual;
//!   collinear points are refused.
//! * The pose: [`brush_pose`] turns a track point `(H, α, x, y, β)` into the TCP [`Pose`]
//!   `[x, y, z, rx, ry, rz]` (m, rad, `R = Rz·Ry·Rx`): the brush tip `H` into the paper, tilted
//!   by α towards β.
//! * Kinematics: [`DhParams`] (AUBO-i5 and UR5e, modified DH) and its [`Chain`], forward
//!   kinematics and a numerical inverse.
//! * The program: [`RobotConfig`] (`robot.json`), [`build_program`] → [`Program`], the writing
//!   program (travel, descend, press, lift, optional dipping), and the safety envelope checked
//!   before anything moves ([`CheckReport`]); [`time_program`] times it ([`ProgramTiming`]).
//! * [`Controller`]: the seam `maobi robot send` drives: prepare a checked program in a
//!   controller's form, connect and check before anything moves, run it with progress and a safe
//!   stop. Each controller lives in its own module.
//! * [`aubo`]: AUBO arms: the ARCS JSON-RPC client (the SDK's framed protocol with its login,
//!   line-delimited JSON, or HTTP), a fault-tolerant runner (reconnect, lift, resume) and the
//!   [`aubo::AuboRpc`] controller.
//! * [`ur`]: Universal Robots e-Series arms driven live: URScript on the script port, RTDE for
//!   progress and state, the dashboard server to stop ([`ur::UrArm`]).
//! * Exports: [`aubo_lua`] (ARCS Lua script), [`urscript`], [`gcode`], each read back by its
//!   parser ([`read_lua`], [`read_urscript`], [`read_gcode`]) before it is returned;
//!   [`export_program`] writes any of them ([`ExportFormat`]) from a [`Plan`].
//! * `track.json`: [`TrackFile`], its program built and checked ([`TrackFile::build_program`]),
//!   checked and timed ([`TrackFile::check`]), or placed on a plotter's level sheet
//!   ([`TrackFile::level_frame`]).
//! * The pure motion executor (no sockets): [`execute_program`] executes a program as the
//!   controller would move, sampled in time, tagged by stroke and ink dip
//!   ([`execute_program_tagged`]), and [`trace_to_states`] turns it back into brush states on the
//!   paper; [`level_frame_in_front`] is the level sheet in front of the arm; [`read_trace`]
//!   reads a simulator's trace file back.
//! * [`sim`]: loopback TCP simulators of the controllers for tests and dry runs.
//! * [`wire`]: the AUBO controller's wire formats (the SDK's frames, JSON text and login; lines;
//!   JSON-RPC over HTTP), the transports and the controller's ports.
//!
//! ```
//! use robot_io::{PaperFrame, brush_pose};
//! use brush_model::TrackPoint;
//! let paper = PaperFrame::level([0.4, 0.1, 0.02], [200.0, 200.0]);
//! let p = TrackPoint { x_mm: 50.0, y_mm: 20.0, h_mm: 15.0, alpha_rad: 0.0, beta_rad: 0.0 };
//! let pose = brush_pose(&paper, &p);
//! // 50 mm along +x, 20 mm along −y, 15 mm below the paper surface.
//! assert!((pose.0[0] - 0.45).abs() < 1e-12 && (pose.0[1] - 0.08).abs() < 1e-12 && (pose.0[2] - 0.005).abs() < 1e-12);
//! ```

#![warn(unreachable_pub)]

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`robot_io::brush_model::Press`).
pub use brush_model;
pub use nalgebra;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub mod aubo;
mod config;
mod controller;
mod exec;
mod export;
mod follow;
mod frame;
mod kinematics;
mod pose;
mod program;
pub mod sim;
mod timing;
mod trace;
mod track_file;
pub mod ur;
pub mod wire;

pub use config::{
    Approach, CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_SPEED_FRACTION,
    CONTROLLER_MAX_TCP_OFFSET_M, DWELL_SINK_MM, DipStation, InkStation, Limits, MAX_DWELL_S, MAX_INTERVAL_S,
    MAX_LIFT_MM, MAX_PAYLOAD_KG, MAX_STEP_LIMIT_MM, MIN_ACC, MIN_INTERVAL_S, MIN_JOINT_SPEED_RAD_S,
    MIN_LINEAR_SPEED_M_S, MIN_SPEED_FRACTION, PlotterConfig, Reload, RobotConfig, SettingError, Timing, YAxis,
    dip_plan, pressed_mm,
};
pub use controller::{Controller, Plan, Position, Preflight, Prepared, Progress, RunSummary, Watch, expected_seconds};
pub use exec::{
    HOME_JOINTS, IN_FRONT_M, MAX_SAMPLES_PER_MOVE, TRACE_STEP_M, TRACE_STEP_RAD, TRACE_STEP_S, TaggedEntry, TraceEntry,
    TraceKind, execute_program, execute_program_tagged, joint_motion, level_frame_in_front, line_motion,
    trace_to_states,
};
pub use export::{
    ArmKinematics, ExportFormat, ExportTarget, Exported, GCODE_MERGE_TOLERANCE_MM, GcodeStatement,
    KINEMATICS_TOLERANCE, MAX_COMMENT_CHARS, PROGRESS_VARIABLE, PointTimes, ReadMove, ReadPathBuffer, ReadProgram,
    URSCRIPT_FUNCTIONS, URSCRIPT_PROGRAM, URSCRIPT_PROGRESS_REGISTER, aubo_lua, aubo_lua_path_buffer, comment_text,
    export_program, gcode, gcode_chars, gcode_merge, point_times, read_gcode, read_lua, read_urscript, urscript,
    verify_gcode, verify_lua, verify_lua_path_buffer, verify_urscript,
};
pub use follow::{MAX_REACH_M, NEIGHBOURHOOD_M, ORIENTATION_TOLERANCE_RAD, POSE_TOLERANCE_M};
pub use frame::{
    MAX_RESIDUAL_MM, MAX_SHEET_MM, MAX_TOUCH_REACH_M, MIN_TOUCH_SPAN_MM, PaperFile, PaperFrame, TouchPoint,
};
pub use kinematics::{Chain, DhParams, JOINT_LIMIT_RAD, READY_JOINTS, UR_HOME_JOINTS};
pub use pose::{Pose, brush_pose, brush_rotation_in_paper, lifted_pose};
pub use program::{
    COMPACT_TOLERANCE_M, COMPACT_TOLERANCE_RAD, CheckReport, IN_PLACE_MM, MIN_DEEPEST_PRESS_FRACTION,
    MIN_TRACK_EXTENT_MM, Move, Program, StrokeProgram, build_program, build_program_chars, check_approach,
    check_blends, compact_program, tcp_iso,
};
pub use timing::{
    BRANCH_STEP_RAD, MAX_PIECE_M, MAX_STROKE_WAYPOINTS, MERGE_M, PATH_START_TOLERANCE_RAD, PATH_TOLERANCE_M,
    PATH_TOLERANCE_RAD, ProgramTiming, TURN_LENGTH_M, TimedStroke, pressed_path, time_program, time_program_from,
    time_stroke,
};
pub use trace::{Trace, read_trace};
pub use track_file::{TrackCheck, TrackFile};

use std::path::{Path, PathBuf};

use brush_model::ProfileError;
use thiserror::Error;

/// Errors of robot-io.
#[derive(Debug, Error)]
pub enum RobotError {
    /// A configuration file cannot be read.
    #[error("{}: cannot read", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A configuration file is not the JSON expected (serde's message, the source, names the
    /// field, line and column).
    #[error("{}: cannot parse", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        #[source]
        source: serde_json::Error,
    },
    /// A file is not a simulator trace ([`read_trace`]): `line` (from 1) names the sample's line
    /// when one is wrong, `source` the parser's error when there is one.
    #[error("{}{}: {message}", path.display(), line.map_or(String::new(), |l| format!(":{l}")))]
    Trace {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: Option<usize>,
        /// What is wrong.
        message: String,
        /// The parser's error.
        #[source]
        source: Option<serde_json::Error>,
    },
    /// A configuration value is invalid (`file` names the file, or the configuration when
    /// there is none).
    #[error("{}: {message}", file.display())]
    Config {
        /// The file.
        file: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A setting in `robot.json` is out of range (the source names the field and the value).
    #[error("{}: a setting is out of range", file.display())]
    Setting {
        /// The file.
        file: PathBuf,
        /// Which setting, and why.
        #[source]
        source: config::SettingError,
    },
    /// The brush profile in a track file is invalid.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// The program would leave the safety envelope; nothing was sent.
    #[error("refused{}{}: {reason}", stroke.map_or(String::new(), |s| format!(" at stroke {}", s + 1)), point.map_or(String::new(), |p| format!(", point {}", p + 1)))]
    Unsafe {
        /// Zero-based stroke index.
        stroke: Option<usize>,
        /// Zero-based point index within the stroke.
        point: Option<usize>,
        /// Why.
        reason: String,
    },
    /// The connection failed, was lost or closed (`context`: the address or the call).
    #[error("connection: {context}")]
    Io {
        /// What was being done: the address or the method called.
        context: String,
        /// The I/O error (a closed connection is [`std::io::ErrorKind::UnexpectedEof`]).
        #[source]
        source: std::io::Error,
    },
    /// A call did not answer in time.
    #[error("timeout waiting for {0}")]
    Timeout(String),
    /// The controller's answer is not valid JSON-RPC.
    #[error("protocol: {0}")]
    Protocol(String),
    /// The controller's answer is not JSON, or not the JSON the call expects.
    #[error("protocol: {context}")]
    BadJson {
        /// The method called and what was being read.
        context: String,
        /// The parser's error.
        #[source]
        source: serde_json::Error,
    },
    /// The byte stream is not in the transport's format (a frame without `SOF`, an unknown
    /// frame type, a length beyond the limit, a malformed HTTP message); the connection cannot
    /// be used further.
    #[error("framing: {0}")]
    Framing(String),
    /// The controller refused the login (or the user name cannot be sent).
    #[error("login as `{user}` refused: {message}")]
    Login {
        /// The user.
        user: String,
        /// Why.
        message: String,
    },
    /// A JSON-RPC `error` object.
    #[error("{method}: JSON-RPC error {code}: {message}")]
    Rpc {
        /// The method called.
        method: String,
        /// Error code.
        code: i64,
        /// Error message.
        message: String,
    },
    /// The controller returned a negative status.
    #[error("{method}: controller error code {code}")]
    Controller {
        /// The method called.
        method: String,
        /// The status.
        code: i64,
    },
    /// The controller does not behave as the runner commanded: a reported pose or joint
    /// position that is not finite, outside the workspace, or farther than the tolerance from
    /// what was commanded; motion the runner did not queue (another client?); or motion that
    /// does not finish in the time the queued moves need. Not a link fault: the run is not
    /// resumed. The message names what was reported, what was expected and by how much they
    /// differ.
    #[error("the controller disagrees with what was commanded: {0}")]
    UnexpectedState(String),
    /// The run was stopped on request (Ctrl-C).
    #[error("interrupted (Ctrl-C)")]
    Interrupted,
    /// Path-buffer waypoints would be computed from maobi's nominal AUBO-i5 parameters (the
    /// controller does not report its own, or nominal ones were asked for) and the caller did
    /// not accept that ([`aubo::RunOptions::accept_nominal_kinematics`]); nothing was moved.
    #[error(
        "refused: the joint waypoints would be computed from maobi's nominal AUBO-i5 parameters, not the arm's own ({reason}); nothing was moved"
    )]
    NominalKinematics {
        /// Why the nominal parameters would be used.
        reason: String,
    },
    /// The link kept failing: the retry budget per stroke or for the whole run is spent, or
    /// reconnecting failed `reconnect_attempts` times. The last fault is the source.
    #[error(
        "gave up on the flaky link at stroke {}: {faults_stroke} fault(s) on this stroke (at most {max_stroke}), {faults_total} in the run (at most {max_total}){}; last fault",
        stroke + 1,
        if *reconnect_attempts > 0 { format!(", then {reconnect_attempts} connection attempt(s) failed") } else { String::new() }
    )]
    GaveUp {
        /// Zero-based index of the stroke that could not be finished.
        stroke: usize,
        /// Faults while that stroke ran.
        faults_stroke: usize,
        /// The per-stroke budget.
        max_stroke: usize,
        /// Faults in the whole run.
        faults_total: usize,
        /// The budget for the whole run.
        max_total: usize,
        /// Failed reconnection attempts after the last fault (0: the budget was spent first).
        reconnect_attempts: usize,
        /// The last fault.
        #[source]
        last: Box<RobotError>,
    },
    /// A run on the controller ended before the program finished, after the brush may have
    /// moved; says how far it got and whether the brush was lifted to the safe height. The
    /// cause is the source.
    #[error(
        "stopped after {completed} of {total} strokes ({reconnects} reconnect(s)); {lift}{}",
        at.as_ref().map_or(String::new(), |p| format!("; last seen at {p}"))
    )]
    RunStopped {
        /// Why the run stopped.
        #[source]
        cause: Box<RobotError>,
        /// Strokes completed.
        completed: usize,
        /// Strokes in the program.
        total: usize,
        /// Reconnections made.
        reconnects: usize,
        /// Whether the brush is known to be at the safe height above the paper.
        lifted: bool,
        /// What the retreat did, in words.
        lift: String,
        /// Where the machine was last seen after the retreat (`None`: not known, or not trusted);
        /// boxed to keep the error small.
        at: Option<Box<Position>>,
    },
}

/// Reads and parses a JSON file; errors are [`RobotError::Read`] and [`RobotError::Json`]
/// naming the file.
pub(crate) fn load_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RobotError> {
    use std::io::Read;
    let read_err = |source| RobotError::Read { path: path.to_path_buf(), source };
    let mut text = String::new();
    let file = std::fs::File::open(path).map_err(read_err)?;
    // The size from the metadata first (nothing read), then a bounded read (a pipe or a device
    // has no size).
    let listed = file.metadata().map(|m| m.len()).unwrap_or(0);
    if listed <= MAX_FILE_BYTES {
        file.take(MAX_FILE_BYTES + 1).read_to_string(&mut text).map_err(read_err)?;
    }
    if listed > MAX_FILE_BYTES || text.len() as u64 > MAX_FILE_BYTES {
        return Err(RobotError::Config {
            file: path.to_path_buf(),
            message: format!("larger than {} MiB: not a paper, robot or track file maobi writes", MAX_FILE_BYTES >> 20),
        });
    }
    serde_json::from_str(&text).map_err(|source| RobotError::Json { path: path.to_path_buf(), source })
}

/// The largest `paper.json`, `robot.json` or `track.json` read, bytes (64 MiB: an A4 sheet's
/// track of 44 strokes is about 10 MiB).
pub const MAX_FILE_BYTES: u64 = 64 << 20;
