//! Seed 002's local discretization around a tree node (a cube lattice of translations,
//! then single-axis rotations), shared by the tree searches: [`local_rrt`](super::local_rrt)
//! tries it on every failed extension, the other RRTs through
//! [`NarrowPassage`](super::NarrowPassage)'s fallback.

use super::run::PlanError;
use super::space::PlanningSpace;
use super::tree::{Target, Tree};
use super::validator::Checker;
use crate::math::{Rng, Transform, Vec3};
use nalgebra::{Unit, UnitQuaternion};

/// The axes of the local lattice and of the single-axis rotations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum DiscretizationFrame {
    /// The assembly frame's X, Y, Z (seed 002's figures).
    World,
    /// The node's own axes (the component's local frame at that pose). An insertion
    /// usually runs along one of the component's own axes, so this lattice contains
    /// the insertion direction even when the part is tilted. Default.
    #[default]
    Part,
}

/// Seed 002's local discretization around a tree node: a cube lattice of edge `l`
/// (26 translation neighbours), then 6 single-axis rotations `±α`.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// Largest lattice edge length `l` (mm). Default 5.
    pub edge_length_max: f64,
    /// Smallest lattice edge length `l` (mm). Default 0.05.
    pub edge_length_min: f64,
    /// `l = clamp(clearance_gain · clearance, l_min, l_max)` when the validator reports
    /// a clearance. Without one, `l` starts at `edge_length_max` and halves down to
    /// `edge_length_min` until a neighbour is free. Default 1.
    pub clearance_gain: f64,
    /// Rotation steps `αX, αY, αZ` (rad) of the 6 single-axis rotations. Default
    /// 5° each.
    pub alpha: [f64; 3],
    /// Axes of the lattice and rotations.
    pub frame: DiscretizationFrame,
    /// After a lattice move succeeds, keep moving the same way with doubling length
    /// (up to `step`) while it is free and brings the node closer to the goal: one
    /// iteration then crosses a whole narrow channel. Not in seed 002. Default true.
    pub follow_through: bool,
    /// Rank the lattice candidates by distance to the random sample when the sample
    /// was not the goal (seed 002 always ranks by distance to the goal, which pulls
    /// every failed extension into the same local minimum in front of a wall).
    /// Goal-biased iterations always rank by distance to the goal. Default true.
    pub rank_toward_sample: bool,
    /// Random coordinated moves tried with the single-axis rotations when no
    /// translation of the lattice is free: each translates by up to the lattice
    /// edge in a random direction while turning by up to the largest `alpha` about
    /// a random axis (a screw about a random line, which is what threading a part
    /// through a slit or round a corner needs); all are ranked together with the
    /// 6 rotations. Not in seed 002 (0 gives its discretization). Default 0.
    pub random_moves: usize,
    /// Rotation steps scaled to the clearance (contact-aware turns): besides the
    /// 6 rotations by `alpha`, try the 6 single-axis rotations whose size in the
    /// metric equals the lattice edge (`l / rotation_weight` rad) when that is
    /// smaller than `alpha`, and bound half of the random coordinated moves' turns
    /// by it. Near a surface the lattice edge follows the clearance, so a part
    /// with 0.15 mm to spare still finds a turn that fits, where a 5° turn of a
    /// 20 mm part moves its rim 1.7 mm. Not in seed 002 (false); true in fitup's
    /// own defaults. Default false.
    pub clearance_turns: bool,
}

impl Default for Lattice {
    fn default() -> Self {
        Self {
            edge_length_max: 5.0,
            edge_length_min: 0.05,
            clearance_gain: 1.0,
            alpha: [5f64.to_radians(); 3],
            frame: DiscretizationFrame::Part,
            follow_through: true,
            rank_toward_sample: true,
            random_moves: 0,
            clearance_turns: false,
        }
    }
}

