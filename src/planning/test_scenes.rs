//! Analytic test scenes: a box-shaped component among axis-aligned box obstacles,
//! checked exactly with a separating-axis test, and the planner property tests.

use super::*;
use crate::collision::SweepMethod;
use crate::math::Aabb;
use crate::math::{Transform, Vec3};
use nalgebra::Matrix3;

/// A box component (half extents `half`, centred on its origin) among boxes.
#[derive(Clone)]
pub(crate) struct BoxScene {
    pub half: Vec3,
    pub obstacles: Vec<Aabb>,
    /// Obstacles are grown by this (mm) when checking, so that a stepwise edge check
    /// is conservative against the exact scene.
    pub inflate: f64,
    pub step_mm: f64,
    pub step_rad: f64,
    pub report_clearance: bool,
}

/// Whether the oriented box (rotation `r`, centre `c`, half `h`) and the axis-aligned
/// box (centre `b`, half `e`) overlap; touching is not overlapping.
fn obb_overlaps_aabb(r: &Matrix3<f64>, c: &Vec3, h: &Vec3, b: &Vec3, e: &Vec3) -> bool {
    let t = b - c;
    let a = [
        r.column(0).into_owned(),
        r.column(1).into_owned(),
        r.column(2).into_owned(),
    ];
    let separated = |l: Vec3| {
        let n = l.norm();
        if n < 1e-9 {
            return false;
        }
        let ra: f64 = (0..3).map(|i| h[i] * a[i].dot(&l).abs()).sum();
        let rb: f64 = (0..3).map(|i| e[i] * l[i].abs()).sum();
        t.dot(&l).abs() >= ra + rb
    };
    for (i, ai) in a.iter().enumerate() {
        if separated(Vec3::ith(i, 1.0)) || separated(*ai) {
            return false;
        }
    }
    for ai in &a {
        for j in 0..3 {
            if separated(ai.cross(&Vec3::ith(j, 1.0))) {
                return false;
            }
        }
    }
    true
}

impl BoxScene {
    pub fn exact(&self) -> Self {
        Self {
            inflate: 0.0,
            ..self.clone()
        }
    }

    fn local_box(&self) -> Aabb {
        Aabb::new(-self.half, self.half)
    }
}

impl MotionValidator for BoxScene {
    fn is_free(&mut self, pose: &Transform) -> bool {
        let r = pose.rotation().to_rotation_matrix().into_inner();
        let c = pose.translation();
        !self.obstacles.iter().any(|o| {
            let b = (o.lo.coords + o.hi.coords) * 0.5;
            let e = (o.hi - o.lo) * 0.5 + Vec3::repeat(self.inflate);
            obb_overlaps_aabb(&r, &c, &self.half, &b, &e)
        })
    }
    fn resolution(&self) -> SweepMethod {
        SweepMethod::Stepwise {
            step_mm: self.step_mm,
            step_rad: self.step_rad,
        }
    }
    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        if !self.report_clearance {
            return None;
        }
        // Distance from the component's bounding box: a lower bound of the true one.
        let b = self.local_box().transformed(pose.isometry());
        let d = self.obstacles.iter().fold(f64::INFINITY, |m, o| {
            let gap = (o.lo - b.hi).sup(&(b.lo - o.hi)).sup(&Vec3::zeros());
            m.min(gap.norm() - self.inflate)
        });
        Some(d.max(0.0))
    }
}

fn aabb(min: [f64; 3], max: [f64; 3]) -> Aabb {
    Aabb::new(Vec3::from(min), Vec3::from(max))
}

fn scene(half: [f64; 3], obstacles: Vec<Aabb>) -> BoxScene {
    BoxScene {
        half: Vec3::from(half),
        obstacles,
        inflate: 0.3,
        step_mm: 0.25,
        step_rad: 0.01,
        report_clearance: false,
    }
}

/// One cube obstacle in the middle.
fn open_scene() -> BoxScene {
    scene([2.0; 3], vec![aabb([-10.0; 3], [10.0; 3])])
}

