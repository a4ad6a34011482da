//! Fonts as users get them: TrueType and OpenType files (`.ttf`, `.otf` with CFF outlines),
//! collections (`.ttc`, `.otc`, one face chosen by index), and web fonts (`.woff`, `.woff2`,
//! decoded with the pure-Rust `wuff` crate). Web-font packages split a CJK font into many files,
//! each covering one unicode range, so a [`FontSet`] holds several files (or folders of them)
//! and takes each character from the first file whose character map covers it.
//!
//! Outlines land in the em frame like hanzi-writer-data: font units are scaled so the em is 1024
//! units (`y' = 900 − y·1024/upem`), then each glyph is placed by its real ink box: moved so
//! that box is centred in the 1024-unit em box (and shrunk to fit when it is larger than the
//! em). Fonts put the em box in different places (the baseline, ascender and descender vary:
//! a glyph that reaches below hanzi-writer-data's descender of 124 units would be cut off), and
//! a character is centred in its box on the paper as calligraphers centre it in its grid cell.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use kurbo::{BezPath, Point};

use super::{EM, EM_TOP, Glyph, GlyphError, GlyphSource, Shape, limits, path_outside};

/// File name extensions taken from a folder (compared without case).
pub const FONT_EXTENSIONS: [&str; 6] = ["ttf", "otf", "ttc", "otc", "woff", "woff2"];

/// The container a font file is in, from its first four bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FontFormat {
    /// One face with TrueType outlines (`00 01 00 00` or `true`).
    TrueType,
    /// One face with CFF outlines (`OTTO`).
    OpenTypeCff,
    /// A collection of faces (`ttcf`: TTC or OTC).
    Collection,
    /// WOFF 1.0 (`wOFF`, zlib-compressed tables).
    Woff,
    /// WOFF 2.0 (`wOF2`, brotli-compressed, transformed tables).
    Woff2,
}

impl FontFormat {
    /// The format of `data` from its magic number, if it is one of the known ones.
    pub fn sniff(data: &[u8]) -> Option<FontFormat> {
        match data.get(..4)? {
            [0, 1, 0, 0] | b"true" => Some(FontFormat::TrueType),
            b"OTTO" => Some(FontFormat::OpenTypeCff),
            b"ttcf" => Some(FontFormat::Collection),
            b"wOFF" => Some(FontFormat::Woff),
            b"wOF2" => Some(FontFormat::Woff2),
            _ => None,
        }
    }

    /// A short name for messages: `TrueType`, `OpenType (CFF)`, `collection`, `WOFF`, `WOFF2`.
    pub fn name(self) -> &'static str {
        match self {
            FontFormat::TrueType => "TrueType",
            FontFormat::OpenTypeCff => "OpenType (CFF)",
            FontFormat::Collection => "collection",
            FontFormat::Woff => "WOFF",
            FontFormat::Woff2 => "WOFF2",
        }
    }
}

const EXPECTED: &str = "a TrueType/OpenType font (.ttf, .otf), a collection (.ttc, .otc), WOFF or WOFF2";

fn malformed(path: &Path, message: String) -> GlyphError {
    GlyphError::Malformed { source_name: path.display().to_string(), message }
}

fn be_u32(d: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(d.get(at..at + 4)?.try_into().ok()?))
}

fn be_u16(d: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes(d.get(at..at + 2)?.try_into().ok()?))
}

/// zlib cannot expand data by more than about 1032:1; a WOFF table that claims more is corrupt
/// (and would make the decoder reserve its claimed size).
const ZLIB_MAX_RATIO: u64 = 1032;

