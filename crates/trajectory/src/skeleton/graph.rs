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

/// The graph of a one-pixel skeleton `skel` (`n × n`), node widths from `dt`.
pub(super) fn build_graph(skel: &[bool], dt: &[f32], n: usize) -> Graph {
    let on = |x: isize, y: isize| {
        x >= 0 && y >= 0 && (x as usize) < n && (y as usize) < n && skel[y as usize * n + x as usize]
    };
    let centre = |i: usize| Point::new((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
    // Branch count: 0→1 transitions around the 8-neighbourhood (robust to staircases).
    let branches = |i: usize| {
        let (x, y) = ((i % n) as isize, (i / n) as isize);
        let p: Vec<bool> = N8.iter().map(|&(dx, dy)| on(x + dx, y + dy)).collect();
        let count = p.iter().filter(|&&b| b).count();
        let trans = (0..8).filter(|&k| !p[k] && p[(k + 1) % 8]).count();
        (count, trans)
    };
    let mut node_of = vec![usize::MAX; n * n];
    let mut nodes: Vec<Node> = Vec::new();
    // Junction pixels (≥ 3 branches) clustered 8-connected; end pixels (1 neighbour) alone.
    let is_junction = |i: usize| {
        let (count, trans) = branches(i);
        let _ = count;
        trans >= 3
    };
    for i in 0..n * n {
        if !skel[i] || node_of[i] != usize::MAX {
            continue;
        }
        let (count, trans) = branches(i);
        if is_junction(i) {
            let id = nodes.len();
            let mut stack = vec![i];
            node_of[i] = id;
            let (mut sum, mut k, mut wmax) = (Vec2::ZERO, 0.0, 0.0f64);
            while let Some(j) = stack.pop() {
                sum += centre(j).to_vec2();
                k += 1.0;
                wmax = wmax.max(dt[j] as f64);
                let (x, y) = ((j % n) as isize, (j / n) as isize);
                for &(dx, dy) in &N8 {
                    if on(x + dx, y + dy) {
                        let q = (y + dy) as usize * n + (x + dx) as usize;
                        if node_of[q] == usize::MAX && is_junction(q) {
                            node_of[q] = id;
                            stack.push(q);
                        }
                    }
                }
            }
            nodes.push(Node { pos: (sum / k).to_point(), width: wmax, alive: true });
        } else if count <= 1 || (count == 2 && trans == 1) {
            // An end: one neighbour, or two touching ones (a one-pixel hook at the tip).
            node_of[i] = nodes.len();
            nodes.push(Node { pos: centre(i), width: dt[i] as f64, alive: true });
        }
    }
    let mut visited = vec![false; n * n];
    let mut edges = Vec::new();
    let trace = |start_node: usize,
                 from: usize,
                 first: usize,
                 visited: &mut Vec<bool>,
                 node_of: &Vec<usize>,
                 nodes: &Vec<Node>|
     -> Result<Edge, (Vec<Point>, usize)> {
        let mut pts = vec![nodes[start_node].pos, centre(first)];
        let (mut prev, mut cur) = (from, first);
        visited[cur] = true;
        loop {
            if node_of[cur] != usize::MAX {
                *pts.last_mut().expect("non-empty") = nodes[node_of[cur]].pos;
                return Ok(Edge { a: start_node, b: node_of[cur], pts, alive: true });
            }
            let (x, y) = ((cur % n) as isize, (cur / n) as isize);
            let mut cands: Vec<(usize, bool)> = Vec::new();
            for &(dx, dy) in &N8 {
                if on(x + dx, y + dy) {
                    let q = (y + dy) as usize * n + (x + dx) as usize;
                    if q == prev || (node_of[q] == start_node && pts.len() < 4) {
                        continue;
                    }
                    if node_of[q] != usize::MAX || !visited[q] {
                        cands.push((q, dx == 0 || dy == 0));
                    }
                }
            }
            // Prefer a node, then 4-neighbours (so staircase corners are not skipped).
            cands.sort_by_key(|&(q, four)| (node_of[q] == usize::MAX, !four));
            let Some(&(next, _)) = cands.first() else {
                // A dead end that was not classified as an end: the caller makes it one.
                return Err((pts, cur));
            };
            // Absorb staircase pixels adjacent to both cur and next (never next to a node, whose
            // other branches start there).
            for &(q, _) in cands.iter().skip(1) {
                if node_of[q] == usize::MAX && node_of[next] == usize::MAX {
                    let (qx, qy) = ((q % n) as isize, (q / n) as isize);
                    let (nx, ny) = ((next % n) as isize, (next / n) as isize);
                    if (qx - nx).abs() <= 1 && (qy - ny).abs() <= 1 {
                        visited[q] = true;
                    }
                }
            }
            pts.push(centre(next));
            prev = cur;
            cur = next;
            if node_of[cur] == usize::MAX {
                visited[cur] = true;
            }
        }
    };
    let mut start_pixels: Vec<usize> = (0..n * n).filter(|&i| node_of[i] != usize::MAX).collect();
    let mut k = 0;
    loop {
        while k < start_pixels.len() {
            let i = start_pixels[k];
            k += 1;
            let id = node_of[i];
            let (x, y) = ((i % n) as isize, (i / n) as isize);
            for &(dx, dy) in &N8 {
                if !on(x + dx, y + dy) {
                    continue;
                }
                let q = (y + dy) as usize * n + (x + dx) as usize;
                if node_of[q] != usize::MAX || visited[q] {
                    // Adjacent node pixels of different nodes: a direct edge.
                    if node_of[q] != usize::MAX && node_of[q] != id && id < node_of[q] {
                        let (a, b) = (id, node_of[q]);
                        if !edges.iter().any(|e: &Edge| (e.a == a && e.b == b) || (e.a == b && e.b == a)) {
                            edges.push(Edge { a, b, pts: vec![nodes[a].pos, nodes[b].pos], alive: true });
                        }
                    }
                    continue;
                }
                match trace(id, i, q, &mut visited, &node_of, &nodes) {
                    Ok(e) => edges.push(e),
                    Err((pts, cur)) => {
                        let b = nodes.len();
                        node_of[cur] = b;
                        nodes.push(Node { pos: centre(cur), width: dt[cur] as f64, alive: true });
                        edges.push(Edge { a: id, b, pts, alive: true });
                    }
                }
            }
        }
        // Loops with no node at all (an 口 traced as one ring): seed a node on them.
        let Some(seed) = (0..n * n).find(|&i| skel[i] && node_of[i] == usize::MAX && !visited[i]) else { break };
        node_of[seed] = nodes.len();
        nodes.push(Node { pos: centre(seed), width: dt[seed] as f64, alive: true });
        start_pixels.push(seed);
    }
    Graph { nodes, edges }
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

pub(super) fn merge_junctions(g: &mut Graph, opts: &GraphOptions) {
    loop {
        let mut merged = false;
        for k in 0..g.edges.len() {
            if !g.edges[k].alive {
                continue;
            }
            let (a, b) = (g.edges[k].a, g.edges[k].b);
            // Contract short edges between two branching nodes (a crossing that thinning drew as
            // a small cluster of junctions), never one to a free end.
            if a == b || degree(g, a) < 2 || degree(g, b) < 2 {
                continue;
            }
            let w = g.nodes[a].width.max(g.nodes[b].width).max(1.0);
            if length(&g.edges[k].pts) >= opts.merge_factor * w {
                continue;
            }
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
            merged = true;
            break;
        }
        if !merged {
            break;
        }
    }
}

/// Direction leaving node `v` along edge `e` (which end given by `at_a`).
fn leaving(g: &Graph, e: &Edge, at_a: bool) -> Vec2 {
    let pts: Vec<Point> = if at_a { e.pts.clone() } else { e.pts.iter().rev().copied().collect() };
    let v = if at_a { e.a } else { e.b };
    // From half a width out (past the junction blob) to three widths out.
    let reach = (3.0 * g.nodes[v].width).max(4.0);
    let skip = 0.5 * g.nodes[v].width;
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
        if acc >= w && acc <= 3.0 * w {
            sum += crate::distance::sample(dt, n, n, p[1].x, p[1].y);
            k += 1;
        }
        if acc > 3.0 * w {
            break;
        }
    }
    if k == 0 { crate::distance::sample(dt, n, n, pts[pts.len() - 1].x, pts[pts.len() - 1].y) } else { sum / k as f64 }
}
