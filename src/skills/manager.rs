//! The skill manager (seed 003, section 3.3): pending, running and finished skills,
//! dispatched to a controller over simple_message, with pause, resume, abort, edits
//! of pending skills and manual commands.
//!
//! Faults: when the controller disconnects mid-skill the skill is marked
//! interrupted, the manager reconnects and resumes that skill from where the arm
//! is; finished skills are never run again. Reconnection attempts back off (from
//! [`RECONNECT_FIRST_DELAY`], doubling, to [`RECONNECT_MAX_DELAY`]) and give up after
//! [`ManagerOptions::reconnect_timeout`]. A controller that drops the connection
//! twice at the same command (as a simulator does on a point it cannot decode) has
//! refused it: the run fails there instead of resending it forever. A refusal, a
//! controller error, a value the wire cannot carry or a timeout stops the run with
//! the reason. Pausing stops the arm at once; resuming
//! continues the running skill from where it stopped.

use super::program::{ControllerCommand, Plan, PlanStep};
use super::PartState;
use crate::db::SkillEvent;
use crate::manipulator::client::{
    resolve, AddressError, Client, ClientOptions, ManipulatorError, Request, WireError,
};
use crate::math::Deadline;
use std::collections::VecDeque;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The first pause between two connection attempts.
pub const RECONNECT_FIRST_DELAY: Duration = Duration::from_millis(100);
/// The longest pause between two connection attempts (the pause doubles up to it).
pub const RECONNECT_MAX_DELAY: Duration = Duration::from_secs(2);
/// Disconnections at the same command of a skill that make it a failure.
pub const MAX_DROPS_AT_ONE_COMMAND: usize = 2;

/// Where a skill is.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SkillStatus {
    /// Not started.
    Pending,
    /// Being executed.
    Running,
    /// Cut off by a disconnection; resumes after reconnecting.
    Interrupted,
    /// Done.
    Finished,
    /// Stopped the run.
    Failed(String),
}

/// What the manager reports while it runs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ManagerEvent {
    /// Connected to the controller.
    Connected(SocketAddr),
    /// A skill started (id, description).
    Started(usize, String),
    /// A skill finished; the part is now in `state`.
    Finished {
        /// Skill id.
        skill: usize,
        /// The part.
        part: String,
        /// Its new state.
        state: PartState,
    },
    /// The controller went away during a skill.
    Interrupted(usize, String),
    /// Reconnected; the interrupted skill resumes.
    Reconnected,
    /// Paused (the arm stopped).
    Paused,
    /// Resumed.
    Resumed,
    /// A pending skill was edited.
    Edited(usize),
    /// An edit was refused (the skill is not pending).
    EditRefused(usize, String),
    /// A manual command was executed.
    Manual(String),
    /// The run stopped on an error.
    Failed(usize, String),
    /// The run was aborted by the user.
    Aborted,
    /// Every skill finished.
    Done,
}

/// Settings of a run.
#[derive(Debug, Clone)]
pub struct ManagerOptions {
    /// Motion port address `HOST:PORT`.
    pub target: String,
    /// State port (default: [`crate::manipulator::state_port_for`] the motion port,
    /// + 2 as 11000 / 11002).
    pub state_port: Option<u16>,
    /// Client timeouts and the remote-dispatch switch.
    pub client: ClientOptions,
    /// Longest time one trajectory may take to finish after it was sent.
    pub skill_timeout: Duration,
    /// Longest time to get the controller back after a disconnection.
    pub reconnect_timeout: Duration,
    /// Joint tolerance for "arrived" (rad / mm).
    pub tolerance: f64,
}

impl Default for ManagerOptions {
    fn default() -> Self {
        Self {
            target: format!("127.0.0.1:{}", crate::manipulator::MOTION_PORT),
            state_port: None,
            client: ClientOptions::default(),
            skill_timeout: Duration::from_secs(120),
            reconnect_timeout: Duration::from_secs(30),
            tolerance: 1e-3,
        }
    }
}

/// The one cancel token of a skill run: set by the user's abort, by a [`RunSink`]
/// that stops the run or a log write that fails, or by the caller's own flag (a
/// script's cancellation, [`CancelToken::linked`]). The manager stops the arm as soon
/// as it sees it set.
#[derive(Debug, Clone, Default)]
pub struct CancelToken {
    own: Arc<AtomicBool>,
    outer: Option<Arc<AtomicBool>>,
}

