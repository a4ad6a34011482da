//! The registration marks found in a photo and the photo → paper homography.

use bezier_raster::connected_components;
use serde::{Deserialize, Serialize};

use crate::{Homography, InkMap, ObserveError};

/// The largest distance, mm, between a mark's centre of ink (mapped to the paper) and where the
/// sheet puts it, above which the photo is refused.
pub const RESIDUAL_LIMIT_MM: f64 = 1.5;

/// The largest distance, mm on the paper, between a mark's centre of ink and where the map
/// fitted to the other marks puts it, above which the photo is refused: a mark out of place
/// moves the fit to all marks towards itself (and so hides in its residual) but not the fit
/// to the others. Measured on clean and on displaced marks (docs/closed-loop.md,
/// "Registration").
pub const LEAVE_ONE_OUT_LIMIT_MM: f64 = 0.6;

/// The widest 10–90 % edge of the marks' ink, mm, above which the photo is refused as blurred.
pub const BLUR_LIMIT_MM: f64 = 1.2;

/// How far (mm, on the paper) a found blob may be from where the corner marks predict a mark.
const MATCH_MM: f64 = 4.0;

/// Extra paper around a mark's planned ink searched for its centre of ink, mm.
const WINDOW_MM: [f64; 2] = [4.0, 2.0];

/// Samples per mm over a mark's window.
const WINDOW_PX_PER_MM: f64 = 16.0;

/// A registration mark where the sheet put it: the centre of its ink in paper mm and the size
/// of its ink (a bar along paper x).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KnownMark {
    /// Its name in messages (`top-left`).
    pub role: String,
    /// The centre of its ink, paper mm.
    pub centre_mm: [f64; 2],
    /// Half its ink's length along paper x, mm.
    pub half_length_mm: f64,
    /// Half its ink's width along paper y, mm.
    pub half_width_mm: f64,
}

/// One mark as found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MarkFit {
    /// Its name.
    pub role: String,
    /// The centre of its ink in the photo, px (of the reduced photo).
    pub photo_px: [f64; 2],
    /// That centre mapped to the paper by the fitted homography, less where the sheet puts it, mm.
    pub error_mm: [f64; 2],
    /// That centre mapped to the paper by the homography fitted to the other marks, its
    /// distance from where the sheet puts it, mm.
    pub leave_one_out_mm: f64,
    /// Its ink's area on the paper, mm².
    pub area_mm2: f64,
}

/// The photo registered onto the paper.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Registration {
    /// Paper mm → photo px.
    pub paper_to_photo: Homography,
    /// Every mark as found, in the order given.
    pub marks: Vec<MarkFit>,
    /// Root mean square of the marks' errors, mm.
    pub residual_rms_mm: f64,
    /// The largest mark error, mm.
    pub residual_max_mm: f64,
    /// The largest [`MarkFit::leave_one_out_mm`], mm.
    pub leave_one_out_max_mm: f64,
    /// The marks' 10–90 % edge width (median), mm: how sharp the photo is.
    pub edge_mm: f64,
    /// Photo px per paper mm at the sheet's centre.
    pub px_per_mm: f64,
    /// Which of the four ways round was kept: the corners of the largest quadrilateral (in hull
    /// order from its leftmost blob) shifted by this many places onto top-left, top-right,
    /// bottom-right, bottom-left.
    pub corner_shift: usize,
}

#[derive(Clone, Copy, Debug)]
struct Blob {
    c: [f64; 2],
    px: usize,
}

