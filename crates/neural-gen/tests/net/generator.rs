//! The generator: training moves the loss, determinism, checkpoints, gradients.

use brush_model::{BrushProfile, Press};
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};

fn tiny(seed: u64) -> Generator {
    Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::tiny_32()), seed).unwrap()
}

fn weights(g: &Generator) -> Vec<f32> {
    g.weights().unwrap().values().flat_map(|t| t.flatten_all().unwrap().to_vec1::<f32>().unwrap()).collect()
}

/// The error and its causes, as the CLI prints them.
fn chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        out.push_str(": ");
        out.push_str(&c.to_string());
        cur = c.source();
    }
    out
}

fn opts(steps: usize) -> TrainOptions {
    TrainOptions { steps, batch: 16, lr: 3e-3, seed: 3, val_every: 10, patience: 100, checkpoint: None }
}

#[test]
fn training_lowers_the_loss_and_changes_the_weights() {
    let mut g = tiny(7);
    let before = weights(&g);
    let r = neural_gen::train(&mut g, &opts(60), |_| {}).unwrap();
    let first = r.history[..5].iter().map(|p| p.train_mse).sum::<f64>() / 5.0;
    let last = r.history[r.history.len() - 5..].iter().map(|p| p.train_mse).sum::<f64>() / 5.0;
    assert!(last < 0.7 * first, "loss {first} → {last}");
    let vals: Vec<f64> = r.history.iter().filter_map(|p| p.val_mse).collect();
    assert!(vals.last().unwrap() < &vals[0], "{vals:?}");
    let after = weights(&g);
    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    assert!(changed > before.len() / 2, "{changed} of {} weights changed", before.len());
}

#[test]
fn training_is_deterministic_for_a_seed() {
    let (mut a, mut b) = (tiny(5), tiny(5));
    let ra = neural_gen::train(&mut a, &opts(8), |_| {}).unwrap();
    let rb = neural_gen::train(&mut b, &opts(8), |_| {}).unwrap();
    let la: Vec<f64> = ra.history.iter().map(|p| p.train_mse).collect();
    let lb: Vec<f64> = rb.history.iter().map(|p| p.train_mse).collect();
    assert_eq!(la, lb);
    assert_eq!(weights(&a), weights(&b));
    assert_ne!(weights(&tiny(5)), weights(&tiny(6)));
}

