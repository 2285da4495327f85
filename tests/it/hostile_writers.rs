//! Hostile writers, through the real binary: every writer a script or the command line
//! reaches (`Trajectory`/`Path`/`Sequence.save_csv`, `Skills.save`, `--log`,
//! `db export --out`, `docs --out`, `demo`, `open_db`) is pointed at the results
//! database, a URDF, the hole table, a `.plan.json` problem, a document, a user's own
//! CSV, a symbolic link, a FIFO and a folder. Each write is refused with a message
//! naming the file and the cause, and the sha256 of every user file is unchanged; a
//! file fitup wrote earlier may be replaced; `--force` / `overwrite: true` replaces
//! user files (never links, FIFOs or folders).
//!
//! Bounds: every command is killed after 60 s, which fails the test (a hang, not a
//! speed assertion); a FIFO target must not block a writer.

use crate::common;
use common::copy_tree;

mod sources;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Generous bound on any single command.
const HANG: Duration = Duration::from_secs(60);

/// Exit code and combined output of `fitup ARGS` in `dir`, bounded by [`HANG`].
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let o = common::run_bounded(dir, args, HANG);
    (o.status.code().unwrap_or(-1), common::text(&o))
}

/// sha256 (by `sha256sum`) of every regular file under `dir`, except fitup's own
/// outputs folder `out/` and the output registries.
fn sha256_all(dir: &Path) -> BTreeMap<PathBuf, String> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let md = std::fs::symlink_metadata(&p).unwrap();
            if md.is_dir() && !p.ends_with("out") {
                stack.push(p);
            } else if md.is_file() && !p.ends_with(fitup::project::OUTPUT_REGISTRY) {
                files.push(p);
            }
        }
    }
    let o = std::process::Command::new("sha256sum")
        .args(&files)
        .output()
        .expect("sha256sum");
    assert!(o.status.success());
    String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let (hash, name) = l.split_once("  ").unwrap();
            (PathBuf::from(name), hash.to_string())
        })
        .collect()
}

/// Every file of `before` is still there with the same sha256.
fn unchanged(before: &BTreeMap<PathBuf, String>, dir: &Path, what: &str) {
    let now = sha256_all(dir);
    for (path, hash) in before {
        assert_eq!(
            now.get(path),
            Some(hash),
            "{what}: {} changed or vanished",
            path.display()
        );
    }
}

/// The user files every writer is pointed at, with the cause its refusal must name.
const USER_TARGETS: &[(&str, &str)] = &[
    ("fitup.db", "a SQLite database"),
    ("models/urdf/fitup_arm6.urdf", "a file the project uses"),
    ("models/urdf/arm6_copy.xml", "a file fitup did not write"),
    ("models/holes_fig5.csv", "a file this run read"),
    (
        "models/problems/bar_slot.plan.json",
        "a file fitup did not write",
    ),
    ("models/cell.yaml", "a file the project uses"),
    ("data/mine.csv", "a file fitup did not write"),
];

/// The document [`matrix_script`] opens (a user target the command line's writers,
/// which open no document, refuse only without `--force`).
const OPEN_DOCUMENT: &str = "models/cell.yaml";

/// Targets that are never replaced, even with `--force` / `overwrite: true`.
const SPECIAL_TARGETS: &[(&str, &str)] = &[
    ("link.csv", "symbolic link"),
    ("fifo.csv", "a FIFO"),
    ("dir.csv", "a folder"),
];

/// A project with the repository's models, a results database holding one path (by
/// fitup), a user's CSV, a URDF under another extension, a link, a FIFO and a folder.
fn hostile_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    copy_tree(&common::repo().join("models"), &p.join("models"));
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    for d in ["scripts", "data", "dir.csv"] {
        std::fs::create_dir_all(p.join(d)).unwrap();
    }
    std::fs::copy(
        p.join("models/urdf/fitup_arm6.urdf"),
        p.join("models/urdf/arm6_copy.xml"),
    )
    .unwrap();
    std::fs::write(p.join("data/mine.csv"), "id,x\n1,2.5\n").unwrap();
    std::os::unix::fs::symlink(p.join("data/mine.csv"), p.join("link.csv")).unwrap();
    let fifo = std::process::Command::new("mkfifo")
        .arg(p.join("fifo.csv"))
        .status()
        .unwrap();
    assert!(fifo.success());
    std::fs::write(
        p.join("scripts/db.rhai"),
        "let doc = open_doc(\"models/cell.yaml\");\n\
         let path = doc.plan_disassembly(\"screw4\", #{seed: 1});\n\
         open_db().save(path, \"screw4_out\");\n",
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/db.rhai"]);
    assert_eq!(code, 0, "{t}");
    dir
}

