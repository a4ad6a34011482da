//! From a skeleton to strokes: a graph of end points and junctions, spur pruning, junction
//! merging, straight-through pairing at crossings, and stroke order.
//!
//! Coordinates here are analysis-raster pixels (pixel centres at `i + 0.5`).

use kurbo::{Point, Vec2};

/// Tuning of the skeleton graph, relative to the local stroke half-width `w` (the distance
/// transform at a junction).
#[derive(Clone, Copy, Debug)]
pub struct GraphOptions {
    /// A branch from a junction to a free end shorter than `spur_factor · w` is a spur and is
    /// removed (thinning leaves them at blunt stroke ends and corners).
    pub spur_factor: f64,
    /// Junctions closer than `merge_factor · w` are one crossing.
    pub merge_factor: f64,
    /// At a junction, two branches continue each other if the angle between them exceeds this
    /// (radians; π = perfectly straight).
    pub straight_min_rad: f64,
}

impl Default for GraphOptions {
    fn default() -> Self {
        Self { spur_factor: 2.0, merge_factor: 1.5, straight_min_rad: 125f64.to_radians() }
    }
}

#[derive(Clone, Debug)]
struct Node {
    pos: Point,
    /// Local half-width at the node, px.
    width: f64,
    alive: bool,
}

#[derive(Clone, Debug)]
struct Edge {
    a: usize,
    b: usize,
    /// Pixel path from node a to node b (node centres included at both ends).
    pts: Vec<Point>,
    alive: bool,
}

