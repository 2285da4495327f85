//! [`MotionValidator`]: the one question planners ask about geometry.

use crate::collision::SweepMethod;
use crate::math::{Deadline, Transform};

/// Lazy validation of a tree search: edges are explored with pose checks only
/// (`is_free` at most `step_mm` of translation and `step_mm / rotation_weight` of
/// rotation apart, the end pose first), which is cheap but can cut a corner or
/// cross a feature thinner than a step; once the trees join, every edge of the
/// candidate path is certified with the validator's own
/// [`edge_free`](MotionValidator::edge_free) (continuous for the mesh validator).
/// An edge that fails certification is cut from its tree with everything grown
/// from it and the search goes on. The returned path is the certified one: its
/// `resolution` is the validator's, as for an eager search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LazyValidation {
    /// Largest translation (mm) between two explored poses of an edge; the rotation
    /// step is this over the space's `rotation_weight` (rad). Default 1.
    pub step_mm: f64,
}

impl Default for LazyValidation {
    fn default() -> Self {
        Self { step_mm: 1.0 }
    }
}

impl LazyValidation {
    /// The explored `(mm, rad)` steps in `space`'s metric.
    pub(crate) fn steps(&self, space: &super::PlanningSpace) -> (f64, f64) {
        (self.step_mm, self.step_mm / space.rotation_weight)
    }

    pub(crate) fn validate(&self) -> Result<(), super::PlanError> {
        super::PlanError::positive("lazy.step_mm", self.step_mm)
    }
}

/// Answers whether the moving component collides with the fixed ones at a pose or
/// along a straight edge between two poses.
///
/// Poses place the moving component in the assembly frame (mm). What counts as a
/// collision is the validator's business: touching (zero distance, or penetration
/// below its tolerance) is free, so a start or goal pose resting against a
/// neighbour is valid.
///
/// Planners count the calls they make (reported as `pose_checks` and `edge_checks`
/// in [`PlannedPath`](super::PlannedPath)).
pub trait MotionValidator {
    /// Whether the component at `pose` is free of collision.
    fn is_free(&mut self, pose: &Transform) -> bool;

    /// How [`edge_free`](Self::edge_free) covers an edge (for an edge, a stepwise
    /// `step_mm` bounds the translation of the part origin, mm, and `step_rad` its
    /// rotation, rad).
    fn resolution(&self) -> SweepMethod {
        SweepMethod::DEFAULT
    }

    /// Penetration depth (mm) this validator still counts as free (touching); it is
    /// recorded in [`PlannedPath::tolerance_mm`](super::PlannedPath::tolerance_mm)
    /// so the path can be checked again with the rule it was planned with. Default 0.
    fn tolerance(&self) -> f64 {
        0.0
    }

    /// Whether the straight edge `from → to` (translation lerp + slerp) is free.
    ///
    /// `from` is assumed already validated (it is a node the planner holds); every
    /// other pose of the edge, `to` included, is checked.
    ///
    /// The default checks poses at [`resolution`](Self::resolution) with
    /// [`stepwise_edge_free`]; a validator that reports
    /// [`SweepMethod::Continuous`] must override this method (the default then
    /// falls back to [`SweepMethod::DEFAULT`] steps).
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        let (step_mm, step_rad) = match self.resolution() {
            SweepMethod::Stepwise { step_mm, step_rad } => (step_mm, step_rad),
            SweepMethod::Continuous { .. } => {
                (SweepMethod::DEFAULT_STEP_MM, SweepMethod::DEFAULT_STEP_RAD)
            }
        };
        stepwise_edge_free(|p| self.is_free(p), from, to, step_mm, step_rad)
    }

    /// Distance (mm) from the component at `pose` to the nearest obstacle, or `None`
    /// when the validator cannot tell. A lower bound is fine. [`local_rrt`](super::local_rrt)
    /// sizes its local lattice from it.
    fn clearance(&mut self, _pose: &Transform) -> Option<f64> {
        None
    }

    /// The instant the caller's time budget runs out (`None`: no deadline). A
    /// validator whose single queries can take long (fine stepwise edges, long
    /// continuous edges) should answer "not free" once it has passed, so that one
    /// check cannot overrun the budget; planners set it for the duration of a call
    /// and clear it afterwards. The default ignores it.
    fn set_deadline(&mut self, _deadline: Option<Deadline>) {}

    /// Radius of the moving part about its own origin (mm), when the validator
    /// knows it: the scale-free defaults derive their lengths from it
    /// ([`ProblemScale`](super::ProblemScale)). Default `None`.
    fn part_radius(&self) -> Option<f64> {
        None
    }

    /// The moving part's thinnest extent (mm): the smallest side of its box in its
    /// own frame, when the validator knows it. The scale-free narrow-passage search
    /// steps by a share of it ([`ProblemScale`](super::ProblemScale)). Default
    /// `None`.
    fn part_thickness(&self) -> Option<f64> {
        None
    }

    /// An independent copy of this validator for another thread (same geometry and
    /// rule, its own counters and deadline), or `None` when it cannot be copied.
    /// The default planner races its searches on two cores with it
    /// ([`rrt_connect`](super::rrt_connect)); without a copy it interleaves them on
    /// one thread, with the same result.
    fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        None
    }
}

