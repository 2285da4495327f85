//! Options, errors and results of assembly sequence planning.

use super::graph::RelationGraph;
use super::task::Task;
use crate::math::Vec3;
use crate::workspace::{GivenValue, WorkspaceError};
use std::collections::BTreeMap;

/// Default time budget of one sequence-planning call (ms): 30 s, everything included
/// (scene, contacts, blocking graph, direction search, planned paths, safe lengths,
/// grasps); the call returns within 5 % of it.
pub const DEFAULT_SEQUENCE_TIME_LIMIT_MS: f64 = 30_000.0;

/// Default largest gap (mm) at which two components count as touching for support:
/// a part held 1 mm clear inside a housing (a clip in a duct) is held by it.
pub const DEFAULT_CONTACT_GAP_MM: f64 = 1.5;

/// Most components a document may have for sequence planning.
pub const MAX_COMPONENTS: usize = 128;

/// Where the relations between components come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Mode {
    /// Seed 003: the document's mates (relation graph, freedoms, composite nodes).
    /// A document without mates among the product's components is planned in
    /// [`Mode::Geometry`] instead (the plan reports the mode used).
    #[default]
    Mates,
    /// Meshes only: contacts (within the contact gap) in the assembled pose and a
    /// directional blocking graph over ±X/±Y/±Z and the contact normals; parts those
    /// do not free get directions from their geometry (normals of near faces,
    /// principal axes, away from their neighbours), then a seeded sphere of
    /// directions refined near the free ones (mates ignored).
    Geometry,
}

impl Mode {
    /// `mates` or `geometry`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Mates => "mates",
            Mode::Geometry => "geometry",
        }
    }

    /// Parses [`Mode::name`].
    pub fn parse(s: &str) -> Option<Mode> {
        match s {
            "mates" => Some(Mode::Mates),
            "geometry" => Some(Mode::Geometry),
            _ => None,
        }
    }
}

/// The end effector of seed 003 (a two-finger gripper) as boxes: each finger is a box
/// `thickness × width × length` (mm) slid along the grasp plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gripper {
    /// Finger thickness along the closing direction (mm).
    pub finger_thickness: f64,
    /// Finger width across the closing and mating directions (mm); 0: half the part's
    /// extent across.
    pub finger_width: f64,
    /// Largest opening between the fingers (mm): wider face pairs are not grasped.
    pub max_opening: f64,
}

impl Default for Gripper {
    fn default() -> Self {
        Gripper {
            finger_thickness: 1.0,
            finger_width: 0.0,
            max_opening: 200.0,
        }
    }
}

/// The most sequences a call ranks ([`SequenceOptions::max_sequences`]): each one kept
/// becomes tasks with safe lengths and grasps, and the search's memo keeps up to this
/// many costs a state (within [`MAX_SEARCH_MEMO_BYTES`](crate::sequence::MAX_SEARCH_MEMO_BYTES)).
pub const MAX_SEQUENCES: usize = 1000;

