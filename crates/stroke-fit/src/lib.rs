//! # stroke-fit
//!
//! Calibration from photos (the B-BSMG paper's §4.2, automated): a brush pressed on a grid of
//! `(h, α, β)` leaves strokes; each photo is normalised ([`photo`]: scale from metadata,
//! background flattened, Otsu threshold, the one ink blob) and a B-BSM footprint is fitted to it
//! ([`fit`]: moments and principal axis to start, Nelder–Mead on the soft IoU to refine, both
//! ends tried as the root). [`synth`] makes synthetic stroke photos from known footprints.
//!
//! The measurements then go to `brush_model::fit` as usual.

pub mod fit;
pub mod photo;
pub mod synth;

pub use fit::{StrokeFit, fit_footprint};
pub use photo::{InkMask, PhotoError, load_ink, mask_from_gray, scale_from_metadata};
