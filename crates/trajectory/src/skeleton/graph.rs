//! The skeleton as a graph: nodes at end points and junction clusters, edges along the
//! one-pixel lines between them, and its clean-up (loose ends joined, spurs pruned, nearby
//! junctions merged).
//!
//! Frame: the analysis raster, px, pixel centres at `i + 0.5`, y down. Invariants: every live
//! edge joins two live nodes and its `pts` start at node `a`'s position and end at node `b`'s;
//! a node's `width` is the distance transform there (px, the widest pixel of a junction
//! cluster); dead nodes and edges stay in the vectors (indices are stable) with `alive` false.

use kurbo::{Point, Vec2};

use super::options::GraphOptions;
use crate::polyline::length;

#[derive(Clone, Debug)]
pub(super) struct Node {
    pub(super) pos: Point,
    /// Local half-width at the node, px.
    pub(super) width: f64,
    pub(super) alive: bool,
}

#[derive(Clone, Debug)]
pub(super) struct Edge {
    pub(super) a: usize,
    pub(super) b: usize,
    /// Pixel path from node a to node b (node centres included at both ends).
    pub(super) pts: Vec<Point>,
    pub(super) alive: bool,
}

const N8: [(isize, isize); 8] = [(0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)];

/// Nodes and edges; see the module doc for the invariants.
pub(super) struct Graph {
    pub(super) nodes: Vec<Node>,
    pub(super) edges: Vec<Edge>,
}

/// The graph of a one-pixel skeleton `skel` (`n × n`), node widths from `dt`: nodes first
/// (junction clusters and end pixels), then every line traced from them, then a seed node on
/// each loop that has none.
pub(super) fn build_graph(skel: &[bool], dt: &[f32], n: usize) -> Graph {
    let mut b = Builder {
        px: Pixels { skel, dt, n },
        node_of: vec![NO_NODE; n * n],
        nodes: Vec::new(),
        visited: vec![false; n * n],
        edges: Vec::new(),
    };
    b.find_nodes();
    b.trace_all();
    Graph { nodes: b.nodes, edges: b.edges }
}

/// `node_of` for a pixel that belongs to no node.
const NO_NODE: usize = usize::MAX;

/// The skeleton raster: which pixels are on, their centres and neighbourhoods.
struct Pixels<'a> {
    skel: &'a [bool],
    dt: &'a [f32],
    n: usize,
}

impl Pixels<'_> {
    fn on(&self, x: isize, y: isize) -> bool {
        let n = self.n;
        x >= 0 && y >= 0 && (x as usize) < n && (y as usize) < n && self.skel[y as usize * n + x as usize]
    }

    fn centre(&self, i: usize) -> Point {
        Point::new((i % self.n) as f64 + 0.5, (i / self.n) as f64 + 0.5)
    }

    /// The set 8-neighbours of pixel `i` in [`N8`] order, each with whether it is a 4-neighbour.
    fn neighbours(&self, i: usize) -> Vec<(usize, bool)> {
        let n = self.n;
        let (x, y) = ((i % n) as isize, (i / n) as isize);
        N8.iter()
            .filter(|&&(dx, dy)| self.on(x + dx, y + dy))
            .map(|&(dx, dy)| ((y + dy) as usize * n + (x + dx) as usize, dx == 0 || dy == 0))
            .collect()
    }

    /// Set neighbours and 0→1 transitions around the 8-neighbourhood (the branch count, robust
    /// to staircases).
    fn branches(&self, i: usize) -> (usize, usize) {
        let n = self.n;
        let (x, y) = ((i % n) as isize, (i / n) as isize);
        let p: Vec<bool> = N8.iter().map(|&(dx, dy)| self.on(x + dx, y + dy)).collect();
        let count = p.iter().filter(|&&b| b).count();
        let trans = (0..8).filter(|&k| !p[k] && p[(k + 1) % 8]).count();
        (count, trans)
    }

    /// A junction pixel: three or more branches.
    fn is_junction(&self, i: usize) -> bool {
        self.branches(i).1 >= 3
    }

    fn node_at(&self, i: usize) -> Node {
        Node { pos: self.centre(i), width: self.dt[i] as f64, alive: true }
    }
}

/// The graph under construction: `node_of` maps each node pixel to its node, `visited` marks
/// line pixels already traced.
struct Builder<'a> {
    px: Pixels<'a>,
    node_of: Vec<usize>,
    nodes: Vec<Node>,
    visited: Vec<bool>,
    edges: Vec<Edge>,
}

