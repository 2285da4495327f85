//! Round 3 of the hostile cases, the classes left after the first two passes:
//! string → array builders counted before they allocate, `fitup check` of a very
//! large document, and files read through the project's held folder.
//!
//! Bounds (not speed assertions): every command ends within the runner's bound
//! ([`crate::hostile_bounds::run`], 20 s), its peak resident memory is under the bound
//! stated at the case, its message names the script line and the cause.

use crate::common;

/// Writes `scripts/NAME` in a fresh project and runs it.
fn run_script(source: &str) -> (tempfile::TempDir, crate::hostile_bounds::Run) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir(p.join("scripts")).unwrap();
    std::fs::write(p.join("scripts/s.rhai"), source).unwrap();
    let r = crate::hostile_bounds::run(p, &["run", "scripts/s.rhai"]);
    (dir, r)
}

/// Peak resident memory of a refused string → array builder on a 16 M-character
/// string (kB): 250 MB (the string is 16 MB; Rhai's own `split("")` took 1.08 GB
/// before refusing).
const BUILDER_RSS_KB: u64 = 250 * 1024;

/// `split("")`, `split(' ')`, `split()`, `split_rev`, `to_chars` and `to_blob` of a
/// 16 M-character string: refused by their element count before the array is built,
/// naming the script line, the builder and the count.
#[test]
fn string_to_array_builders_count_before_allocating() {
    for (call, what, count) in [
        (r#"s.split("")"#, "`split`", "16,000,002"),
        ("s.split(' ')", "`split`", "8,000,001"),
        ("s.split()", "`split`", "8,000,000"),
        (r#"s.split_rev(" ")"#, "`split_rev`", "8,000,001"),
        ("s.to_chars()", "`to_chars`", "16,000,000"),
        ("s.to_blob()", "`to_blob`", "16,000,000"),
    ] {
        let source = format!(
            "let s = \"\";\ns.pad(8000000, 'x');\ns.replace(\"x\", \"x \");\nlet a = {call};\nprint(a.len());\n"
        );
        let (_dir, r) = run_script(&source);
        assert_eq!(r.code, Some(1), "{call}: {}", r.text);
        assert!(
            r.text.contains("s.rhai:4:")
                && r.text.contains(what)
                && r.text.contains(&format!("({count} elements)"))
                && r.text.contains("larger than the sandbox allows"),
            "{call}: {}",
            r.text
        );
        assert!(r.peak_kb < BUILDER_RSS_KB, "{call}: peak {} kB", r.peak_kb);
    }
    // Within the limit, the builders work as Rhai's.
    let (_dir, r) =
        run_script("print(\"a,b,,c\".split(\",\").len());\nprint(\"a b\".to_chars());\n");
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("4\n[a,  , b]"), "{}", r.text);
}

// ---- fitup check of a very large document ----------------------------------------

/// A binary STL of a unit cube.
fn cube_stl() -> Vec<u8> {
    let m = fitup::mesh::Mesh::cuboid(
        fitup::math::Point3::origin(),
        fitup::math::Point3::new(1.0, 1.0, 1.0),
    );
    let f = tempfile::NamedTempFile::new().unwrap();
    fitup::mesh::write_stl(f.path(), &m).unwrap();
    std::fs::read(f.path()).unwrap()
}

/// Bytes `fitup check` may print besides one line per part and component: the
/// description is cut to 2,000 characters (UTF-8: at most 8,000 bytes) and 20 lines.
const CHECK_HEAD_BYTES: usize = 16 * 1024;

/// A document within the 16 MiB limit holding a 15 MB description and 200,000 parts
/// that all name one mesh: `check` lists every part and component but prints the
/// description cut with the count left out (it printed all 15 MB), and each part's
/// mesh file is resolved, read and inspected once for all the parts that share it
/// (the load resolved and stat-ed the file once per part: 20,000 parts took 4.5 s,
/// 400,000 past 60 s). Bounds: the runner's 20 s, 600 MB.
#[test]
fn check_of_a_huge_document_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::write(p.join("cube.stl"), cube_stl()).unwrap();
    let description = "lorem ipsum ".repeat(1_250_000) + "end";
    let mut doc = format!("description: {description}\nparts:\n");
    let n = 60_000;
    for i in 0..n {
        doc += &format!("  p{i}: {{stl: cube.stl}}\n");
    }
    doc += "components:\n  - {name: c0, part: p0}\n";
    assert!(doc.len() < 16 << 20, "{} bytes", doc.len());
    std::fs::write(p.join("big.yaml"), &doc).unwrap();
    let r = crate::hostile_bounds::run(p, &["check", "big.yaml"]);
    assert_eq!(r.code, Some(0), "{}", &r.text[..r.text.len().min(2000)]);
    assert!(
        r.text
            .contains("(14,998,003 more characters of the description not shown)"),
        "{}",
        &r.text[..r.text.len().min(3000)]
    );
    // The whole output (the runner keeps its head and tail only).
    let out = common::run_in(p, &["check", "big.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    let listing: usize = text
        .lines()
        .filter(|l| l.starts_with("    p") || l.starts_with("    c0"))
        .map(|l| l.len() + 1)
        .sum();
    assert!(
        text.len() - listing < CHECK_HEAD_BYTES,
        "{} bytes besides the listing",
        text.len() - listing
    );
    assert_eq!(text.matches(" cube.stl").count(), n, "one line per part");
    assert!(r.peak_kb < 600 * 1024, "peak {} kB", r.peak_kb);
}

// ---- exit codes of refused paths ---------------------------------------------------

/// Every file or folder named on the command line that is missing, outside the project
/// or reached through a symbolic link is refused with exit code 1 (a file error) and
/// its name, whatever the command (`run` of a script or a motion program, `--doc`,
/// `--root`, `skills`, `check`, `cache prune`); exit code 2 stays for the command line
/// itself. (`run PROGRAM` and `run SCRIPT` exited 2 for a refused path, `skills` and
/// `check` 1.)
#[test]
fn every_refused_command_line_path_exits_1() {
    let dir = common::project();
    let p = dir.path();
    fitup::demo::write_robots(&p.join("models")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::write(o.join("s.rhai"), "print(\"FROMOUTSIDE\");\n").unwrap();
    std::fs::write(o.join("p.prg"), "Joint 0 0 0 0 0 0\n").unwrap();
    std::fs::write(o.join("d.yaml"), "parts: {}\n").unwrap();
    std::os::unix::fs::symlink(o, p.join("link")).unwrap();
    std::fs::write(p.join("p.prg"), "Joint 0 0 0 0 0 0\n").unwrap();
    std::fs::write(p.join("scripts/ok.rhai"), "print(\"inside\");\n").unwrap();
    let os = |f: &str| o.join(f).to_string_lossy().into_owned();
    let (script, program, doc) = (os("s.rhai"), os("p.prg"), os("d.yaml"));
    let (script, program, doc) = (script.as_str(), program.as_str(), doc.as_str());
    let missing = os("missing");
    let missing = missing.as_str();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["run", "scripts/missing.rhai"], "missing.rhai"),
        (vec!["run", "link/s.rhai", "--root", "."], "s.rhai"),
        (vec!["run", script, "--root", "."], "s.rhai"),
        (vec!["run", "scripts/ok.rhai", "--doc", doc], "d.yaml"),
        (vec!["run", "scripts/ok.rhai", "--root", missing], "missing"),
        (vec!["watch", "link/s.rhai", "--root", "."], "s.rhai"),
        (
            vec!["run", "missing.prg", "--doc", "models/mz07.yaml"],
            "missing.prg",
        ),
        (
            vec!["run", program, "--root", ".", "--doc", "models/mz07.yaml"],
            "p.prg",
        ),
        (
            vec![
                "run",
                "link/p.prg",
                "--root",
                ".",
                "--doc",
                "models/mz07.yaml",
            ],
            "p.prg",
        ),
        (vec!["run", "p.prg", "--doc", "link/d.yaml"], "d.yaml"),
        (vec!["run", "p.prg", "--doc", doc], "d.yaml"),
        (vec!["skills", "template", "missing.yaml"], "missing.yaml"),
        (
            vec!["skills", "run", "missing.json", "--plain"],
            "missing.json",
        ),
        (vec!["check", "missing.yaml"], "missing.yaml"),
        (vec!["cache", "prune", "missing"], "missing"),
    ];
    let before = common::snapshot(o);
    for (args, name) in cases {
        let r = crate::hostile_bounds::run(p, &args);
        assert_eq!(r.code, Some(1), "{args:?}: {}", r.text);
        assert!(
            r.text.contains(name),
            "{args:?} does not name {name}: {}",
            r.text
        );
        assert!(!r.text.contains("FROMOUTSIDE"), "{args:?}: {}", r.text);
    }
    // The command line itself: exit 2.
    for args in [
        vec!["run"],
        vec!["run", "p.prg"],
        vec!["run", "scripts/ok.rhai", "--", "x"],
    ] {
        let r = crate::hostile_bounds::run(p, &args);
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.text);
    }
    assert_eq!(common::snapshot(o), before, "changed outside");
}