/// A wall across X with a square hole of half-width `4 + clearance` for a peg of
/// square section 8 × 8 mm, 16 mm long.
fn slot_scene(clearance: f64) -> BoxScene {
    let (w, hole) = (60.0, 4.0 + clearance);
    let wall = |ylo, yhi, zlo, zhi| aabb([-5.0, ylo, zlo], [5.0, yhi, zhi]);
    scene(
        [8.0, 4.0, 4.0],
        vec![
            wall(-w, -hole, -w, w),
            wall(hole, w, -w, w),
            wall(-hole, hole, -w, -hole),
            wall(-hole, hole, hole, w),
        ],
    )
}

/// The component shut in a closed box.
fn sealed_scene() -> BoxScene {
    let (i, o) = (15.0, 20.0);
    scene(
        [2.0; 3],
        vec![
            aabb([-o, -o, -o], [-i, o, o]),
            aabb([i, -o, -o], [o, o, o]),
            aabb([-i, -o, -o], [i, -i, o]),
            aabb([-i, i, -o], [i, o, o]),
            aabb([-i, -i, -o], [i, i, -i]),
            aabb([-i, -i, i], [i, i, o]),
        ],
    )
}

fn space() -> PlanningSpace {
    PlanningSpace::new(Vec3::repeat(-50.0), Vec3::repeat(50.0)).with_rotation_weight(10.0)
}

fn at(x: f64, y: f64, z: f64) -> Transform {
    Transform::from_translation(Vec3::new(x, y, z))
}

fn limits(seed: u64, max_iterations: usize) -> PlanLimits {
    PlanLimits {
        seed,
        max_iterations,
        time_limit_ms: None,
    }
}

/// Every planner on one query, by name.
fn plan(
    name: &str,
    s: &PlanningSpace,
    v: &mut dyn MotionValidator,
    start: &Transform,
    goal: &Transform,
    seed: u64,
    iterations: usize,
) -> PlannedPath {
    let lim = limits(seed, iterations);
    let s = s.clone();
    match name {
        "greedy_ant" => greedy_ant(
            v,
            &s,
            start,
            goal,
            &GreedyAntOptions {
                limits: lim,
                radius: Some(30.0),
                ..Default::default()
            },
            None,
        ),
        "rrt_floyd" => rrt_floyd(
            v,
            &s,
            start,
            goal,
            &RrtFloydOptions {
                limits: lim,
                ..Default::default()
            },
            None,
        ),
        "rrt" => rrt(
            v,
            &s,
            start,
            goal,
            &RrtOptions {
                limits: lim,
                ..Default::default()
            },
            None,
        ),
        "biased_rrt" => biased_rrt(
            v,
            &s,
            start,
            goal,
            &RrtOptions {
                limits: lim,
                ..RrtOptions::biased()
            },
            None,
        ),
        "local_rrt" => {
            let mut o = LocalRrtOptions::default();
            o.rrt.limits = lim;
            local_rrt(v, &s, start, goal, &o, None)
        }
        "rrt_connect" => rrt_connect(
            v,
            &s,
            start,
            goal,
            &RrtConnectOptions {
                limits: lim,
                ..Default::default()
            },
            None,
        ),
        "rrt_connect_eager" => rrt_connect(
            v,
            &s,
            start,
            goal,
            &RrtConnectOptions {
                limits: lim,
                lazy: None,
                ..Default::default()
            },
            None,
        ),
        "rrt_connect_plain" => rrt_connect(
            v,
            &s,
            start,
            goal,
            &RrtConnectOptions {
                limits: lim,
                lattice: None,
                ..Default::default()
            },
            None,
        ),
        _ => unreachable!("unknown planner {name}"),
    }
    .expect("valid options")
}

/// Every planner by name, and RRT-Connect eager and without its measures.
fn planners() -> impl Iterator<Item = &'static str> {
    super::request::PLANNER_NAMES
        .into_iter()
        .chain(["rrt_connect_eager", "rrt_connect_plain"])
}

/// The property every found path must have: it starts and ends where asked and is
/// free in the exact scene at a resolution finer than the planner's.
fn assert_valid(p: &PlannedPath, scene: &BoxScene, start: &Transform, goal: Option<&Transform>) {
    assert!(p.found(), "{}: {:?}", p.planner, p.failure);
    assert!(
        p.poses[0].approx_eq(start, 1e-9, 1e-9),
        "{} start",
        p.planner
    );
    if let Some(g) = goal {
        assert!(
            p.poses.last().unwrap().approx_eq(g, 1e-9, 1e-9),
            "{} goal",
            p.planner
        );
    }
    let mut exact = scene.exact();
    for (k, pose) in p.densify(0.05, 0.002).unwrap().iter().enumerate() {
        assert!(
            exact.is_free(pose),
            "{}: collision at dense pose {k}: {pose}",
            p.planner
        );
    }
    assert!(p.revalidate(&mut scene.clone()).is_ok(), "{}", p.planner);
    assert!(p.length_mm <= p.raw_length_mm + 1e-9);
}

