//! Register-blocked kernels for [`crate::InputVjp`]: a 3×3 correlation (padding 1) on
//! padded planes and a small row-major matrix product, written once over [`pulp::Simd`] and
//! run on the widest vectors the CPU has ([`pulp::Arch::dispatch`]: AVX-512, AVX2 + FMA, NEON
//! or scalar).
//!
//! Every output is summed in the same order with fused multiply–adds (over input channel,
//! then kernel row, then kernel column; or over the inner dimension), from zero, whatever the
//! vector width, and never depends on the outputs computed beside it: the results are the same
//! bits on every instruction set, batch size, thread count and tiling. These kernels are
//! separate from [`crate::conv`]'s, whose summation (training, the committed fixtures) is left
//! as it is.
//!
//! The correlation works on the "padded stride" layout of [`crate::conv`]: an image of `n × n`
//! pixels and `C` channels is held as `C` zero-bordered planes of `(n + 2)²` values followed by
//! [`SLACK`] values, so that output position `p = y·(n + 2) + x` of kernel tap `(ky, kx)` reads
//! position `p + ky·(n + 2) + kx`: a tile of consecutive positions is a few contiguous vector
//! loads. A tile of positions × a block of output channels is accumulated in registers over
//! every input channel and tap, and the results are handed row by row to the caller's `emit`
//! (bias, activation, pixel shuffle, masks), which writes them where the next layer reads them.

use pulp::{Simd, WithSimd};
use rayon::prelude::*;

/// Values after the last padded plane of a correlation's input: the tiles of the last row
/// read up to this far past the planes (into outputs that are discarded).
pub(crate) const SLACK: usize = 64;

/// Length of the padded-plane buffer of `c` channels of `n × n` pixels (with [`SLACK`]).
pub(crate) fn padded_len(c: usize, n: usize) -> usize {
    c * (n + 2) * (n + 2) + SLACK
}

/// f32 lanes of the vectors [`pulp::Arch::dispatch`] runs on.
struct Lanes;

impl WithSimd for Lanes {
    type Output = usize;
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) -> usize {
        S::F32_LANES
    }
}

/// The kernels' instruction set: pulp's dispatcher and its vector width.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Isa {
    arch: pulp::Arch,
    lanes: usize,
}

impl Isa {
    /// The best the CPU supports.
    pub(crate) fn detect() -> Self {
        let arch = pulp::Arch::new();
        Isa { arch, lanes: arch.dispatch(Lanes) }
    }

    /// Runs `op` on the detected vectors (what it inlines is compiled for them).
    #[inline(always)]
    pub(crate) fn dispatch<Op: WithSimd>(self, op: Op) -> Op::Output {
        self.arch.dispatch(op)
    }

    /// The detected instruction set, on x86-64 also AVX2 + FMA where the CPU has wider
    /// vectors (so that both paths are tested on an AVX-512 machine), and the scalar one (one
    /// lane).
    #[cfg(test)]
    pub(crate) fn all_for_tests() -> Vec<Isa> {
        let scalar = pulp::Arch::Scalar;
        let mut out = vec![Isa::detect()];
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            let arch = pulp::Arch::V3(v3);
            if arch.dispatch(Lanes) != out[0].lanes {
                out.push(Isa { arch, lanes: arch.dispatch(Lanes) });
            }
        }
        out.push(Isa { arch: scalar, lanes: 1 });
        out
    }

    /// Output channels per register block and vectors per tile for a correlation with `o`
    /// outputs: `ob × nv` accumulators (16 of the 32 AVX-512 registers, [`NARROW_VECTORS`]
    /// × 4 of 16 otherwise).
    fn blocking(self, o: usize) -> (usize, usize) {
        match self.lanes {
            16 if o % 8 == 0 => (8, 2),
            16 => (4, 4),
            _ => (4, NARROW_VECTORS),
        }
    }
}

/// A 3×3 correlation with padding 1 (`y[o] = Σ_c w[o, c] ⋆ x[c]`, no bias), its weights
/// rearranged for the register blocks of one [`Isa`].
#[derive(Debug, Clone)]
pub(crate) struct Conv3 {
    cin: usize,
    cout: usize,
    ob: usize,
    isa: Isa,
    /// `[block][c][tap][j]`, zero for channels past `cout`.
    w: Vec<f32>,
}

