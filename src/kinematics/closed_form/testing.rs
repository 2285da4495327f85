use crate::kinematics::{Branches, Catalog, IkOptions, NumericIk, Robot};
use crate::math::trig::wrap;
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
