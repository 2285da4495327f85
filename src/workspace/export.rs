//! Per-component export with the transform baked in (CodeStack's "Export Part Or
//! Component To STL", "Export Relative To Coordinate System"; issue 37, capability
//! 3): components' meshes at their poses, in the world or in a coordinate system, as
//! binary STL ([`export_stl`]) or binary glTF ([`export_glb`]). The whole document as
//! glTF with one node per component at its pose is [`Document::export_glb`].

use crate::document::{Document, DocumentError, GlbExport, WriteProblem};
use crate::math::Transform;
use crate::mesh::{glb_bytes, stl_bytes, GlbNode, Mesh};
use std::path::Path;

/// The meshes of components `which` (indices) of `doc` at their poses, in one mesh,
/// expressed in the coordinate system `frame` (its pose in the world; `None`: the
/// world), mm: what a per-component STL export writes, with the transform baked in
/// (CodeStack's "Export Part Or Component To STL").
///
/// # Errors
/// [`DocumentError::NotLoaded`] for a suppressed component whose part is not loaded
/// (its mesh is not known; an empty one would export nothing without a word).
pub fn world_mesh(
    doc: &Document,
    which: &[usize],
    frame: Option<&Transform>,
) -> Result<Mesh, DocumentError> {
    let to_frame = frame.map(|f| f.inverse());
    let mut out = Mesh {
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

/// Refuses a suppressed component among `which`: SolidWorks has no body for one, and
/// its part may not even be loaded ([`crate::document::Part::is_loaded`]).
fn refuse_suppressed(doc: &Document, which: &[usize]) -> Result<(), DocumentError> {
    match which.iter().find(|&&i| doc.components()[i].is_suppressed()) {
        Some(&i) => Err(DocumentError::Suppressed(
            doc.components()[i].name.clone().into(),
        )),
        None => Ok(()),
    }
}

/// Binary STL (mm) of [`world_mesh`] of components `which` in `frame`: what
/// [`export_stl`] writes.
///
/// # Errors
/// [`DocumentError::Suppressed`] naming the first suppressed component of `which`.
pub fn world_stl_bytes(
    doc: &Document,
    which: &[usize],
    frame: Option<&Transform>,
) -> Result<Vec<u8>, DocumentError> {
    refuse_suppressed(doc, which)?;
    Ok(stl_bytes(&world_mesh(doc, which, frame)?))
}

/// Binary glTF (GLB) of components `which` with their poses baked in: one node per
/// component, named as it, without a matrix of its own, whose mesh is the
/// component's [`world_mesh`] in `frame` (its pose in the world; `None`: the world).
/// As every fitup GLB ([`crate::mesh::glb_bytes`]) positions are in metres (f32) under
/// the root node [`crate::mesh::GLB_ROOT`], which turns fitup's +Z up into glTF's +Y
/// up, so reading the file back ([`crate::mesh::read_mesh_file`]) gives each
/// component's mesh in `frame`, mm (to f32's precision).
///
/// # Errors
/// [`DocumentError::Suppressed`] naming the first suppressed component of `which`;
/// [`DocumentError::GlbExport`] past GLB's 4 GiB.
pub fn world_glb_bytes(
    doc: &Document,
    which: &[usize],
    frame: Option<&Transform>,
) -> Result<Vec<u8>, DocumentError> {
    refuse_suppressed(doc, which)?;
    let meshes = which
        .iter()
        .map(|&i| world_mesh(doc, &[i], frame))
        .collect::<Result<Vec<Mesh>, _>>()?;
    let nodes: Vec<GlbNode> = which
        .iter()
        .zip(&meshes)
        .map(|(&i, mesh)| GlbNode {
            name: &doc.components()[i].name,
            mesh,
            pose: Transform::IDENTITY,
        })
        .collect();
    glb_bytes(&nodes).map_err(DocumentError::GlbExport)
}

/// Writes `bytes()` to `path` through the project's write rule
/// ([`crate::project::check_output`]), as [`Document::export_glb`] does: a file the
/// document was built from ([`Document::source_files`]: its YAML, sub-documents,
/// meshes, STEP files, URDFs) is never replaced, not even with `force`
/// ([`crate::project::OutputError::Source`]); another existing file only when fitup
/// wrote it and it is not a project file (by extension), or with `force` (never a
/// link or fitup's bookkeeping); checked before anything is built, written
/// atomically. Returns the bytes written.
fn write_export(
    doc: &Document,
    path: &Path,
    force: bool,
    bytes: impl FnOnce() -> Result<Vec<u8>, DocumentError>,
) -> Result<Vec<u8>, DocumentError> {
    let sources = doc.source_files();
    let rule = crate::project::OutputRule::forced(force).protecting(&sources);
    let write_error = |e: crate::project::OutputError| DocumentError::Write {
        path: path.to_path_buf(),
        cause: WriteProblem::Output(e),
    };
    crate::project::check_output(path, &rule).map_err(write_error)?;
    let bytes = bytes()?;
    // Checked again through the folder handle it is written with.
    crate::project::write_output(path, &bytes, &rule).map_err(write_error)?;
    Ok(bytes)
}

/// Writes [`world_stl_bytes`] of components `which` to `path` through the project's
/// write rule, as [`Document::export_glb`] does (never a file the document was built
/// from, even with `force`; another existing file only when fitup wrote it, or with
/// `force`; atomically).
/// Returns the bytes written.
///
/// # Errors
/// [`DocumentError::Write`] naming the file, or as [`world_stl_bytes`].
pub fn export_stl(
    doc: &Document,
    path: &Path,
    which: &[usize],
    frame: Option<&Transform>,
    force: bool,
) -> Result<usize, DocumentError> {
    Ok(write_export(doc, path, force, || world_stl_bytes(doc, which, frame))?.len())
}

/// Writes [`world_glb_bytes`] of components `which` to `path` through the project's
/// write rule, as [`export_stl`] does: each component's mesh with its pose (in
/// `frame`) baked in, one node per component.
///
/// # Errors
/// [`DocumentError::Write`] naming the file, or as [`world_glb_bytes`].
pub fn export_glb(
    doc: &Document,
    path: &Path,
    which: &[usize],
    frame: Option<&Transform>,
    force: bool,
) -> Result<GlbExport, DocumentError> {
    let bytes = write_export(doc, path, force, || world_glb_bytes(doc, which, frame))?;
    Ok(GlbExport {
        path: path.to_path_buf(),
        nodes: which.len(),
        meshes: which.len(),
        bytes: bytes.len(),
    })
}
