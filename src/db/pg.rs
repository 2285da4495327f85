//! The PostgreSQL back end (cargo feature `postgres`): the `postgres` client behind
//! [`Tx`](super::backend::Tx), the connect with its deadline, and scripts' read-only
//! queries in a `READ ONLY` transaction. Everything above the back ends is written once
//! against `Tx` with `?` placeholders ([`numbered`] turns them into `$n`).

use super::backend::{Dialect, Kind, Raw, SqlValue, Tx};
use super::query::{Collector, QueryLimits, Stop, WHY_CANCEL, WHY_NONE, WHY_TIME};
use super::{JailRefusal, QueryResult};
use crate::math::Deadline;
use postgres::types::{ToSql, Type};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The longest `connect_timeout` a URL may ask for.
const MAX_CONNECT_TIMEOUT: Duration = Duration::from_secs(120);

/// How long data sent to a PostgreSQL server may stay unacknowledged before the
/// connection is dropped (a server or network that went away).
const TCP_USER_TIMEOUT: Duration = Duration::from_secs(30);

/// `?` placeholders → PostgreSQL's `$1, $2, …` (fitup's own SQL has no `?`
/// inside string literals).
pub(crate) fn numbered(sql: &str) -> String {
    let mut out = String::with_capacity(sql.len() + 8);
    let mut n = 0;
    for c in sql.chars() {
        if c == '?' {
            n += 1;
            out.push('$');
            out.push_str(&n.to_string());
        } else {
            out.push(c);
        }
    }
    out
}

impl From<postgres::Error> for Raw {
    fn from(e: postgres::Error) -> Self {
        use postgres::error::SqlState;
        let kind = match e.code() {
            Some(c) if *c == SqlState::READ_ONLY_SQL_TRANSACTION => Kind::WriteRefused,
            Some(c)
                if *c == SqlState::T_R_SERIALIZATION_FAILURE
                    || *c == SqlState::T_R_DEADLOCK_DETECTED
                    || *c == SqlState::LOCK_NOT_AVAILABLE =>
            {
                Kind::Busy
            }
            Some(c) if *c == SqlState::DISK_FULL => Kind::Full,
            _ => Kind::Other,
        };
        Raw {
            kind,
            message: server_message(&e),
        }
    }
}

/// The server's own message (and detail), which says more than the client's summary;
/// the client's when the server said nothing.
fn server_message(e: &postgres::Error) -> String {
    match e.as_db_error() {
        Some(db) => match db.detail() {
            Some(d) => format!("{} ({d})", db.message()),
            None => db.message().to_string(),
        },
        None => e.to_string(),
    }
}

/// Converts a value to what PostgreSQL expects for a parameter of type `ty`.
pub(crate) fn pg_param(
    v: &SqlValue,
    ty: &Type,
    index: usize,
) -> Result<Box<dyn ToSql + Sync>, Raw> {
    let bad = || {
        Raw::other(format!(
            "parameter {} ({v:?}) does not fit type {ty}",
            index + 1
        ))
    };
    Ok(match *ty {
        Type::INT8 => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(v.as_i64().ok_or_else(bad)?),
        }),
        Type::INT4 => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(i32::try_from(v.as_i64().ok_or_else(bad)?).map_err(|_| bad())?),
        }),
        Type::INT2 => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(i16::try_from(v.as_i64().ok_or_else(bad)?).map_err(|_| bad())?),
        }),
        Type::FLOAT8 => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(v.as_f64().ok_or_else(bad)?),
        }),
        Type::FLOAT4 => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(v.as_f64().ok_or_else(bad)? as f32),
        }),
        Type::BOOL => Box::new(match v {
            SqlValue::Null => None,
            _ => Some(v.as_i64().ok_or_else(bad)? != 0),
        }),
        Type::TEXT | Type::VARCHAR | Type::BPCHAR | Type::NAME | Type::UNKNOWN => {
            Box::new(match v {
                SqlValue::Null => None,
                other => Some(other.to_string()),
            })
        }
        _ => {
            return Err(Raw::other(format!(
                "parameter {} has type {ty}, which fitup does not bind: cast it (`$n::text`)",
                index + 1
            )))
        }
    })
}

