//! How much two interfering solids overlap: the **intersection volume** (what
//! SolidWorks' interference detection reports as the interference volume) and the
//! **separation**, the shortest straight translation that takes one part out of the
//! other (the depth a user means: a screw pushed 5 mm into a table reads 5 mm,
//! whatever the facets of its tip).
//!
//! Both are exact for the polyhedra the meshes bound (closed, consistently oriented
//! meshes; [`VolumeError::NotSolid`] otherwise), in the world frame, mm.
//!
//! **Volume.** Each closed mesh's indicator is a signed sum of vertical prisms, one
//! under each triangle (+ under a face looking up, − under one looking down). The
//! volume of `A ∩ B` is then the sum over pairs of triangles (one of each) whose
//! footprints overlap of `±∫ min(z_a, z_b)` over the common footprint: a convex
//! polygon split by the line where the two planes cross, integrated in closed form.
//! Only the footprints inside the parts' common box count, and only triangles whose
//! footprint meets it are visited (a grid over the box).
//!
//! **Separation.** For a direction `d`, the part `A` is pulled out along `d` until it
//! last touches `B`: the largest `t ≥ 0` at which `A + t·d` still meets `B`, found
//! exactly from its three kinds of events (a vertex of `A` crossing a face of `B`, a
//! vertex of `B` crossing a face of `A`, an edge crossing an edge). The separation is
//! the smallest such pull over directions: the face normals of both parts near the
//! overlap (exact for a flat face pushed into anything), 162 directions spread over
//! the sphere, then a local refinement of the best ones. A part inside a cavity of
//! the other is measured as pulled out of the whole other part, not into the cavity.

use super::node::Node;
use super::shape::Collider;
use super::triangle::{ray_box, ray_triangle};
use crate::math::{Aabb, Deadline, Point3, Transform, Vec3};

/// Why an overlap cannot be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum VolumeError {
    /// A mesh does not bound a solid (holes, non-manifold or misoriented edges).
    #[error(
        "the {0} part's mesh is not a closed solid: an overlap volume or depth is undefined for it"
    )]
    NotSolid(&'static str),
    /// A pose with NaN or infinite entries.
    #[error("a pose is not finite")]
    BadPose,
    /// The call's time budget ran out (ms).
    #[error("measuring the overlap ran out of its time limit of {0} ms; give it a larger `time_limit_ms`")]
    TimeLimit(f64),
}

/// Default time budget of [`intersection_volume`] and [`separation`], ms.
pub const DEFAULT_OVERLAP_TIME_LIMIT_MS: f64 = 10_000.0;

/// The separating translation of two interfering parts ([`separation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Separation {
    /// How far `A` must move along `direction` to be clear of `B` (mm); 0 when the
    /// parts only touch or are apart.
    pub distance: f64,
    /// The unit direction (world) in which `A` moves out; `B` moves out along its
    /// negation.
    pub direction: Vec3,
}

struct Clock {
    deadline: Option<Deadline>,
    limit_ms: f64,
    ticks: u32,
}

impl Clock {
    fn new(limit_ms: f64) -> Self {
        let deadline =
            (limit_ms.is_finite() && limit_ms >= 0.0).then(|| Deadline::after_ms(limit_ms));
        Clock {
            deadline,
            limit_ms,
            ticks: 0,
        }
    }

    #[inline]
    fn tick(&mut self) -> Result<(), VolumeError> {
        self.ticks = self.ticks.wrapping_add(1);
        if self.ticks.is_multiple_of(1024) && self.deadline.is_some_and(Deadline::passed) {
            return Err(VolumeError::TimeLimit(self.limit_ms));
        }
        Ok(())
    }
}

fn check_inputs(
    a: &Collider,
    pose_a: &Transform,
    b: &Collider,
    pose_b: &Transform,
) -> Result<(), VolumeError> {
    if !pose_a.is_finite() || !pose_b.is_finite() {
        return Err(VolumeError::BadPose);
    }
    if !a.is_solid() {
        return Err(VolumeError::NotSolid("first"));
    }
    if !b.is_solid() {
        return Err(VolumeError::NotSolid("second"));
    }
    Ok(())
}

