//! # trajectory
//!
//! From a Chinese character to the 5D brush track `T_i = (H_i, α_i, x_i, y_i, β_i)` a robot can
//! write.
//!
//! 1. **Glyph** ([`Glyph`]: [`embedded_glyph`], [`glyph_from_font`], [`glyph_from_image`], …): hanzi-writer-data (every character of the package embedded,
//!    compressed, or an unpacked package's JSON), a CJK font's outlines, or a photo of a character.
//!    Everything is in the em frame (1024 box, y down).
//! 2. **Centre lines** ([`centre_lines`]): the source's stroke medians ([`Method::Medians`]), or a
//!    skeleton of the glyph image ([`Method::Skeleton`]: Zhang–Suen thinning, spur pruning,
//!    junction merging, a graph search that goes straight through crossings, stroke ordering).
//!    Each point carries the glyph's local half-width from a Euclidean distance transform (of
//!    the stroke's own outline when the source has one); ends run out into the end caps and
//!    sharp corners out into their pressed knobs, which become the [`StrokePath::corners`].
//! 3. **Track** ([`build_track`]): footprints that trail the motion, sized through the brush
//!    profile's inverse model, placed on the paper by a [`CharBox`].
//!
//! ```
//! use trajectory::{centre_lines, build_track, embedded_glyph, CharBox, Method, Sizing, TrackOptions, DEFAULT_SPACING_MM};
//! use brush_model::BrushProfile;
//! let g = embedded_glyph('十').unwrap();
//! let paths = centre_lines(&g, Method::Medians, 256).unwrap();
//! let pen1 = BrushProfile::builtin("pen1").unwrap();
//! let opts = TrackOptions {
//!     char_box: CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 80.0 },
//!     spacing_mm: DEFAULT_SPACING_MM, alpha_rad: 0.0, sizing: Sizing::Brush,
//! };
//! let built = build_track(&paths, &pen1, &opts).unwrap();
//! assert_eq!(built.track.strokes.len(), 2);
//! ```

#![warn(unreachable_pub)]

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`trajectory::brush_model::Press`).
pub use bezier_raster;
pub use brush_model;
pub use image;
pub use kurbo;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod distance;
mod glyph;
mod medians;
mod metrics;
mod paper;
mod path;
mod polyline;
mod raster;
mod scan;
mod skeleton;
mod template;
mod thinning;
mod track;

use thiserror::Error;

pub use glyph::{
    ARPHIC_LICENSE, EM, EM_TOP, EMBEDDED_NAME, FONT_EXTENSIONS, FontFormat, FontSet, Glyph, GlyphError, GlyphSource,
    HANZI_SUBFOLDERS, Shape, embedded_all_chars, embedded_chars, embedded_glyph, font_files, glyph_from_font,
    glyph_from_font_files, glyph_from_gray, glyph_from_hanzi_dir, glyph_from_image, limits, pack_hanzi,
    parse_hanzi_json, read_sfnt, sfnt_from_bytes, verify_embedded,
};
pub use metrics::chamfer_pct;
pub use paper::{CharBox, auto_char_mm};
pub use path::{CORNER_RAD, CORNER_REACH_EM, StrokePath, find_corners};
pub use raster::{mask_of, render_glyph, render_outlines, resample_bitmap};
pub use scan::{ScanError, ScanOptions, decode_gray, synth_scan};
pub use skeleton::{
    CORNER_FEATURE_NAMES, CornerSample, DecisionModel, FEATURE_NAMES, GraphOptions, NUM_CORNER_FEATURES, NUM_FEATURES,
    PairSample, Skeleton, SkeletonModelError, SkeletonModels,
};
pub use template::{Registration, StrokeFit, TemplateOptions, register_template, shape_only};
pub use track::{
    BuiltTrack, DEFAULT_SPACING_MM, GLIDE_CONTACT_FACTOR, GLIDE_H_MM, Sizing, TrackOptions, build_track, glide_h_mm,
};

/// The analysis raster (px per em box) the `maobi` pipeline uses for widths and skeletons.
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
pub const DEFAULT_ANALYSIS_PX: u32 = 512;

