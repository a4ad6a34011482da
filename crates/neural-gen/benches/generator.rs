//! Generator speed: inference at batch 1 and 64 (direct kernels, and candle's graph for
//! comparison), one training step at batch 64 (the whole `train` step, and the network alone on
//! the direct kernels and through candle's graph; the whole `train` job for 10 steps), next to
//! the analytic renderer; and the
//! machine's peak FP32 rate (a loop of independent fused multiply–adds on every thread), the
//! yardstick `cargo xtask bench` divides by (`cargo bench -p neural-gen --bench generator`).

use bezier_raster::{Bsm, Coverage, DatasetSpec, Rasterizer};
use brush_model::{BrushProfile, Press};
use candle_core::{Device, Tensor};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use neural_gen::bench::{DirectTrainer, NetworkStep};
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};
use pulp::{Simd, WithSimd};
use rayon::prelude::*;
use std::hint::black_box;

// As in the `maobi` binary: an allocator that reuses freed large buffers.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Fused multiply–adds per accumulator and thread in one peak measurement.
const FMA_ITERS: usize = 1 << 22;
/// Independent vector accumulators (enough to hide the FMA latency on two ports).
const FMA_ACC: usize = 12;

/// `FMA_ITERS` rounds of `FMA_ACC` independent vector FMAs; returns the FLOPs done (2 per
/// lane and FMA) and a value that depends on every accumulator.
struct FmaLoop;

impl WithSimd for FmaLoop {
    type Output = (f64, f32);
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> (f64, f32) {
        let a = simd.splat_f32s(0.999_999);
        let b = simd.splat_f32s(1e-7);
        let mut acc = [simd.splat_f32s(1.0); FMA_ACC];
        for (i, v) in acc.iter_mut().enumerate() {
            *v = simd.splat_f32s(1.0 + i as f32);
        }
        for _ in 0..FMA_ITERS {
            for v in acc.iter_mut() {
                *v = simd.mul_add_f32s(*v, a, b);
            }
        }
        let mut s = 0f32;
        for v in &acc {
            let lanes: &[f32] = pulp::bytemuck::cast_slice(std::slice::from_ref(v));
            s += lanes.iter().sum::<f32>();
        }
        ((2 * S::F32_LANES * FMA_ACC * FMA_ITERS) as f64, s)
    }
}

fn bench(c: &mut Criterion) {
    let arch = pulp::Arch::new();
    let threads = rayon::current_num_threads();
    let mut grp = c.benchmark_group("peak_fp32");
    grp.sample_size(10);
    let flops = arch.dispatch(FmaLoop).0 * threads as f64;
    // Criterion's throughput in "elements" = FLOPs: elements/s is FLOP/s.
    grp.throughput(Throughput::Elements(flops as u64));
    grp.bench_function("fma_all_threads", |b| {
        b.iter(|| (0..threads).into_par_iter().map(|_| arch.dispatch(FmaLoop).1).sum::<f32>())
    });
    grp.finish();

    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let g = Generator::new(GeneratorConfig::new(pen1.clone(), Arch::default_128()), 1).unwrap();
    let spec = DatasetSpec::new(pen1, 128, 3);
    let presses: Vec<Press> = (0..64).map(|i| spec.press(i)).collect();
    let mut grp = c.benchmark_group("generator_inference");
    grp.throughput(Throughput::Elements(1));
    grp.bench_function("batch_1", |b| b.iter(|| g.render(black_box(&presses[..1])).unwrap()));
    grp.throughput(Throughput::Elements(64));
    grp.bench_function("batch_64", |b| b.iter(|| g.render(black_box(&presses)).unwrap()));
    // The same batch through candle's graph: what `render` ran on before the direct kernels.
    let x = g.inputs(&presses).unwrap();
    grp.bench_function("batch_64_candle_graph", |b| {
        b.iter(|| g.forward_autograd(black_box(&x)).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap())
    });
    grp.throughput(Throughput::Elements(64));
    grp.bench_function("analytic_64", |b| {
        let mut r = Rasterizer::new();
        let mut img = Coverage::new(128, 128);
        b.iter(|| {
            for i in 0..64u64 {
                let s = spec.sample(i).unwrap();
                spec.render(&s, &Bsm, &mut r, &mut img);
            }
        })
    });
    grp.finish();
    let mut grp = c.benchmark_group("generator_training");
    grp.sample_size(10);
    grp.bench_function("step_batch_64", |b| {
        let mut g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::default_128()), 1)
                .unwrap();
        let opts = TrainOptions { steps: 1, batch: 64, val_every: 1_000_000, ..TrainOptions::default() };
        b.iter(|| neural_gen::train(&mut g, &opts, |_| {}).unwrap())
    });
    // The whole job of `maobi train` for 10 steps (its data rendered by bezier-raster, the
    // network on the direct kernels, one validation at the end): the figure, per step, that
    // benches/train_torch.py (PyTorch, its targets drawn by OpenCV) is compared with.
    grp.bench_function("train_job_10_steps_batch_64", |b| {
        let mut g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::default_128()), 1)
                .unwrap();
        let opts = TrainOptions { steps: 10, batch: 64, val_every: 1_000_000, ..TrainOptions::default() };
        b.iter(|| neural_gen::train(&mut g, &opts, |_| {}).unwrap())
    });
    // The network alone (as benches/gen_vjp_torch.py's training step): fixed inputs and
    // targets, forward, MSE, backward, AdamW; on the direct kernels (what `train` runs) and
    // through candle's graph (what it ran before).
    let target = Tensor::rand(0f32, 1f32, (64, 1, 128, 128), &Device::Cpu).unwrap();
    grp.bench_function("network_step_batch_64", |b| {
        let g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::default_128()), 1)
            .unwrap();
        let x: Vec<f32> = presses.iter().flat_map(|p| g.config.normalise(p)).collect();
        let y: Vec<f32> = target.flatten_all().unwrap().to_vec1().unwrap();
        let mut net = DirectTrainer::new(&g).unwrap();
        b.iter(|| net.step(black_box(&x), &y, 1e-4).unwrap())
    });
    grp.bench_function("network_step_batch_64_candle_graph", |b| {
        let mut g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::default_128()), 1)
                .unwrap();
        let x = g.inputs(&presses).unwrap();
        let mut net = NetworkStep::new(&g, 1e-4).unwrap();
        b.iter(|| net.step(&mut g, black_box(&x), &target, 1e-4).unwrap())
    });
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
