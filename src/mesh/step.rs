//! STEP (ISO 10303-21: AP203, AP214, AP242) assemblies as meshes, read by Open CASCADE
//! through fitup's C++ shim (`cpp/step_shim.cpp`, cargo feature `step`).
//!
//! [`read_step`] returns one [`StepPart`] per distinct solid (meshed once, in its own
//! frame, mm) and one [`StepInstance`] per placed solid of the assembly tree (its pose
//! part frame → world, mm). Lengths are converted to mm whatever unit the file is in.
//! Every mesh is checked closed and consistently oriented, and its volume is compared
//! with the exact B-rep volume ([`StepPart::volume_ratio`]).
//!
//! **Gaps.** Open CASCADE's mesh of a closed solid is now and then not closed: a face
//! left without triangles (a sliver, or a face that did not mesh), or a node on one
//! face's side of an edge that the other face's side skips (a T-junction). Before a
//! solid is refused as open, such gaps are closed: a T-junction's triangle is split
//! at the node (within the linear deflection of its side), and a hole whose rim is a
//! triangle or a flat convex polygon (within the deflection) is filled. The mend is
//! kept only when the closed mesh's volume is within 1.5 % of the exact B-rep volume
//! (a hole that was not one missing face would not be); [`StepPart::mended`] counts
//! what was closed and `fitup import` says so.
//!
//! Without the feature every call returns [`StepError::NotBuilt`], whose message says
//! how to rebuild.
//!
//! **Isolation.** Open CASCADE is a large C++ library that can crash (a null handle on a
//! malformed entity), loop or allocate without bound on a hostile file. With
//! [`Isolation::Child`] (what the `fitup` binary uses, see [`read_in_child_processes`])
//! the read runs in a child process — the program re-executed with the hidden command
//! [`CHILD_COMMAND`] — under an address-space cap ([`ChildReader::memory_limit`]) and
//! killed at the time limit, so a crash, hang or memory blow-up becomes a
//! [`StepError`] naming the file, in bounded time and memory, never an abort of the
//! caller. [`Isolation::InProcess`] (the library's default when no child program was
//! registered) reads in this process.
//!
//! Bounds: the file must be at most [`FileKind::Step`]'s cap (64 MiB) — Open CASCADE
//! holds a model in about 10–30 times the file's size —, the transfer and the meshing
//! stop at [`StepOptions::time_limit`] (OCCT polls it through its progress indicator;
//! in a child the whole read is also killed shortly after it), and all meshes together
//! have at most [`StepOptions::max_triangles`].
//!
//! **Tessellation store.** [`read_step_stored`] keeps what Open CASCADE returned in a
//! folder (a project's [`STEP_STORE`]), one file per STEP content hash, deflection and
//! angle, written by the project's write rule ([`crate::project::write_output`]); a
//! later read of the same bytes with the same tessellation skips Open CASCADE. Stored
//! files are checked like a fresh read (and ignored when damaged). Writing an entry
//! removes the entries of the same STEP file's older contents and keeps the folder
//! under [`DEFAULT_STORE_CAP`] (least recently used first); [`prune_store`] removes
//! the rest of what is stale (`fitup cache prune`; see the `store` module).

mod child;
mod gaps;
mod raw;
mod shim;
mod store;

pub(crate) use store::prune_held;
pub use store::{
    prune_store, PruneOptions, PruneReport, Pruned, StaleReason, StoreError, Tessellation,
    DEFAULT_STORE_CAP,
};

use super::{Mesh, MeshError};
use crate::fsutil::{FileKind, ReadError};
use crate::math::Transform;
use crate::project::Project;
use raw::RawModel;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

/// Default linear deflection of the tessellation: the largest distance between a
/// triangle and the exact surface, mm.
pub const DEFAULT_LINEAR_DEFLECTION: f64 = 0.1;

/// Default angular deflection of the tessellation: the largest angle between the
/// normals of neighbouring triangles on a curved face, radians (OCCT's default, ≈ 28.6°).
pub const DEFAULT_ANGULAR_DEFLECTION: f64 = 0.5;

/// Default address-space cap of a child reader, bytes (1 GiB: Open CASCADE holds a
/// model in 10–30 times the file's size; a file that needs more is refused as
/// [`StepError::MemoryLimit`], naming the file and the cap; `fitup import
/// --memory-limit-mb` raises it).
pub const DEFAULT_MEMORY_LIMIT: u64 = 1 << 30;

