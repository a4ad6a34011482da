//! Issue 18, non-motion classes: every bad input ends in a one-line error that names the flag,
//! field, file or line and what was expected (or in a correct result), never a panic, a hang or
//! a runaway allocation; stdout closing early ends quietly; outputs go through symlinks and
//! never replace special files; `dataset` streams its labels and cleans up on Ctrl-C.
//!
//! Each table row is one example from the issue (or its class), run against the real binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{fails, maobi, ok, s};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

fn fixture(rel: &str) -> String {
    fixtures().join(rel).to_str().unwrap().to_string()
}

/// Asserts that a run ended in a clear error (exit 2, one line, no panic) containing `needle`.
fn refused(args: &[&str], needle: &str) {
    let t0 = Instant::now();
    let o = maobi(args);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!e.contains("panicked"), "{args:?} panicked: {e}");
    fails(&o, needle);
    assert!(t0.elapsed() < Duration::from_secs(60), "{args:?} took {:?}", t0.elapsed());
}

/// The embedded 永 as hanzi-writer-data JSON with `edit` applied, in its own folder.
fn hanzi_dir(root: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let subset = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../trajectory/data/hanzi-subset.jsonl"));
    let subset = subset.unwrap();
    let line = subset.lines().find(|l| l.starts_with("{\"c\":\"永\"")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(line).unwrap();
    edit(&mut v);
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("永.json"), v.to_string()).unwrap();
    dir.to_str().unwrap().to_string()
}

/// pen1's nominal profile as JSON with `edit` applied.
fn profile_file(root: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let mut v: serde_json::Value =
        serde_json::from_str(&brush_model::BrushProfile::builtin("pen1").unwrap().to_json()).unwrap();
    edit(&mut v);
    let p = root.join(name);
    std::fs::write(&p, v.to_string()).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn numeric_flags_have_validated_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = s(&out);
    let photo = fixture("photos/stroke_05.png");
    let ovl = dir.path().join("ovl.png");
    let g = dir.path().join("g.safetensors");
    #[rustfmt::skip]
    let table: &[(&[&str], &str)] = &[
        // Panics before: a sheet past the PNG/raster limit, zero sizes, a zero modulus.
        (&["write", "永字八法", "--size", "4096", "--per-line", "1", "--out", o], "over the 16384 px limit"),
        (&["evaluate", "--size", "0", "--limit", "2"], "--size 0: expected 64..=4096 px"),
        (&["models", "--size", "0", "--n", "5"], "--size 0: expected 8..=4096 px"),
        (&["models", "--n", "0"], "--n 0: expected 1..=1000000"),
        (&["train", "--val-every", "0", "--steps", "2", "--arch", "tiny", "-o", s(&g)], "--val-every 0: expected 1..=10000000 steps"),
        (&["train", "--batch", "100000", "--arch", "tiny", "-o", s(&g)], "--batch 100000: expected 1..=256"),
        (&["train", "--lr", "NaN", "--arch", "tiny", "-o", s(&g)], "--lr NaN"),
        // Metrics of nothing before.
        (&["train", "--eval-n", "0", "--steps", "2", "--arch", "tiny", "-o", s(&g)], "--eval-n 0: expected 1..=100000"),
        (&["eval-generator", "--n", "0"], "--n 0: expected 1..=100000"),
        // Memory before: 8 GB for the track, 17.8 GB for the overlay.
        (&["write", "永", "--char-mm", "1e9", "--out", o], "--char-mm 1000000000: expected 1..=1000 mm"),
        (&["write", "永", "--char-mm", "NaN", "--out", o], "--char-mm NaN"),
        (&["evaluate", "--char-mm", "1e9", "--limit", "1"], "--char-mm 1000000000"),
        (&["fit-stroke", &photo, "--px-per-mm", "1e-30", "--overlay", s(&ovl)], "--px-per-mm 1e-30: expected 0.1..=10000 px/mm"),
        (&["stroke", "--h", "15", "--alpha", "5", "--px-per-mm", "1e300", "-o", s(&ovl)], "--px-per-mm 1e300"),
        (&["footprint", "--h", "1e300", "--alpha", "0", "--extrapolate"], "--h 1e300: expected 0..=48"),
        (&["footprint", "--h", "15", "--alpha", "NaN", "--extrapolate"], "--alpha NaN"),
        (&["footprint", "--h", "15", "--alpha", "0", "--beta", "1e9", "--extrapolate"], "--beta 1000000000"),
        (&["dataset", "--n", "0", "-o", o], "--n 0"),
        (&["dataset", "--n", "1", "--size", "100000", "-o", o], "--size 100000: expected 8..=4096"),
        (&["calibrate", "--images", o, "--min-iou", "2", "-o", s(&g)], "--min-iou 2: expected 0..=1"),
    ];
    for (args, needle) in table {
        refused(args, needle);
    }
    assert!(!ovl.exists(), "no overlay is written for a refused scale");
}

