//! Closing the gaps Open CASCADE's meshing leaves in one closed solid: T-junctions
//! between two faces, and holes where a face got no triangles.
//!
//! Open CASCADE discretizes each edge once and both faces of the edge share its
//! nodes, so welding identical points closes a solid. Some exports still come back
//! with a few open edges (a HOOPS-exported servo: 9 of 60,000): one face's side of
//! the edge carries a node the other face's side skips. The node lies on the other
//! side's segment, within the deflection (the segment is a chord of the same curve),
//! and the solid is closed once that segment's triangle is split at the node, as any
//! mesh repair does for a T-junction. A face left without triangles (a sliver, or
//! a face that did not mesh) leaves a hole whose rim is that face's outline: filled
//! when the rim is a triangle or a flat convex polygon. Either mend is kept only
//! when the closed mesh has the B-rep's volume; any other gap stays open and the
//! solid is refused as before. The welding of the face meshes into one is here too
//! ([`closed_mesh`]).

use super::raw::RawPart;
use super::{StepError, StepOptions};
use crate::math::Point3;
use crate::mesh::{Mesh, MeshError};
use std::collections::HashMap;
use std::path::Path;

/// Open edges past which no repair is tried (a solid with that many is not a few
/// T-junctions; the search is quadratic in them).
const MAX_OPEN_EDGES: usize = 4096;

/// How far a mended solid's mesh volume may be from the B-rep's exact volume
/// (relative): the chordal error of a fine mesh is well under it (the corpus: within
/// 0.3 %), a wrongly closed hole is not.
pub(super) const MENDED_VOLUME_SLACK: f64 = 0.015;

/// Rounds of splitting (a triangle with two open sides is split once per round).
const MAX_ROUNDS: usize = 4;

/// One distinct solid's mesh from Open CASCADE's face meshes of `p`: welded, its
/// gaps closed where that gives the B-rep's volume, and checked closed and
/// consistently oriented; with how many gaps were closed. `solid` names it in errors.
pub(super) fn closed_mesh(
    path: &Path,
    options: &StepOptions,
    p: &RawPart,
    solid: String,
) -> Result<(Mesh, usize), StepError> {
    let unmeshed = (p.unmeshed_faces > 0).then(|| StepError::UnmeshedFace {
        path: path.into(),
        solid: solid.clone(),
        face: p.first_unmeshed_face,
        faces: p.faces,
        count: p.unmeshed_faces,
    });
    let mut mesh = weld(&p.vertices, &p.triangles).map_err(|source| StepError::Mesh {
        path: path.into(),
        solid: solid.clone(),
        source,
    })?;
    let mut report = mesh.inspect();
    let mut mended = 0;
    if !report.is_watertight() {
        let welded = report;
        mended = split_t_junctions(&mut mesh, options.linear_deflection)
            + fill_holes(&mut mesh, options.linear_deflection);
        report = mesh.inspect();
        // A mend is kept only where it gives the B-rep's own volume: a hole that
        // was not one missing face would not.
        // (a NaN ratio, from a zero or broken exact volume, keeps no mend)
        let off = (mesh.signed_volume() / p.exact_volume - 1.0).abs();
        let exact = off
            .partial_cmp(&MENDED_VOLUME_SLACK)
            .is_some_and(|o| o.is_le());
        if mended > 0 && !exact {
            report = welded;
        }
    }
    if mesh.triangles.is_empty() || !report.is_watertight() {
        // A face without triangles whose hole is not one flat convex polygon:
        // that face is the cause.
        if let Some(e) = unmeshed {
            return Err(e);
        }
        return Err(StepError::OpenSolid {
            path: path.into(),
            solid,
            boundary_edges: report.boundary_edges,
            non_manifold_edges: report.non_manifold_edges,
            misoriented_edges: report.misoriented_edges,
        });
    }
    Ok((mesh, mended))
}

/// What the edge counts of [`StepError::OpenSolid`] say is wrong, each count that is
/// not zero by its usual cause.
pub(super) fn open_solid_cause(open: usize, non_manifold: usize, misoriented: usize) -> String {
    let mut causes = Vec::new();
    if open > 0 {
        causes.push("open edges: a face missing or a gap between faces");
    }
    if non_manifold > 0 {
        causes.push("non-manifold edges: more than two faces meet at an edge, as where two bodies touch along it");
    }
    if misoriented > 0 {
        causes.push("misoriented edges: faces turned against their neighbours");
    }
    if causes.is_empty() {
        causes.push("no triangles");
    }
    causes.join("; ")
}

