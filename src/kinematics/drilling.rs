//! Drilling (seed 001, section 2.2): hole tables, the tool pose for a hole (tool axis
//! opposite the hole normal, free spin about it chosen for reachability and nearness
//! to the current configuration, tool offset compensation) and drilling programs
//! (initial posture, move keeping it, align to the normal, drill, retract).

use super::motion::{move_line_within, MotionBudget};
use super::{IkOptions, MotionError, MotionOptions, Robot, Trajectory};
use crate::math::{Point3, Transform, Vec3};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use std::path::Path;

/// One hole: a position and a unit normal pointing out of the surface (towards the
/// tool), world frame, mm.
#[derive(Debug, Clone, PartialEq)]
pub struct Hole {
    /// Identifier (the table's number column) if the file has one.
    pub id: Option<String>,
    /// Hole position (mm).
    pub position: Point3,
    /// Unit normal.
    pub normal: Vec3,
    /// 1-based line in the source file.
    pub line: usize,
}

impl Hole {
    /// A hole at `position` (mm) drilled along `normal` (any length, in the frame of
    /// `position`; stored as a unit vector). `None` when the normal is zero or not
    /// finite. `line` is the 1-based line of its source, 0 when it has none.
    pub fn new(id: Option<String>, position: Point3, normal: Vec3, line: usize) -> Option<Hole> {
        let normal = normal.try_normalize(1e-12)?;
        normal.iter().all(|c| c.is_finite()).then_some(Hole {
            id,
            position,
            normal,
            line,
        })
    }
}

/// A malformed hole table line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}: {cause}")]
pub struct DrillError {
    /// Source name.
    pub file: String,
    /// 1-based line (0 when the file could not be read).
    pub line: usize,
    /// What is wrong.
    pub cause: String,
}

impl DrillError {
    /// The file `file` could not be read (line 0).
    fn unreadable(file: &str, e: impl std::fmt::Display) -> Self {
        Self {
            file: file.to_string(),
            line: 0,
            cause: format!("cannot read the file: {e}"),
        }
    }
}

/// Which axis of the TCP frame is the drill axis (pointing into the work, opposite the
/// hole normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToolAxis {
    /// The TCP's +X axis, as in seed 001 ("frame 6's X axis opposite the normal").
    #[default]
    X,
    /// The TCP's +Z axis (the usual industrial tool convention).
    Z,
    /// The TCP's −Z axis (a tool frame whose Z points back to the flange, like the
    /// MZ07 tool point of seed 000).
    NegZ,
}

impl std::str::FromStr for ToolAxis {
    type Err = UnknownToolAxis;

    /// `"x"`, `"z"` or `"-z"`, as the scripting API spells them.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "x" => Ok(ToolAxis::X),
            "z" => Ok(ToolAxis::Z),
            "-z" => Ok(ToolAxis::NegZ),
            other => Err(UnknownToolAxis {
                given: other.to_string(),
            }),
        }
    }
}

/// A tool axis name that is not `x`, `z` or `-z`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("tool_axis `{given}`: use \"x\", \"z\" or \"-z\"")]
pub struct UnknownToolAxis {
    /// The name given.
    pub given: String,
}

/// The most spin angles sampled about the drill axis per hole (one every 0.1°).
pub const MAX_SPIN_SAMPLES: usize = 3600;

/// Settings of a drilling program.
#[derive(Debug, Clone, PartialEq)]
pub struct DrillOptions {
    /// The drill axis in the TCP frame.
    pub tool_axis: ToolAxis,
    /// Tool offset compensation: the drill tip in the TCP frame (mm), seed 001's
    /// `(X₀, Y₀, Z₀)`.
    pub compensation: Vec3,
    /// Distance above the hole, along the normal, where the tool aligns (mm).
    pub approach: f64,
    /// Distance along the normal the tool retracts to after drilling (mm).
    pub retract: f64,
    /// Number of spin angles sampled about the drill axis (at least 1).
    pub spin_samples: usize,
    /// Travel posture of steps 1–2 (world rotation of the TCP); `None` keeps the TCP
    /// orientation at the start of each hole. Seed 001 uses `(0, 180°, 0)`.
    pub travel_orientation: Option<UnitQuaternion<f64>>,
    /// Speeds and checks of the motions.
    pub motion: MotionOptions,
}

