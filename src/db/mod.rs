//! The results database: every run's paths, trajectories, document snapshots and
//! interference results kept in SQL, so they can be compared, queried and shared.
//!
//! Two back ends behind one API ([`Database`]):
//! - **SQLite** (default): one file per project, `fitup.db` at the project root unless
//!   `--db` or the `FITUP_DB` variable names another ([`Target::resolve`]). WAL mode,
//!   foreign keys on, a busy timeout plus retries so several `fitup run` processes can
//!   write at once.
//! - **PostgreSQL** (`postgres://…` or `postgresql://…`): the same schema and API for
//!   teams and batches that outgrow one machine.
//!
//! Every stored result is one transaction: a process killed mid-write leaves either
//! the whole result or none of it. The schema is versioned in code (`schema_version`);
//! a database written by a newer fitup is refused with [`DbError::NewerSchema`].
//!
//! Units: millimetres and radians, as everywhere in fitup. Poses are stored as columns
//! `x_mm, y_mm, z_mm` (translation), `a_deg, b_deg, c_deg` (the user-facing `X Y Z A B C`
//! triple, **degrees**, fixed X then Y then Z, for queries) and `qw, qx, qy, qz` (the
//! rotation quaternion, which is what is read back, so poses round-trip exactly).
//! Joint values of trajectory samples are a JSON array in radians (mm for prismatic
//! joints). See `docs/database.md` for the tables.
//!
//! # Examples
//!
//! ```
//! use fitup::db::{Database, PathQuery, Target};
//! let dir = tempfile::tempdir().unwrap();
//! let mut db = Database::open(&Target::Sqlite(dir.path().join("fitup.db"))).unwrap();
//! let run = db.start_run(&fitup::db::NewRun::script("scripts/demo.rhai")).unwrap();
//! db.finish_run(run, fitup::db::RunStatus::Ok, "done").unwrap();
//! assert_eq!(db.runs().unwrap()[0].status, "ok");
//! assert!(db.paths(&PathQuery::default()).unwrap().is_empty());
//! ```

mod backend;
pub mod diff;
mod error;
mod functions;
mod held;
#[cfg(feature = "postgres")]
mod pg;
mod query;
pub mod recording;
mod records;
mod schema;
mod skill_log;
pub use skill_log::{SkillEvent, SkillLogEntry};

pub use backend::{Dialect, SqlValue};
pub use error::{
    AskedLimit, DbError, DriverError, DriverErrorKind, FolderError, ForeignFile, JailRefusal,
    OpenCause, ReadOnlyCause, Refusal,
};
pub use query::{QueryLimits, RunQueryBudget, RUN_QUERY_BUDGET, SQLITE_HEAP_LIMIT};
pub use records::*;
pub use schema::LATEST as SCHEMA_VERSION;

use crate::fsutil::IoCause;
use backend::{Kind, Raw, SqliteTx, Tx};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

/// The database file name at a project's root when nothing else is said.
pub const DEFAULT_FILE: &str = "fitup.db";

/// The environment variable that names the database (a file or a `postgres://` URL).
pub const ENV_VAR: &str = "FITUP_DB";

/// How long SQLite waits for another writer before reporting busy (then fitup retries).
const BUSY_TIMEOUT: Duration = Duration::from_secs(5);

/// How many times a busy transaction is tried before giving up.
const TRIES: u32 = 12;

/// How long opening a PostgreSQL database may take (TCP connect, TLS negotiation,
/// authentication) unless the URL says `connect_timeout=N` (seconds).
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

/// Where the data lives. `Display` and `Debug` never show a password.
#[derive(Clone, PartialEq, Eq)]
pub enum Target {
    /// A SQLite file.
    Sqlite(PathBuf),
    /// A PostgreSQL connection URL (`postgres://user@host:port/db`).
    Postgres(String),
}

