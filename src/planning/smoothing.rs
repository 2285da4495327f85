//! Shortcut smoothing of a found path.

use super::path::{measure, PlannedPath};
use super::run::{PlanError, PlanLimits, ProgressFn, Run};
use super::space::PlanningSpace;
use super::validator::{Checker, MotionValidator};
use crate::math::{Rng, Transform};
use std::time::Instant;

/// How a found path is shortened.
///
/// First a linear pass drops every key pose whose neighbours see each other; then
/// random shortcuts join two random points of the path (anywhere on its edges) by a
/// straight edge when that edge is free, until `patience` attempts in a row have
/// not shortened the path by [`Smoothing::GAIN`] of its length (it has stopped
/// improving), or after `shortcut_attempts`. Each candidate edge is screened first
/// with pose checks at the problem's resolution
/// ([`ProblemScale::resolution`](super::ProblemScale::resolution)), which rejects a
/// blocked shortcut after a few checks, and only a screened one is certified by
/// the validator's own edge check: every kept edge has been accepted by the
/// validator. Smoothing takes at most `budget_share` of the call's time budget (and
/// never more than is left of it): a search that found its path late still returns
/// it, unsmoothed when nothing is left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Smoothing {
    /// Whether to smooth at all. Default true.
    pub enabled: bool,
    /// Largest number of random shortcut attempts after the linear pass. Default
    /// 1000 (convergence, `patience`, normally ends smoothing first).
    pub shortcut_attempts: usize,
    /// Attempts in a row without a gain of [`Smoothing::GAIN`] of the path's
    /// length after which smoothing stops. Default 50.
    pub patience: usize,
    /// Largest share of the call's time budget smoothing may take, in [0, 1].
    /// Default 0.2: smoothing that outlasts the search is a budget bug (issue 23).
    pub budget_share: f64,
}

/// Default [`Smoothing::budget_share`].
pub const DEFAULT_SMOOTHING_SHARE: f64 = 0.2;

impl Default for Smoothing {
    fn default() -> Self {
        Self {
            enabled: true,
            shortcut_attempts: 1000,
            patience: 50,
            budget_share: DEFAULT_SMOOTHING_SHARE,
        }
    }
}

impl Smoothing {
    /// No smoothing.
    pub const OFF: Self = Self {
        enabled: false,
        shortcut_attempts: 0,
        patience: 0,
        budget_share: DEFAULT_SMOOTHING_SHARE,
    };

    /// The share of the path's metric length a shortcut must gain to count as an
    /// improvement for [`patience`](Self::patience).
    pub const GAIN: f64 = 1e-3;

    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        PlanError::probability("smoothing.budget_share", self.budget_share)
    }

    /// Smoothing's time, ms, in a call of `budget_ms` with `left_ms` remaining:
    /// its share of the budget, at most what is left.
    pub fn time_ms(&self, budget_ms: f64, left_ms: f64) -> f64 {
        (self.budget_share * budget_ms).min(left_ms).max(0.0)
    }
}

/// Smooths a found `path` in place with `validator`, costs in `space`'s metric,
/// seeded by `seed`, within `time_limit_ms` — smoothing's own time, which the caller
/// sizes with [`Smoothing::time_ms`] (`None`: the default budget,
/// [`DEFAULT_TIME_LIMIT_MS`](super::DEFAULT_TIME_LIMIT_MS), all of it for smoothing). Anytime: when the budget
/// is spent or `progress` cancels, the shortest path so far is kept (every kept edge
/// was accepted by the validator). Updates the lengths, check counts, `smoothing_ms`
/// and `time_ms` (`raw_*` keep the lengths before).
pub fn smooth(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    path: &mut PlannedPath,
    smoothing: &Smoothing,
    seed: u64,
    time_limit_ms: Option<f64>,
    progress: Option<ProgressFn<'_>>,
) {
    if !path.found() {
        return;
    }
    let limits = PlanLimits {
        seed,
        max_iterations: usize::MAX,
        time_limit_ms,
    };
    let mut run = Run::new(limits, progress);
    run.end_search();
    let mut checker = Checker::new(validator, Some(run.deadline()));
    let mut rng = Rng::new(seed);
    let until = run.deadline();
    shortcut(
        &mut checker,
        space,
        &mut path.poses,
        smoothing,
        &mut rng,
        &mut run,
        until,
    );
    let (l, r) = measure(&path.poses);
    path.length_mm = l;
    path.rotation_rad = r;
    path.pose_checks += checker.pose_checks;
    path.edge_checks += checker.edge_checks;
    let ms = run.elapsed_ms();
    path.smoothing_ms += ms;
    path.time_ms += ms;
}

