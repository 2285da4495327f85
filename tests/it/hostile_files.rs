//! Hostile files, driven through the real binary in temporary projects: paths that
//! escape the project, special files, alias bombs, non-finite and huge numbers, saves
//! over meshes and non-documents, concurrent writers and a writer killed mid-save.
//!
//! Every case must end (the process is killed after 30 s, which fails the test: a
//! bound on hangs, not a speed assertion) with a message naming file and line where
//! there is one, and must leave the user's files exactly as they were.

use crate::common;
use common::{snapshot, Snapshot};

use common::{project, spawn};
use std::path::Path;
use std::process::Child;
use std::time::Duration;

/// Generous bound on any single command: a hang, not slowness, fails.
const HANG: Duration = Duration::from_secs(30);

/// Exit code and combined output of a finished child; fails when it hangs.
fn finish(child: Child, what: &str) -> (i32, String) {
    let o = common::finish(child, what, HANG);
    (o.status.code().unwrap_or(-1), common::text(&o))
}

/// Runs `fitup ARGS` in `dir` with the hang bound.
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    finish(spawn(dir, args), &args.join(" "))
}

/// Every file of `before` is still there with the same content (files the test wrote
/// since are not user files).
fn unchanged(before: &Snapshot, dir: &Path) {
    common::assert_kept(before, &snapshot(dir));
}

/// The 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// A one-part document `models/NAME` whose mesh is `stl`; returns the text.
fn one_part_doc(dir: &Path, name: &str, stl: &str) -> String {
    let text =
        format!("parts:\n  evil:\n    stl: {stl}\ncomponents:\n  - name: e1\n    part: evil\n");
    std::fs::write(dir.join("models").join(name), &text).unwrap();
    text
}

fn write(dir: &Path, rel: &str, text: &str) {
    std::fs::write(dir.join(rel), text).unwrap();
}

