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
