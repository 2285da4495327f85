//! Joint and Cartesian motions: `move_joint`, `move_line`, `move_circle`, each sampled
//! into a [`Trajectory`].
//!
//! Cartesian moves keep the inverse-kinematics branch: the path is checked at a fine
//! resolution, every check step takes the solution nearest to the previous one, and
//! the move fails (with the step index and path parameter) when the target becomes
//! unreachable, leaves the joint limits, meets a singularity, changes configuration
//! or makes a joint jump. Speeds are constant over each move (no acceleration ramps).

use super::{
    Configuration, IkError, IkOptions, JointKind, KinematicsError, NumericIk, Robot, Trajectory,
    TrajectorySample,
};
use crate::math::limits::{steps, LimitError, SampleBudget};
use crate::math::{Transform, Vec3};

/// Speeds and resolutions of motions.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionOptions {
    /// Joint speed of joint moves (rad/s; prismatic joints use `linear_speed`).
    pub joint_speed: f64,
    /// TCP speed of Cartesian moves (mm/s).
    pub linear_speed: f64,
    /// TCP reorientation speed of Cartesian moves (rad/s); the slower of the two
    /// decides the duration.
    pub angular_speed: f64,
    /// Time between output samples (s).
    pub sample_interval: f64,
    /// Largest TCP step between two IK checks of a Cartesian move (mm).
    pub max_step_mm: f64,
    /// Largest TCP rotation between two IK checks (rad).
    pub max_step_rad: f64,
    /// Largest joint change allowed between two IK checks (rad or mm); a larger one is
    /// a configuration flip or a singularity and stops the move.
    pub max_joint_jump: f64,
    /// Jacobian conditioning (smallest / largest singular value) under which a jump
    /// is reported as a singularity.
    pub singular_conditioning: f64,
    /// Inverse-kinematics settings.
    pub ik: IkOptions,
}

impl Default for MotionOptions {
    fn default() -> Self {
        Self {
            joint_speed: 60f64.to_radians(),
            linear_speed: 100.0,
            angular_speed: 90f64.to_radians(),
            sample_interval: 0.05,
            max_step_mm: 1.0,
            max_step_rad: 1f64.to_radians(),
            max_joint_jump: 10f64.to_radians(),
            singular_conditioning: 1e-3,
            ik: IkOptions {
                restarts: 4,
                ..IkOptions::default()
            },
        }
    }
}

/// Why a motion cannot be carried out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MotionError {
    /// Bad joint vector.
    #[error(transparent)]
    Input(#[from] KinematicsError),
    /// An option out of its range: speeds and intervals must be positive and finite,
    /// drilling distances finite and not negative, spin samples within their bounds.
    #[error("invalid motion options: {option} = {value} must be {rule}")]
    InvalidOptions {
        /// The option's name as the API spells it (`joint_speed`, `spin_samples`).
        option: &'static str,
        /// The value given (in the option's unit: mm, rad, s, mm/s, rad/s, a count).
        value: f64,
        /// The rule it breaks, for people ("positive and finite").
        rule: &'static str,
    },
    /// The motion (or the whole program or drilling run) would produce more samples
    /// or IK checks than the shared cap, [`MAX_SAMPLES`](crate::math::MAX_SAMPLES).
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// A joint target or start lies outside the limits.
    #[error("joint {joint} value {value:.6} is outside its limits")]
    JointLimit {
        /// 1-based joint number.
        joint: usize,
        /// The value (rad or mm).
        value: f64,
    },
    /// The path cannot be built (e.g. collinear circle points).
    #[error("degenerate path: {0}")]
    Degenerate(#[source] DegeneratePath),
    /// Inverse kinematics failed at a path point.
    #[error("at step {step} (s = {s:.4}): {cause}")]
    Ik {
        /// Index of the check step.
        step: usize,
        /// Path parameter in [0, 1].
        s: f64,
        /// Unreachable, singular or joint limits.
        cause: IkError,
    },
    /// The path passes through or near a singularity.
    #[error("at step {step} (s = {s:.4}): singularity (joint {joint} would jump {jump:.4})")]
    Singular {
        /// Index of the check step.
        step: usize,
        /// Path parameter.
        s: f64,
        /// 1-based joint with the largest jump.
        joint: usize,
        /// Its jump (rad or mm).
        jump: f64,
    },
    /// The nearest solution changed configuration.
    #[error("at step {step} (s = {s:.4}): configuration would change from {from} to {to}")]
    ConfigurationChange {
        /// Index of the check step.
        step: usize,
        /// Path parameter.
        s: f64,
        /// Configuration at the start.
        from: Configuration,
        /// Configuration of the nearest solution.
        to: Configuration,
    },
    /// A joint would jump more than the allowed step.
    #[error("at step {step} (s = {s:.4}): joint {joint} would jump {jump:.4} (max {max:.4})")]
    JointJump {
        /// Index of the check step.
        step: usize,
        /// Path parameter.
        s: f64,
        /// 1-based joint number.
        joint: usize,
        /// Its jump (rad or mm).
        jump: f64,
        /// The allowed jump.
        max: f64,
    },
}

/// Why a Cartesian path cannot be built (the cause of a [`MotionError::Degenerate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DegeneratePath {
    /// A line's end pose has a NaN or an infinity.
    #[error("end pose is not finite")]
    EndNotFinite,
    /// An arc's via or end pose has a NaN or an infinity.
    #[error("via or end pose is not finite")]
    ViaOrEndNotFinite,
    /// An arc's three points do not span a circle.
    #[error("start, via and end points are collinear or coincide")]
    Collinear,
}

