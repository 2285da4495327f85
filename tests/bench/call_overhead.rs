//! One call's cost from Rust and from a Rhai script, for the calls docs/performance.md
//! ("Python") compares with Python (`python/bench/overhead.py` runs this bench first
//! and adds its own columns): FK, IK of every branch, an interference check of one
//! pair and a short plan (screw5 lifted 40 mm, RRT-Connect, seed 3), on the demo
//! MZ07 and cell documents. Script figures subtract an empty loop of the same shape.
//!
//! Run: `cargo bench --profile dev --bench call_overhead` (the profile of the Python
//! module CI builds; drop `--profile dev` for release figures).
//!
//! Besides the table it prints one `CALL <name> <rust ns> <rhai ns>` line per call,
//! read by overhead.py.

use fitup::document::Document;
use fitup::kinematics::IkOptions;
use fitup::math::{Transform, Vec3};
use fitup::planning::Planner;
use fitup::workspace::{CheckOptions, PlanRequest, SceneCache, Workspace};
#[path = "rhai_timing.rs"]
mod rhai_timing;

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

const ROUNDS: usize = 7;

/// Calls per round of each kind (about the same wall time each).
const N_KINEMATICS: usize = 20_000;
const N_CHECK: usize = 2_000;
const N_PLAN: usize = 20;

const SETUP: &str = r#"let d = open_doc("models/mz07.yaml");
let arm = d.robot("mz07");
let q = [10.0, -20.0, 30.0, 40.0, -50.0, 60.0];
arm.joints = q;
let t = arm.fk(q);
let cell = open_doc("models/cell.yaml");
let goal = cell.component("screw5").transform * translation(0.0, 0.0, 40.0);
let opts = #{planner: "rrt_connect", seed: 3};
cell.interferes("screw4", "screw5"); // colliders built before the timed loops
"#;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// ns per call of `n` calls of the script expression `call`, minus the same loop on `q`.
fn rhai_ns(dir: &Path, call: &str, n: usize) -> f64 {
    let body = |x: &str| format!("{SETUP}for i in 0..{n} {{ let x = {x}; }}\n");
    let full = rhai_timing::rhai_seconds(dir, &body(call));
    let empty = rhai_timing::rhai_seconds(dir, &body("q"));
    (full - empty) / n as f64 * 1e9
}

/// ns per call of `n` calls of `f`.
fn rust_ns(n: usize, mut f: impl FnMut()) -> f64 {
    let t0 = Instant::now();
    for _ in 0..n {
        f();
    }
    t0.elapsed().as_secs_f64() / n as f64 * 1e9
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_robots(&dir.path().join("models")).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    let doc = Document::open(&dir.path().join("models/mz07.yaml")).unwrap();
    let robot = doc.robot("mz07").unwrap().robot().clone();
    let q: Vec<f64> = [10.0f64, -20.0, 30.0, 40.0, -50.0, 60.0]
        .iter()
        .map(|v| v.to_radians())
        .collect();
    let target = robot.tcp_pose(&q).unwrap();
    let every = IkOptions::every_branch();
    let cell = Document::open(&dir.path().join("models/cell.yaml")).unwrap();
    let check = CheckOptions::default();
    let goal = {
        let ws = Workspace::new(&cell, &mut SceneCache::new()).unwrap();
        ws.pose("screw5").unwrap() * Transform::from_translation(Vec3::new(0.0, 0.0, 40.0))
    };
    let request = || {
        let mut planner: Planner = "rrt_connect".parse().unwrap();
        planner.limits_mut().seed = 3;
        PlanRequest {
            planner,
            ..PlanRequest::default()
        }
    };
    // Each call keeps its own scene cache, filled by the warm-up call below.
    let (mut check_cache, mut plan_cache) = (SceneCache::new(), SceneCache::new());
    // (name, Rhai expression, calls per round, the Rust call)
    type Call<'a> = (&'a str, &'a str, usize, Box<dyn FnMut() + 'a>);
    let mut calls: Vec<Call> = vec![
        (
            "fk",
            "arm.fk(q)",
            N_KINEMATICS,
            Box::new(|| {
                black_box(robot.tcp_pose(black_box(&q)).unwrap());
            }),
        ),
        (
            "ik_all",
            "arm.ik(t)",
            N_KINEMATICS,
            Box::new(|| {
                black_box(robot.inverse(black_box(&target), &q, &every).unwrap());
            }),
        ),
        (
            // The workspace (the scene of the document as it is now, colliders from the
            // cache) is built per call, as the Rhai and Python bindings do.
            "interferes",
            r#"cell.interferes("screw4", "screw5")"#,
            N_CHECK,
            Box::new(|| {
                let ws = Workspace::new(&cell, &mut check_cache).unwrap();
                black_box(ws.interferes("screw4", "screw5", &check).unwrap());
            }),
        ),
        (
            "plan_short",
            r#"cell.plan_path("screw5", goal, opts)"#,
            N_PLAN,
            Box::new(|| {
                let ws = Workspace::new(&cell, &mut plan_cache).unwrap();
                let path = ws.plan_path("screw5", &goal, &request(), None).unwrap();
                assert!(path.found(), "the short plan must find its path");
                black_box(path);
            }),
        ),
    ];
    let mut rows = Vec::new();
    for (name, script, n, f) in &mut calls {
        f(); // warm-up: colliders, caches
        let (mut rust, mut rhai) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            rust.push(rust_ns(*n, &mut *f));
            rhai.push(rhai_ns(dir.path(), script, *n));
        }
        rows.push((*name, *script, median(&mut rust), median(&mut rhai)));
    }
    println!("medians over {ROUNDS} rounds (ns per call, wall clock):");
    println!("| call | Rust | Rhai | Rhai − Rust |");
    println!("|---|---|---|---|");
    for (name, script, rust, rhai) in &rows {
        println!(
            "| {name} `{script}` | {rust:.0} | {rhai:.0} | {:.0} |",
            rhai - rust
        );
    }
    for (name, _, rust, rhai) in &rows {
        println!("CALL {name} {rust:.0} {rhai:.0}");
    }
    println!(
        "loadavg: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
