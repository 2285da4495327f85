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
        #[source]
        cause: LinkProblem,
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
    InvalidDescription(#[source] DescriptionProblem),
}

/// What is wrong with a link of a tree or robot (the cause of a
/// [`KinematicsError::InvalidLink`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinkProblem {
    /// The parent is listed at or after the link.
    #[error("parent index {parent} is not before the link (links must be listed parents first)")]
    ParentAfter {
        /// The parent's index.
        parent: usize,
    },
    /// The home transform has a NaN or an infinity.
    #[error("home transform is not finite")]
    HomeNotFinite,
    /// A movable joint's axis is not a finite unit vector.
    #[error("joint axis is zero or not finite")]
    AxisNotUnit,
    /// A movable joint's axis point has a NaN or an infinity.
    #[error("joint axis point is not finite")]
    AxisPointNotFinite,
    /// Joint limits not finite, or `min > max`.
    #[error("joint limits {min}..{max} are invalid")]
    Limits {
        /// The lower limit.
        min: f64,
        /// The upper limit.
        max: f64,
    },
    /// A mimic joint or its leader is fixed, or they are the same joint.
    #[error("a mimic joint and its leader must be two movable joints")]
    MimicNotMovable,
    /// A mimic multiplier or offset is not finite.
    #[error("mimic multiplier and offset must be finite")]
    MimicNotFinite,
    /// A mimic joint whose leader follows another joint.
    #[error("its mimic leader follows another joint (resolve the chain to the first leader)")]
    MimicChain,
    /// An external axis that is a fixed joint.
    #[error("an external axis must be a movable joint")]
    ExternalFixed,
    /// An external axis on the chain from the root to the flange.
    #[error("an external axis must be off the flange chain")]
    ExternalOnChain,
    /// An external axis that follows a mimic joint.
    #[error("an external axis cannot follow a mimic joint")]
    ExternalMimic,
    /// A link listed twice as an external axis.
    #[error("the link is listed twice as an external axis")]
    ExternalTwice,
}

/// What is wrong with a robot's description: a D-H table, OPW parameters, the tool
/// frame or the flange chain (the cause of a [`KinematicsError::InvalidDescription`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DescriptionProblem {
    /// A D-H row with a NaN or an infinity (`row` is 1-based).
    #[error("D-H row {row} is not finite")]
    DhNotFinite {
        /// The row, 1-based.
        row: usize,
    },
    /// A D-H row whose joint is neither revolute nor prismatic (`row` is 1-based).
    #[error("D-H row {row} must be revolute or prismatic")]
    DhJointKind {
        /// The row, 1-based.
        row: usize,
    },
    /// An OPW length that is not finite.
    #[error("OPW parameter {name} = {value} is not finite")]
    OpwLength {
        /// `a1`, `a2`, `b`, `c1` … `c4`.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// An OPW joint offset that is not finite (`joint` is 1-based).
    #[error("OPW offset of joint {joint} is not finite")]
    OpwOffset {
        /// The joint, 1-based.
        joint: usize,
    },
    /// An OPW joint sign that is not ±1 (`joint` is 1-based).
    #[error("OPW sign of joint {joint} is {sign}, not ±1")]
    OpwSign {
        /// The joint, 1-based.
        joint: usize,
        /// The sign given.
        sign: f64,
    },
    /// OPW `c2 <= 0`: no upper arm.
    #[error("OPW c2 = {c2} mm: the upper arm needs a positive length")]
    OpwUpperArm {
        /// The value given.
        c2: f64,
    },
    /// OPW `a2 = c3 = 0`: no forearm.
    #[error("OPW a2 = c3 = 0: the forearm has no length")]
    OpwForearm,
    /// A link on the chain to the flange follows a mimic joint.
    #[error("link `{link}` on the chain to the flange moves with a mimic joint (it follows link `{leader}`): choose a flange above it")]
    MimicOnChain {
        /// The link's name (empty if none).
        link: String,
        /// Its leader's name (empty if none).
        leader: String,
    },
    /// The tool frame has a NaN or an infinity.
    #[error("tool frame is not finite")]
    ToolNotFinite,
    /// An IK target pose has a NaN or an infinity.
    #[error("target pose is not finite")]
    TargetNotFinite,
}
