//! One stroke's SVG path (the `strokes` strings of hanzi-writer-data) with a fixed median:
//! no panic; an accepted outline renders at a small size in bounded time.
#![no_main]

use libfuzzer_sys::fuzz_target;
use trajectory::{GlyphSource, parse_hanzi_json};

fuzz_target!(|data: &[u8]| {
    let Ok(path) = std::str::from_utf8(data) else { return };
    let doc = serde_json::json!({"strokes": [path], "medians": [[[100, 400], [900, 400]]]}).to_string();
    let Ok(g) = parse_hanzi_json('一', &doc, GlyphSource::Embedded, "fuzz.json") else { return };
    let img = trajectory::render_glyph(&g, 64);
    assert!(img.data().iter().all(|v| v.is_finite()));
});