/// The world triangles of a posed collider, relative to `origin`.
fn world_tris(c: &Collider, pose: &Transform, origin: &Point3) -> Vec<[Point3; 3]> {
    let mesh = c.mesh();
    (0..mesh.triangles.len())
        .map(|i| {
            mesh.triangle(i)
                .map(|p| Point3::from(pose.apply(&p) - origin.coords))
        })
        .collect()
}

/// The volume of the intersection of two posed solids, mm³ (0 when they only touch
/// or are apart). `time_limit_ms` bounds the call.
///
/// # Examples
/// ```
/// use fitup::collision::{intersection_volume, Collider};
/// use fitup::math::{Point3, Transform, Vec3};
/// use fitup::mesh::Mesh;
/// use std::sync::Arc;
///
/// let cube = Arc::new(Mesh::cuboid(Point3::origin(), Point3::new(10.0, 10.0, 10.0)));
/// let c = Collider::new(cube)?;
/// let moved = Transform::from_translation(Vec3::new(4.0, 3.0, 0.0));
/// let v = intersection_volume(&c, &Transform::default(), &c, &moved, 10_000.0)?;
/// assert!((v - 6.0 * 7.0 * 10.0).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn intersection_volume(
    a: &Collider,
    pose_a: &Transform,
    b: &Collider,
    pose_b: &Transform,
    time_limit_ms: f64,
) -> Result<f64, VolumeError> {
    check_inputs(a, pose_a, b, pose_b)?;
    let mut clock = Clock::new(time_limit_ms);
    let (ba, bb) = (a.world_bounds(pose_a), b.world_bounds(pose_b));
    let lo = ba.lo.sup(&bb.lo);
    let hi = ba.hi.inf(&bb.hi);
    if (0..3).any(|k| lo[k] >= hi[k]) {
        return Ok(0.0);
    }
    let origin = nalgebra::center(&lo, &hi);
    let rect = [
        lo.x - origin.x,
        lo.y - origin.y,
        hi.x - origin.x,
        hi.y - origin.y,
    ];
    let prisms = |c: &Collider, pose: &Transform| -> Vec<Prism> {
        world_tris(c, pose, &origin)
            .iter()
            .filter_map(Prism::new)
            .filter(|p| {
                p.lo[0] < rect[2] && p.hi[0] > rect[0] && p.lo[1] < rect[3] && p.hi[1] > rect[1]
            })
            .collect()
    };
    let pa = prisms(a, pose_a);
    let pb = prisms(b, pose_b);
    if pa.is_empty() || pb.is_empty() {
        return Ok(0.0);
    }
    // A grid over the box's footprint holding B's prisms.
    let n = ((pb.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
    let (w, h) = (
        (rect[2] - rect[0]) / n as f64,
        (rect[3] - rect[1]) / n as f64,
    );
    let cell = |x: f64, wdt: f64, lo: f64| (((x - lo) / wdt).floor().max(0.0) as usize).min(n - 1);
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); n * n];
    for (k, p) in pb.iter().enumerate() {
        for i in cell(p.lo[0], w, rect[0])..=cell(p.hi[0], w, rect[0]) {
            for j in cell(p.lo[1], h, rect[1])..=cell(p.hi[1], h, rect[1]) {
                grid[i * n + j].push(k as u32);
            }
        }
    }
    let clip_rect = [
        ([1.0, 0.0], -rect[0]),
        ([-1.0, 0.0], rect[2]),
        ([0.0, 1.0], -rect[1]),
        ([0.0, -1.0], rect[3]),
    ];
    let mut seen = vec![u32::MAX; pb.len()];
    let (mut poly, mut tmp) = (Vec::with_capacity(16), Vec::with_capacity(16));
    let mut total = 0.0;
    for (ka, p) in pa.iter().enumerate() {
        for i in cell(p.lo[0], w, rect[0])..=cell(p.hi[0], w, rect[0]) {
            for j in cell(p.lo[1], h, rect[1])..=cell(p.hi[1], h, rect[1]) {
                for &kb in &grid[i * n + j] {
                    if seen[kb as usize] == ka as u32 {
                        continue;
                    }
                    seen[kb as usize] = ka as u32;
                    clock.tick()?;
                    let q = &pb[kb as usize];
                    if q.lo[0] >= p.hi[0]
                        || q.hi[0] <= p.lo[0]
                        || q.lo[1] >= p.hi[1]
                        || q.hi[1] <= p.lo[1]
                    {
                        continue;
                    }
                    poly.clear();
                    poly.extend_from_slice(&p.corners);
                    for e in q.edges().into_iter().chain(clip_rect) {
                        clip(&poly, e, &mut tmp);
                        std::mem::swap(&mut poly, &mut tmp);
                        if poly.len() < 3 {
                            break;
                        }
                    }
                    if poly.len() < 3 {
                        continue;
                    }
                    // Where z_a ≤ z_b the column's top is A's face, else B's.
                    let d = [p.plane[0] - q.plane[0], p.plane[1] - q.plane[1]];
                    let dc = p.plane[2] - q.plane[2];
                    clip(&poly, ([-d[0], -d[1]], -dc), &mut tmp);
                    let under_a = integrate(&tmp, p);
                    clip_with(&poly, (d, dc), true, &mut tmp);
                    let under_b = integrate(&tmp, q);
                    total += p.sign * q.sign * (under_a + under_b);
                }
            }
        }
    }
    // Shift the integrals' reference from z = 0 (the box centre) out: the signed
    // footprints cancel, so the sum is the volume; round-off is all that goes below 0.
    Ok(total.max(0.0))
}

