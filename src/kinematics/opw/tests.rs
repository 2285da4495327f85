use super::*;
use crate::kinematics::closed_form::testing::{assert_no_branch_missing, same_angles};
use crate::kinematics::{Catalog, IkError, IkOptions, Joint, KinematicTree, Link, OpwParameters};
use crate::math::{Rng, Transform, Vec3};

/// The parameters extracted from the MZ07 tree are table 2's: upper arm 330 mm,
/// forearm √(340² + 45²) mm, no lateral offset, axis 2 at 50 mm out and 340 mm up.
#[test]
fn mz07_parameters_are_extracted_from_the_tree() {
    let r = Catalog::NachiMz07.robot();
    let (p2, u2, u3, b, _) = r.analytic().unwrap().parameters();
    assert!(
        (p2[0] - 50.0).abs() < 1e-9 && (p2[1] - 340.0).abs() < 1e-9,
        "{p2:?}"
    );
    assert!((u2[0].hypot(u2[1]) - 330.0).abs() < 1e-9);
    assert!((u3[0].hypot(u3[1]) - 340f64.hypot(45.0)).abs() < 1e-9);
    assert!(b.abs() < 1e-9);
}

const OPW_ARMS: [Catalog; 5] = [
    Catalog::NachiMz07,
    Catalog::AbbIrb2400,
    Catalog::KukaKr6R700,
    Catalog::FanucLrMate200iD,
    Catalog::StaubliTx2_60L,
];

fn random_q(rng: &mut Rng, robot: &Robot) -> [f64; 6] {
    let mut q = [0.0; 6];
    for (v, l) in q.iter_mut().zip(robot.joint_limits()) {
        let l = l.unwrap_or(JointLimits::symmetric(PI));
        *v = rng.range(l.min.max(-PI), l.max.min(PI));
    }
    q
}

#[test]
fn every_catalog_arm_but_ur5_is_detected() {
    for arm in OPW_ARMS {
        let r = arm.robot();
        assert!(
            r.analytic().is_some(),
            "{}: {:?}",
            arm.name(),
            r.analytic_rejection()
        );
    }
    let ur5 = Catalog::Ur5.robot();
    assert_eq!(ur5.analytic_rejection(), Some(NotOpw::WristNotSpherical));
}

#[test]
fn closed_form_forward_matches_tree() {
    let mut rng = Rng::new(11);
    for arm in OPW_ARMS {
        let r = arm.robot();
        let s = r.analytic().unwrap();
        for _ in 0..200 {
            let q = random_q(&mut rng, &r);
            let a = Transform::from_isometry(s.forward(&q));
            let b = r.tcp_pose(&q).unwrap();
            assert!(a.approx_eq(&b, 1e-9, 1e-12), "{}", arm.name());
        }
    }
}

/// Every returned branch reproduces the pose, and the generating configuration is
/// among the branches, for thousands of seeded configurations per arm.
#[test]
fn round_trip_all_branches() {
    let mut rng = Rng::new(2024);
    for arm in OPW_ARMS {
        let r = arm.robot();
        let s = r.analytic().unwrap();
        let mut total = 0;
        for _ in 0..3000 {
            let q = random_q(&mut rng, &r);
            let target = r.tcp_pose(&q).unwrap();
            let br = s.branches(target.isometry(), 1e-9);
            assert!(!br.is_empty(), "{}: no branch for {q:?}", arm.name());
            for b in br.as_slice() {
                let got = r.tcp_pose(&b.joints).unwrap();
                let (ang, dist) = got.distance_to(&target);
                assert!(
                    dist < 1e-6 && ang < 1e-9,
                    "{} {q:?} -> {b:?}: {dist} mm {ang} rad",
                    arm.name()
                );
                total += 1;
            }
            assert!(
                br.as_slice()
                    .iter()
                    .any(|b| same_angles(&b.joints, &q, 1e-7)),
                "{}: original {q:?} missing from {:?}",
                arm.name(),
                br.as_slice()
            );
            // Branches are distinct.
            for (i, a) in br.as_slice().iter().enumerate() {
                for b in &br.as_slice()[i + 1..] {
                    assert!(!same_angles(&a.joints, &b.joints, 1e-9));
                    assert_ne!(a.configuration, b.configuration);
                }
            }
        }
        assert!(total >= 3000);
    }
}

