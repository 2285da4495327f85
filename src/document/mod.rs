//! The assembly document: parts (STL meshes + reference geometry), components (part
//! instances at a pose), mates and their driving dimensions.
//!
//! A document is a YAML file (schema in [`file`]); meshes are STL files next to it.
//! Lengths are millimetres, angles radians inside; the file writes angle mate values in
//! degrees. Poses use the SolidWorks pose-matrix layout, see [`Transform`].
//!
//! # Examples
//!
//! Seed 000's macro `swDim.SystemValue = ang * PI / 180`, from Rust: drive the angle
//! mate `D1@角度1` of the bundled cell and read the plate's pose the mates give.
//!
//! ```
//! use fitup::document::Document;
//! use fitup::math::AngleConvention;
//!
//! let mut doc = Document::open(std::path::Path::new("models/cell.yaml"))?;
//! assert!(doc.component("table")?.fixed);
//! doc.set_dimension("D1@角度1", 30f64.to_radians())?; // internal units: radians
//! let angle = doc.dimension("D1@角度1")?;
//! assert!((angle.document_value() - 30.0).abs() < 1e-9); // the file's degrees
//! assert!((angle.system_value() - 30f64.to_radians()).abs() < 1e-12); // SI, as SolidWorks
//! let plate = doc.component("plate_b")?.transform;
//! let c = plate.to_xyzabc_deg(AngleConvention::XyzFixed)[5]; // about world Z, degrees
//! assert!((c - 30.0).abs() < 1e-6);
//! # Ok::<(), fitup::document::DocumentError>(())
//! ```

pub mod dimension;
mod export;
pub mod file;
pub mod import;
pub mod mates;
pub mod reference;
pub mod robot;
pub mod scan;
pub mod tessellations;
pub use export::GlbExport;

pub use dimension::{Dimension, DimensionKind, DimensionTarget};
pub use mates::{Mate, MateEntity, MateKind};
pub use reference::Reference;
pub use robot::{LinkDisplay, RobotError, RobotInstance};
pub use scan::MAX_ABS_VALUE;

use crate::collision::CutSpec;
use crate::diagnostics::{locate, suggestion, SourceError};
use crate::fsutil::{content_hash, FileKind};
use crate::math::{Aabb, Transform, Vec3};
use crate::mesh::{Mesh, MeshCache};
use crate::project::Project;
use file::{
    AxisFile, ComponentFile, DocumentFile, FeatureFile, MateFile, PartFile, PlaneFile, PlanesFile,
};
use indexmap::IndexMap;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A part definition: mesh and named references in the part frame (mm).
#[derive(Debug, Clone)]
pub struct Part {
    /// Part name.
    pub name: String,
    /// The geometry file's path as written in the document (relative to the
    /// document's folder): the `stl:` mesh, or the `step:` file of a STEP part.
    pub stl: String,
    /// That file resolved on disk.
    pub mesh_path: PathBuf,
    /// The other files its mesh was read from (a `.gltf`'s buffers), on disk.
    pub mesh_files: Vec<PathBuf>,
    /// For a `step:` part, how it was tessellated (`None`: an `stl:` mesh).
    pub step: Option<StepGeometry>,
    /// The triangle mesh (mm, part frame).
    pub mesh: Arc<Mesh>,
    /// Named references (planes, axes, points) in the part frame, in file order.
    pub references: IndexMap<String, Reference>,
    /// The feature tree, in order.
    pub features: Vec<Feature>,
}

/// A feature of a part's feature tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Feature {
    /// Seed 000's cut cells: the part cut by plane arrays into cells, one box each.
    /// The cells themselves are derived from the mesh when needed (and again when the
    /// mesh changes), see [`crate::workspace::SceneCache`].
    CutCells {
        /// Feature name.
        name: String,
        /// How the part is cut.
        spec: CutSpec,
    },
}

impl Feature {
    /// The feature's name.
    pub fn name(&self) -> &str {
        match self {
            Feature::CutCells { name, .. } => name,
        }
    }

    fn from_file(f: &FeatureFile) -> Result<Feature, String> {
        match f {
            FeatureFile::CutCells {
                name,
                cell_size,
                planes,
            } => {
                let spec = match (cell_size, planes) {
                    (Some(s), None) if s.is_finite() && *s > 0.0 => CutSpec::Size(*s),
                    (Some(s), None) => {
                        return Err(format!(
                            "cut cells `{name}`: cell_size must be a number > 0 mm, not {s}"
                        ))
                    }
                    (None, Some(p)) => {
                        if p.x.iter().chain(&p.y).chain(&p.z).any(|v| !v.is_finite()) {
                            return Err(format!(
                                "cut cells `{name}`: plane positions must be finite"
                            ));
                        }
                        CutSpec::Planes {
                            x: p.x.clone(),
                            y: p.y.clone(),
                            z: p.z.clone(),
                        }
                    }
                    _ => {
                        return Err(format!(
                            "cut cells `{name}`: give exactly one of `cell_size` and `planes`"
                        ))
                    }
                };
                Ok(Feature::CutCells {
                    name: name.clone(),
                    spec,
                })
            }
        }
    }

    fn to_file(&self) -> FeatureFile {
        match self {
            Feature::CutCells {
                name,
                spec: CutSpec::Size(s),
            } => FeatureFile::CutCells {
                name: name.clone(),
                cell_size: Some(*s),
                planes: None,
            },
            Feature::CutCells {
                name,
                spec: CutSpec::Planes { x, y, z },
            } => FeatureFile::CutCells {
                name: name.clone(),
                cell_size: None,
                planes: Some(PlanesFile {
                    x: x.clone(),
                    y: y.clone(),
                    z: z.clone(),
                }),
            },
        }
    }
}

/// How a `step:` part's STEP file was tessellated.
#[derive(Debug, Clone, PartialEq)]
pub struct StepGeometry {
    /// `deflection:` as written (mm), if given.
    pub deflection: Option<f64>,
    /// `angle:` as written (degrees), if given.
    pub angle: Option<f64>,
    /// Mesh volume over the exact B-rep volume of the solids.
    pub volume_ratio: f64,
    /// Whether Open CASCADE's result came from the project's tessellation store
    /// ([`crate::mesh::step::STEP_STORE`]) instead of a read.
    pub from_store: bool,
}

impl Part {
    /// A reference by name, including the built-ins (`origin`, `front`, `top`, `right`,
    /// `x_axis`, `y_axis`, `z_axis`).
    pub fn reference(&self, name: &str) -> Option<Reference> {
        let name = &*nfc_name(name);
        self.references
            .get(name)
            .copied()
            .or_else(|| Reference::builtin(name))
    }
}

/// An RGB colour, components in 0..1.
pub type Color = [f64; 3];

/// A part instance at a pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Unique name.
    pub name: String,
    /// The part it instantiates.
    pub part: String,
    /// Never moved by mates or planners.
    pub fixed: bool,
    /// Display colour.
    pub color: Option<Color>,
    /// Pose: part frame → world (mm).
    pub transform: Transform,
    /// Mass in kg when the document gives one (finite, > 0).
    pub mass: Option<f64>,
    /// Screwed in (its assembly task is a `screw` operation).
    pub threaded: bool,
    /// Not part of the product (a fixture, the table): sequence planning leaves it
    /// out (document key `fixture: true`).
    pub fixture: bool,
}

