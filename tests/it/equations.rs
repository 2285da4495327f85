//! Equations and global variables (issue 37, capability 8): `"Factor" = 2`,
//! `"D1@lift" = 10 * "Factor"` evaluated on load and on every rebuild, saved with the
//! document, each error naming its file, line, equation and cause.

use crate::common;
use fitup::document::{Document, DocumentError, EquationCause};
use std::path::{Path, PathBuf};

/// A scratch project holding `models/solidworks/lift.yaml` (the repository's) with
/// `edit` applied to its text; returns the folder and the document's path.
fn lift(edit: impl FnOnce(String) -> String) -> (tempfile::TempDir, PathBuf) {
    let dir = common::project();
    let text = std::fs::read_to_string(common::repo().join("models/solidworks/lift.yaml")).unwrap();
    std::fs::create_dir_all(dir.path().join("models/solidworks")).unwrap();
    let path = dir.path().join("models/solidworks/lift.yaml");
    std::fs::write(&path, edit(text)).unwrap();
    (dir, path)
}

fn z_of(doc: &Document, name: &str) -> f64 {
    doc.component(name).unwrap().transform.translation().z
}

/// The document with the equations `list` in place of the file's.
fn with_equations(list: &[&str]) -> (tempfile::TempDir, PathBuf) {
    lift(|t| {
        let head = &t[..t.find("equations:").unwrap()];
        let mut out = format!("{head}equations:\n");
        for e in list {
            out.push_str(&format!("- '{e}'\n"));
        }
        out
    })
}

/// The 1-based line of `needle` in the file.
fn line_of(path: &Path, needle: &str) -> usize {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .position(|l| l.contains(needle))
        .unwrap()
        + 1
}

#[test]
fn equations_drive_dimensions_on_load_and_rebuild() {
    let (_dir, path) = lift(|t| t);
    let mut doc = Document::open(&path).unwrap();
    let eq = doc.equations();
    assert_eq!(eq.len(), 4);
    assert_eq!(eq[2].text(), "\"D1@lift\" = 10 * \"Factor\"");
    assert!(eq[0].is_global() && !eq[2].is_global());
    assert_eq!(doc.global_variable("Factor").unwrap(), 2.0);
    // the file says 20 mm and 0°: the equations give 20 mm and 30°
    assert_eq!(doc.dimension("D1@lift").unwrap().value, 20.0);
    assert!((doc.dimension("D1@turn").unwrap().document_value() - 30.0).abs() < 1e-9);
    assert!((z_of(&doc, "plate") - 770.0).abs() < 1e-6);
    doc.set_global_variable("Factor", 3.5).unwrap();
    assert_eq!(doc.dimension("D1@lift").unwrap().value, 35.0);
    assert!((doc.dimension("D1@turn").unwrap().document_value() - 52.5).abs() < 1e-9);
    assert!(
        (z_of(&doc, "plate") - 785.0).abs() < 1e-6,
        "the mates follow"
    );
    assert_eq!(doc.equations()[2].value, 35.0);
    // a driven dimension is the equation's
    let e = doc.set_dimension("D1@lift", 5.0).unwrap_err().to_string();
    assert!(e.contains("driven by equation [2]"), "{e}");
    // an equation using a dimension nothing drives reads it at its value
    doc.set_equation(1, "\"Clearance\" = \"D1@lift\" / 7")
        .unwrap();
    assert_eq!(doc.global_variable("Clearance").unwrap(), 5.0);
    // added at an index; deleted: what it set keeps its value
    doc.add_equation(Some(0), "\"Spare\" = sin(30) * 2 + (10 - 5)")
        .unwrap();
    assert!((doc.equations()[0].value - 6.0).abs() < 1e-12);
    doc.delete_equation(3).unwrap(); // "D1@lift" = 10 * "Factor"
    assert_eq!(doc.dimension("D1@lift").unwrap().value, 35.0);
    doc.set_dimension("D1@lift", 12.0).unwrap();
    assert!((z_of(&doc, "plate") - 762.0).abs() < 1e-6);
}

#[test]
fn equations_are_saved_and_reload_to_the_same_values() {
    let (_dir, path) = lift(|t| t);
    let mut doc = Document::open(&path).unwrap();
    doc.set_global_variable("Factor", 1.25).unwrap();
    doc.add_equation(None, "\"Half\" = \"Factor\" / 2").unwrap();
    doc.save().unwrap();
    let again = Document::open(&path).unwrap();
    let texts = |d: &Document| d.equations().iter().map(|e| e.text()).collect::<Vec<_>>();
    assert_eq!(texts(&again), texts(&doc));
    assert_eq!(texts(&again)[0], "\"Factor\" = 1.25");
    assert_eq!(again.global_variable("Half").unwrap(), 0.625);
    assert_eq!(again.dimension("D1@lift").unwrap().value, 12.5);
    assert!((z_of(&again, "plate") - 762.5).abs() < 1e-6);
}

