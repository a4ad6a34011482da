//! One character end to end: glyph → centre lines → track → 512² render → reference → scores
//! (`cargo bench -p pipeline`).

use brush_model::BrushProfile;
use criterion::{Criterion, criterion_group, criterion_main};
use pipeline::{BoxRule, WriteOptions, prepare, write_placed};
use std::hint::black_box;
use trajectory::{Method, embedded_glyph};

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let opts = WriteOptions { free_widths: false, ..WriteOptions::default() };
    for (name, method) in [("write_yong_medians_512", Method::Medians), ("write_yong_skeleton_512", Method::Skeleton)] {
        c.bench_function(name, |b| {
            b.iter(|| {
                let p = prepare(embedded_glyph(black_box('永')).unwrap(), Some(method)).unwrap();
                write_placed(&p, &pen1, &opts, BoxRule::Auto).unwrap()
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
