//! Scripts' read-only queries ([`Database::query_with`](super::Database::query_with)):
//! jailed to the results database, bounded in time, rows and bytes, and cancellable.
//!
//! SQLite: a separate connection opened `SQLITE_OPEN_READ_ONLY` (it cannot write any
//! file, nor create one), with an authorizer that allows reading tables and calling
//! ordinary functions only (no `ATTACH`, no `PRAGMA` that sets anything, no
//! transactions, no file functions), no attached databases at all, values of at most
//! 16 MiB, and a progress handler that stops the statement when its time is up or the
//! run is cancelled. PostgreSQL: one `READ ONLY` transaction per query with a
//! `statement_timeout`, statements that start with `SELECT`/`WITH`/`VALUES`/`TABLE`
//! only, no server-file or session functions, rows fetched in batches so the caps hold
//! before the rows are in memory, and a watcher thread that cancels the statement on
//! the server when the run is cancelled.

use super::backend::{self, Raw, SqlValue};
use super::{AskedLimit, DbError, JailRefusal, QueryResult};
use crate::math::Deadline;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The bounds of one read-only query: wall time and the size of its result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QueryLimits {
    /// Wall time the statement may run (SQLite: until the last row is read;
    /// PostgreSQL: `statement_timeout`, and the whole fetch).
    pub time: Duration,
    /// Rows the result may hold.
    pub max_rows: usize,
    /// Bytes the result may take in memory (values, text and row overhead as fitup
    /// stores them).
    pub max_bytes: usize,
}

impl QueryLimits {
    /// What a query gets unless the script asks for more: 10 s, 100,000 rows, 64 MiB.
    pub const DEFAULT: QueryLimits = QueryLimits {
        time: Duration::from_secs(10),
        max_rows: 100_000,
        max_bytes: 64 << 20,
    };

    /// The most a script may ask for: 600 s, 1,000,000 rows, 256 MiB. What these
    /// maxima cost is stated (docs/database.md, "Result caps"): the rows held while
    /// they are read (at most `max_bytes`), then the script's values (≈ 500 bytes a
    /// row; a script holds at most 2,000,000 values and 16 MiB of text, which a
    /// script's query is refused past before any is built): under 1 GB at the maxima.
    pub const MAX: QueryLimits = QueryLimits {
        time: Duration::from_secs(600),
        max_rows: 1_000_000,
        max_bytes: 256 << 20,
    };

    /// These limits if each is positive and within [`QueryLimits::MAX`], else
    /// [`DbError::QueryLimit`] naming the first one that is not.
    pub fn checked(self) -> Result<Self, DbError> {
        let bad = |asked| Err(DbError::QueryLimit { asked });
        if self.time.is_zero() || self.time > Self::MAX.time {
            return bad(AskedLimit::Seconds(self.time.as_secs_f64()));
        }
        if self.max_rows == 0 || self.max_rows > Self::MAX.max_rows {
            return bad(AskedLimit::Rows(self.max_rows));
        }
        if self.max_bytes == 0 || self.max_bytes > Self::MAX.max_bytes {
            return bad(AskedLimit::Bytes(self.max_bytes));
        }
        Ok(self)
    }
}

impl Default for QueryLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The time all of a run's queries may take together, by default: a script that calls
/// an endless query a hundred times stops after this, not after a hundred time limits.
pub const RUN_QUERY_BUDGET: Duration = Duration::from_secs(60);

/// One time budget for all the queries of a run (a script's `db.query` calls): each
/// query runs within its own limit and within what is left of the budget; the budget is
/// [`RUN_QUERY_BUDGET`], or the largest `time` a query of the run asked for when that
/// is more (so [`QueryLimits::MAX`] stays reachable by one query).
#[derive(Debug)]
pub struct RunQueryBudget {
    inner: Mutex<(Duration, Duration)>,
}

impl Default for RunQueryBudget {
    fn default() -> Self {
        RunQueryBudget {
            inner: Mutex::new((RUN_QUERY_BUDGET, Duration::ZERO)),
        }
    }
}

