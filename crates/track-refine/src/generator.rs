//! The generator path ([`crate::Gradients::Generator`], cargo feature `generator`): every
//! footprint's image comes from the B-BSMG generator (neural-gen), placed and rotated onto the
//! target raster by bilinear resampling (as `neural_gen::compose::render_track` places them),
//! and the image term's gradient comes from the network and the image:
//!
//! * with respect to `(h, α)` (and β where the generator's β input is not clamped): the network's
//!   vector–Jacobian product (`neural_gen::InputVjp`, one forward and one backward pass per
//!   batch of [`BATCH`] footprints), plus the move of the footprint inside the generator's
//!   canvas (the canvas centres each footprint's bounds, so the anchor moves with the press;
//!   its derivative by central differences of the exact bounds);
//! * with respect to position and direction: the image's spatial gradient (the derivative of
//!   the bilinear interpolant) through the placement: pixel `P` samples the generated image at
//!   `g = (a + R(βg − β)·(P − q))·k − ½` (`q` the point, `a` the anchor in the canvas, `k` its
//!   px/mm), so `∂g/∂q = −k·R`, `∂g/∂β = k·(l_y, −l_x)` with `l = R·(P − q)`.
//!
//! The loss is the analytic path's (soft union against the glyph; the generator's sigmoid never
//! reaches 0 or 1, so no coverage saturates). The judge is never the generator: callers score
//! the refined track with the analytic renderer and the executed simulation.

use brush_model::{BrushProfile, Extrapolation, PointMm, Press, Range};
use neural_gen::{Generator, InputVjp, Tape};
use rayon::prelude::*;

use crate::RefineError;
use crate::problem::{CHUNK, Fp};

/// Footprints per generator batch (one forward and one backward pass each).
pub const BATCH: usize = 128;

/// A generator prepared for refinement.
pub struct GenModel {
    net: InputVjp,
    size: usize,
    px_per_mm: f64,
    beta: Range,
    profile: BrushProfile,
    mode: Mode,
}

/// How the network's derivatives with respect to the press are taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// One image per footprint and one reverse-mode VJP per footprint (each footprint's
    /// upstream image holds its own pixels' `∂L/∂c`): one forward and one backward pass per
    /// batch of [`BATCH`] footprints. Exact, and slow: a character has thousands of footprints.
    Vjp,
    /// Presses rounded to multiples of `quantum` (h in mm, α and β in rad; 0 keeps a value
    /// exact); footprints whose presses round alike share one image and its Jacobian
    /// `∂image/∂(h, α, β)` (forward mode, three tangents: `InputVjp::jacobian`), and each
    /// footprint's derivative is its own pixels' `Σ ∂L/∂c · ∂c/∂press` read from the Jacobian
    /// images. A character's thousands of footprints need a few hundred network evaluations.
    /// The derivative at a rounded press is the network's there (straight through the
    /// rounding).
    Shared {
        /// Rounding step of h (mm), α (rad), β (rad).
        quantum: [f64; 3],
    },
}

/// The default mode: [`Mode::Shared`] at 0.05 mm in h and 0.05° in α and β (pen1's lengths
/// move by under 0.05 mm per step, well under a pixel of the default 256² analysis raster).
pub const DEFAULT_MODE: Mode =
    Mode::Shared { quantum: [0.05, 0.05 * std::f64::consts::PI / 180.0, 0.05 * std::f64::consts::PI / 180.0] };

impl GenModel {
    /// Prepares a generator (copies its weights).
    ///
    /// # Errors
    /// [`RefineError::Generator`] when the weights cannot be read.
    pub fn new(g: &Generator) -> Result<Self, RefineError> {
        Ok(Self {
            net: InputVjp::new(g).map_err(|e| RefineError::Generator(e.to_string()))?,
            size: g.config.size as usize,
            px_per_mm: g.config.px_per_mm,
            beta: g.config.ranges.beta_rad,
            profile: g.config.profile.clone(),
            mode: DEFAULT_MODE,
        })
    }

