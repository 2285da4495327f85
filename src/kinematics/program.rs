//! Motion programs: seed 001's command files (`Line x y z a b c`, `Circle …`) extended
//! with joint moves, speeds, tool frames and comments; a parser with line-numbered
//! errors and an executor producing one [`Trajectory`].
//!
//! # Syntax (one command per line, keywords case-insensitive)
//! ```text
//! # comment (also "//" as in seed 001); blank lines are ignored
//! Speed 250                      # TCP speed, mm/s
//! JointSpeed 45                  # joint speed, deg/s
//! Interval 0.02                  # sample interval, s
//! Angles xyz                     # X Y Z A B C convention: xyz (default) or zyx
//! Tool 0 0 120 0 0 0             # TCP in the flange frame: mm, deg
//! Joint 0 -30 20 0 45 0          # joint move, deg (mm for prismatic joints)
//! Line 400 0 300 180 0 0         # straight line to the world pose, mm and deg
//! Circle 450 50 300 180 0 0  500 0 300 180 0 0   # arc through a via pose to the end
//! ```

use super::motion::{move_circle_within, move_joint_within, move_line_within, MotionBudget};
use super::{JointKind, MotionError, MotionOptions, Robot, Trajectory};
use crate::math::{AngleConvention, Transform, Vec3};
use std::path::Path;

/// One command of a program (values as written: mm and degrees).
#[derive(Debug, Clone, PartialEq)]
pub enum Instruction {
    /// Straight line to the world pose `x y z a b c` (mm, deg).
    Line([f64; 6]),
    /// Arc through the via pose to the end pose (mm, deg).
    Circle {
        /// Via pose `x y z a b c`.
        via: [f64; 6],
        /// End pose `x y z a b c`.
        end: [f64; 6],
    },
    /// Joint move to the values (deg for revolute joints, mm for prismatic ones).
    Joint(Vec<f64>),
    /// TCP speed (mm/s).
    Speed(f64),
    /// Joint speed (deg/s).
    JointSpeed(f64),
    /// Sample interval (s).
    Interval(f64),
    /// Tool frame `x y z a b c` in the flange frame (mm, deg).
    Tool([f64; 6]),
    /// Angle convention of later poses.
    Angles(AngleConvention),
}

/// A command with its 1-based source line.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramLine {
    /// 1-based line number.
    pub line: usize,
    /// The command.
    pub command: Instruction,
}

/// A parsed program.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Program {
    /// Source name used in messages.
    pub file: String,
    /// Commands in order.
    pub lines: Vec<ProgramLine>,
}

/// A syntax error, with its place.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}:{column}: {cause}")]
pub struct ProgramError {
    /// Source name.
    pub file: String,
    /// 1-based line (0 when the file could not be read).
    pub line: usize,
    /// 1-based column of the offending token.
    pub column: usize,
    /// What is wrong.
    pub cause: String,
}

impl ProgramError {
    /// The file `file` could not be read (line and column 0).
    fn unreadable(file: &str, e: impl std::fmt::Display) -> Self {
        Self {
            file: file.to_string(),
            line: 0,
            column: 0,
            cause: format!("cannot read the file: {e}"),
        }
    }
}

/// A motion error while running a program, with the command's place.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}: {source}")]
pub struct ProgramRunError {
    /// Source name.
    pub file: String,
    /// 1-based line of the failing command.
    pub line: usize,
    /// The motion error.
    pub source: MotionError,
}

/// The most commands a program may hold, counted as its lines are read: a 64 MiB
/// program of `Joint` lines is 3.7 million commands, which took 784 MB before the
/// sample cap ([`crate::math::MAX_SAMPLES`], as many) refused it at its millionth
/// move. At the cap the commands take about 200 bytes each (≈ 200 MB).
pub const MAX_PROGRAM_COMMANDS: usize = crate::math::limits::MAX_SAMPLES;