/// Checks a WOFF 1.0 header and table directory against the size limits before decoding.
fn check_woff1(path: &Path, d: &[u8]) -> Result<(), GlyphError> {
    let bad = |m: &str| malformed(path, format!("not a valid WOFF file: {m}"));
    let total = be_u32(d, 16).ok_or_else(|| bad("the 44-byte header is truncated"))?;
    if u64::from(total) > limits::MAX_FONT_BYTES {
        return Err(bad(&format!(
            "it claims {total} bytes decoded; a font is at most {} bytes",
            limits::MAX_FONT_BYTES
        )));
    }
    let tables = be_u16(d, 12).ok_or_else(|| bad("the 44-byte header is truncated"))? as usize;
    let mut sum = 0u64;
    for t in 0..tables {
        let at = 44 + 20 * t;
        let (Some(comp), Some(orig)) = (be_u32(d, at + 8), be_u32(d, at + 12)) else {
            return Err(bad(&format!("the table directory ({tables} tables) is truncated")));
        };
        if comp < orig && u64::from(orig) > ZLIB_MAX_RATIO * u64::from(comp) + 64 {
            return Err(bad(&format!("table {} claims {orig} bytes from {comp} compressed bytes", t + 1)));
        }
        sum += u64::from(orig);
    }
    if sum > limits::MAX_FONT_BYTES {
        return Err(bad(&format!(
            "its tables decode to {sum} bytes; a font is at most {} bytes",
            limits::MAX_FONT_BYTES
        )));
    }
    Ok(())
}

/// Reads a font file and returns its OpenType (sfnt) bytes: WOFF and WOFF2 are decoded, the
/// other formats are returned as they are.
///
/// # Errors
/// [`GlyphError::Io`] if the file cannot be read; [`GlyphError::Malformed`] naming the file for
/// one larger than [`limits::MAX_FONT_BYTES`] and as [`sfnt_from_bytes`].
pub fn read_sfnt(path: &Path) -> Result<Vec<u8>, GlyphError> {
    let io = |e: std::io::Error| GlyphError::io(path, e);
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > limits::MAX_FONT_BYTES {
        return Err(malformed(path, format!("{len} bytes; a font is at most {} bytes", limits::MAX_FONT_BYTES)));
    }
    let too_large = || malformed(path, format!("a font is at most {} bytes", limits::MAX_FONT_BYTES));
    sfnt_from_bytes(path, brush_model::read_regular(path, limits::MAX_FONT_BYTES).map_err(io)?.ok_or_else(too_large)?)
}

/// The OpenType (sfnt) bytes of a font file's contents `data`: WOFF and WOFF2 are decoded, the
/// other formats returned as they are. `path` only names the file in errors.
///
/// # Errors
/// [`GlyphError::Malformed`] naming `path` for data that is none of the known formats, a web font
/// that does not decode (truncated or corrupt) or would decode to more than
/// [`limits::MAX_FONT_BYTES`], or one whose content is not an OpenType font.
pub fn sfnt_from_bytes(path: &Path, data: Vec<u8>) -> Result<Vec<u8>, GlyphError> {
    let format = FontFormat::sniff(&data).ok_or_else(|| {
        let head: Vec<String> = data.iter().take(4).map(|b| format!("{b:02x}")).collect();
        malformed(path, format!("not a font: expected {EXPECTED}; the file starts with bytes [{}]", head.join(" ")))
    })?;
    let decoded = match format {
        FontFormat::Woff => {
            check_woff1(path, &data)?;
            wuff::decompress_woff1(&data).map_err(|_| {
                malformed(path, "not a valid WOFF file: truncated or corrupt (it does not decode)".into())
            })?
        }
        FontFormat::Woff2 => wuff::decompress_woff2(&data)
            .map_err(|_| malformed(path, "not a valid WOFF2 file: truncated or corrupt (it does not decode)".into()))?,
        _ => return Ok(data),
    };
    if decoded.len() as u64 > limits::MAX_FONT_BYTES {
        return Err(malformed(
            path,
            format!("decodes to {} bytes; a font is at most {} bytes", decoded.len(), limits::MAX_FONT_BYTES),
        ));
    }
    match FontFormat::sniff(&decoded) {
        Some(FontFormat::TrueType | FontFormat::OpenTypeCff | FontFormat::Collection) => Ok(decoded),
        _ => Err(malformed(path, format!("a {} file whose content is not an OpenType font", format.name()))),
    }
}

