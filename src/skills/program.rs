//! Skills bound to a robot, as data: each skill becomes the commands a controller runs
//! (joint trajectories and tool commands), saved as a plan file (JSON) that
//! `fitup skills run PLAN --target HOST:PORT` dispatches. Binding itself is
//! [`Plan::bind`] (`bind.rs` for arms, `precision.rs` for the precision manipulator).

use super::{PartState, Skill};
use crate::kinematics::{JointKind, Robot};
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
    /// The part's state once the skill finished (stored by its name: `Grasped`, …).
    pub end_state: PartState,
    /// What the controller does.
    pub commands: Vec<ControllerCommand>,
}

impl PlanStep {
    /// The step of skill `s` doing `commands`.
    pub fn of(s: &Skill, commands: Vec<ControllerCommand>) -> Self {
        Self {
            skill: s.id,
            task: s.task,
            part: s.part.clone(),
            action: s.action.name().into(),
            description: s.describe(),
            end_state: s.end.1,
            commands,
        }
    }
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
    /// A plan file that cannot be read.
    #[error("plan file: {}{problem}", .file.display())]
    File {
        /// The file, as named to [`Plan::from_json`].
        file: std::path::PathBuf,
        /// What is wrong, and where in the file.
        problem: PlanFileProblem,
    },
}

/// What is wrong in a plan file ([`BindError::File`]).
#[derive(Debug)]
#[non_exhaustive]
pub enum PlanFileProblem {
    /// JSON that does not parse, or does not fit a plan (serde's error, with its line
    /// and column).
    Json(crate::files::JsonError),
    /// A value the plan cannot take, at its JSON path
    /// (`steps[2].commands[0].trajectory[5][1]`, with the skill: ` (skill #4)`).
    Value {
        /// Where.
        at: String,
        /// Why.
        problem: PlanValueProblem,
    },
}

impl std::fmt::Display for PlanFileProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlanFileProblem::Json(e) => write!(
                f,
                ":{}:{}: {}",
                e.line(),
                e.column(),
                crate::diagnostics::shorten(&e.to_string(), 200)
            ),
            PlanFileProblem::Value { at, problem } => write!(f, ": {at}: {problem}"),
        }
    }
}

/// A plan value the controller or the wire cannot take ([`PlanFileProblem::Value`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum PlanValueProblem {
    /// A file version this build does not read.
    Version(u32),
    /// A joint count simple_message cannot carry.
    JointCount(usize),
    /// A joint kind other than revolute and prismatic (shortened).
    JointKind(String),
    /// More than [`MAX_PLAN_POINTS`] trajectory points.
    TooManyPoints,
    /// A trajectory point with another joint count than the robot's.
    PointJoints {
        /// The point's joint values.
        values: usize,
        /// The robot's joints.
        joints: usize,
    },
    /// A duration that is not finite, negative, or beyond a 32-bit float.
    Duration(f64),
    /// A point the wire cannot carry.
    Wire(crate::manipulator::client::WireError),
    /// A tool action other than grasp, release, touch and set_output (shortened).
    ToolAction(String),
    /// A tool value beyond a 32-bit float.
    ToolValue(f64),
    /// A negative tool index.
    ToolIndex(i32),
}

