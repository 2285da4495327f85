//! Planning benchmark: fitup's best planner (`plan_insertion`) on the benchmark
//! problems (`tests/common/problems.rs`) against OMPL's RRTConnect (FCL collision,
//! `tests/bench/ompl_peer.py`) and OMPL 1.5 C++ RRTConnect and KPIECE1
//! (`tests/bench/ompl/harness.cpp`, compiled here when `libompl-dev` and
//! `libfcl-dev` are installed, skipped with a message otherwise) in the same run, and seed 002's protocol (100 runs ×
//! 100 iterations: rrt, biased_rrt, local_rrt on the piston-rod cap).
//!
//! `cargo bench --bench planning`. The peer runs when `FITUP_PY` (default
//! `.venv/bin/python`) exists. Environment: `FITUP_RUNS` (fitup runs per problem,
//! 10), `FITUP_OMPL_RUNS` (5), `FITUP_OMPL_LIMIT_S` (10), `FITUP_OMPL_RRT=1` (also
//! OMPL's plain RRT), `FITUP_STEPWISE=1` (also fitup with stepwise edges),
//! `FITUP_PROBLEM=name[,name…]` (only problems whose name contains one of them),
//! `FITUP_PROTOCOL=0` (skip seed 002's protocol), `FITUP_VALIDATOR=0` (skip the
//! validator profile: pose and edge checks per problem), `FITUP_VARIANTS=1` (also
//! fitup's exploration variants side by side: eager, lazy, random moves;
//! `FITUP_VARIANTS=narrow`: the narrow-passage variants instead, `FITUP_VARIANTS=step`:
//! the extension-step variants, `FITUP_VARIANT=a,b`
//! only those named), `FITUP_BUDGET_MS` (fitup's budget per call,
//! default 10000), `FITUP_DEFAULT=0` (skip the default rows: variants and peers only),
//! `FITUP_SMOOTHED=0` (skip the smoothed row), `FITUP_VARIANTS=share` (the
//! fallback-share variants), `FITUP_SOLVER=rrt_connect` (fitup runs `rrt_connect`
//! alone, what `plan_path` does without `disassemble`, instead of
//! `plan_insertion`), `FITUP_ITERATIONS` (iteration cap, default
//! `PlanLimits::default()`'s: the time budget ends a search, as OMPL's),
//! `FITUP_PROBE_MS` (also a row per problem at this short budget with smoothing
//! on, and the largest overrun of each call's budget, setup included, in %),
//! `FITUP_SCALE=k` (every problem scaled by k: meshes, poses, bounds and the
//! rotation weight).

#[path = "../common/problems.rs"]
mod problems;

use fitup::planning::{
    disassemble, DisassemblyPlanner, InsertionOptions, LocalRrtOptions, MeshValidatorOptions,
    PlanLimits, RrtOptions, Smoothing,
};
use problems::Problem;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Stepwise resolution shared by fitup and the peer (mm of the SE(3) metric).
const RESOLUTION_MM: f64 = 0.05;

fn median(xs: &mut [f64]) -> Option<f64> {
    if xs.is_empty() {
        return None;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    Some(if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    })
}

/// Writes the peer's input: the moving mesh (part frame), the obstacles in world
/// coordinates and problem.json.
fn export(p: &Problem, dir: &Path) -> PathBuf {
    let mut spec = p.plan_json();
    fitup::mesh::write_stl(&dir.join("moving.stl"), &p.moving).unwrap();
    let mut stls = Vec::new();
    for (k, o) in p.obstacles.iter().enumerate() {
        let name = format!("obstacle{k}.stl");
        fitup::mesh::write_stl(&dir.join(&name), &o.mesh.transformed(&o.pose)).unwrap();
        stls.push(name);
    }
    spec["moving_stl"] = "moving.stl".into();
    spec["obstacle_stls"] = stls.into();
    spec["resolution_mm"] = RESOLUTION_MM.into();
    // FCL reports touching as collision: lift the resting ends off their supports.
    spec["peer_lift_mm"] = 0.05.into();
    // the C++ harness's plain-text spec (tests/bench/ompl/harness.cpp)
    let pose = |t: &fitup::math::Transform| {
        let q = t.rotation();
        let v = t.translation();
        format!("{} {} {} {} {} {} {}", v.x, v.y, v.z, q.w, q.i, q.j, q.k)
    };
    let mut txt = String::from("moving moving.stl\n");
    for (k, _) in p.obstacles.iter().enumerate() {
        txt += &format!("obstacle obstacle{k}.stl\n");
    }
    let (lo, hi) = (p.space.min, p.space.max);
    txt += &format!(
        "bounds {} {} {} {} {} {}\nstart {}\ngoal {}\nrotation_weight {}\nresolution_mm {RESOLUTION_MM}\nlift_mm 0.05\n",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, pose(&p.start), pose(&p.goal), p.space.rotation_weight
    );
    std::fs::write(dir.join("problem.txt"), txt).unwrap();
    let path = dir.join("problem.json");
    std::fs::write(&path, serde_json::to_string_pretty(&spec).unwrap()).unwrap();
    path
}

