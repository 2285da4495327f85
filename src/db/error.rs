//! [`DbError`] and its typed causes: the driver's answer ([`DriverError`]), why a
//! database did not open ([`OpenCause`], [`FolderError`]), how a read-only one showed
//! ([`ReadOnlyCause`]), what a foreign file is ([`ForeignFile`]) and what a read-only
//! query was refused ([`Refusal`]).

pub use super::backend::{DriverError, DriverErrorKind};
use super::query::{self, QueryLimits};
use super::Target;
use crate::fsutil::IoCause;
use std::path::PathBuf;
use std::time::Duration;

/// Why a database operation failed. Every variant names the database.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DbError {
    /// The database was written by a newer fitup.
    #[error("{target} was written by a newer fitup (schema version {found}; this fitup {ours} knows versions up to {supported}): upgrade fitup to use it")]
    NewerSchema {
        /// The database.
        target: Target,
        /// Its schema version.
        found: u32,
        /// The newest version this build knows.
        supported: u32,
        /// This build's version.
        ours: &'static str,
    },
    /// The database cannot be opened or reached.
    #[error("cannot open the database {target}: {cause}")]
    Open {
        /// The database.
        target: Target,
        /// Why not.
        #[source]
        cause: OpenCause,
    },
    /// The file, its folder or the server refuses writes.
    #[error("the database {target} is read-only: {cause}")]
    ReadOnly {
        /// The database.
        target: Target,
        /// How it showed.
        #[source]
        cause: ReadOnlyCause,
    },
    /// An existing file that is not a fitup results database (another program's
    /// SQLite database, a CSV named `x.db`): it is not opened, so nothing turns it
    /// into one.
    #[error("{target} is not a fitup results database: {cause}; it was left as it is (name a new file, or the project's own database)")]
    Foreign {
        /// The database file.
        target: Target,
        /// What it is instead.
        cause: ForeignFile,
    },
    /// The disk is full; the result was not stored (earlier results are intact).
    #[error("the disk holding {target} is full; the result was not stored: {cause}")]
    DiskFull {
        /// The database.
        target: Target,
        /// The driver's answer.
        #[source]
        cause: DriverError,
    },
    /// Other writers held the database for too long.
    #[error("the database {target} stayed busy (other writers) through {tries} tries: {cause}")]
    Busy {
        /// The database.
        target: Target,
        /// Attempts made.
        tries: u32,
        /// The driver's last answer.
        #[source]
        cause: DriverError,
    },
    /// A read-only query tried to change the database, or to reach outside it
    /// (ATTACH, a setting, a file or server function).
    #[error("db.query is read-only and reads this database only: {cause}")]
    WriteRefused {
        /// What was refused.
        #[source]
        cause: Refusal,
    },
    /// A query ran past its time limit and was stopped.
    #[error("query stopped after {} s (the time limit of db.query on {target}; a script may raise it up to {} s with #{{max_seconds: …}})", .limit.as_secs_f64(), QueryLimits::MAX.time.as_secs())]
    QueryTimeout {
        /// The database.
        target: Target,
        /// The limit that passed.
        limit: Duration,
    },
    /// A query's result passed the row or byte cap; nothing of it is returned.
    #[error("the query on {target} returned more than {} rows or {} (the result limit of db.query; a script may raise it up to {} rows and {} with #{{max_rows: …, max_bytes: …}}, or ask for fewer rows with LIMIT)", query::thousands(*.max_rows as u64), query::bytes(*.max_bytes), query::thousands(QueryLimits::MAX.max_rows as u64), query::bytes(QueryLimits::MAX.max_bytes))]
    QueryTooLarge {
        /// The database.
        target: Target,
        /// The row cap.
        max_rows: usize,
        /// The byte cap.
        max_bytes: usize,
    },
    /// The run's queries used up their shared time budget ([`RunQueryBudget`]).
    #[error("the queries of this run have used their time budget of {} s (db.query's run budget: {} s, or the largest max_seconds a query of the run asked for; docs/database.md)", .budget.as_secs_f64(), query::RUN_QUERY_BUDGET.as_secs())]
    QueryBudget {
        /// The budget that was used up.
        budget: Duration,
    },
    /// The run was cancelled (a newer save in watch mode) while a query ran.
    #[error("query on {target} cancelled")]
    QueryCancelled {
        /// The database.
        target: Target,
    },
    /// A query limit asked for by a script is out of range.
    #[error(
        "the query limit {} = {} is out of range: it must be positive and at most {}",
        .asked.name(),
        .asked.value(),
        .asked.max()
    )]
    QueryLimit {
        /// Which limit, and what was asked for.
        asked: AskedLimit,
    },
    /// No record with that id.
    #[error("no {what} with id {id} in {target}")]
    NotFound {
        /// "run", "path", …
        what: &'static str,
        /// The id asked for.
        id: i64,
        /// The database.
        target: Target,
    },
    /// A value that cannot be stored (a non-finite number, …).
    #[error("cannot store {what}: {}{cause}", during_prefix(.during))]
    Invalid {
        /// What was being stored.
        what: String,
        /// The operation it failed in ("storing the path", …).
        during: Option<String>,
        /// Why not.
        #[source]
        cause: DriverError,
    },
    /// Any other SQL error.
    #[error("database {target}: {}{cause}", during_prefix(.during))]
    Sql {
        /// The database.
        target: Target,
        /// The operation it failed in ("storing the run", …); none for a script's query.
        during: Option<String>,
        /// The driver's answer.
        #[source]
        cause: DriverError,
    },
}