/// Sizes of one correlation call: input channels, padded width, accumulator span per output
/// channel, tiles and output channels per block.
#[derive(Debug, Clone, Copy)]
struct Geometry {
    cin: usize,
    wp: usize,
    span: usize,
    tiles: usize,
    ob: usize,
    /// Rows per band.
    band: usize,
}

impl Conv3 {
    /// From weights `[cout, cin, 3, 3]`, row-major.
    pub(crate) fn new(w: &[f32], cout: usize, cin: usize, isa: Isa) -> Self {
        assert_eq!(w.len(), cout * cin * 9, "3×3 weights");
        let ob = isa.blocking(cout).0;
        let blocks = cout.div_ceil(ob);
        let mut c3 = Conv3 { cin, cout, ob, isa, w: vec![0f32; blocks * cin * 9 * ob] };
        c3.repack(w);
        c3
    }

    /// Rearranges new weights `[cout, cin, 3, 3]` (row-major) into the blocks, in place.
    ///
    /// # Panics
    /// When `w` is not `cout × cin × 9` long.
    pub(crate) fn repack(&mut self, w: &[f32]) {
        let (cin, cout, ob) = (self.cin, self.cout, self.ob);
        assert_eq!(w.len(), cout * cin * 9, "3×3 weights");
        for o in 0..cout {
            for c in 0..cin {
                for tap in 0..9 {
                    self.w[(((o / ob) * cin + c) * 9 + tap) * ob + o % ob] = w[(o * cin + c) * 9 + tap];
                }
            }
        }
    }

    /// As [`Conv3::repack`] from the weights `[cout, cin, 3, 3]` of the correlation this one is
    /// the flipped transpose of (`[cin, cout, 3, 3]` here: the input gradient's kernel).
    ///
    /// # Panics
    /// When `w` is not `cout × cin × 9` long.
    pub(crate) fn repack_flipped(&mut self, w: &[f32]) {
        // This correlation maps `cin` (the original's outputs) to `cout` (its inputs).
        let (ci, co, ob) = (self.cin, self.cout, self.ob);
        assert_eq!(w.len(), co * ci * 9, "3×3 weights");
        for o in 0..co {
            for c in 0..ci {
                for tap in 0..9 {
                    // wf[o, c, tap] = w[c, o, 8 − tap].
                    self.w[(((o / ob) * ci + c) * 9 + tap) * ob + o % ob] = w[(c * co + o) * 9 + 8 - tap];
                }
            }
        }
    }

    /// Correlates the padded planes `x` (`cin` planes of `(n + 2)²`, then [`SLACK`]) and calls
    /// `emit(o, y, row)` with the `n` outputs of every output channel `o` and row `y`: band of
    /// rows after band of rows, in each band channel block after block, rows in order (every
    /// pair `(o, y)` exactly once). `acc` is scratch.
    ///
    /// # Panics
    /// When `x` is shorter than [`padded_len`]`(cin, n)`.
    #[inline(always)]
    pub(crate) fn run(&self, x: &[f32], n: usize, acc: &mut Vec<f32>, mut emit: impl FnMut(usize, usize, &[f32])) {
        let g = self.geometry(x, n, acc);
        for y0 in (0..n).step_by(g.band) {
            let y1 = (y0 + g.band).min(n);
            for blk in 0..self.cout.div_ceil(self.ob) {
                self.block(x, blk, g, (y0, y1, n), acc);
                let o0 = blk * self.ob;
                for j in 0..self.ob.min(self.cout - o0) {
                    for y in y0..y1 {
                        let r = j * g.span + (y - y0) * g.wp;
                        emit(o0 + j, y, &acc[r..r + n]);
                    }
                }
            }
        }
    }