impl RunQueryBudget {
    /// Runs `query` with `limits` cut to what is left of the budget; a query stopped
    /// by the budget (not by its own limit) is [`DbError::QueryBudget`], and so is any
    /// query once the budget is used up.
    pub fn run<T>(
        &self,
        limits: QueryLimits,
        query: impl FnOnce(QueryLimits) -> Result<T, DbError>,
    ) -> Result<T, DbError> {
        let (budget, left) = {
            let mut g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
            g.0 = g.0.max(limits.time);
            (g.0, g.0.saturating_sub(g.1))
        };
        if left.is_zero() {
            return Err(DbError::QueryBudget { budget });
        }
        let cut = left < limits.time;
        let start = Instant::now();
        let result = query(QueryLimits {
            time: limits.time.min(left),
            ..limits
        });
        let spent = start.elapsed();
        let mut g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        g.1 += spent;
        match result {
            Err(DbError::QueryTimeout { .. }) if cut => Err(DbError::QueryBudget { budget }),
            other => other,
        }
    }
}

/// `1234567` → `1,234,567`.
pub(crate) fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `64 MiB`, `1.5 KiB`, `12 bytes`.
pub(crate) fn bytes(n: usize) -> String {
    const MIB: usize = 1 << 20;
    const KIB: usize = 1 << 10;
    let unit = |u: usize, name: &str| {
        if n.is_multiple_of(u) {
            format!("{} {name}", n / u)
        } else {
            format!("{:.1} {name}", n as f64 / u as f64)
        }
    };
    if n >= MIB {
        unit(MIB, "MiB")
    } else if n >= KIB {
        unit(KIB, "KiB")
    } else {
        format!("{n} bytes")
    }
}

/// Why a query stopped before it returned its rows.
#[derive(Debug)]
pub(crate) enum Stop {
    /// The jail refused the statement (what and why).
    Refused(JailRefusal),
    /// The time limit passed.
    Timeout,
    /// The run was cancelled.
    Cancelled,
    /// The result passed the row or byte cap.
    TooLarge,
    /// Any other back-end error.
    Sql(Raw),
}

impl From<Raw> for Stop {
    fn from(e: Raw) -> Self {
        Stop::Sql(e)
    }
}

/// Why the progress handler or the watcher stopped a statement.
pub(super) const WHY_NONE: u8 = 0;
pub(super) const WHY_TIME: u8 = 1;
pub(super) const WHY_CANCEL: u8 = 2;

/// Collects rows under the caps: counts rows and an estimate of the memory they take.
pub(super) struct Collector {
    limits: QueryLimits,
    pub(super) rows: Vec<Vec<SqlValue>>,
    bytes: usize,
}

impl Collector {
    pub(super) fn new(limits: QueryLimits, columns: &[String]) -> Self {
        Collector {
            limits,
            rows: Vec::new(),
            bytes: columns.iter().map(|c| c.len() + 24).sum(),
        }
    }

    pub(super) fn push(&mut self, row: Vec<SqlValue>) -> Result<(), Stop> {
        // What the row costs as stored: the Vec, every value, the text's bytes.
        let size = 24
            + row
                .iter()
                .map(|v| {
                    std::mem::size_of::<SqlValue>()
                        + match v {
                            SqlValue::Text(s) => s.len(),
                            _ => 0,
                        }
                })
                .sum::<usize>();
        self.bytes += size;
        if self.rows.len() >= self.limits.max_rows || self.bytes > self.limits.max_bytes {
            return Err(Stop::TooLarge);
        }
        self.rows.push(row);
        Ok(())
    }
}

/// How many SQLite virtual-machine steps pass between two looks at the cancel flag
/// and the clock by the progress handler (a few microseconds of work). The clock is
/// also watched by time, by a watchdog thread that interrupts the statement at its
/// deadline however long one step takes ([`SqliteReader::query`]).
const PROGRESS_STEPS: i32 = 1_000;

/// The most memory SQLite itself may take in a fitup process (page caches, sorts,
/// temporary tables and indices of every connection), bytes: a query's sort or
/// temporary table is kept in memory (never in the system's temporary folder,
/// outside the project) and stops with "out of memory" past this.
pub const SQLITE_HEAP_LIMIT: i64 = 512 << 20;

