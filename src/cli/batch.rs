//! `fitup batch SCRIPT --docs A.yaml B.yaml …`: the same script run once per document,
//! the runs spread over all cores, each one independent (its own engine, document and
//! database record with `--db`), like `fitup run SCRIPT --doc A.yaml` for each.

use super::out::errln;
use super::{run, Exit, ScriptArgs};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
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
    let exits: Vec<Exit> = std::thread::scope(|s| {
        let progress = s.spawn(|| {
            let mut last = Instant::now();
            while done.load(Ordering::Relaxed) < total {
                std::thread::sleep(Duration::from_millis(50));
                if start.elapsed() >= Duration::from_secs(1)
                    && last.elapsed() >= Duration::from_secs(1)
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
        let exits = a
            .docs
            .par_iter()
            .map(|d| {
                let mut one = a.run.clone();
                one.doc = Some(d.clone());
                let exit = run::run(&one);
                done.fetch_add(1, Ordering::Relaxed);
                exit
            })
            .collect();
        let _ = progress.join();
        exits
    });
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
