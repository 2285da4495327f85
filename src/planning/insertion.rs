//! [`plan_insertion`]: disassembly-first planning between any two poses (seed 002's
//! "what can be taken apart can be assembled", joined to the free end by RRT-Connect).

use super::disassembly::{disassemble, DisassemblyPlanner};
use super::lattice::Lattice;
use super::local_rrt::LocalRrtOptions;
use super::narrow::NarrowPassage;
use super::path::{measure, PlannedPath};
use super::rrt_connect::{rrt_connect, RrtConnectOptions};
use super::run::{PlanError, PlanLimits, ProgressFn};
use super::smoothing::{smooth, Smoothing};
use super::space::PlanningSpace;
use super::validator::{Checker, LazyValidation, MotionValidator};
use crate::math::Aabb;
use crate::math::Transform;
use std::time::Instant;

/// Options of [`plan_insertion`].
#[derive(Debug, Clone, PartialEq)]
pub struct InsertionOptions {
    /// The disassembly search from the assembled end (its `limits.seed` seeds the
    /// whole run; its smoothing and time limit are not used). Default: `local_rrt`
    /// with lazy validation, [`Lattice::RANDOM_MOVES`] random coordinated moves,
    /// [`Lattice::clearance_turns`], [`NarrowPassage::default`] and a
    /// `fallback_share` of 0.1.
    pub disassembly: DisassemblyPlanner,
    /// The search joining the free end to where the disassembly left the product
    /// (its seed is derived from the disassembly's; its smoothing and time limit are
    /// not used). Default: [`RrtConnectOptions::default`] (lazy, random moves).
    pub approach: RrtConnectOptions,
    /// Shortcut smoothing of the joined path.
    pub smoothing: Smoothing,
    /// Budget of the whole call in ms: disassembly, join and smoothing together
    /// (`None`: [`DEFAULT_TIME_LIMIT_MS`](super::DEFAULT_TIME_LIMIT_MS)).
    pub time_limit_ms: Option<f64>,
}

impl Default for InsertionOptions {
    fn default() -> Self {
        let mut local = LocalRrtOptions::default();
        local.lattice.random_moves = Lattice::RANDOM_MOVES;
        local.lattice.clearance_turns = true;
        local.rrt.lazy = Some(LazyValidation::default());
        local.rrt.narrow = NarrowPassage::default();
        // The lattice and the narrow-passage measures within a tenth of the work,
        // as in `rrt_connect`: on the benchmark problems this was 1.4–11× faster
        // than every blocked extension falling back (docs/performance.md).
        local.rrt.fallback_share = 0.1;
        let mut disassembly = DisassemblyPlanner::LocalRrt(local);
        disassembly.rrt_mut().smoothing.enabled = false;
        let mut approach = RrtConnectOptions::default();
        approach.smoothing.enabled = false;
        Self {
            disassembly,
            approach,
            smoothing: Smoothing::default(),
            time_limit_ms: None,
        }
    }
}

impl InsertionOptions {
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
pub(crate) fn inside(part_box: &Aabb, pose: &Transform, product_box: &Aabb) -> bool {
    let b = part_box.transformed(pose.isometry());
    (0..3).all(|k| b.lo[k] < product_box.hi[k] && b.hi[k] > product_box.lo[k])
}

/// The label of a path made by [`plan_insertion`]: what actually ran (`lazy_`:
/// explored with pose checks, the path certified by the validator's edge check).
fn label(disassembly: &DisassemblyPlanner, approach: &RrtConnectOptions) -> &'static str {
    let local = matches!(disassembly, DisassemblyPlanner::LocalRrt(_));
    match (
        local,
        disassembly.rrt().lazy.is_some(),
        approach.lazy.is_some(),
    ) {
        (false, false, false) => "disassemble_rrt+rrt_connect",
        (false, false, true) => "disassemble_rrt+lazy_rrt_connect",
        (false, true, false) => "lazy_disassemble_rrt+rrt_connect",
        (false, true, true) => "lazy_disassemble_rrt+lazy_rrt_connect",
        (true, false, false) => "disassemble_local_rrt+rrt_connect",
        (true, false, true) => "disassemble_local_rrt+lazy_rrt_connect",
        (true, true, false) => "lazy_disassemble_local_rrt+rrt_connect",
        (true, true, true) => "lazy_disassemble_local_rrt+lazy_rrt_connect",
    }
}

