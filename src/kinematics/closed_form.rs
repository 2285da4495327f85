//! What the closed-form inverse-kinematics solvers share: the principal [`Branch`]es
//! of a target (up to 8, no limits applied), the expansion into every solution
//! within the joint limits, the [`ClosedFormIk`] trait that
//! [`OpwSolver`](super::OpwSolver) (spherical wrists) and
//! [`UrSolver`](super::UrSolver) (UR-type offset wrists) implement, and the steps
//! both derivations take: the canonical frame on axis 1, the arm plane (joint 1 from
//! the wrist point, joints 2 and 3 as a planar two-link problem), the tolerances that
//! follow the geometry, and the polish of a branch on the robot's own tree. Lengths
//! mm, angles rad, poses in the robot's root frame.
//!
//! # Tolerances follow the geometry
//! A closed form solves an *idealized* arm: axes exactly parallel or perpendicular,
//! wrist axes meeting exactly. Real descriptions are rounded (ROS-Industrial's
//! `ur_description` writes a roll of `1.570796327`), so the idealized arm differs from
//! the robot's tree by a model error (`ε_mm`, `ε_rad`) that detection measures on
//! sample configurations ([`ClosedFormIk::model_error`]). Every decision the closed
//! form takes at a singularity is taken within that error: the wrist point within
//! it of the shoulder cylinder is *on* it (one shoulder root, never a false
//! "unreachable"), the elbow within it of stretched *is* stretched (one elbow root),
//! axis 6 within it of axes 2–4 (or 4 and 6 of a spherical wrist) *is* aligned (the
//! free joint keeps the reference's value). Branches near a singularity but outside
//! those bands are polished on the robot's tree ([`Robot::inverse`]) when the
//! idealized arm is not exact, since the model error is amplified there.

use super::{
    Configuration, Elbow, IkError, IkOptions, IkSolution, JointKind, JointLimits, Robot, Shoulder,
    Unreachable, Wrist,
};
use crate::math::trig::{ang, atan2, hyp, rot2, wrap};
use crate::math::{Rng, Transform};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
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

    /// How far the solver's idealized arm is from the robot it was detected on: the
    /// largest TCP position (mm) and orientation (rad) difference between the two over
    /// sample configurations. ~1e-13 mm for an exact description; ~1e-7 mm for a
    /// URDF with rounded angles. The singularity tolerances follow it (see the
    /// module docs).
    fn model_error(&self) -> ModelError;

    /// The TCP pose (root frame, mm) of the idealized arm the closed form solves, at
    /// joint values `q` (rad).
    fn idealized_forward(&self, q: &[f64; 6]) -> Isometry3<f64>;

    /// [`branches_seeded`](Self::branches_seeded) with seed 0.
    #[inline]
    fn branches(&self, target: &Isometry3<f64>, singularity_threshold: f64) -> Branches {
        self.branches_seeded(target, singularity_threshold, 0.0)
    }

    /// All solutions for the TCP pose `target` (root frame, mm) within the joint
    /// limits, with every ±2π variant the limits allow, sorted by Euclidean joint
    /// distance to `reference` (rad); the wrist-singularity seed is the reference's
    /// [`SEED_JOINT`](Self::SEED_JOINT). The idealized arm's solutions, not polished on
    /// a robot's tree ([`Robot::inverse`](super::Robot::inverse) polishes).
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
    ) -> Result<Vec<IkSolution>, IkError>
    where
        Self: Sized,
    {
        solve(self, None, target, reference, options)
    }
}

/// How far a closed form's idealized arm is from the robot's tree (see
/// [`ClosedFormIk::model_error`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModelError {
    /// Largest TCP position difference (mm).
    pub mm: f64,
    /// Largest TCP orientation difference (rad).
    pub rad: f64,
}

impl ModelError {
    /// The idealized arm is the robot up to floating-point rounding: nothing to polish.
    pub fn is_exact(&self) -> bool {
        self.mm < 1e-10 && self.rad < 1e-13
    }
}

