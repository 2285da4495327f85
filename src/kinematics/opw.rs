//! [`OpwSolver`]: closed-form inverse kinematics of 6R arms with an ortho-parallel base
//! and a spherical wrist, derived from the tree geometry (no per-robot code).
//!
//! # Derivation (product of exponentials)
//! At the zero configuration every joint `i` has an axis line (unit direction `aᵢ`,
//! point `pᵢ`) in the robot root frame. For any joint values the TCP pose is
//! `T(q) = E₁(q₁)·…·E₆(q₆)·T₀`, where `Eᵢ(θ)` is the rotation by `θ` about the
//! zero-configuration axis line `i` and `T₀` the TCP pose at zero. The arm qualifies
//! when `a₁ ⟂ a₂`, `a₂ ∥ a₃`, axes 4, 5, 6 meet in one point `W₀` (the wrist centre)
//! and `a₄ ⟂ a₅ ⟂ a₆`. Offsets of any sign, axis directions of either sign and any
//! zero position are covered because nothing else is assumed.
//!
//! A canonical frame C is put on axis 1: `z = a₁`, `y ⟂ z` along axis 2 and `x`
//! chosen so that the wrist centre at zero has `x ≥ 0`. In C, axes 2 and 3 are
//! parallel to `y` (signs `s₂, s₃ = ±1`) and cross the `xz` plane at `P₂`, `P₃`;
//! `W₀ = (·, b, ·)`.
//!
//! **Position.** The wrist joints do not move `W₀`, so
//! `W(q) = Rz(q₁)·[P₂ + R(s₂q₂)(u₂ + R(s₃q₃)u₃), b]` with the planar vectors
//! `u₂ = P₃ − P₂`, `u₃ = W₀ − P₃` (in `x,z`) and `R` the rotation about `y`.
//! The wrist centre of a target TCP pose `X` is `W = X·(T₀⁻¹W₀)`.
//! - Axis 1: the `y` component of `Rz(−q₁)W` must be `b`, so with `ρ² = Wx² + Wy²`
//!   the arm-plane abscissa is `x' = ±√(ρ² − b²)` (shoulder front/back) and
//!   `q₁ = atan2(Wy, Wx) − atan2(b, x')`. `ρ < |b|` is out of reach; `ρ = b = 0` is
//!   the shoulder singularity.
//! - Axis 3: with `d = (x', Wz) − P₂`,
//!   `|u₂ + R(θ)u₃|² = |u₂|² + |u₃|² + 2|u₂||u₃|cos(θ + γ) = |d|²`, `γ` the angle
//!   from `u₂` to `u₃`: `θ = ±acos(κ) − γ` (elbow), `q₃ = s₃θ`; `|κ| > 1` is out
//!   of reach.
//! - Axis 2: `q₂ = s₂(∠d − ∠(u₂ + R(θ)u₃))`.
//!
//! **Orientation.** `Rw = Ry(−θ₂₃)·Rz(−q₁)·R_X·R₀ᵀ = Rot(a₄,q₄)Rot(a₅,q₅)Rot(a₆,q₆)`.
//! With `t = Rw·a₆`, rotations about `a₄` keep `a₄·t`, and `Rot(a₅,q₅)a₆ =
//! cos q₅·a₆ + sin q₅·(a₅×a₆)`, so `A cos q₅ + B sin q₅ = a₄·t` with
//! `A = a₄·a₆`, `B = a₄·(a₅×a₆)`, `A² + B² = 1`: `q₅ = atan2(B, A) ± acos(a₄·t)`
//! (wrist flip). `q₄` turns `Rot(a₅,q₅)a₆` onto `t` about `a₄`, and `q₆` turns `a₅`
//! onto `Rot(a₅,−q₅)Rot(a₄,−q₄)Rw·a₅` about `a₆`. The flip root needs no more
//! trigonometry: `Rot(a₄,π)·Rot(a₆,π) = Rot(a₅, 2φ₅)` (`φ₅ = atan2(B, A)`) and
//! `Rot(a₄,π)` reverses `a₅`, so `(q₄+π, 2φ₅−q₅, q₆+π)` gives the same rotation.
//! When the two `q₅` roots coincide
//! (`sin(acos(a₄·t)) = 0`) axes 4 and 6 line up: the wrist singularity.

