//! Stroke templates registered onto a target glyph (`--from template`).
//!
//! A character's stroke medians (hanzi-writer-data: the *template*) are carried onto another
//! glyph of the same character (a font outline or an image bitmap: the *target*) in three steps,
//! all in the em frame (1024 units, y down; docs/contracts.md §2):
//!
//! 1. **Global affine fit.** Both glyphs are rasterised at [`TemplateOptions::fit_px`]; the start
//!    maps the template ink's centroid and per-axis spread onto the target's, then Nelder–Mead
//!    maximises the symmetric overlap of the two inks, each blurred by a Gaussian (coarse, then
//!    fine): the mean of the target's blurred ink under the moved template ink plus the mean of
//!    the template's blurred ink under the target ink pulled back.
//! 2. **Non-rigid fit.** Coherent point drift (Myronenko & Song 2010, the non-rigid form) moves
//!    the template's median points (after step 1) onto the target's skeleton points, a Gaussian
//!    displacement field of width [`TemplateOptions::cpd_beta_em`] regularised by
//!    [`TemplateOptions::cpd_lambda`], with an outlier weight for skeleton spurs.
//! 3. **Ridge snap.** Each moved stroke is resampled, points off the target's ink at the ends are
//!    trimmed, every point climbs across the stroke to the nearest ridge of the target ink's
//!    distance transform, the shifts are smoothed along the stroke, and the ridge height is the
//!    half-width. Ends run out into the end caps and corners into their knobs as for the other
//!    methods.
//!
//! Stroke count and order are the template's. A stroke with too little target ink under it
//! after step 2 is kept (moved, not snapped, with a typical width) and reported in
//! [`StrokeFit::found_ink`]; a stroke that lies along another one after snapping is reported in
//! [`StrokeFit::doubled_with`]. Everything is deterministic (no randomness, fixed iteration
//! counts).

use kurbo::{Affine, Point};

use crate::glyph::{EM, Glyph, Shape};
use crate::{StrokePath, TrajectoryError, distance, raster, thinning};

mod cpd;
mod global;
mod ridge;

use cpd::Cpd;
use global::global_fit;
use ridge::{extend_ends_own, own_margin_px, snap_to_ridge};

/// Settings of [`register_template`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateOptions {
    /// Raster (px per em box) of the target's ink, distance transform and ridge snap.
    pub analysis_px: u32,
    /// Raster (px per em box) of the global fit.
    pub fit_px: u32,
    /// Raster (px per em box) of the target skeleton that the non-rigid fit pulls towards.
    pub skeleton_px: u32,
    /// Width of the Gaussian displacement kernel of the non-rigid fit, em units.
    pub cpd_beta_em: f64,
    /// Smoothness weight of the non-rigid fit (larger: stiffer).
    pub cpd_lambda: f64,
    /// Outlier weight of the non-rigid fit, 0..1 (the share of target points explained by noise).
    pub cpd_outlier: f64,
    /// Iterations of the non-rigid fit (0 skips it).
    pub cpd_iters: usize,
    /// A stroke with less than this share of its moved centre line on the target ink is reported
    /// as finding no ink.
    pub min_ink_fraction: f64,
}

impl Default for TemplateOptions {
    fn default() -> Self {
        Self {
            analysis_px: crate::DEFAULT_ANALYSIS_PX,
            fit_px: 128,
            skeleton_px: 256,
            cpd_beta_em: 160.0,
            cpd_lambda: 8.0,
            cpd_outlier: 0.2,
            cpd_iters: 40,
            min_ink_fraction: 0.5,
        }
    }
}

