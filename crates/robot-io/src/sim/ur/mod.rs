//! A UR5e stand-in on loopback: the script port runs the URScript subset maobi writes (and
//! refuses anything else, naming the line and the function), executed on the UR5e's published
//! kinematics on a time law; RTDE serves the fields maobi and UR's own client ask for, sampled
//! from the running program; the dashboard server answers the commands maobi uses.
//!
//! Bounded against a hostile client: at most [`UrSimOptions::max_connections`] connections, a
//! script of at most [`MAX_SCRIPT_BYTES`], RTDE packages of at most 64 KiB with at most
//! [`MAX_RECIPE_FIELDS`] fields, dashboard lines of at most 4 KiB, a program path of at most
//! [`MAX_PROGRAM_SAMPLES`] samples; a connection that sends nothing but whitespace for
//! [`UrSimOptions::idle_timeout`] is closed (an RTDE client receiving data packages is not idle).

mod program;

pub use program::MAX_PROGRAM_SAMPLES;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nalgebra::Isometry3;

use crate::RobotError;
use crate::exec::TraceEntry;
use crate::kinematics::{DhParams, UR_HOME_JOINTS};
use crate::pose::Pose;
use crate::ur::rtde::{self, ControlVersion, FieldType, PackageDecoder, Value};
use crate::ur::{UrPorts, pose_to_ur};
use program::Compiled;

/// The longest script the stand-in reads, bytes (8 MiB: 永's program is about 60 KB).
pub const MAX_SCRIPT_BYTES: usize = 8 << 20;
/// Most fields one RTDE recipe may name.
pub const MAX_RECIPE_FIELDS: usize = 64;
/// The longest dashboard command line, bytes.
pub const MAX_DASHBOARD_LINE: usize = 4096;
/// The greeting of UR's dashboard server.
pub const DASHBOARD_GREETING: &str = "Connected: Universal Robots Dashboard Server";

/// Faults the stand-in can be told to show, at program times (s since the first program of the
/// run started, on the stand-in's clock).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UrFaults {
    /// A protective stop at this time: the program pauses, `safety_status_bits` bit 2 is set.
    pub protective_stop_at_s: Option<f64>,
    /// The program stops by itself at this time (as a runtime error would stop it).
    pub program_stop_at_s: Option<f64>,
    /// From this time on the reported TCP pose is 20 mm off in +y from where the arm is.
    pub pose_offset_at_s: Option<f64>,
    /// A hostile controller, from this time on: the reported TCP pose is NaN.
    pub nan_pose_at_s: Option<f64>,
    /// A hostile controller, from this time on: every RTDE data package is one byte short of
    /// the recipe (the program keeps playing).
    pub rtde_garbage_at_s: Option<f64>,
    /// A hostile controller, from this time on: RTDE sends nothing more but keeps the
    /// connection open (the program keeps playing).
    pub rtde_silent_at_s: Option<f64>,
    /// A hostile controller: RTDE closes its connections at this time (the program keeps
    /// playing).
    pub rtde_close_at_s: Option<f64>,
}

/// How the stand-in behaves.
#[derive(Clone, Debug, PartialEq)]
pub struct UrSimOptions {
    /// The arm's kinematics (the UR5e's).
    pub kinematics: DhParams,
    /// The installation's TCP offset, UR's form `[x, y, z, rx, ry, rz]` (m, rotation vector):
    /// reported over RTDE until a program sets its own.
    pub tcp_offset: [f64; 6],
    /// The installation's payload, kg.
    pub payload_kg: f64,
    /// The URControl version reported.
    pub version: ControlVersion,
    /// How fast the stand-in's clock runs against the wall clock (1: real time).
    pub time_scale: f64,
    /// Whether the arm is in remote control (the dashboard's `is in remote control`).
    pub remote_control: bool,
    /// Faults to show.
    pub faults: UrFaults,
    /// Most connections served at once, over the three ports.
    pub max_connections: usize,
    /// A connection that sends nothing for this long is closed (unless it receives RTDE data).
    pub idle_timeout: Duration,
}

