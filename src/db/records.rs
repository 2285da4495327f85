//! What is stored: runs, paths, trajectories, document snapshots, interference
//! results — each written in one transaction and read back whole.

use super::backend::{Raw, SqlValue, Tx};
use super::{now_utc, Database, DbError};
use crate::collision::{Contact, SweepMethod};
use crate::document::DimensionKind;
use crate::kinematics::{JointKind, Trajectory, TrajectorySample};
use crate::math::{AngleConvention, Transform, Vec3};
use crate::planning::{Failure, PlannedPath, PLANNER_NAMES};
use nalgebra::{Quaternion, UnitQuaternion};

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunStatus {
    /// Still running (or killed before it could say).
    Running,
    /// Finished without error.
    Ok,
    /// Stopped by an error.
    Failed,
    /// Cancelled (a newer save in watch mode).
    Cancelled,
}

impl RunStatus {
    /// The stored word: `running`, `ok`, `failed`, `cancelled`.
    pub fn as_str(self) -> &'static str {
        match self {
            RunStatus::Running => "running",
            RunStatus::Ok => "ok",
            RunStatus::Failed => "failed",
            RunStatus::Cancelled => "cancelled",
        }
    }
}

/// A run about to start.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NewRun {
    /// The script (or program), as the user named it.
    pub script: String,
    /// The document given with `--doc`, if any.
    pub document: Option<String>,
    /// Content hash of the script (hex).
    pub script_hash: Option<String>,
    /// Content hash of the document (hex).
    pub document_hash: Option<String>,
}

impl NewRun {
    /// A run of `script` with nothing else known.
    pub fn script(script: &str) -> Self {
        NewRun {
            script: script.to_string(),
            ..Default::default()
        }
    }
}

/// A stored run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    /// Key.
    pub id: i64,
    /// The script.
    pub script: String,
    /// The document, if any.
    pub document: Option<String>,
    /// Content hash of the script.
    pub script_hash: Option<String>,
    /// Content hash of the document.
    pub document_hash: Option<String>,
    /// Start (UTC, ISO 8601).
    pub started_at: String,
    /// End (UTC, ISO 8601); `None` while running or when the process died.
    pub finished_at: Option<String>,
    /// `running`, `ok`, `failed` or `cancelled`.
    pub status: String,
    /// What the run printed (the last 64 KiB).
    pub output: String,
    /// The fitup version that ran it.
    pub fitup_version: String,
}

/// What is known about a path beyond the [`PlannedPath`] itself.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PathMeta {
    /// The component the path moves (needed to follow or re-validate it).
    pub component: Option<String>,
    /// The planner's seed.
    pub seed: Option<u64>,
    /// The planning options as JSON.
    pub options: Option<serde_json::Value>,
}

/// A stored path.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredPath {
    /// Key.
    pub id: i64,
    /// The run that stored it.
    pub run_id: Option<i64>,
    /// The name it was stored under.
    pub name: String,
    /// When (UTC, ISO 8601).
    pub created_at: String,
    /// Component, seed, options.
    pub meta: PathMeta,
    /// The number of key poses (also when they were not read: [`PathQuery::without_poses`]).
    pub pose_count: usize,
    /// The path: key poses (mm), lengths (mm), rotation (rad), statistics.
    pub path: PlannedPath,
}

/// Which stored paths to read; unset fields match everything.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PathQuery {
    /// Exactly this name.
    pub name: Option<String>,
    /// Exactly this planner.
    pub planner: Option<String>,
    /// Exactly this component.
    pub component: Option<String>,
    /// Stored at or after this time (UTC, ISO 8601 or a prefix such as `2026-11-30`).
    pub since: Option<String>,
    /// Stored by this run.
    pub run_id: Option<i64>,
    /// Only the key poses' count, not the poses (listings).
    pub without_poses: bool,
}

/// A stored trajectory (robot program result).
#[derive(Debug, Clone, PartialEq)]
pub struct StoredTrajectory {
    /// Key.
    pub id: i64,
    /// The run that stored it.
    pub run_id: Option<i64>,
    /// The name it was stored under.
    pub name: String,
    /// The robot that ran it.
    pub robot: Option<String>,
    /// When (UTC, ISO 8601).
    pub created_at: String,
    /// Samples: time (s), joints (rad or mm), TCP pose (mm).
    pub trajectory: Trajectory,
}

