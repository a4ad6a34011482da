//! The closed loop's correction (docs/closed-loop.md): what a photo of the last attempt showed
//! turned into the next attempt. Two levers: the brush ([`fit_brush`]: a width factor, a length
//! factor and a spread on top of the profile, fitted so that the last attempt's commanded track
//! rendered through the corrected profile matches the observed ink) and the track ([`Residual`],
//! [`ilc_target`], [`refine_observed`]: iterative learning control, the model's prediction of
//! the last attempt shifted by what the photo showed, and the next track refined so that the
//! model plus that residual matches the glyph). The brush fit also finds how the hairs follow
//! the motion (the profile's [`HairMotion`]: the trailing reach and the depth from which they
//! turn), so the corrected profile carries everything the next attempt is planned with.

use bezier_raster::{Coverage, ModelKind, Stamp, render_stamps, track_stamps};
use brush_model::{BrushProfile, Extrapolation, ForwardModel, HairMotion, PointMm, Stroke, Terms, Track};
use numerics::{NelderMead, nelder_mead};
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;
use track_refine::{RefineOptions, Target};
use trajectory::CharBox;
use trajectory::render_glyph;

use crate::write::refine_result;
use crate::{CharResult, Prepared, WriteOptions};

/// The side of the images the brush correction is fitted on, at most, px (the observed ink is
/// averaged down to it).
pub const FIT_PX: u32 = 96;

/// The bounds of a fitted width or length factor.
pub const FACTOR_RANGE: [f64; 2] = [0.5, 2.0];
/// The bounds of a fitted spread, mm.
pub const SPREAD_RANGE_MM: [f64; 2] = [-1.0, 2.0];

/// The least share of the profile's ink error a fitted correction must explain to be taken
/// (below it the fit is within what the brush's lag and trail, the photo and the fit's own
/// weakly determined directions leave, and the profile is kept).
pub const MIN_CORRECTION_GAIN: f64 = 0.2;

/// Nelder–Mead iterations of the brush fit.
const FIT_ITERS: usize = 40;

/// The forward model's sampling during the brush fit: coarser than the renderers' (0.1 mm),
/// fine against the fit images' pixels (about 1 mm or more) and footprints several mm long, and
/// ten times fewer footprints.
const FIT_MODEL: ForwardModel = ForwardModel {
    tilt_threshold_rad: brush_model::TILT_THRESHOLD_RAD,
    min_motion_mm: 0.3,
    step_mm: 1.0,
    step_rad: 0.5 * std::f64::consts::PI / 180.0,
    step_h_mm: 1.0,
};

/// The trailing reaches (an upright brush's tip on the path this fraction of a footprint length
/// back: [`HairMotion::trail_reach`]) the brush fit tries beside the profile's own.
pub const TRAIL_CANDIDATES: [f64; 5] = [0.2, 0.3, 0.4, 0.5, 0.6];

/// The depths from which the hairs follow motion ([`HairMotion::contact_h_mm`], mm) the brush
/// fit tries beside the profile's own, ascending; those at or past the profile's lightest
/// calibrated press are left out. A photo tells them apart only where the last attempt moved
/// the brush touching the paper between two of them (a glide lighter than one and deeper than
/// the other), so among depths that explain the ink equally the lightest is kept.
pub const CONTACT_CANDIDATES_MM: [f64; 7] = [0.0, 0.25, 0.5, 1.0, 2.0, 3.0, 4.0];

/// What the closed loop's correction can refuse.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ClosedLoopError {
    /// No characters were given.
    #[error("no observed characters to correct from")]
    Empty,
    /// An observed image is not square (it is a character box's frame).
    #[error("{ch}: the observed image is {width}×{height} px (expected a square, the character box's frame)")]
    NotSquare {
        /// The character.
        ch: String,
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
    /// The last attempt of a character has no strokes.
    #[error("{ch}: the last attempt has no strokes")]
    NoStrokes {
        /// The character.
        ch: String,
    },
    /// The corrected profile is not a valid profile (a factor took a length out of bounds).
    #[error("the corrected brush profile")]
    Profile(#[source] brush_model::ProfileError),
    /// Rendering the last attempt through a profile failed.
    #[error("{ch}: predicting the last attempt")]
    Predict {
        /// The character.
        ch: String,
        /// Why.
        #[source]
        source: brush_model::ProfileError,
    },
    /// The shifted glyph made no refinement target.
    #[error("{ch}: the shifted glyph")]
    Target {
        /// The character.
        ch: String,
        /// Why.
        #[source]
        source: Box<track_refine::RefineError>,
    },
    /// A profile is not the observed brush's base with a width, length and spread correction
    /// on top (so the correction cannot be carried over to another brush).
    #[error("{corrected} is not {base} with a correction on top ({component}: {why})")]
    NotACorrection {
        /// The corrected profile's name.
        corrected: String,
        /// The base profile's name.
        base: String,
        /// The footprint length that does not fit (`lt`, `lh` or `lr`).
        component: &'static str,
        /// What does not fit.
        why: &'static str,
    },
    /// Writing the next attempt failed.
    #[error(transparent)]
    Pipeline(Box<crate::Error>),
}

impl From<crate::Error> for ClosedLoopError {
    fn from(e: crate::Error) -> Self {
        ClosedLoopError::Pipeline(Box::new(e))
    }
}

/// One character of the last attempt: where it sat, what was commanded and what the photo
/// showed.
#[derive(Clone, Copy, Debug)]
pub struct LastAttempt<'a> {
    /// The character (for messages).
    pub ch: &'a str,
    /// Its box on the paper, mm.
    pub char_box: CharBox,
    /// The commanded strokes of its track, paper mm.
    pub strokes: &'a [Stroke],
    /// The observed ink over the box (`maobi observe`'s `observed.png`: the box at its side in
    /// px, ink = 1).
    pub observed: &'a Coverage,
}