/// Default cap on all meshes of one file together, triangles ([`StepOptions::max_triangles`]):
/// what keeps fitup's own process under 1 GB at the cap (at most 84 bytes a triangle
/// for the decoded answer, the same again for the store's encoding, and the welded
/// meshes: see docs/document.md).
pub const DEFAULT_MAX_TRIANGLES: u64 = 3_000_000;

/// The hidden command a child reader is started with (`PROGRAM __step-read …`); a
/// program that registers itself with [`read_in_child_processes`] must hand it to
/// [`serve_child`] before anything else.
pub const CHILD_COMMAND: &str = "__step-read";

/// The project-relative folder where documents keep the tessellations of their `step:`
/// parts ([`read_step_stored`]).
pub const STEP_STORE: &str = ".fitup-cache/step";

/// Whether this build reads STEP files (the `step` feature).
pub const AVAILABLE: bool = cfg!(feature = "step");

/// A child reader: the program re-executed to read a STEP file, and its memory cap.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChildReader {
    /// The program; it must call [`serve_child`] when started with [`CHILD_COMMAND`]
    /// (the `fitup` binary does).
    pub program: PathBuf,
    /// The child's address-space cap (`RLIMIT_AS`), bytes; 0: none.
    pub memory_limit: u64,
}

/// Where Open CASCADE runs.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Isolation {
    /// In this process: a crash in Open CASCADE ends the process.
    InProcess,
    /// In a child process, bounded in time and memory (see the module documentation).
    Child(ChildReader),
}

static CHILD_PROGRAM: OnceLock<PathBuf> = OnceLock::new();

/// Makes every later [`StepOptions::default`] read in a child process running
/// `program` (which must serve [`CHILD_COMMAND`] through [`serve_child`]); the
/// `fitup` binary registers itself at start. The first registration stands.
pub fn read_in_child_processes(program: PathBuf) {
    let _ = CHILD_PROGRAM.set(program);
}

impl Isolation {
    /// A child running the program registered with [`read_in_child_processes`], with
    /// [`DEFAULT_MEMORY_LIMIT`]; in this process when none was registered.
    pub fn process_default() -> Isolation {
        match CHILD_PROGRAM.get() {
            Some(program) => Isolation::Child(ChildReader {
                program: program.clone(),
                memory_limit: DEFAULT_MEMORY_LIMIT,
            }),
            None => Isolation::InProcess,
        }
    }
}

/// How to read and mesh a STEP file.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOptions {
    /// Linear deflection, mm (> 0): smaller is finer.
    pub linear_deflection: f64,
    /// Angular deflection, radians (> 0).
    pub angular_deflection: f64,
    /// Time limit of the transfer and meshing together.
    pub time_limit: Duration,
    /// The most triangles of all solids together.
    pub max_triangles: u64,
    /// Where Open CASCADE runs.
    pub isolation: Isolation,
}

impl Default for StepOptions {
    fn default() -> Self {
        StepOptions {
            linear_deflection: DEFAULT_LINEAR_DEFLECTION,
            angular_deflection: DEFAULT_ANGULAR_DEFLECTION,
            time_limit: Duration::from_secs(300),
            max_triangles: DEFAULT_MAX_TRIANGLES,
            isolation: Isolation::process_default(),
        }
    }
}

/// A distinct solid of the file, meshed once.
#[derive(Debug, Clone)]
pub struct StepPart {
    /// The product's name in the file (may be empty or repeated; the importer makes
    /// document names of it).
    pub product: String,
    /// Which solid of the product (1-based), and how many the product has.
    pub solid: (u32, u32),
    /// The mesh in the part's own frame, mm, closed and consistently oriented.
    pub mesh: Mesh,
    /// The exact B-rep volume (Open CASCADE's BRepGProp), mm³.
    pub exact_volume: f64,
    /// Gaps of Open CASCADE's mesh closed before the solid was taken: T-junctions
    /// split plus holes filled (this module's docs, "Gaps"); 0 for most solids.
    pub mended: usize,
}

impl StepPart {
    /// Mesh volume over exact volume (1 is exact; a chordal mesh of convex curved
    /// faces is slightly below 1).
    pub fn volume_ratio(&self) -> f64 {
        self.mesh.signed_volume() / self.exact_volume
    }
}

