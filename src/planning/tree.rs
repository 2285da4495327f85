//! The search tree shared by the RRT family, and helpers every tree planner needs.

#[cfg(test)]
use super::nearest::metric;
use super::nearest::{metric_below, KdIndex};
use super::path::PlannedPath;
use super::run::{Failure, PlanError, PlanLimits, ProgressFn, Run};
use super::space::PlanningSpace;
use super::validator::{Checker, MotionValidator};
use crate::math::{Rng, Transform, Vec3};
use nalgebra::UnitQuaternion;
use std::collections::HashSet;

/// A tree of poses rooted at index 0.
///
/// Nearest-neighbour queries go through a k-d tree in the space's SE(3) metric
/// ([`KdIndex`]) rebuilt as the tree grows by a quarter, plus a scan of the nodes
/// added since; the answer is exactly the linear scan's (same distances, ties to
/// the lowest index), so paths do not depend on when the index was rebuilt.
pub(crate) struct Tree {
    pub poses: Vec<Transform>,
    pub parent: Vec<usize>,
    translations: Vec<Vec3>,
    rotations: Vec<UnitQuaternion<f64>>,
    /// Quantized poses, so the local discretization does not re-add a lattice vertex.
    keys: HashSet<[i64; 7]>,
    key_mm: f64,
    /// Nodes cut off by a failed certification (lazy search): never nearest again.
    dead: Vec<bool>,
    /// Whether the edge parent → node passed the validator's own edge check (the
    /// root's entry is true).
    certified: Vec<bool>,
    /// Dynamic-domain radius of each node (metric mm; infinite until an extension
    /// from it was blocked, see [`NarrowPassage`](super::NarrowPassage)).
    domain: Vec<f64>,
    /// Adaptive reach of each node (metric mm; infinite: the search's full
    /// step), see [`Tree::reach`].
    reach: Vec<f64>,
    /// The k-d tree over the first `index.len()` nodes.
    index: KdIndex,
    /// The rotation weight of the last query (steers the next rebuild's splits).
    weight: std::cell::Cell<f64>,
}

/// Below this many nodes a query scans them all.
const INDEX_FROM: usize = 128;

impl Tree {
    /// A tree holding `root`; `key_mm` is the translation quantum of duplicate detection.
    pub fn new(root: Transform, key_mm: f64) -> Self {
        let mut t = Self {
            poses: Vec::new(),
            parent: Vec::new(),
            translations: Vec::new(),
            rotations: Vec::new(),
            keys: HashSet::new(),
            key_mm,
            dead: Vec::new(),
            certified: Vec::new(),
            domain: Vec::new(),
            reach: Vec::new(),
            index: KdIndex::default(),
            weight: std::cell::Cell::new(25.0),
        };
        t.add(root, 0);
        t.certified[0] = true;
        t
    }

    pub fn len(&self) -> usize {
        self.poses.len()
    }

    pub fn add(&mut self, pose: Transform, parent: usize) -> usize {
        let i = self.poses.len();
        self.keys.insert(self.key(&pose));
        self.poses.push(pose);
        self.parent.push(parent);
        self.translations.push(pose.translation());
        self.rotations.push(pose.rotation());
        self.dead.push(false);
        self.certified.push(false);
        self.domain.push(f64::INFINITY);
        self.reach.push(f64::INFINITY);
        let built = self.index.len();
        if self.poses.len() >= INDEX_FROM && self.poses.len() - built > (built / 4).max(32) {
            self.index = KdIndex::build(&self.translations, &self.rotations, self.weight.get());
        }
        i
    }

    /// Node `i`'s dynamic-domain radius (metric mm; infinite: unbounded).
    pub fn domain(&self, i: usize) -> f64 {
        self.domain[i]
    }

    /// An extension from node `i` was blocked: its domain becomes at most `radius`.
    pub fn shrink_domain(&mut self, i: usize, radius: f64) {
        self.domain[i] = self.domain[i].min(radius);
    }

