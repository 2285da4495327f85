//! Interference detection between posed parts (see `docs/interference.md`).
//!
//! Three static methods, all on meshes in the part frame (mm) posed by a
//! [`Transform`] (part frame → world):
//!
//! - [`Method::Exact`]: solid semantics. Parts interfere when their surfaces cross
//!   deeper than a penetration tolerance (default [`DEFAULT_TOLERANCE`]) or one solid
//!   lies inside the other; surfaces that only meet (a plate on a table, a screw in a
//!   hole of its diameter, coplanar faces) are [`Contact::Touching`].
//! - [`Method::Aabb`]: the whole-part world boxes (seed 000, first stage).
//! - [`Method::Cells`]: seed 000's "finite subdivision": the whole-part boxes, then
//!   the boxes of the cut cells ([`CutCells`]).
//!
//! Dynamic interference along a [`Motion`] is in [`sweep`]; along one planner edge
//! (lerp + slerp) in [`edge_interferes`].
//!
//! # Motion-check vocabulary
//! One type, [`SweepMethod`], for every check of a moving part (sweeps here, planner
//! edges in `planning`; mm and radians):
//! - **stepwise**: static checks at poses at most `step_mm` and `step_rad` apart
//!   ([`SweepMethod::Stepwise`]); can jump over features thinner than a step.
//! - **continuous**: conservative advancement ([`SweepMethod::Continuous`],
//!   [`edge_interferes`]): every advance is shorter than the distance to the nearest
//!   obstacle, so nothing is jumped over. Below the **contact gap**
//!   ([`contact_gap`]) the part counts as in contact and advances by at most the
//!   **contact step** ([`contact_step`]).
//!
//! Every query validates its input and returns [`CollisionError`]; none panics.
//!
//! # Examples
//!
//! A 10 mm cube set on another touches it; lowered 1 mm further, the two interfere;
//! lifted 5 mm, their surfaces are 5 mm apart:
//!
//! ```
//! use fitup::collision::{contact, surface_distance, Collider, DEFAULT_TOLERANCE};
//! use fitup::math::{Point3, Transform, Vec3};
//! use fitup::mesh::Mesh;
//! use std::sync::Arc;
//!
//! let cube = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 10.0, 10.0));
//! let cube = Collider::new(Arc::new(cube))?;
//! let below = Transform::IDENTITY;
//! let at = |z: f64| Transform::from_translation(Vec3::new(0.0, 0.0, z));
//!
//! assert!(contact(&cube, &below, &cube, &at(10.0), DEFAULT_TOLERANCE)?.is_touching());
//! let pushed = contact(&cube, &below, &cube, &at(9.0), DEFAULT_TOLERANCE)?;
//! assert!(pushed.is_interfering());
//! assert!((surface_distance(&cube, &below, &cube, &at(15.0), 0.0)? - 5.0).abs() < 1e-9);
//! # Ok::<(), fitup::collision::CollisionError>(())
//! ```

mod cells;
mod containment;
mod distance;
mod edge;
mod exact;
mod method;
mod node;
mod relative;
mod shape;
mod sweep;
mod tree;
mod triangle;
mod volume;

pub use cells::{
    cells_contact, method_disagreement, Cell, CutCells, CutSpec, Disagreement, MAX_CELLS,
};
pub use distance::{clearance, distance_lower_bound, surface_distance};
pub use edge::{edge_interferes, edge_interferes_until, EdgeOptions};
pub use exact::{contact, contact_until, interferes, interferes_until};
pub use method::{contact_gap, contact_step, SweepMethod, MIN_CONTACT_GAP_MM};
pub use shape::{Collider, ColliderCache, ColliderWarning, MAX_COORDINATE};
pub use sweep::{sweep, Motion, Obstacle, SweepHit, SweepOptions, DEFAULT_SWEEP_TIME_LIMIT_MS};
pub use volume::{
    intersection_volume, separation, Separation, SeparationOptions, VolumeError,
    DEFAULT_OVERLAP_TIME_LIMIT_MS,
};

pub use crate::math::Aabb;
use crate::math::Transform;
use rayon::prelude::*;