/// A placed solid: a component of the assembly.
#[derive(Debug, Clone)]
pub struct StepInstance {
    /// The component's name in the assembly (the instance name, else the product's).
    pub name: String,
    /// Its names from the root of the assembly tree, `/`-separated (where errors point).
    pub path: String,
    /// Index into [`StepModel::parts`].
    pub part: usize,
    /// Its pose: part frame → world (the file's root frame), mm.
    pub transform: Transform,
    /// The assembly occurrence holding it (index into [`StepModel::assemblies`]);
    /// `None` for a free shape outside any assembly.
    pub parent: Option<usize>,
}

/// A placed assembly: the root of the tree, or an occurrence of a sub-assembly.
#[derive(Debug, Clone)]
pub struct StepAssembly {
    /// The occurrence's name (the instance name, else the product's; the root's
    /// product name for a root).
    pub name: String,
    /// Its names from the root, `/`-separated.
    pub path: String,
    /// The assembly product's name.
    pub product: String,
    /// The assembly holding it (an index below its own into
    /// [`StepModel::assemblies`]); `None` for a root.
    pub parent: Option<usize>,
    /// Its pose: assembly frame → world (the file's root frame), mm.
    pub transform: Transform,
}

/// Where the time of a read went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepTimings {
    /// Open CASCADE parsing the file (`ReadFile`).
    pub parse: Duration,
    /// Open CASCADE building the B-rep and assembly tree (`Transfer`).
    pub transfer: Duration,
    /// Tessellation (`BRepMesh_IncrementalMesh`).
    pub mesh: Duration,
    /// The whole [`read_step`] call, checks, welding and the child process included.
    pub total: Duration,
}

/// What [`read_step`] read.
#[derive(Debug, Clone)]
pub struct StepModel {
    /// The file.
    pub path: PathBuf,
    /// Distinct solids.
    pub parts: Vec<StepPart>,
    /// Placed solids, in the order of the assembly tree.
    pub instances: Vec<StepInstance>,
    /// Placed assemblies (roots and sub-assembly occurrences), each listed before
    /// everything it holds.
    pub assemblies: Vec<StepAssembly>,
    /// The file's length unit as it names it (`MM`, `INCH`, `M`, …); lengths here are mm.
    pub file_unit: String,
    /// The options it was meshed with.
    pub options: StepOptions,
    /// Where the time went (of the read that made a stored tessellation, when
    /// `from_store`).
    pub timings: StepTimings,
    /// The child reader's peak resident memory (bytes), when the read ran in a child.
    pub reader_peak_memory: Option<u64>,
    /// Whether Open CASCADE's result came from the tessellation store
    /// ([`read_step_stored`]) instead of a read.
    pub from_store: bool,
}

impl StepModel {
    /// Every placed solid's mesh at its placement, as one mesh in the file's root frame
    /// (mm): a `step:` part's geometry. Each solid stays closed, so the whole is closed.
    ///
    /// # Errors
    /// [`StepError::TooManyPlaced`]: the placed solids together have more than
    /// [`MAX_TRIANGLES`](crate::mesh::MAX_TRIANGLES) triangles (counted before
    /// anything is allocated: one small solid placed 100,000 times is refused, not
    /// copied).
    pub fn placed_mesh(&self) -> Result<Mesh, StepError> {
        let triangles: u64 = self
            .instances
            .iter()
            .map(|i| self.parts[i.part].mesh.triangles.len() as u64)
            .sum();
        let vertices: u64 = self
            .instances
            .iter()
            .map(|i| self.parts[i.part].mesh.vertices.len() as u64)
            .sum();
        let cap = crate::mesh::MAX_TRIANGLES;
        if triangles > cap as u64 || vertices > 3 * cap as u64 {
            return Err(StepError::TooManyPlaced {
                path: self.path.clone(),
                instances: self.instances.len(),
                triangles,
                cap,
            });
        }
        let mut all = Mesh {
            vertices: Vec::with_capacity(vertices as usize),
            triangles: Vec::with_capacity(triangles as usize),
        };
        for inst in &self.instances {
            all.append(&self.parts[inst.part].mesh.transformed(&inst.transform));
        }
        Ok(all)
    }