/// Each refused equation in a file: located at its own line, naming the equation and
/// the cause.
#[test]
fn a_bad_equation_in_a_file_is_located_with_its_cause() {
    let cases: &[(&[&str], &str, &str)] = &[
        (
            &["\"Factor\" = 2", "\"D1@lift\" = 10 * \"Factr\""],
            "Factr",
            "unknown name \"Factr\"",
        ),
        (
            &["\"A\" = \"B\" + 1", "\"B\" = \"A\" * 2"],
            "\"A\" = \"B\"",
            "circular: \"A\" uses \"B\" uses \"A\"",
        ),
        (
            &["\"Zero\" = 0", "\"D1@lift\" = 10 / \"Zero\""],
            "10 / ",
            "division by zero",
        ),
        (
            &["\"D1@lift\" = sqr(-4)"],
            "sqr",
            "sqr(-4) is not a finite number",
        ),
        (&["\"D1@lift\" = -3"], "-3", "a distance cannot be negative"),
        (
            &["\"D1@nothing\" = 3"],
            "nothing",
            "not a dimension of this document",
        ),
        (
            &["\"Factor\" = 2", "\"Factor\" = 3"],
            "= 3",
            "set by equation [0] already",
        ),
        (&["\"Factor\" = 2 +"], "2 +", "syntax at column 15"),
        (&["\"Factor\" = 1e200 ^ 2"], "1e200", "not a finite number"),
    ];
    for (list, needle, cause) in cases {
        let (_dir, path) = with_equations(list);
        let e = Document::open(&path).unwrap_err();
        let at = e
            .location()
            .unwrap_or_else(|| panic!("{list:?}: not located: {e}"));
        assert_eq!(at.line, Some(line_of(&path, needle)), "{list:?}: {e}");
        let shown = e.to_string();
        assert!(shown.contains(cause), "{list:?}: {shown}");
        assert!(shown.contains("lift.yaml:"), "{list:?}: {shown}");
        assert!(shown.contains("equation ["), "{list:?}: {shown}");
    }
}

#[test]
fn a_refused_change_changes_nothing() {
    let (_dir, path) = lift(|t| t);
    let mut doc = Document::open(&path).unwrap();
    let before = (doc.to_yaml(), z_of(&doc, "plate"));
    for bad in [
        "\"Factor\" = \"D1@lift\"", // circular through D1@lift
        "\"Factor\" = 1 / 0",       // division by zero
        "\"Factor\" = -4",          // D1@lift = -40: a negative distance
        "\"Factor\" = \"Nope\"",    // unknown
    ] {
        let e = doc.set_equation(0, bad).unwrap_err();
        assert!(matches!(e, DocumentError::Equation { .. }), "{bad}: {e}");
        assert_eq!((doc.to_yaml(), z_of(&doc, "plate")), before, "{bad}");
    }
    match doc.add_equation(None, "\"D1@lift\" = 3").unwrap_err() {
        DocumentError::Equation { source, .. } => {
            assert!(matches!(
                source.cause,
                EquationCause::SetTwice { first: 2, .. }
            ))
        }
        e => panic!("{e}"),
    }
    assert!(
        doc.set_global_variable("D1@lift", 3.0).is_err(),
        "not a global variable"
    );
    assert!(doc.set_global_variable("Factor", f64::NAN).is_err());
    // a mate whose dimension an equation drives is not deleted under it
    let e = doc.delete_mate("lift").unwrap_err().to_string();
    assert!(e.contains("equation [2]"), "{e}");
    assert_eq!((doc.to_yaml(), z_of(&doc, "plate")), before);
}

#[test]
fn long_chains_and_too_many_equations_are_bounded() {
    // a chain of 1000 equations evaluates without recursion, in dependency order
    // even when written backwards
    let mut list: Vec<String> = (1..1000)
        .rev()
        .map(|i| format!("\"v{i}\" = \"v{}\" + 1", i - 1))
        .collect();
    list.push("\"v0\" = 1".into());
    let refs: Vec<&str> = list.iter().map(String::as_str).collect();
    let (_dir, path) = with_equations(&refs);
    let doc = Document::open(&path).unwrap();
    assert_eq!(doc.global_variable("v999").unwrap(), 1000.0);
    // one more is refused, at the first equation past the bound
    list.push("\"w\" = 1".into());
    let refs: Vec<&str> = list.iter().map(String::as_str).collect();
    let (_dir, path) = with_equations(&refs);
    let e = Document::open(&path).unwrap_err();
    assert!(e.to_string().contains("at most 1000"), "{e}");
    assert_eq!(
        e.location().unwrap().line,
        Some(line_of(&path, "\"w\" = 1"))
    );
}

