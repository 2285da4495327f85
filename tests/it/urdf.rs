//! URDF import end to end: a 6-axis industrial arm (ROS-Industrial layout, written
//! here) and a 7-DOF arm of our own load with the right kinematics (FK against hand
//! computations, IK round trips, the closed form chosen for the OPW arm), mesh URIs
//! resolve by the documented rule, and hostile files give located errors.

use fitup::document::Document;
use fitup::kinematics::{parse_urdf, resolve_mesh, IkOptions, OpwSolver, MAX_URDF_BYTES};
use fitup::math::{Point3, Rng, Vec3};
use fitup::mesh::{write_stl, Mesh};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

/// A 6-axis industrial arm in the ROS-Industrial style (metres, `base_link`,
/// `link_1..6`, `tool0` with z out of the flange), our own dimensions.
const ARM6: &str = r#"<?xml version="1.0"?>
<robot name="arm6">
  <link name="base_link">
    <visual><geometry><mesh filename="package://arm6_support/meshes/base_link.stl"/></geometry></visual>
  </link>
  <link name="link_1"><visual><origin xyz="0 0 0.1" rpy="0 0 0"/><geometry><mesh filename="package://arm6_support/meshes/link_1.stl"/></geometry></visual></link>
  <link name="link_2"/>
  <link name="link_3"/>
  <link name="link_4"/>
  <link name="link_5"/>
  <link name="link_6"/>
  <link name="tool0"/>
  <joint name="joint_1" type="revolute">
    <origin xyz="0 0 0.45" rpy="0 0 0"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="0" velocity="2"/>
  </joint>
  <joint name="joint_2" type="revolute">
    <origin xyz="0.15 0 0" rpy="0 0 0"/><parent link="link_1"/><child link="link_2"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" effort="0" velocity="2"/>
  </joint>
  <joint name="joint_3" type="revolute">
    <origin xyz="0 0 0.6" rpy="0 0 0"/><parent link="link_2"/><child link="link_3"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="0" velocity="2"/>
  </joint>
  <joint name="joint_4" type="revolute">
    <origin xyz="0 0 0.12" rpy="0 0 0"/><parent link="link_3"/><child link="link_4"/>
    <axis xyz="1 0 0"/><limit lower="-3.5" upper="3.5" effort="0" velocity="2"/>
  </joint>
  <joint name="joint_5" type="revolute">
    <origin xyz="0.55 0 0" rpy="0 0 0"/><parent link="link_4"/><child link="link_5"/>
    <axis xyz="0 1 0"/><limit lower="-2.1" upper="2.1" effort="0" velocity="2"/>
  </joint>
  <joint name="joint_6" type="continuous">
    <origin xyz="0.1 0 0" rpy="0 0 0"/><parent link="link_5"/><child link="link_6"/>
    <axis xyz="1 0 0"/>
  </joint>
  <joint name="joint_6-tool0" type="fixed">
    <origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/><parent link="link_6"/><child link="tool0"/>
  </joint>
</robot>
"#;

/// A 7-DOF arm of our own: alternating z / y axes with elbow offsets (not OPW).
const ARM7: &str = r#"<robot name="arm7">
  <link name="l0"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/>
  <link name="l5"/><link name="l6"/><link name="l7"/><link name="tip"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.3"/><parent link="l0"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/><limit lower="-1.8" upper="1.8"/></joint>
  <joint name="j3" type="revolute"><origin xyz="0 0 0.4"/><parent link="l2"/><child link="l3"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9"/></joint>
  <joint name="j4" type="revolute"><origin xyz="0.05 0 0"/><parent link="l3"/><child link="l4"/><axis xyz="0 1 0"/><limit lower="-3.0" upper="3.0"/></joint>
  <joint name="j5" type="revolute"><origin xyz="-0.05 0 0.35"/><parent link="l4"/><child link="l5"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/><axis xyz="0 1 0"/><limit lower="-3.0" upper="3.0"/></joint>
  <joint name="j7" type="revolute"><origin xyz="0.08 0 0.1"/><parent link="l6"/><child link="l7"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9"/></joint>
  <joint name="flange" type="fixed"><origin xyz="0 0 0.1"/><parent link="l7"/><child link="tip"/></joint>
</robot>"#;

fn path() -> &'static Path {
    Path::new("support/urdf/arm.urdf")
}