/// A document's state: every component's pose and every dimension's value.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// The document file.
    pub document: String,
    /// Component name and pose (part frame → world, mm).
    pub poses: Vec<(String, Transform)>,
    /// Dimension full name, kind and internal value (mm or rad).
    pub dimensions: Vec<(String, DimensionKind, f64)>,
}

impl Snapshot {
    /// The snapshot of an open document.
    pub fn of(doc: &crate::document::Document) -> Self {
        let poses = doc
            .components()
            .iter()
            .map(|c| (c.name.clone(), c.transform))
            .collect();
        let dimensions = doc
            .dimensions()
            .into_iter()
            .filter_map(|n| doc.dimension(&n).ok())
            .map(|d| (d.name, d.kind, d.value))
            .collect();
        Snapshot {
            document: doc.path().display().to_string(),
            poses,
            dimensions,
        }
    }
}

/// One pair of an interference result: the two components and the verdict.
/// Stored as the verdict's words ([`Contact::state_name`], depth in mm,
/// [`Contact::kind_text`]), read back by [`Contact::from_text`].
#[derive(Debug, Clone, PartialEq)]
pub struct InterferencePair {
    /// First component.
    pub a: String,
    /// Second component.
    pub b: String,
    /// The verdict (its depth in mm).
    pub contact: Contact,
}

impl InterferencePair {
    /// `separate`, `touching` or `interfering`.
    pub fn state(&self) -> &'static str {
        self.contact.state_name()
    }

    /// Penetration estimate (mm), 0 unless interfering.
    pub fn depth_mm(&self) -> f64 {
        self.contact.depth()
    }

    /// `surfaces cross`, `A inside B`, `boxes overlap`, or empty.
    pub fn kind(&self) -> String {
        self.contact.kind_text(&self.a, &self.b)
    }
}

/// A stored interference result.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredInterference {
    /// Key.
    pub id: i64,
    /// The run that stored it.
    pub run_id: Option<i64>,
    /// The name it was stored under.
    pub name: String,
    /// When (UTC, ISO 8601).
    pub created_at: String,
    /// The pairs.
    pub pairs: Vec<InterferencePair>,
}

/// The pose columns of `t`; `what` names it in the error (called only then: no
/// string is built per row of a 10,000-row result).
fn pose_values(t: &Transform, what: impl FnOnce() -> String) -> Result<Vec<SqlValue>, Raw> {
    let mut out = Vec::with_capacity(POSE_COLUMNS.len());
    push_pose_values(&mut out, t, what)?;
    Ok(out)
}

/// [`pose_values`] appended to a row (one allocation per row, not two).
fn push_pose_values(
    out: &mut Vec<SqlValue>,
    t: &Transform,
    what: impl FnOnce() -> String,
) -> Result<(), Raw> {
    if !t.is_finite() {
        return Err(Raw::other(format!("{} is not finite", what())));
    }
    let v = t.to_xyzabc_deg(AngleConvention::default());
    let q = t.rotation();
    let c = q.quaternion().coords; // i, j, k, w
    out.extend([
        v[0].into(),
        v[1].into(),
        v[2].into(),
        v[3].into(),
        v[4].into(),
        v[5].into(),
        c[3].into(),
        c[0].into(),
        c[1].into(),
        c[2].into(),
    ]);
    Ok(())
}

const POSE_COLUMNS: [&str; 10] = [
    "x_mm", "y_mm", "z_mm", "a_deg", "b_deg", "c_deg", "qw", "qx", "qy", "qz",
];

/// A pose from `x_mm, y_mm, z_mm, qw, qx, qy, qz` (the degrees are for queries only).
fn pose_from(row: &[SqlValue]) -> Result<Transform, Raw> {
    let f = |i: usize| {
        row.get(i)
            .and_then(SqlValue::as_f64)
            .ok_or_else(|| Raw::other(format!("pose column {i} is not a number")))
    };
    let q = Quaternion::new(f(3)?, f(4)?, f(5)?, f(6)?);
    if q.norm() < 1e-9 {
        return Err(Raw::other("a stored rotation quaternion is zero"));
    }
    Ok(Transform::from_parts(
        Vec3::new(f(0)?, f(1)?, f(2)?),
        UnitQuaternion::from_quaternion(q),
    ))
}