#[test]
fn inputs_have_bounds_named_by_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let out = root.join("o");
    let o = s(&out);
    // hanzi-writer-data: a median coordinate of 1e300 (memory before) or 1e7 (hang before),
    // 10⁵ points, and an outline coordinate out of range.
    let h300 = hanzi_dir(root, "h300", |v| v["medians"][0][0] = serde_json::json!([1e300, 100]));
    let h1e7 = hanzi_dir(root, "h1e7", |v| v["medians"][0][0] = serde_json::json!([1e7, 100]));
    let many = hanzi_dir(root, "many", |v| {
        v["medians"][0] = (0..2000).map(|i| serde_json::json!([100.0 + 0.1 * i as f64, 300])).collect()
    });
    let huge = hanzi_dir(root, "huge", |v| {
        v["medians"][0] = (0..100_000).map(|i| serde_json::json!([100.0 + 0.001 * i as f64, 300])).collect()
    });
    let svg = hanzi_dir(root, "svg", |v| v["strokes"][0] = serde_json::json!("M 1e300 0 L 10 10 Z"));
    // Profiles: h range to 1e300 (hang before), a coefficient of 1e300 (CSIM 0 and a
    // 300-digit length before), a NaN range end (JSON cannot say NaN: a string is a type error).
    let hmax = profile_file(root, "hmax.json", |v| v["ranges"]["h_mm"]["max"] = serde_json::json!(1e300));
    let coef = profile_file(root, "coef.json", |v| v["model"]["lt_mm"]["h_mm"] = serde_json::json!(1e300));
    let tilt = profile_file(root, "tilt.json", |v| v["ranges"]["alpha_rad"]["max"] = serde_json::json!(3.0));
    // Measurements: a 1e308 length blamed the output path before.
    let csv = root.join("big.csv");
    let mut text = std::fs::read_to_string(fixtures().join("measurements/pen1-sample.csv")).unwrap();
    text = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i == 2 { format!("{},1e308", &l[..l.rfind(',').unwrap()]) } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&csv, text).unwrap();
    let prof_out = root.join("p.json");
    #[rustfmt::skip]
    let table: &[(&[&str], &str)] = &[
        (&["write", "永", "--hanzi-data", &h300, "--out", o], "median 1: point (1e300, 100) outside the accepted coordinates"),
        (&["write", "永", "--hanzi-data", &h1e7, "--out", o], "median 1: point (1e7, 100) outside"),
        (&["write", "永", "--hanzi-data", &many, "--out", o], "median 1: 2000 points; at most 1000"),
        (&["write", "永", "--hanzi-data", &huge, "--out", o], "a character file is at most 1048576 bytes"),
        (&["write", "永", "--hanzi-data", &svg, "--out", o], "stroke 1: SVG path number 1e300 is beyond ±100000"),
        (&["write", "永", "--brush", &hmax, "--out", o], "field `ranges.h_mm`: [11, 1e300] leaves 0 up to brush.length_mm"),
        (&["write", "永", "--brush", &coef, "--out", o], "field `model.lt_mm`: predicts 1.1000e301 mm"),
        (&["footprint", "--brush", &coef, "--h", "15", "--alpha", "5"], "at most 96.0 mm"),
        (&["footprint", "--brush", &tilt, "--h", "15", "--alpha", "5"], "field `ranges.alpha_rad`"),
        (&["calibrate", s(&csv), "-o", s(&prof_out)], "line 3, column `lr_mm`: expected a positive length of at most 2000 mm, got \"1e308\""),
    ];
    for (args, needle) in table {
        refused(args, needle);
    }
    assert!(!out.exists() && !prof_out.exists(), "nothing is written for refused inputs");
}

