//! Zhang–Suen thinning of a binary image to a one-pixel-wide skeleton, and an even sampling of
//! its pixels.

use kurbo::Point;

/// The 8 neighbours of `(x, y)` clockwise from north (P2..P9); outside the image is paper.
fn ring(m: &[bool], w: usize, h: usize, x: isize, y: isize) -> [bool; 8] {
    let at =
        |x: isize, y: isize| x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h && m[y as usize * w + x as usize];
    [
        at(x, y - 1),
        at(x + 1, y - 1),
        at(x + 1, y),
        at(x + 1, y + 1),
        at(x, y + 1),
        at(x - 1, y + 1),
        at(x - 1, y),
        at(x - 1, y - 1),
    ]
}

/// Thins `mask` (`w × h`, true = ink) in place by Zhang–Suen's two-subiteration algorithm,
/// until no pixel changes. Pixels on the image border are treated as having paper outside.
pub(crate) fn zhang_suen(mask: &mut [bool], w: usize, h: usize) {
    let mut remove = Vec::new();
    loop {
        let mut changed = false;
        for step in 0..2 {
            remove.clear();
            for y in 0..h as isize {
                for x in 0..w as isize {
                    if !mask[y as usize * w + x as usize] {
                        continue;
                    }
                    // Neighbours P2..P9, clockwise from north.
                    let p = ring(mask, w, h, x, y);
                    let b = p.iter().filter(|&&v| v).count();
                    if !(2..=6).contains(&b) {
                        continue;
                    }
                    let a = (0..8).filter(|&i| !p[i] && p[(i + 1) % 8]).count();
                    if a != 1 {
                        continue;
                    }
                    let (p2, p4, p6, p8) = (p[0], p[2], p[4], p[6]);
                    // Zhang & Suen (1984) state these as products that must vanish
                    // (P2·P4·P6 = 0 and P4·P6·P8 = 0); written so, they read against the paper.
                    #[allow(clippy::nonminimal_bool, reason = "the paper's conditions, term by term")]
                    let ok = if step == 0 {
                        !(p2 && p4 && p6) && !(p4 && p6 && p8)
                    } else {
                        !(p2 && p4 && p8) && !(p2 && p6 && p8)
                    };
                    if ok {
                        remove.push(y as usize * w + x as usize);
                    }
                }
            }
            for &i in &remove {
                mask[i] = false;
            }
            changed |= !remove.is_empty();
        }
        if !changed {
            break;
        }
    }
}

/// Removes the redundant corner pixels Zhang–Suen leaves on diagonal lines (4-connected
/// staircases), so every line pixel has exactly two 8-neighbours: a pixel is removed when two of
/// its 4-neighbours at right angles are set (a staircase corner), it has two or three
/// neighbours, and those stay 8-connected without it.
pub(crate) fn remove_staircases(mask: &mut [bool], w: usize, h: usize) {
    for y in 0..h as isize {
        for x in 0..w as isize {
            if !mask[y as usize * w + x as usize] {
                continue;
            }
            let p = ring(mask, w, h, x, y);
            let (n, e, s, wst) = (p[0], p[2], p[4], p[6]);
            // A staircase corner: a horizontal and a vertical 4-neighbour, at right angles.
            let corner = (e || wst) && (n || s);
            let count = p.iter().filter(|&&b| b).count();
            if corner && (2..=3).contains(&count) && neighbours_connected(&p) {
                mask[y as usize * w + x as usize] = false;
            }
        }
    }
}

/// Whether the set neighbours (ring order N, NE, E, SE, S, SW, W, NW) are 8-connected among
/// themselves without the centre pixel.
fn neighbours_connected(p: &[bool; 8]) -> bool {
    const XY: [(i32, i32); 8] = [(0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)];
    let set: Vec<usize> = (0..8).filter(|&i| p[i]).collect();
    let Some(&first) = set.first() else { return true };
    let mut seen = vec![first];
    let mut k = 0;
    while k < seen.len() {
        let (ax, ay) = XY[seen[k]];
        for &j in &set {
            let (bx, by) = XY[j];
            if !seen.contains(&j) && (ax - bx).abs() <= 1 && (ay - by).abs() <= 1 {
                seen.push(j);
            }
        }
        k += 1;
    }
    seen.len() == set.len()
}

/// Keeps the first pixel of each `cell × cell` block (an even sampling along lines of any
/// direction, where every k-th pixel in raster order would alias); returns the kept pixel
/// centres in em units (`px_em` em units per pixel).
pub(crate) fn grid_thin(px: &[(usize, usize)], cell: usize, px_em: f64) -> Vec<Point> {
    let mut seen = std::collections::HashSet::new();
    px.iter()
        .filter(|&&(x, y)| seen.insert((x / cell, y / cell)))
        .map(|&(x, y)| Point::new((x as f64 + 0.5) * px_em, (y as f64 + 0.5) * px_em))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(m: &[bool]) -> usize {
        m.iter().filter(|&&b| b).count()
    }

    #[test]
    fn a_thick_bar_becomes_a_line() {
        let (w, h) = (40, 15);
        let mut m: Vec<bool> = (0..w * h).map(|i| (5..10).contains(&(i / w)) && (3..37).contains(&(i % w))).collect();
        zhang_suen(&mut m, w, h);
        // One pixel wide: each inked column has exactly one pixel, on the bar's middle row.
        for x in 0..w {
            let col: Vec<usize> = (0..h).filter(|&y| m[y * w + x]).collect();
            assert!(col.len() <= 1, "column {x}: {col:?}");
            if let Some(&y) = col.first() {
                assert!((6..=8).contains(&y));
            }
        }
        assert!(count(&m) > 25);
    }

    #[test]
    fn staircases_become_eight_connected_lines() {
        let (w, h) = (30, 30);
        let mut m: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                (3..27).contains(&x) && (y == x || y == x + 1)
            })
            .collect();
        remove_staircases(&mut m, w, h);
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                if m[y * w + x] {
                    let nb = [(0i64, -1i64), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)]
                        .iter()
                        .filter(|(dx, dy)| m[(y as i64 + dy) as usize * w + (x as i64 + dx) as usize])
                        .count();
                    assert!(nb <= 2, "({x},{y}) has {nb} neighbours");
                }
            }
        }
        assert!(m.iter().filter(|&&b| b).count() >= 23);
    }

    #[test]
    fn a_plus_keeps_its_four_arms_connected() {
        let (w, h) = (41, 41);
        let mut m: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                ((17..24).contains(&x) && (3..38).contains(&y)) || ((17..24).contains(&y) && (3..38).contains(&x))
            })
            .collect();
        zhang_suen(&mut m, w, h);
        let (_, sizes) = bezier_raster::connected_components(&m, w, h, true);
        // 4-connectivity may split diagonal steps, so check 8-connected reach instead: the arms'
        // tips are all inked and the centre is inked.
        assert!(sizes.len() >= 2);
        assert!(m[20 * w + 20] || m[20 * w + 19] || m[19 * w + 20]);
        for (x, y) in [(20usize, 8usize), (20, 32), (8, 20), (32, 20)] {
            assert!(m[y * w + x], "arm through ({x},{y}) missing");
        }
    }
}
