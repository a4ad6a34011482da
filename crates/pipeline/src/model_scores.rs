//! Every stroke model against a reference (the paper's Tables 2 and 3): random presses drawn by
//! the B-BSM footprint, or real stroke photos registered to the stroke canvas; each model's
//! footprint of the same press scored against it by CSIM and SSIM.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use bezier_raster::{Coverage, DatasetSpec, ModelKind, RasterError, Rasterizer, StrokeCanvas};
use brush_model::{BrushProfile, Extrapolation, Press};
use rayon::prelude::*;
use serde::Serialize;
use stroke_fit::LabelsError;
use stroke_metrics::{SsimWorkspace, Summary, csim};
use thiserror::Error;

/// CSIM and SSIM summaries of one model over a set of targets.
#[derive(Serialize, Debug, Clone, Copy, PartialEq)]
pub struct ModelScores {
    /// Cosine similarity over the set.
    pub csim: Summary,
    /// Structural similarity over the set.
    pub ssim: Summary,
}

/// One target a model is scored against: a press and, for a photo, its image (else the B-BSM
/// footprint of the press is the reference).
#[derive(Clone, Debug)]
pub struct ModelTarget {
    /// The press.
    pub press: Press,
    /// The photo, registered to the stroke canvas (footprint placed as the canvas places it).
    pub photo: Option<Coverage>,
    /// The scale the footprints are drawn at, px per mm.
    pub px_per_mm: f64,
}

impl ModelTarget {
    /// The first `n` presses of `spec` (its canvas's scale), each against its B-BSM footprint.
    pub fn presses(spec: &DatasetSpec, n: u64) -> Vec<ModelTarget> {
        (0..n).map(|i| ModelTarget { press: spec.press(i), photo: None, px_per_mm: spec.canvas.px_per_mm }).collect()
    }
}

/// Why reference photos could not be read.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReferenceError {
    /// The labels file is refused.
    #[error(transparent)]
    Labels(#[from] LabelsError),
    /// A photo cannot be read.
    #[error(transparent)]
    Image(#[from] RasterError),
    /// A photo is not square.
    #[error("{}: expected a square image registered to the stroke canvas, got {width}×{height}", path.display())]
    NotSquare {
        /// The photo.
        path: PathBuf,
        /// Its width, px.
        width: u32,
        /// Its height, px.
        height: u32,
    },
    /// A photo's size differs from the first's.
    #[error("{}: all reference images must have the same size", path.display())]
    OtherSize {
        /// The photo.
        path: PathBuf,
    },
}

/// The photos of `dir` as targets: `dir/labels.csv` ([`stroke_fit::read_labels`]) and square
/// images of one size registered to the stroke canvas, each at its `px_per_mm` column or else
/// the scale of `profile`'s default canvas of that size. Returns them and their side, px.
///
/// # Errors
/// [`ReferenceError`] naming the file.
pub fn load_reference_photos(dir: &Path, profile: &BrushProfile) -> Result<(Vec<ModelTarget>, u32), ReferenceError> {
    let mut targets = Vec::new();
    let mut size = None;
    for l in stroke_fit::read_labels(&dir.join("labels.csv"))? {
        let path = dir.join(&l.file);
        let photo = Coverage::load(&path)?;
        let (width, height) = (photo.width(), photo.height());
        if width != height {
            return Err(ReferenceError::NotSquare { path, width, height });
        }
        if *size.get_or_insert(width) != width {
            return Err(ReferenceError::OtherSize { path });
        }
        let px_per_mm = l.px_per_mm.unwrap_or_else(|| StrokeCanvas::for_profile(profile, width).px_per_mm);
        targets.push(ModelTarget { press: l.press, photo: Some(photo), px_per_mm });
    }
    Ok((targets, size.expect("read_labels returns at least one row")))
}

/// Scores each of `models` against every target (in parallel; `each` is called once per target,
/// for progress): the profile's footprint of the target's press (predicted with
/// `extrapolation`) drawn by the model on a `size`² canvas, against the target's photo or its
/// B-BSM footprint; CSIM and SSIM summarised per model, keyed by [`ModelKind::name`].
///
/// # Errors
/// [`crate::Error::Profile`] when a press is outside the profile's range and extrapolation is
/// refused.
///
/// # Examples
/// ```
/// use bezier_raster::{DatasetSpec, ModelKind};
/// use brush_model::Extrapolation;
/// use pipeline::{ModelTarget, score_models};
///
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let spec = DatasetSpec::new(pen1.clone(), 32, 7);
/// let targets = ModelTarget::presses(&spec, 4);
/// let scores = score_models(&pen1, &targets, 32, &[ModelKind::Bsm, ModelKind::Circle], Extrapolation::Refuse, &|| {})?;
/// assert!(scores["bsm"].csim.worst > 0.999_999);
/// assert!(scores["circle"].csim.mean < 1.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn score_models(
    profile: &BrushProfile,
    targets: &[ModelTarget],
    size: u32,
    models: &[ModelKind],
    extrapolation: Extrapolation,
    each: &(dyn Fn() + Sync),
) -> crate::Result<BTreeMap<&'static str, ModelScores>> {
    // Per target: (csim, ssim) for each model.
    let scores: Vec<Vec<(f64, f64)>> = targets
        .par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(size, size), Coverage::new(size, size), SsimWorkspace::new()),
            |(raster, truth, img, ws), t| -> crate::Result<Vec<(f64, f64)>> {
                let fp = profile.predict(&t.press, extrapolation)?;
                let canvas = StrokeCanvas::with_scale(size, t.px_per_mm);
                let anchor = canvas.anchor_mm(&fp, t.press.beta_rad);
                let truth: &Coverage = match &t.photo {
                    Some(p) => p,
                    None => {
                        raster.render(ModelKind::Bsm.model(), &fp, anchor, t.press.beta_rad, t.px_per_mm, truth);
                        truth
                    }
                };
                let mut out = Vec::with_capacity(models.len());
                for m in models {
                    raster.render(m.model(), &fp, anchor, t.press.beta_rad, t.px_per_mm, img);
                    out.push((csim(truth.as_gray(), img.as_gray())?, ws.ssim(truth.as_gray(), img.as_gray())?));
                }
                each();
                Ok(out)
            },
        )
        .collect::<crate::Result<_>>()?;
    Ok(models
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let csim = Summary::of(scores.iter().map(|s| s[k].0));
            let ssim = Summary::of(scores.iter().map(|s| s[k].1));
            (m.name(), ModelScores { csim, ssim })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_press_outside_the_range_is_refused_unless_extrapolating() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let far = Press::new(pen1.ranges.h_mm.max * 3.0, 0.0, 0.0);
        let t = [ModelTarget { press: far, photo: None, px_per_mm: 4.0 }];
        assert!(score_models(&pen1, &t, 32, &[ModelKind::Circle], Extrapolation::Refuse, &|| {}).is_err());
        let s = score_models(&pen1, &t, 32, &[ModelKind::Circle], Extrapolation::Allow, &|| {}).unwrap();
        assert_eq!(s.len(), 1);
    }

    #[test]
    fn missing_reference_labels_are_named() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let e = load_reference_photos(Path::new("/no/such/photos"), &pen1).unwrap_err();
        assert!(e.to_string().starts_with("/no/such/photos/labels.csv: cannot read"), "{e}");
    }
}
