//! Calligraphy rules at the corners of a chain: which turns end a stroke (the upper left of 口,
//! box bottoms) and which stay inside one (横折, 竖提 and other 提, hooks 钩 at a chain's end).
//!
//! Frame: the analysis raster, px, y down (so "rising" is `y` decreasing). Turns are measured
//! between chords over [`GraphOptions::corner_reach`] local half-widths each way; every
//! returned piece is a sub-polyline of the chain, consecutive pieces sharing their cut point.

use kurbo::{Point, Vec2};

use super::learned::{DecisionModel, GlyphFrame, NUM_CORNER_FEATURES, stroke_along};
use super::options::GraphOptions;
use super::order::writing_direction;
use crate::polyline::{arc_lengths, nearly_horizontal};

/// Splits a chain at corners that cannot be inside one written stroke.
///
/// A corner is a point where the chain turns by more than `corner_rad`, measured between the
/// points [`CORNER_REACH`] local half-widths before and after it (a local maximum of the turn). With
/// the chain's two legs oriented as the chain runs, one stroke can turn there only if both legs
/// run the way they are written ([`writing_direction`]) or both against it; otherwise the
/// corner joins the starts of two strokes (the upper left of 口) or their ends (the lower
/// right); a leg rising to the right out of a downward one is 提 and stays (竖提). On a closed
/// chain, vertical-into-rightward corners split too when `split_box_corners` is set. Legs
/// shorter than two half-widths never split, nor do hooks at a chain's ends ([`HOOK_WIDTHS`],
/// [`HOOK_RATIO`]). A closed chain (a box drawn as one loop) is cut at its splitting corners.
///
/// With `mode` [`CornerSplit::Model`], the learned model decides at each corner instead, the
/// rules' verdicts among its features.
pub(super) fn split_at_corners(
    p: &[Point],
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    junctions: &[Point],
    mode: CornerSplit<'_>,
) -> Vec<Vec<Point>> {
    if p.len() < 5 {
        return vec![p.to_vec()];
    }
    let chain = Chain::new(p, dt, n, opts);
    let corners = chain.corners(opts);
    let verdicts: Vec<Verdict> = corners.iter().map(|&i| chain.verdict(i, &corners, opts)).collect();
    let rule_splits = chain.splits(&corners, &verdicts, junctions);
    let splits: Vec<usize> = match mode {
        CornerSplit::Rules => rule_splits,
        CornerSplit::Model(model, frame) => {
            let ctx = CornerContext { corners: &corners, verdicts: &verdicts, rule_splits: &rule_splits, junctions };
            (0..corners.len())
                .filter(|&k| model.probability(&chain.corner_features(k, &ctx, opts, frame)) >= opts.corner_threshold)
                .map(|k| corners[k])
                .collect()
        }
        CornerSplit::Labels(medians) => corners
            .iter()
            .copied()
            .filter(|&c| chain.label(c, medians).unwrap_or_else(|| rule_splits.contains(&c)))
            .collect(),
    };
    if splits.is_empty() {
        return vec![p.to_vec()];
    }
    chain.cut(&splits)
}

/// How a chain's corners are split.
#[derive(Clone, Copy)]
pub(super) enum CornerSplit<'a> {
    /// The hand rules alone.
    Rules,
    /// The learned model, with the rules' verdicts among its features.
    Model(&'a DecisionModel, &'a GlyphFrame),
    /// The glyph's own medians (px): split where the two legs lie along different strokes,
    /// elsewhere by the rules. For measuring how far better corners alone could go.
    Labels(&'a [Vec<Point>]),
}

/// Training samples at every corner of chain `p`: its features and, when the medians (px) say
/// which stroke each leg lies along, whether they differ (two strokes meet there).
pub(super) fn corner_samples(
    p: &[Point],
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    junctions: &[Point],
    frame: &GlyphFrame,
    medians: &[Vec<Point>],
) -> Vec<([f64; NUM_CORNER_FEATURES], Option<bool>)> {
    if p.len() < 5 {
        return Vec::new();
    }
    let chain = Chain::new(p, dt, n, opts);
    let corners = chain.corners(opts);
    let verdicts: Vec<Verdict> = corners.iter().map(|&i| chain.verdict(i, &corners, opts)).collect();
    let rule_splits = chain.splits(&corners, &verdicts, junctions);
    let ctx = CornerContext { corners: &corners, verdicts: &verdicts, rule_splits: &rule_splits, junctions };
    (0..corners.len())
        .map(|k| (chain.corner_features(k, &ctx, opts, frame), chain.label(corners[k], medians)))
        .collect()
}