/// The shared steps of [`ClosedFormIk::solve`] and [`Robot::inverse`]: the branches
/// (seeded with the reference's free joint), the error when there is none, the
/// polish of near-singular branches on `robot`'s tree when the idealized arm is not
/// exact, and the expansion into every solution within the limits.
pub(crate) fn solve<S: ClosedFormIk, T: Solved>(
    solver: &S,
    robot: Option<&Robot>,
    target: &Transform,
    reference: &[f64],
    options: &IkOptions,
) -> Result<Vec<T>, IkError> {
    let seed = reference.get(S::SEED_JOINT).copied().unwrap_or(0.0);
    let mut branches =
        solver.branches_seeded(target.isometry(), options.singularity_threshold, seed);
    if branches.is_empty() {
        return Err(if branches.undetermined {
            IkError::Singular(super::Singularity::JointUndetermined)
        } else {
            IkError::Unreachable(solver.unreachable())
        });
    }
    let model = solver.model_error();
    if let Some(robot) = robot {
        if !model.is_exact() {
            let threshold = options.singularity_threshold;
            let x = target.isometry();
            let mut corrected = Vec::new();
            for b in branches.items[..branches.len]
                .iter_mut()
                .filter(|b| b.polish)
            {
                corrected.push(polish(solver, robot, x, threshold, seed, b));
            }
            // Far from the tree's solution (a near-singular wrist turns the model
            // error into large joint errors) the first pass can miss a branch whose
            // wrist point it put beyond the reach; asked for a corrected target the
            // idealized arm finds it: such branches are polished and kept if they
            // reach the target (provisional).
            for y in corrected {
                let again = solver.branches_seeded(&y, threshold, seed);
                for c in again.as_slice() {
                    if branches
                        .as_slice()
                        .iter()
                        .any(|b| b.configuration == c.configuration)
                    {
                        continue;
                    }
                    let mut c = *c;
                    polish(solver, robot, x, threshold, seed, &mut c);
                    c.provisional = true;
                    branches.push(c);
                }
            }
            // The solution at the reference, unless another branch holds it already
            // (near a shoulder or elbow singularity distinct branches are close).
            for i in 0..branches.len {
                if !branches.items[i].polish {
                    continue;
                }
                let Some(q) = toward_reference(robot, x, reference, &branches.items[i]) else {
                    continue;
                };
                let taken = branches.as_slice().iter().enumerate().any(|(j, b)| {
                    j != i
                        && b.joints
                            .iter()
                            .zip(&q)
                            .all(|(u, v)| wrap(u - v).abs() < 1e-7)
                });
                if !taken {
                    branches.items[i].joints = q;
                }
            }
        }
    }
    // Provisional branches stay only if they reach the target (within the model
    // error, against the tree; within rounding, against the idealized arm).
    if branches.as_slice().iter().any(|b| b.provisional) {
        let (mm, rad) = match robot {
            Some(_) => (8.0 * model.mm + 1e-9, 8.0 * model.rad + 1e-12),
            None => (1e-9, 1e-12),
        };
        let mut kept = Branches::new();
        for b in branches.as_slice() {
            let pose = match robot {
                Some(r) => r.tcp_in_root(&b.joints),
                None => solver.idealized_forward(&b.joints),
            };
            let d = target.isometry().rotation * pose.rotation.inverse();
            let ok = (target.isometry().translation.vector - pose.translation.vector).norm() <= mm
                && 2.0 * d.imag().norm().min(1.0).asin() <= rad;
            if !b.provisional || ok {
                kept.push(*b);
            }
        }
        kept.singular = branches.singular;
        kept.undetermined = branches.undetermined;
        kept.out_of_reach = true;
        branches = kept;
        if branches.is_empty() {
            return Err(IkError::Unreachable(solver.unreachable()));
        }
    }
    solutions_within_limits(branches.as_slice(), solver.joint_limits(), reference)
}

