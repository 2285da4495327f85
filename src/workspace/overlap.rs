//! Document-level measures of interfering components (the intersection volume and the
//! separating translation, [`crate::collision::intersection_volume`] and
//! [`crate::collision::separation`]) and mass properties of components, a selection
//! or the whole assembly ([`crate::mesh::MassProperties`]).

use super::{Workspace, WorkspaceError};
use crate::collision::{
    intersection_volume, separation, Contact, SeparationOptions, DEFAULT_OVERLAP_TIME_LIMIT_MS,
};
use crate::document::{Document, DocumentError};
use crate::math::Vec3;
use crate::mesh::{MassProperties, MassSpec};

/// How two interfering components overlap (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overlap {
    /// The volume of the intersection, mm³ (SolidWorks' interference volume).
    pub volume: f64,
    /// The shortest translation of the first component that clears the second, mm:
    /// the interference depth.
    pub depth: f64,
    /// The unit direction (world) of that translation.
    pub direction: Vec3,
}

/// Options of [`Workspace::overlap`] (the options map of `doc.overlap`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OverlapOptions {
    /// Time budget of the whole call, ms (default 10 s).
    pub time_limit_ms: f64,
}

impl Default for OverlapOptions {
    fn default() -> Self {
        OverlapOptions {
            time_limit_ms: DEFAULT_OVERLAP_TIME_LIMIT_MS,
        }
    }
}

impl Workspace<'_> {
    /// The intersection volume of components `a` and `b` and the shortest translation
    /// of `a` that separates them (both 0 when they only touch or are apart).
    ///
    /// # Errors
    /// Unknown or equal components, a mesh that is not a closed solid, a spent time
    /// budget.
    pub fn overlap(
        &self,
        a: &str,
        b: &str,
        options: &OverlapOptions,
    ) -> Result<Overlap, WorkspaceError> {
        let (ia, ib) = self.pair(a, b)?;
        let scene = self.scene();
        let (ca, cb) = (&scene.colliders[ia], &scene.colliders[ib]);
        let (pa, pb) = (scene.poses[ia], scene.poses[ib]);
        let deadline = crate::math::Deadline::after_ms(options.time_limit_ms);
        let volume = intersection_volume(ca, &pa, cb, &pb, options.time_limit_ms)
            .map_err(|e| WorkspaceError::overlap(a, b, e))?;
        if volume == 0.0 {
            return Ok(Overlap {
                volume,
                depth: 0.0,
                direction: Vec3::z(),
            });
        }
        let left = deadline.remaining().as_secs_f64() * 1000.0;
        let s = separation(
            ca,
            &pa,
            cb,
            &pb,
            &SeparationOptions {
                time_limit_ms: left,
            },
        )
        .map_err(|e| WorkspaceError::overlap(a, b, e))?;
        Ok(Overlap {
            volume,
            depth: s.distance,
            direction: s.direction,
        })
    }
}

/// Options of [`mass_properties`] (the options map of `doc.mass_properties`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MassOptions {
    /// Density of components without their own `mass`, kg/m³ (default 1000, water —
    /// SolidWorks' density of a part without a material).
    pub density: f64,
}

impl Default for MassOptions {
    fn default() -> Self {
        MassOptions { density: 1000.0 }
    }
}

/// The mass properties of components `which` (indices) of `doc` together, in world
/// coordinates (mm, kg): each component's closed mesh at its pose, with its own
/// `mass` (kg) when the document gives one, else `options.density`. Express them in
/// any coordinate system with [`MassProperties::in_frame`].
///
/// # Errors
/// No component, a mesh that is not a closed solid (naming the component), a bad
/// density.
pub fn mass_properties(
    doc: &Document,
    which: &[usize],
    options: &MassOptions,
) -> Result<MassProperties, WorkspaceError> {
    let mut bodies = Vec::with_capacity(which.len());
    for &i in which {
        let c = &doc.components()[i];
        let spec = match c.mass {
            Some(kg) => MassSpec::Mass(kg),
            None => MassSpec::Density(options.density),
        };
        let m = MassProperties::of_mesh_with(doc.loaded_mesh_of(i)?, spec).map_err(|e| {
            WorkspaceError::Mass {
                component: c.name.clone().into(),
                source: e,
            }
        })?;
        bodies.push(m.moved(&c.transform));
    }
    MassProperties::combine(&bodies).map_err(|e| WorkspaceError::Mass {
        component: crate::diagnostics::Name::default(),
        source: e,
    })
}

