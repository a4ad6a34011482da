//! `maobi robot`: check, export, send and simulate writing programs.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use robot_io::aubo::{AuboRpc, Link, Motion};
use robot_io::brush_model::Track;
use robot_io::sim::{FaultSpecError, Faults, Listen, SimOptions, Simulator};
use robot_io::wire::Transport;
use robot_io::wire::{RPC_PORT, SCRIPT_PORT};
use robot_io::{
    Controller, ExportFormat, Exported, PaperFrame, Plan, Program, Progress, RobotConfig, RobotError, TrackFile, Watch,
};

use crate::common::{PROGRESS_QUIET_S, check_output_file, clock, print_json, progress, write_atomic};

/// `maobi robot` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum RobotCmd {
    /// Reachability and safety report for a track.
    Check(CheckArgs),
    /// Export the program: aubo-lua, urscript or gcode.
    Export(ExportArgs),
    /// Run the program on a controller (or on `maobi robot sim`).
    Send(SendArgs),
    /// A loopback AUBO controller simulator (framed, line-delimited and HTTP JSON-RPC).
    Sim(SimArgs),
    /// Render a simulator trace as what the brush wrote, framed like `maobi write`'s render.
    RenderTrace(RenderTraceArgs),
    /// Read the arm's kinematic parameters from its controller (getKinematicsParam) into a file
    /// for `robot export --kinematics`.
    Kinematics(KinematicsArgs),
}

/// How to reach a controller (`robot send`, `robot kinematics`).
#[derive(clap::Args, Debug)]
pub struct ControllerArgs {
    /// Controller host (AUBO).
    #[arg(long)]
    host: Option<String>,
    /// Port (default: AUBO 30004 for framed and lines, 9012 for http; UR the script port 30002).
    #[arg(long)]
    port: Option<u16>,
    /// How to talk to an AUBO controller: framed (the AUBO SDK's protocol, with login), lines
    /// (line-delimited JSON, positional params), http (JSON-RPC over HTTP), or script (`robot
    /// send` only: the program as one Lua script on --script-port, followed over framed
    /// JSON-RPC on --port).
    #[arg(long, default_value = "framed", value_parser = parse_transport)]
    transport: SendTransport,
    /// AUBO: the script port --transport script sends to.
    #[arg(long, default_value_t = SCRIPT_PORT)]
    script_port: u16,
    /// User for the framed transport's login.
    #[arg(long, default_value = robot_io::wire::DEFAULT_USER)]
    user: String,
    /// Password for the framed transport's login.
    #[arg(long, default_value = robot_io::wire::DEFAULT_PASSWORD)]
    password: String,
    /// Timeout per call, ms.
    #[arg(long, default_value_t = 2000)]
    timeout_ms: u64,
}

impl ControllerArgs {
    /// `host:port`, the port the transport's default when not given; refuses a timeout out of
    /// range.
    fn addr(&self) -> Result<String> {
        between("--timeout-ms", self.timeout_ms, 1, 600_000)?;
        let host = self.host.as_deref().context("--host is required: the controller's address")?;
        Ok(format!("{host}:{}", self.port.unwrap_or(self.rpc_transport().default_port())))
    }

    /// The JSON-RPC transport (a script is followed over the framed one).
    fn rpc_transport(&self) -> Transport {
        match self.transport {
            SendTransport::Rpc(t) => t,
            SendTransport::Script => Transport::Framed,
        }
    }

    fn link(&self) -> Link {
        Link { transport: self.rpc_transport(), user: self.user.clone(), password: self.password.clone() }
    }

    fn timeout(&self) -> Duration {
        Duration::from_millis(self.timeout_ms)
    }
}

/// `--transport`: one of AUBO's JSON-RPC transports, or its script port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SendTransport {
    /// JSON-RPC, move by move.
    Rpc(Transport),
    /// The program as one Lua script.
    Script,
}

impl std::fmt::Display for SendTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SendTransport::Rpc(t) => write!(f, "{t}"),
            SendTransport::Script => write!(f, "script"),
        }
    }
}

fn parse_transport(s: &str) -> Result<SendTransport, String> {
    match s {
        "script" => Ok(SendTransport::Script),
        _ => s
            .parse::<Transport>()
            .map(SendTransport::Rpc)
            .map_err(|_| format!("unknown transport `{s}`: expected framed, lines, http or script")),
    }
}

