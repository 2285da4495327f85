//! The workspace: a [`Document`] seen as a collision scene, and every
//! document-level request — interference of all or some components, touching,
//! clearance, contact, sweeps, planning a path for a component, re-validating a
//! path and following it.
//!
//! This is the layer between [`document`](crate::document) (what the user wrote)
//! and `script` (Rhai bindings, which only convert values): a Rust
//! program does through it everything a script does. It owns the document's
//! collision scene ([`Scene`], built through a [`SceneCache`] that keeps colliders
//! and cut cells while meshes are unchanged) and the rules that turn a component
//! name into a planning problem: the obstacles (every other component), the
//! planning bounds (default: the product box with start and goal, grown by
//! [`DEFAULT_MARGIN_DIAMETERS`] of the part), the component's box for disassembly, and one tolerance
//! rule shared by planners, [`Workspace::revalidate`] and [`Workspace::contact`].
//!
//! Units: millimetres and radians; poses are [`Transform`]s (part frame → world).
//!
//! # Examples
//! ```
//! use fitup::document::Document;
//! use fitup::workspace::{CheckOptions, SceneCache, Workspace};
//!
//! let doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
//! let mut cache = SceneCache::new();
//! let ws = Workspace::new(&doc, &mut cache).unwrap();
//! // The demo cell is assembled without interference: screws rest in their holes.
//! assert!(ws.interferences(&CheckOptions::default()).unwrap().is_empty());
//! assert!(!ws.interferes("screw1", "plate_a", &CheckOptions::default()).unwrap());
//! let gap = ws.clearance("screw4", "screw5", 1000.0).unwrap();
//! assert!(gap > 0.0 && gap < 50.0, "{gap} mm");
//! ```

mod export;
mod features;
mod overlap;
mod plan;
mod scene;

pub use export::{export_glb, export_stl, world_glb_bytes, world_mesh, world_stl_bytes};
pub use features::{feature_cells, split_part, CUT_CELLS_FEATURE};
pub use overlap::{
    mass_properties, part_frame_mass_properties, MassOptions, Overlap, OverlapOptions,
};
pub use plan::{follow, PlanRequest, Revalidation, DEFAULT_MARGIN_DIAMETERS};
pub use scene::{Scene, SceneCache};

/// How far [`Workspace::clearance`] searches when the caller names no distance (mm):
/// the scripting and Python faces' default.
pub const DEFAULT_CLEARANCE_SEARCH_MM: f64 = 1000.0;

use crate::collision::{
    CollisionError, Contact, Method, Motion, PairContact, SweepHit, SweepOptions, DEFAULT_TOLERANCE,
};
use crate::diagnostics::Name;
use crate::document::{Document, DocumentError};
use crate::math::Transform;
use crate::planning::PlanError;

/// A value given for an option, as its refusal shows it
/// ([`WorkspaceError::InvalidOption`], [`crate::sequence::SequenceError::InvalidOption`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum GivenValue {
    /// A number.
    Number(f64),
    /// A count.
    Count(usize),
    /// Numbers: a direction, a list (`[0.0, 0.0, 0.0]`, `[]`).
    Numbers(Vec<f64>),
    /// A pose (boxed: a pose is seven numbers, and every `Result` carrying a
    /// [`WorkspaceError`] would grow with it).
    Pose(Box<Transform>),
    /// A component, by name.
    Component(String),
    /// A component's mass (kg).
    Mass {
        /// The component.
        component: String,
        /// The mass given.
        mass: f64,
    },
}

impl std::fmt::Display for GivenValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GivenValue::Number(v) => write!(f, "{v}"),
            GivenValue::Count(n) => write!(f, "{n}"),
            GivenValue::Numbers(v) => write!(f, "{:?}", v.as_slice()),
            GivenValue::Pose(t) => write!(f, "{t:?}"),
            GivenValue::Component(name) => f.write_str(name),
            GivenValue::Mass { component, mass } => write!(f, "{component}: {mass}"),
        }
    }
}

