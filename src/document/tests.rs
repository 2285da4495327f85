use super::*;
use crate::math::{AngleConvention, Point3, Vec3};
use proptest::strategy::Strategy;

fn write_demo() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    crate::demo::write_cell(dir.path()).unwrap();
    dir
}

#[test]
fn demo_loads_and_mates_seat_the_screws() {
    let dir = write_demo();
    let doc = Document::open(&dir.path().join("cell.yaml")).unwrap();
    assert_eq!(doc.components().len(), 8);
    // screw1 axis is collinear with plate_a's hole1 and its head rests on the plate.
    let s = doc.component("screw1").unwrap();
    let plate = doc.component("plate_a").unwrap();
    let hole = plate.transform.apply(&Point3::new(50.0, 50.0, 0.0));
    let tip = s.transform.apply(&Point3::origin());
    assert!((tip - hole).norm() < 1e-6, "tip {tip} hole {hole}");
    // plate_b got onto the table top and centred on b_axis.
    let pb = doc.component("plate_b").unwrap();
    let centre = pb.transform.apply(&Point3::new(100.0, 100.0, 0.0));
    assert!(
        (centre - Point3::new(800.0, 400.0, 750.0)).norm() < 1e-6,
        "{centre}"
    );
}

#[test]
fn round_trip_is_exact() {
    let dir = write_demo();
    let p = dir.path().join("cell.yaml");
    let doc = Document::open(&p).unwrap();
    let out = dir.path().join("copy.yaml");
    let mut d2 = doc.clone();
    d2.save_as(&out).unwrap();
    let again = Document::open(&out).unwrap();
    assert_eq!(doc.to_file(), again.to_file());
    assert_eq!(doc.to_yaml(), again.to_yaml());
    for (a, b) in doc.components().iter().zip(again.components()) {
        assert!(a.transform.approx_eq(&b.transform, 1e-12, 1e-12));
    }
}

#[test]
fn angle_dimension_drives_plate_and_units_are_si() {
    let dir = write_demo();
    let mut doc = Document::open(&dir.path().join("cell.yaml")).unwrap();
    assert_eq!(doc.dimensions(), vec!["D1@角度1".to_string()]);
    doc.set_dimension("D1@角度1", 30f64.to_radians()).unwrap();
    let d = doc.dimension("D1@角度1").unwrap();
    assert!((d.document_value() - 30.0).abs() < 1e-9);
    assert!((d.system_value() - 30f64.to_radians()).abs() < 1e-12);
    let pb = doc.component("plate_b").unwrap();
    let [.., c] = pb.transform.to_xyzabc(AngleConvention::XyzFixed);
    assert!((c.to_degrees() - 30.0).abs() < 1e-6, "{}", c.to_degrees());
    // Still centred and on the table after the re-solve.
    let centre = pb.transform.apply(&Point3::new(100.0, 100.0, 0.0));
    assert!((centre - Point3::new(800.0, 400.0, 750.0)).norm() < 1e-6);
    assert!(matches!(
        doc.dimension("D1@角度2"),
        Err(DocumentError::NotFound { .. })
    ));
}

fn load_text(dir: &Path, text: &str) -> Result<Document, DocumentError> {
    let p = dir.join("t.yaml");
    std::fs::write(&p, text).unwrap();
    Document::open(&p)
}

#[test]
fn bad_documents_name_the_line_and_cause() {
    let dir = write_demo();
    let base = std::fs::read_to_string(dir.path().join("cell.yaml")).unwrap();
    let cases = [
        (
            base.replacen("part: plate_a", "part: plate_x", 1),
            "unknown part `plate_x`",
        ),
        (
            base.replacen("name: screw2", "name: screw1", 1),
            "duplicate component name",
        ),
        (
            base.replacen("type: concentric", "type: concentrik", 1),
            "unknown type `concentrik`",
        ),
        (
            base.replacen("units: mm", "units: inch", 1)
                + if base.contains("units") {
                    ""
                } else {
                    "units: inch\n"
                },
            "units",
        ),
        (
            base.replacen("meshes/screw.stl", "meshes/nope.stl", 1),
            "nope.stl",
        ),
        (base.replacen("parts:", "parts: [", 1), "invalid document"),
    ];
    for (text, needle) in cases {
        let e = load_text(dir.path(), &text).unwrap_err();
        let msg = e.render();
        assert!(msg.contains(needle), "expected `{needle}` in:\n{msg}");
        assert!(msg.contains("t.yaml:"), "no file:line in {msg}");
    }
}

