//! [`Joint`]: how a link moves relative to its parent (seed 001's `CSTLModel` pair type,
//! axis direction and axis position).

use crate::math::{Point3, Vec3};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion};

/// The kind of pair between a link and its parent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum JointKind {
    /// Rigidly attached: the link does not move relative to its parent.
    #[default]
    Fixed,
    /// Rotation about an axis line; the joint value is an angle in radians
    /// (right hand about the axis direction).
    Revolute,
    /// Translation along an axis direction; the joint value is a distance in mm.
    Prismatic,
}

impl JointKind {
    /// Whether the joint has a variable (revolute or prismatic).
    pub fn is_movable(self) -> bool {
        !matches!(self, JointKind::Fixed)
    }
}

/// The range a joint value may take: radians for revolute joints, millimetres for
/// prismatic joints; `min <= max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lowest allowed value (rad or mm).
    pub min: f64,
    /// Highest allowed value (rad or mm).
    pub max: f64,
}

impl JointLimits {
    /// Limits `min..=max` (rad or mm).
    pub fn new(min: f64, max: f64) -> Self {
        Self { min, max }
    }

    /// Symmetric limits `-half..=half`.
    pub fn symmetric(half: f64) -> Self {
        Self::new(-half, half)
    }

    /// Limits given in degrees, stored in radians.
    pub fn degrees(min: f64, max: f64) -> Self {
        Self::new(min.to_radians(), max.to_radians())
    }

    /// Whether `value` lies in the range, with a tolerance of `tol` (rad or mm).
    pub fn contains(&self, value: f64, tol: f64) -> bool {
        value >= self.min - tol && value <= self.max + tol
    }
}

/// The joint between a link and its parent, expressed in the **parent link's frame**.
///
/// At joint value `v` the link's pose in its parent frame is its home transform
/// followed by the joint motion: a rotation of `v` radians about the line through
/// `point` along `axis` (revolute) or a translation of `v` mm along `axis`
/// (prismatic). `axis` is stored normalised.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// Fixed, revolute or prismatic.
    pub kind: JointKind,
    /// Unit axis direction in the parent frame (unused for fixed joints).
    pub axis: Vec3,
    /// A point on the rotation axis in the parent frame, mm (revolute joints only).
    pub point: Point3,
    /// Allowed range of the joint value, if limited (rad or mm).
    pub limits: Option<JointLimits>,
}

impl Default for Joint {
    fn default() -> Self {
        Self::fixed()
    }
}

impl Joint {
    /// A rigid attachment.
    pub fn fixed() -> Self {
        Self {
            kind: JointKind::Fixed,
            axis: Vec3::z(),
            point: Point3::origin(),
            limits: None,
        }
    }

    /// A revolute joint about the line through `point` along `axis` (parent frame,
    /// mm). The axis is normalised; a zero or non-finite axis is rejected later by
    /// [`KinematicTree::new`](super::KinematicTree::new).
    pub fn revolute(axis: Vec3, point: Point3) -> Self {
        Self {
            kind: JointKind::Revolute,
            axis: normalised(axis),
            point,
            limits: None,
        }
    }

    /// A prismatic joint along `axis` (parent frame).
    pub fn prismatic(axis: Vec3) -> Self {
        Self {
            kind: JointKind::Prismatic,
            axis: normalised(axis),
            point: Point3::origin(),
            limits: None,
        }
    }

    /// The same joint with limits (rad or mm).
    #[must_use]
    pub fn with_limits(mut self, limits: JointLimits) -> Self {
        self.limits = Some(limits);
        self
    }

    /// The joint motion at value `v` in the parent frame (column-vector isometry).
    #[inline]
    pub(crate) fn motion(&self, v: f64) -> Isometry3<f64> {
        match self.kind {
            JointKind::Fixed => Isometry3::identity(),
            JointKind::Prismatic => Isometry3::from_parts(
                Translation3::from(self.axis * v),
                UnitQuaternion::identity(),
            ),
            JointKind::Revolute => {
                let q = UnitQuaternion::from_axis_angle(&Unit::new_unchecked(self.axis), v);
                let t = self.point.coords - q * self.point.coords;
                Isometry3::from_parts(Translation3::from(t), q)
            }
        }
    }
}

/// A joint driven by another (URDF `<mimic>`): its value is `multiplier · leader +
/// offset`, where `leader` is the leader link's joint value (rad or mm; the offset in
/// the follower's unit). A follower is not a free joint of its robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mimic {
    /// Index of the link whose joint leads (itself not a follower).
    pub leader: usize,
    /// Factor on the leader's value.
    pub multiplier: f64,
    /// Added to the product (rad or mm).
    pub offset: f64,
}

fn normalised(v: Vec3) -> Vec3 {
    let n = v.norm();
    if n > 0.0 && n.is_finite() {
        v / n
    } else {
        v
    }
}