/// A correction on top of a brush profile: every footprint's tip and root lengths scaled by
/// `length_factor`, its belly half-width by `width_factor`, then `spread_mm` added to all three
/// (ink spreading past the outline). Applied to the profile's linear model
/// ([`BrushCorrection::apply`]), so it is a normal profile.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BrushCorrection {
    /// Belly half-width factor.
    pub width_factor: f64,
    /// Tip and root length factor.
    pub length_factor: f64,
    /// Added to tip length, root length and belly half-width, mm.
    pub spread_mm: f64,
    /// Mean squared difference between the observed ink and the last attempt predicted by the
    /// profile, per pixel of the fit images.
    pub ink_error_before: f64,
    /// The same through the corrected profile.
    pub ink_error_after: f64,
    /// A correction that was fitted but not taken (it explained less than
    /// [`MIN_CORRECTION_GAIN`] of the error; the factors above are then 1 and the spread 0):
    /// `[width factor, length factor, spread mm, ink error]`.
    pub not_taken: Option<[f64; 4]>,
    /// The hair motion the factors were fitted under, written into the corrected profile by
    /// [`BrushCorrection::apply`] (`None`: the profile's own is kept). [`fit_brush`] sets it:
    /// the profile's own trailing reach and contact depth unless another candidate
    /// ([`TRAIL_CANDIDATES`], [`CONTACT_CANDIDATES_MM`]) explained the ink better by at least
    /// [`MIN_CORRECTION_GAIN`] of what remained. Fitted so that hairs that trail or turn
    /// otherwise do not bias the lengths; the corrected profile carries it, so the next
    /// attempt's track is planned, refined, rendered and its residual predicted with it, and the
    /// next round's fit starts from it.
    pub hairs: Option<HairMotion>,
}

impl BrushCorrection {
    /// No change.
    pub const IDENTITY: BrushCorrection = BrushCorrection {
        width_factor: 1.0,
        length_factor: 1.0,
        spread_mm: 0.0,
        ink_error_before: 0.0,
        ink_error_after: 0.0,
        not_taken: None,
        hairs: None,
    };

    /// `profile` with this correction applied to its model (every coefficient of `lt` and
    /// `lh` times the length factor and of `lr` times the width factor, the spread added to
    /// each intercept) and its hairs (when [`BrushCorrection::hairs`] is set), named `name`,
    /// checked as a loaded profile is.
    ///
    /// # Errors
    /// [`ClosedLoopError::Profile`] when the corrected model predicts a length out of bounds at
    /// a corner of the calibrated range.
    ///
    /// # Examples
    /// ```
    /// use pipeline::BrushCorrection;
    /// use brush_model::{BrushProfile, Extrapolation, Press};
    ///
    /// let pen1 = BrushProfile::builtin("pen1")?;
    /// let c = BrushCorrection { width_factor: 1.2, spread_mm: 0.1, ..BrushCorrection::IDENTITY };
    /// let fat = c.apply(&pen1, "pen1-observed")?;
    /// let press = Press::new(15.0, 0.0, 0.0);
    /// let (a, b) = (pen1.predict(&press, Extrapolation::Refuse)?, fat.predict(&press, Extrapolation::Refuse)?);
    /// assert!((b.lr_mm - (1.2 * a.lr_mm + 0.1)).abs() < 1e-12);
    /// assert!((b.lt_mm - (a.lt_mm + 0.1)).abs() < 1e-12);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn apply(&self, profile: &BrushProfile, name: &str) -> Result<BrushProfile, ClosedLoopError> {
        let scale = |t: Terms, k: f64| Terms {
            intercept: k * t.intercept + self.spread_mm,
            h_mm: t.h_mm.map(|v| k * v),
            alpha_rad: t.alpha_rad.map(|v| k * v),
            beta_rad: t.beta_rad.map(|v| k * v),
        };
        let mut out = profile.clone();
        out.name = name.to_string();
        out.model.lt_mm = scale(profile.model.lt_mm, self.length_factor);
        out.model.lh_mm = scale(profile.model.lh_mm, self.length_factor);
        out.model.lr_mm = scale(profile.model.lr_mm, self.width_factor);
        if let Some(h) = self.hairs {
            out.hairs = h;
        }
        // The fit statistics were the old model's.
        out.fit = None;
        out.validate(name).map_err(ClosedLoopError::Profile)?;
        Ok(out)
    }
}

/// The correction `corrected` carries on top of `base`, per footprint length: `(k, s)` with every
/// term of `corrected` `k` times `base`'s and its intercept `k·b + s` (`lt` and `lh` share one
/// pair after one [`BrushCorrection`], `lr` has its own; after several rounds the spreads of
/// lengths and width differ, so the pairs are kept per length).
fn correction_of(base: &BrushProfile, corrected: &BrushProfile) -> Result<[(f64, f64); 3], ClosedLoopError> {
    let (b, c) = (&base.model, &corrected.model);
    let mut out = [(1.0, 0.0); 3];
    for (k, (component, tb, tc)) in
        [("lt", b.lt_mm, c.lt_mm), ("lh", b.lh_mm, c.lh_mm), ("lr", b.lr_mm, c.lr_mm)].into_iter().enumerate()
    {
        let err = |why| ClosedLoopError::NotACorrection {
            corrected: corrected.name.clone(),
            base: base.name.clone(),
            component,
            why,
        };
        let (hb, hc) = (tb.h_mm.unwrap_or(0.0), tc.h_mm.unwrap_or(0.0));
        if !(hb.abs() > 1e-9 && (hc / hb).is_finite() && hc / hb > 0.0) {
            return Err(err("no positive ratio of the depth terms"));
        }
        let f = hc / hb;
        let same = |x: Option<f64>, y: Option<f64>| {
            let (x, y) = (x.unwrap_or(0.0), y.unwrap_or(0.0));
            (f * x - y).abs() <= 1e-9 * (1.0 + y.abs())
        };
        if !(same(tb.alpha_rad, tc.alpha_rad) && same(tb.beta_rad, tc.beta_rad)) {
            return Err(err("the tilt terms are not scaled as the depth term is"));
        }
        out[k] = (f, tc.intercept - f * tb.intercept);
    }
    Ok(out)
}