impl CancelToken {
    /// A token of its own, not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// A token that is also cancelled while `outer` is set (a flag its owner sets and
    /// clears; [`reset`](Self::reset) leaves it alone).
    pub fn linked(outer: Arc<AtomicBool>) -> Self {
        Self {
            own: Arc::default(),
            outer: Some(outer),
        }
    }

    /// Cancels the run.
    pub fn cancel(&self) {
        self.own.store(true, Ordering::SeqCst);
    }

    /// Whether the run is cancelled (by this token or its outer flag).
    pub fn is_cancelled(&self) -> bool {
        self.own.load(Ordering::SeqCst)
            || self
                .outer
                .as_ref()
                .is_some_and(|o| o.load(Ordering::SeqCst))
    }

    /// Clears this token's own cancellation, for a new run.
    pub fn reset(&self) {
        self.own.store(false, Ordering::SeqCst);
    }
}

/// Where a skill run's events go, as they happen: the run loop's one output (as
/// ripgrep's `Sink` is a search's). The CLI prints them or feeds its terminal UI, a
/// script collects them and calls its callback; [`SkillManager::run_logged`] writes
/// them to the skill log first. Any `FnMut(&ManagerEvent)` is a sink that never stops
/// the run.
pub trait RunSink {
    /// Takes one event; `false` stops the run (the arm stops, as on an abort; the sink
    /// keeps its own reason).
    fn event(&mut self, event: &ManagerEvent) -> bool;

    /// The skill log could not be written, so the run stops at once (called once, before
    /// the event that was not written reaches [`event`](Self::event)).
    fn log_failed(&mut self, _error: &crate::db::DbError) {}
}

impl<F: FnMut(&ManagerEvent)> RunSink for F {
    fn event(&mut self, event: &ManagerEvent) -> bool {
        self(event);
        true
    }
}

#[derive(Default)]
struct Control {
    paused: AtomicBool,
    abort: CancelToken,
    manual: Mutex<VecDeque<ControllerCommand>>,
    edits: Mutex<VecDeque<(usize, PlanStep)>>,
    /// The controller's joints last seen (rad / mm).
    joints: Mutex<Vec<f64>>,
}

/// A handle to steer a running manager from another thread.
#[derive(Clone)]
pub struct ManagerHandle(Arc<Control>);

impl Default for ManagerHandle {
    fn default() -> Self {
        Self::new()
    }
}

