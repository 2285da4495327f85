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
    ang, rot2, rot_vec, wrap, zero_axis_lines, DISTANCE_TOL, PARALLEL_TOL, WRIST_SNAP,
};
use super::{
    Branch, Branches, ClosedFormIk, Configuration, Elbow, JointLimits, Robot, Shoulder,
    Unreachable, Wrist,
};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
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
/// from the tree geometry at the zero configuration. Works in the robot's root frame
/// (the [`Robot`] applies its base pose). Lengths in mm, angles in radians.
#[derive(Debug, Clone, PartialEq)]
pub struct UrSolver {
    /// C ← root frame.
    c_from_root: Isometry3<f64>,
    /// Axis 2 in the arm plane (x, z), mm.
    p2: [f64; 2],
    /// Upper arm (axis 2 → axis 3) and forearm (axis 3 → W₄) at zero, (x, z), mm.
    u2: [f64; 2],
    u3: [f64; 2],
    /// Lateral offset of axis 5 along y (mm).
    b: f64,
    /// |u2|² + |u3|², 2|u2||u3|, angle from u2 to u3 and its sine and cosine.
    len_sq: f64,
    len_prod2: f64,
    gamma: f64,
    sg: f64,
    cg: f64,
    /// Reach limits of W₄ from axis 2 (mm).
    reach: [f64; 2],
    /// Signs of axes 2, 3, 4 relative to C's y.
    s: [f64; 3],
    /// Axes 5 and 6 at zero in C.
    a5: Vector3<f64>,
    a6: Vector3<f64>,
    /// Signed distance W₄ → W₅ along a₅ (mm).
    e5: f64,
    /// φ₅ = atan2(y·(a₅×a₆), y·a₆), its sine and cosine.
    phi5: f64,
    s_phi5: f64,
    c_phi5: f64,
    /// W₅ in the TCP frame (mm).
    w5_tcp: Vector3<f64>,
    /// R₀ᵀ (R₀: TCP rotation at zero in C).
    r0t: Matrix3<f64>,
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
        let ez = a1;
        let mut ex = a2.cross(&ez).normalize();
        let side = (w5 - p1).dot(&ex);
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
        let root_from_c = Isometry3::from_parts(
            Translation3::from(p1.coords),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rc)),
        );
        let c_from_root = root_from_c.inverse();
        let (q2, q3, q4) = (c_from_root * p2, c_from_root * p3, c_from_root * w4);
        let u2 = [q3.x - q2.x, q3.z - q2.z];
        let u3 = [q4.x - q3.x, q4.z - q3.z];
        let (l2, l3) = (u2[0].hypot(u2[1]), u3[0].hypot(u3[1]));
        if l2 < DISTANCE_TOL || l3 < DISTANCE_TOL {
            return Err(NotUr::Degenerate);
        }
        let a5c = c_from_root.rotation * a5;
        let a6c = c_from_root.rotation * a6;
        let phi5 = a5c.cross(&a6c).y.atan2(a6c.y);
        // Axes built by rotations carry rounding: the UR wrist has φ5 = 0 (or π)
        // exactly, so that singular targets give joint 5 exactly that value.
        let phi5 = if phi5.abs() < 1e-12 {
            0.0
        } else if (phi5.abs() - PI).abs() < 1e-12 {
            PI
        } else {
            phi5
        };
        let gamma = ang(u3) - ang(u2);
        let tcp0_c = c_from_root * tcp0;
        let mut limits = [None; 6];
        limits.copy_from_slice(&robot.joint_limits()[..6]);
        Ok(Self {
            c_from_root,
            p2: [q2.x, q2.z],
            u2,
            u3,
            b: q4.y,
            len_sq: l2 * l2 + l3 * l3,
            len_prod2: 2.0 * l2 * l3,
            gamma,
            sg: gamma.sin(),
            cg: gamma.cos(),
            reach: [(l2 - l3).abs(), l2 + l3],
            s: [
                ey.dot(&a2).signum(),
                ey.dot(&a3).signum(),
                ey.dot(&a4).signum(),
            ],
            a5: a5c,
            a6: a6c,
            e5: (w5 - w4).dot(&a5),
            phi5,
            s_phi5: phi5.sin(),
            c_phi5: phi5.cos(),
            w5_tcp: (tcp0.inverse() * w5).coords,
            r0t: tcp0_c
                .rotation
                .to_rotation_matrix()
                .into_inner()
                .transpose(),
            limits,
        })
    }

    /// The detected parameters: lateral offset `b` of axis 5 from axis 1 (mm), the
    /// upper-arm and forearm vectors in the arm plane `(x, z)` (mm), the signed
    /// distance `e5` between the wrist points on axis 5 (mm) and the distance from
    /// `W₅` to the TCP (mm).
    pub fn parameters(&self) -> UrParameters {
        UrParameters {
            b: self.b,
            upper_arm: self.u2,
            forearm: self.u3,
            e5: self.e5,
            tcp_offset: self.w5_tcp.norm(),
        }
    }
}