/// A chain's corners with the rules' verdicts, for the features.
struct CornerContext<'a> {
    corners: &'a [usize],
    verdicts: &'a [Verdict],
    rule_splits: &'a [usize],
    junctions: &'a [Point],
}

/// A chain closes on itself (a box drawn as one loop) when its ends are closer than this (px).
const CLOSED_GAP_PX: f64 = 1.5;
/// A chain end this near a junction (px) ends against other strokes.
const AT_JUNCTION_PX: f64 = 1.5;
/// The turn is measured at least this far each way (px), however thin the stroke.
const MIN_REACH_PX: f64 = 3.0;
/// A leg shorter than this many local half-widths never splits at its corner.
const MIN_LEG_WIDTHS: f64 = 2.0;
/// A short end leg rising by more than this share of its length is a hook (every 钩 points up).
const HOOK_MIN_RISE: f64 = 0.2;
/// A leg is vertical when it falls by more than this per unit run (a box's side).
const VERTICAL_MIN_SLOPE: f64 = 2.0;
/// An open box's side leans by at most this run per unit fall (撇折 in 纟 and 幺 leans more).
const UPRIGHT_MAX_LEAN: f64 = 0.3;
/// An open box's bottom rises by at most this per unit run (撇折's second leg rises more).
const LEVEL_MAX_RISE: f64 = 0.15;

/// A chain parsed for the corner rules: points, arc lengths, local widths and turn reaches.
struct Chain<'a> {
    p: &'a [Point],
    dt: &'a [f32],
    n: usize,
    /// Arc length at each point, px.
    s: Vec<f64>,
    /// Whether the chain is a loop ([`CLOSED_GAP_PX`]).
    closed: bool,
    /// Arc length including the closing segment of a loop, px.
    total: f64,
    /// How far each way the turn at each point is measured, px.
    reach: Vec<f64>,
}

/// Per corner: stays, splits, or an open box corner that splits if the horizontal leg's far
/// end (the neighbouring corner's index or the chain's end) lies against other strokes: a
/// splitting corner or a junction.
enum Verdict {
    Stay,
    Split,
    OpenBox(usize),
}

impl<'a> Chain<'a> {
    fn new(p: &'a [Point], dt: &'a [f32], n: usize, opts: &GraphOptions) -> Self {
        let m = p.len();
        let closed = p[0].distance(p[m - 1]) < CLOSED_GAP_PX;
        // Arc length, with the closing segment for loops.
        let s = arc_lengths(p);
        let total = s[m - 1] + if closed { p[m - 1].distance(p[0]) } else { 0.0 };
        let mut chain = Chain { p, dt, n, s, closed, total, reach: Vec::new() };
        chain.reach = p.iter().map(|&q| (opts.corner_reach * chain.width(q)).max(MIN_REACH_PX)).collect();
        chain
    }

    fn last(&self) -> usize {
        self.p.len() - 1
    }

    /// The local half-width at `q` (px, at least 1).
    fn width(&self, q: Point) -> f64 {
        let n = self.n;
        let (x, y) = (q.x.floor().clamp(0.0, (n - 1) as f64) as usize, q.y.floor().clamp(0.0, (n - 1) as f64) as usize);
        f64::from(self.dt[y * n + x]).max(1.0)
    }

    /// The point at arc length `t` (wrapping for loops; clamped otherwise).
    fn at(&self, t: f64) -> Point {
        let (s, m) = (&self.s, self.p.len());
        let t = if self.closed { t.rem_euclid(self.total) } else { t.clamp(0.0, s[m - 1]) };
        let i = s.partition_point(|&x| x <= t).clamp(1, m) - 1;
        self.p[i]
    }

    /// The chords into and out of point `i`, over its reach.
    fn legs(&self, i: usize) -> (Vec2, Vec2) {
        let (s, r, p) = (&self.s, &self.reach, self.p);
        (p[i] - self.at(s[i] - r[i]), self.at(s[i] + r[i]) - p[i])
    }

