//! From a skeleton to strokes: a graph of end points and junctions ([`graph`]), spur pruning
//! and junction merging, pairing of the branches that continue each other at crossings
//! ([`chains`]), corner and hook rules ([`corners`]), and stroke order ([`order`]). Which pairs
//! continue through a junction and which corners split are decided by two small learned models
//! ([`learned`], compiled in from `data/skeleton-models.json`) that take the hand rules'
//! verdicts among their features; `GraphOptions::learned_pairing` / `learned_corners` off gives
//! the rules alone.
//!
//! Frame: the analysis raster (`n × n` px of the em box, pixel centres at `i + 0.5`, y down);
//! widths are distance-transform values (px). [`crate::medians`] scales the result into the em
//! frame. Invariant: the output is a pure function of the skeleton, the distance transform,
//! the [`GraphOptions`] and the compiled-in models (no randomness, no environment).

mod chains;
mod corners;
mod graph;
mod learned;
mod options;
mod order;

use kurbo::Point;

pub use learned::{
    CORNER_FEATURE_NAMES, DecisionModel, FEATURE_NAMES, NUM_CORNER_FEATURES, NUM_FEATURES, SkeletonModelError,
    SkeletonModels,
};
pub use options::GraphOptions;

use crate::polyline::length;
use chains::{Pairing, drop_covered, pair_and_chain};
use corners::{CornerSplit, corner_samples, split_at_corners};
use graph::{Graph, attach_loose_ends, build_graph, degree, merge_junctions, prune_spurs};
use learned::{GlyphFrame, end_strokes};
use order::order_strokes;

/// Chains no longer than this (px) are thinning debris, not strokes. Hand-set.
const MIN_STROKE_PX: f64 = 1.5;

/// Extracts strokes from a one-pixel skeleton. `dt` is the distance transform of the glyph mask
/// (same `n × n` raster). Returns polylines in pixel coordinates, oriented and ordered by the
/// usual writing rules. Junctions pair their branches and corners split with the learned
/// models ([`SkeletonModels::embedded`]) unless `opts.learned_pairing` / `opts.learned_corners`
/// is off.
pub(crate) fn skeleton_strokes(skel: &[bool], dt: &[f32], n: usize, opts: &GraphOptions) -> Vec<Vec<Point>> {
    let g = cleaned_graph(skel, dt, n, opts);
    let frame = GlyphFrame::of(skel, dt, n);
    let models = SkeletonModels::embedded();
    let pairing = if opts.learned_pairing { Pairing::Model(&models.pairs, &frame) } else { Pairing::Rules };
    let corners = if opts.learned_corners { CornerSplit::Model(&models.corners, &frame) } else { CornerSplit::Rules };
    strokes_of_graph(&g, dt, n, opts, pairing, corners)
}

/// The skeleton's graph with loose ends joined, spurs pruned and nearby junctions merged.
fn cleaned_graph(skel: &[bool], dt: &[f32], n: usize, opts: &GraphOptions) -> Graph {
    let mut g = build_graph(skel, dt, n);
    attach_loose_ends(&mut g, opts.loose_end_em * n as f64 / 1024.0);
    prune_spurs(&mut g, opts);
    merge_junctions(&mut g, opts);
    prune_spurs(&mut g, opts);
    g
}

/// Pairs, chains, splits at corners, drops debris and orders.
fn strokes_of_graph(
    g: &Graph,
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    pairing: Pairing<'_>,
    corners: CornerSplit<'_>,
) -> Vec<Vec<Point>> {
    let junctions = junctions(g);
    let strokes: Vec<Vec<Point>> = pair_and_chain(g, dt, n, opts, pairing)
        .iter()
        .flat_map(|s| split_at_corners(s, dt, n, opts, &junctions, corners))
        .collect();
    let strokes: Vec<Vec<Point>> = strokes.into_iter().filter(|s| length(s) > MIN_STROKE_PX).collect();
    let strokes = drop_covered(strokes, dt, n, opts.covered_max_widths);
    order_strokes(strokes)
}

/// Where three or more branches meet (chains that end there end against other strokes).
fn junctions(g: &Graph) -> Vec<Point> {
    (0..g.nodes.len()).filter(|&v| g.nodes[v].alive && degree(g, v) >= 3).map(|v| g.nodes[v].pos).collect()
}

