//! Skill generators: from tasks and templates to skill primitives (seed 003, 3.2).
//!
//! Each workflow of a task's template runs its generator from the part's current
//! pose and state. The **Move** generator (Grasped → Adjusted) turns the part to its
//! assembled orientation first (`Rotate_Table` when the turn is about the vertical,
//! else `Rotate_Probes`), then follows the straight-line path P0 → P1 → P2 → P3
//! around the obstacle box: up along the approach direction (the negated mating
//! direction) to a level clear of the box, across, and down to P3, the safe length
//! back from the assembled pose. Each segment becomes `Move_Table` (longer than
//! [`GeneratorOptions::long_range_mm`]) or `Move_Probe`, and is checked for
//! interference by the caller's [`SegmentCheck`].

use super::{Action, Attribute, Condition, PartState, Skill, Source, Template};
use crate::math::{Transform, Vec3};
use crate::sequence::Task;
use thiserror::Error;

/// Settings of the generators (mm, N).
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratorOptions {
    /// Segments longer than this go to `Move_Table`, shorter to `Move_Probe` (mm).
    pub long_range_mm: f64,
    /// Height above the obstacle box (along the approach direction) of the
    /// crossing segment P1 → P2 (mm).
    pub clearance_mm: f64,
    /// Contact force that ends `Touch` and `Insert` (N).
    pub contact_force_n: f64,
    /// How far `Touch` may travel looking for contact (mm).
    pub touch_distance_mm: f64,
    /// Turns of a `Screw`.
    pub screw_turns: f64,
}

impl Default for GeneratorOptions {
    fn default() -> Self {
        Self {
            long_range_mm: 50.0,
            clearance_mm: 20.0,
            contact_force_n: 2.0,
            touch_distance_mm: 10.0,
            screw_turns: 2.0,
        }
    }
}

/// Checks one straight segment of the part (poses part frame → world) against the
/// cell; `Err` holds the reason (what it hits).
pub type SegmentCheck<'a> = dyn FnMut(&Task, &Transform, &Transform) -> Result<(), String> + 'a;

/// Why skills cannot be generated.
#[derive(Debug, Error)]
pub enum SkillError {
    /// The template needs a grasp and the task has none.
    #[error("task {task} ({part}): the template grasps the part but the task has no grasp")]
    NoGrasp {
        /// Task index.
        task: usize,
        /// Part.
        part: String,
    },
    /// A segment interferes with the cell.
    #[error("task {task} ({part}): {action} segment {segment} interferes: {reason}")]
    Interference {
        /// Task index.
        task: usize,
        /// Part.
        part: String,
        /// The segment's action.
        action: &'static str,
        /// `P0->P1`, …
        segment: String,
        /// What it hits.
        reason: String,
    },
    /// A task that cannot be used (non-finite values, zero mating direction…).
    #[error("task {task} ({part}): {reason}")]
    BadTask {
        /// Task index.
        task: usize,
        /// Part.
        part: String,
        /// Why.
        reason: String,
    },
}

/// Generates the skills of `tasks` in order. `templates` overrides the default
/// template of an operation; `start_pose(part)` is where a part is before its task
/// (FREE / In_WS: e.g. its supply position), `None` for "as assembled".
///
/// # Errors
/// A task without the grasp its template needs, a segment that interferes, a bad
/// task.
pub fn generate(
    tasks: &[Task],
    templates: &[Template],
    start_pose: &dyn Fn(&str) -> Option<Transform>,
    options: &GeneratorOptions,
    check: &mut SegmentCheck<'_>,
) -> Result<Vec<Skill>, SkillError> {
    let mut skills = Vec::new();
    for task in tasks {
        let bad = |reason: String| SkillError::BadTask {
            task: task.index,
            part: task.part.clone(),
            reason,
        };
        let m = task.mating_direction;
        if !(m.norm() > 0.5 && m.iter().all(|v| v.is_finite())) {
            return Err(bad("the mating direction is not a unit vector".into()));
        }
        if !(task.safe_length.is_finite() && task.safe_length >= 0.0) {
            return Err(bad(format!("bad safe length {}", task.safe_length)));
        }
        let template = templates
            .iter()
            .find(|t| t.operation == task.operation)
            .cloned()
            .unwrap_or_else(|| super::default_template(task.operation));
        let mut pose = start_pose(&task.part).unwrap_or(task.assembled_pose);
        if !pose.is_finite() || !task.assembled_pose.is_finite() {
            return Err(bad("a pose is not finite".into()));
        }
        for w in &template.workflows {
            let mut out = Vec::new();
            let mut push = |action: Action,
                            to: Transform,
                            state: PartState,
                            attributes: Vec<Attribute>,
                            condition: Condition,
                            from: Transform| {
                out.push(Skill {
                    id: 0,
                    task: task.index,
                    part: task.part.clone(),
                    workflow: w.name(),
                    action,
                    attributes,
                    start: (from, w.from),
                    end: (to, state),
                    condition,
                });
            };
            let attr = |name: &str, value: f64, source: Source| Attribute {
                name: name.into(),
                value,
                required: true,
                source,
            };
            match w.generator.as_str() {
                "locate" => push(
                    Action::Touch,
                    pose,
                    w.to,
                    vec![attr("distance_mm", options.touch_distance_mm, Source::User)],
                    Condition::Contact {
                        force_n: options.contact_force_n,
                    },
                    pose,
                ),
                "grasp" => {
                    let g = task.grasp.as_ref().ok_or_else(|| SkillError::NoGrasp {
                        task: task.index,
                        part: task.part.clone(),
                    })?;
                    push(
                        Action::Grasp,
                        pose,
                        w.to,
                        vec![
                            attr("width_mm", g.width, Source::Cad),
                            attr("depth_mm", g.depth, Source::Cad),
                        ],
                        Condition::PartIn(w.from),
                        pose,
                    );
                }
                "move" => {
                    for (action, from, to, segment) in move_path(task, pose, options) {
                        check(task, &from, &to).map_err(|reason| SkillError::Interference {
                            task: task.index,
                            part: task.part.clone(),
                            action: action.name(),
                            segment: segment.clone(),
                            reason,
                        })?;
                        let (r, d) = from.distance_to(&to);
                        let a = if action.moves_part() && r > 1e-9 && d < 1e-9 {
                            attr("angle_rad", r, Source::Cad)
                        } else {
                            attr("length_mm", d, Source::Cad)
                        };
                        let state = if to.approx_eq(&adjusted_pose(task), 1e-6, 1e-9) {
                            w.to
                        } else {
                            w.from
                        };
                        push(action, to, state, vec![a], Condition::Always, from);
                        pose = to;
                    }
                }
                g @ ("insert" | "screw" | "align") => {
                    let action = match g {
                        "insert" => Action::Insert,
                        "screw" => Action::Screw,
                        _ => Action::MoveProbe,
                    };
                    let end = task.assembled_pose;
                    check(task, &pose, &end).map_err(|reason| SkillError::Interference {
                        task: task.index,
                        part: task.part.clone(),
                        action: action.name(),
                        segment: "P3->assembled".into(),
                        reason,
                    })?;
                    let mut attributes =
                        vec![attr("length_mm", pose.distance_to(&end).1, Source::Cad)];
                    if action == Action::Screw {
                        attributes.push(attr("turns", options.screw_turns, Source::User));
                    }
                    let condition = if action == Action::MoveProbe {
                        Condition::Always
                    } else {
                        Condition::Contact {
                            force_n: options.contact_force_n,
                        }
                    };
                    push(action, end, w.to, attributes, condition, pose);
                    pose = end;
                    push(
                        Action::Release,
                        end,
                        w.to,
                        vec![],
                        Condition::PartIn(w.to),
                        end,
                    );
                }
                other => return Err(bad(format!("unknown generator `{other}`"))),
            }
            skills.extend(out);
        }
    }
    for (i, s) in skills.iter_mut().enumerate() {
        s.id = i;
    }
    Ok(skills)
}

