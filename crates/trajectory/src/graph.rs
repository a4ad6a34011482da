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
    /// The same for a branch off a corner (the junction's two other branches turn rather than
    /// continue each other, and the branch points away from both by more than
    /// [`CORNER_SPUR_AWAY_RAD`]): thinning leaves the pressed outer corner of 折, 钩 and 提 as
    /// such a branch, longer than ordinary spurs.
    pub corner_spur_factor: f64,
    /// Junctions closer than `merge_factor · w` are one crossing.
    pub merge_factor: f64,
    /// At a junction, two branches continue each other if the angle between them exceeds this
    /// (radians; π = perfectly straight).
    pub straight_min_rad: f64,
    /// A chain that turns by more than this (radians, measured over about a stroke width each
    /// way) has a corner there; see [`GraphOptions::split_box_corners`] for which corners
    /// end a stroke.
    pub corner_rad: f64,
    /// On a closed chain (a box), split where a vertical leg turns right (竖折): the lower left
    /// corner of 口 or 日, whose bottom is a stroke of its own. Open chains keep 竖折 (山, 出).
    pub split_box_corners: bool,
    /// An end point within this distance (em units) of a junction it is not joined to is joined
    /// to it ([`LOOSE_END_EM`]).
    pub loose_end_em: f64,
    /// A corner spur points away from both legs of its corner by more than this (radians,
    /// [`CORNER_SPUR_AWAY_RAD`]).
    pub corner_spur_away_rad: f64,
    /// How far each way the turn at a chain point is measured, in local half-widths
    /// ([`CORNER_REACH`]).
    pub corner_reach: f64,
    /// A chain's end leg no longer than this many half-widths can be a hook ([`HOOK_WIDTHS`]).
    pub hook_widths: f64,
    /// ... when shorter than this fraction of the leg it turns from ([`HOOK_RATIO`]).
    pub hook_ratio: f64,
    /// Pieces no longer than this many half-widths that lie inside other strokes are dropped
    /// ([`COVERED_MAX_WIDTHS`]).
    pub covered_max_widths: f64,
    /// At a junction of three or more branches, two branches continue each other only if the
    /// thinner one's half-width (measured one to three junction half-widths out) is at least this
    /// fraction of the thicker one's: a tapering tip (the end of a 提 or 撇) that touches the
    /// start of another stroke is not its continuation. 0 turns the test off.
    pub pair_width_ratio: f64,
    /// Split a vertical leg turning right (竖折) on open chains too, when the vertical leg is at
    /// least this many times as long as the horizontal one (0: never). The bottom of a box
    /// (口, 日, 甘, 自) is a stroke of its own; 竖折 (山, 出, 区) tends to have a short vertical leg
    /// and a long horizontal one.
    pub open_box_min_ratio: f64,
    /// A leg rising to the right out of a downward one is 提 (竖提, one stroke) when it rises by
    /// more than this much per unit run; a box's bottom (口, 日) rises a little too and is a
    /// stroke of its own.
    pub ti_min_rise: f64,
}

impl Default for GraphOptions {
    fn default() -> Self {
        Self {
            spur_factor: 2.0,
            corner_spur_factor: 3.0,
            merge_factor: 2.0,
            straight_min_rad: 125f64.to_radians(),
            corner_rad: 50f64.to_radians(),
            split_box_corners: true,
            loose_end_em: LOOSE_END_EM,
            corner_spur_away_rad: CORNER_SPUR_AWAY_RAD,
            corner_reach: CORNER_REACH,
            hook_widths: HOOK_WIDTHS,
            hook_ratio: HOOK_RATIO,
            covered_max_widths: COVERED_MAX_WIDTHS,
            pair_width_ratio: 0.5,
            open_box_min_ratio: 0.5,
            ti_min_rise: 0.4,
        }
    }
}

