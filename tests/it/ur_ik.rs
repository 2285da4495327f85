//! UR-type closed-form inverse kinematics (issue 25, part 1), checked against an
//! independent reference written here: the tree's forward kinematics (a walk over
//! the D-H or URDF links, no solver code) and a brute-force view of the solution set.
//! For every catalog Universal Robots arm: every branch reproduces the target to
//! 1e-9 mm and ~1e-12 rad, the generating configuration is among the branches, generic
//! targets have 8 distinct branches (modulo 2π) and the ±360° limits offer every
//! equivalent; targets at the wrist, shoulder and elbow singularities are solved
//! completely; a URDF in ROS `ur_description` form gives the same FK and the UR solver.

use crate::common::ur_urdf::{ur_description, ROUNDED_ROLL};
use fitup::kinematics::{parse_urdf, Catalog, ClosedFormIk, IkOptions, IkSolverKind, Robot};
use fitup::math::{Rng, Transform, Vec3};
use nalgebra::{Isometry3, UnitQuaternion};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::Path;

fn wrap(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

fn same_mod_2pi(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| wrap(x - y).abs() < tol)
}

/// Position error (mm) and orientation error (Frobenius norm of the rotation matrix
/// difference, ≈ √2 × the angle in rad, exact to rounding unlike an `acos`).
fn pose_error(a: &Transform, b: &Transform) -> (f64, f64) {
    let d = (a.translation() - b.translation()).norm();
    let ra = a.rotation().to_rotation_matrix().into_inner();
    let rb = b.rotation().to_rotation_matrix().into_inner();
    (d, (ra - rb).norm())
}

/// Distinct joint vectors modulo 2π.
fn distinct(sets: impl Iterator<Item = Vec<f64>>, tol: f64) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for q in sets {
        if !out.iter().any(|o| same_mod_2pi(o, &q, tol)) {
            out.push(q);
        }
    }
    out
}

/// Checks every branch of `target` (from `robot.inverse` with ±360° limits): FK
/// matches to `mm` and `rot`; returns the distinct solutions modulo 2π.
fn solve_checked(
    robot: &Robot,
    target: &Transform,
    reference: &[f64],
    mm: f64,
    rot: f64,
) -> Vec<Vec<f64>> {
    let sols = robot
        .inverse(target, reference, &IkOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e} for {reference:?}", robot.name()));
    for s in &sols {
        let got = robot.tcp_pose(&s.joints).unwrap();
        let (d, r) = pose_error(&got, target);
        assert!(
            d < mm && r < rot,
            "{}: {:?} misses the target by {d:e} mm, {r:e}",
            robot.name(),
            s.joints
        );
        assert!(robot.limit_violation(&s.joints).is_none());
    }
    distinct(sols.into_iter().map(|s| s.joints), 1e-9)
}

/// ≥ 1000 random joint vectors per UR model: every branch exact, the generating
/// configuration among them, 8 distinct branches, and with ±360° limits every
/// equivalent (2 per joint: 8 × 2⁶ = 512 solutions) offered.
#[test]
fn every_branch_exact_and_generating_configuration_found() {
    let mut rng = Rng::new(2025);
    for arm in Catalog::UR {
        let r = arm.robot();
        assert_eq!(r.solver(), IkSolverKind::Ur, "{}", arm.name());
        let s = r.ur_solver().unwrap();
        let mut eight = 0;
        for n in 0..1000 {
            let q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            let target = r.tcp_pose(&q).unwrap();
            let br = s.branches_seeded(target.isometry(), 1e-9, q[5]);
            let joints: Vec<Vec<f64>> = br.as_slice().iter().map(|b| b.joints.to_vec()).collect();
            for j in &joints {
                let (d, e) = pose_error(&r.tcp_pose(j).unwrap(), &target);
                assert!(
                    d < 1e-9 && e < 1e-11,
                    "{}: {j:?}: {d:e} mm {e:e}",
                    arm.name()
                );
            }
            // Near θ5 = 0 axes 2, 3, 4 and 6 are nearly parallel and the solution is
            // determined only to ~rounding / sin²θ5 (FK stays exact, checked above).
            let tol = 1e-7_f64.max(1e-15 / (q[4].sin() * q[4].sin()));
            assert!(
                joints.iter().any(|j| same_mod_2pi(j, &q, tol)),
                "{}: generating {q:?} missing from {joints:?}",
                arm.name()
            );
            let count = distinct(joints.into_iter(), 1e-6).len();
            assert_eq!(count, br.len(), "{}: duplicate branches", arm.name());
            // A UR has 8 branches unless a shoulder/wrist choice puts axis 4 out of the
            // arm's reach (then that choice's two elbow branches do not exist; the
            // brute-force unit test shows none is missed).
            assert!(
                count.is_multiple_of(2) && count >= 2,
                "{}: {count}",
                arm.name()
            );
            if count == 8 {
                eight += 1;
            }
            if n % 50 == 0 && count == 8 {
                // Through Robot::inverse: limits ±360° offer v and v ± 2π on every joint.
                let all = r.inverse(&target, &q, &IkOptions::default()).unwrap();
                assert_eq!(all.len(), 512, "{}", arm.name());
                assert!(same_mod_2pi(&all[0].joints, &q, 1e-7));
                assert!(all[0].distance < 1e-6, "nearest is the generating config");
                assert_eq!(solve_checked(&r, &target, &q, 1e-9, 1e-11).len(), 8);
            }
        }
        println!("{}: 8 branches on {eight}/1000 random targets", arm.name());
        assert!(
            eight > 500,
            "{}: only {eight}/1000 with 8 branches",
            arm.name()
        );
    }
}