impl Default for UrSimOptions {
    /// A UR5e at its tool-down home, no TCP offset and no payload in its installation, URControl
    /// 5.15.0, real time, in remote control, no faults, 16 connections, 60 s idle time-out.
    fn default() -> Self {
        Self {
            kinematics: DhParams::UR5E,
            tcp_offset: [0.0; 6],
            payload_kg: 0.0,
            version: ControlVersion { major: 5, minor: 15, bugfix: 0, build: 0 },
            time_scale: 1.0,
            remote_control: true,
            faults: UrFaults::default(),
            max_connections: 16,
            idle_timeout: Duration::from_secs(60),
        }
    }
}

/// The ports the stand-in listens on (`:0` binds any free port).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UrListen {
    /// The script port (UR's 30002).
    pub script: String,
    /// RTDE (30004).
    pub rtde: String,
    /// The dashboard server (29999).
    pub dashboard: String,
}

impl UrListen {
    /// The stand-in on `127.0.0.1` at `ports` (a port 0: any free one).
    pub fn loopback(ports: UrPorts) -> Self {
        let at = |port: u16| format!("127.0.0.1:{port}");
        UrListen { script: at(ports.script), rtde: at(ports.rtde), dashboard: at(ports.dashboard) }
    }
}

/// A program playing (or played): what was compiled and when it started.
struct Playing {
    c: Compiled,
    /// The stand-in's clock at the start, s.
    t0: f64,
    /// Stopped (by `stop`, a fault or a new program) at this program time, s.
    stopped_at: Option<f64>,
}

/// The arm and its bookkeeping.
struct State {
    joints: [f64; 6],
    /// The TCP offset active now.
    tcp: Isometry3<f64>,
    registers: [i32; 48],
    playing: Option<Playing>,
    protective_stop: bool,
    /// Refusals of programs the script port was sent, in order (the latest 64).
    errors: Vec<String>,
    /// The stand-in's clock when the first program started.
    first_start: Option<f64>,
    programs: usize,
}

struct Shared {
    options: UrSimOptions,
    state: Mutex<State>,
    connections: AtomicUsize,
    /// The wall-clock origin of the stand-in's clock.
    origin: Instant,
}

/// Where the arm is at one moment, as RTDE reports it.
#[derive(Clone, Copy, Debug)]
struct Snapshot {
    clock_s: f64,
    pose: Pose,
    joints: [f64; 6],
    runtime_state: u32,
    tcp: [f64; 6],
    registers: [i32; 48],
    protective_stop: bool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The stand-in's clock, s.
    fn clock(&self) -> f64 {
        self.origin.elapsed().as_secs_f64() * self.options.time_scale
    }

    /// Whether a fault set `at` a program time is due (the first program started that long ago).
    fn due(&self, at: Option<f64>) -> bool {
        let Some(at) = at else { return false };
        let first = self.lock().first_start;
        first.is_some_and(|f| self.clock() - f >= at)
    }

