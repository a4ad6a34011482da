//! # bezier-raster
//!
//! Footprints to pixels, exactly and fast.
//!
//! * Stroke models: the [`StrokeModel`] trait ([`ModelKind`] names them): the analytic B-BSM outline ([`Bsm`]) and the paper's
//!   baselines ([`Circle`], [`Ellipse`], [`Line`], [`Qbc`]), all built from the same
//!   [`Footprint`](brush_model::Footprint) and anchor so comparisons are fair. Outlines are kurbo
//!   [`BezPath`](kurbo::BezPath)s in paper millimetres.
//! * Rasterising: a reusable [`Rasterizer`] that fills a path, scaled by `px_per_mm`, into a
//!   [`Coverage`] image with tiny-skia's anti-aliasing (ink = 1), either replacing the image or
//!   stamping into it by per-pixel max (docs/contracts.md §6).
//! * The single-footprint canvas convention shared by `maobi stroke`, the dataset and
//!   the neural generator ([`StrokeCanvas`]).
//! * Batches: parallel rendering with rayon ([`render_batch`], [`render_track`]) and the [`Compositor`] for many stamps.
//! * Datasets ([`DatasetSpec`]): deterministic random presses over a profile's range and their images.
//! * Binary analysis: [`otsu_threshold`], [`connected_components`], [`fill_holes`].
//! * [`Coverage`]: the image type, PNG encode/decode (black ink on white on disk), and SVG
//!   ([`svg_document`]); image files read within limits ([`decode_image`]).
//!
//! Pixel convention: x right, y down; pixel `(i, j)` covers `[i, i+1) × [j, j+1)` in pixel
//! units, so its centre is at `(i + 0.5, j + 0.5)`; paper point `(x, y)` mm is at
//! `(x·px_per_mm, y·px_per_mm)` px.
//!
//! ```
//! use bezier_raster::{Bsm, Rasterizer, StrokeCanvas, Coverage};
//! use brush_model::{BrushProfile, Extrapolation, Press};
//! let pen1 = BrushProfile::builtin("pen1").unwrap();
//! let canvas = StrokeCanvas::for_profile(&pen1, 128);
//! let press = Press::from_degrees(15.0, 5.0, 0.0);
//! let fp = pen1.predict(&press, Extrapolation::Refuse).unwrap();
//! let mut img = Coverage::new(128, 128);
//! Rasterizer::new().render(&Bsm, &fp, canvas.anchor_mm(&fp, press.beta_rad), press.beta_rad, canvas.px_per_mm, &mut img);
//! let ink: f32 = img.data().iter().sum();
//! let area_px = fp.area_mm2() * canvas.px_per_mm * canvas.px_per_mm;
//! assert!((ink as f64 - area_px).abs() < 0.02 * area_px);
//! ```

#![warn(unreachable_pub)]

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`bezier_raster::brush_model::Press`).
pub use brush_model;
pub use image;
pub use kurbo;
pub use stroke_metrics;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod batch;
mod binary;
mod canvas;
mod coverage;
mod dataset;
mod models;
mod raster;

pub use batch::{Compositor, Stamp, render_batch, render_stamps, render_track, sweep_stamps, track_stamps};
pub use binary::{connected_components, fill_holes, otsu_threshold};
pub use canvas::StrokeCanvas;
pub use coverage::{
    Coverage, ImageFileError, MAX_LOAD_PIXELS, MAX_SIDE, RasterError, decode_image, image_header, image_limits,
    overlay_png, svg_document,
};
pub use dataset::{DatasetSpec, Sample};
pub use models::{Bsm, Circle, Ellipse, Line, ModelKind, QBC_DISCS, Qbc, StrokeModel};
pub use raster::Rasterizer;
