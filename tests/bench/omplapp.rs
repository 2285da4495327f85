//! fitup's default `plan_path` against OMPL 1.5 C++ (seven planners, FCL meshes) on
//! OMPL.app's rigid-body problems, seed by seed in one run (issue 35).
//!
//! The problems are OMPL.app's own `resources/3D/*.cfg` + COLLADA meshes, converted
//! at bench time by `../shared/bench/omplapp/prepare.sh` into a folder of
//! `NAME/{NAME.yaml, NAME.json, NAME_env.stl, NAME_robot.stl}` plus the OMPL harness
//! `bin/se3stl`; their meshes may not be redistributed, so nothing of them is in
//! this repository. Without `FITUP_OMPLAPP` naming that folder the bench says so
//! and does nothing.
//!
//! ```sh
//! FITUP_OMPLAPP=target/omplapp cargo bench --no-default-features --bench omplapp
//! ```
//!
//! Environment: `FITUP_OMPLAPP` (the converted folder), `FITUP_OMPLAPP_BIN` (the
//! harness, default `$FITUP_OMPLAPP/bin/se3stl`; without it fitup runs alone),
//! `FITUP_PROBLEM=a,b` (problems whose name is one of them; default every folder),
//! `FITUP_RUNS` (seeds 1..=N, default 5), `FITUP_BUDGET_S` (the budget of each
//! call, fitup's and OMPL's, default 20), `FITUP_PLANNERS` (OMPL planners, default
//! `rrtconnect,kpiece1,bitrrt,bkpiece1,lbkpiece1,biest,prm`; `none`: fitup alone),
//! `FITUP_SCALE=k` (every problem scaled by k — meshes, poses, bounds — for fitup
//! and OMPL alike, written to `$FITUP_OMPLAPP/scaled-k/`), `FITUP_RECHECK=0` (skip
//! the independent re-check).
//!
//! Every fitup path is re-checked independently with parry3d-f64: the robot's and
//! the environment's meshes as parry `TriMesh`es, `intersection_test` at poses at
//! most 1 % of the robot's radius (and 0.01 rad) apart along every edge. A pose
//! parry finds intersecting is then measured by fitup's own contact depth, which
//! must stay within the path's tolerance (touching is free in fitup's rule).
//! Times are wall-clock, for fitup the whole call (search and smoothing), for OMPL
//! the timed solve (its simplification is untimed and reported apart); the load
//! average is printed with every run.

use fitup::collision::{contact, Collider};
use fitup::document::Document;
use fitup::math::{Transform, Vec3};
use fitup::planning::PlannedPath;
use fitup::workspace::{PlanRequest, SceneCache, Workspace};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

/// One problem file (`NAME.json`): meshes, start and goal (row-vector 4×4), bounds.
struct ProblemJson {
    dir: PathBuf,
    name: String,
    start: Transform,
    goal: Transform,
    min: Vec3,
    max: Vec3,
}

fn matrix(v: &serde_json::Value) -> Transform {
    let rows = v["matrix"].as_array().expect("matrix rows");
    let mut m = [[0.0; 4]; 4];
    for (i, r) in rows.iter().enumerate() {
        for (j, x) in r.as_array().expect("a row").iter().enumerate() {
            m[i][j] = x.as_f64().expect("a number");
        }
    }
    Transform::from_matrix(&m).expect("a rigid pose")
}

fn vec3(v: &serde_json::Value) -> Vec3 {
    let a = v.as_array().expect("three numbers");
    Vec3::new(
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    )
}

fn read_problem(dir: &Path, name: &str) -> ProblemJson {
    let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).expect("problem json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    ProblemJson {
        dir: dir.to_path_buf(),
        name: name.to_string(),
        start: matrix(&v["start"]),
        goal: matrix(&v["goal"]),
        min: vec3(&v["bounds"]["min"]),
        max: vec3(&v["bounds"]["max"]),
    }
}

