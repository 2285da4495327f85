//! `fitup watch` as a subprocess: every save of the script, the document or a mesh the
//! script read gives exactly one rerun; a save during a run cancels it.

use crate::common;

use common::{copy_tree, Watch};

use std::path::Path;
use std::time::Duration;

/// A bound on hangs while waiting for a watch line, not a speed assertion.
const BOUND: Duration = Duration::from_secs(20);

/// How many runs started among `lines`.
fn runs_started(lines: &[String]) -> usize {
    lines.iter().filter(|l| l.starts_with("== run ")).count()
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
    w.out.wait_for("== done 1 ok", BOUND);
    assert!(
        w.out.seen.iter().any(|l| l == "tag one 8"),
        "{:?}",
        w.out.seen
    );

    // 1. The script, written in place.
    std::fs::write(&script, body("two")).unwrap();
    w.out.wait_for("== done 2", BOUND);
    let after = w.out.quiet(SETTLE);
    assert_eq!(
        runs_started(&after),
        0,
        "extra rerun after an in-place save: {after:?}"
    );
    assert!(w.out.seen.iter().any(|l| l == "tag two 8"));

    // 2. The script, saved by rename (temporary file + rename).
    save_by_rename(&script, &body("three"));
    w.out.wait_for("== done 3", BOUND);
    assert_eq!(
        runs_started(&w.out.quiet(SETTLE)),
        0,
        "extra rerun after a rename save"
    );
    assert!(w.out.seen.iter().any(|l| l == "tag three 8"));

    // 3. The document.
    let yaml_path = p.join("models/cell.yaml");
    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    std::fs::write(
        &yaml_path,
        yaml.replacen("description: '", "description: 'edited ", 1),
    )
    .unwrap();
    let header = w.out.wait_for("== run 4", BOUND);
    assert!(header.contains("cell.yaml"), "{header}");
    w.out.wait_for("== done 4", BOUND);
    assert_eq!(
        runs_started(&w.out.quiet(SETTLE)),
        0,
        "extra rerun after a document save"
    );

    // 4. A mesh the run read (through the document).
    let screw = fitup::mesh::Mesh::cylinder(4.0, 12.0, 16);
    fitup::mesh::write_stl(&p.join("models/meshes/screw.stl"), &screw).unwrap();
    let header = w.out.wait_for("== run 5", BOUND);
    assert!(header.contains("screw.stl"), "{header}");
    w.out.wait_for("== done 5", BOUND);
    assert_eq!(
        runs_started(&w.out.quiet(SETTLE)),
        0,
        "extra rerun after a mesh save"
    );

    // 5. A save that does not change the content: no rerun.
    std::fs::write(&script, body("three")).unwrap();
    assert_eq!(
        runs_started(&w.out.quiet(SETTLE)),
        0,
        "rerun without a content change"
    );

    // 6. An error keeps the watcher going, and the next good save runs.
    std::fs::write(&script, "let x = ;\n").unwrap();
    w.out.wait_for("== done 6 error", BOUND);
    std::fs::write(&script, body("four")).unwrap();
    w.out.wait_for("== done 7 ok", BOUND);
}

