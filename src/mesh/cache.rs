//! [`MeshCache`]: meshes kept between watch reruns, re-read only when their file changed.

use super::step::{read_step, read_step_stored, StepError, StepOptions};
use super::{Mesh, MeshError, MeshErrorKind};
use crate::fsutil::{content_hash, stamp, FileKind, Stamp};
use crate::project::Project;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

struct Entry {
    stamp: Stamp,
    hash: u64,
    /// The other files the mesh was read from (a `.gltf`'s buffers) and their stamps.
    deps: Vec<(PathBuf, Stamp)>,
    mesh: Arc<Mesh>,
}

impl Entry {
    /// Whether the file's buffers are as they were read.
    fn deps_fresh(&self) -> bool {
        self.deps
            .iter()
            .all(|(p, s)| stamp(p).is_ok_and(|now| now == *s))
    }
}

/// What [`read_mesh`] found: the main file's content hash, the other files read with
/// their stamps, and the mesh (`None`: unchanged, the cached mesh stands).
type Read = (u64, Vec<(PathBuf, Stamp)>, Option<Mesh>);

/// Loaded meshes (every format [`super::read_mesh_file`] reads) by canonical path. A
/// lookup costs one `stat` when the file did not change (and one per buffer file of a
/// `.gltf`); a file whose stamp changed is re-read, and re-parsed only when its bytes
/// (or a buffer file) did.
#[derive(Default)]
pub struct MeshCache {
    entries: HashMap<PathBuf, Entry>,
    /// STEP geometry by (canonical path, deflection bits, angle bits), with the stamp
    /// of the STEP file it was read from.
    steps: HashMap<(PathBuf, u64, u64), (Stamp, StepMesh)>,
    loads: usize,
}

/// A STEP file's geometry as one mesh ([`MeshCache::get_step`]).
#[derive(Debug, Clone)]
pub struct StepMesh {
    /// Every placed solid at its placement in the file's root frame, mm
    /// ([`super::step::StepModel::placed_mesh`]).
    pub mesh: Arc<Mesh>,
    /// Their exact B-rep volume together, mm³.
    pub exact_volume: f64,
    /// Whether Open CASCADE's result came from the tessellation store.
    pub from_store: bool,
}