/// Why the folder of a SQLite file cannot be held open (the cause of a
/// [`DbError::Open`]).
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum FolderError {
    /// The path ends in `..` or is a root: no file name.
    #[error("not a file name")]
    NotAFileName,
    /// The folder does not exist.
    #[error("the folder {} does not exist", .0.display())]
    Missing(PathBuf),
    /// The folder cannot be opened (permissions, a file on the way, …).
    #[error("its folder {}: {source}", .folder.display())]
    Unreadable {
        /// The folder.
        folder: PathBuf,
        /// The operating system's refusal.
        #[source]
        source: IoCause,
    },
}

/// `"{during}: "`, or nothing.
fn during_prefix(during: &Option<String>) -> String {
    during
        .as_deref()
        .map(|d| format!("{d}: "))
        .unwrap_or_default()
}

/// Why a database could not be opened (the cause of a [`DbError::Open`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OpenCause {
    /// The SQLite file's folder cannot be held open.
    #[error(transparent)]
    Folder(#[from] FolderError),
    /// The file's kind or first bytes could not be read.
    #[error(transparent)]
    Io(#[from] IoCause),
    /// The path names a folder.
    #[error("it is a folder, not a database file")]
    IsFolder,
    /// The path became a symbolic link after it was checked.
    #[error("it is a symbolic link (it was not one when its path was checked): not followed")]
    Symlink,
    /// The path names a device, socket or pipe.
    #[error("it is {0}, not a database file")]
    Special(&'static str),
    /// The driver refused to open or set up the connection (SQLite), or the server
    /// could not be reached (PostgreSQL; its message scrubbed of credentials).
    #[error(transparent)]
    Driver(DriverError),
    /// The read-only connection of scripts' queries could not be opened.
    #[error("the read-only query connection: {0}")]
    QueryConnection(#[source] DriverError),
    /// A SQLite connection without a held file (cannot happen through
    /// [`Database::open`](super::Database::open)).
    #[error("a SQLite connection without a file")]
    NoFile,
    /// A `postgres://` target in a build without the `postgres` feature.
    #[error("this fitup was built without PostgreSQL support: rebuild with `cargo install --path . --features postgres`")]
    NoPostgres,
}

/// How a read-only database showed (the cause of a [`DbError::ReadOnly`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReadOnlyCause {
    /// The existing file cannot be opened for writing; `driver` is SQLite's refusal
    /// when it came first.
    #[error("the file is not writable{}", .driver.as_ref().map(|d| format!(" ({d})")).unwrap_or_default())]
    FileNotWritable {
        /// SQLite's answer, when it refused before fitup checked the file.
        driver: Option<DriverError>,
    },
    /// The driver said the database is read-only.
    #[error(transparent)]
    Driver(DriverError),
}

/// What an existing file that is not a fitup results database is instead (the cause
/// of a [`DbError::Foreign`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ForeignFile {
    /// Its first bytes are not SQLite's header.
    #[error("it is not a SQLite file (its first bytes are not SQLite's header)")]
    NotSqlite,
    /// A SQLite database with tables but without fitup's `schema_version`.
    #[error(
        "it is a SQLite database of another program (it has tables but not fitup's schema_version)"
    )]
    OtherProgram,
}

/// What a read-only query was refused (the cause of a [`DbError::WriteRefused`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Refusal {
    /// fitup's jail refused an action of the statement before it ran (SQLite's
    /// authorizer, or the PostgreSQL statement check): the action and why.
    #[error("{0}")]
    Jail(JailRefusal),
    /// The server refused a write inside the read-only transaction (PostgreSQL).
    #[error(transparent)]
    Driver(DriverError),
}

