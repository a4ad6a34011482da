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

pub mod parse;
pub mod text;

use brush_model::Track;
use nalgebra::{UnitQuaternion, Vector3};

use crate::RobotError;
use crate::pose::Pose;
use crate::program::{DWELL_SINK_MM, Move, Program, RobotConfig, dip_plan};
use parse::{GcodeStatement, LUA_IK_ERROR, ReadMove, ReadProgram};
use text::{LENGTH_FLOOR, Target, close, comment_text, num};

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
fn mismatch(target: Target, stroke: Option<usize>, line: Option<usize>, reason: String) -> RobotError {
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

/// Every move of `program` in the order it runs, with its stroke index (`None`: the start).
fn program_moves(program: &Program) -> Vec<(Option<usize>, &Move)> {
    let mut out = vec![(None, &program.start)];
    for st in &program.strokes {
        out.extend(st.moves().map(|m| (Some(st.index), m)));
    }
    out
}

/// An ARCS Lua script (`return function(api) ... end`) that sets the tool offset and speed
/// fraction and runs every move. The title goes, made inert ([`text::comment_text`]), into
/// the first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, aubo_lua, build_program, export::verify_lua, level_frame_in_front};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &profile, &frame, &RobotConfig::default()).unwrap();
/// let lua = aubo_lua(&program, "一 -- a title stays a comment").unwrap();
/// assert!(lua.contains("return function(api)"));
/// // The text reads back as the checked program.
/// verify_lua(&lua, &program).unwrap();
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when the text, read back ([`parse::read_lua`]), does not match the
/// program (a number that cannot be printed so that it reads back as the checked value).
pub fn aubo_lua(program: &Program, title: &str) -> Result<String, RobotError> {
    let mut s = String::new();
    s.push_str(&format!(
        "-- maobi writing program: {}\n-- {} strokes, {} moves. Generated; do not edit by hand.\n",
        comment_text(title, Target::Lua),
        program.strokes.len(),
        program.move_count()
    ));
    s.push_str("return function(api)\n");
    s.push_str("  local robot_name = api:getRobotNames()[1]\n");
    s.push_str("  local robot = api:getRobotInterface(robot_name)\n");
    s.push_str(&format!("  robot:getRobotConfig():setTcpOffset({{0, 0, {}, 0, 0, 0}})\n", len(program.tcp_offset_m)));
    s.push_str("  local mc = robot:getMotionControl()\n");
    s.push_str(&format!("  mc:setSpeedFraction({})\n", rate(program.speed_fraction)));
    let emit = |s: &mut String, m: &Move| {
        match m {
        Move::Joint { q, a, v } => {
            s.push_str(&format!("  mc:moveJoint({{{}}}, {}, {}, 0, 0)\n", lens(q), rate(*a), rate(*v)))
        }
        // The controller solves the joints from where the arm is, and the script stops
        // (`error`) rather than move when it cannot; `do ... end` keeps `q` and `ret` local.
        Move::JointPose { pose, a, v } => s.push_str(&format!(
            "  do\n    local q, ret = robot:getRobotAlgorithm():inverseKinematics(robot:getRobotState():getJointPositions(), {{{}}})\n    if type(q) ~= \"table\" or #q ~= 6 or (ret ~= nil and ret ~= 0) then error(\"{LUA_IK_ERROR}\") end\n    mc:moveJoint(q, {}, {}, 0, 0)\n  end\n",
            lens(&pose.0),
            rate(*a),
            rate(*v)
        )),
        Move::Line { pose, a, v, blend_m } => s.push_str(&format!(
            "  mc:moveLine({{{}}}, {}, {}, {}, 0)\n",
            lens(&pose.0),
            rate(*a),
            rate(*v),
            rate(*blend_m)
        )),
    }
    };
    emit_moves(&mut s, program, "--", emit);
    s.push_str("end\n");
    verify_lua(&s, program)?;
    Ok(s)
}

/// Every move of `program` in order, through `emit`: the start, then per stroke its dip (after
/// a `comment` line `ink dip before stroke N`) and its other moves (after `stroke N`).
fn emit_moves(s: &mut String, program: &Program, comment: &str, emit: impl Fn(&mut String, &Move)) {
    emit(s, &program.start);
    for st in &program.strokes {
        if !st.dip.is_empty() {
            s.push_str(&format!("  {comment} ink dip before stroke {}\n", st.index + 1));
            for m in &st.dip {
                emit(s, m);
            }
        }
        s.push_str(&format!("  {comment} stroke {}\n", st.index + 1));
        for m in st.moves().skip(st.dip.len()) {
            emit(s, m);
        }
    }
}

/// Checks an ARCS Lua script against the program it should run: reads it back
/// ([`parse::read_lua`]) and compares the tool offset, the speed fraction and every move, in
/// order, with `program`'s.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not in the exporter's grammar, or the
/// first move (line, stroke, value) that differs from the program's.
pub fn verify_lua(text: &str, program: &Program) -> Result<(), RobotError> {
    compare_arm(Target::Lua, &parse::read_lua(text)?, program)
}

/// A URScript program: `movel(p[x, y, z, rx, ry, rz], a, v, r=blend)` with rotation vectors.
/// The title goes, made inert ([`text::comment_text`]), into the first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, build_program, export::verify_urscript, level_frame_in_front, urscript};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &profile, &frame, &RobotConfig::default()).unwrap();
/// let script = urscript(&program, "一").unwrap();
/// assert!(script.contains("def maobi_write():") && script.contains("movel(p["));
/// verify_urscript(&script, &program).unwrap();
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when the text, read back ([`parse::read_urscript`]), does not match
/// the program.
pub fn urscript(program: &Program, title: &str) -> Result<String, RobotError> {
    let mut s = format!("# maobi writing program: {}\ndef maobi_write():\n", comment_text(title, Target::UrScript));
    s.push_str(&format!("  set_tcp(p[0, 0, {}, 0, 0, 0])\n", len(program.tcp_offset_m)));
    let emit = |s: &mut String, m: &Move| match m {
        Move::Joint { q, a, v } => s.push_str(&format!("  movej([{}], a={}, v={})\n", lens(q), rate(*a), rate(*v))),
        // A pose target: the UR controller solves the joints.
        Move::JointPose { pose, a, v } => s.push_str(&format!(
            "  movej(p[{}, {}], a={}, v={})\n",
            lens(&pose.position()),
            lens(&pose.rotation_vector()),
            rate(*a),
            rate(*v)
        )),
        Move::Line { pose, a, v, blend_m } => {
            s.push_str(&format!(
                "  movel(p[{}, {}], a={}, v={}, r={})\n",
                lens(&pose.position()),
                lens(&pose.rotation_vector()),
                rate(*a),
                rate(*v),
                rate(*blend_m)
            ));
        }
    };
    emit_moves(&mut s, program, "#", emit);
    s.push_str("end\nmaobi_write()\n");
    verify_urscript(&s, program)?;
    Ok(s)
}

/// Checks a URScript program against the program it should run, as [`verify_lua`] does
/// (rotation vectors are compared as rotations, within 1e-8 rad).
///
/// # Errors
/// As [`verify_lua`].
pub fn verify_urscript(text: &str, program: &Program) -> Result<(), RobotError> {
    compare_arm(Target::UrScript, &parse::read_urscript(text)?, program)
}

fn compare_arm(target: Target, read: &ReadProgram, program: &Program) -> Result<(), RobotError> {
    if !close(read.tcp_offset_m, program.tcp_offset_m, LENGTH_FLOOR) {
        return Err(mismatch(
            target,
            None,
            None,
            format!("the tool offset reads {} m where it is {} m", show(read.tcp_offset_m), show(program.tcp_offset_m)),
        ));
    }
    if let Some(f) = read.speed_fraction.filter(|&f| !close(f, program.speed_fraction, 0.0)) {
        return Err(mismatch(
            target,
            None,
            None,
            format!("the speed fraction reads {} where it is {}", show(f), show(program.speed_fraction)),
        ));
    }
    let want = program_moves(program);
    for (i, ((line, got), (stroke, m))) in read.moves.iter().zip(&want).enumerate() {
        compare_move(target, got, m)
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

fn compare_move(target: Target, read: &ReadMove, want: &Move) -> Result<(), String> {
    match (read, want) {
        (ReadMove::Joint { q, a, v }, Move::Joint { q: wq, a: wa, v: wv }) => {
            for (k, (r, w)) in q.iter().zip(wq).enumerate() {
                same(&format!("joint {}", k + 1), *r, *w, LENGTH_FLOOR)?;
            }
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)
        }
        (ReadMove::JointPose { target: t, a, v }, Move::JointPose { pose, a: wa, v: wv }) => {
            same_pose(target, t, pose)?;
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)
        }
        (ReadMove::Line { target: t, a, v, blend_m }, Move::Line { pose, a: wa, v: wv, blend_m: wb }) => {
            same_pose(target, t, pose)?;
            same("the acceleration", *a, *wa, 0.0)?;
            same("the speed", *v, *wv, 0.0)?;
            same("the blend radius", *blend_m, *wb, 0.0)
        }
        _ => Err(format!("{} where the program has {}", read_kind(read), move_kind(want))),
    }
}

fn read_kind(m: &ReadMove) -> &'static str {
    match m {
        ReadMove::Joint { .. } => "a joint move to joints",
        ReadMove::JointPose { .. } => "a joint move to a pose",
        ReadMove::Line { .. } => "a line move",
    }
}

