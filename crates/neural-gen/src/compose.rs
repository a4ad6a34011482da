//! Rendering a whole track with the generator: footprints generated in batches, resampled onto
//! the character image and composed by per-pixel max.

use bezier_raster::{Coverage, StrokeCanvas};
use brush_model::{ForwardModel, PointMm, Press, Track};

use crate::model::Generator;
use crate::{ConfigError, NeuralGenError};

/// Renders `track` into a `width × height` image whose top-left corner is paper point
/// `origin_mm`, at `px_per_mm`. The track goes through the forward model of the moving brush
/// first (`brush_model::ForwardModel`, as every renderer does), so the footprints are those of
/// the swept path with directions derived from motion and tilt. Each footprint is generated for its press with β reduced
/// into the calibrated range (as `BrushProfile::predict_oriented` does; the generator was
/// trained there), then rotated to the point's β while being resampled (bilinear) onto the
/// image; footprints compose by per-pixel max. Presses are generated `batch` at a time.
///
/// # Errors
/// [`NeuralGenError`] from inference or a profile that refuses a press.
pub fn render_track(
    g: &Generator,
    track: &Track,
    origin_mm: PointMm,
    px_per_mm: f64,
    width: u32,
    height: u32,
    batch: usize,
) -> Result<Coverage, NeuralGenError> {
    let mut out = Coverage::new(width, height);
    let s = g.config.size as usize;
    let canvas = StrokeCanvas::with_scale(g.config.size, g.config.px_per_mm);
    let r = g.config.ranges;
    let swept = ForwardModel::default().sweep_track(&g.config.profile, track, brush_model::Extrapolation::Allow);
    let points: Vec<_> = swept.points().copied().collect();
    for chunk in points.chunks(batch.max(1)) {
        let shaped: Vec<Press> = chunk
            .iter()
            .map(|p| {
                let b = (p.beta_rad + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
                Press::new(p.h_mm, p.alpha_rad, r.beta_rad.clamp(b))
            })
            .collect();
        let imgs = g.render(&shaped)?;
        for ((p, sp), img) in chunk.iter().zip(&shaped).zip(&imgs) {
            let fp = g.config.profile.predict(sp, brush_model::Extrapolation::Allow).map_err(|e| {
                NeuralGenError::Config { source_name: "profile".into(), problem: ConfigError::Profile(e) }
            })?;
            let a_gen = canvas.anchor_mm(&fp, sp.beta_rad);
            let b = fp.placed_bounds(p.anchor(), p.beta_rad);
            let k = px_per_mm;
            let (x0, y0) = (
                (((b.min_x - origin_mm.x_mm) * k).floor() as i64 - 1).max(0),
                (((b.min_y - origin_mm.y_mm) * k).floor() as i64 - 1).max(0),
            );
            let (x1, y1) = (
                (((b.max_x - origin_mm.x_mm) * k).ceil() as i64 + 1).min(width as i64),
                (((b.max_y - origin_mm.y_mm) * k).ceil() as i64 + 1).min(height as i64),
            );
            let (sn, cs) = (p.beta_rad - sp.beta_rad).sin_cos();
            let src = img.data();
            let w = width as usize;
            for y in y0..y1 {
                for x in x0..x1 {
                    // Paper mm of this pixel's centre, relative to the track anchor, rotated back
                    // into the generated footprint's orientation.
                    let (dx, dy) = (
                        (x as f64 + 0.5) / k + origin_mm.x_mm - p.x_mm,
                        (y as f64 + 0.5) / k + origin_mm.y_mm - p.y_mm,
                    );
                    let (lx, ly) = (cs * dx + sn * dy, -sn * dx + cs * dy);
                    let (gx, gy) =
                        ((a_gen.x_mm + lx) * canvas.px_per_mm - 0.5, (a_gen.y_mm + ly) * canvas.px_per_mm - 0.5);
                    if gx < 0.0 || gy < 0.0 || gx >= (s - 1) as f64 || gy >= (s - 1) as f64 {
                        continue;
                    }
                    let (ix, iy) = (gx as usize, gy as usize);
                    let (tx, ty) = ((gx - ix as f64) as f32, (gy - iy as f64) as f32);
                    let at = |xx: usize, yy: usize| src[yy * s + xx];
                    let v = (at(ix, iy) * (1.0 - tx) + at(ix + 1, iy) * tx) * (1.0 - ty)
                        + (at(ix, iy + 1) * (1.0 - tx) + at(ix + 1, iy + 1) * tx) * ty;
                    let d = &mut out.data_mut()[y as usize * w + x as usize];
                    *d = d.max(v);
                }
            }
        }
    }
    Ok(out)
}
