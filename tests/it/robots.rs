//! Robots in documents, end to end: dimensions drive link components, IK through the
//! script API, programs through the CLI (and their located errors), save/load round
//! trips, and the loader's located validation errors.

use crate::common;

use fitup::document::{DimensionKind, Document};
use fitup::math::{Point3, Transform, Vec3};
use std::path::{Path, PathBuf};

/// A scratch project with the demo cell and the robot models under `models/`.
fn project() -> tempfile::TempDir {
    let dir = common::project();
    fitup::demo::write_robots(&dir.path().join("models")).unwrap();
    dir
}

fn mz07(dir: &Path) -> PathBuf {
    dir.join("models/mz07.yaml")
}

/// Runs `script` as `scripts/NAME` in a fresh robot project; it must succeed.
fn script_passes(name: &str, script: &str) {
    let dir = project();
    let out = common::run_script_in(dir.path(), name, script);
    assert!(out.status.success(), "{}", common::text(&out));
}

/// Setting a joint dimension moves every link component to `offset · link pose`, so
/// the mesh drawn at the zero configuration follows the kinematics: the tool point of
/// link 6's mesh is the robot's TCP, and the base does not move.
#[test]
fn dimensions_drive_link_components() {
    let dir = project();
    let mut doc = Document::open(&mz07(dir.path())).unwrap();
    let names = doc.dimensions();
    for i in 1..=6 {
        assert!(names.contains(&format!("D1@角度{i}")), "{names:?}");
    }
    let tip_drawn = Point3::new(390.0, 0.0, 198.1);
    let base_before = doc.component("mz07_base").unwrap().transform;
    let q_deg: [f64; 6] = [25.0, -30.0, 40.0, 60.0, -45.0, 90.0];
    for (i, v) in q_deg.iter().enumerate() {
        let name = format!("D1@角度{}", i + 1);
        assert_eq!(doc.dimension(&name).unwrap().kind, DimensionKind::Angle);
        doc.set_dimension(&name, v.to_radians()).unwrap();
        assert!((doc.dimension(&name).unwrap().document_value() - v).abs() < 1e-12);
    }
    let robot = doc.robot("mz07").unwrap();
    let q: Vec<f64> = q_deg.iter().map(|v| v.to_radians()).collect();
    assert_eq!(robot.joints(), q.as_slice());
    let tcp = robot.robot().tcp_pose(&q).unwrap();
    let link6 = doc.component("mz07_link6").unwrap().transform;
    assert!((link6.apply(&tip_drawn).coords - tcp.translation()).norm() < 1e-9);
    // Every link component equals offset · link pose.
    let poses = robot.robot().link_poses(&q).unwrap();
    for (l, p) in robot.links().iter().zip(&poses) {
        let c = &doc.components()[l.component.unwrap()];
        assert!(
            c.transform.approx_eq(&(l.offset * *p), 1e-9, 1e-12),
            "{}",
            c.name
        );
    }
    assert!(doc
        .component("mz07_base")
        .unwrap()
        .transform
        .approx_eq(&base_before, 1e-12, 1e-12));
    // A link component is moved through its robot, not directly.
    let err = doc
        .set_transform("mz07_link3", Transform::IDENTITY)
        .unwrap_err();
    assert!(err.to_string().contains("link of robot `mz07`"), "{err}");
    // Out of the limits: refused, nothing moves.
    let err = doc
        .set_dimension("D1@角度5", 150f64.to_radians())
        .unwrap_err();
    assert!(err.to_string().contains("joint 5"), "{err}");
    assert!(doc
        .component("mz07_link6")
        .unwrap()
        .transform
        .approx_eq(&link6, 1e-12, 1e-12));
}