/// How to plan an assembly sequence. Lengths mm, angles radians.
#[derive(Debug, Clone)]
pub struct SequenceOptions {
    /// Mates (default) or geometry only.
    pub mode: Mode,
    /// Pin the base component (seed 003: "the user can pin a base"); `None`: chosen by
    /// size.
    pub base: Option<String>,
    /// Pin the first components after the base, in order.
    pub order: Vec<String>,
    /// How many sequences to return, best first (default 5).
    pub max_sequences: usize,
    /// Wall-clock budget of the whole call (ms); default
    /// [`DEFAULT_SEQUENCE_TIME_LIMIT_MS`].
    pub time_limit_ms: Option<f64>,
    /// Seed of the planner fallback (the only randomized part).
    pub seed: u64,
    /// Penetration tolerance of every interference check (mm); default
    /// [`crate::collision::DEFAULT_TOLERANCE`]. Never finer than the document's
    /// [`mesh_deflection`](crate::document::Document::mesh_deflection): a mesh
    /// tessellated from exact surfaces is known to that much only (an imported
    /// bolt's facets cross its bore's by up to the deflection).
    pub tolerance: f64,
    /// Fits (interferences of the assembled pose) no deeper than this (mm, their
    /// reported depth) may also slide: a press fit, a card modelled a little wider
    /// than the guides it slides down. Along a straight motion from the assembled
    /// pose such a part may overlap its fit partner, along every line of the motion,
    /// only where it overlapped it assembled and by no more; deeper fits (a bolt
    /// modelled through a plate without its hole) keep to the overlap of the
    /// assembled pose. Default 2; 0 turns sliding off.
    pub slide_fit_mm: f64,
    /// How far a part is separated along a free direction to test it (mm, larger than
    /// the largest fit clearance; seed 003 section 2.1 step 2). Default 0.5.
    pub probe_mm: f64,
    /// Step of the safe-length search and the two-segment slide (mm; the blocking
    /// sweeps are continuous and take no step); 0: 1 % of the
    /// smallest part's box diagonal, clamped to 0.05..2 mm.
    pub step_mm: f64,
    /// Mass (any unit) per component or part name, for the base choice; missing:
    /// the mesh volume (mm³).
    pub masses: BTreeMap<String, f64>,
    /// Components or parts marked threaded: their tasks are `screw`.
    pub threaded: Vec<String>,
    /// A base is inactive when its size is below this fraction of its largest
    /// related part (seed 003 section 2.2 step 2). Default 0.2.
    pub small_base_ratio: f64,
    /// Largest angle (rad) between two consecutive mating directions that needs no
    /// re-mounting of the base. Default 0 (every change of direction re-mounts).
    pub max_tilt: f64,
    /// Plan a path with fitup's planners (`local_rrt` disassembly among the parts
    /// already assembled) when no straight insertion exists. Default true.
    pub planner_fallback: bool,
    /// Budget of one planner fallback call (ms), within the call's budget. Default 5000.
    pub fallback_time_limit_ms: f64,
    /// The gripper used for grasps.
    pub gripper: Gripper,
    /// The product's components (names): only they are sequenced, and the other
    /// components are ignored (neither moved nor obstacles). Empty (default): every
    /// component except robot links, components the document marks `fixture: true`
    /// and `exclude` (a fixture named here is taken in).
    pub components: Vec<String>,
    /// Components that are not part of the product (fixtures, the table, pedestals):
    /// ignored like robot links, which are always left out.
    pub exclude: Vec<String>,
    /// Physically plausible sequences (default true): every added part touches (within
    /// `contact_gap_mm`) a part already placed, so no intermediate sub-assembly has
    /// a floating part. `false`: parts may be placed where nothing holds them yet.
    pub support: bool,
    /// Largest gap (mm) at which two components count as touching (support, and the
    /// contact graph of geometry mode). Default [`DEFAULT_CONTACT_GAP_MM`].
    pub contact_gap_mm: f64,
    /// The down direction (any non-zero length, assembly frame) when gravity must be
    /// respected: every part then moves down or sideways into place (its mating
    /// direction at most 90° from down). `None` (default): any direction.
    pub gravity: Option<Vec3>,
    /// An insertion is difficult (ranked after easier orders) when the part cannot
    /// move this far (mm) sideways in its assembled pose among the parts already
    /// placed in at least two directions across its mating direction (a bore), or
    /// when its path is planned. Default 0.5.
    pub tight_clearance_mm: f64,
    /// Directions on the sampled sphere (geometry mode, parts no other candidate
    /// frees; rotated by `seed`). Default 48; 0 turns the sphere off.
    pub sphere_directions: usize,
}

impl Default for SequenceOptions {
    fn default() -> Self {
        SequenceOptions {
            mode: Mode::Mates,
            base: None,
            order: Vec::new(),
            max_sequences: 5,
            time_limit_ms: None,
            seed: 0,
            tolerance: crate::collision::DEFAULT_TOLERANCE,
            slide_fit_mm: 2.0,
            probe_mm: 0.5,
            step_mm: 0.0,
            masses: BTreeMap::new(),
            threaded: Vec::new(),
            small_base_ratio: 0.2,
            max_tilt: 0.0,
            planner_fallback: true,
            fallback_time_limit_ms: 5_000.0,
            gripper: Gripper::default(),
            components: Vec::new(),
            exclude: Vec::new(),
            support: true,
            contact_gap_mm: DEFAULT_CONTACT_GAP_MM,
            gravity: None,
            tight_clearance_mm: 0.5,
            sphere_directions: 48,
        }
    }
}

