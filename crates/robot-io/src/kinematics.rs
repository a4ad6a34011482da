//! AUBO-i5 kinematics: forward kinematics by modified DH and a numerical inverse.
//!
//! Nominal geometry (m): `d1 = 0.122`, `a2 = 0.408`, `a3 = 0.376`, a lateral offset of
//! `0.1215` (the issue's `d2`), `d5 = 0.1025`, `d6 = 0.094`; joint limits ±175°. The table below
//! follows the modified-DH layout of the public robotics kinematics catalogue's AUBO models
//! (`α_{i−1}, a_{i−1}, d_i, θ offset`), with the lateral offset carried at joint 4. It has not
//! been checked against a controller: treat absolute joint angles as assumed and use the
//! kinematics for what it is for here, checking that poses are reachable.

use brush_model::wrap_angle_rad;
use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::pose::Pose;

/// Modified DH rows `(α_{i−1}, a_{i−1}, d_i, θ offset)`, radians and metres.
pub const AUBO_I5_MDH: [(f64, f64, f64, f64); 6] = [
    (0.0, 0.0, 0.122, 0.0),
    (std::f64::consts::FRAC_PI_2, 0.0, 0.0, std::f64::consts::FRAC_PI_2),
    (0.0, 0.408, 0.0, 0.0),
    (0.0, 0.376, 0.1215, -std::f64::consts::FRAC_PI_2),
    (-std::f64::consts::FRAC_PI_2, 0.0, 0.1025, 0.0),
    (std::f64::consts::FRAC_PI_2, 0.0, 0.094, 0.0),
];

/// Joint limit, radians (±175°).
pub const JOINT_LIMIT_RAD: f64 = 175.0 * std::f64::consts::PI / 180.0;

/// Forward kinematics: the flange pose for joint angles `q` (radians), then `tcp` applied.
pub fn forward(q: &[f64; 6], tcp: &Isometry3<f64>) -> Isometry3<f64> {
    let mut t = Isometry3::identity();
    for (i, &(alpha, a, d, off)) in AUBO_I5_MDH.iter().enumerate() {
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha);
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[i] + off);
        t = t
            * Isometry3::from_parts(Translation3::identity(), rx)
            * Isometry3::from_parts(Translation3::new(a, 0.0, 0.0), UnitQuaternion::identity())
            * Isometry3::from_parts(Translation3::identity(), rz)
            * Isometry3::from_parts(Translation3::new(0.0, 0.0, d), UnitQuaternion::identity());
    }
    t * tcp
}

fn error(target: &Isometry3<f64>, at: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - at.translation.vector;
    let dr = (target.rotation * at.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

/// Numerical inverse kinematics (damped least squares from `seed` and a few standard seeds):
/// joint angles within ±175° reaching `target` to 0.01 mm and 1e-4 rad, or `None`.
pub fn inverse(target: &Pose, tcp: &Isometry3<f64>, seed: Option<&[f64; 6]>) -> Option<[f64; 6]> {
    let goal = target.to_iso();
    let mut seeds: Vec<[f64; 6]> = seed.into_iter().copied().collect();
    seeds.extend([
        [0.0, 0.3, 1.6, 0.3, 1.57, 0.0],
        [0.0, -0.3, -1.6, -0.3, -1.57, 0.0],
        [1.57, 0.3, 1.6, 0.3, 1.57, 0.0],
        [-1.57, 0.3, 1.6, 0.3, 1.57, 0.0],
        [0.0, 0.6, 2.0, 1.0, 1.57, 1.57],
        [3.0, 0.3, 1.6, 0.3, 1.57, 0.0],
    ]);
    for s in seeds {
        if let Some(q) = solve_from(&goal, tcp, s) {
            return Some(q);
        }
    }
    None
}

fn solve_from(goal: &Isometry3<f64>, tcp: &Isometry3<f64>, mut q: [f64; 6]) -> Option<[f64; 6]> {
    let mut lambda = 1e-2;
    let mut e = error(goal, &forward(&q, tcp));
    for _ in 0..200 {
        if e.fixed_rows::<3>(0).norm() < 1e-5 && e.fixed_rows::<3>(3).norm() < 1e-4 {
            return q.iter().all(|v| v.abs() <= JOINT_LIMIT_RAD).then_some(q);
        }
        // Numerical Jacobian.
        let mut j = Matrix6::zeros();
        let base = forward(&q, tcp);
        for k in 0..6 {
            let mut qk = q;
            qk[k] += 1e-6;
            let d = error(&forward(&qk, tcp), &base) / 1e-6;
            j.set_column(k, &d);
        }
        let jt = j.transpose();
        let step = (jt * j + Matrix6::identity() * lambda).try_inverse()? * jt * e;
        let mut cand = q;
        for k in 0..6 {
            cand[k] = wrap_angle_rad(cand[k] + step[k]);
        }
        let e2 = error(goal, &forward(&cand, tcp));
        if e2.norm() < e.norm() {
            q = cand;
            e = e2;
            lambda = (lambda * 0.5).max(1e-6);
        } else {
            lambda *= 4.0;
            if lambda > 1e3 {
                return None;
            }
        }
    }
    None
}