/// Why a document operation failed. Load errors carry file, line and column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DocumentError {
    /// An error in a file the user wrote (YAML, STL, …), located.
    #[error("{0}")]
    Source(#[from] SourceError),
    /// A name that does not exist; the message lists close matches.
    #[error("no {what} named `{name}`: {hint}")]
    NotFound {
        /// "component", "dimension", …
        what: &'static str,
        /// The name asked for.
        name: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// An operation a lower layer refused, in its words (a robot definition, the
    /// mates' solver, a GLB export).
    #[error("{0}")]
    Invalid(String),
    /// Fixed components do not move.
    #[error("component `{0}` is fixed; set `fixed: false` to move it")]
    FixedComponent(String),
    /// A robot's links move with its joints, not on their own.
    #[error("component `{component}` is a link of robot `{robot}`: set the robot's joints (or base) to move it")]
    RobotLink {
        /// The component asked to move.
        component: String,
        /// The robot that drives it.
        robot: String,
    },
    /// A value out of range for what it sets.
    #[error("{what}: {value} is out of range: {rule}")]
    OutOfRange {
        /// What was set (a dimension's full name, a pose, cut cells `name`).
        what: String,
        /// The value given (document units: mm or degrees; a pose as text).
        value: String,
        /// What is accepted.
        rule: &'static str,
    },
    /// A new robot's name is empty or taken.
    #[error("robot names must be unique and non-empty: `{0}`")]
    RobotName(String),
    /// A new robot would add a dimension that exists.
    #[error("robot `{robot}`: dimension `{dimension}` already exists")]
    DimensionTaken {
        /// The robot being added.
        robot: String,
        /// The dimension's full name.
        dimension: String,
    },
    /// A name with a control or invisible character (they hide or reorder what is
    /// shown).
    #[error("{what} name `{name}`: {character} is not allowed in names (control and invisible characters hide or reorder what is shown)")]
    HiddenCharacter {
        /// What is named (`robot`, …).
        what: String,
        /// The name, printable.
        name: String,
        /// The character, described.
        character: String,
    },
    /// `save_as` onto one of the document's own meshes.
    #[error("refusing to save over {}: it is the mesh of part `{part}`", .path.display())]
    OverMesh {
        /// The target path.
        path: PathBuf,
        /// The part whose mesh it is.
        part: String,
    },
    /// A robot refused an operation (kinematics, joint limits, program).
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// Writing the document failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// Target path.
        path: PathBuf,
        /// OS message.
        message: String,
    },
}

/// An assembly document.
#[derive(Debug, Clone)]
pub struct Document {
    path: PathBuf,
    description: Option<String>,
    parts: IndexMap<String, Part>,
    components: Vec<Component>,
    by_name: HashMap<String, usize>,
    mates: Vec<Mate>,
    robots: Vec<RobotInstance>,
    /// Parts (and their components, same name) made from `urdf:` robots' link meshes:
    /// derived data, not written by `save`.
    generated: std::collections::HashSet<String>,
    revision: u64,
    aabb_cache: AabbCache,
    /// Hash of the file's bytes when it was loaded or last saved: a save refuses to
    /// overwrite a file that changed on disk since (another writer's edits).
    disk_hash: Option<u64>,
    /// Located warnings of the load (names that differ only by case).
    warnings: Vec<String>,
}

/// A rotation and the box of a mesh rotated by it (mm).
type RotatedBox = (nalgebra::UnitQuaternion<f64>, Aabb);

/// Per component: the rotation last seen and the box of the mesh rotated by it.
#[derive(Debug, Default)]
struct AabbCache(std::sync::Mutex<Vec<Option<RotatedBox>>>);

impl Clone for AabbCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

fn parse_color(v: &serde_yaml::Value) -> Option<Color> {
    match v {
        serde_yaml::Value::String(s) => {
            let h = s.strip_prefix('#')?;
            if h.len() != 6 {
                return None;
            }
            let c = |i: usize| {
                u8::from_str_radix(&h[i..i + 2], 16)
                    .ok()
                    .map(|x| x as f64 / 255.0)
            };
            Some([c(0)?, c(2)?, c(4)?])
        }
        serde_yaml::Value::Sequence(s) if s.len() == 3 => {
            let mut out = [0.0; 3];
            for (o, x) in out.iter_mut().zip(s) {
                *o = x.as_f64()?;
                if !(0.0..=1.0).contains(o) {
                    return None;
                }
            }
            Some(out)
        }
        _ => None,
    }
}

fn color_value(c: &Color) -> serde_yaml::Value {
    let h = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    serde_yaml::Value::String(format!("#{:02x}{:02x}{:02x}", h(c[0]), h(c[1]), h(c[2])))
}

/// Snaps round-off (|x| < 1e-14 → 0) so saved matrices read cleanly; idempotent.
fn tidy(x: f64) -> f64 {
    if x.abs() < 1e-14 {
        0.0
    } else {
        x
    }
}

impl Document {
    /// Loads a document and its meshes (through `cache`, so unchanged meshes are not
    /// re-read), validates it and solves its mates.
    ///
    /// The project (which bounds its mesh paths) is found by the path rule of
    /// [`Project::for_file`]: the nearest folder holding `fitup.toml`, else the
    /// document's folder.
    pub fn load(path: &Path, cache: &mut MeshCache) -> Result<Self, DocumentError> {
        let project = Project::for_file(path)
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot read the document: {e}")))?;
        Self::load_in(path, &project, cache)
    }

    /// Loads a document whose meshes must lie inside `project` (a mesh path leading
    /// outside it is refused at its `stl:` line, and the outside file is never opened).
    pub fn load_in(
        path: &Path,
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        let text = crate::fsutil::read_text(path, FileKind::Document)
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot read the document: {e}")))?;
        let mut doc = Self::from_yaml_in(&text, path, project, cache)?;
        doc.disk_hash = Some(content_hash(text.as_bytes()));
        Ok(doc)
    }

    /// Loads a document with a private mesh cache.
    ///
    /// # Examples
    /// Drive a mate's dimension (internal units: radians) and read the driven pose
    /// (world frame, mm):
    /// ```
    /// use fitup::document::Document;
    ///
    /// let mut doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
    /// doc.set_dimension("D1@角度1", 30f64.to_radians()).unwrap();
    /// let angle = doc.dimension("D1@角度1").unwrap();
    /// assert!((angle.document_value() - 30.0).abs() < 1e-9); // degrees in the file
    /// let plate = doc.component("plate_b").unwrap();
    /// assert!(plate.transform.translation().z > 700.0); // on the table, mm
    /// ```
    ///
    /// # Errors
    /// The file cannot be read, is not a valid document (located [`SourceError`]),
    /// or its mates cannot be solved.
    pub fn open(path: &Path) -> Result<Self, DocumentError> {
        Self::load(path, &mut MeshCache::new())
    }

    /// Builds a document from YAML text; `path` names the file in messages and anchors
    /// relative mesh paths (which must stay inside the folder [`Project::for_file`]
    /// finds for `path`, or `path`'s folder when `path` does not exist).
    pub fn from_yaml(
        text: &str,
        path: &Path,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        let project = Project::for_file(path)
            .or_else(|_| Project::new(path.parent().unwrap_or(Path::new("."))))
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot resolve its folder: {e}")))?;
        Self::from_yaml_in(text, path, &project, cache)
    }

    /// Parses and checks document text without loading meshes: the checks of
    /// [`scan`] (aliases, duplicate keys, number ranges, empty files), then the schema.
    /// Errors are located in `path`.
    pub fn parse_text(
        text: &str,
        path: &Path,
    ) -> Result<(DocumentFile, scan::Positions), DocumentError> {
        let (file, positions): (DocumentFile, scan::Positions) =
            scan::from_yaml(text, path, "invalid document", scan::DOCUMENT_EMPTY)?;
        let file = if unicode_normalization::is_nfc(text) {
            file
        } else {
            nfc_file(file).map_err(|e| {
                SourceError::new(path, 0, 0, format!("invalid document after NFC: {e}"))
            })?
        };
        Ok((file, positions))
    }