struct Row {
    solved: usize,
    runs: usize,
    median_s: Option<f64>,
    /// fitup only: the largest overrun of the budget over these runs, in % of the
    /// budget, measured by the caller's clock around setup (the validator's
    /// colliders) and the call together (negative: every run ended within it).
    overrun_pct: f64,
    /// fitup only: the largest `smoothing_ms` less smoothing's share of the
    /// budget, ms (negative: within its share).
    smoothing_over_ms: f64,
}

/// fitup's time budget per call in the benchmark (ms): the default one, or
/// `FITUP_BUDGET_MS`.
fn budget_ms() -> f64 {
    env_or("FITUP_BUDGET_MS", fitup::planning::DEFAULT_TIME_LIMIT_MS)
}

/// The largest overrun of the time budget seen in this run (ms of wall time past
/// the budget, measured around each call), printed at the end.
static WORST_OVERRUN_MS: std::sync::Mutex<f64> = std::sync::Mutex::new(f64::NEG_INFINITY);

/// `FITUP_SOLVER=rrt_connect`: fitup runs `rrt_connect` alone instead of
/// `plan_insertion`.
fn rrt_connect_alone() -> bool {
    std::env::var("FITUP_SOLVER").is_ok_and(|s| s == "rrt_connect")
}

/// fitup's best planner on `p` for `runs` seeds; `smoothing` adds the shortcut
/// pass (OMPL's `solve` does not simplify either); `variant` adjusts the options.
fn fitup_runs(
    p: &Problem,
    options: MeshValidatorOptions,
    runs: usize,
    smoothing: bool,
    variant: &dyn Fn(&mut InsertionOptions),
) -> Row {
    fitup_runs_within(p, options, runs, smoothing, variant, budget_ms())
}

/// [`fitup_runs`] with a budget of `budget` ms per call.
fn fitup_runs_within(
    p: &Problem,
    options: MeshValidatorOptions,
    runs: usize,
    smoothing: bool,
    variant: &dyn Fn(&mut InsertionOptions),
    budget: f64,
) -> Row {
    let mut times = Vec::new();
    let (mut overrun_pct, mut smoothing_over_ms) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let first: u64 = env_or("FITUP_FIRST_SEED", 0);
    for seed in first..first + runs as u64 {
        // Setup (the colliders) counts against the budget in the overrun figure.
        let setup = Instant::now();
        let mut v = p.validator(options).unwrap();
        let setup_ms = setup.elapsed().as_secs_f64() * 1e3;
        let mut plan = InsertionOptions::default().with_limits(
            seed,
            env_or("FITUP_ITERATIONS", PlanLimits::default().max_iterations),
        );
        plan.time_limit_ms = Some(budget);
        if !smoothing {
            plan.smoothing = Smoothing::OFF;
        }
        variant(&mut plan);
        let t0 = Instant::now();
        let path = if rrt_connect_alone() {
            // What `plan_path` runs by default: `rrt_connect` from start to goal,
            // no disassembly.
            let mut o = plan.approach.clone();
            o.limits.time_limit_ms = plan.time_limit_ms;
            o.smoothing = plan.smoothing;
            fitup::planning::rrt_connect(&mut v, &p.space, &p.start, &p.goal, &o, None).unwrap()
        } else {
            p.solve_with(&mut v, &plan).unwrap()
        };
        let dt = t0.elapsed().as_secs_f64();
        let over_ms = setup_ms + dt * 1e3 - budget;
        let mut worst = WORST_OVERRUN_MS.lock().unwrap();
        *worst = worst.max(over_ms);
        overrun_pct = overrun_pct.max(100.0 * over_ms / budget);
        if plan.smoothing.enabled {
            smoothing_over_ms =
                smoothing_over_ms.max(path.smoothing_ms - plan.smoothing.budget_share * budget);
        }
        if path.found() {
            times.push(dt);
        }
        if std::env::var_os("FITUP_VERBOSE").is_some() {
            eprintln!(
                "  {} seed {seed} budget {budget} ms: {:.3} s (setup {setup_ms:.1} ms, search {:.0} ms, smoothing {:.0} ms) {} {:?} iterations {} nodes {} pose checks {} edge checks {}",
                p.name,
                dt,
                path.search_ms,
                path.smoothing_ms,
                path.planner,
                path.failure,
                path.iterations,
                path.nodes,
                path.pose_checks,
                path.edge_checks
            );
        }
    }
    Row {
        solved: times.len(),
        runs,
        median_s: median(&mut times),
        overrun_pct,
        smoothing_over_ms,
    }
}

