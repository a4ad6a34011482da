//! Glyph sources: hanzi-writer-data (embedded, packed; or a folder of JSON files), CJK fonts,
//! and images.
//!
//! Every glyph lives in the **em frame**: the 1024-unit box of Make Me a Hanzi with y flipped to
//! point down, so `x' = x`, `y' = 900 − y` (docs/contracts.md §2). The em box is `[0, 1024]²` in `(x', y')`.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use kurbo::{BezPath, Point};
use serde::Deserialize;
use thiserror::Error;

mod bitmap;
pub use bitmap::glyph_from_gray;
mod font;
pub use font::{FONT_EXTENSIONS, FontFormat, FontSet, font_files, glyph_from_font_files, read_sfnt, sfnt_from_bytes};
mod packed;

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

/// The embedded hanzi-writer-data: every character of the package, packed and compressed in
/// chunks (read through [`embedded_glyph`]; the format is in docs/trajectory.md).
static EMBEDDED_BLOB: &[u8] = include_bytes!("../data/hanzi.bin");
/// The Arphic Public License the embedded data is distributed under.
pub static ARPHIC_LICENSE: &str = include_str!("../data/ARPHICPL.TXT");
/// What the embedded data is, for messages and reports.
pub const EMBEDDED_NAME: &str = "the embedded hanzi-writer-data 2.0.1";