impl ManagerHandle {
    /// A handle not yet bound to a manager (see [`SkillManager::with_handle`]):
    /// steering calls made before the run are applied when it starts.
    pub fn new() -> Self {
        Self(Arc::new(Control::default()))
    }
    /// A handle whose runs stop on `cancel` as well (e.g. a token
    /// [`linked`](CancelToken::linked) to a script's cancellation).
    pub fn with_cancel(cancel: CancelToken) -> Self {
        Self(Arc::new(Control {
            abort: cancel,
            ..Control::default()
        }))
    }
    /// The run's cancel token (what [`abort`](Self::abort) sets).
    pub fn cancel_token(&self) -> CancelToken {
        self.0.abort.clone()
    }
    /// The controller's joints last seen by the manager (rad / mm; empty before the
    /// first motion), refreshed while a trajectory runs.
    pub fn joints(&self) -> Vec<f64> {
        lock(&self.0.joints).clone()
    }
    /// Clears a previous abort and pause, for a new run.
    pub fn reset(&self) {
        self.0.abort.reset();
        self.0.paused.store(false, Ordering::SeqCst);
    }
    /// Whether the run's cancel token is set ([`abort`](Self::abort) was called and not
    /// [`reset`](Self::reset), or its outer flag is set).
    pub fn aborted(&self) -> bool {
        self.0.abort.is_cancelled()
    }
    /// Pauses: the arm stops now; the running skill resumes on [`resume`](Self::resume).
    pub fn pause(&self) {
        self.0.paused.store(true, Ordering::SeqCst);
    }
    /// Resumes after a pause.
    pub fn resume(&self) {
        self.0.paused.store(false, Ordering::SeqCst);
    }
    /// Stops the run (the arm stops; pending skills stay pending).
    pub fn abort(&self) {
        self.0.abort.cancel();
    }
    /// Queues a manual command, run between skills or while paused.
    pub fn manual(&self, command: ControllerCommand) {
        lock(&self.0.manual).push_back(command);
    }
    /// Replaces a pending skill's step (applied before the next dispatch; refused
    /// with [`ManagerEvent::EditRefused`] unless the skill is still pending).
    pub fn edit(&self, skill: usize, step: PlanStep) {
        lock(&self.0.edits).push_back((skill, step));
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// How a run ended with an error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ManagerError {
    /// The user aborted.
    #[error("aborted by the user")]
    Aborted,
    /// A skill failed: the controller refused it, timed out or went away.
    #[error("skill #{skill} failed: {source}")]
    Skill {
        /// The skill's id.
        skill: usize,
        /// What the controller (or the connection to it) said.
        source: ManipulatorError,
    },
    /// The controller could not be reached.
    #[error("{0}")]
    Connection(ManipulatorError),
    /// An event could not be written to the skill log, so the run was stopped at the
    /// next skill boundary ([`SkillLog`]).
    #[error("the skill log could not be written, so the run was stopped: {0}")]
    Log(crate::db::DbError),
}

/// Runs a [`Plan`] on a controller.
pub struct SkillManager {
    plan: Plan,
    status: Vec<SkillStatus>,
    options: ManagerOptions,
    control: Arc<Control>,
}

enum Outcome {
    Done,
    Paused,
    Aborted,
}

impl SkillManager {
    /// A manager for `plan`; every skill pending.
    pub fn new(plan: Plan, options: ManagerOptions) -> Self {
        let n = plan.steps.len();
        Self {
            plan,
            status: vec![SkillStatus::Pending; n],
            options,
            control: Arc::new(Control::default()),
        }
    }

    /// A manager for `plan` steered through an existing `handle` (e.g. one a script
    /// holds before the run starts).
    pub fn with_handle(plan: Plan, options: ManagerOptions, handle: &ManagerHandle) -> Self {
        let mut m = Self::new(plan, options);
        m.control = handle.0.clone();
        m
    }

    /// A handle for pause / resume / abort / edit / manual.
    pub fn handle(&self) -> ManagerHandle {
        ManagerHandle(self.control.clone())
    }

    /// Each skill's status, in plan order.
    pub fn status(&self) -> &[SkillStatus] {
        &self.status
    }

    /// The plan (with edits applied).
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    fn addresses(&self) -> Result<(SocketAddr, SocketAddr), ManipulatorError> {
        let motion = resolve(&self.options.target, self.options.client.allow_remote)?;
        let mut state = motion;
        let port = match self.options.state_port {
            Some(p) => p,
            None => crate::manipulator::state_port_for(motion.port()).ok_or_else(|| {
                ManipulatorError::Address {
                    addr: self.options.target.clone(),
                    cause: AddressError::NoStatePort {
                        port: motion.port(),
                    },
                }
            })?,
        };
        state.set_port(port);
        Ok((motion, state))
    }

    fn connect(&self, until: Deadline) -> Result<Client, ManipulatorError> {
        let (motion, state) = self.addresses()?;
        let mut delay = RECONNECT_FIRST_DELAY;
        loop {
            match Client::connect(motion, state, self.plan.kinds(), &self.options.client) {
                Ok(c) => return Ok(c),
                Err(e @ (ManipulatorError::NotLocal(_) | ManipulatorError::NotOnWire { .. })) => {
                    return Err(e)
                }
                Err(e) => {
                    if until.passed() || self.control.abort.is_cancelled() {
                        return Err(e);
                    }
                    std::thread::sleep(delay.min(until.remaining()));
                    delay = (delay * 2).min(RECONNECT_MAX_DELAY);
                }
            }
        }
    }

