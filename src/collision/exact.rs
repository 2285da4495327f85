//! Exact interference of two posed parts: simultaneous traversal of the two trees in
//! the first part's frame, triangle pairs tested with [`tri_tri`], containment by
//! ray parity, and the minimum distance used by continuous sweeps.

use super::shape::{Aabb, Collider, Node, Obb};
use super::triangle::{tri_distance, tri_tri, Tri};
use super::{CollisionError, Contact, InterferenceKind, PairMember, PoseFault};
use crate::math::Transform;
use nalgebra::{Isometry3, Matrix3};
use std::cell::Cell;
use std::collections::{HashMap, HashSet};
use std::ops::ControlFlow;

/// The pose of `b`'s part frame in `a`'s part frame, with what the node test needs.
pub(crate) struct Relative {
    iso: Isometry3<f64>,
    rot: Matrix3<f64>,
}

impl Relative {
    pub(crate) fn new(pa: &Transform, pb: &Transform) -> Self {
        let iso = pa.isometry().inverse() * pb.isometry();
        let rot = *iso.rotation.to_rotation_matrix().matrix();
        Relative { iso, rot }
    }

    /// Whether oriented boxes `a` (frame A) and `b` (frame B) come within `margin`:
    /// a bounding-sphere reject, then the separating-axis test on the 15 axes (faces
    /// of both boxes and edge cross products). Conservative: cross axes are not
    /// normalised (length ≤ 1), so the margin they apply is at least `margin`.
    #[inline]
    pub(crate) fn boxes_meet(&self, a: &Obb, b: &Obb, margin: f64) -> bool {
        let d = self.rot * b.centre + self.iso.translation.vector - a.centre;
        let reach = a.half.norm() + b.half.norm() + margin;
        if d.norm_squared() > reach * reach {
            return false;
        }
        // b's axes and the centre offset in a's box frame
        let r = a.axes.tr_mul(&(self.rot * b.axes));
        let t = a.axes.tr_mul(&d);
        // the small bias keeps near-parallel axes conservative
        let ar = r.abs().add_scalar(1e-12);
        let (ha, hb) = (&a.half, &b.half);
        for i in 0..3 {
            let rb = hb[0] * ar[(i, 0)] + hb[1] * ar[(i, 1)] + hb[2] * ar[(i, 2)];
            if t[i].abs() > ha[i] + rb + margin {
                return false;
            }
        }
        for j in 0..3 {
            let ra = ha[0] * ar[(0, j)] + ha[1] * ar[(1, j)] + ha[2] * ar[(2, j)];
            let tj = t[0] * r[(0, j)] + t[1] * r[(1, j)] + t[2] * r[(2, j)];
            if tj.abs() > ra + hb[j] + margin {
                return false;
            }
        }
        // axis a_i × b_j
        for i in 0..3 {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            for j in 0..3 {
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                let ra = ha[i1] * ar[(i2, j)] + ha[i2] * ar[(i1, j)];
                let rb = hb[j1] * ar[(i, j2)] + hb[j2] * ar[(i, j1)];
                let tl = t[i2] * r[(i1, j)] - t[i1] * r[(i2, j)];
                if tl.abs() > ra + rb + margin {
                    return false;
                }
            }
        }
        true
    }

    /// Lower bound of the distance between oriented boxes `a` (frame A) and `b`
    /// (frame B): the widest gap between their shadows on the six face normals, or
    /// between their bounding spheres.
    #[inline]
    fn obb_gap(&self, a: &Obb, b: &Obb) -> f64 {
        let d = self.rot * b.centre + self.iso.translation.vector - a.centre;
        let (ha, hb) = (&a.half, &b.half);
        let mut gap = d.norm() - ha.norm() - hb.norm();
        let r = a.axes.tr_mul(&(self.rot * b.axes));
        let t = a.axes.tr_mul(&d);
        let ar = r.abs();
        for i in 0..3 {
            let rb = hb[0] * ar[(i, 0)] + hb[1] * ar[(i, 1)] + hb[2] * ar[(i, 2)];
            gap = gap.max(t[i].abs() - ha[i] - rb);
        }
        for j in 0..3 {
            let ra = ha[0] * ar[(0, j)] + ha[1] * ar[(1, j)] + ha[2] * ar[(2, j)];
            let tj = t[0] * r[(0, j)] + t[1] * r[(1, j)] + t[2] * r[(2, j)];
            gap = gap.max(tj.abs() - ra - hb[j]);
        }
        gap.max(0.0)
    }

