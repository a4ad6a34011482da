//! What the examples and the bench of track-refine share: the track `maobi` builds for a
//! character's centre lines (pen1, automatic char box, brush sizing), the glyph target,
//! the plan's render and its scores, and options from JSON.
//!
//! (Not an example itself: Cargo only finds `examples/*.rs` and `examples/*/main.rs`.)

#![allow(dead_code)] // each example uses part of it

use bezier_raster::{Coverage, ModelKind, render_track};
use brush_model::{BrushProfile, Extrapolation, PointMm, Track};
use stroke_metrics::GrayRef;
use track_refine::{RefineOptions, Target};
use trajectory::{CharBox, Glyph, Sizing, StrokePath, TrackOptions, build_track, raster::render_glyph};

/// The track `maobi` builds from `paths` with `pen` in the automatic char box (α = 0) placed
/// at `origin_mm`, and that box.
pub fn built_track(paths: &[StrokePath], pen: &BrushProfile, origin_mm: (f64, f64)) -> (Track, CharBox) {
    let char_box =
        CharBox { x0_mm: origin_mm.0, y0_mm: origin_mm.1, size_mm: trajectory::auto_char_mm(paths, pen, 0.0) };
    let topts =
        TrackOptions { char_box, spacing_mm: trajectory::DEFAULT_SPACING_MM, alpha_rad: 0.0, sizing: Sizing::Brush };
    let track = build_track(paths, pen, &topts).expect("the centre lines build a track").track;
    (track, char_box)
}

/// The glyph raster at `px²` over the char box, as refinement's target.
pub fn target_for(g: &Glyph, char_box: &CharBox, px: u32) -> Target {
    Target::new(
        px,
        px,
        render_glyph(g, px).data().to_vec(),
        PointMm::new(char_box.x0_mm, char_box.y0_mm),
        char_box.size_mm / px as f64,
    )
    .expect("a glyph raster is a valid target")
}

/// The plan's B-BSM render of a track over the char box at `size²`.
pub fn render(track: &Track, profile: &BrushProfile, b: &CharBox, size: u32) -> Coverage {
    render_track(
        track,
        profile,
        ModelKind::Bsm.model(),
        Extrapolation::Refuse,
        PointMm::new(b.x0_mm, b.y0_mm),
        size as f64 / b.size_mm,
        size,
        size,
    )
    .expect("a built or refined track renders")
}

/// A coverage as a gray image for the metrics.
pub fn gray(c: &Coverage) -> GrayRef<'_> {
    GrayRef::new(c.data(), c.width() as usize, c.height() as usize).expect("w × h values")
}

/// The plan's CSIM and IoU against the reference (rendered at the reference's size).
pub fn scores(track: &Track, profile: &BrushProfile, b: &CharBox, reference: &Coverage) -> (f64, f64) {
    let img = render(track, profile, b, reference.width());
    (
        stroke_metrics::csim(gray(reference), gray(&img)).unwrap(),
        stroke_metrics::iou(gray(reference), gray(&img)).unwrap(),
    )
}

/// The default options with the fields of a JSON object (an argument) overridden.
pub fn options(json: Option<&String>) -> Result<RefineOptions, Box<dyn std::error::Error>> {
    let opts = RefineOptions::default();
    let Some(js) = json else { return Ok(opts) };
    let mut v = serde_json::to_value(opts)?;
    for (k, x) in serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(js)? {
        v[k] = x;
    }
    Ok(serde_json::from_value(v)?)
}