#[test]
fn checkpoints_round_trip_and_mismatches_are_refused() {
    let dir = std::env::temp_dir().join(format!("neural-gen-{}", std::process::id()));
    let p = dir.join("g.safetensors");
    let g = tiny(9);
    g.save(&p).unwrap();
    let back = Generator::load(&p).unwrap();
    assert_eq!(weights(&g), weights(&back));
    let press = Press::from_degrees(15.0, 5.0, 2.0);
    assert_eq!(g.render(&[press]).unwrap()[0], back.render(&[press]).unwrap()[0]);
    // A config whose architecture does not match the weights.
    let cfg_path = dir.join("g.json");
    let good = std::fs::read_to_string(&cfg_path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
    v["arch"]["hidden"] = serde_json::json!([48]);
    std::fs::write(&cfg_path, v.to_string()).unwrap();
    let e = Generator::load(&p).err().unwrap();
    assert!(
        matches!(&e, neural_gen::NeuralGenError::Config { problem: neural_gen::ConfigError::TensorShape { .. }, .. }),
        "{e:?}"
    );
    let e = chain(&e);
    assert!(e.contains("g.safetensors") && e.contains("shape"), "{e}");
    // A size that does not match the architecture.
    let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
    v["size"] = serde_json::json!(128);
    std::fs::write(&cfg_path, v.to_string()).unwrap();
    assert!(chain(&Generator::load(&p).err().unwrap()).contains("does not match"));
    // An inconsistent architecture keeps its typed cause.
    let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
    v["arch"]["stages"][1][0] = serde_json::json!(5);
    std::fs::write(&cfg_path, v.to_string()).unwrap();
    let e = Generator::load(&p).err().unwrap();
    let arch = std::error::Error::source(&e)
        .and_then(|c| c.source())
        .and_then(|a| a.downcast_ref::<neural_gen::ArchError>())
        .cloned();
    assert_eq!(arch, Some(neural_gen::ArchError::StageInput { stage: 2, takes: 5, gets: 4 }), "{}", chain(&e));
    // Corrupted weights.
    std::fs::write(&cfg_path, &good).unwrap();
    std::fs::write(&p, b"garbage").unwrap();
    assert!(chain(&Generator::load(&p).err().unwrap()).contains("safetensors"));
    // Missing config.
    std::fs::remove_file(&cfg_path).unwrap();
    assert!(Generator::load(&p).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn gradients_match_finite_differences() {
    let mut g = tiny(11);
    neural_gen::train(&mut g, &opts(20), |_| {}).unwrap();
    let s = g.config.size as usize;
    // A fixed, uneven upstream gradient: L = Σ w · image.
    let w: Vec<f32> = (0..s * s).map(|i| ((i * 7919) % 101) as f32 / 101.0 - 0.3).collect();
    let loss = |p: &Press| -> f64 {
        g.render(&[*p]).unwrap()[0].data().iter().zip(&w).map(|(a, b)| (*a as f64) * (*b as f64)).sum()
    };
    let p = Press::from_degrees(15.0, 4.0, 2.0);
    let (img, grad) = g.image_and_vjp(&p, &w).unwrap();
    for (a, b) in img.data().iter().zip(g.render(&[p]).unwrap()[0].data()) {
        assert!((a - b).abs() < 1e-5, "candle {a} vs direct {b}");
    }
    let steps = [1e-2, 1e-3, 1e-3];
    for k in 0..3 {
        let mut a = p;
        let mut b = p;
        match k {
            0 => {
                a.h_mm += steps[0];
                b.h_mm -= steps[0];
            }
            1 => {
                a.alpha_rad += steps[1];
                b.alpha_rad -= steps[1];
            }
            _ => {
                a.beta_rad += steps[2];
                b.beta_rad -= steps[2];
            }
        }
        let fd = (loss(&a) - loss(&b)) / (2.0 * steps[k]);
        let tol = 0.02 * fd.abs().max(grad[k].abs()) + 1e-3;
        assert!((fd - grad[k]).abs() < tol, "d/d{k}: autodiff {} vs finite difference {fd}", grad[k]);
    }
    assert!(g.image_and_vjp(&p, &w[..10]).is_err());
}

/// Presses spread over pen1's calibrated ranges.
fn spread(n: usize) -> Vec<Press> {
    (0..n)
        .map(|i| {
            let f = i as f64 / n as f64;
            Press::from_degrees(11.0 + 9.0 * f, 10.0 * ((7 * i) % n) as f64 / n as f64, 5.0 * f)
        })
        .collect()
}

/// `render` and `forward` (direct kernels) against candle's graph (`forward_autograd`) on the
/// same inputs: equal within float rounding; and the same bits whatever the batch split and
/// the thread count.
fn assert_direct_matches_candle(g: &Generator, presses: &[Press], what: &str) {
    let s = g.config.size as usize;
    let x = g.inputs(presses).unwrap();
    let want = g.forward_autograd(&x).unwrap();
    assert_eq!(want.dims(), &[presses.len(), 1, s, s]);
    let want: Vec<f32> = want.flatten_all().unwrap().to_vec1().unwrap();
    let got: Vec<f32> = g.forward(&x).unwrap().flatten_all().unwrap().to_vec1().unwrap();
    let imgs = g.render(presses).unwrap();
    let rendered: Vec<f32> = imgs.iter().flat_map(|c| c.data().iter().copied()).collect();
    assert_eq!(got, rendered, "{what}: forward and render differ");
    let mut worst = 0f32;
    for (a, b) in got.iter().zip(&want) {
        worst = worst.max((a - b).abs());
    }
    assert!(worst < 2e-5, "{what}: direct vs candle differ by {worst}");
    // Not a constant image: the comparison has something to compare.
    let (lo, hi) = want.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(hi - lo > 0.1, "{what}: images span {lo}..{hi}");
    // Batch by batch and on one or two threads: the same bits.
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let split: Vec<f32> = pool
            .install(|| presses.chunks(3).flat_map(|c| g.render(c).unwrap()).flat_map(|c| c.data().to_vec()).collect());
        assert_eq!(split, got, "{what}: {threads} thread(s), batches of 3");
    }
    assert!(g.forward(&x.reshape((presses.len() * 3,)).unwrap()).is_err());
}

#[test]
fn inference_on_the_direct_kernels_matches_candle_for_the_shipped_generator() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/pen1.safetensors");
    let g = Generator::load(std::path::Path::new(dir)).unwrap();
    assert_eq!(g.config.arch, Arch::default_128());
    assert_direct_matches_candle(&g, &spread(7), "pen1");
}

#[test]
fn inference_on_the_direct_kernels_matches_candle_for_an_odd_architecture() {
    // Odd widths, a 3² seed, channel counts no register block divides, a 24² output.
    let arch = Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] };
    let mut g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 4).unwrap();
    // Trained a few steps so that the weights are not just their initialisation; the cached
    // kernels follow the new weights.
    let before = g.render(&spread(2)).unwrap();
    neural_gen::train(&mut g, &TrainOptions { steps: 5, batch: 8, val_every: 100, ..TrainOptions::default() }, |_| {})
        .unwrap();
    assert_ne!(before, g.render(&spread(2)).unwrap(), "the kernels did not follow training");
    assert_direct_matches_candle(&g, &spread(9), "odd");
}
