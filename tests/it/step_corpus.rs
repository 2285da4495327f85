//! `fitup import` on real CAD exports (SolidWorks, CATIA, …), which are third-party
//! files and so never committed: `FITUP_STEP_CORPUS` names a folder of `.step`/`.stp`
//! files (or one file); without it the test says so and passes. With
//! `FITUP_OCCT_CHECK` naming tests/bench/step/occt_check (built by
//! tests/bench/step_corpus.sh), every import is checked against Open CASCADE's own
//! reading of the file: one component per placed solid at the placement of the
//! assembly tree, its part named from the product, its mesh closed and within 1.5 % of
//! the exact B-rep volume, the file's unit named and lengths in mm. Every imported
//! file of more than one component then gets an assembly sequence with the default
//! options, re-checked independently by `sequence_fits`' dense removal test (the
//! reported assembled-pose fits exactly the interfering pairs, each part taken out
//! along its path and straight on against the parts placed before it, allowed the
//! reported fits' overlap and nothing else).

#[cfg(feature = "step")]
mod with_occt {
    use crate::common;
    use fitup::document::Document;
    use fitup::math::{Point3, Transform};
    use std::path::{Path, PathBuf};

    /// The corpus files, sorted; empty when `FITUP_STEP_CORPUS` is not set.
    fn corpus() -> Vec<PathBuf> {
        let Some(root) = std::env::var_os("FITUP_STEP_CORPUS").map(PathBuf::from) else {
            return Vec::new();
        };
        if root.is_file() {
            return vec![root];
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(&root)
            .unwrap_or_else(|e| panic!("FITUP_STEP_CORPUS={}: {e}", root.display()))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && fitup::mesh::step::is_step_path(p))
            .collect();
        files.sort();
        assert!(
            !files.is_empty(),
            "no .step/.stp file in {}",
            root.display()
        );
        files
    }

    /// One placed solid as Open CASCADE alone reads it (occt_check's `solid` line).
    struct Reference {
        path: String,
        product: String,
        volume: f64,
        /// Part frame → root, column vectors, mm.
        r: [[f64; 3]; 3],
        t: [f64; 3],
    }

    impl Reference {
        fn apply(&self, p: [f64; 3]) -> Point3 {
            let v: Vec<f64> = (0..3)
                .map(|i| (0..3).map(|j| self.r[i][j] * p[j]).sum::<f64>() + self.t[i])
                .collect();
            Point3::new(v[0], v[1], v[2])
        }

        /// Whether `pose` moves the part frame as this placement does (within
        /// `tol` mm at the origin and at 100 mm along each axis).
        fn placed_as(&self, pose: &Transform, tol: f64) -> bool {
            [
                [0.0, 0.0, 0.0],
                [100.0, 0.0, 0.0],
                [0.0, 100.0, 0.0],
                [0.0, 0.0, 100.0],
            ]
            .iter()
            .all(|p| (pose.apply(&Point3::new(p[0], p[1], p[2])) - self.apply(*p)).norm() <= tol)
        }
    }