/// A triangle's footprint on the XY plane (counter-clockwise), the plane it lies in
/// as `z = αx + βy + γ`, its z range and the sign of its prism.
struct Prism {
    corners: [[f64; 2]; 3],
    plane: [f64; 3],
    zr: [f64; 2],
    sign: f64,
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Prism {
    fn new(t: &[Point3; 3]) -> Option<Prism> {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        // A footprint of no area bounds no prism.
        if n.z.abs().partial_cmp(&(1e-14 * n.norm())) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let mut corners = [[t[0].x, t[0].y], [t[1].x, t[1].y], [t[2].x, t[2].y]];
        if n.z < 0.0 {
            corners.swap(1, 2);
        }
        let (alpha, beta) = (-n.x / n.z, -n.y / n.z);
        let gamma = t[0].z - alpha * t[0].x - beta * t[0].y;
        Some(Prism {
            corners,
            plane: [alpha, beta, gamma],
            zr: [
                t[0].z.min(t[1].z).min(t[2].z),
                t[0].z.max(t[1].z).max(t[2].z),
            ],
            sign: n.z.signum(),
            lo: [
                t[0].x.min(t[1].x).min(t[2].x),
                t[0].y.min(t[1].y).min(t[2].y),
            ],
            hi: [
                t[0].x.max(t[1].x).max(t[2].x),
                t[0].y.max(t[1].y).max(t[2].y),
            ],
        })
    }

    /// The footprint's edges as inner half-planes `n·p + c ≥ 0`.
    fn edges(&self) -> [([f64; 2], f64); 3] {
        let c = &self.corners;
        [0, 1, 2].map(|k| {
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let n = [-(q[1] - p[1]), q[0] - p[0]];
            (n, -(n[0] * p[0] + n[1] * p[1]))
        })
    }

    fn z(&self, x: f64, y: f64) -> f64 {
        (self.plane[0] * x + self.plane[1] * y + self.plane[2]).clamp(self.zr[0], self.zr[1])
    }
}

/// Sutherland–Hodgman: the part of convex `poly` where `n·p + c ≥ 0`.
fn clip(poly: &[[f64; 2]], half: ([f64; 2], f64), out: &mut Vec<[f64; 2]>) {
    clip_with(poly, half, false, out)
}

/// [`clip`], keeping only `n·p + c > 0` when `strict`: the two sides of a split get
/// the points on the line once, so a plane that equals the other everywhere
/// (coplanar faces) is counted on one side only.
fn clip_with(poly: &[[f64; 2]], (n, c): ([f64; 2], f64), strict: bool, out: &mut Vec<[f64; 2]>) {
    out.clear();
    let m = poly.len();
    let inside = |s: f64| if strict { s > 0.0 } else { s >= 0.0 };
    for k in 0..m {
        let (p, q) = (poly[k], poly[(k + 1) % m]);
        let (sp, sq) = (n[0] * p[0] + n[1] * p[1] + c, n[0] * q[0] + n[1] * q[1] + c);
        if inside(sp) {
            out.push(p);
        }
        if inside(sp) != inside(sq) {
            let s = sp / (sp - sq);
            out.push([p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])]);
        }
    }
}

