//! Helpers shared by the integration tests: a scratch project with the demo cell,
//! and the `fitup` binary.

#![allow(dead_code)]

pub mod bounded;
pub mod duct;
pub mod fit_check;
pub mod kin_driver;
pub mod lines;
#[cfg(feature = "step")]
pub mod occt_check;
pub mod ur_kin;
pub mod ur_urdf;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The indices of the components an assembly order names, in its order.
pub fn component_indices(doc: &fitup::document::Document, order: &[String]) -> Vec<usize> {
    order
        .iter()
        .map(|n| doc.component_index(n).unwrap())
        .collect()
}

/// Whether component `p` of `scene` at `pose` (whose world box is `bp`) interferes
/// with component `q` at its pose by more than `tol`: the world boxes first (boxes
/// that overlap by at most `tol` cannot), then the meshes.
pub fn interferes_in(
    scene: &fitup::workspace::Scene,
    p: usize,
    pose: &fitup::math::Transform,
    bp: &fitup::math::Aabb,
    q: usize,
    tol: f64,
) -> bool {
    let bq = scene.colliders[q].world_bounds(&scene.poses[q]);
    bp.overlap(&bq).min() > tol
        && fitup::collision::interferes(
            &scene.colliders[p],
            pose,
            &scene.colliders[q],
            &scene.poses[q],
            tol,
        )
        .unwrap()
}

/// How many distinct indices `idx` holds.
pub fn distinct(idx: &[usize]) -> usize {
    let mut seen = idx.to_vec();
    seen.sort();
    seen.dedup();
    seen.len()
}

/// The built `fitup` binary.
pub fn fitup() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fitup"))
}

/// A temporary project folder (`fitup demo`): `fitup.toml`, `models/cell.yaml` and its
/// meshes.
pub fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fitup::demo::write_project(dir.path()).unwrap();
    std::fs::create_dir(dir.path().join("scripts")).unwrap();
    dir
}

/// Runs `fitup ARGS` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    fitup().current_dir(dir).args(args).output().unwrap()
}

/// [`run_in`] that must succeed: the combined output text.
pub fn run_ok(dir: &Path, args: &[&str]) -> String {
    let o = run_in(dir, args);
    let t = text(&o);
    assert!(o.status.success(), "{args:?}: {t}");
    t
}

/// Writes `source` as `scripts/NAME` of the project `dir` and runs it there (`fitup
/// run scripts/NAME`).
pub fn run_script_in(dir: &Path, name: &str, source: &str) -> Output {
    let rel = format!("scripts/{name}");
    std::fs::write(dir.join(&rel), source).unwrap();
    run_in(dir, &["run", &rel])
}

/// `fitup manipulator` on the MZ07 of `models/mz07.yaml` (run from the repository
/// root); the ports and the speed follow.
pub const MZ07_SIMULATOR: [&str; 5] = [
    "manipulator",
    "--doc",
    "models/mz07.yaml",
    "--robot",
    "mz07",
];

/// A segment check for `fitup::skills::generate` that finds nothing in the way.
pub fn no_check(
    _: &fitup::sequence::Task,
    _: &fitup::math::Transform,
    _: &fitup::math::Transform,
) -> Result<(), fitup::skills::SegmentHit> {
    Ok(())
}

/// Skill `i` of the test plans: `Move_Table` of the part `gear`, ending in `end_state`,
/// doing `commands`.
pub fn gear_step(
    i: usize,
    end_state: fitup::skills::PartState,
    commands: Vec<fitup::skills::ControllerCommand>,
) -> fitup::skills::PlanStep {
    fitup::skills::PlanStep {
        skill: i,
        task: 0,
        part: "gear".into(),
        action: "Move_Table".into(),
        description: format!("#{i} Move_Table gear"),
        end_state,
        commands,
    }
}

/// A [`gear_step`] that follows the joint trajectory `pts`, then sets digital output 1.
pub fn gear_move_step(
    i: usize,
    end_state: fitup::skills::PartState,
    pts: Vec<(Vec<f64>, f64)>,
) -> fitup::skills::PlanStep {
    use fitup::skills::ControllerCommand;
    gear_step(
        i,
        end_state,
        vec![
            ControllerCommand::Trajectory(pts),
            ControllerCommand::Tool {
                action: "set_output".into(),
                index: 1,
                value: 1.0,
            },
        ],
    )
}