/// A solution as [`solutions_within_limits`] makes it: an [`IkSolution`] (one `Vec`
/// per solution), or a [`Solution6`] (joints inline) where the caller only reads it
/// and allocating per solution would be most of its cost beside the solve.
pub(crate) trait Solved {
    /// The solution `joints` of branch `b`, at `distance` from the reference.
    fn new(b: &Branch, joints: [f64; 6], distance: f64) -> Self;
    /// Its distance to the reference (the sort key).
    fn distance(&self) -> f64;
}

impl Solved for IkSolution {
    fn new(b: &Branch, joints: [f64; 6], distance: f64) -> Self {
        Solution6 {
            joints,
            configuration: b.configuration,
            distance,
            singular: b.singular,
        }
        .into()
    }

    fn distance(&self) -> f64 {
        self.distance
    }
}

/// An [`IkSolution`] of a 6-joint closed form with its joints inline (no allocation).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Solution6 {
    pub(crate) joints: [f64; 6],
    pub(crate) configuration: Configuration,
    pub(crate) distance: f64,
    pub(crate) singular: bool,
}

impl Solved for Solution6 {
    fn new(b: &Branch, joints: [f64; 6], distance: f64) -> Self {
        Self {
            joints,
            configuration: b.configuration,
            distance,
            singular: b.singular,
        }
    }

    fn distance(&self) -> f64 {
        self.distance
    }
}

impl From<Solution6> for IkSolution {
    fn from(s: Solution6) -> Self {
        Self {
            joints: s.joints.to_vec(),
            configuration: Some(s.configuration),
            distance: s.distance,
            singular: s.singular,
        }
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
    /// Near a singularity but outside the model-error bands: the idealized arm's
    /// error is amplified here, so [`Robot::inverse`] polishes the branch on the tree.
    pub(crate) polish: bool,
    /// Accepted only within the widened reach of a near-singular wrist (see
    /// [`ArmPlane::elbow`]): kept by [`solve`] only if it reaches the target after the
    /// polish (on the robot's tree, or on the idealized arm without a robot).
    pub(crate) provisional: bool,
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
    /// Branches were dropped because joint 1 or joint 2 is undetermined (the wrist
    /// point on axis 1 or on axis 2).
    pub undetermined: bool,
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
        polish: false,
        provisional: false,
    };

