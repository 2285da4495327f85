//! Skills from a task built by hand (a gear onto an axis along −Z): the Move
//! generator's path, interference checks, templates, and the whole chain to the
//! simulated manipulator (in process, over loopback).

use crate::common::no_check;
use fitup::collision::SweepMethod;
use fitup::document::Document;
use fitup::kinematics::MotionOptions;
use fitup::manipulator::simulator::{Simulator, SimulatorOptions};
use fitup::math::{Aabb, Point3, Transform, Vec3};
use fitup::planning::PlannedPath;
use fitup::sequence::{Grasp, Operation, Task};
use fitup::skills::{
    generate, Action, GeneratorOptions, ManagerEvent, ManagerOptions, PartState, Plan, SegmentHit,
    SkillManager, Template,
};
use std::path::Path;

fn path() -> PlannedPath {
    let resolution = SweepMethod::Stepwise {
        step_mm: 1.0,
        step_rad: 0.01,
    };
    PlannedPath::given("by hand", vec![], resolution)
}

/// A gear inserted onto an axis along −Z, 30 mm safe length, at `assembled`; the
/// axis and base (the obstacle box) reach 40 mm above the gear's seat.
fn gear_task(assembled: Transform) -> Task {
    let seat = assembled.translation();
    Task {
        index: 0,
        base: "axis".into(),
        part: "gear".into(),
        operation: Operation::Insertion,
        mating_direction: Vec3::new(0.0, 0.0, -1.0),
        safe_length: 30.0,
        grasp: Some(Grasp {
            faces: ["rim_a".into(), "rim_b".into()],
            normal: Vec3::new(1.0, 0.0, 0.0),
            width: 12.0,
            point: Vec3::zeros(),
            depth: 3.0,
            tool_in_part: Transform::IDENTITY,
        }),
        obstacle_box: Aabb::new(
            Point3::new(seat.x - 20.0, seat.y - 20.0, seat.z - 60.0),
            Point3::new(seat.x + 20.0, seat.y + 20.0, seat.z + 40.0),
        ),
        assembled_pose: assembled,
        base_pose: Transform::IDENTITY,
        sequence_frame: Transform::IDENTITY,
        mount: false,
        path: path(),
        fits: Vec::new(),
        slides: Vec::new(),
    }
}

#[test]
fn the_move_generator_goes_around_the_obstacle_box() {
    let assembled = Transform::from_translation(Vec3::new(0.0, 0.0, 0.0));
    let task = gear_task(assembled);
    // The gear waits 200 mm to the side, turned 30° about Z.
    let start = Transform::from_rotation_about(Point3::origin(), Vec3::z(), 30f64.to_radians())
        .unwrap()
        .then(&Transform::from_translation(Vec3::new(200.0, 0.0, -10.0)));
    let mut checked = Vec::new();
    let mut check = |_: &Task, a: &Transform, b: &Transform| {
        checked.push((*a, *b));
        Ok(())
    };
    let skills = generate(
        std::slice::from_ref(&task),
        &[],
        &|_| Some(start),
        &GeneratorOptions::default(),
        &mut check,
    )
    .unwrap();
    let actions: Vec<Action> = skills.iter().map(|s| s.action).collect();
    assert_eq!(
        actions,
        [
            Action::Touch,
            Action::Grasp,
            Action::RotateTable,
            // Vertical: the probes (the table has no Z axis), however long.
            Action::MoveProbe,
            Action::MoveTable,
            Action::MoveProbe,
            Action::Insert,
            Action::Release
        ],
        "{skills:#?}"
    );
    // Orientation first: the turn is in place.
    let rot = &skills[2];
    assert!((rot.attribute("angle_rad").unwrap() - 30f64.to_radians()).abs() < 1e-9);
    assert_eq!(rot.start.0.translation(), rot.end.0.translation());
    // P1 and P2 are 20 mm (clearance) above the box top (z = 40): level 60.
    let p1 = skills[3].end.0.translation();
    let p2 = skills[4].end.0.translation();
    let p3 = skills[5].end.0.translation();
    assert!((p1 - Vec3::new(200.0, 0.0, 60.0)).norm() < 1e-9, "{p1}");
    assert!((p2 - Vec3::new(0.0, 0.0, 60.0)).norm() < 1e-9, "{p2}");
    // P3: the safe length back from the seat along the mating direction.
    assert!((p3 - Vec3::new(0.0, 0.0, 30.0)).norm() < 1e-9, "{p3}");
    assert_eq!(skills[5].end.1, PartState::Adjusted);
    assert_eq!(skills[6].end.1, PartState::Assembled);
    assert_eq!(skills[6].attribute("length_mm"), Some(30.0));
    // Every motion segment went through the interference check, the 30° turn in
    // three arcs of 10°.
    assert_eq!(checked.len(), 7);
    // Horizontal segments longer than 50 mm go to the table: 70 mm up (probes), 200
    // across (table), 30 down (probes).
    assert_eq!(skills[3].attribute("length_mm"), Some(70.0));
    assert_eq!(skills[4].attribute("length_mm"), Some(200.0));
    // Ids in execution order.
    assert!(skills.iter().enumerate().all(|(i, s)| s.id == i));
}

