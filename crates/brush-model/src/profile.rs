//! Brush profiles: a brush, the press range it was calibrated over, and the linear model from
//! press to footprint (docs/contracts.md §4).
//!
//! Profiles are versioned JSON. The built-in `pen1` and `pen2` are *nominal*: their coefficients
//! come from the brush geometry (see `docs/brush-model.md`), not from measurements, and a
//! calibration (`maobi calibrate`) replaces them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::footprint::Footprint;
use crate::regression::{FitReport, LinearModel, Terms};
use crate::units::{Brush, Press, wrap_angle_rad};

/// The profile format version this crate writes. Version 2 added [`BrushProfile::hairs`]; a
/// version 1 file is still read (its hairs take [`HairMotion::NOMINAL`]) and written back as
/// version 2.
pub const PROFILE_VERSION: u32 = 2;

/// The oldest profile format version this crate reads.
pub const OLDEST_PROFILE_VERSION: u32 = 1;

/// The depth from which a brush's hairs follow its motion when nothing measured it, mm: the
/// nominal built-ins' and every profile's without a `hairs` field (a guess, not a
/// measurement: friction needs a press, and a brush whose hairs need about a millimetre of it
/// is the top of the range docs/brush-model.md, "Hairs that need a press", considers). The
/// closed loop fits it from a photo (docs/closed-loop.md).
pub const CONTACT_H_MM: f64 = 1.0;

/// The longest brush a profile may describe, mm (a metre: far beyond any writing brush).
pub const MAX_BRUSH_MM: f64 = 1000.0;

/// The largest profile file read, bytes (a profile with its fit report is about 4 KiB).
pub const MAX_PROFILE_BYTES: u64 = 1 << 20;

/// How many times the bundle's length a predicted footprint length may be: no brush leaves a
/// mark much longer than its hair, and a coefficient of 1e300 must not reach the renderers.
pub const MAX_FOOTPRINT_PER_LENGTH: f64 = 2.0;

/// A field that failed validation: its dotted path and what is wrong with it.
type BadField = (&'static str, String);

/// Errors from loading, validating or using a profile.
#[derive(Debug, Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The JSON is malformed or a field is missing or of the wrong type.
    #[error("{source_name}: not a valid brush profile")]
    Json {
        /// File name or other label.
        source_name: String,
        /// serde_json's error (names the field, line and column).
        #[source]
        source: serde_json::Error,
    },
    /// A field has an impossible value.
    #[error("{source_name}: field `{field}`: {reason}")]
    Invalid {
        /// File name or other label.
        source_name: String,
        /// Dotted path of the field.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A press lies outside the calibrated range and extrapolation was not allowed.
    #[error(
        "{quantity} = {value:.4} is outside the calibrated range [{min:.4}, {max:.4}] of profile `{profile}` (allow extrapolation to use it anyway)"
    )]
    OutOfRange {
        /// The profile's name.
        profile: String,
        /// Which quantity, with its unit.
        quantity: &'static str,
        /// The value asked for, in the quantity's unit.
        value: f64,
        /// Range minimum.
        min: f64,
        /// Range maximum.
        max: f64,
    },
    /// The model predicts a non-positive length for this press.
    #[error("profile `{profile}` predicts a non-positive {field} ({value:.4} mm) for this press")]
    Degenerate {
        /// The profile's name.
        profile: String,
        /// Which length.
        field: &'static str,
        /// The predicted value.
        value: f64,
    },
    /// The belly width does not depend on h, so no h gives a wanted width.
    #[error("profile `{profile}`: lr does not change with h, so h cannot be chosen from a width")]
    NotInvertible {
        /// The profile's name.
        profile: String,
    },
    /// The model predicts a length no brush of this size can leave (see
    /// [`MAX_FOOTPRINT_PER_LENGTH`]).
    #[error(
        "profile `{profile}` predicts {field} = {value:.4e} mm for this press, beyond the {max:.1} mm a {length:.1} mm brush can leave"
    )]
    Implausible {
        /// The profile's name.
        profile: String,
        /// Which length.
        field: &'static str,
        /// The predicted value.
        value: f64,
        /// The cap, mm.
        max: f64,
        /// The brush's length, mm.
        length: f64,
    },
    /// No built-in profile has this name.
    #[error("unknown built-in brush `{0}` (known: pen1, pen2, pen1-s84 … pen1-s25)")]
    UnknownBuiltin(String),
}

