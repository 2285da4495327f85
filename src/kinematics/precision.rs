//! Seed 003's two-finger precision manipulator (section 4.1) as a kinematic tree, and
//! the closed-form joint solution its skills need.
//!
//! The machine is a two-stage system: a large-range, lower-precision **XY table**
//! (NSK linear stages, 2 µm) carrying a **rotary table** (Z rotation, a stepper of
//! 0.1°/step) on which the work sits, and above it a small-range, high-precision
//! **probe stage** (the parallel mechanism, 1 µm, moving linearly while its angles
//! stay small) carrying the two **probes** (fingers, on steppers of 0.05°/step) that
//! grasp a part between their tips and can turn it about the line through both tips.
//!
//! As a [`Robot`]: the flange chain is the probe stage (`probe_x`, `probe_y`,
//! `probe_z` prismatic, `probe_r` revolute about the closing axis through the grasp
//! point); the table (`table_x`, `table_y` prismatic, `table_c` revolute about the
//! vertical) and the fingers (`finger_a`, `finger_b`, each tip's distance from the
//! grasp point along the closing axis) are external axes
//! ([`Robot::with_external_axes`]). Joint order: `probe_x, probe_y, probe_z,
//! probe_r, table_x, table_y, table_c, finger_a, finger_b` (mm, rad).
//!
//! Frames: world z up, the table top at z = 0 at the machine's origin. The **work
//! frame** is the rotary table's frame (`table_c`'s link): parts on the table are
//! posed in it. The tool frame sits at the grasp point between the tips, z pointing
//! down (the approach), x along the closing axis (world X).
//!
//! A pose of the part relative to the table is reached by many joint vectors; which
//! axes move is the skill's choice (the seed's rules, in `skills`): [`Free`] says
//! which axes a solve may change, [`PrecisionAxes::solve`] finds them in closed form
//! or says why the pose is out of those axes' reach.

use super::{Joint, JointLimits, KinematicTree, KinematicsError, Link, Robot};
use crate::math::{Point3, Transform, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use thiserror::Error;

/// Catalog name of the machine.
pub const PRECISION_NAME: &str = "precision_2finger";
/// Half stroke of the XY table on each axis (mm): the large range.
pub const TABLE_STROKE: f64 = 50.0;
/// Range of the rotary table (rad): ±2 turns (a stepper with no end stops, cabled
/// for two turns each way).
pub const TABLE_TURN: f64 = 4.0 * PI;
/// Half stroke of the probe stage in X and Y (mm): the small range.
pub const PROBE_STROKE_XY: f64 = 3.0;
/// Half stroke of the probe stage in Z (mm).
pub const PROBE_STROKE_Z: f64 = 10.0;
/// Height of the grasp point above the table top with the probe stage at 0 (mm).
pub const PROBE_HEIGHT: f64 = 10.0;
/// Range of the probes' turn about the closing axis (rad): ±100°.
pub const PROBE_TURN: f64 = 100.0 * PI / 180.0;
/// Largest distance of a probe tip from the grasp point (mm): an opening of 12 mm.
pub const FINGER_OPEN: f64 = 6.0;

/// The two-finger precision manipulator (see the module docs), base at the origin.
pub fn precision_manipulator() -> Result<Robot, KinematicsError> {
    let none = Transform::IDENTITY;
    let p =
        |axis: Vec3, half: f64| Joint::prismatic(axis).with_limits(JointLimits::symmetric(half));
    let links = vec![
        Link::new("base", None, none, Joint::fixed()),
        Link::new("table_x", Some(0), none, p(Vec3::x(), TABLE_STROKE)),
        Link::new("table_y", Some(1), none, p(Vec3::y(), TABLE_STROKE)),
        Link::new(
            "table_c",
            Some(2),
            none,
            Joint::revolute(Vec3::z(), Point3::origin())
                .with_limits(JointLimits::symmetric(TABLE_TURN)),
        ),
        Link::new(
            "probe_x",
            Some(0),
            Transform::from_translation(Vec3::new(0.0, 0.0, PROBE_HEIGHT)),
            p(Vec3::x(), PROBE_STROKE_XY),
        ),
        Link::new("probe_y", Some(4), none, p(Vec3::y(), PROBE_STROKE_XY)),
        Link::new("probe_z", Some(5), none, p(Vec3::z(), PROBE_STROKE_Z)),
        Link::new(
            "probe_r",
            Some(6),
            none,
            Joint::revolute(Vec3::x(), Point3::origin())
                .with_limits(JointLimits::symmetric(PROBE_TURN)),
        ),
        Link::new(
            "finger_a",
            Some(7),
            none,
            Joint::prismatic(-Vec3::x()).with_limits(JointLimits::new(0.0, FINGER_OPEN)),
        ),
        Link::new(
            "finger_b",
            Some(7),
            none,
            Joint::prismatic(Vec3::x()).with_limits(JointLimits::new(0.0, FINGER_OPEN)),
        ),
    ];
    let tree = KinematicTree::new(links)?;
    // Tool z down (the approach), x along the closing axis.
    let tool = Transform::from_parts(
        Vec3::zeros(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI),
    );
    Robot::new(PRECISION_NAME, tree, 7, tool)?
        .with_external_axes(&[1, 2, 3, 8, 9])
        .map(|r| {
            r.with_limits_source(
                "fitup's model of seed 003 §4.1 (ranges chosen for mm-sized parts)",
            )
        })
}

/// Which axes a [`PrecisionAxes::solve`] may move; the others keep their values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Free {
    /// The XY table.
    pub table_xy: bool,
    /// The rotary table.
    pub table_c: bool,
    /// The probe stage in X and Y.
    pub probe_xy: bool,
    /// The probe stage in Z.
    pub probe_z: bool,
    /// The probes' turn about the closing axis.
    pub probe_r: bool,
}

