//! The setup of one sequence search, built before the search starts (validate, then
//! build, as ripgrep turns its flags into a checked configuration before it
//! searches): the options checked, the product, the call's deadlines, the colliders
//! and the scene, the assembled state checked free of interference, the relations and
//! contacts, the step of the safe-length search. Units: millimetres and radians,
//! assembly frame.

use super::graph::{Freedom, Node, Relation, RelationGraph};
use super::options::{Mode, SequenceError, SequenceOptions, MAX_COMPONENTS};
use crate::document::Document;
use crate::math::{Aabb, Deadline, Transform, Vec3};
use crate::mesh::Mesh;
use crate::workspace::{GivenValue, Scene, SceneCache, WorkspaceError};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Triangles per batch of trees built (the deadline is read between batches; a
/// batch of this size takes tens of ms).
const TREE_BATCH_TRIANGLES: usize = 50_000;

/// Triangles of the first batch of trees (smallest meshes first), whose time
/// predicts the rest's: enough that a tree's fixed costs do not dominate it.
const FIRST_BATCH_TRIANGLES: usize = 1_000;

pub(super) type Mask = u128;

/// The share of the time limit the work may use: the rest (3 %) is kept for what
/// is in flight when the deadline passes (a sweep piece, an exact query, on a
/// loaded machine) and for returning, so the call ends within its limit.
pub(super) const DEADLINE_SHARE: f64 = 0.97;

/// The share of the time limit after which the search stops: what is left builds
/// the answer (safe lengths and grasps of the sequences kept) before the deadline.
pub(super) const SEARCH_SHARE: f64 = 0.9;

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

pub(super) fn diag(b: &Aabb) -> f64 {
    (b.hi - b.lo).norm()
}

pub(super) fn boxes_meet(a: &Aabb, b: &Aabb, slack: f64) -> bool {
    a.overlap(b).min() > -slack
}

/// The time budget of one call: when it started, its limit and its two deadlines.
#[derive(Debug, Clone, Copy)]
pub(super) struct Budget {
    /// When the call started.
    pub started: Instant,
    /// The limit (ms).
    pub limit_ms: f64,
    /// The one deadline every check reads ([`DEADLINE_SHARE`] of the limit).
    pub deadline: Deadline,
    /// When the search stops ([`SEARCH_SHARE`] of the limit).
    pub search_deadline: Deadline,
}

impl Budget {
    fn new(started: Instant, limit_ms: f64) -> Self {
        Budget {
            started,
            limit_ms,
            deadline: Deadline::share_of_ms(started, limit_ms, DEADLINE_SHARE),
            search_deadline: Deadline::share_of_ms(started, limit_ms, SEARCH_SHARE),
        }
    }

    /// [`SequenceError::TimeLimit`] once the deadline has passed: the setup reads it
    /// after each of its phases (a budget spent there is reported as such).
    pub fn check(&self) -> Result<(), SequenceError> {
        if self.deadline.passed() {
            Err(SequenceError::TimeLimit(self.limit_ms))
        } else {
            Ok(())
        }
    }
}

/// What the search starts from, computed once per call.
pub(super) struct Setup {
    /// The options as used: checked, gravity a unit vector, the mode the document
    /// allows.
    pub opts: SequenceOptions,
    pub budget: Budget,
    pub scene: Scene,
    pub n: usize,
    /// The product (see [`super::context::Ctx::active`]).
    pub active: Mask,
    pub names: Vec<String>,
    /// World boxes in the assembled pose.
    pub boxes: Vec<Aabb>,
    /// Size (mass or volume) per component.
    pub sizes: Vec<f64>,
    pub graph: RelationGraph,
    /// Related components (mates, or contacts in geometry mode), within the product.
    pub related: Vec<Mask>,
    /// The support relation (see [`super::context::Ctx::touching`]).
    pub touching: Vec<Mask>,
    /// Per component: its group of the support relation (see
    /// [`super::context::Ctx::support_groups`]).
    pub support_groups: Vec<Mask>,
    /// Per component: the product's components within `tight_clearance_mm` of its box.
    pub tight_near: Vec<Mask>,
    /// Step of the safe-length search (mm).
    pub step: f64,
    /// The interferences of the assembled pose, taken as fits.
    pub fits: Vec<FitPair>,
    /// The support links added across gaps wider than the contact gap: the pair and
    /// its surface distance (`None`: a mated pair).
    pub support_gaps: Vec<((usize, usize), Option<f64>)>,
}

/// An interference of the assembled pose taken as a fit: components `a < b`, the
/// least tolerance at which they count as touching (mm), and whether one lies
/// wholly inside the other.
#[derive(Debug, Clone, Copy)]
pub(super) struct FitPair {
    pub a: usize,
    pub b: usize,
    pub depth: f64,
    pub contained: bool,
}

/// The depth of the interference of `a` at `pa` and `b` at `pb` (mm): the least
/// penetration tolerance at which [`contact`](crate::collision::contact) calls the
/// pair touching — the deepest crossing of the surfaces and the deepest point of
/// one inside the other (a verdict reports the first of these it finds, so the
/// tolerance is raised to each depth found until the pair touches) — or, for a
/// solid wholly inside the other, its containment depth (`true`). `None`: the
/// deadline passed first.
pub(super) fn fit_depth(
    a: &crate::collision::Collider,
    pa: &Transform,
    b: &crate::collision::Collider,
    pb: &Transform,
    tolerance: f64,
    deadline: Instant,
) -> Result<Option<(f64, bool)>, crate::collision::CollisionError> {
    use crate::collision::{contact_until, Contact, InterferenceKind};
    let mut t = tolerance;
    // Each round raises the tolerance past the depth reported, which only a deeper
    // kind of witness can exceed: crossing, then the depth walk, then faces.
    for _ in 0..8 {
        match contact_until(a, pa, b, pb, t, deadline)? {
            None => return Ok(None),
            Some(Contact::Interfering {
                depth,
                kind: InterferenceKind::Contained { .. },
            }) => return Ok(Some((depth.max(t), true))),
            Some(Contact::Interfering { depth, .. }) => {
                t = depth.max(t) * (1.0 + 1e-9) + 1e-9;
            }
            Some(_) => return Ok(Some((t, false))),
        }
    }
    Ok(Some((t, false)))
}

/// The pairs of the product's components related by a mate, `(a, b)` with `a < b`.
fn mated_pairs(doc: &Document, active: Mask) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for m in doc.mates() {
        let cs: Vec<usize> = m.entities.iter().map(|e| e.component).collect();
        for (i, &a) in cs.iter().enumerate() {
            for &b in &cs[i + 1..] {
                if a != b && active & bit(a) != 0 && active & bit(b) != 0 {
                    out.push((a.min(b), a.max(b)));
                }
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

impl Setup {
    /// Checks the options, then builds everything the search reads.
    ///
    /// # Errors
    /// An option out of range, an empty or too large document, a base or order
    /// outside the product, an unusable mesh, components that interfere in the
    /// assembled pose, the time limit spent before the setup is done.
    pub fn build(
        doc: &Document,
        cache: &mut SceneCache,
        opts: &SequenceOptions,
    ) -> Result<Setup, SequenceError> {
        let started = Instant::now();
        let n = doc.components().len();
        if n == 0 {
            return Err(SequenceError::Empty);
        }
        if n > MAX_COMPONENTS {
            return Err(SequenceError::TooManyComponents(n));
        }
        let budget = Budget::new(started, opts.validate()?);
        let mut opts = opts.clone();
        opts.gravity = opts.gravity.map(|g| g.normalize());
        // Meshes tessellated from exact surfaces lie up to their deflection from
        // them: two facetings of one cylinder (a bolt in a bore of its diameter)
        // cross by up to that much, and by a varying amount as one slides along the
        // other, so a finer tolerance blocks what the CAD model leaves free.
        opts.tolerance = opts.tolerance.max(doc.mesh_deflection().unwrap_or(0.0));
        let active = product_mask(doc, &opts)?;
        check_pins(doc, &opts, active)?;
        opts.mode = mode_used(doc, &opts, active);
        build_colliders(doc, cache, &budget)?;
        let scene = Scene::new(doc, cache)?;
        budget.check()?;
        let names: Vec<String> = doc.components().iter().map(|c| c.name.clone()).collect();
        let mut boxes = Vec::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            // a component outside the product (a suppressed one's part may not be
            // loaded, its mesh empty) is neither moved nor an obstacle
            if active & bit(i) != 0 && doc.mesh_of(i).vertices.is_empty() {
                return Err(WorkspaceError::EmptyMesh(name.clone().into()).into());
            }
            boxes.push(scene.colliders[i].world_bounds(&scene.poses[i]));
        }
        let sizes = component_sizes(doc, &opts);
        let parts = Parts {
            scene: &scene,
            boxes: &boxes,
            active,
            opts: &opts,
            deadline: budget.deadline,
        };
        let fits = parts.fits(budget.limit_ms)?;
        budget.check()?;
        // The contact graph: touching within the gap, fits, and (connecting what
        // nothing within the gap connects) the closest links across wider gaps.
        let mut contacts = parts.touching_pairs();
        contacts.extend(fits.iter().map(|f| (f.a, f.b)));
        let mated = match opts.mode {
            Mode::Mates => mated_pairs(doc, active),
            Mode::Geometry => Vec::new(),
        };
        let support_gaps = parts.bridges(&contacts, &mated);
        budget.check()?;
        let mut contact_masks = vec![0 as Mask; n];
        for &(a, b) in contacts.iter().chain(support_gaps.iter().map(|g| &g.0)) {
            contact_masks[a] |= bit(b);
            contact_masks[b] |= bit(a);
        }
        let (graph, related) = parts.relations(doc, &names, &sizes, &contact_masks);
        budget.check()?;
        // Support: touching within the contact gap (geometry mode: the relations).
        let touching = match opts.mode {
            Mode::Mates if opts.support => contact_masks,
            _ => related.clone(),
        };
        let support_groups = groups_of(&touching, active);
        let step = if opts.step_mm > 0.0 {
            opts.step_mm
        } else {
            let smallest = boxes.iter().map(diag).fold(f64::INFINITY, f64::min);
            (0.01 * smallest).clamp(0.05, 2.0)
        };
        let tight_near = parts.tight_near();
        Ok(Setup {
            fits,
            support_gaps,
            opts,
            budget,
            scene,
            n,
            active,
            names,
            boxes,
            sizes,
            graph,
            related,
            touching,
            support_groups,
            tight_near,
            step,
        })
    }
}

/// Per component of `active`: the members of its connected group of the relation
/// `touching` (0 outside `active`). Parts of different groups touch nothing of each
/// other in the finished product.
fn groups_of(touching: &[Mask], active: Mask) -> Vec<Mask> {
    let mut group = vec![0 as Mask; touching.len()];
    for start in members(active) {
        if group[start] != 0 {
            continue;
        }
        let mut reached = bit(start);
        let mut frontier = bit(start);
        while frontier != 0 {
            let mut next = 0 as Mask;
            for i in members(frontier) {
                next |= touching[i] & active;
            }
            frontier = next & !reached;
            reached |= next;
        }
        for i in members(reached) {
            group[i] = reached;
        }
    }
    group
}

/// The base and the pinned order name components of the product.
fn check_pins(doc: &Document, opts: &SequenceOptions, active: Mask) -> Result<(), SequenceError> {
    for name in opts.base.iter().chain(&opts.order) {
        let i = doc.component_index(name).map_err(WorkspaceError::from)?;
        if active & bit(i) == 0 {
            return Err(SequenceError::InvalidOption {
                option: "base/order",
                value: GivenValue::Component(name.clone()),
                expected: "a component of the product (not a robot link or excluded)",
            });
        }
    }
    Ok(())
}

/// The mode the search uses: without mates among the product's components the mates
/// mode has nothing to go on (every part would look unrelated), and the geometry
/// decides.
fn mode_used(doc: &Document, opts: &SequenceOptions, active: Mask) -> Mode {
    let mated = doc
        .mates()
        .iter()
        .any(|m| m.entities.iter().all(|e| active & bit(e.component) != 0));
    if opts.mode == Mode::Mates && !mated {
        Mode::Geometry
    } else {
        opts.mode
    }
}

/// Builds every component's collision tree through `cache`, in batches between which
/// the deadline is read.
///
/// Smallest meshes first, the first batch as soon as it holds
/// [`FIRST_BATCH_TRIANGLES`]: the time it takes per triangle predicts the next
/// batches', and a batch that cannot end before the deadline is not started (the call
/// could only run out of time in it; one large mesh takes 0.1–1 s on a loaded
/// machine).
fn build_colliders(
    doc: &Document,
    cache: &mut SceneCache,
    budget: &Budget,
) -> Result<(), SequenceError> {
    let n = doc.components().len();
    let mut batch: Vec<&Arc<Mesh>> = Vec::new();
    let mut batch_tris = 0;
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
            budget.check()?;
            if built > 0 {
                let per = trees_started.elapsed().as_secs_f64() / built as f64;
                if !budget
                    .deadline
                    .fits(Duration::from_secs_f64(per * batch_tris as f64))
                {
                    return Err(SequenceError::TimeLimit(budget.limit_ms));
                }
            }
            cache.colliders(&batch).map_err(WorkspaceError::from)?;
            built += batch_tris;
            batch.clear();
            batch_tris = 0;
        }
    }
    Ok(())
}

/// The product's parts in their assembled poses, for the checks of the setup.
struct Parts<'a> {
    scene: &'a Scene,
    boxes: &'a [Aabb],
    active: Mask,
    opts: &'a SequenceOptions,
    deadline: Deadline,
}

