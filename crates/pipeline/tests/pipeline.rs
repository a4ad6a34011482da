//! The pipeline through its public API: the files it gives robot-io, the sheet rules, the brush
//! verdict, and errors that name what is wrong without naming a flag.

use brush_model::BrushProfile;
use pipeline::{
    BoxRule, BrushFit, BrushMiss, Error, Flow, GlyphInput, TextOptions, WriteOptions, auto_layout, prepare, write_char,
    write_placed, write_text,
};
use trajectory::{Method, embedded_glyph};

fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

fn quick() -> WriteOptions {
    WriteOptions { size: 64, free_widths: false, execute: false, ..WriteOptions::default() }
}

#[test]
fn a_written_character_reads_back_through_robot_io_as_it_was_written() {
    let p = prepare(embedded_glyph('十').unwrap(), None).unwrap();
    let r = write_placed(&p, &pen1(), &quick(), BoxRule::Fixed(40.0)).unwrap();
    let file = r.track_file(&pen1(), Some([210.0, 297.0]));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("track.json");
    std::fs::write(&path, serde_json::to_string_pretty(&file).unwrap()).unwrap();
    let back = robot_io::TrackFile::load(&path).unwrap();
    assert_eq!(back.char.as_deref(), Some("十"));
    assert_eq!(back.char_box_mm, Some([0.0, 0.0, 40.0]));
    assert_eq!(back.sheet_mm, Some([210.0, 297.0]));
    assert_eq!(back.track(), r.track);
    assert_eq!(back.brush, pen1());
    // A single character has no stroke → character map.
    assert!(back.stroke_chars.is_none());
}

#[test]
fn write_text_writes_each_character_as_write_char_does_in_its_box() {
    let pen = pen1();
    let chars: Vec<_> = "十口".chars().map(|c| prepare(embedded_glyph(c).unwrap(), None).unwrap()).collect();
    let text = TextOptions { char_mm: Some(30.0), per_line: 1, flow: Flow::Rows, ..TextOptions::default() };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let w = write_text(chars.clone(), &pen, &quick(), &text, &|| {
        done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(done.into_inner(), 2);
    // Rows left to right, one per line: the second character below the first, same size.
    let b = &w.layout.boxes;
    assert_eq!((b[0].size_mm, b[1].size_mm), (30.0, 30.0));
    assert!(b[1].y0_mm > b[0].y0_mm && b[1].x0_mm == b[0].x0_mm, "{b:?}");
    for ((p, r), bx) in chars.iter().zip(&w.results).zip(b) {
        let alone = write_char(p, &pen, *bx, &quick()).unwrap();
        assert_eq!(alone.track, r.track);
        assert_eq!(alone.report.plan.csim, r.report.plan.csim);
    }
}

#[test]
fn the_automatic_layout_runs_columns_right_to_left_and_refuses_an_oversized_image() {
    let l = auto_layout(5, 20.0, 4, Flow::Columns);
    assert_eq!((l.per_line, l.lines), (4, 2));
    // The first column is on the right, read top to bottom.
    assert!(l.boxes[0].x0_mm > l.boxes[4].x0_mm);
    assert!(l.boxes[1].y0_mm > l.boxes[0].y0_mm);
    assert!(l.sheet.width_mm > 2.0 * 20.0 && l.sheet.height_mm > 4.0 * 20.0);
    assert!(l.check_image_size(64).is_ok());
    let e = l.check_image_size(4096).unwrap_err().to_string();
    assert!(e.contains("px") && !e.contains("--"), "{e}");
}

#[test]
fn the_brush_verdict_says_which_way_the_brush_misses() {
    let pen = pen1();
    let p = prepare(embedded_glyph('永').unwrap(), Some(Method::Medians)).unwrap();
    let auto = trajectory::auto_char_mm(&p.paths, &pen, 0.0);
    let at = |mm: f64| {
        let r = write_placed(&p, &pen, &quick(), BoxRule::Fixed(mm)).unwrap().report;
        BrushFit::of(&[&r], mm, auto)
    };
    let fits = at(auto);
    assert!(fits.covered && fits.miss.is_none(), "{fits:?}");
    let small = at(auto / 2.0);
    assert_eq!(small.miss, Some(BrushMiss::TooWide), "{small:?}");
    assert!(small.clamped_thin > small.clamped_wide, "{small:?}");
    let large = at(auto * 2.0);
    assert_eq!(large.miss, Some(BrushMiss::TooNarrow), "{large:?}");
}

#[test]
fn a_blank_photo_is_refused_naming_the_file_and_no_flag() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blank.png");
    std::fs::write(&path, bezier_raster::Coverage::new(96, 96).encode_png().unwrap()).unwrap();
    let input = GlyphInput::Images(vec![('永', path.clone())], None);
    let e = input.prepare('永', None).unwrap_err();
    let text = format!("{e}");
    assert!(text.contains("blank.png"), "{text}");
    assert!(!text.contains("--"), "{text}");
    // A character the images do not cover is its own error.
    assert!(matches!(input.load('十'), Err(Error::NoImage('十'))));
}

#[test]
fn an_image_folder_lists_one_character_images_and_refuses_others() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["永.png", "十.JPG", "notes.txt", "口.jpeg"] {
        std::fs::write(dir.path().join(name), b"").unwrap();
    }
    let found: String = pipeline::image_folder(dir.path()).unwrap().iter().map(|(c, _)| *c).collect();
    assert_eq!(found, "十口永");
    std::fs::write(dir.path().join("永字.png"), b"").unwrap();
    let e = pipeline::image_folder(dir.path()).unwrap_err().to_string();
    assert!(e.contains("永字.png") && e.contains("named after its one character"), "{e}");
    let empty = tempfile::tempdir().unwrap();
    let e = pipeline::image_folder(empty.path()).unwrap_err().to_string();
    assert!(e.contains("no <char>.png"), "{e}");
    let e = pipeline::image_folder(&empty.path().join("missing")).unwrap_err();
    assert!(e.to_string().contains("cannot read the folder") && std::error::Error::source(&e).is_some());
}
