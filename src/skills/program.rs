//! Skills bound to a robot: each skill becomes the commands a controller runs (joint
//! trajectories and tool commands), saved as a plan file (JSON) that
//! `fitup skills run PLAN --target HOST:PORT` dispatches.
//!
//! On an arm every part motion (Move_Table, Move_Probe, Rotate_*, Insert, Screw,
//! Line) is a straight TCP line of the tool holding the part (tool pose = grasp's
//! tool-in-part, then the part's pose); Grasp first moves the arm (joint move) to
//! the grasp, then closes the gripper; Release opens it; Touch asks the controller to
//! move until contact. Joints are rad / mm; trajectory points carry the time from
//! the previous point (s).

use super::{Action, PartState, Skill};
use crate::kinematics::{move_joint, move_line, JointKind, MotionOptions, Robot};
use crate::manipulator::message::ToolAction;
use crate::math::Transform;
use crate::sequence::Task;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use thiserror::Error;

/// The most trajectory points a plan file may hold (all skills together): far above
/// any real plan (a point every 0.2 s is 55 hours), low enough that memory stays small.
pub const MAX_PLAN_POINTS: usize = 1_000_000;

/// One thing a controller does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ControllerCommand {
    /// Joint trajectory: `(joints rad/mm, seconds from the previous point)`; the first
    /// point is where the arm starts.
    Trajectory(Vec<(Vec<f64>, f64)>),
    /// A tool command of fitup's simple_message extension: `action` is `grasp`,
    /// `release`, `touch` or `set_output`; `value` in metres (opening, distance) or
    /// 0/1 for an output.
    Tool {
        /// Action name.
        action: String,
        /// Output index (set_output), else 0.
        index: i32,
        /// Value (m, or 0/1).
        value: f64,
    },
}

impl ControllerCommand {
    /// The wire action of a `Tool` command.
    pub fn tool_action(name: &str) -> Option<ToolAction> {
        Some(match name {
            "grasp" => ToolAction::Grasp,
            "release" => ToolAction::Release,
            "touch" => ToolAction::Touch,
            "set_output" => ToolAction::SetOutput,
            _ => return None,
        })
    }

    /// The command for people, as [`parse_manual`](Self::parse_manual) reads it:
    /// `grasp 12 mm`, `output 3 1`, `trajectory of 5 points`.
    pub fn describe(&self) -> String {
        match self {
            Self::Trajectory(p) => format!("trajectory of {} points", p.len()),
            Self::Tool {
                action,
                index,
                value,
                ..
            } if action == "set_output" => format!("output {index} {value}"),
            Self::Tool { action, value, .. } => format!("{action} {} mm", value * 1000.0),
        }
    }

    /// Parses a manual command line: `grasp W_MM`, `release W_MM`, `touch D_MM`,
    /// `output I 0|1`.
    pub fn parse_manual(line: &str) -> Option<Self> {
        let w: Vec<&str> = line.split_whitespace().collect();
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
        Some(match w.as_slice() {
            ["grasp", v] => Self::Tool {
                action: "grasp".into(),
                index: 0,
                value: num(v)? / 1000.0,
            },
            ["release", v] => Self::Tool {
                action: "release".into(),
                index: 0,
                value: num(v)? / 1000.0,
            },
            ["touch", v] => Self::Tool {
                action: "touch".into(),
                index: 0,
                value: num(v)? / 1000.0,
            },
            ["output", i, v] => Self::Tool {
                action: "set_output".into(),
                index: i.parse().ok()?,
                value: num(v)?,
            },
            _ => return None,
        })
    }
}

/// One skill of a plan, ready to dispatch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanStep {
    /// The skill's id.
    pub skill: usize,
    /// Task index.
    pub task: usize,
    /// The part.
    pub part: String,
    /// Seed action name (`Move_Table`, …).
    pub action: String,
    /// For people: `#3 Move_Table gear 120 mm`.
    pub description: String,
    /// The part's state once the skill finished (`Grasped`, …).
    pub end_state: String,
    /// What the controller does.
    pub commands: Vec<ControllerCommand>,
}

/// Skills bound to a robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Format version (1).
    pub version: u32,
    /// The robot's name.
    pub robot: String,
    /// Joint kinds in joint order (`revolute` / `prismatic`): units on the wire.
    pub joint_kinds: Vec<String>,
    /// The steps, in order.
    pub steps: Vec<PlanStep>,
}