#[test]
fn every_planner_finds_a_free_path_around_an_obstacle() {
    let scene = open_scene();
    let (start, goal) = (at(-30.0, 0.0, 0.0), at(30.0, 0.0, 0.0));
    // Turning about Z within ±0.5 rad: rotation is exercised, and plain RRT (no goal
    // bias) still gets within its tolerance of the goal.
    let turn_z = space().with_rotation(RotationFreedom::Axes {
        x: false,
        y: false,
        z: true,
        max_angle: 0.5,
    });
    for name in planners() {
        let p = plan(name, &turn_z, &mut scene.clone(), &start, &goal, 1, 5000);
        assert_valid(&p, &scene, &start, Some(&goal));
        assert!(p.collision_checks() > 0);
    }
}

#[test]
fn same_seed_same_path() {
    let scene = slot_scene(2.0);
    let (start, goal) = (at(-30.0, 10.0, 10.0), at(30.0, -5.0, 0.0));
    for name in planners() {
        let a = plan(name, &space(), &mut scene.clone(), &start, &goal, 7, 3000);
        let b = plan(name, &space(), &mut scene.clone(), &start, &goal, 7, 3000);
        assert_eq!(a.failure, b.failure, "{name}");
        assert_eq!(a.poses, b.poses, "{name}");
        assert_eq!(a.collision_checks(), b.collision_checks(), "{name}");
    }
}

#[test]
fn sealed_box_fails_within_limits_with_a_reason() {
    let scene = sealed_scene();
    let (start, goal) = (at(0.0, 0.0, 0.0), at(40.0, 0.0, 0.0));
    for name in planners() {
        let p = plan(name, &space(), &mut scene.clone(), &start, &goal, 3, 300);
        assert!(!p.found(), "{name}");
        assert!(p.poses.is_empty());
        let expected = match name {
            "greedy_ant" => matches!(p.failure, Some(Failure::Exhausted(_))),
            "rrt_floyd" => matches!(
                p.failure,
                Some(Failure::IterationLimit | Failure::Exhausted(_))
            ),
            _ => p.failure == Some(Failure::IterationLimit),
        };
        assert!(expected, "{name}: {:?}", p.failure);
        assert!(p.iterations <= 300);
    }
}

#[test]
fn colliding_or_outside_ends_are_reported() {
    let scene = open_scene();
    for name in planners() {
        let p = plan(
            name,
            &space(),
            &mut scene.clone(),
            &at(0.0, 0.0, 0.0),
            &at(30.0, 0.0, 0.0),
            0,
            10,
        );
        assert_eq!(p.failure, Some(Failure::StartInCollision), "{name}");
        let p = plan(
            name,
            &space(),
            &mut scene.clone(),
            &at(30.0, 0.0, 0.0),
            &at(0.0, 5.0, 0.0),
            0,
            10,
        );
        assert_eq!(p.failure, Some(Failure::GoalInCollision), "{name}");
        let p = plan(
            name,
            &space(),
            &mut scene.clone(),
            &at(30.0, 0.0, 0.0),
            &at(99.0, 0.0, 0.0),
            0,
            10,
        );
        assert_eq!(p.failure, Some(Failure::GoalOutOfBounds), "{name}");
    }
}

#[test]
fn touching_start_is_valid() {
    // Resting against the obstacle's face at x = 10 (exact scene: touching is free).
    let mut scene = open_scene().exact();
    let start = at(12.0, 0.0, 0.0);
    assert!(scene.is_free(&start));
    let p = plan(
        "rrt_connect",
        &space(),
        &mut scene,
        &start,
        &at(30.0, 20.0, 0.0),
        0,
        1000,
    );
    assert!(p.found(), "{:?}", p.failure);
}