impl GraphOptions {
    /// Sets one option by name, for sweeps (`cargo xtask skeleton-counts --opts`): the field
    /// names above, with angles in degrees and named `*_deg` instead of `*_rad`
    /// (`straight_min_deg`, `corner_deg`, `corner_spur_away_deg`); `split_box_corners` takes 0
    /// or 1.
    ///
    /// # Errors
    /// A message naming the key when it is unknown or the value is not finite.
    pub fn set(&mut self, key: &str, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("option {key}: {value} is not a finite number"));
        }
        match key {
            "spur_factor" => self.spur_factor = value,
            "corner_spur_factor" => self.corner_spur_factor = value,
            "merge_factor" => self.merge_factor = value,
            "straight_min_deg" => self.straight_min_rad = value.to_radians(),
            "corner_deg" => self.corner_rad = value.to_radians(),
            "split_box_corners" => self.split_box_corners = value != 0.0,
            "loose_end_em" => self.loose_end_em = value,
            "corner_spur_away_deg" => self.corner_spur_away_rad = value.to_radians(),
            "corner_reach" => self.corner_reach = value,
            "hook_widths" => self.hook_widths = value,
            "hook_ratio" => self.hook_ratio = value,
            "covered_max_widths" => self.covered_max_widths = value,
            "pair_width_ratio" => self.pair_width_ratio = value,
            "open_box_min_ratio" => self.open_box_min_ratio = value,
            "ti_min_rise" => self.ti_min_rise = value,
            _ => return Err(format!("unknown skeleton option `{key}`")),
        }
        Ok(())
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
    attach_loose_ends(&mut g, opts.loose_end_em * n as f64 / 1024.0);
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
    // Where three or more branches meet (chains that end there end against other strokes).
    let junctions: Vec<Point> =
        (0..g.nodes.len()).filter(|&v| g.nodes[v].alive && degree(&g, v) >= 3).map(|v| g.nodes[v].pos).collect();
    let strokes: Vec<Vec<Point>> =
        pair_and_chain(&g, dt, n, opts).iter().flat_map(|s| split_at_corners(s, dt, n, opts, &junctions)).collect();
    let strokes: Vec<Vec<Point>> = strokes.into_iter().filter(|s| length(s) > 1.5).collect();
    let strokes = drop_covered(strokes, dt, n, opts.covered_max_widths);
    order_strokes(strokes)
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

    /// The strokes found with `opts` ([`skeleton_strokes`]), in pixels.
    pub fn strokes(&self, opts: &GraphOptions) -> Vec<Vec<Point>> {
        skeleton_strokes(&self.skel, &self.dt, self.n, opts)
    }
}

/// A piece no longer than this many half-widths, all of whose points lie within one local
/// half-width of another stroke's centre line, is dropped by `drop_covered`.
pub const COVERED_MAX_WIDTHS: f64 = 3.0;

