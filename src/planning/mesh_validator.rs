//! [`MeshValidator`]: the planners' [`MotionValidator`] over real meshes (exact
//! interference of the moving part's collider with posed obstacle colliders).

use super::validator::{stepwise_edge_free, MotionValidator};
use crate::collision::{
    contact_step, edge_interferes, interferes, surface_distance, Aabb, Collider, CollisionError,
    EdgeOptions, MotionFault, PoseFault, SweepMethod,
};
use crate::math::Deadline;
use crate::math::Transform;
use std::sync::Arc;

/// The finest stepwise edge resolution and contact step accepted, mm: finer steps
/// cannot see anything the 0.01 mm default tolerance does not, and only make one
/// edge check take hours.
pub const MIN_STEP_MM: f64 = 1e-4;
/// The finest stepwise rotation step accepted, rad.
pub const MIN_STEP_RAD: f64 = 1e-6;

/// Options of [`MeshValidator`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshValidatorOptions {
    /// Penetration tolerance (mm, ≥ 0): surfaces crossing no deeper than this count
    /// as touching, which is free. `None` (default): [`default_tolerance`] of the
    /// moving part — [`crate::collision::DEFAULT_TOLERANCE`], at most
    /// [`TOLERANCE_SHARE`] of the part's thinnest extent, so a scene scaled by `k`
    /// is judged alike (the validator reports the value in use,
    /// [`MotionValidator::tolerance`]).
    pub tolerance: Option<f64>,
    /// How edges are checked — the same type the validator reports in
    /// [`PlannedPath::resolution`](super::PlannedPath::resolution). Default
    /// [`SweepMethod::CONTINUOUS`]: [`edge_interferes`] (the part's boxes swept
    /// over the edge, then conservative advancement per triangle pair that can meet,
    /// so no obstacle is jumped over); a pair in contact (within `tolerance / 2`,
    /// touching or sliding) gets a crossing check every `contact_step_mm` (≥
    /// [`MIN_STEP_MM`], raised to half the tolerance; 0.05 by default: a sliding
    /// contact costs one check per 0.05 mm instead of one per 0.005 mm, and a contact
    /// can deepen by at most about half a step between two checks). Or
    /// [`SweepMethod::Stepwise`]: static checks at most `step_mm` (≥
    /// [`MIN_STEP_MM`]) of translation and `step_rad` (≥ [`MIN_STEP_RAD`]) of rotation apart, bisection order,
    /// end pose first; features thinner than a step can be missed.
    pub edge: SweepMethod,
    /// Largest distance (mm) [`MotionValidator::clearance`] looks for; farther
    /// obstacles report this value. `None` (default): the moving part's radius, so
    /// the search scales with the part (scale-free, like the planner's defaults).
    pub clearance_cap: Option<f64>,
}

impl Default for MeshValidatorOptions {
    fn default() -> Self {
        Self {
            tolerance: None,
            edge: SweepMethod::CONTINUOUS,
            clearance_cap: None,
        }
    }
}

/// Largest share of the moving part's thinnest extent the default penetration
/// tolerance may be ([`default_tolerance`]). At 1 %, every part at least 1 mm thin
/// keeps [`crate::collision::DEFAULT_TOLERANCE`]; OMPL.app's spirelli scaled by 0.1
/// (a strip 0.11 mm thin) is judged at 0.0011 mm, and its search makes the same
/// moves as at full size, where 0.01 mm let it through crossings a tenth of the
/// strip deep (unsolved in 20 s; docs/planning.md).
pub const TOLERANCE_SHARE: f64 = 0.01;

/// The default penetration tolerance for `moving` (mm): the CAD contact tolerance
/// [`crate::collision::DEFAULT_TOLERANCE`], at most [`TOLERANCE_SHARE`] of the
/// part's thinnest extent (the smallest side of its box in its own frame); a part
/// with no thickness (a sheet) keeps the CAD tolerance.
pub fn default_tolerance(moving: &Collider) -> f64 {
    let share = TOLERANCE_SHARE * thinnest(moving);
    if share.is_finite() && share > 0.0 {
        crate::collision::DEFAULT_TOLERANCE.min(share)
    } else {
        crate::collision::DEFAULT_TOLERANCE
    }
}