/// Face meshes side by side → one indexed mesh: the nodes OCCT puts on an edge
/// are the same points on both faces, so merging identical vertices closes it.
/// Triangles that collapse in the merge (two nodes at one point: a sphere's pole, a
/// cone's apex) have no surface and are left out.
fn weld(vertices: &[f64], triangles: &[u32]) -> Result<Mesh, MeshError> {
    let n = vertices.len() / 3;
    let point = |i: u32| -> Result<Point3, MeshError> {
        let i = i as usize;
        if i >= n {
            return Err(MeshError::invalid(format!(
                "a triangle refers to vertex {i} of {n}"
            )));
        }
        let p = Point3::new(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
        let ok = |v: f64| v.is_finite() && v.abs() <= crate::math::MAX_ABS_VALUE;
        if !(ok(p.x) && ok(p.y) && ok(p.z)) {
            return Err(MeshError::invalid(format!(
                "vertex {i} is not finite or beyond {:e} mm",
                crate::math::MAX_ABS_VALUE
            )));
        }
        Ok(p)
    };
    // Counted before anything is kept, and welded as it goes (no soup of corners:
    // that took 72 bytes a triangle more, 1.4 GB at 20 million).
    let n = triangles.len() / 3;
    if n > crate::mesh::MAX_TRIANGLES {
        return Err(MeshError::too_many(crate::mesh::MAX_TRIANGLES, "triangles"));
    }
    let mut w = crate::mesh::Welder::new(n);
    for t in triangles.chunks_exact(3) {
        w.push([point(t[0])?, point(t[1])?, point(t[2])?]);
    }
    let mut mesh = w.finish()?;
    mesh.triangles
        .retain(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
    Ok(mesh)
}

/// Splits every triangle of `mesh` whose side is an open edge at the open-edge
/// vertices lying on that side, within `tolerance` (mm) of the segment and strictly
/// between its ends, keeping the triangle's orientation. Returns how many triangles
/// were split. A mesh with more than [`MAX_OPEN_EDGES`] open edges is left as it is.
pub(super) fn split_t_junctions(mesh: &mut Mesh, tolerance: f64) -> usize {
    let mut split = 0;
    for _ in 0..MAX_ROUNDS {
        let open = open_sides(mesh);
        if open.is_empty() || open.len() > MAX_OPEN_EDGES {
            break;
        }
        let mut ends: Vec<u32> = open
            .iter()
            .flat_map(|&(t, s)| {
                let tri = mesh.triangles[t];
                [tri[s], tri[(s + 1) % 3]]
            })
            .collect();
        ends.sort_unstable();
        ends.dedup();
        let mut touched = vec![false; mesh.triangles.len()];
        let mut round = 0;
        for &(t, s) in &open {
            if touched[t] {
                continue;
            }
            let tri = mesh.triangles[t];
            let (a, b, c) = (tri[s], tri[(s + 1) % 3], tri[(s + 2) % 3]);
            let on = on_segment(&mesh.vertices, a, b, &ends, tolerance);
            if on.is_empty() {
                continue;
            }
            touched[t] = true;
            let mut chain = Vec::with_capacity(on.len() + 2);
            chain.push(a);
            chain.extend(on);
            chain.push(b);
            mesh.triangles[t] = [chain[0], chain[1], c];
            for w in chain[1..].windows(2) {
                mesh.triangles.push([w[0], w[1], c]);
            }
            round += 1;
        }
        if round == 0 {
            break;
        }
        split += round;
    }
    split
}

/// Most sides of a hole [`fill_holes`] fills.
const MAX_HOLE_SIDES: usize = 64;

/// Fills each hole of `mesh` whose rim is a simple loop of open sides that a face
/// of Open CASCADE's left without triangles would close: a triangle (three sides),
/// or a convex polygon flat within `tolerance` (mm), fanned from its first corner.
/// The new triangles face the way the rim's triangles do. Returns how many holes
/// were filled; a rim that is not flat or not convex is left open.
pub(super) fn fill_holes(mesh: &mut Mesh, tolerance: f64) -> usize {
    let open = open_sides(mesh).len();
    if open == 0 || open > MAX_OPEN_EDGES {
        return 0;
    }
    let mut filled = 0;
    for rim in boundary_loops(mesh) {
        // The rim's sides run one way in its triangles; the fill runs the other.
        let hole: Vec<u32> = rim.iter().rev().copied().collect();
        if hole.len() > MAX_HOLE_SIDES
            || !(hole.len() == 3 || flat_and_convex(mesh, &hole, tolerance))
        {
            continue;
        }
        for i in 1..hole.len() - 1 {
            mesh.triangles.push([hole[0], hole[i], hole[i + 1]]);
        }
        filled += 1;
    }
    filled
}

/// Whether polygon `corners` (vertex indices, in order) lies in one plane within
/// `tolerance` and turns the same way at every corner.
fn flat_and_convex(mesh: &Mesh, corners: &[u32], tolerance: f64) -> bool {
    let p: Vec<Point3> = corners.iter().map(|&v| mesh.vertices[v as usize]).collect();
    let n = p.len();
    // Newell's normal: the polygon's area vector, robust for any simple polygon
    let mut normal = crate::math::Vec3::zeros();
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        normal += crate::math::Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let Some(normal) = normal.try_normalize(1e-300) else {
        return false;
    };
    let centre = p
        .iter()
        .fold(crate::math::Vec3::zeros(), |s, q| s + q.coords)
        / n as f64;
    if p.iter()
        .any(|q| (q.coords - centre).dot(&normal).abs() > tolerance)
    {
        return false;
    }
    (0..n).all(|i| {
        let (a, b, c) = (p[i], p[(i + 1) % n], p[(i + 2) % n]);
        (b - a).cross(&(c - b)).dot(&normal) > 0.0
    })
}

/// The closed loops of open sides, each as its vertices in the order the sides run
/// (each side as its triangle has it); `None` for a vertex where open sides branch.
fn boundary_loops(mesh: &Mesh) -> Vec<Vec<u32>> {
    let open = open_sides(mesh);
    let mut next: HashMap<u32, Option<u32>> = HashMap::with_capacity(open.len());
    for &(t, s) in &open {
        let tri = mesh.triangles[t];
        let (a, b) = (tri[s], tri[(s + 1) % 3]);
        // a vertex with two open sides leaving it is not on one simple loop
        next.entry(a).and_modify(|n| *n = None).or_insert(Some(b));
    }
    let mut loops = Vec::new();
    let mut seen: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        let mut path = vec![start];
        let mut at = start;
        let closed = loop {
            match next.get(&at).copied().flatten() {
                Some(n) if n == start => break true,
                Some(n) if !seen.contains(&n) && !path.contains(&n) && path.len() < open.len() => {
                    path.push(n);
                    at = n;
                }
                _ => break false,
            }
        };
        seen.extend(path.iter().copied());
        if closed {
            loops.push(path);
        }
    }
    loops
}

/// The open sides of `mesh`: (triangle, side `s` from corner `s` to `s + 1`) whose
/// undirected edge belongs to this triangle alone.
fn open_sides(mesh: &Mesh) -> Vec<(usize, usize)> {
    let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
    let mut count: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangles.len() * 2);
    for t in &mesh.triangles {
        for s in 0..3 {
            *count.entry(key(t[s], t[(s + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut open = Vec::new();
    for (i, t) in mesh.triangles.iter().enumerate() {
        for s in 0..3 {
            if count[&key(t[s], t[(s + 1) % 3])] == 1 {
                open.push((i, s));
            }
        }
    }
    open
}

/// The vertices of `candidates` on segment `a`–`b` (within `tolerance`, strictly
/// between the ends), ordered from `a` to `b`.
fn on_segment(vertices: &[Point3], a: u32, b: u32, candidates: &[u32], tolerance: f64) -> Vec<u32> {
    let (pa, pb) = (vertices[a as usize], vertices[b as usize]);
    let d = pb - pa;
    let len2 = d.norm_squared();
    if len2 <= tolerance * tolerance {
        return Vec::new();
    }
    // Ends of the other side closer than the tolerance to `a` or `b` are those ends
    // (or a sliver), not nodes between them.
    let margin = tolerance / len2.sqrt();
    let mut on: Vec<(f64, u32)> = candidates
        .iter()
        .filter(|&&v| v != a && v != b)
        .filter_map(|&v| {
            let p = vertices[v as usize];
            let s = (p - pa).dot(&d) / len2;
            let off = (p - (pa + d * s)).norm();
            (s > margin && s < 1.0 - margin && off <= tolerance).then_some((s, v))
        })
        .collect();
    on.sort_by(|x, y| x.0.total_cmp(&y.0));
    on.into_iter().map(|(_, v)| v).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed unit cube whose top face's front edge has an extra node at its
    /// middle on the top's side only: the front face still spans the edge with one
    /// triangle side. Open (a T-junction) until split.
    fn cube_with_t_junction() -> Mesh {
        let mut m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        let top = m
            .triangles
            .iter()
            .position(|t| t.iter().all(|&v| m.vertices[v as usize].z == 1.0))
            .expect("a top triangle");
        // the top triangle's side along y = 0, if it has one; else the other top one
        let side = |t: &[u32; 3], vs: &[Point3]| {
            (0..3).find(|&s| {
                let (p, q) = (vs[t[s] as usize], vs[t[(s + 1) % 3] as usize]);
                p.y == 0.0 && q.y == 0.0
            })
        };
        let (t, s) = m
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| t.iter().all(|&v| m.vertices[v as usize].z == 1.0))
            .find_map(|(i, t)| side(t, &m.vertices).map(|s| (i, s)))
            .unwrap_or((top, 0));
        let tri = m.triangles[t];
        let (a, b, c) = (tri[s], tri[(s + 1) % 3], tri[(s + 2) % 3]);
        let mid = (m.vertices[a as usize].coords + m.vertices[b as usize].coords) / 2.0;
        // off the chord by less than the tolerance, as a node of a curved edge is
        m.vertices
            .push(Point3::from(mid) + crate::math::Vec3::new(0.0, 0.0, 1e-4));
        let v = (m.vertices.len() - 1) as u32;
        m.triangles[t] = [a, v, c];
        m.triangles.push([v, b, c]);
        m
    }

    #[test]
    fn a_t_junction_is_split_and_the_solid_closes() {
        let mut m = cube_with_t_junction();
        let before = m.inspect();
        assert_eq!(before.boundary_edges, 3, "{before:?}");
        assert!(!before.is_watertight());
        assert_eq!(split_t_junctions(&mut m, 0.01), 1);
        let after = m.inspect();
        assert!(after.is_watertight(), "{after:?}");
        let volume = m.signed_volume();
        assert!((volume - 1.0).abs() < 1e-3, "{volume}");
    }

    #[test]
    fn a_node_farther_than_the_tolerance_is_not_a_t_junction() {
        let mut m = cube_with_t_junction();
        assert_eq!(split_t_junctions(&mut m, 1e-5), 0);
        assert!(!m.inspect().is_watertight());
    }

    #[test]
    fn a_missing_triangle_is_not_a_t_junction() {
        let mut m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        m.triangles.pop();
        assert_eq!(split_t_junctions(&mut m, 0.01), 0);
        assert_eq!(m.inspect().boundary_edges, 3);
    }

    /// A 2 × 3 × 4 box without the triangles of `missing`.
    fn box_without(missing: &[usize]) -> Mesh {
        let mut m = Mesh::cuboid(Point3::origin(), Point3::new(2.0, 3.0, 4.0));
        let mut k = 0;
        m.triangles.retain(|_| {
            k += 1;
            !missing.contains(&(k - 1))
        });
        m
    }

    /// The triangle of the 2 × 3 × 4 box sharing a side with its triangle 0 and
    /// lying in the same face (`same_face`) or in the face across that side.
    fn beside_first(same_face: bool) -> usize {
        let whole = Mesh::cuboid(Point3::origin(), Point3::new(2.0, 3.0, 4.0));
        let normal = |t: &[u32; 3]| {
            let p = |k: usize| whole.vertices[t[k] as usize];
            (p(1) - p(0)).cross(&(p(2) - p(0))).normalize()
        };
        let first = whole.triangles[0];
        (1..whole.triangles.len())
            .find(|&b| {
                let t = whole.triangles[b];
                let shared = first.iter().filter(|v| t.contains(v)).count();
                let cos = normal(&first).dot(&normal(&t));
                shared == 2
                    && if same_face {
                        cos > 0.999
                    } else {
                        cos.abs() < 1e-9
                    }
            })
            .expect("a triangle beside triangle 0")
    }

    #[test]
    fn a_missing_triangle_or_flat_face_is_filled_facing_out() {
        // one triangle, then both triangles of one face (a flat, convex 4-sided hole)
        for missing in [vec![0], vec![0, beside_first(true)]] {
            let mut m = box_without(&missing);
            assert!(!m.inspect().is_watertight());
            assert_eq!(fill_holes(&mut m, 0.01), 1, "{missing:?}");
            let r = m.inspect();
            assert!(r.is_watertight(), "{missing:?}: {r:?}");
            let v = m.signed_volume();
            assert!((v - 24.0).abs() < 1e-9, "{missing:?}: {v}");
        }
    }

    #[test]
    fn a_hole_that_is_not_one_flat_face_stays_open() {
        // two triangles of two faces meeting at an edge: a 4-sided rim bent 90°
        let other = beside_first(false);
        let mut m = box_without(&[0, other]);
        assert_eq!(fill_holes(&mut m, 0.01), 0);
        assert_eq!(m.inspect().boundary_edges, 4);
    }
}
