//! One character end to end: glyph → centre lines → track → 512² render → reference → scores
//! (`cargo bench -p maobi`).

use brush_model::BrushProfile;
use criterion::{Criterion, criterion_group, criterion_main};
use maobi::pipeline::{WriteOptions, prepare, write_char};
use std::hint::black_box;
use trajectory::{CharBox, Method, glyph};

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let opts = WriteOptions { free_widths: false, ..WriteOptions::default() };
    for (name, method) in [("write_yong_medians_512", Method::Medians), ("write_yong_skeleton_512", Method::Skeleton)] {
        c.bench_function(name, |b| {
            b.iter(|| {
                let p = prepare(glyph::embedded(black_box('永')).unwrap(), Some(method)).unwrap();
                let mm = trajectory::auto_char_mm(&p.paths, &pen1, 0.0);
                write_char(&p, &pen1, CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: mm }, &opts).unwrap()
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
