//! Dynamic interference: the first pose along a motion at which a moving part
//! interferes with one of the obstacles, by seed 000's stepwise method (a static check
//! after every step) or by a continuous method (conservative advancement) that cannot
//! jump over thin features.

use super::distance::distance_lower_bound;
use super::edge::{edge_interferes_until, EdgeOptions, MAX_EDGE_ANGLE};
use super::exact::interferes;
use super::method::{contact_gap, contact_step, SweepMethod};
use super::shape::Collider;
use super::{CollisionError, MotionFault, PoseFault};
use crate::math::limits::{steps, SampleBudget};
use crate::math::{Point3, Transform, Vec3};

/// A motion of the moving part, parametrised by `t ∈ [0, 1]` (world frame, mm, rad).
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// From `start`, translate by `offset` (mm) in the world.
    Translation {
        /// Pose at `t = 0`.
        start: Transform,
        /// World translation over the whole motion, mm.
        offset: Vec3,
    },
    /// From `start`, rotate by `angle` (rad, right hand) about the world line through
    /// `centre` along `axis`.
    Rotation {
        /// Pose at `t = 0`.
        start: Transform,
        /// A point of the axis, world, mm.
        centre: Point3,
        /// Axis direction (any length > 0).
        axis: Vec3,
        /// Total angle, rad.
        angle: f64,
    },
    /// Through a sequence of poses, each segment by [`Transform::interpolate`]
    /// (linear translation, slerp rotation about the part origin); each segment takes
    /// an equal share of `t`.
    Poses(Vec<Transform>),
}

impl Motion {
    fn validate(&self) -> Result<(), CollisionError> {
        let bad = |f: MotionFault| Err(CollisionError::BadMotion(f));
        match self {
            Motion::Translation { start, offset } => {
                if !start.is_finite() || !offset.iter().all(|v| v.is_finite()) {
                    return bad(MotionFault::NonFinite("the start pose or the offset"));
                }
            }
            Motion::Rotation {
                start,
                centre,
                axis,
                angle,
            } => {
                if !start.is_finite()
                    || !centre
                        .coords
                        .iter()
                        .chain(axis.iter())
                        .all(|v| v.is_finite())
                    || !angle.is_finite()
                {
                    return bad(MotionFault::NonFinite("the rotation"));
                }
                if axis.norm() < 1e-12 {
                    return bad(MotionFault::ZeroAxis);
                }
            }
            Motion::Poses(p) => {
                if p.is_empty() {
                    return bad(MotionFault::NoPoses);
                }
                if p.iter().any(|t| !t.is_finite()) {
                    return bad(MotionFault::NonFinite("a pose of the sequence"));
                }
            }
        }
        Ok(())
    }

    /// The pose at `t` (clamped to `[0, 1]`).
    pub fn pose_at(&self, t: f64) -> Transform {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        match self {
            Motion::Translation { start, offset } => {
                start.then(&Transform::from_translation(offset * t))
            }
            Motion::Rotation {
                start,
                centre,
                axis,
                angle,
            } => match Transform::from_rotation_about(*centre, *axis, angle * t) {
                Ok(r) => start.then(&r),
                Err(_) => *start,
            },
            Motion::Poses(p) => {
                if p.len() < 2 {
                    return p.first().copied().unwrap_or_default();
                }
                let m = (p.len() - 1) as f64;
                let k = ((t * m).floor() as usize).min(p.len() - 2);
                p[k].interpolate(&p[k + 1], t * m - k as f64)
            }
        }
    }

    /// Pieces of `t` on which the motion is smooth, with the largest distance any
    /// point within `radius` of the part origin moves over each piece (mm) and the
    /// piece's rotation (rad).
    fn pieces(&self, radius: f64) -> Vec<(f64, f64, f64, f64)> {
        match self {
            Motion::Translation { offset, .. } => vec![(0.0, 1.0, offset.norm(), 0.0)],
            Motion::Rotation {
                start,
                centre,
                angle,
                ..
            } => {
                let arm = (start.translation() - centre.coords).norm() + radius;
                vec![(0.0, 1.0, angle.abs() * arm, angle.abs())]
            }
            Motion::Poses(p) => {
                let m = p.len().saturating_sub(1).max(1) as f64;
                p.windows(2)
                    .enumerate()
                    .map(|(k, w)| {
                        let (angle, dist) = w[0].distance_to(&w[1]);
                        (
                            k as f64 / m,
                            (k + 1) as f64 / m,
                            dist + angle * radius,
                            angle,
                        )
                    })
                    .collect()
            }
        }
    }
}