    fn tri(&self, t: &Tri) -> Tri {
        [self.iso * t[0], self.iso * t[1], self.iso * t[2]]
    }
}

pub(crate) fn tri_box(t: &Tri) -> Aabb {
    Aabb {
        lo: t[0].inf(&t[1]).inf(&t[2]),
        hi: t[0].sup(&t[1]).sup(&t[2]),
    }
}

fn size(n: &Node) -> f64 {
    n.bounds.half_extents().norm_squared()
}

pub(crate) fn obb_size(o: &Obb) -> f64 {
    o.half.norm_squared()
}

/// Calls `f` on every pair of triangles (b's already in a's frame) whose leaf boxes
/// come within `margin`, until it breaks.
///
/// `floor` prunes by depth: node pairs whose crossing depth cannot exceed
/// `floor.get()` are skipped. The crossing depth of two triangles ([`tri_tri`]) is
/// at most the smaller triangle's diameter plus `margin`, and a triangle's diameter
/// at most its box's diagonal; a negative floor prunes nothing.
fn for_each_triangle_pair<B>(
    a: &Collider,
    b: &Collider,
    rel: &Relative,
    margin: f64,
    floor: &Cell<f64>,
    mut f: impl FnMut(u32, &Tri, u32, &Tri) -> ControlFlow<B>,
) -> ControlFlow<B> {
    let mut stack: Vec<(u32, u32)> = Vec::with_capacity(64);
    stack.push((0, 0));
    let mut moved: Vec<(u32, Tri, Aabb)> = Vec::with_capacity(8);
    while let Some((i, j)) = stack.pop() {
        let (na, nb) = (&a.nodes[i as usize], &b.nodes[j as usize]);
        let (oa, ob) = (&a.obbs[i as usize], &b.obbs[j as usize]);
        let least = floor.get();
        if least >= 0.0 && 2.0 * oa.half.norm().min(ob.half.norm()) + margin <= least {
            continue;
        }
        if !rel.boxes_meet(oa, ob, margin) {
            continue;
        }
        match (na.count > 0, nb.count > 0) {
            (true, true) => {
                moved.clear();
                moved.extend((nb.first..nb.first + nb.count).map(|kb| {
                    let m = rel.tri(&b.tri(kb as usize));
                    (kb, m, tri_box(&m))
                }));
                for ka in na.first..na.first + na.count {
                    let ta = a.tri(ka as usize);
                    let ba = tri_box(&ta);
                    for (kb, tb, bb) in &moved {
                        // cheap reject before the exact test
                        if ba.overlap(bb).min() >= -margin {
                            f(ka, &ta, *kb, tb)?;
                        }
                    }
                }
            }
            (false, true) => {
                // A subtree of `a` on one side of every plane of `b`'s few triangles
                // cannot cross them (`tri_tri` rejects such pairs first): a small
                // part deep inside a large box never reaches the leaves.
                let planes = b.leaf_tris(nb).map(|t| rel.tri(&t));
                if obb_meets_planes(oa, planes, margin) {
                    stack.extend([(na.first, j), (na.first + 1, j)]);
                }
            }
            (true, false) => {
                let moved_obb = Obb {
                    centre: rel.rot * ob.centre + rel.iso.translation.vector,
                    axes: rel.rot * ob.axes,
                    half: ob.half,
                };
                if obb_meets_planes(&moved_obb, a.leaf_tris(na), margin) {
                    stack.extend([(i, nb.first), (i, nb.first + 1)]);
                }
            }
            (false, false) => {
                if obb_size(oa) >= obb_size(ob) {
                    stack.extend([(na.first, j), (na.first + 1, j)]);
                } else {
                    stack.extend([(i, nb.first), (i, nb.first + 1)]);
                }
            }
        }
    }
    ControlFlow::Continue(())
}

