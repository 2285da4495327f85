//! Why a document operation failed.

use super::equations::EquationError;
use super::mates::SolveError;
use super::robot;
use crate::diagnostics::SourceError;
use std::path::PathBuf;

/// Why a document operation failed. Load errors carry file, line and column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DocumentError {
    /// An error in a file the user wrote (YAML, STL, …), located.
    #[error("{0}")]
    Source(#[from] SourceError),
    /// A name that does not exist; the message lists close matches.
    #[error("no {what} named `{name}`: {hint}")]
    NotFound {
        /// "component", "dimension", …
        what: &'static str,
        /// The name asked for.
        name: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// An entry that is not valid (a full name, a mate's entities, a robot's joints).
    /// Boxed: the entry's kinds are large, and every `Result` carrying a
    /// `DocumentError` (the sequence and workspace layers') would grow with them.
    #[error(transparent)]
    Entry(Box<super::EntryError>),
    /// An operation a lower layer refused, in its words (a robot definition, a GLB
    /// export).
    #[error("{0}")]
    Invalid(String),
    /// The mates cannot all be satisfied: the worst mate and its residual. A load's
    /// error is located at that mate's entry (`at`, whose message is the cause's).
    #[error("{}", mates_message(.at.as_deref(), .source))]
    Mates {
        /// Where the failing mate is written, when it comes from a file.
        at: Option<Box<SourceError>>,
        /// The solver's verdict.
        #[source]
        source: SolveError,
    },
    /// An equation cannot be evaluated (syntax, unknown name, circle, division by
    /// zero, a value that is not finite or that its dimension refuses): which
    /// equation and why. A load's error is located at the equation's line (`at`).
    #[error("{}", equation_message(.at.as_deref(), .source))]
    Equation {
        /// Where the equation is written, when it comes from a file.
        at: Option<Box<SourceError>>,
        /// Which equation and why.
        #[source]
        source: EquationError,
    },
    /// A dimension an equation drives cannot be set by hand (SolidWorks refuses too):
    /// change the equation or the global variables it uses.
    #[error("dimension `{dimension}`{} is driven by equation [{index}] {equation}: change the equation (`set_equation`) or the global variables it uses", joint.as_ref().map_or(String::new(), |j| format!(" ({j})")))]
    DrivenByEquation {
        /// The dimension's full name.
        dimension: String,
        /// Which robot joint it is (`joint 2 of robot \`arm\``), when it is one.
        joint: Option<String>,
        /// The equation's index (`equation(i)`).
        index: usize,
        /// The equation's text (shortened when long).
        equation: String,
    },
    /// A suppressed component is not checked, planned or measured.
    #[error(
        "component `{0}` is suppressed; unsuppress it (`suppressed = false`) to check or plan it"
    )]
    Suppressed(String),
    /// A reference asked for as a coordinate system is another kind.
    #[error("reference `{reference}` of part `{part}` is a {kind}, not a coordinate system")]
    NotACoordinateSystem {
        /// The part.
        part: String,
        /// The reference's name.
        reference: String,
        /// What it is (`plane`, `axis`, `point`).
        kind: &'static str,
    },
    /// Fixed components do not move.
    #[error("component `{0}` is fixed; set `fixed: false` to move it")]
    FixedComponent(String),
    /// A robot's links move with its joints, not on their own.
    #[error("component `{component}` is a link of robot `{robot}`: set the robot's joints (or base) to move it")]
    RobotLink {
        /// The component asked to move.
        component: String,
        /// The robot that drives it.
        robot: String,
    },
    /// A value out of range for what it sets.
    #[error("{what}: {value} is out of range: {rule}")]
    OutOfRange {
        /// What was set (a dimension's full name, a pose, cut cells `name`).
        what: String,
        /// The value given (document units: mm or degrees; a pose as text).
        value: String,
        /// What is accepted.
        rule: &'static str,
    },
    /// A new robot's name is empty or taken.
    #[error("robot names must be unique and non-empty: `{0}`")]
    RobotName(String),
    /// A new robot would add a dimension that exists.
    #[error("robot `{robot}`: dimension `{dimension}` already exists")]
    DimensionTaken {
        /// The robot being added.
        robot: String,
        /// The dimension's full name.
        dimension: String,
    },
    /// A name with a control or invisible character (they hide or reorder what is
    /// shown).
    #[error("{what} name `{name}`: {character} is not allowed in names (control and invisible characters hide or reorder what is shown)")]
    HiddenCharacter {
        /// What is named (`robot`, …).
        what: String,
        /// The name, printable.
        name: String,
        /// The character, described.
        character: String,
    },
    /// `save_as` onto one of the document's own meshes.
    #[error("refusing to save over {}: it is the mesh of part `{part}`", .path.display())]
    OverMesh {
        /// The target path.
        path: PathBuf,
        /// The part whose mesh it is.
        part: String,
    },
    /// A robot refused an operation (kinematics, joint limits, program).
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// Writing the document failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// Target path.
        path: PathBuf,
        /// OS message.
        message: String,
    },
}

impl DocumentError {
    /// No `what` is named `name`: the error names the closest of `candidates`.
    pub(crate) fn not_found<'a>(
        what: &'static str,
        name: &str,
        candidates: impl IntoIterator<Item = &'a str> + Clone,
    ) -> Self {
        DocumentError::NotFound {
            what,
            name: name.into(),
            hint: crate::diagnostics::suggestion(name, candidates),
        }
    }

    /// Adds a hint to a located error.
    pub fn with_help(self, help: String) -> Self {
        match self {
            DocumentError::Source(s) => DocumentError::Source(s.with_help(help)),
            other => other,
        }
    }

    /// The message with source snippet for located errors.
    pub fn render(&self) -> String {
        match self.location() {
            Some(s) => s.render(),
            None => self.to_string(),
        }
    }

    /// Where in a file the error is, for located errors (a file's error, or mates
    /// of a file that cannot be satisfied).
    pub fn location(&self) -> Option<&SourceError> {
        match self {
            DocumentError::Source(s) => Some(s),
            DocumentError::Mates { at, .. } | DocumentError::Equation { at, .. } => at.as_deref(),
            _ => None,
        }
    }
}

/// A mate failure's message: located (`file:line:col: …`) when it comes from a file.
fn mates_message(at: Option<&SourceError>, source: &SolveError) -> String {
    match at {
        Some(at) => at.to_string(),
        None => source.to_string(),
    }
}

/// An equation failure's message: located (`file:line:col: …`) when it comes from a
/// file.
fn equation_message(at: Option<&SourceError>, source: &EquationError) -> String {
    match at {
        Some(at) => at.to_string(),
        None => source.to_string(),
    }
}

impl From<super::EntryError> for DocumentError {
    fn from(e: super::EntryError) -> Self {
        Self::Entry(Box::new(e))
    }
}