pub(crate) fn check_options(o: &MotionOptions) -> Result<(), MotionError> {
    let vals = [
        ("joint_speed", o.joint_speed),
        ("linear_speed", o.linear_speed),
        ("angular_speed", o.angular_speed),
        ("sample_interval", o.sample_interval),
        ("max_step_mm", o.max_step_mm),
        ("max_step_rad", o.max_step_rad),
        ("max_joint_jump", o.max_joint_jump),
    ];
    for (name, v) in vals {
        if !(v.is_finite() && v > 0.0) {
            return Err(MotionError::InvalidOptions {
                option: name,
                value: v,
                rule: "positive and finite",
            });
        }
    }
    Ok(())
}

fn check_joints(robot: &Robot, q: &[f64]) -> Result<(), MotionError> {
    robot.tcp_pose(q)?;
    if let Some(j) = robot.limit_violation(q) {
        return Err(MotionError::JointLimit {
            joint: j + 1,
            value: q[j],
        });
    }
    Ok(())
}

fn sample(robot: &Robot, t: f64, q: Vec<f64>) -> Result<TrajectorySample, MotionError> {
    let tcp = robot.tcp_pose(&q)?;
    Ok(TrajectorySample { t, joints: q, tcp })
}

/// What one call may still produce: output samples and IK checks, each counted
/// against the shared cap ([`MAX_SAMPLES`](crate::math::MAX_SAMPLES)) over the whole
/// call — one motion, or every move of a program or a drilling run.
#[derive(Debug, Clone)]
pub(crate) struct MotionBudget {
    samples: SampleBudget,
    checks: SampleBudget,
}

impl MotionBudget {
    pub(crate) fn new() -> Self {
        Self {
            samples: SampleBudget::new("samples"),
            checks: SampleBudget::new("IK checks"),
        }
    }

    /// Takes `count` IK checks that `argument = value` asked for (drilling's spin
    /// samples).
    pub(crate) fn take_ik_checks(
        &mut self,
        count: f64,
        argument: &'static str,
        value: f64,
    ) -> Result<(), LimitError> {
        self.checks.take(count, argument, value).map(|_| ())
    }

