//! The C++ `opw_kinematics` (Jmeyer1292/opw_kinematics, header-only, Eigen) as a
//! reference in the same run: compiled at bench time from the include folder that
//! `FITUP_OPW_KIN_SRC` names (never committed), driven through
//! `tests/common/opw_kin_driver.cpp` over pipes. Lengths in the unit of the
//! parameters given (mm here), poses row-major 4×4 of the flange.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

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

/// One compiled opw_kinematics driver for one parameter set.
pub struct OpwKin {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl OpwKin {
    /// Compiles the driver against the include folder `include` (and Eigen from
    /// `EIGEN_INCLUDE_DIR`, default `/usr/include/eigen3`) into `out_dir` and starts it
    /// for the OPW parameters `[a1, a2, b, c1, c2, c3, c4]`.
    pub fn build(include: &Path, params: [f64; 7], out_dir: &Path) -> Result<OpwKin, String> {
        let driver = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/common/opw_kin_driver.cpp");
        let eigen =
            std::env::var("EIGEN_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include/eigen3".into());
        std::fs::create_dir_all(out_dir).map_err(|e| e.to_string())?;
        let exe = out_dir.join("opw_kin");
        let out = Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()))
            .args(["-O2", "-std=c++17", "-DNDEBUG", "-I"])
            .arg(include)
            .arg("-I")
            .arg(&eigen)
            .arg(&driver)
            .arg("-o")
            .arg(&exe)
            .output()
            .map_err(|e| format!("c++: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "compiling the opw_kinematics driver: {}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let mut child = Command::new(&exe)
            .args(params.iter().map(|v| format!("{v:e}")))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| e.to_string())?;
        let stdin = child.stdin.take().ok_or("no stdin")?;
        let stdout = BufReader::new(child.stdout.take().ok_or("no stdout")?);
        Ok(OpwKin {
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

    /// `forward(p, q)`: the flange pose, row-major 4×4.
    pub fn fk(&mut self, q: &[f64; 6]) -> [f64; 16] {
        let v = self.ask(&format!("fk {}", Self::numbers(q)));
        v.try_into().unwrap()
    }

    /// `inverse(p, T)`: the valid solutions (no NaN).
    pub fn ik(&mut self, t: &[f64; 16]) -> Vec<[f64; 6]> {
        let v = self.ask(&format!("ik {}", Self::numbers(t)));
        let n = v[0] as usize;
        (0..n)
            .map(|i| v[1 + 6 * i..7 + 6 * i].try_into().unwrap())
            .collect()
    }

    /// CPU nanoseconds per `inverse()` call over `reps` passes of `targets`, measured
    /// inside the driver, and the valid solutions counted.
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

impl Drop for OpwKin {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
