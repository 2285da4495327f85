//! The child reader: Open CASCADE run in a child process (the program re-executed
//! with [`CHILD_COMMAND`]) under an address-space cap and killed at the time limit;
//! its answer, a model or the shim's failure, comes back in raw.rs's byte format.

use super::raw::{decode_model_within, encode_model, Bad, RawModel, Reader, Writer};
use super::shim::{self, ShimFailure};
use super::{ChildFailure, ChildReader, StepError, StepOptions, StepStage, CHILD_COMMAND};
use crate::math::Deadline;
use std::path::Path;
use std::time::Duration;

/// A [`ShimFailure`] in a child's answer: its cause code, then the cause's fields.
fn encode_failure(w: &mut Writer, f: &ShimFailure) {
    match f {
        ShimFailure::Parse => w.u32(0),
        ShimFailure::Transfer => w.u32(1),
        ShimFailure::TimeLimit(stage) => {
            w.u32(2);
            w.u32(match stage {
                StepStage::Reading => 0,
                StepStage::Transferring => 1,
                StepStage::Meshing => 2,
            });
        }
        ShimFailure::TooManyTriangles => w.u32(3),
        ShimFailure::TooDeep { at } => {
            w.u32(4);
            w.str(at);
        }
        ShimFailure::OutOfMemory => w.u32(5),
        ShimFailure::Exception { kind, message } => {
            w.u32(6);
            w.str(kind);
            w.str(message);
        }
    }
}

fn decode_failure(r: &mut Reader) -> Result<ShimFailure, Bad> {
    Ok(match r.u32()? {
        0 => ShimFailure::Parse,
        1 => ShimFailure::Transfer,
        2 => ShimFailure::TimeLimit(match r.u32()? {
            0 => StepStage::Reading,
            1 => StepStage::Transferring,
            2 => StepStage::Meshing,
            _ => return Err("a failure at an unknown stage"),
        }),
        3 => ShimFailure::TooManyTriangles,
        4 => ShimFailure::TooDeep { at: r.str()? },
        5 => ShimFailure::OutOfMemory,
        6 => ShimFailure::Exception {
            kind: r.str()?,
            message: r.str()?,
        },
        _ => return Err("a failure of an unknown cause"),
    })
}

/// How a child's answer file begins.
const REPLY_MAGIC: &[u8] = b"fitup-step-reply 3\n";

/// How long past the time limit a child may take before it is killed: Open CASCADE
/// stops the transfer and the meshing itself at the limit, and parsing is not
/// interruptible, so this bounds the parse.
fn grace(limit: Duration) -> Duration {
    Duration::from_secs(1) + limit / 10
}

/// The largest answer a child may give (bytes): the triangle cap's worth of
/// unwelded triangles (three vertices of 24 bytes and three 4-byte indices each)
/// plus room for names.
fn max_reply(options: &StepOptions) -> u64 {
    (64 << 20) + options.max_triangles.saturating_mul(3 * 28)
}

