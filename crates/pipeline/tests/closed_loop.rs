//! One round of the closed loop through the pipeline's API, without the binary: a sheet written
//! by the pipeline, an observation of it built here (its ink drawn by a brush wider than the one
//! the sheet was written with), read back and the next attempt planned.

use std::path::{Path, PathBuf};

use bezier_raster::ModelKind;
use brush_model::BrushProfile;
use pipeline::{
    BrushCorrection, Flow, Grid, Layout, NextOptions, ObservedRun, ObservedRunError, Prepared, SheetTrack, TextOptions,
    WriteOptions, layout_on_sheet, parse_sheet, predict_attempt, prepare, write_text,
};
use trajectory::embedded_glyph;

const SIDE: u32 = 64;

fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

fn quick() -> WriteOptions {
    WriteOptions { size: SIDE, free_widths: false, execute: false, ..WriteOptions::default() }
}

fn layout(text: &str, sheet: &str) -> Layout {
    let n = text.chars().count();
    layout_on_sheet(&parse_sheet(sheet).unwrap(), n, Flow::Columns, Some(2), 15.0, Some(30.0)).unwrap()
}

fn prepared(text: &str) -> Vec<Prepared> {
    text.chars().map(|c| prepare(embedded_glyph(c).unwrap(), None).unwrap()).collect()
}

/// A sheet of `text` written with pen1 in `dir/sheet` (its track.json), as `maobi write` lays it.
fn write_sheet(dir: &Path, text: &str) -> (PathBuf, SheetTrack) {
    let lay = layout(text, "A5");
    let opts = TextOptions { layout: Some(lay.clone()), per_line: 2, ..TextOptions::default() };
    let w = write_text(prepared(text), &pen1(), &quick(), &opts, &|| {}).unwrap();
    let chars: Vec<_> =
        w.results.iter().map(|r| (r.report.char.clone(), r.char_box, r.track.strokes.as_slice())).collect();
    let track = SheetTrack::new(&w.layout, Flow::Columns, Grid::None, &chars, &pen1());
    let sheet = dir.join("sheet");
    std::fs::create_dir_all(&sheet).unwrap();
    std::fs::write(sheet.join("track.json"), serde_json::to_string_pretty(&track).unwrap()).unwrap();
    (std::fs::canonicalize(&sheet).unwrap(), track)
}

/// An observation of `sheet` in `dir/obs`: each character's ink as `world` writes its track.
fn observe(dir: &Path, sheet: &Path, track: &SheetTrack, world: &BrushProfile) -> PathBuf {
    let obs = dir.join("obs");
    let scores = serde_json::json!({"csim": 0.9, "ssim": 0.8, "iou": 0.8});
    let mut chars = Vec::new();
    for (i, c) in track.chars.iter().enumerate() {
        let folder = pipeline::char_folder(i, &c.char);
        let [x0_mm, y0_mm, size_mm] = c.char_box_mm;
        let attempt = pipeline::LastAttempt {
            ch: &c.char,
            char_box: trajectory::CharBox { x0_mm, y0_mm, size_mm },
            strokes: &track.strokes[c.strokes[0]..c.strokes[1]],
            observed: &bezier_raster::Coverage::new(SIDE, SIDE),
        };
        let ink = predict_attempt(&attempt, world, ModelKind::Bsm, SIDE).unwrap();
        std::fs::create_dir_all(obs.join(&folder)).unwrap();
        std::fs::write(obs.join(&folder).join("observed.png"), ink.encode_png().unwrap()).unwrap();
        chars.push(serde_json::json!({"char": c.char, "folder": folder, "size_px": SIDE, "vs_glyph": scores,
            "vs_plan": scores, "verdict": "wider than planned",
            "diagnosis": {"strokes": [], "width_ratio": 1.3, "end_beyond_mm": null, "lateral_mm": null}}));
    }
    let text: String = track.chars.iter().map(|c| c.char.as_str()).collect();
    let summary = serde_json::json!({
        "version": pipeline::OBSERVATION_VERSION, "photo": "photo.jpg", "text": text, "brush": "pen1",
        "sheet": {
            "path": sheet,
            "track_fingerprint": pipeline::fingerprint(&std::fs::read(sheet.join("track.json")).unwrap()),
        },
        "registration": {"residual_rms_mm": 0.0, "residual_max_mm": 0.0, "leave_one_out_max_mm": 0.0, "edge_mm": 0.3,
            "photo_px_per_mm": 6.0, "photo_reduced_by": 1, "corner_shift": 0, "lens_distortion": "not modelled",
            "paper_to_photo": {"m": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]}, "marks": []},
        "chars": chars,
    });
    std::fs::write(obs.join("summary.json"), summary.to_string()).unwrap();
    obs
}

/// pen1 writing 30 % wider and spreading 0.2 mm.
fn wide() -> BrushProfile {
    let c = BrushCorrection { width_factor: 1.3, spread_mm: 0.2, ..BrushCorrection::IDENTITY };
    c.apply(&pen1(), "wide").unwrap()
}

fn opts(char_mm: Option<f64>, brush_only: bool) -> NextOptions {
    NextOptions { model: ModelKind::Bsm, refine: None, brush_only, char_mm, choose_brush: true, alpha_rad: 0.0 }
}

