use super::super::raw::tests::sample_model as model;
use super::*;

fn options(linear: f64) -> StepOptions {
    StepOptions {
        linear_deflection: linear,
        ..StepOptions::default()
    }
}

/// Prunes `st` with a size cap of 0 bytes: every entry goes.
fn prune_to_nothing(st: &Path) -> PruneReport {
    prune_store(
        st,
        &PruneOptions {
            max_bytes: 0,
            ..PruneOptions::default()
        },
    )
    .unwrap()
}

/// A source file with `bytes` and its key at `linear` deflection.
fn source(dir: &Path, name: &str, bytes: &[u8], linear: f64) -> (PathBuf, StoreKey) {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    (p, StoreKey::new(bytes, &options(linear)))
}

fn age(file: &Path, secs: u64) {
    let f = std::fs::OpenOptions::new().write(true).open(file).unwrap();
    f.set_modified(SystemTime::now() - Duration::from_secs(secs))
        .unwrap();
}

#[test]
fn the_store_serves_only_its_key_and_ignores_damage() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let (a, key) = source(dir.path(), "a.step", b"ISO-10303-21; one", 0.1);
    store(&st, &key, &a, &model("peg"), DEFAULT_STORE_CAP);
    assert_eq!(load_stored(&st, &key), Some(model("peg")));
    let (_, other) = source(dir.path(), "b.step", b"ISO-10303-21; two", 0.1);
    assert_eq!(load_stored(&st, &other), None);
    assert_eq!(
        load_stored(&st, &StoreKey::new(b"ISO-10303-21; one", &options(0.01))),
        None
    );
    // A damaged file is a miss, and a rewrite replaces it (it is fitup's).
    let files = stored_files(&st);
    assert_eq!(files.len(), 1);
    let mut bytes = std::fs::read(&files[0]).unwrap();
    bytes.truncate(bytes.len() - 3);
    std::fs::write(&files[0], &bytes).unwrap();
    assert_eq!(load_stored(&st, &key), None);
    store(&st, &key, &a, &model("peg"), DEFAULT_STORE_CAP);
    assert!(load_stored(&st, &key).is_some());
    // A file fitup did not write at that name is left alone.
    std::fs::write(&files[0], b"my notes").unwrap();
    store(&st, &key, &a, &model("peg"), DEFAULT_STORE_CAP);
    assert_eq!(std::fs::read(&files[0]).unwrap(), b"my notes");
}

/// A poisoned entry (NaN or 1e300 coordinates, an index past the vertices), a cut
/// one, one larger than the bound and a link to a file outside are misses and are
/// removed (a rewrite then keeps the good model); none is read through a link.
#[test]
fn poisoned_linked_and_oversized_entries_are_misses_and_removed() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let (a, key) = source(dir.path(), "a.step", b"ISO-10303-21; one", 0.1);
    let poisons: [fn(&mut RawModel); 4] = [
        |m| m.parts[0].vertices[0] = f64::NAN,
        |m| m.parts[0].vertices[4] = 1e300,
        |m| m.parts[0].triangles[2] = 99,
        |m| m.instances[0].part = 7,
    ];
    for poison in poisons {
        let mut m = model("peg");
        poison(&mut m);
        store(&st, &key, &a, &m, DEFAULT_STORE_CAP);
        assert_eq!(stored_files(&st).len(), 1);
        assert_eq!(load_stored(&st, &key), None);
        assert!(
            stored_files(&st).is_empty(),
            "the poisoned entry is removed"
        );
        store(&st, &key, &a, &model("peg"), DEFAULT_STORE_CAP);
        assert_eq!(load_stored(&st, &key), Some(model("peg")));
    }
    // Larger than the bound: not read, removed.
    let file = stored_files(&st)[0].clone();
    let f = std::fs::OpenOptions::new().write(true).open(&file).unwrap();
    f.set_len(MAX_ENTRY_BYTES + 1).unwrap();
    assert_eq!(load_stored(&st, &key), None);
    assert!(!file.exists());
    // A link to a sound entry outside the store: not followed, the link removed,
    // the outside file untouched.
    #[cfg(unix)]
    {
        let outside = tempfile::tempdir().unwrap();
        let st2 = outside.path().join("store");
        store(&st2, &key, &a, &model("peg"), DEFAULT_STORE_CAP);
        let target = stored_files(&st2)[0].clone();
        let before = std::fs::read(&target).unwrap();
        std::os::unix::fs::symlink(&target, &file).unwrap();
        assert_eq!(load_stored(&st, &key), None);
        assert!(
            std::fs::symlink_metadata(&file).is_err(),
            "the link is removed"
        );
        assert_eq!(std::fs::read(&target).unwrap(), before);
        // The store folder itself a link: not used.
        let moved = dir.path().join("real");
        std::fs::rename(&st, &moved).unwrap();
        std::os::unix::fs::symlink(&st2, &st).unwrap();
        assert_eq!(load_stored(&st, &key), None);
        assert!(prune_store(&st, &PruneOptions::default()).is_err());
    }
}

