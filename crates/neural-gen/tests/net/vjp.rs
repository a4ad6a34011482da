//! The batched, autograd-free images and VJPs against candle's autograd and finite differences.

use brush_model::{BrushProfile, Press};
use neural_gen::{Arch, Generator, GeneratorConfig, InputVjp};

fn tiny(seed: u64) -> Generator {
    Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::tiny_32()), seed).unwrap()
}

fn presses() -> Vec<Press> {
    vec![
        Press::from_degrees(12.0, 0.0, 0.0),
        Press::from_degrees(15.0, 4.0, 2.0),
        Press::from_degrees(19.0, 9.0, 5.0),
        Press::from_degrees(16.5, 2.5, 1.0),
        Press::from_degrees(11.2, 7.0, 3.5),
    ]
}

fn upstream(n: usize, s: usize) -> Vec<f32> {
    (0..n * s * s).map(|i| ((i * 7919) % 101) as f32 / 101.0 - 0.3).collect()
}

/// The forward-mode Jacobian of `ps` contracted with `up` (images of side `s`) gives the VJPs
/// `grads`, to 1e-3 relative; `what` names the case in a failure. Returns the Jacobian.
fn assert_jacobian_matches_vjp(
    net: &InputVjp,
    ps: &[Press],
    up: &[f32],
    s: usize,
    grads: &[[f64; 3]],
    what: &str,
) -> Vec<f32> {
    let jac = net.jacobian(&net.forward(ps));
    for i in 0..ps.len() {
        for k in 0..3 {
            let col = &jac[(i * 3 + k) * s * s..(i * 3 + k + 1) * s * s];
            let p: f64 = col.iter().zip(&up[i * s * s..(i + 1) * s * s]).map(|(a, b)| *a as f64 * *b as f64).sum();
            let tol = 1e-3 * grads[i][k].abs().max(1.0);
            assert!((p - grads[i][k]).abs() < tol, "{what} press {i} ∂{k}: Jacobian {p} vs VJP {}", grads[i][k]);
        }
    }
    jac
}

#[test]
fn batched_vjps_equal_the_single_press_vjp() {
    let g = tiny(3);
    let s = g.config.size as usize;
    let ps = presses();
    let up = upstream(ps.len(), s);
    let (imgs, grads) = g.images_and_vjps(&ps, &up).unwrap();
    let (imgs_c, grads_c) = g.images_and_vjps_candle(&ps, &up).unwrap();
    let rendered = g.render(&ps).unwrap();
    for (i, p) in ps.iter().enumerate() {
        let (img1, g1) = g.image_and_vjp(p, &up[i * s * s..(i + 1) * s * s]).unwrap();
        for (a, b) in imgs[i].data().iter().zip(img1.data()) {
            assert!((a - b).abs() < 1e-5, "image {i}: {a} vs {b}");
        }
        for (a, b) in imgs_c[i].data().iter().zip(rendered[i].data()) {
            assert!((a - b).abs() < 1e-5);
        }
        for k in 0..3 {
            let tol = 1e-3 * g1[k].abs().max(1.0);
            assert!((grads[i][k] - g1[k]).abs() < tol, "press {i} ∂{k}: batched {} vs single {}", grads[i][k], g1[k]);
            assert!((grads_c[i][k] - g1[k]).abs() < tol, "press {i} ∂{k}: candle batch {} vs {}", grads_c[i][k], g1[k]);
        }
    }
    // Batch size does not change a press's numbers (each image is computed on its own).
    let net = g.kernels().unwrap();
    let tape = net.forward(&ps[1..3]);
    let part = net.vjp(&tape, &up[s * s..3 * s * s]).unwrap();
    assert_eq!(part[0], grads[1]);
    assert_eq!(tape.image(1), imgs[2].data());
    // The forward-mode Jacobian gives the same products.
    let jac = assert_jacobian_matches_vjp(net, &ps, &up, s, &grads, "tiny");
    // Only the marked columns, the same numbers.
    let some = net.jacobian_of(&net.forward(&ps), [true, false, true]);
    for i in 0..ps.len() {
        for k in 0..3 {
            let col = (i * 3 + k) * s * s..(i * 3 + k + 1) * s * s;
            if k == 1 {
                assert!(some[col].iter().all(|&v| v == 0.0));
            } else {
                assert_eq!(some[col.clone()], jac[col]);
            }
        }
    }
    assert!(g.images_and_vjps(&ps, &up[1..]).is_err());
    assert!(net.vjp(&tape, &up).is_err());
}

