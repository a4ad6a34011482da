//! Program exporters: AUBO ARCS Lua script, Universal Robots URScript, and G-code for 3-axis
//! brush plotters.
//!
//! What is exported is what was checked. Text that reaches a program (the title) goes through
//! [`text::comment_text`], which leaves nothing in a comment that could end it or open another
//! one; numbers are printed in plain decimals with as many digits as it takes to read back
//! within 1e-9 (relative) of the checked value (lengths and angles: or within 1e-12 m or rad).
//! Then every exporter reads its own text back with the parser of [`parse`], which accepts
//! exactly the grammar the exporters write and nothing else, and compares what it read, move
//! by move, with the checked program (G-code: with the plotter moves made from the track);
//! any difference (an extra line, a statement out of place, a number that lost its value in
//! print) is an error, and no text is returned.

mod arm;
mod format;
mod lua;
mod parse;
mod text;
mod timed;

pub use arm::ArmKinematics;
pub use format::{ExportFormat, Exported, export_program};
pub use lua::{KINEMATICS_TOLERANCE, PROGRESS_VARIABLE};
pub(crate) use parse::read_urscript_named;
pub use parse::{
    GcodeStatement, ReadMove, ReadPathBuffer, ReadProgram, URSCRIPT_FUNCTIONS, URSCRIPT_PROGRAM,
    URSCRIPT_PROGRESS_REGISTER, read_gcode, read_lua, read_urscript,
};
pub use text::{ExportTarget, MAX_COMMENT_CHARS, comment_text};
pub use timed::{PointTimes, point_times};

use brush_model::Track;
use nalgebra::{UnitQuaternion, Vector3};

use crate::RobotError;
use crate::aubo::PATH_APPEND_WAYPOINTS;
use crate::kinematics::DhParams;
use crate::pose::Pose;
use crate::program::{DWELL_SINK_MM, IN_PLACE_MM, Move, Program, RobotConfig, StrokeProgram, dip_plan};
use crate::timing::{PATH_TOLERANCE_M, PATH_TOLERANCE_RAD, ProgramTiming, TimedStroke, pressed_path};
use parse::LUA_IK_ERROR;
use text::{LENGTH_FLOOR, close, num};

/// Largest rotation, rad, between a URScript rotation vector read back and the checked pose's
/// orientation (its components are printed within 1e-9 relative).
const ROTATION_TOL_RAD: f64 = 1e-8;

/// A length (m, mm) or an angle (rad) as the exporters print it.
fn len(v: f64) -> String {
    num(v, LENGTH_FLOOR)
}

/// A speed, acceleration, feed rate, blend radius or fraction as the exporters print it.
fn rate(v: f64) -> String {
    num(v, 0.0)
}

fn lens(v: &[f64]) -> String {
    v.iter().map(|x| len(*x)).collect::<Vec<_>>().join(", ")
}