fn move_kind(m: &Move) -> &'static str {
    match m {
        Move::Joint { .. } => "a joint move to joints",
        Move::JointPose { .. } => "a joint move to a pose",
        Move::Line { .. } => "a line move",
    }
}

/// A pose read back (Lua: `[x, y, z, rx, ry, rz]`; URScript: position and rotation vector)
/// against the checked pose.
fn same_pose(target: Target, read: &[f64; 6], want: &Pose) -> Result<(), String> {
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        same(name, read[k], want.0[k], LENGTH_FLOOR)?;
    }
    if target == Target::UrScript {
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

/// G-code for a 3-axis brush plotter working in paper millimetres: X, Y on the paper, Z = −H
/// (Z 0 where the tip touches, positive up), feed rates from the configured speeds. Tilt α and
/// direction β cannot be expressed and are ignored; the returned warnings say so. Ink dips
/// (robot.json `ink` with `paper_mm`) go to the pot, down `depth_mm` below the paper plane,
/// soak (sink `DWELL_SINK_MM` further over `dwell_s`, as the arm programs do) and back up,
/// before the strokes the reload rule picks. The title goes, made inert
/// ([`text::comment_text`]), into the first comment.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, gcode};
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=50).map(|i| pt(30.0 + 0.4 * f64::from(i))).collect() }] };
/// let (text, _warnings) = gcode(&track, &RobotConfig::default(), "一").unwrap();
/// assert!(text.starts_with("; maobi writing program: 一"));
/// // The press is Z = −H: 3 mm below the touching plane.
/// assert!(text.lines().any(|l| l.starts_with("G1") && l.contains("Z-3")));
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] when the text, read back ([`parse::read_gcode`]), does not match the
/// moves made from the track (a value that is not finite or cannot be printed so that it
/// reads back as itself).
pub fn gcode(track: &Track, cfg: &RobotConfig, title: &str) -> Result<(String, Vec<String>), RobotError> {
    gcode_chars(track, None, cfg, title)
}