impl DrillOptions {
    /// Checks every setting: the motion options (see [`MotionOptions`]), approach and
    /// retract distances finite and not negative (mm), a finite compensation, and
    /// `spin_samples` between 1 and [`MAX_SPIN_SAMPLES`]. [`drill_program`] calls it
    /// first; bindings call it to report a bad option before anything runs.
    pub fn validate(&self) -> Result<(), MotionError> {
        super::motion::check_options(&self.motion)?;
        for (option, value) in [("approach", self.approach), ("retract", self.retract)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(MotionError::InvalidOptions {
                    option,
                    value,
                    rule: "finite and not negative (mm)",
                });
            }
        }
        if let Some(value) = self.compensation.iter().copied().find(|v| !v.is_finite()) {
            return Err(MotionError::InvalidOptions {
                option: "compensation",
                value,
                rule: "finite (mm)",
            });
        }
        if !(1..=MAX_SPIN_SAMPLES).contains(&self.spin_samples) {
            return Err(MotionError::InvalidOptions {
                option: "spin_samples",
                value: self.spin_samples as f64,
                rule: "between 1 and 3600",
            });
        }
        Ok(())
    }
}

impl Default for DrillOptions {
    fn default() -> Self {
        Self {
            tool_axis: ToolAxis::X,
            compensation: Vec3::zeros(),
            approach: 50.0,
            retract: 50.0,
            spin_samples: 72,
            travel_orientation: None,
            motion: MotionOptions::default(),
        }
    }
}

/// What happened to one hole.
#[derive(Debug, Clone, PartialEq)]
pub enum HoleOutcome {
    /// Drilled: the chosen spin (rad) and the joint values with the tip in the hole.
    Drilled {
        /// Spin about the drill axis (rad).
        spin: f64,
        /// Joint values at the bottom of the hole.
        joints: Vec<f64>,
    },
    /// Not drilled, and why (which step failed and the cause).
    Unreachable(HoleFailure),
}

