//! The SolidWorks macro author's document (issue 37): the CodeStack macros ported
//! under `scripts/solidworks/` run as documented (`fitup run
//! scripts/solidworks/NAME.rhai` from the repository root, no other argument), and
//! the bugs found porting them stay fixed.

use crate::common;

#[test]
fn every_ported_macro_runs() {
    let scripts = common::repo_scripts("scripts/solidworks");
    assert!(
        scripts.len() >= 30,
        "expected the ported macros, found {scripts:?}"
    );
    for rel in &scripts {
        let text = std::fs::read_to_string(common::repo().join(rel)).unwrap();
        assert!(
            text.lines()
                .take(3)
                .any(|l| l.contains("Ports CodeStack's")),
            "{rel} names the macro it ports in its first lines"
        );
    }
    let failures = common::failing_repo_runs(&scripts);
    assert!(
        failures.is_empty(),
        "failing ports:\n{}",
        failures.join("\n")
    );
}

/// A scratch project with the demo cell and one script.
fn run_script(body: &str) -> std::process::Output {
    let dir = common::project();
    let out = common::run_script_in(dir.path(), "t.rhai", body);
    // keep the folder alive until the run is over
    drop(dir);
    out
}

#[test]
fn document_warnings_go_to_stderr_not_into_the_scripts_output() {
    let dir = common::project();
    // two component names that differ only by case: a document warning
    let doc = dir.path().join("models/cell.yaml");
    let text = std::fs::read_to_string(&doc).unwrap();
    std::fs::write(&doc, text.replacen("- name: screw5", "- name: Screw4", 1)).unwrap();
    std::fs::write(
        dir.path().join("scripts/t.rhai"),
        "let d = open_doc(\"models/cell.yaml\");\nprint(\"name,x\");\nfor c in d.components() { print(`${c.name},${c.transform.translation[0]}`); }\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/t.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.starts_with("name,x\n"),
        "the CSV starts with its own header: {stdout:?}"
    );
    assert!(
        !stdout.contains("warning"),
        "no warning in the script's output: {stdout:?}"
    );
    assert!(
        stderr.contains("warning") && stderr.contains("Screw4"),
        "the warning is on stderr: {stderr:?}"
    );
}

#[test]
fn a_screw_pushed_5_mm_into_the_table_reads_5_mm() {
    let out = run_script(
        "let d = open_doc(\"models/cell.yaml\");\n\
         d.component(\"screw4\").translate(0, 0, -5);\n\
         let c = d.contact(\"screw4\", \"table\");\n\
         print(`${c.state} ${c.depth}`);\n\
         let i = d.interferences().filter(|p| p.a == \"screw4\" || p.b == \"screw4\");\n\
         print(`${i[0].depth}`);\n",
    );
    assert!(out.status.success(), "{}", common::text(&out));
    let lines: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(String::from)
        .collect();
    let depth: f64 = lines[0]
        .strip_prefix("interfering ")
        .unwrap()
        .parse()
        .unwrap();
    assert!((depth - 5.0).abs() < 1e-6, "contact depth {depth}");
    let listed: f64 = lines[1].parse().unwrap();
    assert!((listed - 5.0).abs() < 1e-6, "interferences depth {listed}");
}

#[test]
fn fixed_is_set_on_a_calls_result() {
    let out = run_script(
        "let d = open_doc(\"models/cell.yaml\");\n\
         d.component(\"screw4\").fixed = true;\n\
         assert(d.component(\"screw4\").fixed, \"fixed\");\n\
         d.component(\"screw4\").fixed = false;\n\
         d.component(\"screw4\").transform = translation(1, 2, 3);\n\
         print(`${d.component(\"screw4\").transform.translation}`);\n",
    );
    assert!(out.status.success(), "{}", common::text(&out));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        "[1.0, 2.0, 3.0]"
    );
    // errors keep their line after the rewrite
    let out = run_script("let d = open_doc(\"models/cell.yaml\");\nd.component(\"screw4\").fixed = true;\nd.component(\"nope\").fixed = true;\n");
    assert!(!out.status.success());
    assert!(
        common::text(&out).contains("t.rhai:3"),
        "{}",
        common::text(&out)
    );
}

