//! STEP (ISO 10303-21: AP203, AP214, AP242) assemblies as meshes, read by Open CASCADE
//! through fitup's C++ shim (`cpp/step_shim.cpp`, cargo feature `step`).
//!
//! [`read_step`] returns one [`StepPart`] per distinct solid (meshed once, in its own
//! frame, mm) and one [`StepInstance`] per placed solid of the assembly tree (its pose
//! part frame → world, mm). Lengths are converted to mm whatever unit the file is in.
//! Every mesh is checked closed and consistently oriented, and its volume is compared
//! with the exact B-rep volume ([`StepPart::volume_ratio`]).
//!
//! Without the feature every call returns [`StepError::NotBuilt`], whose message says
//! how to rebuild.
//!
//! Bounds: the file must be at most [`FileKind::Step`]'s cap (64 MiB) — Open CASCADE
//! holds a model in about 10–30 times the file's size —, the transfer and the meshing
//! stop at [`StepOptions::time_limit`] (OCCT polls it through its progress indicator;
//! parsing, linear in the file's size, is bounded by the cap), and all meshes together
//! have at most [`StepOptions::max_triangles`]. The read runs in this process: OCCT's
//! own exceptions become [`StepError::Occt`].

use super::{Mesh, MeshError};
use crate::fsutil::{FileKind, ReadError};
use crate::math::Transform;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Default linear deflection of the tessellation: the largest distance between a
/// triangle and the exact surface, mm.
pub const DEFAULT_LINEAR_DEFLECTION: f64 = 0.1;

/// Default angular deflection of the tessellation: the largest angle between the
/// normals of neighbouring triangles on a curved face, radians (OCCT's default, ≈ 28.6°).
pub const DEFAULT_ANGULAR_DEFLECTION: f64 = 0.5;

/// Whether this build reads STEP files (the `step` feature).
pub const AVAILABLE: bool = cfg!(feature = "step");

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
}