/// `to` with the correction that turns `base` into `corrected` (every round's width and length
/// factors and spreads so far) carried over, and `corrected`'s hairs, named `name`: the brush
/// `to` as the robot's ink, paper and hairs would make it write, on the assumption that they
/// change `to`'s footprints as they changed `base`'s (the factors scale every term, the spreads
/// add to the intercepts) and that its hairs trail the same share of a footprint and follow
/// from the same depth.
///
/// # Errors
/// [`ClosedLoopError::NotACorrection`] when `corrected` is not `base` with per-length factors
/// and spreads on top; [`ClosedLoopError::Profile`] when the carried-over model predicts a
/// length out of bounds over `to`'s calibrated range.
///
/// # Examples
/// ```
/// use pipeline::{BrushCorrection, carry_correction};
/// use brush_model::{BrushProfile, Extrapolation, Press};
///
/// let (s71, s59) = (BrushProfile::builtin("pen1-s71")?, BrushProfile::builtin("pen1-s59")?);
/// let c = BrushCorrection { width_factor: 1.2, spread_mm: 0.3, ..BrushCorrection::IDENTITY };
/// let fat71 = c.apply(&s71, "pen1-s71+observed1")?;
/// let fat59 = carry_correction(&s71, &fat71, &s59, "pen1-s59+observed1")?;
/// let press = Press::new(7.0, 0.0, 0.0);
/// let (a, b) = (s59.predict(&press, Extrapolation::Refuse)?, fat59.predict(&press, Extrapolation::Refuse)?);
/// assert!((b.lr_mm - (1.2 * a.lr_mm + 0.3)).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn carry_correction(
    base: &BrushProfile,
    corrected: &BrushProfile,
    to: &BrushProfile,
    name: &str,
) -> Result<BrushProfile, ClosedLoopError> {
    let [lt, lh, lr] = correction_of(base, corrected)?;
    let scale = |t: Terms, (k, s): (f64, f64)| Terms {
        intercept: k * t.intercept + s,
        h_mm: t.h_mm.map(|v| k * v),
        alpha_rad: t.alpha_rad.map(|v| k * v),
        beta_rad: t.beta_rad.map(|v| k * v),
    };
    let mut out = to.clone();
    out.name = name.to_string();
    out.model.lt_mm = scale(to.model.lt_mm, lt);
    out.model.lh_mm = scale(to.model.lh_mm, lh);
    out.model.lr_mm = scale(to.model.lr_mm, lr);
    out.hairs = corrected.hairs;
    out.fit = None;
    out.validate(name).map_err(ClosedLoopError::Profile)?;
    Ok(out)
}

/// The brush for the next attempt after a correction: among `candidates` (the base brushes the
/// robot could hold, e.g. [`crate::builtin_brushes`]), each with the correction that turns
/// `base` into `corrected` carried over ([`carry_correction`], named `<candidate><suffix>`),
/// the one [`crate::choose_brush`] picks for `prepared` in `char_mm` boxes: the same rule as
/// `--brush auto`, applied to the corrected footprints. A candidate the correction cannot be
/// carried to (a length out of bounds) is left out. A brush writing wider than its profile
/// says suits larger characters, so a smaller base brush may suit the box better.
///
/// # Errors
/// [`ClosedLoopError::NotACorrection`] when `corrected` is not `base` with a correction on
/// top; [`ClosedLoopError::Profile`] when no candidate takes the correction.
pub fn choose_corrected_brush(
    prepared: &[Prepared],
    base: &BrushProfile,
    corrected: &BrushProfile,
    candidates: &[BrushProfile],
    suffix: &str,
    char_mm: f64,
    alpha_rad: f64,
) -> Result<crate::BrushChoice, ClosedLoopError> {
    correction_of(base, corrected)?;
    let mut carried = Vec::new();
    let mut last_err = None;
    for c in candidates {
        match carry_correction(base, corrected, c, &format!("{}{suffix}", c.name)) {
            Ok(p) => carried.push(p),
            Err(e) => last_err = Some(e),
        }
    }
    if carried.is_empty() {
        return Err(last_err.unwrap_or(ClosedLoopError::Empty));
    }
    Ok(crate::choose_brush(prepared, &carried, char_mm, alpha_rad))
}

/// `img` (square) averaged onto `side²` px: each output pixel the mean of a k × k grid of
/// bilinear samples over its area (k the ratio of the sides, rounded up).
fn resample(img: &Coverage, side: u32) -> Vec<f32> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if img.width() == side && img.height() == side {
        return img.data().to_vec();
    }
    let scale = w as f64 / side as f64;
    let k = scale.ceil().max(1.0) as usize;
    let d = img.data();
    let at = |x: f64, y: f64| -> f64 {
        let (fx, fy) = ((x - 0.5).clamp(0.0, w as f64 - 1.0), (y - 0.5).clamp(0.0, h as f64 - 1.0));
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let g = |x: usize, y: usize| d[y * w + x] as f64;
        (g(x0, y0) * (1.0 - tx) + g(x1, y0) * tx) * (1.0 - ty) + (g(x0, y1) * (1.0 - tx) + g(x1, y1) * tx) * ty
    };
    let n = side as usize;
    let mut out = vec![0f32; n * n];
    for j in 0..n {
        for i in 0..n {
            let mut s = 0.0;
            for b in 0..k {
                for a in 0..k {
                    let x = (i as f64 + (a as f64 + 0.5) / k as f64) * scale;
                    let y = (j as f64 + (b as f64 + 0.5) / k as f64) * scale;
                    s += at(x, y);
                }
            }
            out[j * n + i] = (s / (k * k) as f64) as f32;
        }
    }
    out
}

