//! Training on the direct kernels: the forward pass of [`InputVjp`] with every stage's input
//! kept, the backward pass to the weights (the input-gradient correlations of [`InputVjp`],
//! then a weight-gradient correlation per stage and products for the fully connected layers),
//! and AdamW fused into one pass per tensor, on plain buffers allocated once.
//!
//! Every image's gradients are computed on their own and summed over the batch in image order,
//! each sum a fixed chain of operations: the results do not depend on the thread count. The
//! weights live here during training; [`DirectTrainer::write_back`] copies them into the
//! generator's candle variables (checkpoints, the final weights).

use std::sync::{Mutex, MutexGuard};

use pulp::{Simd, WithSimd};
use rayon::prelude::*;

use crate::kernels::{Dense, padded_len};
use crate::model::Generator;
use crate::vjp::{BackwardImage, ForwardImage, InputVjp};
use crate::{GeneratorConfig, NeuralGenError};

/// One trainable tensor and its AdamW moments.
struct Param {
    name: String,
    dims: Vec<usize>,
    w: Vec<f32>,
    g: Vec<f32>,
    m: Vec<f32>,
    v: Vec<f32>,
}

/// The generator's training step on the direct kernels (AdamW with weight decay 0 on MSE).
/// Public for the benchmarks; [`crate::train()`] is the entry point.
#[doc(hidden)]
pub struct DirectTrainer {
    config: GeneratorConfig,
    /// `fc0.weight, fc0.bias, …, conv0.weight, conv0.bias, …`.
    params: Vec<Param>,
    net: InputVjp,
    t: i32,
    /// Per image: the convolution stages' weight and bias gradients, then the seed-map gradient.
    per_image: Vec<f32>,
    /// The gradient at a fully connected layer's output, transposed (`[out, batch]`).
    gt: Vec<f32>,
    /// The fully connected layers' outputs (after the ReLU but the last: the seed maps).
    hid: Vec<Vec<f32>>,
    /// Each fully connected layer's input, packed for its weight gradient (`[batch, in]`).
    xin: Vec<Dense>,
    /// The gradients at a fully connected layer's output and input (`[batch, ·]`).
    g: Vec<f32>,
    gi: Vec<f32>,
    /// Scratch of the panel-parallel products; the images' squared errors.
    dense_t: Vec<f32>,
    sq: Vec<f64>,
    /// Per-thread scratch of the per-image passes (gradient planes with zero borders).
    pool: Vec<Mutex<Scratch>>,
    batch: usize,
}

/// One thread's scratch for the per-image pass (forward, loss, backward and weight gradients
/// of one image, so that its activations stay in the core's cache): the stages' padded inputs
/// and the padded gradient at every stage's output (zero borders kept), the ReLU masks, the
/// image and the loss's gradient, and the correlation's accumulators.
struct Scratch {
    acts: Vec<f32>,
    bufs: Vec<Vec<f32>>,
    masks: Vec<u8>,
    img: Vec<f32>,
    up: Vec<f32>,
    acc: Vec<f32>,
}

/// A thread's [`Scratch`] from the trainer's pool, or its own where that is in use.
struct ScratchRef<'a> {
    guard: Option<MutexGuard<'a, Scratch>>,
    own: Option<Scratch>,
}

impl Scratch {
    fn new(net: &InputVjp) -> Self {
        let ss = net.size() * net.size();
        Scratch {
            acts: vec![0f32; net.per_image],
            bufs: net.stages.iter().map(|st| vec![0f32; padded_len(st.cout, st.n)]).collect(),
            masks: vec![0u8; net.masks_per_image],
            img: vec![0f32; ss],
            up: vec![0f32; ss],
            acc: Vec::new(),
        }
    }

    /// The current thread's entry of `pool` (by rayon's thread index), when free.
    fn take(pool: &[Mutex<Scratch>]) -> ScratchRef<'_> {
        let i = rayon::current_thread_index().unwrap_or(0) % pool.len().max(1);
        ScratchRef { guard: pool.get(i).and_then(|m| m.try_lock().ok()), own: None }
    }
}

