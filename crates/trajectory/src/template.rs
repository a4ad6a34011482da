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

use kurbo::{Affine, Point, Vec2};

use crate::glyph::{EM, Glyph, Shape};
use crate::{StrokePath, TrajectoryError, distance, raster, thinning};

mod cpd;

use cpd::Cpd;

/// Settings of [`register`].
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

/// The result of [`register`]: centre lines as [`crate::centre_lines`] returns them, plus what
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
pub fn register(template: &Glyph, target: &Glyph, opts: &TemplateOptions) -> Result<Registration, TrajectoryError> {
    let medians =
        template.medians.as_ref().ok_or_else(|| TrajectoryError::NoMedians(template.source.kind().to_string()))?;
    // 1. Global affine fit.
    let global = global_fit(template, target, opts)?;
    let (q, affine) = (global.coeffs, Affine::new(global.coeffs));
    // 2. Non-rigid fit of the moved medians onto the target skeleton.
    let moved: Vec<Vec<Point>> = medians.iter().map(|m| m.iter().map(|&p| affine * p).collect()).collect();
    let (field, nonrigid_mean_em) = nonrigid_fit(template, target, affine, opts);
    // 3. Snap onto the target's distance ridge.
    let n = opts.analysis_px.max(32) as usize;
    let px_to_em = EM / n as f64;
    let mask = raster::mask_of(&raster::render_glyph(target, n as u32));
    if !mask.iter().any(|&b| b) {
        return Err(TrajectoryError::Empty(target.ch));
    }
    let dt = distance::distance_to_background(&mask, n, n);
    let at = |p: Point| distance::sample(&dt, n, n, p.x / px_to_em, p.y / px_to_em);
    // Distance to the nearest ink, for the check after the global fit.
    let paper: Vec<bool> = mask.iter().map(|&b| !b).collect();
    let to_ink = distance::distance_to_background(&paper, n, n);
    let ink_near = |p: Point| distance::sample(&to_ink, n, n, p.x / px_to_em, p.y / px_to_em) * px_to_em <= NEAR_INK_EM;
    let warp = |p: Point| {
        let q = affine * p;
        field.as_ref().map_or(q, |f| q + f.displacement(q))
    };
    let mut lines = Vec::with_capacity(moved.len());
    let mut fits = Vec::with_capacity(moved.len());
    for (i, m) in moved.iter().enumerate() {
        let placed = crate::medians::densify(m, crate::medians::MEDIAN_STEP_EM);
        let near = placed.iter().filter(|&&p| ink_near(p)).count() as f64 / placed.len() as f64;
        let pts: Vec<Point> = placed.iter().map(|&p| field.as_ref().map_or(p, |f| p + f.displacement(p))).collect();
        let on_ink = pts.iter().filter(|&&p| at(p) >= 1.0).count();
        let ink_fraction = on_ink as f64 / pts.len() as f64;
        // No ink near where the global fit put it, or none under it after the non-rigid fit (which
        // can drag a stroke with no counterpart onto a neighbour's ink: the first test).
        let found_ink = near >= opts.min_ink_fraction && ink_fraction >= opts.min_ink_fraction && on_ink >= 2;
        if !found_ink {
            lines.push((pts, None));
            fits.push(StrokeFit { ink_fraction: ink_fraction.min(near), found_ink, doubled_with: None, snap_em: 0.0 });
            continue;
        }
        // Keep the longest run on ink (gaps of up to two points bridged): the ends that hang off
        // the ink (the template stroke was longer than the target's) go, and so does a piece the
        // non-rigid fit pulled across paper onto a neighbouring stroke.
        let (first, last) = longest_ink_run(&pts, |p| at(p) >= 1.0);
        let pts = pts[first..=last].to_vec();
        let (snapped, _) = snap_to_ridge(&pts, &dt, n, px_to_em);
        let snap_em = pts.iter().zip(&snapped).map(|(a, b)| a.distance(*b)).sum::<f64>() / pts.len() as f64;
        // The stroke's own ink: the target's ink near the template's stroke outline carried over by
        // both fits, so a crossing stroke neither widens it nor lets its ends run on.
        let own = template.stroke_outlines.as_ref().and_then(|o| o.get(i)).and_then(|o| {
            let warped = warp_path(o, &warp);
            let omask = raster::mask_of(&raster::render_outlines(std::slice::from_ref(&warped), n as u32));
            let outside: Vec<bool> = omask.iter().map(|&b| !b).collect();
            let to_outline = distance::distance_to_background(&outside, n, n);
            let margin_px = own_margin_px(&snapped, &dt, &omask, n, px_to_em);
            let region: Vec<bool> = mask.iter().zip(&to_outline).map(|(&m, &d)| m && (d as f64) <= margin_px).collect();
            region.iter().any(|&b| b).then(|| distance::distance_to_background(&region, n, n))
        });
        // On the stroke's own ink, re-centre from where the fits put it (the snap on the whole
        // ink bends towards a crossing stroke's ridge and leaves kinks that read as corners).
        let (p, w) = match &own {
            Some(sdt) => crate::medians::centre_on_ridge(&pts, sdt, n, px_to_em),
            None => crate::medians::centre_on_ridge(&snapped, &dt, n, px_to_em),
        };
        let (p, w) = unfold(p, w);
        lines.push((p, Some((w, own))));
        fits.push(StrokeFit { ink_fraction, found_ink, doubled_with: None, snap_em });
    }
    // Strokes without ink get the median half-width of the others.
    let mut all_w: Vec<f64> =
        lines.iter().filter_map(|(_, w)| w.as_ref()).flat_map(|(w, _)| w.iter()).copied().collect();
    all_w.sort_by(f64::total_cmp);
    let typical = if all_w.is_empty() { 20.0 } else { all_w[all_w.len() / 2] };
    let mut paths = Vec::with_capacity(lines.len());
    for (pts, widths) in lines {
        match widths {
            Some((w, own)) => {
                let sdt = own.as_ref().unwrap_or(&dt);
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
    mark_doubled(&paths, &mut fits);
    let uncovered_ink = uncovered(&paths, &mask, n, px_to_em);
    Ok(Registration {
        paths,
        strokes: fits,
        affine: q,
        overlap_start: global.overlap_start,
        overlap_fit: global.overlap_fit,
        nonrigid_mean_em,
        uncovered_ink,
    })
}

/// The global affine fit of [`register`] (stage 1): its coefficients and the blurred-ink
/// overlap before and after.
struct GlobalFit {
    coeffs: [f64; 6],
    overlap_start: f64,
    overlap_fit: f64,
}

/// Stage 1 of [`register`]: the affine map of the template's ink onto the target's, from the
/// moments start, Nelder–Mead on the overlap of the blurred inks at two blur widths.
fn global_fit(template: &Glyph, target: &Glyph, opts: &TemplateOptions) -> Result<GlobalFit, TrajectoryError> {
    let fit_n = opts.fit_px.max(32) as usize;
    let t_cov = raster::render_glyph(template, fit_n as u32);
    let g_cov = raster::render_glyph(target, fit_n as u32);
    let t_ink = ink_points(t_cov.data(), fit_n, 2500).ok_or(TrajectoryError::Empty(template.ch))?;
    let g_ink = ink_points(g_cov.data(), fit_n, 2500).ok_or(TrajectoryError::Empty(target.ch))?;
    let start = moment_start(t_cov.data(), g_cov.data(), fit_n);
    let mut q = start.as_coeffs();
    let mut overlap_start = None;
    let mut overlap_fit = 0.0;
    for sigma_px in [4.0, 1.5] {
        let tb = raster::gaussian_blur(t_cov.data(), fit_n, sigma_px, raster::Edge::Zero);
        let gb = raster::gaussian_blur(g_cov.data(), fit_n, sigma_px, raster::Edge::Zero);
        let score =
            |c: &[f64]| overlap(Affine::new([c[0], c[1], c[2], c[3], c[4], c[5]]), &t_ink, &g_ink, &tb, &gb, fit_n);
        overlap_start.get_or_insert_with(|| score(&q));
        let steps = [0.05, 0.05, 0.05, 0.05, 12.0, 12.0];
        let (best, val) = nelder_mead(|c| -score(c), &q, &steps, 160);
        q = best.try_into().expect("six coefficients");
        overlap_fit = -val;
    }
    Ok(GlobalFit { coeffs: q, overlap_start: overlap_start.unwrap_or(0.0), overlap_fit })
}

/// Stage 2 of [`register`]: the non-rigid field (CPD) taking the template's skeleton, moved by
/// `affine`, onto the target's, and its mean displacement (em); `None` when it is switched off
/// or there is too little skeleton.
fn nonrigid_fit(template: &Glyph, target: &Glyph, affine: Affine, opts: &TemplateOptions) -> (Option<Cpd>, f64) {
    // Like with like: the template's skeleton (moved) against the target's, so a glyph registered
    // onto itself stays put; the field then carries the medians.
    let sk_n = opts.skeleton_px.max(32) as usize;
    // Both thinned on one grid (cells of the same size), so the two samplings have one density.
    let (t_skel, g_skel) = (skeleton_points(template, sk_n), skeleton_points(target, sk_n));
    let px_em = EM / sk_n as f64;
    let cell = (1..=16).find(|&c| grid_thin(&t_skel, c, px_em).len() <= 400).unwrap_or(16);
    let ctrl: Vec<Point> = grid_thin(&t_skel, cell, px_em).into_iter().map(|p| affine * p).collect();
    let skel = grid_thin(&g_skel, cell, px_em);
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

/// A stroke's own ink is the target's ink within this distance of the template's stroke outline
/// carried over by both fits, em units.
const OWN_INK_MARGIN_EM: f64 = 10.0;

/// The own-ink margin of one stroke, px: [`OWN_INK_MARGIN_EM`] plus how much thicker the target's
/// stroke is than the template's outline carried onto it (`outline`, a mask): the difference of
/// the medians of their half-widths (distance transforms `dt` and the outline's) along the
/// snapped centre line `line`. A brush font's strokes can be twice as thick as the template's;
/// a fixed margin cut them down to the template's width.
fn own_margin_px(line: &[Point], dt: &[f32], outline: &[bool], n: usize, px_to_em: f64) -> f64 {
    let odt = distance::distance_to_background(outline, n, n);
    let median = |f: &[f32]| {
        let mut v: Vec<f64> = line.iter().map(|p| distance::sample(f, n, n, p.x / px_to_em, p.y / px_to_em)).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    OWN_INK_MARGIN_EM / px_to_em + (median(dt) - median(&odt)).max(0.0)
}

/// Continues both ends of a stroke's centre line outward along its end direction, one em unit at
/// a time, while the distance to the outline (`dt`, px, on the `n²` raster) stays above
/// [`END_STOP_FRACTION`] of the end's half-width and has not grown again by more than
/// [`RUN_OUT_REGROW_EM`] after narrowing (past a neck the line would run into other ink). Each new
/// point's half-width is the ink's half-chord across the line there, between the distance to the
/// outline and the end's half-width: a blunt or swollen terminal keeps its width out to the cap,
/// a taper narrows. (The medians method's [`crate::medians::extend_ends`] stops at 0.65 of the
/// width with the distance as the width, tuned on hanzi-writer's shapes.)
fn extend_ends_own(p: Vec<Point>, w: Vec<f64>, dt: &[f32], n: usize, px_to_em: f64) -> (Vec<Point>, Vec<f64>) {
    crate::medians::extend_ends_by(p, w, |end, u, w_end| run_out_own(end, u, w_end, dt, n, px_to_em))
}

/// The run-out of [`extend_ends_own`] from `from` along the unit direction `u`: points and
/// half-widths, em units.
fn run_out_own(from: Point, u: Vec2, w_end: f64, dt: &[f32], n: usize, px_to_em: f64) -> Vec<(Point, f64)> {
    let at = |q: Point| distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em) * px_to_em;
    let nrm = Vec2::new(-u.y, u.x);
    let mut out = Vec::new();
    let (mut q, mut lo) = (from, f64::INFINITY);
    for _ in 0..(3.0 * w_end).ceil() as usize {
        q += u;
        let v = at(q);
        if v <= END_STOP_FRACTION * w_end || v > lo + RUN_OUT_REGROW_EM {
            break;
        }
        lo = lo.min(v);
        // Half the chord of ink across the line through q (half-pixel steps, out to 2·w_end).
        let reach = |side: f64| {
            let step = 0.5 * px_to_em;
            let mut t = 0.0;
            while t < 2.0 * w_end && at(q + nrm * (side * (t + step))) > 0.0 {
                t += step;
            }
            t
        };
        let chord = 0.5 * (reach(1.0) + reach(-1.0));
        // Past the medians method's stop only while the ink keeps nearly its full width (a blunt
        // cap); a rounded or tapered end stops about where that method stops.
        if v <= crate::medians::END_CAP_FRACTION * w_end && chord < BLUNT_CHORD_FRACTION * w_end {
            break;
        }
        out.push((q, chord.clamp(v, w_end.max(v))));
    }
    out
}

/// A stroke end's run-out ([`extend_ends_own`]) stops where the distance to the outline falls to
/// this share of the end's half-width. LXGW WenKai Bold, embedded characters 1–20, executed CSIM
/// (before [`BLUNT_CHORD_FRACTION`]): 0.65 / 0.4 / 0.25 / 0.1 / 0 → 0.923 / 0.928 / 0.931 /
/// **0.935** / 0.935 (0.65 with the distance as the width, as the medians method does: 0.925).
const END_STOP_FRACTION: f64 = 0.1;

/// Past the medians method's stop ([`crate::medians::END_CAP_FRACTION`] of the end's width) a
/// run-out goes on only while the ink's half-chord across it is at least this share of the end's
/// half-width. LXGW WenKai Bold, characters 1–20: none (stop at [`END_STOP_FRACTION`] alone) 0.935,
/// 0.85 **0.930**, 0.9 0.928; at 0.8 and below hanzi-writer's own 八 lost more than 0.015 CSIM
/// against the medians method (the test on its own outline), at 0.85 none does.
const BLUNT_CHORD_FRACTION: f64 = 0.85;

/// The most a registered stroke's half-width changes per em of its length (em/em), a forward
/// and backward pass lowering the wider side. Without it a thin run-out next to a swollen body
/// made the track's press jump by 6 mm in 0.15 mm, which the robot check refuses (40 mm/mm).
/// LXGW WenKai Bold, characters 1–20: **1.0** / 0.5 → CSIM 0.927 / 0.928 (with the blunt-cap
/// share at 0.9); at 0.5 hanzi-writer's own 八 lost 0.017 CSIM against the medians method.
const MAX_WIDTH_SLOPE: f64 = 1.0;

/// A stroke end's run-out stops where its width grows again by this much (em units) after
/// narrowing: it has passed a neck into other ink. Hand-set (2 and 4 within 0.001 CSIM on LXGW
/// WenKai Bold, characters 1–20; without it a run-out into a neighbour made a press jump the
/// robot check refuses).
const RUN_OUT_REGROW_EM: f64 = 4.0;

/// Removes the folds re-centring can leave in a line: a point where the line turns back on
/// itself (the segments before and after it point more than 90° apart) and one of those two
/// segments is shorter than [`FOLD_EM`]. Re-centring moves neighbouring points by different
/// amounts along their normals; where those cross, the line doubled back by a few em units, and
/// track building's trailing press, sized from the width a footprint length behind, jumped at
/// the fold past the robot's depth-rate limit (Zhi Mang Xing's 得). Real turns (hooks, 折) are
/// longer than that on both sides. Repeats until none is left; the ends stay.
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

/// Ink pixel centres (coverage ≥ 0.5) of an `n × n` em-box raster, em units, at most `cap` of
/// them (every k-th in raster order). `None` if there is no ink.
fn ink_points(cov: &[f32], n: usize, cap: usize) -> Option<Vec<Point>> {
    let s = EM / n as f64;
    let all: Vec<Point> = (0..n * n)
        .filter(|&i| cov[i] >= 0.5)
        .map(|i| Point::new(((i % n) as f64 + 0.5) * s, ((i / n) as f64 + 0.5) * s))
        .collect();
    if all.is_empty() {
        return None;
    }
    let k = all.len().div_ceil(cap);
    Some(all.into_iter().step_by(k).collect())
}

/// Ink centroid and per-axis standard deviation of a raster, em units.
fn moments(cov: &[f32], n: usize) -> (Point, Vec2) {
    let s = EM / n as f64;
    let (mut m0, mut mx, mut my) = (0.0, 0.0, 0.0);
    for (i, &v) in cov.iter().enumerate() {
        let v = v as f64;
        m0 += v;
        mx += v * ((i % n) as f64 + 0.5) * s;
        my += v * ((i / n) as f64 + 0.5) * s;
    }
    let c = Point::new(mx / m0.max(1e-9), my / m0.max(1e-9));
    let (mut vx, mut vy) = (0.0, 0.0);
    for (i, &v) in cov.iter().enumerate() {
        let v = v as f64;
        vx += v * (((i % n) as f64 + 0.5) * s - c.x).powi(2);
        vy += v * (((i / n) as f64 + 0.5) * s - c.y).powi(2);
    }
    (c, Vec2::new((vx / m0.max(1e-9)).sqrt(), (vy / m0.max(1e-9)).sqrt()))
}

/// The start of the global fit: template ink centroid onto the target's, per-axis spread matched.
fn moment_start(t: &[f32], g: &[f32], n: usize) -> Affine {
    let (ct, st) = moments(t, n);
    let (cg, sg) = moments(g, n);
    let sx = (sg.x / st.x.max(1e-9)).clamp(0.3, 3.0);
    let sy = (sg.y / st.y.max(1e-9)).clamp(0.3, 3.0);
    Affine::new([sx, 0.0, 0.0, sy, cg.x - sx * ct.x, cg.y - sy * ct.y])
}

/// Symmetric blurred overlap of template and target under `a` (template → target).
fn overlap(a: Affine, t_ink: &[Point], g_ink: &[Point], tb: &[f32], gb: &[f32], n: usize) -> f64 {
    let det = a.determinant();
    if !(0.05..20.0).contains(&det) {
        return 0.0;
    }
    let inv = a.inverse();
    let s = n as f64 / EM;
    let fwd = t_ink.iter().map(|&p| {
        let q = a * p;
        distance::sample(gb, n, n, q.x * s, q.y * s)
    });
    let back = g_ink.iter().map(|&p| {
        let q = inv * p;
        distance::sample(tb, n, n, q.x * s, q.y * s)
    });
    0.5 * (fwd.sum::<f64>() / t_ink.len() as f64 + back.sum::<f64>() / g_ink.len() as f64)
}

/// Nelder–Mead minimisation of `f` from `x0` with initial steps `steps`, `iters` iterations.
/// Returns the best point and its value. Deterministic.
fn nelder_mead(f: impl Fn(&[f64]) -> f64, x0: &[f64], steps: &[f64], iters: usize) -> (Vec<f64>, f64) {
    let d = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    simplex.push((x0.to_vec(), f(x0)));
    for i in 0..d {
        let mut x = x0.to_vec();
        x[i] += steps[i];
        let v = f(&x);
        simplex.push((x, v));
    }
    let lerp = |a: &[f64], b: &[f64], t: f64| -> Vec<f64> { a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect() };
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut centroid = vec![0.0; d];
        for (x, _) in &simplex[..d] {
            for (c, v) in centroid.iter_mut().zip(x) {
                *c += v / d as f64;
            }
        }
        let worst = simplex[d].clone();
        let refl = lerp(&centroid, &worst.0, -1.0);
        let fr = f(&refl);
        if fr < simplex[0].1 {
            let exp = lerp(&centroid, &worst.0, -2.0);
            let fe = f(&exp);
            simplex[d] = if fe < fr { (exp, fe) } else { (refl, fr) };
        } else if fr < simplex[d - 1].1 {
            simplex[d] = (refl, fr);
        } else {
            let con = if fr < worst.1 { lerp(&centroid, &refl, 0.5) } else { lerp(&centroid, &worst.0, 0.5) };
            let fc = f(&con);
            if fc < worst.1.min(fr) {
                simplex[d] = (con, fc);
            } else {
                let best = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    let x = lerp(&best, &s.0, 0.5);
                    let v = f(&x);
                    *s = (x, v);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0)
}

/// A glyph's skeleton pixels (Zhang–Suen at `n²`): pixel centres, px.
fn skeleton_points(target: &Glyph, n: usize) -> Vec<(usize, usize)> {
    let mut mask = raster::mask_of(&raster::render_glyph(target, n as u32));
    thinning::zhang_suen(&mut mask, n, n);
    thinning::remove_staircases(&mut mask, n, n);
    (0..n * n).filter(|&i| mask[i]).map(|i| (i % n, i / n)).collect()
}

/// Keeps the first pixel of each `cell × cell` block (an even sampling along lines of any
/// direction, where every k-th pixel in raster order would alias); returns the kept pixel
/// centres in em units (`px_em` em units per pixel).
fn grid_thin(px: &[(usize, usize)], cell: usize, px_em: f64) -> Vec<Point> {
    let mut seen = std::collections::HashSet::new();
    px.iter()
        .filter(|&&(x, y)| seen.insert((x / cell, y / cell)))
        .map(|&(x, y)| Point::new((x as f64 + 0.5) * px_em, (y as f64 + 0.5) * px_em))
        .collect()
}

/// Moves each point across the stroke to the nearest ridge of the distance transform `dt`
/// (`n × n`): off the ink it first steps to the nearest ink along the normal, then climbs while
/// the distance grows. The shifts are smoothed along the stroke (window 5). Returns the moved
/// points and the ridge heights (half-widths), em units.
#[allow(clippy::needless_range_loop)] // indices address p, its normals and the shifts together
fn snap_to_ridge(p: &[Point], dt: &[f32], n: usize, px_to_em: f64) -> (Vec<Point>, Vec<f64>) {
    let at = |q: Point| distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em);
    let step = 0.5 * px_to_em;
    let normal_at = |i: usize| {
        let (a, b) = (p[i.saturating_sub(1)], p[(i + 1).min(p.len() - 1)]);
        let d = b - a;
        let len = d.hypot();
        if len < 1e-9 { None } else { Some(Vec2::new(-d.y / len, d.x / len)) }
    };
    let mut shifts = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let Some(nrm) = normal_at(i) else {
            shifts.push(0.0);
            continue;
        };
        let mut off = 0.0;
        if at(p[i]) < 0.5 {
            // Nearest ink along the normal, within 12 px.
            let found = (1..=24).find_map(|k| {
                let o = k as f64 * step;
                if at(p[i] + nrm * o) >= 0.5 {
                    Some(o)
                } else if at(p[i] - nrm * o) >= 0.5 {
                    Some(-o)
                } else {
                    None
                }
            });
            match found {
                Some(o) => off = o,
                None => {
                    shifts.push(0.0);
                    continue;
                }
            }
        }
        // Climb on the uphill side until clearly past the ridge (a raster's distance transform
        // has small dips along a line), then take the middle of the points near the top.
        let dir = if at(p[i] + nrm * (off + 2.0 * step)) >= at(p[i] + nrm * (off - 2.0 * step)) { 1.0 } else { -1.0 };
        let mut prof = vec![(off, at(p[i] + nrm * off))];
        let mut best = prof[0].1;
        let mut o = off;
        for _ in 0..160 {
            o += dir * step;
            let v = at(p[i] + nrm * o);
            if v < best - 1.0 || v <= 0.0 {
                break;
            }
            best = best.max(v);
            prof.push((o, v));
        }
        let top: Vec<f64> = prof.iter().filter(|(_, v)| *v >= best - 0.3).map(|(o, _)| *o).collect();
        shifts.push(top.iter().sum::<f64>() / top.len() as f64);
    }
    let mut out = Vec::with_capacity(p.len());
    let mut widths = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let (lo, hi) = (i.saturating_sub(2), (i + 2).min(p.len() - 1));
        let off = shifts[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
        let q = match normal_at(i) {
            Some(nrm) => p[i] + nrm * off,
            None => p[i],
        };
        out.push(q);
        widths.push(at(q) * px_to_em);
    }
    (out, widths)
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
    fn nelder_mead_finds_a_quadratic_minimum() {
        let f = |x: &[f64]| (x[0] - 3.0).powi(2) + 2.0 * (x[1] + 1.0).powi(2) + 1.0;
        let (x, v) = nelder_mead(f, &[0.0, 0.0], &[1.0, 1.0], 200);
        assert!((x[0] - 3.0).abs() < 1e-4 && (x[1] + 1.0).abs() < 1e-4 && (v - 1.0).abs() < 1e-8, "{x:?} {v}");
    }

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

    /// An `n × n` mask (em box) inked where `ink(x_em, y_em)` holds, its distance transform and
    /// px → em factor.
    fn bar_dt(n: usize, ink: impl Fn(f64, f64) -> bool) -> (Vec<bool>, Vec<f32>, f64) {
        let s = EM / n as f64;
        let mask: Vec<bool> = (0..n * n).map(|i| ink(((i % n) as f64 + 0.5) * s, ((i / n) as f64 + 0.5) * s)).collect();
        let dt = distance::distance_to_background(&mask, n, n);
        (mask, dt, s)
    }

    #[test]
    fn an_end_runs_out_to_a_blunt_cap_at_full_width() {
        // A bar 60 em thick from x = 100 to 600: from x = 550 the line runs on to near the cap,
        // and the run-out keeps the bar's half-width (the distance to the outline would taper).
        let (_, dt, s) = bar_dt(256, |x, y| (100.0..600.0).contains(&x) && (200.0..260.0).contains(&y));
        let p: Vec<Point> = (0..=10).map(|i| Point::new(150.0 + 40.0 * i as f64, 230.0)).collect();
        let w = vec![30.0; p.len()];
        let (q, v) = extend_ends_own(p, w, &dt, 256, s);
        let (last, w_last) = (q[q.len() - 1], v[v.len() - 1]);
        assert!(last.x > 585.0 && last.x < 600.0, "{last:?}");
        assert!(w_last > 24.0, "{w_last}");
        // And the head (x = 150) runs back towards x = 100 the same way.
        assert!(q[0].x < 115.0 && q[0].x > 100.0, "{:?}", q[0]);
        assert_eq!(q.len(), v.len());
    }

    #[test]
    fn an_end_stops_at_a_neck_before_other_ink() {
        // The bar narrows to a 16 em neck at x = 500..520, then a wide blob: the run-out stops
        // in the neck instead of running on into the blob.
        let (_, dt, s) = bar_dt(256, |x, y| {
            ((100.0..500.0).contains(&x) && (200.0..260.0).contains(&y))
                || ((500.0..520.0).contains(&x) && (222.0..238.0).contains(&y))
                || ((520.0..700.0).contains(&x) && (160.0..300.0).contains(&y))
        });
        let from = Point::new(470.0, 230.0);
        let out = run_out_own(from, Vec2::new(1.0, 0.0), 30.0, &dt, 256, s);
        let end = out.last().map_or(from, |o| o.0);
        assert!(end.x < 530.0, "ran on to {end:?}");
    }

    #[test]
    fn the_own_ink_margin_grows_with_a_thicker_target() {
        // Template outline 20 em thick, target stroke 60 em thick on the same line: the margin
        // grows by about the 20 em difference of the half-widths.
        let n = 256;
        let (outline, _, s) = bar_dt(n, |x, y| (100.0..600.0).contains(&x) && (220.0..240.0).contains(&y));
        let (_, dt, _) = bar_dt(n, |x, y| (100.0..600.0).contains(&x) && (200.0..260.0).contains(&y));
        let line: Vec<Point> = (0..20).map(|i| Point::new(200.0 + 15.0 * i as f64, 230.0)).collect();
        let grown = own_margin_px(&line, &dt, &outline, n, s) * s - OWN_INK_MARGIN_EM;
        assert!((grown - 20.0).abs() < 5.0, "{grown}");
        // The same thickness: the fixed margin.
        let same = own_margin_px(&line, &distance::distance_to_background(&outline, n, n), &outline, n, s) * s;
        assert!((same - OWN_INK_MARGIN_EM).abs() < 1e-9, "{same}");
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
