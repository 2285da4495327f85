//! Robots from Denavit–Hartenberg tables (seed 000, table 2).

use super::{
    DescriptionProblem, Joint, JointKind, JointLimits, KinematicTree, KinematicsError, Link, Robot,
};
use crate::math::{Point3, Transform, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Which Denavit–Hartenberg convention a table uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DhConvention {
    /// Standard (distal) D-H, as in seed 000 table 2: frame `i` follows frame `i−1` by
    /// `Rz(θᵢ + qᵢ) · Tz(dᵢ) · Tx(aᵢ) · Rx(αᵢ)`; joint `i` turns about `z` of frame
    /// `i−1`.
    #[default]
    Standard,
    /// Modified (proximal, Craig) D-H: frame `i` follows frame `i−1` by
    /// `Rx(αᵢ₋₁) · Tx(aᵢ₋₁) · Rz(θᵢ + qᵢ) · Tz(dᵢ)` (the row holds `αᵢ₋₁, aᵢ₋₁`);
    /// joint `i` turns about `z` of frame `i`.
    Modified,
}

/// One row of a D-H table. `theta` is the joint **offset**: the joint value 0 puts the
/// row at `theta` (seed 000's θ column). Lengths in mm, angles in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhRow {
    /// Joint offset θ (rad); for a prismatic row the fixed angle.
    pub theta: f64,
    /// Offset d along z (mm); for a prismatic row the offset at joint value 0.
    pub d: f64,
    /// Length a along x (mm).
    pub a: f64,
    /// Twist α about x (rad).
    pub alpha: f64,
    /// Revolute (about z, varies θ) or prismatic (along z, varies d).
    pub kind: JointKind,
    /// Joint limits (rad or mm), relative to the offset.
    pub limits: Option<JointLimits>,
}

impl DhRow {
    /// A revolute row (rad, mm).
    pub fn revolute(theta: f64, d: f64, a: f64, alpha: f64) -> Self {
        Self {
            theta,
            d,
            a,
            alpha,
            kind: JointKind::Revolute,
            limits: None,
        }
    }

    /// A revolute row with angles in degrees, as tables are printed.
    pub fn degrees(theta_deg: f64, d: f64, a: f64, alpha_deg: f64) -> Self {
        Self::revolute(theta_deg.to_radians(), d, a, alpha_deg.to_radians())
    }

    /// A prismatic row (rad, mm).
    pub fn prismatic(theta: f64, d: f64, a: f64, alpha: f64) -> Self {
        Self {
            kind: JointKind::Prismatic,
            ..Self::revolute(theta, d, a, alpha)
        }
    }

    /// The same row with joint limits (rad or mm).
    #[must_use]
    pub fn with_limits(mut self, limits: JointLimits) -> Self {
        self.limits = Some(limits);
        self
    }
}

fn rz(a: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vec3::z_axis(), a),
    )
}
fn rx(a: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vec3::x_axis(), a),
    )
}
fn tr(x: f64, z: f64) -> Isometry3<f64> {
    Isometry3::translation(x, 0.0, z)
}

impl KinematicTree {
    /// A serial tree from a D-H table: link 0 is the fixed base (D-H frame 0), link
    /// `i` carries D-H frame `i` and joint `i`. Every link frame is its D-H frame.
    pub fn from_dh(rows: &[DhRow], convention: DhConvention) -> Result<Self, KinematicsError> {
        let mut links = vec![Link::new("base", None, Transform::IDENTITY, Joint::fixed())];
        for (i, r) in rows.iter().enumerate() {
            if ![r.theta, r.d, r.a, r.alpha].iter().all(|v| v.is_finite()) {
                return Err(KinematicsError::InvalidDescription(
                    DescriptionProblem::DhNotFinite { row: i + 1 },
                ));
            }
            if r.kind == JointKind::Fixed {
                return Err(KinematicsError::InvalidDescription(
                    DescriptionProblem::DhJointKind { row: i + 1 },
                ));
            }
            let (home, axis, point) = match convention {
                DhConvention::Standard => (
                    rz(r.theta) * tr(0.0, r.d) * tr(r.a, 0.0) * rx(r.alpha),
                    Vec3::z(),
                    Point3::origin(),
                ),
                DhConvention::Modified => (
                    rx(r.alpha) * tr(r.a, 0.0) * rz(r.theta) * tr(0.0, r.d),
                    Vec3::new(0.0, -r.alpha.sin(), r.alpha.cos()),
                    Point3::new(r.a, 0.0, 0.0),
                ),
            };
            let mut joint = match r.kind {
                JointKind::Prismatic => Joint::prismatic(axis),
                _ => Joint::revolute(axis, point),
            };
            joint.limits = r.limits;
            links.push(Link::new(
                format!("link{}", i + 1),
                Some(i),
                Transform::from_isometry(home),
                joint,
            ));
        }
        KinematicTree::new(links)
    }
}

