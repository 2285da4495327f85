//! `fitup cache prune`: stale STEP tessellations leave `.fitup-cache/step`, and nothing
//! else does (src/mesh/step/store.rs has the rules' unit tests).

use crate::common;

#[test]
fn pruning_leaves_what_fitup_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    // No store yet: nothing to do, and a subfolder finds its project.
    std::fs::create_dir(p.join("models")).unwrap();
    let o = common::run_in(&p.join("models"), &["cache", "prune"]);
    let t = common::text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains(".fitup-cache/step: removed 0 files"), "{t}");
    // Files in the store that fitup did not write stay, whatever their names.
    let store = p.join(fitup::mesh::step::STEP_STORE);
    std::fs::create_dir_all(&store).unwrap();
    std::fs::write(store.join("0123456789abcdef.tess"), "my notes").unwrap();
    std::fs::write(store.join("notes.txt"), "fitup-tessellation 3\n").unwrap();
    let before = common::snapshot(p);
    let o = common::run_in(p, &["cache", "prune", "--max-mb", "0"]);
    assert!(o.status.success(), "{}", common::text(&o));
    assert_eq!(common::snapshot(p), before);
}

#[cfg(unix)]
#[test]
fn a_store_that_is_a_symbolic_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let victim = elsewhere.path().join("0123456789abcdef.tess");
    std::fs::write(&victim, "fitup-tessellation 1\n").unwrap();
    std::os::unix::fs::symlink(elsewhere.path(), p.join(".fitup-cache")).unwrap();
    let o = common::run_in(p, &["cache", "prune"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("not a folder"), "{t}");
    assert!(victim.exists());
}

#[cfg(feature = "step")]
mod with_occt {
    use crate::common;
    use common::run_ok as run;
    use common::stored_tessellations as stored;
    use fitup::mesh::step::write_test_step;

    /// A user changes a part's `deflection:`, then deletes the STEP file: each time
    /// `fitup cache prune` removes what no document can use, and the tessellation in
    /// use stays (the next load reads no STEP).
    #[test]
    fn prune_removes_other_deflections_and_gone_files_and_keeps_what_is_used() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        std::fs::write(p.join("fitup.toml"), "").unwrap();
        std::fs::create_dir_all(p.join("parts")).unwrap();
        write_test_step("cylinder_hole", &p.join("parts/bushing.step")).unwrap();
        let doc = p.join("cell.yaml");
        let yaml = "parts:\n  b:\n    step: parts/bushing.step\n    deflection: 0.05\ncomponents:\n  - {name: b-1, part: b}\n";
        std::fs::write(&doc, yaml).unwrap();
        assert!(run(p, &["check", "cell.yaml"]).contains("tessellated now"));
        std::fs::write(&doc, yaml.replace("0.05", "0.02")).unwrap();
        assert!(run(p, &["check", "cell.yaml"]).contains("tessellated now"));
        assert_eq!(stored(p).len(), 2, "another deflection is another entry");

        let t = run(p, &["cache", "prune", "--dry-run"]);
        assert!(t.contains("would remove 1 files"), "{t}");
        assert!(t.contains("no document uses this tessellation"), "{t}");
        assert!(t.contains("parts/bushing.step"), "{t}");
        assert_eq!(stored(p).len(), 2, "a dry run removes nothing");

        // A document that names `step:` but does not parse: what it needs is not
        // known, so nothing of a current file is removed.
        std::fs::write(p.join("draft.yaml"), "parts:\n  x:\n    step: [\n").unwrap();
        let o = common::run_in(p, &["cache", "prune"]);
        let t = common::text(&o);
        assert!(o.status.success(), "{t}");
        assert!(t.contains("draft.yaml") && t.contains("warning"), "{t}");
        assert_eq!(stored(p).len(), 2);
        std::fs::remove_file(p.join("draft.yaml")).unwrap();

        let t = run(p, &["cache", "prune"]);
        assert!(t.contains("removed 1 files") && t.contains("kept 1"), "{t}");
        assert_eq!(stored(p).len(), 1);
        assert!(run(p, &["check", "cell.yaml"]).contains("stored tessellation"));

        std::fs::remove_file(p.join("parts/bushing.step")).unwrap();
        let t = run(p, &["cache", "prune"]);
        assert!(t.contains("its STEP file is gone"), "{t}");
        assert!(stored(p).is_empty());
    }

    /// A CAD re-export replaces the file's entries when it is read: no prune needed.
    #[test]
    fn a_new_export_replaces_the_old_contents_entries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        std::fs::write(p.join("fitup.toml"), "").unwrap();
        std::fs::create_dir_all(p.join("parts")).unwrap();
        let step = p.join("parts/a.step");
        write_test_step("box", &step).unwrap();
        std::fs::write(
            p.join("cell.yaml"),
            "parts:\n  a:\n    step: parts/a.step\ncomponents:\n  - {name: a-1, part: a}\n",
        )
        .unwrap();
        run(p, &["check", "cell.yaml"]);
        let first = stored(p);
        assert_eq!(first.len(), 1);
        write_test_step("cylinder_hole", &step).unwrap();
        assert!(run(p, &["check", "cell.yaml"]).contains("tessellated now"));
        let now = stored(p);
        assert_eq!(now.len(), 1, "{now:?}");
        assert_ne!(now, first);
    }
}
