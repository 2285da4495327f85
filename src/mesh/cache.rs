//! [`MeshCache`]: meshes kept between watch reruns, re-read only when their file changed.

use super::{read_stl, Mesh, MeshError};
use crate::fsutil::{content_hash, stamp, Stamp};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

struct Entry {
    stamp: Stamp,
    hash: u64,
    mesh: Arc<Mesh>,
}

/// Loaded meshes by canonical path. A lookup costs one `stat` when the file did not
/// change; a file whose stamp changed is re-read, and re-parsed only when its bytes did.
#[derive(Default)]
pub struct MeshCache {
    entries: HashMap<PathBuf, Entry>,
    loads: usize,
}

impl MeshCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The mesh of the STL file at `path`, from the cache when the file is unchanged.
    pub fn get(&mut self, path: &Path) -> Result<Arc<Mesh>, MeshError> {
        let key = path
            .canonicalize()
            .map_err(|e| MeshError::invalid(format!("cannot open: {e}")).in_file(path))?;
        let now = stamp(&key)
            .map_err(|e| MeshError::invalid(format!("cannot stat: {e}")).in_file(path))?;
        if let Some(e) = self.entries.get(&key) {
            if e.stamp == now {
                return Ok(e.mesh.clone());
            }
        }
        let bytes = crate::fsutil::read_file(&key, crate::fsutil::FileKind::Mesh)
            .map_err(|e| MeshError::invalid(e.to_string()).in_file(path))?;
        let hash = content_hash(&bytes);
        if let Some(e) = self.entries.get_mut(&key) {
            if e.hash == hash {
                e.stamp = now;
                return Ok(e.mesh.clone());
            }
        }
        let mesh = Arc::new(super::parse_stl(&bytes).map_err(|e| e.in_file(path))?);
        self.loads += 1;
        self.entries.insert(
            key,
            Entry {
                stamp: now,
                hash,
                mesh: mesh.clone(),
            },
        );
        Ok(mesh)
    }

    /// How many times a file was actually parsed (for tests and the watch header).
    pub fn parse_count(&self) -> usize {
        self.loads
    }

    /// Reads without caching (one-off use).
    pub fn read_uncached(path: &Path) -> Result<Mesh, MeshError> {
        read_stl(path)
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
}
