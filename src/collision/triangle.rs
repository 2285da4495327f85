//! Triangle-level predicates written for fitup: triangle–triangle intersection with a
//! crossing depth (robust for coplanar and edge-on contacts), closest points, and the
//! watertight ray-crossing rule used for point-in-mesh.
//!
//! All coordinates are millimetres in one common frame (the caller transforms first).

use crate::math::{Aabb, Point3, Vec3};

/// A triangle as its three corners.
pub(crate) type Tri = [Point3; 3];

/// Intersection of two closed triangles.
///
/// `None`: disjoint (farther apart than `eps`). `Some(depth)`: they meet; `depth` is
/// the *crossing depth* of the pair (see `docs/interference.md`): the smallest of
/// how far `a` reaches through the plane of `b` (over `b` only), how far `b`
/// reaches through the plane of `a` (over `a`), and the length of their
/// intersection segment. With `oriented`
/// (both meshes bound solids, normals outward) "reaches through" means behind the
/// plane, into the other solid; otherwise it is the lesser of the two sides.
/// It is 0 for coplanar contact, for a triangle resting on another's plane, and for
/// pairs that meet in a single point, so touching surfaces have depth 0.
///
/// Distances within `eps` (mm) of a plane count as on it.
pub(crate) fn tri_tri(a: &Tri, b: &Tri, eps: f64, oriented: bool) -> Option<f64> {
    tri_tri_with(a, &unit_normal(a)?, b, &unit_normal(b)?, eps, oriented)
}

/// [`tri_tri`] with the triangles' unit normals `na`, `nb` given (as
/// [`unit_normal`] computes them; a zero normal is a triangle without area, which
/// meets nothing): the same answer, bit for bit, without normalising two cross
/// products per pair. The pair queries keep the normals of the static side in the
/// collider and those of the moved side once per query.
pub(crate) fn tri_tri_with(
    a: &Tri,
    na: &Vec3,
    b: &Tri,
    nb: &Vec3,
    eps: f64,
    oriented: bool,
) -> Option<f64> {
    if *na == Vec3::zeros() || *nb == Vec3::zeros() {
        return None;
    }
    let (na, nb) = (*na, *nb);
    let db = [
        snap(na.dot(&(b[0] - a[0])), eps),
        snap(na.dot(&(b[1] - a[0])), eps),
        snap(na.dot(&(b[2] - a[0])), eps),
    ];
    if one_strict_side(&db) {
        return None;
    }
    let da = [
        snap(nb.dot(&(a[0] - b[0])), eps),
        snap(nb.dot(&(a[1] - b[0])), eps),
        snap(nb.dot(&(a[2] - b[0])), eps),
    ];
    if one_strict_side(&da) {
        return None;
    }
    let coplanar = da.iter().all(|&d| d == 0.0) || db.iter().all(|&d| d == 0.0);
    let line = na.cross(&nb);
    let sin = line.norm();
    if coplanar || sin < 1e-12 {
        let n = if coplanar && da.iter().all(|&d| d == 0.0) {
            nb
        } else {
            na
        };
        if !coplanar_intersect(a, b, &n, eps) {
            return None;
        }
        return Some(if coplanar {
            0.0
        } else {
            reach_into(a, b, &nb, eps, oriented).min(reach_into(b, a, &na, eps, oriented))
        });
    }
    let dir = line / sin;
    let (lo_a, hi_a) = interval_on_line(a, &da, &dir)?;
    let (lo_b, hi_b) = interval_on_line(b, &db, &dir)?;
    let overlap = hi_a.min(hi_b) - lo_a.max(lo_b);
    if overlap < -eps {
        return None;
    }
    Some(
        reach_into(a, b, &nb, eps, oriented)
            .min(reach_into(b, a, &na, eps, oriented))
            .min(overlap.max(0.0)),
    )
}

/// The triangle's unit normal (right-hand order of its corners); `None` when it has
/// no area.
pub(crate) fn unit_normal(t: &Tri) -> Option<Vec3> {
    (t[1] - t[0]).cross(&(t[2] - t[0])).try_normalize(0.0)
}

fn snap(d: f64, eps: f64) -> f64 {
    if d.abs() <= eps {
        0.0
    } else {
        d
    }
}

