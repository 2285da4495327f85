//! Errors of the Python module and their Python exceptions.
//!
//! The exception classes are plain Python (`fitup/errors.py`), so they pickle across
//! Dask or Ray workers and `InputError` can also be a `ValueError`. Each carries
//! `file`, `line`, `column` (None when the error is not located in a file) and
//! `cause` (the message without the location).

use fitup::diagnostics::SourceError;
use fitup::document::DocumentError;
use fitup::workspace::WorkspaceError;
use pyo3::prelude::*;

/// Why a call from Python failed, before it becomes a Python exception.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The document refused (load, save, unknown name, bad value).
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// A collision, sweep or planning request was refused.
    #[error(transparent)]
    Workspace(#[from] WorkspaceError),
    /// Sequence planning could not answer.
    #[error(transparent)]
    Sequence(#[from] fitup::sequence::SequenceError),
    /// A robot refused its input (joint count, non-finite values, a bad description).
    #[error(transparent)]
    Kinematics(#[from] fitup::kinematics::KinematicsError),
    /// Inverse kinematics refused its input or met a singularity.
    #[error(transparent)]
    Ik(#[from] fitup::kinematics::IkError),
    /// A motion program could not be read (located).
    #[error(transparent)]
    Program(#[from] fitup::kinematics::ProgramError),
    /// The results database refused.
    #[error(transparent)]
    Database(#[from] fitup::db::DbError),
    /// A script failed (located) or was cancelled.
    #[error(transparent)]
    Script(#[from] fitup::script::ScriptError),
    /// Script arguments that are not `key=value` text.
    #[error(transparent)]
    Arguments(#[from] fitup::script::ArgError),
    /// A project folder or a path outside it.
    #[error("{path}: {source}")]
    Project {
        /// The path given.
        path: String,
        /// What the project rule said.
        source: std::io::Error,
    },
    /// A path the project rule refuses (outside the project, empty).
    #[error(transparent)]
    Path(#[from] fitup::project::PathError),
    /// An array of the wrong shape.
    #[error("`{argument}` must have shape {expected}, not {shape:?}")]
    Shape {
        /// The argument's name.
        argument: &'static str,
        /// The shape accepted, e.g. `(4, 4)`.
        expected: &'static str,
        /// The shape given.
        shape: Vec<usize>,
    },
    /// A 4×4 array that is not a rigid motion.
    #[error("`{argument}` is not a rigid pose: {source}")]
    Pose {
        /// The argument's name.
        argument: &'static str,
        /// Why not.
        source: fitup::math::transform::TransformError,
    },
    /// An origin and axes that are not a coordinate system.
    #[error("`{argument}`: {source}")]
    CoordinateSystem {
        /// The argument's name.
        argument: &'static str,
        /// Why not.
        source: fitup::document::CoordinateSystemError,
    },
    /// Keyword arguments the request's vocabulary refuses (an unknown key, a value
    /// not of its kind).
    #[error(transparent)]
    Options(#[from] fitup::options::OptionError),
    /// A keyword argument with a value the call cannot use.
    #[error("`{option}` = {value}: expected {expected}")]
    Option {
        /// The keyword.
        option: &'static str,
        /// The value given (its repr).
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// Document call arguments that do not fit together (raised as `DocumentError`,
    /// as the document's own refusals).
    #[error(transparent)]
    Argument(#[from] Argument),
    /// A name that does not exist, with close matches.
    #[error("no {what} named `{name}`: {hint}")]
    Unknown {
        /// "planner", "robot", …
        what: &'static str,
        /// The name asked for.
        name: String,
        /// Close matches or what exists.
        hint: String,
    },
    /// A Python-side failure (a conversion, an import) passed through as it is.
    #[error(transparent)]
    Python(#[from] PyErr),
    /// A lock held by a call that panicked.
    #[error("internal error: the {what} lock was poisoned by a panic (please report this)")]
    Poisoned {
        /// What was locked.
        what: &'static str,
    },
}

/// What is wrong with a document call's arguments ([`Error::Argument`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Argument {
    /// Custom properties of both or neither of a component and a part.
    #[error("give exactly one of `component` and `part`")]
    OneOwner,
    /// A custom property's value of another type.
    #[error("custom property `{key}`: a value is a str, number or bool")]
    PropertyValue {
        /// The property's name.
        key: String,
    },
    /// A reference without one of the vectors its kind needs.
    #[error("a {kind} needs `{argument}`")]
    Needs {
        /// The reference kind.
        kind: String,
        /// The keyword it needs (`point`, `direction`, `x`, `y`).
        argument: &'static str,
    },
    /// A reference kind that does not exist.
    #[error("reference kind `{0}`: plane, axis, point or coordinate_system")]
    ReferenceKind(String),
}

/// Result of a conversion or a library call on the way to Python.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// The Python class in `fitup.errors` this error raises.
    fn class(&self) -> &'static str {
        match self {
            Error::Document(DocumentError::Robot(_)) => "RobotError",
            Error::Document(_) => "DocumentError",
            Error::Workspace(WorkspaceError::Document(_)) => "DocumentError",
            // A planner option the library refuses is a bad argument.
            Error::Workspace(WorkspaceError::Plan(_)) => "InputError",
            Error::Workspace(_) => "WorkspaceError",
            Error::Sequence(_) => "SequenceError",
            Error::Kinematics(_) | Error::Ik(_) | Error::Program(_) => "RobotError",
            Error::Database(_) => "DatabaseError",
            Error::Script(_) | Error::Arguments(_) => "ScriptError",
            Error::Project { .. } | Error::Argument(_) => "DocumentError",
            Error::Shape { .. }
            | Error::Pose { .. }
            | Error::Option { .. }
            | Error::CoordinateSystem { .. } => "InputError",
            Error::Path(_) => "InputError",
            Error::Unknown { .. } | Error::Options(_) => "InputError",
            Error::Poisoned { .. } | Error::Python(_) => "FitupError",
        }
    }

    /// The file, line and column the error is located at, and its cause alone.
    fn location(&self) -> (Option<String>, Option<usize>, Option<usize>, String) {
        fn source(s: &SourceError) -> (Option<String>, Option<usize>, Option<usize>, String) {
            (
                Some(s.path.display().to_string()),
                s.line,
                s.column,
                s.message.clone(),
            )
        }
        use fitup::sequence::SequenceError as S;
        let document = match self {
            Error::Document(d)
            | Error::Workspace(WorkspaceError::Document(d))
            | Error::Sequence(S::Workspace(WorkspaceError::Document(d))) => Some(d),
            _ => None,
        };
        if let Some(s) = document.and_then(DocumentError::location) {
            return source(s);
        }
        match self {
            Error::Script(fitup::script::ScriptError::Located(s)) => source(s),
            Error::Program(p) => (
                Some(p.file.clone()),
                (p.line > 0).then_some(p.line),
                (p.column > 0).then_some(p.column),
                p.cause.clone(),
            ),
            Error::Document(DocumentError::Robot(fitup::document::RobotError::Program {
                source,
                ..
            })) => (
                Some(source.file.clone()),
                (source.line > 0).then_some(source.line),
                None,
                source.source.to_string(),
            ),
            Error::Project { path, source } => (Some(path.clone()), None, None, source.to_string()),
            other => (None, None, None, other.to_string()),
        }
    }

    /// The Python exception (an instance of a `fitup.errors` class), with `output`
    /// (a script's printed lines) when there is one.
    pub fn into_py(self, py: Python<'_>, output: Option<Vec<String>>) -> PyErr {
        if let Error::Python(e) = self {
            return e;
        }
        let message = match &self {
            Error::Document(d) => d.render(),
            Error::Script(s) => s.render(),
            other => other.to_string(),
        };
        let (file, line, column, cause) = self.location();
        let class = self.class();
        let made = py
            .import("fitup.errors")
            .and_then(|m| m.getattr(class))
            .and_then(|c| c.call1((message, file, line, column, cause, output)));
        match made {
            Ok(value) => PyErr::from_value(value),
            Err(e) => e,
        }
    }
}

impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        Python::attach(|py| e.into_py(py, None))
    }
}
