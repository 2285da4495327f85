//! Sub-assemblies that are other documents (issue 37): `assemblies: - {name, file}`
//! loads another fitup document inside the assembly (as a `.sldasm` inside an
//! assembly): components, mates and poses composed through the levels, full names
//! through the levels, circles, depth and size refused where they happen, saved
//! without flattening, the sub-document rewritten only when a script changed it; and
//! whole sub-assemblies suppressed. Every project here is generated in code.

use crate::common;
use fitup::document::{Document, DocumentError};
use fitup::math::{Transform, Vec3};
use std::path::{Path, PathBuf};

/// An ASCII STL cube of edge `s` mm from the origin.
pub(crate) fn cube(s: f64) -> String {
    let v = |x: f64, y: f64, z: f64| format!("vertex {} {} {}\n", x * s, y * s, z * s);
    let quads: [[(f64, f64, f64); 4]; 6] = [
        [(0., 0., 0.), (0., 1., 0.), (1., 1., 0.), (1., 0., 0.)],
        [(0., 0., 1.), (1., 0., 1.), (1., 1., 1.), (0., 1., 1.)],
        [(0., 0., 0.), (1., 0., 0.), (1., 0., 1.), (0., 0., 1.)],
        [(0., 1., 0.), (0., 1., 1.), (1., 1., 1.), (1., 1., 0.)],
        [(0., 0., 0.), (0., 0., 1.), (0., 1., 1.), (0., 1., 0.)],
        [(1., 0., 0.), (1., 1., 0.), (1., 1., 1.), (1., 0., 1.)],
    ];
    let mut out = String::from("solid c\n");
    for q in quads {
        for t in [[0, 1, 2], [0, 2, 3]] {
            out += "facet normal 0 0 0\nouter loop\n";
            for i in t {
                let (x, y, z) = q[i];
                out += &v(x, y, z);
            }
            out += "endloop\nendfacet\n";
        }
    }
    out + "endsolid c\n"
}

const AXLE: &str = "\
description: an axle, its own document
parts:
  rod:
    stl: ../meshes/cube.stl
  wheel:
    stl: ../meshes/cube.stl
components:
- name: Rod-1
  part: rod
  fixed: true
- name: Wheel-1
  part: wheel
  transform:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [30, 0, 0, 1]
- name: Wheel-2
  part: wheel
  transform:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [-30, 0, 0, 1]
mates:
- name: Gap
  type: distance
  entities: [Rod-1/right, Wheel-1/right]
  value: 30
  aligned: true
";

const CART: &str = "\
parts:
  deck:
    stl: ../meshes/cube.stl
assemblies:
- name: Axle-1
  file: axle.yaml
  transform:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [0, 100, 0, 1]
- name: Axle-2
  file: axle.yaml
  transform:
  - [0, 1, 0, 0]
  - [-1, 0, 0, 0]
  - [0, 0, 1, 0]
  - [0, 300, 0, 1]
components:
- name: Deck-1
  part: deck
";

const TOP: &str = "\
parts:
  table:
    stl: meshes/cube.stl
assemblies:
- name: Cart-1
  file: sub/cart.yaml
  transform:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [500, 0, 750, 1]
components:
- name: table
  part: table
  fixed: true
";

/// A project: `top.yaml` holding `sub/cart.yaml` (Cart-1) holding `sub/axle.yaml`
/// twice (Axle-1, Axle-2), with `edit` applied to each file's text.
fn project(edit: impl Fn(&str, &str) -> String) -> (tempfile::TempDir, PathBuf) {
    nested_project([("axle", AXLE), ("cart", CART), ("top", TOP)], edit)
}

/// A project of three documents, `sub/{inner}.yaml` held by `sub/{middle}.yaml`
/// held by `top.yaml` (`files`: innermost first, each a name and its text), with
/// `edit` applied to each text (given the name) and `meshes/cube.stl` beside.
pub(crate) fn nested_project(
    files: [(&str, &str); 3],
    edit: impl Fn(&str, &str) -> String,
) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(p.join("meshes")).unwrap();
    std::fs::create_dir_all(p.join("sub")).unwrap();
    std::fs::write(p.join("meshes/cube.stl"), cube(10.0)).unwrap();
    let [inner, middle, (top_name, top_text)] = files;
    for (name, text) in [inner, middle] {
        std::fs::write(p.join(format!("sub/{name}.yaml")), edit(name, text)).unwrap();
    }
    std::fs::write(p.join("top.yaml"), edit(top_name, top_text)).unwrap();
    let top = p.join("top.yaml");
    (dir, top)
}

