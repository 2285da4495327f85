//! [`rrt_connect`]: the bidirectional RRT (Kuffner & LaValle), fitup's default
//! planner: with scale-free defaults, long-range searches for open space and a
//! narrow-passage search for tight assemblies race on two cores, deterministically.

use super::axis::AxisSearch;
use super::lattice::Lattice;
use super::narrow::NarrowPassage;
use super::path::PlannedPath;
use super::rrt::Ending;
use super::run::{Failure, PlanError, PlanLimits, ProgressFn, Run};
use super::scale::ProblemScale;
use super::smoothing::Smoothing;
use super::space::PlanningSpace;
use super::tree::{begin, steer, Begun, Effort, PoseTarget, Tree};
use super::validator::{Checker, LazyValidation, MotionValidator};
use crate::math::{Deadline, Rng, Transform};
use nalgebra::UnitQuaternion;
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Options of [`rrt_connect`].
#[derive(Debug, Clone, PartialEq)]
pub struct RrtConnectOptions {
    /// Seed and limits (each search of a race has its own iteration count).
    pub limits: PlanLimits,
    /// Largest extension, in metric mm (see [`PlanningSpace`]). `None` (default):
    /// scale-free — every length comes from the problem ([`ProblemScale`]) and two
    /// searches race (see [`rrt_connect`]). `Some(step)`: one search with this
    /// step, and the lengths of `lattice`, `narrow` and `lazy` as given.
    pub step: Option<f64>,
    /// The local discretization tried when an extension or a connection is blocked
    /// (`None`: plain RRT-Connect). Default: [`Lattice::default`] with
    /// [`Lattice::RANDOM_MOVES`] random coordinated moves and
    /// [`Lattice::clearance_turns`]. Its lengths are for a step of
    /// [`RrtConnectOptions::STEP`]; the scale-free narrow-passage search scales them
    /// with its own step.
    pub lattice: Option<Lattice>,
    /// Largest share of the search's work the fallbacks of a blocked extension
    /// may take, in `[0, 1]`: the lattice, extension to contact, bridge-test
    /// sampling and dynamic-domain redraws run only while their work so far is at
    /// most this share of all work (pose and edge checks, clearance queries and
    /// nearest-node scans in pose-check units); past it an iteration is a plain
    /// RRT-Connect one (uniform sample, straight step, the turn-limited retry).
    /// They cost tens of checks where a plain extension costs a few: where plain
    /// extensions make progress (open space, a rod turning a corner) they must not
    /// eat the budget, and where they do not (a part threading a slit, a peg in a
    /// tight hole) they still get their share, and more when the search stalls:
    /// the share doubles for every 10,000 iterations that bring the trees no
    /// closer (up to 1), and returns to this value when they do. Work is counted,
    /// not timed, so the same seed gives the same path. 0: never; 1: always
    /// (fitup before 2026-12). Default 0.1. The long-range search of a race has
    /// no fallbacks.
    pub fallback_share: f64,
    /// Shortcut smoothing of the found path.
    pub smoothing: Smoothing,
    /// Explore with pose checks and certify only the candidate path with the
    /// validator's edge check ([`LazyValidation`]); `None`: every edge is checked
    /// by the validator when it is added. The path is then labelled
    /// `lazy_rrt_connect`. With a scale-free `step` the explored resolution is
    /// derived too: the long-range search's is [`ProblemScale::resolution`], the
    /// narrow-passage search's `step_mm` scaled like its lattice.
    pub lazy: Option<LazyValidation>,
    /// Narrow-passage measures of the extensions and the sampling
    /// ([`NarrowPassage`]). Default [`NarrowPassage::default`]; lengths for a step
    /// of [`RrtConnectOptions::STEP`] (the scale-free narrow-passage search scales
    /// them); the long-range search of a race uses none.
    pub narrow: NarrowPassage,
}

impl RrtConnectOptions {
    /// The reference extension step, metric mm, that the lengths of the default
    /// lattice, narrow-passage measures and lazy resolution were measured with
    /// (issue 23's puzzles, parts of ≈ 25 mm radius: a step below the width of a
    /// passage keeps extensions inside it; 3 mm solved the 7 mm corridor corner
    /// and the zigzag tunnel). The scale-free narrow-passage search's step is
    /// [`ProblemScale::narrow_step`], and it scales those lengths by its ratio to
    /// this one.
    pub const STEP: f64 = 3.0;
}

impl Default for RrtConnectOptions {
    fn default() -> Self {
        Self {
            limits: PlanLimits::default(),
            step: None,
            lattice: Some(Lattice {
                random_moves: Lattice::RANDOM_MOVES,
                clearance_turns: true,
                ..Lattice::default()
            }),
            fallback_share: 0.1,
            smoothing: Smoothing::default(),
            lazy: Some(LazyValidation::default()),
            narrow: NarrowPassage::default(),
        }
    }
}

impl RrtConnectOptions {
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        self.limits.validate()?;
        if let Some(step) = self.step {
            PlanError::positive("step", step)?;
        }
        if let Some(l) = &self.lattice {
            l.validate()?;
        }
        if let Some(l) = &self.lazy {
            l.validate()?;
        }
        self.narrow.validate()?;
        PlanError::probability("fallback_share", self.fallback_share)?;
        self.smoothing.validate()
    }
}

/// How one search extends: its step, fallbacks and exploration resolution, all
/// lengths resolved (metric mm).
#[derive(Debug, Clone)]
struct Strategy {
    step: f64,
    lattice: Option<Lattice>,
    narrow: NarrowPassage,
    /// Lazy exploration `(mm, rad)`, or `None` for the validator's own edge check.
    lazy: Option<(f64, f64)>,
    fallback_share: f64,
    /// Length unit of the axis-move slides (1: mm as given).
    unit: f64,
    /// Translation quantum of the trees' duplicate detection (mm).
    key_mm: f64,
    /// Offset of the search's random stream from the seed's.
    stream: u64,
    /// The rotation weight of the search's metric (mm per rad).
    rotation_weight: f64,
    /// Adaptive reach: the shortest extension (metric mm) a node's reach halves
    /// down to after blocked extensions (`None`: every extension takes `step`).
    reach_floor: Option<f64>,
}

