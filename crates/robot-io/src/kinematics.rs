//! AUBO-i5 kinematics in the controller's own convention: forward kinematics by modified DH and
//! a numerical inverse.
//!
//! The AUBO controller describes its arm by four arrays, `a`, `alpha`, `d` and `theta` (the
//! joint offsets), as `RobotConfig.getKinematicsParam` reports them. Link `i` is
//! `Rx(alpha_i) · Tx(a_i) · Rz(q_i + theta_i) · Tz(d_i)` (Craig's modified DH, the row's own
//! `alpha` and `a`). [`DhParams::AUBO_I5`] holds the i5's nominal arrays. The convention is
//! verified against a waypoint saved by a real controller (see docs/robot.md, "Kinematics");
//! the nominal lengths are not a calibrated arm's, so joints computed here are used only to
//! check reachability and by the simulator. Programs never command joints solved here: the
//! first move is a [`crate::program::Move::JointPose`], solved by the controller.

use brush_model::wrap_angle_rad;
use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::pose::Pose;

/// An arm's modified-DH parameters as the AUBO controller reports them
/// (`RobotConfig.getKinematicsParam`): per joint, the link length `a` (m), the twist `alpha`
/// (rad), the offset `d` (m) and the joint's zero offset `theta` (rad).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DhParams {
    /// Link lengths `a`, m.
    pub a_m: [f64; 6],
    /// Link twists `alpha`, rad.
    pub alpha_rad: [f64; 6],
    /// Link offsets `d`, m.
    pub d_m: [f64; 6],
    /// Joint zero offsets `theta`, rad (added to the joint angle).
    pub theta_rad: [f64; 6],
}

use std::f64::consts::{FRAC_PI_2, PI};

impl DhParams {
    /// The AUBO-i5's nominal parameters in the controller's convention.
    pub const AUBO_I5: DhParams = DhParams {
        a_m: [0.0, 0.0, 0.408, 0.376, 0.0, 0.0],
        alpha_rad: [0.0, -FRAC_PI_2, PI, PI, -FRAC_PI_2, FRAC_PI_2],
        d_m: [0.122, 0.1215, 0.0, 0.0, 0.1025, 0.094],
        theta_rad: [PI, -FRAC_PI_2, 0.0, -FRAC_PI_2, 0.0, 0.0],
    };

    /// A Universal Robots UR5e's nominal parameters in this convention. UR publishes standard
    /// DH rows (`Rz(θ)·Tz(d)·Tx(a)·Rx(α)`; "Parameters for calculations of kinematics and
    /// dynamics", universal-robots.com FAQ 45257): d = 0.1625, 0, 0, 0.1333, 0.0997, 0.0996 m,
    /// a = 0, −0.425, −0.3922, 0, 0, 0 m, α = π/2, 0, 0, π/2, −π/2, 0, θ = 0. Regrouped as
    /// modified rows, each row takes the previous standard row's `a` and `α` (the last standard
    /// row's are zero), so the same chain reads a = 0, 0, −0.425, −0.3922, 0, 0 and
    /// α = 0, π/2, 0, 0, π/2, −π/2.
    pub const UR5E: DhParams = DhParams {
        a_m: [0.0, 0.0, -0.425, -0.3922, 0.0, 0.0],
        alpha_rad: [0.0, FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2],
        d_m: [0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996],
        theta_rad: [0.0; 6],
    };

    /// Checks that every value is finite, lengths within ±2 m and angles within ±2π; returns
    /// what is wrong, naming the array and the joint.
    ///
    /// # Errors
    /// A message such as `a[3] = inf m is not finite or beyond ±2 m`.
    pub fn validate(&self) -> Result<(), String> {
        let rows: [(&str, &[f64; 6], f64, &str); 4] = [
            ("a", &self.a_m, 2.0, "m"),
            ("alpha", &self.alpha_rad, 2.0 * PI, "rad"),
            ("d", &self.d_m, 2.0, "m"),
            ("theta", &self.theta_rad, 2.0 * PI, "rad"),
        ];
        for (name, v, max, unit) in rows {
            for (i, x) in v.iter().enumerate() {
                if !(x.is_finite() && x.abs() <= max) {
                    return Err(format!("{name}[{i}] = {x} {unit} is not finite or beyond ±{max:.3} {unit}"));
                }
            }
        }
        Ok(())
    }

    /// Forward kinematics: the flange pose in the base frame for joint angles `q` (rad), then
    /// the tool transform `tcp` (flange → TCP) applied.
    pub fn forward(&self, q: &[f64; 6], tcp: &Isometry3<f64>) -> Isometry3<f64> {
        self.chain().forward(q, tcp)
    }