/// A number as an error message shows it.
fn show(v: f64) -> String {
    if v == 0.0 || (1e-4..1e9).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// The refusal of an exported text that does not match what was checked.
fn mismatch(target: ExportTarget, stroke: Option<usize>, line: Option<usize>, reason: String) -> RobotError {
    let at = line.map_or(String::new(), |l| format!(", line {l}"));
    RobotError::Unsafe {
        stroke,
        point: None,
        reason: format!(
            "the exported {} program{at} does not match the checked program: {reason}; the export is refused",
            target.name()
        ),
    }
}

/// What an exported arm program must do at one step.
#[derive(Clone, Debug)]
enum Want {
    /// A move of the checked program.
    Move(Move),
    /// A URScript process move (`movep`) to a pressed point of the compacted stroke.
    Process { pose: Pose, a: f64, v: f64, blend_m: f64 },
    /// A stroke's pressed path as one path buffer (Lua).
    PathBuffer(Box<TimedStroke>),
    /// The count of finished strokes published after a stroke's lift.
    Progress(usize),
}

/// One entry of an arm plan: a comment line or a step with its stroke (`None`: the start).
#[derive(Clone, Debug)]
enum Entry {
    Comment(String),
    Step(Option<usize>, Want),
}

/// What an exported arm program must be: its settings and its steps in order.
struct ArmPlan {
    tcp_offset_m: f64,
    speed_fraction: f64,
    /// The kinematics a path-buffer program checks the controller's against.
    kinematics: Option<DhParams>,
    /// `pathBufferEval`'s joint acceleration and speed limits, rad/s², rad/s.
    eval_acc_speed: (f64, f64),
    /// The joints the controller solves the start pose near (Lua; `None`: where the arm is).
    start_qnear: Option<[f64; 6]>,
    entries: Vec<Entry>,
}

impl ArmPlan {
    fn steps(&self) -> impl Iterator<Item = (Option<usize>, &Want)> {
        self.entries.iter().filter_map(|e| match e {
            Entry::Step(s, w) => Some((*s, w)),
            Entry::Comment(_) => None,
        })
    }
}

/// The plan of `program`: the start, then per stroke its dip (after a comment `ink dip before
/// stroke N`), its approach (after `stroke N`), what `pressed` makes of its pressed moves, and
/// its lift; with `progress`, the count of finished strokes published first (0) and after each
/// lift.
fn arm_plan(
    program: &Program,
    progress: bool,
    mut pressed: impl FnMut(&StrokeProgram) -> Result<Vec<Want>, RobotError>,
) -> Result<ArmPlan, RobotError> {
    let mut entries = vec![];
    if progress {
        entries.push(Entry::Step(None, Want::Progress(0)));
    }
    entries.push(Entry::Step(None, Want::Move(program.start)));
    for st in &program.strokes {
        let at = Some(st.index);
        if !st.dip.is_empty() {
            entries.push(Entry::Comment(format!("ink dip before stroke {}", st.index + 1)));
            entries.extend(st.dip.iter().map(|m| Entry::Step(at, Want::Move(*m))));
        }
        entries.push(Entry::Comment(format!("stroke {}", st.index + 1)));
        entries.extend(st.approach.iter().map(|m| Entry::Step(at, Want::Move(*m))));
        entries.extend(pressed(st)?.into_iter().map(|w| Entry::Step(at, w)));
        entries.push(Entry::Step(at, Want::Move(st.lift)));
        if progress {
            entries.push(Entry::Step(at, Want::Progress(st.index + 1)));
        }
    }
    Ok(ArmPlan {
        tcp_offset_m: program.tcp_offset_m,
        speed_fraction: program.speed_fraction,
        kinematics: None,
        eval_acc_speed: (0.0, 0.0),
        start_qnear: None,
        entries,
    })
}

/// The plan of a move-per-point program: every move as it is.
fn moves_plan(program: &Program) -> ArmPlan {
    arm_plan(program, true, |st| Ok(st.press.iter().map(|m| Want::Move(*m)).collect())).expect("no step can fail")
}

/// A move as a Lua statement after `indent`; a joint move to a pose is solved near `qnear`
/// (rad), or near the joints the arm reports.
fn lua_move_text(m: &Move, indent: &str, qnear: Option<&[f64; 6]>) -> String {
    let near = qnear.map_or("getJointPositions()".to_string(), |q| format!("{{{}}}", lens(q)));
    match m {
        Move::Joint { q, a, v } => format!("{indent}moveJoint({{{}}}, {}, {}, 0, 0)\n", lens(q), rate(*a), rate(*v)),
        // The controller solves the joints (its Lua `inverseKinematics(qnear, pose) -> table,
        // int`), and the script stops (`error`) rather than move when it cannot; `do ... end`
        // keeps `q` and `ret` local.
        Move::JointPose { pose, a, v } => format!(
            "{indent}do\n{indent}  local q, ret = inverseKinematics({near}, {{{}}})\n{indent}  if type(q) ~= \"table\" or #q ~= 6 or (ret ~= nil and ret ~= 0) then error(\"{LUA_IK_ERROR}\") end\n{indent}  moveJoint(q, {}, {}, 0, 0)\n{indent}end\n",
            lens(&pose.0),
            rate(*a),
            rate(*v)
        ),
        Move::Line { pose, a, v, blend_m } => {
            format!("{indent}moveLine({{{}}}, {}, {}, {}, 0)\n", lens(&pose.0), rate(*a), rate(*v), rate(*blend_m))
        }
    }
}

/// The Lua text of a plan, in the form of AUBO's script documentation: `return function(api)`,
/// the robot's environment (`local _ENV = require('aubo').sched.select_robot(1)`), then the
/// robot's methods as globals (`setTcpOffset`, `moveLine(pose, a, v, blend_radius, duration)`, …).
fn lua_text(plan: &ArmPlan, title: &str, what: &str) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "-- maobi writing program: {}\n-- {what}. Generated; do not edit by hand.\n",
        comment_text(title, ExportTarget::Lua),
    ));
    let lines = |s: &mut String, v: Vec<String>| {
        for l in v {
            s.push_str(&l);
            s.push('\n');
        }
    };
    lines(&mut s, lua::head_lines());
    if let Some(k) = &plan.kinematics {
        s.push_str("  do\n");
        s.push_str(&lua::want_line(k));
        s.push('\n');
        lines(&mut s, lua::kinematics_check_lines());
    }
    s.push_str(&format!("  setTcpOffset({{0, 0, {}, 0, 0, 0}})\n", len(plan.tcp_offset_m)));
    s.push_str(&format!("  setSpeedFraction({})\n", rate(plan.speed_fraction)));
    // After a path buffer, the lift goes inside its block, then the buffer is freed.
    let mut open_block = false;
    for e in &plan.entries {
        match e {
            Entry::Comment(c) => s.push_str(&format!("  -- {c}\n")),
            Entry::Step(_, Want::Move(m)) if open_block => {
                s.push_str(&lua_move_text(m, "    ", None));
                lines(&mut s, lua::free_lines());
                open_block = false;
            }
            Entry::Step(_, Want::Move(m)) => s.push_str(&lua_move_text(m, "  ", plan.start_qnear.as_ref())),
            Entry::Step(_, Want::PathBuffer(t)) => {
                let (acc, speed) = plan.eval_acc_speed;
                s.push_str("  do\n");
                s.push_str(&lua::name_line(t.stroke));
                s.push('\n');
                s.push_str(&format!("    pathBufferAlloc(name, 2, {})\n", t.joints.len()));
                for piece in t.joints.chunks(PATH_APPEND_WAYPOINTS) {
                    s.push_str("    pathBufferAppend(name, {\n");
                    for q in piece {
                        s.push_str(&lua::waypoint_line(q));
                        s.push('\n');
                    }
                    s.push_str("    })\n");
                }
                s.push_str(&lua::eval_line(acc, speed, t.interval_s));
                s.push('\n');
                lines(&mut s, lua::valid_wait_lines());
                s.push_str(&lua::start_line(&t.joints[0]));
                s.push('\n');
                lines(&mut s, lua::start_check_lines());
                open_block = true;
            }
            Entry::Step(_, Want::Progress(k)) => {
                s.push_str(&lua::progress_line(*k));
                s.push('\n');
            }
            // Not in Lua plans.
            Entry::Step(_, Want::Process { .. }) => {}
        }
    }
    s.push_str("end\n");
    s
}

/// An ARCS Lua script in the form of AUBO's script documentation (`return function(api) local
/// _ENV = require('aubo').sched.select_robot(1) … end`, the robot's methods as globals) that sets
/// the tool offset and speed fraction and runs every move of `program`, one statement per move,
/// publishing the count of finished strokes (`setInt32("maobi_strokes", N)`) at the start and
/// after each lift. For a blending
/// controller give it a compacted program ([`crate::program::compact_program`], checked by
/// [`crate::program::check_blends`]); [`aubo_lua_path_buffer`] sends each pressed stroke as
/// one path buffer instead. The title goes, made inert ([`text::comment_text`]), into the
/// first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, aubo_lua, build_program, verify_lua, level_frame_in_front};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &profile, &frame, &RobotConfig::default()).unwrap();
/// let lua = aubo_lua(&program, "一 -- a title stays a comment").unwrap();
/// assert!(lua.contains("local _ENV = require('aubo').sched.select_robot(1)"));
/// // The text reads back as the checked program.
/// verify_lua(&lua, &program).unwrap();
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when the text, read back ([`parse::read_lua`]), does not match the
/// program (a number that cannot be printed so that it reads back as the checked value).
pub fn aubo_lua(program: &Program, title: &str) -> Result<String, RobotError> {
    let plan = moves_plan(program);
    let what = format!("{} strokes, {} moves", program.strokes.len(), program.move_count());
    let s = lua_text(&plan, title, &what);
    compare_arm(ExportTarget::Lua, &parse::read_lua(&s)?, &plan)?;
    Ok(s)
}

