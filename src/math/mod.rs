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

/// A unit vector perpendicular to the direction `d`, chosen stably (`d × X`, or
/// `d × Y` when `d` is nearly along X). Deterministic: the same `d` gives the same vector.
pub fn perpendicular(d: &Vec3) -> Vec3 {
    let helper = if d.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    d.cross(&helper).normalize()
}

/// Two directions across the unit direction `d`: `u` = [`perpendicular`]`(d)` and
/// `v = d × u`, so that `(u, v, d)` is a right-handed orthonormal frame.
pub fn frame_across(d: &Vec3) -> (Vec3, Vec3) {
    let u = perpendicular(d);
    (u, d.cross(&u))
}

/// The six axis directions: +X, -X, +Y, -Y, +Z, -Z.
pub fn axis_directions() -> [Vec3; 6] {
    [
        Vec3::x(),
        -Vec3::x(),
        Vec3::y(),
        -Vec3::y(),
        Vec3::z(),
        -Vec3::z(),
    ]
}

/// `n` unit directions spread evenly over the sphere (a Fibonacci lattice, from near
/// +Z to near -Z).
pub fn sphere_lattice(n: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * i as f64;
            Vec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

/// The smallest rotation taking the direction `from` onto the direction `to` (any
/// axis perpendicular to `from` when they are opposite). Frame-free: both vectors in
/// the same frame, the rotation in that frame.
pub fn rotation_between(from: &Vec3, to: &Vec3) -> nalgebra::UnitQuaternion<f64> {
    nalgebra::UnitQuaternion::rotation_between(from, to).unwrap_or_else(|| {
        nalgebra::UnitQuaternion::from_axis_angle(
            &nalgebra::Unit::new_unchecked(perpendicular(from)),
            std::f64::consts::PI,
        )
    })
}