/// Reads column `i` of a PostgreSQL row.
pub(crate) fn pg_value(row: &postgres::Row, i: usize) -> Result<SqlValue, Raw> {
    let col = &row.columns()[i];
    let ty = col.type_();
    let get_err = |e: postgres::Error| Raw::from(e);
    Ok(match *ty {
        Type::INT8 => row.try_get::<_, Option<i64>>(i).map_err(get_err)?.into(),
        Type::INT4 => row
            .try_get::<_, Option<i32>>(i)
            .map_err(get_err)?
            .map(i64::from)
            .into(),
        Type::INT2 => row
            .try_get::<_, Option<i16>>(i)
            .map_err(get_err)?
            .map(i64::from)
            .into(),
        Type::OID => row
            .try_get::<_, Option<u32>>(i)
            .map_err(get_err)?
            .map(i64::from)
            .into(),
        Type::FLOAT8 => row.try_get::<_, Option<f64>>(i).map_err(get_err)?.into(),
        Type::FLOAT4 => row
            .try_get::<_, Option<f32>>(i)
            .map_err(get_err)?
            .map(f64::from)
            .into(),
        Type::BOOL => row
            .try_get::<_, Option<bool>>(i)
            .map_err(get_err)?
            .map(i64::from)
            .into(),
        Type::TEXT | Type::VARCHAR | Type::BPCHAR | Type::NAME | Type::UNKNOWN => {
            row.try_get::<_, Option<String>>(i).map_err(get_err)?.into()
        }
        _ => {
            return Err(Raw::other(format!(
                "column `{}` has type {ty}, which fitup does not read: cast it (`{}::text`)",
                col.name(),
                col.name()
            )))
        }
    })
}

/// The parameters of a prepared statement, converted to the types it declares; a
/// wrong count is an error (zipping would silently drop or ignore parameters).
pub(crate) fn pg_bind(
    stmt: &postgres::Statement,
    params: &[SqlValue],
) -> Result<Vec<Box<dyn ToSql + Sync>>, Raw> {
    if stmt.params().len() != params.len() {
        return Err(Raw::other(format!(
            "the statement has {} parameters, {} given",
            stmt.params().len(),
            params.len()
        )));
    }
    params
        .iter()
        .zip(stmt.params())
        .enumerate()
        .map(|(i, (v, t))| pg_param(v, t, i))
        .collect()
}

/// Every row of a query result as values.
pub(crate) fn pg_table(rows: &[postgres::Row]) -> Result<Vec<Vec<SqlValue>>, Raw> {
    rows.iter()
        .map(|r| (0..r.len()).map(|i| pg_value(r, i)).collect())
        .collect()
}

pub(crate) fn pg_rows(
    client: &mut impl postgres::GenericClient,
    sql: &str,
    params: &[SqlValue],
) -> Result<Vec<Vec<SqlValue>>, Raw> {
    let stmt = client.prepare(&numbered(sql))?;
    let boxed = pg_bind(&stmt, params)?;
    let refs: Vec<&(dyn ToSql + Sync)> = boxed.iter().map(|b| b.as_ref()).collect();
    pg_table(&client.query(&stmt, &refs)?)
}

/// A PostgreSQL transaction.
pub(crate) struct PgTx<'a>(pub postgres::Transaction<'a>);

impl Tx for PgTx<'_> {
    fn exec(&mut self, sql: &str, params: &[SqlValue]) -> Result<u64, Raw> {
        let stmt = self.0.prepare(&numbered(sql))?;
        let boxed = pg_bind(&stmt, params)?;
        let refs: Vec<&(dyn ToSql + Sync)> = boxed.iter().map(|b| b.as_ref()).collect();
        Ok(self.0.execute(&stmt, &refs)?)
    }

    fn rows(&mut self, sql: &str, params: &[SqlValue]) -> Result<Vec<Vec<SqlValue>>, Raw> {
        pg_rows(&mut self.0, sql, params)
    }

    fn insert_id(&mut self, sql: &str, params: &[SqlValue]) -> Result<i64, Raw> {
        let rows = self.rows(&format!("{sql} RETURNING id"), params)?;
        rows.first()
            .and_then(|r| r.first())
            .and_then(SqlValue::as_i64)
            .ok_or_else(|| Raw::other("INSERT returned no id"))
    }

    fn insert_many(
        &mut self,
        table: &str,
        columns: &[&str],
        rows: &[Vec<SqlValue>],
    ) -> Result<(), Raw> {
        // Multi-row VALUES in chunks: one round trip per chunk instead of per row, and
        // well under PostgreSQL's 65,535 parameters per statement.
        let per = (4000 / columns.len().max(1)).max(1);
        for chunk in rows.chunks(per) {
            let one = format!("({})", vec!["?"; columns.len()].join(", "));
            let sql = format!(
                "INSERT INTO {table} ({}) VALUES {}",
                columns.join(", "),
                vec![one.as_str(); chunk.len()].join(", ")
            );
            let flat: Vec<SqlValue> = chunk.iter().flatten().cloned().collect();
            self.exec(&sql, &flat)?;
        }
        Ok(())
    }

    fn dialect(&self) -> Dialect {
        Dialect::Postgres
    }
}