impl SequenceOptions {
    /// Checks every option's range (the one place they are checked, before anything
    /// is built); returns the call's time limit (ms), the default when none is given.
    ///
    /// # Errors
    /// [`SequenceError::InvalidOption`] naming the first option out of range, its
    /// value and what is accepted.
    pub fn validate(&self) -> Result<f64, SequenceError> {
        let bad = |option: &'static str, v: f64, expected: &'static str| {
            Err(SequenceError::InvalidOption {
                option,
                value: GivenValue::Number(v),
                expected,
            })
        };
        let limit = self.time_limit_ms.unwrap_or(DEFAULT_SEQUENCE_TIME_LIMIT_MS);
        let finite_at_least = |v: f64, min: f64| v.is_finite() && v >= min;
        let finite_above = |v: f64, min: f64| v.is_finite() && v > min;
        let checks: [(&'static str, f64, bool, &'static str); 10] = [
            (
                "time_limit_ms",
                limit,
                finite_above(limit, 0.0),
                "a finite number of ms > 0",
            ),
            (
                "tolerance",
                self.tolerance,
                finite_at_least(self.tolerance, 0.0),
                "a finite number of mm ≥ 0",
            ),
            (
                "slide_fit_mm",
                self.slide_fit_mm,
                finite_at_least(self.slide_fit_mm, 0.0),
                "a finite number of mm ≥ 0",
            ),
            (
                "probe_mm",
                self.probe_mm,
                finite_above(self.probe_mm, 0.0) && self.probe_mm < 1e6,
                "a finite number of mm > 0",
            ),
            (
                "step_mm",
                self.step_mm,
                finite_at_least(self.step_mm, 0.0) && self.step_mm < 1e6,
                "a finite number of mm ≥ 0 (0: automatic)",
            ),
            (
                "max_tilt",
                self.max_tilt,
                finite_at_least(self.max_tilt, 0.0),
                "a finite angle ≥ 0",
            ),
            (
                "small_base_ratio",
                self.small_base_ratio,
                finite_at_least(self.small_base_ratio, 0.0),
                "a finite number ≥ 0",
            ),
            (
                "fallback_time_limit_ms",
                self.fallback_time_limit_ms,
                finite_above(self.fallback_time_limit_ms, 0.0),
                "a finite number of ms > 0",
            ),
            (
                "contact_gap_mm",
                self.contact_gap_mm,
                finite_at_least(self.contact_gap_mm, 0.0),
                "a finite number of mm ≥ 0",
            ),
            (
                "tight_clearance_mm",
                self.tight_clearance_mm,
                finite_at_least(self.tight_clearance_mm, 0.0),
                "a finite number of mm ≥ 0",
            ),
        ];
        if let Some(&(option, v, _, expected)) = checks.iter().find(|c| !c.2) {
            return bad(option, v, expected);
        }
        if self.sphere_directions > 4096 {
            return bad(
                "sphere_directions",
                self.sphere_directions as f64,
                "at most 4096",
            );
        }
        if let Some(g) = self.gravity {
            if !(g.iter().all(|v| v.is_finite()) && g.norm() > 1e-12) {
                return Err(SequenceError::InvalidOption {
                    option: "gravity",
                    value: GivenValue::Numbers(g.as_slice().to_vec()),
                    expected: "a finite non-zero down direction",
                });
            }
        }
        if self.max_sequences == 0 || self.max_sequences > MAX_SEQUENCES {
            return Err(SequenceError::InvalidOption {
                option: "max_sequences",
                value: GivenValue::Count(self.max_sequences),
                expected: "1 to 1000 (each sequence kept is built into tasks; the search's memo keeps up to this many costs a state)",
            });
        }
        if let Some((k, v)) = self
            .masses
            .iter()
            .find(|(_, v)| !(v.is_finite() && **v > 0.0))
        {
            return Err(SequenceError::InvalidOption {
                option: "masses",
                value: GivenValue::Mass {
                    component: k.clone(),
                    mass: *v,
                },
                expected: "finite numbers > 0",
            });
        }
        Ok(limit)
    }
}

