//! The two back ends behind one small transaction interface ([`Tx`]): SQLite through
//! `rusqlite`, PostgreSQL through the synchronous `postgres` client. Everything above
//! this file (schema, records) is written once against [`Tx`] with `?` placeholders.

use postgres::types::{ToSql, Type};

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

/// What went wrong at the back end, before the database's name is attached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// Another writer holds the lock (SQLite busy/locked, PostgreSQL serialization
    /// failure or deadlock): worth retrying.
    Busy,
    /// The file, folder or server refuses writes.
    ReadOnly,
    /// No space left.
    Full,
    /// A write inside a read-only query.
    WriteRefused,
    /// Anything else.
    Other,
}

/// A back-end error: its kind and the driver's message.
#[derive(Debug, Clone)]
pub(crate) struct Raw {
    pub kind: Kind,
    pub message: String,
}

impl Raw {
    pub fn other(message: impl Into<String>) -> Self {
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
        // The server's own message (and detail) says more than the client's summary.
        let message = match e.as_db_error() {
            Some(db) => match db.detail() {
                Some(d) => format!("{} ({d})", db.message()),
                None => db.message().to_string(),
            },
            None => e.to_string(),
        };
        Raw { kind, message }
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

/// `?` placeholders → PostgreSQL's `$1, $2, …` (the SQL in this module has no `?`
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