    /// Takes the IK checks of a Cartesian move of `length` mm and `rotation` rad.
    fn take_checks(
        &mut self,
        length: f64,
        rotation: f64,
        options: &MotionOptions,
    ) -> Result<(), LimitError> {
        let (by_mm, by_rad) = (
            steps(length, options.max_step_mm),
            steps(rotation, options.max_step_rad),
        );
        if by_mm >= by_rad {
            self.checks
                .take(by_mm, "max_step_mm", options.max_step_mm)?;
        } else {
            self.checks
                .take(by_rad, "max_step_rad", options.max_step_rad)?;
        }
        Ok(())
    }
}

/// Output times `0, dt, 2dt, …, duration` (the last interval may be shorter), counted
/// against `budget` before they are made.
fn output_times(
    duration: f64,
    dt: f64,
    budget: &mut MotionBudget,
) -> Result<Vec<f64>, MotionError> {
    if duration <= 0.0 {
        budget.samples.take(1.0, "interval", dt)?;
        return Ok(vec![0.0]);
    }
    let n = (duration / dt - 1e-9).ceil().max(1.0);
    let n = budget.samples.take(n + 1.0, "interval", dt)? - 1;
    Ok((0..=n).map(|j| (j as f64 * dt).min(duration)).collect())
}

/// A joint move from `start` to `target` (joint order, rad/mm): every joint moves
/// linearly and all arrive together; the duration is set by the joint that moves most
/// at `joint_speed` (prismatic joints at `linear_speed`).
pub fn move_joint(
    robot: &Robot,
    start: &[f64],
    target: &[f64],
    options: &MotionOptions,
) -> Result<Trajectory, MotionError> {
    move_joint_within(robot, start, target, options, &mut MotionBudget::new())
}

/// [`move_joint`] taking its samples from a caller's budget.
pub(crate) fn move_joint_within(
    robot: &Robot,
    start: &[f64],
    target: &[f64],
    options: &MotionOptions,
    budget: &mut MotionBudget,
) -> Result<Trajectory, MotionError> {
    check_options(options)?;
    check_joints(robot, start)?;
    check_joints(robot, target)?;
    let kinds = robot.joint_kinds();
    let duration = start
        .iter()
        .zip(target)
        .zip(&kinds)
        .map(|((a, b), k)| {
            let speed = if *k == JointKind::Prismatic {
                options.linear_speed
            } else {
                options.joint_speed
            };
            (b - a).abs() / speed
        })
        .fold(0.0, f64::max);
    let mut traj = Trajectory::new(kinds);
    for t in output_times(duration, options.sample_interval, budget)? {
        let s = if duration > 0.0 { t / duration } else { 1.0 };
        let q: Vec<f64> = start
            .iter()
            .zip(target)
            .map(|(a, b)| a + (b - a) * s)
            .collect();
        traj.samples.push(sample(robot, t, q)?);
    }
    Ok(traj)
}

