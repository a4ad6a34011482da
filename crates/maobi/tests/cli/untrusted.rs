//! Safety III (issue 43): folders maobi once wrote and reads back (a sheet's track.json and
//! images, an observation's summary.json and observed.png, a calibration layout) are untrusted
//! input. Each failure of the sweep, tried against the real binary: a clear one-line
//! error naming the file and field (or flag), nothing written outside `-o`, no panic.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{Value, json};

use crate::common::world::*;
use crate::common::{fails, maobi, ok, s};

/// Copies the files of folder `from` into `to` (one level of subfolders, as a sheet has).
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let t = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), t).unwrap();
        }
    }
}

/// Rewrites the JSON file `p` through `f`.
fn edit(p: &Path, f: impl FnOnce(&mut Value)) {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(p, serde_json::to_string(&v).unwrap()).unwrap();
}

/// Every path under `dir`, relative.
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(dir).unwrap().display().to_string());
            if p.is_dir() {
                todo.push(p);
            }
        }
    }
    out
}

/// A two-character A5 sheet with marks, 64 px a character.
fn small_sheet(dir: &Path) -> PathBuf {
    let out = dir.join("sheet");
    ok(&maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "-o", s(&out)]));
    out
}

#[test]
fn a_sheets_track_json_is_validated_before_anything_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = small_sheet(dir.path());
    let n_strokes = json(&sheet.join("track.json"))["strokes"].as_array().unwrap().len();
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "escape",
            Box::new(|t| t["chars"][0]["char"] = json!("x/../../../escaped")),
            "field `chars[0].char`: \"x/../../../escaped\": expected one printable character",
        ),
        (
            "box-0",
            Box::new(|t| t["chars"][0]["char_box_mm"][2] = json!(0.0)),
            "field `chars[0].char_box_mm`: side 0 mm",
        ),
        ("box-huge", Box::new(|t| t["chars"][1]["char_box_mm"][2] = json!(1e308)), "field `chars[1].char_box_mm`"),
        ("box-negative", Box::new(|t| t["chars"][0]["char_box_mm"][2] = json!(-30.0)), "field `chars[0].char_box_mm`"),
        (
            "char-mm-huge",
            Box::new(|t| t["char_mm"] = json!(1e308)),
            "field `char_mm`: 1e308 mm: expected a number in 1..=1000",
        ),
        ("no-chars", Box::new(|t| t["chars"] = json!([])), "field `chars`: empty"),
        ("range", Box::new(|t| t["chars"][0]["strokes"] = json!([15, 99999])), "field `chars[0].strokes`: [15, 99999]"),
        (
            "marks",
            Box::new(|t| {
                let m = t["marks"][0].clone();
                t["marks"] = Value::Array(vec![m; 12_000]);
            }),
            "field `marks`: 12000 marks: a sheet has at most 6",
        ),
        ("brush", Box::new(|t| t["brush"]["ranges"]["h_mm"]["min"] = json!(-1e308)), "ranges.h_mm"),
        ("stroke-chars", Box::new(move |t| t["stroke_chars"][n_strokes - 1] = json!(7)), "field `stroke_chars["),
        ("kind", Box::new(|t| t["kind"] = json!("calibration")), "field `kind`"),
        ("point", Box::new(|t| t["strokes"][12][0]["x_mm"] = json!(1e300)), "field `strokes[12][0]`"),
    ];
    let photo = dir.path().join("photo.jpg");
    for (name, f, needle) in cases {
        let bad = dir.path().join(format!("bad-{name}"));
        copy_dir(&sheet, &bad);
        edit(&bad.join("track.json"), f);
        let out = dir.path().join(format!("out-{name}"));
        let o = maobi(&["observe", s(&photo), "--sheet", s(&bad), "-o", s(&out)]);
        fails(&o, needle);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("--sheet") && e.contains("track.json"), "{name}: {e}");
        assert!(!out.exists(), "{name}");
    }
    // Cut short: not JSON, said so.
    let cut = dir.path().join("bad-cut");
    copy_dir(&sheet, &cut);
    let t = std::fs::read(cut.join("track.json")).unwrap();
    std::fs::write(cut.join("track.json"), &t[..t.len() / 2]).unwrap();
    fails(
        &maobi(&["observe", s(&photo), "--sheet", s(&cut), "-o", s(&dir.path().join("o"))]),
        "is not a sheet's track.json",
    );
    // Nothing escaped the output (or anywhere in the folder).
    assert!(!tree(dir.path()).iter().any(|p| p.contains("escaped")), "{:?}", tree(dir.path()));
    // A character image of another size names its file, before the photo is read.
    let sized = dir.path().join("bad-size");
    copy_dir(&sheet, &sized);
    image::GrayImage::from_pixel(100, 80, image::Luma([255])).save(sized.join("02-口/render.png")).unwrap();
    fails(
        &maobi(&["observe", s(&photo), "--sheet", s(&sized), "-o", s(&dir.path().join("o"))]),
        "02-口/render.png is 100×80 px: expected a square of 64..=4096 px",
    );
    image::GrayImage::from_pixel(96, 96, image::Luma([255])).save(sized.join("02-口/render.png")).unwrap();
    fails(
        &maobi(&["observe", s(&photo), "--sheet", s(&sized), "-o", s(&dir.path().join("o"))]),
        "02-口/render.png is not the size of",
    );
}