    /// [`from_yaml`](Self::from_yaml) with meshes bounded by `project`.
    pub fn from_yaml_in(
        text: &str,
        path: &Path,
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        let (file, positions) = Self::parse_text(text, path)?;
        Self::from_file(file, text, path, project, &positions, cache)
    }

    fn from_file(
        file: DocumentFile,
        text: &str,
        path: &Path,
        project: &Project,
        positions: &scan::Positions,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        let at = |needle: &str, section: &str, message: String| -> DocumentError {
            let from = locate(text, &format!("{section}:"), 1)
                .map(|l| l.0)
                .unwrap_or(1);
            let (line, col) = locate(text, needle, from).unwrap_or((0, 0));
            SourceError::new(path, line, col, message).into()
        };
        if file.units != "mm" {
            return Err(at(
                "units",
                "units",
                format!(
                    "units `{}` are not supported: fitup documents are in mm",
                    file.units
                ),
            ));
        }
        let dir = std::path::absolute(path)
            .ok()
            .and_then(|p| p.parent().and_then(|d| d.canonicalize().ok()))
            .unwrap_or_else(|| project.root().to_path_buf());
        // every part's mesh read and parsed at once, in parallel (the cost of opening
        // a cell of many distinct parts); errors are reported by the loop below
        let resolved: Vec<_> = file
            .parts
            .values()
            .filter(|pf| pf.step.is_none())
            .filter_map(|pf| project.resolve_from(&dir, &pf.stl).ok())
            .collect();
        cache.prefetch_in(
            project,
            &resolved.iter().map(|p| p.as_path()).collect::<Vec<_>>(),
        );
        let mut parts = IndexMap::new();
        let mut warnings = Vec::new();
        for (name, pf) in &file.parts {
            let key = if pf.step.is_some() { "step" } else { "stl" };
            // The `stl:` (or `step:`) value's own line, from the scan.
            let stl_at = |message: String| -> DocumentError {
                let (line, col) = positions
                    .get(&format!("parts/{name}/{key}"))
                    .or_else(|| positions.get(&format!("parts/{name}")))
                    .unwrap_or((0, 0));
                SourceError::new(path, line, col, message).into()
            };
            let source = match (&pf.step, pf.stl.is_empty()) {
                (Some(step), true) => step,
                (None, false) => &pf.stl,
                (Some(_), false) => {
                    return Err(stl_at(format!(
                        "part `{name}`: give either `stl:` (a mesh file) or `step:` (a STEP file), not both"
                    )))
                }
                (None, true) => {
                    return Err(stl_at(format!(
                        "part `{name}` has no geometry: give `stl:` (a mesh file) or `step:` (a STEP file)"
                    )))
                }
            };
            if pf.step.is_none() && (pf.deflection.is_some() || pf.angle.is_some()) {
                return Err(stl_at(format!(
                    "part `{name}`: `deflection:` and `angle:` tessellate a `step:` part; an `stl:` mesh is used as it is"
                )));
            }
            let mesh_path = project.resolve_from(&dir, source).map_err(|e| {
                let what = if pf.step.is_some() {
                    "STEP file"
                } else {
                    "mesh"
                };
                stl_at(format!("part `{name}`: {what} {e}"))
            })?;
            let (mesh, mesh_files, step) = if pf.step.is_some() {
                let (mesh, geometry) = step_part(
                    pf,
                    &mesh_path,
                    &project.root().join(crate::mesh::step::STEP_STORE),
                    cache,
                )
                .map_err(|m| stl_at(format!("part `{name}`: {m}")))?;
                if (geometry.volume_ratio - 1.0).abs() > 0.015 {
                    let (line, col) = positions
                        .get(&format!("parts/{name}/step"))
                        .unwrap_or((0, 0));
                    warnings.push(format!(
                        "{}:{line}:{col}: part `{name}`: its mesh is {:.4} of the exact volume (more than 1.5 % off): set a smaller `deflection:`",
                        path.display(),
                        geometry.volume_ratio
                    ));
                }
                (mesh, Vec::new(), Some(geometry))
            } else {
                let mesh = cache
                    .get_in(project, &mesh_path)
                    .map_err(|e| stl_at(format!("part `{name}`: {e}")))?;
                (mesh, cache.files_of(&mesh_path), None)
            };
            let mut references = IndexMap::new();
            for (rname, p) in &pf.planes {
                let normal = vec3(p.normal).try_normalize(1e-12).ok_or_else(|| {
                    at(
                        rname,
                        "parts",
                        format!("plane `{rname}` of part `{name}` has a zero normal"),
                    )
                })?;
                references.insert(
                    rname.clone(),
                    Reference::Plane {
                        point: vec3(p.point).into(),
                        normal,
                    },
                );
            }
            for (rname, a) in &pf.axes {
                let direction = vec3(a.direction).try_normalize(1e-12).ok_or_else(|| {
                    at(
                        rname,
                        "parts",
                        format!("axis `{rname}` of part `{name}` has a zero direction"),
                    )
                })?;
                references.insert(
                    rname.clone(),
                    Reference::Axis {
                        point: vec3(a.point).into(),
                        direction,
                    },
                );
            }
            for (rname, p) in &pf.points {
                references.insert(rname.clone(), Reference::Point(vec3(*p).into()));
            }
            let mut features = Vec::new();
            for f in &pf.features {
                let feature = Feature::from_file(f).map_err(|m| {
                    at(
                        &format!("name: {}", feature_name(f)),
                        "parts",
                        format!("part `{name}`: {m}"),
                    )
                })?;
                if features
                    .iter()
                    .any(|g: &Feature| g.name() == feature.name())
                {
                    return Err(at(
                        &format!("name: {}", feature.name()),
                        "parts",
                        format!("part `{name}`: duplicate feature name `{}`", feature.name()),
                    ));
                }
                features.push(feature);
            }
            for (rname, r) in &references {
                let finite = r
                    .anchor()
                    .coords
                    .iter()
                    .chain(r.direction().unwrap_or_default().iter())
                    .all(|v| v.is_finite());
                if !finite {
                    return Err(at(
                        rname,
                        "parts",
                        format!("reference `{rname}` of part `{name}` is not finite"),
                    ));
                }
            }
            parts.insert(
                name.clone(),
                Part {
                    name: name.clone(),
                    stl: source.clone(),
                    mesh_path,
                    mesh_files,
                    step,
                    mesh,
                    references,
                    features,
                },
            );
        }
        let mut components = Vec::with_capacity(file.components.len());
        let mut by_name = HashMap::new();
        for (ci, c) in file.components.iter().enumerate() {
            let needle = format!("name: {}", c.name);
            // The name's own line from the scan (the text may spell it in NFD).
            let name_at = |message: String| -> DocumentError {
                let (line, col) = positions
                    .get(&format!("components/{ci}/name"))
                    .unwrap_or((0, 0));
                SourceError::new(path, line, col, message).into()
            };
            if c.name.is_empty() || c.name.contains('/') {
                return Err(name_at(format!(
                    "component name `{}` must be non-empty without `/`",
                    c.name
                )));
            }
            if let Some(first) = by_name.insert(c.name.clone(), components.len()) {
                let first_line = positions
                    .get(&format!("components/{first}/name"))
                    .map_or(String::new(), |(l, _)| format!(" (first at line {l})"));
                return Err(name_at(format!(
                    "duplicate component name `{}`{first_line}; names are compared in Unicode NFC, so two spellings of one name are the same",
                    c.name
                )));
            }
            if !parts.contains_key(&c.part) {
                return Err(at(
                    &format!("part: {}", c.part),
                    &needle,
                    format!("component `{}` uses unknown part `{}`", c.name, c.part),
                )
                .with_help(suggestion(&c.part, parts.keys().map(String::as_str))));
            }
            let transform = match &c.transform {
                None => Transform::IDENTITY,
                Some(m) if m.iter().flatten().any(|v| !v.is_finite() || v.abs() > MAX_ABS_VALUE) => {
                    return Err(at(
                        "transform",
                        &needle,
                        format!("component `{}`: pose entries must be finite and at most {MAX_ABS_VALUE:e} in magnitude", c.name),
                    ))
                }
                Some(m) => Transform::from_matrix(m).map_err(|e| {
                    let from = locate(text, &needle, 1).map(|l| l.0).unwrap_or(1);
                    let (line, col) = locate(text, "transform", from).unwrap_or((0, 0));
                    DocumentError::from(SourceError::new(
                        path,
                        line,
                        col,
                        format!("component `{}`: {e}", c.name),
                    ))
                })?,
            };
            let color = match &c.color {
                None => None,
                Some(v) => Some(parse_color(v).ok_or_else(|| {
                    at(
                        &needle,
                        "components",
                        format!(
                            "component `{}`: colour must be [r, g, b] in 0..1 or \"#rrggbb\"",
                            c.name
                        ),
                    )
                })?),
            };
            if let Some(m) = c.mass {
                if !(m.is_finite() && m > 0.0 && m <= MAX_ABS_VALUE) {
                    let from = locate(text, &needle, 1).map(|l| l.0).unwrap_or(1);
                    let (line, col) = locate(text, "mass", from).unwrap_or((0, 0));
                    return Err(SourceError::new(
                        path,
                        line,
                        col,
                        format!(
                            "component `{}`: mass must be a finite number of kg > 0, not {m}",
                            c.name
                        ),
                    )
                    .into());
                }
            }
            components.push(Component {
                name: c.name.clone(),
                part: c.part.clone(),
                fixed: c.fixed,
                color,
                transform,
                mass: c.mass,
                threaded: c.threaded,
                fixture: c.fixture,
            });
        }
        // URDF robots: their links' meshes become generated parts and components.
        let mut urdf = HashMap::new();
        let mut urdf_warnings: Vec<String> = Vec::new();
        let mut generated = std::collections::HashSet::new();
        for rf in &file.robots {
            let Some(u) = &rf.urdf else { continue };
            let robot_at = |m: String| {
                let from = locate(text, &format!("name: {}", rf.name), 1)
                    .map(|l| l.0)
                    .unwrap_or(1);
                let (line, col) = locate(text, "urdf:", from).unwrap_or((0, 0));
                DocumentError::from(SourceError::new(
                    path,
                    line,
                    col,
                    format!("robot `{}`: {m}", rf.name),
                ))
            };
            let loaded = robot::read_urdf_robot(project, &dir, u, rf.tip.as_deref(), cache)
                .map_err(robot_at)?;
            urdf_warnings.extend(loaded.warnings.iter().cloned());
            add_urdf_parts(
                &rf.name,
                u,
                &loaded,
                &mut parts,
                &mut components,
                &mut by_name,
                &mut generated,
            )
            .map_err(robot_at)?;
            urdf.insert(rf.name.clone(), loaded);
        }
        let mut doc = Document {
            path: path.to_path_buf(),
            generated,
            description: file.description.clone(),
            parts,
            components,
            by_name,
            mates: Vec::new(),
            robots: Vec::new(),
            revision: 0,
            aabb_cache: AabbCache::default(),
            disk_hash: None,
            warnings: Vec::new(),
        };
        let mut mate_names = HashMap::new();
        for (mi, m) in file.mates.iter().enumerate() {
            let needle = format!("name: {}", m.name);
            let err = |msg: String| at(&needle, "mates", msg);
            if mate_names.insert(m.name.clone(), ()).is_some() {
                let (line, col) = positions.get(&format!("mates/{mi}/name")).unwrap_or((0, 0));
                return Err(SourceError::new(
                    path,
                    line,
                    col,
                    format!(
                        "duplicate mate name `{}` (names are compared in Unicode NFC)",
                        m.name
                    ),
                )
                .into());
            }
            let kind = MateKind::parse(&m.kind).ok_or_else(|| {
                err(format!(
                    "mate `{}`: unknown type `{}` (coincident, concentric, parallel, perpendicular, distance, angle)",
                    m.name, m.kind
                ))
            })?;
            let ea = doc
                .mate_entity(&m.entities[0])
                .map_err(|e| err(format!("mate `{}`: {e}", m.name)))?;
            let eb = doc
                .mate_entity(&m.entities[1])
                .map_err(|e| err(format!("mate `{}`: {e}", m.name)))?;
            mates::check_entities(kind, &ea.geometry, &eb.geometry)
                .map_err(|e| err(format!("mate `{}`: {e}", m.name)))?;
            let about = match &m.about {
                None => None,
                Some(s) => {
                    let e = doc
                        .mate_entity(s)
                        .map_err(|e| err(format!("mate `{}`: {e}", m.name)))?;
                    if !matches!(e.geometry, Reference::Axis { .. }) {
                        return Err(err(format!("mate `{}`: `about` must name an axis", m.name)));
                    }
                    Some(e)
                }
            };
            let value = match (kind, m.value) {
                (MateKind::Angle, Some(v)) => Some(v.to_radians()),
                (MateKind::Distance, Some(v)) => Some(v),
                (k, None) if k.has_dimension() => {
                    return Err(err(format!(
                        "{} mate `{}` needs a `value`",
                        k.name(),
                        m.name
                    )))
                }
                (_, None) => None,
                (k, Some(_)) => return Err(err(format!("a {} mate takes no `value`", k.name()))),
            };
            if value.is_some_and(|v| !v.is_finite()) {
                return Err(err(format!("mate `{}`: value is not finite", m.name)));
            }
            doc.mates.push(Mate {
                name: m.name.clone(),
                kind,
                entities: [ea, eb],
                value,
                aligned: m.aligned,
                about,
            });
        }
        let mate_dimensions = doc
            .mates
            .iter()
            .filter(|m| m.kind.has_dimension())
            .map(|m| m.name.clone())
            .collect();
        doc.robots = robot::load(
            &file.robots,
            &doc.by_name,
            &urdf,
            &mate_dimensions,
            text,
            path,
        )?;
        doc.apply_robots();
        let mut poses: Vec<Transform> = doc.components.iter().map(|c| c.transform).collect();
        let fixed = doc.solver_fixed();
        mates::solve(&doc.mates, &mut poses, &fixed)
            .map_err(|e| at(&format!("name: {}", e.mate), "mates", e.to_string()))?;
        for (c, p) in doc.components.iter_mut().zip(poses) {
            c.transform = p;
        }
        doc.warnings = case_warnings(&file, path, positions);
        doc.warnings.extend(urdf_warnings);
        doc.warnings.extend(warnings);
        Ok(doc)
    }