/// Opens a connection to the server at `url` with fitup's settings: the URL's
/// `connect_timeout` (else [`CONNECT_TIMEOUT`](super::CONNECT_TIMEOUT)) bounds the whole
/// handshake, a TCP user timeout and keepalives notice a server that went away. The
/// error's message is the driver's, not yet scrubbed of credentials.
pub(crate) fn connect(url: &str) -> Result<postgres::Client, ConnectError> {
    let mut config: postgres::Config = url.parse().map_err(ConnectError::Url)?;
    let timeout = config
        .get_connect_timeout()
        .copied()
        .unwrap_or(super::CONNECT_TIMEOUT)
        .clamp(Duration::from_secs(1), MAX_CONNECT_TIMEOUT);
    config.connect_timeout(timeout);
    config.tcp_user_timeout(TCP_USER_TIMEOUT);
    config.keepalives(true);
    config.keepalives_idle(Duration::from_secs(30));
    config.application_name("fitup");
    connect_within(config, timeout)
}

/// Why a connection to PostgreSQL was not made (the cause of a
/// [`DbError::Open`](super::DbError::Open), scrubbed of credentials there).
#[derive(Debug, thiserror::Error)]
pub(crate) enum ConnectError {
    /// The URL does not parse.
    #[error("{0}")]
    Url(#[source] postgres::Error),
    /// The connecting thread could not start.
    #[error("cannot start the connecting thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The server or the network refused (the driver's message).
    #[error("{}", server_message(.0))]
    Refused(#[source] postgres::Error),
    /// The handshake did not finish within the connect timeout.
    #[error("no answer from the server within {} s (the connect timeout; `connect_timeout=N` in the URL changes it, up to {} s)", .0.as_secs_f64(), MAX_CONNECT_TIMEOUT.as_secs())]
    NoAnswer(Duration),
}

/// Connects to PostgreSQL, giving up after `timeout`: the driver bounds the TCP
/// connect only, so a server that accepts and then never answers would hang the
/// handshake forever. The attempt runs on its own thread; one that has not finished
/// in time is left to end by itself (when the server closes, or with the process).
fn connect_within(
    config: postgres::Config,
    timeout: Duration,
) -> Result<postgres::Client, ConnectError> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("fitup-db-connect".into())
        .spawn(move || {
            let _ = tx.send(config.connect(postgres::NoTls));
        })
        .map_err(ConnectError::Thread)?;
    match rx.recv_timeout(timeout) {
        Ok(Ok(client)) => Ok(client),
        Ok(Err(e)) => Err(ConnectError::Refused(e)),
        Err(_) => Err(ConnectError::NoAnswer(timeout)),
    }
}

/// Words that may start a PostgreSQL query from a script.
const PG_STATEMENTS: &[&str] = &["select", "with", "values", "table"];

/// PostgreSQL functions refused anywhere in a script's query (also inside string
/// literals, which `query_to_xml` and friends would run): they read or write server
/// files, run other SQL, signal other sessions, change settings or take session locks
/// that outlive the query.
const PG_DENIED: &[&str] = &[
    "pg_read_file",
    "pg_read_binary_file",
    "pg_ls_",
    "pg_stat_file",
    "pg_file_",
    "lo_import",
    "lo_export",
    "dblink",
    "query_to_xml",
    "cursor_to_xml",
    "table_to_xml",
    "schema_to_xml",
    "database_to_xml",
    "ts_stat",
    "ts_rewrite",
    "set_config",
    "pg_terminate_backend",
    "pg_cancel_backend",
    "pg_signal_backend",
    "pg_reload_conf",
    "pg_rotate_logfile",
    "pg_promote",
    "pg_switch_wal",
    "pg_advisory_",
    "pg_try_advisory_",
    "pg_notify",
    "pg_logical_",
    "pg_replication_",
    "pg_create_",
    "pg_drop_",
    "pg_log_backend",
    "pg_import_system",
];

/// Refuses a PostgreSQL statement that is not a plain query or names a function of
/// [`PG_DENIED`]; the message says which.
pub(crate) fn pg_refusal(sql: &str) -> Option<JailRefusal> {
    let first = first_word(sql);
    if !PG_STATEMENTS.contains(&first.as_str()) {
        return Some(JailRefusal::NotAQuery {
            first: first.to_ascii_uppercase(),
        });
    }
    let lower = sql.to_ascii_lowercase();
    PG_DENIED
        .iter()
        .find(|f| lower.contains(*f))
        .map(|f| JailRefusal::Outside {
            function: f.trim_end_matches('_'),
        })
}

/// The first keyword of a statement, after spaces, comments and opening parentheses,
/// lowercased.
fn first_word(sql: &str) -> String {
    let b = sql.as_bytes();
    let mut i = 0;
    loop {
        while i < b.len() && (b[i].is_ascii_whitespace() || b[i] == b'(') {
            i += 1;
        }
        if b[i..].starts_with(b"--") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            // PostgreSQL block comments nest.
            i = crate::diagnostics::nested_comment_end(b, i);
        } else {
            break;
        }
    }
    let end = b[i..]
        .iter()
        .position(|c| !c.is_ascii_alphanumeric() && *c != b'_')
        .map_or(b.len(), |p| i + p);
    sql[i..end].to_ascii_lowercase()
}

