//! Every metric agrees with scikit-image / numpy on committed image pairs
//! (`golden/gen_metrics.py` made them), plus the analytic checks.

use stroke_metrics::{GrayRef, MetricsError, SsimWorkspace, compare, csim, iou, mse, psnr, ssim};

fn decode(hex: &str) -> Vec<f32> {
    (0..hex.len() / 2).map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).unwrap() as f32 / 255.0).collect()
}

#[test]
fn matches_scikit_image_to_1e_minus_6() {
    let g: serde_json::Value = serde_json::from_str(include_str!("golden/metrics.json")).unwrap();
    let mut ws = SsimWorkspace::new();
    let mut n = 0;
    for (name, case) in g.as_object().unwrap() {
        let (w, h) = (case["width"].as_u64().unwrap() as usize, case["height"].as_u64().unwrap() as usize);
        let a = decode(case["a_hex"].as_str().unwrap());
        let b = decode(case["b_hex"].as_str().unwrap());
        let (a, b) = (GrayRef::new(&a, w, h).unwrap(), GrayRef::new(&b, w, h).unwrap());
        let s = ws.ssim(a, b).unwrap();
        let want = case["ssim"].as_f64().unwrap();
        assert!((s - want).abs() < 1e-6, "{name}: ssim {s} vs skimage {want}");
        // In fact the agreement is to rounding.
        assert!((s - want).abs() < 1e-12, "{name}: ssim {s} vs skimage {want}");
        for (metric, ours) in [("csim", csim(a, b).unwrap()), ("iou", iou(a, b).unwrap()), ("mse", mse(a, b).unwrap())]
        {
            let want = case[metric].as_f64().unwrap();
            assert!((ours - want).abs() < 1e-12, "{name}: {metric} {ours} vs {want}");
        }
        n += 1;
    }
    assert_eq!(n, 5);
}

fn pattern(w: usize, h: usize, k: f32) -> Vec<f32> {
    (0..w * h).map(|i| ((i % w) as f32 * 0.37 + (i / w) as f32 * k).sin() * 0.5 + 0.5).collect()
}

#[test]
fn identical_images_score_one() {
    let a = pattern(37, 29, 0.21);
    let g = GrayRef::new(&a, 37, 29).unwrap();
    let s = compare(g, g).unwrap();
    assert!((s.ssim - 1.0).abs() < 1e-12);
    assert!((s.csim - 1.0).abs() < 1e-12);
    assert_eq!(s.iou, 1.0);
    assert_eq!(s.mse, 0.0);
    assert_eq!(s.psnr, None);
    assert_eq!(psnr(g, g).unwrap(), f64::INFINITY);
}

#[test]
fn constant_images_follow_the_closed_form() {
    // Both constant: variances vanish, so SSIM = (2ab + C1)/(a² + b² + C1) · C2/C2.
    for (a, b) in [(0.2f32, 0.8f32), (0.0, 1.0), (0.5, 0.5), (1.0, 0.9)] {
        let (va, vb) = (vec![a; 20 * 16], vec![b; 20 * 16]);
        let (ga, gb) = (GrayRef::new(&va, 20, 16).unwrap(), GrayRef::new(&vb, 20, 16).unwrap());
        let (a, b) = (a as f64, b as f64);
        let c1 = 1e-4;
        let want = (2.0 * a * b + c1) / (a * a + b * b + c1);
        let got = ssim(ga, gb).unwrap();
        assert!((got - want).abs() < 1e-12, "{a} {b}: {got} vs {want}");
        let m = (a - b) * (a - b);
        assert!((mse(ga, gb).unwrap() - m).abs() < 1e-12);
    }
}

#[test]
fn blank_and_edge_cases() {
    let z = vec![0.0f32; 16 * 16];
    let o = pattern(16, 16, 0.5);
    let (gz, go) = (GrayRef::new(&z, 16, 16).unwrap(), GrayRef::new(&o, 16, 16).unwrap());
    assert_eq!(csim(gz, gz).unwrap(), 1.0);
    assert_eq!(csim(gz, go).unwrap(), 0.0);
    assert_eq!(iou(gz, gz).unwrap(), 1.0);
    let small = vec![0.0f32; 10 * 30];
    let gs = GrayRef::new(&small, 30, 10).unwrap();
    assert_eq!(ssim(gs, gs), Err(MetricsError::TooSmall(30, 10)));
    let other = vec![0.0f32; 17 * 16];
    let g2 = GrayRef::new(&other, 17, 16).unwrap();
    assert_eq!(csim(gz, g2), Err(MetricsError::SizeMismatch(16, 16, 17, 16)));
    assert!(GrayRef::new(&z, 15, 16).is_err());
}

#[test]
fn ssim_is_symmetric_and_falls_with_shift() {
    let w = 64;
    let disc = |cx: f32| -> Vec<f32> {
        (0..w * w)
            .map(|i| {
                let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                (12.0 - ((x - cx).powi(2) + (y - 32.0).powi(2)).sqrt()).clamp(0.0, 1.0)
            })
            .collect()
    };
    let (a, b, c) = (disc(32.0), disc(34.0), disc(38.0));
    fn g(v: &[f32]) -> GrayRef<'_> {
        GrayRef::new(v, 64, 64).unwrap()
    }
    let (s_ab, s_ba, s_ac) = (ssim(g(&a), g(&b)).unwrap(), ssim(g(&b), g(&a)).unwrap(), ssim(g(&a), g(&c)).unwrap());
    assert!((s_ab - s_ba).abs() < 1e-12);
    assert!(s_ab > s_ac && s_ac > 0.0 && s_ab < 1.0);
}