/// Parses program text; `file` names it in errors. A program of more than
/// [`MAX_PROGRAM_COMMANDS`] commands is refused at the line of the first one past it.
pub fn parse_program(file: &str, text: &str) -> Result<Program, ProgramError> {
    let mut lines = Vec::new();
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let code = raw.split('#').next().unwrap_or("");
        let code = code.split("//").next().unwrap_or("");
        // Tokens with their 1-based columns.
        let mut tokens: Vec<(usize, &str)> = Vec::new();
        let mut start = None;
        for (i, ch) in code
            .char_indices()
            .chain(std::iter::once((code.len(), ' ')))
        {
            if ch.is_whitespace() || ch == ',' {
                if let Some(s) = start.take() {
                    tokens.push((code[..s].chars().count() + 1, &code[s..i]));
                }
            } else if start.is_none() {
                start = Some(i);
            }
        }
        let Some(&(kcol, keyword)) = tokens.first() else {
            continue;
        };
        let err = |column: usize, cause: String| ProgramError {
            file: file.to_string(),
            line,
            column,
            cause,
        };
        let args = &tokens[1..];
        let numbers = |n: Option<usize>| -> Result<Vec<f64>, ProgramError> {
            if let Some(n) = n {
                if args.len() != n {
                    let col = args.get(n).map_or(kcol, |a| a.0);
                    return Err(err(
                        col,
                        format!("{keyword} takes {n} numbers, found {}", args.len()),
                    ));
                }
            }
            args.iter()
                .map(|&(col, tok)| match tok.parse::<f64>() {
                    Ok(v) if v.is_finite() && v.abs() <= crate::math::MAX_ABS_VALUE => Ok(v),
                    Ok(v) if v.is_finite() => Err(err(
                        col,
                        format!("'{tok}' is out of range (magnitude at most 1e9)"),
                    )),
                    _ => Err(err(col, format!("'{tok}' is not a finite number"))),
                })
                .collect()
        };
        let six = |v: &[f64]| [v[0], v[1], v[2], v[3], v[4], v[5]];
        let positive = |v: f64, what: &str| {
            if v > 0.0 {
                Ok(v)
            } else {
                Err(err(
                    args.first().map_or(kcol, |a| a.0),
                    format!("{what} must be positive"),
                ))
            }
        };
        let command = match keyword.to_ascii_lowercase().as_str() {
            "line" => Instruction::Line(six(&numbers(Some(6))?)),
            "circle" => {
                let v = numbers(Some(12))?;
                Instruction::Circle {
                    via: six(&v[..6]),
                    end: six(&v[6..]),
                }
            }
            "joint" => {
                let v = numbers(None)?;
                if v.is_empty() {
                    return Err(err(kcol, "Joint needs one value per joint".into()));
                }
                Instruction::Joint(v)
            }
            "speed" => Instruction::Speed(positive(numbers(Some(1))?[0], "Speed")?),
            "jointspeed" => Instruction::JointSpeed(positive(numbers(Some(1))?[0], "JointSpeed")?),
            "interval" => Instruction::Interval(positive(numbers(Some(1))?[0], "Interval")?),
            "tool" => Instruction::Tool(six(&numbers(Some(6))?)),
            "angles" => {
                let Some(&(col, name)) = args.first() else {
                    return Err(err(kcol, "Angles needs xyz or zyx".into()));
                };
                if args.len() > 1 {
                    return Err(err(args[1].0, "Angles takes one name".into()));
                }
                Instruction::Angles(
                    AngleConvention::parse(name).ok_or_else(|| err(col, format!("unknown angle convention '{name}' (xyz or zyx)")))?,
                )
            }
            other => {
                return Err(err(
                    kcol,
                    format!("unknown command '{other}' (Line, Circle, Joint, Speed, JointSpeed, Interval, Tool, Angles)"),
                ))
            }
        };
        if lines.len() == MAX_PROGRAM_COMMANDS {
            return Err(err(
                kcol,
                format!(
                    "more than {} commands: the most a program may hold (as many as the samples of one program)",
                    crate::math::format::count(MAX_PROGRAM_COMMANDS as u64)
                ),
            ));
        }
        lines.push(ProgramLine { line, command });
    }
    Ok(Program {
        file: file.to_string(),
        lines,
    })
}