/// Whether box `o` reaches within `margin` of the plane of some triangle of
/// `tris` (same frame); degenerate triangles meet nothing ([`tri_tri`] skips them).
#[inline]
fn obb_meets_planes(o: &Obb, tris: impl Iterator<Item = Tri>, margin: f64) -> bool {
    for t in tris {
        let Some(n) = (t[1] - t[0]).cross(&(t[2] - t[0])).try_normalize(0.0) else {
            continue;
        };
        let c = n.dot(&(o.centre - t[0].coords));
        let r = o.half[0] * n.dot(&o.axes.column(0)).abs()
            + o.half[1] * n.dot(&o.axes.column(1)).abs()
            + o.half[2] * n.dot(&o.axes.column(2)).abs();
        // the small bias keeps the test conservative against rounding
        if c.abs() <= r + margin + 1e-9 * (1.0 + c.abs()) {
            return true;
        }
    }
    false
}

pub(crate) fn check_pose(p: &Transform) -> Result<(), CollisionError> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(CollisionError::BadPose(PoseFault::Part))
    }
}

pub(crate) fn check_tolerance(tolerance: f64) -> Result<(), CollisionError> {
    if tolerance.is_finite() && tolerance >= 0.0 {
        Ok(())
    } else {
        Err(CollisionError::BadTolerance(tolerance))
    }
}

pub(crate) fn eps(a: &Collider, b: &Collider, pa: &Transform, pb: &Transform) -> f64 {
    let far = pa.translation().amax().max(pb.translation().amax());
    a.eps.max(b.eps).max(1e-12 * far)
}

/// Whether parts `a` at `pa` and `b` at `pb` interfere: their surfaces cross deeper
/// than `tolerance` (mm), or one solid lies inside the other. Stops at the first
/// witness; the cheap query for planners. Same verdict as [`contact`]
/// (`Contact::Interfering`).
pub fn interferes(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
) -> Result<bool, CollisionError> {
    interferes_by(a, pa, b, pb, tolerance, None).map(|v| v.unwrap_or(true))
}

/// [`interferes`] that gives up at `deadline`: `Ok(None)` when it passed before the
/// answer was known. The clock is read every 256 triangle pairs of the crossing walk,
/// so parts seated in each other over many fine facets do not hold the caller past
/// its budget; the depth walk and the containment test that may follow it are not
/// interrupted (they run once, after the walk).
///
/// # Errors
/// As [`interferes`].
pub fn interferes_until(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: std::time::Instant,
) -> Result<Option<bool>, CollisionError> {
    interferes_by(a, pa, b, pb, tolerance, Some(deadline))
}

/// The deadline of a static pair walk, read every 256 triangle pairs (a clock read
/// per pair would cost more than the pair test).
struct PairClock {
    deadline: Option<std::time::Instant>,
    visited: u32,
}

impl PairClock {
    fn new(deadline: Option<std::time::Instant>) -> Self {
        Self {
            deadline,
            visited: 0,
        }
    }

    /// Counts one pair; whether the deadline has passed (read on every 256th).
    fn passed(&mut self) -> bool {
        self.visited = self.visited.wrapping_add(1);
        self.visited.is_multiple_of(256)
            && self
                .deadline
                .is_some_and(|d| std::time::Instant::now() >= d)
    }
}

