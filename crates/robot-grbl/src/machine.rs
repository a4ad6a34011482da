//! Connecting to GRBL and what it says of itself: the banner, `$I`, `$$`, `$#`, `$G` and a
//! status report; and the checks of a program against them, before anything moves.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::GrblError;
use crate::link::{Lines, Port};
use crate::program::{GRBL_MAX_LINE, GcodeProgram, LineKind};
use crate::response::{Response, State, Status, offset};

/// GRBL's receive buffer when `$I` does not say (GRBL 1.1's `RX_BUFFER_SIZE`), bytes.
pub const DEFAULT_RX_BUFFER: usize = 128;

/// Most lines one query (`$$`, `$#`) may answer before its `ok`: GRBL 1.1 prints 34 settings;
/// a link that goes on is not GRBL.
const MAX_QUERY_LINES: usize = 200;

/// How maobi talks to the machine.
#[derive(Clone, Debug)]
pub struct LinkOptions {
    /// How long to wait for the banner after opening, before a soft reset (an Arduino takes
    /// about 2 s to boot after the port opens), and again after it.
    pub banner_wait: Duration,
    /// How long any answer may take (a query's `ok`, a status report); a link silent for longer
    /// is lost.
    pub timeout: Duration,
}

impl Default for LinkOptions {
    fn default() -> Self {
        LinkOptions { banner_wait: Duration::from_millis(2500), timeout: Duration::from_secs(3) }
    }
}

/// What the machine said of itself at connect.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MachineInfo {
    /// The version in its banner (`1.1h`).
    pub version: String,
    /// `$I`'s `[VER:…]` (`1.1h.20190830:`).
    pub build: String,
    /// Planner blocks, from `$I`'s `[OPT:…,15,128]`, when reported.
    pub planner_blocks: Option<usize>,
    /// The receive buffer, bytes (`[OPT:…]`, else 128).
    pub rx_buffer: usize,
    /// The settings, `$N` → value.
    pub settings: BTreeMap<u16, f64>,
    /// The offsets of `$#`: `G54`…`G59`, `G28`, `G30`, `G92` (mm) and `TLO`.
    pub offsets: BTreeMap<String, Vec<f64>>,
    /// `$G`: the parser state (`G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0`).
    pub parser_state: String,
    /// The active work coordinate system (`G54`…`G59`).
    pub wcs: String,
    /// The work coordinate offset in force, mm: the active system's plus `G92`'s (and the
    /// tool length offset on Z).
    pub wco: [f64; 3],
    /// The status at connect.
    pub status: Status,
    /// Messages it pushed while connecting (`[MSG:'$H'|'$X' to unlock]`).
    pub messages: Vec<String>,
}

impl MachineInfo {
    /// A setting's value, or `None` when `$$` did not list it.
    pub fn setting(&self, n: u16) -> Option<f64> {
        self.settings.get(&n).copied()
    }
}

/// A connection to GRBL.
pub struct Grbl {
    pub(crate) lines: Lines,
    pub(crate) opts: LinkOptions,
}

