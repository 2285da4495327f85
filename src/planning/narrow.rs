//! [`NarrowPassage`]: how the tree searches extend and sample where the way out is a
//! narrow passage that needs rotation and translation together (rings threaded
//! through slits, rods round corners, bars turned through slots).
//!
//! Four measures, each independent, all drawn from the search's seeded `Rng` so the
//! same seed still gives the same path:
//!
//! * **turn-limited retry** (`max_turn`): an extension whose straight step toward
//!   the sample is blocked is tried again turning by at most `max_turn` with the
//!   same translation. A uniform sample's orientation is on average ≈ 2 rad away,
//!   so a step mostly turns; in a narrow passage a small turn with a translation
//!   is what fits. Limiting every step instead (not only blocked ones) turns the
//!   orientation into a slow random walk of `max_turn` steps, and a part that must
//!   reorient by 90° in open space (peg_tilt: lying through a window, standing in
//!   the chamber) then runs out of time.
//! * **dynamic-domain sampling** (Yershova et al. 2005): a node whose extension was
//!   blocked gets a domain radius; samples farther than that from their nearest
//!   node are redrawn, so boundary nodes inside a cavity stop attracting samples
//!   from the whole space (which they can never reach) and the tree's real frontier
//!   gets the iterations.
//! * **bridge-test sampling** (Hsu et al. 2003): with probability `bridge`, a
//!   sample is the free midpoint of two blocked poses a short distance apart, which
//!   lands in the narrow passages between obstacles.
//! * **extension to contact** (`to_contact`): a blocked extension keeps the farthest
//!   free pose on its edge (bisection), so the tree reaches the obstacle's surface
//!   instead of stopping a whole step short of it; the local discretization then
//!   slides and turns from that contact pose.

use super::lattice::Lattice;
use super::run::PlanError;
use super::space::PlanningSpace;
use super::tree::{steer, Effort, Target, Tree};
use super::validator::Checker;
use crate::math::{Rng, Transform, Vec3};
use nalgebra::{Unit, UnitQuaternion};

/// Narrow-passage measures of the tree searches ([`rrt_connect`](super::rrt_connect),
/// and the single-tree search under [`local_rrt`](super::local_rrt) and
/// [`disassemble`](super::disassemble)). Lengths are metric mm of the
/// [`PlanningSpace`] (`|Δt| + rotation_weight · θ`), angles radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NarrowPassage {
    /// Turn-limited retry (rad): an extension whose straight step is blocked is
    /// tried again turning by at most this much, with the same translation.
    /// `None`: no retry. Default `Some(15°)` ([`NarrowPassage::MAX_TURN_DEG`]).
    pub max_turn: Option<f64>,
    /// Dynamic-domain radius (metric mm) given to a node whose extension was
    /// blocked: samples farther than it from their nearest node are redrawn (up to
    /// [`NarrowPassage::DOMAIN_TRIES`] times). `None`: off. Default `Some(10)`
    /// (the seed 002 planners' default extension step; three of
    /// `rrt_connect`'s).
    pub dynamic_domain: Option<f64>,
    /// Probability of drawing a sample by the bridge test (two blocked poses
    /// `bridge_width` apart with a free midpoint) instead of uniformly; 0: off.
    /// Default 0.1.
    pub bridge: f64,
    /// Standard deviation (metric mm) of the bridge test's second pose around the
    /// first. Default 5.
    pub bridge_width: f64,
    /// Keep the farthest free pose of a blocked extension (3 bisections of its
    /// edge) and run the local discretization from there. Default true.
    pub to_contact: bool,
    /// Largest share of [`rrt_connect`](super::rrt_connect)'s work, in `[0, 1]`,
    /// that the axis-move search may take: a deterministic best-first search over
    /// the poses each tree reaches by turning about the part's own axes by 45° or
    /// 90° and sliding along its own (or the start's) axes to contact or to the
    /// other root's coordinate (`planning/axis.rs`, docs/planning.md "Axis
    /// moves"). It finds passages aligned with the part's axes that are far too
    /// narrow to sample (a bar rolled 90° through a slot 0.3 mm wider than
    /// itself). 0: off. Default 0.1 (0.2 made the house puzzle's slow seeds 2–3×
    /// slower; 0.05 doubled the slots' times). The single-tree searches do not
    /// use it.
    pub axis_moves: f64,
    /// Probability, in `[0, 1]`, that a sample of a search with free rotation is
    /// **axis-aligned**: its translation uniform as usual, its orientation the
    /// extending tree's root orientation turned by a uniform angle about one of
    /// the assembly frame's axes (drawn at random). Parts in a flat channel, a
    /// corridor or a tunnel (a rod round a corner, a zigzag tunnel, a body under a
    /// ceiling) move with their orientation in such a one-axis family; a uniform
    /// orientation almost never fits there (a 12 mm rod under a 5 mm ceiling
    /// tilts at most ≈ 10°), so the searches spend their samples on the subspace
    /// where the part can be. 0: uniform orientations only. Default 0: in a first
    /// trial (issue 23, 3 seeds, 10 s) 0.25 solved the 7 mm corridor corner in 3
    /// of 3 seeds against 2 of 3 without, solved the zigzag tunnel in none either
    /// way, and lost a ring-puzzle seed that uniform orientations solve in 8 ms
    /// (docs/performance.md).
    pub axis_samples: f64,
}

