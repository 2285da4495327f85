//! A catalog of industrial arms with published parameters.
//!
//! Sources (see `docs/kinematics.md` for details and caveats):
//! - NACHI MZ07: D-H table 2 of seed 000 (geometry); flange at 80 mm from the wrist
//!   centre, the rest of the paper's d₆ = −516.9 mm is the tool.
//! - ABB IRB 2400/10, KUKA KR 6 R700 sixx: the ortho-parallel parameter sets
//!   published with the ROS-Industrial `opw_kinematics` package (also shipped by
//!   `rs-opw-kinematics`); Fanuc LR Mate 200iD and Stäubli TX2-60L: manufacturer
//!   dimension drawings as tabulated in public kinematics catalogues.
//! - UR3, UR5, UR10, UR3e, UR5e, UR10e: the D-H tables published by Universal Robots
//!   ("Parameters for calculations of kinematics and dynamics"), solved in closed form
//!   by [`UrSolver`](super::UrSolver).
//!
//! - Seed 003's two-finger precision manipulator (section 4.1): fitup's model of the
//!   machine the paper describes (XY table with a rotary table, probe stage, two
//!   probes), see [`precision_manipulator`](super::precision_manipulator).
//!
//! Joint limits are the manufacturers' data-sheet ranges (see the docs for which
//! could be confirmed).

use super::{DhConvention, DhRow, JointLimits, KinematicsError, OpwParameters, Robot};
use crate::math::{Transform, Vec3};
use std::f64::consts::{FRAC_PI_2, PI};

/// The arms (and seed 003's precision manipulator) of the catalog.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Catalog {
    /// NACHI MZ07 (seed 000, table 2).
    NachiMz07,
    /// ABB IRB 2400/10.
    AbbIrb2400,
    /// KUKA KR 6 R700 sixx.
    KukaKr6R700,
    /// Fanuc LR Mate 200iD (J2/J3 decoupled, as in ROS descriptions).
    FanucLrMate200iD,
    /// Stäubli TX2-60L.
    StaubliTx2_60L,
    /// Universal Robots UR5 (CB-Series; no spherical wrist: UR closed form).
    Ur5,
    /// Universal Robots UR3 (CB-Series).
    Ur3,
    /// Universal Robots UR10 (CB-Series).
    Ur10,
    /// Universal Robots UR3e.
    Ur3e,
    /// Universal Robots UR5e.
    Ur5e,
    /// Universal Robots UR10e.
    Ur10e,
    /// Seed 003's two-finger precision manipulator: XY table with a rotary table,
    /// a probe stage and two probes ([`precision_manipulator`](super::precision_manipulator);
    /// not an arm, so not in [`Catalog::ALL`]).
    PrecisionTwoFinger,
}

impl Catalog {
    /// Every catalog arm.
    pub const ALL: [Catalog; 11] = [
        Catalog::NachiMz07,
        Catalog::AbbIrb2400,
        Catalog::KukaKr6R700,
        Catalog::FanucLrMate200iD,
        Catalog::StaubliTx2_60L,
        Catalog::Ur5,
        Catalog::Ur3,
        Catalog::Ur10,
        Catalog::Ur3e,
        Catalog::Ur5e,
        Catalog::Ur10e,
    ];

    /// The machines of the catalog that are not 6-axis arms.
    pub const MACHINES: [Catalog; 1] = [Catalog::PrecisionTwoFinger];

    /// The Universal Robots arms of the catalog.
    pub const UR: [Catalog; 6] = [
        Catalog::Ur3,
        Catalog::Ur5,
        Catalog::Ur10,
        Catalog::Ur3e,
        Catalog::Ur5e,
        Catalog::Ur10e,
    ];

