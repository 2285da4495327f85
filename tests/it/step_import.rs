//! `fitup import FILE.step` (issue 24, STEP): the STEP files are made in the tests by
//! Open CASCADE itself (`fitup::mesh::step::write_test_step`), never committed. The
//! tests that need OCCT run with `--features step`, in the `step` binary
//! (`cargo test --features step --test step step_import::`); the default build checks
//! the "rebuild with --features step" answer (in `it`).

use crate::common;

/// `arm.step` (a STEP header and nothing else) and `cell.yaml`, whose part `arm` names
/// it with `key` (`stl` or `step`) on line 3.
fn fake_step_cell(dir: &std::path::Path, key: &str) {
    std::fs::write(dir.join("arm.step"), "ISO-10303-21;\nHEADER;\nENDSEC;\n").unwrap();
    std::fs::write(
        dir.join("cell.yaml"),
        format!(
            "parts:\n  arm:\n    {key}: arm.step\ncomponents:\n  - {{name: arm-1, part: arm}}\n"
        ),
    )
    .unwrap();
}

/// `fitup check cell.yaml` in `dir` fails at the `key:` line (3): its output.
fn refused_at_line_3(dir: &std::path::Path, key: &str) -> String {
    let o = common::run_in(dir, &["check", "cell.yaml"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("cell.yaml:3"), "at the {key}: line: {t}");
    t
}

/// A part whose `stl:` names a STEP file says how to import it (and, without the
/// feature, how to rebuild), at the `stl:` line.
#[test]
fn a_step_file_as_a_part_mesh_says_how_to_import_it() {
    let dir = tempfile::tempdir().unwrap();
    fake_step_cell(dir.path(), "stl");
    let t = refused_at_line_3(dir.path(), "stl");
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
    use fitup::mesh::step::{
        read_step, write_test_step, OcctFailure, StepError, StepOptions, StepStage,
    };
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
            "nested",
            "roots",
            "inch_box",
            "open_shell",
            "no_solid",
            "bad_face",
            "plate_holes",
            "sphere",
            "cone",
        ] {
            let text = std::fs::read_to_string(made(&dir, kind)).unwrap();
            assert!(text.starts_with("ISO-10303-21;"), "{kind}");
            assert!(text.trim_end().ends_with("END-ISO-10303-21;"), "{kind}");
        }
        let e = write_test_step("torus", &dir.join("x.step")).unwrap_err();
        assert!(e.to_string().contains("unknown test file kind"), "{e}");
        assert!(
            matches!(
                &e,
                StepError::Occt {
                    failure: OcctFailure::Exception { kind, detail },
                    ..
                } if kind == "write" && detail == "unknown test file kind torus"
            ),
            "{e:?}"
        );
    }

    /// Open CASCADE meshes a sphere's poles and a cone's apex with several nodes at
    /// one point; welded, their triangles collapse. Both solids import closed, at
    /// their exact volumes, at several tessellations (issue 38: such solids were
    /// refused as "non-manifold").
    #[test]
    fn poles_and_apexes_import_closed() {
        let dir = tempfile::tempdir().unwrap();
        for (kind, exact) in [
            ("sphere", 4.0 / 3.0 * std::f64::consts::PI * 1000.0),
            ("cone", std::f64::consts::PI * 64.0 * 15.0 / 3.0),
        ] {
            let file = made(dir.path(), kind);
            for deflection in [0.5, 0.1, 0.01] {
                let o = StepOptions {
                    linear_deflection: deflection,
                    ..StepOptions::default()
                };
                let m = read_step(&file, &o).unwrap_or_else(|e| panic!("{kind} {deflection}: {e}"));
                let p = &m.parts[0];
                let report = p.mesh.inspect();
                assert!(report.is_watertight(), "{kind} {deflection}: {report:?}");
                assert_eq!(report.degenerate_triangles, 0, "{kind} {deflection}");
                assert!((p.exact_volume - exact).abs() < 1e-6 * exact, "{kind}");
                let v = p.mesh.signed_volume() / exact;
                assert!(v > 0.9 && v <= 1.0 + 1e-9, "{kind} {deflection}: {v}");
            }
        }
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
        // The sub-assembly `pegs-1` is kept (issue 37): its pegs are named inside it.
        let names: Vec<_> = doc.components().iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["plate-1", "pegs-1/peg-1", "pegs-1/peg-2", "peg-3"]);
        assert_eq!(
            doc.children(Some("pegs-1")).unwrap(),
            ["pegs-1/peg-1", "pegs-1/peg-2"]
        );
        assert!(doc.components()[1..].iter().all(|c| c.part == "peg"));
        // Placements: the sub-assembly's 10 mm composed with each peg's own.
        let near = |a: Vec3, b: [f64; 3]| (a - Vec3::from(b)).norm() < 1e-9;
        assert!(near(
            doc.sub_assembly("pegs-1").unwrap().transform.translation(),
            [0.0, 0.0, 10.0]
        ));
        assert!(near(translation_of(&doc, "plate-1").0, [0.0, 0.0, 0.0]));
        assert!(near(
            translation_of(&doc, "pegs-1/peg-1").0,
            [20.0, 30.0, 10.0]
        ));
        assert!(near(
            translation_of(&doc, "pegs-1/peg-2").0,
            [80.0, 30.0, 10.0]
        ));
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
        for c in ["plate-1", "pegs-1/peg-1", "pegs-1/peg-2", "peg-3"] {
            assert!(t.contains(c), "{c} planned: {t}");
        }
    }

    /// A transform about `axis` by `deg` degrees, then moved by `at` (mm): the
    /// generator's `pose` in cpp/step_shim.cpp (kind `nested`).
    fn pose(axis: [f64; 3], deg: f64, at: [f64; 3]) -> Transform {
        Transform::from_rotation_about(Point3::origin(), Vec3::from(axis), deg.to_radians())
            .unwrap()
            .then(&Transform::from_translation(Vec3::from(at)))
    }

    /// Issue 37: a STEP assembly with nested sub-assemblies imports with its tree —
    /// sub-assemblies at every level, full names `Frame-1/Axle-2/Wheel-1`, occurrences
    /// SolidWorks names `NAUO<n>` named as its tree names them — and every component
    /// and sub-assembly where Open CASCADE's own reading (occt_check, no fitup code)
    /// places it, composed through three levels; a save and a reload keep it all.
    #[test]
    fn nested_assemblies_import_with_their_tree() {
        let dir = tempfile::tempdir().unwrap();
        let file = made(dir.path(), "nested");
        let o = common::run_in(dir.path(), &["import", "nested.step", "--out", "cart"]);
        let t = common::text(&o);
        assert!(o.status.success(), "{t}");
        assert!(t.contains("3 parts, 18 components"), "{t}");
        let doc_path = dir.path().join("cart/nested.yaml");
        let doc = Document::open(&doc_path).unwrap();
        let subs: Vec<_> = doc
            .sub_assemblies()
            .iter()
            .map(|a| a.name.as_str())
            .collect();
        assert_eq!(
            subs,
            [
                "Frame-1",
                "Frame-1/Axle-1",
                "Frame-1/Axle-2",
                "Frame-2",
                "Frame-2/Axle-1",
                "Frame-2/Axle-2",
                "axle_asm-1",
            ]
        );
        assert_eq!(
            doc.children(Some("Frame-2/Axle-1")).unwrap(),
            [
                "Frame-2/Axle-1/bar-1",
                "Frame-2/Axle-1/Wheel-1",
                "Frame-2/Axle-1/Wheel-2"
            ]
        );
        assert_eq!(
            doc.children(None).unwrap(),
            ["Frame-1", "Frame-2", "axle_asm-1", "wheel-1"]
        );
        assert_eq!(
            doc.parent_of("Frame-1/Axle-2/Wheel-1").unwrap().as_deref(),
            Some("Frame-1/Axle-2")
        );
        // One part per distinct solid, whatever the level.
        let mut parts: Vec<_> = doc.parts().map(|p| p.name.clone()).collect();
        parts.sort();
        assert_eq!(parts, ["axle_bar", "frame_plate", "wheel"]);

        // Composed by hand from the generator's placements: Frame-1 ∘ Axle-2 ∘ Wheel-1.
        let frame1 = pose([0.0, 0.0, 1.0], 45.0, [0.0, 0.0, 20.0]);
        let axle2 = pose([1.0, 1.0, 0.0], -60.0, [90.0, 0.0, 5.0]);
        let wheel1 = pose([1.0, 0.0, 0.0], 180.0, [2.0, 2.0, 0.0]);
        let by_hand = wheel1.then(&axle2).then(&frame1);
        let got = doc.component("Frame-1/Axle-2/Wheel-1").unwrap().transform;
        assert!(got.approx_eq(&by_hand, 1e-9, 1e-9), "{got} vs {by_hand}");
        // Relative to its parent, each pose is the generator's own.
        let local = |name: &str| doc.local_transform(name).unwrap();
        assert!(local("Frame-1/Axle-2/Wheel-1").approx_eq(&wheel1, 1e-9, 1e-9));
        assert!(local("Frame-1/Axle-2").approx_eq(&axle2, 1e-9, 1e-9));
        assert!(local("Frame-1").approx_eq(&frame1, 1e-9, 1e-9));

        // Every placed solid and assembly as Open CASCADE reads the file.
        let reference = common::occt_check::read(&common::occt_check::program(), &file);
        assert_eq!(reference.solids.len(), doc.components().len());
        assert_eq!(
            reference.assemblies.len(),
            doc.sub_assemblies().len() + 1,
            "and the root"
        );
        // occt_check's paths start at the root `cart`, which is the document; the
        // occurrences the exporter names NAUO<n> are named as SolidWorks does.
        let name = |path: &str| {
            let inside = path.strip_prefix("cart/").unwrap();
            inside
                .replace("NAUO7", "wheel-1")
                .replace("NAUO8", "axle_asm-1")
        };
        let mut checked = 0;
        for s in &reference.solids {
            let c = doc.component(&name(&s.path)).unwrap();
            assert!(
                s.placed_as(&c.transform, 1e-9),
                "{}: {}",
                s.path,
                c.transform
            );
            assert!(c.part.starts_with(&s.product), "{} {}", c.part, s.product);
            checked += 1;
        }
        for a in reference.assemblies.iter().filter(|a| a.path != "cart") {
            let sub = doc.sub_assembly(&name(&a.path)).unwrap();
            assert!(
                a.placed_as(&sub.transform, 1e-9),
                "{}: {}",
                a.path,
                sub.transform
            );
            checked += 1;
        }
        assert_eq!(checked, 18 + 7);

        // A save and a reload keep the tree and the poses.
        let mut doc = doc;
        doc.save().unwrap();
        let again = Document::open(&doc_path).unwrap();
        for s in &reference.solids {
            let c = again.component(&name(&s.path)).unwrap();
            assert!(s.placed_as(&c.transform, 1e-9), "after a save: {}", s.path);
        }
        assert_eq!(again.sub_assemblies().len(), 7);
        let o = common::run_in(&dir.path().join("cart"), &["check", "nested.yaml"]);
        assert!(o.status.success(), "{}", common::short_text(&o));
    }

    /// Issue 37: a file with several free shapes — two root assemblies sharing one
    /// product name and a loose solid — has no root that is the document: each root
    /// is a sub-assembly at the top (the second named apart from the first), the
    /// loose solid a component at the top, and every component and sub-assembly is
    /// where Open CASCADE's own reading (occt_check) places it, in its order.
    #[test]
    fn several_root_shapes_import_side_by_side() {
        let dir = tempfile::tempdir().unwrap();
        let file = made(dir.path(), "roots");
        let o = common::run_in(dir.path(), &["import", "roots.step", "--out", "cell"]);
        let t = common::text(&o);
        assert!(o.status.success(), "{t}");
        let doc_path = dir.path().join("cell/roots.yaml");
        let doc = Document::open(&doc_path).unwrap();
        let subs: Vec<_> = doc
            .sub_assemblies()
            .iter()
            .map(|a| a.name.clone())
            .collect();
        let top = doc.children(None).unwrap();
        assert_eq!(top.len(), 3, "two roots and the loose solid: {top:?}");
        assert!(top.contains(&"loose".to_string()), "{top:?}");
        let roots: Vec<_> = top.iter().filter(|n| doc.sub_assembly(n).is_ok()).collect();
        assert_eq!(roots.len(), 2, "{top:?}");
        assert_ne!(roots[0], roots[1]);
        for r in &roots {
            assert!(r.starts_with("module"), "{r}");
            let kids = doc.children(Some(r.as_str())).unwrap();
            assert_eq!(kids.len(), 2, "{r}: {kids:?}");
            let pair = format!("{r}/pair-1");
            assert!(subs.contains(&pair), "{pair} in {subs:?}");
            assert_eq!(
                doc.children(Some(&pair)).unwrap(),
                [format!("{pair}/peg-1"), format!("{pair}/peg-2")]
            );
        }
        assert_eq!(subs.len(), 4, "{subs:?}");

        // By hand from the generator: the second module's pair-1 ∘ peg-2.
        let peg2 = pose([1.0, 0.0, 0.0], 90.0, [20.0, 0.0, 4.0]);
        let pair_in_second = pose([0.0, 1.0, 0.0], -45.0, [100.0, 50.0, 0.0]);
        let got = doc
            .component(&format!("{}/pair-1/peg-2", roots[1]))
            .unwrap()
            .transform;
        let by_hand = peg2.then(&pair_in_second);
        assert!(got.approx_eq(&by_hand, 1e-9, 1e-9), "{got} vs {by_hand}");

        // Open CASCADE's reading, in its order: solids, then assemblies (the roots
        // included: none of them is the document).
        let reference = common::occt_check::read(&common::occt_check::program(), &file);
        assert_eq!(reference.solids.len(), doc.components().len());
        assert_eq!(reference.solids.len(), 7);
        for (s, c) in reference.solids.iter().zip(doc.components()) {
            assert!(s.placed_as(&c.transform, 1e-9), "{}: {}", s.path, c.name);
            assert_eq!(
                c.name.split('/').count(),
                s.depth(),
                "{} {}",
                c.name,
                s.path
            );
            let leaf = s.path.rsplit('/').next().unwrap();
            assert!(c.name.ends_with(leaf), "{} for {}", c.name, s.path);
        }
        assert_eq!(reference.assemblies.len(), doc.sub_assemblies().len());
        for (a, sub) in reference.assemblies.iter().zip(doc.sub_assemblies()) {
            assert!(
                a.placed_as(&sub.transform, 1e-9),
                "{}: {}",
                a.path,
                sub.name
            );
            assert_eq!(sub.name.split('/').count(), a.depth(), "{}", sub.name);
        }

        // A save and a reload keep it.
        let mut doc = doc;
        doc.save().unwrap();
        let again = Document::open(&doc_path).unwrap();
        for (s, c) in reference.solids.iter().zip(again.components()) {
            assert!(s.placed_as(&c.transform, 1e-9), "after a save: {}", s.path);
        }
        assert_eq!(again.sub_assemblies().len(), 4);
    }

    /// The library's reading keeps the tree too: assemblies before what they hold,
    /// parents by index, placements composed (the root's is the identity here).
    #[test]
    fn read_step_gives_the_assembly_tree() {
        let dir = tempfile::tempdir().unwrap();
        let m = read_step(&made(dir.path(), "nested"), &StepOptions::default()).unwrap();
        let paths: Vec<_> = m.assemblies.iter().map(|a| a.path.as_str()).collect();
        assert_eq!(paths[..3], ["cart", "cart/Frame-1", "cart/Frame-1/Axle-1"]);
        assert_eq!(m.assemblies.len(), 8);
        assert_eq!(m.assemblies[0].parent, None);
        assert_eq!(m.assemblies[0].product, "cart");
        for (k, a) in m.assemblies.iter().enumerate().skip(1) {
            let p = a.parent.unwrap();
            assert!(p < k);
            assert!(a.path.starts_with(&format!("{}/", m.assemblies[p].path)));
        }
        for i in &m.instances {
            let p = i.parent.unwrap();
            assert_eq!(i.path, format!("{}/{}", m.assemblies[p].path, i.name));
        }
        // A single solid file has no assembly.
        let b = read_step(&made(dir.path(), "box"), &StepOptions::default()).unwrap();
        assert!(b.assemblies.is_empty());
        assert_eq!(b.instances[0].parent, None);
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
        // The shim says where it stopped (a cause code and its stage, not text).
        assert!(
            matches!(
                e,
                StepError::TimeLimit {
                    stage: StepStage::Transferring | StepStage::Meshing,
                    ..
                }
            ),
            "{e:?}"
        );
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

/// Without the feature, a `step:` part is refused at its `step:` line, naming the file
/// and the command that adds the feature.
#[cfg(not(feature = "step"))]
#[test]
fn without_the_feature_a_step_part_asks_for_a_rebuild() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("fitup.toml"), "").unwrap();
    fake_step_cell(dir.path(), "step");
    let before = common::snapshot(dir.path());
    let t = refused_at_line_3(dir.path(), "step");
    assert!(t.contains("arm.step"), "{t}");
    assert!(t.contains("cargo install --path . --features step"), "{t}");
    assert_eq!(common::snapshot(dir.path()), before, "nothing written");
}

