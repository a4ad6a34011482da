//! The learned decisions of the skeleton method: at a junction of three or more branches, which
//! two branch ends continue each other (one stroke through the junction) and which end there;
//! at a corner of a chain, whether two strokes meet there (split) or one stroke turns.
//!
//! Each is a tiny multilayer perceptron ([`DecisionModel`], one hidden layer of tanh units and
//! a logistic output) over geometric features ([`FEATURE_NAMES`] for a pair of branch ends,
//! [`CORNER_FEATURE_NAMES`] for a corner) among which are the hand rules' own verdicts. Pairs
//! are taken most probable first while their probability reaches the model's threshold;
//! corners split where it does. The weights are `data/skeleton-models.json`, compiled in;
//! `cargo xtask skeleton-train` writes them. Training labels come from the glyph's own medians
//! ([`end_strokes`], [`stroke_along`]): each branch end or corner leg is assigned the median
//! stroke it lies along; a pair is positive when both of its ends lie along the same stroke, a
//! corner when its legs lie along different ones.
//!
//! Frame: the analysis raster (px, y down), as in [`super`]; features are unitless (lengths and
//! widths relative to the local half-width, positions relative to the skeleton's bounding box,
//! directions as unit vectors).

use std::sync::OnceLock;

use kurbo::{Point, Vec2};
use serde::{Deserialize, Serialize};

use super::graph::{Graph, branch_width, degree};
use crate::polyline::length;

/// The compiled-in models (see the module doc).
static MODELS_JSON: &str = include_str!("../../data/skeleton-models.json");

/// Names of the features of one candidate pair, in the order the pair features are computed. "thin" and "thick"
/// are the pair's two branches ordered by their half-width (measured one to three junction
/// half-widths out); "dir" is the unit direction a branch leaves the junction in.
pub const FEATURE_NAMES: [&str; NUM_FEATURES] = [
    "cos",            // dot of the two directions (-1: straight through)
    "cos_sq",         // its square
    "rule_pair",      // the hand rules pair these two ends (1/0)
    "width_ratio",    // thinner / thicker branch half-width
    "thin_width",     // thinner branch half-width / junction half-width
    "thick_width",    // thicker branch half-width / junction half-width
    "thin_len",       // ln(1 + edge length / junction half-width), thinner branch
    "thick_len",      // the same, thicker branch
    "thin_free",      // the thinner branch's edge ends at a free end (1/0)
    "thick_free",     // the same, thicker branch
    "degree3",        // the junction has three branches (1/0)
    "degree5",        // the junction has five or more branches (1/0)
    "best_alt",       // straightest cos either end makes with a third branch (1 if none)
    "is_straightest", // no other pair at the junction is straighter (1/0)
    "thin_dx",        // thinner branch direction, x
    "thin_dy",        // thinner branch direction, y (down)
    "thick_dx",       // thicker branch direction, x
    "thick_dy",       // thicker branch direction, y
    "line_dx_sq",     // squared x of the unit line through the pair (thin - thick)
    "line_dxdy",      // x·y of that line (sign: 捺-like vs 撇-like)
    "rel_x",          // junction x in the skeleton's bounding box (0 left, 1 right)
    "rel_y",          // junction y in the skeleton's bounding box (0 top, 1 bottom)
    "junction_width", // junction half-width / the skeleton's mean half-width
    "thin_turn",      // cos of the thinner branch's turn over its edge (chord vs leaving dir)
    "thick_turn",     // the same, thicker branch
];

/// How many features a candidate pair has ([`FEATURE_NAMES`]).
pub const NUM_FEATURES: usize = 25;

