//! The skill execution log: one row per skill-manager event, written as it happens
//! (schema version 4, table `skill_log`).

use super::backend::SqlValue;
use super::{now_utc, Database, DbError};

/// What happened, as the skill execution log stores it: by its
/// [`name`](SkillEvent::name) (`started`, `finished`, …; the text logs have always held).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SkillEvent {
    /// Connected to the controller.
    Connected,
    /// A skill started.
    Started,
    /// A skill finished.
    Finished,
    /// The controller went away during a skill.
    Interrupted,
    /// Reconnected.
    Reconnected,
    /// Paused.
    Paused,
    /// Resumed.
    Resumed,
    /// A pending skill was edited.
    Edited,
    /// An edit was refused.
    EditRefused,
    /// A manual command ran.
    Manual,
    /// The run stopped on an error.
    Failed,
    /// The user aborted the run.
    Aborted,
    /// Every skill finished.
    Done,
}

impl SkillEvent {
    /// Every event, in table order.
    pub const ALL: [SkillEvent; 13] = [
        Self::Connected,
        Self::Started,
        Self::Finished,
        Self::Interrupted,
        Self::Reconnected,
        Self::Paused,
        Self::Resumed,
        Self::Edited,
        Self::EditRefused,
        Self::Manual,
        Self::Failed,
        Self::Aborted,
        Self::Done,
    ];

    /// The stored name (`connected`, `started`, `finished`, `interrupted`,
    /// `reconnected`, `paused`, `resumed`, `edited`, `edit_refused`, `manual`,
    /// `failed`, `aborted`, `done`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Connected => "connected",
            Self::Started => "started",
            Self::Finished => "finished",
            Self::Interrupted => "interrupted",
            Self::Reconnected => "reconnected",
            Self::Paused => "paused",
            Self::Resumed => "resumed",
            Self::Edited => "edited",
            Self::EditRefused => "edit_refused",
            Self::Manual => "manual",
            Self::Failed => "failed",
            Self::Aborted => "aborted",
            Self::Done => "done",
        }
    }

    /// Parses [`name`](Self::name).
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == s)
    }
}

impl std::fmt::Display for SkillEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

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
    /// What happened; `Err` holds a stored name this build does not know (a log
    /// written by another program), as it is.
    pub event: Result<SkillEvent, String>,
    /// Details for people (the part's new state, a reason).
    pub detail: String,
    /// UTC time (RFC 3339).
    pub created_at: String,
}

impl SkillLogEntry {
    /// The event's stored name (known or not).
    pub fn event_name(&self) -> &str {
        match &self.event {
            Ok(e) => e.name(),
            Err(name) => name,
        }
    }
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
        event: SkillEvent,
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
                    event.name().into(),
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
                    event: {
                        let name = text(&r[5]).unwrap_or_default();
                        SkillEvent::parse(&name).ok_or(name)
                    },
                    detail: text(&r[6]).unwrap_or_default(),
                    created_at: text(&r[7]).unwrap_or_default(),
                })
                .collect())
        })
    }
}
