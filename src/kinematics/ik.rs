//! Inverse-kinematics results, options and errors shared by the analytic and numeric
//! solvers.

use super::KinematicsError;
use std::fmt;

/// Which side of the first axis the wrist centre is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shoulder {
    /// The wrist centre is on the side it has at the zero configuration.
    Front,
    /// The arm reaches over to the other side of axis 1.
    Back,
}

/// Which way the elbow bends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Elbow {
    /// The elbow (axis 3) lies above the line from axis 2 to the wrist centre, as
    /// seen with the arm reaching forward.
    Up,
    /// The elbow lies below that line.
    Down,
}

/// Which of the two wrist solutions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Wrist {
    /// Axis 5 angle on the positive side (for the usual wrist, joint 5 > 0).
    NoFlip,
    /// Axis 5 angle on the negative side, axes 4 and 6 turned half a turn.
    Flip,
}

/// The configuration (branch) of a 6R ortho-parallel arm with a spherical wrist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Configuration {
    /// Shoulder front or back.
    pub shoulder: Shoulder,
    /// Elbow up or down.
    pub elbow: Elbow,
    /// Wrist flipped or not.
    pub wrist: Wrist,
}

impl fmt::Display for Configuration {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self.shoulder {
            Shoulder::Front => "front",
            Shoulder::Back => "back",
        };
        let e = match self.elbow {
            Elbow::Up => "up",
            Elbow::Down => "down",
        };
        let w = match self.wrist {
            Wrist::NoFlip => "noflip",
            Wrist::Flip => "flip",
        };
        write!(f, "{s}/{e}/{w}")
    }
}

/// One inverse-kinematics solution.
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Joint values in joint order (rad, or mm for prismatic joints).
    pub joints: Vec<f64>,
    /// The branch, for arms solved in closed form.
    pub configuration: Option<Configuration>,
    /// Euclidean distance in joint space to the reference configuration (rad/mm mix).
    pub distance: f64,
    /// The solution is at or near a singularity (wrist axes 4 and 6 aligned for the
    /// closed-form solver, Jacobian conditioning below the threshold for the numeric
    /// one): some joints are ill-conditioned or, exactly at it, chosen by a rule.
    pub singular: bool,
}

/// Settings of inverse kinematics.
#[derive(Debug, Clone, PartialEq)]
pub struct IkOptions {
    /// Seed of the numeric solver's random restarts.
    pub seed: u64,
    /// Number of numeric attempts (the first starts at the reference).
    pub restarts: usize,
    /// Iterations per numeric attempt.
    pub max_iterations: usize,
    /// Position tolerance (mm).
    pub position_tolerance: f64,
    /// Orientation tolerance (rad).
    pub angle_tolerance: f64,
    /// Stop the numeric search after this many distinct solutions (at least 1).
    pub max_solutions: usize,
    /// Wrist/shoulder singularity threshold (sine of the degenerate angle, or the
    /// relative smallest singular value of the Jacobian for the numeric solver).
    pub singularity_threshold: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            restarts: 24,
            max_iterations: 100,
            position_tolerance: 1e-7,
            angle_tolerance: 1e-10,
            max_solutions: 1,
            singularity_threshold: 1e-9,
        }
    }
}

/// Why inverse kinematics found no usable solution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IkError {
    /// The target lies outside the workspace (reason says which condition failed).
    #[error("target unreachable: {0}")]
    Unreachable(String),
    /// The target is at a singularity: infinitely many solutions (which joints are
    /// coupled is in the message).
    #[error("target at a singularity: {0}")]
    Singular(String),
    /// Solutions exist but every one violates a joint limit.
    #[error("every solution violates a joint limit (first: joint {joint} = {value:.6})")]
    JointLimits {
        /// 1-based joint number of the first violation of the nearest solution.
        joint: usize,
        /// Its value (rad or mm).
        value: f64,
    },
    /// Bad input (joint count, non-finite values).
    #[error(transparent)]
    Input(#[from] KinematicsError),
}
