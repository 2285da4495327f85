//! The results database against a real SQLite file and a real PostgreSQL server
//! (`FITUP_TEST_POSTGRES`, a URL; `.ci/run` starts a throw-away server and sets it).
//! Without the variable the PostgreSQL half is skipped with a note, except under
//! `CI=true`, where it fails: CI cannot skip it silently.

use crate::common;

use fitup::collision::{Contact, InterferenceKind, PairMember, SweepMethod};
use fitup::db::{
    pose_counts, Database, DbError, InterferencePair, NewRun, PathMeta, PathQuery, RunStatus,
    Snapshot, SqlValue, Target,
};
use fitup::document::DimensionKind;
use fitup::kinematics::{JointKind, Trajectory, TrajectorySample};
use fitup::math::{AngleConvention, Transform, Vec3};
use fitup::planning::{Failure, PlannedPath};
use std::process::Stdio;
#[cfg(feature = "postgres")]
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A fresh, empty database on one back end, removed when dropped.
pub(crate) struct Fresh {
    pub(crate) target: Target,
    _dir: Option<tempfile::TempDir>,
    #[cfg_attr(not(feature = "postgres"), allow(dead_code))]
    pg_drop: Option<(String, String)>,
}

#[cfg(feature = "postgres")]
impl Fresh {
    /// The PostgreSQL URL of this database (panics for SQLite).
    pub(crate) fn url(&self) -> &str {
        match &self.target {
            Target::Postgres(u) => u,
            Target::Sqlite(p) => panic!("{} is not a PostgreSQL database", p.display()),
        }
    }
}

impl Drop for Fresh {
    fn drop(&mut self) {
        #[cfg(feature = "postgres")]
        if let Some((admin, name)) = &self.pg_drop {
            if let Ok(mut c) = postgres::Client::connect(admin, postgres::NoTls) {
                let _ = c.batch_execute(&format!("DROP DATABASE IF EXISTS {name} WITH (FORCE)"));
            }
        }
    }
}

fn sqlite() -> Fresh {
    let dir = tempfile::tempdir().unwrap();
    Fresh {
        target: Target::Sqlite(dir.path().join("results.db")),
        _dir: Some(dir),
        pg_drop: None,
    }
}

/// The PostgreSQL server's URL, or `None` (with a note) when there is none outside CI.
#[cfg(feature = "postgres")]
fn postgres_url() -> Option<String> {
    match std::env::var("FITUP_TEST_POSTGRES") {
        Ok(u) if !u.trim().is_empty() => Some(u),
        _ => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("FITUP_TEST_POSTGRES is not set under CI=true: the PostgreSQL tests must run (.ci/run starts a server)");
            }
            // Straight to stderr: the test harness would swallow `eprintln!`.
            use std::io::Write;
            let _ = writeln!(
                std::io::stderr(),
                "note: PostgreSQL tests skipped: set FITUP_TEST_POSTGRES=postgres://user@host:port/db to run them"
            );
            None
        }
    }
}

/// A build without the `postgres` feature has no PostgreSQL back end to test.
#[cfg(not(feature = "postgres"))]
pub(crate) fn postgres() -> Option<Fresh> {
    None
}

