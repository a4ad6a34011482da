//! Image files (PNG/JPEG) as `compare`, `fit-stroke`, `calibrate --images` and
//! `write --image` read them: size caps before decoding, no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("maobi-fuzz-image-{}.png", std::process::id()));
    std::fs::write(&path, data).unwrap();
    if let Ok((w, h)) = bezier_raster::image_header(&path) {
        assert!(w as u64 * h as u64 <= bezier_raster::MAX_LOAD_PIXELS);
    }
    if let Ok(c) = bezier_raster::Coverage::load(&path) {
        assert!(c.data().iter().all(|v| (0.0..=1.0).contains(v)));
    }
    let _ = stroke_fit::load_ink(&path);
    let _ = trajectory::glyph_from_image(&path, '永');
});