    /// The turn at point `i`, radians (0 where the reach runs off an open chain's ends).
    fn turn(&self, i: usize) -> f64 {
        let (s, r, m) = (&self.s, &self.reach, self.p.len());
        if !self.closed && (s[i] < r[i] || s[m - 1] - s[i] < r[i]) {
            return 0.0;
        }
        let (a, b) = self.legs(i);
        if a.hypot() < 1e-9 || b.hypot() < 1e-9 {
            return 0.0;
        }
        (a.dot(b) / (a.hypot() * b.hypot())).clamp(-1.0, 1.0).acos()
    }

    /// Corners: local maxima of the turn above `corner_rad`, one per neighbourhood (the reach).
    fn corners(&self, opts: &GraphOptions) -> Vec<usize> {
        let m = self.p.len();
        let s = &self.s;
        let turn: Vec<f64> = (0..m).map(|i| self.turn(i)).collect();
        let mut corners: Vec<usize> = Vec::new();
        for i in 0..m {
            if turn[i] <= opts.corner_rad {
                continue;
            }
            let near = |j: usize| {
                let d = (s[j] - s[i]).abs();
                if self.closed { d.min(self.total - d) } else { d }
            };
            let is_max = (0..m).all(|j| near(j) > self.reach[i] || turn[j] < turn[i] || (turn[j] == turn[i] && j >= i));
            if is_max {
                corners.push(i);
            }
        }
        corners
    }

    /// Arc lengths of the neighbouring corners before and after corner `i` (the chain's ends on
    /// an open chain; `None` on a loop without another corner that way).
    fn leg_ends(&self, i: usize, corners: &[usize]) -> (Option<f64>, Option<f64>) {
        let s = &self.s;
        let (start, end) = if self.closed { (None, None) } else { (Some(0.0), Some(s[self.last()])) };
        let prev = corners.iter().rev().find(|&&c| c < i).map_or(start, |&c| Some(s[c]));
        let next = corners.iter().find(|&&c| c > i).map_or(end, |&c| Some(s[c]));
        (prev, next)
    }

    /// Whether corner `i` is a hook (钩) at an open chain's first or last corner: an end leg much
    /// shorter than the leg it turns from, or short and rising away from the corner.
    fn is_hook(&self, i: usize, corners: &[usize], (len_in, len_out): (f64, f64), opts: &GraphOptions) -> bool {
        let (d_in, d_out) = self.legs(i);
        let w = self.width(self.p[i]);
        let hook = |len: f64, other: f64, outward: Vec2| {
            len < opts.hook_widths * w
                && (len < opts.hook_ratio * other || outward.y < -HOOK_MIN_RISE * outward.hypot())
        };
        let first = corners.first() == Some(&i);
        let last = corners.last() == Some(&i);
        (first && hook(len_in, len_out, -d_in)) || (last && hook(len_out, len_in, d_out))
    }

    /// Whether one stroke turns at corner `i`, two strokes meet there, or it is an open box's
    /// corner (see the module doc and [`split_at_corners`]).
    fn verdict(&self, i: usize, corners: &[usize], opts: &GraphOptions) -> Verdict {
        let (s, last) = (&self.s, self.last());
        let (d_in, d_out) = self.legs(i);
        let forward_in = writing_direction(d_in).dot(d_in) > 0.0;
        let forward_out = writing_direction(d_out).dot(d_out) > 0.0;
        // The legs up to the neighbouring corners (or the chain's ends).
        let (prev, next) = self.leg_ends(i, corners);
        let min_leg = MIN_LEG_WIDTHS * self.width(self.p[i]);
        let long = prev.is_none_or(|a| s[i] - a >= min_leg) && next.is_none_or(|b| b - s[i] >= min_leg);
        if !long {
            return Verdict::Stay;
        }
        let leg_lengths = (s[i] - prev.unwrap_or(0.0), next.unwrap_or(s[last]) - s[i]);
        if !self.closed && self.is_hook(i, corners, leg_lengths, opts) {
            return Verdict::Stay;
        }
        if is_ti((d_in, d_out), opts) {
            return Verdict::Stay;
        }
        if forward_in != forward_out {
            return Verdict::Split;
        }
        // As written: which leg comes first. A vertical leg turning right is a box corner.
        let (first, second) = if forward_in { (d_in, d_out) } else { (-d_out, -d_in) };
        let vertical = |v: Vec2| v.y > VERTICAL_MIN_SLOPE * v.x.abs();
        let right = |v: Vec2| nearly_horizontal(v) && v.x > 0.0;
        if !(vertical(first) && right(second)) {
            return Verdict::Stay;
        }
        if self.closed {
            return if opts.split_box_corners { Verdict::Split } else { Verdict::Stay };
        }
        // The legs as written: the vertical one, then the horizontal one, which must run to
        // the chain's end and end there against other strokes (the bottom of 口 ending at
        // the right side), not at a free end or another corner.
        let (len_in, len_out) = leg_lengths;
        let (len_v, len_h) = if forward_in { (len_in, len_out) } else { (len_out, len_in) };
        // A box side is upright and its bottom level (撇折 in 纟 and 幺 slants and rises).
        let upright = first.x.abs() <= UPRIGHT_MAX_LEAN * first.y && second.y >= -LEVEL_MAX_RISE * second.x;
        if !(opts.open_box_min_ratio > 0.0 && upright && len_v >= opts.open_box_min_ratio * len_h) {
            return Verdict::Stay;
        }
        let far = if forward_in {
            corners.iter().copied().find(|&c| c > i).unwrap_or(last)
        } else {
            corners.iter().rev().copied().find(|&c| c < i).unwrap_or(0)
        };
        Verdict::OpenBox(far)
    }