fn one_strict_side(d: &[f64; 3]) -> bool {
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

/// How far triangle `t` reaches behind the plane of `o` (unit normal `n`), counting
/// only the part of `t` over `o` (inside the prism that extrudes `o` along `n`), so
/// a large triangle is judged where it meets `o`, not at a far corner. `oriented`:
/// behind means against `n` (into the solid); otherwise the lesser of the two sides.
fn reach_into(t: &Tri, o: &Tri, n: &Vec3, eps: f64, oriented: bool) -> f64 {
    let mut sides = [(Vec3::zeros(), Point3::origin(), 0.0); 5];
    for k in 0..3 {
        let (u, v) = (o[k], o[(k + 1) % 3]);
        let m = n.cross(&(v - u)); // points into `o` for a counter-clockwise `o`
        sides[k] = (m, u, eps * m.norm());
    }
    reach_within(t, &sides[..3], o, n, oriented)
}

/// The most [`reach_into`] can become while `o` moves by `s` (mm) parallel to its
/// plane (the component of `s` along `n` is ignored): how far `t` reaches behind
/// `o`'s plane over the region `o` sweeps, the Minkowski sum of `o` and the segment
/// `0..s`. That sum is bounded by `o`'s three sides, each moved out by the part of
/// `s` across it, and by the two lines along `s` through `o`'s outermost corners.
/// A pair of triangles translating against each other parallel to one's plane can
/// cross no deeper than this anywhere on the way (`edge.rs`).
pub(crate) fn reach_into_swept(
    t: &Tri,
    o: &Tri,
    n: &Vec3,
    s: &Vec3,
    eps: f64,
    oriented: bool,
) -> f64 {
    let s = s - n * n.dot(s);
    let mut sides = [(Vec3::zeros(), Point3::origin(), 0.0); 5];
    for k in 0..3 {
        let (u, v) = (o[k], o[(k + 1) % 3]);
        let m = n.cross(&(v - u));
        // inside the swept region: m·(p − u) ≥ min(0, m·s)
        sides[k] = (m, u, eps * m.norm() - m.dot(&s).min(0.0));
    }
    let w = n.cross(&s);
    let slack = eps * w.norm();
    let across = o.map(|p| w.dot(&p.coords));
    let (lo, hi) = (0..3).fold((0, 0), |(lo, hi), k| {
        (
            if across[k] < across[lo] { k } else { lo },
            if across[k] > across[hi] { k } else { hi },
        )
    });
    sides[3] = (w, o[lo], slack);
    sides[4] = (-w, o[hi], slack);
    reach_within(t, &sides, o, n, oriented)
}

/// How far triangle `t`, clipped to the half-spaces `m·(p − u) + extra ≥ 0` of
/// `sides`, reaches behind the plane through `o[0]` with unit normal `n`
/// (`oriented`), or to the lesser side.
fn reach_within(t: &Tri, sides: &[(Vec3, Point3, f64)], o: &Tri, n: &Vec3, oriented: bool) -> f64 {
    // Clipping a triangle by five half-planes leaves at most 8 corners: fixed
    // buffers (this runs for every crossing pair; no allocation).
    let mut poly = [Point3::origin(); 8];
    let mut len = 3;
    poly[..3].copy_from_slice(t);
    for (m, u, extra) in sides {
        let side = |p: &Point3| m.dot(&(p - u)) + extra;
        let mut next = [Point3::origin(); 8];
        let mut count = 0;
        for i in 0..len {
            let (p, q) = (&poly[i], &poly[(i + 1) % len]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 && count < next.len() {
                next[count] = *p;
                count += 1;
            }
            if (sp >= 0.0) != (sq >= 0.0) && count < next.len() {
                next[count] = p + (q - p) * (sp / (sp - sq));
                count += 1;
            }
        }
        poly = next;
        len = count;
        if len == 0 {
            return 0.0;
        }
    }
    let poly = &poly[..len];
    let d = poly.iter().map(|p| n.dot(&(p - o[0])));
    let above = d.clone().fold(0.0f64, |m, v| m.max(v));
    let below = d.fold(0.0f64, |m, v| m.max(-v));
    if oriented {
        below
    } else {
        above.min(below)
    }
}

/// The part of triangle `t` on the other plane (distances `d`), projected on `dir`.
fn interval_on_line(t: &Tri, d: &[f64; 3], dir: &Vec3) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut push = |p: Vec3| {
        let s = dir.dot(&p);
        lo = lo.min(s);
        hi = hi.max(s);
    };
    for i in 0..3 {
        let j = (i + 1) % 3;
        if d[i] == 0.0 {
            push(t[i].coords);
        }
        if (d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0) {
            let s = d[i] / (d[i] - d[j]);
            push(t[i].coords + (t[j] - t[i]) * s);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Closed 2-D intersection of two (nearly) coplanar triangles, projected on the
/// coordinate plane most perpendicular to `n`.
fn coplanar_intersect(a: &Tri, b: &Tri, n: &Vec3, eps: f64) -> bool {
    let (i, j) = if n.x.abs() >= n.y.abs() && n.x.abs() >= n.z.abs() {
        (1, 2)
    } else if n.y.abs() >= n.z.abs() {
        (2, 0)
    } else {
        (0, 1)
    };
    let p = |t: &Tri| t.map(|v| [v[i], v[j]]);
    let (a2, b2) = (p(a), p(b));
    for k in 0..3 {
        for l in 0..3 {
            if segments_meet(a2[k], a2[(k + 1) % 3], b2[l], b2[(l + 1) % 3], eps) {
                return true;
            }
        }
    }
    inside_2d(a2[0], &b2, eps) || inside_2d(b2[0], &a2, eps)
}

fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

fn point_segment_distance_2d(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let s = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - s * ab[0], ap[1] - s * ab[1]];
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2], eps: f64) -> bool {
    let (o1, o2) = (cross2(a, b, c), cross2(a, b, d));
    let (o3, o4) = (cross2(c, d, a), cross2(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    point_segment_distance_2d(a, c, d) <= eps
        || point_segment_distance_2d(b, c, d) <= eps
        || point_segment_distance_2d(c, a, b) <= eps
        || point_segment_distance_2d(d, a, b) <= eps
}

fn inside_2d(p: [f64; 2], t: &[[f64; 2]; 3], eps: f64) -> bool {
    let area = cross2(t[0], t[1], t[2]);
    if area == 0.0 {
        return false;
    }
    let s = area.signum();
    (0..3).all(|k| {
        let (u, v) = (t[k], t[(k + 1) % 3]);
        let len = ((v[0] - u[0]).powi(2) + (v[1] - u[1]).powi(2)).sqrt();
        s * cross2(u, v, p) >= -eps * len
    })
}

/// Closest point of triangle `t` to `p` (Voronoi-region walk over vertices, edges
/// and face).
pub(crate) fn closest_on_triangle(p: &Point3, t: &Tri) -> Point3 {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        return a;
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// Distance between segments `p0p1` and `q0q1` (mm).
fn segment_distance(p0: &Point3, p1: &Point3, q0: &Point3, q1: &Point3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    let tiny = 1e-300;
    let (s, t);
    if a <= tiny && e <= tiny {
        return r.norm();
    }
    if a <= tiny {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= tiny {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    ((p0 + d1 * s) - (q0 + d2 * t)).norm()
}

/// Distance between two triangles (mm); 0 when they intersect.
pub(crate) fn tri_distance(a: &Tri, b: &Tri) -> f64 {
    if tri_tri(a, b, 0.0, false).is_some() {
        return 0.0;
    }
    let mut best = f64::INFINITY;
    for p in a {
        best = best.min((p - closest_on_triangle(p, b)).norm());
    }
    for p in b {
        best = best.min((p - closest_on_triangle(p, a)).norm());
    }
    for i in 0..3 {
        for j in 0..3 {
            best = best.min(segment_distance(
                &a[i],
                &a[(i + 1) % 3],
                &b[j],
                &b[(j + 1) % 3],
            ));
        }
    }
    best
}

/// Where the line `{(x, y, z) : y = q.y, z = q.z}` crosses triangle `t`, by a
/// watertight rule: edge functions are evaluated on canonically ordered endpoints and
/// ties on an edge are given to exactly one side, so a line through a shared edge or
/// vertex of a closed mesh crosses it an even or odd number of times consistently.
/// Returns the `x` of the crossing.
pub(crate) fn x_line_crossing(t: &Tri, y: f64, z: f64) -> Option<f64> {
    let mut w = [0.0f64; 3];
    for k in 0..3 {
        let (u, v) = (&t[(k + 1) % 3], &t[(k + 2) % 3]);
        // canonical order so a shared edge gives bit-identical magnitudes
        let flip = (u.y, u.z) > (v.y, v.z);
        let (p, q) = if flip { (v, u) } else { (u, v) };
        let e = (q.y - p.y) * (z - p.z) - (q.z - p.z) * (y - p.y);
        let e = if e == 0.0 {
            // tie: the point belongs to the side given by the edge direction
            let owns = (q.y - p.y) > 0.0 || ((q.y - p.y) == 0.0 && (q.z - p.z) > 0.0);
            if owns {
                f64::MIN_POSITIVE
            } else {
                -f64::MIN_POSITIVE
            }
        } else {
            e
        };
        w[k] = if flip { -e } else { e };
    }
    let pos = w.iter().all(|&v| v > 0.0);
    let neg = w.iter().all(|&v| v < 0.0);
    if !(pos || neg) {
        return None;
    }
    let sum = w[0] + w[1] + w[2];
    if sum == 0.0 || !sum.is_finite() {
        return None;
    }
    Some((w[0] * t[0].x + w[1] * t[1].x + w[2] * t[2].x) / sum)
}

/// The parameter interval of the ray `o + t·d` inside box `b` (t may be negative).
pub(crate) fn ray_box(o: &Point3, d: &Vec3, b: &Aabb) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-300 {
            if o[k] < b.lo[k] || o[k] > b.hi[k] {
                return None;
            }
        } else {
            let (a, c) = ((b.lo[k] - o[k]) / d[k], (b.hi[k] - o[k]) / d[k]);
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
    }
    // a small margin: a ray along a face must not miss it by round-off
    let m = 1e-9 * (1.0 + t1.abs());
    (t0 <= t1 + m).then_some((t0, t1 + m))
}

/// Where the line `o + t·d` meets the closed triangle `t` (Möller–Trumbore, edges
/// included); `None` when parallel or outside.
pub(crate) fn ray_triangle(o: &Point3, d: &Vec3, t: &[Point3; 3]) -> Option<f64> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(&e2);
    let det = e1.dot(&p);
    let scale = e1.norm() * e2.norm() * d.norm();
    if det.abs() <= 1e-12 * scale {
        return None;
    }
    let s = o - t[0];
    let u = s.dot(&p) / det;
    let eps = 1e-12;
    if !(-eps..=1.0 + eps).contains(&u) {
        return None;
    }
    let q = s.cross(&e1);
    let v = d.dot(&q) / det;
    if v < -eps || u + v > 1.0 + eps {
        return None;
    }
    Some(e2.dot(&q) / det)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point3 {
        Point3::new(x, y, z)
    }

    #[test]
    fn crossing_triangles_have_positive_depth() {
        let a = [p(-1.0, -1.0, 0.0), p(2.0, -1.0, 0.0), p(-1.0, 2.0, 0.0)];
        let b = [p(0.0, 0.0, -0.5), p(0.0, 0.5, 1.0), p(0.5, 0.0, 1.0)];
        let d = tri_tri(&a, &b, 1e-9, false).expect("they cross");
        // limited by the length of the crossing segment, (0, 1/6, 0)-(1/6, 0, 0)
        assert!((d - 2f64.sqrt() / 6.0).abs() < 1e-12, "{d}");
        assert_eq!(tri_tri(&b, &a, 1e-9, false), Some(d));
    }

    #[test]
    fn coplanar_and_resting_contacts_are_depth_zero() {
        let a = [p(0.0, 0.0, 0.0), p(2.0, 0.0, 0.0), p(0.0, 2.0, 0.0)];
        let b = [p(0.5, 0.5, 0.0), p(3.0, 0.5, 0.0), p(0.5, 3.0, 0.0)];
        assert_eq!(tri_tri(&a, &b, 1e-9, false), Some(0.0));
        let far = [p(5.0, 5.0, 0.0), p(6.0, 5.0, 0.0), p(5.0, 6.0, 0.0)];
        assert_eq!(tri_tri(&a, &far, 1e-9, true), None);
        let standing = [p(0.5, 0.5, 0.0), p(1.0, 0.5, 0.0), p(0.5, 0.5, 3.0)];
        assert_eq!(tri_tri(&a, &standing, 1e-9, true), Some(0.0));
    }

    #[test]
    fn single_point_contact_of_straddling_triangles_is_depth_zero() {
        // b passes through a's plane and a's edge passes through b's plane, but they
        // only meet at (1, 0, 0).
        let a = [p(1.0, 0.0, 0.0), p(3.0, -1.0, 0.0), p(3.0, 1.0, 0.0)];
        let b = [p(1.0, 0.0, -1.0), p(1.0, 0.0, 1.0), p(-1.0, 0.0, 0.0)];
        let d = tri_tri(&a, &b, 1e-9, false).expect("they touch");
        assert!(d < 1e-9, "{d}");
    }

    #[test]
    fn distance_of_parallel_triangles() {
        let a = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
        let b = [p(0.0, 0.0, 2.0), p(1.0, 0.0, 2.0), p(0.0, 1.0, 2.0)];
        assert!((tri_distance(&a, &b) - 2.0).abs() < 1e-12);
        let c = [p(3.0, 0.0, 0.0), p(4.0, 0.0, 1.0), p(4.0, 1.0, 0.0)];
        assert!((tri_distance(&a, &c) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn line_crossing_counts_shared_edges_once() {
        // two triangles sharing the diagonal of the unit square in the plane x = 1
        let t1 = [p(1.0, 0.0, 0.0), p(1.0, 1.0, 0.0), p(1.0, 1.0, 1.0)];
        let t2 = [p(1.0, 0.0, 0.0), p(1.0, 1.0, 1.0), p(1.0, 0.0, 1.0)];
        for (y, z) in [(0.5, 0.5), (0.25, 0.25), (0.0, 0.0), (1.0, 1.0), (0.3, 0.7)] {
            let n = [&t1, &t2]
                .iter()
                .filter(|t| x_line_crossing(t, y, z).is_some())
                .count();
            assert!(n <= 1, "({y},{z}) counted {n} times");
        }
        let n = [&t1, &t2]
            .iter()
            .filter(|t| x_line_crossing(t, 0.5, 0.5).is_some())
            .count();
        assert_eq!(n, 1);
    }
}