/// Checks an ARCS Lua script against the move-per-point program it should run: reads it back
/// ([`parse::read_lua`]) and compares the tool offset, the speed fraction and every move, in
/// order, with `program`'s.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not in the exporter's grammar, or the
/// first move (line, stroke, value) that differs from the program's.
pub fn verify_lua(text: &str, program: &Program) -> Result<(), RobotError> {
    compare_arm(ExportTarget::Lua, &parse::read_lua(text)?, &moves_plan(program))
}

/// The plan of a path-buffer Lua program: `program` timed on `kin` ([`crate::time_program`]),
/// each timed stroke's pressed moves replaced by its path buffer.
fn path_buffer_plan(program: &Program, kin: &DhParams, cfg: &RobotConfig) -> Result<ArmPlan, RobotError> {
    kin.validate().map_err(|why| RobotError::Unsafe {
        stroke: None,
        point: None,
        reason: format!("the arm's kinematics: {why}"),
    })?;
    let timing = crate::timing::time_program(program, kin, cfg)?;
    let tcp = program.tcp();
    let mut plan = arm_plan(program, true, |st| {
        let Some(t) = timing.strokes.iter().find(|t| t.stroke == st.index) else {
            return Ok(st.press.iter().map(|m| Want::Move(*m)).collect());
        };
        // The waypoints are this arm's: its forward kinematics keeps them on the path.
        for (k, (q, pose)) in t.joints.iter().zip(&t.poses).enumerate() {
            let got = kin.forward(q, &tcp);
            let want = pose.to_iso();
            let dm = (got.translation.vector - want.translation.vector).norm();
            let dr = got.rotation.angle_to(&want.rotation);
            if !(dm <= PATH_TOLERANCE_M && dr <= PATH_TOLERANCE_RAD) {
                return Err(RobotError::Unsafe {
                    stroke: Some(st.index),
                    point: None,
                    reason: format!(
                        "waypoint {k} of the path buffer lies {:.4} mm and {dr:.5} rad from the path on the arm's kinematics",
                        dm * 1e3
                    ),
                });
            }
        }
        Ok(vec![Want::PathBuffer(Box::new(t.clone()))])
    })?;
    plan.kinematics = Some(*kin);
    plan.eval_acc_speed = (cfg.limits.max_joint_acc_rad_s2, cfg.limits.max_joint_speed_rad_s);
    // The controller solves the start near the first waypoint, so the arm reaches the first
    // stroke on the branch its waypoints were computed on.
    plan.start_qnear = timing.strokes.first().map(|t| t.joints[0]);
    Ok(plan)
}

/// An ARCS Lua script that writes each pressed stroke as one path buffer of joint waypoints,
/// as `robot send` does: the stroke timed on the arm `kin` ([`crate::time_program`]: waypoints
/// every `timing.interval_s`), `pathBufferAlloc(name, 2, n)` (type 2: a cubic spline through
/// waypoints at a fixed interval), `pathBufferAppend` in pieces of
/// [`PATH_APPEND_WAYPOINTS`], `pathBufferEval` with `limits.max_joint_acc_rad_s2` and
/// `max_joint_speed_rad_s`, `pathBufferValid` polled (at most 5 s), the arm's joints checked
/// within [`crate::timing::PATH_START_TOLERANCE_RAD`] of the first waypoint, `movePathBuffer`,
/// the lift, `pathBufferFree`. The dips, approaches and lifts stay `moveLine`s and the first
/// move a joint move to a pose the controller solves.
///
/// `kin` must be the arm's own parameters (`RobotConfig.getKinematicsParam(true)`, saved by
/// `maobi robot kinematics`): the script carries them, reads the controller's before
/// anything moves, and stops (`error`) if any differs by more than [`KINEMATICS_TOLERANCE`]
/// (or reports a `beta` other than zeros), so joints computed on other parameters (the
/// nominal ones) never move an arm. It needs the controller's `sched.sleep` (AUBO's Lua
/// examples bind `sleep` from it) and stops before anything moves without it.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{aubo_lua_path_buffer, verify_lua_path_buffer};
/// use robot_io::DhParams;
/// use robot_io::{RobotConfig, build_program, level_frame_in_front};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// // The nominal i5 here; a real arm's parameters come from its controller.
/// let lua = aubo_lua_path_buffer(&program, &DhParams::AUBO_I5, &cfg, "一").unwrap();
/// assert!(lua.contains("pathBufferAlloc(name, 2, ") && lua.contains("getKinematicsParam(true)"));
/// verify_lua_path_buffer(&lua, &program, &DhParams::AUBO_I5, &cfg).unwrap();
/// ```
///
/// # Errors
/// As [`crate::time_program`] (a stroke the arm cannot follow within the limits);
/// [`RobotError::Unsafe`] when `kin` is not finite or in range, or the text, read back
/// ([`parse::read_lua`]), does not match the plan.
pub fn aubo_lua_path_buffer(
    program: &Program,
    kin: &DhParams,
    cfg: &RobotConfig,
    title: &str,
) -> Result<String, RobotError> {
    let plan = path_buffer_plan(program, kin, cfg)?;
    let buffers = plan.steps().filter(|(_, w)| matches!(w, Want::PathBuffer(_))).count();
    let moves = plan.steps().filter(|(_, w)| matches!(w, Want::Move(_))).count();
    let what = format!("{} strokes, {buffers} path buffers, {moves} moves", program.strokes.len());
    let s = lua_text(&plan, title, &what);
    compare_arm(ExportTarget::Lua, &parse::read_lua(&s)?, &plan)?;
    Ok(s)
}

/// Checks a path-buffer ARCS Lua script ([`aubo_lua_path_buffer`]) against the program it
/// should run, timed again on `kin`: the kinematics it checks, every move and every path
/// buffer (name, size, waypoints, limits, interval, the joints checked before it moves).
///
/// # Errors
/// As [`aubo_lua_path_buffer`]; [`RobotError::Unsafe`] naming the first line that differs.
pub fn verify_lua_path_buffer(
    text: &str,
    program: &Program,
    kin: &DhParams,
    cfg: &RobotConfig,
) -> Result<(), RobotError> {
    compare_arm(ExportTarget::Lua, &parse::read_lua(text)?, &path_buffer_plan(program, kin, cfg)?)
}

