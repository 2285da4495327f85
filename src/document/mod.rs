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

pub mod assembly;
pub mod dimension;
mod edit;
mod entry;
mod equation_mgr;
pub mod equations;
mod error;
mod export;
pub mod file;
pub mod import;
mod load;
pub mod mates;
mod names;
mod numbering;
pub mod reference;
mod remove;
pub mod robot;
mod save;
pub mod scan;
pub mod subdoc;
pub mod tessellations;

pub use assembly::SubAssembly;
pub use error::{
    DimensionInUse, DocumentError, LinkEdit, MateProblem, MissingReference, OutsideItem,
    OutsideSubDocument, PartMeshError, ReferenceProblem, UrdfLinkAt, UrdfMeshProblem,
    UrdfRobotError, WriteProblem, YamlError,
};
pub use export::GlbExport;
pub(crate) use names::new_name;
pub use names::nfc_name;

pub use dimension::{Dimension, DimensionKind, DimensionTarget};
pub use edit::{MateSpec, PropertyOwner};
pub use entry::EntryError;
pub use equations::{
    Equation, EquationCause, EquationError, EquationLimit, EquationTarget, NonFiniteAt,
    SyntaxProblem,
};
pub use mates::{Mate, MateEntity, MateKind};
pub use reference::{coordinate_system, CoordinateSystemError, Reference};
pub use remove::RemoveMates;
pub use robot::{LinkDisplay, RobotError, RobotInstance};
pub use scan::MAX_ABS_VALUE;
pub use subdoc::SubDocument;

use crate::collision::CutSpec;
use crate::diagnostics::suggestion;
use crate::math::{Aabb, Transform};
use crate::mesh::Mesh;
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
    /// For a `step:` part, how it was tessellated (`None`: an `stl:` mesh). While
    /// the part is not loaded only the settings are known (`volume_ratio` is NaN).
    pub step: Option<StepGeometry>,
    /// The triangle mesh (mm, part frame); empty while the part is not loaded
    /// ([`Part::is_loaded`]).
    pub mesh: Arc<Mesh>,
    /// Named references (planes, axes, points) in the part frame, in file order.
    pub references: IndexMap<String, Reference>,
    /// The feature tree, in order.
    pub features: Vec<Feature>,
    /// Custom properties (SolidWorks' file properties: `Description`, `Price`, …),
    /// name → text, in file order.
    pub properties: IndexMap<String, String>,
    /// Whether its geometry file has been read, see [`Part::is_loaded`].
    pub(crate) loaded: bool,
    /// Where a document names its geometry file (`None`: a part a script added).
    pub(crate) at: Option<GeometryAt>,
}

/// Where a document names a part's geometry file: the document file, and the line
/// and column of the part's `stl:` or `step:` (0: unknown), for the errors and
/// warnings of reading it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GeometryAt {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
}

