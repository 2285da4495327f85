//! Assembly sequence planning timings (`cargo bench --bench sequence`): seed 003's
//! wheel, the fig. 11 cell, and a generated 10-part pegboard with mates (a plate with
//! nine pegs seated in its holes), with mates and from the meshes alone. Medians of 5
//! runs; the goal is 10 parts with mates in ≤ 1 s.

use fitup::document::Document;
use fitup::sequence::{plan_sequence, Mode, SequenceOptions};
use fitup::workspace::SceneCache;
use std::path::Path;
use std::time::Instant;

#[path = "../common/pegboard.rs"]
mod pegboard;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn time(doc: &Document, mode: Mode, threaded: &[&str]) -> (f64, usize, usize) {
    let o = SequenceOptions {
        mode,
        threaded: threaded.iter().map(|s| s.to_string()).collect(),
        ..SequenceOptions::default()
    };
    let mut ms = Vec::new();
    let mut last = None;
    for _ in 0..5 {
        let t = Instant::now();
        let p = plan_sequence(doc, &mut SceneCache::new(), &o).expect("a sequence");
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        last = Some(p);
    }
    let p = last.unwrap();
    (median(ms), p.sweeps, p.best().tasks.len())
}

fn main() {
    let dir = std::env::temp_dir().join(format!("fitup_bench_sequence_{}", std::process::id()));
    let board = pegboard::pegboard(&dir, true);
    let cases: Vec<(&str, Document, &[&str])> = vec![
        (
            "wheel (3 parts)",
            Document::open(Path::new("models/wheel.yaml")).unwrap(),
            &[],
        ),
        (
            "fig. 11 cell (8 parts)",
            Document::open(Path::new("models/cell.yaml")).unwrap(),
            &["screw"],
        ),
        ("pegboard (10 parts)", Document::open(&board).unwrap(), &[]),
    ];
    println!("| assembly | triangles | mode | median | sweeps | tasks |");
    println!("|---|---|---|---|---|---|");
    for (name, doc, threaded) in &cases {
        let tris: usize = (0..doc.components().len())
            .map(|i| doc.mesh_of(i).triangles.len())
            .sum();
        for mode in [Mode::Mates, Mode::Geometry] {
            let (ms, sweeps, tasks) = time(doc, mode, threaded);
            println!(
                "| {name} | {tris} | {} | {ms:.1} ms | {sweeps} | {tasks} |",
                mode.name()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
