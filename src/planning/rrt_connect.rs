//! [`rrt_connect`]: the bidirectional RRT (Kuffner & LaValle), with seed 002's local
//! discretization as a fallback when an extension fails.

use super::axis::AxisSearch;
use super::lattice::Lattice;
use super::narrow::NarrowPassage;
use super::path::PlannedPath;
use super::rrt::finish;
use super::run::{PlanError, PlanLimits, ProgressFn, Run};
use super::smoothing::Smoothing;
use super::space::PlanningSpace;
use super::tree::{check_ends, steer, Effort, PoseTarget, Tree};
use super::validator::{Checker, LazyValidation, MotionValidator};
use crate::math::{Rng, Transform};

/// Options of [`rrt_connect`].
#[derive(Debug, Clone, PartialEq)]
pub struct RrtConnectOptions {
    /// Seed and limits.
    pub limits: PlanLimits,
    /// Largest extension, in metric mm (see [`PlanningSpace`]). Default
    /// [`RrtConnectOptions::STEP`], 3.
    pub step: f64,
    /// The local discretization tried when an extension or a connection is blocked
    /// (`None`: plain RRT-Connect). Default: [`Lattice::default`] with
    /// [`Lattice::RANDOM_MOVES`] random coordinated moves and
    /// [`Lattice::clearance_turns`].
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
    /// (fitup before 2026-12). Default 0.1.
    pub fallback_share: f64,
    /// Shortcut smoothing of the found path.
    pub smoothing: Smoothing,
    /// Explore with pose checks and certify only the candidate path with the
    /// validator's edge check ([`LazyValidation`]); `None`: every edge is checked
    /// by the validator when it is added. The path is then labelled
    /// `lazy_rrt_connect`.
    pub lazy: Option<LazyValidation>,
    /// Narrow-passage measures of the extensions and the sampling
    /// ([`NarrowPassage`]). Default [`NarrowPassage::default`].
    pub narrow: NarrowPassage,
}

impl RrtConnectOptions {
    /// The default extension step, metric mm. Measured on issue 23's puzzles
    /// (docs/performance.md, "Issue 23, round 4"): a step below the width of a
    /// passage keeps extensions inside it. In a 7 mm corridor a 10 mm step ends
    /// in a wall almost every time (97 % of the extensions of the rod round the
    /// corner were blocked); 3 mm solved the corridor corner 30× and the zigzag
    /// tunnel from 0/5 to 5/5, and the open puzzles (house, tubes) kept their
    /// times, since a node that comes closer to the other tree's root tries the
    /// straight edge to it whatever the step.
    pub const STEP: f64 = 3.0;
}