#[test]
fn a_wider_ink_corrects_the_brush_and_plans_both_levers() {
    let dir = tempfile::tempdir().unwrap();
    let (sheet, track) = write_sheet(dir.path(), "十口");
    let obs = observe(dir.path(), &sheet, &track, &wide());
    let run = ObservedRun::load(&obs, &['十', '口'], Some(&layout("十口", "A5"))).unwrap();
    assert_eq!(run.sheet_dir, sheet);
    assert!(run.earlier.is_empty());
    let p = prepared("十口");
    // Without a box size the corrected brush writes the next attempt.
    let next = run.plan(&p, &opts(None, false)).unwrap();
    let c = next.correction;
    assert!(c.not_taken.is_none(), "{c:?}");
    assert!(c.width_factor > 1.1, "{c:?}");
    assert!(c.ink_error_after < 0.5 * c.ink_error_before, "{c:?}");
    assert_eq!(next.corrected.name, "pen1+observed1");
    assert!(pipeline::same_brush(&next.brush, &next.corrected));
    assert!(!pipeline::same_brush(&next.brush, &pen1()));
    assert!(next.choice.is_none() && next.kept_because.is_none());
    // Both levers: the tracks are refined (the defaults) against residuals of every character.
    assert_eq!(next.refine, Some(track_refine::RefineOptions::default()));
    assert_eq!(next.residuals.as_ref().map(Vec::len), Some(2));
    // The round's entry names what was observed and what writes the next attempt.
    let round = next.round(&run, false);
    assert_eq!(round.round, 0);
    assert_eq!(round.brush, "pen1");
    assert_eq!(round.brush_after, "pen1+observed1");
    assert_eq!(round.chars.len(), 2);
    assert_eq!(round.chars[1].char, "02-口");
    assert!(round.track.starts_with("refined against"), "{}", round.track);
    assert_eq!(pipeline::NextAttempt::rounds(&run, &round).len(), 1);
    // With a box size, pen1's correction is carried to the built-ins and one chosen for it;
    // --brush-only leaves the track lever out.
    let next = run.plan(&p, &opts(Some(30.0), true)).unwrap();
    let choice = next.choice.as_ref().expect("a built-in chosen");
    assert!(choice.profile.name.ends_with("+observed1"), "{}", choice.profile.name);
    assert_eq!(next.brush.name, choice.profile.name);
    assert!(next.refine.is_none() && next.residuals.is_none());
    assert_eq!(next.round(&run, false).track, "built with the corrected brush");
}

#[test]
fn ink_as_planned_keeps_the_brush_and_starts_from_the_last_tracks() {
    let dir = tempfile::tempdir().unwrap();
    let (sheet, track) = write_sheet(dir.path(), "十");
    let obs = observe(dir.path(), &sheet, &track, &pen1());
    let run = ObservedRun::load(&obs, &['十'], None).unwrap();
    let p = prepared("十");
    let next = run.plan(&p, &opts(None, false)).unwrap();
    // Nothing to explain: the correction is not taken and the brush stays pen1.
    assert_eq!(next.corrected.name, "pen1", "{:?}", next.correction);
    assert!(pipeline::same_brush(&next.brush, &pen1()));
    // Written with the brush of the last attempt, the refinement starts from its tracks.
    let lay = layout("十", "A5");
    let text = TextOptions { layout: Some(lay), per_line: 2, ..TextOptions::default() };
    let mut w = write_text(p.clone(), &next.brush, &quick(), &text, &|| {}).unwrap();
    let ro = track_refine::RefineOptions { iterations: 2, ..track_refine::RefineOptions::default() };
    let next = pipeline::NextAttempt { refine: Some(ro), ..next };
    assert!(next.refine(&run, &mut w.results, &p, &quick()).unwrap());
    assert!(w.results[0].report.refine.is_some());
    assert!(next.round(&run, true).track.starts_with("refined from the last attempt's track"));
}

#[test]
fn another_text_layout_sheet_or_blank_ink_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (sheet, track) = write_sheet(dir.path(), "十口");
    let obs = observe(dir.path(), &sheet, &track, &wide());
    let msg = |e: ObservedRunError| {
        let mut s = e.to_string();
        let mut src = std::error::Error::source(&e);
        while let Some(e) = src {
            s.push_str(&format!(": {e}"));
            src = e.source();
        }
        s
    };
    let e = ObservedRun::load(&obs, &['口', '十'], None).unwrap_err();
    assert!(matches!(e, ObservedRunError::OtherText { .. }), "{e:?}");
    assert!(msg(e).contains("give the same characters"));
    let e = ObservedRun::load(&obs, &['十', '口'], Some(&layout("十口", "A4"))).unwrap_err();
    assert!(matches!(e, ObservedRunError::OtherLayout { .. }), "{e:?}");
    assert!(msg(e).contains("laid out otherwise"));
    // A blank observed image.
    let png = obs.join("02-口/observed.png");
    let kept = std::fs::read(&png).unwrap();
    std::fs::write(&png, bezier_raster::Coverage::new(SIDE, SIDE).encode_png().unwrap()).unwrap();
    let e = msg(ObservedRun::load(&obs, &['十', '口'], None).unwrap_err());
    assert!(e.contains("02-口/observed.png holds no ink (0 inked px of 4096)"), "{e}");
    std::fs::write(&png, kept).unwrap();
    // The sheet written again since: its fingerprint no longer matches.
    let mut t = std::fs::read_to_string(sheet.join("track.json")).unwrap();
    t.push('\n');
    std::fs::write(sheet.join("track.json"), t).unwrap();
    let e = msg(ObservedRun::load(&obs, &['十', '口'], None).unwrap_err());
    assert!(
        e.contains("summary.json: field `sheet.track_fingerprint`") && e.contains("not the sheet that was observed")
    );
    // A corrected sheet's summary.json whose rounds are not a list.
    std::fs::write(sheet.join("summary.json"), r#"{"rounds": 3}"#).unwrap();
    std::fs::write(sheet.join("track.json"), serde_json::to_string_pretty(&track).unwrap()).unwrap();
    let e = msg(ObservedRun::load(&obs, &['十', '口'], None).unwrap_err());
    assert!(e.contains("summary.json: field `rounds`: expected a list of rounds"), "{e}");
}