#[test]
fn output_over_an_input_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = small_sheet(dir.path());
    let photo = dir.path().join("photo.jpg");
    for (out, needle) in [
        (sheet.clone(), "is the input --sheet"),
        (sheet.join("inside"), "lies inside the input --sheet"),
        (dir.path().to_path_buf(), "holds the input --sheet"),
    ] {
        fails(&maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&out), "--force"]), needle);
    }
    // Through a symlink too.
    #[cfg(unix)]
    {
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&sheet, &link).unwrap();
        fails(&maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&link), "--force"]), "is the input --sheet");
    }
    assert!(sheet.join("track.json").is_file() && sheet.join("01-十/reference.png").is_file());
}

#[test]
fn a_truncated_jpeg_is_called_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = small_sheet(dir.path());
    let img = image::RgbImage::from_fn(400, 300, |x, y| image::Rgb([(x % 256) as u8, (y % 256) as u8, 128]));
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
        .encode(&img, 400, 300, image::ExtendedColorType::Rgb8)
        .unwrap();
    let photo = dir.path().join("cut.jpg");
    std::fs::write(&photo, &jpeg[..jpeg.len() / 2]).unwrap();
    fails(
        &maobi(&["observe", s(&photo), "--sheet", s(&sheet), "-o", s(&dir.path().join("o"))]),
        "cut.jpg: the JPEG file ends before its image data does (truncated",
    );
}

/// A sheet of 十口 (A5, 64 px) photographed in the test world and observed: (sheet, observation).
fn observed_sheet(dir: &Path) -> (PathBuf, PathBuf) {
    let sheet = small_sheet(dir);
    let track = robot_io::TrackFile::load(&sheet.join("track.json")).unwrap();
    let mut rng = Rng(3);
    let cam = random_camera(&mut rng, 0.0);
    let (jpeg, _) =
        photograph_sized(&world_stamps(&track.strokes, &track.brush), [148.0, 210.0], &cam, 9, [1200, 1620], 1410.0);
    let photo = dir.join("photo.jpg");
    std::fs::write(&photo, &jpeg).unwrap();
    // --sheet as typed relative to the working folder.
    let obs = dir.join("obs");
    let o = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .current_dir(dir)
        .args(["observe", "photo.jpg", "--sheet", "sheet", "-o", "obs"])
        .output()
        .unwrap();
    ok(&o);
    (sheet, obs)
}

