//! The context of one sequence search (seed 003 section 2.1): the components, their
//! boxes and sizes, the relation graph, the candidate directions and the blocking
//! they meet, the time budget; component sets as bit masks. Units: millimetres and
//! radians, assembly frame.

use super::graph::RelationGraph;
use super::options::{Mode, SequenceError, SequenceOptions, Stuck};
use super::setup::Setup;
pub(super) use super::setup::{bit, boxes_meet, component_sizes, diag, members, members_of, Mask};
use super::task::Grasp;
use crate::document::Document;
use crate::math::{Aabb, Deadline, Transform, Vec3};
use crate::workspace::{Scene, SceneCache};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::AtomicUsize;
use std::sync::Mutex;
use std::time::Instant;

/// The longest piece of a blocking sweep (mm): past the point where the boxes first
/// meet, the pieces grow from half the probe length to this, and the deadline is read
/// between them.
pub(super) const SWEEP_PIECE_MM: f64 = 10.0;

/// The longest piece of a sweep between two parts over [`PIECE_TRIANGLES`] each (mm).
pub(super) const LARGE_SWEEP_PIECE_MM: f64 = 2.0;

/// Parts with more triangles than this sweep each other in pieces of at most
/// [`LARGE_SWEEP_PIECE_MM`].
pub(super) const PIECE_TRIANGLES: usize = 1_000;

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
    /// Per component: its group of the support relation, the parts it is connected
    /// to through touching pairs in the finished product. A product whose parts
    /// form several groups (parts the file places apart, held by a frame or fixture
    /// it leaves out) is held together by nothing modelled: the first part placed of
    /// each group needs no support, every other part does.
    pub support_groups: Vec<Mask>,
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
    pub deadline: Deadline,
    /// When the search stops ([`SEARCH_SHARE`](super::setup::SEARCH_SHARE) of the limit, or the deadline when
    /// the search starts later): the rest of the budget builds the answer.
    pub search_deadline: Deadline,
    pub started: Instant,
    /// Blocking sweeps run (counted from the parallel sweeps).
    pub sweeps: AtomicUsize,
    /// Safe lengths found, by part, direction and the assembled parts that matter.
    pub(super) safe_lengths: Mutex<HashMap<SafeKey, f64>>,
    /// Grasps found, by part, mating direction, free directions and the assembled
    /// parts the fingers can reach.
    pub(super) grasps: Mutex<HashMap<GraspKey, Option<Grasp>>>,
    /// The interferences of the assembled pose, taken as fits.
    pub(super) fits: Vec<super::setup::FitPair>,
    /// The support links added across gaps wider than the contact gap.
    pub(super) support_gaps: Vec<((usize, usize), Option<f64>)>,
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
    crate::math::axis_directions()
}

