//! Reference geometry of parts (planes, axes, points) and its world placement.

use crate::math::{Point3, Transform, Vec3};

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
        }
    }

    /// A point of the entity (mm).
    pub fn anchor(&self) -> Point3 {
        match *self {
            Reference::Plane { point, .. }
            | Reference::Axis { point, .. }
            | Reference::Point(point) => point,
        }
    }

    /// The normal of a plane or direction of an axis; `None` for a point.
    pub fn direction(&self) -> Option<Vec3> {
        match *self {
            Reference::Plane { normal, .. } => Some(normal),
            Reference::Axis { direction, .. } => Some(direction),
            Reference::Point(_) => None,
        }
    }

    /// `plane`, `axis` or `point`, for messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Reference::Plane { .. } => "plane",
            Reference::Axis { .. } => "axis",
            Reference::Point(_) => "point",
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
