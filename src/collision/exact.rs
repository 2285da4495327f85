//! Exact interference of two posed parts: simultaneous traversal of the two trees in
//! the first part's frame, triangle pairs tested with [`tri_tri`]; containment at
//! rest is in `containment.rs`, distances for continuous sweeps in `distance.rs`.

use super::containment::{contained, containment};
use super::node::{Node, Obb, LEAF_SIZE};
use super::relative::{obbs_meet, Relative};
use super::shape::{Collider, Plane};
use super::triangle::{tri_tri_with, unit_normal, Tri};
use super::{CollisionError, Contact, InterferenceKind, PoseFault};
use crate::math::{Aabb, Deadline, Transform, Vec3};
use nalgebra::Isometry3;
use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::ops::ControlFlow;

pub(crate) fn tri_box(t: &Tri) -> Aabb {
    Aabb {
        lo: t[0].inf(&t[1]).inf(&t[2]),
        hi: t[0].sup(&t[1]).sup(&t[2]),
    }
}

pub(super) fn size(n: &Node) -> f64 {
    n.bounds.half_extents().norm_squared()
}

pub(crate) fn obb_size(o: &Obb) -> f64 {
    o.half.norm_squared()
}

/// A triangle of the moved part (`b`) in `a`'s frame, with its unit normal (as
/// [`unit_normal`] computes it from these corners; zero without area) and its box.
#[derive(Debug, Clone, Copy)]
struct Moved {
    t: Tri,
    n: Vec3,
    bx: Aabb,
}

/// A leaf of `b` in `a`'s frame: its triangles `moved[first..first + count]`, the
/// box around them and the leaf's oriented box.
#[derive(Debug, Clone, Copy)]
struct MovedLeaf {
    first: u32,
    count: u32,
    bx: Aabb,
    obb: Obb,
}

/// What a pair walk reuses from query to query (one per thread), so a query
/// allocates nothing: the walk's stack, and `b`'s leaves moved into `a`'s frame,
/// each once per query however many leaves of `a` it meets (a planner's query met
/// the same leaf of the environment from several leaves of the part, and moved its
/// triangles again every time).
#[derive(Debug, Default)]
struct PairScratch {
    /// The current query; `stamp[j] == generation` when `b`'s node `j` is moved.
    generation: u32,
    stamp: Vec<u32>,
    /// `b`'s node → its entry in `leaves`, valid where stamped.
    slot: Vec<u32>,
    leaves: Vec<MovedLeaf>,
    moved: Vec<Moved>,
    stack: Vec<(u32, u32)>,
    /// `b`'s node `j`'s oriented box in `a`'s frame, valid where
    /// `box_stamp[j] == generation` (a node meets several of `a`'s).
    box_stamp: Vec<u32>,
    boxes: Vec<Obb>,
}

impl PairScratch {
    /// Starts a query whose moved part has `nodes` nodes.
    fn begin(&mut self, nodes: usize) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.box_stamp.fill(0);
            self.generation = 1;
        }
        if self.stamp.len() < nodes {
            self.stamp.resize(nodes, 0);
            self.slot.resize(nodes, 0);
            self.box_stamp.resize(nodes, 0);
            self.boxes.resize(nodes, Obb::BLANK);
        }
        self.leaves.clear();
        self.moved.clear();
        self.stack.clear();
    }

    /// `b`'s node `j`'s oriented box in `a`'s frame, moved on first use.
    #[inline]
    fn obb(&mut self, b: &Collider, j: u32, rel: &Relative) -> &Obb {
        let at = j as usize;
        if self.box_stamp[at] != self.generation {
            self.box_stamp[at] = self.generation;
            self.boxes[at] = rel.obb(&b.obbs[at]);
        }
        &self.boxes[at]
    }

    /// `b`'s leaf `j` in `a`'s frame, moved on first use in this query.
    fn leaf(&mut self, b: &Collider, j: u32, rel: &Relative) -> MovedLeaf {
        let at = j as usize;
        if self.stamp[at] == self.generation {
            return self.leaves[self.slot[at] as usize];
        }
        let node = &b.nodes[at];
        let first = self.moved.len() as u32;
        let mut bx = Aabb::EMPTY;
        for k in node.first..node.first + node.count {
            let t = rel.tri(&b.tri(k as usize));
            let n = unit_normal(&t).unwrap_or_else(Vec3::zeros);
            let tb = tri_box(&t);
            bx = bx.union(&tb);
            self.moved.push(Moved { t, n, bx: tb });
        }
        let leaf = MovedLeaf {
            first,
            count: node.count,
            bx,
            obb: *self.obb(b, j, rel),
        };
        self.stamp[at] = self.generation;
        self.slot[at] = self.leaves.len() as u32;
        self.leaves.push(leaf);
        leaf
    }
}

