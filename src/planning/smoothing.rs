//! Shortcut smoothing of a found path.

use super::path::{measure, PlannedPath};
use super::run::{PlanError, PlanLimits, ProgressFn, Run};
use super::space::PlanningSpace;
use super::validator::{Checker, MotionValidator};
use crate::math::{Deadline, Rng, Transform};
use std::sync::{Condvar, Mutex, PoisonError};

/// How a found path is shortened.
///
/// First a linear pass drops every key pose whose neighbours see each other; then
/// random shortcuts join two random points of the path (anywhere on its edges) by a
/// straight edge when that edge is free, until `patience` attempts in a row have
/// not shortened the path by [`Smoothing::GAIN`] of its length (it has stopped
/// improving), or after `shortcut_attempts`. Each candidate edge is screened first
/// with pose checks at the problem's resolution
/// ([`ProblemScale::resolution`](super::ProblemScale::resolution)), which rejects a
/// blocked shortcut after a few checks. With a continuous validator a screened
/// shortcut is certified by the validator's own edge check only when it must be:
/// when a later shortcut keeps a piece of it, or when it is still in the path at
/// the end; a shortcut that fails its certification gives way to the path it
/// replaced (itself certified, or screened with its own fallback); a shortcut
/// that cuts a screened edge certifies only the piece it keeps. Meanwhile a
/// second thread (when the validator can be forked) certifies the screened
/// edges of the path ahead, newest first, so that the verdicts are often known
/// when they are needed; a verdict depends on its edge alone, so the path is the
/// same either way. With a stepwise validator every shortcut is certified when
/// it is accepted. Either way every
/// edge of the returned path has been accepted by the validator. The shortcuts
/// take at most `budget_share` of the call's time budget (and never more than is
/// left of it); the certification of the path's last screened edges runs within
/// what is left of the call's budget (past it, the path falls back to its
/// certified edges): a search that found its path late still returns it,
/// unsmoothed when nothing is left.
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
    until: Deadline,
) {
    // No time for smoothing (a zero share, or the budget spent): the path as found.
    if !smoothing.enabled || poses.len() < 3 || until.passed() {
        return;
    }
    let call = checker.deadline();
    let share = Some(call.map_or(until, |d| d.min(until)));
    checker.set_deadline(share);
    // With a continuous validator a piece of a certified edge is certified (the
    // interpolation of a piece is the same motion: linear translation, slerp), and
    // a screened shortcut is certified only when it must be: when it is still in
    // the path at the end, or when a later shortcut keeps a piece of it. Most
    // accepted shortcuts are cut away by later ones (Apartment: 138 accepted, 8
    // left), and the certification is the expensive part of smoothing (95 % of it).
    // A stepwise validator checks other poses on a piece than on its edge: there
    // every new edge and piece is certified at once, as the validator's own edge.
    let exact = !checker.is_lazy()
        && matches!(
            checker.resolution(),
            crate::collision::SweepMethod::Continuous { .. }
        );
    let ahead = Ahead::new();
    let worker = if exact { checker.fork() } else { None };
    let screen = screen_steps(checker, space);
    let (mut path, unfolded) = std::thread::scope(|scope| {
        let handle = worker.map(|validator| {
            let ahead = &ahead;
            scope.spawn(move || ahead.work(validator, call))
        });
        let ahead = handle.is_some().then_some(&ahead);
        let stop = ahead.map(StopOnDrop);
        let how = Shortcutting {
            smoothing,
            until,
            exact,
            ahead,
        };
        let mut path = shortcut_until(checker, space, std::mem::take(poses), rng, run, &how);
        // Shortcuts that land next to an existing key pose leave near-duplicates
        // behind: a last linear pass, screened like the shortcuts, so that the
        // certification below checks the joined edges and not the ones they replace.
        if exact && run.smoothing_tick(0, 0, 0.0, until) {
            path.linear_pass(checker, space, screen, true);
        }

        // The certification of the screened edges left in the path is the work an
        // eager smoothing would have done when it accepted them: it runs within the
        // call's budget, so that a smoothing share spent does not unfold the path.
        checker.set_deadline(call);
        let (poses_left, unfolded) = path.resolve(checker, ahead);
        drop(stop);
        // Joined here, a worker that panicked (a bug) only loses its verdicts,
        // which this thread made itself; the scope would re-raise the panic.
        if let Some(handle) = handle {
            let _ = handle.join();
        }
        (LazyPath::certified(poses_left), unfolded)
    });
    // A failed certification brings back the poses of its detour (and a
    // stepwise validator's shortcuts had no lazy pass): a linear pass, certified
    // at once, within smoothing's share.
    checker.set_deadline(share);
    if (unfolded || !exact) && run.smoothing_tick(0, 0, 0.0, until) {
        path.linear_pass(checker, space, screen, false);
    }
    checker.set_deadline(call);
    *poses = path.poses;
}

