//! Containment along a motion: when two closed solids share material without any
//! pair of their triangles crossing.
//!
//! The crossing depth of a triangle pair ([`tri_tri`](super::triangle::tri_tri)) is 0
//! for coplanar faces and for edges lying on faces, so a part whose cross-section
//! equals its neighbour's (two equal tubes, a wall sliding into an equal wall) can
//! slide into it with every pair at depth 0: each face it pushes in lies in the plane
//! of one of the neighbour's faces, or meets them only edge-on. The volumes overlap
//! all the same, and there the two solids' faces lie in one plane **facing the same
//! way**, with both solids' material behind them — faces of solids that only touch
//! face opposite ways (a plate on a table, a peg in its hole). This module tests
//! that: the overlap of two coplanar, equally facing triangles of closed meshes over
//! a straight translation, in millimetres.
//!
//! "Closed" here (`shape::encloses_volume`) is weaker than watertight: every edge is
//! used as often in one direction as in the other, so the surface is the boundary of
//! a volume even where it is not a 2-manifold — a wall cut in stacked closed slices,
//! a union of closed boxes sharing faces (CAD exports, the bench's sliced ducts).

use super::relative::Relative;
use super::shape::Collider;
use super::triangle::{unit_normal, Tri};
use super::PairMember;
use crate::math::{Point3, Transform, Vec3};
use nalgebra::Isometry3;

/// How far apart (mm) two faces facing the same way may lie and still count as in one
/// plane. STL stores f32 coordinates (7 significant digits), so faces that coincide in
/// the CAD differ by up to ≈ 6e-5 mm for parts placed 1 m from their origin; same-facing
/// faces with both solids' material behind them share that material whatever their
/// offset, so a wider band only catches more real overlaps.
pub(crate) const PLANE_TOLERANCE: f64 = 1e-3;

/// How far apart (mm) a walk over triangle pairs looks: the pair's numerical slack
/// `eps`, widened to [`PLANE_TOLERANCE`] when the shared-face rule applies
/// (`shared`: both parts enclose a volume), since such faces may lie a few f32
/// roundings apart.
pub(crate) fn walk_margin(shared: bool, eps: f64) -> f64 {
    if shared {
        eps.max(PLANE_TOLERANCE)
    } else {
        eps
    }
}

/// How far (mm) moving triangle `a` (at `a0` at the start of a straight
/// translation, at `a1` at its end; obstacle frame) and obstacle triangle `b`
/// overlap at most over the motion when both lie in one plane facing the same way
/// (unit normals within 1e-9): the largest over the motion of the overlap's least
/// width — how far `a` must move in the plane to leave `b`, as a crossing depth is
/// how far one triangle reaches through the other. Only overlaps wider than at the
/// start count (the start is taken as free): a part sliding out of such an
/// overlap gets 0. 0 as well when they do not stay in one plane (within
/// [`PLANE_TOLERANCE`], or `eps` mm if larger), face opposite ways, or the motion
/// turns `a`.
///
/// The overlap of two convex sets, one translated along a line, has a least width
/// that is concave in the translation (Brunn–Minkowski: the overlap halfway
/// contains the mean of the two end overlaps), so a ternary search over the
/// translations where the two meet finds its largest value.
pub(crate) fn coplanar_overlap(a0: &Tri, a1: &Tri, b: &Tri, eps: f64) -> f64 {
    let v = a1[0] - a0[0];
    // a translation: every corner moves by the same vector
    if (1..3).any(|k| ((a1[k] - a0[k]) - v).norm() > eps) {
        return 0.0;
    }
    // On the plane at both ends of the motion.
    let Some(plane) = Flat::shared(a0, b, a0.iter().chain(a1), eps.max(PLANE_TOLERANCE)) else {
        return 0.0;
    };
    let pa = a0.each_ref().map(|p| plane.at(p));
    let pb = b.each_ref().map(|p| plane.at(p));
    let dv = plane.along(&v);
    let width = |t: f64| {
        let moved = pa.map(|p| [p[0] + t * dv[0], p[1] + t * dv[1]]);
        overlap_width(&moved, &pb)
    };
    let start = width(0.0);
    let len2 = dv[0] * dv[0] + dv[1] * dv[1];
    if len2 <= eps * eps {
        return 0.0;
    }
    // The translations t·dv at which the triangles meet: the line through the
    // origin along dv inside the Minkowski difference b − a (the hull of the nine
    // corner differences), as an interval of t.
    let perp = [-dv[1], dv[0]];
    let diffs: Vec<[f64; 2]> = pb
        .iter()
        .flat_map(|q| pa.iter().map(move |p| [q[0] - p[0], q[1] - p[1]]))
        .collect();
    let side = |d: &[f64; 2]| d[0] * perp[0] + d[1] * perp[1];
    let along = |d: &[f64; 2]| (d[0] * dv[0] + d[1] * dv[1]) / len2;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, d) in diffs.iter().enumerate() {
        let s = side(d);
        if s.abs() <= eps * len2.sqrt() {
            lo = lo.min(along(d));
            hi = hi.max(along(d));
        }
        for e in &diffs[i + 1..] {
            let r = side(e);
            if (s < 0.0) != (r < 0.0) && (s - r).abs() > 0.0 {
                let f = s / (s - r);
                let c = [d[0] + f * (e[0] - d[0]), d[1] + f * (e[1] - d[1])];
                lo = lo.min(along(&c));
                hi = hi.max(along(&c));
            }
        }
    }
    let (mut lo, mut hi) = (lo.max(0.0), hi.min(1.0));
    if lo > hi {
        return 0.0;
    }
    for _ in 0..60 {
        if hi - lo <= 1e-12 {
            break;
        }
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if width(m1) < width(m2) {
            lo = m1;
        } else {
            hi = m2;
        }
    }
    let best = width(0.5 * (lo + hi)).max(width(1.0_f64.min(hi)));
    if best > start + eps.max(1e-12) {
        best
    } else {
        0.0
    }
}

