//! Refining one character at the default settings (`cargo bench -p track-refine`).

#[path = "../examples/common/mod.rs"]
mod common;

use brush_model::BrushProfile;
use criterion::{Criterion, criterion_group, criterion_main};
use track_refine::{RefineOptions, refine};
use trajectory::{Method, centre_lines, glyph};

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let opts = RefineOptions::default();
    let mut group = c.benchmark_group("refine");
    group.sample_size(10);
    for ch in ['永', '字'] {
        let g = glyph::embedded(ch).unwrap();
        let paths = centre_lines(&g, Method::Medians, 512).unwrap();
        let (track, char_box) = common::built_track(&paths, &pen1, (0.0, 0.0));
        let target = common::target_for(&g, &char_box, opts.analysis_px);
        group.bench_function(format!("{ch} default"), |b| b.iter(|| refine(&track, &pen1, &target, &opts).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