/// How centre lines are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The source's stroke medians (hanzi-writer-data).
    Medians,
    /// A skeleton of the glyph image.
    Skeleton,
    /// A stroke template (hanzi-writer medians of the same character) registered onto the glyph
    /// ([`register_template`], [`centre_lines_from_template`]).
    Template,
}

impl Method {
    /// `medians` or `skeleton`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Medians => "medians",
            Method::Skeleton => "skeleton",
            Method::Template => "template",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "medians" => Ok(Method::Medians),
            "skeleton" => Ok(Method::Skeleton),
            "template" => Ok(Method::Template),
            _ => Err(format!("unknown method `{s}` (expected medians, skeleton or template)")),
        }
    }
}

/// Errors from centre-line extraction.
#[derive(Debug, Error)]
pub enum TrajectoryError {
    /// Medians were asked for but the source has none (the value names the source kind:
    /// `font`, `image`, …).
    #[error("{0} has no stroke medians (the medians and template methods need hanzi-writer stroke data)")]
    NoMedians(String),
    /// The glyph has no ink at the analysis resolution.
    #[error("the glyph of {0:?} has no ink to trace")]
    Empty(char),
}

/// The stroke centre lines of a glyph with half-widths, in writing order, using `method` on an
/// `analysis_px × analysis_px` raster of the em box.
///
/// [`Method::Template`] here registers the glyph's own medians onto its own shape (the glyph is
/// its own template); for a font or image glyph use [`centre_lines_from_template`].
///
/// # Examples
/// ```
/// use trajectory::{Method, centre_lines, embedded_glyph};
/// let g = embedded_glyph('十').unwrap();
/// let paths = centre_lines(&g, Method::Medians, 256).unwrap();
/// // 十 is written in two strokes: 横, then 竖.
/// assert_eq!(paths.len(), 2);
/// // Every point carries the glyph's local half-width (em units).
/// assert!(paths.iter().all(|p| p.points.len() == p.half_widths.len()));
/// assert!(paths.iter().all(|p| p.half_widths.iter().any(|w| *w > 0.0)));
/// ```
///
/// # Errors
/// [`TrajectoryError::NoMedians`] for [`Method::Medians`] or [`Method::Template`] on a source
/// without medians; [`TrajectoryError::Empty`] for a blank glyph.
pub fn centre_lines(g: &Glyph, method: Method, analysis_px: u32) -> Result<Vec<StrokePath>, TrajectoryError> {
    match method {
        Method::Template => {
            let opts = TemplateOptions { analysis_px, ..TemplateOptions::default() };
            Ok(template::register_template(g, &template::shape_only(g), &opts)?.paths)
        }
        Method::Medians => medians::from_medians(g, analysis_px),
        Method::Skeleton => medians::from_skeleton(g, analysis_px),
    }
}

/// Registers the stroke template `template` (a glyph with medians: embedded or a hanzi-writer
/// folder) onto `target` (a font or image glyph of the same character) and returns its centre
/// lines, in the template's stroke count and order, with what the registration found per stroke
/// ([`Registration::strokes`]: strokes that found no ink are kept and flagged there). Analysis on
/// an `analysis_px²` raster of the em box; otherwise [`TemplateOptions::default`].
///
/// # Examples
/// ```
/// use trajectory::{centre_lines_from_template, embedded_glyph, shape_only};
/// let hanzi_writer = embedded_glyph('十').unwrap();
/// // A target with the shape only, as a font or a photo gives it.
/// let target = shape_only(&hanzi_writer);
/// let reg = centre_lines_from_template(&hanzi_writer, &target, 128).unwrap();
/// assert_eq!(reg.paths.len(), 2);
/// assert!(reg.strokes.iter().all(|s| s.found_ink));
/// ```
///
/// # Errors
/// [`TrajectoryError::NoMedians`] when the template has no medians; [`TrajectoryError::Empty`]
/// when either glyph is blank.
pub fn centre_lines_from_template(
    template: &Glyph,
    target: &Glyph,
    analysis_px: u32,
) -> Result<Registration, TrajectoryError> {
    template::register_template(template, target, &TemplateOptions { analysis_px, ..TemplateOptions::default() })
}
