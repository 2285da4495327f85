//! [`Planner`]: a planner chosen by name with its options — the single entry point
//! that scripts, the CLI and benchmarks use, so the dispatch lives in one place.

use super::{
    biased_rrt, disassemble, greedy_ant, local_rrt, rrt, rrt_connect, rrt_floyd, Aabb, DisassemblyPlanner,
    GreedyAntOptions, Limits, LocalRrtOptions, MotionValidator, Path, PlanError, PlanningSpace, ProgressFn,
    RrtConnectOptions, RrtFloydOptions, RrtOptions, Smoothing,
};
use crate::math::Transform;

/// A planner and its options.
#[derive(Debug, Clone)]
pub enum Planner {
    /// Seed 000's single-ant dynamic greedy algorithm.
    GreedyAnt(GreedyAntOptions),
    /// Seed 000's random-walk tree + Floyd shortest path.
    RrtFloyd(RrtFloydOptions),
    /// Seed 002's plain RRT baseline.
    Rrt(RrtOptions),
    /// Seed 002's Biased-RRT baseline (goal bias p).
    BiasedRrt(RrtOptions),
    /// Seed 002's improved RRT with local discretization.
    LocalRrt(LocalRrtOptions),
    /// Bidirectional RRT-Connect (with the lattice fallback by default).
    RrtConnect(RrtConnectOptions),
}

/// The planner names accepted by [`Planner::by_name`].
pub const PLANNER_NAMES: [&str; 6] = ["greedy_ant", "rrt_floyd", "rrt", "biased_rrt", "local_rrt", "rrt_connect"];

impl Planner {
    /// The planner called `name` with its default options.
    pub fn by_name(name: &str) -> Option<Planner> {
        Some(match name {
            "greedy_ant" => Planner::GreedyAnt(GreedyAntOptions::default()),
            "rrt_floyd" => Planner::RrtFloyd(RrtFloydOptions::default()),
            "rrt" => Planner::Rrt(RrtOptions::default()),
            "biased_rrt" => Planner::BiasedRrt(RrtOptions::biased()),
            "local_rrt" => Planner::LocalRrt(LocalRrtOptions::default()),
            "rrt_connect" => Planner::RrtConnect(RrtConnectOptions::default()),
            _ => return None,
        })
    }

