//! `maobi observe` against a world that is not the model: a sheet written with `write --sheet`,
//! its ink made by a brush that writes differently from `brush_model::ForwardModel` (wider,
//! longer, hairs lagging differently, ink spreading), photographed by a simulated camera (a
//! random pose up to 15° of tilt, lens blur, uneven light, noise, JPEG at quality 70), then
//! observed; and the photos `observe` must refuse. The world and the camera are in
//! `common::world`.

use std::path::Path;

use crate::common::world::*;
use crate::common::{fails, maobi, ok, s};

#[test]
fn a_photo_of_a_sheet_written_by_another_brush_is_observed_in_the_paper_frame() {
    let dir = tempfile::tempdir().unwrap();
    // Characters not used to set the observer's constants (those were tried on 永字).
    let sheet = write_sheet(dir.path(), "中国");
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let st = json(&sheet.join("track.json"));
    let sheet_mm = [210.0, 297.0];
    let stamps = world_stamps(&track.strokes, &track.brush);
    let mut rng = Rng(28);
    // Upright-ish, and the sheet upside down in the photo.
    for (k, yaw) in [0.0, 180.0].into_iter().enumerate() {
        let cam = random_camera(&mut rng, yaw);
        let (jpeg, truth_h) = photograph(&stamps, sheet_mm, &cam, 100 + k as u64);
        let photo = dir.path().join(format!("photo{k}.jpg"));
        std::fs::write(&photo, &jpeg).unwrap();
        let out = dir.path().join(format!("observed{k}"));
        ok(&maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&out)]));
        let summary = json(&out.join("summary.json"));
        let reg = &summary["registration"];
        let (rms, max) = (reg["residual_rms_mm"].as_f64().unwrap(), reg["residual_max_mm"].as_f64().unwrap());
        // The fitted map against the camera's true one, over the character boxes' corners.
        let m = &reg["paper_to_photo"]["m"];
        let fit: M3 = std::array::from_fn(|r| std::array::from_fn(|c| m[r][c].as_f64().unwrap()));
        let truth_inv = inv(&truth_h);
        let mut true_err_mm: f64 = 0.0;
        for c in st["chars"].as_array().unwrap() {
            let b: Vec<f64> = c["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            for p in [[b[0], b[1]], [b[0] + b[2], b[1]], [b[0], b[1] + b[2]], [b[0] + b[2], b[1] + b[2]]] {
                let q = apply(&truth_inv, apply(&fit, p));
                true_err_mm = true_err_mm.max((q[0] - p[0]).hypot(q[1] - p[1]));
            }
        }
        let mut ious = Vec::new();
        for (i, c) in st["chars"].as_array().unwrap().iter().enumerate() {
            let name = format!("{:02}-{}", i + 1, c["char"].as_str().unwrap());
            let obs = bezier_raster::Coverage::load(&out.join(&name).join("observed.png")).unwrap();
            let reference = bezier_raster::Coverage::load(&sheet.join(&name).join("reference.png")).unwrap();
            assert_eq!((obs.width(), obs.height()), (reference.width(), reference.height()));
            let b: Vec<f64> = c["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let truth = world_ink(&stamps, [b[0], b[1], b[2]], obs.width());
            let iou = stroke_metrics::iou(obs.as_gray(), truth.as_gray()).unwrap();
            let d = &summary["chars"][i];
            eprintln!(
                "photo {k} (tilt {:.1}° about x, {:.1}° about y, yaw {:.1}°) {name}: IoU vs world ink {iou:.4}; vs glyph CSIM {:.4}; vs plan CSIM {:.4}; width ratio {:.3}; ends beyond {:.2} mm; verdict: {}",
                cam.tilt_deg[0],
                cam.tilt_deg[1],
                cam.yaw_deg,
                d["vs_glyph"]["csim"].as_f64().unwrap(),
                d["vs_plan"]["csim"].as_f64().unwrap(),
                d["diagnosis"]["width_ratio"].as_f64().unwrap_or(f64::NAN),
                d["diagnosis"]["end_beyond_mm"].as_f64().unwrap_or(f64::NAN),
                d["verdict"].as_str().unwrap()
            );
            ious.push(iou);
            // The diagnosis sees the world's wider brush.
            let wr = d["diagnosis"]["width_ratio"].as_f64().unwrap();
            assert!(wr > 1.08, "{name}: width ratio {wr}");
            assert!(d["verdict"].as_str().unwrap().contains("wider"), "{d}");
        }
        eprintln!(
            "photo {k}: mark fit residual {rms:.3} mm RMS, {max:.3} mm max; true error at the char boxes' corners {true_err_mm:.3} mm; photo {:.2} px/mm",
            reg["photo_px_per_mm"].as_f64().unwrap()
        );
        assert!(max <= 0.3, "mark fit residual {max} mm");
        assert!(true_err_mm <= 0.5, "true mapping error {true_err_mm} mm");
        for iou in ious {
            assert!(iou >= 0.95, "IoU against the world's ink {iou}");
        }
    }
}

