//! [`NumericIk`]: damped least squares (Levenberg–Marquardt) inverse kinematics for any
//! chain, with seeded random restarts.

use super::{IkError, IkOptions, IkSolution, JointKind, Robot, Singularity, Unreachable};
use crate::math::{Rng, Transform};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

/// Numeric inverse kinematics: Levenberg–Marquardt on the 6-D pose error
/// (position in mm, orientation as a rotation vector scaled by [`Self::LENGTH_SCALE`]),
/// first from the reference configuration, then from seeded random configurations
/// inside the joint limits. Joint values are clamped to their limits while
/// iterating.
#[derive(Debug, Clone, PartialEq)]
pub struct NumericIk {
    /// Settings (seed, restarts, iterations, tolerances).
    pub options: IkOptions,
}

/// Outcome of one descent.
pub(crate) struct Descent {
    pub(crate) q: Vec<f64>,
    pub(crate) pos_err: f64,
    pub(crate) ang_err: f64,
}

impl NumericIk {
    /// mm per radian used to weigh orientation against position errors.
    pub const LENGTH_SCALE: f64 = 100.0;

    /// A solver with `options`.
    pub fn from_options(options: &IkOptions) -> Self {
        Self {
            options: options.clone(),
        }
    }

    /// Pose error of `current` against `target` in the root frame: (position mm,
    /// rotation vector rad), both in root coordinates.
    fn error(target: &Isometry3<f64>, current: &Isometry3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let dp = target.translation.vector - current.translation.vector;
        let dr = (target.rotation * current.rotation.inverse()).scaled_axis();
        (dp, dr)
    }

    /// Geometric Jacobian (6 × dof, rows: linear mm, angular rad) of the TCP in the
    /// root frame.
    pub fn jacobian(robot: &Robot, q: &[f64]) -> DMatrix<f64> {
        let n = robot.dof();
        let mut jac = DMatrix::zeros(6, n);
        let links = robot.tree().links();
        let chain = robot
            .tree()
            .path_from_root(robot.flange())
            .unwrap_or_default();
        let tcp = robot.tcp_in_root(q).translation.vector;
        let mut pose = Isometry3::identity();
        let mut k = 0;
        for &i in &chain {
            let l = &links[i];
            if l.joint.kind != JointKind::Fixed {
                let axis = pose.rotation * l.joint.axis;
                if l.joint.kind == JointKind::Revolute {
                    let p = (pose * l.joint.point).coords;
                    let lin = axis.cross(&(tcp - p));
                    jac.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
                    jac.fixed_view_mut::<3, 1>(3, k).copy_from(&axis);
                } else {
                    jac.fixed_view_mut::<3, 1>(0, k).copy_from(&axis);
                }
                pose = pose * l.joint.motion(q.get(k).copied().unwrap_or(0.0)) * l.home.isometry();
                k += 1;
            } else {
                pose *= l.home.isometry();
            }
        }
        jac
    }

    fn clamp(robot: &Robot, q: &mut [f64], respect_limits: bool) {
        if !respect_limits {
            return;
        }
        for (v, l) in q.iter_mut().zip(robot.joint_limits()) {
            if let Some(l) = l {
                *v = v.clamp(l.min, l.max);
            }
        }
    }

