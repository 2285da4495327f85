//! Hostile sizes and numbers through the real binary: steps that would make billions
//! of poses (densify, follow, sweeps, robot motions and programs), URDF numbers beyond
//! the document range, STL files without a surface or with text after `endsolid`.
//!
//! Bounds of every case (not speed assertions: a case far past them is broken): the
//! process ends within [`BOUND`], exits 1 (never 134, an abort), its peak resident
//! memory (VmHWM, read from /proc while it runs) stays under [`MAX_RSS_KB`], the
//! message names the script or file and line and the cap or range; the sha256 of every
//! user file is the same after as before.

use crate::common;
use common::snapshot;

// The bounded run is shared with the STEP tests (tests/common/bounded.rs).
use common::bounded::BOUND;
pub(crate) use common::bounded::{run, run_within, Run};

use common::project;
use std::path::Path;

/// Peak resident memory every case stays under (kB): 500 MB.
const MAX_RSS_KB: u64 = 500 * 1024;

/// Runs `fitup ARGS` and checks the bounds: exit 1 (not an abort, not a kill), within
/// time and memory, every needle in the output, no panic; returns the output.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) -> String {
    let r = run(dir, args);
    let what = args.join(" ");
    // The measured bounds, for `--nocapture`.
    eprintln!("`fitup {what}`: peak {} kB, {:?}", r.peak_kb, r.elapsed);
    assert_eq!(r.code, Some(1), "`fitup {what}`: {}", r.text);
    assert!(
        r.peak_kb < MAX_RSS_KB,
        "`fitup {what}`: peak {} kB",
        r.peak_kb
    );
    assert!(r.elapsed < BOUND, "`fitup {what}`");
    for n in needles {
        assert!(
            r.text.contains(n),
            "`fitup {what}`: expected `{n}` in:\n{}",
            r.text
        );
    }
    assert!(!r.text.contains("panicked"), "`fitup {what}`: {}", r.text);
    r.text
}

/// Lines shared by the path scripts: the screw planned 40 mm up (a straight, free
/// path), as `p`.
const PLANNED: &str = "let doc = open_doc(\"models/cell.yaml\");\nlet s = doc.component(\"screw5\").transform.xyzabc;\nlet p = doc.plan_path(\"screw5\", [s[0], s[1], s[2] + 40.0, s[3], s[4], s[5]]);\n";

/// A document with one catalog arm, `r` (no meshes).
const ROBOT_DOC: &str =
    "robots:\n- name: r\n  catalog: nachi_mz07\n  joints: [0, 0, 0, 0, 45, 0]\n";