fn check_attempt(a: &LastAttempt<'_>) -> Result<(), ClosedLoopError> {
    if a.observed.width() != a.observed.height() || a.observed.width() == 0 {
        return Err(ClosedLoopError::NotSquare {
            ch: a.ch.to_string(),
            width: a.observed.width(),
            height: a.observed.height(),
        });
    }
    if a.strokes.is_empty() {
        return Err(ClosedLoopError::NoStrokes { ch: a.ch.to_string() });
    }
    Ok(())
}

/// The last attempt as `profile` predicts it: its commanded strokes through the forward model
/// (the profile's footprints and hairs) over its box at `side²` px.
///
/// # Errors
/// [`ClosedLoopError::Predict`] when the profile refuses a press (extrapolation is allowed, so
/// only a degenerate or implausible length).
pub fn predict_attempt(
    a: &LastAttempt<'_>,
    profile: &BrushProfile,
    model: ModelKind,
    side: u32,
) -> Result<Coverage, ClosedLoopError> {
    let track = Track { strokes: a.strokes.to_vec() };
    let stamps = track_stamps(&track, profile, Extrapolation::Allow)
        .map_err(|source| ClosedLoopError::Predict { ch: a.ch.to_string(), source })?;
    let b = a.char_box;
    Ok(render_stamps(&stamps, model.model(), PointMm::new(b.x0_mm, b.y0_mm), side as f64 / b.size_mm, side, side))
}

/// The last attempt through `profile` as the brush fit sees it ([`FIT_MODEL`]'s sampling) at
/// `side²` px; `None` when the profile refuses a press.
fn fit_render(a: &LastAttempt<'_>, profile: &BrushProfile, model: ModelKind, side: u32) -> Option<Coverage> {
    let mut stamps = Vec::new();
    for s in a.strokes {
        for p in FIT_MODEL.sweep(profile, &s.points, Extrapolation::Allow).stamps {
            let footprint = profile.predict_oriented(&p.press(), Extrapolation::Allow).ok()?;
            stamps.push(Stamp { footprint, anchor: p.anchor(), beta_rad: p.beta_rad });
        }
    }
    let b = a.char_box;
    Some(render_stamps(&stamps, model.model(), PointMm::new(b.x0_mm, b.y0_mm), side as f64 / b.size_mm, side, side))
}