fn plain() -> (tempfile::TempDir, PathBuf) {
    project(|_, t| t.to_string())
}

fn pos(doc: &Document, name: &str) -> Vec3 {
    doc.component(name).unwrap().transform.translation()
}

fn located(e: &DocumentError) -> (String, usize) {
    let at = e.location().unwrap_or_else(|| panic!("not located: {e}"));
    (
        at.path.file_name().unwrap().to_string_lossy().into_owned(),
        at.line.unwrap_or(0),
    )
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn components_mates_and_poses_come_through_the_levels() {
    let (_dir, top) = plain();
    let doc = Document::open(&top).unwrap();
    // 1 table + 1 deck + 2 axles × 3
    assert_eq!(doc.components().len(), 8);
    assert_eq!(
        doc.children(None).unwrap(),
        ["Cart-1", "table"],
        "the top level"
    );
    assert_eq!(
        doc.children(Some("Cart-1")).unwrap(),
        ["Cart-1/Axle-1", "Cart-1/Axle-2", "Cart-1/Deck-1"]
    );
    assert_eq!(
        doc.children(Some("Cart-1/Axle-2")).unwrap(),
        [
            "Cart-1/Axle-2/Rod-1",
            "Cart-1/Axle-2/Wheel-1",
            "Cart-1/Axle-2/Wheel-2"
        ]
    );
    // poses: local * axle * cart
    let cart = Transform::from_translation(Vec3::new(500.0, 0.0, 750.0));
    let axle2 = Transform::from_matrix(&[
        [0., 1., 0., 0.],
        [-1., 0., 0., 0.],
        [0., 0., 1., 0.],
        [0., 300., 0., 1.],
    ])
    .unwrap();
    let wheel = Transform::from_translation(Vec3::new(30.0, 0.0, 0.0));
    let expected = wheel * axle2 * cart;
    let got = doc.component("Cart-1/Axle-2/Wheel-1").unwrap().transform;
    assert!(got.approx_eq(&expected, 1e-9, 1e-12), "{got} vs {expected}");
    assert!((pos(&doc, "Cart-1/Axle-2/Wheel-1") - Vec3::new(500.0, 330.0, 750.0)).norm() < 1e-9);
    assert!((pos(&doc, "Cart-1/Axle-1/Wheel-1") - Vec3::new(530.0, 100.0, 750.0)).norm() < 1e-9);
    // the sub-document's mates, once per instance, with their dimensions
    assert!(doc.mate("Cart-1/Axle-1/Gap").is_ok());
    assert!(doc.mate("Cart-1/Axle-2/Gap").is_ok());
    let d = doc.dimension("D1@Cart-1/Axle-2/Gap").unwrap();
    assert!((d.document_value() - 30.0).abs() < 1e-9);
    // parts are named inside the sub-assembly that brought them
    assert_eq!(
        doc.component("Cart-1/Axle-2/Wheel-1").unwrap().part,
        "Cart-1/Axle-2/wheel"
    );
    let sa = doc.sub_assembly("Cart-1/Axle-2").unwrap();
    assert_eq!(sa.file.as_ref().unwrap().file, "axle.yaml");
    assert_eq!(
        doc.parent_of("Cart-1/Axle-2/Rod-1").unwrap().as_deref(),
        Some("Cart-1/Axle-2")
    );
    // and the files are the document's sources (watch mode rereads on their change)
    let sources = doc.source_files();
    assert!(sources.iter().any(|p| p.ends_with("sub/axle.yaml")));
    assert!(sources.iter().any(|p| p.ends_with("sub/cart.yaml")));
}

#[test]
fn a_dimension_inside_drives_the_sub_documents_components() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    doc.set_dimension("D1@Cart-1/Axle-1/Gap", 45.0).unwrap();
    assert!((pos(&doc, "Cart-1/Axle-1/Wheel-1") - Vec3::new(545.0, 100.0, 750.0)).norm() < 1e-6);
    // the other instance keeps its own
    assert!((pos(&doc, "Cart-1/Axle-2/Wheel-1") - Vec3::new(500.0, 330.0, 750.0)).norm() < 1e-6);
}

