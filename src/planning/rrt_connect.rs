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
mod tests;
