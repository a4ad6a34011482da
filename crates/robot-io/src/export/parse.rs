//! Reading an exported program back: one small parser per format that accepts exactly the
//! grammar the exporters write (the statements, in their places, and inert comments) and
//! refuses anything else, naming the line. The exporters compare what these read with the
//! checked program before they return the text.

use super::lua;
use super::text::{ExportTarget, MAX_DECIMALS, is_inert_comment, unsafe_anywhere};
use crate::RobotError;
use crate::kinematics::DhParams;

/// A move of an exported arm program (ARCS Lua or URScript), as read back from its text.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReadMove {
    /// A joint move to joints the program gives: Lua `moveJoint({q}, a, v, 0, 0)`,
    /// URScript `movej([q], a=a, v=v, t=0, r=0)`.
    Joint {
        /// Target joints, rad.
        q: [f64; 6],
        /// Joint acceleration, rad/s².
        a: f64,
        /// Joint speed, rad/s.
        v: f64,
    },
    /// A joint move to a TCP pose that the controller solves: Lua `inverseKinematics` from the
    /// current joints, refusing to move when it fails, then `moveJoint(q, a, v, 0, 0)`;
    /// URScript `movej(p[...], a=a, v=v, t=0, r=0)`.
    JointPose {
        /// Lua: the pose `[x, y, z, rx, ry, rz]` as AUBO writes it (m, rad, `R = Rz·Ry·Rx`);
        /// URScript: position (m) and rotation vector (rad).
        target: [f64; 6],
        /// Joint acceleration, rad/s².
        a: f64,
        /// Joint speed, rad/s.
        v: f64,
        /// Lua: the joints the controller's solution is sought near, when the program gives
        /// them (a path-buffer program: the first waypoint, so the arm starts on the
        /// waypoints' branch); `None`: the joints the arm reports.
        qnear: Option<[f64; 6]>,
    },
    /// A linear TCP move: Lua `moveLine({pose}, a, v, blend, 0)`, URScript
    /// `movel(p[...], a=a, v=v, t=0, r=blend)`.
    Line {
        /// As in [`ReadMove::JointPose`].
        target: [f64; 6],
        /// Acceleration, m/s².
        a: f64,
        /// Speed, m/s.
        v: f64,
        /// Blend radius, m.
        blend_m: f64,
    },
    /// A process move (URScript `movep(p[...], a=a, v=v, r=blend)`: constant tool speed,
    /// blended).
    Process {
        /// Position (m) and rotation vector (rad).
        target: [f64; 6],
        /// Tool acceleration, m/s².
        a: f64,
        /// Tool speed, m/s.
        v: f64,
        /// Blend radius, m.
        blend_m: f64,
    },
    /// A path buffer run (Lua `movePathBuffer(name)` after its allocation, waypoints,
    /// evaluation and checks): the index of the buffer in [`ReadProgram::path_buffers`].
    PathBuffer {
        /// Index into [`ReadProgram::path_buffers`].
        buffer: usize,
    },
    /// The count of finished strokes published at the start and after each stroke's lift
    /// (URScript `write_output_integer_register(24, N)`, Lua `setInt32("maobi_strokes", N)`),
    /// for a client following the run.
    Progress {
        /// Strokes finished.
        strokes: usize,
    },
}

/// A path buffer of an exported ARCS Lua program, as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadPathBuffer {
    /// Its name (`maobi_stroke_N`, N the stroke's number from 1).
    pub name: String,
    /// The size given to `pathBufferAlloc` (its type is always 2).
    pub size: usize,
    /// The joint waypoints appended, rad, in order.
    pub waypoints: Vec<[f64; 6]>,
    /// The joint accelerations given to `pathBufferEval`, rad/s².
    pub acc_rad_s2: [f64; 6],
    /// The joint speeds given to `pathBufferEval`, rad/s.
    pub speed_rad_s: [f64; 6],
    /// The waypoint interval given to `pathBufferEval`, s.
    pub interval_s: f64,
    /// The joints the arm must report (within [`crate::timing::PATH_START_TOLERANCE_RAD`])
    /// before `movePathBuffer`, rad.
    pub start_q: [f64; 6],
}

/// An exported arm program as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadProgram {
    /// The tool offset along the flange z, m.
    pub tcp_offset_m: f64,
    /// The speed fraction (Lua; URScript has none).
    pub speed_fraction: Option<f64>,
    /// The moves in the order they run, each with its line number (from 1).
    pub moves: Vec<(usize, ReadMove)>,
    /// The kinematics the Lua program checks the controller's `getKinematicsParam(true)`
    /// against before anything moves (a path-buffer program; `None` otherwise).
    pub kinematics: Option<DhParams>,
    /// The path buffers, in the order they run.
    pub path_buffers: Vec<ReadPathBuffer>,
}

