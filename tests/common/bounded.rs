//! `fitup ARGS` run with bounds (hostile inputs: tests/it/hostile_*.rs and the STEP
//! tests' hostile files): killed after a time, its peak resident memory measured.

use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// Every case ends within this (a hang or an allocation storm does not).
pub const BOUND: Duration = Duration::from_secs(20);

/// What a bounded run left: exit code, output, peak RSS (kB) and wall time.
pub(crate) struct Run {
    pub(crate) code: Option<i32>,
    pub(crate) text: String,
    pub(crate) peak_kb: u64,
    pub(crate) elapsed: Duration,
}

/// The `VmHWM` (peak resident set, kB) of a running process, if it can be read.
fn peak_kb(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

/// GNU time, when installed: it reports the peak RSS of a process however short.
fn gnu_time() -> Option<&'static Path> {
    let t = Path::new("/usr/bin/time");
    t.is_file().then_some(t)
}

/// The processes `pid` started (GNU time's child), from /proc.
fn children(pid: u32) -> Vec<i32> {
    std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children"))
        .unwrap_or_default()
        .split_whitespace()
        .filter_map(|c| c.parse().ok())
        .collect()
}

/// `fitup ARGS` in `dir`, killed after [`BOUND`] (failing the test). Peak memory:
/// GNU time's `%M` when it is installed (`-o` a file, so the output is untouched),
/// and in any case `VmHWM` of the child polled every 5 ms (a run of a few ms may
/// end between two polls; GNU time sees it).
pub(crate) fn run(dir: &Path, args: &[&str]) -> Run {
    run_within(dir, args, BOUND)
}

/// [`run`] killed after `bound` instead of [`BOUND`] (a case that does a lot of
/// work on purpose, such as reading a mesh at the triangle cap, while other tests run).
pub(crate) fn run_within(dir: &Path, args: &[&str], bound: Duration) -> Run {
    let report = tempfile::NamedTempFile::new().unwrap();
    let command = match gnu_time() {
        Some(time) => {
            let mut c = std::process::Command::new(time);
            c.arg("-f")
                .arg("%M")
                .arg("-o")
                .arg(report.path())
                .arg(env!("CARGO_BIN_EXE_fitup"));
            c
        }
        None => super::fitup(),
    };
    let mut child = super::spawn_with(command, dir, args);
    let (out, err) = super::drain_outputs(&mut child);
    let start = Instant::now();
    let mut peak = 0;
    let status = loop {
        // Read before reaping: once waited for, /proc/PID is gone.
        for pid in
            std::iter::once(child.id()).chain(children(child.id()).into_iter().map(|c| c as u32))
        {
            if let Some(kb) = peak_kb(pid) {
                peak = peak.max(kb);
            }
        }
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > bound {
            for c in children(child.id()) {
                let _ = std::process::Command::new("kill")
                    .arg("-9")
                    .arg(c.to_string())
                    .status();
            }
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "`fitup {}` still running after {bound:?} (peak {peak} kB)",
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let elapsed = start.elapsed();
    let reported = std::fs::read_to_string(report.path()).unwrap_or_default();
    if let Some(kb) = reported
        .lines()
        .last()
        .and_then(|l| l.trim().parse::<u64>().ok())
    {
        peak = peak.max(kb);
    }
    let o = Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    };
    Run {
        code: o.status.code(),
        text: super::short_text(&o),
        peak_kb: peak,
        elapsed,
    }
}
