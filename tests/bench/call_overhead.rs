//! One call's cost from Rust and from a Rhai script, for the calls docs/performance.md
//! ("Python") compares with Python (`python/bench/overhead.py` runs this bench first
//! and adds its own columns): FK, IK of every branch (the demo MZ07, and a UR5e of
//! the published D-H lengths without joint limits; from Rhai as `ik`'s array and as
//! the fast form `ik_solutions`), the UR5e's nearest solution
//! (`ik_near`), an interference check of one pair and a short plan (screw5 lifted
//! 40 mm, RRT-Connect, seed 3), on the demo MZ07 and cell documents; and the floor,
//! `q.len()`: the interpreter's cost of one native method call. The set-up script,
//! the UR5e and the calls (name, calls per round, Rhai expression) are files under
//! `call_overhead/`, read by overhead.py too. Scripts run in fitup's script engine (`script::engine`:
//! every binding, the sandbox's operation counting) on the bench's thread, the set-up
//! once; times are this thread's CPU time, which a busy machine inflates far less than
//! wall time. A script figure is the loop `for i in 0..n { let x = CALL; }` minus the
//! same loop with `let x = i;`, divided by n.
//!
//! Run: `cargo bench --profile dev --bench call_overhead` (the profile of the Python
//! module CI builds; drop `--profile dev` for release figures).
//!
//! Besides the table it prints one `CALL <name> <rust ns> <rhai ns>` line per call,
//! read by overhead.py. `FITUP_CALLS=ik_ur5e,floor` runs only the calls named.

use fitup::document::Document;
use fitup::kinematics::IkOptions;
#[path = "demo_mz07.rs"]
mod demo_mz07;
use fitup::math::{Transform, Vec3};
use fitup::planning::Planner;
use fitup::script::{Caches, Context, Limits, Project};
use fitup::workspace::{CheckOptions, PlanRequest, SceneCache, Workspace};

use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const ROUNDS: usize = 7;

/// Run once before the timed loops (python/bench/overhead.py runs it too).
const SETUP: &str = include_str!("call_overhead/setup.rhai");

/// A UR5e of the published D-H lengths without joint limits (overhead.py writes it
/// too).
const UR5E_YAML: &str = include_str!("call_overhead/ur5e.yaml");

/// `name calls expression` per line: the calls both benches time.
const CALLS: &str = include_str!("call_overhead/calls.txt");

/// The UR5e's joints (degrees, the set-up's): away from every singularity.
const UR5E_Q: [f64; 6] = [10.0, -60.0, 80.0, -110.0, -70.0, 30.0];

/// (name, calls per round, Rhai expression) of each line of [`CALLS`].
fn call_table() -> Vec<(&'static str, usize, &'static str)> {
    CALLS
        .lines()
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let mut it = l.splitn(3, ' ');
            let (name, n, expr) = (it.next(), it.next(), it.next());
            match (name, n.and_then(|n| n.parse().ok()), expr) {
                (Some(name), Some(n), Some(expr)) => (name, n, expr),
                _ => panic!("calls.txt: bad line `{l}`"),
            }
        })
        .collect()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// CPU time of this thread (ns): `clock_gettime(CLOCK_THREAD_CPUTIME_ID)`, exact to the
/// nanosecond (/proc/thread-self/schedstat moves in steps of a scheduler tick).
#[cfg(unix)]
fn cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// Wall time elsewhere (no thread CPU clock in std).
#[cfg(not(unix))]
fn cpu_ns() -> u64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_nanos() as u64
}

/// fitup's script engine on this thread, its scope after [`SETUP`]: the loops are
/// timed alone (no document opening, no compiling), with this thread's CPU time.
struct Rhai {
    engine: rhai::Engine,
    scope: rhai::Scope<'static>,
}

impl Rhai {
    fn new(root: &Path) -> Self {
        let limits = Limits {
            max_operations: u64::MAX / 2,
            ..Limits::default()
        };
        let ctx = Arc::new(Context::new(
            Project::new(root).unwrap(),
            Arc::new(Caches::default()),
            Arc::new(AtomicBool::new(false)),
            Arc::new(|l: &str| println!("{l}")),
        ));
        let engine = fitup::script::engine(&ctx, &limits);
        let mut scope = rhai::Scope::new();
        engine.run_with_scope(&mut scope, SETUP).expect("set-up");
        Self { engine, scope }
    }

    /// CPU ns of `n` iterations of `let x = {expr};`.
    fn loop_ns(&mut self, expr: &str, n: usize) -> f64 {
        let text = format!("for i in 0..{n} {{ let x = {expr}; }}");
        let ast = self
            .engine
            .compile_with_scope(&self.scope, &text)
            .expect("loop");
        let t0 = cpu_ns();
        self.engine
            .run_ast_with_scope(&mut self.scope, &ast)
            .expect("bench loop");
        (cpu_ns() - t0) as f64
    }

    /// ns per call of `n` calls of the script expression `call`, minus the same loop
    /// binding the loop counter (`let x = i;`: no allocation, unlike an array).
    fn ns(&mut self, call: &str, n: usize) -> f64 {
        let full = self.loop_ns(call, n);
        let empty = self.loop_ns("i", n);
        (full - empty) / n as f64
    }
}