/// A change to fitup's default options.
type Variant = Box<dyn Fn(&mut InsertionOptions)>;

/// The narrow-passage variants compared by `FITUP_VARIANTS=narrow`: each measure
/// of [`NarrowPassage`] alone and combined, in both searches of `plan_insertion`,
/// with and without the lattice's clearance-scaled turns (fitup's default is
/// "all four + fine turns").
fn narrow_variants() -> Vec<(&'static str, Variant)> {
    use fitup::planning::NarrowPassage;
    let off = NarrowPassage::OFF;
    let turn = NarrowPassage {
        max_turn: Some(5f64.to_radians()),
        ..off
    };
    // The measure set `n` in both searches, the lattice's clearance-scaled turns
    // on or off.
    let fine = move |n: NarrowPassage, on: bool| -> Variant {
        Box::new(move |o: &mut InsertionOptions| {
            o.approach.narrow = n;
            o.disassembly.rrt_mut().narrow = n;
            if let Some(l) = o.approach.lattice.as_mut() {
                l.clearance_turns = on;
            }
            if let DisassemblyPlanner::LocalRrt(d) = &mut o.disassembly {
                d.lattice.clearance_turns = on;
            }
        })
    };
    let set = move |n: NarrowPassage| fine(n, false);
    let mut out: Vec<(&'static str, Variant)> = vec![
        ("narrow off", set(off)),
        ("max_turn 5°", set(turn)),
        (
            "max_turn 10°",
            set(NarrowPassage {
                max_turn: Some(10f64.to_radians()),
                ..off
            }),
        ),
        (
            "dynamic domain 10 mm",
            set(NarrowPassage {
                dynamic_domain: Some(10.0),
                ..off
            }),
        ),
        ("bridge 0.1", set(NarrowPassage { bridge: 0.1, ..off })),
        (
            "to contact",
            set(NarrowPassage {
                to_contact: true,
                ..off
            }),
        ),
        (
            "turn + contact",
            set(NarrowPassage {
                to_contact: true,
                ..turn
            }),
        ),
        (
            "turn + domain",
            set(NarrowPassage {
                dynamic_domain: Some(10.0),
                ..turn
            }),
        ),
        (
            "all four",
            set(NarrowPassage {
                dynamic_domain: Some(10.0),
                bridge: 0.1,
                to_contact: true,
                ..turn
            }),
        ),
    ];
    let all = NarrowPassage {
        dynamic_domain: Some(10.0),
        bridge: 0.1,
        to_contact: true,
        ..turn
    };
    out.push(("off + fine turns", fine(off, true)));
    out.push(("all four + fine turns", fine(all, true)));
    out.push(("all four, coarse turns", fine(all, false)));
    out.push((
        "turn + contact + fine turns",
        fine(
            NarrowPassage {
                to_contact: true,
                ..turn
            },
            true,
        ),
    ));
    if let Ok(only) = std::env::var("FITUP_VARIANT") {
        let names: Vec<&str> = only.split(',').collect();
        out.retain(|(name, _)| names.contains(name));
    }
    out
}