impl Builder<'_> {
    /// Junction pixels (≥ 3 branches) clustered 8-connected; end pixels alone.
    fn find_nodes(&mut self) {
        let n = self.px.n;
        for i in 0..n * n {
            if !self.px.skel[i] || self.node_of[i] != NO_NODE {
                continue;
            }
            let (count, trans) = self.px.branches(i);
            if self.px.is_junction(i) {
                let node = self.junction_cluster(i);
                self.nodes.push(node);
            } else if count <= 1 || (count == 2 && trans == 1) {
                // An end: one neighbour, or two touching ones (a one-pixel hook at the tip).
                self.node_of[i] = self.nodes.len();
                self.nodes.push(self.px.node_at(i));
            }
        }
    }

    /// Marks the junction pixels 8-connected to `i` as the next node; the node sits at their
    /// mean centre with their widest half-width.
    fn junction_cluster(&mut self, i: usize) -> Node {
        let id = self.nodes.len();
        let mut stack = vec![i];
        self.node_of[i] = id;
        let (mut sum, mut k, mut wmax) = (Vec2::ZERO, 0.0, 0.0f64);
        while let Some(j) = stack.pop() {
            sum += self.px.centre(j).to_vec2();
            k += 1.0;
            wmax = wmax.max(self.px.dt[j] as f64);
            for (q, _) in self.px.neighbours(j) {
                if self.node_of[q] == NO_NODE && self.px.is_junction(q) {
                    self.node_of[q] = id;
                    stack.push(q);
                }
            }
        }
        Node { pos: (sum / k).to_point(), width: wmax, alive: true }
    }

    /// Traces every line leaving a node pixel; a loop with no node at all (an 口 traced as one
    /// ring) gets a seed node and is traced from it.
    fn trace_all(&mut self) {
        let n = self.px.n;
        let mut start_pixels: Vec<usize> = (0..n * n).filter(|&i| self.node_of[i] != NO_NODE).collect();
        let mut k = 0;
        loop {
            while k < start_pixels.len() {
                self.trace_from(start_pixels[k]);
                k += 1;
            }
            let Some(seed) = (0..n * n).find(|&i| self.px.skel[i] && self.node_of[i] == NO_NODE && !self.visited[i])
            else {
                break;
            };
            self.node_of[seed] = self.nodes.len();
            self.nodes.push(self.px.node_at(seed));
            start_pixels.push(seed);
        }
    }

    /// The edges leaving node pixel `i`: direct edges to adjacent pixels of other nodes, and a
    /// traced line through each unvisited neighbour (ending in a new end node at a dead end).
    fn trace_from(&mut self, i: usize) {
        let id = self.node_of[i];
        for (q, _) in self.px.neighbours(i) {
            let other = self.node_of[q];
            if other != NO_NODE || self.visited[q] {
                // Adjacent node pixels of different nodes: a direct edge.
                if other != NO_NODE && other != id && id < other {
                    let (a, b) = (id, other);
                    if !self.edges.iter().any(|e| (e.a == a && e.b == b) || (e.a == b && e.b == a)) {
                        let pts = vec![self.nodes[a].pos, self.nodes[b].pos];
                        self.edges.push(Edge { a, b, pts, alive: true });
                    }
                }
                continue;
            }
            match self.trace(id, i, q) {
                Ok(e) => self.edges.push(e),
                Err((pts, cur)) => {
                    let b = self.nodes.len();
                    self.node_of[cur] = b;
                    self.nodes.push(self.px.node_at(cur));
                    self.edges.push(Edge { a: id, b, pts, alive: true });
                }
            }
        }
    }

    /// Follows the line from node `start_node` (left at pixel `from`) through pixel `first`
    /// to the next node; `Err` with the points so far and the last pixel at a dead end that was
    /// not classified as an end (the caller makes it one).
    fn trace(&mut self, start_node: usize, from: usize, first: usize) -> Result<Edge, (Vec<Point>, usize)> {
        let mut pts = vec![self.nodes[start_node].pos, self.px.centre(first)];
        let (mut prev, mut cur) = (from, first);
        self.visited[cur] = true;
        loop {
            if self.node_of[cur] != NO_NODE {
                *pts.last_mut().expect("non-empty") = self.nodes[self.node_of[cur]].pos;
                return Ok(Edge { a: start_node, b: self.node_of[cur], pts, alive: true });
            }
            let mut cands: Vec<(usize, bool)> = Vec::new();
            for (q, four) in self.px.neighbours(cur) {
                if q == prev || (self.node_of[q] == start_node && pts.len() < 4) {
                    continue;
                }
                if self.node_of[q] != NO_NODE || !self.visited[q] {
                    cands.push((q, four));
                }
            }
            // Prefer a node, then 4-neighbours (so staircase corners are not skipped).
            cands.sort_by_key(|&(q, four)| (self.node_of[q] == NO_NODE, !four));
            let Some(&(next, _)) = cands.first() else {
                return Err((pts, cur));
            };
            self.absorb_staircase(&cands[1..], next);
            pts.push(self.px.centre(next));
            prev = cur;
            cur = next;
            if self.node_of[cur] == NO_NODE {
                self.visited[cur] = true;
            }
        }
    }

    /// Marks the other candidates adjacent to both the current pixel and `next` as visited
    /// (staircase pixels), never next to a node, whose other branches start there.
    fn absorb_staircase(&mut self, others: &[(usize, bool)], next: usize) {
        let n = self.px.n as isize;
        for &(q, _) in others {
            if self.node_of[q] == NO_NODE && self.node_of[next] == NO_NODE {
                let (qx, qy) = (q as isize % n, q as isize / n);
                let (nx, ny) = (next as isize % n, next as isize / n);
                if (qx - nx).abs() <= 1 && (qy - ny).abs() <= 1 {
                    self.visited[q] = true;
                }
            }
        }
    }
}