/// Where the machine stopped, and how: what the safe stop did.
impl Grbl {
    /// Opens the GRBL protocol on `port`: waits for the `Grbl 1.1…` banner (sending a soft
    /// reset, Ctrl-X, if none comes in `banner_wait`), then reads `$I`, `$$`, `$#`, `$G` and a
    /// status report. Nothing moves.
    ///
    /// # Errors
    /// [`GrblError::Timeout`] when no banner or answer comes; [`GrblError::Refused`] for a
    /// firmware that is not GRBL 1.1; [`GrblError::Io`] when the link fails;
    /// [`GrblError::Protocol`] for answers out of the protocol.
    pub fn connect(port: Box<dyn Port>, opts: LinkOptions) -> Result<(Grbl, MachineInfo), GrblError> {
        let mut g = Grbl { lines: Lines::new(port), opts };
        let mut messages = Vec::new();
        let version = match g.wait_banner(&mut messages)? {
            Some(v) => v,
            None => {
                g.lines.write(&[0x18])?;
                g.wait_banner(&mut messages)?.ok_or_else(|| {
                    GrblError::Timeout(format!(
                        "the `Grbl 1.1…` banner ({:.1} s after opening, and again after a soft reset): is it GRBL, at this baud rate?",
                        g.opts.banner_wait.as_secs_f64()
                    ))
                })?
            }
        };
        if !version.starts_with("1.1") {
            return Err(GrblError::Refused(format!(
                "the controller is Grbl {version}; maobi speaks GRBL 1.1's protocol (status reports, `$I`, realtime commands)"
            )));
        }
        let mut build = String::new();
        let (mut planner_blocks, mut rx_buffer) = (None, DEFAULT_RX_BUFFER);
        for r in g.query("$I", &mut messages)? {
            if let Response::Bracket(b) = r {
                if let Some(v) = b.strip_prefix("VER:") {
                    build = v.to_string();
                } else if let Some(o) = b.strip_prefix("OPT:") {
                    let f: Vec<&str> = o.split(',').collect();
                    planner_blocks = f.get(1).and_then(|v| v.parse().ok());
                    if let Some(rx) = f.get(2).and_then(|v| v.parse::<usize>().ok()) {
                        // A buffer reported beyond what GRBL 1.1 has is not trusted.
                        rx_buffer = rx.clamp(GRBL_MAX_LINE + 2, DEFAULT_RX_BUFFER);
                    }
                }
            }
        }
        let mut settings = BTreeMap::new();
        for r in g.query("$$", &mut messages)? {
            if let Response::Setting(n, v) = r {
                settings.insert(n, v);
            }
        }
        let mut offsets = BTreeMap::new();
        for r in g.query("$#", &mut messages)? {
            if let Response::Bracket(b) = r
                && let Some((name, v)) = offset(&b)
            {
                offsets.insert(name.to_string(), v);
            }
        }
        let mut parser_state = String::new();
        for r in g.query("$G", &mut messages)? {
            if let Response::Bracket(b) = r
                && let Some(s) = b.strip_prefix("GC:")
            {
                parser_state = s.to_string();
            }
        }
        let wcs = parser_state.split(' ').find(|w| w.starts_with("G5") && w.len() == 3).unwrap_or("G54").to_string();
        let pick = |name: &str| offsets.get(name).filter(|v| v.len() >= 3).map(|v| [v[0], v[1], v[2]]);
        let (base, g92) = (pick(&wcs).unwrap_or_default(), pick("G92").unwrap_or_default());
        let tlo = offsets.get("TLO").and_then(|v| v.first().copied()).unwrap_or(0.0);
        let wco = [base[0] + g92[0], base[1] + g92[1], base[2] + g92[2] + tlo];
        let status = g.status(&mut messages)?;
        let info = MachineInfo {
            version,
            build,
            planner_blocks,
            rx_buffer,
            settings,
            offsets,
            parser_state,
            wcs,
            wco,
            status,
            messages,
        };
        Ok((g, info))
    }

    /// Waits `banner_wait` for the banner; its version, or `None`.
    fn wait_banner(&mut self, messages: &mut Vec<String>) -> Result<Option<String>, GrblError> {
        let deadline = Instant::now() + self.opts.banner_wait;
        while let Some(line) = self.lines.next_line(deadline)? {
            match Response::parse(&line) {
                Response::Banner(v) => {
                    // What follows the banner at once (the alarm lock message) is read later.
                    return Ok(Some(v));
                }
                Response::Bracket(b) => keep(messages, b),
                _ => {}
            }
        }
        Ok(None)
    }

