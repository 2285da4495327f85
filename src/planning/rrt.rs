//! Seed 002's baselines: [`rrt`] (uniform sampling) and [`biased_rrt`] (goal bias p),
//! and the tree engine that [`local_rrt`](super::local_rrt) extends.

use super::lattice::Lattice;
use super::narrow::NarrowPassage;
use super::path::PlannedPath;
use super::run::{PlanError, PlanLimits, ProgressFn, Run};
use super::smoothing::{shortcut, Smoothing};
use super::space::PlanningSpace;
use super::tree::{begin, Begun, Effort, PoseTarget, Target, Tree};
use super::validator::{Checker, LazyValidation, MotionValidator};
use crate::math::Deadline;
use crate::math::{Rng, Transform};

/// Options of [`rrt`] and [`biased_rrt`].
#[derive(Debug, Clone, PartialEq)]
pub struct RrtOptions {
    /// Seed and limits.
    pub limits: PlanLimits,
    /// Largest extension toward a sample, in metric mm (see
    /// [`PlanningSpace`]). Default 10.
    pub step: f64,
    /// Probability `p` of sampling the goal instead of a uniform pose. Plain RRT: 0;
    /// Biased-RRT: default 0.1.
    pub goal_bias: f64,
    /// The distance `dth` (metric mm) under which a new node tries a straight edge to
    /// the goal. Default 10 (one step).
    pub goal_tolerance: f64,
    /// Shortcut smoothing of the found path.
    pub smoothing: Smoothing,
    /// Explore with pose checks and certify only the branch that reaches the goal
    /// ([`LazyValidation`]); `None` (default): every edge is checked by the
    /// validator when it is added.
    pub lazy: Option<LazyValidation>,
    /// Narrow-passage measures of the extensions and the sampling
    /// ([`NarrowPassage`]); goal-biased samples are drawn and approached as
    /// before. Default [`NarrowPassage::OFF`] (seed 002's search);
    /// [`InsertionOptions::default`](super::InsertionOptions) turns fitup's
    /// defaults on for its disassembly.
    pub narrow: NarrowPassage,
    /// Largest share of the search's work the fallbacks of a blocked extension
    /// (the lattice of [`local_rrt`](super::local_rrt), extension to contact,
    /// bridge-test sampling, dynamic-domain redraws) may take, in `[0, 1]`; see
    /// [`RrtConnectOptions::fallback_share`](super::RrtConnectOptions::fallback_share).
    /// Default 1 (every blocked extension, seed 002's search).
    pub fallback_share: f64,
}

impl Default for RrtOptions {
    /// Plain RRT: step 10, no goal bias, tolerance 10, default smoothing.
    fn default() -> Self {
        Self {
            limits: PlanLimits::default(),
            step: 10.0,
            goal_bias: 0.0,
            goal_tolerance: 10.0,
            smoothing: Smoothing::default(),
            lazy: None,
            narrow: NarrowPassage::OFF,
            fallback_share: 1.0,
        }
    }
}

impl RrtOptions {
    /// Biased-RRT defaults: as [`Default`] with `goal_bias` 0.1.
    pub fn biased() -> Self {
        Self {
            goal_bias: 0.1,
            ..Self::default()
        }
    }

    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        self.limits.validate()?;
        PlanError::positive("step", self.step)?;
        PlanError::probability("goal_bias", self.goal_bias)?;
        PlanError::positive("goal_tolerance", self.goal_tolerance)?;
        if let Some(l) = &self.lazy {
            l.validate()?;
        }
        self.narrow.validate()?;
        PlanError::probability("fallback_share", self.fallback_share)?;
        self.smoothing.validate()
    }
}

/// Plans with seed 002's baseline RRT from `start` to `goal`.
///
/// Each iteration samples a pose (the goal with probability `goal_bias`, else
/// uniformly in `space`), finds the nearest node, and adds the pose `step` toward the
/// sample if that edge is free. A node within `goal_tolerance` of the goal that can
/// see the goal ends the search.
///
/// # Errors
/// Invalid options, bounds or non-finite poses.
pub fn rrt(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &RrtOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    options.validate()?;
    plan_tree(
        "rrt",
        validator,
        space,
        start,
        &PoseTarget(*goal),
        options,
        None,
        progress,
    )
}

/// Seed 002's Biased-RRT: [`rrt`] requiring a goal bias `p > 0`
/// (see [`RrtOptions::biased`]).
///
/// # Errors
/// As [`rrt`], and `goal_bias == 0`.
pub fn biased_rrt(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &RrtOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    options.validate()?;
    if options.goal_bias <= 0.0 {
        return Err(PlanError::invalid(
            "goal_bias",
            options.goal_bias.to_string(),
            "a probability in (0, 1] for biased_rrt",
        ));
    }
    plan_tree(
        "biased_rrt",
        validator,
        space,
        start,
        &PoseTarget(*goal),
        options,
        None,
        progress,
    )
}

