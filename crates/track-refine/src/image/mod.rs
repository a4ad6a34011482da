//! The image term's seam: what the problem hands an image model (the prepared footprints and
//! the target raster), what a model gives back (the soft union and the footprints' partials),
//! and the one residual loop every model's image term goes through.
//!
//! The image term is `Σ_p (U_p − G_p)² / Σ_p G_p`, with `U_p = 1 − Π_i (1 − c_i(p))` the soft
//! union of every pressed point's footprint coverage `c_i` at pixel centre `p` and `G` the
//! glyph raster (ink = 1). Two models give the coverages and their derivatives: [`Analytic`]
//! (the soft teardrop of `crate::soft`, closed form) and, behind the cargo feature
//! `generator`, `crate::GenModel` (the B-BSMG generator's images).

mod analytic;

pub(crate) use analytic::Analytic;

use crate::soft::Shape;

/// Footprints per parallel chunk of the image sums (a fixed size, so that the order of the
/// floating-point sums, and hence the result, does not depend on the thread count).
pub(crate) const CHUNK: usize = 256;

/// One footprint prepared for the image term (by the problem, from an iterate).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fp {
    /// Position of the pressed point, mm.
    pub(crate) x: f64,
    pub(crate) y: f64,
    /// Depth, mm; tilt, rad; direction (root → tip), rad.
    pub(crate) h: f64,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    /// The analytic footprint's lengths (from the profile's model at this press).
    pub(crate) shape: Shape,
    /// `∂(lt, lh, lr)/∂h`.
    pub(crate) dh: [f64; 3],
    /// `∂(lt, lh, lr)/∂α`.
    pub(crate) da: [f64; 3],
    /// `∂(lt, lh, lr)/∂β` (zero in refinement, whose image term turns the footprint only).
    pub(crate) db: [f64; 3],
    /// Pixel bounds, inclusive: columns `i0..=i1`, rows `j0..=j1` (empty when `i0 > i1`).
    pub(crate) i0: i64,
    pub(crate) i1: i64,
    pub(crate) j0: i64,
    pub(crate) j1: i64,
}

/// The target raster as the image sums read it.
pub(crate) struct Raster<'t> {
    /// Columns and rows.
    pub(crate) width: usize,
    pub(crate) height: usize,
    /// Paper position of the top-left corner, mm.
    pub(crate) origin: [f64; 2],
    /// Pixel size, mm.
    pub(crate) mm_per_px: f64,
    /// Ink coverage, row-major.
    pub(crate) ink: &'t [f32],
    /// `Σ ink`.
    pub(crate) ink_sum: f64,
}

/// The soft union per pixel, kept as `Σ ln(1 − c)` over the coverages below 1 and, for a
/// model whose coverages reach 1, how many do at each pixel (there `Π(1 − c) = 0`).
pub(crate) struct UnionSums {
    pub(crate) log_keep: Vec<f64>,
    pub(crate) saturated: Option<Vec<u32>>,
}

impl UnionSums {
    /// `Π(1 − c)` at pixel `k`.
    #[inline]
    pub(crate) fn keep(&self, k: usize) -> f64 {
        match &self.saturated {
            Some(sat) if sat[k] > 0 => 0.0,
            _ => self.log_keep[k].exp(),
        }
    }

    /// The soft union image `U = 1 − Π(1 − c)`.
    pub(crate) fn image(&self) -> Vec<f64> {
        (0..self.log_keep.len()).map(|k| 1.0 - self.keep(k)).collect()
    }

    /// The image term against `r`'s ink and, per pixel, `∂L/∂U · Π(1 − c)`: what each
    /// footprint's `∂L/∂c = q / (1 − c)` is made of.
    pub(crate) fn residuals(&self, r: &Raster<'_>) -> (f64, Vec<f64>) {
        let n = self.log_keep.len();
        let mut image = 0.0;
        let mut q = vec![0.0f64; n];
        for (k, qk) in q.iter_mut().enumerate() {
            let prod = self.keep(k);
            let u = 1.0 - prod;
            let res = u - r.ink[k] as f64;
            image += res * res;
            *qk = 2.0 * res / r.ink_sum * prod;
        }
        image /= r.ink_sum;
        (image, q)
    }
}

/// Where the footprints' coverages and their derivatives come from: the seam of the image
/// term. Every sum runs over [`CHUNK`]-sized chunks in a fixed order (deterministic for any
/// thread count).
pub(crate) trait ImageModel: Send + Sync {
    /// The soft union of `fps` on `r`.
    fn union(&self, r: &Raster<'_>, fps: &[Fp]) -> UnionSums;

    /// The image term (through [`UnionSums::residuals`]) and, when `want_grad`, each
    /// footprint's `∂/∂(x, y, h, α, β)` (empty otherwise).
    fn image_term(&self, r: &Raster<'_>, fps: &[Fp], want_grad: bool) -> (f64, Vec<[f64; 5]>);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The residual loop: a saturated pixel is fully covered and passes no gradient; elsewhere
    /// `U = 1 − exp(Σ ln(1 − c))`, the term is the squared error over the ink and
    /// `q = 2·(U − G)/Σ G · Π(1 − c)`. Without saturation counts (the generator's sums) every
    /// pixel goes through the exponential.
    #[test]
    fn the_residual_loop_reads_the_union_sums() {
        let ink = [1.0f32, 0.0, 1.0];
        let r = Raster { width: 3, height: 1, origin: [0.0; 2], mm_per_px: 1.0, ink: &ink, ink_sum: 2.0 };
        let sums = UnionSums { log_keep: vec![-0.5, 0.75f64.ln(), 0.0], saturated: Some(vec![1, 0, 0]) };
        let u = sums.image();
        assert_eq!(u[0], 1.0);
        assert!((u[1] - 0.25).abs() < 1e-15, "{u:?}");
        assert_eq!(u[2], 0.0);
        let (image, q) = sums.residuals(&r);
        // (0² + 0.25² + 1²) / 2.
        assert!((image - 0.53125).abs() < 1e-12, "{image}");
        assert_eq!(q[0], 0.0);
        assert!((q[1] - 2.0 * 0.25 / 2.0 * 0.75).abs() < 1e-15, "{q:?}");
        assert_eq!(q[2], -1.0);
        let unsaturated = UnionSums { saturated: None, ..sums };
        assert!((unsaturated.image()[0] - (1.0 - (-0.5f64).exp())).abs() < 1e-15);
        assert!(unsaturated.residuals(&r).1[0] < 0.0, "pixel 0 is short of ink: pushed up");
    }
}