#[test]
fn non_rigid_pose_is_rejected_with_its_line() {
    let dir = write_demo();
    let base = std::fs::read_to_string(dir.path().join("cell.yaml")).unwrap();
    // Scale the table's rotation block: first `- - 1.0` row.
    let bad = base.replacen("- [1.0, 0.0, 0.0, 0.0]", "- [2.0, 0.0, 0.0, 0.0]", 1);
    assert_ne!(bad, base);
    let e = load_text(dir.path(), &bad).unwrap_err().render();
    assert!(
        e.contains("not orthonormal") && e.contains("t.yaml:"),
        "{e}"
    );
}

#[test]
fn fixed_components_do_not_move_and_nan_is_refused() {
    let dir = write_demo();
    let mut doc = Document::open(&dir.path().join("cell.yaml")).unwrap();
    // Setting a fixed component's own pose is not a move (scripts do it implicitly);
    // any other pose is refused.
    assert!(doc.set_transform("table", Transform::IDENTITY).is_ok());
    let moved = Transform::from_translation(Vec3::new(1.0, 0.0, 0.0));
    assert!(doc.set_transform("table", moved).is_err());
    let e = doc.component("scerw1").unwrap_err().to_string();
    assert!(e.contains("screw1"), "{e}");
    let mut m = Transform::IDENTITY.to_matrix();
    m[3][0] = f64::NAN;
    assert!(Transform::from_matrix(&m).is_err());
    assert!(doc.set_dimension("D1@角度1", f64::NAN).is_err());
}

#[test]
fn distance_and_angle_mates_solve() {
    let dir = tempfile::tempdir().unwrap();
    crate::mesh::write_stl(
        &dir.path().join("b.stl"),
        &Mesh::cuboid(Point3::origin(), Point3::new(10.0, 10.0, 10.0)),
    )
    .unwrap();
    let text = r#"
parts:
  block:
    stl: b.stl
    planes:
      bottom: {point: [0, 0, 0], normal: [0, 0, -1]}
      topf: {point: [0, 0, 10], normal: [0, 0, 1]}
      side: {point: [0, 0, 0], normal: [0, -1, 0]}
    axes:
      vert: {point: [5, 5, 0], direction: [0, 0, 1]}
components:
  - {name: base, part: block, fixed: true}
  - name: top
    part: block
    transform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [3, 2, 30, 1]]
mates:
  - {name: 距离1, type: distance, entities: [base/topf, top/bottom], value: 5}
  - {name: axis, type: concentric, entities: [base/vert, top/vert]}
  - {name: 角度1, type: angle, entities: [base/side, top/side], value: 45, about: base/vert}
"#;
    let mut doc = load_text(dir.path(), text).unwrap();
    let top = doc.component("top").unwrap().transform;
    assert!((top.apply(&Point3::new(5.0, 5.0, 0.0)) - Point3::new(5.0, 5.0, 15.0)).norm() < 1e-6);
    let [.., c] = top.to_xyzabc(AngleConvention::XyzFixed);
    assert!((c.to_degrees() - 45.0).abs() < 1e-6);
    doc.set_dimension("D1@距离1", 20.0).unwrap();
    let z = doc.component("top").unwrap().transform.translation().z;
    assert!((z - 30.0).abs() < 1e-6, "{z}");
    doc.set_dimension("D1@角度1", (-120f64).to_radians())
        .unwrap();
    let [.., c] = doc
        .component("top")
        .unwrap()
        .transform
        .to_xyzabc(AngleConvention::XyzFixed);
    assert!((c.to_degrees() + 120.0).abs() < 1e-6, "{}", c.to_degrees());
    assert!(doc.set_dimension("D1@距离1", -1.0).is_err());
}

