//! [`PlanningSpace`]: where the component may go, how it may turn, and how far apart
//! two poses are.

use super::run::PlanError;
use crate::math::{AngleConvention, Rng, Transform, Vec3};
use nalgebra::UnitQuaternion;

/// Which orientations the moving component may take.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum RotationFreedom {
    /// The orientation stays that of the start pose (translation-only planning).
    Fixed,
    /// Any orientation.
    Free,
    /// Rotations about the enabled fixed axes of the assembly frame, relative to the
    /// start orientation: `R = Rz(c)·Ry(b)·Rx(a)·R_start` with each enabled angle in
    /// `[-max_angle, max_angle]` (rad) and the disabled ones 0.
    Axes {
        /// Rotation about X allowed.
        x: bool,
        /// Rotation about Y allowed.
        y: bool,
        /// Rotation about Z allowed.
        z: bool,
        /// Largest angle about each enabled axis (rad, in `(0, π]`).
        max_angle: f64,
    },
}

/// The configuration space of one moving component.
///
/// # Bounds
/// `min`/`max` bound the **translation** of the pose (the component's origin in the
/// assembly frame, mm). A good default is the assembly's bounding box grown by the
/// component's size plus a margin.
///
/// # Metric
/// The distance between two poses is `|Δt| + rotation_weight · θ` (mm), with `θ` the
/// rotation angle between them (rad). `rotation_weight` (mm/rad) is a characteristic
/// length of the component, typically the radius of its bounding sphere about its
/// origin: turning by `θ` then moves its farthest point by about as much as the
/// weighted term says.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanningSpace {
    /// Lower corner of the translation box (mm).
    pub min: Vec3,
    /// Upper corner of the translation box (mm).
    pub max: Vec3,
    /// Which orientations are allowed.
    pub rotation: RotationFreedom,
    /// mm per rad in the metric (see the type docs). Default 50.
    pub rotation_weight: f64,
}