/// Thinning sometimes leaves a branch a pixel or two short of the junction it leaves (an end
/// point right beside a junction cluster, typically where two strokes cross): an end within
/// `radius` px of a junction it is not already joined to is joined to it.
pub(super) fn attach_loose_ends(g: &mut Graph, radius: f64) {
    for v in 0..g.nodes.len() {
        if !g.nodes[v].alive || degree(g, v) != 1 {
            continue;
        }
        let pos = g.nodes[v].pos;
        let near = (0..g.nodes.len())
            .filter(|&u| u != v && g.nodes[u].alive && degree(g, u) >= 3)
            .filter(|&u| !g.edges.iter().any(|e| e.alive && ((e.a == u && e.b == v) || (e.a == v && e.b == u))))
            .map(|u| (g.nodes[u].pos.distance(pos), u))
            .filter(|&(d, _)| d <= radius)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, u)) = near {
            let upos = g.nodes[u].pos;
            for e in g.edges.iter_mut().filter(|e| e.alive) {
                if e.a == v {
                    e.a = u;
                    e.pts.insert(0, upos);
                }
                if e.b == v {
                    e.b = u;
                    e.pts.push(upos);
                }
            }
            g.nodes[v].alive = false;
        }
    }
}

pub(super) fn degree(g: &Graph, v: usize) -> usize {
    g.edges.iter().filter(|e| e.alive).map(|e| (e.a == v) as usize + (e.b == v) as usize).sum()
}

