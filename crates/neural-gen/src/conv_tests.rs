//! The fast convolution and pixel shuffle agree with candle's own kernels in value and in every
//! gradient; the fused AdamW follows candle's AdamW.

use crate::conv::{Conv2d, pixel_shuffle};
use candle_core::{D, DType, Device, Module, Tensor, Var};

fn random(shape: &[usize], seed: u64) -> Tensor {
    // A small deterministic generator: values in [-1, 1).
    let n: usize = shape.iter().product();
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let v: Vec<f32> = (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        })
        .collect();
    Tensor::from_vec(v, shape, &Device::Cpu).unwrap()
}

fn max_abs_diff(a: &Tensor, b: &Tensor) -> f32 {
    assert_eq!(a.dims(), b.dims());
    a.sub(b).unwrap().abs().unwrap().flatten_all().unwrap().max(D::Minus1).unwrap().to_scalar::<f32>().unwrap()
}

/// Value, input gradient and weight/bias gradients of a loss `Σ r ⊙ conv(x)` (with and without
/// a ReLU after the convolution) for both kernels.
fn compare(b: usize, c: usize, o: usize, h: usize, w: usize, k: usize, padding: usize) {
    compare_one(b, c, o, h, w, k, padding, false);
    compare_one(b, c, o, h, w, k, padding, true);
}

#[allow(clippy::too_many_arguments)]
fn compare_one(b: usize, c: usize, o: usize, h: usize, w: usize, k: usize, padding: usize, relu: bool) {
    let x = Var::from_tensor(&random(&[b, c, h, w], 1)).unwrap();
    let wt = Var::from_tensor(&random(&[o, c, k, k], 2)).unwrap();
    let bias = Var::from_tensor(&random(&[o], 3)).unwrap();
    let mut ours = Conv2d::new(wt.as_tensor().clone(), Some(bias.as_tensor().clone()), padding).unwrap();
    if relu {
        ours = ours.with_relu();
    }
    let y_ours = ours.forward(&x).unwrap();
    let mut y_ref =
        x.conv2d(&wt, padding, 1, 1, 1).unwrap().broadcast_add(&bias.reshape((1, o, 1, 1)).unwrap()).unwrap();
    if relu {
        y_ref = y_ref.relu().unwrap();
    }
    assert!(max_abs_diff(&y_ours, &y_ref) < 1e-4, "forward differs for {:?}", (b, c, o, h, w, k, padding));
    let r = random(y_ref.dims(), 4);
    let g_ours = (&y_ours * &r).unwrap().sum_all().unwrap().backward().unwrap();
    let g_ref = (&y_ref * &r).unwrap().sum_all().unwrap().backward().unwrap();
    for (name, v) in [("input", &x), ("weight", &wt), ("bias", &bias)] {
        let (a, e) = (g_ours.get(v).unwrap(), g_ref.get(v).unwrap());
        let scale = e.abs().unwrap().flatten_all().unwrap().max(D::Minus1).unwrap().to_scalar::<f32>().unwrap();
        let d = max_abs_diff(a, e);
        assert!(d <= 1e-5 * scale.max(1.0) * 10.0, "{name} gradient differs by {d} (scale {scale})");
    }
}

#[test]
fn matches_candle_conv2d_value_and_gradients() {
    compare(2, 3, 4, 8, 8, 3, 1); // "same" convolution
    compare(3, 2, 5, 7, 9, 3, 0); // valid, non-square image
    compare(1, 4, 2, 6, 5, 5, 2); // 5×5 kernel
    compare(2, 1, 1, 4, 4, 1, 0); // 1×1
    compare(1, 2, 3, 3, 3, 3, 2); // padding of k − 1: the input gradient needs none
    compare(2, 2, 2, 5, 5, 3, 3); // padding ≥ k: candle's kernel (fallback)
    compare(64, 8, 4, 16, 16, 3, 1); // a batch large enough to split over threads
}

