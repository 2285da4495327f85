//! The open document's own files are never replaced by an output, not even with
//! `force` / `--force` / `overwrite: true`: every writer that goes through the write
//! rule (the library's `Document::export_glb`, `workspace::export_stl`/`export_glb`,
//! `Document::save_as`; a script's exports, `write_text`, `save_csv`, `save_as`; the
//! command line's `fitup export` and `fitup run PROGRAM --log`) is pointed at the
//! document's YAML, its sub-document, a part's mesh (its own and the sub-document's),
//! its URDF and a URDF link mesh, and at one of them spelled with `..`. Each write is
//! refused as "a source of the open document" naming the file, and every source
//! keeps its bytes; `force` still replaces an earlier output and a user's file that
//! is no source.

use super::{run, sha256_all, unchanged};
use crate::common;
use common::copy_tree;
use fitup::document::{Document, DocumentError, WriteProblem};
use fitup::project::OutputError;
use std::path::Path;

/// The document every test opens: a part, a sub-document with its own part, a URDF
/// robot (its link meshes read by `package://`).
const TOP: &str = "models/urdf/top.yaml";

/// The files `TOP` was read from, as a writer may be given them.
const SOURCES: &[&str] = &[
    TOP,
    "models/urdf/sub/sub.yaml",
    "models/urdf/obstacle.stl",
    "models/meshes/plate_a.stl",
    "models/urdf/fitup_arm6.urdf",
    "models/urdf/meshes/link_1.stl",
    "models/meshes/cell.glb",
    "models/urdf/sub/../obstacle.stl",
    "models/urdf/sub/../../meshes/cell.glb",
];

/// How many of [`SOURCES`] are other spellings of one before them.
const RESPELLED: usize = 2;

/// What every refusal says.
const SOURCE: &str = "a source of the open document";

/// A copy of the repository's models with `TOP` (the obstacle as a part, the
/// cell of `models/cell.yaml` exported as `models/meshes/cell.glb` as another — the
/// one format `fitup export` writes —, the sub-document `sub/sub.yaml` holding
/// plate_a, the URDF arm of `models/urdf/arm6_cell.yaml` placed where its demo
/// program reaches).
fn sourced_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    copy_tree(&common::repo().join("models"), &p.join("models"));
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(p.join("models/urdf/sub")).unwrap();
    std::fs::create_dir_all(p.join("scripts")).unwrap();
    let cell = Document::open(&p.join("models/cell.yaml")).unwrap();
    std::fs::write(p.join("models/meshes/cell.glb"), cell.glb_bytes().unwrap()).unwrap();
    std::fs::write(
        p.join("models/urdf/sub/sub.yaml"),
        "parts:\n  plate:\n    stl: ../../meshes/plate_a.stl\n\
         components:\n- name: plate\n  part: plate\n  fixed: true\n",
    )
    .unwrap();
    std::fs::write(
        p.join(TOP),
        "parts:\n  obstacle:\n    stl: obstacle.stl\n  cell:\n    stl: ../meshes/cell.glb\n\
         assemblies:\n- name: Sub-1\n  file: sub/sub.yaml\n\
         components:\n- name: cell\n  part: cell\n  fixed: true\n\
         - name: obstacle\n  part: obstacle\n  fixed: true\n  transform:\n\
         \x20 - [1.0, 0.0, 0.0, 0.0]\n  - [0.0, 1.0, 0.0, 0.0]\n  - [0.0, 0.0, 1.0, 0.0]\n\
         \x20 - [400.0, -100.0, 1300.0, 1.0]\n\
         robots:\n- name: arm6\n  urdf: fitup_arm6.urdf\n  base:\n\
         \x20 - [1.0, 0.0, 0.0, 0.0]\n  - [0.0, 1.0, 0.0, 0.0]\n  - [0.0, 0.0, 1.0, 0.0]\n\
         \x20 - [0.0, 1500.0, 0.0, 1.0]\n",
    )
    .unwrap();
    dir
}

/// The bytes of every source (by its first spelling).
fn source_bytes(p: &Path) -> Vec<Vec<u8>> {
    SOURCES
        .iter()
        .map(|s| std::fs::read(p.join(s)).unwrap())
        .collect()
}

