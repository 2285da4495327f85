//! Bindings for skills and the skill manager (seed 003, sections 3–4):
//! `doc.skills(sequence, #{robot, …})` plans the whole chain (`skills::plan_chain`),
//! `skill_manager(#{target})` dispatches it (`skills::SkillManager`). Values are only
//! converted here.
//!
//! Safety: a script commands a manipulator over TCP only when the command line said
//! so (`fitup run SCRIPT --dispatch`, plus `--allow-remote` for an address that is
//! not this machine); the in-process simulator (`target: "sim"`) needs neither. A
//! cancelled run (a new save in watch mode) aborts a running manager within 20 ms.

use super::api::Api;
use super::bind_db::DbHandle;
use super::bind_document::DocHandle;
use super::bind_math::{to_transform, xyzabc_deg};
use super::bind_robot::RobotHandle;
use super::bind_sequence::SequenceHandle;
use super::convert::overwrite_option;
use super::convert::{check_keys, err, fail, opt_num, opt_str, vec3};
use super::{Context, Dispatch, ScriptResult};
use crate::manipulator::client::resolve;
use crate::manipulator::simulator::{Simulator, SimulatorOptions};
use crate::math::AngleConvention;
use crate::skills::{
    plan_chain, CancelToken, Chain, ChainOptions, Condition, ControllerCommand, LogDb,
    ManagerError, ManagerEvent, ManagerHandle, ManagerOptions, PlanStep, RunSink, SkillLog,
    SkillManager, Template,
};
use rhai::{Array, Dynamic, FnPtr, Map, NativeCallContext};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Skills and their plan (`doc.skills`), cheap to clone.
#[derive(Clone)]
pub struct SkillsHandle(Arc<Chain>, Arc<Context>);

/// A skill manager of a script (`skill_manager`), cheap to clone.
#[derive(Clone)]
pub struct ManagerObj(Arc<ManagerInner>);

struct ManagerInner {
    options: ManagerOptions,
    handle: ManagerHandle,
    /// The in-process simulator of `target: "sim"` (stops when the manager goes).
    _sim: Mutex<Option<Simulator>>,
    db: Option<DbHandle>,
    quiet: bool,
    ctx: Arc<Context>,
    /// Each part's state after the skills run so far.
    parts: Mutex<BTreeMap<String, String>>,
}

const SKILL_KEYS: [&str; 13] = [
    "robot",
    "supply",
    "tool",
    "templates",
    "place",
    "supply_offset",
    "long_range_mm",
    "clearance_mm",
    "touch_distance_mm",
    "screw_turns",
    "screw_pitch_mm",
    "contact_force_n",
    "check",
];

const MANAGER_KEYS: [&str; 9] = [
    "target",
    "robot",
    "speed",
    "state_port",
    "byte_order",
    "skill_timeout_s",
    "reconnect_timeout_s",
    "db",
    "quiet",
];

