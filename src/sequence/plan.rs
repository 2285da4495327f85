//! Seed 003 section 2.1 steps 2–6 and section 2.2: mating directions by separating
//! each part along its free directions, the directional blocking graph they form,
//! the safe length, the obstacle box, the sequence search with base choice and
//! mount counting, and the tasks. Units: millimetres and radians, assembly frame.

use super::graph::{separation_directions, Freedom, RelationGraph};
use super::grasp::find_grasp;
use super::options::{
    Mode, Rejected, Sequence, SequenceError, SequenceOptions, SequencePlan, StepInfo,
    DEFAULT_SEQUENCE_TIME_LIMIT_MS, MAX_COMPONENTS,
};
use super::task::{Grasp, Operation, Task};
use crate::collision::{edge_interferes, interferes, Aabb, EdgeOptions, SweepMethod};
use crate::document::{Document, MateKind, Reference};
use crate::math::{Transform, Vec3};
use crate::planning::{MeshValidator, MeshValidatorOptions, PlannedPath, Planner, PlanningSpace};
use crate::workspace::{Scene, SceneCache, WorkspaceError};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The longest piece of a blocking sweep (mm): past the point where the boxes first
/// meet, the pieces grow from half the probe length to this, and the deadline is read
/// between them.
const SWEEP_PIECE_MM: f64 = 10.0;

type Mask = u128;

fn bit(i: usize) -> Mask {
    1u128 << i
}

pub(crate) fn members_of(m: Mask) -> impl Iterator<Item = usize> {
    members(m)
}

fn members(m: Mask) -> impl Iterator<Item = usize> {
    (0..128).filter(move |&i| m & bit(i) != 0)
}

/// The size of every component for the base choice (seed 003 section 2.2: volume or
/// weight): its mass (`options.masses` by component or part, else the document's
/// `mass`, kg) when one is known; else its mesh volume (mm³) times the median density
/// of the components with a mass (so masses and volumes compare), or the bare volume
/// when no component has a mass.
pub(crate) fn component_sizes(doc: &Document, opts: &SequenceOptions) -> Vec<f64> {
    let n = doc.components().len();
    let volumes: Vec<f64> = (0..n)
        .map(|i| doc.mesh_of(i).signed_volume().abs())
        .collect();
    let masses: Vec<Option<f64>> = doc
        .components()
        .iter()
        .map(|c| {
            opts.masses
                .get(&c.name)
                .or_else(|| opts.masses.get(&c.part))
                .copied()
                .or(c.mass)
        })
        .collect();
    let mut densities: Vec<f64> = (0..n)
        .filter_map(|i| {
            masses[i]
                .filter(|_| volumes[i] > 0.0)
                .map(|m| m / volumes[i])
        })
        .collect();
    densities.sort_by(f64::total_cmp);
    let density = densities.get(densities.len() / 2).copied().unwrap_or(1.0);
    (0..n)
        .map(|i| masses[i].unwrap_or(volumes[i] * density))
        .collect()
}

/// Everything the search needs, computed once per call.
pub(crate) struct Ctx<'d> {
    pub doc: &'d Document,
    pub scene: Scene,
    pub opts: SequenceOptions,
    pub n: usize,
    pub names: Vec<String>,
    /// World boxes in the assembled pose.
    pub boxes: Vec<Aabb>,
    /// Size (mass or volume) per component.
    pub sizes: Vec<f64>,
    pub graph: RelationGraph,
    /// Related components (mates, or contacts in geometry mode).
    pub related: Vec<Mask>,
    /// Candidate separation directions per component (unit, world).
    pub dirs: Vec<Vec<Vec3>>,
    /// `blocked[p][k]`: the components that hit `p` moving along `dirs[p][k]`.
    pub blocked: Vec<Vec<Mask>>,
    pub step: f64,
    pub deadline: Instant,
    pub started: Instant,
    /// Blocking sweeps run (counted from the parallel sweeps).
    pub sweeps: AtomicUsize,
    /// Safe lengths found, by part, direction and the assembled parts that matter.
    safe_lengths: Mutex<HashMap<SafeKey, f64>>,
    /// Grasps found, by part, mating direction, free directions and the assembled
    /// parts the fingers can reach.
    pub(super) grasps: Mutex<HashMap<GraspKey, Option<Grasp>>>,
}

/// The key of [`Ctx::safe_lengths`]: part, direction bits, the parts that matter.
type SafeKey = (usize, [u64; 3], Mask);

/// The key of [`Ctx::grasps`].
pub(super) type GraspKey = (usize, [u64; 3], Vec<[u64; 3]>, Mask);

/// The bits of a direction, for exact-match memo keys.
pub(super) fn dir_key(d: &Vec3) -> [u64; 3] {
    [d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]
}

fn same_dir(a: &Vec3, b: &Vec3) -> bool {
    (a - b).norm() < 1e-6
}

fn push_dir(v: &mut Vec<Vec3>, d: Vec3) {
    if d.norm() < 1e-9 {
        return;
    }
    let d = d.normalize();
    if !v.iter().any(|e| same_dir(e, &d)) {
        v.push(d);
    }
}

fn axis_dirs() -> [Vec3; 6] {
    [
        Vec3::x(),
        -Vec3::x(),
        Vec3::y(),
        -Vec3::y(),
        Vec3::z(),
        -Vec3::z(),
    ]
}

fn union_box(boxes: &[Aabb], m: Mask) -> Option<Aabb> {
    members(m)
        .map(|i| boxes[i])
        .reduce(|a, b| Aabb::new(a.lo.inf(&b.lo), a.hi.sup(&b.hi)))
}

fn diag(b: &Aabb) -> f64 {
    (b.hi - b.lo).norm()
}

/// How far `b` must move along unit `d` to leave `region` (mm, ≥ 0).
fn exit_distance(b: &Aabb, region: &Aabb, d: &Vec3) -> f64 {
    let mut best = f64::INFINITY;
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            continue;
        }
        let s = if d[k] > 0.0 {
            (region.hi[k] - b.lo[k]) / d[k]
        } else {
            (region.lo[k] - b.hi[k]) / d[k]
        };
        best = best.min(s.max(0.0));
    }
    if best.is_finite() {
        best
    } else {
        0.0
    }
}