/// How many PostgreSQL rows are fetched per round trip: the caps are checked between
/// batches, so at most this many rows past the cap are ever in memory.
const PG_BATCH: i32 = 1000;

/// How much longer than the server's `statement_timeout` the watcher waits before it
/// cancels the statement itself (the server should have stopped it).
const PG_GRACE: Duration = Duration::from_secs(2);

/// Runs one read-only query on PostgreSQL within `limits`; `cancel` stops it.
pub(crate) fn pg_query(
    client: &mut postgres::Client,
    sql: &str,
    params: &[SqlValue],
    limits: QueryLimits,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<QueryResult, Stop> {
    if let Some(why) = pg_refusal(sql) {
        return Err(Stop::Refused(why));
    }
    // The watcher is detached: a cancel request to a server that never answers must
    // not hold up the script once the statement itself has returned.
    let done = Arc::new(AtomicBool::new(false));
    let why = Arc::new(AtomicU8::new(WHY_NONE));
    {
        let (done, why, token) = (done.clone(), why.clone(), client.cancel_token());
        let deadline = Deadline::after(limits.time + PG_GRACE);
        let _ = std::thread::Builder::new()
            .name("fitup-db-watch".into())
            .spawn(move || {
                while !done.load(Ordering::Relaxed) {
                    let reason = if cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
                        WHY_CANCEL
                    } else if deadline.passed() {
                        WHY_TIME
                    } else {
                        std::thread::sleep(Duration::from_millis(20));
                        continue;
                    };
                    why.store(reason, Ordering::Relaxed);
                    let _ = token.cancel_query(postgres::NoTls);
                    return;
                }
            });
    }
    let result = pg_run(client, sql, params, limits, Deadline::after(limits.time));
    done.store(true, Ordering::Relaxed);
    result.map_err(|e| match (e, why.load(Ordering::Relaxed)) {
        (_, WHY_CANCEL) => Stop::Cancelled,
        (Stop::Sql(_), WHY_TIME) => Stop::Timeout,
        (e, _) => e,
    })
}

