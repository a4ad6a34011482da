//! Glyphs to pixels: coverage images of the em box, and binary masks for analysis.

use bezier_raster::{Coverage, Rasterizer};
use kurbo::{BezPath, Point, Vec2};

use crate::glyph::{EM, Glyph, Shape};

/// Renders outlines (em frame) into a `size × size` coverage image of the em box: pixel
/// `x = x'·size/1024`, `y = y'·size/1024`. Each outline is filled on its own (nonzero) and
/// composed by per-pixel max, so overlapping strokes never cancel or darken.
pub fn render_outlines(outlines: &[BezPath], size: u32) -> Coverage {
    let mut img = Coverage::new(size, size);
    let mut r = Rasterizer::new();
    for o in outlines {
        r.stamp(o, size as f64 / EM, &mut img);
    }
    img
}

/// Resamples a square bitmap to `size × size` by area averaging (box filter over the source
/// pixels each target pixel covers).
pub fn resample_bitmap(src_size: u32, ink: &[f32], size: u32) -> Coverage {
    let mut out = Coverage::new(size, size);
    let (n, m) = (src_size as usize, size as usize);
    let scale = n as f64 / m as f64;
    let data = out.data_mut();
    for ty in 0..m {
        let (y0, y1) = (ty as f64 * scale, (ty + 1) as f64 * scale);
        for tx in 0..m {
            let (x0, x1) = (tx as f64 * scale, (tx + 1) as f64 * scale);
            let mut acc = 0.0;
            let mut sy = y0.floor() as usize;
            while (sy as f64) < y1 && sy < n {
                let wy = (y1.min(sy as f64 + 1.0) - y0.max(sy as f64)).max(0.0);
                let mut sx = x0.floor() as usize;
                while (sx as f64) < x1 && sx < n {
                    let wx = (x1.min(sx as f64 + 1.0) - x0.max(sx as f64)).max(0.0);
                    acc += wx * wy * ink[sy * n + sx] as f64;
                    sx += 1;
                }
                sy += 1;
            }
            data[ty * m + tx] = (acc / (scale * scale)) as f32;
        }
    }
    out
}

/// The reference image of a glyph: its shape rendered onto a `size × size` em box.
pub fn render_glyph(g: &Glyph, size: u32) -> Coverage {
    match &g.shape {
        Shape::Outlines(o) => render_outlines(o, size),
        Shape::Bitmap { size: n, ink } => resample_bitmap(*n, ink, size),
    }
}

/// A binary mask (`coverage ≥ 0.5`) of a coverage image.
pub fn mask_of(c: &Coverage) -> Vec<bool> {
    c.data().iter().map(|&v| v >= 0.5).collect()
}

/// Ink pixel centres (coverage ≥ 0.5) of an `n × n` em-box raster, em units, at most `cap` of
/// them (every k-th in raster order). `None` if there is no ink.
pub(crate) fn ink_points(cov: &[f32], n: usize, cap: usize) -> Option<Vec<Point>> {
    let s = EM / n as f64;
    let all: Vec<Point> = (0..n * n)
        .filter(|&i| cov[i] >= 0.5)
        .map(|i| Point::new(((i % n) as f64 + 0.5) * s, ((i / n) as f64 + 0.5) * s))
        .collect();
    if all.is_empty() {
        return None;
    }
    let k = all.len().div_ceil(cap);
    Some(all.into_iter().step_by(k).collect())
}

/// Ink centroid and per-axis standard deviation of a raster, em units.
pub(crate) fn moments(cov: &[f32], n: usize) -> (Point, Vec2) {
    let s = EM / n as f64;
    let (mut m0, mut mx, mut my) = (0.0, 0.0, 0.0);
    for (i, &v) in cov.iter().enumerate() {
        let v = v as f64;
        m0 += v;
        mx += v * ((i % n) as f64 + 0.5) * s;
        my += v * ((i / n) as f64 + 0.5) * s;
    }
    let c = Point::new(mx / m0.max(1e-9), my / m0.max(1e-9));
    let (mut vx, mut vy) = (0.0, 0.0);
    for (i, &v) in cov.iter().enumerate() {
        let v = v as f64;
        vx += v * (((i % n) as f64 + 0.5) * s - c.x).powi(2);
        vy += v * (((i / n) as f64 + 0.5) * s - c.y).powi(2);
    }
    (c, Vec2::new((vx / m0.max(1e-9)).sqrt(), (vy / m0.max(1e-9)).sqrt()))
}