/// The least width (mm) of the overlap of triangles `a` and `b` (one frame) when they
/// lie in one plane (within [`PLANE_TOLERANCE`]) and face the same way: the static
/// form of [`coplanar_overlap`], for a pose rather than a motion. Two closed solids
/// whose faces overlap so share the material behind them; 0 otherwise.
pub(crate) fn shared_face_overlap(a: &Tri, b: &Tri) -> f64 {
    match Flat::shared(a, b, a, PLANE_TOLERANCE) {
        Some(plane) => overlap_width(
            &a.each_ref().map(|p| plane.at(p)),
            &b.each_ref().map(|p| plane.at(p)),
        ),
        None => 0.0,
    }
}

/// [`shared_face_overlap`] for triangles whose unit normals `na`, `nb` are known
/// (as [`unit_normal`] computes them): faces that do not face the same way, nearly
/// every pair a walk tests, are answered from one dot product.
#[inline]
pub(crate) fn shared_face_overlap_with(a: &Tri, na: &Vec3, b: &Tri, nb: &Vec3) -> f64 {
    if na.dot(nb) < 1.0 - SAME_FACING {
        return 0.0;
    }
    shared_face_overlap(a, b)
}

/// Faces count as facing the same way when their unit normals' dot product is at
/// least `1 - SAME_FACING` (normals within about 4.5e-5 rad).
pub(crate) const SAME_FACING: f64 = 1e-9;

/// The plane of triangle `b` with in-plane coordinates (mm) about its first corner.
struct Flat {
    origin: Point3,
    e1: Vec3,
    e2: Vec3,
}

impl Flat {
    /// `b`'s plane when `a` faces the same way (unit normals within 1e-9) and every
    /// point of `near` lies within `band` mm of it; `None` otherwise.
    fn shared<'p>(
        a: &Tri,
        b: &Tri,
        near: impl IntoIterator<Item = &'p Point3>,
        band: f64,
    ) -> Option<Flat> {
        let (na, nb) = (unit_normal(a)?, unit_normal(b)?);
        let on = |p: &Point3| nb.dot(&(p - b[0])).abs() <= band;
        if na.dot(&nb) < 1.0 - SAME_FACING || !near.into_iter().all(on) {
            return None;
        }
        let e1 = (b[1] - b[0]).normalize();
        Some(Flat {
            origin: b[0],
            e1,
            e2: nb.cross(&e1),
        })
    }

    /// A point's in-plane coordinates.
    fn at(&self, p: &Point3) -> [f64; 2] {
        self.along(&(p - self.origin))
    }

    /// A vector's in-plane components.
    fn along(&self, v: &Vec3) -> [f64; 2] {
        [self.e1.dot(v), self.e2.dot(v)]
    }
}

