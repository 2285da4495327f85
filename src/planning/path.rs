//! [`PlannedPath`]: what a planner returns, found or not.

use super::run::{Failure, Run};
use super::validator::{Checker, MotionValidator};
use crate::collision::SweepMethod;
use crate::math::limits::{steps, LimitError, SampleBudget};
use crate::math::{AngleConvention, Transform};
use std::io::{self, Write};

/// The result of a planning run.
///
/// `poses` are the key poses of the path, start first and goal last; consecutive
/// poses are joined by straight SE(3) edges (translation lerp + slerp) that the
/// validator accepted at `resolution`. Empty when `failure` is set.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedPath {
    /// `None` when a path was found, otherwise why not.
    pub failure: Option<Failure>,
    /// Key poses, start first (empty when not found).
    pub poses: Vec<Transform>,
    /// Sum of the translation lengths of the edges (mm).
    pub length_mm: f64,
    /// Sum of the rotation angles of the edges (rad).
    pub rotation_rad: f64,
    /// `length_mm` before smoothing (equal to it when smoothing is off).
    pub raw_length_mm: f64,
    /// `rotation_rad` before smoothing.
    pub raw_rotation_rad: f64,
    /// Iterations the planner ran.
    pub iterations: usize,
    /// Poses the search held at the end (tree or graph nodes).
    pub nodes: usize,
    /// Calls to [`MotionValidator::is_free`] made by the planner.
    pub pose_checks: u64,
    /// Calls to [`MotionValidator::edge_free`] made by the planner (smoothing included).
    pub edge_checks: u64,
    /// Wall-clock time of the whole call (ms): search, smoothing and any nested
    /// search, bounded by the call's time budget.
    pub time_ms: f64,
    /// Of `time_ms`, the search (ms).
    pub search_ms: f64,
    /// Of `time_ms`, the smoothing (ms); 0 when smoothing is off or no path was found.
    pub smoothing_ms: f64,
    /// How the validator checked the edges.
    pub resolution: SweepMethod,
    /// The validator's penetration tolerance (mm): crossings up to this depth
    /// counted as touching. With `resolution` it is the rule to check the path again
    /// by ([`PlannedPath::validator_options`]).
    pub tolerance_mm: f64,
    /// Which planner produced the path.
    pub planner: &'static str,
}

impl PlannedPath {
    /// Whether a path was found.
    pub fn found(&self) -> bool {
        self.failure.is_none()
    }

    /// Collision checks of both kinds.
    pub fn collision_checks(&self) -> u64 {
        self.pose_checks + self.edge_checks
    }

    pub(crate) fn failed(
        planner: &'static str,
        failure: Failure,
        iterations: usize,
        nodes: usize,
        checker: &Checker<'_>,
        time_ms: f64,
    ) -> Self {
        // Once the budget is spent every check answers "not free": a collision or
        // an exhausted search seen after that is the time limit, not the geometry.
        let failure = match failure {
            Failure::StartInCollision | Failure::GoalInCollision | Failure::Exhausted(_)
                if checker.expired() =>
            {
                Failure::TimeLimit
            }
            f => f,
        };
        Self {
            failure: Some(failure),
            poses: Vec::new(),
            length_mm: 0.0,
            rotation_rad: 0.0,
            raw_length_mm: 0.0,
            raw_rotation_rad: 0.0,
            iterations,
            nodes,
            pose_checks: checker.pose_checks,
            edge_checks: checker.edge_checks,
            time_ms,
            search_ms: time_ms,
            smoothing_ms: 0.0,
            resolution: checker.resolution(),
            tolerance_mm: checker.tolerance(),
            planner,
        }
    }

    /// A path through `poses` (part poses, mm, world frame) that was given rather
    /// than searched — a straight line, a path written by hand: lengths measured
    /// (raw = final), no search counts. `resolution` is how it is meant to be checked
    /// ([`PlannedPath::revalidate`] uses the validator's own options); its tolerance
    /// is the default [`DEFAULT_TOLERANCE`](crate::collision::DEFAULT_TOLERANCE)
    /// until [`with_tolerance`](Self::with_tolerance) says otherwise.
    pub fn given(planner: &'static str, poses: Vec<Transform>, resolution: SweepMethod) -> Self {
        let (length_mm, rotation_rad) = measure(&poses);
        Self {
            failure: None,
            poses,
            length_mm,
            rotation_rad,
            raw_length_mm: length_mm,
            raw_rotation_rad: rotation_rad,
            iterations: 0,
            nodes: 0,
            pose_checks: 0,
            edge_checks: 0,
            time_ms: 0.0,
            search_ms: 0.0,
            smoothing_ms: 0.0,
            resolution,
            tolerance_mm: crate::collision::DEFAULT_TOLERANCE,
            planner,
        }
    }

    /// The same path, recorded as checked with penetration tolerance `mm`.
    #[must_use]
    pub fn with_tolerance(mut self, mm: f64) -> Self {
        self.tolerance_mm = mm;
        self
    }

