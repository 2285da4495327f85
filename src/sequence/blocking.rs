//! The directional blocking graph (seed 003 section 2.1 steps 2–4): candidate
//! separation directions of each part, the sweeps that find which parts block it along
//! each, and the safe length (how far a part can leave before anything blocks it).
//! Units: millimetres and radians, assembly frame.

use super::context::*;
use super::graph::separation_directions;
use super::options::{Mode, SequenceError, DEFAULT_SEQUENCE_TIME_LIMIT_MS};
use crate::collision::{edge_interferes_until, interferes, EdgeOptions, SweepMethod};
use crate::math::{frame_across, Aabb, Transform, Vec3};
use crate::workspace::WorkspaceError;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

impl Ctx<'_> {
    /// Candidate separation directions of component `c`.
    pub(super) fn candidate_directions(&self, c: usize) -> Vec<Vec3> {
        let mut out = Vec::new();
        match self.opts.mode {
            Mode::Mates => {
                for r in self.graph.relations.iter().filter(|r| r.a == c || r.b == c) {
                    for (k, &m) in r.mates.iter().enumerate() {
                        let mate = &self.doc.mates()[m];
                        for d in separation_directions(self.doc, mate, c, &r.freedoms[k]) {
                            push_dir(&mut out, d);
                        }
                    }
                }
                if out.is_empty() {
                    for d in axis_dirs() {
                        push_dir(&mut out, d);
                    }
                }
            }
            Mode::Geometry => {
                for d in axis_dirs() {
                    push_dir(&mut out, d);
                }
                let tol = (2.0 * self.opts.tolerance).max(1e-6);
                for d in self.contact_normals(c, tol) {
                    push_dir(&mut out, d);
                }
            }
        }
        out
    }

    /// Directions from the centres of the (at most 4 nearest) components touching
    /// `c` to `c`'s centre: the way out of what surrounds it.
    fn neighbour_directions(&self, c: usize) -> Vec<Vec3> {
        let centre = |i: usize| (self.boxes[i].lo.coords + self.boxes[i].hi.coords) * 0.5;
        let here = centre(c);
        let mut near: Vec<(f64, Vec3)> = members(self.related[c])
            .map(|q| {
                let d = here - centre(q);
                (d.norm(), d)
            })
            .filter(|(n, _)| *n > 1e-6)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.into_iter()
            .take(4)
            .map(|(_, d)| d.normalize())
            .collect()
    }

    /// Parts whose candidate directions are all blocked by the rest of the product
    /// (they could never go last) get more (geometry mode), each swept against every
    /// other product component: first the directions from their geometry (the
    /// normals of faces near a neighbour, within the contact gap; the principal axes;
    /// the directions away from the neighbours); those still stuck then a seeded
    /// sphere of `sphere_directions`, the free ones refined to the middle of their
    /// free cone, or when none is free the least blocked refined on a cone around
    /// them (at most 4 added, the freest first). A part that can leave the whole
    /// product along an axis or a contact normal never pays for these.
    pub(super) fn extend_directions(&mut self) {
        if self.opts.mode != Mode::Geometry {
            return;
        }
        let stuck = self.stuck();
        let this = &*self;
        let tol = self
            .opts
            .contact_gap_mm
            .max(2.0 * self.opts.tolerance)
            .max(1e-6);
        let added: Vec<(usize, Vec<(Vec3, Mask)>)> = stuck
            .par_iter()
            .map(|&p| {
                let mut dirs = Vec::new();
                // A clip held 1 mm clear in a slot leaves along its walls or its
                // long axis, a part between neighbours away from them.
                for d in this.contact_normals(p, tol) {
                    push_dir(&mut dirs, d);
                }
                for d in principal_axes(this.doc.mesh_of(p), &this.scene.poses[p]) {
                    push_dir(&mut dirs, d);
                    push_dir(&mut dirs, -d);
                }
                for d in this.neighbour_directions(p) {
                    push_dir(&mut dirs, d);
                }
                let rows = dirs
                    .into_iter()
                    .filter(|d| !this.dirs[p].iter().any(|e| same_dir(e, d)))
                    .map(|d| (d, this.blockers(p, &d)))
                    .collect();
                (p, rows)
            })
            .collect();
        self.add_directions(added);
        if self.opts.sphere_directions == 0 {
            return;
        }
        let stuck = self.stuck();
        if stuck.is_empty() {
            return;
        }
        let sphere = sphere_directions(self.opts.sphere_directions, self.opts.seed);
        // Half the spacing of the sphere's points (rad): the refinement cone.
        let spacing = (4.0 * std::f64::consts::PI / sphere.len() as f64).sqrt();
        let this = &*self;
        let added: Vec<(usize, Vec<(Vec3, Mask)>)> = stuck
            .par_iter()
            .map(|&p| (p, this.search_directions(p, &sphere, 0.5 * spacing)))
            .collect();
        self.add_directions(added);
    }

    /// The product components with no candidate direction free of all the others.
    fn stuck(&self) -> Vec<usize> {
        // In parallel: the sweeps left for later run here for every part.
        let parts: Vec<usize> = members(self.active).collect();
        parts
            .into_par_iter()
            .filter(|&p| {
                let others = self.active & !bit(p);
                others != 0
                    && (0..self.dirs[p].len()).all(|k| self.blockers_in(p, k, others, false) != 0)
            })
            .collect()
    }

    fn add_directions(&mut self, added: Vec<(usize, Vec<(Vec3, Mask)>)>) {
        let b = self.blocking.get_mut().unwrap();
        for (p, dirs) in added {
            for (d, blocked) in dirs {
                if !self.dirs[p].iter().any(|e| same_dir(e, &d)) {
                    self.dirs[p].push(d);
                    // Swept against every other product component.
                    b.hit[p].push(blocked);
                    b.known[p].push(self.active & !bit(p));
                }
            }
        }
    }

    /// What blocks `p` along `d` among the other product components (a sweep cut by
    /// the deadline counts as blocked).
    fn blockers(&self, p: usize, d: &Vec3) -> Mask {
        members(self.active & !bit(p))
            .filter(|&q| self.sweep_hits(p, d, q).unwrap_or(true))
            .fold(0, |a, q| a | bit(q))
    }

    fn search_directions(&self, p: usize, sphere: &[Vec3], cone: f64) -> Vec<(Vec3, Mask)> {
        let mut scored: Vec<(Vec3, Mask)> = Vec::new();
        for d in sphere {
            if self.out_of_time() {
                break;
            }
            scored.push((*d, self.blockers(p, d)));
        }
        scored.sort_by_key(|(_, m)| m.count_ones());
        let free: Vec<Vec3> = scored
            .iter()
            .filter(|(_, m)| *m == 0)
            .map(|(d, _)| *d)
            .collect();
        let mut out: Vec<(Vec3, Mask)> = Vec::new();
        if !free.is_empty() {
            // The middle of each free direction's free neighbourhood: more room on
            // every side than the sampled point.
            for d in free.iter().take(2) {
                let mut sum = *d;
                for e in cone_around(d, cone, 8) {
                    if self.out_of_time() {
                        break;
                    }
                    if self.blockers(p, &e) == 0 {
                        sum += e;
                    }
                }
                let mid = sum.normalize();
                if self.blockers(p, &mid) == 0 {
                    out.push((mid, 0));
                } else {
                    out.push((*d, 0));
                }
            }
            for d in free.iter().skip(2).take(2) {
                out.push((*d, 0));
            }
        } else {
            // Nothing free on the sphere: look closer around the least blocked.
            let mut near: Vec<(Vec3, Mask)> = Vec::new();
            for (d, _) in scored.iter().take(3) {
                for e in cone_around(d, cone, 8) {
                    if self.out_of_time() {
                        break;
                    }
                    near.push((e, self.blockers(p, &e)));
                }
            }
            near.extend(scored.iter().take(3).copied());
            near.sort_by_key(|(_, m)| m.count_ones());
            out.extend(near.into_iter().take(4));
        }
        // Blocked by parts outside the product never happens (they are not swept);
        // the full row: blockers among every product component.
        out
    }

    /// Directions leaving the faces of `c` that touch another component: minus the
    /// outward normals of `c`'s triangles lying within `tol` (mm) of a neighbour's
    /// surface (at most 6 new ones, largest area first).
    pub(super) fn contact_normals(&self, c: usize, tol: f64) -> Vec<Vec3> {
        let mesh = self.doc.mesh_of(c);
        let pose = self.scene.poses[c];
        let mut found: Vec<(Vec3, f64)> = Vec::new();
        for q in members(self.related[c]) {
            // A fit's faces lie up to its depth inside the other part.
            let tol = self.fit(c, q).map_or(tol, |f| tol.max(2.0 * f.depth));
            let qb = &self.boxes[q];
            let inv = self.scene.poses[q].inverse();
            for t in 0..mesh.triangles.len() {
                if self.out_of_time() {
                    return Vec::new();
                }
                let [a, b, cc] = mesh.triangle(t);
                let area = 0.5 * (b - a).cross(&(cc - a)).norm();
                if area <= 0.0 {
                    continue;
                }
                let centroid = pose.apply(&nalgebra::Point3::from(
                    (a.coords + b.coords + cc.coords) / 3.0,
                ));
                if qb.distance_to_point(&centroid) > tol {
                    continue;
                }
                let local = inv.apply(&centroid);
                if self.scene.colliders[q].distance_to_point(&local, tol * 2.0) > tol {
                    continue;
                }
                let n = -pose.apply_vector(&mesh.triangle_normal(t));
                match found.iter_mut().find(|(e, _)| (e - n).norm() < 1e-3) {
                    Some((_, w)) => *w += area,
                    None => found.push((n, area)),
                }
            }
        }
        found.sort_by(|a, b| b.1.total_cmp(&a.1));
        found.into_iter().take(6).map(|(n, _)| n).collect()
    }

    /// Whether `p` moved straight along `d` from its assembled pose hits `q`.
    ///
    /// One continuous check ([`edge_interferes`]) from the resting pose outward until
    /// `p`'s box has left `q`'s by `probe_mm`: the assembled pose is known free (the
    /// contacts were checked in [`Ctx::new`]), so the contact region is not walked
    /// pose by pose — faces sliding on or leaving a face in contact are cleared by
    /// their planes at once, and nothing is jumped over. Beyond that length the
    /// boxes are apart for good (the box has passed `q`'s on an axis `d` keeps
    /// moving along), so "not hit" proves the whole straight line along `d` free of
    /// `q`: the tasks' straight insertions reuse this answer instead of checking again.
    pub(super) fn sweep_hits(&self, p: usize, d: &Vec3, q: usize) -> Result<bool, SequenceError> {
        let (bp, bq) = (self.boxes[p], self.boxes[q]);
        let len = exit_distance(&bp, &bq, d) + self.opts.probe_mm;
        let moved = Aabb::new(bp.lo + d * len, bp.hi + d * len);
        let swept = Aabb::new(bp.lo.inf(&moved.lo), bp.hi.sup(&moved.hi));
        // Interference needs the boxes to overlap deeper than the tolerance on every
        // axis: a part sliding on a face (a plate on the table) is never swept.
        let tolerance = self.opts.tolerance;
        if swept.overlap(&bq).min() <= tolerance {
            return Ok(false);
        }
        let time_limit = || {
            SequenceError::TimeLimit(
                self.opts
                    .time_limit_ms
                    .unwrap_or(DEFAULT_SEQUENCE_TIME_LIMIT_MS),
            )
        };
        if self.out_of_time() {
            return Err(time_limit());
        }
        self.sweeps.fetch_add(1, Ordering::Relaxed);
        if let Some(check) = self.fit_check(p, q) {
            // A fit pair: the overlap of the assembled pose allowed, the whole
            // straight line at once (see `fit.rs`).
            return Ok(check.translation_overlap(&self.scene.poses[p], d, len));
        }
        let options = EdgeOptions {
            tolerance,
            contact_step: SweepMethod::DEFAULT_CONTACT_STEP_MM,
        };
        let start = self.scene.poses[p];
        // In pieces: the stretch before `entry`, where the boxes are still apart
        // (the trees' root boxes clear it at once), then pieces growing from half a
        // probe length to SWEEP_PIECE_MM. A part blocked by what it rests against (a
        // peg pushed sideways into its hole's wall) or by a neighbour it reaches (a
        // peg's head meeting the next peg's) is hit within the first short piece,
        // where few triangle pairs can meet, instead of after a walk over every pair
        // a longer piece could meet (thin facets swept across many others, coplanar
        // faces sliding past each other); the deadline is read between pieces.
        let entry = entry_distance(&bp, &bq, d, tolerance).min(len);
        // Two large parts: shorter pieces, so the deadline is read often enough
        // (a piece of such a pair can walk many thousands of triangle pairs).
        let large = |i: usize| self.scene.colliders[i].triangle_count() > PIECE_TRIANGLES;
        let longest = if large(p) && large(q) {
            LARGE_SWEEP_PIECE_MM
        } else {
            SWEEP_PIECE_MM
        };
        let mut piece = (0.5 * self.opts.probe_mm).min(longest);
        let mut at = 0.0;
        // whether the straight piece `a → b` of the sweep hits `q`; each piece
        // stops at the one deadline too (a piece between two large parts can meet
        // many thousands of triangle pairs)
        let hits = |a: &Transform, b: &Transform| {
            edge_interferes_until(
                &self.scene.colliders[p],
                a,
                b,
                &self.scene.colliders[q],
                &self.scene.poses[q],
                &options,
                self.deadline.instant(),
            )
            .map_err(|e| SequenceError::from(WorkspaceError::from(e)))?
            .ok_or_else(&time_limit)
        };
        if entry > piece {
            at = entry - 0.5 * piece;
            if hits(&start, &start.then(&Transform::from_translation(d * at)))? {
                return Ok(true);
            }
        }
        let mut a = start.then(&Transform::from_translation(d * at));
        while at < len {
            if self.out_of_time() {
                return Err(time_limit());
            }
            let next = if len - (at + piece) < 0.25 * piece {
                len
            } else {
                at + piece
            };
            at = next;
            piece = (2.0 * piece).min(longest);
            let b = start.then(&Transform::from_translation(d * next));
            if hits(&a, &b)? {
                return Ok(true);
            }
            a = b;
        }
        Ok(false)
    }

    /// The directional blocking graph: for every product component, direction and
    /// other product component, whether the straight removal hits it. The sweeps are
    /// independent and run in parallel. A sweep the deadline cuts counts as blocked
    /// (never a wrong "free"): the search then reports what it could do in time.
    ///
    /// Sweeps between two large parts (both over [`LAZY_TRIANGLES`]) are left for
    /// when the search asks ([`Ctx::blockers_in`]): a part moving into a large
    /// neighbour walks many triangle pairs, and the answer is often not needed — a
    /// smaller part already placed blocks the same direction (a tube pushed
    /// sideways meets the clip inside its neighbour before the neighbour's walls
    /// matter), or the search never asks for that direction among those parts.
    pub(super) fn build_blocking(&mut self) {
        // p along d meets q exactly when q along −d meets p (the same relative
        // motion, the same separation length): only one of the two is swept.
        let mirror = |p: usize, k: usize, q: usize| -> Option<usize> {
            (q < p)
                .then(|| {
                    self.dirs[q]
                        .iter()
                        .position(|e| same_dir(e, &-self.dirs[p][k]))
                })
                .flatten()
        };
        let large = |i: usize| self.scene.colliders[i].triangle_count() > LAZY_TRIANGLES;
        let mut queries = Vec::new();
        let active = self.active;
        for p in members(active) {
            for k in 0..self.dirs[p].len() {
                for q in members(active).filter(|&q| q != p) {
                    if mirror(p, k, q).is_none() && !(large(p) && large(q)) {
                        queries.push((p, k, q));
                    }
                }
            }
        }
        let this = &*self;
        let hits: Vec<bool> = queries
            .par_iter()
            .map(|&(p, k, q)| this.sweep_hits(p, &this.dirs[p][k], q).unwrap_or(true))
            .collect();
        let mut b = Blocking {
            hit: (0..self.n)
                .map(|p| vec![0 as Mask; self.dirs[p].len()])
                .collect(),
            known: (0..self.n)
                .map(|p| vec![0 as Mask; self.dirs[p].len()])
                .collect(),
        };
        for (&(p, k, q), &hit) in queries.iter().zip(&hits) {
            self.record(&mut b, p, k, q, hit);
        }
        *self.blocking.get_mut().unwrap() = b;
    }

    /// Records the sweep of `p` along `dirs[p][k]` against `q`, and its mirror (`q`
    /// along the opposite direction against `p`) when `q` has that direction.
    fn record(&self, b: &mut Blocking, p: usize, k: usize, q: usize, hit: bool) {
        b.known[p][k] |= bit(q);
        if hit {
            b.hit[p][k] |= bit(q);
        }
        if let Some(k2) = self.dirs[q]
            .iter()
            .position(|e| same_dir(e, &-self.dirs[p][k]))
        {
            b.known[q][k2] |= bit(p);
            if hit {
                b.hit[q][k2] |= bit(p);
            }
        }
    }

    /// The components of `mask` that block `p` along `dirs[p][k]`: every one with
    /// `all`, else as soon as one is found (enough to say the direction is not
    /// free). Sweeps not run yet are run here, the smallest part first.
    pub(super) fn blockers_in(&self, p: usize, k: usize, mask: Mask, all: bool) -> Mask {
        let mask = mask & self.active & !bit(p);
        loop {
            let (hit, unknown) = {
                let b = self.blocking.lock().unwrap();
                (b.hit[p][k] & mask, mask & !b.known[p][k])
            };
            if unknown == 0 || (hit != 0 && !all) {
                return hit;
            }
            let q = members(unknown)
                .min_by_key(|&q| (self.scene.colliders[q].triangle_count(), q))
                .unwrap_or(0);
            let h = self.sweep_hits(p, &self.dirs[p][k], q).unwrap_or(true);
            let mut b = self.blocking.lock().unwrap();
            self.record(&mut b, p, k, q, h);
        }
    }

    /// Whether every candidate direction of `p` that gravity allows is blocked by
    /// a component of `mask` by the sweeps run so far (none is run here): then it
    /// has no straight insertion onto `mask` nor onto anything holding `mask`.
    pub(super) fn known_blocked_everywhere(&self, p: usize, mask: Mask) -> bool {
        let mask = mask & self.active & !bit(p);
        let b = self.blocking.lock().unwrap();
        (0..self.dirs[p].len())
            .all(|k| !self.gravity_allows(&-self.dirs[p][k]) || b.hit[p][k] & mask != 0)
    }

    /// The free separation directions of `p` among the components of `mask`.
    pub fn free_dirs(&self, p: usize, mask: Mask) -> Vec<usize> {
        (0..self.dirs[p].len())
            .filter(|&k| self.blockers_in(p, k, mask, false) == 0)
            .collect()
    }

    /// Static interference of `p` at `pose` with any component of `mask` (a pair
    /// with a fit: an overlap the assembled pose does not have; see `fit.rs`).
    pub(super) fn pose_hits(&self, p: usize, pose: &Transform, mask: Mask) -> bool {
        let b = self.scene.colliders[p].world_bounds(pose);
        let tolerance = self.opts.tolerance;
        members(mask).any(|q| {
            boxes_meet(&b, &self.boxes[q], tolerance)
                && match self.fit_check(p, q) {
                    Some(check) => check.new_overlap(pose),
                    None => interferes(
                        &self.scene.colliders[p],
                        pose,
                        &self.scene.colliders[q],
                        &self.scene.poses[q],
                        tolerance,
                    )
                    .unwrap_or(true),
                }
        })
    }

    /// The memo key of [`safe_length`](Self::safe_length): the part, the direction
    /// and the components of `mask` its probes can reach.
    pub(super) fn safe_length_key(&self, p: usize, d: &Vec3, mask: Mask) -> SafeKey {
        let Some(region) = union_box(&self.boxes, mask) else {
            return (p, dir_key(d), 0);
        };
        let probe = self.opts.probe_mm;
        // Every probe pose lies in p's box swept along d to the bracket's far end
        // (at most `limit`: leaving a smaller region is never farther), grown by a
        // probe: the boxes that cannot meet it never interfere.
        let limit = exit_distance(&self.boxes[p], &region, d) + probe;
        let bp = self.boxes[p];
        let far = Aabb::new(bp.lo + d * limit, bp.hi + d * limit);
        let reach = Aabb::new(
            bp.lo.inf(&far.lo) - Vec3::repeat(probe),
            bp.hi.sup(&far.hi) + Vec3::repeat(probe),
        );
        let near: Mask = members(mask)
            .filter(|&q| boxes_meet(&reach, &self.boxes[q], self.opts.tolerance))
            .fold(0, |a, q| a | bit(q));
        (p, dir_key(d), near)
    }

    /// Seed 003 section 2.1 step 6: step `p` out along `d` (unit) until a probe along
    /// every other candidate direction is free of `mask` (mm).
    ///
    /// Only the components of `mask` whose boxes the probes can reach take part (the
    /// others can never answer "hit"), and the search's bracket is set by them too,
    /// so the answer depends on the part, the direction and those components alone:
    /// it is computed once per such key (the ranked sequences put the same part
    /// onto the same neighbours in many orders).
    pub fn safe_length(&self, p: usize, d: &Vec3, mask: Mask) -> f64 {
        let probe = self.opts.probe_mm;
        let key = self.safe_length_key(p, d, mask);
        let near = key.2;
        if let Some(&s) = self.safe_lengths.lock().unwrap().get(&key) {
            return s;
        }
        let Some(region) = union_box(&self.boxes, near) else {
            return probe;
        };
        let limit = exit_distance(&self.boxes[p], &region, d) + probe;
        if self.out_of_time() {
            // The whole straight line is known free (the blocking sweep): leaving
            // the bracket is safe, only not the shortest; not remembered.
            return limit;
        }
        let others: Vec<Vec3> = self.dirs[p]
            .iter()
            .filter(|e| e.dot(d).abs() < 0.9)
            .copied()
            .collect();
        let step = self.step.max(limit / 200.0);
        let start = self.scene.poses[p];
        let free_at = |s: f64| {
            let at = start.then(&Transform::from_translation(d * s));
            others.iter().all(|e| {
                let probe = at.then(&Transform::from_translation(e * probe));
                !self.pose_hits(p, &probe, near)
            })
        };
        let found = if probe >= limit || free_at(probe) {
            probe.min(limit)
        } else {
            // Bisection to one step: the part is held sideways until it clears what
            // surrounds it, and free from there on (a handful of probes, not one per
            // step — each probe is an exact query, costly on fine meshes).
            let (mut lo, mut hi) = (probe, limit);
            while hi - lo > step {
                if self.out_of_time() {
                    // Not remembered: cut short, not the answer.
                    return limit;
                }
                let mid = 0.5 * (lo + hi);
                if free_at(mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            hi
        };
        self.safe_lengths.lock().unwrap().insert(key, found);
        found
    }
}

/// The principal axes (unit, world) of a mesh at `pose` whose spread differs from
/// the other two by more than 5 % (a symmetric spread has no preferred axis): the
/// eigenvectors of the covariance of its surface (exact per triangle, so the
/// triangulation does not bias it).
pub(super) fn principal_axes(mesh: &crate::mesh::Mesh, pose: &Transform) -> Vec<Vec3> {
    let mut total = 0.0;
    let mut first = Vec3::zeros();
    let mut second = nalgebra::Matrix3::<f64>::zeros();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let area = 0.5 * (b - a).cross(&(c - a)).norm();
        let sum = a.coords + b.coords + c.coords;
        total += area;
        first += sum * (area / 3.0);
        // ∫ x xᵀ dA over a triangle = A/12 (Σ vᵢ vᵢᵀ + s sᵀ), s = Σ vᵢ.
        second += (a.coords * a.coords.transpose()
            + b.coords * b.coords.transpose()
            + c.coords * c.coords.transpose()
            + sum * sum.transpose())
            * (area / 12.0);
    }
    if total <= 0.0 {
        return Vec::new();
    }
    let mean = first / total;
    let cov = second / total - mean * mean.transpose();
    let eig = nalgebra::SymmetricEigen::new(cov);
    let e = eig.eigenvalues;
    let scale = e.iter().fold(0.0f64, |a, &v| a.max(v.abs())).max(1e-12);
    (0..3)
        .filter(|&i| {
            (0..3)
                .filter(|&j| j != i)
                .all(|j| (e[i] - e[j]).abs() > 0.05 * scale)
        })
        .map(|i| {
            pose.apply_vector(&eig.eigenvectors.column(i).into_owned())
                .normalize()
        })
        .collect()
}

