//! Bindings for the robots of a document: joints, FK/IK, motions, programs, drilling,
//! trajectories. Joint arrays are degrees (mm for prismatic joints); poses are
//! Transforms or `[x, y, z, a, b, c]` (mm, degrees). Every motion moves the robot (and
//! its link components) to the end of the motion.

use super::api::Api;
use super::bind_document::DocHandle;
use super::bind_math::{to_transform, xyzabc_deg};
use super::convert::overwrite_option;
use super::convert::{
    array3, check_keys, err, fail, floats, numbers, numbers_into, opt_num, opt_str, read_options,
    vec3,
};
use super::{Context, ScriptResult};
use crate::document::robot::{
    joints_from_document_in_place, joints_to_document, joints_to_document_iter,
};
use crate::kinematics::{
    drill_program, move_circle, move_joint, move_line, parse_holes, parse_program, run_program,
    DhConvention, DhRow, DrillOptions, Hole, HoleOutcome, IkError, IkOptions, JointLimits,
    MotionOptions, OpwParameters, Robot, Trajectory,
};
use crate::math::{AngleConvention, Transform};
use crate::options::{Drill, Motion};
use rhai::{Array, Dynamic, Map};
use std::sync::Arc;

mod drilling;
mod trajectory;

/// A robot of a document, by index (shares the document with its handle).
#[derive(Clone)]
pub struct RobotHandle {
    pub(super) doc: DocHandle,
    pub(super) index: usize,
}

/// A robot built in a script (`robot_opw`, `robot_dh`), not yet in a document.
#[derive(Clone)]
pub struct RobotModel(Arc<Robot>, Option<std::path::PathBuf>);

/// Per-joint limits from a script array of `[min, max]` (degrees; `[]` = unlimited).
fn limits_arg(v: &Dynamic, n: usize) -> ScriptResult<Vec<Option<JointLimits>>> {
    let arr = v.as_array_ref().map_err(|t| {
        fail(format!(
            "option `limits` must be an array of [min, max], not {t}"
        ))
    })?;
    if arr.len() != n {
        return err(format!(
            "option `limits`: {} entries for {n} joints",
            arr.len()
        ));
    }
    arr.iter()
        .enumerate()
        .map(|(i, l)| {
            if l.as_array_ref().is_ok_and(|a| a.is_empty()) {
                return Ok(None);
            }
            let v = numbers(l, 2, &format!("limits[{i}]"))?;
            if v[0] > v[1] {
                return err(format!("limits[{i}]: min {} > max {}", v[0], v[1]));
            }
            Ok(Some(JointLimits::degrees(v[0], v[1])))
        })
        .collect()
}

/// A sampled motion returned by a robot move.
#[derive(Clone)]
pub struct TrajectoryHandle {
    pub(super) trajectory: Arc<Trajectory>,
    ctx: Arc<Context>,
}

impl RobotHandle {
    /// The robot (kinematics, base, tool; shared, not copied) and its current joints
    /// (rad/mm). The document lock is held only to take the handle.
    pub(super) fn snapshot(&self) -> ScriptResult<(Arc<Robot>, Vec<f64>)> {
        let doc = self.doc.lock()?;
        let r = doc.robot_at(self.index).map_err(fail)?;
        Ok((r.shared_robot(), r.joints().to_vec()))
    }

    /// `f` of the shared robot and its current joints (rad/mm), copied out under the
    /// document lock onto the stack (no allocation for up to [`STACK_JOINTS`] joints);
    /// the lock is not held while `f` runs.
    fn with_joints<R>(&self, f: impl FnOnce(&Robot, &[f64]) -> ScriptResult<R>) -> ScriptResult<R> {
        let mut stack = [0.0; STACK_JOINTS];
        let (robot, heap, n) = {
            let doc = self.doc.lock()?;
            let r = doc.robot_at(self.index).map_err(fail)?;
            let q = r.joints();
            let heap = match stack.get_mut(..q.len()) {
                Some(s) => {
                    s.copy_from_slice(q);
                    None
                }
                None => Some(q.to_vec()),
            };
            (r.shared_robot(), heap, q.len())
        };
        f(&robot, heap.as_deref().unwrap_or(&stack[..n]))
    }

    /// The shared robot alone (no joint copy).
    fn shared(&self) -> ScriptResult<Arc<Robot>> {
        let doc = self.doc.lock()?;
        Ok(doc.robot_at(self.index).map_err(fail)?.shared_robot())
    }

    fn set_joints(&self, q: &[f64]) -> ScriptResult<()> {
        self.doc
            .lock()?
            .set_robot_joints(self.index, q)
            .map_err(fail)
    }

    /// Moves the robot to the end of `t`, streams it when asked, and wraps it.
    fn finish(&self, robot: &Robot, t: Trajectory, stream: bool) -> ScriptResult<TrajectoryHandle> {
        if stream {
            stream_samples(self.doc.context(), robot, &t);
        }
        let view = &self.doc.context().caches.view;
        if view.is_live() {
            view.log_trajectory(&*self.doc.lock()?, self.index, &t);
        }
        if let Some(q) = t.last_joints() {
            self.set_joints(q)?;
        }
        Ok(TrajectoryHandle {
            trajectory: Arc::new(t),
            ctx: self.doc.context().clone(),
        })
    }
}

/// Prints every sample as seed 001's live monitor did: time, joints, TCP.
fn stream_samples(ctx: &Context, robot: &Robot, t: &Trajectory) {
    for s in &t.samples {
        // Numbers for people: 0.001 resolution, no `-0`, no rounding noise.
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| crate::math::format::number(*x, 3))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let j = list(&joints_to_document(robot, &s.joints));
        let p = list(&s.tcp.to_xyzabc_deg(AngleConvention::default()));
        ctx.print(&format!(
            "[{}] t={}s joints=[{j}] tcp=[{p}]",
            robot.name(),
            crate::math::format::number(s.t, 3),
        ));
    }
}