/// Plans from `start` to `goal`, disassembly first.
///
/// The end whose component box (`part_box`, component frame, mm) overlaps
/// `product_box` (assembly frame) is the assembled one — the goal for an insertion,
/// the start for a removal: [`disassemble`] takes the component from there out of
/// the product box, and [`rrt_connect`] joins the pose where it left to the other
/// end (in the open, so this is the easy part; its seed is derived from the
/// disassembly's so the two searches draw different numbers). The joined path is
/// then smoothed. The path's `planner` says what ran, e.g.
/// `"disassemble_local_rrt+rrt_connect"`; its counts are the sums of both searches.
///
/// When both or neither end is inside the product box there is nothing to
/// disassemble: the call is plain [`rrt_connect`] with the approach options and the
/// seed as given, smoothed, and the path is labelled `"rrt_connect"`.
///
/// One time budget, `time_limit_ms`, bounds the whole call: the searches get what
/// is left of it, smoothing stops when it is spent and keeps the best path so far.
/// `time_ms` is the whole call, `search_ms` and `smoothing_ms` its parts.
///
/// # Errors
/// Invalid options, bounds, boxes or non-finite poses.
#[allow(clippy::too_many_arguments)]
pub fn plan_insertion(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    part_box: &Aabb,
    product_box: &Aabb,
    options: &InsertionOptions,
    mut progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    let clock = Instant::now();
    PlanError::pose("start", start)?;
    PlanError::pose("goal", goal)?;
    options.smoothing.validate()?;
    let budget = PlanLimits {
        time_limit_ms: options.time_limit_ms,
        ..PlanLimits::default()
    };
    budget.validate()?;
    let deadline = budget.deadline(clock);
    // What is left of the budget, ms (a small positive floor: a limit must be > 0,
    // and a spent one then ends the next search at its first clock read).
    let left = || Some((deadline.remaining().as_secs_f64() * 1e3).max(1e-3));
    let seed = options.disassembly.rrt().limits.seed;
    // Every found path ends the same way: smoothed within what is left, timed.
    let end = |validator: &mut dyn MotionValidator, path: &mut PlannedPath, progress| {
        finish(
            validator,
            space,
            path,
            options,
            seed,
            clock,
            left(),
            progress,
        );
    };
    let (start_in, goal_in) = (
        inside(part_box, start, product_box),
        inside(part_box, goal, product_box),
    );
    let mut approach = options.approach.clone();
    approach.smoothing.enabled = false;
    // A free straight line from start to goal needs no disassembly: RRT-Connect
    // returns it after its first edge check.
    let direct = {
        let mut checker = Checker::new(validator, Some(deadline));
        let reference = start.rotation();
        space.contains(start, &reference)
            && space.contains(goal, &reference)
            && checker.is_free(start)
            && checker.is_free(goal)
            && checker.edge_free(start, goal)
    };
    if start_in == goal_in || direct {
        approach.limits.time_limit_ms = left();
        let mut path = rrt_connect(
            validator,
            space,
            start,
            goal,
            &approach,
            progress.as_mut().map(|p| &mut **p as ProgressFn<'_>),
        )?;
        end(validator, &mut path, progress);
        return Ok(path);
    }
    approach.limits.seed = options.approach.limits.seed ^ 0x9E37_79B9_7F4A_7C15;
    let name = label(&options.disassembly, &options.approach);
    let assembled = if goal_in { goal } else { start };
    // With a scale-free approach the disassembly's lengths (given for the 3 mm
    // reference step) shrink with a thin part, but never grow: a fit's clearance
    // does not grow with the part (a Ø20 mm peg in a bore 0.2 mm wider fails at
    // 3.3× the lengths, tests/it/planning_problems.rs `peg_tilt`).
    let mut out = match options.approach.step {
        Some(_) => options.disassembly.clone(),
        None => {
            let scale = super::ProblemScale::of(space, &*validator);
            let k = (scale.narrow_step() / RrtConnectOptions::STEP).min(1.0);
            options.disassembly.scaled(k)
        }
    };
    out.rrt_mut().smoothing.enabled = false;
    out.rrt_mut().limits.time_limit_ms = left();
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
    apart.planner = name;
    if !apart.found() {
        apart.time_ms = ms_since(clock);
        apart.search_ms = apart.time_ms;
        return Ok(apart);
    }
    let exit = apart.poses[0];
    let free_end = if goal_in { start } else { goal };
    approach.limits.time_limit_ms = left();
    let join = if goal_in {
        rrt_connect(
            validator,
            space,
            free_end,
            &exit,
            &approach,
            progress.as_mut().map(|p| &mut **p as ProgressFn<'_>),
        )?
    } else {
        rrt_connect(
            validator,
            space,
            &exit,
            free_end,
            &approach,
            progress.as_mut().map(|p| &mut **p as ProgressFn<'_>),
        )?
    };
    // One clock read: two would make the search longer than the whole call.
    let elapsed = ms_since(clock);
    let mut path = PlannedPath {
        failure: join.failure,
        poses: Vec::new(),
        iterations: apart.iterations + join.iterations,
        nodes: apart.nodes + join.nodes,
        pose_checks: apart.pose_checks + join.pose_checks,
        edge_checks: apart.edge_checks + join.edge_checks,
        time_ms: elapsed,
        search_ms: elapsed,
        smoothing_ms: 0.0,
        planner: name,
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
    end(validator, &mut path, progress);
    Ok(path)
}

fn ms_since(clock: Instant) -> f64 {
    clock.elapsed().as_secs_f64() * 1e3
}

/// Smooths within what is left of the budget and sets the call's times.
#[allow(clippy::too_many_arguments)]
fn finish(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    path: &mut PlannedPath,
    options: &InsertionOptions,
    seed: u64,
    clock: Instant,
    left_ms: Option<f64>,
    progress: Option<ProgressFn<'_>>,
) {
    // The searches' own smoothing was off: their times are search only.
    path.search_ms = ms_since(clock);
    path.smoothing_ms = 0.0;
    let budget = options
        .time_limit_ms
        .unwrap_or(super::run::DEFAULT_TIME_LIMIT_MS);
    let share = options.smoothing.time_ms(budget, left_ms.unwrap_or(budget));
    // No share (or nothing left): the path as the search found it.
    if share > 0.0 {
        smooth(
            validator,
            space,
            path,
            &options.smoothing,
            seed,
            Some(share),
            progress,
        );
    }
    path.time_ms = ms_since(clock);
}
