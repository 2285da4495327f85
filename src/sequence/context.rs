//! The context of one sequence search (seed 003 section 2.1): the components, their
//! boxes and sizes, the relation graph, the candidate directions and the blocking
//! they meet, the time budget; component sets as bit masks. Units: millimetres and
//! radians, assembly frame.

use super::graph::{Freedom, RelationGraph};
use super::options::{
    Mode, SequenceError, SequenceOptions, Stuck, DEFAULT_SEQUENCE_TIME_LIMIT_MS, MAX_COMPONENTS,
};
use super::task::Grasp;
use crate::collision::Aabb;
use crate::document::Document;
use crate::math::{Transform, Vec3};
use crate::workspace::{Scene, SceneCache, WorkspaceError};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::AtomicUsize;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The longest piece of a blocking sweep (mm): past the point where the boxes first
/// meet, the pieces grow from half the probe length to this, and the deadline is read
/// between them.
pub(super) const SWEEP_PIECE_MM: f64 = 10.0;

/// The longest piece of a sweep between two parts over [`PIECE_TRIANGLES`] each (mm).
pub(super) const LARGE_SWEEP_PIECE_MM: f64 = 2.0;

/// Parts with more triangles than this sweep each other in pieces of at most
/// [`LARGE_SWEEP_PIECE_MM`].
pub(super) const PIECE_TRIANGLES: usize = 1_000;

pub(super) type Mask = u128;

/// The share of the time limit the work may use: the rest (3 %) is kept for what
/// is in flight when the deadline passes (a sweep piece, an exact query, on a
/// loaded machine) and for returning, so the call ends within its limit.
pub(super) const DEADLINE_SHARE: f64 = 0.97;

/// The share of the time limit after which the search stops: what is left builds
/// the answer (safe lengths and grasps of the sequences kept) before the deadline.
pub(super) const SEARCH_SHARE: f64 = 0.9;

/// Triangles per batch of trees built (the deadline is read between batches; a
/// batch of this size takes tens of ms).
const TREE_BATCH_TRIANGLES: usize = 50_000;

/// Triangles of the first batch of trees (smallest meshes first), whose time
/// predicts the rest's: enough that a tree's fixed costs do not dominate it.
const FIRST_BATCH_TRIANGLES: usize = 1_000;

pub(super) fn bit(i: usize) -> Mask {
    1u128 << i
}

pub(crate) fn members_of(m: Mask) -> impl Iterator<Item = usize> {
    members(m)
}

/// The members of `m`, ascending (one step per member, not per bit).
pub(super) fn members(m: Mask) -> impl Iterator<Item = usize> {
    let mut rest = m;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            i
        })
    })
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
    /// The product: the components sequenced (robot links and excluded ones are
    /// not; they are ignored, neither moved nor obstacles).
    pub active: Mask,
    /// Per component: the product's components it touches within the contact gap
    /// (the support relation).
    pub touching: Vec<Mask>,
    /// Tight fits found, by part, mating direction and the placed parts near it.
    pub(super) tight: Mutex<HashMap<SafeKey, bool>>,
    /// Per component: the product's components whose boxes its box grown by
    /// `tight_clearance_mm` meets (the only ones a tight-fit probe can hit).
    pub(super) tight_near: Vec<Mask>,
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
    /// The blocking graph as far as it is swept (see [`Ctx::blockers_in`]).
    pub(super) blocking: Mutex<Blocking>,
    pub step: f64,
    /// The one deadline of the call (every check reads it).
    pub deadline: Instant,
    /// When the search stops ([`SEARCH_SHARE`] of the limit, or the deadline when
    /// the search starts later): the rest of the budget builds the answer.
    pub search_deadline: Instant,
    pub started: Instant,
    /// Blocking sweeps run (counted from the parallel sweeps).
    pub sweeps: AtomicUsize,
    /// Safe lengths found, by part, direction and the assembled parts that matter.
    pub(super) safe_lengths: Mutex<HashMap<SafeKey, f64>>,
    /// Grasps found, by part, mating direction, free directions and the assembled
    /// parts the fingers can reach.
    pub(super) grasps: Mutex<HashMap<GraspKey, Option<Grasp>>>,
}