/// ∫ z over the polygon (area times z at its centroid).
fn integrate(poly: &[[f64; 2]], plane: &Prism) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    let o = poly[0];
    for k in 1..poly.len() - 1 {
        let (p, q) = (
            [poly[k][0] - o[0], poly[k][1] - o[1]],
            [poly[k + 1][0] - o[0], poly[k + 1][1] - o[1]],
        );
        let cr = p[0] * q[1] - p[1] * q[0];
        a2 += cr;
        cx += cr * (p[0] + q[0]);
        cy += cr * (p[1] + q[1]);
    }
    if a2 <= 0.0 {
        return 0.0;
    }
    let (x, y) = (o[0] + cx / (3.0 * a2), o[1] + cy / (3.0 * a2));
    0.5 * a2 * plane.z(x, y)
}

/// Options of [`separation`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeparationOptions {
    /// Time budget, ms (default [`DEFAULT_OVERLAP_TIME_LIMIT_MS`]).
    pub time_limit_ms: f64,
}

impl Default for SeparationOptions {
    fn default() -> Self {
        SeparationOptions {
            time_limit_ms: DEFAULT_OVERLAP_TIME_LIMIT_MS,
        }
    }
}

/// One part, posed, for the pull-out queries: its collider and the map from world to
/// its frame.
struct Side<'a> {
    c: &'a Collider,
    pose: Transform,
    inv: Transform,
    /// Vertices in world coordinates (unique).
    verts: Vec<Point3>,
    /// Unique edges, world.
    edges: Vec<[Point3; 2]>,
}

