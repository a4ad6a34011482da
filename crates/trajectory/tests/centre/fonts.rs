//! Fonts as users get them: every container format gives the glyph the TrueType file gives, a
//! collection's face is chosen by index, folders and lists of web-font subsets give the file
//! that covers the character, and bad files are clear errors, never panics.

use std::path::{Path, PathBuf};

use trajectory::{
    FontFormat, FontSet, Glyph, GlyphError, GlyphSource, Shape, glyph_from_font, glyph_from_font_files, mask_of,
    render_glyph, sfnt_from_bytes,
};

fn fonts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fonts")
}

const UKAI_CHARS: &str = "永字八法十口人丁山水";

fn outline(g: &Glyph) -> &kurbo::BezPath {
    match &g.shape {
        Shape::Outlines(o) => &o[0],
        Shape::Bitmap { .. } => panic!("a font gives outlines"),
    }
}

fn one(path: &Path, ch: char) -> Glyph {
    glyph_from_font(path, ch).unwrap_or_else(|e| panic!("{}: {ch}: {e}", path.display()))
}

fn source_path(g: &Glyph) -> (String, u32) {
    match &g.source {
        GlyphSource::Font { path, face_index } => (path.clone(), *face_index),
        s => panic!("not a font source: {s:?}"),
    }
}

#[test]
fn woff_and_woff2_give_the_truetype_outlines() {
    let ttf = fonts().join("ukai-subset.ttf");
    for ext in ["woff", "woff2"] {
        let web = fonts().join(format!("ukai-subset.{ext}"));
        for ch in UKAI_CHARS.chars() {
            let (a, b) = (one(&ttf, ch), one(&web, ch));
            assert!(!outline(&a).elements().is_empty());
            assert_eq!(outline(&a).elements(), outline(&b).elements(), "{ext}: {ch}");
            assert_eq!(source_path(&b), (web.display().to_string(), 0));
        }
    }
}

/// Intersection over union of two glyphs' masks at `px`², and the number of pixels where they
/// differ that are not on the edge of `a`'s ink (no ink and no background among their 3×3).
fn compare(a: &Glyph, b: &Glyph, px: u32) -> (f64, usize) {
    let (ma, mb) = (mask_of(&render_glyph(a, px)), mask_of(&render_glyph(b, px)));
    let inter = ma.iter().zip(&mb).filter(|(x, y)| **x && **y).count();
    let union = ma.iter().zip(&mb).filter(|(x, y)| **x || **y).count();
    let n = px as usize;
    let off_edge = (0..n * n)
        .filter(|&i| ma[i] != mb[i])
        .filter(|&i| {
            let (x, y) = (i % n, i / n);
            let around: Vec<bool> = (y.saturating_sub(1)..=(y + 1).min(n - 1))
                .flat_map(|yy| (x.saturating_sub(1)..=(x + 1).min(n - 1)).map(move |xx| yy * n + xx))
                .map(|j| ma[j])
                .collect();
            around.iter().all(|&v| v) || around.iter().all(|&v| !v)
        })
        .count();
    (inter as f64 / union.max(1) as f64, off_edge)
}

#[test]
fn cff_outlines_match_the_truetype_ones() {
    // The OTF holds the same glyphs as cubics rounded to font units: the same ink, up to pixels
    // on the outline's edge (the rasteriser flattens quadratics and cubics differently).
    let (ttf, otf) = (fonts().join("ukai-subset.ttf"), fonts().join("ukai-subset-cff.otf"));
    assert_eq!(
        FontFormat::sniff(&std::fs::read(&otf).unwrap()),
        Some(FontFormat::OpenTypeCff),
        "the fixture must be CFF-flavoured"
    );
    for ch in UKAI_CHARS.chars() {
        let (a, b) = (one(&ttf, ch), one(&otf, ch));
        assert!(outline(&b).elements().iter().any(|e| matches!(e, kurbo::PathEl::CurveTo(..))), "{ch}");
        let (iou, off_edge) = compare(&a, &b, 256);
        assert!(iou > 0.98 && off_edge == 0, "{ch}: IoU {iou}, {off_edge} pixels differ off the edge");
    }
    // A different glyph is not mistaken for the same one.
    let (iou, off_edge) = compare(&one(&ttf, '十'), &one(&otf, '丁'), 256);
    assert!(iou < 0.9 && off_edge > 0, "{iou} {off_edge}");
}

