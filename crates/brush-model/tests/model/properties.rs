//! Property tests for every footprint invariant of docs/contracts.md §3.

use brush_model::{BrushProfile, Extrapolation, Footprint, PointMm, Press};
use proptest::prelude::*;

fn footprint() -> impl Strategy<Value = Footprint> {
    (0.2f64..40.0, 0.2f64..20.0, 0.1f64..10.0).prop_map(|(lt, lh, lr)| Footprint::new(lt, lh, lr).unwrap())
}

proptest! {
    #[test]
    fn max_half_width_is_lr_at_x_lh(f in footprint()) {
        let up = f.upper();
        let belly = up.eval(0.5);
        prop_assert!((belly.y_mm - f.lr_mm).abs() < 1e-9 * f.lr_mm.max(1.0));
        prop_assert!((belly.x_mm - f.lh_mm).abs() < 1e-9 * f.length_mm());
        for i in 0..=200 {
            let t = i as f64 / 200.0;
            prop_assert!(up.eval(t).y_mm <= f.lr_mm * (1.0 + 1e-12));
        }
    }

    #[test]
    fn length_along_axis_is_lh_plus_lt(f in footprint()) {
        let up = f.upper();
        prop_assert_eq!(up.eval(0.0), PointMm::new(0.0, 0.0));
        prop_assert!((up.eval(1.0).x_mm - (f.lh_mm + f.lt_mm)).abs() < 1e-9 * f.length_mm());
        // The outline reaches at least to the tip (with a very short tip, lh ≫ lt, the curve
        // can swing slightly past P3 before returning: a property of the model).
        prop_assert!(f.local_bounds().max_x >= f.length_mm() * (1.0 - 1e-12));
        if f.lt_mm >= f.lh_mm {
            prop_assert!((f.local_bounds().max_x - f.length_mm()).abs() < 1e-9 * f.length_mm());
        }
    }

    #[test]
    fn outline_is_mirror_symmetric(f in footprint(), t in 0.0f64..1.0) {
        let (up, lo) = (f.upper(), f.lower());
        let a = up.eval(t);
        let b = lo.eval(1.0 - t);
        prop_assert!((a.x_mm - b.x_mm).abs() < 1e-9 * f.length_mm());
        prop_assert!((a.y_mm + b.y_mm).abs() < 1e-9 * f.length_mm());
    }

    #[test]
    fn placement_is_a_rigid_motion(f in footprint(), x in -50.0f64..50.0, y in -50.0f64..50.0, beta in -3.2f64..3.2, t in 0.0f64..1.0) {
        let anchor = PointMm::new(x, y);
        let o = f.outline(anchor, beta);
        prop_assert!(o.upper.eval(0.0).distance(anchor) < 1e-9);
        let tip = o.upper.eval(1.0);
        prop_assert!((tip.distance(anchor) - f.length_mm()).abs() < 1e-9 * f.length_mm().max(1.0));
        // Direction of the axis is beta.
        let dir = (tip.y_mm - y).atan2(tip.x_mm - x);
        prop_assert!(brush_model::wrap_angle_rad(dir - beta).abs() < 1e-9);
        // Distances between curve points are preserved.
        let (p, q) = (f.upper().eval(t), f.lower().eval(t));
        let (pp, qq) = (o.upper.eval(t), o.lower.eval(t));
        prop_assert!((p.distance(q) - pp.distance(qq)).abs() < 1e-9 * f.length_mm().max(1.0));
    }

    #[test]
    fn area_grows_with_h_under_builtin_profiles(name in prop::sample::select(vec!["pen1", "pen2"]), fa in 0.0f64..1.0, fb in 0.0f64..1.0, f1 in 0.0f64..1.0, f2 in 0.0f64..1.0) {
        let p = BrushProfile::builtin(name).unwrap();
        let r = p.ranges;
        let (a, b) = (r.alpha_rad.lerp(fa), r.beta_rad.lerp(fb));
        let (lo, hi) = (f1.min(f2), f1.max(f2));
        prop_assume!(hi - lo > 1e-6);
        let small = p.predict(&Press::new(r.h_mm.lerp(lo), a, b), Extrapolation::Refuse).unwrap();
        let big = p.predict(&Press::new(r.h_mm.lerp(hi), a, b), Extrapolation::Refuse).unwrap();
        prop_assert!(big.area_mm2() > small.area_mm2());
    }

    #[test]
    fn bounds_contain_every_outline_point(f in footprint(), beta in -3.2f64..3.2, t in 0.0f64..1.0) {
        let b = f.placed_bounds(PointMm::new(3.0, -2.0), beta);
        let o = f.outline(PointMm::new(3.0, -2.0), beta);
        for p in [o.upper.eval(t), o.lower.eval(t)] {
            prop_assert!(p.x_mm >= b.min_x - 1e-9 && p.x_mm <= b.max_x + 1e-9);
            prop_assert!(p.y_mm >= b.min_y - 1e-9 && p.y_mm <= b.max_y + 1e-9);
        }
    }
}
