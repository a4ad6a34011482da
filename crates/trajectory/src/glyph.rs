//! Glyph sources: hanzi-writer-data JSON (embedded subset or a folder), CJK fonts, and images.
//!
//! Every glyph lives in the **em frame**: the 1024-unit box of Make Me a Hanzi with y flipped to
//! point down, so `x' = x`, `y' = 900 − y` (docs/contracts.md §2). The em box is `[0, 1024]²` in `(x', y')`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use kurbo::{BezPath, Point};
use serde::Deserialize;
use thiserror::Error;

mod bitmap;
pub use bitmap::glyph_from_gray;
pub mod font;
pub use font::{FontSet, from_font_files};

/// Side of the em box, em units.
pub const EM: f64 = 1024.0;
/// The original data's top edge: `y' = EM_TOP − y`.
pub const EM_TOP: f64 = 900.0;

/// Input bounds on glyph data, checked before anything is built from it. Real
/// hanzi-writer-data stays inside the em box; these leave a full em of margin on every side and
/// room for ten times the most detailed character, while keeping every raster and every loop
/// over points bounded.
pub mod limits {
    /// Coordinates (em units, either frame) must lie in `[MIN_COORD, MAX_COORD]`.
    pub const MIN_COORD: f64 = -1024.0;
    /// See [`MIN_COORD`].
    pub const MAX_COORD: f64 = 2048.0;
    /// Strokes per character (the most complex characters have about 60).
    pub const MAX_STROKES: usize = 128;
    /// Points per median (hanzi-writer-data uses 2–20).
    pub const MAX_MEDIAN_POINTS: usize = 1000;
    /// Path elements per stroke outline (hanzi-writer-data uses about 10–60).
    pub const MAX_PATH_ELEMENTS: usize = 4096;
    /// Bytes of one stroke's SVG path string.
    pub const MAX_SVG_BYTES: usize = 64 << 10;
    /// The largest magnitude of any number in an SVG path string, checked *before* kurbo parses
    /// it: an arc's radius of 1e66 made kurbo's arc-to-cubic conversion allocate gigabytes
    /// (found by the `svg_path` fuzz target), and relative coordinates add up.
    pub const MAX_SVG_NUMBER: f64 = 100_000.0;
    /// Bytes of one hanzi-writer-data file (the largest real file is about 10 KB).
    pub const MAX_JSON_BYTES: u64 = 1 << 20;
    /// Bytes of a font file (a full CJK font is 10–40 MB).
    pub const MAX_FONT_BYTES: u64 = 256 << 20;
}

/// A coordinate for a message: plain when short, exponent form when huge or tiny.
fn num(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e7).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}

/// The first number in an SVG path string (SVG number grammar) whose magnitude exceeds
/// [`limits::MAX_SVG_NUMBER`] or is not finite, if any. Linear in the string's length.
fn svg_number_too_large(s: &str) -> Option<&str> {
    let b = s.as_bytes();
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if !(c.is_ascii_digit() || c == b'.' || c == b'-' || c == b'+') {
            i += 1;
            continue;
        }
        let start = i;
        if c == b'-' || c == b'+' {
            i += 1;
        }
        i = digits(i);
        if i < b.len() && b[i] == b'.' {
            i = digits(i + 1);
        }
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            let mut j = i + 1;
            if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
                j += 1;
            }
            let k = digits(j);
            if k > j {
                i = k;
            }
        }
        let i_next = i.max(start + 1);
        let tok = &s[start..i_next];
        if let Ok(v) = tok.parse::<f64>()
            && (v.is_nan() || v.abs() > limits::MAX_SVG_NUMBER)
        {
            return Some(tok);
        }
        i = i_next;
    }
    None
}

/// Whether a point lies inside the accepted coordinate window.
fn in_window(p: Point) -> bool {
    (limits::MIN_COORD..=limits::MAX_COORD).contains(&p.x) && (limits::MIN_COORD..=limits::MAX_COORD).contains(&p.y)
}

/// The first point of a path outside the window, if any.
fn path_outside(p: &BezPath) -> Option<Point> {
    p.elements()
        .iter()
        .flat_map(|el| match *el {
            kurbo::PathEl::MoveTo(a) | kurbo::PathEl::LineTo(a) => vec![a],
            kurbo::PathEl::QuadTo(a, b) => vec![a, b],
            kurbo::PathEl::CurveTo(a, b, c) => vec![a, b, c],
            kurbo::PathEl::ClosePath => vec![],
        })
        .find(|&q| !in_window(q))
}

