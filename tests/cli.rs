//! The command line as a user meets it: exit codes and error messages that point at
//! the problem.

mod common;

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
    assert_eq!(
        run_in(p, &["run", "scripts/missing.rhai"]).status.code(),
        Some(2)
    );
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
