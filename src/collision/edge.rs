//! Continuous interference along one straight SE(3) edge — translation by lerp,
//! rotation by slerp, as every planner's edge — in a single traversal of the two
//! trees.
//!
//! The moving part's node boxes are swept over the whole edge (grown along the
//! translation and by the arc its points can travel), so node pairs that cannot meet
//! anywhere on the edge are dropped at once: a peg sliding along the axis of a tight
//! hole keeps its thin facet boxes thin and is cleared in microseconds. Triangle pairs
//! that can meet get their own conservative advancement, so the work goes where the
//! parts are close, not into the whole part.

use super::containment::coplanar_overlap;
use super::exact::{check_pose, check_tolerance, eps, obb_size, tri_box};
use super::node::Obb;
use super::relative::Relative;
use super::shape::Collider;
use super::triangle::{reach_into_swept, tri_distance, tri_tri, unit_normal, Tri};
use super::{CollisionError, MotionFault};
use crate::math::{Deadline, Transform, Vec3};
use nalgebra::Isometry3;

/// Options of [`edge_interferes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeOptions {
    /// Penetration tolerance (mm, ≥ 0): surfaces crossing no deeper count as touching.
    pub tolerance: f64,
    /// While two triangles touch (within the [`contact_gap`](super::contact_gap)),
    /// the largest displacement of the moving one between two crossing checks (mm, more
    /// than 0; raised to half the tolerance by [`contact_step`](super::contact_step)),
    /// and never more than the room left between the pair's crossing depth and the
    /// tolerance (at least 0.0005 mm), so a crossing deeper than the tolerance is not
    /// stepped over. Default
    /// [`SweepMethod::DEFAULT_CONTACT_STEP_MM`](super::SweepMethod::DEFAULT_CONTACT_STEP_MM).
    pub contact_step: f64,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        Self {
            tolerance: super::DEFAULT_TOLERANCE,
            contact_step: super::SweepMethod::DEFAULT_CONTACT_STEP_MM,
        }
    }
}

/// Largest rotation of one edge, rad: beyond it slerp's path is ill-defined.
pub(super) const MAX_EDGE_ANGLE: f64 = 3.0;

/// Most advancement steps of one triangle pair (beyond: reported interfering).
const MAX_PAIR_STEPS: usize = 1_000_000;

/// Where the moving part is along the edge, in the obstacle's frame.
struct EdgeFrames {
    /// World → obstacle frame.
    obstacle_inv: Isometry3<f64>,
    from: Transform,
    to: Transform,
    /// Length of the part origin's translation over the edge, mm.
    shift: f64,
    /// That translation in the obstacle frame, mm.
    shift_local: Vec3,
    /// Rotation over the edge, rad.
    angle: f64,
    /// The unit axis of that rotation in the moving part's frame (slerp turns
    /// about one axis through the part origin), zero for a translation.
    axis: Vec3,
    /// That whole rotation, in the moving part's frame.
    turn: nalgebra::Matrix3<f64>,
}

impl EdgeFrames {
    /// The edge `from → to` of the moving part against an obstacle at `pose`.
    fn new(from: &Transform, to: &Transform, pose: &Transform) -> Self {
        let (angle, shift) = from.distance_to(to);
        let obstacle_inv = pose.isometry().inverse();
        let turn = from.rotation().inverse() * to.rotation();
        Self {
            obstacle_inv,
            from: *from,
            to: *to,
            shift,
            shift_local: obstacle_inv.rotation * (to.translation() - from.translation()),
            angle,
            axis: turn.axis().map_or_else(Vec3::zeros, |k| k.into_inner()),
            turn: turn.to_rotation_matrix().into_inner(),
        }
    }

    /// Moving part frame → obstacle frame at edge parameter `t`.
    fn at(&self, t: f64) -> Isometry3<f64> {
        self.obstacle_inv * self.from.interpolate(&self.to, t).isometry()
    }

    /// Largest displacement over the whole edge of a point `rho` mm from the
    /// rotation axis, mm.
    fn reach(&self, rho: f64) -> f64 {
        self.shift + self.angle * rho
    }