impl Default for StepOptions {
    fn default() -> Self {
        StepOptions {
            linear_deflection: DEFAULT_LINEAR_DEFLECTION,
            angular_deflection: DEFAULT_ANGULAR_DEFLECTION,
            time_limit: Duration::from_secs(300),
            max_triangles: 20_000_000,
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
    /// The whole [`read_step`] call, checks and welding included.
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
    /// The file's length unit as it names it (`MM`, `INCH`, `M`, …); lengths here are mm.
    pub file_unit: String,
    /// The options it was meshed with.
    pub options: StepOptions,
    /// Where the time went.
    pub timings: StepTimings,
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
    /// Open CASCADE failed (its exception, a parse failure, the time limit, the
    /// triangle cap).
    #[error("{}: {message}", path.display())]
    Occt {
        /// The file.
        path: PathBuf,
        /// What Open CASCADE or the shim said.
        message: String,
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
    #[error("{}: solid `{solid}` is not closed: its mesh has {boundary_edges} open, {non_manifold_edges} non-manifold and {misoriented_edges} misoriented edges (an open shell or a gap between faces); fitup needs closed solids", path.display())]
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

/// Whether `path` names a STEP file by its extension (`.step`, `.stp`, any case).
pub fn is_step_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("step") || e.eq_ignore_ascii_case("stp"))
}

/// Why a STEP file cannot be a part's `stl:` mesh, and what to do instead.
pub fn not_a_part_mesh() -> String {
    let mut m = String::from(
        "a STEP file, not an STL mesh: a part cannot name a STEP file yet; turn it into a document with `fitup import FILE.step`",
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

/// Checks the file before Open CASCADE sees it: a regular file within the size cap
/// that begins like a STEP file (so a mistaken path fails fast and clearly).
fn check_file(path: &Path) -> Result<(), StepError> {
    let bytes =
        crate::fsutil::read_file(path, FileKind::Step).map_err(|source| StepError::Read {
            path: path.into(),
            source,
        })?;
    let text = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(&bytes);
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    if !text[start..].starts_with(b"ISO-10303-21") {
        return Err(StepError::NotStep { path: path.into() });
    }
    Ok(())
}

/// Reads a STEP file: its distinct solids meshed with `options`, its placed
/// instances, lengths in mm. Errors are located in the file and, for one solid, by its
/// place in the assembly tree; nothing is written.
pub fn read_step(path: &Path, options: &StepOptions) -> Result<StepModel, StepError> {
    if !AVAILABLE {
        return Err(StepError::NotBuilt { path: path.into() });
    }
    check_options(options)?;
    check_file(path)?;
    imp::read(path, options)
}

/// Writes a STEP file made with Open CASCADE for the tests (`kind`: `box`,
/// `cylinder_hole`, `assembly`, `inch_box`, `open_shell`, `no_solid`); see
/// `cpp/step_shim.cpp` for their shapes. Not a stable API.
#[doc(hidden)]
pub fn write_test_step(kind: &str, path: &Path) -> Result<(), StepError> {
    imp::write_test(kind, path)
}

#[cfg(feature = "step")]
mod imp {
    use super::*;
    use crate::math::Point3;
    use crate::mesh::step_ffi::ffi;
    use std::sync::Mutex;
    use std::time::Instant;

    /// Open CASCADE's reader settings are process-wide (`Interface_Static`): one read
    /// or write at a time.
    static OCCT: Mutex<()> = Mutex::new(());

    fn occt_err(path: &Path, e: cxx::Exception) -> StepError {
        StepError::Occt {
            path: path.into(),
            message: e.what().to_string(),
        }
    }

    fn utf8(path: &Path) -> Result<&str, StepError> {
        path.to_str().ok_or_else(|| StepError::Occt {
            path: path.into(),
            message: "the path is not UTF-8 (Open CASCADE takes UTF-8 paths)".into(),
        })
    }

    pub(super) fn read(path: &Path, options: &StepOptions) -> Result<StepModel, StepError> {
        let start = Instant::now();
        let opts = ffi::ReadOptions {
            linear_deflection: options.linear_deflection,
            angular_deflection: options.angular_deflection,
            time_limit_s: options.time_limit.as_secs_f64(),
            max_triangles: options.max_triangles,
        };
        let model = {
            let _one = OCCT.lock().unwrap_or_else(|e| e.into_inner());
            ffi::read_step(utf8(path)?, &opts).map_err(|e| occt_err(path, e))?
        };
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
                solid: model.first_open_shell,
                count: model.open_shells,
            });
        }
        // Where each part is first placed: how errors about the solid name it.
        let mut first_path = vec![String::new(); model.parts.len()];
        for inst in model.instances.iter().rev() {
            if let Some(p) = first_path.get_mut(inst.part as usize) {
                p.clone_from(&inst.path);
            }
        }
        let mut parts = Vec::with_capacity(model.parts.len());
        for (i, p) in model.parts.into_iter().enumerate() {
            let mut solid = first_path[i].clone();
            if p.solids_in_product > 1 {
                solid += &format!(" (solid {} of {})", p.solid_index, p.solids_in_product);
            }
            if p.unmeshed_faces > 0 {
                return Err(StepError::UnmeshedFace {
                    path: path.into(),
                    solid,
                    face: p.first_unmeshed_face,
                    faces: p.faces,
                    count: p.unmeshed_faces,
                });
            }
            let mesh = weld(&p.vertices, &p.triangles).map_err(|source| StepError::Mesh {
                path: path.into(),
                solid: solid.clone(),
                source,
            })?;
            let report = mesh.inspect();
            if mesh.triangles.is_empty() || !report.is_watertight() {
                return Err(StepError::OpenSolid {
                    path: path.into(),
                    solid,
                    boundary_edges: report.boundary_edges,
                    non_manifold_edges: report.non_manifold_edges,
                    misoriented_edges: report.misoriented_edges,
                });
            }
            parts.push(StepPart {
                product: p.name,
                solid: (p.solid_index, p.solids_in_product),
                mesh,
                exact_volume: p.exact_volume,
            });
        }
        let mut instances = Vec::with_capacity(model.instances.len());
        for inst in model.instances {
            if (inst.scale - 1.0).abs() > 1e-9 {
                return Err(StepError::NotRigid {
                    path: path.into(),
                    instance: inst.path,
                    scale: inst.scale,
                });
            }
            let transform = pose(&inst.matrix).ok_or_else(|| StepError::Occt {
                path: path.into(),
                message: format!(
                    "instance `{}`: its placement is not a rigid motion",
                    inst.path
                ),
            })?;
            instances.push(StepInstance {
                name: inst.name,
                path: inst.path,
                part: inst.part as usize,
                transform,
            });
        }
        Ok(StepModel {
            path: path.into(),
            parts,
            instances,
            file_unit: model.length_unit,
            options: options.clone(),
            timings: StepTimings {
                parse: Duration::from_secs_f64(model.read_s.max(0.0)),
                transfer: Duration::from_secs_f64(model.transfer_s.max(0.0)),
                mesh: Duration::from_secs_f64(model.mesh_s.max(0.0)),
                total: start.elapsed(),
            },
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

    /// Face meshes side by side → one indexed mesh: the nodes OCCT puts on an edge
    /// are the same points on both faces, so merging identical vertices closes it.
    fn weld(vertices: &[f64], triangles: &[u32]) -> Result<Mesh, MeshError> {
        let n = vertices.len() / 3;
        let point = |i: u32| -> Result<Point3, MeshError> {
            let i = i as usize;
            if i >= n {
                return Err(MeshError::invalid(format!(
                    "a triangle refers to vertex {i} of {n}"
                )));
            }
            let p = Point3::new(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
            let ok = |v: f64| v.is_finite() && v.abs() <= crate::math::MAX_ABS_VALUE;
            if !(ok(p.x) && ok(p.y) && ok(p.z)) {
                return Err(MeshError::invalid(format!(
                    "vertex {i} is not finite or beyond {:e} mm",
                    crate::math::MAX_ABS_VALUE
                )));
            }
            Ok(p)
        };
        let soup = triangles
            .chunks_exact(3)
            .map(|t| Ok([point(t[0])?, point(t[1])?, point(t[2])?]))
            .collect::<Result<Vec<_>, MeshError>>()?;
        Mesh::from_triangle_soup(soup)
    }

    pub(super) fn write_test(kind: &str, path: &Path) -> Result<(), StepError> {
        let _one = OCCT.lock().unwrap_or_else(|e| e.into_inner());
        ffi::write_test_step(kind, utf8(path)?).map_err(|e| occt_err(path, e))
    }
}

#[cfg(not(feature = "step"))]
mod imp {
    use super::*;

    pub(super) fn read(path: &Path, _: &StepOptions) -> Result<StepModel, StepError> {
        Err(StepError::NotBuilt { path: path.into() })
    }

    pub(super) fn write_test(_: &str, path: &Path) -> Result<(), StepError> {
        Err(StepError::NotBuilt { path: path.into() })
    }
}
