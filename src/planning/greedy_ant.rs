//! Seed 000's single-ant dynamic greedy algorithm (section 5.2, table 4).

use super::path::PlannedPath;
use super::rrt::Ending;
use super::run::Failure;
use super::run::{PlanError, PlanLimits, ProgressFn};
use super::smoothing::Smoothing;
use super::space::PlanningSpace;
use super::tree::{begin, Begun};
use super::validator::MotionValidator;
use crate::math::{Transform, Vec3};

/// Largest number of grid points on one layer.
const MAX_LAYER_POINTS: usize = 4_000_000;

/// Options of [`greedy_ant`], named after seed 000's table 4. `B` is the planning
/// space's box, `s` and `e` the start and goal poses, `D` their distance (computed).
#[derive(Debug, Clone, PartialEq)]
pub struct GreedyAntOptions {
    /// Time limit and cancellation (the algorithm draws no random numbers; the seed
    /// is unused; one layer is one iteration).
    pub limits: PlanLimits,
    /// `step`: number of segments the straight line `s → e` is cut into (`step - 1`
    /// layers). `None`: `ceil(D / L)`, so consecutive layers are at most `L` apart.
    pub step: Option<usize>,
    /// `L`: shortest length (mm) of the moving component along the direction of
    /// motion; sets the default `step`. Default 10.
    pub shortest_length: f64,
    /// `dis`: spacing (mm) of the grid on each layer's plane. Default 2.
    pub dis: f64,
    /// Half-width (mm) of the grid around the layer's point on the line (`None`: the
    /// whole cross-section of `B`). Default `None`.
    pub radius: Option<f64>,
    /// Shortcut smoothing of the found path. Default off, to return the layers as
    /// seed 000 does.
    pub smoothing: Smoothing,
}

impl Default for GreedyAntOptions {
    fn default() -> Self {
        Self {
            limits: PlanLimits::default(),
            step: None,
            shortest_length: 10.0,
            dis: 2.0,
            radius: None,
            smoothing: Smoothing::OFF,
        }
    }
}

impl GreedyAntOptions {
    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        self.limits.validate()?;
        if self.step == Some(0) {
            return Err(PlanError::invalid("step", "0".into(), "at least 1 segment"));
        }
        PlanError::positive("shortest_length", self.shortest_length)?;
        PlanError::positive("dis", self.dis)?;
        if let Some(r) = self.radius {
            if !(r.is_finite() && r >= 0.0) {
                return Err(PlanError::invalid(
                    "radius",
                    r.to_string(),
                    "a finite number ≥ 0",
                ));
            }
        }
        self.smoothing.validate()
    }
}

/// Plans from `start` (`s`) to `goal` (`e`) with seed 000's single-ant dynamic greedy
/// algorithm.
///
/// 1. The dominant axis of `e - s` picks the cutting planes (largest `|Δx|`: planes
///    parallel to YOZ, …).
/// 2. The line `s → e` is cut into `step` segments; through each of the `step - 1`
///    points a plane perpendicular to the dominant axis carries a grid of spacing
///    `dis` (inside `B`, and within `radius` of the line when set).
/// 3. Layer by layer, the grid points are ranked by distance to the previous path
///    point plus distance to `e`, and the first one whose edge from the previous
///    point is free becomes the next path point (its orientation is interpolated
///    between `s` and `e` by the layer's fraction).
/// 4. The last point joins `e`.
///
/// The search never backtracks: a layer without a free point, or a blocked final
/// edge, ends it with [`Failure::Exhausted`] (layer index, `step` for the final
/// edge).
///
/// # Errors
/// Invalid options, bounds or non-finite poses, or a grid of more than 4 million
/// points on one layer (`dis` too small for `B`; set `radius`).
pub fn greedy_ant(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    start: &Transform,
    goal: &Transform,
    options: &GreedyAntOptions,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    const NAME: &str = "greedy_ant";
    options.validate()?;
    space.validate()?;
    PlanError::pose("start", start)?;
    PlanError::pose("goal", goal)?;
    let (s, e) = (start.translation(), goal.translation());
    let delta = e - s;
    let d = delta.norm();
    let step = options
        .step
        .unwrap_or_else(|| (d / options.shortest_length).ceil().clamp(1.0, 1e6) as usize);
    let axis = delta.iamax();
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let half = |k: usize| {
        let span = space.max[k] - space.min[k];
        options.radius.map_or(span, |r| r.min(span))
    };
    let count = |k: usize| 2 * (half(k) / options.dis).floor() as usize + 1;
    if count(u).saturating_mul(count(v)) > MAX_LAYER_POINTS {
        return Err(PlanError::invalid(
            "dis",
            options.dis.to_string(),
            "a grid spacing giving at most 4 million points per layer (raise dis or set radius)",
        ));
    }
    let ends = (start, Some(goal));
    let (mut run, mut checker) =
        match begin(NAME, validator, space, ends, options.limits, progress)? {
            Begun::Ready(run, checker) => (run, checker),
            Begun::Refused(path) => return Ok(path),
        };
    let reference = start.rotation();
    let mut poses = vec![*start];
    let mut candidates: Vec<(f64, Vec3)> = Vec::new();
    let (nu, nv) = (
        (half(u) / options.dis).floor() as i64,
        (half(v) / options.dis).floor() as i64,
    );
    for layer in 1..step {
        let prev = poses[poses.len() - 1];
        if let Err(f) = run.next(layer, space.distance(&prev, goal)) {
            return Ok(PlannedPath::failed(
                NAME,
                f,
                run.iterations,
                layer,
                &checker,
                run.elapsed_ms(),
            ));
        }
        let frac = layer as f64 / step as f64;
        let centre = s + delta * frac;
        let rotation = start.interpolate(goal, frac).rotation();
        candidates.clear();
        for a in -nu..=nu {
            for b in -nv..=nv {
                let mut p = centre;
                p[u] += a as f64 * options.dis;
                p[v] += b as f64 * options.dis;
                if (0..3).all(|k| p[k] >= space.min[k] && p[k] <= space.max[k]) {
                    let cost = (p - prev.translation()).norm() + (p - e).norm();
                    candidates.push((cost, p));
                }
            }
        }
        // Stable sort + integer grid order: ties resolve the same way on every run.
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut chosen = None;
        for &(_, p) in &candidates {
            let pose = Transform::from_parts(p, rotation);
            if space.contains(&pose, &reference) && checker.edge_free(&prev, &pose) {
                chosen = Some(pose);
                break;
            }
        }
        match chosen {
            Some(pose) => poses.push(pose),
            None => {
                return Ok(PlannedPath::failed(
                    NAME,
                    Failure::Exhausted(layer),
                    run.iterations,
                    layer,
                    &checker,
                    run.elapsed_ms(),
                ))
            }
        }
    }
    let last = poses[poses.len() - 1];
    if !checker.edge_free(&last, goal) {
        return Ok(PlannedPath::failed(
            NAME,
            Failure::Exhausted(step),
            run.iterations,
            step,
            &checker,
            run.elapsed_ms(),
        ));
    }
    poses.push(*goal);
    let nodes = poses.len();
    let ending = Ending::new(NAME, space, &options.smoothing, options.limits.seed);
    Ok(ending.finish(poses, nodes, &mut checker, &mut run))
}