    /// Warnings of the load, each `file:line:col: message`: names of one kind that
    /// differ only by case (`Plate` and `plate`), which lookups keep apart. The CLI
    /// prints them (`fitup check`, `fitup run`).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    fn mate_entity(&self, spec: &str) -> Result<MateEntity, String> {
        let (comp, reference) = spec
            .split_once('/')
            .ok_or_else(|| format!("entity `{spec}` must be written `component/reference`"))?;
        let &component = self.by_name.get(comp).ok_or_else(|| {
            format!(
                "no component `{comp}` ({})",
                suggestion(comp, self.by_name.keys().map(String::as_str))
            )
        })?;
        let part = &self.parts[&self.components[component].part];
        let geometry = part.reference(reference).ok_or_else(|| {
            let names = part
                .references
                .keys()
                .map(String::as_str)
                .chain(Reference::BUILTIN_NAMES);
            format!(
                "part `{}` has no reference `{reference}` ({})",
                part.name,
                suggestion(reference, names)
            )
        })?;
        Ok(MateEntity {
            component,
            reference: reference.to_string(),
            geometry,
        })
    }

    /// Re-solves the mates (SolidWorks' rebuild). On failure the poses are unchanged.
    pub fn rebuild(&mut self) -> Result<(), DocumentError> {
        self.apply_robots();
        let mut poses: Vec<Transform> = self.components.iter().map(|c| c.transform).collect();
        let fixed = self.solver_fixed();
        mates::solve(&self.mates, &mut poses, &fixed)
            .map_err(|e| DocumentError::Invalid(e.to_string()))?;
        for (c, p) in self.components.iter_mut().zip(poses) {
            c.transform = p;
        }
        self.revision += 1;
        Ok(())
    }

    /// The file this document was loaded from (and `save` writes).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Incremented on every change of a pose or dimension (for derived caches).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Free-text description.
    pub fn description(&self) -> Option<&str> {
        self.description.as_deref()
    }

    /// Parts in file order.
    pub fn parts(&self) -> impl Iterator<Item = &Part> {
        self.parts.values()
    }

    /// A part by name.
    pub fn part(&self, name: &str) -> Result<&Part, DocumentError> {
        self.parts
            .get(&*nfc_name(name))
            .ok_or_else(|| DocumentError::NotFound {
                what: "part",
                name: name.into(),
                hint: suggestion(name, self.parts.keys().map(String::as_str)),
            })
    }

    /// Components in file order.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// The index of a component, or an error listing close matches.
    pub fn component_index(&self, name: &str) -> Result<usize, DocumentError> {
        self.by_name
            .get(&*nfc_name(name))
            .copied()
            .ok_or_else(|| DocumentError::NotFound {
                what: "component",
                name: name.into(),
                hint: suggestion(name, self.components.iter().map(|c| c.name.as_str())),
            })
    }

    /// A component by name.
    pub fn component(&self, name: &str) -> Result<&Component, DocumentError> {
        Ok(&self.components[self.component_index(name)?])
    }

    /// The mesh of a component's part (part frame, mm).
    pub fn mesh_of(&self, component: usize) -> &Arc<Mesh> {
        &self.parts[&self.components[component].part].mesh
    }

    /// Sets a component's pose (part → world, mm). Fixed components refuse to move.
    /// Mates are not re-solved until [`rebuild`](Self::rebuild) or a dimension change,
    /// as in SolidWorks.
    pub fn set_transform(&mut self, name: &str, t: Transform) -> Result<(), DocumentError> {
        let i = self.component_index(name)?;
        self.set_transform_at(i, t)
    }

    /// [`set_transform`](Self::set_transform) by component index (no name lookup: the
    /// hot path of stepwise animations).
    pub fn set_transform_at(&mut self, i: usize, t: Transform) -> Result<(), DocumentError> {
        let name = &self.components[i].name;
        // The name is formatted only for a refused pose (scripts move parts in loops).
        check_pose(&t, format_args!("the pose for `{name}`"))?;
        // Setting the pose a component already has is not a move (Rhai writes a property
        // back after a method call on it, as in `table.transform.apply(p)`).
        if t == self.components[i].transform {
            return Ok(());
        }
        if self.components[i].fixed {
            return Err(DocumentError::FixedComponent(name.to_string()));
        }
        if let Some(robot) = self.driving_robot(i) {
            return Err(DocumentError::RobotLink {
                component: name.to_string(),
                robot: robot.to_string(),
            });
        }
        self.components[i].transform = t;
        self.revision += 1;
        Ok(())
    }

    /// Moves component `i` by `motion` applied after its pose (a motion in the world
    /// frame: `pose * motion` in the row-vector layout), with the checks of
    /// [`set_transform_at`](Self::set_transform_at). Returns the new pose.
    pub fn move_component_at(
        &mut self,
        i: usize,
        motion: &Transform,
    ) -> Result<Transform, DocumentError> {
        let t = self.components[i].transform * *motion;
        self.set_transform_at(i, t)?;
        Ok(t)
    }

    /// Reference `name` of component `i`'s part (a user plane, axis or point, or a
    /// built-in one such as `Origin`) in world coordinates at the component's pose (mm).
    pub fn world_reference(&self, i: usize, name: &str) -> Result<Reference, DocumentError> {
        let c = &self.components[i];
        let part = self.part(&c.part)?;
        let r = part
            .reference(name)
            .ok_or_else(|| DocumentError::NotFound {
                what: "reference",
                name: name.into(),
                hint: format!(
                    "part `{}` has none by that name; {}",
                    part.name,
                    suggestion(
                        name,
                        part.references
                            .keys()
                            .map(String::as_str)
                            .chain(Reference::BUILTIN_NAMES)
                    )
                ),
            })?;
        Ok(r.posed(&c.transform))
    }

    /// Marks a component fixed or free.
    pub fn set_fixed(&mut self, name: &str, fixed: bool) -> Result<(), DocumentError> {
        let i = self.component_index(name)?;
        self.components[i].fixed = fixed;
        Ok(())
    }

    /// Adds a feature to a part's tree, replacing the feature of the same name. Saved
    /// with the document.
    pub fn set_feature(&mut self, part: &str, feature: Feature) -> Result<(), DocumentError> {
        match &feature {
            Feature::CutCells {
                spec: CutSpec::Size(s),
                name,
            } => {
                if !(s.is_finite() && *s > 0.0 && *s <= MAX_ABS_VALUE) {
                    return Err(DocumentError::OutOfRange {
                        what: format!("cut cells `{name}`: cell size"),
                        value: format!("{s} mm"),
                        rule: "a number > 0 mm and at most 1e9 mm (MAX_ABS_VALUE)",
                    });
                }
            }
            Feature::CutCells {
                spec: CutSpec::Planes { x, y, z },
                name,
            } => {
                if let Some(v) = x
                    .iter()
                    .chain(y)
                    .chain(z)
                    .find(|v| !v.is_finite() || v.abs() > MAX_ABS_VALUE)
                {
                    return Err(DocumentError::OutOfRange {
                        what: format!("cut cells `{name}`: plane position"),
                        value: format!("{v} mm"),
                        rule: "finite and at most 1e9 mm from the origin (MAX_ABS_VALUE)",
                    });
                }
            }
        }
        let p = self
            .parts
            .get_mut(&*nfc_name(part))
            .ok_or_else(|| DocumentError::NotFound {
                what: "part",
                name: part.into(),
                hint: String::new(),
            })?;
        match p.features.iter_mut().find(|f| f.name() == feature.name()) {
            Some(f) => *f = feature,
            None => p.features.push(feature),
        }
        self.revision += 1;
        Ok(())
    }

    /// World-frame axis-aligned box of a component (mm): the tight box of its mesh's
    /// vertices at the component's pose; `None` for an empty mesh.
    pub fn world_aabb(&self, component: usize) -> Option<Aabb> {
        let c = &self.components[component];
        let rotation = c.transform.rotation();
        let t = c.transform.translation();
        // The box of the rotated mesh is cached per component: moves that only translate
        // (the stepwise animations scripts do) then cost O(1) instead of O(vertices).
        let mut cache = self.aabb_cache.0.lock().ok()?;
        if cache.len() != self.components.len() {
            cache.resize(self.components.len(), None);
        }
        if let Some((q, b)) = cache[component] {
            if q == rotation {
                return Some(b.translated(&t));
            }
        }
        let mesh = self.mesh_of(component);
        if mesh.vertices.is_empty() {
            return None;
        }
        let b = mesh.vertices.iter().fold(Aabb::EMPTY, |mut b, p| {
            b.grow(&(rotation * p));
            b
        });
        cache[component] = Some((rotation, b));
        Some(b.translated(&t))
    }

    /// The box around every component (mm), `None` for an empty document.
    pub fn assembly_aabb(&self) -> Option<Aabb> {
        (0..self.components.len())
            .filter_map(|i| self.world_aabb(i))
            .reduce(|a, b| a.union(&b))
    }

    /// Mates in file order.
    pub fn mates(&self) -> &[Mate] {
        &self.mates
    }

    /// Full names of the driving dimensions, in file order: mates' (`D1@<mate>`),
    /// then every robot joint's (`D1@角度1`, …).
    pub fn dimensions(&self) -> Vec<String> {
        self.mates
            .iter()
            .filter(|m| m.kind.has_dimension())
            .map(|m| dimension::full_name(&m.name))
            .chain(self.robots.iter().flat_map(|r| r.dimension_names()))
            .collect()
    }

    /// A dimension by full name (`D1@角度1`): a mate value or a robot joint
    /// (revolute joints are angles, prismatic joints lengths).
    pub fn dimension(&self, full_name: &str) -> Result<Dimension, DocumentError> {
        let full_name = &*nfc_name(full_name);
        let (kind, value) = match self.dimension_target(full_name)? {
            DimensionTarget::Mate(i) => {
                let m = &self.mates[i];
                let kind = if m.kind == MateKind::Angle {
                    DimensionKind::Angle
                } else {
                    DimensionKind::Length
                };
                (kind, m.value.unwrap_or(0.0))
            }
            DimensionTarget::Joint { robot, joint } => {
                let r = &self.robots[robot];
                let kind =
                    if r.robot().joint_kinds()[joint] == crate::kinematics::JointKind::Prismatic {
                        DimensionKind::Length
                    } else {
                        DimensionKind::Angle
                    };
                (kind, r.joints()[joint])
            }
        };
        Ok(Dimension {
            name: full_name.to_string(),
            kind,
            value,
        })
    }

    /// "No dimension named …", with close matches among the existing ones.
    fn dimension_not_found(&self, full_name: &str) -> DocumentError {
        let names = self.dimensions();
        DocumentError::NotFound {
            what: "dimension",
            name: full_name.into(),
            hint: suggestion(full_name, names.iter().map(String::as_str)),
        }
    }

    /// What a dimension drives: a mate or a robot joint.
    pub fn dimension_target(&self, full_name: &str) -> Result<DimensionTarget, DocumentError> {
        let full_name = &*nfc_name(full_name);
        let not_found = || self.dimension_not_found(full_name);
        let feature = dimension::mate_of(full_name).ok_or_else(not_found)?;
        match self.robot_dimension(feature) {
            Some(t) => Ok(t),
            None => self.dimension_mate(full_name).map(DimensionTarget::Mate),
        }
    }

    fn dimension_mate(&self, full_name: &str) -> Result<usize, DocumentError> {
        let not_found = || self.dimension_not_found(full_name);
        let mate = dimension::mate_of(full_name).ok_or_else(not_found)?;
        self.mates
            .iter()
            .position(|m| m.name == mate && m.kind.has_dimension())
            .ok_or_else(not_found)
    }

    /// Sets a dimension in internal units (mm or radians) and re-solves the mates, so
    /// every later query sees the driven poses. On failure nothing changes.
    pub fn set_dimension(&mut self, full_name: &str, value: f64) -> Result<(), DocumentError> {
        let full_name = &*nfc_name(full_name);
        if !value.is_finite() {
            return Err(DocumentError::OutOfRange {
                what: full_name.to_string(),
                value: value.to_string(),
                rule: "a finite number",
            });
        }
        // The range is checked in document units (mm, degrees), as the file holds them.
        let doc_value = Dimension {
            name: full_name.into(),
            kind: self.dimension(full_name)?.kind,
            value,
        }
        .document_value();
        if !doc_value.is_finite() || doc_value.abs() > MAX_ABS_VALUE {
            return Err(DocumentError::OutOfRange {
                what: full_name.to_string(),
                value: format!("{doc_value:e}"),
                rule: "at most 1e9 mm or degrees (MAX_ABS_VALUE)",
            });
        }
        let i = match self.dimension_target(full_name)? {
            DimensionTarget::Mate(i) => i,
            DimensionTarget::Joint { robot, joint } => {
                let mut q = self.robots[robot].joints().to_vec();
                q[joint] = value;
                return self
                    .set_robot_joints(robot, &q)
                    .map_err(|e| DocumentError::Invalid(format!("{full_name}: {e}")));
            }
        };
        if self.mates[i].kind == MateKind::Distance && value < 0.0 {
            return Err(DocumentError::OutOfRange {
                what: full_name.to_string(),
                value: format!("{value} mm"),
                rule: "a distance cannot be negative",
            });
        }
        let before = (
            self.mates[i].value,
            self.components
                .iter()
                .map(|c| c.transform)
                .collect::<Vec<_>>(),
        );
        self.mates[i].value = Some(value);
        if let Err(e) = self.rebuild() {
            self.mates[i].value = before.0;
            for (c, t) in self.components.iter_mut().zip(before.1) {
                c.transform = t;
            }
            return Err(e);
        }
        Ok(())
    }

    /// The document as its YAML schema (what `save` writes).
    pub fn to_file(&self) -> DocumentFile {
        let parts = self
            .parts
            .values()
            .filter(|p| !self.generated.contains(&p.name))
            .map(|p| {
                let mut pf = PartFile {
                    features: p.features.iter().map(Feature::to_file).collect(),
                    ..PartFile::from_stl(p.stl.clone())
                };
                if let Some(step) = &p.step {
                    pf.step = Some(std::mem::take(&mut pf.stl));
                    pf.deflection = step.deflection;
                    pf.angle = step.angle;
                }
                for (n, r) in &p.references {
                    let a = |v: Vec3| [v.x, v.y, v.z];
                    match *r {
                        Reference::Plane { point, normal } => {
                            pf.planes.insert(
                                n.clone(),
                                PlaneFile {
                                    point: a(point.coords),
                                    normal: a(normal),
                                },
                            );
                        }
                        Reference::Axis { point, direction } => {
                            pf.axes.insert(
                                n.clone(),
                                AxisFile {
                                    point: a(point.coords),
                                    direction: a(direction),
                                },
                            );
                        }
                        Reference::Point(point) => {
                            pf.points.insert(n.clone(), a(point.coords));
                        }
                    }
                }
                (p.name.clone(), pf)
            })
            .collect();
        let components = self
            .components
            .iter()
            .filter(|c| !self.generated.contains(&c.part))
            .map(|c| ComponentFile {
                name: c.name.clone(),
                part: c.part.clone(),
                fixed: c.fixed,
                color: c.color.as_ref().map(color_value),
                transform: Some(c.transform.to_matrix().map(|row| row.map(tidy))),
                mass: c.mass,
                threaded: c.threaded,
                fixture: c.fixture,
            })
            .collect();
        let mates = self
            .mates
            .iter()
            .map(|m| MateFile {
                name: m.name.clone(),
                kind: m.kind.name().into(),
                entities: m
                    .entities
                    .clone()
                    .map(|e| format!("{}/{}", self.components[e.component].name, e.reference)),
                value: m.value.map(|v| {
                    if m.kind == MateKind::Angle {
                        tidy(v.to_degrees())
                    } else {
                        tidy(v)
                    }
                }),
                aligned: m.aligned,
                about: m
                    .about
                    .as_ref()
                    .map(|e| format!("{}/{}", self.components[e.component].name, e.reference)),
            })
            .collect();
        DocumentFile {
            units: "mm".into(),
            description: self.description.clone(),
            parts,
            components,
            mates,
            robots: self.robots.iter().map(RobotInstance::to_file).collect(),
        }
    }

    /// The document as YAML text.
    pub fn to_yaml(&self) -> String {
        self.to_file().to_yaml().unwrap_or_default()
    }

    /// Writes the document back to its file atomically.
    ///
    /// Refused, with nothing written, when the text would not load again (a value out
    /// of range, …) or when the file changed on disk since the document was loaded or
    /// last saved (another writer's edits are never overwritten silently: reopen the
    /// document and apply the change again).
    pub fn save(&mut self) -> Result<(), DocumentError> {
        let path = self.path.clone();
        let expected = self.disk_hash;
        self.write_checked(&path, expected)
    }

    /// Writes the document to `path` atomically and makes it the document's file.
    /// Relative mesh paths are rewritten so they still point at the same meshes.
    ///
    /// Refuses to overwrite a mesh of this document and any existing file that is not
    /// a fitup document; over its own file it behaves as [`save`](Self::save).
    pub fn save_as(&mut self, path: &Path) -> Result<(), DocumentError> {
        let target = canonical_target(path);
        if let Some(p) = self
            .parts
            .values()
            .find(|p| canonical_target(&p.mesh_path) == target)
        {
            return Err(DocumentError::OverMesh {
                path: path.to_path_buf(),
                part: p.name.clone(),
            });
        }
        let expected = (target == canonical_target(&self.path))
            .then_some(self.disk_hash)
            .flatten();
        let new_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let old = self.parts.clone();
        let old_robots = self.robots.clone();
        for p in self.parts.values_mut() {
            if let Some(rel) = relative_path(&p.mesh_path, &new_dir) {
                p.stl = rel;
            }
        }
        for r in &mut self.robots {
            r.rebase_urdf(|f| relative_path(f, &new_dir));
        }
        if let Err(e) = self.write_checked(path, expected) {
            self.parts = old;
            self.robots = old_robots;
            return Err(e);
        }
        self.path = path.to_path_buf();
        Ok(())
    }

    /// Validates the text, then, holding a lock on the folder (so concurrent fitup
    /// writers take turns), checks what is on disk — the bytes hashed to `expected`, or
    /// else no file or a fitup document — and replaces it atomically.
    fn write_checked(&mut self, path: &Path, expected: Option<u64>) -> Result<(), DocumentError> {
        let write_err = |message: String| DocumentError::Write {
            path: path.into(),
            message,
        };
        let text = self
            .to_file()
            .to_yaml()
            .map_err(|e| write_err(e.to_string()))?;
        if let Err(e) = Self::parse_text(&text, path) {
            let why = match &e {
                DocumentError::Source(s) => s.message.clone(),
                other => other.to_string(),
            };
            return Err(write_err(format!(
                "not saved: the document would not open again ({why})"
            )));
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let _lock = crate::fsutil::lock_folder(dir);
        match crate::fsutil::read_file(path, FileKind::Document) {
            Err(crate::fsutil::ReadError::Io(_)) if !path.exists() => {}
            Ok(bytes) => match expected {
                Some(h) if content_hash(&bytes) != h => {
                    return Err(write_err(
                        "not saved: the file changed on disk since it was loaded (another program or script saved it); open it again and redo the change".into(),
                    ))
                }
                Some(_) => {}
                None => {
                    let is_document = std::str::from_utf8(&bytes)
                        .ok()
                        .is_some_and(|t| Self::parse_text(t, path).is_ok());
                    if !is_document {
                        return Err(write_err(
                            "refusing to overwrite a file that is not a fitup document".into(),
                        ));
                    }
                }
            },
            Err(e) => return Err(write_err(format!("refusing to overwrite it: {e}"))),
        }
        crate::fsutil::write_atomic(path, text.as_bytes()).map_err(|e| write_err(e.to_string()))?;
        self.disk_hash = Some(content_hash(text.as_bytes()));
        Ok(())
    }

    /// Every file this document was built from (the document, its meshes and the
    /// files they were read from — a `.gltf`'s buffers —, its STEP files), for watch
    /// mode.
    pub fn source_files(&self) -> Vec<PathBuf> {
        std::iter::once(self.path.clone())
            .chain(self.parts.values().flat_map(|p| {
                std::iter::once(p.mesh_path.clone()).chain(p.mesh_files.iter().cloned())
            }))
            .chain(self.robots.iter().flat_map(|r| r.urdf_files().to_vec()))
            .collect()
    }
}

