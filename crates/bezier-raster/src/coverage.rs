//! The coverage image type and its PNG/SVG forms.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use thiserror::Error;

/// The largest side of any image, px (also what PNG viewers and tiny-skia handle comfortably).
pub const MAX_SIDE: u32 = 16384;

/// The most pixels an image read from a file may have (64 Mpx: a 600-dpi A3 scan), checked from
/// the file's header before anything is decoded.
pub const MAX_LOAD_PIXELS: u64 = 1 << 26;

/// Limits for decoding a user's image: sides up to [`MAX_SIDE`], at most 1 GiB for the decoder.
/// The pixel count is checked separately against [`MAX_LOAD_PIXELS`] (see [`decode_image`]).
pub fn image_limits() -> image::Limits {
    let mut l = image::Limits::default();
    l.max_image_width = Some(MAX_SIDE);
    l.max_image_height = Some(MAX_SIDE);
    l.max_alloc = Some(1 << 30);
    l
}

/// Why an image file cannot be used. The message does not name the file: the error that
/// wraps it ([`RasterError::Read`], or the caller's) does.
#[derive(Debug, Error)]
pub enum ImageFileError {
    /// The file cannot be opened or read (missing, a permission, a read failure).
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The path is a directory or another non-file.
    #[error("not a regular file")]
    NotAFile,
    /// The file has no bytes.
    #[error("the file is empty")]
    Empty,
    /// The bytes are neither PNG nor JPEG.
    #[error("not an image (expected PNG or JPEG)")]
    UnknownFormat,
    /// The header or the pixels cannot be decoded.
    #[error("not a readable image")]
    Decode(#[source] image::ImageError),
    /// More pixels than [`MAX_LOAD_PIXELS`] or a side beyond [`MAX_SIDE`].
    #[error("image is {width}×{height} px; the limit is {MAX_SIDE} px a side and {} Mpx in all", MAX_LOAD_PIXELS >> 20)]
    TooLarge {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
    /// A JPEG file that ends before its image data does (no end-of-image marker after its last
    /// scan): a copy or download cut short. Its decoder would fill the rest in silently.
    #[error("the JPEG file ends before its image data does (truncated: copy it again)")]
    Truncated,
    /// A side of zero pixels.
    #[error("image is {width}×{height} px; each side must be 1..={MAX_SIDE} px")]
    BadSize {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
}

/// Opens and decodes an image file with [`image_limits`], refusing more than
/// [`MAX_LOAD_PIXELS`] from the header's dimensions before decoding ([`image_header`] first).
///
/// # Errors
/// [`ImageFileError`]: missing or unreadable file, empty file, not an image, too large, or
/// pixels that do not decode.
pub fn decode_image(path: &Path) -> Result<image::DynamicImage, ImageFileError> {
    image_header(path)?;
    let mut reader = image::ImageReader::open(path)?.with_guessed_format()?;
    if reader.format() == Some(image::ImageFormat::Jpeg) && !jpeg_is_complete(path)? {
        return Err(ImageFileError::Truncated);
    }
    reader.limits(image_limits());
    reader.decode().map_err(ImageFileError::Decode)
}

/// Whether a JPEG file has an end-of-image marker (FF D9) after its last start-of-scan (FF DA).
/// Inside a scan's data an FF byte is always followed by 00 or a restart marker, so neither
/// pair occurs there by chance. Read in pieces; nothing is kept.
fn jpeg_is_complete(path: &Path) -> Result<bool, ImageFileError> {
    use std::io::Read;
    let mut f = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 16];
    let (mut prev, mut complete) = (0u8, false);
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            return Ok(complete);
        }
        for &b in &buf[..n] {
            if prev == 0xFF {
                match b {
                    0xDA => complete = false,
                    0xD9 => complete = true,
                    _ => {}
                }
            }
            prev = b;
        }
    }
}