/// One corner of a chain, for training the corner model: its features
/// ([`CORNER_FEATURE_NAMES`]) and, when the glyph's medians say, whether two strokes meet there.
#[derive(Clone, Debug)]
pub struct CornerSample {
    /// The features, in [`CORNER_FEATURE_NAMES`] order.
    pub features: [f64; NUM_CORNER_FEATURES],
    /// `Some(true)`: split (two strokes); `Some(false)`: one stroke turns; `None`: unknown.
    pub label: Option<bool>,
}

/// One candidate pair of branch ends at a junction, for training the pairing model: its
/// features ([`FEATURE_NAMES`]) and, when the glyph's medians say, whether the two ends lie
/// along the same stroke.
#[derive(Clone, Debug)]
pub struct PairSample {
    /// The features, in [`FEATURE_NAMES`] order.
    pub features: [f64; NUM_FEATURES],
    /// `Some(true)`: one stroke runs through; `Some(false)`: two strokes; `None`: unknown.
    pub label: Option<bool>,
}

/// A glyph's skeleton on the analysis raster: the thinned mask and the distance transform of the
/// glyph mask (`n × n`, pixel centres at `i + 0.5`), as [`crate::centre_lines`] computes them
/// for [`crate::Method::Skeleton`].
#[derive(Clone, Debug)]
pub struct Skeleton {
    /// One-pixel-wide skeleton, row-major.
    pub skel: Vec<bool>,
    /// Distance to the background, px.
    pub dt: Vec<f32>,
    /// Side, px.
    pub n: usize,
}

impl Skeleton {
    /// Rasterises `g` at `analysis_px`², thins it (Zhang–Suen, staircase removal) and takes its
    /// distance transform; `None` when the glyph has no ink there.
    pub fn of(g: &crate::Glyph, analysis_px: u32) -> Option<Skeleton> {
        let n = analysis_px as usize;
        let mask = crate::raster::mask_of(&crate::raster::render_glyph(g, analysis_px));
        if !mask.iter().any(|&b| b) {
            return None;
        }
        let dt = crate::distance::distance_to_background(&mask, n, n);
        let mut skel = mask;
        crate::thinning::zhang_suen(&mut skel, n, n);
        crate::thinning::remove_staircases(&mut skel, n, n);
        Some(Skeleton { skel, dt, n })
    }

    /// The strokes found with `opts`, in pixels (analysis raster).
    pub fn strokes(&self, opts: &GraphOptions) -> Vec<Vec<Point>> {
        skeleton_strokes(&self.skel, &self.dt, self.n, opts)
    }

    /// Medians (em frame) on the analysis raster, px.
    fn medians_px(&self, medians_em: &[Vec<Point>]) -> Vec<Vec<Point>> {
        let k = self.n as f64 / crate::glyph::EM;
        medians_em.iter().map(|m| m.iter().map(|p| Point::new(p.x * k, p.y * k)).collect()).collect()
    }

    /// Training samples for the pairing model: every candidate pair of branch ends at every
    /// junction, labelled from the glyph's own medians (`medians_em`, em frame) where they say
    /// which stroke each end lies along.
    pub fn pair_samples(&self, opts: &GraphOptions, medians_em: &[Vec<Point>]) -> Vec<PairSample> {
        let g = cleaned_graph(&self.skel, &self.dt, self.n, opts);
        let labels = end_strokes(&g, &self.medians_px(medians_em));
        let frame = GlyphFrame::of(&self.skel, &self.dt, self.n);
        chains::pair_samples(&g, &self.dt, self.n, opts, &frame, &labels)
            .into_iter()
            .map(|(features, label)| PairSample { features, label })
            .collect()
    }

    /// Training samples for the corner model: every corner of every chain (chains as `pairs`
    /// pairs junctions, or the hand rules with `None`), labelled from the glyph's own medians
    /// (`medians_em`, em frame) where they say which stroke each leg lies along.
    pub fn corner_samples(
        &self,
        opts: &GraphOptions,
        pairs: Option<&DecisionModel>,
        medians_em: &[Vec<Point>],
    ) -> Vec<CornerSample> {
        let (dt, n) = (&self.dt, self.n);
        let g = cleaned_graph(&self.skel, dt, n, opts);
        let frame = GlyphFrame::of(&self.skel, dt, n);
        let medians = self.medians_px(medians_em);
        let pairing = pairs.map_or(Pairing::Rules, |m| Pairing::Model(m, &frame));
        let junctions = junctions(&g);
        pair_and_chain(&g, dt, n, opts, pairing)
            .iter()
            .flat_map(|c| corner_samples(c, dt, n, opts, &junctions, &frame, &medians))
            .map(|(features, label)| CornerSample { features, label })
            .collect()
    }