/// Why a hole was not drilled (the run goes on with the next hole).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HoleFailure {
    /// No sampled spin has an IK solution at both the approach point and the bottom:
    /// the last spin's IK error.
    #[error("{0}")]
    NoSpin(#[source] super::IkError),
    /// The TCP pose of the joint values the hole starts from cannot be computed.
    #[error("{0}")]
    Start(#[source] super::KinematicsError),
    /// A step of the hole's motion failed.
    #[error("{step}: {source}")]
    Step {
        /// `initial posture`, `move to the approach point`, `align to the normal`,
        /// `drill` or `retract`.
        step: &'static str,
        /// The motion's error.
        #[source]
        source: MotionError,
    },
}

/// The report of one hole.
#[derive(Debug, Clone, PartialEq)]
pub struct HoleReport {
    /// Index of the hole in the input.
    pub index: usize,
    /// The hole's identifier, if any.
    pub id: Option<String>,
    /// Drilled or why not.
    pub outcome: HoleOutcome,
}

/// The result of a drilling program: the motion of every drilled hole in order, and
/// one report per hole.
#[derive(Debug, Clone, PartialEq)]
pub struct DrillReport {
    /// The whole motion.
    pub trajectory: Trajectory,
    /// Per hole, in input order.
    pub holes: Vec<HoleReport>,
}

/// The most holes a hole table may hold, counted as its lines are read: a 64 MiB
/// table of short lines is 4.8 million holes, which took 4.2 GB as a script's array.
/// At the cap the holes take about 100 bytes each (≈ 100 MB).
pub const MAX_HOLES: usize = 1_000_000;

/// Parses a hole table: per line `x y z nx ny nz` or `id x y z nx ny nz` (commas,
/// tabs or spaces), an optional header line, `#` comments. Normals are normalised; a
/// zero or non-finite value is an error naming the line. A table of more than
/// [`MAX_HOLES`] holes is refused at the line of the first hole past it.
pub fn parse_holes(file: &str, text: &str) -> Result<Vec<Hole>, DrillError> {
    let mut holes = Vec::new();
    let mut seen_data = false;
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let code = raw.split('#').next().unwrap_or("").trim();
        if code.is_empty() {
            continue;
        }
        let err = |cause: String| DrillError {
            file: file.to_string(),
            line,
            cause,
        };
        let fields: Vec<&str> = code
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        let (id, nums) = match fields.len() {
            6 => (None, &fields[..]),
            7 => (Some(fields[0].to_string()), &fields[1..]),
            n => {
                return Err(err(format!(
                    "expected 6 values (x y z nx ny nz) or 7 (id first), found {n}"
                )))
            }
        };
        let parsed: Vec<Option<f64>> = nums.iter().map(|s| s.parse::<f64>().ok()).collect();
        if parsed.iter().all(|v| v.is_none()) && !seen_data {
            seen_data = true; // a header
            continue;
        }
        seen_data = true;
        let mut v = [0.0; 6];
        for (k, (p, s)) in parsed.iter().zip(nums).enumerate() {
            match p {
                Some(x) if x.is_finite() && x.abs() <= crate::math::MAX_ABS_VALUE => v[k] = *x,
                _ => {
                    return Err(err(format!(
                        "column {}: '{s}' is not a finite number of magnitude at most 1e9",
                        k + 1 + usize::from(id.is_some())
                    )))
                }
            }
        }
        let hole = Hole::new(
            id,
            Point3::new(v[0], v[1], v[2]),
            Vec3::new(v[3], v[4], v[5]),
            line,
        )
        .ok_or_else(|| err("the normal is zero".into()))?;
        if holes.len() == MAX_HOLES {
            return Err(err(format!(
                "more than {} holes: the most a hole table may hold (split the table)",
                crate::math::format::count(MAX_HOLES as u64)
            )));
        }
        holes.push(hole);
    }
    Ok(holes)
}

/// Reads and parses a hole table file.
pub fn read_holes(path: &Path) -> Result<Vec<Hole>, DrillError> {
    let name = path.display().to_string();
    let text = crate::fsutil::read_text(path, crate::fsutil::FileKind::Table)
        .map_err(|e| DrillError::unreadable(&name, e))?;
    parse_holes(&name, &text)
}

/// [`read_holes`] of a file inside `project` (absolute, as
/// [`crate::project::Project::resolve`] returns it), read through the project's held
/// root folder: a folder swapped for a symbolic link after the path was checked is
/// refused, never followed.
pub fn read_holes_in(
    project: &crate::project::Project,
    path: &Path,
) -> Result<Vec<Hole>, DrillError> {
    let name = project.display(path);
    let text = project
        .read_text(path, crate::fsutil::FileKind::Table)
        .map_err(|e| DrillError::unreadable(&name, e))?;
    parse_holes(&name, &text)
}

/// A rotation whose drill axis (per `axis`) is `dir` (unit), turned by `spin` about it.
fn drill_rotation(dir: &Vec3, axis: ToolAxis, spin: f64) -> UnitQuaternion<f64> {
    // Two unit vectors across dir, chosen stably.
    let (u, w) = crate::math::frame_across(dir);
    // Columns: images of the TCP x, y, z axes.
    let m = match axis {
        ToolAxis::X => Matrix3::from_columns(&[*dir, u, w]),
        ToolAxis::Z => Matrix3::from_columns(&[u, w, *dir]),
        ToolAxis::NegZ => Matrix3::from_columns(&[u, -w, -dir]),
    };
    let base = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
    let local = match axis {
        ToolAxis::X => Vec3::x_axis(),
        ToolAxis::Z => Vec3::z_axis(),
        ToolAxis::NegZ => -Vec3::z_axis(),
    };
    base * UnitQuaternion::from_axis_angle(&local, spin)
}