/// Joint values (rad / mm) from a script array of `dof` numbers (degrees / mm): one
/// allocation, converted in place.
fn joints_arg(robot: &Robot, v: &Dynamic, what: &str) -> ScriptResult<Vec<f64>> {
    let mut q = vec![0.0; robot.dof()];
    numbers_into(v, &mut q, what)?;
    joints_from_document_in_place(robot, &mut q);
    Ok(q)
}

/// A script array of joint values (degrees / mm) from rad / mm.
fn joints_out(robot: &Robot, q: &[f64]) -> Dynamic {
    floats(joints_to_document_iter(robot, q))
}

/// Joint arrays of up to this many joints are handled on the stack by the IK bindings.
const STACK_JOINTS: usize = 12;

/// Each joint's unit factor (rad/mm → degrees/mm) for up to [`STACK_JOINTS`] joints:
/// `x.to_degrees()` is `x * (180 / π)` and the factor is `to_degrees(1)` (1 for a
/// prismatic joint), so `v * factor` is [`joints_out`]'s value to the bit.
fn unit_factors(robot: &Robot) -> Option<[f64; STACK_JOINTS]> {
    let dof = robot.dof();
    let ones = [1.0; STACK_JOINTS];
    let mut factor = [1.0; STACK_JOINTS];
    for (f, k) in factor
        .iter_mut()
        .zip(joints_to_document_iter(robot, ones.get(..dof)?))
    {
        *f = k;
    }
    Some(factor)
}

/// Every solution of [`Robot::inverse`] (every branch), the joints in degrees / mm row
/// after row: what `Robot.ik_solutions` returns, made into script arrays only where the
/// script reads a solution (`sols[i]`, `for q in sols`), and what `Robot.ik` makes its
/// array of arrays from. One value for the whole result: on the stack for up to eight
/// 6-joint solutions, one allocation beyond.
#[derive(Clone)]
pub struct IkSolutions {
    dof: usize,
    len: usize,
    inline: [f64; IkSolutions::INLINE],
    heap: Vec<f64>,
}

impl IkSolutions {
    /// Numbers kept inline: every branch of a 6-axis arm without ±360° variants.
    const INLINE: usize = 48;

    fn new(dof: usize) -> Self {
        Self {
            dof,
            len: 0,
            inline: [0.0; Self::INLINE],
            heap: Vec::new(),
        }
    }

    /// Appends one solution (`dof` numbers, degrees / mm).
    fn push(&mut self, row: impl Iterator<Item = f64>) {
        let at = self.len * self.dof;
        let fits = self.heap.is_empty() && at + self.dof <= Self::INLINE;
        if fits {
            for (x, v) in self.inline[at..at + self.dof].iter_mut().zip(row) {
                *x = v;
            }
        } else {
            if self.heap.is_empty() {
                self.heap.extend_from_slice(&self.inline[..at]);
            }
            self.heap.extend(row);
        }
        self.len += 1;
    }

    /// Every number, solution after solution.
    fn numbers(&self) -> &[f64] {
        if self.heap.is_empty() {
            &self.inline[..self.len * self.dof]
        } else {
            &self.heap
        }
    }

    /// Solution `i` (negative counts from the end, as for arrays).
    fn get(&self, i: i64) -> ScriptResult<&[f64]> {
        let k = if i < 0 { i + self.len as i64 } else { i };
        match usize::try_from(k).ok().filter(|&k| k < self.len) {
            Some(k) => Ok(&self.numbers()[k * self.dof..(k + 1) * self.dof]),
            None => err(format!(
                "IK solution index {i} out of range ({} solutions)",
                self.len
            )),
        }
    }

    fn row_value(row: &[f64]) -> Dynamic {
        floats(row.iter().copied())
    }

    /// The script array of joint arrays (`Robot.ik`'s value).
    fn to_array(&self) -> Array {
        if self.dof == 0 {
            return (0..self.len)
                .map(|_| Dynamic::from_array(Array::new()))
                .collect();
        }
        self.numbers()
            .chunks(self.dof)
            .map(Self::row_value)
            .collect()
    }
}

impl IntoIterator for IkSolutions {
    type Item = Dynamic;
    type IntoIter = std::vec::IntoIter<Dynamic>;

    /// `for q in sols`: each solution's joint array, in order.
    fn into_iter(self) -> Self::IntoIter {
        self.to_array().into_iter()
    }
}

/// Every solution of [`Robot::inverse`] (every branch) as [`IkSolutions`], each as
/// [`joints_out`] makes it, written straight from the solver's solutions (no `Vec` per
/// solution, [`Robot::inverse_each`]) with each joint's unit looked up once per call.
fn every_solution(
    robot: &Robot,
    target: &Transform,
    reference: &[f64],
) -> Result<IkSolutions, IkError> {
    let mut out = IkSolutions::new(robot.dof());
    let Some(factor) = unit_factors(robot) else {
        for s in robot.inverse(target, reference, &ik_all())? {
            out.push(joints_to_document_iter(robot, &s.joints));
        }
        return Ok(out);
    };
    robot.inverse_each(target, reference, &ik_all(), |q| {
        out.push(q.iter().zip(&factor).map(|(v, f)| v * f))
    })?;
    Ok(out)
}