impl Free {
    /// `Move_Table`: the XY table only.
    pub const TABLE: Free = Free {
        table_xy: true,
        table_c: false,
        probe_xy: false,
        probe_z: false,
        probe_r: false,
    };
    /// `Rotate_Table`: the rotary table, the XY table following so that the grasp
    /// point stays where it is.
    pub const TABLE_TURN: Free = Free {
        table_xy: true,
        table_c: true,
        probe_xy: false,
        probe_z: false,
        probe_r: false,
    };
    /// `Move_Probe`, `Insert`: the probe stage in X, Y and Z.
    pub const PROBES: Free = Free {
        table_xy: false,
        table_c: false,
        probe_xy: true,
        probe_z: true,
        probe_r: false,
    };
    /// `Rotate_Probes`: the probes' turn (the stage may follow).
    pub const PROBE_TURN: Free = Free {
        table_xy: false,
        table_c: false,
        probe_xy: true,
        probe_z: true,
        probe_r: true,
    };
    /// `Screw`: the rotary table turns the work about the screw axis (the XY table
    /// following) while the probe stage advances in Z.
    pub const SCREW: Free = Free {
        table_xy: true,
        table_c: true,
        probe_xy: false,
        probe_z: true,
        probe_r: false,
    };
    /// `Grasp`: the table brings the part under the probes (XY and C), the probes
    /// come down and turn to it; the probe stage's X and Y stay.
    pub const GRASP: Free = Free {
        table_xy: true,
        table_c: true,
        probe_xy: false,
        probe_z: true,
        probe_r: true,
    };
}

/// The joint indices of a precision manipulator's axes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrecisionAxes {
    /// Probe stage X, Y, Z (mm).
    pub probe: [usize; 3],
    /// The probes' turn (rad).
    pub probe_r: usize,
    /// XY table X, Y (mm).
    pub table: [usize; 2],
    /// Rotary table (rad).
    pub table_c: usize,
    /// The two fingers: each tip's distance from the grasp point (mm).
    pub fingers: [usize; 2],
    /// Grasp point at probe 0, in the base frame (mm).
    probe_home: Vec3,
}

