//! Watch mode: rerun a script whenever the script, its document or any file the last
//! run read is saved — exactly once per save.
//!
//! How a save is recognised, quickly and once:
//! - the *folders* of the dependencies are watched, not the files, so editors that save
//!   by writing a temporary file and renaming it over the original are seen;
//! - a rerun starts as soon as the writer closes the file (inotify's close-write) or a
//!   rename lands on it; a bare "modified" event (which on Linux arrives before the
//!   writer is done) only arms a fallback timer (300 ms, re-armed by every further modification);
//! - a file counts as changed only when its content hash differs from the one the last
//!   run saw, so duplicate events, `touch`, and the run's own writes trigger nothing.
//!
//! A save while a run is in progress cancels that run (the engine checks the flag
//! between operations) and starts a new one.

use crate::fsutil::content_hash;
use crate::script::{run_script, Caches, RunOptions, RunOutcome};
use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind};
use notify::{RecursiveMode, Watcher as _};
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long a bare "modified" event waits for the writer's close before the file is
/// checked anyway (writers that keep the file open, network file systems).
pub const MODIFY_FALLBACK: Duration = Duration::from_millis(300);

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
    mut report: impl FnMut(WatchEvent),
) -> notify::Result<()> {
    let caches = Arc::new(Caches::default());
    let (tx, rx) = channel::<Msg>();
    let fs_tx = tx.clone();
    let mut watcher = notify::recommended_watcher(move |e| {
        let _ = fs_tx.send(Msg::Fs(e));
    })?;
    let mut watched_dirs: BTreeSet<PathBuf> = BTreeSet::new();
    // Content hash of every dependency as the current run saw it.
    let mut baseline: HashMap<PathBuf, Option<u64>> = HashMap::new();
    let mut pending: BTreeSet<PathBuf> = BTreeSet::new();
    let mut deadline: Option<Instant> = None;
    let mut number = 0u64;
    let mut running: Option<(u64, Arc<AtomicBool>)> = None;
    let mut queued: Option<Vec<PathBuf>> = Some(Vec::new());
    let always: Vec<PathBuf> = std::iter::once(opts.script.clone())
        .chain(opts.doc.clone())
        .map(|p| absolute(&p))
        .collect();
    for p in &always {
        baseline.insert(p.clone(), hash_file(p));
        // Watched before the first run ends, so a save can cancel a first run that spins.
        if let Some(dir) = p.parent() {
            if watched_dirs.insert(dir.to_path_buf()) {
                watcher.watch(dir, RecursiveMode::NonRecursive)?;
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
                    baseline.insert(p.clone(), hash_file(p));
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
        let wait = deadline
            .map(|d| d.saturating_duration_since(Instant::now()))
            .unwrap_or(Duration::from_millis(200));
        let msg = rx.recv_timeout(wait);
        let mut check_now = false;
        match msg {
            Ok(Msg::Fs(Ok(event))) => {
                let relevant: Vec<PathBuf> = event
                    .paths
                    .iter()
                    .map(|p| absolute(p))
                    .filter(|p| baseline.contains_key(p))
                    .collect();
                if !relevant.is_empty() {
                    pending.extend(relevant);
                    match event.kind {
                        EventKind::Access(AccessKind::Close(AccessMode::Write))
                        | EventKind::Create(_)
                        | EventKind::Remove(_)
                        | EventKind::Modify(ModifyKind::Name(_)) => check_now = true,
                        // Re-armed by every further "modified": a writer that is
                        // still writing (or slow under load) is not read half-done.
                        _ => deadline = Some(Instant::now() + MODIFY_FALLBACK),
                    }
                }
            }
            Ok(Msg::Fs(Err(e))) => report(WatchEvent::Warning(format!("file watching: {e}"))),
            Ok(Msg::Done(n, outcome)) => {
                // The run's dependencies become the watched set: script, document, and
                // whatever it read. Its own writes are the new baseline, not a save.
                for f in outcome.files_read.iter().chain(&always) {
                    let f = absolute(f);
                    baseline.entry(f.clone()).or_insert_with(|| hash_file(&f));
                    if let Some(dir) = f.parent() {
                        if watched_dirs.insert(dir.to_path_buf()) {
                            if let Err(e) = watcher.watch(dir, RecursiveMode::NonRecursive) {
                                report(WatchEvent::Warning(format!(
                                    "cannot watch {}: {e}",
                                    dir.display()
                                )));
                            }
                        }
                    }
                }
                for f in &outcome.files_written {
                    let f = absolute(f);
                    if baseline.contains_key(&f) {
                        baseline.insert(f.clone(), hash_file(&f));
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
            Err(RecvTimeoutError::Timeout) => {
                check_now = deadline.is_some_and(|d| Instant::now() >= d)
            }
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        }
        if check_now {
            deadline = None;
            let changed: Vec<PathBuf> = pending
                .iter()
                .filter(|p| baseline.get(*p).is_some_and(|h| *h != hash_file(p)))
                .cloned()
                .collect();
            pending.clear();
            if !changed.is_empty() {
                for p in &changed {
                    baseline.insert(p.clone(), hash_file(p));
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

fn hash_file(p: &Path) -> Option<u64> {
    std::fs::read(p).ok().map(|b| content_hash(&b))
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
