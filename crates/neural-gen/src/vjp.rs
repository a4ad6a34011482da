//! Batched footprint images and their vector–Jacobian products with respect to the press,
//! without candle's autograd.
//!
//! Track refinement needs, for every footprint of a character (thousands), the image and then,
//! once the loss of all images together is known, `∂L/∂(h, α, β)` from `∂L/∂image`. That is a
//! gradient with respect to the network's *input* only, so the weight gradients candle's
//! autograd computes on every backward pass (a third of the work) are not needed, and neither is
//! the graph. [`InputVjp`] copies the generator's weights out of candle once and runs the same
//! network on plain buffers with its own kernels (`kernels`: packed matrix products for the
//! fully connected layers, on the whole batch; register-tiled 3×3 correlations for the
//! convolution stages, image by image in parallel, with bias, ReLU, pixel shuffle and sigmoid
//! fused into the pass that writes the next layer's padded input): [`InputVjp::forward`] keeps
//! what the backward pass needs (the ReLU masks, one byte per activation, and the images, a
//! [`Tape`]), [`InputVjp::vjp`] runs the backward pass to the input. One forward and one
//! backward per batch, and the forward's images can be used (to compute the upstream gradient)
//! before the backward runs.
//!
//! Every image is computed independently of the others in its batch, every sum in a fixed
//! order of fused multiply–adds, so the results do not depend on the batch size, the thread
//! count or the vector width. Training ([`crate::DirectTrainer`]) runs on the same kernels.
//! Tested against candle's autograd ([`crate::Generator::image_and_vjp`]) and against finite
//! differences.

use brush_model::Press;
use candle_core::Tensor;
use pulp::{Simd, WithSimd};
use rayon::prelude::*;

use crate::NeuralGenError;
use crate::conv::flip_transpose;
use crate::kernels::{Conv3, Dense, Isa, padded_len};
use crate::model::Generator;

/// One fully connected layer `y = W·x + b`.
pub(crate) struct Fc {
    /// `· Wᵀ`: the forward products (`x` `[batch, in]`).
    pub(crate) fwd: Dense,
    /// `· W`: the backward product (`g` `[batch, out]`).
    pub(crate) bwd: Dense,
    pub(crate) b: Vec<f32>,
    pub(crate) out: usize,
}

/// One 3×3 convolution stage (padding 1), followed by a ×2 pixel shuffle.
pub(crate) struct Stage {
    pub(crate) fwd: Conv3,
    /// The flipped, transposed kernel: the correlation that gives the input gradient.
    pub(crate) bwd: Conv3,
    pub(crate) b: Vec<f32>,
    pub(crate) cin: usize,
    pub(crate) cout: usize,
    /// Side of the stage's input (and of its convolution's output), px.
    pub(crate) n: usize,
    /// Offset of the ReLU mask of the stage's input in an image's masks on a [`Tape`] (the
    /// first stage's input, the seed map, has none).
    moff: usize,
}

/// The generator's network on plain buffers, for batched images and input VJPs (see the
/// module doc). Build it once per generator with [`InputVjp::new`].
pub struct InputVjp {
    pub(crate) fcs: Vec<Fc>,
    pub(crate) stages: Vec<Stage>,
    /// Values per image of the stages' padded inputs (forward scratch).
    pub(crate) per_image: usize,
    /// Mask bytes per image on a [`Tape`].
    pub(crate) masks_per_image: usize,
    size: usize,
    slopes: [f64; 3],
    config: crate::GeneratorConfig,
    pub(crate) isa: Isa,
}

/// What a forward pass keeps for its backward pass: the ReLU masks of every layer but the last
/// and the images.
pub struct Tape {
    batch: usize,
    /// Outputs (after the ReLU) of the fully connected layers but the last, `[batch, width]`
    /// (their signs are the masks).
    hidden: Vec<Vec<f32>>,
    /// Per image, the ReLU masks (1 where positive) of the inputs of every stage but the first,
    /// `[c, y, x]` after the pixel shuffle, stage after stage.
    masks: Vec<u8>,
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

