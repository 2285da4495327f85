//! `fitup import FILE.step` (issue 24, STEP): the STEP files are made in the tests by
//! Open CASCADE itself (`fitup::mesh::step::write_test_step`), never committed. The
//! tests that need OCCT run with `--features step`
//! (`cargo test --features step --test it step_import::`); the default build checks
//! the "rebuild with --features step" answer.

use crate::common;

/// A part whose `stl:` names a STEP file says how to import it (and, without the
/// feature, how to rebuild), at the `stl:` line.
#[test]
fn a_step_file_as_a_part_mesh_says_how_to_import_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("arm.step"),
        "ISO-10303-21;\nHEADER;\nENDSEC;\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("cell.yaml"),
        "parts:\n  arm:\n    stl: arm.step\ncomponents:\n  - {name: arm-1, part: arm}\n",
    )
    .unwrap();
    let o = common::run_in(dir.path(), &["check", "cell.yaml"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("cell.yaml:3"), "at the stl: line: {t}");
    assert!(t.contains("fitup import"), "{t}");
    if !fitup::mesh::step::AVAILABLE {
        assert!(t.contains("--features step"), "{t}");
    }
    assert!(!t.contains("panicked"), "{t}");
}

#[cfg(not(feature = "step"))]
#[test]
fn without_the_feature_a_step_file_asks_for_a_rebuild() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("arm.step"),
        "ISO-10303-21;\nHEADER;\nENDSEC;\n",
    )
    .unwrap();
    let before = common::snapshot(dir.path());
    let o = common::run_in(dir.path(), &["import", "arm.step", "--out", "arm"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("arm.step"), "names the file: {t}");
    assert!(
        t.contains("cargo install --path . --features step"),
        "says how to rebuild: {t}"
    );
    assert!(!t.contains("panicked"), "{t}");
    assert_eq!(common::snapshot(dir.path()), before, "nothing written");
    // The library says the same.
    let e = fitup::mesh::step::read_step(
        &dir.path().join("arm.step"),
        &fitup::mesh::step::StepOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, fitup::mesh::step::StepError::NotBuilt { .. }),
        "{e}"
    );
}

#[cfg(feature = "step")]
mod with_occt {
    use super::*;
    use fitup::document::Document;
    use fitup::math::{Point3, Transform, Vec3};
    use fitup::mesh::step::{read_step, write_test_step, StepError, StepOptions};
    use std::f64::consts::PI;
    use std::path::Path;

    fn made(dir: &Path, kind: &str) -> std::path::PathBuf {
        let path = dir.join(format!("{kind}.step"));
        write_test_step(kind, &path).unwrap();
        path
    }