#[test]
fn cached_world_boxes_match_brute_force_after_moves() {
    let dir = write_demo();
    let mut doc = Document::open(&dir.path().join("cell.yaml")).unwrap();
    let i = doc.component_index("screw4").unwrap();
    let brute = |doc: &Document| {
        let c = &doc.components()[i];
        let m = doc.mesh_of(i);
        let pts: Vec<Point3> = m.vertices.iter().map(|p| c.transform.apply(p)).collect();
        crate::math::Aabb::around(&pts)
    };
    let mut rng = crate::math::Rng::new(3);
    for k in 0..50 {
        let t = doc.component("screw4").unwrap().transform;
        let step = if k % 3 == 0 {
            Transform::from_parts(Vec3::new(rng.range(-5.0, 5.0), 0.0, 1.0), rng.rotation())
        } else {
            Transform::from_translation(Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), 0.5))
        };
        doc.set_transform("screw4", t * step).unwrap();
        let b = doc.world_aabb(i).unwrap();
        let expected = brute(&doc);
        assert!(
            (b.lo - expected.lo).norm() < 1e-9 && (b.hi - expected.hi).norm() < 1e-9,
            "step {k}"
        );
    }
}

proptest::proptest! {
    #![proptest_config(crate::test_support::proptest_config(64))]
    /// Mangled documents give an error or a document, never a panic.
    #[test]
    fn loader_never_panics_on_mangled_yaml(cut in 0usize..6000, junk in "[ -~\\n\\t]{0,30}", drop in 0usize..200) {
        let dir = write_demo();
        let base = std::fs::read_to_string(dir.path().join("cell.yaml")).unwrap();
        let mut s: Vec<char> = base.chars().collect();
        let at = cut.min(s.len());
        let end = (at + drop).min(s.len());
        s.splice(at..end, junk.chars());
        let text: String = s.into_iter().collect();
        match load_text(dir.path(), &text) {
            Ok(doc) => {
                // Whatever loads saves to text that loads again.
                proptest::prop_assert!(Document::parse_text(&doc.to_yaml(), &dir.path().join("t.yaml")).is_ok());
            }
            Err(DocumentError::Source(e)) => {
                proptest::prop_assert!(e.path.ends_with("t.yaml") || e.path.extension().is_some_and(|x| x == "stl"), "{e}");
            }
            Err(e) => proptest::prop_assert!(false, "unlocated error: {e}"),
        }
    }

    /// Any number in a pose: accepted only when finite and in range; otherwise the
    /// error names the line of the matrix.
    #[test]
    fn pose_numbers_are_range_checked_with_their_line(v in proptest::prop_oneof![
        proptest::num::f64::ANY.prop_map(|v| format!("{v:e}")),
        proptest::strategy::Just(".inf".to_string()),
        proptest::strategy::Just("-.inf".to_string()),
        proptest::strategy::Just(".nan".to_string()),
        proptest::strategy::Just("1e400".to_string()),
        (-1e10f64..1e10).prop_map(|v| format!("{v}")),
    ]) {
        let dir = write_demo();
        let base = std::fs::read_to_string(dir.path().join("cell.yaml")).unwrap();
        // plate_a's translation row.
        let row = "- [100.0, 150.0, 750.0, 1.0]";
        let line = base.lines().position(|l| l.trim() == row).map(|l| l + 1);
        proptest::prop_assert!(line.is_some());
        let text = base.replacen(row, &format!("- [{v}, 150.0, 750.0, 1.0]"), 1);
        let parsed: Option<f64> = v.parse().ok().filter(|x: &f64| x.is_finite() && x.abs() <= MAX_ABS_VALUE);
        match (load_text(dir.path(), &text), parsed) {
            (Ok(_), p) => proptest::prop_assert!(p.is_some(), "{v} accepted"),
            (Err(DocumentError::Source(e)), None) => {
                proptest::prop_assert_eq!(e.line, line, "{}", e);
            }
            // In range, but the mates may not solve that far away: still located.
            (Err(DocumentError::Source(e)), Some(_)) => {
                proptest::prop_assert!(e.line.is_some(), "{}", e);
            }
            (Err(e), _) => proptest::prop_assert!(false, "unlocated error: {e}"),
        }
    }

    /// Alias bombs of any shape are refused at once (aliases never expand).
    #[test]
    fn aliases_are_refused_whatever_their_shape(width in 1usize..200, depth in 1usize..6) {
        let mut text = String::from("a0: &a0 [");
        text += &vec!["1"; width].join(", ");
        text += "]\n";
        for d in 1..depth {
            text += &format!("a{d}: &a{d} [{}]\n", vec![format!("*a{}", d - 1); width].join(", "));
        }
        let e = scan::scan(&text).unwrap_err();
        proptest::prop_assert_eq!(e.line, 1);
    }
}

