//! `fitup.Database`: the results database (SQLite file or PostgreSQL URL).

use crate::convert;
use crate::error::{Error, Result};
use crate::path::Path;
use fitup::db::{Database as Db, NewRun, PathMeta, RunStatus, SqlValue, Target};
use fitup::options::{Limits, PathFilter};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Mutex;

/// The results database: runs, paths with their key poses, trajectories, document
/// snapshots (``docs/database.md``).
///
/// ``Database(target)``: a SQLite file (created when missing; relative paths from the
/// current folder) or a ``postgres://user@host:port/db`` URL, which a batch on a
/// cluster shares. Every stored result is one transaction. Poses come back as
/// column-vector 4×4 arrays (mm), exactly as stored (quaternions).
#[pyclass(module = "fitup", name = "Database", frozen)]
pub struct Database {
    db: Mutex<Db>,
}

impl Database {
    fn with<R: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut Db) -> std::result::Result<R, fitup::db::DbError> + Send,
    ) -> Result<R> {
        py.detach(|| {
            let mut db = self
                .db
                .lock()
                .map_err(|_| Error::Poisoned { what: "database" })?;
            Ok(f(&mut db)?)
        })
    }
}

/// A query's answer: column names and rows.
type QueryRows<'py> = (Vec<String>, Vec<Vec<Bound<'py, PyAny>>>);

fn status_of(s: &str) -> Result<RunStatus> {
    Ok(match s {
        "ok" => RunStatus::Ok,
        "failed" => RunStatus::Failed,
        "cancelled" => RunStatus::Cancelled,
        "running" => RunStatus::Running,
        other => {
            return Err(Error::Option {
                option: "status",
                value: format!("{other:?}"),
                expected: "\"ok\", \"failed\", \"cancelled\" or \"running\"",
            })
        }
    })
}

fn sql_value(v: &Bound<'_, PyAny>) -> Result<SqlValue> {
    Ok(if v.is_none() {
        SqlValue::Null
    } else if let Ok(i) = v.extract::<i64>() {
        SqlValue::Int(i)
    } else if let Ok(x) = v.extract::<f64>() {
        SqlValue::Real(x)
    } else if let Ok(s) = v.extract::<String>() {
        SqlValue::Text(s)
    } else {
        return Err(Error::Option {
            option: "params",
            value: v.repr().map(|r| r.to_string()).unwrap_or_default(),
            expected: "None, an int, a float or a str",
        });
    })
}

fn py_value<'py>(py: Python<'py>, v: &SqlValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        SqlValue::Null => py.None().into_bound(py),
        SqlValue::Int(i) => i.into_pyobject(py)?.into_any(),
        SqlValue::Real(x) => x.into_pyobject(py)?.into_any(),
        SqlValue::Text(s) => s.into_pyobject(py)?.into_any(),
        #[allow(unreachable_patterns)]
        _ => py.None().into_bound(py),
    })
}

#[pymethods]
impl Database {
    /// Opens (or creates) the database ``target``: a file path or a PostgreSQL URL.
    #[new]
    fn new(py: Python<'_>, target: &str) -> Result<Self> {
        let here = std::env::current_dir().map_err(|source| Error::Project {
            path: ".".into(),
            source,
        })?;
        let target = Target::parse(target, &here);
        let db = py.detach(|| Db::open(&target))?;
        Ok(Self { db: Mutex::new(db) })
    }

    /// The database, without a password.
    #[getter]
    fn target(&self) -> Result<String> {
        Ok(self
            .db
            .lock()
            .map_err(|_| Error::Poisoned { what: "database" })?
            .target()
            .to_string())
    }

    /// Records the start of a run (``script``: what ran, e.g. a batch job's
    /// description; ``document``: its document). Returns the run's id.
    #[pyo3(signature = (script, document = None))]
    fn start_run(&self, py: Python<'_>, script: &str, document: Option<String>) -> Result<i64> {
        let run = NewRun {
            script: script.to_string(),
            document,
            ..NewRun::default()
        };
        self.with(py, |db| db.start_run(&run))
    }

    /// Records the end of run ``run_id``: ``status`` ``"ok"``, ``"failed"`` or
    /// ``"cancelled"`` and its output text.
    #[pyo3(signature = (run_id, status, output = ""))]
    fn finish_run(&self, py: Python<'_>, run_id: i64, status: &str, output: &str) -> Result<()> {
        let status = status_of(status)?;
        self.with(py, |db| db.finish_run(run_id, status, output))
    }

