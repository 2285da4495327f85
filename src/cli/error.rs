//! [`CliError`]: why the command line refused a request before it ran.

use crate::fsutil::ReadError;
use crate::options::OptionError;
use crate::project::PathError;
use crate::script::ArgError;
use std::path::PathBuf;

/// Why a command-line request was refused before it ran (printed as `error: …`; the
/// command exits with its usage code).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CliError {
    /// A path given on the command line that cannot be made absolute, or a file's
    /// project that cannot be opened.
    #[error("{what} {}: {source}", .path.display())]
    Path {
        /// What the path is (`script`, `program`, `document`, `--record`).
        what: &'static str,
        /// The path as given.
        path: PathBuf,
        /// The operating system's refusal.
        #[source]
        source: std::io::Error,
    },
    /// A file named on the command line that does not exist.
    #[error("{what} {} does not exist", .path.display())]
    Missing {
        /// What the file is.
        what: &'static str,
        /// The path as given.
        path: PathBuf,
    },
    /// The `--root` folder cannot be opened.
    #[error("project folder {}: {source}", .path.display())]
    ProjectFolder {
        /// The folder as given.
        path: PathBuf,
        /// The operating system's refusal.
        #[source]
        source: std::io::Error,
    },
    /// The project of a file named on the command line cannot be opened (the file's
    /// path is in the message around it).
    #[error("its project cannot be opened: {0}")]
    ProjectOfFile(#[source] std::io::Error),
    /// A path the project's path rule refuses (outside the project, …).
    #[error("{what}: {source}{}", if *.root_hint { " (pass --root)" } else { "" })]
    Refused {
        /// What the path is.
        what: &'static str,
        /// The rule's refusal.
        #[source]
        source: PathError,
        /// Whether `--root` would name another project.
        root_hint: bool,
    },
    /// The current folder cannot be read (`fitup db` without `--root`).
    #[error("cannot read the current folder: {0}")]
    CurrentFolder(#[source] std::io::Error),
    /// A number of seconds that is negative, not finite or too large.
    #[error("--{flag} must be a number of seconds ≥ 0, got {value}")]
    Seconds {
        /// The flag.
        flag: &'static str,
        /// The value given.
        value: f64,
    },
    /// `--gravity` that is not three numbers.
    #[error("--gravity must be three numbers `x,y,z`, not `{0}`")]
    Gravity(String),
    /// A record id of `fitup db` whose kind is not one of the four.
    #[error("unknown record kind `{0}`: use run:N, path:N, trajectory:N or interference:N")]
    RecordKind(String),
    /// A record id whose number is not a number.
    #[error("`{0}` is not a record number")]
    RecordNumber(String),
    /// An option the request's vocabulary refuses.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// Script arguments (after `--`) that are not `KEY=VALUE`.
    #[error(transparent)]
    Arguments(#[from] ArgError),
    /// A file named on the command line that cannot be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The viewer cannot start (or is not built in).
    #[error(transparent)]
    Viewer(#[from] crate::viewer::ViewerError),
}