/// Reads and parses a program file.
pub fn read_program(path: &Path) -> Result<Program, ProgramError> {
    let name = path.display().to_string();
    let text = crate::fsutil::read_text(path, crate::fsutil::FileKind::Program)
        .map_err(|e| ProgramError::unreadable(&name, e))?;
    parse_program(&name, &text)
}

/// [`read_program`] of a file inside `project` (absolute, as
/// [`crate::project::Project::resolve`] returns it), read through the project's held
/// root folder: a folder swapped for a symbolic link after the path was checked is
/// refused, never followed.
pub fn read_program_in(
    project: &crate::project::Project,
    path: &Path,
) -> Result<Program, ProgramError> {
    let name = project.display(path);
    let text = project
        .read_text(path, crate::fsutil::FileKind::Program)
        .map_err(|e| ProgramError::unreadable(&name, e))?;
    parse_program(&name, &text)
}

fn pose(v: &[f64; 6], conv: AngleConvention) -> Transform {
    Transform::from_xyzabc(
        Vec3::new(v[0], v[1], v[2]),
        [v[3].to_radians(), v[4].to_radians(), v[5].to_radians()],
        conv,
    )
}

/// Runs `program` on `robot` from joint values `start` (rad/mm) with `options` as the
/// initial speeds, returning the whole motion as one trajectory, or the first failing
/// command's line and motion error.
///
/// The samples and IK checks of all moves together are counted against the shared cap
/// ([`MAX_SAMPLES`](crate::math::MAX_SAMPLES)): the move that would pass it fails with
/// [`MotionError::Limit`] at its line, before its samples are made.
pub fn run_program(
    program: &Program,
    robot: &Robot,
    start: &[f64],
    options: &MotionOptions,
) -> Result<Trajectory, ProgramRunError> {
    let mut robot = robot.clone();
    let mut opts = options.clone();
    let mut conv = AngleConvention::default();
    let mut q = start.to_vec();
    let mut traj = Trajectory::new(robot.joint_kinds());
    let mut budget = MotionBudget::new();
    for pl in &program.lines {
        let fail = |source: MotionError| ProgramRunError {
            file: program.file.clone(),
            line: pl.line,
            source,
        };
        let piece = match &pl.command {
            Instruction::Speed(v) => {
                opts.linear_speed = *v;
                continue;
            }
            Instruction::JointSpeed(v) => {
                opts.joint_speed = v.to_radians();
                continue;
            }
            Instruction::Interval(v) => {
                opts.sample_interval = *v;
                continue;
            }
            Instruction::Angles(c) => {
                conv = *c;
                continue;
            }
            Instruction::Tool(t) => {
                robot.set_tool(pose(t, conv));
                continue;
            }
            Instruction::Joint(values) => {
                if values.len() != robot.dof() {
                    return Err(fail(MotionError::Input(
                        super::KinematicsError::JointCount {
                            expected: robot.dof(),
                            got: values.len(),
                        },
                    )));
                }
                let target: Vec<f64> = values
                    .iter()
                    .zip(robot.joint_kinds())
                    .map(|(v, k)| {
                        if k == JointKind::Prismatic {
                            *v
                        } else {
                            v.to_radians()
                        }
                    })
                    .collect();
                move_joint_within(&robot, &q, &target, &opts, &mut budget)
            }
            Instruction::Line(p) => {
                move_line_within(&robot, &q, &pose(p, conv), &opts, &mut budget)
            }
            Instruction::Circle { via, end } => move_circle_within(
                &robot,
                &q,
                &pose(via, conv),
                &pose(end, conv),
                &opts,
                &mut budget,
            ),
        }
        .map_err(fail)?;
        if let Some(last) = piece.last_joints() {
            q = last.to_vec();
        }
        traj.append(piece);
    }
    if traj.samples.is_empty() {
        let tcp = robot.tcp_pose(&q).map_err(|e| ProgramRunError {
            file: program.file.clone(),
            line: 0,
            source: e.into(),
        })?;
        traj.samples.push(super::TrajectorySample {
            t: 0.0,
            joints: q,
            tcp,
        });
    }
    Ok(traj)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Catalog;

    #[test]
    fn parses_every_command_with_comments() {
        let text = "# header\nSpeed 200\nJointSpeed 30 // seed style\n\nTool 0 0 10 0 0 0\nAngles zyx\nInterval 0.1\nJoint 0 0 0 0 45 0\nLine 1 2 3 10 180 0  # to a pose\nCircle 1,2,3,0,0,0 4 5 6 0 0 0\n";
        let p = parse_program("t.prg", text).unwrap();
        assert_eq!(p.lines.len(), 8);
        assert_eq!(
            p.lines[0],
            ProgramLine {
                line: 2,
                command: Instruction::Speed(200.0)
            }
        );
        assert_eq!(
            p.lines[5].command,
            Instruction::Joint(vec![0.0, 0.0, 0.0, 0.0, 45.0, 0.0])
        );
        assert_eq!(p.lines[6].line, 9);
        assert!(matches!(p.lines[7].command, Instruction::Circle { .. }));
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let e = parse_program("a.prg", "Speed 10\n  Line 1 2 x 4 5 6\n").unwrap_err();
        assert_eq!((e.line, e.column), (2, 12));
        assert!(e.to_string().starts_with("a.prg:2:12:"), "{e}");
        let e = parse_program("a.prg", "Line 1 2 3\n").unwrap_err();
        assert_eq!(e.line, 1);
        assert!(e.cause.contains("6 numbers"));
        let e = parse_program("a.prg", "\n\nFly 1 2\n").unwrap_err();
        assert_eq!((e.line, e.column), (3, 1));
        let e = parse_program("a.prg", "Speed -1\n").unwrap_err();
        assert!(e.cause.contains("positive"));
        let e = parse_program("a.prg", "Line 1 2 3 4 5 NaN\n").unwrap_err();
        assert_eq!(e.column, 16);
    }

    #[test]
    fn runs_a_program_into_one_trajectory_and_reports_the_failing_line() {
        let r = Catalog::NachiMz07.robot();
        let q0 = [0.1, -0.2, 0.3, 0.2, 0.6, -0.4];
        let p0 = r
            .tcp_pose(&q0)
            .unwrap()
            .to_xyzabc(AngleConvention::XyzFixed);
        let (x, y, z) = (p0[0], p0[1], p0[2]);
        let (a, b, c) = (p0[3].to_degrees(), p0[4].to_degrees(), p0[5].to_degrees());
        let text = format!(
            "Speed 200\nLine {} {y} {z} {a} {b} {c}\nCircle {} {} {z} {a} {b} {c}  {} {y} {z} {a} {b} {c}\nJointSpeed 90\nJoint 0 0 0 0 30 0\n",
            x + 50.0,
            x + 80.0,
            y + 30.0,
            x + 110.0
        );
        let prog = parse_program("p", &text).unwrap();
        let t = run_program(&prog, &r, &q0, &MotionOptions::default()).unwrap();
        let last = t.last_joints().unwrap();
        assert!((last[4] - 30f64.to_radians()).abs() < 1e-12);
        for w in t.samples.windows(2) {
            assert!(w[1].t > w[0].t);
        }
        let bad = parse_program("p", "Line 5000 0 0 0 0 0\n").unwrap();
        let e = run_program(&bad, &r, &q0, &MotionOptions::default()).unwrap_err();
        assert_eq!(e.line, 1);
        let bad = parse_program("p", "Speed 10\nJoint 1 2\n").unwrap();
        assert_eq!(
            run_program(&bad, &r, &q0, &MotionOptions::default())
                .unwrap_err()
                .line,
            2
        );
    }
}