impl ScratchRef<'_> {
    fn get(&mut self, net: &InputVjp) -> &mut Scratch {
        match &mut self.guard {
            Some(g) => g,
            None => self.own.get_or_insert_with(|| Scratch::new(net)),
        }
    }
}

/// Convolution parameters (weights and biases of every stage) of an architecture.
fn conv_len(net: &InputVjp) -> usize {
    net.stages.iter().map(|s| s.cout * s.cin * 9 + s.cout).sum()
}

impl DirectTrainer {
    /// Copies `g`'s weights.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn new(g: &Generator) -> Result<Self, NeuralGenError> {
        let weights = g.weights()?;
        let mut params = Vec::new();
        let a = &g.config.arch;
        let names =
            (0..=a.hidden.len()).map(|i| format!("fc{i}")).chain((0..a.stages.len()).map(|i| format!("conv{i}")));
        for layer in names {
            for part in ["weight", "bias"] {
                let name = format!("{layer}.{part}");
                let t = weights.get(&name).ok_or_else(|| NeuralGenError::Config {
                    source_name: "generator".into(),
                    problem: crate::ConfigError::MissingTensor { name: name.clone() },
                })?;
                let w: Vec<f32> = t.flatten_all().and_then(|f| f.to_vec1()).map_err(NeuralGenError::Candle)?;
                let n = w.len();
                params.push(Param {
                    name,
                    dims: t.dims().to_vec(),
                    w,
                    g: vec![0.0; n],
                    m: vec![0.0; n],
                    v: vec![0.0; n],
                });
            }
        }
        let mut tr = DirectTrainer {
            config: g.config.clone(),
            net: InputVjp::new(g)?,
            params,
            t: 0,
            per_image: Vec::new(),
            gt: Vec::new(),
            hid: Vec::new(),
            xin: Vec::new(),
            g: Vec::new(),
            gi: Vec::new(),
            dense_t: Vec::new(),
            sq: Vec::new(),
            pool: Vec::new(),
            batch: 0,
        };
        tr.rebuild()?;
        Ok(tr)
    }

    /// Repacks the kernels' weights from the parameters.
    fn rebuild(&mut self) -> Result<(), NeuralGenError> {
        let params = &self.params;
        self.net = InputVjp::from_weights(&self.config, |name| {
            Ok(params.iter().find(|p| p.name == name).map(|p| p.w.clone()).unwrap_or_default())
        })?;
        Ok(())
    }

    /// Sizes the per-image buffers for `batch` images (only when the batch changes).
    fn size_for(&mut self, batch: usize) {
        if batch == self.batch {
            return;
        }
        self.per_image = vec![0.0; batch * (conv_len(&self.net) + self.net.seed_len())];
        self.hid = self.net.fcs.iter().map(|fc| vec![0.0; batch * fc.out]).collect();
        let mut inp = 3;
        self.xin = self
            .net
            .fcs
            .iter()
            .map(|fc| {
                let d = Dense::new(&vec![0.0; batch * inp], batch, inp, self.net.isa);
                inp = fc.out;
                d
            })
            .collect();
        let threads = rayon::current_num_threads().max(1);
        self.pool = (0..threads).map(|_| Mutex::new(Scratch::new(&self.net))).collect();
        self.batch = batch;
    }

    /// The MSE of the network's images of normalised inputs `x` (`[B, 3]`) against `target`
    /// (`B × size²`), and every parameter's gradient of it (kept for [`DirectTrainer::update`]).
    ///
    /// # Panics
    /// When `target` is not `B × size²` long.
    pub fn gradients(&mut self, x: &[f32], target: &[f32]) -> f64 {
        let b = x.len() / 3;
        let ss = self.net.size() * self.net.size();
        assert_eq!(target.len(), b * ss, "targets");
        self.size_for(b);
        let net = &self.net;
        let nfc = net.fcs.len();
        // The fully connected layers on the whole batch, into the kept buffers (the same
        // products as `InputVjp::dense_forward`).
        for li in 0..nfc {
            let (prev, cur) = self.hid.split_at_mut(li);
            let input: &[f32] = if li == 0 { x } else { &prev[li - 1] };
            let fc = &net.fcs[li];
            fc.fwd.apply_scratch(input, Some(&fc.b), &mut cur[0], &mut self.dense_t);
            if li + 1 < nfc {
                cur[0].iter_mut().for_each(|v| *v = v.max(0.0));
            }
        }
        let (hidden, seed) = self.hid.split_at(nfc - 1);
        let seed = &seed[0];
        let sl = net.seed_len();
        let pool = &self.pool;
        // Per image, in one pass (its activations stay in the core's cache): the stages, the
        // squared error and its gradient, back through the stages, the weight gradients of each.
        // The squared errors are summed image by image, then over the images in order.
        let k = 2.0 / (b * ss) as f32;
        let cl = conv_len(net);
        self.sq.resize(b, 0.0);
        self.per_image
            .par_chunks_mut(cl + sl)
            .zip(self.sq.par_iter_mut())
            .zip(seed.par_chunks(sl))
            .zip(target.par_chunks(ss))
            .for_each_init(
                || Scratch::take(pool),
                |sc, (((out, sq), sd), t)| {
                    let Scratch { acts, bufs, masks, img, up, acc } = sc.get(net);
                    net.isa.dispatch(ForwardImage { net, seed: sd, img, masks: Some(&mut masks[..]), buf: acts, acc });
                    let mut e = 0f64;
                    for ((u, &y), &t) in up.iter_mut().zip(img.iter()).zip(t) {
                        let d = y - t;
                        e += (d as f64) * (d as f64);
                        *u = k * d;
                    }
                    *sq = e;
                    let (grads, gs) = out.split_at_mut(cl);
                    net.isa.dispatch(BackwardImage { net, gs, up, img, masks, bufs, acc });
                    net.isa.dispatch(WeightGrads { net, bufs, acts, grads });
                },
            );
        let loss = self.sq.iter().sum::<f64>() / (b * ss) as f64;
        // The convolution gradients summed over the images, in image order.
        let mut off = 0;
        for p in &mut self.params[2 * nfc..] {
            let len = p.g.len();
            let per = &self.per_image;
            p.g.par_chunks_mut(1024).enumerate().for_each(|(ci, gch)| {
                let base = off + ci * 1024;
                gch.fill(0.0);
                for i in 0..b {
                    let src = &per[i * (cl + sl) + base..i * (cl + sl) + base + gch.len()];
                    gch.iter_mut().zip(src).for_each(|(a, v)| *a += v);
                }
            });
            off += len;
        }
        // Back through the fully connected layers, on the whole batch.
        let (mut g, mut gi) = (std::mem::take(&mut self.g), std::mem::take(&mut self.gi));
        g.clear();
        for i in 0..b {
            g.extend_from_slice(&self.per_image[i * (cl + sl) + cl..(i + 1) * (cl + sl)]);
        }
        for li in (0..nfc).rev() {
            let fc = &net.fcs[li];
            let input: &[f32] = if li == 0 { x } else { &hidden[li - 1] };
            let inp = input.len() / b.max(1);
            let (wp, rest) = self.params[2 * li..].split_at_mut(1);
            let (gw, gb) = (&mut wp[0].g, &mut rest[0].g);
            // dW = gᵀ · input ([out, inp], candle's layout), a packed product (each value a
            // chain of fused multiply–adds over the batch in order); db[o] = Σ_b g[b, o].
            let out = fc.out;
            self.gt.resize(out * b, 0.0);
            self.gt.par_chunks_mut(b).enumerate().for_each(|(o, row)| {
                for (i, v) in row.iter_mut().enumerate() {
                    *v = g[i * out + o];
                }
            });
            let xin = &mut self.xin[li];
            xin.repack(input);
            xin.apply_scratch(&self.gt, None, gw, &mut self.dense_t);
            gb.par_iter_mut().zip(self.gt.par_chunks(b)).for_each(|(bo, row)| *bo = row.iter().fold(0.0, |a, v| a + v));
            if li > 0 {
                gi.resize(b * inp, 0.0);
                fc.bwd.apply_scratch(&g, None, &mut gi, &mut self.dense_t);
                gi.iter_mut().zip(&hidden[li - 1]).for_each(|(v, &a)| {
                    if a <= 0.0 {
                        *v = 0.0;
                    }
                });
                std::mem::swap(&mut g, &mut gi);
            }
        }
        self.g = g;
        self.gi = gi;
        loss
    }

    /// One AdamW step (candle's `AdamW` rule, weight decay 0) on the gradients of the last
    /// [`DirectTrainer::gradients`], at learning rate `lr`; the kernels then run on the new
    /// weights.
    ///
    /// # Errors
    /// As [`InputVjp::new`].
    pub fn update(&mut self, lr: f64) -> Result<(), NeuralGenError> {
        self.t += 1;
        for p in &mut self.params {
            adamw_step(&mut p.w, &p.g, &mut p.m, &mut p.v, lr, self.t);
        }
        self.repack();
        Ok(())
    }

    /// Packs the parameters into the kernels' layouts, in place (the same values as
    /// [`InputVjp::from_weights`] would pack).
    fn repack(&mut self) {
        let nfc = self.net.fcs.len();
        for (li, fc) in self.net.fcs.iter_mut().enumerate() {
            let w = &self.params[2 * li].w;
            fc.fwd.repack_transposed(w);
            fc.bwd.repack(w);
            fc.b.copy_from_slice(&self.params[2 * li + 1].w);
        }
        for (si, st) in self.net.stages.iter_mut().enumerate() {
            let w = &self.params[2 * (nfc + si)].w;
            st.fwd.repack(w);
            st.bwd.repack_flipped(w);
            st.b.copy_from_slice(&self.params[2 * (nfc + si) + 1].w);
        }
    }

    /// [`DirectTrainer::gradients`] then [`DirectTrainer::update`]: one training step; returns
    /// the MSE before it.
    ///
    /// # Errors
    /// As [`DirectTrainer::update`].
    pub fn step(&mut self, x: &[f32], target: &[f32], lr: f64) -> Result<f64, NeuralGenError> {
        let loss = self.gradients(x, target);
        self.update(lr)?;
        Ok(loss)
    }

    /// The gradient of the last [`DirectTrainer::gradients`] for the tensor `name`.
    pub fn gradient(&self, name: &str) -> Option<&[f32]> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.g[..])
    }

    /// The network on the current weights.
    pub fn kernels(&self) -> &InputVjp {
        &self.net
    }

    /// The current weights, by name.
    pub(crate) fn snapshot(&self) -> Vec<Vec<f32>> {
        self.params.iter().map(|p| p.w.clone()).collect()
    }

    /// Restores weights from [`DirectTrainer::snapshot`].
    pub(crate) fn restore(&mut self, w: Vec<Vec<f32>>) -> Result<(), NeuralGenError> {
        for (p, w) in self.params.iter_mut().zip(w) {
            p.w = w;
        }
        self.repack();
        Ok(())
    }

    /// Copies the current weights into `g`'s candle variables.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn write_back(&self, g: &mut Generator) -> Result<(), NeuralGenError> {
        {
            let data = g.varmap.data().lock().expect("varmap");
            for p in &self.params {
                let t = candle_core::Tensor::from_vec(p.w.clone(), p.dims.clone(), g.device())
                    .map_err(NeuralGenError::Candle)?;
                data[&p.name].set(&t).map_err(NeuralGenError::Candle)?;
            }
        }
        g.weights_changed();
        Ok(())
    }
}

