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

impl IkOptions {
    /// Numeric solutions searched for by [`IkOptions::every_branch`].
    pub const EVERY_BRANCH: usize = 16;

    /// The defaults, asking for every solution: the closed-form solvers give every
    /// branch anyway; the numeric solver keeps restarting until it has
    /// [`IkOptions::EVERY_BRANCH`] distinct solutions or runs out of restarts. What a
    /// script's `ik` and Python's `Robot.ik` ask for.
    pub fn every_branch() -> Self {
        Self {
            max_solutions: Self::EVERY_BRANCH,
            ..Self::default()
        }
    }
}

/// Why a target is out of reach, as each solver sees it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Unreachable {
    /// The target pose or the reference joints have NaN or infinite values.
    #[error("the target or the reference is not finite")]
    NotFinite,
    /// A closed-form solver's wrist point is outside the arm's reach.
    #[error("{wrist_point} is outside the arm's reach ({min_mm:.3}..{max_mm:.3} mm from axis 2, at least {offset_mm:.3} mm from axis 1)")]
    BeyondReach {
        /// Which point (the wrist centre; a UR's wrist point on axis 4).
        wrist_point: &'static str,
        /// Nearest reach from axis 2 (mm).
        min_mm: f64,
        /// Farthest reach from axis 2 (mm).
        max_mm: f64,
        /// The lateral offset the point keeps from axis 1 (mm).
        offset_mm: f64,
    },
    /// The numeric solver's descents did not converge.
    #[error("no descent converged; closest approach {distance_mm:.3} mm / {angle_rad:.3e} rad")]
    NoConvergence {
        /// Closest position error reached (mm).
        distance_mm: f64,
        /// Its orientation error (rad).
        angle_rad: f64,
    },
    /// A solver returned no solution and no reason.
    #[error("no solution")]
    NoSolution,
}

/// Which joints a singular target leaves undetermined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Singularity {
    /// A closed-form solver's wrist point is on axis 1 or axis 2: joint 1 or 2 is
    /// undetermined.
    #[error("the wrist point is on axis 1 or axis 2 (joint 1 or 2 undetermined)")]
    JointUndetermined,
    /// The numeric solver converged where the Jacobian is rank-deficient.
    #[error("the solution has a rank-deficient Jacobian")]
    RankDeficient,
}

/// Why inverse kinematics found no usable solution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IkError {
    /// The target lies outside the workspace (which condition failed).
    #[error("target unreachable: {0}")]
    Unreachable(Unreachable),
    /// The target is at a singularity: infinitely many solutions (which joints are
    /// coupled).
    #[error("target at a singularity: {0}")]
    Singular(Singularity),
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