/// What registration found for one template stroke (index = its place in writing order, from 0).
/// Serialises as the `report.json` entry (`{"ink_fraction", "found_ink", "doubled_with", "snap_em"}`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StrokeFit {
    /// Share (0..1) of the stroke's moved centre line (after steps 1 and 2) lying on target ink.
    pub ink_fraction: f64,
    /// Whether that share reached [`TemplateOptions::min_ink_fraction`]; a stroke without ink is
    /// kept in the output where the template put it, not snapped.
    pub found_ink: bool,
    /// Another stroke (index from 0) along which this one lies after snapping (most of its points
    /// within half its width of that stroke's centre line): two template strokes landed on one
    /// target stroke.
    pub doubled_with: Option<usize>,
    /// Mean distance the ridge snap moved the stroke's points, em units.
    pub snap_em: f64,
}

/// The result of [`register_template`]: centre lines as [`crate::centre_lines`] returns them, plus what
/// the registration measured.
#[derive(Clone, Debug)]
pub struct Registration {
    /// Centre lines with half-widths, one per template stroke, in the template's order.
    pub paths: Vec<StrokePath>,
    /// Per stroke, in the same order.
    pub strokes: Vec<StrokeFit>,
    /// The global fit, template em frame → target em frame, as kurbo's affine coefficients
    /// `[a, b, c, d, e, f]`: `x' = a·x + c·y + e`, `y' = b·x + d·y + f`.
    pub affine: [f64; 6],
    /// Symmetric blurred-ink overlap (0..1) of the start and of the global fit.
    pub overlap_start: f64,
    /// See [`Registration::overlap_start`].
    pub overlap_fit: f64,
    /// Mean displacement of the non-rigid fit over the template's skeleton points, em units.
    pub nonrigid_mean_em: f64,
    /// Share (0..1) of the target's ink farther than 1.5 local half-widths (plus 2 px) from every
    /// registered centre line: ink the template does not explain. High when the target draws
    /// another form of the character (UKai's 真 is 眞) or has extra strokes.
    pub uncovered_ink: f64,
}

impl Registration {
    /// Indices (from 0) of strokes that found no ink under them.
    pub fn missing(&self) -> Vec<usize> {
        self.strokes.iter().enumerate().filter(|(_, s)| !s.found_ink).map(|(i, _)| i).collect()
    }

    /// Whether every stroke found ink and none lies along another: the template's stroke count
    /// holds on the target.
    pub fn strokes_ok(&self) -> bool {
        self.strokes.iter().all(|s| s.found_ink && s.doubled_with.is_none())
    }
}

/// The glyph as a target: its shape only (no medians or per-stroke outlines), as a font or an
/// image would give it. Used to register a hanzi-writer glyph onto itself.
pub fn shape_only(g: &Glyph) -> Glyph {
    let shape = match &g.shape {
        Shape::Outlines(o) => Shape::Outlines(o.clone()),
        Shape::Bitmap { size, ink } => Shape::Bitmap { size: *size, ink: ink.clone() },
    };
    Glyph { ch: g.ch, source: g.source.clone(), shape, stroke_outlines: None, medians: None }
}

/// Registers the stroke medians of `template` onto `target` (see the module docs).
///
/// # Errors
/// [`TrajectoryError::NoMedians`] when the template has no medians; [`TrajectoryError::Empty`]
/// when either glyph has no ink at the fit raster.
pub fn register_template(
    template: &Glyph,
    target: &Glyph,
    opts: &TemplateOptions,
) -> Result<Registration, TrajectoryError> {
    let medians =
        template.medians.as_ref().ok_or_else(|| TrajectoryError::NoMedians(template.source.kind().to_string()))?;
    // 1. Global affine fit.
    let global = global_fit(template, target, opts)?;
    let affine = Affine::new(global.coeffs);
    // 2. Non-rigid fit of the moved medians onto the target skeleton.
    let (field, nonrigid_mean_em) = nonrigid_fit(template, target, affine, opts);
    // 3. Snap onto the target's distance ridge.
    let ink = TargetInk::new(target, opts.analysis_px)?;
    let warp = |p: Point| {
        let q = affine * p;
        field.as_ref().map_or(q, |f| q + f.displacement(q))
    };
    let (lines, mut fits): (Vec<Line>, Vec<StrokeFit>) = medians
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let moved: Vec<Point> = m.iter().map(|&p| affine * p).collect();
            let outline = template.stroke_outlines.as_ref().and_then(|o| o.get(i));
            place_stroke(&moved, outline, field.as_ref(), &warp, &ink, opts)
        })
        .unzip();
    let paths = finish_lines(lines, &ink);
    mark_doubled(&paths, &mut fits);
    let uncovered_ink = uncovered(&paths, &ink.mask, ink.n, ink.px_to_em);
    Ok(Registration {
        paths,
        strokes: fits,
        affine: global.coeffs,
        overlap_start: global.overlap_start,
        overlap_fit: global.overlap_fit,
        nonrigid_mean_em,
        uncovered_ink,
    })
}