    /// The strokes found when junctions pair their branches and corners split as the glyph's
    /// own medians say (`medians_em`, em frame; where they say nothing, by the hand rules), each
    /// only where `opts` turns its learned decision on: how far better decisions could go. For
    /// measurements only (it needs the answer).
    pub fn strokes_paired_by_medians(&self, opts: &GraphOptions, medians_em: &[Vec<Point>]) -> Vec<Vec<Point>> {
        let g = cleaned_graph(&self.skel, &self.dt, self.n, opts);
        let medians = self.medians_px(medians_em);
        let labels = end_strokes(&g, &medians);
        let corners = if opts.learned_corners { CornerSplit::Labels(&medians) } else { CornerSplit::Rules };
        let pairing = if opts.learned_pairing { Pairing::Labels(&labels) } else { Pairing::Rules };
        strokes_of_graph(&g, &self.dt, self.n, opts, pairing, corners)
    }
}

#[cfg(test)]
mod tests {
    use super::graph::{Edge, Node};
    use super::order::is_horizontal;
    use super::*;
    use crate::distance::distance_to_background;
    use crate::thinning::zhang_suen;

    /// The hand rules alone: the tests below pin them down (the learned decisions, on by
    /// default, are tested on their own and on real glyphs in tests/skeleton_counts.rs).
    fn rules() -> GraphOptions {
        GraphOptions { learned_pairing: false, learned_corners: false, ..GraphOptions::default() }
    }

    fn strokes_of(mask: Vec<bool>, n: usize) -> Vec<Vec<Point>> {
        strokes_with(mask, n, &rules())
    }

    fn strokes_with(mask: Vec<bool>, n: usize, opts: &GraphOptions) -> Vec<Vec<Point>> {
        let dt = distance_to_background(&mask, n, n);
        let mut skel = mask;
        zhang_suen(&mut skel, n, n);
        crate::thinning::remove_staircases(&mut skel, n, n);
        skeleton_strokes(&skel, &dt, n, opts)
    }

    fn bar(m: &mut [bool], n: usize, x0: usize, x1: usize, y0: usize, y1: usize) {
        for y in y0..y1 {
            for x in x0..x1 {
                m[y * n + x] = true;
            }
        }
    }

    #[test]
    fn a_cross_splits_into_horizontal_then_vertical() {
        let n = 96;
        let mut m = vec![false; n * n];
        bar(&mut m, n, 10, 86, 44, 52); // horizontal
        bar(&mut m, n, 44, 52, 8, 88); // vertical
        let s = strokes_of(m, n);
        assert_eq!(s.len(), 2, "{s:?}");
        // Horizontal first (it crosses the vertical), drawn left to right.
        let (h, v) = (&s[0], &s[1]);
        assert!(h[0].x < 20.0 && h[h.len() - 1].x > 76.0 && (h[0].y - 48.0).abs() < 3.0);
        assert!(v[0].y < 18.0 && v[v.len() - 1].y > 78.0 && (v[0].x - 48.0).abs() < 3.0);
    }

    #[test]
    fn a_t_junction_keeps_the_bar_whole() {
        let n = 96;
        let mut m = vec![false; n * n];
        bar(&mut m, n, 10, 86, 14, 22); // top bar
        bar(&mut m, n, 44, 52, 14, 88); // stem hanging from it
        let s = strokes_of(m, n);
        assert_eq!(s.len(), 2, "{s:?}");
        assert!(is_horizontal(&s[0]) && !is_horizontal(&s[1]));
        let stem = &s[1];
        assert!(stem[stem.len() - 1].y > 80.0 && stem[0].y < 26.0);
    }

    /// A thick segment from `a` to `b` (pixel units), half-width `r`.
    fn line(m: &mut [bool], n: usize, a: (f64, f64), b: (f64, f64), r: f64) {
        let (a, b) = (Point::new(a.0, a.1), Point::new(b.0, b.1));
        for y in 0..n {
            for x in 0..n {
                let q = Point::new(x as f64 + 0.5, y as f64 + 0.5);
                let t = ((q - a).dot(b - a) / (b - a).hypot2()).clamp(0.0, 1.0);
                if q.distance(a + (b - a) * t) <= r {
                    m[y * n + x] = true;
                }
            }
        }
    }