    /// As [`Conv3::run`], two channels at a time: `emit(o, y, row_o, row_o+1)` for every even
    /// `o` (what a ×2 pixel shuffle interleaves into one row).
    ///
    /// # Panics
    /// As [`Conv3::run`], and when the number of output channels is odd.
    #[inline(always)]
    pub(crate) fn run_pairs(
        &self,
        x: &[f32],
        n: usize,
        acc: &mut Vec<f32>,
        mut emit: impl FnMut(usize, usize, &[f32], &[f32]),
    ) {
        assert!(self.cout % 2 == 0, "pairs of {} channels", self.cout);
        let g = self.geometry(x, n, acc);
        for y0 in (0..n).step_by(g.band) {
            let y1 = (y0 + g.band).min(n);
            for blk in 0..self.cout.div_ceil(self.ob) {
                self.block(x, blk, g, (y0, y1, n), acc);
                let o0 = blk * self.ob;
                for j in (0..self.ob.min(self.cout - o0)).step_by(2) {
                    for y in y0..y1 {
                        let (r0, r1) = (j * g.span + (y - y0) * g.wp, (j + 1) * g.span + (y - y0) * g.wp);
                        emit(o0 + j, y, &acc[r0..r0 + n], &acc[r1..r1 + n]);
                    }
                }
            }
        }
    }

    /// Checks the input and sizes the accumulators for an `n × n` image, in bands of rows of
    /// about [`BAND_POSITIONS`] positions (so that a band's accumulators and input rows stay
    /// in the L1 cache while every block of output channels runs over them).
    #[inline(always)]
    fn geometry(&self, x: &[f32], n: usize, acc: &mut Vec<f32>) -> Geometry {
        let wp = n + 2;
        assert!(
            x.len() >= padded_len(self.cin, n),
            "correlation input: {} values for {} planes of {wp}²",
            x.len(),
            self.cin
        );
        let t = self.isa.blocking(self.cout).1 * self.isa.lanes;
        assert!(t <= SLACK);
        let band = BAND_POSITIONS.div_ceil(wp).clamp(1, n.max(1));
        let span = (band * wp).div_ceil(t) * t;
        acc.resize(self.ob * span, 0.0);
        Geometry { cin: self.cin, wp, span, tiles: 0, ob: self.ob, band }
    }

    /// Block `blk` of output channels of the rows `y0 .. y1` (of `n`) into `acc`, on rows of
    /// `n + 2` from row `y0` (`span` values per channel).
    #[inline(always)]
    fn block(&self, x: &[f32], blk: usize, g: Geometry, (y0, y1, n): (usize, usize, usize), acc: &mut [f32]) {
        let wblk = self.cin * 9 * self.ob;
        let w = &self.w[blk * wblk..(blk + 1) * wblk];
        let t = self.isa.blocking(self.cout).1 * self.isa.lanes;
        // The last band stops two positions short of its last padded row (what lies past
        // them is discarded), so that its tiles read at most `t` values past the planes.
        let positions = (y1 - y0) * g.wp - if y1 == n { 2 } else { 0 };
        let g = Geometry { tiles: positions.div_ceil(t), ..g };
        self.isa.arch.dispatch(ConvBlock { x, w, acc, g, p0: y0 * g.wp });
    }
}

/// Vectors of positions per correlation tile below 16 lanes (AVX2: 4 output channels × this
/// many vectors of accumulators, of the 16 vector registers).
const NARROW_VECTORS: usize = 2;

/// Output positions per band of rows of a correlation (see [`Conv3::run`]).
const BAND_POSITIONS: usize = 512;

/// One block of output channels of a correlation, every tile (see [`conv_block`]).
struct ConvBlock<'a> {
    x: &'a [f32],
    w: &'a [f32],
    acc: &'a mut [f32],
    g: Geometry,
    /// First position of the band (its tiles' positions are relative to it in `acc`).
    p0: usize,
}

impl WithSimd for ConvBlock<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        match (S::F32_LANES, self.g.ob) {
            (16, 8) => conv_block::<S, 8, 2>(simd, self),
            (16, _) => conv_block::<S, 4, 4>(simd, self),
            _ => conv_block::<S, 4, NARROW_VECTORS>(simd, self),
        }
    }
}

/// An unaligned vector load of `S::F32_LANES` values.
#[inline(always)]
fn load<S: Simd>(s: &[f32]) -> S::f32s {
    pulp::bytemuck::pod_read_unaligned(pulp::bytemuck::cast_slice(s))
}