/// How far `b` can move along unit `d` before it overlaps `region` deeper than
/// `slack` (mm) on every axis `d` moves along (mm, ≥ 0; 0 when it already does):
/// before that distance the two boxes are apart.
fn entry_distance(b: &Aabb, region: &Aabb, d: &Vec3, slack: f64) -> f64 {
    let mut worst = 0.0f64;
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            continue;
        }
        let s = if d[k] > 0.0 {
            (region.lo[k] + slack - b.hi[k]) / d[k]
        } else {
            (region.hi[k] - slack - b.lo[k]) / d[k]
        };
        worst = worst.max(s);
    }
    worst
}

fn boxes_meet(a: &Aabb, b: &Aabb, slack: f64) -> bool {
    a.overlap(b).min() > -slack
}

impl<'d> Ctx<'d> {
    pub fn new(
        doc: &'d Document,
        cache: &mut SceneCache,
        opts: &SequenceOptions,
    ) -> Result<Ctx<'d>, SequenceError> {
        let started = Instant::now();
        let n = doc.components().len();
        if n == 0 {
            return Err(SequenceError::Empty);
        }
        if n > MAX_COMPONENTS {
            return Err(SequenceError::TooManyComponents(n));
        }
        let bad = |option: &'static str, v: f64, expected: &'static str| {
            Err(SequenceError::InvalidOption {
                option,
                value: v.to_string(),
                expected,
            })
        };
        let limit = opts.time_limit_ms.unwrap_or(DEFAULT_SEQUENCE_TIME_LIMIT_MS);
        if !(limit.is_finite() && limit > 0.0) {
            return bad("time_limit_ms", limit, "a finite number of ms > 0");
        }
        if !(opts.tolerance.is_finite() && opts.tolerance >= 0.0) {
            return bad("tolerance", opts.tolerance, "a finite number of mm ≥ 0");
        }
        if !(opts.probe_mm.is_finite() && opts.probe_mm > 0.0 && opts.probe_mm < 1e6) {
            return bad("probe_mm", opts.probe_mm, "a finite number of mm > 0");
        }
        if !(opts.step_mm.is_finite() && opts.step_mm >= 0.0 && opts.step_mm < 1e6) {
            return bad(
                "step_mm",
                opts.step_mm,
                "a finite number of mm ≥ 0 (0: automatic)",
            );
        }
        if !(opts.max_tilt.is_finite() && opts.max_tilt >= 0.0) {
            return bad("max_tilt", opts.max_tilt, "a finite angle ≥ 0");
        }
        if !(opts.small_base_ratio.is_finite() && opts.small_base_ratio >= 0.0) {
            return bad(
                "small_base_ratio",
                opts.small_base_ratio,
                "a finite number ≥ 0",
            );
        }
        if !(opts.fallback_time_limit_ms.is_finite() && opts.fallback_time_limit_ms > 0.0) {
            return bad(
                "fallback_time_limit_ms",
                opts.fallback_time_limit_ms,
                "a finite number of ms > 0",
            );
        }
        if opts.max_sequences == 0 {
            return Err(SequenceError::InvalidOption {
                option: "max_sequences",
                value: "0".into(),
                expected: "at least 1",
            });
        }
        for (k, v) in &opts.masses {
            if !(v.is_finite() && *v > 0.0) {
                return Err(SequenceError::InvalidOption {
                    option: "masses",
                    value: format!("{k}: {v}"),
                    expected: "finite numbers > 0",
                });
            }
        }
        for name in opts.base.iter().chain(&opts.order) {
            doc.component_index(name).map_err(WorkspaceError::from)?;
        }
        let deadline = started + Duration::from_secs_f64(limit.min(1e9) / 1e3);
        let scene = Scene::new(doc, cache)?;
        let names: Vec<String> = doc.components().iter().map(|c| c.name.clone()).collect();
        let mut boxes = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            if doc.mesh_of(i).vertices.is_empty() {
                return Err(WorkspaceError::EmptyMesh(name.clone()).into());
            }
            boxes.push(scene.colliders[i].world_bounds(&scene.poses[i]));
        }
        let sizes = component_sizes(doc, opts);
        // The assembled state must be free of interference.
        let contacts = scene
            .contacts(crate::collision::Method::Exact, opts.tolerance)
            .map_err(WorkspaceError::from)?;
        if let Some(p) = contacts.iter().find(|p| p.contact.is_interfering()) {
            return Err(SequenceError::AssembledInterference {
                a: names[p.a].clone(),
                b: names[p.b].clone(),
                depth: p.contact.depth(),
            });
        }
        let sizes_for = sizes.clone();
        let mut graph = match opts.mode {
            Mode::Mates => RelationGraph::build(doc, &|i| sizes_for[i]),
            Mode::Geometry => RelationGraph {
                components: names.clone(),
                relations: Vec::new(),
                nodes: (0..n)
                    .map(|i| super::graph::Node { members: vec![i] })
                    .collect(),
                loops: Vec::new(),
            },
        };
        let mut related = vec![0 as Mask; n];
        match opts.mode {
            Mode::Mates => {
                for r in &graph.relations {
                    related[r.a] |= bit(r.b);
                    related[r.b] |= bit(r.a);
                }
            }
            Mode::Geometry => {
                for p in &contacts {
                    related[p.a] |= bit(p.b);
                    related[p.b] |= bit(p.a);
                    let f = Freedom {
                        frame: Transform::IDENTITY,
                        translations: Vec::new(),
                        rotations: Vec::new(),
                    };
                    graph.relations.push(super::graph::Relation {
                        a: p.a,
                        b: p.b,
                        mates: Vec::new(),
                        freedoms: Vec::new(),
                        freedom: f,
                    });
                }
            }
        }
        let step = if opts.step_mm > 0.0 {
            opts.step_mm
        } else {
            let smallest = boxes.iter().map(diag).fold(f64::INFINITY, f64::min);
            (0.01 * smallest).clamp(0.05, 2.0)
        };
        let mut ctx = Ctx {
            doc,
            scene,
            opts: opts.clone(),
            n,
            names,
            boxes,
            sizes,
            graph,
            related,
            dirs: Vec::new(),
            blocked: Vec::new(),
            step,
            deadline,
            started,
            sweeps: AtomicUsize::new(0),
            safe_lengths: Mutex::new(HashMap::new()),
            grasps: Mutex::new(HashMap::new()),
        };
        // Independent per component (the contact normals walk the meshes): parallel.
        let this = &ctx;
        let dirs: Vec<Vec<Vec3>> = (0..n)
            .into_par_iter()
            .map(|i| this.candidate_directions(i))
            .collect();
        ctx.dirs = dirs;
        ctx.build_blocking()?;
        ctx.order_composites();
        Ok(ctx)
    }

    /// The order a composite node implies (seed 003 section 2.1 step 3), from the
    /// blocking graph: taken apart member by member (the first member, the node's
    /// base, stays), each time one that can leave the others straight, the latest
    /// in the loop-breaking order first; assembly is the reverse. A stack on a shaft
    /// (bushing, gear, washer, cap) so comes out bottom-up whatever the sizes say.
    /// Members that cannot be taken apart keep their loop-breaking order.
    fn order_composites(&mut self) {
        for ni in 0..self.graph.nodes.len() {
            let members = self.graph.nodes[ni].members.clone();
            if members.len() < 3 {
                continue;
            }
            let mut left: Vec<usize> = members.clone();
            let mut removed = Vec::new();
            while left.len() > 1 {
                let mask: Mask = left.iter().fold(0, |a, &m| a | bit(m));
                let Some(pos) = (1..left.len())
                    .rev()
                    .find(|&i| !self.free_dirs(left[i], mask & !bit(left[i])).is_empty())
                else {
                    break;
                };
                removed.push(left.remove(pos));
            }
            left.extend(removed.into_iter().rev());
            self.graph.nodes[ni].members = left;
        }
    }

    pub fn out_of_time(&self) -> bool {
        Instant::now() >= self.deadline
    }

    fn remaining_ms(&self) -> f64 {
        self.deadline
            .saturating_duration_since(Instant::now())
            .as_secs_f64()
            * 1e3
    }

    /// Candidate separation directions of component `c`.
    fn candidate_directions(&self, c: usize) -> Vec<Vec3> {
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
                for d in self.contact_normals(c) {
                    push_dir(&mut out, d);
                }
            }
        }
        out
    }

    /// Directions leaving the faces of `c` that touch another component: minus the
    /// outward normals of `c`'s triangles lying on a neighbour's surface (at most 6
    /// new ones, largest touching area first).
    fn contact_normals(&self, c: usize) -> Vec<Vec3> {
        let mesh = self.doc.mesh_of(c);
        let pose = self.scene.poses[c];
        let tol = (2.0 * self.opts.tolerance).max(1e-6);
        let mut found: Vec<(Vec3, f64)> = Vec::new();
        for q in members(self.related[c]) {
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
    fn sweep_hits(&self, p: usize, d: &Vec3, q: usize) -> Result<bool, SequenceError> {
        let (bp, bq) = (self.boxes[p], self.boxes[q]);
        let len = exit_distance(&bp, &bq, d) + self.opts.probe_mm;
        let moved = Aabb::new(bp.lo + d * len, bp.hi + d * len);
        let swept = Aabb::new(bp.lo.inf(&moved.lo), bp.hi.sup(&moved.hi));
        // Interference needs the boxes to overlap deeper than the tolerance on every
        // axis: a part sliding on a face (a plate on the table) is never swept.
        if swept.overlap(&bq).min() <= self.opts.tolerance {
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
        let options = EdgeOptions {
            tolerance: self.opts.tolerance,
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
        let entry = entry_distance(&bp, &bq, d, self.opts.tolerance).min(len);
        let mut piece = (0.5 * self.opts.probe_mm).min(SWEEP_PIECE_MM);
        let mut at = 0.0;
        // whether the straight piece `a → b` of the sweep hits `q`
        let hits = |a: &Transform, b: &Transform| {
            edge_interferes(
                &self.scene.colliders[p],
                a,
                b,
                &self.scene.colliders[q],
                &self.scene.poses[q],
                &options,
            )
            .map_err(|e| SequenceError::from(WorkspaceError::from(e)))
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
            piece = (2.0 * piece).min(SWEEP_PIECE_MM);
            let b = start.then(&Transform::from_translation(d * next));
            if hits(&a, &b)? {
                return Ok(true);
            }
            a = b;
        }
        Ok(false)
    }

    /// The directional blocking graph: for every component, direction and other
    /// component, whether the straight removal hits it. The sweeps are independent
    /// and run in parallel.
    fn build_blocking(&mut self) -> Result<(), SequenceError> {
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
        let mut queries = Vec::new();
        for p in 0..self.n {
            for k in 0..self.dirs[p].len() {
                for q in (0..self.n).filter(|&q| q != p) {
                    if mirror(p, k, q).is_none() {
                        queries.push((p, k, q));
                    }
                }
            }
        }
        let this = &*self;
        let hits: Vec<bool> = queries
            .par_iter()
            .map(|&(p, k, q)| this.sweep_hits(p, &this.dirs[p][k], q))
            .collect::<Result<_, _>>()?;
        let mut blocked: Vec<Vec<Mask>> = (0..self.n)
            .map(|p| vec![0 as Mask; self.dirs[p].len()])
            .collect();
        for (&(p, k, q), &hit) in queries.iter().zip(&hits) {
            if hit {
                blocked[p][k] |= bit(q);
            }
        }
        // The mirrored half, from the swept one (its q < p: p ascending fills them).
        for p in 0..self.n {
            for k in 0..self.dirs[p].len() {
                for q in (0..self.n).filter(|&q| q != p) {
                    if let Some(k2) = mirror(p, k, q) {
                        if blocked[q][k2] & bit(p) != 0 {
                            blocked[p][k] |= bit(q);
                        }
                    }
                }
            }
        }
        self.blocked = blocked;
        Ok(())
    }

    /// The free separation directions of `p` among the components of `mask`.
    pub fn free_dirs(&self, p: usize, mask: Mask) -> Vec<usize> {
        (0..self.dirs[p].len())
            .filter(|&k| self.blocked[p][k] & mask == 0)
            .collect()
    }

    fn node_index(&self, c: usize) -> usize {
        self.graph.node_of(c)
    }

    fn group_of(&self, c: usize) -> Mask {
        let mut g = bit(c);
        loop {
            let mut next = g;
            for i in members(g) {
                next |= self.related[i];
            }
            if next == g {
                return g;
            }
            g = next;
        }
    }

    fn node_size(&self, node: usize) -> f64 {
        self.graph.nodes[node]
            .members
            .iter()
            .map(|&m| self.sizes[m])
            .sum()
    }

    /// Whether `p` may be assembled next onto `mask` (seed 003 section 2.2: nodes in
    /// the relation graph, composite nodes in their implied order).
    fn eligible(&self, p: usize, mask: Mask) -> bool {
        let node = &self.graph.nodes[self.node_index(p)];
        let pos = node.members.iter().position(|&m| m == p).unwrap_or(0);
        if pos > 0 {
            return mask & bit(node.members[pos - 1]) != 0;
        }
        // The node's first member: related to an assembled component (composite
        // nodes are assembled part by part, so a part may go onto the members of a
        // composite already in place, between them), or the first node of a group
        // nothing of which is assembled yet (its largest).
        if self.related[p] & mask != 0 {
            return true;
        }
        let group = self.group_of(p);
        if group & mask != 0 {
            return false;
        }
        let best = members(group)
            .map(|c| self.node_index(c))
            .max_by(|&a, &b| {
                self.node_size(a)
                    .total_cmp(&self.node_size(b))
                    .then(b.cmp(&a))
            })
            .unwrap_or(usize::MAX);
        best == self.node_index(p)
    }

    fn why_not(&self, p: usize, mask: Mask) -> String {
        if !self.eligible(p, mask) {
            let node = &self.graph.nodes[self.node_index(p)];
            let pos = node.members.iter().position(|&m| m == p).unwrap_or(0);
            if pos > 0 {
                return format!(
                    "{} waits for {} (composite node order)",
                    self.names[p],
                    self.names[node.members[pos - 1]]
                );
            }
            return format!("{} has nothing assembled to go onto", self.names[p]);
        }
        let mut by: Mask = 0;
        for k in 0..self.dirs[p].len() {
            by |= self.blocked[p][k] & mask;
        }
        let names: Vec<&str> = members(by).map(|i| self.names[i].as_str()).collect();
        format!(
            "{} is blocked along all {} directions by {}",
            self.names[p],
            self.dirs[p].len(),
            names.join(", ")
        )
    }

    /// A path for `p` out of the components of `mask` found by fitup's planners
    /// (seed 002's disassembly with `local_rrt`), ending assembled.
    fn plan_fallback(&self, p: usize, mask: Mask) -> Option<PlannedPath> {
        let budget = self.opts.fallback_time_limit_ms.min(self.remaining_ms());
        if budget < 1.0 {
            return None;
        }
        let obstacles: Vec<_> = members(mask)
            .map(|q| (self.scene.colliders[q].clone(), self.scene.poses[q]))
            .collect();
        let product = union_box(&self.boxes, mask)?;
        let mut validator = MeshValidator::new(
            self.scene.colliders[p].clone(),
            obstacles,
            MeshValidatorOptions {
                tolerance: self.opts.tolerance,
                ..MeshValidatorOptions::default()
            },
        )
        .ok()?;
        let margin = diag(&self.boxes[p]).max(10.0);
        let all = Aabb::new(
            product.lo.inf(&self.boxes[p].lo),
            product.hi.sup(&self.boxes[p].hi),
        );
        let space = PlanningSpace::new(
            all.lo.coords - Vec3::repeat(margin),
            all.hi.coords + Vec3::repeat(margin),
        );
        let mut planner = Planner::by_name("local_rrt")?;
        planner.limits_mut().seed = self.opts.seed;
        planner.limits_mut().time_limit_ms = Some(budget);
        planner.limits_mut().max_iterations = 20_000;
        let part_box = self.scene.colliders[p].bounds();
        let path = planner
            .plan_disassembly(
                &mut validator,
                &space,
                &self.scene.poses[p],
                &part_box,
                &product,
                None,
            )
            .ok()?;
        path.found().then_some(path)
    }

    /// A validator for `p` moving among the components of `mask`.
    fn validator(&self, p: usize, mask: Mask, edge: SweepMethod) -> Option<MeshValidator> {
        let obstacles: Vec<_> = members(mask)
            .map(|q| (self.scene.colliders[q].clone(), self.scene.poses[q]))
            .collect();
        MeshValidator::new(
            self.scene.colliders[p].clone(),
            obstacles,
            MeshValidatorOptions {
                tolerance: self.opts.tolerance,
                edge,
                ..MeshValidatorOptions::default()
            },
        )
        .ok()
    }

    /// The cheapest non-straight insertion: slide along one candidate direction
    /// from the assembled pose, then leave straight along another (an L: under a
    /// roof, then out of the opening). Tries slides of 1/8 … 8/8 of the free travel,
    /// shortest first. Returns the insertion path (outside → corner → assembled),
    /// checked continuously among `mask`.
    fn two_segment(&self, p: usize, mask: Mask) -> Option<PlannedPath> {
        let region = union_box(&self.boxes, mask)?;
        let mut v = self.validator(p, mask, SweepMethod::CONTINUOUS)?;
        let start = self.scene.poses[p];
        let mut leaves: Vec<Vec3> = axis_dirs().to_vec();
        for d in &self.dirs[p] {
            push_dir(&mut leaves, *d);
        }
        let mut best: Option<PlannedPath> = None;
        for d1 in &self.dirs[p] {
            // The free travel along d1: the first stepped pose that hits.
            let limit = exit_distance(&self.boxes[p], &region, d1) + self.opts.probe_mm;
            let step = self.step.max(limit / 100.0);
            let mut travel = 0.0;
            while travel + step < limit {
                if self.out_of_time() {
                    return best;
                }
                let at = start.then(&Transform::from_translation(d1 * (travel + step)));
                if self.pose_hits(p, &at, mask) {
                    break;
                }
                travel += step;
            }
            if travel < self.opts.probe_mm {
                continue;
            }
            for k in 1..=8 {
                let s = travel * k as f64 / 8.0;
                let corner = start.then(&Transform::from_translation(d1 * s));
                let moved = self.scene.colliders[p].world_bounds(&corner);
                for d2 in leaves.iter().filter(|d2| d2.dot(d1).abs() < 0.9) {
                    let out = exit_distance(&moved, &region, d2) + self.opts.probe_mm;
                    let from = corner.then(&Transform::from_translation(d2 * out));
                    let path = PlannedPath::given(
                        "two_segment",
                        vec![from, corner, start],
                        v.options().edge,
                    );
                    if best.as_ref().is_some_and(|b| b.length_mm <= path.length_mm) {
                        continue;
                    }
                    if path.revalidate(&mut v).is_ok() {
                        best = Some(path);
                    }
                }
                if best.is_some() {
                    break;
                }
            }
        }
        best
    }

    /// Static interference of `p` at `pose` with any component of `mask`.
    fn pose_hits(&self, p: usize, pose: &Transform, mask: Mask) -> bool {
        let b = self.scene.colliders[p].world_bounds(pose);
        members(mask).any(|q| {
            boxes_meet(&b, &self.boxes[q], self.opts.tolerance)
                && interferes(
                    &self.scene.colliders[p],
                    pose,
                    &self.scene.colliders[q],
                    &self.scene.poses[q],
                    self.opts.tolerance,
                )
                .unwrap_or(true)
        })
    }

    /// The memo key of [`safe_length`](Self::safe_length): the part, the direction
    /// and the components of `mask` its probes can reach.
    fn safe_length_key(&self, p: usize, d: &Vec3, mask: Mask) -> SafeKey {
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

/// One choice of the search: a part and how it goes in.
#[derive(Clone)]
struct Choice {
    part: usize,
    /// Separation direction (the part leaves along it; the mating direction is its
    /// negation).
    leave: Vec3,
    planned: Option<PlannedPath>,
}

#[derive(Clone)]
struct Found {
    base: usize,
    choices: Vec<Choice>,
    cost: (usize, usize, f64),
}

fn cost_lt(a: &(usize, usize, f64), b: &(usize, usize, f64)) -> bool {
    (a.0, a.1) < (b.0, b.1) || ((a.0, a.1) == (b.0, b.1) && a.2 < b.2 - 1e-9)
}

struct Search<'c, 'd> {
    ctx: &'c Ctx<'d>,
    k: usize,
    found: Vec<Found>,
    rejected: Vec<Rejected>,
    dead: HashSet<Mask>,
    /// Per part: the planned path found for it (reused wherever it is still free).
    planned_ok: Vec<Option<PlannedPath>>,
    /// Per part: the sets of assembled parts among which no path was found (a
    /// superset cannot do better).
    planned_failed: Vec<Vec<Mask>>,
    /// Pairs (a, b) with a before b, counted over every complete sequence seen.
    before: Vec<Vec<u32>>,
    complete_count: u32,
    expanded: usize,
    cut: bool,
    /// Whether dead ends ask the planners (second pass).
    use_fallback: bool,
    /// Whether branch and bound cut a subtree below the current node.
    pruned: bool,
}

const MAX_EXPANDED: usize = 200_000;
const MAX_REJECTED: usize = 50;

impl Search<'_, '_> {
    /// A planned insertion path for `p` onto `mask` (second pass only): the path
    /// found for `p` before when it is still free; else, unless `p` had a straight
    /// insertion earlier on this branch or failed among fewer parts, a two-segment
    /// path or seed 002's disassembly planner. `None`: no path.
    fn planned_path(&mut self, p: usize, mask: Mask, had_free: Mask) -> Option<PlannedPath> {
        let ctx = self.ctx;
        if let Some(path) = &self.planned_ok[p] {
            // Reuse only: a part whose path the later parts block should have gone
            // in earlier (that order is searched too).
            let mut v = ctx.validator(p, mask, SweepMethod::CONTINUOUS)?;
            return path.revalidate(&mut v).is_ok().then(|| path.clone());
        }
        if had_free & bit(p) != 0 || self.planned_failed[p].iter().any(|&f| f & !mask == 0) {
            return None;
        }
        let found = ctx
            .two_segment(p, mask)
            .or_else(|| ctx.plan_fallback(p, mask));
        match &found {
            Some(path) => self.planned_ok[p] = Some(path.clone()),
            None => self.planned_failed[p].push(mask),
        }
        found
    }

    fn mounts_for(&self, current: Option<Vec3>, mate: &Vec3) -> bool {
        match current {
            None => false,
            Some(c) => c.angle(mate) > self.ctx.opts.max_tilt + 1e-9,
        }
    }

    fn worst_kept(&self) -> Option<(usize, usize, f64)> {
        (self.found.len() >= self.k).then(|| self.found[self.found.len() - 1].cost)
    }

    fn record(&mut self, base: usize, choices: &[Choice], cost: (usize, usize, f64)) {
        let order: Vec<usize> = std::iter::once(base)
            .chain(choices.iter().map(|c| c.part))
            .collect();
        for (i, &a) in order.iter().enumerate() {
            for &b in &order[i + 1..] {
                self.before[a][b] += 1;
            }
        }
        self.complete_count += 1;
        let f = Found {
            base,
            choices: choices.to_vec(),
            cost,
        };
        let pos = self
            .found
            .iter()
            .position(|g| cost_lt(&cost, &g.cost))
            .unwrap_or(self.found.len());
        self.found.insert(pos, f);
        self.found.truncate(self.k);
    }

    fn reject(&mut self, base: usize, choices: &[Choice], reason: String) {
        if self.rejected.len() < MAX_REJECTED {
            let order = std::iter::once(base)
                .chain(choices.iter().map(|c| c.part))
                .map(|i| self.ctx.names[i].clone())
                .collect();
            self.rejected.push(Rejected { order, reason });
        }
    }

    /// Depth-first over feasible next parts; returns whether a completion exists
    /// below (`self.cut` tells whether the answer is partial).
    // The search state of one node, passed down by value (cheap copies).
    #[allow(clippy::too_many_arguments)]
    fn dfs(
        &mut self,
        base: usize,
        mask: Mask,
        choices: &mut Vec<Choice>,
        current: Option<Vec3>,
        cost: (usize, usize, f64),
        pins: &[usize],
        had_free: Mask,
    ) -> bool {
        let ctx = self.ctx;
        let all: Mask = if ctx.n == 128 { !0 } else { bit(ctx.n) - 1 };
        if mask == all {
            self.record(base, choices, cost);
            return true;
        }
        if ctx.out_of_time() || self.expanded >= MAX_EXPANDED {
            self.cut = true;
            return false;
        }
        if let Some(w) = self.worst_kept() {
            if !cost_lt(&cost, &w) {
                // Branch and bound: nothing below can rank among the kept ones. The
                // mask is not dead, so it is not memoised either.
                self.pruned = true;
                return false;
            }
        }
        if self.dead.contains(&mask) {
            return false;
        }
        self.expanded += 1;
        let depth = choices.len();
        let pinned = pins.get(depth).copied();
        let region = union_box(&ctx.boxes, mask).unwrap_or(ctx.boxes[base]);
        // Options: (needs mount, exit distance, part, leave, planned).
        let mut options: Vec<(bool, f64, Choice)> = Vec::new();
        for p in (0..ctx.n).filter(|&p| mask & bit(p) == 0) {
            if pinned.is_some_and(|q| q != p) || !ctx.eligible(p, mask) {
                continue;
            }
            let free = ctx.free_dirs(p, mask);
            // Keeping the current mount direction dominates every other choice.
            let keep = free
                .iter()
                .find(|&&k| current.is_some_and(|c| !self.mounts_for(Some(c), &-ctx.dirs[p][k])));
            let ks: Vec<usize> = match keep {
                Some(&k) => vec![k],
                None => free,
            };
            for k in ks {
                let d = ctx.dirs[p][k];
                options.push((
                    self.mounts_for(current, &-d),
                    exit_distance(&ctx.boxes[p], &region, &d),
                    Choice {
                        part: p,
                        leave: d,
                        planned: None,
                    },
                ));
            }
        }
        if self.use_fallback {
            // Parts without a straight insertion: a planned path (seed 002's
            // disassembly, or a two-segment slide-and-lift first), tried as soon as
            // the part is eligible — the fewer parts assembled, the likelier a path.
            for p in (0..ctx.n).filter(|&p| mask & bit(p) == 0) {
                if pinned.is_some_and(|q| q != p)
                    || !ctx.eligible(p, mask)
                    || options.iter().any(|o| o.2.part == p)
                {
                    continue;
                }
                if let Some(path) = self.planned_path(p, mask, had_free) {
                    let n = path.poses.len();
                    let last = path.poses[n - 1].translation() - path.poses[n - 2].translation();
                    let leave = if last.norm() > 1e-9 {
                        -last.normalize()
                    } else {
                        Vec3::z()
                    };
                    options.push((
                        self.mounts_for(current, &-leave),
                        path.length_mm,
                        Choice {
                            part: p,
                            leave,
                            planned: Some(path),
                        },
                    ));
                }
            }
        }
        if options.is_empty() {
            let reasons: Vec<String> = (0..ctx.n)
                .filter(|&p| mask & bit(p) == 0)
                .filter(|&p| pinned.is_none_or(|q| q == p))
                .take(4)
                .map(|p| ctx.why_not(p, mask))
                .collect();
            let mut reason = reasons.join("; ");
            if let Some(q) = pinned {
                reason = format!("pinned order: {} cannot go next: {reason}", ctx.names[q]);
            }
            self.reject(base, choices, reason);
            self.dead.insert(mask);
            return false;
        }
        // A planned part goes first: what comes after may close its way in.
        options.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(a.2.planned.is_none().cmp(&b.2.planned.is_none()))
                .then(a.1.total_cmp(&b.1))
                .then(a.2.part.cmp(&b.2.part))
        });
        // Parts that could go straight here: the planners are not asked for them
        // further down this branch (the order where they go straight is searched).
        let next_had_free = options
            .iter()
            .filter(|o| o.2.planned.is_none())
            .fold(had_free, |a, o| a | bit(o.2.part));
        let (cut_before, pruned_before) = (self.cut, self.pruned);
        self.cut = false;
        self.pruned = false;
        let mut any = false;
        for (mount, len, choice) in options {
            let mate = -choice.leave;
            let change = current.is_some_and(|c| c.angle(&mate) > 1e-6);
            let next_current = if current.is_none() || mount {
                Some(mate)
            } else {
                current
            };
            let next_cost = (
                cost.0 + mount as usize,
                cost.1 + change as usize,
                cost.2 + len,
            );
            let part = choice.part;
            choices.push(choice);
            any |= self.dfs(
                base,
                mask | bit(part),
                choices,
                next_current,
                next_cost,
                pins,
                next_had_free,
            );
            choices.pop();
        }
        if !any && !self.cut && !self.pruned {
            self.dead.insert(mask);
        }
        self.cut |= cut_before;
        self.pruned |= pruned_before;
        any
    }
}

/// The mating directions of `p` against `mask` (negated free separations).
fn step_info(ctx: &Ctx, p: usize, mask: Mask, order: &[usize]) -> (Vec<usize>, Vec<Vec3>) {
    let receivers: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&q| mask & bit(q) != 0 && ctx.related[p] & bit(q) != 0)
        .collect();
    let dirs = ctx
        .free_dirs(p, mask)
        .into_iter()
        .map(|k| -ctx.dirs[p][k])
        .collect();
    (receivers, dirs)
}

/// The operation from the geometry (seed 003 section 2 step 9).
fn operation(ctx: &Ctx, p: usize, receivers: &[usize], mate: &Vec3) -> Operation {
    let c = &ctx.doc.components()[p];
    if c.threaded
        || ctx
            .opts
            .threaded
            .iter()
            .any(|t| t == &c.name || t == &c.part)
    {
        return Operation::Screw;
    }
    let (mut axis, mut plane) = (false, false);
    for m in ctx.doc.mates() {
        let (a, b) = (m.entities[0].component, m.entities[1].component);
        let other = if a == p {
            b
        } else if b == p {
            a
        } else {
            continue;
        };
        if !receivers.contains(&other) {
            continue;
        }
        match (m.kind, &m.entities[0].geometry) {
            (MateKind::Concentric, _) | (MateKind::Coincident, Reference::Axis { .. }) => {
                axis = true
            }
            (MateKind::Coincident | MateKind::Distance, Reference::Plane { .. }) => plane = true,
            _ => {}
        }
    }
    if axis {
        return Operation::Insertion;
    }
    if plane {
        return Operation::Align;
    }
    // No mates (geometry mode): a part held sideways by what is assembled (at least
    // two of the four axis directions across its mating direction blocked) is
    // inserted.
    let mask: Mask = receivers.iter().fold(0, |a, &q| a | bit(q));
    let blocked_across = axis_dirs()
        .iter()
        .filter(|d| d.dot(mate).abs() < 0.5)
        .filter(|d| {
            ctx.dirs[p]
                .iter()
                .position(|e| same_dir(e, d))
                .is_some_and(|k| ctx.blocked[p][k] & mask != 0)
        })
        .count();
    if blocked_across >= 2 {
        Operation::Insertion
    } else {
        Operation::Align
    }
}

/// Turns a found order into tasks: safe lengths, checked paths, grasps, boxes and
/// frames. `Err(reason)` when a step's path cannot be checked free.
fn build_sequence(ctx: &Ctx, f: &Found) -> Result<Sequence, String> {
    let mut mask = bit(f.base);
    let mut order = vec![f.base];
    let mut tasks = Vec::new();
    let mut steps = Vec::new();
    let mut current: Option<Vec3> = None;
    let mut prev: Option<Vec3> = None;
    let (mut mounts, mut changes, mut total) = (0, 0, 0.0);
    let base_pose = ctx.scene.poses[f.base];
    for (index, ch) in f.choices.iter().enumerate() {
        let p = ch.part;
        let (receivers, mating_directions) = step_info(ctx, p, mask, &order);
        let mate = -ch.leave;
        let assembled = ctx.scene.poses[p];
        let (safe, path) = match &ch.planned {
            Some(path) => {
                let mut validator = ctx
                    .validator(p, mask, SweepMethod::CONTINUOUS)
                    .ok_or_else(|| format!("no validator for {}", ctx.names[p]))?;
                if path.revalidate(&mut validator).is_err() {
                    return Err(format!("the planned path of {} is blocked", ctx.names[p]));
                }
                (ctx.opts.probe_mm, path.clone())
            }
            None => {
                // The blocking graph's continuous sweep of p along this direction
                // found no component of `mask` on the whole straight line (see
                // `Ctx::sweep_hits`): that is this path's check, already made.
                let free = ctx.dirs[p]
                    .iter()
                    .position(|e| same_dir(e, &ch.leave))
                    .is_some_and(|k| ctx.blocked[p][k] & mask == 0);
                if !free {
                    return Err(format!(
                        "the straight insertion of {} along {:?} collides",
                        ctx.names[p],
                        mate.as_slice()
                    ));
                }
                let safe = ctx.safe_length(p, &ch.leave, mask);
                let from = assembled.then(&Transform::from_translation(ch.leave * safe));
                let path =
                    PlannedPath::given("straight", vec![from, assembled], SweepMethod::CONTINUOUS);
                (safe, path)
            }
        };
        let mount = current.is_some_and(|c| c.angle(&mate) > ctx.opts.max_tilt + 1e-9);
        if current.is_none() || mount {
            current = Some(mate);
        }
        let change = prev.is_some_and(|c| c.angle(&mate) > 1e-6);
        prev = Some(mate);
        mounts += mount as usize;
        changes += change as usize;
        total += path.length_mm;
        let down = current.unwrap_or(mate);
        let sequence_frame = Transform::from_parts(
            base_pose.translation(),
            crate::math::rotation_between(&-Vec3::z(), &down),
        );
        let receiver = receivers.first().copied().unwrap_or(f.base);
        let obstacle_box = union_box(&ctx.boxes, mask).unwrap_or(ctx.boxes[f.base]);
        let grasp = find_grasp(ctx, p, &mating_directions, &mate, mask);
        tasks.push(Task {
            index,
            base: ctx.names[receiver].clone(),
            part: ctx.names[p].clone(),
            operation: operation(ctx, p, &receivers, &mate),
            mating_direction: mate,
            safe_length: safe,
            grasp,
            obstacle_box,
            assembled_pose: assembled,
            base_pose: ctx.scene.poses[receiver],
            sequence_frame,
            mount,
            path,
        });
        steps.push(StepInfo {
            receivers: receivers.iter().map(|&q| ctx.names[q].clone()).collect(),
            mating_directions,
            planned: ch.planned.is_some(),
            direction_change: change,
        });
        mask |= bit(p);
        order.push(p);
    }
    Ok(Sequence {
        base: ctx.names[f.base].clone(),
        tasks,
        steps,
        mounts,
        direction_changes: changes,
        path_length_mm: total,
    })
}

/// Plans the assembly sequences of `doc` (seed 003 section 2.2; see the module docs).
pub(crate) fn plan(
    doc: &Document,
    cache: &mut SceneCache,
    opts: &SequenceOptions,
) -> Result<SequencePlan, SequenceError> {
    let mut ctx = Ctx::new(doc, cache, opts)?;
    let n = ctx.n;
    // Base candidates: the pinned one, or every component by size.
    let bases: Vec<usize> = match &opts.base {
        Some(b) => {
            let base = doc.component_index(b).map_err(WorkspaceError::from)?;
            // A pinned base starts its composite node.
            let ni = ctx.graph.node_of(base);
            let node = &mut ctx.graph.nodes[ni];
            node.members.retain(|&x| x != base);
            node.members.insert(0, base);
            vec![base]
        }
        None => {
            let mut c: Vec<usize> = (0..n).collect();
            c.sort_by(|&a, &b| ctx.sizes[b].total_cmp(&ctx.sizes[a]).then(a.cmp(&b)));
            c
        }
    };
    let pins: Vec<usize> = opts
        .order
        .iter()
        .map(|s| doc.component_index(s).map_err(WorkspaceError::from))
        .collect::<Result<_, _>>()?;
    let ctx = ctx;
    let mut search = Search {
        ctx: &ctx,
        k: opts.max_sequences.max(1),
        found: Vec::new(),
        rejected: Vec::new(),
        dead: HashSet::new(),
        planned_ok: vec![None; n],
        planned_failed: vec![Vec::new(); n],
        before: vec![vec![0; n]; n],
        complete_count: 0,
        expanded: 0,
        cut: false,
        use_fallback: false,
        pruned: false,
    };
    // Straight insertions first; the planners only when no sequence exists without
    // them (they cost seconds where a sweep costs milliseconds).
    let passes: &[bool] = if opts.planner_fallback {
        &[false, true]
    } else {
        &[false]
    };
    for &fallback in passes {
        if fallback && search.complete_count > 0 {
            break;
        }
        search.use_fallback = fallback;
        search.fallback_pass(&bases, &pins);
    }
    let found = std::mem::take(&mut search.found);
    let rejected = std::mem::take(&mut search.rejected);
    let before = std::mem::take(&mut search.before);
    let (count, cut) = (search.complete_count, search.cut);
    finish(&ctx, found, rejected, before, count, cut)
}

impl Search<'_, '_> {
    fn fallback_pass(&mut self, bases: &[usize], pins: &[usize]) {
        let ctx = self.ctx;
        let opts = &ctx.opts;
        let search = self;
        for &base in bases {
            if ctx.out_of_time() {
                search.cut = true;
                break;
            }
            // A base that does not start its composite node is not a base.
            if ctx.graph.nodes[ctx.graph.node_of(base)].members[0] != base {
                continue;
            }
            // Seed 003 section 2.2 step 2: a base much smaller than what it joins is
            // inactive.
            let biggest_related = members(ctx.related[base])
                .map(|q| ctx.sizes[q])
                .fold(0.0, f64::max);
            if opts.base.is_none() && ctx.sizes[base] < opts.small_base_ratio * biggest_related {
                search.reject(
                    base,
                    &[],
                    format!(
                        "inactive base: {} is much smaller ({}) than a part it joins ({})",
                        ctx.names[base],
                        crate::math::format::number(ctx.sizes[base], 3),
                        crate::math::format::number(biggest_related, 3)
                    ),
                );
                continue;
            }
            search.dead.clear();
            let mut choices = Vec::new();
            search.dfs(base, bit(base), &mut choices, None, (0, 0, 0.0), pins, 0);
        }
    }
}

fn finish(
    ctx: &Ctx,
    found: Vec<Found>,
    mut rejected: Vec<Rejected>,
    before: Vec<Vec<u32>>,
    count: u32,
    cut: bool,
) -> Result<SequencePlan, SequenceError> {
    // The safe lengths of every straight task of the kept sequences, each distinct
    // one once and in parallel (the sequences then read them from the memo).
    let mut jobs: Vec<(usize, Vec3, Mask)> = Vec::new();
    let mut keys = HashSet::new();
    for f in &found {
        let mut mask = bit(f.base);
        for ch in &f.choices {
            if ch.planned.is_none() && keys.insert(ctx.safe_length_key(ch.part, &ch.leave, mask)) {
                jobs.push((ch.part, ch.leave, mask));
            }
            mask |= bit(ch.part);
        }
    }
    jobs.par_iter().for_each(|(p, d, mask)| {
        ctx.safe_length(*p, d, *mask);
    });
    let mut sequences = Vec::new();
    for f in &found {
        match build_sequence(ctx, f) {
            Ok(s) => sequences.push(s),
            Err(reason) => {
                if rejected.len() < MAX_REJECTED {
                    rejected.push(Rejected {
                        order: std::iter::once(f.base)
                            .chain(f.choices.iter().map(|c| c.part))
                            .map(|i| ctx.names[i].clone())
                            .collect(),
                        reason,
                    });
                }
            }
        }
    }
    if sequences.is_empty() {
        return Err(SequenceError::NoSequence {
            timed_out: ctx.out_of_time(),
            reasons: rejected
                .iter()
                .take(4)
                .map(|r| format!("after [{}]: {}", r.order.join(", "), r.reason))
                .collect(),
        });
    }
    sequences.sort_by(|a, b| {
        (a.mounts, a.direction_changes)
            .cmp(&(b.mounts, b.direction_changes))
            .then(a.path_length_mm.total_cmp(&b.path_length_mm))
    });
    // Precedence: a before b in every complete sequence seen, transitively reduced.
    let n = ctx.n;
    let rel = |a: usize, b: usize| count > 0 && before[a][b] == count;
    let mut precedence = Vec::new();
    for a in 0..n {
        for b in 0..n {
            if a != b && rel(a, b) && !(0..n).any(|c| c != a && c != b && rel(a, c) && rel(c, b)) {
                precedence.push((ctx.names[a].clone(), ctx.names[b].clone()));
            }
        }
    }
    Ok(SequencePlan {
        mode: ctx.opts.mode,
        sequences,
        rejected,
        precedence,
        complete: !cut,
        graph: ctx.graph.clone(),
        time_ms: ctx.started.elapsed().as_secs_f64() * 1e3,
        sweeps: ctx.sweeps.load(Ordering::Relaxed),
    })
}

/// `Vec3` of the component's candidate directions that are free among every other
/// component related to it (the seed's mating directions of a node; negated: the
/// direction the part moves while it is joined).
pub(crate) fn mating_directions_of(ctx: &Ctx, p: usize) -> Vec<Vec3> {
    let mask = ctx.related[p];
    ctx.free_dirs(p, mask)
        .into_iter()
        .map(|k| -ctx.dirs[p][k])
        .collect()
}

/// Related components of `p`.
pub(crate) fn related_of(ctx: &Ctx, p: usize) -> Mask {
    ctx.related[p]
}