/// The TCP world pose that puts the drill tip (TCP + `compensation`) at
/// `hole.position + offset·normal` with the drill axis along `−normal`, spun by `spin`
/// radians about it.
pub fn hole_tool_pose(hole: &Hole, spin: f64, offset: f64, options: &DrillOptions) -> Transform {
    let rot = drill_rotation(&(-hole.normal), options.tool_axis, spin);
    let tip = hole.position.coords + hole.normal * offset;
    Transform::from_parts(tip - rot * options.compensation, rot)
}

/// The spin (sampled) whose hole pose is reachable with the solution nearest to `q`,
/// with that solution; or why none is.
fn best_spin(
    robot: &Robot,
    hole: &Hole,
    q: &[f64],
    options: &DrillOptions,
) -> Result<(f64, Vec<f64>), HoleFailure> {
    let n = options.spin_samples.max(1);
    let ik = IkOptions {
        max_solutions: 1,
        ..options.motion.ik.clone()
    };
    let mut best: Option<(f64, f64, Vec<f64>)> = None;
    let mut last_err = super::IkError::Unreachable(super::Unreachable::NoSolution);
    for k in 0..n {
        let spin = -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / n as f64;
        let approach = hole_tool_pose(hole, spin, options.approach, options);
        let bottom = hole_tool_pose(hole, spin, 0.0, options);
        let sol = robot.inverse_nearest(&approach, q, &ik).and_then(|a| {
            robot
                .inverse_nearest(&bottom, &a.joints, &ik)
                .map(|b| (a, b))
        });
        match sol {
            Ok((a, b)) => {
                if best.as_ref().is_none_or(|(d, _, _)| a.distance < *d) {
                    best = Some((a.distance, spin, b.joints));
                }
            }
            Err(e) => last_err = e,
        }
    }
    best.map(|(_, s, j)| (s, j))
        .ok_or(HoleFailure::NoSpin(last_err))
}

