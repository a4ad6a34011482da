//! A written sheet's folder read back as `maobi observe` reads it (`pipeline::SheetFolder`):
//! the marks it needs, the images' sizes checked from their headers, each character's frame.

use std::path::{Path, PathBuf};

use bezier_raster::Coverage;
use brush_model::BrushProfile;
use pipeline::{
    Flow, Grid, SheetFolder, SheetFolderError, SheetTrack, TextOptions, WriteOptions, layout_on_sheet, parse_sheet,
    prepare, registration_marks, write_text,
};

const SIDE: u32 = 64;

/// A sheet of two characters in `dir/sheet`: its track.json (with marks when asked) and no
/// images yet.
fn sheet(dir: &Path, marks: bool) -> (PathBuf, SheetTrack) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let lay = layout_on_sheet(&parse_sheet("A5").unwrap(), 2, Flow::Columns, Some(2), 15.0, Some(30.0)).unwrap();
    let prepared = "十口".chars().map(|c| prepare(trajectory::embedded_glyph(c).unwrap(), None).unwrap()).collect();
    let quick = WriteOptions { size: SIDE, free_widths: false, execute: false, ..WriteOptions::default() };
    let opts = TextOptions { layout: Some(lay.clone()), per_line: 2, ..TextOptions::default() };
    let w = write_text(prepared, &pen1, &quick, &opts, &|| {}).unwrap();
    let chars: Vec<_> =
        w.results.iter().map(|r| (r.report.char.clone(), r.char_box, r.track.strokes.as_slice())).collect();
    let mut track = SheetTrack::new(&w.layout, Flow::Columns, Grid::None, &chars, &pen1);
    if marks {
        track = track.with_marks(&registration_marks(&w.layout, &pen1).unwrap(), &pen1);
    }
    let dir = dir.join("sheet");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("track.json"), serde_json::to_string_pretty(&track).unwrap()).unwrap();
    (dir, track)
}

/// Blank `reference.png` and `render.png` of `side` px for every character, `odd` (a file
/// under the sheet) of another shape.
fn images(dir: &Path, side: u32, odd: Option<(&str, u32, u32)>) {
    for folder in ["01-十", "02-口"] {
        for f in ["reference.png", "render.png"] {
            let rel = format!("{folder}/{f}");
            let (w, h) = odd.filter(|o| o.0 == rel).map_or((side, side), |o| (o.1, o.2));
            std::fs::create_dir_all(dir.join(folder)).unwrap();
            std::fs::write(dir.join(&rel), Coverage::new(w, h).encode_png().unwrap()).unwrap();
        }
    }
}

#[test]
fn a_sheet_folder_gives_each_character_its_frame_and_inking_paths() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, track) = sheet(tmp.path(), true);
    images(&dir, SIDE, None);
    let folder = SheetFolder::load(&dir).unwrap();
    assert_eq!(folder.dir, std::fs::canonicalize(&dir).unwrap());
    assert_eq!(folder.marks.len(), track.marks.len());
    assert_eq!(folder.marks[0].role, "top-left");
    assert_eq!(folder.chars.len(), 2);
    for (c, planned) in track.chars.iter().zip(&folder.chars) {
        let [x0, y0, size] = c.char_box_mm;
        assert_eq!((planned.frame.x0_mm, planned.frame.y0_mm), (x0, y0));
        assert_eq!(planned.frame.width, SIDE);
        assert!((planned.frame.px_per_mm - SIDE as f64 / size).abs() < 1e-12);
        assert_eq!(planned.paths.len(), c.strokes[1] - c.strokes[0]);
        // Only the inking part: every point at least the shallowest calibrated press.
        let inking: usize = track.strokes[c.strokes[0]..c.strokes[1]]
            .iter()
            .map(|s| s.points.iter().filter(|p| p.h_mm >= track.brush.ranges.h_mm.min).count())
            .sum();
        assert_eq!(planned.paths.iter().map(Vec::len).sum::<usize>(), inking);
        let (reference, plan) = planned.images().unwrap();
        assert_eq!((reference.width(), plan.height()), (SIDE, SIDE));
    }
    assert_eq!(folder.chars[1].folder, "02-口");
}

#[test]
fn a_sheet_without_marks_or_with_odd_images_is_refused_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, _) = sheet(tmp.path(), false);
    images(&dir, SIDE, None);
    let e = SheetFolder::load(&dir).unwrap_err();
    assert!(matches!(e, SheetFolderError::NoMarks { .. }), "{e:?}");
    assert!(e.to_string().contains("track.json has no registration marks"), "{e}");

    let (dir, _) = sheet(tmp.path(), true);
    images(&dir, SIDE, Some(("02-口/render.png", 100, 80)));
    let e = SheetFolder::load(&dir).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "02-口/render.png is 100×80 px: expected a square of 64..=4096 px (a character image of the sheet)"
        ),
        "{e}"
    );

    images(&dir, SIDE, Some(("02-口/render.png", 96, 96)));
    let e = SheetFolder::load(&dir).unwrap_err().to_string();
    assert!(e.contains("02-口/render.png is not the size of") && e.contains("01-十/reference.png (64×64 px)"), "{e}");

    // Replaced after the headers were read: the decoded image is checked against the frame.
    images(&dir, SIDE, None);
    let folder = SheetFolder::load(&dir).unwrap();
    images(&dir, SIDE, Some(("01-十/render.png", 96, 96)));
    let e = folder.chars[0].images().unwrap_err().to_string();
    assert!(
        e.ends_with("render.png is 96×96 px, expected 64×64 px (the size of the sheet's first reference.png)"),
        "{e}"
    );
}
