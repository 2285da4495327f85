//! [`Planner`]: a planner chosen by name with its options — the single entry point
//! that scripts, the CLI and benchmarks use, so the dispatch lives in one place.

use super::{
    biased_rrt, disassemble, greedy_ant, local_rrt, plan_insertion, rrt, rrt_connect, rrt_floyd,
    DisassemblyPlanner, GreedyAntOptions, InsertionOptions, LocalRrtOptions, MotionValidator,
    NarrowPassage, PlanError, PlanLimits, PlannedPath, PlanningSpace, ProgressFn,
    RrtConnectOptions, RrtFloydOptions, RrtOptions, Smoothing,
};
use crate::math::Aabb;
use crate::math::Transform;

/// A planner and its options.
#[derive(Debug, Clone)]
#[non_exhaustive]
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

/// The tree planners, which have narrow-passage measures and a fallback share.
const TREE_PLANNERS: &str = "rrt, biased_rrt, local_rrt and rrt_connect";

/// The planner names accepted by [`Planner::by_name`] and [`str::parse`].
pub const PLANNER_NAMES: [&str; 6] = [
    "greedy_ant",
    "rrt_floyd",
    "rrt",
    "biased_rrt",
    "local_rrt",
    "rrt_connect",
];

impl std::str::FromStr for Planner {
    type Err = PlanError;