#[test]
fn photos_say_why_they_cannot_be_read() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.png");
    let empty = dir.path().join("empty.png");
    let text = dir.path().join("text.png");
    std::fs::write(&empty, b"").unwrap();
    std::fs::write(&text, b"hello\n").unwrap();
    // Before, all three said "no scale: pass --px-per-mm".
    refused(&["fit-stroke", s(&missing)], "missing.png: cannot read image: No such file");
    refused(&["fit-stroke", s(&empty)], "empty.png: cannot read image: the file is empty");
    refused(&["fit-stroke", s(&text)], "text.png: cannot read image: not a readable image");
    // calibrate --images lists the same reasons for the photos it leaves out.
    let photos = dir.path().join("photos");
    std::fs::create_dir(&photos).unwrap();
    let src = fixtures().join("photos");
    let labels = std::fs::read_to_string(src.join("labels.csv")).unwrap();
    for l in labels.lines().skip(1) {
        let f = l.split(',').next().unwrap();
        std::fs::copy(src.join(f), photos.join(f)).unwrap();
    }
    std::fs::copy(&empty, photos.join("empty.png")).unwrap();
    let first = labels.lines().nth(1).unwrap();
    let f0 = first.split(',').next().unwrap();
    let extra = format!("{}\n{}\n", first.replacen(f0, "empty.png", 1), first.replacen(f0, "gone.png", 1));
    std::fs::write(photos.join("labels.csv"), labels.trim_end().to_string() + "\n" + &extra).unwrap();
    let o = maobi(&["calibrate", "--images", s(&photos), "-o", s(&dir.path().join("cal/p.json"))]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("empty.png: cannot read image: the file is empty"), "{e}");
    assert!(e.contains("gone.png: cannot read image: No such file"), "{e}");
    assert!(!e.contains("no scale"), "{e}");
}

#[test]
fn constant_calibration_data_has_an_undefined_r2_and_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("c.csv");
    let mut t = String::from("h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n");
    for i in 0..12 {
        let h = 11 + i % 5;
        t.push_str(&format!("{h},{},{},{},3.3,1.7\n", (i * 3) % 10, (i * 7) % 5, 0.9 * h as f64));
    }
    std::fs::write(&csv, t).unwrap();
    let p = dir.path().join("c.json");
    let o = maobi(&["calibrate", s(&csv), "-o", s(&p)]);
    let out = ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    // Before: lh_mm R² = −626.7, lr_mm R² = −158.4, t values of 8e13.
    assert!(
        err.contains("warning: ") && err.contains("lh_mm is constant in the data (3.3000 mm): R² is undefined"),
        "{err}"
    );
    assert!(out.contains("lh_mm: R² undefined") && out.contains("lr_mm: R² undefined"), "{out}");
    assert!(!out.contains("R² = -"), "{out}");
    assert!(out.contains("lt_mm: R² = 1.00000"), "the varying output keeps its R²: {out}");
    // JSON says null, and the profile (fit included) loads back.
    let j: serde_json::Value = serde_json::from_str(&ok(&maobi(&["calibrate", s(&csv), "--json"]))).unwrap();
    assert!(j["outputs"]["lh_mm"]["r2"].is_null(), "{j}");
    assert!(j["outputs"]["lt_mm"]["r2"].as_f64().unwrap() > 0.99);
    let f = ok(&maobi(&["footprint", "--brush", s(&p), "--h", "13", "--alpha", "3", "--json"]));
    let fp: serde_json::Value = serde_json::from_str(&f).unwrap();
    assert!((fp["lh_mm"].as_f64().unwrap() - 3.3).abs() < 1e-9, "{fp}");
}

