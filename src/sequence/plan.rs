//! Seed 003 section 2.1 steps 5–6 and section 2.2: the sequence search over the
//! blocking graph (`blocking.rs`) with base choice, mount counting and planned
//! insertions (`paths.rs`) where no straight line is free, then the tasks of the
//! sequences found. Units: millimetres and radians, assembly frame.

use super::context::*;
use super::grasp::find_grasp;
use super::options::{
    Fit, RejectReason, Rejected, Sequence, SequenceError, SequenceOptions, SequencePlan, StepInfo,
    SupportGap,
};
use super::task::{Operation, Task};
use crate::collision::SweepMethod;
use crate::document::{Document, MateKind, Reference};
use crate::math::{Transform, Vec3};
use crate::planning::PlannedPath;
use crate::workspace::{SceneCache, WorkspaceError};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::Ordering;

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
    cost: Cost,
}

/// The ranking of a (partial) sequence: mounts, direction changes, difficult
/// insertions, total path length (mm); lexicographic.
type Cost = (usize, usize, usize, f64);

fn cost_lt(a: &Cost, b: &Cost) -> bool {
    (a.0, a.1, a.2) < (b.0, b.1, b.2) || ((a.0, a.1, a.2) == (b.0, b.1, b.2) && a.3 < b.3 - 1e-9)
}

struct Search<'c, 'd> {
    ctx: &'c Ctx<'d>,
    k: usize,
    found: Vec<Found>,
    rejected: Vec<Rejected>,
    dead: HashSet<Mask>,
    /// Per search state (placed parts, mount direction, and in the second pass the
    /// parts that had a straight insertion): the best `k` costs it was reached
    /// with. What can follow depends on the state alone, so a later arrival no
    /// better than `k` earlier ones cannot rank among the kept sequences (the same
    /// completions after `k` cheaper prefixes): it is skipped. This cuts the
    /// re-orderings of independent parts (a dozen clips in any order) that branch
    /// and bound alone cannot, as their partial costs stay below the worst kept.
    seen: HashMap<StateKey, Vec<Cost>>,
    /// Per part: the planned path found for it (reused wherever it is still free).
    planned_ok: Vec<Option<PlannedPath>>,
    /// Per part: the sets of assembled parts among which no path was found (a
    /// superset cannot do better).
    planned_failed: Vec<Vec<Mask>>,
    /// Pairs (a, b) with a before b, counted over every complete sequence seen.
    before: Vec<Vec<u32>>,
    complete_count: u32,
    /// The memo's size as counted against [`MAX_SEARCH_MEMO_BYTES`].
    memo_bytes: usize,
    cut: bool,
    /// Whether dead ends ask the planners (second pass).
    use_fallback: bool,
    /// Whether branch and bound cut a subtree below the current node.
    pruned: bool,
}

/// The key of [`Search::seen`].
type StateKey = (Mask, Option<[u64; 3]>, Mask);

/// The memory bound of the search, bytes: its memo ([`Search::seen`], up to
/// `max_sequences` costs a state, and [`Search::dead`]) is counted as it grows
/// ([`MEMO_STATE_BYTES`] a state, the size of a cost per cost kept) and the search
/// stops there as at its deadline (`complete: false`): ≈ 200,000 states of one cost
/// each (as before the bound was counted in bytes), fewer when states keep more. A bound on memory, not on time: the
/// search expands tens of thousands of states a second, so without it a long budget
/// (or a large `max_sequences`: 1,000,000 of them on 128 parts passed 8 GB) would
/// grow the memo by gigabytes; within it the budget decides.
pub const MAX_SEARCH_MEMO_BYTES: usize = 80 << 20;