/// [`interferes`]; `None`: `deadline` passed first.
fn interferes_by(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: Option<std::time::Instant>,
) -> Result<Option<bool>, CollisionError> {
    check_pose(pa)?;
    check_pose(pb)?;
    check_tolerance(tolerance)?;
    let rel = Relative::new(pa, pb);
    let eps = eps(a, b, pa, pb);
    let oriented = a.is_solid() && b.is_solid();
    let mut crossed = false;
    let mut seeds = Vec::new();
    // Open meshes: once some pair crosses, only a pair deeper than the tolerance can
    // change the answer. Solids: shallow crossings are seeds of the depth walk, so
    // every one is visited (the same pairs as `contact` visits before a deep one).
    let floor = Cell::new(-1.0);
    let mut clock = PairClock::new(deadline);
    let mut late = false;
    // Closed solids (watertight or stacked slices) also interfere where their faces
    // overlap in one plane facing the same way, with no pair crossing (an equal wall
    // pushed into an equal wall): the edge check's rule, containment.rs.
    let shared = a.encloses_volume() && b.encloses_volume();
    let margin = super::containment::walk_margin(shared, eps);
    let crossing = for_each_triangle_pair(a, b, &rel, margin, &floor, |ka, ta, kb, tb| {
        if clock.passed() {
            late = true;
            return ControlFlow::Break(());
        }
        let depth = tri_tri(ta, tb, eps, oriented);
        if shared
            && depth.is_none_or(|d| d <= tolerance)
            && super::containment::shared_face_overlap(ta, tb) > tolerance
        {
            return ControlFlow::Break(());
        }
        match depth {
            Some(d) if d > tolerance => ControlFlow::Break(()),
            Some(d) => {
                if d > 0.0 {
                    crossed = true;
                    if oriented {
                        seeds.push((ka, kb));
                    } else {
                        floor.set(tolerance);
                    }
                }
                ControlFlow::Continue(())
            }
            None => ControlFlow::Continue(()),
        }
    });
    if late {
        return Ok(None);
    }
    if crossing.is_break() {
        return Ok(Some(true));
    }
    if crossed {
        // surfaces that cross (even shallowly) cannot have one solid inside the other
        return Ok(Some(
            oriented && deep_reach(a, pa, b, pb, &seeds, tolerance, eps, true) > tolerance,
        ));
    }
    Ok(Some(contained(a, pa, b, pb, eps).is_some()))
}

/// The full verdict for parts `a` at `pa` and `b` at `pb` (part frames → world):
/// separate, touching (surfaces meet, crossing depth ≤ `tolerance` mm), or
/// interfering with the largest crossing depth, or by containment.
/// Symmetric: swapping the parts gives the same verdict and depth (with
/// [`InterferenceKind::Contained`]'s `inner` swapped).
///
/// # Examples
/// Two 10 mm cubes: apart, face to face, then 0.5 mm into each other.
/// ```
/// use fitup::collision::{contact, Collider, Contact, DEFAULT_TOLERANCE};
/// use fitup::math::{Point3, Transform, Vec3};
/// use fitup::mesh::Mesh;
/// use std::sync::Arc;
///
/// let cube = Collider::new(Arc::new(Mesh::cuboid(
///     Point3::new(0.0, 0.0, 0.0),
///     Point3::new(10.0, 10.0, 10.0),
/// )))
/// .unwrap();
/// let at = |x: f64| Transform::from_translation(Vec3::new(x, 0.0, 0.0));
/// let verdict = |x| contact(&cube, &at(0.0), &cube, &at(x), DEFAULT_TOLERANCE).unwrap();
/// assert_eq!(verdict(15.0), Contact::Separate);
/// assert_eq!(verdict(10.0), Contact::Touching);
/// assert!((verdict(9.5).depth() - 0.5).abs() < 1e-9);
/// ```
///
/// # Errors
/// A pose with NaN or infinite entries, a negative or non-finite tolerance.
pub fn contact(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
) -> Result<Contact, CollisionError> {
    contact_by(a, pa, b, pb, tolerance, None).map(|c| c.expect("no deadline, no give-up"))
}

/// [`contact`] that gives up at `deadline`: `Ok(None)` when it passed before the
/// verdict was known. As in [`interferes_until`], the clock is read every 256
/// triangle pairs of the crossing walk; the depth walk and the containment test
/// that may follow it run once and are not interrupted.
///
/// # Errors
/// As [`contact`].
pub fn contact_until(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: std::time::Instant,
) -> Result<Option<Contact>, CollisionError> {
    contact_by(a, pa, b, pb, tolerance, Some(deadline))
}

