//! The `fitup` command line: parsed flags ([`Cli`]) are kept apart from what each
//! command does; `main` maps errors to exit codes (0 ok, 1 script or document error,
//! 2 usage).

mod batch;
mod cache;
mod check;
mod db;
mod error;
mod import;
pub(crate) mod out;
mod run;
mod sequence;
mod skills;
mod skills_tui;
mod view;

pub use error::CliError;

use clap::{Parser, Subcommand};
use out::{errln, outln};
use std::path::{Path, PathBuf};

/// fitup: scripting engine for robotic assembly (SolidWorks-API macros without SolidWorks).
#[derive(Debug, Parser)]
#[command(name = "fitup", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Options of `run`.
#[derive(Debug, clap::Args, Clone)]
pub struct ScriptArgs {
    /// The Rhai script (`.rhai`), or a robot motion program (any other extension:
    /// needs `--doc`, and `--robot` when the document has several robots).
    pub script: PathBuf,
    /// A document to open and provide to the script as `doc`.
    #[arg(long)]
    pub doc: Option<PathBuf>,
    /// The project folder that bounds file access [default: the nearest folder of the
    /// script holding `fitup.toml`, else the script's folder].
    #[arg(long)]
    pub root: Option<PathBuf>,
    /// The robot of `--doc` that runs a motion program.
    #[arg(long)]
    pub robot: Option<String>,
    /// Where to write a motion program's joint/TCP log (CSV) [default: standard output].
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Let `--log` and `--record` replace an existing file that the project uses or that
    /// fitup did not write (never a folder, FIFO or symbolic link); see "What a run
    /// writes" in docs/scripting.md. A script's own writers take `overwrite: true`.
    #[arg(long)]
    pub force: bool,
    /// Operation limit of the sandbox (roughly: expressions evaluated, over the script
    /// and its imports); the default stops an endless loop within about two seconds.
    #[arg(long, default_value_t = crate::script::Limits::default().max_operations)]
    pub max_operations: u64,
    /// Time limit of the run, seconds (0: none). The operation limit alone does not
    /// bound time (a call on a large array costs one operation).
    #[arg(long, default_value_t = crate::script::Limits::default().max_seconds)]
    pub max_seconds: u64,
    /// Script arguments after `--`: `key=value …`, the map `args` in the script
    /// (numbers become numbers, `true`/`false` booleans, anything else text).
    #[arg(last = true, value_name = "KEY=VALUE")]
    pub args: Vec<String>,
    /// Record every run in the results database: `--db` alone for the project's
    /// (`FITUP_DB`, else `fitup.db`), or `--db FILE|postgres://…`; the script's
    /// `open_db()` opens the same one.
    #[arg(long, num_args = 0..=1, default_missing_value = "")]
    pub db: Option<String>,
    /// Whether the script may command a manipulator (`--dispatch`, `--allow-remote`).
    #[command(flatten)]
    pub dispatch: DispatchArgs,
    /// The live 3D viewer (`--view`, `--open`, `--record FILE.rrd`).
    #[command(flatten)]
    pub view: ViewArgs,
}

/// Permission for a script's skill manager to reach a real controller (docs/skills.md).
#[derive(Debug, clap::Args, Clone, Copy, Default)]
pub struct DispatchArgs {
    /// Let the script's skill manager command a manipulator over TCP on this
    /// machine (`skill_manager(#{target: "127.0.0.1:11000"})`); without it only the
    /// in-process simulator (`target: "sim"`) runs.
    #[arg(long)]
    pub dispatch: bool,
    /// With `--dispatch`: also to an address that is not this machine (a real
    /// controller).
    #[arg(long, requires = "dispatch")]
    pub allow_remote: bool,
}

/// Options of the live 3D viewer (docs/viewer.md).
#[derive(Debug, clap::Args, Clone, Default)]
pub struct ViewArgs {
    /// Show the run in the live 3D viewer: serves it on 127.0.0.1 and prints the address
    /// (`run` keeps serving after the script until Ctrl-C; `watch` shows every rerun).
    #[arg(long)]
    pub view: bool,
    /// With `--view`: also open the address in the default browser.
    #[arg(long, requires = "view")]
    pub open: bool,
    /// Save the run as a Rerun recording (`.rrd`; `fitup view FILE` shows it again). In
    /// watch mode the file holds the latest run.
    #[arg(long, value_name = "FILE.rrd")]
    pub record: Option<PathBuf>,
}

