//! # brush-model
//!
//! The physical core of maobi: how a hairy brush pressed into paper leaves a footprint.
//!
//! * Units: unit-carrying types ([`Brush`], [`Press`], [`TrackPoint`], [`Track`]); lengths
//!   in mm, angles in radians, units in every field name.
//! * The B-BSM footprint ([`Footprint`]: tip length `lt`, root length `lh`, belly
//!   half-width `lr`) as two mirrored cubic Béziers, placed on the paper by an anchor and `β`.
//! * Regression ([`fit_general`], [`fit_paper`], [`FitReport`]): the least-squares fits from measured presses to footprints (the paper's
//!   general Eq. 6 and its Eq. 1–5 form) with a statsmodels-style report.
//! * The measurements CSV ([`load_measurements`], [`Measurement`], [`measurement_fields`]).
//! * The forward model of the moving brush ([`ForwardModel`]): from the brush's
//!   commanded path (position, depth, tilt) to the footprints it leaves and which way they point.
//! * Profiles: versioned [`BrushProfile`] JSON, built-in nominal `pen1`/`pen2`, prediction
//!   and the inverse model (the h that gives a wanted width).
//!
//! ```
//! use brush_model::{BrushProfile, Extrapolation, Press};
//! let pen1 = BrushProfile::builtin("pen1").unwrap();
//! let fp = pen1.predict(&Press::from_degrees(15.0, 5.0, 0.0), Extrapolation::Refuse).unwrap();
//! assert!(fp.lt_mm > fp.lh_mm && fp.lr_mm < pen1.brush.radius_mm);
//! // A press deeper than the calibrated range is refused unless asked for.
//! assert!(pen1.predict(&Press::from_degrees(30.0, 0.0, 0.0), Extrapolation::Refuse).is_err());
//! ```

#![warn(unreachable_pub)]

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod footprint;
mod input;
mod measurements;
mod motion;
mod profile;
mod regression;
mod units;

pub use footprint::{BoundsMm, CubicMm, Footprint, GeometryError, Outline};
pub use input::{open_regular, read_regular};
pub use measurements::{
    MEASUREMENT_COLUMNS, Measurement, MeasurementError, load_measurements, measurement_fields, read_measurements,
    write_measurements,
};
pub use motion::{DEPTH_EDGE_TOLERANCE_MM, ForwardModel, Sweep, TILT_THRESHOLD_RAD, TRAIL_REACH};
pub use profile::{
    BrushProfile, CONTACT_H_MM, Clamp, Extrapolation, HairMotion, InverseH, MAX_BRUSH_MM, MAX_FOOTPRINT_PER_LENGTH,
    MAX_PROFILE_BYTES, OLDEST_PROFILE_VERSION, PROFILE_VERSION, PressRanges, ProfileError, Range, Source,
};
pub use regression::{FitError, FitReport, Form, LinearModel, OutputFit, Terms, fit, fit_general, fit_paper};
pub use units::{Brush, PointMm, Press, Stroke, Track, TrackPoint, deg_to_rad, rad_to_deg, wrap_angle_rad};