/// A statement of an exported G-code program, as read back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GcodeStatement {
    /// `G21`: millimetres.
    Millimetres,
    /// `G90`: absolute coordinates.
    Absolute,
    /// `G0` (rapid) or `G1` (feed) with the words given: one of `G0 Z`, `G0 X Y F`, `G1 Z F`,
    /// `G1 X Y Z F`.
    Move {
        /// `G0` rather than `G1`.
        rapid: bool,
        /// X, paper mm.
        x_mm: Option<f64>,
        /// Y, paper mm.
        y_mm: Option<f64>,
        /// Z, mm (0 where the tip touches the paper, positive up).
        z_mm: Option<f64>,
        /// Feed rate, mm/min.
        f_mm_min: Option<f64>,
    },
    /// `M2`: end of program (the last line).
    End,
}

/// Where a parse failed: the line (from 1) and why.
pub(crate) struct At {
    pub(crate) line: usize,
    pub(crate) reason: String,
}

/// The refusal of a text in `target`'s format.
pub(crate) fn refused(target: ExportTarget, stroke: Option<usize>, at: At) -> RobotError {
    RobotError::Unsafe {
        stroke,
        point: None,
        reason: format!(
            "the exported {} program, line {}: {}; the export is refused",
            target.name(),
            at.line,
            at.reason
        ),
    }
}

/// A line as an error quotes it: escaped, at most 80 characters.
fn quote(line: &str) -> String {
    let cut: String = line.chars().take(80).collect();
    let more = if cut.len() < line.len() { "…" } else { "" };
    format!("{cut:?}{more}")
}

/// The lines of `text` with their numbers (from 1): `\n` ends every line, including the last;
/// no other control character, line separator or invisible format character anywhere.
fn lines(text: &str) -> Result<Vec<(usize, &str)>, At> {
    let Some(body) = text.strip_suffix('\n') else {
        return Err(At { line: text.lines().count().max(1), reason: "the text does not end with a line end".into() });
    };
    let mut out = Vec::new();
    for (i, l) in body.split('\n').enumerate() {
        if let Some(c) = l.chars().find(|&c| unsafe_anywhere(c)) {
            return Err(At {
                line: i + 1,
                reason: format!(
                    "U+{:04X} (a control character, line separator or invisible format character) in {}",
                    c as u32,
                    quote(l)
                ),
            });
        }
        out.push((i + 1, l));
    }
    Ok(out)
}

/// A cursor over one line.
struct Cur<'a>(&'a str);

impl Cur<'_> {
    fn lit(&mut self, l: &str) -> Option<()> {
        self.0 = self.0.strip_prefix(l)?;
        Some(())
    }

    /// A number as the exporters print it: `-?[0-9]+\.[0-9]{6,20}`.
    fn num(&mut self) -> Option<f64> {
        let b = self.0.as_bytes();
        let digits = |from: usize| b[from..].iter().take_while(|c| c.is_ascii_digit()).count();
        let sign = usize::from(b.first() == Some(&b'-'));
        let int = digits(sign);
        if int == 0 || b.get(sign + int) != Some(&b'.') {
            return None;
        }
        let frac = digits(sign + int + 1);
        if !(6..=MAX_DECIMALS).contains(&frac) {
            return None;
        }
        let end = sign + int + 1 + frac;
        let v = self.0[..end].parse().ok()?;
        self.0 = &self.0[end..];
        Some(v)
    }

    /// A whole number without a sign or leading zeros, at most 9 digits.
    fn int(&mut self) -> Option<usize> {
        let n = self.0.bytes().take_while(u8::is_ascii_digit).count();
        if n == 0 || n > 9 || (n > 1 && self.0.starts_with('0')) {
            return None;
        }
        let v = self.0[..n].parse().ok()?;
        self.0 = &self.0[n..];
        Some(v)
    }

    /// `N` numbers separated by `, `.
    fn nums<const N: usize>(&mut self) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        for (i, o) in out.iter_mut().enumerate() {
            if i > 0 {
                self.lit(", ")?;
            }
            *o = self.num()?;
        }
        Some(out)
    }

    fn end(&self) -> Option<()> {
        self.0.is_empty().then_some(())
    }
}

