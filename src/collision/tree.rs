//! Building a [`Collider`](super::Collider)'s tree: how each group of triangles is
//! split, and each node's oriented box fitted (principal axes of its corners'
//! moments, extents along them).

use super::node::{Node, Obb, LEAF_SIZE};
use super::triangle::unit_normal;
use crate::math::{Aabb, Point3, Vec3};
use crate::mesh::Mesh;
use nalgebra::Matrix3;

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

/// A triangle while the tree is built: its centroid and its index in the mesh.
pub(super) type Item = (Point3, u32);

/// The tree over `items` (reordered into tree order): its nodes, root first, and
/// their oriented boxes.
pub(super) fn build(mesh: &Mesh, items: &mut [Item]) -> (Vec<Node>, Vec<Obb>) {
    let mut tree = Tree {
        mesh,
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
    let _ = tree.build(0, items, 0, &Matrix3::identity());
    (tree.nodes, tree.obbs)
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
pub(super) fn symmetric_eigenvectors(
    m: &Matrix3<f64>,
    start: &Matrix3<f64>,
    tolerance: f64,
) -> Matrix3<f64> {
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