/// A project holding `models/mz07.yaml` (the repository's robot) with the equations
/// `list` (`{J2}` stands for the full name of its second joint's dimension).
fn mz07_with(list: &[&str]) -> (tempfile::TempDir, PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(dir.path().join("models/meshes")).unwrap();
    std::fs::create_dir_all(dir.path().join("scripts")).unwrap();
    let models = common::repo().join("models");
    for e in std::fs::read_dir(models.join("meshes")).unwrap() {
        let e = e.unwrap();
        if e.file_name().to_string_lossy().starts_with("mz07_") {
            std::fs::copy(
                e.path(),
                dir.path().join("models/meshes").join(e.file_name()),
            )
            .unwrap();
        }
    }
    let path = dir.path().join("models/mz07.yaml");
    let text = std::fs::read_to_string(models.join("mz07.yaml")).unwrap();
    std::fs::write(&path, &text).unwrap();
    let j2 = Document::open(&path).unwrap().robots()[0].dimension_names()[1].clone();
    let mut out = format!("{text}equations:\n");
    for e in list {
        out.push_str(&format!("- '{}'\n", e.replace("{J2}", &j2)));
    }
    std::fs::write(&path, out).unwrap();
    (dir, path, j2)
}

/// Issue 37: a robot joint whose dimension an equation drives cannot be set by hand
/// (SolidWorks refuses to edit a driven dimension): `set_robot_joints` and the
/// dimension setters are refused naming the equation, from Rust and Rhai; the other
/// joints still move, and the equation moves the driven one.
#[test]
fn a_joint_an_equation_drives_is_refused_naming_the_equation() {
    let (dir, path, j2) = mz07_with(&["\"Lean\" = 20", "\"{J2}\" = \"Lean\" + 5deg"]);
    let mut doc = Document::open(&path).unwrap();
    let q = doc.robots()[0].joints().to_vec();
    assert!((q[1].to_degrees() - 25.0).abs() < 1e-9, "{q:?}");
    let mut moved = q.clone();
    moved[1] += 0.1;
    let e = doc.set_robot_joints(0, &moved).unwrap_err();
    match &e {
        DocumentError::DrivenByEquation {
            dimension,
            index,
            equation,
            joint,
        } => {
            assert_eq!((dimension.as_str(), *index), (j2.as_str(), 1));
            assert!(equation.contains("\"Lean\" + 5deg"), "{equation}");
            assert!(joint.as_deref().unwrap().contains("joint 2"), "{joint:?}");
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("change the equation"), "{e}");
    assert_eq!(doc.robots()[0].joints(), &q[..], "nothing moved");
    // The dimension setters say the same.
    let e = doc.set_dimension(&j2, 0.2).unwrap_err();
    assert!(
        matches!(e, DocumentError::DrivenByEquation { index: 1, .. }),
        "{e}"
    );
    // Another joint moves; the driven one may be passed at its value.
    let mut other = q.clone();
    other[0] += 0.2;
    doc.set_robot_joints(0, &other).unwrap();
    assert_eq!(doc.robots()[0].joints()[0], q[0] + 0.2);
    // The equation moves it.
    doc.set_global_variable("Lean", 30.0).unwrap();
    assert!((doc.robots()[0].joints()[1].to_degrees() - 35.0).abs() < 1e-9);

    // Rhai: the same refusal, as a script error naming the equation.
    std::fs::write(
        dir.path().join("scripts/lean.rhai"),
        "let doc = open_doc(\"models/mz07.yaml\");\nlet r = doc.robot(\"mz07\");\nlet q = r.joints;\nq[0] = q[0] + 5.0;\nr.joints = q;\nprint(\"moved\");\nq[1] = 0.0;\nr.joints = q;\n",
    )
    .unwrap();
    let o = common::run_in(dir.path(), &["run", "scripts/lean.rhai"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("moved"), "{t}");
    assert!(
        t.contains(&format!("dimension `{j2}`")) && t.contains("equation [1]"),
        "{t}"
    );
    assert!(t.contains("lean.rhai:8"), "located at the line: {t}");
}