pub(super) fn prune_spurs(g: &mut Graph, opts: &GraphOptions) {
    loop {
        let mut changed = false;
        for k in 0..g.edges.len() {
            if !g.edges[k].alive {
                continue;
            }
            let (a, b) = (g.edges[k].a, g.edges[k].b);
            let (da, db) = (degree(g, a), degree(g, b));
            let (free, junction) = if da == 1 && db >= 3 {
                (a, b)
            } else if db == 1 && da >= 3 {
                (b, a)
            } else {
                continue;
            };
            let factor = if corner_spur(g, k, junction, opts) { opts.corner_spur_factor } else { opts.spur_factor };
            if length(&g.edges[k].pts) < factor * g.nodes[junction].width.max(1.0) {
                g.edges[k].alive = false;
                g.nodes[free].alive = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Whether edge `k`, a free branch off `junction`, sits on a corner: the junction has exactly
/// two other branches, they do not continue each other, and the branch points away from both
/// (thinning leaves the blunt outer corner of 折 and 钩 as such a branch).
fn corner_spur(g: &Graph, k: usize, junction: usize, opts: &GraphOptions) -> bool {
    let others: Vec<Vec2> = ends_at(g, junction).into_iter().filter(|&(end, _)| end / 2 != k).map(|(_, d)| d).collect();
    if others.len() != 2 || others[0].dot(others[1]) <= opts.straight_min_rad.cos() {
        return false;
    }
    let e = &g.edges[k];
    let s = leaving(g, e, e.a == junction);
    let lim = opts.corner_spur_away_rad.cos();
    s.dot(others[0]) < lim && s.dot(others[1]) < lim
}

/// Contracts short edges between two branching nodes (a crossing that thinning drew as a small
/// cluster of junctions), never one to a free end: the first such edge, then the first in the
/// graph it leaves, until none is left.
pub(super) fn merge_junctions(g: &mut Graph, opts: &GraphOptions) {
    let short = |g: &Graph, k: usize| {
        let e = &g.edges[k];
        let (a, b) = (e.a, e.b);
        e.alive
            && a != b
            && degree(g, a) >= 2
            && degree(g, b) >= 2
            && length(&e.pts) < opts.merge_factor * g.nodes[a].width.max(g.nodes[b].width).max(1.0)
    };
    while let Some(k) = (0..g.edges.len()).find(|&k| short(g, k)) {
        let (a, b) = (g.edges[k].a, g.edges[k].b);
        let w = g.nodes[a].width.max(g.nodes[b].width).max(1.0);
        // Contract b into a.
        g.edges[k].alive = false;
        let pos = g.nodes[a].pos.midpoint(g.nodes[b].pos);
        g.nodes[a].pos = pos;
        g.nodes[a].width = w;
        g.nodes[b].alive = false;
        for e in g.edges.iter_mut().filter(|e| e.alive) {
            if e.a == b {
                e.a = a;
                e.pts[0] = pos;
            }
            if e.b == b {
                e.b = a;
                *e.pts.last_mut().expect("non-empty") = pos;
            }
            if e.a == a {
                e.pts[0] = pos;
            }
            if e.b == a {
                *e.pts.last_mut().expect("non-empty") = pos;
            }
        }
    }
}

/// A branch's direction (and width) is measured out to this many of its node's half-widths...
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const BRANCH_REACH_WIDTHS: f64 = 3.0;
/// ... and at least this far (px).
const BRANCH_REACH_MIN_PX: f64 = 4.0;
/// A branch's direction starts this many half-widths out (past the junction blob).
const BRANCH_SKIP_WIDTHS: f64 = 0.5;

/// Direction leaving node `v` along edge `e` (which end given by `at_a`).
fn leaving(g: &Graph, e: &Edge, at_a: bool) -> Vec2 {
    let pts: Vec<Point> = if at_a { e.pts.clone() } else { e.pts.iter().rev().copied().collect() };
    let v = if at_a { e.a } else { e.b };
    // From half a width out (past the junction blob) to three widths out.
    let reach = (BRANCH_REACH_WIDTHS * g.nodes[v].width).max(BRANCH_REACH_MIN_PX);
    let skip = BRANCH_SKIP_WIDTHS * g.nodes[v].width;
    let mut acc = 0.0;
    let mut target = *pts.last().expect("non-empty");
    let mut origin = pts[0];
    let mut set_origin = skip <= 0.0;
    for w in pts.windows(2) {
        acc += w[0].distance(w[1]);
        if !set_origin && acc >= skip {
            origin = w[1];
            set_origin = true;
        }
        if acc >= reach {
            target = w[1];
            break;
        }
    }
    let d = target - origin;
    if d.hypot() > 0.0 { d / d.hypot() } else { Vec2::ZERO }
}

/// The live branch ends at node `v`: end id (2k for edge k's end a, 2k+1 for its end b) and the
/// direction the branch leaves in (see [`leaving`]).
pub(super) fn ends_at(g: &Graph, v: usize) -> Vec<(usize, Vec2)> {
    let mut out = Vec::new();
    for (k, e) in g.edges.iter().enumerate().filter(|(_, e)| e.alive) {
        if e.a == v {
            out.push((2 * k, leaving(g, e, true)));
        }
        if e.b == v {
            out.push((2 * k + 1, leaving(g, e, false)));
        }
    }
    out
}

/// The mean half-width (px) of the branch leaving node `v` along edge `e`, sampled from one to
/// three of the node's half-widths out (past the junction blob).
pub(super) fn branch_width(g: &Graph, e: &Edge, at_a: bool, dt: &[f32], n: usize) -> f64 {
    let v = if at_a { e.a } else { e.b };
    let w = g.nodes[v].width.max(1.0);
    let pts: Vec<Point> = if at_a { e.pts.clone() } else { e.pts.iter().rev().copied().collect() };
    let (mut acc, mut sum, mut k) = (0.0, 0.0, 0usize);
    for p in pts.windows(2) {
        acc += p[0].distance(p[1]);
        if acc >= w && acc <= BRANCH_REACH_WIDTHS * w {
            sum += crate::distance::sample(dt, n, n, p[1].x, p[1].y);
            k += 1;
        }
        if acc > BRANCH_REACH_WIDTHS * w {
            break;
        }
    }
    if k == 0 { crate::distance::sample(dt, n, n, pts[pts.len() - 1].x, pts[pts.len() - 1].y) } else { sum / k as f64 }
}