/// Finds the registration marks and fits the homography. `marks` lists the sheet's marks: the
/// first four are its corners in the order top-left, top-right, bottom-right, bottom-left; the
/// others (at least one, none of them symmetric to another under a quarter turn of the sheet)
/// tell the corners apart and give the fit its residual.
///
/// The four corner marks are the corners of the largest quadrilateral over the centres of the
/// sheet's blobs of ink; each of the four ways round gives a first homography, and the way
/// whose other marks are found (a blob within 4 mm of where it puts them) is kept. Then each
/// mark's centre of ink is measured on the paper (its planned ink and a few mm around it,
/// resampled through the current fit) and the homography refitted to all marks, three times.
///
/// # Errors
/// [`ObserveError::TooFewBlobs`], [`ObserveError::MarkNotFound`], [`ObserveError::Ambiguous`],
/// [`ObserveError::MarkSize`], [`ObserveError::Residual`] (over [`RESIDUAL_LIMIT_MM`]),
/// [`ObserveError::Misplaced`] (a mark against the others over [`LEAVE_ONE_OUT_LIMIT_MM`]),
/// [`ObserveError::Blurred`] (over [`BLUR_LIMIT_MM`]) or [`ObserveError::Degenerate`].
pub fn register(ink: &InkMap, marks: &[KnownMark]) -> Result<Registration, ObserveError> {
    assert!(marks.len() >= 5, "four corner marks and at least one more");
    let blobs = blobs(ink);
    if blobs.len() < 4 {
        return Err(ObserveError::TooFewBlobs { found: blobs.len() });
    }
    let quad = largest_quad(&blobs).ok_or(ObserveError::TooFewBlobs { found: blobs.len() })?;
    let corners: Vec<[f64; 2]> = marks[..4].iter().map(|m| m.centre_mm).collect();
    // Each way round: how many of the other marks it finds, and their distances.
    let mut fits = Vec::new();
    let mut missing = None;
    for turn in 0..4 {
        let photo: Vec<[f64; 2]> = (0..4).map(|i| blobs[quad[(i + turn) % 4]].c).collect();
        let Some(h) = Homography::fit(&corners, &photo) else { continue };
        let Some(inv) = h.inverse() else { continue };
        let mut ok = true;
        for m in &marks[4..] {
            let near = blobs.iter().any(|b| {
                let p = inv.apply(b.c);
                (p[0] - m.centre_mm[0]).hypot(p[1] - m.centre_mm[1]) < MATCH_MM
            });
            if !near {
                ok = false;
                missing.get_or_insert_with(|| m.role.clone());
                break;
            }
        }
        if ok {
            fits.push((turn, h));
        }
    }
    let (corner_shift, mut h) = match fits.len() {
        0 => return Err(ObserveError::MarkNotFound { role: missing.unwrap_or_else(|| marks[4].role.clone()) }),
        1 => fits[0],
        n => return Err(ObserveError::Ambiguous { ways: n }),
    };
    let mut measured = Vec::new();
    for _ in 0..3 {
        measured = marks.iter().map(|m| measure(ink, &h, m)).collect::<Vec<_>>();
        let photo: Vec<[f64; 2]> = measured.iter().map(|m| m.photo).collect();
        let paper: Vec<[f64; 2]> = marks.iter().map(|m| m.centre_mm).collect();
        h = Homography::fit(&paper, &photo).ok_or(ObserveError::Degenerate)?;
    }
    let inv = h.inverse().ok_or(ObserveError::Degenerate)?;
    let mut fitted = Vec::new();
    for (m, s) in marks.iter().zip(&measured) {
        let expected_mm2 = 0.8 * 4.0 * m.half_length_mm * m.half_width_mm;
        if !(s.area_mm2 > 0.35 * expected_mm2 && s.area_mm2 < 2.5 * expected_mm2) {
            return Err(ObserveError::MarkSize { role: m.role.clone(), area_mm2: s.area_mm2, expected_mm2 });
        }
        let p = inv.apply(s.photo);
        fitted.push(MarkFit {
            role: m.role.clone(),
            photo_px: s.photo,
            error_mm: [p[0] - m.centre_mm[0], p[1] - m.centre_mm[1]],
            leave_one_out_mm: f64::NAN,
            area_mm2: s.area_mm2,
        });
    }
    // Each mark against the map fitted to the others.
    for i in 0..marks.len() {
        let others = |v: Vec<[f64; 2]>| -> Vec<[f64; 2]> {
            v.into_iter().enumerate().filter(|(k, _)| *k != i).map(|(_, p)| p).collect()
        };
        let paper = others(marks.iter().map(|m| m.centre_mm).collect());
        let photo = others(measured.iter().map(|m| m.photo).collect());
        let h_i = Homography::fit(&paper, &photo).and_then(|h| h.inverse()).ok_or(ObserveError::Degenerate)?;
        let p = h_i.apply(measured[i].photo);
        let e = (p[0] - marks[i].centre_mm[0]).hypot(p[1] - marks[i].centre_mm[1]);
        fitted[i].leave_one_out_mm = if e.is_finite() { e } else { f64::INFINITY };
    }
    let errs: Vec<f64> = fitted.iter().map(|f| f.error_mm[0].hypot(f.error_mm[1])).collect();
    let residual_rms_mm = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    let (worst, &residual_max_mm) = errs.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).expect("marks");
    if !(residual_max_mm <= RESIDUAL_LIMIT_MM) {
        return Err(ObserveError::Residual {
            role: fitted[worst].role.clone(),
            error_mm: residual_max_mm,
            limit_mm: RESIDUAL_LIMIT_MM,
        });
    }
    let mut edges: Vec<f64> = measured.iter().map(|m| m.edge_mm).collect();
    edges.sort_by(f64::total_cmp);
    let edge_mm = edges[edges.len() / 2];
    if !(edge_mm <= BLUR_LIMIT_MM) {
        return Err(ObserveError::Blurred { edge_mm, limit_mm: BLUR_LIMIT_MM });
    }
    let (far, leave_one_out_max_mm) = fitted
        .iter()
        .enumerate()
        .map(|(i, f)| (i, f.leave_one_out_mm))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("marks");
    if !(leave_one_out_max_mm <= LEAVE_ONE_OUT_LIMIT_MM) {
        return Err(ObserveError::Misplaced {
            role: fitted[far].role.clone(),
            error_mm: leave_one_out_max_mm,
            limit_mm: LEAVE_ONE_OUT_LIMIT_MM,
        });
    }
    let mid = [
        marks[..4].iter().map(|m| m.centre_mm[0]).sum::<f64>() / 4.0,
        marks[..4].iter().map(|m| m.centre_mm[1]).sum::<f64>() / 4.0,
    ];
    Ok(Registration {
        paper_to_photo: h,
        marks: fitted,
        residual_rms_mm,
        residual_max_mm,
        leave_one_out_max_mm,
        edge_mm,
        px_per_mm: h.scale_at(mid),
        corner_shift,
    })
}