/// The target's ink on the analysis raster (`n × n` px over the em box), as stage 3 reads it.
struct TargetInk {
    n: usize,
    /// Em units per pixel.
    px_to_em: f64,
    mask: Vec<bool>,
    /// Distance to the paper, px: its ridge is where centre lines snap to.
    dt: Vec<f32>,
    /// Distance to the ink, px, for the check after the global fit.
    to_ink: Vec<f32>,
}

impl TargetInk {
    /// `target` rendered at `analysis_px` (at least 32) px per em box.
    ///
    /// # Errors
    /// [`TrajectoryError::Empty`] when it has no ink.
    fn new(target: &Glyph, analysis_px: u32) -> Result<Self, TrajectoryError> {
        let n = analysis_px.max(32) as usize;
        let mask = raster::mask_of(&raster::render_glyph(target, n as u32));
        if !mask.iter().any(|&b| b) {
            return Err(TrajectoryError::Empty(target.ch));
        }
        let dt = distance::distance_to_background(&mask, n, n);
        let paper: Vec<bool> = mask.iter().map(|&b| !b).collect();
        let to_ink = distance::distance_to_background(&paper, n, n);
        Ok(Self { n, px_to_em: EM / n as f64, mask, dt, to_ink })
    }

    /// How deep `p` (em) lies in the ink: the distance to the paper, px.
    fn depth(&self, p: Point) -> f64 {
        distance::sample(&self.dt, self.n, self.n, p.x / self.px_to_em, p.y / self.px_to_em)
    }

    /// Whether `p` (em) lies within [`NEAR_INK_EM`] of the ink.
    fn near(&self, p: Point) -> bool {
        distance::sample(&self.to_ink, self.n, self.n, p.x / self.px_to_em, p.y / self.px_to_em) * self.px_to_em
            <= NEAR_INK_EM
    }
}

/// One stroke after [`place_stroke`]: its centre line (em) and, when it found ink, its
/// half-widths (em) and the distance transform of its own ink (px; `None`: no own ink, the
/// whole target's is used).
type Line = (Vec<Point>, Option<(Vec<f64>, Option<Vec<f32>>)>);

