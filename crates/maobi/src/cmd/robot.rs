//! `maobi robot`: check, export, send and simulate writing programs.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use robot_io::Transport;
use robot_io::aubo::{Link, RunOptions, run_program};
use robot_io::frame::PaperFrame;
use robot_io::program::{RobotConfig, build_program_chars};
use robot_io::sim::{Faults, Listen, SimOptions, Simulator};
use robot_io::wire::{RPC_PORT, SCRIPT_PORT};
use robot_io::{RobotError, TrackFile};

use crate::common::{check_output_file, print_json, progress, write_atomic};

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
    /// Controller host.
    #[arg(long)]
    host: String,
    /// Port (default: 30004 for framed and lines, 9012 for http).
    #[arg(long)]
    port: Option<u16>,
    /// How to talk to the controller: framed (the AUBO SDK's protocol, with login), lines
    /// (line-delimited JSON, positional params) or http (JSON-RPC over HTTP).
    #[arg(long, default_value = "framed")]
    transport: Transport,
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
        if !(1..=600_000).contains(&self.timeout_ms) {
            bail!("--timeout-ms must be between 1 and 600000, got {}", self.timeout_ms);
        }
        Ok(format!("{}:{}", self.host, self.port.unwrap_or(self.transport.default_port())))
    }

    fn link(&self) -> Link {
        Link { transport: self.transport, user: self.user.clone(), password: self.password.clone() }
    }

    fn timeout(&self) -> Duration {
        Duration::from_millis(self.timeout_ms)
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
    /// `paper.json`: touched points (paper mm ↔ robot m).
    #[arg(long)]
    paper: PathBuf,
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

/// Arguments of `maobi robot send`.
#[derive(clap::Args, Debug)]
pub struct SendArgs {
    #[command(flatten)]
    program: ProgramArgs,
    #[command(flatten)]
    controller: ControllerArgs,
    /// Check and print the plan without connecting.
    #[arg(long)]
    dry_run: bool,
    /// How pressed strokes are sent: path-buffer (each stroke one path buffer of joint
    /// waypoints on its timing, on the controller's own kinematics) or moves (a moveLine per
    /// point of the compacted track, blends at most half the shorter neighbouring move).
    #[arg(long, default_value = "path-buffer", value_parser = ["path-buffer", "moves"])]
    motion: String,
    /// Time the path buffers on maobi's nominal AUBO-i5 parameters instead of the ones the
    /// controller reports (getKinematicsParam); needs --accept-nominal-kinematics.
    #[arg(long)]
    nominal_kinematics: bool,
    /// Accept path-buffer joint waypoints computed from maobi's nominal AUBO-i5 parameters
    /// (when --nominal-kinematics asks for them, or the controller does not report its own);
    /// its forward kinematics must still agree with them before anything moves.
    #[arg(long)]
    accept_nominal_kinematics: bool,
}

/// Arguments of `maobi robot sim`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// Port to listen on (127.0.0.1).
    #[arg(long, default_value_t = RPC_PORT)]
    port: u16,
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
    /// The user the framed login accepts.
    #[arg(long, default_value = robot_io::wire::DEFAULT_USER)]
    user: String,
    /// The password the framed login accepts.
    #[arg(long, default_value = robot_io::wire::DEFAULT_PASSWORD)]
    password: String,
    /// Inject a fault: drop-after=N, delay-ms=D or queue-full-every=K (repeatable).
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
    frame: PaperFrame,
    cfg: RobotConfig,
}

fn load(a: &ProgramArgs) -> Result<Loaded> {
    let track = TrackFile::load(&a.track)?;
    let frame = PaperFrame::load(&a.paper)?;
    let cfg = match &a.robot {
        Some(p) => RobotConfig::load(p)?,
        None => RobotConfig::default(),
    };
    Ok(Loaded { track, frame, cfg })
}

fn title(t: &TrackFile) -> String {
    t.char.clone().unwrap_or_else(|| "track".into())
}

