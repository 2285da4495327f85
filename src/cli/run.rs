//! `fitup run` and `fitup watch`.

use super::{Exit, ScriptArgs};
use crate::script::{run_script, Caches, Limits, Project, RunOptions, ScriptError};
use crate::watch::{watch as watch_loop, WatchEvent};
use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn options(a: &ScriptArgs) -> Result<RunOptions, String> {
    let root = match &a.root {
        Some(r) => r.clone(),
        None => {
            std::env::current_dir().map_err(|e| format!("cannot read the current folder: {e}"))?
        }
    };
    let project =
        Project::new(&root).map_err(|e| format!("project folder {}: {e}", root.display()))?;
    let script = project
        .resolve(&a.script.to_string_lossy())
        .map_err(|e| format!("script: {e} (pass --root)"))?;
    if !script.is_file() {
        return Err(format!("script {} does not exist", a.script.display()));
    }
    let doc = match &a.doc {
        Some(d) => Some(
            project
                .resolve(&d.to_string_lossy())
                .map_err(|e| format!("document: {e}"))?,
        ),
        None => None,
    };
    Ok(RunOptions {
        script,
        doc,
        project,
        limits: Limits {
            max_operations: a.max_operations,
            ..Limits::default()
        },
        cancel: Arc::new(AtomicBool::new(false)),
        output: Arc::new(|line: &str| {
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        }),
    })
}

pub(super) fn run(a: &ScriptArgs) -> Exit {
    let opts = match options(a) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return Exit::Usage;
        }
    };
    let outcome = run_script(&opts, &Arc::new(Caches::default()));
    match outcome.result {
        Ok(()) => Exit::Ok,
        Err(e) => {
            eprintln!("error: {}", e.render());
            Exit::Failure
        }
    }
}

pub(super) fn watch(a: &ScriptArgs) -> Exit {
    let opts = match options(a) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return Exit::Usage;
        }
    };
    let project = opts.project.clone();
    let stop = Arc::new(AtomicBool::new(false));
    println!(
        "watching {} (Ctrl-C to stop)",
        project.display(&opts.script)
    );
    let result = watch_loop(opts, stop, |event| {
        let mut out = std::io::stdout().lock();
        match event {
            WatchEvent::RunStarted { number, changed } => {
                let what = if changed.is_empty() {
                    "first run".to_string()
                } else {
                    changed
                        .iter()
                        .map(|p| project.display(p))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                let _ = writeln!(out, "== run {number} at {} ({what})", clock());
            }
            WatchEvent::RunFinished { number, outcome } => {
                let ms = outcome.elapsed.as_secs_f64() * 1000.0;
                match &outcome.result {
                    Ok(()) => {
                        let _ = writeln!(out, "== done {number} ok in {ms:.1} ms");
                    }
                    Err(ScriptError::Cancelled) => {
                        let _ = writeln!(
                            out,
                            "== done {number} cancelled after {ms:.1} ms (a newer save)"
                        );
                    }
                    Err(e) => {
                        let _ = writeln!(out, "{}", e.render());
                        let _ = writeln!(out, "== done {number} error in {ms:.1} ms");
                    }
                }
            }
            WatchEvent::Warning(w) => {
                let _ = writeln!(out, "warning: {w}");
            }
        }
        let _ = out.flush();
    });
    match result {
        Ok(()) => Exit::Ok,
        Err(e) => {
            eprintln!("error: file watching failed: {e}");
            Exit::Failure
        }
    }
}

/// Wall-clock time of day (UTC) for run headers.
fn clock() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0);
    let day = secs % 86_400.0;
    format!(
        "{:02}:{:02}:{:06.3}",
        (day / 3600.0) as u32,
        ((day % 3600.0) / 60.0) as u32,
        day % 60.0
    )
}
