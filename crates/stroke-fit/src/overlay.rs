//! A fitted footprint drawn over its photo (the paper's Fig. 8), to see how well it fits.

use bezier_raster::kurbo;
use bezier_raster::{Bsm, StrokeModel};

use crate::{InkMask, StrokeFit};

/// The photo in grey with the fitted B-BSM outline in red, as PNG bytes: `mask` the photo as
/// [`crate::load_ink`] read it, `fit` [`crate::fit_footprint`]'s result on it, `scale_px_per_mm`
/// the photo's scale.
///
/// The outline is flattened to a quarter pixel and drawn as 2-px dots, so the work follows the
/// outline's length in pixels (a tiny scale does not make millions of points), each segment's
/// dots capped by the image's perimeter.
///
/// # Errors
/// [`image::ImageError`] if the PNG cannot be encoded.
///
/// # Examples
/// ```
/// use stroke_fit::{fit_footprint, fit_overlay, mask_from_gray};
/// // A dark 20×8 px bar on white, at 4 px/mm.
/// let (w, h) = (48, 32);
/// let gray = (0..w * h).map(|i| if (14..34).contains(&(i % w)) && (12..20).contains(&(i / w)) { 0.1 } else { 0.9 }).collect();
/// let mask = mask_from_gray(gray, w, h, "bar.png")?;
/// let fit = fit_footprint(&mask, 4.0);
/// let png = fit_overlay(&mask, &fit, 4.0)?;
/// assert_eq!(&png[1..4], b"PNG");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn fit_overlay(mask: &InkMask, fit: &StrokeFit, scale_px_per_mm: f64) -> Result<Vec<u8>, image::ImageError> {
    let scale = scale_px_per_mm;
    let (w, h) = (mask.width as u32, mask.height as u32);
    let path =
        Bsm.outline(&fit.footprint(), brush_model::PointMm::new(fit.anchor_mm[0], fit.anchor_mm[1]), fit.beta_rad);
    let mut img = image::RgbImage::from_fn(w, h, |x, y| {
        let g = (mask.gray[(y * w + x) as usize].clamp(0.0, 1.0) * 255.0) as u8;
        image::Rgb([g, g, g])
    });
    let mut flat = Vec::new();
    kurbo::flatten(path.iter(), 0.25 / scale, |el| match el {
        kurbo::PathEl::MoveTo(p) | kurbo::PathEl::LineTo(p) => flat.push(p),
        _ => {}
    });
    for win in flat.windows(2) {
        let (a, b) = (win[0], win[1]);
        let steps = ((a.distance(b) * scale) * 2.0).ceil().clamp(1.0, 4.0 * (w + h) as f64) as usize;
        for i in 0..=steps {
            let p = a.lerp(b, i as f64 / steps as f64);
            let (cx, cy) = ((p.x * scale) as i64, (p.y * scale) as i64);
            for dy in 0..2 {
                for dx in 0..2 {
                    let (x, y) = (cx + dx, cy + dy);
                    if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
                        img.put_pixel(x as u32, y as u32, image::Rgb([230, 20, 20]));
                    }
                }
            }
        }
    }
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit_footprint;

    #[test]
    fn the_outline_is_red_on_grey_and_stays_inside_the_image() {
        let (w, h) = (64usize, 40usize);
        let gray = (0..w * h)
            .map(|i| if (16..48).contains(&(i % w)) && (14..26).contains(&(i / w)) { 0.1 } else { 0.9 })
            .collect();
        let mask = crate::mask_from_gray(gray, w, h, "bar.png").unwrap();
        let fit = fit_footprint(&mask, 4.0);
        let png = fit_overlay(&mask, &fit, 4.0).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (w as u32, h as u32));
        let red = img.pixels().filter(|p| p.0 == [230, 20, 20]).count();
        assert!(red > 40, "{red} red pixels");
        let grey = img.get_pixel(0, 0).0;
        assert!(grey[0] == grey[1] && grey[1] == grey[2], "{grey:?}");
        // A tiny scale: the dots stay bounded, the image whole.
        assert!(fit_overlay(&mask, &fit, 1e-3).is_ok());
    }
}