impl<V: MotionValidator + ?Sized> MotionValidator for &mut V {
    fn is_free(&mut self, pose: &Transform) -> bool {
        (**self).is_free(pose)
    }
    fn resolution(&self) -> SweepMethod {
        (**self).resolution()
    }
    fn tolerance(&self) -> f64 {
        (**self).tolerance()
    }
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        (**self).edge_free(from, to)
    }
    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        (**self).clearance(pose)
    }
    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        (**self).set_deadline(deadline)
    }
    fn part_radius(&self) -> Option<f64> {
        (**self).part_radius()
    }
    fn part_thickness(&self) -> Option<f64> {
        (**self).part_thickness()
    }
    fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        (**self).fork()
    }
}

/// Checks the edge `from → to` pose by pose with `is_free`, at most `step_mm` of
/// translation and `step_rad` of rotation apart; `from` itself is not checked, `to` is.
///
/// The end pose is checked first (extensions mostly fail where they end), then the
/// interior in bisection order (midpoint, quarter points, …) so that a blocked edge is
/// usually rejected after few checks. Steps are in mm and rad; non-positive or
/// non-finite steps fall back to [`SweepMethod::DEFAULT`]'s; non-finite poses are
/// reported as not free.
pub fn stepwise_edge_free(
    mut is_free: impl FnMut(&Transform) -> bool,
    from: &Transform,
    to: &Transform,
    step_mm: f64,
    step_rad: f64,
) -> bool {
    let valid_or = |x: f64, default: f64| {
        if x.is_finite() && x > 0.0 {
            x
        } else {
            default
        }
    };
    let step_mm = valid_or(step_mm, SweepMethod::DEFAULT_STEP_MM);
    let step_rad = valid_or(step_rad, SweepMethod::DEFAULT_STEP_RAD);
    let (angle, dist) = from.distance_to(to);
    if !(angle.is_finite() && dist.is_finite()) {
        return false;
    }
    if !is_free(to) {
        return false;
    }
    let steps = (dist / step_mm)
        .ceil()
        .max((angle / step_rad).ceil())
        .max(1.0);
    // Above ~10^9 poses the caller asked for something unreasonable; cap the count
    // rather than loop for hours.
    let n = steps.min(1e9) as usize;
    if n <= 1 {
        return true;
    }
    // Every k in 1..n is odd · 2^j for exactly one j: visiting strides from the largest
    // power of two down gives a bisection order without allocating.
    let mut stride = n.next_power_of_two() / 2;
    while stride >= 1 {
        let mut k = stride;
        while k < n {
            if !is_free(&from.interpolate(to, k as f64 / n as f64)) {
                return false;
            }
            k += 2 * stride;
        }
        stride /= 2;
    }
    true
}

/// Wraps the caller's validator to count the checks a planner makes and to hold
/// the call's deadline: once it has passed every check answers "not free" at once
/// (nothing unchecked is ever accepted), and the planner's next clock read ends the
/// search with the time limit.
pub(crate) struct Checker<'v> {
    validator: &'v mut dyn MotionValidator,
    deadline: Option<Deadline>,
    /// Lazy exploration: `edge_free` checks poses `(mm, rad)` apart with `is_free`
    /// only; [`Checker::certify`] asks the validator's own edge check.
    lazy: Option<(f64, f64)>,
    pub pose_checks: u64,
    pub edge_checks: u64,
    /// Clearance queries (not reported: they serve the search, not the path).
    pub clearance_checks: u64,
    /// Collision effort of this checker's queries (node pairs visited on this
    /// thread while they ran, [`crate::collision::effort`]).
    effort: u64,
}