    /// Brings the state up to now: a program past its end or a fault's time is settled (its
    /// registers written, the arm at its last pose, the program stopped).
    fn advance(&self, st: &mut State) {
        let now = self.clock();
        let f = self.options.faults;
        let since_first = |t: f64| st.first_start.map(|s| t - s);
        if let Some(p) = &mut st.playing
            && p.stopped_at.is_none()
        {
            let t = now - p.t0;
            let end = p.c.samples.last().map_or(0.0, |s| s.t_s);
            let error_at = p.c.error.as_ref().map(|(t, _)| *t);
            let mut stop_at = None;
            let first = since_first(p.t0).unwrap_or(0.0);
            for (fault, what) in [(f.protective_stop_at_s, 0), (f.program_stop_at_s, 1)] {
                if let Some(at) = fault {
                    let local = at - first;
                    if local >= 0.0 && t >= local && stop_at.is_none_or(|(s, _)| local < s) {
                        stop_at = Some((local, what));
                    }
                }
            }
            if let Some(e) = error_at
                && t >= e
                && stop_at.is_none_or(|(s, _)| e < s)
            {
                stop_at = Some((e, 2));
            }
            match stop_at {
                Some((at, what)) if at <= end || what != 2 => {
                    p.stopped_at = Some(at.min(end));
                    if what == 0 {
                        st.protective_stop = true;
                    }
                }
                _ if t >= end => p.stopped_at = Some(end),
                _ => {}
            }
            if let Some(at) = p.stopped_at {
                let (joints, registers) = settle(&p.c, at, st.joints, st.registers);
                st.joints = joints;
                st.registers = registers;
                if let Some((_, e)) = &p.c.error
                    && p.c.error.as_ref().is_some_and(|(et, _)| *et <= at)
                {
                    let e = format!("program `{}` stopped: {e}", p.c.name);
                    push_error(&mut st.errors, e);
                }
            }
        }
    }

    /// The arm now, as RTDE reports it.
    fn snapshot(&self) -> Snapshot {
        let mut st = self.lock();
        self.advance(&mut st);
        let clock_s = self.clock();
        let mut pose = Pose::from_iso(&self.options.kinematics.forward(&st.joints, &st.tcp));
        let mut runtime_state = crate::ur::RUNTIME_STOPPED;
        let mut registers = st.registers;
        let mut tcp = st.tcp;
        if let Some(p) = &st.playing {
            tcp = p.c.tcp;
            let t = p.stopped_at.unwrap_or(clock_s - p.t0);
            pose = pose_at(&p.c.samples, t).unwrap_or(pose);
            if p.stopped_at.is_none() {
                runtime_state = crate::ur::RUNTIME_PLAYING;
                registers = settle(&p.c, t, st.joints, st.registers).1;
            } else if st.protective_stop {
                runtime_state = 4; // PAUSED
            }
        }
        if let (Some(at), Some(first)) = (self.options.faults.pose_offset_at_s, st.first_start)
            && clock_s - first >= at
        {
            pose.0[1] += 0.02;
        }
        if let (Some(at), Some(first)) = (self.options.faults.nan_pose_at_s, st.first_start)
            && clock_s - first >= at
        {
            pose.0[0] = f64::NAN;
        }
        Snapshot {
            clock_s,
            pose,
            joints: st.joints,
            runtime_state,
            tcp: pose_to_ur(&Pose::from_iso(&tcp)),
            registers,
            protective_stop: st.protective_stop,
        }
    }

    /// Runs a program sent to the script port, replacing the one playing; a refused program is
    /// recorded and changes nothing.
    fn run_program(&self, text: &str) {
        let mut guard = self.lock();
        let st = &mut *guard;
        self.advance(st);
        if st.protective_stop {
            push_error(&mut st.errors, "program refused: the arm is in a protective stop".into());
            return;
        }
        let now = self.clock();
        // The arm is where the playing program has brought it.
        if let Some(p) = &mut st.playing
            && p.stopped_at.is_none()
        {
            p.stopped_at = Some(now - p.t0);
        }
        if let Some(p) = &st.playing {
            let at = p.stopped_at.unwrap_or(0.0);
            let (joints, registers) = settle(&p.c, at, st.joints, st.registers);
            st.joints = joints;
            st.registers = registers;
            st.tcp = p.c.tcp;
        }
        let tcp0 = Pose(self.options.tcp_offset).to_iso();
        match program::compile(text, &self.options.kinematics, &st.joints, &tcp0) {
            Ok(c) => {
                st.first_start.get_or_insert(now);
                st.programs += 1;
                st.playing = Some(Playing { c, t0: now, stopped_at: None });
            }
            Err(e) => push_error(&mut st.errors, format!("program refused: {e}")),
        }
    }