impl std::fmt::Display for PlanValueProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlanValueProblem::Version(v) => write!(f, "{v} (this build reads 1)"),
            PlanValueProblem::JointCount(n) => write!(
                f,
                "{n} joints (1 to {}: what simple_message carries)",
                crate::manipulator::message::MAX_JOINTS
            ),
            PlanValueProblem::JointKind(k) => {
                write!(f, "unknown joint kind `{k}` (revolute or prismatic)")
            }
            PlanValueProblem::TooManyPoints => write!(
                f,
                "more than {MAX_PLAN_POINTS} trajectory points in the plan"
            ),
            PlanValueProblem::PointJoints { values, joints } => {
                write!(f, "{values} joint values, the robot has {joints}")
            }
            PlanValueProblem::Duration(d) => write!(
                f,
                "duration {d} s: a finite number ≥ 0 that fits a 32-bit float"
            ),
            PlanValueProblem::Wire(why) => write!(f, "{why}"),
            PlanValueProblem::ToolAction(a) => write!(
                f,
                "unknown tool action `{a}` (grasp, release, touch, set_output)"
            ),
            PlanValueProblem::ToolValue(v) => {
                write!(f, "{v} does not fit the wire's 32-bit float")
            }
            PlanValueProblem::ToolIndex(i) => write!(f, "{i} is negative"),
        }
    }
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
    /// Bad JSON (with line and column; nesting deeper than serde_json's 128 levels,
    /// numbers beyond f64 and an unknown part state included), a wrong version, more than [`MAX_JOINTS`]
    /// joints, more than [`MAX_PLAN_POINTS`] trajectory points, a joint or duration
    /// that is not finite as a 32-bit float on the wire (prismatic joints in metres),
    /// a trajectory point of the wrong joint count, a negative duration, an unknown
    /// tool action — each naming the file and the JSON path of the
    /// value (`steps[2].commands[0].trajectory[5][1][3]`).
    ///
    /// [`MAX_JOINTS`]: crate::manipulator::message::MAX_JOINTS
    pub fn from_json(name: &str, text: &str) -> Result<Self, BindError> {
        let plan: Plan = serde_json::from_str(text).map_err(|e| BindError::File {
            file: name.into(),
            problem: PlanFileProblem::Json(e.into()),
        })?;
        let bad = |at: String, problem| BindError::File {
            file: name.into(),
            problem: PlanFileProblem::Value { at, problem },
        };
        if plan.version != 1 {
            return Err(bad(
                "version".into(),
                PlanValueProblem::Version(plan.version),
            ));
        }
        let n = plan.joint_kinds.len();
        let max = crate::manipulator::message::MAX_JOINTS;
        if n == 0 || n > max {
            return Err(bad("joint_kinds".into(), PlanValueProblem::JointCount(n)));
        }
        if let Some((j, k)) = plan
            .joint_kinds
            .iter()
            .enumerate()
            .find(|(_, k)| !matches!(k.as_str(), "revolute" | "prismatic"))
        {
            return Err(bad(
                format!("joint_kinds[{j}]"),
                PlanValueProblem::JointKind(crate::diagnostics::shorten(k, 80)),
            ));
        }
        let kinds = plan.kinds();
        let mut total = 0usize;
        for (si, s) in plan.steps.iter().enumerate() {
            let at = |rest: String| format!("steps[{si}]{rest} (skill #{})", s.skill);
            for (ci, c) in s.commands.iter().enumerate() {
                match c {
                    ControllerCommand::Trajectory(pts) => {
                        total += pts.len();
                        if total > MAX_PLAN_POINTS {
                            return Err(bad(
                                at(format!(".commands[{ci}]")),
                                PlanValueProblem::TooManyPoints,
                            ));
                        }
                        for (pi, (q, d)) in pts.iter().enumerate() {
                            let here =
                                |k: String| at(format!(".commands[{ci}].trajectory[{pi}]{k}"));
                            if q.len() != n {
                                return Err(bad(
                                    here("[0]".into()),
                                    PlanValueProblem::PointJoints {
                                        values: q.len(),
                                        joints: n,
                                    },
                                ));
                            }
                            if !(d.is_finite() && *d >= 0.0 && (*d as f32).is_finite()) {
                                return Err(bad(
                                    here("[1]".into()),
                                    PlanValueProblem::Duration(*d),
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
                                return Err(bad(
                                    here(format!("[0][{j}]")),
                                    PlanValueProblem::Wire(why),
                                ));
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
                                PlanValueProblem::ToolAction(crate::diagnostics::shorten(
                                    action, 80,
                                )),
                            ));
                        }
                        if !(value.is_finite() && (*value as f32).is_finite()) {
                            return Err(bad(here("value"), PlanValueProblem::ToolValue(*value)));
                        }
                        if *index < 0 {
                            return Err(bad(here("index"), PlanValueProblem::ToolIndex(*index)));
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
                end_state: PartState::Grasped,
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
    fn plan_file_messages_name_the_file_the_place_and_the_value() {
        let refused = |p: &Plan| Plan::from_json("p.json", &p.to_json()).unwrap_err();
        let mut p = plan();
        p.version = 2;
        assert_eq!(
            refused(&p).to_string(),
            "plan file: p.json: version: 2 (this build reads 1)"
        );
        let mut p = plan();
        p.joint_kinds = vec!["revolute".into(); 11];
        assert_eq!(
            refused(&p).to_string(),
            format!(
                "plan file: p.json: joint_kinds: 11 joints (1 to {}: what simple_message carries)",
                crate::manipulator::message::MAX_JOINTS
            )
        );
        let mut p = plan();
        p.joint_kinds[1] = "linear".into();
        assert_eq!(
            refused(&p).to_string(),
            "plan file: p.json: joint_kinds[1]: unknown joint kind `linear` (revolute or prismatic)"
        );
        let mut p = plan();
        if let ControllerCommand::Trajectory(t) = &mut p.steps[0].commands[0] {
            t[1].1 = -1.0;
        }
        let e = refused(&p);
        assert!(matches!(
            &e,
            BindError::File {
                problem: PlanFileProblem::Value {
                    problem: PlanValueProblem::Duration(d),
                    ..
                },
                ..
            } if *d == -1.0
        ));
        assert_eq!(
            e.to_string(),
            "plan file: p.json: steps[0].commands[0].trajectory[1][1] (skill #0): duration -1 s: a finite number ≥ 0 that fits a 32-bit float"
        );
        let mut p = plan();
        if let ControllerCommand::Tool { index, .. } = &mut p.steps[0].commands[1] {
            *index = -1;
        }
        assert_eq!(
            refused(&p).to_string(),
            "plan file: p.json: steps[0].commands[1].tool.index (skill #0): -1 is negative"
        );
        let json = serde_json::from_str::<Plan>("{").unwrap_err();
        assert_eq!(
            Plan::from_json("j.json", "{").unwrap_err().to_string(),
            format!(
                "plan file: j.json:{}:{}: {json}",
                json.line(),
                json.column()
            )
        );
    }

    #[test]
    fn part_states_are_stored_by_name_and_unknown_ones_are_located() {
        let text = plan().to_json();
        assert!(text.contains("\"end_state\": \"Grasped\""), "{text}");
        let bad = text.replace("\"Grasped\"", "\"Gripped\"");
        let e = Plan::from_json("p.json", &bad).unwrap_err().to_string();
        assert!(e.starts_with("plan file: p.json:"), "{e}");
        assert!(e.contains("unknown state `Gripped`"), "{e}");
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
