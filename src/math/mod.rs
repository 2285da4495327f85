//! Rigid transforms and angle conventions: the pose matrix of the SolidWorks API
//! (`IMathTransform`) on top of nalgebra.
//!
//! Units: millimetres for lengths, radians for angles (degrees only in the
//! user-facing `X Y Z A B C` pose triples, see [`AngleConvention`]).

mod aabb;
mod euler;
pub mod format;
mod rng;
pub mod transform;

pub use aabb::Aabb;
pub use euler::AngleConvention;
pub use rng::Rng;
pub use transform::Transform;

/// A point or free vector in millimetres.
pub type Vec3 = nalgebra::Vector3<f64>;
/// A point in millimetres.
pub type Point3 = nalgebra::Point3<f64>;