pub(super) fn union_box(boxes: &[Aabb], m: Mask) -> Option<Aabb> {
    members(m)
        .map(|i| boxes[i])
        .reduce(|a, b| Aabb::new(a.lo.inf(&b.lo), a.hi.sup(&b.hi)))
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

impl<'d> Ctx<'d> {
    /// Checks the options and builds the setup ([`Setup::build`]), then what the
    /// search reads from the geometry: candidate directions per component, the
    /// blocking graph (as far as it is swept up front), the extra directions and the
    /// order within composite nodes.
    pub fn new(
        doc: &'d Document,
        cache: &mut SceneCache,
        opts: &SequenceOptions,
    ) -> Result<Ctx<'d>, SequenceError> {
        let setup = Setup::build(doc, cache, opts)?;
        let budget = setup.budget;
        let (n, active) = (setup.n, setup.active);
        let mut ctx = Ctx {
            doc,
            fits: setup.fits,
            support_gaps: setup.support_gaps,
            tight_near: setup.tight_near,
            scene: setup.scene,
            opts: setup.opts,
            n,
            active,
            touching: setup.touching,
            support_groups: setup.support_groups,
            tight: Mutex::new(HashMap::new()),
            names: setup.names,
            boxes: setup.boxes,
            sizes: setup.sizes,
            graph: setup.graph,
            related: setup.related,
            dirs: Vec::new(),
            blocking: Mutex::new(Blocking::default()),
            step: setup.step,
            deadline: budget.deadline,
            search_deadline: budget.search_deadline,
            started: budget.started,
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
        budget.check()?;
        ctx.build_blocking();
        // Sweeps the deadline cut count as blocked; with no time left there is
        // nothing to search: say so.
        budget.check()?;
        ctx.extend_directions();
        budget.check()?;
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

    /// The spacing (mm) of the lines of the checks between fit pairs, and the
    /// step of the turning edges among them: twice the safe-length step, 0.1 to 1 mm.
    pub(super) fn fit_step(&self) -> f64 {
        (2.0 * self.step).clamp(0.1, 1.0)
    }

    /// The check of `p` moving against `q` when the two have a fit.
    pub(super) fn fit_check(&self, p: usize, q: usize) -> Option<super::fit::FitPairCheck> {
        let fit = self.fit(p, q)?;
        Some(super::fit::FitPairCheck {
            slides: fit.depth <= self.opts.slide_fit_mm,
            p: self.scene.colliders[p].clone(),
            p_home: self.scene.poses[p],
            q: self.scene.colliders[q].clone(),
            q_pose: self.scene.poses[q],
            p_carved: carved_first(self.doc.mesh_of(p), self.doc.mesh_of(q), p < q),
            spacing: self.fit_step(),
            tolerance: self.opts.tolerance,
        })
    }

    /// The fit of `p` and `q` when they have one.
    pub(super) fn fit(&self, p: usize, q: usize) -> Option<&super::setup::FitPair> {
        self.fits
            .iter()
            .find(|f| (f.a, f.b) == (p.min(q), p.max(q)))
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
        let (u, v) = crate::math::frame_across(mate);
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
    /// placed part, or it is the first placed of its support group (nothing of the
    /// product touches that group in the finished product either), or support is off.
    pub(super) fn supported(&self, p: usize, mask: Mask) -> bool {
        !self.opts.support
            || self.touching[p] & mask != 0
            || self.support_groups[p] & mask & !super::setup::bit(p) == 0
    }

    /// Whether the call's deadline has passed.
    pub fn out_of_time(&self) -> bool {
        self.deadline.passed()
    }

    /// Whether the search must stop (see [`Ctx::search_deadline`]).
    pub(super) fn search_out_of_time(&self) -> bool {
        self.search_deadline.passed()
    }

    /// What is left of the search's time (ms).
    pub(super) fn search_remaining_ms(&self) -> f64 {
        self.search_deadline.remaining().as_secs_f64() * 1e3
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
        self.blocked(p, mask)
    }

    /// Why `p` cannot go in straight onto `mask`: every candidate direction with
    /// what blocks it, the least blocked one named.
    pub(super) fn blocked(&self, p: usize, mask: Mask) -> Stuck {
        let part = self.names[p].clone();
        let mut by: Mask = 0;
        let mut least: Option<(usize, Mask)> = None;
        for k in 0..self.dirs[p].len() {
            let m = self.blockers_in(p, k, mask, true);
            by |= m;
            if least.is_none_or(|(_, l)| m.count_ones() < l.count_ones()) {
                least = Some((k, m));
            }
        }
        let (k, least_by) = least.unwrap_or((0, 0));
        let d = self.dirs[p].get(k).copied().unwrap_or_else(Vec3::zeros);
        let names = |m: Mask| members(m).map(|i| self.names[i].clone()).collect();
        Stuck::Blocked {
            part,
            directions: self.dirs[p].len(),
            by: names(by),
            least: ([d.x, d.y, d.z], names(least_by)),
            in_contact: least_by != 0 && least_by & !self.touching[p] == 0,
            tolerance: self.opts.tolerance,
            deflection: self.doc.mesh_deflection(),
            deep_fits: members(least_by)
                .filter_map(|q| {
                    let f = self.fit(p, q)?;
                    (f.depth > self.opts.slide_fit_mm).then(|| (self.names[q].clone(), f.depth))
                })
                .collect(),
            slide_fit_mm: self.opts.slide_fit_mm,
        }
    }
}

/// Whether `a` is the part of a fit that is carved (see `fit.rs`): the larger by
/// volume; equal volumes: the first in document order (`a_first`).
pub(super) fn carved_first(a: &crate::mesh::Mesh, b: &crate::mesh::Mesh, a_first: bool) -> bool {
    let (va, vb) = (a.signed_volume().abs(), b.signed_volume().abs());
    va > vb || (va == vb && a_first)
}