/// [`contact`]; `None`: `deadline` passed first.
fn contact_by(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: Option<std::time::Instant>,
) -> Result<Option<Contact>, CollisionError> {
    check_pose(pa)?;
    check_pose(pb)?;
    check_tolerance(tolerance)?;
    let rel = Relative::new(pa, pb);
    let eps = eps(a, b, pa, pb);
    let oriented = a.is_solid() && b.is_solid();
    let mut touching = false;
    let mut depth = 0.0f64;
    let mut seeds = Vec::new();
    // Once some pair crosses deeper than the tolerance (or, for open meshes, at
    // all), the verdict is `Touching` or `Interfering` with the largest pair depth:
    // only a pair deeper than both the tolerance and the depth found can change it.
    // Solids visit every shallow crossing first: they seed the depth walk.
    let floor = Cell::new(-1.0);
    // The shared-face rule of `interferes_by`.
    let shared = a.encloses_volume() && b.encloses_volume();
    let margin = super::containment::walk_margin(shared, eps);
    let mut faces = 0.0f64;
    let mut clock = PairClock::new(deadline);
    let walk = for_each_triangle_pair::<()>(a, b, &rel, margin, &floor, |ka, ta, kb, tb| {
        if clock.passed() {
            return ControlFlow::Break(());
        }
        let crossing = tri_tri(ta, tb, eps, oriented);
        if shared && crossing.is_none_or(|d| d <= tolerance) {
            faces = faces.max(super::containment::shared_face_overlap(ta, tb));
        }
        if let Some(d) = crossing {
            touching = true;
            depth = depth.max(d);
            if oriented && d > 0.0 && d <= tolerance {
                seeds.push((ka, kb));
            }
            if depth > tolerance || (!oriented && depth > 0.0) {
                floor.set(depth.max(tolerance));
            }
        }
        ControlFlow::Continue(())
    });
    // The walk breaks only for the deadline.
    if walk.is_break() {
        return Ok(None);
    }
    if depth > tolerance {
        return Ok(Some(Contact::Interfering {
            depth,
            kind: InterferenceKind::SurfacesCross,
        }));
    }
    if faces > tolerance {
        return Ok(Some(Contact::Interfering {
            depth: faces,
            kind: InterferenceKind::FacesOverlap,
        }));
    }
    // surfaces that cross (even shallowly) cannot have one solid inside the other
    if depth > 0.0 {
        if oriented {
            let reach = deep_reach(a, pa, b, pb, &seeds, tolerance, eps, false);
            if reach > tolerance {
                return Ok(Some(Contact::Interfering {
                    depth: reach,
                    kind: InterferenceKind::SurfacesCross,
                }));
            }
        }
        return Ok(Some(Contact::Touching));
    }
    if let Some((inner, depth)) = containment(a, pa, b, pb, eps) {
        return Ok(Some(Contact::Interfering {
            depth,
            kind: InterferenceKind::Contained { inner },
        }));
    }
    Ok(Some(if touching {
        Contact::Touching
    } else {
        Contact::Separate
    }))
}

/// How deep the surface of one solid reaches into the other when their surfaces
/// cross only shallowly (every pair of triangles within the tolerance), mm: the
/// largest distance to `b`'s surface of a sample point (centroid, edge midpoints)
/// of a triangle of `a` inside `b`, and vice versa, over the triangles reached by
/// climbing from the crossing triangles `seeds` (`(a's, b's)` tree indices) to
/// deeper and deeper edge neighbours. 0 when nothing is found deeper than the
/// tolerance. With `early`, returns as soon as some point is deeper than
/// `tolerance` (the verdict is the same: the climbs are deterministic).
///
/// Why: a crossing pair's depth cannot exceed the smaller facet, so on fine meshes
/// (facets about the tolerance) a 0.5 mm overlap crosses only shallowly pair by
/// pair; the surface inside the other solid still reaches 0.5 mm deep. Cheap when
/// touching: every sample point near a contact line is within the tolerance of the
/// other surface, so the climbs stop after a step or two.
#[allow(clippy::too_many_arguments)]
fn deep_reach(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    seeds: &[(u32, u32)],
    tolerance: f64,
    eps: f64,
    early: bool,
) -> f64 {
    let mut of_a: Vec<u32> = seeds.iter().map(|s| s.0).collect();
    let mut of_b: Vec<u32> = seeds.iter().map(|s| s.1).collect();
    for v in [&mut of_a, &mut of_b] {
        v.sort_unstable();
        v.dedup();
    }
    let a_in_b = Relative::new(pb, pa).iso;
    let b_in_a = Relative::new(pa, pb).iso;
    // A witness of `a` deeper than the tolerance inside `b` lies in `a`'s box and in
    // `b`'s box shrunk by the tolerance: when these do not meet (a plate on a table,
    // a part near first contact in a sweep), no climb can find one.
    let may_reach = |inner: &Collider, outer: &Collider, iso: &Isometry3<f64>| {
        let b = outer.bounds();
        let shrunk = Aabb {
            lo: b.lo.map(|v| v + tolerance),
            hi: b.hi.map(|v| v - tolerance),
        };
        inner.bounds().transformed(iso).overlap(&shrunk).min() >= 0.0
    };
    let mut reach = 0.0f64;
    if may_reach(a, b, &a_in_b) {
        reach = climb(a, b, &a_in_b, &of_a, tolerance, eps, early);
        if early && reach > tolerance {
            return reach;
        }
    }
    if may_reach(b, a, &b_in_a) {
        reach = reach.max(climb(b, a, &b_in_a, &of_b, tolerance, eps, early));
    }
    reach
}