#[test]
fn bad_options_are_rejected_with_their_name() {
    let s = space();
    let mut v = open_scene();
    let (a, b) = (at(-30.0, 0.0, 0.0), at(30.0, 0.0, 0.0));
    let err = |r: Result<PlannedPath, PlanError>| r.unwrap_err().to_string();
    let o = RrtOptions {
        step: -1.0,
        ..Default::default()
    };
    assert!(err(rrt(&mut v, &s, &a, &b, &o, None)).contains("`step`"));
    let o = RrtOptions {
        goal_bias: 1.5,
        ..Default::default()
    };
    assert!(err(rrt(&mut v, &s, &a, &b, &o, None)).contains("goal_bias"));
    let o = RrtOptions {
        goal_bias: f64::NAN,
        ..Default::default()
    };
    assert!(err(rrt(&mut v, &s, &a, &b, &o, None)).contains("goal_bias"));
    assert!(
        err(biased_rrt(&mut v, &s, &a, &b, &RrtOptions::default(), None)).contains("goal_bias")
    );
    let o = RrtOptions {
        limits: limits(0, 0),
        ..Default::default()
    };
    assert!(err(rrt(&mut v, &s, &a, &b, &o, None)).contains("max_iterations"));
    let inverted = PlanningSpace::new(Vec3::repeat(10.0), Vec3::repeat(-10.0));
    assert!(err(rrt(&mut v, &inverted, &a, &b, &RrtOptions::default(), None)).contains("bounds"));
    let mut o = LocalRrtOptions::default();
    o.lattice.edge_length_min = 10.0;
    assert!(err(local_rrt(&mut v, &s, &a, &b, &o, None)).contains("edge_length_min"));
    let o = GreedyAntOptions {
        dis: 0.0,
        ..Default::default()
    };
    assert!(err(greedy_ant(&mut v, &s, &a, &b, &o, None)).contains("dis"));
    let o = GreedyAntOptions {
        step: Some(0),
        ..Default::default()
    };
    assert!(err(greedy_ant(&mut v, &s, &a, &b, &o, None)).contains("step"));
    let o = RrtFloydOptions {
        max_nodes: 5000,
        ..Default::default()
    };
    assert!(err(rrt_floyd(&mut v, &s, &a, &b, &o, None)).contains("max_nodes"));
    let o = RrtConnectOptions {
        step: Some(0.0),
        ..Default::default()
    };
    assert!(err(rrt_connect(&mut v, &s, &a, &b, &o, None)).contains("step"));
    let o = RrtConnectOptions {
        lazy: Some(LazyValidation { step_mm: -1.0 }),
        ..Default::default()
    };
    assert!(err(rrt_connect(&mut v, &s, &a, &b, &o, None)).contains("lazy.step_mm"));
    let nan = at(f64::NAN, 0.0, 0.0);
    assert!(err(rrt_connect(
        &mut v,
        &s,
        &nan,
        &b,
        &RrtConnectOptions::default(),
        None
    ))
    .contains("start"));
}

/// Lazy validation explores with pose checks 8 mm apart, which jump a wall 1 mm
/// thick (the box is 4 mm long); certification with the validator's own edge check
/// must catch every such edge, cut it and let the search go round through the
/// window. Every returned path is free in the exact scene, and the paths that were
/// certified by the search's own counts: each edge of the path cost one check.
#[test]
fn lazy_search_certifies_its_path_and_repairs_jumped_walls() {
    let hole = 6.0;
    let wall = |ylo, yhi, zlo, zhi| aabb([-0.5, ylo, zlo], [0.5, yhi, zhi]);
    let scene = scene(
        [2.0; 3],
        vec![
            wall(-50.0, -hole, -50.0, 50.0),
            wall(hole, 50.0, -50.0, 50.0),
            wall(-hole, hole, -50.0, -hole),
            wall(-hole, hole, hole, 50.0),
        ],
    );
    let (start, goal) = (at(-20.0, 30.0, 0.0), at(20.0, 30.0, 0.0));
    // The pose checks alone accept the straight edge through the wall.
    let mut probe = scene.clone();
    assert!(stepwise_edge_free(
        |p| probe.is_free(p),
        &start,
        &goal,
        8.0,
        0.8
    ));
    assert!(!scene.clone().edge_free(&start, &goal));
    let fixed = space().with_rotation(RotationFreedom::Fixed);
    for seed in 0..5 {
        // Iterations include the axis-move search's (issue 23); 3000 left a
        // seed short once it took its share.
        let o = RrtConnectOptions {
            limits: limits(seed, 10_000),
            // An explicit step: the lazy step as given (coarser than the wall).
            step: Some(RrtConnectOptions::STEP),
            lazy: Some(LazyValidation { step_mm: 8.0 }),
            smoothing: Smoothing::OFF,
            ..Default::default()
        };
        let p = rrt_connect(&mut scene.clone(), &fixed, &start, &goal, &o, None).unwrap();
        assert_eq!(p.planner, "lazy_rrt_connect");
        assert_valid(&p, &scene, &start, Some(&goal));
        assert!(
            p.edge_checks >= (p.poses.len() - 1) as u64,
            "every edge of the path was certified"
        );
        // It went through the window.
        let crossing = p.densify(0.5, 0.01).unwrap();
        assert!(crossing
            .iter()
            .filter(|q| q.translation().x.abs() < 2.8)
            .all(|q| q.translation().y.abs() < hole));
    }
}

