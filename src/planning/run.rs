//! What every planner shares: limits, progress reports, cancellation, option errors.

use crate::math::Deadline;
use std::time::Instant;

/// Why a planner returned no path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Failure {
    /// The iteration limit was reached.
    #[error("iteration limit reached")]
    IterationLimit,
    /// The time limit was reached.
    #[error("time limit reached")]
    TimeLimit,
    /// The start pose collides.
    #[error("the start pose is in collision")]
    StartInCollision,
    /// The goal pose collides.
    #[error("the goal pose is in collision")]
    GoalInCollision,
    /// The start pose is outside the planning space (box or allowed rotations).
    #[error("the start pose is outside the planning space")]
    StartOutOfBounds,
    /// The goal pose is outside the planning space (box or allowed rotations).
    #[error("the goal pose is outside the planning space")]
    GoalOutOfBounds,
    /// The progress callback asked to stop.
    #[error("cancelled")]
    Cancelled,
    /// A deterministic search ran out of candidates (greedy ant: no free grid point
    /// on layer `layer`; rrt_floyd: the graph does not join start and goal).
    #[error("no free candidate left (layer or stage {0})")]
    Exhausted(usize),
}

/// The time budget of a planning call when none is given: 10 s (search, smoothing
/// and every nested search together).
pub const DEFAULT_TIME_LIMIT_MS: f64 = 10_000.0;

/// Seed and limits of one planning run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanLimits {
    /// Seed of the run's [`Rng`](crate::math::Rng): equal seeds give equal paths
    /// whenever the iteration limit, not the time limit, ends the search.
    pub seed: u64,
    /// Largest number of iterations (tree extensions, or layers for the greedy ant).
    /// Default 1,000,000: the time budget is what normally ends a search (an
    /// iteration of RRT-Connect can cost a few microseconds, so a smaller cap
    /// would end a search long before the budget a user asked for).
    pub max_iterations: usize,
    /// Wall-clock budget of the whole call in milliseconds — search, smoothing and
    /// nested searches together (`None`: [`DEFAULT_TIME_LIMIT_MS`]). When it runs out
    /// the search stops with [`Failure::TimeLimit`], or smoothing stops and keeps the
    /// best path found so far.
    pub time_limit_ms: Option<f64>,
}

impl Default for PlanLimits {
    /// Seed 0, 10 000 iterations, the default time budget ([`DEFAULT_TIME_LIMIT_MS`]).
    fn default() -> Self {
        Self {
            seed: 0,
            max_iterations: 1_000_000,
            time_limit_ms: None,
        }
    }
}

impl PlanLimits {
    /// The time budget in ms: `time_limit_ms` or [`DEFAULT_TIME_LIMIT_MS`].
    pub fn budget_ms(&self) -> f64 {
        self.time_limit_ms.unwrap_or(DEFAULT_TIME_LIMIT_MS)
    }

    /// When the budget runs out for a call started at `started`.
    pub fn deadline(&self, started: Instant) -> Deadline {
        Deadline::from_start(started, crate::math::deadline::budget_ms(self.budget_ms()))
    }

    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        if self.max_iterations == 0 {
            return Err(PlanError::invalid(
                "max_iterations",
                "0".into(),
                "at least 1",
            ));
        }
        if let Some(t) = self.time_limit_ms {
            PlanError::positive("time_limit_ms", t)?;
        }
        Ok(())
    }
}

/// What a planning call is doing when it reports progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Phase {
    /// Searching for a path.
    Search,
    /// Shortening a found path (anytime: stopping keeps the best path so far).
    Smoothing,
}

/// A progress report, handed to the caller's callback every
/// [`PROGRESS_EVERY`] iterations (searching) or shortcut attempts (smoothing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Searching or smoothing.
    pub phase: Phase,
    /// Iterations done so far (smoothing: shortcut attempts).
    pub iterations: usize,
    /// Poses held by the search (tree nodes, graph nodes, layers; smoothing: the
    /// path's key poses).
    pub nodes: usize,
    /// Metric distance (mm) from the closest pose found so far to the goal
    /// (smoothing: the path's current length in the space's metric).
    pub best_distance: f64,
    /// Time since the call started (ms).
    pub elapsed_ms: f64,
}

/// The callback's answer: go on or stop the run (reported as [`Failure::Cancelled`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Control {
    /// Keep planning.
    Continue,
    /// Stop now.
    Cancel,
}

/// A progress callback.
pub type ProgressFn<'a> = &'a mut dyn FnMut(&Progress) -> Control;

/// Iterations between two progress callbacks.
pub const PROGRESS_EVERY: usize = 256;
/// Shortcut attempts between two progress callbacks while smoothing.
pub const SMOOTHING_PROGRESS_EVERY: usize = 16;
/// Iterations between two clock reads.
const CLOCK_EVERY: usize = 16;

/// Why a planner refused its input before planning.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// No planner has this name.
    #[error("unknown planner `{name}`: {suggestion}")]
    UnknownPlanner {
        /// The name given.
        name: String,
        /// The closest names, or the list of names.
        suggestion: String,
    },
    /// The option exists, but not for this planner.
    #[error("planner `{planner}` has no option `{option}` ({planners} have)")]
    NotAnOption {
        /// The option's name.
        option: &'static str,
        /// The planner it was given to.
        planner: &'static str,
        /// The planners that have it.
        planners: &'static str,
    },
    /// An option, bound or pose has a value the planner cannot use.
    #[error("invalid planning option `{option}` = {value}: expected {expected}")]
    InvalidOption {
        /// The option's name, as in the options struct.
        option: &'static str,
        /// The value given.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
}

