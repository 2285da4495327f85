//! Helpers shared by the integration tests: a scratch project with the demo cell,
//! and the `fitup` binary.

#![allow(dead_code)]

pub mod lines;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The built `fitup` binary.
pub fn fitup() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fitup"))
}

/// A temporary project folder (`fitup demo`): `fitup.toml`, `models/cell.yaml` and its
/// meshes.
pub fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_project(dir.path()).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    dir
}

/// Runs `fitup ARGS` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    fitup().current_dir(dir).args(args).output().unwrap()
}

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Stdout and stderr as text.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// [`text`] cut to a readable length for failure messages.
pub fn short_text(o: &Output) -> String {
    let t = text(o);
    let n = t.chars().count();
    if n > 4000 {
        let head: String = t.chars().take(4000).collect();
        format!("{head}… ({n} characters)")
    } else {
        t
    }
}

/// Starts `fitup ARGS` in `dir` with no input and both outputs piped.
pub fn spawn(dir: &Path, args: &[&str]) -> Child {
    fitup()
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits for `child`, killing it and failing the test after `bound` — a bound on
/// hangs, not a speed assertion. Its output is read meanwhile, so a chatty child
/// never blocks on a full pipe.
pub fn finish(mut child: Child, what: &str, bound: Duration) -> Output {
    fn drain(r: Option<impl Read + Send + 'static>) -> std::thread::JoinHandle<Vec<u8>> {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            buf
        })
    }
    let out = drain(child.stdout.take());
    let err = drain(child.stderr.take());
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > bound {
            let _ = child.kill();
            let o = Output {
                status: child.wait().unwrap(),
                stdout: out.join().unwrap(),
                stderr: err.join().unwrap(),
            };
            panic!(
                "`fitup {what}`: still running after {bound:?}; output:\n{}",
                text(&o)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    }
}

/// `fitup ARGS` in `dir`, killed (failing the test) after `bound`.
pub fn run_bounded(dir: &Path, args: &[&str], bound: Duration) -> Output {
    finish(spawn(dir, args), &args.join(" "), bound)
}

/// `fitup watch SCRIPT EXTRA…` in `dir`: the process (killed when dropped) and its
/// stdout line by line (stderr is discarded).
pub struct Watch {
    /// The `fitup watch` process.
    pub process: lines::Killed,
    /// The watch's stdout.
    pub out: lines::Lines,
}

impl Watch {
    /// Starts the watch with no input.
    pub fn start(dir: &Path, script: &str, extra: &[&str]) -> Watch {
        let mut child = fitup()
            .current_dir(dir)
            .arg("watch")
            .arg(script)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let out = lines::Lines::read(child.stdout.take().unwrap());
        Watch {
            process: lines::Killed(child),
            out,
        }
    }
}

/// Copies the micro-robot wheel (seed 003: `models/wheel.yaml` and its three meshes)
/// into the project `p`.
pub fn copy_wheel(p: &Path) {
    let root = repo();
    std::fs::create_dir_all(p.join("models/meshes")).unwrap();
    std::fs::copy(root.join("models/wheel.yaml"), p.join("models/wheel.yaml")).unwrap();
    for m in ["axis", "gear", "cup"] {
        let f = format!("models/meshes/wheel_{m}.stl");
        std::fs::copy(root.join(&f), p.join(&f)).unwrap();
    }
}

/// sha256 of each regular file, by path: what the hostile tests compare before and
/// after a run to show that nothing the user owns changed.
pub type Snapshot = std::collections::BTreeMap<PathBuf, [u8; 32]>;

/// sha256 of every regular file under `dir` (links, FIFOs and other special files are
/// not read, so a planted FIFO cannot block the test).
pub fn snapshot(dir: &Path) -> Snapshot {
    use sha2::{Digest, Sha256};
    let mut out = Snapshot::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let md = std::fs::symlink_metadata(&p).unwrap();
            if md.is_dir() {
                stack.push(p);
            } else if md.is_file() {
                out.insert(p.clone(), Sha256::digest(std::fs::read(&p).unwrap()).into());
            }
        }
    }
    out
}

/// `fitup manipulator ARGS` started from the repository root, returned once its state
/// port (`state_port`, on 127.0.0.1) accepts connections; killed when dropped.
pub fn manipulator(args: &[&str], state_port: u16) -> lines::Killed {
    let mut child = fitup()
        .current_dir(repo())
        .arg("manipulator")
        .args(args)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", state_port)).is_err() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "fitup manipulator exited"
        );
        assert!(
            start.elapsed() < std::time::Duration::from_secs(60),
            "no manipulator"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    lines::Killed(child)
}
