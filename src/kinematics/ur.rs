//! [`UrSolver`]: closed-form inverse kinematics of 6R arms with three parallel axes
//! 2-3-4 and an offset (non-spherical) wrist, the Universal Robots geometry
//! (UR3/5/10/16/20/30 and their e-Series), derived from the tree geometry like
//! [`OpwSolver`](super::OpwSolver) (no per-robot code, any link frames).
//!
//! # Derivation (product of exponentials)
//! With the zero-configuration axis lines (`aᵢ`, `pᵢ`) the TCP pose is
//! `T(q) = E₁(q₁)·…·E₆(q₆)·T₀`. The arm qualifies when `a₁ ⟂ a₂`, `a₂ ∥ a₃ ∥ a₄`,
//! axes 4 and 5 meet in a point `W₄` with `a₅ ⟂ a₄`, and axes 5 and 6 meet in a
//! point `W₅` with `a₆ ⟂ a₅` (`W₅ = W₄ + e₅·a₅`).
//!
//! A canonical frame C is put on axis 1: `z = a₁`, `y ∥ a₂` (axes 2, 3, 4 are `sᵢ·y`,
//! `sᵢ = ±1`, crossing the `xz` plane at `P₂`, `P₃`, `P₄`). Joints 2–4 turn about
//! lines parallel to `y`, so the orientation is
//! `R_X·R₀ᵀ = Rz(q₁)·Ry(θ₂₃₄)·Rot(a₅,q₅)·Rot(a₆,q₆)` with `θ₂₃₄ = s₂q₂ + s₃q₃ + s₄q₄`.
//!
//! - **Axis 1.** `W₅` is fixed on links 5 and 6, so the target gives it:
//!   `W₅ = X·(T₀⁻¹W₅)`. Every point on axis 5 keeps the `y` coordinate `b` of `W₄` in
//!   the frame turned by `q₁` (`a₅ ⟂ y` and joints 2–4 preserve `y`), so
//!   `Rz(−q₁)W₅ = (x', b, ·)` with `x' = ±√(ρ² − b²)`, `ρ² = W₅x² + W₅y²` (shoulder
//!   front/back; `ρ < |b|` is out of reach, `ρ = |b|` the shoulder singularity with one
//!   double root).
//! - **Axis 5.** `y·Rz(−q₁)·t₆ = y·Rot(a₅,q₅)a₆ = A cos q₅ + B sin q₅` with
//!   `t₆ = R_X·R₀ᵀ·a₆`, `A = y·a₆`, `B = y·(a₅×a₆)`, `A² + B² = 1`:
//!   `q₅ = φ₅ ± δ`, `φ₅ = atan2(B, A)`, `δ = ∠(y, Rz(−q₁)t₆)` (wrist flip).
//! - **Axis 6.** With `M = Rz(−q₁)·R_X·R₀ᵀ`, `Rot(a₆,q₆)·Mᵀy = Rot(a₅,−q₅)·y`: `q₆`
//!   turns `Mᵀy` onto `Rot(a₅,−q₅)y` about `a₆`. When `sin δ = 0` (`a₆` after joint 5
//!   parallel to axes 2–4, the wrist singularity; θ₅ = 0 on a UR) only `θ₂₃₄ ± q₆` is
//!   determined: the rule is that `q₆` keeps the reference's joint 6 (no-flip label)
//!   or that plus π (flip label).
//! - **θ₂₃₄** is the angle about `y` of `M·Rot(a₆,−q₆)·Rot(a₅,−q₅)`.
//! - **Axes 2, 3.** `W₄ = Rz(−q₁)W₅ − e₅·Ry(θ₂₃₄)a₅` is a planar 2R problem in `xz`,
//!   solved as in the OPW solver (elbow up/down; `|κ| = 1` is the stretched or folded
//!   elbow with one double root); `q₄ = s₄(θ₂₃₄ − θ₂ − θ₃)`.