impl Lattice {
    /// The random coordinated moves ([`Lattice::random_moves`]) of fitup's own
    /// defaults ([`RrtConnectOptions`](super::RrtConnectOptions),
    /// [`InsertionOptions`](super::InsertionOptions)): on the rotation puzzles they
    /// solved more seeds within the same iterations than the 6 single-axis
    /// rotations alone (docs/performance.md). [`Lattice::default`] keeps seed 002's 0.
    pub const RANDOM_MOVES: usize = 8;

    /// The same lattice with its edge lengths times `k` (angles unchanged): the
    /// scale-free search's lattice, `k` its narrow step over the 3 mm the defaults
    /// were measured with.
    #[must_use]
    pub fn scaled(&self, k: f64) -> Lattice {
        Lattice {
            edge_length_max: self.edge_length_max * k,
            edge_length_min: self.edge_length_min * k,
            ..self.clone()
        }
    }

    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        PlanError::positive("edge_length_max", self.edge_length_max)?;
        PlanError::positive("edge_length_min", self.edge_length_min)?;
        if self.edge_length_min > self.edge_length_max {
            return Err(PlanError::invalid(
                "edge_length_min",
                self.edge_length_min.to_string(),
                "at most edge_length_max",
            ));
        }
        PlanError::positive("clearance_gain", self.clearance_gain)?;
        for (name, a) in ["alpha[0]", "alpha[1]", "alpha[2]"].iter().zip(self.alpha) {
            PlanError::positive(name, a)?;
        }
        Ok(())
    }

    /// The lattice edge lengths to try around `pose`, longest first.
    fn edge_lengths(&self, checker: &mut Checker<'_>, pose: &Transform) -> Vec<f64> {
        if let Some(c) = checker.clearance(pose) {
            return vec![
                (c * self.clearance_gain).clamp(self.edge_length_min, self.edge_length_max)
            ];
        }
        let mut out = Vec::new();
        let mut l = self.edge_length_max;
        while l > self.edge_length_min {
            out.push(l);
            l *= 0.5;
        }
        out.push(self.edge_length_min);
        out
    }

    fn axis(&self, pose: &Transform, i: usize) -> Vec3 {
        let e = Vec3::ith(i.min(2), 1.0);
        match self.frame {
            DiscretizationFrame::World => e,
            DiscretizationFrame::Part => pose.apply_vector(&e),
        }
    }

    /// Seed 002's local discretization around node `near`: the 26 lattice neighbours
    /// (ranked by distance to the goal), then the 6 single-axis rotations; the first
    /// free one is added to `tree` (followed through when enabled). Added node
    /// indices go to `added`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn expand(
        &self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        tree: &mut Tree,
        near: usize,
        target: &dyn Target,
        reference: &UnitQuaternion<f64>,
        step: f64,
        rng: &mut Rng,
        added: &mut Vec<usize>,
    ) {
        let base = tree.poses[near];
        let here = target.distance(&base, space);
        let axes = [
            self.axis(&base, 0),
            self.axis(&base, 1),
            self.axis(&base, 2),
        ];
        let mut candidates: Vec<(f64, Vec3, Transform)> = Vec::with_capacity(26);
        let lengths = self.edge_lengths(checker, &base);
        for &l in &lengths {
            candidates.clear();
            for dx in -1i32..=1 {
                for dy in -1i32..=1 {
                    for dz in -1i32..=1 {
                        if dx == 0 && dy == 0 && dz == 0 {
                            continue;
                        }
                        let dir = (axes[0] * f64::from(dx)
                            + axes[1] * f64::from(dy)
                            + axes[2] * f64::from(dz))
                            * l;
                        let pose = Transform::from_parts(base.translation() + dir, base.rotation());
                        if space.contains(&pose, reference) && !tree.holds(&pose) {
                            candidates.push((target.distance(&pose, space), dir, pose));
                        }
                    }
                }
            }
            candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
            for &(d, dir, pose) in &candidates {
                if checker.edge_free(&base, &pose) {
                    let i = tree.add(pose, near);
                    added.push(i);
                    if self.follow_through && d < here {
                        self.follow(
                            checker, space, tree, i, dir, d, target, reference, step, added,
                        );
                    }
                    return;
                }
            }
        }
        // Rotation strategy: ±α about each allowed axis, ranked by distance to the
        // goal; ties go to the positive turn, then the smaller angle (seed 002).
        let mut turns: Vec<(f64, bool, f64, Transform)> = Vec::with_capacity(12);
        // The turn whose metric size is the lattice edge (clearance-scaled).
        let fine = lengths[0] / space.rotation_weight;
        for (i, &alpha) in self.alpha.iter().enumerate() {
            if !space.axis_enabled(i) {
                continue;
            }
            let axis = Unit::new_normalize(self.axis(&base, i));
            let sizes: &[f64] = if self.clearance_turns && fine < alpha {
                &[alpha, fine]
            } else {
                &[alpha]
            };
            for &size in sizes {
                for sign in [1.0, -1.0] {
                    let turn = UnitQuaternion::from_axis_angle(&axis, sign * size);
                    let pose = Transform::from_parts(base.translation(), turn * base.rotation());
                    if space.contains(&pose, reference) && !tree.holds(&pose) {
                        turns.push((target.distance(&pose, space), sign < 0.0, size, pose));
                    }
                }
            }
        }
        if self.random_moves > 0 {
            let l = lengths[0];
            let coarse = self.alpha.iter().copied().fold(0.0, f64::max);
            let free_rotation = matches!(space.rotation, super::RotationFreedom::Free);
            for k in 0..self.random_moves {
                let alpha = if self.clearance_turns && k % 2 == 1 {
                    coarse.min(fine)
                } else {
                    coarse
                };
                let dir = Vec3::new(rng.normal(), rng.normal(), rng.normal());
                let dir = dir / dir.norm().max(1e-12) * l * rng.uniform();
                let angle = rng.range(-alpha, alpha);
                let axis = Vec3::new(rng.normal(), rng.normal(), rng.normal());
                let turn = match (free_rotation, Unit::try_new(axis, 1e-9)) {
                    (true, Some(axis)) => UnitQuaternion::from_axis_angle(&axis, angle),
                    _ => UnitQuaternion::identity(),
                };
                let pose = Transform::from_parts(base.translation() + dir, turn * base.rotation());
                if space.contains(&pose, reference) && !tree.holds(&pose) {
                    turns.push((target.distance(&pose, space), false, angle.abs(), pose));
                }
            }
        }
        turns.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(a.1.cmp(&b.1))
                .then(a.2.total_cmp(&b.2))
        });
        for &(_, _, _, pose) in &turns {
            if checker.edge_free(&base, &pose) {
                added.push(tree.add(pose, near));
                return;
            }
        }
    }

    /// Keeps translating along `dir`, doubling the move up to `step`, while the move
    /// is free, in the space, and gets closer to the goal.
    #[allow(clippy::too_many_arguments)]
    fn follow(
        &self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        tree: &mut Tree,
        mut from: usize,
        dir: Vec3,
        mut dist: f64,
        target: &dyn Target,
        reference: &UnitQuaternion<f64>,
        step: f64,
        added: &mut Vec<usize>,
    ) {
        let unit = dir.normalize();
        let mut len = dir.norm();
        // Bounded so a long free channel cannot stall one iteration.
        for _ in 0..64 {
            if target.reached(&tree.poses[from]) {
                return;
            }
            len = (len * 2.0).min(step.max(dir.norm()));
            let base = tree.poses[from];
            let mut moved = false;
            let mut l = len;
            while l >= dir.norm() * 0.999 {
                let pose = Transform::from_parts(base.translation() + unit * l, base.rotation());
                let d = target.distance(&pose, space);
                if d < dist
                    && space.contains(&pose, reference)
                    && !tree.holds(&pose)
                    && checker.edge_free(&base, &pose)
                {
                    from = tree.add(pose, from);
                    added.push(from);
                    dist = d;
                    len = l;
                    moved = true;
                    break;
                }
                l *= 0.5;
            }
            if !moved {
                return;
            }
        }
    }
}
