//! The pipeline's one error type.

use std::path::PathBuf;

use brush_model::ProfileError;
use robot_io::RobotError;
use thiserror::Error;
use trajectory::{GlyphError, TrajectoryError};

/// What can go wrong between a character and its scores. The messages name the character, the
/// file or the value at fault and what was expected; they never name a command-line flag (the
/// caller knows which flag or field a value came from and adds that).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// A glyph source could not give the character (not covered, unreadable, malformed).
    #[error(transparent)]
    Glyph(#[from] GlyphError),
    /// An image source has no image for this character.
    #[error("no image for {0:?}")]
    NoImage(char),
    /// The character's stroke template (embedded or from a hanzi-writer-data folder) could not
    /// be read.
    #[error("the stroke template of {ch:?}")]
    Template {
        /// The character.
        ch: char,
        /// Why.
        #[source]
        source: GlyphError,
    },
    /// [`trajectory::Method::Template`] on a glyph without medians, and no template given.
    #[error(
        "{0:?}: the template method needs the character's stroke data, and {0:?} has none here (expected it in the embedded set or in a hanzi-writer-data folder)"
    )]
    NoTemplate(char),
    /// The centre lines could not be found.
    #[error("{ch:?}")]
    CentreLines {
        /// The character.
        ch: char,
        /// Why.
        #[source]
        source: TrajectoryError,
    },
    /// The glyph gave no strokes, or a template registration found no ink for most of its
    /// strokes (the glyph is not this character, or not legible).
    #[error(
        "{ch}: found no strokes{}{} (is it one character, dark ink on light paper, strokes wider than a hair?)",
        image.as_ref().map_or(String::new(), |p| format!(" in {}", p.display())),
        missing.map_or(String::new(), |(m, n)| format!(" for {m} of the template's {n} strokes"))
    )]
    NoStrokes {
        /// The character.
        ch: char,
        /// The image the glyph came from, if it came from one.
        image: Option<PathBuf>,
        /// `(strokes that found no ink, template strokes)` when a registration failed.
        missing: Option<(usize, usize)>,
    },
    /// The brush profile refused a press (a track point outside its calibrated range).
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// Two images could not be compared (sizes differ or are too small).
    #[error(transparent)]
    Metrics(#[from] stroke_metrics::MetricsError),
    /// A track's robot program failed the safety check (`robot check`).
    #[error("{ch}: the track fails `robot check`")]
    Check {
        /// The character.
        ch: String,
        /// Why.
        #[source]
        source: RobotError,
    },
    /// Refinement failed.
    #[error("{ch}: refining the track")]
    Refine {
        /// The character.
        ch: char,
        /// Why.
        #[source]
        source: track_refine::RefineError,
    },
    /// Refinement with generator gradients was asked for, but no generator was given (or this
    /// build has no generator support: the `generator` feature).
    #[error(
        "refinement with generator gradients needs a generator (none was given, or this build lacks the `generator` feature)"
    )]
    NoGenerator,
    /// The generator was trained for another brush than the one written with.
    #[error("the generator was trained for brush `{trained}`, not `{brush}`")]
    GeneratorBrush {
        /// The generator's brush.
        trained: String,
        /// The brush written with.
        brush: String,
    },
    /// The generator failed to render.
    #[cfg(feature = "generator")]
    #[error(transparent)]
    Generator(#[from] neural_gen::NeuralGenError),
    /// A folder of character images ([`crate::image_folder`]) could not be read or holds no
    /// usable image (`path`: the folder, or the file whose name is not one character).
    #[error("{}: {what}", path.display())]
    ImageFolder {
        /// The folder or file.
        path: PathBuf,
        /// What was wrong or expected.
        what: &'static str,
        /// The I/O error, when reading failed.
        #[source]
        source: Option<std::io::Error>,
    },
    /// A sheet could not be understood or laid out.
    #[error(transparent)]
    Sheet(#[from] crate::sheet::SheetError),
}

impl Error {
    /// Whether the glyph source does not cover the character (a font or folder without it),
    /// as opposed to a source that could not be read.
    pub fn is_uncovered(&self) -> bool {
        matches!(self, Error::Glyph(GlyphError::Unknown { .. }))
    }
}

/// The pipeline's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;