    pub(crate) fn new() -> Self {
        Self {
            items: [Self::EMPTY_BRANCH; 8],
            len: 0,
            singular: false,
            undetermined: false,
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

pub(crate) const PARALLEL_TOL: f64 = 1e-9;
/// Below this sine of the angle between axis 4 and the target's axis 6 the wrist is
/// treated as exactly singular. The arm joints of a target taken near a shoulder or
/// elbow singularity carry ~1e-13 rad of rounding, which shows up in that sine; 1e-10
/// absorbs it while the orientation error of snapping (the sine itself) stays below
/// 1e-10 rad.
pub(crate) const WRIST_SNAP: f64 = 1e-10;
pub(crate) const DISTANCE_TOL: f64 = 1e-6;

/// Branches nearer a singularity than this (the sine of the wrist or elbow angle,
/// the shoulder root over the wrist point's radius) are polished on the robot's tree
/// when the idealized arm is not exact: the model error divided by this stays below
/// 1e-7 rad elsewhere for any rounded description (model errors ≲ 1e-9 rad).
pub(crate) const POLISH_NEAR: f64 = 1e-2;

/// The canonical frame C of a closed form (returned as root ← C): origin on axis 1
/// (`p1`), `z = a1`, `x ⟂ a2` on the side of `w` (the wrist point at zero) or, when
/// `w` lies on axis 1, of `p3` (axis 3's point), `y = z × x` (axes 2 and 3 are `±y`).
pub(crate) fn canonical_frame(
    a1: Vector3<f64>,
    p1: Point3<f64>,
    a2: Vector3<f64>,
    w: Point3<f64>,
    p3: Point3<f64>,
) -> Isometry3<f64> {
    let ez = a1;
    let mut ex = a2.cross(&ez).normalize();
    let side = (w - p1).dot(&ex);
    let side = if side.abs() > DISTANCE_TOL {
        side
    } else {
        (p3 - p1).dot(&ex)
    };
    if side < -DISTANCE_TOL {
        ex = -ex;
    }
    let ey = ez.cross(&ex);
    let rc = Matrix3::from_columns(&[ex, ey, ez]);
    Isometry3::from_parts(
        Translation3::from(p1.coords),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rc)),
    )
}

/// The arm plane of both closed forms, in the canonical frame C: axes 2 and 3 are
/// parallel to `y` and cross the `xz` plane at `p2` and `p2 + u2`; the wrist point
/// (OPW: the wrist centre; UR: where axes 4 and 5 meet) is at `p2 + u2 + u3` at zero
/// and keeps `y = b`. Joint 1 comes from the wrist point's distance to axis 1, joints
/// 2 and 3 from a planar two-link problem. Lengths mm.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ArmPlane {
    /// Axis 2 in the arm plane (x, z).
    pub(crate) p2: [f64; 2],
    /// Upper arm (axis 2 → axis 3) and forearm (axis 3 → wrist point) at zero, (x, z).
    pub(crate) u2: [f64; 2],
    pub(crate) u3: [f64; 2],
    /// Lateral offset of the wrist point along y.
    pub(crate) b: f64,
    /// |u2|² + |u3|², 2|u2||u3|.
    len_sq: f64,
    len_prod2: f64,
    /// Angle from u2 to u3, its sine and cosine.
    pub(crate) gamma: f64,
    sg: f64,
    cg: f64,
    /// Reach of the wrist point from axis 2.
    pub(crate) reach: [f64; 2],
}

/// One root of joint 1 (see [`ArmPlane::shoulder`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ShoulderRoot {
    /// The wrist point's abscissa in the arm plane (mm).
    pub(crate) xp: f64,
    /// Sine, cosine and value of joint 1 (rad).
    pub(crate) s1: f64,
    pub(crate) c1: f64,
    pub(crate) q1: f64,
    /// Front (x' ≥ 0) or back.
    pub(crate) front: bool,
    /// |x'| / ρ: distance to the shoulder singularity (0 there).
    pub(crate) margin: f64,
    /// Taken as exactly singular (within the model error).
    pub(crate) snapped: bool,
}

impl ShoulderRoot {
    /// Its label.
    #[inline]
    pub(crate) fn shoulder(&self) -> Shoulder {
        if self.front {
            Shoulder::Front
        } else {
            Shoulder::Back
        }
    }
}

/// Joint 5 of both closed forms at the wrist singularity: exactly φ₅ when the
/// singular axes are aligned (`cos_wrist > 0`), φ₅ + π (wrapped) when opposed.
#[inline]
pub(crate) fn singular_q5(phi5: f64, cos_wrist: f64) -> f64 {
    if cos_wrist > 0.0 {
        phi5
    } else {
        wrap(phi5 + PI)
    }
}

/// One root of joints 2 and 3 (see [`ArmPlane::elbow`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ElbowRoot {
    /// Geometric angles of axes 2 and 3 about C's y (rad), and sine, cosine of their sum.
    pub(crate) th2: f64,
    pub(crate) th3: f64,
    pub(crate) s23: f64,
    pub(crate) c23: f64,
    /// The first (`el = +1`) root.
    pub(crate) first: bool,
    /// Sine of the elbow angle: distance to stretched or folded (0 there).
    pub(crate) margin: f64,
    /// Beyond the reach by more than the position band (within `slack`).
    pub(crate) beyond: bool,
    /// Taken as exactly stretched or folded (within the model error).
    pub(crate) snapped: bool,
}

