//! Planned insertions for parts that no straight line brings in: a two-segment path
//! (leave along one free direction, then another) and seed 002's disassembly planner
//! (`local_rrt`), each checked against the parts already assembled. Units: millimetres
//! and radians, assembly frame.

use super::context::*;
use super::fit::FitPairValidator;
use crate::collision::SweepMethod;
use crate::math::{Aabb, Deadline, Transform, Vec3};
use crate::planning::{
    MeshValidator, MeshValidatorOptions, MotionValidator, PlannedPath, Planner, PlanningSpace,
};

/// The checks of one part moving among others where some pairs have a fit: a mesh
/// validator for the obstacles without a fit (the call's tolerance) and a fit
/// validator for the fit partners (the overlap of the assembled pose allowed, see
/// `fit.rs`); a pose or edge is free when both say so.
#[derive(Clone)]
pub(crate) struct FitValidator {
    main: MeshValidator,
    fits: Option<FitPairValidator>,
}

impl FitValidator {
    /// `main` and the fit partners' checks together.
    pub(crate) fn new(main: MeshValidator, fits: Option<FitPairValidator>) -> Self {
        FitValidator { main, fits }
    }

    /// The resolution and tolerance the path records (the main validator's).
    pub(crate) fn options(&self) -> MeshValidatorOptions {
        *self.main.options()
    }
}

impl MotionValidator for FitValidator {
    fn is_free(&mut self, pose: &Transform) -> bool {
        self.main.is_free(pose) && self.fits.as_mut().is_none_or(|f| f.is_free(pose))
    }
    fn resolution(&self) -> SweepMethod {
        self.main.resolution()
    }
    fn tolerance(&self) -> f64 {
        self.main.tolerance()
    }
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        self.main.edge_free(from, to) && self.fits.as_mut().is_none_or(|f| f.edge_free(from, to))
    }
    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        // The fit partners overlap the part: no clearance to report from them.
        self.main.clearance(pose)
    }
    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.main.set_deadline(deadline);
        if let Some(f) = &mut self.fits {
            f.set_deadline(deadline);
        }
    }
    fn part_radius(&self) -> Option<f64> {
        self.main.part_radius()
    }
    fn part_thickness(&self) -> Option<f64> {
        self.main.part_thickness()
    }
    fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        let mut copy = self.clone();
        copy.set_deadline(None);
        Some(Box::new(copy))
    }
}

impl Ctx<'_> {
    /// A path for `p` out of the components of `mask` found by fitup's planners
    /// (seed 002's disassembly with `local_rrt`), ending assembled.
    pub(super) fn plan_fallback(&self, p: usize, mask: Mask) -> Option<PlannedPath> {
        let budget = self
            .opts
            .fallback_time_limit_ms
            .min(self.search_remaining_ms());
        if budget < 1.0 {
            return None;
        }
        let product = union_box(&self.boxes, mask)?;
        let mut validator = self.validator(p, mask, MeshValidatorOptions::default().edge)?;
        // The planner sets its own deadline for the call.
        validator.set_deadline(None);
        let margin = diag(&self.boxes[p]).max(10.0);
        let all = Aabb::new(
            product.lo.inf(&self.boxes[p].lo),
            product.hi.sup(&self.boxes[p].hi),
        );
        let space = PlanningSpace::new(
            all.lo.coords - Vec3::repeat(margin),
            all.hi.coords + Vec3::repeat(margin),
        );
        let mut planner = Planner::by_name("local_rrt")?;
        planner.limits_mut().seed = self.opts.seed;
        planner.limits_mut().time_limit_ms = Some(budget);
        planner.limits_mut().max_iterations = 20_000;
        let part_box = self.scene.colliders[p].bounds();
        let path = planner
            .plan_disassembly(
                &mut validator,
                &space,
                &self.scene.poses[p],
                &part_box,
                &product,
                None,
            )
            .ok()?;
        path.found().then_some(path)
    }

    /// A validator for `p` moving among the components of `mask`: the call's
    /// tolerance, and between `p` and its fit partners the overlap of the assembled
    /// pose allowed.
    pub(super) fn validator(
        &self,
        p: usize,
        mask: Mask,
        edge: SweepMethod,
    ) -> Option<FitValidator> {
        let checks: Vec<_> = members(mask)
            .filter_map(|q| self.fit_check(p, q).map(|c| (q, c)))
            .collect();
        let fitted: Mask = checks.iter().fold(0, |a, (q, _)| a | bit(*q));
        let main = MeshValidator::new(
            self.scene.colliders[p].clone(),
            members(mask & !fitted)
                .map(|q| (self.scene.colliders[q].clone(), self.scene.poses[q]))
                .collect(),
            MeshValidatorOptions {
                tolerance: Some(self.opts.tolerance),
                edge,
                ..MeshValidatorOptions::default()
            },
        )
        .ok()?;
        let fits = (!checks.is_empty()).then(|| FitPairValidator {
            pairs: checks.into_iter().map(|(_, c)| c).collect(),
            step_mm: self.fit_step(),
            deadline: None,
        });
        let mut v = FitValidator::new(main, fits);
        // The call's one deadline: past it every check answers "not free" at once
        // (a path is then not taken, never wrongly taken).
        v.set_deadline(Some(self.deadline));
        Some(v)
    }

    /// The cheapest non-straight insertion: slide along one candidate direction
    /// from the assembled pose, then leave straight along another (an L: under a
    /// roof, then out of the opening). Tries slides of 1/8 … 8/8 of the free travel,
    /// shortest first. Returns the insertion path (outside → corner → assembled),
    /// checked continuously among `mask`.
    pub(super) fn two_segment(&self, p: usize, mask: Mask) -> Option<PlannedPath> {
        let region = union_box(&self.boxes, mask)?;
        let mut v = self.validator(p, mask, SweepMethod::CONTINUOUS)?;
        let start = self.scene.poses[p];
        let mut leaves: Vec<Vec3> = axis_dirs().to_vec();
        for d in &self.dirs[p] {
            push_dir(&mut leaves, *d);
        }
        let mut best: Option<PlannedPath> = None;
        for d1 in &self.dirs[p] {
            // The free travel along d1: the first stepped pose that hits.
            let limit = exit_distance(&self.boxes[p], &region, d1) + self.opts.probe_mm;
            let step = self.step.max(limit / 100.0);
            let mut travel = 0.0;
            while travel + step < limit {
                if self.out_of_time() {
                    return best;
                }
                let at = start.then(&Transform::from_translation(d1 * (travel + step)));
                if self.pose_hits(p, &at, mask) {
                    break;
                }
                travel += step;
            }
            if travel < self.opts.probe_mm {
                continue;
            }
            for k in 1..=8 {
                let s = travel * k as f64 / 8.0;
                let corner = start.then(&Transform::from_translation(d1 * s));
                let moved = self.scene.colliders[p].world_bounds(&corner);
                for d2 in leaves.iter().filter(|d2| d2.dot(d1).abs() < 0.9) {
                    let out = exit_distance(&moved, &region, d2) + self.opts.probe_mm;
                    let from = corner.then(&Transform::from_translation(d2 * out));
                    let path = PlannedPath::given(
                        "two_segment",
                        vec![from, corner, start],
                        v.options().edge,
                    )
                    .with_tolerance(v.tolerance());
                    if best.as_ref().is_some_and(|b| b.length_mm <= path.length_mm) {
                        continue;
                    }
                    if path.revalidate(&mut v).is_ok() {
                        best = Some(path);
                    }
                }
                if best.is_some() {
                    break;
                }
            }
        }
        best
    }
}