/// The number of faces in OpenType bytes: the collection's count, 1 for a single font.
fn faces_in(data: &[u8]) -> u32 {
    ttf_parser::fonts_in_collection(data).unwrap_or(1)
}

/// The font files named by `paths`: a file is taken as it is (whatever its name); a folder gives
/// the files in it (not in sub-folders) whose extension is one of [`FONT_EXTENSIONS`], sorted by
/// file name so the choice is the same on every machine.
///
/// # Errors
/// [`GlyphError::Io`] for a path that does not exist or a folder that cannot be listed or holds
/// no font files; [`GlyphError::Malformed`] if `paths` is empty.
pub fn font_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, GlyphError> {
    if paths.is_empty() {
        return Err(GlyphError::Malformed { source_name: "--font".into(), message: "no font file given".into() });
    }
    let mut out = Vec::new();
    for p in paths {
        let io = |e: std::io::Error| GlyphError::io(p, e);
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.is_file()
                        && f.extension()
                            .and_then(|x| x.to_str())
                            .is_some_and(|x| FONT_EXTENSIONS.iter().any(|k| k.eq_ignore_ascii_case(x)))
                })
                .collect();
            if found.is_empty() {
                let why = format!("no font files (.{}) in this folder", FONT_EXTENSIONS.join(", ."));
                return Err(GlyphError::io(p, std::io::Error::new(std::io::ErrorKind::NotFound, why)));
            }
            found.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
            out.extend(found);
        } else {
            std::fs::metadata(p).map_err(io)?;
            out.push(p.clone());
        }
    }
    Ok(out)
}

/// One font file of a [`FontSet`], decoded on first use.
#[derive(Debug)]
struct FontFile {
    path: PathBuf,
    sfnt: OnceLock<Result<Arc<Vec<u8>>, GlyphError>>,
}

/// Several font files (a web font split by unicode range, or fonts to fall back on) searched in
/// order for a character. Files are read and decoded once, when first needed; a `FontSet` can
/// be shared between threads.
#[derive(Debug)]
pub struct FontSet {
    files: Vec<FontFile>,
    face_index: Option<u32>,
}

impl FontSet {
    /// The files of `paths` (files or folders, see [`font_files`]). `face_index` picks the face
    /// of a collection (TTC/OTC); `None` is face 0. Nothing is decoded yet.
    ///
    /// # Errors
    /// As [`font_files`].
    pub fn open(paths: &[PathBuf], face_index: Option<u32>) -> Result<FontSet, GlyphError> {
        let files = font_files(paths)?.into_iter().map(|path| FontFile { path, sfnt: OnceLock::new() }).collect();
        Ok(FontSet { files, face_index })
    }

    /// The files searched, in order.
    pub fn files(&self) -> Vec<&Path> {
        self.files.iter().map(|f| f.path.as_path()).collect()
    }

    fn sfnt(&self, f: &FontFile) -> Result<Arc<Vec<u8>>, GlyphError> {
        f.sfnt.get_or_init(|| read_sfnt(&f.path).map(Arc::new)).clone()
    }