/// A fresh database on the PostgreSQL server of `FITUP_TEST_POSTGRES` (created here,
/// dropped afterwards), or `None` with a note when there is none outside CI.
#[cfg(feature = "postgres")]
pub(crate) fn postgres() -> Option<Fresh> {
    static N: AtomicUsize = AtomicUsize::new(0);
    let admin = postgres_url()?;
    let name = format!(
        "fitup_t{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    );
    let mut c = postgres::Client::connect(&admin, postgres::NoTls)
        .unwrap_or_else(|e| panic!("cannot reach FITUP_TEST_POSTGRES ({admin}): {e}"));
    c.batch_execute(&format!("CREATE DATABASE {name}")).unwrap();
    // Same server and user, the new database.
    let (base, query) = match admin.split_once('?') {
        Some((b, q)) => (b.to_string(), format!("?{q}")),
        None => (admin.clone(), String::new()),
    };
    let scheme_end = base.find("://").unwrap() + 3;
    let url = match base[scheme_end..].find('/') {
        Some(i) => format!("{}/{name}{query}", &base[..scheme_end + i]),
        None => format!("{base}/{name}{query}"),
    };
    Some(Fresh {
        target: Target::Postgres(url),
        _dir: None,
        pg_drop: Some((admin, name)),
    })
}

/// Runs `check` on a fresh SQLite file and a fresh PostgreSQL database.
fn on_both(check: impl Fn(&Fresh)) {
    check(&sqlite());
    if let Some(pg) = postgres() {
        check(&pg);
    }
}

fn pose(x: f64, y: f64, z: f64, abc_deg: [f64; 3]) -> Transform {
    Transform::from_xyzabc(
        Vec3::new(x, y, z),
        abc_deg.map(f64::to_radians),
        AngleConvention::XyzFixed,
    )
}

fn sample_path(n: usize) -> PlannedPath {
    let poses: Vec<Transform> = (0..n)
        .map(|i| {
            pose(
                i as f64 * 1.5,
                200.0 - i as f64,
                751.25,
                [0.0, 90.0 * (i % 3) as f64 / 7.0, -12.5],
            )
        })
        .collect();
    let length = poses.windows(2).map(|w| w[0].distance_to(&w[1]).1).sum();
    PlannedPath {
        failure: None,
        poses,
        length_mm: length,
        rotation_rad: 0.75,
        raw_length_mm: length * 1.25,
        raw_rotation_rad: 0.8,
        iterations: 321,
        nodes: 77,
        pose_checks: 1000,
        edge_checks: 99,
        time_ms: 12.5,
        search_ms: 10.0,
        smoothing_ms: 2.5,
        resolution: SweepMethod::Stepwise {
            step_mm: 0.1,
            step_rad: 0.002,
        },
        // Not the default: a stored path must keep the rule it was planned with.
        tolerance_mm: 0.05,
        planner: "rrt_connect",
    }
}

fn assert_same_path(a: &PlannedPath, b: &PlannedPath) {
    assert_eq!(a.poses.len(), b.poses.len());
    for (p, q) in a.poses.iter().zip(&b.poses) {
        assert!(p.approx_eq(q, 1e-9, 1e-12), "{p:?} != {q:?}");
    }
    let mut a2 = a.clone();
    a2.poses = b.poses.clone();
    assert_eq!(&a2, b);
}

#[test]
fn every_stored_kind_round_trips() {
    on_both(|f| {
        let mut db = Database::open(&f.target).unwrap();
        assert_eq!(db.schema_version().unwrap(), fitup::db::SCHEMA_VERSION);
        let run = db
            .start_run(&NewRun {
                script: "scripts/x.rhai".into(),
                document: Some("models/cell.yaml".into()),
                script_hash: Some("00ff".into()),
                document_hash: None,
            })
            .unwrap();

        // A found path with its metadata, and a path that was not found.
        let path = sample_path(25);
        let meta = PathMeta {
            component: Some("screw4".into()),
            seed: Some(u64::MAX - 3),
            options: Some(serde_json::json!({"seed": 7, "disassemble": true})),
        };
        let id = db
            .save_path(Some(run), "screw4_into_hole1", &path, &meta)
            .unwrap();
        let mut lost = sample_path(0);
        lost.failure = Some(Failure::Exhausted(4));
        lost.resolution = SweepMethod::Continuous {
            contact_step_mm: 0.05,
        };
        lost.planner = "plan_assembly";
        let lost_id = db
            .save_path(None, "nowhere", &lost, &PathMeta::default())
            .unwrap();
        let back = db.path(id).unwrap();
        assert_eq!(
            (back.run_id, back.name.as_str(), &back.meta),
            (Some(run), "screw4_into_hole1", &meta)
        );
        assert_same_path(&path, &back.path);
        assert_eq!(db.path(lost_id).unwrap().path, lost);
        let q = |name: &str| PathQuery {
            name: Some(name.into()),
            ..Default::default()
        };
        assert_eq!(db.paths(&q("nowhere")).unwrap().len(), 1);
        assert_eq!(
            db.paths(&PathQuery {
                planner: Some("rrt_connect".into()),
                since: Some("2000-01-01".into()),
                ..Default::default()
            })
            .unwrap()
            .len(),
            1
        );
        assert!(db
            .paths(&PathQuery {
                since: Some("2999".into()),
                ..Default::default()
            })
            .unwrap()
            .is_empty());

        // A trajectory with a prismatic joint.
        let mut t = Trajectory::new(vec![JointKind::Revolute, JointKind::Prismatic]);
        for i in 0..5 {
            t.samples.push(TrajectorySample {
                t: i as f64 * 0.004,
                joints: vec![0.1 * i as f64, 12.5 - i as f64],
                tcp: pose(500.0, i as f64, 300.0, [180.0, 0.0, 5.0 * i as f64]),
            });
        }
        let tid = db
            .save_trajectory(Some(run), "weld", Some("mz07"), &t)
            .unwrap();
        let tb = db.trajectory(tid).unwrap();
        assert_eq!(
            (tb.name.as_str(), tb.robot.as_deref()),
            ("weld", Some("mz07"))
        );
        assert_eq!(tb.trajectory.joint_kinds, t.joint_kinds);
        assert_eq!(tb.trajectory.samples.len(), 5);
        for (a, b) in t.samples.iter().zip(&tb.trajectory.samples) {
            assert_eq!((a.t, &a.joints), (b.t, &b.joints));
            assert!(a.tcp.approx_eq(&b.tcp, 1e-9, 1e-12));
        }

        // A document snapshot (the demo cell's real poses and dimensions).
        let dir = tempfile::tempdir().unwrap();
        fitup::demo::write_cell(dir.path()).unwrap();
        let doc = fitup::document::Document::open(&dir.path().join("cell.yaml")).unwrap();
        let snap = Snapshot::of(&doc);
        assert!(snap.poses.len() >= 8 && !snap.dimensions.is_empty());
        assert!(snap.dimensions.iter().any(|d| d.1 == DimensionKind::Angle));
        db.save_snapshot(Some(run), &snap).unwrap();
        let (_, sb) = db.snapshots(Some(run)).unwrap().pop().unwrap();
        assert_eq!(sb.document, snap.document);
        let mut names: Vec<_> = snap.poses.iter().map(|p| p.0.clone()).collect();
        names.sort();
        assert_eq!(
            sb.poses.iter().map(|p| p.0.clone()).collect::<Vec<_>>(),
            names
        );
        for (n, t) in &sb.poses {
            let orig = &snap.poses.iter().find(|p| &p.0 == n).unwrap().1;
            assert!(orig.approx_eq(t, 1e-9, 1e-12));
        }
        let mut dims = snap.dimensions.clone();
        dims.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(sb.dimensions, dims);

        // Interference results.
        let pairs = vec![
            InterferencePair {
                a: "screw4".into(),
                b: "plate_b".into(),
                contact: Contact::Interfering {
                    depth: 0.25,
                    kind: InterferenceKind::SurfacesCross,
                },
            },
            InterferencePair {
                a: "screw4".into(),
                b: "plate_a".into(),
                contact: Contact::Interfering {
                    depth: 1.5,
                    kind: InterferenceKind::Contained {
                        inner: PairMember::Second,
                    },
                },
            },
            InterferencePair {
                a: "plate_b".into(),
                b: "table, top".into(),
                contact: Contact::Touching,
            },
        ];
        let iid = db
            .save_interference(Some(run), "after move", &pairs)
            .unwrap();
        assert_eq!(db.interference(iid).unwrap().pairs, pairs);

        // The run itself.
        db.finish_run(run, RunStatus::Failed, "line 1\nerror: x")
            .unwrap();
        let r = db.run(run).unwrap();
        assert_eq!(
            (r.status.as_str(), r.output.as_str()),
            ("failed", "line 1\nerror: x")
        );
        assert!(r.finished_at.unwrap() >= r.started_at);
        assert_eq!(r.document.as_deref(), Some("models/cell.yaml"));

        // Poses are queryable as columns.
        let rows = db
            .query(
                if db.dialect() == fitup::db::Dialect::Sqlite {
                    "SELECT COUNT(*), MAX(x_mm) FROM path_poses WHERE path_id = ?1"
                } else {
                    "SELECT COUNT(*), MAX(x_mm) FROM path_poses WHERE path_id = $1"
                },
                &[SqlValue::Int(id)],
            )
            .unwrap();
        assert_eq!(rows.rows[0][0].as_i64(), Some(25));
        assert!((rows.rows[0][1].as_f64().unwrap() - 36.0).abs() < 1e-9);
    });
}

#[test]
fn non_finite_values_are_refused_and_nothing_is_half_written() {
    on_both(|f| {
        let mut db = Database::open(&f.target).unwrap();
        let mut p = sample_path(5);
        p.length_mm = f64::NAN;
        let e = db
            .save_path(None, "bad", &p, &PathMeta::default())
            .unwrap_err();
        assert!(matches!(e, DbError::Invalid { .. }), "{e}");
        assert!(e.to_string().contains("path `bad`"), "{e}");
        assert!(db.paths(&PathQuery::default()).unwrap().is_empty());
        assert!(db
            .query("SELECT * FROM path_poses", &[])
            .unwrap()
            .rows
            .is_empty());
    });
}

#[test]
fn read_only_query_refuses_writes() {
    on_both(|f| {
        let mut db = Database::open(&f.target).unwrap();
        db.start_run(&NewRun::script("a.rhai")).unwrap();
        for sql in [
            "DELETE FROM runs",
            "INSERT INTO runs (script, started_at, status, fitup_version) VALUES ('x', 'now', 'ok', '0')",
            "DROP TABLE paths",
            "UPDATE runs SET status = 'ok'",
        ] {
            let e = db.query(sql, &[]).unwrap_err();
            assert!(matches!(e, DbError::WriteRefused { .. }), "{sql}: {e}");
        }
        // Two statements, the second a write: refused too.
        assert!(db.query("SELECT 1; DELETE FROM runs", &[]).is_err());
        if db.dialect() == fitup::db::Dialect::Postgres {
            // A function that writes, inside a SELECT.
            let e = db.query("SELECT nextval('runs_id_seq')", &[]).unwrap_err();
            assert!(matches!(e, DbError::WriteRefused { .. }), "{e}");
        }
        let rows = db.query("SELECT script FROM runs", &[]).unwrap();
        assert_eq!(rows.rows, vec![vec![SqlValue::Text("a.rhai".into())]]);
        // Ordinary writes still work after a refused query.
        db.start_run(&NewRun::script("b.rhai")).unwrap();
        assert_eq!(db.runs().unwrap().len(), 2);
    });
}

/// Writes a v1 database by hand (what fitup 0.1 with schema 1 stored).
#[test]
fn migration_from_the_previous_schema_keeps_the_data() {
    on_both(|f| {
        {
            let mut old = Database::open_at_version(&f.target, 1).unwrap();
            assert_eq!(old.schema_version().unwrap(), 1);
            // The v1 tables exist, the v2 ones not yet.
            assert!(old.query("SELECT COUNT(*) FROM trajectories", &[]).is_err());
            let run = old.start_run(&NewRun::script("old.rhai")).unwrap();
            raw_exec(
                &f.target,
                &format!(
                    "INSERT INTO paths (run_id, name, planner, found, reason, pose_count, length_mm, rotation_rad, raw_length_mm, raw_rotation_rad, iterations, nodes, pose_checks, edge_checks, time_ms, resolution, resolution_mm, resolution_rad, created_at) \
                     VALUES ({run}, 'old', 'rrt', 1, NULL, 2, 10.0, 0.0, 10.0, 0.0, 5, 6, 7, 8, 1.5, 'stepwise', 0.1, 0.002, '2026-01-01T00:00:00.000Z');
                     INSERT INTO path_poses VALUES (1, 0, 0,0,0, 0,0,0, 1,0,0,0);
                     INSERT INTO path_poses VALUES (1, 1, 10,0,0, 0,0,0, 1,0,0,0);"
                ),
            );
        }
        let mut db = Database::open(&f.target).unwrap();
        assert_eq!(db.schema_version().unwrap(), fitup::db::SCHEMA_VERSION);
        let old = db.path(1).unwrap();
        assert_eq!(
            (
                old.name.as_str(),
                old.path.planner,
                old.meta.component.clone()
            ),
            ("old", "rrt", None)
        );
        assert_eq!(old.path.poses.len(), 2);
        assert!((old.path.poses[1].translation().x - 10.0).abs() < 1e-12);
        // Schema 1 did not record the tolerance: read as the default every planner used.
        assert_eq!(old.path.tolerance_mm, fitup::collision::DEFAULT_TOLERANCE);
        assert_eq!(db.runs().unwrap()[0].script, "old.rhai");
        // The new kinds can be stored now.
        let t = Trajectory::new(vec![JointKind::Revolute]);
        db.save_trajectory(None, "empty", None, &t).unwrap();
        let versions = db
            .query("SELECT version FROM schema_version ORDER BY version", &[])
            .unwrap();
        assert_eq!(
            versions.rows,
            vec![
                vec![SqlValue::Int(1)],
                vec![SqlValue::Int(2)],
                vec![SqlValue::Int(3)],
                vec![SqlValue::Int(4)],
                vec![SqlValue::Int(5)]
            ]
        );
    });
}

fn raw_exec(target: &Target, sql: &str) {
    match target {
        Target::Sqlite(p) => rusqlite::Connection::open(p)
            .unwrap()
            .execute_batch(sql)
            .unwrap(),
        #[cfg(feature = "postgres")]
        Target::Postgres(u) => postgres::Client::connect(u, postgres::NoTls)
            .unwrap()
            .batch_execute(sql)
            .unwrap(),
        #[cfg(not(feature = "postgres"))]
        Target::Postgres(_) => unreachable!("no PostgreSQL back end in this build"),
    }
}

#[test]
fn a_database_from_a_newer_fitup_is_refused() {
    on_both(|f| {
        Database::open(&f.target).unwrap();
        raw_exec(
            &f.target,
            "INSERT INTO schema_version (version, description, applied_at, fitup_version) VALUES (99, 'from the future', 'x', '9.0.0')",
        );
        let e = Database::open(&f.target).unwrap_err();
        match &e {
            DbError::NewerSchema {
                found, supported, ..
            } => {
                assert_eq!((*found, *supported), (99, fitup::db::SCHEMA_VERSION))
            }
            other => panic!("expected NewerSchema, got {other}"),
        }
        assert!(e.to_string().contains("newer fitup"), "{e}");
        // The command line says the same and changes nothing.
        let out = common::fitup()
            .args(["db", "runs", "--db", &db_arg(&f.target)])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{}", common::text(&out));
        assert!(
            common::text(&out).contains("written by a newer fitup (schema version 99"),
            "{}",
            common::text(&out)
        );
    });
}

#[test]
fn a_file_that_is_not_a_database_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fitup.db");
    std::fs::write(&p, "runs:\n  - not sqlite at all\n".repeat(100)).unwrap();
    let e = Database::open(&Target::Sqlite(p.clone())).unwrap_err();
    // Refused before SQLite touches it (the write rule: never turn a user's file into
    // a database), the file left as it was.
    assert!(matches!(e, DbError::Foreign { .. }), "{e}");
    assert!(
        e.to_string().contains(&p.display().to_string())
            && e.to_string().contains("not a SQLite file"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(&p).unwrap().len(),
        2800,
        "the file is left alone"
    );
    let e = Database::open(&Target::Sqlite(dir.path().join("missing/x.db"))).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
}

fn db_arg(t: &Target) -> String {
    match t {
        Target::Sqlite(p) => p.display().to_string(),
        Target::Postgres(u) => u.clone(),
    }
}

/// A project with the demo cell and a script that plans one short path and saves it
/// `count` times (or forever when `count` is 0) under `prefix`.
fn writer_project(count: usize) -> tempfile::TempDir {
    let dir = common::project();
    let body = if count == 0 {
        "let i = 0; loop { db.save(path, `k${i}`, #{component: \"screw4\"}); i += 1; }".to_string()
    } else {
        format!("for i in 0..{count} {{ db.save(path, `${{PREFIX}}_${{i}}`, #{{component: \"screw4\"}}); }}")
    };
    for w in 0..4 {
        std::fs::write(
            dir.path().join(format!("scripts/writer{w}.rhai")),
            format!(
                "const PREFIX = \"w{w}\";
let doc = open_doc(\"models/cell.yaml\");
let db = open_db();
let start = doc.component(\"screw4\").transform;
let path = doc.plan_path(\"screw4\", translation([0, 0, 40]) * start, #{{seed: {w}}});
assert(path.found, path.reason);
{body}
print(`saved by run ${{db.run}}`);
"
            ),
        )
        .unwrap();
    }
    dir
}

/// Processes opening a new SQLite database at the same moment: SQLite answers the
/// switch to WAL with "database is locked" at once, without waiting; every run must
/// still be recorded (one in four was lost to a warning before).
#[test]
fn processes_opening_a_new_database_together_all_record_their_run() {
    let dir = common::project();
    std::fs::write(
        dir.path().join("scripts/open.rhai"),
        "let db = open_db();\nprint(`run ${db.run}`);\n",
    )
    .unwrap();
    for trial in 0..4 {
        let db = format!("t{trial}.db");
        let children: Vec<_> = (0..6)
            .map(|_| {
                common::fitup()
                    .current_dir(dir.path())
                    .args(["run", "scripts/open.rhai", "--db", &db])
                    .stdout(Stdio::piped())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        let mut ids: Vec<i64> = children
            .into_iter()
            .map(|c| {
                let out = c.wait_with_output().unwrap();
                let text = common::text(&out);
                assert!(out.status.success(), "{text}");
                assert!(!text.contains("warning"), "trial {trial}: {text}");
                text.lines()
                    .find_map(|l| l.strip_prefix("run "))
                    .and_then(|n| n.trim().parse().ok())
                    .unwrap_or_else(|| panic!("no run id printed: {text}"))
            })
            .collect();
        ids.sort_unstable();
        assert_eq!(ids, (1..=6).collect::<Vec<i64>>(), "trial {trial}");
    }
}

#[test]
fn four_concurrent_writer_processes_lose_nothing() {
    on_both(|f| {
        let dir = writer_project(200);
        let db = db_arg(&f.target);
        let children: Vec<_> = (0..4)
            .map(|w| {
                common::fitup()
                    .current_dir(dir.path())
                    .args(["run", &format!("scripts/writer{w}.rhai"), "--db", &db])
                    .stdout(Stdio::piped())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for c in children {
            let out = c.wait_with_output().unwrap();
            assert!(out.status.success(), "{}", common::text(&out));
        }
        let mut d = Database::open(&f.target).unwrap();
        let paths = d
            .paths(&PathQuery {
                without_poses: true,
                ..Default::default()
            })
            .unwrap();
        assert_eq!(paths.len(), 800);
        let mut names: Vec<_> = paths.iter().map(|p| p.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 800, "every result stored once");
        for (id, said, rows) in pose_counts(&mut d).unwrap() {
            assert!(
                said >= 2 && said == rows,
                "path {id}: {said} poses said, {rows} stored"
            );
        }
        // Four recorded runs, each ok, each owning its 200 paths.
        let runs = d.runs().unwrap();
        assert_eq!(runs.len(), 4);
        for r in &runs {
            assert_eq!(r.status, "ok", "{r:?}");
            assert!(
                r.output.contains(&format!("saved by run {}", r.id)),
                "{r:?}"
            );
            let mine = d
                .paths(&PathQuery {
                    run_id: Some(r.id),
                    without_poses: true,
                    ..Default::default()
                })
                .unwrap();
            assert_eq!(mine.len(), 200);
        }
    });
}

#[test]
fn kill_9_during_writes_leaves_a_consistent_database() {
    on_both(|f| {
        let dir = writer_project(0);
        let db = db_arg(&f.target);
        let mut child = common::fitup()
            .current_dir(dir.path())
            .args([
                "run",
                "scripts/writer0.rhai",
                "--db",
                &db,
                "--max-operations",
                "1000000000000",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // Wait until it is writing steadily, then kill it without warning.
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            assert!(
                Instant::now() < deadline,
                "the writer never stored 30 paths"
            );
            std::thread::sleep(Duration::from_millis(100));
            // The connection closes before the kill (end of this block).
            if let Ok(mut x) = Database::open(&f.target) {
                if x.paths(&PathQuery {
                    without_poses: true,
                    ..Default::default()
                })
                .map(|p| p.len())
                .unwrap_or(0)
                    >= 30
                {
                    break;
                }
            }
        }
        child.kill().unwrap(); // SIGKILL on Unix
        child.wait().unwrap();
        let mut d = Database::open(&f.target).unwrap();
        if d.dialect() == fitup::db::Dialect::Sqlite {
            let ok = d.query("PRAGMA integrity_check", &[]).unwrap();
            assert_eq!(ok.rows, vec![vec![SqlValue::Text("ok".into())]]);
        }
        let counts = pose_counts(&mut d).unwrap();
        assert!(counts.len() >= 30);
        for (id, said, rows) in counts {
            assert!(
                said >= 2 && said == rows,
                "path {id}: {said} poses said, {rows} stored"
            );
        }
        // The killed run stays `running` (it never finished) and the database takes
        // new results.
        assert_eq!(d.runs().unwrap()[0].status, "running");
        d.save_path(None, "after", &sample_path(3), &PathMeta::default())
            .unwrap();
    });
}

#[test]
fn the_example_is_recorded_and_the_cli_lists_shows_exports_and_diffs() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("results.db");
    let db = file.display().to_string();
    let root = common::repo();
    for _ in 0..2 {
        let out = common::run_in(&root, &["run", "scripts/db_paths.rhai", "--db", &db]);
        assert!(out.status.success(), "{}", common::text(&out));
    }
    let cli = |args: &[&str]| {
        let mut all = vec!["db"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--db", &db]);
        let out = common::run_in(&root, &all);
        assert!(out.status.success(), "{all:?}: {}", common::text(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    let runs = cli(&["runs"]);
    assert_eq!(runs.matches("scripts/db_paths.rhai").count(), 2, "{runs}");
    assert_eq!(runs.matches(" ok ").count(), 2, "{runs}");
    let paths = cli(&["paths"]);
    assert_eq!(paths.matches("screw4_into_hole1").count(), 2, "{paths}");
    assert!(paths.contains("screw5_into_hole2"), "{paths}");
    let show = cli(&["show", "path:1"]);
    assert!(
        show.contains("component  screw4") && show.contains("X 600 Y 650 Z 750 A "),
        "{show}"
    );
    let csv = cli(&["export", "path:1", "--csv"]);
    assert!(
        csv.starts_with(
            "index,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg\n0,600.000000,650.000000,750.000000"
        ),
        "{csv}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&cli(&["export", "run:1", "--json"])).unwrap();
    assert_eq!(json["paths"].as_array().unwrap().len(), 2);
    assert_eq!(json["status"], "ok");
    assert!(json["output"].as_str().unwrap().contains("still holds"));
    assert!(json["snapshots"][0]["poses_xyzabc_mm_deg"]["screw4"].is_array());
    // Same seeds, same cell: the two runs agree.
    let diff = cli(&["diff", "1", "2"]);
    assert!(diff.contains("no differences"), "{diff}");
    // A run whose document changed: poses and dimensions differ.
    let mut d = Database::open(&Target::Sqlite(file.clone())).unwrap();
    let run = d.start_run(&NewRun::script("edited")).unwrap();
    let mut snap = d.snapshots(Some(1)).unwrap().pop().unwrap().1;
    snap.poses[0].1 = Transform::from_translation(Vec3::new(0.0, 0.0, 5.0)).then(&snap.poses[0].1);
    snap.dimensions[0].2 += 0.5;
    d.save_snapshot(Some(run), &snap).unwrap();
    let diff = cli(&["diff", "1", &run.to_string()]);
    assert!(diff.contains("moved 5.000 mm"), "{diff}");
    assert!(
        diff.contains("dimension D1@角度1: 0.000° → 28.648°"),
        "{diff}"
    );
    assert!(
        diff.contains("path screw4_into_hole1: only in run 1"),
        "{diff}"
    );
    // Usage errors are told apart.
    let out = common::run_in(&root, &["db", "show", "robot:1", "--db", &db]);
    assert_eq!(out.status.code(), Some(2));
    let out = common::run_in(&root, &["db", "show", "path:99", "--db", &db]);
    assert_eq!(out.status.code(), Some(1));
    assert!(common::text(&out).contains("no path with id 99"));
}

#[test]
fn a_script_query_cannot_write_and_script_paths_stay_in_the_project() {
    let dir = common::project();
    std::fs::write(
        dir.path().join("scripts/q.rhai"),
        "let db = open_db(\"results.db\");\nlet n = db.query(\"SELECT COUNT(*) AS n FROM runs\")[0].n;\nassert(n == 0);\ndb.query(\"DELETE FROM paths\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/q.rhai"]);
    assert_eq!(out.status.code(), Some(1));
    let t = common::text(&out);
    assert!(
        t.contains("q.rhai:4") && t.contains("db.query is read-only"),
        "{t}"
    );
    std::fs::write(
        dir.path().join("scripts/out.rhai"),
        "open_db(\"../escape.db\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/out.rhai"]);
    assert_eq!(out.status.code(), Some(1), "{}", common::text(&out));
    assert!(!dir.path().parent().unwrap().join("escape.db").exists());
    // No database is created by a run that does not use one.
    assert!(!dir.path().join("fitup.db").exists());
}

/// A small tmpfs mounted on a fresh folder (unmounted on drop): a real filesystem that
/// fills up or turns read-only. `None` where this process may not mount (not root).
struct SmallDisk(tempfile::TempDir);

impl SmallDisk {
    fn mount(size: &str) -> Option<SmallDisk> {
        let dir = tempfile::tempdir().unwrap();
        let ok = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!(
                "cannot mount a tmpfs here (needs root): full-disk and read-only media not tested"
            );
            return None;
        }
        Some(SmallDisk(dir))
    }

    fn remount_read_only(&self) {
        let s = std::process::Command::new("mount")
            .args(["-o", "remount,ro"])
            .arg(self.0.path())
            .status()
            .unwrap();
        assert!(s.success());
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount")
            .arg(self.0.path())
            .status();
    }
}

fn big_trajectory(n: usize) -> Trajectory {
    let mut t = Trajectory::new(vec![JointKind::Revolute; 6]);
    for i in 0..n {
        let x = i as f64;
        t.samples.push(TrajectorySample {
            t: x * 0.004,
            joints: (0..6).map(|j| (x * 0.37 + j as f64).sin()).collect(),
            tcp: pose(x, -x, 0.5 * x, [x % 90.0, 0.0, 0.0]),
        });
    }
    t
}

#[test]
fn a_full_disk_is_a_typed_error_and_earlier_results_survive() {
    let Some(disk) = SmallDisk::mount("1m") else {
        return;
    };
    let file = disk.0.path().join("fitup.db");
    let target = Target::Sqlite(file.clone());
    let mut db = Database::open(&target).unwrap();
    let kept = db
        .save_path(None, "kept", &sample_path(20), &PathMeta::default())
        .unwrap();
    // About 2.5 MB of samples on a 1 MB disk.
    let e = db
        .save_trajectory(None, "too big", None, &big_trajectory(10_000))
        .unwrap_err();
    assert!(matches!(e, DbError::DiskFull { .. }), "{e:?}");
    assert!(e.to_string().contains(&file.display().to_string()), "{e}");
    // The same connection and a new one still read the earlier result whole, and
    // nothing of the refused one.
    assert_eq!(db.path(kept).unwrap().path.poses.len(), 20);
    drop(db);
    let mut again = Database::open(&target).unwrap();
    assert_eq!(again.path(kept).unwrap().path.poses.len(), 20);
    assert!(again.trajectory_list(None).unwrap().is_empty());
}

#[test]
fn a_read_only_file_is_a_typed_error_and_its_results_stay_readable() {
    let Some(disk) = SmallDisk::mount("4m") else {
        return;
    };
    let file = disk.0.path().join("fitup.db");
    let target = Target::Sqlite(file.clone());
    let kept = {
        let mut db = Database::open(&target).unwrap();
        db.save_path(None, "kept", &sample_path(20), &PathMeta::default())
            .unwrap()
    };
    disk.remount_read_only();
    let e = Database::open(&target).unwrap_err();
    assert!(matches!(e, DbError::ReadOnly { .. }), "{e:?}");
    assert!(e.to_string().contains(&file.display().to_string()), "{e}");
    assert!(e.to_string().contains("read-only"), "{e}");
    // Nothing was lost: the file reads back once writable again.
    let s = std::process::Command::new("mount")
        .args(["-o", "remount,rw"])
        .arg(disk.0.path())
        .status()
        .unwrap();
    assert!(s.success());
    let mut db = Database::open(&target).unwrap();
    assert_eq!(db.path(kept).unwrap().path.poses.len(), 20);
}
