//! A document's components ready for collision queries: one [`Collider`] per
//! component (shared per part mesh) and the cut cells of parts that have the
//! feature, all cached across watch reruns while the meshes are unchanged.

use super::WorkspaceError;
use crate::collision::{
    candidate_pairs, check, clearance, interferes, sweep, Collider, ColliderCache, CollisionError,
    Contact, CutCells, CutSpec, Method, Motion, Obstacle, PairContact, PosedPart, SweepHit,
    SweepOptions,
};
use crate::document::{Document, Feature};
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, Weak};

/// Colliders and derived cut cells by mesh, and pair verdicts by pose, kept between
/// runs.
#[derive(Default)]
pub struct SceneCache {
    colliders: ColliderCache,
    cells: HashMap<(usize, String), (Weak<Mesh>, Arc<CutCells>)>,
    verdicts: Arc<Mutex<Verdicts>>,
}

/// Most pair verdicts remembered; beyond, the memo starts over.
const MAX_VERDICTS: usize = 100_000;

/// What a pair verdict depends on: both colliders (and cut cells), both poses
/// (exact bits), the method and the tolerance.
#[derive(Clone, PartialEq, Eq, Hash)]
struct VerdictKey {
    parts: [usize; 4],
    poses: [[u64; 7]; 2],
    method: Method,
    tolerance: u64,
}

/// Pair verdicts of earlier passes. Each entry keeps weak handles of its colliders
/// and cells: an address reused by another mesh after a drop never matches.
#[derive(Default)]
struct Verdicts(HashMap<VerdictKey, (Weak<Collider>, Weak<Collider>, Contact)>);

fn pose_bits(t: &crate::math::Transform) -> [u64; 7] {
    let iso = t.isometry();
    let q = iso.rotation.coords;
    let v = iso.translation.vector;
    [q[0], q[1], q[2], q[3], v.x, v.y, v.z].map(f64::to_bits)
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

    /// The colliders of `meshes` (same order), the missing ones built in parallel.
    /// The mesh of a part that is not loaded ([`crate::document::Part::is_loaded`],
    /// used by suppressed components only) gets a stand-in collider (see
    /// [`Scene::colliders`]).
    pub fn colliders(
        &mut self,
        meshes: &[&Arc<Mesh>],
    ) -> Result<Vec<Arc<Collider>>, CollisionError> {
        let unloaded = crate::document::unloaded_mesh();
        let stand_in = stand_in_mesh();
        let meshes: Vec<&Arc<Mesh>> = meshes
            .iter()
            .map(|&m| {
                if Arc::ptr_eq(m, &unloaded) {
                    stand_in
                } else {
                    m
                }
            })
            .collect();
        self.colliders.get_all(&meshes)
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

/// The collider mesh of a component whose part is not loaded: one small triangle
/// (1 mm) at its part origin. Such a component is suppressed, so inactive (no
/// contact, no obstacle); the stand-in only fills its slot in [`Scene::colliders`].
fn stand_in_mesh() -> &'static Arc<Mesh> {
    static STAND_IN: std::sync::OnceLock<Arc<Mesh>> = std::sync::OnceLock::new();
    STAND_IN.get_or_init(|| {
        Arc::new(Mesh {
            vertices: vec![
                crate::math::Point3::new(0.0, 0.0, 0.0),
                crate::math::Point3::new(1.0, 0.0, 0.0),
                crate::math::Point3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2]],
        })
    })
}

/// The components of a document as collision shapes at their current poses.
pub struct Scene {
    /// Per component: the collider of its part's mesh (a suppressed component whose
    /// part is not loaded: a stand-in, see [`SceneCache::colliders`]; it is never
    /// active).
    pub colliders: Vec<Arc<Collider>>,
    /// Per component: the cut cells of its part, when the part has the feature.
    pub cells: Vec<Option<Arc<CutCells>>>,
    /// Per component: the pose (part frame → world, mm).
    pub poses: Vec<crate::math::Transform>,
    /// Per component: whether it takes part (a suppressed component does not: no
    /// contacts, no obstacle).
    pub active: Vec<bool>,
    /// The cache's pair verdicts: a pass over an unchanged scene (a watch rerun, a
    /// repeated check) only recomputes the pairs that moved.
    verdicts: Arc<Mutex<Verdicts>>,
}