    /// The planner's name.
    pub fn name(&self) -> &'static str {
        match self {
            Planner::GreedyAnt(_) => "greedy_ant",
            Planner::RrtFloyd(_) => "rrt_floyd",
            Planner::Rrt(_) => "rrt",
            Planner::BiasedRrt(_) => "biased_rrt",
            Planner::LocalRrt(_) => "local_rrt",
            Planner::RrtConnect(_) => "rrt_connect",
        }
    }

    /// Seed, iteration and time limits.
    pub fn limits_mut(&mut self) -> &mut Limits {
        match self {
            Planner::GreedyAnt(o) => &mut o.limits,
            Planner::RrtFloyd(o) => &mut o.limits,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => &mut o.limits,
            Planner::LocalRrt(o) => &mut o.rrt.limits,
            Planner::RrtConnect(o) => &mut o.limits,
        }
    }

    /// Sets the extension step (metric mm) of the tree planners; for `greedy_ant`,
    /// `step` is the number of segments of the line s → e (seed 000 table 4).
    pub fn set_step(&mut self, step: f64) {
        match self {
            Planner::GreedyAnt(o) => o.step = Some(step.round().max(1.0) as usize),
            Planner::RrtFloyd(o) => o.step = step,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.step = step,
            Planner::LocalRrt(o) => o.rrt.step = step,
            Planner::RrtConnect(o) => o.step = step,
        }
    }

    /// Sets the goal bias `p` where the planner has one; `false` otherwise.
    pub fn set_goal_bias(&mut self, p: f64) -> bool {
        match self {
            Planner::RrtFloyd(o) => o.goal_bias = p,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.goal_bias = p,
            Planner::LocalRrt(o) => o.rrt.goal_bias = p,
            Planner::GreedyAnt(_) | Planner::RrtConnect(_) => return false,
        }
        true
    }

    /// Path shortcutting on or off.
    pub fn set_smoothing(&mut self, on: bool) {
        let s = Smoothing { enabled: on, ..Smoothing::default() };
        match self {
            Planner::GreedyAnt(o) => o.smoothing = s,
            Planner::RrtFloyd(o) => o.smoothing = s,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.smoothing = s,
            Planner::LocalRrt(o) => o.rrt.smoothing = s,
            Planner::RrtConnect(o) => o.smoothing = s,
        }
    }

    /// Plans from `start` to `goal`.
    pub fn plan(
        &self,
        validator: &mut dyn MotionValidator,
        space: &PlanningSpace,
        start: &Transform,
        goal: &Transform,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<Path, PlanError> {
        match self {
            Planner::GreedyAnt(o) => greedy_ant(validator, space, start, goal, o, progress),
            Planner::RrtFloyd(o) => rrt_floyd(validator, space, start, goal, o, progress),
            Planner::Rrt(o) => rrt(validator, space, start, goal, o, progress),
            Planner::BiasedRrt(o) => biased_rrt(validator, space, start, goal, o, progress),
            Planner::LocalRrt(o) => local_rrt(validator, space, start, goal, o, progress),
            Planner::RrtConnect(o) => rrt_connect(validator, space, start, goal, o, progress),
        }
    }

    /// Seed 002's disassembly-first planning: from `assembled` until the part's box
    /// (part frame) is outside `product_box` (world), then reversed, so the path ends
    /// assembled. Only the tree planners `rrt`, `biased_rrt` and `local_rrt` apply.
    pub fn plan_disassembly(
        &self,
        validator: &mut dyn MotionValidator,
        space: &PlanningSpace,
        assembled: &Transform,
        part_box: &Aabb,
        product_box: &Aabb,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<Path, PlanError> {
        let planner = match self {
            Planner::Rrt(o) | Planner::BiasedRrt(o) => DisassemblyPlanner::Rrt(o.clone()),
            Planner::LocalRrt(o) => DisassemblyPlanner::LocalRrt(o.clone()),
            other => {
                return Err(PlanError::InvalidOption {
                    option: "planner",
                    value: other.name().to_string(),
                    expected: "rrt, biased_rrt or local_rrt for disassembly",
                })
            }
        };
        disassemble(validator, space, assembled, part_box, product_box, &planner, progress)
    }

    /// Seed 002's assembly by disassembly, for a full start → goal path: plans the
    /// disassembly from `goal` (the assembled pose) until the part's box leaves
    /// `product_box`, then a free-space path from `start` to where the disassembly
    /// left the product (with this planner, or `rrt_connect` when this planner cannot
    /// disassemble), and joins them: start → outside → assembled.
    #[allow(clippy::too_many_arguments)]
    pub fn plan_via_disassembly(
        &self,
        validator: &mut dyn MotionValidator,
        space: &PlanningSpace,
        start: &Transform,
        goal: &Transform,
        part_box: &Aabb,
        product_box: &Aabb,
        mut progress: Option<ProgressFn<'_>>,
    ) -> Result<Path, PlanError> {
        let disassembler = match self {
            Planner::Rrt(_) | Planner::BiasedRrt(_) | Planner::LocalRrt(_) => self.clone(),
            other => {
                let mut l = LocalRrtOptions::default();
                l.rrt.limits = other.clone().limits_mut().clone();
                Planner::LocalRrt(l)
            }
        };
        let out = disassembler.plan_disassembly(
            validator,
            space,
            goal,
            part_box,
            product_box,
            progress.as_mut().map(|p| &mut **p as ProgressFn<'_>),
        )?;
        if !out.found() {
            return Ok(out);
        }
        let exit = out.poses[0];
        let approach_planner = match self {
            Planner::GreedyAnt(_) | Planner::RrtFloyd(_) | Planner::RrtConnect(_) => self.clone(),
            other => {
                let mut c = RrtConnectOptions::default();
                c.limits = other.clone().limits_mut().clone();
                Planner::RrtConnect(c)
            }
        };
        let approach = approach_planner.plan(validator, space, start, &exit, progress)?;
        if !approach.found() {
            return Ok(approach);
        }
        let mut poses = approach.poses.clone();
        poses.extend(out.poses.iter().skip(1).copied());
        Ok(Path {
            failure: None,
            poses,
            length_mm: approach.length_mm + out.length_mm,
            rotation_rad: approach.rotation_rad + out.rotation_rad,
            raw_length_mm: approach.raw_length_mm + out.raw_length_mm,
            raw_rotation_rad: approach.raw_rotation_rad + out.raw_rotation_rad,
            iterations: approach.iterations + out.iterations,
            nodes: approach.nodes + out.nodes,
            pose_checks: approach.pose_checks + out.pose_checks,
            edge_checks: approach.edge_checks + out.edge_checks,
            time_ms: approach.time_ms + out.time_ms,
            resolution: out.resolution,
            planner: "disassembly_first",
        })
    }
}