/// Arguments of `maobi robot kinematics`.
#[derive(clap::Args, Debug)]
pub struct KinematicsArgs {
    #[command(flatten)]
    controller: ControllerArgs,
    /// The robot's name on the controller (default: the first it reports).
    #[arg(long)]
    robot_name: Option<String>,
    /// Output file (arm.json).
    #[arg(short, long)]
    output: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

/// Arguments of `maobi robot render-trace`.
#[derive(clap::Args, Debug)]
pub struct RenderTraceArgs {
    /// The trace (`maobi robot sim --trace`).
    trace: PathBuf,
    /// `track.json` the run came from (for the brush and the char box).
    #[arg(long)]
    track: PathBuf,
    /// `paper.json` used for the run.
    #[arg(long)]
    paper: PathBuf,
    /// Image side, px.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

/// Inputs every program command needs.
#[derive(clap::Args, Debug)]
pub struct ProgramArgs {
    /// `track.json` from `maobi write`.
    track: PathBuf,
    /// `paper.json`: touched points (paper mm ↔ robot m). Not needed for a plotter
    /// (`--format gcode`, `--controller grbl`): its paper is its work coordinates, and the
    /// program is then checked and timed on a level sheet in front of the nominal arm.
    #[arg(long)]
    paper: Option<PathBuf>,
    /// `robot.json`: speeds, heights, limits (defaults when omitted).
    #[arg(long)]
    robot: Option<PathBuf>,
}

/// Arguments of `maobi robot check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    #[command(flatten)]
    program: ProgramArgs,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

/// Arguments of `maobi robot export`.
#[derive(clap::Args, Debug)]
#[group(id = "destination", required = true, multiple = true)]
pub struct ExportArgs {
    #[command(flatten)]
    program: ProgramArgs,
    /// Output format.
    #[arg(long, value_parser = ["aubo-lua", "urscript", "gcode"])]
    format: String,
    /// Output file (required unless --send-script is given; both may be).
    #[arg(short, long, group = "destination")]
    output: Option<PathBuf>,
    /// Send the aubo-lua script to this controller's script port instead of (or as well as)
    /// writing it (HOST or HOST:PORT, default port 30002), framed by `\r\n\r\n`.
    #[arg(long, group = "destination", value_name = "HOST[:PORT]")]
    send_script: Option<String>,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
    /// aubo-lua only: how pressed strokes are written: path-buffer (each stroke one path
    /// buffer of joint waypoints on its timing, computed on --kinematics and checked against
    /// the controller's before anything moves) or moves (a moveLine per point of the
    /// compacted track, blends at most half the shorter neighbouring move).
    #[arg(long, default_value = "path-buffer", value_parser = ["path-buffer", "moves"])]
    motion: String,
    /// The arm's kinematics as its controller reports them (`maobi robot kinematics -o
    /// arm.json`): the path buffer's joints are computed on them (and the URScript and G-code
    /// speeds timed on them).
    #[arg(long, value_name = "ARM.json")]
    kinematics: Option<PathBuf>,
    /// Compute path-buffer joints on the nominal AUBO-i5 parameters instead of --kinematics
    /// (the script still stops before moving an arm whose controller reports others).
    #[arg(long, conflicts_with = "kinematics")]
    accept_nominal_kinematics: bool,
}

/// The controllers `maobi robot send` drives (each behind `robot_io::Controller`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControllerKind {
    /// An AUBO arm (ARCS): JSON-RPC over --transport framed, lines or http.
    Aubo,
    /// A Universal Robots e-Series arm: URScript on --port (30002), RTDE on --rtde-port (30004),
    /// the dashboard server on --dashboard-port (29999).
    Ur,
    /// A GRBL 1.1 brush plotter on --serial DEVICE or --tcp HOST:PORT (docs/robot.md, "GRBL
    /// brush plotters"): maobi's G-code streamed live.
    Grbl,
}

/// Where a GRBL plotter is, and how to meet its settings (`robot send --controller grbl`).
#[derive(clap::Args, Debug)]
pub struct GrblArgs {
    /// GRBL: the serial device (`/dev/ttyUSB0`, `/dev/ttyACM0`, `COM3`; any character device,
    /// a pseudo-terminal included).
    #[arg(long, value_name = "DEVICE", conflicts_with = "tcp")]
    serial: Option<String>,
    /// GRBL: the serial baud rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// GRBL: a board bridged over the network (an ESP32 or ser2net serial bridge), HOST:PORT.
    #[arg(long, value_name = "HOST:PORT")]
    tcp: Option<String>,
    /// GRBL: where a feed exceeds the machine's maximum rate ($110-$112), slow every feed by one
    /// factor so all fit (said so), instead of refusing.
    #[arg(long)]
    slow_to_machine: bool,
}

/// Arguments of `maobi robot send`.
#[derive(clap::Args, Debug)]
pub struct SendArgs {
    #[command(flatten)]
    program: ProgramArgs,
    /// Which controller drives the arm.
    #[arg(long, value_enum, default_value = "aubo")]
    controller: ControllerKind,
    #[command(flatten)]
    link: ControllerArgs,
    #[command(flatten)]
    grbl: GrblArgs,
    /// Check and print the plan without connecting.
    #[arg(long)]
    dry_run: bool,
    /// AUBO: how pressed strokes are sent: path-buffer (each stroke one path buffer of joint
    /// waypoints on its timing, on the controller's own kinematics) or moves (a moveLine per
    /// point of the compacted track, blends at most half the shorter neighbouring move).
    #[arg(long, default_value = "path-buffer", value_parser = ["path-buffer", "moves"])]
    motion: String,
    /// AUBO: time the path buffers on maobi's nominal AUBO-i5 parameters instead of the ones the
    /// controller reports (getKinematicsParam); needs --accept-nominal-kinematics.
    #[arg(long)]
    nominal_kinematics: bool,
    /// AUBO: accept path-buffer joint waypoints computed from maobi's nominal AUBO-i5 parameters
    /// (when --nominal-kinematics asks for them, or the controller does not report its own);
    /// its forward kinematics must still agree with them before anything moves.
    #[arg(long)]
    accept_nominal_kinematics: bool,
    #[command(flatten)]
    ur: UrPortArgs,
}

/// A UR controller's RTDE and dashboard ports (its script port is --port).
#[derive(clap::Args, Debug)]
pub struct UrPortArgs {
    /// UR: the RTDE port.
    #[arg(long, default_value_t = robot_io::ur::RTDE_PORT)]
    rtde_port: u16,
    /// UR: the dashboard server's port.
    #[arg(long, default_value_t = robot_io::ur::DASHBOARD_PORT)]
    dashboard_port: u16,
}

impl UrPortArgs {
    /// These ports with the script port `--port` names (UR's 30002 by default).
    fn with_script(&self, port: Option<u16>) -> robot_io::ur::UrPorts {
        let script = port.unwrap_or(robot_io::ur::SCRIPT_PORT);
        robot_io::ur::UrPorts { script, rtde: self.rtde_port, dashboard: self.dashboard_port }
    }
}

/// Arguments of `maobi robot sim`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// Which controller to stand in for: aubo (an AUBO-i5's JSON-RPC) or ur (a UR5e: URScript
    /// on --port, RTDE on --rtde-port, the dashboard on --dashboard-port).
    #[arg(long, value_enum, default_value = "aubo")]
    controller: ControllerKind,
    /// Port to listen on (127.0.0.1; default 30004 for aubo, the script port 30002 for ur).
    #[arg(long)]
    port: Option<u16>,
    #[command(flatten)]
    ur_ports: UrPortArgs,
    /// UR: the installation's TCP offset along the flange axis, mm (maobi's program needs the
    /// brush's length_mm: pen1 48).
    #[arg(long, default_value_t = 0.0)]
    tcp_offset_mm: f64,
    /// UR: the installation's payload, kg.
    #[arg(long, default_value_t = 0.0)]
    payload_kg: f64,
    /// UR: run the clock this many times faster than the wall clock (tests; 1 = real time).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Transports served on --port: framed (the AUBO SDK's protocol, with login; the default),
    /// lines (line-delimited JSON) or http (JSON-RPC over HTTP), repeated or a comma-separated
    /// list; with several, each connection's first bytes tell them apart. lines and http are
    /// UNAUTHENTICATED: anyone who reaches the port can move the arm.
    #[arg(long = "transport", value_delimiter = ',', default_value = "framed")]
    transports: Vec<Transport>,
    /// Also serve JSON-RPC over HTTP alone on this port (AUBO's is 9012). UNAUTHENTICATED.
    #[arg(long)]
    http_port: Option<u16>,
    /// Also serve the line-delimited transport alone on this port. UNAUTHENTICATED.
    #[arg(long)]
    lines_port: Option<u16>,
    /// Also serve the framed transport alone on this port.
    #[arg(long)]
    framed_port: Option<u16>,
    /// Also serve AUBO's script port here (AUBO's is 30002): scripts ending in a blank line run
    /// in Lua 5.4 on the simulated arm. UNAUTHENTICATED, like the controller's.
    #[arg(long)]
    script_port: Option<u16>,
    /// The user the framed login accepts.
    #[arg(long, default_value = robot_io::wire::DEFAULT_USER)]
    user: String,
    /// The password the framed login accepts.
    #[arg(long, default_value = robot_io::wire::DEFAULT_PASSWORD)]
    password: String,
    /// Inject a fault (repeatable). aubo: drop-after=N, delay-ms=D or queue-full-every=K; ur:
    /// protective-stop-at-s=S, program-stop-at-s=S or pose-offset-at-s=S (20 mm off from then).
    #[arg(long)]
    fault: Vec<String>,
    /// Write the executed TCP path here (JSON lines), flushed after every move. If a write fails
    /// (a full disk) the file ends there, the failure is reported and the simulator goes on.
    #[arg(long)]
    trace: Option<PathBuf>,
    /// The trace file's size limit, MiB (1 to 65536): the file ends there and the simulator
    /// says so on stderr (and goes on).
    #[arg(long, default_value_t = 256, requires = "trace")]
    trace_max_mib: u64,
    /// Most connections served at once (1 to 1024); when all are taken, a new one takes the
    /// place of the one longest without a request answered (at least 1 s), or is closed at once.
    #[arg(long, default_value_t = 16)]
    max_connections: usize,
    /// Close a connection that sends nothing for this many seconds (1 to 86400).
    #[arg(long, default_value_t = 60)]
    idle_timeout_s: u64,
    /// Answer getKinematicsParam and getKinematicsCompensate with "method not found", as a
    /// controller without them would.
    #[arg(long)]
    no_kinematics_param: bool,
    /// Be another arm: move, answer forwardKinematics/inverseKinematics and report
    /// getKinematicsParam(true) with the parameters in this file (as `maobi robot kinematics
    /// -o` writes it), the compensation being their difference from the nominal i5 (default:
    /// the nominal i5).
    #[arg(long, value_name = "ARM.json")]
    kinematics: Option<PathBuf>,
}