use super::closed_form::{
    canonical_frame, measure_model_error, singular_q5, zero_axis_lines, ArmPlane, ModelError,
    Tolerances, DISTANCE_TOL, PARALLEL_TOL, POLISH_NEAR,
};
use super::{
    Branch, Branches, ClosedFormIk, Configuration, JointLimits, Robot, Unreachable, Wrist,
};
use crate::math::trig::atan2;
use crate::math::trig::{hyp, rot2, wrap};
use nalgebra::{Isometry3, Matrix3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Why a robot does not qualify for the UR closed-form solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum NotUr {
    /// The chain does not have exactly six revolute joints.
    #[error("the chain does not have exactly six revolute joints")]
    NotSixRevolute,
    /// Axes 1 and 2 are not perpendicular.
    #[error("axes 1 and 2 are not perpendicular")]
    Axes12NotPerpendicular,
    /// Axes 2, 3 and 4 are not parallel.
    #[error("axes 2, 3 and 4 are not parallel")]
    Axes234NotParallel,
    /// Axes 4 and 5 do not meet in a point at a right angle.
    #[error("axes 4 and 5 do not meet at a right angle")]
    Axes45NotMeeting,
    /// Axes 5 and 6 do not meet in a point at a right angle.
    #[error("axes 5 and 6 do not meet at a right angle")]
    Axes56NotMeeting,
    /// Zero upper-arm or forearm length.
    #[error("zero upper-arm or forearm length")]
    Degenerate,
}

/// Closed-form solver of a UR-type arm (tool included), every parameter precomputed
/// from the tree geometry at the zero configuration and idealized (axis 5 exactly
/// perpendicular to axes 2–4, axis 6 to axis 5); the difference to the tree is
/// [`ClosedFormIk::model_error`]. Works in the robot's root frame (the [`Robot`]
/// applies its base pose). Lengths in mm, angles in radians.
#[derive(Debug, Clone, PartialEq)]
pub struct UrSolver {
    /// C ← root frame and back.
    c_from_root: Isometry3<f64>,
    root_from_c: Isometry3<f64>,
    /// Axes 2, 3 and the wrist point W₄ (where axes 4 and 5 meet) in the arm plane.
    arm: ArmPlane,
    /// Signs of axes 2, 3, 4 relative to C's y.
    s: [f64; 3],
    /// Axes 5 and 6 at zero in C (a5 ⟂ y, a6 ⟂ a5) and a6 × a5.
    a5: Vector3<f64>,
    a6: Vector3<f64>,
    a6x5: Vector3<f64>,
    /// Signed distance W₄ → W₅ along a₅ (mm).
    e5: f64,
    /// φ₅ = atan2(y·(a₅×a₆), y·a₆).
    phi5: f64,
    /// W₅ in the TCP frame (mm).
    w5_tcp: Vector3<f64>,
    /// R₀ (TCP rotation at zero in C) and R₀ᵀ.
    r0: UnitQuaternion<f64>,
    r0t: Matrix3<f64>,
    tol: Tolerances,
    limits: [Option<JointLimits>; 6],
}

/// The point where two lines meet, or `None` when they are parallel or pass more than
/// [`DISTANCE_TOL`] apart.
fn meet(pa: Point3<f64>, a: Vector3<f64>, pb: Point3<f64>, b: Vector3<f64>) -> Option<Point3<f64>> {
    let cb = a.dot(&b);
    let denom = 1.0 - cb * cb;
    if denom < 1e-12 {
        return None;
    }
    let w = pa - pb;
    let (d, e) = (a.dot(&w), b.dot(&w));
    let s = (cb * e - d) / denom;
    let t = (e - cb * d) / denom;
    let ca = pa + a * s;
    let cb = pb + b * t;
    ((ca - cb).norm() <= DISTANCE_TOL).then(|| Point3::from((ca.coords + cb.coords) * 0.5))
}

/// `φ` snapped onto 0 or π when within the detection tolerance of it: rounded
/// descriptions put the UR wrist's φ₅ a few 1e-10 off, and the exact value makes
/// singular targets give joint 5 exactly 0 (or π).
pub(crate) fn snap_phi(phi: f64) -> f64 {
    if phi.abs() < PARALLEL_TOL {
        0.0
    } else if (phi.abs() - PI).abs() < PARALLEL_TOL {
        PI
    } else {
        phi
    }
}

impl UrSolver {
    /// Derives the solver from a robot's geometry at the zero configuration, or says
    /// why the robot does not qualify.
    pub fn detect(robot: &Robot) -> Result<Self, NotUr> {
        let (axes, tcp0) = zero_axis_lines(robot).ok_or(NotUr::NotSixRevolute)?;
        let [(a1, p1), (a2, p2), (a3, p3), (a4, p4), (a5, p5), (a6, p6)] = axes;
        if a1.dot(&a2).abs() > PARALLEL_TOL {
            return Err(NotUr::Axes12NotPerpendicular);
        }
        if a2.cross(&a3).norm() > PARALLEL_TOL || a2.cross(&a4).norm() > PARALLEL_TOL {
            return Err(NotUr::Axes234NotParallel);
        }
        if a4.dot(&a5).abs() > PARALLEL_TOL {
            return Err(NotUr::Axes45NotMeeting);
        }
        let w4 = meet(p4, a4, p5, a5).ok_or(NotUr::Axes45NotMeeting)?;
        if a5.dot(&a6).abs() > PARALLEL_TOL {
            return Err(NotUr::Axes56NotMeeting);
        }
        let w5 = meet(p5, a5, p6, a6).ok_or(NotUr::Axes56NotMeeting)?;
        // Canonical frame C on axis 1, x towards W₅ at zero (as the OPW solver does).
        let root_from_c = canonical_frame(a1, p1, a2, w5, p3);
        let c_from_root = root_from_c.inverse();
        let ey = root_from_c.rotation * Vector3::y();
        let arm = ArmPlane::new(c_from_root * p2, c_from_root * p3, c_from_root * w4)
            .ok_or(NotUr::Degenerate)?;
        // The idealized wrist: a5 ⟂ y (axes 2–4), a6 ⟂ a5.
        let a5c = c_from_root.rotation * a5;
        let a5c = Vector3::new(a5c.x, 0.0, a5c.z).normalize();
        let a6c = c_from_root.rotation * a6;
        let a6c = (a6c - a5c * a5c.dot(&a6c)).normalize();
        let phi5 = snap_phi(a5c.cross(&a6c).y.atan2(a6c.y));
        let tcp0_c = c_from_root * tcp0;
        let e5 = (w5 - w4).dot(&a5);
        let mut limits = [None; 6];
        limits.copy_from_slice(&robot.joint_limits()[..6]);
        let mut solver = Self {
            c_from_root,
            root_from_c,
            s: [
                ey.dot(&a2).signum(),
                ey.dot(&a3).signum(),
                ey.dot(&a4).signum(),
            ],
            a5: a5c,
            a6: a6c,
            a6x5: a6c.cross(&a5c),
            e5,
            phi5,
            w5_tcp: (tcp0.inverse() * w5).coords,
            r0: tcp0_c.rotation,
            r0t: tcp0_c
                .rotation
                .to_rotation_matrix()
                .into_inner()
                .transpose(),
            tol: Tolerances::new(&arm, ModelError::default(), e5.abs()),
            arm,
            limits,
        };
        let model = measure_model_error(robot, |q| solver.forward(q));
        solver.tol = Tolerances::new(&solver.arm, model, e5.abs());
        Ok(solver)
    }

    /// The detected parameters: lateral offset `b` of axis 5 from axis 1 (mm), the
    /// upper-arm and forearm vectors in the arm plane `(x, z)` (mm), the signed
    /// distance `e5` between the wrist points on axis 5 (mm) and the distance from
    /// `W₅` to the TCP (mm).
    pub fn parameters(&self) -> UrParameters {
        UrParameters {
            b: self.arm.b,
            upper_arm: self.arm.u2,
            forearm: self.arm.u3,
            e5: self.e5,
            tcp_offset: self.w5_tcp.norm(),
        }
    }

    /// TCP pose in the root frame for joint values `q` (rad) of the idealized arm, in
    /// closed form: `Rz(q₁)·[W₄(θ₂, θ₃) + e₅·Ry(θ₂₃₄)a₅] − R·w₅` with
    /// `R = Rz(q₁)·Ry(θ₂₃₄)·Rot(a₅,q₅)·Rot(a₆,q₆)·R₀`.
    pub fn forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        let (th2, th3) = (self.s[0] * q[1], self.s[1] * q[2]);
        let th = th2 + th3 + self.s[2] * q[3];
        let [x, z] = self.arm.wrist(th2, th3);

        let (st, ct) = th.sin_cos();
        let a5r = rot2([self.a5.x, self.a5.z], st, ct);
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[0]);
        let w5 = rz * Vector3::new(x + self.e5 * a5r[0], self.arm.b, z + self.e5 * a5r[1]);
        let r = rz
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), th)
            * UnitQuaternion::from_axis_angle(&Unit::new_unchecked(self.a5), q[4])
            * UnitQuaternion::from_axis_angle(&Unit::new_unchecked(self.a6), q[5])
            * self.r0;
        self.root_from_c * Isometry3::from_parts(Translation3::from(w5 - r * self.w5_tcp), r)
    }
}

