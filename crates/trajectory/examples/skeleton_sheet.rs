//! Draws the skeleton strokes of several characters on one sheet (debugging aid): the glyph in
//! grey, each stroke in its own colour with a dot at its start, the found/expected counts above.
//!
//! `cargo run --release -p trajectory --example skeleton_sheet -- OUT.png CHARS [HANZI_DIR [K=V,K=V]]`
//! (the last argument sets [`GraphOptions`] as `cargo xtask skeleton-counts --opts` does).
use image::{Rgb, RgbImage};
use kurbo::Point;
use trajectory::{GraphOptions, Skeleton, embedded_glyph, glyph_from_hanzi_dir, mask_of, render_glyph};

const PX: u32 = 512;
const CELL: u32 = 256;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (out, chars) = (&args[1], &args[2]);
    let dir = args.get(3).filter(|d| !d.is_empty()).map(std::path::PathBuf::from);
    let mut opts = GraphOptions::default();
    for kv in args.get(4).map_or("", String::as_str).split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').expect("K=V");
        opts.set(k, v.parse().expect("number")).expect("option");
    }
    let chars: Vec<char> = chars.chars().collect();
    let cols = 6u32;
    let rows = (chars.len() as u32).div_ceil(cols);
    let mut img = RgbImage::from_pixel(cols * CELL, rows * CELL, Rgb([255, 255, 255]));
    let colours = [
        [230, 25, 75],
        [60, 180, 75],
        [0, 130, 200],
        [245, 130, 48],
        [145, 30, 180],
        [70, 240, 240],
        [240, 50, 230],
        [128, 128, 0],
        [0, 0, 128],
        [170, 110, 40],
        [128, 0, 0],
        [0, 128, 128],
    ];
    for (k, &ch) in chars.iter().enumerate() {
        let g = match &dir {
            Some(d) => glyph_from_hanzi_dir(d, ch),
            None => embedded_glyph(ch),
        }
        .expect("glyph");
        let (ox, oy) = ((k as u32 % cols) * CELL, (k as u32 / cols) * CELL);
        let mask = mask_of(&render_glyph(&g, PX));
        let s = PX / CELL;
        for y in 0..CELL {
            for x in 0..CELL {
                if mask[((y * s) * PX + x * s) as usize] {
                    img.put_pixel(ox + x, oy + y, Rgb([205, 205, 205]));
                }
            }
        }
        let sk = Skeleton::of(&g, PX).expect("ink");
        let strokes = sk.strokes(&opts);
        let mut put = |p: Point, c: [u8; 3], r: i32| {
            for dy in -r..=r {
                for dx in -r..=r {
                    let (x, y) = ((p.x / s as f64) as i32 + dx, (p.y / s as f64) as i32 + dy);
                    if (0..CELL as i32).contains(&x) && (0..CELL as i32).contains(&y) {
                        img.put_pixel(ox + x as u32, oy + y as u32, Rgb(c));
                    }
                }
            }
        };
        for (i, st) in strokes.iter().enumerate() {
            let c = colours[i % colours.len()];
            for w in st.windows(2) {
                let n = (w[0].distance(w[1]) * 2.0).ceil().max(1.0) as usize;
                for j in 0..=n {
                    put(w[0].lerp(w[1], j as f64 / n as f64), c, 0);
                }
            }
            put(st[0], c, 3);
        }
        // found/expected as bars: one dark tick per found stroke, one light per expected.
        let exp = g.medians.as_ref().map_or(0, Vec::len);
        for i in 0..strokes.len() {
            put(Point::new((4 + 6 * i) as f64 * s as f64, 4.0 * s as f64), [0, 0, 0], 1);
        }
        for i in 0..exp {
            put(Point::new((4 + 6 * i) as f64 * s as f64, 10.0 * s as f64), [150, 150, 150], 1);
        }
        println!("{ch}: {} / {exp}", strokes.len());
    }
    img.save(out).expect("write png");
}