impl Target {
    /// A database named by the user: a `postgres://`/`postgresql://` URL, or a file
    /// (relative paths are taken from `root`, the project folder).
    pub fn parse(text: &str, root: &Path) -> Target {
        if text.starts_with("postgres://") || text.starts_with("postgresql://") {
            Target::Postgres(text.to_string())
        } else {
            let p = Path::new(text);
            Target::Sqlite(if p.is_absolute() {
                p.to_path_buf()
            } else {
                root.join(p)
            })
        }
    }

    /// The database of a project: `explicit` (the `--db` flag) if given, else the
    /// `FITUP_DB` variable, else `fitup.db` at `root`.
    pub fn resolve(explicit: Option<&str>, root: &Path) -> Target {
        match explicit
            .map(str::to_string)
            .or_else(|| std::env::var(ENV_VAR).ok().filter(|s| !s.trim().is_empty()))
        {
            Some(t) => Target::parse(&t, root),
            None => Target::Sqlite(root.join(DEFAULT_FILE)),
        }
    }
}

impl std::fmt::Display for Target {
    /// The file path, or the URL without its password ([`redact_url`]).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Sqlite(p) => write!(f, "{}", p.display()),
            Target::Postgres(url) => write!(f, "{}", redact_url(url)),
        }
    }
}

impl std::fmt::Debug for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Sqlite(p) => f.debug_tuple("Sqlite").field(p).finish(),
            Target::Postgres(url) => f.debug_tuple("Postgres").field(&redact_url(url)).finish(),
        }
    }
}

impl Target {
    /// `message` with every credential of this target's URL replaced by `***` (for
    /// driver messages, which might quote the connection string).
    pub fn scrub(&self, message: &str) -> String {
        let Target::Postgres(url) = self else {
            return message.to_string();
        };
        let mut out = message.replace(url.as_str(), &redact_url(url));
        for secret in url_secrets(url) {
            // A one- to three-character password would garble the message; such a
            // password is not worth keeping secret anyway, but it is still not quoted
            // by fitup's own messages (the URL is always shown redacted).
            if secret.chars().count() >= 4 {
                out = out.replace(&secret, "***");
            }
        }
        out
    }
}

pub use crate::diagnostics::redact_url;

/// The credentials written in a URL (the userinfo password and `…pass…=` values), as
/// written and percent-decoded.
fn url_secrets(url: &str) -> Vec<String> {
    let mut out = Vec::new();
    let Some(scheme_end) = url.find("://").map(|s| s + 3) else {
        return out;
    };
    let (main, query) = match url[scheme_end..].find('?') {
        Some(q) => url.split_at(scheme_end + q),
        None => (url, ""),
    };
    if let Some(at) = main[scheme_end..].rfind('@') {
        if let Some((_, pw)) = main[scheme_end..scheme_end + at].split_once(':') {
            out.push(pw.to_string());
        }
    }
    for kv in query.trim_start_matches('?').split('&') {
        if let Some((k, v)) = kv.split_once('=') {
            if k.to_ascii_lowercase().contains("pass") {
                out.push(v.to_string());
            }
        }
    }
    let decoded: Vec<String> = out.iter().map(|s| percent_decode(s)).collect();
    out.extend(decoded);
    out.retain(|s| !s.is_empty());
    out
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).copied().and_then(hex),
            b.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, ..) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

enum Conn {
    Sqlite(rusqlite::Connection),
    #[cfg(feature = "postgres")]
    Postgres(Box<postgres::Client>),
}

/// An open results database (SQLite file or PostgreSQL server), migrated to
/// [`SCHEMA_VERSION`].
pub struct Database {
    /// The read-only, jailed connection of [`Database::query_with`] (SQLite; opened
    /// on the first query). Declared first, so it closes before the writing
    /// connection, whose close (the last one) checkpoints and removes the `-wal`.
    reader: Option<query::SqliteReader>,
    conn: Conn,
    target: Target,
    /// The SQLite file's folder, held open for as long as the connections (declared
    /// after them: dropped after them); SQLite opens the file, its `-wal` and `-shm`
    /// through it ([`held`]).
    held: Option<held::HeldFile>,
}

impl std::fmt::Debug for Database {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Database({})", self.target)
    }
}

