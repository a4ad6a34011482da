//! Batched footprint images and their vector–Jacobian products with respect to the press,
//! without candle's autograd.
//!
//! Track refinement needs, for every footprint of a character (thousands), the image and then,
//! once the loss of all images together is known, `∂L/∂(h, α, β)` from `∂L/∂image`. That is a
//! gradient with respect to the network's *input* only, so the weight gradients candle's
//! autograd computes on every backward pass (a third of the work) are not needed, and neither is
//! the graph. [`InputVjp`] copies the generator's weights out of candle once and runs the same
//! network on plain buffers with the direct convolution kernels of [`crate::conv`]:
//! [`InputVjp::forward`] keeps what the backward pass needs (the ReLU masks and the images, a
//! [`Tape`]), [`InputVjp::vjp`] runs the backward pass to the input. One forward and one
//! backward per batch, and the forward's images can be used (to compute the upstream gradient)
//! before the backward runs.
//!
//! Every image is computed independently of the others in its batch, in a fixed order, so the
//! results do not depend on the batch size or the thread count. Tested against candle's
//! autograd ([`crate::Generator::image_and_vjp`]) and against finite differences.

use brush_model::Press;
use candle_core::Tensor;
use rayon::prelude::*;

use crate::NeuralGenError;
use crate::conv::{Padded, direct_forward, flip_transpose, pad_planes};
use crate::model::Generator;

/// One fully connected layer: `y = W·x + b`, `W` `[out, in]` row-major.
struct Fc {
    w: Vec<f32>,
    b: Vec<f32>,
    inp: usize,
    out: usize,
}

/// One 3×3 convolution stage (padding 1), followed by a ×2 pixel shuffle.
struct Stage {
    w: Vec<f32>,
    /// The flipped, transposed kernel for the input gradient.
    wf: Vec<f32>,
    b: Vec<f32>,
    cin: usize,
    cout: usize,
}

/// The generator's network on plain buffers, for batched images and input VJPs (see the
/// module doc). Build it once per generator with [`InputVjp::new`].
pub struct InputVjp {
    fcs: Vec<Fc>,
    stages: Vec<Stage>,
    seed_side: usize,
    size: usize,
    slopes: [f64; 3],
    config: crate::GeneratorConfig,
}

/// What a forward pass keeps for its backward pass: the ReLU masks of every layer but the last
/// and the images.
pub struct Tape {
    batch: usize,
    fc_masks: Vec<Vec<u8>>,
    stage_masks: Vec<Vec<u8>>,
    images: Vec<f32>,
}

impl Tape {
    /// Number of images.
    pub fn len(&self) -> usize {
        self.batch
    }

    /// Whether the batch was empty.
    pub fn is_empty(&self) -> bool {
        self.batch == 0
    }

    /// All images, `len() × size²` values in [0, 1], image after image, row-major.
    pub fn images(&self) -> &[f32] {
        &self.images
    }

    /// Image `i` (`size²` values).
    ///
    /// # Panics
    /// When `i ≥ len()`.
    pub fn image(&self, i: usize) -> &[f32] {
        let n = self.images.len() / self.batch.max(1);
        &self.images[i * n..(i + 1) * n]
    }
}

fn tensor_vec(t: &Tensor) -> Result<Vec<f32>, NeuralGenError> {
    t.flatten_all()
        .and_then(|f| f.to_dtype(candle_core::DType::F32))
        .and_then(|f| f.to_vec1::<f32>())
        .map_err(NeuralGenError::Candle)
}

/// `Σ a·b` with eight accumulators (vectorises).
#[inline]
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f32 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    acc.iter().sum::<f32>() + tail
}

/// Pixel shuffle by 2 of one image: `[4C, n, n]` → `[C, 2n, 2n]` (PyTorch's arrangement), or
/// the inverse.
fn shuffle(src: &[f32], dst: &mut [f32], c: usize, n: usize, inverse: bool) {
    let (small, big) = (n * n, 4 * n * n);
    for ch in 0..c {
        for dy in 0..2 {
            for dx in 0..2 {
                let sp = (ch * 2 + dy) * 2 + dx;
                for y in 0..n {
                    for x in 0..n {
                        let (si, li) = (sp * small + y * n + x, ch * big + (2 * y + dy) * 2 * n + 2 * x + dx);
                        if inverse {
                            dst[si] = src[li];
                        } else {
                            dst[li] = src[si];
                        }
                    }
                }
            }
        }
    }
}