impl Default for NarrowPassage {
    /// fitup's defaults (see the field docs and docs/planning.md): what won on the
    /// benchmark problems.
    fn default() -> Self {
        Self {
            max_turn: Some(Self::MAX_TURN_DEG.to_radians()),
            dynamic_domain: Some(10.0),
            bridge: 0.1,
            bridge_width: 5.0,
            to_contact: true,
            axis_moves: 0.1,
            axis_samples: 0.0,
        }
    }
}

impl NarrowPassage {
    /// Every measure off: the plain extension and uniform sampling (seed 002's
    /// baselines use this).
    pub const OFF: Self = Self {
        max_turn: None,
        dynamic_domain: None,
        bridge: 0.0,
        bridge_width: 5.0,
        to_contact: false,
        axis_moves: 0.0,
        axis_samples: 0.0,
    };

    /// The default turn-limited retry, degrees. With 3 mm extension steps
    /// ([`RrtConnectOptions::STEP`](super::RrtConnectOptions::STEP)) 15° halved
    /// the zigzag tunnel's median against 5° and left the other puzzles as they
    /// were (docs/performance.md, "Issue 23, round 4").
    pub const MAX_TURN_DEG: f64 = 15.0;

    /// How many samples dynamic-domain sampling draws before it takes the last one
    /// whatever its distance.
    pub const DOMAIN_TRIES: usize = 32;

    /// How many first poses the bridge test draws before it falls back to a
    /// uniform sample.
    pub const BRIDGE_TRIES: usize = 16;

    /// The same measures with their lengths (`dynamic_domain`, `bridge_width`)
    /// times `k`: the scale-free search's, `k` its narrow step over the 3 mm the
    /// defaults were measured with.
    #[must_use]
    pub fn scaled(&self, k: f64) -> NarrowPassage {
        NarrowPassage {
            dynamic_domain: self.dynamic_domain.map(|d| d * k),
            bridge_width: self.bridge_width * k,
            ..*self
        }
    }

    pub(crate) fn validate(&self) -> Result<(), PlanError> {
        if let Some(t) = self.max_turn {
            if !(t > 0.0 && t <= std::f64::consts::PI) {
                return Err(PlanError::invalid(
                    "narrow.max_turn",
                    format!("{t} rad ({:.3}°)", t.to_degrees()),
                    "an angle in (0, π] rad (None: no limit)",
                ));
            }
        }
        if let Some(r) = self.dynamic_domain {
            PlanError::positive("narrow.dynamic_domain", r)?;
        }
        PlanError::probability("narrow.bridge", self.bridge)?;
        PlanError::probability("narrow.axis_moves", self.axis_moves)?;
        PlanError::probability("narrow.axis_samples", self.axis_samples)?;
        PlanError::positive("narrow.bridge_width", self.bridge_width)
    }