impl<'v> Checker<'v> {
    pub fn new(validator: &'v mut dyn MotionValidator, deadline: Option<Deadline>) -> Self {
        validator.set_deadline(deadline);
        Self {
            validator,
            deadline,
            lazy: None,
            pose_checks: 0,
            edge_checks: 0,
            clearance_checks: 0,
            effort: 0,
        }
    }

    /// Runs `query` on the validator, adding the collision effort it took on this
    /// thread to the checker's.
    fn counted<R>(&mut self, query: impl FnOnce(&mut dyn MotionValidator) -> R) -> R {
        let before = crate::collision::effort();
        let answer = query(&mut *self.validator);
        self.effort = self
            .effort
            .wrapping_add(crate::collision::effort().wrapping_sub(before));
        answer
    }

    /// Switches lazy exploration on (`Some((step_mm, step_rad))`: edges are
    /// explored by pose checks that far apart) or off (`None`: the validator's own
    /// edge check).
    pub fn set_lazy(&mut self, steps: Option<(f64, f64)>) {
        self.lazy = steps;
    }

    /// Whether edges are explored lazily.
    pub fn is_lazy(&self) -> bool {
        self.lazy.is_some()
    }

    /// The validator's own check of the edge `from → to` (what a lazy search
    /// certifies its path with), whatever the mode.
    pub fn certify(&mut self, from: &Transform, to: &Transform) -> bool {
        self.edge_checks += 1;
        !self.expired() && self.counted(|v| v.edge_free(from, to))
    }

    /// [`certify`](Self::certify) of every edge `(from, to)`, the verdicts in order:
    /// on two cores when the validator can be forked (a fork takes the second
    /// half), else one after the other. Each verdict depends on its edge alone, so
    /// the answer is the same either way (the deadline aside, which fails what it
    /// stops). Why: certifying the edges a smoothed path keeps is most of
    /// smoothing's time on long sliding contacts (OMPL.app's alpha puzzle), and
    /// after a race the second core is idle.
    pub fn certify_each(&mut self, edges: &[(Transform, Transform)]) -> Vec<bool> {
        let fork = if edges.len() >= 2 {
            self.validator.fork()
        } else {
            None
        };
        let Some(mut fork) = fork else {
            return edges.iter().map(|(a, b)| self.certify(a, b)).collect();
        };
        let deadline = self.deadline;
        fork.set_deadline(deadline);
        let (mine, theirs) = edges.split_at(edges.len().div_ceil(2));
        let mut verdicts = std::thread::scope(|scope| {
            let other = scope.spawn(move || {
                let free = |(a, b): &(Transform, Transform)| {
                    !deadline.is_some_and(Deadline::passed) && fork.edge_free(a, b)
                };
                theirs.iter().map(free).collect::<Vec<bool>>()
            });
            let mut verdicts: Vec<bool> = mine.iter().map(|(a, b)| self.certify(a, b)).collect();
            // A fork that panicked is a bug; its edges then count as not free,
            // which only keeps the detours.
            verdicts.extend(other.join().unwrap_or_else(|_| vec![false; theirs.len()]));
            verdicts
        });
        self.edge_checks += theirs.len() as u64;
        verdicts.truncate(edges.len());
        verdicts
    }