    /// The exact volume of every placed solid together, mm³.
    pub fn placed_exact_volume(&self) -> f64 {
        self.instances
            .iter()
            .map(|i| self.parts[i.part].exact_volume)
            .sum()
    }
}

/// What Open CASCADE was doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum StepStage {
    /// Parsing the file, or an unknown stage (a child killed from outside).
    Reading,
    /// Building the B-rep and the assembly tree.
    Transferring,
    /// Tessellating.
    Meshing,
}

impl std::fmt::Display for StepStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StepStage::Reading => "reading the file",
            StepStage::Transferring => "transferring the B-rep",
            StepStage::Meshing => "meshing",
        })
    }
}

/// What went wrong inside Open CASCADE (or fitup's shim around it).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OcctFailure {
    /// `ReadFile` failed: not ISO 10303-21 that Open CASCADE can parse.
    #[error("not a STEP file Open CASCADE can parse (ISO 10303-21)")]
    Parse,
    /// `Transfer` failed: no shapes could be built from the entities.
    #[error("Open CASCADE could not transfer the file's shapes")]
    Transfer,
    /// The meshes passed [`StepOptions::max_triangles`].
    #[error("more than {cap} triangles: raise --deflection for a coarser mesh")]
    TooManyTriangles {
        /// The cap.
        cap: u64,
    },
    /// The assembly tree is nested deeper than 64 levels.
    #[error("assembly nested deeper than 64 levels at `{at}`")]
    TooDeep {
        /// The assembly path where it stopped.
        at: String,
    },
    /// An allocation failed (in a child reader: its memory cap).
    #[error("out of memory")]
    OutOfMemory,
    /// One of Open CASCADE's exceptions.
    #[error("Open CASCADE failed: {kind}{}", if detail.is_empty() { String::new() } else { format!(": {detail}") })]
    Exception {
        /// The exception's class (`Standard_NullObject`, …).
        kind: String,
        /// Its own message (may be empty).
        detail: String,
    },
}

/// Why a child reader gave no answer.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ChildFailure {
    /// The program could not be started.
    #[error("cannot start the reader `{}`: {kind}", program.display())]
    Spawn {
        /// The program.
        program: PathBuf,
        /// The operating system's answer.
        kind: std::io::ErrorKind,
    },
    /// It exited with a failure code without an answer.
    #[error("the reader exited with code {code} without an answer")]
    Exit {
        /// Its exit code.
        code: i32,
    },
    /// Its answer was missing or malformed (a program that does not serve
    /// [`CHILD_COMMAND`]).
    #[error("the reader's answer is {what} (is `{}` a fitup that serves `{CHILD_COMMAND}`?)", program.display())]
    BadReply {
        /// The program.
        program: PathBuf,
        /// What is wrong with it.
        what: &'static str,
    },
    /// A temporary file for its answer could not be made or read.
    #[error("cannot exchange the reader's answer through a temporary file: {kind}")]
    Io {
        /// The operating system's answer.
        kind: std::io::ErrorKind,
    },
}