    /// The glyph of `ch` from the first file whose character map covers it (with an outline).
    ///
    /// # Errors
    /// [`GlyphError::Unknown`] naming the files tried when none covers `ch`;
    /// [`GlyphError::Malformed`] naming the file for a file met on the way that is not a font,
    /// does not decode, has no face `face_index`, or whose glyph breaks [`limits`];
    /// [`GlyphError::Io`].
    pub fn glyph(&self, ch: char) -> Result<Glyph, GlyphError> {
        for f in &self.files {
            let data = self.sfnt(f)?;
            let index = self.face_index.unwrap_or(0);
            let faces = faces_in(&data);
            if index >= faces {
                return Err(malformed(
                    &f.path,
                    format!(
                        "no face {index}: the file has {faces} face{} (indices 0..={})",
                        if faces == 1 { "" } else { "s" },
                        faces - 1
                    ),
                ));
            }
            let face = ttf_parser::Face::parse(&data, index).map_err(|e| {
                malformed(&f.path, format!("not a valid font (face {index}): {e}; expected {EXPECTED}"))
            })?;
            if let Some(g) = outline_of(&face, &f.path, index, ch)? {
                return Ok(g);
            }
        }
        let names: Vec<String> = self.files.iter().map(|f| f.path.display().to_string()).collect();
        let shown = if names.len() > 6 {
            format!("{}, … and {} more", names[..5].join(", "), names.len() - 5)
        } else {
            names.join(", ")
        };
        let face = self.face_index.map(|i| format!(" (face {i})")).unwrap_or_default();
        Err(GlyphError::Unknown {
            ch,
            code: ch as u32,
            tried: vec![format!(
                "the {} font file{} tried{face}, none of which covers it: {shown}",
                names.len(),
                if names.len() == 1 { "" } else { "s" }
            )],
        })
    }
}

struct OutlineSink {
    path: BezPath,
    scale: f64,
}

impl OutlineSink {
    fn p(&self, x: f32, y: f32) -> Point {
        Point::new(x as f64 * self.scale, EM_TOP - y as f64 * self.scale)
    }
}

impl ttf_parser::OutlineBuilder for OutlineSink {
    fn move_to(&mut self, x: f32, y: f32) {
        let p = self.p(x, y);
        self.path.move_to(p);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        let p = self.p(x, y);
        self.path.line_to(p);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let (a, b) = (self.p(x1, y1), self.p(x, y));
        self.path.quad_to(a, b);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let (a, b, c) = (self.p(x1, y1), self.p(x2, y2), self.p(x, y));
        self.path.curve_to(a, b, c);
    }
    fn close(&mut self) {
        self.path.close_path();
    }
}

/// The glyph of `ch` in `face`, `None` when the face does not map it or has no outline for it.
fn outline_of(face: &ttf_parser::Face<'_>, path: &Path, index: u32, ch: char) -> Result<Option<Glyph>, GlyphError> {
    let Some(gid) = face.glyph_index(ch).filter(|g| g.0 != 0) else { return Ok(None) };
    let upem = face.units_per_em();
    let mut sink = OutlineSink { path: BezPath::new(), scale: EM / f64::from(upem) };
    if face.outline_glyph(gid, &mut sink).is_none() {
        return Ok(None);
    }
    let max = limits::MAX_STROKES * limits::MAX_PATH_ELEMENTS;
    if sink.path.elements().len() > max {
        return Err(malformed(
            path,
            format!("glyph of {ch:?}: {} outline elements; at most {max}", sink.path.elements().len()),
        ));
    }
    let placed = centred_in_em(&sink.path);
    if let Some(q) = path_outside(&placed) {
        return Err(malformed(
            path,
            format!(
                "glyph of {ch:?}: point ({:.0}, {:.0}) outside the accepted em coordinates {}..={} (odd units_per_em {upem}?)",
                q.x,
                q.y,
                limits::MIN_COORD,
                limits::MAX_COORD
            ),
        ));
    }
    Ok(Some(Glyph {
        ch,
        source: GlyphSource::Font { path: path.display().to_string(), face_index: index },
        shape: Shape::Outlines(vec![placed]),
        stroke_outlines: None,
        medians: None,
    }))
}

/// `path` (em units) moved so its ink box is centred in the em box `0..EM` on both axes, and
/// scaled about that centre to fit when the ink box is larger than the em. An empty outline is
/// returned as it is.
fn centred_in_em(path: &BezPath) -> BezPath {
    use kurbo::Shape as _;
    let b = path.bounding_box();
    if path.elements().is_empty() || !(b.width() > 0.0 && b.height() > 0.0) || !b.is_finite() {
        return path.clone();
    }
    let k = (EM / b.width()).min(EM / b.height()).min(1.0);
    let c = b.center();
    let t = kurbo::Affine::translate((EM / 2.0, EM / 2.0))
        * kurbo::Affine::scale(k)
        * kurbo::Affine::translate((-c.x, -c.y));
    let mut out = path.clone();
    out.apply_affine(t);
    out
}

