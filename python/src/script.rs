//! `fitup.run_script`: a Rhai script run as `fitup run` runs it, from Python.

use crate::error::{Error, Result};
use fitup::script::{run_script as run, Arguments, Caches, Limits, Project, RunOptions};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

/// The run registry of the results database is one per process
/// (`fitup::db::recording`): recorded runs go one at a time.
static RECORDED: Mutex<()> = Mutex::new(());

/// `key=value` words from a dict: bools as `true`/`false`, numbers and text as
/// written (the script sees them typed, as `fitup run SCRIPT -- key=value` gives them).
fn words(args: Option<&Bound<'_, PyDict>>) -> Result<Vec<String>> {
    let mut out = Vec::new();
    if let Some(d) = args {
        for (k, v) in d.iter() {
            let k: String = k.str()?.to_string();
            let v = if v.is_instance_of::<PyBool>() {
                if v.extract::<bool>()? {
                    "true"
                } else {
                    "false"
                }
                .to_string()
            } else {
                v.str()?.to_string()
            };
            out.push(format!("{k}={v}"));
        }
    }
    Ok(out)
}

/// Runs the Rhai script ``script`` to completion, as ``fitup run`` does: sandboxed,
/// file access bounded by its project (``root``, else the nearest folder holding
/// ``fitup.toml``, else the script's folder).
///
/// ``doc``: a document the script sees as ``doc``; ``args``: a dict the script sees
/// as the map ``args`` (values typed like ``fitup run SCRIPT -- key=value``: ints,
/// floats, ``true``/``false``, else text); ``db``: record the run in this results
/// database (a file or ``postgres://`` URL; the script's ``open_db()`` of the same
/// database files its results under the run); ``max_operations``: the operation
/// limit (0 = none); ``max_seconds``: the wall-time limit of the run, seconds (default
/// 3600, as ``fitup run --max-seconds``; 0 = none): a script still running then stops
/// with a ``ScriptError`` naming the limit, at the line it had reached.
///
/// Returns a dict ``output`` (the printed lines), ``files_read``, ``files_written``,
/// ``elapsed_s``, ``operations``. A failing script raises ``ScriptError`` with the
/// script's ``file``, ``line`` and ``column`` and the ``output`` printed before it.
/// The GIL is released while the script runs.
#[pyfunction]
#[pyo3(signature = (script, doc = None, args = None, root = None, db = None, max_operations = None, max_seconds = None))]
// Python's keyword arguments, one parameter each.
#[allow(clippy::too_many_arguments)]
pub fn run_script<'py>(
    py: Python<'py>,
    script: PathBuf,
    doc: Option<PathBuf>,
    args: Option<&Bound<'py, PyDict>>,
    root: Option<PathBuf>,
    db: Option<String>,
    max_operations: Option<u64>,
    max_seconds: Option<u64>,
) -> Result<Bound<'py, PyDict>> {
    let words = words(args)?;
    let arguments = Arguments::parse(&words)?;
    let abs = std::path::absolute(&script).map_err(|source| Error::Project {
        path: script.display().to_string(),
        source,
    })?;
    let project = match &root {
        Some(r) => Project::new(r),
        None => Project::for_file(&abs),
    }
    .map_err(|source| Error::Project {
        path: root.as_ref().unwrap_or(&script).display().to_string(),
        source,
    })?;
    let script = project.resolve(&abs.to_string_lossy())?;
    let doc = match doc {
        Some(d) => {
            let d = std::path::absolute(&d).map_err(|source| Error::Project {
                path: d.display().to_string(),
                source,
            })?;
            Some(project.resolve(&d.to_string_lossy())?)
        }
        None => None,
    };
    let lines: Arc<Mutex<Vec<String>>> = Arc::default();
    let sink = lines.clone();
    let opts = RunOptions {
        script,
        doc,
        limits: Limits {
            max_operations: max_operations.unwrap_or(Limits::default().max_operations),
            max_seconds: max_seconds.unwrap_or(Limits::default().max_seconds),
            ..Limits::default()
        },
        cancel: Arc::new(AtomicBool::new(false)),
        output: Arc::new(move |line: &str| {
            if let Ok(mut l) = sink.lock() {
                l.push(line.to_string());
            }
        }),
        args: arguments,
        project,
    };
    let outcome = py.detach(|| -> Result<_> {
        let Some(db) = db else {
            return Ok(run(&opts, &Arc::new(Caches::default())));
        };
        let _one = RECORDED.lock().unwrap_or_else(|e| e.into_inner());
        let target = fitup::db::Target::parse(&db, opts.project.root());
        let new = fitup::db::NewRun {
            script: opts.project.display(&opts.script),
            document: opts.doc.as_ref().map(|d| opts.project.display(d)),
            ..Default::default()
        };
        fitup::db::recording::begin(target, new, true)?;
        let outcome = run(&opts, &Arc::new(Caches::default()));
        let status = match &outcome.result {
            Ok(()) => fitup::db::RunStatus::Ok,
            Err(fitup::script::ScriptError::Cancelled) => fitup::db::RunStatus::Cancelled,
            Err(_) => fitup::db::RunStatus::Failed,
        };
        let text = lines.lock().map(|l| l.join("\n")).unwrap_or_default();
        fitup::db::recording::finish(status, &text)?;
        Ok(outcome)
    })?;
    let output = lines.lock().map(|l| l.clone()).unwrap_or_default();
    if let Err(e) = outcome.result {
        return Err(Error::Python(Error::Script(e).into_py(py, Some(output))));
    }
    let d = PyDict::new(py);
    d.set_item("output", output)?;
    d.set_item("files_read", outcome.files_read)?;
    d.set_item("files_written", outcome.files_written)?;
    d.set_item("elapsed_s", outcome.elapsed.as_secs_f64())?;
    d.set_item("operations", outcome.operations)?;
    Ok(d)
}
