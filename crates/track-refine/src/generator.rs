//! The generator path ([`crate::Gradients::Generator`], cargo feature `generator`): an image
//! model (`crate::image::ImageModel`) in which every
//! footprint's image comes from the B-BSMG generator (neural-gen), placed and rotated onto the
//! target raster by bilinear resampling (as `neural_gen::render_track` places them),
//! and the image term's gradient comes from the network and the image:
//!
//! * with respect to `(h, α)` (and β where the generator's β input is not clamped): the network's
//!   vector–Jacobian product (`neural_gen::InputVjp`, one forward and one backward pass per
//!   batch of `BATCH` footprints), plus the move of the footprint inside the generator's
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

use std::sync::Arc;

use brush_model::{BrushProfile, Extrapolation, PointMm, Press, Range};
use neural_gen::{Generator, InputVjp, Tape};
use rayon::prelude::*;

use crate::image::{CHUNK, Fp, ImageModel, Raster, UnionSums};
use crate::{Gradients, Problem, RefineError};

/// Footprints per generator batch (one forward and one backward pass each).
pub(crate) const BATCH: usize = 128;

/// A B-BSMG generator prepared for refinement: the image model of the generator path
/// ([`crate::refine_with_generator`], [`Problem::with_generator`]).
///
/// # Examples
/// ```
/// use neural_gen::{Arch, Generator, GeneratorConfig};
/// use track_refine::brush_model::BrushProfile;
/// use track_refine::{GenMode, GenModel};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// // An untrained tiny generator (a real one comes from `Generator::load`).
/// let generator = Generator::new(GeneratorConfig::new(pen1, Arch::tiny_32()), 5)?;
/// let model = GenModel::new(&generator)?.with_mode(GenMode::Vjp);
/// assert_eq!(model.profile_name(), "pen1");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct GenModel {
    net: InputVjp,
    size: usize,
    px_per_mm: f64,
    beta: Range,
    profile: BrushProfile,
    mode: GenMode,
}

/// How the generator's derivatives with respect to the press are taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GenMode {
    /// One image per footprint and one reverse-mode VJP per footprint (each footprint's
    /// upstream image holds its own pixels' `∂L/∂c`): one forward and one backward pass per
    /// batch of 128 footprints. Exact, and slow: a character has thousands of footprints.
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

impl GenMode {
    /// The default mode: [`GenMode::Shared`] at 0.05 mm in h and 0.05° in α and β (why:
    /// docs/trajectory.md, "Refinement").
    pub const DEFAULT: GenMode =
        GenMode::Shared { quantum: [0.05, 0.05 * std::f64::consts::PI / 180.0, 0.05 * std::f64::consts::PI / 180.0] };
}