/// Default penetration tolerance, mm: crossings up to this depth count as touching.
pub const DEFAULT_TOLERANCE: f64 = 0.01;

/// Why a collision query could not be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CollisionError {
    /// The mesh cannot be used (no triangle of non-zero area, NaN or huge
    /// coordinates, bad indices).
    #[error("unusable mesh: {0}")]
    BadMesh(MeshFault),
    /// A pose has NaN or infinite entries.
    #[error("bad pose: {0}")]
    BadPose(PoseFault),
    /// The penetration tolerance is negative or not finite.
    #[error("the penetration tolerance must be a finite number >= 0 mm, got {0}")]
    BadTolerance(f64),
    /// The cell size or cut planes are unusable.
    #[error("bad cut cells: {0}")]
    BadCells(CellsFault),
    /// The cut would make more cells than [`MAX_CELLS`].
    #[error("the cut would make {count} cells ({nx} x {ny} x {nz}), more than the limit of {limit}; use a larger cell size")]
    TooManyCells {
        /// Cells the grid would have.
        count: u128,
        /// Cells along X.
        nx: u64,
        /// Cells along Y.
        ny: u64,
        /// Cells along Z.
        nz: u64,
        /// The limit, [`MAX_CELLS`].
        limit: usize,
    },
    /// The cells method was asked for a part without cut cells where they are needed.
    #[error("method \"cells\" needs the cut cells of both parts")]
    MissingCells,
    /// The motion or sweep options are unusable (NaN, zero axis, empty, step <= 0).
    #[error("bad motion: {0}")]
    BadMotion(MotionFault),
    /// A sweep ran out of its time budget (ms) before it could answer.
    #[error("the sweep ran out of its time limit of {0} ms before reaching the end of the motion; give it a larger `time_limit_ms` or a coarser method")]
    TimeLimit(f64),
    /// An unknown method name.
    #[error("unknown interference method \"{0}\": expected \"exact\", \"aabb\" or \"cells\"")]
    UnknownMethod(String),
    /// A stepwise sweep would take more steps than the shared cap
    /// ([`MAX_SAMPLES`](crate::math::MAX_SAMPLES)).
    #[error(transparent)]
    Limit(#[from] crate::math::LimitError),
}

/// What makes a mesh unusable for collision queries.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshFault {
    /// A vertex is not finite or lies beyond [`MAX_COORDINATE`] mm.
    #[error("vertex {index} ({}, {}, {}) is not finite or beyond {:e} mm", .position[0], .position[1], .position[2], MAX_COORDINATE)]
    VertexOutOfRange {
        /// The vertex's index.
        index: usize,
        /// Its coordinates (mm, part frame).
        position: [f64; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to a vertex past the {vertices} vertices")]
    BadIndex {
        /// The triangle's index.
        triangle: usize,
        /// How many vertices the mesh has.
        vertices: usize,
    },
    /// Every triangle is degenerate.
    #[error("the mesh has no triangle of non-zero area")]
    NoArea,
}

/// Which pose of a query has NaN or infinite entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PoseFault {
    /// The pose of a queried part.
    #[error("the pose has a NaN or infinite entry")]
    Part,
    /// The pose of obstacle `n` (in the order given).
    #[error("obstacle {0} has a NaN or infinite pose")]
    Obstacle(usize),
}

/// What makes a cut-cells request unusable.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CellsFault {
    /// The cell size (mm) is not a finite number > 0.
    #[error("the cell size must be a finite number > 0 mm, got {0}")]
    CellSize(f64),
    /// A cut plane's position (mm) is not finite.
    #[error("cut plane position {0} is not finite")]
    PlanePosition(f64),
}