    /// Dashboard `stop`.
    fn stop_program(&self) {
        let mut st = self.lock();
        self.advance(&mut st);
        let now = self.clock();
        let State { playing, joints, registers, .. } = &mut *st;
        if let Some(p) = playing
            && p.stopped_at.is_none()
        {
            let at = now - p.t0;
            p.stopped_at = Some(at);
            let (j, r) = settle(&p.c, at, *joints, *registers);
            *joints = j;
            *registers = r;
        }
    }
}

fn push_error(errors: &mut Vec<String>, e: String) {
    if errors.len() >= 64 {
        errors.remove(0);
    }
    errors.push(e);
}

/// The joints and registers after `t` s of program `c` (from `joints`, `registers`).
fn settle(c: &Compiled, t: f64, joints: [f64; 6], mut registers: [i32; 48]) -> ([f64; 6], [i32; 48]) {
    let joints = c.joints.iter().rev().find(|(te, _)| *te <= t + 1e-12).map_or(joints, |(_, q)| *q);
    for (te, r, v) in &c.registers {
        if *te <= t + 1e-12 && *r < registers.len() {
            registers[*r] = *v;
        }
    }
    (joints, registers)
}

/// The pose at time `t` on a timed path (linear between samples; the first before it starts,
/// the last after it ends).
fn pose_at(samples: &[TraceEntry], t: f64) -> Option<Pose> {
    let first = samples.first()?;
    if t <= first.t_s {
        return Some(first.pose);
    }
    let i = samples.partition_point(|s| s.t_s <= t);
    if i >= samples.len() {
        return samples.last().map(|s| s.pose);
    }
    let (a, b) = (&samples[i - 1], &samples[i]);
    let f = if b.t_s > a.t_s { (t - a.t_s) / (b.t_s - a.t_s) } else { 1.0 };
    Some(crate::exec::pose_between(&a.pose.to_iso(), &b.pose.to_iso(), f))
}