/// Parses a whole line with `f`, which must consume all of it.
fn whole<T>(line: &str, f: impl FnOnce(&mut Cur<'_>) -> Option<T>) -> Option<T> {
    let mut c = Cur(line);
    let v = f(&mut c)?;
    c.end()?;
    Some(v)
}

/// Whether `line` is a comment line of `target`: `indent`, the marker, a space and inert text.
fn is_comment(line: &str, indent: &str, marker: &str, target: ExportTarget) -> bool {
    line.strip_prefix(indent)
        .and_then(|l| l.strip_prefix(marker))
        .and_then(|l| l.strip_prefix(' '))
        .is_some_and(|t| is_inert_comment(t, target))
}

fn unexpected(line: usize, l: &str, want: &str) -> At {
    At { line, reason: format!("expected {want}, found {}", quote(l)) }
}

/// The next line, which must be exactly `want`.
fn expect<'a>(it: &mut impl Iterator<Item = (usize, &'a str)>, want: &str, last: usize) -> Result<(), At> {
    match it.next() {
        Some((_, l)) if l == want => Ok(()),
        Some((n, l)) => Err(unexpected(n, l, &format!("`{want}`"))),
        None => Err(At { line: last, reason: format!("the text ends before `{want}`") }),
    }
}

/// The next statement of an arm program's body, its `  `-indented comments (`marker`) skipped;
/// `None` at the closing `end`.
fn statement<'a>(
    it: &mut impl Iterator<Item = (usize, &'a str)>,
    last: usize,
    marker: &str,
    target: ExportTarget,
) -> Result<Option<(usize, &'a str)>, At> {
    loop {
        let Some((n, l)) = it.next() else {
            return Err(At { line: last, reason: "the program does not end with `end`".into() });
        };
        if l == "end" {
            return Ok(None);
        }
        if !is_comment(l, "  ", marker, target) {
            return Ok(Some((n, l)));
        }
    }
}

/// The first line that is not a header comment (`marker` at the start), with the lines after.
fn after_header<'a>(
    it: &mut std::iter::Peekable<impl Iterator<Item = (usize, &'a str)>>,
    marker: &str,
    target: ExportTarget,
) -> Result<(), At> {
    while let Some(&(n, l)) = it.peek() {
        if !l.starts_with(marker) {
            break;
        }
        if !is_comment(l, "", marker, target) {
            return Err(At { line: n, reason: format!("a comment that is not inert: {}", quote(l)) });
        }
        it.next();
    }
    Ok(())
}

/// The Lua error a joint move to a pose raises when the controller cannot solve it.
pub(crate) const LUA_IK_ERROR: &str = "maobi: the controller cannot reach the first pose";

/// Reads back an ARCS Lua program as [`super::aubo_lua`] or [`super::aubo_lua_path_buffer`]
/// writes it, in the form of AUBO's script documentation: header comments (`-- text`),
/// `return function(api)`, `local _ENV = require('aubo').sched.select_robot(1)`, the `sched` and
/// `sleep` bindings and their check, for a path-buffer program the kinematics check (`do`,
/// `local want = {a = {…}, alpha = {…}, d = {…}, theta = {…}}` and its fixed lines),
/// `setTcpOffset({0, 0, z, 0, 0, 0})`, `setSpeedFraction(f)`, then moves, the progress
/// (`setInt32("maobi_strokes", N)`), path-buffer blocks (`do`, `local name =
/// "maobi_stroke_N"`, `pathBufferAlloc(name, 2, n)`, `pathBufferAppend` pieces of at most 1,000
/// waypoints, `pathBufferEval`, the waits, `local q0 = {…}` and the joints check,
/// `movePathBuffer`, the lift `moveLine`, the wait, `pathBufferFree`, `end`; only after the
/// kinematics check) and `  -- text` comments, `end`. Numbers are `-?d+.d{6,20}` (sizes and
/// stroke numbers whole); comment text must be inert (see [`super::text::comment_text`]).
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not exactly one of these.
pub fn read_lua(text: &str) -> Result<ReadProgram, RobotError> {
    read_lua_at(text).map_err(|at| refused(ExportTarget::Lua, None, at))
}