fn skills(d: &DocHandle, seq: &SequenceHandle, m: &Map) -> ScriptResult<SkillsHandle> {
    check_keys(m, &SKILL_KEYS, "skills")?;
    let ctx = d.context().clone();
    let Some(robot) = m
        .get("robot")
        .and_then(|r| r.clone().try_cast::<RobotHandle>())
    else {
        return err("skills: `robot` (a Robot, e.g. open_doc(\"models/mz07.yaml\").robot(\"mz07\")) is required");
    };
    // The robot may live in the same document: take its copy before locking `d`.
    let (model, start) = robot.snapshot()?;
    let mut options = ChainOptions::default();
    if let Some(p) = m.get("place") {
        options.place = to_transform(p, "place")?;
    }
    if let Some(t) = m.get("tool") {
        options.tool_in_grasp = to_transform(t, "tool")?;
    }
    if let Some(v) = m.get("supply") {
        let Some(map) = v.clone().try_cast::<Map>() else {
            return err("skills: `supply` must be a map part: pose");
        };
        for (part, pose) in map {
            let t = to_transform(&pose, "supply")?;
            options.supply.insert(part.to_string(), t);
        }
    }
    if let Some(v) = m.get("supply_offset") {
        options.supply_offset = vec3(v, "supply_offset")?;
    }
    let g = &mut options.generator;
    for (key, field) in [
        ("long_range_mm", &mut g.long_range_mm),
        ("clearance_mm", &mut g.clearance_mm),
        ("touch_distance_mm", &mut g.touch_distance_mm),
        ("screw_turns", &mut g.screw_turns),
        ("screw_pitch_mm", &mut g.screw_pitch_mm),
        ("contact_force_n", &mut g.contact_force_n),
    ] {
        if let Some(v) = opt_num(m, key)? {
            if !(v.is_finite() && v >= 0.0) {
                return err(format!("skills: `{key}` must be a number ≥ 0, not {v}"));
            }
            *field = v;
        }
    }
    if let Some(v) = m.get("check") {
        options.check = v
            .as_bool()
            .map_err(|t| fail(format!("skills: `check` must be a bool, not {t}")))?;
    }
    let mut templates = Vec::new();
    if let Some(v) = m.get("templates") {
        let Some(files) = v.clone().try_cast::<Array>() else {
            return err("skills: `templates` must be an array of template files");
        };
        for f in files {
            let Ok(name) = f.into_string() else {
                return err("skills: `templates` must hold file names");
            };
            let full = ctx.project.resolve(&name).map_err(fail)?;
            ctx.record_read(&full);
            templates.push(Template::read_in(&ctx.project, &full).map_err(|e| fail(e.render()))?);
        }
    }
    let tasks = &seq.0.best().tasks;
    let doc = d.lock()?;
    let chain = plan_chain(&doc, tasks, &templates, &model, &start, &options).map_err(fail)?;
    Ok(SkillsHandle(Arc::new(chain), ctx))
}

fn skill_map(s: &crate::skills::Skill) -> Dynamic {
    let conv = AngleConvention::default();
    let mut m = Map::new();
    m.insert("id".into(), (s.id as i64).into());
    m.insert("task".into(), (s.task as i64).into());
    m.insert("part".into(), s.part.clone().into());
    m.insert("workflow".into(), s.workflow.clone().into());
    m.insert("action".into(), s.action.name().into());
    let mut a = Map::new();
    for at in &s.attributes {
        a.insert(at.name.as_str().into(), Dynamic::from_float(at.value));
    }
    m.insert("attributes".into(), a.into());
    m.insert("start".into(), xyzabc_deg(&s.start.0, conv));
    m.insert("end".into(), xyzabc_deg(&s.end.0, conv));
    m.insert("start_state".into(), s.start.1.name().into());
    m.insert("end_state".into(), s.end.1.name().into());
    m.insert(
        "condition".into(),
        match s.condition {
            Condition::Always => "always".to_string(),
            Condition::PartIn(st) => format!("part in {}", st.name()),
            Condition::Contact { force_n } => format!("contact {force_n} N"),
        }
        .into(),
    );
    m.insert("text".into(), s.describe().into());
    Dynamic::from_map(m)
}

fn secs(m: &Map, key: &str, default: Duration) -> ScriptResult<Duration> {
    match opt_num(m, key)? {
        None => Ok(default),
        Some(v) => Duration::try_from_secs_f64(v).map_err(|_| {
            fail(format!(
                "skill_manager: `{key}` must be seconds ≥ 0, not {v}"
            ))
        }),
    }
}