/// The pose-check spacing (mm, rad) that screens a candidate edge: the problem's
/// resolution.
fn screen_steps(checker: &Checker<'_>, space: &PlanningSpace) -> (f64, f64) {
    let r = checker.scale(space).resolution();
    (r, r / space.rotation_weight)
}

/// How [`shortcut_until`] shortcuts: the options, until when, whether screened
/// shortcuts are certified lazily (`exact`: a continuous validator), and the
/// worker certifying ahead, if any.
struct Shortcutting<'a> {
    smoothing: &'a Smoothing,
    until: Deadline,
    exact: bool,
    ahead: Option<&'a Ahead>,
}

fn shortcut_until(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    poses: Vec<Transform>,
    rng: &mut Rng,
    run: &mut Run<'_>,
    how: &Shortcutting<'_>,
) -> LazyPath {
    let &Shortcutting {
        smoothing,
        until,
        exact,
        ahead,
    } = how;
    let screen = screen_steps(checker, space);
    let mut path = LazyPath::certified(poses);
    path.linear_pass(checker, space, screen, exact);
    if let Some(ahead) = ahead {
        ahead.resync(&path);
    }
    let mut stalled = 0;
    for attempt in 0..smoothing.shortcut_attempts {
        if stalled >= smoothing.patience.max(1) {
            break;
        }
        stalled += 1;
        // Anytime: every accepted shortcut leaves a path whose uncertified edges
        // have certified detours, so stopping here keeps the best one so far.
        if !run.smoothing_tick(
            attempt,
            path.poses.len(),
            space.distance_along(&path.poses),
            until,
        ) {
            return path;
        }
        let edges = path.edges.len();
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
        let p = &path.poses;
        let a = p[i].interpolate(&p[i + 1], rng.uniform());
        let b = p[j].interpolate(&p[j + 1], rng.uniform());
        // Cost in the space's metric: mm + weight · rad.
        let cost = |seg: &[Transform]| space.distance_along(seg);
        let old = cost(&[a, p[i + 1]]) + cost(&p[i + 1..=j]) + cost(&[p[j], b]);
        let new = space.distance(&a, &b);
        // A shortcut that cannot gain what patience counts as a gain is not worth
        // its checks: the path has converged there.
        if old - new <= Smoothing::GAIN * space.distance_along(p) {
            continue;
        }
        if !checker.screen(&a, &b, screen) {
            continue;
        }
        let accepted = if exact {
            // The pieces p[i] → a and b → p[j + 1] stay: a piece of a screened
            // edge is certified first (a failed piece fails its edge, which gives
            // way to its detour, and the attempt is spent).
            path.certify_pieces(checker, (i, a), (j, b), ahead)
        } else {
            checker.edge_free(&a, &b)
                && screened(checker, &path.poses[i], &a, screen)
                && screened(checker, &b, &path.poses[j + 1], screen)
        };
        if accepted {
            stalled = 0;
            path.shortcut(i, a, j, b, exact);
            if let Some(ahead) = ahead {
                ahead.resync(&path);
            }
        }
    }
    path
}

