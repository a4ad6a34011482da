//! The glyph raster a track is refined against.

use brush_model::PointMm;

use crate::RefineError;

/// The glyph raster a track is refined against: `width × height` pixels of ink coverage
/// (1 = ink), row-major, pixel `(i, j)` centred at paper point
/// `origin + ((i + ½)·mm_per_px, (j + ½)·mm_per_px)` mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Ink coverage in [0, 1], `width × height` values, row-major.
    pub ink: Vec<f32>,
    /// Paper position of the image's top-left corner, mm.
    pub origin_mm: PointMm,
    /// Pixel size, mm.
    pub mm_per_px: f64,
}

impl Target {
    /// A target from its parts.
    ///
    /// # Errors
    /// [`RefineError::Target`] when the sizes disagree, a value is outside [0, 1] or not
    /// finite, or the pixel size is not a positive length.
    ///
    /// # Examples
    /// ```
    /// use track_refine::Target;
    /// use track_refine::brush_model::PointMm;
    ///
    /// // 4 × 2 px at 0.5 mm per pixel, its top-left corner at (10, 20) mm; the left half inked.
    /// let ink = vec![1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0];
    /// let target = Target::new(4, 2, ink.clone(), PointMm::new(10.0, 20.0), 0.5)?;
    /// assert_eq!(target.ink, ink);
    /// // Seven values for eight pixels, or coverage above 1, are refused.
    /// assert!(Target::new(4, 2, vec![0.0; 7], PointMm::new(0.0, 0.0), 0.5).is_err());
    /// assert!(Target::new(1, 1, vec![1.5], PointMm::new(0.0, 0.0), 0.5).is_err());
    /// # Ok::<(), track_refine::RefineError>(())
    /// ```
    pub fn new(
        width: u32,
        height: u32,
        ink: Vec<f32>,
        origin_mm: PointMm,
        mm_per_px: f64,
    ) -> Result<Self, RefineError> {
        if width == 0 || height == 0 || ink.len() != width as usize * height as usize {
            return Err(RefineError::Target(format!(
                "{} values for {width}×{height} px (expected width × height values, both sides at least 1)",
                ink.len()
            )));
        }
        if !(mm_per_px.is_finite() && mm_per_px > 0.0) {
            return Err(RefineError::Target(format!("pixel size {mm_per_px} mm (expected a positive length)")));
        }
        if !(origin_mm.x_mm.is_finite() && origin_mm.y_mm.is_finite()) {
            return Err(RefineError::Target("the origin is not finite".into()));
        }
        if let Some(v) = ink.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(RefineError::Target(format!("ink value {v} (expected coverage in [0, 1])")));
        }
        Ok(Self { width, height, ink, origin_mm, mm_per_px })
    }
}