#[test]
fn batched_vjps_match_finite_differences() {
    // A few training steps first: at random weights many ReLUs sit at their kinks, where finite
    // differences step across them.
    let mut g = tiny(11);
    let opts = neural_gen::TrainOptions { steps: 20, batch: 16, val_every: 1_000_000, ..Default::default() };
    neural_gen::train(&mut g, &opts, |_| {}).unwrap();
    let s = g.config.size as usize;
    let net = g.kernels().unwrap();
    let ps = presses();
    let up = upstream(ps.len(), s);
    let grads = net.vjp(&net.forward(&ps), &up).unwrap();
    let loss = |i: usize, p: Press| -> f64 {
        let t = net.forward(&[p]);
        t.image(0).iter().zip(&up[i * s * s..(i + 1) * s * s]).map(|(a, b)| *a as f64 * *b as f64).sum()
    };
    for (i, p) in ps.iter().enumerate().skip(1) {
        let steps = [1e-2, 1e-3, 1e-3];
        for k in 0..3 {
            let (mut a, mut b) = (*p, *p);
            let (pa, pb) = match k {
                0 => (&mut a.h_mm, &mut b.h_mm),
                1 => (&mut a.alpha_rad, &mut b.alpha_rad),
                _ => (&mut a.beta_rad, &mut b.beta_rad),
            };
            *pa += steps[k];
            *pb -= steps[k];
            let fd = (loss(i, a) - loss(i, b)) / (2.0 * steps[k]);
            // f32 images and the odd ReLU kink inside the step: a few per cent.
            let tol = 0.08 * fd.abs().max(grads[i][k].abs()) + 2e-2;
            assert!((fd - grads[i][k]).abs() < tol, "press {i} ∂{k}: {} vs finite difference {fd}", grads[i][k]);
        }
    }
}

/// Architectures whose channel counts do not fill the kernels' register blocks (12 outputs,
/// odd input counts, a single stage, an odd seed side) give candle's images and gradients.
#[test]
fn odd_architectures_match_candle_autograd() {
    let archs = [
        Arch { hidden: vec![5, 7], seed_channels: 3, seed_side: 3, stages: vec![(3, 12), (3, 4)] },
        Arch { hidden: vec![], seed_channels: 5, seed_side: 5, stages: vec![(5, 4)] },
        Arch { hidden: vec![9], seed_channels: 2, seed_side: 2, stages: vec![(2, 8), (2, 20), (5, 4)] },
    ];
    let ps = presses();
    for (ai, arch) in archs.into_iter().enumerate() {
        let g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 5 + ai as u64).unwrap();
        let s = g.config.size as usize;
        let up = upstream(ps.len(), s);
        let (imgs, grads) = g.images_and_vjps(&ps, &up).unwrap();
        let (imgs_c, grads_c) = g.images_and_vjps_candle(&ps, &up).unwrap();
        for i in 0..ps.len() {
            for (a, b) in imgs[i].data().iter().zip(imgs_c[i].data()) {
                assert!((a - b).abs() < 1e-5, "arch {ai} image {i}: {a} vs candle {b}");
            }
            for k in 0..3 {
                let tol = 1e-3 * grads_c[i][k].abs().max(1.0);
                assert!(
                    (grads[i][k] - grads_c[i][k]).abs() < tol,
                    "arch {ai} press {i} ∂{k}: {} vs candle {}",
                    grads[i][k],
                    grads_c[i][k]
                );
            }
        }
        // The forward-mode Jacobian agrees with the VJP here too.
        let net = g.kernels().unwrap();
        assert_jacobian_matches_vjp(net, &ps, &up, s, &grads, &format!("arch {ai}"));
    }
}
