//! [`AuboScript`]: the program as one ARCS Lua script in the form of AUBO's script
//! documentation, sent on the script port (30002) as AUBO documents it (one string ending in a
//! blank line, `\r\n\r\n`), and followed through the JSON-RPC port's state calls
//! (`RuntimeMachine.getStatus`, `RegisterControl.getInt32("maobi_strokes")`, the TCP pose), as
//! AUBO's own SDK examples follow a script (`example_script.py`: `getRuntimeMachine().getStatus()`
//! until it is no longer `Running`).

use std::time::{Duration, Instant};

use serde_json::{Value, json};

use super::client::check_script;
use super::{AuboClient, Link, METHOD_NOT_FOUND, Motion, NominalKinematicsPolicy, send_script};
use crate::RobotError;
use crate::controller::{
    Controller, Plan, Position, Preflight, Prepared, Progress, RunSummary, Watch, expected_seconds,
};
use crate::export::{PROGRESS_VARIABLE, aubo_lua, aubo_lua_path_buffer};
use crate::follow::{Commanded, Expect, Sent, check_pose, distance_m, lift_words, program_box, run_stopped};
use crate::kinematics::DhParams;
use crate::pose::Pose;
use crate::program::{Move, Program, RobotConfig, compact_program};

/// How long the controller has to start a script it was sent.
pub const SCRIPT_START_WAIT: Duration = Duration::from_secs(5);
/// How often the run is polled.
const POLL: Duration = Duration::from_millis(20);

/// An AUBO controller running the program as one Lua script (see the module documentation).
///
/// [`Controller::prepare`] writes and checks the script on the nominal AUBO-i5 (for
/// [`Motion::PathBuffer`]) or the compacted moves; [`Controller::connect`] logs in over
/// JSON-RPC, reads the controller's kinematics and writes the script again on them (checked as
/// written; the script itself compares them with the controller's before anything moves), and
/// checks that no script runs, the arm is idle and within reach; [`Controller::run`] sends the
/// script and follows it: the strokes it reports done, its pose on the commanded path; Ctrl-C
/// or a script that stops early stops it (`RuntimeMachine.stop`) and lifts the brush.
///
/// # Examples
/// ```no_run
/// use std::time::Duration;
/// use robot_io::aubo::{AuboScript, Link, Motion};
/// use robot_io::Controller;
/// let c = AuboScript::new("192.168.1.10:30004", "192.168.1.10:30002", Link::default(), Duration::from_secs(2), Motion::PathBuffer);
/// assert!(c.describe().contains("script"));
/// ```
pub struct AuboScript {
    rpc_addr: String,
    script_addr: String,
    link: Link,
    timeout: Duration,
    motion: Motion,
    nominal: NominalKinematicsPolicy,
    ready: Option<Ready>,
    conn: Option<(AuboClient, String)>,
}

struct Ready {
    program: Program,
    config: RobotConfig,
    title: String,
    script: String,
    strokes_s: Vec<f64>,
    near: ([f64; 3], [f64; 3]),
    /// Whether the script's joints were computed on maobi's nominal parameters.
    nominal: bool,
}

impl AuboScript {
    /// A controller whose JSON-RPC port is `rpc_addr` and script port `script_addr`.
    pub fn new(rpc_addr: &str, script_addr: &str, link: Link, timeout: Duration, motion: Motion) -> Self {
        Self {
            rpc_addr: rpc_addr.into(),
            script_addr: script_addr.into(),
            link,
            timeout,
            motion,
            nominal: NominalKinematicsPolicy::default(),
            ready: None,
            conn: None,
        }
    }

    /// As [`super::AuboRpc::nominal_kinematics`].
    pub fn nominal_kinematics(mut self, nominal: bool, accept: bool) -> Self {
        self.nominal = NominalKinematicsPolicy { nominal, accept };
        self
    }

    fn script_for(
        &self,
        program: &Program,
        cfg: &RobotConfig,
        kin: &DhParams,
        title: &str,
    ) -> Result<String, RobotError> {
        let s = match self.motion {
            Motion::Moves => aubo_lua(program, title)?,
            Motion::PathBuffer => aubo_lua_path_buffer(program, kin, cfg, title)?,
        };
        check_script(&s)?;
        Ok(s)
    }

    /// `params` as this transport sends them: `named` on framed and HTTP, `positional` on lines.
    fn params(&self, named: Value, positional: Value) -> Value {
        if self.link.transport.named_params() { named } else { positional }
    }
}