    /// The distance of part-frame point `p` from the rotation axis, mm: a point
    /// moves by at most `angle` times it, on an arc in a plane normal to the axis.
    fn arm(&self, p: &Vec3) -> f64 {
        (p - self.axis * self.axis.dot(p)).norm()
    }
}

/// Whether `moving`, carried from `from` to `to` (part frame → world; translation
/// lerp, rotation slerp about the part origin), interferes with `obstacle` at
/// `pose` anywhere after `from`: some pair of triangles crosses deeper than the
/// tolerance, or (both meshes bounding volumes, a translation) faces of the two
/// lying in one plane and facing the same way overlap wider than the tolerance —
/// the two solids then share the material behind them though no pair crosses (a
/// wall pushed into an equal wall). `from` is taken as free; containment without
/// any contact is not tested here — a solid can only get inside another through
/// its surface, and the caller checks `to` with [`interferes`](super::interferes).
///
/// Edges turning by more than 3 rad are refused as interfering (split them).
///
/// # Errors
/// Non-finite poses, a bad tolerance or contact step.
pub fn edge_interferes(
    moving: &Collider,
    from: &Transform,
    to: &Transform,
    obstacle: &Collider,
    pose: &Transform,
    options: &EdgeOptions,
) -> Result<bool, CollisionError> {
    edge_check(moving, from, to, obstacle, pose, options, None).map(|hit| hit.unwrap_or(true))
}

/// [`edge_interferes`] that gives up at `deadline`: `Ok(None)` when it passed before
/// the answer was known. The clock is read between node pairs of the traversal and
/// before each triangle pair's advancement, so a call returns within about one
/// triangle pair's walk after the deadline, however many pairs the edge meets.
///
/// # Errors
/// As [`edge_interferes`].
pub fn edge_interferes_until(
    moving: &Collider,
    from: &Transform,
    to: &Transform,
    obstacle: &Collider,
    pose: &Transform,
    options: &EdgeOptions,
    deadline: std::time::Instant,
) -> Result<Option<bool>, CollisionError> {
    edge_check(
        moving,
        from,
        to,
        obstacle,
        pose,
        options,
        Some(Deadline::at(deadline)),
    )
}

