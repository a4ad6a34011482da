//! Refining one character at the default settings (`cargo bench -p track-refine`).

use brush_model::{BrushProfile, PointMm};
use criterion::{Criterion, criterion_group, criterion_main};
use track_refine::{RefineOptions, Target, refine};
use trajectory::{CharBox, Method, Sizing, TrackOptions, build_track, centre_lines, glyph, raster::render_glyph};

fn bench(c: &mut Criterion) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let opts = RefineOptions::default();
    let mut group = c.benchmark_group("refine");
    group.sample_size(10);
    for ch in ['永', '字'] {
        let g = glyph::embedded(ch).unwrap();
        let paths = centre_lines(&g, Method::Medians, 512).unwrap();
        let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: trajectory::auto_char_mm(&paths, &pen1, 0.0) };
        let topts = TrackOptions {
            char_box,
            spacing_mm: trajectory::DEFAULT_SPACING_MM,
            alpha_rad: 0.0,
            sizing: Sizing::Brush,
        };
        let track = build_track(&paths, &pen1, &topts).unwrap().track;
        let px = opts.analysis_px;
        let target = Target::new(
            px,
            px,
            render_glyph(&g, px).data().to_vec(),
            PointMm::new(0.0, 0.0),
            char_box.size_mm / px as f64,
        )
        .unwrap();
        group.bench_function(format!("{ch} default"), |b| b.iter(|| refine(&track, &pen1, &target, &opts).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