/// The exploration variants compared by `FITUP_VARIANTS=1` (issue 12): eager
/// validation (every edge checked continuously when added), lazy validation of the
/// join only, lazy everywhere, and lazy with random coordinated moves in the
/// local discretization.
fn variants() -> Vec<(&'static str, Variant)> {
    vec![
        ("eager", lazy_variant(false, false, None)),
        ("lazy join", lazy_variant(true, false, None)),
        ("lazy both", lazy_variant(true, true, None)),
        ("lazy + 8 random moves", lazy_variant(true, true, Some(8))),
    ]
}

/// Lazy validation of the join (`join`) and of the disassembly search (`disassembly`),
/// else eager; with `moves`, that many random coordinated moves in both lattices.
fn lazy_variant(join: bool, disassembly: bool, moves: Option<usize>) -> Variant {
    use fitup::planning::LazyValidation;
    let lazy = |on: bool| on.then(LazyValidation::default);
    Box::new(move |o: &mut InsertionOptions| {
        o.approach.lazy = lazy(join);
        o.disassembly.rrt_mut().lazy = lazy(disassembly);
        if let Some(moves) = moves {
            if let Some(l) = o.approach.lattice.as_mut() {
                l.random_moves = moves;
            }
            if let DisassemblyPlanner::LocalRrt(d) = &mut o.disassembly {
                d.lattice.random_moves = moves;
            }
        }
    })
}

/// The fallback-share variants compared by `FITUP_VARIANTS=share` (issue 12): how
/// much of the work the lattice and the narrow-passage measures may take in both
/// searches (1: every blocked extension falls back, fitup before 2026-12; 0.1:
/// fitup's default), and plain RRT-Connect (no lattice, no measures) for the
/// approach.
fn share_variants() -> Vec<(&'static str, Variant)> {
    use fitup::planning::NarrowPassage;
    let share = |f: f64| -> Variant {
        Box::new(move |o: &mut InsertionOptions| {
            o.approach.fallback_share = f;
            o.disassembly.rrt_mut().fallback_share = f;
        })
    };
    vec![
        ("fallback share 1", share(1.0)),
        ("fallback share 0.3", share(0.3)),
        ("fallback share 0.1", share(0.1)),
        ("fallback share 0.05", share(0.05)),
        (
            "plain approach",
            Box::new(|o: &mut InsertionOptions| {
                o.approach.lattice = None;
                o.approach.narrow = NarrowPassage::OFF;
            }),
        ),
    ]
}

/// The extension-step variants compared by `FITUP_VARIANTS=step` (issue 23,
/// round 4): fitup's defaults before 2026-12-02 (a 10 mm step, a 5° turn-limited
/// retry) and the steps and turns between them and today's (3 mm, 15°), in both
/// searches of `plan_insertion` (the approach's step; the disassembly's own RRT
/// step is left alone). `FITUP_VARIANT=a,b` keeps only those named.
fn step_variants() -> Vec<(&'static str, Variant)> {
    let set = |step: f64, turn_deg: f64| -> Variant {
        Box::new(move |o: &mut InsertionOptions| {
            o.approach.step = Some(step);
            o.approach.narrow.max_turn = Some(turn_deg.to_radians());
            o.disassembly.rrt_mut().narrow.max_turn = Some(turn_deg.to_radians());
        })
    };
    let mut out: Vec<(&'static str, Variant)> = vec![
        ("step 10 / 5° (before)", set(10.0, 5.0)),
        ("step 10 / 15°", set(10.0, 15.0)),
        ("step 5 / 5°", set(5.0, 5.0)),
        ("step 5 / 15°", set(5.0, 15.0)),
        ("step 3 / 5°", set(3.0, 5.0)),
        ("step 3 / 15° (default)", set(3.0, 15.0)),
        ("step 30 / 15°", set(30.0, 15.0)),
    ];
    if let Ok(only) = std::env::var("FITUP_VARIANT") {
        let names: Vec<&str> = only.split(',').collect();
        out.retain(|(name, _)| names.contains(name));
    }
    out
}