/// `Robot.ik` / `Robot.ik_solutions`: every solution for `target`, nearest the robot's
/// current joints first.
fn ik_every(r: &RobotHandle, target: &Transform) -> ScriptResult<IkSolutions> {
    r.with_joints(|robot, q| {
        let sols = every_solution(robot, target, q)
            .map_err(|e| fail(format!("robot `{}`: ik: {e}", robot.name())))?;
        if sols.len == 0 {
            return err(format!(
                "robot `{}`: ik: no solution within the joint limits",
                robot.name()
            ));
        }
        Ok(sols)
    })
}

/// `Robot.ik_near`: the solution nearest `joints` (degrees / mm), read onto the stack.
fn ik_near(r: &RobotHandle, target: &Transform, joints: &Dynamic) -> ScriptResult<Dynamic> {
    let robot = r.shared()?;
    let mut stack = [0.0; STACK_JOINTS];
    let mut heap = Vec::new();
    let reference = match stack.get_mut(..robot.dof()) {
        Some(s) => s,
        None => {
            heap.resize(robot.dof(), 0.0);
            &mut heap[..]
        }
    };
    numbers_into(joints, reference, "joints")?;
    joints_from_document_in_place(&robot, reference);
    let sol = robot
        .inverse_nearest(target, reference, &ik_all())
        .map_err(|e| fail(format!("robot `{}`: ik_near: {e}", robot.name())))?;
    Ok(joints_out(&robot, &sol.joints))
}

/// `RobotModel.ik` / `RobotModel.ik_solutions`: every solution for `target`, nearest
/// all-zero joints first.
fn model_ik_every(robot: &Robot, target: &Transform) -> ScriptResult<IkSolutions> {
    let zero = [0.0; STACK_JOINTS];
    let heap;
    let reference = match zero.get(..robot.dof()) {
        Some(z) => z,
        None => {
            heap = vec![0.0; robot.dof()];
            &heap[..]
        }
    };
    every_solution(robot, target, reference).map_err(|e| fail(format!("ik: {e}")))
}

/// Motion options from a map (the library's [`Motion`] vocabulary: `speed` mm/s,
/// `joint_speed` and `angular_speed` deg/s, `interval` s); returns them with the
/// `stream` flag.
fn motion_options(m: &Map) -> ScriptResult<(MotionOptions, bool)> {
    let o: Motion = read_options(m, &|_| {})?;
    Ok((o.motion_options(), o.stream))
}

fn ik_all() -> IkOptions {
    IkOptions::every_branch()
}

fn options_map(v: &Dynamic, what: &str) -> ScriptResult<Map> {
    v.read_lock::<Map>().map(|m| m.clone()).ok_or_else(|| {
        fail(format!(
            "{what} options must be a map, not {}",
            v.type_name()
        ))
    })
}

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Robot", "A robot of a document (`robots:` in the YAML): a kinematic tree whose links move components. Joint arrays are **degrees** (mm for prismatic joints), in joint order; poses are Transforms or `[x, y, z, a, b, c]` (mm, degrees). Setting `joints`, a joint dimension (`D1@角度1`) or running a motion moves the link components. Motion options: a map of the keys in the motion table below, all optional. Failures (unreachable, singular, joint limits) are script errors that say why and at which step. One call — a motion, a whole program, a whole drilling run — produces at most 1,000,000 samples and as many IK checks (docs/scripting.md \"Caps\"); more is an error naming `interval` (and the program line), before the samples are made.");
    register_robots(api);
    register_ik(api);
    register_models(api, ctx);
    api.options::<Motion>(
        "Motion options (`move_joint`, `move_line`, `move_circle`, `run_program`):",
    );
    api.options::<Drill>("Options of `drill_program`:");
    register_motions(api, ctx);
    drilling::register_drilling(api, ctx);
    trajectory::register_trajectory(api);
}