/// Stage 3 for one stroke: its median `moved` by the global fit, then by `field` (the
/// non-rigid fit) is checked for ink under it, trimmed to its longest run on the ink, snapped to
/// the target's ridge and re-centred on its own ink (the target's ink near the template's stroke
/// `outline` carried over by `warp`, both fits), without folds.
fn place_stroke(
    moved: &[Point],
    outline: Option<&kurbo::BezPath>,
    field: Option<&Cpd>,
    warp: &impl Fn(Point) -> Point,
    ink: &TargetInk,
    opts: &TemplateOptions,
) -> (Line, StrokeFit) {
    let (n, px_to_em) = (ink.n, ink.px_to_em);
    let placed = crate::medians::densify(moved, crate::medians::MEDIAN_STEP_EM);
    let near = placed.iter().filter(|&&p| ink.near(p)).count() as f64 / placed.len() as f64;
    let pts: Vec<Point> = placed.iter().map(|&p| field.map_or(p, |f| p + f.displacement(p))).collect();
    let on_ink = pts.iter().filter(|&&p| ink.depth(p) >= 1.0).count();
    let ink_fraction = on_ink as f64 / pts.len() as f64;
    // No ink near where the global fit put it, or none under it after the non-rigid fit (which
    // can drag a stroke with no counterpart onto a neighbour's ink: the first test).
    let found_ink = near >= opts.min_ink_fraction && ink_fraction >= opts.min_ink_fraction && on_ink >= 2;
    if !found_ink {
        let fit = StrokeFit { ink_fraction: ink_fraction.min(near), found_ink, doubled_with: None, snap_em: 0.0 };
        return ((pts, None), fit);
    }
    // Keep the longest run on ink (gaps of up to two points bridged): the ends that hang off
    // the ink (the template stroke was longer than the target's) go, and so does a piece the
    // non-rigid fit pulled across paper onto a neighbouring stroke.
    let (first, last) = longest_ink_run(&pts, |p| ink.depth(p) >= 1.0);
    let pts = pts[first..=last].to_vec();
    let (snapped, _) = snap_to_ridge(&pts, &ink.dt, n, px_to_em);
    let snap_em = pts.iter().zip(&snapped).map(|(a, b)| a.distance(*b)).sum::<f64>() / pts.len() as f64;
    // The stroke's own ink: the target's ink near the template's stroke outline carried over by
    // both fits, so a crossing stroke neither widens it nor lets its ends run on.
    let own = outline.and_then(|o| {
        let warped = warp_path(o, warp);
        let omask = raster::mask_of(&raster::render_outlines(std::slice::from_ref(&warped), n as u32));
        let outside: Vec<bool> = omask.iter().map(|&b| !b).collect();
        let to_outline = distance::distance_to_background(&outside, n, n);
        let margin_px = own_margin_px(&snapped, &ink.dt, &omask, n, px_to_em);
        let region: Vec<bool> = ink.mask.iter().zip(&to_outline).map(|(&m, &d)| m && (d as f64) <= margin_px).collect();
        region.iter().any(|&b| b).then(|| distance::distance_to_background(&region, n, n))
    });
    // On the stroke's own ink, re-centre from where the fits put it (the snap on the whole
    // ink bends towards a crossing stroke's ridge and leaves kinks that read as corners).
    let (p, w) = match &own {
        Some(sdt) => crate::medians::centre_on_ridge(&pts, sdt, n, px_to_em),
        None => crate::medians::centre_on_ridge(&snapped, &ink.dt, n, px_to_em),
    };
    let (p, w) = unfold(p, w);
    ((p, Some((w, own))), StrokeFit { ink_fraction, found_ink, doubled_with: None, snap_em })
}

/// The strokes' final centre lines: those with ink run out at their ends on their own ink and
/// get knobs at their corners; those without get the median half-width of the others; no
/// width changes faster than [`MAX_WIDTH_SLOPE`].
fn finish_lines(lines: Vec<Line>, ink: &TargetInk) -> Vec<StrokePath> {
    let (n, px_to_em) = (ink.n, ink.px_to_em);
    let mut all_w: Vec<f64> =
        lines.iter().filter_map(|(_, w)| w.as_ref()).flat_map(|(w, _)| w.iter()).copied().collect();
    all_w.sort_by(f64::total_cmp);
    let typical = if all_w.is_empty() { 20.0 } else { all_w[all_w.len() / 2] };
    let mut paths = Vec::with_capacity(lines.len());
    for (pts, widths) in lines {
        match widths {
            Some((w, own)) => {
                let sdt = own.as_ref().unwrap_or(&ink.dt);
                let (p, w) = extend_ends_own(pts, w, sdt, n, px_to_em);
                paths.push(crate::medians::knob_corners(p, w, sdt, n, px_to_em));
            }
            None => {
                let w = vec![typical; pts.len()];
                paths.push(StrokePath::new(pts, w));
            }
        }
    }
    // Widths that jump (a thin run-out into a swollen body) make track building's press sizing
    // jump too, past the robot's depth-rate limit.
    for p in &mut paths {
        limit_width_slope(&p.points, &mut p.half_widths, MAX_WIDTH_SLOPE);
    }
    paths
}