/// The check of [`edge_interferes`]; `None`: `deadline` passed first.
fn edge_check(
    moving: &Collider,
    from: &Transform,
    to: &Transform,
    obstacle: &Collider,
    pose: &Transform,
    options: &EdgeOptions,
    deadline: Option<Deadline>,
) -> Result<Option<bool>, CollisionError> {
    let late = || deadline.is_some_and(Deadline::passed);
    check_pose(from)?;
    check_pose(to)?;
    check_pose(pose)?;
    check_tolerance(options.tolerance)?;
    if !(options.contact_step.is_finite() && options.contact_step > 0.0) {
        return Err(MotionFault::option(
            "contact step",
            options.contact_step,
            "a finite number > 0 mm",
        ));
    }
    let frames = EdgeFrames::new(from, to, pose);
    let angle = frames.angle;
    if angle > MAX_EDGE_ANGLE {
        return Ok(Some(true));
    }
    if angle == 0.0 && frames.shift == 0.0 {
        return Ok(Some(false));
    }
    // the translation in the start frame of the moving part: its boxes sweep along it
    let sweep = from.isometry().rotation.inverse() * (to.translation() - from.translation());
    // the obstacle's frame is "a", the moving part at `from` is "b"
    let rel = Relative::new(pose, from);
    let at_start = frames.at(0.0);
    let at_end = frames.at(1.0);
    let pairs = PairCheck {
        eps: eps(moving, obstacle, from, pose).max(eps(moving, obstacle, to, pose)),
        oriented: moving.is_solid() && obstacle.is_solid(),
        // Only translations keep faces in one plane (see below).
        shared_faces: angle == 0.0 && moving.encloses_volume() && obstacle.encloses_volume(),
        tolerance: options.tolerance,
        gap: super::contact_gap(options.tolerance),
        contact_step: super::contact_step(options.contact_step, options.tolerance),
    };
    // Shared faces may lie a few f32 roundings apart (containment.rs): the walk
    // reaches that far for them.
    let margin = super::containment::walk_margin(pairs.shared_faces, pairs.eps);
    // A moving node's swept box is met by many obstacle nodes: made once.
    let mut swept_boxes = SweptBoxes::lend(moving.obbs.len());
    let mut stack: Vec<(u32, u32)> = vec![(0, 0)];
    let mut popped = 0u32;
    let mut tally = super::EffortTally(0);
    while let Some((i, j)) = stack.pop() {
        tally.0 += 1;
        popped = popped.wrapping_add(1);
        if popped.is_multiple_of(64) && late() {
            return Ok(None);
        }
        let (no, nm) = (&obstacle.nodes[i as usize], &moving.nodes[j as usize]);
        let swept = swept_boxes.get(j, || swept_obb(&moving.obbs[j as usize], &sweep, &frames));
        if !rel.boxes_meet(&obstacle.obbs[i as usize], &swept, margin) {
            continue;
        }
        match (no.count > 0, nm.count > 0) {
            (true, true) => {
                for ta in moving.leaf_tris(nm) {
                    let ta = &ta;
                    let rho = ta.iter().map(|p| frames.arm(&p.coords)).fold(0.0, f64::max);
                    // the triangle's box over the edge: both ends, and the arc's bulge
                    // over the chord (at most rho·angle²/8)
                    let a0 = ta.map(|p| at_start * p);
                    let a1 = ta.map(|p| at_end * p);
                    let mut b = tri_box(&a0);
                    let e = tri_box(&a1);
                    b.grow(&e.lo);
                    b.grow(&e.hi);
                    let bulge = rho * angle * angle / 8.0 + margin;
                    for tb in obstacle.leaf_tris(no) {
                        let tb = &tb;
                        if b.distance_to_box(&tri_box(tb)) > bulge {
                            continue;
                        }
                        if pairs.plane_advance(&a0, rho, tb, &frames) < 1.0
                            && !(angle == 0.0
                                && pairs.translation_clears(&a0, tb, &frames.shift_local))
                        {
                            if late() {
                                return Ok(None);
                            }
                            if pairs.first_crossing(ta, rho, tb, &frames).is_some() {
                                return Ok(Some(true));
                            }
                        }
                        // No crossing — but two closed solids' faces sliding in one
                        // plane and facing the same way share the material behind
                        // them (a wall pushed into an equal wall): containment.rs.
                        if pairs.shared_faces
                            && coplanar_overlap(&a0, &a1, tb, pairs.eps) > pairs.tolerance
                        {
                            return Ok(Some(true));
                        }
                    }
                }
            }
            (false, true) => stack.extend([(no.first, j), (no.first + 1, j)]),
            (true, false) => stack.extend([(i, nm.first), (i, nm.first + 1)]),
            (false, false) => {
                if obb_size(&obstacle.obbs[i as usize]) >= obb_size(&swept) {
                    stack.extend([(no.first, j), (no.first + 1, j)]);
                } else {
                    stack.extend([(i, nm.first), (i, nm.first + 1)]);
                }
            }
        }
    }
    Ok(Some(false))
}

/// The moving part's swept node boxes of one edge check, made on first use: a
/// thread's scratch lent to the check ([`SweptLease`]) and given back when it ends, so a check
/// neither allocates nor clears a slot per node (on a finely meshed part, 65,000
/// nodes for OMPL.app's escape robot, that cost more than the walk itself).
struct SweptBoxes {
    /// The current check; `stamp[j] == generation` when `boxes[j]` is node `j`'s.
    generation: u32,
    stamp: Vec<u32>,
    boxes: Vec<Obb>,
}

thread_local! {
    static SWEPT_BOXES: std::cell::Cell<Option<SweptBoxes>> = const { std::cell::Cell::new(None) };
}

