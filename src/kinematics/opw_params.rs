//! [`OpwParameters`]: the seven-number description of an ortho-parallel arm with a
//! spherical wrist (Brandstötter, Angerer, Hofbaur 2014), as published for many
//! industrial robots (`opw_kinematics`, ROS-Industrial `opw_parameters_*.yaml`), and
//! the one place where such a parameter set becomes a [`Robot`].

use super::{DescriptionProblem, Joint, JointLimits, KinematicTree, KinematicsError, Link, Robot};
use crate::math::{Point3, Transform, Vec3};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion};

/// An ortho-parallel arm in the `opw_kinematics` convention. Lengths in **mm**,
/// offsets in **radians**.
///
/// # Convention
/// In the *geometric* reference pose (every geometric angle 0) the arm stands upright
/// in the base frame: axis 1 is the base `z` axis, axis 2 is parallel to `y` at
/// `(a1, b, c1)`, axis 3 parallel to `y` at `(a1, b, c1 + c2)`, the wrist centre at
/// `(a1 + a2, b, c1 + c2 + c3)` with axes 4 and 6 along `z` and axis 5 along `y`; the
/// flange is `c4` above the wrist centre with its frame parallel to the base frame
/// (`z` out of the flange). Axes 2, 3 and 5 turn about `+y`, axes 1, 4 and 6 about
/// `+z` (right hand).
///
/// A controller joint value `qᵢ` gives the geometric angle
/// **`θᵢ = signᵢ·qᵢ − offsetᵢ`** (`opw_kinematics`' `forward`: `q[i]·sign_corrections[i]
/// − offsets[i]`). For example the ABB IRB 2400 has `offsets[2] = −π/2`: at `q = 0`
/// its forearm is horizontal (θ₃ = +π/2) and the flange sits at (940, 0, 1455) mm
/// pointing along `+x`.
///
/// # Examples
/// ```
/// use fitup::kinematics::OpwParameters;
/// use fitup::math::Vec3;
/// // ABB IRB 2400/10 (opw_kinematics `makeIrb2400_10`, metres there, mm here).
/// let mut p = OpwParameters::new(100.0, -135.0, 0.0, 615.0, 705.0, 755.0, 85.0);
/// p.offsets[2] = -std::f64::consts::FRAC_PI_2;
/// let irb = p.robot("irb2400", [None; 6]).unwrap();
/// let flange = irb.tcp_pose(&[0.0; 6]).unwrap();
/// assert!((flange.translation() - Vec3::new(940.0, 0.0, 1455.0)).norm() < 1e-9);
/// assert!(irb.analytic().is_some()); // closed-form IK
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpwParameters {
    /// Shoulder offset along x from axis 1 to axis 2 (mm).
    pub a1: f64,
    /// Elbow offset along x from axis 3 to the wrist centre, upright pose (mm).
    pub a2: f64,
    /// Lateral offset along y of axes 2/3 and the wrist (mm).
    pub b: f64,
    /// Height of axis 2 above the base (mm).
    pub c1: f64,
    /// Upper-arm length, axis 2 to axis 3 (mm).
    pub c2: f64,
    /// Forearm length, axis 3 to the wrist centre (mm).
    pub c3: f64,
    /// Wrist centre to flange (mm).
    pub c4: f64,
    /// Joint offsets (rad): `θ = sign·q − offset`.
    pub offsets: [f64; 6],
    /// Joint direction signs (±1).
    pub signs: [f64; 6],
}

impl OpwParameters {
    /// The names of the seven lengths, in the order of [`lengths`](Self::lengths).
    const LENGTH_NAMES: [&str; 7] = ["a1", "a2", "b", "c1", "c2", "c3", "c4"];

    /// Parameters with zero offsets and positive signs (lengths in mm).
    pub fn new(a1: f64, a2: f64, b: f64, c1: f64, c2: f64, c3: f64, c4: f64) -> Self {
        Self {
            a1,
            a2,
            b,
            c1,
            c2,
            c3,
            c4,
            offsets: [0.0; 6],
            signs: [1.0; 6],
        }
    }

    /// The seven lengths in the order of [`LENGTH_NAMES`](Self::LENGTH_NAMES) (mm).
    fn lengths(&self) -> [f64; 7] {
        [self.a1, self.a2, self.b, self.c1, self.c2, self.c3, self.c4]
    }

