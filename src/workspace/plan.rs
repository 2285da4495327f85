//! Planning for a component of a document: the request, the problem it becomes
//! (validator, bounds, boxes), re-validation and following a path.

use super::{GivenValue, Workspace, WorkspaceError};
use crate::document::Document;
use crate::math::{Aabb, Transform, Vec3};
use crate::planning::{
    Control, MeshValidator, MeshValidatorOptions, PlannedPath, Planner, PlanningSpace, ProblemFile,
    ProgressFn, RotationFreedom,
};

/// Default growth of the planning bounds around the product box, start and goal,
/// in diameters of the moving part (scale-free: room for the part to pass round
/// the product on every side).
pub const DEFAULT_MARGIN_DIAMETERS: f64 = 1.0;

/// How to plan a path for one component of a document.
#[derive(Debug, Clone)]
pub struct PlanRequest {
    /// The planner and its options: seed, iteration limit, time budget (the whole
    /// call, default [`DEFAULT_TIME_LIMIT_MS`](crate::planning::DEFAULT_TIME_LIMIT_MS)),
    /// step, smoothing. Default `rrt_connect`.
    pub planner: Planner,
    /// Penetration tolerance and edge check of the validator — the one tolerance
    /// rule: [`Workspace::revalidate`] with the same options accepts every path the
    /// planner returns.
    pub validator: MeshValidatorOptions,
    /// Bounds of the component's origin (world, mm); `None`: the box of the other
    /// components with start and goal, grown by `margin_mm`.
    pub bounds: Option<Aabb>,
    /// Growth of the default bounds, mm. `None` (default):
    /// [`DEFAULT_MARGIN_DIAMETERS`] diameters of the component's part (twice its
    /// radius about its origin).
    pub margin_mm: Option<f64>,
    /// Whether the component may turn. Default [`RotationFreedom::Free`].
    pub rotation: RotationFreedom,
    /// Weight of rotation in the metric (mm per rad); `None`: the radius of the
    /// component's part about its origin (scale-free: turning by θ then weighs
    /// what it moves the part's farthest point).
    pub rotation_weight: Option<f64>,
    /// Seed 002's disassembly first (see [`Planner::plan_via_disassembly`]): the end
    /// inside the product box is the assembled one. Default false.
    pub disassemble: bool,
    /// Where the path starts (world, mm); `None`: the component's current pose.
    pub start: Option<Transform>,
}

impl Default for PlanRequest {
    fn default() -> Self {
        Self {
            planner: Planner::by_name("rrt_connect").expect("a planner name"),
            validator: MeshValidatorOptions::default(),
            bounds: None,
            margin_mm: None,
            rotation: RotationFreedom::Free,
            rotation_weight: None,
            disassemble: false,
            start: None,
        }
    }
}

/// The outcome of [`Workspace::revalidate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Revalidation {
    /// Every key pose and edge is free.
    Valid,
    /// The first blocked part: edge `segment` (0 for the start pose itself) and the
    /// pose ending it.
    Blocked {
        /// Index of the first blocked edge (0 also for a blocked start pose).
        segment: usize,
        /// The end pose of that edge (the start pose for a blocked start).
        pose: Transform,
    },
}

impl Revalidation {
    /// Whether the path is still free.
    pub fn is_valid(&self) -> bool {
        matches!(self, Revalidation::Valid)
    }
}

/// The planning problem of one component: validator, space, start, product box.
struct Problem {
    validator: MeshValidator,
    space: PlanningSpace,
    start: Transform,
    product: Aabb,
}