/// Names are kept in NFC: the decomposed spelling in the file is found by either
/// spelling (parts, components, references, mate dimensions), saved composed, and
/// case-only twins are warned with their lines.
#[test]
fn names_are_nfc_and_case_twins_are_warned() {
    let dir = write_demo();
    let nfd = "e\u{301}"; // é decomposed
    let text = format!(
        "parts:\n  pl{nfd}:\n    stl: meshes/plate_a.stl\n    planes:\n      f{nfd}ce:\n        point: [0, 0, 0]\n        normal: [0, 0, 1]\n\
         components:\n  - name: c{nfd}1\n    part: pl{nfd}\n  - name: C\u{e9}1\n    part: pl{nfd}\n    transform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 10, 1]]\n\
         mates:\n  - name: d{nfd}\n    type: distance\n    entities: [c{nfd}1/f{nfd}ce, C\u{e9}1/f{nfd}ce]\n    value: 10\n    aligned: true\n"
    );
    let p = dir.path().join("nfd.yaml");
    std::fs::write(&p, &text).unwrap();
    let mut doc = Document::open(&p).unwrap();
    assert!(doc.component("c\u{e9}1").is_ok() && doc.component(&format!("c{nfd}1")).is_ok());
    assert_eq!(doc.component(&format!("c{nfd}1")).unwrap().name, "c\u{e9}1");
    assert!(doc.part("pl\u{e9}").is_ok());
    assert!(doc
        .part("pl\u{e9}")
        .unwrap()
        .reference(&format!("f{nfd}ce"))
        .is_some());
    assert!(doc.dimension("D1@d\u{e9}").is_ok());
    doc.set_dimension(&format!("D1@d{nfd}"), 12.0).unwrap();
    // `c…1` and `C…1` differ only by case: one warning at the second one's line
    assert_eq!(doc.warnings().len(), 1, "{:?}", doc.warnings());
    assert!(
        doc.warnings()[0].contains("nfd.yaml:11:"),
        "{:?}",
        doc.warnings()
    );
    assert!(doc.warnings()[0].contains("differ only by case"));
    doc.save().unwrap();
    let saved = std::fs::read_to_string(&p).unwrap();
    assert!(
        !saved.contains(nfd) && saved.contains("c\u{e9}1"),
        "{saved}"
    );
    // a new robot name with an invisible character is refused, NFC kept
    let robot = crate::kinematics::Catalog::NachiMz07.robot();
    let e = doc.add_robot("arm\u{200b}", &robot, None).unwrap_err();
    assert!(e.to_string().contains("U+200B"), "{e}");
    doc.add_robot(&format!("arm{nfd}"), &robot, None).unwrap();
    assert!(doc.robot("arm\u{e9}").is_ok());
}