#[test]
fn local_rrt_solves_a_narrow_slot_that_rrt_rarely_does() {
    // 2 mm clearance (1.7 mm after the 0.3 mm inflation), translation only: the hole
    // is 0.2 % of the wall's area.
    let scene = slot_scene(2.0);
    let (start, goal) = (at(-30.0, 15.0, 10.0), at(30.0, -10.0, 5.0));
    let runs = 10;
    let mut solved = std::collections::HashMap::new();
    for name in ["rrt", "biased_rrt", "local_rrt", "rrt_connect"] {
        let mut n = 0;
        for seed in 0..runs {
            let fixed = space().with_rotation(RotationFreedom::Fixed);
            // rrt_connect's iterations are mostly plain ones of a check or two
            // (its fallbacks get a tenth of the work until the search stalls for
            // Effort::STAGNATION iterations), so it gets more iterations.
            let iterations = if name == "rrt_connect" { 60_000 } else { 1500 };
            let p = plan(
                name,
                &fixed,
                &mut scene.clone(),
                &start,
                &goal,
                seed,
                iterations,
            );
            if p.found() {
                assert_valid(&p, &scene, &start, Some(&goal));
                n += 1;
            }
        }
        solved.insert(name, n);
    }
    assert!(solved["local_rrt"] >= solved["rrt"] + 3, "{solved:?}");
    assert!(
        solved["local_rrt"] >= solved["biased_rrt"] + 3,
        "{solved:?}"
    );
    assert!(solved["rrt_connect"] >= 9, "{solved:?}");
    assert!(solved["rrt"] <= 2, "{solved:?}");
}

#[test]
fn disassembly_leaves_the_product_box_and_ends_assembled() {
    // A peg in a blind pocket open toward +Z, 0.5 mm clearance.
    let (h, c) = (4.0, 0.5);
    let hole = h + c;
    let cup = |lo: [f64; 3], hi: [f64; 3]| aabb(lo, hi);
    let scene = scene(
        [h, h, 8.0],
        vec![
            cup([-20.0, -20.0, -15.0], [20.0, 20.0, -8.0]),
            cup([-20.0, -20.0, -8.0], [-hole, 20.0, 10.0]),
            cup([hole, -20.0, -8.0], [20.0, 20.0, 10.0]),
            cup([-hole, -20.0, -8.0], [hole, -hole, 10.0]),
            cup([-hole, hole, -8.0], [hole, 20.0, 10.0]),
        ],
    );
    let assembled = at(0.0, 0.0, 0.5);
    let product = aabb([-20.0, -20.0, -15.0], [20.0, 20.0, 10.0]);
    let part = Aabb::new(Vec3::new(-h, -h, -8.0), Vec3::new(h, h, 8.0));
    for planner in [
        DisassemblyPlanner::LocalRrt(LocalRrtOptions::default()),
        DisassemblyPlanner::Rrt(RrtOptions {
            limits: limits(1, 20_000),
            ..RrtOptions::biased()
        }),
    ] {
        let p = disassemble(
            &mut scene.clone(),
            &space(),
            &assembled,
            &part,
            &product,
            &planner,
            None,
        )
        .unwrap();
        if matches!(planner, DisassemblyPlanner::Rrt(_)) && !p.found() {
            continue; // the baseline may fail; only what it returns must be right
        }
        assert!(p.found(), "{:?}", p.failure);
        let first = part.transformed(p.poses[0].isometry());
        assert!((0..3).any(|k| first.lo[k] >= product.hi[k] || first.hi[k] <= product.lo[k]));
        assert!(p.poses.last().unwrap().approx_eq(&assembled, 1e-9, 1e-9));
        let mut exact = scene.exact();
        assert!(p
            .densify(0.05, 0.002)
            .unwrap()
            .iter()
            .all(|q| exact.is_free(q)));
    }
}