    /// The published standard D-H lengths `[d1, a2, a3, d4, d5, d6]` (mm) of a
    /// Universal Robots arm (α = π/2, 0, 0, π/2, −π/2, 0; every θ offset 0), `None`
    /// for the other arms. Source: Universal Robots, "Parameters for calculations of
    /// kinematics and dynamics".
    pub fn ur_dh(self) -> Option<[f64; 6]> {
        Some(match self {
            Catalog::Ur3 => [151.9, -243.65, -213.25, 112.35, 85.35, 81.9],
            Catalog::Ur5 => [89.159, -425.0, -392.25, 109.15, 94.65, 82.3],
            Catalog::Ur10 => [127.3, -612.0, -572.3, 163.941, 115.7, 92.2],
            Catalog::Ur3e => [151.85, -243.55, -213.2, 131.05, 85.35, 92.1],
            Catalog::Ur5e => [162.5, -425.0, -392.2, 133.3, 99.7, 99.6],
            Catalog::Ur10e => [180.7, -612.7, -571.55, 174.15, 119.85, 116.55],
            _ => return None,
        })
    }

    /// The catalog name (used by documents and scripts).
    pub fn name(self) -> &'static str {
        match self {
            Catalog::NachiMz07 => "nachi_mz07",
            Catalog::AbbIrb2400 => "abb_irb2400",
            Catalog::KukaKr6R700 => "kuka_kr6_r700",
            Catalog::FanucLrMate200iD => "fanuc_lrmate200id",
            Catalog::StaubliTx2_60L => "staubli_tx2_60l",
            Catalog::Ur5 => "ur5",
            Catalog::Ur3 => "ur3",
            Catalog::Ur10 => "ur10",
            Catalog::Ur3e => "ur3e",
            Catalog::Ur5e => "ur5e",
            Catalog::Ur10e => "ur10e",
            Catalog::PrecisionTwoFinger => super::precision::PRECISION_NAME,
        }
    }

    /// The robot with base at the origin and the tool at the flange (except the MZ07,
    /// whose tool is the paper's tool point).
    pub fn robot(self) -> Robot {
        // The parameters below are constants checked by the tests: building cannot fail.
        self.build()
            .unwrap_or_else(|e| unreachable!("catalog entry {} is invalid: {e}", self.name()))
    }

    // The limits are the URDFs' published numbers (e.g. 3.1416), kept as written.
    #[allow(clippy::approx_constant)]
    fn build(self) -> Result<Robot, KinematicsError> {
        let deg = JointLimits::degrees;
        let rad = JointLimits::new;
        match self {
            Catalog::PrecisionTwoFinger => super::precision_manipulator(),
            Catalog::NachiMz07 => {
                let limits = [
                    deg(-170.0, 170.0),
                    deg(-135.0, 80.0),
                    deg(-125.0, 280.0),
                    deg(-190.0, 190.0),
                    deg(-120.0, 120.0),
                    deg(-360.0, 360.0),
                ];
                let rows = [
                    DhRow::degrees(0.0, 340.0, 50.0, 90.0),
                    DhRow::degrees(90.0, 0.0, 330.0, 0.0),
                    DhRow::degrees(0.0, 0.0, 45.0, 90.0),
                    DhRow::degrees(0.0, 340.0, 0.0, 90.0),
                    DhRow::degrees(90.0, 0.0, 0.0, 90.0),
                    // Table 2 says d6 = −516.9 mm: that is the tool point. The flange
                    // sits MZ07_FLANGE mm from the wrist centre on the same side.
                    DhRow::degrees(0.0, -MZ07_FLANGE, 0.0, 0.0),
                ];
                let rows: Vec<DhRow> = rows
                    .iter()
                    .zip(limits)
                    .map(|(r, l)| r.with_limits(l))
                    .collect();
                let tool = Transform::from_translation(Vec3::new(
                    0.0,
                    0.0,
                    -(MZ07_TOOL_POINT - MZ07_FLANGE),
                ));
                Ok(
                    Robot::from_dh(self.name(), &rows, DhConvention::Standard, tool)?
                        .with_limits_source(
                        "unverified: NACHI data-sheet ranges from memory, no public source checked",
                    ),
                )
            }
            Catalog::AbbIrb2400 => {
                // Geometry: opw_kinematics `makeIrb2400_10` (Jmeyer1292/opw_kinematics,
                // include/opw_kinematics/opw_parameters_examples.h). Limits: ROS-Industrial
                // (ros-industrial/abb, abb_irb2400_support/urdf/irb2400_macro.xacro), rad.
                let mut p = OpwParameters::new(100.0, -135.0, 0.0, 615.0, 705.0, 755.0, 85.0);
                p.offsets[2] = -FRAC_PI_2;
                let limits = [
                    rad(-3.1416, 3.1416),
                    rad(-1.7453, 1.9199),
                    rad(-1.0472, 1.1345),
                    rad(-3.49, 3.49),
                    rad(-2.0944, 2.0944),
                    rad(-6.9813, 6.9813),
                ];
                Ok(p.robot(self.name(), limits.map(Some))?.with_limits_source(
                    "ros-industrial/abb abb_irb2400_support/urdf/irb2400_macro.xacro",
                ))
            }
            Catalog::KukaKr6R700 => {
                // Geometry: opw_kinematics `makeKukaKR6_R700_sixx` (same file as above).
                // Limits: ros-industrial/kuka_experimental,
                // kuka_kr6_support/urdf/kr6r700sixx_macro.xacro (degrees there).
                let mut p = OpwParameters::new(25.0, -35.0, 0.0, 400.0, 315.0, 365.0, 80.0);
                p.offsets[1] = -FRAC_PI_2;
                p.signs = [-1.0, 1.0, 1.0, -1.0, 1.0, -1.0];
                let limits = [
                    deg(-170.0, 170.0),
                    deg(-190.0, 45.0),
                    deg(-120.0, 156.0),
                    deg(-185.0, 185.0),
                    deg(-120.0, 120.0),
                    deg(-350.0, 350.0),
                ];
                Ok(p.robot(self.name(), limits.map(Some))?.with_limits_source(
                    "ros-industrial/kuka_experimental kuka_kr6_support/urdf/kr6r700sixx_macro.xacro",
                ))
            }
            Catalog::FanucLrMate200iD => {
                // Geometry, offsets (J3 −90°, J6 180°) and signs: ROS-Industrial
                // opw_parameters_lrmate200id.yaml, checked against the URDF
                // (ros-industrial/fanuc, fanuc_lrmate200id_support/urdf/lrmate200id_macro.xacro),
                // which also gives the limits (rad).
                let mut p = OpwParameters::new(50.0, -35.0, 0.0, 330.0, 330.0, 335.0, 80.0);
                p.offsets[2] = -FRAC_PI_2;
                p.offsets[5] = PI;
                p.signs = [1.0, 1.0, -1.0, -1.0, -1.0, -1.0];
                let limits = [
                    rad(-2.965, 2.965),
                    rad(-1.745329, 2.530727),
                    rad(-2.450966, 4.886922),
                    rad(-3.315, 3.315),
                    rad(-2.18, 2.18),
                    rad(-6.285, 6.285),
                ];
                Ok(p.robot(self.name(), limits.map(Some))?.with_limits_source(
                    "ros-industrial/fanuc fanuc_lrmate200id_support/urdf/lrmate200id_macro.xacro",
                ))
            }
            Catalog::StaubliTx2_60L => {
                let p = OpwParameters::new(0.0, 0.0, 20.0, 375.0, 400.0, 450.0, 70.0);
                let limits = [
                    deg(-180.0, 180.0),
                    deg(-127.5, 127.5),
                    deg(-142.5, 142.5),
                    deg(-270.0, 270.0),
                    deg(-121.0, 132.5),
                    deg(-270.0, 270.0),
                ];
                Ok(p.robot(self.name(), limits.map(Some))?.with_limits_source(
                    "unverified: data-sheet ranges from memory, no public source checked",
                ))
            }
            Catalog::Ur3
            | Catalog::Ur5
            | Catalog::Ur10
            | Catalog::Ur3e
            | Catalog::Ur5e
            | Catalog::Ur10e => {
                let [d1, a2, a3, d4, d5, d6] = self
                    .ur_dh()
                    .unwrap_or_else(|| unreachable!("UR arms have a D-H table"));
                let rows = [
                    DhRow::revolute(0.0, d1, 0.0, FRAC_PI_2),
                    DhRow::revolute(0.0, 0.0, a2, 0.0),
                    DhRow::revolute(0.0, 0.0, a3, 0.0),
                    DhRow::revolute(0.0, d4, 0.0, FRAC_PI_2),
                    DhRow::revolute(0.0, d5, 0.0, -FRAC_PI_2),
                    DhRow::revolute(0.0, d6, 0.0, 0.0),
                ];
                let rows: Vec<DhRow> = rows
                    .iter()
                    .map(|r| r.with_limits(deg(-360.0, 360.0)))
                    .collect();
                Ok(Robot::from_dh(
                    self.name(),
                    &rows,
                    DhConvention::Standard,
                    Transform::IDENTITY,
                )?
                .with_limits_source(
                    "unverified: ±360° on every joint (UR data sheet, from memory)",
                ))
            }
        }
    }
}

