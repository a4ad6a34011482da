//! From the cleaned graph to chains: at each node, branch ends that continue each other are
//! paired (straightest first, comparable widths), and paired edges are walked into polylines;
//! short pieces lying inside other strokes are dropped.
//!
//! Frame: the analysis raster, px, y down. Each chain is a polyline of pixel-centre points,
//! lightly smoothed with its end points kept; every live edge ends up in exactly one chain.

use kurbo::{Point, Vec2};

use super::graph::{Graph, branch_width, ends_at};
use super::learned::{DecisionModel, GlyphFrame, NUM_FEATURES, branches, pair_features, pair_greedily};
use super::options::GraphOptions;
use crate::polyline::length;

/// How branch ends at junctions of three or more branches are paired.
#[derive(Clone, Copy)]
pub(super) enum Pairing<'a> {
    /// The hand rules alone ([`rule_pairs`]).
    Rules,
    /// The learned model, with the rules' verdict as one of its features.
    Model(&'a DecisionModel, &'a GlyphFrame),
    /// Training labels (per end id, the median stroke it lies along): ends along the same stroke
    /// pair, straightest first; ends without a label fall back to the rules. For measuring how
    /// far better pairing alone could go.
    Labels(&'a [Option<usize>]),
}

/// Pairs branch ends at every node and walks the pairs into chains (smoothed).
pub(super) fn pair_and_chain(
    g: &Graph,
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    pairing: Pairing<'_>,
) -> Vec<Vec<Point>> {
    // End id: 2k (end a) or 2k+1 (end b) of edge k.
    let mut partner = vec![UNPAIRED; 2 * g.edges.len()];
    for v in 0..g.nodes.len() {
        if g.nodes[v].alive {
            pair_at(g, v, dt, n, opts, pairing, &mut partner);
        }
    }
    walk_chains(g, &partner).into_iter().map(|s| smooth(&s)).collect()
}

/// `partner` of a branch end that continues no other.
const UNPAIRED: usize = usize::MAX;

/// At node `v`, pairs the branch ends that continue each other: both ends of a two-branch node;
/// at a junction, as `pairing` says.
fn pair_at(
    g: &Graph,
    v: usize,
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    pairing: Pairing<'_>,
    partner: &mut [usize],
) {
    let ends = ends_at(g, v);
    if ends.len() < 2 {
        return;
    }
    let rules = rule_pairs(g, &ends, dt, n, opts);
    let scored: Vec<(f64, usize, usize)> = match pairing {
        Pairing::Model(model, frame) if ends.len() >= 3 => {
            let out = junction_pairs(g, v, &ends, &rules, dt, n, frame)
                .into_iter()
                .map(|(x, y, f)| (model.probability(&f), x, y))
                .collect();
            pair_greedily(out, opts.pair_threshold, partner, UNPAIRED);
            return;
        }
        Pairing::Labels(labels) if ends.len() >= 3 => {
            let mut out = Vec::new();
            for i in 0..ends.len() {
                for j in i + 1..ends.len() {
                    let (x, y) = (ends[i].0, ends[j].0);
                    let straight = -ends[i].1.dot(ends[j].1);
                    let score = match (labels[x], labels[y]) {
                        (Some(a), Some(b)) => f64::from(u8::from(a == b)) * (3.0 + straight),
                        _ => f64::from(u8::from(rules.contains(&(x, y)))) * (1.5 + straight / 4.0),
                    };
                    out.push((score, x, y));
                }
            }
            pair_greedily(out, 1.0, partner, UNPAIRED);
            return;
        }
        _ => rules.iter().map(|&(x, y)| (1.0, x, y)).collect(),
    };
    pair_greedily(scored, 1.0, partner, UNPAIRED);
}

