//! Seed 002's disassembly-first planning: "what can be taken apart can be assembled".

use super::local_rrt::LocalRrtOptions;
use super::path::PlannedPath;
use super::rrt::{plan_tree, RrtOptions};
use super::run::{PlanError, ProgressFn};
use super::space::PlanningSpace;
use super::tree::Target;
use super::validator::MotionValidator;
use crate::math::Aabb;
use crate::math::{Rng, Transform};

/// Checks a box is finite with `lo ≤ hi` on every axis.
pub(crate) fn validate_box(b: &Aabb, option: &'static str) -> Result<(), PlanError> {
    let ok = (0..3).all(|i| b.lo[i].is_finite() && b.hi[i].is_finite() && b.lo[i] <= b.hi[i]);
    if ok {
        Ok(())
    } else {
        Err(PlanError::invalid(
            option,
            format!("{:?}..{:?}", b.lo.coords.as_slice(), b.hi.coords.as_slice()),
            "a finite box with min ≤ max on every axis",
        ))
    }
}

/// Which tree planner searches the disassembly path.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum DisassemblyPlanner {
    /// [`rrt`](super::rrt) / [`biased_rrt`](super::biased_rrt) with these options.
    Rrt(RrtOptions),
    /// [`local_rrt`](super::local_rrt) with these options (seed 002's choice).
    LocalRrt(LocalRrtOptions),
}

impl DisassemblyPlanner {
    /// The tree search options (for `local_rrt`, those of its underlying RRT).
    pub fn rrt_mut(&mut self) -> &mut RrtOptions {
        match self {
            DisassemblyPlanner::Rrt(o) => o,
            DisassemblyPlanner::LocalRrt(o) => &mut o.rrt,
        }
    }

    /// The same search with every length times `k` (step, goal tolerance, the
    /// narrow-passage measures', the lazy step and `local_rrt`'s lattice): how a
    /// scale-free [`plan_insertion`](super::plan_insertion) fits the defaults,
    /// given for a 3 mm step, to its problem.
    #[must_use]
    pub fn scaled(&self, k: f64) -> DisassemblyPlanner {
        let rrt = |o: &RrtOptions| RrtOptions {
            step: o.step * k,
            goal_tolerance: o.goal_tolerance * k,
            narrow: o.narrow.scaled(k),
            lazy: o.lazy.map(|l| super::LazyValidation {
                step_mm: l.step_mm * k,
            }),
            ..o.clone()
        };
        match self {
            DisassemblyPlanner::Rrt(o) => DisassemblyPlanner::Rrt(rrt(o)),
            DisassemblyPlanner::LocalRrt(o) => DisassemblyPlanner::LocalRrt(LocalRrtOptions {
                rrt: rrt(&o.rrt),
                lattice: o.lattice.scaled(k),
            }),
        }
    }

    /// The tree search options (for `local_rrt`, those of its underlying RRT).
    pub fn rrt(&self) -> &RrtOptions {
        match self {
            DisassemblyPlanner::Rrt(o) => o,
            DisassemblyPlanner::LocalRrt(o) => &o.rrt,
        }
    }
}

/// The goal region: the component's box is outside the product's box.
struct OutsideBox {
    part: Aabb,
    product: Aabb,
    assembled: Transform,
}

impl OutsideBox {
    /// Translations (mm) along ±X, ±Y, ±Z that would take the box out.
    fn exits(&self, pose: &Transform) -> [f64; 6] {
        let b = self.part.transformed(pose.isometry());
        let p = &self.product;
        [
            p.hi.x - b.lo.x,
            b.hi.x - p.lo.x,
            p.hi.y - b.lo.y,
            b.hi.y - p.lo.y,
            p.hi.z - b.lo.z,
            b.hi.z - p.lo.z,
        ]
    }
}

impl Target for OutsideBox {
    fn reached(&self, pose: &Transform) -> bool {
        // Touching the product box from outside counts as out.
        self.exits(pose).iter().any(|&e| e <= 0.0)
    }
    fn pose(&self) -> Option<&Transform> {
        None
    }
    fn distance(&self, pose: &Transform, _: &PlanningSpace) -> f64 {
        self.exits(pose)
            .iter()
            .fold(f64::INFINITY, |m, &e| m.min(e))
            .max(0.0)
    }
    fn sample(&self, rng: &mut Rng, space: &PlanningSpace, _: &Transform) -> Transform {
        // A pose just outside the box along a random axis direction from the
        // assembled pose, clamped into the space.
        let dir = rng.below(6);
        let travel = self.exits(&self.assembled)[dir] + 1.0;
        let mut t = self.assembled.translation();
        t[dir / 2] += if dir.is_multiple_of(2) {
            travel
        } else {
            -travel
        };
        for k in 0..3 {
            t[k] = t[k].clamp(space.min[k], space.max[k]);
        }
        Transform::from_parts(t, self.assembled.rotation())
    }
}

/// Plans an assembly path by planning the disassembly (seed 002).
///
/// The search starts at the `assembled` pose and stops as soon as the component's
/// box (`part_box`, in the component's local frame) placed at a tree node no longer
/// overlaps `product_box` (assembly frame); there is no goal orientation. The path
/// is then reversed: the returned path starts outside the product and ends at
/// `assembled`. Goal-biased samples are poses just outside the product box along
/// ±X/±Y/±Z from the assembled pose; the local lattice ranks candidates by the
/// smallest translation still needed to leave the box.
///
/// A [`Failure::StartInCollision`](super::Failure::StartInCollision) here means the
/// assembled pose collides.
///
/// # Errors
/// Invalid options, bounds, boxes or a non-finite pose.
pub fn disassemble(
    validator: &mut dyn MotionValidator,
    space: &PlanningSpace,
    assembled: &Transform,
    part_box: &Aabb,
    product_box: &Aabb,
    planner: &DisassemblyPlanner,
    progress: Option<ProgressFn<'_>>,
) -> Result<PlannedPath, PlanError> {
    validate_box(part_box, "part_box")?;
    validate_box(product_box, "product_box")?;
    let target = OutsideBox {
        part: *part_box,
        product: *product_box,
        assembled: *assembled,
    };
    let mut path = match planner {
        DisassemblyPlanner::Rrt(o) => {
            o.validate()?;
            plan_tree(
                "disassemble_rrt",
                validator,
                space,
                assembled,
                &target,
                o,
                None,
                progress,
            )?
        }
        DisassemblyPlanner::LocalRrt(o) => {
            o.validate()?;
            plan_tree(
                "disassemble_local_rrt",
                validator,
                space,
                assembled,
                &target,
                &o.rrt,
                Some(&o.lattice),
                progress,
            )?
        }
    };
    path.poses.reverse();
    Ok(path)
}