/// `OB` output channels × `NV` vectors of positions per tile, accumulated in `OB·NV`
/// registers over every input channel and tap; the block's weights `w` are `[c][tap][j]`.
#[inline(always)]
fn conv_block<S: Simd, const OB: usize, const NV: usize>(simd: S, op: ConvBlock<'_>) {
    let (l, g) = (S::F32_LANES, op.g);
    let plane = g.wp * g.wp;
    for tile in 0..g.tiles {
        let t0 = tile * NV * l;
        let p = op.p0 + t0;
        let mut a = [[simd.splat_f32s(0.0); NV]; OB];
        for c in 0..g.cin {
            let wc = &op.w[c * 9 * OB..(c + 1) * 9 * OB];
            let xc = &op.x[c * plane + p..c * plane + p + 2 * g.wp + 2 + NV * l];
            for ky in 0..3 {
                for kx in 0..3 {
                    let off = ky * g.wp + kx;
                    let xs: [S::f32s; NV] = std::array::from_fn(|v| load::<S>(&xc[off + v * l..off + (v + 1) * l]));
                    let wt = &wc[(ky * 3 + kx) * OB..(ky * 3 + kx + 1) * OB];
                    for (aj, &wj) in a.iter_mut().zip(wt) {
                        let wj = simd.splat_f32s(wj);
                        for (av, &xv) in aj.iter_mut().zip(&xs) {
                            *av = simd.mul_add_f32s(wj, xv, *av);
                        }
                    }
                }
            }
        }
        for (j, aj) in a.iter().enumerate() {
            let dst = &mut op.acc[j * g.span + t0..j * g.span + t0 + NV * l];
            pulp::bytemuck::cast_slice_mut::<f32, S::f32s>(dst).copy_from_slice(aj);
        }
    }
}

/// A fully connected product `y = x · B (+ bias)` over a batch of rows, `B` (`[k, n]`) packed
/// once into panels of a few vectors of columns (`[panel][k][p]`, zero past `n`), so that a
/// tile streams its panel contiguously.
#[derive(Debug, Clone)]
pub(crate) struct Dense {
    k: usize,
    n: usize,
    /// Panel width: columns per register tile.
    p: usize,
    isa: Isa,
    panels: Vec<f32>,
}

impl Dense {
    /// From `B` `[k, n]`, row-major.
    pub(crate) fn new(b: &[f32], k: usize, n: usize, isa: Isa) -> Self {
        let p = Self::vectors(isa.lanes) * isa.lanes;
        let mut d = Dense { k, n, p, isa, panels: vec![0f32; n.div_ceil(p) * k * p] };
        d.repack(b);
        d
    }

    /// From `W` `[n, k]`, row-major: the product `x · Wᵀ` (a fully connected layer's forward
    /// pass with candle's weight layout), without a transposed copy.
    pub(crate) fn new_transposed(w: &[f32], n: usize, k: usize, isa: Isa) -> Self {
        let p = Self::vectors(isa.lanes) * isa.lanes;
        let mut d = Dense { k, n, p, isa, panels: vec![0f32; n.div_ceil(p) * k * p] };
        d.repack_transposed(w);
        d
    }

    /// Packs new values of `B` (`[k, n]`, row-major) into the panels (in parallel over them).
    ///
    /// # Panics
    /// When `b` is not `k × n` long.
    pub(crate) fn repack(&mut self, b: &[f32]) {
        let (k, n, p) = (self.k, self.n, self.p);
        assert_eq!(b.len(), k * n, "matrix: {} values for {k} × {n}", b.len());
        if k == 0 {
            return;
        }
        self.panels.par_chunks_mut(k * p).enumerate().for_each(|(pi, panel)| {
            let (j0, cols) = (pi * p, p.min(n - pi * p));
            for (kk, row) in panel.chunks_exact_mut(p).enumerate() {
                row[..cols].copy_from_slice(&b[kk * n + j0..kk * n + j0 + cols]);
            }
        });
    }