    /// All images, as [`Tape::images`], without a copy (the tape cannot go backward after).
    pub fn into_images(self) -> Vec<f32> {
        self.images
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

/// `eˣ` without a libm call, so that the loops around it vectorise: `x = k·ln 2 + r` with
/// `|r| ≤ ln 2 / 2`, `eʳ` by its Taylor polynomial to degree 7, `2ᵏ` built in the exponent
/// bits. Relative error below 1e-7 (a few ulp of f32) for `x` in [−87, 88]; clamped there.
/// Plain IEEE operations only (no fused multiply–adds), so every instruction set gives the
/// same bits.
#[inline(always)]
fn exp_f32(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // Adding and subtracting 1.5·2²³ rounds to the nearest integer (|x·log₂e| < 2²²).
    const ROUND: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    let y = x * LOG2E + ROUND;
    let k = y - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (1.0 / 2.0
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    // The bits of `y` are those of 1.5·2²³ plus k: 2ᵏ's exponent field is k + 127 (no
    // float-to-integer conversion, which does not vectorise).
    p * f32::from_bits(y.to_bits().wrapping_sub(0x4B40_0000 - 127) << 23)
}

/// The logistic function `1 / (1 + e⁻ˣ)` (through [`exp_f32`]).
#[inline(always)]
pub(crate) fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp_f32(-x))
}

/// `v` where the mask byte is 1, 0 where it is 0 (branch-free, so that the loops vectorise).
#[inline(always)]
fn masked(v: f32, m: u8) -> f32 {
    f32::from_bits(v.to_bits() & u32::from(m).wrapping_neg())
}

/// Splits an image's activations into the padded inputs of the stages.
fn regions<'a>(stages: &[Stage], mut buf: &'a mut [f32]) -> Vec<&'a mut [f32]> {
    let mut out = Vec::with_capacity(stages.len());
    for st in stages {
        let (a, rest) = std::mem::take(&mut buf).split_at_mut(padded_len(st.cin, st.n));
        out.push(a);
        buf = rest;
    }
    out
}