    /// The planner called `name` with its default options.
    ///
    /// # Errors
    /// [`PlanError::UnknownPlanner`], with the closest names.
    fn from_str(name: &str) -> Result<Self, PlanError> {
        Planner::by_name(name).ok_or_else(|| PlanError::UnknownPlanner {
            name: name.to_string(),
            suggestion: crate::diagnostics::suggestion(name, PLANNER_NAMES),
        })
    }
}

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

    /// Checks every option of the planner (ranges, finiteness), as planning does
    /// first: a caller with a long set-up (meshes, scenes) can refuse bad options
    /// before it.
    ///
    /// # Errors
    /// [`PlanError::InvalidOption`] naming the option, its value and the rule.
    pub fn validate(&self) -> Result<(), PlanError> {
        match self {
            Planner::GreedyAnt(o) => o.validate(),
            Planner::RrtFloyd(o) => o.validate(),
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.validate(),
            Planner::LocalRrt(o) => o.validate(),
            Planner::RrtConnect(o) => o.validate(),
        }
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
    pub fn limits_mut(&mut self) -> &mut PlanLimits {
        match self {
            Planner::GreedyAnt(o) => &mut o.limits,
            Planner::RrtFloyd(o) => &mut o.limits,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => &mut o.limits,
            Planner::LocalRrt(o) => &mut o.rrt.limits,
            Planner::RrtConnect(o) => &mut o.limits,
        }
    }

    /// Seed, iteration and time limits (a copy).
    pub fn limits(&self) -> PlanLimits {
        self.clone().limits_mut().to_owned()
    }

    /// Sets the extension step (metric mm) of the tree planners; for `greedy_ant`,
    /// `step` is the number of segments of the line s → e (seed 000 table 4).
    pub fn set_step(&mut self, step: f64) {
        match self {
            // A step that rounds below 1 segment (or is not finite) becomes 0, which
            // validation refuses, instead of silently planning with 1.
            Planner::GreedyAnt(o) => o.step = Some(step.round().max(0.0) as usize),
            Planner::RrtFloyd(o) => o.step = step,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.step = step,
            Planner::LocalRrt(o) => o.rrt.step = step,
            Planner::RrtConnect(o) => o.step = Some(step),
        }
    }

    /// Sets the goal bias `p` (a probability, checked when planning) where the
    /// planner has one.
    ///
    /// # Errors
    /// [`PlanError::NotAnOption`] for `greedy_ant` and `rrt_connect`, which have none.
    pub fn set_goal_bias(&mut self, p: f64) -> Result<(), PlanError> {
        match self {
            Planner::RrtFloyd(o) => o.goal_bias = p,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.goal_bias = p,
            Planner::LocalRrt(o) => o.rrt.goal_bias = p,
            Planner::GreedyAnt(_) | Planner::RrtConnect(_) => {
                return Err(
                    self.not_an_option("goal_bias", "rrt_floyd, rrt, biased_rrt and local_rrt")
                )
            }
        }
        Ok(())
    }

    /// Sets the narrow-passage measures of the tree planners.
    ///
    /// # Errors
    /// [`PlanError::NotAnOption`] for `greedy_ant` and `rrt_floyd`, which have none.
    pub fn set_narrow(&mut self, narrow: NarrowPassage) -> Result<(), PlanError> {
        match self.narrow_mut() {
            Some(slot) => *slot = narrow,
            None => return Err(self.not_an_option("narrow", TREE_PLANNERS)),
        }
        Ok(())
    }

    /// Sets the share of the search the fallbacks of a blocked extension may take
    /// (a probability, checked when planning) for the tree planners.
    ///
    /// # Errors
    /// [`PlanError::NotAnOption`] for `greedy_ant` and `rrt_floyd`.
    pub fn set_fallback_share(&mut self, share: f64) -> Result<(), PlanError> {
        match self.fallback_share_mut() {
            Some(slot) => *slot = share,
            None => return Err(self.not_an_option("fallback_share", TREE_PLANNERS)),
        }
        Ok(())
    }

    /// Sets seed 000's greedy-ant parameters: `shortest_length` (`L`, mm), `dis`
    /// (mm) and `radius` (mm); `None` keeps the current value.
    ///
    /// # Errors
    /// [`PlanError::NotAnOption`] for every planner but `greedy_ant`.
    pub fn set_greedy_ant(
        &mut self,
        shortest_length: Option<f64>,
        dis: Option<f64>,
        radius: Option<f64>,
    ) -> Result<(), PlanError> {
        let Planner::GreedyAnt(g) = self else {
            let option = match (shortest_length, dis) {
                (Some(_), _) => "L",
                (None, Some(_)) => "dis",
                (None, None) => "radius",
            };
            return Err(self.not_an_option(option, "greedy_ant"));
        };
        if let Some(l) = shortest_length {
            g.shortest_length = l;
        }
        if let Some(d) = dis {
            g.dis = d;
        }
        if radius.is_some() {
            g.radius = radius;
        }
        Ok(())
    }

    fn not_an_option(&self, option: &'static str, planners: &'static str) -> PlanError {
        PlanError::NotAnOption {
            option,
            planner: self.name(),
            planners,
        }
    }

    /// The narrow-passage measures ([`NarrowPassage`]) of the tree planners `rrt`,
    /// `biased_rrt`, `local_rrt` and `rrt_connect`; `None` for `greedy_ant` and
    /// `rrt_floyd`, which have none.
    pub fn narrow_mut(&mut self) -> Option<&mut NarrowPassage> {
        match self {
            Planner::Rrt(o) | Planner::BiasedRrt(o) => Some(&mut o.narrow),
            Planner::LocalRrt(o) => Some(&mut o.rrt.narrow),
            Planner::RrtConnect(o) => Some(&mut o.narrow),
            Planner::GreedyAnt(_) | Planner::RrtFloyd(_) => None,
        }
    }

    /// The share of the search's work the fallbacks of a blocked extension may take
    /// ([`RrtConnectOptions::fallback_share`]) for the tree planners; `None` for
    /// `greedy_ant` and `rrt_floyd`.
    pub fn fallback_share_mut(&mut self) -> Option<&mut f64> {
        match self {
            Planner::Rrt(o) | Planner::BiasedRrt(o) => Some(&mut o.fallback_share),
            Planner::LocalRrt(o) => Some(&mut o.rrt.fallback_share),
            Planner::RrtConnect(o) => Some(&mut o.fallback_share),
            Planner::GreedyAnt(_) | Planner::RrtFloyd(_) => None,
        }
    }

    /// The path shortcutting settings.
    pub fn smoothing(&self) -> Smoothing {
        match self {
            Planner::GreedyAnt(o) => o.smoothing,
            Planner::RrtFloyd(o) => o.smoothing,
            Planner::Rrt(o) | Planner::BiasedRrt(o) => o.smoothing,
            Planner::LocalRrt(o) => o.rrt.smoothing,
            Planner::RrtConnect(o) => o.smoothing,
        }
    }

    /// Path shortcutting on or off.
    pub fn set_smoothing(&mut self, on: bool) {
        let s = Smoothing {
            enabled: on,
            ..Smoothing::default()
        };
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
    ) -> Result<PlannedPath, PlanError> {
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
    ) -> Result<PlannedPath, PlanError> {
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
        disassemble(
            validator,
            space,
            assembled,
            part_box,
            product_box,
            &planner,
            progress,
        )
    }

    /// Seed 002's assembly by disassembly, for a full start → goal path: see
    /// [`plan_insertion`]. This planner's options drive the part of the search they fit:
    /// `rrt`, `biased_rrt` and `local_rrt` search the disassembly (seed 002's
    /// comparison), `rrt_connect` options the free-space join (the disassembly is then
    /// `local_rrt`); the seed and limits apply to both. `greedy_ant` and `rrt_floyd`
    /// are refused: they search toward a goal pose, not out of the product box.
    #[allow(clippy::too_many_arguments)]
    pub fn plan_via_disassembly(
        &self,
        validator: &mut dyn MotionValidator,
        space: &PlanningSpace,
        start: &Transform,
        goal: &Transform,
        part_box: &Aabb,
        product_box: &Aabb,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<PlannedPath, PlanError> {
        let limits = self.limits();
        let mut options =
            InsertionOptions::default().with_limits(limits.seed, limits.max_iterations);
        options.time_limit_ms = limits.time_limit_ms;
        options.smoothing = self.smoothing();
        match self {
            Planner::Rrt(o) | Planner::BiasedRrt(o) => {
                options.disassembly = DisassemblyPlanner::Rrt(o.clone())
            }
            Planner::LocalRrt(o) => options.disassembly = DisassemblyPlanner::LocalRrt(o.clone()),
            Planner::RrtConnect(o) => {
                options.approach = o.clone();
                options.approach.limits.max_iterations = limits.max_iterations;
                // The same narrow-passage measures and fallback share for the
                // disassembly search.
                options.disassembly.rrt_mut().narrow = o.narrow;
                options.disassembly.rrt_mut().fallback_share = o.fallback_share;
            }
            Planner::GreedyAnt(_) | Planner::RrtFloyd(_) => {
                return Err(PlanError::InvalidOption {
                    option: "planner",
                    value: self.name().to_string(),
                    expected: "rrt, biased_rrt, local_rrt or rrt_connect with disassemble: true \
                               (greedy_ant and rrt_floyd search toward a goal pose, not out of \
                               the product box)",
                })
            }
        }
        plan_insertion(
            validator,
            space,
            start,
            goal,
            part_box,
            product_box,
            &options,
            progress,
        )
    }
}
