//! paper.json, robot.json and track.json (the input is split in three at 0xFF bytes), loaded
//! by robot-io from files as `maobi robot` does, then checked into a program: no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut parts = data.splitn(3, |&b| b == 0xFF);
    let (paper, robot, track) = (parts.next().unwrap_or(b""), parts.next().unwrap_or(b""), parts.next().unwrap_or(b""));
    let dir = std::env::temp_dir().join(format!("maobi-fuzz-robot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (pp, rp, tp) = (dir.join("paper.json"), dir.join("robot.json"), dir.join("track.json"));
    std::fs::write(&pp, paper).unwrap();
    std::fs::write(&rp, robot).unwrap();
    std::fs::write(&tp, track).unwrap();
    let frame = robot_io::PaperFrame::load(&pp);
    let cfg = robot_io::RobotConfig::load(&rp);
    let tf = robot_io::TrackFile::load(&tp);
    if let (Ok(frame), Ok(cfg), Ok(tf)) = (frame, cfg, tf) {
        let _ = robot_io::build_program(&tf.track(), &tf.brush, &frame, &cfg);
    }
});
