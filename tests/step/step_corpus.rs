//! `fitup import` on real CAD exports (SolidWorks, CATIA, …), which are third-party
//! files and so never committed: `FITUP_STEP_CORPUS` names a folder of `.step`/`.stp`
//! files (or one file); without it the test says so and passes. Every import is
//! checked against Open CASCADE's own reading of the file (tests/bench/step/occt_check:
//! `FITUP_OCCT_CHECK`, else compiled by the test, see `common::occt_check`): one
//! component per placed solid at the placement of the assembly tree and as many levels
//! down, its part named from the product, its mesh closed and within 1.5 % of the exact
//! B-rep volume; one sub-assembly per assembly occurrence below the root, in the tree's
//! order, at its placement (issue 37); the file's unit named and lengths in mm. Every
//! imported file of more than one component then gets an assembly sequence with the
//! default options, re-checked independently by `sequence_fits`' dense removal test
//! (tests/common/fit_check.rs: the reported assembled-pose fits exactly the
//! interfering pairs, each part taken out along its path and straight on against the
//! parts placed before it, allowed the reported fits' overlap and nothing else).

#[cfg(feature = "step")]
mod with_occt {
    use crate::common;
    use crate::common::occt_check;
    use fitup::document::Document;
    use std::path::PathBuf;

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
                    let c = common::fit_check::checker(&doc, &plan);
                    common::fit_check::fits_are_exact(&c, &plan);
                    common::fit_check::dense_removal(&c, &plan);
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
        let check = occt_check::program();
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
            let reference = occt_check::read(&check, &file);
            let (unit, solids) = (&reference.unit, &reference.solids);
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
            // The product tree (issue 37): one root assembly is the document itself;
            // every other assembly occurrence is a sub-assembly, in the tree's order,
            // at Open CASCADE's placement, as many levels down.
            let roots = reference
                .assemblies
                .iter()
                .filter(|a| a.depth() == 1)
                .count();
            let dropped = usize::from(roots == 1 && solids.iter().all(|s| s.depth() > 1));
            let expected: Vec<_> = reference
                .assemblies
                .iter()
                .filter(|a| dropped == 0 || a.depth() > 1)
                .collect();
            assert_eq!(
                doc.sub_assemblies().len(),
                expected.len(),
                "{}: one sub-assembly per assembly occurrence",
                file.display()
            );
            for (a, r) in doc.sub_assemblies().iter().zip(&expected) {
                let scale = 1.0 + r.t.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(
                    r.placed_as(&a.transform, 1e-6 * scale),
                    "{}: sub-assembly {} is not where Open CASCADE places `{}`",
                    file.display(),
                    a.name,
                    r.path
                );
                assert_eq!(a.name.split('/').count(), r.depth() - dropped, "{}", a.name);
            }
            // Match each placed solid to a component at its placement whose part has
            // its volume (two solids at one placement are told apart by volume).
            let mut free: Vec<bool> = vec![true; doc.components().len()];
            for s in solids {
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
                assert_eq!(
                    c.name.split('/').count(),
                    s.depth() - dropped,
                    "{}: component {} for `{}`: not as many levels down",
                    file.display(),
                    c.name,
                    s.path
                );
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
