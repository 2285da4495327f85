//! The whole chain in one call: the tasks of an assembly sequence → workflows →
//! skills (checked against the assembly as it is at each task) → a [`Plan`] bound
//! to a robot of another cell.
//!
//! The assembly is planned in its own frame (the document the sequence came from);
//! it sits in the robot's cell at [`ChainOptions::place`] (assembly frame → robot
//! cell frame). Before its task a part waits at its supply pose: its assembled pose
//! moved by [`ChainOptions::supply_offset`] (assembly frame, mm), the seed's In_WS
//! position on the worktable. Units: millimetres and radians.
//!
//! # Examples
//!
//! ```no_run
//! use fitup::document::Document;
//! use fitup::sequence::{plan_sequence, SequenceOptions};
//! use fitup::skills::chain::{plan_chain, ChainOptions};
//! use fitup::workspace::SceneCache;
//! use std::path::Path;
//!
//! let wheel = Document::open(Path::new("models/wheel.yaml")).unwrap();
//! let seq = plan_sequence(&wheel, &mut SceneCache::new(), &SequenceOptions::default()).unwrap();
//! let cell = Document::open(Path::new("models/mz07.yaml")).unwrap();
//! let robot = cell.robot("mz07").unwrap();
//! let options = ChainOptions {
//!     place: fitup::math::Transform::from_translation(fitup::math::Vec3::new(500.0, 0.0, 200.0)),
//!     ..ChainOptions::default()
//! };
//! let chain = plan_chain(&wheel, &seq.best().tasks, &[], robot.robot(), robot.joints(), &options).unwrap();
//! println!("{} skills", chain.skills.len());
//! ```

use super::generator::{generate, segment_check_fn, GeneratorOptions, SegmentHit, SkillError};
use super::program::{BindError, Plan};
use super::{Skill, Template};
use crate::document::Document;
use crate::kinematics::{MotionOptions, Robot};
use crate::math::{Transform, Vec3};
use crate::sequence::Task;
use std::collections::HashMap;
use thiserror::Error;

/// Settings of [`plan_chain`].
#[derive(Debug, Clone)]
pub struct ChainOptions {
    /// Where the assembly sits in the robot's cell: assembly frame → cell frame.
    pub place: Transform,
    /// Where the parts wait before their tasks, in a row: the k-th task's part (from
    /// 0) at its assembled pose moved by (k + 1) × this, in the assembly frame (mm).
    /// Default: 60 mm along +Y.
    pub supply_offset: Vec3,
    /// Supply poses given per part (part → assembly frame), instead of the row.
    pub supply: HashMap<String, Transform>,
    /// The robot's tool frame in the grasp frame (the grasp's z is the approach — the
    /// mating direction —, x the closing direction): identity when the robot's tool
    /// z points where it approaches; a half turn about x for a tool whose z points
    /// back at the flange (the MZ07 of `models/mz07.yaml`).
    pub tool_in_grasp: Transform,
    /// The generators' settings.
    pub generator: GeneratorOptions,
    /// Speeds and IK settings of the robot's motions.
    pub motion: MotionOptions,
    /// Check every segment of a part for interference with the assembly (the parts
    /// assembled before it where they are assembled, the later ones at their supply
    /// poses).
    pub check: bool,
}

impl Default for ChainOptions {
    fn default() -> Self {
        Self {
            place: Transform::IDENTITY,
            supply_offset: Vec3::new(0.0, 60.0, 0.0),
            tool_in_grasp: Transform::IDENTITY,
            supply: HashMap::new(),
            generator: GeneratorOptions::default(),
            motion: MotionOptions::default(),
            check: true,
        }
    }
}

/// Skills (in the assembly frame) and the plan that executes them (in the cell).
#[derive(Debug, Clone)]
pub struct Chain {
    /// The skill primitives, in execution order; poses part → assembly frame.
    pub skills: Vec<Skill>,
    /// The skills bound to the robot.
    pub plan: Plan,
}