impl Parts<'_> {
    /// The pairs of the product `(a, b)`, `a < b`, whose boxes meet within `slack`.
    fn near_pairs(&self, slack: f64) -> Vec<(usize, usize)> {
        let mut pairs = Vec::new();
        for a in members(self.active) {
            for b in members(self.active).filter(|&b| b > a) {
                if boxes_meet(&self.boxes[a], &self.boxes[b], slack) {
                    pairs.push((a, b));
                }
            }
        }
        pairs
    }

    /// The interferences of the assembled state among the product (a robot's
    /// adjacent links may overlap, they are not sequenced), each taken as a fit with
    /// its depth ([`fit_depth`]). Pair by pair in parallel, each query stopping at
    /// the deadline (parts seated in each other over fine facets take seconds a
    /// pair).
    fn fits(&self, limit_ms: f64) -> Result<Vec<FitPair>, SequenceError> {
        let (scene, tolerance) = (self.scene, self.opts.tolerance);
        let deadline = self.deadline.instant();
        let near = self.near_pairs(tolerance);
        let found: Vec<Option<Option<FitPair>>> = near
            .par_iter()
            .map(|&(a, b)| {
                if self.deadline.passed() {
                    return Ok(None);
                }
                let (ca, cb) = (&scene.colliders[a], &scene.colliders[b]);
                let (pa, pb) = (&scene.poses[a], &scene.poses[b]);
                match crate::collision::interferes_until(ca, pa, cb, pb, tolerance, deadline)? {
                    None => Ok(None),
                    Some(false) => Ok(Some(None)),
                    Some(true) => Ok(fit_depth(ca, pa, cb, pb, tolerance, deadline)?.map(
                        |(depth, contained)| {
                            Some(FitPair {
                                a,
                                b,
                                depth,
                                contained,
                            })
                        },
                    )),
                }
            })
            .collect::<Result<_, crate::collision::CollisionError>>()
            .map_err(WorkspaceError::from)?;
        if found.iter().any(Option::is_none) {
            return Err(SequenceError::TimeLimit(limit_ms));
        }
        Ok(found.into_iter().flatten().flatten().collect())
    }

    /// The relation graph and the related components (within the product): the
    /// mates' in mates mode, the contacts' in geometry mode.
    fn relations(
        &self,
        doc: &Document,
        names: &[String],
        sizes: &[f64],
        contacts: &[Mask],
    ) -> (RelationGraph, Vec<Mask>) {
        let n = names.len();
        let mut related = vec![0 as Mask; n];
        let graph = match self.opts.mode {
            Mode::Mates => {
                let graph = RelationGraph::build(doc, &|i| sizes[i]);
                for r in &graph.relations {
                    related[r.a] |= bit(r.b);
                    related[r.b] |= bit(r.a);
                }
                graph
            }
            Mode::Geometry => {
                related = contacts.to_vec();
                let mut relations = Vec::new();
                for (a, &rel) in related.iter().enumerate() {
                    for b in members(rel).filter(|&b| b > a) {
                        let freedom = Freedom {
                            frame: Transform::IDENTITY,
                            translations: Vec::new(),
                            rotations: Vec::new(),
                        };
                        relations.push(Relation {
                            a,
                            b,
                            mates: Vec::new(),
                            freedoms: Vec::new(),
                            freedom,
                        });
                    }
                }
                RelationGraph {
                    components: names.to_vec(),
                    relations,
                    nodes: (0..n).map(|i| Node { members: vec![i] }).collect(),
                    loops: Vec::new(),
                }
            }
        };
        // Mates with a component outside the product relate nothing.
        for (i, r) in related.iter_mut().enumerate() {
            *r &= self.active;
            if self.active & bit(i) == 0 {
                *r = 0;
            }
        }
        (graph, related)
    }

    /// The links that connect the product's contact graph (`contacts`: pairs that
    /// touch within the gap or fit) where it falls apart in groups: first the
    /// `mated` pairs joining two groups (mates mode: a mated part is held by its
    /// mate), then, Kruskal's way, the closest pairs of surfaces between groups
    /// (a clearance joint wider than the gap) no farther apart than half the
    /// thinner part's thinnest box extent (a part standing apart is not held). Each link joins two groups, so
    /// there are at most groups − 1, and none when the graph is connected.
    fn bridges(
        &self,
        contacts: &[(usize, usize)],
        mated: &[(usize, usize)],
    ) -> Vec<((usize, usize), Option<f64>)> {
        let n = self.boxes.len();
        let mut root: Vec<usize> = (0..n).collect();
        fn find(root: &mut [usize], mut i: usize) -> usize {
            while root[i] != i {
                root[i] = root[root[i]];
                i = root[i];
            }
            i
        }
        let mut groups = members(self.active).count();
        fn join(root: &mut [usize], groups: &mut usize, a: usize, b: usize) -> bool {
            let (ra, rb) = (find(root, a), find(root, b));
            if ra != rb {
                root[ra] = rb;
                *groups -= 1;
                true
            } else {
                false
            }
        }
        for &(a, b) in contacts {
            join(&mut root, &mut groups, a, b);
        }
        let mut out = Vec::new();
        for &(a, b) in mated {
            if join(&mut root, &mut groups, a, b) {
                out.push(((a, b), None));
            }
        }
        if groups <= 1 {
            return out;
        }
        // Pairs across groups with their box gaps (a lower bound of their surface
        // distance). Kruskal in rounds of a growing bound `t`: every pair whose box
        // gap is below `t` gets its distance when it is below `t` (the search
        // capped there), so when the links under `t` are taken in order, no pair
        // closer than the one taken is unknown.
        let scene = self.scene;
        let mut across: Vec<(f64, usize, usize, Option<f64>)> = Vec::new();
        for a in members(self.active) {
            for b in members(self.active).filter(|&b| b > a) {
                if find(&mut root, a) != find(&mut root, b) {
                    let gap = (-self.boxes[a].overlap(&self.boxes[b]).min()).max(0.0);
                    across.push((gap, a, b, None));
                }
            }
        }
        let first = across.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        let mut t = first.max(self.opts.contact_gap_mm).max(1e-3) * 2.0;
        let mut done = 0.0;
        // No link is longer than half the thickest part's thinnest extent.
        let longest = members(self.active)
            .map(|i| 0.5 * (self.boxes[i].hi - self.boxes[i].lo).min())
            .fold(0.0f64, f64::max);
        for _ in 0..64 {
            if groups <= 1 || self.deadline.passed() || done > longest {
                break;
            }
            let found: Vec<Option<f64>> = across
                .par_iter()
                .map(|&(gap, a, b, known)| {
                    if known.is_some() || gap >= t || self.deadline.passed() {
                        return known;
                    }
                    crate::collision::distance_lower_bound(
                        &scene.colliders[a],
                        &scene.poses[a],
                        &scene.colliders[b],
                        &scene.poses[b],
                        0.0,
                        t,
                        0.0,
                    )
                    .ok()
                    .filter(|&d| d < t)
                })
                .collect();
            for (p, d) in across.iter_mut().zip(found) {
                p.3 = d;
            }
            let mut round: Vec<(f64, usize, usize)> = across
                .iter()
                .filter_map(|&(_, a, b, d)| d.filter(|&d| d >= done).map(|d| (d, a, b)))
                .collect();
            round.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
            for (d, a, b) in round {
                // A joint's clearance, not a part standing apart: at most half
                // the thinner part's thinnest extent.
                let thin = |i: usize| (self.boxes[i].hi - self.boxes[i].lo).min();
                if d > 0.5 * thin(a).min(thin(b)) {
                    continue;
                }
                if groups > 1 && join(&mut root, &mut groups, a, b) {
                    out.push(((a, b), Some(d)));
                }
            }
            done = t;
            t *= 2.0;
        }
        out
    }

    /// The pairs of product components `(a, b)`, `a < b`, that touch within
    /// `contact_gap_mm`: pairs whose surfaces are at most the gap apart (0 for
    /// surfaces that meet; searched only where the boxes are that close; skipped once
    /// the deadline has passed). Pairs that interfere are fits (found before), so
    /// a part inside another without touching it is counted there.
    fn touching_pairs(&self) -> Vec<(usize, usize)> {
        let gap = self.opts.contact_gap_mm;
        let scene = self.scene;
        let pairs = self.near_pairs(gap + 1e-9);
        // "Within the gap?" only: the distance search stops at the first pair of
        // triangles nearer than the gap (the exact clearance of two parts seated in
        // each other walks every facet pair along the seat: seconds on fine meshes).
        let near: Vec<bool> = pairs
            .par_iter()
            .map(|&(a, b)| {
                !self.deadline.passed()
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

    /// Per component: the product's components whose boxes its box grown by
    /// `tight_clearance_mm` meets (the only ones a tight-fit probe can hit).
    fn tight_near(&self) -> Vec<Mask> {
        let c = self.opts.tight_clearance_mm;
        self.boxes
            .iter()
            .map(|bp| {
                let grown = Aabb::new(bp.lo - Vec3::repeat(c), bp.hi + Vec3::repeat(c));
                members(self.active)
                    .filter(|&q| boxes_meet(&grown, &self.boxes[q], self.opts.tolerance))
                    .fold(0, |a, q| a | bit(q))
            })
            .collect()
    }
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
        for (i, c) in doc.components().iter().enumerate() {
            if c.is_suppressed() {
                m &= !bit(i);
            }
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
        if c.fixture || c.is_suppressed() {
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