/// The part's thinnest extent (mm): the smallest side of its box in its own frame.
fn thinnest(part: &Collider) -> f64 {
    let b = part.bounds();
    (b.hi - b.lo).min()
}

/// Work done by a [`MeshValidator`] (for benchmarks and reports).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ValidatorStats {
    /// `is_free` calls.
    pub pose_checks: u64,
    /// `edge_free` calls.
    pub edge_checks: u64,
    /// `clearance` calls.
    pub clearance_checks: u64,
    /// Mesh pair queries (interference or distance) that passed the box prefilter.
    pub pair_queries: u64,
}

/// A [`MotionValidator`] for one moving part among fixed obstacles, all meshes.
///
/// Poses place the moving part's frame in the assembly frame (mm); obstacle poses
/// are fixed (part frame → assembly frame). A pose is free when no obstacle
/// interferes deeper than `tolerance` (touching is free). Every query first keeps
/// the obstacles whose world box meets the moving part's (swept) world box.
#[derive(Debug, Clone)]
pub struct MeshValidator {
    moving: Arc<Collider>,
    obstacles: Vec<(Arc<Collider>, Transform, Aabb)>,
    options: MeshValidatorOptions,
    /// The penetration tolerance in use (mm): the options', or the part's default.
    tolerance: f64,
    stats: ValidatorStats,
    near: Vec<usize>,
    deadline: Option<Deadline>,
}