    fn no_leftovers(dir: &Path) {
        for e in std::fs::read_dir(dir).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            assert!(!name.starts_with(".fitup-"), "left behind: {name}");
        }
    }

    /// Every kind of test file is a STEP file; with `FITUP_STEP_SAMPLES=DIR` they are
    /// written there (the files docs/performance.md measures).
    #[test]
    fn every_test_file_kind_is_a_step_file() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = std::env::var_os("FITUP_STEP_SAMPLES")
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| tmp.path().to_path_buf());
        std::fs::create_dir_all(&dir).unwrap();
        for kind in [
            "box",
            "cylinder_hole",
            "assembly",
            "inch_box",
            "open_shell",
            "no_solid",
        ] {
            let text = std::fs::read_to_string(made(&dir, kind)).unwrap();
            assert!(text.starts_with("ISO-10303-21;"), "{kind}");
            assert!(text.trim_end().ends_with("END-ISO-10303-21;"), "{kind}");
        }
        let e = write_test_step("sphere", &dir.join("x.step")).unwrap_err();
        assert!(e.to_string().contains("unknown test file kind"), "{e}");
    }

    #[test]
    fn a_box_is_one_closed_part_with_its_exact_volume() {
        let dir = tempfile::tempdir().unwrap();
        let file = made(dir.path(), "box");
        let m = read_step(&file, &StepOptions::default()).unwrap();
        assert_eq!((m.parts.len(), m.instances.len()), (1, 1));
        let p = &m.parts[0];
        assert_eq!(p.product, "block");
        assert!(p.mesh.inspect().is_watertight());
        assert!((p.exact_volume - 1000.0).abs() < 1e-6, "{}", p.exact_volume);
        assert!((p.mesh.signed_volume() - 1000.0).abs() < 1e-6);
        let b = p.mesh.bounds().unwrap();
        assert!((b.hi - Point3::new(20.0, 10.0, 5.0)).norm() < 1e-9, "{b:?}");
        assert!(m.instances[0]
            .transform
            .approx_eq(&Transform::IDENTITY, 1e-12, 1e-12));
        assert_eq!(m.file_unit.to_ascii_uppercase(), "MILLIMETRE");

        // The command: a new project, the document loads, `fitup check` passes.
        let o = common::run_in(dir.path(), &["import", "box.step", "--out", "cell"]);
        assert!(o.status.success(), "{}", common::short_text(&o));
        let out = dir.path().join("cell");
        assert!(out.join("fitup.toml").is_file());
        assert!(out.join("meshes/block.stl").is_file());
        let doc = Document::open(&out.join("box.yaml")).unwrap();
        assert_eq!(doc.components().len(), 1);
        assert!(doc.part("block").unwrap().mesh.inspect().is_watertight());
        let d = doc.description().unwrap();
        assert!(d.contains("linear deflection 0.1 mm"), "{d}");
        let o = common::run_in(&out, &["check", "box.yaml"]);
        assert!(o.status.success(), "{}", common::short_text(&o));
        assert!(
            !common::text(&o).contains("warning"),
            "{}",
            common::text(&o)
        );
        no_leftovers(dir.path());
    }

    #[test]
    fn a_cylinder_with_a_hole_is_within_one_and_a_half_percent_of_analytic() {
        let dir = tempfile::tempdir().unwrap();
        let file = made(dir.path(), "cylinder_hole");
        let analytic = PI * (10.0f64.powi(2) - 3.0f64.powi(2)) * 20.0;
        for deflection in [0.1, 0.01] {
            let o = StepOptions {
                linear_deflection: deflection,
                ..StepOptions::default()
            };
            let m = read_step(&file, &o).unwrap();
            let p = &m.parts[0];
            assert_eq!(p.product, "bushing");
            let r = p.mesh.inspect();
            assert!(r.is_watertight(), "{r:?}");
            assert!(
                (p.exact_volume / analytic - 1.0).abs() < 1e-6,
                "{}",
                p.exact_volume
            );
            let ratio = p.mesh.signed_volume() / analytic;
            assert!(
                (ratio - 1.0).abs() < 0.015,
                "deflection {deflection}: ratio {ratio}"
            );
            assert!((p.volume_ratio() - ratio).abs() < 1e-6);
            if deflection == 0.01 {
                assert!((ratio - 1.0).abs() < 0.002, "finer is closer: {ratio}");
            }
        }
    }

    fn translation_of(doc: &Document, name: &str) -> (Vec3, Transform) {
        let t = doc.component(name).unwrap().transform;
        (t.translation(), t)
    }

    #[test]
    fn an_assembly_keeps_names_placements_and_shared_solids() {
        let dir = tempfile::tempdir().unwrap();
        made(dir.path(), "assembly");
        let o = common::run_in(
            dir.path(),
            &[
                "import",
                "assembly.step",
                "--out",
                "cell",
                "--deflection",
                "0.05",
            ],
        );
        let t = common::text(&o);
        assert!(o.status.success(), "{t}");
        assert!(t.contains("2 parts, 4 components"), "{t}");
        let doc_path = dir.path().join("cell/assembly.yaml");
        let doc = Document::open(&doc_path).unwrap();
        // One part per distinct solid: the peg is meshed once, placed three times.
        let mut parts: Vec<_> = doc.parts().map(|p| p.name.clone()).collect();
        parts.sort();
        assert_eq!(parts, ["peg", "plate"]);
        let stls = std::fs::read_dir(dir.path().join("cell/meshes"))
            .unwrap()
            .count();
        assert_eq!(stls, 2);
        let names: Vec<_> = doc.components().iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["plate-1", "peg-1", "peg-2", "peg-3"]);
        assert!(doc.components()[1..].iter().all(|c| c.part == "peg"));
        // Placements: the sub-assembly's 10 mm composed with each peg's own.
        let near = |a: Vec3, b: [f64; 3]| (a - Vec3::from(b)).norm() < 1e-9;
        assert!(near(translation_of(&doc, "plate-1").0, [0.0, 0.0, 0.0]));
        assert!(near(translation_of(&doc, "peg-1").0, [20.0, 30.0, 10.0]));
        assert!(near(translation_of(&doc, "peg-2").0, [80.0, 30.0, 10.0]));
        let (at, lying) = translation_of(&doc, "peg-3");
        assert!(near(at, [50.0, 45.0, 14.0]), "{at}");
        let expected =
            Transform::from_rotation_about(Point3::new(0.0, 0.0, 0.0), Vec3::x(), PI / 2.0)
                .unwrap()
                .then(&Transform::from_translation(Vec3::new(50.0, 45.0, 14.0)));
        assert!(lying.approx_eq(&expected, 1e-9, 1e-9), "{lying}");
        // The lying peg's axis runs along -Y in the world: its tip is at y = 45 - 30.
        let tip = lying.apply(&Point3::new(0.0, 0.0, 30.0));
        assert!((tip - Point3::new(50.0, 15.0, 14.0)).norm() < 1e-9, "{tip}");
        for p in doc.parts() {
            assert!(p.mesh.inspect().is_watertight(), "{}", p.name);
        }

        // A mate-free imported assembly goes straight into sequence planning.
        let o = common::run_in(
            &dir.path().join("cell"),
            &[
                "plan-sequence",
                "assembly.yaml",
                "--mode",
                "geometry",
                "--json",
            ],
        );
        let t = common::text(&o);
        assert!(o.status.success(), "{}", common::short_text(&o));
        for c in ["plate-1", "peg-1", "peg-2", "peg-3"] {
            assert!(t.contains(c), "{c} planned: {t}");
        }
    }

    #[test]
    fn an_inch_file_is_read_in_millimetres() {
        let dir = tempfile::tempdir().unwrap();
        let file = made(dir.path(), "inch_box");
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.contains("INCH"), "the file is in inches");
        let m = read_step(&file, &StepOptions::default()).unwrap();
        assert_eq!(m.file_unit.to_ascii_uppercase(), "INCH");
        let b = m.parts[0].mesh.bounds().unwrap();
        let size = b.hi - b.lo;
        assert!((size - Vec3::new(25.4, 50.8, 76.2)).norm() < 1e-6, "{size}");
        let in3 = 25.4f64.powi(3);
        assert!((m.parts[0].exact_volume / (6.0 * in3) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn an_open_shell_is_a_located_error_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        made(dir.path(), "open_shell");
        let before = common::snapshot(dir.path());
        let o = common::run_in(dir.path(), &["import", "open_shell.step", "--out", "cell"]);
        let t = common::text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(t.contains("open_shell.step"), "{t}");
        assert!(t.contains("lidless") && t.contains("not closed"), "{t}");
        assert!(t.contains("open"), "{t}");
        assert_eq!(common::snapshot(dir.path()), before);
        assert!(!dir.path().join("cell").exists());
        no_leftovers(dir.path());
    }

    #[test]
    fn bad_files_are_refused_with_their_cause() {
        let dir = tempfile::tempdir().unwrap();
        let no_solid = made(dir.path(), "no_solid");
        let e = read_step(&no_solid, &StepOptions::default()).unwrap_err();
        assert!(matches!(e, StepError::NoSolids { .. }), "{e}");
        assert!(e.to_string().contains("no solid"), "{e}");

        let text = dir.path().join("notes.step");
        std::fs::write(&text, "these are my notes\n").unwrap();
        let e = read_step(&text, &StepOptions::default()).unwrap_err();
        assert!(
            e.to_string().contains("notes.step:1: not a STEP file"),
            "{e}"
        );

        // A syntactically broken STEP body.
        let broken = dir.path().join("broken.step");
        std::fs::write(&broken, "ISO-10303-21;\nHEADER;\n#1=((((;\n").unwrap();
        let started = std::time::Instant::now();
        let e = read_step(&broken, &StepOptions::default()).unwrap_err();
        assert!(e.to_string().contains("broken.step"), "{e}");
        assert!(started.elapsed().as_secs() < 30);

        // Over the size cap: refused before Open CASCADE reads a byte (sparse file).
        let huge = dir.path().join("huge.step");
        std::fs::File::create(&huge)
            .unwrap()
            .set_len((64 << 20) + 1)
            .unwrap();
        let started = std::time::Instant::now();
        let e = read_step(&huge, &StepOptions::default()).unwrap_err();
        assert!(e.to_string().contains("64 MiB limit"), "{e}");
        assert!(started.elapsed().as_secs() < 5);

        // A folder and a FIFO are not read.
        let e = read_step(dir.path(), &StepOptions::default()).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");

        // Options out of range.
        let bad = StepOptions {
            linear_deflection: 0.0,
            ..StepOptions::default()
        };
        let e = read_step(&made(dir.path(), "box"), &bad).unwrap_err();
        assert!(matches!(e, StepError::Option { .. }), "{e}");

        // The time limit stops the transfer or the meshing cleanly.
        let tight = StepOptions {
            time_limit: std::time::Duration::from_nanos(1),
            ..StepOptions::default()
        };
        let e = read_step(&made(dir.path(), "assembly"), &tight).unwrap_err();
        assert!(e.to_string().contains("time limit"), "{e}");
    }

    #[test]
    fn an_existing_project_keeps_its_files_unless_forced() {
        let dir = common::project();
        made(dir.path(), "box");
        let o = common::run_in(dir.path(), &["import", "box.step", "--out", "models"]);
        assert!(o.status.success(), "{}", common::short_text(&o));
        // Added beside the demo cell, no second fitup.toml.
        assert!(dir.path().join("models/box.yaml").is_file());
        assert!(dir.path().join("models/cell.yaml").is_file());
        assert!(!dir.path().join("models/fitup.toml").exists());
        let before = common::snapshot(dir.path());
        let o = common::run_in(dir.path(), &["import", "box.step", "--out", "models"]);
        let t = common::text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(t.contains("refusing to overwrite"), "{t}");
        assert_eq!(common::snapshot(dir.path()), before, "nothing changed");
        let o = common::run_in(
            dir.path(),
            &["import", "box.step", "--out", "models", "--force"],
        );
        assert!(o.status.success(), "{}", common::short_text(&o));
        assert!(Document::open(&dir.path().join("models/box.yaml")).is_ok());
    }
}