    /// An extension from node `i` succeeded: a finite domain grows by `factor`.
    pub fn grow_domain(&mut self, i: usize, factor: f64) {
        if self.domain[i].is_finite() {
            self.domain[i] *= factor;
        }
    }

    /// Node `i`'s adaptive reach: how far an extension from it goes at most
    /// (metric mm; infinite until an extension from it was blocked).
    pub fn reach(&self, i: usize) -> f64 {
        self.reach[i]
    }

    /// Sets node `i`'s adaptive reach (metric mm).
    pub fn set_reach(&mut self, i: usize, reach: f64) {
        self.reach[i] = reach;
    }

    /// Cuts node `i` and everything grown from it out of the tree (they stay in the
    /// arrays but are never nearest again). Parents come before their children, so
    /// one pass from `i` finds every descendant.
    fn cut(&mut self, i: usize) {
        self.dead[i] = true;
        for k in i + 1..self.len() {
            if self.dead[self.parent[k]] {
                self.dead[k] = true;
            }
        }
    }

    /// Certifies the branch root → `i` with the validator's own edge check
    /// ([`Checker::certify`]), each edge in the direction it was grown (parent →
    /// child), from the root outward, skipping edges certified before. On the first
    /// edge that fails, cuts its child's subtree and returns `false`.
    pub fn certify_branch(&mut self, i: usize, checker: &mut Checker<'_>) -> bool {
        let mut chain = Vec::new();
        let mut k = i;
        while k != 0 {
            chain.push(k);
            k = self.parent[k];
        }
        for &k in chain.iter().rev() {
            if self.certified[k] {
                continue;
            }
            if checker.certify(&self.poses[self.parent[k]], &self.poses[k]) {
                self.certified[k] = true;
            } else {
                self.cut(k);
                return false;
            }
        }
        true
    }

    /// Whether node `i` is still part of the tree (not cut by a failed
    /// certification).
    pub fn alive(&self, i: usize) -> bool {
        !self.dead[i]
    }

    /// Whether a pose equal to `pose` (up to the quantum) is already a node.
    pub fn holds(&self, pose: &Transform) -> bool {
        self.keys.contains(&self.key(pose))
    }

    fn key(&self, pose: &Transform) -> [i64; 7] {
        let t = pose.translation() / self.key_mm;
        let q = pose.rotation();
        // q and -q are the same rotation.
        let s = if q.w < 0.0 { -1e3 } else { 1e3 };
        [
            t.x.round() as i64,
            t.y.round() as i64,
            t.z.round() as i64,
            (q.w * s).round() as i64,
            (q.i * s).round() as i64,
            (q.j * s).round() as i64,
            (q.k * s).round() as i64,
        ]
    }

    /// The node nearest to `target` in the metric of `space`, and its distance.
    pub fn nearest(&self, target: &Transform, space: &PlanningSpace) -> (usize, f64) {
        let tt = target.translation();
        let tq = target.rotation();
        let w = space.rotation_weight;
        self.weight.set(w);
        let built = self.index.len();
        let mut best = self.index.nearest(
            &self.translations,
            &self.rotations,
            &tt,
            &tq,
            w,
            &|i| self.dead[i],
            (0, f64::INFINITY),
        );
        // The nodes added since the last rebuild: all indices above the index's, so
        // a strict `<` keeps ties at the lowest index.
        for i in built..self.len() {
            let d = (self.translations[i] - tt).norm();
            if d >= best.1 || self.dead[i] {
                continue;
            }
            let d = metric_below(
                &self.translations[i],
                &self.rotations[i],
                &tt,
                &tq,
                w,
                best.1,
            );
            if d < best.1 {
                best = (i, d);
            }
        }
        best
    }