/// The blobs of ink (coverage ≥ ½, 4-connected) on the sheet, at least 20 px each.
fn blobs(ink: &InkMap) -> Vec<Blob> {
    let (w, h) = (ink.width, ink.height);
    let mask: Vec<bool> = ink.ink.iter().map(|&v| v >= 0.5).collect();
    let (label, sizes) = connected_components(&mask, w, h, true);
    let mut sx = vec![0f64; sizes.len()];
    let mut sy = vec![0f64; sizes.len()];
    for (i, &l) in label.iter().enumerate() {
        if l != 0 {
            sx[l as usize] += (i % w) as f64 + 0.5;
            sy[l as usize] += (i / w) as f64 + 0.5;
        }
    }
    (1..sizes.len())
        .filter(|&l| sizes[l] >= 20)
        .map(|l| Blob { c: [sx[l] / sizes[l] as f64, sy[l] / sizes[l] as f64], px: sizes[l] })
        .collect()
}

/// The four blobs, in the order of the convex hull (clockwise on the image), spanning the
/// largest quadrilateral.
fn largest_quad(blobs: &[Blob]) -> Option<[usize; 4]> {
    let hull = hull(blobs);
    if hull.len() < 4 {
        return None;
    }
    let area = |q: [usize; 4]| {
        let p: Vec<[f64; 2]> = q.iter().map(|&i| blobs[i].c).collect();
        (0..4).map(|i| p[i][0] * p[(i + 1) % 4][1] - p[(i + 1) % 4][0] * p[i][1]).sum::<f64>() / 2.0
    };
    let n = hull.len();
    let mut best = None;
    let mut best_a = 0.0;
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let q = [hull[a], hull[b], hull[c], hull[d]];
                    let s = area(q);
                    if s.abs() > best_a {
                        best_a = s.abs();
                        best = Some(if s > 0.0 { q } else { [q[0], q[3], q[2], q[1]] });
                    }
                }
            }
        }
    }
    best
}