fn text(v: &SqlValue) -> Option<String> {
    v.as_str().map(str::to_string)
}

fn int(v: &SqlValue) -> i64 {
    v.as_i64().unwrap_or(0)
}

fn real(v: &SqlValue) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

/// The `&'static str` planner name for a stored one (paths carry static names).
fn planner_name(name: &str) -> &'static str {
    if let Some(n) = PLANNER_NAMES.iter().find(|n| **n == name) {
        return n;
    }
    // Names outside the built-in list (tests, future planners) are interned once.
    static OTHERS: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let mut others = OTHERS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(n) = others.iter().find(|n| **n == name) {
        return n;
    }
    let leaked: &'static str = Box::leak(name.to_string().into_boxed_str());
    others.push(leaked);
    leaked
}

/// The failure whose message is `reason`.
fn failure_from(reason: &str) -> Failure {
    let known = [
        Failure::IterationLimit,
        Failure::TimeLimit,
        Failure::StartInCollision,
        Failure::GoalInCollision,
        Failure::StartOutOfBounds,
        Failure::GoalOutOfBounds,
        Failure::Cancelled,
    ];
    if let Some(f) = known.iter().find(|f| f.to_string() == reason) {
        return *f;
    }
    let stage = reason
        .rsplit(' ')
        .next()
        .and_then(|s| s.trim_end_matches(')').parse().ok())
        .unwrap_or(0);
    Failure::Exhausted(stage)
}

/// A JSON array of numbers (what [`Database::save_trajectory`] writes), read with
/// the standard float parser: exact round trip and faster than a general JSON parser
/// for the 10,000s of samples of a trajectory. Anything else goes to `serde_json`.
fn parse_joints(text: &str) -> Result<Vec<f64>, Raw> {
    let inner = text
        .trim()
        .strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'));
    if let Some(inner) = inner {
        if inner.trim().is_empty() {
            return Ok(Vec::new());
        }
        if let Ok(v) = inner
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<Vec<_>, _>>()
        {
            return Ok(v);
        }
    }
    serde_json::from_str(text).map_err(|e| Raw::other(format!("stored joints `{text}`: {e}")))
}

fn joint_kind_name(k: JointKind) -> &'static str {
    match k {
        JointKind::Fixed => "fixed",
        JointKind::Revolute => "revolute",
        JointKind::Prismatic => "prismatic",
    }
}

fn finite(what: &str, values: &[f64]) -> Result<(), Raw> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Raw::other(format!("{what} has a non-finite number")))
    }
}

const PATH_COLUMNS: &str = "id, run_id, name, created_at, component, seed, options, planner, found, reason, pose_count, length_mm, rotation_rad, raw_length_mm, raw_rotation_rad, iterations, nodes, pose_checks, edge_checks, time_ms, resolution, resolution_mm, resolution_rad, search_ms, smoothing_ms, tolerance_mm";

impl Database {
    fn invalid(&self, what: &str, e: DbError) -> DbError {
        match e {
            DbError::Sql { during, cause, .. }
                if cause.message.contains("non-finite") || cause.message.contains("not finite") =>
            {
                DbError::Invalid {
                    what: what.to_string(),
                    during,
                    cause,
                }
            }
            other => other,
        }
    }

    /// Records the start of a run; returns its id.
    pub fn start_run(&mut self, run: &NewRun) -> Result<i64, DbError> {
        let now = now_utc();
        self.transaction("storing the run", |tx| {
            tx.insert_id(
                "INSERT INTO runs (script, document, script_hash, document_hash, started_at, status, output, fitup_version) VALUES (?, ?, ?, ?, ?, ?, '', ?)",
                &[
                    run.script.as_str().into(),
                    run.document.clone().into(),
                    run.script_hash.clone().into(),
                    run.document_hash.clone().into(),
                    now.as_str().into(),
                    RunStatus::Running.as_str().into(),
                    env!("CARGO_PKG_VERSION").into(),
                ],
            )
        })
    }