impl SweptBoxes {
    /// The thread's scratch (or a new one) for a check of a part with `nodes` nodes.
    fn lend(nodes: usize) -> SweptLease {
        let mut s = SWEPT_BOXES
            .try_with(|c| c.take())
            .ok()
            .flatten()
            .unwrap_or(SweptBoxes {
                generation: 0,
                stamp: Vec::new(),
                boxes: Vec::new(),
            });
        s.generation = s.generation.wrapping_add(1);
        if s.generation == 0 {
            s.stamp.fill(0);
            s.generation = 1;
        }
        if s.stamp.len() < nodes {
            s.stamp.resize(nodes, 0);
            s.boxes.resize(nodes, Obb::BLANK);
        }
        SweptLease(s)
    }

    /// Node `j`'s swept box, made by `make` on first use in this check.
    #[inline]
    fn get(&mut self, j: u32, make: impl FnOnce() -> Obb) -> Obb {
        let at = j as usize;
        if self.stamp[at] != self.generation {
            self.stamp[at] = self.generation;
            self.boxes[at] = make();
        }
        self.boxes[at]
    }
}

/// A lent [`SweptBoxes`], given back to the thread when the check ends (a check
/// nested in another's has a scratch of its own, dropped then).
struct SweptLease(SweptBoxes);

impl std::ops::Deref for SweptLease {
    type Target = SweptBoxes;
    fn deref(&self) -> &SweptBoxes {
        &self.0
    }
}

impl std::ops::DerefMut for SweptLease {
    fn deref_mut(&mut self) -> &mut SweptBoxes {
        &mut self.0
    }
}

impl Drop for SweptLease {
    fn drop(&mut self) {
        let s = SweptBoxes {
            generation: self.0.generation,
            stamp: std::mem::take(&mut self.0.stamp),
            boxes: std::mem::take(&mut self.0.boxes),
        };
        // the value replaced is a plain `SweptBoxes`: no drop runs back in here
        let _ = SWEPT_BOXES.try_with(|c| c.set(Some(s)));
    }
}

/// A box (moving part frame at the edge start) holding every position of `b` over
/// the edge. Its centre `c` moves by `sweep` (mm) plus the chord of its arc about
/// the rotation axis `k` through the part origin, `turn · c − c`; off that straight
/// chord it strays by at most the arc's sagitta bound `ρ · angle² / 8` (`ρ` its
/// distance from the axis: a curve with `|f''| ≤ M` between two points of a chord
/// leaves it by at most `M / 8`). The box turns about its centre as well, which
/// moves its points by at most `angle` times their distance from the axis through
/// the centre. Both offsets lie in planes normal to `k`, so along a unit box axis
/// `a` they count `√(1 − (a·k)²)` of their length, and not at all along `k`.
///
/// Growing every side by the whole arc `angle · ρ` of the centre instead (the
/// box before) made a node far from the axis a cube as wide as its arc: OMPL.app's
/// alpha robot (radius 197) turning 0.2 rad met three times the obstacle nodes in
/// smoothing's long edges. A part screwed along its own length (OMPL.app's
/// spirelli) keeps boxes about as thin as the part.
fn swept_obb(b: &Obb, sweep: &Vec3, frames: &EdgeFrames) -> Obb {
    let normal_share = Vec3::from_fn(|i, _| {
        let c = b.axes.column(i).dot(&frames.axis);
        (1.0 - c * c).max(0.0).sqrt()
    });
    // A corner's distance from the axis through the centre is at most each half
    // side times its axis's share normal to `k` (tighter than the box's radius for
    // a box long along the axis).
    let own = b.half.dot(&normal_share).min(b.radius);
    let angle = frames.angle;
    let chord = sweep + (frames.turn * b.centre - b.centre);
    let sagitta = frames.arm(&b.centre) * angle * angle / 8.0;
    let along = b.axes.tr_mul(&chord).abs() / 2.0;
    let grow = normal_share * (angle * own + sagitta);
    Obb::new(b.centre + chord / 2.0, b.axes, b.half + along + grow)
}

/// The per-triangle-pair conservative advancement.
struct PairCheck {
    eps: f64,
    oriented: bool,
    /// Both parts bound volumes and the edge only translates: coplanar faces
    /// facing the same way are tested for shared material.
    shared_faces: bool,
    tolerance: f64,
    /// Below this distance the pair is in contact, mm.
    gap: f64,
    contact_step: f64,
}

