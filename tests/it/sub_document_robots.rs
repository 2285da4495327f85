//! Robots inside sub-documents (issue 37; they were refused): a document holding a
//! robot (catalog, drawn link components, or a `urdf:` arm with generated link
//! components) used as a sub-assembly of another, through two levels of files. The
//! robot, its joints and its driving dimensions are named inside the sub-assembly
//! (`Line-1/Cell-1/Arm`, `D1@Line-1/Cell-1/角度2@Arm`), its base and links placed by
//! the composed frames (checked against the sub-document opened on its own), driven
//! from Rust, Rhai and the CLI, moved with its sub-assembly, and saved back to its own
//! file without loss. Every project is generated in code (the URDF arm is the
//! repository's `models/urdf`, copied).

use super::sub_documents::nested_project;
use crate::common;
use fitup::document::{Document, DocumentError};
use fitup::kinematics::Catalog;
use fitup::math::{Transform, Vec3};
use std::path::{Path, PathBuf};

/// A robot cell: a NACHI MZ07 drawn by seven link components, on a fixed plinth.
const CELL: &str = "\
description: a robot cell, its own document
parts:
  link:
    stl: ../meshes/cube.stl
  plinth:
    stl: ../meshes/cube.stl
components:
- name: Plinth-1
  part: plinth
  fixed: true
- name: L0
  part: link
- name: L1
  part: link
- name: L2
  part: link
- name: L3
  part: link
- name: L4
  part: link
- name: L5
  part: link
- name: L6
  part: link
robots:
- name: Arm
  catalog: nachi_mz07
  base:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [100, 50, 0, 1]
  drawn_at_zero: true
  links:
  - {component: L0}
  - {component: L1}
  - {component: L2}
  - {component: L3}
  - {component: L4}
  - {component: L5}
  - {component: L6}
  joints: [10, -20, 30, 0, 45, 0]
";

/// A line holding the cell twice.
const LINE: &str = "\
assemblies:
- name: Cell-1
  file: cell.yaml
  transform:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [0, 0, 750, 1]
- name: Cell-2
  file: cell.yaml
  transform:
  - [-1, 0, 0, 0]
  - [0, -1, 0, 0]
  - [0, 0, 1, 0]
  - [2000, 0, 750, 1]
components: []
";

const TOP: &str = "\
parts:
  floor:
    stl: meshes/cube.stl
assemblies:
- name: Line-1
  file: sub/line.yaml
  transform:
  - [0, 1, 0, 0]
  - [-1, 0, 0, 0]
  - [0, 0, 1, 0]
  - [1000, 200, 0, 1]
components:
- name: floor
  part: floor
  fixed: true
";

/// `top.yaml` → `sub/line.yaml` (Line-1) → `sub/cell.yaml` twice (Cell-1, Cell-2),
/// `edit` applied to each file's text (`"cell"`, `"line"`, `"top"`).
fn project(edit: impl Fn(&str, &str) -> String) -> (tempfile::TempDir, PathBuf) {
    nested_project([("cell", CELL), ("line", LINE), ("top", TOP)], edit)
}

fn plain() -> (tempfile::TempDir, PathBuf) {
    project(|_, t| t.to_string())
}

fn m(rows: [[f64; 4]; 4]) -> Transform {
    Transform::from_matrix(&rows).unwrap()
}

/// Cell-1's and Cell-2's frames in the world: their pose in the line, then the
/// line's in the top document (row-vector order).
fn frames() -> [Transform; 2] {
    let line = m([
        [0., 1., 0., 0.],
        [-1., 0., 0., 0.],
        [0., 0., 1., 0.],
        [1000., 200., 0., 1.],
    ]);
    let cell1 = Transform::from_translation(Vec3::new(0.0, 0.0, 750.0));
    let cell2 = m([
        [-1., 0., 0., 0.],
        [0., -1., 0., 0.],
        [0., 0., 1., 0.],
        [2000., 0., 750., 1.],
    ]);
    [cell1 * line, cell2 * line]
}

