//! Prints the skeleton strokes found for a character (debugging aid).
//!
//! `cargo run -p trajectory --example skeleton_debug -- 永 [POINTS.json]` (the second argument
//! writes every stroke's points, em units, as a JSON array of arrays of `[x, y]`).
use trajectory::{Method, centre_lines, embedded_glyph};

fn main() {
    let ch = std::env::args().nth(1).and_then(|s| s.chars().next()).unwrap_or('永');
    let g = embedded_glyph(ch).expect("embedded character");
    let paths = centre_lines(&g, Method::Skeleton, trajectory::DEFAULT_ANALYSIS_PX).expect("skeleton");
    println!("{ch}: {} strokes (medians: {})", paths.len(), g.medians.as_ref().map_or(0, Vec::len));
    for (i, p) in paths.iter().enumerate() {
        let (a, b) = (p.points[0], p.points[p.points.len() - 1]);
        println!("  {i}: {} pts from ({:.0},{:.0}) to ({:.0},{:.0})", p.points.len(), a.x, a.y, b.x, b.y);
    }
    if let Some(path) = std::env::args().nth(2) {
        // Every stroke's points (em units) as JSON, for plotting.
        let v: Vec<Vec<[f64; 2]>> = paths.iter().map(|p| p.points.iter().map(|q| [q.x, q.y]).collect()).collect();
        std::fs::write(&path, format!("{v:?}")).expect("write");
    }
}