/// A plan of the catalog MZ07 (six revolute joints) doing `steps`.
pub fn mz07_plan(steps: Vec<fitup::skills::PlanStep>) -> fitup::skills::Plan {
    fitup::skills::Plan {
        version: 1,
        robot: "mz07".into(),
        joint_kinds: vec!["revolute".into(); 6],
        steps,
    }
}

/// The committed `models/` files `files` are byte for byte what the generator `write`
/// (one of `fitup::demo`'s) writes into a fresh folder. With `FITUP_BLESS` set,
/// `write` first rewrites them in `models/`; `test` is the test filter that does so.
pub fn assert_models_generated<E: std::fmt::Debug>(
    write: impl Fn(&Path) -> Result<(), E>,
    files: &[&str],
    test: &str,
) {
    let models = repo().join("models");
    if std::env::var_os("FITUP_BLESS").is_some() {
        write(&models).unwrap();
    }
    let fresh = tempfile::tempdir().unwrap();
    write(fresh.path()).unwrap();
    for f in files {
        let committed = std::fs::read(models.join(f)).unwrap_or_else(|e| panic!("models/{f}: {e}"));
        let generated = std::fs::read(fresh.path().join(f)).unwrap();
        assert!(
            committed == generated,
            "models/{f} differs from the generator: run FITUP_BLESS=1 cargo test --test it {test}"
        );
    }
}

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `.rhai` scripts directly in the repository folder `folder`, sorted, each as its
/// path from the repository root (how the README runs them: `fitup run scripts/…`).
pub fn repo_scripts(folder: &str) -> Vec<String> {
    let root = repo();
    let mut scripts: Vec<String> = std::fs::read_dir(root.join(folder))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .map(|p| {
            p.strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    scripts.sort();
    scripts
}

/// Runs `fitup run SCRIPT` from the repository root for each of `scripts` (paths from
/// the root); the ones that failed, each with its output.
pub fn failing_repo_runs(scripts: &[String]) -> Vec<String> {
    let root = repo();
    scripts
        .iter()
        .filter_map(|rel| {
            let out = run_in(&root, &["run", rel]);
            (!out.status.success()).then(|| format!("{rel}:\n{}", text(&out)))
        })
        .collect()
}

/// Stdout and stderr as text.
/// The numbers of the last line of `text`, a CSV row a script printed (panics on
/// an empty text or a field that is not a number).
pub fn last_csv_numbers(text: &str) -> Vec<f64> {
    let last = text.trim().lines().last().expect("a printed line");
    last.split(',')
        .map(|v| {
            v.trim()
                .parse()
                .unwrap_or_else(|e| panic!("{v:?} in {last:?}: {e}"))
        })
        .collect()
}

pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// [`text`] cut to a readable length for failure messages.
pub fn short_text(o: &Output) -> String {
    let t = text(o);
    let n = t.chars().count();
    if n > 4000 {
        let head: String = t.chars().take(4000).collect();
        format!("{head}… ({n} characters)")
    } else {
        t
    }
}

/// Starts `fitup ARGS` in `dir` with no input and both outputs piped.
pub fn spawn(dir: &Path, args: &[&str]) -> Child {
    spawn_with(fitup(), dir, args)
}

/// [`spawn`] of another command line (`fitup` under a wrapper such as GNU time).
pub fn spawn_with(mut command: Command, dir: &Path, args: &[&str]) -> Child {
    command
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Reads `child`'s piped standard output and error to their ends on two threads, so a
/// chatty child never blocks on a full pipe: join the handles for the bytes (empty for
/// an output that was not piped).
pub fn drain_outputs(child: &mut Child) -> (JoinHandle<Vec<u8>>, JoinHandle<Vec<u8>>) {
    fn drain(r: Option<impl Read + Send + 'static>) -> JoinHandle<Vec<u8>> {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            buf
        })
    }
    (drain(child.stdout.take()), drain(child.stderr.take()))
}

/// A GLB container around `json` (padded with spaces to 4 bytes) and the binary chunk
/// `bin`, whose length is written as it is.
pub fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Waits for `child`, killing it and failing the test after `bound` — a bound on
/// hangs, not a speed assertion. Its output is read meanwhile, so a chatty child
/// never blocks on a full pipe.
pub fn finish(mut child: Child, what: &str, bound: Duration) -> Output {
    let (out, err) = drain_outputs(&mut child);
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > bound {
            let _ = child.kill();
            let o = Output {
                status: child.wait().unwrap(),
                stdout: out.join().unwrap(),
                stderr: err.join().unwrap(),
            };
            panic!(
                "`fitup {what}`: still running after {bound:?}; output:\n{}",
                text(&o)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    }
}

/// `fitup ARGS` in `dir`, killed (failing the test) after `bound`.
pub fn run_bounded(dir: &Path, args: &[&str], bound: Duration) -> Output {
    finish(spawn(dir, args), &args.join(" "), bound)
}

/// `fitup watch SCRIPT EXTRA…` in `dir`: the process (killed when dropped) and its
/// stdout line by line (stderr is discarded).
pub struct Watch {
    /// The `fitup watch` process.
    pub process: lines::Killed,
    /// The watch's stdout.
    pub out: lines::Lines,
}

impl Watch {
    /// Starts the watch with no input.
    pub fn start(dir: &Path, script: &str, extra: &[&str]) -> Watch {
        let mut child = fitup()
            .current_dir(dir)
            .arg("watch")
            .arg(script)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let out = lines::Lines::read(child.stdout.take().unwrap());
        Watch {
            process: lines::Killed(child),
            out,
        }
    }
}

/// Copies the micro-robot wheel (seed 003: `models/wheel.yaml` and its three meshes)
/// into the project `p`.
pub fn copy_wheel(p: &Path) {
    let root = repo();
    std::fs::create_dir_all(p.join("models/meshes")).unwrap();
    std::fs::copy(root.join("models/wheel.yaml"), p.join("models/wheel.yaml")).unwrap();
    for m in ["axis", "gear", "cup"] {
        let f = format!("models/meshes/wheel_{m}.stl");
        std::fs::copy(root.join(&f), p.join(&f)).unwrap();
    }
}

/// Every file of `before` is still in `now` with the same content (files written since
/// are not user files).
pub fn assert_kept(before: &Snapshot, now: &Snapshot) {
    for (path, hash) in before {
        assert_eq!(
            now.get(path),
            Some(hash),
            "{} changed or vanished",
            path.display()
        );
    }
}

/// The user's files as hashes: everything but the results database and its WAL
/// (queries read it; fitup writes it).
pub fn user_files(dir: &Path) -> Snapshot {
    let mut s = snapshot(dir);
    s.retain(|p, _| {
        !p.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with("fitup.db"))
    });
    s
}

/// Copies a folder tree (files and folders only).
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// The tessellations in `dir`'s STEP store (`*.tess`), sorted.
pub fn stored_tessellations(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir.join(fitup::mesh::step::STEP_STORE))
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    v.retain(|p: &PathBuf| p.extension().is_some_and(|e| e == "tess"));
    v.sort();
    v
}