/// Follows the Cartesian path `path(s)`, `s ∈ [0, 1]`, of TCP world poses starting at
/// joint values `start` (whose TCP must be `path(0)`), with the given path length
/// (mm) and total rotation (rad).
fn track(
    robot: &Robot,
    start: &[f64],
    path: &dyn Fn(f64) -> Transform,
    length: f64,
    rotation: f64,
    options: &MotionOptions,
    budget: &mut MotionBudget,
) -> Result<Trajectory, MotionError> {
    check_options(options)?;
    check_joints(robot, start)?;
    let duration = (length / options.linear_speed).max(rotation / options.angular_speed);
    // Both counts before the first IK solve: samples and the checks between them.
    let times = output_times(duration, options.sample_interval, budget)?;
    budget.take_checks(length, rotation, options)?;
    let ik = IkOptions {
        max_solutions: 1,
        ..options.ik.clone()
    };
    // The branch the move must keep: the start's own, or, when the start is singular
    // (its branch is undetermined), the one of the first step.
    let mut start_config = robot
        .inverse(&robot.tcp_pose(start)?, start, &ik)
        .ok()
        .and_then(|s| s.into_iter().next())
        .filter(|s| s.distance < 1e-6)
        .and_then(|s| s.configuration);
    let mut traj = Trajectory::new(robot.joint_kinds());
    traj.samples.push(sample(robot, 0.0, start.to_vec())?);
    let mut q = start.to_vec();
    let mut s_prev = 0.0;
    let mut step = 0usize;
    for t in times.into_iter().skip(1) {
        let s_next = if duration > 0.0 { t / duration } else { 1.0 };
        let ds = s_next - s_prev;
        let sub = ((ds * length / options.max_step_mm).ceil())
            .max((ds * rotation / options.max_step_rad).ceil())
            .max(1.0) as usize;
        for k in 1..=sub {
            step += 1;
            let s = s_prev + ds * k as f64 / sub as f64;
            let target = path(s);
            let sol = robot
                .inverse_nearest(&target, &q, &ik)
                .map_err(|cause| match cause {
                    IkError::Singular(_) => MotionError::Singular {
                        step,
                        s,
                        joint: 0,
                        jump: f64::NAN,
                    },
                    cause => MotionError::Ik { step, s, cause },
                })?;
            let (joint, jump) = sol
                .joints
                .iter()
                .zip(&q)
                .map(|(a, b)| (a - b).abs())
                .enumerate()
                .fold((0, 0.0), |acc, (i, d)| if d > acc.1 { (i, d) } else { acc });
            if jump > options.max_joint_jump {
                let cond = NumericIk::conditioning(robot, &sol.joints)
                    .min(NumericIk::conditioning(robot, &q));
                return Err(if cond < options.singular_conditioning {
                    MotionError::Singular {
                        step,
                        s,
                        joint: joint + 1,
                        jump,
                    }
                } else {
                    MotionError::JointJump {
                        step,
                        s,
                        joint: joint + 1,
                        jump,
                        max: options.max_joint_jump,
                    }
                });
            }
            match (start_config, sol.configuration) {
                (Some(from), Some(to))
                    if from.shoulder != to.shoulder || from.elbow != to.elbow =>
                {
                    return Err(MotionError::ConfigurationChange { step, s, from, to });
                }
                // Joint 5 crossing 0 continuously (the jump check above rules out the
                // half turn of joints 4 and 6 a real wrist flip needs): the arm keeps its
                // branch, only the wrist label follows the sign of joint 5.
                (Some(_), Some(to)) | (None, Some(to)) => start_config = Some(to),
                _ => {}
            }
            q = sol.joints;
        }
        traj.samples.push(sample(robot, t, q.clone())?);
        s_prev = s_next;
    }
    Ok(traj)
}

/// A straight TCP line from the current TCP pose (joint values `start`) to the world
/// pose `end`, orientation interpolated by slerp, at `linear_speed` /
/// `angular_speed`.
pub fn move_line(
    robot: &Robot,
    start: &[f64],
    end: &Transform,
    options: &MotionOptions,
) -> Result<Trajectory, MotionError> {
    move_line_within(robot, start, end, options, &mut MotionBudget::new())
}

/// [`move_line`] taking its samples and IK checks from a caller's budget.
pub(crate) fn move_line_within(
    robot: &Robot,
    start: &[f64],
    end: &Transform,
    options: &MotionOptions,
    budget: &mut MotionBudget,
) -> Result<Trajectory, MotionError> {
    let from = robot.tcp_pose(start)?;
    if !end.is_finite() {
        return Err(MotionError::Degenerate(DegeneratePath::EndNotFinite));
    }
    let (rotation, length) = from.distance_to(end);
    let end = *end;
    track(
        robot,
        start,
        &move |s| from.interpolate(&end, s),
        length,
        rotation,
        options,
        budget,
    )
}

/// A circular arc from the current TCP pose through `via` to `end` (world poses). The
/// position follows the circle through the three points; the orientation slerps from
/// the start to `via`'s orientation (reached at the via point) and on to `end`'s.
pub fn move_circle(
    robot: &Robot,
    start: &[f64],
    via: &Transform,
    end: &Transform,
    options: &MotionOptions,
) -> Result<Trajectory, MotionError> {
    move_circle_within(robot, start, via, end, options, &mut MotionBudget::new())
}