/// A glyph from the first of `paths` (font files or folders of them, see [`font_files`]) whose
/// character map covers `ch`; `face_index` picks a collection's face (`None`: face 0).
/// [`GlyphSource::Font`] records the file used and the face. To load many characters from the
/// same files, open a [`FontSet`] once instead: it decodes each file only once.
///
/// # Errors
/// As [`FontSet::open`] and [`FontSet::glyph`].
pub fn glyph_from_font_files(paths: &[PathBuf], face_index: Option<u32>, ch: char) -> Result<Glyph, GlyphError> {
    FontSet::open(paths, face_index)?.glyph(ch)
}

#[cfg(test)]
mod tests {
    use super::*;
    use kurbo::Shape as _;

    fn fixture(rel: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fonts").join(rel)
    }

    fn ink_box(g: &Glyph) -> kurbo::Rect {
        let Shape::Outlines(paths) = &g.shape else { panic!("a font glyph is outlines") };
        paths.iter().map(|p| p.bounding_box()).reduce(|a, b| a.union(b)).unwrap()
    }

    /// Ma Shan Zheng's 永 sits low in its em box (placed by the em box alone its ink reaches to
    /// within 24 of the 1024 units of the bottom, at the image's edge): placed by its ink box it
    /// is centred.
    #[test]
    fn a_glyph_is_placed_by_its_ink_box_inside_the_em() {
        let font = FontSet::open(&[fixture("msz")], None).unwrap();
        let data = font
            .files
            .iter()
            .find_map(|f| {
                let d = font.sfnt(f).ok()?;
                let face = ttf_parser::Face::parse(&d, 0).ok()?;
                face.glyph_index('永').filter(|g| g.0 != 0).map(|_| d.clone())
            })
            .expect("msz covers 永");
        let face = ttf_parser::Face::parse(&data, 0).unwrap();
        let gid = face.glyph_index('永').unwrap();
        let upem = f64::from(face.units_per_em());
        let raw = face.glyph_bounding_box(gid).unwrap();
        // The em-box placement (y' = 900 − y·1024/upem) puts the ink's centre well off the em's.
        let raw_top = EM_TOP - f64::from(raw.y_max) * EM / upem;
        let raw_bottom = EM_TOP - f64::from(raw.y_min) * EM / upem;
        let off = (raw_top + raw_bottom) / 2.0 - EM / 2.0;
        assert!(off > 0.0 && raw_bottom > 1000.0, "ink {raw_top:.0}..{raw_bottom:.0}: em and ink box differ");
        let b = ink_box(&font.glyph('永').unwrap());
        assert!(b.x0 >= 0.0 && b.y0 >= 0.0 && b.x1 <= EM && b.y1 <= EM, "{b:?}");
        assert!((b.center().x - EM / 2.0).abs() < 1e-6 && (b.center().y - EM / 2.0).abs() < 1e-6, "{b:?}");
        // The font's scale is kept (1024/upem): the box only moved (the font's box holds the
        // control points, so it may exceed the curves' by a few units).
        let h = f64::from(raw.y_max - raw.y_min) * EM / upem;
        assert!(b.height() <= h + 1e-6 && h - b.height() < 5.0, "{} vs {h}", b.height());
    }

    #[test]
    fn an_ink_box_larger_than_the_em_is_shrunk_to_fit() {
        let mut p = BezPath::new();
        p.move_to((-300.0, 100.0));
        p.line_to((1500.0, 100.0));
        p.line_to((1500.0, 400.0));
        p.close_path();
        let b = centred_in_em(&p).bounding_box();
        assert!((b.x0 - 0.0).abs() < 1e-9 && (b.x1 - EM).abs() < 1e-9, "{b:?}");
        assert!((b.height() - 300.0 * EM / 1800.0).abs() < 1e-9, "{b:?}");
    }
}
