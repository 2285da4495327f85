//! `fitup db …` (list, show, export and compare stored results) and the recording
//! of `fitup run`/`watch` runs in the results database.

use super::out::{errln, outln};
use super::CliError;
use super::{Exit, ScriptArgs};
use crate::db::{recording, Database, NewRun, PathQuery, RunStatus, StoredPath, Target};
use crate::math::AngleConvention;
use crate::script::{OutputSink, RunOptions, ScriptError};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// `fitup db`: the results database of the project.
#[derive(Debug, Args)]
pub struct DbArgs {
    /// The database: a SQLite file or a `postgres://` URL [default: `FITUP_DB`, else
    /// `fitup.db` in the project folder].
    #[arg(long, global = true)]
    pub db: Option<String>,
    /// The project folder [default: the current folder].
    #[arg(long, global = true)]
    pub root: Option<PathBuf>,
    /// What to do.
    #[command(subcommand)]
    pub action: DbAction,
}

/// The `fitup db` subcommands.
#[derive(Debug, Subcommand)]
pub enum DbAction {
    /// List the recorded runs.
    Runs,
    /// List the stored paths.
    Paths {
        /// Only paths stored under this name.
        #[arg(long)]
        name: Option<String>,
        /// Only paths of this planner.
        #[arg(long)]
        planner: Option<String>,
    },
    /// Show one record: `N` or `run:N`, `path:N`, `trajectory:N`, `interference:N`.
    Show {
        /// The record.
        id: String,
    },
    /// Write one record as CSV or JSON (to standard output or `--out`).
    Export {
        /// The record: `N` or `run:N`, `path:N`, `trajectory:N`, `interference:N`.
        id: String,
        /// CSV (paths, trajectories, interference results).
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// JSON (every kind).
        #[arg(long)]
        json: bool,
        /// Output file (inside the project) instead of standard output. An existing
        /// file is replaced only when fitup wrote it (see "What a run writes" in
        /// docs/scripting.md), or with `--force`.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Let `--out` replace a file that the project uses or that fitup did not
        /// write (never a folder, FIFO or symbolic link).
        #[arg(long, requires = "out")]
        force: bool,
    },
    /// Compare two runs: component poses, dimension values and paths by name.
    Diff {
        /// The first run.
        run_a: i64,
        /// The second run.
        run_b: i64,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Run,
    Path,
    Trajectory,
    Interference,
}

fn parse_id(s: &str) -> Result<(Kind, i64), CliError> {
    let (kind, n) = match s.split_once(':') {
        None => (Kind::Run, s),
        Some(("run", n)) => (Kind::Run, n),
        Some(("path", n)) => (Kind::Path, n),
        Some(("trajectory", n)) => (Kind::Trajectory, n),
        Some(("interference", n)) => (Kind::Interference, n),
        Some((k, _)) => return Err(CliError::RecordKind(k.to_string())),
    };
    let id = n
        .trim()
        .parse()
        .map_err(|_| CliError::RecordNumber(n.to_string()))?;
    Ok((kind, id))
}

fn root_of(root: &Option<PathBuf>) -> Result<PathBuf, CliError> {
    match root {
        Some(r) => Ok(r.clone()),
        None => std::env::current_dir().map_err(CliError::CurrentFolder),
    }
}

/// Runs `fitup db …`.
pub(super) fn main(a: &DbArgs) -> Exit {
    match run_action(a) {
        Ok(()) => Exit::Ok,
        Err((exit, m)) => {
            errln!("error: {m}");
            exit
        }
    }
}

fn run_action(a: &DbArgs) -> Result<(), (Exit, String)> {
    let usage = |m: String| (Exit::Usage, m);
    let fail = |m: String| (Exit::Failure, m);
    let cli = |e: CliError| (Exit::Usage, e.to_string());
    let root = root_of(&a.root).map_err(cli)?;
    let target = Target::resolve(a.db.as_deref(), &root);
    if let Target::Sqlite(p) = &target {
        if !p.exists() {
            return Err(fail(format!(
                "no results database at {} (scripts create it with `open_db()`; `fitup run --db` records runs)",
                p.display()
            )));
        }
    }
    let mut db = Database::open(&target).map_err(|e| fail(e.to_string()))?;
    let e = |x: crate::db::DbError| (Exit::Failure, x.to_string());
    match &a.action {
        DbAction::Runs => {
            let runs = db.runs().map_err(e)?;
            if runs.is_empty() {
                outln!("no runs recorded in {target}");
                return Ok(());
            }
            outln!(
                "{:>5}  {:<9}  {:<24}  {:<10}  script",
                "run",
                "status",
                "started (UTC)",
                "time"
            );
            for r in runs {
                outln!(
                    "{:>5}  {:<9}  {:<24}  {:<10}  {}{}",
                    r.id,
                    r.status,
                    r.started_at,
                    duration(&r.started_at, r.finished_at.as_deref()),
                    r.script,
                    r.document
                        .map(|d| format!(" --doc {d}"))
                        .unwrap_or_default()
                );
            }
        }
        DbAction::Paths { name, planner } => {
            let paths = db
                .paths(&PathQuery {
                    name: name.clone(),
                    planner: planner.clone(),
                    without_poses: true,
                    ..Default::default()
                })
                .map_err(e)?;
            if paths.is_empty() {
                outln!("no paths stored in {target}");
                return Ok(());
            }
            outln!(
                "{:>5}  {:<20} {:<10} {:<12} {:>5} {:>10} {:>9}  {:>4}  stored (UTC)",
                "path",
                "name",
                "component",
                "planner",
                "found",
                "length mm",
                "rot. °",
                "run"
            );
            for p in paths {
                outln!(
                    "{:>5}  {:<20} {:<10} {:<12} {:>5} {:>10.1} {:>9.1}  {:>4}  {}",
                    p.id,
                    p.name,
                    p.meta.component.as_deref().unwrap_or("-"),
                    p.path.planner,
                    if p.path.found() { "yes" } else { "no" },
                    p.path.length_mm,
                    p.path.rotation_rad.to_degrees(),
                    p.run_id
                        .map(|r| r.to_string())
                        .unwrap_or_else(|| "-".into()),
                    p.created_at
                );
            }
        }
        DbAction::Show { id } => {
            let (kind, id) = parse_id(id).map_err(cli)?;
            show(&mut db, kind, id).map_err(e)?;
        }
        DbAction::Export {
            id,
            csv,
            json,
            out,
            force,
        } => {
            let (kind, id) = parse_id(id).map_err(cli)?;
            if !csv && !json {
                return Err(usage("say --csv or --json".into()));
            }
            let text = export(&mut db, kind, id, *json).map_err(|m| match m {
                ExportError::Db(db) => e(db),
                other => usage(other.to_string()),
            })?;
            match out {
                None => print!("{text}"),
                Some(o) => {
                    let project = crate::script::Project::new(&root)
                        .map_err(|x| fail(format!("project folder {}: {x}", root.display())))?;
                    let rule = crate::project::OutputRule::forced(*force);
                    project
                        .write_output(&o.to_string_lossy(), text.as_bytes(), &rule)
                        .map_err(|x| fail(format!("--out: {x}")))?;
                    outln!("wrote {}", o.display());
                }
            }
        }
        DbAction::Diff { run_a, run_b } => diff(&mut db, *run_a, *run_b).map_err(e)?,
    }
    Ok(())
}

/// `12.3 s` between two stored times, or `running`.
fn duration(start: &str, end: Option<&str>) -> String {
    let secs = |t: &str| -> Option<f64> {
        // 2026-11-30T17:43:21.123Z: the time of day is enough for runs under a day.
        let tod = t.get(11..23)?;
        let h: f64 = tod.get(0..2)?.parse().ok()?;
        let m: f64 = tod.get(3..5)?.parse().ok()?;
        let s: f64 = tod.get(6..12)?.parse().ok()?;
        Some(h * 3600.0 + m * 60.0 + s)
    };
    match end {
        None => "-".into(),
        Some(e) => match (secs(start), secs(e)) {
            (Some(a), Some(b)) if start.get(0..10) == e.get(0..10) => {
                format!("{:.1} s", b - a)
            }
            _ => "-".into(),
        },
    }
}

fn show(db: &mut Database, kind: Kind, id: i64) -> Result<(), crate::db::DbError> {
    match kind {
        Kind::Run => {
            let r = db.run(id)?;
            outln!("run {}: {} ({})", r.id, r.script, r.status);
            if let Some(d) = &r.document {
                outln!("  document   {d}");
            }
            outln!("  started    {}", r.started_at);
            outln!(
                "  finished   {}",
                r.finished_at
                    .as_deref()
                    .unwrap_or("- (running, or the process died)")
            );
            outln!("  fitup      {}", r.fitup_version);
            let paths = db.paths(&PathQuery {
                run_id: Some(id),
                without_poses: true,
                ..Default::default()
            })?;
            for p in &paths {
                outln!(
                    "  path:{:<4} {} ({}, {})",
                    p.id,
                    p.name,
                    p.path.planner,
                    if p.path.found() {
                        format!("{:.1} mm", p.path.length_mm)
                    } else {
                        "not found".into()
                    }
                );
            }
            for (tid, name, n) in db.trajectory_list(Some(id))? {
                outln!("  trajectory:{tid:<4} {name} ({n} samples)");
            }
            for (iid, name, n) in db.interference_list(Some(id))? {
                outln!("  interference:{iid:<4} {name} ({n} pairs)");
            }
            for (sid, s) in db.snapshots(Some(id))? {
                outln!(
                    "  snapshot {sid}: {} ({} components, {} dimensions)",
                    s.document,
                    s.poses.len(),
                    s.dimensions.len()
                );
            }
            if !r.output.is_empty() {
                outln!("  output:");
                for line in r.output.lines() {
                    outln!("    {line}");
                }
            }
        }
        Kind::Path => {
            let p = db.path(id)?;
            outln!("path {}: {} ({})", p.id, p.name, p.created_at);
            outln!(
                "  component  {}",
                p.meta.component.as_deref().unwrap_or("-")
            );
            outln!(
                "  planner    {}{}",
                p.path.planner,
                p.meta
                    .seed
                    .map(|s| format!(", seed {s}"))
                    .unwrap_or_default()
            );
            match &p.path.failure {
                None => outln!(
                    "  found      {} key poses, {:.3} mm, {:.2}°, {} iterations, {:.1} ms",
                    p.path.poses.len(),
                    p.path.length_mm,
                    p.path.rotation_rad.to_degrees(),
                    p.path.iterations,
                    p.path.time_ms
                ),
                Some(f) => outln!("  not found  {f}"),
            }
            outln!("  edges      {}", p.path.resolution);
            for (i, t) in p.path.poses.iter().enumerate() {
                outln!("  {i:>4}  {t}");
            }
        }
        Kind::Trajectory => {
            let t = db.trajectory(id)?;
            outln!(
                "trajectory {}: {} ({} samples, {:.3} s{})",
                t.id,
                t.name,
                t.trajectory.samples.len(),
                t.trajectory.duration(),
                t.robot.map(|r| format!(", robot {r}")).unwrap_or_default()
            );
            print!("{}", t.trajectory.to_csv(AngleConvention::default()));
        }
        Kind::Interference => {
            let r = db.interference(id)?;
            outln!(
                "interference {}: {} ({} pairs)",
                r.id,
                r.name,
                r.pairs.len()
            );
            for p in r.pairs {
                outln!(
                    "  {} – {}: {} {:.3} mm {}",
                    p.a,
                    p.b,
                    p.state(),
                    p.depth_mm(),
                    p.kind()
                );
            }
        }
    }
    Ok(())
}

fn path_json(p: &StoredPath) -> serde_json::Value {
    let poses: Vec<serde_json::Value> = p
        .path
        .poses
        .iter()
        .map(|t| {
            let v = t.to_xyzabc_deg(AngleConvention::default());
            let q = t.rotation();
            serde_json::json!({
                "x_mm": v[0], "y_mm": v[1], "z_mm": v[2],
                "a_deg": v[3], "b_deg": v[4], "c_deg": v[5],
                "qw": q.w, "qx": q.i, "qy": q.j, "qz": q.k,
            })
        })
        .collect();
    serde_json::json!({
        "id": p.id, "name": p.name, "run": p.run_id, "created_at": p.created_at,
        "component": p.meta.component, "seed": p.meta.seed, "options": p.meta.options,
        "planner": p.path.planner, "found": p.path.found(),
        "reason": p.path.failure.map(|f| f.to_string()),
        "length_mm": p.path.length_mm, "rotation_rad": p.path.rotation_rad,
        "iterations": p.path.iterations, "time_ms": p.path.time_ms,
        "resolution": p.path.resolution.to_string(),
        "poses": poses,
    })
}

/// Why `fitup db export` wrote nothing: the database's error, or a usage error.
#[derive(Debug, thiserror::Error)]
enum ExportError {
    /// The record could not be read.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// A run asked for as CSV.
    #[error("a run holds several tables: export it with --json, or export path:N / trajectory:N / interference:N as CSV")]
    RunAsCsv,
    /// The path's CSV could not be written.
    #[error(transparent)]
    Csv(std::io::Error),
}

/// The record as CSV or JSON.
fn export(db: &mut Database, kind: Kind, id: i64, json: bool) -> Result<String, ExportError> {
    let pretty = |v: serde_json::Value| serde_json::to_string_pretty(&v).unwrap_or_default() + "\n";
    Ok(match (kind, json) {
        (Kind::Path, false) => {
            let p = db.path(id)?;
            let mut bytes = Vec::new();
            p.path
                .write_csv(&mut bytes, AngleConvention::default())
                .map_err(ExportError::Csv)?;
            String::from_utf8_lossy(&bytes).into_owned()
        }
        (Kind::Path, true) => pretty(path_json(&db.path(id)?)),
        (Kind::Trajectory, false) => db
            .trajectory(id)?
            .trajectory
            .to_csv(AngleConvention::default()),
        (Kind::Trajectory, true) => {
            let t = db.trajectory(id)?;
            let samples: Vec<serde_json::Value> = t
                .trajectory
                .samples
                .iter()
                .map(|s| {
                    let v = s.tcp.to_xyzabc_deg(AngleConvention::default());
                    serde_json::json!({
                        "t_s": s.t, "joints": s.joints,
                        "x_mm": v[0], "y_mm": v[1], "z_mm": v[2],
                        "a_deg": v[3], "b_deg": v[4], "c_deg": v[5],
                    })
                })
                .collect();
            pretty(serde_json::json!({
                "id": t.id, "name": t.name, "robot": t.robot, "run": t.run_id,
                "created_at": t.created_at, "joints_unit": "rad (mm for prismatic joints)",
                "samples": samples,
            }))
        }
        (Kind::Interference, false) => {
            let r = db.interference(id)?;
            let mut s = String::from("a,b,state,depth_mm,kind\n");
            for p in r.pairs {
                s += &format!(
                    "{},{},{},{},{}\n",
                    csv_field(&p.a),
                    csv_field(&p.b),
                    p.state(),
                    p.depth_mm(),
                    csv_field(&p.kind())
                );
            }
            s
        }
        (Kind::Interference, true) => {
            let r = db.interference(id)?;
            let pairs: Vec<serde_json::Value> = r
                .pairs
                .iter()
                .map(|p| serde_json::json!({"a": p.a, "b": p.b, "state": p.state(), "depth_mm": p.depth_mm(), "kind": p.kind()}))
                .collect();
            pretty(
                serde_json::json!({"id": r.id, "name": r.name, "run": r.run_id, "created_at": r.created_at, "pairs": pairs}),
            )
        }
        (Kind::Run, false) => return Err(ExportError::RunAsCsv),
        (Kind::Run, true) => {
            let r = db.run(id)?;
            let paths: Vec<serde_json::Value> = db
                .paths(&PathQuery {
                    run_id: Some(id),
                    ..Default::default()
                })?
                .iter()
                .map(path_json)
                .collect();
            let snapshots: Vec<serde_json::Value> = db
                .snapshots(Some(id))
                ?
                .iter()
                .map(|(sid, s)| {
                    let poses: serde_json::Map<String, serde_json::Value> = s
                        .poses
                        .iter()
                        .map(|(n, t)| {
                            let v = t.to_xyzabc_deg(AngleConvention::default());
                            (n.clone(), serde_json::json!([v[0], v[1], v[2], v[3], v[4], v[5]]))
                        })
                        .collect();
                    let dims: serde_json::Map<String, serde_json::Value> = s
                        .dimensions
                        .iter()
                        .map(|(n, _, v)| (n.clone(), serde_json::json!(v)))
                        .collect();
                    serde_json::json!({"id": sid, "document": s.document, "poses_xyzabc_mm_deg": poses, "dimensions_mm_rad": dims})
                })
                .collect();
            let list = |v: Vec<(i64, String, i64)>| -> Vec<serde_json::Value> {
                v.into_iter()
                    .map(|(i, n, c)| serde_json::json!({"id": i, "name": n, "count": c}))
                    .collect()
            };
            pretty(serde_json::json!({
                "id": r.id, "script": r.script, "document": r.document,
                "script_hash": r.script_hash, "document_hash": r.document_hash,
                "started_at": r.started_at, "finished_at": r.finished_at, "status": r.status,
                "output": r.output, "fitup_version": r.fitup_version,
                "paths": paths, "snapshots": snapshots,
                "trajectories": list(db.trajectory_list(Some(id))?),
                "interference": list(db.interference_list(Some(id))?),
            }))
        }
    })
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Prints [`Database::diff_runs`] for people: one line per difference, angles in degrees.
fn diff(db: &mut Database, a: i64, b: i64) -> Result<(), crate::db::DbError> {
    use crate::db::diff::{Change, Side};
    let d = db.diff_runs(a, b)?;
    outln!(
        "run {a} ({}, {}) → run {b} ({}, {})",
        d.a.script,
        d.a.started_at,
        d.b.script,
        d.b.started_at
    );
    let run = |s: &Side| if *s == Side::A { a } else { b };
    for c in &d.changes {
        match c {
            Change::NoSnapshot { run: r } => outln!(
                "  (no document snapshot in {}: store one with `db.save(doc)`)",
                run(r)
            ),
            Change::ComponentOnlyIn { name, run: r } => {
                outln!("  component {name}: only in run {}", run(r))
            }
            Change::ComponentMoved {
                name,
                distance_mm,
                angle_rad,
            } => outln!(
                "  component {name}: moved {distance_mm:.3} mm, turned {:.3}°",
                angle_rad.to_degrees()
            ),
            Change::DimensionChanged {
                name,
                kind,
                from,
                to,
            } => {
                let (x, y, unit) = match kind {
                    crate::document::DimensionKind::Angle => {
                        (from.to_degrees(), to.to_degrees(), "°")
                    }
                    crate::document::DimensionKind::Length => (*from, *to, " mm"),
                };
                outln!("  dimension {name}: {x:.3}{unit} → {y:.3}{unit}");
            }
            Change::PathOnlyIn { name, run: r } => outln!("  path {name}: only in run {}", run(r)),
            Change::PathChanged { name, from, to } => outln!("  path {name}: {from} → {to}"),
        }
    }
    if !d
        .changes
        .iter()
        .any(|c| !matches!(c, Change::NoSnapshot { .. }))
    {
        outln!("  no differences");
    }
    Ok(())
}

/// Records runs of `fitup run`/`watch` in the results database.
pub(super) struct Recorder {
    output: Arc<Mutex<String>>,
}

/// The most output kept per run.
const OUTPUT_LIMIT: usize = 64 * 1024;

impl Recorder {
    /// Prepares recording for `opts`: `--db` (and `FITUP_DB`) choose the database
    /// the script's `open_db()` uses, and the output is captured for the run record.
    pub(super) fn new(a: &ScriptArgs, opts: &mut RunOptions) -> Self {
        if let Some(db) = a.db.as_deref().filter(|d| !d.is_empty()) {
            // The script's `open_db()` reads the same variable.
            std::env::set_var(crate::db::ENV_VAR, db);
        }
        let output = Arc::new(Mutex::new(String::new()));
        let inner = opts.output.clone();
        let buf = output.clone();
        let sink: OutputSink = Arc::new(move |line: &str| {
            if let Ok(mut b) = buf.lock() {
                b.push_str(line);
                b.push('\n');
                if b.len() > OUTPUT_LIMIT * 2 {
                    // Keep the tail (on a character boundary).
                    let mut cut = b.len() - OUTPUT_LIMIT;
                    while !b.is_char_boundary(cut) {
                        cut += 1;
                    }
                    b.drain(..cut);
                }
            }
            inner(line)
        });
        opts.output = sink;
        Recorder { output }
    }

    /// A run starts: registered for recording (written now with `--db`, else when
    /// the script opens the database). Problems are warnings: the run goes on.
    pub(super) fn start(&self, a: &ScriptArgs, opts: &RunOptions) {
        if let Ok(mut b) = self.output.lock() {
            b.clear();
        }
        // Capped reads of regular files only: a FIFO or device must not block the run.
        let hash = |p: &std::path::Path, kind| {
            crate::fsutil::read_file(p, kind)
                .ok()
                .map(|b| format!("{:016x}", crate::fsutil::content_hash(&b)))
        };
        let run = NewRun {
            script: opts.project.display(&opts.script),
            document: opts.doc.as_ref().map(|d| opts.project.display(d)),
            script_hash: hash(&opts.script, crate::fsutil::FileKind::Script),
            document_hash: opts
                .doc
                .as_deref()
                .and_then(|d| hash(d, crate::fsutil::FileKind::Document)),
        };
        let target = Target::resolve(None, opts.project.root());
        if let Err(e) = recording::begin(target, run, a.db.is_some()) {
            errln!("warning: the run is not recorded: {e}");
        }
    }

    /// A run ended: its status and output are stored.
    pub(super) fn finish(&self, result: &Result<(), ScriptError>) {
        let status = match result {
            Ok(()) => RunStatus::Ok,
            Err(ScriptError::Cancelled) => RunStatus::Cancelled,
            Err(_) => RunStatus::Failed,
        };
        let mut output = self.output.lock().map(|b| b.clone()).unwrap_or_default();
        if let Err(e) = result {
            output.push_str(&format!("error: {}\n", e.render()));
        }
        if output.len() > OUTPUT_LIMIT {
            let mut cut = output.len() - OUTPUT_LIMIT;
            while !output.is_char_boundary(cut) {
                cut += 1;
            }
            output.drain(..cut);
        }
        if let Err(e) = recording::finish(status, &output) {
            errln!("warning: the end of the run is not recorded: {e}");
        }
    }
}
