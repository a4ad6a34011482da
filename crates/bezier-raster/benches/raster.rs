//! Footprint rendering speed (`cargo bench -p bezier-raster`).

use bezier_raster::{Bsm, Compositor, Coverage, DatasetSpec, ModelKind, Rasterizer, Stamp, render_batch};
use brush_model::{BrushProfile, PointMm};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let spec = DatasetSpec::new(BrushProfile::builtin("pen1").unwrap(), 128, 1);
    let samples: Vec<_> = (0..256).map(|i| spec.sample(i).unwrap()).collect();

    let mut g = c.benchmark_group("footprint_128");
    for m in ModelKind::ALL {
        let mut r = Rasterizer::new();
        let mut img = Coverage::new(128, 128);
        let mut i = 0;
        g.bench_function(BenchmarkId::from_parameter(m.name()), |b| {
            b.iter(|| {
                let s = &samples[i % samples.len()];
                i += 1;
                spec.render(black_box(s), m.model(), &mut r, &mut img);
            })
        });
    }
    g.finish();

    let stamps: Vec<Stamp> = samples
        .iter()
        .map(|s| Stamp {
            footprint: s.footprint,
            anchor: spec.canvas.anchor_mm(&s.footprint, s.press.beta_rad),
            beta_rad: s.press.beta_rad,
        })
        .collect();
    let mut g = c.benchmark_group("batch_128");
    g.throughput(Throughput::Elements(stamps.len() as u64));
    g.bench_function("bsm_256", |b| b.iter(|| render_batch(&Bsm, black_box(&stamps), 128, 128, spec.canvas.px_per_mm)));
    g.finish();

    // A character-sized job: 400 stamps along a line into a 512² image.
    let fp = samples[0].footprint;
    let line: Vec<Stamp> = (0..400)
        .map(|i| Stamp {
            footprint: fp,
            anchor: PointMm::new(5.0 + i as f64 * 0.2, 40.0 + (i as f64 * 0.05).sin() * 20.0),
            beta_rad: 0.3,
        })
        .collect();
    c.bench_function("composite_400_stamps_512", |b| {
        b.iter(|| {
            let mut comp = Compositor::new(512, 512, 512.0 / 100.0);
            comp.stamp_all(&Bsm, black_box(&line));
            comp.into_image()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