/// A running UR5e stand-in.
pub struct UrSimulator {
    script: SocketAddr,
    rtde: SocketAddr,
    dashboard: SocketAddr,
    shared: Arc<Shared>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl UrSimulator {
    /// Starts the stand-in on `listen` with `options`.
    ///
    /// # Errors
    /// [`RobotError::Io`] if a port cannot be bound; [`RobotError::Config`] for options out of
    /// range (a time scale not in (0, 1000], no connections, a zero idle time-out, kinematics
    /// out of range, a TCP offset or payload not finite).
    pub fn start(listen: &UrListen, options: UrSimOptions) -> Result<Self, RobotError> {
        let config = |message: String| RobotError::Config { file: "simulator".into(), message };
        if !(options.time_scale > 0.0 && options.time_scale <= 1000.0) {
            return Err(config(format!("time scale {} is not in (0, 1000]", options.time_scale)));
        }
        if options.max_connections == 0 || options.idle_timeout.is_zero() {
            return Err(config("max_connections and idle_timeout must be positive".into()));
        }
        if !(options.tcp_offset.iter().all(|v| v.is_finite()) && options.payload_kg.is_finite()) {
            return Err(config("the TCP offset and the payload must be finite".into()));
        }
        options.kinematics.validate().map_err(|m| config(format!("kinematics: {m}")))?;
        let tcp = Pose(options.tcp_offset).to_iso();
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                joints: UR_HOME_JOINTS,
                tcp,
                registers: [0; 48],
                playing: None,
                protective_stop: false,
                errors: Vec::new(),
                first_start: None,
                programs: 0,
            }),
            options,
            connections: AtomicUsize::new(0),
            origin: Instant::now(),
        });
        let bind = |addr: &str| -> Result<(TcpListener, SocketAddr), RobotError> {
            let io = |source| RobotError::Io { context: addr.to_string(), source };
            let l = TcpListener::bind(addr).map_err(io)?;
            let a = l.local_addr().map_err(io)?;
            l.set_nonblocking(true).map_err(io)?;
            Ok((l, a))
        };
        let (ls, script) = bind(&listen.script)?;
        let (lr, rtde_addr) = bind(&listen.rtde)?;
        let (ld, dashboard) = bind(&listen.dashboard)?;
        let stop = Arc::new(AtomicBool::new(false));
        let (sh, st) = (shared.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let listeners = [(ls, Port::Script), (lr, Port::Rtde), (ld, Port::Dashboard)];
            while !st.load(Ordering::SeqCst) {
                let mut idle = true;
                for (l, port) in &listeners {
                    let Ok((stream, _)) = l.accept() else { continue };
                    idle = false;
                    if sh.connections.load(Ordering::SeqCst) >= sh.options.max_connections {
                        continue; // closed at once
                    }
                    sh.connections.fetch_add(1, Ordering::SeqCst);
                    let (sh, st, port) = (sh.clone(), st.clone(), *port);
                    std::thread::spawn(move || {
                        let _ = stream.set_nodelay(true);
                        let _ = stream.set_write_timeout(Some(sh.options.idle_timeout));
                        match port {
                            Port::Script => serve_script(stream, &sh, &st),
                            Port::Rtde => serve_rtde(stream, &sh, &st),
                            Port::Dashboard => serve_dashboard(stream, &sh, &st),
                        }
                        sh.connections.fetch_sub(1, Ordering::SeqCst);
                    });
                }
                if idle {
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        });
        Ok(UrSimulator { script, rtde: rtde_addr, dashboard, shared, stop, thread: Some(thread) })
    }

    /// The script port's address.
    pub fn script_addr(&self) -> SocketAddr {
        self.script
    }

    /// RTDE's address.
    pub fn rtde_addr(&self) -> SocketAddr {
        self.rtde
    }

    /// The dashboard server's address.
    pub fn dashboard_addr(&self) -> SocketAddr {
        self.dashboard
    }

    /// Refusals and runtime errors of the programs sent, oldest first (the latest 64).
    pub fn errors(&self) -> Vec<String> {
        self.shared.lock().errors.clone()
    }

    /// Programs started.
    pub fn programs(&self) -> usize {
        self.shared.lock().programs
    }

    /// The TCP pose now.
    pub fn pose(&self) -> Pose {
        self.shared.snapshot().pose
    }

    /// Connections served now.
    pub fn connections(&self) -> usize {
        self.shared.connections.load(Ordering::SeqCst)
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for UrSimulator {
    fn drop(&mut self) {
        self.shutdown();
    }
}

#[derive(Clone, Copy)]
enum Port {
    Script,
    Rtde,
    Dashboard,
}

/// The script port: programs (`def NAME(): … end`) run as each completes; lines outside a
/// program are refused by line and name. The connection is closed when the peer closes it, it
/// sends more than [`MAX_SCRIPT_BYTES`] without completing a program, or stays silent (or
/// sends only whitespace) for the idle time-out.
fn serve_script(mut stream: TcpStream, sh: &Shared, stop: &AtomicBool) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = vec![0u8; 16 * 1024];
    let mut last = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        match read_text(&mut stream, &mut chunk, &mut buf, &mut last) {
            TextRead::Closed => break,
            TextRead::Got => {
                if !take_programs(&mut buf, sh) {
                    break;
                }
            }
            TextRead::Quiet => {}
        }
        if last.elapsed() >= sh.options.idle_timeout {
            break;
        }
    }
}

/// What one read of a text port (script, dashboard) gave.
enum TextRead {
    /// The peer closed the connection, or it failed.
    Closed,
    /// Nothing within the read time-out.
    Quiet,
    /// Bytes, appended to the buffer.
    Got,
}

/// Reads what `stream` has into `chunk` and appends it to `buf`; `last` becomes now when any of
/// it is not white space (the idle time-out counts from there).
fn read_text(stream: &mut TcpStream, chunk: &mut [u8], buf: &mut Vec<u8>, last: &mut Instant) -> TextRead {
    match stream.read(chunk) {
        Ok(0) => TextRead::Closed,
        Ok(n) => {
            if chunk[..n].iter().any(|b| !b.is_ascii_whitespace()) {
                *last = Instant::now();
            }
            buf.extend_from_slice(&chunk[..n]);
            TextRead::Got
        }
        Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => TextRead::Quiet,
        Err(_) => TextRead::Closed,
    }
}