thread_local! {
    static PAIR_SCRATCH: RefCell<PairScratch> = RefCell::new(PairScratch::default());
}

/// One triangle of a pair handed to a walk's visitor: its index in its collider's
/// tree order, its corners and unit normal (`a`'s frame).
pub(crate) struct Face<'t> {
    pub(crate) k: u32,
    pub(crate) t: &'t Tri,
    pub(crate) n: &'t Vec3,
}

/// How far (mm) the faces of two parts under the shared-face rule may lie off each
/// other's planes when tested from the other side: `Flat::shared` holds one face
/// within the band of the *other's* plane, with normals within `SAME_FACING` (about
/// 4.5e-5 rad), so seen from the first face's plane the other reaches up to
/// 4.5e-5 × the two faces' extent further.
fn tilt_slack(shared: bool, a: &Obb, b: &Obb) -> f64 {
    if shared {
        1e-4 * (a.radius + b.radius)
    } else {
        0.0
    }
}

/// Calls `f` on every pair of triangles (b's moved into a's frame) that can meet
/// within `margin` (mm), until it breaks; with `shared` (the shared-face rule
/// applies) also every pair whose faces may lie in one plane facing the same way.
///
/// Node pairs are pruned by their oriented boxes, and a leaf against a node by the
/// leaf's triangle planes; in a pair of leaves, only the triangles of each that
/// reach the other leaf (box and oriented box against plane) are paired, and a pair
/// is tested by its triangles' boxes before `f` runs. Every test is conservative:
/// `f` sees every pair for which [`tri_tri`] could answer `Some`, or whose faces
/// lie within `margin` of one plane facing the same way.
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
    shared: bool,
    floor: &Cell<f64>,
    mut f: impl FnMut(Face<'_>, Face<'_>) -> ControlFlow<B>,
) -> ControlFlow<B> {
    PAIR_SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scratch) => walk_pairs(a, b, rel, margin, shared, floor, &mut scratch, &mut f),
        // a visitor that walks again (none does): a scratch of its own
        Err(_) => walk_pairs(
            a,
            b,
            rel,
            margin,
            shared,
            floor,
            &mut PairScratch::default(),
            &mut f,
        ),
    })
}

/// [`for_each_triangle_pair`] with its scratch.
#[allow(clippy::too_many_arguments)]
fn walk_pairs<B>(
    a: &Collider,
    b: &Collider,
    rel: &Relative,
    margin: f64,
    shared: bool,
    floor: &Cell<f64>,
    s: &mut PairScratch,
    f: &mut impl FnMut(Face<'_>, Face<'_>) -> ControlFlow<B>,
) -> ControlFlow<B> {
    s.begin(b.nodes.len());
    s.stack.push((0, 0));
    let mut tally = super::EffortTally(0);
    while let Some((i, j)) = s.stack.pop() {
        tally.0 += 1;
        let (na, nb) = (&a.nodes[i as usize], &b.nodes[j as usize]);
        let (oa, ob) = (&a.obbs[i as usize], &b.obbs[j as usize]);
        let least = floor.get();
        if least >= 0.0 && 2.0 * oa.radius.min(ob.radius) + margin <= least {
            continue;
        }
        if !obbs_meet(oa, s.obb(b, j, rel), margin) {
            continue;
        }
        match (na.count > 0, nb.count > 0) {
            (true, true) => {
                let leaf = s.leaf(b, j, rel);
                // b's triangles reaching a's leaf: box, then plane against a's box
                let mut cols = [0u32; LEAF_SIZE];
                let mut nc = 0;
                for c in leaf.first..leaf.first + leaf.count {
                    let m = &s.moved[c as usize];
                    if m.bx.overlap(&na.bounds).min() >= -margin
                        && Plane::through(&m.n, &m.t[0]).meets_obb(oa, margin)
                    {
                        cols[nc] = c;
                        nc += 1;
                    }
                }
                if nc == 0 {
                    continue;
                }
                let cols = &cols[..nc];
                let row_margin = margin + tilt_slack(shared, oa, ob);
                for ka in na.first..na.first + na.count {
                    let pa = a.plane(ka as usize);
                    if !pa.meets_obb(&leaf.obb, row_margin) {
                        continue;
                    }
                    let ta = a.tri(ka as usize);
                    let ba = tri_box(&ta);
                    if ba.overlap(&leaf.bx).min() < -margin {
                        continue;
                    }
                    for &c in cols {
                        let m = &s.moved[c as usize];
                        // cheap reject before the exact test
                        if ba.overlap(&m.bx).min() >= -margin {
                            let kb = nb.first + (c - leaf.first);
                            f(
                                Face {
                                    k: ka,
                                    t: &ta,
                                    n: &pa.normal,
                                },
                                Face {
                                    k: kb,
                                    t: &m.t,
                                    n: &m.n,
                                },
                            )?;
                        }
                    }
                }
            }
            (false, true) => {
                // A subtree of `a` on one side of every plane of `b`'s few triangles
                // cannot cross them (`tri_tri` rejects such pairs first): a small
                // part deep inside a large box never reaches the leaves.
                let leaf = s.leaf(b, j, rel);
                let moved = &s.moved[leaf.first as usize..(leaf.first + leaf.count) as usize];
                if moved
                    .iter()
                    .any(|m| Plane::through(&m.n, &m.t[0]).meets_obb(oa, margin))
                {
                    s.stack.extend([(na.first, j), (na.first + 1, j)]);
                }
            }
            (true, false) => {
                let moved_obb = *s.obb(b, j, rel);
                let row_margin = margin + tilt_slack(shared, oa, ob);
                if (na.first..na.first + na.count)
                    .any(|k| a.plane(k as usize).meets_obb(&moved_obb, row_margin))
                {
                    s.stack.extend([(i, nb.first), (i, nb.first + 1)]);
                }
            }
            (false, false) => {
                // The larger box is split; the child nearer the other box is walked
                // first (pushed last), so a crossing, when there is one, is found
                // sooner. The order changes no verdict: every pair that can meet is
                // visited unless the visitor breaks.
                if oa.radius >= ob.radius {
                    let other = s.obb(b, j, rel).centre;
                    let (l, r) = (na.first, na.first + 1);
                    let dl = (a.obbs[l as usize].centre - other).norm_squared();
                    let dr = (a.obbs[r as usize].centre - other).norm_squared();
                    if dl <= dr {
                        s.stack.extend([(r, j), (l, j)]);
                    } else {
                        s.stack.extend([(l, j), (r, j)]);
                    }
                } else {
                    let (l, r) = (nb.first, nb.first + 1);
                    let dl = (s.obb(b, l, rel).centre - oa.centre).norm_squared();
                    let dr = (s.obb(b, r, rel).centre - oa.centre).norm_squared();
                    if dl <= dr {
                        s.stack.extend([(i, r), (i, l)]);
                    } else {
                        s.stack.extend([(i, l), (i, r)]);
                    }
                }
            }
        }
    }
    ControlFlow::Continue(())
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
    interferes_by(a, pa, b, pb, tolerance, Some(Deadline::at(deadline)))
}