/// A brute-force numeric search from many seeded starts finds no solution that the
/// closed form misses.
#[test]
fn no_branch_missing_against_brute_force() {
    assert_no_branch_missing(
        &OPW_ARMS,
        77,
        60,
        |rng, r| random_q(rng, r).to_vec(),
        |r, target| r.analytic().unwrap().branches(target, 1e-9),
    );
}

/// Joint 5 values at and around the wrist singularity (issue 11).
const NEAR_SINGULAR: [f64; 7] = [0.0, 1e-12, -1e-12, 1e-9, -1e-9, 1e-7, -1e-7];

/// Rodrigues rotation as the per-branch form had it.
fn rot_v(k: &Vector3<f64>, s: f64, c: f64, v: &Vector3<f64>) -> Vector3<f64> {
    v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c))
}

/// The solve as it was before the wrists ran side by side (issue 38): one arm
/// branch after the other, nalgebra vectors.
fn per_branch(
    s: &OpwSolver,
    target: &Isometry3<f64>,
    singularity_threshold: f64,
    q4_seed: f64,
) -> Branches {
    let mut out = Branches::new();
    let x = s.c_from_root * target;
    let rx = x.rotation.to_rotation_matrix();
    let rx = rx.matrix();
    let w = rx * s.w_tcp + x.translation.vector;
    if !(w.iter().all(|v| v.is_finite()) && rx.iter().all(|v| v.is_finite())) {
        // A non-finite target has no solution (and must not yield NaN joints).
        out.out_of_reach = true;
        return out;
    }
    // Only Rw·a6 and Rw·a5 are needed: R_E·a = R_X·(R0ᵀ·a), the bracket precomputed.
    let re_a6 = rx * s.r0t_a6;
    let re_a5 = rx * s.r0t_a5;
    let tol = &s.tol;
    let (shoulders, n_sh) = s.arm.shoulder(&w, tol, singularity_threshold, &mut out);
    for sh in &shoulders[..n_sh] {
        let (s1, c1, q1) = (sh.s1, sh.c1, sh.q1);
        let d = [sh.xp - s.arm.p2[0], w.z - s.arm.p2[1]];
        // Rz(−q1)·R_E·a6 and ·a5.
        let rz = |v: &Vector3<f64>| Vector3::new(c1 * v.x + s1 * v.y, -s1 * v.x + c1 * v.y, v.z);
        let (r1_a6, r1_a5) = (rz(&re_a6), rz(&re_a5));
        let shoulder = if sh.front {
            Shoulder::Front
        } else {
            Shoulder::Back
        };
        let (elbows, n_el) = s.arm.elbow(d, tol.len, tol, &mut out);
        for el in &elbows[..n_el] {
            let (s23, c23) = (el.s23, el.c23);
            // Ry(−θ23)·….
            let ry =
                |v: &Vector3<f64>| Vector3::new(c23 * v.x - s23 * v.z, v.y, s23 * v.x + c23 * v.z);
            let t = ry(&r1_a6);
            // δ = ∠(a4, t) from its sine and cosine: acos(a4·t) loses half the
            // digits near the singularity (δ = 1e-7 would come back ±1e-9 off).
            let cw = s.a4.dot(&t);
            let sd = s.a4.cross(&t).norm();
            let elbow = if el.first == sh.front {
                Elbow::Up
            } else {
                Elbow::Down
            };
            let rw_a5 = ry(&r1_a5);
            let q2 = wrap(s.s2 * el.th2);
            let q3 = wrap(s.s3 * el.th3);
            let near_singular = sd < singularity_threshold;
            let snapped = sd < tol.wrist;
            if near_singular || snapped {
                out.singular = true;
            }
            if snapped {
                // Axes 4 and 6 aligned (cw > 0) or opposed: q5 is exactly φ5 or
                // φ5 + π and only q4 + q6 (or q4 − q6) is determined; it equals ψ,
                // the angle about a4 from a5 to Rw·a5. Rule: q4 keeps the seed,
                // q6 takes the rest; the flip branch is q4 + π.
                let psi = atan2(s.a4.dot(&s.a5.cross(&rw_a5)), s.a5.dot(&rw_a5));
                let (q5, sgn) = if cw > 0.0 {
                    (s.phi5, 1.0)
                } else {
                    (wrap(s.phi5 + PI), -1.0)
                };
                for (k, wrist) in [(0.0, Wrist::NoFlip), (PI, Wrist::Flip)] {
                    let q4 = wrap(q4_seed + k);
                    out.push(Branch {
                        joints: [q1, q2, q3, q4, q5, wrap(sgn * (psi - q4))],
                        configuration: Configuration {
                            shoulder,
                            elbow,
                            wrist,
                        },
                        singular: true,
                        polish: false,
                        provisional: false,
                    });
                }
                continue;
            }
            let polish =
                sd.min(el.margin).min(sh.margin) < POLISH_NEAR && !(sh.snapped || el.snapped);
            let delta = atan2(sd, cw);
            let tp = t - s.a4 * s.a4.dot(&t);
            // No-flip root q5 = φ5 + δ.
            let s5 = s.s_phi5 * cw + s.c_phi5 * sd;
            let c5 = s.c_phi5 * cw - s.s_phi5 * sd;
            let v5 = s.a6 * c5 + s.a5x6 * s5;
            // q4 turns v5 onto t about a4.
            let vp = v5 - s.a4 * s.a4.dot(&v5);
            let crs4 = s.a4.dot(&vp.cross(&tp));
            let dot4 = vp.dot(&tp);
            let n4 = (crs4 * crs4 + dot4 * dot4).sqrt();
            let (s4, c4) = (crs4 / n4, dot4 / n4);
            // q6 turns a5 onto Rot(a5,−q5)·Rot(a4,−q4)·Rw·a5 about a6.
            let m = rot_v(&s.a5, -s5, c5, &rot_v(&s.a4, -s4, c4, &rw_a5));
            let q4 = atan2(crs4, dot4);
            let q6 = atan2(s.a6.dot(&s.a5.cross(&m)), s.a5.dot(&m));
            out.push(Branch {
                joints: [q1, q2, q3, q4, wrap(s.phi5 + delta), q6],
                configuration: Configuration {
                    shoulder,
                    elbow,
                    wrist: Wrist::NoFlip,
                },
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
                    wrap(s.phi5 - delta),
                    wrap(q6 + PI),
                ],
                configuration: Configuration {
                    shoulder,
                    elbow,
                    wrist: Wrist::Flip,
                },
                singular: near_singular,
                polish,
                provisional: false,
            });
        }
    }
    out
}