/// Why sequence planning could not answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SequenceError {
    /// The workspace refused (unknown component, unusable mesh, bad tolerance…).
    #[error(transparent)]
    Workspace(#[from] WorkspaceError),
    /// An option has a value the planner cannot use.
    #[error("invalid sequence option `{option}` = {value}: expected {expected}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// The value given.
        value: GivenValue,
        /// What is accepted.
        expected: &'static str,
    },
    /// The document has no components.
    #[error("the document has no components to sequence")]
    Empty,
    /// Too many components for the planner's sets.
    #[error("the document has {0} components; sequence planning handles at most {MAX_COMPONENTS}")]
    TooManyComponents(usize),
    /// No order assembles every component (every try is in `rejected`).
    #[error("no assembly sequence found{}: {}", if *.timed_out { " within the time limit (raise `time_limit_ms`)" } else { "" }, rejected_list(.rejected))]
    NoSequence {
        /// Whether the time budget ran out first.
        timed_out: bool,
        /// The orders tried that failed and why (the first four).
        rejected: Vec<Rejected>,
    },
    /// The time budget ran out before the blocking graph was built.
    #[error("the time limit of {0} ms ran out before the blocking graph was complete (raise `time_limit_ms`)")]
    TimeLimit(f64),
}

/// Extra facts of one step besides its [`Task`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepInfo {
    /// The assembled components the part is related to (mates, or contacts in
    /// geometry mode), in assembly order — the task's base is the first.
    pub receivers: Vec<String>,
    /// Every free mating direction at this step (unit, assembly frame).
    pub mating_directions: Vec<Vec3>,
    /// Whether the insertion path was planned (no straight insertion exists).
    pub planned: bool,
    /// Whether the mating direction differs from the previous task's.
    pub direction_change: bool,
    /// Whether the insertion is difficult: a tight fit (the part cannot move
    /// `tight_clearance_mm` sideways among the placed parts) or a planned path.
    pub difficult: bool,
}

/// One assembly sequence: the tasks in order, with their costs.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// The base component (placed first, never moved).
    pub base: String,
    /// The tasks, in order (the base has none).
    pub tasks: Vec<Task>,
    /// Per task: receivers, free directions, planned or straight.
    pub steps: Vec<StepInfo>,
    /// Re-mountings of the base (tasks with `mount` set): the seed's criterion.
    pub mounts: usize,
    /// Changes of mating direction between consecutive tasks.
    pub direction_changes: usize,
    /// Total length of the insertion paths (mm).
    pub path_length_mm: f64,
    /// Difficult insertions (tight fits, planned paths; see [`StepInfo::difficult`]).
    pub difficult: usize,
}

impl Sequence {
    /// The component names in assembly order, base first.
    pub fn order(&self) -> Vec<String> {
        std::iter::once(self.base.clone())
            .chain(self.tasks.iter().map(|t| t.part.clone()))
            .collect()
    }
}

/// An order that was tried and failed, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Rejected {
    /// The components placed before it failed, base first.
    pub order: Vec<String>,
    /// Why no component could go next (per remaining component, or a pin or base rule).
    pub reason: RejectReason,
}

/// `after [a, b]: reason; after [a, c]: reason` (the error's text).
fn rejected_list(rejected: &[Rejected]) -> String {
    let list: Vec<String> = rejected
        .iter()
        .map(|r| format!("after [{}]: {}", r.order.join(", "), r.reason))
        .collect();
    list.join("; ")
}

/// Why an order of the search was given up.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum RejectReason {
    /// No remaining component can go next: why not, for each of the first four (or
    /// for the pinned one).
    DeadEnd {
        /// The component the pinned order puts next, when there is one.
        pinned: Option<String>,
        /// Why each component looked at cannot go next.
        parts: Vec<Stuck>,
    },
    /// Seed 003 section 2.2 step 2: the base is much smaller than a part it joins.
    InactiveBase {
        /// The base.
        base: String,
        /// Its size (mass, or mesh volume in mm³ scaled to a mass; see
        /// [`SequenceOptions::masses`]).
        size: f64,
        /// The size of the largest component related to it.
        largest_related: f64,
    },
    /// A straight insertion of a found order is not free (never expected: the
    /// blocking graph found it free).
    StraightCollides {
        /// The component.
        part: String,
        /// Its mating direction (unit, assembly frame).
        direction: Vec3,
    },
}