#[test]
fn a_segment_that_interferes_stops_generation_with_the_reason() {
    let task = gear_task(Transform::IDENTITY);
    let start = Transform::from_translation(Vec3::new(200.0, 0.0, 0.0));
    let mut check = |_: &Task, a: &Transform, b: &Transform| {
        // A wall at x = 100 between 0 and 100 mm high.
        let (xa, xb) = (a.translation().x, b.translation().x);
        let z = a.translation().z.max(b.translation().z);
        if xa.min(xb) < 100.0 && xa.max(xb) > 100.0 && z < 100.0 {
            Err(SegmentHit::Component {
                with: "wall".into(),
                fraction: 0.5,
            })
        } else {
            Ok(())
        }
    };
    let e = generate(
        &[task],
        &[],
        &|_| Some(start),
        &GeneratorOptions::default(),
        &mut check,
    )
    .unwrap_err();
    let text = e.to_string();
    assert!(text.contains("P1->P2") && text.contains("wall"), "{text}");
}

#[test]
fn a_fixture_template_skips_locate_and_a_missing_grasp_is_an_error() {
    let t = Template::parse(
        Path::new("fixture.yaml"),
        "operation: insertion\nworkflows:\n  - {from: In_WS, to: Grasped, generator: grasp}\n  - {from: Grasped, to: Adjusted, generator: move}\n  - {from: Adjusted, to: Assembled, generator: insert}\n",
    )
    .unwrap();
    let mut task = gear_task(Transform::IDENTITY);
    let skills = generate(
        std::slice::from_ref(&task),
        std::slice::from_ref(&t),
        &|_| None,
        &GeneratorOptions::default(),
        &mut no_check,
    )
    .unwrap();
    assert_eq!(skills[0].action, Action::Grasp);
    assert!(skills.iter().all(|s| s.action != Action::Touch));
    task.grasp = None;
    let e = generate(
        &[task],
        &[t],
        &|_| None,
        &GeneratorOptions::default(),
        &mut no_check,
    )
    .unwrap_err();
    assert!(e.to_string().contains("no grasp"), "{e}");
}

#[test]
fn bundled_template_files_parse() {
    for op in ["insertion", "screw", "align"] {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("models/templates/{op}.yaml"));
        let t = Template::read(&p).unwrap();
        assert_eq!(t.operation.name(), op);
    }
}

/// The gear task on the bundled MZ07 cell: the gear seats 80 mm in front of the TCP
/// at `home` and 100 mm lower; it waits 120 mm to the side, turned `turn_deg` about the
/// vertical. Its skills, bound to the robot (and through the plan's file format), and a
/// simulator at the plan's start joints.
struct GearCell {
    robot: fitup::kinematics::Robot,
    assembled: Transform,
    skills: Vec<fitup::skills::Skill>,
    plan: Plan,
    sim: Simulator,
}