    /// Runs every pending skill in order, reporting [`ManagerEvent`]s.
    ///
    /// # Errors
    /// [`ManagerError`]: aborted, a skill that failed (refused, controller error,
    /// timeout), a controller that could not be reached.
    pub fn run(&mut self, on_event: &mut dyn FnMut(&ManagerEvent)) -> Result<(), ManagerError> {
        let mut client = self
            .connect(Deadline::after(self.options.client.connect_timeout))
            .map_err(ManagerError::Connection)?;
        on_event(&ManagerEvent::Connected(
            self.addresses().map_err(ManagerError::Connection)?.0,
        ));
        let mut i = 0;
        // Commands of the running skill already done (not repeated on resume).
        let mut done_commands = 0;
        // Where the last disconnection happened (skill, command) and how many times
        // in a row it happened there.
        let mut drops: ((usize, usize), usize) = ((usize::MAX, 0), 0);
        while i < self.status.len() {
            self.apply_edits(on_event);
            if let Err(e) = self.manual_commands(&mut client, on_event) {
                return self.fail(i, e, on_event);
            }
            if self.control.abort.is_cancelled() {
                on_event(&ManagerEvent::Aborted);
                return Err(ManagerError::Aborted);
            }
            if self.control.paused.load(Ordering::SeqCst) {
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
            if self.status[i] == SkillStatus::Finished {
                i += 1;
                continue;
            }
            if self.status[i] == SkillStatus::Pending {
                on_event(&ManagerEvent::Started(
                    i,
                    self.plan.steps[i].description.clone(),
                ));
                done_commands = 0;
            }
            self.status[i] = SkillStatus::Running;
            match self.execute(&mut client, i, &mut done_commands) {
                Ok(Outcome::Done) => {
                    self.status[i] = SkillStatus::Finished;
                    let s = &self.plan.steps[i];
                    on_event(&ManagerEvent::Finished {
                        skill: i,
                        part: s.part.clone(),
                        state: s.end_state,
                    });
                    i += 1;
                }
                Ok(Outcome::Paused) => {
                    on_event(&ManagerEvent::Paused);
                    while self.control.paused.load(Ordering::SeqCst)
                        && !self.control.abort.is_cancelled()
                    {
                        if let Err(e) = self.manual_commands(&mut client, on_event) {
                            return self.fail(i, e, on_event);
                        }
                        std::thread::sleep(Duration::from_millis(20));
                    }
                    if !self.control.abort.is_cancelled() {
                        on_event(&ManagerEvent::Resumed);
                    }
                }
                Ok(Outcome::Aborted) => {
                    on_event(&ManagerEvent::Aborted);
                    return Err(ManagerError::Aborted);
                }
                Err(ManipulatorError::Disconnected { port, cause }) => {
                    let at = (i, done_commands);
                    drops = if drops.0 == at {
                        (at, drops.1 + 1)
                    } else {
                        (at, 1)
                    };
                    if drops.1 >= MAX_DROPS_AT_ONE_COMMAND {
                        let e = ManipulatorError::DroppedAt {
                            port,
                            cause,
                            drops: drops.1,
                            command: done_commands + 1,
                        };
                        return self.fail(i, e, on_event);
                    }
                    self.status[i] = SkillStatus::Interrupted;
                    on_event(&ManagerEvent::Interrupted(
                        i,
                        format!("{port} port: {cause}"),
                    ));
                    drop(client);
                    client = self
                        .connect(Deadline::after(self.options.reconnect_timeout))
                        .map_err(|e| {
                            self.status[i] = SkillStatus::Failed(e.to_string());
                            on_event(&ManagerEvent::Failed(i, e.to_string()));
                            ManagerError::Connection(e)
                        })?;
                    on_event(&ManagerEvent::Reconnected);
                }
                Err(e) => return self.fail(i, e, on_event),
            }
        }
        on_event(&ManagerEvent::Done);
        Ok(())
    }

    /// The one run loop of every caller (the CLI and scripts): runs every pending skill
    /// as [`run`](Self::run) does, writes each event to `log` (when there is one) and
    /// then hands it to `sink`. A sink that says stop, or a log write that fails, stops
    /// the run through the run's cancel token; a failed log write then wins over the
    /// run's result ([`ManagerError::Log`]).
    ///
    /// # Errors
    /// As [`run`](Self::run), and [`ManagerError::Log`].
    pub fn run_logged(
        &mut self,
        mut log: Option<SkillLog>,
        sink: &mut dyn RunSink,
    ) -> Result<(), ManagerError> {
        let cancel = self.control.abort.clone();
        let result = self.run(&mut |e| {
            if let Some(err) = log.as_mut().and_then(|l| l.record(e)) {
                cancel.cancel();
                sink.log_failed(err);
            }
            if !sink.event(e) {
                cancel.cancel();
            }
        });
        match log {
            Some(l) => l.finish(result),
            None => result,
        }
    }

    fn fail(
        &mut self,
        i: usize,
        e: ManipulatorError,
        on_event: &mut dyn FnMut(&ManagerEvent),
    ) -> Result<(), ManagerError> {
        let reason = e.to_string();
        if i < self.status.len() {
            self.status[i] = SkillStatus::Failed(reason.clone());
        }
        on_event(&ManagerEvent::Failed(i, reason.clone()));
        Err(ManagerError::Skill {
            skill: i,
            source: e,
        })
    }

    fn apply_edits(&mut self, on_event: &mut dyn FnMut(&ManagerEvent)) {
        let edits: Vec<_> = lock(&self.control.edits).drain(..).collect();
        for (id, step) in edits {
            match self.status.get(id) {
                Some(SkillStatus::Pending) => {
                    self.plan.steps[id] = step;
                    on_event(&ManagerEvent::Edited(id));
                }
                Some(s) => on_event(&ManagerEvent::EditRefused(id, format!("{s:?}"))),
                None => on_event(&ManagerEvent::EditRefused(id, "no such skill".into())),
            }
        }
    }

    fn manual_commands(
        &mut self,
        client: &mut Client,
        on_event: &mut dyn FnMut(&ManagerEvent),
    ) -> Result<(), ManipulatorError> {
        loop {
            let Some(c) = lock(&self.control.manual).pop_front() else {
                return Ok(());
            };
            let text = c.describe();
            self.run_command(client, &c)?;
            on_event(&ManagerEvent::Manual(text));
        }
    }

    fn cancelled(&self) -> bool {
        self.control.paused.load(Ordering::SeqCst) || self.control.abort.is_cancelled()
    }

    /// Runs skill `i` from command `done`; returns when done, paused or aborted.
    fn execute(
        &self,
        client: &mut Client,
        i: usize,
        done: &mut usize,
    ) -> Result<Outcome, ManipulatorError> {
        let commands = self.plan.steps[i].commands.clone();
        while *done < commands.len() {
            match self.run_command(client, &commands[*done])? {
                Outcome::Done => *done += 1,
                other => return Ok(other),
            }
        }
        Ok(Outcome::Done)
    }

    fn run_command(
        &self,
        client: &mut Client,
        c: &ControllerCommand,
    ) -> Result<Outcome, ManipulatorError> {
        match c {
            ControllerCommand::Tool {
                action,
                index,
                value,
            } => {
                let a = ControllerCommand::tool_action(action).ok_or_else(|| {
                    ManipulatorError::NotOnWire {
                        request: Request::Tool {
                            action: action.clone(),
                        },
                        cause: WireError::UnknownTool,
                    }
                })?;
                clear_error(client)?;
                client.tool(a, *index, *value as f32)?;
                Ok(Outcome::Done)
            }
            ControllerCommand::Trajectory(points) => {
                let Some(last) = points.last() else {
                    return Ok(Outcome::Done);
                };
                let here = clear_error(client)?;
                // Resume from where the arm is: skip the points already passed.
                let dist = |q: &[f64]| {
                    q.iter()
                        .zip(&here)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                };
                let nearest = (0..points.len())
                    .min_by(|&a, &b| dist(&points[a].0).total_cmp(&dist(&points[b].0)))
                    .unwrap_or(0);
                if nearest + 1 < points.len() || dist(&last.0) > self.options.tolerance {
                    let mut stream = vec![(here.clone(), 0.0)];
                    stream.extend(
                        points[(nearest + 1).min(points.len() - 1)..]
                            .iter()
                            .cloned(),
                    );
                    client.stream(&stream)?;
                }
                let client_ref: &Client = client;
                let cancel = || {
                    if let Ok(st) = client_ref.state() {
                        *lock(&self.control.joints) = st.joints;
                    }
                    self.cancelled()
                };
                let arrived = client_ref.wait_until_at(
                    &last.0,
                    self.options.tolerance,
                    self.options.skill_timeout,
                    &cancel,
                )?;
                if arrived {
                    return Ok(Outcome::Done);
                }
                client.stop_motion()?;
                if self.control.abort.is_cancelled() {
                    Ok(Outcome::Aborted)
                } else {
                    Ok(Outcome::Paused)
                }
            }
        }
    }
}

impl ManagerEvent {
    /// The event as one line for people: `running #3 Move_Table gear 200 mm`,
    /// `finished #3: gear Grasped`, `paused`, `done`…
    pub fn describe(&self) -> String {
        match self {
            ManagerEvent::Connected(a) => format!("connected {a}"),
            ManagerEvent::Started(_, d) => format!("running {d}"),
            ManagerEvent::Finished { skill, part, state } => {
                format!("finished #{skill}: {part} {state}")
            }
            ManagerEvent::Interrupted(i, why) => format!("interrupted #{i}: {why}"),
            ManagerEvent::Reconnected => "reconnected".into(),
            ManagerEvent::Paused => "paused".into(),
            ManagerEvent::Resumed => "resumed".into(),
            ManagerEvent::Edited(i) => format!("edited #{i}"),
            ManagerEvent::EditRefused(i, why) => format!("edit of #{i} refused: {why}"),
            ManagerEvent::Manual(c) => format!("manual {c}"),
            ManagerEvent::Failed(i, why) => format!("failed #{i}: {why}"),
            ManagerEvent::Aborted => "aborted".into(),
            ManagerEvent::Done => "done".into(),
        }
    }