/// [`move_circle`] taking its samples and IK checks from a caller's budget.
pub(crate) fn move_circle_within(
    robot: &Robot,
    start: &[f64],
    via: &Transform,
    end: &Transform,
    options: &MotionOptions,
    budget: &mut MotionBudget,
) -> Result<Trajectory, MotionError> {
    let from = robot.tcp_pose(start)?;
    if !(via.is_finite() && end.is_finite()) {
        return Err(MotionError::Degenerate(DegeneratePath::ViaOrEndNotFinite));
    }
    let (p0, p1, p2) = (from.translation(), via.translation(), end.translation());
    let u = p1 - p0;
    let v = p2 - p0;
    let w = u.cross(&v);
    let wn = w.norm_squared();
    if wn <= 1e-12 * u.norm_squared().max(1e-12) * v.norm_squared().max(1e-12)
        || u.norm() < 1e-9
        || v.norm() < 1e-9
    {
        return Err(MotionError::Degenerate(DegeneratePath::Collinear));
    }
    let center =
        p0 + (v.cross(&w) * u.norm_squared() + w.cross(&u) * v.norm_squared()) / (2.0 * wn);
    let radius = (p0 - center).norm();
    let n = w / wn.sqrt();
    let e1 = (p0 - center) / radius;
    let e2 = n.cross(&e1);
    let angle_of = |p: Vec3| {
        let a = (p - center).dot(&e2).atan2((p - center).dot(&e1));
        if a < 0.0 {
            a + std::f64::consts::TAU
        } else {
            a
        }
    };
    let (th1, th2) = (angle_of(p1), angle_of(p2));
    let s_via = th1 / th2;
    let (via, end) = (*via, *end);
    let path = move |s: f64| {
        let th = th2 * s;
        let p = center + (e1 * th.cos() + e2 * th.sin()) * radius;
        let r = if s <= s_via {
            from.interpolate(&via, if s_via > 0.0 { s / s_via } else { 1.0 })
        } else {
            via.interpolate(&end, (s - s_via) / (1.0 - s_via))
        };
        Transform::from_parts(p, r.rotation())
    };
    let rotation = from.distance_to(&via).0 + via.distance_to(&end).0;
    track(robot, start, &path, radius * th2, rotation, options, budget)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Catalog;
    use crate::math::AngleConvention;

    fn mz07_start() -> (Robot, Vec<f64>) {
        let r = Catalog::NachiMz07.robot();
        (r, vec![0.1, -0.2, 0.3, 0.2, 0.6, -0.4])
    }

    #[test]
    fn joint_move_timing_and_samples() {
        let (r, q0) = mz07_start();
        let mut q1 = q0.clone();
        q1[0] += 0.5;
        q1[2] -= 0.2;
        let o = MotionOptions::default();
        let t = move_joint(&r, &q0, &q1, &o).unwrap();
        assert!((t.duration() - 0.5 / o.joint_speed).abs() < 1e-12);
        assert_eq!(t.samples.first().unwrap().joints, q0);
        assert!(t
            .last_joints()
            .unwrap()
            .iter()
            .zip(&q1)
            .all(|(a, b)| (a - b).abs() < 1e-12));
        for w in t.samples.windows(2) {
            assert!(w[1].t - w[0].t <= o.sample_interval + 1e-12);
        }
        let mut bad = q1.clone();
        bad[4] = 3.0; // joint 5 limit ±120°
        assert!(matches!(
            move_joint(&r, &q0, &bad, &o),
            Err(MotionError::JointLimit { joint: 5, .. })
        ));
    }

    #[test]
    fn line_is_straight_and_keeps_the_branch() {
        let (r, q0) = mz07_start();
        let p0 = r.tcp_pose(&q0).unwrap();
        let end = Transform::from_translation(Vec3::new(0.0, 80.0, -60.0)) * p0;
        let end = Transform::from_parts(
            end.translation(),
            AngleConvention::XyzFixed.rotation(0.1, 0.0, 0.2) * p0.rotation(),
        );
        let o = MotionOptions::default();
        let t = r_line(&r, &q0, &end, &o);
        let (a, b) = (p0.translation(), end.translation());
        for smp in &t.samples {
            let p = smp.tcp.translation();
            // Distance of the TCP from the segment a–b.
            let d = (p - a).cross(&(b - a)).norm() / (b - a).norm();
            assert!(d < 1e-6, "off the line by {d} mm");
        }
        assert!(t.samples.last().unwrap().tcp.approx_eq(&end, 1e-6, 1e-9));
        // 100 mm at linear_speed; the 0.22 rad turn is faster at angular_speed.
        assert!((t.duration() - 100.0 / o.linear_speed).abs() < 1e-9);
        let csv = t.to_csv(AngleConvention::XyzFixed);
        assert!(csv.starts_with(
            "t_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg\n"
        ));
        assert_eq!(csv.lines().count(), t.samples.len() + 1);
    }

    fn r_line(r: &Robot, q0: &[f64], end: &Transform, o: &MotionOptions) -> Trajectory {
        move_line(r, q0, end, o).unwrap()
    }

    #[test]
    fn unreachable_line_reports_step() {
        let (r, q0) = mz07_start();
        let p0 = r.tcp_pose(&q0).unwrap();
        let end = Transform::from_translation(Vec3::new(3000.0, 0.0, 0.0)) * p0;
        match move_line(&r, &q0, &end, &MotionOptions::default()) {
            Err(MotionError::Ik { step, s, .. }) => {
                assert!(step > 1 && s > 0.0 && s < 1.0);
            }
            other => panic!("expected an IK error, got {other:?}"),
        }
    }

    /// IRB 2400: joint 5 passes through 0 on this line (wrist singular). The move keeps
    /// its arm branch, joints 4 and 6 never turn by a large step (no 180° flip), joint 5
    /// changes sign continuously and every sample is on the line.
    #[test]
    fn line_through_wrist_singularity_keeps_the_branch() {
        let r = Catalog::AbbIrb2400.robot();
        let q0 = vec![0.0, 0.2, 0.1, 0.0, 0.3, 0.0];
        let q1 = vec![0.0, 0.2, 0.1, 0.0, -0.3, 0.0];
        let end = r.tcp_pose(&q1).unwrap();
        let o = MotionOptions::default();
        let t = move_line(&r, &q0, &end, &o).unwrap();
        let last = t.last_joints().unwrap();
        assert!(r.tcp_pose(last).unwrap().approx_eq(&end, 1e-6, 1e-9));
        for (a, b) in last.iter().zip(&q1) {
            assert!((a - b).abs() < 1e-6, "{last:?} vs {q1:?}");
        }
        for w in t.samples.windows(2) {
            for j in [3, 4, 5] {
                let d = (w[1].joints[j] - w[0].joints[j]).abs();
                assert!(d < o.max_joint_jump, "joint {} jumps {d}", j + 1);
            }
        }
        assert!(t.samples.iter().any(|s| s.joints[4] > 0.1));
        assert!(t.samples.iter().any(|s| s.joints[4] < -0.1));
    }

    /// A circle and a program whose TCP path turns only joint 5 from +0.3 through 0
    /// (the via point is exactly wrist-singular) to −0.3: every sample keeps joints
    /// 1–4 and 6 (no 180° flip of 4/6), joint 5 goes down monotonically.
    #[test]
    fn circle_and_program_through_wrist_singularity_keep_the_branch() {
        use crate::kinematics::{parse_program, run_program};
        use crate::math::AngleConvention;
        let r = Catalog::AbbIrb2400.robot();
        let q0 = vec![0.4, 0.2, 0.1, 0.5, 0.3, -0.2];
        let at = |q5: f64| {
            let mut q = q0.clone();
            q[4] = q5;
            r.tcp_pose(&q).unwrap()
        };
        let o = MotionOptions::default();
        let check = |t: &Trajectory| {
            let mut prev = f64::INFINITY;
            for s in &t.samples {
                for j in [0, 1, 2, 3, 5] {
                    assert!(
                        (s.joints[j] - q0[j]).abs() < 1e-6,
                        "joint {}: {:?}",
                        j + 1,
                        s.joints
                    );
                }
                assert!(s.joints[4] <= prev + 1e-9);
                prev = s.joints[4];
            }
            assert!((t.last_joints().unwrap()[4] + 0.3).abs() < 1e-6);
        };
        let t = move_circle(&r, &q0, &at(0.0), &at(-0.3), &o).unwrap();
        check(&t);
        // The same path as a program (poses in mm and degrees, fixed X-Y-Z).
        let line = |t: &Transform| {
            let p = t.to_xyzabc(AngleConvention::XyzFixed);
            format!(
                "{} {} {} {} {} {}",
                p[0],
                p[1],
                p[2],
                p[3].to_degrees(),
                p[4].to_degrees(),
                p[5].to_degrees()
            )
        };
        let text = format!("Circle {}   {}\n", line(&at(0.0)), line(&at(-0.3)));
        let program = parse_program("through.prg", &text).unwrap();
        let t = run_program(&program, &r, &q0, &o).unwrap();
        check(&t);
    }

    /// Leaving a wrist singularity along a Cartesian line needs an instantaneous turn of
    /// joints 4 and 6: the move reports the singularity at its first step instead of
    /// jumping; a joint move out of it first makes the line possible.
    #[test]
    fn line_from_a_singular_start_reports_it() {
        let r = Catalog::AbbIrb2400.robot();
        let q0 = vec![0.0; 6]; // joint 5 = 0: axes 4 and 6 aligned
        let p0 = r.tcp_pose(&q0).unwrap();
        let end = Transform::from_translation(Vec3::new(-50.0, 20.0, -80.0)) * p0;
        let o = MotionOptions::default();
        assert!(matches!(
            move_line(&r, &q0, &end, &o),
            Err(MotionError::Singular { step: 1, .. })
        ));
        let q1 = vec![0.0, 0.0, 0.0, 0.0, 0.3, 0.0];
        let j = move_joint(&r, &q0, &q1, &o).unwrap();
        let end =
            Transform::from_translation(Vec3::new(-50.0, 20.0, -80.0)) * r.tcp_pose(&q1).unwrap();
        let t = move_line(&r, j.last_joints().unwrap(), &end, &o).unwrap();
        assert!(t.samples.last().unwrap().tcp.approx_eq(&end, 1e-6, 1e-9));
    }

    #[test]
    fn circle_passes_through_via_and_stays_on_circle() {
        let (r, q0) = mz07_start();
        let p0 = r.tcp_pose(&q0).unwrap();
        let rot = p0.rotation();
        let via = Transform::from_parts(p0.translation() + Vec3::new(40.0, 40.0, 0.0), rot);
        let end = Transform::from_parts(p0.translation() + Vec3::new(80.0, 0.0, 0.0), rot);
        let t = move_circle(&r, &q0, &via, &end, &MotionOptions::default()).unwrap();
        let c = p0.translation() + Vec3::new(40.0, 0.0, 0.0);
        for smp in &t.samples {
            assert!(((smp.tcp.translation() - c).norm() - 40.0).abs() < 1e-6);
        }
        assert!(t.samples.last().unwrap().tcp.approx_eq(&end, 1e-6, 1e-9));
        let min_to_via = t
            .samples
            .iter()
            .map(|s| (s.tcp.translation() - via.translation()).norm())
            .fold(f64::INFINITY, f64::min);
        // Samples are 5 mm apart along the arc (100 mm/s, 0.05 s).
        assert!(min_to_via <= 2.5 + 1e-6, "{min_to_via}");
        let collinear = Transform::from_parts(p0.translation() + Vec3::new(40.0, 0.0, 0.0), rot);
        assert!(matches!(
            move_circle(&r, &q0, &collinear, &end, &MotionOptions::default()),
            Err(MotionError::Degenerate(_))
        ));
    }
}