/// The embedded hanzi-writer-data subset: one minified JSON object per line.
pub static EMBEDDED_SUBSET: &str = include_str!("../data/hanzi-subset.jsonl");
/// The Arphic Public License the embedded subset is distributed under.
pub static ARPHIC_LICENSE: &str = include_str!("../data/ARPHICPL.TXT");

/// Errors from loading glyphs.
#[derive(Clone, Debug, Error)]
pub enum GlyphError {
    /// The character is not in the source.
    #[error("character {ch:?} (U+{code:04X}) is not in {source_name}")]
    Unknown {
        /// The character.
        ch: char,
        /// Its code point.
        code: u32,
        /// Which source was searched.
        source_name: String,
    },
    /// A file or folder could not be read (or is not what was asked for: a folder where a
    /// file was expected, a folder without fonts; the source says which).
    #[error("{}: cannot read", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why (shared, so the error stays `Clone`).
        #[source]
        source: Arc<std::io::Error>,
    },
    /// An image file could not be opened or decoded.
    #[error("{}: cannot read image", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// Why (missing, empty, too large, not an image).
        #[source]
        source: Arc<bezier_raster::ImageFileError>,
    },
    /// The data is malformed.
    #[error("{source_name}: {message}")]
    Malformed {
        /// File or source.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// An image holds no usable glyph.
    #[error("{}: {message}", path.display())]
    BadImage {
        /// The file (or the label an in-memory image was given).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl GlyphError {
    /// [`GlyphError::Io`] for `path`.
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        GlyphError::Io { path: path.to_path_buf(), source: Arc::new(source) }
    }
}

/// Where a glyph came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GlyphSource {
    /// The subset compiled into this crate.
    Embedded,
    /// A hanzi-writer-data folder.
    HanziData(String),
    /// A font file: the file the glyph was taken from and the face in it (0 unless the file is
    /// a collection).
    Font {
        /// The file.
        path: String,
        /// The face index in the file.
        face_index: u32,
    },
    /// An image file.
    Image(String),
}

impl GlyphSource {
    /// A short label for reports: `embedded`, `hanzi-data`, `font` or `image`.
    pub fn kind(&self) -> &'static str {
        match self {
            GlyphSource::Embedded => "embedded",
            GlyphSource::HanziData(_) => "hanzi-data",
            GlyphSource::Font { .. } => "font",
            GlyphSource::Image(_) => "image",
        }
    }
}

/// The shape of a glyph in the em frame.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Filled outlines (nonzero rule each), one per stroke for hanzi data, one in all for a font.
    Outlines(Vec<BezPath>),
    /// A bitmap whose `size × size` pixels cover the em box, ink = 1.
    Bitmap {
        /// Side, px.
        size: u32,
        /// Values, row-major.
        ink: Vec<f32>,
    },
}

/// A character's glyph.
#[derive(Clone, Debug)]
pub struct Glyph {
    /// The character.
    pub ch: char,
    /// Where it came from.
    pub source: GlyphSource,
    /// Its shape.
    pub shape: Shape,
    /// Stroke outlines in writing order, when the source has them (hanzi data).
    pub stroke_outlines: Option<Vec<BezPath>>,
    /// Stroke centre lines in writing order (em frame), when the source has them.
    pub medians: Option<Vec<Vec<Point>>>,
}

#[derive(Deserialize)]
struct HanziJson {
    strokes: Vec<String>,
    medians: Vec<Vec<[f64; 2]>>,
}

fn flip(p: Point) -> Point {
    Point::new(p.x, EM_TOP - p.y)
}

/// Parses one hanzi-writer-data character file (`{"strokes": [...], "medians": [...]}`).
///
/// # Errors
/// [`GlyphError::Malformed`] naming `source_name` and the stroke at fault.
pub fn parse_hanzi_json(ch: char, text: &str, source: GlyphSource, source_name: &str) -> Result<Glyph, GlyphError> {
    let bad = |message: String| GlyphError::Malformed { source_name: source_name.to_string(), message };
    if text.len() as u64 > limits::MAX_JSON_BYTES {
        return Err(bad(format!("{} bytes; a character file is at most {} bytes", text.len(), limits::MAX_JSON_BYTES)));
    }
    let j: HanziJson = serde_json::from_str(text).map_err(|e| bad(format!("not hanzi-writer data: {e}")))?;
    if j.strokes.is_empty() || j.strokes.len() != j.medians.len() {
        return Err(bad(format!("{} strokes but {} medians", j.strokes.len(), j.medians.len())));
    }
    if j.strokes.len() > limits::MAX_STROKES {
        return Err(bad(format!("{} strokes; at most {}", j.strokes.len(), limits::MAX_STROKES)));
    }
    let outlines = j.strokes.iter().enumerate().map(|(i, s)| stroke_outline(i + 1, s).map_err(bad));
    let outlines: Vec<BezPath> = outlines.collect::<Result<_, _>>()?;
    let medians = j.medians.iter().enumerate().map(|(i, m)| median(i + 1, m).map_err(bad));
    let medians: Vec<Vec<Point>> = medians.collect::<Result<_, _>>()?;
    Ok(Glyph {
        ch,
        source,
        shape: Shape::Outlines(outlines.clone()),
        stroke_outlines: Some(outlines),
        medians: Some(medians),
    })
}