    /// Whether every measure is off.
    pub fn is_off(&self) -> bool {
        self.max_turn.is_none()
            && self.dynamic_domain.is_none()
            && self.bridge == 0.0
            && !self.to_contact
            && self.axis_moves == 0.0
            && self.axis_samples == 0.0
    }

    /// A sample of `space` for extending `tree`: with probability
    /// [`axis_samples`](Self::axis_samples) (free rotation only) axis-aligned —
    /// the tree root's orientation turned about a random axis of the assembly
    /// frame by a uniform angle in [−π, π) — else `space.sample`.
    pub(crate) fn draw(
        &self,
        rng: &mut Rng,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &Tree,
    ) -> Transform {
        if self.axis_samples > 0.0
            && matches!(space.rotation, super::space::RotationFreedom::Free)
            && rng.uniform() < self.axis_samples
        {
            let s = space.sample_translation(rng);
            let axis = [Vec3::x_axis(), Vec3::y_axis(), Vec3::z_axis()][rng.below(3)];
            let angle = rng.range(-std::f64::consts::PI, std::f64::consts::PI);
            let q = UnitQuaternion::from_axis_angle(&axis, angle) * tree.poses[0].rotation();
            return Transform::from_parts(s, q);
        }
        space.sample(rng, reference)
    }

    /// `candidate` (a step from `from`) with its rotation limited to `max_turn`
    /// and its translation kept; `None` when it turns no more than that (or there
    /// is no limit).
    pub(crate) fn limit_turn(&self, from: &Transform, candidate: &Transform) -> Option<Transform> {
        let max_turn = self.max_turn?;
        let angle = from.rotation().angle_to(&candidate.rotation());
        if angle <= max_turn {
            return None;
        }
        let q = from
            .rotation()
            .try_slerp(&candidate.rotation(), max_turn / angle, 1e-12)
            .unwrap_or(from.rotation());
        Some(Transform::from_parts(candidate.translation(), q))
    }

