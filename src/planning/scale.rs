//! [`ProblemScale`]: the lengths of one planning problem that fitup's scale-free
//! defaults derive from, so that the same defaults serve a 20 mm peg in a bore and
//! a table carried through a 700 mm house.

use super::space::PlanningSpace;

/// The characteristic lengths of a planning problem (mm).
///
/// Every length default of the default planner ([`rrt_connect`](super::rrt_connect)
/// with `step: None`) is a multiple of one of these, never an absolute number of
/// millimetres: scaling a problem (meshes, poses, bounds) by `k` scales every
/// derived length by `k`, so the search draws the same numbers and makes the same
/// moves, and finds the same path scaled by `k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProblemScale {
    /// Diagonal of the translation bounds (mm).
    pub extent: f64,
    /// Radius of the moving part about its own origin (mm): how far its farthest
    /// point moves per radian of rotation. The validator's
    /// [`part_radius`](super::MotionValidator::part_radius), or the space's
    /// rotation weight when the validator knows no part.
    pub part_radius: f64,
    /// The moving part's thinnest extent (mm): the smallest side of its box in its
    /// own frame ([`part_thickness`](super::MotionValidator::part_thickness)), or
    /// its radius when the validator knows no part.
    pub part_thickness: f64,
    /// The space's rotation weight (mm per rad).
    pub rotation_weight: f64,
}

impl ProblemScale {
    /// Share of the [metric extent](Self::metric_extent) the long-range search
    /// extends by at most. OMPL's RRT-Connect takes 0.2 of its space's extent,
    /// but fitup's metric extent also counts half a turn at the part's radius, so
    /// the same share is a longer reach; on OMPL.app's Home, Apartment and cubicles
    /// 0.1 needed 1.9–3.7× fewer pose checks (median of 5 seeds) than 0.2, and
    /// 0.05 or 0.07 no fewer than 0.1 (docs/planning.md).
    pub const RANGE_SHARE: f64 = 0.1;

    /// Share of the [range](Self::range) the long-range search's adaptive reach
    /// halves down to at most: a node whose extensions are blocked halves its
    /// reach after each (a twisting corridor, a cluttered corner), one whose
    /// extension goes through doubles it back (open space). On OMPL.app's
    /// spirelli, whose corridors are narrow against the space, a fixed range
    /// needed 763k pose checks (seed 1) and a quarter of it 193k; adapting down
    /// to a quarter needed 189k–253k (seeds 1–3) and cut the median on Home,
    /// Abstract and Apartment by 1.2–1.5×, at 1.4× more on cubicles
    /// (docs/planning.md).
    pub const REACH_FLOOR_SHARE: f64 = 0.25;

    /// Share of the metric extent between two poses the long-range search explores
    /// an edge with (lazily: pose checks that far apart, the path certified by the
    /// validator's own edge check): OMPL's default state-validity resolution, 1 %.
    pub const RESOLUTION_SHARE: f64 = 0.01;

    /// Share of the part's thickness the narrow-passage search extends by: a step
    /// below the width of a passage keeps extensions inside it, and a passage is at
    /// least as wide as the part is thin. On issue 23's puzzles (parts 3–8 mm
    /// thick) this is 1.5–4 mm, about the 3 mm step their measures were tuned
    /// with.
    pub const NARROW_STEP_SHARE: f64 = 0.5;

    /// Share of the space's rotation weight (the part's radius, mm per rad) the
    /// long-range search's metric weighs a turn by when it picks the nearest node
    /// and steers toward a sample: turning is cheap against crossing a room, so
    /// extensions reach a sample's orientation in fewer steps. Only the metric of
    /// the search changes: its range, reach floor and the rotation resolution its
    /// edges are explored at stay those of the space's weight. On OMPL.app's
    /// problems (20 seeds, 2026-12-06) a quarter took the median from 1.26 s to
    /// 0.72 s on alpha-1.5, 1.11 s to 0.75 s on Home, 0.85 s to 0.66 s on
    /// Twistycool and, 5 seeds, 7.1 s to 2.7 s on spirelli, with the others
    /// within noise; a half or a tenth helped less (docs/planning.md). OMPL's SE(3)
    /// metric weighs half the turn angle against the scene's units, which is
    /// nearly nothing in a scene hundreds of units wide.
    pub const LONG_RANGE_ROTATION_SHARE: f64 = 0.25;