impl Strategy {
    /// The random stream of the second long-range search, which shares the
    /// narrow-passage search's core: the long-range search's time to a path
    /// varies over seeds by 10× and more (alpha-1.5: 723 to 8,519 iterations),
    /// so two independent draws cut its long tail where the narrow-passage
    /// search does not win.
    const SECOND_LONG_RANGE_STREAM: u64 = 0xD1B5_4A32_D192_ED03;

    /// One search with the options as given (`step` explicit).
    fn explicit(options: &RrtConnectOptions, space: &PlanningSpace, step: f64) -> Self {
        Self {
            step,
            lattice: options.lattice.clone(),
            narrow: options.narrow,
            lazy: options.lazy.map(|l| l.steps(space)),
            fallback_share: options.fallback_share,
            unit: 1.0,
            key_mm: key_mm(options.lattice.as_ref(), step),
            stream: 0,
            rotation_weight: space.rotation_weight,
            reach_floor: None,
        }
    }

    /// The long-range search: OMPL's RRT-Connect range and resolution as shares
    /// of the space's metric extent, no fallbacks; what crosses open, twisting
    /// space (a table carried through a house) fastest. Its reach adapts per
    /// node between the range and [`ProblemScale::reach_floor`]: it shrinks
    /// where extensions are blocked and grows back where they go through. Its
    /// metric weighs turns at [`ProblemScale::long_range_rotation_weight`].
    fn long_range(
        options: &RrtConnectOptions,
        space: &PlanningSpace,
        scale: &ProblemScale,
    ) -> Self {
        let step = scale.range();
        let res = scale.resolution();
        Self {
            step,
            lattice: None,
            narrow: NarrowPassage::OFF,
            lazy: options.lazy.map(|_| (res, res / space.rotation_weight)),
            fallback_share: 0.0,
            unit: 1.0,
            key_mm: res * 1e-3,
            stream: 0,
            rotation_weight: scale.long_range_rotation_weight(),
            reach_floor: Some(scale.reach_floor()),
        }
    }

    /// The narrow-passage search: fitup's measures (lattice, turn-limited retry,
    /// dynamic domains, bridge test, axis moves) with every length scaled from
    /// their 3 mm reference to [`ProblemScale::narrow_step`]; what threads a part
    /// through a slit or into a bore.
    fn narrow(options: &RrtConnectOptions, space: &PlanningSpace, scale: &ProblemScale) -> Self {
        let step = scale.narrow_step();
        let k = step / RrtConnectOptions::STEP;
        let lattice = options.lattice.as_ref().map(|l| l.scaled(k));
        Self {
            step,
            key_mm: key_mm(lattice.as_ref(), step),
            lattice,
            narrow: options.narrow.scaled(k),
            lazy: options.lazy.map(|l| {
                let mm = l.step_mm * k;
                (mm, mm / space.rotation_weight)
            }),
            fallback_share: options.fallback_share,
            unit: k,
            stream: 0x9E37_79B9_7F4A_7C15,
            rotation_weight: space.rotation_weight,
            reach_floor: None,
        }
    }
}

/// The duplicate-detection quantum: a quarter of the finest lattice edge, or a
/// thousandth of the step.
fn key_mm(lattice: Option<&Lattice>, step: f64) -> f64 {
    lattice.map_or(step * 1e-3, |l| l.edge_length_min * 0.25)
}

/// One RRT-Connect search, iterated by a driver (one thread, or one of a race).
struct Search<'v, 's> {
    checker: Checker<'v>,
    /// The search's space: the call's, with the strategy's rotation weight.
    space: &'s PlanningSpace,
    s: Strategy,
    trees: [Tree; 2],
    axis: [AxisSearch; 2],
    rng: Rng,
    effort: Effort,
    /// The closest any node came to the other tree's root (metric mm).
    best: f64,
    /// Per tree: how close any node of the other tree has come to its root. A new
    /// node closer than that tries the straight edge to the root (one check, and
    /// only on progress, so open space is crossed in one edge once the trees see
    /// each other's ends).
    closest_to_root: [f64; 2],
    added: Vec<usize>,
    axis_spent: u64,
    /// The tree extending this iteration (0 grows from the start, 1 from the goal).
    a: usize,
    reference: UnitQuaternion<f64>,
}

impl<'v, 's> Search<'v, 's> {
    fn new(
        mut checker: Checker<'v>,
        space: &'s PlanningSpace,
        start: &Transform,
        goal: &Transform,
        s: Strategy,
        seed: u64,
    ) -> Self {
        checker.set_lazy(s.lazy);
        let trees = [Tree::new(*start, s.key_mm), Tree::new(*goal, s.key_mm)];
        let axis = [
            AxisSearch::new(&trees[0], goal, space, s.unit),
            AxisSearch::new(&trees[1], start, space, s.unit),
        ];
        let best = space.distance(start, goal);
        Self {
            checker,
            space,
            rng: Rng::new(seed ^ s.stream),
            effort: Effort::new(s.fallback_share),
            s,
            trees,
            axis,
            best,
            closest_to_root: [best; 2],
            added: Vec::new(),
            axis_spent: 0,
            a: 0,
            reference: start.rotation(),
        }
    }

    fn nodes(&self) -> usize {
        self.trees[0].len() + self.trees[1].len()
    }

    fn work(&self) -> u64 {
        self.checker.cost()
    }