#[test]
fn an_observation_is_typed_names_its_sheet_and_is_validated() {
    let dir = tempfile::tempdir().unwrap();
    let (sheet, obs) = observed_sheet(dir.path());
    let summary = json(&obs.join("summary.json"));
    assert_eq!(summary["version"], 1);
    let abs = std::fs::canonicalize(&sheet).unwrap();
    assert_eq!(summary["sheet"]["path"].as_str(), abs.to_str(), "{summary}");
    let fp = summary["sheet"]["track_fingerprint"].as_str().unwrap();
    assert_eq!(fp, pipeline::fingerprint(&std::fs::read(sheet.join("track.json")).unwrap()));
    assert_eq!(summary["chars"][1]["folder"], "02-口");
    assert_eq!(summary["chars"][1]["size_px"], 64);
    assert!(summary["registration"]["leave_one_out_max_mm"].as_f64().unwrap() < 0.6, "{summary}");
    let write = |o: &Path, out: &Path| {
        maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "--observed", s(o), "--brush-only", "-o", s(out)])
    };
    // The wrong sheet: from a folder holding another sheet of the same name, the observed one
    // is used (its absolute path), not the one beside the working folder.
    let elsewhere = dir.path().join("elsewhere");
    ok(&maobi(&["write", "大小", "--sheet", "A5", "--size", "64", "-o", s(&elsewhere.join("sheet"))]));
    let o = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .current_dir(&elsewhere)
        .args(["write", "十口", "--sheet", "A5", "--size", "64", "--observed"])
        .arg(&obs)
        .args(["--brush-only", "-o", "round1"])
        .output()
        .unwrap();
    ok(&o);
    let r1 = json(&elsewhere.join("round1/summary.json"));
    assert_eq!(r1["observed"]["sheet"].as_str(), abs.to_str(), "{}", r1["observed"]);
    // Each case on a copy of the observation (or of the sheet), refused before any work.
    type Edit = Box<dyn Fn(&Path, &Path)>;
    let white = |side: u32| {
        move |o: &Path, _: &Path| {
            image::GrayImage::from_pixel(side, side, image::Luma([255])).save(o.join("01-十/observed.png")).unwrap()
        }
    };
    let cases: Vec<(&str, Edit, &str)> = vec![
        ("one-px", Box::new(white(1)), "01-十/observed.png is 1×1 px, expected 64×64 px (chars[0].size_px of"),
        (
            "blank",
            Box::new(white(64)),
            "01-十/observed.png holds no ink (0 inked px of 4096): no ink was seen of \"十\"",
        ),
        (
            "no-version",
            Box::new(|o, _| {
                edit(&o.join("summary.json"), |v| v.as_object_mut().unwrap().remove("version").map(|_| ()).unwrap())
            }),
            "summary.json: field `version`: missing: written by an older maobi",
        ),
        (
            "score",
            Box::new(|o, _| edit(&o.join("summary.json"), |v| v["chars"][0]["vs_plan"]["csim"] = json!(7.0))),
            "field `chars[0].vs_plan.csim`: 7",
        ),
        (
            "char",
            Box::new(|o, _| edit(&o.join("summary.json"), |v| v["chars"][0]["char"] = json!("x/../../escaped"))),
            "field `chars[0].char`",
        ),
        (
            "relative-sheet",
            Box::new(|o, _| edit(&o.join("summary.json"), |v| v["sheet"]["path"] = json!("sheet"))),
            "field `sheet.path`: sheet: expected an absolute path",
        ),
        (
            "cut",
            Box::new(|o, _| {
                let t = std::fs::read(o.join("summary.json")).unwrap();
                std::fs::write(o.join("summary.json"), &t[..t.len() / 2]).unwrap();
            }),
            "is not the summary.json of `maobi observe`",
        ),
        (
            "sheet-summary-cut",
            Box::new(|_, sh| {
                let t = std::fs::read(sh.join("summary.json")).unwrap();
                std::fs::write(sh.join("summary.json"), &t[..t.len() / 2]).unwrap();
            }),
            "summary.json is not the summary.json of `maobi write` (cut short, or not JSON)",
        ),
        (
            "rounds",
            Box::new(|_, sh| edit(&sh.join("summary.json"), |v| v["rounds"] = Value::Array(vec![json!({}); 20_000]))),
            "field `rounds`: 20000 rounds, expected at most 100",
        ),
        (
            "sheet-replaced",
            Box::new(|_, sh| {
                ok(&maobi(&[
                    "write",
                    "十口",
                    "--sheet",
                    "A5",
                    "--size",
                    "64",
                    "--per-line",
                    "1",
                    "-o",
                    s(sh),
                    "--force",
                ]));
            }),
            "not the sheet that was observed",
        ),
    ];
    for (name, f, needle) in cases {
        // Each case gets its own copies: the observation names its sheet by absolute path, so
        // the copy is pointed at the sheet's copy.
        let (o, sh) = (dir.path().join(format!("obs-{name}")), dir.path().join(format!("sheet-{name}")));
        copy_dir(&obs, &o);
        copy_dir(&sheet, &sh);
        let sh_abs = std::fs::canonicalize(&sh).unwrap();
        edit(&o.join("summary.json"), |v| v["sheet"]["path"] = json!(sh_abs.to_str().unwrap()));
        f(&o, &sh);
        let out = dir.path().join(format!("out-{name}"));
        let r = write(&o, &out);
        fails(&r, needle);
        assert!(String::from_utf8_lossy(&r.stderr).contains("--observed"), "{name}");
        assert!(!out.exists(), "{name}");
    }
    // An observation over 8192² px is refused from its header, before it is decoded.
    let big = dir.path().join("obs-big");
    copy_dir(&obs, &big);
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut png,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::NoFilter,
    )
    .write_image(&vec![255u8; 8192 * 8192], 8192, 8192, image::ExtendedColorType::L8)
    .unwrap();
    std::fs::write(big.join("01-十/observed.png"), png).unwrap();
    fails(&write(&big, &dir.path().join("out-big")), "observed.png is 8192×8192 px, expected 64×64 px");
    // The output over the observation or its sheet.
    fails(&write(&obs, &obs), "is the input --observed");
    let o =
        maobi(&["write", "十口", "--sheet", "A5", "--size", "64", "--observed", s(&obs), "-o", s(&sheet), "--force"]);
    fails(&o, "is the input --observed's sheet");
    assert!(sheet.join("track.json").is_file());
}

use image::ImageEncoder;

