//! [`Collider`]: the per-mesh collision shape (an AABB tree over the triangles in the
//! part frame), built once and shared, and [`ColliderCache`] which keeps colliders
//! across watch reruns while the mesh is unchanged.

use super::triangle::{closest_on_triangle, unit_normal, x_line_crossing, Tri};
use super::{CollisionError, MeshFault};
pub use crate::math::Aabb;
use crate::math::{Point3, Vec3};
use crate::mesh::{Mesh, MeshReport};
use nalgebra::Matrix3;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock, Weak};

/// Largest coordinate magnitude (mm) a collider accepts: beyond it the f64 spacing
/// exceeds the contact tolerances used here.
pub const MAX_COORDINATE: f64 = 1e9;

/// Most triangles per BVH leaf. A leaf pair's triangles are culled by plane before
/// pairing, which beats two more levels of box tests where a few facets of a fine
/// tessellation lie close together; a group bent round a corner or a tube is split
/// further ([`SPLIT_GAIN`]).
pub(crate) const LEAF_SIZE: usize = 4;

/// A group small enough for a leaf is split on while some split of it gives halves
/// whose oriented boxes have less than this share of its own box's surface
/// (`Tree::leaf_split`).
///
/// Measured on OMPL.app's meshes (docs/performance.md, "Pose checks on OMPL.app's
/// meshes"): leaves of up to four made near-contact checks 1.3–2× slower than
/// leaves of one on the low-poly alpha, Home, Apartment and Abstract, where four
/// facets bent round a corner or a tube leave their box mostly empty; leaves of one
/// made them 1.3× slower on the finely meshed escape (and its plans up to 2.6×
/// slower). Thresholds of 0.95 and 1.0 left most of alpha's loss.
const SPLIT_GAIN: f64 = 1.1;

/// A group whose facets' normals are all within about 14° of one another (cosine
/// at least this) is a patch of a smooth or flat surface and keeps its leaf
/// whatever [`SPLIT_GAIN`] says: splitting such groups gave a fine sphere 2.7 times
/// the nodes (memory) and made escape's near-contact checks 1.2× slower, for no
/// gain elsewhere.
const FLAT_GROUP_COS: f64 = 0.97;

/// Groups of at most this many triangles choose their split among four cuts
/// (`Tree::split_search`); larger ones, few and near the root, take the widest
/// axis's median (searching there too made the trees of 30–40k-triangle meshes
/// another 1.3× longer to build for no fewer node pairs on the whole).
const SPLIT_SEARCH_MAX: usize = 4096;

/// Nodes over more triangles than this take their oriented box around their
/// children's boxes instead of scanning every corner (the scans of the top levels
/// were most of the build; their boxes are a little looser).
const EXACT_EXTENTS: usize = 1024;

/// An oriented box (part frame, mm) fitted to a node's triangles: `axes` columns are
/// orthonormal directions, `half` the half extents along them. Far tighter than the
/// node's axis-aligned box for a surface patch that is tilted in the part frame, which
/// is what prunes near misses in the exact traversal.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Obb {
    pub(crate) centre: Vec3,
    pub(crate) axes: Matrix3<f64>,
    pub(crate) half: Vec3,
    /// `half.norm()`, kept: the bounding-sphere reject of every node pair reads it.
    pub(crate) radius: f64,
}

impl Obb {
    pub(crate) const BLANK: Obb = Obb {
        centre: Vec3::new(0.0, 0.0, 0.0),
        axes: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        half: Vec3::new(0.0, 0.0, 0.0),
        radius: 0.0,
    };

    /// The box with these centre, axes and half extents.
    #[inline]
    pub(crate) fn new(centre: Vec3, axes: Matrix3<f64>, half: Vec3) -> Obb {
        Obb {
            centre,
            axes,
            half,
            radius: half.norm(),
        }
    }

