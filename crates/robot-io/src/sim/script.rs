//! The simulator's script port (AUBO's 30002): a script arrives as one string ending in a blank
//! line (`\r\n\r\n`, as AUBO's script protocol and the SDK's `ScriptClient.sendString` send it)
//! and runs in a real Lua 5.4 (mlua, feature `lua`), against the simulator's own `aubo`
//! bindings: `require('aubo')`, `aubo.sched.select_robot(1)` returning the robot's environment
//! with its methods as globals (the subset maobi's scripts call, with the argument types of
//! AUBO's documented Lua prototypes), and `sched.sleep`. Every motion goes through the same
//! request handling as the JSON-RPC transports, so it is checked and traced the same way. A
//! script that calls anything else, passes a wrong argument or has a move refused fails there,
//! its error naming the line.
//!
//! The runtime's state is served over JSON-RPC as the SDK asks for it (checked with
//! `pyaubo_sdk` 0.24.1): `RuntimeMachine.getStatus` and `getRuntimeState` answer the enum's name
//! (`"Running"`, `"Stopped"`: the SDK reads an integer as `Running` whatever it is),
//! `RuntimeMachine.stop`/`abort` stop a running script, `RegisterControl.getInt32`/`setInt32`
//! (params `{key, default_value}`, `{key, value}`) read and write its named integers.
//!
//! Bounded: a script of at most [`MAX_LUA_SCRIPT_BYTES`], one script at a time, at most
//! [`LUA_MEMORY_BYTES`] of Lua memory, [`MAX_INSTRUCTIONS`] instructions and [`MAX_SCRIPT_TIME`]
//! of wall time; at most [`MAX_NAMED_INTS`] named integers.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use serde_json::{Value, json};

use super::dispatch::Shared;

/// The longest script the port reads, bytes (a path-buffer script of 永 is about 1.4 MB).
pub const MAX_LUA_SCRIPT_BYTES: usize = 8 << 20;
/// Most Lua memory one script may use, bytes.
pub const LUA_MEMORY_BYTES: usize = 256 << 20;
/// Most Lua instructions one script may run.
pub const MAX_INSTRUCTIONS: u64 = 4_000_000_000;
/// Longest one script may run (wall clock).
pub const MAX_SCRIPT_TIME: Duration = Duration::from_secs(600);
/// Most named integers kept (`setInt32`); keys of at most 64 bytes.
pub const MAX_NAMED_INTS: usize = 1024;
/// Script errors kept (the latest).
const MAX_ERRORS: usize = 64;

/// The script runtime: whether a script runs, its named integers, the stop request, the errors.
#[derive(Debug, Default)]
pub(super) struct ScriptState {
    inner: Mutex<Inner>,
    stop: AtomicBool,
}

#[derive(Debug, Default)]
struct Inner {
    running: bool,
    ints: BTreeMap<String, i32>,
    errors: Vec<String>,
    scripts: usize,
}

impl ScriptState {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Records a script's failure (or refusal).
    pub(super) fn error(&self, e: String) {
        let mut i = self.lock();
        if i.errors.len() >= MAX_ERRORS {
            i.errors.remove(0);
        }
        i.errors.push(e);
    }

    /// The failures recorded, oldest first.
    pub(super) fn errors(&self) -> Vec<String> {
        self.lock().errors.clone()
    }

    /// Scripts run (finished or failed).
    pub(super) fn scripts(&self) -> usize {
        self.lock().scripts
    }

    fn set_int(&self, key: &str, v: i32) -> Result<(), String> {
        if key.is_empty() || key.len() > 64 {
            return Err(format!("a named integer's key must be 1 to 64 bytes, got {} bytes", key.len()));
        }
        let mut i = self.lock();
        if i.ints.len() >= MAX_NAMED_INTS && !i.ints.contains_key(key) {
            return Err(format!("more than {MAX_NAMED_INTS} named integers"));
        }
        i.ints.insert(key.to_string(), v);
        Ok(())
    }

    fn get_int(&self, key: &str, default: i32) -> i32 {
        self.lock().ints.get(key).copied().unwrap_or(default)
    }
}

