//! Assembly sequence planning timings (`cargo bench --bench sequence`): seed 003's
//! wheel, the fig. 11 cell, and a generated 10-part pegboard with mates (a plate with
//! nine pegs seated in its holes), with mates and from the meshes alone, the 12-part
//! gearbox (`models/gearbox.yaml`), and the pegboard tessellated to ~158 000 triangles
//! from the meshes alone (one run), and issue 26's 25-part duct grid without mates
//! (plain, tessellated to ~460 000 triangles, and the same with each tube one closed
//! surface, one run), and a 17-part duct (2 × 4 tubes) of ~461 000 triangles, the
//! issue's real-product row (10–20 parts, ≤ 500k triangles, ≤ 30 s). Medians of 5
//! runs; the goals are 10 parts
//! with mates in ≤ 1 s and a 10-part mesh-only assembly of 150 000 triangles in ≤ 10 s.
//!
//! `FITUP_BENCH_SEQUENCE=fine` (any part of an assembly's name, e.g. `fine`, `wheel`)
//! runs only the matching rows; the fine pegboard is generated only when it is run.
//! `FITUP_BENCH_SEQUENCE_JSON=DIR` writes each row's last plan as JSON (without its
//! timing) to `DIR/<assembly>-<mode>.json`, to diff the results of two builds.

use fitup::document::Document;
use fitup::sequence::{plan_sequence, Mode, SequenceOptions};
use fitup::workspace::SceneCache;
use std::path::Path;
use std::time::Instant;

#[path = "../common/duct.rs"]
mod duct;
#[path = "../common/pegboard.rs"]
mod pegboard;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Median time (ms) of `runs` calls, sweeps and tasks of the last; the call's own
/// time limit is raised to `limit_ms` so a slow case reports its time, not an error.
/// The last plan's JSON goes to `dump` when given.
fn time(
    doc: &Document,
    mode: Mode,
    threaded: &[&str],
    runs: usize,
    limit_ms: f64,
    dump: Option<&Path>,
) -> (f64, usize, usize) {
    let o = SequenceOptions {
        mode,
        threaded: threaded.iter().map(|s| s.to_string()).collect(),
        time_limit_ms: Some(limit_ms),
        ..SequenceOptions::default()
    };
    let mut ms = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let r = plan_sequence(doc, &mut SceneCache::new(), &o);
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        match r {
            Ok(p) => last = Some(p),
            // A case the limit cuts reports its time and no tasks (the duct grids).
            Err(e) => {
                eprintln!("no sequence: {e}");
                return (median(ms), 0, 0);
            }
        }
    }
    let p = last.unwrap();
    if let Some(path) = dump {
        let mut v = p.to_json_value();
        // Timings and the sweep count differ run to run; the results must not.
        v.as_object_mut()
            .map(|o| (o.remove("time_ms"), o.remove("sweeps")));
        std::fs::write(path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    }
    (median(ms), p.sweeps, p.best().tasks.len())
}