/// Why a robot is not a precision manipulator of the catalog's layout.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum NotPrecision {
    /// A link the layout needs is not a joint of the robot.
    #[error("no joint `{0}`")]
    MissingJoint(&'static str),
    /// A joint of the layout has another axis, point, parent or home.
    #[error("joint `{0}` is not placed as the precision manipulator's")]
    Layout(&'static str),
}

/// Why a pose is out of reach of the axes a skill may move.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum PrecisionError {
    /// The tool's closing axis would have to leave the horizontal: the probes turn
    /// only about it and the table only about the vertical.
    #[error("the closing axis is {tilt_rad:.3e} rad off the horizontal: no turn of the table and the probes gives that orientation (regrasp)")]
    Tilted {
        /// The closing axis's angle to the horizontal (rad).
        tilt_rad: f64,
    },
    /// The pose needs an axis the skill may not move.
    #[error("{axis} would have to move by {amount:.4} (mm or rad) and the skill does not move it")]
    Needs {
        /// The axis (`table_x`, `probe_z`, …) or `orientation`.
        axis: &'static str,
        /// How far (mm or rad).
        amount: f64,
    },
    /// A joint would leave its limits.
    #[error("joint `{joint}` = {value:.4} is outside its limits [{min:.4}, {max:.4}]")]
    Limit {
        /// The joint's link name.
        joint: String,
        /// The value (mm or rad).
        value: f64,
        /// Lower limit.
        min: f64,
        /// Upper limit.
        max: f64,
    },
    /// Joints or a pose that are not finite, or of the wrong count.
    #[error("the joints or the target are not finite or of the wrong count")]
    BadInput,
}

/// Angle `a` moved by whole turns to lie within π of `near`.
fn unwrap_near(a: f64, near: f64) -> f64 {
    near + (a - near + PI).rem_euclid(2.0 * PI) - PI
}

/// Tolerance of the closed-form checks (mm and rad).
const EXACT: f64 = 1e-7;