/// Where a profile's numbers come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// Derived from the brush geometry; to be replaced by a calibration.
    Nominal,
    /// Fitted from measurements.
    Calibrated,
}

/// A closed interval `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Lower end.
    pub min: f64,
    /// Upper end.
    pub max: f64,
}

impl Range {
    /// A range from its ends.
    pub const fn new(min: f64, max: f64) -> Self {
        Self { min, max }
    }
    /// Whether `v` lies in the range (with a relative tolerance of 1e-9).
    pub fn contains(&self, v: f64) -> bool {
        let tol = 1e-9 * self.min.abs().max(self.max.abs()).max(1.0);
        v >= self.min - tol && v <= self.max + tol
    }
    /// `v` clamped into the range.
    pub fn clamp(&self, v: f64) -> f64 {
        v.clamp(self.min, self.max)
    }
    /// The point at fraction `f ∈ [0, 1]` of the range.
    pub fn lerp(&self, f: f64) -> f64 {
        self.min + f * (self.max - self.min)
    }
}

/// The press ranges a profile is valid over (mm and radians).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressRanges {
    /// Press depth, mm.
    pub h_mm: Range,
    /// Tilt, radians.
    pub alpha_rad: Range,
    /// Rotation, radians.
    pub beta_rad: Range,
}

impl PressRanges {
    /// The smallest ranges that hold every measured press: the calibrated range of a fit to
    /// `rows` (empty ranges, from +∞ to −∞, when there are none).
    ///
    /// # Examples
    /// ```
    /// let rows = brush_model::read_measurements(
    ///     "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n2,0,0,3,1,1\n5,10,0,6,2,2\n".as_bytes(),
    ///     "example",
    /// )
    /// .unwrap();
    /// let r = brush_model::PressRanges::spanning(&rows);
    /// assert_eq!((r.h_mm.min, r.h_mm.max), (2.0, 5.0));
    /// ```
    pub fn spanning(rows: &[crate::Measurement]) -> PressRanges {
        let span = |f: fn(&crate::Measurement) -> f64| {
            let lo = rows.iter().map(f).fold(f64::INFINITY, f64::min);
            let hi = rows.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
            Range::new(lo, hi)
        };
        PressRanges {
            h_mm: span(|m| m.press.h_mm),
            alpha_rad: span(|m| m.press.alpha_rad),
            beta_rad: span(|m| m.press.beta_rad),
        }
    }

    /// The eight corner presses of the range box. With a linear model every footprint length
    /// takes its extremes at corners.
    pub fn corners(&self) -> Vec<Press> {
        let mut v = Vec::with_capacity(8);
        for h in [self.h_mm.min, self.h_mm.max] {
            for a in [self.alpha_rad.min, self.alpha_rad.max] {
                for b in [self.beta_rad.min, self.beta_rad.max] {
                    v.push(Press::new(h, a, b));
                }
            }
        }
        v
    }
}

/// Whether prediction may leave the calibrated range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Extrapolation {
    /// Refuse presses outside the calibrated range (the default).
    #[default]
    Refuse,
    /// Predict anyway.
    Allow,
}

/// Which way the inverse model clamped h.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Clamp {
    /// The exact solution lies inside the range.
    None,
    /// The wanted width needs less than the minimum h; the minimum is returned.
    Min,
    /// The wanted width needs more than the maximum h; the maximum is returned.
    Max,
}

/// The result of the inverse model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct InverseH {
    /// The press depth to use, mm (inside the calibrated range).
    pub h_mm: f64,
    /// The unclamped solution, mm.
    pub exact_h_mm: f64,
    /// Whether and which way it was clamped.
    pub clamped: Clamp,
}

