//! [`EntryError`]: why one entry of a document is not valid (a full name, a mate's
//! entities, a feature, custom properties, a `step:` part's settings, a robot's
//! joints), in the entry's own terms. A file's loader locates it at the entry's line;
//! an edit returns it as [`DocumentError::Entry`](super::DocumentError::Entry).

use super::mates::MateKind;
use crate::kinematics::KinematicsError;
use crate::math::transform::TransformError;
use crate::mesh::step::StepError;

/// Why one entry of a document is not valid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EntryError {
    /// A full name with an empty level or spaces around a level.
    #[error(
        "`{0}`: a full name is levels joined by `/`, each non-empty without surrounding spaces"
    )]
    FullName(String),
    /// A mate entity not written `component/reference`.
    #[error("entity `{0}` must be written `component/reference`")]
    EntitySyntax(String),
    /// A mate entity naming no component.
    #[error("no component `{name}` ({hint})")]
    NoComponent {
        /// The component name given.
        name: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// A mate entity naming a reference its part does not have.
    #[error("part `{part}` has no reference `{reference}` ({hint})")]
    NoReference {
        /// The component's part.
        part: String,
        /// The reference name given.
        reference: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// A mate kind that cannot join these entity types.
    #[error("a {} mate cannot join a {a} and a {b}", .kind.name())]
    MateEntities {
        /// The mate's kind.
        kind: MateKind,
        /// The first entity's type (`plane`, `axis`, `point`, `coordinate_system`).
        a: &'static str,
        /// The second entity's type.
        b: &'static str,
    },
    /// A coincident mate between two coordinate systems asked to be anti-aligned.
    #[error("two coordinate systems coincide axis for axis: anti-aligned is not defined")]
    AntiAlignedSystems,
    /// Cut cells whose `cell_size` is not a number > 0 mm.
    #[error("cut cells `{name}`: cell_size must be a number > 0 mm, not {value}")]
    CellSize {
        /// The feature's name.
        name: String,
        /// The size given.
        value: f64,
    },
    /// Cut cells with a plane position that is not finite.
    #[error("cut cells `{0}`: plane positions must be finite")]
    CutPlanes(String),
    /// Cut cells with both or neither of `cell_size` and `planes`.
    #[error("cut cells `{0}`: give exactly one of `cell_size` and `planes`")]
    CutSpec(String),
    /// A custom property with an empty name.
    #[error("a custom property needs a name")]
    PropertyName,
    /// A custom property whose value is a list or a map.
    #[error("custom property `{0}` must be a text, a number or true/false")]
    PropertyValue(String),
    /// A `step:` part's `deflection:` or `angle:` that is not a number > 0.
    #[error("`{0}:` must be a number > 0")]
    StepSetting(&'static str),
    /// A `step:` part's `angle:` of 180 degrees or more.
    #[error("`angle:` is in degrees and must be below 180")]
    StepAngle,
    /// A `step:` part's file cannot be read.
    #[error(transparent)]
    Step(#[from] StepError),
    /// A robot's `home`, `base`, `tool` or `offset` that is not a rigid pose matrix.
    #[error("{what}: {source}")]
    Matrix {
        /// Which matrix.
        what: &'static str,
        /// Why it is not a pose.
        #[source]
        source: TransformError,
    },
    /// A joint type other than fixed, revolute and prismatic.
    #[error("unknown joint type `{0}` (fixed, revolute, prismatic)")]
    JointType(String),
    /// Joint limits that are not finite.
    #[error("limits [{lo}, {hi}] are not finite")]
    LimitsNotFinite {
        /// The lower limit given.
        lo: f64,
        /// The upper limit given.
        hi: f64,
    },
    /// Joint limits whose minimum is above their maximum.
    #[error("limits [{lo}, {hi}] are inverted (min > max)")]
    LimitsInverted {
        /// The lower limit given.
        lo: f64,
        /// The upper limit given.
        hi: f64,
    },
    /// A D-H convention other than standard and modified.
    #[error("unknown D-H convention `{0}` (standard, modified)")]
    DhConvention(String),
    /// A row of a D-H table that is not valid (1-based).
    #[error("D-H row {row}: {source}")]
    DhRow {
        /// The row, 1-based.
        row: usize,
        /// What is wrong with it.
        #[source]
        source: Box<EntryError>,
    },
    /// A fixed row in a D-H table.
    #[error("a row must be revolute or prismatic")]
    DhFixedRow,
    /// A D-H table without rows.
    #[error("the D-H table has no rows")]
    DhEmpty,
    /// The robot the entry describes is not valid.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
}