/// Stage 2 of [`register_template`]: the non-rigid field (CPD) taking the template's skeleton, moved by
/// `affine`, onto the target's, and its mean displacement (em); `None` when it is switched off
/// or there is too little skeleton.
fn nonrigid_fit(template: &Glyph, target: &Glyph, affine: Affine, opts: &TemplateOptions) -> (Option<Cpd>, f64) {
    // Like with like: the template's skeleton (moved) against the target's, so a glyph registered
    // onto itself stays put; the field then carries the medians.
    let sk_n = opts.skeleton_px.max(32) as usize;
    // Both thinned on one grid (cells of the same size), so the two samplings have one density.
    let (t_skel, g_skel) = (skeleton_points(template, sk_n), skeleton_points(target, sk_n));
    let px_em = EM / sk_n as f64;
    let cell = (1..=16).find(|&c| thinning::grid_thin(&t_skel, c, px_em).len() <= 400).unwrap_or(16);
    let ctrl: Vec<Point> = thinning::grid_thin(&t_skel, cell, px_em).into_iter().map(|p| affine * p).collect();
    let skel = thinning::grid_thin(&g_skel, cell, px_em);
    let field = if opts.cpd_iters > 0 && !skel.is_empty() && ctrl.len() >= 3 {
        Some(Cpd::fit(&ctrl, &skel, opts))
    } else {
        None
    };
    let nonrigid_mean_em = field
        .as_ref()
        .map_or(0.0, |f| ctrl.iter().map(|&p| f.displacement(p).hypot()).sum::<f64>() / ctrl.len() as f64);
    (field, nonrigid_mean_em)
}

/// The share of ink pixels of `mask` (`n × n`) outside discs of radius 1.5·half-width + 2 px
/// around every centre-line point.
fn uncovered(paths: &[StrokePath], mask: &[bool], n: usize, px_to_em: f64) -> f64 {
    let mut cov = vec![false; n * n];
    for p in paths {
        for (q, w) in p.points.iter().zip(&p.half_widths) {
            let r = 1.5 * w / px_to_em + 2.0;
            let (cx, cy) = (q.x / px_to_em, q.y / px_to_em);
            let (x0, x1) = ((cx - r).floor().max(0.0) as usize, ((cx + r).ceil().max(0.0) as usize).min(n));
            let (y0, y1) = ((cy - r).floor().max(0.0) as usize, ((cy + r).ceil().max(0.0) as usize).min(n));
            for y in y0..y1 {
                for x in x0..x1 {
                    if (x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2) <= r * r {
                        cov[y * n + x] = true;
                    }
                }
            }
        }
    }
    let ink = mask.iter().filter(|&&b| b).count();
    let left = mask.iter().zip(&cov).filter(|&(&m, &c)| m && !c).count();
    if ink == 0 { 0.0 } else { left as f64 / ink as f64 }
}

/// A stroke with less than [`TemplateOptions::min_ink_fraction`] of its centre line within this
/// distance of target ink after the global fit (em units, about a stroke's width) finds no ink.
const NEAR_INK_EM: f64 = 24.0;

/// The most a registered stroke's half-width changes per em of its length (em/em), a forward
/// and backward pass lowering the wider side, so that a thin run-out next to a swollen body
/// does not make the track's press jump faster than the robot check allows. Chosen on the
/// tuning set (docs/trajectory.md, Tuned constants).
const MAX_WIDTH_SLOPE: f64 = 1.0;