/// The deadline of a static pair walk, read every 256 triangle pairs (a clock read
/// per pair would cost more than the pair test).
struct PairClock {
    deadline: Option<Deadline>,
    visited: u32,
}

impl PairClock {
    fn new(deadline: Option<Deadline>) -> Self {
        Self {
            deadline,
            visited: 0,
        }
    }

    /// Whether the deadline has passed (a clock read): a bounded check whose
    /// deadline passed before it started gives up at once, however few pairs its
    /// walk would visit.
    fn expired(&self) -> bool {
        self.deadline.is_some_and(Deadline::passed)
    }

    /// Counts one pair; whether the deadline has passed (read on every 256th).
    fn passed(&mut self) -> bool {
        self.visited = self.visited.wrapping_add(1);
        self.visited.is_multiple_of(256) && self.deadline.is_some_and(Deadline::passed)
    }
}

/// What a pair query of `a` at `pa` and `b` at `pb` starts from, once the poses
/// and the tolerance are checked: `b`'s frame in `a`'s, the length below which
/// two points are one (mm), and whether both parts are solids.
fn prepare(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
) -> Result<(Relative, f64, bool), CollisionError> {
    check_pose(pa)?;
    check_pose(pb)?;
    check_tolerance(tolerance)?;
    Ok((
        Relative::new(pa, pb),
        eps(a, b, pa, pb),
        a.is_solid() && b.is_solid(),
    ))
}

