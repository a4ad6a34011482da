//! Streaming a checked program with GRBL's character-counting protocol, and the safe stop.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::codes::{alarm_keeps_position, describe};
use crate::machine::{Grbl, MachineInfo, keep};
use crate::program::{GcodeProgram, LineKind};
use crate::response::{Response, State, Status};
use crate::{Fault, GrblError, Stopped};

/// How often a status report is asked for while streaming.
const POLL: Duration = Duration::from_millis(200);

/// How far a run has got.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StreamProgress {
    /// Lines acknowledged (`ok`: parsed and planned; the machine may still be moving through
    /// the last few).
    pub lines_acked: usize,
    /// Lines in the program.
    pub lines_total: usize,
    /// Strokes whose lift has been acknowledged.
    pub strokes_done: usize,
    /// Strokes in the program.
    pub strokes_total: usize,
    /// Seconds since the first line was sent.
    pub elapsed_s: f64,
    /// The planned time of the lines not yet acknowledged, s.
    pub remaining_s: f64,
    /// The last reported position, work mm.
    pub work_mm: Option<[f64; 3]>,
    /// The last reported state.
    pub state: Option<State>,
}

/// What a finished run did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StreamReport {
    /// Lines streamed (all acknowledged).
    pub lines: usize,
    /// Bytes streamed.
    pub bytes: usize,
    /// The most bytes ever in flight (sent, not yet acknowledged).
    pub max_in_flight: usize,
    /// Seconds from the first line to the machine `Idle` after the last.
    pub elapsed_s: f64,
    /// The program's planned time, s (at the feeds streamed).
    pub planned_s: f64,
    /// Where the machine stopped, work mm.
    pub work_mm: Option<[f64; 3]>,
    /// Messages the machine pushed (`[MSG:Pgm End]`).
    pub messages: Vec<String>,
}

/// The safe height the brush is raised to, and how.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SafeStop {
    /// Whether the brush is known to be off the paper (raised, the machine answered).
    pub lifted: bool,
    /// What was done, in words.
    pub how: String,
    /// Where the machine stopped, work mm, as last reported.
    pub work_mm: Option<[f64; 3]>,
}

/// A line sent and not yet acknowledged.
struct InFlight {
    index: usize,
    bytes: usize,
}

/// The lines as streamed: the program's, with every feed scaled by `scale`.
fn streamed_lines(program: &GcodeProgram, scale: f64) -> Vec<String> {
    program
        .lines
        .iter()
        .map(|l| {
            if scale >= 1.0 || l.kind != LineKind::Feed {
                return l.text.clone();
            }
            match l.text.rsplit_once('F') {
                Some((head, _)) => format!("{head}F{:.6}", l.feed_mm_min * scale),
                None => l.text.clone(),
            }
        })
        .collect()
}