/// `n` directions spread evenly on the unit sphere (a Fibonacci lattice) turned by
/// a rotation drawn from `seed`: deterministic for a seed.
pub(super) fn sphere_directions(n: usize, seed: u64) -> Vec<Vec3> {
    let turn = crate::math::Rng::new(seed ^ 0x5e9_d1c5).rotation();
    crate::math::sphere_lattice(n)
        .into_iter()
        .map(|d| turn * d)
        .collect()
}

/// `k` unit directions at angle `angle` (rad) around unit `d`.
pub(super) fn cone_around(d: &Vec3, angle: f64, k: usize) -> Vec<Vec3> {
    let (u, v) = frame_across(d);
    (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            (d * angle.cos() + (u * a.cos() + v * a.sin()) * angle.sin()).normalize()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_is_seeded_unit_and_spread() {
        let a = sphere_directions(48, 3);
        assert_eq!(a, sphere_directions(48, 3));
        assert_ne!(a, sphere_directions(48, 4));
        assert!(a.iter().all(|d| (d.norm() - 1.0).abs() < 1e-12));
        // Every direction has a sample within 35°.
        for d in sphere_directions(200, 9) {
            assert!(a.iter().any(|e| e.angle(&d) < 35f64.to_radians()));
        }
        for e in cone_around(&Vec3::z(), 0.1, 8) {
            assert!((e.angle(&Vec3::z()) - 0.1).abs() < 1e-9);
        }
    }

    #[test]
    fn principal_axes_of_a_long_box_and_none_of_a_cube() {
        use crate::math::Point3;
        let bar =
            crate::mesh::Mesh::cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 2.0, 20.0));
        let turn = Transform::from_parts(
            Vec3::zeros(),
            nalgebra::UnitQuaternion::from_axis_angle(&Vec3::y_axis(), 30f64.to_radians()),
        );
        let axes = principal_axes(&bar, &turn);
        assert_eq!(axes.len(), 1, "{axes:?}");
        let want = Vec3::new(0.5, 0.0, 3f64.sqrt() / 2.0);
        assert!(axes[0].dot(&want).abs() > 1.0 - 1e-9, "{axes:?}");
        let cube =
            crate::mesh::Mesh::cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 2.0, 2.0));
        assert!(principal_axes(&cube, &Transform::IDENTITY).is_empty());
    }
}