/// The script API's IK returns branches that each reproduce the target, for targets
/// made by FK of configurations across the workspace; joints set through `joints` and
/// through dimensions agree.
#[test]
fn ik_round_trip_through_the_script_api() {
    let script = r#"
        let doc = open_doc("models/mz07.yaml");
        let arm = doc.robot("mz07");
        let configs = [[0, 0, 0, 0, 30, 0], [40, -60, 20, 90, -70, 10], [-120, 30, 100, -45, 60, -200],
                       [150, -100, -80, 170, 100, 300], [5, 60, 250, -150, -20, -90]];
        for q in configs {
            let target = arm.fk(q);
            let sols = arm.ik(target);
            let found = false;
            for s in sols {
                let d = arm.fk(s).distance_to(target);
                assert(d.mm < 1e-6 && d.deg < 1e-6, `${s} misses ${q}`);
                let same = true;
                for i in 0..6 { if (s[i] - q[i]).abs() > 1e-6 { same = false; } }
                if same { found = true; }
            }
            assert(found, `${q} is not among its branches`);
            // The same target as `[x, y, z, a, b, c]` (the general, untyped overload).
            let again = arm.ik(target.xyzabc);
            assert(again.len() == sols.len(), `${again.len()} branches from xyzabc, ${sols.len()} from the Transform`);
            for s in again { assert(arm.fk(s).distance_to(target).mm < 1e-6, `${s} from xyzabc misses ${q}`); }
            arm.joints = q;
            for i in 0..6 { assert_near(doc.dimension(arm.dimensions[i]).value, q[i], 1e-9); }
            assert(arm.tcp == target, "tcp");
        }
        print("ok");
    "#;
    script_passes("ik.rhai", script);
}

