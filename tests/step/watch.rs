//! `fitup watch` of a `step:` part (feature `step`): the watch test that needs Open
//! CASCADE, here beside the other STEP tests (the rest of the watch tests are
//! tests/it/watch.rs, in the `it` binary).

use crate::common;

use common::Watch;
use std::time::Duration;

/// A bound on hangs while waiting for a watch line, not a speed assertion.
const BOUND: Duration = Duration::from_secs(20);

/// A `step:` part's STEP file is a file the run read: re-exporting it from CAD reruns
/// the script with the new geometry (feature `step`).
#[test]
fn step_part_saved_again_reruns_the_script() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir(p.join("parts")).unwrap();
    let file = p.join("parts/block.step");
    fitup::mesh::step::write_test_step("box", &file).unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        "parts:\n  block:\n    step: parts/block.step\ncomponents:\n  - {name: block-1, part: block}\n",
    )
    .unwrap();
    std::fs::write(
        p.join("w.rhai"),
        "let d = open_doc(\"cell.yaml\");\nlet b = d.component(\"block-1\").aabb();\nprint(`height ${b.max[2].round()}`);\n",
    )
    .unwrap();
    let mut w = Watch::start(p, "w.rhai", &[]);
    w.out.wait_for("== done 1 ok", BOUND);
    assert!(
        w.out.seen.iter().any(|l| l == "height 5.0"),
        "{:?}",
        w.out.seen
    );
    // The CAD re-export: another solid in the same file (written beside, renamed over).
    let tmp = p.join("parts/new.step.part");
    fitup::mesh::step::write_test_step("inch_box", &tmp).unwrap();
    std::fs::rename(&tmp, &file).unwrap();
    let header = w.out.wait_for("== run 2", BOUND);
    assert!(header.contains("block.step"), "{header}");
    w.out.wait_for("== done 2 ok", BOUND);
    assert!(
        w.out.seen.iter().any(|l| l == "height 76.0"),
        "{:?}",
        w.out.seen
    );
}