/// Why one component cannot be assembled next at a dead end of the search.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Stuck {
    /// Support on: it touches nothing placed within the contact gap.
    Floats {
        /// The component.
        part: String,
        /// The contact gap (mm).
        gap_mm: f64,
    },
    /// It is a member of a composite node and waits for the member before it.
    WaitsFor {
        /// The component.
        part: String,
        /// The member that goes before it.
        before: String,
    },
    /// Nothing it relates to is assembled, and it does not start its group.
    NothingToGoOnto {
        /// The component.
        part: String,
    },
    /// Every candidate separation direction is blocked by placed components.
    Blocked {
        /// The component.
        part: String,
        /// How many directions were tried.
        directions: usize,
        /// The placed components blocking it along at least one of them.
        by: Vec<String>,
        /// The least blocked direction (unit, assembly frame) and what blocks it
        /// there: what would have to go (or change) for the part to come out.
        least: ([f64; 3], Vec<String>),
        /// Whether every one of `least`'s blockers touches the part where assembled
        /// (a contact the tolerance may judge too finely: a tessellated fit).
        in_contact: bool,
        /// The penetration tolerance used (mm).
        tolerance: f64,
        /// The document's mesh deflection (mm), when it records one: the tolerance
        /// is never finer, so raising it to that frees nothing.
        deflection: Option<f64>,
        /// Those of `least`'s blockers that have a fit with the part deeper than
        /// `slide_fit_mm`, with the fit's depth (mm): they hold it to the overlap
        /// of the assembled pose and do not let it slide.
        deep_fits: Vec<(String, f64)>,
        /// The `slide_fit_mm` used (mm).
        slide_fit_mm: f64,
    },
}

impl std::fmt::Display for Stuck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stuck::Floats { part, gap_mm } => write!(
                f,
                "{part} would float: it touches nothing placed within {} mm (support on: raise `contact_gap_mm`, or set `support` false)",
                crate::math::format::number(*gap_mm, 3)
            ),
            Stuck::WaitsFor { part, before } => {
                write!(f, "{part} waits for {before} (composite node order)")
            }
            Stuck::NothingToGoOnto { part } => write!(f, "{part} has nothing assembled to go onto"),
            Stuck::Blocked {
                part,
                directions,
                by,
                least: (d, least_by),
                in_contact,
                tolerance,
                deflection,
                deep_fits,
                slide_fit_mm,
            } => {
                let n = |v: f64| crate::math::format::number(v, 3);
                // Every blocker is named (the one a user must move may block only
                // the directions the part would naturally take), then the least
                // blocked direction and what blocks it there.
                write!(
                    f,
                    "{part} is blocked along all {directions} directions by {}; the least blocked, ({}, {}, {}), by {}",
                    by.join(", "),
                    n(d[0]),
                    n(d[1]),
                    n(d[2]),
                    least_by.join(", ")
                )?;
                if !*in_contact {
                    return Ok(());
                }
                let touch = if least_by.len() == 1 { "es" } else { "" };
                if !deep_fits.is_empty() {
                    // Fits too deep to slide: the option that would let them.
                    let list: Vec<String> = deep_fits
                        .iter()
                        .map(|(q, depth)| format!("{q} {} mm", n(*depth)))
                        .collect();
                    return write!(
                        f,
                        " only, which touch{touch} it where assembled; fits deeper than `slide_fit_mm` ({} mm) may not slide: {}",
                        n(*slide_fit_mm),
                        list.join(", ")
                    );
                }
                match deflection {
                    // The tolerance is the meshes' own accuracy already: raising
                    // it to that would change nothing.
                    Some(dfl) if *tolerance >= *dfl => write!(
                        f,
                        " only, which touch{touch} it where assembled (the tolerance {} mm is already the meshes' deflection: blocked as modelled)",
                        n(*tolerance)
                    ),
                    _ => write!(
                        f,
                        " only, which touch{touch} it where assembled (a fit whose meshes cross by more than the tolerance {} mm: raise `tolerance` to the meshes' deflection)",
                        n(*tolerance)
                    ),
                }
            }
        }
    }
}

impl std::fmt::Display for RejectReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RejectReason::DeadEnd { pinned, parts } => {
                let list: Vec<String> = parts.iter().map(|p| p.to_string()).collect();
                match pinned {
                    Some(q) => write!(f, "pinned order: {q} cannot go next: {}", list.join("; ")),
                    None => write!(f, "{}", list.join("; ")),
                }
            }
            RejectReason::InactiveBase {
                base,
                size,
                largest_related,
            } => write!(
                f,
                "inactive base: {base} is much smaller ({}) than a part it joins ({}; pin `base`, or lower `small_base_ratio`)",
                crate::math::format::number(*size, 3),
                crate::math::format::number(*largest_related, 3)
            ),
            RejectReason::StraightCollides { part, direction } => write!(
                f,
                "the straight insertion of {part} along {:?} collides",
                direction.as_slice()
            ),
        }
    }
}