impl MeshValidator {
    /// A validator for `moving` among `obstacles` (collider, pose part → assembly).
    ///
    /// # Errors
    /// [`CollisionError::BadTolerance`] for a negative or non-finite tolerance,
    /// [`CollisionError::BadPose`] for a non-finite obstacle pose,
    /// [`CollisionError::BadMotion`] for a stepwise resolution or contact step
    /// finer than [`MIN_STEP_MM`] / [`MIN_STEP_RAD`] or not finite, or a bad
    /// clearance cap.
    pub fn new(
        moving: Arc<Collider>,
        obstacles: Vec<(Arc<Collider>, Transform)>,
        options: MeshValidatorOptions,
    ) -> Result<Self, CollisionError> {
        let tolerance = match options.tolerance {
            Some(t) if !(t.is_finite() && t >= 0.0) => {
                return Err(CollisionError::BadTolerance(t));
            }
            Some(t) => t,
            None => default_tolerance(&moving),
        };
        if let SweepMethod::Stepwise {
            step_mm: mm,
            step_rad: rad,
        } = options.edge
        {
            if !(mm.is_finite() && mm >= MIN_STEP_MM) {
                return Err(MotionFault::option(
                    "stepwise edge step (mm)",
                    mm,
                    "a finite number of at least MIN_STEP_MM = 1e-4 mm",
                ));
            }
            if !(rad.is_finite() && rad >= MIN_STEP_RAD) {
                return Err(MotionFault::option(
                    "stepwise edge rotation step (rad)",
                    rad,
                    "a finite angle of at least MIN_STEP_RAD = 1e-6 rad",
                ));
            }
        }
        if let SweepMethod::Continuous { contact_step_mm: c } = options.edge {
            if !(c.is_finite() && c >= MIN_STEP_MM) {
                return Err(MotionFault::option(
                    "contact step (mm)",
                    c,
                    "a finite number of at least MIN_STEP_MM = 1e-4 mm",
                ));
            }
        }
        if let Some(cap) = options
            .clearance_cap
            .filter(|c| !(c.is_finite() && *c > 0.0))
        {
            return Err(MotionFault::option(
                "clearance cap",
                cap,
                "a finite number > 0 mm",
            ));
        }
        let obstacles = obstacles
            .into_iter()
            .enumerate()
            .map(|(i, (c, pose))| {
                if pose.is_finite() {
                    let b = c.world_bounds(&pose);
                    Ok((c, pose, b))
                } else {
                    Err(CollisionError::BadPose(PoseFault::Obstacle(i)))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            moving,
            obstacles,
            options,
            tolerance,
            stats: ValidatorStats::default(),
            near: Vec::new(),
            deadline: None,
        })
    }

    /// The options given.
    pub fn options(&self) -> &MeshValidatorOptions {
        &self.options
    }

    /// The moving part's collider.
    pub fn moving(&self) -> &Arc<Collider> {
        &self.moving
    }

    /// Checks and mesh queries made so far.
    pub fn stats(&self) -> ValidatorStats {
        self.stats
    }

    /// Resets [`stats`](Self::stats) to zero.
    pub fn reset_stats(&mut self) {
        self.stats = ValidatorStats::default();
    }

    /// Fills `self.near` with the obstacles whose world box comes within `margin`
    /// (mm) of `region`.
    fn collect_near(&mut self, region: &Aabb, margin: f64) {
        self.near.clear();
        for (i, (_, _, b)) in self.obstacles.iter().enumerate() {
            if region.overlap(b).min() >= -margin {
                self.near.push(i);
            }
        }
    }

    /// Fills `self.near` with the obstacles the part can meet along `from → to`
    /// (`angle`: the edge's rotation, rad).
    fn collect_swept(&mut self, from: &Transform, to: &Transform, angle: f64) {
        // Every point of the part moves along (chord + arc): within the union of the
        // end boxes grown by the arc's sagitta.
        let mut swept = self.moving.world_bounds(from);
        let b = self.moving.world_bounds(to);
        swept.grow(&b.lo);
        swept.grow(&b.hi);
        let bulge = self.moving.radius() * (1.0 - (angle.min(std::f64::consts::PI) / 2.0).cos());
        self.collect_near(&swept, bulge);
    }

    /// Whether the caller's deadline has passed (then every check answers "not free").
    fn expired(&self) -> bool {
        self.deadline.is_some_and(Deadline::passed)
    }

    /// Static check of the obstacles in `self.near` (`false` for a bad pose or a
    /// passed deadline).
    fn free_among_near(&mut self, pose: &Transform) -> bool {
        if self.expired() {
            return false;
        }
        for k in 0..self.near.len() {
            let (c, p, _) = &self.obstacles[self.near[k]];
            self.stats.pair_queries += 1;
            match interferes(&self.moving, pose, c, p, self.tolerance) {
                Ok(false) => {}
                _ => return false,
            }
        }
        true
    }

    fn pose_free(&mut self, pose: &Transform) -> bool {
        if !pose.is_finite() {
            return false;
        }
        let b = self.moving.world_bounds(pose);
        self.collect_near(&b, 0.0);
        self.free_among_near(pose)
    }

    /// The options of the continuous edge check.
    fn edge_options(&self) -> EdgeOptions {
        EdgeOptions {
            tolerance: self.tolerance,
            contact_step: match self.options.edge {
                SweepMethod::Continuous { contact_step_mm } => contact_step_mm,
                SweepMethod::Stepwise { .. } => SweepMethod::DEFAULT_CONTACT_STEP_MM,
            },
        }
    }

    /// The longest piece of a continuous edge check (mm of point displacement):
    /// [`PIECE_REACH`] radii of the moving part, at most its thinnest extent, at
    /// least [`MIN_PIECE_REACH`] radii.
    fn piece_reach(&self) -> f64 {
        let r = self.moving.radius();
        (PIECE_REACH * r)
            .min(thinnest(&self.moving))
            .max(MIN_PIECE_REACH * r)
    }

    /// Continuous check of `from → to` (`to` already known free) against every
    /// obstacle the swept part can reach ([`edge_interferes`]).
    fn continuous_edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        let (angle, dist) = from.distance_to(to);
        self.collect_swept(from, to, angle);
        if self.near.is_empty() {
            return true;
        }
        // Long edges (shortcuts, direct connections) that fail mostly fail somewhere
        // in the middle, where a continuous pass would crawl along a near contact
        // first: 15 static checks in bisection order reject them cheaply.
        let r = self.moving.radius();
        if dist + angle * r > PRESAMPLE_REACH * r {
            for level in 1..=4u32 {
                let n = 1u32 << level;
                for m in (1..n).step_by(2) {
                    let pose = from.interpolate(to, f64::from(m) / f64::from(n));
                    if !self.free_among_near(&pose) {
                        return false;
                    }
                }
            }
        }
        let options = self.edge_options();
        // One continuous check along a long sliding contact can take a second; in
        // pieces of at most PIECE_REACH_MM (a piece of a straight SE(3) edge is
        // the straight edge between its ends, so nothing changes but where the
        // deadline is read) no single call overruns the caller's budget by much.
        let reach = dist + angle * r;
        let pieces = (reach / self.piece_reach()).ceil().clamp(1.0, 1e6) as u32;
        let mut a = *from;
        for i in 1..=pieces {
            let b = if i == pieces {
                *to
            } else {
                from.interpolate(to, f64::from(i) / f64::from(pieces))
            };
            for k in 0..self.near.len() {
                if self.expired() {
                    return false;
                }
                let (c, p, _) = &self.obstacles[self.near[k]];
                self.stats.pair_queries += 1;
                match edge_interferes(&self.moving, &a, &b, c, p, &options) {
                    Ok(false) => {}
                    _ => return false,
                }
            }
            a = b;
        }
        true
    }
}