impl Workspace<'_> {
    /// A [`MeshValidator`] for component `name` moving among all the others at
    /// their current poses.
    ///
    /// # Errors
    /// An unknown component, bad validator options.
    pub fn validator(
        &self,
        name: &str,
        options: &MeshValidatorOptions,
    ) -> Result<MeshValidator, WorkspaceError> {
        let index = self.index(name)?;
        let s = self.scene();
        let obstacles = (0..s.poses.len())
            .filter(|&i| i != index && s.is_active(i))
            .map(|i| (s.colliders[i].clone(), s.poses[i]))
            .collect();
        Ok(MeshValidator::new(
            s.colliders[index].clone(),
            obstacles,
            *options,
        )?)
    }

    /// The box of component `name` in its part frame (mm).
    ///
    /// # Errors
    /// An unknown component or an empty mesh.
    pub fn part_box(&self, name: &str) -> Result<Aabb, WorkspaceError> {
        let index = self.index(name)?;
        self.document()
            .mesh_of(index)
            .bounds()
            .ok_or_else(|| WorkspaceError::EmptyMesh(name.into()))
    }

    /// The box of every component but `name` (world, mm): the product a
    /// disassembly leaves; `None` when there is no other component.
    ///
    /// # Errors
    /// An unknown component.
    pub fn product_box(&self, name: &str) -> Result<Option<Aabb>, WorkspaceError> {
        let index = self.index(name)?;
        let doc = self.document();
        Ok((0..doc.components().len())
            .filter(|&i| i != index && !doc.components()[i].is_suppressed())
            .filter_map(|i| doc.world_aabb(i))
            .reduce(|a, b| a.union(&b)))
    }

    /// The planning space of component `name` for `request`: its bounds, or the
    /// product box with the current pose and `through` grown by the margin.
    ///
    /// # Errors
    /// An unknown component, bad bounds or margin.
    pub fn planning_space(
        &self,
        name: &str,
        request: &PlanRequest,
        through: &[Transform],
    ) -> Result<PlanningSpace, WorkspaceError> {
        let start = match request.start {
            Some(s) => s,
            None => self.pose(name)?,
        };
        let (lo, hi) = match request.bounds {
            Some(b) => (b.lo.coords, b.hi.coords),
            None => {
                let radius = self.scene().colliders[self.index(name)?].radius();
                let m = request
                    .margin_mm
                    .unwrap_or(DEFAULT_MARGIN_DIAMETERS * 2.0 * radius);
                if !(m.is_finite() && m >= 0.0) {
                    return Err(WorkspaceError::InvalidOption {
                        option: "margin",
                        value: GivenValue::Number(m),
                        expected: "a finite number of mm ≥ 0",
                    });
                }
                let mut lo = start.translation();
                let mut hi = lo;
                for t in through {
                    lo = lo.inf(&t.translation());
                    hi = hi.sup(&t.translation());
                }
                if let Some(p) = self.product_box(name)? {
                    lo = lo.inf(&p.lo.coords);
                    hi = hi.sup(&p.hi.coords);
                }
                (lo - Vec3::repeat(m), hi + Vec3::repeat(m))
            }
        };
        let weight = match request.rotation_weight {
            Some(w) => w,
            None => self.scene().colliders[self.index(name)?].radius(),
        };
        // A part that is a single point has no radius: the space's default weight.
        let space = PlanningSpace::new(lo, hi).with_rotation(request.rotation);
        Ok(if weight > 0.0 {
            space.with_rotation_weight(weight)
        } else {
            space
        })
    }

    fn problem(
        &self,
        name: &str,
        request: &PlanRequest,
        through: &[Transform],
    ) -> Result<Problem, WorkspaceError> {
        let index = self.index(name)?;
        if self.document().components()[index].fixed {
            return Err(WorkspaceError::FixedComponent(name.into()));
        }
        // Bad options are refused before the validator's meshes and trees are built.
        request.planner.validate()?;
        let space = self.planning_space(name, request, through)?;
        space.validate()?;
        let product = match self.product_box(name)? {
            Some(p) => p,
            None => Aabb::new(space.min, space.max),
        };
        Ok(Problem {
            validator: self.validator(name, &request.validator)?,
            space,
            start: match request.start {
                Some(s) if !s.is_finite() => {
                    return Err(WorkspaceError::InvalidOption {
                        option: "start",
                        value: GivenValue::Pose(Box::new(s)),
                        expected: "a finite pose",
                    })
                }
                Some(s) => s,
                None => self.pose(name)?,
            },
            product,
        })
    }

    /// Plans a path for component `name` from its current pose to `goal` (world,
    /// mm) among all the other components. The whole call — search, smoothing and
    /// any nested search — honours the planner's time budget; a path that is not
    /// found says why in [`PlannedPath::failure`] (e.g. the time limit).
    ///
    /// # Examples
    /// ```
    /// use fitup::document::Document;
    /// use fitup::math::{Transform, Vec3};
    /// use fitup::workspace::{PlanRequest, SceneCache, Workspace};
    ///
    /// let doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
    /// let mut cache = SceneCache::new();
    /// let ws = Workspace::new(&doc, &mut cache).unwrap();
    /// let goal = ws.pose("screw5").unwrap().then(&Transform::from_translation(Vec3::new(0.0, 0.0, 40.0)));
    /// let mut request = PlanRequest::default();
    /// request.planner.limits_mut().time_limit_ms = Some(5_000.0);
    /// let path = ws.plan_path("screw5", &goal, &request, None).unwrap();
    /// assert!(path.found(), "{:?}", path.failure);
    /// assert!(path.time_ms >= path.search_ms);
    /// // The same tolerance rule re-checks it.
    /// assert!(ws.revalidate("screw5", &path, &request.validator).unwrap().is_valid());
    /// // Fixed components are never planned for.
    /// assert!(ws.plan_path("table", &goal, &request, None).is_err());
    /// ```
    ///
    /// # Errors
    /// An unknown or fixed component, bad options, bounds or goal.
    pub fn plan_path(
        &self,
        name: &str,
        goal: &Transform,
        request: &PlanRequest,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<PlannedPath, WorkspaceError> {
        let mut p = self.problem(name, request, &[*goal])?;
        let path = if request.disassemble {
            request.planner.plan_via_disassembly(
                &mut p.validator,
                &p.space,
                &p.start,
                goal,
                &self.part_box(name)?,
                &p.product,
                progress,
            )
        } else {
            request
                .planner
                .plan(&mut p.validator, &p.space, &p.start, goal, progress)
        }?;
        Ok(path)
    }

    /// Plans the problem of a [`ProblemFile`]: its moving component from the
    /// file's start to its goal within its bounds (and its rotation weight unless
    /// `request` sets one); the rest of `request` (planner, budget, validator,
    /// disassembly) as given.
    ///
    /// # Examples
    /// ```
    /// use fitup::document::Document;
    /// use fitup::planning::ProblemFile;
    /// use fitup::workspace::{PlanRequest, SceneCache, Workspace};
    ///
    /// let problem = ProblemFile::read("models/problems/peg_in_hole_500.plan.json".as_ref()).unwrap();
    /// let doc = Document::open(&std::path::Path::new("models/problems").join(&problem.document)).unwrap();
    /// let mut cache = SceneCache::new();
    /// let ws = Workspace::new(&doc, &mut cache).unwrap();
    /// let mut request = PlanRequest { disassemble: true, ..PlanRequest::default() };
    /// request.planner.limits_mut().time_limit_ms = Some(20_000.0);
    /// let path = ws.plan_problem(&problem, &request, None).unwrap();
    /// assert!(path.found(), "{:?}", path.failure);
    /// assert!(path.poses[0].approx_eq(&problem.start, 1e-9, 1e-9));
    /// ```
    ///
    /// # Errors
    /// As [`plan_path`](Self::plan_path) (e.g. the file's component is not in the
    /// document).
    pub fn plan_problem(
        &self,
        problem: &ProblemFile,
        request: &PlanRequest,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<PlannedPath, WorkspaceError> {
        let mut request = request.clone();
        request.start = Some(problem.start);
        request.bounds = Some(problem.bounds);
        request.rotation_weight = request.rotation_weight.or(problem.rotation_weight);
        self.plan_path(&problem.moving_component, &problem.goal, &request, progress)
    }

    /// Seed 002's "can be disassembled, can be assembled" for component `name`:
    /// plans from its current (assembled) pose until its box leaves the box of the
    /// other components, then reverses the path so it ends assembled. Planners
    /// `rrt`, `biased_rrt` and `local_rrt`.
    ///
    /// # Errors
    /// An unknown or fixed component, another planner, bad options.
    pub fn plan_disassembly(
        &self,
        name: &str,
        request: &PlanRequest,
        progress: Option<ProgressFn<'_>>,
    ) -> Result<PlannedPath, WorkspaceError> {
        let mut p = self.problem(name, request, &[])?;
        Ok(request.planner.plan_disassembly(
            &mut p.validator,
            &p.space,
            &p.start,
            &self.part_box(name)?,
            &p.product,
            progress,
        )?)
    }

    /// Checks a path for component `name` again against the document as it is
    /// now, with the validator options the path was planned with (the one tolerance
    /// rule: see [`PlannedPath::revalidate`]).
    ///
    /// # Errors
    /// An unknown component, bad options, a path that was not found.
    pub fn revalidate(
        &self,
        name: &str,
        path: &PlannedPath,
        options: &MeshValidatorOptions,
    ) -> Result<Revalidation, WorkspaceError> {
        if !path.found() {
            return Err(WorkspaceError::PathNotFound);
        }
        let mut v = self.validator(name, options)?;
        Ok(match path.revalidate(&mut v) {
            Ok(()) => Revalidation::Valid,
            Err((segment, pose)) => Revalidation::Blocked { segment, pose },
        })
    }
}

/// Moves component `name` of `doc` along `path` in steps of at most `step_mm` of
/// translation (and as many degrees of rotation), calling `on_step(k, n, pose)`
/// after each move (`k` from 1 to `n`); [`Control::Cancel`] stops with
/// [`WorkspaceError::Cancelled`]. Returns the number of steps.
///
/// # Errors
/// A path that was not found, a step that is not a finite number > 0 or that would
/// make more than [`MAX_SAMPLES`](crate::math::MAX_SAMPLES) poses
/// ([`WorkspaceError::Limit`]), an unknown or fixed component, cancellation.
pub fn follow(
    doc: &mut Document,
    name: &str,
    path: &PlannedPath,
    step_mm: f64,
    mut on_step: impl FnMut(usize, usize, &Transform) -> Control,
) -> Result<usize, WorkspaceError> {
    if !path.found() {
        return Err(WorkspaceError::PathNotFound);
    }
    let index = doc.component_index(name)?;
    // Rotation steps follow the translation step: 1 mm ~ 1°. The poses are counted
    // against the shared cap before any is made.
    let poses = path.densify_as(step_mm, step_mm.to_radians(), "step", step_mm)?;
    let n = poses.len();
    for (k, t) in poses.iter().enumerate() {
        doc.set_transform_at(index, *t)?;
        if on_step(k + 1, n, t) == Control::Cancel {
            return Err(WorkspaceError::Cancelled);
        }
    }
    Ok(n)
}
