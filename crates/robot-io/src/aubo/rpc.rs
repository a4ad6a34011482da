//! [`AuboRpc`]: the JSON-RPC runner ([`super::run_program`]) behind the [`Controller`] seam, as
//! `maobi robot send --controller aubo` drives it.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use super::run::{self, Opened};
use super::{Link, RunOptions, RunReport};
use crate::RobotError;
use crate::controller::{
    Controller, Plan, Position, Preflight, Prepared, Progress, RunSummary, Watch, expected_seconds,
};
use crate::kinematics::DhParams;
use crate::program::{Program, RobotConfig, check_blends, compact_program};

/// How an AUBO program writes its pressed strokes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Motion {
    /// Each pressed stroke one path buffer of joint waypoints on its timing, computed on the
    /// kinematics the controller reports and checked by its forward kinematics before anything
    /// moves (the default).
    #[default]
    PathBuffer,
    /// A `moveLine` per point of the compacted track ([`compact_program`]), every blend at most
    /// half the shorter neighbouring move ([`check_blends`]).
    Moves,
}

impl Motion {
    /// The name `--motion` takes: `path-buffer` or `moves`.
    pub fn name(self) -> &'static str {
        match self {
            Motion::PathBuffer => "path-buffer",
            Motion::Moves => "moves",
        }
    }
}

/// An AUBO controller driven over JSON-RPC, move by move, by the fault-tolerant runner
/// ([`super::run_program`]: reconnect, lift, resume; every reported pose checked).
///
/// [`Controller::prepare`] compacts the program for [`Motion::Moves`] (its blends checked) or
/// times it on the nominal AUBO-i5 for [`Motion::PathBuffer`] (the run times it again on the
/// controller's own kinematics before anything moves); [`Controller::connect`] logs in, sets the
/// tool offset and speed fraction and checks the controller idle at a pose within reach;
/// [`Controller::run`] is the runner.
///
/// # Examples
/// ```no_run
/// use std::time::Duration;
/// use robot_io::aubo::{AuboRpc, Link, Motion};
/// use robot_io::Controller;
/// let mut c = AuboRpc::new("192.168.1.10:30004", Link::default(), Duration::from_secs(2), Motion::PathBuffer);
/// assert!(c.describe().contains("framed"));
/// ```
pub struct AuboRpc {
    addr: String,
    link: Link,
    timeout: Duration,
    motion: Motion,
    nominal_kinematics: bool,
    accept_nominal_kinematics: bool,
    ready: Option<Ready>,
    opened: Option<Opened>,
}

/// A prepared program and what the run needs of the plan.
struct Ready {
    program: Program,
    config: RobotConfig,
    strokes_s: Vec<f64>,
}

impl AuboRpc {
    /// A controller at `addr` (`host:port`), reached with `link`, `timeout` per call, writing
    /// pressed strokes as `motion` says.
    pub fn new(addr: &str, link: Link, timeout: Duration, motion: Motion) -> Self {
        Self {
            addr: addr.to_string(),
            link,
            timeout,
            motion,
            nominal_kinematics: false,
            accept_nominal_kinematics: false,
            ready: None,
            opened: None,
        }
    }

    /// Path buffers timed on maobi's nominal AUBO-i5 parameters instead of the controller's
    /// (`nominal`), and whether joints computed on nominal parameters are accepted (`accept`;
    /// [`RunOptions::accept_nominal_kinematics`]).
    pub fn nominal_kinematics(mut self, nominal: bool, accept: bool) -> Self {
        self.nominal_kinematics = nominal;
        self.accept_nominal_kinematics = accept;
        self
    }

    /// The runner's options for `stop`.
    fn options<'s>(&self, cfg: &RobotConfig, stop: &'s AtomicBool) -> RunOptions<'s> {
        RunOptions {
            timeout: self.timeout,
            lift_m: cfg.lift_mm / 1000.0,
            link: self.link.clone(),
            path_buffer: (self.motion == Motion::PathBuffer).then(|| cfg.clone()),
            nominal_kinematics: self.nominal_kinematics,
            accept_nominal_kinematics: self.accept_nominal_kinematics,
            ..RunOptions::new(stop)
        }
    }
}