    /// Sends `cmd` and returns the lines before its `ok`.
    pub(crate) fn query(&mut self, cmd: &str, messages: &mut Vec<String>) -> Result<Vec<Response>, GrblError> {
        self.lines.write(format!("{cmd}\n").as_bytes())?;
        let deadline = Instant::now() + self.opts.timeout;
        let mut out = Vec::new();
        loop {
            let Some(line) = self.lines.next_line(deadline)? else {
                return Err(GrblError::Timeout(format!("the answer to `{cmd}`")));
            };
            match Response::parse(&line) {
                Response::Ok => return Ok(out),
                Response::Error(e) => {
                    return Err(GrblError::Protocol(format!(
                        "`{cmd}` answered {}",
                        crate::codes::describe("error", e)
                    )));
                }
                Response::Alarm(a) => {
                    return Err(GrblError::Refused(format!(
                        "the machine raised {} while maobi was connecting",
                        crate::codes::describe("ALARM", a)
                    )));
                }
                Response::Bracket(b) if b.starts_with("MSG:") => keep(messages, b),
                r => {
                    if out.len() == MAX_QUERY_LINES {
                        return Err(GrblError::Protocol(format!(
                            "`{cmd}` answered more than {MAX_QUERY_LINES} lines without `ok`"
                        )));
                    }
                    out.push(r);
                }
            }
        }
    }

    /// Asks for a status report (`?`) and waits for it.
    pub(crate) fn status(&mut self, messages: &mut Vec<String>) -> Result<Status, GrblError> {
        self.lines.write(b"?")?;
        let deadline = Instant::now() + self.opts.timeout;
        loop {
            let Some(line) = self.lines.next_line(deadline)? else {
                return Err(GrblError::Timeout("a status report (`?`)".into()));
            };
            match Response::parse(&line) {
                Response::Status(s) => return Ok(s),
                Response::Bracket(b) => keep(messages, b),
                _ => {}
            }
        }
    }
}

/// Keeps a pushed message, at most 16 of them.
pub(crate) fn keep(messages: &mut Vec<String>, m: String) {
    if messages.len() < 16 {
        messages.push(m);
    }
}

/// How to meet a machine slower than the program.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RateFit {
    /// Refuse a program whose feeds exceed a maximum rate (`$110`–`$112`), naming it.
    #[default]
    Refuse,
    /// Slow every feed of the program by one factor, so that every axis stays within its
    /// maximum rate (the strokes keep their shape and relative speeds; the writing takes longer
    /// and the brush lingers, so the ink spreads more).
    Slow,
}

/// The most [`RateFit::Slow`] slows a program (1/100): a machine slower than that has a bogus
/// maximum rate, or is not a plotter for this program.
pub(crate) const MIN_FEED_SCALE: f64 = 0.01;

/// What the checks found: each passed check in words, and the factor the feeds are scaled by
/// (1 unless [`RateFit::Slow`] slowed them).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Checked {
    /// The checks passed, in words.
    pub checks: Vec<String>,
    /// Every `G1` feed is multiplied by this (at most 1).
    pub feed_scale: f64,
}

const AXES: [&str; 3] = ["X", "Y", "Z"];

/// Checks `program` against the machine before anything moves: the state (idle, no alarm),
/// reports in millimetres (`$13=0`), no `G92` or tool length offset (a reset clears them),
/// every line within GRBL's line and receive buffers, every feed within the maximum rates
/// (`$110`–`$112`, per axis), and with soft limits on (`$20=1`) every target within the travel
/// (`$130`–`$132`: machine coordinates from −travel to 0, as GRBL 1.1 checks them).
///
/// # Errors
/// [`GrblError::Refused`] naming the setting or state and what the program needs.
pub fn check_program(info: &MachineInfo, program: &GcodeProgram, fit: RateFit) -> Result<Checked, GrblError> {
    let mut checks = Vec::new();
    check_state(info, program, &mut checks)?;
    let scale = check_rates(info, program, fit, &mut checks)?;
    check_travel(info, program, &mut checks)?;
    Ok(Checked { checks, feed_scale: scale })
}