/// Issue 37: mates as objects, suppression, visibility, properties, added, renamed
/// and re-pointed components survive a save and a reload, and a change the mates
/// cannot satisfy changes nothing.
#[test]
fn edits_of_a_macro_author_round_trip() {
    let dir = write_demo();
    let p = dir.path().join("cell.yaml");
    let mut doc = Document::open(&p).unwrap();
    // mates: flip, suppress, delete, add
    assert_eq!(doc.mate_alignment("screw1_seated").unwrap(), Some(false));
    let seated = doc.component("screw1").unwrap().transform;
    doc.flip_mate("screw1_seated").unwrap();
    assert_eq!(doc.mate_alignment("screw1_seated").unwrap(), Some(true));
    let flipped = doc.component("screw1").unwrap().transform;
    let z = flipped.apply_vector(&Vec3::z());
    assert!((z.z + 1.0).abs() < 1e-9, "screw1 turned over: {z}");
    doc.flip_mate("screw1_seated").unwrap();
    assert!(
        (doc.component("screw1")
            .unwrap()
            .transform
            .apply_vector(&Vec3::z())
            - seated.apply_vector(&Vec3::z()))
        .norm()
            < 1e-9
    );
    doc.set_mate_suppressed("screw2_seated", true).unwrap();
    assert!(!doc.mate_active(doc.mate("screw2_seated").unwrap()));
    let deleted = doc.delete_mate("screw3_in_hole").unwrap();
    assert_eq!(deleted.kind, MateKind::Concentric);
    assert!(doc.mate("screw3_in_hole").is_err());
    // a new mate that conflicts with the fixed plate is refused, nothing changed
    let before = doc.to_file();
    let conflict = MateSpec {
        name: "bad".into(),
        kind: MateKind::Distance,
        entities: ["table/origin".into(), "plate_a/origin".into()],
        value: Some(1.0),
        aligned: None,
        about: None,
    };
    assert!(doc.add_mate(&conflict).is_err());
    assert_eq!(doc.to_file(), before);
    // components: suppressed, hidden, properties, added, renamed, re-pointed
    doc.set_suppressed("screw4", true).unwrap();
    doc.set_hidden("screw5", true).unwrap();
    doc.set_property(PropertyOwner::Part("screw"), "Description", "M5 screw")
        .unwrap();
    doc.set_property(PropertyOwner::Component("screw5"), "Finish", "zinc")
        .unwrap();
    let i = doc
        .add_component(
            "extra-1",
            "screw",
            Transform::from_translation(Vec3::new(0.0, 0.0, 900.0)),
        )
        .unwrap();
    assert_eq!(doc.next_instance_name("extra"), "extra-2");
    doc.rename_component("extra-1", "extra-2").unwrap();
    assert_eq!(doc.component_index("extra-2").unwrap(), i);
    assert!(doc
        .add_component("extra-2", "screw", Transform::IDENTITY)
        .is_err());
    assert!(doc
        .add_component("x", "no_part", Transform::IDENTITY)
        .is_err());
    doc.rename_component("screw1", "Screw-1").unwrap();
    doc.save().unwrap();
    let back = Document::open(&p).unwrap();
    assert_eq!(back.to_file(), doc.to_file());
    assert!(back.component("screw4").unwrap().suppressed);
    assert!(back.component("screw5").unwrap().hidden);
    assert_eq!(
        back.component("screw5").unwrap().properties["Finish"],
        "zinc"
    );
    assert_eq!(
        back.part("screw").unwrap().properties["Description"],
        "M5 screw"
    );
    assert!(back.mate("screw2_seated").unwrap().suppressed);
    assert_eq!(back.mate_alignment("screw1_seated").unwrap(), Some(false));
    assert_eq!(
        back.mates()[3].entities[1].component,
        back.component_index("Screw-1").unwrap()
    );
    assert!(back.component("extra-2").is_ok());
    // the export leaves the suppressed and the hidden out; the box the suppressed one
    let glb = back.export_glb(&dir.path().join("out.glb"), false).unwrap();
    assert_eq!(glb.nodes, back.components().len() - 2);
    let mut moved = back.clone();
    let b0 = moved.assembly_aabb().unwrap();
    moved
        .set_transform(
            "screw4",
            Transform::from_translation(Vec3::new(0.0, 0.0, 1e5)),
        )
        .unwrap();
    assert_eq!(moved.assembly_aabb().unwrap(), b0);
}

#[test]
fn properties_must_be_scalars_and_a_replaced_part_needs_the_mates_references() {
    let dir = write_demo();
    let p = dir.path().join("cell.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    let bad = text.replacen(
        "- name: screw5\n",
        "- name: screw5\n  properties:\n    Price: [1, 2]\n",
        1,
    );
    let e = load_text(dir.path(), &bad).unwrap_err().to_string();
    assert!(e.contains("Price") && e.contains("text, a number"), "{e}");
    let good = text.replacen(
        "- name: screw5\n",
        "- name: screw5\n  properties:\n    Price: 12.50\n    Stock: true\n",
        1,
    );
    let doc = load_text(dir.path(), &good).unwrap();
    let props = &doc.component("screw5").unwrap().properties;
    assert_eq!(
        (props["Price"].as_str(), props["Stock"].as_str()),
        ("12.5", "true")
    );
    // plate_b has no `axis`: screw1's concentric mate cannot follow it there
    let mut doc = Document::open(&p).unwrap();
    let e = doc
        .set_component_part("screw1", "plate_b")
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not have"), "{e}");
    assert_eq!(doc.component("screw1").unwrap().part, "screw");
    // a reference added to the new part lets it through, and mates follow it
    doc.set_reference(
        "screw",
        "under_head",
        Reference::Plane {
            point: Point3::new(0.0, 0.0, 12.0),
            normal: Vec3::new(0.0, 0.0, -2.0),
        },
    )
    .unwrap();
    assert!(doc
        .set_reference("screw", "origin", Reference::Point(Point3::origin()))
        .is_err());
}

