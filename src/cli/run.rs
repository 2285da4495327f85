//! `fitup run` and `fitup watch`.

use super::out::{errln, outln};
use super::{CliError, Exit, ScriptArgs};
use crate::math::format;
use crate::script::{
    run_script, Arguments, Caches, Dispatch, Limits, Project, RunOptions, ScriptError,
};
use crate::watch::{watch_with, WatchEvent};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// The options of a run, or the exit status and message of why not: a file named on
/// the command line that is missing or refused by the path rule exits 1 (a script or
/// document error, like every refused path), malformed arguments exit 2 (usage).
fn options(a: &ScriptArgs) -> Result<RunOptions, (Exit, String)> {
    let fail = |e: CliError| (Exit::Failure, e.to_string());
    let (project, script) = project_of(a, "script").map_err(fail)?;
    let doc = match &a.doc {
        Some(d) => Some(inside(&project, d, "document").map_err(fail)?),
        None => None,
    };
    let args = Arguments::parse(&a.args).map_err(|e| (Exit::Usage, e.to_string()))?;
    Ok(RunOptions {
        script,
        doc,
        project,
        limits: Limits {
            max_operations: a.max_operations,
            max_seconds: a.max_seconds,
            dispatch: match (a.dispatch.dispatch, a.dispatch.allow_remote) {
                (false, _) => Dispatch::Never,
                (true, false) => Dispatch::Loopback,
                (true, true) => Dispatch::Remote,
            },
            ..Limits::default()
        },
        cancel: Arc::new(AtomicBool::new(false)),
        output: Arc::new(|line: &str| super::out::line(line)),
        args,
    })
}

/// The project of a run (the path rule of [`Project`]: `--root`, else the nearest
/// folder of the script holding `fitup.toml`, else the script's folder) and the
/// script's absolute path. Command-line paths are relative to the current folder.
fn project_of(
    a: &ScriptArgs,
    what: &'static str,
) -> Result<(Project, std::path::PathBuf), CliError> {
    let path_error = |source| CliError::Path {
        what,
        path: a.script.clone(),
        source,
    };
    let script = std::path::absolute(&a.script).map_err(path_error)?;
    // Anything else that exists (a folder, a FIFO) is refused by name when it is read.
    if !script.exists() {
        return Err(CliError::Missing {
            what,
            path: a.script.clone(),
        });
    }
    let project = match &a.root {
        Some(r) => Project::new(r).map_err(|source| CliError::ProjectFolder {
            path: r.clone(),
            source,
        })?,
        None => Project::for_file(&script).map_err(path_error)?,
    };
    let script = project
        .resolve(&script.to_string_lossy())
        .map_err(|source| CliError::Refused {
            what,
            source,
            root_hint: true,
        })?;
    Ok((project, script))
}

/// A command-line path (relative to the current folder), checked to lie inside the
/// project; `what` names it in errors.
fn inside(
    project: &Project,
    path: &std::path::Path,
    what: &'static str,
) -> Result<std::path::PathBuf, CliError> {
    let abs = std::path::absolute(path).map_err(|source| CliError::Path {
        what,
        path: path.to_path_buf(),
        source,
    })?;
    project
        .resolve(&abs.to_string_lossy())
        .map_err(|source| CliError::Refused {
            what,
            source,
            root_hint: false,
        })
}

/// Whether the file is a robot motion program rather than a Rhai script.
fn is_program(path: &std::path::Path) -> bool {
    path.extension().is_none_or(|e| e != "rhai")
}

pub(super) fn run(a: &ScriptArgs) -> Exit {
    if is_program(&a.script) {
        if !a.args.is_empty() {
            errln!(
                "error: script arguments (after `--`) are for .rhai scripts; {} is a motion program",
                a.script.display()
            );
            return Exit::Usage;
        }
        return match run_program(a) {
            Ok(()) => Exit::Ok,
            Err((exit, message)) => {
                errln!("error: {message}");
                exit
            }
        };
    }
    let mut opts = match options(a) {
        Ok(o) => o,
        Err((exit, e)) => {
            errln!("error: {e}");
            return exit;
        }
    };
    let live = match super::view::start(
        &a.view,
        a.force,
        std::slice::from_ref(&opts.script),
        &opts.project,
        Some(run_name(&opts.script, None)),
    ) {
        Ok(l) => l,
        Err(e) => {
            errln!("error: {e}");
            return Exit::Usage;
        }
    };
    let recorder = super::db::Recorder::new(a, &mut opts);
    recorder.start(a, &opts);
    let caches = Caches {
        view: super::view::handle(&live),
        ..Caches::default()
    };
    let outcome = run_script(&opts, &Arc::new(caches));
    recorder.finish(&outcome.result);
    let exit = match outcome.result {
        Ok(()) => Exit::Ok,
        Err(e) => {
            errln!("error: {}", e.render());
            Exit::Failure
        }
    };
    super::view::finish(live);
    exit
}