fn read_lua_at(text: &str) -> Result<ReadProgram, At> {
    let all = lines(text)?;
    let last = all.len();
    let mut it = all.into_iter().peekable();
    after_header(&mut it, "--", ExportTarget::Lua)?;
    for want in lua::head_lines() {
        expect(&mut it, &want, last)?;
    }
    let kinematics = lua_kinematics(&mut it, last)?;
    let tcp_offset_m = one_number(
        &mut it,
        last,
        ("setTcpOffset", "  setTcpOffset({0, 0, ", ", 0, 0, 0})"),
        "`  setTcpOffset({0, 0, z, 0, 0, 0})`",
        unexpected,
    )?;
    let speed_fraction = one_number(
        &mut it,
        last,
        ("setSpeedFraction", "  setSpeedFraction(", ")"),
        "`  setSpeedFraction(f)`",
        unexpected,
    )?;
    let mut moves = Vec::new();
    let mut path_buffers = Vec::new();
    while let Some((n, l)) = statement(&mut it, last, "--", ExportTarget::Lua)? {
        let m = if l == "  do" {
            let (m, l) = it.next().ok_or(At { line: last, reason: "the text ends inside `do`".into() })?;
            if l.starts_with("    local name = ") {
                if kinematics.is_none() {
                    return Err(At {
                        line: m,
                        reason: "a path buffer in a program that does not check the controller's kinematics first"
                            .into(),
                    });
                }
                let (buffer, lift) = read_path_buffer(&mut it, (m, l), last)?;
                moves.push((n, ReadMove::PathBuffer { buffer: path_buffers.len() }));
                path_buffers.push(buffer);
                moves.push(lift);
                continue;
            }
            lua_joint_pose(&mut it, (m, l), last)?
        } else if let Some(k) = whole(l, |c| {
            c.lit(&format!("  setInt32(\"{}\", ", lua::PROGRESS_VARIABLE))?;
            let k = c.int()?;
            c.lit(")")?;
            Some(k)
        }) {
            ReadMove::Progress { strokes: k }
        } else {
            lua_move(l, "  ").ok_or_else(|| {
                unexpected(
                    n,
                    l,
                    "a move (`moveLine`, `moveJoint`, `do`), `setInt32(\"maobi_strokes\", N)`, a `--` comment or `end`",
                )
            })?
        };
        moves.push((n, m));
    }
    if let Some((n, l)) = it.next() {
        return Err(unexpected(n, l, "nothing after the final `end`"));
    }
    Ok(ReadProgram { tcp_offset_m, speed_fraction: Some(speed_fraction), moves, kinematics, path_buffers })
}

/// The kinematics a path-buffer program checks first (`  do`, `    local want = {a = {…},
/// alpha = {…}, d = {…}, theta = {…}}` and the check's fixed lines), or `None` where the
/// program does not begin so.
fn lua_kinematics<'a>(
    it: &mut std::iter::Peekable<impl Iterator<Item = (usize, &'a str)>>,
    last: usize,
) -> Result<Option<DhParams>, At> {
    if it.peek().is_none_or(|(_, l)| *l != "  do") {
        return Ok(None);
    }
    it.next();
    let (n, l) = it.next().ok_or(At { line: last, reason: "the text ends before the kinematics".into() })?;
    let k = whole(l, |c| {
        c.lit(lua::WANT_PREFIX)?;
        let a_m = c.nums::<6>()?;
        c.lit("}, alpha = {")?;
        let alpha_rad = c.nums::<6>()?;
        c.lit("}, d = {")?;
        let d_m = c.nums::<6>()?;
        c.lit("}, theta = {")?;
        let theta_rad = c.nums::<6>()?;
        c.lit("}}")?;
        Some(DhParams { a_m, alpha_rad, d_m, theta_rad })
    })
    .ok_or_else(|| unexpected(n, l, "`    local want = {a = {...}, alpha = {...}, d = {...}, theta = {...}}`"))?;
    k.validate().map_err(|why| At { line: n, reason: format!("the kinematics: {why}") })?;
    for want in lua::kinematics_check_lines() {
        expect(it, &want, last)?;
    }
    Ok(Some(k))
}

/// The next line, which must be `prefix`, one number and `suffix` (`what`: the statement's
/// name, for a text that ends before it; `want`: the expected line, for `unexpected`).
fn one_number<'a>(
    it: &mut impl Iterator<Item = (usize, &'a str)>,
    last: usize,
    (what, prefix, suffix): (&str, &str, &str),
    want: &str,
    unexpected: fn(usize, &str, &str) -> At,
) -> Result<f64, At> {
    let (n, l) = it.next().ok_or_else(|| At { line: last, reason: format!("the text ends before {what}") })?;
    whole(l, |c| {
        c.lit(prefix)?;
        let v = c.num()?;
        c.lit(suffix)?;
        Some(v)
    })
    .ok_or_else(|| unexpected(n, l, want))
}