/// Why a workspace request could not be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WorkspaceError {
    /// The document refused (unknown component or part, a fixed component moved…).
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// A collision query refused its input (bad mesh, pose, tolerance, motion).
    #[error(transparent)]
    Collision(#[from] CollisionError),
    /// A planner refused its options.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// Planners never move a fixed component.
    #[error(
        "component `{0}` is fixed: planners never move fixed components (set `fixed: false` first)"
    )]
    FixedComponent(Name),
    /// A pair query names the same component twice.
    #[error("`{0}` is checked against itself")]
    SameComponent(Name),
    /// The component's mesh has no vertices.
    #[error("the mesh of component `{0}` is empty")]
    EmptyMesh(Name),
    /// An option has a value the request cannot use.
    #[error("invalid option `{option}` = {value}: expected {expected}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// The value given.
        value: GivenValue,
        /// What is accepted.
        expected: &'static str,
    },
    /// There is no path to follow or revalidate.
    #[error("the path was not found; nothing to follow")]
    PathNotFound,
    /// The caller's callback asked to stop.
    #[error("cancelled")]
    Cancelled,
    /// A step that gives no number of poses, or more than the shared cap
    /// ([`MAX_SAMPLES`](crate::math::MAX_SAMPLES)).
    #[error(transparent)]
    Limit(#[from] crate::math::LimitError),
    /// The overlap of two components cannot be measured.
    #[error("`{a}` and `{b}`: {source}")]
    Overlap {
        /// The first component.
        a: Name,
        /// The second component.
        b: Name,
        /// Why.
        #[source]
        source: crate::collision::VolumeError,
    },
    /// A component has no mass properties (empty `component` for the combination).
    #[error("{}{source}", if component.is_empty() { String::new() } else { format!("component `{component}`: ") })]
    Mass {
        /// The component.
        component: Name,
        /// Why.
        #[source]
        source: crate::mesh::MassError,
    },
}

impl WorkspaceError {
    fn overlap(a: &str, b: &str, source: crate::collision::VolumeError) -> Self {
        WorkspaceError::Overlap {
            a: a.into(),
            b: b.into(),
            source,
        }
    }
}

/// Method and tolerance of a static interference request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckOptions {
    /// Exact (default), whole-part boxes or cut cells.
    pub method: Method,
    /// Penetration tolerance, mm (≥ 0): crossings up to this depth are touching.
    /// Default [`DEFAULT_TOLERANCE`], the planners' default too.
    pub tolerance: f64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            method: Method::Exact,
            tolerance: DEFAULT_TOLERANCE,
        }
    }
}

/// A document's components as a collision scene at their current poses, with the
/// document-level requests. Cheap to build from a warm [`SceneCache`]; build a new
/// one after moving components.
pub struct Workspace<'d> {
    doc: &'d Document,
    scene: Scene,
}

impl<'d> Workspace<'d> {
    /// The workspace of `doc`, colliders and cut cells through `cache`.
    ///
    /// # Errors
    /// Unusable meshes or cuts, parts the document does not hold.
    pub fn new(doc: &'d Document, cache: &mut SceneCache) -> Result<Self, WorkspaceError> {
        Ok(Self {
            doc,
            scene: Scene::new(doc, cache)?,
        })
    }

