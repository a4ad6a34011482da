//! The analytic image model: each footprint is the soft teardrop of `crate::soft`, its
//! coverage a smoothstep of the signed measure over the edge half-width, its derivatives in
//! closed form.

use rayon::prelude::*;

use super::{CHUNK, Fp, ImageModel, Raster, UnionSums};
use crate::soft::edge;

/// Bins of a footprint's half-width bounds (`crate::soft::WidthBounds`): pixels they class as
/// fully inside or outside skip the Newton solve.
const WIDTH_BINS: usize = 32;

/// The analytic image model.
pub(crate) struct Analytic {
    /// Edge half-width, mm.
    pub(crate) edge_mm: f64,
}

/// A pixel in a footprint's soft edge, kept from the union pass for the gradient pass.
#[derive(Clone, Copy, Debug)]
struct EdgePx {
    /// Pixel index, row-major.
    k: u32,
    /// `1 − c`.
    one_minus_c: f64,
    /// `∂c/∂d`, per mm.
    dc: f64,
    /// `∂d/∂(x, y, h, α, β)` of the footprint at this pixel.
    a: [f64; 5],
}

impl ImageModel for Analytic {
    fn union(&self, r: &Raster<'_>, fps: &[Fp]) -> UnionSums {
        self.union_edges(r, fps, false).0
    }

    fn image_term(&self, r: &Raster<'_>, fps: &[Fp], want_grad: bool) -> (f64, Vec<[f64; 5]>) {
        let (sums, edges) = self.union_edges(r, fps, want_grad);
        let (image, q) = sums.residuals(r);
        let per_fp = if want_grad { per_footprint(&edges, &q) } else { Vec::new() };
        (image, per_fp)
    }
}

/// Each footprint's `∂L/∂(x, y, h, α, β)` from its soft edge's pixels, given per pixel
/// `q = ∂L/∂U · Π(1 − c)`.
fn per_footprint(edges: &[Vec<EdgePx>], q: &[f64]) -> Vec<[f64; 5]> {
    edges
        .par_iter()
        .map(|list| {
            let mut g = [0.0f64; 5];
            for px in list {
                let qk = q[px.k as usize];
                if qk == 0.0 {
                    continue;
                }
                // ∂U/∂c_i = Π_{j≠i}(1 − c_j) = Π/(1 − c_i), so ∂L/∂d = q/(1 − c)·∂c/∂d.
                let w = qk / px.one_minus_c * px.dc;
                for (gi, ai) in g.iter_mut().zip(&px.a) {
                    *gi += w * ai;
                }
            }
            g
        })
        .collect()
}

impl Analytic {
    /// The soft union image `U` of `fps` on `r` and, for an upstream gradient `∂L/∂U` per pixel
    /// (`r`'s ink is not read), each footprint's `∂L/∂(x, y, h, α, β)`: the vector–Jacobian
    /// product of the soft render.
    pub(crate) fn render_vjp(&self, r: &Raster<'_>, fps: &[Fp], upstream: Option<&[f64]>) -> (Vec<f64>, Vec<[f64; 5]>) {
        let (sums, edges) = self.union_edges(r, fps, upstream.is_some());
        let per_fp = match upstream {
            Some(up) => {
                let q: Vec<f64> = up.iter().enumerate().map(|(k, g)| g * sums.keep(k)).collect();
                per_footprint(&edges, &q)
            }
            None => Vec::new(),
        };
        (sums.image(), per_fp)
    }

