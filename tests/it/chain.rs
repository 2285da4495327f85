//! The whole chain from one script (issue 16): sequence → tasks → workflows →
//! skills → dispatched to the simulated manipulator → every part Assembled, the
//! execution log in the database. The commands are those of docs/skills.md and the
//! README, run from the repository root against the real binaries over loopback.

use crate::common;

use fitup::db::{Database, SkillEvent, SkillLogEntry, Target};
use fitup::skills::Plan;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

const BOUND: Duration = Duration::from_secs(300);

/// The skill log of the database's last recorded run.
fn last_run_log(db: &Path) -> Vec<SkillLogEntry> {
    let mut db = Database::open(&Target::Sqlite(db.to_path_buf())).unwrap();
    let log = db.skill_log(None).unwrap();
    let last = log.iter().filter_map(|e| e.run_id).max();
    assert!(last.is_some(), "no run recorded the skill log: {log:?}");
    log.into_iter().filter(|e| e.run_id == last).collect()
}

/// Every skill of the plan started and finished exactly once, in order, and every
/// part of the plan ended Assembled.
fn assert_assembled(plan_file: &Path, db: &Path) {
    let root = common::repo();
    let plan = Plan::from_json(
        "plan",
        &std::fs::read_to_string(root.join(plan_file)).unwrap(),
    )
    .unwrap();
    assert!(!plan.steps.is_empty());
    let log = last_run_log(&root.join(db));
    for event in ["started", "finished"] {
        let skills: Vec<i64> = log
            .iter()
            .filter(|e| e.event_name() == event)
            .map(|e| e.skill.unwrap())
            .collect();
        let expected: Vec<i64> = (0..plan.steps.len() as i64).collect();
        assert_eq!(skills, expected, "`{event}` events of {}", db.display());
    }
    let mut state = BTreeMap::new();
    for e in log.iter().filter(|e| e.event == Ok(SkillEvent::Finished)) {
        let (part, s) = e.detail.split_once(' ').unwrap();
        assert_eq!(Some(part), e.part.as_deref());
        state.insert(part.to_string(), s.to_string());
    }
    for s in &plan.steps {
        assert_eq!(state[&s.part], "Assembled", "{}: {state:?}", s.part);
    }
    assert_eq!(log.last().unwrap().event, Ok(SkillEvent::Done));
}

fn run(args: &[&str]) -> std::process::Output {
    let o = common::run_bounded(&common::repo(), args, BOUND);
    assert!(
        o.status.success(),
        "fitup {}: {}",
        args.join(" "),
        common::text(&o)
    );
    o
}

#[test]
fn the_wheel_and_the_cell_assemble_as_documented_in_process_and_over_tcp() {
    // Each example as documented: the in-process simulator, then a separate
    // `fitup manipulator` on the default ports with `--dispatch`.
    for (name, cell, last) in [
        ("wheel", "models/mz07.yaml", "finished #13: cup Assembled"),
        ("cell", "models/cell_arm.yaml", "Assembled"),
    ] {
        let script = format!("scripts/assemble_{name}.rhai");
        let db = format!("out/{name}.db");
        let plan = format!("out/assemble_{name}.plan.json");
        let o = run(&["run", &script, "--db", &db]);
        assert!(common::text(&o).contains(last), "{}", common::text(&o));
        assert_assembled(Path::new(&plan), Path::new(&db));
        // The documented default ports (11000, 11002) when they are free; another
        // run's manipulator holding them moves this one to a free pair.
        let sim = common::manipulator(&["--doc", cell, "--robot", "mz07", "--speed", "20"]);
        let target = format!("target={}", sim.target());
        run(&["run", &script, "--dispatch", "--db", &db, "--", &target]);
        assert_assembled(Path::new(&plan), Path::new(&db));
    }
}