    /// Packs new values of `W = Bᵀ` (`[n, k]`, row-major) into the panels.
    ///
    /// # Panics
    /// When `w` is not `n × k` long.
    pub(crate) fn repack_transposed(&mut self, w: &[f32]) {
        let (k, n, p) = (self.k, self.n, self.p);
        assert_eq!(w.len(), k * n, "matrix: {} values for {n} × {k}", w.len());
        if k == 0 {
            return;
        }
        self.panels.par_chunks_mut(k * p).enumerate().for_each(|(pi, panel)| {
            for q in 0..p.min(n - pi * p) {
                let src = &w[(pi * p + q) * k..(pi * p + q + 1) * k];
                for (kk, &v) in src.iter().enumerate() {
                    panel[kk * p + q] = v;
                }
            }
        });
    }

    /// Vectors of columns per tile (with 4 rows: 16 accumulators of 32 AVX-512 registers, 8
    /// of 16 otherwise).
    fn vectors(lanes: usize) -> usize {
        if lanes == 16 { 4 } else { 2 }
    }

    /// `y = x · B (+ bias)` for `x` `[m, k]` row-major: `[m, n]`; each sum in order of the
    /// inner index from zero, the bias added last. Parallel over fixed blocks of rows.
    pub(crate) fn apply(&self, x: &[f32], bias: Option<&[f32]>) -> Vec<f32> {
        let m = x.len().checked_div(self.k).unwrap_or(0);
        let mut y = vec![0f32; m * self.n];
        self.apply_into(x, bias, &mut y);
        y
    }

    /// As [`Dense::apply`], into `y` (`[m, n]`; every value overwritten).
    ///
    /// # Panics
    /// When `y` is not `m × n` long.
    pub(crate) fn apply_into(&self, x: &[f32], bias: Option<&[f32]>, y: &mut [f32]) {
        self.apply_scratch(x, bias, y, &mut Vec::new());
    }

    /// As [`Dense::apply_into`], with `t` as the scratch of the panel-parallel products (kept
    /// by the caller, so that repeated products allocate nothing).
    ///
    /// # Panics
    /// When `y` is not `m × n` long.
    pub(crate) fn apply_scratch(&self, x: &[f32], bias: Option<&[f32]>, y: &mut [f32], t: &mut Vec<f32>) {
        const ROWS: usize = 16;
        let (k, n) = (self.k, self.n);
        let m = x.len().checked_div(k).unwrap_or(0);
        assert_eq!(y.len(), m * n, "product: {} values for {m} × {n}", y.len());
        if n == 0 || m == 0 {
            return;
        }
        let np = n.div_ceil(self.p);
        if m <= PANEL_PARALLEL_ROWS && np >= 4 {
            // Few rows, many columns: in parallel over the panels, so that each weight is read
            // once (the rows stay in cache), into a panel-major buffer, then into the rows.
            let p = self.p;
            t.resize(np * m * p, 0.0);
            t.par_chunks_mut(m * p).enumerate().for_each(|(pi, tb)| {
                self.isa.arch.dispatch(DenseOp { d: self, x, y: tb, panels: pi..pi + 1, stride: p, col0: pi * p });
            });
            y.par_chunks_mut(n).enumerate().for_each(|(r, row)| {
                for (pi, chunk) in row.chunks_mut(p).enumerate() {
                    chunk.copy_from_slice(&t[(pi * m + r) * p..(pi * m + r) * p + chunk.len()]);
                }
                if let Some(bias) = bias {
                    row.iter_mut().zip(bias).for_each(|(v, b)| *v += b);
                }
            });
            return;
        }
        y.par_chunks_mut(ROWS * n).zip(x.par_chunks(ROWS * k)).for_each(|(yb, xb)| {
            self.isa.arch.dispatch(DenseOp { d: self, x: xb, y: &mut yb[..], panels: 0..np, stride: n, col0: 0 });
            if let Some(bias) = bias {
                for row in yb.chunks_exact_mut(n) {
                    row.iter_mut().zip(bias).for_each(|(v, b)| *v += b);
                }
            }
        });
    }
}

/// Products of at most this many rows run in parallel over the panels of columns.
const PANEL_PARALLEL_ROWS: usize = 256;

/// Rows `x` through panels `panels` of a [`Dense`] into `y`: row `r`, column `j` of the
/// product at `y[r · stride + j − col0]`.
struct DenseOp<'a> {
    d: &'a Dense,
    x: &'a [f32],
    y: &'a mut [f32],
    panels: std::ops::Range<usize>,
    stride: usize,
    col0: usize,
}

