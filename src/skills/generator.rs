//! Skill generators: from tasks and templates to skill primitives (seed 003, 3.2).
//!
//! Each workflow of a task's template runs its generator from the part's current
//! pose and state. The **Move** generator (Grasped → Adjusted) turns the part to its
//! assembled orientation first, about the grasp point (the seed's rule 1, see
//! [`orientation_turns`]: `Rotate_Table` for a turn about the vertical,
//! `Rotate_Probes` for a turn about the probes' closing axis, one of each when the
//! turn splits into those two), then follows the straight-line path P0 → P1 → P2 →
//! P3 around the obstacle box: up along the approach direction (the negated mating
//! direction) to a level clear of the box, across, and down to P3, the safe length
//! back from the assembled pose. Each segment becomes `Move_Table` (horizontal and
//! longer than [`GeneratorOptions::long_range_mm`]: the table has the large range
//! and no vertical axis) or `Move_Probe` (rule 3), and is checked for interference by
//! the caller's [`SegmentCheck`]. The **screw** generator turns the part about the
//! mating direction while it advances by the pitch per turn ([`screw_pose`]).

use super::{Action, Attribute, Condition, PartState, Skill, Source, Template};
use crate::math::{Point3, Transform, Vec3};
use crate::sequence::Task;
use nalgebra::{Unit, UnitQuaternion};
use std::f64::consts::PI;
use thiserror::Error;

/// Settings of the generators (mm, N).
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratorOptions {
    /// Horizontal segments longer than this go to `Move_Table`, the others to
    /// `Move_Probe` (mm). 50 mm suits an arm's cell; the precision manipulator's
    /// probes reach ±3 mm, so its experiment uses 2 mm.
    pub long_range_mm: f64,
    /// Height above the obstacle box (along the approach direction) of the
    /// crossing segment P1 → P2 (mm).
    pub clearance_mm: f64,
    /// Contact force that ends `Touch` and `Insert` (N).
    pub contact_force_n: f64,
    /// How far `Touch` may travel looking for contact (mm).
    pub touch_distance_mm: f64,
    /// Turns of a `Screw` (the thread's engagement): the last `pitch × turns` mm of
    /// the approach turn, the rest is a straight `Insert`.
    pub screw_turns: f64,
    /// Advance of a screw per turn (mm; > 0). 0.5 mm: an M3 thread.
    pub screw_pitch_mm: f64,
}

impl Default for GeneratorOptions {
    fn default() -> Self {
        Self {
            long_range_mm: 50.0,
            clearance_mm: 20.0,
            contact_force_n: 2.0,
            touch_distance_mm: 10.0,
            screw_turns: 1.0,
            screw_pitch_mm: 0.5,
        }
    }
}

/// Checks one straight segment of the part (poses part frame → world) against the
/// cell; `Err` says what it hits.
pub type SegmentCheck<'a> = dyn FnMut(&Task, &Transform, &Transform) -> Result<(), SegmentHit> + 'a;

/// Why a segment of a part's motion is refused by a [`SegmentCheck`].
#[derive(Debug, Clone, Error)]
#[non_exhaustive]
pub enum SegmentHit {
    /// The part hits a component of the cell.
    #[error("the part hits `{with}` at {:.0}% of the segment", fraction * 100.0)]
    Component {
        /// The component hit.
        with: String,
        /// Where along the segment (0 at its start, 1 at its end).
        fraction: f64,
    },
    /// The segment could not be checked (the cell's geometry, the part's name).
    #[error("the segment cannot be checked: {0}")]
    Unchecked(std::sync::Arc<crate::workspace::WorkspaceError>),
}

/// What is wrong with a task or the generators' settings.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum TaskProblem {
    /// The mating direction is not a unit vector.
    #[error("the mating direction is not a unit vector")]
    MatingDirection,
    /// The safe length is negative or not finite.
    #[error("bad safe length {0}")]
    SafeLength(f64),
    /// A pose (start or assembled) is not finite.
    #[error("a pose is not finite")]
    NotFinite,
    /// The template names a generator that does not exist.
    #[error("unknown generator `{0}`")]
    UnknownGenerator(String),
    /// A generator setting out of its range.
    #[error("`{option}` = {value} (must be {rule})")]
    Option {
        /// The setting.
        option: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        rule: &'static str,
    },
}