/// Why a STEP file could not be read. Every variant names the file; those about one
/// solid name it by its place in the assembly tree.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    /// This build has no STEP reader.
    #[error("{}: reading STEP needs fitup built with the `step` feature: rebuild with `cargo install --path . --features step` (it links Open CASCADE: `apt-get install libocct-data-exchange-dev libocct-modeling-algorithms-dev`), or export the parts as STL", path.display())]
    NotBuilt {
        /// The file asked for.
        path: PathBuf,
    },
    /// The file could not be read (missing, not a regular file, over the size cap).
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: ReadError,
    },
    /// Not a STEP file: it does not begin with `ISO-10303-21;`.
    #[error("{}:1: not a STEP file: it does not begin with `ISO-10303-21;`", path.display())]
    NotStep {
        /// The file.
        path: PathBuf,
    },
    /// An option out of range.
    #[error("{what} must be finite and > 0 (got {value})")]
    Option {
        /// Which option.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// The path is not UTF-8 (Open CASCADE takes UTF-8 paths).
    #[error("{}: the path is not UTF-8 (Open CASCADE takes UTF-8 paths): rename the file", path.display())]
    NonUtf8Path {
        /// The file.
        path: PathBuf,
    },
    /// Open CASCADE failed.
    #[error("{}: {failure}", path.display())]
    Occt {
        /// The file.
        path: PathBuf,
        /// What failed.
        failure: OcctFailure,
    },
    /// The read passed its time limit.
    #[error("{}: time limit of {:.1} s reached while {stage}: raise --time-limit-s, or the file is hostile", path.display(), limit.as_secs_f64())]
    TimeLimit {
        /// The file.
        path: PathBuf,
        /// The limit.
        limit: Duration,
        /// Where it stopped.
        stage: StepStage,
    },
    /// The child reader ran out of its memory cap.
    #[error("{}: Open CASCADE ran out of memory reading it (the reader's cap is {} MiB): raise --memory-limit-mb, or the file is hostile", path.display(), limit >> 20)]
    MemoryLimit {
        /// The file.
        path: PathBuf,
        /// The cap, bytes.
        limit: u64,
    },
    /// The child reader crashed (Open CASCADE on a malformed file).
    #[error("{}: Open CASCADE crashed reading it (signal {signal}{}); the file is malformed: export it again from CAD", path.display(), signal_name(*signal))]
    Crashed {
        /// The file.
        path: PathBuf,
        /// The signal that ended the reader.
        signal: i32,
    },
    /// The child reader gave no usable answer.
    #[error("{}: {failure}", path.display())]
    Child {
        /// The file.
        path: PathBuf,
        /// What happened.
        failure: ChildFailure,
    },
    /// No solid in the file (a surface model, wireframe or empty file).
    #[error("{}: the file holds no solid ({shells} shells and {faces} faces outside any solid): fitup needs closed solids to check interference; export solid bodies", path.display())]
    NoSolids {
        /// The file.
        path: PathBuf,
        /// Shells outside any solid.
        shells: u32,
        /// Faces outside any shell.
        faces: u32,
    },
    /// A shell outside any solid that is not closed (a surface body, or a solid with a
    /// face missing).
    #[error("{}: `{solid}` is not closed: an open shell ({count} in the file; a surface body, or a solid with a face missing): fitup needs closed solids", path.display())]
    OpenShell {
        /// The file.
        path: PathBuf,
        /// The product holding the first, by its place in the assembly tree.
        solid: String,
        /// How many open shells the file has.
        count: u32,
    },
    /// Faces of a solid that Open CASCADE could not tessellate.
    #[error("{}: solid `{solid}`: face {face} of {faces} did not mesh ({count} faces without triangles): the B-rep is broken there; repair it in CAD or try another --deflection", path.display())]
    UnmeshedFace {
        /// The file.
        path: PathBuf,
        /// The solid, by its place in the assembly tree.
        solid: String,
        /// The first face without triangles (1-based, in Open CASCADE's face order).
        face: u32,
        /// The solid's faces.
        faces: u32,
        /// How many did not mesh.
        count: u32,
    },
    /// A solid whose mesh is not closed or not consistently oriented (an open shell).
    #[error("{}: solid `{solid}` is not closed: its mesh has {boundary_edges} open, {non_manifold_edges} non-manifold and {misoriented_edges} misoriented edges ({}); fitup needs closed solids", path.display(), gaps::open_solid_cause(*boundary_edges, *non_manifold_edges, *misoriented_edges))]
    OpenSolid {
        /// The file.
        path: PathBuf,
        /// The solid, by its place in the assembly tree.
        solid: String,
        /// Edges used by one triangle.
        boundary_edges: usize,
        /// Edges used by more than two.
        non_manifold_edges: usize,
        /// Edges traversed twice the same way.
        misoriented_edges: usize,
    },
    /// A placement that is not rigid (scaled or mirrored).
    #[error("{}: instance `{instance}` is placed with scale {scale}: only rigid placements (rotation and translation) are supported", path.display())]
    NotRigid {
        /// The file.
        path: PathBuf,
        /// The instance, by its place in the assembly tree.
        instance: String,
        /// The placement's scale factor (negative: mirrored).
        scale: f64,
    },
    /// The placed solids together (a `step:` part's one mesh,
    /// [`StepModel::placed_mesh`]) have more triangles than one mesh may hold.
    #[error("{}: its {instances} placed solids have {triangles} triangles together, more than one mesh may hold ({cap}, MAX_TRIANGLES): give a coarser `deflection:`, or import the assembly (`fitup import`: one component per solid)", path.display())]
    TooManyPlaced {
        /// The file.
        path: PathBuf,
        /// How many solids are placed.
        instances: usize,
        /// Their triangles together.
        triangles: u64,
        /// The cap ([`crate::mesh::MAX_TRIANGLES`]).
        cap: usize,
    },
    /// A placement whose matrix is not a rotation and translation.
    #[error("{}: instance `{instance}`: its placement is not a rigid motion", path.display())]
    BadPlacement {
        /// The file.
        path: PathBuf,
        /// The instance, by its place in the assembly tree.
        instance: String,
    },
    /// A mesh the shim returned was not valid (non-finite or out-of-range vertices).
    #[error("{}: solid `{solid}`: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// The solid.
        solid: String,
        /// Why.
        source: MeshError,
    },
}