/// Writing the entry of a changed STEP file removes the entries of its older
/// contents, and only those: other files' entries and the same contents at another
/// deflection stay.
#[test]
fn writing_an_entry_removes_the_same_files_older_contents() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let (a, old) = source(dir.path(), "a.step", b"ISO-10303-21; v1", 0.1);
    store(&st, &old, &a, &model("v1"), DEFAULT_STORE_CAP);
    let (_, old_fine) = source(dir.path(), "a.step", b"ISO-10303-21; v1", 0.01);
    store(&st, &old_fine, &a, &model("v1 fine"), DEFAULT_STORE_CAP);
    let (b, other) = source(dir.path(), "b.step", b"ISO-10303-21; b", 0.1);
    store(&st, &other, &b, &model("b"), DEFAULT_STORE_CAP);
    assert_eq!(stored_files(&st).len(), 3);
    // Another deflection of the same contents is not stale.
    assert!(load_stored(&st, &old).is_some());
    // a.step is saved again with other contents and read.
    let (_, new) = source(dir.path(), "a.step", b"ISO-10303-21; v2!", 0.1);
    store(&st, &new, &a, &model("v2"), DEFAULT_STORE_CAP);
    assert_eq!(
        load_stored(&st, &old),
        None,
        "the old contents' entry is gone"
    );
    assert_eq!(load_stored(&st, &old_fine), None, "at every deflection");
    assert_eq!(load_stored(&st, &new), Some(model("v2")));
    assert_eq!(load_stored(&st, &other), Some(model("b")), "b.step's stays");
    assert_eq!(stored_files(&st).len(), 2);
}

/// Over the size cap, writing evicts the least recently used entries — a hit
/// counts as a use — and never the entry just written.
#[test]
fn the_size_cap_evicts_the_least_recently_used() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let keys: Vec<(PathBuf, StoreKey)> = (0..3)
        .map(|i| {
            let bytes = format!("ISO-10303-21; {i}");
            source(dir.path(), &format!("{i}.step"), bytes.as_bytes(), 0.1)
        })
        .collect();
    for (i, (p, k)) in keys.iter().enumerate() {
        store(&st, k, p, &model("m"), DEFAULT_STORE_CAP);
        age(&st.join(k.file_name()), 1000 - 100 * i as u64);
    }
    let one = std::fs::metadata(st.join(keys[0].1.file_name()))
        .unwrap()
        .len();
    // Entry 0 is the oldest, but a hit makes it the most recent.
    assert!(load_stored(&st, &keys[0].1).is_some());
    let (p, k) = source(dir.path(), "3.step", b"ISO-10303-21; 3", 0.1);
    store(&st, &k, &p, &model("m"), 3 * one);
    assert!(
        load_stored(&st, &keys[1].1).is_none(),
        "the least recently used goes"
    );
    for k in [&keys[0].1, &keys[2].1, &k] {
        assert!(load_stored(&st, k).is_some());
    }
    // A cap smaller than one entry still keeps the entry just written.
    let (p, k) = source(dir.path(), "4.step", b"ISO-10303-21; 4", 0.1);
    store(&st, &k, &p, &model("m"), 1);
    assert_eq!(stored_files(&st), vec![st.join(k.file_name())]);
}