/// The 6-axis arm: FK by hand (mm), z out of the flange, the closed form detected and
/// every IK solution round-tripping; joint 6 `continuous` has no limits.
#[test]
fn industrial_arm_loads_with_closed_form_ik() {
    let u = parse_urdf(path(), ARM6, None).unwrap();
    let r = &u.robot;
    assert_eq!(r.dof(), 6);
    assert!(r.analytic().is_some(), "{:?}", r.analytic_rejection());
    assert_eq!(r.tree().links()[r.flange()].name.as_deref(), Some("tool0"));
    assert!(r.joint_limits()[5].is_none());
    assert!((r.joint_limits()[1].unwrap().max - 2.0).abs() < 1e-15);
    // q = 0: tool0 at (150 + 550 + 100, 0, 450 + 600 + 120), z along +x.
    let t = r.tcp_pose(&[0.0; 6]).unwrap();
    assert!((t.translation() - Vec3::new(800.0, 0.0, 1170.0)).norm() < 1e-9);
    assert!((t.apply_vector(&Vec3::z()) - Vec3::x()).norm() < 1e-12);
    // Joint 2 by 90° about +y through (150, 0, 450): (650, 0, 720) turns to (720, 0, −650).
    let t = r.tcp_pose(&[0.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert!((t.translation() - Vec3::new(870.0, 0.0, -200.0)).norm() < 1e-9);
    // Joint 1 by 90°: a quarter turn about z.
    let t = r.tcp_pose(&[FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert!((t.translation() - Vec3::new(0.0, 800.0, 1170.0)).norm() < 1e-9);
    // The derived OPW parameters: upper arm 600 mm, forearm √(550² + 120²), no lateral offset.
    let (_p2, u2, u3, b, _) = OpwSolver::detect(r).unwrap().parameters();
    assert!((u2[0].hypot(u2[1]) - 600.0).abs() < 1e-9);
    assert!((u3[0].hypot(u3[1]) - 550f64.hypot(120.0)).abs() < 1e-9);
    assert!(b.abs() < 1e-9);
    let mut rng = Rng::new(6);
    for _ in 0..300 {
        let q: Vec<f64> = (0..6).map(|_| rng.range(-1.5, 1.5)).collect();
        let target = r.tcp_pose(&q).unwrap();
        let sols = r.inverse(&target, &q, &IkOptions::default()).unwrap();
        assert!(sols[0]
            .joints
            .iter()
            .zip(&q)
            .all(|(a, b)| (a - b).abs() < 1e-7));
        for s in &sols {
            assert!(r
                .tcp_pose(&s.joints)
                .unwrap()
                .approx_eq(&target, 1e-6, 1e-9));
        }
    }
    // Meshes: listed per link with their visual origin, scaled to mm.
    assert_eq!(u.meshes.len(), 2);
    assert_eq!(u.meshes[1].link, 1);
    assert!((u.meshes[1].origin.translation() - Vec3::new(0.0, 0.0, 100.0)).norm() < 1e-12);
    assert_eq!(u.meshes[0].scale, [1000.0; 3]);
}

/// The 7-DOF arm: FK by hand, numeric IK (no closed form) round-trips.
#[test]
fn seven_dof_arm_loads_with_numeric_ik() {
    let r = parse_urdf(path(), ARM7, None).unwrap().robot;
    assert_eq!(r.dof(), 7);
    assert!(r.analytic().is_none());
    // q = 0: tip at x = 50 − 50 + 80, z = 300 + 400 + 350 + 100 + 100.
    let t = r.tcp_pose(&[0.0; 7]).unwrap();
    assert!((t.translation() - Vec3::new(80.0, 0.0, 1250.0)).norm() < 1e-9);
    // Joint 4 by 90° about +y through (50, 0, 700): (30, 0, 550) turns to (550, 0, −30).
    let mut q = [0.0; 7];
    q[3] = FRAC_PI_2;
    let t = r.tcp_pose(&q).unwrap();
    assert!((t.translation() - Vec3::new(600.0, 0.0, 670.0)).norm() < 1e-9);
    let mut rng = Rng::new(7);
    let opts = IkOptions::default();
    for _ in 0..40 {
        let q: Vec<f64> = (0..7).map(|_| rng.range(-1.2, 1.2)).collect();
        let target = r.tcp_pose(&q).unwrap();
        let start: Vec<f64> = q.iter().map(|v| v + rng.range(-0.2, 0.2)).collect();
        let sols = r.inverse(&target, &start, &opts).unwrap();
        for s in &sols {
            let (ang, dist) = r.tcp_pose(&s.joints).unwrap().distance_to(&target);
            assert!(dist < 1e-6 && ang < 1e-9, "{dist} mm {ang} rad");
            assert!(r.limit_violation(&s.joints).is_none());
        }
    }
}

/// `package://PKG/rest` resolves next to the URDF's package (ROS-Industrial layout).
#[test]
fn package_uris_resolve_by_the_documented_rule() {
    let p = Path::new("models/arm6_support/urdf/arm6.urdf");
    assert_eq!(
        resolve_mesh(p, "package://arm6_support/meshes/link_1.stl"),
        Path::new("models/arm6_support/meshes/link_1.stl")
    );
    let flat = Path::new("models/arm6.urdf");
    assert_eq!(
        resolve_mesh(flat, "package://arm6_support/meshes/l.stl"),
        Path::new("models/meshes/l.stl")
    );
    assert_eq!(
        resolve_mesh(flat, "meshes/l.stl"),
        Path::new("models/meshes/l.stl")
    );
}

fn error(text: &str) -> String {
    parse_urdf(path(), text, None).unwrap_err().to_string()
}

/// Hostile URDFs: located errors (file and line), no panic, bounded work.
#[test]
fn hostile_urdfs_give_located_errors() {
    let cycle = r#"<robot name="c">
<link name="a"/><link name="b"/>
<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>
</robot>"#;
    let e = error(cycle);
    assert!(e.contains("cycle") && e.contains("arm.urdf"), "{e}");
    let two_parents = r#"<robot name="c">
<link name="a"/><link name="b"/><link name="c"/>
<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
<joint name="cb" type="fixed"><parent link="c"/><child link="b"/></joint>
</robot>"#;
    let e = error(two_parents);
    assert!(
        e.contains(":4:") && e.contains("already has a parent"),
        "{e}"
    );
    let missing = "<robot name=\"m\">\n<link name=\"a\"/>\n<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"ghost\"/></joint>\n</robot>";
    let e = error(missing);
    assert!(e.contains(":3:") && e.contains("ghost"), "{e}");
    let roots = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n</robot>";
    let e = error(roots);
    assert!(e.contains(":3:") && e.contains("two root links"), "{e}");
    for bad in ["nan 0 0", "0 inf 0", "1e999 0 0", "0 0", "x y z"] {
        let t = format!("<robot name=\"n\">\n<link name=\"a\"/><link name=\"b\"/>\n<joint name=\"j\" type=\"revolute\"><origin xyz=\"{bad}\"/><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint>\n</robot>");
        let e = error(&t);
        assert!(e.contains(":3:") && e.contains("xyz"), "{bad}: {e}");
    }
    let e = error("<robot name=\"u\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"floating\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>");
    assert!(e.contains("floating"), "{e}");
    let e = error("<robot><link name=\"a\"></robot>");
    assert!(e.contains("not valid XML"), "{e}");
    let e = error("<robot name=\"z\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 0\"/></joint></robot>");
    assert!(e.contains("zero length"), "{e}");
    let huge = format!("<robot name=\"h\">{}</robot>", " ".repeat(MAX_URDF_BYTES));
    assert!(error(&huge).contains("limit"));
}

/// A project in a temporary folder: `proj/fitup.toml`, a URDF `proj/r.urdf` whose
/// link `arm` has the mesh `mesh` (visual origin 0.1 m along x, scale 2 1 1), the
/// cuboid STL `proj/m.stl` (metres) and a document `proj/cell.yaml` with the robot.
fn urdf_project(mesh: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let proj = dir.path().join("proj");
    std::fs::create_dir_all(&proj).unwrap();
    std::fs::write(proj.join("fitup.toml"), "").unwrap();
    let cube = Mesh::cuboid(Point3::origin(), Point3::new(0.01, 0.02, 0.03));
    write_stl(&proj.join("m.stl"), &cube).unwrap();
    write_stl(&dir.path().join("elsewhere.stl"), &cube).unwrap();
    let urdf = format!(
        r#"<robot name="r">
  <link name="base"/>
  <link name="arm">
    <visual><origin xyz="0.1 0 0"/><geometry><mesh filename="{mesh}" scale="2 1 1"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute">
    <origin xyz="0 0 0.5"/><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3"/>
  </joint>
</robot>"#
    );
    std::fs::write(proj.join("r.urdf"), urdf).unwrap();
    std::fs::write(
        proj.join("cell.yaml"),
        "robots:\n- name: r\n  urdf: r.urdf\n  joints: [90]\n",
    )
    .unwrap();
    let doc = proj.join("cell.yaml");
    (dir, doc)
}

/// A `urdf:` robot in a document: the link's STL mesh is a component posed by FK with
/// the visual origin and scale applied, and saving writes the `urdf:` entry back.
#[test]
fn document_urdf_robot_meshes_are_posed_and_saved() {
    let (_dir, path) = urdf_project("package://r_support/m.stl");
    let mut doc = Document::open(&path).unwrap();
    let c = doc.component_index("r:arm").unwrap();
    let world: Vec<Point3> = {
        let t = doc.components()[c].transform;
        doc.mesh_of(c).vertices.iter().map(|v| t.apply(v)).collect()
    };
    // By hand: corner (10, 20, 30) mm, scaled (2, 1, 1) → (20, 20, 30), visual origin
    // +100 x → (120, 20, 30) in the link frame; joint 1 at 90° about z turns it to
    // (−20, 120, 30), the joint origin lifts it 500 mm.
    for (x, y, z) in [(0.0, 0.0, 0.0), (20.0, 20.0, 30.0), (20.0, 0.0, 30.0)] {
        // Link frame (100 + x, y, z) turned 90° about z: (−y, 100 + x, z), lifted 500.
        let e = Point3::new(-y, 100.0 + x, 500.0 + z);
        assert!(
            world.iter().any(|w| (w - e).norm() < 1e-4),
            "{e:?} not among {world:?}"
        );
    }
    assert!(world
        .iter()
        .any(|w| (w - Point3::new(-20.0, 120.0, 530.0)).norm() < 1e-4));
    // Joints move the component: at 0 the same corner is at (120, 20, 530).
    doc.set_robot_joints(0, &[0.0]).unwrap();
    let t = doc.components()[c].transform;
    assert!(doc
        .mesh_of(c)
        .vertices
        .iter()
        .any(|v| (t.apply(v) - Point3::new(120.0, 20.0, 530.0)).norm() < 1e-4));
    // Saved: the `urdf:` entry, not the generated part; it loads again.
    let yaml = doc.to_yaml();
    assert!(
        yaml.contains("urdf: r.urdf") && !yaml.contains("r:arm"),
        "{yaml}"
    );
    let moved = path.parent().unwrap().join("sub/cell2.yaml");
    std::fs::create_dir_all(moved.parent().unwrap()).unwrap();
    doc.save_as(&moved).unwrap();
    let text = std::fs::read_to_string(&moved).unwrap();
    assert!(text.contains("urdf: ../r.urdf"), "{text}");
    let again = Document::open(&moved).unwrap();
    assert!(again.component_index("r:arm").is_ok());
    // add_urdf_robot: the same robot added in code brings its mesh component.
    let mut empty = Document::from_yaml("{}", &path, &mut fitup::mesh::MeshCache::new()).unwrap();
    let i = empty
        .add_urdf_robot("r2", &path.parent().unwrap().join("r.urdf"), None, &[])
        .unwrap();
    assert_eq!(empty.robots()[i].name(), "r2");
    assert!(empty.component_index("r2:arm").is_ok());
    assert!(empty.to_yaml().contains("urdf: r.urdf"));
}

/// A mesh path leading outside the project is refused (the file outside is never
/// read); a `.dae` mesh without a collision mesh fitup reads is left out with a
/// warning naming the URDF line (the robot's kinematics still load).
#[test]
fn urdf_mesh_escape_refused_and_dae_reported() {
    let (_dir, path) = urdf_project("../elsewhere.stl");
    let e = Document::open(&path).unwrap_err().to_string();
    assert!(
        e.contains("outside the project") && e.contains("r.urdf:4"),
        "{e}"
    );
    let (_dir, path) = urdf_project("package://r_support/meshes/arm.dae");
    let doc = Document::open(&path).unwrap();
    let w = doc.warnings().join("\n");
    assert!(
        w.contains("r.urdf:4") && w.contains("arm.dae") && w.contains("left out"),
        "{w}"
    );
    assert!(doc.component_index("r:arm").is_err());
    assert_eq!(doc.robots()[0].robot().dof(), 1);
}

/// The docs/robots.md example's `robots:` block (the `ur5e_robotiq` entry), as written.
fn docs_arm_and_gripper_entry() -> String {
    let md =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/robots.md")).unwrap();
    let block = md
        .split("```yaml")
        .skip(1)
        .filter_map(|b| b.split("```").next())
        .find(|b| b.contains("ur5e_robotiq"))
        .expect("docs/robots.md shows the ur5e_robotiq entry");
    let lines: Vec<&str> = block.lines().filter(|l| !l.trim().is_empty()).collect();
    let indent = lines[0].len() - lines[0].trim_start().len();
    lines
        .iter()
        .map(|l| format!("{}\n", &l[indent..]))
        .collect()
}

/// Edge of the cube standing for each package's meshes (metres): which file was read
/// shows in the component's volume.
const UR_CUBE: f64 = 0.06;
const ROBOTIQ_CUBE: f64 = 0.08;

/// A project holding two ROS packages side by side, as a ROS workspace does:
/// `ur_description/urdf/ur5e_robotiq.urdf` (a UR5e, every arm link's visual mesh in
/// `package://ur_description/meshes/ur5e/visual/`, carrying a two-finger gripper on
/// `tool0` whose meshes are in `package://robotiq_2f_85_gripper_visualization/meshes/`)
/// and the gripper package at `gripper_parent/robotiq_2f_85_gripper_visualization`.
fn arm_and_gripper_project(gripper_parent: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("proj");
    let ur = p.join("ur_description");
    let robotiq = p
        .join(gripper_parent)
        .join("robotiq_2f_85_gripper_visualization");
    std::fs::create_dir_all(ur.join("urdf")).unwrap();
    std::fs::create_dir_all(ur.join("meshes/ur5e/visual")).unwrap();
    std::fs::create_dir_all(robotiq.join("meshes/visual")).unwrap();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    let cube = |e: f64| Mesh::cuboid(Point3::new(-e, -e, -e) / 2.0, Point3::new(e, e, e) / 2.0);
    let dh = fitup::kinematics::Catalog::Ur5e.ur_dh().unwrap();
    let mut urdf =
        crate::common::ur_urdf::ur_description("ur5e_robotiq", dh.map(|v| v / 1000.0), FRAC_PI_2);
    let visual = |link: &str, uri: String| {
        format!("<link name=\"{link}\"><visual><geometry><mesh filename=\"{uri}\"/></geometry></visual></link>")
    };
    for link in [
        "base_link",
        "shoulder_link",
        "upper_arm_link",
        "forearm_link",
    ] {
        let file = format!("meshes/ur5e/visual/{link}.stl");
        write_stl(&ur.join(&file), &cube(UR_CUBE)).unwrap();
        urdf = urdf.replace(
            &format!("<link name=\"{link}\"/>"),
            &visual(link, format!("package://ur_description/{file}")),
        );
    }
    let mut gripper = String::new();
    for link in ["robotiq_arg2f_base_link", "left_finger", "right_finger"] {
        let file = format!("meshes/visual/{link}.stl");
        write_stl(&robotiq.join(&file), &cube(ROBOTIQ_CUBE)).unwrap();
        gripper += &visual(
            link,
            format!("package://robotiq_2f_85_gripper_visualization/{file}"),
        );
    }
    gripper += r#"
  <joint name="tool0-gripper" type="fixed"><parent link="tool0"/><child link="robotiq_arg2f_base_link"/><origin xyz="0 0 0"/></joint>
  <joint name="finger_joint" type="prismatic"><parent link="robotiq_arg2f_base_link"/><child link="left_finger"/><origin xyz="0 0.01 0.1"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04"/></joint>
  <joint name="right_finger_joint" type="prismatic"><parent link="robotiq_arg2f_base_link"/><child link="right_finger"/><origin xyz="0 -0.01 0.1"/><axis xyz="0 1 0"/><limit lower="-0.04" upper="0"/><mimic joint="finger_joint" multiplier="-1"/></joint>
</robot>"#;
    urdf = urdf.replace("</robot>", &gripper);
    std::fs::write(ur.join("urdf/ur5e_robotiq.urdf"), urdf).unwrap();
    std::fs::write(p.join("cell.yaml"), docs_arm_and_gripper_entry()).unwrap();
    dir
}

/// An arm and a gripper from two packages (issue 38): `package://OTHER_PKG/…` is looked
/// up by the package's name (beside the URDF's package, or on the robot's
/// `package_path`), never read from the URDF's own package; the docs example entry
/// loads as written, the gripper's meshes follow `tool0`.
#[test]
fn an_arm_and_a_gripper_from_two_packages_load() {
    let dir = arm_and_gripper_project("");
    let cell = dir.path().join("proj/cell.yaml");
    let doc = Document::open(&cell).unwrap();
    assert!(doc.warnings().is_empty(), "{:?}", doc.warnings());
    let robot = doc.robots()[0].robot();
    assert_eq!((robot.dof(), robot.solver_name()), (6, "ur"));
    let volume = |d: &Document, c: &str| {
        d.mesh_of(d.component_index(c).unwrap_or_else(|e| panic!("{c}: {e}")))
            .signed_volume()
    };
    let cube = |e: f64| (e * 1000.0).powi(3);
    for (c, e) in [
        ("ur:shoulder_link", UR_CUBE),
        ("ur:robotiq_arg2f_base_link", ROBOTIQ_CUBE),
        ("ur:right_finger", ROBOTIQ_CUBE),
    ] {
        assert!((volume(&doc, c) - cube(e)).abs() < 1e-6 * cube(e), "{c}");
    }
    // The gripper body is centred on tool0.
    let c = doc.component_index("ur:robotiq_arg2f_base_link").unwrap();
    let t = doc.components()[c].transform;
    let b = doc.mesh_of(c).transformed(&t).bounds().unwrap();
    let centre = (b.lo.coords + b.hi.coords) / 2.0;
    let tcp = robot.tcp_pose(&[0.0; 6]).unwrap().translation();
    assert!((centre - tcp).norm() < 1e-6, "{centre:?} vs {tcp:?}");

    // The gripper package elsewhere: not found by name, the error says where it looked
    // and what to write; named on `package_path`, it loads and saves relative.
    let dir = arm_and_gripper_project("vendor");
    let p = dir.path().join("proj");
    let e = Document::open(&p.join("cell.yaml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("ur5e_robotiq.urdf:")
            && e.contains("no folder named `robotiq_2f_85_gripper_visualization`")
            && e.contains("package_path"),
        "{e}"
    );
    let entry = docs_arm_and_gripper_entry() + "  package_path: [vendor]\n";
    std::fs::write(p.join("cell.yaml"), &entry).unwrap();
    let mut doc = Document::open(&p.join("cell.yaml")).unwrap();
    assert!((volume(&doc, "ur:left_finger") - cube(ROBOTIQ_CUBE)).abs() < 1.0);
    let moved = p.join("sub/cell.yaml");
    std::fs::create_dir_all(p.join("sub")).unwrap();
    doc.save_as(&moved).unwrap();
    let text = std::fs::read_to_string(&moved).unwrap();
    assert!(text.contains("../vendor"), "{text}");
    assert!(Document::open(&moved)
        .unwrap()
        .component_index("ur:left_finger")
        .is_ok());

    // The package path comes before a folder of that name beside the URDF.
    let beside = p.join("robotiq_2f_85_gripper_visualization/meshes/visual");
    std::fs::create_dir_all(&beside).unwrap();
    for link in ["robotiq_arg2f_base_link", "left_finger", "right_finger"] {
        let m = Mesh::cuboid(Point3::origin(), Point3::new(0.01, 0.01, 0.01));
        write_stl(&beside.join(format!("{link}.stl")), &m).unwrap();
    }
    let doc = Document::open(&p.join("cell.yaml")).unwrap();
    assert!((volume(&doc, "ur:left_finger") - cube(ROBOTIQ_CUBE)).abs() < 1.0);
    let bare = p.join("bare.yaml");
    std::fs::write(&bare, docs_arm_and_gripper_entry()).unwrap();
    let doc = Document::open(&bare).unwrap();
    assert!((volume(&doc, "ur:left_finger") - cube(0.01)).abs() < 1e-3);
    // A package path entry that is a file is named as written.
    let entry = docs_arm_and_gripper_entry() + "  package_path: [bare.yaml]\n";
    std::fs::write(p.join("file.yaml"), entry).unwrap();
    let e = Document::open(&p.join("file.yaml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("package_path `bare.yaml` is not a folder"),
        "{e}"
    );
}

/// The same arm + gripper added in code (issue 38): `Document::add_urdf_robot` and a
/// script's `add_robot(name, load_urdf(..), #{package_path})` take the folder of the
/// gripper's package, load both packages' meshes and save the entry with it;
/// without it the gripper's package is not found.
#[test]
fn an_arm_and_a_gripper_from_two_packages_are_added_from_rust_and_scripts() {
    let dir = arm_and_gripper_project("vendor");
    let p = dir.path().join("proj");
    std::fs::write(p.join("empty.yaml"), "parts: {}\ncomponents: []\n").unwrap();
    let urdf = p.join("ur_description/urdf/ur5e_robotiq.urdf");
    let mut doc = Document::open(&p.join("empty.yaml")).unwrap();
    let e = doc
        .add_urdf_robot("ur", &urdf, None, &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no folder named `robotiq_2f_85_gripper_visualization`"),
        "{e}"
    );
    assert!(doc.robots().is_empty(), "nothing added on error");
    doc.add_urdf_robot("ur", &urdf, None, &[&p.join("vendor")])
        .unwrap();
    let finger = doc.component_index("ur:left_finger").unwrap();
    let cube = (ROBOTIQ_CUBE * 1000.0).powi(3);
    assert!((doc.mesh_of(finger).signed_volume() - cube).abs() < 1e-6 * cube);
    doc.save_as(&p.join("added.yaml")).unwrap();
    let text = std::fs::read_to_string(p.join("added.yaml")).unwrap();
    assert!(
        text.contains("package_path:") && text.contains("vendor"),
        "{text}"
    );
    let reopened = Document::open(&p.join("added.yaml")).unwrap();
    assert!(reopened.component_index("ur:right_finger").is_ok());

    // From a script, the folders relative to the project.
    std::fs::create_dir_all(p.join("scripts")).unwrap();
    let script = r#"let d = open_doc("empty.yaml");
let arm = load_urdf("ur_description/urdf/ur5e_robotiq.urdf");
let r = d.add_robot("ur", arm, #{package_path: ["vendor"]});
print(d.components().len());
d.save_as("scripted.yaml");
"#;
    std::fs::write(p.join("scripts/add.rhai"), script).unwrap();
    let o = crate::common::run_in(&p, &["run", "scripts/add.rhai"]);
    assert!(o.status.success(), "{}", crate::common::text(&o));
    let text = std::fs::read_to_string(p.join("scripted.yaml")).unwrap();
    assert!(
        text.contains("package_path:") && text.contains("vendor"),
        "{text}"
    );
    let scripted = Document::open(&p.join("scripted.yaml")).unwrap();
    assert!(scripted.component_index("ur:left_finger").is_ok());
    // Without it, the script's error names the missing package.
    std::fs::write(
        p.join("scripts/bare.rhai"),
        script.replace(", #{package_path: [\"vendor\"]}", ""),
    )
    .unwrap();
    let o = crate::common::run_in(&p, &["run", "scripts/bare.rhai"]);
    assert!(!o.status.success());
    assert!(
        crate::common::text(&o).contains("robotiq_2f_85_gripper_visualization"),
        "{}",
        crate::common::text(&o)
    );
}

/// The package search stays in the project: a `package_path` folder outside is
/// refused, and a package folder that is a link leading out is not followed.
#[cfg(unix)]
#[test]
fn package_search_stays_inside_the_project() {
    let dir = arm_and_gripper_project("../outside");
    let p = dir.path().join("proj");
    let entry = docs_arm_and_gripper_entry() + "  package_path: [../outside]\n";
    std::fs::write(p.join("cell.yaml"), &entry).unwrap();
    let e = Document::open(&p.join("cell.yaml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("package_path") && e.contains("outside the project"),
        "{e}"
    );
    std::os::unix::fs::symlink(
        dir.path()
            .join("outside/robotiq_2f_85_gripper_visualization"),
        p.join("robotiq_2f_85_gripper_visualization"),
    )
    .unwrap();
    std::fs::write(p.join("cell.yaml"), docs_arm_and_gripper_entry()).unwrap();
    let e = Document::open(&p.join("cell.yaml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("robotiq_2f_85_gripper_visualization"), "{e}");
}