    /// The joined path: from the start tree's node `s` and the goal tree's `g`.
    fn path(&self, (s, g): (usize, usize)) -> Vec<Transform> {
        let mut poses = self.trees[0].branch(s);
        let mut back = self.trees[1].branch(g);
        back.reverse();
        // The meeting pose is in both branches.
        poses.extend(back.into_iter().skip(1));
        poses
    }

    /// Whether the branches to `s` (start tree) and `g` (goal tree) hold: always
    /// when eager; lazily, once both pass the validator's own check (a failed edge
    /// is cut with its subtree, and the search goes on).
    fn certified(&mut self, s: usize, g: usize) -> bool {
        !self.checker.is_lazy()
            || (self.trees[0].certify_branch(s, &mut self.checker)
                && self.trees[1].certify_branch(g, &mut self.checker))
    }

    /// One iteration; the joined nodes (start tree, goal tree) once the trees meet.
    fn iterate(&mut self) -> Option<(usize, usize)> {
        let space = self.space;
        self.effort.iteration(self.best);
        let (a, b) = (self.a, 1 - self.a);
        self.a = b;
        let narrow = self.s.narrow;
        // An axis-move iteration: within its share of the work, expand tree
        // `a`'s best aligned node, and try to meet the other tree from what it
        // added (the other root, or its aligned nodes of the same orientation).
        if narrow.axis_moves > 0.0
            && self.axis[a].has_open()
            && self.axis_spent as f64 <= narrow.axis_moves * self.checker.work() as f64
        {
            let before = self.checker.work();
            let met = self.axis_iteration(a, b);
            self.axis_spent += self.checker.work() - before;
            return met;
        }
        // The bridge test and dynamic-domain redraws are fallbacks: within the
        // share they run, past it the sample is uniform. The extension below
        // always keeps the domains up to date and retries with a limited turn.
        let (sample, near) = narrow.sample_within(
            &mut self.effort,
            &mut self.rng,
            &mut self.checker,
            space,
            &self.reference,
            &self.trees[a],
        );
        self.added.clear();
        let step = self.s.step.min(self.trees[a].reach(near));
        let extended = narrow.extend(
            &mut self.checker,
            space,
            &self.reference,
            &mut self.trees[a],
            near,
            &sample,
            step,
        );
        if let Some(floor) = self.s.reach_floor {
            self.adapt_reach(a, near, step, extended.as_ref().ok().copied(), floor);
        }
        match extended {
            Ok(i) => self.added.push(i),
            Err(candidate) => {
                let other_root = PoseTarget(self.trees[b].poses[0]);
                narrow.fall_back(
                    self.s.lattice.as_ref(),
                    &mut self.effort,
                    &mut self.checker,
                    space,
                    &self.reference,
                    &mut self.trees[a],
                    near,
                    &candidate,
                    &other_root,
                    self.s.step,
                    &mut self.rng,
                    &mut self.added,
                );
            }
        }
        let &last = self.added.last()?;
        let q = self.trees[a].poses[last];
        let root = self.trees[b].poses[0];
        let to_root = space.distance(&q, &root);
        let direct = if to_root < self.closest_to_root[b] {
            self.closest_to_root[b] = to_root;
            self.best = self.best.min(to_root);
            // The meeting pose `q` joins the other tree as a child of its root.
            self.checker
                .edge_free(&root, &q)
                .then(|| self.trees[b].add(q, 0))
        } else {
            None
        };
        let reached = direct.or_else(|| self.connect(b, &q))?;
        let (s, g) = if a == 0 {
            (last, reached)
        } else {
            (reached, last)
        };
        self.certified(s, g).then_some((s, g))
    }

    /// Adaptive reach after an extension of `step` from tree `a`'s node `near`:
    /// blocked, the node's reach halves (down to `floor`); through to `added`,
    /// it doubles back (from the full step on: unbounded again), and the new node
    /// starts with its parent's reach, so a corridor is crossed in short steps
    /// while open space keeps the long ones.
    fn adapt_reach(&mut self, a: usize, near: usize, step: f64, added: Option<usize>, floor: f64) {
        let tree = &mut self.trees[a];
        match added {
            Some(i) => {
                let grown = 2.0 * step;
                let reach = if grown >= self.s.step {
                    f64::INFINITY
                } else {
                    grown
                };
                tree.set_reach(near, reach);
                tree.set_reach(i, reach);
            }
            None => tree.set_reach(near, (0.5 * step).max(floor)),
        }
    }

    /// The axis-move part of an iteration of tree `a` toward tree `b`'s root.
    fn axis_iteration(&mut self, a: usize, b: usize) -> Option<(usize, usize)> {
        let space = self.space;
        self.added.clear();
        let target = self.trees[b].poses[0];
        self.axis[a].expand(
            &mut self.checker,
            space,
            &self.reference,
            &mut self.trees[a],
            &target,
            &mut self.added,
        );
        for k in 0..self.added.len() {
            let i = self.added[k];
            // A failed certification below may have cut it.
            if !self.trees[a].alive(i) {
                continue;
            }
            let q = self.trees[a].poses[i];
            let to_root = space.distance(&q, &target);
            self.best = self.best.min(to_root);
            let mut reached = None;
            // A slide stops at the root's coordinate: from the root's own
            // place only a turn is left, always worth its one check.
            let at_root = (q.translation() - target.translation()).norm() < 1e-9;
            if to_root < self.closest_to_root[b] || at_root {
                self.closest_to_root[b] = self.closest_to_root[b].min(to_root);
                if self.checker.edge_free(&target, &q) {
                    reached = Some(self.trees[b].add(q, 0));
                }
            }
            if reached.is_none() {
                for m in self.axis[b].same_orientation(&self.trees[b], &q) {
                    if self.checker.edge_free(&self.trees[b].poses[m], &q) {
                        reached = Some(self.trees[b].add(q, m));
                        break;
                    }
                }
            }
            if let Some(r) = reached {
                let (s, g) = if a == 0 { (i, r) } else { (r, i) };
                if self.certified(s, g) {
                    return Some((s, g));
                }
            }
        }
        None
    }