/// Drops short pieces that lie wholly inside the ink of other strokes (a crossing that thinning
/// drew as two junctions leaves such a piece between them): they add no ink of their own, and
/// counted as strokes they would be wrong.
fn drop_covered(strokes: Vec<Vec<Point>>, dt: &[f32], n: usize, k: f64) -> Vec<Vec<Point>> {
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

/// How near a junction (em units) an end point is taken to belong to it.
pub const LOOSE_END_EM: f64 = 9.0;

/// Thinning sometimes leaves a branch a pixel or two short of the junction it leaves (an end
/// point right beside a junction cluster, typically where two strokes cross): an end within
/// `radius` px of a junction it is not already joined to is joined to it.
fn attach_loose_ends(g: &mut Graph, radius: f64) {
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

/// A corner spur points away from both legs of its corner by more than this (radians).
pub const CORNER_SPUR_AWAY_RAD: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

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
fn ends_at(g: &Graph, v: usize) -> Vec<(usize, Vec2)> {
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
fn branch_width(g: &Graph, e: &Edge, at_a: bool, dt: &[f32], n: usize) -> f64 {
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

fn pair_and_chain(g: &Graph, dt: &[f32], n: usize, opts: &GraphOptions) -> Vec<Vec<Point>> {
    let live: Vec<usize> = (0..g.edges.len()).filter(|&k| g.edges[k].alive).collect();
    // End id: 2k (end a) or 2k+1 (end b) of edge k.
    let mut partner = vec![usize::MAX; 2 * g.edges.len()];
    for v in 0..g.nodes.len() {
        if !g.nodes[v].alive {
            continue;
        }
        let ends = ends_at(g, v);
        if ends.len() < 2 {
            continue;
        }
        let widths: Vec<f64> = if opts.pair_width_ratio > 0.0 && ends.len() >= 3 {
            ends.iter().map(|&(end, _)| branch_width(g, &g.edges[end / 2], end % 2 == 0, dt, n)).collect()
        } else {
            Vec::new()
        };
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for i in 0..ends.len() {
            for j in i + 1..ends.len() {
                if !widths.is_empty() && widths[i].min(widths[j]) < opts.pair_width_ratio * widths[i].max(widths[j]) {
                    continue;
                }
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

/// A chain's end leg no longer than this many local half-widths can be a hook (钩) of the
/// stroke it turns from rather than a stroke of its own...
pub const HOOK_WIDTHS: f64 = 5.0;
/// ... when it is shorter than this fraction of that stroke's leg, or rises away from the corner.
pub const HOOK_RATIO: f64 = 0.5;
/// How far each way the turn at a chain point is measured, in local half-widths (a skeleton
/// corner is rounded over about one width).
pub const CORNER_REACH: f64 = 2.5;

/// The direction a line of direction `v` (either sign; raster y down) is written in: rightward
/// if it is nearly horizontal, otherwise downward (撇 and 捺 both go down; 提, the rising
/// stroke, is short and rarely meets another at a corner).
fn writing_direction(v: Vec2) -> Vec2 {
    let flip = if v.y.abs() <= 0.6 * v.x.abs() { v.x < 0.0 } else { v.y < 0.0 };
    if flip { -v } else { v }
}

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
fn split_at_corners(p: &[Point], dt: &[f32], n: usize, opts: &GraphOptions, junctions: &[Point]) -> Vec<Vec<Point>> {
    let m = p.len();
    if m < 5 {
        return vec![p.to_vec()];
    }
    let closed = p[0].distance(p[m - 1]) < 1.5;
    // Arc length, with the closing segment for loops.
    let mut s = vec![0.0; m];
    for i in 1..m {
        s[i] = s[i - 1] + p[i - 1].distance(p[i]);
    }
    let total = s[m - 1] + if closed { p[m - 1].distance(p[0]) } else { 0.0 };
    let width = |q: Point| -> f64 {
        let (x, y) = (q.x.floor().clamp(0.0, (n - 1) as f64) as usize, q.y.floor().clamp(0.0, (n - 1) as f64) as usize);
        f64::from(dt[y * n + x]).max(1.0)
    };
    // The point at arc length `t` (wrapping for loops; clamped otherwise).
    let at = |t: f64| -> Point {
        let t = if closed { t.rem_euclid(total) } else { t.clamp(0.0, s[m - 1]) };
        let i = s.partition_point(|&x| x <= t).clamp(1, m) - 1;
        p[i]
    };
    let reach: Vec<f64> = p.iter().map(|&q| (opts.corner_reach * width(q)).max(3.0)).collect();
    let turn: Vec<f64> = (0..m)
        .map(|i| {
            if !closed && (s[i] < reach[i] || s[m - 1] - s[i] < reach[i]) {
                return 0.0;
            }
            let (a, b) = (p[i] - at(s[i] - reach[i]), at(s[i] + reach[i]) - p[i]);
            if a.hypot() < 1e-9 || b.hypot() < 1e-9 {
                return 0.0;
            }
            (a.dot(b) / (a.hypot() * b.hypot())).clamp(-1.0, 1.0).acos()
        })
        .collect();
    // Corners: local maxima of the turn above the threshold, one per neighbourhood.
    let mut corners: Vec<usize> = Vec::new();
    for i in 0..m {
        if turn[i] <= opts.corner_rad {
            continue;
        }
        let near = |j: usize| {
            let d = (s[j] - s[i]).abs();
            if closed { d.min(total - d) } else { d }
        };
        let is_max = (0..m).all(|j| near(j) > reach[i] || turn[j] < turn[i] || (turn[j] == turn[i] && j >= i));
        if is_max {
            corners.push(i);
        }
    }
    // Per corner: stays, splits, or an open box corner that splits if the horizontal leg's far
    // end (the neighbouring corner's index or the chain's end) lies against other strokes: a
    // splitting corner or a junction.
    enum Verdict {
        Stay,
        Split,
        OpenBox(usize),
    }
    let decide = |i: usize| -> Verdict {
        let d_in = p[i] - at(s[i] - reach[i]);
        let d_out = at(s[i] + reach[i]) - p[i];
        let (w_in, w_out) = (writing_direction(d_in), writing_direction(d_out));
        let forward_in = w_in.dot(d_in) > 0.0;
        let forward_out = w_out.dot(d_out) > 0.0;
        // The legs up to the neighbouring corners (or the chain's ends).
        let prev =
            corners.iter().rev().find(|&&c| c < i).map_or(if closed { None } else { Some(0.0) }, |&c| Some(s[c]));
        let next = corners.iter().find(|&&c| c > i).map_or(if closed { None } else { Some(s[m - 1]) }, |&c| Some(s[c]));
        let min_leg = 2.0 * width(p[i]);
        let long = prev.is_none_or(|a| s[i] - a >= min_leg) && next.is_none_or(|b| b - s[i] >= min_leg);
        if !long {
            return Verdict::Stay;
        }
        // A hook: a chain's first or last leg that is much shorter than the leg it turns
        // from, or short and rising away from the corner (every 钩 points up).
        if !closed {
            let (len_in, len_out) = (s[i] - prev.unwrap_or(0.0), next.unwrap_or(s[m - 1]) - s[i]);
            let w = width(p[i]);
            let hook = |len: f64, other: f64, outward: Vec2| {
                len < opts.hook_widths * w && (len < opts.hook_ratio * other || outward.y < -0.2 * outward.hypot())
            };
            let first = corners.first() == Some(&i);
            let last = corners.last() == Some(&i);
            if (first && hook(len_in, len_out, -d_in)) || (last && hook(len_out, len_in, d_out)) {
                return Verdict::Stay;
            }
        }
        // 提 rises to the right out of a downward leg (竖提, 横折提): one stroke, whichever
        // way the chain runs.
        let down = |v: Vec2| v.y > 0.6 * v.x.abs();
        let rising = |v: Vec2| v.x > 0.0 && v.y < -opts.ti_min_rise * v.x;
        if (down(d_in) && rising(d_out)) || (down(-d_out) && rising(-d_in)) {
            return Verdict::Stay;
        }
        if forward_in != forward_out {
            return Verdict::Split;
        }
        // As written: which leg comes first. A vertical leg turning right is a box corner.
        let (first, second) = if forward_in { (d_in, d_out) } else { (-d_out, -d_in) };
        let vertical = |v: Vec2| v.y > 2.0 * v.x.abs();
        let right = |v: Vec2| v.x > 0.0 && v.y.abs() <= 0.6 * v.x;
        if !(vertical(first) && right(second)) {
            return Verdict::Stay;
        }
        if closed {
            return if opts.split_box_corners { Verdict::Split } else { Verdict::Stay };
        }
        // The legs as written: the vertical one, then the horizontal one, which must run to
        // the chain's end and end there against other strokes (the bottom of 口 ending at
        // the right side), not at a free end or another corner.
        let (len_in, len_out) = (s[i] - prev.unwrap_or(0.0), next.unwrap_or(s[m - 1]) - s[i]);
        let (len_v, len_h) = if forward_in { (len_in, len_out) } else { (len_out, len_in) };
        // A box side is upright and its bottom level (撇折 in 纟 and 幺 slants and rises).
        let upright = first.x.abs() <= 0.3 * first.y && second.y >= -0.15 * second.x;
        if !(opts.open_box_min_ratio > 0.0 && upright && len_v >= opts.open_box_min_ratio * len_h) {
            return Verdict::Stay;
        }
        let far = if forward_in {
            corners.iter().copied().find(|&c| c > i).unwrap_or(m - 1)
        } else {
            corners.iter().rev().copied().find(|&c| c < i).unwrap_or(0)
        };
        Verdict::OpenBox(far)
    };
    let verdicts: Vec<Verdict> = corners.iter().map(|&i| decide(i)).collect();
    let base: Vec<usize> =
        corners.iter().zip(&verdicts).filter(|(_, v)| matches!(v, Verdict::Split)).map(|(&c, _)| c).collect();
    let splits: Vec<usize> = corners
        .iter()
        .zip(&verdicts)
        .filter(|(_, v)| match v {
            Verdict::Split => true,
            Verdict::OpenBox(far) => {
                base.contains(far)
                    || ((*far == 0 || *far == m - 1) && junctions.iter().any(|j| j.distance(p[*far]) < 1.5))
            }
            Verdict::Stay => false,
        })
        .map(|(&c, _)| c)
        .collect();
    if splits.is_empty() {
        return vec![p.to_vec()];
    }
    let mut out = Vec::new();
    if closed {
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
        strokes_with(mask, n, &GraphOptions::default())
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
        let plain = GraphOptions { corner_spur_factor: GraphOptions::default().spur_factor, ..GraphOptions::default() };
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
        let old = GraphOptions { open_box_min_ratio: 0.0, ..GraphOptions::default() };
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
        let kept = drop_covered(strokes.clone(), &dt, n, COVERED_MAX_WIDTHS);
        assert_eq!(kept.len(), 4);
        assert!(!kept.contains(&strokes[2]));
    }
}
