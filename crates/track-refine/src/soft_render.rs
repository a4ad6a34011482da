//! The soft footprint as a renderer of its own: presses in, the soft union image out, and the
//! vector–Jacobian product of that image with respect to every press, the same closed-form
//! derivatives the refinement's image term uses (for an optimisation loop outside this crate,
//! such as the Python package's PyTorch function).

use brush_model::{BrushProfile, PointMm, TrackPoint, wrap_angle_rad};

use crate::RefineError;
use crate::image::{Analytic, Fp, Raster};
use crate::problem::pixel_box_on;
use crate::soft::Shape;

/// The raster a [`soft_render`] draws on: `width × height` pixels, pixel `(i, j)` centred at
/// paper point `origin + ((i + ½)·mm_per_px, (j + ½)·mm_per_px)` mm, footprint edges softened
/// over `edge_px` pixels each side (the refinement's [`crate::RefineOptions::edge_px`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftCanvas {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Paper position of the image's top-left corner, mm.
    pub origin_mm: PointMm,
    /// Pixel size, mm.
    pub mm_per_px: f64,
    /// Half-width of a footprint's soft edge, px.
    pub edge_px: f64,
}

impl SoftCanvas {
    fn check(&self) -> Result<(), RefineError> {
        let px = u64::from(self.width) * u64::from(self.height);
        if self.width == 0 || self.height == 0 || px > 1 << 26 {
            return Err(RefineError::Target(format!(
                "{}×{} px (expected both sides at least 1, at most 2^26 pixels)",
                self.width, self.height
            )));
        }
        if !(self.mm_per_px.is_finite() && self.mm_per_px > 0.0) {
            return Err(RefineError::Target(format!("pixel size {} mm (expected a positive length)", self.mm_per_px)));
        }
        if !(self.origin_mm.x_mm.is_finite() && self.origin_mm.y_mm.is_finite()) {
            return Err(RefineError::Target("the origin is not finite".into()));
        }
        if !(self.edge_px.is_finite() && self.edge_px > 0.0 && self.edge_px <= 16.0) {
            return Err(RefineError::BadOption {
                name: "edge_px",
                value: self.edge_px.to_string(),
                expected: "a half-width above 0 and at most 16 px",
            });
        }
        Ok(())
    }
}

/// The prepared footprints of `presses` on `c`: each press's anchor `(x, y)` (the footprint's
/// root end) and direction β (root → tip) as given, its lengths from the profile's model at
/// (h, α, β reduced into the calibrated β range, as [`BrushProfile::predict_oriented`]), with
/// their partials. A press with `h ≤ 0` is off the paper and left out.
fn footprints(presses: &[TrackPoint], profile: &BrushProfile, c: &SoftCanvas) -> Result<Vec<(usize, Fp)>, RefineError> {
    let m = &profile.model;
    let e = c.edge_px * c.mm_per_px;
    let mut out = Vec::with_capacity(presses.len());
    for (i, p) in presses.iter().enumerate() {
        if ![p.x_mm, p.y_mm, p.h_mm, p.alpha_rad, p.beta_rad].iter().all(|v| v.is_finite()) {
            return Err(RefineError::Target(format!("press {i} is not finite: {p:?}")));
        }
        if !p.is_pressed() {
            continue;
        }
        let wrapped = wrap_angle_rad(p.beta_rad);
        let inside = profile.ranges.beta_rad.contains(wrapped);
        let bs = profile.ranges.beta_rad.clamp(wrapped);
        let terms = [&m.lt_mm, &m.lh_mm, &m.lr_mm];
        let raw = terms.map(|t| t.eval(p.h_mm, p.alpha_rad, bs));
        // A length clamped at its floor does not move with the press.
        let live = raw.map(|v| v > 1e-6);
        let [lt, lh, lr] = raw.map(|v| v.max(1e-6));
        let part = |f: fn(&brush_model::Terms) -> Option<f64>| {
            let mut d = [0.0; 3];
            for k in 0..3 {
                if live[k] {
                    d[k] = f(terms[k]).unwrap_or(0.0);
                }
            }
            d
        };
        let dh = part(|t| t.h_mm);
        let da = part(|t| t.alpha_rad);
        let db = if inside { part(|t| t.beta_rad) } else { [0.0; 3] };
        let shape = Shape { lt, lh, lr };
        let [i0, i1, j0, j1] =
            pixel_box_on(c.origin_mm, c.mm_per_px, (c.width, c.height), e, (p.x_mm, p.y_mm), p.beta_rad, &shape);
        out.push((
            i,
            Fp {
                x: p.x_mm,
                y: p.y_mm,
                h: p.h_mm,
                alpha: p.alpha_rad,
                beta: p.beta_rad,
                shape,
                dh,
                da,
                db,
                i0,
                i1,
                j0,
                j1,
            },
        ));
    }
    Ok(out)
}