    /// The box with extents `lo..hi` along the columns of `axes` (coordinates
    /// `axesᵀ·p`), or the axis-aligned `aabb` when that is smaller; padded so rounding
    /// never leaves a vertex outside.
    fn from_extents(axes: &Matrix3<f64>, lo: Vec3, hi: Vec3, aabb: &Aabb) -> Obb {
        let ha = aabb.half_extents();
        let half = (hi - lo) * 0.5;
        let usable = axes.iter().all(|v| v.is_finite()) && half.iter().all(|v| v.is_finite());
        let (centre, axes, half) = if usable && half.product() < ha.product() {
            (axes * ((lo + hi) * 0.5), *axes, half)
        } else {
            (aabb.centre().coords, Matrix3::identity(), ha)
        };
        let pad = 1e-12 * (centre.amax() + half.amax());
        // thinnest axis first: the separating-axis test tries it first, and a
        // surface patch's box is most often told apart along its thin side
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| half[i].total_cmp(&half[j]));
        let axes = Matrix3::from_columns(&order.map(|k| axes.column(k).into_owned()));
        let half = Vec3::from(order.map(|k| half[k]));
        Obb::new(centre, axes, half.add_scalar(pad))
    }
}

/// First and second moments of a set of triangle corners about a fixed reference
/// point (the mesh's box centre, so the sums stay well conditioned for parts far
/// from the origin): a node's are the sum of its children's, so the covariance of
/// every node costs one pass over the triangles in all.
#[derive(Debug, Clone, Copy)]
struct Moments {
    count: f64,
    sum: Vec3,
    outer: Matrix3<f64>,
}

impl Moments {
    /// The moments of `items`' triangle corners about `origin`.
    fn of(mesh: &Mesh, items: &[Item], origin: &Vec3) -> Moments {
        let mut m = Moments {
            count: 0.0,
            sum: Vec3::zeros(),
            outer: Matrix3::zeros(),
        };
        for p in items.iter().flat_map(|it| mesh.triangle(it.1 as usize)) {
            let d = p.coords - origin;
            m.count += 1.0;
            m.sum += d;
            m.outer += d * d.transpose();
        }
        m
    }

    fn add(&self, o: &Moments) -> Moments {
        Moments {
            count: self.count + o.count,
            sum: self.sum + o.sum,
            outer: self.outer + o.outer,
        }
    }

    /// The moments of the corners of `self` that are not in `part` (a subset).
    fn without(&self, part: &Moments) -> Moments {
        Moments {
            count: self.count - part.count,
            sum: self.sum - part.sum,
            outer: self.outer - part.outer,
        }
    }

    /// The principal axes (columns, orthonormal) of the corners: the eigenvectors of
    /// their covariance (the search starting from the orthonormal `start`), or the
    /// part frame's axes when that is not finite.
    fn principal_axes(&self, start: &Matrix3<f64>) -> Matrix3<f64> {
        self.principal_axes_within(start, 1e-6)
    }

    /// [`Moments::principal_axes`] to a relative off-diagonal of `tolerance`.
    fn principal_axes_within(&self, start: &Matrix3<f64>, tolerance: f64) -> Matrix3<f64> {
        let mean = self.sum / self.count;
        let cov = self.outer / self.count - mean * mean.transpose();
        let axes = symmetric_eigenvectors(&cov, start, tolerance);
        if axes.iter().all(|v| v.is_finite()) {
            axes
        } else {
            Matrix3::identity()
        }
    }
}

/// Orthonormal eigenvectors (columns) of the symmetric 3×3 matrix `m`, by cyclic
/// Jacobi rotations from the orthonormal `start` (a child's axes for its parent:
/// nearly right already, so one or two sweeps do), to a relative off-diagonal of
/// `tolerance` (1e-6 for a node's box: axes within about a microradian of the
/// principal ones, as tight a box). Several times cheaper than a general solver for this size and orthonormal
/// by construction (`start` times rotations) even for repeated eigenvalues, which is
/// all an oriented box needs: any orthonormal axes give a box that bounds the
/// points, the eigenvectors only make it tight.
fn symmetric_eigenvectors(m: &Matrix3<f64>, start: &Matrix3<f64>, tolerance: f64) -> Matrix3<f64> {
    let scale = m.abs().max();
    if !(scale.is_finite() && scale > 0.0) {
        return *start;
    }
    let mut a = start.tr_mul(&(m * start));
    let mut v = *start;
    for _sweep in 0..12 {
        let off = a[(0, 1)].abs() + a[(0, 2)].abs() + a[(1, 2)].abs();
        if off <= tolerance * scale {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[(p, q)];
            if apq.abs() <= 1e-300 {
                continue;
            }
            // the rotation that zeroes a[p][q] (Numerical Recipes' stable form)
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[(k, p)], a[(k, q)]);
                a[(k, p)] = c * akp - s * akq;
                a[(k, q)] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                a[(p, k)] = c * apk - s * aqk;
                a[(q, k)] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                v[(k, p)] = c * vkp - s * vkq;
                v[(k, q)] = s * vkp + c * vkq;
            }
        }
    }
    v
}