/// The tool speed of a URScript process move shorter than [`IN_PLACE_MM`] (one that only
/// turns the brush: no length to divide by its time), m/s.
const TURN_PROCESS_SPEED_M_S: f64 = 1e-3;

/// The plan of a URScript program: each stroke's pressed moves compacted
/// ([`crate::program::compact_program`], blends checked), each a `movep` at the timed
/// stroke's mean speed over it.
fn urscript_plan(program: &Program, timing: &ProgramTiming, cfg: &RobotConfig) -> Result<ArmPlan, RobotError> {
    let times = point_times(program, timing)?;
    let compact = crate::program::compact_program(program, cfg);
    crate::program::check_blends(&compact)?;
    let originals: Vec<Vec<Pose>> = program.strokes.iter().map(pressed_path).collect();
    let mut k = 0;
    arm_plan(&compact, true, |st| {
        let path = &originals[k];
        let t = times.strokes.get(st.index).and_then(Option::as_ref);
        k += 1;
        let mut at = 0;
        let mut out = Vec::with_capacity(st.press.len());
        for m in &st.press {
            let Move::Line { pose, a, v, blend_m } = *m else {
                out.push(Want::Move(*m));
                continue;
            };
            let from = at;
            // The compacted move ends at one of the stroke's own points, after the last.
            at = (at + 1..path.len()).find(|&i| path[i] == pose).ok_or_else(|| RobotError::Unsafe {
                stroke: Some(st.index),
                point: None,
                reason: "a compacted move ends off the stroke's points".into(),
            })?;
            let speed = match t {
                Some(t) => {
                    let d = (Vector3::from(path[at].position()) - Vector3::from(path[from].position())).norm();
                    let dt = t[at] - t[from];
                    if d * 1000.0 < IN_PLACE_MM {
                        TURN_PROCESS_SPEED_M_S.min(v)
                    } else if dt > 0.0 {
                        (d / dt).min(v)
                    } else {
                        v
                    }
                }
                None => v,
            };
            out.push(Want::Process { pose, a, v: speed, blend_m });
        }
        Ok(out)
    })
}

/// A URScript program, one `def maobi_program(): … end` as a UR controller runs it when it
/// arrives on its script port: the tool (`set_tcp`), the first move a `movej` to a pose (the
/// controller solves it), travel, dips, descents and lifts `movel`, and each pressed stroke as
/// `movep` process moves (constant tool speed, blended) over its compacted points
/// ([`crate::program::compact_program`]: every blend radius at most half the shorter of the
/// two moves it joins, checked by [`crate::program::check_blends`], so neighbouring blends never
/// overlap as UR's rule requires), each at the mean tool speed `timing` gives the stroke over
/// that move (so it slows where the timed stroke slows). Arguments after the target are named in
/// UR's order (`a`, `v`, `t=0`, `r`). The count of finished strokes goes into output integer
/// register 24 ([`parse::URSCRIPT_PROGRESS_REGISTER`]) at the start (0) and after each lift, for
/// a client following the run over RTDE. No joint angle is exported: `timing` only gives the
/// speeds. The title goes, made inert ([`text::comment_text`]), into the first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::DhParams;
/// use robot_io::{RobotConfig, build_program, verify_urscript, level_frame_in_front, time_program, urscript};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let timing = time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap();
/// let script = urscript(&program, &timing, &cfg, "一").unwrap();
/// // A straight stroke is one process move.
/// assert_eq!(script.matches("movep(p[").count(), 1);
/// verify_urscript(&script, &program, &timing, &cfg).unwrap();
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when `timing` is not `program`'s, a blend is invalid, or the text,
/// read back ([`parse::read_urscript`]), does not match the plan.
pub fn urscript(
    program: &Program,
    timing: &ProgramTiming,
    cfg: &RobotConfig,
    title: &str,
) -> Result<String, RobotError> {
    let plan = urscript_plan(program, timing, cfg)?;
    let s = urscript_text(&plan, title, parse::URSCRIPT_PROGRAM);
    compare_arm(ExportTarget::UrScript, &parse::read_urscript(&s)?, &plan)?;
    Ok(s)
}

/// The URScript text of a plan: `def <name>():`, the tool, the steps, `end`.
fn urscript_text(plan: &ArmPlan, title: &str, name: &str) -> String {
    let mut s = format!("# maobi writing program: {}\ndef {name}():\n", comment_text(title, ExportTarget::UrScript));
    s.push_str(&format!("  set_tcp(p[0, 0, {}, 0, 0, 0])\n", len(plan.tcp_offset_m)));
    let pose_text = |pose: &Pose| format!("p[{}, {}]", lens(&pose.position()), lens(&pose.rotation_vector()));
    // UR's argument orders: movej(q, a, v, t, r), movel(pose, a, v, t, r), movep(pose, a, v, r);
    // every argument after the target named, t=0 (the speed decides the time).
    for e in &plan.entries {
        match e {
            Entry::Comment(c) => s.push_str(&format!("  # {c}\n")),
            Entry::Step(_, Want::Move(Move::Joint { q, a, v })) => {
                s.push_str(&format!("  movej([{}], a={}, v={}, t=0, r=0)\n", lens(q), rate(*a), rate(*v)))
            }
            // A pose target: the UR controller solves the joints.
            Entry::Step(_, Want::Move(Move::JointPose { pose, a, v })) => {
                s.push_str(&format!("  movej({}, a={}, v={}, t=0, r=0)\n", pose_text(pose), rate(*a), rate(*v)))
            }
            Entry::Step(_, Want::Move(Move::Line { pose, a, v, blend_m })) => s.push_str(&format!(
                "  movel({}, a={}, v={}, t=0, r={})\n",
                pose_text(pose),
                rate(*a),
                rate(*v),
                rate(*blend_m)
            )),
            Entry::Step(_, Want::Process { pose, a, v, blend_m }) => s.push_str(&format!(
                "  movep({}, a={}, v={}, r={})\n",
                pose_text(pose),
                rate(*a),
                rate(*v),
                rate(*blend_m)
            )),
            Entry::Step(_, Want::Progress(k)) => {
                s.push_str(&format!("  write_output_integer_register({}, {k})\n", parse::URSCRIPT_PROGRESS_REGISTER))
            }
            // Not in URScript plans.
            Entry::Step(_, Want::PathBuffer(_)) => {}
        }
    }
    s.push_str("end\n");
    s
}