/// The controller's runtime state (`RuntimeMachine.getStatus`: the enum's name).
fn status(c: &mut AuboClient) -> Result<String, RobotError> {
    let m = "RuntimeMachine.getStatus";
    match c.call(m, Value::Null)? {
        Value::String(s) if s.len() <= 32 && s.bytes().all(|b| b.is_ascii_alphabetic()) => Ok(s),
        v => Err(RobotError::Protocol(format!("{m}: expected the runtime state's name, got {v}"))),
    }
}

impl Controller for AuboScript {
    fn describe(&self) -> String {
        format!("AUBO Lua script on {} (followed over {} at {})", self.script_addr, self.link.transport, self.rpc_addr)
    }

    fn prepare(&mut self, plan: &Plan<'_>) -> Result<Prepared, RobotError> {
        let cfg = plan.config;
        let program = match self.motion {
            Motion::Moves => {
                let p = compact_program(plan.program, cfg);
                crate::program::check_blends(&p)?;
                p
            }
            Motion::PathBuffer => plan.program.clone(),
        };
        let script = self.script_for(&program, cfg, &DhParams::AUBO_I5, plan.title)?;
        let timing = match self.motion {
            Motion::PathBuffer => Some(crate::timing::time_program(&program, &DhParams::AUBO_I5, cfg)?),
            Motion::Moves => None,
        };
        let (start_s, strokes_s) = expected_seconds(&program, timing.as_ref());
        let prepared = Prepared {
            summary: format!(
                "one Lua script of {} lines ({} path buffers, {} moves)",
                script.lines().count(),
                script.matches("movePathBuffer(name)").count(),
                script.lines().filter(|l| l.trim_start().starts_with("move")).count()
            ),
            strokes: program.strokes.len(),
            expected_s: Some(start_s + strokes_s.iter().sum::<f64>()),
        };
        self.ready = Some(Ready {
            near: program_box(&program),
            program,
            config: cfg.clone(),
            title: plan.title.to_string(),
            script,
            strokes_s,
            nominal: false,
        });
        self.conn = None;
        Ok(prepared)
    }

    fn connect(&mut self) -> Result<Preflight, RobotError> {
        if self.ready.is_none() {
            return Err(RobotError::Protocol("connect before prepare: nothing to run".into()));
        }
        let (mut client, names) = AuboClient::open(&self.rpc_addr, &self.link, self.timeout)?;
        let ready = self.ready.as_ref().expect("prepared");
        let robot = match &ready.config.robot_name {
            Some(n) if names.contains(n) => n.clone(),
            Some(n) => {
                return Err(RobotError::Config {
                    file: "robot.json".into(),
                    message: format!("robot `{n}` is not on the controller (it has {names:?})"),
                });
            }
            None => names.first().cloned().ok_or_else(|| RobotError::Protocol("getRobotNames: no robots".into()))?,
        };
        let mut checks = Vec::new();
        // The script's joints on the arm's own parameters (it checks them again itself).
        let (script, nominal) = match self.motion {
            Motion::Moves => (ready.script.clone(), false),
            Motion::PathBuffer => {
                let reported = if self.nominal.nominal {
                    Err("nominal parameters were asked for".to_string())
                } else {
                    match client.kinematics_params(&robot, true) {
                        Ok(k) => Ok(k),
                        Err(RobotError::Rpc { code: METHOD_NOT_FOUND, method, message }) => {
                            Err(format!("the controller does not answer {method}: {message}"))
                        }
                        Err(e) => return Err(e),
                    }
                };
                let (kin, nominal) = match reported {
                    Ok(k) => (k, false),
                    Err(_) if self.nominal.accept => (DhParams::AUBO_I5, true),
                    Err(reason) => return Err(RobotError::NominalKinematics { reason }),
                };
                checks.push(if nominal {
                    "the path buffers' joints on maobi's nominal AUBO-i5 parameters (accepted; the script compares them with the controller's)".to_string()
                } else {
                    "the path buffers' joints on the controller's kinematics (getKinematicsParam(true))".to_string()
                });
                (self.script_for(&ready.program, &ready.config, &kin, &ready.title)?, nominal)
            }
        };
        let s = status(&mut client)?;
        if s != "Stopped" {
            return Err(RobotError::UnexpectedState(format!(
                "the controller's runtime is {s} (RuntimeMachine.getStatus): a script or program runs; stop it first"
            )));
        }
        let id = client.exec_id(&robot)?;
        if id != -1 {
            return Err(RobotError::UnexpectedState(format!(
                "before the run: getExecId reported motion {id} (is another client driving the arm?)"
            )));
        }
        let pose = client.tcp_pose(&robot)?;
        check_pose(&pose, &Expect::Reach, None, "before the run")?;
        // The count of finished strokes, from "not started".
        let p = self.params(json!({"key": PROGRESS_VARIABLE, "value": -1}), json!([PROGRESS_VARIABLE, -1]));
        client.call("RegisterControl.setInt32", p)?;
        checks.push("runtime Stopped, idle (getExecId −1)".into());
        checks.push(format!("at {} within reach", Position::Tcp(pose)));
        let controller = format!(
            "AUBO controller, robot `{robot}`{}",
            client.interface_version().map_or(String::new(), |v| format!(", interface version {v}"))
        );
        let ready = self.ready.as_mut().expect("prepared");
        ready.script = script;
        ready.nominal = nominal;
        self.conn = Some((client, robot));
        Ok(Preflight { controller, checks })
    }