#[cfg(test)]
mod cap_tests {
    use super::*;
    use crate::kinematics::Catalog;

    /// Two joint moves of 6e5 samples each: each alone fits the cap, the program does
    /// not; the second move's line is named and nothing of it is sampled.
    #[test]
    fn the_cap_is_on_the_whole_program() {
        let r = Catalog::NachiMz07.robot();
        let q0 = [0.0, 0.0, 0.0, 0.0, 0.5, 0.0];
        // 60° at 60°/s = 1 s, at 1e-6 s intervals ≈ 1e6 samples per move.
        let one = parse_program("p.prg", "Interval 0.0000017\nJoint 60 0 0 0 28.6 0\n").unwrap();
        assert!(run_program(&one, &r, &q0, &MotionOptions::default()).is_ok());
        let two = parse_program(
            "p.prg",
            "Interval 0.0000017\nJoint 60 0 0 0 28.6 0\n\nJoint 0 0 0 0 28.6 0\n",
        )
        .unwrap();
        let e = run_program(&two, &r, &q0, &MotionOptions::default()).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        let MotionError::Limit(crate::math::LimitError::TooMany {
            argument,
            count,
            cap,
            ..
        }) = &e.source
        else {
            panic!("{e}")
        };
        assert_eq!((*argument, *cap), ("interval", crate::math::MAX_SAMPLES));
        assert!(*count > 1.1e6, "{e}");
        assert!(
            e.to_string().starts_with("p.prg:4: `interval` = 0.0000017"),
            "{e}"
        );
    }

