//! Jails under races: a swapper thread replaces a project folder with a symbolic link
//! to a folder outside the project, and back, over and over (a bounded number of
//! times), while fitup writes outputs into that folder or reads a mesh from it. The
//! writer and the mesh cache check and use the same opened folder handle (walked from
//! the project root without following a link), so:
//!
//! - nothing is ever written outside (the outside folder stays empty: no output, no
//!   registry, no temporary file), and no temporary file is left inside;
//! - the outside mesh is never loaded (its triangle count never appears);
//! - every run ends (exit 0 or a located error) within the runner's bound, and the
//!   user's files are byte for byte as before.

use crate::common;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// How many times the swapper swaps at most (each swap: the folder away, a link in its
/// place, a pause, the folder back).
const SWAPS: usize = 400;

/// How many swaps a race needs to have raced against its work: the work is done again
/// (a round) until the swapper has swapped this often while it ran, so a loaded machine
/// (where the swapper thread gets few turns during one round) runs more rounds instead
/// of racing less.
const MIN_SWAPS: usize = 11;

/// The most rounds of work a race runs waiting for [`MIN_SWAPS`] swaps: a swapper
/// that cannot swap at all fails the race instead of running it forever.
const MAX_ROUNDS: usize = 30;

/// Swaps `folder` for a link to `outside` and back until `stop` or [`SWAPS`] swaps,
/// counting them in `swaps` as they are done.
fn swapper(
    folder: PathBuf,
    outside: PathBuf,
    stop: Arc<AtomicBool>,
    swaps: Arc<AtomicUsize>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let away = folder.with_extension("away");
        while swaps.load(Ordering::Relaxed) < SWAPS && !stop.load(Ordering::Relaxed) {
            if std::fs::rename(&folder, &away).is_ok() {
                let _ = std::os::unix::fs::symlink(&outside, &folder);
                std::thread::sleep(Duration::from_micros(300));
                let _ = std::fs::remove_file(&folder);
                let _ = std::fs::rename(&away, &folder);
                swaps.fetch_add(1, Ordering::Relaxed);
            }
            std::thread::sleep(Duration::from_micros(300));
        }
        // Leave the real folder in place whatever happened.
        if !folder.is_dir() {
            let _ = std::fs::remove_file(&folder);
            let _ = std::fs::rename(&away, &folder);
        }
    })
}

/// Opens of anything in a folder tree outside the project while a race runs, seen by
/// inotify (`IN_OPEN`, `IN_ACCESS`, `IN_MODIFY`: a read or write through a swapped
/// link opens the outside file; refusing the link opens nothing there).
struct Opens {
    fd: std::os::fd::OwnedFd,
    names: std::collections::HashMap<i32, PathBuf>,
}

impl Opens {
    fn watch(dir: &Path) -> Opens {
        use rustix::fs::inotify;
        let fd =
            inotify::init(inotify::CreateFlags::NONBLOCK | inotify::CreateFlags::CLOEXEC).unwrap();
        let mut names = std::collections::HashMap::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            let wd = inotify::add_watch(
                &fd,
                &d,
                inotify::WatchFlags::OPEN
                    | inotify::WatchFlags::ACCESS
                    | inotify::WatchFlags::MODIFY,
            )
            .unwrap();
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if std::fs::symlink_metadata(&p).unwrap().is_dir() {
                    stack.push(p);
                }
            }
            names.insert(wd, d);
        }
        // The walk above opened the folders: what it left queued is not the race's.
        let _ = Opens::drain(&fd, &names);
        Opens { fd, names }
    }

    /// What was opened, read or written since [`watch`](Self::watch) (path: events).
    fn seen(self) -> Vec<String> {
        Opens::drain(&self.fd, &self.names)
    }

    fn drain(
        fd: &std::os::fd::OwnedFd,
        names: &std::collections::HashMap<i32, PathBuf>,
    ) -> Vec<String> {
        use rustix::fs::inotify;
        let mut buf = [std::mem::MaybeUninit::<u8>::uninit(); 4096];
        let mut reader = inotify::Reader::new(fd, &mut buf);
        let mut out = Vec::new();
        while let Ok(e) = reader.next() {
            let mut p = names.get(&e.wd()).cloned().unwrap_or_default();
            if let Some(n) = e.file_name() {
                p.push(n.to_string_lossy().as_ref());
            }
            out.push(format!("{}: {:?}", p.display(), e.events()));
        }
        out
    }
}

/// Every file below `dir` whose name is a writer's temporary file.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    common::snapshot(dir)
        .into_keys()
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(".fitup-") && n.ends_with(".tmp"))
        })
        .collect()
}