/// How an edge of a path being smoothed is known to be free.
#[derive(Debug, Clone)]
enum Edge {
    /// Accepted by the validator's own edge check (or a piece of such an edge).
    Certified,
    /// Screened with pose checks only; its detour is certified or has certified
    /// detours in turn, so a failed certification falls back to it.
    Screened(Box<Detour>),
}

/// The path an uncertified edge replaced: the poses between its ends and the edges
/// joining them.
#[derive(Debug, Clone)]
struct Detour {
    via: Vec<Transform>,
    edges: Vec<Edge>,
}

/// A path whose edges are certified, or screened with a detour to fall back to.
struct LazyPath {
    poses: Vec<Transform>,
    /// `edges[k]` joins `poses[k]` and `poses[k + 1]`.
    edges: Vec<Edge>,
}

impl LazyPath {
    fn certified(poses: Vec<Transform>) -> Self {
        let edges = vec![Edge::Certified; poses.len().saturating_sub(1)];
        Self { poses, edges }
    }

    /// Edge `k`, screened, after its certification: certified when `free`, else
    /// replaced by its detour.
    fn settle(&mut self, k: usize, free: bool) {
        let Edge::Screened(detour) = std::mem::replace(&mut self.edges[k], Edge::Certified) else {
            return;
        };
        if !free {
            let Detour { via, edges } = *detour;
            self.poses.splice(k + 1..k + 1, via);
            self.edges.splice(k..=k, edges);
        }
    }

    /// Certifies the pieces `p[i] → a` and `b → p[j + 1]` (`i < j`) that a
    /// shortcut `a → b` keeps of edges `i` and `j`, where those edges are only
    /// screened (a piece of a certified edge is certified), on two cores when both
    /// are: whether both hold. A piece is on average half its edge, and its
    /// certification is what smoothing spends most of its time on (long sliding
    /// edges on OMPL.app's alpha puzzle and Apartment). A failed piece fails its
    /// edge, which gives way to its detour; the other edge keeps its state.
    fn certify_pieces(
        &mut self,
        checker: &mut Checker<'_>,
        (i, a): (usize, Transform),
        (j, b): (usize, Transform),
        ahead: Option<&Ahead>,
    ) -> bool {
        // A piece needs its own check unless its whole edge was certified ahead
        // (a failed edge may still have a free piece).
        let mut needs = |k: usize| {
            matches!(self.edges[k], Edge::Screened(_))
                && !ahead.is_some_and(|ahead| {
                    // Not waiting for an edge the worker is on: the piece is
                    // less work than the rest of the edge might be.
                    let free = ahead.take(&self.poses[k], &self.poses[k + 1], false) == Some(true);
                    if free {
                        checker.count_edge();
                    }
                    free
                })
        };
        let (check_j, check_i) = (needs(j), needs(i));
        let mut pieces = Vec::with_capacity(2);
        let mut edges = Vec::with_capacity(2);
        if check_j {
            pieces.push((b, self.poses[j + 1]));
            edges.push(j);
        }
        if check_i {
            pieces.push((self.poses[i], a));
            edges.push(i);
        }
        if pieces.is_empty() {
            return true;
        }
        let verdicts = checker.certify_each(&pieces);
        // `j` first: its detour does not move edge `i`.
        let mut all = true;
        for (&k, free) in edges.iter().zip(verdicts) {
            if !free {
                self.settle(k, false);
                all = false;
            }
        }
        all
    }

