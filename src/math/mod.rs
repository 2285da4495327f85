//! Rigid transforms and angle conventions: the pose matrix of the SolidWorks API
//! (`IMathTransform`) on top of nalgebra; axis-aligned boxes; the shared limits of
//! every call (number ranges, sample counts, the [`Deadline`] of a time budget).
//!
//! Units: millimetres for lengths, radians for angles (degrees only in the
//! user-facing `X Y Z A B C` pose triples, see [`AngleConvention`]).

mod aabb;
pub mod deadline;
mod euler;
pub mod format;
pub mod limits;
mod rng;
pub mod transform;
pub(crate) mod trig;

pub use aabb::Aabb;
pub use deadline::Deadline;
pub use euler::AngleConvention;
pub use limits::{LimitError, SampleBudget, MAX_ABS_VALUE, MAX_SAMPLES};
pub use rng::Rng;
pub use transform::Transform;

/// A point or free vector in millimetres.
pub type Vec3 = nalgebra::Vector3<f64>;
/// A point in millimetres.
pub type Point3 = nalgebra::Point3<f64>;

/// The smallest rotation taking the direction `from` onto the direction `to` (any
/// axis perpendicular to `from` when they are opposite). Frame-free: both vectors in
/// the same frame, the rotation in that frame.
pub fn rotation_between(from: &Vec3, to: &Vec3) -> nalgebra::UnitQuaternion<f64> {
    nalgebra::UnitQuaternion::rotation_between(from, to).unwrap_or_else(|| {
        let perp = if from.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        nalgebra::UnitQuaternion::from_axis_angle(
            &nalgebra::Unit::new_normalize(from.cross(&perp)),
            std::f64::consts::PI,
        )
    })
}