    /// Records how run `id` ended and what it printed.
    pub fn finish_run(&mut self, id: i64, status: RunStatus, output: &str) -> Result<(), DbError> {
        let now = now_utc();
        let n = self.transaction("finishing the run", |tx| {
            tx.exec(
                "UPDATE runs SET finished_at = ?, status = ?, output = ? WHERE id = ?",
                &[
                    now.as_str().into(),
                    status.as_str().into(),
                    output.into(),
                    id.into(),
                ],
            )
        })?;
        if n == 0 {
            return Err(self.not_found("run", id));
        }
        Ok(())
    }

    fn not_found(&self, what: &'static str, id: i64) -> DbError {
        DbError::NotFound {
            what,
            id,
            target: self.target.clone(),
        }
    }

    /// Every run, oldest first.
    pub fn runs(&mut self) -> Result<Vec<RunRecord>, DbError> {
        let rows = self.read("reading runs", |tx| {
            tx.rows("SELECT id, script, document, script_hash, document_hash, started_at, finished_at, status, output, fitup_version FROM runs ORDER BY id", &[])
        })?;
        Ok(rows
            .iter()
            .map(|r| RunRecord {
                id: int(&r[0]),
                script: text(&r[1]).unwrap_or_default(),
                document: text(&r[2]),
                script_hash: text(&r[3]),
                document_hash: text(&r[4]),
                started_at: text(&r[5]).unwrap_or_default(),
                finished_at: text(&r[6]),
                status: text(&r[7]).unwrap_or_default(),
                output: text(&r[8]).unwrap_or_default(),
                fitup_version: text(&r[9]).unwrap_or_default(),
            })
            .collect())
    }

    /// Run `id`.
    pub fn run(&mut self, id: i64) -> Result<RunRecord, DbError> {
        self.runs()?
            .into_iter()
            .find(|r| r.id == id)
            .ok_or_else(|| self.not_found("run", id))
    }