/// The single-tree engine of rrt, biased_rrt and local_rrt (options validated).
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_tree(
    planner: &'static str,
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    target: &dyn Target,
    options: &RrtOptions,
    local: Option<&Lattice>,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    let ends = (start, target.pose());
    let (mut run, mut checker) =
        match begin(planner, validator, space, ends, options.limits, progress)? {
            Begun::Ready(run, checker) => (run, checker),
            Begun::Refused(path) => return Ok(path),
        };
    let ending = Ending::new(planner, space, &options.smoothing, options.limits.seed);
    checker.set_lazy(options.lazy.map(|l| l.steps(space)));
    let mut rng = Rng::new(options.limits.seed);
    let key_mm = local.map_or(options.step * 1e-3, |l| l.edge_length_min * 0.25);
    let mut tree = Tree::new(*start, key_mm);
    let reference = start.rotation();
    let mut best = target.distance(start, space);
    let mut effort = Effort::new(options.fallback_share);
    let outcome = loop {
        if target.reached(start) {
            break Ok(0);
        }
        effort.iteration(best);
        if let Err(f) = run.next(tree.len(), best) {
            break Err(f);
        }
        let goal_biased = rng.uniform() < options.goal_bias;
        let narrow = &options.narrow;
        let (sample, near) = if goal_biased {
            let s = target.sample(&mut rng, space, start);
            (s, tree.nearest(&s, space).0)
        } else {
            narrow.sample_within(
                &mut effort,
                &mut rng,
                &mut checker,
                space,
                &reference,
                &tree,
            )
        };
        let mut added = Vec::new();
        let extended = narrow.extend(
            &mut checker,
            space,
            &reference,
            &mut tree,
            near,
            &sample,
            options.step,
        );
        if let Ok(i) = extended {
            added.push(i);
        }
        if let Err(candidate) = extended {
            let toward_sample = PoseTarget(sample);
            let rank: &dyn Target = if goal_biased || local.is_none_or(|l| !l.rank_toward_sample) {
                target
            } else {
                &toward_sample
            };
            narrow.fall_back(
                local,
                &mut effort,
                &mut checker,
                space,
                &reference,
                &mut tree,
                near,
                &candidate,
                rank,
                options.step,
                &mut rng,
                &mut added,
            );
        }
        let mut done = None;
        for &i in &added {
            let pose = tree.poses[i];
            let d = target.distance(&pose, space);
            best = best.min(d);
            if target.reached(&pose) {
                done = Some(i);
                break;
            }
            if let Some(goal) = target.pose() {
                if d <= options.goal_tolerance && checker.edge_free(&pose, goal) {
                    done = Some(if d == 0.0 { i } else { tree.add(*goal, i) });
                    break;
                }
            }
        }
        if let Some(i) = done {
            // Lazy: the goal was reached through explored edges; certify the branch
            // (a failed edge is cut with its subtree, and the search goes on).
            if !checker.is_lazy() || tree.certify_branch(i, &mut checker) {
                break Ok(i);
            }
        }
    };
    match outcome {
        Err(f) => Ok(PlannedPath::failed(
            planner,
            f,
            run.iterations,
            tree.len(),
            &checker,
            run.elapsed_ms(),
        )),
        Ok(i) => {
            let poses = tree.branch(i);
            // Smoothing keeps only edges the validator itself accepts.
            checker.set_lazy(None);
            Ok(ending.finish(poses, tree.len(), &mut checker, &mut run))
        }
    }
}

/// How one planner call ends a path it found: the planner's name, the space its
/// lengths are measured in (metric mm: mm + rotation weight · rad), its smoothing
/// and its seed, fixed for the call.
pub(crate) struct Ending<'a> {
    planner: &'static str,
    space: &'a PlanningSpace,
    smoothing: &'a Smoothing,
    seed: u64,
}

impl<'a> Ending<'a> {
    pub(crate) fn new(
        planner: &'static str,
        space: &'a PlanningSpace,
        smoothing: &'a Smoothing,
        seed: u64,
    ) -> Self {
        Self {
            planner,
            space,
            smoothing,
            seed,
        }
    }

    /// Smooths the found `poses` (the search grew `nodes` nodes) within the call's
    /// smoothing share and builds the result.
    pub(crate) fn finish(
        &self,
        mut poses: Vec<Transform>,
        nodes: usize,
        checker: &mut Checker<'_>,
        run: &mut Run<'_>,
    ) -> PlannedPath {
        let raw = super::path::measure(&poses);
        run.end_search();
        // A different stream than the planner's, so smoothing does not depend on how
        // many numbers the search drew.
        let mut rng = Rng::new(self.seed ^ 0x5DEE_CE66_D1CE_5EED);
        // Smoothing's share of the budget, at most what is left of it.
        let left_ms = run.deadline().remaining().as_secs_f64() * 1e3;
        let until = Deadline::after_ms(self.smoothing.time_ms(run.budget_ms(), left_ms));
        shortcut(
            checker,
            self.space,
            &mut poses,
            self.smoothing,
            &mut rng,
            run,
            until,
        );
        PlannedPath::found_with(
            self.planner,
            poses,
            raw,
            run.iterations,
            nodes,
            checker,
            run,
        )
    }
}