/// A copy of problem `name` of `src` scaled by `k` in `out/NAME/` (meshes, poses,
/// bounds), for fitup and OMPL alike.
fn scaled_copy(src: &Path, name: &str, k: f64, out: &Path) -> PathBuf {
    let dir = out.join(name);
    std::fs::create_dir_all(&dir).expect("scaled folder");
    for part in ["env", "robot"] {
        let file = format!("{name}_{part}.stl");
        let mut f = std::fs::File::open(src.join(&file)).expect("stl");
        let mesh = stl_io::read_stl(&mut f).expect("binary stl");
        let tris: Vec<stl_io::Triangle> = mesh
            .faces
            .iter()
            .map(|t| {
                let v = |i: usize| {
                    let p = mesh.vertices[t.vertices[i]];
                    stl_io::Vertex::new([p[0] * k as f32, p[1] * k as f32, p[2] * k as f32])
                };
                stl_io::Triangle {
                    normal: t.normal,
                    vertices: [v(0), v(1), v(2)],
                }
            })
            .collect();
        let mut w = std::fs::File::create(dir.join(&file)).expect("scaled stl");
        stl_io::write_stl(&mut w, tris.iter()).expect("write stl");
    }
    let text = std::fs::read_to_string(src.join(format!("{name}.json"))).expect("json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    for end in ["start", "goal"] {
        for x in v[end]["matrix"][3]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .take(3)
        {
            *x = serde_json::json!(x.as_f64().unwrap() * k);
        }
    }
    for side in ["min", "max"] {
        for x in v["bounds"][side].as_array_mut().unwrap() {
            *x = serde_json::json!(x.as_f64().unwrap() * k);
        }
    }
    std::fs::write(
        dir.join(format!("{name}.json")),
        serde_json::to_string_pretty(&v).unwrap(),
    )
    .unwrap();
    let yaml = std::fs::read_to_string(src.join(format!("{name}.yaml"))).expect("yaml");
    // The robot's start row (the last row of the second transform) is scaled too.
    let mut lines: Vec<String> = yaml.lines().map(str::to_string).collect();
    let last = lines.len() - 1;
    let row: Vec<f64> = lines[last]
        .trim()
        .trim_start_matches("- [")
        .trim_end_matches(']')
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect();
    lines[last] = format!("  - [{}, {}, {}, 1.0]", row[0] * k, row[1] * k, row[2] * k);
    std::fs::write(dir.join(format!("{name}.yaml")), lines.join("\n") + "\n").unwrap();
    dir
}

/// One run's outcome.
#[derive(Clone, Debug, Default)]
struct Outcome {
    solved: bool,
    time_s: f64,
    trans: f64,
    rot: f64,
}

