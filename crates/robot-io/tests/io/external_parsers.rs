//! Every export format read by a parser that is not ours (issue 26: "an external parser for
//! every export format"). The ARCS Lua script (a move per point, or a path buffer per stroke:
//! issue 27) is compiled by the real Lua compiler (`luac5.4 -p`) and run by the real
//! interpreter (`lua5.4`) against a stub of the ARCS script environment (`require('aubo')`,
//! `sched.select_robot(1)` and the robot's methods as globals, as AUBO documents them) that
//! records every call (its kinematics, the arm's joints and `sched.sleep` set per case); the G-code (merged moves, feed
//! rates from the timing) is parsed by the `gcodeparser` package from PyPI.
//! Without a tool a test prints `SKIPPED <name>: <why>` and returns (`.ci/run` installs them).
//! URScript has no offline parser outside a UR controller or URSim (docs/robot.md says so).
//!
//! Each tool runs once per case on a few kB of text read from its standard input, under a
//! time limit; nothing touches the network.

use std::io::{Read, Write};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use brush_model::{Stroke, Track, TrackPoint};
use robot_io::{
    DhParams, GCODE_MERGE_TOLERANCE_MM, InkStation, Move, PointTimes, Program, Reload, RobotConfig, aubo_lua,
    aubo_lua_path_buffer, build_program, gcode, point_times, time_program,
};
use serde_json::Value;

use crate::common::{paper, pen1};

/// Longest a tool may take on one case before the test fails.
const TOOL_LIMIT: Duration = Duration::from_secs(20);

/// Relative tolerance between a number as the external tool read it and the checked value
/// (the exporters print numbers to read back within 1e-9 relative), with a 1e-12 absolute
/// floor for lengths and angles that are rounding noise around 0.
fn close(read: f64, want: f64) -> bool {
    (read - want).abs() <= 1e-9 * want.abs() + 1e-12
}

/// Two short strokes, pressed at 15 and 18 mm, tilted 0.05 rad.
fn small_track() -> Track {
    let line = |pts: &[(f64, f64, f64)], beta: f64| Stroke {
        points: pts
            .iter()
            .map(|&(x, y, h)| TrackPoint { x_mm: x, y_mm: y, h_mm: h, alpha_rad: 0.05, beta_rad: beta })
            .collect(),
    };
    Track {
        strokes: vec![
            line(
                &[(40.0, 60.0, 15.0), (50.0, 60.0, 16.5), (60.0, 61.0, 18.0), (70.0, 62.0, 15.0)],
                std::f64::consts::PI,
            ),
            line(
                &[(55.0, 40.0, 15.0), (55.0, 55.0, 17.25), (55.0, 70.0, 15.0), (55.5, 85.0, 15.0)],
                -std::f64::consts::FRAC_PI_2,
            ),
        ],
    }
}

/// Where the plotter finds the ink, paper mm.
const POT_MM: [f64; 2] = [330.0, 150.0];

/// A pot beside the sheet, dipped before every stroke, `dwell_s` in the ink; `None`: no pot.
fn config(dwell_s: Option<f64>) -> RobotConfig {
    RobotConfig {
        limits: robot_io::Limits { max_step_mm: 16.0, ..Default::default() },
        ink: dwell_s.map(|dwell_s| InkStation {
            pose: [0.63, 0.10, 0.07, std::f64::consts::PI, 0.0, 0.0],
            depth_mm: 25.0,
            dwell_s,
            reload: Reload::EveryStrokes(1),
            paper_mm: Some(POT_MM),
        }),
        ..RobotConfig::default()
    }
}

fn program(cfg: &RobotConfig) -> Program {
    build_program(&small_track(), &pen1(), &paper(), cfg).unwrap().0
}

/// When the small track's strokes, timed on the nominal arm, reach each of their points.
fn times(cfg: &RobotConfig) -> PointTimes {
    let p = program(cfg);
    point_times(&p, &time_program(&p, &DhParams::AUBO_I5, cfg).unwrap()).unwrap()
}

/// Titles that try to leave the first comment of a Lua or G-code program.
const HOSTILE_TITLES: &[&str] = &[
    "十\nos.exit(3)",
    "十\r\nos.exit(3)",
    "十\ros.exit(3)",
    "]] os.exit(3) --[[",
    "]==] os.exit(3) --[==[",
    "--[[\nos.exit(3)\n]]",
    "--[==[\nos.exit(3)\n]==]",
    "十\nreturn function() os.exit(3) end",
    "十\nmoveLine({0, 0, 0, 0, 0, 0}, 1, 1, 0, 0)",
    "a\u{2028}os.exit(3)\u{2029}b",
    "a\u{85}os.exit(3)",
    "a\u{0}os.exit(3)\u{1b}[2J",
    "\"'`\\\" ; os.exit(3) --",
    "十\nG1 Z-40 F3000",
    "十\r\n\r\nG1 Z-40 F3000",
    "; G1 Z-40 F3000",
    "(G1 Z-40) M2 %",
    "十 G1 Z-40 ; M2",
    "\u{202e}0-Z 1G\u{2066}",
];

/// What a tool did with one input.
struct Ran {
    status: ExitStatus,
    stdout: String,
    stderr: String,
}

