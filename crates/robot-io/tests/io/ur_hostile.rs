//! A hostile UR controller mid-program (the controller half of the sweep in docs/testing.md,
//! "Sweep of the Python API and the controller paths"): the UR stand-in on loopback reports a
//! NaN pose, sends RTDE data packages that do not fit the recipe, falls silent or closes RTDE
//! while the program plays. Each run ends in bounded time with the cause named, and no motion
//! is sent after it unless a pose was reported after the stop (a lift planned from a stale pose
//! could drag the brush across the paper).

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::PaperFrame;
use robot_io::sim::{UrFaults, UrListen, UrSimOptions, UrSimulator};
use robot_io::ur::{UrArm, UrPorts};
use robot_io::{Controller, Plan, Progress, RobotError, Watch};
use robot_io::{RobotConfig, build_program};

/// Runs a two-stroke program on the stand-in (its clock 10 × the wall clock) with `faults`:
/// the result, the programs the stand-in was sent (the program, then any lift) and the time.
fn run(faults: UrFaults) -> (Result<robot_io::RunSummary, RobotError>, usize, Duration) {
    let any = || "127.0.0.1:0".to_string();
    let sim = UrSimulator::start(
        &UrListen { script: any(), rtde: any(), dashboard: any() },
        UrSimOptions { tcp_offset: [0.0, 0.0, 0.048, 0.0, 0.0, 0.0], time_scale: 10.0, faults, ..Default::default() },
    )
    .unwrap();
    let paper = PaperFrame::level([0.35, 0.15, 0.05], [200.0, 200.0]);
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 14.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let stroke = |y: f64| Stroke { points: (0..21).map(|i| pt(30.0 + 2.0 * f64::from(i), y)).collect() };
    let track = Track { strokes: vec![stroke(45.0), stroke(75.0)] };
    let cfg = RobotConfig::default();
    let (program, _) = build_program(&track, &BrushProfile::builtin("pen1").unwrap(), &paper, &cfg).unwrap();
    let ports = UrPorts {
        script: sim.script_addr().port(),
        rtde: sim.rtde_addr().port(),
        dashboard: sim.dashboard_addr().port(),
    };
    let mut arm = UrArm::new("127.0.0.1", ports, Duration::from_secs(1));
    let plan = Plan { program: &program, config: &cfg, track: &track, stroke_chars: None, title: "二" };
    arm.prepare(&plan).unwrap();
    arm.connect().unwrap();
    let stop = AtomicBool::new(false);
    let mut progress = |_: &Progress| {};
    let t0 = Instant::now();
    let r = arm.run(&mut Watch { stop: &stop, progress: &mut progress });
    let took = t0.elapsed();
    // What the stand-in was sent, once everything has had time to arrive.
    std::thread::sleep(Duration::from_millis(300));
    (r, sim.programs(), took)
}

fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cur = c.source();
    }
    s
}

#[test]
fn a_hostile_ur_controller_mid_program_stops_the_run_in_bounded_time_and_gets_no_motion_from_a_stale_pose() {
    // The baseline: the same program runs to its end, one program sent.
    let (r, programs, _) = run(UrFaults::default());
    assert!(r.is_ok(), "{}", chain(&r.unwrap_err()));
    assert_eq!(programs, 1);
    // 12 s on the stand-in's clock: in the first stroke, the brush pressed 14 mm.
    let at = Some(12.0);
    let cases: [(&str, UrFaults, &str); 4] = [
        ("a NaN pose", UrFaults { nan_pose_at_s: at, ..Default::default() }, "which is not a finite pose"),
        (
            "data packages a byte short",
            UrFaults { rtde_garbage_at_s: at, ..Default::default() },
            "where the recipe needs",
        ),
        ("RTDE silent", UrFaults { rtde_silent_at_s: at, ..Default::default() }, "timeout waiting for RTDE"),
        ("RTDE closed", UrFaults { rtde_close_at_s: at, ..Default::default() }, "closed by the controller"),
    ];
    for (what, faults, cause) in cases {
        let (r, programs, took) = run(faults);
        let e = chain(&r.expect_err(what));
        assert!(e.contains(cause), "{what}: {e}");
        assert!(e.contains("nothing sent") || e.contains("nothing more sent"), "{what}: {e}");
        // Before the fix, malformed, silent or closed RTDE had the runner send a lift planned
        // from the pose seen before the fault (2 programs; "could not lift the brush").
        assert_eq!(programs, 1, "{what}: a motion program was sent after the fault: {e}");
        assert!(took < Duration::from_secs(20), "{what}: took {took:?}");
    }
}