/// ` SIGSEGV` and the like, for the signals a crash gives.
fn signal_name(signal: i32) -> &'static str {
    match signal {
        4 => ", SIGILL",
        6 => ", SIGABRT",
        7 => ", SIGBUS",
        8 => ", SIGFPE",
        9 => ", SIGKILL",
        11 => ", SIGSEGV",
        _ => "",
    }
}

/// Whether `path` names a STEP file by its extension (`.step`, `.stp`, any case).
pub fn is_step_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("step") || e.eq_ignore_ascii_case("stp"))
}

/// Why a STEP file cannot be a part's `stl:` mesh, and what to do instead.
pub fn not_a_part_mesh() -> String {
    let mut m = String::from(
        "a STEP file, not a mesh: name it with `step:` instead of `stl:` (tessellated when the document loads), or turn a whole assembly into a document with `fitup import FILE.step`",
    );
    if !AVAILABLE {
        m += " (this fitup was built without the `step` feature: rebuild with `cargo install --path . --features step`)";
    }
    m
}

fn check_options(options: &StepOptions) -> Result<(), StepError> {
    for (what, value) in [
        ("the linear deflection (mm)", options.linear_deflection),
        (
            "the angular deflection (radians)",
            options.angular_deflection,
        ),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(StepError::Option { what, value });
        }
    }
    Ok(())
}

/// Opens and checks the file before Open CASCADE sees it: a regular file within the
/// size cap that begins like a STEP file (so a mistaken path fails fast and clearly).
/// With `project`, the file is opened through the project's held root without
/// following a link ([`Project::open_file`]); without, by the path the caller named.
/// Returns the opened file (what Open CASCADE is handed: it never looks the path up
/// again) and its bytes (the store's key is their hash).
fn check_file(
    path: &Path,
    project: Option<&Project>,
) -> Result<(std::fs::File, Vec<u8>), StepError> {
    let read = |source| StepError::Read {
        path: path.into(),
        source,
    };
    let io = |e: std::io::Error| read(ReadError::Io(e.into()));
    let file = match project {
        Some(p) => p.open_file(path).map_err(io)?,
        None => {
            let md = std::fs::metadata(path).map_err(io)?;
            if !md.is_file() {
                return Err(read(ReadError::NotRegular(crate::fsutil::file_type_name(
                    &md,
                ))));
            }
            std::fs::File::open(path).map_err(io)?
        }
    };
    let bytes =
        crate::fsutil::read_opened(file.try_clone().map_err(io)?, FileKind::Step).map_err(read)?;
    let text = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(&bytes);
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    if !text[start..].starts_with(b"ISO-10303-21") {
        return Err(StepError::NotStep { path: path.into() });
    }
    Ok((file, bytes))
}

/// Reads a STEP file: its distinct solids meshed with `options`, its placed
/// instances, lengths in mm. Errors are located in the file and, for one solid, by its
/// place in the assembly tree; nothing is written.
pub fn read_step(path: &Path, options: &StepOptions) -> Result<StepModel, StepError> {
    let start = std::time::Instant::now();
    if !AVAILABLE {
        return Err(StepError::NotBuilt { path: path.into() });
    }
    check_options(options)?;
    let (file, bytes) = check_file(path, None)?;
    drop(bytes);
    let raw = read_raw(path, &file, options)?;
    from_raw(path, options, &raw, false, start)
}