fn manager(ctx: &Arc<Context>, m: &Map) -> ScriptResult<ManagerObj> {
    check_keys(m, &MANAGER_KEYS, "skill_manager")?;
    let target = opt_str(m, "target")?.unwrap_or_else(|| "sim".into());
    let defaults = ManagerOptions::default();
    let mut options = ManagerOptions {
        skill_timeout: secs(m, "skill_timeout_s", defaults.skill_timeout)?,
        reconnect_timeout: secs(m, "reconnect_timeout_s", defaults.reconnect_timeout)?,
        ..defaults
    };
    let mut sim = None;
    if target == "sim" {
        let Some(robot) = m
            .get("robot")
            .and_then(|r| r.clone().try_cast::<RobotHandle>())
        else {
            return err("skill_manager: target \"sim\" needs `robot` (the Robot to simulate)");
        };
        let speed = opt_num(m, "speed")?.unwrap_or(SimulatorOptions::default().speed);
        if !(speed.is_finite() && speed > 0.0 && speed <= 1000.0) {
            return err(format!(
                "skill_manager: `speed` must be in (0, 1000], not {speed}"
            ));
        }
        let (doc, name) = {
            let doc = robot.doc.lock()?;
            let name = doc.robot_at(robot.index).map_err(fail)?.name().to_string();
            (doc.clone(), name)
        };
        let s = Simulator::start(
            &doc,
            &name,
            &SimulatorOptions {
                motion_port: 0,
                state_port: 0,
                speed,
                ..SimulatorOptions::default()
            },
        )
        .map_err(|e| fail(format!("skill_manager: simulator: {e}")))?;
        options.target = s.motion_addr().to_string();
        options.state_port = Some(s.state_addr().port());
        sim = Some(s);
    } else {
        if m.contains_key("robot") || m.contains_key("speed") {
            return err("skill_manager: `robot` and `speed` are for target \"sim\"; start `fitup manipulator` for a TCP target");
        }
        match ctx.dispatch {
            Dispatch::Never => {
                return err(format!(
                    "skill_manager: dispatching to a manipulator at {target} needs `--dispatch` on the command line (`fitup run SCRIPT --dispatch`); target \"sim\" runs the in-process simulator"
                ))
            }
            Dispatch::Loopback => {}
            Dispatch::Remote => options.client.allow_remote = true,
        }
        resolve(&target, options.client.allow_remote)
            .map_err(|e| fail(format!("skill_manager: {e}")))?;
        options.target = target;
        if let Some(p) = opt_num(m, "state_port")? {
            if !(p.fract() == 0.0 && (1.0..=65535.0).contains(&p)) {
                return err(format!(
                    "skill_manager: `state_port` must be a port number, not {p}"
                ));
            }
            options.state_port = Some(p as u16);
        }
        if let Some(v) = m.get("byte_order") {
            let text = v.clone().into_string().ok();
            options.client.byte_order = text
                .as_deref()
                .and_then(crate::manipulator::message::ByteOrder::parse)
                .ok_or_else(|| {
                    fail(format!(
                        "skill_manager: `byte_order` must be \"big\" or \"little\", not {}",
                        text.unwrap_or_else(|| v.type_name().to_string())
                    ))
                })?;
        }
    }
    let db = match m.get("db") {
        None => None,
        Some(v) => Some(
            v.clone()
                .try_cast::<DbHandle>()
                .ok_or_else(|| fail("skill_manager: `db` must be a Database (open_db())"))?,
        ),
    };
    let quiet = match m.get("quiet") {
        None => false,
        Some(v) => v
            .as_bool()
            .map_err(|t| fail(format!("skill_manager: `quiet` must be a bool, not {t}")))?,
    };
    Ok(ManagerObj(Arc::new(ManagerInner {
        options,
        handle: ManagerHandle::with_cancel(CancelToken::linked(ctx.cancel_flag())),
        _sim: Mutex::new(sim),
        db,
        quiet,
        ctx: ctx.clone(),
        parts: Mutex::default(),
    })))
}

fn event_map(e: &ManagerEvent, plan: &crate::skills::Plan) -> Dynamic {
    let (skill, name, detail) = e.log_fields();
    let mut m = Map::new();
    m.insert("event".into(), name.name().into());
    m.insert(
        "skill".into(),
        skill.map_or(Dynamic::UNIT, |i| (i as i64).into()),
    );
    m.insert(
        "part".into(),
        skill
            .and_then(|i| plan.steps.get(i))
            .map_or(Dynamic::UNIT, |s| s.part.clone().into()),
    );
    if let ManagerEvent::Finished { state, .. } = e {
        m.insert("state".into(), state.name().into());
    }
    m.insert("detail".into(), detail.into());
    m.insert("text".into(), e.describe().into());
    Dynamic::from_map(m)
}