/// Runs every complete program in `buf` and drops what it consumed; `false` when the
/// connection must close (too much without a program, or text that is not UTF-8).
fn take_programs(buf: &mut Vec<u8>, sh: &Shared) -> bool {
    loop {
        // Whole lines only.
        let Some(end) = buf.iter().rposition(|&b| b == b'\n') else {
            return buf.len() <= MAX_SCRIPT_BYTES;
        };
        let Ok(text) = std::str::from_utf8(&buf[..=end]) else {
            let mut st = sh.lock();
            push_error(&mut st.errors, "script refused: not UTF-8".into());
            return false;
        };
        // Leading blank lines and comments wait for their program; a line outside a program
        // is refused by its name.
        let mut offset = 0;
        let mut program_start = None;
        for line in text.split_inclusive('\n') {
            let l = line.trim_end_matches('\n');
            if program_start.is_none() {
                if l.trim().is_empty() || l.starts_with('#') {
                    offset += line.len();
                    continue;
                }
                if l.starts_with("def ") || l.starts_with("sec ") {
                    program_start = Some(offset);
                } else {
                    let name: String = l
                        .trim_start()
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .take(64)
                        .collect();
                    let e = format!(
                        "script refused: line {:?} outside a program{}: the stand-in runs only maobi's programs",
                        l.chars().take(80).collect::<String>(),
                        if name.is_empty() { String::new() } else { format!(" (`{name}`)") }
                    );
                    push_error(&mut sh.lock().errors, e);
                    offset += line.len();
                    continue;
                }
            }
            offset += line.len();
            if l == "end" {
                break;
            }
        }
        let Some(start) = program_start else {
            buf.drain(..offset);
            return true;
        };
        let text_end = offset;
        let program = &text[..text_end];
        if !program.lines().any(|l| l == "end") {
            // Incomplete: wait for more (within the limit).
            buf.drain(..start);
            return buf.len() <= MAX_SCRIPT_BYTES;
        }
        // The header comments before the program belong to it.
        sh.run_program(program);
        buf.drain(..text_end);
    }
}

