//! # robot-grbl
//!
//! Streams maobi's checked G-code (`robot_io::gcode_chars`) to a GRBL 1.1 brush
//! plotter, live, over a serial device (USB serial, a pseudo-terminal) or TCP:
//!
//! 1. [`Grbl::connect`]: waits for the `Grbl 1.1…` banner (a soft reset if none comes), reads
//!    `$I`, `$$`, `$#`, `$G` and a status report. Nothing moves.
//! 2. [`check_program`]: refuses, before anything moves, a machine that cannot run the program
//!    as checked, naming the setting and what the program needs: an alarm or a state other than
//!    `Idle`, inch reports (`$13`), a `G92` or tool length offset (a reset clears them), feeds
//!    beyond the maximum rates (`$110`–`$112`; or every feed slowed by one factor, said so),
//!    targets outside the soft limits' travel (`$20`, `$130`–`$132`).
//! 3. [`Grbl::stream`]: GRBL's character-counting protocol (never more than its receive
//!    buffer in flight, every line answered `ok`), progress after every answer, and on
//!    `error:N`, `ALARM:N`, Ctrl-C, a reset or a silent link a safe stop
//!    ([`Grbl::safe_stop`]: feed hold, soft reset in the hold so the position is kept, the
//!    brush raised) reported with the last acknowledged line; the run ends when the last line
//!    is acknowledged and the machine is `Idle`.
//!
//! Tested against the real GRBL 1.1h firmware compiled for the host by grbl-sim, over a
//! pseudo-terminal (`tests/firmware.rs`; the sources are vendored under `third_party/grbl`
//! in the maobi repository, outside this crate).
//!
//! ```no_run
//! use std::sync::atomic::AtomicBool;
//! use robot_grbl::{GcodeProgram, Grbl, LinkOptions, RateFit, SerialLink, check_program};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let text = std::fs::read_to_string("yong.gcode")?; // `maobi robot export --format gcode`
//! let program = GcodeProgram::from_export(&text, 3000.0)?;
//! let port = SerialLink::open("/dev/ttyUSB0", 115_200)?;
//! let (mut grbl, info) = Grbl::connect(Box::new(port), LinkOptions::default())?;
//! let checked = check_program(&info, &program, RateFit::Refuse)?;
//! let stop = AtomicBool::new(false);
//! let done = grbl.stream(&info, &program, checked.feed_scale, &stop, &mut |p| {
//!     eprintln!("{} of {} lines, {:.0} s left", p.lines_acked, p.lines_total, p.remaining_s)
//! })?;
//! println!("written in {:.1} s (planned {:.1} s)", done.elapsed_s, done.planned_s);
//! # Ok(())
//! # }
//! ```

#![warn(unreachable_pub)]

// The README's example runs as a doctest (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod codes;
mod controller;
mod link;
mod machine;
mod program;
mod response;
mod stream;

pub use codes::{alarm_meaning, error_meaning};
pub use controller::{Endpoint, GrblPlotter};
pub use link::{MAX_LINE_BYTES, Port, SerialLink, TcpLink};
pub use machine::{Checked, DEFAULT_RX_BUFFER, Grbl, LinkOptions, MachineInfo, RateFit, check_program};
pub use program::{GRBL_MAX_LINE, GcodeProgram, LineKind, ProgramLine};
pub use response::{Response, State, Status};
pub use stream::{SafeStop, StreamProgress, StreamReport};

use thiserror::Error;

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum Fault {
    /// The machine refused a line (`error:N`): the code with GRBL's meaning, the line's number
    /// in the G-code file and its text as sent.
    Firmware {
        /// `error:N (meaning)`.
        what: String,
        /// The line's number in the exported G-code (1-based).
        line: usize,
        /// The line as sent.
        text: String,
    },
    /// `ALARM:N`.
    Alarm(u16),
    /// A status report in `Alarm` without an `ALARM:N` line.
    AlarmState,
    /// The machine printed its banner: it was reset (its button, a power dip, another program).
    Reset(String),
    /// Ctrl-C (or the caller's stop flag).
    Interrupted,
    /// No answer for this many seconds.
    Quiet(f64),
    /// The link failed or closed.
    Link(String),
    /// An answer out of the protocol.
    Protocol(String),
    /// The program has not finished long after its plan (a machine that reports but
    /// acknowledges nothing more): the time run and the planned time, s.
    Overdue {
        /// Seconds since the stream started.
        elapsed_s: f64,
        /// The program's planned time, s.
        planned_s: f64,
    },
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Firmware { what, line, text } => write!(f, "GRBL answered {what} to line {line} `{text}`"),
            Fault::Alarm(code) => write!(f, "GRBL raised {}", codes::describe("ALARM", *code)),
            Fault::AlarmState => write!(f, "GRBL reports Alarm"),
            Fault::Reset(v) => write!(f, "GRBL reset itself (its banner `Grbl {v}` came mid-run)"),
            Fault::Interrupted => write!(f, "interrupted (Ctrl-C)"),
            Fault::Quiet(s) => write!(f, "GRBL did not answer for {s:.1} s: the link is lost"),
            Fault::Link(e) => write!(f, "the link failed: {e}"),
            Fault::Protocol(e) => write!(f, "out of GRBL's protocol: {e}"),
            Fault::Overdue { elapsed_s, planned_s } => write!(
                f,
                "the program has not finished after {elapsed_s:.1} s (planned {planned_s:.1} s): GRBL acknowledges nothing more"
            ),
        }
    }
}

/// How a run that stopped ended.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Stopped {
    /// Why.
    pub cause: Fault,
    /// Lines acknowledged.
    pub lines_acked: usize,
    /// Lines in the program.
    pub lines_total: usize,
    /// Strokes whose lift was acknowledged.
    pub strokes_done: usize,
    /// Strokes in the program.
    pub strokes_total: usize,
    /// The last acknowledged line: its number in the G-code file and its text.
    pub last_acked: Option<(usize, String)>,
    /// What the safe stop did.
    pub safe: SafeStop,
}

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}; stopped after {} of {} lines", self.cause, self.lines_acked, self.lines_total)?;
        match &self.last_acked {
            Some((n, t)) => write!(f, " (the last acknowledged: line {n} `{t}`)")?,
            None => write!(f, " (none acknowledged)")?,
        }
        write!(f, "; {}", self.safe.how)?;
        if let Some([x, y, z]) = self.safe.work_mm {
            write!(f, "; last reported at work X{x:.3} Y{y:.3} Z{z:.3}")?;
        }
        Ok(())
    }
}

/// Errors of robot-grbl.
#[derive(Debug, Error)]
pub enum GrblError {
    /// The link could not be opened, failed or closed (`context`: the device or what was done).
    #[error("{context}")]
    Io {
        /// The device, address or operation.
        context: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// No answer in time.
    #[error("timeout waiting for {0}")]
    Timeout(String),
    /// Answers out of GRBL's protocol.
    #[error("protocol: {0}")]
    Protocol(String),
    /// The machine cannot run the program as checked; nothing moved. Says which setting or state
    /// and what the program needs.
    #[error("refused before any motion: {0}")]
    Refused(String),
    /// The run stopped after lines were sent.
    #[error("{0}")]
    Stopped(Box<Stopped>),
}