    fn run(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError> {
        let (Some(ready), Some((client, robot))) = (&self.ready, self.conn.take()) else {
            return Err(RobotError::Protocol("run before connect: no connection checked".into()));
        };
        send_script(&self.script_addr, &ready.script, self.timeout)?;
        let named = self.link.transport.named_params();
        let mut run =
            ScriptRun { ready, client, robot, named, t0: Instant::now(), done: 0, started: false, counted: false };
        match run.follow(watch) {
            Ok(()) => {
                let mut notes = vec!["the program ran as one Lua script on the controller".to_string()];
                if ready.nominal {
                    notes
                        .push("its path buffers were computed on maobi's nominal AUBO-i5 parameters (accepted)".into());
                }
                Ok(RunSummary {
                    strokes_total: run.total(),
                    strokes_completed: (0..run.total()).collect(),
                    elapsed_s: run.t0.elapsed().as_secs_f64(),
                    at: None,
                    counts: vec![format!("{} controller calls", run.client.calls())],
                    notes,
                })
            }
            // The script stopped in its checks, before its first count and any motion.
            Err((cause, _)) if !run.counted && !matches!(cause, RobotError::Interrupted) => Err(cause),
            Err((cause, trusted)) => Err(run.stop(cause, trusted)),
        }
    }
}

struct ScriptRun<'a> {
    ready: &'a Ready,
    client: AuboClient,
    robot: String,
    named: bool,
    t0: Instant,
    done: usize,
    started: bool,
    /// Whether the script has published a count (it passed its checks; motion may follow).
    counted: bool,
}

