//! A document's components ready for collision queries: one [`Collider`] per
//! component (shared per part mesh) and the cut cells of parts that have the
//! feature, all cached across watch reruns while the meshes are unchanged.

use super::WorkspaceError;
use crate::collision::{
    check, check_all, surface_distance, sweep, Collider, ColliderCache, CollisionError, Contact,
    CutCells, CutSpec, Method, Motion, Obstacle, PairContact, PosedPart, SweepHit, SweepOptions,
};
use crate::document::{Document, Feature};
use crate::mesh::Mesh;
use std::collections::HashMap;
use std::sync::{Arc, Weak};

/// Colliders and derived cut cells by mesh, kept between runs.
#[derive(Default)]
pub struct SceneCache {
    colliders: ColliderCache,
    cells: HashMap<(usize, String), (Weak<Mesh>, Arc<CutCells>)>,
}

impl SceneCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The collider of a mesh.
    pub fn collider(&mut self, mesh: &Arc<Mesh>) -> Result<Arc<Collider>, CollisionError> {
        self.colliders.get(mesh)
    }

    /// The cells of `spec` cut from `mesh`, derived once per mesh and spec.
    pub fn cells(
        &mut self,
        mesh: &Arc<Mesh>,
        spec: &CutSpec,
    ) -> Result<Arc<CutCells>, CollisionError> {
        let key = (Arc::as_ptr(mesh) as usize, format!("{spec:?}"));
        if let Some((w, c)) = self.cells.get(&key) {
            if w.upgrade().is_some_and(|m| Arc::ptr_eq(&m, mesh)) {
                return Ok(c.clone());
            }
        }
        let collider = self.collider(mesh)?;
        let cells = Arc::new(CutCells::derive(&collider, spec.clone())?);
        self.cells.retain(|_, (w, _)| w.strong_count() > 0);
        self.cells
            .insert(key, (Arc::downgrade(mesh), cells.clone()));
        Ok(cells)
    }

    /// Colliders built so far (the watch header and tests use it).
    pub fn collider_builds(&self) -> usize {
        self.colliders.build_count()
    }
}

/// The components of a document as collision shapes at their current poses.
pub struct Scene {
    /// Per component: the collider of its part's mesh.
    pub colliders: Vec<Arc<Collider>>,
    /// Per component: the cut cells of its part, when the part has the feature.
    pub cells: Vec<Option<Arc<CutCells>>>,
    /// Per component: the pose (part frame → world, mm).
    pub poses: Vec<crate::math::Transform>,
}

impl Scene {
    /// Builds the scene of `doc` through `cache`.
    ///
    /// # Errors
    /// A part the document does not hold ([`WorkspaceError::Document`]), a mesh or
    /// cut that cannot be used ([`WorkspaceError::Collision`]).
    pub fn new(doc: &Document, cache: &mut SceneCache) -> Result<Scene, WorkspaceError> {
        let n = doc.components().len();
        let mut colliders = Vec::with_capacity(n);
        let mut cells = Vec::with_capacity(n);
        for (i, c) in doc.components().iter().enumerate() {
            let mesh = doc.mesh_of(i);
            colliders.push(cache.collider(mesh)?);
            let part = doc.part(&c.part)?;
            let mut spec = part.features.iter().map(|f| match f {
                Feature::CutCells { spec, .. } => spec,
            });
            cells.push(match spec.next_back() {
                Some(s) => Some(cache.cells(mesh, s)?),
                None => None,
            });
        }
        Ok(Scene {
            colliders,
            cells,
            poses: doc.components().iter().map(|c| c.transform).collect(),
        })
    }

    /// Component `i` as a posed part.
    pub fn posed(&self, i: usize) -> PosedPart<'_> {
        PosedPart {
            collider: &self.colliders[i],
            cells: self.cells[i].as_deref(),
            pose: self.poses[i],
        }
    }

    /// Every pair that touches or interferes (`a < b`, component indices).
    pub fn contacts(
        &self,
        method: Method,
        tolerance: f64,
    ) -> Result<Vec<PairContact>, CollisionError> {
        let parts: Vec<PosedPart> = (0..self.poses.len()).map(|i| self.posed(i)).collect();
        check_all(&parts, method, tolerance)
    }

    /// The verdict for components `a` and `b`.
    pub fn contact(
        &self,
        a: usize,
        b: usize,
        method: Method,
        tolerance: f64,
    ) -> Result<Contact, CollisionError> {
        check(method, &self.posed(a), &self.posed(b), tolerance)
    }

    /// Distance between the surfaces of `a` and `b` (mm); 0 when they touch or cross.
    /// Searches no farther than `stop` mm (returns `stop` or more beyond it).
    pub fn clearance(&self, a: usize, b: usize, stop: f64) -> Result<f64, CollisionError> {
        surface_distance(
            &self.colliders[a],
            &self.poses[a],
            &self.colliders[b],
            &self.poses[b],
            stop,
        )
    }

    /// The first contact of component `moving` along `motion` with any other
    /// component; `with` in the result is a component index.
    pub fn sweep(
        &self,
        moving: usize,
        motion: &Motion,
        options: &SweepOptions,
    ) -> Result<SweepHit, CollisionError> {
        let others: Vec<usize> = (0..self.poses.len()).filter(|&i| i != moving).collect();
        let obstacles: Vec<Obstacle> = others
            .iter()
            .map(|&i| Obstacle {
                collider: &self.colliders[i],
                pose: self.poses[i],
            })
            .collect();
        let mut hit = sweep(&self.colliders[moving], motion, &obstacles, options)?;
        hit.with = hit.with.map(|k| others[k]);
        Ok(hit)
    }
}