/// A part whose geometry is its STEP file (`step:`): tessellated when the document
/// loads, kept in the project's tessellation store by content and tessellation, so
/// the next load reads no STEP; a damaged store file is read again, never trusted.
#[cfg(feature = "step")]
mod step_parts {
    use super::*;
    use crate::common::stored_tessellations as stored;
    use fitup::document::Document;
    use fitup::mesh::step::write_test_step;
    use std::f64::consts::PI;
    use std::path::{Path, PathBuf};

    /// `fitup.toml`, `parts/<kind>.step` and `cell.yaml` with part `p` made of it
    /// (plus `extra` lines under the part) and one component `p-1`.
    fn step_project(dir: &Path, kind: &str, extra: &str) -> PathBuf {
        std::fs::write(dir.join("fitup.toml"), "").unwrap();
        std::fs::create_dir_all(dir.join("parts")).unwrap();
        write_test_step(kind, &dir.join(format!("parts/{kind}.step"))).unwrap();
        let doc = dir.join("cell.yaml");
        std::fs::write(
            &doc,
            format!("parts:\n  p:\n    step: parts/{kind}.step\n{extra}components:\n  - {{name: p-1, part: p}}\n"),
        )
        .unwrap();
        doc
    }

    fn check(dir: &Path) -> String {
        common::run_ok(dir, &["check", "cell.yaml"])
    }

