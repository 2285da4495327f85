//! Versioned migrations, kept in code. The table `schema_version` holds one row per
//! applied migration; a database whose highest version is above [`LATEST`] was written
//! by a newer fitup and is refused rather than misread.
//!
//! Every migration is written once with three placeholders that each back end fills
//! in: `{id}` (the auto-numbered key), `{int}` (64-bit integers), `{real}` (64-bit
//! floats) and `{clustered}` (SQLite's `WITHOUT ROWID` for small rows read by key
//! range).

use super::backend::{Dialect, Raw, SqlValue, Tx};

/// The schema version this fitup writes.
pub const LATEST: u32 = 5;

/// One step of the schema.
struct Migration {
    version: u32,
    what: &'static str,
    sql: &'static str,
}

const MIGRATIONS: &[Migration] = &[
    Migration {
        version: 1,
        what: "runs, paths and their key poses",
        sql: "
CREATE TABLE runs (
    id {id},
    script TEXT NOT NULL,
    document TEXT,
    script_hash TEXT,
    document_hash TEXT,
    started_at TEXT NOT NULL,
    finished_at TEXT,
    status TEXT NOT NULL,
    output TEXT NOT NULL DEFAULT '',
    fitup_version TEXT NOT NULL
);
CREATE TABLE paths (
    id {id},
    run_id {int} REFERENCES runs(id) ON DELETE SET NULL,
    name TEXT NOT NULL,
    planner TEXT NOT NULL,
    found {int} NOT NULL,
    reason TEXT,
    pose_count {int} NOT NULL,
    length_mm {real} NOT NULL,
    rotation_rad {real} NOT NULL,
    raw_length_mm {real} NOT NULL,
    raw_rotation_rad {real} NOT NULL,
    iterations {int} NOT NULL,
    nodes {int} NOT NULL,
    pose_checks {int} NOT NULL,
    edge_checks {int} NOT NULL,
    time_ms {real} NOT NULL,
    resolution TEXT NOT NULL,
    resolution_mm {real} NOT NULL,
    resolution_rad {real},
    created_at TEXT NOT NULL
);
CREATE INDEX paths_by_name ON paths(name, created_at);
CREATE TABLE path_poses (
    path_id {int} NOT NULL REFERENCES paths(id) ON DELETE CASCADE,
    idx {int} NOT NULL,
    x_mm {real} NOT NULL, y_mm {real} NOT NULL, z_mm {real} NOT NULL,
    a_deg {real} NOT NULL, b_deg {real} NOT NULL, c_deg {real} NOT NULL,
    qw {real} NOT NULL, qx {real} NOT NULL, qy {real} NOT NULL, qz {real} NOT NULL,
    PRIMARY KEY (path_id, idx)
) {clustered}",
    },
    Migration {
        version: 2,
        what: "path metadata, document snapshots, trajectories, interference results",
        sql: "
ALTER TABLE paths ADD COLUMN component TEXT;
ALTER TABLE paths ADD COLUMN seed {int};
ALTER TABLE paths ADD COLUMN options TEXT;
CREATE INDEX paths_by_planner ON paths(planner, created_at);
CREATE TABLE snapshots (
    id {id},
    run_id {int} REFERENCES runs(id) ON DELETE SET NULL,
    document TEXT NOT NULL,
    created_at TEXT NOT NULL
);
CREATE TABLE component_poses (
    snapshot_id {int} NOT NULL REFERENCES snapshots(id) ON DELETE CASCADE,
    component TEXT NOT NULL,
    x_mm {real} NOT NULL, y_mm {real} NOT NULL, z_mm {real} NOT NULL,
    a_deg {real} NOT NULL, b_deg {real} NOT NULL, c_deg {real} NOT NULL,
    qw {real} NOT NULL, qx {real} NOT NULL, qy {real} NOT NULL, qz {real} NOT NULL,
    PRIMARY KEY (snapshot_id, component)
);
CREATE TABLE dimension_values (
    snapshot_id {int} NOT NULL REFERENCES snapshots(id) ON DELETE CASCADE,
    name TEXT NOT NULL,
    kind TEXT NOT NULL,
    value {real} NOT NULL,
    PRIMARY KEY (snapshot_id, name)
);
CREATE TABLE trajectories (
    id {id},
    run_id {int} REFERENCES runs(id) ON DELETE SET NULL,
    name TEXT NOT NULL,
    robot TEXT,
    joint_kinds TEXT NOT NULL,
    sample_count {int} NOT NULL,
    duration_s {real} NOT NULL,
    created_at TEXT NOT NULL
);
CREATE TABLE trajectory_samples (
    trajectory_id {int} NOT NULL REFERENCES trajectories(id) ON DELETE CASCADE,
    idx {int} NOT NULL,
    t_s {real} NOT NULL,
    joints TEXT NOT NULL,
    x_mm {real} NOT NULL, y_mm {real} NOT NULL, z_mm {real} NOT NULL,
    a_deg {real} NOT NULL, b_deg {real} NOT NULL, c_deg {real} NOT NULL,
    qw {real} NOT NULL, qx {real} NOT NULL, qy {real} NOT NULL, qz {real} NOT NULL,
    PRIMARY KEY (trajectory_id, idx)
);
CREATE TABLE interference_results (
    id {id},
    run_id {int} REFERENCES runs(id) ON DELETE SET NULL,
    name TEXT NOT NULL,
    pair_count {int} NOT NULL,
    created_at TEXT NOT NULL
);
CREATE TABLE interference_pairs (
    result_id {int} NOT NULL REFERENCES interference_results(id) ON DELETE CASCADE,
    idx {int} NOT NULL,
    a TEXT NOT NULL,
    b TEXT NOT NULL,
    state TEXT NOT NULL,
    depth_mm {real} NOT NULL,
    kind TEXT NOT NULL,
    PRIMARY KEY (result_id, idx)
)",
    },
    Migration {
        version: 3,
        what: "search and smoothing times of paths",
        sql: "
ALTER TABLE paths ADD COLUMN search_ms {real} NOT NULL DEFAULT 0;
ALTER TABLE paths ADD COLUMN smoothing_ms {real} NOT NULL DEFAULT 0;
",
    },
    Migration {
        version: 4,
        what: "skill execution log",
        sql: "
CREATE TABLE skill_log (
    id {id},
    run_id {int} REFERENCES runs(id) ON DELETE SET NULL,
    plan TEXT NOT NULL,
    skill {int},
    part TEXT,
    event TEXT NOT NULL,
    detail TEXT NOT NULL DEFAULT '',
    created_at TEXT NOT NULL
);
CREATE INDEX skill_log_by_plan ON skill_log(plan, id)
",
    },
    Migration {
        version: 5,
        what: "the penetration tolerance a path was planned with",
        sql: "
ALTER TABLE paths ADD COLUMN tolerance_mm {real}
",
    },
];