impl<'a> Side<'a> {
    fn new(c: &'a Collider, pose: &Transform) -> Self {
        let mesh = c.mesh();
        let verts = mesh.vertices.iter().map(|p| pose.apply(p)).collect();
        let mut keys: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [0, 1, 2].map(|k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
            .filter(|(a, b)| a != b)
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let edges = keys
            .iter()
            .map(|&(a, b)| {
                [
                    pose.apply(&mesh.vertices[a as usize]),
                    pose.apply(&mesh.vertices[b as usize]),
                ]
            })
            .collect();
        Side {
            c,
            pose: *pose,
            inv: pose.inverse(),
            verts,
            edges,
        }
    }

    /// The largest `t ≥ 0` at which the world ray `p + t·d` crosses this part's
    /// surface; `None` when it never does.
    fn last_hit(
        &self,
        p: &Point3,
        d: &Vec3,
        clock: &mut Clock,
    ) -> Result<Option<f64>, VolumeError> {
        let o = self.inv.apply(p);
        let dir = self.inv.apply_vector(d);
        let mut best: Option<f64> = None;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            clock.tick()?;
            let node: &Node = &self.c.nodes[i as usize];
            let Some((_, t1)) = ray_box(&o, &dir, &node.bounds) else {
                continue;
            };
            if best.is_some_and(|b| t1 <= b) {
                continue;
            }
            if node.count > 0 {
                for t in self.c.leaf_tris(node) {
                    if let Some(s) = ray_triangle(&o, &dir, &t) {
                        if s >= 0.0 && best.is_none_or(|b| s > b) {
                            best = Some(s);
                        }
                    }
                }
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
        Ok(best)
    }

    /// The largest `t ≥ 0` at which the world segment `e + t·d` crosses an edge of
    /// this part.
    fn last_edge_hit(
        &self,
        e: &[Point3; 2],
        d: &Vec3,
        reach: f64,
        clock: &mut Clock,
    ) -> Result<Option<f64>, VolumeError> {
        let (p0, p1) = (self.inv.apply(&e[0]), self.inv.apply(&e[1]));
        let dir = self.inv.apply_vector(d);
        let mut sweep = Aabb::around(&[p0, p1]);
        sweep = sweep.union(&Aabb::around(&[p0 + dir * reach, p1 + dir * reach]));
        let mut best: Option<f64> = None;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            clock.tick()?;
            let node: &Node = &self.c.nodes[i as usize];
            if !boxes_meet(&node.bounds, &sweep) {
                continue;
            }
            if node.count > 0 {
                for t in self.c.leaf_tris(node) {
                    for k in 0..3 {
                        if let Some(s) = segment_sweep(&p0, &p1, &dir, &t[k], &t[(k + 1) % 3]) {
                            if s >= 0.0 && best.is_none_or(|b| s > b) {
                                best = Some(s);
                            }
                        }
                    }
                }
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
        Ok(best)
    }
}

fn boxes_meet(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k])
}

/// The `t` at which the segment `p0 p1` moved by `t·d` crosses the segment `q0 q1`;
/// `None` when it never does or the segments are parallel to the motion's plane.
fn segment_sweep(p0: &Point3, p1: &Point3, d: &Vec3, q0: &Point3, q1: &Point3) -> Option<f64> {
    // p0 + u (p1 − p0) + t d = q0 + v (q1 − q0)
    let (a, b) = (p1 - p0, q1 - q0);
    let m = nalgebra::Matrix3::from_columns(&[a, -b, *d]);
    let det = m.determinant();
    let scale = a.norm() * b.norm() * d.norm();
    if det.abs() <= 1e-12 * scale {
        return None;
    }
    let x = m.try_inverse()? * (q0 - p0);
    let eps = 1e-12;
    ((-eps..=1.0 + eps).contains(&x[0]) && (-eps..=1.0 + eps).contains(&x[1])).then_some(x[2])
}

/// How far `a` must be pulled along the unit world direction `d` to be clear of `b`
/// (the last contact coming back from far away). Stops early, returning `None`, as
/// soon as the answer is known to be at least `stop`.
fn pull_out(
    a: &Side,
    b: &Side,
    d: &Vec3,
    stop: f64,
    clock: &mut Clock,
) -> Result<Option<f64>, VolumeError> {
    let mut worst = 0.0f64;
    let over = |t: f64| t >= stop;
    // vertices of A meeting B's faces, then B's vertices meeting A's faces (A moves
    // along d = B moves along −d)
    for v in &a.verts {
        if let Some(t) = b.last_hit(v, d, clock)? {
            if over(t) {
                return Ok(None);
            }
            worst = worst.max(t);
        }
    }
    let back = -d;
    for v in &b.verts {
        if let Some(t) = a.last_hit(v, &back, clock)? {
            if over(t) {
                return Ok(None);
            }
            worst = worst.max(t);
        }
    }
    // edges crossing edges; a pull beyond both boxes' extents cannot meet anything
    let ab = a.c.world_bounds(&a.pose);
    let bb = b.c.world_bounds(&b.pose);
    let reach =
        (ab.hi - ab.lo).norm() + (bb.hi - bb.lo).norm() + (ab.centre() - bb.centre()).norm();
    for e in &a.edges {
        if let Some(t) = b.last_edge_hit(e, d, reach, clock)? {
            if over(t) {
                return Ok(None);
            }
            worst = worst.max(t);
        }
    }
    Ok(Some(worst))
}

/// Unit directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The shortest straight translation of `a` that separates it from `b` (both posed,
/// world, mm): see the module docs for the method. Parts that touch or are apart
/// give distance 0.
///
/// # Examples
/// A pin pushed 5 mm into a plate reads 5 mm, up:
/// ```
/// use fitup::collision::{separation, Collider, SeparationOptions};
/// use fitup::math::{Point3, Transform, Vec3};
/// use fitup::mesh::Mesh;
/// use std::sync::Arc;
///
/// let plate = Collider::new(Arc::new(Mesh::cuboid(Point3::new(-50.0, -50.0, -20.0), Point3::new(50.0, 50.0, 0.0))))?;
/// let pin = Collider::new(Arc::new(Mesh::cylinder(3.0, 30.0, 64)))?;
/// let pushed = Transform::from_translation(Vec3::new(0.0, 0.0, -5.0));
/// let s = separation(&pin, &pushed, &plate, &Transform::default(), &SeparationOptions::default())?;
/// assert!((s.distance - 5.0).abs() < 1e-9);
/// assert!((s.direction - Vec3::z()).norm() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn separation(
    a: &Collider,
    pose_a: &Transform,
    b: &Collider,
    pose_b: &Transform,
    options: &SeparationOptions,
) -> Result<Separation, VolumeError> {
    check_inputs(a, pose_a, b, pose_b)?;
    let mut clock = Clock::new(options.time_limit_ms);
    let none = Separation {
        distance: 0.0,
        direction: Vec3::z(),
    };
    let (ba, bb) = (a.world_bounds(pose_a), b.world_bounds(pose_b));
    if !boxes_meet(&ba, &bb) {
        return Ok(none);
    }
    let sa = Side::new(a, pose_a);
    let sb = Side::new(b, pose_b);
    // Candidates: B's outward normals and A's inward ones where the boxes overlap
    // (a flat face pushed in comes out along its normal), then the sphere.
    let lo = ba.lo.sup(&bb.lo);
    let hi = ba.hi.inf(&bb.hi);
    let inside = |p: &Point3| (0..3).all(|k| p[k] >= lo[k] - 1e-9 && p[k] <= hi[k] + 1e-9);
    let mut cands: Vec<Vec3> = Vec::new();
    let mut keys = std::collections::HashSet::new();
    let mut push = |n: Vec3, cands: &mut Vec<Vec3>| {
        if let Some(n) = n.try_normalize(1e-300) {
            let key = (n * 1e6).map(|v| v.round() as i64);
            if keys.insert((key.x, key.y, key.z)) {
                cands.push(n);
            }
        }
    };
    for (side, sign) in [(&sb, 1.0), (&sa, -1.0)] {
        let mesh = side.c.mesh();
        for i in 0..mesh.triangles.len() {
            let t = mesh.triangle(i).map(|p| side.pose.apply(&p));
            if t.iter().any(&inside) {
                push((t[1] - t[0]).cross(&(t[2] - t[0])) * sign, &mut cands);
            }
        }
    }
    // Many faces (a fine curved mesh): keep an even subset; the sphere and the
    // refinement cover the rest.
    if cands.len() > 600 {
        let step = cands.len() as f64 / 600.0;
        cands = (0..600)
            .map(|k| cands[(k as f64 * step) as usize])
            .collect();
    }
    for d in sphere_directions(162) {
        push(d, &mut cands);
    }
    let mut best = none;
    best.distance = f64::INFINITY;
    let mut scored: Vec<(f64, Vec3)> = Vec::new();
    for d in &cands {
        if let Some(t) = pull_out(&sa, &sb, d, best.distance, &mut clock)? {
            scored.push((t, *d));
            if t < best.distance {
                best = Separation {
                    distance: t,
                    direction: *d,
                };
            }
            if t == 0.0 {
                return Ok(none_with(*d));
            }
        }
    }
    // Refine the best few by a pattern search on the sphere.
    scored.sort_by(|x, y| x.0.total_cmp(&y.0));
    for &(t0, d0) in scored.iter().take(3) {
        let (mut t, mut d) = (t0, d0);
        let mut step = 0.05;
        while step > 1e-5 {
            let (u, v) = crate::math::frame_across(&d);
            let mut improved = false;
            for (du, dv) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
                let n = (d + (u * du + v * dv) * step).normalize();
                if let Some(tn) = pull_out(&sa, &sb, &n, t, &mut clock)? {
                    if tn < t {
                        t = tn;
                        d = n;
                        improved = true;
                    }
                }
            }
            if !improved {
                step *= 0.5;
            }
        }
        if t < best.distance {
            best = Separation {
                distance: t,
                direction: d,
            };
        }
    }
    if !best.distance.is_finite() {
        // every direction met something farther than the first finite pull: cannot
        // happen for finite parts, kept as a guard
        return Ok(none);
    }
    Ok(best)
}