#[test]
fn a_collection_face_is_chosen_by_index() {
    let ttc = fonts().join("ukai-two-faces.ttc");
    let ttf = fonts().join("ukai-subset.ttf");
    let name = ttc.display().to_string();
    // Face 0 (the default) is ukai-subset.ttf.
    let g = one(&ttc, '永');
    assert_eq!(outline(&g).elements(), outline(&one(&ttf, '永')).elements());
    assert_eq!(source_path(&g), (name.clone(), 0));
    let g = glyph_from_font_files(std::slice::from_ref(&ttc), Some(0), '永').unwrap();
    assert_eq!(source_path(&g).1, 0);
    // Face 1 holds 中大小 only.
    let g = glyph_from_font_files(std::slice::from_ref(&ttc), Some(1), '中').unwrap();
    assert_eq!(source_path(&g), (name.clone(), 1));
    let e = glyph_from_font_files(std::slice::from_ref(&ttc), Some(1), '永').unwrap_err();
    assert!(matches!(e, GlyphError::Unknown { .. }), "{e}");
    assert!(e.to_string().contains("(face 1)") && e.to_string().contains(&name), "{e}");
    assert!(matches!(glyph_from_font_files(std::slice::from_ref(&ttc), None, '中'), Err(GlyphError::Unknown { .. })));
    // A face that is not there.
    let e = glyph_from_font_files(std::slice::from_ref(&ttc), Some(2), '永').unwrap_err().to_string();
    assert!(e.contains(&name) && e.contains("no face 2") && e.contains("2 faces (indices 0..=1)"), "{e}");
    // A single font has face 0 only.
    let e = glyph_from_font_files(&[ttf], Some(1), '永').unwrap_err().to_string();
    assert!(e.contains("ukai-subset.ttf") && e.contains("no face 1: the file has 1 face "), "{e}");
}

#[test]
fn the_file_that_covers_the_character_is_used() {
    let dir = fonts().join("msz");
    let set = FontSet::open(std::slice::from_ref(&dir), None).unwrap();
    // The folder's WOFF2 files in name order (LICENSE is not a font).
    let names: Vec<String> =
        set.files().iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(
        names,
        [
            "ma-shan-zheng-114-400-normal.woff2",
            "ma-shan-zheng-117-400-normal.woff2",
            "ma-shan-zheng-118-400-normal.woff2"
        ]
    );
    for (ch, file) in [('永', "114"), ('水', "117"), ('口', "117"), ('法', "118"), ('国', "118")] {
        let g = set.glyph(ch).unwrap_or_else(|e| panic!("{ch}: {e}"));
        let (path, face) = source_path(&g);
        assert!(path.ends_with(&format!("ma-shan-zheng-{file}-400-normal.woff2")), "{ch}: {path}");
        assert_eq!(face, 0);
        // Brush-written, so not UKai: but a real glyph with ink in the em box.
        let ink = mask_of(&render_glyph(&g, 128)).iter().filter(|&&b| b).count();
        assert!(ink > 128 * 128 / 20, "{ch}: {ink} ink pixels");
    }
    // Files listed one by one, in any order with a folder: the first covering file wins.
    let files = [fonts().join("ukai-subset.woff2"), dir.clone()];
    let g = glyph_from_font_files(&files, None, '永').unwrap();
    assert!(source_path(&g).0.ends_with("ukai-subset.woff2"));
    let g = glyph_from_font_files(&files, None, '国').unwrap();
    assert!(source_path(&g).0.ends_with("ma-shan-zheng-118-400-normal.woff2"));
}