/// [`check_program`]'s machine state, units, offsets and line length.
fn check_state(info: &MachineInfo, program: &GcodeProgram, checks: &mut Vec<String>) -> Result<(), GrblError> {
    let refuse = |m: String| Err(GrblError::Refused(m));
    let st = &info.status;
    if st.state == State::Alarm {
        return refuse(format!(
            "the machine is in alarm{}: home it (`$H`) or, once you know where it is, unlock it (`$X`), then send again",
            info.messages.iter().find(|m| m.contains("unlock")).map_or(String::new(), |m| format!(" ([{m}])"))
        ));
    }
    if st.state != State::Idle {
        return refuse(format!(
            "the machine is in state {}, not Idle: let it finish or reset it first",
            st.state_text()
        ));
    }
    checks.push(format!("Grbl {} ({}), Idle", info.version, info.build));
    if info.setting(13).is_some_and(|v| v != 0.0) {
        return refuse(
            "$13=1 reports positions in inches; maobi's program and checks are in millimetres: set $13=0".into(),
        );
    }
    let g92 = info.offsets.get("G92").cloned().unwrap_or_default();
    if g92.iter().any(|v| *v != 0.0) {
        return refuse(format!(
            "a G92 offset is set ({}); GRBL clears it on a reset, so after a safe stop the work coordinates would move: touch off with `G10 L20 P1 X0 Y0 Z0` instead, and clear G92 with `G92.1`",
            join(&g92)
        ));
    }
    let tlo = info.offsets.get("TLO").and_then(|v| v.first().copied()).unwrap_or(0.0);
    if tlo != 0.0 {
        return refuse(format!(
            "a tool length offset is set (TLO {tlo:.3} mm); GRBL clears it on a reset: set Z zero with `G10 L20 P1 Z0` instead, and clear it with `G49`"
        ));
    }
    checks.push(format!("work offset {} (work zero at machine {})", info.wcs, join(&info.wco)));
    let longest = program.lines.iter().map(|l| l.text.len() + 1).max().unwrap_or(0);
    if longest > info.rx_buffer - 1 {
        return refuse(format!(
            "a line of {longest} bytes does not fit the receive buffer of {} bytes",
            info.rx_buffer
        ));
    }
    Ok(())
}

/// [`check_program`]'s maximum rates: the feed scale that fits them (1 when they all do).
fn check_rates(
    info: &MachineInfo,
    program: &GcodeProgram,
    fit: RateFit,
    checks: &mut Vec<String>,
) -> Result<f64, GrblError> {
    let refuse = |m: String| Err(GrblError::Refused(m));
    // Rates: each feed move's speed along each axis. A maximum rate that is not a positive
    // speed is no machine's (slowing to it would stream feeds of 0 or below).
    for k in 0..3u16 {
        if let Some(max) = info.setting(110 + k).filter(|&m| m <= 0.0) {
            return refuse(format!(
                "${}={max:.3}: the {} axis's maximum rate must be a positive speed (mm/min): check `$$`",
                110 + k,
                AXES[usize::from(k)]
            ));
        }
    }
    let mut scale: f64 = 1.0;
    let mut worst: Option<(usize, usize, f64, f64)> = None;
    let mut prev: [Option<f64>; 3] = [None; 3];
    for (i, l) in program.lines.iter().enumerate() {
        if l.kind == LineKind::Feed && l.length_mm > 0.0 {
            for (k, (a, b)) in prev.iter().zip(&l.to).enumerate() {
                let (Some(a), Some(b)) = (*a, *b) else { continue };
                let v = l.feed_mm_min * (b - a).abs() / l.length_mm;
                let Some(max) = info.setting(110 + k as u16) else { continue };
                if v > max * (1.0 + 1e-9) {
                    scale = scale.min(max / v);
                    if worst.is_none_or(|w| max / v < w.3 / w.2) {
                        worst = Some((i, k, v, max));
                    }
                }
            }
        }
        prev = l.to;
    }
    if let Some((i, k, v, max)) = worst {
        let l = &program.lines[i];
        let what = match l.stroke {
            Some(s) => format!(" (stroke {})", s + 1),
            None => String::new(),
        };
        let msg = format!(
            "${}={max:.3} (the {} axis's maximum rate, mm/min) is below the {v:.3} mm/min the program moves along {} at line {}{what}",
            110 + k,
            AXES[k],
            AXES[k],
            l.source_line,
        );
        match fit {
            RateFit::Refuse => {
                return refuse(format!(
                    "{msg}: raise ${} if the machine can go that fast, or slow the program (robot.json `write_speed_m_s`, or send with --slow-to-machine to scale every feed by {scale:.3})",
                    110 + k
                ));
            }
            RateFit::Slow if scale < MIN_FEED_SCALE => {
                return refuse(format!(
                    "{msg}: slowing every feed by {scale:.3e} (below {MIN_FEED_SCALE}) would make the run last {:.0}× its plan: check `$$`, or slow the program itself",
                    1.0 / scale
                ));
            }
            RateFit::Slow => checks.push(format!("{msg}: every feed slowed to {scale:.3}× the program's")),
        }
    } else {
        checks.push("every feed within the maximum rates ($110-$112)".into());
    }
    Ok(scale)
}

