//! The generator: training moves the loss, determinism, checkpoints, gradients.

use brush_model::{BrushProfile, Press};
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};

fn tiny(seed: u64) -> Generator {
    Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::tiny_32()), seed).unwrap()
}

fn weights(g: &Generator) -> Vec<f32> {
    let data = g.varmap.data().lock().unwrap();
    let mut names: Vec<&String> = data.keys().collect();
    names.sort();
    names.iter().flat_map(|n| data[*n].as_tensor().flatten_all().unwrap().to_vec1::<f32>().unwrap()).collect()
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
    let e = Generator::load(&p).err().unwrap().to_string();
    assert!(e.contains("g.safetensors") && e.contains("shape"), "{e}");
    // A size that does not match the architecture.
    let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
    v["size"] = serde_json::json!(128);
    std::fs::write(&cfg_path, v.to_string()).unwrap();
    assert!(Generator::load(&p).err().unwrap().to_string().contains("does not match"));
    // Corrupted weights.
    std::fs::write(&cfg_path, &good).unwrap();
    std::fs::write(&p, b"garbage").unwrap();
    assert!(Generator::load(&p).err().unwrap().to_string().contains("safetensors"));
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
    assert_eq!(img, g.render(&[p]).unwrap()[0]);
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
