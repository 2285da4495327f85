//! [`Collider`]: the per-mesh collision shape (an AABB tree over the triangles in the
//! part frame), built once and shared, and [`ColliderCache`] which keeps colliders
//! across watch reruns while the mesh is unchanged.

use super::node::{Node, Obb};
use super::triangle::{closest_on_triangle, unit_normal, x_line_crossing, Tri};
use super::{CollisionError, MeshFault};
pub use crate::math::Aabb;
use crate::math::{Point3, Vec3};
use crate::mesh::{Mesh, MeshReport};
use std::collections::HashMap;
use std::sync::{Arc, OnceLock, Weak};

/// Largest coordinate magnitude (mm) a collider accepts: beyond it the f64 spacing
/// exceeds the contact tolerances used here.
pub const MAX_COORDINATE: f64 = 1e9;

/// The plane of a triangle: its unit normal as
/// [`unit_normal`](super::triangle::unit_normal) computes it (zero for a triangle
/// without area) and the normal's dot product with the first corner (mm).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plane {
    pub(crate) normal: Vec3,
    pub(crate) offset: f64,
}

impl Plane {
    pub(crate) fn of(t: &Tri) -> Plane {
        let normal = unit_normal(t).unwrap_or_else(Vec3::zeros);
        Plane {
            normal,
            offset: normal.dot(&t[0].coords),
        }
    }

    /// The plane with unit normal `normal` (or zero) through `p`.
    #[inline]
    pub(crate) fn through(normal: &Vec3, p: &Point3) -> Plane {
        Plane {
            normal: *normal,
            offset: normal.dot(&p.coords),
        }
    }

    /// Whether the oriented box `o` (same frame) reaches within `margin` mm of the
    /// plane; a plane without a normal meets nothing (its triangle has no area).
    /// Conservative against rounding by a bias of 1e-9 of the distances involved.
    #[inline]
    pub(crate) fn meets_obb(&self, o: &Obb, margin: f64) -> bool {
        let n = &self.normal;
        if *n == Vec3::zeros() {
            return false;
        }
        let c = n.dot(&o.centre) - self.offset;
        let r = o.half[0] * n.dot(&o.axes.column(0)).abs()
            + o.half[1] * n.dot(&o.axes.column(1)).abs()
            + o.half[2] * n.dot(&o.axes.column(2)).abs();
        c.abs() <= r + margin + 1e-9 * (1.0 + c.abs() + self.offset.abs())
    }
}

/// The precomputed collision shape of a part's mesh: a bounding-volume hierarchy of
/// axis-aligned boxes over its triangles, in the part frame (mm).
///
/// Built once per mesh ([`Collider::new`]) and shared through `Arc`; queries take it
/// with a pose (`Transform`, part frame → world). Degenerate (zero-area) triangles
/// are dropped: they bound no material.
///
/// Memory: at most `2n − 1` nodes (a leaf per triangle) of an axis-aligned and an
/// oriented box (184 bytes) for `n` triangles, with each triangle's plane and index:
/// at most about 410 bytes a triangle besides the mesh, 0.8 GB at
/// [`MAX_TRIANGLES`](crate::mesh::MAX_TRIANGLES); a fine, smooth tessellation keeps
/// leaves of up to four and about a third of that.
#[derive(Debug)]
pub struct Collider {
    mesh: Arc<Mesh>,
    pub(crate) nodes: Vec<Node>,
    /// The oriented box of each node (same index as `nodes`).
    pub(crate) obbs: Vec<Obb>,
    /// Mesh triangle indices in tree order (zero-area triangles left out): a leaf's
    /// triangles are one run. The corners are read from the mesh, never copied.
    order: Vec<u32>,
    /// The plane of each triangle in tree order: the static side of a pair query
    /// reads its planes from here instead of normalising a cross product for every
    /// pair it tests.
    planes: Vec<Plane>,
    report: MeshReport,
    radius: f64,
    pub(crate) eps: f64,
    /// Edge neighbours of each triangle in tree order (`u32::MAX`: none), built on
    /// first use by the shallow-crossing depth walk (`exact::deep_reach`).
    neighbours: OnceLock<Vec<[u32; 3]>>,
    /// Whether the mesh bounds a volume, watertight or not (see
    /// [`encloses_volume`]). Found with the tree, so that no check pays
    /// for it after its deadline.
    encloses: bool,
}

