//! # figures
//!
//! The pictures maobi's results come as, beside their JSON: a written character's pictures
//! ([`char_pictures`]), labelled rows of images
//! ([`labelled_row_png`]), a render over its glyph with a legend ([`overlay_legend_png`]), the
//! calibration's regression plot ([`regression_png`]), loss curves ([`loss_png`]), every stroke
//! model's outline of one press ([`models_png`]), and the preview page of a robot program
//! ([`preview_html`], [`sheet_preview`]). Each returns the encoded bytes (PNG, or the HTML
//! text); the caller writes them.
//!
//! Nothing here computes what it shows: images come from `bezier-raster`, fits from
//! `brush-model`, the program's run and footprints from [`pipeline::run_sheet_with`].

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod char;
mod error;
mod page;
mod plot;

pub use char::char_pictures;
pub use error::FigureError;
pub use page::{PreviewInput, TrackPreview, preview_html, sheet_preview, track_preview};
pub use plot::{labelled_row_png, labelled_row_rgb_png, loss_png, models_png, overlay_legend_png, regression_png};

/// This crate's results.
pub type Result<T, E = FigureError> = std::result::Result<T, E>;
