//! [`plan_assembly`]: disassembly-first planning between any two poses (seed 002's
//! "what can be taken apart can be assembled", joined to the free end by RRT-Connect).

use super::disassembly::{disassemble, Aabb, DisassemblyPlanner};
use super::local_rrt::LocalRrtOptions;
use super::path::{measure, Path};
use super::rrt_connect::{rrt_connect, RrtConnectOptions};
use super::run::{PlanError, ProgressFn};
use super::smoothing::{smooth, Smoothing};
use super::space::PlanningSpace;
use super::validator::MotionValidator;
use crate::math::Transform;

/// Options of [`plan_assembly`].
#[derive(Debug, Clone, PartialEq)]
pub struct AssemblyOptions {
    /// The disassembly search from the assembled end (its `limits.seed` seeds the
    /// whole run; its smoothing is not used). Default: `local_rrt`.
    pub disassembly: DisassemblyPlanner,
    /// The search joining the free end to where the disassembly left the product
    /// (its seed is derived from the disassembly's; its smoothing is not used).
    pub approach: RrtConnectOptions,
    /// Shortcut smoothing of the joined path.
    pub smoothing: Smoothing,
}

impl Default for AssemblyOptions {
    fn default() -> Self {
        let mut disassembly = DisassemblyPlanner::LocalRrt(LocalRrtOptions::default());
        disassembly.rrt_mut().smoothing.enabled = false;
        let mut approach = RrtConnectOptions::default();
        approach.smoothing.enabled = false;
        Self {
            disassembly,
            approach,
            smoothing: Smoothing::default(),
        }
    }
}

impl AssemblyOptions {
    /// The same options with `seed` and `max_iterations` for both searches.
    #[must_use]
    pub fn with_limits(mut self, seed: u64, max_iterations: usize) -> Self {
        self.disassembly.rrt_mut().limits.seed = seed;
        self.disassembly.rrt_mut().limits.max_iterations = max_iterations;
        self.approach.limits.seed = seed;
        self.approach.limits.max_iterations = max_iterations;
        self
    }
}

/// Whether `part_box` (component frame) placed at `pose` overlaps `product_box`
/// (assembly frame) with a positive volume.
fn inside(part_box: &Aabb, pose: &Transform, product_box: &Aabb) -> bool {
    let b = part_box.transformed(pose);
    (0..3).all(|k| b.min[k] < product_box.max[k] && b.max[k] > product_box.min[k])
}

/// Plans from `start` to `goal`, disassembly first.
///
/// The end whose component box (`part_box`, component frame, mm) overlaps
/// `product_box` (assembly frame) is the assembled one: [`disassemble`] with the
/// local discretization takes the component from there out of the product box, and
/// [`rrt_connect`] joins the pose where it left to the other end (in the open, so
/// this is the easy part). When both or neither end is inside the product box the
/// whole problem goes to [`rrt_connect`]. The joined path is then smoothed. The
/// returned counts (iterations, nodes, checks, time) are the sums of both searches;
/// `planner` is `"plan_assembly"`.
///
/// # Errors
/// Invalid options, bounds, boxes or non-finite poses.
#[allow(clippy::too_many_arguments)]
pub fn plan_assembly(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    part_box: &Aabb,
    product_box: &Aabb,
    options: &AssemblyOptions,
    mut progress: Option<ProgressFn<'_>>,
) -> Result<Path, PlanError> {
    const NAME: &str = "plan_assembly";
    PlanError::pose("start", start)?;
    PlanError::pose("goal", goal)?;
    options.smoothing.validate()?;
    let seed = options.disassembly.rrt().limits.seed;
    let (start_in, goal_in) = (
        inside(part_box, start, product_box),
        inside(part_box, goal, product_box),
    );
    let mut approach = options.approach.clone();
    approach.smoothing.enabled = false;
    approach.limits.seed = options.approach.limits.seed ^ 0x9E37_79B9_7F4A_7C15;
    if start_in == goal_in {
        let mut path = rrt_connect(validator, space, start, goal, &approach, progress)?;
        path.planner = NAME;
        smooth(validator, space, &mut path, &options.smoothing, seed);
        return Ok(path);
    }
    let assembled = if goal_in { goal } else { start };
    let mut out = options.disassembly.clone();
    out.rrt_mut().smoothing.enabled = false;
    // `disassemble` returns the path outside → assembled.
    let mut apart = disassemble(
        validator,
        space,
        assembled,
        part_box,
        product_box,
        &out,
        progress.as_mut().map(|p| &mut **p as ProgressFn<'_>),
    )?;
    apart.planner = NAME;
    if !apart.found() {
        return Ok(apart);
    }
    let exit = apart.poses[0];
    let free_end = if goal_in { start } else { goal };
    let join = if goal_in {
        rrt_connect(validator, space, free_end, &exit, &approach, progress)?
    } else {
        rrt_connect(validator, space, &exit, free_end, &approach, progress)?
    };
    let mut path = Path {
        failure: join.failure,
        poses: Vec::new(),
        iterations: apart.iterations + join.iterations,
        nodes: apart.nodes + join.nodes,
        pose_checks: apart.pose_checks + join.pose_checks,
        edge_checks: apart.edge_checks + join.edge_checks,
        time_ms: apart.time_ms + join.time_ms,
        planner: NAME,
        ..join.clone()
    };
    if !join.found() {
        return Ok(path);
    }
    path.poses = if goal_in {
        // start … exit, then exit … assembled
        let mut p = join.poses;
        p.extend(apart.poses.into_iter().skip(1));
        p
    } else {
        // assembled … exit, then exit … goal
        let mut p = apart.poses;
        p.reverse();
        p.extend(join.poses.into_iter().skip(1));
        p
    };
    let (l, r) = measure(&path.poses);
    path.raw_length_mm = l;
    path.raw_rotation_rad = r;
    path.length_mm = l;
    path.rotation_rad = r;
    let clock = std::time::Instant::now();
    smooth(validator, space, &mut path, &options.smoothing, seed);
    path.time_ms += clock.elapsed().as_secs_f64() * 1e3;
    Ok(path)
}