/// Something about a mesh that weakens the answers given for it.
#[derive(Debug, Clone, PartialEq)]
pub enum ColliderWarning {
    /// The mesh is not closed and consistently oriented, so "inside" is undefined:
    /// only surface crossings are reported for it, never containment.
    NotWatertight(MeshReport),
    /// Zero-area triangles were ignored.
    DegenerateTriangles(usize),
}

impl std::fmt::Display for ColliderWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColliderWarning::NotWatertight(r) => write!(
                f,
                "mesh is not watertight ({} open edges, {} non-manifold, {} misoriented): \
                 only surface crossings are detected, not containment",
                r.boundary_edges, r.non_manifold_edges, r.misoriented_edges
            ),
            ColliderWarning::DegenerateTriangles(n) => {
                write!(f, "{n} zero-area triangles ignored")
            }
        }
    }
}

impl Collider {
    /// Builds the tree for `mesh` (part frame, mm).
    ///
    /// Errors: a mesh without any non-degenerate triangle, or with a coordinate that
    /// is not finite or beyond [`MAX_COORDINATE`].
    pub fn new(mesh: Arc<Mesh>) -> Result<Collider, CollisionError> {
        if let Some(index) = mesh.vertices.iter().position(|p| {
            !p.coords
                .iter()
                .all(|v| v.is_finite() && v.abs() <= MAX_COORDINATE)
        }) {
            let p = mesh.vertices[index];
            return Err(CollisionError::BadMesh(MeshFault::VertexOutOfRange {
                index,
                position: [p.x, p.y, p.z],
            }));
        }
        let n = mesh.vertices.len();
        if let Some(i) = mesh
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= n))
        {
            return Err(CollisionError::BadMesh(MeshFault::BadIndex {
                triangle: i,
                vertices: n,
            }));
        }
        let report = mesh.inspect();
        // A watertight mesh's edges balance already: only its orientation is left.
        let encloses = if report.is_watertight() {
            mesh.signed_volume() > 0.0
        } else {
            encloses_volume(&mesh)
        };
        let scale = mesh.area_scale();
        let mut items: Vec<super::tree::Item> = (0..mesh.triangles.len())
            .filter_map(|i| {
                let t = mesh.triangle(i);
                mesh.triangle_has_area(i, scale).then(|| {
                    (
                        nalgebra::center(&nalgebra::center(&t[0], &t[1]), &t[2]),
                        i as u32,
                    )
                })
            })
            .collect();
        if items.is_empty() {
            return Err(CollisionError::BadMesh(MeshFault::NoArea));
        }
        let radius = mesh
            .vertices
            .iter()
            .map(|p| p.coords.norm())
            .fold(0.0, f64::max);
        let (nodes, obbs) = super::tree::build(&mesh, &mut items);
        let order: Vec<u32> = items.into_iter().map(|(_, i)| i).collect();
        let planes = order
            .iter()
            .map(|&i| Plane::of(&mesh.triangle(i as usize)))
            .collect();
        Ok(Collider {
            nodes,
            obbs,
            order,
            planes,
            mesh,
            report,
            radius,
            eps: 1e-9 * scale,
            neighbours: OnceLock::new(),
            encloses,
        })
    }

    /// Triangle `k` in tree order (part frame, mm).
    #[inline]
    pub(crate) fn tri(&self, k: usize) -> Tri {
        self.mesh.triangle(self.order[k] as usize)
    }

    /// The mesh's vertex indices of triangle `k` in tree order, in the order of
    /// [`tri`](Self::tri)'s corners.
    #[inline]
    pub(crate) fn corners(&self, k: usize) -> [u32; 3] {
        self.mesh.triangles[self.order[k] as usize]
    }

    /// The plane of triangle `k` in tree order (part frame).
    #[inline]
    pub(crate) fn plane(&self, k: usize) -> &Plane {
        &self.planes[k]
    }

    /// Every (non-degenerate) triangle, in tree order.
    pub(crate) fn tris(&self) -> impl Iterator<Item = Tri> + '_ {
        (0..self.order.len()).map(|k| self.tri(k))
    }

    /// The parameters `t` (any sign) at which the line `o + t·d` (part frame)
    /// meets a triangle, ascending, into `out` (cleared first). For the solid's
    /// inside along the line, pair them up (a line through an edge or a vertex may
    /// count it twice: callers keep their lines off them).
    pub(crate) fn line_hits(&self, o: &Point3, d: &Vec3, out: &mut Vec<f64>) {
        out.clear();
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if super::triangle::ray_box(o, d, &node.bounds).is_none() {
                continue;
            }
            if node.count > 0 {
                for t in self.leaf_tris(node) {
                    if let Some(s) = super::triangle::ray_triangle(o, d, &t) {
                        out.push(s);
                    }
                }
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
        out.sort_by(f64::total_cmp);
    }

    /// The triangles of leaf `n`.
    #[inline]
    pub(crate) fn leaf_tris(&self, n: &Node) -> impl Iterator<Item = Tri> + '_ {
        (n.first as usize..(n.first + n.count) as usize).map(|k| self.tri(k))
    }

    /// The mesh this collider was built from.
    pub fn mesh(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// Whether the mesh bounds a solid (closed, consistently oriented), so that
    /// containment can be decided.
    pub fn is_solid(&self) -> bool {
        self.report.is_watertight()
    }

    /// Whether the mesh bounds a volume even where it is not a 2-manifold (closed
    /// slices stacked on their faces): see [`encloses_volume`].
    pub(crate) fn encloses_volume(&self) -> bool {
        self.encloses
    }

    /// What weakens the answers for this mesh (not watertight, degenerate triangles).
    pub fn warnings(&self) -> Vec<ColliderWarning> {
        let mut w = Vec::new();
        if !self.report.is_watertight() {
            w.push(ColliderWarning::NotWatertight(self.report));
        }
        if self.report.degenerate_triangles > 0 {
            w.push(ColliderWarning::DegenerateTriangles(
                self.report.degenerate_triangles,
            ));
        }
        w
    }

    /// Bounds of the mesh in the part frame, mm.
    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds
    }

    /// World axis-aligned box of the part at `pose` (the box around the rotated
    /// part-frame bounds: conservative), mm.
    pub fn world_bounds(&self, pose: &crate::math::Transform) -> Aabb {
        self.bounds().transformed(pose.isometry())
    }

    /// Largest distance of a vertex from the part-frame origin, mm: bounds how far
    /// any point of the part moves under a rotation about the origin.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Number of (non-degenerate) triangles.
    pub fn triangle_count(&self) -> usize {
        self.order.len()
    }

    /// Distance from `p` (part frame) to the surface, stopping early once it is
    /// known to be below `stop` (then the value returned is some distance `< stop`).
    pub fn distance_to_point(&self, p: &Point3, stop: f64) -> f64 {
        self.closest(p, stop).0
    }

    /// Whether some triangle lies within `eps` mm of `p` (part frame): the same
    /// answer as `distance_to_point(p, eps) <= eps`, visiting only the nodes whose
    /// boxes come within `eps` of `p` instead of searching for the nearest triangle.
    pub(crate) fn within(&self, p: &Point3, eps: f64) -> bool {
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.bounds.distance_to_point(p) > eps {
                continue;
            }
            if node.count > 0 {
                for k in node.first as usize..(node.first + node.count) as usize {
                    if (p - closest_on_triangle(p, &self.tri(k))).norm() <= eps {
                        return true;
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            } else {
                // deeper than any tree built here (depth ≈ log2 of the leaves)
                return self.distance_to_point(p, eps) <= eps;
            }
        }
        false
    }

    /// The nearest surface point to `p` (part frame): distance (mm), tree-order
    /// index of its triangle and the point, best first through the tree; stops at
    /// the first leaf that brings the distance below `stop` (0: never stops early).
    fn closest(&self, p: &Point3, stop: f64) -> (f64, usize, Point3) {
        self.closest_from(p, stop, None)
    }

    /// [`closest`](Self::closest) given a triangle `hint` (tree order) that is
    /// likely near `p`, such as the answer for a nearby point: its distance bounds
    /// the search from the start, so only nodes nearer than it are opened. The
    /// answer is the same as without the hint when `stop` is 0, down to which of
    /// equally near triangles is returned: a node no nearer than the hint holds no
    /// triangle as near as the nearest, and the nodes left are visited in the same
    /// order.
    pub(crate) fn closest_from(
        &self,
        p: &Point3,
        stop: f64,
        hint: Option<usize>,
    ) -> (f64, usize, Point3) {
        let mut best = (f64::INFINITY, 0usize, *p);
        // strictly above the hint's distance: a triangle exactly as near is found
        let mut bound = f64::INFINITY;
        if let Some(k) = hint.filter(|&k| k < self.order.len()) {
            let d = (p - closest_on_triangle(p, &self.tri(k))).norm();
            bound = d + d * 1e-9 + f64::MIN_POSITIVE;
        }
        let mut stack = WalkStack::new();
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if node.bounds.distance_to_point(p) >= best.0.min(bound) {
                continue;
            }
            if node.count > 0 {
                for k in node.first as usize..(node.first + node.count) as usize {
                    let q = closest_on_triangle(p, &self.tri(k));
                    let d = (p - q).norm();
                    if d < best.0 {
                        best = (d, k, q);
                    }
                }
                if best.0 < stop {
                    return best;
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = self.nodes[l as usize].bounds.distance_to_point(p);
                let dr = self.nodes[r as usize].bounds.distance_to_point(p);
                // nearer child last so it is popped first
                if dl < dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        best
    }

    /// The triangles (tree order) sharing an edge with triangle `k` (tree order);
    /// `u32::MAX` where the edge has no single other triangle (open or non-manifold
    /// edge, or a neighbour dropped as degenerate).
    pub(crate) fn neighbours(&self, k: usize) -> [u32; 3] {
        self.neighbours.get_or_init(|| {
            let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * self.order.len());
            for (k, &t) in self.order.iter().enumerate() {
                let v = self.mesh.triangles[t as usize];
                for e in 0..3 {
                    let (a, b) = (v[e], v[(e + 1) % 3]);
                    let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                    edges.push((key, (k as u32) << 2 | e as u32));
                }
            }
            edges.sort_unstable();
            let mut out = vec![[u32::MAX; 3]; self.order.len()];
            let mut i = 0;
            while i < edges.len() {
                let mut j = i + 1;
                while j < edges.len() && edges[j].0 == edges[i].0 {
                    j += 1;
                }
                if j - i == 2 {
                    let (x, y) = (edges[i].1, edges[i + 1].1);
                    out[(x >> 2) as usize][(x & 3) as usize] = y >> 2;
                    out[(y >> 2) as usize][(y & 3) as usize] = x >> 2;
                }
                i = j;
            }
            out
        })[k]
    }

    /// The `x` of every crossing of the line `y = y0, z = z0` (part frame) with the
    /// surface, by the watertight rule, unsorted.
    pub(crate) fn x_line_crossings(&self, y0: f64, z0: f64, out: &mut Vec<f64>) {
        out.clear();
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            let b = &node.bounds;
            if y0 < b.lo.y || y0 > b.hi.y || z0 < b.lo.z || z0 > b.hi.z {
                continue;
            }
            if node.count > 0 {
                for t in self.leaf_tris(node) {
                    if let Some(x) = x_line_crossing(&t, y0, z0) {
                        out.push(x);
                    }
                }
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
    }

    /// Whether `p` (part frame) lies inside the solid, by the parity of surface
    /// crossings of the ray from `p` along +X. Meaningful for solid meshes and points
    /// farther than about 1e-9 × the part size from the surface; a point on the
    /// surface may go either way.
    pub fn contains_point(&self, p: &Point3) -> bool {
        let b = self.bounds();
        if p.x < b.lo.x
            || p.x > b.hi.x
            || p.y < b.lo.y
            || p.y > b.hi.y
            || p.z < b.lo.z
            || p.z > b.hi.z
        {
            return false;
        }
        // a line lying in a face plane has no defined parity: shift it off by far
        // less than the contact resolution (callers keep points `eps` off the surface)
        let (y0, z0) = (p.y + 0.0707 * self.eps, p.z + 0.0577 * self.eps);
        // Only crossings beyond `p.x` count: nodes wholly before it are skipped (a
        // crossing's `x` is a convex combination of its triangle's corners').
        let mut beyond = 0usize;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            let b = &node.bounds;
            if y0 < b.lo.y || y0 > b.hi.y || z0 < b.lo.z || z0 > b.hi.z || b.hi.x < p.x {
                continue;
            }
            if node.count > 0 {
                for t in self.leaf_tris(node) {
                    if x_line_crossing(&t, y0, z0).is_some_and(|x| x > p.x) {
                        beyond += 1;
                    }
                }
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
        beyond % 2 == 1
    }
}

/// Whether `mesh` bounds a volume with its normals outward: every edge is
/// traversed as often in one direction as in the other (a closed, consistently
/// oriented surface, possibly non-manifold: stacked closed slices share their faces
/// and edges), and its signed volume is positive (an inside-out mesh resting on a
/// part would otherwise seem to share its faces' material).
pub(crate) fn encloses_volume(mesh: &Mesh) -> bool {
    let mut balance: HashMap<(u32, u32), i32> = HashMap::with_capacity(3 * mesh.triangles.len());
    for t in &mesh.triangles {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            if u == v {
                continue;
            }
            *balance.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
        }
    }
    !mesh.triangles.is_empty() && balance.values().all(|&b| b == 0) && mesh.signed_volume() > 0.0
}

/// A depth-first walk's stack of node indices: on the call's stack up to 64
/// entries (a tree's depth; the walk holds one entry per level and one more),
/// spilling to the heap beyond, so the nearest-point queries a depth walk makes by
/// the thousand allocate nothing.
struct WalkStack {
    inline: [u32; 64],
    len: usize,
    spill: Vec<u32>,
}

impl WalkStack {
    fn new() -> Self {
        WalkStack {
            inline: [0; 64],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline]
    fn push(&mut self, v: u32) {
        if self.len < self.inline.len() {
            self.inline[self.len] = v;
            self.len += 1;
        } else {
            self.spill.push(v);
        }
    }

    /// The last pushed: the spilled entries are the newest when there are any.
    #[inline]
    fn pop(&mut self) -> Option<u32> {
        if let Some(v) = self.spill.pop() {
            return Some(v);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

/// Colliders by mesh, so trees survive watch reruns while the mesh is unchanged.
///
/// Keyed by the `Arc<Mesh>` allocation: [`crate::mesh::MeshCache`] hands out the same
/// `Arc` for an unchanged file, so a lookup is one hash probe. Entries whose mesh
/// was dropped are pruned on insertion.
#[derive(Default)]
pub struct ColliderCache {
    entries: HashMap<usize, (Weak<Mesh>, Arc<Collider>)>,
    builds: usize,
}

impl ColliderCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The collider for `mesh`, built on first use.
    pub fn get(&mut self, mesh: &Arc<Mesh>) -> Result<Arc<Collider>, CollisionError> {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some((weak, c)) = self.entries.get(&key) {
            if weak.upgrade().is_some_and(|m| Arc::ptr_eq(&m, mesh)) {
                return Ok(c.clone());
            }
        }
        let c = Arc::new(Collider::new(mesh.clone())?);
        self.builds += 1;
        self.entries.retain(|_, (w, _)| w.strong_count() > 0);
        self.entries.insert(key, (Arc::downgrade(mesh), c.clone()));
        Ok(c)
    }

    /// The colliders of `meshes` (same order), the missing ones built in parallel
    /// (one rayon task per distinct mesh): what opening a cell of many distinct
    /// parts costs once.
    ///
    /// # Errors
    /// The first mesh that cannot be used (see [`Collider::new`]).
    pub fn get_all(&mut self, meshes: &[&Arc<Mesh>]) -> Result<Vec<Arc<Collider>>, CollisionError> {
        use rayon::prelude::*;
        let key = |m: &Arc<Mesh>| Arc::as_ptr(m) as usize;
        // per distinct mesh: its collider when cached and still for this mesh
        let mut found: HashMap<usize, Option<Arc<Collider>>> = HashMap::new();
        let mut missing: Vec<&Arc<Mesh>> = Vec::new();
        for &m in meshes {
            if found.contains_key(&key(m)) {
                continue;
            }
            let hit = self
                .entries
                .get(&key(m))
                .filter(|(w, _)| w.upgrade().is_some_and(|x| Arc::ptr_eq(&x, m)))
                .map(|(_, c)| c.clone());
            if hit.is_none() {
                missing.push(m);
            }
            found.insert(key(m), hit);
        }
        let built: Vec<Arc<Collider>> = missing
            .par_iter()
            .map(|m| Collider::new(Arc::clone(m)).map(Arc::new))
            .collect::<Result<_, _>>()?;
        if !built.is_empty() {
            self.builds += built.len();
            self.entries.retain(|_, (w, _)| w.strong_count() > 0);
        }
        for (m, c) in missing.into_iter().zip(built) {
            found.insert(key(m), Some(c.clone()));
            self.entries.insert(key(m), (Arc::downgrade(m), c));
        }
        Ok(meshes
            .iter()
            .filter_map(|m| found.get(&key(m)).cloned().flatten())
            .collect())
    }

    /// How many colliders were built (for tests and the watch header).
    pub fn build_count(&self) -> usize {
        self.builds
    }
}

#[cfg(test)]
mod tests;
