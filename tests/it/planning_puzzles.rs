//! The standard rigid-body puzzle classes (issue 23; generators in
//! `tests/common/problems.rs`, files under `models/problems/`): each is well posed,
//! the easy ones are planned with a fixed seed, and every returned path is
//! re-checked independently at dense poses with the collision API.

// The generators, loaded once in the binary (by planning_problems).
use super::planning_problems::problems;

use fitup::collision::{interferes, DEFAULT_TOLERANCE};
use fitup::planning::{Failure, InsertionOptions, MotionValidator, PlannedPath};
use problems::Problem;
use std::time::Instant;

/// Every pose of the densified path (0.01 mm; the rotation moving no point more
/// than 0.01 mm) is free by the exact interference test and inside the bounds.
fn assert_collision_free(p: &Problem, path: &PlannedPath) {
    let (moving, obstacles) = p.colliders().unwrap();
    let step = 0.01;
    let dense = path
        .densify(step, step / moving.radius())
        .expect("within the pose cap");
    assert!(dense.len() >= path.poses.len());
    for (k, pose) in dense.iter().enumerate() {
        for (o, (c, op)) in obstacles.iter().enumerate() {
            assert!(
                !interferes(&moving, pose, c, op, DEFAULT_TOLERANCE).unwrap(),
                "{}: pose {k} of the densified path hits {}",
                p.name,
                p.obstacles[o].name
            );
        }
        let t = pose.translation();
        assert!(
            (0..3).all(|i| t[i] >= p.space.min[i] - 1e-9 && t[i] <= p.space.max[i] + 1e-9),
            "{}: pose {k} leaves the bounds",
            p.name
        );
    }
}

/// Both ends free and inside the bounds; the straight line blocked, except for the
/// plate hole, whose point is that it is free.
#[test]
fn puzzles_are_well_posed() {
    for p in problems::puzzles().unwrap() {
        let mut v = p.validator(p.default_validator_options()).unwrap();
        assert!(v.is_free(&p.start), "{}: start", p.name);
        assert!(v.is_free(&p.goal), "{}: goal", p.name);
        for end in [p.start, p.goal] {
            let t = end.translation();
            assert!(
                (0..3).all(|i| t[i] >= p.space.min[i] && t[i] <= p.space.max[i]),
                "{}",
                p.name
            );
        }
        assert_eq!(
            v.edge_free(&p.start, &p.goal),
            p.name == "plate_hole",
            "{}: straight line",
            p.name
        );
    }
}

/// Plans `p` with `seed`, iteration-limited (a budget far above what the call
/// needs, so the clock never decides and the same seed gives the same path),
/// re-checks the path densely, and plans again: same poses, same checks.
fn check_solves(p: &Problem, seed: u64, iterations: usize) -> PlannedPath {
    let options = InsertionOptions {
        time_limit_ms: Some(600_000.0),
        ..InsertionOptions::default().with_limits(seed, iterations)
    };
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let path = p.solve_with(&mut v, &options).unwrap();
    assert!(path.found(), "{}: {:?}", p.name, path.failure);
    assert!(
        path.poses[0].approx_eq(&p.start, 1e-9, 1e-9),
        "{}: start",
        p.name
    );
    assert!(
        path.poses.last().unwrap().approx_eq(&p.goal, 1e-9, 1e-9),
        "{}: goal",
        p.name
    );
    assert_collision_free(p, &path);
    let mut again = p.validator(p.default_validator_options()).unwrap();
    let repeat = p.solve_with(&mut again, &options).unwrap();
    assert_eq!(path.poses, repeat.poses, "{}: same seed, same path", p.name);
    assert_eq!(path.collision_checks(), repeat.collision_checks());
    path
}

