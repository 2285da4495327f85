//! `fitup manipulator` (the simulated controller) and `fitup skills run` (the skill
//! manager, line by line).

use super::out::{errln, outln};
use super::Exit;
use crate::manipulator::message::ByteOrder;
use crate::manipulator::simulator::{Simulator, SimulatorOptions};
use crate::skills::{LogDb, ManagerEvent, ManagerOptions, RunSink, SkillLog, SkillManager};
use std::io::IsTerminal;
use std::path::PathBuf;

/// Options of `manipulator`.
#[derive(Debug, clap::Args, Clone)]
pub struct ManipulatorArgs {
    /// The cell document (`.yaml`).
    #[arg(long)]
    pub doc: PathBuf,
    /// The robot of the document the controller moves.
    #[arg(long)]
    pub robot: String,
    /// Motion port on 127.0.0.1 (JOINT_TRAJ_PT, tool commands); 0 picks a free one.
    #[arg(long, default_value_t = crate::manipulator::MOTION_PORT)]
    pub port: u16,
    /// State port on 127.0.0.1 (JOINT_POSITION, STATUS); 0 picks a free one
    /// [default: the motion port + 2, the rule `skills run` follows too].
    #[arg(long)]
    pub state_port: Option<u16>,
    /// Byte order of simple_message: `auto` detects it per motion connection from its
    /// first length prefix (a sane length reads sanely in one order only); a state
    /// connection, whose client never sends, speaks the order of the last motion
    /// connection heard before it connected, else big-endian. `big` or `little`
    /// forces one on every connection (`little` for industrial_core's default x86
    /// build when its state node connects first).
    #[arg(long, value_enum, default_value_t = WireOrder::Auto)]
    pub byte_order: WireOrder,
    /// Time scale: 1 is real time, 10 ten times faster.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
}

/// `--byte-order` of `manipulator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WireOrder {
    /// Detect per connection.
    Auto,
    /// Big-endian (network order).
    Big,
    /// Little-endian.
    Little,
}

/// `--byte-order` of `skills run`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ClientOrder {
    /// Big-endian (network order).
    Big,
    /// Little-endian.
    Little,
}

impl ClientOrder {
    fn order(self) -> ByteOrder {
        match self {
            Self::Big => ByteOrder::Big,
            Self::Little => ByteOrder::Little,
        }
    }
}

/// Options of `skills`.
#[derive(Debug, clap::Args, Clone)]
pub struct SkillsArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: SkillsCommand,
}

/// `skills` subcommands.
#[derive(Debug, clap::Subcommand, Clone)]
pub enum SkillsCommand {
    /// Dispatch a plan file (JSON: a script's `skills.save(FILE)`, or `Plan::to_json`)
    /// to a controller. On a terminal: a terminal UI (running / finished / pending
    /// skills, part states, live joints; keys p pause, r resume, a abort, m manual
    /// command, q quit). Otherwise (or `--plain`) one line per event, and standard
    /// input takes `pause`, `resume`, `abort`, `manual grasp|release|touch MM`,
    /// `manual output I 0|1`.
    Run {
        /// The plan file.
        plan: PathBuf,
        /// The controller's motion port `HOST:PORT`.
        #[arg(long, default_value = "127.0.0.1:11000")]
        target: String,
        /// The controller's state port [default: the motion port + 2, the rule
        /// `fitup manipulator --port` follows too].
        #[arg(long)]
        state_port: Option<u16>,
        /// Byte order of simple_message on both ports. Big-endian (network order,
        /// REP-I0006's examples) is what big-endian controllers' drivers put on the
        /// wire; `little` for a controller that speaks industrial_core's default x86
        /// (non-swap) order. `fitup manipulator` detects either.
        #[arg(long, value_enum, default_value_t = ClientOrder::Big)]
        byte_order: ClientOrder,
        /// Allow a target that is not this machine (a real controller).
        #[arg(long)]
        allow_remote: bool,
        /// Longest time to get the controller back after a disconnection (s).
        #[arg(long, default_value_t = 30.0)]
        reconnect_timeout: f64,
        /// Longest time one trajectory may take (s).
        #[arg(long, default_value_t = 120.0)]
        skill_timeout: f64,
        /// Write the execution log to the results database as it happens: `--db`
        /// alone for the project's (`FITUP_DB`, else `fitup.db` in the current
        /// folder), or `--db FILE|postgres://…`.
        #[arg(long, num_args = 0..=1, default_missing_value = "")]
        db: Option<String>,
        /// One line per event, commands from standard input, even on a terminal
        /// (the default when standard output or input is not a terminal).
        #[arg(long)]
        plain: bool,
    },
    /// Validate a task template (`models/templates/*.yaml` or your own copy): errors
    /// at `file:line:col`, then the chain of workflows.
    Template {
        /// The template file.
        file: PathBuf,
    },
}

