//! Axis moves: a deterministic best-first search over the poses a tree reaches by
//! turning about the moving part's own axes by 45° or 90° and by sliding along its
//! own (or the start's) axes as far as contact, interleaved with
//! [`rrt_connect`](super::rrt_connect) within a share of the work
//! ([`NarrowPassage::axis_moves`](super::NarrowPassage::axis_moves)).
//!
//! Why: engineered passages (a slot, a keyway, a door, a stepped bore) are aligned
//! with the parts' own axes, and the motion through them is a pure translation at
//! an orientation aligned with the passage, reached by quarter or eighth turns
//! where there is room. A bar rolled 90° through a slot 0.3 mm wider than itself
//! needs its roll within ±0.9° and its centre within ±0.15 mm at once: a uniform
//! sample lands there with a probability of about 10⁻¹⁰, and a random tree grows
//! into the slot mouth no better. The aligned poses form a small set that
//! contains the passage exactly, and sliding to contact (then bisecting the
//! blocked piece to a few µm) finds where a chamber ends. A translation toward the
//! other tree's root stops at the root's coordinate along that axis, so the
//! straight lines through the ends' coordinates (where an assembly's approach
//! usually lies) are tried first.
//!
//! Order: the open aligned node nearest in translation to the other tree's root
//! (turns add 5 % of their metric length, so at one place the turns are tried
//! before the search moves on). Every move is checked with the search's edge
//! check (lazy or the validator's own); no random numbers are drawn, so the
//! search does not change the seed's stream.

use super::space::PlanningSpace;
use super::tree::Tree;
use super::validator::Checker;
use crate::math::{Transform, Vec3};
use nalgebra::{Unit, UnitQuaternion};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

/// The turns about each of the part's axes (rad).
const TURNS: [f64; 4] = [FRAC_PI_4, -FRAC_PI_4, FRAC_PI_2, -FRAC_PI_2];

/// Length of the pieces a slide is checked in (mm): the first blocked piece is
/// bisected.
const PIECE_MM: f64 = 2.0;

/// Bisections of the blocked piece: 2 mm / 2⁹ ≈ 4 µm short of contact.
const BISECTIONS: usize = 9;

/// How far a slide that ended at contact backs off (mm): the bisection stops
/// where the pose is still free, i.e. possibly crossing the obstacle by almost the
/// validator's tolerance (0.01 mm by default); backed off, the turns tried there
/// next and the certification of the slide do not start at that limit. Freedom
/// is monotone along the slide, so the shorter slide is free too.
const BACK_OFF_MM: f64 = 0.02;

/// Shortest slide worth a node (mm).
const MIN_SLIDE_MM: f64 = 0.05;

/// Share of a turn's metric length in the order of the open nodes.
const TURN_WEIGHT: f64 = 0.05;

/// Nodes of the other tree with the same orientation tried for a straight
/// (pure translation) connection to a new aligned node.
const MEET_TRIES: usize = 3;

/// A total order on priorities (finite by construction).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Key(f64);

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The axis-move search of one tree.
pub(crate) struct AxisSearch {
    /// Aligned nodes not expanded yet, best first (ties: the lower index).
    open: BinaryHeap<Reverse<(Key, usize)>>,
    /// Every aligned node of the tree (the root and what axis moves added).
    nodes: Vec<usize>,
    /// Length unit of the slides (1 for the lengths in mm above; the scale-free
    /// search's narrow step over its 3 mm reference, so slides scale with the
    /// problem).
    unit: f64,
}

impl AxisSearch {
    /// The search of `tree`, whose root is the first aligned node.
    pub fn new(tree: &Tree, target: &Transform, space: &PlanningSpace, unit: f64) -> Self {
        let mut s = Self {
            open: BinaryHeap::new(),
            nodes: Vec::new(),
            unit,
        };
        s.push(tree, 0, target, space);
        s
    }

    fn push(&mut self, tree: &Tree, i: usize, target: &Transform, space: &PlanningSpace) {
        let p = &tree.poses[i];
        let key = (p.translation() - target.translation()).norm()
            + TURN_WEIGHT * space.rotation_weight * p.rotation().angle_to(&target.rotation());
        self.open.push(Reverse((Key(key), i)));
        self.nodes.push(i);
    }

    /// Whether an open node is left.
    pub fn has_open(&self) -> bool {
        !self.open.is_empty()
    }

    /// Expands the best open node of `tree` that is still alive: every turn and
    /// slide from it that is free, in the space and new becomes a node (pushed to
    /// `added`). `target` is the other tree's root.
    pub fn expand(
        &mut self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &mut Tree,
        target: &Transform,
        added: &mut Vec<usize>,
    ) {
        let node = loop {
            match self.open.pop() {
                None => return,
                Some(Reverse((_, i))) if tree.alive(i) => break i,
                Some(_) => {}
            }
        };
        let from = tree.poses[node];
        let (t, q) = (from.translation(), from.rotation());
        for axis in 0..3 {
            let e = Unit::new_unchecked(Vec3::ith(axis, 1.0));
            for angle in TURNS {
                let turned =
                    Transform::from_parts(t, q * UnitQuaternion::from_axis_angle(&e, angle));
                if space.contains(&turned, reference)
                    && !tree.holds(&turned)
                    && checker.edge_free(&from, &turned)
                {
                    let i = tree.add(turned, node);
                    self.push(tree, i, target, space);
                    added.push(i);
                }
            }
        }
        for d in directions(&q, reference) {
            if let Some(to) = slide(checker, space, reference, &from, &d, target, self.unit) {
                if !tree.holds(&to) {
                    let i = tree.add(to, node);
                    self.push(tree, i, target, space);
                    added.push(i);
                }
            }
        }
    }