impl ClosedFormIk for UrSolver {
    const SEED_JOINT: usize = 5;

    /// Every principal branch (up to 8: shoulder × wrist × elbow) reaching `target`
    /// (root frame, mm); joint values in (−π, π], no limits applied.
    ///
    /// **Wrist singularity** (axis 6 parallel to axes 2–4: the wrist sine within the
    /// model error of 0, at least 1e-10): every arm branch still comes back with both
    /// wrist labels and `singular` set; joint 5 is exactly φ₅ (0 on a UR; φ₅ + π when
    /// the axes are opposed) and only `θ₂₃₄ ± q₆` is determined. Rule: joint 6 keeps
    /// `q6_seed` (wrapped) on the no-flip branch and `q6_seed + π` on the flip branch;
    /// joints 2–4 take the rest. Near the singularity (sine below
    /// `singularity_threshold`) branches are solved normally and flagged. **Shoulder
    /// singularity** (`ρ = |b|`) and **stretched or folded elbow** (`|κ| = 1`), each
    /// within the model error: the two roots coincide and come back once. With no
    /// lateral offset and `W₅` on axis 1, or `W₄` on axis 2, joint 1 or 2 is
    /// undetermined: those branches are dropped and [`Branches::undetermined`] set.
    fn branches_seeded(
        &self,
        target: &Isometry3<f64>,
        singularity_threshold: f64,
        q6_seed: f64,
    ) -> Branches {
        let mut out = Branches::new();
        let x = self.c_from_root * target;
        let rx = x.rotation.to_rotation_matrix().into_inner();
        let w = rx * self.w5_tcp + x.translation.vector;
        if !(w.iter().all(|v| v.is_finite()) && rx.iter().all(|v| v.is_finite())) {
            out.out_of_reach = true;
            return out;
        }
        // R_X·R₀ᵀ = Rz(q1)·Ry(θ234)·Rot(a5,q5)·Rot(a6,q6), and its images of a6, a5
        // and a6 × a5: everything the wrist needs.
        let rt = rx * self.r0t;
        let (t6, ra5, ra65) = (rt * self.a6, rt * self.a5, rt * self.a6x5);
        let tol = &self.tol;
        let (shoulders, n_sh) = self.arm.shoulder(&w, tol, singularity_threshold, &mut out);
        for sh in &shoulders[..n_sh] {
            let mut sh = *sh;
            // t = Rz(−q1)·t6; the wrist sine and cosine δ = ∠(y, t).
            let tx = sh.c1 * t6.x + sh.s1 * t6.y;
            let mut cw = -sh.s1 * t6.x + sh.c1 * t6.y;
            let mut sd = hyp(tx, t6.z);
            // At the wrist singularity axis 6 lies along axes 2–4, Rz(q1)·y: joint 1
            // follows from the orientation alone, where the position's joint 1 is off
            // by the position band over x' (x' = √(ρ² − b²) near the shoulder
            // singularity): when axis 6 is level within the wrist band and the
            // position's joint 1 agrees within its own error, the wrist is singular
            // and joint 1 the orientation's.
            // (The lengths and joint 1's error only where axis 6 is level.)
            let mut snapped = sd < tol.wrist;
            let level = !snapped && t6.z.abs() < tol.wrist;
            let t6h = if level { hyp(t6.x, t6.y) } else { 0.0 };
            let near = level && t6h > 0.5 && {
                let rho = hyp(w.x, w.y);
                let xp_eff = sh.xp.abs().max(tol.disc.sqrt());
                let dq1 = tol.len / rho + self.arm.b.abs() * tol.len / (rho * xp_eff);
                sd < tol.wrist + dq1
            };
            if near {
                let sign = cw.signum();
                let (s1, c1) = (-sign * t6.x / t6h, sign * t6.y / t6h);
                sh.s1 = s1;
                sh.c1 = c1;
                sh.q1 = atan2(s1, c1);
                sh.xp = c1 * w.x + s1 * w.y;
                cw = sign * t6h;
                sd = t6.z.abs();
                snapped = true;
            }
            let (s1, c1) = (sh.s1, sh.c1);
            let near_singular = sd < singularity_threshold;
            out.singular |= near_singular || snapped;
            // No-flip wrist: q5 = φ5 + δ, and q6 turns Mᵀy onto Rot(a5,−q5)y about a6
            // with M = Rz(−q1)·R_X·R₀ᵀ. In the basis (a5, a6 × a5) of the plane ⟂ a6 the
            // former is (r1, r2) = (Rz(q1)y)·(R a5, R (a6×a5)) and the latter
            // (0, sin(q5 − φ5)): q6 = atan2(r1, r2), both components computed
            // directly (no difference of nearly equal numbers near the singularity).
            let (q5, q6, s6, c6) = if snapped {
                let q5 = singular_q5(self.phi5, cw);
                // At the wrist singularity joint 6 is the seed on every branch.
                let (s6, c6) = q6_seed.sin_cos();
                (q5, wrap(q6_seed), s6, c6)
            } else {
                let r1 = -s1 * ra5.x + c1 * ra5.y;
                let r2 = -s1 * ra65.x + c1 * ra65.y;
                let n = hyp(r1, r2);
                (
                    wrap(self.phi5 + atan2(sd, cw)),
                    atan2(r1, r2),
                    r1 / n,
                    r2 / n,
                )
            };
            // Ry(θ234)·a5 = M·Rot(a6,−q6)·a5 = Rz(−q1)·(c6·R a5 − s6·R (a6×a5)), in xz.
            let m = ra5 * c6 - ra65 * s6;
            let a5r = [c1 * m.x + s1 * m.y, m.z];
            let (ax, az) = (self.a5.x, self.a5.z);
            let th234 = atan2(az * a5r[0] - ax * a5r[1], ax * a5r[0] + az * a5r[1]);
            // The flip wrist: Ry(π)·Rot(a5, q5)·Ry(π)⁻¹ = Rot(a5, −q5) and a6 ∥ y at
            // φ5 = 0, so (θ234 + π, 2φ5 − q5, q6 + π) gives the same orientation: a5r
            // turns over, nothing else to compute.
            for (sgn, wrist) in [(1.0_f64, Wrist::NoFlip), (-1.0, Wrist::Flip)] {
                let (q5w, q6w, th) = if sgn > 0.0 {
                    (q5, q6, th234)
                } else {
                    (wrap(2.0 * self.phi5 - q5), wrap(q6 + PI), wrap(th234 + PI))
                };
                // W4 in the arm plane: Rz(−q1)W5 − e5·Ry(θ234)a5.
                let d = [
                    sh.xp - sgn * self.e5 * a5r[0] - self.arm.p2[0],
                    w.z - sgn * self.e5 * a5r[1] - self.arm.p2[1],
                ];
                // Near the wrist singularity (not on it) θ234 carries the orientation
                // band and joint 1's error over the wrist sine (together the wrist
                // band), and W4 that times e5: a wrist point that far beyond the
                // reach is taken as stretched (and polished).
                let slack = if snapped || tol.model.is_exact() {
                    tol.len
                } else {
                    tol.len + self.e5.abs() * tol.wrist / sd
                };
                let (elbows, n_el) = self.arm.elbow(d, slack, tol, &mut out);
                for el in &elbows[..n_el] {
                    let margin = sd.min(el.margin).min(sh.margin);
                    out.push(Branch {
                        joints: [
                            sh.q1,
                            wrap(self.s[0] * el.th2),
                            wrap(self.s[1] * el.th3),
                            wrap(self.s[2] * (th - el.th2 - el.th3)),
                            q5w,
                            q6w,
                        ],
                        configuration: Configuration {
                            shoulder: sh.shoulder(),
                            elbow: el.elbow(&sh),
                            wrist,
                        },
                        singular: near_singular || snapped,
                        polish: margin < POLISH_NEAR && !(snapped || sh.snapped),
                        provisional: el.beyond,
                    });
                }
            }
        }
        out
    }