/// `fitup manipulator …`: runs until killed.
pub(super) fn manipulator(a: &ManipulatorArgs) -> Exit {
    if !(a.speed.is_finite() && a.speed > 0.0 && a.speed <= 1000.0) {
        errln!("error: --speed must be in (0, 1000], got {}", a.speed);
        return Exit::Usage;
    }
    let doc = match crate::document::Document::open(&a.doc) {
        Ok(d) => d,
        Err(e) => {
            errln!("error: {}", e.render());
            return Exit::Failure;
        }
    };
    let Some(state_port) = a
        .state_port
        .or_else(|| crate::manipulator::state_port_for(a.port))
    else {
        errln!(
            "error: --port {} leaves no state port at +{}: give --state-port",
            a.port,
            crate::manipulator::STATE_PORT_OFFSET
        );
        return Exit::Usage;
    };
    let byte_order = match a.byte_order {
        WireOrder::Auto => None,
        WireOrder::Big => Some(ByteOrder::Big),
        WireOrder::Little => Some(ByteOrder::Little),
    };
    let options = SimulatorOptions {
        motion_port: a.port,
        state_port,
        speed: a.speed,
        byte_order,
        ..SimulatorOptions::default()
    };
    let sim = match Simulator::start(&doc, &a.robot, &options) {
        Ok(s) => s,
        Err(e) => {
            errln!("error: {e}");
            return Exit::Failure;
        }
    };
    outln!(
        "manipulator `{}` listening: motion {}, state {} (simple_message, {}), speed ×{}",
        a.robot,
        sim.motion_addr(),
        sim.state_addr(),
        byte_order.map_or_else(
            || "byte order detected per connection".to_string(),
            |o| o.to_string()
        ),
        a.speed
    );
    loop {
        std::thread::park();
    }
}

fn duration(s: f64, flag: &'static str) -> Result<std::time::Duration, super::CliError> {
    std::time::Duration::try_from_secs_f64(s)
        .map_err(|_| super::CliError::Seconds { flag, value: s })
}

/// The text of a file named on the command line, read through its project's held
/// root ([`crate::project::Project::read_named_text`]: a folder on the way swapped for
/// a link is refused, never followed), as `fitup check` reads its document.
fn read_in_its_project(file: &std::path::Path) -> Result<String, super::CliError> {
    let project =
        crate::project::Project::for_file(file).map_err(super::CliError::ProjectOfFile)?;
    Ok(project.read_named_text(file, crate::fsutil::FileKind::Document)?)
}

/// `fitup skills template FILE`.
fn template(file: &std::path::Path) -> Exit {
    let read = read_in_its_project(file)
        .map_err(|e| crate::diagnostics::SourceError::new(file, 0, 0, e.to_string()));
    match read.and_then(|text| crate::skills::Template::parse(file, &text)) {
        Ok(t) => {
            outln!("{}: {} template", file.display(), t.operation.name());
            for w in &t.workflows {
                outln!("  {} -> {}: {}", w.from.name(), w.to.name(), w.generator);
            }
            Exit::Ok
        }
        Err(e) => {
            errln!("error: {}", e.render());
            Exit::Failure
        }
    }
}