/// How a brush's hairs follow its motion (the forward model's drag rule, docs/brush-model.md,
/// "The moving brush"): parameters of the brush, fitted from a photo by the closed loop as its
/// footprint lengths are.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HairMotion {
    /// An upright brush's tip lies on the path it pressed along this fraction of a footprint
    /// length behind it (straight-line distance), in (0, 1].
    #[serde(default = "default_trail_reach")]
    pub trail_reach: f64,
    /// The depth from which the hairs follow motion, mm: pressed lighter (`0 < h <
    /// contact_h_mm`), the brush touches the paper but neither inks nor turns its hairs, which
    /// keep their bend and move with it. 0 means any touch turns them (the forward model's
    /// rule before profile version 2).
    #[serde(default = "default_contact_h_mm")]
    pub contact_h_mm: f64,
}

impl HairMotion {
    /// Hairs as the nominal built-ins describe them: the tip [`crate::TRAIL_REACH`] footprint
    /// lengths back, following motion from [`CONTACT_H_MM`].
    pub const NOMINAL: HairMotion = HairMotion { trail_reach: crate::motion::TRAIL_REACH, contact_h_mm: CONTACT_H_MM };
}

impl Default for HairMotion {
    fn default() -> Self {
        Self::NOMINAL
    }
}

fn default_trail_reach() -> f64 {
    HairMotion::NOMINAL.trail_reach
}

fn default_contact_h_mm() -> f64 {
    HairMotion::NOMINAL.contact_h_mm
}

/// A brush profile.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushProfile {
    /// Format version ([`PROFILE_VERSION`]).
    pub version: u32,
    /// A short name, e.g. `pen1`.
    pub name: String,
    /// Where the coefficients come from.
    pub source: Source,
    /// The brush.
    pub brush: Brush,
    /// The calibrated press ranges.
    pub ranges: PressRanges,
    /// Footprint lengths as linear functions of `(h, α, β)`.
    pub model: LinearModel,
    /// How the hairs follow the brush's motion (absent before version 2:
    /// [`HairMotion::NOMINAL`]).
    #[serde(default)]
    pub hairs: HairMotion,
    /// The fit that produced the model, when calibrated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitReport>,
}

impl BrushProfile {
    /// A built-in nominal profile by name: `pen1`, `pen2` or a scaled `pen1-sNN`
    /// ([`BrushProfile::SCALED`]).
    ///
    /// # Errors
    /// [`ProfileError::UnknownBuiltin`] for any other name.
    pub fn builtin(name: &str) -> Result<Self, ProfileError> {
        match name {
            "pen1" => Ok(Self::nominal("pen1", Brush { length_mm: 48.0, radius_mm: 6.0 }, Range::new(11.0, 20.0))),
            "pen2" => {
                // The paper keeps the press under half the bundle length; scale pen1's h range by
                // the length ratio 32/48.
                let k = 32.0 / 48.0;
                Ok(Self::nominal("pen2", Brush { length_mm: 32.0, radius_mm: 4.5 }, Range::new(11.0 * k, 20.0 * k)))
            }
            other => match Self::builtin_scale(other) {
                Some(s) => Ok(Self::scaled_nominal(other, s)),
                None => Err(ProfileError::UnknownBuiltin(other.to_string())),
            },
        }
    }

    /// Names of the built-in profiles: pen1, pen2 and pen1's scalings ([`BrushProfile::SCALED`]).
    pub const BUILTINS: [&'static str; 10] = [
        "pen1", "pen2", "pen1-s84", "pen1-s71", "pen1-s59", "pen1-s50", "pen1-s42", "pen1-s35", "pen1-s30", "pen1-s25",
    ];