/// A URScript program that lifts the brush from `from` straight out of the paper to `to` (a
/// stopped run's retreat: `def maobi_lift():`, the tool, one `movel` at `v`, `a`), checked as
/// written.
///
/// # Errors
/// [`RobotError::Unsafe`] when the text does not read back as that move.
pub(crate) fn urscript_lift(tcp_offset_m: f64, to: &Pose, a: f64, v: f64) -> Result<String, RobotError> {
    let plan = ArmPlan {
        tcp_offset_m,
        speed_fraction: 1.0,
        kinematics: None,
        eval_acc_speed: (0.0, 0.0),
        start_qnear: None,
        entries: vec![Entry::Step(None, Want::Move(Move::Line { pose: *to, a, v, blend_m: 0.0 }))],
    };
    let s = urscript_text(&plan, "lift", "maobi_lift");
    let read =
        parse::read_urscript_named(&s, "maobi_lift").map_err(|at| parse::refused(ExportTarget::UrScript, None, at))?;
    compare_arm(ExportTarget::UrScript, &read, &plan)?;
    Ok(s)
}

/// Checks a URScript program against the program it should run, as [`urscript`] plans it
/// (rotation vectors are compared as rotations, within 1e-8 rad).
///
/// # Errors
/// As [`urscript`]; [`RobotError::Unsafe`] naming the first line that differs.
pub fn verify_urscript(
    text: &str,
    program: &Program,
    timing: &ProgramTiming,
    cfg: &RobotConfig,
) -> Result<(), RobotError> {
    compare_arm(ExportTarget::UrScript, &parse::read_urscript(text)?, &urscript_plan(program, timing, cfg)?)
}

fn compare_arm(target: ExportTarget, read: &ReadProgram, plan: &ArmPlan) -> Result<(), RobotError> {
    if !close(read.tcp_offset_m, plan.tcp_offset_m, LENGTH_FLOOR) {
        return Err(mismatch(
            target,
            None,
            None,
            format!("the tool offset reads {} m where it is {} m", show(read.tcp_offset_m), show(plan.tcp_offset_m)),
        ));
    }
    if let Some(f) = read.speed_fraction.filter(|&f| !close(f, plan.speed_fraction, 0.0)) {
        return Err(mismatch(
            target,
            None,
            None,
            format!("the speed fraction reads {} where it is {}", show(f), show(plan.speed_fraction)),
        ));
    }
    match (&read.kinematics, &plan.kinematics) {
        (None, None) => {}
        (Some(r), Some(w)) => {
            let rows = [("a", &r.a_m, &w.a_m), ("alpha", &r.alpha_rad, &w.alpha_rad), ("d", &r.d_m, &w.d_m)];
            let rows = rows.into_iter().chain([("theta", &r.theta_rad, &w.theta_rad)]);
            for (name, r, w) in rows {
                for (k, (r, w)) in r.iter().zip(w).enumerate() {
                    same(&format!("{name}[{k}]"), *r, *w, LENGTH_FLOOR)
                        .map_err(|e| mismatch(target, None, None, format!("the kinematics checked: {e}")))?;
                }
            }
        }
        (r, _) => {
            let has = |b: bool| if b { "checks" } else { "does not check" };
            return Err(mismatch(
                target,
                None,
                None,
                format!(
                    "the text {} the controller's kinematics where the plan {}",
                    has(r.is_some()),
                    has(plan.kinematics.is_some())
                ),
            ));
        }
    }
    let want: Vec<_> = plan.steps().collect();
    for (i, ((line, got), (stroke, w))) in read.moves.iter().zip(&want).enumerate() {
        compare_step(target, got, w, read, plan)
            .map_err(|r| mismatch(target, *stroke, Some(*line), format!("move {}: {r}", i + 1)))?;
    }
    if read.moves.len() != want.len() {
        let line = read.moves.get(want.len()).map(|m| m.0);
        return Err(mismatch(
            target,
            None,
            line,
            format!("the text has {} moves where the program has {}", read.moves.len(), want.len()),
        ));
    }
    Ok(())
}

fn same(what: &str, read: f64, want: f64, floor: f64) -> Result<(), String> {
    if close(read, want, floor) {
        Ok(())
    } else {
        Err(format!("{what} reads {} where it is {}", show(read), show(want)))
    }
}

fn compare_step(
    target: ExportTarget,
    read: &ReadMove,
    want: &Want,
    program: &ReadProgram,
    plan: &ArmPlan,
) -> Result<(), String> {
    match (read, want) {
        (ReadMove::Joint { q, a, v }, Want::Move(Move::Joint { q: wq, a: wa, v: wv })) => {
            for (k, (r, w)) in q.iter().zip(wq).enumerate() {
                same(&format!("joint {}", k + 1), *r, *w, LENGTH_FLOOR)?;
            }
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)
        }
        (ReadMove::JointPose { target: t, a, v, qnear }, Want::Move(Move::JointPose { pose, a: wa, v: wv })) => {
            match (qnear, plan.start_qnear) {
                (None, None) => {}
                (Some(r), Some(w)) => {
                    for j in 0..6 {
                        same(
                            &format!("the joints the start is solved near, joint {}", j + 1),
                            r[j],
                            w[j],
                            LENGTH_FLOOR,
                        )?;
                    }
                }
                _ => return Err("the start is solved near other joints than the plan's".into()),
            }
            same_pose(target, t, pose)?;
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)
        }
        (ReadMove::Line { target: t, a, v, blend_m }, Want::Move(Move::Line { pose, a: wa, v: wv, blend_m: wb }))
        | (ReadMove::Process { target: t, a, v, blend_m }, Want::Process { pose, a: wa, v: wv, blend_m: wb }) => {
            same_pose(target, t, pose)?;
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)?;
            same("the blend radius", *blend_m, *wb, 0.0)
        }
        (ReadMove::PathBuffer { buffer }, Want::PathBuffer(t)) => {
            let b = program.path_buffers.get(*buffer).ok_or("a path buffer that was not read")?;
            let name = lua::buffer_name(t.stroke);
            if b.name != name {
                return Err(format!("the path buffer is named `{}` where it is `{name}`", b.name));
            }
            if b.size != t.joints.len() || b.waypoints.len() != t.joints.len() {
                return Err(format!(
                    "the path buffer has {} waypoints (allocated {}) where the timed stroke has {}",
                    b.waypoints.len(),
                    b.size,
                    t.joints.len()
                ));
            }
            for (k, (r, w)) in b.waypoints.iter().zip(&t.joints).enumerate() {
                for j in 0..6 {
                    same(&format!("waypoint {k}, joint {}", j + 1), r[j], w[j], LENGTH_FLOOR)?;
                }
            }
            for j in 0..6 {
                same(
                    &format!("the first waypoint checked, joint {}", j + 1),
                    b.start_q[j],
                    t.joints[0][j],
                    LENGTH_FLOOR,
                )?;
                same("the joint acceleration limit", b.acc_rad_s2[j], plan.eval_acc_speed.0, 0.0)?;
                same("the joint speed limit", b.speed_rad_s[j], plan.eval_acc_speed.1, 0.0)?;
            }
            same("the waypoint interval", b.interval_s, t.interval_s, 0.0)
        }
        (ReadMove::Progress { strokes }, Want::Progress(w)) if strokes == w => Ok(()),
        (ReadMove::Progress { strokes }, Want::Progress(w)) => {
            Err(format!("the progress register reads {strokes} strokes where it is {w}"))
        }
        _ => Err(format!("{} where the program has {}", read_kind(read), want_kind(want))),
    }
}