#[test]
fn nan_generator_weights_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let src = fixtures().join("../crates/neural-gen/data");
    let mut bytes = std::fs::read(src.join("pen1.safetensors")).unwrap();
    // The header says where each tensor lies; poison the first tensor's data with NaN.
    let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).unwrap();
    let (name, t) = header.as_object().unwrap().iter().find(|(k, _)| *k != "__metadata__").unwrap();
    let (a, b) = (t["data_offsets"][0].as_u64().unwrap() as usize, t["data_offsets"][1].as_u64().unwrap() as usize);
    for i in (8 + n + a..8 + n + b).step_by(4) {
        bytes[i..i + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    }
    let w = dir.path().join("nan.safetensors");
    std::fs::write(&w, bytes).unwrap();
    std::fs::copy(src.join("pen1.json"), dir.path().join("nan.json")).unwrap();
    let needle = format!("tensor `{name}` holds NaN or infinite weights");
    refused(&["eval-generator", "--generator", s(&w), "--n", "4"], &needle);
    let png = dir.path().join("nn.png");
    refused(
        &["stroke", "--h", "15", "--alpha", "5", "--renderer", "neural", "--generator", s(&w), "-o", s(&png)],
        &needle,
    );
}

#[test]
fn an_image_without_strokes_is_an_error_not_an_empty_track() {
    let dir = tempfile::tempdir().unwrap();
    // Two round blobs: no stroke has a centre line.
    let side = 256u32;
    let img = image::GrayImage::from_fn(side, side, |x, y| {
        let d = |cx: f64, cy: f64| ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
        if d(65.0, 65.0) < 35.0 || d(185.0, 185.0) < 35.0 { image::Luma([0]) } else { image::Luma([255]) }
    });
    let p = dir.path().join("blobs.png");
    img.save(&p).unwrap();
    let out = dir.path().join("o");
    refused(&["write", "永", "--image", s(&p), "--out", s(&out)], "found no strokes in --image");
    assert!(!out.join("track.json").exists());
}

/// Runs `maobi` with stdout a pipe whose reading end is closed before it writes.
fn with_closed_stdout(args: &[&str]) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn stdout_closing_early_ends_quietly() {
    let csv = fixture("measurements/pen1-sample.csv");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    // `calibrate … | true` panicked with "failed printing to stdout: Broken pipe".
    for args in [
        &["calibrate", csv.as_str()][..],
        &["models", "--n", "20", "--size", "32"][..],
        &["footprint", "--h", "15", "--alpha", "5", "--json"][..],
        // `write` still prints with println!: the panic hook ends it quietly too.
        &["write", "永", "--size", "64", "--out", s(&out)][..],
    ] {
        let o = with_closed_stdout(args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!e.contains("panicked") && !e.contains("Broken pipe"), "{args:?}: {e}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {e}");
    }
    assert!(out.join("track.json").exists(), "write finished its work before stdout mattered");
}

#[cfg(unix)]
#[test]
fn outputs_go_through_symlinks_and_never_replace_special_files() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A symlink: the target is written, the link stays a link.
    std::fs::create_dir(d.join("real")).unwrap();
    std::os::unix::fs::symlink("real/fp.png", d.join("link.png")).unwrap();
    ok(&maobi(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&d.join("link.png"))]));
    assert!(std::fs::symlink_metadata(d.join("link.png")).unwrap().file_type().is_symlink());
    let png = std::fs::read(d.join("real/fp.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    // A FIFO and a folder are refused and left as they were.
    let fifo = d.join("fifo.png");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    refused(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&fifo)], "fifo.png is a FIFO: refusing to write there");
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    let folder = d.join("p.json");
    std::fs::create_dir(&folder).unwrap();
    refused(&["calibrate", &fixture("measurements/pen1-sample.csv"), "-o", s(&folder)], "p.json is a folder");
    assert!(folder.is_dir());
    // A symlink to a FIFO names both.
    std::os::unix::fs::symlink("fifo.png", d.join("to-fifo.png")).unwrap();
    refused(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&d.join("to-fifo.png"))], "(the link's target");
    // No temporary files are left anywhere.
    for e in std::fs::read_dir(d).unwrap() {
        let n = e.unwrap().file_name();
        assert!(!n.to_string_lossy().starts_with(".tmp"), "left {n:?}");
    }
}

fn labels_rows(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path).unwrap_or_default().lines().skip(1).map(str::to_string).collect()
}

#[test]
fn dataset_streams_labels_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ds");
    ok(&maobi(&["dataset", "--n", "1500", "--size", "16", "-o", s(&out)]));
    let rows = labels_rows(&out.join("labels.csv"));
    assert_eq!(rows.len(), 1500);
    for (i, r) in rows.iter().enumerate() {
        assert!(r.starts_with(&format!("fp_{i:06}.png,")), "row {i}: {r}");
    }
    // The images, labels.csv and the list of what maobi wrote (.maobi-written).
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1502);
    assert_eq!(std::fs::read_to_string(out.join(".maobi-written")).unwrap().lines().count(), 1501);
}

