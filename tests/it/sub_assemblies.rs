//! Sub-assemblies (issue 37, capability 2): groups of components nested by full name
//! (`Cart-1/Axle-2/Wheel-2`), poses composed through the levels, `children`,
//! `parent`, moves of a whole sub-assembly, saved (poses relative to the parent) and
//! reloaded.

use crate::common;
use fitup::document::Document;
use fitup::math::{Transform, Vec3};
use std::path::PathBuf;

/// A scratch project holding `models/solidworks/cart.yaml` with `edit` applied.
fn cart(edit: impl FnOnce(String) -> String) -> (tempfile::TempDir, PathBuf) {
    let dir = common::project();
    let text = std::fs::read_to_string(common::repo().join("models/solidworks/cart.yaml")).unwrap();
    std::fs::create_dir_all(dir.path().join("models/solidworks")).unwrap();
    let path = dir.path().join("models/solidworks/cart.yaml");
    std::fs::write(&path, edit(text)).unwrap();
    (dir, path)
}

fn at(doc: &Document, name: &str) -> [f64; 3] {
    let t = doc.component(name).unwrap().transform.translation();
    [t.x, t.y, t.z]
}

fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
}

#[test]
fn poses_compose_through_the_levels() {
    let (_dir, path) = cart(|t| t);
    let doc = Document::open(&path).unwrap();
    assert!(near(
        at(&doc, "Cart-1/Axle-1/Wheel-1"),
        [150.0, 170.0, 760.0]
    ));
    assert!(near(
        at(&doc, "Cart-1/Axle-2/Wheel-2"),
        [350.0, 330.0, 760.0]
    ));
    // Axle-2 is turned 90° about Z: its wheels' X axis is the world's Y
    let x = doc
        .component("Cart-1/Axle-2/Wheel-1")
        .unwrap()
        .transform
        .apply_vector(&Vec3::x());
    assert!((x.y - 1.0).abs() < 1e-12, "{x:?}");
    assert_eq!(
        doc.children(None).unwrap(),
        ["Cart-1", "table"],
        "top level: sub-assemblies first"
    );
    assert_eq!(
        doc.children(Some("Cart-1")).unwrap(),
        ["Cart-1/Axle-1", "Cart-1/Axle-2", "Cart-1/Deck-1"]
    );
    assert_eq!(
        doc.parent_of("Cart-1/Axle-2/Wheel-2").unwrap().as_deref(),
        Some("Cart-1/Axle-2")
    );
    assert_eq!(doc.parent_of("Cart-1").unwrap(), None);
    assert!(doc.parent_of("Cart-9").is_err());
    let local = doc.local_transform("Cart-1/Axle-2/Wheel-2").unwrap();
    assert!(local.approx_eq(
        &Transform::from_translation(Vec3::new(180.0, 0.0, 0.0)),
        1e-9,
        1e-12
    ));
}

#[test]
fn a_sub_assembly_moves_what_it_holds_and_saves_relative_poses() {
    let (_dir, path) = cart(|t| t);
    let mut doc = Document::open(&path).unwrap();
    let cart = doc.sub_assembly("Cart-1").unwrap().transform;
    let turn = Transform::from_parts(
        Vec3::zeros(),
        nalgebra::UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::FRAC_PI_2),
    );
    doc.set_sub_assembly_transform("Cart-1", cart * turn)
        .unwrap();
    // (350, 330) turned 90° about the world Z: (-330, 350)
    assert!(near(
        at(&doc, "Cart-1/Axle-2/Wheel-2"),
        [-330.0, 350.0, 760.0]
    ));
    assert!(near(at(&doc, "table"), [0.0, 0.0, 0.0]));
    doc.add_sub_assembly(
        "Cart-1/Axle-3",
        doc.sub_assembly("Cart-1").unwrap().transform,
    )
    .unwrap();
    assert!(doc
        .add_component("Cart-1/Axle-9/Wheel-1", "wheel", Transform::IDENTITY)
        .is_err());
    doc.add_component(
        "Cart-1/Axle-3/Wheel-1",
        "wheel",
        Transform::from_translation(Vec3::new(1.0, 2.0, 3.0)),
    )
    .unwrap();
    doc.save().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("- [180.0, 0.0, 0.0, 1.0]"),
        "local poses in the file:\n{text}"
    );
    assert!(text.contains("Cart-1/Axle-1/Wheel-1/axis"), "{text}");
    let again = Document::open(&path).unwrap();
    for c in doc.components() {
        let b = again.component(&c.name).unwrap().transform;
        assert!(b.approx_eq(&c.transform, 1e-9, 1e-12), "{}", c.name);
    }
    assert_eq!(again.sub_assemblies().len(), 4);
    assert!(near(at(&again, "Cart-1/Axle-3/Wheel-1"), [1.0, 2.0, 3.0]));
    // a fixed component inside stops the move
    let mut fixed = again.clone();
    fixed.set_fixed("Cart-1/Deck-1", true).unwrap();
    assert!(fixed
        .set_sub_assembly_transform("Cart-1", Transform::IDENTITY)
        .is_err());
}

#[test]
fn a_bad_tree_is_located() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "- name: Cart-1/Deck-1",
            "- name: Cart-2/Deck-1",
            "parent `Cart-2` is no sub-assembly",
        ),
        (
            "- name: Cart-1/Axle-1\n",
            "- name: Cart-1//Axle-1\n",
            "each non-empty",
        ),
        (
            "- name: Cart-1/Axle-2\n",
            "- name: Cart-1/Axle-1\n",
            "duplicate sub-assembly name",
        ),
        (
            "- name: Cart-1\n",
            "- name: Cart-0\n",
            "must be a sub-assembly listed before it",
        ),
    ];
    for (from, to, cause) in cases {
        let (_dir, path) = cart(|t| t.replacen(from, to, 1));
        let e = Document::open(&path).unwrap_err();
        let shown = e.to_string();
        assert!(shown.contains(cause), "{to}: {shown}");
        assert!(
            e.location().is_some_and(|l| l.line.is_some()),
            "{to}: not located: {shown}"
        );
    }
}

#[test]
fn the_sub_assembly_ports_run() {
    let root = common::repo();
    for s in ["get_by_name", "traverse_tree", "where_used"] {
        let out = common::run_in(&root, &["run", &format!("scripts/solidworks/{s}.rhai")]);
        assert!(out.status.success(), "{s}: {}", common::text(&out));
    }
}
