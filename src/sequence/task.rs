//! The task: one step of an assembly sequence (seed 003, section 2.2).
//!
//! A task is `T = (base part, assembly part, operation)` with everything a robot needs
//! to carry it out: the mating direction, the safe length, the grasp, the obstacle box
//! and the frames. Units: millimetres and radians; every direction, point and box is in
//! the **assembly frame** (the document's world frame) unless its doc says otherwise.
//!
//! This type is the contract between sequence planning (which produces tasks) and
//! skills (which turn each task into skill primitives for a manipulator).

use crate::math::{Aabb, Transform, Vec3};
use crate::planning::PlannedPath;

/// What the robot does to join the assembly part to what is already assembled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Operation {
    /// Push the part along its mating direction (concentric + coplanar mates, a peg in a
    /// hole, a gear onto an axis).
    Insertion,
    /// Insert, then turn about the mating direction (a part marked threaded, or a mate
    /// whose operation is `screw`).
    Screw,
    /// Bring a face onto a face (planar mates only).
    Align,
}

impl Operation {
    /// The name used in documents, templates, scripts and files (`insertion`, `screw`,
    /// `align`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Insertion => "insertion",
            Self::Screw => "screw",
            Self::Align => "align",
        }
    }

    /// Parses [`Operation::name`].
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "insertion" => Self::Insertion,
            "screw" => Self::Screw,
            "align" => Self::Align,
            _ => return None,
        })
    }
}

/// Where the end effector holds the assembly part (seed 003, section 2.1 step 5).
#[derive(Debug, Clone, PartialEq)]
pub struct Grasp {
    /// The two parallel faces gripped, as reference names of the part (or names made
    /// up for faces found on the mesh, e.g. `mesh_face_3`).
    pub faces: [String; 2],
    /// Normal of the grasp plane (the direction the fingers close along), unit, part
    /// frame.
    pub normal: Vec3,
    /// Opening between the two faces (mm).
    pub width: f64,
    /// The gripping point: the tool centre point at the grasp, part frame (mm).
    pub point: Vec3,
    /// How far the end effector slid along the grasp plane in the mating direction
    /// before it fully gripped or collided (mm).
    pub depth: f64,
    /// The tool pose relative to the part: tool frame → part frame.
    pub tool_in_part: Transform,
}

/// One step of an assembly sequence.
#[derive(Debug, Clone)]
pub struct Task {
    /// Position in the sequence, 0 first.
    pub index: usize,
    /// The component already in place that receives the part (component name).
    pub base: String,
    /// The component moved in this step (component name).
    pub part: String,
    /// What is done.
    pub operation: Operation,
    /// The direction the part moves while it is joined (unit, assembly frame). The
    /// part leaves along its negation.
    pub mating_direction: Vec3,
    /// How far back along the mating direction the part is free of every other part
    /// in every remaining degree of freedom (mm): the approach starts there.
    pub safe_length: f64,
    /// Where the part is held, when a grasp was found.
    pub grasp: Option<Grasp>,
    /// The box around every part already in the workspace at this step (mm, assembly
    /// frame): the approach goes around it.
    pub obstacle_box: Aabb,
    /// The part's pose when assembled: part frame → assembly frame.
    pub assembled_pose: Transform,
    /// The base part's pose: base-part frame → assembly frame.
    pub base_pose: Transform,
    /// The sequence frame of this step → assembly frame: the base as mounted for this
    /// step (after a re-mounting the mating direction points down the sequence
    /// frame's −Z, i.e. the part is inserted from above).
    pub sequence_frame: Transform,
    /// Whether the base must be unloaded and re-placed before this step.
    pub mount: bool,
    /// The checked insertion path (part poses, assembly frame), start at the safe
    /// length, end at `assembled_pose`: collision-free against exactly the parts
    /// assembled before this step (the fits below allowed).
    pub path: PlannedPath,
    /// The components assembled before it that the part has a fit with (see
    /// [`Fit`](super::Fit)): its path may overlap each where the part overlaps it
    /// assembled, and interferes with no other deeper than the path's tolerance.
    pub fits: Vec<String>,
    /// Those of `fits` no deeper than `slide_fit_mm` (press fits): along a straight
    /// stretch of the path through the assembled pose the part may also slide
    /// against each, overlapping along every line of the motion only the material
    /// it overlaps assembled, by no more than assembled.
    pub slides: Vec<String>,
}
