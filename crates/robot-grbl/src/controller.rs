//! [`GrblPlotter`]: a GRBL brush plotter behind robot-io's [`Controller`] seam, which
//! `maobi robot send --controller grbl` drives.

use std::time::Duration;

use robot_io::{
    Controller, DhParams, ExportFormat, Exported, Plan, Position, Preflight, Prepared, Progress, RobotError,
    RunSummary, Watch, export_program,
};

use crate::link::{Port, SerialLink, TcpLink};
use crate::machine::{Checked, Grbl, LinkOptions, MachineInfo, RateFit, check_program};
use crate::program::{GcodeProgram, LineKind};
use crate::{Fault, GrblError, Stopped};

/// Where the plotter is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// A serial device (`/dev/ttyUSB0`, `COM3`, a pseudo-terminal) at a baud rate.
    Serial {
        /// The device.
        path: String,
        /// Baud rate (GRBL 1.1: 115200).
        baud: u32,
    },
    /// A TCP bridge to the board's serial port, `HOST:PORT`.
    Tcp(String),
}

/// A GRBL 1.1 brush plotter: [`Controller::prepare`] writes the plan as maobi's G-code export
/// (timed on the nominal AUBO-i5, as `maobi robot export --format gcode` without
/// `--kinematics`: only the speeds are used) and reads it back; [`Controller::connect`] reads
/// the machine and checks the program against it ([`check_program`]);
/// [`Controller::run`] streams it ([`Grbl::stream`]).
pub struct GrblPlotter {
    endpoint: Endpoint,
    opts: LinkOptions,
    fit: RateFit,
    program: Option<GcodeProgram>,
    warnings: Vec<String>,
    session: Option<(Grbl, MachineInfo, Checked)>,
}

impl GrblPlotter {
    /// A plotter at `endpoint`, answers awaited at most `timeout` (a silent link is lost after
    /// it), feeds beyond the machine's maximum rates refused or slowed (`fit`).
    pub fn new(endpoint: Endpoint, timeout: Duration, fit: RateFit) -> GrblPlotter {
        GrblPlotter {
            endpoint,
            opts: LinkOptions { timeout, ..LinkOptions::default() },
            fit,
            program: None,
            warnings: Vec::new(),
            session: None,
        }
    }

    /// The program as prepared (after [`Controller::prepare`]).
    pub fn program(&self) -> Option<&GcodeProgram> {
        self.program.as_ref()
    }

    /// The export's warnings (α and β are ignored by a 3-axis machine; no ink station).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

fn to_robot(e: GrblError) -> RobotError {
    match e {
        GrblError::Io { context, source } => RobotError::Io { context, source },
        GrblError::Timeout(w) => RobotError::Timeout(w),
        GrblError::Protocol(m) => RobotError::Protocol(m),
        GrblError::Refused(reason) => RobotError::Unsafe { stroke: None, point: None, reason },
        GrblError::Stopped(s) => stopped(*s),
    }
}

fn stopped(s: Stopped) -> RobotError {
    let cause = match &s.cause {
        Fault::Interrupted => RobotError::Interrupted,
        Fault::Quiet(_) => RobotError::Timeout(s.cause.to_string()),
        Fault::Link(_) => RobotError::Io {
            context: s.cause.to_string(),
            source: std::io::Error::from(std::io::ErrorKind::BrokenPipe),
        },
        _ => RobotError::UnexpectedState(s.cause.to_string()),
    };
    let last = match &s.last_acked {
        Some((n, t)) => format!("line {n} `{t}`"),
        None => "none".into(),
    };
    RobotError::RunStopped {
        cause: Box::new(cause),
        completed: s.strokes_done,
        total: s.strokes_total,
        reconnects: 0,
        lifted: s.safe.lifted,
        lift: format!(
            "{} of {} G-code lines acknowledged (the last: {last}); {}",
            s.lines_acked, s.lines_total, s.safe.how
        ),
        at: s.safe.work_mm.map(|[x_mm, y_mm, z_mm]| Box::new(Position::Plotter { x_mm, y_mm, z_mm })),
    }
}

impl Controller for GrblPlotter {
    fn describe(&self) -> String {
        match &self.endpoint {
            Endpoint::Serial { path, baud } => format!("GRBL on {path} ({baud} baud)"),
            Endpoint::Tcp(a) => format!("GRBL at {a} (TCP)"),
        }
    }