    /// The mesh validator's options that check this path again by the rule it was
    /// planned with: its `tolerance_mm` and its edge `resolution` (the rest default).
    pub fn validator_options(&self) -> super::MeshValidatorOptions {
        super::MeshValidatorOptions {
            tolerance: Some(self.tolerance_mm),
            edge: self.resolution,
            ..super::MeshValidatorOptions::default()
        }
    }

    pub(crate) fn found_with(
        planner: &'static str,
        poses: Vec<Transform>,
        raw: (f64, f64),
        iterations: usize,
        nodes: usize,
        checker: &Checker<'_>,
        run: &Run<'_>,
    ) -> Self {
        let (length_mm, rotation_rad) = measure(&poses);
        let time_ms = run.elapsed_ms();
        let search_ms = run.search_ms.unwrap_or(time_ms);
        Self {
            failure: None,
            poses,
            length_mm,
            rotation_rad,
            raw_length_mm: raw.0,
            raw_rotation_rad: raw.1,
            iterations,
            nodes,
            pose_checks: checker.pose_checks,
            edge_checks: checker.edge_checks,
            time_ms,
            search_ms,
            smoothing_ms: time_ms - search_ms,
            resolution: checker.resolution(),
            tolerance_mm: checker.tolerance(),
            planner,
        }
    }

    /// The path with poses at most `step_mm` and `step_rad` apart along every edge
    /// (for animation and fine re-checks); key poses are kept.
    ///
    /// # Errors
    /// A step that is not a finite number > 0, or more poses in all than
    /// [`MAX_SAMPLES`](crate::math::MAX_SAMPLES) — counted over all edges before
    /// anything is allocated — is a [`LimitError`] naming `step_mm` or `step_rad`.
    pub fn densify(&self, step_mm: f64, step_rad: f64) -> Result<Vec<Transform>, LimitError> {
        self.densify_steps(step_mm, step_rad, None)
    }

    /// [`PlannedPath::densify`] for a caller whose one argument `argument = value`
    /// set both steps (a script's `step`, in mm and as many degrees): errors name it.
    pub fn densify_as(
        &self,
        step_mm: f64,
        step_rad: f64,
        argument: &'static str,
        value: f64,
    ) -> Result<Vec<Transform>, LimitError> {
        self.densify_steps(step_mm, step_rad, Some((argument, value)))
    }