    /// The document.
    pub fn document(&self) -> &'d Document {
        self.doc
    }

    /// The collision scene (per component: collider, cut cells, pose).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The index of component `name`.
    ///
    /// # Errors
    /// [`DocumentError::NotFound`] with close matches.
    pub fn index(&self, name: &str) -> Result<usize, WorkspaceError> {
        let i = self.doc.component_index(name)?;
        if self.doc.components()[i].is_suppressed() {
            return Err(
                DocumentError::Suppressed(self.doc.components()[i].name.clone().into()).into(),
            );
        }
        Ok(i)
    }

    /// The name of component `index`.
    pub fn name(&self, index: usize) -> &'d str {
        &self.doc.components()[index].name
    }

    /// The current pose of component `name` (part frame → world, mm).
    ///
    /// # Errors
    /// An unknown component.
    pub fn pose(&self, name: &str) -> Result<Transform, WorkspaceError> {
        Ok(self.scene.poses[self.index(name)?])
    }

    fn pair(&self, a: &str, b: &str) -> Result<(usize, usize), WorkspaceError> {
        let (ia, ib) = (self.index(a)?, self.index(b)?);
        if ia == ib {
            return Err(WorkspaceError::SameComponent(a.into()));
        }
        Ok((ia, ib))
    }

    /// Every pair that touches or interferes (`a < b`, component indices), sorted.
    ///
    /// # Errors
    /// A bad tolerance or an unusable mesh.
    pub fn contacts(&self, options: &CheckOptions) -> Result<Vec<PairContact>, WorkspaceError> {
        Ok(self.scene.contacts(options.method, options.tolerance)?)
    }

    /// Every interfering pair.
    ///
    /// # Errors
    /// As [`contacts`](Self::contacts).
    pub fn interferences(
        &self,
        options: &CheckOptions,
    ) -> Result<Vec<PairContact>, WorkspaceError> {
        let mut all = self.contacts(options)?;
        all.retain(|p| p.contact.is_interfering());
        Ok(all)
    }

    /// Every pair whose surfaces meet without interfering.
    ///
    /// # Errors
    /// As [`contacts`](Self::contacts).
    pub fn touching(&self, options: &CheckOptions) -> Result<Vec<PairContact>, WorkspaceError> {
        let mut all = self.contacts(options)?;
        all.retain(|p| p.contact.is_touching());
        Ok(all)
    }

    /// The verdict for components `a` and `b` (`Contained::inner` refers to them in
    /// this order). A pose a planner accepts with the same tolerance is never
    /// [`Contact::Interfering`] here: both use "deeper than the tolerance".
    ///
    /// # Errors
    /// Unknown or equal components, a bad tolerance.
    pub fn contact(
        &self,
        a: &str,
        b: &str,
        options: &CheckOptions,
    ) -> Result<Contact, WorkspaceError> {
        let (ia, ib) = self.pair(a, b)?;
        Ok(self
            .scene
            .contact(ia, ib, options.method, options.tolerance)?)
    }

    /// Whether components `a` and `b` interfere: the answer of
    /// [`contact`](Self::contact)`.is_interfering()`, found without measuring the
    /// depth (the exact method stops at the first crossing deeper than the
    /// tolerance, mm).
    ///
    /// # Errors
    /// As [`contact`](Self::contact).
    pub fn interferes(
        &self,
        a: &str,
        b: &str,
        options: &CheckOptions,
    ) -> Result<bool, WorkspaceError> {
        let (ia, ib) = self.pair(a, b)?;
        Ok(self
            .scene
            .interferes(ia, ib, options.method, options.tolerance)?)
    }

    /// Clearance between `a` and `b` (mm, [`crate::collision::clearance`]): the distance
    /// between their surfaces, 0 when they touch, cross or one solid lies inside the
    /// other; searched no farther than `stop_mm` (returns `stop_mm` when nothing is
    /// nearer). It agrees with [`contact`](Self::contact) at any tolerance: not
    /// `Separate` ⇒ clearance ≤ tolerance, `Interfering` ⇒ 0.
    ///
    /// # Errors
    /// Unknown or equal components.
    pub fn clearance(&self, a: &str, b: &str, stop_mm: f64) -> Result<f64, WorkspaceError> {
        let (ia, ib) = self.pair(a, b)?;
        Ok(self.scene.clearance(ia, ib, stop_mm)?)
    }

    /// The first contact of component `name` along `motion` with any other
    /// component (`with` in the result is a component index; see [`name`](Self::name)).
    ///
    /// # Errors
    /// An unknown component, a bad motion or options, a spent time budget
    /// ([`CollisionError::TimeLimit`]).
    pub fn sweep(
        &self,
        name: &str,
        motion: &Motion,
        options: &SweepOptions,
    ) -> Result<SweepHit, WorkspaceError> {
        Ok(self.scene.sweep(self.index(name)?, motion, options)?)
    }

    /// [`sweep`](Self::sweep) from the component's current pose through
    /// `waypoints` in order (translation lerp + rotation slerp between them).
    ///
    /// # Examples
    /// ```
    /// use fitup::document::Document;
    /// use fitup::collision::SweepOptions;
    /// use fitup::math::{Transform, Vec3};
    /// use fitup::workspace::{SceneCache, Workspace};
    ///
    /// use fitup::document::Reference;
    ///
    /// let mut doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
    /// // screw4 40 mm above plate_b's first hole.
    /// let plate_b = doc.component_index("plate_b").unwrap();
    /// let Reference::Axis { point: hole, .. } = doc.world_reference(plate_b, "hole1").unwrap() else {
    ///     unreachable!("hole1 is an axis")
    /// };
    /// let at = |dz: f64| Transform::from_translation(Vec3::new(hole.x, hole.y, hole.z + dz));
    /// doc.set_transform("screw4", at(40.0)).unwrap();
    /// let mut cache = SceneCache::new();
    /// let ws = Workspace::new(&doc, &mut cache).unwrap();
    /// // Lower it 60 mm into the hole: the head lands on the plate (10 mm thick) after 40 mm.
    /// let hit = ws.sweep_through("screw4", &[at(-20.0)], &SweepOptions::default()).unwrap();
    /// assert!(hit.hit);
    /// assert!((hit.t - 40.0 / 60.0).abs() < 0.002, "t = {}", hit.t);
    /// assert!(["plate_b", "table"].contains(&ws.name(hit.with.unwrap())));
    /// ```
    ///
    /// # Errors
    /// As [`sweep`](Self::sweep); an empty `waypoints`.
    pub fn sweep_through(
        &self,
        name: &str,
        waypoints: &[Transform],
        options: &SweepOptions,
    ) -> Result<SweepHit, WorkspaceError> {
        if waypoints.is_empty() {
            return Err(WorkspaceError::InvalidOption {
                option: "waypoints",
                value: GivenValue::Numbers(Vec::new()),
                expected: "at least one pose",
            });
        }
        let mut poses = vec![self.pose(name)?];
        poses.extend_from_slice(waypoints);
        self.sweep(name, &Motion::Poses(poses), options)
    }
}

#[cfg(test)]
mod tests;