/// Robot handles of a document: names, joints, joint dimensions, poses of the base, flange and TCP.
fn register_robots(api: &mut Api) {
    api.type_::<RobotHandle>("Robot");
    api.type_::<TrajectoryHandle>("Trajectory");
    api.f(
        "Document.robots() -> array",
        "Names of the robots, in document order.",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(d.lock()?
                .robots()
                .iter()
                .map(|r| Dynamic::from(r.name().to_string()))
                .collect())
        },
    );
    api.f(
        "Document.robot(name: string) -> Robot",
        "A robot by name; a missing name is an error that lists close matches.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<RobotHandle> {
            let index = d.lock()?.robot_index(name).map_err(fail)?;
            Ok(RobotHandle {
                doc: d.clone(),
                index,
            })
        },
    );
    api.get(
        "Robot.name -> string",
        "The robot's name.",
        |r: &mut RobotHandle| -> ScriptResult<String> { Ok(r.snapshot()?.0.name().to_string()) },
    );
    api.get(
        "Robot.dof -> int",
        "Number of joints.",
        |r: &mut RobotHandle| -> ScriptResult<i64> { Ok(r.snapshot()?.0.dof() as i64) },
    );
    api.get(
        "Robot.joints -> array",
        "Current joint values (degrees; mm for prismatic joints).",
        |r: &mut RobotHandle| -> ScriptResult<Dynamic> {
            let (robot, q) = r.snapshot()?;
            Ok(joints_out(&robot, &q))
        },
    );
    api.set(
        "Robot.joints",
        |r: &mut RobotHandle, v: Dynamic| -> ScriptResult<()> {
            let (robot, _) = r.snapshot()?;
            let q = joints_arg(&robot, &v, "joints")?;
            r.set_joints(&q)
        },
    );
    api.get(
        "Robot.limits -> array",
        "Per joint `[min, max]` (degrees or mm), or `[]` for an unlimited joint.",
        |r: &mut RobotHandle| -> ScriptResult<Array> {
            let (robot, _) = r.snapshot()?;
            Ok(robot
                .joint_limits()
                .iter()
                .zip(robot.joint_kinds())
                .map(|(l, k)| match l {
                    None => Dynamic::from_array(Array::new()),
                    Some(l) if k == crate::kinematics::JointKind::Prismatic => {
                        floats([l.min, l.max])
                    }
                    Some(l) => floats([l.min.to_degrees(), l.max.to_degrees()]),
                })
                .collect())
        },
    );
    api.get(
        "Robot.dimensions -> array",
        "Full names of the joints' driving dimensions (`D1@角度1`, …), in joint order.",
        |r: &mut RobotHandle| -> ScriptResult<Array> {
            let doc = r.doc.lock()?;
            Ok(doc.robots()[r.index]
                .dimension_names()
                .into_iter()
                .map(Dynamic::from)
                .collect())
        },
    );
    api.get(
        "Robot.components -> array",
        "Names of the components displaying the links (root first).",
        |r: &mut RobotHandle| -> ScriptResult<Array> {
            let doc = r.doc.lock()?;
            Ok(doc.robots()[r.index]
                .links()
                .iter()
                .filter_map(|l| l.component)
                .map(|c| Dynamic::from(doc.components()[c].name.clone()))
                .collect())
        },
    );
    api.get(
        "Robot.base -> Transform",
        "World pose of the robot's root link (mm).",
        |r: &mut RobotHandle| -> ScriptResult<Transform> { Ok(r.snapshot()?.0.base()) },
    );
    api.set(
        "Robot.base",
        |r: &mut RobotHandle, v: Dynamic| -> ScriptResult<()> {
            let t = to_transform(&v, "base")?;
            r.doc.lock()?.set_robot_base(r.index, t).map_err(fail)
        },
    );
    api.get(
        "Robot.tool -> Transform",
        "The tool centre point in the flange frame (mm).",
        |r: &mut RobotHandle| -> ScriptResult<Transform> { Ok(r.snapshot()?.0.tool()) },
    );
    api.set(
        "Robot.tool",
        |r: &mut RobotHandle, v: Dynamic| -> ScriptResult<()> {
            let t = to_transform(&v, "tool")?;
            r.doc.lock()?.set_robot_tool(r.index, t).map_err(fail)
        },
    );
    api.get(
        "Robot.tcp -> Transform",
        "World pose of the tool centre point at the current joints (mm).",
        |r: &mut RobotHandle| -> ScriptResult<Transform> {
            let (robot, q) = r.snapshot()?;
            robot.tcp_pose(&q).map_err(fail)
        },
    );
    api.f(
        "Robot.fk(joints: array) -> Transform",
        "World pose of the TCP for the joint values (degrees / mm); the robot does not move.",
        |r: &mut RobotHandle, j: Dynamic| -> ScriptResult<Transform> {
            let robot = r.shared()?;
            let q = joints_arg(&robot, &j, "joints")?;
            robot.tcp_pose(&q).map_err(fail)
        },
    );
    api.f(
        "Robot.fk_many(joints: array) -> array",
        "World TCP poses (Transforms, mm) for an array of joint arrays (degrees / mm), computed in one call (one document lock, no per-call overhead); the robot does not move. A bad entry is an error naming its index.",
        |r: &mut RobotHandle, list: Array| -> ScriptResult<Array> {
            let robot = r.shared()?;
            list.iter()
                .enumerate()
                .map(|(i, j)| {
                    // The entry's name is formatted only for an error message.
                    let q = joints_arg(&robot, j, "joints")
                        .or_else(|_| joints_arg(&robot, j, &format!("joints[{i}]")))?;
                    robot
                        .tcp_pose(&q)
                        .map(Dynamic::from)
                        .map_err(|e| fail(format!("fk_many: entry {i}: {e}")))
                })
                .collect()
        },
    );
    api.f(
        "Robot.ik_many(targets: array) -> array",
        "For each world pose in `targets` (Transforms or `[x,y,z,a,b,c]`), the joint solution (degrees) nearest to the previous entry's (the first nearest the current joints), or `()` when the pose has no solution within the limits; one call for thousands of poses. The robot does not move.",
        |r: &mut RobotHandle, list: Array| -> ScriptResult<Array> {
            let targets = list
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    // The entry's name is formatted only for an error message.
                    to_transform(t, "target")
                        .or_else(|_| to_transform(t, &format!("targets[{i}]")))
                })
                .collect::<ScriptResult<Vec<_>>>()?;
            let (robot, q) = r.snapshot()?;
            Ok(robot.inverse_chain(&targets, &q, &IkOptions::default())
                .into_iter()
                .map(|s| s.map_or(Dynamic::UNIT, |s| joints_out(&robot, &s.joints)))
                .collect())
        },
    );
    api.get(
        "Robot.limits_source -> string",
        "Where the joint limits come from: a public source (`ros-industrial/…` file), `unverified: …`, or `\"\"` when the document gave them.",
        |r: &mut RobotHandle| -> ScriptResult<String> {
            Ok(r.shared()?.limits_source().unwrap_or_default().to_string())
        },
    );
    api.f(
        "Robot.link_poses(joints: array) -> array",
        "World pose of every link of the tree (root first) for the joint values (degrees / mm).",
        |r: &mut RobotHandle, j: Dynamic| -> ScriptResult<Array> {
            let (robot, _) = r.snapshot()?;
            let q = joints_arg(&robot, &j, "joints")?;
            Ok(robot
                .link_poses(&q)
                .map_err(fail)?
                .into_iter()
                .map(Dynamic::from)
                .collect())
        },
    );
}

