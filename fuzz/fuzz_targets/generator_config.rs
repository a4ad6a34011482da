//! The generator's config JSON with the committed pen1 weights: architecture and profile
//! bounds are checked before anything is allocated; no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

static WEIGHTS: &[u8] = include_bytes!("../../crates/neural-gen/data/pen1.safetensors");

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(g) = neural_gen::Generator::from_bytes(WEIGHTS, text, "pen1.safetensors", "fuzz.json") {
        assert!(g.config.arch.parameter_count() <= 50_000_000);
    }
});
