//! A document written as binary glTF (GLB) for other viewers: `fitup export`,
//! `doc.export_glb(file)` in scripts. Components with their poses baked into their
//! meshes (per-component export) are [`crate::workspace::export_glb`].

use super::{Document, DocumentError, WriteProblem};
use crate::mesh::{glb_bytes, GlbNode};
use std::path::{Path, PathBuf};

/// What [`Document::export_glb`] or [`crate::workspace::export_glb`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GlbExport {
    /// The file written.
    pub path: PathBuf,
    /// glTF nodes besides the root: one per component written ([`Document::export_glb`]:
    /// every one shown, robot links' generated components included, suppressed and
    /// hidden ones left out).
    pub nodes: usize,
    /// glTF meshes: one per distinct part mesh ([`crate::workspace::export_glb`]: one
    /// per component, each placed by its pose).
    pub meshes: usize,
    /// Bytes written.
    pub bytes: usize,
}

impl Document {
    /// The document as GLB bytes: one node per component that is neither suppressed
    /// nor hidden, named as the component, at
    /// its current pose (robot links where the joints put them), showing its part's
    /// mesh (one glTF mesh per part, shared by its components). Metres and +Y up as
    /// glTF wants: see [`crate::mesh::glb_bytes`] (a root node `fitup` turns fitup's
    /// +Z-up world; each component node's matrix is its pose with the translation
    /// in metres).
    pub fn glb_bytes(&self) -> Result<Vec<u8>, DocumentError> {
        let nodes: Vec<GlbNode> = self
            .components()
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_shown())
            .map(|(i, c)| GlbNode {
                name: &c.name,
                mesh: self.mesh_of(i).as_ref(),
                pose: c.transform,
            })
            .collect();
        glb_bytes(&nodes).map_err(DocumentError::GlbExport)
    }

    /// Writes [`Document::glb_bytes`] to `path` through the project's write rule
    /// ([`crate::project::check_output`]): a file this document was built from
    /// ([`Document::source_files`]: its YAML, sub-documents, meshes, STEP files,
    /// URDFs) is never replaced, not even with `force`
    /// ([`crate::project::OutputError::Source`]); another existing file only when
    /// fitup wrote it, or with `force`; written atomically (a reader never sees half a
    /// file), and checked before anything is built.
    pub fn export_glb(&self, path: &Path, force: bool) -> Result<GlbExport, DocumentError> {
        let sources = self.source_files();
        let rule = crate::project::OutputRule::forced(force).protecting(&sources);
        let write_error = |e: crate::project::OutputError| DocumentError::Write {
            path: path.to_path_buf(),
            cause: WriteProblem::Output(e),
        };
        crate::project::check_output(path, &rule).map_err(write_error)?;
        let bytes = self.glb_bytes()?;
        // Checked again through the folder handle it is written with.
        crate::project::write_output(path, &bytes, &rule).map_err(write_error)?;
        let shown: Vec<usize> = (0..self.components().len())
            .filter(|&i| self.components()[i].is_shown())
            .collect();
        let mut meshes: Vec<*const crate::mesh::Mesh> = shown
            .iter()
            .map(|&i| std::sync::Arc::as_ptr(self.mesh_of(i)))
            .collect();
        meshes.sort();
        meshes.dedup();
        Ok(GlbExport {
            path: path.to_path_buf(),
            nodes: shown.len(),
            meshes: meshes.len(),
            bytes: bytes.len(),
        })
    }
}