impl ElbowRoot {
    /// Its label on shoulder root `sh`: the first root is elbow up on the front side.
    #[inline]
    pub(crate) fn elbow(&self, sh: &ShoulderRoot) -> Elbow {
        if self.first == sh.front {
            Elbow::Up
        } else {
            Elbow::Down
        }
    }
}

impl ArmPlane {
    /// The arm plane from axis 2's and 3's points and the wrist point at zero, in C
    /// (mm); `None` when the upper arm or the forearm has zero length.
    pub(crate) fn new(p2: Point3<f64>, p3: Point3<f64>, w: Point3<f64>) -> Option<Self> {
        let u2 = [p3.x - p2.x, p3.z - p2.z];
        let u3 = [w.x - p3.x, w.z - p3.z];
        let (l2, l3) = (u2[0].hypot(u2[1]), u3[0].hypot(u3[1]));
        if l2 < DISTANCE_TOL || l3 < DISTANCE_TOL {
            return None;
        }
        let gamma = ang(u3) - ang(u2);
        Some(Self {
            p2: [p2.x, p2.z],
            u2,
            u3,
            b: w.y,
            len_sq: l2 * l2 + l3 * l3,
            len_prod2: 2.0 * l2 * l3,
            gamma,
            sg: gamma.sin(),
            cg: gamma.cos(),
            reach: [(l2 - l3).abs(), l2 + l3],
        })
    }

    /// The wrist point in the arm plane (x, z) at geometric angles `th2`, `th3` (rad).
    pub(crate) fn wrist(&self, th2: f64, th3: f64) -> [f64; 2] {
        let (st, ct) = th3.sin_cos();
        let (s2, c2) = th2.sin_cos();
        let f = rot2(self.u3, st, ct);
        let arm = rot2([self.u2[0] + f[0], self.u2[1] + f[1]], s2, c2);
        [self.p2[0] + arm[0], self.p2[1] + arm[1]]
    }

    /// Joint 1 for the wrist point `w` (C, mm): `Rz(−q₁)·w = (x', b, ·)` with
    /// `x' = ±√(ρ² − b²)`, front first. Within the model error of the shoulder
    /// cylinder (`ρ = |b|`) the one double root `x' = 0`; beyond it out of reach (flag
    /// set in `out`); on axis 1 with no offset joint 1 is undetermined (flags set).
    #[inline(always)]
    pub(crate) fn shoulder(
        &self,
        w: &Vector3<f64>,
        tol: &Tolerances,
        threshold: f64,
        out: &mut Branches,
    ) -> ([ShoulderRoot; 2], usize) {
        let mut roots = [ShoulderRoot::default(); 2];
        let rho_sq = w.x * w.x + w.y * w.y;
        let disc = rho_sq - self.b * self.b;
        if disc < -tol.disc {
            out.out_of_reach = true;
            return (roots, 0);
        }
        let rho = rho_sq.sqrt();
        let snapped = disc <= tol.disc;
        // |(x', b)| = ρ, or |b| where ρ is snapped onto the cylinder.
        let norm = if snapped { rho * self.b.abs() } else { rho_sq };
        if (rho < threshold * tol.scale && self.b.abs() < DISTANCE_TOL) || norm <= 0.0 {
            out.singular = true;
            out.undetermined = true;
            return (roots, 0);
        }
        let root = if snapped { 0.0 } else { disc.sqrt() };
        let mut n = 0;
        for sh in [1.0_f64, -1.0] {
            if sh < 0.0 && snapped {
                break;
            }
            let xp = sh * root;
            let (s1, c1) = (
                (xp * w.y - self.b * w.x) / norm,
                (xp * w.x + self.b * w.y) / norm,
            );
            roots[n] = ShoulderRoot {
                xp,
                s1,
                c1,
                q1: atan2(s1, c1),
                front: sh > 0.0,
                margin: root / rho,
                snapped,
            };
            n += 1;
        }
        (roots, n)
    }

