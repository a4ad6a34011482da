//! The pen1 generator's inference (batch 64) and network training step (batch 64) timed by the
//! CPU time of every thread of the process as well as by the wall clock, so that runs on a
//! machine shared with other jobs can still be compared: a thread waiting for a core does not
//! count. The same work as the criterion benches `generator_inference/batch_64` and
//! `generator_training/network_step_batch_64` (`benches/generator.rs`).
//!
//! `cargo run --profile bench -p neural-gen --example gen_speed [-- ITERS [infer|step]]`
//! (default 20 of each, after two warm-up iterations). Linux only (the CPU time is read from
//! `/proc/self/task/*/schedstat`).

use std::time::Instant;

// As in the `maobi` binary and the benches.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use bezier_raster::DatasetSpec;
use brush_model::{BrushProfile, Press};
use neural_gen::bench::DirectTrainer;
use neural_gen::{Arch, Generator, GeneratorConfig};

/// Nanoseconds every thread of this process has run on a CPU.
fn cpu_ns() -> u64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else { return 0 };
    dir.filter_map(|e| e.ok())
        .filter_map(|e| std::fs::read_to_string(e.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next().and_then(|v| v.parse::<u64>().ok()))
        .sum()
}

/// Runs `f` `iters` times after two warm-up calls; prints wall and CPU milliseconds per call.
fn time(what: &str, iters: usize, mut f: impl FnMut()) {
    f();
    f();
    let (c0, t0) = (cpu_ns(), Instant::now());
    for _ in 0..iters {
        f();
    }
    let wall = t0.elapsed().as_secs_f64() * 1e3 / iters as f64;
    let cpu = (cpu_ns() - c0) as f64 / 1e6 / iters as f64;
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let load = load.split_whitespace().next().unwrap_or("?");
    println!("{what}: wall {wall:.2} ms, cpu {cpu:.2} ms per call ({iters} calls, load {load})");
}

fn main() {
    let iters: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let which = std::env::args().nth(2).unwrap_or_default();
    let pen1 = BrushProfile::builtin("pen1").expect("pen1");
    let g = Generator::new(GeneratorConfig::new(pen1.clone(), Arch::default_128()), 1).expect("generator");
    let spec = DatasetSpec::new(pen1, 128, 3);
    let presses: Vec<Press> = (0..64).map(|i| spec.press(i)).collect();
    if which != "step" {
        time("inference batch 64", iters, || {
            std::hint::black_box(g.render(std::hint::black_box(&presses)).expect("render"));
        });
    }
    if which != "infer" {
        let x: Vec<f32> = presses.iter().flat_map(|p| g.config.normalise(p)).collect();
        let y: Vec<f32> = (0..64 * 128 * 128).map(|i| ((i * 7919) % 1000) as f32 / 1000.0).collect();
        let mut net = DirectTrainer::new(&g).expect("trainer");
        time("network step batch 64", iters, || {
            net.step(std::hint::black_box(&x), &y, 1e-4).expect("step");
        });
    }
}
