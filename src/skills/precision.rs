//! Skills bound to seed 003's two-finger precision manipulator (the catalog's
//! `precision_2finger`, [`crate::kinematics::precision_manipulator`]): each skill
//! moves only the axes its action names (section 3.2 and 4.1), solved in closed form
//! by [`PrecisionAxes::solve`].
//!
//! | action | axes that move |
//! |---|---|
//! | `Move_Table` | XY table |
//! | `Move_Probe`, `Insert`, `Line`, `Joint`, `Circle` | probe stage X, Y, Z |
//! | `Rotate_Table` | rotary table, the XY table following so that the grasp point stays put |
//! | `Rotate_Probes` | the probes' turn about the closing axis |
//! | `Screw` | rotary table (the turns, about the screw axis) + probe stage Z (the advance) |
//! | `Grasp` | fingers open, probe stage up to the top of its stroke, table XY and C bring the part under the probes (and the probes turn to it), probes down, fingers close |
//! | `Release` | fingers open, probe stage up |
//! | `Touch` | the controller's guarded move along the tool's z (down) |
//!
//! Part poses of the skills are in the **work frame** (the rotary table's frame;
//! the world frame when the table's axes are at 0). A motion is sampled every
//! 0.25 mm and 2° of the part's own path (a turn about the grasp point, a screw's
//! helix, else a straight line), so the table's arc is followed, not its chord; a
//! sample the skill's axes cannot reach stops the binding naming the skill and the
//! axis.

use super::generator::skill_pose_at;
use super::program::{BindError, ControllerCommand, Grasps, Plan, PlanStep};
use super::{Action, Skill};
use crate::kinematics::{Free, PrecisionAxes, Robot, FINGER_OPEN};
use crate::math::Point3;

/// Speeds of the precision manipulator's axes used to time trajectory points:
/// table 10 mm/s, rotary table 60°/s, probe stage 2 mm/s, probes' turn 30°/s,
/// fingers 2 mm/s.
fn speed(axes: &PrecisionAxes, j: usize) -> f64 {
    if axes.table.contains(&j) {
        10.0
    } else if j == axes.table_c {
        60f64.to_radians()
    } else if axes.probe.contains(&j) || axes.fingers.contains(&j) {
        2.0
    } else {
        30f64.to_radians()
    }
}

/// How much wider than the part the fingers open before a grasp and on a release
/// (mm, on each side).
const OPEN_MARGIN: f64 = 0.5;

/// Largest number of samples of one skill's motion.
const MAX_SAMPLES: usize = 20_000;

fn seconds(axes: &PrecisionAxes, a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .enumerate()
        .map(|(j, (x, y))| (y - x).abs() / speed(axes, j))
        .fold(0.0, f64::max)
}

/// A trajectory through `qs` from `q` (timed by the axes' speeds).
fn trajectory(axes: &PrecisionAxes, q: &[f64], qs: &[Vec<f64>]) -> ControllerCommand {
    let mut pts = vec![(q.to_vec(), 0.0)];
    let mut prev = q.to_vec();
    for next in qs {
        pts.push((next.clone(), seconds(axes, &prev, next)));
        prev.clone_from(next);
    }
    ControllerCommand::Trajectory(pts)
}

/// Binds `skills` (part poses in the work frame) to the precision manipulator
/// `robot` from joints `start`.
pub(super) fn bind(
    skills: &[Skill],
    grasps: &Grasps,
    robot: &Robot,
    axes: &PrecisionAxes,
    start: &[f64],
) -> Result<Plan, BindError> {
    let mut q = start.to_vec();
    let mut steps = Vec::new();
    let top = robot.joint_limits()[axes.probe[2]].map_or(0.0, |l| l.max);
    let finger_max = |j: usize| robot.joint_limits()[j].map_or(FINGER_OPEN, |l| l.max);
    for s in skills {
        let fail = |source| BindError::Precision {
            skill: s.id,
            action: s.action.name(),
            part: s.part.clone(),
            source,
        };
        let grasp = || grasps.of_skill(s);
        let tool = |action: &str, value: f64| ControllerCommand::Tool {
            action: action.into(),
            index: 0,
            value,
        };
        let open = |q: &[f64], width: f64| {
            let mut o = q.to_vec();
            for &f in &axes.fingers {
                o[f] = (width / 2.0 + OPEN_MARGIN).min(finger_max(f));
            }
            o
        };
        let up = |q: &[f64]| {
            let mut u = q.to_vec();
            u[axes.probe[2]] = u[axes.probe[2]].max(top);
            u
        };
        let commands = match s.action {
            Action::Touch => vec![tool(
                "touch",
                s.attribute("distance_mm").unwrap_or(0.0) / 1000.0,
            )],
            Action::Grasp => {
                let (g, width) = grasp()?;
                let target = g.then(&s.start.0);
                let q_open = open(&q, width);
                let q_up = up(&q_open);
                let q_at = axes
                    .solve(robot, &q_up, &target, Free::GRASP)
                    .map_err(fail)?;
                let mut q_over = q_at.clone();
                q_over[axes.probe[2]] = q_up[axes.probe[2]];
                let mut q_closed = q_at.clone();
                for &f in &axes.fingers {
                    q_closed[f] = (width / 2.0).min(finger_max(f));
                }
                axes.check_limits(robot, &q_closed).map_err(fail)?;
                let approach = trajectory(axes, &q, &[q_open, q_up, q_over, q_at.clone()]);
                let close = trajectory(axes, &q_at, std::slice::from_ref(&q_closed));
                q = q_closed;
                vec![approach, close, tool("grasp", (width / 1000.0).min(1.0))]
            }
            Action::Release => {
                let (_, width) = grasp()?;
                let q_open = open(&q, width);
                let q_up = up(&q_open);
                let t = trajectory(axes, &q, &[q_open, q_up.clone()]);
                q = q_up;
                vec![tool("release", (width * 1.5 / 1000.0).min(1.0)), t]
            }
            action => {
                let (g, _) = grasp()?;
                let free = match action {
                    Action::MoveTable => Free::TABLE,
                    Action::RotateTable => Free::TABLE_TURN,
                    Action::RotateProbe => Free::PROBE_TURN,
                    Action::Screw => Free::SCREW,
                    _ => Free::PROBES,
                };
                let (r, d) = s.start.0.distance_to(&s.end.0);
                let turns = s.attribute("turns").unwrap_or(0.0).abs();
                let n = (d / 0.25)
                    .max(r / 2f64.to_radians())
                    .max(turns * 180.0)
                    .ceil()
                    .clamp(1.0, MAX_SAMPLES as f64) as usize;
                let pivot = s.start.0.apply(&Point3::from(g.translation())).coords;
                let mut qs = Vec::with_capacity(n);
                let mut prev = q.clone();
                for k in 1..=n {
                    let pose = skill_pose_at(s, &pivot, k as f64 / n as f64);
                    let next = axes
                        .solve(robot, &prev, &g.then(&pose), free)
                        .map_err(fail)?;
                    qs.push(next.clone());
                    prev = next;
                }
                let t = trajectory(axes, &q, &qs);
                q = prev;
                vec![t]
            }
        };
        steps.push(PlanStep::of(s, commands));
    }
    Ok(Plan::for_robot(robot, steps))
}