/// Checks, from the file and its header only, that an image file can be decoded by
/// [`decode_image`]: it exists, is not empty, is PNG or JPEG, and is within the size limits.
/// Returns its width and height, px.
///
/// # Errors
/// [`ImageFileError`] saying which check failed.
pub fn image_header(path: &Path) -> Result<(u32, u32), ImageFileError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(ImageFileError::NotAFile);
    }
    if meta.len() == 0 {
        return Err(ImageFileError::Empty);
    }
    let reader = image::ImageReader::open(path)?.with_guessed_format()?;
    if reader.format().is_none() {
        return Err(ImageFileError::UnknownFormat);
    }
    let (width, height) = reader.into_dimensions().map_err(ImageFileError::Decode)?;
    if width as u64 * height as u64 > MAX_LOAD_PIXELS || width > MAX_SIDE || height > MAX_SIDE {
        return Err(ImageFileError::TooLarge { width, height });
    }
    Ok((width, height))
}

/// Errors from image I/O.
#[derive(Debug, Error)]
pub enum RasterError {
    /// The file could not be read or decoded.
    #[error("{}: cannot read image", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: ImageFileError,
    },
    /// Encoding failed.
    #[error("cannot encode PNG")]
    Encode(#[source] image::ImageError),
    /// A size was zero or too large.
    #[error("bad image size {0}×{1} (each side must be 1..={MAX_SIDE} px)")]
    BadSize(u32, u32),
}

/// A grayscale coverage image: `width × height` values in `[0, 1]`, row-major, ink = 1.
///
/// # Examples
/// ```
/// use bezier_raster::Coverage;
/// let mut a = Coverage::new(4, 2);
/// a.data_mut()[0] = 1.0;
/// let b = Coverage::from_vec(4, 2, vec![0.5; 8]).unwrap();
/// // Stamps compose by per-pixel max.
/// a.max_with(&b);
/// assert_eq!((a.get(0, 0), a.get(3, 1)), (1.0, 0.5));
/// assert!((a.ink() - 4.5).abs() < 1e-9);
/// // On disk ink is black on white: full ink is grey level 0.
/// assert_eq!(a.to_gray8()[0], 0);
/// // A buffer of the wrong length is refused.
/// assert!(Coverage::from_vec(4, 2, vec![0.0; 7]).is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    width: u32,
    height: u32,
    data: Vec<f32>,
}

impl Coverage {
    /// A blank (all paper) image.
    ///
    /// # Panics
    /// If either side is zero; use [`Coverage::try_new`] for sizes from user input.
    pub fn new(width: u32, height: u32) -> Self {
        Self::try_new(width, height).expect("non-zero image size")
    }