/// Copies `c` planes of `n × n` into the interior of zero-bordered padded planes.
pub(crate) fn write_padded(dst: &mut [f32], src: &[f32], c: usize, n: usize) {
    let wp = n + 2;
    for ch in 0..c {
        for y in 0..n {
            let d = ch * wp * wp + (y + 1) * wp + 1;
            dst[d..d + n].copy_from_slice(&src[(ch * n + y) * n..(ch * n + y + 1) * n]);
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
        let data = g.varmap.data().lock().expect("varmap");
        Self::from_weights(&g.config, |name: String| -> Result<Vec<f32>, NeuralGenError> {
            let v = data.get(&name).ok_or_else(|| NeuralGenError::Config {
                source_name: "generator".into(),
                problem: crate::ConfigError::MissingTensor { name: name.clone() },
            })?;
            tensor_vec(v.as_tensor())
        })
    }

    /// The network of `config` with the weights `get(name)` returns (`fc0.weight`, …, as
    /// candle names and lays them out).
    pub(crate) fn from_weights(
        config: &crate::GeneratorConfig,
        get: impl Fn(String) -> Result<Vec<f32>, NeuralGenError>,
    ) -> Result<Self, NeuralGenError> {
        let a = &config.arch;
        let isa = Isa::detect();
        let mut fcs = Vec::new();
        let mut inp = 3;
        let widths: Vec<usize> =
            a.hidden.iter().copied().chain([a.seed_channels * a.seed_side * a.seed_side]).collect();
        for (i, &out) in widths.iter().enumerate() {
            let w = get(format!("fc{i}.weight"))?;
            let mut wt = vec![0f32; w.len()];
            for o in 0..out {
                for k in 0..inp {
                    wt[k * out + o] = w[o * inp + k];
                }
            }
            fcs.push(Fc {
                fwd: Dense::new(&wt, inp, out, isa),
                bwd: Dense::new(&w, out, inp, isa),
                b: get(format!("fc{i}.bias"))?,
                out,
            });
            inp = out;
        }
        let mut stages = Vec::new();
        let (mut n, mut per_image, mut moff) = (a.seed_side, 0, 0);
        for (i, &(cin, cout)) in a.stages.iter().enumerate() {
            let w = get(format!("conv{i}.weight"))?;
            let wf = flip_transpose(&w, cout, cin, 3);
            stages.push(Stage {
                fwd: Conv3::new(&w, cout, cin, isa),
                bwd: Conv3::new(&wf, cin, cout, isa),
                b: get(format!("conv{i}.bias"))?,
                cin,
                cout,
                n,
                moff,
            });
            per_image += padded_len(cin, n);
            if i > 0 {
                moff += cin * n * n;
            }
            n *= 2;
        }
        Ok(Self {
            fcs,
            stages,
            per_image,
            // At least one byte, so that the per-image chunks of a tape are never empty.
            masks_per_image: moff.max(1),
            size: config.size as usize,
            slopes: config.normalise_slopes(),
            config: config.clone(),
            isa,
        })
    }

    /// Side of the images, px.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Values of the seed map (the last fully connected layer's output) per image.
    pub(crate) fn seed_len(&self) -> usize {
        let s = &self.stages[0];
        s.cin * s.n * s.n
    }

    /// The forward pass for a batch of presses (β as the generator takes it: inside its
    /// calibrated range), keeping what [`InputVjp::vjp`] needs. The fully connected layers
    /// run on the whole batch, the convolutions image by image in parallel.
    pub fn forward(&self, presses: &[Press]) -> Tape {
        let b = presses.len();
        let x: Vec<f32> = presses.iter().flat_map(|p| self.config.normalise(p)).collect();
        let (hidden, seed) = self.dense_forward(&x);
        let ss = self.size * self.size;
        let mut masks = vec![0u8; b * self.masks_per_image];
        let mut images = vec![0f32; b * ss];
        let mp = self.masks_per_image;
        images.par_chunks_mut(ss).zip(masks.par_chunks_mut(mp)).zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), ((img, m), sd)| {
                self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: Some(m), buf, acc })
            },
        );
        Tape { batch: b, hidden, masks, images }
    }

    /// The fully connected layers on the whole batch of normalised inputs `x` (`[batch, 3]`):
    /// the outputs of every layer but the last (after the ReLU) and the seed maps.
    pub(crate) fn dense_forward(&self, x: &[f32]) -> (Vec<Vec<f32>>, Vec<f32>) {
        let mut hidden: Vec<Vec<f32>> = Vec::new();
        let mut seed = Vec::new();
        for (li, fc) in self.fcs.iter().enumerate() {
            let input = if li == 0 { x } else { &hidden[li - 1] };
            let mut y = fc.fwd.apply(input, Some(&fc.b));
            if li + 1 < self.fcs.len() {
                y.iter_mut().for_each(|v| *v = v.max(0.0));
                hidden.push(y);
            } else {
                seed = y;
            }
        }
        (hidden, seed)
    }

    /// Images for a batch of normalised inputs `x` (`[batch, 3]`, as
    /// [`crate::GeneratorConfig::normalise`] makes them): `batch × size²` values in [0, 1],
    /// image after image. Inference only: the same numbers as [`InputVjp::forward`]'s images,
    /// without keeping a tape. The fully connected layers run on the whole batch, the
    /// convolutions image by image in parallel; the bits do not depend on the batch or the
    /// thread count.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images_normalised(&self, x: &[f32]) -> Vec<f32> {
        assert_eq!(x.len() % 3, 0, "inputs come in threes");
        let b = x.len() / 3;
        let ss = self.size * self.size;
        let mut images = vec![0f32; b * ss];
        if b == 0 {
            return images;
        }
        let (_, seed) = self.dense_forward(x);
        images.par_chunks_mut(ss).zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (img, sd)| self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: None, buf, acc }),
        );
        images
    }

    /// As [`InputVjp::images_normalised`], each image in a vector of its own (`size²` values),
    /// written where the image is computed (no copy out of a batch buffer). The vectors are
    /// allocated by the calling thread, which usually frees them too (so that the allocator
    /// reuses their memory), and filled in parallel.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images_normalised_each(&self, x: &[f32]) -> Vec<Vec<f32>> {
        assert_eq!(x.len() % 3, 0, "inputs come in threes");
        let ss = self.size * self.size;
        let mut out: Vec<Vec<f32>> = (0..x.len() / 3).map(|_| Vec::with_capacity(ss)).collect();
        if out.is_empty() {
            return out;
        }
        let (_, seed) = self.dense_forward(x);
        out.par_iter_mut().zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (img, sd)| {
                img.resize(ss, 0.0);
                self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: None, buf, acc })
            },
        );
        out
    }

    /// The convolution stages of one image, from its seed map: the image into `img`, the ReLU
    /// masks into `masks` where given (training and VJPs; inference does without); `buf`
    /// holds the stages' padded inputs (zero borders kept), `acc` scratch.
    #[inline(always)]
    fn forward_image(
        &self,
        seed: &[f32],
        img: &mut [f32],
        mut masks: Option<&mut [u8]>,
        buf: &mut [f32],
        acc: &mut Vec<f32>,
    ) {
        let mut reg = regions(&self.stages, buf);
        write_padded(reg[0], seed, self.stages[0].cin, self.stages[0].n);
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let (cur, next) = reg.split_at_mut(si + 1);
            let (x, n, s) = (&*cur[si], st.n, 2 * st.n);
            if si < last {
                // Bias, ReLU and the pixel shuffle into the next stage's padded input.
                let (dst, wq) = (&mut *next[0], s + 2);
                let nx = &self.stages[si + 1];
                let mut m = masks.as_deref_mut().map(|m| &mut m[nx.moff..nx.moff + nx.cin * s * s]);
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, st.b[o], st.b[o + 1]);
                    let d = &mut dst[ch * wq * wq + (r + 1) * wq + 1..ch * wq * wq + (r + 1) * wq + 1 + s];
                    for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                        dd[0] = (v0 + b0).max(0.0);
                        dd[1] = (v1 + b1).max(0.0);
                    }
                    if let Some(m) = m.as_deref_mut() {
                        for (mm, &v) in m[(ch * s + r) * s..(ch * s + r + 1) * s].iter_mut().zip(d.iter()) {
                            *mm = u8::from(v > 0.0);
                        }
                    }
                });
            } else {
                // Bias and the pixel shuffle into the image, then the sigmoid on the row while
                // it is in cache (each call writes one whole row of the image).
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, st.b[o], st.b[o + 1]);
                    let d = &mut img[(ch * s + r) * s..(ch * s + r + 1) * s];
                    for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                        dd[0] = v0 + b0;
                        dd[1] = v1 + b1;
                    }
                    for v in d.iter_mut() {
                        *v = sigmoid(*v);
                    }
                });
            }
        }
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
        for (li, fc) in self.fcs.iter().enumerate() {
            let mut y = fc.fwd.apply(&x, None);
            if li + 1 < self.fcs.len() {
                let h = &tape.hidden[li];
                y.par_chunks_mut(fc.out).enumerate().for_each(|(r, row)| {
                    let m = &h[(r / ns) * fc.out..(r / ns + 1) * fc.out];
                    row.iter_mut().zip(m).for_each(|(v, &a)| {
                        if a <= 0.0 {
                            *v = 0.0;
                        }
                    });
                });
            }
            x = y;
        }
        let (sl, mp) = (self.seed_len(), self.masks_per_image);
        let mut out = vec![0f32; b * 3 * ss];
        out.par_chunks_mut(3 * ss).enumerate().for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (i, cols)| {
                for (q, &k) in sel.iter().enumerate() {
                    let r = i * ns + q;
                    let masks = &tape.masks[i * mp..(i + 1) * mp];
                    let col = &mut cols[k * ss..(k + 1) * ss];
                    let seed = &x[r * sl..(r + 1) * sl];
                    let img = tape.image(i);
                    self.isa.dispatch(TangentImage { net: self, seed, masks, img, col, buf, acc });
                }
            },
        );
        out
    }

    /// One tangent of one image through the stages: `seed` the tangent of the seed map,
    /// `masks` and `img` the image's ReLU masks and image from the forward pass, the tangent
    /// of the image into `col`; `buf` scratch for the stages' padded inputs (zero borders kept).
    #[inline(always)]
    fn tangent_image(
        &self,
        seed: &[f32],
        masks: &[u8],
        img: &[f32],
        col: &mut [f32],
        buf: &mut [f32],
        acc: &mut Vec<f32>,
    ) {
        let mut reg = regions(&self.stages, buf);
        write_padded(reg[0], seed, self.stages[0].cin, self.stages[0].n);
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let (cur, next) = reg.split_at_mut(si + 1);
            let (x, n, s) = (&*cur[si], st.n, 2 * st.n);
            if si < last {
                let (dst, wq) = (&mut *next[0], s + 2);
                let m = &masks[self.stages[si + 1].moff..];
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r) = (o / 4, 2 * y + (o / 2) % 2);
                    let d = &mut dst[ch * wq * wq + (r + 1) * wq + 1..ch * wq * wq + (r + 1) * wq + 1 + s];
                    let mr = &m[(ch * s + r) * s..(ch * s + r + 1) * s];
                    for ((dd, mm), (&v0, &v1)) in d.chunks_exact_mut(2).zip(mr.chunks_exact(2)).zip(r0.iter().zip(r1)) {
                        dd[0] = masked(v0, mm[0]);
                        dd[1] = masked(v1, mm[1]);
                    }
                });
            } else {
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r) = (o / 4, 2 * y + (o / 2) % 2);
                    let row = (ch * s + r) * s..(ch * s + r + 1) * s;
                    let (d, im) = (&mut col[row.clone()], &img[row]);
                    for ((dd, yy), (&v0, &v1)) in d.chunks_exact_mut(2).zip(im.chunks_exact(2)).zip(r0.iter().zip(r1)) {
                        dd[0] = v0 * (yy[0] * (1.0 - yy[0]));
                        dd[1] = v1 * (yy[1] * (1.0 - yy[1]));
                    }
                });
            }
        }
    }

    /// The gradient of `Σ upstream · image` with respect to each press `(h [per mm], α [per
    /// rad], β [per rad])`, `upstream` holding `size²` values per image of the tape.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `upstream` does not hold `size²` values per image.
    pub fn vjp(&self, tape: &Tape, upstream: &[f32]) -> Result<Vec<[f64; 3]>, NeuralGenError> {
        let b = tape.batch;
        let ss = self.size * self.size;
        if upstream.len() != b * ss {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({} images of {}²)",
                upstream.len(),
                b * ss,
                b,
                self.size
            )));
        }
        if b == 0 {
            return Ok(Vec::new());
        }
        // The convolution stages image by image, to the seed map.
        let (sl, mp) = (self.seed_len(), self.masks_per_image);
        let mut g = vec![0f32; b * sl];
        let bufs = || -> Vec<Vec<f32>> { self.stages.iter().map(|st| vec![0f32; padded_len(st.cout, st.n)]).collect() };
        g.par_chunks_mut(sl)
            .zip(upstream.par_chunks(ss))
            .zip(tape.images.par_chunks(ss))
            .zip(tape.masks.par_chunks(mp))
            .for_each_init(
                || (bufs(), Vec::new()),
                |(bufs, acc), (((gs, up), img), masks)| {
                    self.isa.dispatch(BackwardImage { net: self, gs, up, img, masks, bufs, acc })
                },
            );
        // Back through the fully connected layers, on the whole batch.
        for (li, fc) in self.fcs.iter().enumerate().rev() {
            let mut gi = fc.bwd.apply(&g, None);
            if li > 0 {
                gi.iter_mut().zip(&tape.hidden[li - 1]).for_each(|(v, &a)| {
                    if a <= 0.0 {
                        *v = 0.0;
                    }
                });
            }
            g = gi;
        }
        let k = self.slopes;
        Ok(g.chunks_exact(3).map(|v| [v[0] as f64 * k[0], v[1] as f64 * k[1], v[2] as f64 * k[2]]).collect())
    }

    /// The backward pass of one image through the stages: `up` the upstream gradient of the
    /// image `img`, `masks` its ReLU masks from the tape; the gradient of the seed map into
    /// `gs`. `bufs[si]` holds the padded gradient at stage `si`'s convolution output (zero
    /// borders kept), `acc` scratch.
    #[inline(always)]
    fn backward_image(
        &self,
        gs: &mut [f32],
        up: &[f32],
        img: &[f32],
        masks: &[u8],
        bufs: &mut [Vec<f32>],
        acc: &mut Vec<f32>,
    ) {
        let last = self.stages.len() - 1;
        // Through the sigmoid, un-shuffled onto the last convolution's padded output: row yy
        // of image channel ch interleaves rows yy / 2 of channels 4ch + 2(yy % 2) + {0, 1}.
        let st = &self.stages[last];
        let (n, s, wp) = (st.n, 2 * st.n, st.n + 2);
        let q2 = wp * wp;
        let gl = &mut bufs[last];
        for ch in 0..st.cout / 4 {
            for yy in 0..s {
                let base = (4 * ch + 2 * (yy % 2)) * q2 + (yy / 2 + 1) * wp + 1;
                let (lo, hi) = gl.split_at_mut(base + q2);
                let (d0, d1) = (&mut lo[base..base + n], &mut hi[..n]);
                let row = (ch * s + yy) * s..(ch * s + yy + 1) * s;
                let (u, y) = (&up[row.clone()], &img[row]);
                for ((e0, e1), (uu, yv)) in
                    d0.iter_mut().zip(d1.iter_mut()).zip(u.chunks_exact(2).zip(y.chunks_exact(2)))
                {
                    *e0 = uu[0] * yv[0] * (1.0 - yv[0]);
                    *e1 = uu[1] * yv[1] * (1.0 - yv[1]);
                }
            }
        }
        for (si, st) in self.stages.iter().enumerate().rev() {
            let n = st.n;
            let (lo, hi) = bufs.split_at_mut(si);
            let gy = &hi[0];
            if si > 0 {
                // The gradient at this stage's input is the previous stage's output after the
                // ReLU and the shuffle: mask it and un-shuffle it (row y of channel c
                // de-interleaves into rows y / 2 of channels 4c + 2(y % 2) + {0, 1}).
                let (dst, m) = (&mut lo[si - 1], &masks[st.moff..st.moff + st.cin * n * n]);
                let (h, wq) = (n / 2, n / 2 + 2);
                let q2 = wq * wq;
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let base = (4 * c + 2 * (y % 2)) * q2 + (y / 2 + 1) * wq + 1;
                    let (lo, hi) = dst.split_at_mut(base + q2);
                    let (d0, d1) = (&mut lo[base..base + h], &mut hi[..h]);
                    let mr = &m[(c * n + y) * n..(c * n + y + 1) * n];
                    for ((e0, e1), (v, mm)) in
                        d0.iter_mut().zip(d1.iter_mut()).zip(row.chunks_exact(2).zip(mr.chunks_exact(2)))
                    {
                        *e0 = masked(v[0], mm[0]);
                        *e1 = masked(v[1], mm[1]);
                    }
                });
            } else {
                st.bwd.run(gy, n, acc, |c, y, row| gs[(c * n + y) * n..(c * n + y + 1) * n].copy_from_slice(row));
            }
        }
    }
}