impl ScriptRun<'_> {
    fn total(&self) -> usize {
        self.ready.program.strokes.len()
    }

    fn progress_count(&mut self) -> Result<i64, RobotError> {
        let p = if self.named {
            json!({"key": PROGRESS_VARIABLE, "default_value": -1})
        } else {
            json!([PROGRESS_VARIABLE, -1])
        };
        let m = "RegisterControl.getInt32";
        let v = self.client.call(m, p)?;
        v.as_i64().ok_or_else(|| RobotError::Protocol(format!("{m}: expected an integer, got {v}")))
    }

    /// Follows the script to its end; the cause and whether the reports are trusted (a lift)
    /// when it stops early.
    fn follow(&mut self, watch: &mut Watch<'_>) -> Result<(), (RobotError, bool)> {
        let total = self.total();
        let expected: f64 = self.ready.strokes_s.iter().sum();
        let limit = Duration::from_secs_f64((2.0 * expected).max(30.0));
        loop {
            if watch.stop.load(std::sync::atomic::Ordering::SeqCst) {
                return Err((RobotError::Interrupted, true));
            }
            if self.t0.elapsed() > limit {
                let e = format!("the script has not finished after {:.0} s", limit.as_secs_f64());
                return Err((RobotError::UnexpectedState(e), true));
            }
            let s = status(&mut self.client).map_err(|e| (e, true))?;
            let k = self.progress_count().map_err(|e| (e, true))?;
            let pose = self.client.tcp_pose(&self.robot).map_err(|e| (e, true))?;
            if s == "Running" || k >= 0 {
                self.started = true;
            }
            if self.started && k < 0 {
                // Running, not yet at its first count: nothing has moved.
                if s != "Running" {
                    let e = format!(
                        "the script stopped before its first line that counts strokes (runtime {s}): the controller's log says why"
                    );
                    return Err((RobotError::UnexpectedState(e), true));
                }
                std::thread::sleep(POLL);
                continue;
            }
            if !self.started {
                if self.t0.elapsed() > SCRIPT_START_WAIT {
                    let e = format!(
                        "the controller did not start the script within {:.0} s (runtime {s}): its log says why",
                        SCRIPT_START_WAIT.as_secs_f64()
                    );
                    return Err((RobotError::UnexpectedState(e), true));
                }
                std::thread::sleep(POLL);
                continue;
            }
            self.counted = true;
            let k = usize::try_from(k).ok().filter(|&k| k >= self.done && k <= total).ok_or_else(|| {
                let e = format!(
                    "{PROGRESS_VARIABLE} reads {k} after {} of {total} strokes: not this script's count",
                    self.done
                );
                (RobotError::UnexpectedState(e), false)
            })?;
            self.check(&pose, k).map_err(|e| (e, false))?;
            if k > self.done {
                self.done = k;
                let elapsed_s = self.t0.elapsed().as_secs_f64();
                (watch.progress)(&Progress::of_arm(k, total, &self.ready.strokes_s, elapsed_s, pose));
            }
            if s != "Running" {
                if k == total {
                    return Ok(());
                }
                let e = format!(
                    "the script stopped after {k} of {total} strokes (runtime {s}) without maobi stopping it: the controller's log says why"
                );
                return Err((RobotError::UnexpectedState(e), true));
            }
            std::thread::sleep(POLL);
        }
    }

    /// The pose against stroke `k`'s commanded path (any pose within reach before the arm was
    /// seen at the start).
    fn check(&mut self, pose: &Pose, k: usize) -> Result<(), RobotError> {
        let p = &self.ready.program;
        let start = p.start.target();
        if k == 0 && !start.is_some_and(|s| distance_m(&s, pose) <= crate::POSE_TOLERANCE_M) && self.done == 0 {
            return check_pose(pose, &Expect::Reach, None, "on the move to the start pose");
        }
        let Some(st) = p.strokes.get(k) else {
            return check_pose(pose, &Expect::Reach, Some(&self.ready.near), "after the last stroke");
        };
        let from = if k == 0 { start } else { p.strokes[k - 1].lift.target() };
        let commanded = Commanded { from, sent: st.moves().map(Sent::of).collect() };
        check_pose(pose, &Expect::Along(&commanded), Some(&self.ready.near), &format!("during stroke {}", k + 1))
    }

    /// Stops the script (`RuntimeMachine.stop`), waits for the arm, and, when the reports are
    /// trusted, lifts the brush out of the paper from where it stopped.
    fn stop(mut self, cause: RobotError, trusted: bool) -> RobotError {
        let words = match self.client.call("RuntimeMachine.stop", Value::Null) {
            Ok(_) => "the script was stopped (RuntimeMachine.stop)".to_string(),
            Err(e) => format!("RuntimeMachine.stop failed ({e})"),
        };
        let _ = self.client.wait_idle(&self.robot, Duration::from_secs(10));
        let lift = if trusted {
            self.lift().map_err(|e| format!("could not lift the brush ({e}): it may still touch the paper"))
        } else {
            Err("the arm's reports are not trusted: nothing more sent; check the arm".into())
        };
        run_stopped(cause, self.done, self.total(), words, lift)
    }

    fn lift(&mut self) -> Result<(String, Pose), RobotError> {
        let program = &self.ready.program;
        let lift_m = self.ready.config.lift_mm / 1000.0;
        let here = self.client.tcp_pose(&self.robot)?;
        check_pose(&here, &Expect::Reach, Some(&self.ready.near), "before the lift")?;
        let depth_mm = program.depth_mm(here.position());
        if depth_mm <= -self.ready.config.lift_mm + 0.5 {
            return Ok((format!("the brush is at the safe height ({:.1} mm above the paper)", -depth_mm), here));
        }
        let to = program.lifted_out(&here, lift_m);
        let m = Move::Line { pose: to, a: program.retreat_acc_m_s2, v: program.retreat_speed_m_s, blend_m: 0.0 };
        self.client.send_move(&self.robot, &m)?;
        self.client.wait_idle(&self.robot, Duration::from_secs_f64(10.0 + 4.0 * (lift_m + 0.05) / m_speed(&m)))?;
        let end = self.client.tcp_pose(&self.robot)?;
        check_pose(&end, &Expect::At(to), Some(&self.ready.near), "after the lift")?;
        Ok((lift_words(depth_mm, self.ready.config.lift_mm), end))
    }
}

fn m_speed(m: &Move) -> f64 {
    match *m {
        Move::Line { v, .. } | Move::Joint { v, .. } | Move::JointPose { v, .. } => v.max(1e-6),
    }
}
