//! hanzi-writer-data JSON → glyph → centre lines: no panic, no hang; accepted medians within
//! the coordinate window and point cap.
#![no_main]

use libfuzzer_sys::fuzz_target;
use trajectory::{GlyphSource, limits, parse_hanzi_json};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(g) = parse_hanzi_json('永', text, GlyphSource::Embedded, "fuzz.json") else { return };
    for m in g.medians.as_ref().expect("hanzi data has medians") {
        assert!(m.len() <= limits::MAX_MEDIAN_POINTS);
        for p in m {
            assert!(p.x.abs() <= 4096.0 && p.y.abs() <= 4096.0);
        }
    }
    let _ = trajectory::centre_lines(&g, trajectory::Method::Medians, 64);
});