/// A `step:` part's mesh through the mesh cache and the project's tessellation store
/// `store`, with the part's `deflection:` (mm) and `angle:` (degrees); the message of
/// an error names the file (and, without the `step` feature, the rebuild command).
fn step_part(
    pf: &PartFile,
    file: &Path,
    store: &Path,
    cache: &mut MeshCache,
) -> Result<(Arc<Mesh>, StepGeometry), String> {
    use crate::mesh::step::StepOptions;
    for (key, v) in [("deflection", pf.deflection), ("angle", pf.angle)] {
        if v.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(format!("`{key}:` must be a number > 0"));
        }
    }
    if pf.angle.is_some_and(|a| a >= 180.0) {
        return Err("`angle:` is in degrees and must be below 180".into());
    }
    let (linear_deflection, angular_deflection) = tessellations::of_part(pf);
    let options = StepOptions {
        linear_deflection,
        angular_deflection,
        ..StepOptions::default()
    };
    let got = cache
        .get_step(file, &options, Some(store))
        .map_err(|e| e.to_string())?;
    let geometry = StepGeometry {
        deflection: pf.deflection,
        angle: pf.angle,
        volume_ratio: got.mesh.signed_volume() / got.exact_volume,
        from_store: got.from_store,
    };
    Ok((got.mesh, geometry))
}

