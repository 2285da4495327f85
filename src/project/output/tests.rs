use super::*;
use crate::fsutil::content_hash;

fn refused(path: &Path, rule: &OutputRule) -> OutputError {
    check_output(path, rule).expect_err("refused")
}

#[test]
fn outputs_replace_only_files_fitup_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rule = OutputRule::default();
    let out = d.join("log.csv");
    // A new file may be written, and then replaced.
    write_output(&out, b"t_s\n0\n", &rule).unwrap();
    write_output(&out, b"t_s\n1\n", &rule).unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), b"t_s\n1\n");
    // Edited by the user since: no longer fitup's.
    std::fs::write(&out, b"t_s\nmine\n").unwrap();
    assert_eq!(refused(&out, &rule), OutputError::NotOurs);
    // Same size, other bytes: still not.
    std::fs::write(&out, b"t_s\n2\n").unwrap();
    assert_eq!(refused(&out, &rule), OutputError::NotOurs);
    // `force` replaces it, and it is fitup's again.
    write_output(&out, b"x\n", &OutputRule::forced(true)).unwrap();
    write_output(&out, b"y\n", &rule).unwrap();
    // A user's own CSV, whatever its name.
    let holes = d.join("holes.csv");
    std::fs::write(&holes, b"x,y\n1,2\n").unwrap();
    assert_eq!(refused(&holes, &rule), OutputError::NotOurs);
    assert_eq!(std::fs::read(&holes).unwrap(), b"x,y\n1,2\n");
}

#[test]
fn files_the_project_uses_need_force() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rule = OutputRule::default();
    for name in ["cell.yaml", "arm.URDF", "part.stl", "fitup.toml", "a.rhai"] {
        let p = d.join(name);
        std::fs::write(&p, b"mine").unwrap();
        assert!(
            matches!(refused(&p, &rule), OutputError::InUse { .. }),
            "{name}"
        );
        // Even when the registry lists it (fitup's demo writes such files).
        register_output(&p).unwrap();
        assert!(
            matches!(refused(&p, &rule), OutputError::InUse { .. }),
            "{name}"
        );
        assert!(check_output(&p, &OutputRule::forced(true)).is_ok());
    }
    // A SQLite database by its header, whatever its name; listed or not.
    let db = d.join("results.csv");
    std::fs::write(&db, b"SQLite format 3\0rest").unwrap();
    register_output(&db).unwrap();
    let e = refused(&db, &rule);
    assert!(e.to_string().contains("SQLite database"), "{e}");
    // A file the run read (a problem file, a hole table).
    let plan = d.join("bar.plan.json");
    std::fs::write(&plan, b"{}").unwrap();
    register_output(&plan).unwrap();
    assert!(check_output(&plan, &rule).is_ok());
    let used = |p: &Path| p.ends_with("bar.plan.json");
    let run = OutputRule {
        used: Some(&used),
        ..OutputRule::default()
    };
    assert!(matches!(refused(&plan, &run), OutputError::InUse { .. }));
    // fitup's bookkeeping, never.
    let reg = d.join(OUTPUT_REGISTRY);
    assert_eq!(
        refused(&reg, &OutputRule::forced(true)),
        OutputError::Bookkeeping
    );
}

#[test]
fn signatures_streams_and_special_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rule = OutputRule::default();
    // A file that begins with the writer's signature is its own.
    let api = d.join("api.md");
    std::fs::write(&api, b"# fitup scripting API\nold").unwrap();
    let sig = OutputRule {
        signature: Some(b"# fitup scripting API\n"),
        ..OutputRule::default()
    };
    assert!(check_output(&api, &sig).is_ok());
    std::fs::write(&api, b"# my notes\n").unwrap();
    assert_eq!(refused(&api, &sig), OutputError::NotOurs);
    // A streamed recording: accepted while it starts with its magic.
    let rrd = d.join("run.rrd");
    std::fs::write(&rrd, b"not yet").unwrap();
    register_stream(&rrd, RRD_MAGIC).unwrap();
    assert_eq!(refused(&rrd, &rule), OutputError::NotOurs);
    std::fs::write(&rrd, b"RRF2\0\0\0\0data").unwrap();
    assert!(check_output(&rrd, &rule).is_ok());
    // Folders, FIFOs and links: never, even with force.
    assert!(matches!(
        refused(d, &OutputRule::forced(true)),
        OutputError::NotRegular("a folder")
    ));
    #[cfg(unix)]
    {
        let link = d.join("link.csv");
        std::os::unix::fs::symlink(&api, &link).unwrap();
        assert_eq!(
            refused(&link, &OutputRule::forced(true)),
            OutputError::Symlink
        );
        let fifo = d.join("fifo.csv");
        if std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            assert_eq!(
                refused(&fifo, &OutputRule::forced(true)),
                OutputError::NotRegular("a FIFO")
            );
        }
    }
    // A forged or foreign registry lists nothing.
    let out = d.join("x.csv");
    std::fs::write(&out, b"1\n").unwrap();
    std::fs::write(
        d.join(OUTPUT_REGISTRY),
        format!("file 2 {:016x} x.csv\n", content_hash(b"1\n")),
    )
    .unwrap();
    assert_eq!(refused(&out, &rule), OutputError::NotOurs);
}

#[test]
fn the_registry_stays_bounded_and_forgets_deleted_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rule = OutputRule::default();
    for i in 0..50 {
        write_output(&d.join(format!("f{i}.csv")), b"a\n", &rule).unwrap();
    }
    for i in 0..40 {
        std::fs::remove_file(d.join(format!("f{i}.csv"))).unwrap();
    }
    write_output(&d.join("last.csv"), b"b\n", &rule).unwrap();
    let text = std::fs::read_to_string(d.join(OUTPUT_REGISTRY)).unwrap();
    assert_eq!(text.lines().count(), 1 + 10 + 1, "{text}");
    assert!(check_output(&d.join("f45.csv"), &rule).is_ok());
}

#[test]
fn a_source_of_the_open_document_is_refused_even_with_force_under_any_spelling() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir_all(d.join("m/sub")).unwrap();
    let mesh = d.join("m/part.stl");
    std::fs::write(&mesh, b"solid part").unwrap();
    let sources = vec![mesh.clone(), d.join("m/gone.yaml")];
    let rule = OutputRule::forced(true).protecting(&sources);
    std::os::unix::fs::symlink(d.join("m"), d.join("link")).unwrap();
    std::fs::hard_link(&mesh, d.join("m/other_name.stl")).unwrap();
    // Itself, through `..`, through a linked folder, another name of the same file,
    // and a source that is missing now.
    for p in [
        mesh.clone(),
        d.join("m/sub/../part.stl"),
        d.join("link/part.stl"),
        d.join("m/other_name.stl"),
        d.join("m/gone.yaml"),
    ] {
        let source = OutputError::Source { path: p.clone() };
        assert_eq!(refused(&p, &rule), source, "{}", p.display());
        assert_eq!(write_output(&p, b"x", &rule), Err(source.clone()));
        assert!(source.to_string().contains("a source of the open document"));
    }
    assert_eq!(std::fs::read(&mesh).unwrap(), b"solid part");
    assert!(!d.join("m/gone.yaml").exists());
    // A file that is no source: `force` replaces it.
    let free = d.join("m/free.stl");
    std::fs::write(&free, b"mine").unwrap();
    write_output(&free, b"out", &rule).unwrap();
    assert_eq!(std::fs::read(&free).unwrap(), b"out");
}