fn gear_cell(turn_deg: f64, speed: f64) -> GearCell {
    let mut doc = Document::open(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/mz07.yaml"
    )))
    .unwrap();
    let robot = doc.robot("mz07").unwrap().robot().clone();
    let home = vec![0.0, 0.3, -0.2, 0.0, -0.4, 0.0];
    let tcp = robot.tcp_pose(&home).unwrap();
    let assembled = tcp.then(&Transform::from_translation(Vec3::new(80.0, 0.0, -100.0)));
    let task = gear_task(assembled);
    let start = tcp
        .then(&Transform::from_translation(-tcp.translation()))
        .then(
            &Transform::from_rotation_about(Point3::origin(), Vec3::z(), turn_deg.to_radians())
                .unwrap(),
        )
        .then(&Transform::from_translation(
            tcp.translation() + Vec3::new(0.0, 120.0, -100.0),
        ));
    let skills = generate(
        std::slice::from_ref(&task),
        &[],
        &|_| Some(start),
        &GeneratorOptions::default(),
        &mut no_check,
    )
    .unwrap();
    let plan = Plan::bind(
        &skills,
        std::slice::from_ref(&task),
        &robot,
        &home,
        &MotionOptions::default(),
    )
    .unwrap();
    // The plan survives its file format.
    let plan = Plan::from_json("plan.json", &plan.to_json()).unwrap();
    doc.set_robot_joints(0, &home).unwrap();
    let sim = Simulator::start(
        &doc,
        "mz07",
        &SimulatorOptions {
            motion_port: 0,
            state_port: 0,
            speed,
            ..SimulatorOptions::default()
        },
    )
    .unwrap();
    GearCell {
        robot,
        assembled,
        skills,
        plan,
        sim,
    }
}

#[test]
fn the_whole_chain_runs_on_the_simulated_mz07_until_assembled() {
    let GearCell {
        robot,
        assembled,
        skills,
        plan,
        sim,
    } = gear_cell(20.0, 50.0);
    let mut manager = SkillManager::new(plan, options_for(&sim));
    let mut events = Vec::new();
    manager.run(&mut |e| events.push(e.clone())).unwrap();
    let states: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            ManagerEvent::Finished { state, .. } => Some(state.name()),
            _ => None,
        })
        .collect();
    assert_eq!(states.len(), skills.len());
    assert_eq!(*states.last().unwrap(), "Assembled");
    assert!(states.contains(&"Grasped") && states.contains(&"Adjusted"));
    assert_eq!(events.last(), Some(&ManagerEvent::Done));
    // The arm holds the gear at its seat: FK of the controller's joints.
    let q = sim.joints();
    let at = robot.tcp_pose(&q).unwrap();
    assert!(
        (at.translation() - assembled.translation()).norm() < 0.5,
        "TCP at {} instead of {}",
        at.translation(),
        assembled.translation()
    );
    // Grasp opened to the grasp width, released wider at the end (metres on the wire).
    assert!((sim.gripper() - 0.018).abs() < 1e-6, "{}", sim.gripper());
}

/// The gear cell's plan (no turn) and its simulator, with the number of skills.
fn chain(speed: f64) -> (Plan, Simulator, usize) {
    let c = gear_cell(0.0, speed);
    (c.plan, c.sim, c.skills.len())
}

fn options_for(sim: &Simulator) -> ManagerOptions {
    ManagerOptions {
        target: sim.motion_addr().to_string(),
        state_port: Some(sim.state_addr().port()),
        ..ManagerOptions::default()
    }
}

#[test]
fn a_pending_skill_can_be_edited_and_a_finished_one_cannot() {
    let (plan, sim, n) = chain(50.0);
    // Edit the last skill (a Release): open wider.
    let mut last = plan.steps[n - 1].clone();
    last.commands = vec![fitup::skills::ControllerCommand::Tool {
        action: "release".into(),
        index: 0,
        value: 0.05,
    }];
    let mut manager = SkillManager::new(plan, options_for(&sim));
    let handle = manager.handle();
    handle.edit(n - 1, last);
    let mut events = Vec::new();
    let h2 = handle.clone();
    let mut edited_finished = false;
    manager
        .run(&mut |e| {
            if let ManagerEvent::Finished { skill: 0, .. } = e {
                if !edited_finished {
                    // Skill 0 is done: an edit of it is refused at the next dispatch.
                    h2.edit(
                        0,
                        fitup::skills::PlanStep {
                            skill: 0,
                            task: 0,
                            part: "gear".into(),
                            action: "Touch".into(),
                            description: "changed".into(),
                            end_state: PartState::InWs,
                            commands: vec![],
                        },
                    );
                    edited_finished = true;
                }
            }
            events.push(e.clone());
        })
        .unwrap();
    assert!(events.contains(&ManagerEvent::Edited(n - 1)), "{events:?}");
    assert!(
        events
            .iter()
            .any(|e| matches!(e, ManagerEvent::EditRefused(0, _))),
        "{events:?}"
    );
    assert!((sim.gripper() - 0.05).abs() < 1e-6, "{}", sim.gripper());
    assert_eq!(manager.status().len(), n);
    assert!(manager
        .status()
        .iter()
        .all(|s| *s == fitup::skills::SkillStatus::Finished));
}