/// Inverse kinematics: every branch, the nearest one, branches with their configuration.
fn register_ik(api: &mut Api) {
    api.f("Robot.ik(target) -> array", "Every joint solution (arrays of degrees) putting the TCP at the world pose `target` (Transform or `[x,y,z,a,b,c]`), within the joint limits (every closed-form branch and the ±360° variants the limits allow), nearest the current joints first. At a wrist singularity (joints 4 and 6 aligned) every branch still comes back with joint 5 exactly at its singular value and joint 4 kept at its current value (joint 6 takes the rest). An unreachable target is an error saying why.", |r: &mut RobotHandle, t: Dynamic| -> ScriptResult<Array> {
        Ok(ik_every(r, &to_transform(&t, "target")?)?.to_array())
    });
    // A Transform target, the usual one: no Dynamic conversion.
    api.overload(
        "Robot.ik(target) -> array",
        |r: &mut RobotHandle, t: Transform| -> ScriptResult<Array> {
            Ok(ik_every(r, &t)?.to_array())
        },
    );
    api.f("Robot.ik_solutions(target) -> IkSolutions", "The solutions of `ik(target)` (the same, in the same order, nearest the current joints first; the same errors) as one `IkSolutions` value whose joint arrays are made only when read: `sols.len`, `sols[i]` (degrees; negative `i` counts from the end), `for q in sols`, `sols.to_array()` (what `ik` returns). The fast form where a script calls IK often and reads few of the solutions (one value instead of an array per solution).", |r: &mut RobotHandle, t: Dynamic| -> ScriptResult<IkSolutions> {
        ik_every(r, &to_transform(&t, "target")?)
    });
    // A Transform target, the usual one: no Dynamic conversion.
    api.overload(
        "Robot.ik_solutions(target) -> IkSolutions",
        |r: &mut RobotHandle, t: Transform| -> ScriptResult<IkSolutions> { ik_every(r, &t) },
    );
    api.f("Robot.ik_near(target, joints: array) -> array", "The joint solution (degrees) for the world pose `target` nearest to `joints` (degrees); the robot does not move.", |r: &mut RobotHandle, t: Dynamic, j: Dynamic| -> ScriptResult<Dynamic> {
        ik_near(r, &to_transform(&t, "target")?, &j)
    });
    // A Transform target, the usual one: no Dynamic conversion.
    api.overload(
        "Robot.ik_near(target, joints: array) -> array",
        |r: &mut RobotHandle, t: Transform, j: Dynamic| -> ScriptResult<Dynamic> {
            ik_near(r, &t, &j)
        },
    );
    api.f("Robot.ik_branches(target) -> array", "Every solution with its configuration: `#{joints, configuration, singular}` (configuration like `front/up/noflip`, or `\"\"` for numeric solutions; `singular` when joints 4 and 6 are at or near alignment).", |r: &mut RobotHandle, t: Dynamic| -> ScriptResult<Array> {
        let (robot, q) = r.snapshot()?;
        let target = to_transform(&t, "target")?;
        let sols = robot.inverse(&target, &q, &ik_all()).map_err(|e| fail(format!("robot `{}`: ik: {e}", robot.name())))?;
        Ok(sols.iter().map(|s| {
            let mut m = Map::new();
            m.insert("joints".into(), joints_out(&robot, &s.joints));
            m.insert("configuration".into(), Dynamic::from(s.configuration.map(|c| c.to_string()).unwrap_or_default()));
            m.insert("singular".into(), Dynamic::from(s.singular));
            Dynamic::from_map(m)
        }).collect())
    });
    register_ik_solutions(api);
}

/// `IkSolutions`, `Robot.ik_solutions`' value: length, indexing, iteration, the array.
fn register_ik_solutions(api: &mut Api) {
    api.type_::<IkSolutions>("IkSolutions");
    api.iterable::<IkSolutions>();
    api.get(
        "IkSolutions.len -> int",
        "Number of solutions (also `sols.len()`).",
        |s: &mut IkSolutions| s.len as i64,
    );
    api.f(
        "IkSolutions.len() -> int",
        "Number of solutions.",
        |s: &mut IkSolutions| s.len as i64,
    );
    api.index_get(
        "IkSolutions[i: int] -> array",
        "Solution `i` (0 the nearest the reference joints), its joints in degrees (mm for prismatic joints); negative `i` counts from the end; out of range is an error.",
        |s: &mut IkSolutions, i: i64| -> ScriptResult<Dynamic> {
            Ok(IkSolutions::row_value(s.get(i)?))
        },
    );
    api.f(
        "IkSolutions.to_array() -> array",
        "Every solution as an array of joint arrays (degrees), what `Robot.ik` returns.",
        |s: &mut IkSolutions| s.to_array(),
    );
    api.f(
        "IkSolutions.to_string() -> string",
        "As the array `to_array()` prints (what `print` and `${sols}` show).",
        |s: &mut IkSolutions| Dynamic::from_array(s.to_array()).to_string(),
    );
    api.overload("to_debug(s: IkSolutions)", |s: &mut IkSolutions| {
        format!("{:?}", Dynamic::from_array(s.to_array()))
    });
}