    #[test]
    fn a_step_part_is_tessellated_on_load_and_kept_in_the_store() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        let doc_path = step_project(p, "cylinder_hole", "    deflection: 0.05\n");
        let t = check(p);
        assert!(t.contains("parts/cylinder_hole.step"), "{t}");
        assert!(t.contains("tessellated now"), "{t}");
        assert_eq!(stored(p).len(), 1, "one stored tessellation");

        // The part: one closed mesh within 1.5 % of the analytic volume, from the
        // store this time (no Open CASCADE read).
        let doc = Document::open(&doc_path).unwrap();
        let part = doc.part("p").unwrap();
        let g = part.step.as_ref().expect("a STEP part");
        assert!(g.from_store);
        assert_eq!(g.deflection, Some(0.05));
        assert!(part.mesh.inspect().is_watertight());
        let analytic = PI * (10.0f64.powi(2) - 3.0f64.powi(2)) * 20.0;
        let ratio = part.mesh.signed_volume() / analytic;
        assert!((ratio - 1.0).abs() < 0.015, "{ratio}");
        assert!((g.volume_ratio - ratio).abs() < 1e-6);
        assert!(doc
            .source_files()
            .iter()
            .any(|f| f.ends_with("parts/cylinder_hole.step")));
        assert!(check(p).contains("stored tessellation"));