fn snapshot(top: &Path) -> Vec<(String, Vec<u8>, std::time::SystemTime)> {
    let dir = top.parent().unwrap();
    ["sub/axle.yaml", "sub/cart.yaml"]
        .iter()
        .map(|f| {
            let p = dir.join(f);
            (
                f.to_string(),
                std::fs::read(&p).unwrap(),
                std::fs::metadata(&p).unwrap().modified().unwrap(),
            )
        })
        .collect()
}

#[test]
fn saved_without_flattening_and_sub_documents_left_alone() {
    let (_dir, top) = plain();
    let before = snapshot(&top);
    let mut doc = Document::open(&top).unwrap();
    let moved = Transform::from_translation(Vec3::new(600.0, 50.0, 750.0));
    doc.set_sub_assembly_transform("Cart-1", moved).unwrap();
    doc.save().unwrap();
    let text = std::fs::read_to_string(&top).unwrap();
    assert!(text.contains("file: sub/cart.yaml"), "{text}");
    for inner in ["Wheel", "Deck", "Axle", "Gap", "deck", "wheel"] {
        assert!(!text.contains(inner), "flattened: {inner} in\n{text}");
    }
    assert_eq!(snapshot(&top), before, "sub-documents rewritten");
    assert!(doc.saved_sub_documents().is_empty());
    let back = Document::open(&top).unwrap();
    assert!((pos(&back, "Cart-1/Axle-2/Wheel-1") - Vec3::new(600.0, 380.0, 750.0)).norm() < 1e-9);
    assert_eq!(back.components().len(), 8);
}

#[test]
fn a_change_inside_is_written_to_the_sub_document_only() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let axle_before = std::fs::read(top.parent().unwrap().join("sub/axle.yaml")).unwrap();
    doc.set_suppressed("Cart-1/Deck-1", true).unwrap();
    doc.save().unwrap();
    let cart = std::fs::read_to_string(top.parent().unwrap().join("sub/cart.yaml")).unwrap();
    assert!(cart.contains("suppressed: true"), "{cart}");
    assert!(cart.contains("file: axle.yaml"), "{cart}");
    assert!(
        !cart.contains("Wheel"),
        "axle flattened into the cart:\n{cart}"
    );
    let top_text = std::fs::read_to_string(&top).unwrap();
    assert!(
        !top_text.contains("Deck"),
        "flattened into the top:\n{top_text}"
    );
    assert_eq!(
        std::fs::read(top.parent().unwrap().join("sub/axle.yaml")).unwrap(),
        axle_before
    );
    assert_eq!(doc.saved_sub_documents().len(), 1);
    let back = Document::open(&top).unwrap();
    assert!(back.component("Cart-1/Deck-1").unwrap().is_suppressed());
}

#[test]
fn two_instances_of_one_file_changed_differently_are_refused() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let axle = top.parent().unwrap().join("sub/axle.yaml");
    let before = std::fs::read(&axle).unwrap();
    doc.set_dimension("D1@Cart-1/Axle-1/Gap", 45.0).unwrap();
    let e = doc.save().unwrap_err().to_string();
    assert!(
        e.contains("Axle-1") && e.contains("Axle-2") && e.contains("changed differently"),
        "{e}"
    );
    assert_eq!(std::fs::read(&axle).unwrap(), before);
    // the same change in both: one file, written once
    doc.set_dimension("D1@Cart-1/Axle-2/Gap", 45.0).unwrap();
    doc.save().unwrap();
    let text = std::fs::read_to_string(&axle).unwrap();
    assert!(text.contains("value: 45"), "{text}");
    assert!(text.contains("description: an axle"), "{text}");
    let back = Document::open(&top).unwrap();
    assert!(
        (back
            .dimension("D1@Cart-1/Axle-2/Gap")
            .unwrap()
            .document_value()
            - 45.0)
            .abs()
            < 1e-9
    );
    assert!((pos(&back, "Cart-1/Axle-1/Wheel-1") - Vec3::new(545.0, 100.0, 750.0)).norm() < 1e-6);
}

#[test]
fn a_sub_document_changed_on_disk_is_not_overwritten() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let cart = top.parent().unwrap().join("sub/cart.yaml");
    let theirs = format!("{CART}# another writer's edit\n");
    std::fs::write(&cart, &theirs).unwrap();
    doc.set_suppressed("Cart-1/Deck-1", true).unwrap();
    let e = doc.save().unwrap_err().to_string();
    assert!(e.contains("changed on disk"), "{e}");
    assert_eq!(std::fs::read_to_string(&cart).unwrap(), theirs);
}