fn fill(sql: &str, dialect: Dialect) -> String {
    // `{clustered}`: SQLite keeps pose and sample rows in their key's b-tree (one
    // insert per row instead of a row plus an index entry).
    let (id, int, real, clustered) = match dialect {
        Dialect::Sqlite => (
            "INTEGER PRIMARY KEY AUTOINCREMENT",
            "INTEGER",
            "REAL",
            "WITHOUT ROWID",
        ),
        Dialect::Postgres => ("BIGSERIAL PRIMARY KEY", "BIGINT", "DOUBLE PRECISION", ""),
    };
    sql.replace("{id}", id)
        .replace("{clustered}", clustered)
        .replace("{int}", int)
        .replace("{real}", real)
}

/// Outcome of [`migrate`].
pub(crate) enum Migrated {
    /// At `target` (or already there).
    Ok,
    /// The database is at a newer version than this fitup knows.
    Newer(u32),
}

/// The highest applied version (0 for an empty database).
pub(crate) fn current_version(tx: &mut dyn Tx) -> Result<u32, Raw> {
    let rows = tx.rows("SELECT MAX(version) FROM schema_version", &[])?;
    Ok(rows
        .first()
        .and_then(|r| r.first())
        .and_then(SqlValue::as_i64)
        .unwrap_or(0) as u32)
}

/// Brings the schema to `target` inside the caller's transaction.
pub(crate) fn migrate(tx: &mut dyn Tx, target: u32, now: &str) -> Result<Migrated, Raw> {
    let dialect = tx.dialect();
    if dialect == Dialect::Postgres {
        // Two processes opening a fresh database at once: the second waits here
        // instead of failing on a half-created table.
        tx.exec("SELECT pg_advisory_xact_lock(7414014)", &[])?;
    }
    tx.exec(
        &fill(
            "CREATE TABLE IF NOT EXISTS schema_version (
                version {int} PRIMARY KEY,
                description TEXT NOT NULL,
                applied_at TEXT NOT NULL,
                fitup_version TEXT NOT NULL
            )",
            dialect,
        ),
        &[],
    )?;
    let current = current_version(tx)?;
    if current > LATEST {
        return Ok(Migrated::Newer(current));
    }
    for m in MIGRATIONS
        .iter()
        .filter(|m| m.version > current && m.version <= target)
    {
        for stmt in fill(m.sql, dialect).split(';') {
            if !stmt.trim().is_empty() {
                tx.exec(stmt, &[])?;
            }
        }
        tx.exec(
            "INSERT INTO schema_version (version, description, applied_at, fitup_version) VALUES (?, ?, ?, ?)",
            &[
                SqlValue::Int(m.version as i64),
                m.what.into(),
                now.into(),
                env!("CARGO_PKG_VERSION").into(),
            ],
        )?;
    }
    Ok(Migrated::Ok)
}
