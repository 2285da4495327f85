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

/// Whether the file is a robot motion program rather than a Rhai script.
fn is_program(path: &std::path::Path) -> bool {
    path.extension().is_none_or(|e| e != "rhai")
}

pub(super) fn run(a: &ScriptArgs) -> Exit {
    if is_program(&a.script) {
        return match run_program(a) {
            Ok(()) => Exit::Ok,
            Err((exit, message)) => {
                eprintln!("error: {message}");
                exit
            }
        };
    }
    let mut opts = match options(a) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return Exit::Usage;
        }
    };
    let recorder = super::db::Recorder::new(a, &mut opts);
    recorder.start(a, &opts);
    let outcome = run_script(&opts, &Arc::new(Caches::default()));
    recorder.finish(&outcome.result);
    match outcome.result {
        Ok(()) => Exit::Ok,
        Err(e) => {
            eprintln!("error: {}", e.render());
            Exit::Failure
        }
    }
}

pub(super) fn watch(a: &ScriptArgs) -> Exit {
    let mut opts = match options(a) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return Exit::Usage;
        }
    };
    let recorder = super::db::Recorder::new(a, &mut opts);
    let run_opts = opts.clone();
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
                recorder.start(a, &run_opts);
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
                recorder.finish(&outcome.result);
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

/// `fitup run PROGRAM --doc DOC [--robot NAME] [--log CSV]`: runs a motion program on a
/// robot of the document from its saved joints and prints (or writes) the joint/TCP log.
fn run_program(a: &ScriptArgs) -> Result<(), (Exit, String)> {
    let usage = |m: String| (Exit::Usage, m);
    let root = match &a.root {
        Some(r) => r.clone(),
        None => std::env::current_dir()
            .map_err(|e| usage(format!("cannot read the current folder: {e}")))?,
    };
    let project = Project::new(&root)
        .map_err(|e| usage(format!("project folder {}: {e}", root.display())))?;
    let program_path = project
        .resolve(&a.script.to_string_lossy())
        .map_err(|e| usage(format!("program: {e} (pass --root)")))?;
    let doc_arg = a.doc.as_ref().ok_or_else(|| {
        usage(format!(
            "{} is a robot program (not .rhai): pass --doc with the document holding the robot",
            a.script.display()
        ))
    })?;
    let doc_path = project
        .resolve(&doc_arg.to_string_lossy())
        .map_err(|e| usage(format!("document: {e}")))?;
    let fail = |m: String| (Exit::Failure, m);
    let mut doc = crate::document::Document::open(&doc_path).map_err(|e| fail(e.render()))?;
    let index = match &a.robot {
        Some(name) => doc.robot_index(name).map_err(|e| usage(e.to_string()))?,
        None => match doc.robots().len() {
            1 => 0,
            0 => return Err(fail(format!("{} has no robots", doc_arg.display()))),
            _ => {
                let names: Vec<&str> = doc.robots().iter().map(|r| r.name()).collect();
                return Err(usage(format!(
                    "{} has several robots ({}): pass --robot",
                    doc_arg.display(),
                    names.join(", ")
                )));
            }
        },
    };
    let text = std::fs::read_to_string(&program_path)
        .map_err(|e| fail(format!("cannot read {}: {e}", a.script.display())))?;
    let program = crate::kinematics::parse_program(&project.display(&program_path), &text)
        .map_err(|e| fail(e.to_string()))?;
    let trajectory = doc
        .run_robot_program(
            index,
            &program,
            &crate::kinematics::MotionOptions::default(),
        )
        .map_err(|e| fail(e.to_string()))?;
    let csv = trajectory.to_csv(crate::math::AngleConvention::default());
    match &a.log {
        Some(log) => {
            let path = project
                .resolve(&log.to_string_lossy())
                .map_err(|e| usage(format!("log: {e}")))?;
            crate::fsutil::write_atomic(&path, csv.as_bytes())
                .map_err(|e| fail(format!("cannot write {}: {e}", log.display())))?;
            println!(
                "{}: {} samples, {:.3} s; log written to {}",
                doc.robots()[index].name(),
                trajectory.samples.len(),
                trajectory.duration(),
                log.display()
            );
        }
        None => print!("{csv}"),
    }
    Ok(())
}