fn median(mut xs: Vec<f64>) -> f64 {
    if xs.is_empty() {
        return f64::INFINITY;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// Median time with an unsolved run counted as infinitely slow.
fn median_time(runs: &[Outcome]) -> f64 {
    median(
        runs.iter()
            .map(|r| if r.solved { r.time_s } else { f64::INFINITY })
            .collect(),
    )
}

fn solved(runs: &[Outcome]) -> usize {
    runs.iter().filter(|r| r.solved).count()
}

/// The independent re-check with parry3d-f64 (see the module docs): the number of
/// dense poses parry finds intersecting whose fitup contact depth exceeds the
/// path's tolerance, and how many poses were checked.
struct Recheck {
    env: parry3d_f64::shape::TriMesh,
    robot: parry3d_f64::shape::TriMesh,
    env_collider: Arc<Collider>,
    robot_collider: Arc<Collider>,
    radius: f64,
}

fn trimesh(path: &Path) -> parry3d_f64::shape::TriMesh {
    use parry3d_f64::math::Vector;
    let mut f = std::fs::File::open(path).expect("stl");
    let mesh = stl_io::read_stl(&mut f).expect("stl");
    let vertices: Vec<Vector> = mesh
        .vertices
        .iter()
        .map(|v| Vector::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .collect();
    let indices: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .map(|t| t.vertices.map(|i| i as u32))
        .collect();
    parry3d_f64::shape::TriMesh::new(vertices, indices).expect("a parry trimesh")
}

impl Recheck {
    fn new(p: &ProblemJson, ws: &Workspace<'_>) -> Self {
        let v = ws
            .validator("robot", &Default::default())
            .expect("a validator");
        let robot_collider = v.moving().clone();
        let env_collider = ws
            .validator("env", &Default::default())
            .unwrap()
            .moving()
            .clone();
        Self {
            env: trimesh(&p.dir.join(format!("{}_env.stl", p.name))),
            robot: trimesh(&p.dir.join(format!("{}_robot.stl", p.name))),
            radius: robot_collider.radius(),
            env_collider,
            robot_collider,
        }
    }

    fn bad_poses(&self, path: &PlannedPath) -> (usize, usize) {
        use parry3d_f64::math::{Pose, Rot3, Vector};
        let dense = path
            .densify(0.01 * self.radius, 0.01)
            .expect("within the pose cap");
        let identity = Pose::identity();
        let mut bad = 0;
        for pose in &dense {
            let t = pose.translation();
            let q = pose.rotation();
            let rot = Rot3::from_xyzw(q.i, q.j, q.k, q.w);
            let at = Pose::from_parts(Vector::new(t.x, t.y, t.z), rot);
            let hit = parry3d_f64::query::intersection_test(&at, &self.robot, &identity, &self.env)
                .map_or(true, |i| i.intersecting);
            if hit {
                let c = contact(
                    &self.robot_collider,
                    pose,
                    &self.env_collider,
                    &Transform::IDENTITY,
                    path.tolerance_mm,
                )
                .expect("a contact verdict");
                if c.is_interfering() {
                    bad += 1;
                }
            }
        }
        (bad, dense.len())
    }
}

fn run_fitup(p: &ProblemJson, seed: u64, budget_s: f64, recheck: bool) -> (Outcome, String) {
    let doc = Document::open(&p.dir.join(format!("{}.yaml", p.name))).expect("the document");
    let mut cache = SceneCache::new();
    let ws = Workspace::new(&doc, &mut cache).expect("a workspace");
    let mut request = PlanRequest {
        bounds: Some(fitup::collision::Aabb::new(p.min, p.max)),
        start: Some(p.start),
        ..PlanRequest::default()
    };
    request.planner.limits_mut().seed = seed;
    request.planner.limits_mut().time_limit_ms = Some(budget_s * 1e3);
    experiment(p, &ws, &mut request);
    let t0 = std::time::Instant::now();
    let path = ws
        .plan_path("robot", &p.goal, &request, None)
        .expect("a planning call");
    let wall = t0.elapsed().as_secs_f64();
    let mut check = String::new();
    if path.found() && recheck {
        let r = Recheck::new(p, &ws);
        let (bad, n) = r.bad_poses(&path);
        check = format!(" recheck={bad}/{n}");
        assert_eq!(
            bad, 0,
            "{} seed {seed}: {bad} of {n} dense poses interfere",
            p.name
        );
    }
    let line = format!(
        "fitup seed={seed} solved={} time_s={wall:.3} search_s={:.3} smooth_s={:.3} trans={:.1} rot={:.2} raw_trans={:.1} raw_rot={:.2} keyposes={} iterations={} nodes={} pose_checks={} edge_checks={} failure={:?}{check}",
        u8::from(path.found()),
        path.search_ms / 1e3,
        path.smoothing_ms / 1e3,
        path.length_mm,
        path.rotation_rad,
        path.raw_length_mm,
        path.raw_rotation_rad,
        path.poses.len(),
        path.iterations,
        path.nodes,
        path.pose_checks,
        path.edge_checks,
        path.failure,
    );
    (
        Outcome {
            solved: path.found(),
            time_s: wall,
            trans: path.length_mm,
            rot: path.rotation_rad,
        },
        line,
    )
}

/// Development knobs (not part of the benchmark's figures): `FITUP_X_STEP` (range as
/// a fraction of the bounds' diagonal), `FITUP_X_LAZY` (lazy step, same),
/// `FITUP_X_PLAIN=1` (no lattice, no narrow-passage measures), `FITUP_X_W=1` (the
/// rotation weight is the robot's radius).
fn experiment(p: &ProblemJson, ws: &Workspace<'_>, request: &mut PlanRequest) {
    let diag = (p.max - p.min).norm();
    let fitup::planning::Planner::RrtConnect(o) = &mut request.planner else {
        return;
    };
    if let Ok(f) = std::env::var("FITUP_X_STEP") {
        o.step = f.parse::<f64>().unwrap() * diag;
    }
    if let Ok(f) = std::env::var("FITUP_X_LAZY") {
        o.lazy = Some(fitup::planning::LazyValidation {
            step_mm: f.parse::<f64>().unwrap() * diag,
        });
    }
    if std::env::var("FITUP_X_PLAIN").is_ok_and(|v| v == "1") {
        o.lattice = None;
        o.narrow = fitup::planning::NarrowPassage::OFF;
    }
    if std::env::var("FITUP_X_W").is_ok_and(|v| v == "1") {
        let r = ws
            .validator("robot", &Default::default())
            .unwrap()
            .moving()
            .radius();
        request.rotation_weight = Some(r);
    }
}

fn field(line: &str, key: &str) -> Option<f64> {
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
        .and_then(|v| v.parse().ok())
}

fn run_ompl(bin: &Path, p: &ProblemJson, planner: &str, seed: u64, budget_s: f64) -> Outcome {
    let out = Command::new(bin)
        .arg(p.dir.join(format!("{}.json", p.name)))
        .args(["--planner", planner, "--runs", "1"])
        .args(["--time", &budget_s.to_string(), "--seed", &seed.to_string()])
        .output()
        .expect("the OMPL harness");
    let text = String::from_utf8_lossy(&out.stdout);
    let mut o = Outcome::default();
    for line in text.lines() {
        if line.starts_with("RUN ") {
            o.solved = field(line, "solved") == Some(1.0);
            o.time_s = field(line, "time_s").unwrap_or(f64::INFINITY);
            println!("  ompl {planner} {line} load={}", load());
        } else if line.starts_with("QUALITY simp") {
            o.trans = field(line, "trans_mm").unwrap_or(f64::NAN);
            o.rot = field(line, "rot_rad").unwrap_or(f64::NAN);
            println!("  ompl {planner} {line}");
        }
    }
    o
}

fn main() {
    let Ok(root) = std::env::var("FITUP_OMPLAPP") else {
        println!(
            "omplapp bench: FITUP_OMPLAPP is not set; convert OMPL.app's problems with \
             ../shared/bench/omplapp/prepare.sh and name the folder (skipped)"
        );
        return;
    };
    let root = PathBuf::from(root);
    let bin = std::env::var("FITUP_OMPLAPP_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|_| root.join("bin/se3stl"));
    let runs: u64 = env_or("FITUP_RUNS", 5);
    let budget: f64 = env_or("FITUP_BUDGET_S", 20.0);
    let scale: f64 = env_or("FITUP_SCALE", 1.0);
    let recheck = std::env::var("FITUP_RECHECK").map_or(true, |v| v != "0");
    let planners: Vec<String> = std::env::var("FITUP_PLANNERS")
        .unwrap_or_else(|_| "rrtconnect,kpiece1,bitrrt,bkpiece1,lbkpiece1,biest,prm".into())
        .split(',')
        .filter(|s| !s.is_empty() && *s != "none")
        .map(str::to_string)
        .collect();
    let planners = if bin.exists() {
        planners
    } else {
        println!(
            "omplapp bench: no OMPL harness at {}: fitup alone",
            bin.display()
        );
        Vec::new()
    };
    let mut names: Vec<String> = std::fs::read_dir(&root)
        .expect("the FITUP_OMPLAPP folder")
        .filter_map(|e| {
            let e = e.ok()?;
            let n = e.file_name().to_string_lossy().to_string();
            e.path().join(format!("{n}.json")).exists().then_some(n)
        })
        .collect();
    names.sort();
    if let Ok(only) = std::env::var("FITUP_PROBLEM") {
        let only: Vec<&str> = only.split(',').collect();
        names.retain(|n| only.contains(&n.as_str()));
    }
    println!(
        "omplapp bench: {} problems, seeds 1..={runs}, budget {budget} s, scale {scale}, OMPL planners {:?}, load {}",
        names.len(),
        planners,
        load()
    );
    let checks: usize = env_or("FITUP_CHECKS", 0);
    if checks > 0 {
        for name in &names {
            pose_checks(&read_problem(&root.join(name), name), checks, &root);
        }
        return;
    }
    let mut table = Vec::new();
    for name in &names {
        let src = root.join(name);
        let dir = if scale == 1.0 {
            src
        } else {
            scaled_copy(&src, name, scale, &root.join(format!("scaled-{scale}")))
        };
        let p = read_problem(&dir, name);
        println!("## {name}");
        let mut fitup = Vec::new();
        let mut ompl: BTreeMap<String, Vec<Outcome>> = BTreeMap::new();
        for seed in 1..=runs {
            let (o, line) = run_fitup(&p, seed, budget, recheck);
            println!("  {line} load={}", load());
            fitup.push(o);
            for planner in &planners {
                let o = run_ompl(&bin, &p, planner, seed, budget);
                ompl.entry(planner.clone()).or_default().push(o);
            }
        }
        // The best OMPL planner: most seeds solved, then the lowest median time.
        let best = ompl.iter().min_by(|a, b| {
            solved(b.1)
                .cmp(&solved(a.1))
                .then(median_time(a.1).total_cmp(&median_time(b.1)))
        });
        let quality = |runs: &[Outcome]| {
            let ok: Vec<&Outcome> = runs.iter().filter(|r| r.solved).collect();
            (
                median(ok.iter().map(|r| r.trans).collect()),
                median(ok.iter().map(|r| r.rot).collect()),
            )
        };
        let (ft, fr) = quality(&fitup);
        let row = match best {
            Some((planner, runs)) => {
                let (ot, or) = quality(runs);
                let (fm, om) = (median_time(&fitup), median_time(runs));
                format!(
                    "| {name} | {}/{runs_n}, {} | {planner} {}/{runs_n}, {} | {} | {} | {} |",
                    solved(&fitup),
                    secs(fm),
                    solved(runs),
                    secs(om),
                    ratio(om, fm),
                    ratio(ft, ot),
                    ratio(fr, or),
                    runs_n = runs.len(),
                )
            }
            None => format!(
                "| {name} | {}/{}, {} | — | — | — | — |",
                solved(&fitup),
                fitup.len(),
                secs(median_time(&fitup))
            ),
        };
        println!("{row}");
        table.push(row);
    }
    println!(
        "\n| problem | fitup solved, median | best OMPL solved, median | best OMPL / fitup time | fitup / OMPL translation | fitup / OMPL rotation |\n|---|---|---|---|---|---|"
    );
    for row in table {
        println!("{row}");
    }
    println!("load at the end: {}", load());
}

/// Pose-check throughput, fitup's planner check (`MeshValidator::is_free`) against
/// FCL's `collide` as OMPL's validity checker calls it (`fcl_poses`, built beside
/// `se3stl` from tests/bench/omplapp/fcl_poses.cpp), on the same `n` poses drawn
/// uniformly in the problem's bounds with uniform rotations (seed 7).
fn pose_checks(p: &ProblemJson, n: usize, root: &Path) {
    use fitup::planning::MotionValidator;
    let doc = Document::open(&p.dir.join(format!("{}.yaml", p.name))).expect("the document");
    let mut cache = SceneCache::new();
    let ws = Workspace::new(&doc, &mut cache).expect("a workspace");
    let mut v = ws.validator("robot", &Default::default()).unwrap();
    let space = fitup::planning::PlanningSpace::new(p.min, p.max);
    let mut rng = fitup::math::Rng::new(7);
    let reference = nalgebra::UnitQuaternion::identity();
    let poses: Vec<Transform> = (0..n).map(|_| space.sample(&mut rng, &reference)).collect();
    let mut verdicts = vec![false; n];
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        for (k, q) in poses.iter().enumerate() {
            verdicts[k] = !v.is_free(q);
        }
        best = best.min(t0.elapsed().as_secs_f64());
    }
    let colliding = verdicts.iter().filter(|&&c| c).count();
    let fitup_ns = 1e9 * best / n as f64;
    let file = std::env::temp_dir().join(format!("fitup-poses-{}.txt", p.name));
    let text: String = poses
        .iter()
        .map(|q| {
            let t = q.translation();
            let r = q.rotation();
            format!("{} {} {} {} {} {} {}\n", t.x, t.y, t.z, r.w, r.i, r.j, r.k)
        })
        .collect();
    std::fs::write(&file, text).unwrap();
    let fcl = root.join("bin/fcl_poses");
    let peer = Command::new(&fcl)
        .arg(p.dir.join(format!("{}_env.stl", p.name)))
        .arg(p.dir.join(format!("{}_robot.stl", p.name)))
        .arg(&file)
        .output();
    let (fcl_ns, agree) = match peer {
        Ok(out) if out.status.success() => {
            let text = String::from_utf8_lossy(&out.stdout).to_string();
            let mut lines = text.lines();
            let head = lines.next().unwrap_or_default().to_string();
            let ns = field(&head, "ns_per_check").unwrap_or(f64::NAN);
            let agree = lines
                .zip(&verdicts)
                .filter(|(l, &c)| (l.trim() == "1") == c)
                .count();
            (ns, agree)
        }
        _ => (f64::NAN, 0),
    };
    println!(
        "| {} | {n} | {colliding} | {fitup_ns:.0} | {fcl_ns:.0} | {:.2} | {agree} |",
        p.name,
        fcl_ns / fitup_ns
    );
}

fn secs(t: f64) -> String {
    if t.is_finite() {
        format!("{t:.3} s")
    } else {
        "—".into()
    }
}

fn ratio(a: f64, b: f64) -> String {
    if a.is_finite() && b.is_finite() && b > 0.0 {
        format!("{:.2}", a / b)
    } else if a.is_infinite() && b.is_finite() {
        "∞".into()
    } else {
        "—".into()
    }
}
