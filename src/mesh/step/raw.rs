//! What Open CASCADE returns, as plain data, and the one byte format it travels in:
//! from a child reader to its parent, and into the tessellation store. Decoding checks
//! every length against the bytes left before allocating, so a damaged store file or a
//! confused child is refused, never trusted.

use super::{ChildFailure, ChildReader, StepError, StepOptions, CHILD_COMMAND};
use std::path::Path;
use std::time::{Duration, Instant};

/// One distinct solid as the shim returns it.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawPart {
    pub name: String,
    pub solid_index: u32,
    pub solids_in_product: u32,
    /// xyz per vertex, mm, face meshes side by side.
    pub vertices: Vec<f64>,
    pub triangles: Vec<u32>,
    pub exact_volume: f64,
    pub faces: u32,
    pub unmeshed_faces: u32,
    pub first_unmeshed_face: u32,
}

/// One placed solid as the shim returns it.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawInstance {
    pub name: String,
    pub path: String,
    pub part: u32,
    /// Row-major 3 × 4 `[R | t]`, mm.
    pub matrix: Vec<f64>,
    pub scale: f64,
    /// The assembly occurrence holding it: 1-based index into
    /// [`RawModel::assemblies`], 0 at the top.
    pub parent: u32,
}

/// One placed assembly as the shim returns it (listed before what it holds).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawAssembly {
    pub name: String,
    pub path: String,
    pub product: String,
    /// As [`RawInstance::parent`]; always below this assembly's own index.
    pub parent: u32,
    /// Row-major 3 × 4 `[R | t]`, mm: assembly frame → root.
    pub matrix: Vec<f64>,
    pub scale: f64,
}

/// The shim's whole answer (see `src/mesh/step_ffi.rs` for the fields' meaning), and
/// the reader's peak memory (bytes, 0 when unknown).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawModel {
    pub parts: Vec<RawPart>,
    pub instances: Vec<RawInstance>,
    pub length_unit: String,
    pub read_s: f64,
    pub transfer_s: f64,
    pub mesh_s: f64,
    pub shells_without_solid: u32,
    pub faces_without_solid: u32,
    pub open_shells: u32,
    pub first_open_shell: String,
    pub peak_memory: u64,
    pub assemblies: Vec<RawAssembly>,
}

// ---- the byte format ---------------------------------------------------------------

#[derive(Default)]
pub(super) struct Writer(pub(super) Vec<u8>);

impl Writer {
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn f64(&mut self, v: f64) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.extend(s.as_bytes());
    }
    pub(super) fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
    }
    pub(super) fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        for x in v {
            self.u32(*x);
        }
    }
}

/// Reads the byte format from a slice or a stream (a store entry is decoded as it is
/// read, never held whole), knowing how many bytes are left: every count is checked
/// against them before anything is allocated.
pub(super) struct Reader<'a> {
    src: Box<dyn std::io::Read + 'a>,
    left: u64,
}

/// The decoder's only failure: the bytes are not a model (what is wrong).
pub(super) type Bad = &'static str;

impl<'a> Reader<'a> {
    /// A reader of `bytes`.
    pub(super) fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader {
            left: bytes.len() as u64,
            src: Box::new(bytes),
        }
    }

    /// A reader of `len` bytes from `src` (a file: buffered here).
    pub(super) fn stream(src: impl std::io::Read + 'a, len: u64) -> Reader<'a> {
        Reader {
            src: Box::new(std::io::BufReader::with_capacity(1 << 20, src)),
            left: len,
        }
    }

    /// Whether every byte was read.
    pub(super) fn is_empty(&self) -> bool {
        self.left == 0
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], Bad> {
        if self.left < N as u64 {
            return Err("truncated");
        }
        let mut b = [0u8; N];
        self.src.read_exact(&mut b).map_err(|_| "truncated")?;
        self.left -= N as u64;
        Ok(b)
    }

    pub(super) fn take(&mut self, n: usize) -> Result<Vec<u8>, Bad> {
        if self.left < n as u64 {
            return Err("truncated");
        }
        let mut b = vec![0u8; n];
        self.src.read_exact(&mut b).map_err(|_| "truncated")?;
        self.left -= n as u64;
        Ok(b)
    }
    pub(super) fn u32(&mut self) -> Result<u32, Bad> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(super) fn u64(&mut self) -> Result<u64, Bad> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub(super) fn f64(&mut self) -> Result<f64, Bad> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A count of items of `size` bytes each, checked against what is left.
    pub(super) fn count(&mut self, size: usize) -> Result<usize, Bad> {
        let n = self.u64()?;
        if n > self.left / size as u64 {
            return Err("a length past its end");
        }
        Ok(n as usize)
    }
    pub(super) fn str(&mut self) -> Result<String, Bad> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?).map_err(|_| "not UTF-8 text")
    }
    pub(super) fn f64s(&mut self) -> Result<Vec<f64>, Bad> {
        self.f64s_within(usize::MAX, "")
    }
    /// [`f64s`](Self::f64s) of at most `max` values (else `why`), counted first.
    pub(super) fn f64s_within(&mut self, max: usize, why: Bad) -> Result<Vec<f64>, Bad> {
        let n = self.count(8)?;
        if n > max {
            return Err(why);
        }
        (0..n).map(|_| self.f64()).collect()
    }
    /// [`u32s`](Self::u32s) of at most `max` values (else `why`), counted first.
    pub(super) fn u32s_within(&mut self, max: usize, why: Bad) -> Result<Vec<u32>, Bad> {
        let n = self.count(4)?;
        if n > max {
            return Err(why);
        }
        (0..n).map(|_| self.u32()).collect()
    }
}