    /// Replaces the path from `a` (on edge `i`) to `b` (on edge `j > i`) by the
    /// straight edge `a → b`, screened (`lazy`, after
    /// [`certify_pieces`](Self::certify_pieces)) or already certified.
    ///
    /// The lazy edge's detour runs `a → p[i + 1] → … → p[j] → b`. Its first and
    /// last pieces are pieces of edges `i` and `j`: certified when their edges
    /// were, else screened, with a detour of their own back over the certified
    /// piece and through the edge's detour (`a → p[i] ⇝ p[i + 1]`, and
    /// `p[j] ⇝ p[j + 1] → b`). Those detours turn back on themselves, but they
    /// are only walked when a certification fails, and the last linear pass
    /// straightens them.
    fn shortcut(&mut self, i: usize, a: Transform, j: usize, b: Transform, lazy: bool) {
        let middle = if lazy {
            let first = match &self.edges[i] {
                Edge::Certified => Edge::Certified,
                Edge::Screened(d) => {
                    let mut via = Vec::with_capacity(d.via.len() + 1);
                    via.push(self.poses[i]);
                    via.extend_from_slice(&d.via);
                    let mut edges = Vec::with_capacity(d.edges.len() + 1);
                    edges.push(Edge::Certified);
                    edges.extend(d.edges.iter().cloned());
                    Edge::Screened(Box::new(Detour { via, edges }))
                }
            };
            let last = match &self.edges[j] {
                Edge::Certified => Edge::Certified,
                Edge::Screened(d) => {
                    let mut via = d.via.clone();
                    via.push(self.poses[j + 1]);
                    let mut edges = d.edges.clone();
                    edges.push(Edge::Certified);
                    Edge::Screened(Box::new(Detour { via, edges }))
                }
            };
            let mut edges = Vec::with_capacity(j - i + 1);
            edges.push(first);
            edges.extend(self.edges[i + 1..j].iter().cloned());
            edges.push(last);
            Edge::Screened(Box::new(Detour {
                via: self.poses[i + 1..=j].to_vec(),
                edges,
            }))
        } else {
            Edge::Certified
        };
        self.poses.splice(i + 1..=j, [a, b]);
        self.edges
            .splice(i..=j, [Edge::Certified, middle, Edge::Certified]);
    }

    /// Drops `p[i]` whenever its kept predecessor sees `p[i + 1]` (a spent budget
    /// makes every check answer "not free", which keeps the pose) and dropping it
    /// shortens the path by at least [`Smoothing::GAIN`] of its length: a pose
    /// whose removal gains less is not worth an edge check (on OMPL.app's alpha
    /// puzzle one certification of a long sliding edge costs tens of ms). `lazy`:
    /// the new edge is only screened, with the two edges it replaces as its detour.
    fn linear_pass(
        &mut self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        screen: (f64, f64),
        lazy: bool,
    ) {
        let n = self.poses.len();
        if n < 3 || checker.expired() {
            return;
        }
        let min_gain = Smoothing::GAIN * space.distance_along(&self.poses);
        let old_poses = std::mem::take(&mut self.poses);
        let mut old_edges = std::mem::take(&mut self.edges).into_iter();
        let mut poses = vec![old_poses[0]];
        let mut edges = Vec::with_capacity(n - 1);
        // The edge from the last kept pose to old_poses[i].
        let mut carried = old_edges.next().expect("n ≥ 3 poses have edges");
        for i in 1..n - 1 {
            let next = old_edges.next().expect("one edge per pose pair");
            let last = poses[poses.len() - 1];
            let gain = space.distance(&last, &old_poses[i])
                + space.distance(&old_poses[i], &old_poses[i + 1])
                - space.distance(&last, &old_poses[i + 1]);
            // A pose on the straight edge between its neighbours (an extension
            // made in steps) goes at no cost: the joined edge is the same motion
            // as the two it replaces.
            let between = gain < min_gain && on_edge(&last, &old_poses[i], &old_poses[i + 1]);
            let free = between
                || gain >= min_gain
                    && if lazy {
                        checker.screen(&last, &old_poses[i + 1], screen)
                    } else {
                        screened(checker, &last, &old_poses[i + 1], screen)
                    };
            if between {
                let both = matches!((&carried, &next), (Edge::Certified, Edge::Certified));
                carried = if both {
                    Edge::Certified
                } else {
                    Edge::Screened(Box::new(Detour {
                        via: vec![old_poses[i]],
                        edges: vec![carried, next],
                    }))
                };
            } else if free {
                carried = if lazy {
                    Edge::Screened(Box::new(Detour {
                        via: vec![old_poses[i]],
                        edges: vec![carried, next],
                    }))
                } else {
                    Edge::Certified
                };
            } else {
                poses.push(old_poses[i]);
                edges.push(std::mem::replace(&mut carried, next));
            }
        }
        poses.push(old_poses[n - 1]);
        edges.push(carried);
        self.poses = poses;
        self.edges = edges;
    }

