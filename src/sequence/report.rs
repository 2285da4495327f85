//! Plain-data views of a sequence plan: JSON (for programs and `fitup plan-sequence
//! --json`), CSV (one row per task) and a text summary for people. Lengths mm,
//! directions unit vectors in the assembly frame, poses `[X, Y, Z, A, B, C]` with the
//! angles in degrees (as everywhere a person reads a pose).

use super::options::{Sequence, SequencePlan};
use super::task::Task;
use crate::math::format::{length as fmt_mm, number};
use crate::math::{AngleConvention, Transform, Vec3};
use serde_json::{json, Value};
use std::io::{self, Write};

fn v3(v: &Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn pose(t: &Transform) -> Value {
    json!(t.to_xyzabc_deg(AngleConvention::default()))
}

fn task_json(t: &Task, s: &super::options::StepInfo) -> Value {
    json!({
        "index": t.index,
        "base": t.base,
        "part": t.part,
        "operation": t.operation.name(),
        "mating_direction": v3(&t.mating_direction),
        "mating_directions": s.mating_directions.iter().map(v3).collect::<Vec<_>>(),
        "receivers": s.receivers,
        "safe_length_mm": t.safe_length,
        "mount": t.mount,
        "direction_change": s.direction_change,
        "planned": s.planned,
        "difficult": s.difficult,
        "path_length_mm": t.path.length_mm,
        "path": t.path.poses.iter().map(pose).collect::<Vec<_>>(),
        "fits": t.fits,
        "slides": t.slides,
        "obstacle_box": {"min": [t.obstacle_box.lo.x, t.obstacle_box.lo.y, t.obstacle_box.lo.z],
                         "max": [t.obstacle_box.hi.x, t.obstacle_box.hi.y, t.obstacle_box.hi.z]},
        "assembled_pose": pose(&t.assembled_pose),
        "base_pose": pose(&t.base_pose),
        "sequence_frame": pose(&t.sequence_frame),
        "grasp": t.grasp.as_ref().map(|g| json!({
            "faces": g.faces,
            "normal": v3(&g.normal),
            "width_mm": g.width,
            "point": v3(&g.point),
            "depth_mm": g.depth,
            "tool_in_part": pose(&g.tool_in_part),
        })),
    })
}

impl Sequence {
    /// The sequence as JSON: base, order, costs and tasks.
    pub fn to_json_value(&self) -> Value {
        json!({
            "base": self.base,
            "order": self.order(),
            "mounts": self.mounts,
            "direction_changes": self.direction_changes,
            "difficult": self.difficult,
            "path_length_mm": self.path_length_mm,
            "tasks": self.tasks.iter().zip(&self.steps).map(|(t, s)| task_json(t, s)).collect::<Vec<_>>(),
        })
    }

    /// One CSV row per task: `index,base,part,operation,mate_x,mate_y,mate_z,
    /// safe_length_mm,mount,planned,path_length_mm,receivers,grasp_faces`
    /// (receivers and faces joined by `+`).
    pub fn write_csv(&self, out: &mut dyn Write) -> io::Result<()> {
        writeln!(
            out,
            "index,base,part,operation,mate_x,mate_y,mate_z,safe_length_mm,mount,planned,path_length_mm,receivers,grasp_faces"
        )?;
        for (t, s) in self.tasks.iter().zip(&self.steps) {
            let faces = t
                .grasp
                .as_ref()
                .map(|g| g.faces.join("+"))
                .unwrap_or_default();
            writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                t.index,
                csv(&t.base),
                csv(&t.part),
                t.operation.name(),
                fmt_num(t.mating_direction.x),
                fmt_num(t.mating_direction.y),
                fmt_num(t.mating_direction.z),
                fmt_num(t.safe_length),
                t.mount,
                s.planned,
                fmt_num(t.path.length_mm),
                csv(&s.receivers.join("+")),
                csv(&faces),
            )?;
        }
        Ok(())
    }

    /// A few lines for people: the order and each task.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "base {}; {} mount(s), {} direction change(s), {} difficult insertion(s), insertion paths {}\n",
            self.base,
            self.mounts,
            self.direction_changes,
            self.difficult,
            fmt_mm(self.path_length_mm)
        );
        for (t, st) in self.tasks.iter().zip(&self.steps) {
            let d = t.mating_direction;
            s += &format!(
                "  {}. {} {} onto {} along ({}, {}, {}), safe length {}{}{}{}\n",
                t.index + 1,
                t.operation.name(),
                t.part,
                if st.receivers.is_empty() {
                    t.base.clone()
                } else {
                    st.receivers.join("+")
                },
                fmt_num(d.x),
                fmt_num(d.y),
                fmt_num(d.z),
                fmt_mm(t.safe_length),
                if t.mount {
                    ", re-mount the base first"
                } else {
                    ""
                },
                if st.planned { ", planned path" } else { "" },
                if st.difficult && !st.planned {
                    ", tight fit"
                } else {
                    ""
                },
            );
        }
        s
    }
}

