//! The one generator of Universal Robots URDFs in ROS `ur_description` form, shared by
//! the UR IK tests (exact twists), the real-URDF tests (the rounded twists
//! `ur_description` writes) and the arm + gripper package test.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The twist `ur_description` (noetic) writes for joints 2 and 5: its calibration
/// rounds π/2 to ten digits.
#[allow(clippy::approx_constant)]
pub const ROUNDED_ROLL: f64 = 1.570796327;

/// A URDF in ROS `ur_description` joint-origin form from the published D-H numbers
/// `[d1, a2, a3, d4, d5, d6]` in **metres**: `base_link` → `base_link_inertia` turned by π
/// as there, `flange` and `tool0` frames, every link empty (`<link name="…"/>`, for a
/// caller to give geometry by replacing it). `roll` is the twist of joints 2 and 5:
/// [`FRAC_PI_2`] for the exact arm, [`ROUNDED_ROLL`] for the file `ur_description`
/// writes, whose joint 5 and 6 origins then carry the offsets that make up for it along
/// the rounded axis and whose joint 6 roll is `π − roll` (with pitch and yaw π).
pub fn ur_description(name: &str, dh_m: [f64; 6], roll: f64) -> String {
    let [d1, a2, a3, d4, d5, d6] = dh_m;
    let slack = roll - FRAC_PI_2;
    let joint = |n: &str, parent: &str, child: &str, xyz: [f64; 3], rpy: [f64; 3]| {
        format!(
            r#"  <joint name="{n}" type="revolute"><origin xyz="{} {} {}" rpy="{} {} {}"/><parent link="{parent}"/><child link="{child}"/><axis xyz="0 0 1"/><limit lower="{}" upper="{}" effort="150" velocity="3.14"/></joint>
"#,
            xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], -TAU, TAU
        )
    };
    let mut s = format!(
        r#"<?xml version="1.0"?>
<robot name="{name}">
  <link name="base_link"/><link name="base_link_inertia"/><link name="shoulder_link"/>
  <link name="upper_arm_link"/><link name="forearm_link"/><link name="wrist_1_link"/>
  <link name="wrist_2_link"/><link name="wrist_3_link"/><link name="flange"/><link name="tool0"/>
  <joint name="base_link-base_link_inertia" type="fixed"><parent link="base_link"/><child link="base_link_inertia"/><origin xyz="0 0 0" rpy="0 0 {PI}"/></joint>
"#
    );
    // Joint, parent, child, origin xyz (m), origin rpy.
    type Row<'a> = (&'a str, &'a str, &'a str, [f64; 3], [f64; 3]);
    let rows: [Row; 6] = [
        (
            "shoulder_pan_joint",
            "base_link_inertia",
            "shoulder_link",
            [0.0, 0.0, d1],
            [0.0; 3],
        ),
        (
            "shoulder_lift_joint",
            "shoulder_link",
            "upper_arm_link",
            [0.0; 3],
            [roll, 0.0, 0.0],
        ),
        (
            "elbow_joint",
            "upper_arm_link",
            "forearm_link",
            [a2, 0.0, 0.0],
            [0.0; 3],
        ),
        (
            "wrist_1_joint",
            "forearm_link",
            "wrist_1_link",
            [a3, 0.0, d4],
            [0.0; 3],
        ),
        (
            "wrist_2_joint",
            "wrist_1_link",
            "wrist_2_link",
            [0.0, -d5, -d5 * slack],
            [roll, 0.0, 0.0],
        ),
        (
            "wrist_3_joint",
            "wrist_2_link",
            "wrist_3_link",
            [0.0, d6, -d6 * slack],
            [PI - roll, PI, PI],
        ),
    ];
    for (n, parent, child, xyz, rpy) in rows {
        s += &joint(n, parent, child, xyz, rpy);
    }
    s += &format!(
        r#"  <joint name="wrist_3-flange" type="fixed"><parent link="wrist_3_link"/><child link="flange"/><origin xyz="0 0 0" rpy="0 {} {}"/></joint>
  <joint name="flange-tool0" type="fixed"><parent link="flange"/><child link="tool0"/><origin xyz="0 0 0" rpy="{FRAC_PI_2} 0 {FRAC_PI_2}"/></joint>
</robot>
"#,
        -FRAC_PI_2, -FRAC_PI_2
    );
    s
}