/// A joint move to a pose inside `  do` (`first`: the line after it): the controller's
/// `inverseKinematics`, the refusal when it fails, `moveJoint(q, a, v, 0, 0)`, `  end`.
fn lua_joint_pose<'a>(
    it: &mut impl Iterator<Item = (usize, &'a str)>,
    first: (usize, &str),
    last: usize,
) -> Result<ReadMove, At> {
    let (m, l) = first;
    let (qnear, pose) = whole(l, |c| {
        c.lit("    local q, ret = inverseKinematics(")?;
        let qnear = if c.lit("getJointPositions()").is_some() {
            None
        } else {
            c.lit("{")?;
            let q = c.nums::<6>()?;
            c.lit("}")?;
            Some(q)
        };
        c.lit(", {")?;
        let p = c.nums::<6>()?;
        c.lit("})")?;
        Some((qnear, p))
    })
    .ok_or_else(|| unexpected(m, l, "`    local q, ret = inverseKinematics(qnear, {pose})`"))?;
    expect(
        it,
        &format!(
            "    if type(q) ~= \"table\" or #q ~= 6 or (ret ~= nil and ret ~= 0) then error(\"{LUA_IK_ERROR}\") end"
        ),
        last,
    )?;
    let (m, l) = it.next().ok_or(At { line: last, reason: "the text ends inside `do`".into() })?;
    let (a, v) = whole(l, |c| {
        c.lit("    moveJoint(q, ")?;
        let [a, v] = c.nums::<2>()?;
        c.lit(", 0, 0)")?;
        Some((a, v))
    })
    .ok_or_else(|| unexpected(m, l, "`    moveJoint(q, a, v, 0, 0)`"))?;
    expect(it, "  end", last)?;
    Ok(ReadMove::JointPose { target: pose, a, v, qnear })
}

/// A Lua `moveJoint({q}, a, v, 0, 0)` or `moveLine({pose}, a, v, blend, 0)` after `indent`.
fn lua_move(l: &str, indent: &str) -> Option<ReadMove> {
    whole(l, |c| {
        c.lit(indent)?;
        if c.lit("moveJoint({").is_some() {
            let q = c.nums::<6>()?;
            c.lit("}, ")?;
            let [a, v] = c.nums::<2>()?;
            c.lit(", 0, 0)")?;
            Some(ReadMove::Joint { q, a, v })
        } else {
            c.lit("moveLine({")?;
            let target = c.nums::<6>()?;
            c.lit("}, ")?;
            let [a, v, blend_m] = c.nums::<3>()?;
            c.lit(", 0)")?;
            Some(ReadMove::Line { target, a, v, blend_m })
        }
    })
}