fn none_with(d: Vec3) -> Separation {
    Separation {
        distance: 0.0,
        direction: d,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use std::sync::Arc;

    fn col(m: Mesh) -> Collider {
        Collider::new(Arc::new(m)).unwrap()
    }

    fn at(x: f64, y: f64, z: f64) -> Transform {
        Transform::from_translation(Vec3::new(x, y, z))
    }

    const T: f64 = 60_000.0;

    #[test]
    fn boxes_overlap_by_their_common_box() {
        let c = col(Mesh::cuboid(
            Point3::origin(),
            Point3::new(10.0, 10.0, 10.0),
        ));
        let id = Transform::default();
        for (x, y, z) in [
            (4.0, 3.0, 0.0),
            (-2.5, 1.0, 7.0),
            (0.0, 0.0, 0.0),
            (9.0, 9.0, 9.0),
        ] {
            let v = intersection_volume(&c, &id, &c, &at(x, y, z), T).unwrap();
            let want = (10.0 - f64::abs(x)) * (10.0 - f64::abs(y)) * (10.0 - f64::abs(z));
            assert!(
                (v - want).abs() < 1e-9 * 1000.0,
                "{x} {y} {z}: {v} vs {want}"
            );
        }
        // a box standing on another, off the origin (coplanar faces): nothing
        let low = col(Mesh::cuboid(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(10.0, 10.0, 3.0),
        ));
        let v = intersection_volume(&low, &at(5.0, 5.0, 40.0), &c, &at(0.0, 0.0, 43.0), T).unwrap();
        assert_eq!(v, 0.0);
        let v = intersection_volume(&low, &at(5.0, 5.0, 41.0), &c, &at(0.0, 0.0, 43.0), T).unwrap();
        assert!((v - 25.0).abs() < 1e-9, "{v}");
        // touching faces and apart: nothing
        assert_eq!(
            intersection_volume(&c, &id, &c, &at(10.0, 0.0, 0.0), T).unwrap(),
            0.0
        );
        assert_eq!(
            intersection_volume(&c, &id, &c, &at(30.0, 0.0, 0.0), T).unwrap(),
            0.0
        );
    }

    #[test]
    fn a_solid_inside_another_is_its_own_volume() {
        let ball = Mesh::uv_sphere(4.0, 48);
        let vol = ball.signed_volume();
        let b = col(ball);
        let big = col(Mesh::cuboid(
            Point3::new(-20.0, -20.0, -20.0),
            Point3::new(20.0, 20.0, 20.0),
        ));
        let id = Transform::default();
        let v = intersection_volume(&b, &at(3.0, -2.0, 1.0), &big, &id, T).unwrap();
        assert!((v - vol).abs() < 1e-9 * vol, "{v} vs {vol}");
        // and with itself, every face coplanar with its twin
        let v = intersection_volume(&b, &id, &b, &id, T).unwrap();
        assert!((v - vol).abs() < 1e-9 * vol, "{v} vs {vol}");
        // a rotated copy of a box inside a box: the small box's volume
        let small = col(Mesh::cuboid(
            Point3::new(-3.0, -2.0, -1.0),
            Point3::new(3.0, 2.0, 1.0),
        ));
        let r = Transform::from_rotation_about(Point3::origin(), Vec3::new(1.0, 1.0, 0.3), 0.8)
            .unwrap();
        let v = intersection_volume(&small, &r, &big, &id, T).unwrap();
        assert!((v - 48.0).abs() < 1e-9 * 48.0, "{v}");
    }

    #[test]
    fn a_pin_pushed_into_a_plate() {
        let plate = col(Mesh::cuboid(
            Point3::new(-50.0, -50.0, -20.0),
            Point3::new(50.0, 50.0, 0.0),
        ));
        let n = 64;
        let pin = col(Mesh::cylinder(3.0, 30.0, n));
        let area = n as f64 * 9.0 * (std::f64::consts::TAU / n as f64).sin() / 2.0;
        let id = Transform::default();
        let tilt = Transform::from_rotation_about(Point3::origin(), Vec3::new(1.0, 0.0, 0.0), 0.3)
            .unwrap();
        let v = intersection_volume(&pin, &at(0.0, 0.0, -5.0), &plate, &id, T).unwrap();
        assert!((v - 5.0 * area).abs() < 1e-9 * v, "{v}");
        let s = separation(
            &pin,
            &at(0.0, 0.0, -5.0),
            &plate,
            &id,
            &SeparationOptions::default(),
        )
        .unwrap();
        assert!((s.distance - 5.0).abs() < 1e-9, "{s:?}");
        assert!((s.direction - Vec3::z()).norm() < 1e-9);
        // B's view: the plate comes out downwards by the same 5 mm
        let s = separation(
            &plate,
            &id,
            &pin,
            &at(0.0, 0.0, -5.0),
            &SeparationOptions::default(),
        )
        .unwrap();
        assert!((s.distance - 5.0).abs() < 1e-9 && (s.direction + Vec3::z()).norm() < 1e-9);
        // tilted, the deepest rim point decides: out along the plate's normal
        let pose = tilt.then(&at(0.0, 0.0, -5.0));
        let s = separation(&pin, &pose, &plate, &id, &SeparationOptions::default()).unwrap();
        let deepest = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                -pose
                    .apply(&Point3::new(3.0 * a.cos(), 3.0 * a.sin(), 0.0))
                    .z
            })
            .fold(0.0, f64::max);
        assert!(
            (s.distance - deepest).abs() < 1e-6,
            "{} vs {deepest}",
            s.distance
        );
        // resting on it: nothing to separate
        let s = separation(&pin, &id, &plate, &id, &SeparationOptions::default()).unwrap();
        assert_eq!(s.distance, 0.0);
    }

    #[test]
    fn crossed_bars_need_the_edge_events() {
        // a bar with a sharp bottom edge (a box rotated 45° about X) dipping 1 mm into
        // a block narrower than it: no vertex of either lies in the other
        let block = col(Mesh::cuboid(
            Point3::new(-5.0, -5.0, -10.0),
            Point3::new(5.0, 5.0, 0.0),
        ));
        let bar = col(Mesh::cuboid(
            Point3::new(-20.0, -2.0, -2.0),
            Point3::new(20.0, 2.0, 2.0),
        ));
        let pose = Transform::from_rotation_about(
            Point3::origin(),
            Vec3::x(),
            std::f64::consts::FRAC_PI_4,
        )
        .unwrap()
        .then(&at(0.0, 0.0, 8f64.sqrt() - 1.0));
        let s = separation(
            &bar,
            &pose,
            &block,
            &Transform::default(),
            &SeparationOptions::default(),
        )
        .unwrap();
        assert!((s.distance - 1.0).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn refusals() {
        let mut open = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        open.triangles.pop();
        let o = col(open);
        let c = col(Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0)));
        let id = Transform::default();
        assert_eq!(
            intersection_volume(&o, &id, &c, &id, T),
            Err(VolumeError::NotSolid("first"))
        );
        assert_eq!(
            separation(&c, &id, &o, &id, &SeparationOptions::default()),
            Err(VolumeError::NotSolid("second"))
        );
    }
}