/// Adds the parts and components of a URDF robot's link meshes (named by
/// [`robot::urdf_component_name`]), recording them as generated.
fn add_urdf_parts(
    robot_name: &str,
    uri: &str,
    loaded: &robot::UrdfLoaded,
    parts: &mut IndexMap<String, Part>,
    components: &mut Vec<Component>,
    by_name: &mut HashMap<String, usize>,
    generated: &mut std::collections::HashSet<String>,
) -> Result<(), String> {
    for (i, mesh) in loaded.meshes.iter().enumerate() {
        let Some(mesh) = mesh else { continue };
        let link = loaded.robot.tree().links()[i]
            .name
            .clone()
            .unwrap_or_else(|| format!("link{i}"));
        let name = robot::urdf_component_name(robot_name, &link);
        if parts.contains_key(&name) || by_name.contains_key(&name) {
            return Err(format!(
                "the part or component `{name}` (made for link `{link}` of the URDF) already exists"
            ));
        }
        parts.insert(
            name.clone(),
            Part {
                name: name.clone(),
                stl: uri.to_string(),
                mesh_path: loaded.path.clone(),
                mesh_files: Vec::new(),
                step: None,
                mesh: Arc::new(mesh.clone()),
                references: IndexMap::new(),
                features: Vec::new(),
            },
        );
        by_name.insert(name.clone(), components.len());
        components.push(Component {
            name: name.clone(),
            part: name.clone(),
            fixed: false,
            color: None,
            transform: Transform::IDENTITY,
            mass: None,
            threaded: false,
            fixture: false,
        });
        generated.insert(name);
    }
    Ok(())
}