impl Robot {
    /// A robot from a D-H table: the flange is the last D-H frame and `tool` the TCP
    /// in it.
    pub fn from_dh(
        name: impl Into<String>,
        rows: &[DhRow],
        convention: DhConvention,
        tool: Transform,
    ) -> Result<Self, KinematicsError> {
        let tree = KinematicTree::from_dh(rows, convention)?;
        let flange = tree.len() - 1;
        Robot::new(name, tree, flange, tool)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    /// 2R planar arm in standard D-H (a1 = 100, a2 = 60): by hand the tip is at
    /// (100 cos q1 + 60 cos(q1+q2), 100 sin q1 + 60 sin(q1+q2), 0).
    #[test]
    fn planar_dh_by_hand_both_conventions() {
        let std_rows = [
            DhRow::revolute(0.0, 0.0, 100.0, 0.0),
            DhRow::revolute(0.0, 0.0, 60.0, 0.0),
        ];
        let r =
            Robot::from_dh("2r", &std_rows, DhConvention::Standard, Transform::IDENTITY).unwrap();
        // Modified: the a of row i is the previous link length; the tip needs a tool.
        let mod_rows = [
            DhRow::revolute(0.0, 0.0, 0.0, 0.0),
            DhRow::revolute(0.0, 0.0, 100.0, 0.0),
        ];
        let tool = Transform::from_translation(Vec3::new(60.0, 0.0, 0.0));
        let m = Robot::from_dh("2r", &mod_rows, DhConvention::Modified, tool).unwrap();
        for &(q1, q2) in &[(0.0, 0.0), (0.4, -1.1), (FRAC_PI_2, FRAC_PI_2)] {
            let hand = Vec3::new(
                100.0 * q1.cos() + 60.0 * (q1 + q2).cos(),
                100.0 * q1.sin() + 60.0 * (q1 + q2).sin(),
                0.0,
            );
            assert!((r.tcp_pose(&[q1, q2]).unwrap().translation() - hand).norm() < 1e-12);
            assert!((m.tcp_pose(&[q1, q2]).unwrap().translation() - hand).norm() < 1e-12);
        }
    }

    #[test]
    fn modified_twisted_axis_matches_definition() {
        // One modified row with α = 90°, a = 10, d = 5: joint axis is Rx(90°)·z = −y
        // through (10, 0, 0); a point at the link origin moves on a circle about it.
        let rows = [DhRow::degrees(0.0, 5.0, 10.0, 90.0)];
        let r = Robot::from_dh("m", &rows, DhConvention::Modified, Transform::IDENTITY).unwrap();
        let p0 = r.tcp_pose(&[0.0]).unwrap().translation();
        assert!((p0 - Vec3::new(10.0, -5.0, 0.0)).norm() < 1e-12);
        let p = r.tcp_pose(&[FRAC_PI_2]).unwrap().translation();
        // Rotating (0, −5, 0) relative to (10,0,0) by +90° about −y keeps it on −y.
        assert!((p - Vec3::new(10.0, -5.0, 0.0)).norm() < 1e-12);
        let r2 = Robot::from_dh(
            "m",
            &rows,
            DhConvention::Modified,
            Transform::from_translation(Vec3::new(1.0, 0.0, 0.0)),
        )
        .unwrap();
        // The tool x (world x at zero) turns by +90° about −y: x → +z.
        let p = r2.tcp_pose(&[FRAC_PI_2]).unwrap().translation();
        assert!((p - Vec3::new(10.0, -5.0, 1.0)).norm() < 1e-12, "{p}");
    }
}
