//! A loopback AUBO JSON-RPC simulator: serves the SDK's framed transport (with its login) and,
//! only when asked, the line-delimited form and JSON-RPC over HTTP (both unauthenticated);
//! validates every request (named or positional params), executes moves on a model of the arm
//! (the executor of [`crate::execute_program`]), answers `getExecId`, `isSteady`, `getTcpPose` and
//! `getJointPositions`, injects faults, and records the executed TCP path.
//!
//! It is built to survive a hostile client (docs/robot.md, "The simulator as a server"): one
//! session at a time owns motion, requests are parsed incrementally under a byte limit,
//! connections are bounded in number and idle time, every move's trace is bounded and streamed
//! to the trace file, and no lock is held while a move is computed.

mod blend;
mod dispatch;

pub use blend::{BLEND_SLACK_M, BlendMove, BlendRefused, blended_line_motion, check_blend};
pub use dispatch::{
    MAX_BLEND_CHAIN, MAX_BUFFER_NAME, MAX_BUFFER_WAYPOINTS, MAX_PATH_BUFFERS, MAX_TOTAL_WAYPOINTS, PATH_BUFFER_SPLINE,
    ramped_joint_motion, ramped_line_motion,
};
mod fault_spec;
mod replay;
mod script;
mod server;
pub use server::EVICT_AFTER;
mod session;
mod ur;

pub use script::{LUA_MEMORY_BYTES, MAX_INSTRUCTIONS, MAX_LUA_SCRIPT_BYTES, MAX_NAMED_INTS, MAX_SCRIPT_TIME};
pub use ur::{
    DASHBOARD_GREETING, MAX_DASHBOARD_LINE, MAX_PROGRAM_SAMPLES, MAX_RECIPE_FIELDS, MAX_SCRIPT_BYTES, UrFaults,
    UrListen, UrSimOptions, UrSimulator,
};

pub use fault_spec::{AUBO_FAULT_KEYS, FaultSpecError, UR_FAULT_KEYS};
pub use replay::{SendMotion, execute_as_sent, execute_as_sent_tagged};

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::RobotError;
use crate::exec::TraceEntry;
use crate::wire::Transport;

/// Faults to inject.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Faults {
    /// Close the connection (once) when the N-th move request arrives, without executing it.
    pub drop_after_moves: Option<usize>,
    /// Delay every answer by this many milliseconds.
    pub delay_ms: Option<u64>,
    /// Answer every K-th move request with 2 (queue full) without executing it.
    pub queue_full_every: Option<usize>,
}

/// The robot name the simulator answers to.
pub const SIM_ROBOT: &str = "rob1";

/// Slowest move the simulator executes, m/s for `moveLine` and rad/s for `moveJoint`: a
/// commanded speed below it (or one the speed fraction brings below it) is refused with
/// status −5. At 0.1 mm/s a 1 m move already takes about 3 hours; nothing slower is a brush
/// stroke. (A physical choice: the controller's own minimum is not documented.)
pub const MIN_MOVE_SPEED: f64 = 1e-4;
/// Smallest speed fraction `setSpeedFraction` accepts (1 %, the lowest step of the pendant's
/// speed slider; an assumption).
pub const MIN_SPEED_FRACTION: f64 = 0.01;
/// Largest request the simulator reads, bytes (1 MiB): one frame's payload, one HTTP body or
/// one line-delimited JSON text. A longer one is answered with an error naming the limit and
/// the connection is closed; the simulator never buffers more than this (and one read) for a
/// connection.
pub const MAX_REQUEST_BYTES: usize = 1 << 20;
/// JSON-RPC error code for a motion request while another session owns motion (an assumption:
/// the code a real controller uses is not known).
pub const MOTION_OWNED: i64 = -32001;