impl PlanningSpace {
    /// A space with translation box `min..max` (mm), free rotation and a rotation
    /// weight of 50 mm/rad.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self {
            min,
            max,
            rotation: RotationFreedom::Free,
            rotation_weight: 50.0,
        }
    }

    /// The same space with `rotation` freedom.
    #[must_use]
    pub fn with_rotation(mut self, rotation: RotationFreedom) -> Self {
        self.rotation = rotation;
        self
    }

    /// The same space with the metric's rotation weight `mm_per_rad`.
    #[must_use]
    pub fn with_rotation_weight(mut self, mm_per_rad: f64) -> Self {
        self.rotation_weight = mm_per_rad;
        self
    }

    /// Checks the box is finite and non-empty and the weight positive.
    pub fn validate(&self) -> Result<(), PlanError> {
        for i in 0..3 {
            let (lo, hi) = (self.min[i], self.max[i]);
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(PlanError::invalid(
                    "bounds",
                    format!("{lo}..{hi}"),
                    "finite numbers",
                ));
            }
            if lo >= hi {
                return Err(PlanError::invalid(
                    "bounds",
                    format!("{}: {lo}..{hi}", ["x", "y", "z"][i]),
                    "min < max on every axis (the box is empty or inverted)",
                ));
            }
        }
        PlanError::positive("rotation_weight", self.rotation_weight)?;
        if let RotationFreedom::Axes { max_angle, .. } = self.rotation {
            if !(max_angle > 0.0 && max_angle <= std::f64::consts::PI) {
                return Err(PlanError::invalid(
                    "rotation.max_angle",
                    max_angle.to_string(),
                    "an angle in (0, π] rad",
                ));
            }
        }
        Ok(())
    }

    /// The metric distance between two poses (mm, see the type docs).
    pub fn distance(&self, a: &Transform, b: &Transform) -> f64 {
        let (angle, d) = a.distance_to(b);
        d + self.rotation_weight * angle
    }

    /// The metric length of a polyline of poses (mm).
    pub fn distance_along(&self, poses: &[Transform]) -> f64 {
        poses.windows(2).map(|w| self.distance(&w[0], &w[1])).sum()
    }

    /// Whether `pose` lies in the box and has an allowed orientation, orientations
    /// being relative to `reference` (the start orientation).
    pub fn contains(&self, pose: &Transform, reference: &UnitQuaternion<f64>) -> bool {
        let t = pose.translation();
        if !(0..3).all(|i| t[i] >= self.min[i] && t[i] <= self.max[i]) {
            return false;
        }
        self.orientation_allowed(&pose.rotation(), reference)
    }

    /// Whether orientation `q` is allowed relative to `reference`.
    pub fn orientation_allowed(
        &self,
        q: &UnitQuaternion<f64>,
        reference: &UnitQuaternion<f64>,
    ) -> bool {
        const TOL: f64 = 1e-9;
        match self.rotation {
            RotationFreedom::Free => true,
            RotationFreedom::Fixed => q.angle_to(reference) <= 1e-7,
            RotationFreedom::Axes { x, y, z, max_angle } => {
                let rel = q * reference.inverse();
                let (a, b, c) = AngleConvention::XyzFixed.angles(&rel);
                [(x, a), (y, b), (z, c)].iter().all(|&(on, ang)| {
                    if on {
                        ang.abs() <= max_angle + TOL
                    } else {
                        ang.abs() <= 1e-7
                    }
                })
            }
        }
    }

    /// Whether rotating about world axis `axis` (0 = X, 1 = Y, 2 = Z) can be allowed.
    pub(crate) fn axis_enabled(&self, axis: usize) -> bool {
        match self.rotation {
            RotationFreedom::Free => true,
            RotationFreedom::Fixed => false,
            RotationFreedom::Axes { x, y, z, .. } => [x, y, z][axis.min(2)],
        }
    }

    /// Draws a pose uniformly: translation uniform in the box, orientation uniform
    /// over the allowed set (relative to `reference`).
    pub fn sample(&self, rng: &mut Rng, reference: &UnitQuaternion<f64>) -> Transform {
        let t = self.sample_translation(rng);
        let q = match self.rotation {
            RotationFreedom::Fixed => *reference,
            RotationFreedom::Free => rng.rotation(),
            RotationFreedom::Axes { x, y, z, max_angle } => {
                let mut angle = |on: bool| {
                    if on {
                        rng.range(-max_angle, max_angle)
                    } else {
                        0.0
                    }
                };
                let (a, b, c) = (angle(x), angle(y), angle(z));
                AngleConvention::XyzFixed.rotation(a, b, c) * reference
            }
        };
        Transform::from_parts(t, q)
    }

    /// A translation uniform in the box (mm), drawn from `rng` as
    /// [`sample`](Self::sample) draws it.
    pub(crate) fn sample_translation(&self, rng: &mut Rng) -> Vec3 {
        Vec3::new(
            rng.range(self.min.x, self.max.x),
            rng.range(self.min.y, self.max.y),
            rng.range(self.min.z, self.max.z),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stay_in_the_space() {
        let reference = UnitQuaternion::from_euler_angles(0.3, 0.2, 0.1);
        let mut rng = Rng::new(3);
        for rotation in [
            RotationFreedom::Fixed,
            RotationFreedom::Free,
            RotationFreedom::Axes {
                x: false,
                y: true,
                z: true,
                max_angle: 0.5,
            },
        ] {
            let space = PlanningSpace::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 5.0, 3.0))
                .with_rotation(rotation);
            space.validate().unwrap();
            for _ in 0..200 {
                let p = space.sample(&mut rng, &reference);
                assert!(space.contains(&p, &reference), "{rotation:?}: {p}");
            }
        }
    }

    #[test]
    fn rejects_bad_boxes_and_weights() {
        let s = PlanningSpace::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 1.0));
        assert!(s.validate().unwrap_err().to_string().contains("empty"));
        let s = PlanningSpace::new(Vec3::new(0.0, f64::NAN, 0.0), Vec3::new(1.0, 1.0, 1.0));
        assert!(s.validate().is_err());
        let s = PlanningSpace::new(Vec3::zeros(), Vec3::repeat(1.0)).with_rotation_weight(0.0);
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("rotation_weight"));
    }
}