#[test]
fn a_circle_of_documents_is_refused_at_its_file_line() {
    let (_dir, top) = project(|which, t| {
        if which == "axle" {
            t.replace(
                "components:",
                "assemblies:\n- name: Back-1\n  file: ../top.yaml\ncomponents:",
            )
        } else {
            t.to_string()
        }
    });
    let e = Document::open(&top).unwrap_err();
    let (file, line) = located(&e);
    let axle = std::fs::read_to_string(top.parent().unwrap().join("sub/axle.yaml")).unwrap();
    assert_eq!(file, "axle.yaml", "{e}");
    assert_eq!(line, line_of(&axle, "file: ../top.yaml"), "{e}");
    let m = e.to_string();
    assert!(
        m.contains("holds itself")
            && m.contains("top.yaml → sub/cart.yaml → sub/axle.yaml → top.yaml"),
        "{m}"
    );
    // a file holding itself directly
    let (_dir, top) = project(|which, t| {
        if which == "top" {
            t.replace("file: sub/cart.yaml", "file: top.yaml")
        } else {
            t.to_string()
        }
    });
    let e = Document::open(&top).unwrap_err();
    assert_eq!(located(&e).0, "top.yaml");
    assert!(e.to_string().contains("holds itself"), "{e}");
}

/// A chain of `n` documents `d0.yaml` → `d1.yaml` → …, each holding one cube, the
/// last one's mesh `last_mesh`.
fn chain(n: usize, per_level: usize, last_mesh: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::write(p.join("cube.stl"), cube(1.0)).unwrap();
    for i in 0..n {
        let mesh = if i + 1 == n { last_mesh } else { "cube.stl" };
        let mut t = format!("parts:\n  c:\n    stl: {mesh}\n");
        if i + 1 < n {
            t += "assemblies:\n";
            for k in 0..per_level {
                t += &format!("- name: L{k}\n  file: d{}.yaml\n", i + 1);
            }
        }
        t += "components:\n- name: C-1\n  part: c\n- name: C-2\n  part: c\n";
        std::fs::write(p.join(format!("d{i}.yaml")), t).unwrap();
    }
    let top = p.join("d0.yaml");
    (dir, top)
}

#[test]
fn depth_and_size_are_bounded_before_any_mesh_is_read() {
    use fitup::document::subdoc::{MAX_DEPTH, MAX_TOTAL_COMPONENTS};
    // a chain as deep as allowed loads, names through every level
    let (_dir, top) = chain(MAX_DEPTH, 1, "cube.stl");
    let doc = Document::open(&top).unwrap();
    let deepest = format!("{}C-1", "L0/".repeat(MAX_DEPTH - 1));
    assert!(doc.component(&deepest).is_ok(), "{deepest}");
    assert_eq!(doc.components().len(), 2 * MAX_DEPTH);
    // one level more is refused at the `file:` line that goes too deep
    let (_dir, top) = chain(MAX_DEPTH + 1, 1, "cube.stl");
    let e = Document::open(&top).unwrap_err();
    assert_eq!(located(&e), (format!("d{}.yaml", MAX_DEPTH - 1), 6), "{e}");
    assert!(e.to_string().contains("levels"), "{e}");
    // 8 levels of 10 instances each: 2·(10^8 − 1)/9 components, refused by counting
    // the files' text — the last level's mesh does not even exist, and is never read
    let (_dir, top) = chain(8, 10, "missing.stl");
    let e = Document::open(&top).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains(&MAX_TOTAL_COMPONENTS.to_string()) && !m.contains("missing.stl"),
        "{m}"
    );
    assert!(e.location().is_some(), "{m}");
}

#[test]
fn what_a_sub_document_holds_cannot_be_written_in_the_assembly() {
    let (_dir, top) = project(|which, t| {
        if which == "top" {
            format!("{t}- name: Cart-1/Extra-1\n  part: table\n")
        } else {
            t.to_string()
        }
    });
    let e = Document::open(&top).unwrap_err();
    let text = std::fs::read_to_string(&top).unwrap();
    assert_eq!(
        located(&e),
        ("top.yaml".into(), line_of(&text, "Cart-1/Extra-1")),
        "{e}"
    );
    assert!(e.to_string().contains("sub/cart.yaml"), "{e}");
}

