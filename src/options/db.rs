//! The vocabularies of the results database's requests (feature `db`): the filter of
//! `paths` and the limits of `query`. [`PathFilter::query`] and [`Limits::limits`]
//! build the library's [`PathQuery`] and [`QueryLimits`].

use super::{Deprecated, Key, Kind, Options, Vocabulary};
use crate::db::{AskedLimit, DbError, PathQuery, QueryLimits};
use serde::{Deserialize, Serialize};

/// Which stored paths `paths` lists.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PathFilter {
    /// Exactly this name.
    pub name: Option<String>,
    /// Exactly this planner.
    pub planner: Option<String>,
    /// Exactly this component.
    pub component: Option<String>,
    /// Stored at or after this time (UTC, ISO 8601 or a prefix).
    pub since: Option<String>,
    /// Stored by this run.
    pub run: Option<u64>,
}

impl PathFilter {
    /// The library's query.
    pub fn query(&self) -> PathQuery {
        PathQuery {
            name: self.name.clone(),
            planner: self.planner.clone(),
            component: self.component.clone(),
            since: self.since.clone(),
            run_id: self.run.map(|r| i64::try_from(r).unwrap_or(i64::MAX)),
            ..PathQuery::default()
        }
    }
}

const ANY: Option<&str> = Some("any");

impl Options for PathFilter {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "path filter",
        keys: &[
            Key {
                name: "name",
                kind: Kind::Text,
                unit: "",
                meaning: "exactly this name",
                default: ANY,
            },
            Key {
                name: "planner",
                kind: Kind::Text,
                unit: "",
                meaning: "exactly this planner",
                default: ANY,
            },
            Key {
                name: "component",
                kind: Kind::Text,
                unit: "",
                meaning: "exactly this component",
                default: ANY,
            },
            Key {
                name: "since",
                kind: Kind::Text,
                unit: "UTC",
                meaning:
                    "stored at or after this time (ISO 8601, or a prefix such as `2026-11-30`)",
                default: ANY,
            },
            Key {
                name: "run",
                kind: Kind::Count,
                unit: "",
                meaning: "stored by this run (its id)",
                default: ANY,
            },
        ],
        deprecated: &[Deprecated {
            old: "run_id",
            new: "run",
            scale: 1.0,
            until: "fitup 0.2",
        }],
    };
}

/// The limits of one read-only query.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Wall time, s.
    pub max_seconds: f64,
    /// Rows.
    pub max_rows: u64,
    /// Bytes in memory.
    pub max_bytes: u64,
}

impl Default for Limits {
    fn default() -> Self {
        let d = QueryLimits::DEFAULT;
        Self {
            max_seconds: d.time.as_secs_f64(),
            max_rows: d.max_rows as u64,
            max_bytes: d.max_bytes as u64,
        }
    }
}

impl Limits {
    /// The library's limits, checked against [`QueryLimits::MAX`].
    ///
    /// # Errors
    /// [`DbError::QueryLimit`] naming the first limit out of range.
    pub fn limits(&self) -> Result<QueryLimits, DbError> {
        let count = |n: u64| usize::try_from(n).unwrap_or(usize::MAX);
        let max = QueryLimits::MAX.time.as_secs_f64();
        if !(self.max_seconds > 0.0 && self.max_seconds <= max) {
            // Out of range before it becomes a `Duration` (which cannot hold every f64).
            return Err(DbError::QueryLimit {
                asked: AskedLimit::Seconds(self.max_seconds),
            });
        }
        QueryLimits {
            time: std::time::Duration::from_secs_f64(self.max_seconds),
            max_rows: count(self.max_rows),
            max_bytes: count(self.max_bytes),
        }
        .checked()
    }
}

impl Options for Limits {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "query limits",
        keys: &[
            Key {
                name: "max_seconds",
                kind: Kind::Number,
                unit: "s",
                meaning: "wall time the statement may run (more than 0, at most 600)",
                default: None,
            },
            Key {
                name: "max_rows",
                kind: Kind::Count,
                unit: "",
                meaning: "rows the result may hold (at most 1,000,000)",
                default: None,
            },
            Key {
                name: "max_bytes",
                kind: Kind::Count,
                unit: "bytes",
                meaning: "memory the result may take (at most 256 MiB)",
                default: None,
            },
        ],
        deprecated: &[],
    };
}