/// What makes a motion, a sweep or an edge check unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MotionFault {
    /// Part of the motion (named) has NaN or infinite values.
    #[error("{0} has NaN or infinite values")]
    NonFinite(&'static str),
    /// A rotation about an axis of zero length.
    #[error("the rotation axis has zero length")]
    ZeroAxis,
    /// A motion through no poses.
    #[error("the pose sequence is empty")]
    NoPoses,
    /// A step, time limit or cap of the query is out of range.
    #[error("the {option} must be {expected}, got {value}")]
    Option {
        /// The option, in words (e.g. `contact step`).
        option: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// A stepwise sweep would check more than the cap.
    #[error("{steps} steps would take more than {limit} checks")]
    TooManySteps {
        /// Steps of the piece.
        steps: usize,
        /// The cap on checks.
        limit: usize,
    },
    /// A continuous sweep used up its query cap.
    #[error("the continuous sweep took more than {0} queries")]
    TooManyQueries(usize),
}

impl MotionFault {
    /// An option out of range, as a [`CollisionError`].
    pub(crate) fn option(
        option: &'static str,
        value: f64,
        expected: &'static str,
    ) -> CollisionError {
        CollisionError::BadMotion(MotionFault::Option {
            option,
            value,
            expected,
        })
    }
}

/// Why a verdict written in words ([`Contact::from_text`]) is not one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ContactTextError {
    /// The state is not `separate`, `touching` or `interfering`.
    #[error("unknown contact state `{0}`: expected \"separate\", \"touching\" or \"interfering\"")]
    UnknownState(String),
    /// The kind of an interfering pair is not one of the words.
    #[error("unknown interference kind `{kind}` for `{a}` and `{b}`: expected \"surfaces cross\", \"{a} inside {b}\", \"{b} inside {a}\" or \"boxes overlap\"")]
    UnknownKind {
        /// The kind given.
        kind: String,
        /// The first part.
        a: String,
        /// The second part.
        b: String,
    },
    /// The depth of an interfering pair is negative or not finite (mm).
    #[error("the penetration depth must be a finite number ≥ 0 mm, got {0}")]
    BadDepth(f64),
}

/// One of the two parts of a pair query.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PairMember {
    /// The first part given (`a`).
    First,
    /// The second part given (`b`).
    Second,
}

/// How two parts interfere.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterferenceKind {
    /// The surfaces cross deeper than the tolerance.
    SurfacesCross,
    /// No surfaces cross, but `inner`'s solid lies inside the other's.
    Contained {
        /// The part inside.
        inner: PairMember,
    },
    /// No surfaces cross, but faces of the two closed solids overlap in one plane
    /// facing the same way, so the solids share the material behind them (a wall
    /// pushed into an equal wall, solids cut in stacked slices); the depth is the
    /// overlap's least width, mm.
    FacesOverlap,
    /// Approximate methods ([`Method::Aabb`], [`Method::Cells`]): boxes overlap
    /// deeper than the tolerance on all three axes.
    BoxesOverlap,
}

/// The verdict for a pair of posed parts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Contact {
    /// Apart (farther than the contact resolution, about 1e-9 × part size).
    Separate,
    /// The surfaces meet but cross no deeper than the tolerance.
    Touching,
    /// They interfere.
    Interfering {
        /// Penetration depth estimate, mm (defined in `docs/interference.md`).
        depth: f64,
        /// Surfaces crossing or containment.
        kind: InterferenceKind,
    },
}

impl Contact {
    /// Whether the verdict is [`Contact::Interfering`].
    pub fn is_interfering(&self) -> bool {
        matches!(self, Contact::Interfering { .. })
    }

    /// Whether the verdict is [`Contact::Touching`].
    pub fn is_touching(&self) -> bool {
        matches!(self, Contact::Touching)
    }

    /// The penetration depth (mm), 0 unless interfering.
    pub fn depth(&self) -> f64 {
        match self {
            Contact::Interfering { depth, .. } => *depth,
            _ => 0.0,
        }
    }