#[test]
fn bad_photos_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = write_sheet(dir.path(), "中国");
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let sheet_mm = [210.0, 297.0];
    let mut rng = Rng(7);
    let cam = random_camera(&mut rng, 0.0);
    let refused = |name: &str, jpeg: &[u8], sheet: &Path, needle: &str| {
        let photo = dir.path().join(format!("{name}.jpg"));
        std::fs::write(&photo, jpeg).unwrap();
        let out = dir.path().join(format!("out-{name}"));
        fails(&maobi(&["observe", s(&photo), "--sheet", s(sheet), "-o", s(&out)]), needle);
        assert!(!out.exists(), "{name}: {} was written", out.display());
    };
    // Blurred.
    let stamps = world_stamps(&track.strokes, &track.brush);
    let (jpeg, _) = photograph(&stamps, sheet_mm, &Camera { blur_px: 9.0, ..cam }, 1);
    refused("blurred", &jpeg, &sheet, "blurred");
    // A mark missing (the bottom-right one was never written: its two strokes left out).
    let mut strokes = track.strokes.clone();
    strokes.drain(4..6);
    let (jpeg, _) = photograph(&world_stamps(&strokes, &track.brush), sheet_mm, &cam, 2);
    refused("missing-mark", &jpeg, &sheet, "registration mark");
    // A photo of another sheet (same paper, other characters).
    let other = write_sheet(dir.path(), "大小");
    let t2 = robot_io::TrackFile::load(&other.join("track.json")).unwrap();
    let (jpeg, _) = photograph(&world_stamps(&t2.strokes, &t2.brush), sheet_mm, &cam, 3);
    refused("other-sheet", &jpeg, &sheet, "another sheet");
    // A sheet written without marks cannot be observed.
    let bare = dir.path().join("bare");
    ok(&maobi(&["write", "中国", "--sheet", "A4", "--size", "96", "--no-marks", "-o", s(&bare)]));
    let (jpeg, _) = photograph(&stamps, sheet_mm, &cam, 4);
    refused("no-marks", &jpeg, &bare, "no registration marks");
}

#[test]
fn sheets_carry_registration_marks_that_the_robot_checks_and_exports() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a5");
    ok(&maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "-o", s(&out)]));
    let t = json(&out.join("track.json"));
    let marks = t["marks"].as_array().unwrap();
    assert_eq!(marks.len(), 6);
    assert_eq!(t["mark_strokes"], 12);
    // The marks come first, in the margin (15 mm), the characters' strokes after them.
    let strokes = t["strokes"].as_array().unwrap();
    for st in &strokes[..12] {
        for p in st.as_array().unwrap() {
            let y = p["y_mm"].as_f64().unwrap();
            assert!(!(15.0..=210.0 - 15.0).contains(&y), "mark point at y {y}");
        }
    }
    assert_eq!(t["chars"][0]["strokes"][0], 12);
    assert_eq!(t["stroke_chars"].as_array().unwrap().len(), strokes.len());
    // robot check and every export take them as strokes.
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json");
    let check: serde_json::Value = serde_json::from_str(&ok(&maobi(&[
        "robot",
        "check",
        s(&out.join("track.json")),
        "--paper",
        s(&paper),
        "--json",
    ])))
    .unwrap();
    assert_eq!(check["strokes"].as_u64().unwrap() as usize, strokes.len(), "{check}");
    for format in ["gcode", "urscript", "aubo-lua"] {
        let f = dir.path().join(format!("p.{format}"));
        ok(&maobi(&[
            "robot",
            "export",
            s(&out.join("track.json")),
            "--paper",
            s(&paper),
            "--format",
            format,
            "-o",
            s(&f),
            "--accept-nominal-kinematics",
        ]));
        assert!(std::fs::metadata(&f).unwrap().len() > 0);
    }
    // --no-marks leaves them out; one character without --sheet gets them only with --marks.
    let bare = dir.path().join("bare");
    ok(&maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "--no-marks", "-o", s(&bare)]));
    assert!(json(&bare.join("track.json")).get("marks").is_none());
    // sheet.png draws the marks as the preview does: ink at every mark's centre and along its
    // bar, none there without marks; the characters' pixels are the same in both.
    let (img, img_bare) = (
        image::open(out.join("sheet.png")).unwrap().to_luma8(),
        image::open(bare.join("sheet.png")).unwrap().to_luma8(),
    );
    assert_eq!(img.dimensions(), img_bare.dimensions());
    let ppm = 64.0 / t["char_mm"].as_f64().unwrap();
    for m in marks {
        let c = [m["centre_mm"][0].as_f64().unwrap(), m["centre_mm"][1].as_f64().unwrap()];
        let half = m["half_length_mm"].as_f64().unwrap();
        for dx_mm in [-0.5 * half, 0.0, 0.5 * half] {
            let (x, y) = (((c[0] + dx_mm) * ppm) as u32, (c[1] * ppm) as u32);
            assert!(img.get_pixel(x, y)[0] < 128, "no mark ink at {x},{y} px ({m})");
            assert!(img_bare.get_pixel(x, y)[0] > 250, "ink at {x},{y} px without marks");
        }
    }
    let top = (15.0 * ppm).ceil() as u32 + 1;
    let bottom = ((210.0 - 15.0) * ppm).floor() as u32 - 1;
    for y in top..bottom {
        for x in 0..img.width() {
            assert_eq!(img.get_pixel(x, y), img_bare.get_pixel(x, y), "character pixel {x},{y} differs");
        }
    }
    let one = dir.path().join("one");
    ok(&maobi(&["write", "十", "--size", "64", "-o", s(&one)]));
    assert!(json(&one.join("track.json")).get("marks").is_none());
    let one_m = dir.path().join("one-marks");
    ok(&maobi(&["write", "十", "--size", "64", "--char-mm", "120", "--marks", "-o", s(&one_m)]));
    let t1 = json(&one_m.join("track.json"));
    assert_eq!((t1["kind"].as_str(), t1["marks"].as_array().map(Vec::len)), (Some("sheet"), Some(6)));
    // A sheet too small for them: written without, or refused when --marks asks for them.
    let small = dir.path().join("small");
    let o = maobi(&["write", "十", "--sheet", "90x300", "--size", "64", "-o", s(&small)]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("without registration marks"), "{o:?}");
    ok(&o);
    fails(
        &maobi(&["write", "十", "--sheet", "90x300", "--size", "64", "--marks", "-o", s(&dir.path().join("s2"))]),
        "--marks",
    );
}