#[cfg(unix)]
fn interrupt(child: &std::process::Child) {
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
}

#[cfg(unix)]
#[test]
fn an_interrupted_dataset_leaves_a_consistent_prefix_and_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ds");
    let child = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(["dataset", "--n", "100000000", "--size", "64", "-o", s(&out)])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first chunk's rows (in the staging folder beside the output), then press
    // Ctrl-C.
    let stage = dir.path().join(format!(".ds.maobi-partial-{}", child.id()));
    let t0 = Instant::now();
    while labels_rows(&stage.join("labels.csv")).is_empty() {
        assert!(t0.elapsed() < Duration::from_secs(120), "no labels after two minutes");
        std::thread::sleep(Duration::from_millis(20));
    }
    interrupt(&child);
    let t1 = Instant::now();
    let o = child.wait_with_output().unwrap();
    assert!(t1.elapsed() < Duration::from_secs(30), "stopping took {:?}", t1.elapsed());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("interrupted") && e.contains("labels.csv lists exactly those"), "{e}");
    let rows = labels_rows(&out.join("labels.csv"));
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "labels.csv" && n != ".maobi-written")
        .collect();
    files.sort();
    assert!(files.iter().all(|f| !f.contains("tmp")), "temporary files left");
    let listed: Vec<String> = rows.iter().map(|r| r.split(',').next().unwrap().to_string()).collect();
    assert_eq!(listed, files, "labels.csv lists exactly the images on disk, in order");
    for (i, f) in listed.iter().enumerate() {
        assert_eq!(f, &format!("fp_{i:08}.png"));
    }
    // The prefix was installed (there was no older dataset); no staging folder or lock is left.
    assert_eq!(names(dir.path()), ["ds"]);
}

#[cfg(unix)]
#[test]
fn ctrl_c_exits_130_saying_interrupted() {
    let child = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(["evaluate", "--limit", "300", "--size", "256"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(400));
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("interrupted"), "{e}");
}

// Issue 26, "Files and concurrent runs": outputs are staged and swapped in, one run per output
// at a time, and Ctrl-C, a kill or a full disk at any step leaves the old output or the new one,
// never neither and never a mix. The binary's test hook (`MAOBI_TEST_HOOK`, debug builds only)
// makes a named step fail as a full disk would (`fail:STEP`) or pause there (`pause:STEP`: it
// creates `MAOBI_TEST_HOOK_MARKER` and waits until the file is removed or a signal arrives).

/// `maobi` with a test hook, not yet waited for.
fn spawn_hooked(args: &[&str], hook: Option<&str>, marker: &Path) -> std::process::Child {
    let mut c = Command::new(env!("CARGO_BIN_EXE_maobi"));
    c.args(args).stdout(Stdio::null()).stderr(Stdio::piped()).env("MAOBI_TEST_HOOK_MARKER", marker);
    if let Some(h) = hook {
        c.env("MAOBI_TEST_HOOK", h);
    }
    c.spawn().unwrap()
}

/// `maobi` with a test hook, run to the end.
fn hooked(args: &[&str], hook: &str, marker: &Path) -> std::process::Output {
    spawn_hooked(args, Some(hook), marker).wait_with_output().unwrap()
}