    /// Up to [`MEET_TRIES`] alive aligned nodes of `tree` with the orientation of
    /// `pose`, nearest first: a straight edge from one of them is a pure
    /// translation.
    pub fn same_orientation(&self, tree: &Tree, pose: &Transform) -> Vec<usize> {
        let (t, q) = (pose.translation(), pose.rotation());
        let mut same: Vec<(f64, usize)> = self
            .nodes
            .iter()
            .filter(|&&i| tree.alive(i) && tree.poses[i].rotation().angle_to(&q) < 1e-9)
            .map(|&i| ((tree.poses[i].translation() - t).norm(), i))
            .collect();
        same.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        same.into_iter().take(MEET_TRIES).map(|(_, i)| i).collect()
    }
}

/// The unit directions of the slides from a pose with rotation `q`: ± its own
/// axes, then ± the reference (start) axes not already among them.
fn directions(q: &UnitQuaternion<f64>, reference: &UnitQuaternion<f64>) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::with_capacity(12);
    for frame in [q, reference] {
        for axis in 0..3 {
            let a = *frame * Vec3::ith(axis, 1.0);
            for d in [a, -a] {
                if out.iter().all(|o| o.dot(&d) < 1.0 - 1e-9) {
                    out.push(d);
                }
            }
        }
    }
    out
}

/// How far (mm) a point at `t` may move along the unit direction `d` inside the
/// box `[min, max]`.
fn room(t: &Vec3, d: &Vec3, min: &Vec3, max: &Vec3) -> f64 {
    let mut s = f64::INFINITY;
    for k in 0..3 {
        if d[k] > 1e-12 {
            s = s.min((max[k] - t[k]) / d[k]);
        } else if d[k] < -1e-12 {
            s = s.min((min[k] - t[k]) / d[k]);
        }
    }
    s.max(0.0)
}

/// The farthest free pose of the pure translation from `from` along `d`: as far
/// as the other tree's root's coordinate along `d` when that lies ahead, else as
/// far as the bounds; checked in [`PIECE_MM`] pieces (times `unit`), the first
/// blocked one bisected and the slide backed off by [`BACK_OFF_MM`] from where it
/// was blocked. `None` when it moves less than [`MIN_SLIDE_MM`] (times `unit`).
fn slide(
    checker: &mut Checker<'_>,
    space: &PlanningSpace,
    reference: &UnitQuaternion<f64>,
    from: &Transform,
    d: &Vec3,
    target: &Transform,
    unit: f64,
) -> Option<Transform> {
    let (piece, min_slide) = (PIECE_MM * unit, MIN_SLIDE_MM * unit);
    let (t, q) = (from.translation(), from.rotation());
    let bound = room(&t, d, &space.min, &space.max);
    let ahead = (target.translation() - t).dot(d);
    let cap = if ahead > min_slide {
        ahead.min(bound)
    } else {
        bound
    };
    if cap < min_slide {
        return None;
    }
    let at = |s: f64| Transform::from_parts(t + d * s, q);
    let mut lo = 0.0;
    while lo < cap {
        let hi = (lo + piece).min(cap);
        let (a, b) = (at(lo), at(hi));
        if space.contains(&b, reference) && checker.edge_free(&a, &b) {
            lo = hi;
            continue;
        }
        // Farthest free point of the blocked piece: freedom of a straight piece
        // from a free start is monotone in its length.
        let base = a;
        let mut hi = hi;
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            let m = at(mid);
            if space.contains(&m, reference) && checker.edge_free(&base, &m) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo = (lo - BACK_OFF_MM).max(0.0);
        break;
    }
    (lo >= min_slide).then(|| at(lo))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_the_axes_without_repeats() {
        let id = UnitQuaternion::identity();
        assert_eq!(directions(&id, &id).len(), 6);
        let roll = UnitQuaternion::from_axis_angle(&Vec3::x_axis(), FRAC_PI_4);
        // Rolled 45° about x: x is shared, y and z are new.
        assert_eq!(directions(&roll, &id).len(), 10);
    }

    #[test]
    fn room_is_the_distance_to_the_box() {
        let (min, max) = (Vec3::repeat(-10.0), Vec3::repeat(10.0));
        let t = Vec3::new(5.0, 0.0, 0.0);
        assert!((room(&t, &Vec3::x(), &min, &max) - 5.0).abs() < 1e-12);
        assert!((room(&t, &-Vec3::x(), &min, &max) - 15.0).abs() < 1e-12);
        let diag = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((room(&t, &diag, &min, &max) - 5.0 * 2f64.sqrt()).abs() < 1e-9);
    }
}