/// Removes the folds re-centring can leave in a line: a point where the line turns back on
/// itself (the segments before and after it point more than 90° apart) and one of those two
/// segments is shorter than [`FOLD_EM`]. Re-centring moves neighbouring points by different
/// amounts along their normals; where those cross, the line doubles back by a few em units, and
/// track building's trailing press, sized from the width a footprint length behind, would jump
/// at the fold past the robot's depth-rate limit. Real turns (hooks, 折) are longer than that on
/// both sides. Repeats until none is left; the ends stay.
fn unfold(mut p: Vec<Point>, mut w: Vec<f64>) -> (Vec<Point>, Vec<f64>) {
    let mut i = 1;
    while i + 1 < p.len() {
        let (a, b) = (p[i] - p[i - 1], p[i + 1] - p[i]);
        if a.dot(b) < 0.0 && a.hypot().min(b.hypot()) < FOLD_EM {
            p.remove(i);
            w.remove(i);
            i = i.saturating_sub(1).max(1);
        } else {
            i += 1;
        }
    }
    (p, w)
}

/// The longest segment next to a turn back that [`unfold`] treats as a fold, em units: half the
/// medians' resampling step (8 em; segments that short come from re-centring, not from the
/// template's line). Hand-set.
const FOLD_EM: f64 = 4.0;

/// Lowers the half-widths `w` (em) along the line `p` until none changes by more than `slope`
/// em per em of arc length (a forward and a backward pass).
fn limit_width_slope(p: &[Point], w: &mut [f64], slope: f64) {
    for i in 1..p.len() {
        w[i] = w[i].min(w[i - 1] + slope * p[i].distance(p[i - 1]));
    }
    for i in (0..p.len().saturating_sub(1)).rev() {
        w[i] = w[i].min(w[i + 1] + slope * p[i].distance(p[i + 1]));
    }
}

/// A path with every point moved by `f`.
fn warp_path(p: &kurbo::BezPath, f: &impl Fn(Point) -> Point) -> kurbo::BezPath {
    use kurbo::PathEl;
    p.elements()
        .iter()
        .map(|el| match *el {
            PathEl::MoveTo(a) => PathEl::MoveTo(f(a)),
            PathEl::LineTo(a) => PathEl::LineTo(f(a)),
            PathEl::QuadTo(a, b) => PathEl::QuadTo(f(a), f(b)),
            PathEl::CurveTo(a, b, c) => PathEl::CurveTo(f(a), f(b), f(c)),
            PathEl::ClosePath => PathEl::ClosePath,
        })
        .collect()
}

/// The first and last index of the longest run of points (by arc length) that are on ink, runs
/// joined across gaps of at most two points off ink.
fn longest_ink_run(p: &[Point], on: impl Fn(Point) -> bool) -> (usize, usize) {
    let ink: Vec<bool> = p.iter().map(|&q| on(q)).collect();
    let (mut best, mut best_len) = ((0, p.len() - 1), -1.0);
    let mut i = 0;
    while i < p.len() {
        if !ink[i] {
            i += 1;
            continue;
        }
        let start = i;
        let mut end = i;
        let mut j = i + 1;
        while j < p.len() {
            if ink[j] {
                end = j;
                j += 1;
            } else if j + 2 < p.len() && (ink[j + 1] || ink[j + 2]) {
                j += 1;
            } else {
                break;
            }
        }
        let len: f64 = p[start..=end].windows(2).map(|w| w[0].distance(w[1])).sum();
        if len > best_len {
            best = (start, end);
            best_len = len;
        }
        i = end + 1;
    }
    best
}

/// A glyph's skeleton pixels (Zhang–Suen at `n²`): pixel centres, px.
fn skeleton_points(target: &Glyph, n: usize) -> Vec<(usize, usize)> {
    let mut mask = raster::mask_of(&raster::render_glyph(target, n as u32));
    thinning::zhang_suen(&mut mask, n, n);
    thinning::remove_staircases(&mut mask, n, n);
    (0..n * n).filter(|&i| mask[i]).map(|i| (i % n, i / n)).collect()
}