impl PlanError {
    pub(crate) fn invalid(option: &'static str, value: String, expected: &'static str) -> Self {
        Self::InvalidOption {
            option,
            value,
            expected,
        }
    }

    /// Checks `v` is finite and > 0.
    pub(crate) fn positive(option: &'static str, v: f64) -> Result<(), Self> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Self::invalid(option, v.to_string(), "a finite number > 0"))
        }
    }

    /// Checks `v` is a probability.
    pub(crate) fn probability(option: &'static str, v: f64) -> Result<(), Self> {
        if (0.0..=1.0).contains(&v) {
            Ok(())
        } else {
            Err(Self::invalid(
                option,
                v.to_string(),
                "a probability in [0, 1]",
            ))
        }
    }

    /// Checks a pose has finite entries.
    pub(crate) fn pose(option: &'static str, p: &crate::math::Transform) -> Result<(), Self> {
        if p.is_finite() {
            Ok(())
        } else {
            Err(Self::invalid(option, format!("{p}"), "a finite pose"))
        }
    }
}

/// The start, deadline and limits a run shares with its siblings.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RunClock {
    started: Instant,
    deadline: Deadline,
    limits: PlanLimits,
}

/// The clock, counters and callback of one run.
pub(crate) struct Run<'p> {
    started: Instant,
    deadline: Deadline,
    limits: PlanLimits,
    progress: Option<ProgressFn<'p>>,
    pub iterations: usize,
    /// Time the search took (ms), set by [`Run::end_search`].
    pub search_ms: Option<f64>,
}

impl<'p> Run<'p> {
    pub fn new(limits: PlanLimits, progress: Option<ProgressFn<'p>>) -> Self {
        let started = Instant::now();
        Self {
            started,
            deadline: limits.deadline(started),
            limits,
            progress,
            iterations: 0,
            search_ms: None,
        }
    }

    /// The run of another search of the same call (a race's): the same start,
    /// deadline and limits, its own iteration count, no progress callback.
    pub fn sibling<'q>(&self) -> Run<'q> {
        Run::of_clock(self.clock())
    }

    /// What a sibling run shares with this one (sendable to another thread).
    pub fn clock(&self) -> RunClock {
        RunClock {
            started: self.started,
            deadline: self.deadline,
            limits: self.limits,
        }
    }

    /// A run on `clock`, with no progress callback.
    pub fn of_clock<'q>(clock: RunClock) -> Run<'q> {
        Run {
            started: clock.started,
            deadline: clock.deadline,
            limits: clock.limits,
            progress: None,
            iterations: 0,
            search_ms: None,
        }
    }

    pub fn elapsed_ms(&self) -> f64 {
        self.started.elapsed().as_secs_f64() * 1e3
    }

    /// When the call's budget runs out.
    pub fn deadline(&self) -> Deadline {
        self.deadline
    }

    /// Whether the budget is spent.
    pub fn expired(&self) -> bool {
        self.deadline.passed()
    }

    /// The call's whole time budget (ms).
    pub fn budget_ms(&self) -> f64 {
        self.limits.budget_ms()
    }

    /// Marks the end of the search (smoothing follows).
    pub fn end_search(&mut self) {
        self.search_ms = Some(self.elapsed_ms());
    }

    /// Called once per shortcut attempt while smoothing: reports progress every
    /// [`SMOOTHING_PROGRESS_EVERY`] attempts; `false` when smoothing must stop
    /// (budget or smoothing's share of it, `until`, spent, or cancelled).
    pub fn smoothing_tick(
        &mut self,
        attempt: usize,
        key_poses: usize,
        length: f64,
        until: Deadline,
    ) -> bool {
        if self.expired() || until.passed() {
            return false;
        }
        if attempt.is_multiple_of(SMOOTHING_PROGRESS_EVERY) && attempt > 0 {
            let elapsed_ms = self.elapsed_ms();
            if let Some(f) = self.progress.as_mut() {
                let report = Progress {
                    phase: Phase::Smoothing,
                    iterations: attempt,
                    nodes: key_poses,
                    best_distance: length,
                    elapsed_ms,
                };
                if f(&report) == Control::Cancel {
                    return false;
                }
            }
        }
        true
    }

    /// Starts the next iteration, or says why the run must stop.
    pub fn next(&mut self, nodes: usize, best_distance: f64) -> Result<(), Failure> {
        if self.iterations >= self.limits.max_iterations {
            return Err(Failure::IterationLimit);
        }
        self.check(nodes, best_distance)?;
        self.iterations += 1;
        Ok(())
    }

    /// Time and callback checks without counting an iteration (long inner loops).
    pub fn check(&mut self, nodes: usize, best_distance: f64) -> Result<(), Failure> {
        let i = self.iterations;
        if i.is_multiple_of(CLOCK_EVERY) && self.expired() {
            return Err(Failure::TimeLimit);
        }
        if i.is_multiple_of(PROGRESS_EVERY) && i > 0 {
            let elapsed_ms = self.elapsed_ms();
            if let Some(f) = self.progress.as_mut() {
                let report = Progress {
                    phase: Phase::Search,
                    iterations: i,
                    nodes,
                    best_distance,
                    elapsed_ms,
                };
                if f(&report) == Control::Cancel {
                    return Err(Failure::Cancelled);
                }
            }
        }
        Ok(())
    }
}