/// RTDE: version negotiation, the controller's version, one output recipe, start/pause, then
/// data packages at the recipe's frequency (on the wall clock).
fn serve_rtde(mut stream: TcpStream, sh: &Shared, stop: &AtomicBool) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(2)));
    let mut dec = PackageDecoder::default();
    let mut chunk = vec![0u8; 16 * 1024];
    let mut recipe: Option<(Vec<String>, Vec<FieldType>, f64)> = None;
    let mut started = false;
    let mut next = Instant::now();
    let mut last = Instant::now();
    let reply = |stream: &mut TcpStream, cmd: u8, payload: &[u8]| -> bool {
        rtde::encode(cmd, payload).is_ok_and(|p| stream.write_all(&p).is_ok())
    };
    while !stop.load(Ordering::SeqCst) {
        match stream.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                last = Instant::now();
                dec.push(&chunk[..n]);
            }
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(_) => break,
        }
        loop {
            let (cmd, payload) = match dec.next_package() {
                Ok(Some(p)) => p,
                Ok(None) => break,
                Err(_) => return,
            };
            let ok = match cmd {
                rtde::REQUEST_PROTOCOL_VERSION => {
                    let v = (payload.len() == 2).then(|| u16::from_be_bytes([payload[0], payload[1]]));
                    reply(&mut stream, cmd, &[u8::from(matches!(v, Some(1 | 2)))])
                }
                rtde::GET_URCONTROL_VERSION => {
                    let v = sh.options.version;
                    let mut p = Vec::new();
                    for x in [v.major, v.minor, v.bugfix, v.build] {
                        p.extend_from_slice(&x.to_be_bytes());
                    }
                    reply(&mut stream, cmd, &p)
                }
                rtde::SETUP_OUTPUTS => {
                    let (answer, r) = setup_outputs(&payload);
                    if started {
                        reply(&mut stream, cmd, &[0])
                    } else {
                        recipe = r;
                        reply(&mut stream, cmd, &answer)
                    }
                }
                rtde::SETUP_INPUTS => {
                    // No inputs are served: every name is NOT_FOUND.
                    let names = String::from_utf8_lossy(&payload).split(',').count().min(MAX_RECIPE_FIELDS);
                    let mut p = vec![0u8];
                    p.extend_from_slice(vec!["NOT_FOUND"; names].join(",").as_bytes());
                    reply(&mut stream, cmd, &p)
                }
                rtde::START => {
                    started = recipe.is_some();
                    next = Instant::now();
                    reply(&mut stream, cmd, &[u8::from(started)])
                }
                rtde::PAUSE => {
                    started = false;
                    reply(&mut stream, cmd, &[1])
                }
                // Data and text from the client: inputs are not served; both are dropped.
                rtde::DATA_PACKAGE | rtde::TEXT_MESSAGE => true,
                _ => return,
            };
            if !ok {
                return;
            }
        }
        if dec.pending() > rtde::MAX_PACKAGE_BYTES {
            return;
        }
        let f = sh.options.faults;
        if sh.due(f.rtde_close_at_s) {
            return;
        }
        if started {
            let Some((names, types, hz)) = &recipe else { return };
            if Instant::now() >= next && !sh.due(f.rtde_silent_at_s) {
                let snap = sh.snapshot();
                let mut p = vec![1u8];
                for (n, t) in names.iter().zip(types) {
                    field(n, *t, &snap, sh).write(&mut p);
                }
                if sh.due(f.rtde_garbage_at_s) {
                    p.pop();
                }
                if !reply(&mut stream, rtde::DATA_PACKAGE, &p) {
                    return;
                }
                next += Duration::from_secs_f64(1.0 / hz);
                if next < Instant::now() {
                    next = Instant::now();
                }
            }
        } else if last.elapsed() >= sh.options.idle_timeout {
            return;
        }
    }
}

/// The answer to an output setup and the recipe it makes (none when a name is unknown or the
/// frequency out of range).
#[allow(clippy::type_complexity, reason = "the recipe's names, types and frequency, used once")]
fn setup_outputs(payload: &[u8]) -> (Vec<u8>, Option<(Vec<String>, Vec<FieldType>, f64)>) {
    let refuse = |n: usize| {
        let mut p = vec![0u8];
        p.extend_from_slice(vec!["NOT_FOUND"; n.max(1)].join(",").as_bytes());
        (p, None)
    };
    if payload.len() < 8 {
        return refuse(1);
    }
    let hz = f64::from_be_bytes(payload[..8].try_into().expect("8 bytes"));
    let Ok(text) = std::str::from_utf8(&payload[8..]) else { return refuse(1) };
    let names: Vec<&str> = text.split(',').collect();
    if names.len() > MAX_RECIPE_FIELDS || !(hz > 0.0 && hz <= rtde::MAX_FREQUENCY_HZ) {
        return refuse(names.len().min(MAX_RECIPE_FIELDS));
    }
    let types: Vec<Option<FieldType>> = names.iter().map(|n| rtde::output_type(n)).collect();
    let text: Vec<&str> = types.iter().map(|t| t.map_or("NOT_FOUND", FieldType::name)).collect();
    let ok = types.iter().all(Option::is_some);
    let mut p = vec![u8::from(ok)];
    p.extend_from_slice(text.join(",").as_bytes());
    let recipe = ok.then(|| (names.iter().map(|s| s.to_string()).collect(), types.into_iter().flatten().collect(), hz));
    (p, recipe)
}