#[test]
fn the_library_writers_never_replace_a_source_even_with_force() {
    let dir = sourced_project();
    let p = dir.path();
    let mut doc = Document::open(&p.join(TOP)).unwrap();
    // Every source is one of the document's, the `..` spelling aside.
    let files = doc.source_files();
    for s in &SOURCES[..SOURCES.len() - RESPELLED] {
        let want = p.join(s).canonicalize().unwrap();
        assert!(
            files.iter().any(|f| f.canonicalize().unwrap() == want),
            "{s} is not in {files:?}"
        );
    }
    let obstacle = [doc.component_index("obstacle").unwrap()];
    let before = source_bytes(p);
    for s in SOURCES {
        let target = p.join(s);
        let is_source = |e: &DocumentError| {
            matches!(e, DocumentError::Write {
                cause: WriteProblem::Output(OutputError::Source { path }), ..
            } if *path == target)
                && e.to_string().contains(SOURCE)
                && e.to_string().contains(&target.display().to_string())
        };
        let e = doc.export_glb(&target, true).unwrap_err();
        assert!(is_source(&e), "export_glb {s}: {e:?}");
        let e = fitup::workspace::export_stl(&doc, &target, &obstacle, None, true).unwrap_err();
        assert!(is_source(&e), "export_stl {s}: {e:?}");
        let e = fitup::workspace::export_glb(&doc, &target, &obstacle, None, true).unwrap_err();
        assert!(is_source(&e), "workspace::export_glb {s}: {e:?}");
        if *s != TOP {
            // Its own file is its save; a part's geometry file (a mesh, the URDF of
            // the robot's link parts) is `OverMesh`, the rest `Source`.
            let e = doc.save_as(&target).unwrap_err();
            let over_mesh = matches!(e, DocumentError::OverMesh { .. });
            assert!(
                (over_mesh && !s.ends_with(".yaml")) || is_source(&e),
                "save_as {s}: {e:?}"
            );
            assert!(e.to_string().contains(SOURCE), "save_as {s}: {e}");
            assert_eq!(
                doc.path(),
                p.join(TOP).as_path(),
                "save_as {s} kept the document's file"
            );
        }
        assert_eq!(source_bytes(p), before, "after the writes to {s}");
    }
    // `force` still replaces an earlier output, and a user's file that is no source.
    let own = p.join("out/own.glb");
    std::fs::create_dir_all(p.join("out")).unwrap();
    doc.export_glb(&own, false).unwrap();
    doc.export_glb(&own, true).unwrap();
    fitup::workspace::export_glb(&doc, &own, &obstacle, None, true).unwrap();
    let mine = p.join("out/mine.stl");
    std::fs::write(&mine, b"my own notes").unwrap();
    let e = fitup::workspace::export_stl(&doc, &mine, &obstacle, None, false).unwrap_err();
    assert!(e.to_string().contains("refusing"), "{e}");
    assert_eq!(std::fs::read(&mine).unwrap(), b"my own notes");
    let n = fitup::workspace::export_stl(&doc, &mine, &obstacle, None, true).unwrap();
    assert_eq!(std::fs::read(&mine).unwrap().len(), n);
    // And the document still saves over its own file, and saves as a new one.
    doc.save().unwrap();
    doc.save_as(&p.join("models/urdf/top_copy.yaml")).unwrap();
    assert_eq!(
        source_bytes(p)[1..],
        before[1..],
        "the other sources after the saves"
    );
}