/// The JSON-RPC calls of the script runtime; `None` for every other method.
pub(super) fn handle(method: &str, params: &Value, shared: &Shared) -> Option<Result<Value, String>> {
    let arg = |name: &str, pos: usize| match params {
        Value::Object(m) => m.get(name),
        Value::Array(a) => a.get(pos),
        _ => None,
    };
    let s = &shared.script;
    Some(match method {
        "RuntimeMachine.getStatus" | "RuntimeMachine.getRuntimeState" => {
            Ok(json!(if s.lock().running { "Running" } else { "Stopped" }))
        }
        "RuntimeMachine.stop" | "RuntimeMachine.abort" => {
            if s.lock().running {
                s.stop.store(true, Ordering::SeqCst);
            }
            Ok(json!(0))
        }
        "RegisterControl.getInt32" => match (arg("key", 0).and_then(Value::as_str), arg("default_value", 1)) {
            (Some(k), Some(d)) => match d.as_i64().and_then(|d| i32::try_from(d).ok()) {
                Some(d) => Ok(json!(s.get_int(k, d))),
                None => Err("getInt32: default_value must be an int32".into()),
            },
            _ => Err("getInt32 takes `key` (a string) and `default_value` (an int32)".into()),
        },
        "RegisterControl.setInt32" => match (arg("key", 0).and_then(Value::as_str), arg("value", 1)) {
            (Some(k), Some(v)) => match v.as_i64().and_then(|v| i32::try_from(v).ok()) {
                Some(v) => s.set_int(k, v).map(|()| json!(0)),
                None => Err("setInt32: value must be an int32".into()),
            },
            _ => Err("setInt32 takes `key` (a string) and `value` (an int32)".into()),
        },
        _ => return None,
    })
}

/// Splits the scripts out of a connection's bytes: each ends with `\r\n\r\n`. Returns the
/// complete ones (without the terminator), or why the connection must close (a script longer
/// than [`MAX_LUA_SCRIPT_BYTES`], or not UTF-8).
pub(super) fn take_scripts(buf: &mut Vec<u8>) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    while let Some(i) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
        let script: Vec<u8> = buf.drain(..i + 4).take(i).collect();
        out.push(String::from_utf8(script).map_err(|_| "a script that is not UTF-8".to_string())?);
    }
    if buf.len() > MAX_LUA_SCRIPT_BYTES {
        return Err(format!("a script longer than {MAX_LUA_SCRIPT_BYTES} bytes"));
    }
    Ok(out)
}

/// Runs `text` as a script on the simulator's arm, on this thread; the error (naming the line)
/// when it fails. Refused at once while another script runs.
pub(super) fn run(text: &str, shared: &Arc<Shared>) -> Result<(), String> {
    {
        let mut i = shared.script.lock();
        if i.running {
            return Err("refused: another script is running (the runtime runs one at a time)".into());
        }
        i.running = true;
        i.scripts += 1;
    }
    shared.script.stop.store(false, Ordering::SeqCst);
    let session = shared.new_session();
    let r = lua::run(text, shared, session);
    shared.release(session);
    shared.script.lock().running = false;
    r
}

#[cfg(not(feature = "lua"))]
mod lua {
    use super::{Arc, Shared};

    pub(super) fn run(_text: &str, _shared: &Arc<Shared>, _session: u64) -> Result<(), String> {
        Err("this simulator was built without Lua (robot-io's feature `lua`): it cannot run scripts".into())
    }
}

#[cfg(feature = "lua")]
mod lua {
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::time::Instant;

    use mlua::{HookTriggers, Lua, LuaOptions, MultiValue, StdLib, Table, Value as LuaValue, VmState};
    use serde_json::{Value, json};

    use super::{Arc, LUA_MEMORY_BYTES, MAX_INSTRUCTIONS, MAX_SCRIPT_TIME, Shared};
    use crate::sim::SIM_ROBOT;
    use crate::sim::dispatch::{Reply, handle};

    /// An argument type of a binding, as AUBO's Lua prototypes name them.
    #[derive(Clone, Copy)]
    enum Arg {
        /// `table` of six numbers.
        Six,
        /// `table` of six-number tables (waypoints).
        Waypoints,
        /// `number`.
        Number,
        /// `string`.
        Text,
        /// `boolean`.
        Bool,
    }