    /// Joints 2 and 3 putting the wrist point at `p2 + d` (arm plane, mm):
    /// `|u₂ + R(θ₃)u₃| = |d|`, `θ₃ = ±acos κ − γ`, θ₂ turning `u₂ + R(θ₃)u₃` onto
    /// `d`. With `|d|` within the position band `tol.len` of the longest or shortest
    /// reach (stretched or folded) the one double root; beyond the reach by up to
    /// `slack` (mm, at least `tol.len`: where the wrist amplifies the model error the
    /// wrist point itself is that uncertain) the same double root, to be polished;
    /// farther nothing (flag set); `d` on axis 2 leaves joint 2 undetermined (flags
    /// set).
    #[inline(always)]
    pub(crate) fn elbow(
        &self,
        d: [f64; 2],
        slack: f64,
        tol: &Tolerances,
        out: &mut Branches,
    ) -> ([ElbowRoot; 2], usize) {
        let mut roots = [ElbowRoot::default(); 2];
        let d2 = d[0] * d[0] + d[1] * d[1];
        let [lo, hi] = self.reach;
        let (band, slack) = (tol.len, slack.max(tol.len));
        // Bands in length, not in κ: snapping κ moves the wrist point by
        // Δκ·2|u2||u3| / 2|d|, which is large where |d| is short (folded).
        if d2 > (hi + slack) * (hi + slack) || (lo > slack && d2 < (lo - slack) * (lo - slack)) {
            out.out_of_reach = true;
            return (roots, 0);
        }
        let beyond =
            d2 > (hi + band) * (hi + band) || (lo > band && d2 < (lo - band) * (lo - band));
        let (kappa, snapped) = if d2 >= (hi - band) * (hi - band) {
            (1.0, true)
        } else if d2 <= (lo + band) * (lo + band) {
            (-1.0, true)
        } else {
            (
                ((d2 - self.len_sq) / self.len_prod2).clamp(-1.0, 1.0),
                false,
            )
        };
        // sin(acos κ) from (1 − κ)(1 + κ) (exact near ±1), and acos κ from it.
        let sk = if snapped {
            0.0
        } else {
            ((1.0 - kappa) * (1.0 + kappa)).sqrt()
        };
        let acos_k = atan2(sk, kappa);
        let mut n = 0;
        for el in [1.0_f64, -1.0] {
            if el < 0.0 && snapped {
                break;
            }
            // θ = el·acos κ − γ, its sine and cosine by the angle difference.
            let (sa, ca) = (el * sk, kappa);
            let (st, ct) = (sa * self.cg - ca * self.sg, ca * self.cg + sa * self.sg);
            let f = rot2(self.u3, st, ct);
            let v = [self.u2[0] + f[0], self.u2[1] + f[1]];
            // Angle from v to d about +y.
            let crs = d[0] * v[1] - d[1] * v[0];
            let dot = d[0] * v[0] + d[1] * v[1];
            let nrm = hyp(crs, dot);
            if nrm < 1e-12 * tol.scale * tol.scale {
                // The wrist point on axis 2: joint 2 undetermined.
                out.singular = true;
                out.undetermined = true;
                continue;
            }
            let (s2a, c2a) = (crs / nrm, dot / nrm);
            roots[n] = ElbowRoot {
                th2: atan2(crs, dot),
                th3: el * acos_k - self.gamma,
                s23: s2a * ct + c2a * st,
                c23: c2a * ct - s2a * st,
                first: el > 0.0,
                margin: sk,
                beyond,
                snapped,
            };
            n += 1;
        }
        (roots, n)
    }
}

/// The singularity bands of one closed form, from its model error (see the module
/// docs). Lengths mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tolerances {
    /// The measured model error.
    pub(crate) model: ModelError,
    /// Length scale of the arm (1 mm + reach + wrist offsets).
    pub(crate) scale: f64,
    /// Position band: four times the model error plus rounding.
    pub(crate) len: f64,
    /// Band of ρ² − b² around the shoulder cylinder (mm²): ρ within `len` of |b|.
    pub(crate) disc: f64,
    /// Band of the wrist sine around 0.
    pub(crate) wrist: f64,
    /// Orientation band (rad): four times the model error plus rounding.
    pub(crate) ang: f64,
}