/// Introspection pragmas a query may use, with or without an argument (they read the
/// schema and never change anything).
const READ_PRAGMAS: &[&str] = &[
    "table_info",
    "table_xinfo",
    "table_list",
    "index_list",
    "index_info",
    "index_xinfo",
    "foreign_key_list",
    "foreign_key_check",
    "collation_list",
    "function_list",
    "module_list",
    "pragma_list",
    "database_list",
    "integrity_check",
    "quick_check",
];

/// Settings of the database file a query may read, but only without a value
/// (`PRAGMA user_version` reads; `PRAGMA user_version = 5` writes and is refused).
/// Per-connection settings (`foreign_keys`, `synchronous`, …) are not among them:
/// the query connection's own values would say nothing about fitup's writes.
const READ_SETTINGS: &[&str] = &[
    "application_id",
    "auto_vacuum",
    "encoding",
    "freelist_count",
    "page_count",
    "page_size",
    "schema_version",
    "user_version",
    "data_version",
];

/// SQL functions refused although the statement only reads: they reach files or
/// load code (most are absent from fitup's SQLite; refused should one ever appear).
const DENIED_FUNCTIONS: &[&str] = &[
    "load_extension",
    "readfile",
    "writefile",
    "edit",
    "fts3_tokenizer",
    "lsmode",
    "sqlar_compress",
    "sqlar_uncompress",
    "zipfile",
];

/// The authorizer's verdict on one action of a statement being prepared: `None`
/// allows it, `Some(why)` refuses it.
pub(crate) fn sqlite_refusal(action: &rusqlite::hooks::AuthAction<'_>) -> Option<JailRefusal> {
    use rusqlite::hooks::AuthAction as A;
    match action {
        A::Select | A::Read { .. } | A::Recursive => None,
        A::Function { function_name } => {
            let f = function_name.to_ascii_lowercase();
            DENIED_FUNCTIONS
                .contains(&f.as_str())
                .then(|| JailRefusal::Function {
                    name: function_name.to_string(),
                })
        }
        A::Pragma {
            pragma_name,
            pragma_value,
        } => {
            let p = pragma_name.to_ascii_lowercase();
            if READ_PRAGMAS.contains(&p.as_str())
                || (pragma_value.is_none() && READ_SETTINGS.contains(&p.as_str()))
            {
                None
            } else if pragma_value.is_some() {
                Some(JailRefusal::PragmaSet {
                    name: pragma_name.to_string(),
                })
            } else {
                Some(JailRefusal::Pragma {
                    name: pragma_name.to_string(),
                })
            }
        }
        A::Attach { .. } => Some(JailRefusal::Attach),
        A::Detach { .. } => Some(JailRefusal::Detach),
        A::Transaction { .. } | A::Savepoint { .. } => Some(JailRefusal::Transaction),
        // DROP, CREATE and ALTER are first asked as a write to the schema table (and
        // end there).
        A::Insert { table_name } | A::Update { table_name, .. } | A::Delete { table_name }
            if is_schema_table(table_name) =>
        {
            Some(JailRefusal::Schema)
        }
        A::Insert { table_name } => Some(JailRefusal::Insert {
            table: table_name.to_string(),
        }),
        A::Update { table_name, .. } => Some(JailRefusal::Update {
            table: table_name.to_string(),
        }),
        A::Delete { table_name } => Some(JailRefusal::Delete {
            table: table_name.to_string(),
        }),
        A::DropTable { table_name } | A::DropTempTable { table_name } => {
            Some(JailRefusal::DropTable {
                table: table_name.to_string(),
            })
        }
        other => Some(JailRefusal::Other {
            action: action_name(other),
        }),
    }
}

/// SQLite's schema table under any of its names.
fn is_schema_table(name: &str) -> bool {
    matches!(
        name.to_ascii_lowercase().as_str(),
        "sqlite_master" | "sqlite_schema" | "sqlite_temp_master" | "sqlite_temp_schema"
    )
}

/// A short name of an authorizer action for messages.
fn action_name(a: &rusqlite::hooks::AuthAction<'_>) -> String {
    let d = format!("{a:?}");
    d.split([' ', '{', '('])
        .next()
        .unwrap_or("the statement")
        .to_string()
}