    /// Certifies every screened edge, in path order, a failed one giving way to its
    /// detour (whose own screened edges are certified next): the poses of a path
    /// whose every edge the validator accepted. Past the deadline every
    /// certification fails, which unfolds the path back to certified edges.
    fn resolve(
        mut self,
        checker: &mut Checker<'_>,
        ahead: Option<&Ahead>,
    ) -> (Vec<Transform>, bool) {
        // Round by round: every screened edge is certified (on both cores), then
        // the failed ones, last first so that indices hold, give way to their
        // detours, whose screened edges are the next round's. The verdict of an
        // edge does not depend on the others, so this is the path one-by-one
        // certification gives.
        let mut unfolded = false;
        loop {
            let screened: Vec<usize> = (0..self.edges.len())
                .filter(|&k| matches!(self.edges[k], Edge::Screened(_)))
                .collect();
            if screened.is_empty() {
                return (self.poses, unfolded);
            }
            let ends: Vec<(Transform, Transform)> = screened
                .iter()
                .map(|&k| (self.poses[k], self.poses[k + 1]))
                .collect();
            let verdicts = match ahead {
                // The worker takes the queue from its end, this thread from the
                // path's start: they meet in between.
                Some(ahead) => {
                    ahead.resync(&self);
                    // Edges the worker is on are waited for last.
                    let mut verdicts = vec![None; ends.len()];
                    for pass in [false, true] {
                        for (v, (a, b)) in verdicts.iter_mut().zip(&ends) {
                            if v.is_some() || !pass && ahead.running(a, b) {
                                continue;
                            }
                            *v = Some(match ahead.take(a, b, true) {
                                Some(free) => {
                                    checker.count_edge();
                                    free
                                }
                                None => checker.certify(a, b),
                            });
                        }
                    }
                    verdicts.into_iter().map(|v| v == Some(true)).collect()
                }
                None => checker.certify_each(&ends),
            };
            for (&k, free) in screened.iter().zip(verdicts).rev() {
                unfolded |= !free;
                self.settle(k, free);
            }
        }
    }
}

/// Whether `p` lies on the straight edge `a → b` (translation lerp, rotation slerp
/// at the same parameter), to rounding.
fn on_edge(a: &Transform, p: &Transform, b: &Transform) -> bool {
    let (angle, shift) = a.distance_to(b);
    let (pa, ps) = a.distance_to(p);
    let s = if shift > 1e-12 {
        ps / shift
    } else if angle > 1e-12 {
        pa / angle
    } else {
        return p.approx_eq(a, 1e-9, 1e-12);
    };
    let tol = 1e-9 * (1.0 + a.translation().amax().max(b.translation().amax()));
    (0.0..=1.0).contains(&s) && p.approx_eq(&a.interpolate(b, s), tol, 1e-9)
}

/// Whether the edge `a → b` is free: screened with pose checks `screen` (mm, rad)
/// apart, then, when they all pass, the checker's own edge check.
fn screened(checker: &mut Checker<'_>, a: &Transform, b: &Transform, screen: (f64, f64)) -> bool {
    checker.screen(a, b, screen) && checker.edge_free(a, b)
}