/// Options of `watch` (a Rhai script only: motion programs are run with `run`).
#[derive(Debug, clap::Args, Clone)]
pub struct WatchArgs {
    /// The Rhai script (`.rhai`).
    pub script: PathBuf,
    /// A document to open and provide to the script as `doc`.
    #[arg(long)]
    pub doc: Option<PathBuf>,
    /// The project folder that bounds file access [default: the current folder].
    #[arg(long)]
    pub root: Option<PathBuf>,
    /// Operation limit of the sandbox per run (roughly: expressions evaluated, over the
    /// script and its imports); a new save cancels a running script anyway.
    #[arg(long, default_value_t = crate::script::Limits::default().max_operations)]
    pub max_operations: u64,
    /// Time limit of each run, seconds (0: none); a new save cancels a running script
    /// anyway.
    #[arg(long, default_value_t = crate::script::Limits::default().max_seconds)]
    pub max_seconds: u64,
    /// Script arguments after `--`: `key=value …`, the map `args` in the script.
    #[arg(last = true, value_name = "KEY=VALUE")]
    pub args: Vec<String>,
    /// Record every run in the results database: `--db` alone for the project's
    /// (`FITUP_DB`, else `fitup.db`), or `--db FILE|postgres://…`; the script's
    /// `open_db()` opens the same one.
    #[arg(long, num_args = 0..=1, default_missing_value = "")]
    pub db: Option<String>,
    /// Let `--record` replace an existing file that the project uses or that
    /// fitup did not write (never a folder, FIFO or symbolic link); see "What a run
    /// writes" in docs/scripting.md. A script's own writers take `overwrite: true`.
    #[arg(long)]
    pub force: bool,
    /// Whether the script may command a manipulator (`--dispatch`, `--allow-remote`).
    #[command(flatten)]
    pub dispatch: DispatchArgs,
    /// The live 3D viewer (`--view`, `--open`, `--record FILE.rrd`).
    #[command(flatten)]
    pub view: ViewArgs,
}