/// The side-by-side wrists give the per-branch form's bits: every branch, label
/// and flag, on random, wrist-singular, near-singular and shoulder-singular
/// targets of every catalog OPW arm (both the dispatched and the portable code).
#[test]
fn lanes_give_the_per_branch_bits() {
    let mut rng = Rng::new(3838);
    let same = |a: &Branches, b: &Branches| {
        a.len() == b.len()
            && a.singular == b.singular
            && a.undetermined == b.undetermined
            && a.out_of_reach == b.out_of_reach
            && a.as_slice().iter().zip(b.as_slice()).all(|(x, y)| {
                x.joints.map(f64::to_bits) == y.joints.map(f64::to_bits)
                    && x.configuration == y.configuration
                    && x.singular == y.singular
                    && x.polish == y.polish
                    && x.provisional == y.provisional
            })
    };
    let mut compared = 0;
    for arm in OPW_ARMS {
        let r = arm.robot();
        let s = r.analytic().unwrap();
        for k in 0..4000 {
            let mut q = random_q(&mut rng, &r);
            match k % 4 {
                1 => q[4] = s.phi5 + NEAR_SINGULAR[k / 4 % NEAR_SINGULAR.len()],
                2 => q[4] = wrap(s.phi5 + PI) + NEAR_SINGULAR[k / 4 % NEAR_SINGULAR.len()],
                _ => {}
            }
            let mut target = *r.tcp_pose(&q).unwrap().isometry();
            if k % 16 == 3 {
                // The wrist centre moved onto axis 1 (or near it).
                let wc = s.c_from_root * (target * Point3::from(s.w_tcp));
                let shift = Vector3::new(wc.x, wc.y, 0.0) * (1.0 - rng.range(0.0, 1e-9));
                target.translation.vector -= s.root_from_c.rotation * shift;
            }
            if k % 16 == 7 {
                // Out of reach or at the edge.
                target.translation.vector *= rng.range(1.0, 3.0);
            }
            for thr in [1e-9, 1e-3] {
                let seed = rng.range(-PI, PI);
                let reference = per_branch(s, &target, thr, seed);
                let got = s.branches_seeded(&target, thr, seed);
                let portable = s.solve(&target, thr, seed);
                assert!(
                    same(&got, &reference) && same(&portable, &reference),
                    "{} {q:?}: {:?} / {:?}, per branch {:?}",
                    arm.name(),
                    got.as_slice(),
                    portable.as_slice(),
                    reference.as_slice()
                );
                compared += reference.len();
            }
        }
    }
    assert!(compared > 100_000, "{compared}");
}