/// [`read_step`] through the tessellation store in folder `store` (created when
/// missing): Open CASCADE's result for these bytes and this deflection and angle is
/// taken from there when present and sound, else read and kept there (written by the
/// write rule; a store that cannot be written only means the next read reads again).
///
/// With `project`, `path` (absolute, inside the project, as
/// [`Project::resolve_from`] returns it) is opened through the project's held root
/// without following a link, and Open CASCADE reads that opened file: a folder
/// swapped for a link after the path was checked is refused, never read outside.
pub fn read_step_stored(
    path: &Path,
    project: Option<&Project>,
    options: &StepOptions,
    store: &Path,
) -> Result<StepModel, StepError> {
    let start = std::time::Instant::now();
    if !AVAILABLE {
        return Err(StepError::NotBuilt { path: path.into() });
    }
    check_options(options)?;
    let (file, bytes) = check_file(path, project)?;
    let key = store::StoreKey::new(&bytes, options);
    drop(bytes);
    if let Some(raw) = store::load_stored(store, &key) {
        // A stored answer that does not make a model is the store's damage, not the
        // STEP file's: discarded, and the file read again.
        if let Ok(model) = from_raw(path, options, &raw, true, start) {
            return Ok(model);
        }
        drop(raw);
        store::discard(store, &key);
    }
    let raw = read_raw(path, &file, options)?;
    drop(file);
    // Only what makes a model is kept: an answer refused here (too many triangles, an
    // open solid) would otherwise be read whole from the store on every load, found
    // wanting and read again from the STEP file.
    let model = from_raw(path, options, &raw, false, start)?;
    store::store(store, &key, path, &raw, DEFAULT_STORE_CAP);
    Ok(model)
}

/// Open CASCADE's read of the opened `file` (whose name, `path`, is only for
/// messages), in this process or in a child: Open CASCADE opens it as
/// `/proc/self/fd/N` (the child gets it as its standard input), the same file
/// whatever is at `path` by now. (Without `/proc`, by `path`.)
fn read_raw(
    path: &Path,
    file: &std::fs::File,
    options: &StepOptions,
) -> Result<RawModel, StepError> {
    let utf8 = path
        .to_str()
        .ok_or_else(|| StepError::NonUtf8Path { path: path.into() })?;
    let by_fd = cfg!(unix) && Path::new("/proc/self/fd").is_dir();
    match &options.isolation {
        Isolation::InProcess => {
            #[cfg(unix)]
            let name = if by_fd {
                use std::os::fd::AsRawFd;
                format!("/proc/self/fd/{}", file.as_raw_fd())
            } else {
                utf8.to_string()
            };
            #[cfg(not(unix))]
            let name = utf8.to_string();
            shim::read(&name, options).map_err(|failure| shim::error(path, options, failure))
        }
        Isolation::Child(child) => {
            let given = if by_fd {
                Some(file.try_clone().map_err(|e| StepError::Child {
                    path: path.into(),
                    failure: ChildFailure::Io { kind: e.kind() },
                })?)
            } else {
                None
            };
            child::read_in_child(path, given, options, child)
        }
    }
}

/// Serves [`CHILD_COMMAND`]: `args` are what follows it on the command line. Reads the
/// file with Open CASCADE under the memory cap and writes the answer to the file the
/// parent named; returns the exit code. Only for programs that registered themselves
/// with [`read_in_child_processes`].
pub fn serve_child(args: &[std::ffi::OsString]) -> i32 {
    child::serve_child(args)
}