/// The read-only, jailed SQLite connection of scripts' queries.
pub(crate) struct SqliteReader {
    conn: rusqlite::Connection,
    /// What the authorizer refused last (its messages say more than "not authorized").
    refused: Arc<Mutex<Option<JailRefusal>>>,
    /// The running query's deadline and cancel flag, read by fitup's own functions.
    clock: Arc<super::functions::Clock>,
}

/// Sets SQLite's process-wide heap limit ([`SQLITE_HEAP_LIMIT`]) once.
fn limit_sqlite_heap() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // SAFETY: sqlite3_hard_heap_limit64 only sets a number SQLite's allocator
        // reads; it may be called at any time from any thread.
        unsafe {
            rusqlite::ffi::sqlite3_hard_heap_limit64(SQLITE_HEAP_LIMIT);
        }
    });
}

impl SqliteReader {
    /// Opens the held file read-only (it must exist: the writing connection made it),
    /// through its held folder ([`super::held`]).
    pub fn open(held: &super::held::HeldFile, busy: Duration) -> Result<Self, Raw> {
        use rusqlite::limits::Limit;
        use rusqlite::OpenFlags;
        // No SQLITE_OPEN_URI: a file name is a file name, never `file:…?mode=rwc`.
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let (name, vfs) = held.sqlite_name();
        let mut conn = match vfs {
            Some(vfs) => rusqlite::Connection::open_with_flags_and_vfs(&name, flags, vfs),
            None => rusqlite::Connection::open_with_flags(&name, flags),
        }?;
        conn.busy_timeout(busy)?;
        conn.set_limit(Limit::SQLITE_LIMIT_ATTACHED, 0)?;
        conn.set_limit(
            Limit::SQLITE_LIMIT_LENGTH,
            super::functions::MAX_VALUE_BYTES,
        )?;
        conn.set_db_config(rusqlite::config::DbConfig::SQLITE_DBCONFIG_DEFENSIVE, true)?;
        conn.set_db_config(
            rusqlite::config::DbConfig::SQLITE_DBCONFIG_TRUSTED_SCHEMA,
            false,
        )?;
        // Sorts, temporary tables and indices stay in memory (never a file in the
        // system's temporary folder, outside the project), under SQLite's heap limit.
        conn.execute_batch("PRAGMA cache_size=-16000; PRAGMA temp_store=MEMORY")?;
        limit_sqlite_heap();
        conn.set_limit(
            Limit::SQLITE_LIMIT_LIKE_PATTERN_LENGTH,
            super::functions::MAX_PATTERN_BYTES as i32,
        )?;
        let clock = Arc::new(super::functions::Clock::new());
        super::functions::register(&conn, &clock)?;
        let refused = Arc::new(Mutex::new(None));
        let r = refused.clone();
        conn.authorizer(Some(
            move |ctx: rusqlite::hooks::AuthContext<'_>| match sqlite_refusal(&ctx.action) {
                None => rusqlite::hooks::Authorization::Allow,
                Some(why) => {
                    if let Ok(mut slot) = r.lock() {
                        slot.get_or_insert(why);
                    }
                    rusqlite::hooks::Authorization::Deny
                }
            },
        ))?;
        Ok(SqliteReader {
            conn,
            refused,
            clock,
        })
    }

    /// Runs one read-only statement within `limits`; `cancel` stops it when set.
    pub fn query(
        &mut self,
        sql: &str,
        params: &[SqlValue],
        limits: QueryLimits,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<QueryResult, Stop> {
        if let Ok(mut slot) = self.refused.lock() {
            *slot = None;
        }
        let why = Arc::new(AtomicU8::new(WHY_NONE));
        let deadline = Deadline::after(limits.time);
        let w = why.clone();
        let c = cancel.clone();
        self.conn
            .progress_handler(
                PROGRESS_STEPS,
                Some(move || {
                    if c.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
                        w.store(WHY_CANCEL, Ordering::Relaxed);
                        true
                    } else if deadline.passed() {
                        w.store(WHY_TIME, Ordering::Relaxed);
                        true
                    } else {
                        false
                    }
                }),
            )
            .map_err(Raw::from)?;
        self.clock.start(deadline.instant(), cancel.clone());
        // The clock read by time, not by steps: a watchdog interrupts the statement at
        // its deadline (or when the run is cancelled) however long one step takes,
        // and is joined before the query returns (an interrupt never reaches the
        // next statement).
        let watchdog = Watchdog::start(
            self.conn.get_interrupt_handle(),
            deadline,
            cancel,
            why.clone(),
        );
        let result = self.run(sql, params, limits);
        watchdog.stop();
        self.clock.stop();
        // A handler left behind would stop the next statement at this one's deadline.
        let _ = self.conn.progress_handler(0, None::<fn() -> bool>);
        result.map_err(|e| match e {
            Stop::Sql(raw) => match why.load(Ordering::Relaxed) {
                WHY_TIME => Stop::Timeout,
                // One of fitup's functions saw the deadline before the watchdog did.
                WHY_NONE if deadline.passed() => Stop::Timeout,
                WHY_CANCEL => Stop::Cancelled,
                _ => match self.refused.lock().ok().and_then(|mut s| s.take()) {
                    Some(reason) => Stop::Refused(reason),
                    // SQLite's heap limit: say which limit, and that nothing spilled.
                    None if raw.message.contains("out of memory") => Stop::Sql(Raw::other(format!(
                        "out of memory: the query needed more than SQLite's memory limit of {} (sorts and temporary tables are kept in memory, never written outside the project; docs/database.md)",
                        bytes(SQLITE_HEAP_LIMIT as usize)
                    ))),
                    None => Stop::Sql(raw),
                },
            },
            other => other,
        })
    }

    fn run(
        &self,
        sql: &str,
        params: &[SqlValue],
        limits: QueryLimits,
    ) -> Result<QueryResult, Stop> {
        let mut stmt = self.conn.prepare(sql).map_err(Raw::from)?;
        if !stmt.readonly() {
            return Err(Stop::Refused(JailRefusal::Writes));
        }
        if stmt.parameter_count() != params.len() {
            return Err(Stop::Sql(Raw::other(format!(
                "the statement has {} parameters, {} given",
                stmt.parameter_count(),
                params.len()
            ))));
        }
        let columns: Vec<String> = stmt.column_names().map(|s| s.to_string()).collect();
        let n = columns.len();
        let mut out = Collector::new(limits, &columns);
        let mut rows = stmt
            .query(rusqlite::params_from_iter(params.iter()))
            .map_err(Raw::from)?;
        while let Some(row) = rows.next().map_err(Raw::from)? {
            out.push(
                (0..n)
                    .map(|i| row.get_ref(i).map(backend::sqlite_value))
                    .collect::<Result<_, _>>()
                    .map_err(Raw::from)?,
            )?;
        }
        Ok(QueryResult {
            columns,
            rows: out.rows,
        })
    }
}