/// Checks the wrist-singularity properties for `robot` at joints `q` whose joint 5
/// is `eps` away from the singular value (axes 4 and 6 aligned, or opposed when
/// `opposed`): the branch count equals the regular count (same wrist centre,
/// joint 5 moved away), every branch reproduces the target to 1e-8 mm (well under
/// 1e-9 m) and 1e-9 rad, the generating configuration is among them (up to the
/// split of q4 ± q6 where that is ill-conditioned), and at the exact singularity
/// joint 5 is exactly the singular value, the branch is flagged and q4 is the seed.
fn check_wrist_singular(robot: &Robot, q: [f64; 5], eps: f64, opposed: bool) -> Result<(), String> {
    let s = robot.analytic().ok_or("not OPW")?;
    let q5s = if opposed { wrap(s.phi5 + PI) } else { s.phi5 };
    let q = [q[0], q[1], q[2], q[3], q5s + eps, q[4]];
    let target = robot.tcp_pose(&q).unwrap();
    let mut regular_q = q;
    regular_q[4] = q5s + 0.5;
    let regular = s.branches(robot.tcp_pose(&regular_q).unwrap().isometry(), 1e-9);
    let br = s.branches_seeded(target.isometry(), 1e-9, q[3]);
    if br.len() != regular.len() || br.is_empty() {
        return Err(format!("{} branches, regular {}", br.len(), regular.len()));
    }
    let sgn = if opposed { -1.0 } else { 1.0 };
    let mut found = false;
    for b in br.as_slice() {
        let got = robot.tcp_pose(&b.joints).unwrap();
        let (ang, dist) = got.distance_to(&target);
        // 1e-8 mm (10 pm) on arms up to ~3 m: a few ulps of the reach, amplified
        // near the shoulder singularity; far below any physical meaning.
        if dist > 1e-8 || ang > 1e-9 {
            return Err(format!("{b:?}: {dist:e} mm {ang:e} rad"));
        }
        if !same_angles(&b.joints[..3], &q[..3], 1e-7) {
            continue; // another arm branch: its wrist is not singular
        }
        if eps == 0.0 {
            if b.joints[4] != q5s || !b.singular {
                return Err(format!("singular target, q5 must be {q5s}: {b:?}"));
            }
            if b.configuration.wrist == Wrist::NoFlip && b.joints[3] != wrap(q[3]) {
                return Err(format!("q4 must keep the seed {}: {b:?}", q[3]));
            }
        } else if eps.abs() < 1e-9 && !b.singular {
            return Err(format!("near-singular branch not flagged: {b:?}"));
        }
        // Near the singularity q4 ± q6 is well conditioned; q4 alone carries the
        // rounding of the target divided by sin(θ5) (≈ 1e-16 / |eps|).
        // (an arm near its shoulder singularity adds its own ill-conditioning).
        let q4_tol = if eps == 0.0 { PI } else { 1e-11 / eps.abs() };
        found |= wrap(b.joints[4] - q[4]).abs() < 1e-9
            && wrap(b.joints[3] + sgn * b.joints[5] - q[3] - sgn * q[5]).abs() < 1e-7
            && wrap(b.joints[3] - q[3]).abs() < q4_tol;
    }
    if !found {
        return Err(format!("original {q:?} missing from {:?}", br.as_slice()));
    }
    Ok(())
}