/// [`check_program`]'s soft-limit travel.
fn check_travel(info: &MachineInfo, program: &GcodeProgram, checks: &mut Vec<String>) -> Result<(), GrblError> {
    let refuse = |m: String| Err(GrblError::Refused(m));
    // Travel.
    let bounds = program.bounds();
    if info.setting(20).is_some_and(|v| v != 0.0) {
        for k in 0..3 {
            let (Some([lo, hi]), Some(travel)) = (bounds[k], info.setting(130 + k as u16)) else { continue };
            let (mlo, mhi) = (lo + info.wco[k], hi + info.wco[k]);
            if mlo < -travel - 1e-6 || mhi > 1e-6 {
                return refuse(format!(
                    "soft limits are on ($20=1) and the program reaches work {a} {lo:.3} to {hi:.3}, machine {a} {mlo:.3} to {mhi:.3}, outside the travel ${}={travel:.3} (machine {a} {:.3} to 0): {}",
                    130 + k,
                    -travel,
                    if hi - lo > travel {
                        format!("the program spans {:.3} mm, more than the machine's travel", hi - lo)
                    } else {
                        "move the work zero (touch off again) so that the sheet lies within the travel".into()
                    },
                    a = AXES[k],
                ));
            }
        }
        checks.push("every target within the soft limits ($20=1, $130-$132)".into());
    } else {
        checks.push("soft limits off ($20=0): the travel is not checked by the machine".into());
    }
    Ok(())
}

