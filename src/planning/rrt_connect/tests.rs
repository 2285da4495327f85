use super::*;
use crate::collision::Collider;
use crate::math::{Point3, Vec3};
use crate::mesh::Mesh;
use crate::planning::{MeshValidator, MeshValidatorOptions};
use std::sync::Arc;

/// A wall 2k thick at x = 0 with a square window of half width 8k, and a cube
/// of side 10k that must pass it from y = 20k on one side to y = 20k on the
/// other (the straight line hits the wall), in bounds 80k × 80k × 40k; all
/// lengths times `k`.
fn window(k: f64) -> (MeshValidator, PlanningSpace, Transform, Transform) {
    let collider = |lo: [f64; 3], hi: [f64; 3]| {
        let m = Mesh::cuboid(
            Point3::new(lo[0] * k, lo[1] * k, lo[2] * k),
            Point3::new(hi[0] * k, hi[1] * k, hi[2] * k),
        );
        Arc::new(Collider::new(Arc::new(m)).unwrap())
    };
    let wall = [
        ([-1.0, -40.0, 8.0], [1.0, 40.0, 20.0]),
        ([-1.0, -40.0, -20.0], [1.0, 40.0, -8.0]),
        ([-1.0, 8.0, -8.0], [1.0, 40.0, 8.0]),
        ([-1.0, -40.0, -8.0], [1.0, -8.0, 8.0]),
    ];
    let obstacles = wall
        .iter()
        .map(|(lo, hi)| (collider(*lo, *hi), Transform::IDENTITY))
        .collect();
    let cube = collider([-5.0; 3], [5.0; 3]);
    let radius = cube.radius();
    let v = MeshValidator::new(cube, obstacles, MeshValidatorOptions::default()).unwrap();
    let space = PlanningSpace::new(
        Vec3::new(-40.0, -40.0, -20.0) * k,
        Vec3::new(40.0, 40.0, 20.0) * k,
    )
    .with_rotation_weight(radius);
    let at = |x: f64| Transform::from_translation(Vec3::new(x * k, 20.0 * k, 0.0));
    (v, space, at(-30.0), at(30.0))
}

/// The mesh validator without [`MotionValidator::fork`]: its race runs
/// interleaved on one thread.
struct OneThread(MeshValidator);

impl MotionValidator for OneThread {
    fn is_free(&mut self, pose: &Transform) -> bool {
        self.0.is_free(pose)
    }
    fn resolution(&self) -> crate::collision::SweepMethod {
        self.0.resolution()
    }
    fn tolerance(&self) -> f64 {
        self.0.tolerance()
    }
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        self.0.edge_free(from, to)
    }
    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        self.0.clearance(pose)
    }
    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.0.set_deadline(deadline)
    }
    fn part_radius(&self) -> Option<f64> {
        self.0.part_radius()
    }
    fn part_thickness(&self) -> Option<f64> {
        self.0.part_thickness()
    }
}

fn options(seed: u64) -> RrtConnectOptions {
    let mut o = RrtConnectOptions::default();
    o.limits.seed = seed;
    o.limits.max_iterations = 200_000;
    o.limits.time_limit_ms = Some(120_000.0);
    o.smoothing = Smoothing::OFF;
    o
}

#[test]
fn the_race_finds_the_same_path_on_two_threads_and_on_one() {
    for seed in 0..4 {
        let (mut v, space, start, goal) = window(1.0);
        let o = options(seed);
        let two = rrt_connect(&mut v, &space, &start, &goal, &o, None).unwrap();
        assert!(two.found(), "seed {seed}: {:?}", two.failure);
        let (v, ..) = window(1.0);
        let one = rrt_connect(&mut OneThread(v), &space, &start, &goal, &o, None).unwrap();
        assert_eq!(one.poses, two.poses, "seed {seed}");
        assert_eq!(
            (one.iterations, one.nodes, one.pose_checks, one.edge_checks),
            (two.iterations, two.nodes, two.pose_checks, two.edge_checks),
            "seed {seed}"
        );
        let (mut v, ..) = window(1.0);
        let again = rrt_connect(&mut v, &space, &start, &goal, &o, None).unwrap();
        assert_eq!(again.poses, two.poses, "seed {seed}: same seed, same path");
    }
}

