//! Generator speed: inference at batch 1 and 64, one training step at batch 64, next to the
//! analytic renderer (`cargo bench -p neural-gen`).

use bezier_raster::{Bsm, Coverage, DatasetSpec, Rasterizer};
use brush_model::{BrushProfile, Press};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};
use std::hint::black_box;

// As in the `maobi` binary: an allocator that reuses freed large buffers.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let g = Generator::new(GeneratorConfig::new(pen1.clone(), Arch::default_128()), 1).unwrap();
    let spec = DatasetSpec::new(pen1, 128, 3);
    let presses: Vec<Press> = (0..64).map(|i| spec.press(i)).collect();
    let mut grp = c.benchmark_group("generator_inference");
    grp.throughput(Throughput::Elements(1));
    grp.bench_function("batch_1", |b| b.iter(|| g.render(black_box(&presses[..1])).unwrap()));
    grp.throughput(Throughput::Elements(64));
    grp.bench_function("batch_64", |b| b.iter(|| g.render(black_box(&presses)).unwrap()));
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
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