/// sha256 of each regular file, by path: what the hostile tests compare before and
/// after a run to show that nothing the user owns changed.
pub type Snapshot = std::collections::BTreeMap<PathBuf, [u8; 32]>;

/// sha256 of every regular file under `dir` (links, FIFOs and other special files are
/// not read, so a planted FIFO cannot block the test).
pub fn snapshot(dir: &Path) -> Snapshot {
    use sha2::{Digest, Sha256};
    let mut out = Snapshot::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let md = std::fs::symlink_metadata(&p).unwrap();
            if md.is_dir() {
                stack.push(p);
            } else if md.is_file() {
                out.insert(p.clone(), Sha256::digest(std::fs::read(&p).unwrap()).into());
            }
        }
    }
    out
}

/// A free port P on 127.0.0.1 whose P + 2 is free too (the port rule: the state port
/// is the motion port + 2). Free when asked; whoever binds first gets it, so callers
/// start their process and check that it bound ([`manipulator`] retries).
pub fn free_pair() -> u16 {
    for _ in 0..100 {
        let a = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let p = a.local_addr().unwrap().port();
        if p < 65000 && std::net::TcpListener::bind(("127.0.0.1", p + 2)).is_ok() {
            return p;
        }
    }
    panic!("no free port pair");
}

/// The motion and state addresses of a simulator's `listening` line
/// (`… listening: motion 127.0.0.1:P, state 127.0.0.1:Q …`).
pub fn listening_addrs(line: &str) -> (std::net::SocketAddr, std::net::SocketAddr) {
    let addr = |key: &str| -> std::net::SocketAddr {
        let rest = &line[line.find(key).unwrap() + key.len()..];
        rest.split([',', ' '])
            .find(|w| !w.is_empty())
            .unwrap()
            .parse()
            .unwrap()
    };
    (addr("motion "), addr("state "))
}