/// Edges longer than this (largest point displacement, in radii of the moving
/// part) get static checks at 15 inner poses before the continuous pass.
const PRESAMPLE_REACH: f64 = 0.5;
/// The continuous check runs in pieces whose points move at most this far (in
/// radii of the moving part), reading the deadline between them: in a sliding
/// contact the check steps by about the contact step (0.05 mm by default), so a
/// piece must be short enough for the deadline to be read often; but each piece
/// is a traversal of the trees of its own, which long edges of a large part in
/// open space (a table carried through a house: edges of 200 mm) must not pay
/// hundreds of times.
///
/// A piece is also at most the part's thinnest extent: a piece's swept boxes
/// grow with its length, and a thin part sliding in a tight channel (OMPL.app's
/// spirelli, a strip 1.1 thick and 14.8 in radius, screwed through a block)
/// met most of the channel's walls in pieces of a quarter radius: 25k node pairs
/// per piece, 1k in pieces of its thickness, and the whole call took 4.5 s
/// instead of 12 s (same path). Parts whose thinnest side exceeds a quarter
/// radius (every other OMPL.app robot: 0.39–1.0 radii) keep the quarter radius,
/// where shorter pieces cost more traversals than they save (Apartment 1.8×).
const PIECE_REACH: f64 = 0.25;
/// The shortest piece, in radii of the moving part (a flat part has no
/// thickness to bound its pieces by).
const MIN_PIECE_REACH: f64 = 0.05;

/// A total order of poses (translation, then rotation, by their numbers), which
/// fixes the direction an edge is swept in whatever the direction it is asked in.
fn precedes(a: &Transform, b: &Transform) -> bool {
    let (ta, tb) = (a.translation(), b.translation());
    let (qa, qb) = (a.rotation(), b.rotation());
    let ka = [ta.x, ta.y, ta.z, qa.w, qa.i, qa.j, qa.k];
    let kb = [tb.x, tb.y, tb.z, qb.w, qb.i, qb.j, qb.k];
    ka.iter()
        .zip(&kb)
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .is_some_and(std::cmp::Ordering::is_lt)
}

impl MotionValidator for MeshValidator {
    fn is_free(&mut self, pose: &Transform) -> bool {
        self.stats.pose_checks += 1;
        self.pose_free(pose)
    }

    fn tolerance(&self) -> f64 {
        self.tolerance
    }