impl MeshCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The mesh of the file at `path` (STL, OBJ, PLY, glTF/GLB), from the cache when
    /// the file is unchanged.
    pub fn get(&mut self, path: &Path) -> Result<Arc<Mesh>, MeshError> {
        let key = path.canonicalize().map_err(|e| {
            MeshError::new(MeshErrorKind::Read, format!("cannot open: {e}")).in_file(path)
        })?;
        self.get_with(key, path, Opener::Path)
    }

    /// [`get`](Self::get) for a mesh of `project` at `path` (absolute and inside the
    /// project, as [`Project::resolve_from`] returns it): the file (and a `.gltf`'s
    /// buffer files) are read through the project's held root without following a
    /// link ([`Project::read_file`]), so a folder swapped for a link after the path
    /// was checked is refused, never read outside.
    pub fn get_in(&mut self, project: &Project, path: &Path) -> Result<Arc<Mesh>, MeshError> {
        self.get_with(path.to_path_buf(), path, Opener::Project(project))
    }

    fn get_with(
        &mut self,
        key: PathBuf,
        path: &Path,
        opener: Opener<'_>,
    ) -> Result<Arc<Mesh>, MeshError> {
        let now = stamp(&key).map_err(|e| {
            MeshError::new(MeshErrorKind::Read, format!("cannot stat: {e}")).in_file(path)
        })?;
        if let Some(e) = self.entries.get(&key) {
            if e.stamp == now && e.deps_fresh() {
                return Ok(e.mesh.clone());
            }
        }
        let known = self.known(&key);
        let (hash, deps, mesh) = read_mesh(&key, path, known, opener)?;
        // `read_mesh` leaves out the mesh only when the bytes hash as the cached entry
        self.store(key, now, hash, deps, mesh).ok_or_else(|| {
            MeshError::new(MeshErrorKind::Read, "the cached mesh vanished").in_file(path)
        })
    }

    /// The other files the cached mesh of `path` was read from (a `.gltf`'s buffers):
    /// what a change of must reload it, as the file itself.
    pub fn files_of(&self, path: &Path) -> Vec<PathBuf> {
        path.canonicalize()
            .ok()
            .and_then(|key| self.entries.get(&key))
            .map(|e| e.deps.iter().map(|(p, _)| p.clone()).collect())
            .unwrap_or_default()
    }

    /// The geometry of the STEP file at `path` tessellated with `options`' deflection
    /// and angle: from memory while the file's stamp is unchanged, else read through
    /// the tessellation store `store` ([`read_step_stored`]; `None`: read with Open
    /// CASCADE every time the file changes).
    ///
    /// With `project`, the file is opened through the project's held root without
    /// following a link ([`read_step_stored`]).
    pub fn get_step(
        &mut self,
        path: &Path,
        project: Option<&Project>,
        options: &StepOptions,
        store: Option<&Path>,
    ) -> Result<StepMesh, StepError> {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        let key = (
            canonical,
            options.linear_deflection.to_bits(),
            options.angular_deflection.to_bits(),
        );
        // Stamped before reading: a change during the read is seen by the next get.
        let now = stamp(&key.0).ok();
        if let (Some(now), Some((then, mesh))) = (now, self.steps.get(&key)) {
            if now == *then {
                return Ok(mesh.clone());
            }
        }
        let model = match store {
            Some(store) => read_step_stored(path, project, options, store)?,
            None => read_step(path, options)?,
        };
        let mesh = StepMesh {
            mesh: Arc::new(model.placed_mesh()?),
            exact_volume: model.placed_exact_volume(),
            from_store: model.from_store,
        };
        self.loads += 1;
        if let Some(now) = now {
            self.steps.insert(key, (now, mesh.clone()));
        }
        Ok(mesh)
    }

    /// Reads and parses the files of `paths` that are not cached or changed, in
    /// parallel (one rayon task per file), so that the [`get`](Self::get) calls
    /// that follow are cache hits: what opening a document of many distinct parts
    /// costs once. A file that cannot be read or parsed is skipped here; its `get`
    /// reports the error.
    pub fn prefetch(&mut self, paths: &[&Path]) {
        self.prefetch_with(paths, Opener::Path)
    }

    /// [`prefetch`](Self::prefetch) of meshes of `project` (paths as for
    /// [`get_in`](Self::get_in)), read through its held root.
    pub fn prefetch_in(&mut self, project: &Project, paths: &[&Path]) {
        self.prefetch_with(paths, Opener::Project(project))
    }

    fn prefetch_with(&mut self, paths: &[&Path], opener: Opener<'_>) {
        use rayon::prelude::*;
        let mut wanted: Vec<(PathBuf, Stamp)> = Vec::new();
        for path in paths {
            let key = match opener {
                Opener::Path => match path.canonicalize() {
                    Ok(k) => k,
                    Err(_) => continue,
                },
                Opener::Project(_) => path.to_path_buf(),
            };
            let Ok(now) = stamp(&key) else { continue };
            let fresh = self
                .entries
                .get(&key)
                .is_some_and(|e| e.stamp == now && e.deps_fresh());
            if !fresh && !wanted.iter().any(|(k, _)| *k == key) {
                wanted.push((key, now));
            }
        }
        if wanted.len() < 2 {
            return; // nothing to share out; `get` reads it
        }
        let known: HashMap<&PathBuf, u64> = wanted
            .iter()
            .filter_map(|(k, _)| self.known(k).map(|h| (k, h)))
            .collect();
        let read: Vec<Option<Read>> = wanted
            .par_iter()
            .map(|(key, _)| read_mesh(key, key, known.get(key).copied(), opener).ok())
            .collect();
        for ((key, now), r) in wanted.into_iter().zip(read) {
            if let Some((hash, deps, mesh)) = r {
                self.store(key, now, hash, deps, mesh);
            }
        }
    }

    /// The cached hash of `key` that lets [`read_mesh`] skip parsing: only while the
    /// entry's buffer files are unchanged (their bytes are not hashed).
    fn known(&self, key: &Path) -> Option<u64> {
        self.entries
            .get(key)
            .filter(|e| e.deps_fresh())
            .map(|e| e.hash)
    }

    /// Records what [`read_mesh`] found for `key` at `stamp`: a parsed mesh replaces
    /// the entry (one more load); no mesh (the bytes hash as cached) refreshes the
    /// cached entry's stamp. Returns the entry's mesh (`None`: no mesh and no entry).
    fn store(
        &mut self,
        key: PathBuf,
        stamp: Stamp,
        hash: u64,
        deps: Vec<(PathBuf, Stamp)>,
        mesh: Option<Mesh>,
    ) -> Option<Arc<Mesh>> {
        let Some(mesh) = mesh else {
            let e = self.entries.get_mut(&key)?;
            e.stamp = stamp;
            return Some(e.mesh.clone());
        };
        let mesh = Arc::new(mesh);
        self.loads += 1;
        self.entries.insert(
            key,
            Entry {
                stamp,
                hash,
                deps,
                mesh: mesh.clone(),
            },
        );
        Some(mesh)
    }

    /// How many times a file was actually parsed (for tests and the watch header).
    pub fn parse_count(&self) -> usize {
        self.loads
    }

    /// Reads without caching (one-off use), any format ([`super::read_mesh_file`]).
    pub fn read_uncached(path: &Path) -> Result<Mesh, MeshError> {
        super::read_mesh_file(path)
    }
}