/// Free space a ball of radius 12 about the origin: every extension of 40
/// from the centre leaves it, one of 10 stays inside.
struct Ball;

impl MotionValidator for Ball {
    fn is_free(&mut self, pose: &Transform) -> bool {
        pose.translation().norm() <= 12.0
    }
}

/// The long-range search's adaptive reach: blocked extensions halve a node's
/// reach down to the floor, where the search grows again; without it (the
/// narrow search's fixed step) the tree never leaves its root.
#[test]
fn a_blocked_node_shrinks_its_reach_down_to_the_floor_and_grows_again() {
    let space = PlanningSpace::new(
        Vec3::new(-100.0, -100.0, -100.0),
        Vec3::new(100.0, 100.0, 100.0),
    )
    .with_rotation_weight(1.0);
    let o = RrtConnectOptions::default();
    let strategy = |floor: Option<f64>| Strategy {
        reach_floor: floor,
        lazy: Some((1.0, 1.0)),
        narrow: NarrowPassage::OFF,
        lattice: None,
        fallback_share: 0.0,
        ..Strategy::explicit(&o, &space, 40.0)
    };
    let start = Transform::IDENTITY;
    let goal = Transform::from_translation(Vec3::new(90.0, 0.0, 0.0));
    let grown = |floor: Option<f64>| {
        let mut v = Ball;
        let checker = Checker::new(&mut v, None);
        let mut search = Search::new(checker, &space, &start, &goal, strategy(floor), 7);
        let mut lowest = f64::INFINITY;
        for _ in 0..400 {
            search.iterate();
            lowest = lowest.min(search.trees[0].reach(0));
        }
        let tree = &search.trees[0];
        let inside = (0..tree.len()).all(|i| tree.poses[i].translation().norm() <= 12.0);
        (tree.len(), lowest, inside)
    };
    let (nodes, lowest, inside) = grown(Some(10.0));
    // Nodes near the ball's surface block at the floor too, and a uniform
    // sample of the large space is nearest to one of them: a few nodes.
    assert!(nodes >= 3, "the tree grows at the floor: {nodes} nodes");
    assert!(inside, "every node is free");
    assert_eq!(lowest, 10.0, "the root's reach halved from 40 to the floor");
    let (fixed, ..) = grown(None);
    assert_eq!(fixed, 1, "with a fixed reach of 40 nothing is added");
}

/// Scale-free defaults: every length of both searches follows the problem, so
/// the same problem 10× larger gets the same strategies with every length 10×.
#[test]
fn the_strategies_scale_with_the_problem() {
    let o = RrtConnectOptions::default();
    let at = |k: f64| {
        let (v, space, ..) = window(k);
        let scale = ProblemScale::of(&space, &v);
        (
            Strategy::long_range(&o, &space, &scale),
            Strategy::narrow(&o, &space, &scale),
        )
    };
    let close = |a: f64, b: f64| (a * 10.0 - b).abs() <= 1e-9 * b.abs().max(1.0);
    let ((l1, n1), (l10, n10)) = (at(1.0), at(10.0));
    for (a, b) in [(&l1, &l10), (&n1, &n10)] {
        assert!(close(a.step, b.step), "step {} → {}", a.step, b.step);
        assert!(close(a.key_mm, b.key_mm));
        assert!(close(a.rotation_weight, b.rotation_weight));
        let (la, lb) = (a.lazy.unwrap(), b.lazy.unwrap());
        assert!(
            close(la.0, lb.0) && (la.1 - lb.1).abs() < 1e-12,
            "{la:?} → {lb:?}"
        );
    }
    let (la, lb) = (n1.lattice.unwrap(), n10.lattice.unwrap());
    assert!(close(la.edge_length_max, lb.edge_length_max));
    assert!(close(la.edge_length_min, lb.edge_length_min));
    assert_eq!(la.alpha, lb.alpha, "angles do not scale");
    assert!(close(n1.unit, n10.unit));
    assert!(close(n1.narrow.bridge_width, n10.narrow.bridge_width));
    assert!(close(
        n1.narrow.dynamic_domain.unwrap(),
        n10.narrow.dynamic_domain.unwrap()
    ));
    assert!(l1.lattice.is_none() && l1.narrow == NarrowPassage::OFF);
}