/// The runner's report as the seam's summary.
fn summary(r: &RunReport, elapsed_s: f64) -> RunSummary {
    let mut notes = Vec::new();
    if r.nominal_kinematics {
        notes.push(
            "the path buffers were timed on maobi's nominal AUBO-i5 parameters (accepted), checked by the controller's forward kinematics"
                .to_string(),
        );
    } else if r.path_buffers > 0 {
        notes.push(format!(
            "the path buffers were timed on the controller's kinematics (getKinematicsParam{})",
            if r.compensation_checked { ", its compensation checked" } else { "" }
        ));
    }
    RunSummary {
        strokes_total: r.strokes_total,
        strokes_completed: r.strokes_completed.clone(),
        elapsed_s,
        at: None,
        counts: vec![
            format!("{} reconnect(s), {} stroke(s) resumed", r.reconnects, r.strokes_resumed),
            format!("{} controller calls, {} path buffer(s)", r.calls, r.path_buffers),
        ],
        notes,
    }
}

impl Controller for AuboRpc {
    fn describe(&self) -> String {
        format!("AUBO JSON-RPC ({}) at {}", self.link.transport, self.addr)
    }

    fn prepare(&mut self, plan: &Plan<'_>) -> Result<Prepared, RobotError> {
        let cfg = plan.config;
        let (program, timing) = match self.motion {
            Motion::Moves => {
                let p = compact_program(plan.program, cfg);
                check_blends(&p)?;
                (p, None)
            }
            // Checked here on the nominal arm (the simulator's); the run times again on the
            // controller's own kinematics before anything moves.
            Motion::PathBuffer => {
                (plan.program.clone(), Some(crate::timing::time_program(plan.program, &DhParams::AUBO_I5, cfg)?))
            }
        };
        let (start_s, strokes_s) = expected_seconds(&program, timing.as_ref());
        let prepared = Prepared {
            summary: format!("{} moves", program.move_count()),
            strokes: program.strokes.len(),
            expected_s: Some(start_s + strokes_s.iter().sum::<f64>()),
        };
        self.ready = Some(Ready { program, config: cfg.clone(), strokes_s });
        self.opened = None;
        Ok(prepared)
    }

    fn connect(&mut self) -> Result<Preflight, RobotError> {
        let Some(ready) = &self.ready else {
            return Err(RobotError::Protocol("connect before prepare: nothing to run".into()));
        };
        let idle = AtomicBool::new(false);
        let opts = self.options(&ready.config, &idle);
        let opened = run::preflight(&self.addr, &ready.program, ready.config.robot_name.as_deref(), &opts)?;
        let version = opened.interface_version.map_or(String::new(), |v| format!(", interface version {v}"));
        let preflight = Preflight {
            controller: format!("AUBO controller, robot `{}`{version}", opened.robot),
            checks: vec![
                format!("tool offset set to {} m along the flange axis", ready.program.tcp_offset_m),
                format!("speed fraction set to {}", ready.program.speed_fraction),
                "idle (getExecId −1)".to_string(),
                format!("at {} within reach", Position::Tcp(opened.pose)),
            ],
        };
        self.opened = Some(opened);
        Ok(preflight)
    }

    fn run(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError> {
        let (Some(ready), Some(opened)) = (&self.ready, self.opened.take()) else {
            return Err(RobotError::Protocol("run before connect: no connection checked".into()));
        };
        let opts = self.options(&ready.config, watch.stop);
        let t0 = Instant::now();
        let total = ready.program.strokes.len();
        let progress = &mut *watch.progress;
        let report = run::run_preflighted(
            &self.addr,
            &ready.program,
            ready.config.robot_name.as_deref(),
            &opts,
            opened,
            |r: &RunReport| {
                let left: f64 = (0..total)
                    .filter(|i| !r.strokes_completed.contains(i))
                    .filter_map(|i| ready.strokes_s.get(i))
                    .sum();
                progress(&Progress {
                    strokes_done: r.strokes_completed.len(),
                    strokes_total: total,
                    elapsed_s: t0.elapsed().as_secs_f64(),
                    remaining_s: Some(left),
                    at: None,
                    lines: None,
                });
            },
        )?;
        Ok(summary(&report, t0.elapsed().as_secs_f64()))
    }
}