/// [`gcode`] with the track's character boundaries (`stroke_chars`, for the reload rule
/// `before_each_char`).
///
/// # Examples
/// ```
/// use robot_io::brush_model::{Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, gcode, gcode_chars};
/// let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let stroke = |y: f64| Stroke { points: (0..=20).map(|i| pt(30.0 + f64::from(i), y)).collect() };
/// // Two characters of one stroke each.
/// let track = Track { strokes: vec![stroke(40.0), stroke(80.0)] };
/// let cfg = RobotConfig::default();
/// let (text, _) = gcode_chars(&track, Some(&[0, 1]), &cfg, "一一").unwrap();
/// // Without an ink station the boundaries change nothing.
/// assert_eq!(text, gcode(&track, &cfg, "一一").unwrap().0);
/// ```
///
/// # Errors
/// As [`gcode`].
pub fn gcode_chars(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    cfg: &RobotConfig,
    title: &str,
) -> Result<(String, Vec<String>), RobotError> {
    let (plan, warnings) = gcode_plan(track, stroke_chars, cfg);
    let mut s = format!("; maobi writing program: {}\n", comment_text(title, Target::Gcode));
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

/// Checks G-code against the plotter moves made from `track` and `cfg` (as [`gcode_chars`]
/// makes them): reads it back ([`parse::read_gcode`]) and compares every statement, in order.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not in the exporter's grammar, or the
/// first statement (line, stroke, value) that differs.
pub fn verify_gcode(
    text: &str,
    track: &Track,
    stroke_chars: Option<&[usize]>,
    cfg: &RobotConfig,
) -> Result<(), RobotError> {
    compare_gcode(text, &gcode_plan(track, stroke_chars, cfg).0)
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
fn gcode_plan(track: &Track, stroke_chars: Option<&[usize]>, cfg: &RobotConfig) -> (Vec<GcodeLine>, Vec<String>) {
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
            push(Some(mv(true, Some(x), Some(y), None, Some(travel_f))), None, Some(i));
            push(Some(mv(false, None, None, Some(-st.depth_mm), Some(travel_f * 0.5))), None, Some(i));
            if st.dwell_s > 0.0 {
                let soak_f = DWELL_SINK_MM / st.dwell_s * 60.0;
                let soak = mv(false, None, None, Some(-st.depth_mm - DWELL_SINK_MM), Some(soak_f));
                push(Some(soak), Some(comment_text(&format!("dwell {} s", st.dwell_s), Target::Gcode)), Some(i));
            }
            push(Some(up), None, Some(i));
        }
        push(None, Some(format!("stroke {}", i + 1)), Some(i));
        push(Some(mv(true, Some(first.x_mm), Some(first.y_mm), None, Some(travel_f))), None, Some(i));
        for p in &st.points {
            push(Some(mv(false, Some(p.x_mm), Some(p.y_mm), Some(-p.h_mm), Some(write_f))), None, Some(i));
        }
        push(Some(up), None, Some(i));
    }
    push(Some(GcodeStatement::End), None, None);
    (out, warnings)
}

fn compare_gcode(text: &str, plan: &[GcodeLine]) -> Result<(), RobotError> {
    let read = parse::read_gcode(text)?;
    let want: Vec<_> = plan.iter().filter_map(|l| l.statement.as_ref().map(|s| (l.stroke, s))).collect();
    for (i, ((line, got), (stroke, w))) in read.iter().zip(&want).enumerate() {
        compare_gcode_statement(got, w)
            .map_err(|r| mismatch(Target::Gcode, *stroke, Some(*line), format!("statement {}: {r}", i + 1)))?;
    }
    if read.len() != want.len() {
        let line = read.get(want.len()).map(|m| m.0);
        return Err(mismatch(
            Target::Gcode,
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