fn feature_name(f: &FeatureFile) -> &str {
    match f {
        FeatureFile::CutCells { name, .. } => name,
    }
}

impl DocumentError {
    /// Adds a hint to a located error.
    pub fn with_help(self, help: String) -> Self {
        match self {
            DocumentError::Source(s) => DocumentError::Source(s.with_help(help)),
            other => other,
        }
    }

    /// The message with source snippet for located errors.
    pub fn render(&self) -> String {
        match self {
            DocumentError::Source(s) => s.render(),
            other => other.to_string(),
        }
    }
}

/// The canonical form of a path that may not exist yet (its folder canonicalized), to
/// tell whether two paths name the same file.
fn canonical_target(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    match (
        abs.parent().and_then(|d| d.canonicalize().ok()),
        abs.file_name(),
    ) {
        (Some(d), Some(n)) => d.join(n),
        _ => abs,
    }
}

/// Checks a pose set through the API: finite, translation within [`MAX_ABS_VALUE`] mm.
pub(crate) fn check_pose(t: &Transform, what: impl std::fmt::Display) -> Result<(), DocumentError> {
    if !t.is_finite() {
        return Err(DocumentError::OutOfRange {
            what: what.to_string(),
            value: format!("{t}"),
            rule: "a pose with finite entries",
        });
    }
    if t.translation().iter().any(|v| v.abs() > MAX_ABS_VALUE) {
        return Err(DocumentError::OutOfRange {
            what: what.to_string(),
            value: format!("{t}"),
            rule: "translations are at most 1e9 mm (MAX_ABS_VALUE)",
        });
    }
    Ok(())
}