/// Shortcuts `poses` until `until` (smoothing's deadline, at most the call's): the
/// checker's deadline is narrowed to it meanwhile, so no edge check outlives it.
pub(crate) fn shortcut(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    poses: &mut Vec<Transform>,
    smoothing: &Smoothing,
    rng: &mut Rng,
    run: &mut Run<'_>,
    until: Instant,
) {
    // No time for smoothing (a zero share, or the budget spent): the path as found.
    if !smoothing.enabled || poses.len() < 3 || Instant::now() >= until {
        return;
    }
    let call = checker.deadline();
    checker.set_deadline(Some(call.map_or(until, |d| d.min(until))));
    shortcut_until(checker, space, poses, smoothing, rng, run, until);
    checker.set_deadline(call);
}

fn shortcut_until(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    poses: &mut Vec<Transform>,
    smoothing: &Smoothing,
    rng: &mut Rng,
    run: &mut Run<'_>,
    until: Instant,
) {
    let screen = {
        let r = checker.scale(space).resolution();
        (r, r / space.rotation_weight)
    };
    linear_pass(checker, poses, screen);
    // Pieces of a continuously certified edge need no check of their own (the
    // interpolation of a piece is the same motion: linear translation, slerp).
    let exact = !checker.is_lazy()
        && matches!(
            checker.resolution(),
            crate::collision::SweepMethod::Continuous { .. }
        );
    let mut stalled = 0;
    for attempt in 0..smoothing.shortcut_attempts {
        if stalled >= smoothing.patience.max(1) {
            break;
        }
        stalled += 1;
        // Anytime: every accepted shortcut leaves a valid path, so stopping here
        // keeps the best one so far.
        if !run.smoothing_tick(attempt, poses.len(), space.distance_along(poses), until) {
            return;
        }
        let edges = poses.len() - 1;
        if edges < 2 {
            break;
        }
        let (mut i, mut j) = (rng.below(edges), rng.below(edges));
        if i == j {
            continue;
        }
        if i > j {
            std::mem::swap(&mut i, &mut j);
        }
        let a = poses[i].interpolate(&poses[i + 1], rng.uniform());
        let b = poses[j].interpolate(&poses[j + 1], rng.uniform());
        // Cost in the space's metric: mm + weight · rad.
        let cost = |seg: &[Transform]| space.distance_along(seg);
        let old = cost(&[a, poses[i + 1]]) + cost(&poses[i + 1..=j]) + cost(&[poses[j], b]);
        let new = space.distance(&a, &b);
        if new >= old - 1e-9 {
            continue;
        }
        // p[i]→a and b→p[j+1] lie on accepted edges. A continuous check certified
        // every pose of those edges, so their pieces are free; a stepwise validator
        // checks other poses on them: re-check so that every kept edge was itself
        // accepted.
        if screened(checker, &a, &b, screen)
            && (exact
                || (screened(checker, &poses[i], &a, screen)
                    && screened(checker, &b, &poses[j + 1], screen)))
        {
            if old - new > Smoothing::GAIN * space.distance_along(poses) {
                stalled = 0;
            }
            let mut next = Vec::with_capacity(poses.len());
            next.extend_from_slice(&poses[..=i]);
            next.push(a);
            next.push(b);
            next.extend_from_slice(&poses[j + 1..]);
            *poses = next;
        }
    }
    // Shortcuts that land next to an existing key pose leave near-duplicates behind.
    linear_pass(checker, poses, screen);
}

/// Whether the edge `a → b` is free: screened with pose checks `screen` (mm, rad)
/// apart, then, when they all pass, the checker's own edge check.
fn screened(checker: &mut Checker<'_>, a: &Transform, b: &Transform, screen: (f64, f64)) -> bool {
    checker.screen(a, b, screen) && checker.edge_free(a, b)
}

/// Drops `p[i]` whenever its kept predecessor sees `p[i + 1]` (a spent budget makes
/// every check answer "not free", which keeps the pose: the path stays valid).
fn linear_pass(checker: &mut Checker<'_>, poses: &mut Vec<Transform>, screen: (f64, f64)) {
    if poses.len() < 3 || checker.expired() {
        return;
    }
    let mut kept = vec![poses[0]];
    for i in 1..poses.len() - 1 {
        let last = kept[kept.len() - 1];
        if !screened(checker, &last, &poses[i + 1], screen) {
            kept.push(poses[i]);
        }
    }
    kept.push(poses[poses.len() - 1]);
    *poses = kept;
}
