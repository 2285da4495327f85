//! The command line as a user meets it: exit codes and error messages that point at
//! the problem.

use crate::common;

use common::{project, run_in, text};

#[test]
fn exit_codes_and_located_errors() {
    let dir = project();
    let p = dir.path();
    std::fs::write(
        p.join("scripts/ok.rhai"),
        "let d = open_doc(\"models/cell.yaml\");\nprint(d.components().len());\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/ok.rhai"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "8");

    // `doc` is provided by --doc.
    std::fs::write(
        p.join("scripts/doc.rhai"),
        "assert(doc.component(\"table\").fixed, \"table fixed\");\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/doc.rhai", "--doc", "models/cell.yaml"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));

    // A failed assertion: exit 1, file:line:col and the source line.
    std::fs::write(
        p.join("scripts/bad.rhai"),
        "let x = 1;\nassert(x == 2, \"x is two\");\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/bad.rhai"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(
        t.contains("bad.rhai:2:")
            && t.contains("assertion failed: x is two")
            && t.contains("assert(x == 2"),
        "{t}"
    );

    // Syntax error.
    std::fs::write(p.join("scripts/syntax.rhai"), "let x = ;\n").unwrap();
    let t = text(&run_in(p, &["run", "scripts/syntax.rhai"]));
    assert!(
        t.contains("syntax.rhai:1:") && t.contains("syntax error"),
        "{t}"
    );

    // Usage errors: exit 2.
    assert_eq!(run_in(p, &["run"]).status.code(), Some(2));
    assert_eq!(run_in(p, &["frobnicate"]).status.code(), Some(2));
    // A missing script is a file error, like every refused path: exit 1, named.
    let o = run_in(p, &["run", "scripts/missing.rhai"]);
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    assert!(common::text(&o).contains("scripts/missing.rhai"));
}