    fn densify_steps(
        &self,
        step_mm: f64,
        step_rad: f64,
        named: Option<(&'static str, f64)>,
    ) -> Result<Vec<Transform>, LimitError> {
        let (mm, rad) = match named {
            Some((a, v)) => ((a, v), (a, v)),
            None => (("step_mm", step_mm), ("step_rad", step_rad)),
        };
        for ((argument, value), step) in [(mm, step_mm), (rad, step_rad)] {
            if !(step.is_finite() && step > 0.0) {
                return Err(LimitError::BadStep { argument, value });
            }
        }
        // Count first, allocate after: the key poses plus every edge's steps.
        let mut budget = SampleBudget::new("poses");
        budget.take(self.poses.len().min(1) as f64, mm.0, mm.1)?;
        let mut counts = Vec::with_capacity(self.poses.len().saturating_sub(1));
        for w in self.poses.windows(2) {
            let (angle, dist) = w[0].distance_to(&w[1]);
            let (by_mm, by_rad) = (steps(dist, step_mm), steps(angle, step_rad));
            let (argument, value) = if by_mm >= by_rad { mm } else { rad };
            counts.push(budget.take(by_mm.max(by_rad), argument, value)?);
        }
        let mut out = Vec::with_capacity(budget.used());
        if let Some(first) = self.poses.first() {
            out.push(*first);
        }
        for (w, &n) in self.poses.windows(2).zip(&counts) {
            for k in 1..n {
                out.push(w[0].interpolate(&w[1], k as f64 / n as f64));
            }
            // The key pose itself, not its slerp at 1 (which differs in the last
            // bits): the planner checked this pose, and near a face-on-face
            // contact the interference verdict can flip between the two (issue
            // 23: a house key pose free with depth 0, its slerp at 1 crossing
            // 0.0101 mm).
            out.push(w[1]);
        }
        Ok(out)
    }

    /// Re-checks the path with `validator`: every key pose with `is_free`, every edge
    /// with `edge_free`. On failure returns the index of the first bad edge (0 for the
    /// start pose itself) and its end pose.
    ///
    /// The one tolerance rule: an edge is accepted when the validator accepts it in
    /// either direction. Planners check an edge in the direction they grew it, and a
    /// path from a goal tree or a disassembly is reversed afterwards; a continuous
    /// check's steps along a sliding contact depend on the direction, so checking
    /// only the other one could reject a pose the planner accepted.
    pub fn revalidate(
        &self,
        validator: &mut dyn MotionValidator,
    ) -> Result<(), (usize, Transform)> {
        for (i, p) in self.poses.iter().enumerate() {
            if !validator.is_free(p) {
                return Err((i.saturating_sub(1), *p));
            }
        }
        for (i, w) in self.poses.windows(2).enumerate() {
            if !validator.edge_free(&w[0], &w[1]) && !validator.edge_free(&w[1], &w[0]) {
                return Err((i, w[1]));
            }
        }
        Ok(())
    }

    /// Writes the key poses as CSV: `index,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg`, angles in
    /// `conv` (degrees, as in the user-facing `X Y Z A B C` triples).
    pub fn write_csv(&self, out: &mut dyn Write, conv: AngleConvention) -> io::Result<()> {
        writeln!(out, "index,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg")?;
        for (i, p) in self.poses.iter().enumerate() {
            let v = p.to_xyzabc_deg(conv);
            writeln!(
                out,
                "{i},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
                v[0], v[1], v[2], v[3], v[4], v[5]
            )?;
        }
        Ok(())
    }
}

/// Translation length (mm) and rotation (rad) of a polyline of poses.
pub(crate) fn measure(poses: &[Transform]) -> (f64, f64) {
    poses.windows(2).fold((0.0, 0.0), |(l, r), w| {
        let (a, d) = w[0].distance_to(&w[1]);
        (l + d, r + a)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn sample_path() -> PlannedPath {
        let poses = vec![
            Transform::IDENTITY,
            Transform::from_translation(Vec3::new(10.0, 0.0, 0.0)),
            Transform::from_xyzabc(
                Vec3::new(10.0, 5.0, 0.0),
                [0.0, 0.0, 0.5],
                AngleConvention::XyzFixed,
            ),
        ];
        PlannedPath::given("test", poses, SweepMethod::DEFAULT)
    }

    #[test]
    fn densify_keeps_ends_and_respects_steps() {
        let p = sample_path();
        assert!((p.length_mm - 15.0).abs() < 1e-9 && (p.rotation_rad - 0.5).abs() < 1e-9);
        let d = p.densify(1.0, 0.05).unwrap();
        assert!(d[0].approx_eq(&p.poses[0], 1e-12, 1e-12));
        assert!(d.last().unwrap().approx_eq(&p.poses[2], 1e-9, 1e-9));
        for w in d.windows(2) {
            let (a, l) = w[0].distance_to(&w[1]);
            assert!(l <= 1.0 + 1e-9 && a <= 0.05 + 1e-9);
        }
    }

    #[test]
    fn densify_refuses_bad_steps_and_counts_against_the_cap_before_allocating() {
        let p = sample_path();
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                p.densify(bad, 0.1),
                Err(LimitError::BadStep {
                    argument: "step_mm",
                    ..
                })
            ));
            assert!(matches!(
                p.densify(1.0, bad),
                Err(LimitError::BadStep {
                    argument: "step_rad",
                    ..
                })
            ));
        }
        // 15 mm at 1e-9 mm: 1.5e10 poses (≈ 0.8 TB) would abort; refused at once.
        let e = p
            .densify_as(1e-9, 1e-9f64.to_radians(), "step", 1e-9)
            .unwrap_err();
        match &e {
            LimitError::TooMany {
                argument,
                count,
                cap,
                what,
                ..
            } => {
                assert_eq!(
                    (*argument, *cap, *what),
                    ("step", crate::math::MAX_SAMPLES, "poses")
                );
                assert!(*count > 1e10, "{e}");
            }
            other => panic!("{other}"),
        }
        // The cap is on the whole path: each edge alone fits, the sum does not.
        let long = PlannedPath::given(
            "test",
            (0..4)
                .map(|i| Transform::from_translation(Vec3::new(i as f64 * 400.0, 0.0, 0.0)))
                .collect(),
            SweepMethod::DEFAULT,
        );
        assert_eq!(long.densify(0.5, 1.0).unwrap().len(), 2401);
        let e = long.densify(0.001, 1.0).unwrap_err();
        assert!(
            matches!(
                e,
                LimitError::TooMany {
                    argument: "step_mm",
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn csv_has_header_and_one_row_per_pose() {
        let p = sample_path();
        let mut buf = Vec::new();
        p.write_csv(&mut buf, AngleConvention::XyzFixed).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "index,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg");
        assert_eq!(lines.len(), 4);
        let last: Vec<f64> = lines[3].split(',').map(|s| s.parse().unwrap()).collect();
        assert!((last[2] - 5.0).abs() < 1e-6 && (last[6] - 0.5f64.to_degrees()).abs() < 1e-6);
    }

    struct Wall;
    impl MotionValidator for Wall {
        fn is_free(&mut self, pose: &Transform) -> bool {
            (pose.translation().x - 5.0).abs() > 0.5
        }
    }

    #[test]
    fn revalidate_names_the_bad_segment() {
        let p = sample_path();
        assert_eq!(p.revalidate(&mut Wall).unwrap_err().0, 0);
        let mut q = sample_path();
        q.poses.remove(0);
        assert!(q.revalidate(&mut Wall).is_ok());
    }
}