/// A fixed part the moving part may hit.
#[derive(Debug, Clone, Copy)]
pub struct Obstacle<'a> {
    /// Its collision shape.
    pub collider: &'a Collider,
    /// Part frame → world.
    pub pose: Transform,
}

/// Options of [`sweep`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepOptions {
    /// Stepwise (`step_mm` bounds the displacement of every point of the part,
    /// `step_rad` the rotation and may be infinite) or continuous. Default
    /// [`SweepMethod::CONTINUOUS_FINE`] (contact steps of the contact gap).
    pub method: SweepMethod,
    /// Penetration tolerance of the static checks, mm.
    pub tolerance: f64,
    /// Wall-clock budget of the sweep in ms (`None`: [`DEFAULT_SWEEP_TIME_LIMIT_MS`]);
    /// a sweep that runs out of it fails with [`CollisionError::TimeLimit`].
    pub time_limit_ms: Option<f64>,
}

/// The time budget of a sweep when none is given: 10 s.
pub const DEFAULT_SWEEP_TIME_LIMIT_MS: f64 = 10_000.0;

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            method: SweepMethod::CONTINUOUS_FINE,
            tolerance: super::DEFAULT_TOLERANCE,
            time_limit_ms: None,
        }
    }
}

/// The outcome of a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepHit {
    /// Whether the part interferes somewhere along the motion.
    pub hit: bool,
    /// First interfering parameter (1 when there is no hit).
    pub t: f64,
    /// The pose at `t`.
    pub pose: Transform,
    /// Index of the obstacle hit.
    pub with: Option<usize>,
    /// Static checks and distance queries made (for benchmarks).
    pub queries: usize,
}

/// Most queries a sweep may make before it gives up with an error.
const MAX_QUERIES: usize = 2_000_000;