/// Why skills cannot be bound to a robot.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BindError {
    /// A part moves without a grasp.
    #[error("skill #{skill} moves `{part}` but its task has no grasp")]
    NoGrasp {
        /// Skill id.
        skill: usize,
        /// Part.
        part: String,
    },
    /// The robot cannot make a motion.
    #[error("skill #{skill} ({action} {part}): {source}")]
    Motion {
        /// Skill id.
        skill: usize,
        /// Action name.
        action: &'static str,
        /// Part.
        part: String,
        /// The motion error.
        source: crate::kinematics::MotionError,
    },
    /// The robot cannot reach a grasp.
    #[error("skill #{skill} ({action} {part}): {source}")]
    Ik {
        /// Skill id.
        skill: usize,
        /// Action name.
        action: &'static str,
        /// Part.
        part: String,
        /// The inverse-kinematics error.
        source: crate::kinematics::IkError,
    },
    /// The precision manipulator's axes for this skill cannot make the motion.
    #[error("skill #{skill} ({action} {part}): {source}")]
    Precision {
        /// Skill id.
        skill: usize,
        /// Action name.
        action: &'static str,
        /// Part.
        part: String,
        /// Which axis, and why.
        source: crate::kinematics::PrecisionError,
    },
    /// A plan file that cannot be read or written.
    #[error("plan file: {0}")]
    File(String),
}

/// The FITUP_TOOL TOUCH `index` of the tool axis nearest `direction` (tool
/// frame): 0 +z, 1 −z, 2 +x, 3 −x, 4 +y, 5 −y
/// ([`crate::manipulator::simulator::touch_direction`]).
pub fn touch_index(direction: &crate::math::Vec3) -> i32 {
    let d = direction;
    let (k, v) = [(0, d.z), (2, d.x), (4, d.y)]
        .into_iter()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .unwrap_or((0, 1.0));
    if v < 0.0 {
        k + 1
    } else {
        k
    }
}

/// Keeps a sample every `interval` seconds (and the last): `(joints, dt)`.
fn points(
    traj: &crate::kinematics::Trajectory,
    start: &[f64],
    interval: f64,
) -> Vec<(Vec<f64>, f64)> {
    let mut out = vec![(start.to_vec(), 0.0)];
    let mut last_t = 0.0;
    let n = traj.samples.len();
    for (i, s) in traj.samples.iter().enumerate() {
        if s.t - last_t >= interval || (i + 1 == n && s.t > last_t) {
            out.push((s.joints.clone(), s.t - last_t));
            last_t = s.t;
        }
    }
    out
}

/// Each task's grasp (tool pose in the part frame, mm; gripper width, mm), by task
/// index: what both binders (arm and precision manipulator) look up per skill.
pub(super) struct Grasps(HashMap<usize, (Transform, f64)>);

impl Grasps {
    pub(super) fn of(tasks: &[Task]) -> Self {
        Self(
            tasks
                .iter()
                .filter_map(|t| {
                    t.grasp
                        .as_ref()
                        .map(|g| (t.index, (g.tool_in_part, g.width)))
                })
                .collect(),
        )
    }

    /// The grasp of skill `s`'s task; a part motion without one is an error.
    pub(super) fn of_skill(&self, s: &Skill) -> Result<(Transform, f64), BindError> {
        self.0
            .get(&s.task)
            .copied()
            .ok_or_else(|| BindError::NoGrasp {
                skill: s.id,
                part: s.part.clone(),
            })
    }
}