fn fmt_num(x: f64) -> String {
    number(x, 3)
}

fn csv(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl SequencePlan {
    /// The whole plan as JSON: mode, sequences (best first), rejected orders,
    /// precedence, relation graph, time.
    pub fn to_json_value(&self) -> Value {
        let g = &self.graph;
        json!({
            "mode": self.mode.name(),
            "product": self.product,
            "ranking": self.ranking,
            "sequences": self.sequences.iter().map(|s| s.to_json_value()).collect::<Vec<_>>(),
            "rejected": self.rejected.iter().map(|r| json!({"order": r.order, "reason": r.reason.to_string()})).collect::<Vec<_>>(),
            "precedence": self.precedence.iter().map(|(a, b)| json!([a, b])).collect::<Vec<_>>(),
            "complete": self.complete,
            "fits": self.fits.iter().map(|f| json!({
                "a": f.a, "b": f.b, "depth_mm": f.depth, "contained": f.contained,
            })).collect::<Vec<_>>(),
            "support_gaps": self.support_gaps.iter().map(|g| json!({
                "a": g.a, "b": g.b, "gap_mm": g.gap_mm,
            })).collect::<Vec<_>>(),
            "separate_groups": self.separate_groups,
            "tolerance_mm": self.tolerance,
            "relations": g.relations.iter().map(|r| json!({
                "a": g.components[r.a],
                "b": g.components[r.b],
                "mates": r.mates.len(),
                "freedom": r.freedom.vector(),
                "ones": r.freedom.count(),
            })).collect::<Vec<_>>(),
            "composites": g.nodes.iter().filter(|n| n.is_composite())
                .map(|n| n.members.iter().map(|&m| g.components[m].clone()).collect::<Vec<_>>())
                .collect::<Vec<_>>(),
            "time_ms": self.time_ms,
            "sweeps": self.sweeps,
        })
    }

    /// [`to_json_value`](Self::to_json_value) as pretty text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.to_json_value()).unwrap_or_default()
    }

    /// A text report for people: the best sequence, the others' costs, precedence and
    /// the first rejected orders.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} sequence(s) ({} mode, {:.0} ms{})\n",
            self.sequences.len(),
            self.mode.name(),
            self.time_ms,
            if self.complete {
                ""
            } else {
                ", search cut by its limits"
            }
        );
        for (i, q) in self.sequences.iter().enumerate() {
            if i == 0 {
                s += &format!(
                    "best: {}\n{}{}\n",
                    q.order().join(" → "),
                    q.summary(),
                    self.ranking
                );
            } else {
                s += &format!(
                    "#{}: {} ({} mount(s), {} direction change(s), {} difficult, {})\n",
                    i + 1,
                    q.order().join(" → "),
                    q.mounts,
                    q.direction_changes,
                    q.difficult,
                    fmt_mm(q.path_length_mm)
                );
            }
        }
        if !self.precedence.is_empty() {
            let p: Vec<String> = self
                .precedence
                .iter()
                .map(|(a, b)| format!("{a} < {b}"))
                .collect();
            s += &format!("precedence: {}\n", p.join(", "));
        }
        for f in &self.fits {
            s += &format!(
                "fit: {} {} {} ({} deep in the assembled pose; removal allows that overlap and no other)\n",
                f.a,
                if f.contained { "inside" } else { "and" },
                f.b,
                fmt_mm(f.depth)
            );
        }
        for g in &self.support_gaps {
            s += &match g.gap_mm {
                Some(d) => format!(
                    "held across a gap: {} and {} ({} apart, wider than the contact gap)\n",
                    g.a,
                    g.b,
                    fmt_mm(d)
                ),
                None => format!("held by their mates: {} and {}\n", g.a, g.b),
            };
        }
        for g in &self.separate_groups {
            s += &format!(
                "held by nothing modelled (touches no other group): {}\n",
                g.join(", ")
            );
        }
        for r in self.rejected.iter().take(5) {
            s += &format!("rejected after [{}]: {}\n", r.order.join(", "), r.reason);
        }
        s
    }
}
