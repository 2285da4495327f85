//! A compiled C++ kinematics reference (`ur_kin.cpp`, opw_kinematics) behind its
//! driver, one request per line over pipes: `fk q…` → 16 numbers (row-major 4×4),
//! `ik T…` → `n` then `n` × 6 joint values, `bench reps n T…` → CPU ns per call and
//! solutions counted. The drivers are `tests/common/{ur,opw}_kin_driver.cpp`.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// One running driver.
pub struct KinDriver {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl KinDriver {
    /// Runs the compiler command `compile` (which writes `exe`), then starts `exe`
    /// with `args`; `what` names the reference in errors.
    pub fn compile_and_start(
        mut compile: Command,
        exe: &Path,
        args: &[String],
        what: &str,
    ) -> Result<KinDriver, String> {
        let out = compile.output().map_err(|e| format!("c++: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "compiling {what}: {}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let mut child = Command::new(exe)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| e.to_string())?;
        let stdin = child.stdin.take().ok_or("no stdin")?;
        let stdout = BufReader::new(child.stdout.take().ok_or("no stdout")?);
        Ok(KinDriver {
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

    /// The reference's forward kinematics: the pose, row-major 4×4, in the
    /// reference's own units and frames (see its module).
    pub fn fk(&mut self, q: &[f64]) -> [f64; 16] {
        let v = self.ask(&format!("fk {}", Self::numbers(q)));
        v.try_into().unwrap()
    }

    /// The reference's inverse kinematics: every solution it returns.
    pub fn ik(&mut self, t: &[f64; 16]) -> Vec<[f64; 6]> {
        let v = self.ask(&format!("ik {}", Self::numbers(t)));
        let n = v[0] as usize;
        (0..n)
            .map(|i| v[1 + 6 * i..7 + 6 * i].try_into().unwrap())
            .collect()
    }

    /// CPU nanoseconds per inverse call over `reps` passes of `targets`, measured
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

impl Drop for KinDriver {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