    /// The scaled nominal built-ins, largest first: pen1 with its length, radius and press range
    /// all scaled by `s = 2^(−k/4)` for the k-th name, k = 1…8 (steps of about 1.19 from 0.84
    /// down to 0.25), named `pen1-sNN` with NN the scale in percent, for characters smaller
    /// than pen1 suits. Every footprint length of the nominal model ([`BrushProfile::nominal`])
    /// is a sum of terms each proportional to a length (h, the mid press, the radius; R/L does
    /// not change), so each footprint of the scaled brush is pen1's at the scaled press, scaled
    /// by `s`: its width range, and the character size it suits, are pen1's times `s`. They are
    /// nominal (derived, not calibrated), like pen1.
    pub const SCALED: [&'static str; 8] =
        ["pen1-s84", "pen1-s71", "pen1-s59", "pen1-s50", "pen1-s42", "pen1-s35", "pen1-s30", "pen1-s25"];

    /// The scale of a [`BrushProfile::SCALED`] name (`None` for any other).
    pub fn builtin_scale(name: &str) -> Option<f64> {
        let k = Self::SCALED.iter().position(|n| *n == name)? + 1;
        Some(2f64.powf(-(k as f64) / 4.0))
    }

    /// pen1 scaled by `s` (see [`BrushProfile::SCALED`]), named `name`.
    fn scaled_nominal(name: &str, s: f64) -> Self {
        Self::nominal(name, Brush { length_mm: 48.0 * s, radius_mm: 6.0 * s }, Range::new(11.0 * s, 20.0 * s))
    }

    /// A nominal profile derived from the brush geometry over the paper's angle ranges
    /// (α 0–10°, β 0–5°). See `docs/brush-model.md` for the derivation of each coefficient.
    pub fn nominal(name: &str, brush: Brush, h_range: Range) -> Self {
        let (l, r) = (brush.length_mm, brush.radius_mm);
        let h_mid = 0.5 * (h_range.min + h_range.max);
        // Contact length grows in proportion to h (κ = 1.25 mm per mm), split 72/28 between tip
        // and root; tilting lays more hair on the paper, about h_mid mm per radian in total.
        let lt = Terms { intercept: 0.0, h_mm: Some(0.9), alpha_rad: Some(0.8 * h_mid), beta_rad: Some(0.0) };
        let lh = Terms { intercept: 0.0, h_mm: Some(0.35), alpha_rad: Some(0.2 * h_mid), beta_rad: Some(0.0) };
        // Belly half-width: the cone's radius R·h/L where it meets the paper, flattened by 1.6.
        let lr = Terms { intercept: 0.0, h_mm: Some(1.6 * r / l), alpha_rad: Some(0.1 * r), beta_rad: Some(0.0) };
        BrushProfile {
            version: PROFILE_VERSION,
            name: name.to_string(),
            source: Source::Nominal,
            brush,
            ranges: PressRanges {
                h_mm: h_range,
                alpha_rad: Range::new(0.0, 10f64.to_radians()),
                beta_rad: Range::new(0.0, 5f64.to_radians()),
            },
            model: LinearModel { lt_mm: lt, lh_mm: lh, lr_mm: lr },
            hairs: HairMotion::NOMINAL,
            fit: None,
        }
    }

    /// A calibrated profile from a fit, over the ranges spanned by the measurements.
    pub fn calibrated(name: &str, brush: Brush, ranges: PressRanges, fit: FitReport) -> Self {
        BrushProfile {
            version: PROFILE_VERSION,
            name: name.to_string(),
            source: Source::Calibrated,
            brush,
            ranges,
            model: fit.linear_model(),
            hairs: HairMotion::NOMINAL,
            fit: Some(fit),
        }
    }

    /// Loads and validates a profile from a JSON file.
    ///
    /// # Errors
    /// [`ProfileError::Io`], [`ProfileError::Json`] (names the missing or mistyped field, with
    /// line and column) or [`ProfileError::Invalid`].
    pub fn load(path: &Path) -> Result<Self, ProfileError> {
        let io = |source| ProfileError::Io { path: path.to_path_buf(), source };
        let len = std::fs::metadata(path).map_err(io)?.len();
        if len > MAX_PROFILE_BYTES {
            return Err(ProfileError::Invalid {
                source_name: path.display().to_string(),
                field: "(file)".into(),
                reason: format!("{len} bytes; a profile is at most {MAX_PROFILE_BYTES} bytes"),
            });
        }
        let too_large = || ProfileError::Invalid {
            source_name: path.display().to_string(),
            field: "(file)".into(),
            reason: format!("more than {MAX_PROFILE_BYTES} bytes; a profile is at most {MAX_PROFILE_BYTES} bytes"),
        };
        let bytes = crate::read_regular(path, MAX_PROFILE_BYTES).map_err(io)?.ok_or_else(too_large)?;
        let text = String::from_utf8(bytes)
            .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}"))))?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Parses and validates a profile; `source_name` labels errors. A version 1 profile is
    /// read with [`HairMotion::NOMINAL`] and comes back as version [`PROFILE_VERSION`].
    ///
    /// # Errors
    /// As [`BrushProfile::load`].
    pub fn from_json(text: &str, source_name: &str) -> Result<Self, ProfileError> {
        let mut p: BrushProfile = serde_json::from_str(text)
            .map_err(|source| ProfileError::Json { source_name: source_name.to_string(), source })?;
        p.validate(source_name)?;
        p.version = PROFILE_VERSION;
        Ok(p)
    }

    /// The profile as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("profile serialises")
    }

