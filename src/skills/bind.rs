//! Skills bound to a robot: the one entry [`Plan::bind`], which binds a robot with
//! the precision manipulator's layout by its own rules (`precision.rs`) and any other
//! robot as an arm (here). The plan's data and its file format live in `program.rs`.
//!
//! On an arm every part motion (Move_Table, Move_Probe, Rotate_*, Insert, Screw,
//! Line) is a straight TCP line of the tool holding the part (tool pose = grasp's
//! tool-in-part, then the part's pose); Grasp first moves the arm (joint move) to
//! the grasp, then closes the gripper; Release opens it; Touch asks the controller to
//! move until contact. Joints are rad / mm; trajectory points carry the time from
//! the previous point (s).

use super::program::{BindError, ControllerCommand, Grasps, Plan, PlanStep};
use super::{Action, Skill};
use crate::kinematics::{move_joint, move_line, MotionOptions, Robot};
use crate::sequence::Task;
use std::collections::HashMap;

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
            steps.push(PlanStep::of(s, commands));
        }
        Ok(Self::for_robot(robot, steps))
    }
}
