//! Bindings for the results database: `open_db`, `db.save`, `db.paths`, `db.runs`,
//! `db.query`. Conversions only; the work is in [`crate::db`].

use super::api::Api;
use super::bind_document::DocHandle;
use super::bind_planning::PathHandle;
use super::bind_robot::TrajectoryHandle;
use super::convert::{check_keys, err, fail, opt_str, read_options};
use super::{Context, ScriptResult};
use crate::collision::Contact;
use crate::db::{
    recording, Database, InterferencePair, PathMeta, QueryLimits, Snapshot, SqlValue, Target,
};
use crate::options::{Limits, PathFilter};
use rhai::{Array, Dynamic, Map};
use std::sync::{Arc, Mutex, MutexGuard};

/// An open results database in a script (cheap to clone).
#[derive(Clone)]
pub struct DbHandle {
    pub(super) db: Arc<Mutex<Database>>,
    pub(super) run_id: Option<i64>,
    ctx: Arc<Context>,
}

impl DbHandle {
    fn open(ctx: &Arc<Context>, which: Option<&str>) -> ScriptResult<Self> {
        let target = match which {
            None => Target::resolve(None, ctx.project.root()),
            Some(url) if url.starts_with("postgres://") || url.starts_with("postgresql://") => {
                Target::Postgres(url.to_string())
            }
            // A file named by the script stays inside the project.
            Some(file) => Target::Sqlite(ctx.project.resolve(file).map_err(fail)?),
        };
        // A file the script named is opened through the project's held folders.
        let mut db = match which {
            Some(_) => Database::open_in(&ctx.project, &target),
            None => Database::open(&target),
        }
        .map_err(fail)?;
        if let Target::Sqlite(p) = &target {
            // The run's own writes are not user saves (watch mode); never read back
            // while SQLite holds them (see `record_write_unread`).
            for suffix in ["", "-wal", "-shm"] {
                ctx.record_write_unread(std::path::Path::new(&format!("{}{suffix}", p.display())));
            }
        }
        let run_id = recording::run_id_for(&mut db).map_err(fail)?;
        Ok(DbHandle {
            db: Arc::new(Mutex::new(db)),
            run_id,
            ctx: ctx.clone(),
        })
    }

    fn lock(&self) -> ScriptResult<MutexGuard<'_, Database>> {
        self.db
            .lock()
            .map_err(|_| fail("the database handle is unusable after an earlier panic"))
    }
}

/// A script value as JSON (for stored planning options).
fn to_json(v: &Dynamic) -> serde_json::Value {
    if let Some(m) = v.read_lock::<Map>() {
        return serde_json::Value::Object(
            m.iter().map(|(k, v)| (k.to_string(), to_json(v))).collect(),
        );
    }
    if let Some(a) = v.read_lock::<Array>() {
        return serde_json::Value::Array(a.iter().map(to_json).collect());
    }
    if let Ok(i) = v.as_int() {
        return i.into();
    }
    if let Ok(f) = v.as_float() {
        return serde_json::Number::from_f64(f).map_or(serde_json::Value::Null, Into::into);
    }
    if let Ok(b) = v.as_bool() {
        return b.into();
    }
    if v.is_unit() {
        return serde_json::Value::Null;
    }
    v.to_string().into()
}

fn to_sql(v: &Dynamic, i: usize) -> ScriptResult<SqlValue> {
    if v.is_unit() {
        return Ok(SqlValue::Null);
    }
    if let Ok(i) = v.as_int() {
        return Ok(SqlValue::Int(i));
    }
    if let Ok(f) = v.as_float() {
        return Ok(SqlValue::Real(f));
    }
    if let Ok(b) = v.as_bool() {
        return Ok(SqlValue::Int(i64::from(b)));
    }
    if v.is_string() {
        return Ok(SqlValue::Text(v.to_string()));
    }
    err(format!(
        "query parameter {} must be a number, string, bool or (), not {}",
        i + 1,
        v.type_name()
    ))
}

fn from_sql(v: &SqlValue) -> Dynamic {
    match v {
        SqlValue::Null => Dynamic::UNIT,
        SqlValue::Int(i) => Dynamic::from_int(*i),
        SqlValue::Real(r) => Dynamic::from_float(*r),
        SqlValue::Text(s) => s.clone().into(),
    }
}