/// The directional blocking graph as far as it is known: per component `p` and
/// direction `k`, the components found to hit `p` moving along `dirs[p][k]`
/// (`hit`) and those swept at all (`known`).
#[derive(Default)]
pub(super) struct Blocking {
    pub hit: Vec<Vec<Mask>>,
    pub known: Vec<Vec<Mask>>,
}

/// Sweeps between two parts with more triangles than this each are run only when
/// the search needs their answer (see [`Ctx::build_blocking`]).
pub(super) const LAZY_TRIANGLES: usize = 20_000;

/// The key of [`Ctx::safe_lengths`]: part, direction bits, the parts that matter.
pub(super) type SafeKey = (usize, [u64; 3], Mask);

/// The key of [`Ctx::grasps`].
pub(super) type GraspKey = (usize, [u64; 3], Vec<[u64; 3]>, Mask);

/// The bits of a direction, for exact-match memo keys.
pub(super) fn dir_key(d: &Vec3) -> [u64; 3] {
    [d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]
}

pub(super) fn same_dir(a: &Vec3, b: &Vec3) -> bool {
    (a - b).norm() < 1e-6
}

pub(super) fn push_dir(v: &mut Vec<Vec3>, d: Vec3) {
    if d.norm() < 1e-9 {
        return;
    }
    let d = d.normalize();
    if !v.iter().any(|e| same_dir(e, &d)) {
        v.push(d);
    }
}

pub(super) fn axis_dirs() -> [Vec3; 6] {
    [
        Vec3::x(),
        -Vec3::x(),
        Vec3::y(),
        -Vec3::y(),
        Vec3::z(),
        -Vec3::z(),
    ]
}

pub(super) fn union_box(boxes: &[Aabb], m: Mask) -> Option<Aabb> {
    members(m)
        .map(|i| boxes[i])
        .reduce(|a, b| Aabb::new(a.lo.inf(&b.lo), a.hi.sup(&b.hi)))
}

pub(super) fn diag(b: &Aabb) -> f64 {
    (b.hi - b.lo).norm()
}