    /// The same generator with another [`Mode`].
    pub fn with_mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        self
    }

    /// Each footprint's image source: the presses that go into the network and, per
    /// footprint, the index of its press.
    fn sources(&self, fps: &[Fp], places: &[Place]) -> (Vec<Press>, Vec<usize>) {
        match self.mode {
            Mode::Vjp => (
                fps.iter().zip(places).map(|(f, p)| Press::new(f.h, f.alpha, p.beta_gen)).collect(),
                (0..fps.len()).collect(),
            ),
            Mode::Shared { quantum } => {
                let mut uniq: std::collections::BTreeMap<[i64; 3], (Press, Vec<usize>)> =
                    std::collections::BTreeMap::new();
                for (k, (f, p)) in fps.iter().zip(places).enumerate() {
                    let v = [f.h, f.alpha, p.beta_gen];
                    let (mut r, mut key) = ([0.0; 3], [0i64; 3]);
                    for i in 0..3 {
                        if quantum[i] > 0.0 {
                            let q = (v[i] / quantum[i]).round();
                            (r[i], key[i]) = (q * quantum[i], q as i64);
                        } else {
                            (r[i], key[i]) = (v[i], v[i].to_bits() as i64);
                        }
                    }
                    uniq.entry(key).or_insert_with(|| (Press::new(r[0], r[1], r[2]), Vec::new())).1.push(k);
                }
                let mut which = vec![0usize; fps.len()];
                let mut presses = Vec::with_capacity(uniq.len());
                for (u, (press, members)) in uniq.into_values().enumerate() {
                    presses.push(press);
                    for k in members {
                        which[k] = u;
                    }
                }
                (presses, which)
            }
        }
    }

    /// The name of the brush profile the generator was trained for.
    pub fn profile_name(&self) -> &str {
        &self.profile.name
    }

    /// The canvas anchor (mm) of a press: the canvas centres the footprint's bounds.
    fn anchor(&self, h: f64, alpha: f64, beta_gen: f64) -> [f64; 2] {
        let fp = self.profile.predict(&Press::new(h, alpha, beta_gen), Extrapolation::Allow);
        let half = 0.5 * self.size as f64 / self.px_per_mm;
        match fp {
            Ok(fp) => {
                let c = fp.placed_bounds(PointMm::default(), beta_gen).centre();
                [half - c.x_mm, half - c.y_mm]
            }
            Err(_) => [half, half],
        }
    }
}

/// One footprint's placement.
struct Place {
    /// The generator's β input (the direction reduced into its calibrated range), rad.
    beta_gen: f64,
    /// 1 where `beta_gen` follows β (inside the range), else 0.
    follows: f64,
    /// `sin, cos` of `β − βg`.
    sn: f64,
    cs: f64,
    /// Canvas anchor, mm.
    a: [f64; 2],
    /// `∂a/∂(h, α, βg)`, mm per unit.
    da: [[f64; 2]; 3],
}