/// Waits (at most a minute) for a paused run's marker.
fn wait_for(marker: &Path) {
    let t0 = Instant::now();
    while !marker.exists() {
        assert!(t0.elapsed() < Duration::from_secs(60), "the run never reached its pause");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The names in a folder, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// Whether a dataset folder is consistent: labels.csv lists exactly its images, in order.
fn dataset_rows(out: &Path) -> usize {
    let rows = labels_rows(&out.join("labels.csv"));
    let listed: Vec<String> = rows.iter().map(|r| r.split(',').next().unwrap().to_string()).collect();
    let files: Vec<String> = names(out).into_iter().filter(|n| n != "labels.csv" && n != ".maobi-written").collect();
    assert_eq!(listed, files, "labels.csv lists exactly the images in {}", out.display());
    rows.len()
}

#[test]
fn dataset_refuses_a_used_folder_and_replaces_it_only_when_finished() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ds");
    let marker = dir.path().join("marker");
    let ds = |n: &str, size: &str, force: bool| -> Vec<String> {
        let mut a = vec!["dataset", "--n", n, "--size", size, "-o", s(&out)];
        if force {
            a.push("--force");
        }
        a.into_iter().map(String::from).collect()
    };
    let run = |a: &[String]| maobi(&a.iter().map(String::as_str).collect::<Vec<_>>());
    ok(&run(&ds("30", "16", false)));
    assert_eq!(dataset_rows(&out), 30);
    // Before: a second run into the folder exited 0 and mixed with the first.
    fails(&run(&ds("10", "24", false)), "already exists and is not empty; give --force");
    assert_eq!(dataset_rows(&out), 30);
    // --force replaces the whole folder: a smaller --n leaves none of the old images.
    ok(&run(&ds("10", "24", true)));
    assert_eq!(dataset_rows(&out), 10);
    let size = image::image_dimensions(out.join("fp_000000.png")).unwrap();
    assert_eq!(size, (24, 24));
    // A full disk after 700 images (before: 768 PNGs and a header-only labels.csv): the old
    // dataset stays, and no staging folder or lock is left.
    let a = ds("800", "16", true);
    let o = hooked(&a.iter().map(String::as_str).collect::<Vec<_>>(), "fail:dataset-image-700", &marker);
    fails(&o, "No space left on device");
    assert_eq!(dataset_rows(&out), 10);
    assert_eq!(names(dir.path()), ["ds"], "leftovers beside the output");
    // Two runs at once into one new folder: one writes it, the other says why it did not.
    let out2 = dir.path().join("ds2");
    let both: Vec<_> = (0..2)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_maobi"))
                .args(["dataset", "--n", "200", "--size", "16", "-o", s(&out2)])
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let outs: Vec<_> = both.into_iter().map(|c| c.wait_with_output().unwrap()).collect();
    let won = outs.iter().filter(|o| o.status.success()).count();
    assert_eq!(won, 1, "exactly one run writes the folder");
    let lost = outs.iter().find(|o| !o.status.success()).unwrap();
    let e = String::from_utf8_lossy(&lost.stderr);
    assert!(e.contains("another maobi run") || e.contains("already exists"), "{e}");
    assert_eq!(dataset_rows(&out2), 200);
}

#[cfg(unix)]
#[test]
fn write_force_swap_survives_an_error_a_signal_or_a_kill_at_each_step() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let marker = dir.path().join("marker");
    let write = ["write", "十", "--size", "64", "--out", s(&out), "--force"];
    // An older run's outputs: a file maobi wrote, listed in the folder's manifest.
    let old = |out: &Path| {
        std::fs::create_dir_all(out).unwrap();
        std::fs::write(out.join("old.txt"), "old").unwrap();
        std::fs::write(out.join(".maobi-written"), "old.txt\n").unwrap();
    };
    old(&out);
    for step in ["swap-aside", "swap-install", "swap-cleanup"] {
        // An error at the step (a full disk): exit 2, the old folder in place, nothing left.
        fails(&hooked(&write, &format!("fail:{step}"), &marker), "No space left on device");
        assert_eq!(names(&out), [".maobi-written", "old.txt"], "{step}: error");
        assert_eq!(names(dir.path()), ["out"], "{step}: error");
        // Ctrl-C at the step (before: a SIGINT between removing the old and installing the new
        // left neither): exit 130, the old folder in place, nothing left.
        let child = spawn_hooked(&write, Some(&format!("pause:{step}")), &marker);
        wait_for(&marker);
        interrupt(&child);
        let o = child.wait_with_output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{step}: {e}");
        assert!(e.contains("interrupted"), "{step}: {e}");
        assert_eq!(names(&out), [".maobi-written", "old.txt"], "{step}: Ctrl-C");
        std::fs::remove_file(&marker).unwrap();
        assert_eq!(names(dir.path()), ["out"], "{step}: Ctrl-C");
        // Killed at the step: the next run puts the old folder back (or, once the new one is in
        // place, removes the old) and says so; then it refuses to replace it without --force.
        let mut child = spawn_hooked(&write, Some(&format!("pause:{step}")), &marker);
        wait_for(&marker);
        child.kill().unwrap();
        child.wait().unwrap();
        std::fs::remove_file(&marker).unwrap();
        let o = maobi(&write[..write.len() - 1]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{step}: {e}");
        assert!(e.contains("already exists and is not empty"), "{step}: {e}");
        assert!(e.contains("taking over the lock"), "{step}: {e}");
        if step == "swap-cleanup" {
            assert!(e.contains("note: removed") && e.contains(".old, the old"), "{step}: {e}");
            assert!(out.join("track.json").exists(), "{step}: the new outputs stay");
            std::fs::remove_dir_all(&out).unwrap();
            old(&out);
        } else {
            if step == "swap-install" {
                assert!(e.contains("note: put back"), "{step}: {e}");
            }
            assert_eq!(names(&out), [".maobi-written", "old.txt"], "{step}: kill");
        }
        assert_eq!(names(dir.path()), ["out"], "{step}: kill");
    }
    // Undisturbed, --force replaces the old folder.
    ok(&maobi(&write));
    assert!(out.join("track.json").exists() && !out.join("old.txt").exists());
    assert_eq!(names(dir.path()), ["out"]);
}

#[cfg(unix)]
#[test]
fn interrupted_sheets_leave_no_staging_folder() {
    // Before: 2 of 24 interrupted sheets left `.X.maobi-partial-PID/` behind (Ctrl-C removed
    // the staging folder while the run re-created it). Signals at several points of the run.
    let dir = tempfile::tempdir().unwrap();
    for (i, delay_ms) in [0u64, 150, 300, 450, 600, 750, 900, 1100].into_iter().enumerate() {
        let out = dir.path().join(format!("s{i}"));
        let child = Command::new(env!("CARGO_BIN_EXE_maobi"))
            .args(["write", "十口人大", "--size", "64", "--out", s(&out)])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        interrupt(&child);
        let o = child.wait_with_output().unwrap();
        // Either finished before the signal, or interrupted with nothing written.
        match o.status.code() {
            Some(0) => assert!(out.join("track.json").exists()),
            // 130: interrupted; none: killed by the signal before the handler was installed.
            Some(130) | None => assert!(!out.exists(), "an interrupted run wrote {}", out.display()),
            c => panic!("exit {c:?}: {}", String::from_utf8_lossy(&o.stderr)),
        }
    }
    let left: Vec<String> = names(dir.path()).into_iter().filter(|n| n.starts_with('.')).collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[cfg(unix)]
#[test]
fn two_writes_into_one_folder_one_wins_and_the_other_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let marker = dir.path().join("marker");
    let write = ["write", "十", "--size", "64", "--out", s(&out)];
    // The first run holds the folder (paused before its swap); the second is refused at once.
    let first = spawn_hooked(&write, Some("pause:swap-aside"), &marker);
    wait_for(&marker);
    refused(&["write", "口", "--size", "64", "--out", s(&out)], "another maobi run (process");
    std::fs::remove_file(&marker).unwrap();
    let o = first.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let track: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("track.json")).unwrap()).unwrap();
    assert_eq!(track["char"], "十");
    // Before: both of two runs started together succeeded and one silently replaced the other.
    let out2 = dir.path().join("out2");
    let both: Vec<_> = ["十", "口"]
        .into_iter()
        .map(|c| spawn_hooked(&["write", c, "--size", "64", "--out", s(&out2)], None, &marker))
        .collect();
    let outs: Vec<_> = both.into_iter().map(|c| c.wait_with_output().unwrap()).collect();
    assert_eq!(outs.iter().filter(|o| o.status.success()).count(), 1, "exactly one run writes the folder");
    let lost = outs.iter().find(|o| !o.status.success()).unwrap();
    let e = String::from_utf8_lossy(&lost.stderr);
    assert_eq!(lost.status.code(), Some(2), "{e}");
    assert!(e.contains("another maobi run (process") || e.contains("already exists and is not empty"), "{e}");
    // A lock left by a process that no longer runs is taken over.
    let gone = Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait_with_output().unwrap();
    let out3 = dir.path().join("out3");
    std::fs::write(dir.path().join(".out3.maobi-lock"), format!("{pid}\n")).unwrap();
    let o = maobi(&["write", "十", "--size", "64", "--out", s(&out3)]);
    let e = ok_stderr(&o);
    assert!(e.contains("taking over the lock"), "{e}");
    assert_eq!(names(dir.path()), ["out", "out2", "out3"]);
}