/// The extents of the vertices of `items`' triangles along the columns of `axes`,
/// and their axis-aligned box.
fn extents(mesh: &Mesh, items: &[Item], axes: &Matrix3<f64>) -> (Vec3, Vec3, Aabb) {
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    let mut aabb = Aabb::EMPTY;
    for p in items.iter().flat_map(|it| mesh.triangle(it.1 as usize)) {
        let q = axes.tr_mul(&p.coords);
        lo = lo.inf(&q);
        hi = hi.sup(&q);
        aabb.grow(&p);
    }
    (lo, hi, aabb)
}

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

/// A triangle while the tree is built: its centroid and its index in the mesh.
type Item = (Point3, u32);

/// A node of the tree: `count > 0`: a leaf over the triangles
/// `order[first..first + count]`;
/// otherwise children `first` and `first + 1`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub(crate) bounds: Aabb,
    pub(crate) first: u32,
    pub(crate) count: u32,
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
    /// `containment::encloses_volume`). Found with the tree, so that no check pays
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
            super::containment::encloses_volume(&mesh)
        };
        let scale = mesh.area_scale();
        let mut items: Vec<Item> = (0..mesh.triangles.len())
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
        let mut tree = Tree {
            mesh: &mesh,
            origin: mesh.bounds().map_or(Vec3::zeros(), |b| b.centre().coords),
            nodes: Vec::with_capacity(2 * items.len()),
            obbs: Vec::with_capacity(2 * items.len()),
        };
        tree.nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        tree.obbs.push(Obb::BLANK);
        let _ = tree.build(0, &mut items, 0, &Matrix3::identity());
        let Tree { nodes, obbs, .. } = tree;
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
    /// slices stacked on their faces): see `containment::encloses_volume`.
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

    /// The nearest point of the surface to `p` (part frame): its distance (mm), the
    /// tree-order index of its triangle, and the point itself (part frame).
    pub(crate) fn closest_triangle(&self, p: &Point3) -> (f64, usize, Point3) {
        self.closest(p, 0.0)
    }

    /// The nearest surface point to `p` (part frame): distance (mm), tree-order
    /// index of its triangle and the point, best first through the tree; stops at
    /// the first leaf that brings the distance below `stop` (0: never stops early).
    fn closest(&self, p: &Point3, stop: f64) -> (f64, usize, Point3) {
        let mut best = (f64::INFINITY, 0usize, *p);
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if node.bounds.distance_to_point(p) >= best.0 {
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
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
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

/// A box's surface over 8, from its half extents: what the split rules compare.
fn half_surface(h: &Vec3) -> f64 {
    h[0] * h[1] + h[1] * h[2] + h[2] * h[0]
}

/// The tree under construction.
struct Tree<'m> {
    mesh: &'m Mesh,
    /// Reference point of the moments (the mesh's box centre, part frame, mm).
    origin: Vec3,
    nodes: Vec<Node>,
    obbs: Vec<Obb>,
}

impl Tree<'_> {
    /// Splits `items` (reordering them) and returns the index of the split: a group
    /// of at most [`SPLIT_SEARCH_MAX`] at the median along whichever of x, y, z and
    /// its centroids' principal axis gives children whose oriented boxes have the
    /// least surface ([`Tree::split_search`]); a larger group at the median along the
    /// widest extent of its centroids.
    fn split(&self, items: &mut [Item]) -> usize {
        if items.len() <= SPLIT_SEARCH_MAX {
            return self.split_search(items);
        }
        let axis = Self::widest_axis(items);
        Self::split_on(items, axis, items.len() / 2)
    }

    /// The axis (0 = x, 1 = y, 2 = z) of the widest extent of `items`' centroids.
    fn widest_axis(items: &[Item]) -> usize {
        let mut cb = Aabb::EMPTY;
        items.iter().for_each(|(c, _)| cb.grow(c));
        let ext = cb.hi - cb.lo;
        if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        }
    }

    /// Of the four median splits (along x, y, z and the centroids' principal
    /// axis), the one whose two children's oriented boxes have the least surface.
    ///
    /// A surface patch or tube running diagonally to the part frame (alpha's
    /// tubes, Apartment's slanted walls) is cut across by an x, y or z median into
    /// children as wide as their parent; the principal axis follows it, and the
    /// surface picks the cut that leaves the least empty box. Measured on
    /// OMPL.app's meshes against the widest-axis median alone: 1.3–3.4× fewer node
    /// pairs per check, the trees 1.5–2.5× longer to build (docs/performance.md,
    /// "Pose checks on OMPL.app's meshes").
    fn split_search(&self, items: &mut [Item]) -> usize {
        let whole = Moments::of(self.mesh, items, &self.origin);
        // the box of `items` along the principal axes of their corners' moments,
        // searched from the whole group's and only to 1e-3: a choice between cuts
        // needs the surface to a few per cent, and the eigen search from scratch to
        // 1e-6 was half of the trees' build
        let near = whole.principal_axes_within(&Matrix3::identity(), 1e-3);
        let half_extents = |items: &[Item], m: &Moments| {
            let (lo, hi, _) = extents(self.mesh, items, &m.principal_axes_within(&near, 1e-3));
            (hi - lo) * 0.5
        };
        let at = items.len() / 2;
        let mut best = f64::INFINITY;
        let mut kept: Vec<Item> = Vec::new();
        for cut in 0..4 {
            self.cut(items, cut, at);
            // the second half's moments by difference: one pass fewer per cut (a
            // little rounding only sways which cut is taken, never a box)
            let first = Moments::of(self.mesh, &items[..at], &self.origin);
            let cost = half_surface(&half_extents(&items[..at], &first))
                + half_surface(&half_extents(&items[at..], &whole.without(&first)));
            if cost < best {
                best = cost;
                kept.clear();
                kept.extend_from_slice(items);
            }
        }
        if !kept.is_empty() {
            items.copy_from_slice(&kept);
        }
        at
    }

    /// Reorders `items` so the first `at` lie lowest along cut `cut`: 0–2 the
    /// centroids' x, y, z, 3 their principal axis (x when that is not finite).
    fn cut(&self, items: &mut [Item], cut: usize, at: usize) {
        if cut < 3 {
            Self::split_on(items, cut, at);
            return;
        }
        let n = items.len() as f64;
        let mean = items.iter().fold(Vec3::zeros(), |s, (c, _)| s + c.coords) / n;
        let cov = items.iter().fold(Matrix3::zeros(), |m, (c, _)| {
            let d = c.coords - mean;
            m + d * d.transpose()
        });
        let axes = symmetric_eigenvectors(&cov, &Matrix3::identity(), 1e-3);
        let spread = |k: usize| axes.column(k).dot(&(cov * axes.column(k)));
        let k = (0..3)
            .max_by(|&i, &j| spread(i).total_cmp(&spread(j)))
            .unwrap_or(0);
        let dir: Vec3 = axes.column(k).into();
        if !dir.iter().all(|x| x.is_finite()) {
            Self::split_on(items, 0, at);
            return;
        }
        items.select_nth_unstable_by(at, |a, b| {
            a.0.coords.dot(&dir).total_cmp(&b.0.coords.dot(&dir))
        });
    }

    /// Splits `items` into the `at` of least centroid coordinate `axis` and the
    /// rest (reordering them); returns `at`.
    fn split_on(items: &mut [Item], axis: usize, at: usize) -> usize {
        items.select_nth_unstable_by(at, |a, b| a.0[axis].total_cmp(&b.0[axis]));
        at
    }

    /// The oriented box of `items`' corners along their principal axes.
    fn fitted(&self, items: &[Item]) -> Obb {
        let axes = Moments::of(self.mesh, items, &self.origin).principal_axes(&Matrix3::identity());
        let (lo, hi, aabb) = extents(self.mesh, items, &axes);
        Obb::from_extents(&axes, lo, hi, &aabb)
    }

    /// For a group of at most [`LEAF_SIZE`] triangles: how to split it instead of
    /// making it a leaf, if at all (a centroid axis and how many go first). None for
    /// a group of facets facing nearly one way ([`FLAT_GROUP_COS`]); else, of the
    /// splits at the middle along x, y and z (both middles of an odd count), the one
    /// whose halves' boxes have the least surface, if that is less than
    /// [`SPLIT_GAIN`] of the group's box's (the widest axis's median alone missed
    /// the split between two faces of a corner).
    fn leaf_split(&self, items: &[Item]) -> Option<(usize, usize)> {
        if items.len() < 2 {
            return None;
        }
        let surface = |o: &Obb| half_surface(&o.half);
        let normals: Vec<Vec3> = items
            .iter()
            .filter_map(|it| unit_normal(&self.mesh.triangle(it.1 as usize)))
            .collect();
        if normals
            .iter()
            .all(|a| normals.iter().all(|b| a.dot(b) >= FLAT_GROUP_COS))
        {
            return None;
        }
        let whole = surface(&self.fitted(items));
        let mut halves = items.to_vec();
        let n = items.len();
        let mut best: Option<(f64, (usize, usize))> = None;
        for axis in 0..3 {
            for at in [n / 2, n - n / 2] {
                Self::split_on(&mut halves, axis, at);
                let parts =
                    surface(&self.fitted(&halves[..at])) + surface(&self.fitted(&halves[at..]));
                if parts < SPLIT_GAIN * whole && best.is_none_or(|(b, _)| parts < b) {
                    best = Some((parts, (axis, at)));
                }
                if n.is_multiple_of(2) {
                    break;
                }
            }
        }
        best.map(|(_, split)| split)
    }

    /// Builds node `at` over `items` (which start at `offset` in tree order) and
    /// returns the moments of its triangles' corners about `self.origin`.
    ///
    /// Every node gets its own principal axes (from its children's summed moments)
    /// and its extents along them from one pass over its corners: reusing a parent's
    /// axes (tried, to save work) made tilted surface patches' boxes several times
    /// thicker and near-miss queries slower than FCL.
    ///
    /// `hint`: orthonormal axes of a nearby patch (a sibling's or an uncle's), where
    /// the eigen search of a leaf starts.
    fn build(
        &mut self,
        at: usize,
        items: &mut [Item],
        offset: usize,
        hint: &Matrix3<f64>,
    ) -> (Moments, Matrix3<f64>) {
        let leaf_split = if items.len() <= LEAF_SIZE {
            self.leaf_split(items)
        } else {
            None
        };
        let (moments, start, children) = if items.len() <= LEAF_SIZE && leaf_split.is_none() {
            self.nodes[at].first = offset as u32;
            self.nodes[at].count = items.len() as u32;
            let m = Moments::of(self.mesh, items, &self.origin);
            (m, *hint, None)
        } else {
            let mid = match leaf_split {
                Some((axis, at)) => Self::split_on(items, axis, at),
                None => self.split(items),
            };
            let left = self.nodes.len();
            self.nodes[at].first = left as u32;
            self.nodes[at].count = 0;
            let blank = Node {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            };
            self.nodes.extend([blank, blank]);
            self.obbs.extend([Obb::BLANK, Obb::BLANK]);
            let (l, r) = items.split_at_mut(mid);
            let (ml, axes_l) = self.build(left, l, offset, hint);
            let (mr, _) = self.build(left + 1, r, offset + mid, &axes_l);
            (ml.add(&mr), axes_l, Some(left))
        };
        let axes = moments.principal_axes(&start);
        let (lo, hi, aabb) = match children {
            // a large node: the corners of its children's boxes along its axes (they
            // hold every vertex; a little looser than the vertices, on few nodes)
            Some(left) if items.len() > EXACT_EXTENTS => {
                let (mut lo, mut hi) =
                    (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
                for o in &self.obbs[left..left + 2] {
                    for k in 0..8 {
                        let sign = |b: usize| if k & (1 << b) == 0 { -1.0 } else { 1.0 };
                        let corner = o.centre
                            + o.axes.column(0) * (sign(0) * o.half.x)
                            + o.axes.column(1) * (sign(1) * o.half.y)
                            + o.axes.column(2) * (sign(2) * o.half.z);
                        let q = axes.tr_mul(&corner);
                        lo = lo.inf(&q);
                        hi = hi.sup(&q);
                    }
                }
                let aabb = self.nodes[left].bounds.union(&self.nodes[left + 1].bounds);
                (lo, hi, aabb)
            }
            _ => extents(self.mesh, items, &axes),
        };
        self.nodes[at].bounds = aabb;
        self.obbs[at] = Obb::from_extents(&axes, lo, hi, &aabb);
        (moments, axes)
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