    /// Stores a path (found or not) with its key poses in one transaction; returns
    /// its id.
    pub fn save_path(
        &mut self,
        run_id: Option<i64>,
        name: &str,
        path: &PlannedPath,
        meta: &PathMeta,
    ) -> Result<i64, DbError> {
        let now = now_utc();
        let (res, res_mm, res_rad) = match path.resolution {
            SweepMethod::Continuous { contact_step_mm } => ("continuous", contact_step_mm, None),
            SweepMethod::Stepwise { step_mm, step_rad } => ("stepwise", step_mm, Some(step_rad)),
        };
        let options = meta.options.as_ref().map(|o| o.to_string());
        let r = self.transaction("storing the path", |tx| {
            finite(
                "the path",
                &[
                    path.length_mm,
                    path.rotation_rad,
                    path.raw_length_mm,
                    path.raw_rotation_rad,
                    path.time_ms,
                    path.search_ms,
                    path.smoothing_ms,
                    res_mm,
                    path.tolerance_mm,
                ],
            )?;
            let poses = path
                .poses
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let mut row = Vec::with_capacity(2 + POSE_COLUMNS.len());
                    row.extend([SqlValue::Null, SqlValue::Int(i as i64)]);
                    push_pose_values(&mut row, p, || format!("key pose {i}"))?;
                    Ok(row)
                })
                .collect::<Result<Vec<_>, Raw>>()?;
            let id = tx.insert_id(
                "INSERT INTO paths (run_id, name, created_at, component, seed, options, planner, found, reason, pose_count, length_mm, rotation_rad, raw_length_mm, raw_rotation_rad, iterations, nodes, pose_checks, edge_checks, time_ms, resolution, resolution_mm, resolution_rad, search_ms, smoothing_ms, tolerance_mm) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                &[
                    run_id.into(),
                    name.into(),
                    now.as_str().into(),
                    meta.component.clone().into(),
                    meta.seed.map(|s| s as i64).into(),
                    options.clone().into(),
                    path.planner.into(),
                    SqlValue::Int(i64::from(path.found())),
                    path.failure.map(|f| f.to_string()).into(),
                    SqlValue::Int(path.poses.len() as i64),
                    path.length_mm.into(),
                    path.rotation_rad.into(),
                    path.raw_length_mm.into(),
                    path.raw_rotation_rad.into(),
                    SqlValue::Int(path.iterations as i64),
                    SqlValue::Int(path.nodes as i64),
                    SqlValue::Int(path.pose_checks as i64),
                    SqlValue::Int(path.edge_checks as i64),
                    path.time_ms.into(),
                    res.into(),
                    res_mm.into(),
                    res_rad.into(),
                    path.search_ms.into(),
                    path.smoothing_ms.into(),
                    path.tolerance_mm.into(),
                ],
            )?;
            let poses: Vec<Vec<SqlValue>> = poses
                .into_iter()
                .map(|mut r| {
                    r[0] = SqlValue::Int(id);
                    r
                })
                .collect();
            let mut cols = vec!["path_id", "idx"];
            cols.extend(POSE_COLUMNS);
            tx.insert_many("path_poses", &cols, &poses)?;
            Ok(id)
        });
        r.map_err(|e| self.invalid(&format!("path `{name}`"), e))
    }

    /// Stored paths matching `q`, oldest first.
    pub fn paths(&mut self, q: &PathQuery) -> Result<Vec<StoredPath>, DbError> {
        let mut sql = format!("SELECT {PATH_COLUMNS} FROM paths WHERE 1 = 1");
        let mut params = Vec::new();
        for (col, v) in [
            ("name", &q.name),
            ("planner", &q.planner),
            ("component", &q.component),
        ] {
            if let Some(v) = v {
                sql.push_str(&format!(" AND {col} = ?"));
                params.push(SqlValue::from(v.as_str()));
            }
        }
        if let Some(s) = &q.since {
            sql.push_str(" AND created_at >= ?");
            params.push(s.as_str().into());
        }
        if let Some(r) = q.run_id {
            sql.push_str(" AND run_id = ?");
            params.push(r.into());
        }
        sql.push_str(" ORDER BY id");
        let with_poses = !q.without_poses;
        self.read("reading paths", |tx| {
            let rows = tx.rows(&sql, &params)?;
            rows.iter().map(|r| path_from(tx, r, with_poses)).collect()
        })
    }

    /// Path `id` with its key poses.
    pub fn path(&mut self, id: i64) -> Result<StoredPath, DbError> {
        let sql = format!("SELECT {PATH_COLUMNS} FROM paths WHERE id = ?");
        let found = self.read("reading the path", |tx| {
            let rows = tx.rows(&sql, &[id.into()])?;
            rows.first().map(|r| path_from(tx, r, true)).transpose()
        })?;
        found.ok_or_else(|| self.not_found("path", id))
    }

    /// Stores a trajectory with its samples in one transaction; returns its id.
    pub fn save_trajectory(
        &mut self,
        run_id: Option<i64>,
        name: &str,
        robot: Option<&str>,
        t: &Trajectory,
    ) -> Result<i64, DbError> {
        let now = now_utc();
        let kinds = serde_json::Value::from(
            t.joint_kinds
                .iter()
                .map(|k| joint_kind_name(*k))
                .collect::<Vec<_>>(),
        )
        .to_string();
        let r = self.transaction("storing the trajectory", |tx| {
            let mut samples = Vec::with_capacity(t.samples.len());
            for (i, s) in t.samples.iter().enumerate() {
                if !s.t.is_finite() || !s.joints.iter().all(|v| v.is_finite()) {
                    return Err(Raw::other(format!("sample {i} has a non-finite number")));
                }
                let mut row = Vec::with_capacity(4 + POSE_COLUMNS.len());
                row.extend([
                    SqlValue::Null,
                    SqlValue::Int(i as i64),
                    s.t.into(),
                    serde_json::to_string(&s.joints)
                        .map_err(|e| Raw::other(e.to_string()))?
                        .into(),
                ]);
                push_pose_values(&mut row, &s.tcp, || format!("the TCP of sample {i}"))?;
                samples.push(row);
            }
            let id = tx.insert_id(
                "INSERT INTO trajectories (run_id, name, robot, joint_kinds, sample_count, duration_s, created_at) VALUES (?, ?, ?, ?, ?, ?, ?)",
                &[
                    run_id.into(),
                    name.into(),
                    robot.into(),
                    kinds.as_str().into(),
                    SqlValue::Int(t.samples.len() as i64),
                    t.duration().into(),
                    now.as_str().into(),
                ],
            )?;
            for r in &mut samples {
                r[0] = SqlValue::Int(id);
            }
            let mut cols = vec!["trajectory_id", "idx", "t_s", "joints"];
            cols.extend(POSE_COLUMNS);
            tx.insert_many("trajectory_samples", &cols, &samples)?;
            Ok(id)
        });
        r.map_err(|e| self.invalid(&format!("trajectory `{name}`"), e))
    }

    /// Trajectory `id` with its samples.
    pub fn trajectory(&mut self, id: i64) -> Result<StoredTrajectory, DbError> {
        let found = self.read("reading the trajectory", |tx| {
            let head = tx.rows(
                "SELECT id, run_id, name, robot, joint_kinds, created_at FROM trajectories WHERE id = ?",
                &[id.into()],
            )?;
            let Some(h) = head.first() else {
                return Ok(None);
            };
            let kinds: Vec<String> =
                serde_json::from_str(h[4].as_str().unwrap_or("[]")).map_err(|e| Raw::other(e.to_string()))?;
            let joint_kinds = kinds
                .iter()
                .map(|k| match k.as_str() {
                    "revolute" => JointKind::Revolute,
                    "prismatic" => JointKind::Prismatic,
                    _ => JointKind::Fixed,
                })
                .collect();
            let mut samples = Vec::new();
            tx.each_row(
                "SELECT t_s, joints, x_mm, y_mm, z_mm, qw, qx, qy, qz FROM trajectory_samples WHERE trajectory_id = ? ORDER BY idx",
                &[id.into()],
                &mut |r| {
                    samples.push(TrajectorySample {
                        t: real(&r[0]),
                        joints: parse_joints(r[1].as_str().unwrap_or("[]"))?,
                        tcp: pose_from(&r[2..])?,
                    });
                    Ok(())
                },
            )?;
            Ok(Some(StoredTrajectory {
                id,
                run_id: h[1].as_i64(),
                name: text(&h[2]).unwrap_or_default(),
                robot: text(&h[3]),
                created_at: text(&h[5]).unwrap_or_default(),
                trajectory: Trajectory {
                    samples,
                    joint_kinds,
                },
            }))
        })?;
        found.ok_or_else(|| self.not_found("trajectory", id))
    }

    /// Ids and names of the stored trajectories (of one run if `run_id` is given).
    pub fn trajectory_list(
        &mut self,
        run_id: Option<i64>,
    ) -> Result<Vec<(i64, String, i64)>, DbError> {
        let (sql, p) = match run_id {
            Some(r) => (
                "SELECT id, name, sample_count FROM trajectories WHERE run_id = ? ORDER BY id",
                vec![r.into()],
            ),
            None => (
                "SELECT id, name, sample_count FROM trajectories ORDER BY id",
                vec![],
            ),
        };
        let rows = self.read("reading trajectories", |tx| tx.rows(sql, &p))?;
        Ok(rows
            .iter()
            .map(|r| (int(&r[0]), text(&r[1]).unwrap_or_default(), int(&r[2])))
            .collect())
    }

    /// Stores a document snapshot (poses and dimension values); returns its id.
    pub fn save_snapshot(&mut self, run_id: Option<i64>, s: &Snapshot) -> Result<i64, DbError> {
        let now = now_utc();
        let r = self.transaction("storing the snapshot", |tx| {
            let id = tx.insert_id(
                "INSERT INTO snapshots (run_id, document, created_at) VALUES (?, ?, ?)",
                &[
                    run_id.into(),
                    s.document.as_str().into(),
                    now.as_str().into(),
                ],
            )?;
            let mut poses = Vec::with_capacity(s.poses.len());
            for (name, t) in &s.poses {
                let mut row = vec![SqlValue::Int(id), name.as_str().into()];
                row.extend(pose_values(t, || format!("the pose of {name}"))?);
                poses.push(row);
            }
            let mut cols = vec!["snapshot_id", "component"];
            cols.extend(POSE_COLUMNS);
            tx.insert_many("component_poses", &cols, &poses)?;
            let dims = s
                .dimensions
                .iter()
                .map(|(n, k, v)| {
                    finite(&format!("dimension {n}"), &[*v])?;
                    Ok(vec![
                        SqlValue::Int(id),
                        n.as_str().into(),
                        match k {
                            DimensionKind::Length => "length",
                            DimensionKind::Angle => "angle",
                        }
                        .into(),
                        (*v).into(),
                    ])
                })
                .collect::<Result<Vec<_>, Raw>>()?;
            tx.insert_many(
                "dimension_values",
                &["snapshot_id", "name", "kind", "value"],
                &dims,
            )?;
            Ok(id)
        });
        r.map_err(|e| self.invalid("the document snapshot", e))
    }

    /// The snapshots stored by run `run_id` (or every snapshot), oldest first, with ids.
    pub fn snapshots(&mut self, run_id: Option<i64>) -> Result<Vec<(i64, Snapshot)>, DbError> {
        self.read("reading snapshots", |tx| {
            let heads = match run_id {
                Some(r) => tx.rows("SELECT id, document FROM snapshots WHERE run_id = ? ORDER BY id", &[r.into()])?,
                None => tx.rows("SELECT id, document FROM snapshots ORDER BY id", &[])?,
            };
            heads
                .iter()
                .map(|h| {
                    let id = int(&h[0]);
                    let poses = tx
                        .rows("SELECT component, x_mm, y_mm, z_mm, qw, qx, qy, qz FROM component_poses WHERE snapshot_id = ? ORDER BY component", &[id.into()])?
                        .iter()
                        .map(|r| Ok((text(&r[0]).unwrap_or_default(), pose_from(&r[1..])?)))
                        .collect::<Result<_, Raw>>()?;
                    let dimensions = tx
                        .rows("SELECT name, kind, value FROM dimension_values WHERE snapshot_id = ? ORDER BY name", &[id.into()])?
                        .iter()
                        .map(|r| {
                            let kind = if r[1].as_str() == Some("angle") {
                                DimensionKind::Angle
                            } else {
                                DimensionKind::Length
                            };
                            (text(&r[0]).unwrap_or_default(), kind, real(&r[2]))
                        })
                        .collect();
                    Ok((
                        id,
                        Snapshot {
                            document: text(&h[1]).unwrap_or_default(),
                            poses,
                            dimensions,
                        },
                    ))
                })
                .collect()
        })
    }

    /// Stores an interference result (its pairs) in one transaction; returns its id.
    pub fn save_interference(
        &mut self,
        run_id: Option<i64>,
        name: &str,
        pairs: &[InterferencePair],
    ) -> Result<i64, DbError> {
        let now = now_utc();
        let r = self.transaction("storing the interference result", |tx| {
            let id = tx.insert_id(
                "INSERT INTO interference_results (run_id, name, pair_count, created_at) VALUES (?, ?, ?, ?)",
                &[run_id.into(), name.into(), SqlValue::Int(pairs.len() as i64), now.as_str().into()],
            )?;
            let rows = pairs
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    finite("the depth", &[p.depth_mm()])?;
                    Ok(vec![
                        SqlValue::Int(id),
                        SqlValue::Int(i as i64),
                        p.a.as_str().into(),
                        p.b.as_str().into(),
                        p.state().into(),
                        p.depth_mm().into(),
                        p.kind().into(),
                    ])
                })
                .collect::<Result<Vec<_>, Raw>>()?;
            tx.insert_many("interference_pairs", &["result_id", "idx", "a", "b", "state", "depth_mm", "kind"], &rows)?;
            Ok(id)
        });
        r.map_err(|e| self.invalid(&format!("interference result `{name}`"), e))
    }

    /// Interference result `id` with its pairs.
    pub fn interference(&mut self, id: i64) -> Result<StoredInterference, DbError> {
        let found = self.read("reading the interference result", |tx| {
            let head = tx.rows("SELECT run_id, name, created_at FROM interference_results WHERE id = ?", &[id.into()])?;
            let Some(h) = head.first() else {
                return Ok(None);
            };
            let pairs = tx
                .rows("SELECT a, b, state, depth_mm, kind FROM interference_pairs WHERE result_id = ? ORDER BY idx", &[id.into()])?
                .iter()
                .map(|r| {
                    let (a, b) = (text(&r[0]).unwrap_or_default(), text(&r[1]).unwrap_or_default());
                    let state = text(&r[2]).unwrap_or_default();
                    let kind = text(&r[4]).unwrap_or_default();
                    let contact = Contact::from_text(&state, real(&r[3]), &kind, &a, &b)
                        .map_err(|e| Raw::other(format!("stored pair `{a}`–`{b}`: {e}")))?;
                    Ok(InterferencePair { a, b, contact })
                })
                .collect::<Result<Vec<_>, Raw>>()?;
            Ok(Some(StoredInterference {
                id,
                run_id: h[0].as_i64(),
                name: text(&h[1]).unwrap_or_default(),
                created_at: text(&h[2]).unwrap_or_default(),
                pairs,
            }))
        })?;
        found.ok_or_else(|| self.not_found("interference result", id))
    }

    /// Ids and names of the stored interference results (of one run if given).
    pub fn interference_list(
        &mut self,
        run_id: Option<i64>,
    ) -> Result<Vec<(i64, String, i64)>, DbError> {
        let (sql, p) = match run_id {
            Some(r) => ("SELECT id, name, pair_count FROM interference_results WHERE run_id = ? ORDER BY id", vec![r.into()]),
            None => ("SELECT id, name, pair_count FROM interference_results ORDER BY id", vec![]),
        };
        let rows = self.read("reading interference results", |tx| tx.rows(sql, &p))?;
        Ok(rows
            .iter()
            .map(|r| (int(&r[0]), text(&r[1]).unwrap_or_default(), int(&r[2])))
            .collect())
    }
}

