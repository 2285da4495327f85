//! The two `X Y Z A B C` angle conventions used by the seed systems.

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

/// How the three angles `A B C` of a pose triple `X Y Z A B C` build a rotation.
///
/// Both conventions describe the same family of matrices; they differ in which angle
/// is written first. Angles in the public API are degrees; this enum works in radians.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum AngleConvention {
    /// Seed 000 (SolidWorks cell): `A` about the fixed X axis, then `B` about the fixed
    /// Y axis, then `C` about the fixed Z axis: `R = Rz(C) · Ry(B) · Rx(A)`.
    /// This is the default everywhere in fitup.
    #[default]
    XyzFixed,
    /// Seed 001 (drilling robot): rotate about Z by `A` (α), then about the new Y by `B`
    /// (β), then about the new X by `C` (γ): `R = Rz(A) · Ry(B) · Rx(C)`.
    ZyxMoving,
}

impl AngleConvention {
    /// Parses `"xyz"`/`"xyz_fixed"` or `"zyx"`/`"zyx_moving"` (case-insensitive).
    pub fn parse(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "xyz" | "xyz_fixed" | "xyzfixed" => Some(Self::XyzFixed),
            "zyx" | "zyx_moving" | "zyxmoving" => Some(Self::ZyxMoving),
            _ => None,
        }
    }

    /// The rotation for angles `(a, b, c)` in radians.
    pub fn rotation(self, a: f64, b: f64, c: f64) -> UnitQuaternion<f64> {
        let (rx, ry, rz) = match self {
            Self::XyzFixed => (a, b, c),
            Self::ZyxMoving => (c, b, a),
        };
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rz)
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), ry)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), rx)
    }

    /// The angles `(a, b, c)` in radians of a rotation; `b` lies in `[-π/2, π/2]`.
    /// At `|b| = π/2` (gimbal lock) the X angle is set to 0.
    pub fn angles(self, rotation: &UnitQuaternion<f64>) -> (f64, f64, f64) {
        let m: Rotation3<f64> = rotation.to_rotation_matrix();
        let m = m.matrix();
        // R = Rz(rz) Ry(ry) Rx(rx): m[(2,0)] = -sin(ry).
        // atan2 keeps full precision near ±π/2, where asin loses half the digits.
        let cy = m[(0, 0)].hypot(m[(1, 0)]);
        let ry = (-m[(2, 0)]).atan2(cy);
        let (rx, rz) = if cy > 1e-12 {
            (m[(2, 1)].atan2(m[(2, 2)]), m[(1, 0)].atan2(m[(0, 0)]))
        } else {
            // Gimbal lock: only rz ∓ rx is defined; put it all on rz.
            (0.0, (-m[(0, 1)]).atan2(m[(1, 1)]))
        };
        match self {
            Self::XyzFixed => (rx, ry, rz),
            Self::ZyxMoving => (rz, ry, rx),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_round_trip_both_conventions() {
        for conv in [AngleConvention::XyzFixed, AngleConvention::ZyxMoving] {
            for &(a, b, c) in &[(0.1, 0.2, 0.3), (-2.0, 1.2, 3.0), (3.1, -1.5, -0.7)] {
                let q = conv.rotation(a, b, c);
                let (a2, b2, c2) = conv.angles(&q);
                let q2 = conv.rotation(a2, b2, c2);
                assert!(q.angle_to(&q2) < 1e-12, "{conv:?} {a} {b} {c}");
                assert!((a - a2).abs() < 1e-12 && (b - b2).abs() < 1e-12 && (c - c2).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn gimbal_lock_still_reproduces_rotation() {
        let conv = AngleConvention::XyzFixed;
        let q = conv.rotation(0.4, std::f64::consts::FRAC_PI_2, 0.9);
        let (a, b, c) = conv.angles(&q);
        assert!(q.angle_to(&conv.rotation(a, b, c)) < 1e-9);
    }

    #[test]
    fn conventions_differ_only_in_order() {
        let q1 = AngleConvention::XyzFixed.rotation(0.1, 0.2, 0.3);
        let q2 = AngleConvention::ZyxMoving.rotation(0.3, 0.2, 0.1);
        assert!(q1.angle_to(&q2) < 1e-15);
    }
}