    /// The scale of `space` for a moving part of radius `part_radius` and thinnest
    /// extent `part_thickness` (mm; `None` or not a finite number > 0: the space's
    /// rotation weight stands for the radius, the radius for the thickness).
    pub fn new(
        space: &PlanningSpace,
        part_radius: Option<f64>,
        part_thickness: Option<f64>,
    ) -> Self {
        let extent = (space.max - space.min).norm();
        let positive = |x: Option<f64>| x.filter(|r| r.is_finite() && *r > 0.0);
        let part_radius = positive(part_radius).unwrap_or(space.rotation_weight);
        Self {
            extent,
            part_radius,
            part_thickness: positive(part_thickness).unwrap_or(part_radius),
            rotation_weight: space.rotation_weight,
        }
    }

    /// The scale of `space` for the part `validator` moves.
    pub fn of(space: &PlanningSpace, validator: &dyn super::MotionValidator) -> Self {
        Self::new(space, validator.part_radius(), validator.part_thickness())
    }

    /// The largest metric distance between two poses of the space (mm): the
    /// bounds' diagonal plus half a turn weighted by the rotation weight.
    pub fn metric_extent(&self) -> f64 {
        self.extent + self.rotation_weight * std::f64::consts::PI
    }

    /// The long-range search's extension (metric mm): [`RANGE_SHARE`](Self::RANGE_SHARE)
    /// of the metric extent.
    pub fn range(&self) -> f64 {
        Self::RANGE_SHARE * self.metric_extent()
    }

    /// The shortest extension of the long-range search's adaptive reach (metric
    /// mm): [`REACH_FLOOR_SHARE`](Self::REACH_FLOOR_SHARE) of the range.
    pub fn reach_floor(&self) -> f64 {
        Self::REACH_FLOOR_SHARE * self.range()
    }

    /// The long-range search's exploration resolution (metric mm):
    /// [`RESOLUTION_SHARE`](Self::RESOLUTION_SHARE) of the metric extent, at most
    /// a quarter of the part's radius (a part small against its space must not
    /// jump over thin walls between two checks it would then only find when the
    /// path is certified).
    pub fn resolution(&self) -> f64 {
        (Self::RESOLUTION_SHARE * self.metric_extent()).min(0.25 * self.part_radius)
    }

    /// The rotation weight of the long-range search's metric (mm per rad):
    /// [`LONG_RANGE_ROTATION_SHARE`](Self::LONG_RANGE_ROTATION_SHARE) of the
    /// space's.
    pub fn long_range_rotation_weight(&self) -> f64 {
        Self::LONG_RANGE_ROTATION_SHARE * self.rotation_weight
    }

    /// The narrow-passage search's extension (metric mm):
    /// [`NARROW_STEP_SHARE`](Self::NARROW_STEP_SHARE) of the part's thickness, at
    /// most the long range.
    pub fn narrow_step(&self) -> f64 {
        (Self::NARROW_STEP_SHARE * self.part_thickness).min(self.range())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn every_derived_length_scales_with_the_problem() {
        let space = PlanningSpace::new(Vec3::new(-10.0, 0.0, 5.0), Vec3::new(90.0, 40.0, 25.0))
            .with_rotation_weight(12.0);
        let a = ProblemScale::new(&space, Some(12.0), Some(3.0));
        let k = 37.5;
        let scaled =
            PlanningSpace::new(space.min * k, space.max * k).with_rotation_weight(12.0 * k);
        let b = ProblemScale::new(&scaled, Some(12.0 * k), Some(3.0 * k));
        for (x, y) in [
            (a.range(), b.range()),
            (a.resolution(), b.resolution()),
            (a.narrow_step(), b.narrow_step()),
            (a.metric_extent(), b.metric_extent()),
            (a.reach_floor(), b.reach_floor()),
            (
                a.long_range_rotation_weight(),
                b.long_range_rotation_weight(),
            ),
        ] {
            assert!((y - k * x).abs() <= 1e-9 * y, "{x} × {k} ≠ {y}");
        }
        // Without a part radius the rotation weight stands for it, and the radius
        // for the thickness.
        let c = ProblemScale::new(&space, None, None);
        assert_eq!((c.part_radius, c.part_thickness), (12.0, 12.0));
        assert_eq!(
            ProblemScale::new(&space, Some(f64::NAN), None).part_radius,
            12.0
        );
    }
}