    /// Checks that every number is finite, every sign is ±1 and the arm has an upper
    /// arm and a forearm.
    pub fn validate(&self) -> Result<(), KinematicsError> {
        let bad = |what: DescriptionProblem| Err(KinematicsError::InvalidDescription(what));
        for (name, v) in Self::LENGTH_NAMES.into_iter().zip(self.lengths()) {
            if !v.is_finite() {
                return bad(DescriptionProblem::OpwLength { name, value: v });
            }
        }
        for (i, o) in self.offsets.iter().enumerate() {
            if !o.is_finite() {
                return bad(DescriptionProblem::OpwOffset { joint: i + 1 });
            }
        }
        for (i, s) in self.signs.iter().enumerate() {
            if *s != 1.0 && *s != -1.0 {
                return bad(DescriptionProblem::OpwSign {
                    joint: i + 1,
                    sign: *s,
                });
            }
        }
        if self.c2 <= 0.0 {
            return bad(DescriptionProblem::OpwUpperArm { c2: self.c2 });
        }
        if self.a2.hypot(self.c3) <= 0.0 {
            return bad(DescriptionProblem::OpwForearm);
        }
        Ok(())
    }

    /// The robot (base at the origin, tool at the flange): a kinematic tree whose link
    /// frames all coincide with the base frame at `q = 0` (how CAD assemblies of robots
    /// are usually drawn), axes placed from the parameters, flange frame as in the
    /// convention above. Joint `i` turns about `signᵢ·axisᵢ`, so a joint value `q`
    /// means the geometric angle `sign·q − offset`.
    pub fn robot(
        &self,
        name: &str,
        limits: [Option<JointLimits>; 6],
    ) -> Result<Robot, KinematicsError> {
        self.validate()?;
        let [a1, a2, b, c1, c2, c3, c4] = self.lengths();
        let (offsets, signs) = (self.offsets, self.signs);
        // Axis lines in the geometric reference pose (every geometric angle 0).
        let mut axes: Vec<(Vec3, Point3)> = vec![
            (Vec3::z(), Point3::origin()),
            (Vec3::y(), Point3::new(a1, b, c1)),
            (Vec3::y(), Point3::new(a1, b, c1 + c2)),
            (Vec3::z(), Point3::new(a1 + a2, b, c1 + c2 + c3)),
            (Vec3::y(), Point3::new(a1 + a2, b, c1 + c2 + c3)),
            (Vec3::z(), Point3::new(a1 + a2, b, c1 + c2 + c3)),
        ];
        let mut flange = Isometry3::translation(a1 + a2, b, c1 + c2 + c3 + c4);
        // q = 0 means θ = −offset: turn each joint by −offset, moving everything
        // distal to it (axes after it and the flange).
        for i in 0..6 {
            let theta = -offsets[i];
            if theta != 0.0 {
                let (axis, point) = axes[i];
                let r = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), theta);
                let m =
                    Isometry3::from_parts(Translation3::from(point.coords - r * point.coords), r);
                for ax in axes.iter_mut().skip(i + 1) {
                    *ax = (m.rotation * ax.0, m * ax.1);
                }
                flange = m * flange;
            }
        }
        let mut links = vec![Link::new("base", None, Transform::IDENTITY, Joint::fixed())];
        for i in 0..6 {
            let (axis, point) = axes[i];
            let home = if i == 5 {
                Transform::from_isometry(flange)
            } else {
                Transform::IDENTITY
            };
            let mut joint = Joint::revolute(axis * signs[i], point);
            joint.limits = limits[i];
            links.push(Link::new(format!("link{}", i + 1), Some(i), home, joint));
        }
        let tree = KinematicTree::new(links)?;
        Robot::new(name, tree, 6, Transform::IDENTITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn invalid_parameters_are_rejected() {
        let mut p = OpwParameters::new(100.0, -135.0, 0.0, 615.0, 705.0, 755.0, 85.0);
        assert!(p.robot("ok", [None; 6]).is_ok());
        p.c1 = f64::NAN;
        assert!(p.robot("nan", [None; 6]).is_err());
        p.c1 = 615.0;
        p.signs[3] = 0.5;
        assert!(p.robot("sign", [None; 6]).is_err());
        p.signs[3] = 1.0;
        p.offsets[1] = f64::INFINITY;
        assert!(p.robot("offset", [None; 6]).is_err());
    }

    /// θ = s·q − offset: an offset of −π/2 on joint 3 lays the forearm forward at q = 0,
    /// and q₃ = −π/2 stands it back up (θ₃ = 0).
    #[test]
    fn offset_sign_convention() {
        let mut p = OpwParameters::new(100.0, -135.0, 0.0, 615.0, 705.0, 755.0, 85.0);
        p.offsets[2] = -FRAC_PI_2;
        let r = p.robot("irb", [None; 6]).unwrap();
        let at = |q: [f64; 6]| r.tcp_pose(&q).unwrap().translation();
        assert!((at([0.0; 6]) - Vec3::new(940.0, 0.0, 1455.0)).norm() < 1e-9);
        let up = at([0.0, 0.0, -FRAC_PI_2, 0.0, 0.0, 0.0]);
        assert!((up - Vec3::new(-35.0, 0.0, 2160.0)).norm() < 1e-9, "{up:?}");
    }
}
