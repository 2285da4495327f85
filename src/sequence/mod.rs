//! Assembly sequences: which component goes on which, in what order and direction
//! (seed 003's task layer). Units: millimetres and radians; every direction, point and
//! box is in the assembly frame (the document's world frame) unless a doc says
//! otherwise.
//!
//! The seed's method, in the order it runs (see `docs/assembly.md`):
//! 1. the **relation graph** from the document's mates ([`RelationGraph`]);
//! 2. the **remaining degrees of freedom** of each mate as a 6-vector and their
//!    intersections ([`Freedom`]);
//! 3. **loops** broken into **composite nodes** (the pair with the fewest free degrees
//!    around the loop is united; the composite implies an order);
//! 4. **mating directions**: each part separated along its free directions
//!    (straight sweeps against each other component: a directional blocking graph);
//! 5. **grasp planes**: parallel face pairs across every mating direction, with the
//!    end effector's fingers slid along them ([`Grasp`]);
//! 6. the **safe length** along the mating direction;
//! 7. the **obstacle box** of the parts already assembled;
//! 8. the **sequence search**: base by size (or `masses`), inactive bases skipped,
//!    mounts counted, fewest mounts first, pins honoured, several sequences ranked,
//!    rejected orders with their reason;
//! 9. **tasks** `T = (base part, assembly part, operation)` with their checked paths.
//!
//! [`Mode::Geometry`] does the same from the meshes alone (and is what a document
//! without mates gets): contacts within a gap instead of mates, directions ±X/±Y/±Z
//! and the contact normals, then for parts those do not free directions from their
//! geometry and a seeded sphere, and a planner fallback (seed 002's disassembly)
//! when no straight insertion exists.
//!
//! Only the product is sequenced (robot links and `exclude`d fixtures are left out);
//! every added part touches a placed one (`support`), the base is the largest part a
//! sequence starts from, difficult insertions rank later, and one deadline bounds
//! the whole call (see `docs/assembly.md`).
//!
//! # Examples
//! ```
//! use fitup::document::Document;
//! use fitup::sequence::{plan_sequence, SequenceOptions};
//! use fitup::workspace::SceneCache;
//!
//! let doc = Document::open(std::path::Path::new("models/wheel.yaml")).unwrap();
//! let plan = plan_sequence(&doc, &mut SceneCache::new(), &SequenceOptions::default()).unwrap();
//! // Seed 003's answer: the gear onto the axis, then the cup onto axis and gear.
//! assert_eq!(plan.best().order(), ["axis", "gear", "cup"]);
//! assert_eq!(plan.best().mounts, 0);
//! ```

mod blocking;
mod context;
mod fit;
mod graph;
mod grasp;
mod options;
mod paths;
mod plan;
mod report;
mod revalidate;
mod setup;
mod task;

pub use graph::{Freedom, LoopBreak, Node, Relation, RelationGraph};
pub use grasp::{face_pairs, FacePair};
pub use options::{
    Fit, Gripper, Mode, RejectReason, Rejected, Sequence, SequenceError, SequenceOptions,
    SequencePlan, StepInfo, Stuck, SupportGap, DEFAULT_SEQUENCE_TIME_LIMIT_MS, MAX_COMPONENTS,
    MAX_SEQUENCES,
};
pub use plan::MAX_SEARCH_MEMO_BYTES;
pub use revalidate::{revalidate, BrokenStep};
pub use task::{Grasp, Operation, Task};

use crate::document::Document;
use crate::math::Vec3;
use crate::workspace::{GivenValue, SceneCache, WorkspaceError};

/// Plans the assembly sequences of `doc` (seed 003 section 2.2): every returned
/// task's insertion path is collision-free against exactly the components assembled
/// before it. The whole call honours `options.time_limit_ms`.
///
/// Components that interfere in the assembled pose are fits (reported in
/// [`SequencePlan::fits`]), never a reason to refuse: the removal checks between such
/// a pair allow the fit's depth, every other pair the tolerance.
///
/// # Errors
/// Bad options, unknown pinned names, unusable meshes, no sequence (with the
/// reasons), the time limit spent before the blocking graph was built.
pub fn plan_sequence(
    doc: &Document,
    cache: &mut SceneCache,
    options: &SequenceOptions,
) -> Result<SequencePlan, SequenceError> {
    plan::plan(doc, cache, options)
}

/// The relation graph of `doc` from its mates, loops broken into composite nodes
/// (composite bases chosen by the components' `mass`, else mesh volume).
pub fn relation_graph(doc: &Document) -> RelationGraph {
    let sizes = context::component_sizes(doc, &SequenceOptions::default());
    RelationGraph::build(doc, &|i| sizes[i])
}

/// The mating directions of component `name` (unit, assembly frame: the direction
/// it moves while it is joined): its candidate separations that are free of every
/// component related to it (mates, or contacts in geometry mode), negated.
///
/// # Errors
/// As [`plan_sequence`] before the search; an unknown component.
pub fn mating_directions(
    doc: &Document,
    cache: &mut SceneCache,
    name: &str,
    options: &SequenceOptions,
) -> Result<Vec<Vec3>, SequenceError> {
    let p = doc.component_index(name).map_err(WorkspaceError::from)?;
    let ctx = context::Ctx::new(doc, cache, options)?;
    Ok(plan::mating_directions_of(&ctx, p))
}

/// The grasp face pairs of component `name` valid for all its mating directions
/// (the seed's `G1 ∩ G2 ∩ …`), part frame.
///
/// # Errors
/// As [`mating_directions`].
pub fn grasp_planes(
    doc: &Document,
    cache: &mut SceneCache,
    name: &str,
    options: &SequenceOptions,
) -> Result<Vec<FacePair>, SequenceError> {
    let p = doc.component_index(name).map_err(WorkspaceError::from)?;
    let ctx = context::Ctx::new(doc, cache, options)?;
    let dirs = plan::mating_directions_of(&ctx, p);
    Ok(grasp::grasp_planes(&ctx, p, &dirs))
}

/// The safe length (mm) of component `name` moved out along `direction` (any
/// non-zero length, assembly frame) from its assembled pose among its related components: how
/// far it must go before a probe along every other candidate direction is free.
///
/// # Errors
/// As [`mating_directions`]; a zero or non-finite direction.
pub fn safe_length(
    doc: &Document,
    cache: &mut SceneCache,
    name: &str,
    direction: &Vec3,
    options: &SequenceOptions,
) -> Result<f64, SequenceError> {
    let p = doc.component_index(name).map_err(WorkspaceError::from)?;
    if !(direction.iter().all(|v| v.is_finite()) && direction.norm() > 1e-12) {
        return Err(SequenceError::InvalidOption {
            option: "direction",
            value: GivenValue::Numbers(direction.as_slice().to_vec()),
            expected: "a finite non-zero vector",
        });
    }
    let ctx = context::Ctx::new(doc, cache, options)?;
    Ok(ctx.safe_length(p, &direction.normalize(), plan::related_of(&ctx, p)))
}