/// Checks what Open CASCADE returned and makes the model of it.
fn from_raw(
    path: &Path,
    options: &StepOptions,
    model: &RawModel,
    from_store: bool,
    start: std::time::Instant,
) -> Result<StepModel, StepError> {
    if model.instances.is_empty() {
        return Err(StepError::NoSolids {
            path: path.into(),
            shells: model.shells_without_solid,
            faces: model.faces_without_solid,
        });
    }
    if model.open_shells > 0 {
        return Err(StepError::OpenShell {
            path: path.into(),
            solid: model.first_open_shell.clone(),
            count: model.open_shells,
        });
    }
    // Where each part is first placed: how errors about the solid name it.
    let mut first_path = vec![String::new(); model.parts.len()];
    for inst in model.instances.iter().rev() {
        match first_path.get_mut(inst.part as usize) {
            Some(p) => p.clone_from(&inst.path),
            None => {
                return Err(StepError::BadPlacement {
                    path: path.into(),
                    instance: inst.path.clone(),
                })
            }
        }
    }
    let mut parts = Vec::with_capacity(model.parts.len());
    for (i, p) in model.parts.iter().enumerate() {
        let mut solid = first_path[i].clone();
        if p.solids_in_product > 1 {
            solid += &format!(" (solid {} of {})", p.solid_index, p.solids_in_product);
        }
        let (mesh, mended) = gaps::closed_mesh(path, options, p, solid)?;
        parts.push(StepPart {
            product: p.name.clone(),
            solid: (p.solid_index, p.solids_in_product),
            mesh,
            exact_volume: p.exact_volume,
            mended,
        });
    }
    let mut instances = Vec::with_capacity(model.instances.len());
    for inst in &model.instances {
        if !inst.scale.is_finite() || (inst.scale - 1.0).abs() > 1e-9 {
            return Err(StepError::NotRigid {
                path: path.into(),
                instance: inst.path.clone(),
                scale: inst.scale,
            });
        }
        let Some(transform) = pose(&inst.matrix) else {
            return Err(StepError::BadPlacement {
                path: path.into(),
                instance: inst.path.clone(),
            });
        };
        if inst.parent as usize > model.assemblies.len() {
            return Err(StepError::BadPlacement {
                path: path.into(),
                instance: inst.path.clone(),
            });
        }
        instances.push(StepInstance {
            name: inst.name.clone(),
            path: inst.path.clone(),
            part: inst.part as usize,
            transform,
            parent: (inst.parent as usize).checked_sub(1),
        });
    }
    let mut assemblies = Vec::with_capacity(model.assemblies.len());
    for (k, a) in model.assemblies.iter().enumerate() {
        if !a.scale.is_finite() || (a.scale - 1.0).abs() > 1e-9 {
            return Err(StepError::NotRigid {
                path: path.into(),
                instance: a.path.clone(),
                scale: a.scale,
            });
        }
        // Parents come first: an index at or past its own is a confused answer.
        let transform = pose(&a.matrix).filter(|_| a.parent as usize <= k);
        let Some(transform) = transform else {
            return Err(StepError::BadPlacement {
                path: path.into(),
                instance: a.path.clone(),
            });
        };
        assemblies.push(StepAssembly {
            name: a.name.clone(),
            path: a.path.clone(),
            product: a.product.clone(),
            parent: (a.parent as usize).checked_sub(1),
            transform,
        });
    }
    let secs = |s: f64| Duration::try_from_secs_f64(s.max(0.0)).unwrap_or_default();
    Ok(StepModel {
        path: path.into(),
        parts,
        instances,
        assemblies,
        file_unit: model.length_unit.clone(),
        options: options.clone(),
        timings: StepTimings {
            parse: secs(model.read_s),
            transfer: secs(model.transfer_s),
            mesh: secs(model.mesh_s),
            total: start.elapsed(),
        },
        reader_peak_memory: (model.peak_memory > 0).then_some(model.peak_memory),
        from_store,
    })
}

/// The shim's 3 × 4 row-major `[R | t]` (column vectors) as a [`Transform`]
/// (whose matrix is SolidWorks' row-vector layout: the transpose).
fn pose(m: &[f64]) -> Option<Transform> {
    if m.len() != 12 {
        return None;
    }
    let mut sw = [[0.0; 4]; 4];
    for (r, row) in m.chunks_exact(4).enumerate() {
        for (c, v) in row[..3].iter().enumerate() {
            sw[c][r] = *v;
        }
        sw[3][r] = row[3];
    }
    sw[3][3] = 1.0;
    Transform::from_matrix(&sw).ok()
}

/// Writes a STEP file made with Open CASCADE for the tests (`kind`: `box`,
/// `cylinder_hole`, `assembly`, `nested`, `inch_box`, `open_shell`, `no_solid`, `bad_face`,
/// `plate_holes`, `sphere`, `cone`); see `cpp/step_shim.cpp` for their shapes. Not a stable API.
#[doc(hidden)]
pub fn write_test_step(kind: &str, path: &Path) -> Result<(), StepError> {
    let utf8 = path
        .to_str()
        .ok_or_else(|| StepError::NonUtf8Path { path: path.into() })?;
    if !AVAILABLE {
        return Err(StepError::NotBuilt { path: path.into() });
    }
    shim::write_test(kind, utf8)
        .map_err(|failure| shim::error(path, &StepOptions::default(), failure))
}

#[cfg(test)]
mod tests;
