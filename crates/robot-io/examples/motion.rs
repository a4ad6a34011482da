//! How a track runs as `robot send` sends it to the simulator (the controller's time law), with
//! the default `robot.json` and the nominal AUBO-i5: for the plain executor (constant speed, no
//! blends), path buffers and compacted blended moves, the time to run the program, the time
//! pressed, and how far the executed pressed path leaves the commanded one (the corner
//! rounding: largest and mean distance of a pressed sample from the polyline through the
//! stroke's pressed points, and the share of samples more than 0.05 mm off).
//!
//! `cargo run -p robot-io --example motion -- TRACK.json PAPER.json`
use robot_io::sim::{SendMotion, execute_as_sent_tagged};
use robot_io::{
    DhParams, Move, Program, RobotConfig, TraceEntry, build_program_chars, compact_program, execute_program,
    pressed_path,
};

fn distance_to_polyline(p: [f64; 3], line: &[[f64; 3]]) -> f64 {
    let v = |a: [f64; 3]| nalgebra::Vector3::from(a);
    line.windows(2)
        .map(|w| {
            let (a, b, p) = (v(w[0]), v(w[1]), v(p));
            let ab = b - a;
            let f = if ab.norm_squared() > 0.0 { ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
            (a + ab * f - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Prints the run time, the pressed time and the deviation of pressed samples of `entries`
/// (tagged by stroke position; `None`: every stroke's path is searched) from the pressed paths.
fn report(name: &str, program: &Program, entries: &[(TraceEntry, Option<usize>)]) {
    // Each stroke's commanded path: its approach (down onto the first point), the pressed
    // points, the lift.
    let lines: Vec<Vec<[f64; 3]>> = program
        .strokes
        .iter()
        .map(|st| {
            let approach = st.approach.iter().filter_map(|m| match m {
                Move::Line { pose, .. } => Some(pose.position()),
                _ => None,
            });
            let lift = match st.lift {
                Move::Line { pose, .. } => Some(pose.position()),
                _ => None,
            };
            approach.chain(pressed_path(st).iter().map(|p| p.position())).chain(lift).collect()
        })
        .collect();
    let (mut worst, mut sum, mut n, mut off, mut pressed_s) = (0.0f64, 0.0, 0usize, 0usize, 0.0);
    for (k, w) in entries.windows(2).enumerate() {
        let (e, stroke) = entries[k + 1];
        // Pressed: below the paper by more than 1 µm.
        if program.depth_mm(e.pose.position()) <= 1e-3 {
            continue;
        }
        pressed_s += w[1].0.t_s - w[0].0.t_s;
        let d = match stroke {
            Some(s) => distance_to_polyline(e.pose.position(), &lines[s]),
            None => lines.iter().map(|l| distance_to_polyline(e.pose.position(), l)).fold(f64::INFINITY, f64::min),
        };
        worst = worst.max(d);
        sum += d;
        n += 1;
        off += usize::from(d > 5e-5);
    }
    println!(
        "{name}: {:.2} s in all, {pressed_s:.2} s pressed; pressed samples {n}, from the commanded path at most {:.3} mm, mean {:.4} mm, {:.2} % beyond 0.05 mm",
        entries.last().map_or(0.0, |e| e.0.t_s),
        worst * 1e3,
        sum / n.max(1) as f64 * 1e3,
        100.0 * off as f64 / n.max(1) as f64
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, track, paper] = args.as_slice() else {
        return Err("usage: motion TRACK.json PAPER.json".into());
    };
    let tf = robot_io::TrackFile::load(std::path::Path::new(track))?;
    let frame = robot_io::PaperFrame::load(std::path::Path::new(paper))?;
    let cfg = RobotConfig::default();
    let (program, _) = build_program_chars(&tf.track(), tf.stroke_chars.as_deref(), &tf.brush, &frame, &cfg)?;
    let kin = DhParams::AUBO_I5;
    let plain: Vec<_> = execute_program(&program).into_iter().map(|e| (e, None)).collect();
    report("plain executor", &program, &plain);
    let timing = robot_io::time_program(&program, &kin, &cfg)?;
    let pb = execute_as_sent_tagged(&program, &kin, SendMotion::PathBuffer(&timing))?;
    report("path buffer", &program, &pb.iter().map(|e| (e.entry, e.stroke)).collect::<Vec<_>>());
    let q = timing.peak_joint_speed_rad_s.map(|v| format!("{v:.3}")).join(", ");
    println!(
        "timing: writing {:.2} s (reference {:.2} s), {} strokes, longest {:.2} s; peak joint speeds [{q}] rad/s (limit {}), peak joint acc {:.2} rad/s², jerk {:.1} rad/s³",
        timing.writing_s,
        timing.reference_s,
        timing.strokes.len(),
        timing.strokes.iter().map(|t| t.duration_s).fold(0.0, f64::max),
        cfg.limits.max_joint_speed_rad_s,
        timing.strokes.iter().map(|t| t.peak_joint_acc_rad_s2).fold(0.0, f64::max),
        timing.strokes.iter().map(|t| t.peak_joint_jerk_rad_s3).fold(0.0, f64::max),
    );
    let compact = compact_program(&program, &cfg);
    let moves = execute_as_sent_tagged(&compact, &kin, SendMotion::Moves)?;
    println!("moves: {} of the program's {}", compact.move_count(), program.move_count());
    report("moves (compacted, blended)", &program, &moves.iter().map(|e| (e.entry, e.stroke)).collect::<Vec<_>>());
    Ok(())
}