    /// Grows tree `t` straight toward `q` in steps; returns the node equal to `q`
    /// when reached. A blocked step tries the lattice once around the blocked node.
    fn connect(&mut self, t: usize, q: &Transform) -> Option<usize> {
        let space = self.space;
        let tree = &mut self.trees[t];
        let (mut node, _) = tree.nearest(q, space);
        let step = self.s.step;
        // Bounded: the distance shrinks by `step` each round, but poses far apart
        // with a tiny step must not stall one iteration for long.
        for _ in 0..10_000 {
            let from = tree.poses[node];
            let d = space.distance(&from, q);
            self.best = self.best.min(d);
            // The straight SE(3) edge toward `q`, not turn-limited: a turn limit
            // would let the translation run ahead of the rotation, and an approach
            // into a bore or a seat needs both to arrive together.
            let next = steer(&from, q, step, space);
            if space.contains(&next, &self.reference) && self.checker.edge_free(&from, &next) {
                node = tree.add(next, node);
                if d <= step {
                    return Some(node);
                }
                continue;
            }
            if let Some(lattice) = &self.s.lattice {
                let mut added = Vec::new();
                let (rng, reference) = (&mut self.rng, &self.reference);
                self.effort.run(&mut self.checker, |checker| {
                    lattice.expand(
                        checker,
                        space,
                        tree,
                        node,
                        &PoseTarget(*q),
                        reference,
                        step,
                        rng,
                        &mut added,
                    );
                });
                if let Some(&last) = added.last() {
                    if space.distance(&tree.poses[last], q) < 1e-9 {
                        return Some(last);
                    }
                }
            }
            return None;
        }
        None
    }
}

/// What a search of a race ended with.
enum Outcome {
    /// The trees met and the path was certified, after `work` (pose-check units).
    Found {
        poses: Vec<Transform>,
        work: u64,
        nodes: usize,
        iterations: usize,
        pose_checks: u64,
        edge_checks: u64,
    },
    /// Another search found its path with less work: this one cannot win.
    Outrun,
    /// Stopped (time or iteration limit, cancelled).
    Failed(Failure, usize, usize),
}

/// What the searches of a race share: the least work at which one found its path
/// (`u64::MAX`: none yet), and the stop signal of a cancelled call.
struct Rival {
    best: AtomicU64,
    stop: AtomicBool,
}

impl Rival {
    fn new() -> Self {
        Self {
            best: AtomicU64::new(u64::MAX),
            stop: AtomicBool::new(false),
        }
    }
}

/// One iteration of `search` within the race, whose lane has done `lane_work`
/// before it: `Some` when it found its path, must stop, or is outrun by a rival
/// that found its path at a lower cost. A path's cost is its lane's work when it
/// was found (the work of every search of the lane), so a search sharing its
/// core wins only with less work than its share of the core allows.
fn step(
    search: &mut Search<'_, '_>,
    lane_work: u64,
    run: &mut Run<'_>,
    rival: &Rival,
) -> Option<Outcome> {
    if rival.stop.load(Ordering::Relaxed) {
        return Some(Outcome::Failed(
            Failure::Cancelled,
            run.iterations,
            search.nodes(),
        ));
    }
    if lane_work > rival.best.load(Ordering::Relaxed) {
        return Some(Outcome::Outrun);
    }
    if let Err(f) = run.next(search.nodes(), search.best) {
        return Some(Outcome::Failed(f, run.iterations, search.nodes()));
    }
    let before = search.work();
    let joined = search.iterate()?;
    let work = lane_work + (search.work() - before);
    rival.best.fetch_min(work, Ordering::Relaxed);
    Some(Outcome::Found {
        poses: search.path(joined),
        work,
        nodes: search.nodes(),
        iterations: run.iterations,
        pose_checks: search.checker.pose_checks,
        edge_checks: search.checker.edge_checks,
    })
}

/// The race's winner: the path found at the lowest cost (the first search on a
/// tie); without one, the first search's failure.
fn winner(outcomes: Vec<Outcome>) -> Outcome {
    let mut best: Option<Outcome> = None;
    let mut first_failure = None;
    for o in outcomes {
        match o {
            Outcome::Found { work, .. } => {
                let better = match &best {
                    Some(Outcome::Found { work: w, .. }) => work < *w,
                    _ => true,
                };
                if better {
                    best = Some(o);
                }
            }
            Outcome::Failed(..) if first_failure.is_none() => first_failure = Some(o),
            _ => {}
        }
    }
    best.or(first_failure)
        .unwrap_or(Outcome::Failed(Failure::Cancelled, 0, 0))
}

/// The problem every search of a race solves.
struct Problem<'a> {
    space: &'a PlanningSpace,
    start: &'a Transform,
    goal: &'a Transform,
    seed: u64,
    deadline: Deadline,
}

impl Problem<'_> {
    /// The space of a search with `strategy`: the call's, with the strategy's
    /// rotation weight.
    fn space_for(&self, strategy: &Strategy) -> PlanningSpace {
        self.space
            .clone()
            .with_rotation_weight(strategy.rotation_weight)
    }

    /// A search of this problem with `strategy` in `space`, checking through
    /// `checker`.
    fn search<'v, 's>(
        &self,
        checker: Checker<'v>,
        space: &'s PlanningSpace,
        strategy: Strategy,
    ) -> Search<'v, 's> {
        Search::new(checker, space, self.start, self.goal, strategy, self.seed)
    }

    /// The searches of `lane`, each checking through one of `views`.
    fn searches<'v, 's>(
        &self,
        views: &'v mut [Shared<'_, '_>],
        lane: Vec<(Strategy, &'s PlanningSpace)>,
    ) -> Vec<Search<'v, 's>> {
        views
            .iter_mut()
            .zip(lane)
            .map(|(v, (strategy, space))| {
                self.search(Checker::new(v, Some(self.deadline)), space, strategy)
            })
            .collect()
    }
}