/// The name of a run's recording in the viewer: the script's file name (and the run
/// number in watch mode).
fn run_name(script: &std::path::Path, number: Option<u64>) -> String {
    let file = script
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    match number {
        Some(n) => format!("{file} run {n}"),
        None => file,
    }
}

pub(super) fn watch(a: &ScriptArgs) -> Exit {
    let mut opts = match options(a) {
        Ok(o) => o,
        Err((exit, e)) => {
            errln!("error: {e}");
            return exit;
        }
    };
    let live = match super::view::start(
        &a.view,
        a.force,
        std::slice::from_ref(&opts.script),
        &opts.project,
        None,
    ) {
        Ok(l) => l,
        Err(e) => {
            errln!("error: {e}");
            return Exit::Usage;
        }
    };
    let viewer = super::view::handle(&live);
    let caches = Arc::new(Caches {
        view: viewer.clone(),
        ..Caches::default()
    });
    let recorder = super::db::Recorder::new(a, &mut opts);
    let run_opts = opts.clone();
    let project = opts.project.clone();
    let stop = Arc::new(AtomicBool::new(false));
    outln!(
        "watching {} (Ctrl-C to stop)",
        project.display(&opts.script)
    );
    let result = watch_with(opts, caches, stop, |event| match event {
        WatchEvent::RunStarted { number, changed } => {
            viewer.new_run(&run_name(&run_opts.script, Some(number)));
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
            outln!("== run {number} at {} ({what})", clock());
        }
        WatchEvent::RunFinished { number, outcome } => {
            recorder.finish(&outcome.result);
            let ms = format::number(outcome.elapsed.as_secs_f64() * 1000.0, 1);
            let ops = format::count(outcome.operations);
            match &outcome.result {
                Ok(()) => outln!("== done {number} ok in {ms} ms ({ops} operations)"),
                Err(ScriptError::Cancelled) => {
                    outln!("== done {number} cancelled after {ms} ms (a newer save)")
                }
                Err(e) => {
                    outln!("{}", e.render());
                    outln!("== done {number} error in {ms} ms");
                }
            }
        }
        WatchEvent::Warning(w) => outln!("warning: {w}"),
        WatchEvent::Notice(n) => outln!("== {n}"),
    });
    match result {
        Ok(()) => Exit::Ok,
        Err(e) => {
            errln!("error: file watching failed: {e}");
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
    // A refused or missing file named on the command line exits 1, like every
    // refused path.
    let cli = |e: CliError| (Exit::Failure, e.to_string());
    let (project, program_path) = project_of(a, "program").map_err(cli)?;
    let doc_arg = a.doc.as_ref().ok_or_else(|| {
        usage(format!(
            "{} is a robot program (not .rhai): pass --doc with the document holding the robot",
            a.script.display()
        ))
    })?;
    let doc_path = inside(&project, doc_arg, "document").map_err(cli)?;
    let fail = |m: String| (Exit::Failure, m);
    let mut doc =
        crate::document::Document::load_in(&doc_path, &project, &mut crate::mesh::MeshCache::new())
            .map_err(|e| fail(e.render()))?;
    for w in doc.warnings() {
        super::out::error_line(&format!("warning: {w}"));
    }
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
    // Inside the project (as `project_of` resolved it): read through the held root.
    let text = project
        .read_text(&program_path, crate::fsutil::FileKind::Program)
        .map_err(|e| fail(format!("{}: {e}", a.script.display())))?;
    let program = crate::kinematics::parse_program(&project.display(&program_path), &text)
        .map_err(|e| fail(e.to_string()))?;
    let trajectory = doc
        .run_robot_program(
            index,
            &program,
            &crate::kinematics::MotionOptions::default(),
        )
        .map_err(|e| fail(e.to_string()))?;
    // The document's files and the program: never replaced by the log or the
    // recording, not even with --force.
    let mut sources = doc.source_files();
    sources.push(program_path.clone());
    let live = super::view::start(
        &a.view,
        a.force,
        &sources,
        &project,
        Some(run_name(&program_path, None)),
    )
    .map_err(cli)?;
    let viewer = super::view::handle(&live);
    viewer.log_document(&doc);
    viewer.log_trajectory(&doc, index, &trajectory);
    let csv = trajectory.to_csv(crate::math::AngleConvention::default());
    match &a.log {
        Some(log) => {
            let abs = std::path::absolute(log).map_err(|e| usage(format!("log: {e}")))?;
            let rule = crate::project::OutputRule::forced(a.force).protecting(&sources);
            project
                .write_output(&abs.to_string_lossy(), csv.as_bytes(), &rule)
                .map_err(|e| fail(format!("--log: {e}")))?;
            outln!(
                "{}: {} samples, {} s; log written to {}",
                doc.robots()[index].name(),
                trajectory.samples.len(),
                format::number(trajectory.duration(), 3),
                log.display()
            );
        }
        None => super::out::write(super::out::Stream::Stdout, &csv),
    }
    super::view::finish(live);
    Ok(())
}