/// Refuses a whole-number flag outside `lo..=hi`, naming it and the value.
fn between(flag: &str, v: u64, lo: u64, hi: u64) -> Result<()> {
    if !(lo..=hi).contains(&v) {
        bail!("{flag} must be between {lo} and {hi}, got {v}");
    }
    Ok(())
}

/// Runs a `maobi robot` subcommand.
pub fn run(cmd: RobotCmd) -> Result<()> {
    match cmd {
        RobotCmd::Check(a) => check(a),
        RobotCmd::Export(a) => export(a),
        RobotCmd::Send(a) => send(a),
        RobotCmd::Sim(a) => sim(a),
        RobotCmd::RenderTrace(a) => render_trace(a),
        RobotCmd::Kinematics(a) => kinematics(a),
    }
}

struct Loaded {
    track: TrackFile,
    /// Its strokes, and the title its programs carry.
    strokes: Track,
    title: String,
    frame: PaperFrame,
    cfg: RobotConfig,
}

impl Loaded {
    /// `program` (built from this track) as a controller or an exporter takes it.
    fn plan<'a>(&'a self, program: &'a Program) -> Plan<'a> {
        Plan {
            program,
            config: &self.cfg,
            track: &self.strokes,
            stroke_chars: self.track.stroke_chars.as_deref(),
            title: &self.title,
        }
    }
}

