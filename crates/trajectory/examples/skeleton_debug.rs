//! Prints the skeleton strokes found for a character (debugging aid).
//!
//! `cargo run -p trajectory --example skeleton_debug -- 永`
use trajectory::{Method, centre_lines, glyph};

fn main() {
    let ch = std::env::args().nth(1).and_then(|s| s.chars().next()).unwrap_or('永');
    let g = glyph::embedded(ch).expect("embedded character");
    let paths = centre_lines(&g, Method::Skeleton, 256).expect("skeleton");
    println!("{ch}: {} strokes (medians: {})", paths.len(), g.medians.as_ref().map_or(0, Vec::len));
    for (i, p) in paths.iter().enumerate() {
        let (a, b) = (p.points[0], p.points[p.points.len() - 1]);
        println!("  {i}: {} pts from ({:.0},{:.0}) to ({:.0},{:.0})", p.points.len(), a.x, a.y, b.x, b.y);
    }
}