impl Database {
    /// Opens (creating if needed) the database and brings its schema up to date.
    ///
    /// Fails with [`DbError::NewerSchema`] when a newer fitup wrote it.
    pub fn open(target: &Target) -> Result<Self, DbError> {
        Self::open_at_version(target, schema::LATEST)
    }

    /// Opens the database and migrates it only up to `version` (at most
    /// [`SCHEMA_VERSION`]): for migration tests and tools that must write an older
    /// schema. Prefer [`Database::open`].
    pub fn open_at_version(target: &Target, version: u32) -> Result<Self, DbError> {
        Self::open_with(target, version, None)
    }

    /// [`Database::open`] for a database a script names: a SQLite file inside
    /// `project` is reached from the project's held root folder one folder at a time
    /// without following a symbolic link, and SQLite opens it (and its `-wal`, `-shm`)
    /// through that folder handle, so a folder swapped for a link to an outside folder
    /// after the script's path was checked is never followed (a link met is refused).
    pub fn open_in(project: &crate::project::Project, target: &Target) -> Result<Self, DbError> {
        Self::open_with(target, schema::LATEST, Some(project))
    }

    fn open_with(
        target: &Target,
        version: u32,
        project: Option<&crate::project::Project>,
    ) -> Result<Self, DbError> {
        let name = target.clone();
        let open_err = |cause: OpenCause| DbError::Open {
            target: name.clone(),
            cause,
        };
        let (conn, held_file) = match target {
            Target::Sqlite(path) => {
                let held = hold_folder(path, project).map_err(|e| open_err(e.into()))?;
                let (dir, file) = (held.dir(), held.name());
                let kind = dir
                    .stat(file)
                    .map_err(|e| open_err(IoCause::from(e).into()))?;
                let existing = match kind {
                    None => false,
                    Some(crate::fsutil::Kind::File(len)) => len > 0,
                    Some(crate::fsutil::Kind::Dir) => return Err(open_err(OpenCause::IsFolder)),
                    Some(crate::fsutil::Kind::Symlink) => return Err(open_err(OpenCause::Symlink)),
                    Some(crate::fsutil::Kind::Special(what)) => {
                        return Err(open_err(OpenCause::Special(what)))
                    }
                };
                let read_only = || dir.open_file_rw(file).is_err();
                // A file on read-only media (or without write permission) opens, or fails
                // to open its WAL index, with SQLite's generic "unable to open": say
                // read-only when that is the cause.
                let fail = |e: rusqlite::Error| {
                    if existing && read_only() {
                        DbError::ReadOnly {
                            target: name.clone(),
                            cause: ReadOnlyCause::FileNotWritable {
                                driver: Some(Raw::from(e)),
                            },
                        }
                    } else {
                        open_err(OpenCause::Driver(Raw::from(e)))
                    }
                };
                let foreign = |cause: ForeignFile| DbError::Foreign {
                    target: name.clone(),
                    cause,
                };
                // An existing file must already be SQLite before SQLite may touch it
                // (opening in WAL mode rewrites its header).
                if existing {
                    let mut head = Vec::with_capacity(16);
                    dir.open_file(file)
                        .and_then(|f| {
                            use std::io::Read;
                            f.take(16).read_to_end(&mut head)
                        })
                        .map_err(|e| open_err(IoCause::from(e).into()))?;
                    if !head.starts_with(crate::project::SQLITE_MAGIC) {
                        return Err(foreign(ForeignFile::NotSqlite));
                    }
                }
                let (sqlite_name, vfs) = held.sqlite_name();
                // No SQLITE_OPEN_URI: a file name is a file name, never `file:…?mode=rwc`.
                let flags = rusqlite::OpenFlags::SQLITE_OPEN_READ_WRITE
                    | rusqlite::OpenFlags::SQLITE_OPEN_CREATE
                    | rusqlite::OpenFlags::SQLITE_OPEN_NO_MUTEX;
                let c = match vfs {
                    Some(vfs) => {
                        rusqlite::Connection::open_with_flags_and_vfs(&sqlite_name, flags, vfs)
                    }
                    None => rusqlite::Connection::open_with_flags(&sqlite_name, flags),
                }
                .map_err(fail)?;
                c.busy_timeout(BUSY_TIMEOUT).map_err(fail)?;
                if existing && !retry_locked(|| is_fitup_sqlite(&c)).map_err(fail)? {
                    return Err(foreign(ForeignFile::OtherProgram));
                }
                // A file that is not SQLite fails here with "file is not a database".
                let mode: String =
                    retry_locked(|| c.query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0)))
                        .map_err(fail)?;
                if mode != "wal" {
                    // Read-only media cannot switch; reads still work.
                    if read_only() {
                        return Err(DbError::ReadOnly {
                            target: name.clone(),
                            cause: ReadOnlyCause::FileNotWritable { driver: None },
                        });
                    }
                }
                // In WAL mode NORMAL stays consistent after any crash (a power cut may lose
                // the last commits, never half of one; commits do not wait for fsync); a
                // 16 MB page cache holds a large result. The WAL is copied back into the
                // file (a checkpoint, with fsync) once it passes 4,096 pages (16 MB)
                // instead of SQLite's 1,000, so a run storing a few large results does
                // not pay for one in the middle of a commit; the last connection to close
                // checkpoints the rest.
                retry_locked(|| {
                    c.execute_batch(
                        "PRAGMA foreign_keys=ON; PRAGMA synchronous=NORMAL; PRAGMA cache_size=-16000; PRAGMA wal_autocheckpoint=4096;",
                    )
                })
                .map_err(fail)?;
                (Conn::Sqlite(c), Some(held))
            }
            #[cfg(feature = "postgres")]
            Target::Postgres(url) => (
                Conn::Postgres(Box::new(pg::connect(url).map_err(|e| {
                    open_err(OpenCause::Driver(Raw::other(target.scrub(&e.to_string()))))
                })?)),
                None,
            ),
            #[cfg(not(feature = "postgres"))]
            Target::Postgres(_) => return Err(open_err(OpenCause::NoPostgres)),
        };
        let mut db = Database {
            conn,
            target: target.clone(),
            reader: None,
            held: held_file,
        };
        let target_version = version.min(schema::LATEST);
        let now = now_utc();
        match db.transaction("the schema", |tx| schema::migrate(tx, target_version, &now))? {
            schema::Migrated::Ok => Ok(db),
            schema::Migrated::Newer(found) => Err(DbError::NewerSchema {
                target: db.target.clone(),
                found,
                supported: schema::LATEST,
                ours: env!("CARGO_PKG_VERSION"),
            }),
        }
    }

    /// Where the data lives.
    pub fn target(&self) -> &Target {
        &self.target
    }

    /// Which back end.
    pub fn dialect(&self) -> Dialect {
        match self.conn {
            Conn::Sqlite(_) => Dialect::Sqlite,
            #[cfg(feature = "postgres")]
            Conn::Postgres(_) => Dialect::Postgres,
        }
    }

    /// The schema version of the open database.
    pub fn schema_version(&mut self) -> Result<u32, DbError> {
        self.read("the schema version", |tx| schema::current_version(tx))
    }

    fn error(&self, what: &str, e: Raw, tries: u32) -> DbError {
        let target = self.target.clone();
        match e.kind {
            Kind::Busy => DbError::Busy {
                target,
                tries,
                cause: e,
            },
            Kind::ReadOnly => DbError::ReadOnly {
                target,
                cause: ReadOnlyCause::Driver(e),
            },
            Kind::Full => DbError::DiskFull { target, cause: e },
            Kind::WriteRefused => DbError::WriteRefused {
                cause: Refusal::Driver(e),
            },
            Kind::Other => DbError::Sql {
                target,
                during: Some(what.to_string()),
                cause: e,
            },
        }
    }

    /// Runs `f` in one transaction, committed when it returns `Ok`; retried (with the
    /// whole closure) while other writers hold the database.
    pub(crate) fn transaction<R>(
        &mut self,
        what: &str,
        f: impl FnMut(&mut dyn Tx) -> Result<R, Raw>,
    ) -> Result<R, DbError> {
        self.transact(what, rusqlite::TransactionBehavior::Immediate, f)
    }

    /// As [`Database::transaction`] for reads: SQLite takes no write lock, so readers
    /// never wait for (or hold up) writers.
    pub(crate) fn read<R>(
        &mut self,
        what: &str,
        f: impl FnMut(&mut dyn Tx) -> Result<R, Raw>,
    ) -> Result<R, DbError> {
        self.transact(what, rusqlite::TransactionBehavior::Deferred, f)
    }

    fn transact<R>(
        &mut self,
        what: &str,
        behavior: rusqlite::TransactionBehavior,
        mut f: impl FnMut(&mut dyn Tx) -> Result<R, Raw>,
    ) -> Result<R, DbError> {
        let mut attempt = 0;
        loop {
            attempt += 1;
            let result: Result<R, Raw> = match &mut self.conn {
                Conn::Sqlite(c) => (|| {
                    // Writes are IMMEDIATE: they take the write lock up front, so two
                    // writers never deadlock upgrading read locks.
                    let tx = c.transaction_with_behavior(behavior)?;
                    let mut t = SqliteTx(tx);
                    let r = f(&mut t)?;
                    t.0.commit()?;
                    Ok(r)
                })(),
                #[cfg(feature = "postgres")]
                Conn::Postgres(c) => (|| {
                    let tx = c.transaction()?;
                    let mut t = pg::PgTx(tx);
                    let r = f(&mut t)?;
                    t.0.commit()?;
                    Ok(r)
                })(),
            };
            match result {
                Ok(r) => return Ok(r),
                Err(e) if e.kind == Kind::Busy && attempt < TRIES => {
                    // Back off a little longer each time, staggered by process.
                    let jitter = u64::from(std::process::id() % 7);
                    std::thread::sleep(Duration::from_millis(5 * u64::from(attempt) + jitter));
                }
                Err(e) => return Err(self.error(what, e, attempt)),
            }
        }
    }

    /// Runs one read-only SQL query within [`QueryLimits::DEFAULT`]: see
    /// [`Database::query_with`].
    pub fn query(&mut self, sql: &str, params: &[SqlValue]) -> Result<QueryResult, DbError> {
        self.query_with(sql, params, QueryLimits::DEFAULT, None)
    }

    /// Runs one read-only SQL query (parameters are `?1`… in SQLite and `$1`… in
    /// PostgreSQL) and returns its columns and rows: what scripts' `db.query` runs.
    ///
    /// It reads this database only. SQLite: on a separate read-only connection whose
    /// authorizer refuses ATTACH/DETACH, writes, transactions, pragmas that set
    /// anything and file functions ([`DbError::WriteRefused`]). PostgreSQL: in a
    /// `READ ONLY` transaction, plain queries only, no server-file or session
    /// functions. It stops after `limits.time` ([`DbError::QueryTimeout`]), refuses a
    /// result past `limits.max_rows` or `limits.max_bytes` before holding more of it
    /// ([`DbError::QueryTooLarge`]), and stops when `cancel` is set
    /// ([`DbError::QueryCancelled`]). Limits beyond [`QueryLimits::MAX`] are refused.
    pub fn query_with(
        &mut self,
        sql: &str,
        params: &[SqlValue],
        limits: QueryLimits,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<QueryResult, DbError> {
        let limits = limits.checked()?;
        let target = self.target.clone();
        let result = match &mut self.conn {
            #[cfg(feature = "postgres")]
            Conn::Postgres(c) => pg::pg_query(c, sql, params, limits, cancel),
            Conn::Sqlite(_) => {
                let reader = match (&mut self.reader, &self.held) {
                    (Some(r), _) => r,
                    (slot @ None, Some(held)) => {
                        let opened =
                            query::SqliteReader::open(held, BUSY_TIMEOUT).map_err(|e| {
                                DbError::Open {
                                    target: target.clone(),
                                    cause: OpenCause::QueryConnection(e),
                                }
                            })?;
                        slot.insert(opened)
                    }
                    (None, None) => {
                        return Err(DbError::Open {
                            target,
                            cause: OpenCause::NoFile,
                        })
                    }
                };
                reader.query(sql, params, limits, cancel)
            }
        };
        result.map_err(|stop| match stop {
            query::Stop::Refused(why) => DbError::WriteRefused {
                cause: Refusal::Jail(why),
            },
            query::Stop::Timeout => DbError::QueryTimeout {
                target,
                limit: limits.time,
            },
            query::Stop::Cancelled => DbError::QueryCancelled { target },
            query::Stop::TooLarge => DbError::QueryTooLarge {
                target,
                max_rows: limits.max_rows,
                max_bytes: limits.max_bytes,
            },
            query::Stop::Sql(e) => match e.kind {
                Kind::WriteRefused | Kind::ReadOnly => DbError::WriteRefused {
                    cause: Refusal::Driver(e),
                },
                _ => DbError::Sql {
                    target,
                    during: None,
                    cause: e,
                },
            },
        })
    }
}