#[test]
fn a_character_in_no_file_names_the_files() {
    let set = FontSet::open(&[fonts().join("msz"), fonts().join("ukai-subset.ttf")], None).unwrap();
    let e = set.glyph('龍').unwrap_err();
    assert!(matches!(e, GlyphError::Unknown { ch: '龍', .. }), "{e}");
    let e = e.to_string();
    assert!(e.contains("U+9F8D") && e.contains("4 font files tried, none of which covers it"), "{e}");
    for f in ["114", "117", "118"] {
        assert!(e.contains(&format!("ma-shan-zheng-{f}-400-normal.woff2")), "{e}");
    }
    assert!(e.contains("ukai-subset.ttf"), "{e}");
    // Folders without fonts, missing paths and an empty list are errors too.
    let empty = std::env::temp_dir().join(format!("maobi-nofonts-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::write(empty.join("README.txt"), "no fonts here").unwrap();
    let e = FontSet::open(std::slice::from_ref(&empty), None).unwrap_err();
    // The folder is the error, why is its source.
    let why = std::error::Error::source(&e).map(|s| s.to_string()).unwrap_or_default();
    assert!(e.to_string().contains("maobi-nofonts"), "{e}");
    assert!(why.contains("no font files") && why.contains(".woff2"), "{e}: {why}");
    std::fs::remove_dir_all(&empty).unwrap();
    let e = glyph_from_font_files(&[fonts().join("nope.ttf")], None, '永').unwrap_err().to_string();
    assert!(e.contains("nope.ttf"), "{e}");
    assert!(FontSet::open(&[], None).is_err());
}

#[test]
fn broken_web_fonts_are_clear_errors() {
    let name = Path::new("broken.woff2");
    for ext in ["woff", "woff2"] {
        let data = std::fs::read(fonts().join(format!("ukai-subset.{ext}"))).unwrap();
        // Every truncation is refused with the file's name, never a panic.
        for len in 0..data.len() {
            let e = sfnt_from_bytes(name, data[..len].to_vec()).unwrap_err().to_string();
            assert!(e.starts_with("broken.woff2: ") && (e.contains("WOFF") || e.contains("not a font")), "{len}: {e}");
        }
        // Flipped bytes: an error or a font, never a panic; a decoded font still parses safely.
        for at in (0..data.len()).step_by(7) {
            let mut d = data.clone();
            d[at] ^= 0x5a;
            if let Ok(sfnt) = sfnt_from_bytes(name, d)
                && let Ok(face) = ttf_parser::Face::parse(&sfnt, 0)
            {
                let _ = face.glyph_index('永');
            }
        }
    }
    let e = sfnt_from_bytes(name, b"wOF2 and then garbage".to_vec()).unwrap_err().to_string();
    assert!(e.contains("broken.woff2") && e.contains("not a valid WOFF2 file"), "{e}");
    let e = sfnt_from_bytes(name, b"<html>not a font</html>".to_vec()).unwrap_err().to_string();
    assert!(
        e.contains("not a font: expected a TrueType/OpenType font (.ttf, .otf)") && e.contains("3c 68 74 6d"),
        "{e}"
    );
    // A WOFF whose table claims an impossible size is refused before decoding.
    let mut d = std::fs::read(fonts().join("ukai-subset.woff")).unwrap();
    d[44 + 12..44 + 16].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
    let e = sfnt_from_bytes(name, d).unwrap_err().to_string();
    assert!(e.contains("not a valid WOFF file"), "{e}");
    // Through the file API, a garbage file is named.
    let bad = std::env::temp_dir().join(format!("maobi-bad-{}.woff2", std::process::id()));
    std::fs::write(&bad, b"wOF2\0\0\0\0").unwrap();
    let e = glyph_from_font(&bad, '永').unwrap_err().to_string();
    assert!(e.contains(&bad.display().to_string()) && e.contains("WOFF2"), "{e}");
    std::fs::remove_file(&bad).unwrap();
}