    fn prepare(&mut self, plan: &Plan<'_>) -> Result<Prepared, RobotError> {
        let Exported { text, warnings, .. } = export_program(plan, ExportFormat::Gcode, &DhParams::AUBO_I5)?;
        let program = GcodeProgram::from_export(&text, plan.config.travel_speed_m_s * 60_000.0)?;
        let moves = program.lines.iter().filter(|l| matches!(l.kind, LineKind::Travel | LineKind::Feed)).count();
        let prepared = Prepared {
            summary: format!("{} lines of G-code ({moves} moves)", program.lines.len()),
            strokes: program.strokes,
            expected_s: Some(program.planned_s()),
        };
        self.program = Some(program);
        self.warnings = warnings;
        Ok(prepared)
    }

    fn connect(&mut self) -> Result<Preflight, RobotError> {
        let Some(program) = &self.program else {
            return Err(RobotError::Protocol("connect before prepare".into()));
        };
        let port: Box<dyn Port> = match &self.endpoint {
            Endpoint::Serial { path, baud } => Box::new(SerialLink::open(path, *baud).map_err(to_robot)?),
            Endpoint::Tcp(addr) => Box::new(TcpLink::connect(addr, self.opts.timeout).map_err(to_robot)?),
        };
        let (grbl, info) = Grbl::connect(port, self.opts.clone()).map_err(to_robot)?;
        let checked = check_program(&info, program, self.fit).map_err(to_robot)?;
        let preflight = Preflight { controller: format!("Grbl {}", info.version), checks: checked.checks.clone() };
        self.session = Some((grbl, info, checked));
        Ok(preflight)
    }

    fn run(&mut self, watch: &mut Watch<'_>) -> Result<RunSummary, RobotError> {
        let (Some(program), Some((grbl, info, checked))) = (&self.program, &mut self.session) else {
            return Err(RobotError::Protocol("run before connect".into()));
        };
        let stop = watch.stop;
        let progress = &mut *watch.progress;
        let report = grbl
            .stream(info, program, checked.feed_scale, stop, &mut |p| {
                progress(&Progress {
                    strokes_done: p.strokes_done,
                    strokes_total: p.strokes_total,
                    elapsed_s: p.elapsed_s,
                    remaining_s: Some(p.remaining_s),
                    at: p.work_mm.map(|[x_mm, y_mm, z_mm]| Position::Plotter { x_mm, y_mm, z_mm }),
                    lines: Some([p.lines_acked, p.lines_total]),
                })
            })
            .map_err(to_robot)?;
        let mut notes = vec![format!(
            "written in {:.1} s; planned {:.1} s (the G-code's lengths over its feeds, without the machine's acceleration)",
            report.elapsed_s, report.planned_s
        )];
        if checked.feed_scale < 1.0 {
            notes.push(format!(
                "every feed was slowed to {:.3}× the program's to fit the machine's maximum rates",
                checked.feed_scale
            ));
        }
        Ok(RunSummary {
            strokes_total: program.strokes,
            strokes_completed: (0..program.strokes).collect(),
            elapsed_s: report.elapsed_s,
            at: report.work_mm.map(|[x_mm, y_mm, z_mm]| Position::Plotter { x_mm, y_mm, z_mm }),
            counts: vec![format!(
                "{} G-code lines ({} bytes) streamed, at most {} bytes in flight of GRBL's {}-byte buffer",
                report.lines, report.bytes, report.max_in_flight, info.rx_buffer
            )],
            notes,
        })
    }
}