/// Every link component and the TCP of the cell's robot in the assembly equal the
/// cell opened on its own (`alone`), placed by `frame`.
fn assert_placed(doc: &Document, at: &str, alone: &Document, frame: &Transform) {
    for k in 0..7 {
        let got = doc.component(&format!("{at}/L{k}")).unwrap().transform;
        let want = alone.component(&format!("L{k}")).unwrap().transform * *frame;
        assert!(
            got.approx_eq(&want, 1e-6, 1e-9),
            "{at}/L{k}: {got} vs {want}"
        );
    }
    let got = doc.robot(&format!("{at}/Arm")).unwrap().tcp();
    let want = alone.robot("Arm").unwrap().tcp() * *frame;
    assert!(
        got.approx_eq(&want, 1e-6, 1e-9),
        "{at} TCP: {got} vs {want}"
    );
}

fn deg(v: f64) -> f64 {
    v.to_radians()
}

fn sub_files(top: &Path) -> Vec<(String, Vec<u8>)> {
    let dir = top.parent().unwrap();
    ["sub/cell.yaml", "sub/line.yaml", "top.yaml"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(dir.join(f)).unwrap()))
        .collect()
}

#[test]
fn a_robot_inside_is_named_placed_and_driven_through_the_levels() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let mut alone = Document::open(&top.parent().unwrap().join("sub/cell.yaml")).unwrap();
    let names: Vec<&str> = doc.robots().iter().map(|r| r.name()).collect();
    assert_eq!(names, ["Line-1/Cell-1/Arm", "Line-1/Cell-2/Arm"]);
    let [f1, f2] = frames();
    assert_placed(&doc, "Line-1/Cell-1", &alone, &f1);
    assert_placed(&doc, "Line-1/Cell-2", &alone, &f2);
    // the base is the cell's, placed: (100, 50, 0) in Cell-1 is (1000−50, 200+100, 750)
    let base = doc.robot("Line-1/Cell-1/Arm").unwrap().robot().base();
    assert!((base.translation() - Vec3::new(950.0, 300.0, 750.0)).norm() < 1e-9);
    // its joints and dimensions, named inside
    let d = doc.dimension("D1@Line-1/Cell-1/角度2@Arm").unwrap();
    assert!((d.document_value() + 20.0).abs() < 1e-9, "{}", d.value);
    assert!(doc
        .dimensions()
        .contains(&"D1@Line-1/Cell-2/角度6@Arm".to_string()));
    // a dimension drives one instance's links; the other keeps its own
    doc.set_dimension("D1@Line-1/Cell-1/角度2@Arm", deg(35.0))
        .unwrap();
    let original = alone.clone();
    alone.set_dimension("D1@角度2@Arm", deg(35.0)).unwrap();
    assert_placed(&doc, "Line-1/Cell-1", &alone, &f1);
    assert_placed(&doc, "Line-1/Cell-2", &original, &f2);
    // so do the joints, set by index as any robot's
    let q = [
        deg(-30.0),
        deg(10.0),
        deg(20.0),
        deg(40.0),
        deg(-60.0),
        deg(90.0),
    ];
    let i = doc.robot_index("Line-1/Cell-2/Arm").unwrap();
    doc.set_robot_joints(i, &q).unwrap();
    alone.set_robot_joints(0, &q).unwrap();
    assert_placed(&doc, "Line-1/Cell-2", &alone, &f2);
    // a limit is the robot's: refused, naming the robot by its full name
    let e = doc
        .set_dimension("D1@Line-1/Cell-1/角度5@Arm", deg(170.0))
        .unwrap_err();
    assert!(e.to_string().contains("Line-1/Cell-1/Arm"), "{e}");
}