/// Two components of the product that interfere in the assembled pose: a press fit,
/// an insertion that ends in contact, or the overlap a CAD model has (a part
/// modelled through another). Taken as a fit, never a reason to refuse the product:
/// the removal checks between `a` and `b` (sweeps, probes, planned paths) allow
/// exactly the overlap of the assembled pose — the moving part may overlap the
/// other only where it did when assembled (within `tolerance`; stepwise, `step_mm`
/// apart) — and every other pair keeps [`SequenceOptions::tolerance`]. A fit no
/// deeper than [`SequenceOptions::slide_fit_mm`] may also slide straight from the
/// assembled pose (a press fit along its bore or guides; see the option).
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// One component.
    pub a: String,
    /// The other.
    pub b: String,
    /// Depth of the interference in the assembled pose (mm): the deepest crossing of
    /// the two surfaces, or how deep a point of one lies inside the other (see
    /// [`crate::collision::contact`]).
    pub depth: f64,
    /// Whether one solid lies wholly inside the other (no surfaces cross).
    pub contained: bool,
}

/// Two components the support rule takes as holding each other though their
/// surfaces are farther apart than `contact_gap_mm` (a clearance joint, a part
/// held by its mates): without them some part of the product could never be placed
/// touching anything. Each is the closest link between two groups of parts that do
/// not touch each other within the gap (the fewest, shortest links that connect the
/// product), at most half the thinner part's thinnest box extent apart.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportGap {
    /// One component.
    pub a: String,
    /// The other.
    pub b: String,
    /// Their surface distance (mm), or `None` when they are related by a mate
    /// (mates mode: a mated pair holds each other whatever the gap).
    pub gap_mm: Option<f64>,
}

/// The result of [`plan_sequence`](super::plan_sequence): ranked sequences and what
/// was learnt on the way.
#[derive(Debug, Clone)]
pub struct SequencePlan {
    /// The mode used.
    pub mode: Mode,
    /// The sequences found, best first: fewest mounts, then fewest direction changes,
    /// then fewest difficult insertions, then shortest total insertion path.
    pub sequences: Vec<Sequence>,
    /// Why the first sequence ranked first, for people (its costs against the
    /// runner-up's, or that it was the only one found).
    pub ranking: String,
    /// The components sequenced (the product), in document order; robot links and
    /// excluded components are not among them.
    pub product: Vec<String>,
    /// Orders that failed, with the reason (at most 50).
    pub rejected: Vec<Rejected>,
    /// Precedence: `(a, b)` means `a` is assembled before `b` in every complete
    /// sequence the search met (transitively reduced); branch and bound skips orders
    /// that cannot rank among the kept ones, so this is the precedence of the best
    /// sequences, not of every feasible one.
    pub precedence: Vec<(String, String)>,
    /// Whether the search ended by itself (not cut by the time limit or by its
    /// memory bound of its memo, `MAX_SEARCH_MEMO_BYTES`): the sequences returned are then the
    /// best by the ranking.
    pub complete: bool,
    /// The relation graph used (mates mode), or the contact graph (geometry mode,
    /// relations without mates).
    pub graph: RelationGraph,
    /// The interferences of the assembled pose, taken as fits (pairs in document
    /// order).
    pub fits: Vec<Fit>,
    /// The links the support rule added across gaps wider than `contact_gap_mm`.
    pub support_gaps: Vec<SupportGap>,
    /// The product's groups of parts that touch nothing of one another in the
    /// finished product (within `contact_gap_mm`, across the support gaps), in
    /// document order, when there is more than one: nothing modelled holds them
    /// together (a frame or fixture the file leaves out, parts placed apart), so the
    /// first part placed of each group needs no support. Empty when the whole
    /// product holds together.
    pub separate_groups: Vec<Vec<String>>,
    /// The penetration tolerance the checks used (mm): `tolerance`, raised to the
    /// document's [`mesh_deflection`](crate::document::Document::mesh_deflection)
    /// (an imported mesh is known no better).
    pub tolerance: f64,
    /// Wall-clock time of the call (ms).
    pub time_ms: f64,
    /// Blocking sweeps run.
    pub sweeps: usize,
}

impl SequencePlan {
    /// The best sequence.
    pub fn best(&self) -> &Sequence {
        &self.sequences[0]
    }
}