/// A script's sink of a run: events printed (unless `quiet`), collected, the parts'
/// states kept, and the script's callback called (its first error stops the run).
struct ScriptSink<'a> {
    inner: &'a ManagerInner,
    manager: &'a ManagerObj,
    plan: &'a crate::skills::Plan,
    call: Option<(&'a NativeCallContext<'a>, &'a FnPtr)>,
    events: Array,
    callback_error: Option<Box<rhai::EvalAltResult>>,
}

impl RunSink for ScriptSink<'_> {
    fn event(&mut self, e: &ManagerEvent) -> bool {
        if let ManagerEvent::Finished { part, state, .. } = e {
            if let Ok(mut p) = self.inner.parts.lock() {
                p.insert(part.clone(), state.name().to_string());
            }
        }
        if !self.inner.quiet {
            self.inner.ctx.print(&e.describe());
        }
        let map = event_map(e, self.plan);
        self.events.push(map.clone());
        if let Some((ncc, f)) = self.call {
            if self.callback_error.is_none() {
                if let Err(x) = f.call_within_context::<Dynamic>(ncc, (map, self.manager.clone())) {
                    self.callback_error = Some(x);
                    return false;
                }
            }
        }
        true
    }
}

fn run(
    call: Option<(&NativeCallContext, &FnPtr)>,
    m: &ManagerObj,
    plan: &SkillsHandle,
) -> ScriptResult<Array> {
    let inner = &m.0;
    // A cancelled script (new save, Ctrl-C in watch) stops the arm promptly: the run's
    // cancel token is linked to the script's (ManagerHandle::with_cancel).
    inner.handle.reset();
    let steps = plan.0.plan.clone();
    let mut manager =
        SkillManager::with_handle(steps.clone(), inner.options.clone(), &inner.handle);
    let log = inner.db.as_ref().map(|d| {
        SkillLog::new(
            d.run_id,
            format!("script:{}", steps.robot),
            &steps,
            LogDb::Shared(d.db.clone()),
        )
    });
    let mut sink = ScriptSink {
        inner,
        manager: m,
        plan: &steps,
        call,
        events: Array::new(),
        callback_error: None,
    };
    let result = manager.run_logged(log, &mut sink);
    if let Some(e) = sink.callback_error {
        return Err(e);
    }
    if inner.ctx.cancelled() {
        return err("cancelled");
    }
    match result {
        Ok(()) | Err(ManagerError::Aborted) => Ok(sink.events),
        Err(e) => err(e.to_string()),
    }
}

fn plan_step(m: &ManagerObj, plan: &SkillsHandle, id: i64, changes: &Map) -> ScriptResult<()> {
    check_keys(changes, &["commands", "description"], "edit")?;
    let Some(step) = usize::try_from(id)
        .ok()
        .and_then(|i| plan.0.plan.steps.get(i))
    else {
        return err(format!("edit: no skill #{id}"));
    };
    let mut step: PlanStep = step.clone();
    if let Some(d) = opt_str(changes, "description")? {
        step.description = d;
    }
    if let Some(c) = changes.get("commands") {
        let Some(list) = c.clone().try_cast::<Array>() else {
            return err("edit: `commands` must be an array of manual commands (\"grasp 12\", …)");
        };
        step.commands = list
            .into_iter()
            .map(|c| {
                let text = c
                    .into_string()
                    .map_err(|t| fail(format!("edit: a command must be a string, not {t}")))?;
                ControllerCommand::parse_manual(&text)
                    .ok_or_else(|| fail(format!("edit: bad command `{text}` ({MANUAL_HELP})")))
            })
            .collect::<ScriptResult<_>>()?;
    }
    m.0.handle.edit(step.skill, step);
    Ok(())
}