/// θ5 = 0 (axis 6 parallel to axes 2-4): only θ234 ± θ6 is determined. Joint 6 keeps
/// the reference's value, so with the generating configuration as reference it comes
/// back exactly; with another reference joint 6 is that reference's and the pose is
/// still exact. Every arm branch is there (8).
#[test]
fn wrist_singularity_is_complete() {
    let mut rng = Rng::new(5);
    for arm in Catalog::UR {
        let r = arm.robot();
        for _ in 0..200 {
            let mut q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            q[4] = 0.0;
            let target = r.tcp_pose(&q).unwrap();
            let sols = solve_checked(&r, &target, &q, 1e-9, 1e-11);
            assert!(sols.len() >= 2, "{}: {q:?}", arm.name());
            assert!(
                sols.iter().any(|s| same_mod_2pi(s, &q, 1e-9)),
                "{}: {q:?} missing from {sols:?}",
                arm.name()
            );
            let all = r.inverse(&target, &q, &IkOptions::default()).unwrap();
            // The generating arm branches are at the singularity (others need not be).
            assert!(all.iter().any(|s| s.singular));
            // Another reference: joint 6 follows it (or it + π on the flip label).
            let mut other = q.clone();
            other[5] = rng.range(-PI, PI);
            // Known limit of the rule (see below): the other joint 6 can leave no
            // reachable branch at all; the pose is then reported, not solved.
            if r.inverse(&target, &other, &IkOptions::default()).is_err() {
                continue;
            }
            let sols = solve_checked(&r, &target, &other, 1e-9, 1e-11);
            assert!(sols.len() >= 2);
            for s in sols.iter().filter(|s| wrap(s[4]).abs() < 1e-12) {
                let d6 = wrap(s[5] - other[5]).abs();
                assert!(d6 < 1e-12 || (d6 - PI).abs() < 1e-12, "{s:?}");
            }
            // The generating arm branch is there up to the free joint: same q1, q5 and
            // θ2 + θ3 + θ4 ± θ6 (axes 2-4 and 6 parallel).
            // Known limit of the rule: another joint 6 moves axis 4 (θ234 changes), which
            // can put that arm branch out of reach; then only the other shoulder remains.
            let sum = |v: &[f64]| v[1] + v[2] + v[3];
            let singular_left = sols
                .iter()
                .any(|s| same_mod_2pi(&s[..1], &q[..1], 1e-9) && wrap(s[4]).abs() < 1e-12);
            assert!(
                !singular_left
                    || sols.iter().any(|s| {
                        same_mod_2pi(&s[..1], &q[..1], 1e-9)
                            && wrap(s[4] - q[4]).abs() < 1e-12
                            && (wrap(sum(s) + s[5] - sum(&q) - q[5]).abs() < 1e-9
                                || wrap(sum(s) - s[5] - sum(&q) + q[5]).abs() < 1e-9)
                    }),
                "{}: {q:?} reference {other:?}: {sols:?}",
                arm.name()
            );
        }
    }
}

/// θ3 = 0: upper arm and forearm in line (elbow fully stretched, the two elbow roots
/// coincide). Every solution exact and the generating one among them.
#[test]
fn stretched_elbow_is_complete() {
    let mut rng = Rng::new(6);
    for arm in Catalog::UR {
        let r = arm.robot();
        for _ in 0..200 {
            let mut q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            q[2] = 0.0;
            let target = r.tcp_pose(&q).unwrap();
            let sols = solve_checked(&r, &target, &q, 1e-9, 1e-11);
            assert!(
                !sols.is_empty(),
                "{}: {} solutions for {q:?}",
                arm.name(),
                sols.len()
            );
            // At a double root the joints carry √(rounding): ~1e-6 rad.
            assert!(
                sols.iter().any(|s| same_mod_2pi(s, &q, 1e-5)),
                "{}: {q:?} missing from {sols:?}",
                arm.name()
            );
        }
    }
}