/// `ik_solutions`, the fast form of `ik`, gives `ik`'s solutions to the bit and in the
/// same order through every way a script reads it (index, negative index, `for`,
/// `to_array`, printing), each reproducing the target; the same errors. Both stores
/// are used: the MZ07's few branches inline, a UR5e with ±360° limits (hundreds of
/// solutions) on the heap; and a script-built robot (`RobotModel.ik_solutions`).
#[test]
fn ik_solutions_are_ik_read_lazily() {
    let script = r#"
        fn same(arm, target, sols, all) {
            assert(sols.len == all.len() && sols.len() == all.len(), `${sols.len} solutions, ik ${all.len()}`);
            assert(sols.to_array() == all, "to_array is ik");
            assert(`${sols}` == `${all}`, "printed as ik's array");
            for i in 0..all.len() {
                assert(sols[i] == all[i], `solution ${i}: ${sols[i]} != ${all[i]}`);
                assert(sols[i - all.len()] == all[i], `solution ${i - all.len()}`);
            }
            let k = 0;
            for q in sols {
                assert(q == all[k], `for: solution ${k}`);
                let d = arm.fk(q).distance_to(target);
                assert(d.mm < 1e-6 && d.deg < 1e-6, `${q} misses the target by ${d}`);
                k += 1;
            }
            assert(k == all.len(), "for visits every solution");
            let why = "";
            try { sols[all.len()]; } catch (e) { why = `${e}`; }
            assert(why.contains("out of range"), why);
        }
        let doc = open_doc("models/mz07.yaml");
        let arm = doc.robot("mz07");
        for q in [[40, -60, 20, 90, -70, 10], [-120, 30, 100, -45, 60, -200], [0, 0, 0, 0, 30, 0]] {
            arm.joints = q;
            let target = arm.tcp;
            same(arm, target, arm.ik_solutions(target), arm.ik(target));
            same(arm, target, arm.ik_solutions(target.xyzabc), arm.ik(target.xyzabc));
        }
        let far = ["", ""];
        try { arm.ik(pose(3000, 0, 500, 180, 0, 0)); } catch (e) { far[0] = `${e}`; }
        try { arm.ik_solutions(pose(3000, 0, 500, 180, 0, 0)); } catch (e) { far[1] = `${e}`; }
        assert(far[0].contains("unreachable") && far[0] == far[1], `${far}`);
        let ur = robot_dh([[0, 162.5, 0, 90], [0, 0, -425, 0], [0, 0, -392.2, 0], [0, 133.3, 0, 90], [0, 99.7, 0, -90], [0, 99.6, 0, 0]],
                          #{limits: [[-360, 360], [-360, 360], [-360, 360], [-360, 360], [-360, 360], [-360, 360]]});
        assert(ur.closed_form, "the UR5e is solved in closed form");
        let t = ur.fk([10, -60, 80, -110, -70, 30]);
        let many = ur.ik_solutions(t);
        assert(many.len > 8, `${many.len} solutions: the heap store is not used`);
        same(ur, t, many, ur.ik(t));
        let placed = doc.add_robot("ur", ur, #{base: [500, 0, 0, 0, 0, 90]});
        placed.joints = [10, -60, 80, -110, -70, 30];
        same(placed, placed.tcp, placed.ik_solutions(placed.tcp), placed.ik(placed.tcp));
        print("ok");
    "#;
    script_passes("ik_solutions.rhai", script);
}

/// Batch forms: `fk_many` equals `fk` entry by entry, `ik_many` follows a line of poses
/// keeping each solution next to the previous one (and `()` where a pose is out of
/// reach); the wrist-singular pose comes back from `ik_branches` flagged with joint 5
/// exactly 0; `limits_source` says where the catalog limits come from.
#[test]
fn batch_fk_ik_and_singular_flags_through_the_script_api() {
    let script = r#"
        let doc = open_doc("models/mz07.yaml");
        let arm = doc.robot("mz07");
        let qs = [];
        for i in 0..200 { qs.push([i * 0.3, -20 + i * 0.1, 10, 30, 40 - i * 0.2, i]); }
        let poses = arm.fk_many(qs);
        assert(poses.len() == 200, "count");
        for i in 0..200 { assert(poses[i] == arm.fk(qs[i]), `fk_many ${i}`); }
        let sols = arm.ik_many(poses);
        for i in 0..200 {
            for j in 0..6 { assert_near(sols[i][j], qs[i][j], 1e-6); }
        }
        let far = arm.ik_many([[9000, 0, 0, 0, 0, 0]]);
        assert(far[0] == (), "unreachable entry is ()");
        // Joint 5 at its singular value (MZ07: -90° in this table's convention is not
        // special; its wrist aligns axes 4 and 6 at joint 5 = 90°).
        let branches = arm.ik_branches(arm.fk([10, -20, 30, 25, 90, 40]));
        let flagged = 0;
        for b in branches { if b.singular { flagged += 1; assert(b.joints[4] == 90.0 || (b.joints[4] - 90.0).abs() < 1e-9, `${b.joints}`); } }
        assert(flagged >= 2, `${flagged} singular branches`);
        assert(arm.limits_source.starts_with("unverified"), arm.limits_source);
        print("ok");
    "#;
    script_passes("batch.rhai", script);
}

/// Script constructors: `robot_opw` with the IRB 2400's published parameters
/// (opw_kinematics `makeIrb2400_10`, metres there, mm here) puts the flange at
/// (940, 0, 1455) pointing +x and is solved in closed form; `robot_dh` with seed 000's
/// table 2 matches the catalog MZ07's flange; `add_robot` places it in a document at a
/// base, where it moves along a line, and saving then reopening keeps it.
#[test]
fn robots_built_in_scripts_join_a_document() {
    let script = r#"
        let irb = robot_opw(#{a1: 100, a2: -135, b: 0, c1: 615, c2: 705, c3: 755, c4: 85,
                              offsets: [0, 0, -90, 0, 0, 0],
                              limits: [[-180, 180], [-100, 110], [-60, 65], [-200, 200], [-120, 120], [-400, 400]]});
        assert(irb.closed_form, "closed form");
        let p = irb.fk([0, 0, 0, 0, 0, 0]);
        let t = p.translation;
        assert_near(t[0], 940.0, 1e-9); assert_near(t[1], 0.0, 1e-9); assert_near(t[2], 1455.0, 1e-9);
        let z = p.apply_vector([0, 0, 1]);
        assert_near(z[0], 1.0, 1e-12);
        let sols = irb.ik(irb.fk([10, 20, -30, 40, 50, 60]));
        assert(sols.len() >= 2, "branches");
        assert(irb.ik(irb.fk([10, 20, -30, 40, 50, 60]).xyzabc).len() == sols.len(), "branches from xyzabc");
        let mz = robot_dh([[0, 340, 50, 90], [90, 0, 330, 0], [0, 0, 45, 90], [0, 340, 0, 90], [90, 0, 0, 90], [0, -80, 0, 0]]);
        let doc = open_doc("models/mz07.yaml");
        let ref = doc.robot("mz07");
        let q = [10, -20, 30, 40, -50, 60];
        let flange = mz.fk(q);
        // Row-vector composition: the flange is 436.9 mm up the tool axis from the TCP.
        assert_near(flange.distance_to(translation(0, 0, 516.9 - 80) * ref.fk(q)).mm, 0.0, 1e-9);
        let arm = doc.add_robot("irb", irb, #{base: [1000, 0, 0, 0, 0, 90]});
        assert(doc.robots().contains("irb"), "listed");
        assert_near(arm.tcp.translation[0], 1000.0, 1e-9); assert_near(arm.tcp.translation[1], 940.0, 1e-9);
        arm.joints = [0, 10, -10, 0, 30, 0];
        let start = arm.tcp;
        arm.move_line(start * translation(0, 50, -50));
        assert_near(arm.tcp.distance_to(start * translation(0, 50, -50)).mm, 0.0, 1e-6);
        doc.save_as("models/with_irb.yaml");
        let again = open_doc("models/with_irb.yaml");
        let b = again.robot("irb");
        assert_near(b.tcp.distance_to(arm.tcp).mm, 0.0, 1e-6);
        assert_near(b.fk([5, 5, 5, 5, 5, 5]).distance_to(arm.fk([5, 5, 5, 5, 5, 5])).mm, 0.0, 1e-6);
        print("ok");
    "#;
    script_passes("build.rhai", script);
}

/// Robot errors reach the document caller typed: limits and kinematics errors are
/// `DocumentError::Robot`, an unknown robot index is `NotFound`.
#[test]
fn robot_errors_are_typed() {
    use fitup::document::{DocumentError, RobotError};
    let dir = project();
    let mut doc = Document::open(&mz07(dir.path())).unwrap();
    let e = doc
        .set_robot_joints(0, &[0.0, 0.0, 0.0, 0.0, 3.0, 0.0])
        .unwrap_err();
    assert!(
        matches!(
            e,
            DocumentError::Robot(RobotError::JointLimit { joint: 5, .. })
        ),
        "{e}"
    );
    let e = doc.set_robot_joints(0, &[0.0; 3]).unwrap_err();
    assert!(
        matches!(e, DocumentError::Robot(RobotError::Kinematics { .. })),
        "{e}"
    );
    let e = doc.set_robot_joints(7, &[0.0; 6]).unwrap_err();
    assert!(
        matches!(e, DocumentError::NotFound { what: "robot", .. }),
        "{e}"
    );
    let nan = Transform::from_translation(Vec3::new(f64::NAN, 0.0, 0.0));
    let e = doc.set_robot_base(0, nan).unwrap_err();
    assert!(
        matches!(
            e,
            DocumentError::Robot(RobotError::NonFinite { what: "base", .. })
        ),
        "{e}"
    );
}

/// `fitup run PROGRAM --doc DOC --robot NAME` prints the joint/TCP log (or writes it
/// with --log); the last row is the last Joint command.
#[test]
fn program_runs_through_the_cli() {
    let dir = project();
    std::fs::copy(
        common::repo().join("models/mz07_demo.prg"),
        dir.path().join("models/mz07_demo.prg"),
    )
    .unwrap();
    let out = common::run_in(
        dir.path(),
        &["run", "models/mz07_demo.prg", "--doc", "models/mz07.yaml"],
    );
    assert!(out.status.success(), "{}", common::text(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("t_s,j1_deg"));
    let last = common::last_csv_numbers(&text);
    let want = [20.0, -10.0, 10.0, 0.0, 0.0, 0.0];
    for (v, w) in last[1..7].iter().zip(want) {
        assert!((v - w).abs() < 1e-5, "{last:?}");
    }
    // Two robots: --robot chooses, --log writes the CSV.
    let two_robots = |extra: &[&str]| {
        let mut args = vec![
            "run",
            "models/mz07_demo.prg",
            "--doc",
            "models/cell_robots.yaml",
        ];
        args.extend_from_slice(extra);
        common::run_in(dir.path(), &args)
    };
    let out = two_robots(&[]);
    assert_eq!(out.status.code(), Some(2), "{}", common::text(&out));
    assert!(common::text(&out).contains("--robot"));
    let out = two_robots(&["--robot", "mz07_a", "--log", "log.csv"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let log = std::fs::read_to_string(dir.path().join("log.csv")).unwrap();
    assert!(log.lines().count() > 10);
}

/// Syntax and motion errors of a program name the file and the line.
#[test]
fn bad_programs_give_file_and_line() {
    let dir = project();
    std::fs::write(
        dir.path().join("bad.prg"),
        "# comment\nSpeed 100\nLine 390 0 300 0 0\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "bad.prg", "--doc", "models/mz07.yaml"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        common::text(&out).contains("bad.prg:3:"),
        "{}",
        common::text(&out)
    );
    std::fs::write(
        dir.path().join("far.prg"),
        "Line 390 0 300 0 0 0\n\nLine 390 0 1500 0 0 0\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "far.prg", "--doc", "models/mz07.yaml"]);
    assert_eq!(out.status.code(), Some(1));
    let text = common::text(&out);
    assert!(
        text.contains("far.prg:3:") && text.contains("unreachable"),
        "{text}"
    );
    // Without --doc: a usage error that says what is missing.
    let out = common::run_in(dir.path(), &["run", "far.prg"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(common::text(&out).contains("--doc"));
}

/// Saving keeps robots, joints, base and tool; reloading reproduces every link pose.
#[test]
fn save_and_load_keep_robots() {
    let dir = project();
    let mut doc = Document::open(&dir.path().join("models/cell_robots.yaml")).unwrap();
    let a = doc.robot_index("mz07_a").unwrap();
    let b = doc.robot_index("mz07_b").unwrap();
    let qa: Vec<f64> = [10.0f64, -20.0, 30.0, 40.0, 50.0, 60.0]
        .iter()
        .map(|v| v.to_radians())
        .collect();
    doc.set_robot_joints(a, &qa).unwrap();
    doc.set_dimension("D1@b角度3", 0.5).unwrap();
    let base =
        doc.robots()[b].robot().base() * Transform::from_translation(Vec3::new(0.0, 25.0, 0.0));
    doc.set_robot_base(b, base).unwrap();
    let tool = Transform::from_translation(Vec3::new(0.0, 0.0, -300.0));
    doc.set_robot_tool(a, tool).unwrap();
    let copy = dir.path().join("models/copy.yaml");
    doc.save_as(&copy).unwrap();
    let back = Document::open(&copy).unwrap();
    assert_eq!(back.robots().len(), 2);
    assert_eq!(back.dimensions(), doc.dimensions());
    for (r0, r1) in doc.robots().iter().zip(back.robots()) {
        assert_eq!(r0.name(), r1.name());
        for (x, y) in r0.joints().iter().zip(r1.joints()) {
            assert!((x - y).abs() < 1e-12);
        }
        assert!(r0.robot().base().approx_eq(&r1.robot().base(), 1e-9, 1e-12));
        assert!(r0.robot().tool().approx_eq(&r1.robot().tool(), 1e-9, 1e-12));
        assert!(r0.tcp().approx_eq(&r1.tcp(), 1e-9, 1e-12));
    }
    for (c0, c1) in doc.components().iter().zip(back.components()) {
        assert!(
            c0.transform.approx_eq(&c1.transform, 1e-9, 1e-12),
            "{}",
            c0.name
        );
    }
    assert!((back.dimension("D1@b角度3").unwrap().value - 0.5).abs() < 1e-12);
    // The plate's angle mate still drives the plate with the robots present.
    let mut back = back;
    back.set_dimension("D1@角度1", 0.3).unwrap();
    let c = back
        .component("plate_b")
        .unwrap()
        .transform
        .to_xyzabc(Default::default())[5];
    assert!((c - 0.3).abs() < 1e-6);
}

/// A robot from a D-H table (seed 000 table 2) and from explicit links build the same
/// kinematics as the catalog arm; a prismatic joint's dimension is a length.
#[test]
fn dh_and_explicit_trees() {
    let dir = project();
    let doc_text = r#"
parts:
  box: {stl: meshes/pedestal.stl}
components:
- {name: slide, part: box}
- {name: arm, part: box}
robots:
- name: table2
  dh:
    rows:
    - {theta: 0, d: 340, a: 50, alpha: 90, limits: [-170, 170]}
    - {theta: 90, d: 0, a: 330, alpha: 0}
    - {theta: 0, d: 0, a: 45, alpha: 90}
    - {theta: 0, d: 340, a: 0, alpha: 90}
    - {theta: 90, d: 0, a: 0, alpha: 90}
    - {theta: 0, d: -80, a: 0, alpha: 0}
  tool:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [0, 0, -436.9, 1]
  joints: [10, 20, 30, 40, 50, 60]
- name: gantry
  links:
  - {name: floor}
  - {name: carriage, parent: floor, joint: prismatic, axis: [1, 0, 0], limits: [0, 500], component: slide, dimension: X轴}
  - name: arm
    parent: carriage
    joint: revolute
    axis: [0, 0, 1]
    point: [0, 100, 0]
    component: arm
  joints: [120, 90]
"#;
    let path = dir.path().join("models/trees.yaml");
    std::fs::write(&path, doc_text).unwrap();
    let mut doc = Document::open(&path).unwrap();
    let dh = doc.robot("table2").unwrap();
    let cat = fitup::kinematics::Catalog::NachiMz07.robot();
    let q = dh.joints().to_vec();
    assert!(dh
        .robot()
        .tcp_pose(&q)
        .unwrap()
        .approx_eq(&cat.tcp_pose(&q).unwrap(), 1e-9, 1e-12));
    assert!(
        dh.robot().analytic().is_some(),
        "a table-2 arm gets the closed form"
    );
    // Default dimension names, and the prismatic joint's length dimension.
    assert!(doc.dimensions().contains(&"D1@角度1@table2".to_string()));
    let x = doc.dimension("D1@X轴").unwrap();
    assert_eq!(x.kind, DimensionKind::Length);
    assert!((x.system_value() - 0.12).abs() < 1e-12);
    doc.set_dimension("D1@X轴", 300.0).unwrap();
    assert!(
        (doc.component("slide").unwrap().transform.translation() - Vec3::new(300.0, 0.0, 0.0))
            .norm()
            < 1e-9
    );
    // The arm turned 90° about the line x = 300, y = 100: its origin went to (400, 100).
    let arm = doc.component("arm").unwrap().transform;
    assert!((arm.translation() - Vec3::new(400.0, 100.0, 0.0)).norm() < 1e-9);
    assert!(doc.set_dimension("D1@X轴", 600.0).is_err());
}

/// Loader errors are located (line > 0) and say what is wrong.
#[test]
fn invalid_robots_are_located_errors() {
    let dir = project();
    let head = "parts:\n  box: {stl: meshes/pedestal.stl}\ncomponents:\n- {name: b, part: box}\n";
    let cases = [
        (
            "robots:\n- name: r\n  catalog: nachi_mz07\n  links:\n  - component: nope\n",
            "unknown component `nope`",
            9,
        ),
        (
            "robots:\n- name: r\n  catalog: nachi_mz7\n",
            "did you mean `nachi_mz07`",
            7,
        ),
        (
            "robots:\n- name: r\n  links:\n  - {name: a}\n  - {name: c, parent: a, joint: revolute, axis: [0, 0, 1], limits: [90, -90]}\n",
            "inverted",
            9,
        ),
        (
            "robots:\n- name: r\n  catalog: nachi_mz07\n  joints: [0, 0, 0]\n",
            "3 joint values given, the robot has 6",
            8,
        ),
        (
            "robots:\n- name: r\n  catalog: nachi_mz07\n  joints: [0, 0, 0, 0, 130, 0]\n",
            "joint 5",
            8,
        ),
        (
            "robots:\n- name: r\n  catalog: nachi_mz07\n  links:\n  - {}\n  - {dimension: 角度1}\n- name: s\n  catalog: nachi_mz07\n  links:\n  - {}\n  - {dimension: 角度1}\n",
            "duplicate dimension name `D1@角度1`",
            15,
        ),
        (
            "robots:\n- name: r\n  catalog: nachi_mz07\n  links:\n  - {component: b}\n- name: s\n  catalog: nachi_mz07\n  links:\n  - {component: b}\n",
            "already displays a link of robot `r`",
            13,
        ),
    ];
    for (robots, message, line) in cases {
        let path = dir.path().join("models/bad.yaml");
        std::fs::write(&path, format!("{head}{robots}")).unwrap();
        let err = Document::open(&path).unwrap_err();
        let text = err.to_string();
        assert!(text.contains(message), "{robots}\n→ {text}");
        assert!(
            text.contains(&format!("bad.yaml:{line}:")),
            "{robots}\n→ {text} (expected line {line})"
        );
    }
}

/// `stream: true` prints one monitor line per sample through the run's output (the
/// sink `fitup watch` streams), with the joints and the TCP of each sample.
#[test]
fn streamed_motions_print_every_sample() {
    let dir = project();
    let script = r#"
        let arm = open_doc("models/mz07.yaml").robot("mz07");
        let t = arm.move_line(pose(390, 0, 250, 0, 0, 0), #{speed: 100, interval: 0.1, stream: true});
        print(`samples ${t.len}`);
    "#;
    let out = common::run_script_in(dir.path(), "s.rhai", script);
    let text = common::text(&out);
    assert!(out.status.success(), "{text}");
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("[mz07] t="))
        .collect();
    // 51.9 mm at 100 mm/s = 0.519 s: samples at 0, 0.1, …, 0.5 and 0.519.
    assert_eq!(lines.len(), 7, "{text}");
    assert!(text.contains("samples 7"));
    assert!(
        lines[6].contains("tcp=[390 0 250 0 0 0]") && !lines[6].contains("-0 "),
        "{}",
        lines[6]
    );
}
