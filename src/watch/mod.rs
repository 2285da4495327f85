//! Watch mode: rerun a script whenever the script, its document or any file the last
//! run read is saved — exactly once per save.
//!
//! How a save is recognised, quickly and once:
//! - the *folders* of the dependencies are watched, not the files, so editors that save
//!   by writing a temporary file and renaming it over the original are seen;
//! - a rerun starts as soon as the writer closes the file (inotify's close-write) or a
//!   rename lands on it; a bare "modified" event (which on Linux arrives before the
//!   writer is done) only arms a fallback timer ([`MODIFY_FALLBACK`], re-armed by every further modification);
//!   opening or reading a file (the run's reads, the watcher's own) is no news at all;
//! - a file counts as changed only when its content hash differs from the one the last
//!   run saw, so duplicate events, `touch`, and the run's own writes trigger nothing;
//! - a file that is missing or empty when checked is given [`MODIFY_FALLBACK`] to come
//!   back: editors that save by renaming the original to a backup, creating the file
//!   and writing it (Emacs, Vim) give one run of the complete content, not a run of the
//!   missing or empty file. A file still missing after that is reported and waited for;
//! - a newly created file is read at its writer's close, not at its creation (when it
//!   is still empty);
//! - every watched folder is checked every [`FOLDER_POLL`]: a folder renamed away,
//!   deleted or replaced (the project folder moved and recreated) is reported and
//!   watched again when it is back, and its files are compared with what the last run
//!   saw. Events from a folder that was moved away are ignored (inotify keeps reporting
//!   them under the old name).
//!
//! A save while a run is in progress cancels that run (the engine checks the flag
//! between operations) and starts a new one.

use crate::fsutil::content_hash;
use crate::project::Project;
use crate::script::{run_script, Caches, RunOptions, RunOutcome};
use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind, RenameMode};
use notify::{RecursiveMode, Watcher as _};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long a bare "modified" event waits for the writer's close before the file is
/// checked anyway (writers that keep the file open, network file systems). Long
/// enough that a writer stalled between two writes by a busy machine (a build running
/// beside the watch) is not read half-way; every editor closes the file, which starts
/// the run at once.
pub const MODIFY_FALLBACK: Duration = Duration::from_millis(1000);

/// How soon a file a run is writing ([`crate::script::Caches::writing`]) is looked at
/// again.
const OWN_WRITE_RECHECK: Duration = Duration::from_millis(20);

/// How often watched folders are checked for having been moved, deleted or replaced.
pub const FOLDER_POLL: Duration = Duration::from_millis(200);

/// What the watcher reports to its user interface.
pub enum WatchEvent<'a> {
    /// A run starts; `changed` lists what triggered it (empty for the first run).
    RunStarted {
        /// 1-based run number.
        number: u64,
        /// Files whose content changed.
        changed: &'a [PathBuf],
    },
    /// A run ended (or was cancelled by a newer save).
    RunFinished {
        /// 1-based run number.
        number: u64,
        /// The outcome.
        outcome: &'a RunOutcome,
    },
    /// The watcher itself hit a problem (a folder could not be watched…); it goes on.
    Warning(String),
    /// Something the user should know that is not a problem (a folder is back).
    Notice(String),
}

/// Identity of a folder (device and inode on Unix), to tell a folder from a new one
/// created under the same name.
type FolderId = (u64, u64);

#[cfg(unix)]
fn folder_id(dir: &Path) -> Option<FolderId> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(dir)
        .ok()
        .filter(|m| m.is_dir())
        .map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn folder_id(dir: &Path) -> Option<FolderId> {
    // Without inodes a replaced folder is only seen when it goes missing.
    dir.is_dir().then_some((0, 0))
}

enum Msg {
    Fs(notify::Result<notify::Event>),
    Done(u64, RunOutcome),
}

/// Runs `opts.script` now and again after every save of a dependency, until `stop` is
/// set. `report` receives run headers and outcomes.
pub fn watch(
    opts: RunOptions,
    stop: Arc<AtomicBool>,
    report: impl FnMut(WatchEvent),
) -> notify::Result<()> {
    watch_with(opts, Arc::new(Caches::default()), stop, report)
}

