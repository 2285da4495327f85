//! The viewer's share of a run: the bundled demo and peg-in-hole examples run through
//! the library (warm caches, as in watch mode) without a viewer and with a serving
//! session (`--view`; no browser attached), interleaved, medians. Run with
//! `cargo bench --bench viewer`.

use fitup::script::{run_script, Arguments, Caches, Limits, Project, RunOptions};
use fitup::viewer::{Session, SessionOptions};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(10);
    let session = Session::start(SessionOptions {
        serve: true,
        ..SessionOptions::default()
    })
    .unwrap();
    println!("| script | rounds | without viewer | with --view | share | viewer catch-up after the run |");
    println!("|---|---|---|---|---|---|");
    for script in ["scripts/demo.rhai", "scripts/peg_in_hole.rhai"] {
        let opts = RunOptions {
            script: root.join(script),
            doc: None,
            project: Project::new(root).unwrap(),
            limits: Limits::default(),
            cancel: Arc::new(AtomicBool::new(false)),
            output: Arc::new(|_| {}),
            args: Arguments::default(),
        };
        let plain = Arc::new(Caches::default());
        let viewed = Arc::new(Caches {
            view: session.viewer(),
            ..Caches::default()
        });
        // Warm both caches (meshes, collision trees, the viewer's converted meshes).
        assert!(run_script(&opts, &plain).result.is_ok());
        session.viewer().new_run("warm-up");
        assert!(run_script(&opts, &viewed).result.is_ok());
        session.viewer().flush(Duration::from_secs(60));
        let (mut without, mut with, mut catch_up) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..rounds {
            let t = Instant::now();
            assert!(run_script(&opts, &plain).result.is_ok());
            without.push(t.elapsed().as_secs_f64() * 1e3);
            session.viewer().new_run(&format!("{script} {i}"));
            let t = Instant::now();
            assert!(run_script(&opts, &viewed).result.is_ok());
            with.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            session.viewer().flush(Duration::from_secs(60));
            catch_up.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (a, b, c) = (
            median(&mut without),
            median(&mut with),
            median(&mut catch_up),
        );
        println!(
            "| {script} | {rounds} | {a:.1} ms | {b:.1} ms | {:+.1} % | {c:.1} ms |",
            (b / a - 1.0) * 100.0
        );
    }
}