impl WithSimd for DenseOp<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        if S::F32_LANES == 16 { dense_rows::<S, 4>(simd, self) } else { dense_rows::<S, 2>(simd, self) }
    }
}

/// Panel after panel (each then stays in cache), blocks of 4 rows then single rows.
#[inline(always)]
fn dense_rows<S: Simd, const NV: usize>(simd: S, mut op: DenseOp<'_>) {
    let (d, p, st) = (op.d, op.d.p, op.stride);
    debug_assert_eq!(p, NV * S::F32_LANES);
    let m = op.y.len() / st;
    for pi in op.panels.clone() {
        let panel = &d.panels[pi * d.k * p..(pi + 1) * d.k * p];
        let cols = (pi * p - op.col0, p.min(d.n - pi * p));
        let mut r = 0;
        while r + 4 <= m {
            dense_rows_at::<S, 4, NV>(simd, &mut op, panel, r, cols);
            r += 4;
        }
        while r < m {
            dense_rows_at::<S, 1, NV>(simd, &mut op, panel, r, cols);
            r += 1;
        }
    }
}

/// Rows `r .. r + MR` of `op` through one panel, `(j0, cols)` its columns ([`dense_tile`]). A
/// function, not a closure: a closure would not be compiled with the dispatched instruction set.
#[inline(always)]
fn dense_rows_at<S: Simd, const MR: usize, const NV: usize>(
    simd: S,
    op: &mut DenseOp<'_>,
    panel: &[f32],
    r: usize,
    (j0, cols): (usize, usize),
) {
    let (k, st) = (op.d.k, op.stride);
    dense_tile::<S, MR, NV>(simd, &op.x[r * k..(r + MR) * k], k, panel, &mut op.y[r * st..(r + MR) * st], st, j0, cols);
}

/// `MR` rows × one panel (`NV` vectors), in `MR·NV` registers; `cols` of the panel's
/// columns (from `j0`) are stored.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn dense_tile<S: Simd, const MR: usize, const NV: usize>(
    simd: S,
    x: &[f32],
    k: usize,
    panel: &[f32],
    y: &mut [f32],
    n: usize,
    j0: usize,
    cols: usize,
) {
    let l = S::F32_LANES;
    let mut a = [[simd.splat_f32s(0.0); NV]; MR];
    let xr: [&[f32]; MR] = std::array::from_fn(|r| &x[r * k..(r + 1) * k]);
    for (kk, brow) in panel.chunks_exact(NV * l).enumerate() {
        let bv: [S::f32s; NV] = std::array::from_fn(|v| load::<S>(&brow[v * l..(v + 1) * l]));
        for (ar, xr) in a.iter_mut().zip(&xr) {
            let xv = simd.splat_f32s(xr[kk]);
            for (av, &bvv) in ar.iter_mut().zip(&bv) {
                *av = simd.mul_add_f32s(xv, bvv, *av);
            }
        }
    }
    for (r, ar) in a.iter().enumerate() {
        let flat: &[f32] = pulp::bytemuck::cast_slice(&ar[..]);
        y[r * n + j0..r * n + j0 + cols].copy_from_slice(&flat[..cols]);
    }
}