        // Saving keeps the `step:` key and the tessellation as written.
        let mut doc = doc;
        doc.save_as(&p.join("copy.yaml")).unwrap();
        let copy = std::fs::read_to_string(p.join("copy.yaml")).unwrap();
        assert!(copy.contains("step: parts/cylinder_hole.step"), "{copy}");
        assert!(
            copy.contains("deflection: 0.05") && !copy.contains("stl:"),
            "{copy}"
        );

        // Another deflection is another tessellation, kept beside the first.
        let yaml = std::fs::read_to_string(&doc_path).unwrap();
        std::fs::write(&doc_path, yaml.replace("0.05", "0.02")).unwrap();
        assert!(check(p).contains("tessellated now"));
        assert_eq!(stored(p).len(), 2);

        // A damaged store file is a miss: read again, and replaced.
        for f in stored(p) {
            let mut bytes = std::fs::read(&f).unwrap();
            bytes.truncate(bytes.len() / 2);
            std::fs::write(&f, bytes).unwrap();
        }
        assert!(check(p).contains("tessellated now"));
        assert!(check(p).contains("stored tessellation"));

        // A new export of the file (other bytes) is read, not served from the store.
        write_test_step("box", &p.join("parts/cylinder_hole.step")).unwrap();
        let t = check(p);
        assert!(
            t.contains("tessellated now") && t.contains("  12 triangles"),
            "{t}"
        );
    }

    /// Issue 37, capability 7: a script adds a part from a STEP file inside the
    /// project (`IAssemblyDoc.AddComponent5` of a STEP file) and places it: a `step:`
    /// part tessellated with the default deflection, kept in the store, within 1.5 %
    /// of the analytic volume, saved as `step:` and opened again from the store.
    #[test]
    fn a_script_adds_a_part_from_a_step_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        step_project(p, "box", "");
        write_test_step("cylinder_hole", &p.join("parts/tube.step")).unwrap();
        std::fs::create_dir_all(p.join("scripts")).unwrap();
        let out = common::run_script_in(
            p,
            "add.rhai",
            r#"
let doc = open_doc("cell.yaml");
assert(doc.add_part("tube", "parts/tube.step") == "tube", "named");
let c = doc.add_component("tube", translation(0, 0, 100));
assert(c.name == "tube-1", c.name);
assert(doc.part_file("tube") == "parts/tube.step", doc.part_file("tube"));
doc.save();
print(`${c.mass_properties().volume}`);
"#,
        );
        assert!(out.status.success(), "{}", common::text(&out));
        let v: f64 = String::from_utf8_lossy(&out.stdout).trim().parse().unwrap();
        let exact = PI * (10.0f64.powi(2) - 3.0f64.powi(2)) * 20.0;
        assert!(v < exact && v > 0.985 * exact, "{v} of {exact}");
        let yaml = std::fs::read_to_string(p.join("cell.yaml")).unwrap();
        assert!(yaml.contains("step: parts/tube.step"), "{yaml}");
        assert_eq!(stored(p).len(), 2, "both tessellations stored");
        let doc = Document::open(&p.join("cell.yaml")).unwrap();
        let part = doc.part("tube").unwrap();
        assert!(part.step.as_ref().is_some_and(|g| g.from_store));
        assert!(part.mesh.inspect().is_watertight());
        let z = doc.component("tube-1").unwrap().transform.translation().z;
        assert!((z - 100.0).abs() < 1e-12, "{z}");
    }

    /// An assembly file as one part: every solid at its placement, one closed mesh.
    #[test]
    fn an_assembly_file_as_a_part_is_all_its_solids_in_place() {
        let dir = tempfile::tempdir().unwrap();
        let doc = Document::open(&step_project(dir.path(), "assembly", "")).unwrap();
        let m = &doc.part("p").unwrap().mesh;
        assert!(m.inspect().is_watertight());
        // plate 100 × 60 × 10 and three pegs r 4 × 30 (chordal: a little less).
        let exact = 100.0 * 60.0 * 10.0 + 3.0 * PI * 16.0 * 30.0;
        let v = m.signed_volume();
        assert!(v < exact && v > 0.985 * exact, "{v} of {exact}");
        let b = m.bounds().unwrap();
        assert!((b.hi.z - 40.0).abs() < 1e-6, "pegs stand 10 mm up: {b:?}");
    }

    /// Part keys out of place are located errors.
    #[test]
    fn bad_step_part_keys_are_located() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        for (extra, needle) in [
            ("    stl: parts/box.stl\n", "not both"),
            ("    deflection: 0\n", "`deflection:` must be a number > 0"),
            ("    angle: 200\n", "below 180"),
        ] {
            step_project(p, "box", extra);
            let o = common::run_in(p, &["check", "cell.yaml"]);
            let t = common::text(&o);
            assert_eq!(o.status.code(), Some(1), "{t}");
            assert!(t.contains("cell.yaml:"), "{t}");
            assert!(t.contains(needle), "{needle}: {t}");
        }
        std::fs::write(
            p.join("cell.yaml"),
            "parts:\n  p:\n    stl: parts/box.stl\n    deflection: 0.1\ncomponents: []\n",
        )
        .unwrap();
        let o = common::run_in(p, &["check", "cell.yaml"]);
        assert!(common::text(&o).contains("tessellate a `step:` part"));
    }

    /// A face that does not mesh: the error names the solid and the face.
    #[test]
    fn a_face_that_does_not_mesh_names_its_solid_and_face() {
        use fitup::mesh::step::{read_step, StepError, StepOptions};
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("bad_face.step");
        write_test_step("bad_face", &file).unwrap();
        let e = read_step(&file, &StepOptions::default()).unwrap_err();
        match &e {
            StepError::UnmeshedFace {
                solid,
                faces,
                count,
                ..
            } => {
                assert_eq!(solid, "warped", "{e}");
                assert_eq!((*faces, *count), (6, 1), "{e}");
            }
            other => panic!("not an unmeshed face: {other}"),
        }
        let o = common::run_in(dir.path(), &["import", "bad_face.step", "--out", "out"]);
        let t = common::text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(
            t.contains("bad_face.step") && t.contains("solid `warped`: face"),
            "{t}"
        );
        assert!(!dir.path().join("out").exists());
    }
}