impl Plan {
    /// Binds `skills` to `robot` from joints `start` (rad / mm). `tasks` give each
    /// part's grasp (tool in part). A robot with the precision manipulator's layout
    /// ([`crate::kinematics::PrecisionAxes::detect`]) is bound by its own rules
    /// (each action moves only its axes, the part poses are in the rotary table's
    /// frame; `options` are not used); any other robot as an arm.
    ///
    /// # Errors
    /// A part motion without a grasp, a motion the robot cannot make (unreachable,
    /// singular, a joint limit).
    pub fn bind(
        skills: &[Skill],
        tasks: &[Task],
        robot: &Robot,
        start: &[f64],
        options: &MotionOptions,
    ) -> Result<Self, BindError> {
        let grasps = Grasps::of(tasks);
        if let Ok(axes) = crate::kinematics::PrecisionAxes::detect(robot) {
            return super::precision::bind(skills, &grasps, robot, &axes, start);
        }
        let by_task: HashMap<usize, &Task> = tasks.iter().map(|t| (t.index, t)).collect();
        let mut q = start.to_vec();
        let mut steps = Vec::new();
        for s in skills {
            let motion_err = |source| BindError::Motion {
                skill: s.id,
                action: s.action.name(),
                part: s.part.clone(),
                source,
            };
            let grasp = || grasps.of_skill(s);
            let tool = |action: &str, index: i32, value: f64| ControllerCommand::Tool {
                action: action.into(),
                index,
                value,
            };
            let commands = match s.action {
                Action::Touch => {
                    // Along the tool axis nearest the approach (the mating direction,
                    // in the tool frame of the grasp).
                    let index = by_task
                        .get(&s.task)
                        .and_then(|t| {
                            let g = t.grasp.as_ref()?;
                            let m = t.assembled_pose.inverse().apply_vector(&t.mating_direction);
                            Some(touch_index(&g.tool_in_part.inverse().apply_vector(&m)))
                        })
                        .unwrap_or(0);
                    vec![tool(
                        "touch",
                        index,
                        s.attribute("distance_mm").unwrap_or(0.0) / 1000.0,
                    )]
                }
                Action::Release => {
                    let (_, width) = grasp()?;
                    vec![tool("release", 0, (width * 1.5 / 1000.0).min(1.0))]
                }
                Action::Grasp => {
                    let (tip, width) = grasp()?;
                    let target = tip.then(&s.start.0);
                    let sol =
                        robot
                            .inverse_nearest(&target, &q, &options.ik)
                            .map_err(|source| BindError::Ik {
                                skill: s.id,
                                action: s.action.name(),
                                part: s.part.clone(),
                                source,
                            })?;
                    let traj = move_joint(robot, &q, &sol.joints, options).map_err(motion_err)?;
                    let pts = points(&traj, &q, 0.2);
                    q = sol.joints;
                    vec![
                        ControllerCommand::Trajectory(pts),
                        tool("grasp", 0, (width / 1000.0).min(1.0)),
                    ]
                }
                _ => {
                    let (tip, _) = grasp()?;
                    // A screw's helix in pieces of at most 30° (each a straight line
                    // of the tool: exact about an axis through the tool point); any
                    // other motion in one line.
                    let pieces = match s.action {
                        Action::Screw => (s.attribute("turns").unwrap_or(0.0).abs() * 12.0)
                            .ceil()
                            .clamp(1.0, 10_000.0) as usize,
                        _ => 1,
                    };
                    let pivot = s
                        .start
                        .0
                        .apply(&crate::math::Point3::from(tip.translation()))
                        .coords;
                    let mut pts: Vec<(Vec<f64>, f64)> = vec![(q.clone(), 0.0)];
                    for k in 1..=pieces {
                        let pose = if pieces == 1 {
                            s.end.0
                        } else {
                            super::generator::skill_pose_at(s, &pivot, k as f64 / pieces as f64)
                        };
                        let target = tip.then(&pose);
                        let traj = move_line(robot, &q, &target, options).map_err(motion_err)?;
                        pts.extend(points(&traj, &q, 0.2).into_iter().skip(1));
                        if let Some(last) = traj.last_joints() {
                            q = last.to_vec();
                        }
                    }
                    vec![ControllerCommand::Trajectory(pts)]
                }
            };
            steps.push(PlanStep {
                skill: s.id,
                task: s.task,
                part: s.part.clone(),
                action: s.action.name().into(),
                description: s.describe(),
                end_state: s.end.1.name().into(),
                commands,
            });
        }
        Ok(Self::for_robot(robot, steps))
    }

    /// A plan of `steps` for `robot` (its name and joint kinds).
    pub(super) fn for_robot(robot: &Robot, steps: Vec<PlanStep>) -> Self {
        Self {
            version: 1,
            robot: robot.name().into(),
            joint_kinds: robot
                .joint_kinds()
                .iter()
                .map(|k| match k {
                    JointKind::Prismatic => "prismatic".to_string(),
                    _ => "revolute".to_string(),
                })
                .collect(),
            steps,
        }
    }

    /// The joint kinds of [`joint_kinds`](Self::joint_kinds).
    pub fn kinds(&self) -> Vec<JointKind> {
        self.joint_kinds
            .iter()
            .map(|k| {
                if k == "prismatic" {
                    JointKind::Prismatic
                } else {
                    JointKind::Revolute
                }
            })
            .collect()
    }