/// Whether an open SQLite database is fitup's (or empty): it has no tables, or it has
/// fitup's `schema_version` table with its `fitup_version` column. Reads only.
/// Runs `f` again while SQLite answers "database is locked" or "busy", for up to
/// [`BUSY_TIMEOUT`] with a growing, per-process staggered pause. Opening needs it:
/// SQLite answers the switch to WAL (and a first read of a file another process is
/// creating) at once, without waiting in its busy handler, so four processes opening a
/// new database together lost one run record to "database is locked".
fn retry_locked<T>(mut f: impl FnMut() -> rusqlite::Result<T>) -> rusqlite::Result<T> {
    let until = crate::math::Deadline::after(BUSY_TIMEOUT);
    let jitter = u64::from(std::process::id() % 7);
    let mut attempt = 0u64;
    loop {
        match f() {
            Err(rusqlite::Error::SqliteFailure(e, _))
                if matches!(
                    e.code,
                    rusqlite::ErrorCode::DatabaseBusy | rusqlite::ErrorCode::DatabaseLocked
                ) && !until.passed() =>
            {
                attempt += 1;
                std::thread::sleep(Duration::from_millis((5 * attempt).min(100) + jitter));
            }
            r => return r,
        }
    }
}

fn is_fitup_sqlite(c: &rusqlite::Connection) -> rusqlite::Result<bool> {
    let tables: i64 = c.query_row(
        "SELECT count(*) FROM sqlite_master WHERE type IN ('table', 'view', 'index', 'trigger')",
        [],
        |r| r.get(0),
    )?;
    if tables == 0 {
        return Ok(true);
    }
    Ok(
        c.prepare("SELECT version, fitup_version FROM schema_version LIMIT 0")
            .is_ok(),
    )
}

