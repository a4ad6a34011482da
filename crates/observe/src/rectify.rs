//! The ink resampled into a frame of the paper.

use bezier_raster::Coverage;
use serde::Serialize;

use crate::{InkMap, Registration};

/// A raster frame on the paper: `width × height` px whose top-left corner is paper point
/// `(x0_mm, y0_mm)`, at `px_per_mm` (docs/contracts.md §2: pixel `i` covers
/// `[i, i + 1) / px_per_mm` mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// Paper x of the frame's left edge, mm.
    pub x0_mm: f64,
    /// Paper y of the frame's top edge, mm.
    pub y0_mm: f64,
    /// Scale, px per mm.
    pub px_per_mm: f64,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
}

impl Frame {
    /// The paper point at the centre of pixel `(i, j)`, mm.
    pub fn centre_mm(&self, i: u32, j: u32) -> [f64; 2] {
        self.at_mm(i as f64 + 0.5, j as f64 + 0.5)
    }

    /// The paper point at frame position `(u, v)` px, mm.
    pub fn at_mm(&self, u: f64, v: f64) -> [f64; 2] {
        [self.x0_mm + u / self.px_per_mm, self.y0_mm + v / self.px_per_mm]
    }

    /// The frame position of paper point `p`, px.
    pub fn to_px(&self, p: [f64; 2]) -> [f64; 2] {
        [(p[0] - self.x0_mm) * self.px_per_mm, (p[1] - self.y0_mm) * self.px_per_mm]
    }
}

/// The observed ink in `frame`: each pixel the mean of 3 × 3 bilinear samples of the ink map
/// at the photo points the registration maps its area onto.
pub fn rectify(ink: &InkMap, reg: &Registration, frame: &Frame) -> Coverage {
    let mut out = Coverage::new(frame.width, frame.height);
    let w = frame.width as usize;
    let h = &reg.paper_to_photo;
    for j in 0..frame.height {
        for i in 0..frame.width {
            let mut s = 0.0f32;
            for sj in 0..3 {
                for si in 0..3 {
                    let p = frame.at_mm(i as f64 + (si as f64 + 0.5) / 3.0, j as f64 + (sj as f64 + 0.5) / 3.0);
                    let q = h.apply(p);
                    s += ink.sample(q[0], q[1]);
                }
            }
            out.data_mut()[j as usize * w + i as usize] = s / 9.0;
        }
    }
    out
}