    fn resolution(&self) -> SweepMethod {
        match self.options.edge {
            SweepMethod::Continuous { .. } => SweepMethod::Continuous {
                contact_step_mm: contact_step(self.edge_options().contact_step, self.tolerance),
            },
            stepwise => stepwise,
        }
    }

    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        self.stats.edge_checks += 1;
        if !(from.is_finite() && to.is_finite()) {
            return false;
        }
        // Blocked edges mostly end in collision: the end pose first.
        if !self.pose_free(to) {
            return false;
        }
        // The same verdict both ways: the motion is swept from the end that sorts
        // first. A path runs its goal tree's edges backwards, and near a contact
        // at the tolerance a sweep from one end can step onto a depth that one
        // from the other steps over.
        let (from, to) = if precedes(to, from) {
            (to, from)
        } else {
            (from, to)
        };
        match self.options.edge {
            SweepMethod::Continuous { .. } => self.continuous_edge_free(from, to),
            SweepMethod::Stepwise {
                step_mm: mm,
                step_rad: rad,
            } => {
                let (angle, _) = from.distance_to(to);
                self.collect_swept(from, to, angle);
                if self.near.is_empty() {
                    return true;
                }
                stepwise_edge_free(|p| self.free_among_near(p), from, to, mm, rad)
            }
        }
    }

    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.deadline = deadline;
    }

    fn part_radius(&self) -> Option<f64> {
        Some(self.moving.radius())
    }

    fn part_thickness(&self) -> Option<f64> {
        Some(thinnest(&self.moving))
    }

    /// A copy sharing the colliders (`Arc`s), with zeroed counters and no deadline.
    fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        let mut copy = self.clone();
        copy.stats = ValidatorStats::default();
        copy.deadline = None;
        Some(Box::new(copy))
    }

    fn clearance(&mut self, pose: &Transform) -> Option<f64> {
        self.stats.clearance_checks += 1;
        if !pose.is_finite() {
            return None;
        }
        let cap = self
            .options
            .clearance_cap
            .unwrap_or_else(|| self.moving.radius());
        let b = self.moving.world_bounds(pose);
        self.collect_near(&b, cap);
        let mut d = cap;
        for k in 0..self.near.len() {
            let (c, p, _) = &self.obstacles[self.near[k]];
            self.stats.pair_queries += 1;
            match surface_distance(&self.moving, pose, c, p, 0.0) {
                Ok(x) => d = d.min(x),
                Err(_) => return None,
            }
        }
        Some(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Vec3};
    use crate::mesh::Mesh;

    fn collider(m: Mesh) -> Arc<Collider> {
        Arc::new(Collider::new(Arc::new(m)).unwrap())
    }

    /// A 10 mm cube moving over a wall 1 mm thick at x = 50.
    fn wall_scene(edge: SweepMethod) -> MeshValidator {
        let cube = collider(Mesh::cuboid(
            Point3::new(-5.0, -5.0, -5.0),
            Point3::new(5.0, 5.0, 5.0),
        ));
        let wall = collider(Mesh::cuboid(
            Point3::new(50.0, -100.0, -100.0),
            Point3::new(51.0, 100.0, 100.0),
        ));
        MeshValidator::new(
            cube,
            vec![(wall, Transform::IDENTITY)],
            MeshValidatorOptions {
                edge,
                ..Default::default()
            },
        )
        .unwrap()
    }

    fn at(x: f64) -> Transform {
        Transform::from_translation(Vec3::new(x, 0.0, 0.0))
    }

    /// Pieces of a continuous check are at most a quarter of the part's radius,
    /// at most its thinnest side, and not shorter than 0.05 radii.
    #[test]
    fn pieces_are_bounded_by_the_radius_and_the_thinnest_side() {
        let piece = |lo: [f64; 3], hi: [f64; 3]| {
            let part = collider(Mesh::cuboid(Point3::from(lo), Point3::from(hi)));
            let r = part.radius();
            let v = MeshValidator::new(part, vec![], MeshValidatorOptions::default()).unwrap();
            (v.piece_reach(), r)
        };
        let (p, r) = piece([-5.0; 3], [5.0; 3]);
        assert!((p - 0.25 * r).abs() < 1e-12, "a cube: a quarter radius");
        let (p, r) = piece([-1.0, -20.0, -3.0], [1.0, 20.0, 3.0]);
        assert!(p < 0.25 * r);
        assert!((p - 2.0).abs() < 1e-12, "a strip 2 thick: its thickness");
        let (p, r) = piece([0.0, -20.0, -3.0], [0.0, 20.0, 3.0]);
        assert!((p - 0.05 * r).abs() < 1e-12, "a flat sheet: 0.05 radii");
    }

    /// A pose check in contact (touching the wall) visits more node pairs than
    /// one far away, and the checker's cost (what racing searches compare)
    /// counts them.
    #[test]
    fn collision_effort_grows_near_contact_and_counts_as_work() {
        let mut v = wall_scene(SweepMethod::CONTINUOUS);
        let effort = |v: &mut MeshValidator, x: f64| {
            let before = crate::collision::effort();
            v.is_free(&at(x));
            crate::collision::effort() - before
        };
        let far = effort(&mut v, 0.0);
        let near = effort(&mut v, 45.0);
        assert!(near > far, "near {near} vs far {far}");
        let mut checker = crate::planning::validator::Checker::new(&mut v, None);
        let (w0, c0) = (checker.work(), checker.cost());
        for _ in 0..100 {
            checker.is_free(&at(45.0));
        }
        assert_eq!(checker.work() - w0, 100, "one unit per check");
        assert!(checker.cost() - c0 > 100, "more than the checks' count");
    }

    /// A cube of side 10k pressed into a wall by `push` sides, for scale `k`:
    /// whether the default validator calls the pose free, and its tolerance.
    fn pressed(k: f64, push: f64) -> (bool, f64) {
        let cube = collider(Mesh::cuboid(
            Point3::new(-5.0 * k, -5.0 * k, -5.0 * k),
            Point3::new(5.0 * k, 5.0 * k, 5.0 * k),
        ));
        let wall = collider(Mesh::cuboid(
            Point3::new(5.0 * k, -100.0 * k, -100.0 * k),
            Point3::new(6.0 * k, 100.0 * k, 100.0 * k),
        ));
        let mut v = MeshValidator::new(
            cube,
            vec![(wall, Transform::IDENTITY)],
            MeshValidatorOptions::default(),
        )
        .unwrap();
        let pose = Transform::from_translation(Vec3::new(push * 10.0 * k, 0.0, 0.0));
        (v.is_free(&pose), v.tolerance())
    }

    #[test]
    fn the_default_tolerance_scales_down_with_a_thin_part() {
        for k in [0.01, 0.1, 1.0, 10.0, 100.0] {
            let side = 10.0 * k;
            let (_, tol) = pressed(k, 0.0);
            let want = crate::collision::DEFAULT_TOLERANCE.min(TOLERANCE_SHARE * side);
            assert!(
                (tol - want).abs() <= 1e-15,
                "k {k}: tolerance {tol}, want {want}"
            );
            // pressed in by 2 % of its side: blocked at every scale (a fixed
            // 0.01 mm let a 0.1 mm cube 10 % of its side into the wall)
            assert!(!pressed(k, 0.02).0, "k {k}: pressed 2 % of its side in");
            // touching is free at every scale
            assert!(pressed(k, -1e-9).0, "k {k}: touching");
        }
        // below 1 mm the verdict is the same at every scale: 0.5 % in is touching
        for k in [0.01, 0.1] {
            assert!(pressed(k, 0.005).0, "k {k}: 0.5 % of its side in");
        }
        // an explicit tolerance is the one used
        let cube = collider(Mesh::cuboid(Point3::origin(), Point3::new(0.1, 0.1, 0.1)));
        let o = MeshValidatorOptions {
            tolerance: Some(0.05),
            ..Default::default()
        };
        assert_eq!(
            MeshValidator::new(cube, vec![], o).unwrap().tolerance(),
            0.05
        );
        // a part with no thickness (a sheet) keeps the CAD tolerance
        let sheet = collider(
            Mesh::new(
                vec![
                    Point3::origin(),
                    Point3::new(1.0, 0.0, 0.0),
                    Point3::new(0.0, 1.0, 0.0),
                ],
                vec![[0, 1, 2]],
            )
            .unwrap(),
        );
        assert_eq!(
            default_tolerance(&sheet),
            crate::collision::DEFAULT_TOLERANCE
        );
    }

    #[test]
    fn touching_is_free_and_crossing_is_not() {
        let mut v = wall_scene(SweepMethod::CONTINUOUS);
        assert!(v.is_free(&at(0.0)));
        assert!(v.is_free(&at(45.0)), "touching the wall");
        assert!(!v.is_free(&at(45.5)));
        assert!(!v.is_free(&at(50.5)), "straddling the wall");
        // The default cap is the part's radius (a 10 mm cube: 8.66 mm).
        let cap = v.moving().radius();
        assert_eq!(v.clearance(&at(40.0)), Some(5.0));
        assert!((v.clearance(&at(0.0)).unwrap() - cap).abs() < 1e-9);
        assert_eq!(v.stats().pose_checks, 4);
    }

    #[test]
    fn continuous_edges_never_jump_a_thin_wall() {
        let mut v = wall_scene(SweepMethod::CONTINUOUS);
        // both ends free, the wall in between
        assert!(v.is_free(&at(70.0)));
        assert!(!v.edge_free(&at(0.0), &at(70.0)));
        assert!(v.edge_free(&at(0.0), &at(45.0)));
        // a turn that swings a corner through the wall
        let turn =
            Transform::from_rotation_about(Point3::new(44.0, 0.0, 0.0), Vec3::z(), 0.8).unwrap();
        let start = at(44.0);
        assert!(!v.edge_free(&start, &start.then(&turn)));
        // a coarse stepwise check jumps the wall, as documented
        let mut s = wall_scene(SweepMethod::Stepwise {
            step_mm: 100.0,
            step_rad: 1.0,
        });
        assert!(s.edge_free(&at(0.0), &at(70.0)));
        let mut s = wall_scene(SweepMethod::Stepwise {
            step_mm: 0.5,
            step_rad: 0.01,
        });
        assert!(!s.edge_free(&at(0.0), &at(70.0)));
    }

    #[test]
    fn bad_options_and_poses_are_refused() {
        let cube = collider(Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0)));
        let bad = |o: MeshValidatorOptions| MeshValidator::new(cube.clone(), vec![], o).is_err();
        assert!(bad(MeshValidatorOptions {
            tolerance: Some(-1.0),
            ..Default::default()
        }));
        assert!(bad(MeshValidatorOptions {
            edge: SweepMethod::Stepwise {
                step_mm: 0.0,
                step_rad: 0.1,
            },
            ..Default::default()
        }));
        assert!(bad(MeshValidatorOptions {
            clearance_cap: Some(f64::NAN),
            ..Default::default()
        }));
        let nan = Transform::from_translation(Vec3::new(f64::NAN, 0.0, 0.0));
        assert!(
            MeshValidator::new(cube.clone(), vec![(cube.clone(), nan)], Default::default())
                .is_err()
        );
        let mut v = wall_scene(SweepMethod::CONTINUOUS);
        assert!(!v.is_free(&nan));
        assert!(!v.edge_free(&at(0.0), &nan));
    }

    /// The face-on-face verdict is monotone in how far the part is pushed: a bar
    /// face pressed into a wall (square, or tilted by 1e-12 … 1e-2 rad about
    /// several axes) is free up to the tolerance and blocked past it, with one
    /// change of verdict over 0.0095 … 0.0105 mm, and a pose re-interpolated onto
    /// itself (the last bits differ) gets the same verdict away from the
    /// threshold (issue 23: a 0.0001 mm jump was reported around the tolerance).
    #[test]
    fn face_contact_verdict_is_monotone_in_the_push() {
        let bar = collider(Mesh::cuboid(
            Point3::new(-20.0, -10.0, -2.0),
            Point3::new(20.0, 10.0, 2.0),
        ));
        let wall = collider(Mesh::cuboid(
            Point3::new(0.0, -90.0, -90.0),
            Point3::new(5.0, 90.0, 90.0),
        ));
        let mut v = MeshValidator::new(
            bar.clone(),
            vec![(wall, Transform::IDENTITY)],
            MeshValidatorOptions::default(),
        )
        .unwrap();
        let tol = v.tolerance();
        let axes = [Vec3::y(), Vec3::z(), Vec3::new(0.3, 1.0, -0.7)];
        for axis in axes {
            for tilt in [0.0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-2] {
                let r = Transform::from_rotation_about(Point3::origin(), axis, tilt).unwrap();
                // the deepest corner's x with the part at the origin
                let x0 = bar
                    .mesh()
                    .vertices
                    .iter()
                    .map(|p| (r.isometry() * p).x)
                    .fold(f64::MIN, f64::max);
                let mut changes = 0;
                let mut last = true;
                for k in 0..=400 {
                    let push = tol - 0.0005 + 2.5e-6 * f64::from(k);
                    let t = Vec3::new(push - x0, 3.3, 1.0);
                    let pose = r.then(&Transform::from_translation(t));
                    let free = v.is_free(&pose);
                    if k > 0 && free != last {
                        changes += 1;
                    }
                    last = free;
                    if (push - tol).abs() > 1e-6 {
                        assert_eq!(free, push < tol, "push {push}, tilt {tilt} about {axis:?}");
                        let far =
                            pose.then(&Transform::from_translation(Vec3::new(-30.0, 1.0, 2.0)));
                        let again = far.interpolate(&pose, 1.0);
                        assert_eq!(v.is_free(&again), free, "re-interpolated, push {push}");
                    }
                }
                assert_eq!(changes, 1, "tilt {tilt} about {axis:?}");
            }
        }
    }
}