    /// The linear scan [`Tree::nearest`] must agree with.
    #[cfg(test)]
    fn nearest_by_scan(&self, target: &Transform, space: &PlanningSpace) -> (usize, f64) {
        let (tt, tq) = (target.translation(), target.rotation());
        let mut best = (0, f64::INFINITY);
        for i in 0..self.len() {
            let d = metric(
                &self.translations[i],
                &self.rotations[i],
                &tt,
                &tq,
                space.rotation_weight,
            );
            if d < best.1 && !self.dead[i] {
                best = (i, d);
            }
        }
        best
    }

    /// The poses from the root to node `i`.
    pub fn branch(&self, mut i: usize) -> Vec<Transform> {
        let mut out = vec![self.poses[i]];
        while i != 0 {
            i = self.parent[i];
            out.push(self.poses[i]);
        }
        out.reverse();
        out
    }
}

/// The share of a tree search's work its fallbacks may take
/// ([`RrtConnectOptions::fallback_share`](super::RrtConnectOptions::fallback_share)),
/// counted in pose-check units so that the same seed gives the same path.
///
/// The share doubles for every [`Effort::STAGNATION`] iterations in which the
/// search got no closer to its goal (up to 1), and falls back to the base share
/// when it does: where plain iterations stop making progress (the two trees each
/// side of a wall with a small hole) the fallbacks are what can, and they get the
/// work; where plain iterations keep making progress they keep it.
pub(crate) struct Effort {
    share: f64,
    /// Work the fallbacks have done so far.
    spent: u64,
    /// The closest approach to the goal so far (metric mm) and how many
    /// iterations ago it last improved.
    best: f64,
    stagnant: usize,
}

impl Effort {
    /// No work spent yet; `share` in `[0, 1]` (1: no limit).
    pub fn new(share: f64) -> Self {
        Self {
            share,
            spent: 0,
            best: f64::INFINITY,
            stagnant: 0,
        }
    }

    /// Iterations without progress after which the share doubles. Long: a plain
    /// iteration costs a few checks, and on the rotation puzzles the two trees
    /// often stall for thousands of iterations before they meet; a shorter period
    /// (1000, 3000) made `rrt_connect` 1.5–3× slower on the ring puzzle.
    pub const STAGNATION: usize = 10_000;

    /// Ends an iteration whose closest approach to the goal so far is `best`.
    pub fn iteration(&mut self, best: f64) {
        if best < self.best {
            self.best = best;
            self.stagnant = 0;
        } else {
            self.stagnant += 1;
        }
    }

    /// The share in force: the base share doubled per stagnation period.
    fn current_share(&self) -> f64 {
        let doublings = (self.stagnant / Self::STAGNATION).min(64) as i32;
        (self.share * 2f64.powi(doublings)).min(1.0)
    }

    /// How many nodes a nearest-node scan visits in the time of one pose check
    /// (≈ 10 ns against ≈ 4 µs on the benchmark meshes, profiled).
    const NODES_PER_CHECK: usize = 400;

    /// Whether the fallbacks are within their share.
    pub fn allows(&self, checker: &Checker<'_>) -> bool {
        let share = self.current_share();
        share >= 1.0 || self.spent as f64 <= share * checker.work() as f64
    }