fn read_kind(m: &ReadMove) -> &'static str {
    match m {
        ReadMove::Joint { .. } => "a joint move to joints",
        ReadMove::JointPose { .. } => "a joint move to a pose",
        ReadMove::Line { .. } => "a line move",
        ReadMove::Process { .. } => "a process move",
        ReadMove::PathBuffer { .. } => "a path buffer",
        ReadMove::Progress { .. } => "the progress register",
    }
}

fn want_kind(m: &Want) -> &'static str {
    match m {
        Want::Move(Move::Joint { .. }) => "a joint move to joints",
        Want::Move(Move::JointPose { .. }) => "a joint move to a pose",
        Want::Move(Move::Line { .. }) => "a line move",
        Want::Process { .. } => "a process move",
        Want::PathBuffer(_) => "a path buffer",
        Want::Progress(_) => "the progress register",
    }
}

/// A pose read back (Lua: `[x, y, z, rx, ry, rz]`; URScript: position and rotation vector)
/// against the checked pose.
fn same_pose(target: ExportTarget, read: &[f64; 6], want: &Pose) -> Result<(), String> {
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        same(name, read[k], want.0[k], LENGTH_FLOOR)?;
    }
    if target == ExportTarget::UrScript {
        let r = UnitQuaternion::from_scaled_axis(Vector3::new(read[3], read[4], read[5]));
        let angle = r.angle_to(&want.to_iso().rotation);
        if !(angle <= ROTATION_TOL_RAD) {
            return Err(format!("the orientation is {} rad away from the checked one", show(angle)));
        }
        return Ok(());
    }
    for (k, name) in ["rx", "ry", "rz"].iter().enumerate() {
        same(name, read[k + 3], want.0[k + 3], LENGTH_FLOOR)?;
    }
    Ok(())
}

/// How far a point left out of a merged G-code move may lie from it, mm (in X, Y and Z
/// together, so the depth too).
pub const GCODE_MERGE_TOLERANCE_MM: f64 = 0.05;
/// Most track points one merged G-code move may stand for.
const GCODE_MAX_SPAN: usize = 2000;