/// Marks strokes lying along another stroke: at least 70 % of the points of the shorter one
/// within half its local width of the other's centre line.
fn mark_doubled(paths: &[StrokePath], fits: &mut [StrokeFit]) {
    let len = |p: &StrokePath| p.points.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
    for i in 0..paths.len() {
        if !fits[i].found_ink || paths[i].points.is_empty() {
            continue;
        }
        for j in 0..paths.len() {
            if i == j || !fits[j].found_ink || paths[j].points.is_empty() || len(&paths[i]) > len(&paths[j]) {
                continue;
            }
            if len(&paths[i]) == len(&paths[j]) && i < j {
                continue;
            }
            let near = paths[i]
                .points
                .iter()
                .zip(&paths[i].half_widths)
                .filter(|&(p, w)| paths[j].points.iter().any(|q| p.distance(*q) <= 0.5 * w.max(4.0)))
                .count();
            if near as f64 >= 0.7 * paths[i].points.len() as f64 {
                fits[i].doubled_with = Some(j);
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_fold_is_removed_and_a_hook_kept() {
        // Down 60 em, back up 3 em, down again: the fold goes.
        let mut p: Vec<Point> = (0..=6).map(|i| Point::new(100.0, 100.0 + 10.0 * i as f64)).collect();
        p.insert(4, Point::new(100.5, 127.0));
        let w = vec![10.0; p.len()];
        let (q, v) = unfold(p, w);
        assert_eq!(q.len(), v.len());
        assert!(q.windows(2).all(|s| s[1].y > s[0].y), "{q:?}");
        // A hook: down 60 em, then 30 em back up and left in steps of 10 em: kept.
        let mut h: Vec<Point> = (0..=6).map(|i| Point::new(100.0, 100.0 + 10.0 * i as f64)).collect();
        h.extend((1..=3).map(|i| Point::new(100.0 - 7.0 * i as f64, 160.0 - 7.0 * i as f64)));
        let (k, _) = unfold(h.clone(), vec![10.0; h.len()]);
        assert_eq!(k, h);
    }

    #[test]
    fn the_longest_ink_run_bridges_short_gaps() {
        let p: Vec<Point> = (0..20).map(|i| Point::new(i as f64, 0.0)).collect();
        // Ink at 0..=3, 5..=9 (one-point gap at 4: bridged), then 13..=15 after a three-point gap.
        let ink = |q: Point| matches!(q.x as i64, 0..=3 | 5..=9 | 13..=15);
        assert_eq!(longest_ink_run(&p, ink), (0, 9));
        assert_eq!(longest_ink_run(&p, |q| q.x >= 17.0), (17, 19));
    }

    #[test]
    fn cpd_recovers_a_shift_on_and_off_the_points() {
        // An L of points, and the same L moved by (14, −9) em units with its foot bent a little.
        let mut y = Vec::new();
        for i in 0..40 {
            y.push(Point::new(300.0, 200.0 + 10.0 * i as f64));
        }
        for i in 1..40 {
            y.push(Point::new(300.0 + 10.0 * i as f64, 590.0));
        }
        let x: Vec<Point> = y.iter().map(|p| Point::new(p.x + 14.0, p.y - 9.0 + 0.02 * (p.x - 300.0))).collect();
        let f = Cpd::fit(&y, &x, &TemplateOptions::default());
        // Point-to-curve matching sees motion across a line, not along it: check each arm's
        // normal component (the vertical arm's x, the horizontal arm's y).
        for (k, (a, b)) in y.iter().zip(&x).enumerate() {
            let moved = *a + f.displacement(*a);
            let err = if k < 40 { moved.x - b.x } else { moved.y - b.y };
            assert!(err.abs() < 3.0, "{k}: {a:?} → {moved:?}, want {b:?}");
        }
        // Beside the points (where stroke outlines lie) the field moves as it does on them.
        let d = f.displacement(Point::new(325.0, 400.0));
        assert!((d.x - 14.0).abs() < 3.0, "{d:?}");
    }
}
