//! # stroke-fit
//!
//! Calibration from photos (the B-BSMG paper's §4.2, automated): a brush pressed on a grid of
//! `(h, α, β)` leaves strokes; each photo is normalised ([`load_ink`]: scale from metadata,
//! background flattened, Otsu threshold, the one ink blob) and a B-BSM footprint is fitted to it
//! ([`fit_footprint`]: moments and principal axis to start, Nelder–Mead on the soft IoU to refine, both
//! ends tried as the root). [`read_labels`] reads the presses a folder of photos was made with,
//! [`photo_measurements`] turns the fits into measurements and their `measurements.csv`,
//! [`fit_overlay`] draws a fit over its photo, and [`synthetic_photo`] makes synthetic stroke
//! photos from known footprints.
//!
//! The measurements then go to `brush_model::fit` as usual.

#![warn(unreachable_pub)]

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`stroke_fit::brush_model::Press`).
pub use bezier_raster;
pub use brush_model;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod fit;
mod labels;
mod measure;
mod overlay;
mod photo;
mod synth;

pub use fit::{StrokeFit, fit_footprint};
pub use labels::{LabelsError, MAX_LABELS_BYTES, MAX_LABELS_ROWS, StrokeLabel, read_labels};
pub use measure::{PhotoMeasurements, photo_measurements};
pub use overlay::fit_overlay;
pub use photo::{InkMask, PhotoError, load_ink, mask_from_gray, scale_from_metadata};
pub use synth::{Degradation, png_with_scale, synthetic_photo};