/// [`deep_reach`] one way: triangles of `inner` (mapped into `outer`'s frame by
/// `iso`) climbing into the solid `outer` from `seeds` (tree order).
fn climb(
    inner: &Collider,
    outer: &Collider,
    iso: &Isometry3<f64>,
    seeds: &[u32],
    tolerance: f64,
    eps: f64,
    early: bool,
) -> f64 {
    // Points farther than this from the surface are classified by ray parity and
    // count as witnesses; nearer ones take the side of the nearest face's plane,
    // which only steers the climb.
    let sure = tolerance.max(100.0 * eps);
    let mut deepest = 0.0f64;
    let mut scores: HashMap<u32, f64> = HashMap::new();
    let mut walked: HashSet<u32> = HashSet::new();
    // signed depth of triangle k: the largest over its sample points of the
    // distance to `outer`'s surface, negative outside
    let mut score = |k: u32, deepest: &mut f64| -> f64 {
        if let Some(&s) = scores.get(&k) {
            return s;
        }
        let t = inner.tri(k as usize).map(|p| iso * p);
        let centre = nalgebra::center(&nalgebra::center(&t[0], &t[1]), &t[2]);
        let points = [
            centre,
            nalgebra::center(&t[0], &t[1]),
            nalgebra::center(&t[1], &t[2]),
            nalgebra::center(&t[2], &t[0]),
        ];
        let mut best = f64::NEG_INFINITY;
        for p in points {
            let (d, near, on_surface) = outer.closest_triangle(&p);
            if d <= eps {
                best = best.max(0.0);
                continue;
            }
            let f = outer.tri(near);
            let n = (f[1] - f[0]).cross(&(f[2] - f[0])).normalize();
            let along = n.dot(&(p - on_surface));
            let signed = if d > sure {
                // Closest to a face's interior (offset along its normal) and in
                // front of it: outside for sure, no ray cast (most points of a
                // touching part). Otherwise ray parity decides.
                if along >= 0.999 * d {
                    -d
                } else if outer.contains_point(&p) {
                    *deepest = deepest.max(d);
                    d
                } else {
                    -d
                }
            } else if along < 0.0 {
                d
            } else {
                -d
            };
            best = best.max(signed);
        }
        scores.insert(k, best);
        best
    };
    for &seed in seeds {
        let mut here = seed;
        let mut level = score(seed, &mut deepest);
        while walked.insert(here) {
            if early && deepest > tolerance {
                return deepest;
            }
            let mut next = None;
            for n in inner.neighbours(here as usize) {
                if n == u32::MAX {
                    continue;
                }
                let s = score(n, &mut deepest);
                if s > level + eps && next.is_none_or(|(_, best)| s > best) {
                    next = Some((n, s));
                }
            }
            match next {
                Some((n, s)) => (here, level) = (n, s),
                None => break,
            }
        }
        if early && deepest > tolerance {
            return deepest;
        }
    }
    deepest
}

