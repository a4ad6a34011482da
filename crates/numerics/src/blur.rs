//! A separable Gaussian blur of a row-major raster.

/// What [`gaussian_blur`] reads outside the raster.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    /// Nothing (zero): a raster that is all ink fades towards its border.
    Zero,
    /// The nearest border pixel.
    Clamp,
}

/// Where [`gaussian_blur`] divides by the kernel's sum (so that the weights sum to 1). The two
/// are equal in exact arithmetic and can differ in the last bit; both exist so that results
/// computed with either stay bit-identical.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Normalise {
    /// Each weight is divided by the sum before the pass; the weighted sum is the result.
    Kernel,
    /// The weighted sum with the raw weights is divided by their sum.
    Sum,
}

/// A pixel value [`gaussian_blur`] can hold: it computes in `f64` and stores each pass's result
/// in the raster's own type (so an `f32` raster is rounded to `f32` between the passes).
pub trait Pixel: Copy {
    /// The value as `f64` (exact).
    fn to_f64(self) -> f64;
    /// The nearest value to `v` (`as` conversion).
    fn from_f64(v: f64) -> Self;
}

impl Pixel for f32 {
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Pixel for f64 {
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Separable Gaussian blur of a `width × height` raster `src` (row-major): a pass along the
/// rows, then one along the columns, with the kernel `exp(−i²/2σ²)` for `i` in `−⌈3σ⌉..=⌈3σ⌉`
/// normalised to sum 1 (`normalise` says where). `sigma_px` is σ in pixels; σ ≤ 0 (or NaN)
/// returns the raster unchanged. `edge` says what lies outside the raster.
///
/// # Panics
/// If `src.len() != width · height`.
///
/// # Examples
/// ```
/// use numerics::{Edge, Normalise, gaussian_blur};
/// // One ink pixel in the middle of a 9 × 9 raster spreads, keeping its total.
/// let mut img = vec![0.0f64; 81];
/// img[40] = 1.0;
/// let out = gaussian_blur(&img, 9, 9, 1.0, Edge::Zero, Normalise::Kernel);
/// assert!((out.iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// assert!(out[40] < 0.2 && out[40] > out[41] && out[41] > out[42]);
/// ```
pub fn gaussian_blur<T: Pixel>(
    src: &[T],
    width: usize,
    height: usize,
    sigma_px: f64,
    edge: Edge,
    normalise: Normalise,
) -> Vec<T> {
    assert_eq!(src.len(), width * height, "gaussian_blur: {} values for {width} × {height} px", src.len());
    if !(sigma_px > 0.0) {
        return src.to_vec();
    }
    let r = (3.0 * sigma_px).ceil() as i64;
    let k: Vec<f64> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma_px * sigma_px)).exp()).collect();
    let sum: f64 = k.iter().sum();
    let (k, divide) = match normalise {
        Normalise::Kernel => (k.iter().map(|x| x / sum).collect(), None),
        Normalise::Sum => (k, Some(sum)),
    };
    let pass = |from: &[T], horizontal: bool| -> Vec<T> {
        let len = if horizontal { width } else { height } as i64;
        let mut to = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let along = if horizontal { x } else { y } as i64;
                let mut acc = 0.0;
                for (j, w) in k.iter().enumerate() {
                    let i = along + j as i64 - r;
                    let i = match edge {
                        Edge::Zero if !(0..len).contains(&i) => continue,
                        Edge::Zero => i as usize,
                        Edge::Clamp => i.clamp(0, len - 1) as usize,
                    };
                    acc += w * from[if horizontal { y * width + i } else { i * width + x }].to_f64();
                }
                to.push(T::from_f64(divide.map_or(acc, |s| acc / s)));
            }
        }
        to
    };
    pass(&pass(src, true), false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_raster_stays_constant_with_clamped_edges_and_fades_with_zero_edges() {
        let img = vec![0.75f32; 12 * 7];
        for normalise in [Normalise::Kernel, Normalise::Sum] {
            let c = gaussian_blur(&img, 12, 7, 1.5, Edge::Clamp, normalise);
            assert!(c.iter().all(|&v| (v - 0.75).abs() < 1e-6), "{normalise:?}: {c:?}");
            let z = gaussian_blur(&img, 12, 7, 1.5, Edge::Zero, normalise);
            // The corner loses most, the centre keeps most.
            assert!(z[0] < 0.5 && z[0] > 0.1, "{}", z[0]);
            assert!(z[3 * 12 + 6] > z[0] && z[3 * 12 + 6] <= 0.75 + 1e-6);
        }
    }

    #[test]
    fn a_point_spreads_as_a_separable_gaussian_on_a_rectangle() {
        // A 15 × 11 raster with one pixel set: the result is the outer product of the 1-D
        // kernel with itself, centred on the pixel.
        let (w, h, sigma) = (15, 11, 1.2);
        let mut img = vec![0.0f64; w * h];
        img[5 * w + 7] = 1.0;
        let out = gaussian_blur(&img, w, h, sigma, Edge::Zero, Normalise::Sum);
        let g = |d: i64| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp();
        let s: f64 = (-4..=4).map(g).sum();
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as i64 - 7, y as i64 - 5);
                let want = if dx.abs() <= 4 && dy.abs() <= 4 { g(dx) * g(dy) / (s * s) } else { 0.0 };
                assert!((out[y * w + x] - want).abs() < 1e-15, "({x}, {y}): {} vs {want}", out[y * w + x]);
            }
        }
    }

    #[test]
    fn f32_rounds_between_passes_and_f64_does_not() {
        let img64: Vec<f64> = (0..64).map(|i| ((i * 37) % 11) as f64 / 10.0).collect();
        let img32: Vec<f32> = img64.iter().map(|&v| v as f32).collect();
        let a = gaussian_blur(&img64, 8, 8, 0.9, Edge::Clamp, Normalise::Kernel);
        let b = gaussian_blur(&img32, 8, 8, 0.9, Edge::Clamp, Normalise::Kernel);
        assert!(a.iter().zip(&b).all(|(x, y)| (x - f64::from(*y)).abs() < 1e-6));
        assert!(a.iter().zip(&b).any(|(x, y)| *x != f64::from(*y)));
    }

    #[test]
    fn no_blur_returns_the_raster() {
        let img = vec![0.1f32, 0.9, 0.4, 0.0];
        assert_eq!(gaussian_blur(&img, 2, 2, 0.0, Edge::Zero, Normalise::Sum), img);
        assert_eq!(gaussian_blur(&img, 2, 2, f64::NAN, Edge::Clamp, Normalise::Kernel), img);
    }
}