#[test]
fn a_suppressed_sub_assembly_suppresses_everything_it_holds() {
    let (_dir, top) = plain();
    let mut doc = Document::open(&top).unwrap();
    let full = doc.assembly_aabb().unwrap();
    doc.set_sub_assembly_suppressed("Cart-1/Axle-2", true)
        .unwrap();
    assert!(doc.sub_assembly_suppressed("Cart-1/Axle-2").unwrap());
    assert!(!doc.sub_assembly_suppressed("Cart-1").unwrap());
    for c in ["Rod-1", "Wheel-1", "Wheel-2"] {
        let c = doc.component(&format!("Cart-1/Axle-2/{c}")).unwrap();
        assert!(c.is_suppressed() && !c.suppressed, "{}", c.name);
    }
    assert!(!doc
        .component("Cart-1/Axle-1/Wheel-1")
        .unwrap()
        .is_suppressed());
    // its mates are inactive, the box leaves it out (Axle-2 reached furthest in +y)
    assert!(!doc.mate_active(doc.mate("Cart-1/Axle-2/Gap").unwrap()));
    assert!(doc.assembly_aabb().unwrap().hi.y < full.hi.y - 1.0);
    // saved where the entry is written: Axle-2 is an entry of cart.yaml
    doc.save().unwrap();
    let cart = std::fs::read_to_string(top.parent().unwrap().join("sub/cart.yaml")).unwrap();
    assert!(cart.contains("suppressed: true"), "{cart}");
    let mut back = Document::open(&top).unwrap();
    assert!(back
        .component("Cart-1/Axle-2/Wheel-1")
        .unwrap()
        .is_suppressed());
    // suppressing the cart reaches every level; unsuppressing it keeps Axle-2's own
    back.set_sub_assembly_suppressed("Cart-1", true).unwrap();
    assert!(back
        .component("Cart-1/Axle-1/Wheel-1")
        .unwrap()
        .is_suppressed());
    assert!(back.component("Cart-1/Deck-1").unwrap().is_suppressed());
    assert!(back.sub_assembly_suppressed("Cart-1/Axle-1").unwrap());
    back.set_sub_assembly_suppressed("Cart-1", false).unwrap();
    assert!(!back
        .component("Cart-1/Axle-1/Wheel-1")
        .unwrap()
        .is_suppressed());
    assert!(back
        .component("Cart-1/Axle-2/Wheel-1")
        .unwrap()
        .is_suppressed());
}

#[test]
fn a_group_sub_assembly_suppressed_is_saved_in_the_document() {
    let text = std::fs::read_to_string(common::repo().join("models/solidworks/cart.yaml")).unwrap();
    let dir = common::project();
    std::fs::create_dir_all(dir.path().join("models/solidworks")).unwrap();
    let path = dir.path().join("models/solidworks/cart.yaml");
    std::fs::write(&path, text).unwrap();
    let mut doc = Document::open(&path).unwrap();
    doc.set_sub_assembly_suppressed("Cart-1/Axle-1", true)
        .unwrap();
    doc.save().unwrap();
    let back = Document::open(&path).unwrap();
    assert!(back.sub_assembly_suppressed("Cart-1/Axle-1").unwrap());
    assert!(back
        .component("Cart-1/Axle-1/Wheel-2")
        .unwrap()
        .is_suppressed());
    assert!(!back.component("Cart-1/Axle-1/Wheel-2").unwrap().suppressed);
    assert!(!back
        .component("Cart-1/Axle-2/Wheel-2")
        .unwrap()
        .is_suppressed());
}

