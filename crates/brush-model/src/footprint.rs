//! The B-BSM footprint: two mirrored cubic Béziers (docs/contracts.md §3).
//!
//! In the footprint's own frame the root end is at the origin and the axis runs along +x to the
//! tip. The upper boundary is the cubic
//!
//! ```text
//! P0 = (0, 0)   P1 = ((4·lh − lt)/3, 4·lr/3)   P2 = (lh, 4·lr/3)   P3 = (lh + lt, 0)
//! ```
//!
//! and the lower boundary is its mirror image in the x axis. Because `P1y = P2y`, the upper curve
//! is `y(t) = 4·lr·t·(1 − t)`, highest at `t = 0.5` where `y = lr` and `x = lh`. See
//! `docs/brush-model.md` for the derivation and for why the paper's printed `P1x` is read as a
//! sign typo.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::units::PointMm;

/// Errors from constructing footprint geometry.
#[derive(Debug, Error, PartialEq)]
pub enum GeometryError {
    /// A length was negative, zero where it must not be, or not finite.
    #[error("footprint {field} must be a finite positive length in mm, got {value}")]
    BadLength {
        /// Which length (`lt_mm`, `lh_mm` or `lr_mm`).
        field: &'static str,
        /// The value given.
        value: f64,
    },
}

/// A footprint's three lengths (the paper's `S_B = (Lt, Lh, Lr)`), mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Footprint {
    /// Tip length (bifeng): from the belly to the tip, mm.
    pub lt_mm: f64,
    /// Root length (bigen): from the root end to the belly, mm.
    pub lh_mm: f64,
    /// Belly half-width (bidu), mm.
    pub lr_mm: f64,
}

/// A cubic Bézier with control points in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicMm {
    /// Control points `P0..P3` in traversal order.
    pub points: [PointMm; 4],
}

impl CubicMm {
    /// The point at parameter `t ∈ [0, 1]`.
    pub fn eval(&self, t: f64) -> PointMm {
        let u = 1.0 - t;
        let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
        let mut p = PointMm::default();
        for (wi, pi) in w.iter().zip(&self.points) {
            p.x_mm += wi * pi.x_mm;
            p.y_mm += wi * pi.y_mm;
        }
        p
    }

    /// The derivative `dB/dt` at `t`, mm per unit parameter.
    pub fn derivative(&self, t: f64) -> PointMm {
        let u = 1.0 - t;
        let [p0, p1, p2, p3] = self.points;
        let w = [3.0 * u * u, 6.0 * u * t, 3.0 * t * t];
        let d = [(p0, p1), (p1, p2), (p2, p3)];
        let mut out = PointMm::default();
        for (wi, (a, b)) in w.iter().zip(d) {
            out.x_mm += wi * (b.x_mm - a.x_mm);
            out.y_mm += wi * (b.y_mm - a.y_mm);
        }
        out
    }

    /// This curve with every control point rotated by `beta_rad` about the origin and then moved
    /// by `anchor`.
    pub fn placed(&self, anchor: PointMm, beta_rad: f64) -> Self {
        Self { points: self.points.map(|p| p.rotated(beta_rad).offset(anchor)) }
    }
}

/// A footprint's closed outline: `upper` from the root end `P0` to the tip `P3`, then `lower`
/// from the tip back to the root end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outline {
    /// Upper boundary, root to tip.
    pub upper: CubicMm,
    /// Lower boundary, tip to root.
    pub lower: CubicMm,
}

/// Axis-aligned bounds, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundsMm {
    /// Smallest x, mm.
    pub min_x: f64,
    /// Smallest y, mm.
    pub min_y: f64,
    /// Largest x, mm.
    pub max_x: f64,
    /// Largest y, mm.
    pub max_y: f64,
}

impl BoundsMm {
    /// Width `max_x − min_x`, mm.
    pub fn width(&self) -> f64 {
        self.max_x - self.min_x
    }
    /// Height `max_y − min_y`, mm.
    pub fn height(&self) -> f64 {
        self.max_y - self.min_y
    }
    /// Centre point.
    pub fn centre(&self) -> PointMm {
        PointMm::new(0.5 * (self.min_x + self.max_x), 0.5 * (self.min_y + self.max_y))
    }
}

