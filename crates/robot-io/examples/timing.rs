//! Prints the timing of each stroke of a track with the default `robot.json` and the nominal
//! AUBO-i5: `cargo run -p robot-io --example timing -- TRACK.json PAPER.json`.
use robot_io::{DhParams, RobotConfig, build_program, pressed_path, time_stroke};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: timing TRACK.json PAPER.json");
        std::process::exit(2);
    }
    let tf = robot_io::TrackFile::load(std::path::Path::new(&args[1])).unwrap();
    let frame = robot_io::PaperFrame::load(std::path::Path::new(&args[2])).unwrap();
    let cfg = RobotConfig::default();
    let (program, _) = build_program(&tf.track(), &tf.brush, &frame, &cfg).unwrap();
    let mut seed = None;
    for st in &program.strokes {
        let path = pressed_path(st);
        let d: Vec<f64> = path.iter().map(|p| program.depth_mm(p.position())).collect();
        let t =
            time_stroke(st.index, &path, &d, &DhParams::AUBO_I5, &program.tcp(), seed.as_ref(), &cfg).unwrap().unwrap();
        seed = t.joints.last().copied();
        if std::env::var("TIMING_JUMPS").is_ok() {
            for (k, w) in t.poses.windows(2).enumerate() {
                let (a, b) = (w[0].position(), w[1].position());
                let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                if d > 2e-4 {
                    println!("jump {k}: {d} {a:?} {b:?}");
                }
            }
            let pa: Vec<[f64; 3]> = path.iter().map(|p| p.position()).collect();
            for (k, w) in pa.windows(2).enumerate() {
                let d =
                    ((w[0][0] - w[1][0]).powi(2) + (w[0][1] - w[1][1]).powi(2) + (w[0][2] - w[1][2]).powi(2)).sqrt();
                if d > 5e-4 {
                    println!("path step {k}: {d} {:?} {:?}", w[0], w[1]);
                }
            }
        }
        println!(
            "stroke {} pts {} wp {} dur {:.3} ref {:.3} v {:.4} a {:.3} h {:.2} qd {:?} qdd {:.3} qddd {:.1} sv {:.3} err {:.2e} {:.2e}",
            st.index,
            path.len(),
            t.joints.len(),
            t.duration_s,
            t.reference_s,
            t.peak_speed_m_s,
            t.peak_acc_m_s2,
            t.peak_depth_rate_mm_s,
            t.peak_joint_speed_rad_s.map(|v| (v * 1000.0).round() / 1000.0),
            t.peak_joint_acc_rad_s2,
            t.peak_joint_jerk_rad_s3,
            t.min_singular_value,
            t.path_error_m,
            t.path_error_rad
        );
    }
}