    /// What a binding gives back.
    #[derive(Clone, Copy)]
    enum Ret {
        /// The JSON-RPC result as it is (a number, a table, a boolean).
        Plain,
        /// A status: a negative one fails the script (a refused move), others are returned.
        Status,
        /// The SDK's `(values, status)` as Lua's two results.
        Pair,
    }

    /// The robot's methods the environment holds: the Lua name, the JSON-RPC method (after
    /// `rob1.`), the arguments and what comes back (AUBO's SDK headers, `@par Lua函数原型`).
    const BINDINGS: &[(&str, &str, &[Arg], Ret)] = &[
        ("setTcpOffset", "RobotConfig.setTcpOffset", &[Arg::Six], Ret::Status),
        ("setSpeedFraction", "MotionControl.setSpeedFraction", &[Arg::Number], Ret::Status),
        (
            "moveJoint",
            "MotionControl.moveJoint",
            &[Arg::Six, Arg::Number, Arg::Number, Arg::Number, Arg::Number],
            Ret::Status,
        ),
        (
            "moveLine",
            "MotionControl.moveLine",
            &[Arg::Six, Arg::Number, Arg::Number, Arg::Number, Arg::Number],
            Ret::Status,
        ),
        ("inverseKinematics", "RobotAlgorithm.inverseKinematics", &[Arg::Six, Arg::Six], Ret::Pair),
        ("forwardKinematics", "RobotAlgorithm.forwardKinematics", &[Arg::Six], Ret::Pair),
        ("getJointPositions", "RobotState.getJointPositions", &[], Ret::Plain),
        ("getTcpPose", "RobotState.getTcpPose", &[], Ret::Plain),
        ("isSteady", "RobotState.isSteady", &[], Ret::Plain),
        ("getExecId", "MotionControl.getExecId", &[], Ret::Plain),
        ("getKinematicsParam", "RobotConfig.getKinematicsParam", &[Arg::Bool], Ret::Plain),
        ("pathBufferAlloc", "MotionControl.pathBufferAlloc", &[Arg::Text, Arg::Number, Arg::Number], Ret::Status),
        ("pathBufferAppend", "MotionControl.pathBufferAppend", &[Arg::Text, Arg::Waypoints], Ret::Status),
        ("pathBufferEval", "MotionControl.pathBufferEval", &[Arg::Text, Arg::Six, Arg::Six, Arg::Number], Ret::Status),
        ("pathBufferValid", "MotionControl.pathBufferValid", &[Arg::Text], Ret::Plain),
        ("pathBufferFree", "MotionControl.pathBufferFree", &[Arg::Text], Ret::Status),
        ("movePathBuffer", "MotionControl.movePathBuffer", &[Arg::Text], Ret::Status),
    ];

    /// The current line of the script (the caller of a binding), for messages.
    fn line(lua: &Lua) -> String {
        lua.inspect_stack(1, |d| d.current_line()).flatten().map_or("script".into(), |l| format!("script:{l}"))
    }

    fn fail(lua: &Lua, msg: String) -> mlua::Error {
        mlua::Error::RuntimeError(format!("{}: {msg}", line(lua)))
    }

    /// A Lua argument as JSON, checked against `want`.
    fn to_json(v: &LuaValue, want: Arg) -> Option<Value> {
        let number = |v: &LuaValue| match v {
            LuaValue::Integer(i) => Some(*i as f64),
            LuaValue::Number(n) => Some(*n),
            _ => None,
        };
        let six = |v: &LuaValue| -> Option<Vec<f64>> {
            let LuaValue::Table(t) = v else { return None };
            if t.raw_len() != 6 {
                return None;
            }
            (1..=6).map(|i| t.raw_get::<LuaValue>(i).ok().as_ref().and_then(number)).collect()
        };
        match want {
            Arg::Six => six(v).map(|x| json!(x)),
            Arg::Waypoints => {
                let LuaValue::Table(t) = v else { return None };
                let n = t.raw_len();
                if n == 0 || n > crate::timing::MAX_STROKE_WAYPOINTS {
                    return None;
                }
                let w: Option<Vec<Vec<f64>>> =
                    (1..=n).map(|i| t.raw_get::<LuaValue>(i).ok().as_ref().and_then(six)).collect();
                w.map(|w| json!(w))
            }
            // Lua 5.4's integers stay integers (a path buffer's type and size are).
            Arg::Number => match v {
                LuaValue::Integer(i) => Some(json!(i)),
                _ => number(v).map(|x| json!(x)),
            },
            Arg::Text => match v {
                LuaValue::String(s) => s.to_str().ok().map(|s| json!(s.to_string())),
                _ => None,
            },
            Arg::Bool => match v {
                LuaValue::Boolean(b) => Some(json!(b)),
                _ => None,
            },
        }
    }

