//! Reference geometry of parts (planes, axes, points) and its world placement.

use crate::math::{Point3, Transform, Vec3};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};

/// How far from perpendicular (|cos| of the angle) a coordinate system's X and Y axes
/// may be: numbers written with 6 or more significant digits.
pub const MAX_AXES_COS: f64 = 1e-6;

/// Why an origin and two axes are not a coordinate system.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CoordinateSystemError {
    /// A number is NaN, infinite or larger than the document allows.
    #[error("its numbers must be finite and at most 1e9")]
    NotFinite,
    /// An axis has zero length.
    #[error("its {0} axis has zero length")]
    ZeroAxis(&'static str),
    /// X and Y are not perpendicular.
    #[error("its X and Y axes are not perpendicular (cos {0:.2e}, more than 1e-6)")]
    NotPerpendicular(f64),
}

/// The pose of a coordinate system from its origin and its X and Y axes (Z = X × Y),
/// axes normalised.
pub fn coordinate_system(
    origin: Vec3,
    x: Vec3,
    y: Vec3,
) -> Result<Transform, CoordinateSystemError> {
    let finite = |v: &Vec3| {
        v.iter()
            .all(|c| c.is_finite() && c.abs() <= super::MAX_ABS_VALUE)
    };
    if !(finite(&origin) && finite(&x) && finite(&y)) {
        return Err(CoordinateSystemError::NotFinite);
    }
    let x = x
        .try_normalize(1e-12)
        .ok_or(CoordinateSystemError::ZeroAxis("X"))?;
    let y = y
        .try_normalize(1e-12)
        .ok_or(CoordinateSystemError::ZeroAxis("Y"))?;
    let cos = x.dot(&y);
    if cos.abs() > MAX_AXES_COS {
        return Err(CoordinateSystemError::NotPerpendicular(cos));
    }
    // Gram-Schmidt removes what rounding left.
    let y = (y - x * cos).normalize();
    let z = x.cross(&y);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    Ok(Transform::from_parts(
        origin,
        UnitQuaternion::from_rotation_matrix(&r),
    ))
}

/// A reference entity in a part frame (mm), or in the world once posed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reference {
    /// A plane through `point` with unit `normal`.
    Plane {
        /// A point on the plane, mm.
        point: Point3,
        /// Unit normal.
        normal: Vec3,
    },
    /// A line through `point` along unit `direction`.
    Axis {
        /// A point on the axis, mm.
        point: Point3,
        /// Unit direction.
        direction: Vec3,
    },
    /// A point, mm.
    Point(Point3),
    /// A coordinate system (SolidWorks' `CoordSys` feature): the pose that maps
    /// coordinates in the system to the part frame (its origin and axes; mm), as
    /// `CoordinateSystemFeatureData.Transform`.
    CoordinateSystem(Transform),
}

impl Reference {
    /// The entity moved by the component pose `t` (part frame → world).
    pub fn posed(&self, t: &Transform) -> Reference {
        match *self {
            Reference::Plane { point, normal } => Reference::Plane {
                point: t.apply(&point),
                normal: t.apply_vector(&normal),
            },
            Reference::Axis { point, direction } => Reference::Axis {
                point: t.apply(&point),
                direction: t.apply_vector(&direction),
            },
            Reference::Point(p) => Reference::Point(t.apply(&p)),
            Reference::CoordinateSystem(f) => Reference::CoordinateSystem(f * *t),
        }
    }

    /// A point of the entity (mm).
    pub fn anchor(&self) -> Point3 {
        match *self {
            Reference::Plane { point, .. }
            | Reference::Axis { point, .. }
            | Reference::Point(point) => point,
            Reference::CoordinateSystem(f) => f.translation().into(),
        }
    }

    /// The normal of a plane or direction of an axis; `None` for a point or a
    /// coordinate system.
    pub fn direction(&self) -> Option<Vec3> {
        match *self {
            Reference::Plane { normal, .. } => Some(normal),
            Reference::Axis { direction, .. } => Some(direction),
            Reference::Point(_) | Reference::CoordinateSystem(_) => None,
        }
    }

    /// The pose of a coordinate system (system → part frame, or → world once posed);
    /// `None` for the other references.
    pub fn coordinate_system(&self) -> Option<Transform> {
        match *self {
            Reference::CoordinateSystem(f) => Some(f),
            _ => None,
        }
    }

    /// `plane`, `axis`, `point` or `coordinate_system` (the scripts' `type`), for
    /// messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Reference::Plane { .. } => "plane",
            Reference::Axis { .. } => "axis",
            Reference::Point(_) => "point",
            Reference::CoordinateSystem(_) => "coordinate_system",
        }
    }

    /// The references every part has without declaring them, named as in SolidWorks:
    /// `origin`, the planes `front` (XY, normal +Z), `top` (XZ, normal +Y) and `right`
    /// (YZ, normal +X), and the axes `x_axis`, `y_axis`, `z_axis`.
    pub fn builtin(name: &str) -> Option<Reference> {
        let o = Point3::origin();
        Some(match name {
            "origin" => Reference::Point(o),
            "front" => Reference::Plane {
                point: o,
                normal: Vec3::z(),
            },
            "top" => Reference::Plane {
                point: o,
                normal: Vec3::y(),
            },
            "right" => Reference::Plane {
                point: o,
                normal: Vec3::x(),
            },
            "x_axis" => Reference::Axis {
                point: o,
                direction: Vec3::x(),
            },
            "y_axis" => Reference::Axis {
                point: o,
                direction: Vec3::y(),
            },
            "z_axis" => Reference::Axis {
                point: o,
                direction: Vec3::z(),
            },
            _ => return None,
        })
    }

    /// Names of the built-in references.
    pub const BUILTIN_NAMES: [&'static str; 7] = [
        "origin", "front", "top", "right", "x_axis", "y_axis", "z_axis",
    ];
}