    /// The event as a log row: `(skill, event, detail)`.
    pub fn log_fields(&self) -> (Option<usize>, SkillEvent, String) {
        use SkillEvent as E;
        match self {
            ManagerEvent::Connected(a) => (None, E::Connected, a.to_string()),
            ManagerEvent::Started(i, d) => (Some(*i), E::Started, d.clone()),
            ManagerEvent::Finished { skill, part, state } => {
                (Some(*skill), E::Finished, format!("{part} {state}"))
            }
            ManagerEvent::Interrupted(i, why) => (Some(*i), E::Interrupted, why.clone()),
            ManagerEvent::Reconnected => (None, E::Reconnected, String::new()),
            ManagerEvent::Paused => (None, E::Paused, String::new()),
            ManagerEvent::Resumed => (None, E::Resumed, String::new()),
            ManagerEvent::Edited(i) => (Some(*i), E::Edited, String::new()),
            ManagerEvent::EditRefused(i, why) => (Some(*i), E::EditRefused, why.clone()),
            ManagerEvent::Manual(c) => (None, E::Manual, c.clone()),
            ManagerEvent::Failed(i, why) => (Some(*i), E::Failed, why.clone()),
            ManagerEvent::Aborted => (None, E::Aborted, String::new()),
            ManagerEvent::Done => (None, E::Done, String::new()),
        }
    }
}

/// Writes one manager event to the skill execution log of `db` (plan label `plan`);
/// the part is taken from the plan's step.
///
/// # Errors
/// The database's error.
pub fn log_event(
    db: &mut crate::db::Database,
    run_id: Option<i64>,
    plan_label: &str,
    plan: &Plan,
    event: &ManagerEvent,
) -> Result<i64, crate::db::DbError> {
    let (skill, name, detail) = event.log_fields();
    let part = skill
        .and_then(|i| plan.steps.get(i))
        .map(|s| s.part.as_str());
    db.log_skill_event(run_id, plan_label, skill, part, name, &detail)
}

/// The database a [`SkillLog`] writes to: its own, or one shared with a script.
pub enum LogDb {
    /// A database of the log's own (the CLI's `--db`).
    Owned(Box<crate::db::Database>),
    /// A database other code uses too (a script's `open_db()`).
    Shared(Arc<Mutex<crate::db::Database>>),
}

/// The skill log of one run: every event written to the results database as it
/// happens ([`log_event`]), with one failure policy for every caller (CLI and scripts).
///
/// The log is the record of what a machine did, so a run whose record would be
/// incomplete does not go on: the first write that fails stops the run through its
/// cancel token ([`SkillManager::run_logged`]), later events are not written, and
/// [`SkillLog::finish`] turns the run's result into [`ManagerError::Log`].
pub struct SkillLog {
    run_id: Option<i64>,
    label: String,
    plan: Plan,
    db: LogDb,
    failed: Option<crate::db::DbError>,
}

impl SkillLog {
    /// The log of a run of `plan` (stored under `label`, e.g. the plan file, and the
    /// script's run when there is one) in `db`.
    pub fn new(run_id: Option<i64>, label: impl Into<String>, plan: &Plan, db: LogDb) -> Self {
        Self {
            run_id,
            label: label.into(),
            plan: plan.clone(),
            db,
            failed: None,
        }
    }

