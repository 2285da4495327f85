//! Skill primitives, part states, workflows and task templates (seed 003, section 3),
//! and the skill manager that dispatches skills to a manipulator (section 3.3).
//!
//! A **skill primitive** is `S = [Attributes, Action(Attributes), Start(Attributes),
//! End(Attributes), Condition(Attributes)]` ([`Skill`]): one [`Action`] per skill,
//! the part's start and end poses and states, and the [`Condition`] under which it
//! runs; attributes are required or optional and CAD-derived or sensed
//! ([`Attribute`]).
//!
//! An assembly part moves through [`PartState`]s (FREE → In_WS → Grasped → Adjusted →
//! Assembled); a [`Workflow`] takes it from one state to the next and owns a
//! [`Generator`] that emits the skills for that step. A [`Template`] lists the
//! workflows of one operation (insertion, screw, align); the defaults live in
//! `models/templates/*.yaml` and are validated with located errors.
//!
//! Units: millimetres and radians; every pose is part frame → assembly (world) frame.

mod bind;
pub mod chain;
pub mod generator;
pub mod manager;
mod precision;
pub mod program;
mod template;

pub use bind::touch_index;
pub use chain::{plan_chain, Chain, ChainError, ChainOptions};
pub use generator::{
    generate, orientation_turns, screw_pose, segment_check_fn, skill_pose_at, turn_about,
    GeneratorOptions, SegmentCheck, SegmentHit, SkillError, TaskProblem,
};
pub use manager::{
    log_event, CancelToken, LogDb, ManagerError, ManagerEvent, ManagerHandle, ManagerOptions,
    RunSink, SkillLog, SkillManager, SkillStatus,
};
pub use program::{
    BindError, ControllerCommand, Plan, PlanFileProblem, PlanStep, PlanValueProblem,
};
pub use template::{default_template, Template, TemplateError, Workflow};

use crate::math::Transform;

/// What a skill does: the seed's actions plus the arm motions fitup already has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Action {
    /// Long-range straight move of the part (the XY table on seed 003's stage).
    MoveTable,
    /// Short-range straight move of the part (the probes).
    MoveProbe,
    /// Rotation of the part about the vertical (the table's Z rotation).
    RotateTable,
    /// Any other rotation of the part (the probes).
    RotateProbe,
    /// Approach until contact, to sense where a part is.
    Touch,
    /// Push along the mating direction until seated.
    Insert,
    /// Turn about the mating direction while advancing (screw / tap).
    Screw,
    /// Close the gripper (probes) on the part.
    Grasp,
    /// Open the gripper.
    Release,
    /// Joint-space arm motion.
    Joint,
    /// Straight-line TCP motion.
    Line,
    /// Circular TCP motion.
    Circle,
}

impl Action {
    /// Every action, in table order.
    pub const ALL: [Action; 12] = [
        Self::MoveTable,
        Self::MoveProbe,
        Self::RotateTable,
        Self::RotateProbe,
        Self::Touch,
        Self::Insert,
        Self::Screw,
        Self::Grasp,
        Self::Release,
        Self::Joint,
        Self::Line,
        Self::Circle,
    ];

    /// The seed's name (`Move_Table`, `Move_Probe`, `Rotate_Table`, `Rotate_Probes`,
    /// `Touch`, `Insert`, `Screw`, `Grasp`, `Release`, `Joint`, `Line`, `Circle`).
    pub fn name(self) -> &'static str {
        match self {
            Self::MoveTable => "Move_Table",
            Self::MoveProbe => "Move_Probe",
            Self::RotateTable => "Rotate_Table",
            Self::RotateProbe => "Rotate_Probes",
            Self::Touch => "Touch",
            Self::Insert => "Insert",
            Self::Screw => "Screw",
            Self::Grasp => "Grasp",
            Self::Release => "Release",
            Self::Joint => "Joint",
            Self::Line => "Line",
            Self::Circle => "Circle",
        }
    }

    /// Parses [`name`](Self::name).
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|a| a.name() == s)
    }

    /// Whether the action moves the part (start and end poses differ).
    pub fn moves_part(self) -> bool {
        !matches!(self, Self::Touch | Self::Grasp | Self::Release)
    }
}