use super::closed_form::{
    canonical_frame, measure_model_error, singular_q5, zero_axis_lines, ArmPlane, ModelError,
    Tolerances, DISTANCE_TOL, PARALLEL_TOL, POLISH_NEAR,
};
use super::ur::snap_phi;
use super::{
    Branch, Branches, ClosedFormIk, Configuration, Elbow, JointKind, JointLimits, Robot, Shoulder,
    Unreachable, Wrist,
};
use crate::math::trig::{atan2, atan2_lanes, rot_vec, wrap};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Why a robot does not qualify for the closed-form solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum NotOpw {
    /// The chain does not have exactly six revolute joints.
    #[error("the chain does not have exactly six revolute joints")]
    NotSixRevolute,
    /// Axes 1 and 2 are not perpendicular.
    #[error("axes 1 and 2 are not perpendicular")]
    Axes12NotPerpendicular,
    /// Axes 2 and 3 are not parallel.
    #[error("axes 2 and 3 are not parallel")]
    Axes23NotParallel,
    /// Axes 4, 5 and 6 do not meet in one point (no spherical wrist).
    #[error("axes 4, 5 and 6 do not meet in one point (no spherical wrist)")]
    WristNotSpherical,
    /// Axis 5 is not perpendicular to axes 4 and 6.
    #[error("axis 5 is not perpendicular to axes 4 and 6")]
    WristNotOrthogonal,
    /// Axis 3 or the wrist centre lies on the previous axis (zero link length).
    #[error("zero upper-arm or forearm length")]
    Degenerate,
}

/// Closed-form solver for one robot (tool included), with every parameter
/// precomputed from the tree geometry at the zero configuration. Works in the robot's
/// root frame (the [`Robot`] applies its base pose).
#[derive(Debug, Clone, PartialEq)]
pub struct OpwSolver {
    /// Root frame ← canonical frame C.
    root_from_c: Isometry3<f64>,
    /// C ← root frame.
    c_from_root: Isometry3<f64>,
    /// Axes 2, 3 and the wrist centre in the arm plane.
    arm: ArmPlane,
    s2: f64,
    s3: f64,
    /// Wrist axes at zero in C.
    a4: Vector3<f64>,
    a5: Vector3<f64>,
    a6: Vector3<f64>,
    /// a5 × a6.
    a5x6: Vector3<f64>,
    /// φ5 = atan2(a4·(a5×a6), a4·a6), its sine and cosine.
    phi5: f64,
    s_phi5: f64,
    c_phi5: f64,
    /// Wrist centre in the TCP frame.
    w_tcp: Vector3<f64>,
    /// R0ᵀ·a6 and R0ᵀ·a5 (R0: TCP rotation at zero in C), and R0 as a quaternion.
    r0t_a6: Vector3<f64>,
    r0t_a5: Vector3<f64>,
    q0: Quaternion<f64>,
    tol: Tolerances,
    limits: [Option<JointLimits>; 6],
}