    /// `separate`, `touching` or `interfering`: the word scripts, reports and the
    /// results database use for the verdict.
    pub fn state_name(&self) -> &'static str {
        match self {
            Contact::Separate => "separate",
            Contact::Touching => "touching",
            Contact::Interfering { .. } => "interfering",
        }
    }

    /// How the pair `a`, `b` interferes, in words: `surfaces cross`, `A inside B`,
    /// `faces overlap`, `boxes overlap`; empty unless interfering.
    pub fn kind_text(&self, a: &str, b: &str) -> String {
        match self {
            Contact::Interfering { kind, .. } => match kind {
                InterferenceKind::SurfacesCross => "surfaces cross".into(),
                InterferenceKind::Contained {
                    inner: PairMember::First,
                } => format!("{a} inside {b}"),
                InterferenceKind::Contained {
                    inner: PairMember::Second,
                } => format!("{b} inside {a}"),
                InterferenceKind::BoxesOverlap => "boxes overlap".into(),
                InterferenceKind::FacesOverlap => "faces overlap".into(),
            },
            _ => String::new(),
        }
    }

    /// The verdict written as [`state_name`](Self::state_name), depth (mm) and
    /// [`kind_text`](Self::kind_text) for the pair `a`, `b`: the inverse of those
    /// two, for results read back from a script or a database.
    ///
    /// # Errors
    /// [`ContactTextError`] naming the state, kind or depth that is not one of the
    /// words (or not a finite depth ≥ 0).
    pub fn from_text(
        state: &str,
        depth_mm: f64,
        kind: &str,
        a: &str,
        b: &str,
    ) -> Result<Contact, ContactTextError> {
        match state {
            "separate" => Ok(Contact::Separate),
            "touching" => Ok(Contact::Touching),
            "interfering" => {
                if !(depth_mm.is_finite() && depth_mm >= 0.0) {
                    return Err(ContactTextError::BadDepth(depth_mm));
                }
                let kind = match kind {
                    "surfaces cross" => InterferenceKind::SurfacesCross,
                    "boxes overlap" => InterferenceKind::BoxesOverlap,
                    "faces overlap" => InterferenceKind::FacesOverlap,
                    k if k == format!("{a} inside {b}") => InterferenceKind::Contained {
                        inner: PairMember::First,
                    },
                    k if k == format!("{b} inside {a}") => InterferenceKind::Contained {
                        inner: PairMember::Second,
                    },
                    _ => {
                        return Err(ContactTextError::UnknownKind {
                            kind: kind.to_string(),
                            a: a.to_string(),
                            b: b.to_string(),
                        })
                    }
                };
                Ok(Contact::Interfering {
                    depth: depth_mm,
                    kind,
                })
            }
            _ => Err(ContactTextError::UnknownState(state.to_string())),
        }
    }

    /// The same verdict seen from the other part (swaps `Contained::inner`).
    pub fn swapped(self) -> Contact {
        match self {
            Contact::Interfering {
                depth,
                kind: InterferenceKind::Contained { inner },
            } => Contact::Interfering {
                depth,
                kind: InterferenceKind::Contained {
                    inner: match inner {
                        PairMember::First => PairMember::Second,
                        PairMember::Second => PairMember::First,
                    },
                },
            },
            c => c,
        }
    }
}

/// A static interference method.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Mesh-exact, solid semantics.
    #[default]
    Exact,
    /// Whole-part world boxes only.
    Aabb,
    /// Whole-part boxes, then cut-cell boxes (seed 000).
    Cells,
}

impl std::str::FromStr for Method {
    type Err = CollisionError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "exact" => Ok(Method::Exact),
            "aabb" => Ok(Method::Aabb),
            "cells" => Ok(Method::Cells),
            other => Err(CollisionError::UnknownMethod(other.to_string())),
        }
    }
}

/// A part placed in the world: its collider, its cut cells if it has the feature,
/// and its pose (part frame → world).
#[derive(Debug, Clone, Copy)]
pub struct PosedPart<'a> {
    /// The collision shape of the part's mesh.
    pub collider: &'a Collider,
    /// The cut-cells feature, when the part has one ([`Method::Cells`] uses the
    /// whole-part box for parts without).
    pub cells: Option<&'a CutCells>,
    /// Part frame → world.
    pub pose: Transform,
}