/// Stroke `k` (1-based) of a hanzi-writer file: its SVG outline, bounded before parsing and
/// checked after, flipped into the em frame (y down). `Err` is the message.
fn stroke_outline(k: usize, s: &str) -> Result<BezPath, String> {
    let (lo, hi) = (limits::MIN_COORD, limits::MAX_COORD);
    if s.len() > limits::MAX_SVG_BYTES {
        return Err(format!("stroke {k}: SVG path of {} bytes; at most {}", s.len(), limits::MAX_SVG_BYTES));
    }
    if let Some(tok) = svg_number_too_large(s) {
        let tok: String = tok.chars().take(40).collect();
        return Err(format!(
            "stroke {k}: SVG path number {tok} is beyond ±{} (the em box is 0..=1024)",
            limits::MAX_SVG_NUMBER
        ));
    }
    let mut p = BezPath::from_svg(s).map_err(|e| format!("stroke {k}: bad SVG path: {e}"))?;
    if p.elements().len() > limits::MAX_PATH_ELEMENTS {
        return Err(format!("stroke {k}: {} path elements; at most {}", p.elements().len(), limits::MAX_PATH_ELEMENTS));
    }
    if let Some(q) = path_outside(&p) {
        return Err(format!(
            "stroke {k}: point ({}, {}) outside the accepted coordinates {lo}..={hi} (the em box is 0..=1024)",
            num(q.x),
            num(q.y)
        ));
    }
    p.apply_affine(kurbo::Affine::new([1.0, 0.0, 0.0, -1.0, 0.0, EM_TOP]));
    Ok(p)
}

/// Median `k` (1-based) of a hanzi-writer file, checked and flipped into the em frame. `Err` is
/// the message.
fn median(k: usize, m: &[[f64; 2]]) -> Result<Vec<Point>, String> {
    let (lo, hi) = (limits::MIN_COORD, limits::MAX_COORD);
    if m.is_empty() || m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("median {k} is empty or not finite"));
    }
    if m.len() > limits::MAX_MEDIAN_POINTS {
        return Err(format!("median {k}: {} points; at most {}", m.len(), limits::MAX_MEDIAN_POINTS));
    }
    if let Some([x, y]) = m.iter().find(|&&[x, y]| !in_window(Point::new(x, y))) {
        return Err(format!(
            "median {k}: point ({}, {}) outside the accepted coordinates {lo}..={hi} (the em box is 0..=1024)",
            num(*x),
            num(*y)
        ));
    }
    Ok(m.iter().map(|&[x, y]| flip(Point::new(x, y))).collect())
}

fn embedded_index() -> &'static HashMap<char, &'static str> {
    static INDEX: OnceLock<HashMap<char, &'static str>> = OnceLock::new();
    INDEX.get_or_init(|| {
        EMBEDDED_SUBSET
            .lines()
            .filter_map(|l| {
                // Each line starts with {"c":"X", ...
                let rest = l.strip_prefix("{\"c\":\"")?;
                Some((rest.chars().next()?, l))
            })
            .collect()
    })
}

/// The characters of the embedded subset, in the order of the frequency list.
pub fn embedded_chars() -> Vec<char> {
    EMBEDDED_SUBSET.lines().filter_map(|l| l.strip_prefix("{\"c\":\"")?.chars().next()).collect()
}

/// A glyph from the embedded hanzi-writer-data subset.
///
/// # Errors
/// [`GlyphError::Unknown`] if the character is not in the subset.
pub fn embedded(ch: char) -> Result<Glyph, GlyphError> {
    let line = embedded_index().get(&ch).ok_or(GlyphError::Unknown {
        ch,
        code: ch as u32,
        source_name: "the embedded subset (use --hanzi-data DIR for the full set)".into(),
    })?;
    parse_hanzi_json(ch, line, GlyphSource::Embedded, "embedded subset")
}