/// Asserts success and returns stderr.
fn ok_stderr(o: &std::process::Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{e}");
    e
}

#[cfg(unix)]
#[test]
fn an_unfinished_train_never_replaces_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let w = dir.path().join("w.safetensors");
    let marker = dir.path().join("marker");
    let train =
        ["train", "--arch", "tiny", "--steps", "4", "--batch", "2", "--val-every", "1", "--eval-n", "2", "-o", s(&w)];
    ok(&maobi(&train));
    let files = ["w.safetensors", "w.json", "loss.csv", "loss.png"];
    let read = || files.map(|f| std::fs::read(dir.path().join(f)).unwrap());
    let first = read();
    let cfg: serde_json::Value = serde_json::from_slice(&first[1]).unwrap();
    assert!(cfg["recipe"].is_object() && cfg["metrics"].is_object(), "{cfg}");
    assert_eq!(names(dir.path()), ["loss.csv", "loss.png", "w.json", "w.safetensors"], "the checkpoint is removed");
    // A different run that fails (a full disk) or is interrupted just before its outputs move
    // into place: the finished model and its loss files stay; the checkpoint is beside them.
    // Without --force a finished model is not replaced, before any training.
    let mut other = train.to_vec();
    other.extend(["--seed", "7"]);
    fails(&maobi(&other), "already exists; give --force");
    assert!(read() == first);
    other.push("--force");
    let o = hooked(&other, "fail:train-install", &marker);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("error: train-install: No space left on device"), "{e}");
    assert!(read() == first, "a failed train changed the model");
    let child = spawn_hooked(&other, Some("pause:train-install"), &marker);
    wait_for(&marker);
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_file(&marker).unwrap();
    assert!(read() == first, "an interrupted train changed the model");
    let ckpt: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("w.checkpoint.json")).unwrap()).unwrap();
    assert!(ckpt["recipe"].is_null(), "the checkpoint is the mid-run one");
    assert_eq!(
        names(dir.path()),
        ["loss.csv", "loss.png", "w.checkpoint.json", "w.checkpoint.safetensors", "w.json", "w.safetensors"]
    );
    // A finished run replaces all four and removes the checkpoint.
    ok(&maobi(&other));
    let second = read();
    assert!(second[0] != first[0] && second[2] != first[2], "the new run's weights and losses");
    assert_eq!(names(dir.path()), ["loss.csv", "loss.png", "w.json", "w.safetensors"]);
}