/// The convex hull's vertices (indices), no collinear ones.
fn hull(blobs: &[Blob]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..blobs.len()).collect();
    idx.sort_by(|&a, &b| blobs[a].c[0].total_cmp(&blobs[b].c[0]).then(blobs[a].c[1].total_cmp(&blobs[b].c[1])));
    let cross = |o: usize, a: usize, b: usize| {
        let (o, a, b) = (blobs[o].c, blobs[a].c, blobs[b].c);
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut lower: Vec<usize> = Vec::new();
    for &i in &idx {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], i) <= 0.0 {
            lower.pop();
        }
        lower.push(i);
    }
    let mut upper: Vec<usize> = Vec::new();
    for &i in idx.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], i) <= 0.0 {
            upper.pop();
        }
        upper.push(i);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    // Hulls of fewer than four distinct points are of no use; the few hull vertices of a sheet
    // keep the search over quadrilaterals small, but cap it anyway.
    if lower.len() > 40 {
        lower.sort_by(|&a, &b| blobs[b].px.cmp(&blobs[a].px));
        lower.truncate(40);
    }
    lower
}

struct Measured {
    photo: [f64; 2],
    area_mm2: f64,
    edge_mm: f64,
}

/// A mark's centre of ink, area and edge width, measured on the paper through `h`.
fn measure(ink: &InkMap, h: &Homography, m: &KnownMark) -> Measured {
    let (hx, hy) = (m.half_length_mm + WINDOW_MM[0], m.half_width_mm + WINDOW_MM[1]);
    let step = 1.0 / WINDOW_PX_PER_MM;
    let (nx, ny) = ((2.0 * hx / step) as usize, (2.0 * hy / step) as usize);
    let mut img = vec![0f32; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let p = [m.centre_mm[0] - hx + (i as f64 + 0.5) * step, m.centre_mm[1] - hy + (j as f64 + 0.5) * step];
            let q = h.apply(p);
            img[j * nx + i] = ink.sample(q[0], q[1]);
        }
    }
    // Centre of ink: coverage weights, faint noise left out.
    let (mut s, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for j in 0..ny {
        for i in 0..nx {
            let v = img[j * nx + i] as f64;
            let v = if v < 0.1 { 0.0 } else { v };
            s += v;
            sx += v * (i as f64 + 0.5);
            sy += v * (j as f64 + 0.5);
        }
    }
    let centre =
        if s > 0.0 { [m.centre_mm[0] - hx + sx / s * step, m.centre_mm[1] - hy + sy / s * step] } else { m.centre_mm };
    // Edge sharpness: across the bar (along paper y), the steepest rise in each column that
    // reaches full ink, median over the columns.
    let mut slopes = Vec::new();
    for i in 0..nx {
        let col: Vec<f32> = (0..ny).map(|j| img[j * nx + i]).collect();
        if col.iter().cloned().fold(0.0, f32::max) < 0.9 {
            continue;
        }
        let g = (1..ny - 1).map(|j| ((col[j + 1] - col[j - 1]) as f64).abs() / (2.0 * step)).fold(0.0, f64::max);
        slopes.push(g);
    }
    slopes.sort_by(f64::total_cmp);
    let edge_mm = match slopes.get(slopes.len() / 2) {
        Some(&g) if g > 0.0 => 1.0225 / g,
        _ => f64::INFINITY,
    };
    Measured { photo: h.apply(centre), area_mm2: s * step * step, edge_mm }
}