impl PrecisionAxes {
    /// The axes of `robot`, when it has the catalog machine's layout (any base and
    /// tool frame, any limits).
    ///
    /// # Errors
    /// The first joint missing or placed otherwise.
    pub fn detect(robot: &Robot) -> Result<Self, NotPrecision> {
        let tree = robot.tree();
        let joint = |name: &'static str| -> Result<usize, NotPrecision> {
            let link = tree.find(name).ok_or(NotPrecision::MissingJoint(name))?;
            robot
                .joint_links()
                .iter()
                .position(|&l| l == link)
                .ok_or(NotPrecision::MissingJoint(name))
        };
        let names = [
            "probe_x", "probe_y", "probe_z", "probe_r", "table_x", "table_y", "table_c",
            "finger_a", "finger_b",
        ];
        let mut j = [0usize; 9];
        for (k, n) in names.iter().enumerate() {
            j[k] = joint(n)?;
        }
        let links = tree.links();
        let link = |k: usize| &links[robot.joint_links()[j[k]]];
        let parent_name = |k: usize| {
            link(k)
                .parent
                .and_then(|p| links[p].name.as_deref())
                .unwrap_or("")
        };
        let pure = |t: &Transform| t.rotation().angle() < 1e-12;
        let axis_is = |k: usize, v: Vec3| (link(k).joint.axis - v).norm() < 1e-12;
        let at_origin = |k: usize| link(k).joint.point.coords.norm() < 1e-12;
        let identity = |k: usize| link(k).home.approx_eq(&Transform::IDENTITY, 1e-12, 1e-12);
        let checks: [(usize, bool); 9] = [
            // probe_x hangs from the root; its home places the grasp point.
            (
                0,
                link(0).parent.is_some_and(|p| links[p].parent.is_none())
                    && pure(&link(0).home)
                    && axis_is(0, Vec3::x()),
            ),
            (
                1,
                parent_name(1) == "probe_x" && identity(1) && axis_is(1, Vec3::y()),
            ),
            (
                2,
                parent_name(2) == "probe_y" && identity(2) && axis_is(2, Vec3::z()),
            ),
            (
                3,
                parent_name(3) == "probe_z" && identity(3) && axis_is(3, Vec3::x()) && at_origin(3),
            ),
            (
                4,
                link(4).parent.is_some_and(|p| {
                    links[p].parent.is_none()
                        && pure(&links[p].home)
                        && links[p].home.translation().norm() < 1e-12
                }) && identity(4)
                    && axis_is(4, Vec3::x()),
            ),
            (
                5,
                parent_name(5) == "table_x" && identity(5) && axis_is(5, Vec3::y()),
            ),
            (
                6,
                parent_name(6) == "table_y" && identity(6) && axis_is(6, Vec3::z()) && at_origin(6),
            ),
            (
                7,
                parent_name(7) == "probe_r" && identity(7) && axis_is(7, -Vec3::x()),
            ),
            (
                8,
                parent_name(8) == "probe_r" && identity(8) && axis_is(8, Vec3::x()),
            ),
        ];
        if let Some(&(k, _)) = checks.iter().find(|c| !c.1) {
            return Err(NotPrecision::Layout(names[k]));
        }
        if robot.flange() != robot.joint_links()[j[3]] {
            return Err(NotPrecision::Layout("probe_r"));
        }
        Ok(Self {
            probe: [j[0], j[1], j[2]],
            probe_r: j[3],
            table: [j[4], j[5]],
            table_c: j[6],
            fingers: [j[7], j[8]],
            probe_home: link(0).home.translation(),
        })
    }

    /// The work frame (the rotary table's frame) → world at joints `q`.
    pub fn work_frame(&self, robot: &Robot, q: &[f64]) -> Transform {
        let w = Isometry3::from_parts(
            Translation3::new(q[self.table[0]], q[self.table[1]], 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[self.table_c]),
        );
        Transform::from_isometry(robot.base().isometry() * w)
    }

    /// The tool frame → work frame at joints `q`: where the grasp point is relative
    /// to the table.
    pub fn tool_in_work(&self, robot: &Robot, q: &[f64]) -> Result<Transform, PrecisionError> {
        let tcp = robot.tcp_pose(q).map_err(|_| PrecisionError::BadInput)?;
        Ok(tcp.then(&self.work_frame(robot, q).inverse()))
    }

    /// Joints that put the tool frame at `tool_in_work` (tool → work frame), moving
    /// only the `free` axes from `q` (rad / mm); every other joint keeps its value.
    ///
    /// With both turns free the orientation fixes the table's angle (the closing
    /// axis's heading) and the probes' turn; the translation goes to the XY table
    /// when it is free, else to the probe stage, and its height to the probe stage.
    /// Angles are taken nearest to their current values.
    ///
    /// # Errors
    /// [`PrecisionError::Tilted`] (an orientation no turn of table and probes
    /// gives), [`PrecisionError::Needs`] (an axis that is not free would have to
    /// move), [`PrecisionError::Limit`], [`PrecisionError::BadInput`].
    pub fn solve(
        &self,
        robot: &Robot,
        q: &[f64],
        tool_in_work: &Transform,
        free: Free,
    ) -> Result<Vec<f64>, PrecisionError> {
        if q.len() != robot.dof() || q.iter().any(|v| !v.is_finite()) || !tool_in_work.is_finite() {
            return Err(PrecisionError::BadInput);
        }
        let mut out = q.to_vec();
        // work → flange target: the tool frame without the tool offset.
        let g = tool_in_work.isometry() * robot.tool().isometry().inverse();
        let m = g.rotation;
        // Rz(c)·M = Rx(r): M's x column is Rz(−c)·x, horizontal.
        let mx = m * Vector3::x();
        let tilt = mx.z.clamp(-1.0, 1.0).asin().abs();
        if tilt > EXACT {
            return Err(PrecisionError::Tilted { tilt_rad: tilt });
        }
        let c_raw = -mx.y.atan2(mx.x);
        let c = if free.table_c {
            unwrap_near(c_raw, q[self.table_c])
        } else {
            let d = unwrap_near(c_raw, q[self.table_c]) - q[self.table_c];
            if d.abs() > EXACT {
                return Err(PrecisionError::Needs {
                    axis: "table_c",
                    amount: d,
                });
            }
            q[self.table_c]
        };
        let n = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), c) * m;
        let nm = n.to_rotation_matrix();
        let r_raw = nm.matrix()[(2, 1)].atan2(nm.matrix()[(1, 1)]);
        let r = unwrap_near(r_raw, q[self.probe_r]);
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), r);
        let off = rx.angle_to(&n);
        if off > EXACT {
            return Err(PrecisionError::Tilted { tilt_rad: off });
        }
        if !free.probe_r && (r - q[self.probe_r]).abs() > EXACT {
            return Err(PrecisionError::Needs {
                axis: "probe_r",
                amount: r - q[self.probe_r],
            });
        }
        out[self.table_c] = c;
        out[self.probe_r] = if free.probe_r { r } else { q[self.probe_r] };
        // (x, y, 0) + Rz(c)·t = home + p.
        let v = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), c) * g.translation.vector;
        let h = self.probe_home;
        let names = [("table_x", "probe_x"), ("table_y", "probe_y")];
        for k in 0..2 {
            let (t, p) = (self.table[k], self.probe[k]);
            let gap = h[k] + q[p] - (q[t] + v[k]);
            if free.table_xy {
                out[t] = q[t] + gap;
            } else if free.probe_xy {
                out[p] = q[p] - gap;
            } else if gap.abs() > EXACT {
                return Err(PrecisionError::Needs {
                    axis: names[k].0,
                    amount: gap,
                });
            }
        }
        let dz = v.z - (h.z + q[self.probe[2]]);
        if free.probe_z {
            out[self.probe[2]] = q[self.probe[2]] + dz;
        } else if dz.abs() > EXACT {
            return Err(PrecisionError::Needs {
                axis: "probe_z",
                amount: dz,
            });
        }
        self.check_limits(robot, &out)?;
        Ok(out)
    }

    /// [`PrecisionError::Limit`] for the first joint of `q` outside its limits.
    pub fn check_limits(&self, robot: &Robot, q: &[f64]) -> Result<(), PrecisionError> {
        if let Some(j) = robot.limit_violation(q) {
            let link = robot.joint_links()[j];
            let l = robot.joint_limits()[j].unwrap_or(JointLimits::new(q[j], q[j]));
            return Err(PrecisionError::Limit {
                joint: robot.tree().links()[link].name.clone().unwrap_or_default(),
                value: q[j],
                min: l.min,
                max: l.max,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::AngleConvention;

    fn robot() -> Robot {
        precision_manipulator().unwrap()
    }

    /// By hand: the table at (5, −3) turned 90°, the probes at (1, 2, −4) turned 30°.
    /// The work frame's x axis is world +Y; the grasp point is at (1, 2, 6) in the
    /// world, i.e. at ((2 + 3), −(1 − 5), 6) = (5, 4, 6) in the work frame.
    #[test]
    fn the_tree_by_hand() {
        let r = robot();
        assert_eq!(r.dof(), 9);
        assert_eq!(r.chain_dof(), 4);
        let a = PrecisionAxes::detect(&r).unwrap();
        let q = [
            1.0,
            2.0,
            -4.0,
            30f64.to_radians(),
            5.0,
            -3.0,
            PI / 2.0,
            1.5,
            2.5,
        ];
        let tcp = r.tcp_pose(&q).unwrap();
        assert!((tcp.translation() - Vec3::new(1.0, 2.0, 6.0)).norm() < 1e-12);
        // Tool z down turned 30° about X; x along X.
        let z = tcp.apply_vector(&Vec3::z());
        let want = Vec3::new(0.0, (30f64).to_radians().sin(), -(30f64).to_radians().cos());
        assert!((z - want).norm() < 1e-12, "{z}");
        assert!((tcp.apply_vector(&Vec3::x()) - Vec3::x()).norm() < 1e-12);
        let t = a.tool_in_work(&r, &q).unwrap();
        assert!(
            (t.translation() - Vec3::new(5.0, 4.0, 6.0)).norm() < 1e-12,
            "{t}"
        );
        // The fingers open along the closing axis, each from the grasp point.
        let poses = r.link_poses(&q).unwrap();
        assert!((poses[8].translation() - Vec3::new(-0.5, 2.0, 6.0)).norm() < 1e-12);
        assert!((poses[9].translation() - Vec3::new(3.5, 2.0, 6.0)).norm() < 1e-12);
        // The rotary table's link is the work frame.
        assert!(poses[3].approx_eq(&a.work_frame(&r, &q), 1e-12, 1e-12));
    }

    /// Every solve reaches its target with only its free axes moving, from random
    /// joints to random reachable targets; a target that needs another axis says so.
    #[test]
    fn solves_move_only_their_axes() {
        let r = robot();
        let a = PrecisionAxes::detect(&r).unwrap();
        let mut rng = crate::math::Rng::new(7);
        let lim = r.joint_limits();
        let random = |rng: &mut crate::math::Rng| -> Vec<f64> {
            lim.iter()
                .map(|l| {
                    let l = l.unwrap();
                    rng.range(l.min * 0.5, l.max * 0.5)
                })
                .collect()
        };
        for _ in 0..200 {
            let q0 = random(&mut rng);
            let q1 = random(&mut rng);
            for (free, moves) in [
                (Free::TABLE, vec![a.table[0], a.table[1]]),
                (Free::PROBES, a.probe.to_vec()),
                (Free::TABLE_TURN, vec![a.table[0], a.table[1], a.table_c]),
                (
                    Free::PROBE_TURN,
                    vec![a.probe[0], a.probe[1], a.probe[2], a.probe_r],
                ),
                (
                    Free::SCREW,
                    vec![a.table[0], a.table[1], a.table_c, a.probe[2]],
                ),
                (
                    Free::GRASP,
                    vec![a.table[0], a.table[1], a.table_c, a.probe[2], a.probe_r],
                ),
            ] {
                // A target made by moving only those axes.
                let mut qt = q0.clone();
                for &j in &moves {
                    qt[j] = q1[j];
                }
                let target = a.tool_in_work(&r, &qt).unwrap();
                let q = a.solve(&r, &q0, &target, free).unwrap();
                for j in 0..9 {
                    if !moves.contains(&j) {
                        assert_eq!(q[j], q0[j], "joint {j} moved for {free:?}");
                    }
                }
                let got = a.tool_in_work(&r, &q).unwrap();
                assert!(
                    got.approx_eq(&target, 1e-9, 1e-9),
                    "{free:?}: {got} vs {target}"
                );
            }
            // The table cannot lift: a target 1 mm higher needs the probes.
            let up = a
                .tool_in_work(&r, &q0)
                .unwrap()
                .then(&Transform::from_translation(Vec3::new(0.0, 0.0, 1.0)));
            let e = a.solve(&r, &q0, &up, Free::TABLE).unwrap_err();
            assert!(
                matches!(
                    e,
                    PrecisionError::Needs {
                        axis: "probe_z",
                        ..
                    }
                ),
                "{e}"
            );
        }
        // A tilt of the closing axis is no turn of table and probes.
        let q0 = vec![0.0; 9];
        let t = a
            .tool_in_work(&r, &q0)
            .unwrap()
            .then(&Transform::from_xyzabc(
                Vec3::zeros(),
                [0.0, 0.2, 0.0],
                AngleConvention::default(),
            ));
        let tilted =
            Transform::from_parts(a.tool_in_work(&r, &q0).unwrap().translation(), t.rotation());
        assert!(matches!(
            a.solve(&r, &q0, &tilted, Free::GRASP),
            Err(PrecisionError::Tilted { .. })
        ));
        // Out of the probes' small range.
        let far = a
            .tool_in_work(&r, &q0)
            .unwrap()
            .then(&Transform::from_translation(Vec3::new(4.0, 0.0, 0.0)));
        assert!(matches!(
            a.solve(&r, &q0, &far, Free::PROBES),
            Err(PrecisionError::Limit { ref joint, .. }) if joint == "probe_x"
        ));
        assert!(a.solve(&r, &q0, &far, Free::TABLE).is_ok());
    }

    #[test]
    fn other_robots_are_not_precision_manipulators() {
        let mz07 = crate::kinematics::Catalog::NachiMz07.robot();
        assert!(matches!(
            PrecisionAxes::detect(&mz07),
            Err(NotPrecision::MissingJoint("probe_x"))
        ));
    }
}