    /// The corners to cut at: every `Split`, and each `OpenBox` whose far end is a splitting
    /// corner or a chain end at a junction.
    fn splits(&self, corners: &[usize], verdicts: &[Verdict], junctions: &[Point]) -> Vec<usize> {
        let last = self.last();
        let base: Vec<usize> =
            corners.iter().zip(verdicts).filter(|(_, v)| matches!(v, Verdict::Split)).map(|(&c, _)| c).collect();
        let against_strokes = |far: usize| {
            base.contains(&far)
                || ((far == 0 || far == last) && junctions.iter().any(|j| j.distance(self.p[far]) < AT_JUNCTION_PX))
        };
        corners
            .iter()
            .zip(verdicts)
            .filter(|(_, v)| match v {
                Verdict::Split => true,
                Verdict::OpenBox(far) => against_strokes(*far),
                Verdict::Stay => false,
            })
            .map(|(&c, _)| c)
            .collect()
    }

    /// Whether the legs at corner `i` lie along different median strokes (`medians`, px), or
    /// `None` when either is unknown: the training label.
    fn label(&self, i: usize, medians: &[Vec<Point>]) -> Option<bool> {
        let w = self.width(self.p[i]);
        let side = |sign: f64| stroke_along(&self.leg_points(i, sign, 4.0).collect::<Vec<_>>(), medians, w);
        Some(side(-1.0)? != side(1.0)?)
    }