/// One field's value now.
fn field(name: &str, t: FieldType, s: &Snapshot, sh: &Shared) -> Value {
    let safety_bits = if s.protective_stop { 1 << 2 } else { 1 };
    match name {
        "timestamp" => Value::Double(s.clock_s),
        "actual_q" => Value::Vector6d(s.joints),
        "actual_TCP_pose" | "target_TCP_pose" => Value::Vector6d(pose_to_ur(&s.pose)),
        "tcp_offset" => Value::Vector6d(s.tcp),
        "robot_mode" => Value::Int32(crate::ur::ROBOT_MODE_RUNNING),
        "safety_mode" | "safety_status" => Value::Int32(if s.protective_stop { 3 } else { 1 }),
        "runtime_state" => Value::Uint32(s.runtime_state),
        "robot_status_bits" => Value::Uint32(1 | (u32::from(s.runtime_state == crate::ur::RUNTIME_PLAYING) << 1)),
        "safety_status_bits" => Value::Uint32(safety_bits),
        "speed_scaling" | "target_speed_fraction" => Value::Double(1.0),
        "payload" => Value::Double(sh.options.payload_kg),
        _ => {
            let idx = |p: &str| name.strip_prefix(p).and_then(|d| d.parse::<usize>().ok());
            match (t, idx("output_int_register_")) {
                (FieldType::Int32, Some(i)) => Value::Int32(s.registers.get(i).copied().unwrap_or(0)),
                (FieldType::Double, _) => Value::Double(0.0),
                (FieldType::Bool, _) => Value::Bool(false),
                _ => Value::Int32(0),
            }
        }
    }
}

/// The dashboard server: the greeting, then one answer per command line.
fn serve_dashboard(mut stream: TcpStream, sh: &Shared, stop: &AtomicBool) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    if stream.write_all(format!("{DASHBOARD_GREETING}\n").as_bytes()).is_err() {
        return;
    }
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = [0u8; 1024];
    let mut last = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        if let TextRead::Closed = read_text(&mut stream, &mut chunk, &mut buf, &mut last) {
            return;
        }
        while let Some(i) = buf.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = buf.drain(..=i).collect();
            let cmd = String::from_utf8_lossy(&line).trim().to_string();
            if cmd.is_empty() {
                continue;
            }
            let (answer, close) = dashboard_answer(&cmd, sh);
            if stream.write_all(format!("{answer}\n").as_bytes()).is_err() || close {
                return;
            }
        }
        if buf.len() > MAX_DASHBOARD_LINE || last.elapsed() >= sh.options.idle_timeout {
            return;
        }
    }
}

/// The answer to a dashboard command, and whether to close after it.
fn dashboard_answer(cmd: &str, sh: &Shared) -> (String, bool) {
    let snap = sh.snapshot();
    let name = sh.lock().playing.as_ref().map_or("<unnamed>".to_string(), |p| p.c.name.clone());
    let playing = snap.runtime_state == crate::ur::RUNTIME_PLAYING;
    let answer = match cmd.to_ascii_lowercase().as_str() {
        "stop" => {
            sh.stop_program();
            "Stopped".to_string()
        }
        "programstate" => format!("{} {name}", if playing { "PLAYING" } else { "STOPPED" }),
        "running" => format!("Program running: {playing}"),
        "robotmode" => "Robotmode: RUNNING".to_string(),
        "safetystatus" => {
            format!("Safetystatus: {}", if snap.protective_stop { "PROTECTIVE_STOP" } else { "NORMAL" })
        }
        "polyscopeversion" => {
            let v = sh.options.version;
            format!("URSoftware {}.{}.{}.{} (maobi's UR5e stand-in)", v.major, v.minor, v.bugfix, v.build)
        }
        "is in remote control" => sh.options.remote_control.to_string(),
        "unlock protective stop" => {
            sh.lock().protective_stop = false;
            "Protective stop releasing".to_string()
        }
        "quit" => return ("Disconnected".to_string(), true),
        _ => format!("could not understand: '{}'", cmd.chars().take(80).collect::<String>()),
    };
    (answer, false)
}
