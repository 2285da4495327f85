//! Robot kinematics: kinematic trees of links and joints (seed 001), robots built
//! from D-H tables (seed 000, table 2), a catalog of industrial arms, forward
//! kinematics, closed-form inverse kinematics for ortho-parallel arms with a
//! spherical wrist and for UR-type arms with an offset wrist (all branches), numeric inverse kinematics for any chain,
//! joint and Cartesian motions sampled into trajectories, motion programs and
//! drilling of hole tables.
//!
//! Units: millimetres and radians everywhere (joint values of prismatic joints in mm).
//! Degrees appear only in program files, CSV output and the scripting layer.
//! Transforms are [`Transform`](crate::math::Transform)s; see `docs/kinematics.md` for
//! the frame conventions and the derivation of the analytic solver.

mod catalog;
mod closed_form;
mod dh;
mod drilling;
mod error;
mod ik;
mod ik_numeric;
mod joint;
mod motion;
mod opw;
mod opw_params;
mod precision;
mod program;
mod robot;
mod trajectory;
mod tree;
mod ur;
mod urdf;

pub use catalog::{catalog_names, robot_by_name, Catalog};
pub use closed_form::{Branch, Branches, ClosedFormIk, ModelError};
pub use dh::{DhConvention, DhRow};
pub use drilling::{
    drill_program, hole_tool_pose, parse_holes, read_holes, read_holes_in, DrillError,
    DrillOptions, DrillReport, Hole, HoleFailure, HoleOutcome, HoleReport, ToolAxis,
};
pub use error::{DescriptionProblem, KinematicsError, LinkProblem};
pub use ik::{
    Configuration, Elbow, IkError, IkOptions, IkSolution, Shoulder, Singularity, Unreachable, Wrist,
};
pub use ik_numeric::NumericIk;
pub use joint::{Joint, JointKind, JointLimits, Mimic};
pub use motion::{move_circle, move_joint, move_line, DegeneratePath, MotionError, MotionOptions};
pub use opw::{NotOpw, OpwSolver};
pub use opw_params::OpwParameters;
pub use precision::{
    precision_manipulator, Free, NotPrecision, PrecisionAxes, PrecisionError, FINGER_OPEN,
    PRECISION_NAME, PROBE_HEIGHT, PROBE_STROKE_XY, PROBE_STROKE_Z, PROBE_TURN, TABLE_STROKE,
    TABLE_TURN,
};
pub use program::{
    parse_program, read_program, read_program_in, run_program, Instruction, Program, ProgramError,
    ProgramLine, ProgramRunError,
};
pub use robot::{IkSolver, IkSolverKind, Robot};
pub use trajectory::{Trajectory, TrajectorySample};
pub use tree::{KinematicTree, Link};
pub use ur::{NotUr, UrParameters, UrSolver};
pub use urdf::{
    parse_urdf, read_urdf, read_urdf_in, resolve_mesh, resolve_mesh_in, PackageFound, UrdfMesh,
    UrdfRobot, MAX_URDF_BYTES,
};