/// The free straight line through the 0.2 mm hole is the path, found with a
/// handful of checks (no search).
#[test]
fn plate_hole_is_the_straight_line() {
    let p = problems::plate_hole().unwrap();
    let path = check_solves(&p, 1, 2000);
    assert_eq!(path.poses.len(), 2);
    assert!(path.collision_checks() < 10, "{}", path.collision_checks());
}

/// The L-shaped body is rolled through both doors of the house and yawed between
/// them; the path is collision-free at dense poses and repeats for its seed.
#[test]
fn house_is_solved_collision_free_and_deterministic() {
    let p = problems::house().unwrap();
    let path = check_solves(&p, 1, 40_000);
    // It cannot pass a door lying flat: somewhere the body is rolled.
    assert!(path.rotation_rad > 0.5, "{}", path.rotation_rad);
}

/// The twisted loop is screwed off the helix: the long coordinated motion, densely
/// re-checked, same path for the same seed.
#[test]
fn twisted_tubes_are_solved_collision_free_and_deterministic() {
    let p = problems::twisted_tubes().unwrap();
    let path = check_solves(&p, 1, 40_000);
    assert!(path.rotation_rad > 1.0, "{}", path.rotation_rad);
}

/// The slot roll: the bar is rolled 90° (the axis-move search's quarter turn
/// about its own long axis), slid through the slot 0.3 mm wider than itself and
/// rolled back; densely re-checked, same path for the same seed, every seed of 5.
#[test]
fn bar_slot_is_solved_collision_free_and_deterministic() {
    let p = problems::bar_slot().unwrap();
    for seed in 1..6 {
        let path = check_solves(&p, seed, 20_000);
        // Lying flat it cannot pass: somewhere it is rolled.
        assert!(path.rotation_rad > 1.5, "{}", path.rotation_rad);
    }
}

/// The twisted slot: the plate is slid into the first chamber, rolled 45°, slid
/// into the second, rolled 45° more and slid out; densely re-checked, same path
/// for the same seed, every seed of 5.
#[test]
fn twisted_slot_is_solved_collision_free_and_deterministic() {
    let p = problems::twisted_slot().unwrap();
    for seed in 1..6 {
        let path = check_solves(&p, seed, 20_000);
        assert!(path.rotation_rad > 0.7, "{}", path.rotation_rad);
    }
}

/// The corridor classes: the 12 mm rod turns the 7 mm corridor's corner, and the
/// four bends of the zigzag tunnel, turning about Z while it moves; densely
/// re-checked, same path for the same seed, every seed of 5. With fitup's
/// defaults (3 mm steps, 15° turn-limited retries) the tunnel's seeds here take
/// 6k–56k iterations; the cap leaves room without letting a regression pass
/// unnoticed (at the 10 mm steps of before, no seed was solved in 500k).
#[test]
fn rod_corridor_and_zigzag_tunnel_are_solved_collision_free_and_deterministic() {
    for p in [
        problems::rod_corridor().unwrap(),
        problems::zigzag_tunnel().unwrap(),
    ] {
        for seed in 1..6 {
            let path = check_solves(&p, seed, 200_000);
            assert!(path.rotation_rad > 1.5, "{}: {}", p.name, path.rotation_rad);
        }
    }
}

/// How long (ms) this thread has waited runnable for a CPU since it started
/// (`/proc/thread-self/schedstat`, Linux; 0 elsewhere). On a loaded machine a
/// planner preempted past its deadline overruns it in wall time through no
/// work of its own: the budget checks below leave out that wait, measured, and
/// keep the 5 % bound on what the planner did (unchanged on an idle machine).
fn run_delay_ms() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-6)
}