fn check(a: CheckArgs) -> Result<()> {
    let l = load(&a.program)?;
    let (program, report) =
        build_program_chars(&l.track.track(), l.track.stroke_chars.as_deref(), &l.track.brush, &l.frame, &l.cfg)?;
    // Timed with the nominal AUBO-i5 (the simulator's arm); `send` times again with the
    // controller's own parameters before anything moves.
    let timing = robot_io::time_program(&program, &robot_io::kinematics::DhParams::AUBO_I5, &l.cfg)?;
    if a.json {
        let mut v = serde_json::to_value(&report)?;
        v["timing"] = serde_json::to_value(&timing)?;
        print_json(&v)?;
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
    let l = load(&a.program)?;
    let arm = match &a.kinematics {
        Some(p) => Some(robot_io::export::ArmKinematics::load(p)?),
        None => None,
    };
    let track = l.track.track();
    let chars = l.track.stroke_chars.as_deref();
    let (program, _) = build_program_chars(&track, chars, &l.track.brush, &l.frame, &l.cfg)?;
    if lua && !by_moves && arm.is_none() && !a.accept_nominal_kinematics {
        bail!(
            "--format aubo-lua writes joint waypoints, which need the arm's own kinematics: give --kinematics ARM.json \
             (from `maobi robot kinematics --host HOST -o ARM.json`), or --accept-nominal-kinematics (the script \
             then stops before moving an arm whose controller reports other parameters), or --motion moves"
        );
    }
    // URScript and G-code take only speeds from the timing (no joint is exported), so the
    // nominal arm serves when no other is given.
    let kin = arm.as_ref().map_or(robot_io::kinematics::DhParams::AUBO_I5, |k| k.kinematics);
    let t = title(&l.track);
    let (text, what) = match a.format.as_str() {
        "aubo-lua" if by_moves => {
            let compact = robot_io::program::compact_program(&program, &l.cfg);
            robot_io::program::check_blends(&compact)?;
            let text = robot_io::export::aubo_lua(&compact, &t)?;
            (text, format!("{} moves", compact.move_count()))
        }
        "aubo-lua" => {
            let text = robot_io::export::aubo_lua_path_buffer(&program, &kin, &l.cfg, &t)?;
            let buffers = text.matches("mc:movePathBuffer(name)").count();
            let calls = text.lines().filter(|l| l.trim_start().starts_with("mc:move")).count();
            (text, format!("{buffers} path buffers, {calls} motion calls"))
        }
        "urscript" => {
            let timing = robot_io::time_program(&program, &kin, &l.cfg)?;
            let text = robot_io::export::urscript(&program, &timing, &l.cfg, &t)?;
            let moves = text.lines().filter(|l| l.starts_with("  move")).count();
            (text, format!("{moves} moves"))
        }
        _ => {
            let timing = robot_io::time_program(&program, &kin, &l.cfg)?;
            let times = robot_io::export::point_times(&program, &timing)?;
            let (g, warnings) = robot_io::export::gcode_chars(&track, chars, &times, &l.cfg, &t)?;
            for w in warnings {
                eprintln!("warning: {w}");
            }
            let moves = g.lines().filter(|l| l.starts_with("G0") || l.starts_with("G1")).count();
            (g, format!("{moves} moves"))
        }
    };
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
    let addr = c.addr()?;
    check_output_file("-o", &a.output, a.force)?;
    let (mut client, names) = robot_io::AuboClient::open(&addr, &c.link(), c.timeout())
        .with_context(|| format!("connecting to {addr} ({})", c.transport))?;
    let robot = match &a.robot_name {
        Some(r) => r.clone(),
        None => names.first().cloned().with_context(|| format!("{addr}: the controller reports no robot"))?,
    };
    let params =
        client.kinematics_params(&robot, true).with_context(|| format!("reading {robot}'s kinematics from {addr}"))?;
    let arm = robot_io::export::ArmKinematics {
        robot: robot.clone(),
        source: format!("{addr} ({}): RobotConfig.getKinematicsParam(true)", c.transport),
        real: true,
        kinematics: params,
    };
    let mut text = serde_json::to_string_pretty(&arm)?;
    text.push('\n');
    write_atomic(&a.output, text.as_bytes())?;
    println!("{robot}'s kinematics (getKinematicsParam(true)) from {addr} written to {}", a.output.display());
    Ok(())
}

fn send(a: SendArgs) -> Result<()> {
    let c = &a.controller;
    let addr = c.addr()?;
    let l = load(&a.program)?;
    let (program, report) =
        build_program_chars(&l.track.track(), l.track.stroke_chars.as_deref(), &l.track.brush, &l.frame, &l.cfg)?;
    let by_moves = a.motion == "moves";
    let program = if by_moves { robot_io::program::compact_program(&program, &l.cfg) } else { program };
    if by_moves {
        robot_io::program::check_blends(&program)?;
    }
    // Checked here on the nominal arm (the simulator's); the runner times again on the
    // controller's own kinematics before anything moves.
    if !by_moves {
        robot_io::time_program(&program, &robot_io::kinematics::DhParams::AUBO_I5, &l.cfg)?;
    }
    if a.dry_run {
        println!(
            "dry run: {} strokes, {} moves would be sent to {addr} ({}, {}); nothing connected",
            report.strokes,
            if by_moves { program.move_count() } else { report.moves },
            c.transport,
            a.motion
        );
        return Ok(());
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = stop.clone();
    ctrlc::set_handler(move || s2.store(true, Ordering::SeqCst)).context("cannot install the Ctrl-C handler")?;
    let pb = progress(program.strokes.len() as u64, "strokes");
    let opts = RunOptions {
        timeout: c.timeout(),
        lift_m: l.cfg.lift_mm / 1000.0,
        link: c.link(),
        path_buffer: (!by_moves).then(|| l.cfg.clone()),
        nominal_kinematics: a.nominal_kinematics,
        accept_nominal_kinematics: a.accept_nominal_kinematics,
        ..RunOptions::new(&stop)
    };
    let result = run_program(&addr, &program, l.cfg.robot_name.as_deref(), &opts, |r| {
        pb.set_position(r.strokes_completed.len() as u64)
    });
    pb.finish_and_clear();
    let r = match result {
        Ok(r) => r,
        Err(e) if matches!(&e, RobotError::RunStopped { cause, .. } if matches!(**cause, RobotError::Interrupted)) => {
            // Ctrl-C: not a success; the conventional status of a run ended by SIGINT.
            // The cause first (RunStopped's own text says how far it got and the lift).
            eprintln!("error: running on {addr}: {}; {e}", RobotError::Interrupted);
            std::process::exit(130);
        }
        Err(e @ RobotError::NominalKinematics { .. }) => {
            return Err(e).with_context(|| {
                format!(
                    "running on {addr} ({}): the path buffers need the arm's own kinematics; pass --accept-nominal-kinematics to write with maobi's nominal ones anyway (the controller's forward kinematics still checks them), or --motion moves",
                    c.transport
                )
            });
        }
        Err(e) => return Err(e).with_context(|| format!("running on {addr} ({})", c.transport)),
    };
    println!(
        "{} of {} strokes completed; {} reconnect(s), {} stroke(s) resumed; {} controller calls, {} path buffer(s)",
        r.strokes_completed.len(),
        r.strokes_total,
        r.reconnects,
        r.strokes_resumed,
        r.calls,
        r.path_buffers,
    );
    if r.nominal_kinematics {
        println!(
            "the path buffers were timed on maobi's nominal AUBO-i5 parameters (accepted), checked by the controller's forward kinematics"
        );
    } else if r.path_buffers > 0 {
        println!(
            "the path buffers were timed on the controller's kinematics (getKinematicsParam{})",
            if r.compensation_checked { ", its compensation checked" } else { "" }
        );
    }
    Ok(())
}

fn sim(a: SimArgs) -> Result<()> {
    let mut faults = Faults::default();
    for f in &a.fault {
        let (k, v) = f.split_once('=').with_context(|| format!("--fault {f}: expected KEY=VALUE"))?;
        let n: u64 = v.parse().with_context(|| format!("--fault {f}: {v} is not a whole number"))?;
        match k {
            "drop-after" => faults.drop_after_moves = Some(n as usize),
            "delay-ms" => faults.delay_ms = Some(n),
            "queue-full-every" => faults.queue_full_every = Some(n as usize),
            _ => bail!("--fault {f}: unknown fault `{k}` (drop-after, delay-ms, queue-full-every)"),
        }
    }
    if !(1..=1024).contains(&a.max_connections) {
        bail!("--max-connections must be between 1 and 1024, got {}", a.max_connections);
    }
    if !(1..=65_536).contains(&a.trace_max_mib) {
        bail!("--trace-max-mib must be between 1 and 65536, got {}", a.trace_max_mib);
    }
    if !(1..=86_400).contains(&a.idle_timeout_s) {
        bail!("--idle-timeout-s must be between 1 and 86400, got {}", a.idle_timeout_s);
    }
    let mut listen = vec![Listen { bind: format!("127.0.0.1:{}", a.port), transports: a.transports.clone() }];
    for (port, t) in
        [(a.framed_port, Transport::Framed), (a.lines_port, Transport::Lines), (a.http_port, Transport::Http)]
    {
        if let Some(p) = port {
            listen.push(Listen { bind: format!("127.0.0.1:{p}"), transports: vec![t] });
        }
    }
    let arm = a.kinematics.as_deref().map(robot_io::export::ArmKinematics::load).transpose()?;
    let options = SimOptions {
        faults,
        user: a.user.clone(),
        password: a.password.clone(),
        max_connections: a.max_connections,
        idle_timeout: Duration::from_secs(a.idle_timeout_s),
        trace_path: a.trace.clone(),
        trace_max_bytes: a.trace_max_mib << 20,
        kinematics_param: !a.no_kinematics_param,
        kinematics: arm.as_ref().map_or(robot_io::kinematics::DhParams::AUBO_I5, |k| k.kinematics),
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
    if sim.addrs().iter().any(|(ts, _)| ts.iter().any(|t| *t != Transport::Framed)) {
        eprintln!("warning: the lines and http transports have no login: anyone who reaches them can move the arm");
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s2 = stop.clone();
    // Ctrl-C and SIGTERM both stop the loop (the trace file is flushed after every move).
    ctrlc::set_handler(move || s2.store(true, Ordering::SeqCst)).context("cannot install the Ctrl-C handler")?;
    let mut reported = false;
    while !stop.load(Ordering::SeqCst) {
        if !reported && let Some(e) = sim.trace_error() {
            eprintln!("error: {e}");
            reported = true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(())
}

/// Reads a simulator trace: JSON lines (one sample per line, as `robot sim --trace` writes), or
/// one JSON array. A last line cut short (the simulator stopped mid-write, or its disk filled)
/// is skipped with a warning on stderr; a bad line before it is an error.
fn read_trace(path: &std::path::Path) -> Result<Vec<robot_io::exec::TraceEntry>> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).with_context(|| format!("{name}: cannot read"))?;
    // A cut can split a UTF-8 character: the text is read up to what decodes.
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
    };
    if text.trim_start().starts_with('[') {
        return serde_json::from_str(text).with_context(|| format!("{name}: not a simulator trace"));
    }
    let mut out = Vec::new();
    let lines: Vec<&str> = text.split('\n').collect();
    let last = lines.iter().rposition(|l| !l.trim().is_empty());
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str(line) {
            Ok(t) => out.push(t),
            // The last line, unfinished: the file was cut there.
            // (A last line that is complete JSON but not a sample is an error like any other.)
            Err(e)
                if Some(i) == last
                    && (e.is_eof()
                        || (!text.ends_with('\n') && serde_json::from_str::<serde_json::Value>(line).is_err())) =>
            {
                eprintln!(
                    "warning: {name}:{}: skipped a cut last line ({} bytes): the trace ends at the sample before",
                    i + 1,
                    line.len()
                );
            }
            Err(e) => {
                return Err(e).with_context(|| {
                    format!("{name}:{}: not a simulator trace sample (expected {{\"t_s\", \"kind\", \"pose\"}})", i + 1)
                });
            }
        }
    }
    if out.is_empty() {
        bail!("{name}: the trace is empty (did the simulator execute any move?)");
    }
    Ok(out)
}

fn render_trace(a: RenderTraceArgs) -> Result<()> {
    check_output_file("-o", &a.output, a.force)?;
    let name = a.track.display().to_string();
    let text = std::fs::read_to_string(&a.track).with_context(|| format!("{name}: cannot read"))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{name}: not JSON"))?;
    let b: Vec<f64> = serde_json::from_value(v["char_box_mm"].clone())
        .with_context(|| format!("{name}: field `char_box_mm` must be [x0, y0, size]"))?;
    if b.len() != 3 || b[2] <= 0.0 {
        bail!("{name}: field `char_box_mm` must be [x0, y0, size] with size > 0");
    }
    let tf = TrackFile::load(&a.track)?;
    let frame = PaperFrame::load(&a.paper)?;
    let trace = read_trace(&a.trace)?;
    let states = robot_io::exec::trace_to_states(&trace, &frame);
    let char_box = trajectory::CharBox { x0_mm: b[0], y0_mm: b[1], size_mm: b[2] };
    // The same forward model and renderer as `maobi write`'s plan and executed renders.
    let img = pipeline::render_states(
        &states,
        &tf.brush,
        bezier_raster::ModelKind::Bsm,
        brush_model::Extrapolation::Refuse,
        &char_box,
        a.size,
    );
    write_atomic(&a.output, &img.encode_png()?)?;
    let pressed = states.iter().filter(|p| p.h_mm > 0.0).count();
    println!("{} trace samples ({pressed} pressed) rendered to {}", states.len(), a.output.display());
    Ok(())
}