impl Scene {
    /// Builds the scene of `doc` through `cache`.
    ///
    /// # Errors
    /// A part the document does not hold ([`WorkspaceError::Document`]), a mesh or
    /// cut that cannot be used ([`WorkspaceError::Collision`]).
    pub fn new(doc: &Document, cache: &mut SceneCache) -> Result<Scene, WorkspaceError> {
        let n = doc.components().len();
        // every part's tree at once, in parallel (the cost of opening a large cell)
        let meshes: Vec<&Arc<Mesh>> = (0..n).map(|i| doc.mesh_of(i)).collect();
        let colliders = cache.colliders(&meshes)?;
        let mut cells = Vec::with_capacity(n);
        for (i, c) in doc.components().iter().enumerate() {
            let mesh = doc.mesh_of(i);
            let part = doc.part(&c.part)?;
            if !part.is_loaded() {
                // suppressed: never checked, so never cut
                cells.push(None);
                continue;
            }
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
            active: doc
                .components()
                .iter()
                .enumerate()
                .map(|(i, c)| !c.is_suppressed() && doc.part_loaded(i))
                .collect(),
            verdicts: cache.verdicts.clone(),
        })
    }

    /// Whether component `i` takes part in checks (it is not suppressed).
    pub fn is_active(&self, i: usize) -> bool {
        self.active.get(i).copied().unwrap_or(true)
    }

    /// Component `i` as a posed part.
    pub fn posed(&self, i: usize) -> PosedPart<'_> {
        PosedPart {
            collider: &self.colliders[i],
            cells: self.cells[i].as_deref(),
            pose: self.poses[i],
        }
    }

    /// Every pair that touches or interferes (`a < b`, component indices), by
    /// `method` at penetration `tolerance` (mm). Pairs whose world boxes are apart are
    /// skipped; pairs whose colliders and poses are as in an earlier pass through the
    /// same [`SceneCache`] reuse that verdict; the rest run in parallel.
    pub fn contacts(
        &self,
        method: Method,
        tolerance: f64,
    ) -> Result<Vec<PairContact>, CollisionError> {
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(CollisionError::BadTolerance(tolerance));
        }
        let parts: Vec<PosedPart> = (0..self.poses.len()).map(|i| self.posed(i)).collect();
        let mut candidates = candidate_pairs(&parts)?;
        candidates.retain(|&(i, j)| self.is_active(i) && self.is_active(j));
        let cells_id = |i: usize| {
            self.cells[i]
                .as_ref()
                .map_or(0, |c| Arc::as_ptr(c) as usize)
        };
        let key = |i: usize, j: usize| VerdictKey {
            parts: [
                Arc::as_ptr(&self.colliders[i]) as usize,
                Arc::as_ptr(&self.colliders[j]) as usize,
                cells_id(i),
                cells_id(j),
            ],
            poses: [pose_bits(&self.poses[i]), pose_bits(&self.poses[j])],
            method,
            tolerance: tolerance.to_bits(),
        };
        let known: Vec<Option<Contact>> = {
            let memo = self.verdicts.lock().unwrap_or_else(|e| e.into_inner());
            candidates
                .iter()
                .map(|&(i, j)| {
                    memo.0.get(&key(i, j)).and_then(|(wa, wb, c)| {
                        let same = |w: &Weak<Collider>, k: usize| {
                            w.upgrade()
                                .is_some_and(|x| Arc::ptr_eq(&x, &self.colliders[k]))
                        };
                        (same(wa, i) && same(wb, j)).then_some(*c)
                    })
                })
                .collect()
        };
        let computed: Vec<Option<Contact>> = candidates
            .par_iter()
            .zip(&known)
            .map(|(&(i, j), k)| match k {
                Some(_) => Ok(None),
                None => check(method, &parts[i], &parts[j], tolerance).map(Some),
            })
            .collect::<Result<_, CollisionError>>()?;
        let mut memo = self.verdicts.lock().unwrap_or_else(|e| e.into_inner());
        if memo.0.len() > MAX_VERDICTS {
            memo.0.clear();
        }
        let mut out = Vec::new();
        for ((&(i, j), k), c) in candidates.iter().zip(known).zip(computed) {
            if let Some(c) = c {
                memo.0.insert(
                    key(i, j),
                    (
                        Arc::downgrade(&self.colliders[i]),
                        Arc::downgrade(&self.colliders[j]),
                        c,
                    ),
                );
            }
            match k.or(c) {
                Some(Contact::Separate) | None => {}
                Some(contact) => out.push(PairContact {
                    a: i,
                    b: j,
                    contact,
                }),
            }
        }
        Ok(out)
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

    /// Whether components `a` and `b` interfere by `method` at penetration
    /// `tolerance` (mm): the same answer as [`contact`](Self::contact)`.is_interfering()`,
    /// but the exact method stops at the first crossing deeper than the tolerance
    /// instead of measuring the deepest one (the planners' yes/no question).
    pub fn interferes(
        &self,
        a: usize,
        b: usize,
        method: Method,
        tolerance: f64,
    ) -> Result<bool, CollisionError> {
        match method {
            Method::Exact => interferes(
                &self.colliders[a],
                &self.poses[a],
                &self.colliders[b],
                &self.poses[b],
                tolerance,
            ),
            Method::Aabb | Method::Cells => {
                Ok(check(method, &self.posed(a), &self.posed(b), tolerance)?.is_interfering())
            }
        }
    }

    /// The clearance between components `a` and `b` (mm, [`clearance`]): the
    /// distance between their surfaces, 0 when they touch, cross or one is inside
    /// the other; searched up to `cap` mm (returns `cap` when nothing is nearer).
    pub fn clearance(&self, a: usize, b: usize, cap: f64) -> Result<f64, CollisionError> {
        clearance(
            &self.colliders[a],
            &self.poses[a],
            &self.colliders[b],
            &self.poses[b],
            cap,
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
        let others: Vec<usize> = (0..self.poses.len())
            .filter(|&i| i != moving && self.is_active(i))
            .collect();
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