/// A `fitup manipulator` started by [`manipulator`]: killed when dropped.
pub struct Manipulator {
    /// The process and its output.
    pub proc: lines::Proc,
    /// The motion port it listens on (127.0.0.1), from its own `listening` line.
    pub port: u16,
    /// The state port it listens on.
    pub state_port: u16,
}

impl Manipulator {
    /// `127.0.0.1:PORT`, the motion address a client is given.
    pub fn target(&self) -> String {
        format!("127.0.0.1:{}", self.port)
    }
}

/// `fitup manipulator ARGS` started from the repository root, returned once **this**
/// process has printed its `listening` line — it prints it after binding both ports,
/// so a client connecting then cannot be refused, and a port some other process holds
/// (another test run, another checkout's tests, a leftover manipulator) is never
/// taken for this one's (bounded: 60 s per start). The ports of `ARGS` (the
/// documented ones) are tried first; when this process cannot bind them it is
/// started again without `--port`/`--state-port` and with `--port P` on a free pair
/// ([`free_pair`], state port by the rule), up to 5 times. Callers address it by
/// [`Manipulator::port`].
pub fn manipulator(args: &[&str]) -> Manipulator {
    let bound = Duration::from_secs(60);
    let mut args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    for attempt in 0..5 {
        let mut proc = lines::Proc::spawn(
            fitup()
                .current_dir(repo())
                .arg("manipulator")
                .args(&args)
                .stdin(Stdio::null()),
        );
        let start = Instant::now();
        let line = loop {
            let got = proc.drain();
            if let Some(l) = proc
                .seen()
                .iter()
                .find(|l| l.contains(" listening: motion "))
            {
                break Some(l.clone());
            }
            if proc.child.0.try_wait().unwrap().is_some() {
                // Exited before listening: a port in use is retried elsewhere,
                // anything else is the failure. (Its last lines arrive until the
                // streams end.)
                proc.lines.quiet(Duration::from_secs(5));
                let got = proc.drain();
                assert!(
                    got.contains("cannot listen on"),
                    "fitup manipulator {} exited: {got}",
                    args.join(" ")
                );
                break None;
            }
            assert!(
                start.elapsed() < bound,
                "fitup manipulator {}: not listening after {bound:?}: {got}",
                args.join(" ")
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        if let Some(line) = line {
            let port = |key: &str| -> u16 {
                let rest = &line[line.find(key).unwrap() + key.len()..];
                let addr: std::net::SocketAddr = rest
                    .split([',', ' '])
                    .find(|w| !w.is_empty())
                    .unwrap()
                    .parse()
                    .unwrap();
                addr.port()
            };
            return Manipulator {
                port: port("motion "),
                state_port: port("state "),
                proc,
            };
        }
        eprintln!("fitup manipulator: ports in use (attempt {attempt}), moving to a free pair");
        let mut kept = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            if a == "--port" || a == "--state-port" {
                it.next();
            } else {
                kept.push(a.clone());
            }
        }
        kept.extend(["--port".to_string(), free_pair().to_string()]);
        args = kept;
    }
    panic!("fitup manipulator: no free ports after 5 starts");
}

/// The re-checks' way out after a removal path `way` (assembled → outside): straight
/// on along its last move (or `fallback` when that move is a pure turn) in `step` mm
/// steps until the part's box at the pose (`bounds_at`) is more than 0.5 mm clear of
/// `region`, the box of everything placed before (at most 100,000 steps).
pub fn straight_on_until_clear(
    way: &[fitup::math::Transform],
    fallback: fitup::math::Vec3,
    step: f64,
    region: &fitup::math::Aabb,
    bounds_at: impl Fn(&fitup::math::Transform) -> fitup::math::Aabb,
) -> Vec<fitup::math::Transform> {
    let m = way.len();
    let last = way[m - 1].translation() - way[m - 2].translation();
    let d = if last.norm() > 1e-9 {
        last.normalize()
    } else {
        fallback
    };
    let grown = fitup::math::Aabb::new(
        region.lo - fitup::math::Vec3::repeat(0.5),
        region.hi + fitup::math::Vec3::repeat(0.5),
    );
    let mut at = way[m - 1];
    let mut out = Vec::new();
    for _ in 0..100_000 {
        if bounds_at(&at).overlap(&grown).min() < 0.0 {
            break;
        }
        at = fitup::math::Transform::from_parts(at.translation() + d * step, at.rotation());
        out.push(at);
    }
    out
}