/// What the simulator answers to besides its listeners: the faults to inject, the one user who
/// may log in over the framed transport, the arm's kinematics, and its limits.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    /// Faults to inject.
    pub faults: Faults,
    /// The user the framed login accepts.
    pub user: String,
    /// The password the framed login accepts (compared by its digest, as a controller would).
    pub password: String,
    /// Most connections served at once; a further one takes the place of the connection that
    /// has gone longest without a request answered (at least [`EVICT_AFTER`]), or is closed as
    /// soon as it is accepted when none has.
    pub max_connections: usize,
    /// A connection that sends nothing for this long is closed.
    pub idle_timeout: Duration,
    /// Write the executed TCP path here as JSON lines (one [`TraceEntry`] each), flushed after
    /// every move. A write that fails (a full disk) stops the file there and is reported by
    /// [`Simulator::trace_error`]; the simulator keeps serving.
    pub trace_path: Option<PathBuf>,
    /// Most trace samples kept in memory (the latest; [`Simulator::trace`]).
    pub trace_window: usize,
    /// The trace file's size limit, bytes: the sample that would pass it is not written, the
    /// file ends there and [`Simulator::trace_error`] says so; the simulator keeps serving.
    pub trace_max_bytes: u64,
    /// How long a motion request from another session waits for the session that owns motion
    /// to close its connection before it is refused (a client that reconnects after a dropped
    /// link may be faster than the simulator noticing that the old connection closed).
    pub owner_wait: Duration,
    /// The arm's modified-DH parameters, in the controller's convention: the simulator moves,
    /// answers `RobotAlgorithm.inverseKinematics`/`forwardKinematics` and reports
    /// `RobotConfig.getKinematicsParam` with them.
    pub kinematics: crate::kinematics::DhParams,
    /// Whether `RobotConfig.getKinematicsParam` and `getKinematicsCompensate` are served
    /// (`false`: answered with JSON-RPC −32601, method not found, as a controller without them
    /// would). `getKinematicsParam(false)` reports [`crate::kinematics::DhParams::AUBO_I5`],
    /// `(true)` [`SimOptions::kinematics`], and the compensation is their difference.
    pub kinematics_param: bool,
}

impl Default for SimOptions {
    /// No faults; the controller's default user `aubo`, password `123456`; 16 connections,
    /// 60 s idle time-out; no trace file (at most 256 MiB when one is asked for), the last
    /// 262 144 samples (16 MiB) kept in memory; a
    /// second session's motion request waits 1 s for the owner to go; the i5's nominal
    /// kinematics ([`crate::kinematics::DhParams::AUBO_I5`]), reported by
    /// `getKinematicsParam`.
    fn default() -> Self {
        Self {
            faults: Faults::default(),
            user: crate::wire::DEFAULT_USER.into(),
            password: crate::wire::DEFAULT_PASSWORD.into(),
            max_connections: 16,
            idle_timeout: Duration::from_secs(60),
            trace_path: None,
            trace_window: 1 << 18,
            trace_max_bytes: 256 << 20,
            owner_wait: Duration::from_secs(1),
            kinematics: crate::kinematics::DhParams::AUBO_I5,
            kinematics_param: true,
        }
    }
}

/// One port the simulator listens on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Listen {
    /// The address to bind, for example `127.0.0.1:30004` (`:0` for any free port).
    pub bind: String,
    /// The transports it serves. With more than one, each connection's first byte tells them
    /// apart (`S` of `SOF`: framed; `{` or `[`: lines; a capital letter, as in `POST`: HTTP); a
    /// connection speaking another is closed. Lines and HTTP have no login: serve them only on
    /// a trusted host.
    pub transports: Vec<Transport>,
}

impl Listen {
    /// `127.0.0.1:port` (port 0: any free one) serving `transports`.
    pub fn loopback(port: u16, transports: &[Transport]) -> Self {
        Listen { bind: format!("127.0.0.1:{port}"), transports: transports.to_vec() }
    }

    /// The listeners of a simulator on loopback: `port` serving `transports` (each connection's
    /// first bytes telling them apart), then each port of `alone` serving its one transport.
    ///
    /// # Examples
    /// ```
    /// use robot_io::sim::Listen;
    /// use robot_io::wire::Transport;
    /// let l = Listen::loopback_ports(30004, &[Transport::Framed], [(9012, Transport::Http)]);
    /// assert_eq!(l, [Listen::loopback(30004, &[Transport::Framed]), Listen::loopback(9012, &[Transport::Http])]);
    /// assert_eq!(l[1].bind, "127.0.0.1:9012");
    /// ```
    pub fn loopback_ports(
        port: u16,
        transports: &[Transport],
        alone: impl IntoIterator<Item = (u16, Transport)>,
    ) -> Vec<Self> {
        std::iter::once(Listen::loopback(port, transports))
            .chain(alone.into_iter().map(|(p, t)| Listen::loopback(p, &[t])))
            .collect()
    }
}