/// Where an assembly part is in its assembly cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum PartState {
    /// Somewhere, position unknown.
    Free,
    /// In the workspace, position known.
    InWs,
    /// Held by the end effector.
    Grasped,
    /// Oriented as assembled, the safe length back along the mating direction.
    Adjusted,
    /// Joined to the base part.
    Assembled,
}

impl PartState {
    /// Every state, in cycle order.
    pub const ALL: [PartState; 5] = [
        Self::Free,
        Self::InWs,
        Self::Grasped,
        Self::Adjusted,
        Self::Assembled,
    ];

    /// The seed's name (`FREE`, `In_WS`, `Grasped`, `Adjusted`, `Assembled`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Free => "FREE",
            Self::InWs => "In_WS",
            Self::Grasped => "Grasped",
            Self::Adjusted => "Adjusted",
            Self::Assembled => "Assembled",
        }
    }

    /// Parses [`name`](Self::name).
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|a| a.name() == s)
    }
}

impl std::fmt::Display for PartState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Stored by its [`name`](PartState::name), as plan files have always had it.
impl serde::Serialize for PartState {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for PartState {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        Self::parse(&text).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown state `{}` (FREE, In_WS, Grasped, Adjusted, Assembled)",
                crate::diagnostics::shorten(&text, 80)
            ))
        })
    }
}

/// Where an attribute's value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Source {
    /// Derived from the CAD model (the task).
    Cad,
    /// Measured by a sensor at run time (until measured: the CAD estimate).
    Sensed,
    /// Set by the user (a template or an edit).
    User,
}

/// A skill attribute: a named number (mm, rad, or as its name says).
#[derive(Debug, Clone, PartialEq)]
pub struct Attribute {
    /// Name, e.g. `length_mm`, `angle_rad`, `width_mm`, `force_n`.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Required (the skill cannot run without it) or optional.
    pub required: bool,
    /// Where the value comes from.
    pub source: Source,
}

/// The condition under which a skill runs and ends.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Condition {
    /// Runs once the previous skill finished; ends at its end pose.
    Always,
    /// Runs when the part is in this state.
    PartIn(PartState),
    /// Ends on contact (force above `force_n`), else at the end pose.
    Contact {
        /// Contact force threshold (N).
        force_n: f64,
    },
}

/// A skill primitive `S = [Attributes, Action, Start, End, Condition]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Skill {
    /// Unique within a plan, in execution order.
    pub id: usize,
    /// The task (sequence index) it belongs to.
    pub task: usize,
    /// The assembly part it acts on (component name).
    pub part: String,
    /// The workflow that generated it (e.g. `Grasped->Adjusted`).
    pub workflow: String,
    /// What it does.
    pub action: Action,
    /// Its attributes.
    pub attributes: Vec<Attribute>,
    /// Part pose and state at the start.
    pub start: (Transform, PartState),
    /// Part pose and state at the end.
    pub end: (Transform, PartState),
    /// When it runs / ends.
    pub condition: Condition,
}

impl Skill {
    /// An attribute's value by name.
    pub fn attribute(&self, name: &str) -> Option<f64> {
        self.attributes
            .iter()
            .find(|a| a.name == name)
            .map(|a| a.value)
    }

    /// A one-line description for people: `#3 Move_Table gear 120.0 mm`.
    pub fn describe(&self) -> String {
        let (r, d) = self.start.0.distance_to(&self.end.0);
        let mut s = format!("#{} {} {}", self.id, self.action.name(), self.part);
        if d > 1e-9 {
            s += &format!(" {}", crate::math::format::length(d));
        }
        if r > 1e-9 {
            s += &format!(" {}", crate::math::format::angle(r));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for a in Action::ALL {
            assert_eq!(Action::parse(a.name()), Some(a));
        }
        for s in PartState::ALL {
            assert_eq!(PartState::parse(s.name()), Some(s));
        }
        assert_eq!(Action::parse("move_table"), None);
    }
}