/// The hand rules' pairs at a node with branch `ends` (as [`ends_at`] gives them, each pair in
/// that order), straightest first: both ends of a two-branch node; at a crossing, pairs turning
/// by less than `straight_min_rad` whose widths are comparable (`pair_width_ratio`).
fn rule_pairs(g: &Graph, ends: &[(usize, Vec2)], dt: &[f32], n: usize, opts: &GraphOptions) -> Vec<(usize, usize)> {
    let widths: Vec<f64> = if opts.pair_width_ratio > 0.0 && ends.len() >= 3 {
        ends.iter().map(|&(end, _)| branch_width(g, &g.edges[end / 2], end % 2 == 0, dt, n)).collect()
    } else {
        Vec::new()
    };
    let comparable = |i: usize, j: usize| {
        widths.is_empty() || widths[i].min(widths[j]) >= opts.pair_width_ratio * widths[i].max(widths[j])
    };
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for i in 0..ends.len() {
        for j in i + 1..ends.len() {
            if comparable(i, j) {
                pairs.push((ends[i].1.dot(ends[j].1), ends[i].0, ends[j].0));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let limit = if ends.len() == 2 { 1.0 } else { opts.straight_min_rad.cos() };
    let mut used: Vec<usize> = Vec::new();
    let mut out = Vec::new();
    for (c, x, y) in pairs {
        if c <= limit + 1e-12 && !used.contains(&x) && !used.contains(&y) && x / 2 != y / 2 {
            used.extend([x, y]);
            out.push((x, y));
        }
    }
    out
}

/// Training samples at every junction of three or more branches: each pair's features and,
/// when both of its ends have a median stroke in `labels` ([`super::learned::end_strokes`]),
/// whether they lie along the same one.
pub(super) fn pair_samples(
    g: &Graph,
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    frame: &GlyphFrame,
    labels: &[Option<usize>],
) -> Vec<([f64; NUM_FEATURES], Option<bool>)> {
    let mut out = Vec::new();
    for v in (0..g.nodes.len()).filter(|&v| g.nodes[v].alive) {
        let ends = ends_at(g, v);
        if ends.len() < 3 {
            continue;
        }
        let rules = rule_pairs(g, &ends, dt, n, opts);
        for (x, y, f) in junction_pairs(g, v, &ends, &rules, dt, n, frame) {
            let label = match (labels[x], labels[y]) {
                (Some(a), Some(c)) => Some(a == c),
                _ => None,
            };
            out.push((f, label));
        }
    }
    out
}

/// Every pair of branches at junction `v` (branch `ends` as [`ends_at`] gives them): its two
/// end ids and its features, among them whether the hand rules pair it (`rules`, from
/// [`rule_pairs`]).
fn junction_pairs(
    g: &Graph,
    v: usize,
    ends: &[(usize, Vec2)],
    rules: &[(usize, usize)],
    dt: &[f32],
    n: usize,
    frame: &GlyphFrame,
) -> Vec<(usize, usize, [f64; NUM_FEATURES])> {
    let b = branches(g, v, ends, dt, n);
    let mut out = Vec::new();
    for i in 0..b.len() {
        for j in i + 1..b.len() {
            let rule = rules.contains(&(b[i].end, b[j].end));
            out.push((b[i].end, b[j].end, pair_features(g, v, &b, (i, j), rule, frame)));
        }
    }
    out
}

/// Walks the live edges into chains through their paired ends: first from every unpaired end,
/// then around the loops left.
fn walk_chains(g: &Graph, partner: &[usize]) -> Vec<Vec<Point>> {
    let live: Vec<usize> = (0..g.edges.len()).filter(|&k| g.edges[k].alive).collect();
    let mut used = vec![false; g.edges.len()];
    let mut strokes = Vec::new();
    for &k in &live {
        for end in [2 * k, 2 * k + 1] {
            if !used[k] && partner[end] == UNPAIRED {
                strokes.push(walk(g, partner, end, &mut used));
            }
        }
    }
    for &k in &live {
        if !used[k] {
            strokes.push(walk(g, partner, 2 * k, &mut used));
        }
    }
    strokes
}

/// The chain entered at branch end `start_end`, edge after edge through paired ends, until an
/// unpaired end or an edge already used.
fn walk(g: &Graph, partner: &[usize], start_end: usize, used: &mut [bool]) -> Vec<Point> {
    let mut pts: Vec<Point> = Vec::new();
    let mut end = start_end;
    loop {
        let k = end / 2;
        if used[k] {
            break;
        }
        used[k] = true;
        let e = &g.edges[k];
        let seg: Vec<Point> = if end % 2 == 0 { e.pts.clone() } else { e.pts.iter().rev().copied().collect() };
        if pts.is_empty() {
            pts.extend(seg);
        } else {
            pts.extend(seg.into_iter().skip(1));
        }
        match partner[end ^ 1] {
            UNPAIRED => break,
            next => end = next,
        }
    }
    pts
}

/// A light moving average (window 5) that keeps the end points.
fn smooth(p: &[Point]) -> Vec<Point> {
    if p.len() < 5 {
        return p.to_vec();
    }
    let mut out = Vec::with_capacity(p.len());
    out.push(p[0]);
    for i in 1..p.len() - 1 {
        let (lo, hi) = (i.saturating_sub(2), (i + 2).min(p.len() - 1));
        let mut s = Vec2::ZERO;
        for q in &p[lo..=hi] {
            s += q.to_vec2();
        }
        out.push((s / (hi - lo + 1) as f64).to_point());
    }
    out.push(p[p.len() - 1]);
    out
}

/// Drops short pieces that lie wholly inside the ink of other strokes (a crossing that thinning
/// drew as two junctions leaves such a piece between them): they add no ink of their own, and
/// counted as strokes they would be wrong.
pub(super) fn drop_covered(strokes: Vec<Vec<Point>>, dt: &[f32], n: usize, k: f64) -> Vec<Vec<Point>> {
    let width = |p: Point| crate::distance::sample(dt, n, n, p.x, p.y).max(1.0);
    let near = |p: Point, s: &[Point]| {
        s.windows(2)
            .map(|w| kurbo::ParamCurveNearest::nearest(&kurbo::Line::new(w[0], w[1]), p, 1e-6).distance_sq.sqrt())
            .fold(f64::INFINITY, f64::min)
    };
    let mut keep = vec![true; strokes.len()];
    for i in 0..strokes.len() {
        let s = &strokes[i];
        let w = s.iter().map(|&p| width(p)).fold(0.0, f64::max);
        if length(s) > k * w {
            continue;
        }
        let covered = s.iter().all(|&p| {
            let wp = width(p);
            (0..strokes.len()).any(|j| j != i && keep[j] && strokes[j].len() > 1 && near(p, &strokes[j]) < wp)
        });
        if covered {
            keep[i] = false;
        }
    }
    strokes.into_iter().zip(keep).filter_map(|(s, k)| k.then_some(s)).collect()
}