    /// A segment's two ends, pixel units.
    type Segment = ((f64, f64), (f64, f64));

    fn shape(n: usize, segments: &[Segment]) -> Vec<Vec<Point>> {
        let mut m = vec![false; n * n];
        for &(a, b) in segments {
            line(&mut m, n, a, b, 4.0);
        }
        strokes_of(m, n)
    }

    #[test]
    fn a_box_is_three_strokes_like_kou() {
        // 口: left side, top + right side (横折), bottom.
        let s = shape(
            100,
            &[
                ((20.0, 20.0), (20.0, 80.0)),
                ((20.0, 20.0), (80.0, 20.0)),
                ((80.0, 20.0), (80.0, 80.0)),
                ((20.0, 80.0), (80.0, 80.0)),
            ],
        );
        assert_eq!(s.len(), 3, "{s:?}");
        // One of them turns: starts at the upper left going right, ends at the lower right.
        let hengzhe = s.iter().find(|p| {
            let (a, b) = (p[0], p[p.len() - 1]);
            a.x < 35.0 && a.y < 30.0 && b.x > 70.0 && b.y > 65.0
        });
        assert!(hengzhe.is_some(), "{s:?}");
    }

    #[test]
    fn a_corner_where_two_strokes_start_is_split() {
        // 厂's corner: a bar going right and a bar going down both start at the upper left.
        let s = shape(100, &[((20.0, 20.0), (85.0, 20.0)), ((20.0, 20.0), (20.0, 85.0))]);
        assert_eq!(s.len(), 2, "{s:?}");
    }

    #[test]
    fn a_turn_written_in_one_go_stays_whole() {
        // 横折: right, then down.
        assert_eq!(shape(100, &[((15.0, 20.0), (80.0, 20.0)), ((80.0, 20.0), (80.0, 85.0))]).len(), 1);
        // 竖提: down, then rising to the right.
        assert_eq!(shape(100, &[((20.0, 10.0), (20.0, 85.0)), ((20.0, 85.0), (88.0, 30.0))]).len(), 1);
        // A vertical with a short hook to the left at its foot (竖钩).
        assert_eq!(shape(100, &[((50.0, 10.0), (50.0, 85.0)), ((50.0, 85.0), (34.0, 78.0))]).len(), 1);
    }

    #[test]
    fn an_end_beside_a_junction_is_joined_to_it() {
        let node = |x: f64, y: f64| Node { pos: Point::new(x, y), width: 5.0, alive: true };
        let edge = |a: usize, b: usize, g: &[Node]| Edge { a, b, pts: vec![g[a].pos, g[b].pos], alive: true };
        // A junction at (50, 50) with three branches, a loose end 2 px from it with its own
        // branch, and a far end point that must stay free.
        let nodes = vec![
            node(50.0, 50.0),
            node(10.0, 50.0),
            node(90.0, 50.0),
            node(50.0, 10.0),
            node(51.0, 52.0),
            node(80.0, 90.0),
            node(57.0, 50.0),
        ];
        let edges = vec![edge(0, 1, &nodes), edge(0, 2, &nodes), edge(0, 3, &nodes), edge(4, 5, &nodes)];
        let mut g = Graph { nodes, edges };
        attach_loose_ends(&mut g, 4.5);
        assert!(!g.nodes[4].alive);
        assert_eq!(degree(&g, 0), 4);
        assert_eq!((g.edges[3].a, g.edges[3].b), (0, 5));
        assert_eq!(g.edges[3].pts[0], Point::new(50.0, 50.0));
        // Ends already joined to the junction, or too far from it, are left alone.
        assert!(g.nodes[1].alive && g.nodes[5].alive && g.nodes[6].alive);
    }

    #[test]
    fn an_l_corner_is_one_stroke() {
        let n = 80;
        let mut m = vec![false; n * n];
        bar(&mut m, n, 10, 18, 10, 70);
        bar(&mut m, n, 10, 70, 62, 70);
        let s = strokes_of(m, n);
        assert_eq!(s.len(), 1, "{s:?}");
    }

