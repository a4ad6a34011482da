//! The generator path (cargo feature `generator`) on a tiny generator: its gradient against
//! finite differences, one step lowers the loss, and the option without the feature.
#![cfg(feature = "generator")]

use std::sync::Arc;

use crate::common::{bar_target, line_track, pen1};
use brush_model::BrushProfile;
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};
use track_refine::{GenMode, GenModel, Gradients, Problem, RefineError, RefineOptions, refine_with_generator};

/// A tiny 32² generator after a few training steps (so that its images look like footprints).
fn tiny(mode: GenMode) -> Arc<GenModel> {
    let mut g = Generator::new(GeneratorConfig::new(pen1(), Arch::tiny_32()), 5).unwrap();
    let opts = TrainOptions { steps: 30, batch: 16, lr: 3e-3, val_every: 1_000_000, ..Default::default() };
    neural_gen::train(&mut g, &opts, |_| {}).unwrap();
    Arc::new(GenModel::new(&g).unwrap().with_mode(mode))
}

#[test]
fn generator_gradients_match_finite_differences() {
    let profile = pen1();
    let target = bar_target(64);
    // Reverse mode per footprint, and shared exact presses with the forward-mode Jacobian.
    for (mode, alpha) in [
        (GenMode::Vjp, 0.0),
        (GenMode::Vjp, 5f64.to_radians()),
        (GenMode::Shared { quantum: [0.0; 3] }, 5f64.to_radians()),
    ] {
        let net = tiny(mode);
        let track = line_track(12.0, alpha, 40);
        let p = Problem::new(&track, &profile, &target, &RefineOptions::default())
            .unwrap()
            .with_generator(net.clone())
            .unwrap();
        let mut theta = p.initial();
        for (i, v) in theta.iter_mut().enumerate() {
            *v += 0.05 * ((i * 7919) % 13) as f64 / 13.0;
        }
        p.project(&mut theta);
        let dirs = p.directions(&theta);
        let (_, g) = p.loss_grad(&theta, &dirs);
        let n = theta.len();
        let (mut checked, mut largest) = (0, 0.0f64);
        // Positions (the spatial gradient through the placement), depths and tilts (the VJP
        // plus the anchor's move in the canvas).
        for i in (0..n).step_by(7).chain([n - 1, n / 2]) {
            let eps = 1e-4;
            let (mut a, mut b) = (theta.clone(), theta.clone());
            a[i] += eps;
            b[i] -= eps;
            let fd = (p.loss(&a, &dirs).total - p.loss(&b, &dirs).total) / (2.0 * eps);
            // Bilinear sampling has kinks at canvas pixel edges and the images are f32.
            let tol = 0.03 * g[i].abs().max(fd.abs()) + 1e-4;
            assert!(
                (g[i] - fd).abs() <= tol,
                "{mode:?} α {alpha}: variable {i} of {n}: {} vs finite difference {fd}",
                g[i]
            );
            checked += 1;
            largest = largest.max(fd.abs());
        }
        assert!(checked > 10 && largest > 1e-3, "{checked} checked, largest {largest}");
    }
}

#[test]
fn one_generator_step_lowers_the_loss_on_a_synthetic_target() {
    let profile = pen1();
    let target = bar_target(64);
    let opts = RefineOptions { iterations: 1, ..RefineOptions::default() };
    let out =
        refine_with_generator(&line_track(11.5, 0.0, 40), &profile, &target, &opts, tiny(GenMode::default())).unwrap();
    assert_eq!(out.curve.len(), 2);
    assert!(out.curve[1].image < out.curve[0].image, "{:?}", out.curve);
    assert!(out.curve[1].total < out.curve[0].total, "{:?}", out.curve);
    // Plain `refine` has no generator to use: the option is refused there, naming the way.
    let o = RefineOptions { gradients: Gradients::Generator, ..RefineOptions::default() };
    let e = Problem::new(&line_track(12.0, 0.0, 40), &profile, &target, &o).err().unwrap();
    assert!(e.to_string().contains("refine_with_generator"), "{e}");
    // A generator trained for another profile is refused.
    let pen2 = BrushProfile::builtin("pen2").unwrap();
    let e = refine_with_generator(&line_track(12.0, 0.0, 40), &pen2, &target, &opts, tiny(GenMode::default()))
        .err()
        .unwrap();
    assert!(e.to_string().contains("pen1") && e.to_string().contains("pen2"), "{e}");
    assert!(matches!(&e, RefineError::GeneratorProfile { generator, track } if generator == "pen1" && track == "pen2"));
}

/// A generator error becomes a refinement error that keeps neural-gen's error as its source
/// (naming the missing file), not a flattened message.
#[test]
fn a_generator_error_keeps_its_cause() {
    let missing = std::env::temp_dir().join("maobi-no-such-generator.safetensors");
    let cause = neural_gen::Generator::load(&missing).err().expect("no such file");
    let text = cause.to_string();
    let e = RefineError::from(cause);
    let RefineError::Generator(source) = &e else { panic!("{e:?}") };
    assert_eq!(source.to_string(), text);
    let chained = std::error::Error::source(&e).expect("the cause is kept");
    assert_eq!(chained.to_string(), text);
}