fn load(a: &ProgramArgs, plotter: bool) -> Result<Loaded> {
    let track = TrackFile::load(&a.track)?;
    let frame = match &a.paper {
        Some(p) => PaperFrame::load(p)?,
        None if plotter => track.level_frame(),
        None => bail!("--paper is required: paper.json, the touched points that place the sheet for the arm"),
    };
    let cfg = match &a.robot {
        Some(p) => RobotConfig::load(p)?,
        None => RobotConfig::default(),
    };
    Ok(Loaded { strokes: track.track(), title: track.title(), track, frame, cfg })
}

fn check(a: CheckArgs) -> Result<()> {
    let l = load(&a.program, false)?;
    let check = l.track.check(&l.frame, &l.cfg)?;
    let (report, timing) = (&check.report, &check.timing);
    if a.json {
        // As a value: its keys in the order every other JSON of the CLI prints them.
        print_json(&serde_json::to_value(&check)?)?;
    } else {
        println!(
            "safe: {} strokes, {} points, {} moves, {} ink dips; deepest press {:.2} mm (range max {} mm); paper fit residual {:.3} mm; about {:.0} s",
            report.strokes,
            report.points,
            report.moves,
            report.dips,
            report.max_press_mm,
            l.track.brush.ranges.h_mm.max,
            report.frame_residual_mm,
            report.estimated_seconds
        );
        for t in &timing.strokes {
            let qd = t.peak_joint_speed_rad_s.map(|v| format!("{v:.3}")).join(", ");
            println!(
                "stroke {}: {:.2} s ({} waypoints every {} s), peak {:.1} mm/s, {:.3} m/s², joints [{qd}] rad/s, {:.2} rad/s², {:.1} rad/s³",
                t.stroke + 1,
                t.duration_s,
                t.joints.len(),
                t.interval_s,
                t.peak_speed_m_s * 1000.0,
                t.peak_acc_m_s2,
                t.peak_joint_acc_rad_s2,
                t.peak_joint_jerk_rad_s3,
            );
        }
        let qd = timing.peak_joint_speed_rad_s.map(|v| format!("{v:.3}")).join(", ");
        println!(
            "writing time {:.2} s (time-optimal without the jerk limit: {:.2} s); peak joint speeds [{qd}] rad/s",
            timing.writing_s, timing.reference_s
        );
    }
    Ok(())
}