/// A path-buffer block after its `  do` (`first`: the name line): the allocation, the
/// waypoints, the evaluation, the waits, the arm's joints checked, `movePathBuffer`, the lift
/// (returned with its line), the wait and `pathBufferFree`, `  end`.
fn read_path_buffer<'a>(
    it: &mut impl Iterator<Item = (usize, &'a str)>,
    first: (usize, &str),
    last: usize,
) -> Result<(ReadPathBuffer, (usize, ReadMove)), At> {
    let ends = |what: &str| At { line: last, reason: format!("the text ends inside a path buffer, before {what}") };
    let (n, l) = first;
    let stroke = whole(l, |c| {
        c.lit("    local name = \"maobi_stroke_")?;
        let k = c.int()?;
        c.lit("\"")?;
        (k >= 1).then_some(k - 1)
    })
    .ok_or_else(|| unexpected(n, l, "`    local name = \"maobi_stroke_N\"`"))?;
    let name = lua::buffer_name(stroke);
    let (n, l) = it.next().ok_or_else(|| ends("pathBufferAlloc"))?;
    let size = whole(l, |c| {
        c.lit("    pathBufferAlloc(name, 2, ")?;
        let k = c.int()?;
        c.lit(")")?;
        Some(k)
    })
    .ok_or_else(|| unexpected(n, l, "`    pathBufferAlloc(name, 2, SIZE)`"))?;
    if !(2..=crate::timing::MAX_STROKE_WAYPOINTS).contains(&size) {
        return Err(At {
            line: n,
            reason: format!(
                "a path buffer of {size} waypoints (2 to {} expected)",
                crate::timing::MAX_STROKE_WAYPOINTS
            ),
        });
    }
    let mut waypoints: Vec<[f64; 6]> = Vec::new();
    let (mut n, mut l) = it.next().ok_or_else(|| ends("pathBufferAppend"))?;
    while l == "    pathBufferAppend(name, {" {
        let mut piece = 0;
        loop {
            let (m, w) = it.next().ok_or_else(|| ends("the end of pathBufferAppend"))?;
            if w == "    })" {
                break;
            }
            let q = whole(w, |c| {
                c.lit("      {")?;
                let q = c.nums::<6>()?;
                c.lit("},")?;
                Some(q)
            })
            .ok_or_else(|| unexpected(m, w, "a waypoint `      {q1, q2, q3, q4, q5, q6},` or `    })`"))?;
            piece += 1;
            if waypoints.len() == size || piece > crate::aubo::PATH_APPEND_WAYPOINTS {
                return Err(At {
                    line: m,
                    reason: format!(
                        "more waypoints than the {size} allocated, or more than {} in one append",
                        crate::aubo::PATH_APPEND_WAYPOINTS
                    ),
                });
            }
            waypoints.push(q);
        }
        if piece == 0 {
            return Err(At { line: n, reason: "an append without waypoints".into() });
        }
        (n, l) = it.next().ok_or_else(|| ends("pathBufferEval"))?;
    }
    if waypoints.len() != size {
        return Err(At {
            line: n,
            reason: format!("{} waypoints appended where {size} were allocated", waypoints.len()),
        });
    }
    let (acc_rad_s2, speed_rad_s, interval_s) = whole(l, |c| {
        c.lit("    pathBufferEval(name, {")?;
        let a = c.nums::<6>()?;
        c.lit("}, {")?;
        let v = c.nums::<6>()?;
        c.lit("}, ")?;
        let t = c.num()?;
        c.lit(")")?;
        Some((a, v, t))
    })
    .ok_or_else(|| unexpected(n, l, "`    pathBufferAppend(name, {` or `    pathBufferEval(name, {a}, {v}, t)`"))?;
    for want in lua::valid_wait_lines() {
        expect(it, &want, last)?;
    }
    let (n, l) = it.next().ok_or_else(|| ends("the joints check"))?;
    let start_q = whole(l, |c| {
        c.lit(lua::START_PREFIX)?;
        let q = c.nums::<6>()?;
        c.lit("}")?;
        Some(q)
    })
    .ok_or_else(|| unexpected(n, l, "`    local q0 = {q1, q2, q3, q4, q5, q6}`"))?;
    for want in lua::start_check_lines() {
        expect(it, &want, last)?;
    }
    let (n, l) = it.next().ok_or_else(|| ends("the lift"))?;
    let lift = lua_move(l, "    ").ok_or_else(|| unexpected(n, l, "the lift `    moveLine({pose}, a, v, 0, 0)`"))?;
    for want in lua::free_lines() {
        expect(it, &want, last)?;
    }
    Ok((ReadPathBuffer { name, size, waypoints, acc_rad_s2, speed_rad_s, interval_s, start_q }, (n, lift)))
}

/// Reads back a URScript program as [`super::urscript`] writes it: header comments
/// (`# text`), `def maobi_program():`, `set_tcp(p[0, 0, z, 0, 0, 0])`, then
/// `movej([q], a=, v=, t=0, r=0)`, `movej(p[...], a=, v=, t=0, r=0)`,
/// `movel(p[...], a=, v=, t=0, r=)`, `movep(p[...], a=, v=, r=)`,
/// `write_output_integer_register(24, N)` and `  # text` comments, each indented two spaces,
/// and `end` as the last line.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not exactly one of these (and the
/// function, when the line calls one outside [`URSCRIPT_FUNCTIONS`]).
pub fn read_urscript(text: &str) -> Result<ReadProgram, RobotError> {
    read_urscript_at(text).map_err(|at| refused(ExportTarget::UrScript, None, at))
}

fn read_urscript_at(text: &str) -> Result<ReadProgram, At> {
    read_urscript_named(text, URSCRIPT_PROGRAM)
}

/// The name of the URScript program maobi writes (`def maobi_program():`).
pub const URSCRIPT_PROGRAM: &str = "maobi_program";

/// The output integer register a URScript program counts its finished strokes in (24: the first
/// of the registers 24 to 47 that UR's script manual reserves for external RTDE clients).
pub const URSCRIPT_PROGRESS_REGISTER: usize = 24;

/// The URScript functions maobi writes, in the order the reader names them in a refusal.
pub const URSCRIPT_FUNCTIONS: [&str; 5] = ["set_tcp", "write_output_integer_register", "movej", "movel", "movep"];