/// Why a skeleton model file was refused ([`SkeletonModels::from_json`]).
#[derive(Debug, thiserror::Error)]
pub enum SkeletonModelError {
    /// The text is not JSON of the model format.
    #[error("skeleton models: not the model file format")]
    Json(#[source] serde_json::Error),
    /// A model reads other features than this build computes (a file from another version).
    #[error("skeleton model `{model}`: features {found:?}, expected {expected:?}")]
    Features {
        /// Which model: `pairs` or `corners`.
        model: &'static str,
        /// The features the file names.
        found: Vec<String>,
        /// The features this build computes, in order.
        expected: Vec<String>,
    },
    /// A model's layer sizes do not fit its features (or a scale is not positive).
    #[error("skeleton model `{model}`: layer sizes do not fit its {features} features (or a scale is not positive)")]
    Sizes {
        /// Which model: `pairs` or `corners`.
        model: &'static str,
        /// How many features it reads.
        features: usize,
    },
}

/// The skeleton's two learned decisions, as compiled in: junction pairing and corner splitting.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SkeletonModels {
    /// What the file is and how it was made (free text).
    pub about: String,
    /// At a junction, whether a pair of branch ends continues through ([`FEATURE_NAMES`]).
    pub pairs: DecisionModel,
    /// At a chain's corner, whether two strokes meet there ([`CORNER_FEATURE_NAMES`]).
    pub corners: DecisionModel,
}

impl SkeletonModels {
    /// Parses and checks a model file's text (each model as [`DecisionModel::check`]).
    ///
    /// # Errors
    /// [`SkeletonModelError::Json`] when the text is not the model format;
    /// [`SkeletonModelError::Features`] or [`SkeletonModelError::Sizes`] when a model does not
    /// fit the features this build computes.
    pub fn from_json(text: &str) -> Result<SkeletonModels, SkeletonModelError> {
        let m: SkeletonModels = serde_json::from_str(text).map_err(SkeletonModelError::Json)?;
        m.pairs.check("pairs", &FEATURE_NAMES)?;
        m.corners.check("corners", &CORNER_FEATURE_NAMES)?;
        Ok(m)
    }

    /// The compiled-in models (parsed once).
    ///
    /// # Panics
    /// Never for the committed file (a test loads it); a broken file fails that test.
    pub fn embedded() -> &'static SkeletonModels {
        static MODELS: OnceLock<SkeletonModels> = OnceLock::new();
        MODELS.get_or_init(|| SkeletonModels::from_json(MODELS_JSON).expect("data/skeleton-models.json is valid"))
    }
}

/// One learned decision: a small multilayer perceptron over standardised features: `p = σ(out · tanh(W x' + b) + c)`
/// with `x' = (x − mean) / scale`; with no hidden units, logistic regression `σ(out · x' + c)`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DecisionModel {
    /// What the file is and how it was made (free text).
    pub about: String,
    /// Feature names, in order (must equal [`FEATURE_NAMES`]).
    pub features: Vec<String>,
    /// Per-feature mean subtracted before the model.
    pub mean: Vec<f64>,
    /// Per-feature scale divided by before the model.
    pub scale: Vec<f64>,
    /// Hidden layer weights, one row of `features.len()` per unit (empty: logistic regression).
    pub hidden: Vec<Vec<f64>>,
    /// Hidden layer biases, one per unit.
    pub hidden_bias: Vec<f64>,
    /// Output weights: one per hidden unit (or per feature without a hidden layer).
    pub out: Vec<f64>,
    /// Output bias.
    pub out_bias: f64,
    /// The decision threshold the training report's accuracies use (the skeleton itself uses
    /// `GraphOptions::pair_threshold` / `corner_threshold`).
    pub threshold: f64,
}

impl DecisionModel {
    /// Checks that the model reads the features `names` and that its layer sizes fit; `which`
    /// names the model in the error (`pairs`, `corners`).
    ///
    /// # Errors
    /// [`SkeletonModelError::Features`] when the model reads other features than `names`,
    /// [`SkeletonModelError::Sizes`] when its layers do not fit them.
    pub fn check(&self, which: &'static str, names: &[&str]) -> Result<(), SkeletonModelError> {
        if self.features != names {
            return Err(SkeletonModelError::Features {
                model: which,
                found: self.features.clone(),
                expected: names.iter().map(|n| n.to_string()).collect(),
            });
        }
        let f = names.len();
        let sizes_ok = self.mean.len() == f
            && self.scale.len() == f
            && self.scale.iter().all(|&s| s > 0.0)
            && self.hidden.iter().all(|r| r.len() == f)
            && self.hidden_bias.len() == self.hidden.len()
            && self.out.len() == if self.hidden.is_empty() { f } else { self.hidden.len() };
        if !sizes_ok {
            return Err(SkeletonModelError::Sizes { model: which, features: f });
        }
        Ok(())
    }