/// `fitup skills …`.
pub(super) fn skills(a: &SkillsArgs) -> Exit {
    if let SkillsCommand::Template { file } = &a.command {
        return template(file);
    }
    let SkillsCommand::Run {
        plan,
        target,
        state_port,
        byte_order,
        allow_remote,
        reconnect_timeout,
        skill_timeout,
        db,
        plain,
    } = &a.command
    else {
        unreachable!("handled above")
    };
    let (reconnect, skill) = match (
        duration(*reconnect_timeout, "reconnect-timeout"),
        duration(*skill_timeout, "skill-timeout"),
    ) {
        (Ok(r), Ok(s)) => (r, s),
        (Err(e), _) | (_, Err(e)) => {
            errln!("error: {e}");
            return Exit::Usage;
        }
    };
    let text = match read_in_its_project(plan) {
        Ok(t) => t,
        Err(e) => {
            errln!("error: {}: {e}", plan.display());
            return Exit::Failure;
        }
    };
    let plan_label = plan.display().to_string();
    let plan = match crate::skills::Plan::from_json(&plan_label, &text) {
        Ok(p) => p,
        Err(e) => {
            errln!("error: {e}");
            return Exit::Failure;
        }
    };
    let label = plan_label.clone();
    let db = match db {
        None => None,
        Some(d) => {
            let root = std::env::current_dir().unwrap_or_default();
            let target = crate::db::Target::resolve((!d.is_empty()).then_some(d.as_str()), &root);
            match crate::db::Database::open(&target) {
                Ok(db) => Some(db),
                Err(e) => {
                    errln!("error: {e}");
                    return Exit::Failure;
                }
            }
        }
    };
    let mut options = ManagerOptions {
        target: target.clone(),
        state_port: *state_port,
        skill_timeout: skill,
        reconnect_timeout: reconnect,
        ..ManagerOptions::default()
    };
    options.client.allow_remote = *allow_remote;
    options.client.byte_order = byte_order.order();
    let mut manager = SkillManager::new(plan, options);
    let handle = manager.handle();
    // Without `--db` nothing is logged; with it, the library's one policy (SkillLog):
    // a write that fails stops the run.
    let log = db.map(|db| SkillLog::new(None, label, manager.plan(), LogDb::Owned(Box::new(db))));
    let tui = !*plain && std::io::stdout().is_terminal() && std::io::stdin().is_terminal();
    let result = if tui {
        let shown = manager.plan().clone();
        let (tx, rx) = std::sync::mpsc::channel();
        let runner = std::thread::spawn(move || {
            let events = tx.clone();
            let r = manager.run_logged(
                log,
                &mut Cli(|e: &ManagerEvent| {
                    let _ = events.send(super::skills_tui::Msg::Manager(e.clone()));
                }),
            );
            let _ = tx.send(super::skills_tui::Msg::End(
                r.as_ref().err().map(|e| e.to_string()),
            ));
            r
        });
        let title = format!("fitup skills run {plan_label} → {target}");
        if let Err(e) = super::skills_tui::run(&shown, title, &handle, &rx) {
            handle.abort();
            errln!("error: the terminal UI failed: {e}");
        }
        runner
            .join()
            .unwrap_or(Err(crate::skills::ManagerError::Aborted))
    } else {
        // Commands from standard input; the thread ends with the process. Lines are
        // capped (fsutil::MAX_LINE_BYTES): a longer one is read and dropped in
        // bounded memory, with an error.
        std::thread::spawn(move || {
            let mut input = std::io::stdin().lock();
            loop {
                let line = match crate::fsutil::read_line_bounded(
                    &mut input,
                    crate::fsutil::MAX_LINE_BYTES,
                ) {
                    Ok(crate::fsutil::BoundedLine::Line(l)) => l,
                    Ok(crate::fsutil::BoundedLine::TooLong { bytes }) => {
                        errln!(
                                "error: standard input: a command line of {bytes} bytes is longer than {} bytes: ignored",
                                crate::fsutil::MAX_LINE_BYTES
                            );
                        continue;
                    }
                    Ok(crate::fsutil::BoundedLine::End) => break,
                    Err(e) => {
                        errln!("error: standard input: {e}; commands are no longer read");
                        break;
                    }
                };
                let l = line.trim();
                match l {
                    "pause" => handle.pause(),
                    "resume" => handle.resume(),
                    "abort" => handle.abort(),
                    "" => {}
                    _ => match l
                        .strip_prefix("manual ")
                        .and_then(crate::skills::ControllerCommand::parse_manual)
                    {
                        Some(c) => handle.manual(c),
                        None => errln!(
                            "unknown command `{}` (pause, resume, abort, manual grasp|release|touch MM, manual output I 0|1)",
                            crate::diagnostics::shorten(l, crate::document::scan::MAX_QUOTE)
                        ),
                    },
                }
            }
        });
        manager.run_logged(log, &mut Cli(|e: &ManagerEvent| outln!("{}", e.describe())))
    };
    match result {
        Ok(()) => {
            if tui {
                outln!("done");
            }
            Exit::Ok
        }
        Err(e) => {
            errln!("error: {e}");
            Exit::Failure
        }
    }
}

/// The CLI's sink of a run: each event to `F` (printed, or sent to the terminal UI);
/// a skill log that cannot be written is said at once.
struct Cli<F>(F);

impl<F: FnMut(&ManagerEvent)> RunSink for Cli<F> {
    fn event(&mut self, e: &ManagerEvent) -> bool {
        (self.0)(e);
        true
    }

    fn log_failed(&mut self, err: &crate::db::DbError) {
        errln!("error: the skill log could not be written: {err}; the run stops at the next skill boundary");
    }
}
