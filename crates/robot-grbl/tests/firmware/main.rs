//! robot-grbl against the real GRBL 1.1h firmware (grbl-sim, built from `third_party/grbl`)
//! over a pseudo-terminal. The firmware runs in about real time, so the programs are short;
//! one firmware runs at a time (each takes about half a core).

mod harness;

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use harness::{Firmware, Inject, Machine, firmware, mpos, validate};
use robot_grbl::{Endpoint, Fault, GcodeProgram, Grbl, GrblError, GrblPlotter, LinkOptions, RateFit, SerialLink};
use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::{
    Controller, DhParams, Plan, RobotConfig, Watch, build_program, level_frame_in_front, point_times, time_program,
};

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Steps per mm of GRBL's default settings ($100-$102).
const STEPS_PER_MM: f64 = 250.0;

/// Fast axes, so the firmware's real time stays short; the work zero (the paper's top-left
/// corner, the tip touching) at machine (-20, 15, -20), so the machine starts at work
/// (20, -15, 20), above the first stroke.
const SETUP: &[&str] =
    &["$110=6000", "$111=6000", "$112=3000", "$120=800", "$121=800", "$122=800", "G10L2P1X-20Y15Z-20"];
const WCO: [f64; 3] = [-20.0, 15.0, -20.0];

/// The defaults with the lowest travel height (5 mm), to keep the runs short.
fn config() -> RobotConfig {
    RobotConfig { lift_mm: 5.0, ..RobotConfig::default() }
}

/// Two short strokes (10 mm, pressing 1 to 3 mm), or `n` of them.
fn track(n: usize) -> Track {
    let pt = |x_mm: f64, y_mm: f64, h_mm: f64| TrackPoint { x_mm, y_mm, h_mm, alpha_rad: 0.0, beta_rad: 0.0 };
    let strokes = (0..n)
        .map(|k| {
            let y0 = 15.0 + 6.0 * k as f64;
            let points = (0..=20)
                .map(|i| {
                    let t = f64::from(i) / 20.0;
                    if k % 2 == 0 { pt(20.0 + 10.0 * t, y0, 1.0 + 2.0 * t) } else { pt(25.0, y0 + 10.0 * t, 2.0) }
                })
                .collect();
            Stroke { points }
        })
        .collect();
    Track { strokes }
}

/// The G-code maobi exports for `track`, and the plan's config.
fn export(track: &Track, cfg: &RobotConfig) -> String {
    let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
    let profile = BrushProfile::builtin("pen1").unwrap();
    let (program, _) = build_program(track, &profile, &frame, cfg).unwrap();
    let times = point_times(&program, &time_program(&program, &DhParams::AUBO_I5, cfg).unwrap()).unwrap();
    robot_io::gcode(track, &times, cfg, "二").unwrap().0
}

fn link(m: &Machine) -> Box<SerialLink> {
    Box::new(SerialLink::open(&m.device, 115_200).unwrap())
}

fn opts() -> LinkOptions {
    LinkOptions { banner_wait: Duration::from_millis(500), timeout: Duration::from_secs(3) }
}

fn guard() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

fn fw(test: &str) -> Option<&'static Firmware> {
    firmware(test)
}

