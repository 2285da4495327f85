//! [`KinematicsError`]: invalid trees, robots and joint vectors.

/// Why a tree, a robot or a joint vector is not valid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KinematicsError {
    /// A link of a tree is malformed.
    #[error("link {link} ({name}): {cause}")]
    InvalidLink {
        /// Index of the link.
        link: usize,
        /// Its name, empty if none.
        name: String,
        /// What is wrong.
        cause: String,
    },
    /// A joint vector has the wrong length.
    #[error("expected {expected} joint values, got {got}")]
    JointCount {
        /// Number of values expected.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A joint value is NaN or infinite.
    #[error("joint value {0} is not finite")]
    NonFiniteJoint(usize),
    /// The flange link index does not exist.
    #[error("flange link {0} does not exist in the tree")]
    NoSuchLink(usize),
    /// A robot needs at least one movable joint between the root and the flange.
    #[error("the chain from the root to the flange has no movable joint")]
    NoJoints,
    /// A D-H table or catalog entry is malformed.
    #[error("invalid robot description: {0}")]
    InvalidDescription(String),
}
