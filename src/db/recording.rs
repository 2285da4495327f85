//! The run being recorded by this process (`fitup run`/`watch`): the command line
//! registers it here, and a script's `open_db()` on the same database files its
//! results under it. A run is written to the database when `--db` asks for it, or
//! lazily when the script itself opens the database.

use super::{Database, DbError, NewRun, RunStatus, Target};
use std::sync::Mutex;

struct Active {
    target: Target,
    run: NewRun,
    id: Option<i64>,
}

static ACTIVE: Mutex<Option<Active>> = Mutex::new(None);

fn active() -> std::sync::MutexGuard<'static, Option<Active>> {
    ACTIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Registers the run this process is about to make. With `eager`, the run is written
/// to the database now; otherwise when the script first opens that database.
pub fn begin(target: Target, run: NewRun, eager: bool) -> Result<(), DbError> {
    let id = if eager {
        Some(Database::open(&target)?.start_run(&run)?)
    } else {
        None
    };
    *active() = Some(Active { target, run, id });
    Ok(())
}

/// The id of the recorded run when `db` is its database (writing the run now if it
/// was registered lazily); `None` when no run is recorded there.
pub fn run_id_for(db: &mut Database) -> Result<Option<i64>, DbError> {
    let mut guard = active();
    let Some(a) = guard.as_mut() else {
        return Ok(None);
    };
    if &a.target != db.target() {
        return Ok(None);
    }
    if a.id.is_none() {
        a.id = Some(db.start_run(&a.run)?);
    }
    Ok(a.id)
}

/// Ends the registered run: stores its status and output if it was written, and
/// returns its id.
pub fn finish(status: RunStatus, output: &str) -> Result<Option<i64>, DbError> {
    let Some(a) = active().take() else {
        return Ok(None);
    };
    match a.id {
        Some(id) => {
            Database::open(&a.target)?.finish_run(id, status, output)?;
            Ok(Some(id))
        }
        None => Ok(None),
    }
}