/// Drills `holes` in order from joint values `start`: per hole (1) turn to the travel
/// posture, (2) move in a line to the approach point keeping it, (3) align the drill
/// axis with the hole (spin chosen by sampling), (4) drill in to the hole and (5)
/// retract along the normal. A hole that fails is reported with the step and cause and
/// the robot continues from where it was before that hole.
///
/// # Errors
/// A start outside the robot's reach, or a run whose samples, IK checks or spin
/// samples (all holes together) pass the shared cap
/// ([`MAX_SAMPLES`](crate::math::MAX_SAMPLES)): [`MotionError::Limit`].
pub fn drill_program(
    robot: &Robot,
    start: &[f64],
    holes: &[Hole],
    options: &DrillOptions,
) -> Result<DrillReport, MotionError> {
    options.validate()?;
    let mut q = start.to_vec();
    let first = robot.tcp_pose(&q)?;
    let mut traj = Trajectory::new(robot.joint_kinds());
    traj.samples.push(super::TrajectorySample {
        t: 0.0,
        joints: q.clone(),
        tcp: first,
    });
    let mut reports = Vec::with_capacity(holes.len());
    // One budget for the whole run: every hole's moves and spin samples.
    let mut budget = MotionBudget::new();
    for (index, hole) in holes.iter().enumerate() {
        budget.take_ik_checks(
            2.0 * options.spin_samples.max(1) as f64,
            "spin_samples",
            options.spin_samples as f64,
        )?;
        let mut cap: Option<MotionError> = None;
        let outcome = (|| -> Result<(f64, Vec<f64>, Trajectory), HoleFailure> {
            let (spin, _) = best_spin(robot, hole, &q, options)?;
            let here = robot.tcp_pose(&q).map_err(HoleFailure::Start)?;
            let travel_rot = options.travel_orientation.unwrap_or(here.rotation());
            let approach = hole_tool_pose(hole, spin, options.approach, options);
            let bottom = hole_tool_pose(hole, spin, 0.0, options);
            let retract = hole_tool_pose(hole, spin, options.retract, options);
            let steps = [
                (
                    "initial posture",
                    Transform::from_parts(here.translation(), travel_rot),
                ),
                (
                    "move to the approach point",
                    Transform::from_parts(approach.translation(), travel_rot),
                ),
                ("align to the normal", approach),
                ("drill", bottom),
                ("retract", retract),
            ];
            let mut piece = Trajectory::new(robot.joint_kinds());
            let mut cur = q.clone();
            let mut at_bottom = Vec::new();
            for (name, pose) in steps {
                let t = match move_line_within(robot, &cur, &pose, &options.motion, &mut budget) {
                    Ok(t) => t,
                    // The cap ends the whole run; it says nothing about this hole.
                    Err(e @ MotionError::Limit(_)) => {
                        cap = Some(e.clone());
                        return Err(HoleFailure::Step {
                            step: name,
                            source: e,
                        });
                    }
                    Err(source) => return Err(HoleFailure::Step { step: name, source }),
                };
                if let Some(last) = t.last_joints() {
                    cur = last.to_vec();
                }
                if name == "drill" {
                    at_bottom = cur.clone();
                }
                piece.append(t);
            }
            Ok((spin, at_bottom, piece))
        })();
        if let Some(e) = cap {
            return Err(e);
        }
        let outcome = match outcome {
            Ok((spin, joints, piece)) => {
                if let Some(last) = piece.last_joints() {
                    q = last.to_vec();
                }
                traj.append(piece);
                HoleOutcome::Drilled { spin, joints }
            }
            Err(why) => HoleOutcome::Unreachable(why),
        };
        reports.push(HoleReport {
            index,
            id: hole.id.clone(),
            outcome,
        });
    }
    Ok(DrillReport {
        trajectory: traj,
        holes: reports,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Catalog;
    use crate::math::Rng;

    #[test]
    fn parses_tables_with_header_ids_and_errors() {
        let text = "# holes\nid,x,y,z,nx,ny,nz\n1,0,0,0,0,0,2\n2 10 0 5 3 4 0\n";
        let h = parse_holes("h.csv", text).unwrap();
        assert_eq!(h.len(), 2);
        assert_eq!(h[0].id.as_deref(), Some("1"));
        assert!((h[0].normal - Vec3::z()).norm() < 1e-15);
        assert!((h[1].normal - Vec3::new(0.6, 0.8, 0.0)).norm() < 1e-15);
        assert_eq!(h[1].line, 4);
        let e = parse_holes("h.csv", "0 0 0 1 0 0\n1 2 3 0 0 0\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.cause.contains("zero"));
        let e = parse_holes("h.csv", "0 0 0 1 0 0\n1 2 x 0 0 1\n").unwrap_err();
        assert!(e.to_string().starts_with("h.csv:2:"), "{e}");
        assert!(parse_holes("h.csv", "1 2 3\n").is_err());
    }

    #[test]
    fn fig5_table_loads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/holes_fig5.csv");
        let holes = read_holes(&path).unwrap();
        assert_eq!(holes.len(), 10);
        assert_eq!(holes[0].id.as_deref(), Some("684"));
        for h in &holes {
            assert!((h.normal.norm() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn tool_pose_puts_tip_on_hole_with_axis_against_normal() {
        let hole = Hole {
            id: None,
            position: Point3::new(1.0, 2.0, 3.0),
            normal: Vec3::new(0.0, 0.6, 0.8),
            line: 1,
        };
        for axis in [ToolAxis::X, ToolAxis::Z, ToolAxis::NegZ] {
            let o = DrillOptions {
                tool_axis: axis,
                compensation: Vec3::new(5.0, -3.0, 20.0),
                ..DrillOptions::default()
            };
            for spin in [0.0, 1.0, -2.5] {
                let t = hole_tool_pose(&hole, spin, 0.0, &o);
                let tip = t.apply(&Point3::from(o.compensation));
                assert!((tip - hole.position).norm() < 1e-12);
                let local = match axis {
                    ToolAxis::X => Vec3::x(),
                    ToolAxis::Z => Vec3::z(),
                    ToolAxis::NegZ => -Vec3::z(),
                };
                assert!((t.apply_vector(&local) + hole.normal).norm() < 1e-12);
            }
        }
    }

    /// Holes made from reachable poses of the MZ07 are drilled: at the reported joint
    /// values the tip is in the hole with the drill axis against the normal; a hole
    /// far away is reported unreachable and the others still succeed.
    #[test]
    fn drills_reachable_holes_and_reports_the_rest() {
        let r = Catalog::NachiMz07.robot();
        let o = DrillOptions {
            tool_axis: ToolAxis::NegZ,
            compensation: Vec3::new(0.0, 0.0, -10.0),
            approach: 30.0,
            retract: 30.0,
            spin_samples: 24,
            ..DrillOptions::default()
        };
        let mut rng = Rng::new(4);
        let mut holes = Vec::new();
        for i in 0..4 {
            let q = [
                rng.range(-0.5, 0.5),
                rng.range(-0.3, 0.2),
                rng.range(-0.2, 0.3),
                0.0,
                rng.range(0.3, 0.9),
                0.0,
            ];
            let t = r.tcp_pose(&q).unwrap();
            holes.push(Hole {
                id: Some(format!("h{i}")),
                position: t.apply(&Point3::from(o.compensation)),
                normal: t.apply_vector(&Vec3::z()),
                line: i + 1,
            });
        }
        holes.insert(
            2,
            Hole {
                id: Some("far".into()),
                position: Point3::new(5000.0, 0.0, 0.0),
                normal: Vec3::z(),
                line: 9,
            },
        );
        let start = [0.0, 0.0, 0.0, 0.0, 0.5, 0.0];
        let rep = drill_program(&r, &start, &holes, &o).unwrap();
        assert!(matches!(rep.holes[2].outcome, HoleOutcome::Unreachable(_)));
        let mut drilled = 0;
        for (h, rpt) in holes.iter().zip(&rep.holes) {
            if let HoleOutcome::Drilled { joints, .. } = &rpt.outcome {
                drilled += 1;
                let t = r.tcp_pose(joints).unwrap();
                assert!((t.apply(&Point3::from(o.compensation)) - h.position).norm() < 1e-6);
                assert!((t.apply_vector(&-Vec3::z()) + h.normal).norm() < 1e-9);
            }
        }
        assert!(drilled >= 3, "{:?}", rep.holes);
        assert!(rep.trajectory.duration() > 0.0);
    }
}

#[cfg(test)]
mod fuzz {
    use super::*;

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(256))]
        /// Arbitrary tables never panic; an error names the file and a line of it, and
        /// every accepted hole is finite with a unit normal.
        #[test]
        fn hole_tables_parse_or_fail_with_a_line(
            rows in proptest::collection::vec(
                proptest::collection::vec(
                    proptest::prop_oneof![
                        "-?[0-9]{1,4}(\\.[0-9]{1,3})?",
                        proptest::strategy::Just("1e400".to_string()),
                        proptest::strategy::Just("nan".to_string()),
                        proptest::strategy::Just("-1e12".to_string()),
                        "[a-z#,]{1,5}",
                    ],
                    0..9,
                ),
                0..12,
            ),
            sep in proptest::prop_oneof![proptest::strategy::Just(","), proptest::strategy::Just(" ")],
        ) {
            let text: String = rows.iter().map(|r| r.join(sep) + "\n").collect();
            match parse_holes("t.csv", &text) {
                Ok(holes) => {
                    for h in holes {
                        proptest::prop_assert!(h.position.coords.iter().all(|v| v.is_finite()));
                        proptest::prop_assert!((h.normal.norm() - 1.0).abs() < 1e-9);
                        proptest::prop_assert!(h.line >= 1 && h.line <= rows.len());
                    }
                }
                Err(e) => {
                    proptest::prop_assert_eq!(e.file.as_str(), "t.csv");
                    proptest::prop_assert!(e.line >= 1 && e.line <= rows.len().max(1), "{e}");
                }
            }
        }
    }
}
