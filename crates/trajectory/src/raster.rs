//! Glyphs to pixels: coverage images of the em box, and binary masks for analysis.

use bezier_raster::{Coverage, Rasterizer};
use kurbo::BezPath;

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

/// What [`gaussian_blur`] reads outside the raster.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Edge {
    /// Nothing (zero): a raster that is all ink fades towards its border.
    Zero,
    /// The nearest border pixel.
    Clamp,
}

/// Separable Gaussian blur (σ in px, kernel ±3σ, normalised to sum 1) of an `n × n` raster;
/// `edge` says what lies outside it. σ ≤ 0 returns the raster unchanged.
pub(crate) fn gaussian_blur(src: &[f32], n: usize, sigma: f64, edge: Edge) -> Vec<f32> {
    if sigma <= 0.0 {
        return src.to_vec();
    }
    let r = (3.0 * sigma).ceil() as i64;
    let k: Vec<f64> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let norm: f64 = k.iter().sum();
    let at = |i: i64| -> Option<usize> {
        match edge {
            Edge::Zero => (0..n as i64).contains(&i).then_some(i as usize),
            Edge::Clamp => Some(i.clamp(0, n as i64 - 1) as usize),
        }
    };
    // One pass along rows (`horizontal`) or columns.
    let pass = |from: &[f32], horizontal: bool| -> Vec<f32> {
        let mut to = vec![0.0f32; n * n];
        for y in 0..n {
            for x in 0..n {
                let mut acc = 0.0;
                for (j, w) in k.iter().enumerate() {
                    let (along, other) = if horizontal { (x, y) } else { (y, x) };
                    if let Some(i) = at(along as i64 + j as i64 - r) {
                        acc += w * from[if horizontal { other * n + i } else { i * n + other }] as f64;
                    }
                }
                to[y * n + x] = (acc / norm) as f32;
            }
        }
        to
    };
    pass(&pass(src, true), false)
}