fn export(a: ExportArgs) -> Result<()> {
    if let Some(out) = &a.output {
        check_output_file("-o", out, a.force)?;
    }
    let lua = a.format == "aubo-lua";
    let by_moves = a.motion == "moves";
    if by_moves && !lua {
        bail!("--motion moves applies to --format aubo-lua (URScript writes process moves, G-code merged moves)");
    }
    let l = load(&a.program, a.format == "gcode")?;
    let arm = match &a.kinematics {
        Some(p) => Some(robot_io::ArmKinematics::load(p)?),
        None => None,
    };
    let (program, _) = l.track.build_program(&l.frame, &l.cfg)?;
    if lua && !by_moves && arm.is_none() && !a.accept_nominal_kinematics {
        bail!(
            "--format aubo-lua writes joint waypoints, which need the arm's own kinematics: give --kinematics ARM.json \
             (from `maobi robot kinematics --host HOST -o ARM.json`), or --accept-nominal-kinematics (the script \
             then stops before moving an arm whose controller reports other parameters), or --motion moves"
        );
    }
    let format = match a.format.as_str() {
        "aubo-lua" => ExportFormat::AuboLua(if by_moves { Motion::Moves } else { Motion::PathBuffer }),
        "urscript" => ExportFormat::UrScript,
        _ => ExportFormat::Gcode,
    };
    let plan = l.plan(&program);
    // URScript and G-code take only speeds from the timing (no joint is exported), so the
    // nominal arm serves when no other is given.
    let kin = arm.as_ref().map_or(robot_io::DhParams::AUBO_I5, |k| k.kinematics);
    let Exported { text, summary: what, warnings } = robot_io::export_program(&plan, format, &kin)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    if lua && !by_moves && arm.is_none() {
        eprintln!(
            "warning: the path buffer's joints were computed on the nominal AUBO-i5 parameters \
             (--accept-nominal-kinematics); the script stops before moving an arm whose controller reports others"
        );
    }
    if let Some(host) = &a.send_script {
        if !lua {
            bail!("--send-script sends ARCS Lua scripts: use --format aubo-lua");
        }
        let addr = if host.contains(':') { host.clone() } else { format!("{host}:{}", SCRIPT_PORT) };
        robot_io::aubo::send_script(&addr, &text, Duration::from_secs(5))
            .with_context(|| format!("sending the script to {addr}"))?;
        println!("script of {what} sent to {addr}");
    }
    if let Some(out) = &a.output {
        write_atomic(out, text.as_bytes())?;
        println!("{} program of {what} ({} lines) written to {}", a.format, text.lines().count(), out.display());
    }
    Ok(())
}

fn kinematics(a: KinematicsArgs) -> Result<()> {
    let c = &a.controller;
    if c.transport == SendTransport::Script {
        bail!("--transport script runs programs; the kinematics are read over framed, lines or http");
    }
    let addr = c.addr()?;
    check_output_file("-o", &a.output, a.force)?;
    let (mut client, names) = robot_io::aubo::AuboClient::open(&addr, &c.link(), c.timeout())
        .with_context(|| format!("connecting to {addr} ({})", c.rpc_transport()))?;
    let robot = match &a.robot_name {
        Some(r) => r.clone(),
        None => names.first().cloned().with_context(|| format!("{addr}: the controller reports no robot"))?,
    };
    let arm = client.arm_kinematics(&robot).with_context(|| format!("reading {robot}'s kinematics from {addr}"))?;
    let mut text = serde_json::to_string_pretty(&arm)?;
    text.push('\n');
    write_atomic(&a.output, text.as_bytes())?;
    println!("{robot}'s kinematics (getKinematicsParam(true)) from {addr} written to {}", a.output.display());
    Ok(())
}