proptest::proptest! {
    #![proptest_config(crate::test_support::proptest_config(400))]

    /// Every catalog OPW arm with joint 5 at 0, ±1e-12, ±1e-9, ±1e-7 from its
    /// singular value (θ5 = 0 in the arm's own convention; also the opposed case).
    #[test]
    fn catalog_wrist_singularity_keeps_every_branch(
        arm in 0usize..OPW_ARMS.len(),
        q in proptest::array::uniform5(-PI..PI),
        k in 0usize..NEAR_SINGULAR.len(),
        opposed in proptest::bool::weighted(0.2),
    ) {
        let r = OPW_ARMS[arm].robot();
        if let Err(e) = check_wrist_singular(&r, q, NEAR_SINGULAR[k], opposed) {
            proptest::prop_assert!(false, "{}: {}", OPW_ARMS[arm].name(), e);
        }
    }

    /// Random OPW geometries (offsets on joints 2, 3 and 6, random axis signs).
    #[test]
    fn random_opw_wrist_singularity_keeps_every_branch(
        len in proptest::array::uniform7(0.0..1.0f64),
        off in proptest::array::uniform3(-PI..PI),
        signs in proptest::array::uniform6(proptest::bool::ANY),
        q in proptest::array::uniform5(-PI..PI),
        k in 0usize..NEAR_SINGULAR.len(),
        opposed in proptest::bool::weighted(0.2),
    ) {
        let mut p = OpwParameters::new(
            300.0 * len[0],
            400.0 * len[1] - 200.0,
            200.0 * len[2] - 100.0,
            200.0 + 600.0 * len[3],
            200.0 + 800.0 * len[4],
            200.0 + 800.0 * len[5],
            200.0 * len[6],
        );
        p.offsets = [0.0, off[0], off[1], 0.0, 0.0, off[2]];
        p.signs = signs.map(|b| if b { 1.0 } else { -1.0 });
        let r = p.robot("random", [None; 6]).unwrap();
        if let Err(e) = check_wrist_singular(&r, q, NEAR_SINGULAR[k], opposed) {
            proptest::prop_assert!(false, "{p:?}: {}", e);
        }
    }
}

#[test]
fn out_of_reach_and_singular_targets_are_errors() {
    let r = Catalog::AbbIrb2400.robot();
    let far = Transform::from_translation(Vec3::new(5000.0, 0.0, 500.0));
    let zero = [0.0; 6];
    assert!(matches!(
        r.inverse(&far, &zero, &IkOptions::default()),
        Err(IkError::Unreachable(_))
    ));
    // The IRB 2400 zero pose has joint 5 = 0: axes 4 and 6 aligned.
    let home = r.tcp_pose(&zero).unwrap();
    let s = r.analytic().unwrap();
    let br = s.branches(home.isometry(), 1e-9);
    assert!(br.singular);
    for b in br.as_slice() {
        let got = r.tcp_pose(&b.joints).unwrap();
        assert!(got.approx_eq(&home, 1e-6, 1e-9));
    }
    // Wrist centre on axis 1 (b = 0 for the IRB 2400): joint 1 is undetermined.
    // For this arm C is the root frame, so W = (0, 0, 1400) is on axis 1.
    let rot = crate::math::AngleConvention::XyzFixed.rotation(0.3, 1.0, -0.4);
    let p = Vec3::new(0.0, 0.0, 1400.0) - rot * s.w_tcp;
    let on_axis = Transform::from_parts(p, rot);
    assert!(matches!(
        r.inverse(&on_axis, &zero, &IkOptions::default()),
        Err(IkError::Singular(_))
    ));
    let nan = Transform::from_translation(Vec3::new(f64::NAN, 0.0, 0.0));
    assert!(r.inverse(&nan, &zero, &IkOptions::default()).is_err());
}