    /// The plan as JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain data serializes")
    }

    /// Parses a plan file's JSON (`name` for errors) and checks the whole plan before
    /// anything is dispatched, so that a run never stops half-way on a value the
    /// controller or the wire cannot take.
    ///
    /// # Errors
    /// Bad JSON (with line and column; nesting deeper than serde_json's 128 levels
    /// and numbers beyond f64 included), a wrong version, more than [`MAX_JOINTS`]
    /// joints, more than [`MAX_PLAN_POINTS`] trajectory points, a joint or duration
    /// that is not finite as a 32-bit float on the wire (prismatic joints in metres),
    /// a trajectory point of the wrong joint count, a negative duration, an unknown
    /// tool action or part state — each naming the file and the JSON path of the
    /// value (`steps[2].commands[0].trajectory[5][1][3]`).
    ///
    /// [`MAX_JOINTS`]: crate::manipulator::message::MAX_JOINTS
    pub fn from_json(name: &str, text: &str) -> Result<Self, BindError> {
        let plan: Plan = serde_json::from_str(text).map_err(|e| {
            BindError::File(format!(
                "{name}:{}:{}: {}",
                e.line(),
                e.column(),
                crate::diagnostics::shorten(&e.to_string(), 200)
            ))
        })?;
        let bad = |at: String, m: String| BindError::File(format!("{name}: {at}: {m}"));
        if plan.version != 1 {
            return Err(bad(
                "version".into(),
                format!("{} (this build reads 1)", plan.version),
            ));
        }
        let n = plan.joint_kinds.len();
        let max = crate::manipulator::message::MAX_JOINTS;
        if n == 0 || n > max {
            return Err(bad(
                "joint_kinds".into(),
                format!("{n} joints (1 to {max}: what simple_message carries)"),
            ));
        }
        if let Some((j, k)) = plan
            .joint_kinds
            .iter()
            .enumerate()
            .find(|(_, k)| !matches!(k.as_str(), "revolute" | "prismatic"))
        {
            return Err(bad(
                format!("joint_kinds[{j}]"),
                format!(
                    "unknown joint kind `{}` (revolute or prismatic)",
                    crate::diagnostics::shorten(k, 80)
                ),
            ));
        }
        let kinds = plan.kinds();
        let mut total = 0usize;
        for (si, s) in plan.steps.iter().enumerate() {
            let at = |rest: String| format!("steps[{si}]{rest} (skill #{})", s.skill);
            if PartState::parse(&s.end_state).is_none() {
                return Err(bad(
                    at(".end_state".into()),
                    format!(
                        "unknown state `{}`",
                        crate::diagnostics::shorten(&s.end_state, 80)
                    ),
                ));
            }
            for (ci, c) in s.commands.iter().enumerate() {
                match c {
                    ControllerCommand::Trajectory(pts) => {
                        total += pts.len();
                        if total > MAX_PLAN_POINTS {
                            return Err(bad(
                                at(format!(".commands[{ci}]")),
                                format!(
                                    "more than {MAX_PLAN_POINTS} trajectory points in the plan"
                                ),
                            ));
                        }
                        for (pi, (q, d)) in pts.iter().enumerate() {
                            let here =
                                |k: String| at(format!(".commands[{ci}].trajectory[{pi}]{k}"));
                            if q.len() != n {
                                return Err(bad(
                                    here("[0]".into()),
                                    format!("{} joint values, the robot has {n}", q.len()),
                                ));
                            }
                            if !(d.is_finite() && *d >= 0.0 && (*d as f32).is_finite()) {
                                return Err(bad(
                                    here("[1]".into()),
                                    format!("duration {d} s: a finite number ≥ 0 that fits a 32-bit float"),
                                ));
                            }
                            if let Err(why) =
                                crate::manipulator::client::wire_point(&kinds, 0, q, *d)
                            {
                                let j = match why {
                                    crate::manipulator::client::WireError::Joint {
                                        joint, ..
                                    } => joint,
                                    _ => 0,
                                };
                                return Err(bad(here(format!("[0][{j}]")), why.to_string()));
                            }
                        }
                    }
                    ControllerCommand::Tool {
                        action,
                        value,
                        index,
                    } => {
                        let here = |k: &str| at(format!(".commands[{ci}].tool.{k}"));
                        if ControllerCommand::tool_action(action).is_none() {
                            return Err(bad(
                                here("action"),
                                format!(
                                    "unknown tool action `{}` (grasp, release, touch, set_output)",
                                    crate::diagnostics::shorten(action, 80)
                                ),
                            ));
                        }
                        if !(value.is_finite() && (*value as f32).is_finite()) {
                            return Err(bad(
                                here("value"),
                                format!("{value} does not fit the wire's 32-bit float"),
                            ));
                        }
                        if *index < 0 {
                            return Err(bad(here("index"), format!("{index} is negative")));
                        }
                    }
                }
            }
        }
        Ok(plan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Plan {
        Plan {
            version: 1,
            robot: "r".into(),
            joint_kinds: vec!["revolute".into(), "prismatic".into()],
            steps: vec![PlanStep {
                skill: 0,
                task: 0,
                part: "p".into(),
                action: "Move_Table".into(),
                description: "#0".into(),
                end_state: "Grasped".into(),
                commands: vec![
                    ControllerCommand::Trajectory(vec![
                        (vec![0.0, 0.0], 0.0),
                        (vec![0.5, 250.0], 1.0),
                    ]),
                    ControllerCommand::Tool {
                        action: "grasp".into(),
                        index: 0,
                        value: 0.01,
                    },
                ],
            }],
        }
    }

    #[test]
    fn values_beyond_the_wire_are_refused_at_their_json_path() {
        assert!(Plan::from_json("p.json", &plan().to_json()).is_ok());
        type Edit = fn(&mut Plan);
        let cases: [(Edit, &str); 5] = [
            (
                |p| {
                    if let ControllerCommand::Trajectory(t) = &mut p.steps[0].commands[0] {
                        t[1].0[0] = 1e39;
                    }
                },
                "steps[0].commands[0].trajectory[1][0][0]",
            ),
            (
                // A prismatic joint goes out in metres: 1e41 mm is 1e38 m, which fits.
                |p| {
                    if let ControllerCommand::Trajectory(t) = &mut p.steps[0].commands[0] {
                        t[1].0[1] = 1e42;
                    }
                },
                "steps[0].commands[0].trajectory[1][0][1]",
            ),
            (
                |p| {
                    if let ControllerCommand::Trajectory(t) = &mut p.steps[0].commands[0] {
                        t[1].1 = 1e39;
                    }
                },
                "steps[0].commands[0].trajectory[1][1]",
            ),
            (
                |p| {
                    if let ControllerCommand::Tool { value, .. } = &mut p.steps[0].commands[1] {
                        *value = -1e300;
                    }
                },
                "steps[0].commands[1].tool.value",
            ),
            (
                |p| p.joint_kinds = vec!["revolute".into(); 11],
                "joint_kinds",
            ),
        ];
        for (edit, at) in cases {
            let mut p = plan();
            edit(&mut p);
            let e = Plan::from_json("p.json", &p.to_json())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("plan file: p.json: "), "{e}");
            assert!(e.contains(at), "{at}: {e}");
        }
        let mut p = plan();
        if let ControllerCommand::Trajectory(t) = &mut p.steps[0].commands[0] {
            t[1].0[1] = 1e41;
        }
        assert!(Plan::from_json("p.json", &p.to_json()).is_ok());
    }

    #[test]
    fn deep_huge_and_non_finite_json_are_located_errors() {
        let deep = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
        let e = Plan::from_json("d.json", &deep).unwrap_err().to_string();
        assert!(e.starts_with("plan file: d.json:1:"), "{e}");
        let text = plan().to_json().replace("250.0", "1e400");
        let e = Plan::from_json("n.json", &text).unwrap_err().to_string();
        assert!(e.starts_with("plan file: n.json:"), "{e}");
        let text = plan().to_json().replace("250.0", "NaN");
        assert!(Plan::from_json("n.json", &text).is_err());
        let long = format!("{{\"version\": \"{}\"}}", "v".repeat(1 << 20));
        let e = Plan::from_json("l.json", &long).unwrap_err().to_string();
        assert!(e.len() < 400, "{} bytes", e.len());
    }

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(512))]

        /// Random edits of a valid plan file never panic: the result is a plan or an
        /// error that names the file.
        #[test]
        fn mutated_plans_are_ok_or_located_errors(
            edits in proptest::collection::vec((0usize..2000, 0usize..8, 0u8..3), 1..6),
        ) {
            const INSERTS: [&str; 8] = ["1e39", "-", "[", "]", "\"", "NaN", "1e400", ","];
            let mut text = plan().to_json();
            for (at, what, how) in edits {
                let mut at = at % (text.len() + 1);
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                match how {
                    0 => text.insert_str(at, INSERTS[what]),
                    1 if at < text.len() => {
                        let mut end = at + 1;
                        while !text.is_char_boundary(end) {
                            end += 1;
                        }
                        text.replace_range(at..end, "");
                    }
                    _ => text.truncate(at),
                }
            }
            if let Err(e) = Plan::from_json("m.json", &text) {
                let e = e.to_string();
                proptest::prop_assert!(e.starts_with("plan file: m.json"), "{}", e);
            }
        }
    }
}
