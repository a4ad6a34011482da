//! SSIM and CSIM speed at 128² and 512² (`cargo bench -p stroke-metrics`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use stroke_metrics::{GrayRef, SsimWorkspace, csim};

fn image(n: usize, phase: f32) -> Vec<f32> {
    (0..n * n).map(|i| (((i % n) as f32 * 0.05 + phase).sin() * ((i / n) as f32 * 0.03).cos()).abs()).collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("ssim");
    for n in [128usize, 512] {
        let (a, b) = (image(n, 0.0), image(n, 0.3));
        let mut ws = SsimWorkspace::new();
        g.bench_with_input(BenchmarkId::from_parameter(format!("{n}x{n}")), &n, |bench, &n| {
            bench.iter(|| ws.ssim(GrayRef::new(black_box(&a), n, n).unwrap(), GrayRef::new(&b, n, n).unwrap()).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("csim");
    for n in [128usize, 512] {
        let (a, b) = (image(n, 0.0), image(n, 0.3));
        g.bench_with_input(BenchmarkId::from_parameter(format!("{n}x{n}")), &n, |bench, &n| {
            bench.iter(|| csim(GrayRef::new(black_box(&a), n, n).unwrap(), GrayRef::new(&b, n, n).unwrap()).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