impl OpwSolver {
    /// Derives the solver from a robot's geometry at the zero configuration, or says
    /// why the robot does not qualify.
    pub fn detect(robot: &Robot) -> Result<Self, NotOpw> {
        if robot.dof() != 6
            || robot
                .joint_kinds()
                .iter()
                .any(|k| *k != JointKind::Revolute)
        {
            return Err(NotOpw::NotSixRevolute);
        }
        let (axes, tcp0) = zero_axis_lines(robot).ok_or(NotOpw::NotSixRevolute)?;
        let (a1, p1) = axes[0];
        let (a2, p2) = axes[1];
        let (a3, p3) = axes[2];
        let (a4, p4) = axes[3];
        let (a5, p5) = axes[4];
        let (a6, p6) = axes[5];
        if a1.dot(&a2).abs() > PARALLEL_TOL {
            return Err(NotOpw::Axes12NotPerpendicular);
        }
        if a2.cross(&a3).norm() > PARALLEL_TOL {
            return Err(NotOpw::Axes23NotParallel);
        }
        // Wrist centre: closest points of lines 4 and 5, then line 6 through it.
        let cb = a4.dot(&a5);
        let denom = 1.0 - cb * cb;
        if denom < 1e-12 {
            return Err(NotOpw::WristNotSpherical);
        }
        let w = p4 - p5;
        let (d, e) = (a4.dot(&w), a5.dot(&w));
        let s = (cb * e - d) / denom;
        let t = (e - cb * d) / denom;
        let c4 = p4 + a4 * s;
        let c5 = p5 + a5 * t;
        if (c4 - c5).norm() > DISTANCE_TOL {
            return Err(NotOpw::WristNotSpherical);
        }
        let w0 = Point3::from((c4.coords + c5.coords) * 0.5);
        if (w0 - p6).cross(&a6).norm() > DISTANCE_TOL {
            return Err(NotOpw::WristNotSpherical);
        }
        if a4.dot(&a5).abs() > PARALLEL_TOL || a5.dot(&a6).abs() > PARALLEL_TOL {
            return Err(NotOpw::WristNotOrthogonal);
        }
        // Canonical frame C on axis 1.
        let root_from_c = canonical_frame(a1, p1, a2, w0, p3);
        let c_from_root = root_from_c.inverse();
        let ey = root_from_c.rotation * Vector3::y();
        let inc = |p: &Point3<f64>| c_from_root * p;
        let arm = ArmPlane::new(inc(&p2), inc(&p3), inc(&w0)).ok_or(NotOpw::Degenerate)?;
        // The idealized wrist: a5 ⟂ a4, a6 ⟂ a5.
        let to_c = |v: &Vector3<f64>| c_from_root.rotation * v;
        let a4c = to_c(&a4);
        let a5c = to_c(&a5);
        let a5c = (a5c - a4c * a4c.dot(&a5c)).normalize();
        let a6c = to_c(&a6);
        let a6c = (a6c - a5c * a5c.dot(&a6c)).normalize();
        let limits_v = robot.joint_limits();
        let mut limits = [None; 6];
        limits.copy_from_slice(&limits_v[..6]);
        let tcp0_c = c_from_root * tcp0;
        let phi5 = snap_phi(a4c.dot(&a5c.cross(&a6c)).atan2(a4c.dot(&a6c)));
        let mut solver = Self {
            root_from_c,
            c_from_root,
            s2: ey.dot(&a2).signum(),
            s3: ey.dot(&a3).signum(),
            a5x6: a5c.cross(&a6c),
            phi5,
            s_phi5: phi5.sin(),
            c_phi5: phi5.cos(),
            a4: a4c,
            a5: a5c,
            a6: a6c,
            w_tcp: (tcp0.inverse() * w0).coords,
            r0t_a6: tcp0_c.rotation.inverse() * a6c,
            r0t_a5: tcp0_c.rotation.inverse() * a5c,
            q0: *tcp0_c.rotation.quaternion(),
            tol: Tolerances::new(&arm, ModelError::default(), 0.0),
            arm,
            limits,
        };
        let model = measure_model_error(robot, |q| solver.forward(q));
        solver.tol = Tolerances::new(&solver.arm, model, 0.0);
        Ok(solver)
    }

    /// TCP pose in the root frame for joint values `q` (rad), in closed form.
    pub fn forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        let th = self.s3 * q[2];
        let th2 = self.s2 * q[1];
        let [x, z] = self.arm.wrist(th2, th);
        // Half angles build the rotation as a quaternion product (cheaper than matrices).
        let (sh1, ch1) = (0.5 * q[0]).sin_cos();
        let (s1, c1) = (2.0 * sh1 * ch1, ch1 * ch1 - sh1 * sh1);
        let w = Vector3::new(c1 * x - s1 * self.arm.b, s1 * x + c1 * self.arm.b, z);
        let (sh23, ch23) = (0.5 * (th + th2)).sin_cos();
        let quat = |axis: &Vector3<f64>, angle: f64| {
            let (s, c) = (0.5 * angle).sin_cos();
            Quaternion::new(c, axis.x * s, axis.y * s, axis.z * s)
        };
        let r = Quaternion::new(ch1, 0.0, 0.0, sh1)
            * Quaternion::new(ch23, 0.0, sh23, 0.0)
            * quat(&self.a4, q[3])
            * quat(&self.a5, q[4])
            * quat(&self.a6, q[5])
            * self.q0;
        let r = UnitQuaternion::new_unchecked(r);
        let p = w - r * self.w_tcp;
        self.root_from_c * Isometry3::from_parts(Translation3::from(p), r)
    }

    /// Lateral offset `b` of the wrist centre from axis 1 (mm), upper-arm and
    /// forearm vectors in the arm plane `(x, z)` (mm), and the signs of axes 2, 3
    /// relative to the canonical `y`: the detected ortho-parallel parameters.
    pub fn parameters(&self) -> ([f64; 2], [f64; 2], [f64; 2], f64, [f64; 2]) {
        let a = &self.arm;
        (a.p2, a.u2, a.u3, a.b, [self.s2, self.s3])
    }
}