fn render(
    presses: &[TrackPoint],
    profile: &BrushProfile,
    c: &SoftCanvas,
    upstream: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<[f64; 5]>), RefineError> {
    c.check()?;
    let n = c.width as usize * c.height as usize;
    if let Some(up) = upstream {
        if up.len() != n {
            return Err(RefineError::Target(format!(
                "upstream gradient of {} values for {}×{} px (expected one per pixel)",
                up.len(),
                c.width,
                c.height
            )));
        }
    }
    let fps = footprints(presses, profile, c)?;
    let r = Raster {
        width: c.width as usize,
        height: c.height as usize,
        origin: [c.origin_mm.x_mm, c.origin_mm.y_mm],
        mm_per_px: c.mm_per_px,
        ink: &[],
        ink_sum: 0.0,
    };
    let model = Analytic { edge_mm: c.edge_px * c.mm_per_px };
    let list: Vec<Fp> = fps.iter().map(|(_, f)| *f).collect();
    let (image, per_fp) = model.render_vjp(&r, &list, upstream);
    let mut grads = vec![[0.0; 5]; if upstream.is_some() { presses.len() } else { 0 }];
    for ((i, _), g) in fps.iter().zip(per_fp) {
        grads[*i] = g;
    }
    Ok((image, grads))
}

/// The soft union `U = 1 − Π(1 − c_i)` of the presses' soft footprints on `canvas` (row-major,
/// ink = 1): what refinement's image term compares with the glyph. Each press is a footprint
/// whose root end sits at `(x_mm, y_mm)`, pointing along `beta_rad` (root → tip, radians from
/// +x towards +y), its lengths the profile's at `(h_mm, alpha_rad)` and β reduced into the
/// calibrated β range; presses with `h_mm ≤ 0` leave nothing. The lengths are the model's
/// outside the calibrated ranges too (no refusal: an optimiser may step outside; clamp the
/// presses if that matters).
///
/// # Errors
/// [`RefineError::Target`] for an unusable canvas or a press that is not finite;
/// [`RefineError::BadOption`] for an edge width out of range.
///
/// # Examples
/// ```
/// use track_refine::brush_model::{BrushProfile, PointMm, TrackPoint};
/// use track_refine::{SoftCanvas, soft_render};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// let canvas = SoftCanvas { width: 40, height: 40, origin_mm: PointMm::new(0.0, 0.0), mm_per_px: 1.0, edge_px: 0.75 };
/// let press = TrackPoint { x_mm: 10.0, y_mm: 20.0, h_mm: 15.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let image = soft_render(&[press], &pen1, &canvas)?;
/// assert!(image[20 * 40 + 15] > 0.99); // (15.5, 20.5) mm: inside the footprint
/// assert_eq!(image[5 * 40 + 5], 0.0); // far from it
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn soft_render(
    presses: &[TrackPoint],
    profile: &BrushProfile,
    canvas: &SoftCanvas,
) -> Result<Vec<f64>, RefineError> {
    Ok(render(presses, profile, canvas, None)?.0)
}