/// The same defaults solve the window at a tenth, at one and at ten times its
/// size, and every path they return is free pose by pose and edge by edge.
/// (Not the identical path: the validator's contact resolution, 0.01 mm, is a
/// physical length, and the narrow search moves to contact.)
#[test]
fn the_defaults_solve_the_problem_at_every_scale() {
    for k in [0.1, 1.0, 10.0] {
        for seed in 0..3 {
            let (mut v, space, start, goal) = window(k);
            let p = rrt_connect(&mut v, &space, &start, &goal, &options(seed), None).unwrap();
            assert!(p.found(), "k {k} seed {seed}: {:?}", p.failure);
            assert!(p.poses.iter().all(|q| v.is_free(q)), "k {k} seed {seed}");
            assert!(
                p.poses.windows(2).all(|w| v.edge_free(&w[0], &w[1])),
                "k {k} seed {seed}"
            );
        }
    }
}

/// The goal tree's edges are certified from parent to child and run backwards
/// in the path: the validator's verdict must not depend on the direction. This
/// edge of the window scene (k = 1, seed 2, the second long-range search's
/// path) grazes the window's frame: swept from its first pose it was refused,
/// from its second accepted, and the path failed its own edge check.
#[test]
fn an_edge_has_the_same_verdict_both_ways() {
    let (mut v, ..) = window(1.0);
    let pose = |m: [[f64; 4]; 4]| Transform::from_matrix(&m).unwrap();
    let a = pose([
        [
            0.9885727391935328,
            -0.12498714508365366,
            0.0842742717988983,
            0.0,
        ],
        [
            -0.06556757308729438,
            0.1468835829871868,
            0.9869782704843557,
            0.0,
        ],
        [
            -0.13573810328289984,
            -0.9812254718527671,
            0.137010002205959,
            0.0,
        ],
        [
            -2.669005523283383,
            -1.3046986378261967,
            -0.9715228055244611,
            1.0,
        ],
    ]);
    let b = pose([
        [
            0.9509198006394701,
            0.10909576000420058,
            0.2895680367390304,
            0.0,
        ],
        [
            -0.3083368368000792,
            0.2552090752573958,
            0.9164042355742286,
            0.0,
        ],
        [
            0.026075425670771396,
            -0.9607114254839331,
            0.276321604513142,
            0.0,
        ],
        [
            11.305915399783231,
            -2.0120772362623,
            -1.396330613993733,
            1.0,
        ],
    ]);
    assert!(v.is_free(&a) && v.is_free(&b));
    assert_eq!(v.edge_free(&a, &b), v.edge_free(&b, &a));
    // And on random short edges between free poses about the window's frame.
    let mut rng = Rng::new(7);
    let mut u = |h: f64| (2.0 * rng.uniform() - 1.0) * h;
    let (mut near_contact, mut tried) = (0, 0);
    for _ in 0..3000 {
        // From one side of the wall to the other, through or past the window.
        let p = Transform::from_translation(Vec3::new(-9.0 + u(3.0), u(5.0), u(5.0)));
        let q = Transform::from_translation(Vec3::new(9.0 + u(3.0), u(5.0), u(5.0)));
        let turn = Transform::from_rotation_about(
            Point3::from(q.translation()),
            Vec3::new(u(1.0), u(1.0), u(1.0)).normalize(),
            u(0.6),
        )
        .unwrap();
        let q = q.then(&turn);
        if v.is_free(&p) && v.is_free(&q) {
            tried += 1;
            let there = v.edge_free(&p, &q);
            near_contact += usize::from(!there);
            assert_eq!(there, v.edge_free(&q, &p), "{p:?} -> {q:?}");
        }
    }
    assert!(
        tried > 200 && near_contact > 10,
        "{near_contact} blocked of {tried} edges: the sample misses the frame"
    );
}