/// `p` scaled by `k` about the assembly origin: meshes, pose translations, the
/// bounds, the product box and the rotation weight (so the metric scales too).
fn scaled(p: &Problem, k: f64) -> Problem {
    use fitup::math::Transform;
    use fitup::mesh::Mesh;
    let mesh = |m: &Mesh| {
        Mesh::new(
            m.vertices.iter().map(|v| (v.coords * k).into()).collect(),
            m.triangles.clone(),
        )
        .expect("a scaled valid mesh is valid")
    };
    let pose = |t: &Transform| Transform::from_parts(t.translation() * k, t.rotation());
    let mut q = p.clone();
    q.moving = std::sync::Arc::new(mesh(&p.moving));
    for o in &mut q.obstacles {
        o.mesh = std::sync::Arc::new(mesh(&o.mesh));
        o.pose = pose(&o.pose);
    }
    q.start = pose(&p.start);
    q.goal = pose(&p.goal);
    q.space.min = p.space.min * k;
    q.space.max = p.space.max * k;
    q.space.rotation_weight = p.space.rotation_weight * k;
    q.product_box = fitup::math::Aabb::new(p.product_box.lo * k, p.product_box.hi * k);
    q.name = format!("{}_x{k}", p.name);
    q
}

/// Compiles the OMPL C++ harness (tests/bench/ompl/harness.cpp) when OMPL 1.5 and
/// FCL headers and g++ are installed; `None` (with a message) otherwise.
fn build_cpp_peer(out_dir: &Path) -> Option<PathBuf> {
    let ompl = Path::new("/usr/include/ompl-1.5");
    if !ompl.exists() || !Path::new("/usr/include/fcl/fcl.h").exists() {
        eprintln!("no OMPL C++ peer: install libompl-dev libfcl-dev (Debian) for it");
        return None;
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bench/ompl/harness.cpp");
    let exe = out_dir.join("ompl_harness");
    let status = std::process::Command::new("g++")
        .args([
            "-O2",
            "-std=c++17",
            "-I/usr/include/ompl-1.5",
            "-I/usr/include/eigen3",
        ])
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .args(["-lompl", "-lfcl", "-lccd"])
        .status();
    match status {
        Ok(s) if s.success() => Some(exe),
        other => {
            eprintln!(
                "no OMPL C++ peer: compiling {} failed ({other:?})",
                src.display()
            );
            None
        }
    }
}

/// Runs the C++ harness on the problem's `problem.txt` beside `spec`.
fn cpp_runs(exe: &Path, spec: &Path, planner: &str, runs: usize, limit: f64) -> Option<Row> {
    let txt = spec.with_file_name("problem.txt");
    run_peer(std::process::Command::new(exe), &txt, planner, runs, limit)
}

fn peer_runs(py: &Path, spec: &Path, planner: &str, runs: usize, limit: f64) -> Option<Row> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bench/ompl_peer.py");
    let mut python = std::process::Command::new(py);
    python.arg(script);
    run_peer(python, spec, planner, runs, limit)
}

/// Runs a peer as `PEER PROBLEM PLANNER RUNS LIMIT_S` and reads its answer.
fn run_peer(
    mut peer: std::process::Command,
    problem: &Path,
    planner: &str,
    runs: usize,
    limit: f64,
) -> Option<Row> {
    let out = peer
        .arg(problem)
        .arg(planner)
        .arg(runs.to_string())
        .arg(limit.to_string())
        .output()
        .ok()?;
    parse_peer(out)
}

