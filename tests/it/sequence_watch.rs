//! Watch mode with assembly sequences (issue 15: "move a part, save, see the new
//! sequence"): `fitup watch` runs a script that prints the wheel's sequence; the
//! document is edited and saved once; exactly one rerun prints the new sequence.

use crate::common;

use common::Watch;

use fitup::document::Document;
use fitup::math::{Point3, Transform, Vec3};
use std::time::Duration;

/// A bound on hangs while waiting for a watch line, not a speed assertion.
const BOUND: Duration = Duration::from_secs(60);

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
    common::copy_wheel(p);
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
    let mut w = Watch::start(p, "scripts/seq.rhai", &[]);
    w.out.wait_for("== done 1", BOUND);
    let first = w.out.run(1);
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

    w.out.wait_for("== done 2", BOUND);
    let after = w.out.quiet(Duration::from_millis(1500));
    assert!(
        !after.iter().any(|l| l.starts_with("== run ")),
        "one save, one rerun: {:?}",
        w.out.seen
    );
    let second = w.out.run(2);
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
