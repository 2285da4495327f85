//! The two back ends behind one small transaction interface ([`Tx`]): SQLite through
//! `rusqlite`, PostgreSQL through the synchronous `postgres` client. Everything above
//! this file (schema, records) is written once against [`Tx`] with `?` placeholders.

/// A value passed to or read from SQL: the four storage classes both back ends share.
#[derive(Debug, Clone, PartialEq)]
pub enum SqlValue {
    /// SQL `NULL`.
    Null,
    /// An integer (64 bit).
    Int(i64),
    /// A floating-point number (64 bit).
    Real(f64),
    /// Text (UTF-8).
    Text(String),
}

impl SqlValue {
    /// The integer, if this is one (reals with an integral value count).
    pub fn as_i64(&self) -> Option<i64> {
        match self {
            SqlValue::Int(i) => Some(*i),
            SqlValue::Real(r) if r.fract() == 0.0 => Some(*r as i64),
            _ => None,
        }
    }

    /// The number as a float, if this is a number.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            SqlValue::Int(i) => Some(*i as f64),
            SqlValue::Real(r) => Some(*r),
            _ => None,
        }
    }

    /// The text, if this is text.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            SqlValue::Text(s) => Some(s),
            _ => None,
        }
    }
}

impl std::fmt::Display for SqlValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SqlValue::Null => write!(f, "NULL"),
            SqlValue::Int(i) => write!(f, "{i}"),
            SqlValue::Real(r) => write!(f, "{r}"),
            SqlValue::Text(s) => write!(f, "{s}"),
        }
    }
}

impl From<i64> for SqlValue {
    fn from(v: i64) -> Self {
        SqlValue::Int(v)
    }
}
impl From<f64> for SqlValue {
    fn from(v: f64) -> Self {
        SqlValue::Real(v)
    }
}
impl From<&str> for SqlValue {
    fn from(v: &str) -> Self {
        SqlValue::Text(v.to_string())
    }
}
impl From<String> for SqlValue {
    fn from(v: String) -> Self {
        SqlValue::Text(v)
    }
}
impl<T: Into<SqlValue>> From<Option<T>> for SqlValue {
    fn from(v: Option<T>) -> Self {
        v.map_or(SqlValue::Null, Into::into)
    }
}

/// How fitup classes what a database driver answered (the kind of a [`DriverError`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DriverErrorKind {
    /// Another writer holds the lock (SQLite busy/locked, PostgreSQL serialization
    /// failure or deadlock): worth retrying.
    Busy,
    /// The file, folder or server refuses writes.
    ReadOnly,
    /// No space left.
    Full,
    /// A write inside a read-only query (PostgreSQL's read-only transaction; SQLite's
    /// jail refuses before running).
    WriteRefused,
    /// Anything else.
    Other,
}

pub(crate) use DriverErrorKind as Kind;

/// What the back end (SQLite or PostgreSQL) answered, before the database's name is
/// attached: fitup's class of it and the driver's own words (a PostgreSQL message is
/// scrubbed of credentials where it names the server). The cause (`#[source]`) of a
/// [`DbError`](super::DbError) that the driver reported.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct DriverError {
    /// How fitup classes it.
    pub kind: DriverErrorKind,
    /// The driver's message.
    pub message: String,
}

pub(crate) use DriverError as Raw;

impl Raw {
    pub(crate) fn other(message: impl Into<String>) -> Self {
        Raw {
            kind: Kind::Other,
            message: message.into(),
        }
    }
}

impl From<rusqlite::Error> for Raw {
    fn from(e: rusqlite::Error) -> Self {
        use rusqlite::ErrorCode as C;
        let kind = match e.sqlite_error_code() {
            Some(C::DatabaseBusy | C::DatabaseLocked) => Kind::Busy,
            Some(C::ReadOnly) => Kind::ReadOnly,
            Some(C::DiskFull) => Kind::Full,
            _ => Kind::Other,
        };
        Raw {
            kind,
            message: e.to_string(),
        }
    }
}

/// One open transaction on either back end. SQL uses `?` placeholders.
pub(crate) trait Tx {
    /// Runs a statement; returns the rows changed.
    fn exec(&mut self, sql: &str, params: &[SqlValue]) -> Result<u64, Raw>;
    /// Runs a query; returns every row.
    fn rows(&mut self, sql: &str, params: &[SqlValue]) -> Result<Vec<Vec<SqlValue>>, Raw>;
    /// Runs a query and hands each row to `f` in turn (for long results: no row is
    /// kept after `f` returns).
    fn each_row(
        &mut self,
        sql: &str,
        params: &[SqlValue],
        f: &mut dyn FnMut(&[SqlValue]) -> Result<(), Raw>,
    ) -> Result<(), Raw> {
        for r in self.rows(sql, params)? {
            f(&r)?;
        }
        Ok(())
    }
    /// Runs an `INSERT` into a table with an `id` key; returns the new id.
    fn insert_id(&mut self, sql: &str, params: &[SqlValue]) -> Result<i64, Raw>;
    /// Inserts many rows into `table` (`columns` in order).
    fn insert_many(
        &mut self,
        table: &str,
        columns: &[&str],
        rows: &[Vec<SqlValue>],
    ) -> Result<(), Raw>;
    /// Which back end this is.
    fn dialect(&self) -> Dialect;
}

