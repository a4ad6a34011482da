//! The LearningToPaint-sized network (`neural_gen::bench::Ltp`): one Adam training step at batch 64 and
//! inference at batch 1 and 64, with stock candle kernels and with maobi's (direct convolution
//! with fused bias/ReLU, pixel shuffle, fused AdamW), and on the direct kernels
//! (`neural_gen::bench::DirectTrainer`: packed products, register-tiled correlations, no candle
//! graph).
//! `cargo bench -p neural-gen --bench ltp`;
//! the PyTorch reference is `python3 crates/neural-gen/benches/ltp_torch.py`.

use candle_core::{Device, Tensor};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use neural_gen::bench::{DirectTrainer, Ltp, LtpKernels as Kernels};
use std::hint::black_box;

// As in the `maobi` binary: an allocator that reuses freed large buffers.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    let dev = Device::Cpu;
    let x = Tensor::rand(0f32, 1f32, (64, 3), &dev).unwrap();
    let target = Tensor::rand(0f32, 1f32, (64, 1, 128, 128), &dev).unwrap();
    let mut grp = c.benchmark_group("ltp_training");
    grp.sample_size(10);
    for (name, kernels) in [("step_batch_64_maobi", Kernels::Maobi), ("step_batch_64_candle", Kernels::Candle)] {
        let mut net = Ltp::new(kernels, 1e-4).unwrap();
        grp.bench_function(name, |b| b.iter(|| net.step(black_box(&x), &target).unwrap()));
    }
    let xv: Vec<f32> = x.flatten_all().unwrap().to_vec1().unwrap();
    let yv: Vec<f32> = target.flatten_all().unwrap().to_vec1().unwrap();
    let ltp = Ltp::new(Kernels::Candle, 1e-4).unwrap();
    let mut direct = DirectTrainer::from_varmap(&Ltp::spec(), &ltp.varmap).unwrap();
    grp.bench_function("step_batch_64_direct", |b| b.iter(|| direct.step(black_box(&xv), &yv, 1e-4).unwrap()));
    grp.finish();
    let mut grp = c.benchmark_group("ltp_inference");
    grp.throughput(Throughput::Elements(1));
    grp.bench_function("batch_1_direct", |b| b.iter(|| direct.images(black_box(&xv[..3])).unwrap()));
    grp.throughput(Throughput::Elements(64));
    grp.bench_function("batch_64_direct", |b| b.iter(|| direct.images(black_box(&xv)).unwrap()));
    for (name, kernels) in [("maobi", Kernels::Maobi), ("candle", Kernels::Candle)] {
        let net = Ltp::new(kernels, 1e-4).unwrap();
        grp.throughput(Throughput::Elements(1));
        grp.bench_function(format!("batch_1_{name}"), |b| {
            b.iter(|| net.forward(black_box(&x.narrow(0, 0, 1).unwrap())).unwrap())
        });
        grp.throughput(Throughput::Elements(64));
        grp.bench_function(format!("batch_64_{name}"), |b| b.iter(|| net.forward(black_box(&x)).unwrap()));
    }
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