impl PairCheck {
    /// How much further along the edge (in `t`) moving triangle `a` (obstacle frame
    /// at the current pose, `rho` its farthest vertex from the rotation axis) is sure
    /// not to cross obstacle triangle `tb` deeper than the tolerance, by the planes
    /// of the two triangles: a pair's crossing depth is at most how far one triangle
    /// reaches through the other's plane, and along a plane's normal every vertex
    /// moves by at most its share of the translation plus `angle · rho` over the
    /// whole edge. This clears sliding contacts — a face gliding on a face, a peg
    /// along a bore — without stepping. `f64::INFINITY` when nothing limits it.
    fn plane_advance(&self, a: &Tri, rho: f64, tb: &Tri, frames: &EdgeFrames) -> f64 {
        let wobble = frames.angle * rho;
        // depth of the triangle with shadow `lo..hi` behind (and, unoriented, in
        // front of) the plane at height `h`, and how fast that depth can grow
        // (per unit `t`) when the triangle's shadow moves by `along` over the edge
        // and wobbles by `wobble`
        let limit = |lo: f64, hi: f64, h: f64, along: f64, wobble: f64| -> f64 {
            let (depth, rate) = if self.oriented {
                (h - lo, (-along).max(0.0) + wobble)
            } else {
                ((h - lo).min(hi - h), along.abs() + wobble)
            };
            let room = self.tolerance - depth;
            if room < 0.0 {
                0.0
            } else if rate > 0.0 {
                room / rate
            } else {
                f64::INFINITY
            }
        };
        let shadow = |x: &Tri, n: &Vec3| {
            let s = x.map(|p| n.dot(&p.coords));
            (s[0].min(s[1]).min(s[2]), s[0].max(s[1]).max(s[2]))
        };
        let mut dt = 0.0f64;
        if let Some(n) = unit_normal(tb) {
            let (lo, hi) = shadow(a, &n);
            dt = dt.max(limit(
                lo,
                hi,
                n.dot(&tb[0].coords),
                n.dot(&frames.shift_local),
                wobble,
            ));
        }
        // a translating triangle keeps its normal: its plane only shifts, which moves
        // b's shadow relative to it the other way
        if frames.angle == 0.0 {
            if let Some(n) = unit_normal(a) {
                let (lo, hi) = shadow(tb, &n);
                dt = dt.max(limit(
                    lo,
                    hi,
                    n.dot(&a[0].coords),
                    -n.dot(&frames.shift_local),
                    0.0,
                ));
            }
        }
        dt
    }

    /// Whether moving triangle `a` (obstacle frame at the edge's start), translated
    /// by `v` (mm, obstacle frame) over the whole edge, is sure not to cross obstacle
    /// triangle `b` deeper than the tolerance anywhere on it. A pair's crossing depth
    /// ([`tri_tri`]) is at most how far either triangle reaches behind the other's
    /// plane over the other, and over a translation that is at most the reach over
    /// the region the other sweeps ([`reach_into_swept`]) plus how far the planes
    /// close in along their normals. This clears what
    /// [`plane_advance`](Self::plane_advance) cannot: a faceted peg sliding
    /// line-to-line along a faceted bore of another tessellation, where each facet's
    /// plane cuts through the neighbouring facets of the other part (their corners
    /// reach far behind it, but not over it), so that every pair in contact was
    /// stepped along the whole slide at the contact step.
    fn translation_clears(&self, a: &Tri, b: &Tri, v: &Vec3) -> bool {
        // a triangle without area meets nothing (`tri_tri`)
        let (Some(na), Some(nb)) = (unit_normal(a), unit_normal(b)) else {
            return true;
        };
        // how fast a depth measured along a plane's normal can grow over the edge
        let rate = |closing: f64| {
            if self.oriented {
                closing.max(0.0)
            } else {
                closing.abs()
            }
        };
        // `a` behind `b`'s plane over `b`: against `a`, `b` moves by −v
        let a_into_b = reach_into_swept(a, b, &nb, &-v, self.eps, self.oriented) + rate(-nb.dot(v));
        if a_into_b <= self.tolerance {
            return true;
        }
        let b_into_a = reach_into_swept(b, a, &na, v, self.eps, self.oriented) + rate(na.dot(v));
        b_into_a <= self.tolerance
    }

