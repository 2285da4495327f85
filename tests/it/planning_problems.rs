//! The benchmark planning problems (`tests/common/problems.rs`): the committed
//! documents under `models/problems/` are exactly the generators' output
//! (regenerate with `FITUP_BLESS=1 cargo test --test planning_problems`), and
//! fitup's best planner solves them with paths that are collision-free at a fine
//! resolution, start and end where asked, and repeat for a seed.

use fitup::collision::{interferes, DEFAULT_TOLERANCE};
#[path = "../common/problems.rs"]
pub(super) mod problems;

use fitup::planning::PlannedPath;
use problems::Problem;
use std::path::Path as FsPath;

fn files(p: &Problem) -> Vec<String> {
    let mut f = vec![
        format!("{}.yaml", p.name),
        format!("{}.plan.json", p.name),
        format!("meshes/{}_{}.stl", p.name, p.moving_part),
    ];
    for o in &p.obstacles {
        let s = format!("meshes/{}_{}.stl", p.name, o.part);
        if !f.contains(&s) {
            f.push(s);
        }
    }
    f
}

#[test]
fn committed_problems_match_generators_and_load() {
    let dir = FsPath::new(env!("CARGO_MANIFEST_DIR")).join("models/problems");
    let all = problems::all().unwrap();
    if std::env::var_os("FITUP_BLESS").is_some() {
        for p in &all {
            p.write(&dir).unwrap();
        }
    }
    let fresh = tempfile::tempdir().unwrap();
    for p in &all {
        p.write(fresh.path()).unwrap();
        for f in files(p) {
            let committed =
                std::fs::read(dir.join(&f)).unwrap_or_else(|e| panic!("models/problems/{f}: {e}"));
            let generated = std::fs::read(fresh.path().join(&f)).unwrap();
            assert!(
                committed == generated,
                "models/problems/{f} differs from the generator: run FITUP_BLESS=1 cargo test --test planning_problems"
            );
        }
        let file =
            fitup::planning::ProblemFile::read(&dir.join(format!("{}.plan.json", p.name))).unwrap();
        assert_eq!(file.name, p.name);
        assert!(file.start.approx_eq(&p.start, 1e-9, 1e-9), "{}", p.name);
        assert!(file.goal.approx_eq(&p.goal, 1e-9, 1e-9), "{}", p.name);
        assert_eq!(file.bounds.lo.coords, p.space.min, "{}", p.name);
        assert_eq!(file.bounds.hi.coords, p.space.max, "{}", p.name);
        assert_eq!(file.product_box, Some(p.product_box), "{}", p.name);
        let doc = fitup::document::Document::open(&dir.join(&file.document)).unwrap();
        let mut cache = fitup::workspace::SceneCache::new();
        let ws = fitup::workspace::Workspace::new(&doc, &mut cache).unwrap();
        let at = ws.pose(&file.moving_component).unwrap();
        assert!(at.approx_eq(&p.start, 1e-6, 1e-9), "{}", p.name);
        assert_eq!(doc.components().len(), p.obstacles.len() + 1);
        for i in 0..doc.components().len() {
            assert!(
                doc.mesh_of(i).inspect().is_watertight(),
                "{}: {}",
                p.name,
                doc.components()[i].name
            );
        }
    }
}

/// Every pose of the densified path (0.01 mm, and the rotation moving no point more
/// than 0.01 mm) is free by the exact interference test: an independent re-check
/// of what the planner's (lazy or eager) validation accepted.
fn assert_collision_free(p: &Problem, path: &PlannedPath) {
    let (moving, obstacles) = p.colliders().unwrap();
    let step = 0.01;
    for (k, pose) in path
        .densify(step, step / moving.radius())
        .expect("within the pose cap")
        .iter()
        .enumerate()
    {
        for (o, (c, op)) in obstacles.iter().enumerate() {
            assert!(
                !interferes(&moving, pose, c, op, DEFAULT_TOLERANCE).unwrap(),
                "{}: pose {k} of the densified path hits obstacle {}",
                p.name,
                p.obstacles[o].name
            );
        }
        assert!(
            (0..3).all(|i| {
                let t = pose.translation()[i];
                t >= p.space.min[i] - 1e-9 && t <= p.space.max[i] + 1e-9
            }),
            "{}: pose {k} leaves the bounds",
            p.name
        );
    }
}

fn check_solves(p: &Problem, seed: u64, iterations: usize) {
    // The same seed gives the same path when the iteration limits (and the bounded
    // smoothing), not the clock, end the call: a budget far above what the call
    // needs keeps a loaded test machine from cutting one run's smoothing short.
    let options = fitup::planning::InsertionOptions {
        time_limit_ms: Some(600_000.0),
        ..fitup::planning::InsertionOptions::default().with_limits(seed, iterations)
    };
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let path = p.solve_with(&mut v, &options).unwrap();
    assert!(path.found(), "{}: {:?}", p.name, path.failure);
    let (first, last) = (path.poses[0], *path.poses.last().unwrap());
    assert!(first.approx_eq(&p.start, 1e-9, 1e-9), "{}: start", p.name);
    assert!(last.approx_eq(&p.goal, 1e-9, 1e-9), "{}: goal", p.name);
    assert_collision_free(p, &path);
    let mut again = p.validator(p.default_validator_options()).unwrap();
    let repeat = p.solve_with(&mut again, &options).unwrap();
    assert_eq!(path.poses, repeat.poses, "{}: same seed, same path", p.name);
    assert_eq!(path.collision_checks(), repeat.collision_checks());
}