/// MZ07 flange distance from the wrist centre along axis 6 (mm).
pub const MZ07_FLANGE: f64 = 80.0;
/// Seed 000 table 2's |d6|: the tool point's distance from the wrist centre (mm).
pub const MZ07_TOOL_POINT: f64 = 516.9;

/// Names of the catalog's arms and machines.
pub fn catalog_names() -> Vec<&'static str> {
    Catalog::ALL
        .iter()
        .chain(&Catalog::MACHINES)
        .map(|c| c.name())
        .collect()
}

/// The catalog robot called `name` (see [`Catalog::name`]).
pub fn robot_by_name(name: &str) -> Option<Robot> {
    Catalog::ALL
        .iter()
        .chain(&Catalog::MACHINES)
        .find(|c| c.name() == name)
        .map(|c| c.robot())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{IkError, IkOptions, KinematicTree};
    use crate::math::Rng;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};

    fn pos(r: &Robot, q: [f64; 6]) -> Vec3 {
        r.tcp_pose(&q).unwrap().translation()
    }

    /// MZ07 (table 2) by hand, standard D-H: at zero frame 5 is parallel to the base
    /// with its origin (the wrist centre) at (50 + 340, 0, 340 + 330 + 45) =
    /// (390, 0, 715); z₅ points up, so the flange (d = −80) is at z = 635 and the tool
    /// point (d₆ = −516.9) at (390, 0, 198.1), pointing down.
    #[test]
    fn mz07_fk_by_hand() {
        let r = Catalog::NachiMz07.robot();
        let flange = r.flange_pose(&[0.0; 6]).unwrap();
        assert!(flange.approx_eq(
            &Transform::from_translation(Vec3::new(390.0, 0.0, 635.0)),
            1e-9,
            1e-12
        ));
        assert!((pos(&r, [0.0; 6]) - Vec3::new(390.0, 0.0, 198.1)).norm() < 1e-9);
        let down = r.tcp_pose(&[0.0; 6]).unwrap().apply_vector(&Vec3::z());
        assert!(
            (down - Vec3::z()).norm() < 1e-12,
            "tool frame keeps z up; the tool length points along -z"
        );
        // Joint 1 by 90°: a quarter turn about the base z axis.
        assert!(
            (pos(&r, [FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]) - Vec3::new(0.0, 390.0, 198.1)).norm()
                < 1e-9
        );
        // Joint 2 by 90° about z₁ = −y through (50, 0, 340): (340, 0, −141.9) relative
        // turns into (141.9, 0, 340).
        assert!(
            (pos(&r, [0.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0]) - Vec3::new(191.9, 0.0, 680.0)).norm()
                < 1e-9
        );
        // Joint 5 by 90° about z₄ = +y through the wrist centre: the tool swings from −z
        // to −x.
        assert!(
            (pos(&r, [0.0, 0.0, 0.0, 0.0, FRAC_PI_2, 0.0]) - Vec3::new(390.0 - 516.9, 0.0, 715.0))
                .norm()
                < 1e-9
        );
        // Joint 6 spins the tool about its own axis: the point stays.
        assert!(
            (pos(&r, [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]) - Vec3::new(390.0, 0.0, 198.1)).norm() < 1e-9
        );
    }

    /// A serial chain as ROS-Industrial URDFs write it: per joint the origin `xyz`
    /// (metres, every `rpy` 0 in these files) and the axis; then a fixed tool frame.
    /// Returns the tool frame pose in mm for joint values `q`.
    fn urdf_chain(
        joints: &[([f64; 3], [f64; 3])],
        tool: UnitQuaternion<f64>,
        q: &[f64],
    ) -> Isometry3<f64> {
        let mut pose = Isometry3::identity();
        for ((xyz, axis), v) in joints.iter().zip(q) {
            let t = Isometry3::translation(xyz[0] * 1000.0, xyz[1] * 1000.0, xyz[2] * 1000.0);
            let r = UnitQuaternion::from_axis_angle(
                &nalgebra::Unit::new_normalize(Vec3::new(axis[0], axis[1], axis[2])),
                *v,
            );
            pose = pose * t * Isometry3::from_parts(Translation3::identity(), r);
        }
        pose * Isometry3::from_parts(Translation3::identity(), tool)
    }

    /// Arm, its URDF chain, the URDF `tool0` on the last link, and our flange → `tool0`.
    type UrdfCase = (
        Catalog,
        &'static [([f64; 3], [f64; 3]); 6],
        UnitQuaternion<f64>,
        UnitQuaternion<f64>,
    );

    /// URDF `rpy` (fixed X, then Y, then Z) as a rotation.
    fn rpy(r: f64, p: f64, y: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(r, p, y)
    }

    /// ABB IRB 2400: joint origins and axes typed from ros-industrial/abb,
    /// abb_irb2400_support/urdf/irb2400_macro.xacro (tool0: rpy 0 0 0 on link_6).
    const IRB2400_URDF: [([f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.1, 0.0, 0.615], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.705], [0.0, 1.0, 0.0]),
        ([0.258, 0.0, 0.135], [1.0, 0.0, 0.0]),
        ([0.497, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.085, 0.0, 0.0], [1.0, 0.0, 0.0]),
    ];
    /// KUKA KR 6 R700 sixx: ros-industrial/kuka_experimental,
    /// kuka_kr6_support/urdf/kr6r700sixx_macro.xacro (tool0: rpy 0 90° 0 on the flange).
    const KR6_URDF: [([f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.4], [0.0, 0.0, -1.0]),
        ([0.025, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.315, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.035], [-1.0, 0.0, 0.0]),
        ([0.365, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.080, 0.0, 0.0], [-1.0, 0.0, 0.0]),
    ];
    /// Fanuc LR Mate 200iD: ros-industrial/fanuc,
    /// fanuc_lrmate200id_support/urdf/lrmate200id_macro.xacro (tool0: rpy π −π/2 0).
    const LRMATE_URDF: [([f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.330], [0.0, 0.0, 1.0]),
        ([0.050, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.330], [0.0, -1.0, 0.0]),
        ([0.0, 0.0, 0.035], [-1.0, 0.0, 0.0]),
        ([0.335, 0.0, 0.0], [0.0, -1.0, 0.0]),
        ([0.080, 0.0, 0.0], [-1.0, 0.0, 0.0]),
    ];

    /// The zero poses stated by the published models (issue 11, and the URDFs above):
    /// flange at (940, 0, 1455), (785, 0, 435), (465, 0, 695) mm, pointing +x.
    #[test]
    fn catalog_zero_poses_match_the_published_models() {
        for (arm, p) in [
            (Catalog::AbbIrb2400, Vec3::new(940.0, 0.0, 1455.0)),
            (Catalog::KukaKr6R700, Vec3::new(785.0, 0.0, 435.0)),
            (Catalog::FanucLrMate200iD, Vec3::new(465.0, 0.0, 695.0)),
        ] {
            let r = arm.robot();
            let t = r.tcp_pose(&[0.0; 6]).unwrap();
            assert!((t.translation() - p).norm() < 1e-9, "{}: {t}", arm.name());
            let z = t.apply_vector(&Vec3::z());
            assert!((z - Vec3::x()).norm() < 1e-12, "{}: z = {z:?}", arm.name());
            assert!(r.analytic().is_some(), "{}", arm.name());
        }
        // The Stäubli TX2-60L (no offsets) stands upright: flange on top.
        let t = Catalog::StaubliTx2_60L.robot().tcp_pose(&[0.0; 6]).unwrap();
        assert!(
            (t.translation() - Vec3::new(0.0, 20.0, 375.0 + 400.0 + 450.0 + 70.0)).norm() < 1e-9
        );
    }

    /// Published poses: the ROS-Industrial URDF chains (typed in above) at a set of
    /// joint vectors, including large ones on every joint, give the catalog's TCP pose
    /// (the URDF `tool0` frame; for the IRB 2400 its `tool0` has x forward where the
    /// OPW flange has z forward, a fixed quarter turn about y).
    #[test]
    fn catalog_matches_ros_industrial_urdfs() {
        let d = |v: [f64; 6]| v.map(f64::to_radians);
        let poses = [
            [0.0; 6],
            d([30.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            d([0.0, 40.0, 0.0, 0.0, 0.0, 0.0]),
            d([0.0, 0.0, -35.0, 0.0, 0.0, 0.0]),
            d([0.0, 0.0, 0.0, 70.0, 45.0, 0.0]),
            d([0.0, 0.0, 0.0, 0.0, 0.0, 90.0]),
            d([-45.0, 20.0, 30.0, -60.0, 50.0, 120.0]),
        ];
        let cases: [UrdfCase; 3] = [
            (
                Catalog::AbbIrb2400,
                &IRB2400_URDF,
                rpy(0.0, 0.0, 0.0),
                rpy(0.0, -FRAC_PI_2, 0.0),
            ),
            (
                Catalog::KukaKr6R700,
                &KR6_URDF,
                rpy(0.0, FRAC_PI_2, 0.0),
                UnitQuaternion::identity(),
            ),
            (
                Catalog::FanucLrMate200iD,
                &LRMATE_URDF,
                rpy(PI, -FRAC_PI_2, 0.0),
                UnitQuaternion::identity(),
            ),
        ];
        let mut rng = Rng::new(42);
        for (arm, chain, tool0, flange_to_tool0) in cases {
            let r = arm.robot();
            let random: Vec<[f64; 6]> = (0..50)
                .map(|_| std::array::from_fn(|_| rng.range(-PI, PI)))
                .collect();
            for q in poses.iter().chain(&random) {
                let urdf = Transform::from_isometry(urdf_chain(chain, tool0, q));
                let ours = Transform::from_isometry(
                    r.tcp_pose(q).unwrap().isometry()
                        * Isometry3::from_parts(Translation3::identity(), flange_to_tool0),
                );
                assert!(
                    ours.approx_eq(&urdf, 1e-9, 1e-12),
                    "{} at {q:?}: {ours} vs URDF {urdf}",
                    arm.name()
                );
            }
        }
    }

    /// Limits are the URDFs' (typed in above) or marked unverified.
    #[test]
    fn every_catalog_arm_says_where_its_limits_come_from() {
        for arm in Catalog::ALL {
            let r = arm.robot();
            let src = r.limits_source().unwrap();
            assert!(
                src.starts_with("ros-industrial/") || src.starts_with("unverified"),
                "{src}"
            );
        }
        let l = Catalog::FanucLrMate200iD.robot().joint_limits();
        assert_eq!(l[2], Some(JointLimits::new(-2.450966, 4.886922)));
    }

    #[test]
    fn catalog_names_resolve() {
        for name in catalog_names() {
            let r = robot_by_name(name).unwrap();
            // The arms have 6 joints; the precision manipulator 4 on its chain and 5
            // external axes.
            let dof = if name == crate::kinematics::PRECISION_NAME {
                9
            } else {
                6
            };
            assert_eq!(r.dof(), dof);
            assert_eq!(r.name(), name);
        }
        assert!(robot_by_name("nope").is_none());
    }

    /// UR5: numeric IK round trip; every solution reproduces the pose to 1e-6 mm and
    /// 1e-9 rad and lies within the limits.
    #[test]
    fn ur5_numeric_round_trip() {
        let r = Catalog::Ur5.robot();
        assert!(r.analytic().is_none());
        assert_eq!(r.solver_name(), "ur");
        let mut rng = Rng::new(3);
        let opts = IkOptions::default();
        let mut found_original = 0;
        let n = 1000;
        for _ in 0..n {
            let q: Vec<f64> = (0..6).map(|_| rng.range(-PI, PI)).collect();
            let t = r.tcp_pose(&q).unwrap();
            // A reference near the original: the nearest solution is the original.
            let reference: Vec<f64> = q.iter().map(|v| v + rng.range(-0.05, 0.05)).collect();
            let sols = r.inverse(&t, &reference, &opts).unwrap();
            for s in &sols {
                let (ang, dist) = r.tcp_pose(&s.joints).unwrap().distance_to(&t);
                assert!(dist < 1e-6 && ang < 1e-9, "{dist} mm {ang} rad");
                assert!(r.limit_violation(&s.joints).is_none());
            }
            if sols[0]
                .joints
                .iter()
                .zip(&q)
                .all(|(a, b)| (a - b).abs() < 1e-6)
            {
                found_original += 1;
            }
            // From a far reference the restarts still find a solution.
            let sols = r.inverse(&t, &[0.0; 6], &opts).unwrap();
            assert!(r
                .tcp_pose(&sols[0].joints)
                .unwrap()
                .approx_eq(&t, 1e-6, 1e-9));
        }
        // Started 0.05 rad away, the descent lands on the original configuration except
        // near singular configurations, where another branch lies that close (6 of
        // 1000 with this seed).
        assert!(found_original >= n * 99 / 100, "{found_original} of {n}");
    }

    #[test]
    fn ur5_numeric_errors_name_the_cause() {
        let r = Catalog::Ur5.robot();
        let opts = IkOptions {
            restarts: 6,
            ..IkOptions::default()
        };
        let far = Transform::from_translation(Vec3::new(3000.0, 0.0, 0.0));
        assert!(matches!(
            r.inverse(&far, &[0.0; 6], &opts),
            Err(IkError::Unreachable(_))
        ));
        // Joint 1 restricted to a narrow range: a target needing joint 1 ≈ ±2.5 rad
        // (or its other shoulder solution) is only reachable outside the limits.
        let mut tree_links = r.tree().links().to_vec();
        tree_links[1].joint.limits = Some(JointLimits::new(-0.1, 0.1));
        let narrow = Robot::new(
            "ur5-narrow",
            KinematicTree::new(tree_links).unwrap(),
            6,
            Transform::IDENTITY,
        )
        .unwrap();
        let t = r.tcp_pose(&[2.5, -1.0, 1.0, -0.5, 1.2, 0.3]).unwrap();
        assert!(matches!(
            narrow.inverse(&t, &[0.0; 6], &opts),
            Err(IkError::JointLimits { joint: 1, .. })
        ));
    }
}
