//! The C++ `opw_kinematics` (Jmeyer1292/opw_kinematics, header-only, Eigen) as a
//! reference in the same run: compiled at bench time from the include folder that
//! `FITUP_OPW_KIN_SRC` names (never committed), driven through
//! `tests/common/opw_kin_driver.cpp` over pipes. Lengths in the unit of the
//! parameters given (mm here), poses row-major 4×4 of the flange.

use super::kin_driver::KinDriver;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The opw_kinematics include folder (holding `opw_kinematics/opw_kinematics.h`), or
/// `None` with a note printed (the caller skips).
pub fn source() -> Option<PathBuf> {
    match std::env::var_os("FITUP_OPW_KIN_SRC") {
        Some(p) => Some(PathBuf::from(p)),
        None => {
            eprintln!("FITUP_OPW_KIN_SRC is not set: skipping the C++ opw_kinematics comparison");
            None
        }
    }
}

/// One compiled opw_kinematics driver for one parameter set: `fk(q)` is its
/// `forward(p, q)` (the flange pose), `ik(T)` its `inverse(p, T)` (the valid
/// solutions, no NaN).
pub type OpwKin = KinDriver;

/// Compiles the driver against the include folder `include` (and Eigen from
/// `EIGEN_INCLUDE_DIR`, default `/usr/include/eigen3`) into `out_dir` and starts it
/// for the OPW parameters `[a1, a2, b, c1, c2, c3, c4]`.
pub fn build(include: &Path, params: [f64; 7], out_dir: &Path) -> Result<OpwKin, String> {
    let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/common/opw_kin_driver.cpp");
    let eigen = std::env::var("EIGEN_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include/eigen3".into());
    std::fs::create_dir_all(out_dir).map_err(|e| e.to_string())?;
    let exe = out_dir.join("opw_kin");
    let mut compile = Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()));
    compile
        .args(["-O2", "-std=c++17", "-DNDEBUG", "-I"])
        .arg(include)
        .arg("-I")
        .arg(&eigen)
        .arg(&driver)
        .arg("-o")
        .arg(&exe);
    let args: Vec<String> = params.iter().map(|v| format!("{v:e}")).collect();
    KinDriver::compile_and_start(compile, &exe, &args, "the opw_kinematics driver")
}
