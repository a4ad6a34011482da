//! What can go wrong drawing a figure.

use thiserror::Error;

/// Why a figure could not be made.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FigureError {
    /// The plotting backend refused to draw (its message).
    #[error("drawing the figure failed: {0}")]
    Draw(String),
    /// A picture's pixels do not fill its size (a bug in the caller's sizes).
    #[error("the picture's buffer does not match its size {width}×{height}")]
    Size {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
    /// Encoding or decoding a PNG failed.
    #[error("encoding the PNG failed")]
    Png(#[from] image::ImageError),
    /// The two images of an overlay differ in size.
    #[error(transparent)]
    Raster(#[from] bezier_raster::RasterError),
    /// The press is outside the brush profile's calibrated range.
    #[error(transparent)]
    Profile(#[from] brush_model::ProfileError),
    /// A `track.json` could not be read ([`crate::track_preview`]).
    #[error(transparent)]
    Read(#[from] pipeline::ReadBackError),
    /// A `track.json` is not a valid track ([`crate::track_preview`]).
    #[error(transparent)]
    Track(#[from] robot_io::RobotError),
    /// A `track.json` cannot be previewed ([`crate::track_preview`]): no points, no usable
    /// sheet, or a sheet's fields of the wrong shape.
    #[error("{}: {what}", path.display())]
    TrackFile {
        /// The file.
        path: std::path::PathBuf,
        /// What was wrong.
        what: String,
    },
    /// The preview page's data could not be written as JSON.
    #[error("writing the preview's data failed")]
    Json(#[from] serde_json::Error),
}

impl FigureError {
    /// The plotting backend's error, in words.
    pub(crate) fn draw(e: impl std::fmt::Display) -> Self {
        FigureError::Draw(e.to_string())
    }
}