    /// One extension of `tree` from node `near` toward `sample`: the step of at
    /// most `step` (metric mm) along the straight edge; when that is blocked, the
    /// same step turning at most `max_turn`. Returns the added node, or the last
    /// blocked candidate. Keeps the dynamic domains up to date.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn extend(
        &self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &mut Tree,
        near: usize,
        sample: &Transform,
        step: f64,
    ) -> Result<usize, Transform> {
        let from = tree.poses[near];
        let mut candidate = steer(&from, sample, step, space);
        let mut tries = [Some(candidate), self.limit_turn(&from, &candidate)];
        for c in tries.iter_mut().filter_map(Option::take) {
            candidate = c;
            if space.contains(&c, reference) && !tree.holds(&c) && checker.edge_free(&from, &c) {
                if self.dynamic_domain.is_some() {
                    tree.grow_domain(near, 1.1);
                }
                return Ok(tree.add(c, near));
            }
        }
        if let Some(r) = self.dynamic_domain {
            tree.shrink_domain(near, r);
        }
        Err(candidate)
    }

    /// A sample for extending `tree`, and its nearest node: bridge test with
    /// probability `bridge`, else (or when the bridge test finds none) uniform,
    /// redrawn while it lies outside the nearest node's dynamic domain.
    /// Also returns how many nearest-node queries it made (the cost of the
    /// dynamic-domain redraws).
    pub(crate) fn sample(
        &self,
        rng: &mut Rng,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &Tree,
    ) -> (Transform, usize, usize) {
        // A bridge sample already lies in a passage between obstacles: it is not
        // redrawn (redrawing would repeat its collision checks up to
        // DOMAIN_TRIES times, which made the measures together ten times slower
        // than each alone on the rod-round-a-corner problem).
        if self.bridge > 0.0 && rng.uniform() < self.bridge {
            if let Some(s) = self.bridge_sample(rng, checker, space, reference) {
                let (near, _) = tree.nearest(&s, space);
                return (s, near, 1);
            }
        }
        let mut last = None;
        let tries = if self.dynamic_domain.is_some() {
            Self::DOMAIN_TRIES
        } else {
            1
        };
        for k in 1..=tries {
            let s = self.draw(rng, space, reference, tree);
            let (near, d) = tree.nearest(&s, space);
            if d <= tree.domain(near) {
                return (s, near, k);
            }
            last = Some((s, near, k));
        }
        last.expect("at least one try")
    }

    /// [`NarrowPassage::sample`] while the fallbacks are within their share of the
    /// work (`effort`, charged the bridge test's checks and the dynamic-domain
    /// redraws' scans), else a uniform sample; with its nearest node.
    pub(crate) fn sample_within(
        &self,
        effort: &mut Effort,
        rng: &mut Rng,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &Tree,
    ) -> (Transform, usize) {
        match effort.run(checker, |checker| {
            self.sample(rng, checker, space, reference, tree)
        }) {
            Some((s, near, scans)) => {
                // One scan is the plain iteration's own; the redraws are extra.
                effort.charge_scans(scans - 1, tree.len());
                (s, near)
            }
            None => {
                let s = self.draw(rng, space, reference, tree);
                (s, tree.nearest(&s, space).0)
            }
        }
    }

    /// The bridge test: a blocked pose, a second one about `bridge_width` away,
    /// also blocked, and their midpoint when it is free and in the space.
    fn bridge_sample(
        &self,
        rng: &mut Rng,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
    ) -> Option<Transform> {
        for _ in 0..Self::BRIDGE_TRIES {
            let a = space.sample(rng, reference);
            if checker.is_free(&a) {
                continue;
            }
            let b = perturb(rng, &a, self.bridge_width, space);
            if !space.contains(&b, reference) || checker.is_free(&b) {
                continue;
            }
            let mid = a.interpolate(&b, 0.5);
            if space.contains(&mid, reference) && checker.is_free(&mid) {
                return Some(mid);
            }
        }
        None
    }

    /// What a tree search does when its extension from node `near` was blocked at
    /// `candidate`, within the fallbacks' share of the work (`effort`): extension to
    /// contact, then the local discretization `lattice` (candidates ranked toward
    /// `rank`) from the contact pose, or from `near` when there is none. The nodes
    /// added go to `added`; `step` is the search's extension step (metric mm).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn fall_back(
        &self,
        lattice: Option<&Lattice>,
        effort: &mut Effort,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &mut Tree,
        near: usize,
        candidate: &Transform,
        rank: &dyn Target,
        step: f64,
        rng: &mut Rng,
        added: &mut Vec<usize>,
    ) {
        let mut from = near;
        if let Some(Some(c)) = effort.run(checker, |checker| {
            self.extend_to_contact(checker, space, reference, tree, near, candidate)
        }) {
            added.push(c);
            from = c;
        }
        if let Some(lattice) = lattice {
            effort.run(checker, |checker| {
                lattice.expand(
                    checker, space, tree, from, rank, reference, step, rng, added,
                );
            });
        }
    }

    /// Extension to contact: the farthest pose `near → blocked` whose edge from
    /// `near` is free, by 3 bisections (at least an eighth of the edge), added to
    /// `tree`; `None` when even an eighth is blocked.
    pub(crate) fn extend_to_contact(
        &self,
        checker: &mut Checker<'_>,
        space: &PlanningSpace,
        reference: &UnitQuaternion<f64>,
        tree: &mut Tree,
        near: usize,
        blocked: &Transform,
    ) -> Option<usize> {
        if !self.to_contact {
            return None;
        }
        let from = tree.poses[near];
        let (mut lo, mut hi) = (0.0, 1.0);
        let mut best = None;
        for _ in 0..3 {
            let mid = 0.5 * (lo + hi);
            let pose = from.interpolate(blocked, mid);
            if space.contains(&pose, reference)
                && !tree.holds(&pose)
                && checker.edge_free(&from, &pose)
            {
                lo = mid;
                best = Some(pose);
            } else {
                hi = mid;
            }
        }
        best.map(|p| tree.add(p, near))
    }
}