/// [`interferes`]; `None`: `deadline` passed first.
fn interferes_by(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: Option<Deadline>,
) -> Result<Option<bool>, CollisionError> {
    let (rel, eps, oriented) = prepare(a, pa, b, pb, tolerance)?;
    let mut crossed = false;
    let mut seeds = Vec::new();
    // Open meshes: once some pair crosses, only a pair deeper than the tolerance can
    // change the answer. Solids: shallow crossings are seeds of the depth walk, so
    // every one is visited (the same pairs as `contact` visits before a deep one).
    let floor = Cell::new(-1.0);
    let mut clock = PairClock::new(deadline);
    if clock.expired() {
        return Ok(None);
    }
    let mut late = false;
    // Closed solids (watertight or stacked slices) also interfere where their faces
    // overlap in one plane facing the same way, with no pair crossing (an equal wall
    // pushed into an equal wall): the edge check's rule, containment.rs.
    let shared = a.encloses_volume() && b.encloses_volume();
    let margin = super::containment::walk_margin(shared, eps);
    let crossing = for_each_triangle_pair(a, b, &rel, margin, shared, &floor, |fa, fb| {
        if clock.passed() {
            late = true;
            return ControlFlow::Break(());
        }
        let depth = tri_tri_with(fa.t, fa.n, fb.t, fb.n, eps, oriented);
        if shared
            && depth.is_none_or(|d| d <= tolerance)
            && super::containment::shared_face_overlap_with(fa.t, fa.n, fb.t, fb.n) > tolerance
        {
            return ControlFlow::Break(());
        }
        match depth {
            Some(d) if d > tolerance => ControlFlow::Break(()),
            Some(d) => {
                if d > 0.0 {
                    crossed = true;
                    if oriented {
                        seeds.push((fa.k, fb.k));
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
    contact_by(a, pa, b, pb, tolerance, Some(Deadline::at(deadline)))
}

/// [`contact`]; `None`: `deadline` passed first.
fn contact_by(
    a: &Collider,
    pa: &Transform,
    b: &Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: Option<Deadline>,
) -> Result<Option<Contact>, CollisionError> {
    let (rel, eps, oriented) = prepare(a, pa, b, pb, tolerance)?;
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
    if clock.expired() {
        return Ok(None);
    }
    let walk = for_each_triangle_pair::<()>(a, b, &rel, margin, shared, &floor, |fa, fb| {
        if clock.passed() {
            return ControlFlow::Break(());
        }
        let crossing = tri_tri_with(fa.t, fa.n, fb.t, fb.n, eps, oriented);
        if shared && crossing.is_none_or(|d| d <= tolerance) {
            faces = faces.max(super::containment::shared_face_overlap_with(
                fa.t, fa.n, fb.t, fb.n,
            ));
        }
        if let Some(d) = crossing {
            touching = true;
            depth = depth.max(d);
            if oriented && d > 0.0 && d <= tolerance {
                seeds.push((fa.k, fb.k));
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
    // The nearest face of the point scored before bounds the next point's
    // nearest-point search from the start (`Collider::closest_from`, same answers):
    // the points of a triangle, and of its neighbours, lie beside each other.
    let mut last_near: Option<usize> = None;
    // A sample point's signed distance to `outer`'s surface: 0 on it, negative
    // outside; a point farther than `sure` and inside is a witness (`deepest`).
    let mut signed_depth = |p: &crate::math::Point3, deepest: &mut f64| -> f64 {
        let (d, near, on_surface) = outer.closest_from(p, 0.0, last_near);
        last_near = Some(near);
        if d <= eps {
            return 0.0;
        }
        let f = outer.tri(near);
        let n = (f[1] - f[0]).cross(&(f[2] - f[0])).normalize();
        let along = n.dot(&(p - on_surface));
        if d > sure {
            // Closest to a face's interior (offset along its normal) and in
            // front of it: outside for sure, no ray cast (most points of a
            // touching part). Otherwise ray parity decides.
            if along >= 0.999 * d {
                -d
            } else if outer.contains_point(p) {
                *deepest = deepest.max(d);
                d
            } else {
                -d
            }
        } else if along < 0.0 {
            d
        } else {
            -d
        }
    };
    // The signed depth of each edge midpoint scored, by the edge's two mesh
    // vertices: the two triangles sharing an edge share the point, to the bit
    // (the same corners, moved the same way, summed in either order).
    let mut at_edge: HashMap<u64, f64> = HashMap::new();
    let edge = |a: u32, b: u32| (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
    // signed depth of triangle k: the largest over its sample points of the
    // distance to `outer`'s surface, negative outside
    let mut score = |k: u32, deepest: &mut f64| -> f64 {
        if let Some(&s) = scores.get(&k) {
            return s;
        }
        let t = inner.tri(k as usize).map(|p| iso * p);
        let v = inner.corners(k as usize);
        let centre = nalgebra::center(&nalgebra::center(&t[0], &t[1]), &t[2]);
        let points = [
            (centre, None),
            (nalgebra::center(&t[0], &t[1]), Some(edge(v[0], v[1]))),
            (nalgebra::center(&t[1], &t[2]), Some(edge(v[1], v[2]))),
            (nalgebra::center(&t[2], &t[0]), Some(edge(v[2], v[0]))),
        ];
        let mut best = f64::NEG_INFINITY;
        for (p, key) in points {
            if let Some(&s) = key.and_then(|e| at_edge.get(&e)) {
                best = best.max(s);
                continue;
            }
            let signed = signed_depth(&p, deepest);
            if let Some(e) = key {
                at_edge.insert(e, signed);
            }
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

#[cfg(test)]
mod tests;