    fn joint_limits(&self) -> &[Option<JointLimits>; 6] {
        &self.limits
    }

    fn unreachable(&self) -> Unreachable {
        Unreachable::BeyondReach {
            wrist_point: "axis 4's wrist point",
            min_mm: self.arm.reach[0],
            max_mm: self.arm.reach[1],
            offset_mm: self.arm.b.abs(),
        }
    }

    fn model_error(&self) -> ModelError {
        self.tol.model
    }

    fn idealized_forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        self.forward(q)
    }
}

/// The UR-type geometry detected from a robot (mm), see [`UrSolver::parameters`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UrParameters {
    /// Lateral offset of axis 5 from axis 1 (the D-H `d4` on a UR, mm).
    pub b: f64,
    /// Axis 2 → axis 3 at zero in the arm plane `(x, z)` (mm).
    pub upper_arm: [f64; 2],
    /// Axis 3 → axis 4 at zero in the arm plane `(x, z)` (mm).
    pub forearm: [f64; 2],
    /// Signed distance along axis 5 from where axis 4 meets it to where axis 6 does
    /// (the D-H `d5` up to sign, mm).
    pub e5: f64,
    /// Distance from that last point to the TCP (`d6` for the flange, mm).
    pub tcp_offset: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::closed_form::testing::assert_no_branch_missing;
    use crate::kinematics::{Catalog, DhConvention, DhRow, IkError, IkOptions, IkSolverKind};
    use crate::math::Transform;
    use std::f64::consts::FRAC_PI_2;

    /// Every catalog UR arm gets the UR solver with its D-H lengths as the detected
    /// parameters; the spherical-wrist arms keep OPW.
    #[test]
    fn catalog_arms_get_the_right_solver() {
        for arm in Catalog::ALL {
            let r = arm.robot();
            match arm.ur_dh() {
                Some([_, a2, a3, d4, d5, d6]) => {
                    assert_eq!(r.solver(), IkSolverKind::Ur, "{}", arm.name());
                    let p = r.ur_solver().unwrap().parameters();
                    assert!((p.b.abs() - d4).abs() < 1e-9, "{}: {p:?}", arm.name());
                    assert!((p.upper_arm[0].hypot(p.upper_arm[1]) - a2.abs()).abs() < 1e-9);
                    assert!((p.forearm[0].hypot(p.forearm[1]) - a3.abs()).abs() < 1e-9);
                    assert!((p.e5.abs() - d5).abs() < 1e-9);
                    assert!((p.tcp_offset - d6).abs() < 1e-9);
                }
                None => assert_eq!(r.solver_name(), "opw", "{}", arm.name()),
            }
        }
    }

    /// A UR5 whose wrist 2 twist is off by 0.1 rad (axes 5 and 6 no longer at a right
    /// angle) or whose forearm is lifted out of the arm plane's parallelism gets the
    /// numeric solver: detection does not misfire.
    #[test]
    fn near_ur_geometries_fall_back_to_numeric() {
        let [d1, a2, a3, d4, d5, d6] = Catalog::Ur5.ur_dh().unwrap();
        let rows = |alpha3: f64, alpha5: f64| {
            [
                DhRow::revolute(0.0, d1, 0.0, FRAC_PI_2),
                DhRow::revolute(0.0, 0.0, a2, 0.0),
                DhRow::revolute(0.0, 0.0, a3, alpha3),
                DhRow::revolute(0.0, d4, 0.0, FRAC_PI_2),
                DhRow::revolute(0.0, d5, 0.0, alpha5),
                DhRow::revolute(0.0, d6, 0.0, 0.0),
            ]
        };
        let build = |r: [DhRow; 6]| {
            Robot::from_dh("x", &r, DhConvention::Standard, Transform::IDENTITY).unwrap()
        };
        assert_eq!(build(rows(0.0, -FRAC_PI_2)).solver_name(), "ur");
        let twisted = build(rows(0.0, -FRAC_PI_2 + 0.1));
        assert_eq!(twisted.solver_name(), "numeric");
        assert_eq!(
            UrSolver::detect(&twisted).err(),
            Some(NotUr::Axes56NotMeeting)
        );
        let skew = build(rows(0.05, -FRAC_PI_2));
        assert_eq!(skew.solver_name(), "numeric");
        assert_eq!(
            UrSolver::detect(&skew).err(),
            Some(NotUr::Axes234NotParallel)
        );
    }

    /// A brute-force numeric search from many random starts finds no solution that the
    /// closed form misses (fewer than 8 branches where a shoulder/wrist choice puts W4
    /// out of reach, never none).
    #[test]
    fn no_branch_missing_against_brute_force() {
        assert_no_branch_missing(
            &Catalog::UR,
            78,
            80,
            |rng, _| (0..6).map(|_| rng.range(-PI, PI)).collect(),
            |r, target| r.ur_solver().unwrap().branches(target, 1e-9),
        );
    }

    /// Out of reach, inside the shoulder cylinder and non-finite targets are errors, not
    /// NaN joints.
    #[test]
    fn unreachable_targets_are_errors() {
        let r = Catalog::Ur5e.robot();
        let zero = [0.0; 6];
        let opts = IkOptions::default();
        let far = Transform::from_translation(crate::math::Vec3::new(3000.0, 0.0, 0.0));
        assert!(matches!(
            r.inverse(&far, &zero, &opts),
            Err(IkError::Unreachable(_))
        ));
        // The wrist point W5 on axis 1 (inside the cylinder of radius d4).
        let s = r.ur_solver().unwrap();
        let p = crate::math::Vec3::new(0.0, 0.0, 300.0) - s.w5_tcp;
        let inside = Transform::from_translation(p);
        assert!(matches!(
            r.inverse(&inside, &zero, &opts),
            Err(IkError::Unreachable(_))
        ));
        let nan = Transform::from_translation(crate::math::Vec3::new(f64::NAN, 0.0, 0.0));
        assert!(r.inverse(&nan, &zero, &opts).is_err());
    }
}