/// `pose` moved by a random translation and turn whose sizes are normal with
/// standard deviation `sigma` metric mm (the turn's share over the rotation weight).
fn perturb(rng: &mut Rng, pose: &Transform, sigma: f64, space: &PlanningSpace) -> Transform {
    let d = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * (sigma / 3f64.sqrt());
    let axis = Vec3::new(rng.normal(), rng.normal(), rng.normal());
    let angle = rng.normal() * sigma / space.rotation_weight;
    let turn = Unit::try_new(axis, 1e-9).map_or(UnitQuaternion::identity(), |a| {
        UnitQuaternion::from_axis_angle(&a, angle)
    });
    Transform::from_parts(pose.translation() + d, turn * pose.rotation())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Point3;

    #[test]
    fn limit_turn_keeps_the_translation() {
        let space = PlanningSpace::new(Vec3::repeat(-100.0), Vec3::repeat(100.0))
            .with_rotation_weight(10.0);
        let from = Transform::IDENTITY;
        let to = Transform::from_rotation_about(Point3::origin(), Vec3::z(), 2.0)
            .unwrap()
            .then(&Transform::from_translation(Vec3::new(40.0, 0.0, 0.0)));
        let n = NarrowPassage {
            max_turn: Some(0.1),
            ..NarrowPassage::OFF
        };
        let plain = steer(&from, &to, 10.0, &space);
        let s = n.limit_turn(&from, &plain).unwrap();
        let (angle, _) = from.distance_to(&s);
        assert!((angle - 0.1).abs() < 1e-9, "{angle}");
        assert!((s.translation() - plain.translation()).norm() < 1e-12);
        // A small turn is left alone, and without a limit nothing changes.
        let near = Transform::from_rotation_about(Point3::origin(), Vec3::z(), 0.05).unwrap();
        assert_eq!(n.limit_turn(&from, &near), None);
        assert_eq!(NarrowPassage::OFF.limit_turn(&from, &plain), None);
    }

    /// Axis-aligned samples turn the tree root's orientation about one axis of
    /// the assembly frame; off, or with the rotation not free, the space's own
    /// samples come back (same draws).
    #[test]
    fn axis_samples_turn_the_root_about_one_frame_axis() {
        let space = PlanningSpace::new(Vec3::repeat(-10.0), Vec3::repeat(10.0));
        let root = Transform::from_rotation_about(Point3::origin(), Vec3::new(1.0, 2.0, 3.0), 0.7)
            .unwrap();
        let tree = Tree::new(root, 0.01);
        let reference = root.rotation();
        let n = NarrowPassage {
            axis_samples: 1.0,
            ..NarrowPassage::OFF
        };
        let mut rng = Rng::new(5);
        let mut seen = [false; 3];
        for _ in 0..100 {
            let s = n.draw(&mut rng, &space, &reference, &tree);
            assert!(space.contains(&s, &reference), "{s}");
            // the turn from the root, in the assembly frame
            let turn = s.rotation() * root.rotation().inverse();
            let axis = turn.axis().expect("a turn");
            let k = (0..3)
                .find(|&k| axis[k].abs() > 1.0 - 1e-9)
                .expect("about one frame axis");
            seen[k] = true;
        }
        assert_eq!(seen, [true; 3]);
        let (mut a, mut b) = (Rng::new(9), Rng::new(9));
        for _ in 0..20 {
            assert_eq!(
                NarrowPassage::OFF.draw(&mut a, &space, &reference, &tree),
                space.sample(&mut b, &reference)
            );
        }
        let fixed = space
            .clone()
            .with_rotation(super::super::space::RotationFreedom::Fixed);
        let s = n.draw(&mut a, &fixed, &reference, &tree);
        assert!(s.rotation().angle_to(&reference) < 1e-12);
    }

    #[test]
    fn rejects_bad_options() {
        for bad in [
            NarrowPassage {
                max_turn: Some(0.0),
                ..NarrowPassage::OFF
            },
            NarrowPassage {
                dynamic_domain: Some(f64::NAN),
                ..NarrowPassage::OFF
            },
            NarrowPassage {
                bridge: 1.5,
                ..NarrowPassage::OFF
            },
            NarrowPassage {
                bridge_width: -1.0,
                ..NarrowPassage::OFF
            },
            NarrowPassage {
                axis_moves: 1.5,
                ..NarrowPassage::OFF
            },
            NarrowPassage {
                axis_samples: -0.1,
                ..NarrowPassage::OFF
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
        NarrowPassage::default().validate().unwrap();
        assert!(NarrowPassage::OFF.is_off());
    }
}
