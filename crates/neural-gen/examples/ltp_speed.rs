//! Where a training step of the LearningToPaint-sized network goes, with candle's convolution
//! and AdamW, and with maobi's (direct convolution, fused AdamW): forward, backward and optimiser times at batch 64.
//!
//! `cargo run --release -p neural-gen --example ltp_speed [-- STEPS [maobi|candle]]` (default 5
//! steps with each, after one warm-up step). The criterion numbers are in `benches/ltp.rs`.

use std::time::Instant;

// Big tensors come and go every step: an allocator that keeps freed memory avoids a page
// fault per page per tensor (glibc returns allocations above its mmap threshold to the OS).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use candle_core::{Device, Tensor};
use neural_gen::bench::{Ltp, LtpKernels as Kernels};

fn main() -> candle_core::Result<()> {
    let steps: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let x = Tensor::rand(0f32, 1f32, (64, 3), &Device::Cpu)?;
    let target = Tensor::rand(0f32, 1f32, (64, 1, 128, 128), &Device::Cpu)?;
    let which = match std::env::args().nth(2).as_deref() {
        Some("maobi") => vec![Kernels::Maobi],
        Some("candle") => vec![Kernels::Candle],
        _ => vec![Kernels::Maobi, Kernels::Candle],
    };
    for kernels in which {
        let mut net = Ltp::new(kernels, 1e-4)?;
        net.step(&x, &target)?;
        let (mut fwd, mut bwd, mut opt) = (0.0, 0.0, 0.0);
        for _ in 0..steps {
            let t0 = Instant::now();
            let loss = candle_nn::loss::mse(&net.forward(&x)?, &target)?;
            let t1 = Instant::now();
            let grads = loss.backward()?;
            let t2 = Instant::now();
            net.update(&grads)?;
            let t3 = Instant::now();
            fwd += (t1 - t0).as_secs_f64();
            bwd += (t2 - t1).as_secs_f64();
            opt += (t3 - t2).as_secs_f64();
        }
        let n = steps as f64;
        println!(
            "{kernels:?}: {} parameters; step {:.3} s = forward {:.3} + backward {:.3} + Adam {:.3}",
            net.parameters(),
            (fwd + bwd + opt) / n,
            fwd / n,
            bwd / n,
            opt / n
        );
    }
    Ok(())
}