fn pg_error(e: postgres::Error) -> Stop {
    use postgres::error::SqlState;
    match e.code() {
        Some(c) if *c == SqlState::QUERY_CANCELED => Stop::Timeout,
        // A write in the read-only transaction is classed `WriteRefused` (From): a
        // `DbError::WriteRefused` with the server's words.
        _ => Stop::Sql(Raw::from(e)),
    }
}

fn pg_run(
    client: &mut postgres::Client,
    sql: &str,
    params: &[SqlValue],
    limits: QueryLimits,
    deadline: Deadline,
) -> Result<QueryResult, Stop> {
    let mut tx = client
        .build_transaction()
        .read_only(true)
        .start()
        .map_err(pg_error)?;
    // SET LOCAL ends with the transaction (always rolled back).
    tx.batch_execute(&format!(
        "SET LOCAL statement_timeout = {}",
        limits.time.as_millis().max(1)
    ))
    .map_err(pg_error)?;
    let stmt = tx.prepare(sql).map_err(pg_error)?;
    let columns: Vec<String> = stmt
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let boxed = pg_bind(&stmt, params)?;
    let refs: Vec<&(dyn postgres::types::ToSql + Sync)> =
        boxed.iter().map(|b| b.as_ref()).collect();
    let portal = tx.bind(&stmt, &refs).map_err(pg_error)?;
    let mut out = Collector::new(limits, &columns);
    loop {
        let batch = tx.query_portal(&portal, PG_BATCH).map_err(pg_error)?;
        if batch.is_empty() {
            break;
        }
        let last = batch.len() < PG_BATCH as usize;
        for row in pg_table(&batch)? {
            out.push(row)?;
        }
        if last {
            break;
        }
        // Each batch is its own statement for the server's timeout: keep the total.
        if deadline.passed() {
            return Err(Stop::Timeout);
        }
    }
    tx.rollback().map_err(pg_error)?;
    Ok(QueryResult {
        columns,
        rows: out.rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_numbered() {
        assert_eq!(numbered("a = ? AND b = ?"), "a = $1 AND b = $2");
    }

    #[test]
    fn postgres_statements_other_than_queries_are_refused() {
        for ok in [
            "SELECT 1",
            "  -- note\n select * from runs",
            "/* a /* nested */ comment */ WITH x AS (SELECT 1) SELECT * FROM x",
            "(SELECT 1) UNION (SELECT 2)",
            "VALUES (1), (2)",
            "TABLE runs",
        ] {
            assert_eq!(pg_refusal(ok), None, "{ok}");
        }
        for bad in [
            "COPY runs TO '/tmp/x'",
            "COPY (SELECT 1) TO PROGRAM 'id'",
            "INSERT INTO runs DEFAULT VALUES",
            "SET statement_timeout = 0",
            "DO $$ BEGIN END $$",
            "EXPLAIN ANALYZE DELETE FROM runs",
            "",
        ] {
            let why = pg_refusal(bad).unwrap();
            assert!(matches!(why, JailRefusal::NotAQuery { .. }), "{bad}");
            assert!(why.to_string().contains("is not a query"), "{bad}");
        }
        for bad in [
            "SELECT pg_read_file('/etc/passwd')",
            "select PG_CATALOG.Pg_Read_Binary_File('/x')",
            "SELECT * FROM pg_ls_dir('.')",
            "SELECT query_to_xml('select pg_'||'read_file(''/x'')', true, true, '')",
            "SELECT set_config('statement_timeout', '0', false)",
            "SELECT pg_advisory_lock(1)",
            "SELECT lo_export(1, '/tmp/x')",
        ] {
            let why = pg_refusal(bad).unwrap();
            assert!(matches!(why, JailRefusal::Outside { .. }), "{bad}");
            assert!(why.to_string().contains("reaches outside"), "{bad}");
        }
        let said = |sql: &str| pg_refusal(sql).unwrap().to_string();
        assert_eq!(
            said("copy runs to '/tmp/x'"),
            "`COPY` is not a query: only SELECT, WITH, VALUES and TABLE statements run"
        );
        assert_eq!(
            said(" -- nothing\n"),
            "an empty statement is not a query: only SELECT, WITH, VALUES and TABLE statements run"
        );
        assert_eq!(
            said("SELECT * FROM pg_ls_dir('.')"),
            "`pg_ls…` reaches outside the results database (server files, other SQL, other sessions or settings)"
        );
    }
}