impl ClosedFormIk for OpwSolver {
    const SEED_JOINT: usize = 3;

    /// Every principal branch reaching `target` (root frame, mm); joint values in
    /// (−π, π], no limits applied.
    ///
    /// **Wrist singularity** (axes 4 and 6 aligned, `sin ∠(a₄, t) < 1e-10`): every arm
    /// branch still comes back with both wrist labels and `singular` set; joint 5 is
    /// exactly φ₅ (0 for the usual wrist; φ₅ + π when the axes are opposed) and only
    /// `q4 + q6` (`q4 − q6` when opposed) is determined. Rule: joint 4 keeps `q4_seed`
    /// (the current joint 4 value, wrapped) on the no-flip branch and `q4_seed + π` on
    /// the flip branch; joint 6 takes the rest. Near the singularity (sine below
    /// `singularity_threshold`) branches are solved normally and flagged `singular`.
    /// The shoulder singularity (wrist centre on axis 1) and the wrist centre on axis 2
    /// leave joint 1 or 2 undetermined: those branches are dropped and
    /// [`Branches::singular`] set.
    fn branches_seeded(
        &self,
        target: &Isometry3<f64>,
        singularity_threshold: f64,
        q4_seed: f64,
    ) -> Branches {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (just detected).
            return unsafe { self.solve_avx2(target, singularity_threshold, q4_seed) };
        }
        self.solve(target, singularity_threshold, q4_seed)
    }

    fn joint_limits(&self) -> &[Option<JointLimits>; 6] {
        &self.limits
    }

    fn unreachable(&self) -> Unreachable {
        Unreachable::BeyondReach {
            wrist_point: "the wrist centre",
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

impl OpwSolver {
    /// [`Self::solve`] compiled for AVX2 (three-operand VEX instructions: the same
    /// operations in the same order, so the same bits; issue 38).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn solve_avx2(
        &self,
        target: &Isometry3<f64>,
        singularity_threshold: f64,
        q4_seed: f64,
    ) -> Branches {
        self.solve(target, singularity_threshold, q4_seed)
    }

    /// [`ClosedFormIk::branches_seeded`].
    // Lanes indexed in step across several arrays.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn solve(&self, target: &Isometry3<f64>, singularity_threshold: f64, q4_seed: f64) -> Branches {
        let mut out = Branches::new();
        let x = self.c_from_root * target;
        let rx = x.rotation.to_rotation_matrix();
        let rx = rx.matrix();
        let w = rx * self.w_tcp + x.translation.vector;
        if !(w.iter().all(|v| v.is_finite()) && rx.iter().all(|v| v.is_finite())) {
            // A non-finite target has no solution (and must not yield NaN joints).
            out.out_of_reach = true;
            return out;
        }
        // Only Rw·a6 and Rw·a5 are needed: R_E·a = R_X·(R0ᵀ·a), the bracket precomputed.
        let re_a6 = rx * self.r0t_a6;
        let re_a5 = rx * self.r0t_a5;
        let tol = &self.tol;
        // The arm branches first (up to four), then their wrists side by side: the
        // same operations lane by lane, straight-line code the compiler runs in
        // vector registers (issue 38).
        let mut arm = [ArmBranch::default(); 4];
        let (mut t, mut r5) = ([[0.0; 4]; 3], [[0.0; 4]; 3]);
        let mut n = 0;
        let (shoulders, n_sh) = self.arm.shoulder(&w, tol, singularity_threshold, &mut out);
        for sh in &shoulders[..n_sh] {
            let (s1, c1) = (sh.s1, sh.c1);
            let d = [sh.xp - self.arm.p2[0], w.z - self.arm.p2[1]];
            // Rz(−q1)·R_E·a6 and ·a5.
            let rz =
                |v: &Vector3<f64>| Vector3::new(c1 * v.x + s1 * v.y, -s1 * v.x + c1 * v.y, v.z);
            let (r1_a6, r1_a5) = (rz(&re_a6), rz(&re_a5));
            let (elbows, n_el) = self.arm.elbow(d, tol.len, tol, &mut out);
            for el in &elbows[..n_el] {
                let (s23, c23) = (el.s23, el.c23);
                // Ry(−θ23)·….
                let ry = |v: &Vector3<f64>| {
                    Vector3::new(c23 * v.x - s23 * v.z, v.y, s23 * v.x + c23 * v.z)
                };
                let (tv, rv) = (ry(&r1_a6), ry(&r1_a5));
                for k in 0..3 {
                    t[k][n] = tv[k];
                    r5[k][n] = rv[k];
                }
                arm[n] = ArmBranch {
                    q: [sh.q1, wrap(self.s2 * el.th2), wrap(self.s3 * el.th3)],
                    shoulder: sh.shoulder(),
                    elbow: el.elbow(sh),
                    margin: el.margin.min(sh.margin),
                    snapped: sh.snapped || el.snapped,
                };
                n += 1;
            }
        }
        if n == 0 {
            return out;
        }
        // Unused lanes repeat the first (finite, so no lane takes the slow path).
        for k in 0..3 {
            for i in n..4 {
                t[k][i] = t[k][0];
                r5[k][i] = r5[k][0];
            }
        }
        let wr = self.wrist_lanes(&t, &r5);
        for (i, a) in arm.iter().enumerate().take(n) {
            let [q1, q2, q3] = a.q;
            let (sd, cw) = (wr.sd[i], wr.cw[i]);
            let near_singular = sd < singularity_threshold;
            let snapped = sd < tol.wrist;
            if near_singular || snapped {
                out.singular = true;
            }
            let configuration = |wrist| Configuration {
                shoulder: a.shoulder,
                elbow: a.elbow,
                wrist,
            };
            if snapped {
                // Axes 4 and 6 aligned (cw > 0) or opposed: q5 is exactly φ5 or
                // φ5 + π and only q4 + q6 (or q4 − q6) is determined; it equals ψ,
                // the angle about a4 from a5 to Rw·a5. Rule: q4 keeps the seed,
                // q6 takes the rest; the flip branch is q4 + π.
                let rw_a5 = Vector3::new(r5[0][i], r5[1][i], r5[2][i]);
                let psi = atan2(self.a4.dot(&self.a5.cross(&rw_a5)), self.a5.dot(&rw_a5));
                let q5 = singular_q5(self.phi5, cw);
                let sgn = if cw > 0.0 { 1.0 } else { -1.0 };
                for (k, wrist) in [(0.0, Wrist::NoFlip), (PI, Wrist::Flip)] {
                    let q4 = wrap(q4_seed + k);
                    out.push(Branch {
                        joints: [q1, q2, q3, q4, q5, wrap(sgn * (psi - q4))],
                        configuration: configuration(wrist),
                        singular: true,
                        polish: false,
                        provisional: false,
                    });
                }
                continue;
            }
            let polish = sd.min(a.margin) < POLISH_NEAR && !a.snapped;
            let (delta, q4, q6) = (wr.delta[i], wr.q4[i], wr.q6[i]);
            // No-flip root q5 = φ5 + δ.
            out.push(Branch {
                joints: [q1, q2, q3, q4, wrap(self.phi5 + delta), q6],
                configuration: configuration(Wrist::NoFlip),
                singular: near_singular,
                polish,
                provisional: false,
            });
            // The flip root follows without trigonometry: since a5 ⟂ a4 and
            // Rot(a4,π)·Rot(a6,π) = Rot(a5, 2φ5),
            // Rot(a4,q4+π)·Rot(a5,2φ5−q5)·Rot(a6,q6+π) = Rot(a4,q4)·Rot(a5,q5)·Rot(a6,q6).
            out.push(Branch {
                joints: [
                    q1,
                    q2,
                    q3,
                    wrap(q4 + PI),
                    wrap(self.phi5 - delta),
                    wrap(q6 + PI),
                ],
                configuration: configuration(Wrist::Flip),
                singular: near_singular,
                polish,
                provisional: false,
            });
        }
        out
    }

    /// The regular wrist of four arm branches at once, from `t = Rw·a6` and
    /// `Rw·a5` (components by lane): the sine and cosine of δ = ∠(a4, t), δ, and
    /// joints 4 and 6 of the no-flip root. Per lane the operations of the vector
    /// forms in their order (the same bits; a lane at the singularity carries
    /// meaningless values, not used).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn wrist_lanes(&self, t: &[[f64; 4]; 3], r5: &[[f64; 4]; 3]) -> WristLanes {
        let [a4x, a4y, a4z] = [self.a4.x, self.a4.y, self.a4.z];
        let [a5x, a5y, a5z] = [self.a5.x, self.a5.y, self.a5.z];
        let [a6x, a6y, a6z] = [self.a6.x, self.a6.y, self.a6.z];
        let [bx, by, bz] = [self.a5x6.x, self.a5x6.y, self.a5x6.z];
        let (sp, cp) = (self.s_phi5, self.c_phi5);
        let mut o = WristLanes::default();
        let (mut y4, mut x4, mut y6, mut x6) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
        for i in 0..4 {
            let (tx, ty, tz) = (t[0][i], t[1][i], t[2][i]);
            // δ = ∠(a4, t) from its sine and cosine: acos(a4·t) loses half the
            // digits near the singularity (δ = 1e-7 would come back ±1e-9 off).
            let cw = a4x * tx + a4y * ty + a4z * tz;
            let (cx, cy, cz) = (
                a4y * tz - a4z * ty,
                a4z * tx - a4x * tz,
                a4x * ty - a4y * tx,
            );
            let sd = (cx * cx + cy * cy + cz * cz).sqrt();
            let (tpx, tpy, tpz) = (tx - a4x * cw, ty - a4y * cw, tz - a4z * cw);
            // No-flip root q5 = φ5 + δ.
            let s5 = sp * cw + cp * sd;
            let c5 = cp * cw - sp * sd;
            let (vx, vy, vz) = (a6x * c5 + bx * s5, a6y * c5 + by * s5, a6z * c5 + bz * s5);
            // q4 turns v5 onto t about a4.
            let dv = a4x * vx + a4y * vy + a4z * vz;
            let (px, py, pz) = (vx - a4x * dv, vy - a4y * dv, vz - a4z * dv);
            let crs4 = a4x * (py * tpz - pz * tpy)
                + a4y * (pz * tpx - px * tpz)
                + a4z * (px * tpy - py * tpx);
            let dot4 = px * tpx + py * tpy + pz * tpz;
            let n4 = (crs4 * crs4 + dot4 * dot4).sqrt();
            let (s4, c4) = (crs4 / n4, dot4 / n4);
            // q6 turns a5 onto Rot(a5,−q5)·Rot(a4,−q4)·Rw·a5 about a6.
            let m = rot_vec(
                [a5x, a5y, a5z],
                -s5,
                c5,
                rot_vec([a4x, a4y, a4z], -s4, c4, [r5[0][i], r5[1][i], r5[2][i]]),
            );
            let (ux, uy, uz) = (
                a5y * m[2] - a5z * m[1],
                a5z * m[0] - a5x * m[2],
                a5x * m[1] - a5y * m[0],
            );
            o.cw[i] = cw;
            o.sd[i] = sd;
            y4[i] = crs4;
            x4[i] = dot4;
            y6[i] = a6x * ux + a6y * uy + a6z * uz;
            x6[i] = a5x * m[0] + a5y * m[1] + a5z * m[2];
        }
        o.delta = atan2_lanes(&o.sd, &o.cw);
        o.q4 = atan2_lanes(&y4, &x4);
        o.q6 = atan2_lanes(&y6, &x6);
        o
    }
}

/// One arm branch of [`OpwSolver::solve`]: joints 1–3, its labels, the nearness of
/// its shoulder and elbow singularities and whether either was snapped.
#[derive(Clone, Copy)]
struct ArmBranch {
    q: [f64; 3],
    shoulder: Shoulder,
    elbow: Elbow,
    margin: f64,
    snapped: bool,
}

impl Default for ArmBranch {
    fn default() -> Self {
        Self {
            q: [0.0; 3],
            shoulder: Shoulder::Front,
            elbow: Elbow::Up,
            margin: 0.0,
            snapped: false,
        }
    }
}

/// The wrists of [`OpwSolver::wrist_lanes`], by lane.
#[derive(Default)]
struct WristLanes {
    cw: [f64; 4],
    sd: [f64; 4],
    delta: [f64; 4],
    q4: [f64; 4],
    q6: [f64; 4],
}

#[cfg(test)]
mod tests;