const MANUAL_HELP: &str = "grasp MM, release MM, touch MM, output I 0|1";

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Skills and the skill manager", "Seed 003's skills (see `docs/skills.md`): each task of an assembly sequence goes through the workflows of its template (FREE → In_WS → Grasped → Adjusted → Assembled), whose generators emit skill primitives; the skills are bound to a robot and dispatched by a skill manager to a controller speaking ROS-Industrial simple_message. Poses `[X, Y, Z, A, B, C]` in mm and degrees; attributes in mm, radians, N as their names say. A script dispatches over TCP only with `fitup run SCRIPT --dispatch` (`--allow-remote` as well for an address that is not this machine); `target: \"sim\"` runs an in-process simulator and needs neither.");
    api.type_::<SkillsHandle>("Skills");
    api.type_::<ManagerObj>("SkillManager");
    api.f(
        "Document.skills(sequence: Sequence, options: map) -> Skills",
        "The whole chain for the sequence's tasks (this document is the assembly): skills from the templates, checked for interference against the assembly as it is at each task (earlier parts assembled, later ones waiting), bound to a robot. Options: `robot` (a Robot, required; its current joints are the start), `templates: [files]` (override the defaults per operation, validated), `tool` (the robot's tool frame in the grasp frame, whose z is the approach and x the closing direction; identity — `[0, 0, 0, 180, 0, 0]` for a tool whose z points back at the flange), `place` (where the assembly sits in the robot's cell, Transform or `[x,y,z,a,b,c]`; identity), `supply_offset: [x,y,z]` (the parts wait in a row before their tasks: the k-th task's part, from 0, at its assembled pose moved by (k + 1) × this; assembly frame, mm; `[0, 60, 0]`), `supply: #{part: pose}` (where given parts wait instead, assembly frame), `long_range_mm` (50), `clearance_mm` (20), `touch_distance_mm` (10), `screw_turns` (1: the turns of thread engagement), `screw_pitch_mm` (0.5, > 0), `contact_force_n` (2), `check` (true). A `robot` with the precision manipulator's layout (catalog `precision_2finger`, `models/micro_cell.yaml`) is bound by its own rules: each action moves only its axes, and `place` puts the assembly in the rotary table's frame.",
        |d: &mut DocHandle, seq: SequenceHandle, m: Map| skills(d, &seq, &m),
    );
    api.get(
        "Skills.skills -> array",
        "The skill primitives in execution order: `#{id, task, part, workflow, action, attributes: #{name: value}, start, end, start_state, end_state, condition, text}` (poses in the assembly frame).",
        |s: &mut SkillsHandle| -> Array { s.0.skills.iter().map(skill_map).collect() },
    );
    api.get(
        "Skills.len -> int",
        "How many skills.",
        |s: &mut SkillsHandle| s.0.skills.len() as i64,
    );
    api.get(
        "Skills.parts -> array",
        "The parts the skills assemble, in order.",
        |s: &mut SkillsHandle| -> Array {
            let mut parts: Vec<String> = Vec::new();
            for k in &s.0.skills {
                if !parts.contains(&k.part) {
                    parts.push(k.part.clone());
                }
            }
            parts.into_iter().map(Dynamic::from).collect()
        },
    );
    api.f(
        "Skills.to_string() -> string",
        "One line per skill: `#3 Move_Table gear 120 mm (Grasped -> Grasped)`.",
        |s: &mut SkillsHandle| -> String {
            s.0.skills
                .iter()
                .map(|k| {
                    format!(
                        "{} ({} -> {})",
                        k.describe(),
                        k.start.1.name(),
                        k.end.1.name()
                    )
                })
                .collect::<Vec<_>>()
                .join("\n")
        },
    );
    api.f(
        "Skills.save(file: string)",
        "Writes the plan file (JSON, what `fitup skills run PLAN` dispatches) inside the project, atomically. Refuses to replace a file the project uses or one fitup did not write (see \"What a run writes\" in docs/scripting.md); `#{overwrite: true}` replaces it.",
        |s: &mut SkillsHandle, file: &str| -> ScriptResult<()> {
            s.1.write_output(file, s.0.plan.to_json().as_bytes(), false)?;
            Ok(())
        },
    );
    api.f(
        "Skills.save(file: string, options: map)",
        "`save(file)` with `#{overwrite}` (bool, default false).",
        |s: &mut SkillsHandle, file: &str, opts: Map| -> ScriptResult<()> {
            let overwrite = overwrite_option(&opts, "save")?;
            s.1.write_output(file, s.0.plan.to_json().as_bytes(), overwrite)?;
            Ok(())
        },
    );
    let c = ctx.clone();
    api.f(
        "skill_manager(options: map) -> SkillManager",
        "A skill manager: `#{target: \"sim\" | \"HOST:PORT\" (motion port; the state port is +2 unless `state_port`; `byte_order` \"big\" (default) or \"little\"), robot (the Robot the in-process simulator moves, target \"sim\"), speed (simulator time scale, 1), skill_timeout_s (120), reconnect_timeout_s (30), db (a Database: the execution log is written as it happens), quiet (false: print each event)}`. A TCP target needs `fitup run --dispatch`.",
        move |m: Map| manager(&c, &m),
    );
    api.f(
        "SkillManager.run(skills: Skills) -> array",
        "Dispatches every skill in order until done, aborted or failed (a failure is an error naming the skill and the reason); returns the events `#{event, skill, part, state, detail, text}` (printed as they happen unless `quiet`).",
        |m: ManagerObj, s: SkillsHandle| run(None, &m, &s),
    );
    api.f(
        "SkillManager.run(skills: Skills, on_event: fn) -> array",
        "As `run(skills)`, calling `on_event(event, manager)` for each event as it happens: steer the run through the callback's `manager` argument (`pause()`, `resume()`, `abort()`, `edit(…)`, `manual(…)`; a `resume()` on the `paused` event continues) rather than a captured variable.",
        |ncc: NativeCallContext, m: ManagerObj, s: SkillsHandle, f: FnPtr| run(Some((&ncc, &f)), &m, &s),
    );
    api.f(
        "SkillManager.pause()",
        "Stops the arm now; the running skill continues on `resume()`.",
        |m: ManagerObj| m.0.handle.pause(),
    );
    api.f(
        "SkillManager.resume()",
        "Continues after `pause()`.",
        |m: ManagerObj| m.0.handle.resume(),
    );
    api.f(
        "SkillManager.abort()",
        "Stops the arm and the run; pending skills stay pending (`run` returns, its last event `aborted`).",
        |m: ManagerObj| m.0.handle.abort(),
    );
    api.f(
        "SkillManager.manual(command: string)",
        "Queues a manual tool command, run between skills or while paused: `grasp MM`, `release MM`, `touch MM`, `output I 0|1`.",
        |m: ManagerObj, cmd: &str| -> ScriptResult<()> {
            let c = ControllerCommand::parse_manual(cmd)
                .ok_or_else(|| fail(format!("manual: bad command `{cmd}` ({MANUAL_HELP})")))?;
            m.0.handle.manual(c);
            Ok(())
        },
    );
    api.f(
        "SkillManager.edit(skills: Skills, id: int, changes: map)",
        "Replaces pending skill `id` of `skills` before it is dispatched: `#{commands: [manual commands], description}`; refused (event `edit_refused`) once it started.",
        |m: ManagerObj, s: SkillsHandle, id: i64, changes: Map| plan_step(&m, &s, id, &changes),
    );
    api.get(
        "SkillManager.parts -> map",
        "Each part's state after the skills run so far: `#{gear: \"Assembled\", …}`.",
        |m: ManagerObj| -> Map {
            m.0.parts
                .lock()
                .map(|p| {
                    p.iter()
                        .map(|(k, v)| (k.as_str().into(), Dynamic::from(v.clone())))
                        .collect()
                })
                .unwrap_or_default()
        },
    );
}
