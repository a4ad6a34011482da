//! Many footprints: parallel batches and the per-pixel-max compositor.

use brush_model::{BrushProfile, Extrapolation, Footprint, PointMm, ProfileError, Track};
use rayon::prelude::*;

use crate::coverage::Coverage;
use crate::models::StrokeModel;
use crate::raster::Rasterizer;

/// One footprint placed on the paper.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamp {
    /// Its lengths.
    pub footprint: Footprint,
    /// Where its root end sits, mm.
    pub anchor: PointMm,
    /// Its direction, radians from +x towards +y.
    pub beta_rad: f64,
}

/// Renders each stamp into its own `width × height` image, in parallel on rayon's pool (one
/// [`Rasterizer`] per worker).
pub fn render_batch(
    model: &dyn StrokeModel,
    stamps: &[Stamp],
    width: u32,
    height: u32,
    px_per_mm: f64,
) -> Vec<Coverage> {
    stamps
        .par_iter()
        .map_init(Rasterizer::new, |r, s| {
            let mut img = Coverage::new(width, height);
            r.render(model, &s.footprint, s.anchor, s.beta_rad, px_per_mm, &mut img);
            img
        })
        .collect()
}

/// Composes many footprints into one image by per-pixel max (DESIGN §7): overlapping
/// anti-aliased edges never darken each other, and re-stamping the same footprint changes
/// nothing.
pub struct Compositor {
    raster: Rasterizer,
    image: Coverage,
    px_per_mm: f64,
}

impl Compositor {
    /// A blank `width × height` image at `px_per_mm`; paper mm `(0, 0)` is its top-left corner.
    pub fn new(width: u32, height: u32, px_per_mm: f64) -> Self {
        Self { raster: Rasterizer::new(), image: Coverage::new(width, height), px_per_mm }
    }

    /// Stamps one footprint with `model`.
    pub fn stamp(&mut self, model: &dyn StrokeModel, s: &Stamp) {
        let path = model.outline(&s.footprint, s.anchor, s.beta_rad);
        self.raster.stamp(&path, self.px_per_mm, &mut self.image);
    }

    /// Stamps every footprint in order.
    pub fn stamp_all<'a>(&mut self, model: &dyn StrokeModel, stamps: impl IntoIterator<Item = &'a Stamp>) {
        for s in stamps {
            self.stamp(model, s);
        }
    }

    /// The image so far.
    pub fn image(&self) -> &Coverage {
        &self.image
    }

    /// Consumes the compositor, returning the image.
    pub fn into_image(self) -> Coverage {
        self.image
    }
}

/// The stamps of a brush track: each point's footprint (from `profile`, with the point's β as a
/// writing direction, see [`BrushProfile::predict_oriented`]) at its anchor, in writing order.
///
/// # Errors
/// [`ProfileError`] for the first point the profile refuses.
pub fn track_stamps(
    track: &Track,
    profile: &BrushProfile,
    extrapolation: Extrapolation,
) -> Result<Vec<Stamp>, ProfileError> {
    track
        .points()
        .map(|p| {
            Ok(Stamp {
                footprint: profile.predict_oriented(&p.press(), extrapolation)?,
                anchor: p.anchor(),
                beta_rad: p.beta_rad,
            })
        })
        .collect()
}

/// Renders a track into a `width × height` image whose top-left corner is paper point
/// `origin_mm`, at `px_per_mm`, composing footprints by per-pixel max.
///
/// # Errors
/// [`ProfileError`] for the first point the profile refuses.
#[allow(clippy::too_many_arguments)]
pub fn render_track(
    track: &Track,
    profile: &BrushProfile,
    model: &dyn StrokeModel,
    extrapolation: Extrapolation,
    origin_mm: PointMm,
    px_per_mm: f64,
    width: u32,
    height: u32,
) -> Result<Coverage, ProfileError> {
    let mut c = Compositor::new(width, height, px_per_mm);
    for s in track_stamps(track, profile, extrapolation)? {
        let shifted =
            Stamp { anchor: PointMm::new(s.anchor.x_mm - origin_mm.x_mm, s.anchor.y_mm - origin_mm.y_mm), ..s };
        c.stamp(model, &shifted);
    }
    Ok(c.into_image())
}
