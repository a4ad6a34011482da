//! Square blocks of a raster, for statistics per block (a paper level under ink, a background
//! plane).

/// Visits the `side × side` blocks of a `width × height` raster `src` (row-major), block row
/// after block row, each row left to right; the last column and row of blocks are clipped at the
/// raster's edges. `visit(bx, by, values)` gets the block's column and row (in blocks) and its
/// pixels row by row, in a scratch buffer that it may reorder (sort for a percentile).
///
/// # Panics
/// If `side` is 0 or `src` is shorter than `width · height`.
///
/// # Examples
/// ```
/// use numerics::for_each_block;
/// // The largest value of each 2 × 2 block of a 3 × 3 raster.
/// let img = [1, 2, 3, 4, 5, 6, 7, 8, 9];
/// let mut max = Vec::new();
/// for_each_block(&img, 3, 3, 2, |bx, by, values| max.push((bx, by, *values.iter().max().unwrap())));
/// assert_eq!(max, [(0, 0, 5), (1, 0, 6), (0, 1, 8), (1, 1, 9)]);
/// ```
pub fn for_each_block<T: Copy>(
    src: &[T],
    width: usize,
    height: usize,
    side: usize,
    mut visit: impl FnMut(usize, usize, &mut [T]),
) {
    assert!(side > 0, "blocks of side 0");
    assert!(src.len() >= width * height, "raster: {} values for {width} × {height}", src.len());
    let mut values = Vec::with_capacity(side * side);
    for by in 0..height.div_ceil(side) {
        for bx in 0..width.div_ceil(side) {
            values.clear();
            for y in by * side..((by + 1) * side).min(height) {
                values.extend_from_slice(&src[y * width + bx * side..y * width + ((bx + 1) * side).min(width)]);
            }
            visit(bx, by, &mut values);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel lands in exactly one block, in row order within it, the edge blocks clipped.
    #[test]
    fn every_pixel_is_in_one_block_in_row_order() {
        let (w, h) = (7, 5);
        let img: Vec<usize> = (0..w * h).collect();
        let mut seen = Vec::new();
        for_each_block(&img, w, h, 3, |bx, by, values| {
            let cols = (3 * bx..(3 * bx + 3).min(w)).count();
            let rows = (3 * by..(3 * by + 3).min(h)).count();
            assert_eq!(values.len(), cols * rows, "block ({bx}, {by})");
            assert!(values.windows(2).all(|p| p[0] < p[1]), "block ({bx}, {by}): {values:?}");
            assert!(values.iter().all(|&i| i % w / 3 == bx && i / w / 3 == by));
            seen.extend_from_slice(values);
        });
        seen.sort_unstable();
        assert_eq!(seen, img);
    }

    /// An empty raster has no blocks.
    #[test]
    fn an_empty_raster_has_no_blocks() {
        let mut n = 0;
        for_each_block::<f32>(&[], 0, 4, 2, |_, _, _| n += 1);
        assert_eq!(n, 0);
    }
}