    pub(crate) fn descend(
        &self,
        robot: &Robot,
        target: &Isometry3<f64>,
        start: &[f64],
        respect_limits: bool,
    ) -> Descent {
        let o = &self.options;
        let n = robot.dof();
        let mut q = start.to_vec();
        Self::clamp(robot, &mut q, respect_limits);
        let s = Self::LENGTH_SCALE;
        let cost = |q: &[f64]| {
            let (dp, dr) = Self::error(target, &robot.tcp_in_root(q));
            (
                dp.norm_squared() + (dr * s).norm_squared(),
                dp.norm(),
                dr.norm(),
            )
        };
        let (mut c, mut pe, mut ae) = cost(&q);
        let mut lambda = 1e-2;
        for _ in 0..o.max_iterations {
            if pe <= o.position_tolerance && ae <= o.angle_tolerance {
                break;
            }
            let (dp, dr) = Self::error(target, &robot.tcp_in_root(&q));
            let mut jac = Self::jacobian(robot, &q);
            for col in 0..n {
                for row in 3..6 {
                    jac[(row, col)] *= s;
                }
            }
            let e = DVector::from_iterator(6, dp.iter().copied().chain(dr.iter().map(|v| v * s)));
            let jt = jac.transpose();
            let jtj = &jt * &jac;
            let g = &jt * e;
            let mut improved = false;
            for _ in 0..12 {
                let mut a = jtj.clone();
                for d in 0..n {
                    a[(d, d)] += lambda * (1.0 + jtj[(d, d)]);
                }
                let Some(step) = a.cholesky().map(|ch| ch.solve(&g)) else {
                    lambda *= 10.0;
                    continue;
                };
                let mut cand: Vec<f64> = q.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
                Self::clamp(robot, &mut cand, respect_limits);
                let (cc, cp, ca) = cost(&cand);
                if cc < c {
                    q = cand;
                    c = cc;
                    pe = cp;
                    ae = ca;
                    lambda = (lambda * 0.1).max(1e-12);
                    improved = true;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        Descent {
            q,
            pos_err: pe,
            ang_err: ae,
        }
    }

    fn random_start(robot: &Robot, rng: &mut Rng) -> Vec<f64> {
        robot
            .joint_limits()
            .iter()
            .zip(robot.joint_kinds())
            .map(|(l, k)| match (l, k) {
                (Some(l), _) => rng.range(l.min, l.max),
                (None, JointKind::Prismatic) => rng.range(-500.0, 500.0),
                (None, _) => rng.range(-std::f64::consts::PI, std::f64::consts::PI),
            })
            .collect()
    }

    /// A random start for the chain's joints; external axes stay at the reference's
    /// values (they do not move the TCP, so a random value would only be carried
    /// into the solution).
    fn restart(robot: &Robot, rng: &mut Rng, reference: &[f64]) -> Vec<f64> {
        let mut q = Self::random_start(robot, rng);
        let n = robot.chain_dof();
        q[n..].copy_from_slice(&reference[n..]);
        q
    }

    /// Smallest singular value of the Jacobian divided by the largest.
    pub fn conditioning(robot: &Robot, q: &[f64]) -> f64 {
        // External axes do not move the TCP: their columns are zero and say nothing
        // about the chain's singularity.
        let mut jac = Self::jacobian(robot, q)
            .columns(0, robot.chain_dof())
            .into_owned();
        for col in 0..jac.ncols() {
            for row in 3..6 {
                jac[(row, col)] *= Self::LENGTH_SCALE;
            }
        }
        let sv = jac.singular_values();
        let max = sv.max();
        if max <= 0.0 {
            return 0.0;
        }
        // A chain with fewer than 6 joints has fewer singular values; the smallest of
        // those present is what matters.
        sv.min() / max
    }

    /// Solutions for the TCP pose `target` in the robot's root frame, nearest to
    /// `reference` first. Errors: [`IkError::Unreachable`] (no descent converged,
    /// with the best residual), [`IkError::JointLimits`] (converges only with a joint
    /// outside its limits), [`IkError::Singular`] (the solution has a rank-deficient
    /// Jacobian).
    pub fn solve(
        &self,
        robot: &Robot,
        target: &Transform,
        reference: &[f64],
    ) -> Result<Vec<IkSolution>, IkError> {
        if reference.len() != robot.dof() {
            return Err(IkError::Input(super::KinematicsError::JointCount {
                expected: robot.dof(),
                got: reference.len(),
            }));
        }
        if reference.iter().any(|v| !v.is_finite()) || !target.is_finite() {
            return Err(IkError::Unreachable(Unreachable::NotFinite));
        }
        let o = &self.options;
        let target = *target.isometry();
        let mut rng = Rng::new(o.seed);
        let mut found: Vec<IkSolution> = Vec::new();
        let mut best = (f64::INFINITY, f64::INFINITY);
        let attempts = o.restarts.max(1);
        let converged =
            |d: &Descent| d.pos_err <= o.position_tolerance && d.ang_err <= o.angle_tolerance;
        let mut singular = false;
        for attempt in 0..attempts {
            let start = if attempt == 0 {
                reference.to_vec()
            } else {
                Self::restart(robot, &mut rng, reference)
            };
            let d = self.descend(robot, &target, &start, true);
            if converged(&d) {
                if Self::conditioning(robot, &d.q) < o.singularity_threshold.max(1e-12) {
                    singular = true;
                    continue;
                }
                let distance =
                    d.q.iter()
                        .zip(reference)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt();
                if found
                    .iter()
                    .all(|s| s.joints.iter().zip(&d.q).any(|(a, b)| (a - b).abs() > 1e-6))
                {
                    found.push(IkSolution {
                        joints: d.q,
                        configuration: None,
                        distance,
                        // Converged solutions at a rank-deficient Jacobian are skipped above.
                        singular: false,
                    });
                    if found.len() >= o.max_solutions.max(1) {
                        break;
                    }
                }
            } else if d.pos_err + d.ang_err * Self::LENGTH_SCALE
                < best.0 + best.1 * Self::LENGTH_SCALE
            {
                best = (d.pos_err, d.ang_err);
            }
        }
        if !found.is_empty() {
            found.sort_by(|a, b| a.distance.total_cmp(&b.distance));
            return Ok(found);
        }
        if singular {
            return Err(IkError::Singular(Singularity::RankDeficient));
        }
        // Would it converge without the limits?
        let mut rng = Rng::new(o.seed ^ 0x5eed);
        for attempt in 0..attempts {
            let start = if attempt == 0 {
                reference.to_vec()
            } else {
                Self::restart(robot, &mut rng, reference)
            };
            let d = self.descend(robot, &target, &start, false);
            if converged(&d) {
                if let Some(j) = robot.limit_violation(&d.q) {
                    return Err(IkError::JointLimits {
                        joint: j + 1,
                        value: d.q[j],
                    });
                }
            }
        }
        Err(IkError::Unreachable(Unreachable::NoConvergence {
            distance_mm: best.0,
            angle_rad: best.1,
        }))
    }
}