/// The weight and bias gradients of every stage of one image: `bufs[si]` the padded gradient
/// at stage `si`'s output (from [`BackwardImage`]), `acts` the stages' padded inputs.
struct WeightGrads<'a> {
    net: &'a InputVjp,
    bufs: &'a [Vec<f32>],
    acts: &'a [f32],
    grads: &'a mut [f32],
}

impl WithSimd for WeightGrads<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let (mut aoff, mut goff) = (0, 0);
        for (si, st) in self.net.stages.iter().enumerate() {
            let x = &self.acts[aoff..aoff + padded_len(st.cin, st.n)];
            let (gw, rest) = self.grads[goff..].split_at_mut(st.cout * st.cin * 9);
            conv_weight_grads(simd, x, &self.bufs[si], (st.cin, st.cout, st.n), gw, &mut rest[..st.cout]);
            aoff += padded_len(st.cin, st.n);
            goff += st.cout * st.cin * 9 + st.cout;
        }
    }
}

/// The weight (`gw`, `[cout, cin, 3, 3]`) and bias (`gb`, `[cout]`) gradients of one 3×3
/// convolution (padding 1) of one image of `n × n` pixels (`(cin, cout, n)`): `x` its padded
/// input planes, `gy` the padded gradient at its output (zero borders). Each sum a fixed
/// order of operations (vectors of positions, the last one partial, then their lanes, as
/// [`Simd::reduce_sum_f32s`] adds them); output
/// channels are taken four at a time (three at a time, then one, for the rest) and kernel rows
/// one at a time, so that each vector of the input is loaded once for several output
/// channels and taps; the blocking does not change any sum.
#[inline(always)]
pub(crate) fn conv_weight_grads<S: Simd>(
    simd: S,
    x: &[f32],
    gy: &[f32],
    (cin, cout, n): (usize, usize, usize),
    gw: &mut [f32],
    gb: &mut [f32],
) {
    let mut o = 0;
    while o + 4 <= cout {
        wgrad_block::<S, 4>(simd, x, gy, (cin, o, n), gw, gb);
        o += 4;
    }
    while o + 2 <= cout {
        wgrad_block::<S, 2>(simd, x, gy, (cin, o, n), gw, gb);
        o += 2;
    }
    while o < cout {
        wgrad_block::<S, 1>(simd, x, gy, (cin, o, n), gw, gb);
        o += 1;
    }
}