#[test]
fn a_small_sheet_streams_end_to_end_through_the_controller_seam() {
    let Some(fw) = fw("a_small_sheet_streams_end_to_end_through_the_controller_seam") else { return };
    let _g = guard();
    let mut m = Machine::start(fw, SETUP);
    m.relay(Inject::None);
    let (t, cfg) = (track(2), config());
    let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
    let profile = BrushProfile::builtin("pen1").unwrap();
    let (program, _) = build_program(&t, &profile, &frame, &cfg).unwrap();
    let plan = Plan { program: &program, config: &cfg, track: &t, stroke_chars: None, title: "二" };
    let mut plotter = GrblPlotter::new(
        Endpoint::Serial { path: m.device.clone(), baud: 115_200 },
        Duration::from_secs(3),
        RateFit::Refuse,
    );
    let prepared = plotter.prepare(&plan).unwrap();
    assert_eq!(prepared.strokes, 2);
    let preflight = plotter.connect().unwrap();
    assert_eq!(preflight.controller, "Grbl 1.1h");
    assert!(preflight.checks.iter().any(|c| c.contains("within the maximum rates")), "{:?}", preflight.checks);
    let stop = AtomicBool::new(false);
    let mut seen = Vec::new();
    let mut show = |p: &robot_io::Progress| seen.push(*p);
    let summary = plotter.run(&mut Watch { stop: &stop, progress: &mut show }).unwrap();
    assert_eq!(summary.strokes_completed, vec![0, 1]);
    assert!(seen.iter().any(|p| p.strokes_done == 1) && seen.last().unwrap().strokes_done == 2);
    assert!(seen.windows(2).all(|w| w[1].remaining_s.unwrap() <= w[0].remaining_s.unwrap() + 1e-9));
    let gp = plotter.program().unwrap().clone();
    // Never below the deepest press the brush profile allows (no ink pot here).
    assert!(gp.min_z_mm >= -profile.ranges.h_mm.max && gp.min_z_mm <= -2.9, "{}", gp.min_z_mm);
    // Every line answered `ok` (the relay counted them; 5 queries at connect), never more than
    // 127 bytes in flight, and the buffer was used (more than one line at a time).
    assert_eq!(m.seen.oks.load(Ordering::SeqCst), gp.lines.len() + 4);
    let max = m.seen.max_in_flight.load(Ordering::SeqCst);
    assert!((80..=127).contains(&max), "at most {max} bytes in flight");
    m.stop_relay();
    let st = m.wait_idle(Duration::from_secs(30));
    assert!(st.starts_with("<Idle"), "{st}");
    let last = mpos(&st);
    assert!((last[2] - (WCO[2] + gp.lift_mm)).abs() < 1e-3, "ends at the travel height: {st}");
    // The firmware's executed blocks, in work mm, are the program's moves in order.
    let blocks: Vec<[f64; 3]> =
        m.finish().iter().map(|b| [0, 1, 2].map(|k| b[k] as f64 / STEPS_PER_MM - WCO[k])).collect();
    let mut want: Vec<[f64; 3]> = Vec::new();
    let mut pos = [0, 1, 2].map(|k| Some(-WCO[k]));
    for l in &gp.lines {
        let to = [0, 1, 2].map(|k| l.to[k].or(pos[k]).unwrap());
        if to.iter().zip(&pos).any(|(a, b)| (a - b.unwrap()).abs() > 1.0 / STEPS_PER_MM) {
            want.push(to);
        }
        pos = to.map(Some);
    }
    assert_eq!(blocks.len(), want.len(), "blocks {blocks:?}\nwant {want:?}");
    for (b, w) in blocks.iter().zip(&want) {
        assert!(b.iter().zip(w).all(|(a, b)| (a - b).abs() <= 0.5 / STEPS_PER_MM + 1e-9), "block {b:?}, program {w:?}");
    }
}