/// The SQL dialect of a back end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dialect {
    /// SQLite 3.
    Sqlite,
    /// PostgreSQL.
    Postgres,
}

impl rusqlite::ToSql for SqlValue {
    fn to_sql(&self) -> rusqlite::Result<rusqlite::types::ToSqlOutput<'_>> {
        use rusqlite::types::{ToSqlOutput, ValueRef};
        Ok(match self {
            SqlValue::Null => ToSqlOutput::Borrowed(ValueRef::Null),
            SqlValue::Int(i) => ToSqlOutput::Borrowed(ValueRef::Integer(*i)),
            SqlValue::Real(r) => ToSqlOutput::Borrowed(ValueRef::Real(*r)),
            SqlValue::Text(s) => ToSqlOutput::Borrowed(ValueRef::Text(s.as_bytes())),
        })
    }
}

pub(crate) fn sqlite_value(v: rusqlite::types::ValueRef<'_>) -> SqlValue {
    use rusqlite::types::ValueRef;
    match v {
        ValueRef::Null => SqlValue::Null,
        ValueRef::Integer(i) => SqlValue::Int(i),
        ValueRef::Real(r) => SqlValue::Real(r),
        ValueRef::Text(t) => SqlValue::Text(String::from_utf8_lossy(t).into_owned()),
        ValueRef::Blob(b) => SqlValue::Text(format!("<{} bytes>", b.len())),
    }
}

/// A SQLite transaction.
pub(crate) struct SqliteTx<'a>(pub rusqlite::Transaction<'a>);

pub(crate) fn sqlite_rows(
    conn: &rusqlite::Connection,
    sql: &str,
    params: &[SqlValue],
) -> Result<Vec<Vec<SqlValue>>, Raw> {
    let mut stmt = conn.prepare_cached(sql)?;
    let n = stmt.column_count();
    let mut rows = stmt.query(rusqlite::params_from_iter(params.iter()))?;
    let mut out = Vec::new();
    while let Some(row) = rows.next()? {
        out.push(
            (0..n)
                .map(|i| row.get_ref(i).map(sqlite_value))
                .collect::<Result<_, _>>()?,
        );
    }
    Ok(out)
}

impl Tx for SqliteTx<'_> {
    fn exec(&mut self, sql: &str, params: &[SqlValue]) -> Result<u64, Raw> {
        let mut stmt = self.0.prepare_cached(sql)?;
        Ok(stmt.execute(rusqlite::params_from_iter(params.iter()))? as u64)
    }

    fn rows(&mut self, sql: &str, params: &[SqlValue]) -> Result<Vec<Vec<SqlValue>>, Raw> {
        sqlite_rows(&self.0, sql, params)
    }

    fn each_row(
        &mut self,
        sql: &str,
        params: &[SqlValue],
        f: &mut dyn FnMut(&[SqlValue]) -> Result<(), Raw>,
    ) -> Result<(), Raw> {
        let mut stmt = self.0.prepare_cached(sql)?;
        let n = stmt.column_count();
        let mut rows = stmt.query(rusqlite::params_from_iter(params.iter()))?;
        // One row buffer for the whole result; text columns reuse their strings.
        let mut buf = vec![SqlValue::Null; n];
        while let Some(row) = rows.next()? {
            for (i, slot) in buf.iter_mut().enumerate() {
                use rusqlite::types::ValueRef;
                match (row.get_ref(i)?, slot) {
                    (ValueRef::Text(t), SqlValue::Text(s)) => {
                        s.clear();
                        s.push_str(&String::from_utf8_lossy(t));
                    }
                    (v, slot) => *slot = sqlite_value(v),
                }
            }
            f(&buf)?;
        }
        Ok(())
    }

    fn insert_id(&mut self, sql: &str, params: &[SqlValue]) -> Result<i64, Raw> {
        self.exec(sql, params)?;
        Ok(self.0.last_insert_rowid())
    }

    fn insert_many(
        &mut self,
        table: &str,
        columns: &[&str],
        rows: &[Vec<SqlValue>],
    ) -> Result<(), Raw> {
        // Multi-row VALUES: one statement step per chunk amortizes SQLite's per-step
        // setup (about twice as fast as a row per step for 10,000 poses).
        const CHUNK: usize = 64;
        let one = format!("({})", vec!["?"; columns.len()].join(", "));
        let sql_for = |n: usize| {
            format!(
                "INSERT INTO {table} ({}) VALUES {}",
                columns.join(", "),
                vec![one.as_str(); n].join(", ")
            )
        };
        for chunk in rows.chunks(CHUNK) {
            let mut stmt = self.0.prepare_cached(&sql_for(chunk.len()))?;
            stmt.execute(rusqlite::params_from_iter(chunk.iter().flatten()))?;
        }
        Ok(())
    }

    fn dialect(&self) -> Dialect {
        Dialect::Sqlite
    }
}