    /// The arm's links with what does not depend on the joints computed once ([`Chain`]): the
    /// i5's nominal chain is computed once per process.
    pub fn chain(&self) -> std::borrow::Cow<'static, Chain> {
        static AUBO_I5: std::sync::LazyLock<Chain> = std::sync::LazyLock::new(|| Chain::new(&DhParams::AUBO_I5));
        if *self == DhParams::AUBO_I5 {
            std::borrow::Cow::Borrowed(&*AUBO_I5)
        } else {
            std::borrow::Cow::Owned(Chain::new(self))
        }
    }

    /// Numerical inverse kinematics (damped least squares from `seed`, then from a few standard
    /// seeds): joint angles within ±[`JOINT_LIMIT_RAD`] that reach `target` to 0.01 mm and
    /// 1e-4 rad, or `None` when no seed converges.
    pub fn inverse(&self, target: &Pose, tcp: &Isometry3<f64>, seed: Option<&[f64; 6]>) -> Option<[f64; 6]> {
        let goal = target.to_iso();
        if !target.0.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut seeds: Vec<[f64; 6]> = seed.into_iter().copied().filter(|s| s.iter().all(|v| v.is_finite())).collect();
        // The tool-down "ready" pose in front of the arm and its turns about the base, the
        // elbow down, and the wrist turned.
        let ready = READY_JOINTS;
        for q1 in [0.0, FRAC_PI_2, -FRAC_PI_2, PI - 0.1, -PI + 0.1] {
            seeds.push([q1, ready[1], ready[2], ready[3], ready[4], ready[5]]);
        }
        seeds.push([0.0, 0.4, -1.7, -0.5, -1.57, 0.0]);
        seeds.push([0.0, ready[1], ready[2], ready[3], -ready[4], 0.0]);
        // A UR arm's tool-down pose ([`UR_HOME_JOINTS`]) and its turns about the base, last: an
        // AUBO arm converges from the seeds above.
        for q1 in [0.0, FRAC_PI_2, -FRAC_PI_2, PI - 0.1, -PI + 0.1] {
            let h = UR_HOME_JOINTS;
            seeds.push([q1, h[1], h[2], h[3], h[4], h[5]]);
        }
        let chain = self.chain();
        seeds.into_iter().find_map(|s| chain.solve_from(&goal, tcp, s))
    }
}

/// A [`DhParams`] arm with each link's fixed part, `Rx(alpha_i) · Tx(a_i)` and `Tz(d_i)`,
/// computed once ([`DhParams::chain`]): [`Chain::forward`] is [`DhParams::forward`] bit for
/// bit (the same products in the same order) without recomputing them, and
/// [`Chain::forward_nudged`] shares the links before each nudged joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    theta_rad: [f64; 6],
    rx: [Isometry3<f64>; 6],
    tx: [Isometry3<f64>; 6],
    tz: [Isometry3<f64>; 6],
}

impl Chain {
    /// The chain of `dh`.
    pub fn new(dh: &DhParams) -> Self {
        Self {
            theta_rad: dh.theta_rad,
            rx: std::array::from_fn(|i| {
                Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), dh.alpha_rad[i]),
                )
            }),
            tx: std::array::from_fn(|i| {
                Isometry3::from_parts(Translation3::new(dh.a_m[i], 0.0, 0.0), UnitQuaternion::identity())
            }),
            tz: std::array::from_fn(|i| {
                Isometry3::from_parts(Translation3::new(0.0, 0.0, dh.d_m[i]), UnitQuaternion::identity())
            }),
        }
    }

    /// `t` followed by link `i` at joint angle `qi` (rad).
    fn link(&self, t: &Isometry3<f64>, i: usize, qi: f64) -> Isometry3<f64> {
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qi + self.theta_rad[i]);
        t * self.rx[i] * self.tx[i] * Isometry3::from_parts(Translation3::identity(), rz) * self.tz[i]
    }

    /// [`DhParams::forward`]: the TCP pose in the base frame for joint angles `q` (rad).
    pub fn forward(&self, q: &[f64; 6], tcp: &Isometry3<f64>) -> Isometry3<f64> {
        let mut t = Isometry3::identity();
        for (i, &qi) in q.iter().enumerate() {
            t = self.link(&t, i, qi);
        }
        t * tcp
    }

    /// The TCP pose at `q` and, for each joint `k`, at `q` with `dq_rad` added to joint `k`
    /// (what a numerical Jacobian needs), each equal bit for bit to [`Chain::forward`] there.
    pub fn forward_nudged(
        &self,
        q: &[f64; 6],
        dq_rad: f64,
        tcp: &Isometry3<f64>,
    ) -> (Isometry3<f64>, [Isometry3<f64>; 6]) {
        // before[i]: the links before link i.
        let mut before = [Isometry3::identity(); 7];
        for i in 0..6 {
            before[i + 1] = self.link(&before[i], i, q[i]);
        }
        let nudged = std::array::from_fn(|k| {
            let mut qk = *q;
            qk[k] += dq_rad;
            let mut t = self.link(&before[k], k, qk[k]);
            for (i, &qi) in qk.iter().enumerate().skip(k + 1) {
                t = self.link(&t, i, qi);
            }
            t * tcp
        });
        (before[6] * tcp, nudged)
    }

    /// Damped least squares from `q` (see [`DhParams::inverse`]).
    fn solve_from(&self, goal: &Isometry3<f64>, tcp: &Isometry3<f64>, mut q: [f64; 6]) -> Option<[f64; 6]> {
        let mut lambda = 1e-2;
        let mut e = error(goal, &self.forward(&q, tcp));
        for _ in 0..200 {
            if e.fixed_rows::<3>(0).norm() < 1e-5 && e.fixed_rows::<3>(3).norm() < 1e-4 {
                return q.iter().all(|v| v.abs() <= JOINT_LIMIT_RAD).then_some(q);
            }
            // Numerical Jacobian.
            let mut j = Matrix6::zeros();
            let (base, nudged) = self.forward_nudged(&q, 1e-6, tcp);
            for (k, at) in nudged.iter().enumerate() {
                let d = error(at, &base) / 1e-6;
                j.set_column(k, &d);
            }
            let jt = j.transpose();
            let step = (jt * j + Matrix6::identity() * lambda).try_inverse()? * jt * e;
            let mut cand = q;
            for k in 0..6 {
                cand[k] = wrap_angle_rad(cand[k] + step[k]);
            }
            let e2 = error(goal, &self.forward(&cand, tcp));
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
}

/// Joint limit, radians (±175°).
pub const JOINT_LIMIT_RAD: f64 = 175.0 * PI / 180.0;

/// The i5's tool-down "ready" joints in the controller's convention, rad: with
/// [`DhParams::AUBO_I5`] the flange is at (0.549, −0.121, 0.263) m with its z pointing down.
pub const READY_JOINTS: [f64; 6] = [0.0, -0.2618, 1.7453, 0.4363, FRAC_PI_2, 0.0];

/// A UR arm's tool-down joints, rad (UR's convention, [`DhParams::UR5E`]): the upper arm up, the
/// forearm forward, the tool pointing down.
pub const UR_HOME_JOINTS: [f64; 6] = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];