/// Fits a [`BrushCorrection`] on top of `profile` from the last attempts: Nelder–Mead over
/// (width factor, length factor, spread) from (1, 1, 0), minimising the mean squared
/// difference between each character's observed ink and its commanded strokes rendered through
/// the corrected profile (both at up to [`FIT_PX`] px a side; the forward model sampled every
/// 1 mm instead of 0.1 mm), within [`FACTOR_RANGE`] and [`SPREAD_RANGE_MM`]; under each
/// trailing reach of [`TRAIL_CANDIDATES`] and the profile's own (with the profile's contact
/// depth), then under each contact depth of [`CONTACT_CANDIDATES_MM`] and the profile's own
/// (with the reach kept). A reach or a depth other than the profile's is kept only when it
/// explains at least [`MIN_CORRECTION_GAIN`] of the ink error the profile's own leaves after its
/// fit; the hairs kept are [`BrushCorrection::hairs`]. Deterministic. A correction whose factors
/// and spread explain less than [`MIN_CORRECTION_GAIN`] of the profile's ink error is not taken:
/// the factors are the identity's, the fitted values in [`BrushCorrection::not_taken`] (the
/// hairs are still the fitted ones).
///
/// # Errors
/// [`ClosedLoopError::Empty`], [`ClosedLoopError::NotSquare`], [`ClosedLoopError::NoStrokes`]
/// for unusable attempts; [`ClosedLoopError::Predict`] when the profile itself refuses the
/// last attempt's presses.
///
/// # Examples
/// A character written by a brush 30 % wider than the profile says is fitted back:
/// ```
/// use pipeline::{BrushCorrection, LastAttempt, fit_brush, predict_attempt};
/// use brush_model::{BrushProfile, Stroke, TrackPoint};
/// use trajectory::CharBox;
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// let pt = |x_mm: f64, h_mm: f64| TrackPoint { x_mm, y_mm: 40.0, h_mm, alpha_rad: 0.0, beta_rad: 0.0 };
/// let strokes = vec![Stroke { points: (0..=40).map(|i| pt(15.0 + i as f64, 11.0 + 0.2 * i as f64)).collect() }];
/// let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 80.0 };
/// let truth = BrushCorrection { width_factor: 1.3, ..BrushCorrection::IDENTITY }.apply(&pen1, "world")?;
/// let a = LastAttempt { ch: "一", char_box, strokes: &strokes, observed: &bezier_raster::Coverage::new(1, 1) };
/// let observed = predict_attempt(&a, &truth, bezier_raster::ModelKind::Bsm, 96)?;
/// let fit = fit_brush(&[LastAttempt { observed: &observed, ..a }], &pen1, bezier_raster::ModelKind::Bsm)?;
/// assert!(fit.ink_error_after < 0.2 * fit.ink_error_before, "{fit:?}");
/// assert!((fit.width_factor - 1.3).abs() < 0.1, "{fit:?}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn fit_brush(
    attempts: &[LastAttempt<'_>],
    profile: &BrushProfile,
    model: ModelKind,
) -> Result<BrushCorrection, ClosedLoopError> {
    if attempts.is_empty() {
        return Err(ClosedLoopError::Empty);
    }
    attempts.iter().try_for_each(check_attempt)?;
    let sides: Vec<u32> = attempts.iter().map(|a| a.observed.width().min(FIT_PX)).collect();
    let observed: Vec<Vec<f32>> = attempts.iter().zip(&sides).map(|(a, &s)| resample(a.observed, s)).collect();
    // Checks that the profile itself can predict every attempt (a real error, not a bad guess).
    for (a, &s) in attempts.iter().zip(&sides) {
        predict_attempt(a, profile, model, s)?;
    }
    let error_of = |p: &BrushProfile| -> f64 {
        let per: Vec<f64> = attempts
            .par_iter()
            .zip(sides.par_iter())
            .zip(observed.par_iter())
            .map(|((a, &s), obs)| match fit_render(a, p, model, s) {
                Some(img) => {
                    img.data().iter().zip(obs).map(|(&u, &o)| (u as f64 - o as f64).powi(2)).sum::<f64>()
                        / obs.len() as f64
                }
                None => f64::INFINITY,
            })
            .collect();
        per.iter().sum::<f64>() / per.len() as f64
    };
    let loss = |x: &[f64; 3], hairs: HairMotion| -> f64 {
        let inside = |v: f64, r: [f64; 2]| (r[0]..=r[1]).contains(&v);
        if !(inside(x[0], FACTOR_RANGE) && inside(x[1], FACTOR_RANGE) && inside(x[2], SPREAD_RANGE_MM)) {
            return f64::INFINITY;
        }
        let c = BrushCorrection {
            width_factor: x[0],
            length_factor: x[1],
            spread_mm: x[2],
            hairs: Some(hairs),
            ..BrushCorrection::IDENTITY
        };
        match c.apply(profile, &profile.name) {
            Ok(p) => error_of(&p),
            Err(_) => f64::INFINITY,
        }
    };
    let opts = NelderMead { min_spread: Some(1e-5), ..NelderMead::new([0.15, 0.15, 0.2], FIT_ITERS) };
    let fit_under = |hairs: HairMotion| -> HairFit {
        let (x, after) = nelder_mead(|x: &[f64; 3]| loss(x, hairs), [1.0, 1.0, 0.0], &opts);
        HairFit { hairs, before: loss(&[1.0, 1.0, 0.0], hairs), x, after }
    };
    // The trailing reach, under the profile's contact depth.
    let own = fit_under(profile.hairs);
    let reaches = TRAIL_CANDIDATES
        .iter()
        .filter(|&&r| r != profile.hairs.trail_reach)
        .map(|&trail_reach| fit_under(HairMotion { trail_reach, ..profile.hairs }));
    let by_reach = own.or_better(reaches);
    // The contact depth, under that reach. A depth that renders every attempt as the kept one
    // does at the fit so far cannot be told apart from it on these photos: not fitted again.
    let kept = by_reach.hairs;
    let same = loss(&by_reach.x, kept);
    let depths = CONTACT_CANDIDATES_MM
        .iter()
        .filter(|&&c| c != kept.contact_h_mm && c < profile.ranges.h_mm.min)
        .map(|&contact_h_mm| HairMotion { contact_h_mm, ..kept })
        .filter(|&h| loss(&by_reach.x, h) != same)
        .map(fit_under);
    let HairFit { hairs, before, x, after } = by_reach.or_better(depths);
    if !(after < (1.0 - MIN_CORRECTION_GAIN) * before) {
        return Ok(BrushCorrection {
            ink_error_before: before,
            ink_error_after: before,
            not_taken: Some([x[0], x[1], x[2], after]),
            hairs: Some(hairs),
            ..BrushCorrection::IDENTITY
        });
    }
    Ok(BrushCorrection {
        width_factor: x[0],
        length_factor: x[1],
        spread_mm: x[2],
        ink_error_before: before,
        ink_error_after: after,
        not_taken: None,
        hairs: Some(hairs),
    })
}

/// The brush fit under one hair motion: the profile's ink error under it, the fitted (width
/// factor, length factor, spread) and the error after.
#[derive(Clone, Copy, Debug)]
struct HairFit {
    hairs: HairMotion,
    before: f64,
    x: [f64; 3],
    after: f64,
}

impl HairFit {
    /// The best of `others` when it explains at least [`MIN_CORRECTION_GAIN`] of the error this
    /// one leaves, else this one; among equals the first (so, the candidates ascending, the
    /// lightest contact depth).
    fn or_better(self, others: impl Iterator<Item = HairFit>) -> HairFit {
        let best = others.fold(None::<HairFit>, |b, f| match b {
            Some(b) if b.after <= f.after => Some(b),
            _ => Some(f),
        });
        match best {
            Some(b) if b.after < (1.0 - MIN_CORRECTION_GAIN) * self.after => b,
            _ => self,
        }
    }
}

/// What the photo showed beyond the model: the observed ink minus the model's prediction of
/// the last attempt, over the character's box (`side²` px, row-major; positive where the paper
/// has more ink than predicted).
#[derive(Clone, Debug, PartialEq)]
pub struct Residual {
    /// Side, px.
    pub side: u32,
    /// `observed − predicted`, in [−1, 1], row-major.
    pub values: Vec<f32>,
}

impl Residual {
    /// The residual of one attempt: `observed − predict_attempt(profile)`, at the observed
    /// image's side. Take `profile` as the corrected one, so the residual holds only what the
    /// corrected brush (its footprints and its fitted hairs) does not explain.
    ///
    /// # Errors
    /// As [`predict_attempt`]; [`ClosedLoopError::NotSquare`] or
    /// [`ClosedLoopError::NoStrokes`] for an unusable attempt.
    pub fn of(a: &LastAttempt<'_>, profile: &BrushProfile, model: ModelKind) -> Result<Self, ClosedLoopError> {
        check_attempt(a)?;
        let side = a.observed.width();
        let predicted = predict_attempt(a, profile, model, side)?;
        let values = a.observed.data().iter().zip(predicted.data()).map(|(&o, &p)| o - p).collect();
        Ok(Self { side, values })
    }

    /// Mean absolute residual per pixel.
    pub fn mean_abs(&self) -> f64 {
        self.values.iter().map(|v| v.abs() as f64).sum::<f64>() / self.values.len().max(1) as f64
    }