/// The folder of the SQLite file `path` held open, with the file's name: walked from
/// `project`'s held root without following a link when the path lies inside it (a
/// file a script named, its path checked by [`crate::project::Project::resolve`]),
/// else opened by the path the caller named (links in it followed: `--db`,
/// `FITUP_DB`, a library caller).
fn hold_folder(
    path: &Path,
    project: Option<&crate::project::Project>,
) -> Result<held::HeldFile, FolderError> {
    let (Some(name), Some(parent)) = (path.file_name(), path.parent()) else {
        return Err(FolderError::NotAFileName);
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    let missing = |source: std::io::Error| {
        let folder = parent.to_path_buf();
        if source.kind() == std::io::ErrorKind::NotFound {
            FolderError::Missing(folder)
        } else {
            FolderError::Unreadable {
                folder,
                source: source.into(),
            }
        }
    };
    if let Some(project) = project.filter(|p| path.starts_with(p.root())) {
        let dir = project.folder(parent, false).map_err(missing)?;
        return Ok(held::HeldFile::new(dir, name));
    }
    // Named by the caller: a link at the file's own name is followed once, here.
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        if let Ok(real) = path.canonicalize() {
            if let (Some(n), Some(d)) = (real.file_name(), real.parent()) {
                let dir = crate::fsutil::Dir::open(d).map_err(missing)?;
                return Ok(held::HeldFile::new(dir, n));
            }
        }
    }
    let dir = crate::fsutil::Dir::open(parent).map_err(missing)?;
    Ok(held::HeldFile::new(dir, name))
}