    /// The first edge parameter after 0 at which moving triangle `ta` (part frame,
    /// `rho` its farthest vertex from the rotation axis) crosses obstacle triangle `tb`
    /// (obstacle frame) deeper than the tolerance, if any. Each advance is the
    /// larger of the planes' ([`plane_advance`](Self::plane_advance)) and the pair's
    /// distance over its fastest vertex speed; when neither clears a contact step
    /// and the pair is in contact, it moves by `contact_step` and checks the
    /// crossing depth there.
    fn first_crossing(&self, ta: &Tri, rho: f64, tb: &Tri, frames: &EdgeFrames) -> Option<f64> {
        let reach = frames.reach(rho);
        if reach <= 0.0 {
            return None;
        }
        let contact_dt = self.contact_step / reach;
        let mut t = 0.0;
        for _ in 0..MAX_PAIR_STEPS {
            let iso = frames.at(t);
            let a = ta.map(|p| iso * p);
            let mut dt = self.plane_advance(&a, rho, tb, frames);
            if dt < contact_dt {
                let d = tri_distance(&a, tb);
                if d > self.gap {
                    dt = dt.max((d - self.gap / 2.0) / reach);
                } else {
                    let depth = tri_tri(&a, tb, self.eps, self.oriented).unwrap_or(0.0);
                    if t > 0.0 && depth > self.tolerance {
                        return Some(t);
                    }
                    // In contact the pair may deepen as fast as its fastest vertex
                    // moves: a fixed contact step let a corner sliding past a wall's
                    // edge cross deeper than the tolerance and leave again between
                    // two checks (the house puzzle's shortcut, see the tests). So
                    // the step is at most the room left under the tolerance, floored
                    // at the finest contact gap (0.0005 mm) so a contact resting at
                    // the tolerance (or at depth 0 with tolerance 0) still advances.
                    let room = (self.tolerance - depth).max(super::MIN_CONTACT_GAP_MM);
                    dt = dt.max(contact_dt.min(room / reach)).max(f64::MIN_POSITIVE);
                }
            }
            t += dt;
            if t >= 1.0 {
                return None;
            }
        }
        Some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{interferes, DEFAULT_TOLERANCE};
    use crate::math::Point3;
    use crate::mesh::Mesh;
    use nalgebra::{Quaternion, UnitQuaternion};
    use std::sync::Arc;

    fn pose(t: [f64; 3], q: [f64; 4]) -> Transform {
        // q as nalgebra stores it: (i, j, k, w)
        Transform::from_parts(
            Vec3::from(t),
            UnitQuaternion::new_unchecked(Quaternion::new(q[3], q[0], q[1], q[2])),
        )
    }

    /// The house puzzle's L-shaped body and its wall `bc_west` (tests/common/
    /// problems.rs), with the shortcut edge of a smoothed path (seed 1) along which
    /// a pose 2 % in crosses the wall deeper than the tolerance.
    fn house_edge() -> (Collider, Collider, Transform, Transform) {
        let mut body = Mesh::cuboid(Point3::new(-25.0, -4.0, -4.0), Point3::new(25.0, 4.0, 4.0));
        body.append(&Mesh::cuboid(
            Point3::new(17.0, 4.0, -4.0),
            Point3::new(24.5, 26.0, 4.0),
        ));
        let wall = Mesh::cuboid(
            Point3::new(102.0, 98.0, 0.0),
            Point3::new(138.0, 102.0, 40.0),
        );
        let from = pose(
            [138.47476156413913, 71.1652024404471, 17.036050881367885],
            [
                0.22564051165602422,
                0.18844296049983245,
                0.28878100353997727,
                0.911142766710576,
            ],
        );
        let to = pose(
            [143.4204233408139, 84.10582743025753, 15.764837185916395],
            [
                0.20150130705585204,
                0.20209277427677474,
                0.4279286591324698,
                0.8575737849050905,
            ],
        );
        (
            Collider::new(Arc::new(body)).unwrap(),
            Collider::new(Arc::new(wall)).unwrap(),
            from,
            to,
        )
    }

    /// Every position a box's corners take along an edge (translation lerp,
    /// rotation slerp) lies in its swept box, for random boxes and edges turning
    /// up to 1.5 rad about random axes: the axis-aware growth is a bound.
    #[test]
    fn the_swept_box_holds_the_box_along_the_whole_edge() {
        let mut rng = crate::math::Rng::new(7);
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        // Near the part origin with turns up to 1.5 rad, and far from it (where
        // the arc's chord and sagitta bound the box, not its whole arc) with
        // turns up to the 3 rad an edge may take.
        for (far, turn) in [(20.0, 1.5), (300.0, 3.0)] {
            for _ in 0..300 {
                let unit = |v: Vec3| v / v.norm().max(1e-12);
                let rot = |axis: Vec3, a: f64| {
                    UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), a)
                };
                let axes = rot(
                    Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)),
                    u(0.0, 3.0),
                )
                .to_rotation_matrix()
                .into_inner();
                let b = Obb::new(
                    Vec3::new(u(-far, far), u(-far, far), u(-far, far)),
                    axes,
                    Vec3::new(u(0.0, 1.0), u(0.0, 8.0), u(0.0, 3.0)),
                );
                let from = Transform::from_parts(
                    Vec3::new(u(-5.0, 5.0), u(-5.0, 5.0), u(-5.0, 5.0)),
                    rot(
                        Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)),
                        u(0.0, 3.0),
                    ),
                );
                let k = unit(Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)));
                let to = Transform::from_parts(
                    from.translation() + Vec3::new(u(-4.0, 4.0), u(-4.0, 4.0), u(-4.0, 4.0)),
                    from.rotation() * rot(k, u(0.0, turn)),
                );
                let frames = EdgeFrames::new(&from, &to, &Transform::IDENTITY);
                let sweep =
                    from.isometry().rotation.inverse() * (to.translation() - from.translation());
                let swept = swept_obb(&b, &sweep, &frames);
                let start = from.isometry().inverse();
                for n in 0..=200 {
                    let at = *from.interpolate(&to, f64::from(n) / 200.0).isometry();
                    for c in 0..8 {
                        let sign = |bit: usize| if c >> bit & 1 == 1 { 1.0 } else { -1.0 };
                        let corner = b.centre
                            + b.axes.column(0) * (sign(0) * b.half.x)
                            + b.axes.column(1) * (sign(1) * b.half.y)
                            + b.axes.column(2) * (sign(2) * b.half.z);
                        // the corner in the part frame at `from`, where the box sweeps
                        let p = start * (at * Point3::from(corner));
                        let local = swept.axes.tr_mul(&(p.coords - swept.centre));
                        for i in 0..3 {
                            assert!(
                            local[i].abs() <= swept.half[i] + 1e-9,
                            "corner {c} at t = {n}/200 leaves the swept box along axis {i}: {} > {}",
                            local[i].abs(),
                            swept.half[i]
                        );
                        }
                    }
                }
            }
        }
    }

    /// The swept-reach rule (`PairCheck::translation_clears`) is a bound: a pair it
    /// clears never crosses deeper than the tolerance at any of 401 poses along the
    /// translation, for random pairs near each other (crossing planes, planes at a
    /// right angle, nearly parallel ones; oriented and not) and translations along,
    /// across and at random to the obstacle's plane. It also clears pairs that the
    /// planes alone (`plane_advance`) leave to be stepped.
    #[test]
    fn a_pair_cleared_for_a_translation_never_crosses_deeper_than_the_tolerance() {
        let mut rng = crate::math::Rng::new(11);
        let mut u = move |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        let p =
            |u: &mut dyn FnMut(f64, f64) -> f64, s: f64| Point3::new(u(-s, s), u(-s, s), u(-s, s));
        let (mut cleared, mut beyond_planes) = (0, 0);
        for case in 0..20_000 {
            // the obstacle triangle in the plane z = 0, facing +z
            let b: Tri = [
                Point3::new(u(-4.0, 0.0), u(-4.0, 0.0), 0.0),
                Point3::new(u(0.0, 4.0), u(-4.0, 0.0), 0.0),
                Point3::new(u(-2.0, 2.0), u(0.0, 4.0), 0.0),
            ];
            // the moving one: flat on it, at a right angle to it, or at random,
            // within about a tolerance of its plane somewhere
            let lift = u(-0.06, 0.06);
            let a: Tri = match case % 3 {
                0 => [0, 1, 2]
                    .map(|_| Point3::new(u(-5.0, 5.0), u(-5.0, 5.0), lift + u(-0.02, 0.02))),
                1 => {
                    let (x, y) = (u(-5.0, 5.0), u(-5.0, 5.0));
                    let turn = u(0.0, std::f64::consts::TAU);
                    let (c, s) = (turn.cos(), turn.sin());
                    let foot = |w: f64, z: f64| Point3::new(x + c * w, y + s * w, lift + z);
                    [
                        foot(u(-3.0, 3.0), u(-1.0, 0.0)),
                        foot(u(-3.0, 3.0), u(0.0, 3.0)),
                        foot(u(-3.0, 3.0), u(-1.0, 3.0)),
                    ]
                }
                _ => [p(&mut u, 4.0), p(&mut u, 4.0), p(&mut u, 4.0)],
            };
            let v = match case % 4 {
                0 => Vec3::new(u(-8.0, 8.0), u(-8.0, 8.0), 0.0),
                1 => Vec3::new(0.0, 0.0, u(-3.0, 3.0)),
                2 => Vec3::new(u(-8.0, 8.0), u(-8.0, 8.0), u(-0.01, 0.01)),
                _ => Vec3::new(u(-8.0, 8.0), u(-8.0, 8.0), u(-8.0, 8.0)),
            };
            let oriented = case % 2 == 0;
            let pairs = PairCheck {
                eps: 1e-9,
                oriented,
                shared_faces: false,
                tolerance: 0.05,
                gap: 0.025,
                contact_step: 0.025,
            };
            if !pairs.translation_clears(&a, &b, &v) {
                continue;
            }
            cleared += 1;
            let to = Transform::from_translation(v);
            let frames = EdgeFrames::new(&Transform::IDENTITY, &to, &Transform::IDENTITY);
            if pairs.plane_advance(&a, 0.0, &b, &frames) < 1.0 {
                beyond_planes += 1;
            }
            for k in 0..=400 {
                let t = f64::from(k) / 400.0;
                let at = a.map(|q| q + v * t);
                let depth = tri_tri(&at, &b, pairs.eps, oriented).unwrap_or(0.0);
                assert!(
                    depth <= pairs.tolerance + 1e-12,
                    "case {case}: cleared, but crossing {depth} deep at t = {t}: a {a:?}, b {b:?}, v {v:?}"
                );
            }
        }
        println!("cleared {cleared}, of them beyond the planes {beyond_planes}");
        assert!(
            cleared > 2_000 && beyond_planes > 500,
            "{cleared} {beyond_planes}"
        );
    }

    #[test]
    fn a_shortcut_crossing_a_wall_corner_is_seen() {
        let (body, wall, from, to) = house_edge();
        let id = Transform::IDENTITY;
        assert!(!interferes(&body, &from, &wall, &id, DEFAULT_TOLERANCE).unwrap());
        assert!(!interferes(&body, &to, &wall, &id, DEFAULT_TOLERANCE).unwrap());
        let n = 2000;
        let first = (1..n).find(|&k| {
            let p = from.interpolate(&to, k as f64 / n as f64);
            interferes(&body, &p, &wall, &id, DEFAULT_TOLERANCE).unwrap()
        });
        println!("first interfering sample {first:?}");
        assert!(first.is_some());
        assert!(edge_interferes(&body, &from, &to, &wall, &id, &EdgeOptions::default()).unwrap());
    }
}