#[test]
fn a_scripts_writers_never_replace_a_source_of_a_document_it_has_open() {
    let dir = sourced_project();
    let p = dir.path();
    let before = sha256_all(p);
    let list = SOURCES
        .iter()
        .map(|t| format!("{t:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    // `doc` is the document; `sub` the sub-document opened on its own: a second open
    // document, whose writers must not replace the first one's files either.
    let script = format!(
        r#"let doc = open_doc({TOP:?});
let sub = open_doc("models/urdf/sub/sub.yaml");
let c = doc.component("obstacle");
let traj = doc.robot("arm6").move_joint([10, 0, 0, 0, 0, 0]);
let o = #{{overwrite: true}};
for t in [{list}] {{
    for w in ["doc.export_glb", "doc.export_glb parts", "doc.export_stl", "c.export_stl",
              "c.export_glb", "write_text", "save_csv", "sub.export_glb", "sub.save_as"] {{
        let r = "ok";
        try {{
            if w == "doc.export_glb" {{ doc.export_glb(t, o); }}
            if w == "doc.export_glb parts" {{ doc.export_glb(t, #{{components: ["obstacle"], overwrite: true}}); }}
            if w == "doc.export_stl" {{ doc.export_stl(t, o); }}
            if w == "c.export_stl" {{ c.export_stl(t, o); }}
            if w == "c.export_glb" {{ c.export_glb(t, o); }}
            if w == "write_text" {{ write_text(t, "gone", o); }}
            if w == "save_csv" {{ traj.save_csv(t, o); }}
            if w == "sub.export_glb" {{ sub.export_glb(t, o); }}
            if w == "sub.save_as" {{
                if t != "models/urdf/sub/sub.yaml" {{ sub.save_as(t); }} else {{ r = "skip"; }}
            }}
        }} catch (e) {{
            r = `err ${{e}}`;
        }}
        print(`RESULT ${{w}}|${{t}}|${{r}}`);
    }}
}}
// The document's own save as, over the sub-document or its URDF: refused.
for t in ["models/urdf/sub/sub.yaml", "models/urdf/fitup_arm6.urdf"] {{
    try {{ doc.save_as(t); print(`RESULT doc.save_as|${{t}}|ok`); }}
    catch (e) {{ print(`RESULT doc.save_as|${{t}}|err ${{e}}`); }}
}}
// An earlier output and a user's file that is no source: replaced with overwrite.
doc.export_glb("out/own.glb");
doc.export_glb("out/own.glb", o);
try {{ write_text("out/mine.txt", "fitup"); print("RESULT mine|plain|ok"); }}
catch (e) {{ print(`RESULT mine|plain|err ${{e}}`); }}
write_text("out/mine.txt", "fitup", o);
print(`MINE ${{read_text("out/mine.txt")}}`);
"#
    );
    std::fs::write(p.join("scripts/sources.rhai"), script).unwrap();
    std::fs::create_dir_all(p.join("out")).unwrap();
    std::fs::write(p.join("out/mine.txt"), "user").unwrap();
    let (code, t) = run(p, &["run", "scripts/sources.rhai"]);
    assert_eq!(code, 0, "{t}");
    let results: Vec<(&str, &str, &str)> = t
        .lines()
        .filter_map(|l| l.strip_prefix("RESULT "))
        .map(|l| {
            let mut f = l.splitn(3, '|');
            (f.next().unwrap(), f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    assert_eq!(results.len(), SOURCES.len() * 9 + 2 + 1, "{t}");
    for (w, target, r) in &results {
        if *r == "skip" {
            continue;
        }
        if *w == "mine" {
            assert!(
                r.starts_with("err ") && r.contains("fitup did not write"),
                "{r}"
            );
            continue;
        }
        let file = Path::new(target).file_name().unwrap().to_str().unwrap();
        assert!(
            r.starts_with("err ") && r.contains(SOURCE) && r.contains(file),
            "{w} over {target}: expected a refusal naming it as {SOURCE:?}, got: {r}"
        );
    }
    assert!(t.contains("MINE fitup"), "{t}");
    unchanged(&before, p, "a script's writers with overwrite: true");
    assert!(p.join("out/own.glb").is_file());
}

#[test]
fn the_command_lines_writers_never_replace_a_source_even_with_force() {
    let dir = sourced_project();
    let p = dir.path();
    let prg = "models/urdf/arm6_demo.prg";
    let before = sha256_all(p);
    let mut targets: Vec<&str> = SOURCES.to_vec();
    // `--log` of a program run: the program is the run's source too.
    targets.push(prg);
    for target in &targets {
        let mut cases = vec![vec![
            "run", prg, "--doc", TOP, "--robot", "arm6", "--log", target, "--force",
        ]];
        // `fitup export` writes only `.glb` (other names are a usage error).
        if target.ends_with(".glb") {
            cases.push(vec!["export", TOP, target, "--force"]);
        }
        for args in cases {
            let (code, t) = run(p, &args);
            let file = Path::new(target).file_name().unwrap().to_str().unwrap();
            assert_eq!(code, 1, "{args:?}: {t}");
            assert!(
                t.contains(SOURCE) && t.contains(file) && t.contains("refusing"),
                "{args:?}: expected {file} named as {SOURCE:?} in: {t}"
            );
        }
    }
    unchanged(&before, p, "the command line's writers with --force");
    // --force still replaces an earlier output and a user's file that is no source.
    std::fs::create_dir_all(p.join("out")).unwrap();
    std::fs::write(p.join("out/mine.glb"), "user").unwrap();
    for args in [
        vec!["export", TOP, "out/own.glb"],
        vec!["export", TOP, "out/own.glb", "--force"],
        vec!["export", TOP, "out/mine.glb", "--force"],
        vec![
            "run",
            prg,
            "--doc",
            TOP,
            "--robot",
            "arm6",
            "--log",
            "out/own.csv",
        ],
        vec![
            "run",
            prg,
            "--doc",
            TOP,
            "--robot",
            "arm6",
            "--log",
            "out/own.csv",
            "--force",
        ],
    ] {
        let (code, t) = run(p, &args);
        assert_eq!(code, 0, "{args:?}: {t}");
    }
    assert!(std::fs::read(p.join("out/mine.glb"))
        .unwrap()
        .starts_with(b"glTF"));
}