#[test]
fn progress_callback_can_cancel() {
    let scene = sealed_scene();
    let mut calls = 0;
    let mut cancel = |_: &Progress| {
        calls += 1;
        Control::Cancel
    };
    let o = RrtOptions {
        limits: limits(0, 100_000),
        ..Default::default()
    };
    let p = rrt(
        &mut scene.clone(),
        &space(),
        &at(0.0, 0.0, 0.0),
        &at(40.0, 0.0, 0.0),
        &o,
        Some(&mut cancel),
    )
    .unwrap();
    assert_eq!(p.failure, Some(Failure::Cancelled));
    assert_eq!(calls, 1);
}

#[test]
fn clearance_sized_lattice_solves_the_slot() {
    let mut scene = slot_scene(2.0);
    scene.report_clearance = true;
    let (start, goal) = (at(-30.0, 15.0, 10.0), at(30.0, -10.0, 5.0));
    let fixed = space().with_rotation(RotationFreedom::Fixed);
    let solved = (0..4)
        .filter_map(|seed| {
            let p = plan(
                "local_rrt",
                &fixed,
                &mut scene.clone(),
                &start,
                &goal,
                seed,
                3000,
            );
            p.found().then_some(p)
        })
        .inspect(|p| assert_valid(p, &scene, &start, Some(&goal)))
        .count();
    assert!(
        solved >= 1,
        "no seed solved the slot with a clearance-sized lattice"
    );
}

#[test]
fn separating_axis_test_sees_rotation() {
    // A 2 × 2 × 20 bar next to a cube: free when aligned, colliding when turned 90°.
    let mut s = scene(
        [10.0, 1.0, 1.0],
        vec![aabb([-5.0, 5.0, -5.0], [5.0, 15.0, 5.0])],
    );
    s.inflate = 0.0;
    assert!(s.is_free(&Transform::IDENTITY));
    let turned = Transform::from_xyzabc(
        Vec3::zeros(),
        [0.0, 0.0, std::f64::consts::FRAC_PI_2],
        crate::math::AngleConvention::XyzFixed,
    );
    assert!(!s.is_free(&turned));
}

/// A straight line from start to goal through a 0.2 mm clearance (a plate slid onto a
/// pin, issue 23): RRT-Connect and the insertion planner return it after the first edge
/// check, whatever the seed, as the two-pose path. Sampling never draws it: before the
/// direct edge, 98k iterations did not find it.
#[test]
fn a_free_straight_line_is_found_first() {
    let scene = BoxScene {
        inflate: 0.0,
        ..slot_scene(0.2)
    };
    let (start, goal) = (at(-30.0, 0.0, 0.0), at(30.0, 0.0, 0.0));
    for seed in 0..3 {
        let p = plan(
            "rrt_connect",
            &space(),
            &mut scene.clone(),
            &start,
            &goal,
            seed,
            50,
        );
        assert_valid(&p, &scene, &start, Some(&goal));
        assert_eq!((p.poses.len(), p.iterations), (2, 0), "{:?}", p.poses);
        let wall = aabb([-5.0, -60.0, -60.0], [5.0, 60.0, 60.0]);
        let part = Aabb::new(Vec3::new(-8.0, -4.0, -4.0), Vec3::new(8.0, 4.0, 4.0));
        let mut o = InsertionOptions::default().with_limits(seed, 50);
        o.time_limit_ms = Some(10_000.0);
        // Goal inside the product box: without the direct edge this is a disassembly.
        let inside = at(0.0, 0.0, 0.0);
        let p = plan_insertion(
            &mut scene.clone(),
            &space(),
            &start,
            &inside,
            &part,
            &wall,
            &o,
            None,
        )
        .unwrap();
        assert_valid(&p, &scene, &start, Some(&inside));
        assert_eq!(p.poses.len(), 2, "{}: {:?}", p.planner, p.poses);
    }
}