/// `name` in Unicode NFC, the form every name of a document is kept in: lookups by
/// another spelling of the same text (`é` decomposed) find it. Borrows when `name` is
/// NFC already (ASCII and most text).
pub fn nfc_name(name: &str) -> std::borrow::Cow<'_, str> {
    use unicode_normalization::UnicodeNormalization;
    if unicode_normalization::is_nfc_quick(name.chars()) == unicode_normalization::IsNormalized::Yes
    {
        std::borrow::Cow::Borrowed(name)
    } else {
        std::borrow::Cow::Owned(name.nfc().collect())
    }
}

/// A name given through the API (a new robot, …) as the document keeps it: NFC, and
/// refused when it holds a control or invisible character (as in a file).
pub(crate) fn new_name(name: &str, what: &str) -> Result<String, DocumentError> {
    crate::diagnostics::checked_name(name)
        .map(std::borrow::Cow::into_owned)
        .map_err(|c| DocumentError::HiddenCharacter {
            what: what.to_string(),
            name: crate::diagnostics::printable(name, false).into_owned(),
            character: crate::diagnostics::describe_char(c),
        })
}

/// The document file with every name in NFC: all text except file paths (`stl`,
/// `step`, `urdf`, which name files on disk byte for byte) and `description`.
fn nfc_file(file: DocumentFile) -> Result<DocumentFile, serde_yaml::Error> {
    fn walk(v: &mut serde_yaml::Value) {
        use serde_yaml::Value;
        match v {
            Value::String(s) => *s = nfc_name(s).into_owned(),
            Value::Sequence(items) => items.iter_mut().for_each(walk),
            Value::Mapping(m) => {
                let old = std::mem::take(m);
                for (k, mut val) in old {
                    let keep = matches!(k.as_str(), Some("stl" | "step" | "urdf" | "description"));
                    let k = match k {
                        Value::String(s) => Value::String(nfc_name(&s).into_owned()),
                        other => other,
                    };
                    if !keep {
                        walk(&mut val);
                    }
                    m.insert(k, val);
                }
            }
            Value::Tagged(t) => walk(&mut t.value),
            _ => {}
        }
    }
    let mut v = serde_yaml::to_value(&file)?;
    walk(&mut v);
    serde_yaml::from_value(v)
}

/// Names of one kind that differ only by case, as located warnings (see
/// [`Document::warnings`]).
/// A name and where it is written (line, column), when the scan saw it.
type Placed = (String, Option<(usize, usize)>);

fn case_warnings(file: &DocumentFile, path: &Path, positions: &scan::Positions) -> Vec<String> {
    let mut out = Vec::new();
    let mut kind = |what: &str, names: Vec<Placed>| {
        let mut by_case: IndexMap<String, Vec<&Placed>> = IndexMap::new();
        for n in &names {
            by_case.entry(n.0.to_lowercase()).or_default().push(n);
        }
        for group in by_case.values() {
            let mut spellings: Vec<&str> = group.iter().map(|n| n.0.as_str()).collect();
            spellings.dedup();
            if spellings.len() < 2 {
                continue;
            }
            let (line, col) = group[1].1.unwrap_or((0, 0));
            let list: Vec<String> = group
                .iter()
                .map(|(n, at)| match at {
                    Some((l, _)) => format!("`{n}` (line {l})"),
                    None => format!("`{n}`"),
                })
                .collect();
            out.push(
                SourceError::new(
                    path,
                    line,
                    col,
                    format!(
                        "{what} {} differ only by case: they are different names (lookups are exact), which is easy to confuse; rename one",
                        list.join(" and ")
                    ),
                )
                .to_string(),
            );
        }
    };
    let at = |p: String| positions.get(&p);
    kind(
        "parts",
        file.parts
            .keys()
            .map(|n| (n.clone(), at(format!("parts/{n}"))))
            .collect(),
    );
    kind(
        "components",
        file.components
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.clone(), at(format!("components/{i}/name"))))
            .collect(),
    );
    kind(
        "mates",
        file.mates
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), at(format!("mates/{i}/name"))))
            .collect(),
    );
    kind(
        "robots",
        file.robots
            .iter()
            .enumerate()
            .map(|(i, r)| (r.name.clone(), at(format!("robots/{i}/name"))))
            .collect(),
    );
    for (p, pf) in &file.parts {
        let refs = pf
            .planes
            .keys()
            .map(|r| (r.clone(), at(format!("parts/{p}/planes/{r}"))))
            .chain(
                pf.axes
                    .keys()
                    .map(|r| (r.clone(), at(format!("parts/{p}/axes/{r}")))),
            )
            .chain(
                pf.points
                    .keys()
                    .map(|r| (r.clone(), at(format!("parts/{p}/points/{r}")))),
            )
            .collect();
        kind(&format!("references of part `{p}`:"), refs);
        kind(
            &format!("features of part `{p}`:"),
            pf.features
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    (
                        feature_name(f).to_string(),
                        at(format!("parts/{p}/features/{i}/name")),
                    )
                })
                .collect(),
        );
    }
    out
}

/// `target` written relative to `base` when possible (both made absolute first).
pub(super) fn relative_path(target: &Path, base: &Path) -> Option<String> {
    let abs = |p: &Path| std::path::absolute(p).ok();
    let (t, b) = (abs(target)?, abs(base)?);
    let (tc, bc): (Vec<_>, Vec<_>) = (t.components().collect(), b.components().collect());
    let common = tc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return Some(t.to_string_lossy().into_owned());
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &tc[common..] {
        out.push(c);
    }
    Some(out.to_string_lossy().replace('\\', "/"))
}

#[cfg(test)]
mod tests;