    /// Checks every field for impossible values.
    ///
    /// # Errors
    /// [`ProfileError::Invalid`] naming the first bad field.
    pub fn validate(&self, source_name: &str) -> Result<(), ProfileError> {
        self.check_identity()
            .and_then(|()| self.check_ranges())
            .and_then(|()| self.check_model())
            .and_then(|()| self.check_hairs())
            .map_err(|(field, reason)| ProfileError::Invalid {
                source_name: source_name.to_string(),
                field: field.to_string(),
                reason,
            })
    }

    /// Version, name and brush size.
    fn check_identity(&self) -> Result<(), BadField> {
        if !(OLDEST_PROFILE_VERSION..=PROFILE_VERSION).contains(&self.version) {
            return Err((
                "version",
                format!(
                    "unsupported version {} (this build reads {OLDEST_PROFILE_VERSION} to {PROFILE_VERSION})",
                    self.version
                ),
            ));
        }
        if self.name.trim().is_empty() {
            return Err(("name", "must not be empty".into()));
        }
        for (f, v) in [("brush.length_mm", self.brush.length_mm), ("brush.radius_mm", self.brush.radius_mm)] {
            if !(v.is_finite() && v > 0.0 && v <= MAX_BRUSH_MM) {
                return Err((f, format!("must be a length in mm above 0 and at most {MAX_BRUSH_MM}, got {v}")));
            }
        }
        Ok(())
    }

    /// The calibrated ranges: finite, not empty, within physical bounds.
    fn check_ranges(&self) -> Result<(), BadField> {
        for (f, r) in [
            ("ranges.h_mm", self.ranges.h_mm),
            ("ranges.alpha_rad", self.ranges.alpha_rad),
            ("ranges.beta_rad", self.ranges.beta_rad),
        ] {
            if !(r.min.is_finite() && r.max.is_finite()) {
                return Err((f, "ends must be finite".into()));
            }
            if r.min > r.max {
                return Err((f, format!("empty range: min {} > max {}", r.min, r.max)));
            }
        }
        if self.ranges.h_mm.min < 0.0 {
            return Err(("ranges.h_mm", "press depth cannot be negative".into()));
        }
        // Physical bounds: no press deeper than the hair, tilts short of lying flat, rotations
        // within a turn either way. They also bound every loop that walks a range.
        let half_pi = std::f64::consts::FRAC_PI_2;
        let tau = std::f64::consts::TAU;
        for (f, r, lo, hi, what) in [
            ("ranges.h_mm", self.ranges.h_mm, 0.0, self.brush.length_mm, "0 up to brush.length_mm"),
            ("ranges.alpha_rad", self.ranges.alpha_rad, -half_pi, half_pi, "−π/2..=π/2"),
            ("ranges.beta_rad", self.ranges.beta_rad, -tau, tau, "−2π..=2π"),
        ] {
            if r.min < lo || r.max > hi {
                let num = |v: f64| {
                    if v != 0.0 && !(1e-4..1e7).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
                };
                return Err((f, format!("[{}, {}] leaves {what} ({lo:.4}..={hi:.4})", num(r.min), num(r.max))));
            }
        }
        Ok(())
    }