#[test]
fn sixteen_numbers_say_their_unit() {
    // SolidWorks' ArrayData (metres) pasted into transform(): refused, not read as mm
    let out =
        run_script("let t = transform([1, 0, 0, 0, 1, 0, 0, 0, 1, 0.1, 0.2, 0.3, 1, 0, 0, 0]);\n");
    assert!(!out.status.success());
    let text = common::text(&out);
    assert!(
        text.contains("metres") && text.contains("create_transform"),
        "{text}"
    );
    let out = run_script(
        "let d = [1, 0, 0, 0, 1, 0, 0, 0, 1, 0.1, 0.2, 0.3, 1, 0, 0, 0];\n\
         assert(create_transform(d) == translation(100, 200, 300), \"metres\");\n\
         assert(transform(d, \"mm\") == translation(0.1, 0.2, 0.3), \"mm\");\n\
         assert(transform(d, \"m\").array_data == d, \"round trip in SI\");\n\
         let r = [[0.866, 0.5, 0, 0], [-0.5, 0.866, 0, 0], [0, 0, 1, 0], [10, 0, 0, 1]];\n\
         let refused = false;\n\
         try { transform(r); } catch (e) { refused = true; }\n\
         assert(refused, \"rounded rotations are not rigid\");\n\
         let t = orthonormalize(r);\n\
         assert_near(t.xyzabc[5], 30.0, 0.01);\n\
         let mirror = false;\n\
         try { orthonormalize([[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]); } catch (e) { mirror = true; }\n\
         assert(mirror, \"a mirror is refused\");\n",
    );
    assert!(out.status.success(), "{}", common::text(&out));
}

#[test]
fn data_files_are_read_and_written_inside_the_project() {
    let dir = common::project();
    std::fs::create_dir_all(dir.path().join("data")).unwrap();
    std::fs::write(dir.path().join("data/t.csv"), "name;x\n\"a;b\";1.5\nc;2\n").unwrap();
    std::fs::write(
        dir.path().join("data/s.json"),
        "{\"steps\": [1, 2.5, null], \"name\": \"x\"}",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("scripts/t.rhai"),
        "let t = read_csv(\"data/t.csv\", #{delimiter: \";\"});\n\
         assert(t[0].name == \"a;b\" && t[0].x == 1.5 && t[1].x == 2, `${t}`);\n\
         let j = read_json(\"data/s.json\");\n\
         assert(j.steps[0] == 1 && j.steps[1] == 2.5 && j.steps[2] == (), `${j}`);\n\
         write_csv(\"out/r.csv\", [[\"a\", 1], [\"b,c\", 2.5]]);\n\
         write_json(\"out/r.json\", #{pose: translation(1, 2, 3), n: 3});\n\
         write_text(\"out/r.txt\", \"hello\\n\");\n\
         assert(read_text(\"out/r.txt\") == \"hello\\n\", \"text\");\n\
         let back = read_csv(\"out/r.csv\", #{header: false});\n\
         assert(back[1][0] == \"b,c\" && back[1][1] == 2.5, `${back}`);\n\
         let outside = false;\n\
         try { read_text(\"../x.txt\"); } catch (e) { outside = true; }\n\
         assert(outside, \"outside the project\");\n\
         let bad = false;\n\
         try { read_csv(\"data/t.csv\", #{delimter: \";\"}); } catch (e) { bad = `${e}`.contains(\"delimiter\"); }\n\
         assert(bad, \"a misspelt option names the right one\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/t.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let json = std::fs::read_to_string(dir.path().join("out/r.json")).unwrap();
    assert!(json.contains("\"n\": 3"), "{json}");
    // a file the user owns is never replaced by a script's writer
    std::fs::write(dir.path().join("out/mine.txt"), "mine").unwrap();
    std::fs::write(
        dir.path().join("scripts/w.rhai"),
        "write_text(\"out/mine.txt\", \"theirs\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/w.rhai"]);
    assert!(!out.status.success());
    assert_eq!(
        std::fs::read_to_string(dir.path().join("out/mine.txt")).unwrap(),
        "mine"
    );
    // a bad CSV names its line
    std::fs::write(dir.path().join("data/bad.csv"), "a,b\n1,2\n3\n").unwrap();
    std::fs::write(
        dir.path().join("scripts/b.rhai"),
        "read_csv(\"data/bad.csv\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/b.rhai"]);
    assert!(
        common::text(&out).contains("data/bad.csv:3"),
        "{}",
        common::text(&out)
    );
}