#[test]
fn machines_that_cannot_run_the_program_are_refused_before_anything_moves() {
    let Some(fw) = fw("machines_that_cannot_run_the_program_are_refused_before_anything_moves") else { return };
    let _g = guard();
    let cfg = config();
    let text = export(&track(1), &cfg);
    let program = GcodeProgram::from_export(&text, cfg.travel_speed_m_s * 60_000.0).unwrap();
    let mut m = Machine::start(fw, SETUP);
    let try_connect = |m: &mut Machine, fit: RateFit| {
        m.relay(Inject::None);
        Grbl::connect(link(m), opts())
            .and_then(|(g, info)| robot_grbl::check_program(&info, &program, fit).map(|c| (g, info, c)))
    };
    // Soft limits on, an X travel of 20 mm: the sheet's X 20..30 is at machine -130..-120.
    for s in ["$22=1", "$20=1", "$130=20"] {
        m.command(s);
    }
    let r = try_connect(&mut m, RateFit::Refuse);
    let e = r.err().expect("refused").to_string();
    assert!(e.contains("refused before any motion") && e.contains("$130=20.000") && e.contains("$20=1"), "{e}");
    m.stop_relay();
    // A Z rate below the program's descents.
    for s in ["$20=0", "$112=300"] {
        m.command(s);
    }
    let r = try_connect(&mut m, RateFit::Refuse);
    let e = r.err().expect("refused").to_string();
    assert!(e.contains("$112=300.000") && e.contains("along Z") && e.contains("--slow-to-machine"), "{e}");
    m.stop_relay();
    assert_eq!(mpos(&m.status()), [0.0; 3], "nothing moved");
    // Or slowed to it: every Z speed within 300 mm/min, said so, and the program runs.
    let r = try_connect(&mut m, RateFit::Slow);
    let (mut g, info, checked) = r.unwrap();
    assert!(checked.feed_scale < 0.3 && checked.checks.iter().any(|c| c.contains("slowed")), "{:?}", checked);
    let done = g.stream(&info, &program, checked.feed_scale, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert!(done.planned_s > program.planned_s() * 3.0);
    drop(g);
    m.stop_relay();
    // An alarm at connect: reset while moving (ALARM:3), then connect.
    m.command("$112=3000");
    let said = m.raw(b"G1X-60F300\n", Duration::from_millis(400));
    assert!(said.contains("ok"), "{said}");
    let said = m.raw(&[0x18], Duration::from_millis(1500));
    assert!(said.contains("ALARM:3"), "{said}");
    let r = try_connect(&mut m, RateFit::Refuse);
    let e = r.err().expect("refused").to_string();
    assert!(e.contains("alarm") && e.contains("$X"), "{e}");
    m.stop_relay();
}

/// Streams `track(n)` through a relay injecting `inject` (and a stop after `stop_after`);
/// returns the error and the machine.
fn faulted(
    fw: &Firmware,
    n: usize,
    inject: Inject,
    stop_pressing: bool,
) -> (Box<robot_grbl::Stopped>, Machine, GcodeProgram) {
    let cfg = config();
    let text = export(&track(n), &cfg);
    let program = GcodeProgram::from_export(&text, cfg.travel_speed_m_s * 60_000.0).unwrap();
    let mut m = Machine::start(fw, SETUP);
    m.relay(inject);
    // A quiet link is noticed after a second.
    let o = if matches!(inject, Inject::MuteAfterOks(_)) {
        LinkOptions { timeout: Duration::from_secs(1), ..opts() }
    } else {
        opts()
    };
    let (mut g, info) = Grbl::connect(link(&m), o).unwrap();
    let checked = robot_grbl::check_program(&info, &program, RateFit::Refuse).unwrap();
    let stop = AtomicBool::new(false);
    // Ctrl-C once the brush is pressing (the first report below the paper).
    let r = g.stream(&info, &program, checked.feed_scale, &stop, &mut |p| {
        if stop_pressing && p.work_mm.is_some_and(|w| w[2] < -0.5) {
            stop.store(true, Ordering::SeqCst);
        }
    });
    let Err(GrblError::Stopped(s)) = r else { panic!("not stopped: {r:?}") };
    drop(g);
    m.stop_relay();
    (s, m, program)
}

#[test]
fn faults_mid_stream_stop_with_the_last_acknowledged_line_and_a_raised_brush() {
    let Some(fw) = fw("faults_mid_stream_stop_with_the_last_acknowledged_line_and_a_raised_brush") else { return };
    let _g = guard();
    // Ctrl-C mid-stroke: hold, reset in the hold, raised in machine coordinates; the position
    // kept (the machine where it was stopped, at the travel height).
    let (s, mut m, p) = faulted(fw, 4, Inject::None, true);
    assert_eq!(s.cause, Fault::Interrupted);
    assert!(s.safe.lifted && s.safe.how.contains("G53 G0 Z"), "{}", s.safe.how);
    let st = m.wait_idle(Duration::from_secs(5));
    let at = mpos(&st);
    assert!((at[2] - (WCO[2] + p.lift_mm)).abs() < 1e-3, "{st}");
    let [x, y, _] = s.safe.work_mm.unwrap();
    assert!((at[0] - WCO[0] - x).abs() < 1e-3 && (at[1] - WCO[1] - y).abs() < 1e-3, "{st} vs {:?}", s.safe.work_mm);
    assert!(s.lines_acked > 0 && s.lines_acked < p.lines.len(), "{}", s);
    drop(m);
    // Noise on the line: GRBL answers error:N to the corrupted line; stopped, brush raised.
    let (s, mut m, p) = faulted(fw, 2, Inject::CorruptAfterOks(9), false);
    let Fault::Firmware { what, line, text } = &s.cause else { panic!("{s}") };
    assert!(what.starts_with("error:") && text.starts_with('G') && *line > 0, "{s}");
    assert_eq!(s.last_acked.as_ref().map(|l| l.0), Some(p.lines[s.lines_acked - 1].source_line));
    assert!(s.safe.lifted, "{s}");
    let st = m.wait_idle(Duration::from_secs(30));
    assert!(mpos(&st)[2] - WCO[2] >= p.lift_mm - 1e-3, "at or above the travel height: {st}");
    drop(m);
    // A reset from the far side while moving: ALARM:3 (position lost): unlocked and raised
    // relative, said so.
    let (s, mut m, p) = faulted(fw, 4, Inject::ResetBelowZ(WCO[2] - 0.5), false);
    assert_eq!(s.cause, Fault::Alarm(3), "{s}");
    assert!(s.safe.lifted && s.safe.how.contains("position may be lost") && s.safe.how.contains("G91"), "{s}");
    // Raised by the travel height plus the deepest press from where it stood (pressing).
    let st = m.wait_idle(Duration::from_secs(5));
    let up = p.lift_mm - p.min_z_mm;
    assert!(mpos(&st)[2] - WCO[2] >= up - 3.0 - 1e-3, "{st}, raised {up}");
    drop(m);
    // The cable pulled: reported lost with the last acknowledged line; the firmware runs on.
    let (s, mut m, p) = faulted(fw, 2, Inject::CloseAfterOks(8), false);
    assert!(matches!(s.cause, Fault::Link(_)), "{s}");
    assert!(!s.safe.lifted && s.safe.how.contains("lift it by hand"), "{s}");
    assert_eq!(s.lines_acked, 8 - 4, "{s}");
    assert!(s.to_string().contains(&format!("line {}", p.lines[3].source_line)), "{s}");
    let st = m.wait_idle(Duration::from_secs(30));
    assert!(st.starts_with("<Idle"), "{st}");
    drop(m);
    // The link gone quiet (GRBL's answers lost, its input still reaching it): reported lost
    // after the time-out with the last acknowledged line. The feed hold reaches the machine;
    // without an answer saying the hold is complete maobi does not reset (a reset in motion
    // loses the position) nor lift, and says so.
    let (s, mut m, p) = faulted(fw, 2, Inject::MuteAfterOks(7), false);
    assert!(matches!(s.cause, Fault::Quiet(t) if t == 1.0), "{s}");
    assert!(!s.safe.lifted && s.safe.how.contains("lift it by hand"), "{s}");
    assert_eq!(s.last_acked.as_ref().map(|l| l.0), Some(p.lines[s.lines_acked - 1].source_line), "{s}");
    let st = m.status();
    assert!(st.starts_with("<Hold:0"), "the hold reached it: {st}");
}

#[test]
fn a_board_bridged_over_tcp_writes_as_over_serial() {
    let Some(fw) = fw("a_board_bridged_over_tcp_writes_as_over_serial") else { return };
    let _g = guard();
    let mut m = Machine::start(fw, SETUP);
    m.relay(Inject::None);
    let addr = harness::tcp_bridge(&m.device);
    let (t, cfg) = (track(1), config());
    let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
    let (program, _) = build_program(&t, &BrushProfile::builtin("pen1").unwrap(), &frame, &cfg).unwrap();
    let plan = Plan { program: &program, config: &cfg, track: &t, stroke_chars: None, title: "一" };
    let mut plotter = GrblPlotter::new(Endpoint::Tcp(addr.clone()), Duration::from_secs(3), RateFit::Refuse);
    assert_eq!(plotter.describe(), format!("GRBL at {addr} (TCP)"));
    plotter.prepare(&plan).unwrap();
    plotter.connect().unwrap();
    let stop = AtomicBool::new(false);
    let summary = plotter.run(&mut Watch { stop: &stop, progress: &mut |_| {} }).unwrap();
    assert_eq!(summary.strokes_completed, vec![0]);
    let lines = plotter.program().unwrap().lines.len();
    assert_eq!(m.seen.oks.load(Ordering::SeqCst), lines + 4);
}

#[test]
fn gvalidate_accepts_the_exported_gcode_with_ink_dips() {
    let Some(fw) = fw("gvalidate_accepts_the_exported_gcode_with_ink_dips") else { return };
    let mut cfg = RobotConfig::default();
    let text = export(&track(3), &cfg);
    validate(fw, &text).unwrap();
    // The fixture's ink station (a pot at paper (330, 150), 25 mm deep, soaking 0.5 s).
    let ink = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/robot-ink.json");
    cfg = RobotConfig::load(&ink).unwrap();
    let text = export(&track(3), &cfg);
    assert!(text.contains("ink dip before stroke 1") && text.contains("Z-26.000000"), "{text}");
    validate(fw, &text).unwrap();
    // And it refuses what GRBL refuses: a G1 without a feed.
    assert!(validate(fw, "G21\nG90\nG1 X1 Y1\nM2\n").unwrap_err().contains("error:22"));
}