    /// The soft union's per-pixel sums and, when `want_edges`, per footprint the pixels of its
    /// soft edge (`0 < c < 1`) with what the gradient pass needs ([`EdgePx`]), in visiting
    /// order, so that pass neither scans the footprint's box again nor solves for `t*` again.
    fn union_edges(&self, r: &Raster<'_>, fps: &[Fp], want_edges: bool) -> (UnionSums, Vec<Vec<EdgePx>>) {
        let n = r.width * r.height;
        type Part = (Vec<f64>, Vec<u32>, Vec<Vec<EdgePx>>);
        let parts: Vec<Part> = fps
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut s = vec![0.0f64; n];
                let mut sat = vec![0u32; n];
                let mut edges = Vec::with_capacity(if want_edges { chunk.len() } else { 0 });
                for f in chunk {
                    let list = self.add_footprint(r, f, want_edges, &mut s, &mut sat);
                    if want_edges {
                        edges.push(list);
                    }
                }
                (s, sat, edges)
            })
            .collect();
        let mut s = vec![0.0f64; n];
        let mut sat = vec![0u32; n];
        let mut edges = Vec::with_capacity(if want_edges { fps.len() } else { 0 });
        for (ps, pt, pe) in parts {
            for k in 0..n {
                s[k] += ps[k];
                sat[k] += pt[k];
            }
            edges.extend(pe);
        }
        (UnionSums { log_keep: s, saturated: Some(sat) }, edges)
    }

    /// Adds footprint `f`'s coverage to the union's sums `s` (`Σ ln(1 − c)`) and `sat`
    /// (saturated coverages) and, when `want_edges`, returns its soft edge's pixels.
    fn add_footprint(&self, r: &Raster<'_>, f: &Fp, want_edges: bool, s: &mut [f64], sat: &mut [u32]) -> Vec<EdgePx> {
        let e = self.edge_mm;
        let wb = f.shape.width_bounds(WIDTH_BINS);
        let l = f.shape.length();
        let (sb, cb) = f.beta.sin_cos();
        let mut list = Vec::new();
        visit(r, e, f, (sb, cb), |k, u, v| {
            if u > 0.0 && u < l {
                match wb.classify(u, v.abs(), e) {
                    Some(true) => {
                        sat[k] += 1;
                        return;
                    }
                    Some(false) => return,
                    None => {}
                }
            }
            let c = if want_edges {
                let m = f.shape.measure_grad_with(u, v, &wb);
                let (c, dc) = edge(m.d, e);
                if c > 0.0 && c < 1.0 && dc != 0.0 {
                    let [gu, gv, glt, glh, glr] = m.grad;
                    list.push(EdgePx {
                        k: k as u32,
                        one_minus_c: 1.0 - c,
                        dc,
                        a: [
                            -cb * gu + sb * gv,
                            -sb * gu - cb * gv,
                            glt * f.dh[0] + glh * f.dh[1] + glr * f.dh[2],
                            glt * f.da[0] + glh * f.da[1] + glr * f.da[2],
                            // Turning the footprint: ∂u/∂β = v, ∂v/∂β = −u (and, for a
                            // profile whose lengths depend on β, their partials).
                            if f.db == [0.0; 3] {
                                gu * v - gv * u
                            } else {
                                gu * v - gv * u + glt * f.db[0] + glh * f.db[1] + glr * f.db[2]
                            },
                        ],
                    });
                }
                c
            } else {
                edge(f.shape.measure(u, v), e).0
            };
            if c >= 1.0 {
                sat[k] += 1;
            } else if c > 0.0 {
                s[k] += (1.0 - c).ln();
            }
        });
        list
    }
}