#[test]
fn sandbox_limits_and_file_access() {
    let dir = project();
    let p = dir.path();
    let cases = [
        ("loop { }", "operation limit of 2,000,000 operations"),
        ("fn f(n) { f(n + 1) } f(0);", "nested function calls"),
        (
            "let s = \"x\"; loop { s += s; }",
            "larger than the sandbox allows",
        ),
        (
            "let a = []; a.pad(5000000, 0);",
            "larger than the sandbox allows",
        ),
        (
            "open_doc(\"../outside.yaml\");",
            "outside the project folder",
        ),
        ("open_doc(\"/etc/hostname\");", "outside the project folder"),
        ("import \"../../evil\" as e;", "outside the project folder"),
        ("import \"nothere\" as e;", "Module not found"),
    ];
    for (src, needle) in cases {
        std::fs::write(p.join("scripts/s.rhai"), src).unwrap();
        let o = run_in(p, &["run", "scripts/s.rhai", "--max-operations", "2000000"]);
        assert_eq!(o.status.code(), Some(1), "{src}: {}", text(&o));
        assert!(
            text(&o).contains(needle),
            "{src}: expected `{needle}` in {}",
            text(&o)
        );
    }
    // Imports inside the project work, and Unicode identifiers too.
    std::fs::write(p.join("scripts/lib.rhai"), "fn 两倍(x) { x * 2 }\n").unwrap();
    std::fs::write(
        p.join("scripts/main.rhai"),
        "import \"lib\" as lib;\nlet 角度 = lib::两倍(21);\nassert(角度 == 42);\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/main.rhai"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

#[test]
fn check_reports_summary_and_bad_documents() {
    let dir = project();
    let p = dir.path();
    let o = run_in(p, &["check", "models/cell.yaml"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("D1@角度1"));
    let yaml = std::fs::read_to_string(p.join("models/cell.yaml")).unwrap();
    std::fs::write(
        p.join("models/bad.yaml"),
        yaml.replacen("part: screw", "part: scerw", 1),
    )
    .unwrap();
    let o = run_in(p, &["check", "models/bad.yaml"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(
        t.contains("bad.yaml:")
            && t.contains("unknown part `scerw`")
            && t.contains("did you mean `screw`"),
        "{t}"
    );
    // A broken STL names the file and the line.
    std::fs::write(
        p.join("models/meshes/screw.stl"),
        "solid x\n facet normal 0 0 0\n  outer loop\n   vertex 1 2\n",
    )
    .unwrap();
    let t = text(&run_in(p, &["check", "models/cell.yaml"]));
    assert!(t.contains("screw.stl:4") && t.contains("vertex"), "{t}");
}

#[test]
fn docs_command_writes_the_reference() {
    let dir = project();
    let o = run_in(dir.path(), &["docs", "--out", "api.md"]);
    assert_eq!(o.status.code(), Some(0));
    let md = std::fs::read_to_string(dir.path().join("api.md")).unwrap();
    assert!(md.contains("open_doc(path: string) -> Document") && md.contains("system_value"));
}

#[test]
fn docs_without_a_docs_folder_and_to_standard_output() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    // The default target's folder is created.
    let o = run_in(p, &["docs"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("wrote docs/api.md"), "{}", text(&o));
    let md = std::fs::read_to_string(p.join("docs/api.md")).unwrap();
    assert!(md.contains("fmt(value)"));
    // `--out -` prints the reference and writes nothing.
    let o = run_in(p, &["docs", "--out", "-"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(String::from_utf8_lossy(&o.stdout), md);
    // A target that cannot be written: a message naming it and the alternative.
    std::fs::write(p.join("file"), "x").unwrap();
    let o = run_in(p, &["docs", "--out", "file/api.md"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(t.contains("file/api.md") && t.contains("--out -"), "{t}");
}

#[test]
fn demo_refuses_a_folder_that_is_not_empty() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let o = run_in(p, &["demo", "cell"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // The user edits the cell; a second `demo` must not replace it.
    let cell = p.join("cell/models/cell.yaml");
    let edited = std::fs::read_to_string(&cell).unwrap() + "# my edit\n";
    std::fs::write(&cell, &edited).unwrap();
    let o = run_in(p, &["demo", "cell"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(t.contains("is not empty") && t.contains("--force"), "{t}");
    assert_eq!(std::fs::read_to_string(&cell).unwrap(), edited);
    // An empty folder is fine; --force overwrites.
    std::fs::create_dir(p.join("empty")).unwrap();
    assert_eq!(run_in(p, &["demo", "empty"]).status.code(), Some(0));
    let o = run_in(p, &["demo", "cell", "--force"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(!std::fs::read_to_string(&cell)
        .unwrap()
        .contains("# my edit"));
}

#[test]
fn watch_help_lists_only_what_watch_takes() {
    let o = run_in(&common::repo(), &["watch", "--help"]);
    assert_eq!(o.status.code(), Some(0));
    let t = text(&o);
    assert!(
        !t.contains("--robot") && !t.contains("--log") && !t.contains("run only"),
        "{t}"
    );
    assert!(
        t.contains("--max-operations") && t.contains("KEY=VALUE"),
        "{t}"
    );
    let t = text(&run_in(&common::repo(), &["run", "--help"]));
    assert!(t.contains("--robot") && t.contains("KEY=VALUE"), "{t}");
}

#[test]
fn setting_a_pose_in_one_call_and_the_hint_for_the_natural_spelling() {
    let dir = project();
    let p = dir.path();
    std::fs::write(
        p.join("scripts/natural.rhai"),
        "let doc = open_doc(\"models/cell.yaml\");\ndoc.component(\"screw4\").transform = pose(0, 0, 50, 0, 0, 0);\nprint(doc.component(\"screw4\").transform);\n",
    )
    .unwrap();
    // The natural spelling is the setter's method on the call's result (assign.rs).
    let o = run_in(p, &["run", "scripts/natural.rhai"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        "X 0 Y 0 Z 50 A 0° B 0° C 0°",
        "{t}"
    );
    // A property without a setter still cannot be assigned: the hint says what can.
    std::fs::write(
        p.join("scripts/no_setter.rhai"),
        "let doc = open_doc(\"models/cell.yaml\");\ndoc.component(\"screw4\").part_file = \"x\";\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/no_setter.rhai"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(
        t.contains("no_setter.rhai:2:") && t.contains("keep the value in a variable first"),
        "{t}"
    );
    std::fs::write(
        p.join("scripts/one_call.rhai"),
        "let doc = open_doc(\"models/cell.yaml\");\n\
         doc.component(\"screw4\").set_transform(pose(1, 2, 50, 0, 0, 30));\n\
         print(doc.component(\"screw4\").transform);\n\
         doc.set_transform(\"screw5\", [0.1 + 0.2, -0.0, 7, 0, 0, 29.999999999999996]);\n\
         print(fmt(doc.component(\"screw5\").transform));\n\
         print(fmt(doc.component(\"screw5\").transform.xyzabc));\n\
         print(fmt(1.0 / 3.0, 5) + \" \" + fmt_mm(12.5) + \" \" + fmt_deg(-0.0001));\n\
         let failed = false;\n\
         try { doc.set_transform(\"table\", translation(1, 2, 3)); } catch (e) { failed = true; }\n\
         assert(failed, \"the table is fixed\");\n",
    )
    .unwrap();
    let o = run_in(p, &["run", "scripts/one_call.rhai"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let lines: Vec<&str> = t.lines().collect();
    assert_eq!(
        lines,
        [
            "X 1 Y 2 Z 50 A 0° B 0° C 30°",
            "X 0.3 Y 0 Z 7 A 0° B 0° C 30°",
            "[0.3, 0, 7, 0, 0, 30]",
            "0.33333 12.5 mm 0°",
        ],
        "{t}"
    );
}

#[test]
fn check_prints_numbers_for_people() {
    let dir = project();
    let o = run_in(dir.path(), &["check", "models/cell.yaml"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        !t.contains("-0 ") && !t.contains("-0°") && !t.contains("99999"),
        "{t}"
    );
    assert!(t.contains("fixed  at X "), "{t}");
}

/// `fitup batch` runs the script once per document, each with its own `doc`, and
/// names the documents whose run failed.
#[test]
fn batch_runs_the_script_once_per_document() {
    let dir = project();
    let p = dir.path();
    std::fs::copy(p.join("models/cell.yaml"), p.join("models/copy.yaml")).unwrap();
    std::fs::write(
        p.join("scripts/count.rhai"),
        "print(`count ${doc.components().len()}`);\n",
    )
    .unwrap();
    let o = run_in(
        p,
        &[
            "batch",
            "scripts/count.rhai",
            "--docs",
            "models/cell.yaml",
            "models/copy.yaml",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let mut counts: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(str::to_string)
        .collect();
    counts.sort();
    assert_eq!(counts, ["count 8", "count 8"], "{}", text(&o));
    // More runs than cores, each checking interference (rayon work inside the run):
    // every run ends with its own document's answer.
    std::fs::write(
        p.join("scripts/clash.rhai"),
        "print(`clash ${doc.components().len()} ${doc.interferences().len()}`);\n",
    )
    .unwrap();
    let docs = ["models/cell.yaml", "models/copy.yaml"].repeat(3);
    let mut args = vec!["batch", "scripts/clash.rhai", "--docs"];
    args.extend(docs.iter().copied());
    // Bounded: this used to deadlock (runs on rayon's workers waiting for rayon work).
    let o = common::run_bounded(p, &args, std::time::Duration::from_secs(120));
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let clashes: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(str::to_string)
        .collect();
    assert_eq!(clashes, vec!["clash 8 0".to_string(); 6], "{}", text(&o));
    // a missing document fails its run only, and is named
    let o = run_in(
        p,
        &[
            "batch",
            "scripts/count.rhai",
            "--docs",
            "models/cell.yaml",
            "models/none.yaml",
        ],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("count 8") && t.contains("1 of 2 runs failed: models/none.yaml"),
        "{t}"
    );
}

/// A build without the opt-in viewer answers every viewer flag with the one command
/// that adds it, before it runs anything, and exits non-zero.
#[cfg(not(feature = "viewer"))]
#[test]
fn viewer_flags_without_the_viewer_name_the_build_that_adds_it() {
    let dir = project();
    let p = dir.path();
    std::fs::write(p.join("scripts/ok.rhai"), "print(\"ran\");\n").unwrap();
    for args in [
        &["run", "scripts/ok.rhai", "--view"][..],
        &["run", "scripts/ok.rhai", "--record", "out/x.rrd"][..],
        &["view", "out/x.rrd"][..],
    ] {
        let o = run_in(p, args);
        let t = text(&o);
        assert_ne!(o.status.code(), Some(0), "{args:?}: {t}");
        assert!(t.contains("--features viewer"), "{args:?}: {t}");
        assert!(!t.contains("ran"), "{args:?} ran the script: {t}");
        assert!(!p.join("out/x.rrd").exists());
    }
}