/// CPU ns per call of `n` calls of `f`.
fn rust_ns(n: usize, mut f: impl FnMut()) -> f64 {
    let t0 = cpu_ns();
    for _ in 0..n {
        f();
    }
    (cpu_ns() - t0) as f64 / n as f64
}

fn main() {
    let (dir, robot, q, target) = demo_mz07::demo_mz07();
    let every = IkOptions::every_branch();
    std::fs::write(dir.path().join("models/ur5e.yaml"), UR5E_YAML).unwrap();
    let ur_doc = Document::open(&dir.path().join("models/ur5e.yaml")).unwrap();
    let ur = ur_doc.robot("ur5e").unwrap().robot().clone();
    assert_eq!(
        ur.solver_name(),
        "ur",
        "the UR5e must be solved in closed form"
    );
    let ur_q: Vec<f64> = UR5E_Q.iter().map(|v| v.to_radians()).collect();
    let ur_target = ur.tcp_pose(&ur_q).unwrap();
    let branches = ur.inverse(&ur_target, &ur_q, &every).unwrap().len();
    println!("UR5e: {branches} branches at the target");
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
    // The Rust call of each name of calls.txt.
    // (name, the Rust call)
    type RustCall<'a> = (&'a str, Box<dyn FnMut() + 'a>);
    let mut rust_calls: Vec<RustCall> = vec![
        (
            "fk",
            Box::new(|| {
                black_box(robot.tcp_pose(black_box(&q)).unwrap());
            }),
        ),
        (
            "ik_all",
            Box::new(|| {
                black_box(robot.inverse(black_box(&target), &q, &every).unwrap());
            }),
        ),
        (
            "ik_ur5e",
            Box::new(|| {
                black_box(ur.inverse(black_box(&ur_target), &ur_q, &every).unwrap());
            }),
        ),
        (
            "ik_solutions",
            Box::new(|| {
                black_box(robot.inverse(black_box(&target), &q, &every).unwrap());
            }),
        ),
        (
            "ik_solutions_ur5e",
            Box::new(|| {
                black_box(ur.inverse(black_box(&ur_target), &ur_q, &every).unwrap());
            }),
        ),
        (
            // Every solution's joints copied into one stack array: no allocation.
            "ik_each_ur5e",
            Box::new(|| {
                let mut flat = [0.0; 48];
                let mut n = 0;
                ur.inverse_each(black_box(&ur_target), &ur_q, &every, |s| {
                    if let Some(row) = flat.get_mut(n..n + s.len()) {
                        row.copy_from_slice(s);
                    }
                    n += s.len();
                })
                .unwrap();
                black_box((flat, n));
            }),
        ),
        (
            "ik_near_ur5e",
            Box::new(|| {
                black_box(
                    ur.inverse_nearest(black_box(&ur_target), &ur_q, &every)
                        .unwrap(),
                );
            }),
        ),
        // The interpreter's own cost of one native method call: Rust does nothing.
        ("floor", Box::new(|| {})),
        (
            // The workspace (the scene of the document as it is now, colliders from the
            // cache) is built per call, as the Rhai and Python bindings do.
            "interferes",
            Box::new(|| {
                let ws = Workspace::new(&cell, &mut check_cache).unwrap();
                black_box(ws.interferes("screw4", "screw5", &check).unwrap());
            }),
        ),
        (
            "plan_short",
            Box::new(|| {
                let ws = Workspace::new(&cell, &mut plan_cache).unwrap();
                let path = ws.plan_path("screw5", &goal, &request(), None).unwrap();
                assert!(path.found(), "the short plan must find its path");
                black_box(path);
            }),
        ),
    ];
    let mut engine = Rhai::new(dir.path());
    // FITUP_CALLS=ik_ur5e,floor runs only those calls (a profile, a quick look).
    let only = std::env::var("FITUP_CALLS").ok();
    let wanted = |name: &str| {
        only.as_deref()
            .is_none_or(|o| o.split(',').any(|w| w == name))
    };
    let mut rows = Vec::new();
    for (name, n, script) in call_table() {
        if !wanted(name) {
            continue;
        }
        let f = match rust_calls.iter_mut().find(|(r, _)| *r == name) {
            Some((_, f)) => f,
            None => panic!("no Rust call for `{name}` of calls.txt"),
        };
        f(); // warm-up: colliders, caches
        let (mut rust, mut rhai) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            rust.push(rust_ns(n, &mut *f));
            rhai.push(engine.ns(script, n));
        }
        rows.push((name, script, median(&mut rust), median(&mut rhai)));
    }
    println!("medians over {ROUNDS} rounds (ns per call, this thread's CPU time):");
    println!("| call | Rust | Rhai | Rhai − Rust | Rhai / Rust |");
    println!("|---|---|---|---|---|");
    for (name, script, rust, rhai) in &rows {
        println!(
            "| {name} `{script}` | {rust:.0} | {rhai:.0} | {:.0} | {:.2} |",
            rhai - rust,
            rhai / rust
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