/// The wrist point (axes 5 and 6 meeting, D-H frame 5's origin) exactly on the
/// cylinder of radius d4 about axis 1: the two shoulder roots coincide. Joint 2 is
/// found by bisection on the FK of the tree alone so that the wrist point has no
/// component along the arm plane's horizontal direction.
#[test]
fn shoulder_singularity_is_complete() {
    let mut rng = Rng::new(7);
    for arm in Catalog::UR {
        let r = arm.robot();
        let mut done = 0;
        while done < 50 {
            let mut q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            let xprime = |q: &[f64]| {
                let w5 = r.link_poses(q).unwrap()[5].translation();
                w5.x * q[0].cos() + w5.y * q[0].sin()
            };
            let grid: Vec<f64> = (0..=64).map(|i| -PI + TAU * i as f64 / 64.0).collect();
            let Some(k) = grid.windows(2).position(|w| {
                let (mut a, mut b) = (q.clone(), q.clone());
                a[1] = w[0];
                b[1] = w[1];
                xprime(&a).signum() != xprime(&b).signum()
            }) else {
                continue;
            };
            let (mut lo, mut hi) = (grid[k], grid[k + 1]);
            let mut t = q.clone();
            t[1] = lo;
            let f_lo = xprime(&t);
            for _ in 0..200 {
                t[1] = 0.5 * (lo + hi);
                if xprime(&t).signum() == f_lo.signum() {
                    lo = t[1];
                } else {
                    hi = t[1];
                }
            }
            q[1] = 0.5 * (lo + hi);
            assert!(xprime(&q).abs() < 1e-9);
            let target = r.tcp_pose(&q).unwrap();
            let sols = solve_checked(&r, &target, &q, 1e-9, 1e-11);
            assert!(!sols.is_empty(), "{}: {}", arm.name(), sols.len());
            // At a double root the joints carry √(rounding) (~1e-6 rad), more when the
            // wrist is also near θ5 = 0 or π; FK stays exact (checked above).
            assert!(
                sols.iter().any(|s| same_mod_2pi(s, &q, 1e-4)),
                "{}: {q:?} missing from {sols:?}",
                arm.name()
            );
            done += 1;
        }
    }
}

/// The catalog D-H arms against the URDF form of the same published numbers: FK of
/// both agree at 200 random joint vectors (tool0 is D-H frame 6, the URDF base is
/// turned by π about z), the URDF gets the UR solver and its IK round-trips.
#[test]
fn urdf_form_matches_catalog_and_selects_ur_solver() {
    let mut rng = Rng::new(8);
    let half_turn = Transform::from_parts(
        Vec3::zeros(),
        UnitQuaternion::from_axis_angle(&Vec3::z_axis(), PI),
    );
    for arm in Catalog::UR {
        let text = ur_description(
            arm.name(),
            arm.ur_dh().unwrap().map(|v| v / 1000.0),
            FRAC_PI_2,
        );
        let u = parse_urdf(Path::new("ur.urdf"), &text, None)
            .unwrap_or_else(|e| panic!("{}: {e}", arm.name()));
        let urdf = u.robot;
        assert_eq!(urdf.solver_name(), "ur", "{}", arm.name());
        assert_eq!(
            urdf.tree().links()[urdf.flange()].name.as_deref(),
            Some("tool0")
        );
        let dh = arm.robot().with_base(half_turn);
        for _ in 0..200 {
            let q: Vec<f64> = (0..6).map(|_| rng.range(-TAU, TAU)).collect();
            let (d, e) = pose_error(&urdf.tcp_pose(&q).unwrap(), &dh.tcp_pose(&q).unwrap());
            assert!(
                d < 1e-9 && e < 1e-12,
                "{}: {q:?}: {d:e} mm {e:e}",
                arm.name()
            );
        }
        for _ in 0..50 {
            let q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            let target = urdf.tcp_pose(&q).unwrap();
            let sols = solve_checked(&urdf, &target, &q, 1e-9, 1e-11);
            assert!(sols.len() >= 2);
            assert!(sols.iter().any(|s| same_mod_2pi(s, &q, 1e-7)));
        }
    }
    // Unused import guard for the isometry type in older toolchains.
    let _: Option<Isometry3<f64>> = None;
}