    /// A JSON result as a Lua value (arrays as sequences, objects as tables with string keys).
    fn to_lua(lua: &Lua, v: &Value) -> mlua::Result<LuaValue> {
        Ok(match v {
            Value::Null => LuaValue::Nil,
            Value::Bool(b) => LuaValue::Boolean(*b),
            Value::Number(n) => match n.as_i64() {
                Some(i) => LuaValue::Integer(i),
                None => LuaValue::Number(n.as_f64().unwrap_or(f64::NAN)),
            },
            Value::String(s) => LuaValue::String(lua.create_string(s)?),
            Value::Array(a) => {
                let t = lua.create_table()?;
                for (i, x) in a.iter().enumerate() {
                    t.raw_set(i + 1, to_lua(lua, x)?)?;
                }
                LuaValue::Table(t)
            }
            Value::Object(m) => {
                let t = lua.create_table()?;
                for (k, x) in m {
                    t.raw_set(k.as_str(), to_lua(lua, x)?)?;
                }
                LuaValue::Table(t)
            }
        })
    }

    /// The robot's environment: the bindings, `setInt32`/`getInt32`, `textmsg`, falling back to
    /// the (sandboxed) globals.
    fn robot_env(lua: &Lua, shared: &Arc<Shared>, session: u64) -> mlua::Result<Table> {
        let env = lua.create_table()?;
        for &(name, method, args, ret) in BINDINGS {
            let sh = shared.clone();
            let f = lua.create_function(move |lua, a: MultiValue| {
                let a: Vec<LuaValue> = a.into_iter().collect();
                let sig = || {
                    let t: Vec<&str> = args
                        .iter()
                        .map(|x| match x {
                            Arg::Six => "table of six numbers",
                            Arg::Waypoints => "table of six-number tables",
                            Arg::Number => "number",
                            Arg::Text => "string",
                            Arg::Bool => "boolean",
                        })
                        .collect();
                    format!("{name}({})", t.join(", "))
                };
                if a.len() != args.len() {
                    return Err(fail(lua, format!("{} takes {} arguments, got {}", sig(), args.len(), a.len())));
                }
                let mut params = Vec::new();
                for (k, (v, want)) in a.iter().zip(args).enumerate() {
                    let j = to_json(v, *want)
                        .ok_or_else(|| fail(lua, format!("{}: argument {} is a {}", sig(), k + 1, v.type_name())))?;
                    params.push(j);
                }
                let req =
                    json!({"jsonrpc": "2.0", "method": format!("{SIM_ROBOT}.{method}"), "params": params, "id": 1});
                let result = match handle(&req, &sh, session) {
                    Reply::Answer(v) => v,
                    Reply::Drop => return Err(fail(lua, format!("{name}: the controller dropped the request"))),
                };
                if let Some(e) = result.get("error") {
                    return Err(fail(
                        lua,
                        format!("{name}: {}", e.get("message").and_then(Value::as_str).unwrap_or("error")),
                    ));
                }
                let r = result.get("result").cloned().unwrap_or(Value::Null);
                let mut out = MultiValue::new();
                match ret {
                    Ret::Plain => out.push_back(to_lua(lua, &r)?),
                    Ret::Status => {
                        let code = r.as_i64().unwrap_or(0);
                        if code < 0 {
                            return Err(fail(lua, format!("{name} refused by the controller (status {code})")));
                        }
                        out.push_back(LuaValue::Integer(code));
                    }
                    Ret::Pair => {
                        let (v, code) =
                            (r.get(0).cloned().unwrap_or(Value::Null), r.get(1).and_then(Value::as_i64).unwrap_or(0));
                        out.push_back(to_lua(lua, &v)?);
                        out.push_back(LuaValue::Integer(code));
                    }
                }
                Ok(out)
            })?;
            env.raw_set(name, f)?;
        }
        let sh = shared.clone();
        env.raw_set(
            "setInt32",
            lua.create_function(move |lua, (key, v): (LuaValue, LuaValue)| {
                let (Some(Value::String(k)), Some(v)) = (to_json(&key, Arg::Text), to_json(&v, Arg::Number)) else {
                    return Err(fail(lua, "setInt32(key: string, value: number)".into()));
                };
                let v = v.as_f64().filter(|v| v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX)).map(|v| v as i32);
                let v = v.ok_or_else(|| fail(lua, "setInt32: the value is not an int32".into()))?;
                sh.script.set_int(&k, v).map_err(|e| fail(lua, e))
            })?,
        )?;
        let sh = shared.clone();
        env.raw_set(
            "getInt32",
            lua.create_function(move |lua, (key, d): (LuaValue, LuaValue)| {
                let (Some(Value::String(k)), Some(d)) = (to_json(&key, Arg::Text), to_json(&d, Arg::Number)) else {
                    return Err(fail(lua, "getInt32(key: string, default_value: number)".into()));
                };
                Ok(sh.script.get_int(&k, d.as_f64().unwrap_or(0.0) as i32))
            })?,
        )?;
        env.raw_set("textmsg", lua.create_function(|_, _msg: LuaValue| Ok(()))?)?;
        let meta = lua.create_table()?;
        meta.raw_set("__index", lua.globals())?;
        env.set_metatable(Some(meta))?;
        Ok(env)
    }

    pub(super) fn run(text: &str, shared: &Arc<Shared>, session: u64) -> Result<(), String> {
        let e = |e: mlua::Error| format!("{e}");
        // The base library (minus what reaches files, the process or other chunks), tables,
        // strings, maths and UTF-8: no io, os, package, debug.
        let lua = Lua::new_with(StdLib::TABLE | StdLib::STRING | StdLib::MATH | StdLib::UTF8, LuaOptions::new())
            .map_err(e)?;
        lua.set_memory_limit(LUA_MEMORY_BYTES).map_err(e)?;
        let g = lua.globals();
        for name in ["load", "loadfile", "dofile", "collectgarbage", "require", "print", "rawequal"] {
            g.raw_set(name, LuaValue::Nil).map_err(e)?;
        }
        // Bounded: a stop request, the instruction budget, the wall clock.
        let (sh, count, t0) = (shared.clone(), Arc::new(AtomicU64::new(0)), Instant::now());
        const EVERY: u32 = 10_000;
        lua.set_hook(HookTriggers::new().every_nth_instruction(EVERY), move |lua, _| {
            let n = count.fetch_add(u64::from(EVERY), Ordering::Relaxed);
            if sh.script.stop.load(Ordering::SeqCst) {
                return Err(fail(lua, "stopped (RuntimeMachine.stop)".into()));
            }
            if n > MAX_INSTRUCTIONS || t0.elapsed() > MAX_SCRIPT_TIME {
                return Err(fail(lua, "the script ran longer than the simulator allows".into()));
            }
            Ok(VmState::Continue)
        })
        .map_err(e)?;
        let env = robot_env(&lua, shared, session).map_err(e)?;
        // require('aubo'): sched.select_robot(1) gives the robot's environment; sched.sleep.
        let sched = lua.create_table().map_err(e)?;
        sched
            .raw_set(
                "select_robot",
                lua.create_function(move |lua, n: LuaValue| match n {
                    LuaValue::Integer(1) => Ok(env.clone()),
                    LuaValue::Number(1.0) => Ok(env.clone()),
                    _ => Err(fail(lua, format!("select_robot: no robot {n:?} (the simulator has robot 1)"))),
                })
                .map_err(e)?,
            )
            .map_err(e)?;
        let sh = shared.clone();
        sched
            .raw_set(
                "sleep",
                lua.create_function(move |lua, t: LuaValue| {
                    let t = match t {
                        LuaValue::Integer(i) => i as f64,
                        LuaValue::Number(x) => x,
                        _ => return Err(fail(lua, "sleep(seconds: number)".into())),
                    };
                    if !(t.is_finite() && t >= 0.0) {
                        return Err(fail(lua, format!("sleep: {t} s")));
                    }
                    // The simulator's moves take no wall time: a short pause is enough.
                    std::thread::sleep(std::time::Duration::from_secs_f64(t.min(0.002)));
                    if sh.script.stop.load(Ordering::SeqCst) {
                        return Err(fail(lua, "stopped (RuntimeMachine.stop)".into()));
                    }
                    Ok(())
                })
                .map_err(e)?,
            )
            .map_err(e)?;
        let aubo = lua.create_table().map_err(e)?;
        aubo.raw_set("sched", sched).map_err(e)?;
        g.raw_set(
            "require",
            lua.create_function(move |lua, name: LuaValue| match &name {
                LuaValue::String(s) if s.as_bytes().as_ref() == b"aubo" => Ok(aubo.clone()),
                _ => Err(fail(lua, format!("module {name:?} not found (the simulator has `aubo`)"))),
            })
            .map_err(e)?,
        )
        .map_err(e)?;
        let main: LuaValue = lua.load(text).set_name("=script").eval().map_err(e)?;
        if let LuaValue::Function(f) = main {
            let api = lua.create_table().map_err(e)?;
            f.call::<()>(api).map_err(e)?;
        }
        Ok(())
    }
}