    #[test]
    fn a_stub_off_a_hook_corner_is_pruned() {
        // 竖提: down, then up to the right; the thinned blunt corner leaves a stub pointing down.
        let n = 128;
        let mut m = vec![false; n * n];
        line(&mut m, n, (40.0, 10.0), (40.0, 90.0), 6.0);
        line(&mut m, n, (40.0, 90.0), (80.0, 52.0), 6.0);
        line(&mut m, n, (40.0, 90.0), (40.0, 106.0), 6.0);
        let with = strokes_of(m.clone(), n);
        assert_eq!(with.len(), 1, "{with:?}");
        // Pruned only by the corner rule: as an ordinary spur the stub would stay.
        let plain = GraphOptions { corner_spur_factor: GraphOptions::default().spur_factor, ..rules() };
        assert!(strokes_with(m, n, &plain).len() > 1);
    }

    #[test]
    fn the_bottom_of_an_open_box_is_its_own_stroke() {
        // 甘 without its inner bar: a top bar crossed by two uprights, and a bottom between them.
        // The left upright and the bottom form an open chain (the upright starts above the bar).
        let segs = [
            ((10.0, 30.0), (90.0, 30.0)),
            ((30.0, 10.0), (30.0, 82.0)),
            ((70.0, 10.0), (70.0, 82.0)),
            ((30.0, 82.0), (70.0, 82.0)),
        ];
        let s = shape(100, &segs);
        assert_eq!(s.len(), 4, "{s:?}");
        let mut m = vec![false; 100 * 100];
        for &(a, b) in &segs {
            line(&mut m, 100, a, b, 4.0);
        }
        let old = GraphOptions { open_box_min_ratio: 0.0, ..rules() };
        let o = strokes_with(m, 100, &old);
        assert_eq!(o.len(), 3, "without the rule the left side and the bottom are one: {o:?}");
        // 山: the 竖折's vertical leg is short against its bottom, so it stays one stroke.
        let shan = shape(
            128,
            &[
                ((64.0, 10.0), (64.0, 100.0)),
                ((20.0, 64.0), (20.0, 100.0)),
                ((20.0, 100.0), (108.0, 100.0)),
                ((108.0, 40.0), (108.0, 100.0)),
            ],
        );
        assert_eq!(shan.len(), 3, "{shan:?}");
    }

    #[test]
    fn a_box_bottom_that_rises_a_little_is_not_a_ti() {
        // 口 with its bottom rising 17° to the right, as kaishu writes it: still three strokes.
        let segs = [
            ((20.0, 20.0), (20.0, 80.0)),
            ((20.0, 20.0), (80.0, 20.0)),
            ((80.0, 20.0), (80.0, 66.0)),
            ((20.0, 84.0), (80.0, 66.0)),
        ];
        assert_eq!(shape(100, &segs).len(), 3);
        // A real 竖提 (rising steeply out of a vertical) stays one stroke.
        assert_eq!(shape(100, &[((20.0, 10.0), (20.0, 80.0)), ((20.0, 80.0), (70.0, 50.0))]).len(), 1);
    }

    #[test]
    fn options_are_set_by_name() {
        let mut o = GraphOptions::default();
        o.set("corner_deg", 45.0).unwrap();
        assert!((o.corner_rad - 45f64.to_radians()).abs() < 1e-12);
        o.set("split_box_corners", 0.0).unwrap();
        assert!(!o.split_box_corners);
        assert!(o.set("nope", 1.0).unwrap_err().contains("unknown skeleton option `nope`"));
        assert!(o.set("hook_ratio", f64::NAN).is_err());
    }

    #[test]
    fn the_embedded_models_load() {
        let m = SkeletonModels::embedded();
        assert_eq!(m.pairs.features, FEATURE_NAMES);
        assert_eq!(m.corners.features, CORNER_FEATURE_NAMES);
        let p = m.pairs.probability(&m.pairs.mean);
        assert!(p > 0.0 && p < 1.0);
        assert!(matches!(SkeletonModels::from_json("{}"), Err(SkeletonModelError::Json(_))));
        // A file from another version (a feature renamed) or with a layer cut short is refused,
        // naming the model.
        let mut other = m.clone();
        other.corners.features[0] = "something else".into();
        let e = SkeletonModels::from_json(&serde_json::to_string(&other).unwrap()).unwrap_err();
        assert!(matches!(e, SkeletonModelError::Features { model: "corners", .. }), "{e}");
        let mut short = m.clone();
        short.pairs.hidden_bias.pop();
        let e = SkeletonModels::from_json(&serde_json::to_string(&short).unwrap()).unwrap_err();
        assert!(e.to_string().contains("skeleton model `pairs`: layer sizes"), "{e}");
    }