fn length(p: &[Point]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

const N8: [(isize, isize); 8] = [(0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)];

/// Extracts strokes from a one-pixel skeleton. `dt` is the distance transform of the glyph mask
/// (same `n × n` raster). Returns polylines in pixel coordinates, oriented and ordered by the
/// usual writing rules.
pub fn skeleton_strokes(skel: &[bool], dt: &[f32], n: usize, opts: &GraphOptions) -> Vec<Vec<Point>> {
    let mut g = build_graph(skel, dt, n);
    prune_spurs(&mut g, opts);
    merge_junctions(&mut g, opts);
    prune_spurs(&mut g, opts);
    if std::env::var_os("MAOBI_DEBUG_GRAPH").is_some() {
        for (i, v) in g.nodes.iter().enumerate().filter(|(_, v)| v.alive) {
            eprintln!("node {i} at ({:.1},{:.1}) w {:.1} deg {}", v.pos.x, v.pos.y, v.width, degree(&g, i));
        }
        for e in g.edges.iter().filter(|e| e.alive) {
            eprintln!("edge {} - {} len {:.1}", e.a, e.b, length(&e.pts));
        }
    }
    let strokes = pair_and_chain(&g, opts);
    order_strokes(strokes.into_iter().filter(|s| length(s) > 1.5).collect())
}

struct Graph {
    nodes: Vec<Node>,
    edges: Vec<Edge>,
}

fn build_graph(skel: &[bool], dt: &[f32], n: usize) -> Graph {
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

fn degree(g: &Graph, v: usize) -> usize {
    g.edges.iter().filter(|e| e.alive).map(|e| (e.a == v) as usize + (e.b == v) as usize).sum()
}

fn prune_spurs(g: &mut Graph, opts: &GraphOptions) {
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
            if length(&g.edges[k].pts) < opts.spur_factor * g.nodes[junction].width.max(1.0) {
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

fn merge_junctions(g: &mut Graph, opts: &GraphOptions) {
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
    let reach = (2.5 * g.nodes[v].width).max(4.0);
    let mut acc = 0.0;
    let mut target = *pts.last().expect("non-empty");
    for w in pts.windows(2) {
        acc += w[0].distance(w[1]);
        if acc >= reach {
            target = w[1];
            break;
        }
    }
    let d = target - pts[0];
    if d.hypot() > 0.0 { d / d.hypot() } else { Vec2::ZERO }
}

fn pair_and_chain(g: &Graph, opts: &GraphOptions) -> Vec<Vec<Point>> {
    let live: Vec<usize> = (0..g.edges.len()).filter(|&k| g.edges[k].alive).collect();
    // End id: 2k (end a) or 2k+1 (end b) of edge k.
    let mut partner = vec![usize::MAX; 2 * g.edges.len()];
    for v in 0..g.nodes.len() {
        if !g.nodes[v].alive {
            continue;
        }
        let ends: Vec<(usize, Vec2)> = live
            .iter()
            .flat_map(|&k| {
                let e = &g.edges[k];
                let mut out = Vec::new();
                if e.a == v {
                    out.push((2 * k, leaving(g, e, true)));
                }
                if e.b == v {
                    out.push((2 * k + 1, leaving(g, e, false)));
                }
                out
            })
            .collect();
        if ends.len() < 2 {
            continue;
        }
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for i in 0..ends.len() {
            for j in i + 1..ends.len() {
                pairs.push((ends[i].1.dot(ends[j].1), ends[i].0, ends[j].0));
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let limit = if ends.len() == 2 { 1.0 } else { opts.straight_min_rad.cos() };
        for (c, x, y) in pairs {
            if c <= limit + 1e-12 && partner[x] == usize::MAX && partner[y] == usize::MAX && x / 2 != y / 2 {
                partner[x] = y;
                partner[y] = x;
            }
        }
    }
    let mut used = vec![false; g.edges.len()];
    let mut strokes = Vec::new();
    let walk = |start_end: usize, used: &mut Vec<bool>| {
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
            let other = end ^ 1;
            match partner[other] {
                usize::MAX => break,
                next => end = next,
            }
        }
        pts
    };
    for &k in &live {
        for end in [2 * k, 2 * k + 1] {
            if !used[k] && partner[end] == usize::MAX {
                strokes.push(walk(end, &mut used));
            }
        }
    }
    for &k in &live {
        if !used[k] {
            strokes.push(walk(2 * k, &mut used));
        }
    }
    strokes.into_iter().map(|s| smooth(&s)).collect()
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

fn is_horizontal(s: &[Point]) -> bool {
    let d = s[s.len() - 1] - s[0];
    d.y.abs() <= 0.6 * d.x.abs()
}

/// Orients each stroke (horizontal-ish ones left to right, others top to bottom) and orders
/// them: top before bottom (in bands of 1/12 of the raster), left before right, and a
/// horizontal before a vertical it crosses.
pub fn order_strokes(strokes: Vec<Vec<Point>>) -> Vec<Vec<Point>> {
    let mut s: Vec<Vec<Point>> = strokes
        .into_iter()
        .map(|mut p| {
            let d = p[p.len() - 1] - p[0];
            let flip = if d.y.abs() <= 0.6 * d.x.abs() { d.x < 0.0 } else { d.y < 0.0 };
            if flip {
                p.reverse();
            }
            p
        })
        .collect();
    let extent = s.iter().flatten().fold(1.0f64, |m, p| m.max(p.x).max(p.y));
    let band = extent / 12.0;
    s.sort_by(|a, b| {
        let ka = ((a[0].y / band).floor() as i64, a[0].x);
        let kb = ((b[0].y / band).floor() as i64, b[0].x);
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    // Horizontal before a crossing vertical.
    for _ in 0..s.len() * s.len() {
        let mut moved = false;
        'outer: for i in 0..s.len() {
            for j in i + 1..s.len() {
                if !is_horizontal(&s[i]) && is_horizontal(&s[j]) && crosses(&s[i], &s[j]) {
                    let h = s.remove(j);
                    s.insert(i, h);
                    moved = true;
                    break 'outer;
                }
            }
        }
        if !moved {
            break;
        }
    }
    s
}

fn crosses(a: &[Point], b: &[Point]) -> bool {
    let seg = |p: Point, q: Point, r: Point, s: Point| {
        let d = |a: Point, b: Point, c: Point| (b - a).cross(c - a);
        let (d1, d2, d3, d4) = (d(p, q, r), d(p, q, s), d(r, s, p), d(r, s, q));
        d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && (d1 != 0.0 || d2 != 0.0)
    };
    a.windows(2).any(|x| b.windows(2).any(|y| seg(x[0], x[1], y[0], y[1])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::distance_to_background;
    use crate::thinning::zhang_suen;

    fn strokes_of(mask: Vec<bool>, n: usize) -> Vec<Vec<Point>> {
        let dt = distance_to_background(&mask, n, n);
        let mut skel = mask;
        zhang_suen(&mut skel, n, n);
        crate::thinning::remove_staircases(&mut skel, n, n);
        skeleton_strokes(&skel, &dt, n, &GraphOptions::default())
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

    #[test]
    fn an_l_corner_is_one_stroke() {
        let n = 80;
        let mut m = vec![false; n * n];
        bar(&mut m, n, 10, 18, 10, 70);
        bar(&mut m, n, 10, 70, 62, 70);
        let s = strokes_of(m, n);
        assert_eq!(s.len(), 1, "{s:?}");
    }
}
