//! The `fitup` command line: parsed flags ([`Cli`]) are kept apart from what each
//! command does; `main` maps errors to exit codes (0 ok, 1 script or document error,
//! 2 usage).

mod check;
mod db;
mod run;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// fitup: scripting engine for robotic assembly (SolidWorks-API macros without SolidWorks).
#[derive(Debug, Parser)]
#[command(name = "fitup", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Options shared by `run` and `watch`.
#[derive(Debug, clap::Args, Clone)]
pub struct ScriptArgs {
    /// The Rhai script (`.rhai`), or a robot motion program (any other extension,
    /// `run` only: needs `--doc`, and `--robot` when the document has several robots).
    pub script: PathBuf,
    /// A document to open and provide to the script as `doc`.
    #[arg(long)]
    pub doc: Option<PathBuf>,
    /// The project folder that bounds file access [default: the current folder].
    #[arg(long)]
    pub root: Option<PathBuf>,
    /// The robot of `--doc` that runs a motion program.
    #[arg(long)]
    pub robot: Option<String>,
    /// Where to write a motion program's joint/TCP log (CSV) [default: standard output].
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Operation limit of the sandbox (roughly: expressions evaluated).
    #[arg(long, default_value_t = crate::script::Limits::default().max_operations)]
    pub max_operations: u64,
    /// Record every run in the results database: `--db` alone for the project's
    /// (`FITUP_DB`, else `fitup.db`), or `--db FILE|postgres://…`; the script's
    /// `open_db()` opens the same one.
    #[arg(long, num_args = 0..=1, default_missing_value = "")]
    pub db: Option<String>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a script once.
    Run(ScriptArgs),
    /// Run a script, then again on every save of the script, the document or any file it read.
    Watch(ScriptArgs),
    /// Validate a document and print a summary.
    Check {
        /// The document (`.yaml`).
        doc: PathBuf,
    },
    /// Write the scripting API reference (generated from the registered functions).
    Docs {
        /// Output file.
        #[arg(long, default_value = "docs/api.md")]
        out: PathBuf,
    },
    /// The results database: `runs`, `paths`, `show ID`, `export ID --csv|--json`,
    /// `diff RUN_A RUN_B`.
    Db(db::DbArgs),
    /// Write the demo cell (seed 000 fig. 11) into a folder: `cell.yaml` and `meshes/`.
    Demo {
        /// Target folder.
        dir: PathBuf,
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
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                Exit::Usage as i32
            } else {
                Exit::Ok as i32
            };
        }
    };
    let exit = match cli.command {
        Command::Run(a) => run::run(&a),
        Command::Watch(a) => run::watch(&a),
        Command::Db(a) => db::main(&a),
        Command::Check { doc } => check::check(&doc),
        Command::Docs { out } => {
            match crate::fsutil::write_atomic(&out, crate::script::api_reference().as_bytes()) {
                Ok(()) => {
                    println!("wrote {}", out.display());
                    Exit::Ok
                }
                Err(e) => {
                    eprintln!("error: cannot write {}: {e}", out.display());
                    Exit::Failure
                }
            }
        }
        Command::Demo { dir } => match crate::demo::write_cell(&dir) {
            Ok(()) => {
                println!("wrote {}/cell.yaml and its meshes", dir.display());
                Exit::Ok
            }
            Err(e) => {
                eprintln!("error: {e}");
                Exit::Failure
            }
        },
    };
    exit as i32
}