/// The first `t` at which `moving` (moved by `motion`) interferes with one of
/// `obstacles`, by `options.method`.
///
/// # Examples
/// A 10 mm cube pushed 30 mm along +X toward a cube standing 20 mm away stops where
/// the faces meet (within the tolerance, 0.01 mm by default).
/// ```
/// use fitup::collision::{sweep, Collider, Motion, Obstacle, SweepOptions};
/// use fitup::math::{Point3, Transform, Vec3};
/// use fitup::mesh::Mesh;
/// use std::sync::Arc;
///
/// let cube = Collider::new(Arc::new(Mesh::cuboid(
///     Point3::new(0.0, 0.0, 0.0),
///     Point3::new(10.0, 10.0, 10.0),
/// )))
/// .unwrap();
/// let wall = Obstacle {
///     collider: &cube,
///     pose: Transform::from_translation(Vec3::new(20.0, 0.0, 0.0)),
/// };
/// let motion = Motion::Translation {
///     start: Transform::IDENTITY,
///     offset: Vec3::new(30.0, 0.0, 0.0),
/// };
/// let hit = sweep(&cube, &motion, &[wall], &SweepOptions::default()).unwrap();
/// assert!(hit.hit && hit.with == Some(0));
/// assert!((hit.pose.translation().x - 10.0).abs() < 0.05); // mm
/// ```
///
/// # Errors
/// An unusable motion or option ([`CollisionError::BadMotion`]), a bad pose or
/// tolerance, or the time limit ([`CollisionError::TimeLimit`]).
pub fn sweep(
    moving: &Collider,
    motion: &Motion,
    obstacles: &[Obstacle],
    options: &SweepOptions,
) -> Result<SweepHit, CollisionError> {
    motion.validate()?;
    let tol = options.tolerance;
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(CollisionError::BadTolerance(tol));
    }
    if let Some(i) = obstacles.iter().position(|o| !o.pose.is_finite()) {
        return Err(CollisionError::BadPose(PoseFault::Obstacle(i)));
    }
    let budget_ms = options.time_limit_ms.unwrap_or(DEFAULT_SWEEP_TIME_LIMIT_MS);
    if !(budget_ms.is_finite() && budget_ms > 0.0) {
        return Err(MotionFault::option(
            "sweep's time limit",
            budget_ms,
            "a finite number of ms > 0",
        ));
    }
    let deadline = crate::math::Deadline::after_ms(budget_ms);
    let out_of_time = || deadline.passed();
    let pieces = motion.pieces(moving.radius());
    let mut queries = 0usize;
    let hit_at = |t: f64, with: usize, queries: usize| SweepHit {
        hit: true,
        t,
        pose: motion.pose_at(t),
        with: Some(with),
        queries,
    };
    // the obstacles each piece can reach at all
    let reachable = |t0: f64, reach: f64| -> Vec<usize> {
        let wb = moving.world_bounds(&motion.pose_at(t0));
        (0..obstacles.len())
            .filter(|&i| {
                let ob = obstacles[i].collider.world_bounds(&obstacles[i].pose);
                wb.overlap(&ob).min() >= -reach - 1e-9
            })
            .collect()
    };
    let check =
        |t: f64, near: &[usize], queries: &mut usize| -> Result<Option<usize>, CollisionError> {
            if out_of_time() {
                return Err(CollisionError::TimeLimit(budget_ms));
            }
            let pose = motion.pose_at(t);
            for &i in near {
                *queries += 1;
                if interferes(
                    moving,
                    &pose,
                    obstacles[i].collider,
                    &obstacles[i].pose,
                    tol,
                )? {
                    return Ok(Some(i));
                }
            }
            Ok(None)
        };
    match options.method {
        SweepMethod::Stepwise {
            step_mm: step,
            step_rad,
        } => {
            if !(step.is_finite() && step > 0.0) {
                return Err(MotionFault::option("step", step, "a finite number > 0 mm"));
            }
            if step_rad.is_nan() || step_rad <= 0.0 {
                return Err(MotionFault::option(
                    "rotation step",
                    step_rad,
                    "> 0 rad (or infinite)",
                ));
            }
            // The steps of the whole motion, counted against the shared cap before
            // the first check (a step of 1e-12 mm is refused at once, not after the
            // time budget).
            let mut budget = SampleBudget::new("steps");
            let counts = pieces
                .iter()
                .map(|&(_, _, reach, angle)| {
                    let (by_mm, by_rad) = (steps(reach, step), steps(angle, step_rad));
                    if by_mm >= by_rad {
                        budget.take(by_mm, "step", step)
                    } else {
                        budget.take(by_rad, "step_rad", step_rad)
                    }
                })
                .collect::<Result<Vec<usize>, _>>()?;
            let all: Vec<usize> = (0..obstacles.len()).collect();
            if let Some(i) = check(0.0, &all, &mut queries)? {
                return Ok(hit_at(0.0, i, queries));
            }
            for (&(t0, t1, reach, _), &n) in pieces.iter().zip(&counts) {
                if n as f64 * obstacles.len().max(1) as f64 > MAX_QUERIES as f64 {
                    return Err(CollisionError::BadMotion(MotionFault::TooManySteps {
                        steps: n,
                        limit: MAX_QUERIES,
                    }));
                }
                let near = reachable(t0, reach);
                for k in 1..=n {
                    let t = t0 + (t1 - t0) * k as f64 / n as f64;
                    if let Some(i) = check(t, &near, &mut queries)? {
                        return Ok(hit_at(t, i, queries));
                    }
                }
            }
        }
        SweepMethod::Continuous { contact_step_mm } => {
            if !(contact_step_mm.is_finite() && contact_step_mm > 0.0) {
                return Err(MotionFault::option(
                    "contact step",
                    contact_step_mm,
                    "a finite number > 0 mm",
                ));
            }
            let all: Vec<usize> = (0..obstacles.len()).collect();
            if let Some(i) = check(0.0, &all, &mut queries)? {
                return Ok(hit_at(0.0, i, queries));
            }
            // gap below which static checks take over, and their spacing
            let g = contact_gap(tol);
            let in_contact = contact_step(contact_step_mm, tol);
            let edge_options = EdgeOptions {
                tolerance: tol,
                contact_step: contact_step_mm,
            };
            // A translation and the pieces of a pose sequence are planner edges
            // (lerp + slerp about the part origin; a rotation about another axis is
            // not): each is checked whole by the continuous edge check, whose
            // triangle pairs advance on their own, so a part sliding along a face or
            // out of a bore line to line is not stepped pose by pose at the contact
            // step (a screw drawn out of its hole: seconds became milliseconds).
            let straight = !matches!(motion, Motion::Rotation { .. });
            for &(t0, t1, reach, angle) in &pieces {
                if reach <= 0.0 {
                    continue;
                }
                let near = reachable(t0, reach);
                let speed = reach / (t1 - t0); // mm per unit t
                let mut t = t0;
                if straight && angle <= MAX_EDGE_ANGLE {
                    // whether some obstacle is crossed on `a..b` after `a`, and which
                    let crossed = |a: f64, b: f64, queries: &mut usize| {
                        let (pa, pb) = (motion.pose_at(a), motion.pose_at(b));
                        for &i in &near {
                            *queries += 1;
                            let o = &obstacles[i];
                            let hit = edge_interferes_until(
                                moving,
                                &pa,
                                &pb,
                                o.collider,
                                &o.pose,
                                &edge_options,
                                deadline.instant(),
                            )?
                            .ok_or(CollisionError::TimeLimit(budget_ms))?;
                            if hit {
                                return Ok(Some(i));
                            }
                        }
                        Ok::<_, CollisionError>(None)
                    };
                    match crossed(t0, t1, &mut queries)? {
                        // free on the way; the end pose still gets its static
                        // check (containment) below
                        None => t = t1,
                        Some(_) => {
                            // bisect to the first crossing: `lo` stays free
                            let (mut lo, mut hi) = (t0, t1);
                            while (hi - lo) * speed > g / 8.0 {
                                if out_of_time() {
                                    return Err(CollisionError::TimeLimit(budget_ms));
                                }
                                let mid = 0.5 * (lo + hi);
                                if crossed(lo, mid, &mut queries)?.is_some() {
                                    hi = mid;
                                } else {
                                    lo = mid;
                                }
                            }
                            // the first pose past the crossing that a static check
                            // finds interfering; else the stepping below from `lo`
                            let mut at = hi;
                            for _ in 0..64 {
                                if let Some(i) = check(at, &near, &mut queries)? {
                                    return Ok(hit_at(at, i, queries));
                                }
                                if at >= t1 {
                                    break;
                                }
                                at = (at + g / 8.0 / speed).min(t1);
                            }
                            t = lo;
                        }
                    }
                    if t >= t1 {
                        if let Some(i) = check(t1, &near, &mut queries)? {
                            return Ok(hit_at(t1, i, queries));
                        }
                        continue;
                    }
                }
                while t < t1 {
                    if queries > MAX_QUERIES {
                        return Err(CollisionError::BadMotion(MotionFault::TooManyQueries(
                            MAX_QUERIES,
                        )));
                    }
                    if out_of_time() {
                        return Err(CollisionError::TimeLimit(budget_ms));
                    }
                    let pose = motion.pose_at(t);
                    let mut d = f64::INFINITY;
                    for &i in &near {
                        queries += 1;
                        let o = &obstacles[i];
                        // a bound good to 25 %, capped at what is left of the piece
                        let cap = (t1 - t) * speed + g;
                        d = d.min(distance_lower_bound(
                            moving, &pose, o.collider, &o.pose, g, cap, 0.25,
                        )?);
                    }
                    let advance = if d > g { d - g / 2.0 } else { in_contact };
                    let next = (t + advance / speed).min(t1);
                    if d <= g || next >= t1 {
                        if let Some(i) = check(next, &near, &mut queries)? {
                            // bisect between the free t and the interfering `next`
                            let (mut lo, mut hi, mut with) = (t, next, i);
                            while (hi - lo) * speed > g / 8.0 {
                                let mid = 0.5 * (lo + hi);
                                match check(mid, &near, &mut queries)? {
                                    Some(j) => {
                                        hi = mid;
                                        with = j;
                                    }
                                    None => lo = mid,
                                }
                            }
                            return Ok(hit_at(hi, with, queries));
                        }
                    }
                    t = next;
                }
            }
        }
    }
    Ok(SweepHit {
        hit: false,
        t: 1.0,
        pose: motion.pose_at(1.0),
        with: None,
        queries,
    })
}