impl From<WatchArgs> for ScriptArgs {
    fn from(w: WatchArgs) -> Self {
        ScriptArgs {
            script: w.script,
            doc: w.doc,
            root: w.root,
            robot: None,
            log: None,
            force: w.force,
            max_operations: w.max_operations,
            max_seconds: w.max_seconds,
            args: w.args,
            db: w.db,
            dispatch: w.dispatch,
            view: w.view,
        }
    }
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a script once (or a robot motion program with `--doc`).
    Run(ScriptArgs),
    /// Run a script once per document (`--docs A.yaml B.yaml …`), in parallel on
    /// all cores; each run independent (recorded with `--db` like `run`).
    Batch(batch::BatchArgs),
    /// Run a script, then again on every save of the script, the document or any file it read.
    Watch(WatchArgs),
    /// Validate a document and print a summary.
    Check {
        /// The document (`.yaml`).
        doc: PathBuf,
    },
    /// Write a document as binary glTF (`.glb`) for other viewers: one node per
    /// component at its pose, named as the component; metres, +Y up.
    Export {
        /// The document (`.yaml`).
        doc: PathBuf,
        /// The output file (`.glb`; its folder is created when missing). An existing
        /// file is replaced only when fitup wrote it (or with `--force`), never a file
        /// the document was built from.
        out: PathBuf,
        /// Replace `out` even when fitup did not write it.
        #[arg(long)]
        force: bool,
    },
    /// Write the scripting API reference (generated from the registered functions).
    Docs {
        /// Output file (its folder is created when missing), or `-` for standard output.
        /// An existing file is replaced only when fitup wrote it (or with `--force`).
        #[arg(long, default_value = "docs/api.md")]
        out: PathBuf,
        /// Replace `--out` even when fitup did not write it (never a folder, FIFO or
        /// symbolic link).
        #[arg(long)]
        force: bool,
    },
    /// The results database: `runs`, `paths`, `show ID`, `export ID --csv|--json`,
    /// `diff RUN_A RUN_B`.
    Db(db::DbArgs),
    /// A simulated manipulator controller on 127.0.0.1 (simple_message): moves a robot
    /// of the document, refuses trajectories that break joint limits or collide.
    Manipulator(skills::ManipulatorArgs),
    /// Skills: `run PLAN --target HOST:PORT` dispatches a plan to a controller.
    Skills(skills::SkillsArgs),
    /// Show a saved recording (`--record FILE.rrd`) in the viewer, served on 127.0.0.1
    /// until Ctrl-C.
    View {
        /// The recording (`.rrd`).
        file: PathBuf,
        /// Also open the address in the default browser.
        #[arg(long)]
        open: bool,
    },
    /// Write the demo project (seed 000 fig. 11) into a folder: `fitup.toml`,
    /// `models/cell.yaml` and `models/meshes/`.
    Demo {
        /// Target folder: new or empty, unless `--force`.
        dir: PathBuf,
        /// Write into a folder that is not empty, replacing `cell.yaml` and the demo meshes.
        #[arg(long)]
        force: bool,
    },
    /// Import a STEP assembly (SolidWorks, CATIA, … export) as a new document: one part
    /// per distinct solid (STL), one component per placed solid (needs `--features step`).
    Import(import::ImportArgs),
    /// The project's caches: `prune` removes stale STEP tessellations.
    Cache(cache::CacheArgs),
    /// Plan the assembly sequence of a document (seed 003): tasks, mounts, precedence.
    PlanSequence {
        /// The document (`.yaml`).
        doc: PathBuf,
        /// `mates` (the relation graph) or `geometry` (meshes only).
        #[arg(long, default_value = "mates")]
        mode: String,
        /// Pin the base component.
        #[arg(long)]
        base: Option<String>,
        /// Components or parts that are screwed (repeatable).
        #[arg(long)]
        threaded: Vec<String>,
        /// Time budget of the whole call (ms), honoured within 5 %; default 30000.
        #[arg(long)]
        time_limit_ms: Option<f64>,
        /// A component that is not part of the product (fixture, table; repeatable).
        /// Robot links and components marked `fixture: true` are always left out.
        #[arg(long)]
        exclude: Vec<String>,
        /// The product's components (repeatable; default: all but robots and `--exclude`).
        #[arg(long)]
        component: Vec<String>,
        /// Allow parts that touch nothing placed yet (floating sub-assemblies).
        #[arg(long)]
        no_support: bool,
        /// Respect gravity along this down direction, `x,y,z` (parts move down or
        /// sideways into place).
        #[arg(long, allow_hyphen_values = true)]
        gravity: Option<String>,
        /// How many sequences to rank (1 to 1000).
        #[arg(long, default_value_t = 5)]
        max_sequences: usize,
        /// Any key of the sequence options (the table of `assembly_sequence` in
        /// docs/api.md, the same keys as scripts and Python), `KEY=VALUE`
        /// (repeatable; e.g. `--option tolerance=0.05 --option contact_gap_mm=3`).
        /// Lists are comma-separated. Wins over the flags above.
        #[arg(long = "option", short = 'o', value_name = "KEY=VALUE")]
        option: Vec<String>,
        /// Print the plan as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// Exit status of a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Success.
    Ok = 0,
    /// A script, document or input error.
    Failure = 1,
    /// Bad command-line usage.
    Usage = 2,
}

/// Runs the command line; returns the process exit code.
pub fn main() -> i32 {
    // The STEP child reader (`fitup __step-read …`, src/mesh/step.rs): this binary
    // re-executed so that Open CASCADE runs in a process of its own, capped in time and
    // memory; every STEP read of this process goes there.
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args
        .get(1)
        .is_some_and(|a| a == crate::mesh::step::CHILD_COMMAND)
    {
        return crate::mesh::step::serve_child(&args[2..]);
    }
    if crate::mesh::step::AVAILABLE {
        if let Ok(me) = std::env::current_exe() {
            crate::mesh::step::read_in_child_processes(me);
        }
    }
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // Help and errors go through the writer too (`fitup --help | head`).
            let text = e.render().to_string();
            let (stream, code) = if e.use_stderr() {
                (out::Stream::Stderr, Exit::Usage)
            } else {
                (out::Stream::Stdout, Exit::Ok)
            };
            out::write(stream, &text);
            return code as i32;
        }
    };
    let exit = match cli.command {
        Command::Run(a) => run::run(&a),
        Command::Batch(a) => batch::batch(&a),
        Command::Watch(a) => run::watch(&a.into()),
        Command::Db(a) => db::main(&a),
        Command::Check { doc } => check::check(&doc),
        Command::Docs { out, force } => docs(&out, force),
        Command::Export { doc, out, force } => export(&doc, &out, force),
        Command::Demo { dir, force } => demo(&dir, force),
        Command::Manipulator(a) => skills::manipulator(&a),
        Command::Skills(a) => skills::skills(&a),
        Command::Import(a) => import::import(&a),
        Command::Cache(a) => cache::cache(&a),
        Command::PlanSequence {
            doc,
            mode,
            base,
            threaded,
            time_limit_ms,
            exclude,
            component,
            no_support,
            gravity,
            max_sequences,
            option,
            json,
        } => sequence::plan(sequence::Args {
            doc: &doc,
            mode: &mode,
            base,
            threaded,
            time_limit_ms,
            exclude,
            components: component,
            support: !no_support,
            gravity,
            max_sequences,
            options: option,
            json,
        }),
        Command::View { file, open } => view::view_file(&file, open),
    };
    exit as i32
}

