//! What the closed-form inverse-kinematics solvers share: the principal [`Branch`]es
//! of a target (up to 8, no limits applied), the expansion into every solution
//! within the joint limits, the [`ClosedFormIk`] trait that
//! [`OpwSolver`](super::OpwSolver) (spherical wrists) and
//! [`UrSolver`](super::UrSolver) (UR-type offset wrists) implement, and the planar
//! and axis helpers of their derivations. Lengths mm, angles rad, poses in the
//! robot's root frame.

use super::{
    Configuration, Elbow, IkError, IkOptions, IkSolution, JointKind, JointLimits, Robot, Shoulder,
    Unreachable, Wrist,
};
use crate::math::Transform;
use nalgebra::{Isometry3, Point3, Vector3};
use std::f64::consts::{PI, TAU};

/// A closed-form inverse-kinematics solver of a 6R arm: every principal branch of a
/// TCP pose (root frame, mm) at once, with a fixed rule at the wrist singularity,
/// and the solutions within the joint limits. Implemented by
/// [`OpwSolver`](super::OpwSolver) and [`UrSolver`](super::UrSolver); detected from
/// the robot's geometry by [`Robot::inverse`](super::Robot::inverse).
pub trait ClosedFormIk {
    /// The joint (0-based) that keeps the reference's value at a wrist singularity,
    /// where only a sum of two wrist joints is determined (OPW: joint 4, UR: joint 6).
    const SEED_JOINT: usize;

    /// Every principal branch (up to 8: shoulder × elbow × wrist) reaching `target`
    /// (root frame, mm); joint values in (−π, π], no limits applied. At a wrist
    /// singularity the [`SEED_JOINT`](Self::SEED_JOINT) keeps `seed` (wrapped) on the
    /// no-flip branch and `seed + π` on the flip branch; branches with a sine of the
    /// singular angle below `singularity_threshold` are flagged [`Branch::singular`].
    fn branches_seeded(
        &self,
        target: &Isometry3<f64>,
        singularity_threshold: f64,
        seed: f64,
    ) -> Branches;

    /// The joint limits (rad) the solutions must keep; `None`: unlimited.
    fn joint_limits(&self) -> &[Option<JointLimits>; 6];

    /// Why a target with no branch (and no singularity) is out of reach: the arm's
    /// reach as detected.
    fn unreachable(&self) -> Unreachable;

    /// [`branches_seeded`](Self::branches_seeded) with seed 0.
    #[inline]
    fn branches(&self, target: &Isometry3<f64>, singularity_threshold: f64) -> Branches {
        self.branches_seeded(target, singularity_threshold, 0.0)
    }

    /// All solutions for the TCP pose `target` (root frame, mm) within the joint
    /// limits, with every ±2π variant the limits allow, sorted by Euclidean joint
    /// distance to `reference` (rad); the wrist-singularity seed is the reference's
    /// [`SEED_JOINT`](Self::SEED_JOINT).
    ///
    /// # Errors
    /// [`IkError::Singular`] when joint 1 or 2 is undetermined (the wrist point on
    /// axis 1 or 2), [`IkError::Unreachable`] out of reach,
    /// [`IkError::JointLimits`] when every branch violates a limit.
    fn solve(
        &self,
        target: &Transform,
        reference: &[f64],
        options: &IkOptions,
    ) -> Result<Vec<IkSolution>, IkError> {
        let seed = reference.get(Self::SEED_JOINT).copied().unwrap_or(0.0);
        let branches = self.branches_seeded(target.isometry(), options.singularity_threshold, seed);
        if branches.is_empty() {
            return Err(if branches.singular {
                IkError::Singular(super::Singularity::JointUndetermined)
            } else {
                IkError::Unreachable(self.unreachable())
            });
        }
        solutions_within_limits(branches.as_slice(), self.joint_limits(), reference)
    }
}

/// The configuration tag of one principal branch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Branch {
    /// Joint values in (−π, π] (rad).
    pub joints: [f64; 6],
    /// Shoulder, elbow and wrist choice.
    pub configuration: Configuration,
    /// Axes 4 and 6 are (within the singularity threshold) aligned: joints 4 and 6
    /// are ill-conditioned; at the singularity itself joint 5 is exactly φ₅ (0 for the
    /// usual wrist) and joint 4 keeps the seed (see [`ClosedFormIk::branches_seeded`]).
    pub singular: bool,
}