/// Runs `work` while [`swapper`] swaps `folder` for a link to `outside`, again and
/// again until the swapper has done [`MIN_SWAPS`] swaps while it ran (every round's
/// result returned, the first round always run), then checks that the swapper did
/// swap that often (at most [`MAX_ROUNDS`] rounds), that nothing below `outside` was
/// even opened (inotify: no open of a file or folder there, [`Opens`]) and that
/// nothing there was written: every file keeps its bytes (sha256), inode and
/// modification time, and none appeared or vanished. The one setup of every race here.
fn while_swapped<T>(folder: &Path, outside: &Path, mut work: impl FnMut() -> T) -> Vec<T> {
    let ids = identities(outside);
    let hashes = common::snapshot(outside);
    let opens = Opens::watch(outside);
    let stop = Arc::new(AtomicBool::new(false));
    let swaps = Arc::new(AtomicUsize::new(0));
    let swap = swapper(
        folder.to_path_buf(),
        outside.to_path_buf(),
        stop.clone(),
        swaps.clone(),
    );
    let mut rounds = vec![work()];
    while swaps.load(Ordering::Relaxed) < MIN_SWAPS && rounds.len() < MAX_ROUNDS {
        rounds.push(work());
    }
    stop.store(true, Ordering::Relaxed);
    swap.join().unwrap();
    let swaps = swaps.load(Ordering::Relaxed);
    let opened = opens.seen();
    eprintln!(
        "{swaps} swaps of {} in {} rounds",
        folder.display(),
        rounds.len()
    );
    assert!(swaps >= MIN_SWAPS, "the swapper ran ({swaps} swaps)");
    assert_eq!(opened, Vec::<String>::new(), "opened outside");
    assert_eq!(identities(outside), ids, "written outside");
    assert_eq!(common::snapshot(outside), hashes, "changed outside");
    rounds
}

/// The sums of the (ok, refused) counts of every round of a race.
fn summed(rounds: Vec<(usize, usize)>) -> (usize, usize) {
    rounds
        .into_iter()
        .fold((0, 0), |(a, b), (x, y)| (a + x, b + y))
}

/// A script writing outputs into `out/` 300 times while `out` is swapped for a link
/// to a folder outside: the outside folder stays empty, nothing is left behind.
#[test]
fn outputs_never_land_outside_while_their_folder_is_swapped() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    std::fs::create_dir(p.join("out")).unwrap();
    std::fs::write(
        p.join("scripts/write.rhai"),
        "let d = open_doc(\"models/cell.yaml\");\nlet ok = 0;\nfor i in 0..300 {\n    try {\n        d.export_glb(`out/cell_${i % 7}.glb`, #{overwrite: true});\n        ok += 1;\n    } catch (e) {}\n}\nprint(`written ${ok}`);\n",
    )
    .unwrap();
    let before = common::snapshot(p);
    for r in while_swapped(&p.join("out"), outside.path(), || {
        crate::hostile_bounds::run(p, &["run", "scripts/write.rhai"])
    }) {
        ran_clean(p, &r);
    }
    // The user's files are as they were (outputs in out/ are fitup's own).
    let now = common::snapshot(p);
    for (path, hash) in &before {
        assert_eq!(now.get(path), Some(hash), "{} changed", path.display());
    }
}

/// `fitup check` run again and again while the mesh folder is swapped for a link to a
/// folder holding another `screw.stl`: the outside mesh is never loaded.
#[test]
fn the_mesh_cache_never_reads_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    // The outside screw: a different mesh (a box split finer: 24 triangles).
    let mut other = fitup::mesh::Mesh::cuboid(
        fitup::math::Point3::origin(),
        fitup::math::Point3::new(1.0, 1.0, 1.0),
    );
    other.append(&fitup::mesh::Mesh::cuboid(
        fitup::math::Point3::new(2.0, 0.0, 0.0),
        fitup::math::Point3::new(3.0, 1.0, 1.0),
    ));
    for f in std::fs::read_dir(p.join("models/meshes")).unwrap() {
        let name = f.unwrap().file_name();
        fitup::mesh::write_stl(&outside.path().join(&name), &other).unwrap();
    }
    let inside = crate::hostile_bounds::run(p, &["check", "models/cell.yaml"]);
    assert_eq!(inside.code, Some(0), "{}", inside.text);
    assert!(!inside.text.contains(" 24 triangles"), "{}", inside.text);
    let before = common::snapshot(p);
    let (ok, refused) = summed(while_swapped(
        &p.join("models/meshes"),
        outside.path(),
        || {
            let (mut ok, mut refused) = (0, 0);
            for _ in 0..40 {
                let r = crate::hostile_bounds::run(p, &["check", "models/cell.yaml"]);
                assert!(!r.text.contains("panicked"), "{}", r.text);
                assert!(
                    !r.text.contains(" 24 triangles"),
                    "the outside mesh was loaded:\n{}",
                    r.text
                );
                match r.code {
                    Some(0) => ok += 1,
                    Some(1) => {
                        // Located: the document line of the part.
                        assert!(r.text.contains("cell.yaml:"), "{}", r.text);
                        refused += 1;
                    }
                    other => panic!("exit {other:?}: {}", r.text),
                }
            }
            (ok, refused)
        },
    ));
    eprintln!("{ok} runs read the inside meshes, {refused} were refused");
    assert_eq!(common::snapshot(p), before);
}

