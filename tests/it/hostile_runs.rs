//! Hostile runs through the real binary: import cycles, broken pipes, runaway loops,
//! deep recursion and nesting, data growth, weird script arguments. Each must end in
//! bounded time (a run still going after a generous timeout is killed and fails the
//! test; this is not a speed test) with a human message naming file and line, and no
//! panic.

use crate::common;

use common::{project, short_text as text, spawn};
use std::path::Path;
use std::process::Output;
use std::time::Duration;

/// Generous: far beyond what any case needs on a loaded machine.
const TIMEOUT: Duration = Duration::from_secs(120);

/// `fitup ARGS` in `dir`, bounded by [`TIMEOUT`].
fn run(dir: &Path, args: &[&str]) -> Output {
    common::run_bounded(dir, args, TIMEOUT)
}

/// Runs `scripts/NAME` (written with `source`) and expects exit 1 with every needle.
fn expect_error(dir: &Path, name: &str, source: &str, needles: &[&str]) -> String {
    let path = dir.join("scripts").join(name);
    std::fs::write(&path, source).unwrap();
    let o = run(dir, &["run", &format!("scripts/{name}")]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {t}");
    for n in needles {
        assert!(t.contains(n), "{name}: expected `{n}` in:\n{t}");
    }
    assert!(!t.contains("panicked"), "{name}: {t}");
    t
}

#[test]
fn import_cycles_are_reported_with_the_chain() {
    let dir = project();
    let p = dir.path();
    // A script importing itself.
    expect_error(
        p,
        "self.rhai",
        "let x = 1;\nimport \"self\" as me;\n",
        &[
            "self.rhai:2:",
            "import cycle: scripts/self.rhai:2 → scripts/self.rhai",
        ],
    );
    // A pair: the error is at the import that closes the cycle, with the whole chain.
    std::fs::write(p.join("scripts/b.rhai"), "\n\nimport \"a\" as a;\n").unwrap();
    expect_error(
        p,
        "a.rhai",
        "import \"b\" as b;\nprint(\"unreachable\");\n",
        &[
            "b.rhai:3:",
            "scripts/a.rhai:1 → scripts/b.rhai:3 → scripts/a.rhai",
        ],
    );
    // A long chain c0 → c1 → … → c9 → c3, started from main.
    for i in 0..10 {
        let next = if i == 9 { 3 } else { i + 1 };
        std::fs::write(
            p.join(format!("scripts/c{i}.rhai")),
            format!("fn f{i}() {{ {i} }}\nimport \"c{next}\" as n;\n"),
        )
        .unwrap();
    }
    let t = expect_error(
        p,
        "main.rhai",
        "import \"c0\" as c;\n",
        &[
            "c9.rhai:2:",
            "import cycle: scripts/c3.rhai:2 → scripts/c4.rhai:2",
            "scripts/c9.rhai:2 → scripts/c3.rhai",
        ],
    );
    assert!(!t.contains("main.rhai:1 →"), "the chain starts at c3: {t}");
}

#[test]
fn module_count_and_import_depth_limits_fire() {
    let dir = project();
    let p = dir.path();
    // Twenty distinct nested modules: deeper than the 16 allowed.
    for i in 0..20 {
        std::fs::write(
            p.join(format!("scripts/d{i}.rhai")),
            format!("import \"d{}\" as n;\n", i + 1),
        )
        .unwrap();
    }
    std::fs::write(p.join("scripts/d20.rhai"), "fn leaf() { 1 }\n").unwrap();
    expect_error(
        p,
        "deep.rhai",
        "import \"d0\" as d;\n",
        &[
            "imports are nested more than 16 deep",
            "scripts/d15.rhai:1 →",
        ],
    );
    // One module imported again and again: the 65th import is refused.
    std::fs::write(p.join("scripts/lib.rhai"), "fn one() { 1 }\n").unwrap();
    expect_error(
        p,
        "many.rhai",
        "let n = 0;\nfor i in 0..1000 {\n    import \"lib\" as l;\n    n += l::one();\n}\n",
        &["many.rhai:3:", "more than 64 modules imported in one run"],
    );
    // Diamonds are not cycles: main imports x and y, both import lib.
    std::fs::write(p.join("scripts/x.rhai"), "import \"lib\" as l;\n").unwrap();
    std::fs::write(p.join("scripts/y.rhai"), "import \"lib\" as l;\n").unwrap();
    std::fs::write(
        p.join("scripts/diamond.rhai"),
        "import \"x\" as x;\nimport \"y\" as y;\nimport \"lib\" as l;\nprint(l::one());\n",
    )
    .unwrap();
    let o = run(p, &["run", "scripts/diamond.rhai"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

#[test]
fn an_error_inside_a_module_names_the_module_file() {
    let dir = project();
    let p = dir.path();
    std::fs::write(
        p.join("scripts/bad_lib.rhai"),
        "let a = 1;\nlet b = a + \"x\" * 2;\n",
    )
    .unwrap();
    expect_error(
        p,
        "uses_bad.rhai",
        "import \"bad_lib\" as l;\n",
        &["bad_lib.rhai:2:"],
    );
}

#[test]
fn runaway_loops_stop_at_the_default_limit_with_the_way_to_raise_it() {
    let dir = project();
    let p = dir.path();
    expect_error(
        p,
        "spin.rhai",
        "let x = 0;\nwhile true { x += 1 }\n",
        &[
            "spin.rhai:2:",
            "operation limit of 50,000,000 operations",
            "--max-operations",
        ],
    );
    // The limit counts over imported modules too: a module cannot restart the count.
    std::fs::write(
        p.join("scripts/spin_lib.rhai"),
        "let i = 0;\nwhile i < 30000000 { i += 1; }\n",
    )
    .unwrap();
    std::fs::write(
        p.join("scripts/twice.rhai"),
        "import \"spin_lib\" as a;\nimport \"spin_lib\" as b;\nimport \"spin_lib\" as c;\n",
    )
    .unwrap();
    let o = run(
        p,
        &["run", "scripts/twice.rhai", "--max-operations", "1000000"],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("operation limit of 1,000,000") && t.contains("spin_lib.rhai:2"),
        "{t}"
    );
}

#[test]
fn deep_recursion_and_nesting_end_with_the_sandbox_message() {
    let dir = project();
    let p = dir.path();
    expect_error(
        p,
        "recurse.rhai",
        "fn f(n) { if n == 0 { 0 } else { 1 + f(n - 1) } }\nprint(f(50));\nprint(f(100000));\n",
        &["recurse.rhai:3:", "more than 64 nested function calls"],
    );
    // Recursion through a module's function.
    std::fs::write(
        p.join("scripts/rec_lib.rhai"),
        "fn down(n) { down(n + 1) }\n",
    )
    .unwrap();
    expect_error(
        p,
        "recurse_lib.rhai",
        "import \"rec_lib\" as r;\nr::down(0);\n",
        &["nested function calls"],
    );
    let deep = |open: &str, close: &str, n: usize| {
        format!("let x = {}1{};\n", open.repeat(n), close.repeat(n))
    };
    for (name, source) in [
        ("parens.rhai", deep("(", ")", 20000)),
        ("arrays.rhai", deep("[", "]", 20000)),
        ("maps.rhai", deep("#{a: ", "}", 20000)),
        ("blocks.rhai", deep("{ ", " }", 20000)),
        ("unary.rhai", deep("- ", "", 20000)),
        (
            "ifs.rhai",
            format!(
                "fn f() {{ {}1{} }}\nf();\n",
                "if true { ".repeat(5000),
                " }".repeat(5000)
            ),
        ),
        ("sum.rhai", format!("let x = 1{};\n", " + 1".repeat(100000))),
    ] {
        expect_error(
            p,
            name,
            &source,
            &[&format!("{name}:1:"), "exceeds maximum complexity"],
        );
    }
}

#[test]
fn data_growth_stops_at_the_size_limits() {
    let dir = project();
    let p = dir.path();
    for (name, source, needle) in [
        (
            "string.rhai",
            "let s = \"x\";\nloop { s += s; }\n",
            "Length of string is larger than the sandbox allows",
        ),
        (
            "array.rhai",
            "let a = [1];\nloop { a += a; }\n",
            "array/BLOB is larger than the sandbox allows",
        ),
        (
            "pad.rhai",
            "let a = [];\na.pad(100000000, 0);\n",
            "larger than the sandbox allows",
        ),
    ] {
        // Default limits only: the size limit must fire before the operation limit.
        expect_error(p, name, source, &[&format!("{name}:"), needle]);
    }
}

/// Starts `fitup ARGS` with its standard output closed before it writes anything,
/// then checks it ends quietly.
fn closed_stdout(dir: &Path, args: &[&str]) {
    let mut child = spawn(dir, args);
    // Close the reading end at once: every write of the child hits a broken pipe.
    drop(child.stdout.take());
    let o = common::finish(child, &args.join(" "), TIMEOUT);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{args:?}: {err}"
    );
    assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
}

#[test]
fn broken_pipes_end_quietly() {
    let dir = project();
    let p = dir.path();
    closed_stdout(p, &["check", "models/cell.yaml"]);
    closed_stdout(p, &["docs", "--out", "-"]);
    closed_stdout(p, &["--help"]);
    std::fs::write(
        p.join("scripts/chatty.rhai"),
        "for i in 0..100000 { print(`line ${i}`); }\n",
    )
    .unwrap();
    closed_stdout(p, &["run", "scripts/chatty.rhai"]);

    // The same through a real pipe into `head`, as users write it.
    let o = std::process::Command::new("sh")
        .current_dir(p)
        .arg("-c")
        .arg(format!(
            "'{}' run scripts/chatty.rhai | head -n 3",
            env!("CARGO_BIN_EXE_fitup")
        ))
        .output()
        .unwrap();
    let t = text(&o);
    assert!(
        t.starts_with("line 0\nline 1\nline 2\n") && !t.contains("panicked"),
        "{t}"
    );
}

#[test]
fn script_arguments_reach_the_script_typed() {
    let dir = project();
    let p = dir.path();
    std::fs::write(
        p.join("scripts/args.rhai"),
        "for k in args.keys() { print(`${k}: ${type_of(args[k])} ${args[k]}`); }\n\
         let steps = args.get(\"steps\") ?? 10;\nprint(`steps ${steps}`);\n",
    )
    .unwrap();
    let o = run(
        p,
        &[
            "run",
            "scripts/args.rhai",
            "--",
            "n=3",
            "gap=0.5",
            "fast=true",
            "part=screw4",
            "角度=-30",
            "expr=a=b",
            "my-key=x y",
        ],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    for line in [
        "n: i64 3",
        "gap: f64 0.5",
        "fast: bool true",
        "part: string screw4",
        "角度: i64 -30",
        "expr: string a=b",
        "my-key: string x y",
        "steps 10",
    ] {
        assert!(t.lines().any(|l| l == line), "`{line}` missing:\n{t}");
    }
    // No arguments: `args` is an empty map, not an undefined variable.
    let o = run(p, &["run", "scripts/args.rhai"]);
    assert!(text(&o).contains("steps 10"), "{}", text(&o));

    // Weird arguments are usage errors (exit 2) that say what is wrong.
    let long = format!("v={}", "x".repeat(100_000));
    for (args, needle) in [
        (vec!["verbose"], "`verbose` is not `key=value`"),
        (vec!["=3"], "empty key"),
        (vec!["n=1", "n=2"], "`n` is given twice"),
        (vec!["x=1e999"], "out of range"),
        (vec![long.as_str()], "longer than"),
    ] {
        let mut a = vec!["run", "scripts/args.rhai", "--"];
        a.extend(args.iter().copied());
        let o = run(p, &a);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains(needle), "{args:?}: expected `{needle}` in {t}");
        assert!(t.len() < 1000, "the message repeats a huge argument: {t}");
    }
    // Arguments without `--` are not taken as script arguments silently.
    let o = run(p, &["run", "scripts/args.rhai", "n=3"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}

#[cfg(unix)]
#[test]
fn special_and_huge_script_files_are_refused_without_reading_them() {
    let dir = project();
    let p = dir.path();
    let fifo = p.join("scripts/pipe.rhai");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    // Nobody writes to the FIFO: reading it would block forever.
    let o = run(p, &["run", "scripts/pipe.rhai"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("pipe.rhai") && t.contains("not a regular file"),
        "{t}"
    );
    expect_error(
        p,
        "imports_pipe.rhai",
        "import \"pipe\" as p;\n",
        &["imports_pipe.rhai:1:", "not a regular file"],
    );
    // A folder named like a script.
    std::fs::create_dir(p.join("scripts/folder.rhai")).unwrap();
    let o = run(p, &["run", "scripts/folder.rhai"]);
    assert!(text(&o).contains("not a regular file"), "{}", text(&o));
    // A script over the 16 MiB string limit.
    let big = p.join("scripts/big.rhai");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(17 << 20).unwrap();
    let o = run(p, &["run", "scripts/big.rhai"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("big.rhai") && t.contains("larger than"), "{t}");
}