/// Detection from a URDF does not misfire: a spherical-wrist arm stays OPW, a 7-joint
/// arm is numeric.
#[test]
fn detection_from_urdf_does_not_misfire() {
    let opw = r#"<robot name="s"><link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/><link name="f"/><link name="g"/>
<joint name="1" type="revolute"><origin xyz="0 0 0.4"/><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
<joint name="2" type="revolute"><origin xyz="0.1 0 0"/><parent link="b"/><child link="c"/><axis xyz="0 1 0"/></joint>
<joint name="3" type="revolute"><origin xyz="0 0 0.5"/><parent link="c"/><child link="d"/><axis xyz="0 1 0"/></joint>
<joint name="4" type="revolute"><origin xyz="0 0 0.1"/><parent link="d"/><child link="e"/><axis xyz="1 0 0"/></joint>
<joint name="5" type="revolute"><origin xyz="0.5 0 0"/><parent link="e"/><child link="f"/><axis xyz="0 1 0"/></joint>
<joint name="6" type="revolute"><origin xyz="0.08 0 0"/><parent link="f"/><child link="g"/><axis xyz="1 0 0"/></joint>
</robot>"#;
    let r = parse_urdf(Path::new("s.urdf"), opw, None).unwrap().robot;
    assert_eq!(r.solver(), IkSolverKind::Opw);
    // The UR URDF with wrist 2 tilted by 0.05 rad about x: not UR any more.
    let text = ur_description(
        "bent",
        Catalog::Ur5e.ur_dh().unwrap().map(|v| v / 1000.0),
        FRAC_PI_2,
    )
    .replacen(
        r#"rpy="1.5707963267948966 0 0"/><parent link="wrist_1_link""#,
        r#"rpy="1.6207963267948966 0 0"/><parent link="wrist_1_link""#,
        1,
    );
    assert!(text.contains("1.6207963267948966"));
    let r = parse_urdf(Path::new("bent.urdf"), &text, None)
        .unwrap()
        .robot;
    assert_eq!(r.solver_name(), "numeric");
}

/// `Robot::inverse_each` (what the script and Python bindings call) and
/// `Robot::inverse_nearest` give `Robot::inverse`'s solutions to the bit: the same
/// joints in the same order, the nearest the first, the same errors; on every
/// catalog arm (limits with their ±360° variants) and on a UR URDF with rounded
/// angles (branches polished on the tree), at random, wrist-singular and
/// out-of-reach targets.
#[test]
fn inverse_each_and_nearest_are_inverse_to_the_bit() {
    let mut rng = Rng::new(38);
    let arm = Catalog::Ur5e;
    let text = ur_description(
        arm.name(),
        arm.ur_dh().unwrap().map(|v| v / 1000.0),
        ROUNDED_ROLL,
    );
    let rounded = parse_urdf(Path::new("ur.urdf"), &text, None).unwrap().robot;
    let every = IkOptions::every_branch();
    let bits =
        |rows: &[Vec<f64>]| -> Vec<u64> { rows.iter().flatten().map(|v| v.to_bits()).collect() };
    let mut solved = 0;
    for robot in Catalog::ALL.iter().map(|c| c.robot()).chain([rounded]) {
        assert!(robot.closed_form(), "{}", robot.name());
        for k in 0..40 {
            let mut q: Vec<f64> = (0..robot.dof()).map(|_| rng.range(-PI, PI)).collect();
            if k % 4 == 0 {
                q[4] = 0.0; // the wrist singularity
            }
            let target = if k == 39 {
                Transform::from_translation(Vec3::new(1e5, 0.0, 0.0))
            } else {
                robot.tcp_pose(&q).unwrap()
            };
            let reference: Vec<f64> = q.iter().map(|v| v + rng.range(-0.3, 0.3)).collect();
            let all = robot.inverse(&target, &reference, &every);
            let mut rows = Vec::new();
            let each = robot.inverse_each(&target, &reference, &every, |j| rows.push(j.to_vec()));
            let nearest = robot.inverse_nearest(&target, &reference, &every);
            match all {
                Ok(all) => {
                    assert_eq!(each, Ok(all.len()), "{}", robot.name());
                    let want: Vec<Vec<f64>> = all.iter().map(|s| s.joints.clone()).collect();
                    assert_eq!(bits(&rows), bits(&want), "{}: {q:?}", robot.name());
                    let n = nearest.unwrap();
                    assert_eq!(bits(std::slice::from_ref(&n.joints)), bits(&want[..1]));
                    assert_eq!(Some(&n), all.first());
                    solved += 1;
                }
                Err(e) => {
                    assert!(rows.is_empty());
                    assert_eq!(each, Err(e.clone()));
                    assert_eq!(nearest, Err(e));
                }
            }
        }
    }
    assert!(solved > 200, "{solved} targets solved");
}