    /// Writes one event. On the first failure the error is kept and returned (for the
    /// caller to stop the run and show it at once); `None` otherwise, and for every
    /// event after a failure (not written).
    pub fn record(&mut self, event: &ManagerEvent) -> Option<&crate::db::DbError> {
        if self.failed.is_some() {
            return None;
        }
        let written = match &mut self.db {
            LogDb::Owned(db) => log_event(db, self.run_id, &self.label, &self.plan, event),
            LogDb::Shared(db) => {
                log_event(&mut lock(db), self.run_id, &self.label, &self.plan, event)
            }
        };
        match written {
            Ok(_) => None,
            Err(e) => {
                self.failed = Some(e);
                self.failed.as_ref()
            }
        }
    }

    /// Whether a write has failed.
    pub fn failed(&self) -> bool {
        self.failed.is_some()
    }

    /// The run's result with the log's: a failed write wins over success and over the
    /// abort it caused.
    pub fn finish(self, result: Result<(), ManagerError>) -> Result<(), ManagerError> {
        match self.failed {
            Some(e) => Err(ManagerError::Log(e)),
            None => result,
        }
    }
}

/// Clears an error an earlier refusal left on the controller, the one way every
/// simulated and REP-I0006 controller knows: a new trajectory, whose first point
/// (sequence 0, where the arm is) clears it. Returns where the arm is. Without it a
/// skill whose arm was already at its target, or a tool command the controller
/// refuses while in error (a touch), failed on the old error until a restart.
fn clear_error(client: &mut Client) -> Result<Vec<f64>, ManipulatorError> {
    let state = client.state()?;
    let in_error = state
        .status
        .is_some_and(|s| s.in_error == crate::manipulator::message::TriState::On);
    if in_error {
        client.stream(&[(state.joints.clone(), 0.0)])?;
    }
    Ok(state.joints)
}

#[cfg(test)]
mod log_tests {
    use super::*;
    use crate::db::{Database, Target};