/// When the surfaces do not cross: is one solid inside the other? Returns which
/// part is inside ([`PairMember::First`] = `a`) and the containment depth.
fn containment(
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
fn contained(
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
        if outer.distance_to_point(&q, eps) <= eps {
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

/// The clearance between parts `a` at `pa` and `b` at `pb` (mm): the distance between
/// their surfaces, searched up to `cap` mm (returns `cap` when nothing is nearer), and
/// 0 when they meet or one solid lies inside the other — the same geometry
/// [`contact`] judges, so the two agree at every tolerance `tol` ≥ 0:
/// `Touching` or `Interfering` ⇒ clearance ≤ `tol` (0 for crossing or contained
/// parts), and clearance > `tol` ⇒ `Separate`.
///
/// A surface distance within the pair's numerical slack (the colliders' `eps`, the
/// distance at which [`contact`] counts surfaces as meeting) is reported as 0.
pub fn clearance(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    cap: f64,
) -> Result<f64, CollisionError> {
    // The full search (stop 0): a `stop` above 0 would return the first leaf pair's
    // distance below it, not the minimum (clearance once answered 23 mm for touching
    // parts that way).
    let cap = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap.max(0.0)
    };
    let d = distance_search(a, pa, b, pb, 0.0, cap, 0.0)?;
    let eps = eps(a, b, pa, pb);
    // `tri_tri` counts pairs within `eps` of each other's planes as meeting; their
    // distance may be a few `eps` (corner to edge), never more than 4·eps.
    if d <= 4.0 * eps {
        return Ok(0.0);
    }
    // Surfaces apart: one solid may still hold the other (contact says Interfering).
    if contained(a, pa, b, pb, eps).is_some() {
        return Ok(0.0);
    }
    Ok(d)
}

/// Minimum distance between the surfaces of `a` at `pa` and `b` at `pb`, mm (0 when
/// they touch or cross; for one part inside another it is the gap between the
/// surfaces). Pruned by box distances; stops early once below `stop`.
pub fn surface_distance(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
) -> Result<f64, CollisionError> {
    distance_search(a, pa, b, pb, stop, f64::INFINITY, 0.0)
}

/// A lower bound `d` of the surface distance `d*` between `a` at `pa` and `b` at
/// `pb` (mm) for conservative advancement, cheaper than [`surface_distance`]:
/// `d ≤ d* ≤ (1 + slack) · d` when `d* < cap`, else `d ≥ cap / (1 + slack)`
/// (the search drops every box pair farther than what it needs). Stops early once
/// below `stop`. `slack ≥ 0` (0.25 loses a fifth of each advance and skips most
/// of the exact search).
pub fn distance_lower_bound(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
    cap: f64,
    slack: f64,
) -> Result<f64, CollisionError> {
    distance_search(a, pa, b, pb, stop, cap, slack.max(0.0))
}

/// Branch and bound over box pairs; a pair is dropped when its box distance times
/// `1 + slack` reaches the best distance found (initially `cap`), so the true
/// distance is at least `best / (1 + slack)`, which is returned.
fn distance_search(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    stop: f64,
    cap: f64,
    slack: f64,
) -> Result<f64, CollisionError> {
    check_pose(pa)?;
    check_pose(pb)?;
    let rel = Relative::new(pa, pb);
    let grow = 1.0 + slack;
    let mut best = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap * grow
    };
    let mut stack: Vec<(u32, u32, f64)> = vec![(0, 0, 0.0)];
    let mut moved_boxes: Vec<(Tri, Aabb)> = Vec::with_capacity(8);
    while let Some((i, j, lb)) = stack.pop() {
        if lb * grow >= best {
            continue;
        }
        let (na, nb) = (&a.nodes[i as usize], &b.nodes[j as usize]);
        if na.count > 0 && nb.count > 0 {
            moved_boxes.clear();
            moved_boxes.extend(b.leaf_tris(nb).map(|t| {
                let m = rel.tri(&t);
                (m, tri_box(&m))
            }));
            for ta in a.leaf_tris(na) {
                let ba = tri_box(&ta);
                for (tb, bb) in &moved_boxes {
                    // the triangles' boxes bound their distance from below
                    if ba.distance_to_box(bb) * grow < best {
                        best = best.min(tri_distance(&ta, tb));
                    }
                }
            }
            if best < stop {
                return Ok(best / grow);
            }
            continue;
        }
        let split_a = nb.count > 0 || (na.count == 0 && size(na) >= size(nb));
        let children = if split_a {
            [(na.first, j), (na.first + 1, j)]
        } else {
            [(i, nb.first), (i, nb.first + 1)]
        };
        let mut next = children.map(|(ci, cj)| {
            let d = rel.obb_gap(&a.obbs[ci as usize], &b.obbs[cj as usize]);
            (ci, cj, d)
        });
        // nearer pair last so it is explored first
        if next[0].2 < next[1].2 {
            next.swap(0, 1);
        }
        stack.extend(next.into_iter().filter(|c| c.2 * grow < best));
    }
    Ok(best / grow)
}