/// Interference of two posed parts by `method`, tolerance in mm.
pub fn check(
    method: Method,
    a: &PosedPart,
    b: &PosedPart,
    tolerance: f64,
) -> Result<Contact, CollisionError> {
    match method {
        Method::Exact => contact(a.collider, &a.pose, b.collider, &b.pose, tolerance),
        Method::Aabb => cells::boxes_contact(
            &[a.collider.bounds()],
            &a.pose,
            &[b.collider.bounds()],
            &b.pose,
            tolerance,
        ),
        Method::Cells => {
            let ca = a
                .cells
                .map(|c| c.boxes())
                .unwrap_or_else(|| vec![a.collider.bounds()]);
            let cb = b
                .cells
                .map(|c| c.boxes())
                .unwrap_or_else(|| vec![b.collider.bounds()]);
            let whole = cells::boxes_contact(
                &[a.collider.bounds()],
                &a.pose,
                &[b.collider.bounds()],
                &b.pose,
                tolerance,
            )?;
            if whole == Contact::Separate {
                return Ok(whole);
            }
            cells::boxes_contact(&ca, &a.pose, &cb, &b.pose, tolerance)
        }
    }
}

/// A pair of parts (indices into the slice given) that touch or interfere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairContact {
    /// Index of the first part (the smaller index).
    pub a: usize,
    /// Index of the second part.
    pub b: usize,
    /// The verdict (never [`Contact::Separate`]).
    pub contact: Contact,
}

/// Every pair of `parts` that touches or interferes by `method`, sorted by
/// `(a, b)`. Pairs whose world boxes are apart are skipped before any mesh work;
/// the rest run in parallel.
pub fn check_all(
    parts: &[PosedPart],
    method: Method,
    tolerance: f64,
) -> Result<Vec<PairContact>, CollisionError> {
    let candidates = candidate_pairs(parts)?;
    let found: Vec<Option<PairContact>> = candidates
        .par_iter()
        .map(|&(i, j)| {
            let c = check(method, &parts[i], &parts[j], tolerance)?;
            Ok((c != Contact::Separate).then_some(PairContact {
                a: i,
                b: j,
                contact: c,
            }))
        })
        .collect::<Result<_, CollisionError>>()?;
    Ok(found.into_iter().flatten().collect())
}

/// The pairs `(i, j)`, `i < j`, of `parts` whose world boxes touch or overlap: the
/// only pairs any method can find in contact (the broad phase of [`check_all`]).
///
/// # Errors
/// A pose with a NaN or infinite entry.
pub fn candidate_pairs(parts: &[PosedPart]) -> Result<Vec<(usize, usize)>, CollisionError> {
    let boxes: Vec<Aabb> = parts
        .iter()
        .map(|p| {
            if p.pose.is_finite() {
                Ok(p.collider.world_bounds(&p.pose))
            } else {
                Err(CollisionError::BadPose(PoseFault::Part))
            }
        })
        .collect::<Result<_, _>>()?;
    let mut candidates = Vec::new();
    for i in 0..parts.len() {
        for j in i + 1..parts.len() {
            let o = boxes[i].overlap(&boxes[j]);
            let slack = 1e-9 * (1.0 + boxes[i].hi.coords.amax().max(boxes[j].hi.coords.amax()));
            if o.min() >= -slack {
                candidates.push((i, j));
            }
        }
    }
    Ok(candidates)
}

#[cfg(test)]
mod tests;

thread_local! {
    /// Node pairs visited by this thread's pair traversals ([`effort`]).
    static EFFORT: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The node pairs of bounding-volume trees visited so far on this thread by pair
/// traversals (pose checks, continuous edge checks, distance queries): a measure
/// of collision work that is the same on every run and roughly proportional to
/// its CPU time, which the number of checks is not (a check near contact visits
/// many times the pairs of one deep in collision). The default planner's two
/// racing searches compare their work by it (docs/planning.md). Wraps around
/// after 2⁶⁴ pairs; take differences.
pub fn effort() -> u64 {
    EFFORT.with(std::cell::Cell::get)
}

/// Adds the node pairs a traversal visited to [`effort`] when dropped (on every
/// return path of the traversal, early ones included).
pub(crate) struct EffortTally(pub(crate) u64);

impl Drop for EffortTally {
    fn drop(&mut self) {
        let n = self.0;
        EFFORT.with(|e| e.set(e.get().wrapping_add(n)));
    }
}