fn save_path(h: &DbHandle, p: &PathHandle, name: &str, info: &Map) -> ScriptResult<i64> {
    check_keys(info, &["component", "seed", "options"], "path info")?;
    let seed = match info.get("seed") {
        None => None,
        Some(s) => Some(
            s.as_int()
                .map_err(|t| fail(format!("seed must be an integer, not {t}")))? as u64,
        ),
    };
    let meta = PathMeta {
        component: opt_str(info, "component")?,
        seed,
        options: info.get("options").map(to_json),
    };
    h.lock()?
        .save_path(h.run_id, name, &p.0, &meta)
        .map_err(fail)
}

fn save_interference(h: &DbHandle, results: &Array, name: &str) -> ScriptResult<i64> {
    let mut pairs = Vec::with_capacity(results.len());
    for (i, r) in results.iter().enumerate() {
        let m = r.read_lock::<Map>().ok_or_else(|| {
            fail(format!(
                "results[{i}] must be an interference map #{{a, b, state, depth, kind}}, not {}",
                r.type_name()
            ))
        })?;
        let s = |k: &str| -> ScriptResult<String> {
            m.get(k)
                .map(|v| v.to_string())
                .ok_or_else(|| fail(format!("results[{i}] has no `{k}`")))
        };
        let depth = m
            .get("depth")
            .map(|d| super::convert::num(d, "depth"))
            .transpose()?
            .unwrap_or(0.0);
        let (a, b) = (s("a")?, s("b")?);
        let kind = m.get("kind").map(|v| v.to_string()).unwrap_or_default();
        // The verdict's words are the library's (`Contact::from_text`).
        let contact = Contact::from_text(&s("state")?, depth, &kind, &a, &b)
            .map_err(|e| fail(format!("results[{i}]: {e}")))?;
        pairs.push(InterferencePair { a, b, contact });
    }
    h.lock()?
        .save_interference(h.run_id, name, &pairs)
        .map_err(fail)
}

fn paths(h: &DbHandle, filter: &Map) -> ScriptResult<Array> {
    let q = read_options::<PathFilter>(filter, &|w| h.ctx.print(w))?.query();
    let stored = h.lock()?.paths(&q).map_err(fail)?;
    Ok(stored
        .into_iter()
        .map(|s| {
            let mut m = Map::new();
            m.insert("id".into(), Dynamic::from_int(s.id));
            m.insert("name".into(), s.name.into());
            m.insert(
                "component".into(),
                s.meta.component.map_or(Dynamic::UNIT, Into::into),
            );
            m.insert(
                "seed".into(),
                s.meta
                    .seed
                    .map_or(Dynamic::UNIT, |v| Dynamic::from_int(v as i64)),
            );
            m.insert(
                "run".into(),
                s.run_id.map_or(Dynamic::UNIT, Dynamic::from_int),
            );
            m.insert("created_at".into(), s.created_at.into());
            m.insert("planner".into(), s.path.planner.into());
            m.insert("found".into(), s.path.found().into());
            m.insert(
                "path".into(),
                Dynamic::from(PathHandle(Arc::new(s.path), h.ctx.clone())),
            );
            Dynamic::from_map(m)
        })
        .collect())
}

/// `#{max_seconds, max_rows, max_bytes}` over the defaults (the library's
/// [`Limits`] vocabulary; the maxima are its rule and name the limit out of range).
fn query_limits(m: &Map) -> ScriptResult<QueryLimits> {
    read_options::<Limits>(m, &|_| {})?.limits().map_err(fail)
}

