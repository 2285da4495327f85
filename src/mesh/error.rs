//! [`MeshError`]: what every mesh reader and writer returns — a typed kind, the file,
//! the line (text formats) and the cause in words.

use std::fmt;
use std::path::{Path, PathBuf};

/// What kind of problem a [`MeshError`] is (the message says which element and why).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MeshErrorKind {
    /// The file could not be read: missing, not a regular file, over its size cap, a
    /// path outside the project or changed while it was opened.
    Read,
    /// A format or feature fitup does not read (COLLADA, sparse accessors, a glTF
    /// without the `formats` feature, free-form OBJ geometry).
    Unsupported,
    /// The bytes are not valid for the format: syntax, a truncated body, counts that
    /// the file cannot hold.
    Malformed,
    /// A coordinate that is not finite or is beyond
    /// [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE) mm.
    Coordinate,
    /// A vertex index past the vertices.
    Index,
    /// More than a reader's cap: [`MAX_TRIANGLES`](super::MAX_TRIANGLES),
    /// [`MAX_VERTICES`](super::MAX_VERTICES), node visits of a glTF scene. Counted
    /// before the storage is allocated.
    TooLarge,
    /// No triangles, or none with an area: nothing to collide with or show.
    NoSurface,
    /// A file could not be written.
    Write,
}

/// A mesh that could not be read or written: which file, where in it, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct MeshError {
    /// What kind of problem it is.
    pub kind: MeshErrorKind,
    /// The file, when there is one.
    pub path: Option<PathBuf>,
    /// 1-based line of a text format (ASCII STL, OBJ, ASCII PLY, .gltf JSON), when known.
    pub line: Option<usize>,
    /// What is wrong, in words (the element or item and the cause).
    pub message: String,
}

impl MeshError {
    /// An error of `kind`, not yet located.
    pub fn new(kind: MeshErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            path: None,
            line: None,
            message: message.into(),
        }
    }

    /// A [`MeshErrorKind::Malformed`] error, not yet located.
    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Self::new(MeshErrorKind::Malformed, message)
    }

    /// A [`MeshErrorKind::Malformed`] error at `line`.
    pub(crate) fn at(line: usize, message: impl Into<String>) -> Self {
        Self::invalid(message).on_line(line)
    }

    /// The same error, of `kind`.
    pub(crate) fn kind(mut self, kind: MeshErrorKind) -> Self {
        self.kind = kind;
        self
    }

    /// The same error, at `line`.
    pub(crate) fn on_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }

    /// The same error, its message after `prefix` (the element it is in).
    pub(crate) fn prefixed(mut self, prefix: &str) -> Self {
        self.message.insert_str(0, prefix);
        self
    }

    /// The same error, `suffix` after its message (a unit, a hint).
    #[cfg_attr(not(feature = "formats"), allow(dead_code))]
    pub(crate) fn suffixed(mut self, suffix: &str) -> Self {
        self.message.push_str(suffix);
        self
    }

    /// The same error, naming `path`.
    pub fn in_file(mut self, path: &Path) -> Self {
        self.path = Some(path.to_path_buf());
        self
    }

    /// "more than CAP WHAT: larger than fitup reads", of kind
    /// [`MeshErrorKind::TooLarge`] — what every reader says at a cap, before it
    /// allocates past it.
    pub(crate) fn too_many(cap: usize, what: &str) -> Self {
        Self::new(
            MeshErrorKind::TooLarge,
            format!("more than {cap} {what}: larger than fitup reads (docs/document.md, \"Mesh files\")"),
        )
    }
}

impl From<crate::fsutil::ReadError> for MeshError {
    fn from(e: crate::fsutil::ReadError) -> Self {
        MeshError::new(MeshErrorKind::Read, e.to_string())
    }
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.path, self.line) {
            (Some(p), Some(l)) => write!(f, "{}:{}: {}", p.display(), l, self.message),
            (Some(p), None) => write!(f, "{}: {}", p.display(), self.message),
            (None, Some(l)) => write!(f, "line {}: {}", l, self.message),
            (None, None) => write!(f, "{}", self.message),
        }
    }
}