/// [`read_urscript`] for the program `def <name>():` (`maobi_program`, or the lift a stopped
/// run sends, `maobi_lift`).
pub(crate) fn read_urscript_named(text: &str, name: &str) -> Result<ReadProgram, At> {
    let all = lines(text)?;
    let last = all.len();
    let mut it = all.into_iter().peekable();
    after_header(&mut it, "#", ExportTarget::UrScript)?;
    expect(&mut it, &format!("def {name}():"), last)?;
    let tcp_offset_m = one_number(
        &mut it,
        last,
        ("set_tcp", "  set_tcp(p[0, 0, ", ", 0, 0, 0])"),
        "`  set_tcp(p[0, 0, z, 0, 0, 0])`",
        urscript_unexpected,
    )?;
    let mut moves = Vec::new();
    while let Some((n, l)) = statement(&mut it, last, "#", ExportTarget::UrScript)? {
        // UR's argument orders (the script manual): movej(q, a, v, t, r), movel(pose, a, v, t,
        // r), movep(pose, a, v, r); maobi names every argument after the target, in that order,
        // with t=0 (the speeds decide the time).
        let m = whole(l, |c| {
            if c.lit("  write_output_integer_register(").is_some() {
                let register = c.int()?;
                c.lit(", ")?;
                let strokes = c.int()?;
                c.lit(")")?;
                return (register == URSCRIPT_PROGRESS_REGISTER).then_some(ReadMove::Progress { strokes });
            }
            if c.lit("  movej([").is_some() {
                let q = c.nums::<6>()?;
                c.lit("], a=")?;
                let a = c.num()?;
                c.lit(", v=")?;
                let v = c.num()?;
                c.lit(", t=0, r=0)")?;
                Some(ReadMove::Joint { q, a, v })
            } else if c.lit("  movej(p[").is_some() {
                let target = c.nums::<6>()?;
                c.lit("], a=")?;
                let a = c.num()?;
                c.lit(", v=")?;
                let v = c.num()?;
                c.lit(", t=0, r=0)")?;
                Some(ReadMove::JointPose { target, a, v, qnear: None })
            } else {
                let process = if c.lit("  movep(p[").is_some() {
                    true
                } else {
                    c.lit("  movel(p[")?;
                    false
                };
                let target = c.nums::<6>()?;
                c.lit("], a=")?;
                let a = c.num()?;
                c.lit(", v=")?;
                let v = c.num()?;
                if !process {
                    c.lit(", t=0")?;
                }
                c.lit(", r=")?;
                let blend_m = c.num()?;
                c.lit(")")?;
                Some(if process {
                    ReadMove::Process { target, a, v, blend_m }
                } else {
                    ReadMove::Line { target, a, v, blend_m }
                })
            }
        })
        .ok_or_else(|| {
            urscript_unexpected(
                n,
                l,
                "a move (`movel(p[...], a=, v=, t=0, r=)`, `movep(p[...], a=, v=, r=)`, `movej(..., a=, v=, t=0, r=0)`), `write_output_integer_register(24, N)`, a `#` comment or `end`",
            )
        })?;
        moves.push((n, m));
    }
    if let Some((n, l)) = it.next() {
        return Err(unexpected(n, l, "nothing after `end`"));
    }
    Ok(ReadProgram { tcp_offset_m, speed_fraction: None, moves, kinematics: None, path_buffers: Vec::new() })
}

/// [`unexpected`] for a URScript line, naming a called function outside the subset maobi
/// writes.
fn urscript_unexpected(line: usize, l: &str, want: &str) -> At {
    let call = l.trim_start();
    let name: String = call.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
    if !name.is_empty() && call[name.len()..].starts_with('(') && !URSCRIPT_FUNCTIONS.contains(&name.as_str()) {
        return At {
            line,
            reason: format!(
                "`{name}` is not in the URScript subset maobi writes ({}): {}",
                URSCRIPT_FUNCTIONS.join(", "),
                quote(l)
            ),
        };
    }
    unexpected(line, l, want)
}

/// Reads back G-code as [`super::gcode`] writes it: comment lines (`; text`), and the
/// statements `G21`, `G90`, `G0 Z`, `G0 X Y F`, `G1 Z F`, `G1 X Y Z F` (words in that order,
/// one space apart), each optionally followed by ` ; text`, and `M2` on the last line. No
/// `( ... )` comments, line numbers, checksums or other words.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first line that is not exactly one of these.
pub fn read_gcode(text: &str) -> Result<Vec<(usize, GcodeStatement)>, RobotError> {
    read_gcode_at(text).map_err(|at| refused(ExportTarget::Gcode, None, at))
}