impl Footprint {
    /// A footprint from its lengths in mm.
    ///
    /// # Errors
    /// [`GeometryError::BadLength`] if any length is not finite or not strictly positive.
    pub fn new(lt_mm: f64, lh_mm: f64, lr_mm: f64) -> Result<Self, GeometryError> {
        for (field, value) in [("lt_mm", lt_mm), ("lh_mm", lh_mm), ("lr_mm", lr_mm)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(GeometryError::BadLength { field, value });
            }
        }
        Ok(Self { lt_mm, lh_mm, lr_mm })
    }

    /// Length along the axis from root end to tip, `lh + lt`, mm.
    pub fn length_mm(&self) -> f64 {
        self.lh_mm + self.lt_mm
    }

    /// The upper boundary `P0 → P3` in the footprint's own frame.
    pub fn upper(&self) -> CubicMm {
        let (lt, lh, lr) = (self.lt_mm, self.lh_mm, self.lr_mm);
        CubicMm {
            points: [
                PointMm::new(0.0, 0.0),
                PointMm::new((4.0 * lh - lt) / 3.0, 4.0 * lr / 3.0),
                PointMm::new(lh, 4.0 * lr / 3.0),
                PointMm::new(lh + lt, 0.0),
            ],
        }
    }

    /// The lower boundary `P3 → P0` (the upper one mirrored in the x axis and reversed) in the
    /// footprint's own frame.
    pub fn lower(&self) -> CubicMm {
        let [p0, p1, p2, p3] = self.upper().points;
        let m = |p: PointMm| PointMm::new(p.x_mm, -p.y_mm);
        CubicMm { points: [m(p3), m(p2), m(p1), m(p0)] }
    }

    /// The closed outline placed on the paper: rotated by `beta_rad` (from +x towards +y) about
    /// the root end, which is put at `anchor` (mm).
    pub fn outline(&self, anchor: PointMm, beta_rad: f64) -> Outline {
        Outline { upper: self.upper().placed(anchor, beta_rad), lower: self.lower().placed(anchor, beta_rad) }
    }

    /// Half-width of the outline at parameter `t` of the upper curve: `4·lr·t·(1 − t)`, mm.
    pub fn half_width_at(&self, t: f64) -> f64 {
        4.0 * self.lr_mm * t * (1.0 - t)
    }

    /// Enclosed area, mm² (exact: Gauss–Legendre on a degree-4 polynomial integrand).
    pub fn area_mm2(&self) -> f64 {
        // Area under the upper curve is ∫ y(t) x'(t) dt over [0, 1]; the integrand has degree 4,
        // so 3-point Gauss–Legendre is exact. The full outline is twice that.
        let upper = self.upper();
        let nodes = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
        let half: f64 = nodes
            .iter()
            .map(|&(xi, w)| {
                let t = 0.5 * (xi + 1.0);
                0.5 * w * upper.eval(t).y_mm * upper.derivative(t).x_mm
            })
            .sum();
        2.0 * half
    }

    /// Bounds of the outline in its own frame. `min_x` is negative when `lt > 4·lh` (the root end
    /// bulges behind the origin).
    pub fn local_bounds(&self) -> BoundsMm {
        self.outline(PointMm::default(), 0.0).bounds()
    }

    /// Bounds of the outline placed at `anchor` and rotated by `beta_rad`.
    pub fn placed_bounds(&self, anchor: PointMm, beta_rad: f64) -> BoundsMm {
        self.outline(anchor, beta_rad).bounds()
    }
}

impl Outline {
    /// Exact axis-aligned bounds of both curves (extremes at the end points and at the roots of
    /// each coordinate's derivative).
    pub fn bounds(&self) -> BoundsMm {
        let mut b =
            BoundsMm { min_x: f64::INFINITY, min_y: f64::INFINITY, max_x: f64::NEG_INFINITY, max_y: f64::NEG_INFINITY };
        for c in [self.upper, self.lower] {
            let mut ts = vec![0.0, 1.0];
            let xs = c.points.map(|p| p.x_mm);
            let ys = c.points.map(|p| p.y_mm);
            ts.extend(derivative_roots(xs));
            ts.extend(derivative_roots(ys));
            for t in ts {
                let p = c.eval(t);
                b.min_x = b.min_x.min(p.x_mm);
                b.max_x = b.max_x.max(p.x_mm);
                b.min_y = b.min_y.min(p.y_mm);
                b.max_y = b.max_y.max(p.y_mm);
            }
        }
        b
    }
}

/// Parameters in (0, 1) where the derivative of a 1D cubic Bézier with coefficients `p` vanishes.
fn derivative_roots(p: [f64; 4]) -> Vec<f64> {
    // B'(t)/3 = a·t² + b·t + c with these coefficients.
    let (d0, d1, d2) = (p[1] - p[0], p[2] - p[1], p[3] - p[2]);
    let a = d0 - 2.0 * d1 + d2;
    let b = 2.0 * (d1 - d0);
    let c = d0;
    let scale = d0.abs().max(d1.abs()).max(d2.abs()).max(1e-300);
    let mut roots = Vec::with_capacity(2);
    if a.abs() <= 1e-12 * scale {
        if b.abs() > 1e-12 * scale {
            roots.push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let s = disc.sqrt();
            roots.push((-b + s) / (2.0 * a));
            roots.push((-b - s) / (2.0 * a));
        }
    }
    roots.retain(|t| *t > 0.0 && *t < 1.0);
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn belly_is_at_half_parameter() {
        let f = Footprint::new(10.0, 4.0, 3.0).unwrap();
        let p = f.upper().eval(0.5);
        assert!((p.x_mm - 4.0).abs() < 1e-12);
        assert!((p.y_mm - 3.0).abs() < 1e-12);
        assert!(f.upper().derivative(0.5).y_mm.abs() < 1e-12);
    }

    #[test]
    fn area_matches_dense_polygon() {
        let f = Footprint::new(9.0, 3.5, 2.2).unwrap();
        let o = f.outline(PointMm::default(), 0.0);
        let n = 20_000;
        let mut pts = Vec::new();
        for i in 0..n {
            pts.push(o.upper.eval(i as f64 / n as f64));
        }
        for i in 0..n {
            pts.push(o.lower.eval(i as f64 / n as f64));
        }
        let mut a = 0.0;
        for i in 0..pts.len() {
            let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
            a += p.x_mm * q.y_mm - q.x_mm * p.y_mm;
        }
        let poly = (a / 2.0).abs();
        assert!((poly - f.area_mm2()).abs() < 1e-5, "{poly} vs {}", f.area_mm2());
    }

    #[test]
    fn rejects_bad_lengths() {
        assert!(Footprint::new(-1.0, 1.0, 1.0).is_err());
        assert!(Footprint::new(1.0, f64::NAN, 1.0).is_err());
        assert!(Footprint::new(1.0, 1.0, 0.0).is_err());
    }

    #[test]
    fn root_bulges_behind_origin_when_tip_is_long() {
        let f = Footprint::new(20.0, 2.0, 2.0).unwrap();
        assert!(f.local_bounds().min_x < 0.0);
        let g = Footprint::new(6.0, 2.0, 2.0).unwrap();
        assert!(g.local_bounds().min_x.abs() < 1e-12);
    }
}