    /// The model's probability for features `x` (as many as [`DecisionModel::features`]).
    pub fn probability(&self, x: &[f64]) -> f64 {
        let z: Vec<f64> = x.iter().zip(&self.mean).zip(&self.scale).map(|((v, m), s)| (v - m) / s).collect();
        let logit = if self.hidden.is_empty() {
            self.out.iter().zip(&z).map(|(w, v)| w * v).sum::<f64>() + self.out_bias
        } else {
            self.hidden
                .iter()
                .zip(&self.hidden_bias)
                .zip(&self.out)
                .map(|((row, b), o)| o * (row.iter().zip(&z).map(|(w, v)| w * v).sum::<f64>() + b).tanh())
                .sum::<f64>()
                + self.out_bias
        };
        1.0 / (1.0 + (-logit).exp())
    }
}

/// What the features need to know about the whole skeleton.
#[derive(Clone, Copy, Debug)]
pub(super) struct GlyphFrame {
    /// The skeleton's bounding box, px.
    pub(super) min: Point,
    pub(super) max: Point,
    /// Mean half-width along the skeleton, px.
    pub(super) mean_width: f64,
}

impl GlyphFrame {
    /// Where `p` lies in the bounding box (0 to 1 each way).
    pub(super) fn relative(&self, p: Point) -> (f64, f64) {
        let span = self.max - self.min;
        ((p.x - self.min.x) / span.x.max(1.0), (p.y - self.min.y) / span.y.max(1.0))
    }