/// Robot models without a document (catalog, D-H, OPW, URDF) and adding them to a document.
fn register_models(api: &mut Api, ctx: &Arc<Context>) {
    api.type_::<RobotModel>("RobotModel");
    api.f(
        "robot_opw(params: map) -> RobotModel",
        "An ortho-parallel arm from its published OPW parameters (opw_kinematics / ROS-Industrial `opw_parameters_*.yaml` convention, lengths in **mm** — the YAML files give metres): `#{a1, a2, b, c1, c2, c3, c4, offsets, signs, limits, name}`; `offsets` (6 angles, **degrees**) and `signs` (6 × ±1) default to 0 and +1; a joint value q means the geometric angle `sign·q − offset`; `limits` is 6 × `[min, max]` degrees (`[]` unlimited). Upright reference pose: axis 1 = base z, axes 2/3 parallel to y at (a1, b, c1) and (a1, b, c1 + c2), wrist centre at (a1 + a2, b, c1 + c2 + c3), flange c4 above it with z out of the flange. Solved in closed form.",
        |m: Map| -> ScriptResult<RobotModel> {
            check_keys(&m, &["a1", "a2", "b", "c1", "c2", "c3", "c4", "offsets", "signs", "limits", "name"], "robot_opw")?;
            let need = |k: &str| -> ScriptResult<f64> {
                opt_num(&m, k)?.ok_or_else(|| fail(format!("robot_opw: `{k}` is required (mm)")))
            };
            let mut p = OpwParameters::new(need("a1")?, need("a2")?, need("b")?, need("c1")?, need("c2")?, need("c3")?, need("c4")?);
            if let Some(v) = m.get("offsets") {
                let o = numbers(v, 6, "offsets")?;
                p.offsets = std::array::from_fn(|i| o[i].to_radians());
            }
            if let Some(v) = m.get("signs") {
                let o = numbers(v, 6, "signs")?;
                p.signs = std::array::from_fn(|i| o[i]);
            }
            let limits = match m.get("limits") {
                Some(v) => limits_arg(v, 6)?,
                None => vec![None; 6],
            };
            let name = opt_str(&m, "name")?.unwrap_or_else(|| "opw".into());
            let robot = p
                .robot(&name, std::array::from_fn(|i| limits[i]))
                .map_err(|e| fail(format!("robot_opw: {e}")))?;
            Ok(RobotModel(Arc::new(robot), None))
        },
    );
    fn dh_model(rows: &Array, m: &Map) -> ScriptResult<RobotModel> {
        check_keys(
            m,
            &["convention", "base", "tool", "limits", "name"],
            "robot_dh",
        )?;
        let convention = match opt_str(m, "convention")?.as_deref() {
            None | Some("standard") => DhConvention::Standard,
            Some("modified") => DhConvention::Modified,
            Some(o) => {
                return err(format!(
                    "robot_dh: unknown convention `{o}` (standard, modified)"
                ))
            }
        };
        let limits = match m.get("limits") {
            Some(v) => limits_arg(v, rows.len())?,
            None => vec![None; rows.len()],
        };
        let mut dh = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let v = numbers(r, 4, &format!("rows[{i}] ([theta, d, a, alpha])"))?;
            let mut row = DhRow::degrees(v[0], v[1], v[2], v[3]);
            if let Some(l) = limits[i] {
                row = row.with_limits(l);
            }
            dh.push(row);
        }
        let tool = match m.get("tool") {
            Some(t) => to_transform(t, "tool")?,
            None => Transform::IDENTITY,
        };
        let name = opt_str(m, "name")?.unwrap_or_else(|| "dh".into());
        let mut robot = Robot::from_dh(&name, &dh, convention, tool)
            .map_err(|e| fail(format!("robot_dh: {e}")))?;
        if let Some(b) = m.get("base") {
            robot.set_base(to_transform(b, "base")?);
        }
        Ok(RobotModel(Arc::new(robot), None))
    }
    api.f(
        "robot_dh(rows: array, options: map) -> RobotModel",
        "A revolute arm from a D-H table: `rows` are `[theta, d, a, alpha]` per joint (**degrees**, mm; theta is the joint's zero offset); options `#{convention, base, tool, limits, name}`: `convention` `\"standard\"` (default: frame i from i−1 by Rz(θ)·Tz(d)·Tx(a)·Rx(α), as seed 000 table 2) or `\"modified\"` (Craig: Rx(α)·Tx(a)·Rz(θ)·Tz(d)); `base` and `tool` Transforms or `[x,y,z,a,b,c]`; `limits` per joint `[min, max]` degrees.",
        |rows: Array, m: Map| -> ScriptResult<RobotModel> { dh_model(&rows, &m) },
    );
    api.f(
        "robot_dh(rows: array) -> RobotModel",
        "`robot_dh(rows, #{})`: standard D-H, no limits.",
        |rows: Array| -> ScriptResult<RobotModel> { dh_model(&rows, &Map::new()) },
    );
    let c = ctx.clone();
    api.f(
        "load_urdf(path: string) -> RobotModel",
        "A robot from a URDF file (path relative to the project; xacro already expanded): revolute, continuous, prismatic and fixed joints, origins (`xyz` metres → mm, `rpy`), axes, limits. The flange is the end of the chain with the most joints (a fixed `tool0` after the last joint counts). When the geometry is an ortho-parallel arm with a spherical wrist, IK is solved in closed form (`closed_form`, `opw_parameters`). Errors name the file, line and cause.",
        move |path: &str| -> ScriptResult<RobotModel> {
            let full = c.project.resolve(path).map_err(fail)?;
            c.record_read(&full);
            let u = crate::kinematics::read_urdf_in(&c.project, &full, None).map_err(fail)?;
            let source = format!("URDF {}", c.project.display(&full));
            Ok(RobotModel(
                Arc::new(u.robot.with_limits_source(source)),
                Some(full),
            ))
        },
    );
    api.get(
        "RobotModel.opw_parameters -> map",
        "The ortho-parallel parameters detected from the geometry (mm): `#{axis2, upper_arm, forearm, b, signs}` (`axis2` = axis 2 in the arm plane `[x, z]`, `upper_arm` / `forearm` the arm-plane vectors at zero, `b` the lateral offset), or `()` when the robot is not an OPW arm.",
        |r: &mut RobotModel| -> ScriptResult<Dynamic> {
            Ok(match r.0.analytic() {
                None => Dynamic::UNIT,
                Some(s) => {
                    let (p2, u2, u3, b, signs) = s.parameters();
                    let mut m = Map::new();
                    m.insert("axis2".into(), floats(p2));
                    m.insert("upper_arm".into(), floats(u2));
                    m.insert("forearm".into(), floats(u3));
                    m.insert("b".into(), Dynamic::from(b));
                    m.insert("signs".into(), floats(signs));
                    Dynamic::from_map(m)
                }
            })
        },
    );
    api.get(
        "RobotModel.name -> string",
        "The robot's name.",
        |r: &mut RobotModel| -> ScriptResult<String> { Ok(r.0.name().to_string()) },
    );
    api.get(
        "RobotModel.limits_source -> string",
        "Where the joint limits come from (`URDF <file>`, a public source, `unverified: …`, or `\"\"`).",
        |r: &mut RobotModel| -> ScriptResult<String> { Ok(r.0.limits_source().unwrap_or_default().to_string()) },
    );
    api.get(
        "RobotModel.dof -> int",
        "Number of joints.",
        |r: &mut RobotModel| -> ScriptResult<i64> { Ok(r.0.dof() as i64) },
    );
    api.get("RobotModel.closed_form -> bool", "Whether inverse kinematics is solved in closed form (an OPW or UR-type arm detected from the geometry) rather than numerically.", |r: &mut RobotModel| -> ScriptResult<bool> { Ok(r.0.closed_form()) });
    api.get("RobotModel.ik_solver -> string", "Which inverse-kinematics solver the geometry selects: `\"opw\"` (spherical wrist), `\"ur\"` (axes 2-3-4 parallel, offset wrist) or `\"numeric\"`.", |r: &mut RobotModel| -> ScriptResult<String> { Ok(r.0.solver_name().to_string()) });
    api.f(
        "RobotModel.fk(joints: array) -> Transform",
        "World pose of the TCP for the joint values (degrees / mm).",
        |r: &mut RobotModel, j: Dynamic| -> ScriptResult<Transform> {
            let q = joints_arg(&r.0, &j, "joints")?;
            r.0.tcp_pose(&q).map_err(fail)
        },
    );
    api.f(
        "RobotModel.ik(target) -> array",
        "Every joint solution (degrees) for the world pose, nearest to all-zero joints first.",
        |r: &mut RobotModel, t: Dynamic| -> ScriptResult<Array> {
            Ok(model_ik_every(&r.0, &to_transform(&t, "target")?)?.to_array())
        },
    );
    api.overload(
        "RobotModel.ik(target) -> array",
        |r: &mut RobotModel, t: Transform| -> ScriptResult<Array> {
            Ok(model_ik_every(&r.0, &t)?.to_array())
        },
    );
    api.f(
        "RobotModel.ik_solutions(target) -> IkSolutions",
        "The solutions of `ik(target)` as one `IkSolutions` value (see `Robot.ik_solutions`).",
        |r: &mut RobotModel, t: Dynamic| -> ScriptResult<IkSolutions> {
            model_ik_every(&r.0, &to_transform(&t, "target")?)
        },
    );
    api.overload(
        "RobotModel.ik_solutions(target) -> IkSolutions",
        |r: &mut RobotModel, t: Transform| -> ScriptResult<IkSolutions> {
            model_ik_every(&r.0, &t)
        },
    );
    fn add_robot(
        c: &Context,
        d: &DocHandle,
        name: &str,
        model: &RobotModel,
        m: &Map,
    ) -> ScriptResult<RobotHandle> {
        check_keys(m, &["base", "package_path"], "add_robot")?;
        let base = m.get("base").map(|b| to_transform(b, "base")).transpose()?;
        // Folders of other packages (relative to the project), as `package_path:`.
        let mut packages = Vec::new();
        if let Some(list) = m.get("package_path") {
            let list = list.clone().into_array().map_err(|t| {
                fail(format!(
                    "add_robot: package_path must be an array of folders, not {t}"
                ))
            })?;
            for p in list {
                let p = p.into_immutable_string().map_err(|t| {
                    fail(format!(
                        "add_robot: package_path holds folder names, not {t}"
                    ))
                })?;
                packages.push(c.project.resolve(&p).map_err(fail)?);
            }
        }
        let index =
            match &model.1 {
                // A URDF robot brings its link meshes (a `urdf:` entry in the document).
                Some(urdf) => {
                    let packages: Vec<&std::path::Path> =
                        packages.iter().map(|p| p.as_path()).collect();
                    d.lock()?.add_urdf_robot(name, urdf, base, &packages)
                }
                None if !packages.is_empty() => return Err(fail(
                    "add_robot: package_path is for a robot of `load_urdf` (its meshes' packages)",
                )),
                None => d.lock()?.add_robot(name, &model.0, base),
            }
            .map_err(fail)?;
        Ok(RobotHandle {
            doc: d.clone(),
            index,
        })
    }
    let (c1, c2) = (ctx.clone(), ctx.clone());
    api.f(
        "Document.add_robot(name: string, robot: RobotModel, options: map) -> Robot",
        "Adds a robot built with `robot_opw` / `robot_dh` / `load_urdf` to the document under `name`, options `#{base, package_path}` (`base`: world pose of its root, Transform or `[x,y,z,a,b,c]`; `package_path`: for a `load_urdf` robot, folders of the project where `package://NAME/…` meshes of other packages are found, as a document's `package_path:`). Its joints start at 0 (clamped into the limits) with dimensions `D1@角度<n>@<name>`; saving writes it as an explicit tree, or, for a `load_urdf` robot, as a `urdf:` entry whose links' STL meshes become components `<name>:<link>` (shown and checked for interference).",
        move |d: &mut DocHandle, name: &str, model: RobotModel, m: Map| -> ScriptResult<RobotHandle> { add_robot(&c1, d, name, &model, &m) },
    );
    api.f(
        "Document.add_robot(name: string, robot: RobotModel) -> Robot",
        "`add_robot(name, robot, #{})`.",
        move |d: &mut DocHandle, name: &str, model: RobotModel| -> ScriptResult<RobotHandle> {
            add_robot(&c2, d, name, &model, &Map::new())
        },
    );
}