/// `fitup export DOC OUT.glb [--force]`: [`crate::document::Document::export_glb`].
fn export(doc: &Path, out: &Path, force: bool) -> Exit {
    if !out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
    {
        errln!(
            "error: {}: fitup exports binary glTF only; name the output `….glb`",
            out.display()
        );
        return Exit::Usage;
    }
    let d = match crate::document::Document::open(doc) {
        Ok(d) => d,
        Err(e) => {
            errln!("error: {}", e.render());
            return Exit::Failure;
        }
    };
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        if let Err(e) = std::fs::create_dir_all(parent) {
            errln!(
                "error: cannot create the folder {} for {}: {e}",
                parent.display(),
                out.display()
            );
            return Exit::Failure;
        }
    }
    match d.export_glb(out, force) {
        Ok(x) => {
            outln!(
                "wrote {} ({} nodes, {} meshes, {} bytes)",
                x.path.display(),
                x.nodes,
                x.meshes,
                x.bytes
            );
            Exit::Ok
        }
        Err(e) => {
            errln!("error: {e}");
            Exit::Failure
        }
    }
}

/// `fitup docs [--out FILE|-] [--force]`: the output goes through the write rule
/// ([`crate::project::write_output`]).
fn docs(out: &Path, force: bool) -> Exit {
    let text = crate::script::api_reference();
    if out == Path::new("-") {
        out::write(out::Stream::Stdout, &text);
        return Exit::Ok;
    }
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        if let Err(e) = std::fs::create_dir_all(parent) {
            errln!(
                "error: cannot create the folder {} for {}: {e} (pass --out FILE, or --out - for standard output)",
                parent.display(),
                out.display()
            );
            return Exit::Failure;
        }
    }
    // A reference generated earlier (docs/api.md of a fresh clone) is recognised by
    // its title and "Generated by" line.
    let signature = text.split_inclusive('\n').take(3).collect::<String>();
    let rule = crate::project::OutputRule {
        signature: Some(signature.as_bytes()),
        ..crate::project::OutputRule::forced(force)
    };
    match crate::project::write_output(out, text.as_bytes(), &rule) {
        Ok(()) => {
            outln!("wrote {}", out.display());
            Exit::Ok
        }
        Err(e) => {
            errln!(
                "error: cannot write {}: {e} (pass --out FILE, or --out - for standard output)",
                out.display()
            );
            Exit::Failure
        }
    }
}

/// `fitup demo DIR [--force]`: refuses a folder that already holds something, so an
/// edited `cell.yaml` is never replaced by accident.
fn demo(dir: &Path, force: bool) -> Exit {
    if !force {
        match std::fs::read_dir(dir) {
            Ok(mut entries) => {
                if entries.next().is_some() {
                    errln!(
                        "error: {} is not empty: the demo would replace fitup.toml and models/ in it; \
                         choose a new folder, or pass --force to overwrite",
                        dir.display()
                    );
                    return Exit::Failure;
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => {
                errln!("error: {}: {e}", dir.display());
                return Exit::Failure;
            }
        }
    }
    match crate::demo::write_project_checked(dir, force) {
        Ok(()) => {
            outln!(
                "wrote {0}/fitup.toml, {0}/models/cell.yaml and its meshes",
                dir.display()
            );
            Exit::Ok
        }
        Err(e) => {
            errln!("error: {e}");
            Exit::Failure
        }
    }
}