#[test]
fn a_skill_that_times_out_stops_the_run_with_the_reason() {
    // Real time: the first arm motion takes seconds; allow 50 ms.
    let (plan, sim, _) = chain(1.0);
    let mut options = options_for(&sim);
    options.skill_timeout = std::time::Duration::from_millis(50);
    let mut manager = SkillManager::new(plan, options);
    let mut events = Vec::new();
    let e = manager.run(&mut |e| events.push(e.clone())).unwrap_err();
    assert!(e.to_string().contains("timeout"), "{e}");
    let failed = events
        .iter()
        .find_map(|e| match e {
            ManagerEvent::Failed(i, why) => Some((*i, why.clone())),
            _ => None,
        })
        .unwrap();
    assert!(failed.1.contains("did not reach"), "{failed:?}");
    assert!(matches!(
        manager.status()[failed.0],
        fitup::skills::SkillStatus::Failed(_)
    ));
    // Nothing after the failed skill ran.
    assert!(manager.status()[failed.0 + 1..]
        .iter()
        .all(|s| *s == fitup::skills::SkillStatus::Pending));
}

#[test]
fn fitup_skills_template_reports_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("t.yaml");
    std::fs::write(
        &f,
        "operation: insertion\nworkflows:\n  - {from: FREE, to: In_WS, generator: locate}\n  - {from: In_WS, to: Grasped, generator: grab}\n",
    )
    .unwrap();
    let fitup = || std::process::Command::new(env!("CARGO_BIN_EXE_fitup"));
    let o = fitup()
        .args(["skills", "template", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("t.yaml:4:"), "{err}");
    assert!(err.contains("did you mean `grasp`"), "{err}");
    // As the docs show it, from the repository root.
    let o = fitup()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["skills", "template", "models/templates/insertion.yaml"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("Grasped -> Adjusted: move"), "{out}");
}

/// The one run loop (`SkillManager::run_logged`, what the CLI and scripts use): a
/// sink that says stop aborts the run at once, and a skill log that cannot be
/// written stops it and fails it with the log's error, said to the sink once.
#[test]
fn the_one_run_loop_stops_on_its_sink_and_on_a_failed_log() {
    use fitup::skills::{LogDb, ManagerError, RunSink, SkillLog, SkillStatus};
    struct StopAfterFirst(Vec<ManagerEvent>, usize);
    impl RunSink for StopAfterFirst {
        fn event(&mut self, e: &ManagerEvent) -> bool {
            self.0.push(e.clone());
            !matches!(e, ManagerEvent::Finished { .. })
        }
        fn log_failed(&mut self, _: &fitup::db::DbError) {
            self.1 += 1;
        }
    }
    let (plan, sim, n) = chain(50.0);
    assert!(n > 2);
    let mut manager = SkillManager::new(plan.clone(), options_for(&sim));
    let mut sink = StopAfterFirst(Vec::new(), 0);
    let r = manager.run_logged(None, &mut sink);
    assert!(matches!(r, Err(ManagerError::Aborted)), "{r:?}");
    let finished = |events: &[ManagerEvent]| {
        events
            .iter()
            .filter(|e| matches!(e, ManagerEvent::Finished { .. }))
            .count()
    };
    assert_eq!(finished(&sink.0), 1, "{:?}", sink.0);
    assert_eq!(manager.status()[0], SkillStatus::Finished);
    assert_eq!(manager.status()[1], SkillStatus::Pending);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fitup.db");
    let db = fitup::db::Database::open(&fitup::db::Target::Sqlite(path.clone())).unwrap();
    rusqlite::Connection::open(&path)
        .unwrap()
        .execute_batch("DROP TABLE skill_log")
        .unwrap();
    let log = SkillLog::new(None, "plan", &plan, LogDb::Owned(Box::new(db)));
    let mut manager = SkillManager::new(plan, options_for(&sim));
    let mut sink = StopAfterFirst(Vec::new(), 0);
    match manager.run_logged(Some(log), &mut sink) {
        Err(ManagerError::Log(e)) => assert!(e.to_string().contains("skill_log"), "{e}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(sink.1, 1, "the failed write is said once");
    assert_eq!(finished(&sink.0), 0, "{:?}", sink.0);
    assert_eq!(manager.status()[0], SkillStatus::Pending);
}