/// A run raced against a swap ended well (its peak memory shown) and left no
/// temporary file in the project `p`.
fn ran_clean(p: &Path, r: &crate::hostile_bounds::Run) {
    eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert_eq!(
        temporaries(p),
        Vec::<PathBuf>::new(),
        "temporary files left"
    );
}

/// Inode and modification time of every file below `dir`: a write replaces the inode
/// (atomic rename) even when it writes the same bytes.
fn identities(dir: &Path) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
    use std::os::unix::fs::MetadataExt;
    let mut out: Vec<_> = common::snapshot(dir)
        .into_keys()
        .map(|p| {
            let md = std::fs::symlink_metadata(&p).unwrap();
            (p, md.ino(), md.modified().unwrap())
        })
        .collect();
    out.sort();
    out
}

/// A script saving its document 400 times (`save` and `save_as` over itself, the same
/// text each time) while the document's folder (`docs/`, the meshes elsewhere) is
/// swapped for a link to a folder holding an identical copy of it: the check of what
/// is on disk and the write go through one folder handle walked from the project
/// root, so the outside copy is never replaced (its files keep their inodes and
/// times), and no temporary file is left on either side. The script opens the
/// document again until an open falls between two swaps, so the saves do race. Its
/// retries are bounded far above what the swapper can refuse: the swapper stops after
/// [`SWAPS`] swaps, and an open then succeeds (a CI run refused 5,000 opens during 196
/// swaps on a slower machine, where an open no longer fits between two swaps).
#[test]
fn document_saves_never_land_outside_while_their_folder_is_swapped() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    std::fs::create_dir(p.join("docs")).unwrap();
    let yaml = std::fs::read_to_string(p.join("models/cell.yaml"))
        .unwrap()
        .replace("stl: meshes/", "stl: ../models/meshes/");
    std::fs::write(p.join("docs/cell.yaml"), yaml).unwrap();
    std::fs::write(
        p.join("scripts/save.rhai"),
        "let d = ();
let opened = false;
let tries = 0;
while !opened {
    try {
        d = open_doc(\"docs/cell.yaml\");
        opened = true;
    } catch (e) {
        tries += 1;
        if tries > 200000 { throw e; }
    }
}
let ok = 0;
for i in 0..400 {
    try {
        if i % 2 == 0 { d.save(); } else { d.save_as(\"docs/cell.yaml\"); }
        ok += 1;
    } catch (e) {}
}
print(`saved ${ok} of 400 (${tries} opens refused)`);\n",
    )
    .unwrap();
    // The first run normalises the file; the attacker's copy is that text.
    let r = crate::hostile_bounds::run(p, &["run", "scripts/save.rhai"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("saved 400 of 400"), "{}", r.text);
    std::fs::copy(p.join("docs/cell.yaml"), outside.path().join("cell.yaml")).unwrap();
    for r in while_swapped(&p.join("docs"), outside.path(), || {
        crate::hostile_bounds::run_within(p, &["run", "scripts/save.rhai"], Duration::from_secs(60))
    }) {
        ran_clean(p, &r);
    }
    assert_eq!(
        temporaries(outside.path()),
        Vec::<PathBuf>::new(),
        "temporary files outside"
    );
}

/// A script opening `data/x.db` (`open_db`) and storing a snapshot in it 300 times
/// while `data/` is swapped for a link to a folder holding an identical copy of the
/// database: SQLite opens the file, its `-wal` and `-shm` through the folder handle
/// walked from the project root (never by name), so the outside copy is never opened
/// for writing (its bytes, inode and time stay), no `-wal`/`-shm` file appears outside,
/// and every snapshot lands in the inside database.
#[test]
fn databases_never_open_outside_while_their_folder_is_swapped() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    std::fs::create_dir(p.join("data")).unwrap();
    std::fs::write(
        p.join("scripts/db.rhai"),
        "let d = open_doc(\"models/cell.yaml\");
let ok = 0;
let tries = 0;
let errs = #{};
while ok < 200 && tries < 200000 {
    tries += 1;
    try {
        let db = open_db(\"data/x.db\");
        db.save(d);
        ok += 1;
    } catch (e) {
        let k = `${e}`;
        k.truncate(50);
        if k in errs { errs[k] += 1; } else { errs[k] = 1; }
    }
}
print(`stored ${ok} in ${tries} tries ${errs}`);
",
    )
    .unwrap();
    // The first run makes the database; the attacker's copy is that file.
    let r = crate::hostile_bounds::run(p, &["run", "scripts/db.rhai"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("stored 200 in 200 tries"), "{}", r.text);
    let count = |db: &Path| -> i64 {
        let c =
            rusqlite::Connection::open_with_flags(db, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
                .unwrap();
        c.query_row("SELECT count(*) FROM snapshots", [], |r| r.get(0))
            .unwrap()
    };
    assert_eq!(count(&p.join("data/x.db")), 200);
    std::fs::copy(p.join("data/x.db"), outside.path().join("x.db")).unwrap();
    let mut stored = 0;
    for r in while_swapped(&p.join("data"), outside.path(), || {
        crate::hostile_bounds::run_within(p, &["run", "scripts/db.rhai"], Duration::from_secs(60))
    }) {
        eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
        assert_eq!(r.code, Some(0), "{}", r.text);
        assert!(!r.text.contains("panicked"), "{}", r.text);
        let n: i64 = r
            .text
            .split("stored ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{}", r.text));
        assert!(n > 0, "{}", r.text);
        stored += n;
    }
    assert_eq!(
        count(&p.join("data/x.db")),
        200 + stored,
        "every stored snapshot is in the inside database"
    );
}

/// The files a script reads by path — a document (`open_doc`), a hole table
/// (`load_holes`), a motion program (`run_program`), a URDF (`load_urdf`) and an
/// imported module — are read through the project's held root while their folder is
/// swapped for a link to a folder holding other files of the same names: every read
/// returns the inside file or a located refusal, never the outside one, and nothing
/// outside changes.
#[test]
fn script_reads_never_go_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(p.join("data")).unwrap();
    let urdf = |name: &str, joints: usize| {
        let mut s = format!("<robot name=\"{name}\"><link name=\"l0\"/>");
        for j in 1..=joints {
            s += &format!(
                "<link name=\"l{j}\"/><joint name=\"j{j}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{j}\"/><origin xyz=\"0 0 0.1\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
                j - 1
            );
        }
        s + "</robot>\n"
    };
    let yaml = std::fs::read_to_string(p.join("models/cell.yaml"))
        .unwrap()
        .replace("stl: meshes/", "stl: ../models/meshes/");
    for (d, who, holes, joints) in [
        (p.join("data"), "inside", 3, 2),
        (o.to_path_buf(), "outside", 1, 4),
    ] {
        std::fs::write(d.join("m.rhai"), format!("export const WHO = \"{who}\";\n")).unwrap();
        let rows: String = (0..holes)
            .map(|i| format!("h{i},{i},0,0,0,0,1\n"))
            .collect();
        std::fs::write(d.join("holes.csv"), format!("id,x,y,z,nx,ny,nz\n{rows}")).unwrap();
        std::fs::write(d.join("robot.urdf"), urdf(who, joints)).unwrap();
        // The outside document names a component the inside one lacks.
        let doc = if who == "outside" {
            yaml.replace("plate_b", "plate_outside")
        } else {
            yaml.clone()
        };
        std::fs::write(d.join("cell.yaml"), doc).unwrap();
    }
    std::fs::write(
        p.join("scripts/read.rhai"),
        "let seen = #{inside: 0, refused: 0, outside: 0};
for i in 0..60 {
    try { import \"../data/m\" as m; if m::WHO == \"inside\" { seen.inside += 1; } else { seen.outside += 1; } } catch (e) { seen.refused += 1; }
    for k in 0..40 {
        try { let h = load_holes(\"data/holes.csv\"); if h.len() == 3 { seen.inside += 1; } else { seen.outside += 1; } } catch (e) { seen.refused += 1; }
        try { let r = load_urdf(\"data/robot.urdf\"); if r.name == \"inside\" && r.dof == 2 { seen.inside += 1; } else { seen.outside += 1; } } catch (e) { seen.refused += 1; }
        if k % 8 == 0 {
            try {
                let d = open_doc(\"data/cell.yaml\");
                let names = d.components().map(|c| c.name);
                if names.contains(\"plate_outside\") { seen.outside += 1; } else { seen.inside += 1; }
            } catch (e) { seen.refused += 1; }
        }
    }
}
print(`seen ${seen}`);
",
    )
    .unwrap();
    let r = crate::hostile_bounds::run(p, &["run", "scripts/read.rhai"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(
        r.text.contains("\"outside\": 0, \"refused\": 0"),
        "{}",
        r.text
    );
    let before = common::snapshot(p);
    for r in while_swapped(&p.join("data"), o, || {
        crate::hostile_bounds::run_within(
            p,
            &["run", "scripts/read.rhai"],
            Duration::from_secs(120),
        )
    }) {
        eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
        assert_eq!(r.code, Some(0), "{}", r.text);
        assert!(!r.text.contains("panicked"), "{}", r.text);
        assert!(
            r.text.contains("\"outside\": 0,"),
            "an outside file was read: {}",
            r.text
        );
    }
    assert_eq!(common::snapshot(p), before, "a user file changed");
}

/// Runs `fitup ARGS` in `p` 30 times while the folder `swapped` (below `p`: `data/`
/// in most tests) is swapped for a link to `outside` (whose files carry `marker`): no
/// run shows the marker in any case (an outside file was never read), every run shows
/// `inside` (it read the inside file) or ends with exit 1 naming `file` (a refused
/// path is a file error, never usage), and at least one run read the inside file.
/// Returns (inside reads, refusals).
fn cli_reads_while_folder_swapped(
    p: &Path,
    swapped: &Path,
    outside: &Path,
    args: &[&str],
    file: &str,
    inside: &str,
    marker: &str,
) -> (usize, usize) {
    let before = common::snapshot(p);
    let seen = summed(while_swapped(swapped, outside, || {
        let (mut read, mut refused) = (0, 0);
        for _ in 0..30 {
            let r = crate::hostile_bounds::run(p, args);
            assert!(!r.text.contains("panicked"), "{}", r.text);
            assert!(
                !r.text.to_lowercase().contains(&marker.to_lowercase()),
                "an outside file was read:\n{}",
                r.text
            );
            assert!(
                matches!(r.code, Some(0..=1)),
                "exit {:?}: {}",
                r.code,
                r.text
            );
            if r.text.contains(inside) {
                read += 1;
            } else {
                assert_ne!(r.code, Some(0), "{}", r.text);
                assert!(r.text.contains(file), "not located: {}", r.text);
                refused += 1;
            }
        }
        (read, refused)
    }));
    eprintln!("{args:?}: {} inside reads, {} refused", seen.0, seen.1);
    assert!(seen.0 > 0, "the inside file was never read");
    assert_eq!(common::snapshot(p), before, "a user file changed");
    seen
}

/// `fitup skills template FILE` and `fitup skills run PLAN` read the file they are
/// given through its project's held root (the project found along the path as
/// written): while `data/` is swapped for a link to a folder holding a template of
/// another operation and a plan that names itself, neither outside file is ever read
/// (not even when the outside folder holds a `fitup.toml` of its own).
#[test]
fn cli_skills_reads_never_go_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(p.join("data")).unwrap();
    let template = |op: &str| {
        std::fs::read_to_string(common::repo().join(format!("models/templates/{op}.yaml"))).unwrap()
    };
    std::fs::write(p.join("data/t.yaml"), template("insertion")).unwrap();
    std::fs::write(o.join("t.yaml"), template("screw")).unwrap();
    // The inside plan is refused for a missing field; the outside one, a JSON string,
    // would be quoted in its refusal.
    std::fs::write(p.join("data/plan.json"), "{}").unwrap();
    std::fs::write(o.join("plan.json"), "\"FROMOUTSIDE\"").unwrap();
    std::fs::write(o.join("fitup.toml"), "").unwrap();
    let r = crate::hostile_bounds::run(p, &["skills", "template", "data/t.yaml"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(r.text.contains("insertion template"), "{}", r.text);
    let (read, _) = cli_reads_while_folder_swapped(
        p,
        &p.join("data"),
        o,
        &["skills", "template", "data/t.yaml"],
        "data/t.yaml",
        "insertion template",
        "screw",
    );
    assert!(read > 0);
    let r = crate::hostile_bounds::run(p, &["skills", "run", "data/plan.json", "--plain"]);
    assert_eq!(r.code, Some(1), "{}", r.text);
    assert!(r.text.contains("missing field"), "{}", r.text);
    cli_reads_while_folder_swapped(
        p,
        &p.join("data"),
        o,
        &["skills", "run", "data/plan.json", "--plain"],
        "data/plan.json",
        "missing field",
        "FROMOUTSIDE",
    );
}

/// `fitup run PROGRAM --doc DOC` reads the motion program through the project's held
/// root: while `data/` is swapped for a link to a folder holding another program of
/// the same name (an instruction of its own), the outside program is never read.
#[test]
fn cli_programs_never_go_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    fitup::demo::write_robots(&p.join("models")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(p.join("data")).unwrap();
    std::fs::write(
        p.join("data/p.prg"),
        "Interval 0.05\nJoint 0 0 0 0 0 0\nJoint 10 0 0 0 0 0\n",
    )
    .unwrap();
    std::fs::write(o.join("p.prg"), "FROMOUTSIDE 1\n").unwrap();
    std::fs::write(o.join("fitup.toml"), "").unwrap();
    let args = ["run", "data/p.prg", "--doc", "models/mz07.yaml"];
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(0), "{}", r.text);
    // The log: its header, and the last Joint command's row.
    assert!(r.text.starts_with("t_s,j1_deg"), "{}", r.text);
    assert!(r.text.contains(",10.000000,"), "{}", r.text);
    cli_reads_while_folder_swapped(
        p,
        &p.join("data"),
        o,
        &args,
        "p.prg",
        "t_s,j1_deg",
        "FROMOUTSIDE",
    );
}

/// `fitup watch` hashes the files a run read (to tell a save from a touch) through the
/// project's held root: while the folder of a module and a hole table the script read
/// is swapped for a link to a folder holding files of the same names, the watcher
/// (its hashing, its reruns, its file-system watch) never opens anything outside.
#[test]
fn watch_never_hashes_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(p.join("data")).unwrap();
    for (d, who, holes) in [
        (p.join("data"), "inside", 3),
        (o.to_path_buf(), "outside", 1),
    ] {
        std::fs::write(d.join("m.rhai"), format!("export const WHO = \"{who}\";\n")).unwrap();
        let rows: String = (0..holes)
            .map(|i| format!("h{i},{i},0,0,0,0,1\n"))
            .collect();
        std::fs::write(d.join("holes.csv"), format!("id,x,y,z,nx,ny,nz\n{rows}")).unwrap();
    }
    std::fs::write(
        p.join("scripts/w.rhai"),
        "import \"../data/m\" as m;\nlet h = load_holes(\"data/holes.csv\");\nprint(`who ${m::WHO} ${h.len()}`);\n",
    )
    .unwrap();
    let before = common::snapshot(p);
    let mut w = common::Watch::start(p, "scripts/w.rhai", &[]);
    w.out.wait_for("== done 1 ok", Duration::from_secs(60));
    assert!(
        w.out.seen.iter().any(|l| l == "who inside 3"),
        "{:?}",
        w.out.seen
    );
    while_swapped(&p.join("data"), o, || {
        // The swapper's bounded swaps, and the reruns they cause; then the watch is
        // stopped (a bound on the test, not a speed assertion).
        std::thread::sleep(Duration::from_secs(3));
    });
    w.out.quiet(Duration::from_millis(500));
    let all = w.out.seen.join("\n");
    drop(w);
    let reruns = all.matches("== run ").count();
    eprintln!("{reruns} runs under watch");
    assert!(
        !all.contains("who outside"),
        "an outside file was read: {all}"
    );
    assert!(!all.contains("panicked"), "{all}");
    assert_eq!(common::snapshot(p), before, "a user file changed");
}

/// The project of a file named on the command line is searched from folders held all
/// the way from `/`: while a folder three levels above the file (`a` of
/// `a/b/c/t.yaml`, the file's folder `c` being a candidate root) is swapped for a link
/// to a folder whose `b/c/` holds a `fitup.toml` and another template (and a motion
/// program of its own), the outside `fitup.toml` is never taken as the root and
/// nothing outside is opened (not even a folder), for `skills template` and for `run
/// PROGRAM`; a refused run exits 1.
#[test]
fn the_project_search_never_looks_through_a_folder_swapped_far_above() {
    let dir = common::project();
    let p = dir.path();
    fitup::demo::write_robots(&p.join("models")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir_all(p.join("a/b/c")).unwrap();
    std::fs::create_dir_all(o.join("b/c")).unwrap();
    let template = |op: &str| {
        std::fs::read_to_string(common::repo().join(format!("models/templates/{op}.yaml"))).unwrap()
    };
    std::fs::write(p.join("a/b/c/t.yaml"), template("insertion")).unwrap();
    std::fs::write(o.join("b/c/t.yaml"), template("screw")).unwrap();
    std::fs::write(
        p.join("a/b/c/p.prg"),
        "Interval 0.05\nJoint 0 0 0 0 0 0\nJoint 10 0 0 0 0 0\n",
    )
    .unwrap();
    std::fs::write(o.join("b/c/p.prg"), "FROMOUTSIDE 1\n").unwrap();
    for d in ["", "b", "b/c"] {
        std::fs::write(o.join(d).join("fitup.toml"), "").unwrap();
    }
    let args = ["skills", "template", "a/b/c/t.yaml"];
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(0), "{}", r.text);
    cli_reads_while_folder_swapped(
        p,
        &p.join("a"),
        o,
        &args,
        "t.yaml",
        "insertion template",
        "screw",
    );
    // The document is inside the project, the program three levels down.
    let args = ["run", "a/b/c/p.prg", "--doc", "models/mz07.yaml"];
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(0), "{}", r.text);
    let (_, refused) = cli_reads_while_folder_swapped(
        p,
        &p.join("a"),
        o,
        &args,
        "p.prg",
        "t_s,j1_deg",
        "FROMOUTSIDE",
    );
    eprintln!("{refused} refused runs");
}

/// Templates named inside a script (`skills(seq, #{templates: [...]})`) are read
/// through the project's held root: while their folder is swapped for a link to a
/// folder holding a template of the same name, the outside template is never read
/// (each read is the inside one, or a located refusal) and nothing outside is opened.
#[test]
fn script_templates_never_go_through_a_swapped_folder() {
    let dir = common::project();
    let p = dir.path();
    fitup::demo::write_robots(&p.join("models")).unwrap();
    common::copy_wheel(p);
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(p.join("data")).unwrap();
    // Both templates are refused at their operation, which each refusal quotes: the
    // inside one's or the outside one's (no chain is planned per read).
    let template = |op: &str| {
        std::fs::read_to_string(common::repo().join("models/templates/insertion.yaml"))
            .unwrap()
            .replace("operation: insertion", &format!("operation: {op}"))
    };
    std::fs::write(p.join("data/t.yaml"), template("insideop")).unwrap();
    std::fs::write(o.join("t.yaml"), template("fromoutside")).unwrap();
    std::fs::write(
        p.join("scripts/t.rhai"),
        "let wheel = open_doc(\"models/wheel.yaml\");
let seq = wheel.assembly_sequence(#{seed: 1});
let cell = open_doc(\"models/mz07.yaml\");
let robot = cell.robot(\"mz07\");
let seen = #{inside: 0, refused: 0, outside: 0};
for i in 0..400 {
    try {
        wheel.skills(seq, #{robot: robot, templates: [\"data/t.yaml\"]});
        seen.outside += 1;
    } catch (e) {
        let e = `${e}`;
        if e.contains(\"fromoutside\") { seen.outside += 1; }
        else if e.contains(\"insideop\") { seen.inside += 1; }
        else if e.contains(\"t.yaml\") { seen.refused += 1; }
        else { throw e; }
    }
}
print(`seen ${seen}`);
",
    )
    .unwrap();
    let r =
        crate::hostile_bounds::run_within(p, &["run", "scripts/t.rhai"], Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(
        r.text
            .contains("\"inside\": 400, \"outside\": 0, \"refused\": 0"),
        "{}",
        r.text
    );
    let before = common::snapshot(p);
    for r in while_swapped(&p.join("data"), o, || {
        crate::hostile_bounds::run_within(p, &["run", "scripts/t.rhai"], Duration::from_secs(120))
    }) {
        eprintln!("peak {} kB; {}", r.peak_kb, r.text.trim());
        assert_eq!(r.code, Some(0), "{}", r.text);
        assert!(
            r.text.contains("\"outside\": 0,"),
            "an outside template was read: {}",
            r.text
        );
        assert!(!r.text.contains("\"inside\": 0,"), "{}", r.text);
    }
    assert_eq!(common::snapshot(p), before, "a user file changed");
}

/// A project store `DIR/.fitup-cache/step` holding one stale entry (its STEP file,
/// `gone.step` of `dir`, does not exist), and `fitup.toml` in `dir`.
fn stale_store(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("fitup.toml"), "").unwrap();
    let store = dir.join(".fitup-cache/step");
    std::fs::create_dir_all(&store).unwrap();
    let source = dir.canonicalize().unwrap().join("gone.step");
    let entry = store.join("00000000000000a1.tess");
    std::fs::write(
        &entry,
        crate::hostile_round3::forged_entry(&source, 1000, 0xa1),
    )
    .unwrap();
    entry
}

/// `fitup cache prune a/b` (a folder of the project `p`, whose `fitup.toml` is at
/// its top) finds its project through folders held from `/` down and prunes through
/// that held root: while `a` is swapped for a link to an outside folder whose `b/`
/// is a project of its own (a `fitup.toml` and a store holding a stale entry), the
/// outside store is never opened, let alone pruned (it was: the folder was made
/// canonical by name and the nearest `fitup.toml` looked up along it, so the link
/// led the prune into the outside project and removed its entry).
#[test]
fn cache_prune_never_goes_through_a_swapped_folder() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(p.join("a/b")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    std::fs::create_dir(o.join("b")).unwrap();
    let entry = stale_store(&o.join("b"));
    let args = ["cache", "prune", "a/b"];
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(0), "{}", r.text);
    let before = common::snapshot(p);
    let (pruned, refused) = summed(while_swapped(&p.join("a"), o, || {
        let (mut pruned, mut refused) = (0, 0);
        for _ in 0..40 {
            let r = crate::hostile_bounds::run(p, &args);
            assert!(!r.text.contains("panicked"), "{}", r.text);
            if r.code == Some(0) {
                assert!(r.text.contains("removed 0 files"), "{}", r.text);
                pruned += 1;
            } else {
                assert_eq!(r.code, Some(1), "{}", r.text);
                assert!(r.text.contains("a/b"), "not located: {}", r.text);
                refused += 1;
            }
        }
        (pruned, refused)
    }));
    eprintln!("{pruned} prunes of the project, {refused} refused");
    assert!(pruned > 0, "the project was never pruned");
    assert!(entry.is_file(), "the outside entry was removed");
    assert_eq!(common::snapshot(p), before, "a user file changed");
}

/// The library's prune of a project works on the project's held root: when the
/// root's path is renamed and a link to another project put in its place after the
/// project was found, `prune_project_store` prunes the project it was given (its
/// stale entry is removed) and leaves the other one alone (it looked the root, the
/// store and the sources up by name again, three times).
#[test]
fn a_project_prune_stays_in_the_project_it_was_given() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().canonicalize().unwrap();
    let (p, o) = (d.join("p"), d.join("o"));
    std::fs::create_dir_all(&p).unwrap();
    std::fs::create_dir_all(&o).unwrap();
    stale_store(&p);
    let other = stale_store(&o);
    let project = fitup::project::Project::for_folder(&p).unwrap();
    assert_eq!(project.root(), p);
    std::fs::rename(&p, d.join("p.moved")).unwrap();
    std::os::unix::fs::symlink(&o, &p).unwrap();
    let (report, _) =
        fitup::document::tessellations::prune_project_store(&project, false, u64::MAX).unwrap();
    assert_eq!(report.removed.len(), 1, "{report:?}");
    assert!(other.is_file(), "the other project's entry was removed");
    assert_eq!(
        common::snapshot(&d.join("p.moved/.fitup-cache/step")).len(),
        0,
        "the stale entry of the project given is still there"
    );
}

/// A `step:` part is read through the project's held root and handed to the Open
/// CASCADE child as an opened file: while `parts/` is swapped for a link to a folder
/// holding another STEP file of the same name (a sphere; the inside one is a box of 12
/// triangles), `fitup check` (its tessellation store emptied before each run, so each
/// run reads the STEP file) reports the box or a located refusal, never the sphere,
/// and nothing outside is opened.
#[cfg(feature = "step")]
#[test]
fn step_parts_never_go_through_a_swapped_folder() {
    step_parts_race();
}

/// The body of [`step_parts_never_go_through_a_swapped_folder`], compiled in every
/// build (checked by the default build's clippy), run with the `step` feature.
#[cfg_attr(not(feature = "step"), allow(dead_code))]
fn step_parts_race() {
    use fitup::mesh::step::{write_test_step, STEP_STORE};
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir(p.join("parts")).unwrap();
    write_test_step("box", &p.join("parts/x.step")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    write_test_step("sphere", &o.join("x.step")).unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        "parts:\n  p:\n    step: parts/x.step\ncomponents:\n  - {name: p-1, part: p}\n",
    )
    .unwrap();
    let inside = |t: &str| {
        t.lines()
            .any(|l| l.contains(" 12 triangles") && l.contains("parts/x.step"))
    };
    let r = crate::hostile_bounds::run(p, &["check", "cell.yaml"]);
    assert_eq!(r.code, Some(0), "{}", r.text);
    assert!(inside(&r.text), "{}", r.text);
    let _ = std::fs::remove_dir_all(p.join(STEP_STORE));
    let before = common::snapshot(p);
    let (read, refused) = summed(while_swapped(&p.join("parts"), o, || {
        let (mut read, mut refused) = (0, 0);
        for _ in 0..20 {
            let _ = std::fs::remove_dir_all(p.join(STEP_STORE));
            let r = crate::hostile_bounds::run(p, &["check", "cell.yaml"]);
            assert!(!r.text.contains("panicked"), "{}", r.text);
            if inside(&r.text) {
                assert_eq!(r.code, Some(0), "{}", r.text);
                read += 1;
            } else {
                assert_eq!(r.code, Some(1), "{}", r.text);
                assert!(
                    !r.text.contains("triangles"),
                    "the sphere was read: {}",
                    r.text
                );
                assert!(r.text.contains("x.step"), "not located: {}", r.text);
                refused += 1;
            }
        }
        (read, refused)
    }));
    eprintln!("{read} STEP reads inside, {refused} refused");
    assert!(read > 0, "the inside file was never read");
    let _ = std::fs::remove_dir_all(p.join(STEP_STORE));
    assert_eq!(common::snapshot(p), before, "a user file changed");
}

/// `fitup import FILE --out DIR` into an existing project wrote its meshes by name:
/// with `DIR/meshes` a link to a folder outside, the STL landed outside (and the
/// document then failed to load). Every output now goes through the project's held
/// root: the link is refused (exit 1 naming the mesh), and while `meshes` is swapped
/// for that link over and over, repeated imports (`--force`) never open anything
/// outside; each ends in the imported document or a located refusal.
#[cfg(feature = "step")]
#[test]
fn imports_never_write_through_a_swapped_folder() {
    imports_race();
}

/// The body of [`imports_never_write_through_a_swapped_folder`], compiled in every
/// build, run with the `step` feature.
#[cfg_attr(not(feature = "step"), allow(dead_code))]
fn imports_race() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(p.join("models")).unwrap();
    std::fs::write(p.join("models/notes.txt"), "mine").unwrap();
    fitup::mesh::step::write_test_step("box", &p.join("box.step")).unwrap();
    let outside = tempfile::tempdir().unwrap();
    let o = outside.path();
    let args = ["import", "box.step", "--out", "models", "--force"];
    std::os::unix::fs::symlink(o, p.join("models/meshes")).unwrap();
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(1), "{}", r.text);
    assert!(r.text.contains("meshes"), "{}", r.text);
    assert_eq!(std::fs::read_dir(o).unwrap().count(), 0, "written outside");
    std::fs::remove_file(p.join("models/meshes")).unwrap();
    let r = crate::hostile_bounds::run(p, &args);
    assert_eq!(r.code, Some(0), "{}", r.text);
    let (done, refused) = summed(while_swapped(&p.join("models/meshes"), o, || {
        let (mut done, mut refused) = (0, 0);
        for _ in 0..30 {
            let r = crate::hostile_bounds::run(p, &args);
            assert!(!r.text.contains("panicked"), "{}", r.text);
            if r.code == Some(0) {
                done += 1;
            } else {
                assert_eq!(r.code, Some(1), "{}", r.text);
                assert!(r.text.contains("models"), "not located: {}", r.text);
                refused += 1;
            }
        }
        (done, refused)
    }));
    eprintln!("{done} imports, {refused} refused");
    assert!(done > 0, "no import went through");
    assert_eq!(
        std::fs::read_to_string(p.join("models/notes.txt")).unwrap(),
        "mine"
    );
}
