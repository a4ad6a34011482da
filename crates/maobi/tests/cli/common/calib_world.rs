//! A calibration world: a brush whose footprints are not the profile's (its own coefficients,
//! and a footprint length that is not even linear in the press depth), pressing what a robot
//! program commands. Its constants live here only (docs/closed-loop.md, "Calibration sheet"):
//! maobi's library code must not know them. The camera is `world`'s.

#![allow(dead_code)]

use bezier_raster::Stamp;
use brush_model::{Footprint, PointMm, Stroke};

/// The world's tip length: intercept (mm), per mm of h, per rad of α, per rad of β.
pub const WORLD_LT: [f64; 4] = [1.8, 0.82, 12.0, 0.0];
/// Its root length, the same terms.
pub const WORLD_LH: [f64; 4] = [0.9, 0.40, 4.0, 0.0];
/// Its belly half-width, the same terms.
pub const WORLD_LR: [f64; 4] = [0.5, 0.21, 1.1, 0.0];
/// Its tip length also grows by this many mm per mm² of `(h − 15 mm)²`: no linear model is
/// exact for it.
pub const WORLD_LT_CURVE: f64 = 0.01;
/// The world's brush leaves no footprint pressed less than this, mm. (A press's ink is the
/// union of the footprints the brush passes through on its way down; this world's footprints
/// from here on are nearly nested, so that union is close to its deepest footprint.)
pub const WORLD_INKS_FROM_MM: f64 = 8.0;
/// Tilted at least this much (rad), its footprint points the way it leans.
pub const WORLD_TILT_RAD: f64 = 0.03;
/// An upright brush's tip trails on the pressed path this fraction of a footprint length back.
pub const WORLD_TRAIL: f64 = 0.4;
/// Its footprint's root end lies this far ahead of the commanded point (towards the tip), mm.
pub const WORLD_ROOT_SHIFT_MM: f64 = 0.3;

/// The world's footprint for a press (mm and rad).
pub fn world_footprint(h_mm: f64, alpha_rad: f64, beta_rad: f64) -> Footprint {
    let lin = |c: [f64; 4]| c[0] + c[1] * h_mm + c[2] * alpha_rad + c[3] * beta_rad;
    Footprint {
        lt_mm: lin(WORLD_LT) + WORLD_LT_CURVE * (h_mm - 15.0).powi(2),
        lh_mm: lin(WORLD_LH),
        lr_mm: lin(WORLD_LR),
    }
}

/// The world's footprints along `strokes` (paper mm): the path sampled every 0.1 mm (and
/// 0.25 mm of depth), one footprint per sample pressed at least [`WORLD_INKS_FROM_MM`].
pub fn calib_world_stamps(strokes: &[Stroke]) -> Vec<Stamp> {
    let mut out = Vec::new();
    for st in strokes {
        let mut samples: Vec<[f64; 5]> = Vec::new();
        for w in st.points.windows(2) {
            let (a, b) = (w[0], w[1]);
            let d = (b.x_mm - a.x_mm).hypot(b.y_mm - a.y_mm);
            let n = (d / 0.1).max((b.h_mm - a.h_mm).abs() / 0.25).ceil().max(1.0) as usize;
            for k in 0..n {
                let f = k as f64 / n as f64;
                samples.push([
                    a.x_mm + f * (b.x_mm - a.x_mm),
                    a.y_mm + f * (b.y_mm - a.y_mm),
                    a.h_mm + f * (b.h_mm - a.h_mm),
                    a.alpha_rad + f * (b.alpha_rad - a.alpha_rad),
                    a.beta_rad,
                ]);
            }
        }
        if let Some(p) = st.points.last() {
            samples.push([p.x_mm, p.y_mm, p.h_mm, p.alpha_rad, p.beta_rad]);
        }
        let mut hist: Vec<[f64; 2]> = Vec::new();
        let mut last: Option<f64> = None;
        for (i, p) in samples.iter().enumerate() {
            let here = [p[0], p[1]];
            if p[2] <= 0.0 {
                hist.clear();
                last = None;
                continue;
            }
            hist.push(here);
            if p[2] < WORLD_INKS_FROM_MM {
                continue;
            }
            let fp = world_footprint(p[2], p[3], p[4]);
            let dir = if p[3] >= WORLD_TILT_RAD {
                Some(p[4])
            } else {
                // Dragged: back along the pressed path, else its farthest point, else ahead.
                let reach = WORLD_TRAIL * fp.length_mm();
                let mut far = (0.0, None);
                let mut found = None;
                for q in hist.iter().rev() {
                    let d = (q[0] - here[0]).hypot(q[1] - here[1]);
                    if d >= reach {
                        found = Some((q[1] - here[1]).atan2(q[0] - here[0]));
                        break;
                    }
                    if d > far.0 {
                        far = (d, Some(*q));
                    }
                }
                found.or(match far {
                    (d, Some(q)) if d >= 0.3 => Some((q[1] - here[1]).atan2(q[0] - here[0])),
                    _ => None,
                })
            };
            let ahead = || {
                samples[i..]
                    .iter()
                    .find(|q| (q[0] - here[0]).hypot(q[1] - here[1]) >= 0.3)
                    .map(|q| (here[1] - q[1]).atan2(here[0] - q[0]))
            };
            let beta = dir.or(last).or_else(ahead).unwrap_or(std::f64::consts::FRAC_PI_2);
            last = Some(beta);
            let anchor =
                PointMm::new(here[0] + WORLD_ROOT_SHIFT_MM * beta.cos(), here[1] + WORLD_ROOT_SHIFT_MM * beta.sin());
            out.push(Stamp { footprint: fp, anchor, beta_rad: beta });
        }
    }
    out
}