    /// The skeleton of a `+` (horizontal 10–86 at y 44–52, vertical 44–52 at y 8–88, 96²), its
    /// cleaned graph and its one junction.
    fn cross() -> (Vec<bool>, Vec<f32>, usize, Graph, usize) {
        let n = 96;
        let mut m = vec![false; n * n];
        bar(&mut m, n, 10, 86, 44, 52);
        bar(&mut m, n, 44, 52, 8, 88);
        let dt = distance_to_background(&m, n, n);
        let mut skel = m;
        zhang_suen(&mut skel, n, n);
        crate::thinning::remove_staircases(&mut skel, n, n);
        let g = cleaned_graph(&skel, &dt, n, &GraphOptions::default());
        let v = (0..g.nodes.len()).find(|&v| g.nodes[v].alive && degree(&g, v) == 4).expect("one 4-way junction");
        (skel, dt, n, g, v)
    }

    #[test]
    fn a_crossing_pairs_straight_through() {
        let (skel, dt, n, g, v) = cross();
        let frame = GlyphFrame::of(&skel, &dt, n);
        let ends = graph::ends_at(&g, v);
        let b = learned::branches(&g, v, &ends, &dt, n);
        let model = &SkeletonModels::embedded().pairs;
        for i in 0..4 {
            for j in i + 1..4 {
                let straight = b[i].dir.dot(b[j].dir) < -0.9;
                let x = learned::pair_features(&g, v, &b, (i, j), straight, &frame);
                // Features: the cosine, the degree, the junction's place in the middle.
                assert!((x[0] - b[i].dir.dot(b[j].dir)).abs() < 1e-12);
                assert_eq!((x[10], x[11]), (0.0, 0.0), "four branches");
                assert!((x[20] - 0.5).abs() < 0.1 && (x[21] - 0.5).abs() < 0.1, "{x:?}");
                let p = model.probability(&x);
                assert_eq!(p >= model.threshold, straight, "pair {i}-{j}: cos {} p {p}", x[0]);
            }
        }
    }

    #[test]
    fn training_labels_come_from_the_medians() {
        let (skel, dt, n, g, v) = cross();
        let medians = vec![
            vec![Point::new(12.0, 48.0), Point::new(84.0, 48.0)],
            vec![Point::new(48.0, 10.0), Point::new(48.0, 86.0)],
        ];
        let labels = end_strokes(&g, &medians);
        let ends = graph::ends_at(&g, v);
        for &(e, d) in &ends {
            let want = if d.x.abs() > d.y.abs() { 0 } else { 1 };
            assert_eq!(labels[e], Some(want), "end leaving {d:?}");
        }
        // The same through the public API (medians in the em frame, 1024 units for 96 px).
        let sk = Skeleton { skel, dt, n };
        let em: Vec<Vec<Point>> = medians
            .iter()
            .map(|m| m.iter().map(|p| Point::new(p.x * 1024.0 / 96.0, p.y * 1024.0 / 96.0)).collect())
            .collect();
        let samples = sk.pair_samples(&GraphOptions::default(), &em);
        assert_eq!(samples.len(), 6);
        assert_eq!(samples.iter().filter(|s| s.label == Some(true)).count(), 2);
        assert!(samples.iter().all(|s| s.label == Some(s.features[0] < -0.9)));
        assert_eq!(sk.strokes_paired_by_medians(&GraphOptions::default(), &em).len(), 2);
    }

    #[test]
    fn pieces_inside_other_strokes_are_dropped() {
        let n = 100;
        let dt = vec![4.0f32; n * n];
        let pl = |pts: &[(f64, f64)]| pts.iter().map(|&(x, y)| Point::new(x, y)).collect::<Vec<_>>();
        let strokes = vec![
            pl(&[(10.0, 50.0), (90.0, 50.0)]), // horizontal
            pl(&[(50.0, 10.0), (50.0, 90.0)]), // vertical
            pl(&[(47.0, 51.0), (55.0, 52.0)]), // a piece inside the crossing
            pl(&[(20.0, 20.0), (26.0, 24.0)]), // a dot on its own
            pl(&[(70.0, 50.0), (72.0, 58.0)]), // short, but leaves the horizontal's ink
        ];
        let kept = drop_covered(strokes.clone(), &dt, n, GraphOptions::default().covered_max_widths);
        assert_eq!(kept.len(), 4);
        assert!(!kept.contains(&strokes[2]));
    }
}