fn read_gcode_at(text: &str) -> Result<Vec<(usize, GcodeStatement)>, At> {
    let all = lines(text)?;
    let mut out = Vec::new();
    let mut ended = false;
    for (n, l) in all {
        if l.starts_with(';') {
            if !is_comment(l, "", ";", ExportTarget::Gcode) {
                return Err(At { line: n, reason: format!("a comment that is not inert: {}", quote(l)) });
            }
            continue;
        }
        if ended {
            return Err(unexpected(n, l, "nothing after `M2`"));
        }
        let code = match l.split_once(" ; ") {
            Some((code, comment)) if is_inert_comment(comment, ExportTarget::Gcode) => code,
            Some(_) => return Err(At { line: n, reason: format!("a comment that is not inert: {}", quote(l)) }),
            None => l,
        };
        let st = match code {
            "G21" => Some(GcodeStatement::Millimetres),
            "G90" => Some(GcodeStatement::Absolute),
            "M2" => Some(GcodeStatement::End),
            _ => gcode_move(code),
        }
        .ok_or_else(|| {
            unexpected(n, l, "`G21`, `G90`, `G0 Z`, `G0 X Y F`, `G1 Z F`, `G1 X Y Z F`, `M2` or a `;` comment")
        })?;
        ended = st == GcodeStatement::End;
        out.push((n, st));
    }
    if !ended {
        return Err(At { line: out.last().map_or(1, |s| s.0), reason: "the program does not end with `M2`".into() });
    }
    Ok(out)
}

fn gcode_move(code: &str) -> Option<GcodeStatement> {
    let mut c = Cur(code);
    let rapid = if c.lit("G0").is_some() {
        true
    } else {
        c.lit("G1")?;
        false
    };
    let mut words: [Option<f64>; 4] = [None; 4];
    let mut shape = String::new();
    for (k, letter) in ["X", "Y", "Z", "F"].iter().enumerate() {
        let mut t = Cur(c.0);
        if t.lit(" ").and_then(|_| t.lit(letter)).is_some() {
            words[k] = Some(t.num()?);
            c = t;
            shape.push_str(letter);
        }
    }
    c.end()?;
    let allowed: &[&str] = if rapid { &["Z", "XYF"] } else { &["ZF", "XYZF"] };
    if !allowed.contains(&shape.as_str()) {
        return None;
    }
    let [x_mm, y_mm, z_mm, f_mm_min] = words;
    Some(GcodeStatement::Move { rapid, x_mm, y_mm, z_mm, f_mm_min })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gcode_lines_outside_the_grammar_are_refused() {
        let ok = "; t\nG21 ; millimetres\nG90\nG0 Z20.000000\nG0 X1.000000 Y2.000000 F6000.000000\nG1 Z-1.000000 F3000.000000\nG1 X1.000000 Y2.000000 Z-3.000000 F1200.000000\nM2\n";
        assert_eq!(read_gcode_at(ok).map(|v| v.len()).ok(), Some(7));
        for (bad, line) in [
            ("G1 Z-40\n", 1),
            ("G1 Z-40.000000\n", 1),
            ("G0 X1.000000 Y2.000000\n", 1),
            ("G1 Z-4.000000 F1.000000 (x)\n", 1),
            ("G1 Z-4.000000 F1.000000 ; (x)\n", 1),
            ("G1 Z-4.0 F1.000000\n", 1),
            ("G1 Z1e3 F1.000000\n", 1),
            ("G1 Z-4.000000  F1.000000\n", 1),
            ("G1 F1.000000 Z-4.000000\n", 1),
            ("g1 Z-4.000000 F1.000000\n", 1),
            ("N1 G1 Z-4.000000 F1.000000\n", 1),
            ("G21\n(G1 Z-4)\n", 2),
            ("G21\r\nM2\n", 1),
            ("G21\n;x\u{2028}G1\nM2\n", 2),
            ("G21\n", 1),
            ("G21\nM2\nG21\n", 3),
            ("M2", 1),
            ("G0 ZNaN\n", 1),
        ] {
            let e = read_gcode_at(bad).err().unwrap_or_else(|| panic!("{bad:?} was read"));
            assert_eq!(e.line, line, "{bad:?}: {}", e.reason);
        }
    }
}