/// How far `b` must move along unit `d` to leave `region` (mm, ≥ 0).
pub(super) fn exit_distance(b: &Aabb, region: &Aabb, d: &Vec3) -> f64 {
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
pub(super) fn entry_distance(b: &Aabb, region: &Aabb, d: &Vec3, slack: f64) -> f64 {
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

pub(super) fn boxes_meet(a: &Aabb, b: &Aabb, slack: f64) -> bool {
    a.overlap(b).min() > -slack
}

/// The product's components as a mask: `components` when given (naming a component
/// marked `fixture` takes it in), else every component but robot links, components
/// the document marks `fixture: true`, and `exclude`.
fn product_mask(doc: &Document, opts: &SequenceOptions) -> Result<Mask, SequenceError> {
    let n = doc.components().len();
    let index = |name: &String| doc.component_index(name).map_err(WorkspaceError::from);
    if !opts.components.is_empty() {
        let mut m: Mask = 0;
        for name in &opts.components {
            m |= bit(index(name)?);
        }
        for name in &opts.exclude {
            m &= !bit(index(name)?);
        }
        return Ok(m);
    }
    let mut m: Mask = if n == 128 { !0 } else { bit(n) - 1 };
    for r in doc.robots() {
        for l in r.links() {
            if let Some(c) = l.component {
                m &= !bit(c);
            }
        }
    }
    for (i, c) in doc.components().iter().enumerate() {
        if c.fixture {
            m &= !bit(i);
        }
    }
    for name in &opts.exclude {
        m &= !bit(index(name)?);
    }
    if m == 0 {
        return Err(SequenceError::Empty);
    }
    Ok(m)
}

/// The pairs of product components `(a, b)`, `a < b`, that touch within
/// `contact_gap_mm`: pairs whose surfaces are at most the gap apart (0 for surfaces
/// that meet; searched only where the boxes are that close; skipped once the
/// deadline has passed). The assembled pose is known free of interference, so no
/// part lies inside another.
fn touching_pairs(
    scene: &Scene,
    boxes: &[Aabb],
    active: Mask,
    opts: &SequenceOptions,
    deadline: Instant,
) -> Vec<(usize, usize)> {
    let gap = opts.contact_gap_mm;
    let mut pairs = Vec::new();
    for a in members(active) {
        for b in members(active).filter(|&b| b > a) {
            if boxes_meet(&boxes[a], &boxes[b], gap + 1e-9) {
                pairs.push((a, b));
            }
        }
    }
    // "Within the gap?" only: the distance search stops at the first pair of
    // triangles nearer than the gap (the exact clearance of two parts seated in
    // each other walks every facet pair along the seat: seconds on fine meshes).
    let near: Vec<bool> = pairs
        .par_iter()
        .map(|&(a, b)| {
            Instant::now() < deadline
                && crate::collision::surface_distance(
                    &scene.colliders[a],
                    &scene.poses[a],
                    &scene.colliders[b],
                    &scene.poses[b],
                    gap + 1e-6,
                )
                // The search returns the first distance below its stop, not the
                // least: compare against the same stop.
                .is_ok_and(|d| d < gap + 1e-6)
        })
        .collect();
    pairs
        .into_iter()
        .zip(near)
        .filter(|p| p.1)
        .map(|p| p.0)
        .collect()
}

impl<'d> Ctx<'d> {
    pub fn new(
        doc: &'d Document,
        cache: &mut SceneCache,
        opts: &SequenceOptions,
    ) -> Result<Ctx<'d>, SequenceError> {
        let started = Instant::now();
        let mut opts = opts.clone();
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
        if !(opts.contact_gap_mm.is_finite() && opts.contact_gap_mm >= 0.0) {
            return bad(
                "contact_gap_mm",
                opts.contact_gap_mm,
                "a finite number of mm ≥ 0",
            );
        }
        if !(opts.tight_clearance_mm.is_finite() && opts.tight_clearance_mm >= 0.0) {
            return bad(
                "tight_clearance_mm",
                opts.tight_clearance_mm,
                "a finite number of mm ≥ 0",
            );
        }
        if opts.sphere_directions > 4096 {
            return bad(
                "sphere_directions",
                opts.sphere_directions as f64,
                "at most 4096",
            );
        }
        if let Some(g) = opts.gravity {
            if !(g.iter().all(|v| v.is_finite()) && g.norm() > 1e-12) {
                return Err(SequenceError::InvalidOption {
                    option: "gravity",
                    value: format!("{:?}", g.as_slice()),
                    expected: "a finite non-zero down direction",
                });
            }
            opts.gravity = Some(g.normalize());
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
        let active = product_mask(doc, &opts)?;
        for name in opts.base.iter().chain(&opts.order) {
            let i = doc.component_index(name).map_err(WorkspaceError::from)?;
            if active & bit(i) == 0 {
                return Err(SequenceError::InvalidOption {
                    option: "base/order",
                    value: name.clone(),
                    expected: "a component of the product (not a robot link or excluded)",
                });
            }
        }
        // Without mates among the product's components the mates mode has nothing
        // to go on (every part would look unrelated): the geometry decides.
        if opts.mode == Mode::Mates
            && !doc
                .mates()
                .iter()
                .any(|m| m.entities.iter().all(|e| active & bit(e.component) != 0))
        {
            opts.mode = Mode::Geometry;
        }
        let deadline = started + Duration::from_secs_f64(limit.min(1e9) / 1e3 * DEADLINE_SHARE);
        // The setup reads the one deadline too: between the batches of trees built,
        // and after each of its phases (a budget spent there is reported as such).
        let spent = || -> Result<(), SequenceError> {
            if Instant::now() >= deadline {
                Err(SequenceError::TimeLimit(limit))
            } else {
                Ok(())
            }
        };
        let mut batch: Vec<&std::sync::Arc<crate::mesh::Mesh>> = Vec::new();
        let mut batch_tris = 0;
        // Smallest meshes first, the first batch as soon as it holds
        // FIRST_BATCH_TRIANGLES: the time it takes per triangle predicts the next
        // batches', and a batch that cannot end before the deadline
        // is not started (the call could only run out of time in it; one large
        // mesh takes 0.1–1 s on a loaded machine).
        let (trees_started, mut built) = (Instant::now(), 0usize);
        let mut by_size: Vec<usize> = (0..n).collect();
        by_size.sort_by_key(|&i| doc.mesh_of(i).triangles.len());
        for (k, &i) in by_size.iter().enumerate() {
            let mesh = doc.mesh_of(i);
            batch.push(mesh);
            batch_tris += mesh.triangles.len();
            if batch_tris >= TREE_BATCH_TRIANGLES
                || (built == 0 && batch_tris >= FIRST_BATCH_TRIANGLES)
                || k + 1 == n
            {
                spent()?;
                if built > 0 {
                    let per = trees_started.elapsed().as_secs_f64() / built as f64;
                    if Instant::now() + Duration::from_secs_f64(per * batch_tris as f64) > deadline
                    {
                        return Err(SequenceError::TimeLimit(limit));
                    }
                }
                cache.colliders(&batch).map_err(WorkspaceError::from)?;
                built += batch_tris;
                batch.clear();
                batch_tris = 0;
            }
        }
        let scene = Scene::new(doc, cache)?;
        spent()?;
        let names: Vec<String> = doc.components().iter().map(|c| c.name.clone()).collect();
        let mut boxes = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            if doc.mesh_of(i).vertices.is_empty() {
                return Err(WorkspaceError::EmptyMesh(name.clone()).into());
            }
            boxes.push(scene.colliders[i].world_bounds(&scene.poses[i]));
        }
        let sizes = component_sizes(doc, &opts);
        // The assembled state must be free of interference (among the product: a
        // robot's adjacent links may overlap, they are not sequenced).
        // Pair by pair in parallel, each query stopping at the deadline (parts
        // seated in each other over fine facets take seconds a pair).
        let mut near = Vec::new();
        for a in members(active) {
            for b in members(active).filter(|&b| b > a) {
                if boxes_meet(&boxes[a], &boxes[b], opts.tolerance) {
                    near.push((a, b));
                }
            }
        }
        let verdicts: Vec<Option<bool>> = near
            .par_iter()
            .map(|&(a, b)| {
                if Instant::now() >= deadline {
                    return Ok(None);
                }
                crate::collision::interferes_until(
                    &scene.colliders[a],
                    &scene.poses[a],
                    &scene.colliders[b],
                    &scene.poses[b],
                    opts.tolerance,
                    deadline,
                )
            })
            .collect::<Result<_, _>>()
            .map_err(WorkspaceError::from)?;
        if let Some(&(a, b)) = near
            .iter()
            .zip(&verdicts)
            .find(|(_, v)| **v == Some(true))
            .map(|(p, _)| p)
        {
            // The depth for the message: one full query, on the error path only,
            // within what is left of the budget (unknown when it runs out).
            let depth = crate::collision::contact_until(
                &scene.colliders[a],
                &scene.poses[a],
                &scene.colliders[b],
                &scene.poses[b],
                opts.tolerance,
                deadline,
            )
            .ok()
            .flatten()
            .map(|c| c.depth());
            return Err(SequenceError::AssembledInterference {
                a: names[a].clone(),
                b: names[b].clone(),
                depth,
            });
        }
        // An interference found is the answer even when another pair ran out of time.
        if verdicts.iter().any(Option::is_none) {
            return Err(SequenceError::TimeLimit(limit));
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
                for (a, b) in touching_pairs(&scene, &boxes, active, &opts, deadline) {
                    related[a] |= bit(b);
                    related[b] |= bit(a);
                }
                for (a, &rel) in related.iter().enumerate() {
                    for b in members(rel).filter(|&b| b > a) {
                        let f = Freedom {
                            frame: Transform::IDENTITY,
                            translations: Vec::new(),
                            rotations: Vec::new(),
                        };
                        graph.relations.push(super::graph::Relation {
                            a,
                            b,
                            mates: Vec::new(),
                            freedoms: Vec::new(),
                            freedom: f,
                        });
                    }
                }
            }
        }
        spent()?;
        // Mates with a component outside the product relate nothing.
        for (i, r) in related.iter_mut().enumerate() {
            *r &= active;
            if active & bit(i) == 0 {
                *r = 0;
            }
        }
        // Support: touching within the contact gap (geometry mode: the relations).
        let touching = match opts.mode {
            Mode::Geometry => related.clone(),
            Mode::Mates if opts.support => {
                let mut t = vec![0 as Mask; n];
                for (a, b) in touching_pairs(&scene, &boxes, active, &opts, deadline) {
                    t[a] |= bit(b);
                    t[b] |= bit(a);
                }
                t
            }
            Mode::Mates => related.clone(),
        };
        let step = if opts.step_mm > 0.0 {
            opts.step_mm
        } else {
            let smallest = boxes.iter().map(diag).fold(f64::INFINITY, f64::min);
            (0.01 * smallest).clamp(0.05, 2.0)
        };
        let c = opts.tight_clearance_mm;
        let tight_near: Vec<Mask> = boxes
            .iter()
            .map(|bp| {
                let grown = Aabb::new(bp.lo - Vec3::repeat(c), bp.hi + Vec3::repeat(c));
                members(active)
                    .filter(|&q| boxes_meet(&grown, &boxes[q], opts.tolerance))
                    .fold(0, |a, q| a | bit(q))
            })
            .collect();
        let mut ctx = Ctx {
            doc,
            tight_near,
            scene,
            opts,
            n,
            active,
            touching,
            tight: Mutex::new(HashMap::new()),
            names,
            boxes,
            sizes,
            graph,
            related,
            dirs: Vec::new(),
            blocking: Mutex::new(Blocking::default()),
            step,
            deadline,
            search_deadline: started + Duration::from_secs_f64(limit.min(1e9) / 1e3 * SEARCH_SHARE),
            started,
            sweeps: AtomicUsize::new(0),
            safe_lengths: Mutex::new(HashMap::new()),
            grasps: Mutex::new(HashMap::new()),
        };
        // Independent per component (the contact normals walk the meshes): parallel.
        let this = &ctx;
        let dirs: Vec<Vec<Vec3>> = (0..n)
            .into_par_iter()
            .map(|i| {
                if active & bit(i) != 0 {
                    this.candidate_directions(i)
                } else {
                    Vec::new()
                }
            })
            .collect();
        ctx.dirs = dirs;
        spent()?;
        ctx.build_blocking();
        // Sweeps the deadline cut count as blocked; with no time left there is
        // nothing to search: say so.
        spent()?;
        ctx.extend_directions();
        spent()?;
        ctx.order_composites();
        Ok(ctx)
    }

    /// The order a composite node implies (seed 003 section 2.1 step 3), from the
    /// blocking graph: taken apart member by member (the first member, the node's
    /// base, stays), each time one that can leave the others straight, the latest
    /// in the loop-breaking order first; assembly is the reverse. A stack on a shaft
    /// (bushing, gear, washer, cap) so comes out bottom-up whatever the sizes say.
    /// Members that cannot be taken apart keep their loop-breaking order.
    pub(super) fn order_composites(&mut self) {
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

    /// The product's components not in `mask`, ascending.
    pub(super) fn todo(&self, mask: Mask) -> impl Iterator<Item = usize> {
        members(self.active & !mask)
    }

    /// Whether `p` may go in moving along `mate` (unit) by the gravity rule: down or
    /// sideways, never up.
    pub(super) fn gravity_allows(&self, mate: &Vec3) -> bool {
        self.opts.gravity.is_none_or(|g| mate.dot(&g) > -1e-6)
    }

    /// Whether inserting `p` along `mate` (unit) onto `mask` is a tight fit: moved
    /// `tight_clearance_mm` sideways in its assembled pose it hits a placed part in
    /// at least three of the four directions across `mate` (held all round, a bore;
    /// a part in a slot or on a face is not). Memoised by the placed parts near it.
    pub(super) fn tight(&self, p: usize, mate: &Vec3, mask: Mask) -> bool {
        let c = self.opts.tight_clearance_mm;
        if c <= 0.0 {
            return false;
        }
        let near = self.tight_near[p] & mask;
        if near == 0 {
            return false;
        }
        let key = (p, dir_key(mate), near);
        if let Some(&t) = self.tight.lock().unwrap().get(&key) {
            return t;
        }
        // Past the deadline an unknown fit counts as easy (not remembered).
        if self.out_of_time() {
            return false;
        }
        let helper = if mate.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        let u = mate.cross(&helper).normalize();
        let v = mate.cross(&u);
        let start = self.scene.poses[p];
        let hits = [u, -u, v, -v]
            .iter()
            .filter(|e| {
                let at = start.then(&Transform::from_translation(*e * c));
                self.pose_hits(p, &at, near)
            })
            .count();
        let t = hits >= 3;
        self.tight.lock().unwrap().insert(key, t);
        t
    }

    /// Whether `p` placed onto `mask` is held: it touches (within the contact gap) a
    /// placed part, or support is off.
    pub(super) fn supported(&self, p: usize, mask: Mask) -> bool {
        !self.opts.support || self.touching[p] & mask != 0
    }

    pub fn out_of_time(&self) -> bool {
        Instant::now() >= self.deadline
    }

    /// Whether the search must stop (see [`Ctx::search_deadline`]).
    pub(super) fn search_out_of_time(&self) -> bool {
        Instant::now() >= self.search_deadline
    }

    /// What is left of the search's time (ms).
    pub(super) fn search_remaining_ms(&self) -> f64 {
        self.search_deadline
            .saturating_duration_since(Instant::now())
            .as_secs_f64()
            * 1e3
    }

    pub(super) fn node_index(&self, c: usize) -> usize {
        self.graph.node_of(c)
    }

    pub(super) fn group_of(&self, c: usize) -> Mask {
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

    pub(super) fn node_size(&self, node: usize) -> f64 {
        self.graph.nodes[node]
            .members
            .iter()
            .map(|&m| self.sizes[m])
            .sum()
    }

    /// Whether `p` may be assembled next onto `mask` (seed 003 section 2.2: nodes in
    /// the relation graph, composite nodes in their implied order).
    pub(super) fn eligible(&self, p: usize, mask: Mask) -> bool {
        if !self.supported(p, mask) {
            return false;
        }
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
        // Support off in geometry mode: a part may be placed where nothing holds it.
        if self.opts.mode == Mode::Geometry && !self.opts.support {
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

    pub(super) fn why_not(&self, p: usize, mask: Mask) -> Stuck {
        let part = self.names[p].clone();
        if !self.supported(p, mask) {
            return Stuck::Floats {
                part,
                gap_mm: self.opts.contact_gap_mm,
            };
        }
        if !self.eligible(p, mask) {
            let node = &self.graph.nodes[self.node_index(p)];
            let pos = node.members.iter().position(|&m| m == p).unwrap_or(0);
            if pos > 0 {
                return Stuck::WaitsFor {
                    part,
                    before: self.names[node.members[pos - 1]].clone(),
                };
            }
            return Stuck::NothingToGoOnto { part };
        }
        let mut by: Mask = 0;
        for k in 0..self.dirs[p].len() {
            by |= self.blockers_in(p, k, mask, true);
        }
        Stuck::Blocked {
            part,
            directions: self.dirs[p].len(),
            by: members(by).map(|i| self.names[i].clone()).collect(),
        }
    }
}