/// A glyph from an unpacked hanzi-writer-data folder (files `<char>.json`).
///
/// # Errors
/// [`GlyphError::Unknown`] if there is no file for the character; [`GlyphError::Malformed`].
pub fn from_hanzi_dir(dir: &Path, ch: char) -> Result<Glyph, GlyphError> {
    if !dir.is_dir() {
        return Err(GlyphError::io(dir, std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a folder")));
    }
    let path = dir.join(format!("{ch}.json"));
    let unknown = || GlyphError::Unknown { ch, code: ch as u32, source_name: dir.display().to_string() };
    let len = std::fs::metadata(&path).map_err(|_| unknown())?.len();
    if len > limits::MAX_JSON_BYTES {
        return Err(GlyphError::Malformed {
            source_name: path.display().to_string(),
            message: format!("{len} bytes; a character file is at most {} bytes", limits::MAX_JSON_BYTES),
        });
    }
    let text = std::fs::read_to_string(&path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => unknown(),
        _ => GlyphError::io(&path, e),
    })?;
    parse_hanzi_json(ch, &text, GlyphSource::HanziData(dir.display().to_string()), &path.display().to_string())
}

/// A glyph from one font file: TrueType/OpenType (`.ttf`, `.otf`), the first face of a
/// collection (`.ttc`, `.otc`), WOFF or WOFF2 (see [`font`]). Font units are scaled so the em is
/// 1024 units with the baseline at `y = 0` of the original frame (so the ideographic em box,
/// from about −0.12 em to 0.88 em, lands on the 1024 box like hanzi-writer-data). No medians.
/// For several files, folders or another face, see [`from_font_files`] and [`FontSet`].
///
/// # Errors
/// [`GlyphError::Io`], [`GlyphError::Malformed`] (not a font, a web font that does not decode,
/// a glyph beyond [`limits`]), [`GlyphError::Unknown`].
pub fn from_font(path: &Path, ch: char) -> Result<Glyph, GlyphError> {
    if path.is_dir() {
        let e = std::io::Error::new(std::io::ErrorKind::InvalidInput, "a folder, not a font file");
        return Err(GlyphError::io(path, e));
    }
    from_font_files(&[path.to_path_buf()], None, ch)
}

/// A glyph from a photo or scan of one character (dark ink on light paper): Otsu threshold,
/// specks removed, padded to a square whose sides are the em box.
///
/// # Errors
/// [`GlyphError::Io`] for unreadable files, [`GlyphError::BadImage`] for an image with no ink
/// or nothing but ink.
pub fn from_image(path: &Path, ch: char) -> Result<Glyph, GlyphError> {
    let (size, ink) = bitmap::load_clean(path)?;
    Ok(Glyph {
        ch,
        source: GlyphSource::Image(path.display().to_string()),
        shape: Shape::Bitmap { size, ink },
        stroke_outlines: None,
        medians: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(path: &str) -> Result<Glyph, GlyphError> {
        let doc = serde_json::json!({"strokes": [path], "medians": [[[100, 400], [900, 400]]]}).to_string();
        parse_hanzi_json('一', &doc, GlyphSource::Embedded, "t.json")
    }

    #[test]
    fn svg_numbers_are_bounded_before_parsing() {
        // The fuzz find (fuzz/artifacts/svg_path/oom-509c…): an arc to x = 1.1e66 made kurbo
        // build billions of cubics. Now refused from the text, in no time.
        let arc = format!("M 541 410 A 37 9 9 0 0 {} 0 Z", "1".repeat(67));
        let e = parse(&arc).unwrap_err().to_string();
        assert!(e.contains("stroke 1: SVG path number 1111") && e.contains("beyond ±100000"), "{e}");
        for bad in ["M 0 0 L 1e300 0 Z", "M 0 0 L 1e400 0", "M 0 0 l -2e5 0", "M0,0L5E+06,1"] {
            assert!(parse(bad).unwrap_err().to_string().contains("SVG path number"), "{bad}");
        }
        // Ordinary paths, packed numbers and exponents within range pass.
        for good in ["M 100 100 L 900 100 L 900 200 Z", "M 100 100.5 L 1e2 2E+2 Z", "M 10 10 A 5 5 0 0 1 20 20 Z"] {
            let g = parse(good).unwrap_or_else(|e| panic!("{good}: {e}"));
            assert_eq!(g.stroke_outlines.unwrap().len(), 1);
        }
        assert!(parse(&"L 1 1 ".repeat(20_000)).unwrap_err().to_string().contains("bytes; at most"));
    }
}