    /// The residual averaged onto `side²` px.
    fn resampled(&self, side: u32) -> Vec<f32> {
        // Shifted into [0, 1] to reuse the coverage resampler, then back.
        let mut c = Coverage::new(self.side, self.side);
        for (d, v) in c.data_mut().iter_mut().zip(&self.values) {
            *d = 0.5 + 0.5 * v;
        }
        resample(&c, side).into_iter().map(|v| 2.0 * v - 1.0).collect()
    }
}

/// The learning gain of the ILC step: the target is the glyph shifted by this many times the
/// residual (1 would aim the model's render plus the residual exactly at the glyph; the
/// refinement, held to the track's shape by its regularisers, moves only part of the way, so a
/// gain above 1 asks for more). How it was chosen: docs/closed-loop.md.
const ILC_GAIN: f32 = 1.5;

/// The ILC target: the glyph shifted by the residual times the learning gain `γ` (1.5),
/// `clamp(G − γ·R, 0, 1)` at `px²` over the character's box (`G` the glyph raster as
/// [`crate::refine_target`] renders it, `R` the residual averaged onto the same pixels).
/// Refining a track against it makes the model's render plus the residual approach the glyph
/// (the clamp only drops targets the soft union, which lies in [0, 1], cannot reach).
///
/// # Errors
/// [`ClosedLoopError::Target`] when `px` or the box make no usable target.
pub fn ilc_target(
    glyph: &trajectory::Glyph,
    char_box: &CharBox,
    residual: &Residual,
    px: u32,
) -> Result<Target, ClosedLoopError> {
    let g = render_glyph(glyph, px);
    let r = residual.resampled(px);
    let ink = g.data().iter().zip(&r).map(|(&g, &r)| (g - ILC_GAIN * r).clamp(0.0, 1.0)).collect();
    Target::new(px, px, ink, PointMm::new(char_box.x0_mm, char_box.y0_mm), char_box.size_mm / px as f64)
        .map_err(|source| ClosedLoopError::Target { ch: glyph.ch.to_string(), source: Box::new(source) })
}