fn main() {
    let dir = std::env::temp_dir().join(format!("fitup_bench_sequence_{}", std::process::id()));
    let filter = std::env::var("FITUP_BENCH_SEQUENCE").unwrap_or_default();
    let json_dir = std::env::var_os("FITUP_BENCH_SEQUENCE_JSON").map(std::path::PathBuf::from);
    if let Some(d) = &json_dir {
        std::fs::create_dir_all(d).unwrap();
    }
    // Name, document (opened only when the row runs), threaded parts.
    type Open = Box<dyn Fn() -> Document>;
    let (d1, d2, d3, d4, d5, d6) = (
        dir.clone(),
        dir.clone(),
        dir.clone(),
        dir.clone(),
        dir.clone(),
        dir.clone(),
    );
    let all: Vec<(&str, Open, &[&str])> = vec![
        (
            "wheel (3 parts)",
            Box::new(|| Document::open(Path::new("models/wheel.yaml")).unwrap()),
            &[],
        ),
        (
            "fig. 11 cell (8 parts)",
            Box::new(|| Document::open(Path::new("models/cell.yaml")).unwrap()),
            &["screw"],
        ),
        (
            "pegboard (10 parts)",
            Box::new(move || Document::open(&pegboard::pegboard(&d1, true)).unwrap()),
            &[],
        ),
        // The mesh-only goal: 10 parts, ~150 000 triangles.
        (
            "fine pegboard (10 parts)",
            Box::new(move || {
                Document::open(&pegboard::pegboard_with(&d2.join("fine"), true, 1200)).unwrap()
            }),
            &[],
        ),
        (
            "gearbox (12 parts)",
            Box::new(|| Document::open(Path::new("models/gearbox.yaml")).unwrap()),
            &[],
        ),
        // Issue 26: 10–20+ parts without mates (a plate, 12 tubes, 12 clips).
        (
            "duct grid (25 parts)",
            Box::new(move || {
                let d = d3.join("duct");
                std::fs::create_dir_all(&d).unwrap();
                Document::open(&duct::duct_grid(&d, 28)).unwrap()
            }),
            &[],
        ),
        // … tessellated to ~460 000 triangles (the issue's ≤ 500k in ≤ 30 s).
        (
            "fine duct grid (25 parts)",
            Box::new(move || {
                let d = d4.join("fine_duct");
                std::fs::create_dir_all(&d).unwrap();
                Document::open(&duct::duct_grid(&d, 800)).unwrap()
            }),
            &[],
        ),
        // The real-product row: 10–20 parts, ≤ 500k triangles, ≤ 30 s
        // (2 × 4 sliced tubes with their clips on the plate, ~461 000 triangles).
        (
            "17-part fine duct grid",
            Box::new(move || {
                let d = d6.join("duct17");
                std::fs::create_dir_all(&d).unwrap();
                Document::open(&duct::duct_grid_of(&d, 1200, 2, 4)).unwrap()
            }),
            &[],
        ),
        // … the tubes as closed surfaces (no faces inside the walls, as CAD
        // tessellates them), ~461 000 triangles.
        (
            "solid fine duct grid (25 parts)",
            Box::new(move || {
                let d = d5.join("solid_duct");
                std::fs::create_dir_all(&d).unwrap();
                Document::open(&duct::duct_grid_solid(&d, 2400)).unwrap()
            }),
            &[],
        ),
    ];
    let cases: Vec<(&str, Document, &[&str])> = all
        .into_iter()
        .filter(|(name, _, _)| name.contains(filter.as_str()))
        .map(|(name, open, threaded)| (name, open(), threaded))
        .collect();
    println!("| assembly | triangles | mode | median | sweeps | tasks |");
    println!("|---|---|---|---|---|---|");
    for (name, doc, threaded) in &cases {
        let tris: usize = (0..doc.components().len())
            .map(|i| doc.mesh_of(i).triangles.len())
            .sum();
        // The duct grids have no mates (the mates mode would plan them the same way).
        let duct = name.contains("duct");
        let fine = name.contains("fine") || duct;
        // The fine pegboard is the mesh-only goal: one run, geometry only.
        let modes: &[Mode] = if fine {
            &[Mode::Geometry]
        } else {
            &[Mode::Mates, Mode::Geometry]
        };
        for &mode in modes {
            // The duct grids within the 30 s, the call's own limit.
            let (runs, limit) = if duct {
                (1, 30_000.0)
            } else if fine {
                (1, 600_000.0)
            } else {
                (5, 30_000.0)
            };
            let dump = json_dir.as_ref().map(|d| {
                let stem: String = name
                    .chars()
                    .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                    .collect();
                d.join(format!("{stem}-{}.json", mode.name()))
            });
            let (ms, sweeps, tasks) = time(doc, mode, threaded, runs, limit, dump.as_deref());
            println!(
                "| {name} | {tris} | {} | {ms:.1} ms | {sweeps} | {tasks} |",
                mode.name()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