#[test]
fn a_robot_inside_moves_with_its_sub_assembly() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let before = sub_files(&top);
    let tcp = doc.robot("Line-1/Cell-2/Arm").unwrap().tcp();
    let line = doc.sub_assembly("Line-1").unwrap().transform;
    let moved = Transform::from_translation(Vec3::new(0.0, 500.0, 0.0));
    doc.set_sub_assembly_transform("Line-1", moved).unwrap();
    let motion = line.inverse() * moved;
    let now = doc.robot("Line-1/Cell-2/Arm").unwrap().tcp();
    assert!(now.approx_eq(&(tcp * motion), 1e-6, 1e-9), "{now}");
    // a rebuild keeps the links on the moved robot
    doc.rebuild().unwrap();
    let alone = Document::open(&top.parent().unwrap().join("sub/cell.yaml")).unwrap();
    let cell2 = doc.sub_assembly("Line-1/Cell-2").unwrap().transform;
    assert_placed(&doc, "Line-1/Cell-2", &alone, &cell2);
    // saved: only the top document's entry changed; the cell's base stays in its frame
    doc.save().unwrap();
    let after = sub_files(&top);
    assert_eq!(after[..2], before[..2], "sub-documents rewritten");
    let back = Document::open(&top).unwrap();
    let again = back.robot("Line-1/Cell-2/Arm").unwrap().tcp();
    assert!(again.approx_eq(&now, 1e-6, 1e-9), "{again} vs {now}");
}

#[test]
fn a_robot_inside_is_saved_to_its_own_file_without_loss() {
    let (_dir, top) = plain();
    let dir = top.parent().unwrap().to_path_buf();
    let written = sub_files(&top);
    let mut doc = Document::open(&top).unwrap();
    // unchanged: no sub-document rewritten, and the top document names no robot
    doc.save().unwrap();
    let before = sub_files(&top);
    assert_eq!(before[..2], written[..2]);
    let text = std::fs::read_to_string(&top).unwrap();
    assert!(
        !text.contains("robots") && !text.contains("L3"),
        "flattened into the top:\n{text}"
    );
    // one instance changed: cell.yaml cannot hold both
    let q = [
        deg(5.0),
        deg(-15.0),
        deg(25.0),
        deg(35.0),
        deg(45.0),
        deg(55.0),
    ];
    let i1 = doc.robot_index("Line-1/Cell-1/Arm").unwrap();
    let i2 = doc.robot_index("Line-1/Cell-2/Arm").unwrap();
    doc.set_robot_joints(i1, &q).unwrap();
    let e = doc.save().unwrap_err().to_string();
    assert!(e.contains("Cell-1") && e.contains("Cell-2"), "{e}");
    assert_eq!(sub_files(&top), before, "a refused save wrote");
    // both: written once, to cell.yaml, in its own names and frame
    doc.set_robot_joints(i2, &q).unwrap();
    doc.save().unwrap();
    let cell = std::fs::read_to_string(dir.join("sub/cell.yaml")).unwrap();
    assert!(
        cell.contains("name: Arm") && !cell.contains("Cell-1") && !cell.contains("Line-1"),
        "{cell}"
    );
    assert!(
        cell.contains("- [100.0, 50.0, 0.0, 1.0]") || cell.contains("- [100, 50, 0, 1]"),
        "the base left the cell's frame:\n{cell}"
    );
    assert!(cell.contains("component: L3"), "{cell}");
    assert!(cell.contains("description: a robot cell"), "{cell}");
    assert_eq!(
        std::fs::read(dir.join("sub/line.yaml")).unwrap(),
        before[1].1,
        "line.yaml holds no robot and did not change"
    );
    let back = Document::open(&top).unwrap();
    for r in ["Line-1/Cell-1/Arm", "Line-1/Cell-2/Arm"] {
        let j = back.robot(r).unwrap().joints();
        for (a, b) in j.iter().zip(&q) {
            assert!((a - b).abs() < 1e-9, "{r}: {j:?}");
        }
    }
    let alone = Document::open(&dir.join("sub/cell.yaml")).unwrap();
    let [f1, f2] = frames();
    assert_placed(&back, "Line-1/Cell-1", &alone, &f1);
    assert_placed(&back, "Line-1/Cell-2", &alone, &f2);
    // save_as into another folder keeps the sub-documents' own relative paths
    std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
    let mut doc = back;
    doc.save_as(&dir.join("elsewhere/top2.yaml")).unwrap();
    let again = Document::open(&dir.join("elsewhere/top2.yaml")).unwrap();
    assert_eq!(again.robots().len(), 2);
    let cell_now = std::fs::read_to_string(dir.join("sub/cell.yaml")).unwrap();
    assert!(cell_now.contains("stl: ../meshes/cube.stl"), "{cell_now}");
}