/// The thread that interrupts one statement at its deadline or on cancel.
struct Watchdog {
    done: std::sync::mpsc::Sender<()>,
    thread: std::thread::JoinHandle<()>,
}

impl Watchdog {
    /// How often the watchdog looks at the cancel flag.
    const POLL: Duration = Duration::from_millis(20);

    fn start(
        handle: rusqlite::InterruptHandle,
        deadline: Deadline,
        cancel: Option<Arc<AtomicBool>>,
        why: Arc<AtomicU8>,
    ) -> Watchdog {
        let (done, rx) = std::sync::mpsc::channel::<()>();
        let thread = std::thread::spawn(move || loop {
            if deadline.passed() {
                why.store(WHY_TIME, Ordering::Relaxed);
                handle.interrupt();
                return;
            }
            if cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
                why.store(WHY_CANCEL, Ordering::Relaxed);
                handle.interrupt();
                return;
            }
            match rx.recv_timeout(deadline.remaining().min(Self::POLL)) {
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                _ => return, // the statement ended
            }
        });
        Watchdog { done, thread }
    }

    fn stop(self) {
        let _ = self.done.send(());
        let _ = self.thread.join();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_for_people() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(100_000), "100,000");
        assert_eq!(thousands(4_000_000), "4,000,000");
        assert_eq!(bytes(64 << 20), "64 MiB");
        assert_eq!(bytes(1536), "1.5 KiB");
        assert_eq!(bytes(12), "12 bytes");
    }

    #[test]
    fn limits_are_checked_against_the_maxima() {
        assert!(QueryLimits::DEFAULT.checked().is_ok());
        assert!(QueryLimits::MAX.checked().is_ok());
        let too_long = QueryLimits {
            time: Duration::from_secs(601),
            ..QueryLimits::DEFAULT
        };
        let e = too_long.checked().unwrap_err().to_string();
        assert!(e.contains("max_seconds") && e.contains("600 s"), "{e}");
        let no_rows = QueryLimits {
            max_rows: 0,
            ..QueryLimits::DEFAULT
        };
        assert!(no_rows
            .checked()
            .unwrap_err()
            .to_string()
            .contains("max_rows"));
        let huge = QueryLimits {
            max_bytes: QueryLimits::MAX.max_bytes + 1,
            ..QueryLimits::DEFAULT
        };
        assert!(huge
            .checked()
            .unwrap_err()
            .to_string()
            .contains("max_bytes"));
    }

    #[test]
    fn the_authorizer_allows_reads_only() {
        use rusqlite::hooks::AuthAction as A;
        assert_eq!(sqlite_refusal(&A::Select), None);
        assert_eq!(
            sqlite_refusal(&A::Read {
                table_name: "runs",
                column_name: "id"
            }),
            None
        );
        assert_eq!(
            sqlite_refusal(&A::Function {
                function_name: "count"
            }),
            None
        );
        assert_eq!(
            sqlite_refusal(&A::Pragma {
                pragma_name: "table_info",
                pragma_value: Some("paths")
            }),
            None
        );
        assert_eq!(
            sqlite_refusal(&A::Pragma {
                pragma_name: "user_version",
                pragma_value: None
            }),
            None
        );
        for refused in [
            A::Attach {
                filename: "/outside/secret.db",
            },
            A::Detach { database_name: "o" },
            A::Pragma {
                pragma_name: "synchronous",
                pragma_value: Some("OFF"),
            },
            A::Pragma {
                pragma_name: "foreign_keys",
                pragma_value: Some("0"),
            },
            A::Pragma {
                pragma_name: "wal_checkpoint",
                pragma_value: None,
            },
            A::Function {
                function_name: "LOAD_EXTENSION",
            },
            A::Function {
                function_name: "writefile",
            },
            A::Insert { table_name: "runs" },
            A::Delete {
                table_name: "paths",
            },
            A::DropTable { table_name: "runs" },
            A::CreateTable { table_name: "x" },
        ] {
            assert!(sqlite_refusal(&refused).is_some(), "{refused:?}");
        }
        let said = |a: A<'_>| sqlite_refusal(&a).unwrap().to_string();
        assert_eq!(
            said(A::Attach { filename: "o.db" }),
            "ATTACH would open another database file"
        );
        assert_eq!(
            said(A::Pragma {
                pragma_name: "synchronous",
                pragma_value: Some("OFF"),
            }),
            "`PRAGMA synchronous = …` changes a setting"
        );
        assert_eq!(
            said(A::Pragma {
                pragma_name: "wal_checkpoint",
                pragma_value: None,
            }),
            "`PRAGMA wal_checkpoint` is not a schema query"
        );
        assert_eq!(
            said(A::Function {
                function_name: "LOAD_EXTENSION",
            }),
            "the function `LOAD_EXTENSION` reaches outside the database"
        );
        assert_eq!(
            said(A::Insert { table_name: "runs" }),
            "INSERT into `runs` writes"
        );
        assert_eq!(
            said(A::Insert {
                table_name: "sqlite_master"
            }),
            "the statement changes the schema (DROP, CREATE or ALTER)"
        );
        assert_eq!(
            said(A::Delete {
                table_name: "paths"
            }),
            "DELETE from `paths` writes"
        );
        assert_eq!(
            said(A::DropTable { table_name: "runs" }),
            "DROP TABLE `runs` writes"
        );
        assert_eq!(
            said(A::CreateTable { table_name: "x" }),
            "CreateTable writes or changes the schema"
        );
    }

    /// A fresh project database with one run.
    fn db() -> (tempfile::TempDir, crate::db::Database) {
        let dir = tempfile::tempdir().unwrap();
        let mut db =
            crate::db::Database::open(&crate::db::Target::Sqlite(dir.path().join("fitup.db")))
                .unwrap();
        db.start_run(&crate::db::NewRun::script("s.rhai")).unwrap();
        (dir, db)
    }

    #[test]
    fn attach_is_refused_and_creates_no_file() {
        let (dir, mut db) = db();
        let outside = tempfile::tempdir().unwrap();
        let secret = outside.path().join("secret.db");
        rusqlite::Connection::open(&secret)
            .unwrap()
            .execute_batch("CREATE TABLE s(x); INSERT INTO s VALUES ('hidden');")
            .unwrap();
        let missing = outside.path().join("new.db");
        for file in [&secret, &missing] {
            let sql = format!("ATTACH DATABASE '{}' AS o", file.display());
            let e = db.query(&sql, &[]).unwrap_err();
            assert!(matches!(e, DbError::WriteRefused { .. }), "{e}");
            assert!(e.to_string().contains("ATTACH"), "{e}");
        }
        assert!(!missing.exists(), "ATTACH created {}", missing.display());
        // Neither through the table-valued form nor VACUUM INTO.
        let into = outside.path().join("copy.db");
        let e = db
            .query(&format!("VACUUM INTO '{}'", into.display()), &[])
            .unwrap_err();
        assert!(matches!(e, DbError::WriteRefused { .. }), "{e}");
        assert!(!into.exists());
        drop(dir);
    }

    #[test]
    fn pragma_writes_and_table_writes_are_refused() {
        let (_dir, mut db) = db();
        for sql in [
            "PRAGMA synchronous=OFF",
            "PRAGMA foreign_keys=OFF",
            "PRAGMA journal_mode=DELETE",
            "PRAGMA user_version=7",
            "PRAGMA wal_checkpoint",
            "INSERT INTO runs (script, started_at, status, output, fitup_version) VALUES ('x', 'now', 'ok', '', '0')",
            "UPDATE runs SET status = 'ok'",
            "DELETE FROM runs",
            "DROP TABLE runs",
            "CREATE TABLE x(a)",
            "CREATE TEMP TABLE x(a)",
            "BEGIN",
            "SELECT load_extension('/tmp/evil.so')",
            "SELECT 1; DELETE FROM runs",
        ] {
            assert!(db.query(sql, &[]).is_err(), "{sql} was accepted");
        }
        // The state is as before: the run is there, the file still in WAL mode.
        assert_eq!(db.runs().unwrap().len(), 1);
        for setting in READ_SETTINGS.iter().chain(READ_PRAGMAS) {
            if let Err(e) = db.query(&format!("PRAGMA {setting}"), &[]) {
                panic!("PRAGMA {setting}: {e}");
            }
        }
        let e = db.query("PRAGMA synchronous", &[]).unwrap_err();
        assert!(e.to_string().contains("PRAGMA synchronous"), "{e}");
        // Reads and schema queries work.
        assert_eq!(
            db.query("SELECT COUNT(*) FROM runs", &[]).unwrap().rows[0][0],
            SqlValue::Int(1)
        );
        assert!(!db
            .query("SELECT name FROM pragma_table_info('paths')", &[])
            .unwrap()
            .rows
            .is_empty());
        assert!(!db
            .query("PRAGMA table_info(paths)", &[])
            .unwrap()
            .rows
            .is_empty());
    }

    #[test]
    fn a_recursive_query_stops_at_its_time_limit() {
        let (_dir, mut db) = db();
        let limits = QueryLimits {
            time: Duration::from_millis(300),
            ..QueryLimits::DEFAULT
        };
        let start = Instant::now();
        let e = db
            .query_with(
                "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) SELECT COUNT(*) FROM c",
                &[],
                limits,
                None,
            )
            .unwrap_err();
        assert!(matches!(e, DbError::QueryTimeout { .. }), "{e}");
        assert!(e.to_string().contains("query stopped after 0.3 s"), "{e}");
        assert!(start.elapsed() < Duration::from_secs(5));
        // The connection is usable afterwards, without the old deadline.
        std::thread::sleep(Duration::from_millis(350));
        assert!(db.query("SELECT 1", &[]).is_ok());
    }

    #[test]
    fn a_cancelled_run_stops_its_query() {
        let (_dir, mut db) = db();
        let cancel = Arc::new(AtomicBool::new(false));
        let c = cancel.clone();
        let t = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(200));
            c.store(true, Ordering::Relaxed);
        });
        let e = db
            .query_with(
                "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) SELECT COUNT(*) FROM c",
                &[],
                QueryLimits::DEFAULT,
                Some(cancel),
            )
            .unwrap_err();
        t.join().unwrap();
        assert!(matches!(e, DbError::QueryCancelled { .. }), "{e}");
    }

    #[test]
    fn results_past_the_caps_are_refused() {
        let (_dir, mut db) = db();
        let many = "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c LIMIT 5000000) SELECT x FROM c";
        let e = db.query(many, &[]).unwrap_err();
        assert!(matches!(e, DbError::QueryTooLarge { .. }), "{e}");
        assert!(
            e.to_string().contains("more than 100,000 rows or 64 MiB"),
            "{e}"
        );
        let small = QueryLimits {
            max_rows: 10,
            ..QueryLimits::DEFAULT
        };
        let ten = "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c LIMIT 10) SELECT x FROM c";
        assert_eq!(db.query_with(ten, &[], small, None).unwrap().rows.len(), 10);
        let e = db
            .query_with(&ten.replace("LIMIT 10", "LIMIT 11"), &[], small, None)
            .unwrap_err();
        assert!(e.to_string().contains("more than 10 rows"), "{e}");
        // Bytes: 100 rows of 1 MiB text pass 64 MiB.
        let wide = "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c LIMIT 100) SELECT x, zeroblob(1048576) || '' AS t FROM c";
        let e = db.query(wide, &[]).unwrap_err();
        assert!(matches!(e, DbError::QueryTooLarge { .. }), "{e}");
        // One value past 16 MiB is SQLite's refusal.
        let e = db.query("SELECT zeroblob(20000000)", &[]).unwrap_err();
        assert!(e.to_string().contains("too big"), "{e}");
    }

    #[test]
    fn limits_beyond_the_maxima_are_refused_before_running() {
        let (_dir, mut db) = db();
        let e = db
            .query_with(
                "SELECT 1",
                &[],
                QueryLimits {
                    max_rows: 5_000_000,
                    ..QueryLimits::DEFAULT
                },
                None,
            )
            .unwrap_err();
        assert!(
            matches!(
                e,
                DbError::QueryLimit {
                    asked: AskedLimit::Rows(5_000_000)
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn limits_out_of_range_name_the_limit_its_value_and_maximum() {
        let e = |limits: QueryLimits| limits.checked().unwrap_err().to_string();
        let d = QueryLimits::DEFAULT;
        assert_eq!(
            e(QueryLimits {
                time: Duration::ZERO,
                ..d
            }),
            "the query limit max_seconds = 0 s is out of range: it must be positive and at most 600 s"
        );
        assert_eq!(
            e(QueryLimits {
                time: Duration::from_millis(600_500),
                ..d
            }),
            "the query limit max_seconds = 600.5 s is out of range: it must be positive and at most 600 s"
        );
        assert_eq!(
            e(QueryLimits {
                max_rows: 5_000_000,
                ..d
            }),
            "the query limit max_rows = 5,000,000 is out of range: it must be positive and at most 1,000,000"
        );
        assert_eq!(
            e(QueryLimits { max_bytes: 0, ..d }),
            "the query limit max_bytes = 0 is out of range: it must be positive and at most 268,435,456 (256 MiB)"
        );
        let options = crate::options::Limits {
            max_seconds: -1.5,
            ..Default::default()
        };
        assert_eq!(
            options.limits().unwrap_err(),
            DbError::QueryLimit {
                asked: AskedLimit::Seconds(-1.5)
            }
        );
        assert_eq!(
            options.limits().unwrap_err().to_string(),
            "the query limit max_seconds = -1.5 s is out of range: it must be positive and at most 600 s"
        );
    }
}