impl InputVjp {
    /// Copies the generator's weights.
    ///
    /// # Errors
    /// [`NeuralGenError::Config`] when a tensor the architecture names is missing;
    /// [`NeuralGenError::Candle`].
    pub fn new(g: &Generator) -> Result<Self, NeuralGenError> {
        let a = &g.config.arch;
        let data = g.varmap.data().lock().expect("varmap");
        let get = |name: String| -> Result<Vec<f32>, NeuralGenError> {
            let v = data.get(&name).ok_or_else(|| NeuralGenError::Config {
                source_name: "generator".into(),
                message: format!("tensor `{name}` missing"),
            })?;
            tensor_vec(v.as_tensor())
        };
        let mut fcs = Vec::new();
        let mut inp = 3;
        let widths: Vec<usize> =
            a.hidden.iter().copied().chain([a.seed_channels * a.seed_side * a.seed_side]).collect();
        for (i, &out) in widths.iter().enumerate() {
            fcs.push(Fc { w: get(format!("fc{i}.weight"))?, b: get(format!("fc{i}.bias"))?, inp, out });
            inp = out;
        }
        let mut stages = Vec::new();
        for (i, &(cin, cout)) in a.stages.iter().enumerate() {
            let w = get(format!("conv{i}.weight"))?;
            let wf = flip_transpose(&w, cout, cin, 3);
            stages.push(Stage { w, wf, b: get(format!("conv{i}.bias"))?, cin, cout });
        }
        Ok(Self {
            fcs,
            stages,
            seed_side: a.seed_side,
            size: g.config.size as usize,
            slopes: g.config.normalise_slopes(),
            config: g.config.clone(),
        })
    }

