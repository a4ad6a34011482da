//! Writes a two-stroke cross on the loopback simulator and prints the run report.
//!
//! `cargo run -p robot-io --example simulate`

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::aubo::{RunOptions, run_program};
use robot_io::sim::{Faults, Simulator};
use robot_io::{PaperFrame, RobotConfig, build_program};

fn main() {
    let pen1 = BrushProfile::builtin("pen1").expect("built-in");
    let pt = |x: f64, y: f64, beta: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 14.0, alpha_rad: 0.0, beta_rad: beta };
    let track = Track {
        strokes: vec![
            Stroke { points: (0..=20).map(|i| pt(40.0 + 3.0 * i as f64, 80.0, std::f64::consts::PI)).collect() },
            Stroke {
                points: (0..=20).map(|i| pt(70.0, 50.0 + 3.0 * i as f64, -std::f64::consts::FRAC_PI_2)).collect(),
            },
        ],
    };
    let paper = PaperFrame::level([0.35, 0.15, 0.05], [200.0, 200.0]);
    let (program, check) = build_program(&track, &pen1, &paper, &RobotConfig::default()).expect("safe");
    println!("check: {check:?}");
    let sim = Simulator::start("127.0.0.1:0", Faults { drop_after_moves: Some(30), ..Faults::default() }).expect("sim");
    let stop = AtomicBool::new(false);
    let opts = RunOptions {
        timeout: Duration::from_millis(500),
        backoff: Duration::from_millis(20),
        ..RunOptions::new(&stop)
    };
    let report = run_program(&sim.addr.to_string(), &program, None, &opts, |r| {
        println!("  {} strokes done", r.strokes_completed.len())
    })
    .expect("runs");
    println!("run: {report:?}; {} moves executed", sim.trace().len());
}