/// Runs the read in a child: `program __step-read FILE REPLY LINEAR ANGULAR
/// TIME_LIMIT_S MAX_TRIANGLES MEMORY_LIMIT`; with `file` (the STEP file already opened
/// through the jail), that file is the child's standard input and FILE is
/// `/proc/self/fd/0`, so the child never looks the user's path up. Stdout to nowhere, stderr kept (a few
/// KB) to tell an exhausted memory cap from a crash, killed at the time limit plus
/// [`grace`].
pub(super) fn read_in_child(
    path: &Path,
    file: Option<std::fs::File>,
    options: &StepOptions,
    child: &ChildReader,
) -> Result<RawModel, StepError> {
    let fail = |failure| StepError::Child {
        path: path.into(),
        failure,
    };
    let io = |e: std::io::Error| StepError::Child {
        path: path.into(),
        failure: ChildFailure::Io { kind: e.kind() },
    };
    let dir = tempfile::Builder::new()
        .prefix("fitup-step-")
        .tempdir()
        .map_err(io)?;
    let reply = dir.path().join("reply");
    let errors = dir.path().join("stderr");
    let stderr = std::fs::File::create(&errors).map_err(io)?;
    let kill_at = Deadline::after(options.time_limit + grace(options.time_limit));
    let mut proc = std::process::Command::new(&child.program)
        .arg(CHILD_COMMAND)
        .arg(if file.is_some() {
            Path::new("/proc/self/fd/0")
        } else {
            path
        })
        .arg(&reply)
        .arg(options.linear_deflection.to_string())
        .arg(options.angular_deflection.to_string())
        .arg(options.time_limit.as_secs_f64().to_string())
        .arg(options.max_triangles.to_string())
        .arg(child.memory_limit.to_string())
        .stdin(file.map_or_else(std::process::Stdio::null, std::process::Stdio::from))
        // Two malloc arenas: each thread's arena reserves 64 MiB of address space,
        // which the address-space cap would otherwise spend on reservations.
        .env("MALLOC_ARENA_MAX", "2")
        .stdout(std::process::Stdio::null())
        .stderr(stderr)
        .spawn()
        .map_err(|e| {
            fail(ChildFailure::Spawn {
                program: child.program.clone(),
                kind: e.kind(),
            })
        })?;
    let mut nap = Duration::from_millis(1);
    let status = loop {
        match proc.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) => {}
            Err(e) => {
                let _ = proc.kill();
                let _ = proc.wait();
                return Err(io(e));
            }
        }
        if kill_at.passed() {
            let _ = proc.kill();
            let _ = proc.wait();
            return Err(StepError::TimeLimit {
                path: path.into(),
                limit: options.time_limit,
                stage: super::StepStage::Reading,
            });
        }
        std::thread::sleep(nap);
        nap = (nap * 2).min(Duration::from_millis(20));
    };
    if !status.success() {
        let said = crate::fsutil::file_head(&errors, 4096).unwrap_or_default();
        let said = String::from_utf8_lossy(&said);
        // Rust's allocator prints "memory allocation of N bytes failed" and aborts;
        // glibc and C++ say "Cannot allocate memory" or bad_alloc.
        let out_of_memory = ["memory allocation", "bad_alloc", "Cannot allocate memory"]
            .iter()
            .any(|m| said.contains(m));
        if out_of_memory && child.memory_limit > 0 {
            return Err(StepError::MemoryLimit {
                path: path.into(),
                limit: child.memory_limit,
            });
        }
        #[cfg(unix)]
        let signal = std::os::unix::process::ExitStatusExt::signal(&status);
        #[cfg(not(unix))]
        let signal: Option<i32> = None;
        if let Some(signal) = signal {
            // SIGXCPU: the CPU-time backstop the child set on itself.
            if signal == 24 {
                return Err(StepError::TimeLimit {
                    path: path.into(),
                    limit: options.time_limit,
                    stage: super::StepStage::Reading,
                });
            }
            return Err(StepError::Crashed {
                path: path.into(),
                signal,
            });
        }
        return Err(fail(ChildFailure::Exit {
            code: status.code().unwrap_or(-1),
        }));
    }
    let bad = |what| {
        fail(ChildFailure::BadReply {
            program: child.program.clone(),
            what,
        })
    };
    // Decoded as it is read (never held whole): every count is checked against the
    // bytes left, each part against the one-mesh cap, before it is allocated.
    let answer = std::fs::File::open(&reply).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            bad("missing")
        } else {
            io(e)
        }
    })?;
    let len = answer.metadata().map_err(io)?.len();
    if len > max_reply(options) {
        return Err(bad("larger than the triangle cap allows"));
    }
    let mut r = Reader::stream(answer, len);
    if r.take(REPLY_MAGIC.len()).map_err(bad)? != REPLY_MAGIC {
        return Err(bad("not a fitup reader's answer"));
    }
    match r.take(1).map_err(bad)?[0] {
        0 => {
            let model = decode_model_within(&mut r, crate::mesh::MAX_TRIANGLES).map_err(bad)?;
            if !r.is_empty() {
                return Err(bad("longer than its contents"));
            }
            Ok(model)
        }
        1 => {
            let failure = decode_failure(&mut r).map_err(bad)?;
            if !r.is_empty() {
                return Err(bad("longer than its contents"));
            }
            Err(shim::error(path, options, failure))
        }
        _ => Err(bad("of an unknown kind")),
    }
}

