//! Assembly sequence planning timings (`cargo bench --bench sequence`): seed 003's
//! wheel, the fig. 11 cell, and a generated 10-part pegboard with mates (a plate with
//! nine pegs seated in its holes), with mates and from the meshes alone. Medians of 5
//! runs; the goal is 10 parts with mates in ≤ 1 s.

use fitup::document::Document;
use fitup::mesh::{write_stl, Mesh};
use fitup::sequence::{plan_sequence, Mode, SequenceOptions};
use fitup::workspace::SceneCache;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// A 3 × 3 pegboard: a 30 mm plate 5 mm thick with nine 4 mm holes and nine pegs
/// seated in them (concentric + coincident under the head), written to `dir`.
fn pegboard(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let (pitch, t, r) = (10.0, 5.0, 2.0);
    let plate = Mesh::perforated_plate(3, 3, pitch, t, r, 4, |_, _| true).unwrap();
    write_stl(&dir.join("plate.stl"), &plate).unwrap();
    let rs = r * (std::f64::consts::PI / 16.0).cos() * 0.97;
    let peg = Mesh::lathe(
        &[
            (0.0, 0.0),
            (rs, 0.0),
            (rs, t),
            (1.6 * r, t),
            (1.6 * r, t + 2.0),
            (0.0, t + 2.0),
        ],
        16,
    )
    .unwrap();
    write_stl(&dir.join("peg.stl"), &peg).unwrap();
    let mut y = String::from(
        "parts:\n  plate:\n    stl: plate.stl\n    planes:\n      top: {point: [0, 0, 5], normal: [0, 0, 1]}\n    axes:\n",
    );
    for i in 0..3 {
        for j in 0..3 {
            let (x, yy) = (pitch * (i as f64 + 0.5), pitch * (j as f64 + 0.5));
            y += &format!("      hole{i}{j}: {{point: [{x}, {yy}, 0], direction: [0, 0, 1]}}\n");
        }
    }
    y += "  peg:\n    stl: peg.stl\n    planes:\n      under_head: {point: [0, 0, 5], normal: [0, 0, -1]}\n    axes:\n      axis: {point: [0, 0, 0], direction: [0, 0, 1]}\n";
    y += "components:\n- {name: plate, part: plate, fixed: true}\n";
    let mut mates = String::from("mates:\n");
    for i in 0..3 {
        for j in 0..3 {
            let (x, yy) = (pitch * (i as f64 + 0.5), pitch * (j as f64 + 0.5));
            y += &format!("- name: peg{i}{j}\n  part: peg\n  transform: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[{x},{yy},0,1]]\n");
            mates += &format!("- {{name: peg{i}{j}_axis, type: concentric, entities: [plate/hole{i}{j}, peg{i}{j}/axis]}}\n");
            mates += &format!("- {{name: peg{i}{j}_seat, type: coincident, entities: [plate/top, peg{i}{j}/under_head]}}\n");
        }
    }
    let path = dir.join("pegboard.yaml");
    std::fs::write(&path, y + mates.as_str()).unwrap();
    path
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
    let board = pegboard(&dir);
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