/// [`soft_render`]'s image and its vector–Jacobian product: for `upstream` = `∂L/∂U` (one value
/// per pixel), each press's `∂L/∂(x_mm, y_mm, h_mm, alpha_rad, beta_rad)` (per mm, per rad;
/// zero for a press off the paper), in closed form (the refinement's soft-footprint
/// derivatives).
///
/// # Errors
/// As [`soft_render`], and [`RefineError::Target`] when `upstream` does not hold one value per
/// pixel.
pub fn soft_render_vjp(
    presses: &[TrackPoint],
    profile: &BrushProfile,
    canvas: &SoftCanvas,
    upstream: &[f64],
) -> Result<(Vec<f64>, Vec<[f64; 5]>), RefineError> {
    render(presses, profile, canvas, Some(upstream))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form VJP against central differences of the rendered image, for every press
    /// variable, on a brush whose lengths depend on β too.
    #[test]
    fn the_vjp_matches_finite_differences() {
        let mut profile = BrushProfile::builtin("pen1").unwrap();
        profile.model.lt_mm.beta_rad = Some(3.0);
        profile.model.lr_mm.beta_rad = Some(-1.0);
        let canvas =
            SoftCanvas { width: 48, height: 40, origin_mm: PointMm::new(-2.0, 1.0), mm_per_px: 0.9, edge_px: 1.5 };
        let presses = [
            TrackPoint { x_mm: 8.0, y_mm: 18.0, h_mm: 14.0, alpha_rad: 0.05, beta_rad: 0.04 },
            TrackPoint { x_mm: 20.0, y_mm: 22.0, h_mm: 16.0, alpha_rad: 0.1, beta_rad: 0.7 },
        ];
        let n = 48 * 40;
        let up: Vec<f64> = (0..n).map(|k| ((k * 37 % 101) as f64 / 101.0) - 0.4).collect();
        let (_, g) = soft_render_vjp(&presses, &profile, &canvas, &up).unwrap();
        let loss = |ps: &[TrackPoint]| -> f64 {
            soft_render(ps, &profile, &canvas).unwrap().iter().zip(&up).map(|(a, b)| a * b).sum()
        };
        for (i, gi) in g.iter().enumerate() {
            for (v, &analytic) in gi.iter().enumerate() {
                let step = 1e-5;
                let mut plus = presses;
                let mut minus = presses;
                fn field(p: &mut TrackPoint, v: usize) -> &mut f64 {
                    match v {
                        0 => &mut p.x_mm,
                        1 => &mut p.y_mm,
                        2 => &mut p.h_mm,
                        3 => &mut p.alpha_rad,
                        _ => &mut p.beta_rad,
                    }
                }
                *field(&mut plus[i], v) += step;
                *field(&mut minus[i], v) -= step;
                let fd = (loss(&plus) - loss(&minus)) / (2.0 * step);
                let tol = 1e-4 * (1.0 + fd.abs());
                assert!((analytic - fd).abs() < tol, "press {i} variable {v}: analytic {analytic} vs differences {fd}");
            }
        }
        assert!(g.iter().flatten().any(|v| v.abs() > 1e-3), "no gradient at all: {g:?}");
    }

    #[test]
    fn presses_off_the_paper_and_bad_inputs() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let c = SoftCanvas { width: 8, height: 8, origin_mm: PointMm::new(0.0, 0.0), mm_per_px: 1.0, edge_px: 0.75 };
        let up = TrackPoint { x_mm: 2.0, y_mm: 2.0, h_mm: 0.0, alpha_rad: 0.0, beta_rad: 0.0 };
        assert!(soft_render(&[up], &pen1, &c).unwrap().iter().all(|&v| v == 0.0));
        let nan = TrackPoint { h_mm: f64::NAN, ..up };
        assert!(soft_render(&[nan], &pen1, &c).unwrap_err().to_string().contains("press 0 is not finite"));
        let short = soft_render_vjp(&[up], &pen1, &c, &[0.0; 3]).unwrap_err();
        assert!(short.to_string().contains("3 values for 8×8 px"), "{short}");
        let bad = SoftCanvas { edge_px: 0.0, ..c };
        assert!(soft_render(&[up], &pen1, &bad).is_err());
    }
}