/// Output channels `o0 .. o0 + OB` of [`conv_weight_grads`].
#[inline(always)]
fn wgrad_block<S: Simd, const OB: usize>(
    simd: S,
    x: &[f32],
    gy: &[f32],
    (cin, o0, n): (usize, usize, usize),
    gw: &mut [f32],
    gb: &mut [f32],
) {
    let l = S::F32_LANES;
    let wp = n + 2;
    let q2 = wp * wp;
    // Positions q of the padded plane whose 3×3 neighbourhood lies inside it; the
    // gradient is zero on the border, so these are all that count.
    let (q0, q1) = (wp + 1, q2 - wp - 1);
    let full = (q1 - q0) / l * l;
    let tail = q1 - q0 - full;
    let load = |v: &[f32], at: usize| -> S::f32s {
        pulp::bytemuck::pod_read_unaligned(pulp::bytemuck::cast_slice(&v[at..at + l]))
    };
    let g: [&[f32]; OB] = std::array::from_fn(|j| &gy[(o0 + j) * q2..(o0 + j + 1) * q2]);
    // The bias sums: vectors of positions over the whole plane (the last one partial), then
    // their lanes.
    let mut sb = [simd.splat_f32s(0.0); OB];
    let mut q = 0;
    while q + l <= q2 {
        for (s, gj) in sb.iter_mut().zip(&g) {
            *s = simd.add_f32s(*s, load(gj, q));
        }
        q += l;
    }
    if q < q2 {
        for (s, gj) in sb.iter_mut().zip(&g) {
            *s = simd.add_f32s(*s, simd.partial_load_f32s(&gj[q..q2]));
        }
    }
    for (b, s) in gb[o0..o0 + OB].iter_mut().zip(sb) {
        *b = simd.reduce_sum_f32s(s);
    }
    for c in 0..cin {
        let xc = &x[c * q2..(c + 1) * q2];
        for ky in 0..3 {
            let mut acc = [[simd.splat_f32s(0.0); 3]; OB];
            let mut q = q0;
            while q < q0 + full {
                let gv: [S::f32s; OB] = std::array::from_fn(|j| load(g[j], q));
                for kx in 0..3 {
                    let xv = load(xc, q + ky * wp + kx - wp - 1);
                    for (aj, &gj) in acc.iter_mut().zip(&gv) {
                        aj[kx] = simd.mul_add_f32s(gj, xv, aj[kx]);
                    }
                }
                q += l;
            }
            if tail > 0 {
                // The last positions as one partial vector (zeros past the end).
                let gv: [S::f32s; OB] = std::array::from_fn(|j| simd.partial_load_f32s(&g[j][q..q1]));
                for kx in 0..3 {
                    let s = q + ky * wp + kx - wp - 1;
                    let xv = simd.partial_load_f32s(&xc[s..s + tail]);
                    for (aj, &gj) in acc.iter_mut().zip(&gv) {
                        aj[kx] = simd.mul_add_f32s(gj, xv, aj[kx]);
                    }
                }
            }
            for (j, aj) in acc.iter().enumerate() {
                let o = o0 + j;
                let w = &mut gw[(o * cin + c) * 9..(o * cin + c + 1) * 9];
                for (kx, &a) in aj.iter().enumerate() {
                    w[ky * 3 + kx] = simd.reduce_sum_f32s(a);
                }
            }
        }
    }
}

