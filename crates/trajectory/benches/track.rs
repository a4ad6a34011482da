//! Track extraction speed per character (`cargo bench -p trajectory`).

use brush_model::BrushProfile;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use trajectory::{
    CharBox, DEFAULT_SPACING_MM, Method, Sizing, TrackOptions, build_track, centre_lines, embedded_glyph,
};

fn bench(c: &mut Criterion) {
    let g = embedded_glyph('永').unwrap();
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    c.bench_function("centre_lines_medians_yong", |b| {
        b.iter(|| centre_lines(black_box(&g), Method::Medians, trajectory::DEFAULT_ANALYSIS_PX).unwrap())
    });
    c.bench_function("centre_lines_skeleton_yong", |b| {
        b.iter(|| centre_lines(black_box(&g), Method::Skeleton, trajectory::DEFAULT_ANALYSIS_PX).unwrap())
    });
    let paths = centre_lines(&g, Method::Medians, trajectory::DEFAULT_ANALYSIS_PX).unwrap();
    let opts = TrackOptions {
        char_box: CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: trajectory::auto_char_mm(&paths, &pen1, 0.0) },
        spacing_mm: DEFAULT_SPACING_MM,
        alpha_rad: 0.0,
        sizing: Sizing::Brush,
    };
    c.bench_function("build_track_yong", |b| b.iter(|| build_track(black_box(&paths), &pen1, &opts).unwrap()));
}

criterion_group!(benches, bench);
criterion_main!(benches);