/// A search that cannot finish (the twisted slot in half a second without the
/// axis moves, which solve it) ends with the time limit, within 5 % of its
/// budget by its own clock, and well within a generous bound by the caller's.
#[test]
fn a_spent_budget_is_not_overrun() {
    let p = problems::twisted_slot().unwrap();
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let budget = 500.0;
    let mut options = InsertionOptions::default().with_limits(2, usize::MAX / 2);
    options.time_limit_ms = Some(budget);
    options.approach.narrow.axis_moves = 0.0;
    options.disassembly.rrt_mut().narrow.axis_moves = 0.0;
    let clock = Instant::now();
    let waited = run_delay_ms();
    let path = p.solve_with(&mut v, &options).unwrap();
    let waited = run_delay_ms() - waited;
    let wall = clock.elapsed().as_secs_f64() * 1e3;
    assert_eq!(path.failure, Some(Failure::TimeLimit));
    assert!(
        path.time_ms - waited <= 1.05 * budget,
        "{} ms ({waited} ms waiting for a CPU)",
        path.time_ms
    );
    assert!(wall <= 2.0 * budget, "{wall} ms");
}

/// Smoothing takes at most its share of the budget however many shortcuts it is
/// allowed, keeps a valid path, and with no share left the path comes back as the
/// search found it.
#[test]
fn smoothing_stays_within_its_share_and_the_raw_path_is_returned_without_it() {
    let p = problems::house().unwrap();
    // Seed 0: the house's search takes ≈ 0.1 s of the budget there (seed 1 takes
    // ≈ 1.6 s on a loaded machine, leaving smoothing no share to prove itself on).
    let budget = 3000.0;
    let mut options = InsertionOptions::default().with_limits(0, 40_000);
    options.time_limit_ms = Some(budget);
    options.smoothing.shortcut_attempts = usize::MAX;
    options.smoothing.patience = usize::MAX;
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let waited = run_delay_ms();
    let path = p.solve_with(&mut v, &options).unwrap();
    let waited = run_delay_ms() - waited;
    assert!(path.found(), "{:?}", path.failure);
    let share = options.smoothing.budget_share * budget;
    assert!(
        path.smoothing_ms - waited <= 1.05 * share,
        "{} > {share} ({waited} ms waiting for a CPU)",
        path.smoothing_ms
    );
    assert!(
        path.smoothing_ms > 0.5 * share.min(budget - path.search_ms),
        "{}",
        path.smoothing_ms
    );
    assert!(path.time_ms - waited <= 1.05 * budget, "{}", path.time_ms);
    // The heavily shortcut path is re-checked in
    // `a_heavily_smoothed_path_passes_the_dense_recheck`.

    options.smoothing.budget_share = 0.0;
    let mut v = p.validator(p.default_validator_options()).unwrap();
    let raw = p.solve_with(&mut v, &options).unwrap();
    assert!(raw.found());
    assert_eq!(raw.length_mm, raw.raw_length_mm);
    assert!(raw.smoothing_ms < 5.0, "{}", raw.smoothing_ms);
    assert_collision_free(&p, &raw);
}

/// With unlimited shortcut attempts, every edge of the smoothed house path passes
/// the dense re-check (issue 23 work, 2026-12-02: seed 1 had a shortcut whose
/// corner crossed `bc_west` deeper than the tolerance between two contact steps
/// of the continuous edge check; the edge is a unit test in `collision::edge`).
#[test]
fn a_heavily_smoothed_path_passes_the_dense_recheck() {
    let p = problems::house().unwrap();
    for seed in 1..6 {
        // Iterations include the axis-move search's (issue 23, slots); seed 1
        // takes ≈ 43k of them in the race of the scale-free defaults.
        let mut options = InsertionOptions::default().with_limits(seed, 200_000);
        options.time_limit_ms = Some(8000.0);
        options.smoothing.shortcut_attempts = usize::MAX;
        options.smoothing.patience = usize::MAX;
        let mut v = p.validator(p.default_validator_options()).unwrap();
        let path = p.solve_with(&mut v, &options).unwrap();
        assert!(
            path.found(),
            "seed {seed}: {:?} after {} iterations, {:.0} ms",
            path.failure,
            path.iterations,
            path.time_ms
        );
        assert_collision_free(&p, &path);
    }
}