/// What one memo state counts besides its costs, bytes (its key, the map's slot and
/// the costs' vector): 400 bytes with its first cost.
const MEMO_STATE_BYTES: usize = 368;
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

    /// Whether `p` can never be added below a node that has `mask` placed: every
    /// straight insertion gravity allows is known blocked by a part of `mask` (what
    /// blocks one only grows as parts are added), and on the second pass the
    /// planners already found no path for it among a subset of `mask` (nor reuse
    /// one). A branch with such a part is dead whatever goes next; without this the
    /// search tried every order of the other parts first — 2^n nodes for n of them
    /// (a servo horn put on before the gripper base it clamps, with 20 other parts
    /// to go, filled a 30 s budget). Only sweeps already run are read.
    fn doomed(&self, p: usize, mask: Mask) -> bool {
        let ctx = self.ctx;
        if !ctx.known_blocked_everywhere(p, mask) {
            return false;
        }
        !self.use_fallback
            || (self.planned_ok[p].is_none()
                && self.planned_failed[p].iter().any(|&f| f & !mask == 0))
    }

    fn mounts_for(&self, current: Option<Vec3>, mate: &Vec3) -> bool {
        match current {
            None => false,
            Some(c) => c.angle(mate) > self.ctx.opts.max_tilt + 1e-9,
        }
    }

    fn worst_kept(&self) -> Option<Cost> {
        (self.found.len() >= self.k).then(|| self.found[self.found.len() - 1].cost)
    }

    fn record(&mut self, base: usize, choices: &[Choice], cost: Cost) {
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

    fn reject(&mut self, base: usize, choices: &[Choice], reason: RejectReason) {
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
        cost: Cost,
        pins: &[usize],
        had_free: Mask,
    ) -> bool {
        let ctx = self.ctx;
        if mask & ctx.active == ctx.active {
            self.record(base, choices, cost);
            return true;
        }
        if ctx.search_out_of_time() || self.memo_bytes >= MAX_SEARCH_MEMO_BYTES {
            self.cut = true;
            return false;
        }
        if let Some(w) = self.worst_kept() {
            // Straight insertions only (first pass): each part still to come travels
            // at least its way out of today's product box (the box only grows), so
            // that much path length is certain to be added.
            let bound = if self.use_fallback {
                cost
            } else {
                (cost.0, cost.1, cost.2, cost.3 + length_bound(ctx, mask))
            };
            if !cost_lt(&bound, &w) {
                // Branch and bound: nothing below can rank among the kept ones. The
                // mask is not dead, so it is not memoised either.
                self.pruned = true;
                return false;
            }
        }
        if self.dead.contains(&mask) {
            return false;
        }
        if let Some(p) = ctx.todo(mask).find(|&p| self.doomed(p, mask)) {
            // Dead whatever goes next: said now, not after every order of the
            // other parts.
            if self.rejected.len() < MAX_REJECTED {
                let reason = RejectReason::DeadEnd {
                    pinned: None,
                    parts: vec![ctx.blocked(p, mask)],
                };
                self.reject(base, choices, reason);
            }
            if self.dead.insert(mask) {
                self.memo_bytes += MEMO_STATE_BYTES;
            }
            return false;
        }
        let key = (
            mask,
            current.map(|c| dir_key(&c)),
            if self.use_fallback { had_free } else { 0 },
        );
        let fresh = !self.seen.contains_key(&key);
        let costs = self.seen.entry(key).or_default();
        if costs.len() >= self.k && !cost_lt(&cost, &costs[self.k - 1]) {
            self.pruned = true;
            return false;
        }
        let at = costs
            .iter()
            .position(|c| cost_lt(&cost, c))
            .unwrap_or(costs.len());
        let before = costs.len();
        costs.insert(at, cost);
        costs.truncate(self.k);
        let grown = costs.len() - before;
        self.memo_bytes +=
            grown * std::mem::size_of::<Cost>() + usize::from(fresh) * MEMO_STATE_BYTES;
        let depth = choices.len();
        let pinned = pins.get(depth).copied();
        let region = union_box(&ctx.boxes, mask).unwrap_or(ctx.boxes[base]);
        // Options: (needs mount, exit distance, part, leave, planned).
        let mut options: Vec<(bool, f64, Choice)> = Vec::new();
        for p in ctx.todo(mask) {
            if pinned.is_some_and(|q| q != p) || !ctx.eligible(p, mask) {
                continue;
            }
            let allowed = |k: usize| ctx.gravity_allows(&-ctx.dirs[p][k]);
            // Keeping the current mount direction dominates every other choice: the
            // first free direction that keeps it is the only option (looked for
            // first, so the other directions' sweeps are not needed here).
            let keep = (0..ctx.dirs[p].len()).find(|&k| {
                current.is_some_and(|c| !self.mounts_for(Some(c), &-ctx.dirs[p][k]))
                    && allowed(k)
                    && ctx.blockers_in(p, k, mask, false) == 0
            });
            let ks: Vec<usize> = match keep {
                Some(k) => vec![k],
                None => ctx
                    .free_dirs(p, mask)
                    .into_iter()
                    .filter(|&k| allowed(k))
                    .collect(),
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
            for p in ctx.todo(mask) {
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
                    if !ctx.gravity_allows(&-leave) {
                        continue;
                    }
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
            let parts = ctx
                .todo(mask)
                .filter(|&p| pinned.is_none_or(|q| q == p))
                .take(4)
                .map(|p| ctx.why_not(p, mask))
                .collect();
            let reason = RejectReason::DeadEnd {
                pinned: pinned.map(|q| ctx.names[q].clone()),
                parts,
            };
            self.reject(base, choices, reason);
            if self.dead.insert(mask) {
                self.memo_bytes += MEMO_STATE_BYTES;
            }
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
            let hard = choice.planned.is_some() || ctx.tight(choice.part, &mate, mask);
            let next_cost = (
                cost.0 + mount as usize,
                cost.1 + change as usize,
                cost.2 + hard as usize,
                cost.3 + len,
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
        if !any && !self.cut && !self.pruned && self.dead.insert(mask) {
            self.memo_bytes += MEMO_STATE_BYTES;
        }
        self.cut |= cut_before;
        self.pruned |= pruned_before;
        any
    }
}

/// A lower bound of the straight insertion length (mm) still to come onto `mask`:
/// per part not placed, the shortest way its box leaves the box of `mask` along one
/// of its candidate directions not blocked among `mask` (the box of what is placed
/// only grows, and so does what blocks a direction).
fn length_bound(ctx: &Ctx, mask: Mask) -> f64 {
    let Some(region) = union_box(&ctx.boxes, mask) else {
        return 0.0;
    };
    let b = ctx.blocking.lock().unwrap();
    ctx.todo(mask)
        .map(|p| {
            // Along the directions not known to be blocked among `mask` (a later
            // straight insertion is free among a superset of it); no sweep is run.
            (0..ctx.dirs[p].len())
                .filter(|&k| b.hit[p][k] & mask == 0)
                .map(|k| exit_distance(&ctx.boxes[p], &region, &ctx.dirs[p][k]))
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|l| l.is_finite())
        .sum()
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
                .is_some_and(|k| ctx.blockers_in(p, k, mask, false) != 0)
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
fn build_sequence(ctx: &Ctx, f: &Found) -> Result<Sequence, RejectReason> {
    let mut mask = bit(f.base);
    let mut order = vec![f.base];
    let mut tasks = Vec::new();
    let mut steps = Vec::new();
    let mut current: Option<Vec3> = None;
    let mut prev: Option<Vec3> = None;
    let (mut mounts, mut changes, mut difficult, mut total) = (0, 0, 0, 0.0);
    let base_pose = ctx.scene.poses[f.base];
    for (index, ch) in f.choices.iter().enumerate() {
        let p = ch.part;
        let (receivers, mating_directions) = step_info(ctx, p, mask, &order);
        let mate = -ch.leave;
        let assembled = ctx.scene.poses[p];
        let (safe, path) = match &ch.planned {
            // The search checked this path continuously against exactly `mask`
            // when it chose it (found there, or a reused one re-validated there):
            // not checked again, so that building the answer costs no budget.
            Some(path) => (ctx.opts.probe_mm, path.clone()),
            None => {
                // The blocking graph's continuous sweep of p along this direction
                // found no component of `mask` on the whole straight line (see
                // `Ctx::sweep_hits`): that is this path's check, already made.
                let free = ctx.dirs[p]
                    .iter()
                    .position(|e| same_dir(e, &ch.leave))
                    .is_some_and(|k| ctx.blockers_in(p, k, mask, false) == 0);
                if !free {
                    return Err(RejectReason::StraightCollides {
                        part: ctx.names[p].clone(),
                        direction: mate,
                    });
                }
                let safe = ctx.safe_length(p, &ch.leave, mask);
                let from = assembled.then(&Transform::from_translation(ch.leave * safe));
                let path =
                    PlannedPath::given("straight", vec![from, assembled], SweepMethod::CONTINUOUS)
                        .with_tolerance(ctx.opts.tolerance);
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
            fits: members(mask)
                .filter(|&q| ctx.fit(p, q).is_some())
                .map(|q| ctx.names[q].clone())
                .collect(),
            slides: members(mask)
                .filter(|&q| {
                    ctx.fit(p, q)
                        .is_some_and(|f| f.depth <= ctx.opts.slide_fit_mm)
                })
                .map(|q| ctx.names[q].clone())
                .collect(),
        });
        let hard = ch.planned.is_some() || ctx.tight(p, &mate, mask);
        difficult += hard as usize;
        steps.push(StepInfo {
            receivers: receivers.iter().map(|&q| ctx.names[q].clone()).collect(),
            mating_directions,
            planned: ch.planned.is_some(),
            direction_change: change,
            difficult: hard,
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
        difficult,
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
            let mut c: Vec<usize> = members(ctx.active).collect();
            c.sort_by(|&a, &b| ctx.sizes[b].total_cmp(&ctx.sizes[a]).then(a.cmp(&b)));
            c
        }
    };
    let pins: Vec<usize> = opts
        .order
        .iter()
        .map(|s| doc.component_index(s).map_err(WorkspaceError::from))
        .collect::<Result<_, _>>()?;
    // A search that starts after its share of the budget runs to the deadline (the
    // answer is then built with what is left, without the unspent work).
    if ctx.search_out_of_time() {
        ctx.search_deadline = ctx.deadline;
    }
    let ctx = ctx;
    let mut search = Search {
        ctx: &ctx,
        k: opts.max_sequences.max(1),
        found: Vec::new(),
        rejected: Vec::new(),
        dead: HashSet::new(),
        seen: HashMap::new(),
        planned_ok: vec![None; n],
        planned_failed: vec![Vec::new(); n],
        before: vec![vec![0; n]; n],
        complete_count: 0,
        memo_bytes: 0,
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
            if ctx.search_out_of_time() {
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
                    RejectReason::InactiveBase {
                        base: ctx.names[base].clone(),
                        size: ctx.sizes[base],
                        largest_related: biggest_related,
                    },
                );
                continue;
            }
            search.dead.clear();
            search.seen.clear();
            let mut choices = Vec::new();
            search.dfs(base, bit(base), &mut choices, None, (0, 0, 0, 0.0), pins, 0);
            // The base is the part a person would fix: the largest that works. A
            // smaller base is tried only when no sequence starts from a larger one.
            if search.complete_count > 0 {
                break;
            }
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
            // The search stops at its share of the budget: a search cut there found
            // nothing in time, though the whole budget has not run out yet.
            timed_out: ctx.out_of_time() || (cut && ctx.search_out_of_time()),
            rejected: rejected.into_iter().take(4).collect(),
        });
    }
    sequences.sort_by(|a, b| {
        (a.mounts, a.direction_changes, a.difficult)
            .cmp(&(b.mounts, b.direction_changes, b.difficult))
            .then(a.path_length_mm.total_cmp(&b.path_length_mm))
    });
    let ranking = ranking(ctx, &sequences, cut);
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
        ranking,
        product: members(ctx.active).map(|i| ctx.names[i].clone()).collect(),
        rejected,
        precedence,
        complete: !cut,
        graph: ctx.graph.clone(),
        fits: fits_of(ctx),
        support_gaps: ctx
            .support_gaps
            .iter()
            .map(|&((a, b), gap_mm)| SupportGap {
                a: ctx.names[a].clone(),
                b: ctx.names[b].clone(),
                gap_mm,
            })
            .collect(),
        separate_groups: separate_groups(ctx),
        tolerance: ctx.opts.tolerance,
        time_ms: ctx.started.elapsed().as_secs_f64() * 1e3,
        sweeps: ctx.sweeps.load(Ordering::Relaxed),
    })
}

/// The fits of the assembled pose, as reported.
pub(crate) fn fits_of(ctx: &Ctx) -> Vec<Fit> {
    ctx.fits
        .iter()
        .map(|f| Fit {
            a: ctx.names[f.a].clone(),
            b: ctx.names[f.b].clone(),
            depth: f.depth,
            contained: f.contained,
        })
        .collect()
}

/// Why the first sequence ranked first, for people.
fn ranking(ctx: &Ctx, sequences: &[Sequence], cut: bool) -> String {
    let first = &sequences[0];
    let hard: Vec<&str> = first
        .tasks
        .iter()
        .zip(&first.steps)
        .filter(|(_, s)| s.difficult)
        .map(|(t, _)| t.part.as_str())
        .collect();
    let base_why = if ctx.opts.base.is_some() {
        "pinned"
    } else {
        "the largest component that starts a sequence"
    };
    let costs = format!(
        "base {} ({base_why}), {} mounts, {} direction changes, {} difficult insertions{}, {} mm of insertion paths",
        first.base,
        first.mounts,
        first.direction_changes,
        first.difficult,
        if hard.is_empty() {
            String::new()
        } else {
            format!(" ({})", hard.join(", "))
        },
        crate::math::format::number(first.path_length_mm, 4)
    );
    let Some(second) = sequences.get(1) else {
        return format!(
            "the only sequence found{}: {costs}",
            if cut {
                " before the search was cut"
            } else {
                ""
            }
        );
    };
    let why = if first.mounts != second.mounts {
        format!("fewer mounts ({} vs {})", first.mounts, second.mounts)
    } else if first.direction_changes != second.direction_changes {
        format!(
            "fewer direction changes ({} vs {})",
            first.direction_changes, second.direction_changes
        )
    } else if first.difficult != second.difficult {
        format!(
            "fewer difficult insertions — tight fits or planned paths ({} vs {})",
            first.difficult, second.difficult
        )
    } else if first.path_length_mm < second.path_length_mm - 1e-9 {
        format!(
            "shorter insertion paths ({} vs {} mm)",
            crate::math::format::number(first.path_length_mm, 4),
            crate::math::format::number(second.path_length_mm, 4)
        )
    } else {
        "equal costs; found first".to_string()
    };
    format!("ranked first for {why} than the next: {costs}")
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

/// [`SequencePlan::separate_groups`]: the distinct support groups of the product, each
/// in document order, ordered by their first member; empty when there is one.
fn separate_groups(ctx: &Ctx) -> Vec<Vec<String>> {
    let mut seen: Vec<Mask> = Vec::new();
    for i in members(ctx.active) {
        let g = ctx.support_groups[i];
        if g != 0 && !seen.contains(&g) {
            seen.push(g);
        }
    }
    if seen.len() < 2 {
        return Vec::new();
    }
    seen.iter()
        .map(|&g| members(g).map(|i| ctx.names[i].clone()).collect())
        .collect()
}