    /// Points along one leg of corner `i` (`sign` −1: before it), one px apart from one
    /// half-width out to `reach` half-widths, within the chain (or round a closed one).
    fn leg_points(&self, i: usize, sign: f64, reach: f64) -> impl Iterator<Item = Point> + '_ {
        let w = self.width(self.p[i]);
        let (at, end) = (self.s[i], self.s[self.last()]);
        (0..)
            .map(move |k| w + k as f64)
            .take_while(move |&t| t <= reach * w)
            .map(move |t| at + sign * t)
            .filter(move |&u| self.closed || (0.0..=end).contains(&u))
            .map(move |u| self.at(u))
    }

    /// Mean half-width (px) along one leg of corner `i`, one to three half-widths out (`sign`
    /// −1: before it).
    fn leg_width(&self, i: usize, sign: f64) -> f64 {
        let w = self.width(self.p[i]);
        let ws: Vec<f64> =
            self.leg_points(i, sign, 3.0).map(|q| crate::distance::sample(self.dt, self.n, self.n, q.x, q.y)).collect();
        if ws.is_empty() { w } else { ws.iter().sum::<f64>() / ws.len() as f64 }
    }

    /// The features of corner `k` (index into `ctx.corners`), in
    /// [`super::learned::CORNER_FEATURE_NAMES`] order.
    fn corner_features(
        &self,
        k: usize,
        ctx: &CornerContext<'_>,
        opts: &GraphOptions,
        frame: &GlyphFrame,
    ) -> [f64; NUM_CORNER_FEATURES] {
        let (s, last, p) = (&self.s, self.last(), self.p);
        let i = ctx.corners[k];
        let w = self.width(p[i]);
        let (d_in, d_out) = self.legs(i);
        let (prev, next) = self.leg_ends(i, ctx.corners);
        let len_in = s[i] - prev.unwrap_or(if self.closed { s[i] - self.total } else { 0.0 });
        let len_out = next.unwrap_or(if self.closed { s[i] + self.total } else { s[last] }) - s[i];
        let hook = !self.closed && self.is_hook(i, ctx.corners, (len_in, len_out), opts);
        let ti = is_ti((d_in, d_out), opts);
        let at_junction = |q: Point| ctx.junctions.iter().any(|j| j.distance(q) < AT_JUNCTION_PX);
        let (mut start_j, mut end_j) = (at_junction(p[0]), at_junction(p[last]));
        let (mut first, mut last_c) = (k == 0, k + 1 == ctx.corners.len());
        let (mut w_in, mut w_out) = (self.leg_width(i, -1.0), self.leg_width(i, 1.0));
        // View the chain from its end nearer the upper left.
        let reversed = !self.closed && p[last].x + p[last].y < p[0].x + p[0].y;
        let (mut a, mut b, mut la, mut lb) = (d_in, d_out, len_in, len_out);
        if reversed {
            (a, b, la, lb) = (-d_out, -d_in, len_out, len_in);
            std::mem::swap(&mut start_j, &mut end_j);
            std::mem::swap(&mut first, &mut last_c);
            std::mem::swap(&mut w_in, &mut w_out);
        }
        let unit = |v: Vec2| if v.hypot() > 1e-9 { v / v.hypot() } else { Vec2::ZERO };
        let (a, b) = (unit(a), unit(b));
        let flag = |x: bool| f64::from(u8::from(x));
        let forward = |v: Vec2| writing_direction(v).dot(v) > 0.0;
        let (rx, ry) = frame.relative(p[i]);
        [
            self.turn(i),
            flag(ctx.rule_splits.contains(&i)),
            flag(matches!(ctx.verdicts[k], Verdict::Split)),
            flag(matches!(ctx.verdicts[k], Verdict::OpenBox(_))),
            flag(ti),
            flag(hook),
            flag(forward(a)),
            flag(forward(b)),
            a.x,
            a.y,
            b.x,
            b.y,
            (1.0 + la.max(0.0) / w).ln(),
            (1.0 + lb.max(0.0) / w).ln(),
            (1.0 + self.total / w).ln(),
            flag(self.closed),
            ctx.corners.len() as f64,
            flag(first),
            flag(last_c),
            flag(start_j),
            flag(end_j),
            w_in / w,
            w_out / w,
            w / frame.mean_width,
            rx,
            ry,
        ]
    }

    /// The pieces between the cuts (a loop is rotated to start at its first cut).
    fn cut(&self, splits: &[usize]) -> Vec<Vec<Point>> {
        let (p, m) = (self.p, self.p.len());
        let mut out = Vec::new();
        if self.closed {
            // Rotate the loop to start at the first split, then cut at the others.
            let start = splits[0];
            let ring: Vec<Point> = p[start..m - 1].iter().chain(&p[..=start]).copied().collect();
            let cuts: Vec<usize> = splits.iter().map(|&c| (c + (m - 1) - start) % (m - 1)).collect();
            let mut from = 0;
            for &c in cuts.iter().skip(1).chain(std::iter::once(&(ring.len() - 1))) {
                out.push(ring[from..=c].to_vec());
                from = c;
            }
        } else {
            let mut from = 0;
            for &c in splits.iter().chain(std::iter::once(&(m - 1))) {
                out.push(p[from..=c].to_vec());
                from = c;
            }
        }
        out
    }
}

/// 提 rises to the right out of a downward leg (竖提, 横折提): one stroke, whichever way the
/// chain runs (`legs` as the chain runs, into and out of the corner).
fn is_ti((d_in, d_out): (Vec2, Vec2), opts: &GraphOptions) -> bool {
    let down = |v: Vec2| !nearly_horizontal(v) && v.y > 0.0;
    let rising = |v: Vec2| v.x > 0.0 && v.y < -opts.ti_min_rise * v.x;
    (down(d_in) && rising(d_out)) || (down(-d_out) && rising(-d_in))
}