/// The controller `a` asks for, at the address its flags give.
fn controller_for(a: &SendArgs) -> Result<Box<dyn Controller>> {
    let c = &a.link;
    let motion = if a.motion == "moves" { Motion::Moves } else { Motion::PathBuffer };
    Ok(match a.controller {
        ControllerKind::Aubo if c.transport == SendTransport::Script => Box::new(
            robot_io::aubo::AuboScript::new(
                &c.addr()?,
                &format!("{}:{}", c.host.as_deref().unwrap_or_default(), c.script_port),
                c.link(),
                c.timeout(),
                motion,
            )
            .nominal_kinematics(a.nominal_kinematics, a.accept_nominal_kinematics),
        ),
        ControllerKind::Aubo => Box::new(
            AuboRpc::new(&c.addr()?, c.link(), c.timeout(), motion)
                .nominal_kinematics(a.nominal_kinematics, a.accept_nominal_kinematics),
        ),
        ControllerKind::Grbl => {
            let g = &a.grbl;
            let endpoint = match (&g.serial, &g.tcp) {
                (Some(path), None) => robot_grbl::Endpoint::Serial { path: path.clone(), baud: g.baud },
                (None, Some(addr)) => robot_grbl::Endpoint::Tcp(addr.clone()),
                _ => bail!("--controller grbl needs --serial DEVICE or --tcp HOST:PORT"),
            };
            between("--timeout-ms", c.timeout_ms, 1, 600_000)?;
            let fit = if g.slow_to_machine { robot_grbl::RateFit::Slow } else { robot_grbl::RateFit::Refuse };
            Box::new(robot_grbl::GrblPlotter::new(endpoint, c.timeout(), fit))
        }
        ControllerKind::Ur => {
            c.addr()?; // the host and the timeout's range
            let host = c.host.as_deref().unwrap_or_default();
            Box::new(robot_io::ur::UrArm::new(host, a.ur.with_script(c.port), c.timeout()))
        }
    })
}