#[test]
fn peg_in_hole_is_solved_collision_free_and_deterministic() {
    check_solves(&problems::peg_in_hole(0.5).unwrap(), 1, 2000);
}

#[test]
fn piston_rod_cap_is_solved_collision_free_and_deterministic() {
    check_solves(&problems::piston_rod_cap().unwrap(), 1, 2000);
}

#[test]
fn screw_cell_is_solved_collision_free_and_deterministic() {
    check_solves(&problems::screw_cell().unwrap(), 1, 2000);
}

/// Rotation puzzles solved with fitup's default narrow-passage measures
/// (`NarrowPassage::default()`, clearance-scaled lattice turns): the ring comes
/// out of the other ring through its slit, the peg is tilted through the window
/// and stood into its 0.2 mm hole; the paths pass the same dense re-check.
#[test]
fn ring_puzzle_is_solved_collision_free_and_deterministic() {
    check_solves(&problems::ring_puzzle().unwrap(), 0, 2000);
}

#[test]
fn peg_tilt_is_solved_collision_free_and_deterministic() {
    check_solves(&problems::peg_tilt().unwrap(), 0, 2000);
}

/// The ring puzzle is well posed: both ends free, the rings linked (blocked along
/// the other axes), and one way out exists.
#[test]
fn ring_puzzle_is_well_posed() {
    use fitup::planning::MotionValidator;
    let p = problems::ring_puzzle().unwrap();
    let mut v = p.validator(p.default_validator_options()).unwrap();
    assert!(v.is_free(&p.start));
    assert!(v.is_free(&p.goal));
    assert!(!v.edge_free(&p.start, &p.goal));
    let away = |d: [f64; 3]| {
        p.start
            .then(&fitup::math::Transform::from_translation(d.into()))
    };
    for d in [
        [0.0, 0.0, 80.0],
        [0.0, 80.0, 0.0],
        [-80.0, 0.0, 0.0],
        [80.0, 0.0, 0.0],
    ] {
        assert!(!v.edge_free(&p.start, &away(d)), "{d:?}");
    }
    // A witness that it can be solved: the slit faces the fixed wire, so straight
    // down threads the wire through the slit (0.3 mm each side), then across.
    let below = away([0.0, 0.0, -80.0]);
    let beside = away([120.0, 0.0, -80.0]);
    assert!(v.edge_free(&p.start, &below));
    assert!(v.edge_free(&below, &beside));
    assert!(v.edge_free(&beside, &p.goal));
}

/// The rotation puzzles are well posed: both ends free, the straight motion
/// blocked, and (where one is easy to write down) a witness path that is free.
#[test]
fn rotation_puzzles_are_well_posed() {
    use fitup::math::{Point3, Transform, Vec3};
    use fitup::planning::MotionValidator;
    let roll = |t: &Transform| {
        Transform::from_rotation_about(Point3::origin(), Vec3::x(), std::f64::consts::FRAC_PI_2)
            .unwrap()
            .then(t)
    };
    for p in [
        problems::rod_corner().unwrap(),
        problems::bar_slot().unwrap(),
        problems::peg_tilt().unwrap(),
        problems::key_ring().unwrap(),
    ] {
        let mut v = p.validator(p.default_validator_options()).unwrap();
        assert!(v.is_free(&p.start), "{}", p.name);
        assert!(v.is_free(&p.goal), "{}", p.name);
        assert!(!v.edge_free(&p.start, &p.goal), "{}", p.name);
        if p.name == "bar_slot" {
            // Lying flat it cannot pass; rolled 90° it can, and rolls back after.
            let (a, b) = (roll(&p.start), roll(&p.goal));
            assert!(v.edge_free(&p.start, &a));
            assert!(v.edge_free(&a, &b));
            assert!(v.edge_free(&b, &p.goal));
            let flat_at_wall = p
                .start
                .then(&Transform::from_translation(Vec3::new(40.0, 0.0, 0.0)));
            assert!(!v.edge_free(&p.start, &flat_at_wall));
        }
    }
}

/// One time budget for the whole call: a search that cannot finish within it (the
/// key ring, which no planner here solves in seconds) ends with the time limit,
/// and the result reports the call's time as the sum of its search and smoothing.
#[test]
fn a_spent_budget_ends_the_call_with_the_time_limit_reported() {
    use fitup::planning::{Failure, InsertionOptions};
    let p = problems::key_ring().unwrap();
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let mut options = InsertionOptions::default().with_limits(3, usize::MAX / 2);
    options.time_limit_ms = Some(300.0);
    let path = p.solve_with(&mut v, &options).unwrap();
    assert_eq!(path.failure, Some(Failure::TimeLimit), "{}", path.planner);
    assert!(path.time_ms > 0.0 && path.search_ms > 0.0);
    assert!(
        (path.time_ms - path.search_ms - path.smoothing_ms).abs() < 1.0,
        "time {} = search {} + smoothing {}",
        path.time_ms,
        path.search_ms,
        path.smoothing_ms
    );
}