/// The peers' JSON line: `{"runs", "solved", "times_s": [t or null]}`.
fn parse_peer(out: std::process::Output) -> Option<Row> {
    if !out.status.success() {
        eprintln!("peer failed: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).ok()?;
    let mut times: Vec<f64> = v["times_s"]
        .as_array()?
        .iter()
        .filter_map(|t| t.as_f64())
        .collect();
    Some(Row {
        solved: v["solved"].as_u64()? as usize,
        runs: v["runs"].as_u64()? as usize,
        median_s: median(&mut times),
        overrun_pct: f64::NAN,
        smoothing_over_ms: f64::NAN,
    })
}

fn fmt(r: &Row) -> String {
    format!(
        "{:>3}/{:<3} {:>10}",
        r.solved,
        r.runs,
        r.median_s
            .map_or("-".to_string(), |t| format!("{:.4} s", t))
    )
}

/// Seed 002's protocol: 100 runs, at most 100 iterations each, disassembly of the
/// cap from its seat (all three planners through `disassemble`).
fn protocol() {
    let p = problems::piston_rod_cap().unwrap();
    let options = p.default_validator_options();
    println!("\nseed 002 protocol: piston_rod_cap disassembly, 100 runs x 100 iterations");
    println!(
        "{:<12} {:>8} {:>14} {:>14} {:>14}",
        "planner", "success", "mean time", "median time", "mean checks"
    );
    let mk = |bias: f64| {
        DisassemblyPlanner::Rrt(RrtOptions {
            goal_bias: bias,
            ..RrtOptions::default()
        })
    };
    for (name, planner) in [
        ("rrt", mk(0.0)),
        ("biased_rrt", mk(0.1)),
        (
            "local_rrt",
            DisassemblyPlanner::LocalRrt(LocalRrtOptions::default()),
        ),
    ] {
        let (mut ok, mut total, mut checks) = (0, 0.0, 0u64);
        let mut times = Vec::new();
        for seed in 0..100u64 {
            let mut planner = planner.clone();
            match &mut planner {
                DisassemblyPlanner::Rrt(o) => {
                    o.limits.seed = seed;
                    o.limits.max_iterations = 100;
                }
                DisassemblyPlanner::LocalRrt(o) => {
                    o.rrt.limits.seed = seed;
                    o.rrt.limits.max_iterations = 100;
                }
                other => unreachable!("not one of seed 002's planners: {other:?}"),
            }
            let mut v = p.validator(options).unwrap();
            let t0 = Instant::now();
            let path = disassemble(
                &mut v,
                &p.space,
                &p.goal,
                &p.part_box(),
                &p.product_box,
                &planner,
                None,
            )
            .unwrap();
            let dt = t0.elapsed().as_secs_f64();
            total += dt;
            times.push(dt);
            checks += path.collision_checks();
            ok += path.found() as usize;
        }
        println!(
            "{:<12} {:>7}% {:>11.2} ms {:>11.2} ms {:>14.0}",
            name,
            ok,
            total / 100.0 * 1e3,
            median(&mut times).unwrap_or(0.0) * 1e3,
            checks as f64 / 100.0
        );
    }
}

/// The validator's two questions on each problem, at 2000 random poses in the
/// bounds (uniform rotations): the yes/no pose check (`is_free`, stops at the first
/// crossing deeper than the tolerance) split by verdict, and the continuous check of
/// 2 mm / 2° edges from the free ones. Means in µs of the fastest of three runs
/// of each query.
fn validator_profile() {
    use fitup::math::{Transform, Vec3};
    use fitup::planning::MotionValidator;
    println!("\nvalidator: mean µs per query over 2000 random poses per problem (seed 7)");
    println!(
        "{:<18} {:>8} {:>10} {:>8} {:>10} {:>12}",
        "problem", "free", "µs", "blocked", "µs", "edge µs"
    );
    for p in problems::all().unwrap() {
        let mut v = p.validator(p.default_validator_options()).unwrap();
        let mut s: u64 = 7;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut poses = Vec::new();
        for _ in 0..2000 {
            let t = Vec3::new(
                p.space.min.x + rnd() * (p.space.max.x - p.space.min.x),
                p.space.min.y + rnd() * (p.space.max.y - p.space.min.y),
                p.space.min.z + rnd() * (p.space.max.z - p.space.min.z),
            );
            let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                rnd() - 0.5,
                rnd() - 0.5,
                rnd() - 0.5,
                rnd() - 0.5,
            ));
            poses.push(Transform::from_parts(t, q));
        }
        let (mut free, mut blocked) = (Vec::new(), Vec::new());
        for pose in &poses {
            // the fastest of three: a shared machine preempts single queries
            let (mut ok, mut dt) = (false, f64::INFINITY);
            for _ in 0..3 {
                let t0 = Instant::now();
                ok = v.is_free(pose);
                dt = dt.min(t0.elapsed().as_secs_f64() * 1e6);
            }
            if ok {
                free.push((dt, *pose));
            } else {
                blocked.push(dt);
            }
        }
        let mut edge_us = Vec::new();
        for (_, pose) in &free {
            let step = Transform::from_xyzabc(
                Vec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0),
                [
                    (2.0 * rnd() - 1.0).to_radians(),
                    (2.0 * rnd() - 1.0).to_radians(),
                    (2.0 * rnd() - 1.0).to_radians(),
                ],
                Default::default(),
            );
            let to = step.then(pose);
            let mut dt = f64::INFINITY;
            for _ in 0..3 {
                let t0 = Instant::now();
                v.edge_free(pose, &to);
                dt = dt.min(t0.elapsed().as_secs_f64() * 1e6);
            }
            edge_us.push(dt);
        }
        let mean = |xs: &[f64]| {
            if xs.is_empty() {
                "-".to_string()
            } else {
                format!("{:.1}", xs.iter().sum::<f64>() / xs.len() as f64)
            }
        };
        let free_us: Vec<f64> = free.iter().map(|f| f.0).collect();
        println!(
            "{:<18} {:>8} {:>10} {:>8} {:>10} {:>12}",
            p.name,
            free.len(),
            mean(&free_us),
            blocked.len(),
            mean(&blocked),
            mean(&edge_us)
        );
    }
}