impl super::Simulator {
    /// Also serves AUBO's script port on `bind` (for example `127.0.0.1:30002`): each script
    /// received (ending in `\r\n\r\n`) runs in Lua 5.4 on this simulator's arm, one at a time;
    /// a failure is kept ([`super::Simulator::script_errors`]). Connections count against
    /// [`super::SimOptions::max_connections`] and close after
    /// [`super::SimOptions::idle_timeout`] without a byte other than whitespace.
    ///
    /// # Errors
    /// [`crate::RobotError::Io`] if the address cannot be bound.
    pub fn serve_scripts(&self, bind: &str) -> Result<std::net::SocketAddr, crate::RobotError> {
        use std::io::Read;
        let io = |source| crate::RobotError::Io { context: bind.to_string(), source };
        let listener = std::net::TcpListener::bind(bind).map_err(io)?;
        let addr = listener.local_addr().map_err(io)?;
        listener.set_nonblocking(true).map_err(io)?;
        let (shared, stop) = (self.shared.clone(), self.stop.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::SeqCst) {
                let Ok((mut stream, _)) = listener.accept() else {
                    std::thread::sleep(Duration::from_millis(5));
                    continue;
                };
                if shared.connections.load(Ordering::SeqCst) >= shared.options.max_connections {
                    continue;
                }
                shared.connections.fetch_add(1, Ordering::SeqCst);
                let (shared, stop) = (shared.clone(), stop.clone());
                std::thread::spawn(move || {
                    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
                    let (mut buf, mut chunk, mut last) = (Vec::new(), vec![0u8; 64 * 1024], std::time::Instant::now());
                    while !stop.load(Ordering::SeqCst) && last.elapsed() < shared.options.idle_timeout {
                        match stream.read(&mut chunk) {
                            Ok(0) => break,
                            Ok(n) => {
                                if chunk[..n].iter().any(|b| !b.is_ascii_whitespace()) {
                                    last = std::time::Instant::now();
                                }
                                buf.extend_from_slice(&chunk[..n]);
                                match take_scripts(&mut buf) {
                                    Ok(scripts) => {
                                        for s in scripts {
                                            if let Err(e) = run(&s, &shared) {
                                                shared.script.error(e);
                                            }
                                        }
                                    }
                                    Err(e) => {
                                        shared.script.error(format!("script refused: {e}"));
                                        break;
                                    }
                                }
                            }
                            Err(e)
                                if matches!(
                                    e.kind(),
                                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                                ) => {}
                            Err(_) => break,
                        }
                    }
                    shared.connections.fetch_sub(1, Ordering::SeqCst);
                });
            }
        });
        Ok(addr)
    }

    /// The scripts' failures and refusals, oldest first (the latest 64), each naming the line.
    pub fn script_errors(&self) -> Vec<String> {
        self.shared.script.errors()
    }

    /// Scripts run on the script port (finished or failed).
    pub fn scripts_run(&self) -> usize {
        self.shared.script.scripts()
    }
}
