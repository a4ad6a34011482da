//! Glyph loading per character (`cargo bench -p trajectory --bench glyph`): the embedded data
//! (one chunk inflated and decoded) against parsing the same character's JSON.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use trajectory::{GlyphSource, embedded_glyph, parse_hanzi_json};

fn bench(c: &mut Criterion) {
    let subset = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/hanzi-subset.jsonl")).unwrap();
    let line = subset.lines().find(|l| l.starts_with("{\"c\":\"永\"")).unwrap();
    c.bench_function("glyph_embedded_yong", |b| b.iter(|| embedded_glyph(black_box('永')).unwrap()));
    c.bench_function("glyph_embedded_long", |b| b.iter(|| embedded_glyph(black_box('龍')).unwrap()));
    c.bench_function("glyph_json_yong", |b| {
        b.iter(|| parse_hanzi_json('永', black_box(line), GlyphSource::Embedded, "bench").unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