/// Issue 37, "a suppressed component is not loaded": a part only suppressed
/// components use is not read when the document opens (its file is missing here),
/// and every way a component using it stops being suppressed reads it first: adding
/// one, re-pointing one to it, unsuppressing the sub-assembly holding one, renaming
/// one out of it. While the file is missing each is refused with
/// [`DocumentError::PartUnreadable`] and changes nothing; with the file there, it
/// is read.
#[test]
fn a_part_only_suppressed_components_use_is_read_when_one_needs_it() {
    let dir = write_demo();
    let cell = std::fs::read_to_string(dir.path().join("cell.yaml")).unwrap();
    let text = cell
        .replacen(
            "\nparts:\n",
            "\nparts:\n  ghost:\n    stl: meshes/ghost.stl\n",
            1,
        )
        .replacen(
            "\ncomponents:\n",
            "\ncomponents:\n- name: ghost\n  part: ghost\n  suppressed: true\n",
            1,
        );
    assert_ne!(text, cell);
    let path = dir.path().join("ghost.yaml");
    std::fs::write(&path, &text).unwrap();
    let mut doc = Document::open(&path).unwrap();
    let ghost = doc.component_index("ghost").unwrap();
    assert!(!doc.part("ghost").unwrap().is_loaded() && !doc.part_loaded(ghost));
    assert!(doc
        .parts()
        .filter(|p| p.name != "ghost")
        .all(Part::is_loaded));
    assert!(doc.world_aabb(ghost).is_none());
    assert!(matches!(
        doc.loaded_mesh_of(ghost),
        Err(DocumentError::NotLoaded { .. })
    ));
    assert!(matches!(
        crate::workspace::mass_properties(&doc, &[ghost], &Default::default()),
        Err(crate::workspace::WorkspaceError::Document(
            DocumentError::NotLoaded { .. }
        ))
    ));
    let line = 1 + text.lines().position(|l| l.contains("ghost.stl")).unwrap();
    let unreadable = |r: Result<(), DocumentError>, component: &str| match r {
        Err(DocumentError::PartUnreadable {
            component: c,
            part,
            at,
        }) => {
            assert_eq!((&*c, &*part), (component, "ghost"));
            assert_eq!(at.line, Some(line), "{at}");
            assert!(at.message.contains("ghost.stl"), "{at}");
        }
        other => panic!("{component}: expected PartUnreadable, got {other:?}"),
    };
    let file = doc.to_file();
    let check_unchanged = |doc: &Document| {
        assert_eq!(doc.to_file(), file);
        assert!(!doc.part("ghost").unwrap().is_loaded());
    };
    unreadable(doc.set_suppressed("ghost", false), "ghost");
    check_unchanged(&doc);
    unreadable(
        doc.add_component("ghost-2", "ghost", Transform::IDENTITY)
            .map(|_| ()),
        "ghost-2",
    );
    check_unchanged(&doc);
    unreadable(doc.set_component_part("screw4", "ghost"), "screw4");
    check_unchanged(&doc);
    assert_eq!(doc.component("screw4").unwrap().part, "screw");

    // inside a suppressed sub-assembly: added without a read, refused when it comes out
    doc.add_sub_assembly("Box", Transform::IDENTITY).unwrap();
    doc.set_sub_assembly_suppressed("Box", true).unwrap();
    doc.add_component("Box/ghost", "ghost", Transform::IDENTITY)
        .unwrap();
    let file = doc.to_file();
    let check_unchanged = |doc: &Document| {
        assert_eq!(doc.to_file(), file);
        assert!(doc.component("Box/ghost").unwrap().is_suppressed());
        assert!(!doc.part("ghost").unwrap().is_loaded());
    };
    unreadable(doc.set_sub_assembly_suppressed("Box", false), "Box/ghost");
    check_unchanged(&doc);
    unreadable(doc.rename_component("Box/ghost", "ghost-3"), "ghost-3");
    check_unchanged(&doc);

    // the file there: read when needed, the same mesh as that file's other part
    std::fs::copy(
        dir.path().join("meshes/plate_a.stl"),
        dir.path().join("meshes/ghost.stl"),
    )
    .unwrap();
    doc.set_sub_assembly_suppressed("Box", false).unwrap();
    assert!(doc.part("ghost").unwrap().is_loaded());
    let i = doc.component_index("Box/ghost").unwrap();
    assert_eq!(
        doc.mesh_of(i).vertices,
        doc.part("plate_a").unwrap().mesh.vertices
    );
    assert!(doc.world_aabb(i).is_some() && doc.world_aabb(ghost).is_some());
}