fn query(h: &DbHandle, sql: &str, params: &Array, limits: &Map) -> ScriptResult<Array> {
    let limits = query_limits(limits)?;
    let params = params
        .iter()
        .enumerate()
        .map(|(i, v)| to_sql(v, i))
        .collect::<ScriptResult<Vec<_>>>()?;
    // The run's cancel flag reaches the query: a newer save stops it mid-statement;
    // and the run's queries share one time budget.
    let mut db = h.lock()?;
    let r = h
        .ctx
        .query_budget
        .run(limits, |limits| {
            db.query_with(sql, &params, limits, Some(h.ctx.cancel.clone()))
        })
        .map_err(fail)?;
    drop(db);
    // Counted before a script value is built: a result the sandbox cannot hold (it
    // would be refused after the conversion, having cost ≈ 500 bytes a row and every
    // text twice) is refused here, naming the limit.
    let lim = &h.ctx.limits;
    let rows = r.rows.len();
    let values = rows.saturating_mul(r.columns.len());
    let text: usize = r
        .rows
        .iter()
        .flatten()
        .map(|v| match v {
            SqlValue::Text(s) => s.len(),
            _ => 0,
        })
        .sum();
    if rows > lim.max_array_size || values > lim.max_map_size || text > lim.max_string_size {
        return Err(fail(format!(
            "the query on {} returned {} rows × {} columns ({} values, {} characters of text): more than a script may hold (arrays up to {} elements, maps up to {} properties, strings up to {} characters in all); ask for fewer rows with LIMIT or fewer columns",
            h.lock()?.target(),
            crate::math::format::count(rows as u64),
            r.columns.len(),
            crate::math::format::count(values as u64),
            crate::math::format::count(text as u64),
            crate::math::format::count(lim.max_array_size as u64),
            crate::math::format::count(lim.max_map_size as u64),
            crate::math::format::count(lim.max_string_size as u64),
        )));
    }
    let columns = r.columns;
    // Rows are dropped as they are converted: the result is not held twice.
    Ok(r.rows
        .into_iter()
        .map(|row| {
            Dynamic::from_map(
                columns
                    .iter()
                    .zip(&row)
                    .map(|(c, v)| (c.as_str().into(), from_sql(v)))
                    .collect(),
            )
        })
        .collect())
}

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Results database", "Keeps what runs computed — paths, robot trajectories, document snapshots, interference results — in SQL (see docs/database.md). `open_db()` opens the project's database: `--db` / `FITUP_DB` when given, else `fitup.db` at the project root (SQLite; created on first use). `open_db(file)` opens another SQLite file inside the project, `open_db(\"postgres://user@host/db\")` a PostgreSQL server. Each `save` is one transaction: a killed process leaves whole results or none. Results are filed under the current run when `fitup run` records it. Stored poses: `x_mm, y_mm, z_mm`, `a_deg, b_deg, c_deg` (degrees, as pose triples) and the quaternion `qw, qx, qy, qz`; lengths in mm, angles in radians unless the column says `_deg`.");
    api.type_::<DbHandle>("Database");
    let c = ctx.clone();
    api.f(
        "open_db() -> Database",
        "The project's results database (`--db`, `FITUP_DB`, or `fitup.db` at the project root).",
        move || DbHandle::open(&c, None),
    );
    let c = ctx.clone();
    api.f(
        "open_db(file_or_url: string) -> Database",
        "A SQLite file inside the project, or a `postgres://` URL.",
        move |which: &str| DbHandle::open(&c, Some(which)),
    );
    api.get(
        "Database.run -> int",
        "The id of the run results are filed under, or `()` when the run is not recorded.",
        |h: &mut DbHandle| h.run_id.map_or(Dynamic::UNIT, Dynamic::from_int),
    );
    api.get(
        "Database.location -> string",
        "The file path or the URL (without password).",
        |h: &mut DbHandle| -> ScriptResult<String> { Ok(h.lock()?.target().to_string()) },
    );
    api.f(
        "Database.save(path: Path, name: string) -> int",
        "Stores a planned path (found or not: planner, reason, key poses, lengths in mm, rotation in rad, timings); returns its id.",
        |h: &mut DbHandle, p: PathHandle, name: &str| save_path(h, &p, name, &Map::new()),
    );
    api.f(
        "Database.save(path: Path, name: string, info: map) -> int",
        "As above with `#{component, seed, options}`: the component the path moves (needed to re-validate it later), the planner's seed and options.",
        |h: &mut DbHandle, p: PathHandle, name: &str, info: Map| save_path(h, &p, name, &info),
    );
    api.f(
        "Database.save(trajectory: Trajectory, name: string) -> int",
        "Stores a robot trajectory: every sample's time (s), joints (rad, mm for prismatic) and TCP pose; returns its id.",
        |h: &mut DbHandle, t: TrajectoryHandle, name: &str| -> ScriptResult<i64> {
            h.lock()?
                .save_trajectory(h.run_id, name, None, &t.trajectory)
                .map_err(fail)
        },
    );
    api.f(
        "Database.save(trajectory: Trajectory, name: string, robot: string) -> int",
        "As above, naming the robot that ran it.",
        |h: &mut DbHandle, t: TrajectoryHandle, name: &str, robot: &str| -> ScriptResult<i64> {
            h.lock()?
                .save_trajectory(h.run_id, name, Some(robot), &t.trajectory)
                .map_err(fail)
        },
    );
    api.f(
        "Database.save(doc: Document) -> int",
        "Stores a snapshot of the document: every component's pose and every dimension's value (mm or rad), so two runs can be compared (`fitup db diff`); returns its id.",
        |h: &mut DbHandle, d: DocHandle| -> ScriptResult<i64> {
            let snap = Snapshot::of(&*d.lock()?);
            h.lock()?.save_snapshot(h.run_id, &snap).map_err(fail)
        },
    );
    api.f(
        "Database.save(results: array, name: string) -> int",
        "Stores interference results (the maps of `doc.interferences()` / `doc.touching()`); returns its id.",
        |h: &mut DbHandle, r: Array, name: &str| save_interference(h, &r, name),
    );
    api.options::<PathFilter>("The filter of `paths` (Python: keywords of `Database.paths`):");
    api.options::<Limits>("The limits of `query` (Python: keywords of `Database.query`):");
    api.f(
        "Database.paths() -> array",
        "Every stored path, oldest first, as maps `#{id, name, component, seed, run, created_at, planner, found, path}`; `path` is a Path for `follow`, `doc.revalidate` and the Path properties.",
        |h: &mut DbHandle| paths(h, &Map::new()),
    );
    api.f(
        "Database.paths(filter: map) -> array",
        "Stored paths by the keys of the path-filter table below.",
        |h: &mut DbHandle, f: Map| paths(h, &f),
    );
    api.f(
        "Database.runs() -> array",
        "Every recorded run: `#{id, script, document, status, started_at, finished_at, output, fitup_version}` (times UTC, ISO 8601).",
        |h: &mut DbHandle| -> ScriptResult<Array> {
            let runs = h.lock()?.runs().map_err(fail)?;
            Ok(runs
                .into_iter()
                .map(|r| {
                    let mut m = Map::new();
                    m.insert("id".into(), Dynamic::from_int(r.id));
                    m.insert("script".into(), r.script.into());
                    m.insert("document".into(), r.document.map_or(Dynamic::UNIT, Into::into));
                    m.insert("status".into(), r.status.into());
                    m.insert("started_at".into(), r.started_at.into());
                    m.insert("finished_at".into(), r.finished_at.map_or(Dynamic::UNIT, Into::into));
                    m.insert("output".into(), r.output.into());
                    m.insert("fitup_version".into(), r.fitup_version.into());
                    Dynamic::from_map(m)
                })
                .collect())
        },
    );
    api.f(
        "Database.query(sql: string) -> array",
        "Runs one read-only SQL query on this database; each row is a map column → value. Writes, ATTACH, pragmas that set anything and file functions are refused. Stops at the default limits of the query-limits table below and refuses results over them (see docs/database.md, *Queries from scripts*).",
        |h: &mut DbHandle, sql: &str| query(h, sql, &Array::new(), &Map::new()),
    );
    api.f(
        "Database.query(sql: string, params: array) -> array",
        "As above with parameters (`?1`, `?2`… in SQLite, `$1`, `$2`… in PostgreSQL): numbers, strings, bools or `()`.",
        |h: &mut DbHandle, sql: &str, params: Array| query(h, sql, &params, &Map::new()),
    );
    api.f(
        "Database.query(sql: string, params: array, limits: map) -> array",
        "As above within the limits of the query-limits table below (keys `max_seconds`, `max_rows`, `max_bytes`).",
        |h: &mut DbHandle, sql: &str, params: Array, limits: Map| query(h, sql, &params, &limits),
    );
    api.f(
        "Database.to_string() -> string",
        "`Database(location)`.",
        |h: &mut DbHandle| -> ScriptResult<String> {
            Ok(format!("Database({})", h.lock()?.target()))
        },
    );
}