#[test]
fn pixel_shuffle_matches_candle_both_ways() {
    for (b, c, h, w, r) in [(2, 8, 3, 5, 2), (1, 9, 4, 4, 3), (3, 4, 1, 1, 2)] {
        let x = Var::from_tensor(&random(&[b, c, h, w], 13)).unwrap();
        let ours = pixel_shuffle(&x, r).unwrap();
        let theirs = candle_nn::ops::pixel_shuffle(&x, r).unwrap();
        assert_eq!(ours.dims(), &[b, c / (r * r), h * r, w * r]);
        assert_eq!(max_abs_diff(&ours, &theirs), 0.0);
        let up = random(ours.dims(), 14);
        let ga = (&ours * &up).unwrap().sum_all().unwrap().backward().unwrap();
        let gb = (&theirs * &up).unwrap().sum_all().unwrap().backward().unwrap();
        assert_eq!(max_abs_diff(ga.get(&x).unwrap(), gb.get(&x).unwrap()), 0.0);
    }
    assert!(pixel_shuffle(&random(&[1, 6, 2, 2], 15), 2).is_err(), "6 channels are not divisible by 4");
}

#[test]
fn bad_shapes_are_errors_not_panics() {
    let x = random(&[1, 2, 2, 2], 5);
    let big = Conv2d::new(random(&[1, 2, 5, 5], 4), None, 1).unwrap();
    assert!(big.forward(&x).is_err(), "kernel larger than the padded image");
    let w = random(&[3, 4, 3, 3], 6);
    let conv = Conv2d::new(w, None, 1).unwrap();
    assert!(conv.forward(&x).is_err(), "channel mismatch");
    assert!(Conv2d::new(random(&[3, 2, 3, 2], 7), None, 0).is_err(), "non-square kernel");
    assert!(Conv2d::new(random(&[3, 2, 3, 3], 7), Some(random(&[2], 8)), 0).is_err(), "bias size");
    // Other dtypes take candle's kernel and still agree.
    let w = random(&[3, 2, 3, 3], 10);
    let f32y = Conv2d::new(w.clone(), None, 1).unwrap().forward(&x).unwrap();
    let (x64, w64) = (x.to_dtype(DType::F64).unwrap(), w.to_dtype(DType::F64).unwrap());
    let f64y = Conv2d::new(w64, None, 1).unwrap().forward(&x64).unwrap();
    assert!(max_abs_diff(&f32y, &f64y.to_dtype(DType::F32).unwrap()) < 1e-5);
}

#[test]
fn fused_adamw_follows_candle_adamw() {
    use crate::adam::FusedAdamW;
    use candle_nn::{AdamW, Optimizer, ParamsAdamW};
    let params = ParamsAdamW { lr: 0.01, weight_decay: 0.1, ..Default::default() };
    let start = random(&[3, 40_000], 21);
    let (a, b) = (Var::from_tensor(&start).unwrap(), Var::from_tensor(&start).unwrap());
    let mut ours = FusedAdamW::new(vec![a.clone()], params.clone()).unwrap();
    let mut theirs = AdamW::new(vec![b.clone()], params).unwrap();
    for step in 0..5u64 {
        let target = random(&[3, 40_000], 30 + step);
        let la = a.sub(&target).unwrap().sqr().unwrap().sum_all().unwrap();
        let lb = b.sub(&target).unwrap().sqr().unwrap().sum_all().unwrap();
        ours.backward_step(&la).unwrap();
        theirs.backward_step(&lb).unwrap();
        if step == 2 {
            ours.set_learning_rate(0.003);
            theirs.set_learning_rate(0.003);
        }
    }
    let moved = max_abs_diff(a.as_tensor(), &start);
    assert!(moved > 0.01, "the variable moved by {moved}");
    let d = max_abs_diff(a.as_tensor(), b.as_tensor());
    assert!(d < 1e-5, "fused and candle AdamW differ by {d}");
    let f64var = Var::zeros(3, DType::F64, &Device::Cpu).unwrap();
    assert!(FusedAdamW::new(vec![f64var], ParamsAdamW::default()).is_err());
}

#[test]
fn gradients_do_not_depend_on_the_thread_count() {
    let grads_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let x = Var::from_tensor(&random(&[37, 3, 12, 10], 41)).unwrap();
            let w = Var::from_tensor(&random(&[5, 3, 3, 3], 42)).unwrap();
            let conv = Conv2d::new(w.as_tensor().clone(), None, 1).unwrap().with_relu();
            let y = conv.forward(&x).unwrap();
            let g = (&y * &random(y.dims(), 43)).unwrap().sum_all().unwrap().backward().unwrap();
            let flat = |v: &Var| g.get(v).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
            (flat(&x), flat(&w))
        })
    };
    let one = grads_with(1);
    assert_eq!(one, grads_with(3));
    assert_eq!(one, grads_with(2));
}