impl Grbl {
    /// Streams `program` (checked by [`crate::check_program`], feeds scaled by `feed_scale`)
    /// with GRBL's character-counting protocol: lines are sent while the bytes not yet
    /// acknowledged stay below the receive buffer; every line must be answered `ok`. A status
    /// report is asked for every 200 ms; `progress` is called after every answer. The run ends
    /// when the last line is acknowledged and the machine reports `Idle`.
    ///
    /// On `error:N` or `ALARM:N`, when `stop` is set (Ctrl-C), when the machine resets itself or
    /// stops answering, the streaming stops and the brush is made safe where the machine still
    /// answers ([`Grbl::safe_stop`]); the error is [`GrblError::Stopped`] with the cause, the
    /// last acknowledged line and what the safe stop did.
    ///
    /// # Errors
    /// [`GrblError::Stopped`] as above.
    pub fn stream(
        &mut self,
        info: &MachineInfo,
        program: &GcodeProgram,
        feed_scale: f64,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&StreamProgress),
    ) -> Result<StreamReport, GrblError> {
        let mut run = Run::new(info, program, feed_scale);
        let timeout = self.opts.timeout;
        // The whole stream's bound: twice its plan and ten time-outs. Status reports keep a
        // link alive (`last_heard`); they do not keep a run that acknowledges nothing going.
        let overdue = Duration::from_secs_f64((2.0 * run.planned_total).clamp(0.0, 1e7)) + timeout * 10;
        loop {
            if stop.load(Ordering::SeqCst) {
                return Err(run.fault(self, Fault::Interrupted));
            }
            run.send(self)?;
            let now = Instant::now();
            run.poll(self, now)?;
            if let Some(cause) = run.late(now, timeout, overdue) {
                return Err(run.fault(self, cause));
            }
            let deadline = run.last_poll.map_or(now, |t| t + POLL).max(now + Duration::from_millis(5));
            let line = match self.lines.next_line(deadline) {
                Ok(Some(l)) => l,
                Ok(None) => continue,
                Err(e) => return Err(run.link_lost(&e)),
            };
            match run.answer(Response::parse(&line), progress) {
                Answer::Go => {}
                Answer::Done(report) => return Ok(report),
                Answer::Stop(cause) => return Err(run.fault(self, cause)),
            }
        }
    }

    /// Makes the brush safe after a fault, keeping the machine's position where GRBL can:
    ///
    /// 1. feed hold (`!`), and wait until the machine has stopped (`Hold:0`, `Idle` or
    ///    `Alarm`);
    /// 2. soft reset (Ctrl-X), which empties the planner and the receive buffer; GRBL keeps the
    ///    position when it is reset in a completed hold (not in motion);
    /// 3. in alarm, unlock (`$X`);
    /// 4. raise the brush: where the position is kept, straight up in machine coordinates
    ///    (`G53 G0 Z`) to the program's travel height over the work zero found at connect (the
    ///    reset cleared the parser's modes, not the offsets in EEPROM); where it may be lost
    ///    (a hard limit, a reset in motion), up by the travel height plus the deepest press,
    ///    relative (`G91 G0 Z`), and say so.
    ///
    /// Each step waits at most the link time-out (the hold: four of them); a machine that stops
    /// answering leaves the brush where it is, and the result says so.
    pub fn safe_stop(
        &mut self,
        info: &MachineInfo,
        program: &GcodeProgram,
        cause: &Fault,
        last: Option<&Status>,
    ) -> SafeStop {
        let mut work_mm = last.and_then(|s| work(s, info.wco));
        let mut steps: Vec<String> = Vec::new();
        let mut alarm = match cause {
            Fault::Alarm(c) => Some(*c),
            _ => None,
        };
        let result = (|| -> Result<bool, String> {
            // 1. Hold.
            self.lines.write(b"!").map_err(|e| e.to_string())?;
            steps.push("feed hold".into());
            let hold_deadline = Instant::now() + self.opts.timeout * 4;
            let mut held = false;
            while Instant::now() < hold_deadline {
                match self.poll_status(&mut alarm) {
                    Ok(Some(s)) => {
                        work_mm = work(&s, info.wco).or(work_mm);
                        if (s.state == State::Hold && s.sub == Some(0)) || matches!(s.state, State::Idle | State::Alarm)
                        {
                            held = true;
                            break;
                        }
                    }
                    Ok(None) => {}
                    Err(e) => return Err(e),
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            if !held {
                return Err("the machine did not come to a stop after the feed hold".into());
            }
            // 2. Reset: the queue goes, the position stays (stopped in a hold).
            self.lines.write(&[0x18]).map_err(|e| e.to_string())?;
            steps.push("soft reset".into());
            self.wait_for_banner(&mut alarm)?;
            let s = self.status_now(&mut alarm)?;
            work_mm = work(&s, info.wco).or(work_mm);
            // GRBL alarms when it loses the position (a reset in motion is ALARM:3); a reset
            // without an alarm kept it.
            let kept = alarm.is_none_or(alarm_keeps_position);
            // 3. Unlock.
            if s.state == State::Alarm {
                self.command("$X")?;
                steps.push("unlock ($X)".into());
            }
            // 4. Raise the brush.
            if kept {
                let machine_z = s.machine(info.wco).map(|m| m[2]);
                let target = info.wco[2] + program.lift_mm;
                if machine_z.is_some_and(|z| z >= target - 1e-3) {
                    steps.push(format!("the brush already above the travel height (work Z {:.3})", program.lift_mm));
                } else {
                    self.command(&format!("G53G0Z{target:.3}"))?;
                    steps.push(format!("brush raised to work Z {:.3} (G53 G0 Z{target:.3})", program.lift_mm));
                }
            } else {
                let up = program.lift_mm - program.min_z_mm.min(0.0);
                self.command(&format!("G91G0Z{up:.3}"))?;
                self.command("G90")?;
                steps.push(format!(
                    "the position may be lost: brush raised {up:.3} mm (G91 G0 Z{up:.3}); home or touch off again before the next run"
                ));
            }
            // The move is over when the machine is idle again.
            let deadline = Instant::now() + self.opts.timeout * 4;
            loop {
                let s = self.status_now(&mut alarm)?;
                work_mm = work(&s, info.wco).or(work_mm);
                if s.state == State::Idle {
                    return Ok(true);
                }
                if Instant::now() > deadline {
                    return Err(format!("the machine is {} after the lift, not Idle", s.state_text()));
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        })();
        match result {
            Ok(lifted) => SafeStop { lifted, how: steps.join(", "), work_mm },
            Err(e) => {
                let done = if steps.is_empty() { String::new() } else { format!(" after {}", steps.join(", ")) };
                SafeStop {
                    lifted: false,
                    how: format!(
                        "the brush could not be made safe{done}: {e}; it may still press into the paper: lift it by hand"
                    ),
                    work_mm,
                }
            }
        }
    }

    /// Asks for a status report and reads what comes until it (or `None` after 200 ms).
    fn poll_status(&mut self, alarm: &mut Option<u16>) -> Result<Option<Status>, String> {
        self.lines.write(b"?").map_err(|e| e.to_string())?;
        let deadline = Instant::now() + Duration::from_millis(200);
        loop {
            match self.lines.next_line(deadline).map_err(|e| e.to_string())? {
                None => return Ok(None),
                Some(l) => match Response::parse(&l) {
                    Response::Status(s) => return Ok(Some(s)),
                    Response::Alarm(a) => *alarm = Some(a),
                    _ => {}
                },
            }
        }
    }

    /// A status report within the time-out.
    fn status_now(&mut self, alarm: &mut Option<u16>) -> Result<Status, String> {
        let deadline = Instant::now() + self.opts.timeout;
        while Instant::now() < deadline {
            if let Some(s) = self.poll_status(alarm)? {
                return Ok(s);
            }
        }
        Err(format!("no status report for {:.1} s", self.opts.timeout.as_secs_f64()))
    }

    /// Waits for the banner after a reset.
    fn wait_for_banner(&mut self, alarm: &mut Option<u16>) -> Result<(), String> {
        let deadline = Instant::now() + self.opts.timeout.max(self.opts.banner_wait);
        loop {
            match self.lines.next_line(deadline).map_err(|e| e.to_string())? {
                None => return Err("no banner after the soft reset".into()),
                Some(l) => match Response::parse(&l) {
                    Response::Banner(_) => return Ok(()),
                    Response::Alarm(a) => *alarm = Some(a),
                    _ => {}
                },
            }
        }
    }

    /// Sends one command and waits for its `ok`.
    fn command(&mut self, cmd: &str) -> Result<(), String> {
        let mut messages = Vec::new();
        self.query(cmd, &mut messages).map(|_| ()).map_err(|e| format!("`{cmd}`: {e}"))
    }
}

/// What one answer from the machine means for a run.
enum Answer {
    /// Go on streaming.
    Go,
    /// The last line is acknowledged and the machine is idle.
    Done(StreamReport),
    /// Stop, and make the brush safe.
    Stop(Fault),
}

/// One run of [`Grbl::stream`]: the lines as streamed, what is in flight and acknowledged, and
/// what the machine last said.
struct Run<'a> {
    info: &'a MachineInfo,
    program: &'a GcodeProgram,
    /// The lines as streamed (feeds scaled).
    texts: Vec<String>,
    /// Each line's planned time at the feeds streamed, s.
    planned: Vec<f64>,
    planned_total: f64,
    /// The most bytes that may be in flight: strictly less than the receive buffer, as GRBL's
    /// own stream.py keeps it.
    limit: usize,
    /// The next line to send.
    next: usize,
    in_flight: VecDeque<InFlight>,
    in_flight_bytes: usize,
    acked: usize,
    max_in_flight: usize,
    bytes: usize,
    messages: Vec<String>,
    last: Option<Status>,
    start: Instant,
    last_poll: Option<Instant>,
    last_heard: Instant,
    /// Whether every line has been acknowledged (the next `Idle` ends the run).
    all_acked: bool,
}

impl<'a> Run<'a> {
    fn new(info: &'a MachineInfo, program: &'a GcodeProgram, feed_scale: f64) -> Self {
        let planned: Vec<f64> = program
            .lines
            .iter()
            .map(|l| if l.kind == LineKind::Feed && feed_scale < 1.0 { l.planned_s / feed_scale } else { l.planned_s })
            .collect();
        let now = Instant::now();
        Run {
            info,
            program,
            texts: streamed_lines(program, feed_scale),
            planned_total: planned.iter().sum(),
            planned,
            limit: info.rx_buffer - 1,
            next: 0,
            in_flight: VecDeque::new(),
            in_flight_bytes: 0,
            acked: 0,
            max_in_flight: 0,
            bytes: 0,
            messages: Vec::new(),
            last: None,
            start: now,
            last_poll: None,
            last_heard: now,
            all_acked: false,
        }
    }

    /// Sends the next lines while they (each with its `\n`) fit below the limit.
    fn send(&mut self, g: &mut Grbl) -> Result<(), GrblError> {
        while self.next < self.texts.len() && self.in_flight_bytes + self.texts[self.next].len() < self.limit {
            let mut line = self.texts[self.next].clone().into_bytes();
            line.push(b'\n');
            if let Err(e) = g.lines.write(&line) {
                return Err(self.link_lost(&e));
            }
            self.in_flight_bytes += line.len();
            self.bytes += line.len();
            self.max_in_flight = self.max_in_flight.max(self.in_flight_bytes);
            self.in_flight.push_back(InFlight { index: self.next, bytes: line.len() });
            self.next += 1;
        }
        Ok(())
    }

    /// Asks for a status report when the last ask is [`POLL`] old (or none is out).
    fn poll(&mut self, g: &mut Grbl, now: Instant) -> Result<(), GrblError> {
        if self.last_poll.is_none_or(|t| now - t >= POLL) {
            if let Err(e) = g.lines.write(b"?") {
                return Err(self.link_lost(&e));
            }
            self.last_poll = Some(now);
        }
        Ok(())
    }

    /// The fault when the machine has been quiet over `timeout` or the run is `overdue`.
    fn late(&self, now: Instant, timeout: Duration, overdue: Duration) -> Option<Fault> {
        if now - self.last_heard > timeout {
            return Some(Fault::Quiet(timeout.as_secs_f64()));
        }
        if now - self.start > overdue {
            return Some(Fault::Overdue { elapsed_s: (now - self.start).as_secs_f64(), planned_s: self.planned_total });
        }
        None
    }

    /// Takes one answer of the machine's: acknowledgements move the run on, refusals, alarms
    /// and resets stop it, status reports end it once every line is acknowledged and the
    /// machine is `Idle`.
    fn answer(&mut self, response: Response, progress: &mut dyn FnMut(&StreamProgress)) -> Answer {
        // What GRBL says in answer (acknowledgements, refusals, status reports); noise,
        // settings and messages, however many, are not an answer.
        if !matches!(response, Response::Bracket(_) | Response::Setting(..) | Response::Other(_)) {
            self.last_heard = Instant::now();
        }
        match response {
            Response::Ok => {
                let Some(f) = self.in_flight.pop_front() else {
                    return Answer::Stop(Fault::Protocol("an `ok` with no line waiting for it".into()));
                };
                self.in_flight_bytes -= f.bytes;
                self.acked = f.index + 1;
                if self.acked == self.texts.len() {
                    self.all_acked = true;
                    // The next status report decides: Idle ends the run.
                    self.last_poll = None;
                }
                self.report(progress);
            }
            Response::Error(code) => {
                let index = self.in_flight.front().map_or(self.acked, |f| f.index);
                return Answer::Stop(Fault::Firmware {
                    what: describe("error", code),
                    line: self.program.lines[index].source_line,
                    text: self.texts[index].clone(),
                });
            }
            Response::Alarm(code) => return Answer::Stop(Fault::Alarm(code)),
            Response::Banner(v) => return Answer::Stop(Fault::Reset(v)),
            Response::Status(s) => {
                let state = s.state;
                self.last = Some(s);
                if state == State::Alarm {
                    return Answer::Stop(Fault::AlarmState);
                }
                if self.all_acked && state == State::Idle && self.in_flight.is_empty() {
                    return Answer::Done(self.finish());
                }
                self.report(progress);
            }
            Response::Bracket(b) => keep(&mut self.messages, b),
            Response::Setting(..) | Response::Other(_) => {}
        }
        Answer::Go
    }

    /// Tells `progress` how far the run has got.
    fn report(&self, progress: &mut dyn FnMut(&StreamProgress)) {
        progress(&StreamProgress {
            lines_acked: self.acked,
            lines_total: self.texts.len(),
            strokes_done: strokes_done(self.program, self.acked),
            strokes_total: self.program.strokes,
            elapsed_s: self.start.elapsed().as_secs_f64(),
            remaining_s: self.planned[self.acked..].iter().sum(),
            work_mm: self.work_mm(),
            state: self.last.as_ref().map(|s| s.state),
        });
    }

    fn work_mm(&self) -> Option<[f64; 3]> {
        self.last.as_ref().and_then(|s| work(s, self.info.wco))
    }

    fn finish(&mut self) -> StreamReport {
        StreamReport {
            lines: self.texts.len(),
            bytes: self.bytes,
            max_in_flight: self.max_in_flight,
            elapsed_s: self.start.elapsed().as_secs_f64(),
            planned_s: self.planned_total,
            work_mm: self.work_mm(),
            messages: std::mem::take(&mut self.messages),
        }
    }

    /// Stops on `cause`, making the brush safe where the machine still answers.
    fn fault(&self, g: &mut Grbl, cause: Fault) -> GrblError {
        let safe = g.safe_stop(self.info, self.program, &cause, self.last.as_ref());
        stopped(self.program, cause, self.acked, safe)
    }

    /// Stops on a lost link: nothing more can be sent, the brush cannot be made safe.
    fn link_lost(&self, e: &dyn std::fmt::Display) -> GrblError {
        stopped(self.program, Fault::Link(e.to_string()), self.acked, lost())
    }
}

/// The work position of a status report.
fn work(s: &Status, wco: [f64; 3]) -> Option<[f64; 3]> {
    s.wpos.or_else(|| s.mpos.map(|m| [m[0] - wco[0], m[1] - wco[1], m[2] - wco[2]]))
}

fn lost() -> SafeStop {
    SafeStop {
        lifted: false,
        how: "the link is lost: the machine runs what it had queued (up to its planner's moves and its receive buffer) and the brush may be left pressed into the paper: lift it by hand".into(),
        work_mm: None,
    }
}

/// Strokes whose lift (the `G0 Z` that ends them) is among the first `acked` lines.
fn strokes_done(program: &GcodeProgram, acked: usize) -> usize {
    program.lines[..acked]
        .iter()
        .enumerate()
        .filter(|(i, l)| {
            l.kind == LineKind::Travel
                && l.stroke.is_some()
                && program.lines.get(i + 1).is_none_or(|n| n.stroke != l.stroke || n.kind == LineKind::End)
        })
        .count()
}

fn stopped(program: &GcodeProgram, cause: Fault, acked: usize, safe: SafeStop) -> GrblError {
    let last = acked.checked_sub(1).map(|i| (program.lines[i].source_line, program.lines[i].text.clone()));
    GrblError::Stopped(Box::new(Stopped {
        cause,
        lines_acked: acked,
        lines_total: program.lines.len(),
        strokes_done: strokes_done(program, acked),
        strokes_total: program.strokes,
        last_acked: last,
        safe,
    }))
}

#[cfg(test)]
mod tests {
    use std::io;
    use std::sync::mpsc;

    use super::*;
    use crate::Port;
    use crate::link::Lines;
    use crate::machine::LinkOptions;

    /// A hostile controller: every read gives `line` again (never an `ok`), writes are taken.
    struct Flood(&'static [u8]);

    impl Port for Flood {
        fn read_some(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
            let n = self.0.len().min(buf.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            std::thread::sleep(Duration::from_millis(1));
            Ok(n)
        }
        fn write_all_bytes(&mut self, _: &[u8]) -> io::Result<()> {
            Ok(())
        }
    }

    const TEXT: &str = "; maobi writing program: 一\nG21 ; millimetres\nG90 ; absolute\nG0 Z5.000000\n; stroke 1\n\
                        G0 X10.000000 Y-20.000000 F3000.000000\nG1 X10.000000 Y-20.000000 Z-2.000000 F600.000000\n\
                        G1 X30.000000 Y-20.000000 Z-2.000000 F1200.000000\nG0 Z5.000000\nM2\n";

    fn info() -> MachineInfo {
        let Response::Status(status) = Response::parse("<Idle|MPos:0.000,0.000,0.000|FS:0,0>") else { panic!() };
        MachineInfo {
            version: "1.1h".into(),
            build: String::new(),
            planner_blocks: Some(15),
            rx_buffer: 128,
            settings: Default::default(),
            offsets: Default::default(),
            parser_state: String::new(),
            wcs: "G54".into(),
            wco: [0.0; 3],
            status,
            messages: Vec::new(),
        }
    }

    /// Streams the program against `port`'s answers on another thread: the fault, and how long
    /// the stream and its safe stop took (`None` past 60 s).
    fn stream_against(line: &'static [u8]) -> Option<(Fault, Duration)> {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let opts = LinkOptions { banner_wait: Duration::from_millis(100), timeout: Duration::from_millis(100) };
            let mut g = Grbl { lines: Lines::new(Box::new(Flood(line))), opts };
            let program = GcodeProgram::from_export(TEXT, 3000.0).unwrap();
            let t0 = Instant::now();
            let r = g.stream(&info(), &program, 1.0, &AtomicBool::new(false), &mut |_| {});
            let cause = match r {
                Err(GrblError::Stopped(s)) => s.cause,
                r => panic!("not stopped: {r:?}"),
            };
            let _ = tx.send((cause, t0.elapsed()));
        });
        rx.recv_timeout(Duration::from_secs(60)).ok()
    }

    #[test]
    fn a_controller_that_reports_or_chatters_but_never_acknowledges_is_stopped_in_bounded_time() {
        let program = GcodeProgram::from_export(TEXT, 3000.0).unwrap();
        let planned: f64 = program.lines.iter().map(|l| l.planned_s).sum();
        // Before: each status report (or any line) counted as hearing from the machine, so a
        // stream of `<Run|…>` or `[MSG:…]` without an `ok` never ended.
        let (cause, took) = stream_against(b"<Run|MPos:0.000,0.000,0.000|FS:600,0>\r\n").expect("status flood: no end");
        assert!(matches!(cause, Fault::Overdue { .. }), "{cause}");
        assert!(took.as_secs_f64() < 2.0 * planned + 5.0, "{took:?} for a plan of {planned} s");
        let (cause, took) = stream_against(b"[MSG:Caution: Unlocked]\r\n").expect("message flood: no end");
        assert_eq!(cause, Fault::Quiet(0.1));
        assert!(took < Duration::from_secs(5), "{took:?}");
        let (cause, _) = stream_against(b"$110=1\r\n").expect("settings flood: no end");
        assert_eq!(cause, Fault::Quiet(0.1));
        // A bracketed message longer than a line: refused at the line bound, at once.
        let huge: &'static [u8] = Box::leak(format!("[MSG:{}]\r\n", "x".repeat(300)).into_bytes().into_boxed_slice());
        let (cause, took) = stream_against(huge).expect("huge message: no end");
        assert!(matches!(&cause, Fault::Link(e) if e.contains("longer than 256 bytes")), "{cause}");
        assert!(took < Duration::from_secs(5), "{took:?}");
        // `error:` and `ALARM:` floods: the first one stops the run.
        let (cause, _) = stream_against(b"error:9\r\n").expect("error flood: no end");
        assert!(matches!(cause, Fault::Firmware { .. }), "{cause}");
        let (cause, _) = stream_against(b"ALARM:1\r\n").expect("alarm flood: no end");
        assert_eq!(cause, Fault::Alarm(1));
    }
}