    /// Tiny IK steps are counted too: a 10 mm line at 1e-9 mm per check is refused
    /// before the first solve.
    #[test]
    fn ik_checks_along_a_line_are_capped() {
        let r = Catalog::NachiMz07.robot();
        let q0 = [0.1, -0.2, 0.3, 0.2, 0.6, -0.4];
        let p0 = r.tcp_pose(&q0).unwrap();
        let end =
            Transform::from_parts(p0.translation() + Vec3::new(10.0, 0.0, 0.0), p0.rotation());
        let options = MotionOptions {
            max_step_mm: 1e-9,
            ..MotionOptions::default()
        };
        let e = super::super::move_line(&r, &q0, &end, &options).unwrap_err();
        assert!(
            matches!(
                &e,
                MotionError::Limit(crate::math::LimitError::TooMany {
                    argument: "max_step_mm",
                    what: "IK checks",
                    ..
                })
            ),
            "{e}"
        );
    }
}

#[cfg(test)]
mod fuzz {
    use super::*;

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(256))]
        /// Arbitrary programs never panic; an error names the file, a line and column
        /// inside the text; accepted numbers are finite and in range.
        #[test]
        fn programs_parse_or_fail_with_a_place(
            lines in proptest::collection::vec(
                (
                    proptest::prop_oneof![
                        proptest::strategy::Just("Line"), proptest::strategy::Just("Circle"),
                        proptest::strategy::Just("Joint"), proptest::strategy::Just("Speed"),
                        proptest::strategy::Just("Interval"), proptest::strategy::Just("Tool"),
                        proptest::strategy::Just("Angles"), proptest::strategy::Just("#"),
                        proptest::strategy::Just("Bogus"), proptest::strategy::Just(""),
                    ],
                    proptest::collection::vec(
                        proptest::prop_oneof![
                            "-?[0-9]{1,4}(\\.[0-9]{1,3})?",
                            proptest::strategy::Just("1e400".to_string()),
                            proptest::strategy::Just("2e9".to_string()),
                            proptest::strategy::Just("nan".to_string()),
                            proptest::strategy::Just("zyx".to_string()),
                            "[ -~]{0,6}",
                        ],
                        0..14,
                    ),
                ),
                0..10,
            ),
        ) {
            let text: String = lines
                .iter()
                .map(|(k, args)| format!("{k} {}\n", args.join(" ")))
                .collect();
            match parse_program("p.prg", &text) {
                Ok(p) => {
                    for l in &p.lines {
                        let nums: Vec<f64> = match &l.command {
                            Instruction::Line(v) | Instruction::Tool(v) => v.to_vec(),
                            Instruction::Circle { via, end } => via.iter().chain(end).copied().collect(),
                            Instruction::Joint(v) => v.clone(),
                            Instruction::Speed(v) | Instruction::JointSpeed(v) | Instruction::Interval(v) => vec![*v],
                            Instruction::Angles(_) => vec![],
                        };
                        proptest::prop_assert!(nums.iter().all(|v| v.is_finite() && v.abs() <= 1e9));
                    }
                }
                Err(e) => {
                    proptest::prop_assert_eq!(e.file.as_str(), "p.prg");
                    proptest::prop_assert!(e.line >= 1 && e.line <= lines.len(), "{}", e);
                    proptest::prop_assert!(e.column >= 1, "{}", e);
                }
            }
        }
    }
}