#[test]
fn equations_inside_drive_the_robot_inside() {
    let (_dir, top) = project(|which, t| match which {
        "cell" => {
            format!("{t}equations:\n- '\"Reach\" = 12'\n- '\"D1@角度3@Arm\" = 2 * \"Reach\"'\n")
        }
        _ => t.to_string(),
    });
    let mut doc = Document::open(&top).unwrap();
    for at in ["Line-1/Cell-1", "Line-1/Cell-2"] {
        let d = doc.dimension(&format!("D1@{at}/角度3@Arm")).unwrap();
        assert!(
            (d.document_value() - 24.0).abs() < 1e-9,
            "{at}: {}",
            d.value
        );
    }
    // driven: the joint is the equation's
    let i = doc.robot_index("Line-1/Cell-1/Arm").unwrap();
    let mut q = doc.robot("Line-1/Cell-1/Arm").unwrap().joints().to_vec();
    q[2] = deg(5.0);
    let e = doc.set_robot_joints(i, &q).unwrap_err();
    assert!(matches!(e, DocumentError::DrivenByEquation { .. }), "{e}");
    // the global variable inside drives it
    doc.set_global_variable("Line-1/Cell-1/Reach", 20.0)
        .unwrap();
    let d = doc.dimension("D1@Line-1/Cell-1/角度3@Arm").unwrap();
    assert!((d.document_value() - 40.0).abs() < 1e-9);
}

#[test]
fn what_a_sub_document_robot_owns_is_refused_elsewhere() {
    // a robot of the assembly named inside the sub-document
    let robot = "robots:\n- name: Line-1/Arm\n  catalog: nachi_mz07\n";
    let (_dir, top) = project(|which, t| match which {
        "top" => format!("{t}{robot}"),
        _ => t.to_string(),
    });
    let e = Document::open(&top).unwrap_err();
    let text = std::fs::read_to_string(&top).unwrap();
    let at = e.location().unwrap_or_else(|| panic!("not located: {e}"));
    assert_eq!(
        at.line,
        Some(text.lines().position(|l| l.contains("Line-1/Arm")).unwrap() + 1),
        "{e}"
    );
    assert!(e.to_string().contains("sub-document"), "{e}");
    // a robot of the assembly displaying a link of the robot inside
    let other = "robots:\n- name: Other\n  catalog: nachi_mz07\n  links:\n  - {component: Line-1/Cell-1/L0}\n";
    let (_dir, top) = project(|which, t| match which {
        "top" => format!("{t}{other}"),
        _ => t.to_string(),
    });
    let e = Document::open(&top).unwrap_err().to_string();
    assert!(
        e.contains("Line-1/Cell-1/L0") && e.contains("Line-1/Cell-1/Arm"),
        "{e}"
    );
    // added through the API inside a sub-document
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let e = doc
        .add_robot("Line-1/Cell-1/Extra", &Catalog::NachiMz07.robot(), None)
        .unwrap_err();
    assert!(
        matches!(e, DocumentError::RobotInSubDocument { .. }),
        "{e:?}"
    );
    assert_eq!(doc.robots().len(), 2);
    // a bad robot inside is located in its own file
    let (_dir, top) = project(|which, t| match which {
        "cell" => t.replace("catalog: nachi_mz07", "catalog: nachi_mz7"),
        _ => t.to_string(),
    });
    let e = Document::open(&top).unwrap_err();
    let at = e.location().unwrap_or_else(|| panic!("not located: {e}"));
    assert!(at.path.ends_with("sub/cell.yaml"), "{e}");
    assert_eq!(
        at.line,
        Some(CELL.lines().position(|l| l.contains("catalog:")).unwrap() + 1),
        "{e}"
    );
}

