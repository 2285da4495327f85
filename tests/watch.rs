//! `fitup watch` as a subprocess: every save of the script, the document or a mesh the
//! script read gives exactly one rerun; a save during a run cancels it.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

struct Watch {
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Watch {
    fn start(dir: &Path, script: &str, extra: &[&str]) -> Watch {
        let mut child = common::fitup()
            .current_dir(dir)
            .arg("watch")
            .arg(script)
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
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

    /// Waits until a line contains `needle`; panics with the transcript after 20 s.
    fn wait_for(&mut self, needle: &str) -> String {
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) => {
                    self.seen.push(l.clone());
                    if l.contains(needle) {
                        return l;
                    }
                }
                Err(_) => panic!(
                    "no `{needle}` within 20 s; output:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// Collects what arrives within `d`.
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

    fn runs_started(lines: &[String]) -> usize {
        lines.iter().filter(|l| l.starts_with("== run ")).count()
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

const SETTLE: Duration = Duration::from_millis(700);

/// Replaces a file the way many editors do: write a temporary file, then rename it over.
fn save_by_rename(path: &Path, text: &str) {
    let tmp = path.with_extension("swp~");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn each_save_gives_exactly_one_rerun() {
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/w.rhai");
    let body = |tag: &str| {
        format!("let d = open_doc(\"models/cell.yaml\");\nprint(\"tag {tag} \" + d.components().len());\n")
    };
    std::fs::write(&script, body("one")).unwrap();
    let mut w = Watch::start(p, "scripts/w.rhai", &[]);
    w.wait_for("== done 1 ok");
    assert!(w.seen.iter().any(|l| l == "tag one 8"), "{:?}", w.seen);

    // 1. The script, written in place.
    std::fs::write(&script, body("two")).unwrap();
    w.wait_for("== done 2");
    let after = w.quiet(SETTLE);
    assert_eq!(
        Watch::runs_started(&after),
        0,
        "extra rerun after an in-place save: {after:?}"
    );
    assert!(w.seen.iter().any(|l| l == "tag two 8"));

    // 2. The script, saved by rename (temporary file + rename).
    save_by_rename(&script, &body("three"));
    w.wait_for("== done 3");
    assert_eq!(
        Watch::runs_started(&w.quiet(SETTLE)),
        0,
        "extra rerun after a rename save"
    );
    assert!(w.seen.iter().any(|l| l == "tag three 8"));

    // 3. The document.
    let yaml_path = p.join("models/cell.yaml");
    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    std::fs::write(
        &yaml_path,
        yaml.replacen("description: '", "description: 'edited ", 1),
    )
    .unwrap();
    let header = w.wait_for("== run 4");
    assert!(header.contains("cell.yaml"), "{header}");
    w.wait_for("== done 4");
    assert_eq!(
        Watch::runs_started(&w.quiet(SETTLE)),
        0,
        "extra rerun after a document save"
    );

    // 4. A mesh the run read (through the document).
    let screw = fitup::mesh::Mesh::cylinder(4.0, 12.0, 16);
    fitup::mesh::write_stl(&p.join("models/meshes/screw.stl"), &screw).unwrap();
    let header = w.wait_for("== run 5");
    assert!(header.contains("screw.stl"), "{header}");
    w.wait_for("== done 5");
    assert_eq!(
        Watch::runs_started(&w.quiet(SETTLE)),
        0,
        "extra rerun after a mesh save"
    );

    // 5. A save that does not change the content: no rerun.
    std::fs::write(&script, body("three")).unwrap();
    assert_eq!(
        Watch::runs_started(&w.quiet(SETTLE)),
        0,
        "rerun without a content change"
    );

    // 6. An error keeps the watcher going, and the next good save runs.
    std::fs::write(&script, "let x = ;\n").unwrap();
    w.wait_for("== done 6 error");
    std::fs::write(&script, body("four")).unwrap();
    w.wait_for("== done 7 ok");
}

#[test]
fn files_the_script_did_not_read_do_not_trigger() {
    let dir = common::project();
    let p = dir.path();
    std::fs::write(p.join("scripts/plain.rhai"), "print(\"hello\");\n").unwrap();
    let mut w = Watch::start(p, "scripts/plain.rhai", &[]);
    w.wait_for("== done 1 ok");
    let yaml_path = p.join("models/cell.yaml");
    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    std::fs::write(&yaml_path, yaml + "\n").unwrap();
    std::fs::write(p.join("scripts/other.rhai"), "print(1);\n").unwrap();
    assert_eq!(Watch::runs_started(&w.quiet(SETTLE)), 0);
}

#[test]
fn a_save_cancels_the_running_script() {
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/spin.rhai");
    std::fs::write(
        &script,
        "print(\"spinning\");\nlet i = 0;\nloop { i += 1; }\n",
    )
    .unwrap();
    let mut w = Watch::start(
        p,
        "scripts/spin.rhai",
        &["--max-operations", "100000000000"],
    );
    w.wait_for("spinning");
    std::thread::sleep(Duration::from_millis(300));
    std::fs::write(&script, "print(\"fixed\");\n").unwrap();
    w.wait_for("== done 1 cancelled");
    w.wait_for("== done 2 ok");
    assert!(w.seen.iter().any(|l| l == "fixed"));
}
