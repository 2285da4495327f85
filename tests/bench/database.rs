//! `cargo bench --bench database`: storing and reading back a path of 10,000 key poses
//! and a trajectory of 10,000 samples in SQLite (the goal: each a single-digit
//! number of milliseconds): fastest and median of 15 rounds, a fresh file each round. With
//! `FITUP_BENCH_POSTGRES=postgres://…` the same is timed on that PostgreSQL server.
//! Figures go to docs/performance.md.

use fitup::collision::SweepMethod;
use fitup::db::{Database, PathMeta, PathQuery, Target};
use fitup::kinematics::{JointKind, Trajectory, TrajectorySample};
use fitup::math::{Rng, Transform, Vec3};
use fitup::planning::PlannedPath;
use std::time::Instant;

const N: usize = 10_000;
const ROUNDS: usize = 15;

/// The result of `f` and its wall time (ms).
fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let s = Instant::now();
    let r = f();
    (r, s.elapsed().as_secs_f64() * 1e3)
}

/// (fastest, median): on a busy machine the fastest round is the best estimate of
/// the uncontended cost, the median of what a user sees.
fn summary(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

fn pose(rng: &mut Rng) -> Transform {
    Transform::from_parts(
        Vec3::new(
            rng.range(0.0, 1000.0),
            rng.range(0.0, 1000.0),
            rng.range(0.0, 1000.0),
        ),
        rng.rotation(),
    )
}

fn data() -> (PlannedPath, Trajectory) {
    let mut rng = Rng::new(14);
    let poses: Vec<Transform> = (0..N).map(|_| pose(&mut rng)).collect();
    let path = PlannedPath {
        failure: None,
        poses,
        length_mm: 1.0,
        rotation_rad: 1.0,
        raw_length_mm: 1.0,
        raw_rotation_rad: 1.0,
        iterations: N,
        nodes: N,
        pose_checks: 0,
        edge_checks: 0,
        time_ms: 1.0,
        search_ms: 1.0,
        smoothing_ms: 0.0,
        resolution: SweepMethod::DEFAULT,
        tolerance_mm: fitup::collision::DEFAULT_TOLERANCE,
        planner: "rrt_connect",
    };
    let mut t = Trajectory::new(vec![JointKind::Revolute; 6]);
    for i in 0..N {
        t.samples.push(TrajectorySample {
            t: i as f64 * 0.004,
            joints: (0..6).map(|_| rng.range(-3.0, 3.0)).collect(),
            tcp: pose(&mut rng),
        });
    }
    (path, t)
}

/// Wall ms (fastest, median) of: store path, read path, store trajectory, read
/// trajectory.
fn bench(make: &mut dyn FnMut() -> Target, path: &PlannedPath, t: &Trajectory) -> [(f64, f64); 4] {
    let mut wall: [Vec<f64>; 4] = Default::default();
    let mut note = |k: usize, w: f64| wall[k].push(w);
    for _ in 0..ROUNDS {
        let target = make();
        let mut db = Database::open(&target).unwrap();
        let (pid, w) = timed(|| {
            db.save_path(None, "bench", path, &PathMeta::default())
                .unwrap()
        });
        note(0, w);
        let (back, w) = timed(|| {
            db.paths(&PathQuery {
                name: Some("bench".into()),
                ..Default::default()
            })
            .unwrap()
        });
        note(1, w);
        assert_eq!(back[0].id, pid);
        assert_eq!(back[0].path.poses.len(), N);
        assert!(back[0].path.poses[N - 1].approx_eq(&path.poses[N - 1], 1e-9, 1e-12));
        let (tid, w) = timed(|| db.save_trajectory(None, "bench", None, t).unwrap());
        note(2, w);
        let (tb, w) = timed(|| db.trajectory(tid).unwrap());
        note(3, w);
        assert_eq!(tb.trajectory.samples.len(), N);
        assert_eq!(tb.trajectory.samples[N - 1].joints, t.samples[N - 1].joints);
    }
    wall.map(summary)
}

fn report(name: &str, r: [(f64, f64); 4]) {
    println!("{name}, wall ms over {ROUNDS} rounds (fastest / median):");
    for (what, (min, med)) in [
        "store a {N}-pose path",
        "read it back",
        "store a {N}-sample trajectory",
        "read it back",
    ]
    .iter()
    .zip(r)
    {
        println!(
            "  {:<32} {min:>7.1} / {med:>7.1}",
            what.replace("{N}", &N.to_string())
        );
    }
}

fn main() {
    let (path, t) = data();
    let dir = tempfile::tempdir().unwrap();
    let mut k = 0;
    let mut make = || {
        k += 1;
        Target::Sqlite(dir.path().join(format!("bench{k}.db")))
    };
    report(
        "SQLite (WAL, synchronous=NORMAL)",
        bench(&mut make, &path, &t),
    );
    #[cfg(feature = "postgres")]
    if let Ok(url) = std::env::var("FITUP_BENCH_POSTGRES") {
        let mut admin = postgres::Client::connect(&url, postgres::NoTls).unwrap();
        let mut n = 0;
        let mut names = Vec::new();
        let base = url
            .rsplit_once('/')
            .map(|(b, _)| b.to_string())
            .unwrap_or(url.clone());
        let mut make = || {
            n += 1;
            let name = format!("fitup_bench_{}_{n}", std::process::id());
            admin
                .batch_execute(&format!("CREATE DATABASE {name}"))
                .unwrap();
            names.push(name.clone());
            Target::Postgres(format!("{base}/{name}"))
        };
        report("PostgreSQL (loopback)", bench(&mut make, &path, &t));
        for name in names {
            let _ = admin.batch_execute(&format!("DROP DATABASE IF EXISTS {name} WITH (FORCE)"));
        }
    }
}