#[test]
fn files_the_script_did_not_read_do_not_trigger() {
    let dir = common::project();
    let p = dir.path();
    std::fs::write(p.join("scripts/plain.rhai"), "print(\"hello\");\n").unwrap();
    let mut w = Watch::start(p, "scripts/plain.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);
    let yaml_path = p.join("models/cell.yaml");
    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    std::fs::write(&yaml_path, yaml + "\n").unwrap();
    std::fs::write(p.join("scripts/other.rhai"), "print(1);\n").unwrap();
    assert_eq!(runs_started(&w.out.quiet(SETTLE)), 0);
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
    w.out.wait_for("spinning", BOUND);
    std::thread::sleep(Duration::from_millis(300));
    std::fs::write(&script, "print(\"fixed\");\n").unwrap();
    w.out.wait_for("== done 1 cancelled", BOUND);
    w.out.wait_for("== done 2 ok", BOUND);
    assert!(w.out.seen.iter().any(|l| l == "fixed"));
}

/// A script whose first and last lines print the tag, so a run of a half-written file
/// shows.
fn tagged(tag: &str) -> String {
    format!(
        "print(\"begin {tag}\");\nlet d = open_doc(\"models/cell.yaml\");\nlet n = d.components().len();\nprint(\"end {tag} \" + n);\n"
    )
}

/// Writes `text` in two parts with a pause, the way a slow editor or a large file does.
fn write_slowly(path: &Path, text: &str) {
    use std::io::Write;
    let mut f = std::fs::File::create(path).unwrap();
    let (a, b) = text.split_at(text.len() / 2);
    f.write_all(a.as_bytes()).unwrap();
    f.flush().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    f.write_all(b.as_bytes()).unwrap();
}

/// Counts runs and checks each one saw the complete script (`end TAG` printed).
fn assert_one_complete_run(w: &mut Watch, number: u64, tag: &str, how: &str) {
    w.out.wait_for(&format!("== done {number}"), BOUND);
    let after = w.out.quiet(Duration::from_millis(1500));
    assert_eq!(
        runs_started(&after),
        0,
        "{how}: more than one run for one save: {:?}",
        w.out.seen
    );
    assert!(
        w.out.seen.iter().any(|l| l == &format!("end {tag} 8")),
        "{how}: the run did not see the complete file: {:?}",
        w.out.seen
    );
    assert!(
        w.out
            .seen
            .iter()
            .any(|l| l.starts_with(&format!("== done {number} ok"))),
        "{how}: {:?}",
        w.out.seen
    );
}

#[test]
fn backup_and_rename_saves_give_one_run_of_the_complete_file() {
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/e.rhai");
    std::fs::write(&script, tagged("first")).unwrap();
    let mut w = Watch::start(p, "scripts/e.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);

    // Emacs: rename the original to a backup, create the file, write it, close.
    let backup = p.join("scripts/e.rhai~");
    std::fs::rename(&script, &backup).unwrap();
    std::thread::sleep(Duration::from_millis(30));
    write_slowly(&script, &tagged("emacs"));
    assert_one_complete_run(&mut w, 2, "emacs", "emacs-style save");

    // Vim: probe file `4913`, original renamed to a backup, new file written, backup
    // deleted.
    std::fs::write(p.join("scripts/4913"), "").unwrap();
    std::fs::remove_file(p.join("scripts/4913")).unwrap();
    std::fs::rename(&script, &backup).unwrap();
    write_slowly(&script, &tagged("vim"));
    std::fs::remove_file(&backup).unwrap();
    assert_one_complete_run(&mut w, 3, "vim", "vim-style save");

    // In place, slowly (truncate, write, pause, write).
    write_slowly(&script, &tagged("inplace"));
    assert_one_complete_run(&mut w, 4, "inplace", "in-place save");

    // A temporary file renamed over the original.
    save_by_rename(&script, &tagged("renamed"));
    assert_one_complete_run(&mut w, 5, "renamed", "rename save");

    // Deleted: reported, no run; back with new content: one run.
    std::fs::remove_file(&script).unwrap();
    w.out.wait_for("is gone", BOUND);
    assert_eq!(runs_started(&w.out.quiet(Duration::from_millis(800))), 0);
    std::fs::write(&script, tagged("back")).unwrap();
    assert_one_complete_run(&mut w, 6, "back", "file recreated");
}

#[test]
fn a_project_folder_moved_away_and_recreated_is_watched_again() {
    let parent = tempfile::tempdir().unwrap();
    let proj = parent.path().join("proj");
    let moved = parent.path().join("proj.old");
    let template = common::project();
    copy_tree(template.path(), &proj);
    std::fs::write(proj.join("scripts/r.rhai"), tagged("one")).unwrap();
    let mut w = Watch::start(&proj, "scripts/r.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);

    // Move the whole project away and put an identical copy in its place.
    std::fs::rename(&proj, &moved).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    copy_tree(&moved, &proj);
    w.out.wait_for("is back", BOUND);
    let after = w.out.quiet(Duration::from_millis(1500));
    assert_eq!(
        runs_started(&after),
        0,
        "the same content came back: no run expected: {:?}",
        w.out.seen
    );

    // Saves in the moved-away copy are not the project's any more.
    std::fs::write(moved.join("scripts/r.rhai"), tagged("stale")).unwrap();
    assert_eq!(
        runs_started(&w.out.quiet(Duration::from_millis(1000))),
        0,
        "{:?}",
        w.out.seen
    );

    // A save in the new folder: exactly one run, of the new content.
    std::fs::write(proj.join("scripts/r.rhai"), tagged("two")).unwrap();
    assert_one_complete_run(&mut w, 2, "two", "save after the folder came back");
    // And the document, in its recreated folder, is watched too.
    let yaml_path = proj.join("models/cell.yaml");
    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    std::fs::write(
        &yaml_path,
        yaml.replacen("description: '", "description: 'edited ", 1),
    )
    .unwrap();
    let header = w.out.wait_for("== run 3", BOUND);
    assert!(header.contains("cell.yaml"), "{header}");
}

#[test]
fn an_import_cycle_under_watch_is_an_error_run_not_a_crash() {
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/c.rhai");
    std::fs::write(p.join("scripts/lib.rhai"), "fn one() { 1 }\n").unwrap();
    std::fs::write(
        &script,
        "import \"lib\" as l;\nprint(\"sum \" + l::one());\n",
    )
    .unwrap();
    let mut w = Watch::start(p, "scripts/c.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);
    // The library imports the script: a cycle.
    std::fs::write(
        p.join("scripts/lib.rhai"),
        "import \"c\" as c;\nfn one() { 1 }\n",
    )
    .unwrap();
    w.out.wait_for("import cycle", BOUND);
    w.out.wait_for("== done 2 error", BOUND);
    std::fs::write(p.join("scripts/lib.rhai"), "fn one() { 2 }\n").unwrap();
    w.out.wait_for("== done 3 ok", BOUND);
    assert!(w.out.seen.iter().any(|l| l == "sum 2"), "{:?}", w.out.seen);
}

#[test]
fn script_arguments_reach_every_run() {
    let dir = common::project();
    let p = dir.path();
    let script = p.join("scripts/a.rhai");
    std::fs::write(&script, "print(`n is ${args.n}`);\n").unwrap();
    let mut w = Watch::start(p, "scripts/a.rhai", &["--", "n=7"]);
    w.out.wait_for("n is 7", BOUND);
    std::fs::write(&script, "print(`n+1 is ${args.n + 1}`);\n").unwrap();
    w.out.wait_for("n+1 is 8", BOUND);
}

/// A `.gltf` part's `.bin` buffer is a file the run read: saving it reruns the script
/// (the buffer is among the document's source files), and the rerun sees the new mesh.
#[test]
fn a_saved_gltf_buffer_reruns_the_script() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    let block = |x: f64| {
        fitup::mesh::Mesh::cuboid(
            fitup::math::Point3::origin(),
            fitup::math::Point3::new(x, 10.0, 5.0),
        )
    };
    let (mut json, bin) = crate::mesh_formats::gltf_parts(&block(20.0));
    std::fs::write(p.join("block.bin"), &bin).unwrap();
    json["buffers"][0]["uri"] = "block.bin".into();
    std::fs::write(
        p.join("block.gltf"),
        serde_json::to_vec_pretty(&json).unwrap(),
    )
    .unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        "parts:\n  block:\n    stl: block.gltf\ncomponents:\n  - {name: block-1, part: block}\n",
    )
    .unwrap();
    std::fs::write(
        p.join("w.rhai"),
        "let d = open_doc(\"cell.yaml\");\nlet b = d.component(\"block-1\").aabb();\nprint(`width ${b.max[0].round()}`);\n",
    )
    .unwrap();
    let mut w = Watch::start(p, "w.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);
    assert!(
        w.out.seen.iter().any(|l| l == "width 20.0"),
        "{:?}",
        w.out.seen
    );
    // Only the buffer changes: the .gltf's own bytes stay the same.
    let (_, wider) = crate::mesh_formats::gltf_parts(&block(40.0));
    assert_eq!(wider.len(), bin.len());
    std::fs::write(p.join("block.bin"), &wider).unwrap();
    let header = w.out.wait_for("== run 2", BOUND);
    assert!(header.contains("block.bin"), "{header}");
    w.out.wait_for("== done 2 ok", BOUND);
    assert!(
        w.out.seen.iter().any(|l| l == "width 40.0"),
        "{:?}",
        w.out.seen
    );
    assert_eq!(runs_started(&w.out.quiet(SETTLE)), 0, "one rerun per save");
}

/// Bytes the process has read so far (Linux `/proc/PID/io`, `rchar`).
#[cfg(target_os = "linux")]
fn bytes_read(pid: u32) -> u64 {
    let io = std::fs::read_to_string(format!("/proc/{pid}/io")).unwrap();
    io.lines()
        .find_map(|l| l.strip_prefix("rchar: "))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

/// An idle watch reads nothing: its own reads of a dependency (hashing it, the run
/// reading it) are not saves. They used to re-arm the fallback timer, so every
/// dependency was read again every 300 ms for as long as the watch ran.
#[cfg(target_os = "linux")]
#[test]
fn an_idle_watch_does_not_read_its_dependencies_again() {
    let dir = common::project();
    let p = dir.path();
    // A 1 MB script (comments): one read of it is plain in the process's read count.
    let mut text =
        "// padding padding padding padding padding padding padding padding\n".repeat(16_000);
    text.push_str(&tagged("big"));
    let size = text.len() as u64;
    std::fs::write(p.join("scripts/big.rhai"), &text).unwrap();
    let mut w = Watch::start(p, "scripts/big.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);
    // Let the events of the first run's reads settle, then count what an idle watch reads.
    w.out.quiet(Duration::from_millis(1500));
    let pid = w.process.0.id();
    let before = bytes_read(pid);
    assert_eq!(runs_started(&w.out.quiet(Duration::from_millis(3500))), 0);
    let idle = bytes_read(pid) - before;
    assert!(
        idle < size / 2,
        "an idle watch read {idle} bytes in 3.5 s (the script is {size} bytes)"
    );
    // And it still sees a save.
    std::fs::write(p.join("scripts/big.rhai"), text.replace("big", "again")).unwrap();
    assert_one_complete_run(&mut w, 2, "again", "save after idling");
}
