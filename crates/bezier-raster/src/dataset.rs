//! Deterministic footprint datasets: random presses over a profile's calibrated range and the
//! images they leave. The same generator feeds `maobi dataset` (PNG files) and the neural
//! generator's training (in memory).

use brush_model::{BrushProfile, Extrapolation, Footprint, Press, ProfileError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::canvas::StrokeCanvas;
use crate::coverage::Coverage;
use crate::models::StrokeModel;
use crate::raster::Rasterizer;

/// What to generate: presses drawn uniformly from `profile`'s ranges, rendered on `canvas`.
#[derive(Clone, Debug)]
pub struct DatasetSpec {
    /// The brush.
    pub profile: BrushProfile,
    /// The canvas (size and scale).
    pub canvas: StrokeCanvas,
    /// Random seed.
    pub seed: u64,
}

/// One sample's labels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sample {
    /// Index within the dataset.
    pub index: u64,
    /// The press.
    pub press: Press,
    /// The footprint it leaves.
    pub footprint: Footprint,
    /// Footprint origin P0 in pixels.
    pub anchor_px: [f64; 2],
}

impl DatasetSpec {
    /// A spec on the profile's default canvas of `size` px.
    pub fn new(profile: BrushProfile, size: u32, seed: u64) -> Self {
        let canvas = StrokeCanvas::for_profile(&profile, size);
        Self { profile, canvas, seed }
    }

    /// The press of sample `index`: a function of `(seed, index)` only (ChaCha8 stream `index`),
    /// so samples are the same whatever the thread count or order.
    pub fn press(&self, index: u64) -> Press {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index);
        let r = &self.profile.ranges;
        let (u, v, w): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
        Press::new(r.h_mm.lerp(u), r.alpha_rad.lerp(v), r.beta_rad.lerp(w))
    }

    /// The labels of sample `index`.
    ///
    /// # Errors
    /// [`ProfileError`] if the profile cannot predict a footprint there (a degenerate profile).
    pub fn sample(&self, index: u64) -> Result<Sample, ProfileError> {
        let press = self.press(index);
        let footprint = self.profile.predict(&press, Extrapolation::Refuse)?;
        Ok(Sample { index, press, footprint, anchor_px: self.canvas.anchor_px(&footprint, press.beta_rad) })
    }

    /// The header of a dataset's `labels.csv`: `file`, brush-model's measurement columns
    /// (angles in degrees), the scale and the footprint's origin in pixels; with its line end.
    pub fn labels_header() -> String {
        format!("file,{},px_per_mm,anchor_u,anchor_v\n", brush_model::MEASUREMENT_COLUMNS)
    }

    /// The `labels.csv` row of `sample` saved as `file` (under [`DatasetSpec::labels_header`],
    /// every number with all its digits), with its line end.
    ///
    /// # Examples
    /// ```
    /// use bezier_raster::DatasetSpec;
    /// let spec = DatasetSpec::new(brush_model::BrushProfile::builtin("pen1")?, 64, 3);
    /// let row = spec.label_row("fp_000000.png", &spec.sample(0)?);
    /// assert_eq!(row.trim_end().split(',').count(), DatasetSpec::labels_header().trim_end().split(',').count());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn label_row(&self, file: &str, sample: &Sample) -> String {
        let m = brush_model::Measurement { press: sample.press, footprint: sample.footprint };
        let fields = brush_model::measurement_fields(&m, None);
        format!("{file},{fields},{},{},{}\n", self.canvas.px_per_mm, sample.anchor_px[0], sample.anchor_px[1])
    }

    /// Renders a sample with `model` into `out` (which must be `size × size`).
    pub fn render(&self, sample: &Sample, model: &dyn StrokeModel, raster: &mut Rasterizer, out: &mut Coverage) {
        let anchor = self.canvas.anchor_mm(&sample.footprint, sample.press.beta_rad);
        raster.render(model, &sample.footprint, anchor, sample.press.beta_rad, self.canvas.px_per_mm, out);
    }
}