    pub(super) fn of(skel: &[bool], dt: &[f32], n: usize) -> GlyphFrame {
        let (mut min, mut max) = (Point::new(f64::INFINITY, f64::INFINITY), Point::new(0.0, 0.0));
        let (mut sum, mut k) = (0.0, 0usize);
        for (i, _) in skel.iter().enumerate().filter(|(_, b)| **b) {
            let p = Point::new((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
            min = Point::new(min.x.min(p.x), min.y.min(p.y));
            max = Point::new(max.x.max(p.x), max.y.max(p.y));
            sum += f64::from(dt[i]);
            k += 1;
        }
        if k == 0 {
            return GlyphFrame { min: Point::ZERO, max: Point::new(n as f64, n as f64), mean_width: 1.0 };
        }
        GlyphFrame { min, max, mean_width: (sum / k as f64).max(1.0) }
    }
}

/// One branch end at a junction, measured once for all the pairs it is in.
#[derive(Clone, Copy, Debug)]
pub(super) struct Branch {
    /// End id (2k: edge k's end a; 2k + 1: its end b).
    pub(super) end: usize,
    /// Unit direction it leaves the junction in.
    pub(super) dir: Vec2,
    /// Half-width one to three junction half-widths out, px.
    width: f64,
    /// Its edge's length, px.
    len: f64,
    /// Its edge ends at a free end.
    free: bool,
    /// Unit chord from the junction to the edge's far end (or `dir` for a loop).
    chord: Vec2,
}

/// The branches at node `v` (its live ends with their directions as [`super::graph::ends_at`]
/// measures them).
pub(super) fn branches(g: &Graph, v: usize, ends: &[(usize, Vec2)], dt: &[f32], n: usize) -> Vec<Branch> {
    ends.iter()
        .map(|&(end, dir)| {
            let e = &g.edges[end / 2];
            let at_a = end % 2 == 0;
            let far = if at_a { e.b } else { e.a };
            let (p0, p1) = if at_a { (e.pts[0], e.pts[e.pts.len() - 1]) } else { (e.pts[e.pts.len() - 1], e.pts[0]) };
            let c = p1 - p0;
            let chord = if far == v || c.hypot() < 1e-9 { dir } else { c / c.hypot() };
            Branch {
                end,
                dir,
                width: branch_width(g, e, at_a, dt, n),
                len: length(&e.pts),
                free: far != v && degree(g, far) == 1,
                chord,
            }
        })
        .collect()
}

/// The features of the pair of branches `i`, `j` at node `v` ([`FEATURE_NAMES`]); `rule_pair`
/// is whether the hand rules pair them.
pub(super) fn pair_features(
    g: &Graph,
    v: usize,
    b: &[Branch],
    (i, j): (usize, usize),
    rule_pair: bool,
    frame: &GlyphFrame,
) -> [f64; NUM_FEATURES] {
    let node = &g.nodes[v];
    let w = node.width.max(1.0);
    let (t, k) = if b[i].width <= b[j].width { (&b[i], &b[j]) } else { (&b[j], &b[i]) };
    let cos = t.dir.dot(k.dir);
    let best_alt = (0..b.len())
        .filter(|&m| m != i && m != j)
        .map(|m| b[i].dir.dot(b[m].dir).min(b[j].dir.dot(b[m].dir)))
        .fold(1.0, f64::min);
    let is_straightest =
        (0..b.len()).all(|p| (p + 1..b.len()).all(|q| (p, q) == (i.min(j), i.max(j)) || b[p].dir.dot(b[q].dir) >= cos));
    let line = t.dir - k.dir;
    let line = if line.hypot() > 1e-9 { line / line.hypot() } else { Vec2::new(1.0, 0.0) };
    let span = frame.max - frame.min;
    let deg = b.len();
    [
        cos,
        cos * cos,
        f64::from(u8::from(rule_pair)),
        t.width.min(k.width) / t.width.max(k.width).max(1e-9),
        t.width / w,
        k.width / w,
        (1.0 + t.len / w).ln(),
        (1.0 + k.len / w).ln(),
        f64::from(u8::from(t.free)),
        f64::from(u8::from(k.free)),
        f64::from(u8::from(deg == 3)),
        f64::from(u8::from(deg >= 5)),
        best_alt,
        f64::from(u8::from(is_straightest)),
        t.dir.x,
        t.dir.y,
        k.dir.x,
        k.dir.y,
        line.x * line.x,
        line.x * line.y,
        (node.pos.x - frame.min.x) / span.x.max(1.0),
        (node.pos.y - frame.min.y) / span.y.max(1.0),
        w / frame.mean_width,
        t.dir.dot(t.chord),
        k.dir.dot(k.chord),
    ]
}

/// Greedy pairing by score: pairs `(score, end, end)` taken highest first while the score is at
/// least `threshold` and both ends are free; writes `partner`.
pub(super) fn pair_greedily(
    mut pairs: Vec<(f64, usize, usize)>,
    threshold: f64,
    partner: &mut [usize],
    unpaired: usize,
) {
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (p, x, y) in pairs {
        if p >= threshold && partner[x] == unpaired && partner[y] == unpaired && x / 2 != y / 2 {
            partner[x] = y;
            partner[y] = x;
        }
    }
}

/// Names of the features of one corner of a chain, in `Chain::corner_features`' order
/// (`corners.rs`). The chain is viewed running from its end nearer the glyph's upper left, so
/// "in" is the leg before the corner and "out" the one after; directions are unit chords over
/// the corner's reach, lengths in half-widths at the corner.
pub const CORNER_FEATURE_NAMES: [&str; NUM_CORNER_FEATURES] = [
    "turn",           // the turn, radians
    "rule_split",     // the hand rules split here (1/0)
    "verdict_split",  // the rules' verdict: Split (1/0)
    "verdict_box",    // the rules' verdict: an open box corner (1/0)
    "ti",             // the rules see 提 rising out of a downward leg (1/0)
    "hook",           // the rules see a hook at a chain end (1/0)
    "forward_in",     // the leg in runs the way strokes are written (1/0)
    "forward_out",    // the same, leg out
    "in_dx",          // leg in direction, x
    "in_dy",          // leg in direction, y (down)
    "out_dx",         // leg out direction, x
    "out_dy",         // leg out direction, y
    "in_len",         // ln(1 + leg in length to the previous corner or end / half-width)
    "out_len",        // the same, leg out
    "chain_len",      // ln(1 + chain length / half-width)
    "closed",         // the chain is a loop (1/0)
    "corners",        // how many corners the chain has
    "first",          // no corner before this one (1/0)
    "last",           // no corner after this one (1/0)
    "start_junction", // the chain's start lies at a junction (1/0)
    "end_junction",   // the chain's end lies at a junction (1/0)
    "in_width",       // mean half-width along the leg in (one to three half-widths out) / corner's
    "out_width",      // the same, leg out
    "width",          // half-width at the corner / the skeleton's mean half-width
    "rel_x",          // corner x in the skeleton's bounding box
    "rel_y",          // corner y in the skeleton's bounding box
];

/// How many features a corner has.
pub const NUM_CORNER_FEATURES: usize = 26;

/// The medians' stroke each branch end lies along, for training labels: per end id, the stroke
/// (index into `medians`, px) whose polyline is nearest on average to the branch's points one to
/// four junction half-widths out, or `None` when no stroke is within two half-widths plus
/// [`LABEL_SLACK_PX`] on average, or the runner-up is nearly as near ([`LABEL_MARGIN`]).
pub(super) fn end_strokes(g: &Graph, medians: &[Vec<Point>]) -> Vec<Option<usize>> {
    let mut out = vec![None; 2 * g.edges.len()];
    for (k, e) in g.edges.iter().enumerate().filter(|(_, e)| e.alive) {
        for at_a in [true, false] {
            let v = if at_a { e.a } else { e.b };
            let w = g.nodes[v].width.max(1.0);
            let pts: Vec<Point> = if at_a { e.pts.clone() } else { e.pts.iter().rev().copied().collect() };
            let mut samples = Vec::new();
            let mut acc = 0.0;
            for p in pts.windows(2) {
                acc += p[0].distance(p[1]);
                if acc >= w && acc <= 4.0 * w {
                    samples.push(p[1]);
                }
            }
            if samples.is_empty() {
                samples.push(pts[pts.len() / 2]);
            }
            out[2 * k + usize::from(!at_a)] = stroke_along(&samples, medians, w);
        }
    }
    out
}

/// The median stroke (index into `medians`, px) nearest on average to `samples`, when it lies
/// within `2w` + [`LABEL_SLACK_PX`] of them and the runner-up is [`LABEL_MARGIN`]`·w` farther.
pub(super) fn stroke_along(samples: &[Point], medians: &[Vec<Point>], w: f64) -> Option<usize> {
    if samples.is_empty() {
        return None;
    }
    let mut dist: Vec<(f64, usize)> = medians
        .iter()
        .enumerate()
        .filter(|(_, m)| !m.is_empty())
        .map(|(s, m)| (samples.iter().map(|&q| distance_to(q, m)).sum::<f64>() / samples.len() as f64, s))
        .collect();
    dist.sort_by(|a, b| a.0.total_cmp(&b.0));
    let &(best, s) = dist.first()?;
    let runner_up = dist.get(1).map_or(f64::INFINITY, |d| d.0);
    (best <= 2.0 * w + LABEL_SLACK_PX && runner_up - best >= LABEL_MARGIN * w).then_some(s)
}

/// Extra distance (px) a branch may lie from its median stroke and still be labelled.
const LABEL_SLACK_PX: f64 = 2.0;
/// The runner-up stroke must be at least this many junction half-widths farther.
const LABEL_MARGIN: f64 = 0.5;

/// Distance from `q` to the polyline `m` (a single point counts as a polyline).
fn distance_to(q: Point, m: &[Point]) -> f64 {
    if m.len() == 1 {
        return q.distance(m[0]);
    }
    m.windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            let t = if d.hypot2() > 0.0 { ((q - w[0]).dot(d) / d.hypot2()).clamp(0.0, 1.0) } else { 0.0 };
            q.distance(w[0] + d * t)
        })
        .fold(f64::INFINITY, f64::min)
}
