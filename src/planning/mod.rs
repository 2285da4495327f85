//! Path planning for one rigid component moving among fixed ones.
//!
//! A pose is a [`Transform`](crate::math::Transform) (translation in mm + rotation), so
//! the configuration space is SE(3), clipped by a [`PlanningSpace`]. Planners never look
//! at geometry: they ask a [`MotionValidator`] whether a pose or a straight SE(3) edge is
//! free, so any interference checker (meshes, boxes, an analytic test scene) can drive
//! them.
//!
//! | planner | origin | strength |
//! |---|---|---|
//! | [`greedy_ant`] | seed 000, single-ant dynamic greedy algorithm (table 4) | deterministic, open scenes |
//! | [`rrt_floyd`] | seed 000, random-walk RRT + Floyd shortest path | short paths in small graphs |
//! | [`rrt`], [`biased_rrt`] | seed 002 baselines | reference only |
//! | [`local_rrt`] | seed 002, local-discretization RRT | narrow passages, insertions |
//! | [`rrt_connect`] | bidirectional RRT (+ the local discretization on failure) | general, fast |
//! | [`plan_insertion`] | disassembly first, then RRT-Connect to the free end | the benchmark problems (`models/problems/`, [`ProblemFile`]) |
//! | [`disassemble`] | seed 002, "what can be taken apart can be assembled" | insertions with unknown approach |
//!
//! Every planner takes a seed ([`PlanLimits::seed`]); for a given seed the result is
//! identical whenever the iteration limit (not the time limit) ends the search.
//! Every call honours one time budget ([`PlanLimits::time_limit_ms`], default
//! [`DEFAULT_TIME_LIMIT_MS`]) over search and smoothing together.
//! Details, options and defaults: `docs/planning.md`.

mod axis;
mod disassembly;
mod greedy_ant;
mod insertion;
mod lattice;
mod local_rrt;
mod mesh_validator;
mod narrow;
mod nearest;
mod path;
mod problem_file;
mod request;
mod rrt;
mod rrt_connect;
mod rrt_floyd;
mod run;
mod scale;
mod smoothing;
mod space;
mod tree;
mod validator;

#[cfg(test)]
mod test_scenes;

pub use disassembly::{disassemble, DisassemblyPlanner};
pub use greedy_ant::{greedy_ant, GreedyAntOptions};
pub use insertion::{plan_insertion, InsertionOptions};
pub use lattice::{DiscretizationFrame, Lattice};
pub use local_rrt::{local_rrt, LocalRrtOptions};
pub use mesh_validator::{
    default_tolerance, MeshValidator, MeshValidatorOptions, ValidatorStats, MIN_STEP_MM,
    MIN_STEP_RAD, TOLERANCE_SHARE,
};
pub use narrow::NarrowPassage;
pub use path::PlannedPath;
pub use problem_file::{
    ProblemFile, ProblemFileError, ReadCause, ValueProblem, MAX_PROBLEM_FILE_BYTES,
};
pub use request::{Planner, PLANNER_NAMES};
pub use rrt::{biased_rrt, rrt, RrtOptions};
pub use rrt_connect::{rrt_connect, RrtConnectOptions};
pub use rrt_floyd::{rrt_floyd, RrtFloydOptions, MAX_FLOYD_NODES};
pub use run::{
    Control, Failure, Phase, PlanError, PlanLimits, Progress, ProgressFn, DEFAULT_TIME_LIMIT_MS,
    PROGRESS_EVERY, SMOOTHING_PROGRESS_EVERY,
};
pub use scale::ProblemScale;
pub use smoothing::{smooth, Smoothing, DEFAULT_SMOOTHING_SHARE};
pub use space::{PlanningSpace, RotationFreedom};
pub use validator::{stepwise_edge_free, LazyValidation, MotionValidator};