fn wrap(b: f64) -> f64 {
    (b + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// The image term on the generator: its value (`Σ (U − G)² / Σ G`), per footprint
/// `∂/∂(x, y, h, α, β)` when `want_grad`, and the soft union image.
pub(crate) struct ImageTerm {
    pub image: f64,
    pub per_fp: Vec<[f64; 5]>,
    pub union: Vec<f64>,
}

/// Target geometry the sums need.
pub(crate) struct Raster<'t> {
    pub width: usize,
    pub height: usize,
    pub origin: [f64; 2],
    pub mm_per_px: f64,
    pub ink: &'t [f32],
    pub ink_sum: f64,
}

impl GenModel {
    fn places(&self, fps: &[Fp], want_grad: bool) -> Vec<Place> {
        fps.par_iter()
            .map(|f| {
                let w = wrap(f.beta);
                let beta_gen = self.beta.clamp(w);
                let follows = if w > self.beta.min && w < self.beta.max { 1.0 } else { 0.0 };
                let (sn, cs) = (f.beta - beta_gen).sin_cos();
                let a = self.anchor(f.h, f.alpha, beta_gen);
                let mut da = [[0.0; 2]; 3];
                if want_grad {
                    let eps = [1e-4, 1e-5, 1e-5];
                    for (k, e) in eps.iter().enumerate() {
                        let mut p = [f.h, f.alpha, beta_gen];
                        p[k] += e;
                        let hi = self.anchor(p[0], p[1], p[2]);
                        p[k] -= 2.0 * e;
                        let lo = self.anchor(p[0], p[1], p[2]);
                        da[k] = [(hi[0] - lo[0]) / (2.0 * e), (hi[1] - lo[1]) / (2.0 * e)];
                    }
                }
                Place { beta_gen, follows, sn, cs, a, da }
            })
            .collect()
    }

    /// Visits the target pixels of a footprint's box whose sample falls inside the canvas,
    /// with the pixel index, the sample's integer corner, fractions and local offset `l` (mm).
    #[inline]
    fn visit(&self, r: &Raster<'_>, f: &Fp, pl: &Place, mut each: impl FnMut(usize, usize, f64, f64, f64, f64)) {
        let s = self.size;
        let k = self.px_per_mm;
        let lim = (s - 1) as f64;
        for j in f.j0..=f.j1 {
            let dy = r.origin[1] + (j as f64 + 0.5) * r.mm_per_px - f.y;
            for i in f.i0..=f.i1 {
                let dx = r.origin[0] + (i as f64 + 0.5) * r.mm_per_px - f.x;
                let (lx, ly) = (pl.cs * dx + pl.sn * dy, -pl.sn * dx + pl.cs * dy);
                let (gx, gy) = ((pl.a[0] + lx) * k - 0.5, (pl.a[1] + ly) * k - 0.5);
                if !(gx >= 0.0 && gy >= 0.0 && gx < lim && gy < lim) {
                    continue;
                }
                let (ix, iy) = (gx as usize, gy as usize);
                each(j as usize * r.width + i as usize, iy * s + ix, gx - ix as f64, gy - iy as f64, lx, ly);
            }
        }
    }

    /// One pixel's share of a footprint's spatial derivatives: adds ∂L/∂(x, y, θ) and Σ ∂L/∂a
    /// (the canvas anchor) into `g[..5]` and returns the pixel's weight `w = q / (1 − c)`
    /// (∂L/∂c of this footprint's image there). `at` is what [`GenModel::visit`] gives: the
    /// image offset, the bilinear fractions and the footprint-frame offset (mm).
    #[inline]
    fn add_spatial(&self, g: &mut [f64], src: &[f32], pl: &Place, qk: f64, at: (usize, f64, f64, f64, f64)) -> f64 {
        let (o, tx, ty, lx, ly) = at;
        let (s, kc) = (self.size, self.px_per_mm);
        let c = bilerp(src, o, s, tx, ty);
        let w = qk / (1.0 - c.min(1.0 - 1e-7));
        let (v00, v10, v01, v11) = (src[o] as f64, src[o + 1] as f64, src[o + s] as f64, src[o + s + 1] as f64);
        let cgx = (1.0 - ty) * (v10 - v00) + ty * (v11 - v01);
        let cgy = (1.0 - tx) * (v01 - v00) + tx * (v11 - v10);
        let (gx, gy) = (w * cgx * kc, w * cgy * kc);
        g[0] += -gx * pl.cs + gy * pl.sn;
        g[1] += -gx * pl.sn - gy * pl.cs;
        g[2] += gx * ly - gy * lx;
        g[3] += gx;
        g[4] += gy;
        w
    }

    /// The image term (see [`ImageTerm`]).
    pub(crate) fn image_term(&self, r: &Raster<'_>, fps: &[Fp], want_grad: bool) -> ImageTerm {
        let places = self.places(fps, want_grad);
        let (presses, which) = self.sources(fps, &places);
        let tapes: Vec<Tape> = presses.chunks(BATCH).map(|c| self.net.forward(c)).collect();
        let img = |k: usize| tapes[which[k] / BATCH].image(which[k] % BATCH);
        let s = self.size;
        let n = r.width * r.height;
        // Σ ln(1 − c) per pixel, over fixed chunks summed in order.
        let parts: Vec<Vec<f64>> = fps
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(ci, chunk)| {
                let mut acc = vec![0.0f64; n];
                for (m, f) in chunk.iter().enumerate() {
                    let k = ci * CHUNK + m;
                    let src = img(k);
                    self.visit(r, f, &places[k], |p, o, tx, ty, _, _| {
                        let c = bilerp(src, o, s, tx, ty);
                        acc[p] += (1.0 - c.min(1.0 - 1e-7)).ln();
                    });
                }
                acc
            })
            .collect();
        let mut lsum = vec![0.0f64; n];
        for part in parts {
            lsum.iter_mut().zip(&part).for_each(|(a, b)| *a += b);
        }
        let mut image = 0.0;
        let mut q = vec![0.0f64; n];
        let mut union = vec![0.0f64; n];
        for k in 0..n {
            let prod = lsum[k].exp();
            let u = 1.0 - prod;
            union[k] = u;
            let res = u - r.ink[k] as f64;
            image += res * res;
            q[k] = 2.0 * res / r.ink_sum * prod;
        }
        image /= r.ink_sum;
        let mut per_fp = Vec::new();
        if want_grad && matches!(self.mode, Mode::Shared { .. }) {
            // Tangents only for what varies: α where a footprint is tilted, β where the
            // generator's β input follows the direction.
            let need = [true, fps.iter().any(|f| f.alpha > 0.0), places.iter().any(|p| p.follows > 0.0)];
            let jac: Vec<Vec<f32>> = tapes.iter().map(|t| self.net.jacobian_of(t, need)).collect();
            let ss = s * s;
            per_fp = fps
                .par_iter()
                .enumerate()
                .map(|(k, f)| {
                    let (u, pl) = (which[k], &places[k]);
                    let src = img(k);
                    let j = &jac[u / BATCH][(u % BATCH) * 3 * ss..(u % BATCH + 1) * 3 * ss];
                    // x, y, θ, ∂L/∂a (2), ∂L/∂(h, α, βg) through the image (3).
                    let mut g = [0.0f64; 8];
                    self.visit(r, f, pl, |p, o, tx, ty, lx, ly| {
                        let qk = q[p];
                        if qk == 0.0 {
                            return;
                        }
                        let w = self.add_spatial(&mut g, src, pl, qk, (o, tx, ty, lx, ly));
                        for i in 0..3 {
                            g[5 + i] += w * bilerp(&j[i * ss..(i + 1) * ss], o, s, tx, ty);
                        }
                    });
                    let an = |d: [f64; 2]| g[3] * d[0] + g[4] * d[1];
                    [
                        g[0],
                        g[1],
                        g[5] + an(pl.da[0]),
                        g[6] + an(pl.da[1]),
                        g[2] * (1.0 - pl.follows) + pl.follows * (g[7] + an(pl.da[2])),
                    ]
                })
                .collect();
        } else if want_grad {
            per_fp.reserve(fps.len());
            for (bi, tape) in tapes.iter().enumerate() {
                let lo = bi * BATCH;
                let cnt = tape.len();
                let mut up = vec![0f32; cnt * s * s];
                // Per footprint: spatial parts (x, y, θ) and Σ ∂L/∂a.
                let spatial: Vec<[f64; 5]> = up
                    .par_chunks_mut(s * s)
                    .enumerate()
                    .map(|(m, upk)| {
                        let k = lo + m;
                        let (f, pl, src) = (&fps[k], &places[k], tape.image(m));
                        let mut g = [0.0f64; 5];
                        self.visit(r, f, pl, |p, o, tx, ty, lx, ly| {
                            let qk = q[p];
                            if qk == 0.0 {
                                return;
                            }
                            let w = self.add_spatial(&mut g, src, pl, qk, (o, tx, ty, lx, ly));
                            let wf = w as f32;
                            let (txf, tyf) = (tx as f32, ty as f32);
                            upk[o] += wf * (1.0 - txf) * (1.0 - tyf);
                            upk[o + 1] += wf * txf * (1.0 - tyf);
                            upk[o + s] += wf * (1.0 - txf) * tyf;
                            upk[o + s + 1] += wf * txf * tyf;
                        });
                        g
                    })
                    .collect();
                let v = self.net.vjp(tape, &up).expect("upstream sized by the tape");
                for (m, (sp, vj)) in spatial.iter().zip(&v).enumerate() {
                    let pl = &places[lo + m];
                    let an = |d: [f64; 2]| sp[3] * d[0] + sp[4] * d[1];
                    per_fp.push([
                        sp[0],
                        sp[1],
                        vj[0] + an(pl.da[0]),
                        vj[1] + an(pl.da[1]),
                        sp[2] * (1.0 - pl.follows) + pl.follows * (vj[2] + an(pl.da[2])),
                    ]);
                }
            }
        }
        ImageTerm { image, per_fp, union }
    }
}

#[inline]
fn bilerp(src: &[f32], o: usize, s: usize, tx: f64, ty: f64) -> f64 {
    let (v00, v10, v01, v11) = (src[o] as f64, src[o + 1] as f64, src[o + s] as f64, src[o + s + 1] as f64);
    (v00 * (1.0 - tx) + v10 * tx) * (1.0 - ty) + (v01 * (1.0 - tx) + v11 * tx) * ty
}