/// Why skills cannot be generated.
#[derive(Debug, Error)]
#[non_exhaustive]
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
        reason: SegmentHit,
    },
    /// A task that cannot be used (non-finite values, zero mating direction…).
    #[error("task {task} ({part}): {reason}")]
    BadTask {
        /// Task index.
        task: usize,
        /// Part.
        part: String,
        /// Why.
        reason: TaskProblem,
    },
}

/// `pose` turned by `rotation` (a world rotation) about the point `pivot` (world,
/// mm): the pivot stays where it is.
pub fn turn_about(pose: &Transform, pivot: &Vec3, rotation: &UnitQuaternion<f64>) -> Transform {
    Transform::from_parts(
        pivot + rotation * (pose.translation() - pivot),
        rotation * pose.rotation(),
    )
}

/// The seed's rule 1 (section 3.2): the turns that bring a part held at `grasp`
/// (tool → part) from `p0` to the orientation `target`, about the grasp point,
/// as `(action, rotation)` in order. A turn about the vertical is `Rotate_Table`; a
/// turn about the closing axis (horizontal) is `Rotate_Probes`; a turn that splits
/// into one about the closing axis followed by one about the vertical (the only
/// turns a part held by two probes over a rotary table can make without a regrasp)
/// is both; any other turn is one `Rotate_Probes` about its own axis (an arm's wrist
/// makes it; the precision manipulator refuses it when the plan is bound). Angles
/// below 1e-9 rad are no turn.
pub fn orientation_turns(
    p0: &Transform,
    target: &UnitQuaternion<f64>,
    grasp: Option<&Transform>,
) -> Vec<(Action, UnitQuaternion<f64>)> {
    const EPS: f64 = 1e-9;
    let rel = target * p0.rotation().inverse();
    if rel.angle() <= EPS {
        return vec![];
    }
    if rel.axis().is_some_and(|a| a.z.abs() > 1.0 - EPS) {
        return vec![(Action::RotateTable, rel)];
    }
    if let Some(g) = grasp {
        // The closing axis (the tool's x) in the world at P0.
        let g0 = p0.apply_vector(&g.apply_vector(&Vec3::x()));
        let moved = rel * g0;
        if g0.z.abs() < EPS && moved.z.abs() < 1e-7 {
            let heading = |v: &Vec3| v.y.atan2(v.x);
            let phi = heading(&moved) - heading(&g0);
            let table = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), phi);
            let probes = table.inverse() * rel;
            // `probes` keeps g0 (both keep the closing axis where rel takes it).
            let mut out = Vec::new();
            if probes.angle() > EPS {
                out.push((Action::RotateProbe, probes));
            }
            if table.angle() > EPS {
                out.push((Action::RotateTable, table));
            }
            return out;
        }
    }
    vec![(Action::RotateProbe, rel)]
}

/// The pose a `Screw` ends at: `start` advanced `pitch × turns` along `axis` (unit,
/// world) and turned `2π × turns` about the axis line through the part's origin
/// (right-handed: a positive turn about the direction of advance).
pub fn screw_pose(start: &Transform, axis: &Vec3, pitch: f64, turns: f64) -> Transform {
    screw_pose_at(start, axis, pitch, turns, 1.0)
}

/// The pose of a `Screw` a fraction `s` (0..=1) of the way ([`screw_pose`]).
pub fn screw_pose_at(start: &Transform, axis: &Vec3, pitch: f64, turns: f64, s: f64) -> Transform {
    let a = axis.normalize();
    let turn = UnitQuaternion::from_axis_angle(&Unit::new_unchecked(a), 2.0 * PI * turns * s);
    Transform::from_parts(
        start.translation() + a * (pitch * turns * s),
        turn * start.rotation(),
    )
}

/// The pose of `skill`'s part a fraction `s` (0..=1) of the way from its start to
/// its end, along the motion the skill makes: a screw's helix, a turn about the
/// grasp point `pivot` (world) for `Rotate_Table` / `Rotate_Probes`, else the
/// straight line (translation lerp, rotation slerp).
pub fn skill_pose_at(skill: &Skill, pivot: &Vec3, s: f64) -> Transform {
    let (a, b) = (&skill.start.0, &skill.end.0);
    match skill.action {
        Action::Screw => {
            let d = b.translation() - a.translation();
            match (skill.attribute("turns"), skill.attribute("pitch_mm")) {
                (Some(t), Some(p)) if d.norm() > 1e-12 => screw_pose_at(a, &d, p, t, s),
                _ => a.interpolate(b, s),
            }
        }
        Action::RotateTable | Action::RotateProbe => {
            let rel = b.rotation() * a.rotation().inverse();
            let part = UnitQuaternion::identity()
                .try_slerp(&rel, s, 1e-12)
                .unwrap_or(if s < 0.5 {
                    UnitQuaternion::identity()
                } else {
                    rel
                });
            turn_about(a, pivot, &part)
        }
        _ => a.interpolate(b, s),
    }
}