impl Tolerances {
    /// The bands of an arm whose idealized form is `model` away from the tree;
    /// `lever` (mm) is the wrist's extent beyond the wrist point (UR: |e5|).
    pub(crate) fn new(arm: &ArmPlane, model: ModelError, lever: f64) -> Self {
        let scale = 1.0 + arm.reach[1] + lever;
        // The closed forms' own rounding reaches ~2e-10 mm on metre arms near a
        // shoulder singularity (x' = √(ρ² − b²) amplifies the target's last digits).
        let len = 4.0 * model.mm + 1e-12 * scale;
        let b = arm.b.abs();
        // Joint 1 moves the wrist sine through the wrist point's angle about axis 1,
        // wrong by up to len / ρ (ρ ≥ |b|, and the forearm for arms without offset).
        let lever1 = b.max(0.1 * arm.reach[0].max(0.1 * arm.reach[1]));
        Self {
            model,
            scale,
            len,
            disc: 2.0 * b * len + len * len + 1e-16 * scale * scale,
            wrist: WRIST_SNAP.max(4.0 * model.rad + 2.0 * len / lever1),
            ang: 4.0 * model.rad + 1e-15,
        }
    }
}

/// The model error of a closed form whose forward kinematics (root frame) is
/// `forward`, against `robot`'s tree: the zero configuration and 32 seeded ones.
pub(crate) fn measure_model_error(
    robot: &Robot,
    forward: impl Fn(&[f64; 6]) -> Isometry3<f64>,
) -> ModelError {
    let mut rng = Rng::new(0xcf1d);
    let mut e = ModelError::default();
    for k in 0..33 {
        let mut q = [0.0; 6];
        if k > 0 {
            for v in &mut q {
                *v = rng.range(-PI, PI);
            }
        }
        let a = forward(&q);
        let b = robot.tcp_in_root(&q);
        e.mm =
            e.mm.max((a.translation.vector - b.translation.vector).norm());
        // 2·asin(|imag|) keeps small angles that acos of the scalar part rounds away.
        let d = a.rotation.inverse() * b.rotation;
        e.rad = e.rad.max(2.0 * d.imag().norm().min(1.0).asin());
    }
    e
}

/// Takes a closed-form branch of the idealized arm to the robot's own tree: the
/// tree's pose at `branch` differs from `target` by the model error, so the
/// idealized arm is asked again for the target corrected by that difference
/// (`Y ← Y·T(q)⁻¹·X`, the same branch by its configuration), until the tree's pose
/// stops improving (at most four rounds). The correction varies with the joints
/// only at the model error's own scale, so this converges where a Newton step on the
/// near-singular Jacobian would overshoot along its valley. Returns the corrected
/// target for the final branch (where the idealized arm's other branches near this
/// one are found too).
pub(crate) fn polish<S: ClosedFormIk>(
    solver: &S,
    robot: &Robot,
    target: &Isometry3<f64>,
    threshold: f64,
    seed: f64,
    branch: &mut Branch,
) -> Isometry3<f64> {
    let residual = |q: &[f64; 6]| {
        let c = robot.tcp_in_root(q);
        let d = target.rotation * c.rotation.inverse();
        let e = (target.translation.vector - c.translation.vector).norm()
            + 2.0 * super::NumericIk::LENGTH_SCALE * d.imag().norm();
        (c, e)
    };
    let (mut real, mut err) = residual(&branch.joints);
    // The tree's pose is E·(the idealized arm's) with E varying slowly with the
    // joints: ask the idealized arm for E⁻¹·target, E from the current branch (its
    // own idealized pose, not the target it was asked for: a branch taken as
    // stretched within the reach slack does not reach that one).
    let corrected =
        |q: &[f64; 6], real: &Isometry3<f64>| solver.idealized_forward(q) * real.inverse() * target;
    for _ in 0..6 {
        if err == 0.0 {
            break;
        }
        let asked = corrected(&branch.joints, &real);
        let again = solver.branches_seeded(&asked, threshold, seed);
        let Some(next) = again
            .as_slice()
            .iter()
            .filter(|b| b.configuration == branch.configuration)
            .min_by(|a, b| {
                let d = |x: &Branch| -> f64 {
                    x.joints
                        .iter()
                        .zip(&branch.joints)
                        .map(|(u, v)| wrap(u - v).abs())
                        .sum()
                };
                d(a).total_cmp(&d(b))
            })
        else {
            break;
        };
        let (r, e) = residual(&next.joints);
        if e.is_nan() || e >= err {
            break;
        }
        branch.joints = next.joints;
        real = r;
        err = e;
    }
    corrected(&branch.joints, &real)
}