/// Rhai measures an array after every native call on its variable, so one operation
/// of `a.len()` or `a.push(x)` on a 4-million-element array costs milliseconds: a
/// loop of them stays far inside the 50 million operations for a day (measured, dev
/// build at load 8: 200 calls of `a.len()` on 4 M elements 1.6 s; 4 M pushes would
/// walk 8·10¹² elements). The run's time limit (`--max-seconds`, default 3600 s)
/// bounds it: each loop here stops at a 3 s limit with the limit's message at the
/// script line, exit 1, in bounded memory; the default is printed by `--help`.
#[test]
fn calls_on_large_arrays_stop_at_the_runs_time_limit() {
    for (body, line) in [
        ("let n = 0;\nwhile true { n += a.len(); }\n", ":4:"),
        ("let b = [];\nfor i in 0..4000000 { b.push(i); }\n", ":4:"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        std::fs::write(p.join("fitup.toml"), "").unwrap();
        std::fs::create_dir(p.join("scripts")).unwrap();
        let source = format!("let a = [];\na.pad(4000000, 0);\n{body}");
        std::fs::write(p.join("scripts/s.rhai"), &source).unwrap();
        let r = crate::hostile_bounds::run_within(
            p,
            &["run", "scripts/s.rhai", "--max-seconds", "3"],
            std::time::Duration::from_secs(60),
        );
        eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
        assert_eq!(r.code, Some(1), "{source}: {}", r.text);
        assert!(
            r.text.contains("time limit of 3 s")
                && r.text.contains("--max-seconds")
                && r.text.contains(&format!("s.rhai{line}")),
            "{source}: {}",
            r.text
        );
        assert!(!r.text.contains("panicked"), "{}", r.text);
        assert!(r.peak_kb < 500 * 1024, "peak {} kB", r.peak_kb);
    }
    let help = common::run_in(std::path::Path::new("."), &["run", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("--max-seconds") && help.contains("[default: 3600]"),
        "{help}"
    );
}

/// Peak resident memory of a refused data file (kB): 700 MB. The file itself is up
/// to 64 MiB; its values are counted before they are kept (at the library's caps,
/// `MAX_CSV_FIELDS`, `MAX_JSON_VALUES`, `MAX_HOLES`) and before script values are
/// built (the sandbox's sizes).
const DATA_RSS_KB: u64 = 700 * 1024;

/// Data files within the 64 MiB file cap whose values a script could not hold were
/// parsed and converted whole before Rhai refused the result: `read_csv` of 64 MiB
/// of `1,2` lines peaked at 11.5 GB, `read_json` of `[[1,2],…]` at 2.9 GB,
/// `load_holes` of 4.8 million holes at 4.2 GB. Now the readers count as they read
/// (refused at the line, or line and column, that passes the library's cap) and the
/// bindings count a result's elements, properties and text before they build it
/// (refused naming the call and the sandbox's limits): each case exits 1 at the
/// script line within [`DATA_RSS_KB`]; a table within the limits is read.
#[test]
fn data_files_are_counted_before_a_script_holds_them() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir(p.join("scripts")).unwrap();
    let cap = 64usize << 20;
    let fill = |head: &str, line: &str, tail: &str, bytes: usize| {
        let n = (bytes - head.len() - tail.len()) / line.len();
        let mut s = String::with_capacity(bytes);
        s.push_str(head);
        for _ in 0..n {
            s.push_str(line);
        }
        s.push_str(tail);
        s
    };
    std::fs::write(p.join("big.csv"), fill("a,b\n", "1,2\n", "", cap - 16)).unwrap();
    std::fs::write(
        p.join("mid.csv"),
        fill("a,b\n", "1,2\n", "", 1_500_000 * 4 + 4),
    )
    .unwrap();
    std::fs::write(
        p.join("ok.csv"),
        fill("a,b\n", "1,2\n", "", 200_000 * 4 + 4),
    )
    .unwrap();
    let big_json = fill("[[1,2]", ",[1,2]", "]", cap - 16);
    std::fs::write(p.join("big.json"), big_json).unwrap();
    let maps = fill(
        "[{\"a\":1,\"b\":2,\"c\":3}",
        ",{\"a\":1,\"b\":2,\"c\":3}",
        "]",
        900_000 * 20,
    );
    std::fs::write(p.join("maps.json"), maps).unwrap();
    let long = "x".repeat(6 << 20);
    std::fs::write(
        p.join("text.json"),
        format!("[\"{long}\",\"{long}\",\"{long}\"]"),
    )
    .unwrap();
    std::fs::write(
        p.join("holes.csv"),
        fill("", "1,0,0,0,0,0,1\n", "", cap - 16),
    )
    .unwrap();
    std::fs::write(
        p.join("mid_holes.csv"),
        fill("", "1,0,0,0,0,0,1\n", "", 600_000 * 14),
    )
    .unwrap();
    let before = common::snapshot(p);
    for (call, needles) in [
        (
            "read_csv(\"big.csv\")",
            &["big.csv:2000001", "more than 4,000,000 fields"][..],
        ),
        (
            "read_csv(\"mid.csv\")",
            &[
                "read_csv(\"mid.csv\") of 1,500,000 rows",
                "3,000,000 map properties",
                "more than a script may hold",
            ][..],
        ),
        (
            "read_csv(\"mid.csv\", #{header: false})",
            &["4,500,003 array elements", "more than a script may hold"][..],
        ),
        (
            "read_json(\"big.json\")",
            &["big.json:1", "more than 2,000,000 values"][..],
        ),
        (
            "read_json(\"maps.json\")",
            &["maps.json:1", "more than 2,000,000 values"][..],
        ),
        (
            "read_json(\"text.json\")",
            &[
                "read_json(\"text.json\")",
                "18,874,368 characters of text",
                "more than a script may hold",
            ][..],
        ),
        (
            "load_holes(\"holes.csv\")",
            &["holes.csv:1000001", "more than 1,000,000 holes"][..],
        ),
        (
            "load_holes(\"mid_holes.csv\")",
            &[
                "of 600,000 holes",
                "2,400,000 map properties",
                "more than a script may hold",
            ][..],
        ),
    ] {
        std::fs::write(
            p.join("scripts/s.rhai"),
            format!("let x = 1;\nlet t = {call};\nprint(t.len());\n"),
        )
        .unwrap();
        let r = crate::hostile_bounds::run_within(
            p,
            &["run", "scripts/s.rhai"],
            std::time::Duration::from_secs(120),
        );
        eprintln!(
            "{call}: peak {} kB, {:.1} s; {}",
            r.peak_kb,
            r.elapsed.as_secs_f64(),
            r.text.lines().next().unwrap_or("")
        );
        assert_eq!(r.code, Some(1), "{call}: {}", r.text);
        assert!(
            r.text.contains("s.rhai:2:"),
            "{call}: not at the script line: {}",
            r.text
        );
        for n in needles {
            assert!(r.text.contains(n), "{call}: no `{n}` in {}", r.text);
        }
        assert!(!r.text.contains("panicked"), "{}", r.text);
        assert!(r.peak_kb < DATA_RSS_KB, "{call}: peak {} kB", r.peak_kb);
    }
    std::fs::write(
        p.join("scripts/s.rhai"),
        "let t = read_csv(\"ok.csv\");\nprint(`rows ${t.len()} ${t[0].a + t[0].b}`);\n",
    )
    .unwrap();
    let r = crate::hostile_bounds::run(p, &["run", "scripts/s.rhai"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("rows 200000 3"), "{}", r.text);
    std::fs::remove_file(p.join("scripts/s.rhai")).unwrap();
    let mut after = common::snapshot(p);
    after.retain(|k, _| before.contains_key(k));
    assert_eq!(after, before, "a user file changed");
}

/// A 64 MiB motion program of `Joint` lines (3.7 million commands) was parsed whole
/// (784 MB) before the sample cap refused its millionth move: its commands are
/// counted as they are read and the one past `MAX_PROGRAM_COMMANDS` is refused at its
/// line, within [`DATA_RSS_KB`]; the user's files are unchanged.
#[test]
fn a_huge_motion_program_is_counted_before_it_is_kept() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    fitup::demo::write_robots(&p.join("models")).unwrap();
    let line = "Joint 0 0 0 0 0 0\n";
    let mut text = String::from("Interval 0.05\n");
    text.push_str(&line.repeat(((64 << 20) - 64) / line.len()));
    std::fs::write(p.join("big.prg"), text).unwrap();
    let before = common::snapshot(p);
    let r = crate::hostile_bounds::run_within(
        p,
        &["run", "big.prg", "--doc", "models/mz07.yaml"],
        std::time::Duration::from_secs(120),
    );
    eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
    assert_eq!(r.code, Some(1), "{}", r.text);
    assert!(
        r.text.contains("big.prg:1000001:1") && r.text.contains("more than 1,000,000 commands"),
        "{}",
        r.text
    );
    assert!(r.peak_kb < DATA_RSS_KB, "peak {} kB", r.peak_kb);
    assert_eq!(common::snapshot(p), before, "a user file changed");
}