    #[test]
    fn a_failed_log_write_is_reported_once_and_fails_the_run() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fitup.db");
        let db = Database::open(&Target::Sqlite(path.clone())).unwrap();
        let plan = Plan {
            version: 1,
            robot: "arm".into(),
            joint_kinds: vec![],
            steps: vec![],
        };
        let mut log = SkillLog::new(None, "plan.json", &plan, LogDb::Owned(Box::new(db)));
        let event = ManagerEvent::Started(0, "Move".into());
        assert!(log.record(&event).is_none());
        assert!(!log.failed());
        // Another program breaks the table under the run: the next write fails.
        rusqlite::Connection::open(&path)
            .unwrap()
            .execute_batch("DROP TABLE skill_log")
            .unwrap();
        assert!(
            log.record(&event).is_some(),
            "the first failure is reported"
        );
        assert!(log.record(&event).is_none(), "and only once");
        assert!(log.failed());
        match log.finish(Err(ManagerError::Aborted)) {
            Err(ManagerError::Log(e)) => assert!(e.to_string().contains("skill_log"), "{e}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_linked_cancel_token_follows_its_outer_flag_and_reset_keeps_it() {
        let outer = Arc::new(AtomicBool::new(false));
        let handle = ManagerHandle::with_cancel(CancelToken::linked(outer.clone()));
        assert!(!handle.aborted());
        outer.store(true, Ordering::SeqCst);
        assert!(handle.aborted());
        handle.reset();
        assert!(handle.aborted(), "reset clears only the token's own cancel");
        outer.store(false, Ordering::SeqCst);
        assert!(!handle.aborted());
        handle.abort();
        assert!(handle.cancel_token().is_cancelled());
        handle.reset();
        assert!(!handle.aborted());
    }
}
