//! Refining one character's built track at the default settings (`cargo bench -p pipeline
//! --bench refine`): the track `maobi write` builds, refined against its glyph.

use brush_model::BrushProfile;
use criterion::{Criterion, criterion_group, criterion_main};
use pipeline::{BoxRule, WriteOptions, prepare, refine_target, write_placed};
use track_refine::{RefineOptions, refine};
use trajectory::{Method, embedded_glyph};

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let opts = RefineOptions::default();
    let plan = WriteOptions { size: 64, free_widths: false, execute: false, ..WriteOptions::default() };
    let mut group = c.benchmark_group("refine");
    group.sample_size(10);
    for ch in ['永', '字'] {
        let p = prepare(embedded_glyph(ch).unwrap(), Some(Method::Medians)).unwrap();
        let built = write_placed(&p, &pen1, &plan, BoxRule::Auto).unwrap();
        let target = refine_target(&p.glyph, &built.char_box, opts.analysis_px).unwrap();
        group.bench_function(format!("{ch} default"), |b| {
            b.iter(|| refine(&built.track, &pen1, &target, &opts).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