/// [`InputVjp::forward_image`] on the detected vectors (a struct, not a closure, so that the
/// method is inlined where the target features are enabled).
pub(crate) struct ForwardImage<'a> {
    pub(crate) net: &'a InputVjp,
    pub(crate) seed: &'a [f32],
    pub(crate) img: &'a mut [f32],
    pub(crate) masks: Option<&'a mut [u8]>,
    pub(crate) buf: &'a mut [f32],
    pub(crate) acc: &'a mut Vec<f32>,
}

impl WithSimd for ForwardImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.forward_image(self.seed, self.img, self.masks, self.buf, self.acc);
    }
}

/// [`InputVjp::tangent_image`] on the detected vectors.
struct TangentImage<'a> {
    net: &'a InputVjp,
    seed: &'a [f32],
    masks: &'a [u8],
    img: &'a [f32],
    col: &'a mut [f32],
    buf: &'a mut [f32],
    acc: &'a mut Vec<f32>,
}

impl WithSimd for TangentImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.tangent_image(self.seed, self.masks, self.img, self.col, self.buf, self.acc);
    }
}

/// [`InputVjp::backward_image`] on the detected vectors.
pub(crate) struct BackwardImage<'a> {
    pub(crate) net: &'a InputVjp,
    pub(crate) gs: &'a mut [f32],
    pub(crate) up: &'a [f32],
    pub(crate) img: &'a [f32],
    pub(crate) masks: &'a [u8],
    pub(crate) bufs: &'a mut [Vec<f32>],
    pub(crate) acc: &'a mut Vec<f32>,
}