/// P3: the assembled orientation, the safe length back along the mating direction.
pub fn adjusted_pose(task: &Task) -> Transform {
    let up = -task.mating_direction.normalize();
    Transform::from_parts(
        task.assembled_pose.translation() + up * task.safe_length,
        task.assembled_pose.rotation(),
    )
}

/// The Move generator's segments from `p0` (Grasped): `(action, from, to, name)`.
pub fn move_path(
    task: &Task,
    p0: Transform,
    options: &GeneratorOptions,
) -> Vec<(Action, Transform, Transform, String)> {
    let mut out = Vec::new();
    let target_rot = task.assembled_pose.rotation();
    let turned = Transform::from_parts(p0.translation(), target_rot);
    let rel = target_rot * p0.rotation().inverse();
    if rel.angle() > 1e-9 {
        let about_z = rel.axis().is_some_and(|a| a.z.abs() > 1.0 - 1e-9);
        let action = if about_z {
            Action::RotateTable
        } else {
            Action::RotateProbe
        };
        out.push((action, p0, turned, "P0 orientation".to_string()));
    }
    let up = -task.mating_direction.normalize();
    let b = &task.obstacle_box;
    let mut level = f64::NEG_INFINITY;
    if !b.is_empty() {
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { b.lo.x } else { b.hi.x },
                if i & 2 == 0 { b.lo.y } else { b.hi.y },
                if i & 4 == 0 { b.lo.z } else { b.hi.z },
            );
            level = level.max(up.dot(&c) + options.clearance_mm);
        }
    }
    let p3 = adjusted_pose(task);
    let h0 = up.dot(&turned.translation());
    let h3 = up.dot(&p3.translation());
    let level = level.max(h0).max(h3);
    let p1 = Transform::from_parts(turned.translation() + up * (level - h0), target_rot);
    let p2 = Transform::from_parts(p3.translation() + up * (level - h3), target_rot);
    let points = [(turned, "P0"), (p1, "P1"), (p2, "P2"), (p3, "P3")];
    let mut from = points[0];
    for to in &points[1..] {
        let d = from.0.distance_to(&to.0).1;
        if d < 1e-6 {
            continue;
        }
        let action = if d > options.long_range_mm {
            Action::MoveTable
        } else {
            Action::MoveProbe
        };
        out.push((action, from.0, to.0, format!("{}->{}", from.1, to.1)));
        from = *to;
    }
    out
}

/// A [`SegmentCheck`] against a document: sweeps the task's part (a component of
/// `doc`) from one pose to the other and reports the first component it hits. Place
/// the parts as they are at each step in `doc` (parts not yet assembled out of the
/// way).
pub fn segment_check_fn(
    doc: &crate::document::Document,
) -> impl FnMut(&Task, &Transform, &Transform) -> Result<(), String> + '_ {
    let mut cache = crate::workspace::SceneCache::new();
    move |task, from, to| {
        let ws = crate::workspace::Workspace::new(doc, &mut cache).map_err(|e| e.to_string())?;
        let hit = ws
            .sweep(
                &task.part,
                &crate::collision::Motion::Poses(vec![*from, *to]),
                &crate::collision::SweepOptions::default(),
            )
            .map_err(|e| e.to_string())?;
        if hit.hit {
            let with = hit.with.map_or("?", |i| ws.name(i));
            return Err(format!(
                "the part hits `{with}` at {:.0}% of the segment",
                hit.t * 100.0
            ));
        }
        Ok(())
    }
}