#[test]
fn scripts_read_files_and_suppress_sub_assemblies() {
    let (dir, _top) = plain();
    let script = r#"
let doc = open_doc("top.yaml");
assert(doc.sub_assembly_file("Cart-1") == "sub/cart.yaml", "file");
assert(doc.sub_assembly_file("Cart-1/Axle-2") == "axle.yaml", "nested file");
assert(doc.component("Cart-1/Axle-2/Wheel-1").name == "Cart-1/Axle-2/Wheel-1", "full name");
assert(!doc.sub_assembly_suppressed("Cart-1/Axle-2"), "not yet");
doc.set_sub_assembly_suppressed("Cart-1/Axle-2", true);
assert(doc.component("Cart-1/Axle-2/Rod-1").suppressed, "held suppressed");
doc.save();
print("ok");
"#;
    std::fs::write(dir.path().join("s.rhai"), script).unwrap();
    let out = common::run_in(dir.path(), &["run", "s.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let cart = std::fs::read_to_string(dir.path().join("sub/cart.yaml")).unwrap();
    assert!(cart.contains("suppressed: true"), "{cart}");
}

/// Issue 37: a sub-document may hold equations (they were refused): its global
/// variables and dimensions are named inside the sub-assembly (`"Cart-1/Axle-1/Spread"`,
/// `"D1@Cart-1/Axle-1/Gap"`), each instance evaluates its own, the assembly's
/// equations may use them, a save writes each equation back to its own file with its
/// own names, and a bad one is located in its own file.
#[test]
fn equations_inside_sub_documents() {
    let with = |which: &str, t: &str| match which {
        "axle" => format!("{t}equations:\n- '\"Spread\" = 2'\n- '\"D1@Gap\" = 20 * \"Spread\"'\n"),
        "cart" => format!("{t}equations:\n- '\"Half\" = \"Axle-1/Spread\" / 2'\n"),
        _ => t.to_string(),
    };
    let (_dir, top) = project(with);
    let before = snapshot(&top);
    let mut doc = Document::open(&top).unwrap();
    assert_eq!(doc.global_variable("Cart-1/Axle-1/Spread").unwrap(), 2.0);
    assert_eq!(doc.global_variable("Cart-1/Half").unwrap(), 1.0);
    assert_eq!(doc.dimension("D1@Cart-1/Axle-2/Gap").unwrap().value, 40.0);
    assert!((pos(&doc, "Cart-1/Axle-1/Wheel-1") - Vec3::new(540.0, 100.0, 750.0)).norm() < 1e-6);
    assert!((pos(&doc, "Cart-1/Axle-2/Wheel-1") - Vec3::new(500.0, 340.0, 750.0)).norm() < 1e-6);
    let texts: Vec<String> = doc.equations().iter().map(|e| e.text()).collect();
    assert!(
        texts.contains(&"\"D1@Cart-1/Axle-2/Gap\" = 20 * \"Cart-1/Axle-2/Spread\"".to_string()),
        "{texts:?}"
    );
    // A driven dimension inside is the equation's.
    let e = doc.set_dimension("D1@Cart-1/Axle-1/Gap", 10.0).unwrap_err();
    assert!(matches!(e, DocumentError::DrivenByEquation { .. }), "{e}");
    // Saved unchanged: no file rewritten, nothing flattened into the top.
    doc.save().unwrap();
    assert_eq!(snapshot(&top), before);
    assert!(!std::fs::read_to_string(&top).unwrap().contains("Spread"));
    // The same change in both instances is written to axle.yaml, in its own names.
    doc.set_global_variable("Cart-1/Axle-1/Spread", 2.5)
        .unwrap();
    doc.set_global_variable("Cart-1/Axle-2/Spread", 2.5)
        .unwrap();
    assert_eq!(doc.global_variable("Cart-1/Half").unwrap(), 1.25);
    doc.save().unwrap();
    let dir = top.parent().unwrap();
    let axle = std::fs::read_to_string(dir.join("sub/axle.yaml")).unwrap();
    assert!(axle.contains("'\"Spread\" = 2.5'"), "{axle}");
    assert!(axle.contains("'\"D1@Gap\" = 20 * \"Spread\"'"), "{axle}");
    let cart = std::fs::read_to_string(dir.join("sub/cart.yaml")).unwrap();
    assert!(
        cart.contains("'\"Half\" = \"Axle-1/Spread\" / 2'"),
        "{cart}"
    );
    assert!(!cart.contains("\"D1@"), "{cart}");
    let back = Document::open(&top).unwrap();
    assert_eq!(back.dimension("D1@Cart-1/Axle-1/Gap").unwrap().value, 50.0);
    assert_eq!(back.equations().len(), doc.equations().len());
    // Two instances changed differently are refused, as for any content.
    let mut doc = back;
    doc.set_global_variable("Cart-1/Axle-1/Spread", 3.0)
        .unwrap();
    let e = doc.save().unwrap_err();
    assert!(e.to_string().contains("axle.yaml"), "{e}");

    // A bad equation of a sub-document is located in its own file.
    let (_dir, top) = project(|which, t| {
        if which == "axle" {
            format!("{t}equations:\n- '\"D1@Gap\" = 20 * \"Sprad\"'\n")
        } else {
            t.to_string()
        }
    });
    let e = Document::open(&top).unwrap_err();
    assert_eq!(located(&e), ("axle.yaml".into(), 32), "{e}");
    assert!(e.to_string().contains("Sprad"), "{e}");
}