/// G-code for a 3-axis brush plotter working in paper millimetres (GRBL-style): `G21`
/// (millimetres), `G90` (absolute), work coordinates with their zero at the paper's top-left
/// corner where the tip touches: X = the paper's x, Y = −y (`robot.json` `plotter.y_axis`
/// `away`, the default: the machine's +Y runs up the page) or y (`toward`), Z = −H (positive
/// up), `G0` travel at `lift_mm`, `G1` writing. Each stroke's pressed points are
/// merged into straight moves (every point left out within [`GCODE_MERGE_TOLERANCE_MM`] of
/// its move; no move shorter than [`IN_PLACE_MM`]), each with its own feed rate F (mm/min):
/// its length over the time the timed stroke takes between its ends (`times`, from
/// [`point_times`]), so the plotter slows where the timed stroke slows; a stroke without a
/// timing is fed at `write_speed_m_s`. Tilt α and direction β cannot be expressed and are
/// ignored; the returned warnings say so. Ink dips (robot.json `ink` with `paper_mm`) go to
/// the pot, down `depth_mm` below the paper plane, soak (sink `DWELL_SINK_MM` further over
/// `dwell_s`, as the arm programs do) and back up, before the strokes the reload rule picks.
/// The title goes, made inert ([`text::comment_text`]), into the first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::point_times;
/// use robot_io::DhParams;
/// use robot_io::{RobotConfig, build_program, gcode, level_frame_in_front, time_program};
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let (profile, cfg) = (BrushProfile::builtin("pen1").unwrap(), RobotConfig::default());
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let times = point_times(&program, &time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap()).unwrap();
/// let (text, _warnings) = gcode(&track, &times, &cfg, "一").unwrap();
/// assert!(text.starts_with("; maobi writing program: 一"));
/// // The press is Z = −H: 3 mm below the touching plane; the straight stroke is one move
/// // after the descent, slower than the write speed on average (it starts and ends at rest).
/// let g1: Vec<&str> = text.lines().filter(|l| l.starts_with("G1 X")).collect();
/// assert_eq!(g1.len(), 2);
/// assert!(g1[1].starts_with("G1 X50.000000 Y-60.000000 Z-3.000000 F") && !g1[1].ends_with("F1200.000000"));
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when `times` does not fit the track (another number of strokes or
/// points), or the text, read back ([`parse::read_gcode`]), does not match the moves made
/// from the track (a value that is not finite or cannot be printed so that it reads back as
/// itself).
pub fn gcode(
    track: &Track,
    times: &PointTimes,
    cfg: &RobotConfig,
    title: &str,
) -> Result<(String, Vec<String>), RobotError> {
    gcode_chars(track, None, times, cfg, title)
}

/// [`gcode`] with the track's character boundaries (`stroke_chars`, for the reload rule
/// `before_each_char`).
///
/// # Examples
/// ```
/// use robot_io::brush_model::{Stroke, Track, TrackPoint};
/// use robot_io::PointTimes;
/// use robot_io::{RobotConfig, gcode, gcode_chars};
/// let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let stroke = |y: f64| Stroke { points: (0..=20).map(|i| pt(30.0 + f64::from(i), y)).collect() };
/// // Two characters of one stroke each, not timed (fed at the write speed).
/// let track = Track { strokes: vec![stroke(40.0), stroke(80.0)] };
/// let (cfg, times) = (RobotConfig::default(), PointTimes { strokes: vec![None, None] });
/// let (text, _) = gcode_chars(&track, Some(&[0, 1]), &times, &cfg, "一一").unwrap();
/// // Without an ink station the boundaries change nothing.
/// assert_eq!(text, gcode(&track, &times, &cfg, "一一").unwrap().0);
/// ```
///
/// # Errors
/// As [`gcode`].
pub fn gcode_chars(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    times: &PointTimes,
    cfg: &RobotConfig,
    title: &str,
) -> Result<(String, Vec<String>), RobotError> {
    let (plan, warnings) = gcode_plan(track, stroke_chars, times, cfg)?;
    let mut s = format!("; maobi writing program: {}\n", comment_text(title, ExportTarget::Gcode));
    for l in &plan {
        match (&l.statement, &l.comment) {
            (Some(st), Some(c)) => s.push_str(&format!("{} ; {c}\n", gcode_statement(st))),
            (Some(st), None) => s.push_str(&format!("{}\n", gcode_statement(st))),
            (None, Some(c)) => s.push_str(&format!("; {c}\n")),
            (None, None) => {}
        }
    }
    compare_gcode(&s, &plan)?;
    Ok((s, warnings))
}

/// Checks G-code against the plotter moves made from `track`, `times` and `cfg` (as
/// [`gcode_chars`] makes them): reads it back ([`parse::read_gcode`]) and compares every
/// statement, in order.
///
/// # Errors
/// As [`gcode`]; [`RobotError::Unsafe`] naming the first line that is not in the exporter's
/// grammar, or the first statement (line, stroke, value) that differs.
pub fn verify_gcode(
    text: &str,
    track: &Track,
    stroke_chars: Option<&[usize]>,
    times: &PointTimes,
    cfg: &RobotConfig,
) -> Result<(), RobotError> {
    compare_gcode(text, &gcode_plan(track, stroke_chars, times, cfg)?.0)
}

/// The points of a stroke a merged G-code program keeps (indices, the first and the last
/// always): a move runs on while every point it leaves out lies within
/// [`GCODE_MERGE_TOLERANCE_MM`] of it (X, Y, Z); a point within [`IN_PLACE_MM`] of the one
/// kept before it is left out (the last one takes its place).
pub fn gcode_merge(points: &[[f64; 3]]) -> Vec<usize> {
    let n = points.len();
    if n < 2 {
        return (0..n).collect();
    }
    let v = |i: usize| Vector3::from(points[i]);
    let covers = |a: usize, b: usize| {
        let (pa, ab) = (v(a), v(b) - v(a));
        let len2 = ab.norm_squared();
        (a + 1..b).all(|i| {
            let f = if len2 > 0.0 { ((v(i) - pa).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
            (pa + ab * f - v(i)).norm() <= GCODE_MERGE_TOLERANCE_MM
        })
    };
    let mut keep = vec![0];
    let mut a = 0;
    while a < n - 1 {
        let mut b = a + 1;
        while b + 1 < n && b + 1 - a <= GCODE_MAX_SPAN && covers(a, b + 1) {
            b += 1;
        }
        let kept = *keep.last().expect("the first point");
        if (v(b) - v(kept)).norm() >= IN_PLACE_MM {
            keep.push(b);
        } else if b == n - 1 && keep.len() > 1 {
            // The last point coincides with the one kept before it: end there.
            keep.pop();
            keep.push(b);
        }
        a = b;
    }
    keep
}
/// One line of the G-code to write: a statement, a comment, or both.
struct GcodeLine {
    statement: Option<GcodeStatement>,
    comment: Option<String>,
    /// The stroke the line belongs to.
    stroke: Option<usize>,
}

fn gcode_statement(st: &GcodeStatement) -> String {
    match st {
        GcodeStatement::Millimetres => "G21".into(),
        GcodeStatement::Absolute => "G90".into(),
        GcodeStatement::End => "M2".into(),
        GcodeStatement::Move { rapid, x_mm, y_mm, z_mm, f_mm_min } => {
            let mut s = String::from(if *rapid { "G0" } else { "G1" });
            for (letter, v, floor) in
                [("X", x_mm, LENGTH_FLOOR), ("Y", y_mm, LENGTH_FLOOR), ("Z", z_mm, LENGTH_FLOOR), ("F", f_mm_min, 0.0)]
            {
                if let Some(v) = v {
                    s.push_str(&format!(" {letter}{}", num(*v, floor)));
                }
            }
            s
        }
    }
}

/// The plotter program for a track (without the title comment), and the warnings.
fn gcode_plan(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    times: &PointTimes,
    cfg: &RobotConfig,
) -> Result<(Vec<GcodeLine>, Vec<String>), RobotError> {
    let refuse = |stroke: Option<usize>, reason: String| RobotError::Unsafe { stroke, point: None, reason };
    if times.strokes.len() > track.strokes.len() {
        return Err(refuse(
            None,
            format!("{} timed strokes for a track of {} strokes", times.strokes.len(), track.strokes.len()),
        ));
    }
    for (i, (st, t)) in track.strokes.iter().zip(&times.strokes).enumerate() {
        if let Some(t) = t
            && (t.len() != st.points.len() || t.windows(2).any(|w| !(w[1] >= w[0])) || !t.iter().all(|x| x.is_finite()))
        {
            return Err(refuse(
                Some(i),
                format!(
                    "the times of {} points for a stroke of {} points, or not increasing",
                    t.len(),
                    st.points.len()
                ),
            ));
        }
    }
    let mut warnings = Vec::new();
    let station = cfg.station();
    let dips = match (&station, station.and_then(|s| s.paper_mm)) {
        (Some(st), Some(_)) => match dip_plan(track, stroke_chars, st) {
            Ok(d) => d,
            Err(e) => {
                warnings.push(format!("no ink dips in the G-code: {e}"));
                vec![false; track.strokes.len()]
            }
        },
        (Some(_), None) => {
            warnings.push(
                "robot.json ink.paper_mm (where the plotter finds the ink, paper mm) is not set: the G-code has no ink dips"
                    .into(),
            );
            vec![false; track.strokes.len()]
        }
        _ => vec![false; track.strokes.len()],
    };
    if track.points().any(|p| p.alpha_rad.abs() > 1e-9) {
        warnings.push("G-code has no tilt axis: α is ignored".to_string());
    }
    warnings.push("G-code has no brush rotation axis: β is ignored".to_string());
    let ya = cfg.plotter.y_axis;
    let write_f = cfg.write_speed_m_s * 60_000.0;
    let travel_f = cfg.travel_speed_m_s * 60_000.0;
    let mv = |rapid: bool, x_mm: Option<f64>, y_mm: Option<f64>, z_mm: Option<f64>, f_mm_min: Option<f64>| {
        GcodeStatement::Move { rapid, x_mm, y_mm, z_mm, f_mm_min }
    };
    let mut out = Vec::new();
    let mut push = |statement, comment: Option<String>, stroke| out.push(GcodeLine { statement, comment, stroke });
    push(Some(GcodeStatement::Millimetres), Some("millimetres".into()), None);
    push(Some(GcodeStatement::Absolute), Some("absolute".into()), None);
    let up = mv(true, None, None, Some(cfg.lift_mm), None);
    push(Some(up), None, None);
    for (i, st) in track.strokes.iter().enumerate() {
        let Some(first) = st.points.first() else { continue };
        if let (true, Some(st)) = (dips[i], station) {
            let [x, y] = st.paper_mm.unwrap_or([0.0, 0.0]);
            push(None, Some(format!("ink dip before stroke {}", i + 1)), Some(i));
            push(Some(mv(true, Some(x), Some(ya.y(y)), None, Some(travel_f))), None, Some(i));
            push(Some(mv(false, None, None, Some(-st.depth_mm), Some(travel_f * 0.5))), None, Some(i));
            if st.dwell_s > 0.0 {
                let soak_f = DWELL_SINK_MM / st.dwell_s * 60.0;
                let soak = mv(false, None, None, Some(-st.depth_mm - DWELL_SINK_MM), Some(soak_f));
                push(Some(soak), Some(comment_text(&format!("dwell {} s", st.dwell_s), ExportTarget::Gcode)), Some(i));
            }
            push(Some(up), None, Some(i));
        }
        push(None, Some(format!("stroke {}", i + 1)), Some(i));
        push(Some(mv(true, Some(first.x_mm), Some(ya.y(first.y_mm)), None, Some(travel_f))), None, Some(i));
        // The descent onto the first point at the write speed, then the merged moves.
        push(
            Some(mv(false, Some(first.x_mm), Some(ya.y(first.y_mm)), Some(-first.h_mm), Some(write_f))),
            None,
            Some(i),
        );
        let xyz: Vec<[f64; 3]> = st.points.iter().map(|p| [p.x_mm, ya.y(p.y_mm), -p.h_mm]).collect();
        let t = times.strokes.get(i).and_then(Option::as_ref);
        let keep = gcode_merge(&xyz);
        for w in keep.windows(2) {
            let (a, b) = (w[0], w[1]);
            let f = match t {
                Some(t) => {
                    let d_mm = (Vector3::from(xyz[b]) - Vector3::from(xyz[a])).norm();
                    60.0 * d_mm / (t[b] - t[a])
                }
                None => write_f,
            };
            if !(f.is_finite() && f > 0.0) {
                return Err(refuse(
                    Some(i),
                    format!("no G-code feed rate for the move from point {} to {}: {f} mm/min", a + 1, b + 1),
                ));
            }
            let p = &st.points[b];
            push(Some(mv(false, Some(p.x_mm), Some(ya.y(p.y_mm)), Some(-p.h_mm), Some(f))), None, Some(i));
        }
        push(Some(up), None, Some(i));
    }
    push(Some(GcodeStatement::End), None, None);
    Ok((out, warnings))
}

fn compare_gcode(text: &str, plan: &[GcodeLine]) -> Result<(), RobotError> {
    let read = parse::read_gcode(text)?;
    let want: Vec<_> = plan.iter().filter_map(|l| l.statement.as_ref().map(|s| (l.stroke, s))).collect();
    for (i, ((line, got), (stroke, w))) in read.iter().zip(&want).enumerate() {
        compare_gcode_statement(got, w)
            .map_err(|r| mismatch(ExportTarget::Gcode, *stroke, Some(*line), format!("statement {}: {r}", i + 1)))?;
    }
    if read.len() != want.len() {
        let line = read.get(want.len()).map(|m| m.0);
        return Err(mismatch(
            ExportTarget::Gcode,
            None,
            line,
            format!("the text has {} statements where the plotter program has {}", read.len(), want.len()),
        ));
    }
    Ok(())
}

fn compare_gcode_statement(read: &GcodeStatement, want: &GcodeStatement) -> Result<(), String> {
    use GcodeStatement::Move as M;
    match (read, want) {
        (M { rapid, x_mm, y_mm, z_mm, f_mm_min }, M { rapid: wr, x_mm: wx, y_mm: wy, z_mm: wz, f_mm_min: wf })
            if rapid == wr =>
        {
            for (name, r, w, floor) in [
                ("X", x_mm, wx, LENGTH_FLOOR),
                ("Y", y_mm, wy, LENGTH_FLOOR),
                ("Z", z_mm, wz, LENGTH_FLOOR),
                ("F", f_mm_min, wf, 0.0),
            ] {
                match (r, w) {
                    (Some(r), Some(w)) => same(name, *r, *w, floor)?,
                    (None, None) => {}
                    _ => {
                        return Err(format!(
                            "`{}` where the plotter program has `{}`",
                            gcode_statement(read),
                            gcode_statement(want)
                        ));
                    }
                }
            }
            Ok(())
        }
        _ if read == want => Ok(()),
        _ => Err(format!("`{}` where the plotter program has `{}`", gcode_statement(read), gcode_statement(want))),
    }
}
