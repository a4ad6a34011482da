//! The fixed lines of an ARCS Lua program in the form of AUBO's script documentation
//! (`return function(api) local _ENV = require('aubo').sched.select_robot(1) … end`, the robot's
//! methods as globals), shared by the writer and the reader so that both hold exactly the same
//! text.

use super::text::{LENGTH_FLOOR, num};
use crate::kinematics::DhParams;

/// How far each of the controller's kinematic parameters (`getKinematicsParam(true)`: `a`,
/// `d` in m, `alpha`, `theta` in rad) may lie from those a path-buffer program's joint
/// waypoints were computed with before the program refuses to move: 1 µm and 1 µrad, the
/// values being the controller's own, saved to `arm.json` in full.
pub const KINEMATICS_TOLERANCE: f64 = 1e-6;

/// Polls of `pathBufferValid`, 10 ms apart, before a program gives up on a buffer (5 s, as
/// the runner waits).
pub(crate) const VALID_POLLS: usize = 500;

fn list(v: &[f64]) -> String {
    v.iter().map(|x| num(*x, LENGTH_FLOOR)).collect::<Vec<_>>().join(", ")
}

/// The program's first lines: the robot's environment selected as AUBO's script documentation
/// and its examples do, and `sleep` bound from `sched` (refusing to run where the controller's
/// Lua has none, before anything moves).
pub(crate) fn head_lines() -> Vec<String> {
    vec![
        "return function(api)".into(),
        "  local _ENV = require('aubo').sched.select_robot(1)".into(),
        "  local sched = require('aubo').sched".into(),
        "  local sleep = sched.sleep".into(),
        "  if type(sleep) ~= \"function\" then error(\"maobi: this controller's Lua has no sched.sleep: nothing was moved\") end".into(),
    ]
}

/// The name of the named integer variable a program counts its finished strokes in
/// (`setInt32`; read over RPC with `RegisterControl.getInt32`).
pub const PROGRESS_VARIABLE: &str = "maobi_strokes";

/// The line that publishes `strokes` finished strokes.
pub(crate) fn progress_line(strokes: usize) -> String {
    format!("  setInt32(\"{PROGRESS_VARIABLE}\", {strokes})")
}

/// The line that holds the parameters the waypoints were computed with.
pub(crate) fn want_line(k: &DhParams) -> String {
    format!(
        "    local want = {{a = {{{}}}, alpha = {{{}}}, d = {{{}}}, theta = {{{}}}}}",
        list(&k.a_m),
        list(&k.alpha_rad),
        list(&k.d_m),
        list(&k.theta_rad)
    )
}

/// The prefix of [`want_line`] (for the reader).
pub(crate) const WANT_PREFIX: &str = "    local want = {a = {";

/// The kinematics check after [`want_line`]: every parameter within [`KINEMATICS_TOLERANCE`]
/// (NaN fails: `not (|x − want| <= tol)`), and no `beta` other than zeros.
pub(crate) fn kinematics_check_lines() -> Vec<String> {
    let tol = num(KINEMATICS_TOLERANCE, 0.0);
    [
        "    local k = getKinematicsParam(true)".to_string(),
        "    if type(k) ~= \"table\" then error(\"maobi: getKinematicsParam(true) gave no table: nothing was moved\") end".into(),
        "    for _, key in ipairs({\"a\", \"alpha\", \"d\", \"theta\"}) do".into(),
        "      local got = k[key]".into(),
        "      if type(got) ~= \"table\" or #got ~= 6 then error(\"maobi: the controller's kinematics lack six values of \" .. key .. \": nothing was moved\") end".into(),
        "      for i = 1, 6 do".into(),
        format!("        if type(got[i]) ~= \"number\" or not (math.abs(got[i] - want[key][i]) <= {tol}) then error(\"maobi: the controller's kinematics (\" .. key .. \") differ from those the joint waypoints were computed with: nothing was moved\") end"),
        "      end".into(),
        "    end".into(),
        "    if k.beta ~= nil then".into(),
        "      if type(k.beta) ~= \"table\" then error(\"maobi: the controller's kinematics have a beta that is not a table: nothing was moved\") end".into(),
        "      for i = 1, #k.beta do".into(),
        format!("        if type(k.beta[i]) ~= \"number\" or not (math.abs(k.beta[i]) <= {tol}) then error(\"maobi: the controller's kinematics have a beta that maobi does not model: nothing was moved\") end"),
        "      end".into(),
        "    end".into(),
        "  end".into(),
    ]
    .into()
}

/// `local name = "maobi_stroke_N"` (N from 1).
pub(crate) fn name_line(stroke: usize) -> String {
    format!("    local name = \"{}\"", buffer_name(stroke))
}

/// The name of stroke `stroke`'s (from 0) path buffer, as `robot send` names it.
pub(crate) fn buffer_name(stroke: usize) -> String {
    format!("maobi_stroke_{}", stroke + 1)
}

/// A waypoint line inside `pathBufferAppend(name, { ... })`.
pub(crate) fn waypoint_line(q: &[f64; 6]) -> String {
    format!("      {{{}}},", list(q))
}

/// The evaluation line: joint accelerations and speeds (six each), the interval.
pub(crate) fn eval_line(acc: f64, speed: f64, interval_s: f64) -> String {
    let six = |v: f64| vec![num(v, 0.0); 6].join(", ");
    format!("    pathBufferEval(name, {{{}}}, {{{}}}, {})", six(acc), six(speed), num(interval_s, 0.0))
}

/// The wait for the buffer to become valid and for the approach to end.
pub(crate) fn valid_wait_lines() -> Vec<String> {
    vec![
        "    local polls = 0".into(),
        "    while not pathBufferValid(name) do".into(),
        "      polls = polls + 1".into(),
        format!(
            "      if polls > {VALID_POLLS} then error(\"maobi: a path buffer did not become valid within 5 s: its stroke was not written\") end"
        ),
        "      sleep(0.01)".into(),
        "    end".into(),
        "    while getExecId() ~= -1 do sleep(0.01) end".into(),
    ]
}

/// The joints the arm must report before the buffer moves it.
pub(crate) fn start_line(q: &[f64; 6]) -> String {
    format!("    local q0 = {{{}}}", list(q))
}

/// The prefix of [`start_line`].
pub(crate) const START_PREFIX: &str = "    local q0 = {";

/// The check of the arm's joints against the first waypoint, then the move.
pub(crate) fn start_check_lines() -> Vec<String> {
    let tol = num(crate::timing::PATH_START_TOLERANCE_RAD, 0.0);
    vec![
        "    local q = getJointPositions()".into(),
        "    for i = 1, 6 do".into(),
        format!(
            "      if type(q) ~= \"table\" or type(q[i]) ~= \"number\" or not (math.abs(q[i] - q0[i]) <= {tol}) then error(\"maobi: the arm is not at the path buffer's first waypoint: its stroke was not written\") end"
        ),
        "    end".into(),
        "    movePathBuffer(name)".into(),
    ]
}

/// After the lift: the wait for the arm, and the buffer freed.
pub(crate) fn free_lines() -> Vec<String> {
    vec!["    while getExecId() ~= -1 do sleep(0.01) end".into(), "    pathBufferFree(name)".into(), "  end".into()]
}