/// The least width (mm) of the overlap of two plane triangles: `a` clipped by the
/// three edges of `b`, then the smallest over the clipped polygon's edges of its
/// extent across that edge (a convex polygon is narrowest across one of its
/// edges). 0 when they meet in less than an area.
fn overlap_width(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    // b counter-clockwise, so "inside" is the left of each edge
    let ccw = cross(b[0], b[1], b[2]) > 0.0;
    let mut poly = [[0.0; 2]; 9];
    let mut len = 3;
    poly[..3].copy_from_slice(a);
    for k in 0..3 {
        let (u, w) = if ccw {
            (b[k], b[(k + 1) % 3])
        } else {
            (b[(k + 1) % 3], b[k])
        };
        let mut next = [[0.0; 2]; 9];
        let mut count = 0;
        for i in 0..len {
            let (p, q) = (poly[i], poly[(i + 1) % len]);
            let (sp, sq) = (cross(u, w, p), cross(u, w, q));
            if sp >= 0.0 && count < next.len() {
                next[count] = p;
                count += 1;
            }
            if (sp >= 0.0) != (sq >= 0.0) && count < next.len() {
                let f = sp / (sp - sq);
                next[count] = [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])];
                count += 1;
            }
        }
        poly = next;
        len = count;
        if len < 3 {
            return 0.0;
        }
    }
    let poly = &poly[..len];
    let mut least = f64::INFINITY;
    for i in 0..len {
        let (p, q) = (poly[i], poly[(i + 1) % len]);
        let l = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        if l <= 1e-15 {
            continue;
        }
        let across = poly
            .iter()
            .map(|&r| cross(p, q, r).abs() / l)
            .fold(0.0f64, f64::max);
        least = least.min(across);
    }
    if least.is_finite() {
        least
    } else {
        0.0
    }
}

/// Containment at rest: whether one solid lies inside the other when no pair of
/// their triangles crosses (ray parity at points clearly off the outer surface).
/// When the surfaces do not cross: is one solid inside the other? Returns which
/// part is inside ([`PairMember::First`] = `a`) and the containment depth.
pub(super) fn containment(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    eps: f64,
) -> Option<(PairMember, f64)> {
    let (inner, iso) = contained(a, pa, b, pb, eps)?;
    Some(match inner {
        PairMember::First => (inner, containment_depth(a, b, &iso)),
        PairMember::Second => (inner, containment_depth(b, a, &iso)),
    })
}

/// [`containment`] without the depth: which part is inside, and the map from its
/// frame into the other's. The boolean checks stop here, since the depth visits
/// every vertex of the inner part (nearly half a planner's time went to it where
/// sampled poses fall inside solid walls).
pub(super) fn contained(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    eps: f64,
) -> Option<(PairMember, Isometry3<f64>)> {
    let a_in_b = Relative::new(pb, pa).iso; // a's frame → b's frame
    if b.is_solid() && inside(a, b, &a_in_b, eps) {
        return Some((PairMember::First, a_in_b));
    }
    let b_in_a = Relative::new(pa, pb).iso;
    if a.is_solid() && inside(b, a, &b_in_a, eps) {
        return Some((PairMember::Second, b_in_a));
    }
    None
}

