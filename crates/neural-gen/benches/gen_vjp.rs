//! Batched forward + VJP with respect to the presses through the committed generator's
//! architecture (`data/pen1.json`), batch 64: the direct, input-gradient-only path
//! ([`neural_gen::InputVjp`]) and candle's autograd; also the forward pass alone and the
//! forward-mode Jacobian (three tangents per image) of a recorded forward pass. The PyTorch
//! reference on the same network and batch is `benches/gen_vjp_torch.py`
//! (`cargo bench -p neural-gen --bench gen_vjp`).

use brush_model::Press;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use neural_gen::{Generator, GeneratorConfig};
use std::hint::black_box;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

const BATCH: usize = 64;

fn bench(c: &mut Criterion) {
    let text = include_str!("../data/pen1.json");
    let cfg: GeneratorConfig = serde_json::from_str(text).unwrap();
    let g = Generator::new(cfg, 1).unwrap();
    let s = g.config.size as usize;
    let presses: Vec<Press> = (0..BATCH)
        .map(|i| {
            let f = i as f64 / BATCH as f64;
            Press::new(11.0 + 9.0 * f, 0.17 * ((7 * i) % BATCH) as f64 / BATCH as f64, 0.08 * f)
        })
        .collect();
    let up: Vec<f32> = (0..BATCH * s * s).map(|i| ((i * 7919) % 101) as f32 / 101.0 - 0.5).collect();
    let net = g.kernels().unwrap();
    let mut grp = c.benchmark_group("generator_vjp");
    grp.throughput(Throughput::Elements(BATCH as u64));
    grp.sample_size(20);
    grp.bench_function("batch_64_direct", |b| {
        b.iter(|| {
            let tape = net.forward(black_box(&presses));
            net.vjp(&tape, black_box(&up)).unwrap()
        })
    });
    grp.bench_function("batch_64_forward_direct", |b| b.iter(|| net.forward(black_box(&presses))));
    let tape = net.forward(&presses);
    grp.bench_function("batch_64_jacobian_direct", |b| b.iter(|| net.jacobian(black_box(&tape))));
    grp.bench_function("batch_64_candle_autograd", |b| {
        b.iter(|| g.images_and_vjps_candle(black_box(&presses), black_box(&up)).unwrap())
    });
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