/// `path.densify(1e-9)` and `follow(path, 1e-9)` asked for ≈ 10 GB and aborted
/// (rc 134); a stepwise sweep of 1e-12 mm is 4e13 steps. Each is refused at once with
/// the count, the cap and the argument, at the script line.
#[test]
fn tiny_steps_along_paths_and_sweeps_are_refused_by_the_cap() {
    let dir = project();
    let p = dir.path();
    let scripts = [
        ("densify.rhai", "print(p.densify(1e-9).len());\n", "Path.densify: `step` = 0.000000001 would make 40000000001 poses"),
        ("follow.rhai", "doc.component(\"screw5\").follow(p, 1e-9);\n", "`step` = 0.000000001 would make 40000000001 poses"),
        ("follow_quiet.rhai", "doc.component(\"screw5\").follow(p, 1e-7, false);\n", "would make 400000001 poses"),
        (
            "sweep.rhai",
            "print(doc.sweep(\"screw5\", [s[0], s[1], s[2] + 40.0, s[3], s[4], s[5]], #{method: \"step\", step: 1e-12}));\n",
            "`step` = 0.000000000001 would make 40000000000000 steps",
        ),
    ];
    for (name, last, _) in scripts {
        std::fs::write(p.join("scripts").join(name), format!("{PLANNED}{last}")).unwrap();
    }
    let before = snapshot(p);
    for (name, _, needle) in scripts {
        refused(
            p,
            &["run", &format!("scripts/{name}")],
            &[
                &format!("scripts/{name}:4:"),
                needle,
                "more than the cap of 1000000",
            ],
        );
    }
    // Bad steps are refused as such, not as a count.
    for (step, shown) in [("0.0", "0"), ("-1.0", "-1")] {
        std::fs::write(
            p.join("scripts/bad.rhai"),
            format!("{PLANNED}p.densify({step});\n"),
        )
        .unwrap();
        refused(
            p,
            &["run", "scripts/bad.rhai"],
            &[
                "scripts/bad.rhai:4:",
                &format!("`step` must be a finite number > 0, not {shown}"),
            ],
        );
    }
    // Within the cap the same calls work: 40 mm at 0.1 mm is 401 poses.
    std::fs::write(p.join("scripts/ok.rhai"), format!("{PLANNED}print(p.densify(0.1).len());\nprint(doc.component(\"screw5\").follow(p, 0.1, false));\n")).unwrap();
    let r = run(p, &["run", "scripts/ok.rhai"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("401\n401"), "{}", r.text);
    let now = snapshot(p);
    for (path, hash) in &before {
        assert_eq!(now.get(path), Some(hash), "{} changed", path.display());
    }
}

/// Robot programs had 10M samples per move and no total: 20M samples ran past 120 s.
/// The cap is on the whole program (and on one motion from a script): the move that
/// would pass it is named by its line, before its samples are made.
#[test]
fn robot_programs_and_motions_are_capped_in_total() {
    let dir = project();
    let p = dir.path();
    std::fs::write(p.join("models/r.yaml"), ROBOT_DOC).unwrap();
    // 2 × 1e7 samples (60° at 60°/s, 1e-7 s apart).
    std::fs::write(
        p.join("scripts/big.prg"),
        "Interval 0.0000001\nJoint 60 0 0 0 45 0\nJoint 0 0 0 0 45 0\n",
    )
    .unwrap();
    // 2 × 588,236: each move fits, the program does not; line 3 is the one refused.
    std::fs::write(
        p.join("scripts/total.prg"),
        "Interval 0.0000017\nJoint 60 0 0 0 45 0\nJoint 0 0 0 0 45 0\n",
    )
    .unwrap();
    std::fs::write(
        p.join("scripts/prog.rhai"),
        "let d = open_doc(\"models/r.yaml\");\nlet t = d.robot(\"r\").run_program(\"scripts/big.prg\");\nprint(t.len);\n",
    )
    .unwrap();
    std::fs::write(
        p.join("scripts/motion.rhai"),
        "let d = open_doc(\"models/r.yaml\");\nlet r = d.robot(\"r\");\nlet t = r.move_joint([60, 0, 0, 0, 45, 0], #{interval: 1e-9});\n",
    )
    .unwrap();
    let before = snapshot(p);
    refused(
        p,
        &["run", "scripts/big.prg", "--doc", "models/r.yaml"],
        &[
            "scripts/big.prg:2: `interval` = 0.0000001 would make 10000001 samples",
            "cap of 1000000",
        ],
    );
    refused(
        p,
        &["run", "scripts/total.prg", "--doc", "models/r.yaml"],
        &[
            "scripts/total.prg:3: `interval` = 0.0000017 would make 1176474 samples",
            "cap of 1000000",
        ],
    );
    refused(
        p,
        &["run", "scripts/prog.rhai"],
        &[
            "scripts/prog.rhai:2:",
            "scripts/big.prg:2:",
            "cap of 1000000",
        ],
    );
    refused(
        p,
        &["run", "scripts/motion.rhai"],
        &[
            "scripts/motion.rhai:3:",
            "`interval` = 0.000000001 would make 1000000001 samples",
            "cap of 1000000",
        ],
    );
    let now = snapshot(p);
    for (path, hash) in &before {
        assert_eq!(now.get(path), Some(hash), "{} changed", path.display());
    }
}

/// A project with the URDF `r.urdf` (one revolute joint, a link mesh `m.stl`) and a
/// document `models/urdf.yaml` using it (the mesh reaches 1000 m along X); `joint_origin` and `mesh_attrs` are spliced
/// into the joint's `<origin>` and the `<mesh>` element (the joint's origin is on
/// line 4, the mesh on line 8).
fn urdf_project(p: &Path, joint_origin: &str, mesh_attrs: &str) {
    let stl = "solid m\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1000 0 0\nvertex 0 0.01 0\nendloop\nendfacet\nendsolid m\n";
    std::fs::write(p.join("models/m.stl"), stl).unwrap();
    std::fs::write(
        p.join("models/r.urdf"),
        format!(
            "<robot name=\"r\">\n  <link name=\"base\"/>\n  <joint name=\"j1\" type=\"revolute\">\n    <origin {joint_origin}/>\n    <parent link=\"base\"/><child link=\"arm\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\"/>\n  </joint>\n  <link name=\"arm\">\n    <visual><geometry><mesh filename=\"m.stl\" {mesh_attrs}/></geometry></visual>\n  </link>\n</robot>\n"
        ),
    )
    .unwrap();
    std::fs::write(
        p.join("models/urdf.yaml"),
        "robots:\n- name: r\n  urdf: r.urdf\n  joints: [10]\n",
    )
    .unwrap();
}

/// An origin of 1e200 m loaded, saved and reopened; a mesh scale of 1e306 passed
/// `fitup check` and failed later without file or line. Both are refused by
/// `fitup check` at the URDF's line; in range, the same URDF checks fine.
#[test]
fn urdf_numbers_beyond_the_document_range_are_refused_with_file_and_line() {
    let dir = project();
    let p = dir.path();
    let cases = [
        (
            "xyz=\"1e200 0 0\"",
            "",
            "r.urdf:4:",
            "xyz=\"1e200 0 0\": 1e200 is out of range",
        ),
        ("xyz=\"0 0 2e6\"", "", "r.urdf:4:", "mm (metres × 1000)"),
        ("rpy=\"0 0 nan\"", "", "r.urdf:4:", "not finite"),
        (
            "xyz=\"0 0 0.5\"",
            "scale=\"1e306 1 1\"",
            "r.urdf:8:",
            "scale=\"1e306 1 1\": 1e306 is out of range",
        ),
        // Each number in range, the scaled mesh is not: 1000 m × 1e6 × 1000 = 1e12 mm.
        (
            "xyz=\"0 0 0.5\"",
            "scale=\"1e6 1 1\"",
            "r.urdf:8:",
            "beyond the 1e9 mm",
        ),
        ("xyz=\"0 0 0.5\"", "scale=\"0 1 1\"", "r.urdf:8:", "flat"),
    ];
    for (origin, mesh, place, needle) in cases {
        urdf_project(p, origin, mesh);
        let before = snapshot(p);
        refused(p, &["check", "models/urdf.yaml"], &[place, needle]);
        let now = snapshot(p);
        assert_eq!(before, now, "{origin} {mesh}: files changed");
    }
    urdf_project(p, "xyz=\"0 0 0.5\"", "scale=\"2 1 1\"");
    let r = run(p, &["check", "models/urdf.yaml"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
}

/// An STL whose facets all have zero area passed `fitup check` (a warning) and failed
/// later with "the mesh has no triangle of non-zero area", naming no file; text after
/// `endsolid` was ignored. Both are refused by `fitup check` naming the STL and line.
/// A second `solid … endsolid` block (multi-body exporters) is read, not refused.
#[test]
fn stl_without_surface_or_with_trailing_text_is_refused_with_the_file() {
    let dir = project();
    let p = dir.path();
    let screw = p.join("models/meshes/screw.stl");
    let flat = "solid d\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 1 1\nvertex 2 2 2\nendloop\nendfacet\nendsolid d\n";
    let good = "solid g\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid g\n";
    let cases = [
        (flat.to_string(), "screw.stl:2: all 1 facets have zero area"),
        (
            format!("{good}this is not STL\n"),
            "screw.stl:10: `this is not STL` after `endsolid` (line 9)",
        ),
        (
            format!("{good}\n\n{}", "x".repeat(1 << 20)),
            "screw.stl:12: `xxxxxxxx",
        ),
    ];
    for (text, needle) in &cases {
        std::fs::write(&screw, text).unwrap();
        let before = snapshot(p);
        let out = refused(p, &["check", "models/cell.yaml"], &[needle]);
        assert!(
            out.len() < 4000,
            "the message quotes a short excerpt: {} bytes",
            out.len()
        );
        assert_eq!(before, snapshot(p), "files changed");
    }
    // The binary form of the zero-area mesh: named by file.
    let mut bin = vec![0u8; 84 + 50];
    bin[80] = 1;
    for (k, v) in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]
        .iter()
        .enumerate()
    {
        bin[96 + 4 * k..100 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    std::fs::write(&screw, &bin).unwrap();
    refused(
        p,
        &["check", "models/cell.yaml"],
        &["screw.stl: binary STL: all 1 facets have zero area"],
    );
    // Two bodies in one file are read.
    std::fs::write(
        &screw,
        format!("{good}{}", good.replace("vertex 0 ", "vertex 5 ")),
    )
    .unwrap();
    let r = run(p, &["check", "models/cell.yaml"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(
        r.text.contains(" 2 triangles  meshes/screw.stl"),
        "{}",
        r.text
    );
}
