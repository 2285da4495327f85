//! Timing a Rhai script as a user runs it, shared by the script benchmarks
//! (`#[path]`-included by `script_overhead`, `robot_script` and `interference`).

use fitup::script::{run_script, Caches, Limits, Project, RunOptions};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

/// Wall time (s) of running `text` as `scripts/bench.rhai` in the project at `root`
/// (fresh caches, no operation limit worth the name, printed lines to stdout).
///
/// # Panics
/// When the script fails (a benchmark must not time an error).
pub fn rhai_seconds(root: &Path, text: &str) -> f64 {
    let script = root.join("scripts/bench.rhai");
    std::fs::write(&script, text).unwrap();
    let opts = RunOptions {
        script,
        doc: None,
        project: Project::new(root).unwrap(),
        limits: Limits {
            max_operations: u64::MAX / 2,
            ..Limits::default()
        },
        cancel: Arc::new(AtomicBool::new(false)),
        output: Arc::new(|l: &str| println!("{l}")),
        args: Default::default(),
    };
    let caches = Arc::new(Caches::default());
    let t = Instant::now();
    run_script(&opts, &caches).result.expect("bench script");
    t.elapsed().as_secs_f64()
}