/// Screened edges certified ahead on the second core while smoothing goes on.
///
/// After a race the second core is idle during smoothing, and most of smoothing's
/// time is certification (OMPL.app's alpha puzzle and Apartment: long sliding
/// edges). Every accepted shortcut hands its screened edge to a worker thread
/// with a fork of the validator, newest first. A verdict depends on the edge
/// alone, so using the worker's verdict or making one gives the same path: the
/// worker only changes when the answer is known. Where smoothing needs a verdict
/// the worker has not reached, it takes the edge off the queue and certifies it
/// (or the piece it keeps) itself; it waits for the edge the worker is on only
/// when it needs that whole edge (the final certification), after the others.
struct Ahead {
    state: Mutex<AheadState>,
    changed: Condvar,
}

#[derive(Default)]
struct AheadState {
    /// Edges to certify, the newest last (taken first).
    queue: Vec<(Transform, Transform)>,
    /// The edge the worker is certifying.
    running: Option<(Transform, Transform)>,
    /// Verdicts so far.
    done: Vec<((Transform, Transform), bool)>,
    stop: bool,
}

impl Ahead {
    fn new() -> Self {
        Self {
            state: Mutex::new(AheadState::default()),
            changed: Condvar::new(),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, AheadState> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The worker: certifies queued edges with `validator` until [`stop`](Self::stop).
    fn work(&self, mut validator: Box<dyn MotionValidator + Send>, deadline: Option<Deadline>) {
        // A worker that panicked must not leave smoothing waiting for its edge.
        struct Clear<'a>(&'a Ahead);
        impl Drop for Clear<'_> {
            fn drop(&mut self) {
                self.0.lock().running = None;
                self.0.changed.notify_all();
            }
        }
        let _clear = Clear(self);
        validator.set_deadline(deadline);
        loop {
            let edge = {
                let mut s = self.lock();
                loop {
                    if s.stop {
                        return;
                    }
                    if let Some(edge) = s.queue.pop() {
                        s.running = Some(edge);
                        break edge;
                    }
                    s = self.changed.wait(s).unwrap_or_else(PoisonError::into_inner);
                }
            };
            let free =
                !deadline.is_some_and(Deadline::passed) && validator.edge_free(&edge.0, &edge.1);
            let mut s = self.lock();
            s.running = None;
            s.done.push((edge, free));
            self.changed.notify_all();
        }
    }

    fn stop(&self) {
        self.lock().stop = true;
        self.changed.notify_all();
    }

    /// Makes the queue the screened edges of `path` the worker has not taken:
    /// edges that left the path are dropped, new ones go last (taken first).
    fn resync(&self, path: &LazyPath) {
        let screened: Vec<(Transform, Transform)> = (0..path.edges.len())
            .filter(|&k| matches!(path.edges[k], Edge::Screened(_)))
            .map(|k| (path.poses[k], path.poses[k + 1]))
            .collect();
        let mut s = self.lock();
        s.queue.retain(|e| screened.contains(e));
        for e in screened {
            let known = s.running == Some(e) || s.done.iter().any(|(d, _)| *d == e);
            if !known && !s.queue.contains(&e) {
                s.queue.push(e);
            }
        }
        drop(s);
        self.changed.notify_all();
    }

    /// The worker's verdict on `a → b`; `None` when it has none (the edge is then
    /// off its queue: the caller certifies it, or what it needs of it). `wait`:
    /// while the worker is on the edge, wait for its verdict rather than answer
    /// `None`.
    fn take(&self, a: &Transform, b: &Transform, wait: bool) -> Option<bool> {
        let key = (*a, *b);
        let mut s = self.lock();
        loop {
            if let Some(&(_, free)) = s.done.iter().find(|(e, _)| *e == key) {
                return Some(free);
            }
            if !wait || s.running != Some(key) {
                s.queue.retain(|e| *e != key);
                return None;
            }
            s = self.changed.wait(s).unwrap_or_else(PoisonError::into_inner);
        }
    }

    /// Whether the worker is on edge `a → b`.
    fn running(&self, a: &Transform, b: &Transform) -> bool {
        self.lock().running == Some((*a, *b))
    }
}

