//! Seed 000's random-walk RRT + Floyd shortest path.

use super::path::PlannedPath;
use super::rrt::Ending;
use super::run::Failure;
use super::run::{PlanError, PlanLimits, ProgressFn};
use super::smoothing::Smoothing;
use super::space::PlanningSpace;
use super::tree::{begin, steer, Begun, Tree};
use super::validator::MotionValidator;
use crate::math::{Rng, Transform};

/// Largest accepted `max_nodes`: Floyd–Warshall is O(n³) in time and O(n²) in memory,
/// 1000 nodes being about 10⁹ relaxations.
pub const MAX_FLOYD_NODES: usize = 1000;

/// Options of [`rrt_floyd`].
#[derive(Debug, Clone, PartialEq)]
pub struct RrtFloydOptions {
    /// Seed and limits (one iteration = one random-walk extension).
    pub limits: PlanLimits,
    /// Largest extension toward a sample (metric mm). Default 10.
    pub step: f64,
    /// Probability of walking toward the goal instead of a uniform sample. Default 0.05.
    pub goal_bias: f64,
    /// Distance (metric mm) under which a node tries a straight edge to the goal.
    /// Default 10.
    pub goal_tolerance: f64,
    /// Node count at which the walk stops (at most [`MAX_FLOYD_NODES`]). Default 300.
    pub max_nodes: usize,
    /// Graph edges are tried between nodes at most this far apart (metric mm).
    /// Default 30.
    pub connect_radius: f64,
    /// Shortcut smoothing of the found path. Default on.
    pub smoothing: Smoothing,
}

impl Default for RrtFloydOptions {
    fn default() -> Self {
        Self {
            limits: PlanLimits::default(),
            step: 10.0,
            goal_bias: 0.05,
            goal_tolerance: 10.0,
            max_nodes: 300,
            connect_radius: 30.0,
            smoothing: Smoothing::default(),
        }
    }
}

impl RrtFloydOptions {
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        self.limits.validate()?;
        PlanError::positive("step", self.step)?;
        PlanError::probability("goal_bias", self.goal_bias)?;
        PlanError::positive("goal_tolerance", self.goal_tolerance)?;
        PlanError::positive("connect_radius", self.connect_radius)?;
        if !(2..=MAX_FLOYD_NODES).contains(&self.max_nodes) {
            return Err(PlanError::invalid(
                "max_nodes",
                self.max_nodes.to_string(),
                "2 to 1000 nodes (Floyd–Warshall is O(n³))",
            ));
        }
        self.smoothing.validate()
    }
}

/// Plans from `start` to `goal` as seed 000 describes: a random-walk RRT explores
/// until a node sees the goal (or `max_nodes` is reached); its nodes and the goal
/// become a graph whose edges are the tree edges plus every free straight edge
/// between nodes within `connect_radius`; Floyd–Warshall all-pairs shortest paths
/// then give the shortest start–goal route in that graph (metric of `space`).
///
/// Fails with the walk's stop reason, or [`Failure::Exhausted`] when the node cap is
/// reached and the graph does not join start and goal.
///
/// # Errors
/// Invalid options (`max_nodes` above [`MAX_FLOYD_NODES`] included), bounds or
/// non-finite poses.
pub fn rrt_floyd(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &RrtFloydOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    const NAME: &str = "rrt_floyd";
    options.validate()?;
    let ends = (start, Some(goal));
    let (mut run, mut checker) =
        match begin(NAME, validator, space, ends, options.limits, progress)? {
            Begun::Ready(run, checker) => (run, checker),
            Begun::Refused(path) => return Ok(path),
        };
    let mut rng = Rng::new(options.limits.seed);
    let reference = start.rotation();
    let mut tree = Tree::new(*start, options.step * 1e-3);
    let mut best = space.distance(start, goal);
    let mut goal_node = None;
    let mut stop = Failure::Exhausted(0);
    // Phase 1: the random walk.
    while goal_node.is_none() && tree.len() < options.max_nodes - 1 {
        if let Err(f) = run.next(tree.len(), best) {
            stop = f;
            break;
        }
        let sample = if rng.uniform() < options.goal_bias {
            *goal
        } else {
            space.sample(&mut rng, &reference)
        };
        let (near, _) = tree.nearest(&sample, space);
        let from = tree.poses[near];
        let to = steer(&from, &sample, options.step, space);
        if space.contains(&to, &reference) && !tree.holds(&to) && checker.edge_free(&from, &to) {
            let i = tree.add(to, near);
            let d = space.distance(&to, goal);
            best = best.min(d);
            if d <= options.goal_tolerance && (d == 0.0 || checker.edge_free(&to, goal)) {
                goal_node = Some(if d == 0.0 { i } else { tree.add(*goal, i) });
            }
        }
    }
    if matches!(stop, Failure::Cancelled | Failure::TimeLimit) {
        return Ok(PlannedPath::failed(
            NAME,
            stop,
            run.iterations,
            tree.len(),
            &checker,
            run.elapsed_ms(),
        ));
    }
    // Phase 2: the graph (goal last when the walk did not reach it).
    let mut nodes = tree.poses.clone();
    let g = match goal_node {
        Some(i) => i,
        None => {
            nodes.push(*goal);
            nodes.len() - 1
        }
    };
    let n = nodes.len();
    let mut dist = vec![f64::INFINITY; n * n];
    for i in 0..n {
        dist[i * n + i] = 0.0;
    }
    for i in 1..tree.len() {
        let p = tree.parent[i];
        let w = space.distance(&nodes[i], &nodes[p]);
        dist[i * n + p] = w;
        dist[p * n + i] = w;
    }
    for i in 0..n {
        if let Err(f) = run.check(n, best) {
            return Ok(PlannedPath::failed(
                NAME,
                f,
                run.iterations,
                n,
                &checker,
                run.elapsed_ms(),
            ));
        }
        for j in i + 1..n {
            let w = space.distance(&nodes[i], &nodes[j]);
            if w <= options.connect_radius
                && dist[i * n + j].is_infinite()
                && checker.edge_free(&nodes[i], &nodes[j])
            {
                dist[i * n + j] = w;
                dist[j * n + i] = w;
            }
        }
    }
    // Phase 3: Floyd–Warshall with next-hop reconstruction.
    let mut next: Vec<u32> = (0..n * n).map(|k| (k % n) as u32).collect();
    for k in 0..n {
        for i in 0..n {
            let dik = dist[i * n + k];
            if dik.is_infinite() {
                continue;
            }
            for j in 0..n {
                let via = dik + dist[k * n + j];
                if via < dist[i * n + j] {
                    dist[i * n + j] = via;
                    next[i * n + j] = next[i * n + k];
                }
            }
        }
    }
    if dist[g].is_infinite() {
        return Ok(PlannedPath::failed(
            NAME,
            stop,
            run.iterations,
            n,
            &checker,
            run.elapsed_ms(),
        ));
    }
    let mut poses = vec![nodes[0]];
    let mut i = 0;
    while i != g && poses.len() <= n {
        i = next[i * n + g] as usize;
        poses.push(nodes[i]);
    }
    let ending = Ending::new(NAME, space, &options.smoothing, options.limits.seed);
    Ok(ending.finish(poses, n, &mut checker, &mut run))
}