/// [`mass_properties`] of one component in its own part frame (the part's properties
/// with the component's mass or density).
///
/// # Errors
/// As [`mass_properties`].
pub fn part_frame_mass_properties(
    doc: &Document,
    index: usize,
    options: &MassOptions,
) -> Result<MassProperties, WorkspaceError> {
    let c = &doc.components()[index];
    Ok(mass_properties(doc, &[index], options)?.in_frame(&c.transform))
}

/// Budget of the separating translation measured for a reported interference (ms):
/// past it the verdict keeps the crossing estimate.
const REPORTED_DEPTH_TIME_LIMIT_MS: f64 = 2_000.0;

impl Workspace<'_> {
    /// `contact` (the verdict for components `a` and `b`, indices) with an
    /// interfering pair's depth measured as the separating translation
    /// ([`crate::collision::separation`]): what reports show users (a screw pushed
    /// 5 mm into a table: 5 mm, not a facet's crossing depth). Other verdicts, parts
    /// that are not closed solids and a measure that would take more than 2 s keep
    /// the verdict as it is.
    pub fn with_separation_depth(&self, a: usize, b: usize, contact: Contact) -> Contact {
        let Contact::Interfering { kind, .. } = contact else {
            return contact;
        };
        let scene = self.scene();
        let (ca, cb) = (&scene.colliders[a], &scene.colliders[b]);
        if !(ca.is_solid() && cb.is_solid()) {
            return contact;
        }
        let options = SeparationOptions {
            time_limit_ms: REPORTED_DEPTH_TIME_LIMIT_MS,
        };
        match separation(ca, &scene.poses[a], cb, &scene.poses[b], &options) {
            Ok(s) if s.distance > 0.0 => Contact::Interfering {
                depth: s.distance,
                kind,
            },
            _ => contact,
        }
    }
}

/// The meshes of components `which` (indices) of `doc` at their poses, in one mesh,
/// expressed in the coordinate system `frame` (its pose in the world; `None`: the
/// world), mm: what a per-component export writes, with the transform baked in
/// (CodeStack's "Export Part Or Component To STL").
///
/// # Errors
/// [`DocumentError::NotLoaded`] for a suppressed component whose part is not loaded
/// (its mesh is not known; an empty one would export nothing without a word).
pub fn world_mesh(
    doc: &Document,
    which: &[usize],
    frame: Option<&crate::math::Transform>,
) -> Result<crate::mesh::Mesh, DocumentError> {
    let to_frame = frame.map(|f| f.inverse());
    let mut out = crate::mesh::Mesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for &i in which {
        let pose = doc.components()[i].transform;
        let pose = match &to_frame {
            Some(f) => pose.then(f),
            None => pose,
        };
        out.append(&doc.loaded_mesh_of(i)?.transformed(&pose));
    }
    Ok(out)
}

/// Writes [`world_mesh`] of components `which` as binary STL to `path` through the
/// project's write rule, as [`Document::export_glb`] does (a file the document was
/// built from is never replaced, an existing file only when fitup wrote it or with
/// `force`; atomically). Returns the bytes written.
///
/// # Errors
/// [`DocumentError::Write`] naming the file, or as [`world_mesh`].
pub fn export_stl(
    doc: &Document,
    path: &std::path::Path,
    which: &[usize],
    frame: Option<&crate::math::Transform>,
    force: bool,
) -> Result<usize, crate::document::DocumentError> {
    let sources: Vec<std::path::PathBuf> = doc
        .source_files()
        .iter()
        .filter_map(|p| p.canonicalize().ok())
        .collect();
    let used = |p: &std::path::Path| p.canonicalize().is_ok_and(|c| sources.contains(&c));
    let rule = crate::project::OutputRule {
        force,
        used: Some(&used),
        signature: None,
    };
    let write_error = |e: crate::project::OutputError| crate::document::DocumentError::Write {
        path: path.to_path_buf(),
        cause: crate::document::WriteProblem::Output(e),
    };
    crate::project::check_output(path, &rule).map_err(write_error)?;
    let bytes = crate::mesh::stl_bytes(&world_mesh(doc, which, frame)?);
    crate::project::write_output(path, &bytes, &rule).map_err(write_error)?;
    Ok(bytes.len())
}
