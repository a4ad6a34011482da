//! A plane-to-plane projective map (homography), fitted by the normalised DLT.

use nalgebra::{DMatrix, Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// A homography: `(x, y) ↦ (h·(x, y, 1))` dehomogenised; here paper mm → photo px.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Homography {
    /// The 3×3 matrix, row major, scaled so that its bottom-right entry is 1 where it can be.
    pub m: [[f64; 3]; 3],
}

impl Homography {
    /// The identity map.
    pub fn identity() -> Self {
        Homography { m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] }
    }

    fn mat(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.m[r][c])
    }

    fn from_mat(m: &Matrix3<f64>) -> Option<Self> {
        let s = if m[(2, 2)].abs() > 1e-12 { m[(2, 2)] } else { m.norm() };
        if !s.is_finite() || s == 0.0 {
            return None;
        }
        let m = m / s;
        let out = Homography { m: std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])) };
        out.m.iter().flatten().all(|v| v.is_finite()).then_some(out)
    }

    /// Maps a point.
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let m = &self.m;
        let w = m[2][0] * p[0] + m[2][1] * p[1] + m[2][2];
        [(m[0][0] * p[0] + m[0][1] * p[1] + m[0][2]) / w, (m[1][0] * p[0] + m[1][1] * p[1] + m[1][2]) / w]
    }

    /// The inverse map, `None` when the matrix is singular.
    pub fn inverse(&self) -> Option<Self> {
        Self::from_mat(&self.mat().try_inverse()?)
    }

    /// The local scale at `p`: the square root of the Jacobian's determinant (output units per
    /// input unit, e.g. photo px per paper mm).
    pub fn scale_at(&self, p: [f64; 2]) -> f64 {
        let e = 1e-3;
        let (a, b, c) = (self.apply(p), self.apply([p[0] + e, p[1]]), self.apply([p[0], p[1] + e]));
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        (det.abs()).sqrt() / e
    }

    /// The least-squares homography mapping `src[i]` onto `dst[i]` (at least four pairs, no three
    /// of the first four on one line), by the direct linear transform on points normalised to
    /// mean 0 and mean distance √2 (Hartley). `None` for fewer than four pairs or a degenerate
    /// configuration.
    pub fn fit(src: &[[f64; 2]], dst: &[[f64; 2]]) -> Option<Self> {
        let n = src.len();
        if n < 4 || dst.len() != n {
            return None;
        }
        let (ts, td) = (normaliser(src)?, normaliser(dst)?);
        // 2n equations, at least nine rows so the SVD gives the whole null space.
        let rows = (2 * n).max(9);
        let mut a = DMatrix::<f64>::zeros(rows, 9);
        for i in 0..n {
            let p = ts * Vector3::new(src[i][0], src[i][1], 1.0);
            let q = td * Vector3::new(dst[i][0], dst[i][1], 1.0);
            let (x, y, u, v) = (p[0] / p[2], p[1] / p[2], q[0] / q[2], q[1] / q[2]);
            let r1 = [-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u];
            let r2 = [0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v];
            for k in 0..9 {
                a[(2 * i, k)] = r1[k];
                a[(2 * i + 1, k)] = r2[k];
            }
        }
        let svd = a.svd(false, true);
        let vt = svd.v_t?;
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]));
        let k = order[0];
        // A second (near) null direction: the points do not fix the map (three on a line).
        let sv_max = svd.singular_values[order[order.len() - 1]];
        if svd.singular_values[order[1]] <= 1e-9 * sv_max {
            return None;
        }
        let h = Matrix3::from_fn(|r, c| vt[(k, 3 * r + c)]);
        let full = td.try_inverse()? * h * ts;
        let out = Self::from_mat(&full)?;
        // A degenerate fit maps the points nowhere near their partners.
        let ok = src.iter().zip(dst).all(|(s, d)| out.apply(*s).iter().all(|v| v.is_finite()) && d[0].is_finite());
        ok.then_some(out)
    }
}

/// The similarity that moves points to mean 0 and mean distance √2.
fn normaliser(p: &[[f64; 2]]) -> Option<Matrix3<f64>> {
    let n = p.len() as f64;
    let (mx, my) = (p.iter().map(|q| q[0]).sum::<f64>() / n, p.iter().map(|q| q[1]).sum::<f64>() / n);
    let d = p.iter().map(|q| (q[0] - mx).hypot(q[1] - my)).sum::<f64>() / n;
    if !(d > 1e-12) {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / d;
    Some(Matrix3::new(s, 0.0, -s * mx, 0.0, s, -s * my, 0.0, 0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_projective_map_is_recovered_from_six_points_and_inverted() {
        let truth = Homography { m: [[3.1, 0.4, 120.0], [-0.2, 2.9, 80.0], [1e-4, -2e-4, 1.0]] };
        let src = [[0.0, 0.0], [210.0, 0.0], [210.0, 297.0], [0.0, 297.0], [40.0, 7.0], [105.0, 290.0]];
        let dst: Vec<[f64; 2]> = src.iter().map(|p| truth.apply(*p)).collect();
        let h = Homography::fit(&src, &dst).unwrap();
        for p in [[10.0, 20.0], [200.0, 280.0], [105.0, 150.0]] {
            let (a, b) = (h.apply(p), truth.apply(p));
            assert!((a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6, "{a:?} {b:?}");
            let back = h.inverse().unwrap().apply(a);
            assert!((back[0] - p[0]).abs() < 1e-6 && (back[1] - p[1]).abs() < 1e-6);
        }
        // Three points on a line and a fourth: no homography.
        assert!(Homography::fit(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]], &dst[..4]).is_none());
    }
}
