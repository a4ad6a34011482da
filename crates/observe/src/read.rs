//! A photo file taken through the first steps: decoded, its ink found, its marks registered.

use std::path::Path;

use crate::{InkMap, KnownMark, ObserveError, Photo, Registration, ink_map, register};

/// A photo of a sheet with its ink found and its registration marks registered
/// ([`read_sheet_photo`]).
#[derive(Clone, Debug)]
pub struct SheetPhoto {
    /// The photo's luminance.
    pub photo: Photo,
    /// The ink on the sheet.
    pub ink: InkMap,
    /// The photo registered onto the paper.
    pub registration: Registration,
}

/// Reads the photo file `path` (JPEG or PNG, [`bezier_raster::decode_image`]) and takes it
/// through [`Photo::from_image`], [`ink_map`] and [`register`] against `marks`, the sheet's
/// registration marks (the four corners first and at least one more, as [`register`] needs). The decoded image is dropped once the photo's luminance is taken.
///
/// # Errors
/// [`ObserveError::Image`] when the file cannot be read or decoded; as [`Photo::from_image`],
/// [`ink_map`] and [`register`]. No error names `path`: the caller does (it knows which flag
/// gave it).
pub fn read_sheet_photo(path: &Path, marks: &[KnownMark]) -> Result<SheetPhoto, ObserveError> {
    let photo = Photo::from_image(&bezier_raster::decode_image(path)?)?;
    let ink = ink_map(&photo)?;
    let registration = register(&ink, marks)?;
    Ok(SheetPhoto { photo, ink, registration })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_step_says_where_a_photo_fails() {
        let mark = |x: f64, y: f64| KnownMark {
            role: format!("({x}, {y})"),
            centre_mm: [x, y],
            half_length_mm: 2.0,
            half_width_mm: 2.0,
        };
        let marks = [mark(10.0, 10.0), mark(200.0, 10.0), mark(200.0, 287.0), mark(10.0, 287.0), mark(30.0, 10.0)];
        let d = std::env::temp_dir().join(format!("observe-read-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let e = read_sheet_photo(&d.join("missing.png"), &marks).unwrap_err();
        assert!(matches!(e, ObserveError::Image(_)), "{e}");
        let small = d.join("small.png");
        image::GrayImage::from_pixel(50, 50, image::Luma([255])).save(&small).unwrap();
        assert!(matches!(read_sheet_photo(&small, &marks), Err(ObserveError::TooSmall { width: 50, height: 50 })));
        // Blank paper: the sheet is found, but no marks on it.
        let blank = d.join("blank.png");
        image::GrayImage::from_pixel(300, 300, image::Luma([230])).save(&blank).unwrap();
        let e = read_sheet_photo(&blank, &marks).unwrap_err();
        assert!(matches!(e, ObserveError::TooFewBlobs { .. } | ObserveError::NoPaper), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