pub(super) fn encode_model(w: &mut Writer, m: &RawModel) {
    w.u64(m.parts.len() as u64);
    for p in &m.parts {
        w.str(&p.name);
        w.u32(p.solid_index);
        w.u32(p.solids_in_product);
        w.f64s(&p.vertices);
        w.u32s(&p.triangles);
        w.f64(p.exact_volume);
        w.u32(p.faces);
        w.u32(p.unmeshed_faces);
        w.u32(p.first_unmeshed_face);
    }
    w.u64(m.instances.len() as u64);
    for i in &m.instances {
        w.str(&i.name);
        w.str(&i.path);
        w.u32(i.part);
        w.f64s(&i.matrix);
        w.f64(i.scale);
        w.u32(i.parent);
    }
    w.str(&m.length_unit);
    w.f64(m.read_s);
    w.f64(m.transfer_s);
    w.f64(m.mesh_s);
    w.u32(m.shells_without_solid);
    w.u32(m.faces_without_solid);
    w.u32(m.open_shells);
    w.str(&m.first_open_shell);
    w.u64(m.peak_memory);
    w.u64(m.assemblies.len() as u64);
    for a in &m.assemblies {
        w.str(&a.name);
        w.str(&a.path);
        w.str(&a.product);
        w.u32(a.parent);
        w.f64s(&a.matrix);
        w.f64(a.scale);
    }
}

pub(super) fn decode_model(r: &mut Reader) -> Result<RawModel, Bad> {
    decode_model_within(r, usize::MAX)
}

/// [`decode_model`] refusing, before it allocates them, a part of more than
/// `max_part_triangles` triangles or more than three vertices a triangle allowed (what
/// could never become one mesh: [`MAX_TRIANGLES`](crate::mesh::MAX_TRIANGLES)).
pub(super) fn decode_model_within(
    r: &mut Reader,
    max_part_triangles: usize,
) -> Result<RawModel, Bad> {
    // The smallest encoded part is 52 bytes, the smallest instance 40, the smallest
    // assembly 44.
    let n = r.count(52)?;
    let mut parts = Vec::with_capacity(n);
    let max_corners = max_part_triangles.saturating_mul(3);
    for _ in 0..n {
        let name = r.str()?;
        let solid_index = r.u32()?;
        let solids_in_product = r.u32()?;
        let vertices = r.f64s_within(
            max_corners.saturating_mul(3),
            "a part with more vertices than one mesh may hold",
        )?;
        let triangles = r.u32s_within(
            max_corners,
            "a part with more triangles than one mesh may hold",
        )?;
        if vertices.len() % 3 != 0 || triangles.len() % 3 != 0 {
            return Err("a mesh with a partial vertex or triangle");
        }
        parts.push(RawPart {
            name,
            solid_index,
            solids_in_product,
            vertices,
            triangles,
            exact_volume: r.f64()?,
            faces: r.u32()?,
            unmeshed_faces: r.u32()?,
            first_unmeshed_face: r.u32()?,
        });
    }
    let n = r.count(40)?;
    let mut instances = Vec::with_capacity(n);
    for _ in 0..n {
        instances.push(RawInstance {
            name: r.str()?,
            path: r.str()?,
            part: r.u32()?,
            matrix: r.f64s()?,
            scale: r.f64()?,
            parent: r.u32()?,
        });
    }
    let mut m = RawModel {
        parts,
        instances,
        length_unit: r.str()?,
        read_s: r.f64()?,
        transfer_s: r.f64()?,
        mesh_s: r.f64()?,
        shells_without_solid: r.u32()?,
        faces_without_solid: r.u32()?,
        open_shells: r.u32()?,
        first_open_shell: r.str()?,
        peak_memory: r.u64()?,
        assemblies: Vec::new(),
    };
    let n = r.count(44)?;
    m.assemblies.reserve_exact(n);
    for _ in 0..n {
        m.assemblies.push(RawAssembly {
            name: r.str()?,
            path: r.str()?,
            product: r.str()?,
            parent: r.u32()?,
            matrix: r.f64s()?,
            scale: r.f64()?,
        });
    }
    Ok(m)
}

// ---- the child reader ----------------------------------------------------------------