/// README's "Importing a STEP assembly" section, run as written (its `fitup` lines in
/// order, its script saved where the commands expect it) on an assembly made by OCCT.
#[cfg(feature = "step")]
#[test]
fn the_readme_step_workflow_runs_as_documented() {
    let readme = std::fs::read_to_string(common::repo().join("README.md")).unwrap();
    let section = readme
        .split("## Importing a STEP assembly")
        .nth(1)
        .expect("README has the section")
        .split("\n## ")
        .next()
        .unwrap();
    let block = |lang: &str| -> String {
        let start = section.find(&format!("```{lang}\n")).unwrap() + lang.len() + 4;
        let len = section[start..].find("```").unwrap();
        section[start..start + len].to_string()
    };
    let dir = tempfile::tempdir().unwrap();
    fitup::mesh::step::write_test_step("assembly", &dir.path().join("bracket_asm.step")).unwrap();
    let commands: Vec<String> = block("sh")
        .lines()
        .filter(|l| l.starts_with("fitup "))
        .map(|l| l.split(" #").next().unwrap().trim().to_string())
        .collect();
    assert_eq!(commands.len(), 4, "{commands:?}");
    for (i, line) in commands.iter().enumerate() {
        if line.starts_with("fitup run ") {
            std::fs::write(dir.path().join("bracket/check_fit.rhai"), block("rhai")).unwrap();
        }
        let args: Vec<&str> = line.split_whitespace().skip(1).collect();
        let o = common::run_in(dir.path(), &args);
        let t = common::text(&o);
        assert!(o.status.success(), "`{line}`: {}", common::short_text(&o));
        if i == 0 {
            assert!(dir.path().join("bracket/fitup.toml").is_file());
        }
        if line.starts_with("fitup run ") {
            assert!(t.contains("4 components, 2 distinct parts"), "{t}");
            assert!(t.contains("0 interfering pairs"), "{t}");
        }
    }
}
