//! Unit-carrying value types shared by every maobi crate.
//!
//! Every length is in millimetres and every angle in radians; the unit is part of each field's
//! name (`h_mm`, `alpha_rad`) so that it also shows in JSON. Degrees appear only at the edges
//! (CLI flags, CSV columns named `*_deg`) and are converted with [`deg_to_rad`] once.

use serde::{Deserialize, Serialize};

/// Converts degrees to radians (for CLI flags and CSV columns only).
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

/// Converts radians to degrees (for display at the edges only).
pub fn rad_to_deg(rad: f64) -> f64 {
    rad.to_degrees()
}

/// An angle wrapped into (−π, π], rad: the one angle wrap of maobi (a direction, a β, a
/// joint). `π` stays `π` and `−π` becomes `π`; every other finite angle maps to the value in
/// range that differs from it by a multiple of 2π. A non-finite angle gives NaN.
pub fn wrap_angle_rad(angle_rad: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let t = (angle_rad + PI).rem_euclid(TAU) - PI;
    if t <= -PI { t + TAU } else { t }
}

/// A point or vector in a millimetre frame (the paper frame: x right, y down; or a footprint's
/// own frame: x along the axis from root to tip).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct PointMm {
    /// x coordinate, mm.
    pub x_mm: f64,
    /// y coordinate, mm.
    pub y_mm: f64,
}

impl PointMm {
    /// A point from its coordinates in mm.
    pub const fn new(x_mm: f64, y_mm: f64) -> Self {
        Self { x_mm, y_mm }
    }

    /// Rotates this point about the origin by `angle_rad`, measured from +x towards +y.
    pub fn rotated(self, angle_rad: f64) -> Self {
        let (s, c) = angle_rad.sin_cos();
        Self::new(c * self.x_mm - s * self.y_mm, s * self.x_mm + c * self.y_mm)
    }

    /// Component-wise sum.
    pub fn offset(self, by: PointMm) -> Self {
        Self::new(self.x_mm + by.x_mm, self.y_mm + by.y_mm)
    }

    /// Euclidean distance to `other`, mm.
    pub fn distance(self, other: PointMm) -> f64 {
        (self.x_mm - other.x_mm).hypot(self.y_mm - other.y_mm)
    }
}

/// A hairy brush: the bundle's length and its maximum radius (the paper's `B = {L, R}`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Brush {
    /// Length of the hair bundle from the ferrule to the tip, mm (`L`).
    pub length_mm: f64,
    /// Maximum radius of the hair bundle, mm (`R`).
    pub radius_mm: f64,
}

/// How the robot holds the brush against the paper at one instant (the paper's `F_R = (h, α, β)`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Press {
    /// Press depth: how far the holder has descended past the point where the tip just touches
    /// the paper, mm (`h`, the paper's `H`).
    pub h_mm: f64,
    /// Tilt of the bundle away from the paper normal, radians (`α`).
    pub alpha_rad: f64,
    /// Rotation of the footprint in the paper plane, from the paper's +x axis towards +y,
    /// radians (`β`).
    pub beta_rad: f64,
}

impl Press {
    /// A press from depth (mm) and angles (radians).
    pub const fn new(h_mm: f64, alpha_rad: f64, beta_rad: f64) -> Self {
        Self { h_mm, alpha_rad, beta_rad }
    }

    /// A press from depth (mm) and angles in degrees (edge helper for CLI and CSV input).
    pub fn from_degrees(h_mm: f64, alpha_deg: f64, beta_deg: f64) -> Self {
        Self::new(h_mm, deg_to_rad(alpha_deg), deg_to_rad(beta_deg))
    }
}

/// One point of a 5D brush track `T_i = (H_i, α_i, x_i, y_i, β_i)` on the paper.
///
/// `(x_mm, y_mm)` is where the brush axis meets the paper, which is the footprint's anchor
/// (its root end `P0`); `beta_rad` is the direction of the footprint's axis (root to tip).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackPoint {
    /// Paper x of the anchor, mm (x right).
    pub x_mm: f64,
    /// Paper y of the anchor, mm (y down).
    pub y_mm: f64,
    /// Press depth, mm.
    pub h_mm: f64,
    /// Tilt, radians.
    pub alpha_rad: f64,
    /// Footprint direction in the paper plane, radians from +x towards +y.
    pub beta_rad: f64,
}

impl TrackPoint {
    /// The press part `(h, α, β)` of this point.
    pub fn press(&self) -> Press {
        Press::new(self.h_mm, self.alpha_rad, self.beta_rad)
    }

    /// The anchor `(x, y)` of this point on the paper.
    pub fn anchor(&self) -> PointMm {
        PointMm::new(self.x_mm, self.y_mm)
    }

    /// Whether the brush presses into the paper here: `h > 0` (a NaN depth is not pressed).
    pub fn is_pressed(&self) -> bool {
        self.h_mm > 0.0
    }
}

/// One stroke: the points the brush passes through between touching down and lifting off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(transparent)]
pub struct Stroke {
    /// Points in writing order.
    pub points: Vec<TrackPoint>,
}

/// A brush track: strokes in writing order, with a pen lift between consecutive strokes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct Track {
    /// Strokes in writing order.
    pub strokes: Vec<Stroke>,
}

impl Track {
    /// Total number of points over all strokes.
    pub fn point_count(&self) -> usize {
        self.strokes.iter().map(|s| s.points.len()).sum()
    }

    /// All points in writing order, ignoring the lifts.
    pub fn points(&self) -> impl Iterator<Item = &TrackPoint> {
        self.strokes.iter().flat_map(|s| s.points.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::wrap_angle_rad;
    use std::f64::consts::{PI, TAU};

    #[test]
    fn wrap_is_half_open_at_minus_pi() {
        assert_eq!(wrap_angle_rad(PI), PI);
        assert_eq!(wrap_angle_rad(-PI), PI);
        assert_eq!(wrap_angle_rad(3.0 * PI), PI);
        assert_eq!(wrap_angle_rad(0.0), 0.0);
        assert!((wrap_angle_rad(-PI + 1e-9) - (-PI + 1e-9)).abs() < 1e-15);
        for k in -5..=5 {
            let a = 0.3 + k as f64 * TAU;
            assert!((wrap_angle_rad(a) - 0.3).abs() < 1e-12, "{a}");
        }
        assert!(wrap_angle_rad(f64::NAN).is_nan() && wrap_angle_rad(f64::INFINITY).is_nan());
    }
}