/// Races `lanes` of strategies (at least one strategy in the first lane): the
/// first lane on this thread with the call's progress, each other lane in a
/// thread of its own on a fork of the validator, the strategies of a lane
/// interleaved on its thread ([`interleave`]). When the validator cannot be
/// forked, every lane is interleaved on this thread. The same winner either way:
/// the path found at the lowest cost (its lane's work, see [`step`]), the first
/// strategy (lane by lane) on a tie, whichever thread finished first.
fn race(
    validator: &mut dyn MotionValidator,
    lanes: Vec<Vec<Strategy>>,
    p: &Problem<'_>,
    run: &mut Run<'_>,
) -> Outcome {
    let rival = Rival::new();
    let spaces: Vec<Vec<PlanningSpace>> = lanes
        .iter()
        .map(|lane| lane.iter().map(|s| p.space_for(s)).collect())
        .collect();
    let mut lanes: Vec<Vec<(Strategy, &PlanningSpace)>> = lanes
        .into_iter()
        .zip(&spaces)
        .map(|(lane, spaces)| lane.into_iter().zip(spaces).collect())
        .collect();
    let others = lanes.split_off(1);
    let forks: Option<Vec<Box<dyn MotionValidator + Send>>> =
        others.iter().map(|_| validator.fork()).collect();
    let Some(forks) = forks else {
        lanes.extend(others);
        return winner(run_lanes(validator, lanes, p, run, &rival));
    };
    let first = lanes.pop().expect("a first lane");
    let outcomes = std::thread::scope(|scope| {
        let handles: Vec<_> = forks
            .into_iter()
            .zip(others)
            .map(|(mut v, lane)| {
                let rival = &rival;
                let clock = run.clock();
                scope.spawn(move || {
                    let mut sibling = Run::of_clock(clock);
                    run_lanes(&mut *v, vec![lane], p, &mut sibling, rival)
                })
            })
            .collect();
        let mut all = run_lanes(validator, vec![first], p, run, &rival);
        for h in handles {
            // A search that panicked is a bug; its lane loses the race rather
            // than taking the call down.
            all.extend(h.join().unwrap_or_else(|_| vec![Outcome::Outrun]));
        }
        all
    });
    winner(outcomes)
}

/// The outcomes of `lanes` of searches, [`interleave`]d on this thread, each
/// search checking through its own view of `validator`.
fn run_lanes(
    validator: &mut dyn MotionValidator,
    lanes: Vec<Vec<(Strategy, &PlanningSpace)>>,
    p: &Problem<'_>,
    run: &mut Run<'_>,
    rival: &Rival,
) -> Vec<Outcome> {
    let shared = RefCell::new(validator);
    let mut views: Vec<Vec<Shared<'_, '_>>> = lanes
        .iter()
        .map(|lane| lane.iter().map(|_| Shared(&shared)).collect())
        .collect();
    let mut searches: Vec<Vec<Search<'_, '_>>> = views
        .iter_mut()
        .zip(lanes)
        .map(|(views, lane)| p.searches(views, lane))
        .collect();
    interleave(&mut searches, run, rival)
}

/// Runs `lanes` of searches on this thread to their outcomes (lane by lane,
/// search by search): the lane with the least work so far (the first on a tie)
/// advances its search with the least work so far by one iteration, so each
/// lane's schedule, and with it the cost of every path, is the same whether the
/// lanes share this thread or run on threads of their own. The first search's
/// run reports progress, and its cancellation stops the others.
fn interleave(lanes: &mut [Vec<Search<'_, '_>>], run: &mut Run<'_>, rival: &Rival) -> Vec<Outcome> {
    let total: usize = lanes.iter().map(Vec::len).sum();
    let mut runs: Vec<Run<'_>> = (1..total).map(|_| run.sibling()).collect();
    let mut done: Vec<Vec<Option<Outcome>>> = lanes
        .iter()
        .map(|l| l.iter().map(|_| None).collect())
        .collect();
    let lane_work = |lane: &[Search<'_, '_>]| lane.iter().map(Search::work).sum::<u64>();
    loop {
        let open = |l: usize, i: usize, done: &Vec<Vec<Option<Outcome>>>| done[l][i].is_none();
        let Some(l) = (0..lanes.len())
            .filter(|&l| (0..lanes[l].len()).any(|i| open(l, i, &done)))
            .min_by_key(|&l| (lane_work(&lanes[l]), l))
        else {
            break;
        };
        let i = (0..lanes[l].len())
            .filter(|&i| open(l, i, &done))
            .min_by_key(|&i| (lanes[l][i].work(), i))
            .expect("an open search");
        let work = lane_work(&lanes[l]);
        let flat = lanes[..l].iter().map(Vec::len).sum::<usize>() + i;
        let r = if flat == 0 {
            &mut *run
        } else {
            &mut runs[flat - 1]
        };
        if let Some(o) = step(&mut lanes[l][i], work, r, rival) {
            if flat == 0 && matches!(o, Outcome::Failed(Failure::Cancelled, ..)) {
                rival.stop.store(true, Ordering::Relaxed);
            }
            done[l][i] = Some(o);
        }
    }
    done.into_iter().flatten().flatten().collect()
}

/// A view of one validator shared by the searches of an interleaved race (one
/// thread: each call borrows it in turn).
struct Shared<'c, 'v>(&'c RefCell<&'v mut dyn MotionValidator>);

