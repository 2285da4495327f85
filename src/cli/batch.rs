//! `fitup batch SCRIPT --docs A.yaml B.yaml …`: the same script run once per document,
//! the runs spread over all cores, each one independent (its own engine, document and
//! database record with `--db`), like `fitup run SCRIPT --doc A.yaml` for each.

use super::out::errln;
use super::{run, Exit, ScriptArgs};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Options of `batch`.
#[derive(Debug, clap::Args, Clone)]
pub struct BatchArgs {
    /// The script and its options, as for `run` (`--doc` is set per run from `--docs`).
    #[command(flatten)]
    pub run: ScriptArgs,
    /// The documents: one independent run of the script per document (`doc` in the
    /// script).
    #[arg(long, num_args = 1.., required = true)]
    pub docs: Vec<PathBuf>,
}

/// Runs the script once per document in parallel; a progress line on standard error
/// every second while runs are left; a summary per failed document. Exit 0 when
/// every run succeeded.
pub(super) fn batch(a: &BatchArgs) -> Exit {
    if a.run.doc.is_some() {
        errln!("error: `batch` takes its documents from `--docs`, not `--doc`");
        return Exit::Usage;
    }
    let total = a.docs.len();
    let done = AtomicUsize::new(0);
    let start = Instant::now();
    // Plain threads, not rayon's pool: a run blocks on its script thread, and the
    // script's own parallel work (collider builds) needs rayon's workers free — runs
    // on the pool's workers deadlock as soon as a script checks interference.
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Exit>> = a.docs.iter().map(|_| Mutex::new(Exit::Ok)).collect();
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(total);
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(d) = a.docs.get(i) else { break };
                let mut one = a.run.clone();
                one.doc = Some(d.clone());
                let exit = run::run(&one);
                *slots[i].lock().unwrap_or_else(|e| e.into_inner()) = exit;
                done.fetch_add(1, Ordering::Relaxed);
            });
        }
        let mut last = Instant::now();
        while done.load(Ordering::Relaxed) < total {
            std::thread::sleep(Duration::from_millis(50));
            if start.elapsed() >= Duration::from_secs(1) && last.elapsed() >= Duration::from_secs(1)
            {
                last = Instant::now();
                errln!(
                    "batch: {}/{total} runs done, {:.0} s",
                    done.load(Ordering::Relaxed),
                    start.elapsed().as_secs_f64()
                );
            }
        }
    });
    let exits: Vec<Exit> = slots
        .into_iter()
        .map(|e| e.into_inner().unwrap_or_else(|e| e.into_inner()))
        .collect();
    let failed: Vec<String> = a
        .docs
        .iter()
        .zip(&exits)
        .filter(|(_, e)| **e != Exit::Ok)
        .map(|(d, _)| d.display().to_string())
        .collect();
    if failed.is_empty() {
        return Exit::Ok;
    }
    errln!(
        "batch: {} of {total} runs failed: {}",
        failed.len(),
        failed.join(", ")
    );
    if exits.contains(&Exit::Usage) {
        Exit::Usage
    } else {
        Exit::Failure
    }
}