/// [`watch`] with caches the caller made (e.g. with a viewer session: every run logs
/// to `caches.view`, which the caller switches to a new recording on each
/// [`WatchEvent::RunStarted`]).
pub fn watch_with(
    opts: RunOptions,
    caches: Arc<Caches>,
    stop: Arc<AtomicBool>,
    mut report: impl FnMut(WatchEvent),
) -> notify::Result<()> {
    let (tx, rx) = channel::<Msg>();
    let fs_tx = tx.clone();
    let mut watcher = notify::recommended_watcher(move |e| {
        let _ = fs_tx.send(Msg::Fs(e));
    })?;
    // Every watched folder and its identity when it was watched (None while missing).
    let mut watched_dirs: BTreeMap<PathBuf, Option<FolderId>> = BTreeMap::new();
    // Content hash of every dependency as the current run saw it.
    let mut baseline: HashMap<PathBuf, Option<u64>> = HashMap::new();
    // Files with news, and when each may be read: at once after its writer closed it
    // or a rename landed on it, MODIFY_FALLBACK after any other event (re-armed).
    let mut pending: BTreeMap<PathBuf, Instant> = BTreeMap::new();
    // Files found missing or empty, and since when: given MODIFY_FALLBACK to settle.
    let mut settling: HashMap<PathBuf, Instant> = HashMap::new();
    // Files reported missing (reported once; the run waits for them).
    let mut missing: BTreeSet<PathBuf> = BTreeSet::new();
    let mut last_poll = Instant::now();
    let mut number = 0u64;
    let mut running: Option<(u64, Arc<AtomicBool>)> = None;
    let mut queued: Option<Vec<PathBuf>> = Some(Vec::new());
    let always: Vec<PathBuf> = std::iter::once(opts.script.clone())
        .chain(opts.doc.clone())
        .map(|p| absolute(&p))
        .collect();
    for p in &always {
        baseline.insert(p.clone(), hash_file(&opts.project, &always, p));
        // Watched before the first run ends, so a save can cancel a first run that spins.
        if let Some(dir) = p.parent() {
            if !watched_dirs.contains_key(dir) {
                watcher.watch(dir, RecursiveMode::NonRecursive)?;
                watched_dirs.insert(dir.to_path_buf(), folder_id(dir));
            }
        }
    }

    loop {
        if stop.load(Ordering::Relaxed) {
            if let Some((_, c)) = &running {
                c.store(true, Ordering::Relaxed);
            }
            return Ok(());
        }
        // Start the queued run once the previous one has stopped.
        if running.is_none() {
            if let Some(changed) = queued.take() {
                number += 1;
                for p in &changed {
                    baseline.insert(p.clone(), hash_file(&opts.project, &always, p));
                }
                report(WatchEvent::RunStarted {
                    number,
                    changed: &changed,
                });
                let cancel = Arc::new(AtomicBool::new(false));
                let mut run_opts = opts.clone();
                run_opts.cancel = cancel.clone();
                let (tx, caches) = (tx.clone(), caches.clone());
                let n = number;
                std::thread::spawn(move || {
                    let outcome = run_script(&run_opts, &caches);
                    let _ = tx.send(Msg::Done(n, outcome));
                });
                running = Some((number, cancel));
            }
        }
        // Folders moved away, deleted or replaced: watch them again when they are back.
        if last_poll.elapsed() >= FOLDER_POLL {
            last_poll = Instant::now();
            for (dir, id) in watched_dirs.iter_mut() {
                let now = folder_id(dir);
                if now == *id {
                    continue;
                }
                // The old watch follows the moved folder (or is gone with it).
                let _ = watcher.unwatch(dir);
                match now {
                    None => {
                        report(WatchEvent::Warning(format!(
                            "the folder {} was moved or deleted; waiting for it to come back",
                            dir.display()
                        )));
                        *id = None;
                    }
                    Some(_) => match watcher.watch(dir, RecursiveMode::NonRecursive) {
                        Ok(()) => {
                            report(WatchEvent::Notice(format!(
                                "the folder {} is back (a new folder): watching it again",
                                dir.display()
                            )));
                            *id = now;
                            // Compare its files with what the last run saw.
                            let now = Instant::now();
                            pending.extend(
                                baseline
                                    .keys()
                                    .filter(|f| f.parent() == Some(dir.as_path()))
                                    .map(|f| (f.clone(), now)),
                            );
                        }
                        Err(e) => report(WatchEvent::Warning(format!(
                            "cannot watch {} again: {e}; retrying",
                            dir.display()
                        ))),
                    },
                }
            }
        }
        let next_due = pending.values().min().copied();
        let wait = next_due
            .map(|d| d.saturating_duration_since(Instant::now()))
            .unwrap_or(FOLDER_POLL)
            .min(FOLDER_POLL);
        let msg = if wait.is_zero() {
            Err(RecvTimeoutError::Timeout)
        } else {
            rx.recv_timeout(wait)
        };
        match msg {
            Ok(Msg::Fs(Ok(event))) => {
                // Opening and reading a file (the run reading it, the watcher hashing it)
                // says nothing about its content. Counting those events re-armed the
                // timer by the watcher's own reads: every dependency was read again
                // every MODIFY_FALLBACK, for ever, however big.
                if matches!(event.kind, EventKind::Access(a) if a != AccessKind::Close(AccessMode::Write))
                {
                    continue;
                }
                // A save is complete when its writer closes the file or a rename lands
                // on it; the rename's target is the last path of a "both" event.
                let landed = match event.kind {
                    EventKind::Access(AccessKind::Close(AccessMode::Write)) => event.paths.first(),
                    EventKind::Modify(ModifyKind::Name(RenameMode::To | RenameMode::Both)) => {
                        event.paths.last()
                    }
                    _ => None,
                }
                .map(|p| absolute(p));
                for p in &event.paths {
                    let p = absolute(p);
                    if !baseline.contains_key(&p) {
                        continue;
                    }
                    // Events of a folder that was moved away arrive under its old name.
                    let current = p.parent().is_some_and(|d| {
                        watched_dirs
                            .get(d)
                            .is_some_and(|id| id.is_some() && *id == folder_id(d))
                    });
                    if !current {
                        continue;
                    }
                    // Anything else (created, modified, renamed away, deleted) is a
                    // save in progress: wait for its end, re-armed by every event, so
                    // a file is not read half-written or in the gap of a backup save.
                    let due = if landed.as_ref() == Some(&p) {
                        Instant::now()
                    } else {
                        Instant::now() + MODIFY_FALLBACK
                    };
                    pending.insert(p, due);
                }
            }
            Ok(Msg::Fs(Err(e))) => report(WatchEvent::Warning(format!("file watching: {e}"))),
            Ok(Msg::Done(n, outcome)) => {
                // The run's dependencies become the watched set: script, document, and
                // whatever it read. Its own writes are the new baseline, not a save.
                for f in outcome.files_read.iter().chain(&always) {
                    let f = absolute(f);
                    baseline
                        .entry(f.clone())
                        .or_insert_with(|| hash_file(&opts.project, &always, &f));
                    if let Some(dir) = f.parent() {
                        if !watched_dirs.contains_key(dir) {
                            match watcher.watch(dir, RecursiveMode::NonRecursive) {
                                Ok(()) => {
                                    watched_dirs.insert(dir.to_path_buf(), folder_id(dir));
                                }
                                Err(e) => report(WatchEvent::Warning(format!(
                                    "cannot watch {}: {e}",
                                    dir.display()
                                ))),
                            }
                        }
                    }
                }
                for f in &outcome.files_written {
                    let f = absolute(f);
                    if baseline.contains_key(&f) {
                        baseline.insert(f.clone(), hash_file(&opts.project, &always, &f));
                    }
                }
                report(WatchEvent::RunFinished {
                    number: n,
                    outcome: &outcome,
                });
                if running.as_ref().is_some_and(|(r, _)| *r == n) {
                    running = None;
                }
                // Saves completed during the run were checked when their close or
                // rename arrived; what is still pending is a file being written, left
                // to its close event or the fallback timer.
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        }
        let now = Instant::now();
        let due: Vec<PathBuf> = pending
            .iter()
            .filter(|(_, t)| **t <= now)
            .map(|(p, _)| p.clone())
            .collect();
        if !due.is_empty() {
            let mut changed = Vec::new();
            for p in due {
                pending.remove(&p);
                // The run is writing this file now: its bytes are recorded as the
                // run's own once the write returns; judge it then.
                if caches.writing.lock().is_ok_and(|w| w.contains(&p)) {
                    pending.insert(p, now + OWN_WRITE_RECHECK);
                    continue;
                }
                let hash = hash_file(&opts.project, &always, &p);
                // A run's own write (a script rewriting a file it read, itself even):
                // the new baseline, not a save.
                let own = hash.is_some()
                    && caches
                        .own_writes
                        .lock()
                        .ok()
                        .and_then(|w| w.get(&p).copied())
                        == hash;
                if own {
                    baseline.insert(p.clone(), hash);
                }
                if own || baseline.get(&p).is_none_or(|h| *h == hash) {
                    settling.remove(&p);
                    missing.remove(&p);
                    continue;
                }
                let size = std::fs::metadata(&p).ok().map(|m| m.len());
                if matches!(size, None | Some(0)) {
                    // Missing or empty: mid-save (renamed to a backup, or created and
                    // not yet written). Give it time before believing it.
                    let since = *settling.entry(p.clone()).or_insert(now);
                    if now < since + MODIFY_FALLBACK {
                        pending.insert(p, since + MODIFY_FALLBACK);
                        continue;
                    }
                    if size.is_none() {
                        settling.remove(&p);
                        if missing.insert(p.clone()) {
                            report(WatchEvent::Warning(format!(
                                "{} is gone; the next run starts when it is back",
                                p.display()
                            )));
                        }
                        continue;
                    }
                }
                settling.remove(&p);
                missing.remove(&p);
                changed.push(p);
            }
            if !changed.is_empty() {
                for p in &changed {
                    baseline.insert(p.clone(), hash_file(&opts.project, &always, p));
                }
                if let Some((_, cancel)) = &running {
                    cancel.store(true, Ordering::Relaxed);
                }
                let mut all = queued.take().unwrap_or_default();
                all.extend(changed);
                queued = Some(all);
            }
        }
    }
}

/// The content hash of a watched file: capped, regular files only (a path replaced by
/// a FIFO must not block the watcher); a file inside the project is read through the
/// project folder held open for this read and walked without following a link, so a
/// folder swapped for a link is refused, never followed. A path outside the project is
/// read by its name only when it is one of `named` (the script and document given on
/// the command line): an event or dependency path whose folder was resolved while it
/// was swapped for a link to an outside folder is never read.
fn hash_file(project: &Project, named: &[PathBuf], p: &Path) -> Option<u64> {
    let kind = crate::fsutil::FileKind::Mesh;
    // Watched paths are absolute with their folder canonical as they were recorded: a
    // path under the root is walked from the root as it is (never re-resolved, which
    // would follow a folder swapped for a link). The root is opened again for each
    // hash: a project folder moved away and recreated is watched at its path, not in
    // the moved copy that `project` still holds. The script or document given outside
    // the project is read by its name.
    if p.starts_with(project.root()) {
        Project::new(project.root()).ok()?.read_file(p, kind)
    } else if named.iter().any(|n| n == p) {
        crate::fsutil::read_file(p, kind)
    } else {
        return None;
    }
    .ok()
    .map(|b| content_hash(&b))
}

/// The absolute path with the folder canonicalized (the file itself may be missing
/// mid-save), so event paths and dependency paths compare equal.
fn absolute(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    match (
        abs.parent().and_then(|d| d.canonicalize().ok()),
        abs.file_name(),
    ) {
        (Some(dir), Some(name)) => dir.join(name),
        _ => abs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A watched file whose folder became a link to a folder outside the project is not
    /// hashed through the link (its hash would be the outside file's); a file inside
    /// is hashed as it is.
    #[test]
    fn watched_files_are_hashed_through_the_held_root() {
        let dir = tempfile::tempdir().unwrap();
        let outside = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("real")).unwrap();
        std::fs::write(dir.path().join("real/a.rhai"), "inside").unwrap();
        std::fs::write(outside.path().join("a.rhai"), "outside").unwrap();
        std::os::unix::fs::symlink(outside.path(), dir.path().join("data")).unwrap();
        let project = Project::new(dir.path()).unwrap();
        let root = project.root().to_path_buf();
        assert_eq!(
            hash_file(&project, &[], &root.join("real/a.rhai")),
            Some(content_hash(b"inside"))
        );
        // `data/a.rhai` as the watcher recorded it before `data` was swapped.
        assert_eq!(hash_file(&project, &[], &root.join("data/a.rhai")), None);
        // The outside file as an event path resolved through the link: not read,
        // unless it is the script or document named on the command line.
        let out = outside.path().canonicalize().unwrap().join("a.rhai");
        assert_eq!(hash_file(&project, &[], &out), None);
        assert_eq!(
            hash_file(&project, std::slice::from_ref(&out), &out),
            Some(content_hash(b"outside"))
        );
    }
}