fn main() {
    if std::env::var("FITUP_VALIDATOR").map_or(true, |v| v != "0") {
        validator_profile();
    }
    let runs = env_or("FITUP_RUNS", 10usize);
    let peer_n = env_or("FITUP_OMPL_RUNS", 5usize);
    let limit = env_or("FITUP_OMPL_LIMIT_S", 10.0f64);
    let py =
        PathBuf::from(std::env::var("FITUP_PY").unwrap_or_else(|_| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/.venv/bin/python").to_string()
        }));
    let peer = py.exists();
    if !peer {
        eprintln!("no OMPL peer ({} missing): fitup only", py.display());
    }
    let tmp = tempfile::tempdir().unwrap();
    let cpp = build_cpp_peer(tmp.path());
    let stepwise = std::env::var_os("FITUP_STEPWISE").is_some();
    let only: Option<String> = std::env::var("FITUP_PROBLEM").ok();
    let compare = std::env::var_os("FITUP_VARIANTS").is_some();
    let defaults = std::env::var("FITUP_DEFAULT").map_or(true, |v| v != "0");
    let smoothed_rows = std::env::var("FITUP_SMOOTHED").map_or(true, |v| v != "0");
    let puzzles = std::env::var("FITUP_PUZZLES").is_ok_and(|v| v == "1");
    println!(
        "planning: success and median time of successful runs; fitup = {} with continuous edges, no smoothing (as OMPL's solve), {runs} seeds x <= {} ms; OMPL (Python, FCL validity at {RESOLUTION_MM} mm) {peer_n} runs x {limit} s",
        if rrt_connect_alone() {
            "rrt_connect"
        } else {
            "plan_insertion"
        },
        budget_ms()
    );
    println!(
        "OMPL C++ (RRTConnect, KPIECE1{}; FCL validity at {RESOLUTION_MM} mm): {peer_n} runs x {limit} s; ratio = OMPL's best median / fitup's median",
        if puzzles { ", BiTRRT" } else { "" }
    );
    println!(
        "{:<18} {:>20} {:>20} {:>10} {:>20} {:>20} {:>20} {:>20}",
        "problem",
        "fitup",
        "OMPL RRTConnect",
        "ratio",
        "fitup + smoothing",
        "fitup stepwise",
        "C++ RRTConnect",
        "C++ KPIECE1"
    );
    let list = if puzzles {
        problems::puzzles().unwrap()
    } else {
        problems::all().unwrap()
    };
    // `FITUP_SCALE=k`: every problem scaled by k (meshes, poses, bounds and the
    // rotation weight), to see how the planner's mm-valued defaults carry over to
    // bigger (or smaller) scenes.
    let scale: f64 = env_or("FITUP_SCALE", 1.0);
    for p in list {
        if only
            .as_ref()
            .is_some_and(|o| !o.split(',').any(|o| p.name.contains(o)))
        {
            continue;
        }
        let p = if scale == 1.0 { p } else { scaled(&p, scale) };
        let dir = tmp.path().join(&p.name);
        std::fs::create_dir_all(&dir).unwrap();
        let spec = export(&p, &dir);
        if compare {
            let list = match std::env::var("FITUP_VARIANTS").as_deref() {
                Ok("narrow") => narrow_variants(),
                Ok("share") => share_variants(),
                Ok("step") => step_variants(),
                _ => variants(),
            };
            for (name, variant) in list {
                let r = fitup_runs(&p, p.default_validator_options(), runs, false, &*variant);
                println!("{:<18} {:>20} {}", "", fmt(&r), name);
            }
        }
        let none = || Row {
            solved: 0,
            runs: 0,
            median_s: None,
            overrun_pct: f64::NAN,
            smoothing_over_ms: f64::NAN,
        };
        let cont = if defaults {
            fitup_runs(&p, p.default_validator_options(), runs, false, &|_| ())
        } else {
            none()
        };
        let smoothed = if defaults && smoothed_rows {
            fitup_runs(&p, p.default_validator_options(), runs, true, &|_| ())
        } else {
            none()
        };
        let ompl = if peer {
            peer_runs(&py, &spec, "RRTConnect", peer_n, limit)
        } else {
            None
        };
        let step =
            stepwise.then(|| fitup_runs(&p, p.stepwise_validator_options(), runs, false, &|_| ()));
        let ratio = match (&ompl, cont.median_s) {
            (
                Some(Row {
                    median_s: Some(o), ..
                }),
                Some(f),
            ) => format!("{:.0}x", o / f),
            (Some(o), Some(f)) if o.solved == 0 => format!(">{:.0}x", limit / f),
            _ => "-".into(),
        };
        let c_rrt = cpp
            .as_ref()
            .and_then(|e| cpp_runs(e, &spec, "RRTConnect", peer_n, limit));
        let c_kp = cpp
            .as_ref()
            .and_then(|e| cpp_runs(e, &spec, "KPIECE1", peer_n, limit));
        let c_bit = cpp
            .as_ref()
            .filter(|_| puzzles)
            .and_then(|e| cpp_runs(e, &spec, "BiTRRT", peer_n, limit));
        let best = [&ompl, &c_rrt, &c_kp, &c_bit]
            .iter()
            .filter_map(|r| r.as_ref().and_then(|r| r.median_s))
            .fold(None, |b: Option<f64>, t| Some(b.map_or(t, |b| b.min(t))));
        let ratio = match (best, cont.median_s) {
            (Some(o), Some(f)) => format!("{:.1}x", o / f),
            (None, Some(f)) if c_rrt.is_some() || ompl.is_some() => format!(">{:.0}x", limit / f),
            _ => ratio,
        };
        println!(
            "{:<18} {:>20} {:>20} {:>10} {:>20} {:>20} {:>20} {:>20}",
            p.name,
            fmt(&cont),
            ompl.as_ref().map_or("-".into(), fmt),
            ratio,
            fmt(&smoothed),
            step.as_ref().map_or("-".into(), fmt),
            c_rrt.as_ref().map_or("-".into(), fmt),
            c_kp.as_ref().map_or("-".into(), fmt),
        );
        if let Some(r) = &c_bit {
            println!("{:<18} {:>20} {}", "", "C++ BiTRRT", fmt(r));
        }
        if puzzles {
            let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
            println!(
                "{:<18} load {}; fitup's largest overrun {:.2} % of {} ms (setup + call)",
                "",
                load.trim(),
                cont.overrun_pct,
                budget_ms()
            );
        }
        // Budget probe: a budget short enough that the hard seeds run out, with
        // smoothing on at its default share, so the deadline of every stage is
        // exercised (`FITUP_PROBE_MS`, 0: off).
        let probe: f64 = env_or("FITUP_PROBE_MS", 0.0);
        if probe > 0.0 {
            let r = fitup_runs_within(
                &p,
                p.default_validator_options(),
                runs,
                true,
                &|_| (),
                probe,
            );
            println!(
                "{:<18} budget probe {probe} ms with smoothing: {}; largest overrun {:.2} % (setup + call); smoothing {:+.2} ms over its share",
                "",
                fmt(&r),
                r.overrun_pct,
                r.smoothing_over_ms
            );
        }
        if peer && std::env::var_os("FITUP_OMPL_RRT").is_some() {
            if let Some(r) = peer_runs(&py, &spec, "RRT", peer_n, limit) {
                println!("{:<18} {:>20} {:>20}", "", "OMPL RRT", fmt(&r));
            }
        }
    }
    let worst = *WORST_OVERRUN_MS.lock().unwrap();
    if worst.is_finite() {
        println!(
            "fitup's time budget: {} ms per call; largest overrun seen {worst:.1} ms (negative: every call ended within it)",
            budget_ms()
        );
    }
    if std::env::var("FITUP_PROTOCOL").map_or(true, |v| v != "0") {
        protocol();
    }
}