/// Whether the solid `inner` (mapped into `outer`'s frame by `iso`) has its
/// material inside `outer`, judged at the first test point that is clearly off
/// `outer`'s surface: vertices first, then points just inside `inner` under its
/// triangles' centroids (so coincident solids count as overlapping).
fn inside(inner: &Collider, outer: &Collider, iso: &Isometry3<f64>, eps: f64) -> bool {
    let bounds = outer.bounds();
    let off = 1e3 * eps;
    let vertices = inner.tris().flatten();
    let under_faces = inner.tris().filter_map(|t| {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0])).try_normalize(0.0)?;
        let c = nalgebra::center(&nalgebra::center(&t[0], &t[1]), &t[2]);
        Some(c - n * off)
    });
    for p in vertices.take(64).chain(under_faces.take(256)) {
        let q = iso * p;
        if bounds.distance_to_point(&q) > eps {
            return false;
        }
        if outer.within(&q, eps) {
            continue;
        }
        return outer.contains_point(&q);
    }
    false
}

/// Largest distance from a vertex of `inner` to the surface of `outer`, mm.
fn containment_depth(inner: &Collider, outer: &Collider, iso: &Isometry3<f64>) -> f64 {
    let mut best = 0.0f64;
    for t in inner.tris() {
        for p in t {
            best = best.max(outer.distance_to_point(&(iso * p), 0.0));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::shape::encloses_volume;
    use crate::collision::{edge_interferes, Collider, EdgeOptions};
    use crate::math::{Point3, Transform};
    use crate::mesh::Mesh;
    use std::sync::Arc;

    /// A block `lo..hi` cut in `slices` stacked closed boxes along Z (closed, not a
    /// 2-manifold: the slices share their faces), as the bench's sliced ducts.
    fn sliced(lo: [f64; 3], hi: [f64; 3], slices: usize) -> Mesh {
        let mut soup = Vec::new();
        // One expression per level, so the two slices meeting there share its bits.
        let level = |k: usize| lo[2] + (hi[2] - lo[2]) * k as f64 / slices as f64;
        for s in 0..slices {
            let (z0, z1) = (level(s), level(s + 1));
            let m = Mesh::cuboid(Point3::new(lo[0], lo[1], z0), Point3::new(hi[0], hi[1], z1));
            for k in 0..m.triangles.len() {
                soup.push(m.triangle(k));
            }
        }
        Mesh::from_triangle_soup(soup).unwrap()
    }

    fn at(x: f64, y: f64, z: f64) -> Transform {
        Transform::from_translation(Vec3::new(x, y, z))
    }

    #[test]
    fn stacked_slices_enclose_a_volume_an_open_box_does_not() {
        let block = sliced([0.0; 3], [10.0, 10.0, 10.0], 4);
        assert!(encloses_volume(&block));
        assert!(!Collider::new(Arc::new(block)).unwrap().is_solid());
        let mut open = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        open.triangles.pop();
        assert!(!encloses_volume(&open));
        let mut inside_out = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        for t in &mut inside_out.triangles {
            t.swap(1, 2);
        }
        assert!(!encloses_volume(&inside_out));
    }

    #[test]
    fn a_block_sliding_into_an_equal_block_interferes() {
        // Two equal sliced blocks side by side along Y, 2 mm apart: moved +Y by
        // 4 mm, the first is 2 mm deep inside the second, though every face it
        // pushes in meets the other's only coplanar or edge-on (depth 0).
        let block = Collider::new(Arc::new(sliced([0.0; 3], [10.0, 10.0, 10.0], 8))).unwrap();
        let o = EdgeOptions::default();
        let other = at(0.0, 12.0, 0.0);
        let hit = |from: Transform, to: Transform| {
            edge_interferes(&block, &from, &to, &block, &other, &o).unwrap()
        };
        assert!(hit(at(0.0, 0.0, 0.0), at(0.0, 4.0, 0.0)));
        assert!(hit(at(0.0, -5.0, 0.0), at(0.0, 40.0, 0.0)));
        // The same a few f32 roundings above or below the other's planes.
        for off in [2e-5, -2e-5] {
            let o2 = at(off, 12.0, -off);
            let e = edge_interferes(
                &block,
                &at(0.0, 0.0, 0.0),
                &at(0.0, 4.0, 0.0),
                &block,
                &o2,
                &o,
            );
            assert!(e.unwrap(), "offset {off}");
        }
        // Stopping flush against it, sliding along it and on top of it: free.
        assert!(!hit(at(0.0, 0.0, 0.0), at(0.0, 2.0, 0.0)));
        let beside = at(10.0, 12.0, 0.0);
        let slide = |from: Transform, to: Transform, obstacle: &Transform| {
            edge_interferes(&block, &from, &to, &block, obstacle, &o).unwrap()
        };
        assert!(!slide(at(0.0, 0.0, 0.0), at(0.0, 20.0, 0.0), &beside));
        let below = at(0.0, 12.0, -10.0);
        assert!(!slide(at(0.0, 0.0, 0.0), at(0.0, 20.0, 0.0), &below));
    }

    /// The static checks follow the edge check's rule: equal sliced blocks 2 mm into
    /// each other interfere (by shared faces), side by side or stacked they touch,
    /// and a few f32 roundings off the plane change nothing.
    #[test]
    fn static_checks_see_shared_faces_as_the_edge_check_does() {
        use crate::collision::{contact, interferes, Contact, InterferenceKind};
        let block = Collider::new(Arc::new(sliced([0.0; 3], [10.0, 10.0, 10.0], 8))).unwrap();
        let tol = 0.01;
        let verdict = |other: Transform| {
            let i = interferes(&block, &Transform::IDENTITY, &block, &other, tol).unwrap();
            let c = contact(&block, &Transform::IDENTITY, &block, &other, tol).unwrap();
            assert_eq!(i, c.is_interfering(), "{c:?}");
            c
        };
        for off in [0.0, 2e-5, -2e-5] {
            match verdict(at(off, 8.0, -off)) {
                Contact::Interfering {
                    depth,
                    kind: InterferenceKind::FacesOverlap,
                } => assert!((depth - 2.0).abs() < 1e-3, "{depth}"),
                other => panic!("offset {off}: {other:?}"),
            }
        }
        for beside in [at(0.0, 10.0, 0.0), at(0.0, 0.0, 10.0), at(10.0, 10.0, 0.0)] {
            assert_eq!(verdict(beside), Contact::Touching, "{beside:?}");
        }
        assert_eq!(verdict(at(0.0, 10.5, 0.0)), Contact::Separate);
    }

    #[test]
    fn coplanar_overlap_is_the_widest_overlap_met() {
        let p = |x: f64, y: f64| Point3::new(x, y, 0.0);
        let b = [p(0.0, 0.0), p(4.0, 0.0), p(0.0, 4.0)];
        let a0 = [p(-10.0, 0.0), p(-6.0, 0.0), p(-10.0, 4.0)];
        let a1 = a0.map(|q| q + Vec3::new(20.0, 0.0, 0.0));
        // Passing right over it: the widest overlap is the triangle itself (its
        // least width, the height over the hypotenuse, 4/√2).
        let w = coplanar_overlap(&a0, &a1, &b, 1e-9);
        assert!((w - 4.0 / 2f64.sqrt()).abs() < 1e-6, "{w}");
        // Facing the other way (a face against a face): no shared material.
        let flipped = [a0[0], a0[2], a0[1]];
        let flipped1 = [a1[0], a1[2], a1[1]];
        assert_eq!(coplanar_overlap(&flipped, &flipped1, &b, 1e-9), 0.0);
        // Leaving an overlap: 0 (the start is taken as free).
        let on = b;
        let away = b.map(|q| q + Vec3::new(-10.0, 0.0, 0.0));
        assert_eq!(coplanar_overlap(&on, &away, &b, 1e-9), 0.0);
        // A few f32 roundings off the plane (a placed STL part): still one plane,
        // at both ends of the motion.
        let rounded = a0.map(|q| q + Vec3::new(0.0, 0.0, 2e-5));
        let rounded1 = a1.map(|q| q + Vec3::new(0.0, 0.0, -3e-5));
        let w = coplanar_overlap(&rounded, &rounded1, &b, 1e-9);
        assert!((w - 4.0 / 2f64.sqrt()).abs() < 1e-4, "{w}");
        // Off the plane: not coplanar.
        let lifted = a0.map(|q| q + Vec3::new(0.0, 0.0, 0.5));
        let lifted1 = a1.map(|q| q + Vec3::new(0.0, 0.0, 0.5));
        assert_eq!(coplanar_overlap(&lifted, &lifted1, &b, 1e-9), 0.0);
    }
}