/// Open CASCADE in a child process: a crash, a hang or a memory blow-up on a hostile
/// file becomes a located error in bounded time and memory, and nothing is written.
#[cfg(all(feature = "step", unix))]
mod hostile {
    use super::*;
    use fitup::mesh::step::{
        read_step, write_test_step, ChildFailure, ChildReader, Isolation, OcctFailure, StepError,
        StepOptions,
    };
    use std::path::{Path, PathBuf};
    use std::time::{Duration, Instant};

    fn child(program: &Path, memory_limit: u64, time_limit: Duration) -> StepOptions {
        StepOptions {
            time_limit,
            isolation: Isolation::Child(ChildReader {
                program: program.into(),
                memory_limit,
            }),
            ..StepOptions::default()
        }
    }

    /// A shell script standing in for a child reader.
    fn stand_in(dir: &Path, name: &str, body: &str) -> PathBuf {
        use std::os::unix::fs::PermissionsExt;
        let p = dir.join(name);
        std::fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
        p
    }

    /// `read_step`, retried while the script is "busy" (another test thread forked
    /// while it was open for writing: ETXTBSY, not what is tested).
    fn read(file: &Path, o: &StepOptions) -> Result<fitup::mesh::step::StepModel, StepError> {
        for _ in 0..100 {
            match read_step(file, o) {
                Err(StepError::Child {
                    failure:
                        ChildFailure::Spawn {
                            kind: std::io::ErrorKind::ExecutableFileBusy,
                            ..
                        },
                    ..
                }) => std::thread::sleep(Duration::from_millis(20)),
                r => return r,
            }
        }
        panic!("the stand-in stayed busy")
    }