fn join(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::response::Response;

    const TEXT: &str = "; maobi writing program: 一\nG21 ; millimetres\nG90 ; absolute\nG0 Z5.000000\n; stroke 1\n\
                        G0 X10.000000 Y-20.000000 F3000.000000\nG1 X10.000000 Y-20.000000 Z-2.000000 F600.000000\n\
                        G1 X30.000000 Y-20.000000 Z-2.000000 F1200.000000\nG0 Z5.000000\nM2\n";

    /// GRBL 1.1h's defaults (as `$$` prints them on the firmware under test), idle at 0, the
    /// work zero at machine (-100, -5, -30).
    fn machine() -> MachineInfo {
        let dollars = "$0=10 $1=25 $2=0 $3=0 $4=0 $5=0 $6=0 $10=1 $11=0.010 $12=0.002 $13=0 $20=0 $21=0 $22=0 \
                       $23=0 $24=25.000 $25=500.000 $26=250 $27=1.000 $30=1000 $31=0 $32=0 $100=250.000 \
                       $101=250.000 $102=250.000 $110=500.000 $111=500.000 $112=500.000 $120=10.000 \
                       $121=10.000 $122=10.000 $130=200.000 $131=200.000 $132=200.000";
        let settings = dollars
            .split(' ')
            .map(|d| match Response::parse(d) {
                Response::Setting(n, v) => (n, v),
                r => panic!("{d}: {r:?}"),
            })
            .collect();
        let Response::Status(status) = Response::parse("<Idle|MPos:0.000,0.000,0.000|FS:0,0>") else { panic!() };
        let offsets = [("G54", vec![-100.0, -5.0, -30.0]), ("G92", vec![0.0; 3]), ("TLO", vec![0.0])]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        MachineInfo {
            version: "1.1h".into(),
            build: "1.1h.20190830:".into(),
            planner_blocks: Some(15),
            rx_buffer: 128,
            settings,
            offsets,
            parser_state: "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0".into(),
            wcs: "G54".into(),
            wco: [-100.0, -5.0, -30.0],
            status,
            messages: Vec::new(),
        }
    }

    fn refused(info: &MachineInfo, p: &GcodeProgram) -> String {
        match check_program(info, p, RateFit::Refuse) {
            Err(GrblError::Refused(m)) => m,
            r => panic!("not refused: {r:?}"),
        }
    }

    #[test]
    fn each_setting_the_program_cannot_run_with_is_named() {
        let p = GcodeProgram::from_export(TEXT, 3000.0).unwrap();
        // The defaults' 500 mm/min is below the 1200 mm/min along X.
        let m = refused(&machine(), &p);
        assert!(m.contains("$110=500.000") && m.contains("1200.000 mm/min") && m.contains("line 8"), "{m}");
        let mut fast = machine();
        for n in [110, 111, 112] {
            fast.settings.insert(n, 2000.0);
        }
        let ok = check_program(&fast, &p, RateFit::Refuse).unwrap();
        assert_eq!(ok.feed_scale, 1.0);
        assert!(ok.checks.iter().any(|c| c.contains("soft limits off")), "{:?}", ok.checks);
        // Slowed instead: by the worst axis's ratio.
        let slow = check_program(&machine(), &p, RateFit::Slow).unwrap();
        assert!((slow.feed_scale - 500.0 / 1200.0).abs() < 1e-12, "{}", slow.feed_scale);
        // Soft limits: work X 10..30 at machine -90..-70 fits 200 mm, not 50.
        fast.settings.insert(20, 1.0);
        assert!(check_program(&fast, &p, RateFit::Refuse).is_ok());
        fast.settings.insert(130, 50.0);
        let m = refused(&fast, &p);
        assert!(m.contains("$130=50.000") && m.contains("machine X -90.000 to -70.000"), "{m}");
        // Z above the machine's top: the travel height 5 over a work zero at -2 is +3.
        let mut high = fast.clone();
        high.settings.insert(130, 200.0);
        high.wco[2] = -2.0;
        assert!(refused(&high, &p).contains("$132"));
        // Inches, a G92 offset, an alarm, a hold.
        let mut inch = fast.clone();
        inch.settings.insert(13, 1.0);
        assert!(refused(&inch, &p).contains("$13=0"));
        let mut g92 = fast.clone();
        g92.offsets.insert("G92".into(), vec![0.0, 0.0, 1.5]);
        assert!(refused(&g92, &p).contains("G92.1"));
        let mut alarm = fast.clone();
        alarm.status.state = State::Alarm;
        assert!(refused(&alarm, &p).contains("$X"));
        let mut hold = fast;
        hold.status.state = State::Hold;
        hold.status.sub = Some(0);
        assert!(refused(&hold, &p).contains("Hold:0"));
    }

    #[test]
    fn bogus_maximum_rates_are_refused_not_slowed_to() {
        let p = GcodeProgram::from_export(TEXT, 3000.0).unwrap();
        // Before: $110=0 (or below) with RateFit::Slow gave a feed scale of 0 (or below): every
        // feed streamed as F0; $110=1e-9 a run lasting 10^12 × its plan.
        for bogus in [0.0, -5.0] {
            let mut m = machine();
            m.settings.insert(110, bogus);
            for fit in [RateFit::Refuse, RateFit::Slow] {
                let Err(GrblError::Refused(e)) = check_program(&m, &p, fit) else { panic!("{bogus} accepted") };
                assert!(e.contains("$110=") && e.contains("must be a positive speed"), "{e}");
            }
        }
        let mut m = machine();
        m.settings.insert(110, 1e-9);
        let Err(GrblError::Refused(e)) = check_program(&m, &p, RateFit::Slow) else { panic!("1e-9 accepted") };
        assert!(e.contains("below 0.01"), "{e}");
    }
}