    /// Side of the images, px.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The forward pass for a batch of presses (β as the generator takes it: inside its
    /// calibrated range), keeping what [`InputVjp::vjp`] needs.
    pub fn forward(&self, presses: &[Press]) -> Tape {
        let b = presses.len();
        let mut x: Vec<f32> = presses.iter().flat_map(|p| self.config.normalise(p)).collect();
        let mut fc_masks = Vec::new();
        let last_fc = self.fcs.len() - 1;
        for (li, fc) in self.fcs.iter().enumerate() {
            let mut y = vec![0f32; b * fc.out];
            y.par_chunks_mut(fc.out).zip(x.par_chunks(fc.inp)).for_each(|(yo, xi)| {
                for (o, v) in yo.iter_mut().enumerate() {
                    *v = dot(&fc.w[o * fc.inp..(o + 1) * fc.inp], xi) + fc.b[o];
                }
            });
            if li < last_fc {
                fc_masks.push(y.iter().map(|&v| u8::from(v > 0.0)).collect());
                y.iter_mut().for_each(|v| *v = v.max(0.0));
            }
            x = y;
        }
        let mut n = self.seed_side;
        let mut stage_masks = Vec::new();
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let pd = Padded { c: st.cin, hp: n + 2, wp: n + 2, k: 3 };
            let xp = pad_planes(&x, b * st.cin, (n, n), 1);
            let mut y = direct_forward(pd, b, st.cout, &xp, &st.w);
            y.par_chunks_mut(n * n).enumerate().for_each(|(bo, plane)| {
                let bv = st.b[bo % st.cout];
                plane.iter_mut().for_each(|v| *v += bv);
            });
            if si < last {
                stage_masks.push(y.iter().map(|&v| u8::from(v > 0.0)).collect());
                y.iter_mut().for_each(|v| *v = v.max(0.0));
            }
            let mut s = vec![0f32; y.len()];
            let per = st.cout * n * n;
            s.par_chunks_mut(per).zip(y.par_chunks(per)).for_each(|(d, src)| shuffle(src, d, st.cout / 4, n, false));
            x = s;
            n *= 2;
        }
        x.iter_mut().for_each(|v| *v = 1.0 / (1.0 + (-*v).exp()));
        debug_assert_eq!(n, self.size);
        Tape { batch: b, fc_masks, stage_masks, images: x }
    }

    /// The Jacobian of each image with respect to its press by forward-mode differentiation
    /// (three tangents through the network, the forward pass's ReLU masks reused):
    /// `len() × 3 × size²` values, per image `∂image/∂h` (per mm), `∂image/∂α`, `∂image/∂β`
    /// (per rad). `Σ upstream · ∂image/∂p` equals [`InputVjp::vjp`]'s, and with the Jacobian
    /// a press shared by many uses gives each use its own product without another pass.
    pub fn jacobian(&self, tape: &Tape) -> Vec<f32> {
        self.jacobian_of(tape, [true; 3])
    }

    /// As [`InputVjp::jacobian`] for the inputs marked in `which` (h, α, β) only; the columns
    /// of the others are left zero (one tangent pass per marked input).
    pub fn jacobian_of(&self, tape: &Tape, which: [bool; 3]) -> Vec<f32> {
        let b = tape.batch;
        let sel: Vec<usize> = (0..3).filter(|&k| which[k]).collect();
        let ss = self.size * self.size;
        let ns = sel.len();
        if b == 0 || ns == 0 {
            return vec![0f32; b * 3 * ss];
        }
        let t = ns * b;
        // Tangent rows (image r / ns, input sel[r % ns]): the unit step of that input in
        // normalised units.
        let mut x = vec![0f32; t * 3];
        for r in 0..t {
            let k = sel[r % ns];
            x[r * 3 + k] = self.slopes[k] as f32;
        }
        let last_fc = self.fcs.len() - 1;
        for (li, fc) in self.fcs.iter().enumerate() {
            let mut y = vec![0f32; t * fc.out];
            y.par_chunks_mut(fc.out).zip(x.par_chunks(fc.inp)).enumerate().for_each(|(r, (yo, xi))| {
                let mask = (li < last_fc).then(|| &tape.fc_masks[li][(r / ns) * fc.out..(r / ns + 1) * fc.out]);
                for (o, v) in yo.iter_mut().enumerate() {
                    if mask.is_none_or(|m| m[o] != 0) {
                        *v = dot(&fc.w[o * fc.inp..(o + 1) * fc.inp], xi);
                    }
                }
            });
            x = y;
        }
        let mut n = self.seed_side;
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let pd = Padded { c: st.cin, hp: n + 2, wp: n + 2, k: 3 };
            let xp = pad_planes(&x, t * st.cin, (n, n), 1);
            let mut y = direct_forward(pd, t, st.cout, &xp, &st.w);
            let per = st.cout * n * n;
            if si < last {
                y.par_chunks_mut(per).enumerate().for_each(|(r, img)| {
                    let m = &tape.stage_masks[si][(r / ns) * per..(r / ns + 1) * per];
                    img.iter_mut().zip(m).for_each(|(v, &k)| {
                        if k == 0 {
                            *v = 0.0;
                        }
                    });
                });
            }
            let mut sh = vec![0f32; y.len()];
            sh.par_chunks_mut(per).zip(y.par_chunks(per)).for_each(|(d, src)| shuffle(src, d, st.cout / 4, n, false));
            x = sh;
            n *= 2;
        }
        let mut out = vec![0f32; b * 3 * ss];
        x.par_chunks_mut(ss).enumerate().for_each(|(r, j)| {
            let img = tape.image(r / ns);
            j.iter_mut().zip(img).for_each(|(v, y)| *v *= y * (1.0 - y));
        });
        for (r, j) in x.chunks_exact(ss).enumerate() {
            let (i, k) = (r / ns, sel[r % ns]);
            out[(i * 3 + k) * ss..(i * 3 + k + 1) * ss].copy_from_slice(j);
        }
        out
    }

    /// The gradient of `Σ upstream · image` with respect to each press `(h [per mm], α [per
    /// rad], β [per rad])`, `upstream` holding `size²` values per image of the tape.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `upstream` does not hold `size²` values per image.
    pub fn vjp(&self, tape: &Tape, upstream: &[f32]) -> Result<Vec<[f64; 3]>, NeuralGenError> {
        let b = tape.batch;
        if upstream.len() != b * self.size * self.size {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({} images of {}²)",
                upstream.len(),
                b * self.size * self.size,
                b,
                self.size
            )));
        }
        if b == 0 {
            return Ok(Vec::new());
        }
        // Through the sigmoid.
        let mut g: Vec<f32> = upstream.iter().zip(&tape.images).map(|(u, y)| u * y * (1.0 - y)).collect();
        let mut n = self.size / 2;
        for (si, st) in self.stages.iter().enumerate().rev() {
            // Un-shuffle to the convolution's output, [B, cout, n, n].
            let per = st.cout * n * n;
            let mut gy = vec![0f32; g.len()];
            gy.par_chunks_mut(per).zip(g.par_chunks(per)).for_each(|(d, src)| shuffle(src, d, st.cout / 4, n, true));
            if si + 1 < self.stages.len() {
                gy.iter_mut().zip(&tape.stage_masks[si]).for_each(|(v, &m)| {
                    if m == 0 {
                        *v = 0.0;
                    }
                });
            }
            let pd = Padded { c: st.cout, hp: n + 2, wp: n + 2, k: 3 };
            let gp = pad_planes(&gy, b * st.cout, (n, n), 1);
            g = direct_forward(pd, b, st.cin, &gp, &st.wf);
            n /= 2;
        }
        // The seed map is the last FC's output; back through the FC layers.
        for (li, fc) in self.fcs.iter().enumerate().rev() {
            if li < self.fcs.len() - 1 {
                g.iter_mut().zip(&tape.fc_masks[li]).for_each(|(v, &m)| {
                    if m == 0 {
                        *v = 0.0;
                    }
                });
            }
            let mut dx = vec![0f32; b * fc.inp];
            dx.par_chunks_mut(fc.inp).zip(g.par_chunks(fc.out)).for_each(|(d, go)| {
                for (o, &gv) in go.iter().enumerate() {
                    if gv != 0.0 {
                        for (dv, wv) in d.iter_mut().zip(&fc.w[o * fc.inp..(o + 1) * fc.inp]) {
                            *dv += gv * wv;
                        }
                    }
                }
            });
            g = dx;
        }
        let k = self.slopes;
        Ok(g.chunks_exact(3).map(|v| [v[0] as f64 * k[0], v[1] as f64 * k[1], v[2] as f64 * k[2]]).collect())
    }
}