    #[test]
    fn the_child_reader_turns_crashes_hangs_and_exhaustion_into_errors() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("box.step");
        write_test_step("box", &file).unwrap();
        let fitup = PathBuf::from(env!("CARGO_BIN_EXE_fitup"));
        let limit = Duration::from_secs(20);

        // The real child reads what this process reads, and says its peak memory.
        let a = read(&file, &child(&fitup, 1 << 30, limit)).unwrap();
        let in_process = StepOptions {
            isolation: Isolation::InProcess,
            ..StepOptions::default()
        };
        let b = read_step(&file, &in_process).unwrap();
        assert_eq!(a.parts[0].mesh, b.parts[0].mesh);
        assert_eq!(a.instances.len(), b.instances.len());
        assert!(a.reader_peak_memory.is_some_and(|m| m > 1 << 20));

        // The child's own failures come back as the shim's causes, typed: a file
        // Open CASCADE cannot parse, and the triangle cap (with the caller's cap).
        let notes = dir.path().join("notes.step");
        std::fs::write(&notes, "ISO-10303-21;\nthese are my notes\n").unwrap();
        let e = read(&notes, &child(&fitup, 1 << 30, limit)).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::Occt {
                    failure: OcctFailure::Parse,
                    ..
                }
            ),
            "{e:?}"
        );
        let few = StepOptions {
            max_triangles: 10,
            ..child(&fitup, 1 << 30, limit)
        };
        let e = read(&file, &few).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::Occt {
                    failure: OcctFailure::TooManyTriangles { cap: 10 },
                    ..
                }
            ),
            "{e:?}"
        );

        // A child that crashes, hangs, runs out of memory, or is no reader at all.
        let crash = stand_in(dir.path(), "crash", "kill -SEGV $$");
        let e = read(&file, &child(&crash, 0, limit)).unwrap_err();
        assert!(matches!(e, StepError::Crashed { signal: 11, .. }), "{e}");
        assert!(
            e.to_string().contains("box.step: Open CASCADE crashed"),
            "{e}"
        );

        let hang = stand_in(dir.path(), "hang", "exec sleep 60");
        let started = Instant::now();
        let e = read(&file, &child(&hang, 0, Duration::from_secs(1))).unwrap_err();
        assert!(matches!(e, StepError::TimeLimit { .. }), "{e}");
        assert!(started.elapsed() < Duration::from_secs(10), "bounded");

        let oom = stand_in(
            dir.path(),
            "oom",
            "echo 'memory allocation of 4096 bytes failed' >&2; kill -ABRT $$",
        );
        let e = read(&file, &child(&oom, 256 << 20, limit)).unwrap_err();
        assert!(
            matches!(e, StepError::MemoryLimit { limit, .. } if limit == 256 << 20),
            "{e}"
        );
        assert!(e.to_string().contains("256 MiB"), "{e}");

        let silent = stand_in(dir.path(), "silent", "exit 0");
        let e = read(&file, &child(&silent, 0, limit)).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::Child {
                    failure: ChildFailure::BadReply {
                        what: "missing",
                        ..
                    },
                    ..
                }
            ),
            "{e}"
        );
        let failing = stand_in(dir.path(), "failing", "exit 3");
        let e = read(&file, &child(&failing, 0, limit)).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::Child {
                    failure: ChildFailure::Exit { code: 3 },
                    ..
                }
            ),
            "{e}"
        );
        let forged = stand_in(
            dir.path(),
            "forged",
            "printf 'fitup-step-reply 3\\n\\000\\377\\377\\377\\377\\377\\377\\377\\177' > \"$3\"",
        );
        let e = read(&file, &child(&forged, 0, limit)).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::Child {
                    failure: ChildFailure::BadReply { .. },
                    ..
                }
            ),
            "{e}"
        );
    }

    /// A deterministic pseudo-random byte stream (no RNG crate needed).
    fn noise(n: usize, mut x: u64) -> Vec<u8> {
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x >> 24) as u8
            })
            .collect()
    }

    /// Hostile STEP files through `fitup import`: each ends with exit 1 and a message
    /// naming the file, within the hostile suites' time bound and under 600 MB (the
    /// whole process tree), nothing written.
    #[test]
    fn hostile_step_files_are_located_errors_in_bounded_time_and_memory() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        let asm = p.join("assembly.step");
        write_test_step("assembly", &asm).unwrap();
        let whole = std::fs::read(&asm).unwrap();
        std::fs::write(p.join("truncated.step"), &whole[..whole.len() / 2]).unwrap();
        let mut garbage = b"ISO-10303-21;\nHEADER;\n".to_vec();
        garbage.extend(noise(1 << 20, 0x9e37_79b9_7f4a_7c15));
        std::fs::write(p.join("garbage.step"), garbage).unwrap();
        // Huge counts: a million entities in one list, 53 MB (under the 64 MiB cap).
        let mut huge = String::from(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n",
        );
        let n = 1_000_000;
        for i in 1..=n {
            huge += &format!("#{i}=CARTESIAN_POINT('',(0.,{i}.,0.));\n");
        }
        huge += &format!("#{}=POLYLINE('',(", n + 1);
        huge += &(1..=n)
            .map(|i| format!("#{i}"))
            .collect::<Vec<_>>()
            .join(",");
        huge += "));\nENDSEC;\nEND-ISO-10303-21;\n";
        std::fs::write(p.join("huge.step"), huge).unwrap();
        // A memory blow-up: 400,000 points need ≈ 200 MB in Open CASCADE (300,000
        // peaked at 159 MB uncapped), over a 100 MiB cap.
        let mut points = String::from(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n",
        );
        for i in 1..=400_000 {
            points += &format!("#{i}=CARTESIAN_POINT('',(0.,{i}.,0.));\n");
        }
        points += "ENDSEC;\nEND-ISO-10303-21;\n";
        std::fs::write(p.join("points.step"), points).unwrap();
        // An entity number near 2^63, and entities of the wrong type where face
        // bounds are expected.
        let text = String::from_utf8(whole.clone()).unwrap();
        std::fs::write(
            p.join("numbers.step"),
            text.replacen("#1=", "#9223372036854775807=", 1),
        )
        .unwrap();
        let confused = text
            .lines()
            .map(|l| {
                if l.contains("FACE_BOUND(") {
                    let id = l.split('=').next().unwrap();
                    format!("{id}=CARTESIAN_POINT('',(0.,0.,0.));")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(p.join("confused.step"), confused).unwrap();

        // What each one says with Debian's Open CASCADE 7.6: the wrong-type entities
        // crash it (SIGSEGV) — in the child, so fitup reports it; the list of a
        // million points parses for minutes and is killed at the time limit.
        for (file, extra, says) in [
            ("truncated.step", &[][..], "can parse"),
            ("garbage.step", &[][..], "can parse"),
            (
                "huge.step",
                &["--time-limit-s", "2"][..],
                "time limit of 2.0 s",
            ),
            (
                "points.step",
                &["--memory-limit-mb", "100", "--time-limit-s", "15"][..],
                "ran out of memory",
            ),
            ("confused.step", &[][..], "Open CASCADE crashed"),
        ] {
            let before = common::snapshot(p);
            let mut args = vec!["import", file, "--out", "out"];
            args.extend(extra);
            let r = common::bounded::run(p, &args);
            let what = format!("{file} {extra:?}: {} ({} kB)", r.text, r.peak_kb);
            assert_eq!(r.code, Some(1), "{what}");
            assert!(r.text.contains(file), "{what}");
            assert!(r.text.contains(says), "{says}: {what}");
            assert!(!r.text.contains("panicked"), "{what}");
            assert!(r.peak_kb < 600 * 1024, "{what}");
            if file == "points.step" {
                // The cap holds the whole process tree well under what the read needs.
                assert!(r.peak_kb < 150 * 1024, "{what}");
            }
            assert_eq!(common::snapshot(p), before, "{what}");
            assert!(!p.join("out").exists(), "{what}");
            eprintln!(
                "{file} {extra:?}: {:?}, {} kB: {}",
                r.elapsed,
                r.peak_kb,
                r.text.trim()
            );
        }
        // An entity numbered near 2^63 is read like any other: no table sized by it.
        let r = common::bounded::run(p, &["import", "numbers.step", "--out", "out"]);
        assert_eq!(r.code, Some(0), "{}", r.text);
        assert!(r.peak_kb < 600 * 1024, "{} kB", r.peak_kb);
    }
}