/// The columns and rows of a [`Database::query`].
#[derive(Debug, Clone, PartialEq)]
pub struct QueryResult {
    /// Column names, in order.
    pub columns: Vec<String>,
    /// Rows, each with one value per column.
    pub rows: Vec<Vec<SqlValue>>,
}

/// The current time (UTC) as ISO 8601 with milliseconds, `2026-11-30T17:43:21.123Z`:
/// how every `*_at` column is written (text that sorts in time order).
pub fn now_utc() -> String {
    let d = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    format_utc(d.as_secs() as i64, d.subsec_millis())
}

/// Seconds since 1970 (UTC) and milliseconds as ISO 8601.
fn format_utc(secs: i64, millis: u32) -> String {
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}.{millis:03}Z",
        rem / 3600,
        (rem % 3600) / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_format_matches_known_dates() {
        assert_eq!(format_utc(0, 0), "1970-01-01T00:00:00.000Z");
        assert_eq!(format_utc(951_782_400, 5), "2000-02-29T00:00:00.005Z");
        assert_eq!(format_utc(1_796_059_401, 123), "2026-11-30T17:23:21.123Z");
    }

    #[test]
    fn targets_parse_urls_and_files() {
        let root = Path::new("/p");
        assert_eq!(
            Target::parse("postgres://u:pw@h:5/d", root).to_string(),
            "postgres://u@h:5/d"
        );
        assert_eq!(
            Target::parse("x.db", root),
            Target::Sqlite(PathBuf::from("/p/x.db"))
        );
        assert_eq!(
            Target::resolve(Some("/abs.db"), root),
            Target::Sqlite(PathBuf::from("/abs.db"))
        );
    }

    #[test]
    #[cfg(not(feature = "postgres"))]
    fn a_postgres_target_names_the_feature_that_adds_it() {
        let e = Database::open(&Target::Postgres("postgres://u:secret@h/d".into())).unwrap_err();
        let t = e.to_string();
        assert!(
            t.contains("--features postgres") && !t.contains("secret"),
            "{t}"
        );
    }

    #[test]
    fn other_files_are_never_turned_into_databases() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // A CSV named x.db.
        let csv = d.join("x.db");
        std::fs::write(&csv, b"a,b\n1,2\n").unwrap();
        let e = Database::open(&Target::Sqlite(csv.clone())).unwrap_err();
        assert!(matches!(e, DbError::Foreign { .. }), "{e}");
        assert!(e.to_string().contains("not a SQLite file"), "{e}");
        assert_eq!(std::fs::read(&csv).unwrap(), b"a,b\n1,2\n");
        // Another program's SQLite database.
        let other = d.join("other.sqlite");
        {
            let c = rusqlite::Connection::open(&other).unwrap();
            c.execute_batch("CREATE TABLE notes (t TEXT); INSERT INTO notes VALUES ('mine');")
                .unwrap();
        }
        let before = std::fs::read(&other).unwrap();
        let e = Database::open(&Target::Sqlite(other.clone())).unwrap_err();
        assert!(e.to_string().contains("another program"), "{e}");
        assert_eq!(std::fs::read(&other).unwrap(), before);
        assert!(!d.join("other.sqlite-wal").exists());
        // An empty file, a new file and fitup's own database open.
        let empty = d.join("empty.db");
        std::fs::write(&empty, b"").unwrap();
        Database::open(&Target::Sqlite(empty.clone())).unwrap();
        drop(Database::open(&Target::Sqlite(d.join("new.db"))).unwrap());
        Database::open(&Target::Sqlite(d.join("new.db"))).unwrap();
    }

    /// A script's database is opened through the project's held folders: a folder or
    /// the file itself turned into a link to the outside after the path was checked is
    /// refused, nothing outside is opened or made; a database opened before the link
    /// was put in place keeps working in its own folder.
    #[cfg(unix)]
    #[test]
    fn a_scripts_database_never_follows_a_link_put_after_its_check() {
        let dir = tempfile::tempdir().unwrap();
        let outside = tempfile::tempdir().unwrap();
        let project = crate::project::Project::new(dir.path()).unwrap();
        let root = project.root().to_path_buf();
        std::fs::create_dir(root.join("data")).unwrap();
        let path = project.resolve("data/x.db").unwrap();
        let mut db = Database::open_in(&project, &Target::Sqlite(path.clone())).unwrap();
        // The folder swapped for a link after the check (and after the open).
        std::fs::rename(root.join("data"), root.join("away")).unwrap();
        std::os::unix::fs::symlink(outside.path(), root.join("data")).unwrap();
        let e = Database::open_in(&project, &Target::Sqlite(path.clone())).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        // The open connection (and its query connection) still use the held folder.
        db.start_run(&NewRun::script("s.rhai")).unwrap();
        db.query("SELECT count(*) FROM runs", &[]).unwrap();
        drop(db);
        let names = |d: &Path| -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert!(
            names(outside.path()).is_empty(),
            "{:?}",
            names(outside.path())
        );
        assert_eq!(names(&root.join("away")), ["x.db"]);
        // The file itself a link to an outside database.
        std::fs::remove_file(root.join("data")).unwrap();
        std::fs::rename(root.join("away"), root.join("data")).unwrap();
        std::fs::copy(root.join("data/x.db"), outside.path().join("y.db")).unwrap();
        let before = std::fs::read(outside.path().join("y.db")).unwrap();
        std::fs::remove_file(root.join("data/x.db")).unwrap();
        std::os::unix::fs::symlink(outside.path().join("y.db"), root.join("data/x.db")).unwrap();
        let e = Database::open_in(&project, &Target::Sqlite(path)).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read(outside.path().join("y.db")).unwrap(), before);
        assert_eq!(names(outside.path()), ["y.db"]);
    }

    #[test]
    fn credentials_never_show() {
        let t = Target::Postgres(
            "postgres://u:s3cr%40t@h:5/d?sslmode=disable&password=other1&application_name=a@b"
                .into(),
        );
        for shown in [t.to_string(), format!("{t:?}")] {
            assert!(
                !shown.contains("s3cr") && !shown.contains("other1"),
                "{shown}"
            );
            assert!(shown.contains("u@h:5/d"), "{shown}");
            assert!(shown.contains("password=***"), "{shown}");
            assert!(shown.contains("application_name=a@b"), "{shown}");
        }
        let scrubbed = t.scrub("bad password s3cr@t / s3cr%40t / other1");
        assert_eq!(scrubbed, "bad password *** / *** / ***");
        assert_eq!(
            redact_url("postgres://u:p@ss@h/d"),
            "postgres://u@h/d",
            "a password with an @"
        );
        assert_eq!(redact_url("postgres://h/d"), "postgres://h/d");
        assert_eq!(redact_url("postgres://u@h/d"), "postgres://u@h/d");
    }

    #[test]
    fn a_silent_server_fails_within_the_connect_timeout() {
        // Accepts (the kernel's backlog) and never answers.
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let url = format!("postgres://u:verysecret@127.0.0.1:{port}/d?connect_timeout=1");
        let start = std::time::Instant::now();
        let e = Database::open(&Target::Postgres(url)).unwrap_err();
        let shown = e.to_string();
        assert!(start.elapsed() < Duration::from_secs(5), "{shown}");
        assert!(
            shown.contains("no answer from the server within 1 s"),
            "{shown}"
        );
        assert!(!shown.contains("verysecret") && !format!("{e:?}").contains("verysecret"));
        drop(listener);
    }
}
