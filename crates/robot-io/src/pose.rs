//! Brush poses: a track point on the paper → the TCP pose in the robot's base frame.

use brush_model::TrackPoint;
use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::frame::PaperFrame;

/// A TCP pose as AUBO writes it: `[x, y, z, rx, ry, rz]`, metres and radians, with
/// `R = Rz(rz)·Ry(ry)·Rx(rx)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Pose(pub [f64; 6]);

impl Pose {
    /// From an isometry.
    pub fn from_iso(iso: &Isometry3<f64>) -> Self {
        let t = iso.translation.vector;
        let (rx, ry, rz) = iso.rotation.euler_angles();
        Pose([t.x, t.y, t.z, rx, ry, rz])
    }

    /// To an isometry.
    pub fn to_iso(&self) -> Isometry3<f64> {
        let [x, y, z, rx, ry, rz] = self.0;
        Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_euler_angles(rx, ry, rz))
    }

    /// The rotation as a quaternion `[w, x, y, z]`.
    pub fn quaternion(&self) -> [f64; 4] {
        let q = self.to_iso().rotation;
        [q.w, q.i, q.j, q.k]
    }

    /// The rotation as a rotation vector (axis × angle, radians), as URScript wants it.
    pub fn rotation_vector(&self) -> [f64; 3] {
        let v = self.to_iso().rotation.scaled_axis();
        [v.x, v.y, v.z]
    }

    /// Position, m.
    pub fn position(&self) -> [f64; 3] {
        [self.0[0], self.0[1], self.0[2]]
    }

    /// This pose moved by `dz_m` along the base z axis.
    pub fn raised(&self, dz_m: f64) -> Pose {
        let mut p = self.0;
        p[2] += dz_m;
        Pose(p)
    }
}

/// The brush's orientation relative to the paper frame (z into the paper): the tool's +z axis
/// tilted by α towards the footprint direction β, `R = Rz(β)·Ry(α)·Rz(−β)`. The tool z is then
/// `cos α·n + sin α·d(β)`: from the holder down to the tip, leaning so that the tip (and the
/// footprint) trails behind the holder; at α = 0 the tool does not turn about its own axis
/// whatever β is, so the wrist does not spin along a stroke.
pub fn brush_rotation_in_paper(alpha_rad: f64, beta_rad: f64) -> Rotation3<f64> {
    let z = Vector3::z_axis();
    let y = Vector3::y_axis();
    Rotation3::from_axis_angle(&z, beta_rad)
        * Rotation3::from_axis_angle(&y, alpha_rad)
        * Rotation3::from_axis_angle(&z, -beta_rad)
}

/// The TCP pose (the brush tip, the tool offset being the brush length) for a track point: at
/// paper `(x, y)`, `h` mm into the paper along its normal, oriented by
/// [`brush_rotation_in_paper`].
pub fn brush_pose(frame: &PaperFrame, p: &TrackPoint) -> Pose {
    let local = Point3::new(p.x_mm / 1000.0, p.y_mm / 1000.0, p.h_mm / 1000.0);
    let pos = frame.iso * local;
    let rot =
        frame.iso.rotation * UnitQuaternion::from_rotation_matrix(&brush_rotation_in_paper(p.alpha_rad, p.beta_rad));
    Pose::from_iso(&Isometry3::from_parts(Translation3::from(pos.coords), rot))
}

/// A pose `lift_m` above a track point's paper position (H = −lift), same orientation.
pub fn lifted_pose(frame: &PaperFrame, p: &TrackPoint, lift_m: f64) -> Pose {
    let up = TrackPoint { h_mm: -lift_m * 1000.0, ..*p };
    brush_pose(frame, &up)
}