/// Up to eight principal branches (joint values in (−π, π], no limits applied), in a
/// fixed-capacity array so that solving allocates nothing.
#[derive(Debug, Clone, Copy)]
pub struct Branches {
    items: [Branch; 8],
    len: usize,
    /// The target is at or near a singularity: some branch is flagged
    /// [`Branch::singular`] (wrist), or branches were dropped because joint 1 or
    /// joint 2 is undetermined (wrist centre on axis 1 or on axis 2).
    pub singular: bool,
    /// Some branch was dropped because the wrist centre is out of reach.
    pub out_of_reach: bool,
}

impl Branches {
    const EMPTY_BRANCH: Branch = Branch {
        joints: [0.0; 6],
        configuration: Configuration {
            shoulder: Shoulder::Front,
            elbow: Elbow::Up,
            wrist: Wrist::NoFlip,
        },
        singular: false,
    };

    pub(crate) fn new() -> Self {
        Self {
            items: [Self::EMPTY_BRANCH; 8],
            len: 0,
            singular: false,
            out_of_reach: false,
        }
    }

    /// The branches found.
    pub fn as_slice(&self) -> &[Branch] {
        &self.items[..self.len]
    }

    /// Number of branches found (0..=8).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no branch was found.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[inline]
    pub(crate) fn push(&mut self, b: Branch) {
        if self.len < 8 {
            self.items[self.len] = b;
            self.len += 1;
        }
    }
}

/// Angle of the planar vector (x, z), increasing with right-hand rotation about +y.
#[inline]
pub(crate) fn ang(v: [f64; 2]) -> f64 {
    v[0].atan2(v[1])
}

/// Rotation of the planar vector (x, z) about +y by the angle with sine `s`, cosine `c`.
#[inline]
pub(crate) fn rot2(v: [f64; 2], s: f64, c: f64) -> [f64; 2] {
    [v[0] * c + v[1] * s, -v[0] * s + v[1] * c]
}

/// Rodrigues rotation of `v` about unit `k` by the angle with sine `s`, cosine `c`.
#[inline]
pub(crate) fn rot_vec(k: &Vector3<f64>, s: f64, c: f64, v: &Vector3<f64>) -> Vector3<f64> {
    v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c))
}

/// Wraps an angle into (−π, π].
#[inline]
pub(crate) fn wrap(a: f64) -> f64 {
    // Inputs here are sums of a few angles in (−π, π]: subtracting turns is cheaper
    // than a floating-point remainder; the remainder covers anything larger.
    let mut r = if a.abs() > 4.0 * TAU { a % TAU } else { a };
    while r > PI {
        r -= TAU;
    }
    while r <= -PI {
        r += TAU;
    }
    r
}

pub(crate) const PARALLEL_TOL: f64 = 1e-9;
/// Below this sine of the angle between axis 4 and the target's axis 6 the wrist is
/// treated as exactly singular. The arm joints of a target taken near a shoulder or
/// elbow singularity carry ~1e-13 rad of rounding, which shows up in that sine; 1e-10
/// absorbs it while the orientation error of snapping (the sine itself) stays below
/// 1e-10 rad.
pub(crate) const WRIST_SNAP: f64 = 1e-10;
pub(crate) const DISTANCE_TOL: f64 = 1e-6;

/// Six joint axis lines: unit direction and a point (mm).
pub(crate) type AxisLines = [(Vector3<f64>, Point3<f64>); 6];

/// Joint axis lines (unit direction, point) of a 6R robot at the zero configuration in
/// the root frame, and the TCP pose at zero (mm); `None` unless the flange chain has
/// exactly six joints, all revolute.
pub(crate) fn zero_axis_lines(robot: &Robot) -> Option<(AxisLines, Isometry3<f64>)> {
    if robot.dof() != 6
        || robot
            .joint_kinds()
            .iter()
            .any(|k| *k != JointKind::Revolute)
    {
        return None;
    }
    let links = robot.tree().links();
    let chain = robot.tree().path_from_root(robot.flange())?;
    let mut pose = Isometry3::identity();
    let mut axes = [(Vector3::zeros(), Point3::origin()); 6];
    let mut k = 0;
    for &i in &chain {
        let l = &links[i];
        if l.joint.kind != JointKind::Fixed {
            axes[k] = (pose.rotation * l.joint.axis, pose * l.joint.point);
            k += 1;
        }
        pose *= l.home.isometry();
    }
    Some((axes, pose * robot.tool().isometry()))
}

