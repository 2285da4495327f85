//! Watch latency: from the save of the script to the end of the rerun, with a cached
//! mesh set of ≥ 200k triangles. Run with `cargo bench --bench watch_latency`.
//! With the `viewer` feature a second row runs `fitup watch --view` (a serving viewer
//! session, no browser attached) on the same project.

#[path = "../common/lines.rs"]
mod lines;

use fitup::demo;
use fitup::document::file::{ComponentFile, PartFile};
use fitup::mesh::{write_stl, Mesh};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn main() {
    measure(&[]);
    if cfg!(feature = "viewer") {
        measure(&["--view"]);
    }
}

/// Runs `fitup watch` (with `extra` arguments) on a fresh project and prints the
/// latencies of 60 saves.
fn measure(extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    demo::write_cell(&models).unwrap();
    // A sieve plate: 40 × 40 tiles, each with a hole: ~300k triangles.
    let sieve = Mesh::perforated_plate(40, 40, 10.0, 5.0, 3.0, 8, |_, _| true).unwrap();
    write_stl(&models.join("meshes/sieve.stl"), &sieve).unwrap();
    let mut file = demo::cell_document();
    let triangles: usize = sieve.triangles.len() + 60 + 928 + 640 + 5 * 256;
    file.parts
        .insert("sieve".into(), PartFile::from_stl("meshes/sieve.stl"));
    file.components.push(ComponentFile {
        fixed: true,
        ..ComponentFile::new(
            "sieve",
            "sieve",
            Some(
                fitup::math::Transform::from_translation(fitup::math::Vec3::new(0.0, 0.0, 800.0))
                    .to_matrix(),
            ),
        )
    });
    std::fs::write(models.join("big.yaml"), file.to_yaml().unwrap()).unwrap();
    // the project root: scripts/ resolves `models/…` against it
    std::fs::write(dir.path().join("fitup.toml"), "").unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    let script = dir.path().join("scripts/w.rhai");
    let body = |i: usize| {
        format!("let d = open_doc(\"models/big.yaml\");\nlet s = d.component(\"screw4\");\ns.translate({i}, 0, 0);\nprint(`tag {i} ${{s.aabb().min[0]}}`);\n")
    };
    std::fs::write(&script, body(0)).unwrap();

    let mut child = Command::new(env!("CARGO_BIN_EXE_fitup"))
        .current_dir(dir.path())
        .args(["watch", "scripts/w.rhai"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut out = lines::Lines::read(child.stdout.take().unwrap());
    let mut wait_done = |n: usize| -> Instant {
        let done = format!("== done {n} ");
        let (t, l) = out.wait_timed(&done, Duration::from_secs(60));
        assert!(
            l.starts_with(&done) && l.contains(" ok "),
            "{}",
            out.seen.join("\n")
        );
        t
    };
    let t_first = Instant::now();
    wait_done(1);
    println!(
        "first run (reads {triangles} triangles): {:.1} ms",
        t_first.elapsed().as_secs_f64() * 1e3
    );

    let saves = 60;
    let mut latencies = Vec::new();
    for i in 1..=saves {
        std::thread::sleep(Duration::from_millis(120));
        let text = body(i);
        let t0 = Instant::now();
        if i % 2 == 0 {
            std::fs::write(&script, text).unwrap();
        } else {
            let tmp = script.with_extension("tmp~");
            std::fs::write(&tmp, text).unwrap();
            std::fs::rename(&tmp, &script).unwrap();
        }
        let t1 = wait_done(i + 1);
        latencies.push((t1 - t0).as_secs_f64() * 1e3);
    }
    let _ = child.kill();
    let _ = child.wait();
    let mut sorted = latencies.clone();
    sorted.sort_by(f64::total_cmp);
    let q = |p: f64| sorted[((sorted.len() - 1) as f64 * p).round() as usize];
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("watch latency{}, save → end of rerun, {saves} saves (in-place and rename alternating), {triangles} cached triangles:", if extra.is_empty() { String::new() } else { format!(" with {}", extra.join(" ")) });
    println!(
        "  median {:.1} ms   p95 {:.1} ms   min {:.1} ms   max {:.1} ms",
        q(0.5),
        q(0.95),
        sorted[0],
        sorted[sorted.len() - 1]
    );
    println!("  loadavg: {}", load.trim());
}