/// Stops the worker when smoothing ends, however it ends (a panic would otherwise
/// leave the scope waiting for it).
struct StopOnDrop<'a>(&'a Ahead);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::SweepMethod;
    use crate::math::Vec3;

    /// A block `[-10, 10]²` (every pose inside it is blocked) and a thin hidden
    /// fence on x = 0 for 10 < y < 40 that no pose check sees (it is thinner than
    /// any screen step): only the validator's own edge check rejects an edge across
    /// it, as a continuous check rejects a graze between two screened poses.
    #[derive(Default, Clone)]
    struct HiddenFence {
        certified: usize,
        refused: usize,
        /// Whether [`MotionValidator::fork`] gives a copy (certification on two
        /// cores).
        forks: bool,
    }

    fn crosses_fence(from: &Transform, to: &Transform) -> bool {
        let (a, b) = (from.translation(), to.translation());
        if (a.x < 0.0) == (b.x < 0.0) || a.x == b.x {
            return false;
        }
        let y = a.y + (b.y - a.y) * (-a.x / (b.x - a.x));
        10.0 < y && y < 40.0
    }

    impl MotionValidator for HiddenFence {
        fn is_free(&mut self, pose: &Transform) -> bool {
            let t = pose.translation();
            !(t.x.abs() < 10.0 && t.y.abs() < 10.0)
        }
        fn resolution(&self) -> SweepMethod {
            SweepMethod::CONTINUOUS
        }
        fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
            self.certified += 1;
            let free = stepwise_free(self, from, to) && !crosses_fence(from, to);
            if !free {
                self.refused += 1;
            }
            free
        }
        fn part_radius(&self) -> Option<f64> {
            Some(1.0)
        }
        fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
            self.forks
                .then(|| Box::new(self.clone()) as Box<dyn MotionValidator + Send>)
        }
    }

    fn stepwise_free(v: &mut HiddenFence, from: &Transform, to: &Transform) -> bool {
        super::super::validator::stepwise_edge_free(|p| v.is_free(p), from, to, 0.1, 0.01)
    }

    /// Around the block over the top, the long way: (-20, -20) up to y = 45, across,
    /// and down to (20, 20), every 1 mm.
    fn detour() -> PlannedPath {
        let mut poses = Vec::new();
        let mut walk = |from: Vec3, to: Vec3| {
            let n = ((to - from).norm()).ceil() as usize;
            for k in 0..n {
                poses.push(Transform::from_translation(
                    from.lerp(&to, k as f64 / n as f64),
                ));
            }
        };
        walk(Vec3::new(-20.0, -20.0, 0.0), Vec3::new(-20.0, 45.0, 0.0));
        walk(Vec3::new(-20.0, 45.0, 0.0), Vec3::new(20.0, 45.0, 0.0));
        walk(Vec3::new(20.0, 45.0, 0.0), Vec3::new(20.0, 20.0, 0.0));
        poses.push(Transform::from_translation(Vec3::new(20.0, 20.0, 0.0)));
        PlannedPath::given("test", poses, SweepMethod::DEFAULT)
    }

    fn smoothed(seed: u64) -> (PlannedPath, HiddenFence) {
        smoothed_on(seed, false)
    }

    /// `forks`: the validator can be forked, so certification runs on two cores.
    fn smoothed_on(seed: u64, forks: bool) -> (PlannedPath, HiddenFence) {
        let mut fence = HiddenFence {
            forks,
            ..HiddenFence::default()
        };
        let path = smoothed_with(&mut fence, seed);
        (path, fence)
    }

    /// [`detour`] smoothed with `validator` by the default options, no budget.
    fn smoothed_with(validator: &mut dyn MotionValidator, seed: u64) -> PlannedPath {
        let space = PlanningSpace::new(Vec3::new(-60.0, -60.0, -1.0), Vec3::new(60.0, 60.0, 1.0));
        let mut path = detour();
        smooth(
            validator,
            &space,
            &mut path,
            &Smoothing::default(),
            seed,
            None,
            None,
        );
        path
    }

    #[test]
    fn screened_shortcuts_that_fail_certification_fall_back_to_their_detours() {
        let raw = detour();
        let mut refused = 0;
        for seed in 1..=6 {
            let (path, fence) = smoothed(seed);
            refused += fence.refused;
            assert!(path.poses[0].approx_eq(&raw.poses[0], 0.0, 0.0));
            assert!(path
                .poses
                .last()
                .unwrap()
                .approx_eq(raw.poses.last().unwrap(), 0.0, 0.0));
            assert!(path.length_mm < raw.length_mm, "seed {seed}: not shortened");
            // Every edge is one the validator's own check accepts: none crosses the
            // fence, though pose checks alone would have let them.
            let mut check = HiddenFence::default();
            for (k, w) in path.poses.windows(2).enumerate() {
                assert!(check.is_free(&w[1]), "seed {seed}: pose {} blocked", k + 1);
                assert!(
                    check.edge_free(&w[0], &w[1]),
                    "seed {seed}: edge {k} crosses"
                );
            }
            // Same seed, same path, and the same with certification on two
            // cores: the verdicts do not depend on which core gave them.
            assert_eq!(smoothed(seed).0.poses, path.poses);
            let two = smoothed_on(seed, true).0;
            assert_eq!(two.poses, path.poses, "seed {seed}: two cores");
            assert_eq!(two.edge_checks, path.edge_checks, "seed {seed}: two cores");
        }
        // The fallback was exercised: some screened shortcut failed its
        // certification (the fence is invisible to the screen).
        assert!(refused > 0);
    }

    #[test]
    fn a_worker_that_panics_loses_only_its_verdicts() {
        // The fence, with forks whose edge check panics: smoothing certifies
        // every edge itself and returns the path it returns on one core.
        struct PanickyForks(HiddenFence);
        impl MotionValidator for PanickyForks {
            fn is_free(&mut self, pose: &Transform) -> bool {
                self.0.is_free(pose)
            }
            fn resolution(&self) -> SweepMethod {
                SweepMethod::CONTINUOUS
            }
            fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
                if self.0.forks {
                    panic!("a forked edge check failed");
                }
                self.0.edge_free(from, to)
            }
            fn part_radius(&self) -> Option<f64> {
                Some(1.0)
            }
            fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
                let fork = HiddenFence {
                    forks: true,
                    ..HiddenFence::default()
                };
                Some(Box::new(PanickyForks(fork)))
            }
        }
        for seed in 1..=3 {
            let path = smoothed_with(&mut PanickyForks(HiddenFence::default()), seed);
            assert!(
                path.length_mm < detour().length_mm,
                "seed {seed}: not shortened"
            );
            let mut check = HiddenFence::default();
            for (k, w) in path.poses.windows(2).enumerate() {
                assert!(
                    check.edge_free(&w[0], &w[1]),
                    "seed {seed}: edge {k} crosses"
                );
            }
        }
    }

    #[test]
    fn only_the_shortcuts_left_in_the_path_or_cut_by_later_ones_are_certified() {
        // An open plane: every screened shortcut would pass, and an eager smoothing
        // certifies each one it accepts; the lazy one certifies fewer.
        struct Open(usize);
        impl MotionValidator for Open {
            fn is_free(&mut self, _: &Transform) -> bool {
                true
            }
            fn resolution(&self) -> SweepMethod {
                SweepMethod::CONTINUOUS
            }
            fn edge_free(&mut self, _: &Transform, _: &Transform) -> bool {
                self.0 += 1;
                true
            }
            fn part_radius(&self) -> Option<f64> {
                Some(1.0)
            }
        }
        let mut open = Open(0);
        let path = smoothed_with(&mut open, 1);
        // Straight from start to goal in one edge, after at most a handful of
        // certifications.
        assert_eq!(path.poses.len(), 2);
        assert!(open.0 <= 3, "{} certifications", open.0);
    }
}
