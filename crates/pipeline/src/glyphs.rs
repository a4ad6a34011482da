//! Where glyphs come from: the embedded set or a hanzi-writer-data folder, fonts, or images,
//! with stroke templates for the glyphs that have no stroke data of their own.

use std::path::{Path, PathBuf};

use trajectory::Method;
use trajectory::{FontSet, Glyph, GlyphError, GlyphSource, embedded_glyph, glyph_from_hanzi_dir, glyph_from_image};

use crate::{Error, Prepared, Result, prepare_with_template};

/// A glyph source, opened once and asked for one character at a time.
#[derive(Debug)]
pub enum GlyphInput {
    /// The embedded set (`None`), or a hanzi-writer-data folder.
    Hanzi(Option<PathBuf>),
    /// Fonts, with hanzi stroke data (embedded, or the folder) as templates.
    Fonts(FontSet, Option<PathBuf>),
    /// Images, one per character, with hanzi stroke data as templates.
    Images(Vec<(char, PathBuf)>, Option<PathBuf>),
}

impl GlyphInput {
    /// Opens fonts (files or folders; nothing decoded yet); `face_index` picks a face of a
    /// collection; `hanzi` is the folder stroke templates come from (`None`: embedded).
    ///
    /// # Errors
    /// [`Error::Glyph`] when a path is unreadable or holds no font.
    pub fn fonts(paths: &[PathBuf], face_index: Option<u32>, hanzi: Option<PathBuf>) -> Result<Self> {
        Ok(GlyphInput::Fonts(FontSet::open(paths, face_index)?, hanzi))
    }

    /// The glyph of `ch` and, for a font or image glyph, the character's stroke template when
    /// there is one (`None` when neither the embedded set nor the folder has the character).
    ///
    /// # Errors
    /// [`Error::Glyph`] when the source does not cover `ch` or cannot be read;
    /// [`Error::NoImage`] when an image source has no image for `ch`; [`Error::Template`] when
    /// the template exists but cannot be read.
    pub fn load(&self, ch: char) -> Result<(Glyph, Option<Glyph>)> {
        let template = |dir: &Option<PathBuf>| -> Result<Option<Glyph>> {
            let found = match dir {
                Some(d) => glyph_from_hanzi_dir(d, ch),
                None => embedded_glyph(ch),
            };
            match found {
                Ok(g) => Ok(Some(g)),
                Err(GlyphError::Unknown { .. }) => Ok(None),
                Err(source) => Err(Error::Template { ch, source }),
            }
        };
        Ok(match self {
            GlyphInput::Hanzi(Some(dir)) => (glyph_from_hanzi_dir(dir, ch)?, None),
            GlyphInput::Hanzi(None) => (embedded_glyph(ch)?, None),
            GlyphInput::Fonts(set, dir) => (set.glyph(ch)?, template(dir)?),
            GlyphInput::Images(files, dir) => {
                let path: &Path = files.iter().find(|(c, _)| *c == ch).map(|(_, p)| p).ok_or(Error::NoImage(ch))?;
                (glyph_from_image(path, ch)?, template(dir)?)
            }
        })
    }

    /// [`GlyphInput::load`] then [`prepare_loaded`].
    ///
    /// # Errors
    /// As both.
    pub fn prepare(&self, ch: char, method: Option<Method>) -> Result<Prepared> {
        prepare_loaded(self.load(ch)?, method)
    }
}

/// The character images of a folder, for [`GlyphInput::Images`]: files `<char>.png`, `.jpg` or
/// `.jpeg` (any case), each named after its one character, sorted by character (the first of
/// two files for one character kept); other files are passed over.
///
/// # Errors
/// [`Error::ImageFolder`] when the folder cannot be read, an image's name is not one
/// character, or there is no image.
///
/// # Examples
/// ```no_run
/// # fn main() -> Result<(), pipeline::Error> {
/// let images = pipeline::image_folder(std::path::Path::new("scans"))?;
/// let input = pipeline::GlyphInput::Images(images, None);
/// let p = input.prepare('永', None)?;
/// println!("{} strokes", p.paths.len());
/// # Ok(())
/// # }
/// ```
pub fn image_folder(dir: &Path) -> Result<Vec<(char, PathBuf)>> {
    let fail = |path: &Path, what, source| Error::ImageFolder { path: path.to_path_buf(), what, source };
    let entries = std::fs::read_dir(dir).map_err(|e| fail(dir, "cannot read the folder", Some(e)))?;
    let mut out = Vec::new();
    for e in entries {
        let path = e.map_err(|e| fail(dir, "cannot list the folder", Some(e)))?.path();
        let ext = path.extension().and_then(|x| x.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg")) {
            continue;
        }
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let mut cs = stem.chars();
        match (cs.next(), cs.next()) {
            (Some(c), None) => out.push((c, path)),
            _ => return Err(fail(&path, "expected an image named after its one character (e.g. 永.png)", None)),
        }
    }
    out.sort();
    out.dedup_by(|a, b| a.0 == b.0);
    if out.is_empty() {
        return Err(fail(dir, "no <char>.png, .jpg or .jpeg files", None));
    }
    Ok(out)
}

/// Finds the centre lines of a loaded glyph and its template (see [`prepare_with_template`]),
/// refusing a glyph that gave no strokes and a registration where most template strokes found
/// no ink (the glyph is then not this character, or not legible: writing the template where
/// it landed would be a guess). Strokes that found no ink are listed in the result's
/// [`Prepared::template`].
///
/// # Errors
/// [`Error::NoStrokes`], and the errors of [`prepare_with_template`].
pub fn prepare_loaded(loaded: (Glyph, Option<Glyph>), method: Option<Method>) -> Result<Prepared> {
    let (g, template) = loaded;
    let p = prepare_with_template(g, method, template.as_ref())?;
    let missing = p.template.as_ref().map(|t| (t.missing.len(), t.strokes));
    let mostly_missing = missing.is_some_and(|(m, n)| m * 2 > n);
    if p.paths.is_empty() || mostly_missing {
        let image = match &p.glyph.source {
            GlyphSource::Image(path) => Some(PathBuf::from(path)),
            _ => None,
        };
        return Err(Error::NoStrokes { ch: p.glyph.ch, image, missing: missing.filter(|_| mostly_missing) });
    }
    Ok(p)
}
