//! Watch mode with assembly sequences (issue 15: "move a part, save, see the new
//! sequence"): `fitup watch` runs a script that prints the wheel's sequence; the
//! document is edited and saved once; exactly one rerun prints the new sequence.

mod common;

use fitup::document::Document;
use fitup::math::{Point3, Transform, Vec3};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

/// `fitup watch SCRIPT` in `dir`, its stdout read line by line.
struct Watch {
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Watch {
    fn start(dir: &Path, script: &str) -> Watch {
        let mut child = common::fitup()
            .current_dir(dir)
            .arg("watch")
            .arg(script)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let (tx, rx) = channel();
        let out = child.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Watch {
            child,
            lines: rx,
            seen: Vec::new(),
        }
    }

    /// Waits until a line contains `needle`; fails with the transcript after 60 s (a
    /// bound on hangs, not a speed assertion).
    fn wait_for(&mut self, needle: &str) {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) => {
                    let hit = l.contains(needle);
                    self.seen.push(l);
                    if hit {
                        return;
                    }
                }
                Err(_) => panic!(
                    "no `{needle}` within 60 s; output:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// What arrives within `d`.
    fn quiet(&mut self, d: Duration) -> Vec<String> {
        let deadline = Instant::now() + d;
        let mut got = Vec::new();
        while let Ok(l) = self
            .lines
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
        {
            self.seen.push(l.clone());
            got.push(l);
        }
        got
    }

    /// The lines of run `n` (between `== run n` and `== done n`).
    fn run_lines(&self, n: usize) -> Vec<String> {
        let start = format!("== run {n}");
        let end = format!("== done {n}");
        self.seen
            .iter()
            .skip_while(|l| !l.starts_with(&start))
            .take_while(|l| !l.starts_with(&end))
            .cloned()
            .collect()
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The tasks a run printed: `part onto base operation dz`.
fn tasks(lines: &[String]) -> Vec<String> {
    lines
        .iter()
        .filter_map(|l| l.strip_prefix("task "))
        .map(str::to_string)
        .collect()
}

#[test]
fn moving_the_parts_and_saving_prints_the_new_sequence_once() {
    let dir = common::project();
    let p = dir.path();
    // A copy of the wheel in the scratch project.
    let root = common::repo();
    std::fs::create_dir_all(p.join("models/meshes")).unwrap();
    std::fs::copy(root.join("models/wheel.yaml"), p.join("models/wheel.yaml")).unwrap();
    for m in ["axis", "gear", "cup"] {
        let f = format!("models/meshes/wheel_{m}.stl");
        std::fs::copy(root.join(&f), p.join(&f)).unwrap();
    }
    std::fs::write(
        p.join("scripts/seq.rhai"),
        "let d = open_doc(\"models/wheel.yaml\");\n\
         let s = d.assembly_sequence();\n\
         print(`order ${s.order}`);\n\
         for t in s.tasks {\n\
         \x20   print(`task ${t.part} onto ${t.base} ${t.operation} dz ${t.mating_direction[2].round()}`);\n\
         }\n",
    )
    .unwrap();
    let mut w = Watch::start(p, "scripts/seq.rhai");
    w.wait_for("== done 1");
    let first = w.run_lines(1);
    assert!(
        first
            .iter()
            .any(|l| l == "order [\"axis\", \"gear\", \"cup\"]"),
        "{first:?}"
    );
    // Seed 003's answer: both parts come down along −Z.
    assert_eq!(
        tasks(&first),
        [
            "gear onto axis insertion dz -1.0",
            "cup onto axis insertion dz -1.0"
        ],
        "{first:?}"
    );

    // Move the parts: the whole wheel turned upside down (180° about X through the
    // origin), saved once through the document API (an atomic rename).
    let path = p.join("models/wheel.yaml");
    let mut doc = Document::open(&path).unwrap();
    let flip =
        Transform::from_rotation_about(Point3::origin(), Vec3::x(), std::f64::consts::PI).unwrap();
    for name in ["axis", "gear", "cup"] {
        let i = doc.component_index(name).unwrap();
        let pose = doc.components()[i].transform.then(&flip);
        doc.set_transform(name, pose).unwrap();
    }
    doc.save().unwrap();

    w.wait_for("== done 2");
    let after = w.quiet(Duration::from_millis(1500));
    assert!(
        !after.iter().any(|l| l.starts_with("== run ")),
        "one save, one rerun: {:?}",
        w.seen
    );
    let second = w.run_lines(2);
    assert!(
        second
            .iter()
            .any(|l| l == "order [\"axis\", \"gear\", \"cup\"]"),
        "{second:?}"
    );
    // The new sequence: the same order, every part now going up along +Z.
    assert_eq!(
        tasks(&second),
        [
            "gear onto axis insertion dz 1.0",
            "cup onto axis insertion dz 1.0"
        ],
        "{second:?}"
    );
}