/// The mesh every part that is not loaded holds: no vertex, no triangle.
pub(crate) fn unloaded_mesh() -> Arc<Mesh> {
    static EMPTY: std::sync::OnceLock<Arc<Mesh>> = std::sync::OnceLock::new();
    EMPTY
        .get_or_init(|| {
            Arc::new(Mesh {
                vertices: Vec::new(),
                triangles: Vec::new(),
            })
        })
        .clone()
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

    /// Whether its geometry file has been read (SolidWorks' "resolved"). A part that
    /// only suppressed components use is not read when the document opens (as
    /// SolidWorks opens an assembly without loading its suppressed components): its
    /// file may be missing or broken, and its [`mesh`](Self::mesh) is empty until a
    /// component using it is unsuppressed, added or re-pointed to it, which reads it
    /// (an error then names the file, the document's line and the cause, and
    /// changes nothing). Every check, export, mass, box and plan leaves suppressed
    /// components out; asking for the mesh of a component whose part is not loaded
    /// is [`DocumentError::NotLoaded`].
    pub fn is_loaded(&self) -> bool {
        self.loaded
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
    /// Suppressed: kept in the document, but not checked, planned around, sequenced,
    /// weighed, bounded or exported, and its mates are inactive.
    pub suppressed: bool,
    /// Hidden: checked like any other component, but not shown or exported.
    pub hidden: bool,
    /// Custom properties of this instance, name → text, in file order.
    pub properties: IndexMap<String, String>,
    /// Inside a suppressed sub-assembly (then suppressed whatever its own
    /// `suppressed` says; see [`is_suppressed`](Self::is_suppressed)).
    pub held_suppressed: bool,
}

impl Component {
    /// A free, shown, unsuppressed instance of `part` named `name` at `transform`
    /// (component frame → assembly frame, mm), with no colour, mass or properties.
    pub(crate) fn placed(name: String, part: String, transform: Transform) -> Self {
        Self {
            name,
            part,
            fixed: false,
            color: None,
            transform,
            mass: None,
            threaded: false,
            fixture: false,
            suppressed: false,
            hidden: false,
            properties: IndexMap::new(),
            held_suppressed: false,
        }
    }

    /// Suppressed by its own flag or by a suppressed sub-assembly holding it
    /// (SolidWorks' `IsSuppressed`): not checked, planned around, sequenced, weighed,
    /// bounded or exported.
    pub fn is_suppressed(&self) -> bool {
        self.suppressed || self.held_suppressed
    }

    /// Neither suppressed nor hidden (SolidWorks' `IComponent2.Visible` of an
    /// unsuppressed component): what the viewer shows and the exports write by default.
    pub fn is_shown(&self) -> bool {
        !self.is_suppressed() && !self.hidden
    }
}

/// An assembly document.
#[derive(Debug, Clone)]
pub struct Document {
    path: PathBuf,
    /// The project it was loaded in (bounds its files; sub-documents are written
    /// through it).
    project: Option<crate::project::Project>,
    description: Option<String>,
    /// `mesh_deflection:` (mm, finite, ≥ 0), see [`Document::mesh_deflection`].
    mesh_deflection: Option<f64>,
    parts: IndexMap<String, Part>,
    components: Vec<Component>,
    by_name: HashMap<String, usize>,
    /// The first free `N` of `part-N` per base, kept with `by_name`.
    numbering: numbering::Numbering,
    mates: Vec<Mate>,
    /// Equations and global variables, evaluated on every rebuild.
    equations: Vec<Equation>,
    /// Sub-assemblies, parents first (poses in the world frame).
    assemblies: Vec<SubAssembly>,
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
    /// Component indices removed, in order (see [`Document::index_since`]).
    removed: Vec<usize>,
    /// The sub-document files the last save wrote.
    saved_sub_documents: Vec<PathBuf>,
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

impl Document {
    /// Warnings of the load, each `file:line:col: message`: names of one kind that
    /// differ only by case (`Plate` and `plate`), which lookups keep apart. The CLI
    /// prints them (`fitup check`, `fitup run`).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Adds the parts and components of a URDF robot's link meshes (named by
    /// [`robot::urdf_component_name`]), recording them as generated.
    /// The triangles of the parts made for URDF links (see [`robot::MAX_URDF_TRIANGLES`]).
    fn generated_triangles(&self) -> usize {
        self.generated
            .iter()
            .filter_map(|n| self.parts.get(n))
            .map(|p| p.mesh.triangles.len())
            .sum()
    }

    fn add_urdf_parts(
        &mut self,
        robot_name: &str,
        uri: &str,
        loaded: &robot::UrdfLoaded,
    ) -> Result<(), UrdfRobotError> {
        for (i, mesh) in loaded.meshes.iter().enumerate() {
            let Some(mesh) = mesh else { continue };
            let link = loaded.robot.tree().links()[i]
                .name
                .clone()
                .unwrap_or_else(|| format!("link{i}"));
            let name = robot::urdf_component_name(robot_name, &link);
            if self.parts.contains_key(&name) || self.by_name.contains_key(&name) {
                return Err(UrdfRobotError::LinkNameTaken {
                    name: name.into(),
                    link: link.into(),
                });
            }
            self.parts.insert(
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
                    properties: IndexMap::new(),
                    loaded: true,
                    at: None,
                },
            );
            self.by_name.insert(name.clone(), self.components.len());
            self.numbering.insert(&name);
            self.components.push(Component::placed(
                name.clone(),
                name.clone(),
                Transform::IDENTITY,
            ));
            self.generated.insert(name);
        }
        Ok(())
    }

    /// Evaluates the equations, gives the dimensions they drive their values and
    /// re-solves the mates (SolidWorks' rebuild). On failure nothing changes.
    pub fn rebuild(&mut self) -> Result<(), DocumentError> {
        if self.equations.is_empty() {
            self.solve_mates()
                .map_err(|source| DocumentError::Mates { at: None, source })?;
        } else {
            let before = self.clone();
            let solved = self
                .apply_equations()
                .map_err(|source| DocumentError::Equation { at: None, source })
                .and_then(|()| {
                    self.solve_mates()
                        .map_err(|source| DocumentError::Mates { at: None, source })
                });
            if let Err(e) = solved {
                *self = before;
                return Err(e);
            }
        }
        self.revision += 1;
        Ok(())
    }

    /// Moves the robots' links to their joints, then solves the mates; on failure
    /// the poses the mates drive are unchanged.
    fn solve_mates(&mut self) -> Result<(), mates::SolveError> {
        self.apply_robots();
        let mut poses: Vec<Transform> = self.components.iter().map(|c| c.transform).collect();
        let fixed = self.solver_fixed();
        let active: Vec<Mate> = self
            .mates
            .iter()
            .filter(|m| self.mate_active(m))
            .cloned()
            .collect();
        mates::solve(&active, &mut poses, &fixed)?;
        for (c, p) in self.components.iter_mut().zip(poses) {
            c.transform = p;
        }
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

    /// How far the parts' meshes may lie from the exact surfaces they stand for
    /// (mm; the document's `mesh_deflection:`, written by `fitup import` as the
    /// tessellation's linear deflection), and the largest `deflection:` of its
    /// `step:` parts (0.1 mm when not written). `None`: no part is known to be
    /// tessellated (meshes taken as exact).
    pub fn mesh_deflection(&self) -> Option<f64> {
        let step = self
            .parts
            .values()
            .filter_map(|p| p.step.as_ref())
            .map(|s| {
                s.deflection
                    .unwrap_or(crate::mesh::step::DEFAULT_LINEAR_DEFLECTION)
            })
            .fold(None, |a: Option<f64>, d| Some(a.map_or(d, |a| a.max(d))));
        match (self.mesh_deflection, step) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    /// Parts in file order.
    pub fn parts(&self) -> impl Iterator<Item = &Part> {
        self.parts.values()
    }

    /// A part by name.
    pub fn part(&self, name: &str) -> Result<&Part, DocumentError> {
        self.parts.get(&*nfc_name(name)).ok_or_else(|| {
            DocumentError::not_found("part", name, self.parts.keys().map(String::as_str))
        })
    }

    /// Components in file order.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// The index of a component, or an error listing close matches.
    pub fn component_index(&self, name: &str) -> Result<usize, DocumentError> {
        self.by_name.get(&*nfc_name(name)).copied().ok_or_else(|| {
            DocumentError::not_found(
                "component",
                name,
                self.components.iter().map(|c| c.name.as_str()),
            )
        })
    }

    /// A component by name.
    pub fn component(&self, name: &str) -> Result<&Component, DocumentError> {
        Ok(&self.components[self.component_index(name)?])
    }

    /// The mesh of a component's part (part frame, mm): empty when the part is not
    /// loaded ([`Part::is_loaded`]: only suppressed components use it), see
    /// [`loaded_mesh_of`](Self::loaded_mesh_of).
    pub fn mesh_of(&self, component: usize) -> &Arc<Mesh> {
        &self.parts[&self.components[component].part].mesh
    }

    /// Whether component `component`'s part is loaded ([`Part::is_loaded`]; always,
    /// for a component that is not suppressed).
    pub fn part_loaded(&self, component: usize) -> bool {
        self.parts[&self.components[component].part].loaded
    }

    /// [`mesh_of`](Self::mesh_of), refused with [`DocumentError::NotLoaded`] for a
    /// suppressed component whose part is not loaded (its mesh is not known, not
    /// empty).
    pub fn loaded_mesh_of(&self, component: usize) -> Result<&Arc<Mesh>, DocumentError> {
        let c = &self.components[component];
        let part = &self.parts[&c.part];
        if part.loaded {
            Ok(&part.mesh)
        } else {
            Err(DocumentError::NotLoaded {
                component: c.name.clone().into(),
                part: part.name.clone().into(),
            })
        }
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
            return Err(DocumentError::FixedComponent(name.into()));
        }
        if let Some(robot) = self.driving_robot(i) {
            return Err(DocumentError::RobotLink {
                component: name.into(),
                robot: robot.into(),
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

    /// Coordinate system `name` of component `i`'s part in world coordinates: the pose
    /// that maps coordinates in the system to the world (mm), as SolidWorks'
    /// `CoordinateSystemFeatureData.Transform` of a component's `CoordSys` feature
    /// times `Transform2`.
    pub fn coordinate_system(&self, i: usize, name: &str) -> Result<Transform, DocumentError> {
        let c = &self.components[i];
        Ok(self.part_coordinate_system(&c.part, name)? * c.transform)
    }

    /// Coordinate system `name` of part `part` in the part frame (mm), as SolidWorks'
    /// `CoordinateSystemFeatureData.Transform`.
    pub fn part_coordinate_system(
        &self,
        part: &str,
        name: &str,
    ) -> Result<Transform, DocumentError> {
        let p = self.part(part)?;
        let r = p.reference(name).ok_or_else(|| DocumentError::NotFound {
            what: "coordinate system",
            name: name.into(),
            hint: format!(
                "part `{}` has none by that name; {}",
                p.name,
                suggestion(
                    name,
                    p.references
                        .iter()
                        .filter(|(_, r)| r.coordinate_system().is_some())
                        .map(|(n, _)| n.as_str())
                )
            ),
        })?;
        r.coordinate_system()
            .ok_or_else(|| DocumentError::NotACoordinateSystem {
                part: p.name.clone().into(),
                reference: name.into(),
                kind: r.kind_name(),
            })
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
    /// vertices at the component's pose; `None` for an empty mesh or a part that is
    /// not loaded.
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
        let mesh = self.loaded_mesh_of(component).ok()?;
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

    /// The box around every component but the suppressed ones (mm), `None` for an
    /// empty document.
    pub fn assembly_aabb(&self) -> Option<Aabb> {
        (0..self.components.len())
            .filter(|&i| !self.components[i].is_suppressed())
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
        DocumentError::not_found("dimension", full_name, names.iter().map(String::as_str))
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
    /// every later query sees the driven poses. On failure nothing changes. A
    /// dimension an equation drives is refused: change the equation or its global
    /// variables.
    pub fn set_dimension(&mut self, full_name: &str, value: f64) -> Result<(), DocumentError> {
        let full_name = &*nfc_name(full_name);
        if let Some(i) = self.driving_equation(full_name) {
            return Err(DocumentError::DrivenByEquation {
                dimension: full_name.to_string(),
                joint: None,
                index: i,
                equation: equations::shown(&self.equations[i].text()),
            });
        }
        let before = (
            self.mates.clone(),
            self.robots.clone(),
            self.components
                .iter()
                .map(|c| c.transform)
                .collect::<Vec<_>>(),
        );
        self.set_dimension_value(full_name, value)?;
        let is_mate = matches!(
            self.dimension_target(full_name),
            Ok(DimensionTarget::Mate(_))
        );
        if !is_mate && self.equations.is_empty() {
            return Ok(());
        }
        if let Err(e) = self.rebuild() {
            self.mates = before.0;
            self.robots = before.1;
            for (c, t) in self.components.iter_mut().zip(before.2) {
                c.transform = t;
            }
            return Err(e);
        }
        Ok(())
    }

    /// Checks `value` (internal units) for dimension `full_name` and sets it, without
    /// solving the mates (a robot joint moves its links).
    pub(crate) fn set_dimension_value(
        &mut self,
        full_name: &str,
        value: f64,
    ) -> Result<(), DocumentError> {
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
                // An equation sets its own dimension here: not the public check.
                return self.move_robot_joints(robot, &q).map_err(|e| {
                    DocumentError::JointDimension {
                        dimension: full_name.to_string(),
                        source: Box::new(e),
                    }
                });
            }
        };
        if self.mates[i].kind == MateKind::Distance && value < 0.0 {
            return Err(DocumentError::OutOfRange {
                what: full_name.to_string(),
                value: format!("{value} mm"),
                rule: "a distance cannot be negative",
            });
        }
        self.mates[i].value = Some(value);
        Ok(())
    }

    /// Every file this document was built from (the document, its meshes and the
    /// files they were read from — a `.gltf`'s buffers —, its STEP files), for watch
    /// mode.
    pub fn source_files(&self) -> Vec<PathBuf> {
        std::iter::once(self.path.clone())
            .chain(
                self.assemblies
                    .iter()
                    .filter_map(|a| a.file.as_ref().map(|f| f.path.clone())),
            )
            .chain(self.parts.values().flat_map(|p| {
                std::iter::once(p.mesh_path.clone()).chain(p.mesh_files.iter().cloned())
            }))
            .chain(self.robots.iter().flat_map(|r| r.urdf_files().to_vec()))
            .collect()
    }
}

/// `x` at the nearest multiple of 1e-9 when it is within 1e-12 (relative, at least
/// absolute) of it: float noise of a composed pose, not a written digit.
fn snap(x: f64) -> f64 {
    let r = (x * 1e9).round() / 1e9;
    if (r - x).abs() <= 1e-12 * x.abs().max(1.0) {
        r
    } else {
        x
    }
}

/// `t` with each matrix entry [`snap`]ped: a pose composed with a frame and taken
/// apart again (a sub-document's content or robot, written to its own file) reads as
/// written.
fn snapped(t: Transform) -> Transform {
    Transform::from_matrix(&t.to_matrix().map(|row| row.map(snap))).unwrap_or(t)
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

#[cfg(test)]
mod tests;