    /// A blank image, checking the size.
    ///
    /// # Errors
    /// [`RasterError::BadSize`] if a side is 0 or above 16384.
    pub fn try_new(width: u32, height: u32) -> Result<Self, RasterError> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(RasterError::BadSize(width, height));
        }
        Ok(Self { width, height, data: vec![0.0; width as usize * height as usize] })
    }

    /// Wraps existing values (row-major, ink = 1).
    ///
    /// # Errors
    /// [`RasterError::BadSize`] if the length does not match.
    pub fn from_vec(width: u32, height: u32, data: Vec<f32>) -> Result<Self, RasterError> {
        if data.len() != width as usize * height as usize || width == 0 || height == 0 {
            return Err(RasterError::BadSize(width, height));
        }
        Ok(Self { width, height, data })
    }

    /// The pixel values, row-major, without a copy (what [`Coverage::data`] borrows).
    pub fn into_vec(self) -> Vec<f32> {
        self.data
    }

    /// Width, px.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Height, px.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// The values, row-major.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    /// The values, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }
    /// The value at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> f32 {
        self.data[y as usize * self.width as usize + x as usize]
    }
    /// Sets every pixel to paper (0).
    pub fn clear(&mut self) {
        self.data.fill(0.0);
    }
    /// Total ink, in pixels (sum of coverage).
    pub fn ink(&self) -> f64 {
        self.data.iter().map(|&v| v as f64).sum()
    }
    /// Per-pixel maximum with `other` (same size).
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn max_with(&mut self, other: &Coverage) {
        assert_eq!((self.width, self.height), (other.width, other.height), "sizes differ");
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a = a.max(*b);
        }
    }

    /// The image as a [`GrayRef`](stroke_metrics::GrayRef) (same values, ink = 1), for scoring
    /// with stroke-metrics.
    ///
    /// # Examples
    /// ```
    /// use bezier_raster::Coverage;
    /// let mut a = Coverage::new(16, 16);
    /// a.data_mut()[..64].fill(1.0);
    /// assert_eq!(bezier_raster::stroke_metrics::iou(a.as_gray(), a.as_gray()).unwrap(), 1.0);
    /// ```
    pub fn as_gray(&self) -> stroke_metrics::GrayRef<'_> {
        stroke_metrics::GrayRef::new(&self.data, self.width as usize, self.height as usize)
            .expect("a Coverage holds width × height values")
    }

    /// 8-bit gray pixels as written to disk: black ink on white (`255 − round(255·v)`).
    pub fn to_gray8(&self) -> Vec<u8> {
        self.data.iter().map(|&v| 255 - (v.clamp(0.0, 1.0) * 255.0).round() as u8).collect()
    }

    /// Encodes as an 8-bit grayscale PNG, black ink on white (fast compression).
    ///
    /// # Errors
    /// [`RasterError::Encode`] (not expected in practice).
    pub fn encode_png(&self) -> Result<Vec<u8>, RasterError> {
        let mut out = Vec::with_capacity(self.data.len() / 4 + 128);
        PngEncoder::new_with_quality(Cursor::new(&mut out), CompressionType::Fast, FilterType::Sub)
            .write_image(&self.to_gray8(), self.width, self.height, ExtendedColorType::L8)
            .map_err(RasterError::Encode)?;
        Ok(out)
    }

    /// Decodes an image file (PNG or JPEG, any colour type) into coverage: dark ink on light
    /// paper becomes ink = 1; transparent pixels count as paper.
    ///
    /// # Errors
    /// [`RasterError::Read`] naming the file when it cannot be opened or decoded.
    pub fn load(path: &Path) -> Result<Self, RasterError> {
        let err = |source| RasterError::Read { path: path.to_path_buf(), source };
        let img = decode_image(path).map_err(err)?;
        let la = img.to_luma_alpha8();
        let (width, height) = la.dimensions();
        let data = la.pixels().map(|p| (1.0 - p.0[0] as f32 / 255.0) * (p.0[1] as f32 / 255.0)).collect();
        Self::from_vec(width, height, data).map_err(|_| err(ImageFileError::BadSize { width, height }))
    }
}

/// An SVG document (black fill on white) of a path given in millimetres, on a page of
/// `width_mm × height_mm`.
pub fn svg_document(path_mm: &kurbo::BezPath, width_mm: f64, height_mm: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width_mm}mm\" height=\"{height_mm}mm\" viewBox=\"0 0 {width_mm} {height_mm}\">\n  <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n  <path d=\"{}\" fill=\"black\" fill-rule=\"nonzero\"/>\n</svg>\n",
        path_mm.to_svg()
    )
}

/// An RGB PNG comparing two images of the same size: paper white, ink of both black, ink only
/// in `reference` red (missed), ink only in `render` blue (overshoot).
///
/// # Errors
/// [`RasterError::BadSize`] if the sizes differ; [`RasterError::Encode`].
pub fn overlay_png(reference: &Coverage, render: &Coverage) -> Result<Vec<u8>, RasterError> {
    if (reference.width, reference.height) != (render.width, render.height) {
        return Err(RasterError::BadSize(render.width, render.height));
    }
    let mut rgb = Vec::with_capacity(reference.data.len() * 3);
    for (&a, &b) in reference.data.iter().zip(&render.data) {
        let (a, b) = (a.clamp(0.0, 1.0), b.clamp(0.0, 1.0));
        rgb.push((255.0 * (1.0 - b)).round() as u8);
        rgb.push((255.0 * (1.0 - a.max(b))).round() as u8);
        rgb.push((255.0 * (1.0 - a)).round() as u8);
    }
    let mut out = Vec::new();
    PngEncoder::new_with_quality(Cursor::new(&mut out), CompressionType::Fast, FilterType::Sub)
        .write_image(&rgb, reference.width, reference.height, ExtendedColorType::Rgb8)
        .map_err(RasterError::Encode)?;
    Ok(out)
}