/// Runs `program args` with `input` on its standard input, within [`TOOL_LIMIT`]; `None`
/// when the program cannot be started (not installed).
fn run_tool(program: &str, args: &[&str], input: &str) -> Option<Ran> {
    let mut child = Command::new(program)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .ok()?;
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_owned();
    // Written from a thread so that a tool that answers before reading everything cannot
    // block the test on a full pipe.
    let writer = std::thread::spawn(move || {
        let _ = stdin.write_all(input.as_bytes());
    });
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out.read_to_end(&mut s);
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err.read_to_end(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > TOOL_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{program} {args:?} ran past {TOOL_LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    writer.join().unwrap();
    let stdout = String::from_utf8_lossy(&reader.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&err_reader.join().unwrap()).into_owned();
    Some(Ran { status, stdout, stderr })
}

/// Says that a test was skipped, on the terminal (not captured), and why.
fn skipped(test: &str, why: &str) {
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: {why}");
}

// ---------------------------------------------------------------------------------------------
// ARCS Lua under the real Lua 5.4

/// Whether `lua5.4` and `luac5.4` run here.
fn have_lua() -> bool {
    ["lua5.4", "luac5.4"].iter().all(|tool| Command::new(tool).arg("-v").output().is_ok_and(|o| o.status.success()))
}

const NO_LUA: &str = "lua5.4/luac5.4 not installed (Debian: `apt-get install lua5.4`)";

/// The joints the arm reports before the program moves it, rad.
const HOME_Q: [f64; 6] = [0.0, -0.2618, 1.7453, 0.4363, 1.5, 0.0];
/// The joints the stub's inverse kinematics answers, rad.
const IK_Q: [f64; 6] = [0.1, -0.2, 1.3, 0.4, 1.5, -0.6];

/// A stub of the ARCS script environment the exported script runs in, with the bindings and
/// signatures of AUBO's documented script examples and SDK headers (`require('aubo')`,
/// `aubo.sched.select_robot(1)` returning the robot's environment, `sched.sleep`, the robot's
/// methods as globals in it: `setTcpOffset(pose)`, `setSpeedFraction(f)`, `moveLine(pose, a, v,
/// blend_radius, duration)`, `moveJoint(q, a, v, blend_radius, duration)`,
/// `inverseKinematics(qnear, pose) -> table, int`, `getJointPositions()`,
/// `getKinematicsParam(real)`, the path buffer calls, `getExecId()`, `setInt32(key, value)`),
/// and the driver that loads the script from standard input and calls the function it returns.
/// Every call, getters included, is written to standard output as one JSON line `{"call":
/// NAME, "args": [...]}`; numbers as `%.17g` (they read back to the bit). `IK_MODE` picks what
/// `inverseKinematics` answers. The robot's methods are also real globals, so code that escaped
/// into the script's top level could reach them.
const LUA_DRIVER: &str = r##"
local function num(v)
  if math.type(v) == nil then error("not a number: " .. tostring(v)) end
  return string.format("%.17g", v)
end
local function value(v)
  if type(v) == "table" then
    local o = {}
    for i = 1, #v do
      if type(v[i]) == "table" then o[i] = value(v[i]) else o[i] = num(v[i]) end
    end
    return "[" .. table.concat(o, ",") .. "]"
  elseif type(v) == "boolean" then
    return tostring(v)
  elseif type(v) == "string" then
    if v:find('[^%w_]') then error("unexpected string argument") end
    return '"' .. v .. '"'
  else
    return num(v)
  end
end
local function rec(name, ...)
  local parts = {}
  for i = 1, select("#", ...) do parts[i] = value((select(i, ...))) end
  io.write('{"call":"', name, '","args":[', table.concat(parts, ","), ']}\n')
end
local function copy(t) local o = {} for i = 1, #t do o[i] = t[i] end return o end
local joints = copy(HOME_Q)
-- The robot's environment: its methods as globals, falling back to the base library.
local env = setmetatable({}, {__index = _G})
local function method(name, f)
  env[name] = function(...)
    rec(name, ...)
    return f(...)
  end
  _G[name] = env[name]
end
-- Path buffers: appended waypoints by name; the one appended and not yet moved.
local buffers, pending, polls, ints = {}, nil, {}, {}
method("setTcpOffset", function() return 0 end)
method("setSpeedFraction", function() return 0 end)
method("moveLine", function() return 0 end)
method("moveJoint", function(q) joints = copy(q) return 0 end)
method("pathBufferAlloc", function(name) buffers[name] = {} polls[name] = 0 return 0 end)
method("pathBufferAppend", function(name, w)
  for i = 1, #w do table.insert(buffers[name], copy(w[i])) end
  pending = name
  return 0
end)
method("pathBufferEval", function() return 0 end)
-- Valid from the second poll on, so the wait loop runs.
method("pathBufferValid", function(name) polls[name] = polls[name] + 1 return polls[name] > 1 end)
method("movePathBuffer", function(name)
  local b = buffers[name]
  joints = copy(b[#b])
  pending = nil
  return 0
end)
method("pathBufferFree", function(name) buffers[name] = nil return 0 end)
method("getExecId", function() return -1 end)
method("getKinematicsParam", function() return KIN end)
method("setInt32", function(key, v) ints[key] = v end)
-- ARM_MODE "follows": the approach brought the arm to the buffer's first waypoint.
method("getJointPositions", function()
  if ARM_MODE == "follows" and pending ~= nil then return copy(buffers[pending][1]) end
  return copy(joints)
end)
method("inverseKinematics", function()
  if IK_MODE == "status" then return copy(IK_Q), 0
  elseif IK_MODE == "joints" then return copy(IK_Q)
  elseif IK_MODE == "refused" then return copy(IK_Q), -23
  elseif IK_MODE == "nil" then return nil, -5
  elseif IK_MODE == "five" then return {0.1, 0.2, 0.3, 0.4, 0.5}
  end
  error("unknown IK_MODE")
end)
local sched = {select_robot = function(n)
  rec("select_robot", n)
  if n ~= 1 then error("no robot " .. tostring(n)) end
  return env
end}
if HAVE_SCHED then sched.sleep = function(t) rec("sleep", t) end end
package.loaded["aubo"] = {sched = sched}
local chunk = assert(load(io.read("a"), "=export", "t"))
local main = chunk()
if type(main) ~= "function" then error("the script does not return a function") end
main({})
io.write('{"call":"done","args":[]}\n')
"##;

fn lua_list(v: &[f64]) -> String {
    format!("{{{}}}", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "))
}

/// Runs `script` under `lua5.4` with the stub (the nominal arm, following the program).
fn run_lua(script: &str, ik_mode: &str) -> Ran {
    run_lua_arm(script, ik_mode, &kin_table(&DhParams::AUBO_I5, ""), "follows", true)
}

/// The Lua table `getKinematicsParam` answers for `k`, with `extra` fields (`beta = {...}`).
fn kin_table(k: &DhParams, extra: &str) -> String {
    format!(
        "{{a = {}, alpha = {}, d = {}, theta = {}{extra}}}",
        lua_list(&k.a_m),
        lua_list(&k.alpha_rad),
        lua_list(&k.d_m),
        lua_list(&k.theta_rad)
    )
}

/// Runs `script` under `lua5.4` with the stub: `kin` the controller's kinematics (a Lua table
/// expression), `arm_mode` whether the arm follows the program (`follows`) or stays where it
/// was, `sched` whether the controller's Lua has `sched.sleep`.
fn run_lua_arm(script: &str, ik_mode: &str, kin: &str, arm_mode: &str, sched: bool) -> Ran {
    let driver = format!(
        "local IK_MODE = {ik_mode:?}\nlocal HOME_Q = {}\nlocal IK_Q = {}\nlocal KIN = {kin}\nlocal ARM_MODE = {arm_mode:?}\nlocal HAVE_SCHED = {sched}\n{LUA_DRIVER}",
        lua_list(&HOME_Q),
        lua_list(&IK_Q)
    );
    run_tool("lua5.4", &["-e", &driver], script).expect("lua5.4 starts")
}

/// One recorded call: its name and arguments (numbers or lists of numbers).
#[derive(Debug, Clone, PartialEq)]
struct Call {
    name: String,
    args: Vec<Arg>,
}

#[derive(Debug, Clone, PartialEq)]
enum Arg {
    Num(f64),
    List(Vec<f64>),
    Lists(Vec<Vec<f64>>),
    Text(String),
    Bool(bool),
}

fn parse_calls(stdout: &str) -> Vec<Call> {
    stdout
        .lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}"));
            let args = v["args"]
                .as_array()
                .unwrap()
                .iter()
                .map(|a| match a {
                    Value::Number(n) => Arg::Num(n.as_f64().unwrap()),
                    Value::Array(xs) if xs.first().is_some_and(Value::is_array) => Arg::Lists(
                        xs.iter()
                            .map(|x| x.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect())
                            .collect(),
                    ),
                    Value::Array(xs) => Arg::List(xs.iter().map(|x| x.as_f64().unwrap()).collect()),
                    Value::String(s) => Arg::Text(s.clone()),
                    Value::Bool(b) => Arg::Bool(*b),
                    other => panic!("{other}"),
                })
                .collect();
            Call { name: v["call"].as_str().unwrap().to_string(), args }
        })
        .collect()
}

/// The calls that change the arm or its settings, as `program` makes them, in order: the
/// tool offset, the speed fraction, then per move the controller's inverse kinematics (from
/// the joints the arm reports) and a joint move to its answer, or a line move.
fn expected_calls(program: &Program) -> Vec<Call> {
    let call = |name: &str, args: Vec<Arg>| Call { name: name.into(), args };
    let mut out = vec![
        call("setTcpOffset", vec![Arg::List(vec![0.0, 0.0, program.tcp_offset_m, 0.0, 0.0, 0.0])]),
        call("setSpeedFraction", vec![Arg::Num(program.speed_fraction)]),
        progress(0),
    ];
    let mut joints = HOME_Q;
    // Each stroke's last move is followed by the count of strokes finished.
    let moves = std::iter::once((&program.start, None)).chain(program.strokes.iter().flat_map(|s| {
        let n = s.moves().count();
        s.moves().enumerate().map(move |(i, m)| (m, (i + 1 == n).then_some(s.index + 1)))
    }));
    for (m, done) in moves {
        match *m {
            Move::Joint { q, a, v } => {
                joints = q;
                out.push(call(
                    "moveJoint",
                    vec![Arg::List(q.to_vec()), Arg::Num(a), Arg::Num(v), Arg::Num(0.0), Arg::Num(0.0)],
                ));
            }
            Move::JointPose { pose, a, v } => {
                out.push(call("inverseKinematics", vec![Arg::List(joints.to_vec()), Arg::List(pose.0.to_vec())]));
                joints = IK_Q;
                out.push(call(
                    "moveJoint",
                    vec![Arg::List(IK_Q.to_vec()), Arg::Num(a), Arg::Num(v), Arg::Num(0.0), Arg::Num(0.0)],
                ));
            }
            Move::Line { pose, a, v, blend_m } => out.push(call(
                "moveLine",
                vec![Arg::List(pose.0.to_vec()), Arg::Num(a), Arg::Num(v), Arg::Num(blend_m), Arg::Num(0.0)],
            )),
        }
        if let Some(k) = done {
            out.push(progress(k));
        }
    }
    out
}

/// The call publishing `strokes` finished strokes.
fn progress(strokes: usize) -> Call {
    Call { name: "setInt32".into(), args: vec![Arg::Text("maobi_strokes".into()), Arg::Num(strokes as f64)] }
}

/// The calls that change the arm or its settings (not the getters).
fn effects(calls: &[Call]) -> Vec<Call> {
    calls
        .iter()
        .filter(|c| {
            matches!(
                c.name.as_str(),
                "setTcpOffset" | "setSpeedFraction" | "inverseKinematics" | "moveLine" | "moveJoint" | "setInt32"
            )
        })
        .cloned()
        .collect()
}

/// Whether the recorded calls are the expected ones: same count, order, names and argument
/// shapes, every number [`close`] to the checked value. `Err` names the first difference.
fn same_calls(got: &[Call], want: &[Call]) -> Result<(), String> {
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let differs = || format!("call {}: {g:?} where the program has {w:?}", i + 1);
        if g.name != w.name || g.args.len() != w.args.len() {
            return Err(differs());
        }
        for (ga, wa) in g.args.iter().zip(&w.args) {
            let ok = match (ga, wa) {
                (Arg::Num(r), Arg::Num(x)) => close(*r, *x),
                (Arg::List(r), Arg::List(x)) => r.len() == x.len() && r.iter().zip(x).all(|(r, x)| close(*r, *x)),
                (Arg::Lists(r), Arg::Lists(x)) => {
                    r.len() == x.len()
                        && r.iter()
                            .zip(x)
                            .all(|(r, x)| r.len() == x.len() && r.iter().zip(x).all(|(r, x)| close(*r, *x)))
                }
                (Arg::Text(r), Arg::Text(x)) => r == x,
                (Arg::Bool(r), Arg::Bool(x)) => r == x,
                _ => false,
            };
            if !ok {
                return Err(differs());
            }
        }
    }
    if got.len() != want.len() {
        return Err(format!("{} calls where the program makes {}", got.len(), want.len()));
    }
    Ok(())
}

/// The real compiler's syntax check.
fn luac_check(script: &str) -> Ran {
    run_tool("luac5.4", &["-p", "-"], script).expect("luac5.4 starts")
}

#[test]
fn lua_exports_compile_and_run_as_the_checked_program_under_real_lua() {
    if !have_lua() {
        return skipped("lua_exports_compile_and_run_as_the_checked_program_under_real_lua", NO_LUA);
    }
    for cfg in [config(Some(0.5)), config(None)] {
        let p = program(&cfg);
        let script = aubo_lua(&p, "十").unwrap();
        let c = luac_check(&script);
        assert!(c.status.success(), "luac5.4 -p: {}\n{script}", c.stderr);
        // The controller's inverse kinematics answers with a status (0) or the joints alone.
        for mode in ["status", "joints"] {
            let ran = run_lua(&script, mode);
            assert!(ran.status.success(), "{mode}: {}", ran.stderr);
            let calls = parse_calls(&ran.stdout);
            assert_eq!(calls.last().map(|c| c.name.as_str()), Some("done"), "{mode}");
            assert_eq!(calls[0].name, "select_robot", "{mode}");
            let want = expected_calls(&p);
            assert_eq!(want.len(), 2 + p.move_count() + 1 + 1 + p.strokes.len(), "one IK call, the progress");
            if let Err(e) = same_calls(&effects(&calls), &want) {
                panic!("{mode}: {e}");
            }
        }
    }
}

#[test]
fn lua_script_stops_before_moving_when_the_controller_cannot_solve_the_first_pose() {
    if !have_lua() {
        return skipped("lua_script_stops_before_moving_when_the_controller_cannot_solve_the_first_pose", NO_LUA);
    }
    let p = program(&config(Some(0.5)));
    let script = aubo_lua(&p, "十").unwrap();
    let want = expected_calls(&p);
    // A refusal status, no joints, or a table that is not six joints: the script raises an
    // error after the IK call and commands nothing.
    for mode in ["refused", "nil", "five"] {
        let ran = run_lua(&script, mode);
        assert!(!ran.status.success(), "{mode}: {}", ran.stdout);
        assert!(ran.stderr.contains("cannot reach the first pose"), "{mode}: {}", ran.stderr);
        let got = effects(&parse_calls(&ran.stdout));
        assert!(same_calls(&got, &want[..4]).is_ok(), "{mode}: {got:?}");
        assert!(!ran.stdout.contains("\"done\""), "{mode}");
    }
}

#[test]
fn hostile_titles_add_no_lua_call() {
    if !have_lua() {
        return skipped("hostile_titles_add_no_lua_call", NO_LUA);
    }
    let p = program(&config(Some(0.5)));
    let plain = run_lua(&aubo_lua(&p, "t").unwrap(), "status");
    assert!(plain.status.success(), "{}", plain.stderr);
    for title in HOSTILE_TITLES {
        let script = aubo_lua(&p, title).unwrap();
        let c = luac_check(&script);
        assert!(c.status.success(), "{title:?}: luac5.4 -p: {}", c.stderr);
        let ran = run_lua(&script, "status");
        assert!(ran.status.success(), "{title:?}: exit {:?}: {}", ran.status.code(), ran.stderr);
        // Every call, getters included, as with a plain title.
        assert_eq!(ran.stdout, plain.stdout, "{title:?}");
    }
}

/// The harness sees what it is meant to catch: a line that escaped the comment runs under the
/// real interpreter (exit 3, or an extra recorded move), and an unclosed long comment does not
/// compile.
#[test]
fn lua_harness_catches_injected_code() {
    if !have_lua() {
        return skipped("lua_harness_catches_injected_code", NO_LUA);
    }
    let p = program(&config(None));
    let script = aubo_lua(&p, "t").unwrap();
    let (first, rest) = script.split_once('\n').unwrap();
    let exits = format!("{first}\nos.exit(3)\n{rest}");
    assert_eq!(run_lua(&exits, "status").status.code(), Some(3));
    let moves = format!("{first}\nmoveLine({{0.3, 0.1, 0.0, 3.14, 0, 0}}, 1, 1, 0, 0)\n{rest}");
    let ran = run_lua(&moves, "status");
    assert!(ran.status.success(), "{}", ran.stderr);
    let e = same_calls(&effects(&parse_calls(&ran.stdout)), &expected_calls(&p)).unwrap_err();
    assert!(e.contains("call 1"), "{e}");
    let unclosed = format!("{first}\n--[[\n{rest}");
    let c = luac_check(&unclosed);
    assert!(!c.status.success() && c.stderr.contains("unfinished long comment"), "{}", c.stderr);
    // A number that lost its value on the way is named.
    let slower = script.replacen("setSpeedFraction(1.000000)", "setSpeedFraction(0.500000)", 1);
    assert_ne!(slower, script);
    let ran = run_lua(&slower, "status");
    let e = same_calls(&effects(&parse_calls(&ran.stdout)), &expected_calls(&p)).unwrap_err();
    assert!(e.contains("call 2") && e.contains("setSpeedFraction"), "{e}");
}

/// The calls a path-buffer program makes that read the arm's parameters or change the arm or
/// its settings, as `program` timed on `kin` makes them: the kinematics read, the tool offset,
/// the speed fraction, the start (inverse kinematics near the first waypoint, joint move), then
/// per stroke its dip and
/// approach `moveLine`s, its path buffer (allocated, appended in pieces of 1,000 waypoints,
/// evaluated with the joint limits and the interval, moved), its lift and the buffer freed.
fn expected_path_buffer_calls(program: &Program, kin: &DhParams, cfg: &RobotConfig) -> Vec<Call> {
    let call = |name: &str, args: Vec<Arg>| Call { name: name.into(), args };
    let timing = time_program(program, kin, cfg).unwrap();
    let line = |m: &Move| {
        let Move::Line { pose, a, v, blend_m } = *m else { panic!("{m:?}") };
        call("moveLine", vec![Arg::List(pose.0.to_vec()), Arg::Num(a), Arg::Num(v), Arg::Num(blend_m), Arg::Num(0.0)])
    };
    let Move::JointPose { pose, a, v } = program.start else { panic!("{:?}", program.start) };
    let mut out = vec![
        call("getKinematicsParam", vec![Arg::Bool(true)]),
        call("setTcpOffset", vec![Arg::List(vec![0.0, 0.0, program.tcp_offset_m, 0.0, 0.0, 0.0])]),
        call("setSpeedFraction", vec![Arg::Num(program.speed_fraction)]),
        // Solved near the first waypoint, not where the arm is.
        call("inverseKinematics", vec![Arg::List(timing.strokes[0].joints[0].to_vec()), Arg::List(pose.0.to_vec())]),
        call("moveJoint", vec![Arg::List(IK_Q.to_vec()), Arg::Num(a), Arg::Num(v), Arg::Num(0.0), Arg::Num(0.0)]),
    ];
    out.insert(3, progress(0));
    let lim = cfg.limits;
    for st in &program.strokes {
        out.extend(st.dip.iter().chain(&st.approach).map(line));
        let t = timing.strokes.iter().find(|t| t.stroke == st.index).unwrap();
        let name = || Arg::Text(format!("maobi_stroke_{}", st.index + 1));
        out.push(call("pathBufferAlloc", vec![name(), Arg::Num(2.0), Arg::Num(t.joints.len() as f64)]));
        for piece in t.joints.chunks(1000) {
            out.push(call("pathBufferAppend", vec![name(), Arg::Lists(piece.iter().map(|q| q.to_vec()).collect())]));
        }
        out.push(call(
            "pathBufferEval",
            vec![
                name(),
                Arg::List(vec![lim.max_joint_acc_rad_s2; 6]),
                Arg::List(vec![lim.max_joint_speed_rad_s; 6]),
                Arg::Num(t.interval_s),
            ],
        ));
        out.push(call("movePathBuffer", vec![name()]));
        out.push(line(&st.lift));
        out.push(call("pathBufferFree", vec![name()]));
        out.push(progress(st.index + 1));
    }
    out
}

/// The calls of [`expected_path_buffer_calls`]' kinds.
fn path_buffer_effects(calls: &[Call]) -> Vec<Call> {
    const KINDS: &[&str] = &[
        "getKinematicsParam",
        "setTcpOffset",
        "setSpeedFraction",
        "inverseKinematics",
        "moveJoint",
        "moveLine",
        "pathBufferAlloc",
        "pathBufferAppend",
        "pathBufferEval",
        "movePathBuffer",
        "pathBufferFree",
        "setInt32",
    ];
    calls.iter().filter(|c| KINDS.contains(&c.name.as_str())).cloned().collect()
}

#[test]
fn lua_path_buffer_exports_run_under_real_lua_as_the_timed_program() {
    if !have_lua() {
        return skipped("lua_path_buffer_exports_run_under_real_lua_as_the_timed_program", NO_LUA);
    }
    let kin = DhParams::AUBO_I5;
    for cfg in [config(Some(0.5)), config(None)] {
        let p = program(&cfg);
        let script = aubo_lua_path_buffer(&p, &kin, &cfg, "十").unwrap();
        let c = luac_check(&script);
        assert!(c.status.success(), "luac5.4 -p: {}", c.stderr);
        let ran = run_lua(&script, "status");
        assert!(ran.status.success(), "{}", ran.stderr);
        let calls = parse_calls(&ran.stdout);
        assert_eq!(calls.last().map(|c| c.name.as_str()), Some("done"));
        let want = expected_path_buffer_calls(&p, &kin, &cfg);
        assert_eq!(want.iter().filter(|c| c.name == "movePathBuffer").count(), p.strokes.len());
        if let Err(e) = same_calls(&path_buffer_effects(&calls), &want) {
            panic!("{e}");
        }
        // Before each buffer moves: polled until valid (false, then true here), the approach
        // waited for, the arm's joints read; after its lift, the arm waited for again.
        let names: Vec<&str> = calls.iter().map(|c| c.name.as_str()).collect();
        for (i, _) in names.iter().enumerate().filter(|(_, n)| **n == "movePathBuffer") {
            let eval = names[..i].iter().rposition(|n| *n == "pathBufferEval").unwrap();
            let between = &names[eval..i];
            assert_eq!(between.iter().filter(|n| **n == "pathBufferValid").count(), 2, "{between:?}");
            let k = between.iter().position(|n| *n == "getExecId").unwrap();
            assert!(between[k..].contains(&"getJointPositions") && between.contains(&"sleep"), "{between:?}");
            let free = names[i..].iter().position(|n| *n == "pathBufferFree").unwrap();
            assert!(names[i..i + free].contains(&"getExecId"), "{:?}", &names[i..i + free]);
        }
    }
}

#[test]
fn lua_path_buffer_exports_move_nothing_on_another_arm() {
    if !have_lua() {
        return skipped("lua_path_buffer_exports_move_nothing_on_another_arm", NO_LUA);
    }
    let cfg = config(None);
    let p = program(&cfg);
    let script = aubo_lua_path_buffer(&p, &DhParams::AUBO_I5, &cfg, "十").unwrap();
    let moved = |calls: &[Call]| {
        calls.iter().any(|c| matches!(c.name.as_str(), "moveLine" | "moveJoint" | "movePathBuffer" | "setTcpOffset"))
    };
    // An upper arm 20 mm longer (within 2 µm, or with a calibrated beta, it would run).
    let longer = DhParams { a_m: [0.0, 0.0, 0.428, 0.376, 0.0, 0.0], ..DhParams::AUBO_I5 };
    let close_by = DhParams { a_m: [0.0, 0.0, 0.408 + 5e-7, 0.376, 0.0, 0.0], ..DhParams::AUBO_I5 };
    let nominal = kin_table(&DhParams::AUBO_I5, "");
    let cases = [
        (kin_table(&longer, ""), "differ from those the joint waypoints were computed with"),
        (kin_table(&DhParams::AUBO_I5, ", beta = {0, 0.001, 0, 0, 0, 0}"), "a beta that maobi does not model"),
        (kin_table(&DhParams::AUBO_I5, "").replacen("a = {0.0,", "a = {0/0,", 1), "(a) differ"),
        ("{a = {0, 0, 0.408, 0.376, 0, 0}}".to_string(), "lack six values of alpha"),
        ("nil".to_string(), "gave no table"),
    ];
    for (kin, needle) in &cases {
        let ran = run_lua_arm(&script, "status", kin, "follows", true);
        assert!(!ran.status.success() && ran.stderr.contains(needle), "{needle}: {}", ran.stderr);
        let calls = parse_calls(&ran.stdout);
        assert!(!moved(&calls), "{needle}: {calls:?}");
        assert_eq!(calls.iter().filter(|c| c.name == "getKinematicsParam").count(), 1, "{needle}");
    }
    for kin in [kin_table(&close_by, ""), kin_table(&DhParams::AUBO_I5, ", beta = {0, 0, 0, 0, 0, 0}")] {
        let ran = run_lua_arm(&script, "status", &kin, "follows", true);
        assert!(ran.status.success(), "{kin}: {}", ran.stderr);
    }
    // No sched.sleep: stopped before anything moved.
    let ran = run_lua_arm(&script, "status", &nominal, "follows", false);
    assert!(!ran.status.success() && ran.stderr.contains("no sched.sleep"), "{}", ran.stderr);
    assert!(!moved(&parse_calls(&ran.stdout)));
    // The arm not at the first waypoint (the controller chose another branch): the start and
    // the approach ran, no path buffer moved.
    let ran = run_lua_arm(&script, "status", &nominal, "stays", true);
    assert!(!ran.status.success() && ran.stderr.contains("not at the path buffer's first waypoint"), "{}", ran.stderr);
    let calls = parse_calls(&ran.stdout);
    assert!(calls.iter().any(|c| c.name == "moveLine") && !calls.iter().any(|c| c.name == "movePathBuffer"));
}

#[test]
fn lua_path_buffer_exports_on_the_arms_own_kinematics_run_on_that_arm() {
    if !have_lua() {
        return skipped("lua_path_buffer_exports_on_the_arms_own_kinematics_run_on_that_arm", NO_LUA);
    }
    let cfg = config(None);
    let p = program(&cfg);
    // Another i5 (upper arm 20 mm longer, shoulder zero 0.3° off), as `robot export
    // --kinematics ARM.json` gets it from `robot kinematics -o`.
    let mut theirs = DhParams::AUBO_I5;
    theirs.a_m[2] += 0.020;
    theirs.theta_rad[1] += 0.3f64.to_radians();
    let script = aubo_lua_path_buffer(&p, &theirs, &cfg, "十").unwrap();
    assert!(luac_check(&script).status.success());
    // On that arm: its kinematics check passes and every stroke runs as the program timed on it.
    let ran = run_lua_arm(&script, "status", &kin_table(&theirs, ""), "follows", true);
    assert!(ran.status.success(), "{}", ran.stderr);
    let calls = parse_calls(&ran.stdout);
    assert_eq!(calls.last().map(|c| c.name.as_str()), Some("done"));
    if let Err(e) = same_calls(&path_buffer_effects(&calls), &expected_path_buffer_calls(&p, &theirs, &cfg)) {
        panic!("{e}");
    }
    // The same script on a nominal arm moves nothing.
    let ran = run_lua_arm(&script, "status", &kin_table(&DhParams::AUBO_I5, ""), "follows", true);
    assert!(!ran.status.success() && ran.stderr.contains("differ from those the joint waypoints were computed with"));
    assert!(!parse_calls(&ran.stdout).iter().any(|c| c.name == "movePathBuffer" || c.name == "moveLine"));
}

// ---------------------------------------------------------------------------------------------
// G-code through gcodeparser (PyPI)

/// Reads a JSON list of G-code texts from standard input, parses each with
/// `gcodeparser.parse_gcode_lines` (one Python process for a whole batch), and prints a JSON
/// list with, per text, the commands it found: `{"line": N, "cmd": "G1", "params": {"X":
/// 40.0, ...}}` (comment-only lines are left out; a word without a value is `true`).
const GCODE_SCRIPT: &str = r#"
import json, sys
from gcodeparser import parse_gcode_lines
out = []
for text in json.load(sys.stdin):
    out.append([{"line": l.line_index + 1, "cmd": l.command_str, "params": l.params}
                for l in parse_gcode_lines(text, include_comments=False)])
print(json.dumps(out))
"#;

/// Whether python3 can import `gcodeparser`.
fn have_gcodeparser() -> bool {
    Command::new("python3").args(["-c", "import gcodeparser"]).output().is_ok_and(|o| o.status.success())
}

const NO_GCODEPARSER: &str = "python3 cannot import gcodeparser (`python3 -m pip install gcodeparser==0.3.0`)";

/// A command as gcodeparser read it.
#[derive(Debug, Clone, PartialEq)]
struct GCommand {
    line: usize,
    cmd: String,
    params: Vec<(String, f64)>,
}

impl GCommand {
    fn get(&self, letter: &str) -> Option<f64> {
        self.params.iter().find(|(l, _)| l == letter).map(|p| p.1)
    }
}

/// Every text of `texts` as gcodeparser reads it.
fn parse_gcode_external(texts: &[String]) -> Vec<Vec<GCommand>> {
    let input = serde_json::to_string(texts).unwrap();
    let ran = run_tool("python3", &["-c", GCODE_SCRIPT], &input).expect("python3 starts");
    assert!(ran.status.success(), "gcodeparser: {}", ran.stderr);
    let all: Vec<Vec<Value>> = serde_json::from_str(&ran.stdout).unwrap_or_else(|e| panic!("{e}: {}", ran.stdout));
    assert_eq!(all.len(), texts.len());
    all.iter()
        .map(|commands| {
            commands
                .iter()
                .map(|v| {
                    let params = v["params"]
                        .as_object()
                        .unwrap()
                        .iter()
                        // A word without a number (`true`) reads as NaN, which no check accepts.
                        .map(|(k, x)| (k.clone(), x.as_f64().unwrap_or(f64::NAN)))
                        .collect();
                    let line = v["line"].as_u64().unwrap() as usize;
                    GCommand { line, cmd: v["cmd"].as_str().unwrap().into(), params }
                })
                .collect()
        })
        .collect()
}

/// What the G-code of `track` must be, as the external parser reads it: only `G21`, `G90`,
/// `G0`, `G1`, `M2` (the first two first, `M2` last); each command's words from its own set;
/// per stroke a `G0` to its first point, a `G1` descent onto it at the write speed, then `G1`
/// moves to some of its points in order, each point left out within the merge tolerance of its
/// move, each feed rate F the move's length over the time `times` gives it (mm/min), never
/// above the write speed; plus `dip_g1` `G1`s per ink dip (down, and the soak when there is a
/// dwell); Z never below −`h_max_mm` except over the ink pot. Returns the number of pressed
/// `G1` moves (descents aside). `Err` names the line and what is wrong.
fn check_gcode(
    commands: &[GCommand],
    track: &Track,
    times: &PointTimes,
    cfg: &RobotConfig,
    dips: usize,
    dip_g1: usize,
    h_max_mm: f64,
) -> Result<usize, String> {
    let at = |c: &GCommand, what: String| Err(format!("line {}: `{}` {:?}: {what}", c.line, c.cmd, c.params));
    let names: Vec<&str> = commands.iter().map(|c| c.cmd.as_str()).collect();
    if names.len() < 3 || names[..2] != ["G21", "G90"] || names.last() != Some(&"M2") {
        return Err(format!("expected G21, G90 first and M2 last: {names:?}"));
    }
    if names.iter().filter(|n| **n == "M2").count() != 1 {
        return Err(format!("more than one M2: {names:?}"));
    }
    let write_f = cfg.write_speed_m_s * 60_000.0;
    // The plotter's work coordinates (robot.json `plotter.y_axis` `away`, the default): Y = −y.
    let xyz = |p: &TrackPoint| [p.x_mm, -p.y_mm, -p.h_mm];
    // The stroke being written and the last of its points reached.
    let mut stroke: Option<usize> = None;
    let mut reached: Option<usize> = None;
    let mut strokes_done = 0;
    let (mut g1, mut moves) = (0, 0);
    let (mut x, mut y) = (None::<f64>, None::<f64>);
    let over_pot = |x: Option<f64>, y: Option<f64>| {
        x.is_some_and(|x| close(x, POT_MM[0])) && y.is_some_and(|y| close(y, -POT_MM[1]))
    };
    let finish = |stroke: Option<usize>, reached: Option<usize>| -> Result<(), String> {
        match stroke {
            Some(s) if reached != Some(track.strokes[s].points.len() - 1) => {
                Err(format!("stroke {} ends at point {reached:?}, not its last", s + 1))
            }
            _ => Ok(()),
        }
    };
    for c in commands {
        let allowed: &[&str] = match c.cmd.as_str() {
            "G21" | "G90" | "M2" => &[],
            "G0" | "G1" => &["X", "Y", "Z", "F"],
            _ => return at(c, "not one of G21, G90, G0, G1, M2".into()),
        };
        if let Some((l, v)) = c.params.iter().find(|(l, v)| !allowed.contains(&l.as_str()) || !v.is_finite()) {
            return at(c, format!("word {l}{v} not expected"));
        }
        x = c.get("X").or(x);
        y = c.get("Y").or(y);
        if c.cmd == "G0" && c.get("X").is_some() && !over_pot(x, y) {
            // Travel to the next stroke's first point.
            finish(stroke, reached)?;
            let next = stroke.map_or(0, |s| s + 1);
            let Some(st) = track.strokes.get(next) else { return at(c, "travel after the last stroke".into()) };
            let p = xyz(&st.points[0]);
            if !(close(x.unwrap(), p[0]) && close(y.unwrap(), p[1])) {
                return at(c, format!("stroke {} starts at {p:?}", next + 1));
            }
            (stroke, reached) = (Some(next), None);
            strokes_done += 1;
        }
        if c.cmd == "G1" {
            g1 += 1;
            if c.get("X").is_some() {
                let Some(s) = stroke else { return at(c, "a pressed move before any stroke".into()) };
                let pts: Vec<[f64; 3]> = track.strokes[s].points.iter().map(xyz).collect();
                let read = [c.get("X").unwrap(), c.get("Y").unwrap_or(f64::NAN), c.get("Z").unwrap_or(f64::NAN)];
                let f = c.get("F").unwrap_or(f64::NAN);
                let same = |j: usize| read.iter().zip(pts[j]).all(|(r, w)| close(*r, w));
                match reached {
                    None => {
                        if !same(0) || !close(f, write_f) {
                            return at(c, format!("the descent onto {:?} at F{write_f}", pts[0]));
                        }
                        reached = Some(0);
                    }
                    Some(a) => {
                        let Some(b) = (a + 1..pts.len()).find(|&j| same(j)) else {
                            return at(c, format!("no point of stroke {} after point {}", s + 1, a + 1));
                        };
                        let v = |j: usize| nalgebra::Vector3::from(pts[j]);
                        let ab = v(b) - v(a);
                        for i in a + 1..b {
                            let t = ((v(i) - v(a)).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
                            let off = (v(a) + ab * t - v(i)).norm();
                            if off > GCODE_MERGE_TOLERANCE_MM + 1e-9 {
                                return at(c, format!("point {} left out lies {off} mm from the move", i + 1));
                            }
                        }
                        let want = match &times.strokes[s] {
                            Some(t) => 60.0 * ab.norm() / (t[b] - t[a]),
                            None => write_f,
                        };
                        if !((f - want).abs() <= 1e-9 * want && f > 0.0 && f <= write_f * (1.0 + 1e-9)) {
                            return at(c, format!("feed rate F{f} where the timing gives {want} (at most {write_f})"));
                        }
                        reached = Some(b);
                        moves += 1;
                    }
                }
            }
        }
        if let Some(z) = c.get("Z")
            && z < -h_max_mm
            && !over_pot(x, y)
        {
            return at(c, format!("Z below -{h_max_mm} mm away from the ink pot"));
        }
    }
    finish(stroke, reached)?;
    if strokes_done != track.strokes.len() || g1 != strokes_done + moves + dips * dip_g1 {
        return Err(format!(
            "{g1} G1 moves over {strokes_done} strokes ({moves} pressed) where the track has {} strokes and {dips} dips of {dip_g1}",
            track.strokes.len()
        ));
    }
    Ok(moves)
}

#[test]
fn gcode_exports_read_by_gcodeparser_match_the_track() {
    if !have_gcodeparser() {
        return skipped("gcode_exports_read_by_gcodeparser_match_the_track", NO_GCODEPARSER);
    }
    let track = small_track();
    let h_max_mm = pen1().ranges.h_mm.max;
    // (settings, dips, G1 per dip: down, and the soak when there is a dwell)
    let cases = [(config(Some(0.5)), 2, 2), (config(Some(0.0)), 2, 1), (config(None), 0, 0)];
    let texts: Vec<String> = cases.iter().map(|(cfg, ..)| gcode(&track, &times(cfg), cfg, "十").unwrap().0).collect();
    for (((cfg, dips, dip_g1), text), commands) in cases.iter().zip(&texts).zip(parse_gcode_external(&texts)) {
        let (dips, dip_g1) = (*dips, *dip_g1);
        match check_gcode(&commands, &track, &times(cfg), cfg, dips, dip_g1, h_max_mm) {
            // (60, 61, 18) lies 0.1 mm off its neighbours' line: no point is left out.
            Ok(moves) => assert_eq!(moves, track.point_count() - track.strokes.len(), "{text}"),
            Err(e) => panic!("{e}\n{text}"),
        }
        // The feed rates come from the timing: slower than the write speed where it slows.
        let feeds: Vec<f64> =
            commands.iter().filter(|c| c.cmd == "G1" && c.get("X").is_some()).filter_map(|c| c.get("F")).collect();
        assert!(feeds.iter().any(|f| *f < 0.9 * cfg.write_speed_m_s * 60_000.0), "{feeds:?}");
        // Below the brush's deepest press only in the pot: the check above is not vacuous.
        let deepest = commands.iter().filter_map(|c| c.get("Z")).fold(f64::INFINITY, f64::min);
        assert_eq!(deepest < -h_max_mm, dips > 0, "{deepest}");
    }
}

#[test]
fn hostile_titles_add_no_gcode_command() {
    if !have_gcodeparser() {
        return skipped("hostile_titles_add_no_gcode_command", NO_GCODEPARSER);
    }
    let track = small_track();
    let cfg = config(Some(0.5));
    let texts: Vec<String> = std::iter::once(&"t")
        .chain(HOSTILE_TITLES)
        .map(|title| gcode(&track, &times(&cfg), &cfg, title).unwrap().0)
        .collect();
    let read = parse_gcode_external(&texts);
    assert!(!read[0].is_empty());
    for ((title, text), commands) in HOSTILE_TITLES.iter().zip(&texts[1..]).zip(&read[1..]) {
        assert_eq!(commands, &read[0], "{title:?}\n{text}");
    }
}

/// The external check sees what it is meant to catch: a plunge on its own line, one in a
/// `( … )` comment (which gcodeparser, like some senders, does not treat as a comment), a
/// command it does not allow and a pressed point moved.
#[test]
fn gcode_harness_catches_injected_commands() {
    if !have_gcodeparser() {
        return skipped("gcode_harness_catches_injected_commands", NO_GCODEPARSER);
    }
    let track = small_track();
    let cfg = config(Some(0.5));
    let h_max_mm = pen1().ranges.h_mm.max;
    let text = gcode(&track, &times(&cfg), &cfg, "t").unwrap().0;
    let (first, rest) = text.split_once('\n').unwrap();
    let cases = [
        (format!("{first}\nG1 Z-40 F3000\n{rest}"), "G21, G90 first"),
        (text.replacen("Y-60.000000 F6000.000000\n", "Y-60.000000 F6000.000000\nG1 Z-40 F3000\n", 1), "Z below"),
        (format!("{first}\n(G1 Z-40)\n{rest}"), "G21, G90 first"),
        (text.replacen("G21 ; millimetres", "G21 (M3 S1000) ; millimetres", 1), "M3"),
        (text.replacen("M2", "M2\nG0 Z20", 1), "M2 last"),
        (text.replacen("X50.000000", "X51.000000", 1), "no point of stroke 1 after point 1"),
        (
            {
                let line = text.lines().find(|l| l.starts_with("G1 X50.000000")).unwrap();
                let slow = format!("{} F1.000000", line.split(" F").next().unwrap());
                text.replacen(line, &slow, 1)
            },
            "feed rate F1 where the timing gives",
        ),
        (text.replacen("X50.000000 Y-60.000000 Z-16.500000", "X50.000000 Y-60.000000 Z-16.500000 E5", 1), "word E"),
    ];
    let texts: Vec<String> = std::iter::once(text.clone()).chain(cases.iter().map(|c| c.0.clone())).collect();
    let read = parse_gcode_external(&texts);
    let t = times(&cfg);
    assert!(check_gcode(&read[0], &track, &t, &cfg, 2, 2, h_max_mm).is_ok());
    for ((bad, needle), commands) in cases.iter().zip(&read[1..]) {
        assert_ne!(bad, &text, "{needle}");
        let e = check_gcode(commands, &track, &t, &cfg, 2, 2, h_max_mm).unwrap_err();
        assert!(e.contains(needle), "{needle}: {e}");
    }
}