/// A running simulator.
pub struct Simulator {
    /// The address it listens on (the first listener's).
    pub addr: std::net::SocketAddr,
    addrs: Vec<(Vec<Transport>, std::net::SocketAddr)>,
    shared: Arc<dispatch::Shared>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Simulator {
    /// Starts a simulator on `bind` (for example `127.0.0.1:0` for any free port) serving every
    /// transport on that one port (the unauthenticated ones included: for tests), with the
    /// default login and limits.
    ///
    /// # Errors
    /// [`RobotError::Io`] if the address cannot be bound.
    pub fn start(bind: &str, faults: Faults) -> Result<Self, RobotError> {
        Self::start_with(
            &[Listen { bind: bind.to_string(), transports: Transport::ALL.to_vec() }],
            SimOptions { faults, ..SimOptions::default() },
        )
    }

    /// Starts a simulator listening on every address of `listen` (one shared arm).
    ///
    /// # Errors
    /// [`RobotError::Io`] if an address cannot be bound or the trace file cannot be created;
    /// [`RobotError::Config`] if `listen` is empty, a listener serves no transport, a limit in
    /// `options` is zero, or its kinematics are not finite and within range.
    pub fn start_with(listen: &[Listen], options: SimOptions) -> Result<Self, RobotError> {
        let config = |message: &str| RobotError::Config { file: "simulator".into(), message: message.into() };
        if listen.is_empty() {
            return Err(config("no port to listen on"));
        }
        if listen.iter().any(|l| l.transports.is_empty()) {
            return Err(config("a port must serve at least one transport"));
        }
        if options.max_connections == 0
            || options.idle_timeout.is_zero()
            || options.trace_window == 0
            || options.trace_max_bytes == 0
        {
            return Err(config("max_connections, idle_timeout, trace_window and trace_max_bytes must be positive"));
        }
        options.kinematics.validate().map_err(|m| config(&format!("kinematics: {m}")))?;
        let shared = Arc::new(dispatch::Shared::new(options)?);
        let stop = Arc::new(AtomicBool::new(false));
        let (thread, addrs) = server::listen(listen, shared.clone(), stop.clone())?;
        Ok(Simulator { addr: addrs[0].1, addrs, shared, stop, thread: Some(thread) })
    }

    /// Every listener: the transports it serves and its address.
    pub fn addrs(&self) -> &[(Vec<Transport>, std::net::SocketAddr)] {
        &self.addrs
    }

    /// Whether a listener serves a transport without login (lines or HTTP: anyone who reaches
    /// it can move the arm).
    pub fn serves_without_login(&self) -> bool {
        self.addrs.iter().any(|(ts, _)| ts.iter().any(|t| *t != Transport::Framed))
    }

    /// The first address serving `transport`.
    pub fn addr_of(&self, transport: Transport) -> Option<std::net::SocketAddr> {
        self.addrs.iter().find(|(t, _)| t.contains(&transport)).map(|(_, a)| *a)
    }

    /// The executed TCP path: all of it, or its latest [`SimOptions::trace_window`] samples
    /// when more were recorded (the trace file has all).
    pub fn trace(&self) -> Vec<TraceEntry> {
        self.shared.trace()
    }

    /// How many trace samples were recorded since the start (kept in memory or not).
    pub fn samples_recorded(&self) -> u64 {
        self.shared.samples_recorded()
    }

    /// Why the trace file stopped (a failed write, such as a full disk), or `None` while it is
    /// written (or when there is none).
    pub fn trace_error(&self) -> Option<String> {
        self.shared.trace_error()
    }

    /// Connections served now.
    pub fn connections(&self) -> usize {
        self.shared.connections()
    }

    /// Stops accepting connections.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Simulator {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Feeds a byte stream, in the given pieces, to one session of a fresh simulator without any
/// socket (the parsing and dispatch a connection gets: `transports` as a [`Listen`] serves
/// them), and returns the bytes it answered and whether it closed the session. For fuzzing and
/// tests of the request parser; faults and trace files in `options` apply as on a port.
///
/// # Errors
/// As [`Simulator::start_with`] for `options` (the trace file).
pub fn serve_bytes(
    options: SimOptions,
    transports: &[Transport],
    pieces: &[&[u8]],
) -> Result<(Vec<u8>, bool), RobotError> {
    let shared = dispatch::Shared::new(options)?;
    let mut s = session::Session::new(&shared, transports);
    let mut out = Vec::new();
    for p in pieces {
        let o = s.feed(p);
        for m in o.messages {
            out.extend_from_slice(&m);
        }
        if o.close {
            return Ok((out, true));
        }
    }
    Ok((out, false))
}
