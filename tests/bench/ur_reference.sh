#!/bin/sh
# Prepares the third-party UR references of tests/it/ur_real.rs outside the repository
# (nothing here is committed): ROS-Industrial's universal_robot checkout (for
# ur_kinematics/src/ur_kin.cpp) and the UR3e/UR5e/UR10e/UR16e URDFs that its
# ur_description xacros generate (`pip install xacro`).
#
#   tests/bench/ur_reference.sh UNIVERSAL_ROBOT_CHECKOUT OUT_DIR
#   FITUP_UR_KIN_SRC=OUT_DIR/src FITUP_UR_URDF_DIR=OUT_DIR/urdf cargo test --test it ur_real
set -eu
src=$1
out=$2
mkdir -p "$out/src" "$out/urdf"
cp -R "$src/ur_description" "$src/ur_kinematics" "$out/src/"
desc=$(cd "$out/src/ur_description" && pwd)
# xacro without ROS: resolve $(find ur_description) to the copy.
grep -rl '$(find ur_description)' "$desc" | while read -r f; do
    sed -i "s#\$(find ur_description)#$desc#g" "$f"
done
for arm in ur3e ur5e ur10e ur16e; do
    xacro "$desc/urdf/$arm.xacro" > "$out/urdf/$arm.urdf"
done
echo "FITUP_UR_KIN_SRC=$out/src FITUP_UR_URDF_DIR=$out/urdf"