fn path_from(tx: &mut dyn Tx, r: &[SqlValue], with_poses: bool) -> Result<StoredPath, Raw> {
    let id = int(&r[0]);
    let found = int(&r[8]) != 0;
    let poses = if with_poses {
        tx.rows(
            "SELECT x_mm, y_mm, z_mm, qw, qx, qy, qz FROM path_poses WHERE path_id = ? ORDER BY idx",
            &[id.into()],
        )?
        .iter()
        .map(|p| pose_from(p))
        .collect::<Result<Vec<_>, Raw>>()?
    } else {
        Vec::new()
    };
    let resolution = match r[20].as_str() {
        Some("continuous") => SweepMethod::Continuous {
            contact_step_mm: real(&r[21]),
        },
        _ => SweepMethod::Stepwise {
            step_mm: real(&r[21]),
            step_rad: real(&r[22]),
        },
    };
    let options = match r[6].as_str() {
        Some(s) => {
            Some(serde_json::from_str(s).map_err(|e| Raw::other(format!("stored options: {e}")))?)
        }
        None => None,
    };
    Ok(StoredPath {
        id,
        run_id: r[1].as_i64(),
        name: text(&r[2]).unwrap_or_default(),
        created_at: text(&r[3]).unwrap_or_default(),
        pose_count: int(&r[10]) as usize,
        meta: PathMeta {
            component: text(&r[4]),
            seed: r[5].as_i64().map(|s| s as u64),
            options,
        },
        path: PlannedPath {
            failure: if found {
                None
            } else {
                Some(failure_from(r[9].as_str().unwrap_or("")))
            },
            poses,
            length_mm: real(&r[11]),
            rotation_rad: real(&r[12]),
            raw_length_mm: real(&r[13]),
            raw_rotation_rad: real(&r[14]),
            iterations: int(&r[15]) as usize,
            nodes: int(&r[16]) as usize,
            pose_checks: int(&r[17]) as u64,
            edge_checks: int(&r[18]) as u64,
            time_ms: real(&r[19]),
            search_ms: real(&r[23]),
            smoothing_ms: real(&r[24]),
            resolution,
            // Rows from before schema 5 have none: every planner used the default
            // unless told otherwise.
            tolerance_mm: r[25]
                .as_f64()
                .unwrap_or(crate::collision::DEFAULT_TOLERANCE),
            planner: planner_name(r[7].as_str().unwrap_or("")),
        },
    })
}

/// The number of key poses a stored path says it has, and how many rows hold them,
/// for every path: equal in a consistent database (used by the fault tests and
/// `fitup db show`).
pub fn pose_counts(db: &mut Database) -> Result<Vec<(i64, i64, i64)>, DbError> {
    let rows = db.read("counting poses", |tx| {
        tx.rows(
            "SELECT p.id, p.pose_count, (SELECT COUNT(*) FROM path_poses q WHERE q.path_id = p.id) FROM paths p ORDER BY p.id",
            &[],
        )
    })?;
    Ok(rows
        .iter()
        .map(|r| (int(&r[0]), int(&r[1]), int(&r[2])))
        .collect())
}