/// A `urdf:` arm inside: its generated link components are named inside, follow the
/// arm, and a save writes the joints back to the sub-document without the generated
/// parts.
#[test]
fn a_urdf_robot_inside_keeps_its_generated_links_out_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    // the URDF names its meshes `package://fitup_arm6/urdf/meshes/…`: the package is
    // the folder above `urdf/`, as in the repository
    common::copy_tree(&common::repo().join("models/urdf"), &p.join("cell/urdf"));
    std::fs::write(
        p.join("top.yaml"),
        "parts: {}\nassemblies:\n- name: Cell-1\n  file: cell/urdf/arm6_cell.yaml\n  transform:\n  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 500, 1]\ncomponents: []\n",
    )
    .unwrap();
    let sub = p.join("cell/urdf/arm6_cell.yaml");
    let mut alone = Document::open(&sub).unwrap();
    let mut doc = Document::open(&p.join("top.yaml")).unwrap();
    let frame = Transform::from_translation(Vec3::new(0.0, 0.0, 500.0));
    let links: Vec<String> = alone
        .components()
        .iter()
        .filter(|c| c.name.starts_with("arm6:"))
        .map(|c| c.name.clone())
        .collect();
    assert!(links.len() >= 6, "{links:?}");
    let i = doc.robot_index("Cell-1/arm6").unwrap();
    let q = vec![0.3, -0.4, 0.5, 0.2, -0.6, 0.7];
    doc.set_robot_joints(i, &q).unwrap();
    alone.set_robot_joints(0, &q).unwrap();
    for l in &links {
        let got = doc.component(&format!("Cell-1/{l}")).unwrap().transform;
        let want = alone.component(l).unwrap().transform * frame;
        assert!(got.approx_eq(&want, 1e-6, 1e-9), "{l}: {got} vs {want}");
    }
    doc.save().unwrap();
    let text = std::fs::read_to_string(&sub).unwrap();
    assert!(
        text.contains("urdf: fitup_arm6.urdf") && !text.contains("arm6:"),
        "{text}"
    );
    let back = Document::open(&p.join("top.yaml")).unwrap();
    let j = back.robot("Cell-1/arm6").unwrap().joints();
    for (a, b) in j.iter().zip(&q) {
        assert!((a - b).abs() < 1e-9, "{j:?}");
    }
    assert_eq!(back.components().len(), doc.components().len());
}

/// From a script (`fitup run`) and the CLI: the robot inside is reached by its full
/// name, its joints set, the document saved back into the cell's file.
#[test]
fn scripts_drive_a_robot_inside() {
    let (dir, top) = plain();
    let script = r#"
let doc = open_doc("top.yaml");
let names = doc.robots();
assert(names.contains("Line-1/Cell-2/Arm"), `robots: ${names}`);
for at in ["Line-1/Cell-1", "Line-1/Cell-2"] {
    let r = doc.robot(at + "/Arm");
    assert(r.name == at + "/Arm", "name");
    r.joints = [0.0, 10.0, 20.0, 0.0, 30.0, 0.0];
    let d = doc.dimension("D1@" + at + "/角度3@Arm");
    assert(d.value > 19.999 && d.value < 20.001, `joint 3: ${d.value}`);
}
let d5 = doc.dimension("D1@Line-1/Cell-2/角度5@Arm");
d5.value = 30.0;
let t = doc.robot("Line-1/Cell-1/Arm").tcp.translation;
print(`${t[0]},${t[1]},${t[2]}`);
doc.save();
"#;
    std::fs::write(dir.path().join("s.rhai"), script).unwrap();
    let out = common::run_in(dir.path(), &["run", "s.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let cell = std::fs::read_to_string(dir.path().join("sub/cell.yaml")).unwrap();
    let alone = Document::open(&dir.path().join("sub/cell.yaml")).unwrap();
    let j = alone.robot("Arm").unwrap().joints().to_vec();
    let want = [0.0, 10.0, 20.0, 0.0, 30.0, 0.0].map(deg);
    for (a, b) in j.iter().zip(&want) {
        assert!((a - b).abs() < 1e-9, "{j:?}\n{cell}");
    }
    // the TCP printed is the cell's own, placed
    let want = (alone.robot("Arm").unwrap().tcp() * frames()[0]).translation();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let got = common::last_csv_numbers(&stdout);
    assert!(
        (Vec3::new(got[0], got[1], got[2]) - want).norm() < 1e-6,
        "{stdout} vs {want}"
    );
    // `fitup check` reads the assembly with its robots inside
    let out = common::run_in(dir.path(), &["check", "top.yaml"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let _ = top;
}