/// Refines each written character's track against its ILC target ([`ilc_target`] with its
/// residual), in parallel, replacing the result's track, renders and figures as
/// [`crate::write_char`]'s refinement does (figures against the glyph; the built track's are
/// kept as "before"; a refined track that fails the robot check is not used). `results`,
/// `prepared` and `residuals` are in the same order.
///
/// With `starts` (one stroke list per character, paper mm: the last attempt's tracks, when they
/// were written with `profile` in the same boxes), each refinement starts from the last
/// attempt's track instead of the built one, as iterative learning control takes the next input
/// from the last: the residual was measured at that track, so the refinement moves only as far
/// from it as the residual asks. A refined track that is not used leaves the built one.
///
/// # Errors
/// [`ClosedLoopError::Target`] or the pipeline's error for the first character that fails.
pub fn refine_observed(
    results: &mut [CharResult],
    prepared: &[Prepared],
    residuals: &[Residual],
    starts: Option<&[&[Stroke]]>,
    profile: &BrushProfile,
    opts: &WriteOptions,
    ro: &RefineOptions,
) -> Result<(), ClosedLoopError> {
    results.par_iter_mut().zip(prepared.par_iter()).zip(residuals.par_iter()).enumerate().try_for_each(
        |(i, ((r, p), res))| {
            let target = ilc_target(&p.glyph, &r.char_box, res, ro.analysis_px)?;
            let built = match starts.and_then(|s| s.get(i)) {
                Some(s) => Some(std::mem::replace(&mut r.track, Track { strokes: s.to_vec() })),
                None => None,
            };
            refine_result(r, p, profile, opts, ro, &target)?;
            if let Some(built) = built
                && r.report.refine.as_ref().is_some_and(|x| x.rejected.is_some())
            {
                r.track = built;
            }
            Ok(())
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_the_mean_and_a_residual_round_trips() {
        let mut c = Coverage::new(8, 8);
        for (k, v) in c.data_mut().iter_mut().enumerate() {
            *v = if (k % 8) < 4 { 1.0 } else { 0.0 };
        }
        let half = resample(&c, 4);
        assert_eq!(half.len(), 16);
        let mean = half.iter().sum::<f32>() / 16.0;
        assert!((mean - 0.5).abs() < 1e-6, "{half:?}");
        assert!(half[0] > 0.99 && half[3] < 0.01, "{half:?}");
        let r = Residual { side: 2, values: vec![-1.0, 0.5, 0.0, 1.0] };
        let same = r.resampled(2);
        for (a, b) in same.iter().zip(&r.values) {
            assert!((a - b).abs() < 1e-6, "{same:?}");
        }
        assert!((r.mean_abs() - 0.625).abs() < 1e-12);
    }

    /// Half a circle of radius 20 mm, upright, pressed 12–15 mm: where the tip lies on the path
    /// behind decides which way each footprint points round the curve.
    fn half_circle() -> Vec<Stroke> {
        let pts = (0..=200)
            .map(|i| {
                let t = f64::from(i) / 200.0;
                let a = std::f64::consts::PI * t;
                brush_model::TrackPoint {
                    x_mm: 40.0 - 20.0 * a.cos(),
                    y_mm: 30.0 + 20.0 * a.sin(),
                    h_mm: 12.0 + 3.0 * t,
                    alpha_rad: 0.0,
                    beta_rad: 0.0,
                }
            })
            .collect();
        vec![Stroke { points: pts }]
    }

    /// `profile` with other hairs.
    fn with_hairs(profile: &BrushProfile, trail_reach: f64, contact_h_mm: f64) -> BrushProfile {
        BrushProfile { hairs: HairMotion { trail_reach, contact_h_mm }, ..profile.clone() }
    }

    #[test]
    fn a_brush_whose_tip_trails_less_is_fitted_under_its_own_trail() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let strokes = half_circle();
        let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 80.0 };
        let wide = BrushCorrection { width_factor: 1.2, ..BrushCorrection::IDENTITY }.apply(&pen1, "world").unwrap();
        let blank = Coverage::new(96, 96);
        let a = LastAttempt { ch: "~", char_box, strokes: &strokes, observed: &blank };
        for reach in [0.3, brush_model::TRAIL_REACH] {
            let truth = with_hairs(&wide, reach, pen1.hairs.contact_h_mm);
            let observed = predict_attempt(&a, &truth, ModelKind::Bsm, 96).unwrap();
            let fit = fit_brush(&[LastAttempt { observed: &observed, ..a }], &pen1, ModelKind::Bsm).unwrap();
            assert_eq!(fit.hairs.map(|h| h.trail_reach), Some(reach), "{fit:?}");
            assert!((fit.width_factor - 1.2).abs() < 0.05 && (fit.length_factor - 1.0).abs() < 0.05, "{fit:?}");
            // The corrected profile carries the fitted hairs.
            assert_eq!(fit.apply(&pen1, "c").unwrap().hairs.trail_reach, reach);
        }
    }

    #[test]
    fn the_fitted_trail_is_predicted_and_carried_into_the_next_fit() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let strokes = half_circle();
        let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 80.0 };
        let blank = Coverage::new(96, 96);
        let a = LastAttempt { ch: "~", char_box, strokes: &strokes, observed: &blank };
        let own = predict_attempt(&a, &pen1, ModelKind::Bsm, 96).unwrap();
        // The brush trailing 0.3: its ink is predicted, so the residual of that ink is nil.
        let short = with_hairs(&pen1, 0.3, pen1.hairs.contact_h_mm);
        let observed = predict_attempt(&a, &short, ModelKind::Bsm, 96).unwrap();
        assert_ne!(own.data(), observed.data());
        let a = LastAttempt { observed: &observed, ..a };
        assert!(Residual::of(&a, &short, ModelKind::Bsm).unwrap().mean_abs() < 1e-9);
        assert!(Residual::of(&a, &pen1, ModelKind::Bsm).unwrap().mean_abs() > 1e-3);
        // A profile already fitted under 0.3 keeps it (the reach carried), with little to correct.
        let fit = fit_brush(&[a], &short, ModelKind::Bsm).unwrap();
        assert_eq!(fit.hairs, Some(short.hairs), "{fit:?}");
        assert!((fit.width_factor - 1.0).abs() < 0.05 && (fit.length_factor - 1.0).abs() < 0.05, "{fit:?}");
    }

    /// Corners (折) written with a reverse entry along x and a turn-over glide at 0.5 mm, then
    /// pressed again and pulled down the page, by a brush 20 % wider whose hairs follow only from
    /// 0.8 mm: the glide leaves them pointing along +x past the down stroke's edge, and
    /// the fit finds a contact depth past the glide (the lightest candidate that explains the
    /// ink, 1 mm) under a profile that said any touch turns them; a profile whose depth the
    /// glide already passes keeps its own, as the photo cannot tell those apart.
    #[test]
    fn the_contact_depth_is_fitted_from_wedges_a_light_glide_left() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let pt = |x_mm: f64, y_mm: f64, h_mm: f64| brush_model::TrackPoint {
            x_mm,
            y_mm,
            h_mm,
            alpha_rad: 0.0,
            beta_rad: 0.0,
        };
        let strokes: Vec<Stroke> = [5.0, 45.0]
            .iter()
            .map(|&y| Stroke {
                points: vec![
                    pt(30.0, y, 13.0),
                    pt(15.0, y, 13.0),
                    pt(15.0, y, 0.5),
                    pt(27.0, y, 0.5),
                    pt(27.0, y, 12.0),
                    pt(27.0, y + 20.0, 12.0),
                ],
            })
            .collect();
        let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 80.0 };
        let blank = Coverage::new(96, 96);
        let a = LastAttempt { ch: "三", char_box, strokes: &strokes, observed: &blank };
        let wide = BrushCorrection { width_factor: 1.2, ..BrushCorrection::IDENTITY }.apply(&pen1, "world").unwrap();
        let truth = with_hairs(&wide, brush_model::TRAIL_REACH, 0.8);
        let observed = predict_attempt(&a, &truth, ModelKind::Bsm, 96).unwrap();
        let a = LastAttempt { observed: &observed, ..a };
        let touch = with_hairs(&pen1, brush_model::TRAIL_REACH, 0.0);
        assert_ne!(predict_attempt(&a, &touch, ModelKind::Bsm, 96).unwrap().data(), observed.data());
        let fit = fit_brush(&[a], &touch, ModelKind::Bsm).unwrap();
        let hairs = fit.hairs.unwrap();
        assert_eq!((hairs.contact_h_mm, hairs.trail_reach), (1.0, brush_model::TRAIL_REACH), "{fit:?}");
        assert!((fit.width_factor - 1.2).abs() < 0.05 && fit.ink_error_after < 0.5 * fit.ink_error_before, "{fit:?}");
        // Hairs said to follow from 0.25 mm cannot be told from hairs following from 0.5 on a
        // glide at 0.5: those are kept, and the wedges stay in the error.
        let light = with_hairs(&pen1, brush_model::TRAIL_REACH, 0.25);
        let kept = fit_brush(&[a], &light, ModelKind::Bsm).unwrap().hairs.unwrap();
        assert!(kept.contact_h_mm > 0.5, "{kept:?}");
        // The nominal profile's own depth (1 mm) already explains the wedges: kept.
        let nominal = fit_brush(&[a], &pen1, ModelKind::Bsm).unwrap();
        assert_eq!(nominal.hairs.map(|h| h.contact_h_mm), Some(pen1.hairs.contact_h_mm), "{nominal:?}");
    }

    #[test]
    fn the_target_is_the_glyph_shifted_by_the_residual() {
        let glyph = trajectory::embedded_glyph('十').unwrap();
        let b = CharBox { x0_mm: 10.0, y0_mm: 20.0, size_mm: 64.0 };
        let zero = Residual { side: 32, values: vec![0.0; 32 * 32] };
        let t0 = ilc_target(&glyph, &b, &zero, 32).unwrap();
        let g = render_glyph(&glyph, 32);
        assert_eq!(t0.ink, g.data());
        assert_eq!((t0.origin_mm.x_mm, t0.mm_per_px), (10.0, 2.0));
        // Ink the photo showed beyond the prediction is taken off the target; missing ink is
        // added.
        let more = Residual { side: 32, values: vec![0.25; 32 * 32] };
        let t1 = ilc_target(&glyph, &b, &more, 32).unwrap();
        for (a, g) in t1.ink.iter().zip(g.data()) {
            assert!((a - (g - ILC_GAIN * 0.25).clamp(0.0, 1.0)).abs() < 1e-6);
        }
        let less = Residual { side: 32, values: vec![-0.25; 32 * 32] };
        let t2 = ilc_target(&glyph, &b, &less, 32).unwrap();
        assert!(t2.ink.iter().sum::<f32>() > g.data().iter().sum::<f32>());
    }

    #[test]
    fn unusable_attempts_are_refused() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 50.0 };
        let img = Coverage::new(10, 12);
        let strokes = vec![Stroke { points: vec![] }];
        let a = LastAttempt { ch: "十", char_box: b, strokes: &strokes, observed: &img };
        assert!(matches!(fit_brush(&[], &pen1, ModelKind::Bsm), Err(ClosedLoopError::Empty)));
        assert!(matches!(fit_brush(&[a], &pen1, ModelKind::Bsm), Err(ClosedLoopError::NotSquare { .. })));
        let sq = Coverage::new(10, 10);
        let none = LastAttempt { strokes: &[], observed: &sq, ..a };
        assert!(matches!(Residual::of(&none, &pen1, ModelKind::Bsm), Err(ClosedLoopError::NoStrokes { .. })));
        // A correction that makes a length non-positive is refused.
        let bad = BrushCorrection { spread_mm: -50.0, ..BrushCorrection::IDENTITY };
        assert!(matches!(bad.apply(&pen1, "x"), Err(ClosedLoopError::Profile(_))));
    }

    #[test]
    fn a_correction_carries_over_to_another_brush_and_a_wider_brush_picks_a_smaller_one() {
        let s71 = BrushProfile::builtin("pen1-s71").unwrap();
        let s59 = BrushProfile::builtin("pen1-s59").unwrap();
        // Two rounds compound: the lengths' and the width's spreads then differ.
        let c1 =
            BrushCorrection { width_factor: 1.24, length_factor: 1.18, spread_mm: 0.15, ..BrushCorrection::IDENTITY };
        let c2 = BrushCorrection { width_factor: 1.1, length_factor: 0.9, spread_mm: 0.2, ..BrushCorrection::IDENTITY };
        let fat = c2.apply(&c1.apply(&s71, "a").unwrap(), "b").unwrap();
        let carried = carry_correction(&s71, &fat, &s59, "pen1-s59+observed2").unwrap();
        let direct = c2.apply(&c1.apply(&s59, "a").unwrap(), "b").unwrap();
        for (x, y) in [
            (carried.model.lt_mm, direct.model.lt_mm),
            (carried.model.lh_mm, direct.model.lh_mm),
            (carried.model.lr_mm, direct.model.lr_mm),
        ] {
            assert!((x.intercept - y.intercept).abs() < 1e-9 && (x.h_mm.unwrap() - y.h_mm.unwrap()).abs() < 1e-9);
            assert!((x.alpha_rad.unwrap() - y.alpha_rad.unwrap()).abs() < 1e-9);
        }
        assert_eq!((carried.name.as_str(), carried.ranges.h_mm.min), ("pen1-s59+observed2", s59.ranges.h_mm.min));
        // The identity carries the candidate over unchanged.
        let same = carry_correction(&s71, &s71, &s59, "pen1-s59").unwrap();
        assert_eq!(same.model.lr_mm.h_mm, s59.model.lr_mm.h_mm);
        // A profile that is not a correction of the base is refused.
        let mut odd = s71.clone();
        odd.model.lr_mm.alpha_rad = Some(5.0);
        assert!(matches!(carry_correction(&s71, &odd, &s59, "x"), Err(ClosedLoopError::NotACorrection { .. })));
        // At the box --brush auto gives pen1-s71, the brush writing a third wider suits a
        // smaller base brush.
        let p = crate::prepare(trajectory::embedded_glyph('山').unwrap(), None).unwrap();
        let all = crate::builtin_brushes();
        let mm = crate::choose_brush(std::slice::from_ref(&p), &all, 1.0, 0.0).candidates
            [all.iter().position(|b| b.name == "pen1-s71").unwrap()]
        .1;
        let nominal = choose_corrected_brush(std::slice::from_ref(&p), &s71, &s71, &all, "", mm, 0.0).unwrap();
        assert_eq!(nominal.name, "pen1-s71", "{}", nominal.reason);
        let wide = BrushCorrection { width_factor: 1.34, length_factor: 1.12, ..BrushCorrection::IDENTITY }
            .apply(&s71, "pen1-s71+observed1")
            .unwrap();
        let c = choose_corrected_brush(std::slice::from_ref(&p), &s71, &wide, &all, "+observed1", mm, 0.0).unwrap();
        let scale = |n: &str| BrushProfile::builtin_scale(n.split('+').next().unwrap()).unwrap_or(1.0);
        assert!(scale(&c.name) < scale("pen1-s71") && c.name.ends_with("+observed1"), "{}", c.reason);
    }
}