impl Default for RrtConnectOptions {
    fn default() -> Self {
        Self {
            limits: PlanLimits::default(),
            step: Self::STEP,
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
        PlanError::positive("step", self.step)?;
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

/// Plans from `start` to `goal` with two trees, one rooted at each end.
///
/// Each iteration extends one tree by `step` toward a uniform sample, then grows the
/// other tree straight toward the new node until it is reached (a path) or blocked;
/// the trees then swap roles. With a [`Lattice`], a blocked extension or connection
/// falls back to the local discretization around the blocked node, ranked by the
/// distance to the other tree's root (or to the node being connected to), which
/// lets the trees creep through narrow passages.
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
    space.validate()?;
    PlanError::pose("start", start)?;
    PlanError::pose("goal", goal)?;
    let mut run = Run::new(options.limits, progress);
    let mut checker = Checker::new(validator, Some(run.deadline()));
    if let Some(f) = check_ends(&mut checker, space, start, Some(goal)) {
        return Ok(PlannedPath::failed(
            name,
            f,
            0,
            0,
            &checker,
            run.elapsed_ms(),
        ));
    }
    // A free straight line is the answer, found with one edge check before any tree
    // grows: a sampling search almost never draws it when the passage around it is
    // tight (a plate slid onto a pin with 0.2 mm clearance).
    if checker.edge_free(start, goal) {
        return Ok(finish(
            name,
            vec![*start, *goal],
            &mut checker,
            space,
            &options.smoothing,
            options.limits.seed,
            &mut run,
            2,
        ));
    }
    checker.set_lazy(options.lazy.map(|l| l.steps(space)));
    let mut rng = Rng::new(options.limits.seed);
    let reference = start.rotation();
    let key_mm = options
        .lattice
        .as_ref()
        .map_or(options.step * 1e-3, |l| l.edge_length_min * 0.25);
    // trees[0] grows from the start, trees[1] from the goal; `a` is the one extending.
    let mut trees = [Tree::new(*start, key_mm), Tree::new(*goal, key_mm)];
    let mut a = 0;
    let mut best = space.distance(start, goal);
    // Per tree: how close any node of the other tree has come to its root. A new node
    // closer than that tries the straight edge to the root (one check, and only on
    // progress, so open space is crossed in one edge once the trees see each other's
    // ends).
    let mut closest_to_root = [best; 2];
    let mut added = Vec::new();
    let mut effort = Effort::new(options.fallback_share);
    // The axis-move search of each tree, toward the other tree's root, and the
    // work it has done (pose-check units, like the fallbacks' share).
    let mut axis = [
        AxisSearch::new(&trees[0], goal, space),
        AxisSearch::new(&trees[1], start, space),
    ];
    let mut axis_spent = 0u64;
    let joined = loop {
        effort.iteration(best);
        if let Err(f) = run.next(trees[0].len() + trees[1].len(), best) {
            break Err(f);
        }
        let b = 1 - a;
        let narrow = &options.narrow;
        // An axis-move iteration: within its share of the work, expand tree
        // `a`'s best aligned node, and try to meet the other tree from what it
        // added (the other root, or its aligned nodes of the same orientation).
        if narrow.axis_moves > 0.0
            && axis[a].has_open()
            && axis_spent as f64 <= narrow.axis_moves * checker.work() as f64
        {
            let before = checker.work();
            added.clear();
            let target = trees[b].poses[0];
            axis[a].expand(
                &mut checker,
                space,
                &reference,
                &mut trees[a],
                &target,
                &mut added,
            );
            let mut met = None;
            for &i in &added {
                // A failed certification below may have cut it.
                if !trees[a].alive(i) {
                    continue;
                }
                let q = trees[a].poses[i];
                let to_root = space.distance(&q, &target);
                best = best.min(to_root);
                let mut reached = None;
                // A slide stops at the root's coordinate: from the root's own
                // place only a turn is left, always worth its one check.
                let at_root = (q.translation() - target.translation()).norm() < 1e-9;
                if to_root < closest_to_root[b] || at_root {
                    closest_to_root[b] = closest_to_root[b].min(to_root);
                    if checker.edge_free(&target, &q) {
                        reached = Some(trees[b].add(q, 0));
                    }
                }
                if reached.is_none() {
                    for m in axis[b].same_orientation(&trees[b], &q) {
                        if checker.edge_free(&trees[b].poses[m], &q) {
                            reached = Some(trees[b].add(q, m));
                            break;
                        }
                    }
                }
                if let Some(r) = reached {
                    let (s, g) = if a == 0 { (i, r) } else { (r, i) };
                    if !checker.is_lazy()
                        || (trees[0].certify_branch(s, &mut checker)
                            && trees[1].certify_branch(g, &mut checker))
                    {
                        met = Some((s, g));
                        break;
                    }
                }
            }
            axis_spent += checker.work() - before;
            if let Some(m) = met {
                break Ok(m);
            }
            a = b;
            continue;
        }
        // The bridge test and dynamic-domain redraws are fallbacks: within the
        // share they run, past it the sample is uniform. The extension below
        // always keeps the domains up to date and retries with a limited turn.
        let (sample, near) = narrow.sample_within(
            &mut effort,
            &mut rng,
            &mut checker,
            space,
            &reference,
            &trees[a],
        );
        added.clear();
        let extended = narrow.extend(
            &mut checker,
            space,
            &reference,
            &mut trees[a],
            near,
            &sample,
            options.step,
        );
        if let Err(candidate) = extended {
            let other_root = PoseTarget(trees[b].poses[0]);
            narrow.fall_back(
                options.lattice.as_ref(),
                &mut effort,
                &mut checker,
                space,
                &reference,
                &mut trees[a],
                near,
                &candidate,
                &other_root,
                options.step,
                &mut rng,
                &mut added,
            );
        }
        if let Ok(i) = extended {
            added.push(i);
        }
        if let Some(&last) = added.last() {
            let q = trees[a].poses[last];
            let root = trees[b].poses[0];
            let to_root = space.distance(&q, &root);
            let direct = if to_root < closest_to_root[b] {
                closest_to_root[b] = to_root;
                best = best.min(to_root);
                // The meeting pose `q` joins the other tree as a child of its root.
                checker.edge_free(&root, &q).then(|| trees[b].add(q, 0))
            } else {
                None
            };
            if let Some(reached) = direct.or_else(|| {
                connect(
                    &mut checker,
                    space,
                    &mut trees[b],
                    &q,
                    &reference,
                    options,
                    &mut best,
                    &mut rng,
                    &mut effort,
                )
            }) {
                let (s, g) = if a == 0 {
                    (last, reached)
                } else {
                    (reached, last)
                };
                // Lazy: the trees met through explored edges; the path is found
                // once both branches pass the validator's own check (a failed edge
                // is cut with its subtree, and the search goes on).
                if !checker.is_lazy()
                    || (trees[0].certify_branch(s, &mut checker)
                        && trees[1].certify_branch(g, &mut checker))
                {
                    break Ok((s, g));
                }
            }
        }
        a = b;
    };
    let nodes = trees[0].len() + trees[1].len();
    match joined {
        Err(f) => Ok(PlannedPath::failed(
            name,
            f,
            run.iterations,
            nodes,
            &checker,
            run.elapsed_ms(),
        )),
        Ok((from_start, from_goal)) => {
            let mut poses = trees[0].branch(from_start);
            let mut back = trees[1].branch(from_goal);
            back.reverse();
            // The meeting pose is in both branches.
            poses.extend(back.into_iter().skip(1));
            // Smoothing keeps only edges the validator itself accepts.
            checker.set_lazy(None);
            Ok(finish(
                name,
                poses,
                &mut checker,
                space,
                &options.smoothing,
                options.limits.seed,
                &mut run,
                nodes,
            ))
        }
    }
}

/// Grows `tree` straight toward `q` in `step`s; returns the node equal to `q` when
/// reached. A blocked step tries the lattice once around the blocked node.
#[allow(clippy::too_many_arguments)]
fn connect(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    tree: &mut Tree,
    q: &Transform,
    reference: &nalgebra::UnitQuaternion<f64>,
    options: &RrtConnectOptions,
    best: &mut f64,
    rng: &mut Rng,
    effort: &mut Effort,
) -> Option<usize> {
    let (mut node, _) = tree.nearest(q, space);
    // Bounded: the distance shrinks by `step` each round, but poses far apart with a
    // tiny step must not stall one iteration for long.
    for _ in 0..10_000 {
        let from = tree.poses[node];
        let d = space.distance(&from, q);
        *best = best.min(d);
        // The straight SE(3) edge toward `q`, not turn-limited: a turn limit would
        // let the translation run ahead of the rotation, and an approach into a
        // bore or a seat needs both to arrive together.
        let next = steer(&from, q, options.step, space);
        if space.contains(&next, reference) && checker.edge_free(&from, &next) {
            node = tree.add(next, node);
            if d <= options.step {
                return Some(node);
            }
            continue;
        }
        if let Some(lattice) = &options.lattice {
            let mut added = Vec::new();
            effort.run(checker, |checker| {
                lattice.expand(
                    checker,
                    space,
                    tree,
                    node,
                    &PoseTarget(*q),
                    reference,
                    options.step,
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
