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

/// The sheet's strokes with mark `k`'s two strokes moved by `d` mm (the mark written out of
/// place: where track.json says it is no longer holds).
fn with_mark_moved(strokes: &[brush_model::Stroke], k: usize, d: [f64; 2]) -> Vec<brush_model::Stroke> {
    let mut out = strokes.to_vec();
    for st in &mut out[2 * k..2 * k + 2] {
        for p in &mut st.points {
            p.x_mm += d[0];
            p.y_mm += d[1];
        }
    }
    out
}

#[test]
fn a_corner_mark_6_mm_out_of_place_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = write_sheet(dir.path(), "中国");
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let st = json(&sheet.join("track.json"));
    assert_eq!(st["marks"][1]["role"], "top_right");
    let mut rng = Rng(7);
    let cam = random_camera(&mut rng, 0.0);
    // The top-right corner mark 6 mm down and to the left (inwards): the fit to all marks hides
    // most of it in its residual (about 0.75 mm, under RESIDUAL_LIMIT_MM: accepted before this
    // check), the fit to the others does not.
    let d = 6.0 / 2f64.sqrt();
    let strokes = with_mark_moved(&track.strokes, 1, [-d, d]);
    let (jpeg, _) = photograph(&world_stamps(&strokes, &track.brush), [210.0, 297.0], &cam, 5);
    let photo = dir.path().join("moved.jpg");
    std::fs::write(&photo, &jpeg).unwrap();
    let out = dir.path().join("out");
    fails(
        &maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&out)]),
        "mm from where the other marks put it (limit 0.6 mm)",
    );
    assert!(!out.exists());
}

/// The leave-one-out limit (`observe::LEAVE_ONE_OUT_LIMIT_MM`) measured: on clean photos, and
/// with each mark in turn written `d` mm out of place (a random direction), the largest
/// distance of a mark from where the others put it, against the true mapping error the fit to
/// all marks would make at the character boxes' corners. Printed for docs/closed-loop.md.
#[test]
#[ignore = "measurement (about 4 min): cargo test -p maobi --test cli -- observe::leave_one_out_measured --ignored --nocapture"]
fn leave_one_out_measured() {
    use observe::{Homography, KnownMark, ObserveError, Photo, ink_map, register};
    let dir = tempfile::tempdir().unwrap();
    let sheet = write_sheet(dir.path(), "中国");
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let st = json(&sheet.join("track.json"));
    let marks: Vec<KnownMark> = st["marks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| KnownMark {
            role: m["role"].as_str().unwrap().into(),
            centre_mm: [m["centre_mm"][0].as_f64().unwrap(), m["centre_mm"][1].as_f64().unwrap()],
            half_length_mm: m["half_length_mm"].as_f64().unwrap(),
            half_width_mm: m["half_width_mm"].as_f64().unwrap(),
        })
        .collect();
    // The roles in track.json's order are register's (corners first).
    let corners: Vec<[f64; 2]> = st["chars"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|c| {
            let b: Vec<f64> = c["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            [[b[0], b[1]], [b[0] + b[2], b[1]], [b[0], b[1] + b[2]], [b[0] + b[2], b[1] + b[2]]]
        })
        .collect();
    let sheet_mm = [210.0, 297.0];
    let mut rng = Rng(41);
    let observe_one = |strokes: &[brush_model::Stroke], cam: &Camera, seed: u64| {
        let (jpeg, truth) = photograph(&world_stamps(strokes, &track.brush), sheet_mm, cam, seed);
        let img = image::load_from_memory(&jpeg).unwrap();
        let photo = Photo::from_image(&img).unwrap();
        let ink = ink_map(&photo).unwrap();
        let loo = match register(&ink, &marks) {
            Ok(r) => Ok((r.leave_one_out_max_mm, r.residual_max_mm)),
            Err(ObserveError::Misplaced { error_mm, .. }) => Err((error_mm, "refused".to_string())),
            // Far enough out of place that the marks are not found at all.
            Err(e) => Err((f64::NAN, format!("refused ({e})"))),
        };
        (loo, truth, photo.reduced_by as f64)
    };
    let mut clean_max: f64 = 0.0;
    for k in 0..4 {
        let cam = random_camera(&mut rng, if k % 2 == 0 { 0.0 } else { 180.0 });
        let (loo, ..) = observe_one(&track.strokes, &cam, 200 + k);
        let (l, r) = loo.unwrap_or_else(|e| panic!("a clean photo refused: {e:?}"));
        eprintln!("clean photo {k}: leave-one-out max {l:.3} mm, residual max {r:.3} mm");
        clean_max = clean_max.max(l);
    }
    let mut rows = Vec::new();
    for d in [0.5, 1.0, 1.5, 2.0, 3.0, 6.0] {
        for (k, m) in marks.iter().enumerate() {
            let cam = random_camera(&mut rng, 0.0);
            let phi = rng.uniform(0.0, std::f64::consts::TAU);
            let shift = [d * phi.cos(), d * phi.sin()];
            let (loo, truth, _) = observe_one(&with_mark_moved(&track.strokes, k, shift), &cam, 300 + k as u64);
            // The fit to all marks this photo gives (the marks' centres of ink are where the
            // world wrote them), and its true error at the character boxes' corners.
            let paper: Vec<[f64; 2]> = marks.iter().map(|m| m.centre_mm).collect();
            let photo_pts: Vec<[f64; 2]> = paper
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let q = if i == k { [p[0] + shift[0], p[1] + shift[1]] } else { *p };
                    apply(&truth, q)
                })
                .collect();
            let fit = Homography::fit(&paper, &photo_pts).unwrap();
            let back = inv(&truth);
            let true_err = corners
                .iter()
                .map(|p| {
                    let q = apply(&back, fit.apply(*p));
                    (q[0] - p[0]).hypot(q[1] - p[1])
                })
                .fold(0.0, f64::max);
            let (l, verdict) = match loo {
                Ok((l, _)) => (l, "accepted".to_string()),
                Err(e) => e,
            };
            eprintln!(
                "{d:.1} mm {}: leave-one-out max {l:.3} mm, true error at the boxes' corners {true_err:.3} mm: {verdict}",
                m.role
            );
            rows.push((d, l, true_err, verdict));
        }
    }
    eprintln!("clean photos: leave-one-out at most {clean_max:.3} mm");
    for d in [0.5, 1.0, 1.5, 2.0, 3.0, 6.0] {
        let r: Vec<_> = rows.iter().filter(|r| r.0 == d).collect();
        let lo = r.iter().map(|r| r.1).filter(|v| v.is_finite()).fold(f64::INFINITY, f64::min);
        let hi = r.iter().map(|r| r.1).filter(|v| v.is_finite()).fold(0.0, f64::max);
        let err = r.iter().map(|r| r.2).fold(0.0, f64::max);
        let refused = r.iter().filter(|r| r.3.starts_with("refused")).count();
        eprintln!("| {d:.1} mm | {lo:.2}–{hi:.2} mm | {err:.2} mm | {refused} of {} |", r.len());
    }
    // Every mark 1 mm or more out of place is refused, and what is accepted maps the boxes
    // within 0.5 mm; clean photos are far below the limit.
    assert!(clean_max < observe::LEAVE_ONE_OUT_LIMIT_MM / 5.0, "clean {clean_max}");
    assert!(rows.iter().filter(|r| r.0 >= 1.0).all(|r| r.3.starts_with("refused")));
    assert!(rows.iter().filter(|r| r.3 == "accepted").all(|r| r.2 <= 0.5));
}