/// `prune_store` removes exactly what is stale, lists it first with `dry_run`,
/// and leaves everything that is not fitup's — even named like an entry.
#[test]
fn pruning_removes_what_is_stale_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let (used, used_key) = source(dir.path(), "used.step", b"ISO-10303-21; used", 0.1);
    store(&st, &used_key, &used, &model("used"), DEFAULT_STORE_CAP);
    let (_, finer) = source(dir.path(), "used.step", b"ISO-10303-21; used", 0.05);
    store(&st, &finer, &used, &model("finer"), DEFAULT_STORE_CAP);
    let (gone, gone_key) = source(dir.path(), "gone.step", b"ISO-10303-21; gone", 0.1);
    store(&st, &gone_key, &gone, &model("gone"), DEFAULT_STORE_CAP);
    std::fs::remove_file(&gone).unwrap();
    let (edited, edited_key) = source(dir.path(), "edited.step", b"ISO-10303-21; aaaa", 0.1);
    store(
        &st,
        &edited_key,
        &edited,
        &model("edited"),
        DEFAULT_STORE_CAP,
    );
    std::fs::write(&edited, b"ISO-10303-21; bbbb").unwrap(); // same length
    let old_format = st.join("00000000000000a1.tess");
    std::fs::write(&old_format, b"fitup-tessellation 1\nwhatever").unwrap();
    let damaged = st.join("00000000000000d2.tess");
    std::fs::write(&damaged, b"fitup-tessellation 3\n\x01\x02").unwrap();
    let not_ours = st.join("00000000000000e3.tess");
    std::fs::write(&not_ours, b"my own notes").unwrap();
    let notes = st.join("README.txt");
    std::fs::write(&notes, b"fitup-tessellation 3\n but a user's file").unwrap();
    let dead = st.join(".fitup-dead.tmp");
    std::fs::write(&dead, b"half").unwrap();
    age(&dead, 2 * 3600);
    let live = st.join(".fitup-live.tmp");
    std::fs::write(&live, b"being written").unwrap();
    #[cfg(unix)]
    let outside = {
        let target = dir.path().join("precious.tess");
        std::fs::write(&target, b"fitup-tessellation 1\n").unwrap();
        std::os::unix::fs::symlink(&target, st.join("00000000000000f4.tess")).unwrap();
        target
    };
    let in_use: HashSet<Tessellation> =
        [Tessellation::new(&used, 0.1, StepOptions::default().angular_deflection).unwrap()].into();
    let mut o = PruneOptions {
        dry_run: true,
        in_use: Some(in_use),
        ..PruneOptions::default()
    };
    let before = std::fs::read_dir(&st).unwrap().count();
    let dry = prune_store(&st, &o).unwrap();
    assert_eq!(
        std::fs::read_dir(&st).unwrap().count(),
        before,
        "a dry run removes nothing"
    );
    let mut reasons: Vec<(String, StaleReason)> = dry
        .removed
        .iter()
        .map(|p| {
            (
                p.file.file_name().unwrap().to_string_lossy().into_owned(),
                p.reason,
            )
        })
        .collect();
    reasons.sort_by_key(|(n, _)| n.clone());
    let name = |k: &StoreKey| k.file_name();
    let mut expected = vec![
        (".fitup-dead.tmp".to_string(), StaleReason::Leftover),
        ("00000000000000a1.tess".into(), StaleReason::OldFormat),
        ("00000000000000d2.tess".into(), StaleReason::Damaged),
        (name(&finer), StaleReason::Unused),
        (name(&gone_key), StaleReason::SourceGone),
        (name(&edited_key), StaleReason::SourceChanged),
    ];
    expected.sort_by_key(|(n, _)| n.clone());
    assert_eq!(reasons, expected);
    assert_eq!(dry.kept, 1);
    o.dry_run = false;
    let done = prune_store(&st, &o).unwrap();
    assert_eq!(done.removed, dry.removed);
    assert!(done.failed.is_empty());
    let mut left: Vec<String> = std::fs::read_dir(&st)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != crate::project::OUTPUT_REGISTRY)
        .collect();
    left.sort();
    let mut keep = vec![
        name(&used_key),
        "00000000000000e3.tess".into(),
        "README.txt".into(),
        ".fitup-live.tmp".into(),
    ];
    #[cfg(unix)]
    keep.push("00000000000000f4.tess".into());
    keep.sort();
    assert_eq!(left, keep);
    assert_eq!(load_stored(&st, &used_key), Some(model("used")));
    #[cfg(unix)]
    assert_eq!(std::fs::read(&outside).unwrap(), b"fitup-tessellation 1\n");
    // Without knowing what documents use, another deflection is kept; the cap
    // still applies.
    store(&st, &finer, &used, &model("finer"), DEFAULT_STORE_CAP);
    let r = prune_store(&st, &PruneOptions::default()).unwrap();
    assert!(r.removed.is_empty(), "{r:?}");
    assert_eq!(r.kept, 2);
    let r = prune_to_nothing(&st);
    assert_eq!(r.removed.len(), 2);
    assert!(r.removed.iter().all(|p| p.reason == StaleReason::OverCap));
    assert_eq!((r.kept, r.kept_bytes), (0, 0));
    // A missing store is empty.
    assert_eq!(
        prune_store(&dir.path().join("none"), &PruneOptions::default()).unwrap(),
        PruneReport::default()
    );
}