#[test]
fn ink_in_the_alpha_channel_is_read_on_white() {
    // Before: black RGB with the ink in alpha was "no contrast" (write --image) and "100% of
    // the image is ink" (fit-stroke).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let to_alpha = |src: &Path, dst: &Path| {
        let g = image::open(src).unwrap().to_luma8();
        let rgba = image::RgbaImage::from_fn(g.width(), g.height(), |x, y| {
            image::Rgba([0, 0, 0, 255 - g.get_pixel(x, y).0[0]])
        });
        rgba.save(dst).unwrap();
    };
    ok(&maobi(&["write", "永", "--size", "128", "--out", s(&d.join("ref"))]));
    let (yong, stroke, w) = (d.join("yong.png"), d.join("stroke.png"), d.join("w"));
    to_alpha(&d.join("ref/reference.png"), &yong);
    to_alpha(&fixtures().join("photos/stroke_05.png"), &stroke);
    ok(&maobi(&["write", "永", "--image", s(&yong), "--size", "128", "--out", s(&w)]));
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(w.join("report.json")).unwrap()).unwrap();
    assert!(rep["plan"]["strokes_found"].as_u64().unwrap() >= 3, "{rep}");
    // The alpha-ink stroke fits as the opaque original does (its scale given: the PNG lost it).
    let plain = ok(&maobi(&["fit-stroke", &fixture("photos/stroke_05.png")]));
    let alpha = ok(&maobi(&["fit-stroke", s(&stroke), "--px-per-mm", "8"]));
    assert_eq!(plain.lines().next(), alpha.lines().next(), "{plain}\n{alpha}");
}