#[test]
fn a_script_dispatches_over_tcp_only_when_the_command_line_says_so() {
    let root = common::repo();
    // No manipulator listens on this port: the refusal comes before any connection.
    // `fitup run scripts/assemble_wheel.rhai ARGS` fails with status 1; its stderr.
    let refused = |args: &[&str]| {
        let mut all = vec!["run", "scripts/assemble_wheel.rhai"];
        all.extend_from_slice(args);
        let o = common::run_bounded(&root, &all, BOUND);
        assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = refused(&["--", "target=127.0.0.1:1"]);
    assert!(
        err.contains("--dispatch") && err.contains("assemble_wheel.rhai:"),
        "{err}"
    );
    let err = refused(&["--dispatch", "--", "target=192.0.2.7:11000"]);
    assert!(err.contains("--allow-remote"), "{err}");
    // `--allow-remote` alone is a usage error.
    let o = common::run_in(
        &root,
        &["run", "scripts/assemble_wheel.rhai", "--allow-remote"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));
}

/// The start of the chain scripts: the wheel's sequence and its skills for the MZ07
/// at its home pose, the wheel placed 500 mm in front of it.
const WHEEL_SKILLS: &str = r#"
let wheel = open_doc("models/wheel.yaml");
let seq = wheel.assembly_sequence(#{seed: 1});
let cell = open_doc("models/mz07.yaml");
let robot = cell.robot("mz07");
robot.joints = robot.ik_near([500, 0, 250, 0, 0, 0], [0, 0, 0, 0, -90, 0]);
let skills = wheel.skills(seq, #{robot: robot, place: [500, 0, 150, 0, 0, 0], tool: [0, 0, 0, 180, 0, 0]});
"#;

#[test]
fn a_script_pauses_resumes_commands_by_hand_and_aborts_from_its_event_callback() {
    let root = common::repo();
    std::fs::create_dir_all(root.join("out")).unwrap();
    let script = root.join("out/test_chain_callback.rhai");
    std::fs::write(
        &script,
        [
            WHEEL_SKILLS,
            r#"let m = skill_manager(#{target: "sim", robot: robot, speed: 20, quiet: true});
// Skill 2 (a move of the gear) is paused as soon as it starts; on `paused` a manual
// command is queued and the run resumed; the last skill is edited before it runs.
m.edit(skills, skills.len - 1, #{commands: ["release 20"]});
let events = m.run(skills, |e, manager| {
    if e.event == "started" && e.skill == 2 { manager.pause(); }
    if e.event == "paused" { manager.manual("output 3 1"); manager.resume(); }
});
let names = events.map(|e| e.event);
print(names);
assert(names.contains("paused") && names.contains("resumed") && names.contains("manual"), `${names}`);
assert(names.contains("edited"), `${names}`);
assert(names[names.len() - 1] == "done");
assert(m.parts.cup == "Assembled" && m.parts.gear == "Assembled", `${m.parts}`);
// Abort from the callback: the run returns, later skills never start.
let m2 = skill_manager(#{target: "sim", robot: robot, speed: 20, quiet: true});
let events = m2.run(skills, |e, manager| { if e.event == "finished" && e.skill == 1 { manager.abort(); } });
let names = events.map(|e| e.event);
assert(names[names.len() - 1] == "aborted", `${names}`);
assert(events.filter(|e| e.event == "started").len() <= 3, `${names}`);
print("callback ok");
"#,
        ]
        .concat(),
    )
    .unwrap();
    let o = run(&["run", "out/test_chain_callback.rhai"]);
    assert!(
        common::text(&o).contains("callback ok"),
        "{}",
        common::text(&o)
    );
}

#[test]
fn a_new_save_aborts_a_running_manager_in_watch_mode() {
    let root = common::repo();
    std::fs::create_dir_all(root.join("out")).unwrap();
    let script = root.join("out/test_chain_watch.rhai");
    let text = [
        WHEEL_SKILLS,
        r#"// Real time and slow: the run lasts far longer than the test waits.
let m = skill_manager(#{target: "sim", robot: robot, speed: 0.05});
m.run(skills);
"#,
    ]
    .concat();
    std::fs::write(&script, &text).unwrap();
    let mut w = common::Watch::start(&root, "out/test_chain_watch.rhai", &[]);
    let bound = Duration::from_secs(120);
    // The arm is moving (skill #1 is the grasp's joint move), then a save.
    w.out.wait_for("running #1", bound);
    std::thread::sleep(Duration::from_millis(300));
    std::fs::write(&script, format!("{text}\n// saved again\n")).unwrap();
    w.out.wait_for("aborted", bound);
    // The new run starts from the beginning.
    w.out.wait_for("running #0", bound);
    let seen = &w.out.seen;
    let aborted = seen.iter().position(|l| l.contains("aborted")).unwrap();
    assert!(
        !seen[..aborted].iter().any(|l| l.contains("finished #1")),
        "the moving skill was not cut off: {seen:#?}"
    );
}

fn tmux(socket: &str, args: &[&str]) -> String {
    let o = std::process::Command::new("tmux")
        .arg("-L")
        .arg(socket)
        .args(args)
        .output()
        .expect("tmux (Debian package `tmux`) runs the terminal UI test");
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn the_terminal_ui_shows_the_run_and_takes_keys_under_tmux() {
    let root = common::repo();
    // The plan the wheel script saves (deterministic: the same file every run).
    run(&["run", "scripts/assemble_wheel.rhai"]);
    let sim = common::manipulator(&[
        "--doc",
        "models/mz07.yaml",
        "--robot",
        "mz07",
        "--speed",
        "3",
        "--port",
        "11300",
        "--state-port",
        "11302",
    ]);
    let socket = format!("fitup-chain-test-{}", std::process::id());
    let command = format!(
        "{} skills run out/assemble_wheel.plan.json --target {}; echo EXIT=$?; sleep 60",
        env!("CARGO_BIN_EXE_fitup"),
        sim.target()
    );
    tmux(
        &socket,
        &[
            "new-session",
            "-d",
            "-x",
            "150",
            "-y",
            "45",
            "-c",
            root.to_str().unwrap(),
            &command,
        ],
    );
    struct Server(String);
    impl Drop for Server {
        fn drop(&mut self) {
            tmux(&self.0, &["kill-server"]);
        }
    }
    let _server = Server(socket.clone());
    let screen = || tmux(&socket, &["capture-pane", "-p"]);
    // Waits for one screen that `fits` (a frame can be captured half drawn, so what one
    // frame must show is awaited together). The deadline is generous: a loaded machine
    // slows the captures, never what a screen must show.
    let wait_until = |what: &str, fits: &dyn Fn(&str) -> bool| -> String {
        let start = Instant::now();
        loop {
            let s = screen();
            if fits(&s) {
                return s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(120),
                "no screen with {what}:\n{s}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    let wait_for = |what: &[&str]| {
        wait_until(&format!("all of {what:?}"), &|s| {
            what.iter().all(|w| s.contains(w))
        })
    };
    let plan = Plan::from_json(
        "plan",
        &std::fs::read_to_string(root.join("out/assemble_wheel.plan.json")).unwrap(),
    )
    .unwrap();
    let steps = plan.steps.len();
    // The skill a screen shows running, and that the lists agree with it: the skills
    // before it finished, those after it pending (the first four listed), the parts of
    // the finished ones in a state, and the six live joints. Which skill that is
    // depends on when the screen is captured (a loaded machine may miss the first).
    let running_with_lists = |s: &str| -> Option<usize> {
        let lines: Vec<&str> = s.lines().map(str::trim_end).collect();
        let has = |l: String| lines.contains(&l.as_str());
        let n = plan
            .steps
            .iter()
            .position(|step| has(format!("running:  {}", step.description)))?;
        let parts = lines.iter().find(|l| l.starts_with("parts:"))?;
        let joints = lines.iter().find(|l| l.starts_with("joints:"))?;
        let pending = &plan.steps[n + 1..];
        let fits = has(format!("finished ({n}/{steps}):"))
            && has(format!("pending ({}):", pending.len()))
            && pending
                .iter()
                .take(4)
                .all(|p| has(format!("    {}", p.description)))
            && plan.steps[..n]
                .iter()
                .all(|f| !parts.contains(&format!("{} -", f.part)))
            && joints.matches('°').count() == 6;
        fits.then_some(n)
    };
    // The lists and the live joints while the arm moves; paused at once, then the
    // paused skill is the running one of a paused screen.
    let s = wait_until("a skill running and the lists agreeing", &|s| {
        s.contains("state: running") && running_with_lists(s).is_some()
    });
    let first = running_with_lists(&s).unwrap();
    tmux(&socket, &["send-keys", "p"]);
    let s = wait_until("the run paused at a skill", &|s| {
        s.contains("state: paused") && running_with_lists(s).is_some()
    });
    let paused = running_with_lists(&s).unwrap();
    assert!(
        paused >= first,
        "paused at #{paused} after #{first} ran:\n{s}"
    );
    // A manual command while paused, then resume.
    tmux(&socket, &["send-keys", "m"]);
    wait_for(&["manual command ("]);
    tmux(&socket, &["send-keys", "output 3 1", "Enter"]);
    wait_for(&["manual output 3 1"]);
    tmux(&socket, &["send-keys", "r"]);
    wait_for(&["resumed"]);
    wait_for(&[
        "state: done",
        &format!("finished ({steps}/{steps})"),
        "cup Assembled",
    ]);
    tmux(&socket, &["send-keys", "q"]);
    let s = wait_for(&["EXIT="]);
    assert!(s.contains("EXIT=0"), "{s}");
}