impl WithSimd for BackwardImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.backward_image(self.gs, self.up, self.img, self.masks, self.bufs, self.acc);
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
        let y = self.forward_autograd(x.as_tensor())?;
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

#[cfg(test)]
mod tests {
    use super::{exp_f32, sigmoid};

    /// The vectorisable exponential against libm's, over the range the clamp keeps, and the
    /// sigmoid at its ends.
    #[test]
    fn exp_f32_is_within_a_few_ulp() {
        let mut worst = 0f64;
        for i in 0..=200_000 {
            let x = -87.0 + 175.0 * i as f32 / 200_000.0;
            let (got, want) = (exp_f32(x) as f64, (x as f64).exp());
            worst = worst.max((got - want).abs() / want);
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
        assert_eq!(exp_f32(0.0), 1.0);
        assert_eq!(sigmoid(0.0), 0.5);
        assert_eq!(sigmoid(1e4), 1.0);
        assert!(sigmoid(-1e4) >= 0.0 && sigmoid(-1e4) < 1e-37);
        assert!((sigmoid(2.0) as f64 - 1.0 / (1.0 + (-2f64).exp())).abs() < 1e-7);
    }

    /// Inference (no masks kept, the images in a batch buffer or one vector each) gives the
    /// same bits as the forward pass that keeps its tape, for the shipped architecture (its
    /// larger stages run in several bands of rows) and an odd one.
    #[test]
    fn inference_equals_the_taped_forward_pass() {
        use crate::{Arch, Generator, GeneratorConfig};
        use brush_model::{BrushProfile, Press};
        let odd =
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] };
        for arch in [Arch::default_128(), odd] {
            let g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 2).unwrap();
            let ps: Vec<Press> =
                (0..5).map(|i| Press::from_degrees(11.0 + 2.0 * i as f64, 3.0 * i as f64, 1.0 * i as f64)).collect();
            let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
            let net = super::InputVjp::new(&g).unwrap();
            let taped = net.forward(&ps);
            let flat = net.images_normalised(&x);
            assert_eq!(taped.images(), &flat[..]);
            let each: Vec<f32> = net.images_normalised_each(&x).concat();
            assert_eq!(each, flat);
            assert!(flat.iter().any(|&v| v > 0.01 && v < 0.99), "a flat image tests little");
        }
    }
}
