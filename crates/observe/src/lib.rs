//! maobi's eye: a photo of a sheet that maobi wrote → its registration marks → the photo →
//! paper homography → the ink in the paper frame, and how it differs from the plan.
//!
//! The steps, each usable alone (the first three together: [`read_sheet_photo`]):
//! - [`Photo::from_image`]: luminance in `[0, 1]` (large photos are reduced first);
//! - [`ink_map`]: the sheet found against its background, the paper's brightness flattened
//!   (a smooth field fitted to the bright paper), ink as coverage in `[0, 1]` (1 = ink);
//! - [`register`]: the registration marks ([`KnownMark`]) found among the blobs of ink, the
//!   corners told apart by the key mark, a [`Homography`] paper mm → photo px fitted to all
//!   marks' centres of ink, its residual in mm and the sharpness of the marks' edges. Lens
//!   distortion is not modelled: a straight line on the paper is taken to be straight in the
//!   photo;
//! - [`rectify`]: the ink resampled into a [`Frame`] of the paper (a character's image);
//! - [`measure_footprint`]: a single press's footprint (a calibration sheet's) measured on the
//!   paper: its ink rectified and the B-BSM outline fitted, giving `lt`, `lh`, `lr`;
//! - [`diagnose`]: observed against planned strokes: width ratio, ink beyond the ends, lateral
//!   offset, and a one-line verdict.
//!
//! The crate knows nothing of brushes or robots: what it compares is images and paths in mm.
//! See docs/closed-loop.md.
//!
//! # Examples
//! ```
//! use observe::{Frame, Homography};
//! // A frame 10 mm square at 4 px/mm whose top-left corner is paper (20, 30) mm.
//! let f = Frame { x0_mm: 20.0, y0_mm: 30.0, px_per_mm: 4.0, width: 40, height: 40 };
//! assert_eq!(f.centre_mm(0, 0), [20.125, 30.125]);
//! let id = Homography::identity();
//! assert_eq!(id.apply([3.0, 4.0]), [3.0, 4.0]);
//! ```

mod diagnose;
mod error;
mod footprint;
mod homography;
mod photo;
mod read;
mod rectify;
mod register;

pub use diagnose::{Diagnosis, StrokeDiagnosis, diagnose};
pub use error::ObserveError;
pub use footprint::{FOOTPRINT_MAX_PX_PER_MM, FOOTPRINT_MIN_PX_PER_MM, FootprintMeasure, measure_footprint};
pub use homography::Homography;
pub use photo::{InkMap, MAX_PHOTO_SIDE, Photo, ink_map};
pub use read::{SheetPhoto, read_sheet_photo};
pub use rectify::{Frame, rectify};
pub use register::{
    BLUR_LIMIT_MM, KnownMark, LEAVE_ONE_OUT_LIMIT_MM, MarkFit, RESIDUAL_LIMIT_MM, Registration, register,
};

// The README's example runs as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