/// The child's side ([`super::serve_child`]).
pub(super) fn serve_child(args: &[std::ffi::OsString]) -> i32 {
    let [file, reply, linear, angular, limit, triangles, memory] = args else {
        eprintln!("{CHILD_COMMAND}: expected 7 arguments, got {}", args.len());
        return 2;
    };
    let num = |s: &std::ffi::OsString| s.to_str().and_then(|s| s.parse::<f64>().ok());
    let int = |s: &std::ffi::OsString| s.to_str().and_then(|s| s.parse::<u64>().ok());
    let (Some(linear), Some(angular), Some(limit), Some(triangles), Some(memory)) = (
        num(linear),
        num(angular),
        num(limit),
        int(triangles),
        int(memory),
    ) else {
        eprintln!("{CHILD_COMMAND}: an argument is not a number");
        return 2;
    };
    let Ok(time_limit) = Duration::try_from_secs_f64(limit) else {
        eprintln!("{CHILD_COMMAND}: the time limit is not a duration");
        return 2;
    };
    limit_self(memory, time_limit);
    let options = StepOptions {
        linear_deflection: linear,
        angular_deflection: angular,
        time_limit,
        max_triangles: triangles,
        isolation: super::Isolation::InProcess,
    };
    let Some(file) = file.to_str() else {
        eprintln!("{CHILD_COMMAND}: the path is not UTF-8");
        return 2;
    };
    let mut w = Writer(REPLY_MAGIC.to_vec());
    match shim::read(file, &options) {
        Ok(mut model) => {
            model.peak_memory = peak_memory();
            w.0.push(0);
            encode_model(&mut w, &model);
        }
        Err(failure) => {
            // Open CASCADE's parser catches its own allocation failures and only says
            // the file did not parse: a failure with the address space within 32 MiB
            // of the cap is the cap.
            let at_cap = memory > 0 && status_kb("VmPeak:") * 1024 + (32 << 20) >= memory;
            w.0.push(1);
            encode_failure(
                &mut w,
                &if at_cap {
                    ShimFailure::OutOfMemory
                } else {
                    failure
                },
            );
        }
    }
    match std::fs::write(Path::new(reply), &w.0) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("{CHILD_COMMAND}: cannot write the answer: {e}");
            3
        }
    }
}

/// The child caps itself before Open CASCADE runs: its address space at `memory`
/// bytes (an allocation past it fails: C++ gets `bad_alloc`, which the shim reports),
/// no core file on a crash, and CPU time at the limit plus grace (a backstop; the
/// parent kills it on the wall clock anyway).
fn limit_self(memory: u64, time_limit: Duration) {
    #[cfg(all(unix, feature = "step"))]
    {
        use rustix::process::{setrlimit, Resource, Rlimit};
        if memory > 0 {
            let _ = setrlimit(
                Resource::As,
                Rlimit {
                    current: Some(memory),
                    maximum: Some(memory),
                },
            );
        }
        let _ = setrlimit(
            Resource::Core,
            Rlimit {
                current: Some(0),
                maximum: Some(0),
            },
        );
        let cpu = (time_limit + grace(time_limit)).as_secs() + 1;
        let _ = setrlimit(
            Resource::Cpu,
            Rlimit {
                current: Some(cpu),
                maximum: Some(cpu + 1),
            },
        );
    }
    #[cfg(not(all(unix, feature = "step")))]
    let _ = (memory, time_limit);
}

/// This process's peak resident memory (bytes; Linux `VmHWM`, else 0).
fn peak_memory() -> u64 {
    status_kb("VmHWM:") * 1024
}

/// A `kB` line of `/proc/self/status` (`VmHWM:`, `VmPeak:`), 0 when unknown.
fn status_kb(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix(key))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A child's failure reaches its parent as the cause the shim gave, every field
    /// kept; a cut or unknown code is refused, not guessed.
    #[test]
    fn a_failure_round_trips_and_a_cut_or_unknown_cause_is_refused() {
        let failures = [
            ShimFailure::Parse,
            ShimFailure::Transfer,
            ShimFailure::TimeLimit(StepStage::Reading),
            ShimFailure::TimeLimit(StepStage::Transferring),
            ShimFailure::TimeLimit(StepStage::Meshing),
            ShimFailure::TooManyTriangles,
            ShimFailure::TooDeep {
                at: "cart/Frame-1/Axle ✓".into(),
            },
            ShimFailure::OutOfMemory,
            ShimFailure::Exception {
                kind: "Standard_NullObject".into(),
                message: "null handle: a: b".into(),
            },
        ];
        for f in failures {
            let mut w = Writer::default();
            encode_failure(&mut w, &f);
            let mut r = Reader::new(&w.0);
            assert_eq!(decode_failure(&mut r).unwrap(), f);
            assert!(r.is_empty(), "{f:?} left bytes");
            for n in 0..w.0.len() {
                let cut = decode_failure(&mut Reader::new(&w.0[..n]));
                assert!(cut.is_err(), "{f:?} cut at {n}: {cut:?}");
            }
        }
        let mut w = Writer::default();
        w.u32(7);
        assert_eq!(
            decode_failure(&mut Reader::new(&w.0)).unwrap_err(),
            "a failure of an unknown cause"
        );
        let mut w = Writer::default();
        w.u32(2);
        w.u32(3);
        assert_eq!(
            decode_failure(&mut Reader::new(&w.0)).unwrap_err(),
            "a failure at an unknown stage"
        );
    }
}