/// What fitup's jail refused in a read-only query, and why (the cause of a
/// [`Refusal::Jail`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum JailRefusal {
    /// A function that reaches outside the database (`load_extension`, …).
    Function {
        /// The function as written.
        name: String,
    },
    /// `PRAGMA name = …`: it changes a setting.
    PragmaSet {
        /// The pragma as written.
        name: String,
    },
    /// A `PRAGMA` that is not a schema query.
    Pragma {
        /// The pragma as written.
        name: String,
    },
    /// `ATTACH` (another database file).
    Attach,
    /// `DETACH` (it changes the connection).
    Detach,
    /// A transaction or savepoint (each query is one read).
    Transaction,
    /// DROP, CREATE or ALTER (a write to SQLite's schema table).
    Schema,
    /// `INSERT`.
    Insert {
        /// The table.
        table: String,
    },
    /// `UPDATE`.
    Update {
        /// The table.
        table: String,
    },
    /// `DELETE`.
    Delete {
        /// The table.
        table: String,
    },
    /// `DROP TABLE`.
    DropTable {
        /// The table.
        table: String,
    },
    /// Any other action of SQLite's authorizer (its name: `CreateIndex`, …).
    Other {
        /// The authorizer's name of the action.
        action: String,
    },
    /// A statement SQLite says would change the database.
    Writes,
    /// A PostgreSQL statement that is not a query: its first word, uppercased
    /// (empty: an empty statement).
    NotAQuery {
        /// The statement's first word.
        first: String,
    },
    /// A PostgreSQL function that reaches outside the results database (server
    /// files, other SQL, other sessions or settings): its name or prefix.
    Outside {
        /// The name (`pg_read_file`) or prefix (`pg_ls`).
        function: &'static str,
    },
}

impl std::fmt::Display for JailRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            JailRefusal::Function { name } => {
                write!(f, "the function `{name}` reaches outside the database")
            }
            JailRefusal::PragmaSet { name } => write!(f, "`PRAGMA {name} = …` changes a setting"),
            JailRefusal::Pragma { name } => write!(f, "`PRAGMA {name}` is not a schema query"),
            JailRefusal::Attach => f.write_str("ATTACH would open another database file"),
            JailRefusal::Detach => f.write_str("DETACH changes the connection"),
            JailRefusal::Transaction => {
                f.write_str("transactions are fitup's (each query is one read)")
            }
            JailRefusal::Schema => {
                f.write_str("the statement changes the schema (DROP, CREATE or ALTER)")
            }
            JailRefusal::Insert { table } => write!(f, "INSERT into `{table}` writes"),
            JailRefusal::Update { table } => write!(f, "UPDATE of `{table}` writes"),
            JailRefusal::Delete { table } => write!(f, "DELETE from `{table}` writes"),
            JailRefusal::DropTable { table } => write!(f, "DROP TABLE `{table}` writes"),
            JailRefusal::Other { action } => write!(f, "{action} writes or changes the schema"),
            JailRefusal::Writes => f.write_str("the statement would change the database"),
            JailRefusal::NotAQuery { first } => {
                if first.is_empty() {
                    f.write_str("an empty statement")?;
                } else {
                    write!(f, "`{first}`")?;
                }
                f.write_str(" is not a query: only SELECT, WITH, VALUES and TABLE statements run")
            }
            JailRefusal::Outside { function } => write!(
                f,
                "`{function}…` reaches outside the results database (server files, other SQL, other sessions or settings)"
            ),
        }
    }
}

impl PartialEq for FolderError {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (FolderError::NotAFileName, FolderError::NotAFileName) => true,
            (FolderError::Missing(a), FolderError::Missing(b)) => a == b,
            (
                FolderError::Unreadable {
                    folder: a,
                    source: x,
                },
                FolderError::Unreadable {
                    folder: b,
                    source: y,
                },
            ) => a == b && x == y,
            _ => false,
        }
    }
}

/// A query limit a script asked for ([`DbError::QueryLimit`]): which limit and its
/// value.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum AskedLimit {
    /// `max_seconds`: wall time, s.
    Seconds(f64),
    /// `max_rows`.
    Rows(usize),
    /// `max_bytes`.
    Bytes(usize),
}

impl AskedLimit {
    /// The limit's option name (`max_seconds`, `max_rows`, `max_bytes`).
    pub fn name(&self) -> &'static str {
        match self {
            AskedLimit::Seconds(_) => "max_seconds",
            AskedLimit::Rows(_) => "max_rows",
            AskedLimit::Bytes(_) => "max_bytes",
        }
    }

    /// The value asked for, for people (`0 s`, `5,000,000`).
    fn value(&self) -> String {
        match *self {
            AskedLimit::Seconds(s) => format!("{s} s"),
            AskedLimit::Rows(n) | AskedLimit::Bytes(n) => query::thousands(n as u64),
        }
    }

    /// The hard maximum ([`QueryLimits::MAX`]), for people.
    fn max(&self) -> String {
        let max = QueryLimits::MAX;
        match self {
            AskedLimit::Seconds(_) => format!("{} s", max.time.as_secs()),
            AskedLimit::Rows(_) => query::thousands(max.max_rows as u64),
            AskedLimit::Bytes(_) => format!(
                "{} ({})",
                query::thousands(max.max_bytes as u64),
                query::bytes(max.max_bytes)
            ),
        }
    }
}