/// Issue 37's first bug: a save wrote a document fitup then refused to open (a mated
/// component moved and fixed). A save solves what loading solves: such a document is
/// refused with the mate named and the file untouched, and a moved mated component
/// is saved where the mates put it, so the file opens as saved.
#[test]
fn a_save_solves_what_loading_solves() {
    let dir = common::project();
    let before = std::fs::read_to_string(dir.path().join("models/cell.yaml")).unwrap();
    std::fs::write(
        dir.path().join("scripts/t.rhai"),
        "let d = open_doc(\"models/cell.yaml\");\n\
         d.component(\"plate_b\").translate(0, 0, 10);\n\
         d.component(\"plate_b\").fixed = true;\n\
         let refused = \"\";\n\
         try { d.save(); } catch (e) { refused = `${e}`; }\n\
         assert(refused.contains(\"plate_b_on_table\") && refused.contains(\"not saved\"), refused);\n\
         d.component(\"plate_b\").fixed = false;\n\
         d.save();\n\
         let z = d.component(\"plate_b\").transform.translation[2];\n\
         assert_near(z, 750.0, 1e-6);\n\
         let again = open_doc(\"models/cell.yaml\");\n\
         assert(again.component(\"plate_b\").transform == d.component(\"plate_b\").transform, \"opens as saved\");\n\
         print(\"ok\");\n",
    )
    .unwrap();
    let out = common::run_in(dir.path(), &["run", "scripts/t.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let after = std::fs::read_to_string(dir.path().join("models/cell.yaml")).unwrap();
    // the file holds the poses the mates give (the demo's own file holds unsolved ones)
    assert!(
        before.contains("[690.0, 310.0, 753.0, 1.0]")
            && after.contains("[700.0, 300.0, 750.0, 1.0]"),
        "{after}"
    );
}

/// Capability 7, removing: a component with mates is refused unless its mates go with
/// it; the other mates keep their components (indices shift under them), a robot's
/// link and a mate under an equation are refused, and a save reloads.
#[test]
fn removing_a_component_handles_its_mates() {
    use fitup::document::{Document, RemoveMates};
    let dir = common::project();
    let path = dir.path().join("models/cell.yaml");
    let mut doc = Document::open(&path).unwrap();
    let e = doc
        .remove_component("screw1", RemoveMates::Refuse)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`screw1_in_hole`, `screw1_seated`"), "{e}");
    let before: Vec<_> = doc
        .components()
        .iter()
        .filter(|c| c.name != "screw1")
        .map(|c| (c.name.clone(), c.transform))
        .collect();
    let deleted = doc.remove_component("screw1", RemoveMates::Delete).unwrap();
    let names: Vec<_> = deleted.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["screw1_in_hole", "screw1_seated"]);
    let after: Vec<_> = doc
        .components()
        .iter()
        .map(|c| (c.name.clone(), c.transform))
        .collect();
    assert_eq!(after, before, "nothing else moved or changed place");
    // every remaining mate still joins the components it joined
    let m = doc.mate("screw2_in_hole").unwrap();
    let joined: Vec<_> = m
        .entities
        .iter()
        .map(|e| doc.components()[e.component].name.as_str())
        .collect();
    assert_eq!(joined, ["plate_a", "screw2"]);
    // boxes are not taken from the component that had the index before
    let i = doc.component_index("screw5").unwrap();
    let b = doc.world_aabb(i).unwrap();
    assert!((b.lo.x - 650.0).abs() < 10.0, "{b:?}");
    doc.save().unwrap();
    let again = Document::open(&path).unwrap();
    assert!(again.component("screw1").is_err());
    assert_eq!(again.mates().len(), doc.mates().len());

    let robots = Document::open(&common::repo().join("models/cell_robots.yaml")).unwrap();
    let e = robots
        .clone()
        .remove_component("mz07_a_link1", RemoveMates::Delete)
        .unwrap_err()
        .to_string();
    assert!(e.contains("link of robot"), "{e}");

    let mut lift = Document::open(&common::repo().join("models/solidworks/lift.yaml")).unwrap();
    let e = lift
        .remove_component("plate", RemoveMates::Delete)
        .unwrap_err()
        .to_string();
    assert!(e.contains("D1@lift") && e.contains("equation [2]"), "{e}");
    assert_eq!(lift.components().len(), 2);
}

/// A script's component handles stay on their component when an earlier one is
/// removed; the removed one's handle is an error, not another component.
#[test]
fn component_handles_survive_a_removal() {
    let out = run_script(
        r#"
let doc = open_doc("models/cell.yaml");
let s1 = doc.component("screw1");
let s5 = doc.component("screw5");
let all = doc.components();
let x5 = s5.transform.translation[0];
let gone = doc.remove_component("screw1", true);
assert(gone == ["screw1_in_hole", "screw1_seated"], `${gone}`);
assert(s5.name == "screw5", s5.name);
assert(all[7].name == "screw5", all[7].name);
assert_near(s5.transform.translation[0], x5, 1e-12);
assert_near(s5.aabb().min[0], x5 - 5.0, 5.0);
let err = "";
try { print(s1.name); } catch (e) { err = `${e}`; }
assert(err.contains("removed"), err);
let err = "";
try { doc.remove_component("plate_b"); } catch (e) { err = `${e}`; }
assert(err.contains("plate_b_on_table"), err);
print("ok");
"#,
    );
    assert!(out.status.success(), "{}", common::text(&out));
}

/// Capability 5, end to end on the demo cell: a suppressed component is not checked,
/// planned around, sequenced or exported; a hidden one is checked, planned
/// around and sequenced, but not exported (the viewer's half is the unit test
/// `viewer::tests::suppressed_and_hidden_components_are_not_drawn`); both are saved.
#[test]
fn suppressed_and_hidden_components_as_solidworks_treats_them() {
    use fitup::collision::SweepOptions;
    use fitup::document::Document;
    use fitup::math::{Transform, Vec3};
    use fitup::sequence::{plan_sequence, SequenceOptions};
    use fitup::workspace::{CheckOptions, SceneCache, Workspace};

    let dir = common::project();
    let path = dir.path().join("models/cell.yaml");
    let mut doc = Document::open(&path).unwrap();
    // screw4 (no mates) 60 mm above plate_b, away from its holes, lowered 100 mm: it
    // lands on plate_b, or on the table under it once plate_b is out of the way.
    let plate = doc
        .world_aabb(doc.component_index("plate_b").unwrap())
        .unwrap();
    let thickness = plate.hi.z - plate.lo.z;
    let above = |dz: f64| {
        Transform::from_translation(Vec3::new(
            plate.lo.x + 12.0,
            plate.lo.y + 12.0,
            plate.hi.z + dz,
        ))
    };
    doc.set_transform("screw4", above(60.0)).unwrap();
    let lowered = |doc: &Document| {
        let mut cache = SceneCache::new();
        let ws = Workspace::new(doc, &mut cache).unwrap();
        let hit = ws
            .sweep_through("screw4", &[above(-40.0)], &SweepOptions::default())
            .unwrap();
        assert!(hit.hit);
        (hit.t * 100.0, ws.name(hit.with.unwrap()).to_string())
    };
    let interfering = |doc: &Document| -> Vec<String> {
        let mut cache = SceneCache::new();
        let ws = Workspace::new(doc, &mut cache).unwrap();
        ws.interferences(&CheckOptions::default())
            .unwrap()
            .iter()
            .map(|p| format!("{}-{}", ws.name(p.a), ws.name(p.b)))
            .collect()
    };
    let product = |doc: &Document| {
        plan_sequence(doc, &mut SceneCache::new(), &SequenceOptions::default())
            .map(|p| p.product)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let into_plate = |doc: &mut Document, travel: f64| {
        doc.set_transform("screw4", above(60.0 - travel - 2.0))
            .unwrap();
        let hits = interfering(doc);
        doc.set_transform("screw4", above(60.0)).unwrap();
        hits
    };
    let (shown, with) = lowered(&doc);
    assert_eq!(with, "plate_b", "{shown}");

    // hidden: still in the way, checked and sequenced, but not exported
    doc.set_hidden("plate_b", true).unwrap();
    let (travel, with) = lowered(&doc);
    assert!(
        (travel - shown).abs() < 1e-9 && with == "plate_b",
        "hidden: {travel} {with}"
    );
    let hits = into_plate(&mut doc, shown);
    assert!(
        hits.iter()
            .any(|p| p.contains("plate_b") && p.contains("screw4")),
        "hidden is checked: {hits:?}"
    );
    assert!(
        product(&doc).iter().any(|n| n == "plate_b"),
        "hidden is sequenced"
    );
    let glb = doc.export_glb(&dir.path().join("out.glb"), false).unwrap();
    assert_eq!(
        glb.nodes,
        doc.components().len() - 1,
        "hidden is not exported"
    );

    // suppressed: out of the way, the checks, the sequence, the box and the export
    doc.set_hidden("plate_b", false).unwrap();
    doc.set_suppressed("plate_b", true).unwrap();
    let (travel, with) = lowered(&doc);
    assert!(
        with == "table" && (travel - shown - thickness).abs() < 0.5,
        "suppressed: {travel} {with} (shown {shown}, plate {thickness} mm)"
    );
    let hits = into_plate(&mut doc, shown);
    assert!(
        !hits.iter().any(|p| p.contains("plate_b")),
        "suppressed is not checked: {hits:?}"
    );
    let seq = product(&doc);
    assert!(
        !seq.iter().any(|n| n == "plate_b"),
        "suppressed is not sequenced: {seq:?}"
    );
    let glb = doc.export_glb(&dir.path().join("out2.glb"), false).unwrap();
    assert_eq!(
        glb.nodes,
        doc.components().len() - 1,
        "suppressed is not exported"
    );

    // both saved and read back
    doc.set_hidden("screw5", true).unwrap();
    doc.save().unwrap();
    let back = Document::open(&path).unwrap();
    assert!(back.component("plate_b").unwrap().is_suppressed());
    assert!(back.component("screw5").unwrap().hidden);
    assert!(!back.component("screw5").unwrap().is_shown());
}

/// Capability 1, every kind a macro adds (`IAssemblyDoc.AddMate5`): coincident,
/// concentric, angle (about an axis) and distance mates added by a script to a moved
/// component are solved on the rebuild (the references land where each mate says),
/// listed by name, type, entities and value, and kept by a save (the reopened file
/// holds them and the same poses).
#[test]
fn mates_of_every_kind_added_by_a_script_are_solved_and_saved() {
    let out = run_script(
        r#"
let doc = open_doc("models/cell.yaml");
for m in ["plate_b_on_table", "plate_b_centred", "角度1"] { doc.delete_mate(m); }
let p = doc.component("plate_b");
p.transform = pose(100, 50, 900, 10, 20, 30);
doc.add_mate("on_table", "coincident", "table/top_face", "plate_b/bottom");
doc.add_mate("centred", "concentric", "table/b_axis", "plate_b/center_axis");
doc.add_mate("turned", "angle", "table/front_edge", "plate_b/front_edge", #{value: 30, about: "table/b_axis"});
doc.add_mate("lifted", "distance", "table/top_face", "screw4/tip", #{value: 25});
// solved: on the table, on its axis, turned 30° about it; screw4's tip 25 mm above
let bottom = p.reference("bottom");
assert_near(bottom.point[2], 750.0, 1e-9);
assert_near(bottom.normal[2], -1.0, 1e-12);
let axis = p.reference("center_axis");
assert_near(axis.point[0], 800.0, 1e-9);
assert_near(axis.point[1], 400.0, 1e-9);
let front = p.reference("front_edge").normal;
assert_near(front[2], 0.0, 1e-12);
assert_near(front[1], -(rad(30).cos()), 1e-9);
assert_near(doc.component("screw4").reference("tip").point[2], 775.0, 1e-9);
let added = doc.mates().filter(|m| ["on_table", "centred", "turned", "lifted"].contains(m.name));
assert(added.map(|m| m.type) == ["coincident", "concentric", "angle", "distance"], `${added.map(|m| m.type)}`);
assert(doc.mate("turned").entities == ["table/front_edge", "plate_b/front_edge"], "entities");
assert_near(doc.mate("turned").value, 30.0, 1e-12);
assert_near(doc.mate("lifted").value, 25.0, 1e-12);
assert(doc.mate("lifted").components == ["table", "screw4"], `${doc.mate("lifted").components}`);
doc.save();
let back = open_doc("models/cell.yaml");
for n in ["on_table", "centred", "turned", "lifted"] {
    assert(back.mate(n).type == doc.mate(n).type && back.mate(n).entities == doc.mate(n).entities, n);
}
assert_near(back.mate("turned").value, 30.0, 1e-12);
for c in ["plate_b", "screw4"] {
    let d = back.component(c).transform.distance_to(doc.component(c).transform);
    assert(d.mm < 1e-9 && d.deg < 1e-9, `${c} reopened where it was solved: ${d}`);
}
print("ok");
"#,
    );
    assert!(out.status.success(), "{}", common::text(&out));
}

/// Capability 7 from a STEP file (`IAssemblyDoc.AddComponent5` of a STEP file): a
/// build without the `step` feature refuses it with the file and the command that adds
/// the feature, and the document is unchanged (the build with it:
/// `step_import::step_parts::a_script_adds_a_part_from_a_step_file`).
#[cfg(not(feature = "step"))]
#[test]
fn a_step_file_added_as_a_part_asks_for_the_step_feature() {
    let dir = common::project();
    std::fs::write(
        dir.path().join("models/bracket.step"),
        "ISO-10303-21;\nHEADER;\nENDSEC;\n",
    )
    .unwrap();
    let out = common::run_script_in(
        dir.path(),
        "t.rhai",
        r#"
let doc = open_doc("models/cell.yaml");
let n = doc.parts().len();
let e = "";
try { doc.add_part("bracket", "bracket.step"); } catch (err) { e = `${err}`; }
assert(e.contains("bracket.step") && e.contains("--features step"), e);
assert(doc.parts().len() == n && !doc.parts().contains("bracket"), "nothing added");
print("ok");
"#,
    );
    assert!(out.status.success(), "{}", common::text(&out));
}

/// The demo cell with a suppressed `ghost` (part and component, listed first) whose
/// mesh file `meshes/ghost.stl` is not there, placed 5 mm into the table's top
/// (away from the plates), written as `models/ghost.yaml`. Returns its text.
fn write_ghost_document(dir: &std::path::Path) -> String {
    let cell = std::fs::read_to_string(dir.join("models/cell.yaml")).unwrap();
    let part = "\
parts:
  ghost:
    stl: meshes/ghost.stl
    properties:
      Description: bracket, drawing 17-B
";
    let component = "\
components:
- name: ghost
  part: ghost
  suppressed: true
  properties:
    Supplier: ACME
  transform:
  - [1.0, 0.0, 0.0, 0.0]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [850.0, 580.0, 745.0, 1.0]
";
    assert!(cell.contains("\nparts:\n") && cell.contains("\ncomponents:\n"));
    let text = cell
        .replacen("\nparts:\n", &format!("\n{part}"), 1)
        .replacen("\ncomponents:\n", &format!("\n{component}"), 1);
    std::fs::write(dir.join("models/ghost.yaml"), &text).unwrap();
    text
}

/// The 1-based line of `models/ghost.yaml` naming the ghost's mesh.
fn ghost_stl_line(text: &str) -> usize {
    1 + text
        .lines()
        .position(|l| l.contains("stl: meshes/ghost.stl"))
        .unwrap()
}

/// Capability 5, "a suppressed component is not loaded": SolidWorks opens an
/// assembly without reading its suppressed components, so a missing or broken file
/// of one does not stop it. A document whose suppressed component's mesh is missing
/// opens (`fitup check` notes the part is not loaded), and garbage in that file does
/// not matter while it stays suppressed; unsuppressing it from a script is refused
/// with the file, the document's line and the cause, and the document stays as it
/// was (still suppressed, saved with its part entry unchanged).
#[test]
fn a_suppressed_component_whose_mesh_is_missing_opens_checks_and_saves() {
    let dir = common::project();
    let text = write_ghost_document(dir.path());
    let line = ghost_stl_line(&text);
    let check = common::run_ok(dir.path(), &["check", "models/ghost.yaml"]);
    assert!(
        check.contains("ghost") && check.contains("not loaded (only suppressed components use it)"),
        "{check}"
    );
    assert!(!check.contains("warning"), "a note, not a warning: {check}");
    // garbage in the file: still not read
    std::fs::write(
        dir.path().join("models/meshes/ghost.stl"),
        "solid ghost\nfacet oops\n",
    )
    .unwrap();
    let check = common::run_ok(dir.path(), &["check", "models/ghost.yaml"]);
    assert!(check.contains("not loaded"), "{check}");
    std::fs::remove_file(dir.path().join("models/meshes/ghost.stl")).unwrap();

    // unsuppressed by a script: refused, naming the file, the line and the cause
    let out = common::run_script_in(
        dir.path(),
        "unsuppress.rhai",
        r#"
let doc = open_doc("models/ghost.yaml");
let why = "";
try { doc.component("ghost").suppressed = false; } catch (e) { why = `${e}`; }
print(why);
assert(why != "", "unsuppressing a part whose file is missing is refused");
assert(doc.component("ghost").suppressed, "still suppressed");
assert(doc.interferences().filter(|p| p.a == "ghost" || p.b == "ghost").len() == 0, "nothing checked against it");
doc.save();
"#,
    );
    let t = common::text(&out);
    assert!(out.status.success(), "{t}");
    for needed in [
        "component `ghost` needs part `ghost`".to_string(),
        format!("ghost.yaml:{line}:"),
        "meshes/ghost.stl".to_string(),
    ] {
        assert!(t.contains(&needed), "`{needed}` in: {t}");
    }
    // the save kept the part entry and the component as they were
    let saved = std::fs::read_to_string(dir.path().join("models/ghost.yaml")).unwrap();
    let parse = |s: &str| serde_yaml::from_str::<serde_yaml::Value>(s).unwrap();
    let (before, after) = (parse(&text), parse(&saved));
    assert_eq!(after["parts"]["ghost"], before["parts"]["ghost"], "{saved}");
    assert_eq!(
        after["components"][0]["name"],
        before["components"][0]["name"]
    );
    assert_eq!(
        after["components"][0]["suppressed"],
        serde_yaml::Value::Bool(true)
    );
    assert_eq!(
        after["components"][0]["properties"],
        before["components"][0]["properties"]
    );
    common::run_ok(dir.path(), &["check", "models/ghost.yaml"]);
}

/// The same through the Rust API: while not loaded the part has no world mesh
/// (refused, not empty) and the cell is checked and sequenced without it; the
/// refusal to unsuppress is [`fitup::document::DocumentError::PartUnreadable`]
/// located at the part's `stl:` line, the document unchanged (still suppressed, its
/// part not loaded); once the file holds a real mesh, unsuppressing reads it and the
/// interference with it is reported (the ghost sits 5 mm into the table).
#[test]
fn unsuppressing_reads_the_part_then_its_interference_is_reported() {
    use fitup::document::{Document, DocumentError};
    use fitup::workspace::{CheckOptions, SceneCache, Workspace};

    let dir = common::project();
    let text = write_ghost_document(dir.path());
    let path = dir.path().join("models/ghost.yaml");
    let mut doc = Document::open(&path).unwrap();
    assert!(!doc.part("ghost").unwrap().is_loaded());
    assert!(doc.part("table").unwrap().is_loaded());
    let ghost = doc.component_index("ghost").unwrap();
    assert!(matches!(
        fitup::workspace::world_mesh(&doc, &[ghost], None),
        Err(DocumentError::NotLoaded { .. })
    ));
    let interfering = |doc: &Document| -> Vec<String> {
        let mut cache = SceneCache::new();
        let ws = Workspace::new(doc, &mut cache).unwrap();
        ws.interferences(&CheckOptions::default())
            .unwrap()
            .iter()
            .map(|p| format!("{}-{}", ws.name(p.a), ws.name(p.b)))
            .collect()
    };
    let ghostly = |hits: &[String]| hits.iter().any(|h| h.contains("ghost"));
    assert!(!ghostly(&interfering(&doc)));
    let plan = fitup::sequence::plan_sequence(
        &doc,
        &mut SceneCache::new(),
        &fitup::sequence::SequenceOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        plan.product.iter().any(|n| n == "plate_b") && !plan.product.iter().any(|n| n == "ghost"),
        "{:?}",
        plan.product
    );
    let revision = doc.revision();
    match doc.set_suppressed("ghost", false) {
        Err(DocumentError::PartUnreadable {
            component,
            part,
            at,
        }) => {
            assert_eq!((&*component, &*part), ("ghost", "ghost"));
            assert!(at.path.ends_with("models/ghost.yaml"), "{at}");
            assert_eq!(at.line, Some(ghost_stl_line(&text)), "{at}");
            assert!(at.message.contains("ghost.stl"), "{at}");
        }
        other => panic!("expected PartUnreadable, got {other:?}"),
    }
    assert!(doc.component("ghost").unwrap().is_suppressed());
    assert!(!doc.part("ghost").unwrap().is_loaded());
    assert_eq!(doc.revision(), revision);

    // a real mesh: unsuppressing reads it, and it is checked
    std::fs::copy(
        dir.path().join("models/meshes/plate_a.stl"),
        dir.path().join("models/meshes/ghost.stl"),
    )
    .unwrap();
    doc.set_suppressed("ghost", false).unwrap();
    assert!(doc.part("ghost").unwrap().is_loaded());
    let plate = Document::open(&dir.path().join("models/cell.yaml")).unwrap();
    assert_eq!(
        doc.part("ghost").unwrap().mesh.triangles,
        plate.part("plate_a").unwrap().mesh.triangles
    );
    let hits = interfering(&doc);
    assert!(hits.iter().any(|h| h == "ghost-table"), "{hits:?}");
}