    /// The model: finite coefficients, and at every corner of the ranges positive lengths no
    /// longer than [`BrushProfile::max_footprint_mm`].
    fn check_model(&self) -> Result<(), BadField> {
        for (f, t) in
            [("model.lt_mm", self.model.lt_mm), ("model.lh_mm", self.model.lh_mm), ("model.lr_mm", self.model.lr_mm)]
        {
            let vals = [Some(t.intercept), t.h_mm, t.alpha_rad, t.beta_rad];
            if vals.iter().flatten().any(|v| !v.is_finite()) {
                return Err((f, "coefficients must be finite".into()));
            }
        }
        for c in self.ranges.corners() {
            let fp = self.raw(&c);
            let corner = format!("at the range corner h={} α={} β={}", c.h_mm, c.alpha_rad, c.beta_rad);
            for (f, v) in [("model.lt_mm", fp[0]), ("model.lh_mm", fp[1]), ("model.lr_mm", fp[2])] {
                if v <= 0.0 {
                    return Err((f, format!("predicts {v:.4} mm {corner}; lengths must be positive")));
                }
                if v > self.max_footprint_mm() {
                    return Err((
                        f,
                        format!(
                            "predicts {v:.4e} mm {corner}; at most {:.1} mm ({MAX_FOOTPRINT_PER_LENGTH} × brush.length_mm)",
                            self.max_footprint_mm()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The hair motion: a trailing reach in (0, 1], a contact depth from 0 up to the bundle's
    /// length.
    fn check_hairs(&self) -> Result<(), BadField> {
        let r = self.hairs.trail_reach;
        if !(r.is_finite() && r > 0.0 && r <= 1.0) {
            return Err(("hairs.trail_reach", format!("must be a share of the footprint's length in (0, 1], got {r}")));
        }
        let c = self.hairs.contact_h_mm;
        if !(c.is_finite() && c >= 0.0 && c <= self.brush.length_mm) {
            return Err((
                "hairs.contact_h_mm",
                format!("must be a depth in mm from 0 up to brush.length_mm ({}), got {c}", self.brush.length_mm),
            ));
        }
        Ok(())
    }

    /// The longest footprint length this brush can leave, mm.
    pub fn max_footprint_mm(&self) -> f64 {
        MAX_FOOTPRINT_PER_LENGTH * self.brush.length_mm
    }

    fn raw(&self, p: &Press) -> [f64; 3] {
        let m = &self.model;
        [m.lt_mm, m.lh_mm, m.lr_mm].map(|t| t.eval(p.h_mm, p.alpha_rad, p.beta_rad))
    }

    fn check_range(&self, p: &Press) -> Result<(), ProfileError> {
        let r = &self.ranges;
        for (quantity, value, range) in
            [("h_mm", p.h_mm, r.h_mm), ("alpha_rad", p.alpha_rad, r.alpha_rad), ("beta_rad", p.beta_rad, r.beta_rad)]
        {
            if !range.contains(value) {
                return Err(ProfileError::OutOfRange {
                    profile: self.name.clone(),
                    quantity,
                    value,
                    min: range.min,
                    max: range.max,
                });
            }
        }
        Ok(())
    }

    /// The footprint this brush leaves for a press.
    ///
    /// # Errors
    /// [`ProfileError::OutOfRange`] outside the calibrated range unless `extrapolation` is
    /// [`Extrapolation::Allow`]; [`ProfileError::Degenerate`] if a length comes out non-positive.
    pub fn predict(&self, press: &Press, extrapolation: Extrapolation) -> Result<Footprint, ProfileError> {
        if extrapolation == Extrapolation::Refuse {
            self.check_range(press)?;
        }
        let [lt, lh, lr] = self.raw(press);
        for (field, value) in [("lt_mm", lt), ("lh_mm", lh), ("lr_mm", lr)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(ProfileError::Degenerate { profile: self.name.clone(), field, value });
            }
            if value > self.max_footprint_mm() {
                return Err(ProfileError::Implausible {
                    profile: self.name.clone(),
                    field,
                    value,
                    max: self.max_footprint_mm(),
                    length: self.brush.length_mm,
                });
            }
        }
        Ok(Footprint { lt_mm: lt, lh_mm: lh, lr_mm: lr })
    }

    /// The footprint for a press whose β is a writing direction (any angle). A round brush's
    /// footprint does not depend on which way it faces, so β enters the size model only
    /// reduced into the calibrated β range (wrapped to (−π, π], then clamped); the full β is for
    /// rotating the outline.
    ///
    /// # Errors
    /// As [`BrushProfile::predict`], for h and α.
    pub fn predict_oriented(&self, press: &Press, extrapolation: Extrapolation) -> Result<Footprint, ProfileError> {
        let b = wrap_angle_rad(press.beta_rad);
        let shape = Press::new(press.h_mm, press.alpha_rad, self.ranges.beta_rad.clamp(b));
        self.predict(&shape, extrapolation)
    }

    /// The press depth giving a belly half-width `lr_mm` at tilt `alpha_rad` and rotation
    /// `beta_rad` (closed form for the linear model), clamped to the calibrated h range.
    ///
    /// # Errors
    /// [`ProfileError::OutOfRange`] if α or β lie outside their ranges;
    /// [`ProfileError::NotInvertible`] if `lr` does not depend on h.
    pub fn h_for_half_width(&self, lr_mm: f64, alpha_rad: f64, beta_rad: f64) -> Result<InverseH, ProfileError> {
        self.check_range(&Press::new(self.ranges.h_mm.min, alpha_rad, beta_rad))?;
        let t = &self.model.lr_mm;
        let slope = t.h_mm.unwrap_or(0.0);
        if slope.abs() < 1e-12 {
            return Err(ProfileError::NotInvertible { profile: self.name.clone() });
        }
        let rest = t.eval(0.0, alpha_rad, beta_rad);
        let exact = (lr_mm - rest) / slope;
        let r = self.ranges.h_mm;
        let (h, clamped) = if exact < r.min {
            (r.min, Clamp::Min)
        } else if exact > r.max {
            (r.max, Clamp::Max)
        } else {
            (exact, Clamp::None)
        };
        Ok(InverseH { h_mm: h, exact_h_mm: exact, clamped })
    }

    /// The largest footprint extent over the calibrated range: the maximum over the range's
    /// corners of the outline's diagonal `hypot(x extent, 2·lr)`, mm. A canvas this wide holds
    /// any footprint of the range at any rotation.
    pub fn max_extent_mm(&self) -> f64 {
        self.ranges
            .corners()
            .iter()
            .filter_map(|c| self.predict(c, Extrapolation::Allow).ok())
            .map(|f| {
                let b = f.local_bounds();
                b.width().hypot(b.height())
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod scaled_tests {
    use super::*;

    /// A scaled pen1 leaves pen1's footprint scaled by s at the scaled press, at every corner of
    /// the press ranges: its width range is pen1's times s.
    #[test]
    fn a_scaled_brush_leaves_pen1s_footprints_scaled() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        for name in BrushProfile::SCALED {
            let s = BrushProfile::builtin_scale(name).unwrap();
            let b = BrushProfile::builtin(name).unwrap();
            assert_eq!(b.name, name);
            assert!((format!("pen1-s{:.0}", 100.0 * s) == name), "{name} is named by its scale {s}");
            for c in pen1.ranges.corners() {
                let f1 = pen1.predict(&c, Extrapolation::Refuse).unwrap();
                let scaled = Press { h_mm: c.h_mm * s, ..c };
                let fs = b.predict(&scaled, Extrapolation::Refuse).unwrap();
                for (a, z) in [(f1.lt_mm, fs.lt_mm), (f1.lh_mm, fs.lh_mm), (f1.lr_mm, fs.lr_mm)] {
                    assert!((a * s - z).abs() < 1e-9, "{name}: {z} vs {a}×{s}");
                }
            }
        }
        assert!(BrushProfile::builtin_scale("pen1").is_none());
    }
}