/// [`DhParams::forward`] with the i5's nominal parameters.
pub(crate) fn forward(q: &[f64; 6], tcp: &Isometry3<f64>) -> Isometry3<f64> {
    DhParams::AUBO_I5.forward(q, tcp)
}

/// [`DhParams::inverse`] with the i5's nominal parameters.
pub(crate) fn inverse(target: &Pose, tcp: &Isometry3<f64>, seed: Option<&[f64; 6]>) -> Option<[f64; 6]> {
    DhParams::AUBO_I5.inverse(target, tcp, seed)
}

fn error(target: &Isometry3<f64>, at: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - at.translation.vector;
    let dr = (target.rotation * at.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Forward kinematics as the links are written out: each link's four transforms built and
    /// multiplied in order.
    #[allow(clippy::needless_range_loop)] // `i` indexes the joint and the four DH arrays alike
    fn forward_by_the_links(dh: &DhParams, q: &[f64; 6], tcp: &Isometry3<f64>) -> Isometry3<f64> {
        let mut t = Isometry3::identity();
        for (i, qi) in q.iter().enumerate() {
            let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), dh.alpha_rad[i]);
            let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qi + dh.theta_rad[i]);
            t = t
                * Isometry3::from_parts(Translation3::identity(), rx)
                * Isometry3::from_parts(Translation3::new(dh.a_m[i], 0.0, 0.0), UnitQuaternion::identity())
                * Isometry3::from_parts(Translation3::identity(), rz)
                * Isometry3::from_parts(Translation3::new(0.0, 0.0, dh.d_m[i]), UnitQuaternion::identity());
        }
        t * tcp
    }

    fn bits(t: &Isometry3<f64>) -> Vec<u64> {
        t.translation.vector.iter().chain(t.rotation.coords.iter()).map(|v| v.to_bits()).collect()
    }

    proptest::proptest! {
        /// The chain (the i5's cached one, the UR5e's and any other arm's) and its nudged poses
        /// are the links' product bit for bit: the inverse kinematics, the timing and the
        /// simulator give the same joints and poses as before the chain was cached.
        #[test]
        fn the_chain_is_the_links_product_bit_for_bit(
            q in proptest::array::uniform6(-3.2f64..3.2),
            other in proptest::array::uniform6(-1.0f64..1.0),
            tool_m in 0.0f64..0.3,
            zero in 0usize..6,
        ) {
            let mut q = q;
            // Joints at zero (exact zeros in the rotations) as well.
            q[zero] = 0.0;
            let tcp = Isometry3::translation(0.0, 0.0, tool_m);
            let odd = DhParams { a_m: other, alpha_rad: other.map(|v| 3.0 * v), d_m: other.map(|v| -v), theta_rad: other.map(|v| 2.0 * v) };
            for dh in [DhParams::AUBO_I5, DhParams::UR5E, odd] {
                let want = forward_by_the_links(&dh, &q, &tcp);
                proptest::prop_assert_eq!(bits(&dh.forward(&q, &tcp)), bits(&want));
                let (base, nudged) = dh.chain().forward_nudged(&q, 1e-6, &tcp);
                proptest::prop_assert_eq!(bits(&base), bits(&want));
                for (k, got) in nudged.iter().enumerate() {
                    let mut qk = q;
                    qk[k] += 1e-6;
                    proptest::prop_assert_eq!(bits(got), bits(&forward_by_the_links(&dh, &qk, &tcp)), "joint {}", k);
                }
            }
        }
    }
}
