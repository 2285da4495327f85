//! The skill execution log: one row per skill-manager event, written as it happens
//! (schema version 4, table `skill_log`).

use super::backend::SqlValue;
use super::{now_utc, Database, DbError};

/// One row of the skill execution log.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillLogEntry {
    /// Row id (increasing in time).
    pub id: i64,
    /// The run it belongs to, if recorded with one.
    pub run_id: Option<i64>,
    /// The plan (file name or label).
    pub plan: String,
    /// The skill id, for skill events.
    pub skill: Option<i64>,
    /// The part, when known.
    pub part: Option<String>,
    /// `started`, `finished`, `interrupted`, `reconnected`, `paused`, `resumed`,
    /// `edited`, `manual`, `failed`, `aborted`, `done`, …
    pub event: String,
    /// Details for people (the part's new state, a reason).
    pub detail: String,
    /// UTC time (RFC 3339).
    pub created_at: String,
}

impl Database {
    /// Appends one event to the skill execution log (its own transaction, so it is
    /// on disk when this returns); returns its row id.
    pub fn log_skill_event(
        &mut self,
        run_id: Option<i64>,
        plan: &str,
        skill: Option<usize>,
        part: Option<&str>,
        event: &str,
        detail: &str,
    ) -> Result<i64, DbError> {
        let now = now_utc();
        self.transaction("logging a skill event", |tx| {
            tx.insert_id(
                "INSERT INTO skill_log (run_id, plan, skill, part, event, detail, created_at) VALUES (?, ?, ?, ?, ?, ?, ?)",
                &[
                    run_id.into(),
                    plan.into(),
                    skill.map(|s| s as i64).into(),
                    part.map_or(SqlValue::Null, |p| p.into()),
                    event.into(),
                    detail.into(),
                    now.as_str().into(),
                ],
            )
        })
    }

    /// The skill execution log of `plan` (every plan when `None`), oldest first.
    pub fn skill_log(&mut self, plan: Option<&str>) -> Result<Vec<SkillLogEntry>, DbError> {
        self.read("reading the skill log", |tx| {
            let (sql, p): (&str, Vec<SqlValue>) = match plan {
                Some(p) => (
                    "SELECT id, run_id, plan, skill, part, event, detail, created_at FROM skill_log WHERE plan = ? ORDER BY id",
                    vec![p.into()],
                ),
                None => (
                    "SELECT id, run_id, plan, skill, part, event, detail, created_at FROM skill_log ORDER BY id",
                    vec![],
                ),
            };
            let text = |v: &SqlValue| match v {
                SqlValue::Text(s) => Some(s.clone()),
                _ => None,
            };
            Ok(tx
                .rows(sql, &p)?
                .iter()
                .map(|r| SkillLogEntry {
                    id: r[0].as_i64().unwrap_or_default(),
                    run_id: r[1].as_i64(),
                    plan: text(&r[2]).unwrap_or_default(),
                    skill: r[3].as_i64(),
                    part: text(&r[4]),
                    event: text(&r[5]).unwrap_or_default(),
                    detail: text(&r[6]).unwrap_or_default(),
                    created_at: text(&r[7]).unwrap_or_default(),
                })
                .collect())
        })
    }
}
