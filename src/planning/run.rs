//! What every planner shares: limits, progress reports, cancellation, option errors.

use super::path::Failure;
use std::time::Instant;

/// Seed and limits of one planning run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Seed of the run's [`Rng`](crate::math::Rng): equal seeds give equal paths
    /// whenever the iteration limit, not the time limit, ends the search.
    pub seed: u64,
    /// Largest number of iterations (tree extensions, or layers for the greedy ant).
    pub max_iterations: usize,
    /// Wall-clock limit in milliseconds (`None`: none). It only cuts a run short.
    pub time_limit_ms: Option<f64>,
}

impl Default for Limits {
    /// Seed 0, 10 000 iterations, no time limit.
    fn default() -> Self {
        Self {
            seed: 0,
            max_iterations: 10_000,
            time_limit_ms: None,
        }
    }
}

impl Limits {
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

/// A progress report, handed to the caller's callback every
/// [`PROGRESS_EVERY`] iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Iterations done so far.
    pub iterations: usize,
    /// Poses held by the search (tree nodes, graph nodes, layers).
    pub nodes: usize,
    /// Metric distance (mm) from the closest pose found so far to the goal.
    pub best_distance: f64,
    /// Time since the run started (ms).
    pub elapsed_ms: f64,
}

/// The callback's answer: go on or stop the run (reported as [`Failure::Cancelled`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
/// Iterations between two clock reads.
const CLOCK_EVERY: usize = 16;

/// Why a planner refused its input before planning.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
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

/// The clock, counters and callback of one run.
pub(crate) struct Run<'p> {
    started: Instant,
    limits: Limits,
    progress: Option<ProgressFn<'p>>,
    pub iterations: usize,
}

impl<'p> Run<'p> {
    pub fn new(limits: Limits, progress: Option<ProgressFn<'p>>) -> Self {
        Self {
            started: Instant::now(),
            limits,
            progress,
            iterations: 0,
        }
    }

    pub fn elapsed_ms(&self) -> f64 {
        self.started.elapsed().as_secs_f64() * 1e3
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
        if i % CLOCK_EVERY == 0 {
            if let Some(limit) = self.limits.time_limit_ms {
                if self.elapsed_ms() >= limit {
                    return Err(Failure::TimeLimit);
                }
            }
        }
        if i % PROGRESS_EVERY == 0 && i > 0 {
            let elapsed_ms = self.elapsed_ms();
            if let Some(f) = self.progress.as_mut() {
                let report = Progress {
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