/// How a child's answer file begins.
const REPLY_MAGIC: &[u8] = b"fitup-step-reply 2\n";

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
/// TIME_LIMIT_S MAX_TRIANGLES MEMORY_LIMIT`, stdout to nowhere, stderr kept (a few
/// KB) to tell an exhausted memory cap from a crash, killed at the time limit plus
/// [`grace`].
pub(super) fn read_in_child(
    path: &Path,
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
    let start = Instant::now();
    let mut proc = std::process::Command::new(&child.program)
        .arg(CHILD_COMMAND)
        .arg(path)
        .arg(&reply)
        .arg(options.linear_deflection.to_string())
        .arg(options.angular_deflection.to_string())
        .arg(options.time_limit.as_secs_f64().to_string())
        .arg(options.max_triangles.to_string())
        .arg(child.memory_limit.to_string())
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(stderr)
        .spawn()
        .map_err(|e| {
            fail(ChildFailure::Spawn {
                program: child.program.clone(),
                kind: e.kind(),
            })
        })?;
    let deadline = options.time_limit + grace(options.time_limit);
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
        if start.elapsed() > deadline {
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
    let bytes = crate::fsutil::file_head(&reply, max_reply(options) + 1).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            fail(ChildFailure::BadReply {
                program: child.program.clone(),
                what: "missing",
            })
        } else {
            io(e)
        }
    })?;
    let bad = |what| {
        fail(ChildFailure::BadReply {
            program: child.program.clone(),
            what,
        })
    };
    if bytes.len() as u64 > max_reply(options) {
        return Err(bad("larger than the triangle cap allows"));
    }
    let mut r = Reader::new(
        bytes
            .strip_prefix(REPLY_MAGIC)
            .ok_or_else(|| bad("not a fitup reader's answer"))?,
    );
    match r.take(1).map_err(bad)?[0] {
        0 => {
            let model = decode_model(&mut r).map_err(bad)?;
            if !r.is_empty() {
                return Err(bad("longer than its contents"));
            }
            Ok(model)
        }
        1 => {
            let what = r.str().map_err(bad)?;
            Err(super::shim_error(path, options, &what))
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
    match super::imp::occt_read(file, &options) {
        Ok(mut model) => {
            model.peak_memory = peak_memory();
            w.0.push(0);
            encode_model(&mut w, &model);
        }
        Err(what) => {
            // Open CASCADE's parser catches its own allocation failures and only says
            // the file did not parse: a failure with the address space within 32 MiB
            // of the cap is the cap.
            let at_cap = memory > 0 && status_kb("VmPeak:") * 1024 + (32 << 20) >= memory;
            w.0.push(1);
            w.str(if at_cap { "fitup:oom" } else { &what });
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
pub(crate) mod tests {
    use super::*;

    /// One part of one triangle placed once, named `name`: the tests' model (here
    /// and in the tessellation store's tests).
    pub(crate) fn sample_model(name: &str) -> RawModel {
        RawModel {
            parts: vec![RawPart {
                name: name.into(),
                solid_index: 1,
                solids_in_product: 1,
                vertices: vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.5],
                triangles: vec![0, 1, 2],
                exact_volume: 12.5,
                faces: 3,
                ..RawPart::default()
            }],
            instances: vec![RawInstance {
                name: "peg-1".into(),
                path: "cell/peg-1".into(),
                part: 0,
                matrix: (0..12).map(f64::from).collect(),
                scale: 1.0,
                parent: 1,
            }],
            assemblies: vec![RawAssembly {
                name: "cell".into(),
                path: "cell".into(),
                product: "cell".into(),
                parent: 0,
                matrix: (0..12).map(f64::from).collect(),
                scale: 1.0,
            }],
            length_unit: "MILLIMETRE".into(),
            ..RawModel::default()
        }
    }

    /// The sample with every field set, for the codec.
    fn model() -> RawModel {
        let mut m = sample_model("peg ✓");
        let p = &mut m.parts[0];
        (p.solids_in_product, p.unmeshed_faces, p.first_unmeshed_face) = (2, 1, 2);
        (m.read_s, m.first_open_shell, m.peak_memory) = (0.25, "x".into(), 7);
        m
    }

    #[test]
    fn a_model_round_trips_and_every_cut_is_refused() {
        let mut w = Writer::default();
        encode_model(&mut w, &model());
        let back = decode_model(&mut Reader::new(&w.0)).unwrap();
        assert_eq!(back, model());
        // Every truncation fails cleanly (no panic, no huge allocation).
        for n in 0..w.0.len() {
            assert!(
                decode_model(&mut Reader::new(&w.0[..n])).is_err(),
                "cut at {n}"
            );
        }
        // A count claiming 2^60 items is refused before allocating.
        let mut huge = Writer::default();
        huge.u64(1 << 60);
        assert_eq!(
            decode_model(&mut Reader::new(&huge.0)).unwrap_err(),
            "a length past its end"
        );
    }
}