    /// Stores ``path`` (found or not, with its key poses, planner, seed and options)
    /// under ``name``; ``run_id`` files it under a run. Returns its id.
    #[pyo3(signature = (name, path, run_id = None))]
    fn save_path(
        &self,
        py: Python<'_>,
        name: &str,
        path: &Path,
        run_id: Option<i64>,
    ) -> Result<i64> {
        let meta = PathMeta {
            component: Some(path.component.clone()),
            seed: Some(path.seed),
            options: Some(path.options.clone()),
        };
        self.with(py, |db| db.save_path(run_id, name, &path.path, &meta))
    }

    /// Stored paths, oldest first, as dicts: ``id``, ``run_id``, ``name``,
    /// ``created_at``, ``component``, ``seed``, ``planner``, ``found``, ``reason``,
    /// ``length_mm``, ``time_ms``, ``poses`` (``(N, 4, 4)``). Filters (the
    /// path-filter table of docs/api.md, a script's ``paths`` map): ``name``,
    /// ``planner``, ``component``, ``since`` (UTC time or date prefix), ``run`` (a
    /// run id; ``run_id`` is its deprecated spelling).
    #[pyo3(signature = (**filter))]
    fn paths<'py>(
        &self,
        py: Python<'py>,
        filter: Option<&Bound<'py, PyDict>>,
    ) -> Result<Vec<Bound<'py, PyDict>>> {
        let q = crate::options::read::<PathFilter>(py, filter)?.0.query();
        let stored = self.with(py, |db| db.paths(&q))?;
        let mut out = Vec::with_capacity(stored.len());
        for s in stored {
            let d = PyDict::new(py);
            d.set_item("id", s.id)?;
            d.set_item("run_id", s.run_id)?;
            d.set_item("name", &s.name)?;
            d.set_item("created_at", &s.created_at)?;
            d.set_item("component", &s.meta.component)?;
            d.set_item("seed", s.meta.seed)?;
            d.set_item("planner", s.path.planner)?;
            d.set_item("found", s.path.found())?;
            d.set_item("reason", s.path.failure.map(|f| f.to_string()))?;
            d.set_item("length_mm", s.path.length_mm)?;
            d.set_item("time_ms", s.path.time_ms)?;
            d.set_item("poses", convert::poses_array(py, &s.path.poses))?;
            out.push(d);
        }
        Ok(out)
    }

    /// Recorded runs, oldest first, as dicts: ``id``, ``script``, ``document``,
    /// ``started_at``, ``finished_at``, ``status``, ``output``, ``fitup_version``.
    fn runs<'py>(&self, py: Python<'py>) -> Result<Vec<Bound<'py, PyDict>>> {
        let runs = self.with(py, |db| db.runs())?;
        let mut out = Vec::with_capacity(runs.len());
        for r in runs {
            let d = PyDict::new(py);
            d.set_item("id", r.id)?;
            d.set_item("script", &r.script)?;
            d.set_item("document", &r.document)?;
            d.set_item("started_at", &r.started_at)?;
            d.set_item("finished_at", &r.finished_at)?;
            d.set_item("status", &r.status)?;
            d.set_item("output", &r.output)?;
            d.set_item("fitup_version", &r.fitup_version)?;
            out.push(d);
        }
        Ok(out)
    }

    /// A read-only SQL query (SELECT/WITH/VALUES; writes, ATTACH and settings are
    /// refused) with ``?`` parameters, within the time, row and byte limits
    /// ``max_seconds``, ``max_rows``, ``max_bytes`` (keywords; the query-limits table
    /// of docs/api.md). Returns ``(columns, rows)``.
    #[pyo3(signature = (sql, params = Vec::new(), **limits))]
    fn query<'py>(
        &self,
        py: Python<'py>,
        sql: &str,
        params: Vec<Bound<'py, PyAny>>,
        limits: Option<&Bound<'py, PyDict>>,
    ) -> Result<QueryRows<'py>> {
        let limits = crate::options::read::<Limits>(py, limits)?.0.limits()?;
        let params = params.iter().map(sql_value).collect::<Result<Vec<_>>>()?;
        let r = self.with(py, |db| db.query_with(sql, &params, limits, None))?;
        let rows = r
            .rows
            .iter()
            .map(|row| {
                row.iter()
                    .map(|v| py_value(py, v))
                    .collect::<PyResult<Vec<_>>>()
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok((r.columns, rows))
    }

    fn __repr__(&self) -> String {
        format!("Database({:?})", self.target().unwrap_or_default())
    }
}