    /// Runs `f` (a fallback) when the fallbacks are within their share and charges
    /// it the work it did; `None` when over the share.
    pub fn run<R>(
        &mut self,
        checker: &mut Checker<'_>,
        f: impl FnOnce(&mut Checker<'_>) -> R,
    ) -> Option<R> {
        if !self.allows(checker) {
            return None;
        }
        let before = checker.work();
        let r = f(checker);
        self.spent += checker.work() - before;
        Some(r)
    }

    /// Charges `scans` nearest-node scans of a tree of `nodes` nodes.
    pub fn charge_scans(&mut self, scans: usize, nodes: usize) {
        self.spent += (scans * nodes / Self::NODES_PER_CHECK) as u64;
    }
}

/// The pose at most `max_step` (metric mm) from `from` toward `to`.
pub(crate) fn steer(
    from: &Transform,
    to: &Transform,
    max_step: f64,
    space: &PlanningSpace,
) -> Transform {
    let d = space.distance(from, to);
    if d <= max_step {
        *to
    } else {
        from.interpolate(to, max_step / d)
    }
}

/// How a planning call begins ([`begin`]).
pub(crate) enum Begun<'v, 'p> {
    /// The run (limits, deadline, progress) and the checker to plan with.
    Ready(Run<'p>, Checker<'v>),
    /// The ends are out of bounds or in collision: the failed path to return.
    Refused(PlannedPath),
}

/// The first steps of every planning call from `start` (to `goal`, when the
/// target is one pose): the bounds and poses are checked (an error when they are
/// invalid or not finite), the run starts on `limits` with `progress`, and the
/// ends are checked for bounds and collisions through `validator`.
pub(crate) fn begin<'v, 'p>(
    planner: &'static str,
    validator: &'v mut dyn MotionValidator,
    space: &PlanningSpace,
    (start, goal): (&Transform, Option<&Transform>),
    limits: PlanLimits,
    progress: Option<ProgressFn<'p>>,
) -> Result<Begun<'v, 'p>, PlanError> {
    space.validate()?;
    PlanError::pose("start", start)?;
    if let Some(g) = goal {
        PlanError::pose("goal", g)?;
    }
    let run = Run::new(limits, progress);
    let mut checker = Checker::new(validator, Some(run.deadline()));
    Ok(match check_ends(&mut checker, space, start, goal) {
        Some(f) => Begun::Refused(PlannedPath::failed(
            planner,
            f,
            0,
            0,
            &checker,
            run.elapsed_ms(),
        )),
        None => Begun::Ready(run, checker),
    })
}

/// Bounds then collision checks of the start (and goal, when there is one).
fn check_ends(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    start: &Transform,
    goal: Option<&Transform>,
) -> Option<Failure> {
    let reference = start.rotation();
    if !space.contains(start, &reference) {
        return Some(Failure::StartOutOfBounds);
    }
    if let Some(g) = goal {
        if !space.contains(g, &reference) {
            return Some(Failure::GoalOutOfBounds);
        }
    }
    if !checker.is_free(start) {
        return Some(Failure::StartInCollision);
    }
    if let Some(g) = goal {
        if !checker.is_free(g) {
            return Some(Failure::GoalInCollision);
        }
    }
    None
}

/// What a tree grows toward: one pose, or a region recognised by a predicate.
pub(crate) trait Target {
    /// Whether `pose` solves the query by itself (regions).
    fn reached(&self, pose: &Transform) -> bool;
    /// A pose to join with a final edge once within the goal tolerance.
    fn pose(&self) -> Option<&Transform>;
    /// Heuristic distance (metric mm) to the goal, used to rank candidates.
    fn distance(&self, pose: &Transform, space: &PlanningSpace) -> f64;
    /// A goal pose to bias sampling toward.
    fn sample(&self, rng: &mut Rng, space: &PlanningSpace, near: &Transform) -> Transform;
}

/// A single goal pose.
pub(crate) struct PoseTarget(pub Transform);

impl Target for PoseTarget {
    fn reached(&self, _: &Transform) -> bool {
        false
    }
    fn pose(&self) -> Option<&Transform> {
        Some(&self.0)
    }
    fn distance(&self, pose: &Transform, space: &PlanningSpace) -> f64 {
        space.distance(pose, &self.0)
    }
    fn sample(&self, _: &mut Rng, _: &PlanningSpace, _: &Transform) -> Transform {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planning::validator::MotionValidator;

    /// Every pose is free; counts nothing itself (the checker counts).
    struct Open;
    impl MotionValidator for Open {
        fn is_free(&mut self, _: &Transform) -> bool {
            true
        }
    }

    #[test]
    fn fallbacks_stay_within_their_share_and_get_more_when_the_search_stalls() {
        let mut v = Open;
        let mut checker = Checker::new(&mut v, None);
        let mut effort = Effort::new(0.1);
        let p = Transform::IDENTITY;
        // Each iteration: 9 plain checks, then a fallback of 10 checks when allowed.
        let mut ran = 0;
        for i in 0..20_000 {
            effort.iteration(1000.0 - i as f64); // progress every iteration
            for _ in 0..9 {
                checker.is_free(&p);
            }
            if effort
                .run(&mut checker, |c| {
                    for _ in 0..10 {
                        c.is_free(&p);
                    }
                })
                .is_some()
            {
                ran += 1;
            }
        }
        // The fallbacks' share of all work is the base share (within one fallback).
        let share = effort.spent as f64 / checker.work() as f64;
        assert!((share - 0.1).abs() < 0.01, "{share}");
        assert!(ran > 0);
        // No progress for STAGNATION iterations: the share doubles; progress: back.
        assert_eq!(effort.current_share(), 0.1);
        let stuck = effort.best;
        for _ in 0..Effort::STAGNATION - 1 {
            effort.iteration(stuck);
        }
        assert_eq!(effort.current_share(), 0.1);
        effort.iteration(stuck);
        assert!((effort.current_share() - 0.2).abs() < 1e-12);
        for _ in 0..10 * Effort::STAGNATION {
            effort.iteration(stuck);
        }
        assert_eq!(effort.current_share(), 1.0);
        effort.iteration(stuck - 1.0);
        assert_eq!(effort.current_share(), 0.1);
        // Share 1: always allowed.
        let full = Effort::new(1.0);
        assert!(full.allows(&checker));
    }

    /// A grown tree (index rebuilt several times, nodes added since the last
    /// rebuild, a cut branch) answers every query as the linear scan does.
    #[test]
    fn nearest_through_the_index_is_the_linear_scan() {
        let space = PlanningSpace::new(Vec3::repeat(-100.0), Vec3::repeat(100.0))
            .with_rotation_weight(30.0);
        let mut rng = Rng::new(11);
        let mut tree = Tree::new(Transform::IDENTITY, 1e-6);
        for k in 1..2500 {
            let pose = Transform::from_parts(
                Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 200.0
                    - Vec3::repeat(100.0),
                rng.rotation(),
            );
            tree.add(pose, rng.below(k));
        }
        tree.cut(700);
        assert!(tree.index.len() > 1500 && tree.index.len() < tree.len());
        for _ in 0..500 {
            let q = Transform::from_parts(
                Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 200.0
                    - Vec3::repeat(100.0),
                rng.rotation(),
            );
            assert_eq!(tree.nearest(&q, &space), tree.nearest_by_scan(&q, &space));
        }
    }

    #[test]
    fn nearest_uses_the_metric_of_the_space() {
        let space = PlanningSpace::new(Vec3::repeat(-100.0), Vec3::repeat(100.0))
            .with_rotation_weight(10.0);
        let turned = |deg: f64, x: f64| {
            Transform::from_parts(
                Vec3::new(x, 0.0, 0.0),
                UnitQuaternion::from_axis_angle(&Vec3::z_axis(), deg.to_radians()),
            )
        };
        let mut tree = Tree::new(turned(0.0, 0.0), 1e-3);
        tree.add(turned(90.0, 1.0), 0);
        tree.add(turned(-170.0, 5.0), 0);
        // Target at 180°, x = 2: node 2 is 3 mm + 10° away, node 1 1 mm + 90°.
        let target = turned(180.0, 2.0);
        let (i, d) = tree.nearest(&target, &space);
        assert_eq!(i, 2);
        assert!(
            (d - space.distance(&tree.poses[2], &target)).abs() < 1e-9,
            "{d}"
        );
    }
}
