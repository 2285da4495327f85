//! ROS-Industrial's `ur_kinematics` (`ur_kin.cpp`) as a reference in the same run:
//! compiled at test or bench time from the universal_robot checkout that
//! `FITUP_UR_KIN_SRC` names (never committed), one binary per arm, driven through
//! `tests/common/ur_kin_driver.cpp` over pipes. `ur_kin.cpp` works in metres, in its
//! base frame (ur_description's `base_link`) to its end effector (`tool0` turned so
//! that x points out of the flange).

use super::kin_driver::KinDriver;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The universal_robot checkout, or `None` with a note printed (the caller skips).
pub fn source() -> Option<PathBuf> {
    match std::env::var_os("FITUP_UR_KIN_SRC") {
        Some(p) => Some(PathBuf::from(p)),
        None => {
            eprintln!("FITUP_UR_KIN_SRC is not set: skipping the ur_kin.cpp comparison");
            None
        }
    }
}

/// One compiled `ur_kin.cpp` (for one arm) behind its driver: `fk(q)` is its
/// `forward(q)` (metres), `ik(T)` its `inverse(T, q_sols, 0)` (every solution,
/// joint values in [0, 2π)).
pub type UrKin = KinDriver;

/// Compiles `ur_kin.cpp` of the checkout `src` for `params` (`UR5e`, `UR10`, …: its
/// `#define <params>_PARAMS` set) into `out_dir` and starts it.
pub fn build(src: &Path, params: &str, out_dir: &Path) -> Result<UrKin, String> {
    let kin = src.join("ur_kinematics");
    let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/common/ur_kin_driver.cpp");
    std::fs::create_dir_all(out_dir).map_err(|e| e.to_string())?;
    let exe = out_dir.join(format!("ur_kin_{params}"));
    let mut compile = Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()));
    compile
        .arg("-O2")
        .arg(format!("-D{params}_PARAMS"))
        .arg("-DIKFAST_NO_MAIN")
        .arg("-I")
        .arg(kin.join("include"))
        .arg(&driver)
        .arg(kin.join("src/ur_kin.cpp"))
        .arg("-o")
        .arg(&exe);
    KinDriver::compile_and_start(compile, &exe, &[], &format!("ur_kin.cpp for {params}"))
}