/// Expands principal branches (joint values in (−π, π]) into every solution within
/// `limits`, with each ±2π variant a limit range allows (an unlimited joint takes the
/// representative nearest the reference), sorted by Euclidean joint distance to
/// `reference`; the error names the first violated joint of the nearest branch when
/// every branch is outside the limits. Shared by the closed-form solvers.
pub(crate) fn solutions_within_limits(
    branches: &[Branch],
    limits: &[Option<JointLimits>; 6],
    reference: &[f64],
) -> Result<Vec<IkSolution>, IkError> {
    let mut out = Vec::new();
    let mut first_violation: Option<(f64, usize, f64)> = None;
    for br in branches {
        let mut choices: [[f64; 4]; 6] = [[0.0; 4]; 6];
        let mut counts = [0usize; 6];
        for j in 0..6 {
            let v = br.joints[j];
            match limits[j] {
                None => {
                    // Unlimited: the representative nearest the reference.
                    let r = reference.get(j).copied().unwrap_or(0.0);
                    choices[j][0] = v + TAU * ((r - v) / TAU).round();
                    counts[j] = 1;
                }
                Some(l) => {
                    let kmin = ((l.min - 1e-9 - v) / TAU).ceil() as i64;
                    let kmax = ((l.max + 1e-9 - v) / TAU).floor() as i64;
                    let mut k = kmin;
                    while k <= kmax && counts[j] < 4 {
                        choices[j][counts[j]] = (v + TAU * k as f64).clamp(l.min, l.max);
                        counts[j] += 1;
                        k += 1;
                    }
                }
            }
        }
        if let Some(j) = counts.iter().position(|&c| c == 0) {
            let dist: f64 = br
                .joints
                .iter()
                .zip(reference)
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            if first_violation.is_none_or(|(d, _, _)| dist < d) {
                first_violation = Some((dist, j + 1, br.joints[j]));
            }
            continue;
        }
        let mut idx = [0usize; 6];
        loop {
            let joints: Vec<f64> = (0..6).map(|j| choices[j][idx[j]]).collect();
            let distance = joints
                .iter()
                .zip(reference)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            out.push(IkSolution {
                joints,
                configuration: Some(br.configuration),
                distance,
                singular: br.singular,
            });
            let mut j = 0;
            loop {
                idx[j] += 1;
                if idx[j] < counts[j] {
                    break;
                }
                idx[j] = 0;
                j += 1;
                if j == 6 {
                    break;
                }
            }
            if j == 6 {
                break;
            }
        }
    }
    if out.is_empty() {
        let (_, joint, value) = first_violation.unwrap_or((0.0, 1, 0.0));
        return Err(IkError::JointLimits { joint, value });
    }
    out.sort_by(|a, b| a.distance.total_cmp(&b.distance));
    Ok(out)
}

/// Checks the closed-form solvers share: their branch sets against an independent
/// brute-force numeric search.
#[cfg(test)]
pub(crate) mod testing {
    use super::wrap;
    use crate::kinematics::{Branches, Catalog, IkOptions, NumericIk, Robot};
    use crate::math::Rng;
    use nalgebra::Isometry3;
    use std::f64::consts::PI;

    /// Joint vectors equal up to whole turns, within `tol` rad per joint.
    pub(crate) fn same_angles(a: &[f64], b: &[f64], tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| wrap(x - y).abs() < tol)
    }

    /// For each arm, three targets reached at joints drawn by `draw_q`: a numeric
    /// descent from 60 random starts (unlimited, like the branch sets) finds no
    /// solution that `branches` (the closed form, threshold 1e-9) misses, and finds at
    /// least one. `max_iterations` bounds each descent.
    pub(crate) fn assert_no_branch_missing(
        arms: &[Catalog],
        seed: u64,
        max_iterations: usize,
        draw_q: impl Fn(&mut Rng, &Robot) -> Vec<f64>,
        branches: impl Fn(&Robot, &Isometry3<f64>) -> Branches,
    ) {
        let mut rng = Rng::new(seed);
        let numeric = NumericIk::from_options(&IkOptions {
            restarts: 1,
            max_iterations,
            ..IkOptions::default()
        });
        for arm in arms {
            let r = arm.robot();
            for _ in 0..3 {
                let q = draw_q(&mut rng, &r);
                let target = r.tcp_pose(&q).unwrap();
                let br = branches(&r, target.isometry());
                assert!(!br.is_empty(), "{}: no branch at {q:?}", arm.name());
                let mut found = 0;
                for _ in 0..60 {
                    let start: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
                    let d = numeric.descend(&r, target.isometry(), &start, false);
                    if d.pos_err < 1e-6 && d.ang_err < 1e-9 {
                        found += 1;
                        assert!(
                            br.as_slice()
                                .iter()
                                .any(|b| same_angles(&b.joints, &d.q, 1e-5)),
                            "{}: numeric solution {:?} not among {:?}",
                            arm.name(),
                            d.q,
                            br.as_slice()
                        );
                    }
                }
                assert!(found > 0, "{}: brute force found nothing", arm.name());
            }
        }
    }
}