fn check_options(o: &GeneratorOptions) -> Result<(), TaskProblem> {
    let ge0 = "a finite number ≥ 0";
    for (option, value, rule, ok) in [
        (
            "long_range_mm",
            o.long_range_mm,
            ge0,
            o.long_range_mm >= 0.0,
        ),
        ("clearance_mm", o.clearance_mm, ge0, o.clearance_mm >= 0.0),
        (
            "touch_distance_mm",
            o.touch_distance_mm,
            ge0,
            o.touch_distance_mm >= 0.0,
        ),
        ("screw_turns", o.screw_turns, ge0, o.screw_turns >= 0.0),
        (
            "contact_force_n",
            o.contact_force_n,
            ge0,
            o.contact_force_n >= 0.0,
        ),
        (
            "screw_pitch_mm",
            o.screw_pitch_mm,
            "a finite number > 0",
            o.screw_pitch_mm > 0.0,
        ),
    ] {
        if !(value.is_finite() && ok) {
            return Err(TaskProblem::Option {
                option,
                value,
                rule,
            });
        }
    }
    Ok(())
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
        let bad = |reason: TaskProblem| SkillError::BadTask {
            task: task.index,
            part: task.part.clone(),
            reason,
        };
        check_options(options).map_err(bad)?;
        let m = task.mating_direction;
        if !(m.norm() > 0.5 && m.iter().all(|v| v.is_finite())) {
            return Err(bad(TaskProblem::MatingDirection));
        }
        if !(task.safe_length.is_finite() && task.safe_length >= 0.0) {
            return Err(bad(TaskProblem::SafeLength(task.safe_length)));
        }
        let template = templates
            .iter()
            .find(|t| t.operation == task.operation)
            .cloned()
            .unwrap_or_else(|| super::default_template(task.operation));
        let mut pose = start_pose(&task.part).unwrap_or(task.assembled_pose);
        if !pose.is_finite() || !task.assembled_pose.is_finite() {
            return Err(bad(TaskProblem::NotFinite));
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
            let contact = Condition::Contact {
                force_n: options.contact_force_n,
            };
            let interferes =
                |action: Action, segment: &str, reason: SegmentHit| SkillError::Interference {
                    task: task.index,
                    part: task.part.clone(),
                    action: action.name(),
                    segment: segment.to_string(),
                    reason,
                };
            match w.generator.as_str() {
                "locate" => push(
                    Action::Touch,
                    pose,
                    w.to,
                    vec![attr("distance_mm", options.touch_distance_mm, Source::User)],
                    contact,
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
                    let pivot = task.grasp.as_ref().map(|g| g.tool_in_part.translation());
                    for (action, from, to, segment) in move_path(task, pose, options) {
                        let (r, d) = from.distance_to(&to);
                        let turn = matches!(action, Action::RotateTable | Action::RotateProbe);
                        if turn {
                            // The arc about the grasp point, in pieces of at most 10°
                            // (a sweep between two poses follows the chord).
                            let p = from
                                .apply(&Point3::from(pivot.unwrap_or_else(Vec3::zeros)))
                                .coords;
                            let n = (r / 10f64.to_radians()).ceil().max(1.0) as usize;
                            let probe = Skill {
                                id: 0,
                                task: task.index,
                                part: task.part.clone(),
                                workflow: String::new(),
                                action,
                                attributes: vec![],
                                start: (from, w.from),
                                end: (to, w.from),
                                condition: Condition::Always,
                            };
                            for k in 0..n {
                                let a = skill_pose_at(&probe, &p, k as f64 / n as f64);
                                let b = skill_pose_at(&probe, &p, (k + 1) as f64 / n as f64);
                                check(task, &a, &b).map_err(|r| interferes(action, &segment, r))?;
                            }
                        } else {
                            check(task, &from, &to).map_err(|r| interferes(action, &segment, r))?;
                        }
                        let a = if turn {
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
                "insert" | "align" => {
                    let action = if w.generator == "insert" {
                        Action::Insert
                    } else {
                        Action::MoveProbe
                    };
                    let end = task.assembled_pose;
                    check(task, &pose, &end).map_err(|r| interferes(action, "P3->assembled", r))?;
                    let condition = if action == Action::Insert {
                        contact
                    } else {
                        Condition::Always
                    };
                    let length = attr("length_mm", pose.distance_to(&end).1, Source::Cad);
                    push(action, end, w.to, vec![length], condition, pose);
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
                "screw" => {
                    let end = task.assembled_pose;
                    // The screw is symmetric about its axis: the straight segment is
                    // the swept volume of the turning one.
                    check(task, &pose, &end)
                        .map_err(|r| interferes(Action::Screw, "P3->assembled", r))?;
                    let length = pose.distance_to(&end).1;
                    let pitch = options.screw_pitch_mm;
                    let advance = (pitch * options.screw_turns).min(length);
                    let turns = advance / pitch;
                    let axis = task.mating_direction.normalize();
                    // Up to the thread: a straight push.
                    let engage =
                        Transform::from_parts(end.translation() - axis * advance, end.rotation());
                    if length - advance > 1e-9 {
                        let l = attr("length_mm", length - advance, Source::Cad);
                        push(Action::Insert, engage, w.from, vec![l], contact, pose);
                    }
                    let screwed = screw_pose(&engage, &axis, pitch, turns);
                    push(
                        Action::Screw,
                        screwed,
                        w.to,
                        vec![
                            attr("length_mm", advance, Source::Cad),
                            attr("turns", turns, Source::User),
                            attr("pitch_mm", pitch, Source::User),
                        ],
                        contact,
                        engage,
                    );
                    pose = screwed;
                    push(
                        Action::Release,
                        screwed,
                        w.to,
                        vec![],
                        Condition::PartIn(w.to),
                        screwed,
                    );
                }
                other => return Err(bad(TaskProblem::UnknownGenerator(other.to_string()))),
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

/// Whether a straight segment is horizontal (in the table's plane) to 1e-6 of its
/// length: only such a segment can be a `Move_Table`.
fn horizontal(from: &Transform, to: &Transform) -> bool {
    let d = to.translation() - from.translation();
    d.z.abs() <= 1e-6 * d.norm().max(1.0)
}

/// The Move generator's segments from `p0` (Grasped): `(action, from, to, name)`.
/// The turns of [`orientation_turns`] about the grasp point (the part origin when
/// the task has no grasp), then P0 → P1 → P2 → P3; a horizontal segment longer
/// than `long_range_mm` is `Move_Table`, any other `Move_Probe`.
pub fn move_path(
    task: &Task,
    p0: Transform,
    options: &GeneratorOptions,
) -> Vec<(Action, Transform, Transform, String)> {
    let mut out = Vec::new();
    let target_rot = task.assembled_pose.rotation();
    let grasp = task.grasp.as_ref().map(|g| g.tool_in_part);
    let pivot = match &grasp {
        Some(g) => p0.apply(&Point3::from(g.translation())).coords,
        None => p0.translation(),
    };
    let mut turned = p0;
    for (k, (action, rotation)) in orientation_turns(&p0, &target_rot, grasp.as_ref())
        .into_iter()
        .enumerate()
    {
        let next = turn_about(&turned, &pivot, &rotation);
        out.push((action, turned, next, format!("P0 orientation {}", k + 1)));
        turned = next;
    }
    // Exactly the assembled orientation (the turns' product may differ by rounding).
    let turned = Transform::from_parts(turned.translation(), target_rot);
    if let Some(last) = out.last_mut() {
        last.2 = turned;
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
        let action = if d > options.long_range_mm && horizontal(&from.0, &to.0) {
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
) -> impl FnMut(&Task, &Transform, &Transform) -> Result<(), SegmentHit> + '_ {
    let mut cache = crate::workspace::SceneCache::new();
    move |task, from, to| {
        let ws = crate::workspace::Workspace::new(doc, &mut cache)
            .map_err(|e| SegmentHit::Unchecked(std::sync::Arc::new(e)))?;
        let hit = ws
            .sweep(
                &task.part,
                &crate::collision::Motion::Poses(vec![*from, *to]),
                &crate::collision::SweepOptions::default(),
            )
            .map_err(|e| SegmentHit::Unchecked(std::sync::Arc::new(e)))?;
        if hit.hit {
            return Err(SegmentHit::Component {
                with: hit.with.map_or("?", |i| ws.name(i)).to_string(),
                fraction: hit.t,
            });
        }
        Ok(())
    }
}