/// Reproducible test values in `[-scale, scale)` (xorshift64 from `seed`).
#[cfg(test)]
pub(crate) fn test_values(n: usize, seed: u64, scale: f32) -> Vec<f32> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            scale * ((s >> 40) as f32 / (1u64 << 23) as f32 - 1.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(n: usize, seed: u64) -> Vec<f32> {
        test_values(n, seed, 1.0)
    }

    fn isas() -> Vec<Isa> {
        Isa::all_for_tests()
    }

    /// Every kernel against a naive f64 correlation, and every instruction set against the
    /// portable one bit for bit, on odd channel counts and sides (the last two in several
    /// bands of rows, the last band of 40 a single row).
    #[test]
    fn conv3_matches_naive_correlation() {
        for &(cin, cout, n) in
            &[(3, 8, 5), (2, 5, 1), (4, 12, 9), (8, 16, 8), (5, 4, 17), (16, 32, 4), (3, 5, 40), (2, 4, 64)]
        {
            let w = values(cout * cin * 9, (cin * 100 + cout) as u64);
            let img = values(cin * n * n, n as u64 + 7);
            let wp = n + 2;
            let mut x = vec![0f32; padded_len(cin, n)];
            for c in 0..cin {
                for y in 0..n {
                    for xx in 0..n {
                        x[c * wp * wp + (y + 1) * wp + xx + 1] = img[(c * n + y) * n + xx];
                    }
                }
            }
            let mut want = vec![0f64; cout * n * n];
            for o in 0..cout {
                for y in 0..n as isize {
                    for xx in 0..n as isize {
                        let mut s = 0f64;
                        for c in 0..cin {
                            for ky in 0..3isize {
                                for kx in 0..3isize {
                                    let (sy, sx) = (y + ky - 1, xx + kx - 1);
                                    if sy >= 0 && sx >= 0 && sy < n as isize && sx < n as isize {
                                        s += w[((o * cin + c) * 3 + ky as usize) * 3 + kx as usize] as f64
                                            * img[(c * n + sy as usize) * n + sx as usize] as f64;
                                    }
                                }
                            }
                        }
                        want[(o * n + y as usize) * n + xx as usize] = s;
                    }
                }
            }
            let mut first: Option<Vec<f32>> = None;
            for isa in isas() {
                let conv = Conv3::new(&w, cout, cin, isa);
                let mut got = vec![f32::NAN; cout * n * n];
                let mut seen = 0;
                conv.run(&x, n, &mut Vec::new(), |o, y, row| {
                    got[(o * n + y) * n..(o * n + y + 1) * n].copy_from_slice(row);
                    seen += 1;
                });
                assert_eq!(seen, cout * n, "{isa:?}: one call per channel and row");
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        (*g as f64 - w).abs() < 1e-5 * (1.0 + w.abs()),
                        "{isa:?} {cin}→{cout}@{n} [{i}]: {g} vs {w}"
                    );
                }
                match &first {
                    None => first = Some(got),
                    Some(f) => assert_eq!(f, &got, "{isa:?}: not the same bits as the other instruction set"),
                }
            }
        }
    }

    #[test]
    fn matmul_matches_naive_product() {
        for &(m, k, n) in
            &[(1, 3, 5), (5, 7, 16), (9, 12, 70), (4, 33, 128), (6, 128, 3), (2, 4, 0), (300, 5, 70), (7, 9, 300)]
        {
            let x = values(m * k, 3 + m as u64);
            let b = values(k * n, 5 + n as u64);
            let bias = values(n, 9);
            let mut first: Option<Vec<f32>> = None;
            for isa in isas() {
                let y = Dense::new(&b, k, n, isa).apply(&x, Some(&bias));
                // The same product from `Bᵀ`, and repacked in place.
                let bt: Vec<f32> = (0..n * k).map(|i| b[(i % k) * n + i / k]).collect();
                assert_eq!(Dense::new_transposed(&bt, n, k, isa).apply(&x, Some(&bias)), y);
                let mut d = Dense::new(&vec![0.5; k * n], k, n, isa);
                d.repack(&b);
                assert_eq!(d.apply(&x, Some(&bias)), y);
                d.repack_transposed(&bt);
                assert_eq!(d.apply(&x, Some(&bias)), y);
                // Row by row (in parallel over the panels where there are enough): the same bits.
                if k > 0 {
                    let rows: Vec<f32> = x.chunks(k).flat_map(|r| d.apply(r, Some(&bias))).collect();
                    assert_eq!(rows, y, "{isa:?} {m}×{k}×{n}: row by row");
                }
                assert_eq!(y.len(), m * n);
                for r in 0..m {
                    for j in 0..n {
                        let s: f64 =
                            bias[j] as f64 + (0..k).map(|i| x[r * k + i] as f64 * b[i * n + j] as f64).sum::<f64>();
                        let g = y[r * n + j] as f64;
                        assert!((g - s).abs() < 1e-5 * (1.0 + s.abs()), "{isa:?} {m}×{k}×{n} [{r},{j}]: {g} vs {s}");
                    }
                }
                match &first {
                    None => first = Some(y),
                    Some(f) => assert_eq!(f, &y, "{isa:?}: not the same bits as the other instruction set"),
                }
            }
        }
    }
}