    /// A validator of the same scene for another thread, when the validator can
    /// be forked.
    pub fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        self.validator.fork()
    }

    /// Counts an edge verdict another thread's validator gave (so that a path's
    /// counts do not depend on which thread certified what).
    pub fn count_edge(&mut self) {
        self.edge_checks += 1;
    }

    /// The deadline every check honours (`None`: none).
    pub fn deadline(&self) -> Option<Deadline> {
        self.deadline
    }

    /// Moves the deadline (smoothing narrows it to its share of the budget, then
    /// puts the call's back).
    pub fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.deadline = deadline;
        self.validator.set_deadline(deadline);
    }

    /// Whether the deadline has passed.
    pub fn expired(&self) -> bool {
        self.deadline.is_some_and(Deadline::passed)
    }

    pub fn is_free(&mut self, pose: &Transform) -> bool {
        self.pose_checks += 1;
        !self.expired() && self.counted(|v| v.is_free(pose))
    }

    /// The edge check of the current mode: the validator's own, or, when lazy,
    /// pose checks along the edge (end pose first, then bisection order).
    pub fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        let Some((mm, rad)) = self.lazy else {
            return self.certify(from, to);
        };
        self.screen(from, to, (mm, rad))
    }

    /// Pose checks along `from → to` at most `(mm, rad)` apart, whatever the mode
    /// (a cheap screen before [`edge_free`](Self::edge_free) of a candidate edge:
    /// a blocked one is rejected after a few checks).
    pub fn screen(&mut self, from: &Transform, to: &Transform, (mm, rad): (f64, f64)) -> bool {
        if self.expired() {
            return false;
        }
        let mut checks = 0;
        let free = self.counted(|validator| {
            stepwise_edge_free(
                |p| {
                    checks += 1;
                    validator.is_free(p)
                },
                from,
                to,
                mm,
                rad,
            )
        });
        self.pose_checks += checks;
        free
    }

    pub fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        self.clearance_checks += 1;
        self.counted(|v| v.clearance(pose))
            .filter(|c| c.is_finite() && *c >= 0.0)
    }

    pub fn resolution(&self) -> SweepMethod {
        self.validator.resolution()
    }

    /// The problem's scale in `space` for the validator's part.
    pub fn scale(&self, space: &super::PlanningSpace) -> super::ProblemScale {
        super::ProblemScale::of(space, &*self.validator)
    }

    pub fn tolerance(&self) -> f64 {
        self.validator.tolerance()
    }

    /// The work done so far in pose-check units: pose and edge checks, and each
    /// clearance query as [`Checker::CLEARANCE_COST`] of them. The fallbacks'
    /// shares of a search are measured in it.
    pub fn work(&self) -> u64 {
        self.pose_checks + self.edge_checks + self.clearance_checks * Self::CLEARANCE_COST
    }

    /// [`work`](Self::work) plus the collision effort of all of it,
    /// [`Checker::EFFORT_PER_CHECK`] node pairs a unit: what two racing searches
    /// compare. By counts alone a check near contact (thousands of node pairs)
    /// weighed the same as one deep in collision (a few): on OMPL.app's spirelli
    /// the narrow-passage search took 2.7× the CPU time per unit of the
    /// long-range one's, and the race, which stops a search only once it has done
    /// more work than the path found took, waited 8 s for it. A validator whose
    /// queries visit no trees (no effort) is measured by the counts alone.
    pub fn cost(&self) -> u64 {
        self.work() + self.effort / Self::EFFORT_PER_CHECK
    }

    /// The node pairs of collision effort counted as one pose check in
    /// [`Checker::cost`].
    pub const EFFORT_PER_CHECK: u64 = 32;

    /// What one clearance query costs in pose checks: a distance search out to the
    /// validator's cap visits many more triangle pairs than a yes/no check, which
    /// stops at the first crossing (about 16× on the benchmark meshes, profiled).
    pub const CLEARANCE_COST: u64 = 16;
}

impl Drop for Checker<'_> {
    /// The validator outlives the call: its deadline must not.
    fn drop(&mut self) {
        self.validator.set_deadline(None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn stepwise_checks_every_step_once_and_stops_at_first_collision() {
        let a = Transform::IDENTITY;
        let b = Transform::from_translation(Vec3::new(10.0, 0.0, 0.0));
        let mut xs = Vec::new();
        assert!(stepwise_edge_free(
            |p| {
                xs.push(p.translation().x);
                true
            },
            &a,
            &b,
            1.0,
            1.0
        ));
        xs.sort_by(f64::total_cmp);
        let expected: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(xs.len(), 10);
        for (x, e) in xs.iter().zip(&expected) {
            assert!((x - e).abs() < 1e-9);
        }
        // A thin obstacle at x = 3 is found.
        assert!(!stepwise_edge_free(
            |p| (p.translation().x - 3.0).abs() > 0.4,
            &a,
            &b,
            1.0,
            1.0
        ));
    }

    #[test]
    fn rotation_sets_the_step_count() {
        let a = Transform::IDENTITY;
        let b =
            Transform::from_rotation_about(crate::math::Point3::origin(), Vec3::z(), 1.0).unwrap();
        let mut n = 0;
        stepwise_edge_free(
            |_| {
                n += 1;
                true
            },
            &a,
            &b,
            1.0,
            0.1,
        );
        assert_eq!(n, 10);
    }
}