#[test]
fn limits_and_variants_sorted_by_distance() {
    let r = Catalog::AbbIrb2400.robot(); // joint 6 ±400°: two variants often
    let mut rng = Rng::new(5);
    for _ in 0..200 {
        let q = random_q(&mut rng, &r);
        let t = r.tcp_pose(&q).unwrap();
        let sols = r.inverse(&t, &q, &IkOptions::default()).unwrap();
        assert!(
            sols[0].distance < 1e-6,
            "nearest must be the reference itself"
        );
        for w in sols.windows(2) {
            assert!(w[0].distance <= w[1].distance);
        }
        for s in &sols {
            assert!(r.limit_violation(&s.joints).is_none());
            assert!(r.tcp_pose(&s.joints).unwrap().approx_eq(&t, 1e-6, 1e-9));
        }
        assert!(
            sols.iter().any(|s| (s.joints[5] - q[5]).abs() > 6.0),
            "±360° variant of joint 6"
        );
    }
}

/// Re-framing every link (arbitrary link frames, tool pointing back, base moved)
/// keeps the robot detected and solved: nothing depends on D-H frames.
#[test]
fn detection_is_independent_of_link_frames() {
    let mut rng = Rng::new(9);
    for arm in OPW_ARMS {
        let r = arm.robot();
        let links = r.tree().links();
        let frames: Vec<Isometry3<f64>> = (0..links.len())
            .map(|_| {
                Isometry3::from_parts(
                    Translation3::new(
                        rng.range(-50.0, 50.0),
                        rng.range(-50.0, 50.0),
                        rng.range(-50.0, 50.0),
                    ),
                    rng.rotation(),
                )
            })
            .collect();
        // New link frame i = old frame · F_i; children see parent quantities through F_parent⁻¹.
        let new_links: Vec<Link> = links
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let finv = l
                    .parent
                    .map(|p| frames[p].inverse())
                    .unwrap_or_else(Isometry3::identity);
                let mut j: Joint = l.joint;
                j.axis = finv.rotation * j.axis;
                j.point = finv * j.point;
                Link {
                    name: l.name.clone(),
                    parent: l.parent,
                    home: Transform::from_isometry(finv * l.home.isometry() * frames[i]),
                    joint: j,
                }
            })
            .collect();
        let tool = Transform::from_isometry(frames[r.flange()].inverse() * r.tool().isometry());
        let tree = KinematicTree::new(new_links).unwrap();
        let base = Transform::from_xyzabc(
            Vec3::new(100.0, -20.0, 30.0),
            [0.3, -0.2, 1.0],
            Default::default(),
        );
        let r2 = Robot::new("reframed", tree, r.flange(), tool)
            .unwrap()
            .with_base(base);
        assert!(
            r2.analytic().is_some(),
            "{}: {:?}",
            arm.name(),
            r2.analytic_rejection()
        );
        for _ in 0..200 {
            let q = random_q(&mut rng, &r);
            let t = r2.tcp_pose(&q).unwrap();
            assert!(t.approx_eq(&(r.tcp_pose(&q).unwrap() * base), 1e-9, 1e-12));
            let sols = r2.inverse(&t, &q, &IkOptions::default()).unwrap();
            assert!(same_angles(&sols[0].joints, &q, 1e-7));
        }
    }
}