/// Near a singularity a description that is not exactly the idealized arm has
/// solutions in close pairs (a general 6R arm has up to 16; the idealized arm's
/// double roots split by the model error): the polished branch may be the partner
/// of the one at `reference`, a few 1e-6 rad away. When `reference` is that close
/// to the branch (every joint within 1e-4 rad, modulo 2π), Newton steps on the tree
/// started from the reference find the solution there: returned when it reaches the
/// target as well as the branch and stays that close.
fn toward_reference(
    robot: &Robot,
    target: &Isometry3<f64>,
    reference: &[f64],
    branch: &Branch,
) -> Option<[f64; 6]> {
    const NEAR: f64 = 1e-4;
    if reference.len() < 6 || robot.dof() != 6 {
        return None;
    }
    let mut q = [0.0; 6];
    for (k, v) in q.iter_mut().enumerate() {
        let d = wrap(reference[k] - branch.joints[k]);
        if d.is_nan() || d.abs() >= NEAR {
            return None;
        }
        *v = branch.joints[k] + d;
    }
    let s = super::NumericIk::LENGTH_SCALE;
    let error = |q: &[f64; 6]| {
        let c = robot.tcp_in_root(q);
        let dp = target.translation.vector - c.translation.vector;
        let dr = (target.rotation * c.rotation.inverse()).scaled_axis() * s;
        nalgebra::Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
    };
    let start = error(&branch.joints).norm();
    let mut e = error(&q);
    for _ in 0..8 {
        if e.norm() <= start.min(1e-12) {
            break;
        }
        let mut jac = super::NumericIk::jacobian(robot, &q);
        for col in 0..6 {
            for row in 3..6 {
                jac[(row, col)] *= s;
            }
        }
        let rhs = nalgebra::DVector::from_column_slice(e.as_slice());
        let Ok(dq) = jac.svd(true, true).solve(&rhs, 1e-14 * s) else {
            return None;
        };
        let mut next = q;
        for (k, v) in next.iter_mut().enumerate() {
            *v += dq[k];
        }
        let en = error(&next);
        if en.norm().is_nan() || en.norm() >= e.norm() {
            break;
        }
        q = next;
        e = en;
    }
    let stays = q
        .iter()
        .zip(&branch.joints)
        .all(|(a, b)| (a - b).abs() < NEAR);
    (stays && e.norm() <= start.max(1e-12)).then(|| q.map(wrap))
}

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
pub(crate) fn solutions_within_limits<T: Solved>(
    branches: &[Branch],
    limits: &[Option<JointLimits>; 6],
    reference: &[f64],
) -> Result<Vec<T>, IkError> {
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
            let joints: [f64; 6] = std::array::from_fn(|j| choices[j][idx[j]]);
            let distance = joints
                .iter()
                .zip(reference)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            out.push(T::new(br, joints, distance));
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
    out.sort_by(|a, b| a.distance().total_cmp(&b.distance()));
    Ok(out)
}

/// Checks the closed-form solvers share: their branch sets against an independent
/// brute-force numeric search.
#[cfg(test)]
pub(crate) mod testing;