    /// occt_check's reading: the file's length unit and its placed solids.
    fn reference(check: &Path, file: &Path) -> (String, Vec<Reference>) {
        let o = std::process::Command::new(check)
            .arg(file)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "occt_check {}: {}",
            file.display(),
            common::text(&o)
        );
        let text = String::from_utf8(o.stdout).unwrap();
        let mut unit = String::new();
        let mut solids = Vec::new();
        for line in text.lines() {
            let f: Vec<&str> = line.split('\t').collect();
            match f[0] {
                "unit" => unit = f[1].to_string(),
                "solid" => {
                    let mut nums = f[3].split(' ').map(|x| x.parse::<f64>().unwrap());
                    let volume = nums.next().unwrap();
                    let m: Vec<f64> = nums.collect();
                    assert_eq!(m.len(), 12, "{line}");
                    solids.push(Reference {
                        path: f[1].to_string(),
                        product: f[2].to_string(),
                        volume,
                        r: [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]],
                        t: [m[3], m[7], m[11]],
                    });
                }
                _ => panic!("occt_check said {line:?}"),
            }
        }
        (unit, solids)
    }

    /// Every multi-part assembly of the corpus that imports is sequenced with the
    /// default options (geometry mode: an import has no mates) and every sequence is
    /// re-checked; the failures are gathered and reported together.
    #[test]
    fn real_assemblies_get_a_sequence_with_the_default_options() {
        use fitup::sequence::{plan_sequence, SequenceOptions};
        use fitup::workspace::SceneCache;
        let files = corpus();
        if files.is_empty() {
            eprintln!("FITUP_STEP_CORPUS is not set: no real assembly sequenced");
            return;
        }
        let mut failed = Vec::new();
        for file in files {
            let dir = tempfile::tempdir().unwrap();
            let o = common::run_in(
                dir.path(),
                &["import", file.to_str().unwrap(), "--out", "cell"],
            );
            if !o.status.success() {
                // The import test names the import failures.
                continue;
            }
            let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
            let doc = Document::open(&dir.path().join(format!("cell/{stem}.yaml"))).unwrap();
            if doc.components().len() < 2 {
                continue;
            }
            let start = std::time::Instant::now();
            let plan = plan_sequence(&doc, &mut SceneCache::new(), &SequenceOptions::default());
            let wall = start.elapsed().as_secs_f64();
            match plan {
                Ok(plan) => {
                    eprintln!(
                        "{}: {} components, {} sequences in {wall:.1} s, {} fits, {} separate groups; re-checking",
                        file.display(),
                        doc.components().len(),
                        plan.sequences.len(),
                        plan.fits.len(),
                        plan.separate_groups.len()
                    );
                    let c = crate::sequence_fits::checker(&doc, &plan);
                    crate::sequence_fits::fits_are_exact(&c, &plan);
                    crate::sequence_fits::dense_removal(&c, &plan);
                }
                Err(e) => {
                    eprintln!("{}: no sequence in {wall:.1} s: {e}", file.display());
                    failed.push(format!("{}: {e}", file.display()));
                }
            }
        }
        assert!(
            failed.is_empty(),
            "{} assemblies without a sequence:\n{}",
            failed.len(),
            failed.join("\n")
        );
    }

    #[test]
    fn real_cad_exports_import_where_the_cad_put_them() {
        let files = corpus();
        if files.is_empty() {
            eprintln!("FITUP_STEP_CORPUS is not set: no real CAD export checked");
            return;
        }
        let check = std::env::var_os("FITUP_OCCT_CHECK").map(PathBuf::from);
        for file in files {
            let dir = tempfile::tempdir().unwrap();
            let start = std::time::Instant::now();
            let o = common::run_in(
                dir.path(),
                &["import", file.to_str().unwrap(), "--out", "cell"],
            );
            let wall = start.elapsed();
            let t = common::text(&o);
            assert!(o.status.success(), "{}: {t}", file.display());
            eprintln!(
                "{}: fitup import {:.2} s\n{t}",
                file.display(),
                wall.as_secs_f64()
            );
            let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
            let doc = Document::open(&dir.path().join(format!("cell/{stem}.yaml"))).unwrap();
            for p in doc.parts() {
                let r = p.mesh.inspect();
                assert!(
                    r.is_watertight(),
                    "{}: part {} is not closed: {r:?}",
                    file.display(),
                    p.name
                );
            }
            for c in doc.components() {
                let generated = c
                    .name
                    .strip_prefix("NAUO")
                    .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
                assert!(
                    !generated,
                    "{}: component {} is named by the exporter's occurrence id",
                    file.display(),
                    c.name
                );
            }
            let Some(check) = &check else {
                eprintln!("FITUP_OCCT_CHECK is not set: placements and volumes not checked against Open CASCADE");
                continue;
            };
            let (unit, solids) = reference(check, &file);
            let description = doc.description().unwrap_or_default();
            assert!(
                description.contains(&format!("file unit {unit}")),
                "{}: the document's description names the file's unit {unit}: {description}",
                file.display()
            );
            assert_eq!(
                solids.len(),
                doc.components().len(),
                "{}: one component per placed solid",
                file.display()
            );
            // Match each placed solid to a component at its placement whose part has
            // its volume (two solids at one placement are told apart by volume).
            let mut free: Vec<bool> = vec![true; doc.components().len()];
            for s in &solids {
                let scale = 1.0 + s.t.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let hit = doc.components().iter().enumerate().position(|(i, c)| {
                    let part = doc.part(&c.part).unwrap();
                    free[i]
                        && s.placed_as(&c.transform, 1e-6 * scale)
                        && (part.mesh.signed_volume() / s.volume - 1.0).abs() <= 0.015
                });
                let Some(i) = hit else {
                    panic!(
                        "{}: no component at the placement of `{}` ({}) with a mesh within 1.5 % of its exact volume {:.3} mm³",
                        file.display(),
                        s.path,
                        s.product,
                        s.volume
                    );
                };
                free[i] = false;
                let c = &doc.components()[i];
                let product = fitup::document::import::document_name(&s.product, "");
                assert!(
                    product.is_empty() || c.part.starts_with(&product),
                    "{}: `{}` is product {product} but part {}",
                    file.display(),
                    s.path,
                    c.part
                );
            }
        }
    }
}