impl MotionValidator for Shared<'_, '_> {
    fn is_free(&mut self, pose: &Transform) -> bool {
        self.0.borrow_mut().is_free(pose)
    }
    fn resolution(&self) -> crate::collision::SweepMethod {
        self.0.borrow().resolution()
    }
    fn tolerance(&self) -> f64 {
        self.0.borrow().tolerance()
    }
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        self.0.borrow_mut().edge_free(from, to)
    }
    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        self.0.borrow_mut().clearance(pose)
    }
    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.0.borrow_mut().set_deadline(deadline)
    }
    fn part_radius(&self) -> Option<f64> {
        self.0.borrow().part_radius()
    }
    fn part_thickness(&self) -> Option<f64> {
        self.0.borrow().part_thickness()
    }
}

/// Plans from `start` to `goal` with two trees, one rooted at each end.
///
/// Each iteration extends one tree toward a uniform sample, then grows the other
/// tree straight toward the new node until it is reached (a path) or blocked; the
/// trees then swap roles. With a [`Lattice`], a blocked extension or connection
/// falls back to the local discretization around the blocked node, ranked by the
/// distance to the other tree's root (or to the node being connected to), which
/// lets the trees creep through narrow passages.
///
/// **Scale-free defaults** (`step: None`): every length comes from the problem
/// ([`ProblemScale`]), and three searches race on two cores: a long-range search
/// ([`ProblemScale::range`], explored at [`ProblemScale::resolution`], no
/// fallbacks — open, twisting spaces) on this thread, and on a second thread (a
/// [`fork`](MotionValidator::fork) of the validator) the narrow-passage search
/// ([`ProblemScale::narrow_step`] with every measure of [`NarrowPassage`] and the
/// lattice — tight assembly clearances) interleaved with a second long-range
/// search on another random stream (the long-range search's time to a path varies
/// by 10× over seeds; a second draw cuts the tail). The path found at the lowest
/// cost wins, whichever thread finished first: a path's cost is the work
/// (pose-check units) its thread had done when it was found, and a thread stops
/// only once its work is past the lowest cost found, so the same seed gives the
/// same path. Counts in the returned path are the winning search's.
///
/// # Errors
/// Invalid options, bounds or non-finite poses.
pub fn rrt_connect(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &RrtConnectOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    let name = if options.lazy.is_some() {
        "lazy_rrt_connect"
    } else {
        "rrt_connect"
    };
    options.validate()?;
    let ends = (start, Some(goal));
    let (mut run, mut checker) =
        match begin(name, validator, space, ends, options.limits, progress)? {
            Begun::Ready(run, checker) => (run, checker),
            Begun::Refused(path) => return Ok(path),
        };
    let ending = Ending::new(name, space, &options.smoothing, options.limits.seed);
    // A free straight line is the answer, found with one edge check before any tree
    // grows: a sampling search almost never draws it when the passage around it is
    // tight (a plate slid onto a pin with 0.2 mm clearance).
    if checker.edge_free(start, goal) {
        return Ok(ending.finish(vec![*start, *goal], 2, &mut checker, &mut run));
    }
    let seed = options.limits.seed;
    let lanes = match options.step {
        Some(step) => vec![vec![Strategy::explicit(options, space, step)]],
        None => {
            let scale = checker.scale(space);
            let long_range = Strategy::long_range(options, space, &scale);
            let second = Strategy {
                stream: Strategy::SECOND_LONG_RANGE_STREAM,
                ..long_range.clone()
            };
            vec![
                vec![long_range],
                vec![Strategy::narrow(options, space, &scale), second],
            ]
        }
    };
    let ends = (checker.pose_checks, checker.edge_checks);
    drop(checker);
    let problem = Problem {
        space,
        start,
        goal,
        seed,
        deadline: run.deadline(),
    };
    let outcome = race(&mut *validator, lanes, &problem, &mut run);
    let mut checker = Checker::new(validator, Some(run.deadline()));
    match outcome {
        Outcome::Found {
            poses,
            nodes,
            iterations,
            pose_checks,
            edge_checks,
            ..
        } => {
            // The counts are the winning search's (and the ends' checks), on
            // whichever thread it ran.
            checker.pose_checks = ends.0 + pose_checks;
            checker.edge_checks = ends.1 + edge_checks;
            run.iterations = iterations;
            // Smoothing keeps only edges the validator itself accepts.
            Ok(ending.finish(poses, nodes, &mut checker, &mut run))
        }
        Outcome::Failed(f, iterations, nodes) => Ok(PlannedPath::failed(
            name,
            f,
            iterations,
            nodes,
            &checker,
            run.elapsed_ms(),
        )),
        Outcome::Outrun => Ok(PlannedPath::failed(
            name,
            Failure::Cancelled,
            run.iterations,
            0,
            &checker,
            run.elapsed_ms(),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::Collider;
    use crate::math::{Point3, Vec3};
    use crate::mesh::Mesh;
    use crate::planning::{MeshValidator, MeshValidatorOptions};
    use std::sync::Arc;

    /// A wall 2k thick at x = 0 with a square window of half width 8k, and a cube
    /// of side 10k that must pass it from y = 20k on one side to y = 20k on the
    /// other (the straight line hits the wall), in bounds 80k × 80k × 40k; all
    /// lengths times `k`.
    fn window(k: f64) -> (MeshValidator, PlanningSpace, Transform, Transform) {
        let collider = |lo: [f64; 3], hi: [f64; 3]| {
            let m = Mesh::cuboid(
                Point3::new(lo[0] * k, lo[1] * k, lo[2] * k),
                Point3::new(hi[0] * k, hi[1] * k, hi[2] * k),
            );
            Arc::new(Collider::new(Arc::new(m)).unwrap())
        };
        let wall = [
            ([-1.0, -40.0, 8.0], [1.0, 40.0, 20.0]),
            ([-1.0, -40.0, -20.0], [1.0, 40.0, -8.0]),
            ([-1.0, 8.0, -8.0], [1.0, 40.0, 8.0]),
            ([-1.0, -40.0, -8.0], [1.0, -8.0, 8.0]),
        ];
        let obstacles = wall
            .iter()
            .map(|(lo, hi)| (collider(*lo, *hi), Transform::IDENTITY))
            .collect();
        let cube = collider([-5.0; 3], [5.0; 3]);
        let radius = cube.radius();
        let v = MeshValidator::new(cube, obstacles, MeshValidatorOptions::default()).unwrap();
        let space = PlanningSpace::new(
            Vec3::new(-40.0, -40.0, -20.0) * k,
            Vec3::new(40.0, 40.0, 20.0) * k,
        )
        .with_rotation_weight(radius);
        let at = |x: f64| Transform::from_translation(Vec3::new(x * k, 20.0 * k, 0.0));
        (v, space, at(-30.0), at(30.0))
    }

    /// The mesh validator without [`MotionValidator::fork`]: its race runs
    /// interleaved on one thread.
    struct OneThread(MeshValidator);

    impl MotionValidator for OneThread {
        fn is_free(&mut self, pose: &Transform) -> bool {
            self.0.is_free(pose)
        }
        fn resolution(&self) -> crate::collision::SweepMethod {
            self.0.resolution()
        }
        fn tolerance(&self) -> f64 {
            self.0.tolerance()
        }
        fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
            self.0.edge_free(from, to)
        }
        fn clearance(&mut self, pose: &Transform) -> Option<f64> {
            self.0.clearance(pose)
        }
        fn set_deadline(&mut self, deadline: Option<Deadline>) {
            self.0.set_deadline(deadline)
        }
        fn part_radius(&self) -> Option<f64> {
            self.0.part_radius()
        }
        fn part_thickness(&self) -> Option<f64> {
            self.0.part_thickness()
        }
    }

    fn options(seed: u64) -> RrtConnectOptions {
        let mut o = RrtConnectOptions::default();
        o.limits.seed = seed;
        o.limits.max_iterations = 200_000;
        o.limits.time_limit_ms = Some(120_000.0);
        o.smoothing = Smoothing::OFF;
        o
    }

    #[test]
    fn the_race_finds_the_same_path_on_two_threads_and_on_one() {
        for seed in 0..4 {
            let (mut v, space, start, goal) = window(1.0);
            let o = options(seed);
            let two = rrt_connect(&mut v, &space, &start, &goal, &o, None).unwrap();
            assert!(two.found(), "seed {seed}: {:?}", two.failure);
            let (v, ..) = window(1.0);
            let one = rrt_connect(&mut OneThread(v), &space, &start, &goal, &o, None).unwrap();
            assert_eq!(one.poses, two.poses, "seed {seed}");
            assert_eq!(
                (one.iterations, one.nodes, one.pose_checks, one.edge_checks),
                (two.iterations, two.nodes, two.pose_checks, two.edge_checks),
                "seed {seed}"
            );
            let (mut v, ..) = window(1.0);
            let again = rrt_connect(&mut v, &space, &start, &goal, &o, None).unwrap();
            assert_eq!(again.poses, two.poses, "seed {seed}: same seed, same path");
        }
    }

    /// Free space a ball of radius 12 about the origin: every extension of 40
    /// from the centre leaves it, one of 10 stays inside.
    struct Ball;

    impl MotionValidator for Ball {
        fn is_free(&mut self, pose: &Transform) -> bool {
            pose.translation().norm() <= 12.0
        }
    }

    /// The long-range search's adaptive reach: blocked extensions halve a node's
    /// reach down to the floor, where the search grows again; without it (the
    /// narrow search's fixed step) the tree never leaves its root.
    #[test]
    fn a_blocked_node_shrinks_its_reach_down_to_the_floor_and_grows_again() {
        let space = PlanningSpace::new(
            Vec3::new(-100.0, -100.0, -100.0),
            Vec3::new(100.0, 100.0, 100.0),
        )
        .with_rotation_weight(1.0);
        let o = RrtConnectOptions::default();
        let strategy = |floor: Option<f64>| Strategy {
            reach_floor: floor,
            lazy: Some((1.0, 1.0)),
            narrow: NarrowPassage::OFF,
            lattice: None,
            fallback_share: 0.0,
            ..Strategy::explicit(&o, &space, 40.0)
        };
        let start = Transform::IDENTITY;
        let goal = Transform::from_translation(Vec3::new(90.0, 0.0, 0.0));
        let grown = |floor: Option<f64>| {
            let mut v = Ball;
            let checker = Checker::new(&mut v, None);
            let mut search = Search::new(checker, &space, &start, &goal, strategy(floor), 7);
            let mut lowest = f64::INFINITY;
            for _ in 0..400 {
                search.iterate();
                lowest = lowest.min(search.trees[0].reach(0));
            }
            let tree = &search.trees[0];
            let inside = (0..tree.len()).all(|i| tree.poses[i].translation().norm() <= 12.0);
            (tree.len(), lowest, inside)
        };
        let (nodes, lowest, inside) = grown(Some(10.0));
        // Nodes near the ball's surface block at the floor too, and a uniform
        // sample of the large space is nearest to one of them: a few nodes.
        assert!(nodes >= 3, "the tree grows at the floor: {nodes} nodes");
        assert!(inside, "every node is free");
        assert_eq!(lowest, 10.0, "the root's reach halved from 40 to the floor");
        let (fixed, ..) = grown(None);
        assert_eq!(fixed, 1, "with a fixed reach of 40 nothing is added");
    }

    /// Scale-free defaults: every length of both searches follows the problem, so
    /// the same problem 10× larger gets the same strategies with every length 10×.
    #[test]
    fn the_strategies_scale_with_the_problem() {
        let o = RrtConnectOptions::default();
        let at = |k: f64| {
            let (v, space, ..) = window(k);
            let scale = ProblemScale::of(&space, &v);
            (
                Strategy::long_range(&o, &space, &scale),
                Strategy::narrow(&o, &space, &scale),
            )
        };
        let close = |a: f64, b: f64| (a * 10.0 - b).abs() <= 1e-9 * b.abs().max(1.0);
        let ((l1, n1), (l10, n10)) = (at(1.0), at(10.0));
        for (a, b) in [(&l1, &l10), (&n1, &n10)] {
            assert!(close(a.step, b.step), "step {} → {}", a.step, b.step);
            assert!(close(a.key_mm, b.key_mm));
            assert!(close(a.rotation_weight, b.rotation_weight));
            let (la, lb) = (a.lazy.unwrap(), b.lazy.unwrap());
            assert!(
                close(la.0, lb.0) && (la.1 - lb.1).abs() < 1e-12,
                "{la:?} → {lb:?}"
            );
        }
        let (la, lb) = (n1.lattice.unwrap(), n10.lattice.unwrap());
        assert!(close(la.edge_length_max, lb.edge_length_max));
        assert!(close(la.edge_length_min, lb.edge_length_min));
        assert_eq!(la.alpha, lb.alpha, "angles do not scale");
        assert!(close(n1.unit, n10.unit));
        assert!(close(n1.narrow.bridge_width, n10.narrow.bridge_width));
        assert!(close(
            n1.narrow.dynamic_domain.unwrap(),
            n10.narrow.dynamic_domain.unwrap()
        ));
        assert!(l1.lattice.is_none() && l1.narrow == NarrowPassage::OFF);
    }

    /// The same defaults solve the window at a tenth, at one and at ten times its
    /// size, and every path they return is free pose by pose and edge by edge.
    /// (Not the identical path: the validator's contact resolution, 0.01 mm, is a
    /// physical length, and the narrow search moves to contact.)
    #[test]
    fn the_defaults_solve_the_problem_at_every_scale() {
        for k in [0.1, 1.0, 10.0] {
            for seed in 0..3 {
                let (mut v, space, start, goal) = window(k);
                let p = rrt_connect(&mut v, &space, &start, &goal, &options(seed), None).unwrap();
                assert!(p.found(), "k {k} seed {seed}: {:?}", p.failure);
                assert!(p.poses.iter().all(|q| v.is_free(q)), "k {k} seed {seed}");
                assert!(
                    p.poses.windows(2).all(|w| v.edge_free(&w[0], &w[1])),
                    "k {k} seed {seed}"
                );
            }
        }
    }

    /// The goal tree's edges are certified from parent to child and run backwards
    /// in the path: the validator's verdict must not depend on the direction. This
    /// edge of the window scene (k = 1, seed 2, the second long-range search's
    /// path) grazes the window's frame: swept from its first pose it was refused,
    /// from its second accepted, and the path failed its own edge check.
    #[test]
    fn an_edge_has_the_same_verdict_both_ways() {
        let (mut v, ..) = window(1.0);
        let pose = |m: [[f64; 4]; 4]| Transform::from_matrix(&m).unwrap();
        let a = pose([
            [
                0.9885727391935328,
                -0.12498714508365366,
                0.0842742717988983,
                0.0,
            ],
            [
                -0.06556757308729438,
                0.1468835829871868,
                0.9869782704843557,
                0.0,
            ],
            [
                -0.13573810328289984,
                -0.9812254718527671,
                0.137010002205959,
                0.0,
            ],
            [
                -2.669005523283383,
                -1.3046986378261967,
                -0.9715228055244611,
                1.0,
            ],
        ]);
        let b = pose([
            [
                0.9509198006394701,
                0.10909576000420058,
                0.2895680367390304,
                0.0,
            ],
            [
                -0.3083368368000792,
                0.2552090752573958,
                0.9164042355742286,
                0.0,
            ],
            [
                0.026075425670771396,
                -0.9607114254839331,
                0.276321604513142,
                0.0,
            ],
            [
                11.305915399783231,
                -2.0120772362623,
                -1.396330613993733,
                1.0,
            ],
        ]);
        assert!(v.is_free(&a) && v.is_free(&b));
        assert_eq!(v.edge_free(&a, &b), v.edge_free(&b, &a));
        // And on random short edges between free poses about the window's frame.
        let mut rng = Rng::new(7);
        let mut u = |h: f64| (2.0 * rng.uniform() - 1.0) * h;
        let (mut near_contact, mut tried) = (0, 0);
        for _ in 0..3000 {
            // From one side of the wall to the other, through or past the window.
            let p = Transform::from_translation(Vec3::new(-9.0 + u(3.0), u(5.0), u(5.0)));
            let q = Transform::from_translation(Vec3::new(9.0 + u(3.0), u(5.0), u(5.0)));
            let turn = Transform::from_rotation_about(
                Point3::from(q.translation()),
                Vec3::new(u(1.0), u(1.0), u(1.0)).normalize(),
                u(0.6),
            )
            .unwrap();
            let q = q.then(&turn);
            if v.is_free(&p) && v.is_free(&q) {
                tried += 1;
                let there = v.edge_free(&p, &q);
                near_contact += usize::from(!there);
                assert_eq!(there, v.edge_free(&q, &p), "{p:?} -> {q:?}");
            }
        }
        assert!(
            tried > 200 && near_contact > 10,
            "{near_contact} blocked of {tried} edges: the sample misses the frame"
        );
    }
}