/// Motions (joint, line, circle) and motion programs.
fn register_motions(api: &mut Api, ctx: &Arc<Context>) {
    fn motion<F>(
        r: &RobotHandle,
        opts: Option<&Dynamic>,
        what: &str,
        f: F,
    ) -> ScriptResult<TrajectoryHandle>
    where
        F: FnOnce(&Robot, &[f64], &MotionOptions) -> Result<Trajectory, String>,
    {
        let m = match opts {
            Some(v) => options_map(v, what)?,
            None => Map::new(),
        };
        let (o, stream) = motion_options(&m)?;
        let (robot, q) = r.snapshot()?;
        let t = f(&robot, &q, &o)
            .map_err(|e| fail(format!("robot `{}`: {what}: {e}", robot.name())))?;
        r.finish(&robot, t, stream)
    }
    let mj =
        |r: &mut RobotHandle, j: Dynamic, o: Option<&Dynamic>| -> ScriptResult<TrajectoryHandle> {
            let (robot, _) = r.snapshot()?;
            let target = joints_arg(&robot, &j, "joints")?;
            motion(r, o, "move_joint", |robot, q, o| {
                move_joint(robot, q, &target, o).map_err(|e| e.to_string())
            })
        };
    api.f(
        "Robot.move_joint(joints: array) -> Trajectory",
        "Joint move to the joint values (degrees / mm): all joints arrive together.",
        move |r: &mut RobotHandle, j: Dynamic| mj(r, j, None),
    );
    api.f(
        "Robot.move_joint(joints: array, options: map) -> Trajectory",
        "Joint move with motion options (see the section).",
        move |r: &mut RobotHandle, j: Dynamic, o: Dynamic| mj(r, j, Some(&o)),
    );
    let ml =
        |r: &mut RobotHandle, t: Dynamic, o: Option<&Dynamic>| -> ScriptResult<TrajectoryHandle> {
            let end = to_transform(&t, "target")?;
            motion(r, o, "move_line", |robot, q, o| {
                move_line(robot, q, &end, o).map_err(|e| e.to_string())
            })
        };
    api.f("Robot.move_line(target) -> Trajectory", "Straight TCP line to the world pose (orientation slerped), keeping the configuration; fails at the first unreachable, singular or out-of-limits step.", move |r: &mut RobotHandle, t: Dynamic| ml(r, t, None));
    api.f(
        "Robot.move_line(target, options: map) -> Trajectory",
        "Straight TCP line with motion options.",
        move |r: &mut RobotHandle, t: Dynamic, o: Dynamic| ml(r, t, Some(&o)),
    );
    let mc = |r: &mut RobotHandle,
              v: Dynamic,
              t: Dynamic,
              o: Option<&Dynamic>|
     -> ScriptResult<TrajectoryHandle> {
        let via = to_transform(&v, "via")?;
        let end = to_transform(&t, "target")?;
        motion(r, o, "move_circle", |robot, q, o| {
            move_circle(robot, q, &via, &end, o).map_err(|e| e.to_string())
        })
    };
    api.f(
        "Robot.move_circle(via, target) -> Trajectory",
        "Circular TCP arc through the via pose to the target pose (world, mm/degrees).",
        move |r: &mut RobotHandle, v: Dynamic, t: Dynamic| mc(r, v, t, None),
    );
    api.f(
        "Robot.move_circle(via, target, options: map) -> Trajectory",
        "Circular arc with motion options.",
        move |r: &mut RobotHandle, v: Dynamic, t: Dynamic, o: Dynamic| mc(r, v, t, Some(&o)),
    );

    let c = ctx.clone();
    let rp = move |r: &mut RobotHandle,
                   path: &str,
                   o: Option<&Dynamic>|
          -> ScriptResult<TrajectoryHandle> {
        let full = c.project.resolve(path).map_err(fail)?;
        c.record_read(&full);
        let text = c
            .project
            .read_text(&full, crate::fsutil::FileKind::Program)
            .map_err(|e| fail(format!("{path}: {e}")))?;
        let program = parse_program(&c.project.display(&full), &text).map_err(fail)?;
        motion(r, o, "run_program", |robot, q, o| {
            run_program(&program, robot, q, o).map_err(|e| e.to_string())
        })
    };
    let rp2 = rp.clone();
    api.f("Robot.run_program(path: string) -> Trajectory", "Runs a motion program file (Line/Circle/Joint/Speed/Tool…, see docs/kinematics.md) from the current joints; a syntax or motion error names the file and line. The file is a dependency of the run (watch reruns on its saves).", move |r: &mut RobotHandle, p: &str| rp(r, p, None));
    api.f("Robot.run_program(path: string, options: map) -> Trajectory", "Runs a program file with motion options (the program's own Speed/Interval lines override them).", move |r: &mut RobotHandle, p: &str, o: Dynamic| rp2(r, p, Some(&o)));
}