/// Reads the mesh file `key` (canonical path; errors name `path`), any format: its
/// content hash, the other files read (a `.gltf`'s buffers) with their stamps, and the
/// parsed mesh, or `None` for the mesh when the bytes hash to `known` (the cached
/// mesh stands; the caller passes `known` only while the buffer files are unchanged).
fn read_mesh(
    key: &Path,
    path: &Path,
    known: Option<u64>,
    opener: Opener<'_>,
) -> Result<Read, MeshError> {
    if super::step::is_step_path(path) {
        return Err(
            MeshError::new(MeshErrorKind::Unsupported, super::step::not_a_part_mesh())
                .in_file(path),
        );
    }
    let bytes = opener.read(key).map_err(|e| e.in_file(path))?;
    let read = |f: &Path| {
        opener
            .read(f)
            // The reader wants a ReadError; the opener's MeshError (a refused open, a
            // precheck) is passed on in its words, as an error of kind `Other`.
            .map_err(|e| crate::fsutil::ReadError::Io(std::io::Error::other(e.message).into()))
    };
    let hash = content_hash(&bytes);
    if known == Some(hash) {
        return Ok((hash, Vec::new(), None));
    }
    let format = super::MeshFormat::detect(path, &bytes).map_err(|e| e.in_file(path))?;
    let (mesh, files) =
        super::parse_mesh_with(&bytes, format, key.parent(), &read).map_err(|e| e.in_file(path))?;
    let deps = files
        .into_iter()
        .map(|f| {
            let s = stamp(&f).map_err(|e| {
                MeshError::new(
                    MeshErrorKind::Read,
                    format!("cannot stat {}: {e}", f.display()),
                )
            })?;
            Ok((f, s))
        })
        .collect::<Result<_, MeshError>>()?;
    Ok((hash, deps, Some(mesh)))
}

/// How the cache opens files: by path (a library user's own paths, [`MeshCache::get`]),
/// or through a project's held root without following a link ([`MeshCache::get_in`]).
#[derive(Clone, Copy)]
enum Opener<'a> {
    Path,
    Project(&'a Project),
}

impl Opener<'_> {
    /// The file's bytes, after [`super::precheck`] on its first bytes: a binary STL or
    /// PLY whose header passes a cap is refused before the file is read.
    fn read(&self, path: &Path) -> Result<Vec<u8>, MeshError> {
        use crate::fsutil::ReadError;
        let file = match self {
            Opener::Path => {
                // Refused before the open (a FIFO must not block it).
                let md = std::fs::metadata(path).map_err(|e| ReadError::Io(e.into()))?;
                if !md.is_file() {
                    return Ok(crate::fsutil::read_file(path, FileKind::Mesh)?);
                }
                std::fs::File::open(path).map_err(|e| ReadError::Io(e.into()))?
            }
            Opener::Project(p) => p.open_file(path).map_err(|e| ReadError::Io(e.into()))?,
        };
        super::precheck(&file, path)?;
        Ok(crate::fsutil::read_opened(file, FileKind::Mesh)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Point3;

    #[test]
    fn unchanged_files_are_not_reparsed() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.stl");
        let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        super::super::write_stl(&p, &m).unwrap();
        let mut cache = MeshCache::new();
        let a = cache.get(&p).unwrap();
        let b = cache.get(&p).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.parse_count(), 1);
        // Same bytes rewritten: new stamp, same content, still not re-parsed.
        super::super::write_stl(&p, &m).unwrap();
        cache.get(&p).unwrap();
        assert_eq!(cache.parse_count(), 1);
        let m2 = Mesh::cuboid(Point3::origin(), Point3::new(2.0, 1.0, 1.0));
        super::super::write_stl(&p, &m2).unwrap();
        let c = cache.get(&p).unwrap();
        assert_eq!(cache.parse_count(), 2);
        assert_eq!(c.bounds(), m2.bounds());
    }

    /// Prefetching parses each changed file once, leaves the `get`s that follow as
    /// hits, and leaves errors to `get`.
    #[test]
    fn prefetch_fills_the_cache_and_leaves_errors_to_get() {
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<_> = (0..4)
            .map(|i| dir.path().join(format!("{i}.stl")))
            .collect();
        for (i, p) in paths.iter().enumerate() {
            let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0 + i as f64, 1.0, 1.0));
            super::super::write_stl(p, &m).unwrap();
        }
        let bad = dir.path().join("bad.stl");
        std::fs::write(&bad, b"solid x\nfacet nonsense").unwrap();
        let missing = dir.path().join("missing.stl");
        let mut cache = MeshCache::new();
        let mut all: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        all.extend([bad.as_path(), missing.as_path(), paths[0].as_path()]);
        cache.prefetch(&all);
        assert_eq!(cache.parse_count(), 4);
        for (i, p) in paths.iter().enumerate() {
            let m = cache.get(p).unwrap();
            assert_eq!(m.bounds().unwrap().hi.x, 1.0 + i as f64);
        }
        assert_eq!(cache.parse_count(), 4, "the gets after a prefetch are hits");
        assert!(cache.get(&bad).is_err());
        assert!(cache.get(&missing).is_err());
        // nothing changed: a second prefetch parses nothing
        cache.prefetch(&all);
        assert_eq!(cache.parse_count(), 4);
    }
}