/// Why the chain cannot be planned.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ChainError {
    /// A task's part is not a component of the assembly document.
    #[error("task {task}: `{part}` is not a component of the assembly document")]
    UnknownPart {
        /// Task index.
        task: usize,
        /// Part name.
        part: String,
    },
    /// A pose or offset that is not finite.
    #[error("{0} is not finite")]
    NotFinite(&'static str),
    /// Skill generation failed (a segment interferes, a missing grasp…).
    #[error(transparent)]
    Skills(#[from] SkillError),
    /// The robot cannot execute a skill.
    #[error(transparent)]
    Bind(#[from] BindError),
}

/// The supply pose of the `k`-th task's part: its assembled pose moved by
/// (k + 1) × `offset`.
pub fn supply_pose(task: &Task, k: usize, offset: &Vec3) -> Transform {
    Transform::from_parts(
        task.assembled_pose.translation() + offset * (k as f64 + 1.0),
        task.assembled_pose.rotation(),
    )
}

/// Plans the whole chain for `tasks` (in sequence order) of the assembly `doc`:
/// skills from the templates (`templates` override the defaults per operation),
/// bound to `robot` starting at joints `start` (rad / mm).
///
/// # Errors
/// [`ChainError`]: an unknown part, a segment that interferes, a motion the robot
/// cannot make.
pub fn plan_chain(
    doc: &Document,
    tasks: &[Task],
    templates: &[Template],
    robot: &Robot,
    start: &[f64],
    options: &ChainOptions,
) -> Result<Chain, ChainError> {
    if !options.tool_in_grasp.is_finite() {
        return Err(ChainError::NotFinite("the tool frame"));
    }
    if !options.place.is_finite() {
        return Err(ChainError::NotFinite("the placement"));
    }
    if !options.supply_offset.iter().all(|v| v.is_finite())
        || !options.supply.values().all(Transform::is_finite)
    {
        return Err(ChainError::NotFinite("the supply offset"));
    }
    for t in tasks {
        doc.component_index(&t.part)
            .map_err(|_| ChainError::UnknownPart {
                task: t.index,
                part: t.part.clone(),
            })?;
    }
    let supply: HashMap<&str, Transform> = tasks
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let pose = options
                .supply
                .get(&t.part)
                .copied()
                .unwrap_or_else(|| supply_pose(t, k, &options.supply_offset));
            (t.part.as_str(), pose)
        })
        .collect();
    // The assembly as it is during each task: earlier parts assembled, later ones
    // (and this one, which the sweep moves) at their supply poses.
    let stages: Vec<Document> = if options.check {
        (0..tasks.len())
            .map(|k| {
                let mut d = doc.clone();
                for later in &tasks[k..] {
                    // The part exists (checked above).
                    let _ = d.set_transform(&later.part, supply[later.part.as_str()]);
                }
                d
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut checks: Vec<_> = stages.iter().map(segment_check_fn).collect();
    let position: HashMap<usize, usize> = tasks
        .iter()
        .enumerate()
        .map(|(k, t)| (t.index, k))
        .collect();
    let mut check = |task: &Task, a: &Transform, b: &Transform| -> Result<(), SegmentHit> {
        match position.get(&task.index).and_then(|&k| checks.get_mut(k)) {
            Some(c) => c(task, a, b),
            None => Ok(()),
        }
    };
    let skills = generate(
        tasks,
        templates,
        &|part| supply.get(part).copied(),
        &options.generator,
        &mut check,
    )?;
    // In the robot's cell.
    let placed: Vec<Skill> = skills
        .iter()
        .map(|s| {
            let mut s = s.clone();
            s.start.0 = s.start.0.then(&options.place);
            s.end.0 = s.end.0.then(&options.place);
            s
        })
        .collect();
    // The robot holds each part by its own tool frame.
    let held: Vec<Task> = tasks
        .iter()
        .map(|t| {
            let mut t = t.clone();
            if let Some(g) = t.grasp.as_mut() {
                g.tool_in_part = options.tool_in_grasp.then(&g.tool_in_part);
            }
            t
        })
        .collect();
    let plan = Plan::bind(&placed, &held, robot, start, &options.motion)?;
    Ok(Chain { skills, plan })
}
