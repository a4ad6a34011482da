//! Scoring shared by the template and scan tests.

#![allow(dead_code)]

use bezier_raster::{ModelKind, render_track};
use brush_model::{BrushProfile, Extrapolation, PointMm};
use trajectory::{
    CharBox, DEFAULT_SPACING_MM, Glyph, Sizing, StrokePath, TrackOptions, auto_char_mm, build_track, render_glyph,
};

/// Side of the images the tests score at, px.
pub const PX: u32 = 256;

/// CSIM of the track built from `paths` (pen1, auto char box) against the glyph, at [`PX`]².
pub fn csim(paths: &[StrokePath], g: &Glyph) -> f64 {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let size_mm = auto_char_mm(paths, &pen1, 0.0);
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm };
    let o = TrackOptions { char_box: b, spacing_mm: DEFAULT_SPACING_MM, alpha_rad: 0.0, sizing: Sizing::Brush };
    let built = build_track(paths, &pen1, &o).unwrap();
    let img = render_track(
        &built.track,
        &pen1,
        ModelKind::Bsm.model(),
        Extrapolation::Refuse,
        PointMm::new(0.0, 0.0),
        PX as f64 / size_mm,
        PX,
        PX,
    )
    .unwrap();
    let reference = render_glyph(g, PX);
    stroke_metrics::csim(reference.as_gray(), img.as_gray()).unwrap()
}