/// A script that builds a trajectory, a path, a sequence and skills, then points each
/// writer at every target (`overwrite` as given), printing `RESULT writer target ok`
/// or `RESULT writer target err MESSAGE`.
fn matrix_script(targets: &[&str], overwrite: bool) -> String {
    let list: Vec<String> = targets.iter().map(|t| format!("{t:?}")).collect();
    format!(
        r#"let assembly = open_doc("models/cell.yaml");
let seq = assembly.assembly_sequence(#{{seed: 1, time_limit_ms: 20000}});
let path = assembly.plan_disassembly("screw4", #{{seed: 1}});
let cell = open_doc("models/cell_arm.yaml");
let robot = cell.robot("mz07");
robot.joints = robot.ik_near([550, 200, 900, 0, 0, 0], [0, 0, 0, 0, -90, 0]);
let traj = robot.move_joint([10, 0, 0, 0, -90, 0]);
let holes = load_holes("models/holes_fig5.csv");
let supply = #{{ plate_a: [900, 20, 750, 0, 0, 0], plate_b: [950, 580, 750, 0, 0, 0] }};
for i in 1..=5 {{ supply[`screw${{i}}`] = [900 + 50 * i, 350, 750, 0, 0, 0]; }}
let skills = assembly.skills(seq, #{{ robot: robot, supply: supply, tool: [0, 0, 0, 180, 0, 0] }});
let opts = #{{overwrite: {overwrite}}};
for t in [{list}] {{
    for w in ["trajectory", "path", "sequence", "skills"] {{
        let r = "ok";
        try {{
            if w == "trajectory" {{ traj.save_csv(t, opts); }}
            if w == "path" {{ path.save_csv(t, opts); }}
            if w == "sequence" {{ seq.save_csv(t, opts); }}
            if w == "skills" {{ skills.save(t, opts); }}
        }} catch (e) {{
            r = `err ${{e}}`;
        }}
        print(`RESULT ${{w}} ${{t}} ${{r}}`);
    }}
}}
"#,
        list = list.join(", ")
    )
}

/// The `RESULT` lines of a matrix run: (writer, target) → outcome.
fn results(text: &str) -> BTreeMap<(String, String), String> {
    text.lines()
        .filter_map(|l| l.strip_prefix("RESULT "))
        .map(|l| {
            let mut f = l.splitn(3, ' ');
            let (w, t, r) = (f.next().unwrap(), f.next().unwrap(), f.next().unwrap());
            ((w.to_string(), t.to_string()), r.to_string())
        })
        .collect()
}

const WRITERS: &[&str] = &["trajectory", "path", "sequence", "skills"];

#[test]
fn script_writers_never_replace_user_files() {
    let dir = hostile_project();
    let p = dir.path();
    let mut targets: Vec<&str> = USER_TARGETS.iter().map(|(t, _)| *t).collect();
    targets.extend(SPECIAL_TARGETS.iter().map(|(t, _)| *t));
    // Each writer in turn replaces what the one before wrote: fitup's own output.
    targets.push("out/own.csv");
    let before = sha256_all(p);
    std::fs::write(
        p.join("scripts/matrix.rhai"),
        matrix_script(&targets, false),
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/matrix.rhai"]);
    assert_eq!(code, 0, "{t}");
    let r = results(&t);
    assert_eq!(r.len(), targets.len() * WRITERS.len(), "{t}");
    for (target, cause) in USER_TARGETS.iter().chain(SPECIAL_TARGETS) {
        // The script has the document open: its own file is a source of it.
        let cause = match *target {
            OPEN_DOCUMENT => "a source of the open document",
            _ => cause,
        };
        for w in WRITERS {
            let got = &r[&(w.to_string(), target.to_string())];
            assert!(
                got.starts_with("err ") && got.contains(target) && got.contains(cause),
                "{w} over {target}: expected a refusal naming it and `{cause}`, got: {got}"
            );
        }
    }
    for w in WRITERS {
        assert_eq!(r[&(w.to_string(), "out/own.csv".into())], "ok", "{w}: {t}");
    }
    // The last writer's plan is what out/own.csv holds.
    let own = std::fs::read_to_string(p.join("out/own.csv")).unwrap();
    assert!(own.trim_start().starts_with('{'), "{own}");
    unchanged(&before, p, "script writers");
    assert!(std::fs::symlink_metadata(p.join("link.csv"))
        .unwrap()
        .file_type()
        .is_symlink());

    // An uncaught refusal is located at the script's line.
    std::fs::write(
        p.join("scripts/clobber.rhai"),
        "let cell = open_doc(\"models/cell_arm.yaml\");\n\
         let t = cell.robot(\"mz07\").move_joint([5, 0, 0, 0, -90, 0]);\n\
         t.save_csv(\"fitup.db\");\n",
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/clobber.rhai"]);
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("clobber.rhai:3") && t.contains("`fitup.db`") && t.contains("overwrite: true"),
        "{t}"
    );
    // A typo in the option is an error, not a silent default.
    std::fs::write(
        p.join("scripts/typo.rhai"),
        "let cell = open_doc(\"models/cell_arm.yaml\");\n\
         let t = cell.robot(\"mz07\").move_joint([5, 0, 0, 0, -90, 0]);\n\
         t.save_csv(\"data/mine.csv\", #{overwrites: true});\n",
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/typo.rhai"]);
    assert_eq!(code, 1, "{t}");
    assert!(t.contains("typo.rhai:3") && t.contains("overwrite"), "{t}");
    unchanged(&before, p, "located refusals");

    // overwrite: true replaces user files, never links, FIFOs or folders, nor a file
    // a document the run has open was read from (tests in `sources`).
    let open_before = std::fs::read(p.join(OPEN_DOCUMENT)).unwrap();
    std::fs::write(p.join("scripts/force.rhai"), matrix_script(&targets, true)).unwrap();
    let (code, t) = run(p, &["run", "scripts/force.rhai"]);
    assert_eq!(code, 0, "{t}");
    let r = results(&t);
    for (target, _) in USER_TARGETS {
        for w in WRITERS {
            let got = &r[&(w.to_string(), target.to_string())];
            if *target == OPEN_DOCUMENT {
                assert!(
                    got.starts_with("err ") && got.contains("a source of the open document"),
                    "{w} {target}: {got}"
                );
            } else {
                assert_eq!(got, "ok", "{w} {target}");
            }
        }
    }
    assert_eq!(std::fs::read(p.join(OPEN_DOCUMENT)).unwrap(), open_before);
    for (target, cause) in SPECIAL_TARGETS {
        let got = &r[&("path".to_string(), target.to_string())];
        assert!(
            got.starts_with("err ") && got.contains(cause),
            "{target}: {got}"
        );
    }
    let mine = std::fs::read_to_string(p.join("data/mine.csv")).unwrap();
    assert!(mine.trim_start().starts_with('{'), "{mine}");
    assert_eq!(
        std::fs::read_to_string(p.join("link.csv")).unwrap(),
        mine,
        "the link still points at the file"
    );
}

#[test]
fn cli_writers_never_replace_user_files() {
    let dir = hostile_project();
    let p = dir.path();
    let before = sha256_all(p);
    let prg = "models/mz07_demo.prg";
    let doc = "models/mz07.yaml";
    // The CLI's writers run no script: the hole table is simply not fitup's.
    let mut targets: Vec<(&str, &str)> = USER_TARGETS
        .iter()
        .map(|&(t, c)| match c {
            "a file this run read" => (t, "a file fitup did not write"),
            _ => (t, c),
        })
        .collect();
    // `--log` reads the program and the document: files the run uses.
    targets.push((prg, "a file"));
    targets.extend_from_slice(SPECIAL_TARGETS);
    for (target, cause) in &targets {
        let cases: [Vec<&str>; 3] = [
            vec!["run", prg, "--doc", doc, "--log", target],
            vec!["db", "export", "path:1", "--csv", "--out", target],
            vec!["docs", "--out", target],
        ];
        for args in cases {
            let (code, t) = run(p, &args);
            assert_eq!(code, 1, "{args:?}: {t}");
            assert!(
                t.contains(target) && t.contains(cause) && t.contains("refusing"),
                "{args:?}: expected the target and `{cause}` in: {t}"
            );
        }
    }
    unchanged(&before, p, "CLI writers");

    // fitup's own outputs may be replaced, by any writer; a user's edit makes the file
    // the user's.
    for args in [
        vec!["run", prg, "--doc", doc, "--log", "out/own.csv"],
        vec!["db", "export", "path:1", "--csv", "--out", "out/own.csv"],
        vec!["docs", "--out", "out/own.csv"],
        vec!["run", prg, "--doc", doc, "--log", "out/own.csv"],
    ] {
        let (code, t) = run(p, &args);
        assert_eq!(code, 0, "{args:?}: {t}");
    }
    std::fs::write(p.join("out/own.csv"), "edited by hand\n").unwrap();
    let (code, t) = run(p, &["docs", "--out", "out/own.csv"]);
    assert_eq!(code, 1, "{t}");
    assert_eq!(
        std::fs::read_to_string(p.join("out/own.csv")).unwrap(),
        "edited by hand\n"
    );

    // --force replaces user files, never links, FIFOs or folders.
    let (code, t) = run(
        p,
        &[
            "run",
            prg,
            "--doc",
            doc,
            "--log",
            "data/mine.csv",
            "--force",
        ],
    );
    assert_eq!(code, 0, "{t}");
    assert!(std::fs::read_to_string(p.join("data/mine.csv"))
        .unwrap()
        .starts_with("t_s,"));
    let (code, t) = run(
        p,
        &[
            "db",
            "export",
            "path:1",
            "--csv",
            "--out",
            "models/holes_fig5.csv",
            "--force",
        ],
    );
    assert_eq!(code, 0, "{t}");
    let (code, t) = run(p, &["docs", "--out", "models/cell.yaml", "--force"]);
    assert_eq!(code, 0, "{t}");
    for (target, cause) in SPECIAL_TARGETS {
        let (code, t) = run(p, &["docs", "--out", target, "--force"]);
        assert_eq!(code, 1, "{target}: {t}");
        assert!(t.contains(cause), "{target}: {t}");
    }
    assert!(p.join("dir.csv").is_dir());
}

#[test]
fn demo_and_databases_leave_other_files_alone() {
    let dir = hostile_project();
    let p = dir.path();
    // `fitup demo --force` never writes through a link or over a FIFO.
    let demo = p.join("demo");
    std::fs::create_dir_all(demo.join("models")).unwrap();
    std::os::unix::fs::symlink(p.join("data/mine.csv"), demo.join("fitup.toml")).unwrap();
    let before = sha256_all(p);
    let (code, t) = run(p, &["demo", "demo"]);
    assert_eq!(code, 1, "{t}");
    let (code, t) = run(p, &["demo", "demo", "--force"]);
    assert_eq!(code, 1, "{t}");
    assert!(
        t.contains("fitup.toml") && t.contains("symbolic link"),
        "{t}"
    );
    assert!(
        !demo.join("models/cell.yaml").exists(),
        "nothing was written"
    );
    unchanged(&before, p, "demo");

    // A results database is never made of another file: a CSV named x.db, another
    // program's SQLite database, the hole table.
    std::fs::write(p.join("data/x.db"), "a,b\n1,2\n").unwrap();
    std::fs::write(p.join("scripts/mkdb.rhai"), "print(\"ran\");\n").unwrap();
    {
        let c = rusqlite::Connection::open(p.join("data/notes.sqlite")).unwrap();
        c.execute_batch("CREATE TABLE notes (t TEXT); INSERT INTO notes VALUES ('mine');")
            .unwrap();
    }
    let before = sha256_all(p);
    for (file, cause) in [
        ("data/x.db", "not a SQLite file"),
        ("models/holes_fig5.csv", "not a SQLite file"),
        ("data/notes.sqlite", "another program"),
    ] {
        std::fs::write(
            p.join("scripts/open.rhai"),
            format!("let d = open_db({file:?});\n"),
        )
        .unwrap();
        let (code, t) = run(p, &["run", "scripts/open.rhai"]);
        assert_eq!(code, 1, "{file}: {t}");
        assert!(
            t.contains("open.rhai:1")
                && t.contains(cause)
                && t.contains("not a fitup results database"),
            "{file}: {t}"
        );
        // `run --db` goes on unrecorded, saying why.
        let (_, t) = run(p, &["run", "scripts/mkdb.rhai", "--db", file]);
        assert!(
            t.contains(cause) && t.contains("not a fitup results database"),
            "--db {file}: {t}"
        );
    }
    unchanged(&before, p, "databases");
    // fitup's own database still opens.
    std::fs::write(
        p.join("scripts/own.rhai"),
        "print(open_db().paths().len());\n",
    )
    .unwrap();
    let (code, t) = run(p, &["run", "scripts/own.rhai"]);
    assert_eq!(code, 0, "{t}");
}