impl Generator {
    /// Images for a batch of presses and, for each, the gradient of `Σ upstream_i · image_i`
    /// with respect to its press `(h [per mm], α [per rad], β [per rad])`. `upstream` holds
    /// `size²` values per press, press after press. One forward and one backward pass through
    /// the network (direct kernels, input gradient only: [`InputVjp`]); the same numbers as
    /// [`Generator::image_and_vjp`] press by press. For many calls build an [`InputVjp`] once
    /// instead (this copies the weights).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `upstream` is not `presses.len() × size²` long;
    /// [`NeuralGenError::Candle`].
    pub fn images_and_vjps(
        &self,
        presses: &[Press],
        upstream: &[f32],
    ) -> Result<(Vec<bezier_raster::Coverage>, Vec<[f64; 3]>), NeuralGenError> {
        let s = self.config.size as usize;
        if upstream.len() != presses.len() * s * s {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({} presses × {s}²)",
                upstream.len(),
                presses.len() * s * s,
                presses.len()
            )));
        }
        let net = InputVjp::new(self)?;
        let tape = net.forward(presses);
        let grads = net.vjp(&tape, upstream)?;
        let imgs = tape
            .images
            .chunks_exact(s * s)
            .map(|c| bezier_raster::Coverage::from_vec(s as u32, s as u32, c.to_vec()).expect("sized"))
            .collect();
        Ok((imgs, grads))
    }

    /// As [`Generator::images_and_vjps`], through candle's autograd (one forward and one
    /// backward of the whole batch; weight gradients are computed too). Kept for the speed
    /// comparison and as a cross-check.
    ///
    /// # Errors
    /// As [`Generator::images_and_vjps`].
    pub fn images_and_vjps_candle(
        &self,
        presses: &[Press],
        upstream: &[f32],
    ) -> Result<(Vec<bezier_raster::Coverage>, Vec<[f64; 3]>), NeuralGenError> {
        let cerr = |e: candle_core::Error| NeuralGenError::Candle(e);
        let s = self.config.size as usize;
        let b = presses.len();
        if upstream.len() != b * s * s {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({b} presses × {s}²)",
                upstream.len(),
                b * s * s
            )));
        }
        if b == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let x = candle_core::Var::from_tensor(&self.inputs(presses)?).map_err(cerr)?;
        let y = self.forward(x.as_tensor())?;
        let w = Tensor::from_vec(upstream.to_vec(), (b, 1, s, s), self.device()).map_err(cerr)?;
        let l = (&y * &w).and_then(|t| t.sum_all()).map_err(cerr)?;
        let grads = l.backward().map_err(cerr)?;
        let gx = tensor_vec(
            grads
                .get(x.as_tensor())
                .ok_or_else(|| NeuralGenError::Candle(candle_core::Error::Msg("no gradient for the input".into())))?,
        )?;
        let k = self.config.normalise_slopes();
        let img = tensor_vec(&y)?;
        Ok((
            img.chunks_exact(s * s)
                .map(|c| bezier_raster::Coverage::from_vec(s as u32, s as u32, c.to_vec()).expect("sized"))
                .collect(),
            gx.chunks_exact(3).map(|v| [v[0] as f64 * k[0], v[1] as f64 * k[1], v[2] as f64 * k[2]]).collect(),
        ))
    }
}
