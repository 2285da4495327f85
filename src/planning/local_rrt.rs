//! Seed 002's improved RRT: when the extension toward the sample fails, discretize
//! the space around the nearest node and take the best free neighbour.

use super::lattice::Lattice;
use super::path::PlannedPath;
use super::rrt::{plan_tree, RrtOptions};
use super::run::{PlanError, ProgressFn};
use super::space::PlanningSpace;
use super::tree::PoseTarget;
use super::validator::MotionValidator;
use crate::math::Transform;

/// Options of [`local_rrt`] (seed 002's improved RRT).
#[derive(Debug, Clone, PartialEq)]
pub struct LocalRrtOptions {
    /// The RRT part: limits, `step`, goal bias `p` (default 0.2), `goal_tolerance`
    /// `dth`, smoothing.
    pub rrt: RrtOptions,
    /// The local discretization tried when an extension fails.
    pub lattice: Lattice,
}

impl Default for LocalRrtOptions {
    fn default() -> Self {
        Self {
            rrt: RrtOptions {
                goal_bias: 0.2,
                ..RrtOptions::default()
            },
            lattice: Lattice::default(),
        }
    }
}

impl LocalRrtOptions {
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        self.rrt.validate()?;
        self.lattice.validate()
    }
}

/// Plans with seed 002's improved RRT from `start` to `goal`.
///
/// Like [`biased_rrt`](super::biased_rrt), but when the extension toward the sample
/// fails (the nearest node is close to an obstacle), the space around that node is
/// discretized: first the 26 neighbours of a cube lattice of edge `l` (translation
/// only, ranked by distance to the goal), then the 6 rotations `±αX, ±αY, ±αZ`
/// (rotation only). The first free candidate joins the tree.
///
/// # Errors
/// Invalid options, bounds or non-finite poses.
pub fn local_rrt(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &LocalRrtOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    options.validate()?;
    plan_tree(
        "local_rrt",
        validator,
        space,
        start,
        &PoseTarget(*goal),
        &options.rrt,
        Some(&options.lattice),
        progress,
    )
}