impl Default for GenMode {
    /// [`GenMode::DEFAULT`].
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl GenModel {
    /// Prepares a generator (copies its weights), in [`GenMode::DEFAULT`].
    ///
    /// # Errors
    /// [`RefineError::Generator`] (with neural-gen's error as its source) when the weights
    /// cannot be read.
    pub fn new(g: &Generator) -> Result<Self, RefineError> {
        Ok(Self {
            net: g.kernels()?.clone(),
            size: g.config.size as usize,
            px_per_mm: g.config.px_per_mm,
            beta: g.config.ranges.beta_rad,
            profile: g.config.profile.clone(),
            mode: GenMode::DEFAULT,
        })
    }

    /// The same generator with another [`GenMode`].
    pub fn with_mode(mut self, mode: GenMode) -> Self {
        self.mode = mode;
        self
    }

    /// Each footprint's image source: the presses that go into the network and, per
    /// footprint, the index of its press.
    fn sources(&self, fps: &[Fp], places: &[Place]) -> (Vec<Press>, Vec<usize>) {
        match self.mode {
            GenMode::Vjp => (
                fps.iter().zip(places).map(|(f, p)| Press::new(f.h, f.alpha, p.beta_gen)).collect(),
                (0..fps.len()).collect(),
            ),
            GenMode::Shared { quantum } => {
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

    /// [`GenModel::visit`] over the pixels of footprint `f` where the residual weight `q` is
    /// not 0: adds each one's spatial share to `g` ([`GenModel::add_spatial`]), then calls
    /// `image(g, w, o, tx, ty)` with its weight and place in the footprint's image `src`.
    #[allow(
        clippy::too_many_arguments,
        reason = "the visit's inputs and the two outputs, as `visit` and `add_spatial` take them"
    )]
    #[inline]
    fn weighted_pixels<const N: usize>(
        &self,
        r: &Raster<'_>,
        f: &Fp,
        pl: &Place,
        q: &[f64],
        src: &[f32],
        g: &mut [f64; N],
        mut image: impl FnMut(&mut [f64; N], f64, usize, f64, f64),
    ) {
        self.visit(r, f, pl, |p, o, tx, ty, lx, ly| {
            let qk = q[p];
            if qk == 0.0 {
                return;
            }
            let w = self.add_spatial(g, src, pl, qk, (o, tx, ty, lx, ly));
            image(g, w, o, tx, ty);
        });
    }

    /// The footprints' placements, images and soft union (the first half of the image term).
    fn render(&self, r: &Raster<'_>, fps: &[Fp], want_grad: bool) -> (Pass, UnionSums) {
        let places = self.places(fps, want_grad);
        let (presses, which) = self.sources(fps, &places);
        let tapes: Vec<Tape> = presses.chunks(BATCH).map(|c| self.net.forward(c)).collect();
        let pass = Pass { places, which, tapes };
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
                    let src = pass.image(k);
                    self.visit(r, f, &pass.places[k], |p, o, tx, ty, _, _| {
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
        // The generator's sigmoid never reaches 0 or 1: no coverage saturates.
        (pass, UnionSums { log_keep: lsum, saturated: None })
    }

    /// Each footprint's `∂/∂(x, y, h, α, β)` given the residual weights `q` (per pixel,
    /// [`UnionSums::residuals`]).
    fn partials(&self, r: &Raster<'_>, fps: &[Fp], pass: &Pass, q: &[f64]) -> Vec<[f64; 5]> {
        match self.mode {
            GenMode::Shared { .. } => self.partials_shared(r, fps, pass, q),
            GenMode::Vjp => self.partials_vjp(r, fps, pass, q),
        }
    }

    /// [`GenModel::partials`] in [`GenMode::Shared`]: each footprint's pixels read the
    /// forward-mode Jacobian images of its press.
    fn partials_shared(&self, r: &Raster<'_>, fps: &[Fp], pass: &Pass, q: &[f64]) -> Vec<[f64; 5]> {
        let (places, tapes) = (&pass.places, &pass.tapes);
        let s = self.size;
        // Tangents only for what varies: α where a footprint is tilted, β where the
        // generator's β input follows the direction.
        let need = [true, fps.iter().any(|f| f.alpha > 0.0), places.iter().any(|p| p.follows > 0.0)];
        let jac: Vec<Vec<f32>> = tapes.iter().map(|t| self.net.jacobian_of(t, need)).collect();
        let ss = s * s;
        fps.par_iter()
            .enumerate()
            .map(|(k, f)| {
                let (u, pl) = (pass.which[k], &places[k]);
                let src = pass.image(k);
                let j = &jac[u / BATCH][(u % BATCH) * 3 * ss..(u % BATCH + 1) * 3 * ss];
                // x, y, θ, ∂L/∂a (2), ∂L/∂(h, α, βg) through the image (3).
                let mut g = [0.0f64; 8];
                self.weighted_pixels(r, f, pl, q, src, &mut g, |g, w, o, tx, ty| {
                    for i in 0..3 {
                        g[5 + i] += w * bilerp(&j[i * ss..(i + 1) * ss], o, s, tx, ty);
                    }
                });
                press_partials(&g, [g[5], g[6], g[7]], pl)
            })
            .collect()
    }

    /// [`GenModel::partials`] in [`GenMode::Vjp`]: per batch, each footprint's upstream image
    /// and one reverse pass.
    fn partials_vjp(&self, r: &Raster<'_>, fps: &[Fp], pass: &Pass, q: &[f64]) -> Vec<[f64; 5]> {
        let (places, tapes) = (&pass.places, &pass.tapes);
        let s = self.size;
        let mut per_fp = Vec::with_capacity(fps.len());
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
                    self.weighted_pixels(r, f, pl, q, src, &mut g, |_, w, o, tx, ty| {
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
                per_fp.push(press_partials(sp, *vj, &places[lo + m]));
            }
        }
        per_fp
    }
}

/// A footprint's `∂L/∂(x, y, h, α, β)` from its spatial parts `sp` (∂L/∂(x, y, θ) and Σ ∂L/∂a,
/// [`GenModel::add_spatial`]) and the gradient `gi` of its image with respect to the
/// generator's (h, α, β): the anchor's and the direction's dependence on the press added.
fn press_partials(sp: &[f64], gi: [f64; 3], pl: &Place) -> [f64; 5] {
    let an = |d: [f64; 2]| sp[3] * d[0] + sp[4] * d[1];
    [
        sp[0],
        sp[1],
        gi[0] + an(pl.da[0]),
        gi[1] + an(pl.da[1]),
        sp[2] * (1.0 - pl.follows) + pl.follows * (gi[2] + an(pl.da[2])),
    ]
}

/// One rendering of the footprints: placements, the network's forward passes (tapes) and
/// which press (image) each footprint uses.
struct Pass {
    places: Vec<Place>,
    which: Vec<usize>,
    tapes: Vec<Tape>,
}

impl Pass {
    /// Footprint `k`'s image.
    fn image(&self, k: usize) -> &[f32] {
        self.tapes[self.which[k] / BATCH].image(self.which[k] % BATCH)
    }
}

impl ImageModel for GenModel {
    fn union(&self, r: &Raster<'_>, fps: &[Fp]) -> UnionSums {
        self.render(r, fps, false).1
    }

    fn image_term(&self, r: &Raster<'_>, fps: &[Fp], want_grad: bool) -> (f64, Vec<[f64; 5]>) {
        let (pass, sums) = self.render(r, fps, want_grad);
        let (image, q) = sums.residuals(r);
        let per_fp = if want_grad { self.partials(r, fps, &pass, &q) } else { Vec::new() };
        (image, per_fp)
    }
}

impl Problem<'_> {
    /// The same problem with the image term on `generator` (the generator path): footprint
    /// images from the network, gradients from its VJP and the images' spatial gradients.
    ///
    /// # Errors
    /// [`RefineError::GeneratorProfile`] when the generator was trained for another brush
    /// profile.
    pub fn with_generator(mut self, generator: Arc<GenModel>) -> Result<Self, RefineError> {
        if generator.profile_name() != self.profile.name {
            return Err(RefineError::GeneratorProfile {
                generator: generator.profile_name().to_owned(),
                track: self.profile.name.clone(),
            });
        }
        self.image = generator;
        self.opts.gradients = Gradients::Generator;
        Ok(self)
    }
}

#[inline]
fn bilerp(src: &[f32], o: usize, s: usize, tx: f64, ty: f64) -> f64 {
    let (v00, v10, v01, v11) = (src[o] as f64, src[o + 1] as f64, src[o + s] as f64, src[o + s + 1] as f64);
    (v00 * (1.0 - tx) + v10 * tx) * (1.0 - ty) + (v01 * (1.0 - tx) + v11 * tx) * ty
}
