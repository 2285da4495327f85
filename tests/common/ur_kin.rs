//! ROS-Industrial's `ur_kinematics` (`ur_kin.cpp`) as a reference in the same run:
//! compiled at test or bench time from the universal_robot checkout that
//! `FITUP_UR_KIN_SRC` names (never committed), one binary per arm, driven through
//! `tests/common/ur_kin_driver.cpp` over pipes. `ur_kin.cpp` works in metres, in its
//! base frame (ur_description's `base_link`) to its end effector (`tool0` turned so
//! that x points out of the flange).

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

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

/// One compiled `ur_kin.cpp` (for one arm) behind its driver.
pub struct UrKin {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl UrKin {
    /// Compiles `ur_kin.cpp` of the checkout `src` for `params` (`UR5e`, `UR10`, …: its
    /// `#define <params>_PARAMS` set) into `out_dir` and starts it.
    pub fn build(src: &Path, params: &str, out_dir: &Path) -> Result<UrKin, String> {
        let kin = src.join("ur_kinematics");
        let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/common/ur_kin_driver.cpp");
        std::fs::create_dir_all(out_dir).map_err(|e| e.to_string())?;
        let exe = out_dir.join(format!("ur_kin_{params}"));
        let out = Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()))
            .arg("-O2")
            .arg(format!("-D{params}_PARAMS"))
            .arg("-DIKFAST_NO_MAIN")
            .arg("-I")
            .arg(kin.join("include"))
            .arg(&driver)
            .arg(kin.join("src/ur_kin.cpp"))
            .arg("-o")
            .arg(&exe)
            .output()
            .map_err(|e| format!("c++: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "compiling ur_kin.cpp for {params}: {}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let mut child = Command::new(&exe)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| e.to_string())?;
        let stdin = child.stdin.take().unwrap();
        let stdout = BufReader::new(child.stdout.take().unwrap());
        Ok(UrKin {
            child,
            stdin,
            stdout,
        })
    }

    fn ask(&mut self, request: &str) -> Vec<f64> {
        writeln!(self.stdin, "{request}").unwrap();
        self.stdin.flush().unwrap();
        let mut line = String::new();
        self.stdout.read_line(&mut line).unwrap();
        line.split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    }

    fn numbers(v: &[f64]) -> String {
        v.iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// `forward(q)`: the end-effector pose, row-major 4×4, metres.
    pub fn fk(&mut self, q: &[f64]) -> [f64; 16] {
        let v = self.ask(&format!("fk {}", Self::numbers(q)));
        v.try_into().unwrap()
    }

    /// `inverse(T, q_sols, 0)`: every solution it returns (joint values in [0, 2π)).
    pub fn ik(&mut self, t: &[f64; 16]) -> Vec<[f64; 6]> {
        let v = self.ask(&format!("ik {}", Self::numbers(t)));
        let n = v[0] as usize;
        (0..n)
            .map(|i| v[1 + 6 * i..7 + 6 * i].try_into().unwrap())
            .collect()
    }

    /// CPU nanoseconds per `inverse()` call over `reps` passes of `targets`, measured
    /// inside the driver, and the solutions counted.
    pub fn bench(&mut self, reps: usize, targets: &[[f64; 16]]) -> (f64, u64) {
        let all: Vec<f64> = targets.iter().flatten().copied().collect();
        let v = self.ask(&format!(
            "bench {reps} {} {}",
            targets.len(),
            Self::numbers(&all)
        ));
        (v[0], v[1] as u64)
    }
}

impl Drop for UrKin {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