/// Errors from loading glyphs.
#[derive(Clone, Debug, Error)]
pub enum GlyphError {
    /// No source that was tried covers the character.
    #[error("character {ch:?} (U+{code:04X}) is not in {}", tried.join(", nor in "))]
    Unknown {
        /// The character.
        ch: char,
        /// Its code point.
        code: u32,
        /// The sources searched, each described for a reader (`the embedded hanzi-writer-data
        /// 2.0.1 (9574 characters)`, a folder, the font files).
        tried: Vec<String>,
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
    /// The hanzi-writer-data compiled into this crate ([`embedded_glyph`]).
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

/// A character's hanzi-writer data as the file has it (y up), checked against [`limits`]:
/// what both the JSON and the packed embedded data decode to before the flip into the em frame.
pub(crate) struct RawHanzi {
    /// Stroke outlines, in writing order.
    pub(crate) outlines: Vec<BezPath>,
    /// Stroke medians, in writing order.
    pub(crate) medians: Vec<Vec<[f64; 2]>>,
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
    Ok(raw_hanzi_json(text, source_name)?.into_glyph(ch, source))
}

/// [`parse_hanzi_json`] up to the flip.
fn raw_hanzi_json(text: &str, source_name: &str) -> Result<RawHanzi, GlyphError> {
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
    for (i, m) in j.medians.iter().enumerate() {
        check_median(i + 1, m).map_err(bad)?;
    }
    Ok(RawHanzi { outlines, medians: j.medians })
}

impl RawHanzi {
    /// The checks [`raw_hanzi_json`] makes after parsing, for data from elsewhere.
    fn check(&self) -> Result<(), String> {
        if self.outlines.is_empty() || self.outlines.len() != self.medians.len() {
            return Err(format!("{} strokes but {} medians", self.outlines.len(), self.medians.len()));
        }
        for (i, p) in self.outlines.iter().enumerate() {
            if let Some(q) = path_outside(p) {
                let (lo, hi) = (limits::MIN_COORD, limits::MAX_COORD);
                return Err(format!(
                    "stroke {}: point ({}, {}) outside the accepted coordinates {lo}..={hi}",
                    i + 1,
                    num(q.x),
                    num(q.y)
                ));
            }
        }
        self.medians.iter().enumerate().try_for_each(|(i, m)| check_median(i + 1, m))
    }

    /// The glyph in the em frame: outlines and medians flipped (y down).
    fn into_glyph(self, ch: char, source: GlyphSource) -> Glyph {
        let outlines: Vec<BezPath> = self
            .outlines
            .into_iter()
            .map(|mut p| {
                p.apply_affine(kurbo::Affine::new([1.0, 0.0, 0.0, -1.0, 0.0, EM_TOP]));
                p
            })
            .collect();
        let medians = self.medians.iter().map(|m| m.iter().map(|&[x, y]| flip(Point::new(x, y))).collect()).collect();
        Glyph {
            ch,
            source,
            shape: Shape::Outlines(outlines.clone()),
            stroke_outlines: Some(outlines),
            medians: Some(medians),
        }
    }
}

/// Stroke `k` (1-based) of a hanzi-writer file: its SVG outline, bounded before parsing and
/// checked after, in the file's frame (y up). `Err` is the message.
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
    let p = BezPath::from_svg(s).map_err(|e| format!("stroke {k}: bad SVG path: {e}"))?;
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
    Ok(p)
}

/// Checks median `k` (1-based) of a hanzi-writer file. `Err` is the message.
fn check_median(k: usize, m: &[[f64; 2]]) -> Result<(), String> {
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
    Ok(())
}

/// The embedded blob's index, read once.
fn embedded_blob() -> Result<&'static packed::Blob<'static>, GlyphError> {
    static BLOB: OnceLock<Result<packed::Blob<'static>, String>> = OnceLock::new();
    BLOB.get_or_init(|| packed::Blob::open(EMBEDDED_BLOB))
        .as_ref()
        .map_err(|message| GlyphError::Malformed { source_name: EMBEDDED_NAME.into(), message: message.clone() })
}

/// The embedded data's description for [`GlyphError::Unknown`]: its name and size.
fn embedded_label() -> String {
    let n = embedded_blob().map_or(0, |b| b.len());
    format!("{EMBEDDED_NAME} ({n} characters)")
}

/// The characters of the frequency subset: the 1,000 most frequent characters, then the test
/// set, in that order. The default set for evaluations (every one is in the embedded data).
pub fn embedded_chars() -> Vec<char> {
    embedded_blob().map(|b| b.subset()).unwrap_or_default()
}

/// Every character of the embedded data, in code-point order.
pub fn embedded_all_chars() -> Vec<char> {
    embedded_blob().map(|b| b.chars()).unwrap_or_default()
}

/// A glyph from the hanzi-writer-data compiled into this crate (every character of the npm
/// package hanzi-writer-data 2.0.1, about 9,500). One call inflates one chunk of 64
/// characters; nothing is cached.
///
/// # Examples
/// ```
/// let g = trajectory::embedded_glyph('龍')?;
/// assert_eq!(g.medians.as_ref().map(Vec::len), Some(16));
/// # Ok::<(), trajectory::GlyphError>(())
/// ```
///
/// # Errors
/// [`GlyphError::Unknown`] if the character is not in the data; [`GlyphError::Malformed`] if
/// the compiled-in data is damaged (it never is in a released build: a test decodes all of it).
pub fn embedded_glyph(ch: char) -> Result<Glyph, GlyphError> {
    let blob = embedded_blob()?;
    let bad = |message: String| GlyphError::Malformed { source_name: format!("{EMBEDDED_NAME}, {ch:?}"), message };
    let raw = blob.get(ch).map_err(bad)?.ok_or_else(|| GlyphError::Unknown {
        ch,
        code: ch as u32,
        tried: vec![embedded_label()],
    })?;
    raw.check().map_err(bad)?;
    Ok(raw.into_glyph(ch, GlyphSource::Embedded))
}

/// Checks the whole embedded data: its hash, its index, and that every character decodes and
/// passes the checks JSON data gets. Returns the number of characters. For `cargo xtask
/// fixtures --check`, which cannot regenerate the data offline.
///
/// # Errors
/// [`GlyphError::Malformed`] saying what is wrong.
pub fn verify_embedded() -> Result<usize, GlyphError> {
    let blob = embedded_blob()?;
    let mut n = 0;
    blob.verify(|ch, raw| {
        raw.check().map_err(|e| format!("{ch:?}: {e}"))?;
        n += 1;
        Ok(())
    })
    .map_err(|message| GlyphError::Malformed { source_name: EMBEDDED_NAME.into(), message })?;
    Ok(n)
}

/// Packs hanzi-writer-data character files into the embedded data's format (what
/// `data/hanzi.bin` holds): `files` are `(character, JSON text)`, in any order; `subset` is the
/// frequency subset [`embedded_chars`] returns, in order. Deterministic: the same input gives
/// the same bytes.
///
/// # Errors
/// [`GlyphError::Malformed`] for a file that does not parse (as [`parse_hanzi_json`]), a
/// character given twice, or a subset character without a file.
pub fn pack_hanzi(files: &[(char, String)], subset: &[char]) -> Result<Vec<u8>, GlyphError> {
    let raws = files
        .iter()
        .map(|(c, text)| Ok((*c, raw_hanzi_json(text, &format!("{c}.json"))?)))
        .collect::<Result<Vec<_>, GlyphError>>()?;
    packed::pack(&raws, subset).map_err(|message| GlyphError::Malformed { source_name: "hanzi pack".into(), message })
}

/// The folders a hanzi-writer-data folder may hold its character files in, in the order they
/// are searched: the folder itself, then `package/` (what `npm pack hanzi-writer-data` unpacks
/// to), `data/` (the git repository's layout) and `package/data/`.
pub const HANZI_SUBFOLDERS: [&str; 4] = ["", "package", "data", "package/data"];

/// A glyph from a hanzi-writer-data folder (files `<char>.json`): the folder itself or, when it
/// has no file for the character, its `package/`, `data/` or `package/data/` subfolder (see
/// [`HANZI_SUBFOLDERS`]), so the folder `npm pack` unpacked into works as well as its
/// `package/` folder. The glyph's source names the folder the file was found in.
///
/// # Errors
/// [`GlyphError::Io`] if `dir` is not a folder; [`GlyphError::Unknown`] naming the folders
/// searched if none has a file for the character; [`GlyphError::Malformed`].
pub fn glyph_from_hanzi_dir(dir: &Path, ch: char) -> Result<Glyph, GlyphError> {
    if !dir.is_dir() {
        return Err(GlyphError::io(dir, std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a folder")));
    }
    let mut tried = Vec::new();
    for sub in HANZI_SUBFOLDERS {
        let folder = if sub.is_empty() { dir.to_path_buf() } else { dir.join(sub) };
        if !folder.is_dir() {
            continue;
        }
        let path = folder.join(format!("{ch}.json"));
        tried.push(format!("the hanzi-writer-data folder {}", folder.display()));
        let Ok(meta) = std::fs::metadata(&path) else { continue };
        let len = meta.len();
        if len > limits::MAX_JSON_BYTES {
            return Err(GlyphError::Malformed {
                source_name: path.display().to_string(),
                message: format!("{len} bytes; a character file is at most {} bytes", limits::MAX_JSON_BYTES),
            });
        }
        let too_large = || GlyphError::Malformed {
            source_name: path.display().to_string(),
            message: format!("a character file is at most {} bytes", limits::MAX_JSON_BYTES),
        };
        let bytes = match brush_model::read_regular(&path, limits::MAX_JSON_BYTES) {
            Ok(b) => b.ok_or_else(too_large)?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(GlyphError::io(&path, e)),
        };
        let text = String::from_utf8(bytes).map_err(|e| {
            GlyphError::io(&path, std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
        })?;
        let source = GlyphSource::HanziData(folder.display().to_string());
        return parse_hanzi_json(ch, &text, source, &path.display().to_string());
    }
    Err(GlyphError::Unknown { ch, code: ch as u32, tried })
}

/// A glyph from one font file: TrueType/OpenType (`.ttf`, `.otf`), the first face of a
/// collection (`.ttc`, `.otc`), WOFF or WOFF2 (see [`FontSet`]). Font units are scaled so the em is
/// 1024 units with the baseline at `y = 0` of the original frame (so the ideographic em box,
/// from about −0.12 em to 0.88 em, lands on the 1024 box like hanzi-writer-data). No medians.
/// For several files, folders or another face, see [`glyph_from_font_files`] and [`FontSet`].
///
/// # Errors
/// [`GlyphError::Io`], [`GlyphError::Malformed`] (not a font, a web font that does not decode,
/// a glyph beyond [`limits`]), [`GlyphError::Unknown`].
pub fn glyph_from_font(path: &Path, ch: char) -> Result<Glyph, GlyphError> {
    if path.is_dir() {
        let e = std::io::Error::new(std::io::ErrorKind::InvalidInput, "a folder, not a font file");
        return Err(GlyphError::io(path, e));
    }
    glyph_from_font_files(&[path.to_path_buf()], None, ch)
}

/// A glyph from a photo or scan of one character (dark ink on light paper): Otsu threshold,
/// specks removed, padded to a square whose sides are the em box.
///
/// # Errors
/// [`GlyphError::Io`] for unreadable files, [`GlyphError::BadImage`] for an image with no ink
/// or nothing but ink.
pub fn glyph_from_image(path: &Path, ch: char) -> Result<Glyph, GlyphError> {
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

    /// The frequency subset as JSON lines (`{"c":"永","strokes":[...],"medians":[...]}`), the
    /// fixture the packed data is checked against.
    fn subset_json() -> String {
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/hanzi-subset.jsonl")).unwrap()
    }

    /// Every number's bits and every element's kind of a glyph, so that "equal" means
    /// bit-identical (-0.0 and 0.0 differ).
    fn glyph_bits(g: &Glyph) -> (char, GlyphSource, Vec<u64>) {
        let mut v = Vec::new();
        let paths = |v: &mut Vec<u64>, ps: &[BezPath]| {
            v.push(ps.len() as u64);
            for el in ps.iter().flat_map(|p| p.elements()) {
                let (kind, pts) = match *el {
                    kurbo::PathEl::MoveTo(a) => (0, vec![a]),
                    kurbo::PathEl::LineTo(a) => (1, vec![a]),
                    kurbo::PathEl::QuadTo(a, b) => (2, vec![a, b]),
                    kurbo::PathEl::CurveTo(a, b, c) => (3, vec![a, b, c]),
                    kurbo::PathEl::ClosePath => (4, vec![]),
                };
                v.push(kind);
                v.extend(pts.iter().flat_map(|q| [q.x.to_bits(), q.y.to_bits()]));
            }
        };
        let Shape::Outlines(shape) = &g.shape else { panic!("hanzi data gives outlines") };
        paths(&mut v, shape);
        paths(&mut v, g.stroke_outlines.as_deref().unwrap());
        for m in g.medians.as_ref().unwrap() {
            v.push(m.len() as u64);
            v.extend(m.iter().flat_map(|q| [q.x.to_bits(), q.y.to_bits()]));
        }
        (g.ch, g.source.clone(), v)
    }

    #[test]
    fn embedded_data_decodes_to_the_json_glyph_for_every_subset_character() {
        let json = subset_json();
        let mut n = 0;
        for line in json.lines() {
            let ch = line.strip_prefix("{\"c\":\"").and_then(|r| r.chars().next()).unwrap();
            let from_json = parse_hanzi_json(ch, line, GlyphSource::Embedded, "subset").unwrap();
            let packed = embedded_glyph(ch).unwrap();
            assert_eq!(glyph_bits(&packed), glyph_bits(&from_json), "{ch}");
            n += 1;
        }
        assert_eq!(n, 1001);
        // The subset's order is kept for evaluations.
        let order: Vec<char> = json.lines().filter_map(|l| l.strip_prefix("{\"c\":\"")?.chars().next()).collect();
        assert_eq!(embedded_chars(), order);
    }

    #[test]
    fn embedded_data_covers_the_whole_package_and_checks_out() {
        let all = embedded_all_chars();
        assert_eq!(verify_embedded().unwrap(), all.len());
        assert!(all.len() > 9000, "{}", all.len());
        assert!(all.windows(2).all(|w| w[0] < w[1]));
        // Characters beyond the frequency subset.
        for (ch, strokes) in [('眠', 10), ('龍', 16), ('鬱', 29)] {
            assert!(!embedded_chars().contains(&ch));
            let g = embedded_glyph(ch).unwrap();
            assert_eq!(g.medians.as_ref().unwrap().len(), strokes, "{ch}");
            assert_eq!(g.source, GlyphSource::Embedded);
        }
        // Not covered: a private-use code point and a rare extension-B character.
        for ch in ['\u{E000}', '𪚥', 'a'] {
            match embedded_glyph(ch) {
                Err(GlyphError::Unknown { ch: c, tried, .. }) => {
                    assert_eq!(c, ch);
                    assert_eq!(tried.len(), 1);
                    assert!(
                        tried[0].starts_with(EMBEDDED_NAME) && tried[0].contains(&all.len().to_string()),
                        "{tried:?}"
                    );
                }
                other => panic!("{ch}: {other:?}"),
            }
        }
        let e = embedded_glyph('\u{E000}').unwrap_err().to_string();
        assert!(e.contains("U+E000") && e.contains("embedded hanzi-writer-data") && !e.contains("--"), "{e}");
    }

    #[test]
    fn a_hanzi_folder_may_be_the_npm_folder_or_its_package_or_data_folder() {
        let root = std::env::temp_dir().join(format!("trajectory-hanzi-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let json = subset_json();
        let line = |c: char| json.lines().find(|l| l.starts_with(&format!("{{\"c\":\"{c}\""))).unwrap().to_string();
        for (sub, ch) in [("package", '永'), ("data", '字')] {
            std::fs::create_dir_all(root.join(sub)).unwrap();
            std::fs::write(root.join(sub).join(format!("{ch}.json")), line(ch)).unwrap();
        }
        for (from, ch, found_in) in
            [(root.clone(), '永', "package"), (root.clone(), '字', "data"), (root.join("package"), '永', "package")]
        {
            let g = glyph_from_hanzi_dir(&from, ch).unwrap();
            assert_eq!(g.source, GlyphSource::HanziData(root.join(found_in).display().to_string()));
            assert_eq!(glyph_bits(&g).2, glyph_bits(&embedded_glyph(ch).unwrap()).2, "{ch}");
        }
        match glyph_from_hanzi_dir(&root, '八') {
            Err(GlyphError::Unknown { tried, .. }) => {
                let want: Vec<String> = ["", "package", "data"]
                    .iter()
                    .map(|s| {
                        format!(
                            "the hanzi-writer-data folder {}",
                            if s.is_empty() { root.clone() } else { root.join(s) }.display()
                        )
                    })
                    .collect();
                assert_eq!(tried, want);
            }
            other => panic!("{other:?}"),
        }
        std::fs::remove_dir_all(&root).unwrap();
    }

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