/// One AdamW step (candle's rule, weight decay 0) at step `t` (from 1) on weights `w` with
/// gradients `g` and moments `m`, `v`, in parallel over fixed chunks.
pub(crate) fn adamw_step(w: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], lr: f64, t: i32) {
    let (b1, b2, eps) = (0.9f64, 0.999f64, 1e-8f64);
    let (sm, sv) = ((1.0 / (1.0 - b1.powi(t))) as f32, (1.0 / (1.0 - b2.powi(t))) as f32);
    let (lr, b1, b2, eps) = (lr as f32, b1 as f32, b2 as f32, eps as f32);
    w.par_chunks_mut(1 << 14)
        .zip(m.par_chunks_mut(1 << 14))
        .zip(v.par_chunks_mut(1 << 14))
        .zip(g.par_chunks(1 << 14))
        .for_each(|(((th, m), v), g)| {
            for i in 0..th.len() {
                let gi = g[i];
                m[i] = b1 * m[i] + (1.0 - b1) * gi;
                v[i] = b2 * v[i] + (1.0 - b2) * gi * gi;
                let step = (m[i] * sm) / ((v[i] * sv).sqrt() + eps);
                th[i] -= lr * step;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::DirectTrainer;
    use crate::{Arch, Generator, GeneratorConfig, NetworkStep};
    use brush_model::{BrushProfile, Press};
    use candle_core::Tensor;

    fn presses(n: usize) -> Vec<Press> {
        (0..n)
            .map(|i| {
                let f = i as f64 / n as f64;
                Press::from_degrees(11.0 + 9.0 * f, 10.0 * ((7 * i) % n) as f64 / n as f64, 5.0 * f)
            })
            .collect()
    }

    /// Gradients of every tensor and one AdamW step against candle's autograd and the fused
    /// AdamW on the candle graph (`NetworkStep`).
    fn check(arch: Arch, batch: usize, what: &str) {
        let profile = BrushProfile::builtin("pen1").unwrap();
        let mut g = Generator::new(GeneratorConfig::new(profile.clone(), arch.clone()), 3).unwrap();
        let ps = presses(batch);
        let s = g.config.size as usize;
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let t: Vec<f32> = (0..batch * s * s).map(|i| ((i * 7919) % 113) as f32 / 113.0).collect();
        let mut tr = DirectTrainer::new(&g).unwrap();
        let loss = tr.gradients(&x, &t);
        // candle: the same loss through the graph.
        let xs = g.inputs(&ps).unwrap();
        let ts = Tensor::from_vec(t.clone(), (batch, 1, s, s), g.device()).unwrap();
        let l = (g.forward_autograd(&xs).unwrap() - &ts).unwrap().sqr().unwrap().mean_all().unwrap();
        let lc = l.to_scalar::<f32>().unwrap() as f64;
        assert!((loss - lc).abs() < 1e-5 * lc.max(1e-3), "{what}: loss {loss} vs candle {lc}");
        let grads = l.backward().unwrap();
        let data = g.varmap.data().lock().unwrap();
        for (name, var) in data.iter() {
            let want: Vec<f32> = grads.get(var).unwrap().flatten_all().unwrap().to_vec1().unwrap();
            let got = tr.gradient(name).unwrap();
            assert_eq!(want.len(), got.len());
            let scale = want.iter().fold(0f32, |m, v| m.max(v.abs())).max(1e-12);
            let worst = want.iter().zip(got).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst <= 1e-3 * scale, "{what} {name}: worst {worst} of {scale}");
            assert!(scale > 1e-9 || name.ends_with("bias"), "{what} {name}: a zero gradient tests nothing");
        }
        drop(data);
        // One AdamW step each way: the same weights.
        let mut gc = Generator::new(GeneratorConfig::new(profile, arch), 3).unwrap();
        let mut ns = NetworkStep::new(&gc, 1e-3).unwrap();
        ns.step(&mut gc, &xs, &ts, 1e-3).unwrap();
        tr.update(1e-3).unwrap();
        tr.write_back(&mut g).unwrap();
        let (a, b) = (g.weights().unwrap(), gc.weights().unwrap());
        for (name, ta) in &a {
            let va: Vec<f32> = ta.flatten_all().unwrap().to_vec1().unwrap();
            let vb: Vec<f32> = b[name].flatten_all().unwrap().to_vec1().unwrap();
            // Adam moves each weight by about lr; a gradient near zero may flip the sign of a
            // step, so compare to a fraction of the step.
            let worst = va.iter().zip(&vb).fold(0f32, |m, (p, q)| m.max((p - q).abs()));
            assert!(worst < 2.1e-3, "{what} {name}: weights differ by {worst} after one step");
            let moved = va.iter().zip(&vb).filter(|(p, q)| (*p - *q).abs() < 1e-5).count();
            assert!(moved * 10 >= va.len() * 9, "{what} {name}: {moved} of {} weights agree", va.len());
        }
        // The generator renders with the written-back weights.
        assert_eq!(g.render(&ps).unwrap().len(), batch);
    }

    #[test]
    fn gradients_and_steps_match_candle_for_the_shipped_architecture() {
        check(Arch::default_128(), 3, "pen1");
    }

    #[test]
    fn gradients_and_steps_match_candle_for_odd_architectures() {
        check(Arch::tiny_32(), 5, "tiny");
        check(
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] },
            4,
            "odd",
        );
    }

    /// After steps, the kernels repacked in place give the same images, bit for bit, as
    /// kernels packed afresh from the written-back weights.
    #[test]
    fn repacked_kernels_equal_fresh_ones() {
        let arch =
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] };
        let mut g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 4).unwrap();
        let ps = presses(5);
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let s = g.config.size as usize;
        let t: Vec<f32> = (0..5 * s * s).map(|i| ((i * 31) % 17) as f32 / 17.0).collect();
        let mut tr = DirectTrainer::new(&g).unwrap();
        let before = tr.kernels().images_normalised(&x);
        for _ in 0..2 {
            tr.step(&x, &t, 1e-2).unwrap();
        }
        tr.write_back(&mut g).unwrap();
        let fresh = crate::InputVjp::new(&g).unwrap().images_normalised(&x);
        let repacked = tr.kernels().images_normalised(&x);
        assert_ne!(before, repacked, "the steps changed nothing");
        assert_eq!(fresh, repacked);
    }

    /// The same gradients on one thread and on two.
    #[test]
    fn gradients_do_not_depend_on_the_thread_count() {
        let g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::tiny_32()), 5).unwrap();
        let ps = presses(6);
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let t = vec![0.25f32; 6 * 32 * 32];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut tr = DirectTrainer::new(&g).unwrap();
                tr.step(&x, &t, 1e-3).unwrap();
                tr.gradients(&x, &t);
                tr.params.iter().map(|p| (p.g.clone(), p.w.clone())).collect::<Vec<_>>()
            })
        };
        assert_eq!(run(1), run(2));
    }

    /// The weight and bias gradients of one convolution against a naive f64 sum, on every
    /// instruction set (AVX-512, AVX2 and scalar where the CPU has them), for odd channel
    /// counts (blocks of four, two and one output channel) and sides whose positions end in a
    /// partial vector.
    #[test]
    fn convolution_weight_gradients_match_naive_sums() {
        use crate::kernels::{Isa, padded_len};
        use pulp::{Simd, WithSimd};
        struct Grads<'a> {
            x: &'a [f32],
            gy: &'a [f32],
            dims: (usize, usize, usize),
            gw: &'a mut [f32],
            gb: &'a mut [f32],
        }
        impl WithSimd for Grads<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: Simd>(self, simd: S) {
                super::conv_weight_grads(simd, self.x, self.gy, self.dims, self.gw, self.gb);
            }
        }
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        };
        for &(cin, cout, n) in &[(3, 5, 1), (2, 7, 5), (4, 9, 8), (3, 6, 17), (2, 4, 40), (1, 3, 64)] {
            let wp = n + 2;
            let q2 = wp * wp;
            // Padded input planes (borders zero, as the stages write them) and a gradient that
            // is zero on the border.
            let mut x = vec![0f32; padded_len(cin, n)];
            let mut gy = vec![0f32; padded_len(cout, n)];
            for (planes, v) in [(cin, &mut x), (cout, &mut gy)] {
                for p in 0..planes {
                    for y in 1..=n {
                        for xx in 1..=n {
                            v[p * q2 + y * wp + xx] = next();
                        }
                    }
                }
            }
            let mut want_w = vec![0f64; cout * cin * 9];
            let mut scale_w = vec![0f64; cout * cin * 9];
            let mut want_b = vec![0f64; cout];
            for o in 0..cout {
                for y in 0..n {
                    for xx in 0..n {
                        let g = f64::from(gy[o * q2 + (y + 1) * wp + xx + 1]);
                        want_b[o] += g;
                        for c in 0..cin {
                            for ky in 0..3 {
                                for kx in 0..3 {
                                    let v = g * f64::from(x[c * q2 + (y + ky) * wp + xx + kx]);
                                    want_w[((o * cin + c) * 3 + ky) * 3 + kx] += v;
                                    scale_w[((o * cin + c) * 3 + ky) * 3 + kx] += v.abs();
                                }
                            }
                        }
                    }
                }
            }
            for isa in Isa::all_for_tests() {
                let (mut gw, mut gb) = (vec![f32::NAN; cout * cin * 9], vec![f32::NAN; cout]);
                isa.dispatch(Grads { x: &x, gy: &gy, dims: (cin, cout, n), gw: &mut gw, gb: &mut gb });
                for (i, (g, w)) in gw.iter().zip(&want_w).enumerate() {
                    assert!(
                        (f64::from(*g) - w).abs() <= 1e-5 * (1.0 + scale_w[i]),
                        "{isa:?} {cin}→{cout}@{n} weight [{i}]: {g} vs {w}"
                    );
                }
                for (o, (g, w)) in gb.iter().zip(&want_b).enumerate() {
                    assert!(
                        (f64::from(*g) - w).abs() <= 1e-5 * (1.0 + n as f64 * n as f64),
                        "{isa:?} {cin}→{cout}@{n} bias [{o}]: {g} vs {w}"
                    );
                }
            }
        }
    }
}