fn send(a: SendArgs) -> Result<()> {
    let l = load(&a.program, a.controller == ControllerKind::Grbl)?;
    let (program, _) = l.track.build_program(&l.frame, &l.cfg)?;
    let plan = l.plan(&program);
    let mut controller = controller_for(&a)?;
    let to = controller.describe();
    let prepared = controller.prepare(&plan)?;
    if a.dry_run {
        println!(
            "dry run: {} strokes, {} would be sent to {to}; nothing connected",
            prepared.strokes, prepared.summary
        );
        return Ok(());
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = stop.clone();
    ctrlc::set_handler(move || s2.store(true, Ordering::SeqCst)).context("cannot install the Ctrl-C handler")?;
    let preflight = match controller.connect() {
        Ok(p) => p,
        Err(e) => return Err(advice(e, &to)),
    };
    println!("{}: checked before moving: {}", preflight.controller, preflight.checks.join("; "));
    let pb = progress(program.strokes.len() as u64, "strokes");
    let started = std::time::Instant::now();
    // Without a terminal (the bar), a line per stroke once the run is longer than a moment, and
    // one every 10 s within a long stroke (a plotter reports each acknowledged line).
    let mut printed: Option<(usize, f64)> = None;
    let mut show = |p: &Progress| {
        pb.set_position(p.strokes_done as u64);
        let lines = p.lines.map_or(String::new(), |[done, total]| format!(", line {done}/{total}"));
        pb.set_message(format!("strokes{lines}"));
        use std::io::IsTerminal;
        let due = printed.is_none_or(|(strokes, at_s)| p.strokes_done > strokes || p.elapsed_s >= at_s + 10.0);
        if !std::io::stderr().is_terminal() && started.elapsed().as_secs_f64() >= PROGRESS_QUIET_S && due {
            printed = Some((p.strokes_done, p.elapsed_s));
            let left = p.remaining_s.map_or(String::new(), |s| format!(", about {} left", clock(s)));
            eprintln!(
                "send: {}/{} strokes{lines}, elapsed {}{left}",
                p.strokes_done,
                p.strokes_total,
                clock(p.elapsed_s)
            );
        }
    };
    let result = controller.run(&mut Watch { stop: &stop, progress: &mut show });
    pb.finish_and_clear();
    let r = match result {
        Ok(r) => r,
        Err(e) if matches!(&e, RobotError::RunStopped { cause, .. } if matches!(**cause, RobotError::Interrupted)) => {
            // Ctrl-C: not a success; the conventional status of a run ended by SIGINT.
            // The cause first (RunStopped's own text says how far it got and the lift).
            eprintln!("error: running on {to}: {}; {e}", RobotError::Interrupted);
            std::process::exit(130);
        }
        Err(e) => return Err(advice(e, &to)),
    };
    let mut line = format!("{} of {} strokes completed", r.strokes_completed.len(), r.strokes_total);
    for c in &r.counts {
        line.push_str("; ");
        line.push_str(c);
    }
    println!("{line}");
    for n in &r.notes {
        println!("{n}");
    }
    Ok(())
}

/// A controller's error with the flags that change it, in the context of `to`.
fn advice(e: RobotError, to: &str) -> anyhow::Error {
    match e {
        e @ RobotError::NominalKinematics { .. } => anyhow::Error::new(e).context(format!(
            "running on {to}: the path buffers need the arm's own kinematics; pass --accept-nominal-kinematics to write with maobi's nominal ones anyway (the controller's forward kinematics still checks them), or --motion moves"
        )),
        e => anyhow::Error::new(e).context(format!("running on {to}")),
    }
}

/// A `--fault` spec's refusal as the flag's: `--fault SPEC: ` before the library's reason, and
/// `for_controller` after an unknown key.
fn fault_error(e: FaultSpecError, for_controller: &str) -> anyhow::Error {
    let flag = format!("--fault {}", e.spec());
    match e {
        FaultSpecError::Unknown { key, known, .. } => {
            anyhow::anyhow!("{flag}: unknown fault `{key}`{for_controller} ({})", known.join(", "))
        }
        e => anyhow::Error::new(e).context(flag),
    }
}

fn sim(a: SimArgs) -> Result<()> {
    if a.controller == ControllerKind::Ur {
        return sim_ur(&a);
    }
    let faults = Faults::parse(&a.fault).map_err(|e| fault_error(e, ""))?;
    between("--max-connections", a.max_connections as u64, 1, 1024)?;
    between("--trace-max-mib", a.trace_max_mib, 1, 65_536)?;
    between("--idle-timeout-s", a.idle_timeout_s, 1, 86_400)?;
    let alone = [(a.framed_port, Transport::Framed), (a.lines_port, Transport::Lines), (a.http_port, Transport::Http)];
    let alone = alone.into_iter().filter_map(|(port, t)| Some((port?, t)));
    let listen = Listen::loopback_ports(a.port.unwrap_or(RPC_PORT), &a.transports, alone);
    let arm = a.kinematics.as_deref().map(robot_io::ArmKinematics::load).transpose()?;
    let options = SimOptions {
        faults,
        user: a.user.clone(),
        password: a.password.clone(),
        max_connections: a.max_connections,
        idle_timeout: Duration::from_secs(a.idle_timeout_s),
        trace_path: a.trace.clone(),
        trace_max_bytes: a.trace_max_mib << 20,
        kinematics_param: !a.no_kinematics_param,
        kinematics: arm.as_ref().map_or(robot_io::DhParams::AUBO_I5, |k| k.kinematics),
        ..SimOptions::default()
    };
    // The trace file is created before anything listens: a folder or an unwritable path fails now.
    let sim = Simulator::start_with(&listen, options).context("cannot start the simulator")?;
    let ports: Vec<String> = sim
        .addrs()
        .iter()
        .map(|(ts, addr)| {
            let names: Vec<&str> = ts.iter().map(|t| t.name()).collect();
            format!("{addr} ({})", names.join(", "))
        })
        .collect();
    let which = match (&a.kinematics, &arm) {
        (Some(p), Some(k)) => format!("an AUBO-i5 with the kinematics of {} ({})", p.display(), k.source),
        _ => "an AUBO-i5 (nominal kinematics)".to_string(),
    };
    eprintln!(
        "simulating {which} (robot `{}`, login `{}`) on {}; Ctrl-C to stop",
        robot_io::sim::SIM_ROBOT,
        a.user,
        ports.join(", ")
    );
    if sim.serves_without_login() {
        eprintln!("warning: the lines and http transports have no login: anyone who reaches them can move the arm");
    }
    if let Some(p) = a.script_port {
        let addr = sim.serve_scripts(&format!("127.0.0.1:{p}")).context("cannot serve the script port")?;
        eprintln!("scripts (Lua 5.4, ending in a blank line) on {addr}: no login, like the controller's");
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = stop.clone();
    // Ctrl-C and SIGTERM both stop the loop (the trace file is flushed after every move).
    ctrlc::set_handler(move || s2.store(true, Ordering::SeqCst)).context("cannot install the Ctrl-C handler")?;
    let mut reported = false;
    let mut shown = 0;
    while !stop.load(Ordering::SeqCst) {
        let errors = sim.script_errors();
        for e in errors.iter().skip(shown.min(errors.len())) {
            eprintln!("error: script: {e}");
        }
        shown = errors.len();
        if !reported && let Some(e) = sim.trace_error() {
            eprintln!("error: {e}");
            reported = true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(())
}

/// `maobi robot sim --controller ur`: the UR5e stand-in until Ctrl-C, its refusals on stderr.
fn sim_ur(a: &SimArgs) -> Result<()> {
    let faults = robot_io::sim::UrFaults::parse(&a.fault).map_err(|e| fault_error(e, " for --controller ur"))?;
    between("--max-connections", a.max_connections as u64, 1, 1024)?;
    between("--idle-timeout-s", a.idle_timeout_s, 1, 86_400)?;
    if !(a.tcp_offset_mm.is_finite() && a.tcp_offset_mm.abs() <= 500.0) {
        bail!("--tcp-offset-mm must be within ±500 mm, got {}", a.tcp_offset_mm);
    }
    if !(a.payload_kg.is_finite() && (0.0..=16.0).contains(&a.payload_kg)) {
        bail!("--payload-kg must be from 0 to 16 kg, got {}", a.payload_kg);
    }
    let listen = robot_io::sim::UrListen::loopback(a.ur_ports.with_script(a.port));
    let options = robot_io::sim::UrSimOptions {
        tcp_offset: [0.0, 0.0, a.tcp_offset_mm / 1000.0, 0.0, 0.0, 0.0],
        payload_kg: a.payload_kg,
        time_scale: a.time_scale,
        faults,
        max_connections: a.max_connections,
        idle_timeout: Duration::from_secs(a.idle_timeout_s),
        ..robot_io::sim::UrSimOptions::default()
    };
    let sim = robot_io::sim::UrSimulator::start(&listen, options).context("cannot start the UR simulator")?;
    eprintln!(
        "simulating a UR5e (TCP offset {} mm, payload {} kg, clock ×{}) on {} (URScript), {} (RTDE), {} (dashboard); Ctrl-C to stop",
        a.tcp_offset_mm,
        a.payload_kg,
        a.time_scale,
        sim.script_addr(),
        sim.rtde_addr(),
        sim.dashboard_addr()
    );
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = stop.clone();
    ctrlc::set_handler(move || s2.store(true, Ordering::SeqCst)).context("cannot install the Ctrl-C handler")?;
    let mut shown = 0;
    while !stop.load(Ordering::SeqCst) {
        let errors = sim.errors();
        // The list keeps the latest 64: show what is new.
        for e in errors.iter().skip(shown.min(errors.len())) {
            eprintln!("error: {e}");
        }
        shown = errors.len();
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(())
}

fn render_trace(a: RenderTraceArgs) -> Result<()> {
    check_output_file("-o", &a.output, a.force)?;
    let tf = TrackFile::load(&a.track)?;
    let [x0_mm, y0_mm, size_mm] = tf.char_box(&a.track)?;
    let frame = PaperFrame::load(&a.paper)?;
    let trace = robot_io::read_trace(&a.trace)?;
    if let Some((line, bytes)) = trace.cut_line {
        eprintln!(
            "warning: {}:{line}: skipped a cut last line ({bytes} bytes): the trace ends at the sample before",
            a.trace.display()
        );
    }
    let char_box = trajectory::CharBox { x0_mm, y0_mm, size_mm };
    // The same forward model and renderer as `maobi write`'s plan and executed renders.
    let (img, states) =
        pipeline::render_trace(&trace.samples, &frame, &tf.brush, bezier_raster::ModelKind::Bsm, &char_box, a.size);
    write_atomic(&a.output, &img.encode_png()?)?;
    let pressed = states.iter().filter(|p| p.h_mm > 0.0).count();
    println!("{} trace samples ({pressed} pressed) rendered to {}", states.len(), a.output.display());
    Ok(())
}