#[cfg(unix)]
#[test]
fn a_store_reached_through_a_symbolic_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("elsewhere");
    std::fs::create_dir(&real).unwrap();
    std::fs::write(
        real.join("00000000000000a1.tess"),
        b"fitup-tessellation 1\n",
    )
    .unwrap();
    let link = dir.path().join("store");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let e = prune_store(&link, &PruneOptions::default()).unwrap_err();
    assert!(matches!(e, StoreError::NotAFolder { .. }), "{e}");
    assert!(real.join("00000000000000a1.tess").exists());
}

/// Readers take no lock: while one thread prunes and rewrites an entry over and
/// over, another reading it gets the whole model or a miss, never part of one.
#[test]
fn a_reader_sees_a_whole_entry_or_none_while_the_store_is_pruned() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("store");
    let (a, key) = source(dir.path(), "a.step", b"ISO-10303-21; a", 0.1);
    let big = RawModel {
        parts: (0..50)
            .map(|i| model(&format!("p{i}")).parts[0].clone())
            .collect(),
        ..model("m")
    };
    store(&st, &key, &a, &big, DEFAULT_STORE_CAP);
    let stop = std::sync::atomic::AtomicBool::new(false);
    let (hits, misses) = std::thread::scope(|s| {
        let reader = s.spawn(|| {
            let (mut hits, mut misses) = (0, 0);
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                match load_stored(&st, &key) {
                    Some(m) => {
                        assert_eq!(m, big);
                        hits += 1;
                    }
                    None => misses += 1,
                }
            }
            (hits, misses)
        });
        for _ in 0..200 {
            let r = prune_to_nothing(&st);
            assert!(r.failed.is_empty());
            store(&st, &key, &a, &big, DEFAULT_STORE_CAP);
        }
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        reader.join().unwrap()
    });
    assert!(hits + misses > 0);
    let left: Vec<_> = std::fs::read_dir(&st)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".fitup-") && n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}