/// Visits every pixel of footprint `f`'s box on `t` whose centre lies in the footprint's band
/// (`−e ≤ u ≤ L + e`, `|v| ≤ lr + e`, `e` the edge half-width in mm), row by row, with its
/// index and local coordinates `(u, v)`; `(sb, cb)` is the sine and cosine of the footprint's
/// direction. Each row scans only the columns where the band can be, not the whole box.
#[inline]
fn visit(t: &Raster<'_>, e: f64, f: &Fp, (sb, cb): (f64, f64), mut each: impl FnMut(usize, f64, f64)) {
    let (ul, uh, vh) = (-e, f.shape.length() + e, f.shape.lr + e);
    let w = t.width;
    // On each row, the columns where the band can be: `ul ≤ u ≤ uh` and `|v| ≤ vh` bound
    // `px·cb` and `px·sb`; each bound gives an interval of `px` (widened by a hair, the
    // per-pixel tests below decide).
    let interval = |a: f64, lo: f64, hi: f64| -> Option<(f64, f64)> {
        if a > 1e-12 {
            Some((lo / a, hi / a))
        } else if a < -1e-12 {
            Some((hi / a, lo / a))
        } else if lo <= 0.0 && 0.0 <= hi {
            Some((f64::NEG_INFINITY, f64::INFINITY))
        } else {
            None
        }
    };
    for j in f.j0..=f.j1 {
        let py = t.origin[1] + (j as f64 + 0.5) * t.mm_per_px - f.y;
        let (Some(a), Some(b)) = (interval(cb, ul - py * sb, uh - py * sb), interval(sb, py * cb - vh, py * cb + vh))
        else {
            continue;
        };
        let (lo, hi) = (a.0.max(b.0) - 1e-9, a.1.min(b.1) + 1e-9);
        if lo > hi {
            continue;
        }
        let col = |px: f64| (px + f.x - t.origin[0]) / t.mm_per_px - 0.5;
        let c0 = col(lo).ceil().max(f.i0 as f64) as i64;
        let c1 = col(hi).floor().min(f.i1 as f64) as i64;
        for i in c0..=c1 {
            let px = t.origin[0] + (i as f64 + 0.5) * t.mm_per_px - f.x;
            let u = px * cb + py * sb;
            if u < ul || u > uh {
                continue;
            }
            let v = -px * sb + py * cb;
            if v.abs() > vh {
                continue;
            }
            each(j as usize * w + i as usize, u, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::soft::Shape;

    /// `visit` scans only part of each row; it must reach exactly the pixels a scan of the
    /// whole box reaches, at every angle, including the axis-aligned ones.
    #[test]
    fn visiting_rows_by_interval_reaches_every_pixel_of_the_band() {
        let ink = vec![0.0; 64 * 48];
        let t = Raster { width: 64, height: 48, origin: [1.0, 2.0], mm_per_px: 0.7, ink: &ink, ink_sum: 0.0 };
        let e = 0.5;
        let shape = Shape { lt: 13.5, lh: 5.25, lr: 3.0 };
        for k in 0..72 {
            let beta = k as f64 * std::f64::consts::TAU / 72.0 + if k % 9 == 0 { 0.0 } else { 0.013 };
            let (sb, cb) = beta.sin_cos();
            for (x, y, box_) in
                [(20.0, 18.0, (0, 63, 0, 47)), (3.0, 30.0, (0, 20, 10, 40)), (44.5, 4.1, (40, 63, 0, 12))]
            {
                let f = Fp {
                    x,
                    y,
                    h: 0.0,
                    alpha: 0.0,
                    beta,
                    shape,
                    dh: [0.0; 3],
                    da: [0.0; 3],
                    db: [0.0; 3],
                    i0: box_.0,
                    i1: box_.1,
                    j0: box_.2,
                    j1: box_.3,
                };
                let mut got = Vec::new();
                visit(&t, e, &f, (sb, cb), |k, u, v| got.push((k, u, v)));
                let mut want = Vec::new();
                let (ul, uh, vh) = (-e, shape.length() + e, shape.lr + e);
                for j in f.j0..=f.j1 {
                    let py = t.origin[1] + (j as f64 + 0.5) * t.mm_per_px - f.y;
                    for i in f.i0..=f.i1 {
                        let px = t.origin[0] + (i as f64 + 0.5) * t.mm_per_px - f.x;
                        let (u, v) = (px * cb + py * sb, -px * sb + py * cb);
                        if (ul..=uh).contains(&u) && v.abs() <= vh {
                            want.push((j as usize * 64 + i as usize, u, v));
                        }
                    }
                }
                assert_eq!(got, want, "β {beta} at ({x}, {y})");
            }
        }
    }
}
