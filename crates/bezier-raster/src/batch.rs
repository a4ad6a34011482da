//! Many footprints: parallel batches and the per-pixel-max compositor.

use brush_model::{BrushProfile, Extrapolation, Footprint, ForwardModel, PointMm, ProfileError, Track, TrackPoint};
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

/// Composes many footprints into one image by per-pixel max (docs/contracts.md §6): overlapping
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

/// The stamps of a brush track: the footprints the forward model of the moving brush
/// ([`ForwardModel`], docs/brush-model.md; its hairs as `profile.hairs` describes them) leaves
/// along each stroke's swept path, with their directions derived from the motion and tilt, in
/// writing order. Points with `h ≤ 0` are off the paper; points and samples lighter than the
/// profile's lightest calibrated press (a glide, or the brush easing up or down) leave nothing
/// when `extrapolation` refuses them.
///
/// # Errors
/// [`ProfileError`] for the first track point pressed at least the profile's lightest press that
/// the profile refuses (too deep, or α out of range).
pub fn track_stamps(
    track: &Track,
    profile: &BrushProfile,
    extrapolation: Extrapolation,
) -> Result<Vec<Stamp>, ProfileError> {
    // Lighter than the calibrated range (a glide while the brush turns over) is no error: such
    // a sample leaves no footprint.
    for p in track.points().filter(|p| p.h_mm >= profile.ranges.h_mm.min) {
        profile.predict_oriented(&p.press(), extrapolation)?;
    }
    Ok(track.strokes.iter().flat_map(|s| sweep_stamps(&s.points, profile, extrapolation)).collect())
}

/// The stamps the forward model leaves along one sequence of brush states (a stroke, or a
/// whole executed path with lifts in it: states with `h ≤ 0` are off the paper). Presses the
/// profile refuses leave nothing.
pub fn sweep_stamps(states: &[TrackPoint], profile: &BrushProfile, extrapolation: Extrapolation) -> Vec<Stamp> {
    ForwardModel::default()
        .sweep(profile, states, extrapolation)
        .stamps
        .iter()
        .filter_map(|p| {
            Some(Stamp {
                footprint: profile.predict_oriented(&p.press(), extrapolation).ok()?,
                anchor: p.anchor(),
                beta_rad: p.beta_rad,
            })
        })
        .collect()
}

/// Renders stamps into a `width × height` image whose top-left corner is paper point
/// `origin_mm`, at `px_per_mm`, composing by per-pixel max.
///
/// Many stamps are rendered in parallel on rayon's pool, one image per worker's share merged by
/// per-pixel max: the composition does not depend on the order, and each share's rasteriser
/// starts with the scratch size the serial one would have there, so the image is the same bit
/// for bit at any thread count.
pub fn render_stamps(
    stamps: &[Stamp],
    model: &dyn StrokeModel,
    origin_mm: PointMm,
    px_per_mm: f64,
    width: u32,
    height: u32,
) -> Coverage {
    // A stamp's anchor relative to the image's top-left corner.
    let relative = |anchor: PointMm| PointMm::new(anchor.x_mm - origin_mm.x_mm, anchor.y_mm - origin_mm.y_mm);
    let threads = rayon::current_num_threads();
    let pixels = u64::from(width) * u64::from(height);
    if threads < 2 || stamps.len() < 2 * PARALLEL_STAMPS || pixels > PARALLEL_MAX_PIXELS {
        // On the calling thread.
        let mut c = Compositor::new(width, height, px_per_mm);
        for s in stamps {
            c.stamp(model, &Stamp { anchor: relative(s.anchor), ..*s });
        }
        return c.into_image();
    }
    let paths: Vec<kurbo::BezPath> =
        stamps.par_iter().map(|s| model.outline(&s.footprint, relative(s.anchor), s.beta_rad)).collect();
    let share = stamps.len().div_ceil(threads).max(PARALLEL_STAMPS);
    // The scratch mask's size when each share starts, as one rasteriser going through them all
    // would have it: the running maximum of the boxes drawn so far.
    let mut starts = Vec::new();
    let mut size = (0u32, 0u32);
    for (i, p) in paths.iter().enumerate() {
        if i % share == 0 {
            starts.push(size);
        }
        if let Some([_, _, bw, bh]) = crate::raster::stamp_box(p, px_per_mm, width, height) {
            if bw > size.0 || bh > size.1 {
                size = (size.0.max(bw), size.1.max(bh));
            }
        }
    }
    paths
        .par_chunks(share)
        .zip(starts)
        .map(|(part, (mw, mh))| {
            let mut r = Rasterizer::new();
            r.grow_to(mw, mh);
            debug_assert_eq!(r.mask_size(), (mw, mh));
            let mut img = Coverage::new(width, height);
            for p in part {
                r.stamp(p, px_per_mm, &mut img);
            }
            img
        })
        .reduce_with(|mut a, b| {
            a.max_with(&b);
            a
        })
        .unwrap_or_else(|| Coverage::new(width, height))
}

/// Fewer stamps than this per worker are not worth an image of their own.
const PARALLEL_STAMPS: usize = 256;
/// Above this many pixels (64 MiB of f32) an image per worker costs more memory than it saves
/// time: rendered serially.
const PARALLEL_MAX_PIXELS: u64 = 1 << 24;

/// Renders a track into a `width × height` image whose top-left corner is paper point
/// `origin_mm`, at `px_per_mm`, composing footprints by per-pixel max.
///
/// # Examples
/// ```
/// use bezier_raster::brush_model::{BrushProfile, Extrapolation, PointMm, Stroke, Track, TrackPoint};
/// use bezier_raster::{Bsm, render_track};
/// let pen1 = BrushProfile::builtin("pen1").unwrap();
/// // A 20 mm stroke along y = 15 mm, pressed 15 mm.
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 15.0, h_mm: 15.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=100).map(|i| pt(20.0 + 0.2 * f64::from(i))).collect() }] };
/// // The paper window [0, 60] × [0, 30] mm at 4 px/mm.
/// let img = render_track(&track, &pen1, &Bsm, Extrapolation::Refuse, PointMm::new(0.0, 0.0), 4.0, 240, 120).unwrap();
/// assert!(img.get(120, 60) > 0.99); // (30, 15) mm: inside the stroke
/// assert_eq!(img.get(120, 115), 0.0); // (30, 28.75) mm: paper
/// assert!(img.data().iter().all(|v| (0.0..=1.0).contains(v)));
/// ```
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
    Ok(render_stamps(&track_stamps(track, profile, extrapolation)?, model, origin_mm, px_per_mm, width, height))
}