impl ClosedFormIk for UrSolver {
    const SEED_JOINT: usize = 5;

    /// Every principal branch (up to 8: shoulder × wrist × elbow) reaching `target`
    /// (root frame, mm); joint values in (−π, π], no limits applied.
    ///
    /// **Wrist singularity** (axis 6 parallel to axes 2–4, `sin δ < 1e-10`): every arm
    /// branch still comes back with both wrist labels and `singular` set; joint 5 is
    /// exactly φ₅ (0 on a UR; φ₅ + π when the axes are opposed) and only
    /// `θ₂₃₄ ± q₆` is determined. Rule: joint 6 keeps `q6_seed` (wrapped) on the no-flip
    /// branch and `q6_seed + π` on the flip branch; joints 2–4 take the rest. Near the
    /// singularity (sine below `singularity_threshold`) branches are solved normally
    /// and flagged. **Shoulder singularity** (`ρ = |b|`) and **stretched or folded
    /// elbow** (`|κ| = 1`): the two roots coincide and come back once. With no lateral
    /// offset and `W₅` on axis 1, or `W₄` on axis 2, joint 1 or 2 is undetermined:
    /// those branches are dropped and [`Branches::singular`] set.
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
        // R_X·R₀ᵀ = Rz(q1)·Ry(θ234)·Rot(a5,q5)·Rot(a6,q6).
        let rt = rx * self.r0t;
        let t6 = rt * self.a6;
        let rho_sq = w.x * w.x + w.y * w.y;
        let disc = rho_sq - self.b * self.b;
        let scale = 1.0 + self.reach[1] + self.e5.abs();
        if disc < -1e-12 * scale * scale {
            out.out_of_reach = true;
            return out;
        }
        if rho_sq.sqrt() < singularity_threshold * scale && self.b.abs() < DISTANCE_TOL {
            out.singular = true;
            return out;
        }
        let root = disc.max(0.0).sqrt();
        let y = Vector3::y();
        for sh in [1.0_f64, -1.0] {
            if sh < 0.0 && root < 1e-12 * scale {
                // Shoulder singularity: both roots coincide.
                break;
            }
            let xp = sh * root;
            let (s1, c1) = (
                (xp * w.y - self.b * w.x) / rho_sq,
                (xp * w.x + self.b * w.y) / rho_sq,
            );
            let q1 = s1.atan2(c1);
            let rz_inv =
                |v: &Vector3<f64>| Vector3::new(c1 * v.x + s1 * v.y, -s1 * v.x + c1 * v.y, v.z);
            let t = rz_inv(&t6);
            // δ = ∠(y, t) from its sine and cosine (acos loses digits near 0).
            let (cw, sd) = (t.y, t.x.hypot(t.z));
            // Mᵀy = (R_X R₀ᵀ)ᵀ·Rz(q1)·y.
            let u = rt.tr_mul(&Vector3::new(-s1, c1, 0.0));
            let near_singular = sd < singularity_threshold;
            if near_singular {
                out.singular = true;
            }
            // (q5, q6, label) for the two wrist roots.
            let mut wrists = [(0.0, 0.0, Wrist::NoFlip); 2];
            if sd < WRIST_SNAP {
                let q5 = if cw > 0.0 {
                    self.phi5
                } else {
                    wrap(self.phi5 + PI)
                };
                wrists[0] = (q5, wrap(q6_seed), Wrist::NoFlip);
                wrists[1] = (q5, wrap(q6_seed + PI), Wrist::Flip);
            } else {
                let delta = sd.atan2(cw);
                for (k, (sgn, label)) in [(1.0, Wrist::NoFlip), (-1.0, Wrist::Flip)]
                    .into_iter()
                    .enumerate()
                {
                    let (sdl, cdl) = (sgn * sd, cw);
                    let s5 = self.s_phi5 * cdl + self.c_phi5 * sdl;
                    let c5 = self.c_phi5 * cdl - self.s_phi5 * sdl;
                    let v = rot_vec(&self.a5, -s5, c5, &y);
                    let a6u = self.a6.dot(&u);
                    let q6 = self
                        .a6
                        .dot(&u.cross(&v))
                        .atan2(u.dot(&v) - a6u * self.a6.dot(&v));
                    wrists[k] = (wrap(self.phi5 + sgn * delta), q6, label);
                }
            }
            let wrist_singular = sd < WRIST_SNAP || near_singular;
            for (q5, q6, wrist) in wrists {
                let (s5, c5) = q5.sin_cos();
                let (s6, c6) = q6.sin_cos();
                // θ234: angle about y of M·Rot(a6,−q6)·Rot(a5,−q5), read off its x column.
                let p = rot_vec(
                    &self.a6,
                    -s6,
                    c6,
                    &rot_vec(&self.a5, -s5, c5, &Vector3::x()),
                );
                let mp = rz_inv(&(rt * p));
                let n = mp.x.hypot(mp.z);
                let (s234, c234) = (-mp.z / n, mp.x / n);
                let th234 = s234.atan2(c234);
                // W4 in the arm plane: Rz(−q1)W5 − e5·Ry(θ234)a5.
                let a5r = [
                    c234 * self.a5.x + s234 * self.a5.z,
                    -s234 * self.a5.x + c234 * self.a5.z,
                ];
                let d = [
                    xp - self.e5 * a5r[0] - self.p2[0],
                    w.z - self.e5 * a5r[1] - self.p2[1],
                ];
                let kappa = (d[0] * d[0] + d[1] * d[1] - self.len_sq) / self.len_prod2;
                if kappa.abs() > 1.0 + 1e-12 {
                    out.out_of_reach = true;
                    continue;
                }
                let kappa = kappa.clamp(-1.0, 1.0);
                let acos_k = kappa.acos();
                let sk = (1.0 - kappa * kappa).sqrt();
                for el in [1.0_f64, -1.0] {
                    if el < 0.0 && sk < 1e-12 {
                        // Elbow stretched or folded: both roots coincide.
                        break;
                    }
                    let (sa, ca) = (el * sk, kappa);
                    let (st, ct) = (sa * self.cg - ca * self.sg, ca * self.cg + sa * self.sg);
                    let th3 = el * acos_k - self.gamma;
                    let f = rot2(self.u3, st, ct);
                    let v = [self.u2[0] + f[0], self.u2[1] + f[1]];
                    let crs = d[0] * v[1] - d[1] * v[0];
                    let dot = d[0] * v[0] + d[1] * v[1];
                    if crs.hypot(dot) < 1e-12 * scale * scale {
                        // W4 on axis 2: joint 2 undetermined.
                        out.singular = true;
                        continue;
                    }
                    let th2 = crs.atan2(dot);
                    let th4 = th234 - th2 - th3;
                    let elbow = if (el > 0.0) == (sh > 0.0) {
                        Elbow::Up
                    } else {
                        Elbow::Down
                    };
                    let shoulder = if sh > 0.0 {
                        Shoulder::Front
                    } else {
                        Shoulder::Back
                    };
                    out.push(Branch {
                        joints: [
                            q1,
                            wrap(self.s[0] * th2),
                            wrap(self.s[1] * th3),
                            wrap(self.s[2] * th4),
                            q5,
                            q6,
                        ],
                        configuration: Configuration {
                            shoulder,
                            elbow,
                            wrist,
                        },
                        singular: wrist_singular,
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
            min_mm: self.reach[0],
            max_mm: self.reach[1],
            offset_mm: self.b.abs(),
        }
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