#[test]
fn documents_cannot_reach_outside_their_project() {
    let outside = tempfile::tempdir().unwrap();
    let secret = outside.path().join("secret.stl");
    std::fs::write(
        &secret,
        "solid SECRET_MARKER\n  SECRET_LINE_TWO 1 2 3\nendsolid\n",
    )
    .unwrap();
    let dir = project();
    let p = dir.path();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&secret, p.join("models/meshes/link.stl")).unwrap();
    let rel = format!(
        "{}{}/secret.stl",
        std::iter::repeat_n("..", 12).collect::<Vec<_>>().join("/"),
        outside.path().display()
    );
    let mut cases = vec![
        ("relative.yaml", rel),
        ("absolute.yaml", secret.to_string_lossy().into_owned()),
    ];
    if cfg!(unix) {
        cases.push(("symlink.yaml", "meshes/link.stl".into()));
    }
    for (name, stl) in &cases {
        let text = one_part_doc(p, name, stl);
        let line = line_of(&text, "stl:");
        let doc = format!("models/{name}");
        // `fitup check` and a script opening the document say the same.
        write(p, "scripts/open.rhai", &format!("open_doc(\"{doc}\");\n"));
        let before = snapshot(p);
        for args in [
            vec!["check", doc.as_str()],
            vec!["run", "scripts/open.rhai"],
        ] {
            let (code, out) = run(p, &args);
            assert_eq!(code, 1, "{args:?}: {out}");
            assert!(
                out.contains(&format!("{name}:{line}:")) && out.contains("outside the project"),
                "{args:?} must name {name}:{line} and the escape:\n{out}"
            );
            assert!(!out.contains("SECRET"), "outside content printed:\n{out}");
        }
        unchanged(&before, p);
    }
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_without_hanging() {
    let dir = project();
    let p = dir.path();
    let fifo = p.join("models/meshes/fifo.stl");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    std::fs::copy(
        p.join("models/meshes/table.stl"),
        p.join("models/meshes/ok.stl"),
    )
    .unwrap();
    std::os::unix::fs::symlink("fifo.stl", p.join("models/meshes/to_fifo.stl")).unwrap();
    let before = snapshot(p);
    for (name, stl, expect) in [
        ("fifo.yaml", "meshes/fifo.stl", "FIFO"),
        ("to_fifo.yaml", "meshes/to_fifo.stl", "FIFO"),
        ("folder.yaml", "meshes", "folder"),
    ] {
        let text = one_part_doc(p, name, stl);
        let line = line_of(&text, "stl:");
        let doc = format!("models/{name}");
        let (code, out) = run(p, &["check", &doc]);
        assert_eq!(code, 1, "{out}");
        assert!(
            out.contains(&format!("{name}:{line}:")) && out.contains(expect),
            "{name}: {out}"
        );
        std::fs::remove_file(p.join(&doc)).unwrap();
    }
    // A CSV that is a FIFO, and devices given as documents or tables.
    write(
        p,
        "scripts/holes.rhai",
        "load_holes(\"models/meshes/fifo.stl\");\n",
    );
    let (code, out) = run(p, &["run", "scripts/holes.rhai"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("holes.rhai:1") && out.contains("FIFO"),
        "{out}"
    );
    // An import that is a FIFO, and a script past its size cap.
    write(
        p,
        "scripts/imp.rhai",
        "import \"../models/meshes/fifo.stl\" as f;\n",
    );
    let (code, out) = run(p, &["run", "scripts/imp.rhai"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("imp.rhai:1") && out.contains("FIFO"), "{out}");
    let big = std::fs::File::create(p.join("scripts/big.rhai")).unwrap();
    big.set_len(5 << 20).unwrap();
    let (code, out) = run(p, &["run", "scripts/big.rhai"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("big.rhai") && out.contains("4 MiB limit"),
        "{out}"
    );
    let (code, out) = run(p, &["check", "/dev/zero"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("/dev/zero") && out.contains("not a regular file"),
        "{out}"
    );
    let (code, out) = run(p, &["run", "models/mz07_demo.prg", "--doc", "/dev/urandom"]);
    assert_ne!(code, 0, "{out}");
    unchanged(&before, p);
}

#[test]
fn alias_bombs_are_refused_at_their_line() {
    let dir = project();
    let p = dir.path();
    // The case: one part with 3,000 planes, aliased 3,000 times (~250 KB).
    let mut text = String::from("parts:\n  a:\n    stl: meshes/table.stl\n    planes: &planes\n");
    for i in 0..3000 {
        text += &format!("      p{i}: {{point: [0, 0, {i}], normal: [0, 0, 1]}}\n");
    }
    for i in 0..3000 {
        text += &format!("  b{i}:\n    stl: meshes/table.stl\n    planes: *planes\n");
    }
    text += "components:\n  - name: a1\n    part: a\n";
    assert!(text.len() > 200_000, "{}", text.len());
    write(p, "models/bomb.yaml", &text);
    let before = snapshot(p);
    let (code, out) = run(p, &["check", "models/bomb.yaml"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("bomb.yaml:4:") && out.contains("anchors"),
        "{out}"
    );
    // An alias without an anchor-bearing line before it is refused too.
    write(p, "models/alias.yaml", "parts: *nothing\ncomponents: []\n");
    let (code, out) = run(p, &["check", "models/alias.yaml"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("alias.yaml:1:"), "{out}");
    unchanged(&before, p);
}

#[test]
fn bad_yaml_is_located_and_never_silently_accepted() {
    let dir = project();
    let p = dir.path();
    let cell = std::fs::read_to_string(p.join("models/cell.yaml")).unwrap();
    let dup = cell.replacen(
        "  plate_b:\n",
        "  table:\n    stl: meshes/screw.stl\n  plate_b:\n",
        1,
    );
    let first_table = line_of(&dup, "  table:");
    let second_table = dup
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "  table:")
        .nth(1)
        .unwrap()
        .0
        + 1;
    let huge = cell.replacen("- [1.0, 0.0, 0.0, 0.0]", "- [1e308, 0.0, 0.0, 0.0]", 1);
    let inf = cell.replacen("- [1.0, 0.0, 0.0, 0.0]", "- [1e400, 0.0, 0.0, 0.0]", 1);
    let nan = cell.replacen("- [1.0, 0.0, 0.0, 0.0]", "- [.nan, 0.0, 0.0, 0.0]", 1);
    let matrix_line = line_of(&cell, "- [1.0, 0.0, 0.0, 0.0]");
    let cases: Vec<(&str, String, String)> = vec![
        ("empty.yaml", String::new(), "empty.yaml:1:".into()),
        ("comment.yaml", "# nothing\n".into(), "empty".into()),
        ("dup.yaml", dup, format!("dup.yaml:{second_table}:")),
        ("huge.yaml", huge, format!("huge.yaml:{matrix_line}:")),
        ("inf.yaml", inf, "number out of range".into()),
        ("nan.yaml", nan, format!("nan.yaml:{matrix_line}:")),
    ];
    let before = snapshot(p);
    for (name, text, expect) in cases {
        write(p, &format!("models/{name}"), &text);
        let (code, out) = run(p, &["check", &format!("models/{name}")]);
        assert_eq!(code, 1, "{name}: {out}");
        assert!(
            out.contains(&expect),
            "{name}: expected `{expect}` in\n{out}"
        );
        if name == "dup.yaml" {
            assert!(
                out.contains(&format!("first at line {first_table}")),
                "{out}"
            );
        }
        assert!(!out.contains("invalid type: string"), "{out}");
        std::fs::remove_file(p.join(format!("models/{name}"))).unwrap();
    }
    unchanged(&before, p);
}

#[test]
fn check_refuses_meshes_that_scripts_refuse() {
    let dir = project();
    let p = dir.path();
    let facet = |z: &str| {
        format!("solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 {z}\nendloop\nendfacet\nendsolid s\n")
    };
    for (mesh, text, expect) in [
        (
            "empty.stl",
            "solid s\nendsolid s\n".to_string(),
            "no facets".to_string(),
        ),
        ("far.stl", facet("1e39"), "far.stl:6".to_string()),
        ("inf.stl", facet("inf"), "inf.stl:6".to_string()),
    ] {
        write(p, &format!("models/meshes/{mesh}"), &text);
        let doc_text = one_part_doc(p, "m.yaml", &format!("meshes/{mesh}"));
        let line = line_of(&doc_text, "stl:");
        write(p, "scripts/m.rhai", "open_doc(\"models/m.yaml\");\n");
        let before = snapshot(p);
        for args in [
            vec!["check", "models/m.yaml"],
            vec!["run", "scripts/m.rhai"],
        ] {
            let (code, out) = run(p, &args);
            assert_eq!(code, 1, "{mesh} {args:?}: {out}");
            assert!(
                out.contains(&expect) && out.contains(&format!("m.yaml:{line}:")),
                "{mesh} {args:?}: expected `{expect}`:\n{out}"
            );
        }
        unchanged(&before, p);
    }
}

#[test]
fn setters_refuse_non_finite_and_huge_values_and_saves_stay_loadable() {
    let dir = project();
    let p = dir.path();
    let cases = [
        "let d = doc.dimension(\"D1@角度1\"); d.system_value = 1e308;",
        "let d = doc.dimension(\"D1@角度1\"); d.value = 1e300;",
        "doc.component(\"plate_a\").translate(1e308, 0, 0);",
        "doc.component(\"plate_a\").translate(2e9, 0, 0);",
    ];
    let before = snapshot(p);
    for (i, line) in cases.iter().enumerate() {
        let script = format!("scripts/set{i}.rhai");
        write(
            p,
            &script,
            &format!("let doc = open_doc(\"models/cell.yaml\");\n{line}\ndoc.save();\n"),
        );
        let (code, out) = run(p, &["run", &script]);
        assert_eq!(code, 1, "{line}: {out}");
        assert!(
            out.contains(&format!("set{i}.rhai:2")) && out.contains("range"),
            "{line}: {out}"
        );
    }
    unchanged(&before, p);
    let (code, out) = run(p, &["check", "models/cell.yaml"]);
    assert_eq!(code, 0, "{out}");
}

#[test]
fn saves_never_overwrite_meshes_or_other_files() {
    let dir = project();
    let p = dir.path();
    write(p, "notes.txt", "my notes, not a document\n");
    write(p, "other.yaml", "key: value\n");
    let before = snapshot(p);
    for target in [
        "models/meshes/screw.stl",
        "notes.txt",
        "other.yaml",
        "models/meshes",
    ] {
        write(
            p,
            "scripts/save.rhai",
            &format!("let doc = open_doc(\"models/cell.yaml\");\ndoc.save_as(\"{target}\");\n"),
        );
        let (code, out) = run(p, &["run", "scripts/save.rhai"]);
        assert_eq!(code, 1, "{target}: {out}");
        assert!(
            out.contains("save.rhai:2") && out.contains("refusing"),
            "{target}: {out}"
        );
        unchanged(&before, p);
    }
    // Saving over another fitup document is a normal save.
    write(
        p,
        "scripts/save.rhai",
        "let doc = open_doc(\"models/cell.yaml\");\ndoc.save_as(\"models/copy.yaml\");\ndoc.save_as(\"models/copy.yaml\");\n",
    );
    let (code, out) = run(p, &["run", "scripts/save.rhai"]);
    assert_eq!(code, 0, "{out}");
}

/// Four components that nothing mates, on the table mesh.
fn free_document(p: &Path) {
    let mut text = String::from("parts:\n  block:\n    stl: meshes/table.stl\ncomponents:\n");
    for i in 0..4 {
        text += &format!("  - name: c{i}\n    part: block\n");
    }
    write(p, "models/free.yaml", &text);
}

#[test]
fn concurrent_writers_never_lose_an_edit_silently() {
    for _round in 0..3 {
        let dir = project();
        let p = dir.path();
        free_document(p);
        for i in 0..4 {
            write(
                p,
                &format!("scripts/w{i}.rhai"),
                &format!(
                    "let doc = open_doc(\"models/free.yaml\");\ndoc.component(\"c{i}\").translate({}, 0, 0);\ndoc.save();\n",
                    10 * (i + 1)
                ),
            );
        }
        let children: Vec<Child> = (0..4)
            .map(|i| spawn(p, &["run", &format!("scripts/w{i}.rhai")]))
            .collect();
        let results: Vec<(i32, String)> = children
            .into_iter()
            .enumerate()
            .map(|(i, c)| finish(c, &format!("run scripts/w{i}.rhai")))
            .collect();
        // Read the result back through fitup itself.
        write(
            p,
            "scripts/read.rhai",
            "let doc = open_doc(\"models/free.yaml\");\nfor i in 0..4 { print(doc.component(\"c\" + i).transform.translation[0]); }\n",
        );
        let (code, out) = run(p, &["run", "scripts/read.rhai"]);
        assert_eq!(code, 0, "{out}");
        let xs: Vec<f64> = out.lines().map(|l| l.trim().parse().unwrap()).collect();
        assert_eq!(xs.len(), 4, "{out}");
        let mut landed = 0;
        for (i, (code, msg)) in results.iter().enumerate() {
            let expected = 10.0 * (i + 1) as f64;
            if *code == 0 {
                assert_eq!(
                    xs[i], expected,
                    "writer {i} succeeded but its edit vanished"
                );
                landed += 1;
            } else {
                assert!(
                    msg.contains("changed on disk") && msg.contains("free.yaml"),
                    "writer {i}: {msg}"
                );
                assert_eq!(xs[i], 0.0);
            }
        }
        assert!(landed >= 1);
    }
}

#[cfg(unix)]
#[test]
fn a_writer_killed_during_saves_leaves_a_loadable_document() {
    let dir = project();
    let p = dir.path();
    free_document(p);
    write(
        p,
        "scripts/loop.rhai",
        "let doc = open_doc(\"models/free.yaml\");\nfor i in 0..100000 { doc.component(\"c0\").translate(1, 0, 0); doc.save(); }\n",
    );
    for delay in [150u64, 400, 900] {
        let mut child = spawn(p, &["run", "scripts/loop.rhai"]);
        std::thread::sleep(Duration::from_millis(delay));
        // SIGKILL: no destructor, no clean-up.
        child.kill().unwrap();
        child.wait().unwrap();
        let (code, out) = run(p, &["check", "models/free.yaml"]);
        assert_eq!(code, 0, "after kill -9 at {delay} ms: {out}");
    }
}

#[test]
fn cli_paths_follow_the_path_rule() {
    let dir = project();
    let p = dir.path();
    // A script below the project root finds the root by its fitup.toml, from any
    // current folder; the SCRIPT argument is relative to the current folder.
    write(
        p,
        "scripts/n.rhai",
        "print(open_doc(\"models/cell.yaml\").components().len());\n",
    );
    let (code, out) = run(&p.join("models"), &["run", "../scripts/n.rhai"]);
    assert_eq!((code, out.trim()), (0, "8"), "{out}");
    // --root does not change where SCRIPT is looked up; a script outside it is a
    // refused path (exit 1, like every refused path), not a usage error.
    let (code, out) = run(p, &["run", "scripts/n.rhai", "--root", "models"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("outside the project"), "{out}");
    // Scripts copied into a `fitup demo` folder work there.
    let (code, out) = run(p, &["demo", "mycell"]);
    assert_eq!(code, 0, "{out}");
    let demo = std::fs::read_to_string(common::repo().join("scripts/demo.rhai")).unwrap();
    write(p, "mycell/demo.rhai", &demo);
    let (code, out) = run(p, &["run", "mycell/demo.rhai"]);
    assert_eq!(code, 0, "{out}");
    // Without fitup.toml the root is the script's folder: `..` is outside.
    std::fs::remove_file(p.join("fitup.toml")).unwrap();
    let (code, out) = run(p, &["run", "scripts/n.rhai"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("n.rhai:1") && out.contains("does not exist in the project folder"),
        "{out}"
    );
}