#[test]
fn stroke_chars_naming_a_character_that_does_not_exist_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = small_sheet(dir.path());
    let t = sheet.join("track.json");
    let n = json(&t)["strokes"].as_array().unwrap().len();
    // Every stroke given to a character 7 of a sheet of two: a robot.json asking for a dip
    // before each character would get one.
    edit(&t, |v| v["stroke_chars"] = Value::Array(vec![json!(7); n]));
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json");
    for args in [
        vec!["robot", "check", s(&t), "--paper", s(&paper)],
        vec!["preview", s(&t), "-o", s(&dir.path().join("p.html"))],
    ] {
        fails(&maobi(&args), "field `stroke_chars`: stroke 0 is given character 7");
    }
    edit(&t, |v| {
        let mut sc = vec![json!(0); n];
        sc[n - 1] = json!(2);
        v["stroke_chars"] = Value::Array(sc);
    });
    fails(&maobi(&["robot", "check", s(&t), "--paper", s(&paper)]), "field `stroke_chars`: stroke");
}

#[test]
fn a_calibration_layout_with_a_huge_cell_is_refused_before_anything_is_allocated() {
    let dir = tempfile::tempdir().unwrap();
    let cal = dir.path().join("cal");
    ok(&maobi(&["calibrate-sheet", "-o", s(&cal)]));
    edit(&cal.join("layout.json"), |v| v["presses"][0]["cell_mm"] = json!([10.0, 10.0, 2510.0, 2510.0]));
    let photo = dir.path().join("photo.jpg");
    std::fs::write(&photo, b"not read").unwrap();
    fails(
        &maobi(&["calibrate", "--sheet-photo", s(&photo), "--layout", s(&cal), "-o", s(&dir.path().join("b.json"))]),
        "field `presses[0].cell_mm`: [10, 10, 2510, 2510] mm",
    );
}

#[test]
fn a_finished_model_is_not_replaced_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let w = dir.path().join("g/w.safetensors");
    let train =
        ["train", "--arch", "tiny", "--steps", "2", "--batch", "2", "--val-every", "1", "--eval-n", "2", "-o", s(&w)];
    ok(&maobi(&train));
    let before = std::fs::read(&w).unwrap();
    fails(&maobi(&train), "already exists; give --force");
    assert_eq!(std::fs::read(&w).unwrap(), before);
    // The config alone (weights moved away) is not replaced either.
    std::fs::rename(&w, dir.path().join("elsewhere.safetensors")).unwrap();
    fails(&maobi(&train), "w.json: already exists; give --force");
    let mut forced = train.to_vec();
    forced.push("--force");
    ok(&maobi(&forced));
}

#[test]
fn a_long_text_reports_progress_without_a_terminal_and_writes_each_character() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("long");
    let text = "十口人丁山水大小";
    let o = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .env("MAOBI_PROGRESS_AFTER_S", "0")
        .args(["write", text, "--size", "64", "--per-line", "3", "-o", s(&out)])
        .output()
        .unwrap();
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("write: ")).collect();
    assert!(lines.len() >= 3 && lines.last().unwrap().starts_with("write: 8/8 (100%)"), "{err}");
    for (i, c) in text.chars().enumerate() {
        assert!(out.join(format!("{:02}-{c}/render.png", i + 1)).is_file(), "{c}");
    }
    let t = json(&out.join("track.json"));
    assert_eq!(t["chars"].as_array().unwrap().len(), 8);
}

/// A device or a FIFO given as an input file (a measurements CSV, a brush profile, a font, a
/// generator) is refused before it is read: `/dev/zero` never ends (the CSV reader once grew
/// until the process aborted) and a FIFO blocks until a writer comes.
#[test]
fn devices_and_fifos_are_refused_as_input_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let fifo = dir.path().join("fifo.csv");
    assert!(Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()), "mkfifo");
    for input in ["/dev/zero", s(&fifo)] {
        fails(&maobi(&["calibrate", input, "-o", s(&out.join("b.json"))]), "not a regular file");
        fails(&maobi(&["write", "永", "--brush", input, "--size", "64", "-o", s(&out)]), "not a regular file");
        fails(&maobi(&["write", "永", "--font", input, "--size", "64", "-o", s(&out)]), "not a regular file");
    }
    // Weights that are a FIFO, beside a good config.
    let weights = dir.path().join("g.safetensors");
    assert!(Command::new("mkfifo").arg(&weights).status().is_ok_and(|s| s.success()), "mkfifo");
    let pen1 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../neural-gen/data/pen1.json");
    std::fs::copy(pen1, dir.path().join("g.json")).unwrap();
    fails(&maobi(&["eval-generator", "--generator", s(&weights)]), "not a regular file");
    assert!(!out.exists(), "nothing written");
}
