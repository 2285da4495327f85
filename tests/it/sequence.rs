//! Assembly sequence planning (seed 003's task layer) on the bundled models: the
//! micro-robot wheel, the fig. 11 cell, and the same without mates. Every returned
//! sequence is re-checked step by step against exactly the parts assembled before.

use crate::common;
#[path = "../common/gearbox.rs"]
mod gearbox;
#[path = "../common/pegboard.rs"]
mod pegboard;

use fitup::document::Document;
use fitup::math::{Point3, Vec3};
use fitup::mesh::{read_stl, Mesh};
use fitup::planning::{MeshValidator, MeshValidatorOptions};
use fitup::sequence::{
    mating_directions, plan_sequence, relation_graph, safe_length, Mode, Operation,
    SequenceOptions, SequencePlan,
};
use fitup::workspace::SceneCache;
use std::path::Path;

/// A closed profile `(radius, z)` (mm, every radius > 0) revolved about +Z: rings,
/// cups with a bore.
fn revolve(profile: &[(f64, f64)], segments: usize) -> Mesh {
    let at = |(r, z): (f64, f64), k: usize| {
        let a = std::f64::consts::TAU * (k % segments) as f64 / segments as f64;
        Point3::new(r * a.cos(), r * a.sin(), z)
    };
    let mut soup = Vec::new();
    for i in 0..profile.len() {
        let (p, q) = (profile[i], profile[(i + 1) % profile.len()]);
        for k in 0..segments {
            soup.push([at(p, k), at(p, k + 1), at(q, k + 1)]);
            soup.push([at(p, k), at(q, k + 1), at(q, k)]);
        }
    }
    let mut m = Mesh::from_triangle_soup(soup).unwrap();
    if m.signed_volume() < 0.0 {
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
    }
    m
}

/// The wheel of seed 003's experiment (mm): an axis with a flange, a gear ring on the
/// flange, a cup over the gear whose bore rides on the axis.
fn wheel_meshes() -> Vec<(&'static str, Mesh)> {
    let axis = Mesh::lathe(
        &[
            (0.0, 0.0),
            (4.5, 0.0),
            (4.5, 1.5),
            (1.0, 1.5),
            (1.0, 11.5),
            (0.0, 11.5),
        ],
        32,
    )
    .unwrap();
    let gear = revolve(&[(1.05, 0.0), (3.9, 0.0), (3.9, 2.0), (1.05, 2.0)], 32);
    let cup = revolve(
        &[
            (4.0, 0.0),
            (4.8, 0.0),
            (4.8, 3.0),
            (1.05, 3.0),
            (1.05, 2.05),
            (4.0, 2.05),
        ],
        32,
    );
    vec![
        ("models/meshes/wheel_axis.stl", axis),
        ("models/meshes/wheel_gear.stl", gear),
        ("models/meshes/wheel_cup.stl", cup),
    ]
}

/// The committed meshes are the generators' output (`FITUP_REGENERATE=1` rewrites
/// them).
#[test]
fn models_match_their_generators() {
    for (path, mesh) in wheel_meshes()
        .into_iter()
        .chain(gearbox::gearbox_meshes(32))
    {
        assert!(mesh.inspect().is_watertight(), "{path}");
        if std::env::var_os("FITUP_REGENERATE").is_some() {
            fitup::mesh::write_stl(Path::new(path), &mesh).unwrap();
        }
        let read = read_stl(Path::new(path)).unwrap();
        assert_eq!(read.triangles.len(), mesh.triangles.len(), "{path}");
        let (a, b) = (read.signed_volume(), mesh.signed_volume());
        assert!((a - b).abs() < 1e-3 * b.abs(), "{path}: {a} vs {b}");
    }
}

fn open(path: &str) -> Document {
    Document::open(Path::new(path)).unwrap()
}

/// The component index of task `k`'s part and of the parts assembled before it (the
/// base and the first `k` task parts, by `order`).
fn step_parts(doc: &Document, order: &[String], k: usize, part: &str) -> (usize, Vec<usize>) {
    let p = doc.component_index(part).unwrap();
    let before = order[..k + 1]
        .iter()
        .map(|n| doc.component_index(n).unwrap())
        .collect();
    (p, before)
}

/// Re-checks every sequence step by step: each task's path is free against exactly
/// the parts assembled before it (a fresh validator, continuous edges), starts away
/// from the assembled pose and ends there; and each part goes in once.
fn recheck(doc: &Document, plan: &SequencePlan) {
    let mut cache = SceneCache::new();
    let ws = fitup::workspace::Workspace::new(doc, &mut cache).unwrap();
    let scene = ws.scene();
    for s in &plan.sequences {
        let order = s.order();
        let mut sorted = order.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), doc.components().len(), "{order:?}");
        for (k, t) in s.tasks.iter().enumerate() {
            let (p, before) = step_parts(doc, &order, k, &t.part);
            assert!(!before.contains(&p));
            let mut v = MeshValidator::new(
                scene.colliders[p].clone(),
                before
                    .iter()
                    .map(|&q| (scene.colliders[q].clone(), scene.poses[q]))
                    .collect(),
                MeshValidatorOptions::default(),
            )
            .unwrap();
            assert!(t.path.found());
            assert!(
                t.path.revalidate(&mut v).is_ok(),
                "task {k} ({}) collides with {:?}",
                t.part,
                before
            );
            let end = t.path.poses.last().unwrap();
            assert!(end.approx_eq(&t.assembled_pose, 1e-9, 1e-9));
            assert!(t.path.length_mm > 0.0);
            assert!((t.mating_direction.norm() - 1.0).abs() < 1e-9);
            // The obstacle box holds every part assembled before.
            for &q in &before {
                let b = scene.colliders[q].world_bounds(&scene.poses[q]);
                assert!(t
                    .obstacle_box
                    .lo
                    .coords
                    .iter()
                    .zip(b.lo.coords.iter())
                    .all(|(a, c)| a <= &(c + 1e-9)));
                assert!(t
                    .obstacle_box
                    .hi
                    .coords
                    .iter()
                    .zip(b.hi.coords.iter())
                    .all(|(a, c)| a >= &(c - 1e-9)));
            }
        }
        assert_eq!(s.mounts, s.tasks.iter().filter(|t| t.mount).count());
    }
    // Ranked: fewest mounts first.
    for w in plan.sequences.windows(2) {
        assert!((w[0].mounts, w[0].direction_changes) <= (w[1].mounts, w[1].direction_changes));
    }
}

#[test]
fn wheel_relation_graph_has_the_seeds_loop_and_composite() {
    let doc = open("models/wheel.yaml");
    let g = relation_graph(&doc);
    assert_eq!(g.relations.len(), 3, "cup–axis, gear–axis, cup–gear");
    let idx = |n: &str| doc.component_index(n).unwrap();
    let (axis, gear, cup) = (idx("axis"), idx("gear"), idx("cup"));
    let rel = |a, b| g.relation(a, b).unwrap();
    // Collinear ∩ coplanar = {Rotz}; collinear alone {z, Rotz}; coplanar {x, y, Rotz}.
    assert_eq!(rel(axis, gear).freedom.vector(), [0, 0, 0, 0, 0, 1]);
    assert_eq!(rel(axis, cup).freedom.vector(), [0, 0, 1, 0, 0, 1]);
    assert_eq!(rel(gear, cup).freedom.vector(), [1, 1, 0, 0, 0, 1]);
    // The loop is broken by uniting axis and gear (1 one), the axis the larger.
    assert_eq!(g.loops.len(), 1);
    assert_eq!(g.loops[0].united, (axis, gear));
    let composite = g.nodes.iter().find(|n| n.is_composite()).unwrap();
    assert_eq!(composite.members, vec![axis, gear]);
    assert_eq!(g.nodes.len(), 2);
}

#[test]
fn wheel_mating_directions_and_safe_length() {
    let doc = open("models/wheel.yaml");
    let mut cache = SceneCache::new();
    let o = SequenceOptions::default();
    // The gear leaves its related parts (axis and cup) nowhere: the cup covers it.
    assert!(mating_directions(&doc, &mut cache, "gear", &o)
        .unwrap()
        .is_empty());
    // The cup comes down along the axis: −Z only.
    let m = mating_directions(&doc, &mut cache, "cup", &o).unwrap();
    assert_eq!(m.len(), 1, "{m:?}");
    assert!((m[0] - (-Vec3::z())).norm() < 1e-9);
    // Its safe length: the cup must clear the shaft's top (11.5 − 1.5 mm up).
    let s = safe_length(&doc, &mut cache, "cup", &Vec3::z(), &o).unwrap();
    assert!(s > 7.0 - 0.5 && s < 10.0 + 1.0, "{s}");
}

#[test]
fn wheel_sequence_is_the_papers_answer() {
    let doc = open("models/wheel.yaml");
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &SequenceOptions::default()).unwrap();
    let best = plan.best();
    assert_eq!(best.order(), ["axis", "gear", "cup"]);
    assert_eq!(best.mounts, 0);
    let (gear, cup) = (&best.tasks[0], &best.tasks[1]);
    assert_eq!((gear.base.as_str(), gear.part.as_str()), ("axis", "gear"));
    assert_eq!(gear.operation, Operation::Insertion);
    assert_eq!(cup.part, "cup");
    assert_eq!(best.steps[1].receivers, ["axis", "gear"]);
    assert_eq!(cup.operation, Operation::Insertion);
    for t in &best.tasks {
        assert!((t.mating_direction - (-Vec3::z())).norm() < 1e-9);
        let g = t.grasp.as_ref().expect("a grasp");
        // Fingers close across the mating direction.
        let n = t.assembled_pose.apply_vector(&g.normal);
        assert!(n.dot(&t.mating_direction).abs() < 1e-6);
        assert!(g.depth > 0.0 && g.width > 0.0);
    }
    // The gear must clear the 10 mm shaft above it before it can move sideways.
    assert!(gear.safe_length > 9.0, "{}", gear.safe_length);
    recheck(&doc, &plan);
    // Cup first is rejected: the gear cannot get in under it.
    assert!(precedes(&plan, "gear", "cup"), "{:?}", plan.precedence);
}

#[test]
fn wheel_without_mates_gives_the_same_order() {
    let doc = open("models/wheel.yaml");
    let o = SequenceOptions {
        mode: Mode::Geometry,
        ..SequenceOptions::default()
    };
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
    assert_eq!(plan.best().order(), ["axis", "gear", "cup"]);
    recheck(&doc, &plan);
    assert!(!plan.rejected.is_empty());
}

#[test]
fn pinned_order_that_cannot_work_says_why() {
    let doc = open("models/wheel.yaml");
    let o = SequenceOptions {
        base: Some("axis".into()),
        order: vec!["cup".into()],
        ..SequenceOptions::default()
    };
    let e = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("cup"), "{msg}");
}

#[test]
fn cell_screws_go_into_the_plates_holes() {
    let doc = open("models/cell.yaml");
    let o = SequenceOptions {
        threaded: vec!["screw".into()],
        ..SequenceOptions::default()
    };
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
    let best = plan.best();
    let order = best.order();
    assert_eq!(order[0], "table", "the largest part is the base: {order:?}");
    let pos = |n: &str| order.iter().position(|o| o == n).unwrap();
    for s in ["screw1", "screw2", "screw3"] {
        // Into plate_a's holes: after the plate, from above, screwed.
        assert!(pos("plate_a") < pos(s), "{order:?}");
        let t = best.tasks.iter().find(|t| t.part == s).unwrap();
        assert_eq!(t.base, "plate_a");
        assert_eq!(t.operation, Operation::Screw);
        assert!((t.mating_direction - (-Vec3::z())).norm() < 1e-9);
    }
    // Everything goes in from above: no re-mounting.
    assert_eq!(best.mounts, 0);
    let plate_b = best.tasks.iter().find(|t| t.part == "plate_b").unwrap();
    assert_eq!(plate_b.base, "table");
    assert_eq!(plate_b.operation, Operation::Insertion);
    recheck(&doc, &plan);
    assert!(
        precedes(&plan, "plate_a", "screw1"),
        "{:?}",
        plan.precedence
    );
}

/// Whether `a` comes before `b` by the plan's (transitively reduced) precedence.
fn precedes(plan: &SequencePlan, a: &str, b: &str) -> bool {
    let mut reach = vec![a.to_string()];
    let mut i = 0;
    while i < reach.len() {
        let from = reach[i].clone();
        for (x, y) in &plan.precedence {
            if *x == from && !reach.contains(y) {
                reach.push(y.clone());
            }
        }
        i += 1;
    }
    reach.iter().skip(1).any(|n| n == b)
}

#[test]
fn cell_without_mates() {
    let doc = open("models/cell.yaml");
    let o = SequenceOptions {
        mode: Mode::Geometry,
        ..SequenceOptions::default()
    };
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
    let order = plan.best().order();
    let pos = |n: &str| order.iter().position(|o| o == n).unwrap();
    assert_eq!(order[0], "table");
    for s in ["screw1", "screw2", "screw3"] {
        assert!(pos("plate_a") < pos(s), "{order:?}");
    }
    assert_eq!(plan.best().mounts, 0);
    recheck(&doc, &plan);
}

/// The example script, run as a user runs it, writes the paper's answer as CSV.
#[test]
fn wheel_example_script_runs_as_documented() {
    let root = common::repo();
    let out = common::run_in(&root, &["run", "scripts/sequence_wheel.rhai"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let csv = std::fs::read_to_string(root.join("out/sequence_wheel.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 3, "{csv}");
    assert!(
        rows[1].starts_with("0,axis,gear,insertion,0,0,-1,"),
        "{csv}"
    );
    assert!(rows[2].starts_with("1,axis,cup,insertion,0,0,-1,"), "{csv}");
}

#[test]
fn plan_sequence_command_prints_json() {
    let root = common::repo();
    let out = common::run_in(&root, &["plan-sequence", "models/wheel.yaml", "--json"]);
    assert!(out.status.success(), "{}", common::text(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v["sequences"][0]["order"],
        serde_json::json!(["axis", "gear", "cup"])
    );
    assert_eq!(v["composites"], serde_json::json!([["axis", "gear"]]));
    let bad = common::run_in(
        &root,
        &["plan-sequence", "models/wheel.yaml", "--mode", "magic"],
    );
    assert_eq!(bad.status.code(), Some(2));
}

#[test]
fn bad_options_and_names_are_typed_errors() {
    use fitup::sequence::SequenceError;
    let doc = open("models/wheel.yaml");
    let mut cache = SceneCache::new();
    let with = |f: &dyn Fn(&mut SequenceOptions)| {
        let mut o = SequenceOptions::default();
        f(&mut o);
        o
    };
    for o in [
        with(&|o| o.time_limit_ms = Some(0.0)),
        with(&|o| o.time_limit_ms = Some(f64::NAN)),
        with(&|o| o.tolerance = -1.0),
        with(&|o| o.probe_mm = f64::INFINITY),
        with(&|o| o.max_sequences = 0),
        with(&|o| {
            o.masses.insert("gear".into(), -3.0);
        }),
    ] {
        let e = plan_sequence(&doc, &mut cache, &o).unwrap_err();
        assert!(matches!(e, SequenceError::InvalidOption { .. }), "{e}");
    }
    let e = plan_sequence(&doc, &mut cache, &with(&|o| o.base = Some("gearr".into()))).unwrap_err();
    assert!(e.to_string().contains("gear"), "{e}");
    assert!(safe_length(
        &doc,
        &mut cache,
        "cup",
        &Vec3::zeros(),
        &SequenceOptions::default()
    )
    .is_err());
    // A pinned base inside the composite node starts it: gear first, then the axis.
    let p = plan_sequence(&doc, &mut cache, &with(&|o| o.base = Some("gear".into()))).unwrap();
    assert_eq!(p.best().order()[0], "gear");
    recheck(&doc, &p);
}

#[test]
fn pegboard_of_ten_parts_with_and_without_mates() {
    let dir = std::env::temp_dir().join(format!("fitup_seq_pegboard_{}", std::process::id()));
    let doc = Document::open(&pegboard::pegboard(&dir, false)).unwrap();
    for mode in [Mode::Mates, Mode::Geometry] {
        let o = SequenceOptions {
            mode,
            ..SequenceOptions::default()
        };
        let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
        let best = plan.best();
        assert_eq!(best.order()[0], "plate", "{mode:?}");
        assert_eq!(best.mounts, 0);
        assert_eq!(plan.sequences.len(), 5, "several sequences ranked");
        for t in &best.tasks {
            assert_eq!(t.base, "plate");
            assert_eq!(t.operation, Operation::Insertion, "{}", t.part);
            assert!((t.mating_direction - (-Vec3::z())).norm() < 1e-9);
            // The peg clears its 5 mm hole before it may move sideways.
            assert!(t.safe_length > 4.5, "{}", t.safe_length);
        }
        recheck(&doc, &plan);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn interfering_assembly_is_a_fit_and_tiny_budgets_are_refused_in_bounded_time() {
    use fitup::math::Transform;
    let mut doc = open("models/wheel.yaml");
    // The gear sunk 1 mm into the axis's flange.
    let sunk = Transform::from_translation(Vec3::new(0.0, 0.0, 0.5));
    doc.set_transform("gear", sunk).unwrap();
    // Not a refusal (issue 38): the overlap is a fit, reported with its depth, and
    // the gear still leaves upwards (the way it was pushed in).
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &SequenceOptions::default()).unwrap();
    assert_eq!(plan.fits.len(), 1, "{:?}", plan.fits);
    let f = &plan.fits[0];
    assert!(f.a == "gear" || f.b == "gear", "{f:?}");
    assert!(f.depth > 0.0, "{f:?}");
    assert!(plan.summary().contains("fit: "), "{}", plan.summary());
    // A budget too small for the blocking graph: an error, quickly.
    let doc = open("models/cell.yaml");
    let o = SequenceOptions {
        time_limit_ms: Some(1.0),
        ..SequenceOptions::default()
    };
    let t = std::time::Instant::now();
    let r = plan_sequence(&doc, &mut SceneCache::new(), &o);
    assert!(r.is_err(), "1 ms cannot sequence the cell");
    assert!(t.elapsed().as_secs_f64() < 20.0, "{:?}", t.elapsed());
}

/// An independent dense re-check of every sequence: each task's path sampled every
/// `step_mm` (and its rotation every 0.01 rad) is tested with the exact interference
/// query against exactly the parts assembled before it, one pair at a time (no
/// planner validator involved).
fn dense_recheck(doc: &Document, plan: &SequencePlan, step_mm: f64) {
    let mut cache = SceneCache::new();
    let ws = fitup::workspace::Workspace::new(doc, &mut cache).unwrap();
    let scene = ws.scene();
    let tol = fitup::collision::DEFAULT_TOLERANCE;
    for s in &plan.sequences {
        let order = s.order();
        for (k, t) in s.tasks.iter().enumerate() {
            let (p, before) = step_parts(doc, &order, k, &t.part);
            for w in t.path.poses.windows(2) {
                let (a, b) = (w[0], w[1]);
                let len = (b.translation() - a.translation()).norm();
                let rot = a.rotation().angle_to(&b.rotation());
                let n = ((len / step_mm).max(rot / 0.01).ceil() as usize).max(1);
                for i in 0..=n {
                    let pose = a.interpolate(&b, i as f64 / n as f64);
                    let bp = scene.colliders[p].world_bounds(&pose);
                    for &q in &before {
                        assert!(
                            !common::interferes_in(scene, p, &pose, &bp, q, tol),
                            "{:?}: task {k} ({}) hits {} at sample {i}/{n}",
                            order,
                            t.part,
                            order[before.iter().position(|&x| x == q).unwrap()]
                        );
                    }
                }
            }
        }
    }
}

/// The 12-part gearbox (tests/common/gearbox.rs): a loop of mates on the post, parts
/// that must go in before their neighbours close them in, and a slider that needs a
/// non-straight insertion.
fn check_gearbox(doc: &Document, plan: &SequencePlan) {
    let best = plan.best();
    let order = best.order();
    let pos = |n: &str| order.iter().position(|o| o == n).unwrap();
    assert_eq!(order[0], "housing", "the heaviest part is the base");
    // Before their neighbours block them.
    assert!(pos("slider") < pos("cover"), "{order:?}");
    for s in ["screw1", "screw2", "screw3", "screw4"] {
        assert!(pos("cover") < pos(s), "{order:?}");
    }
    let stack = ["post", "bushing", "gear", "washer", "cap"];
    for w in stack.windows(2) {
        assert!(pos(w[0]) < pos(w[1]), "{order:?}");
    }
    // The slider: no straight insertion (roof above, walls around); its planned
    // path slides under the roof, not along one line.
    let k = best.tasks.iter().position(|t| t.part == "slider").unwrap();
    assert!(best.steps[k].planned, "the slider's path is planned");
    assert!(best.steps[k].mating_directions.is_empty());
    let poses = &best.tasks[k].path.poses;
    assert!(poses.len() >= 3, "{poses:?}");
    let first = poses[1].translation() - poses[0].translation();
    let last = poses[poses.len() - 1].translation() - poses[poses.len() - 2].translation();
    assert!(
        first.normalize().dot(&last.normalize()) < 0.9,
        "not straight: {poses:?}"
    );
    // Threaded components are screwed.
    for t in &best.tasks {
        let threaded = t.part.starts_with("screw") || t.part == "cap";
        assert_eq!(t.operation == Operation::Screw, threaded, "{}", t.part);
    }
    // Precedence: the order the geometry forces, in every sequence.
    for (a, b) in [
        ("slider", "cover"),
        ("cover", "screw1"),
        ("post", "bushing"),
        ("bushing", "gear"),
        ("gear", "washer"),
        ("washer", "cap"),
    ] {
        assert!(
            precedes(plan, a, b),
            "{a} before {b}: {:?}",
            plan.precedence
        );
    }
    // Cover before slider was tried and rejected with the reason.
    assert!(
        plan.rejected.iter().any(|r| {
            let p = |n: &str| r.order.iter().position(|o| o == n);
            p("cover").is_some()
                && p("slider").is_none()
                && r.reason.to_string().contains("slider is blocked along all")
                && r.reason.to_string().contains("cover")
        }),
        "{:#?}",
        plan.rejected
    );
    for s in &plan.sequences {
        let k = s.tasks.iter().position(|t| t.part == "slider").unwrap();
        assert!(s.steps[k].planned);
    }
    recheck(doc, plan);
    dense_recheck(doc, plan, 0.1);
}

#[test]
fn gearbox_with_mates() {
    let doc = open("models/gearbox.yaml");
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &SequenceOptions::default()).unwrap();
    check_gearbox(&doc, &plan);
    // The seed's loops: the post stack's mates are broken into one composite node
    // based on the post (the heavier by its `mass`; by volume the gear is larger),
    // its order the one the geometry allows.
    let g = &plan.graph;
    assert!(!g.loops.is_empty());
    let idx = |n: &str| doc.component_index(n).unwrap();
    let composite = g.nodes.iter().find(|n| n.is_composite()).unwrap();
    assert_eq!(
        composite.members,
        [idx("post"), idx("gear"), idx("washer"), idx("cap")]
    );
    // By volume alone the gear would be the composite's base.
    let vol = |i: usize| doc.mesh_of(i).signed_volume();
    let by_volume = fitup::sequence::RelationGraph::build(&doc, &vol);
    let c = by_volume.nodes.iter().find(|n| n.is_composite()).unwrap();
    assert_eq!(c.members[0], idx("gear"));
    assert_eq!(
        relation_graph(&doc)
            .nodes
            .iter()
            .find(|n| n.is_composite())
            .unwrap()
            .members[0],
        idx("post")
    );
}

#[test]
fn gearbox_without_mates() {
    // The same assembly with its mates deleted, planned from the meshes alone.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("models/gearbox.yaml").unwrap();
    let text = &text[..text.find("\nmates:").unwrap() + 1];
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    for e in std::fs::read_dir("models/meshes").unwrap() {
        let e = e.unwrap();
        if e.file_name().to_string_lossy().starts_with("gearbox_") {
            std::fs::copy(e.path(), dir.path().join("meshes").join(e.file_name())).unwrap();
        }
    }
    let path = dir.path().join("gearbox.yaml");
    std::fs::write(&path, text).unwrap();
    let doc = Document::open(&path).unwrap();
    assert!(doc.mates().is_empty());
    let o = SequenceOptions {
        mode: Mode::Geometry,
        ..SequenceOptions::default()
    };
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
    check_gearbox(&doc, &plan);
    assert!(plan.graph.loops.is_empty());
}

#[test]
fn revalidation_after_an_edit_names_the_broken_steps() {
    use fitup::math::Transform;
    use fitup::sequence::revalidate;
    let mut doc = open("models/gearbox.yaml");
    let mut cache = SceneCache::new();
    let plan = plan_sequence(&doc, &mut cache, &SequenceOptions::default()).unwrap();
    let tol = fitup::collision::DEFAULT_TOLERANCE;
    let seq = plan.best();
    assert!(revalidate(seq, &doc, &mut cache, tol).unwrap().is_empty());
    // The cover slid 30 mm right: over the cap's way down and off the screws' holes.
    let cover = Transform::from_translation(Vec3::new(30.0, 0.0, 20.0));
    doc.set_transform("cover", cover).unwrap();
    let broken = revalidate(seq, &doc, &mut cache, tol).unwrap();
    let why = |n: &str| {
        broken
            .iter()
            .find(|b| b.part == n)
            .map(|b| b.reason.clone())
    };
    assert!(why("cover").unwrap().contains("moved"), "{broken:#?}");
    assert!(why("cap").unwrap().contains("hits cover"), "{broken:#?}");
    assert!(why("screw2").unwrap().contains("cover"), "{broken:#?}");
    // Every other broken step is blocked by the cover; the slider (in before it) and
    // the screws left of its new place still hold.
    for b in &broken {
        assert!(
            b.part == "cover" || b.reason.ends_with("hits cover"),
            "{b:?}"
        );
    }
    for n in ["slider", "screw1", "screw3"] {
        assert!(why(n).is_none(), "{n}: {broken:#?}");
    }
    // In task order.
    assert!(broken.windows(2).all(|w| w[0].index < w[1].index));
}

#[test]
fn component_mass_and_threaded_are_read_and_validated() {
    let doc = open("models/gearbox.yaml");
    let c = |n: &str| doc.components()[doc.component_index(n).unwrap()].clone();
    assert_eq!(c("housing").mass, Some(2.5));
    assert_eq!(c("washer").mass, None);
    assert!(c("cap").threaded && c("screw1").threaded && !c("gear").threaded);
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    std::fs::copy(
        "models/meshes/gearbox_slider.stl",
        dir.path().join("meshes/gearbox_slider.stl"),
    )
    .unwrap();
    for (bad, what) in [("-1.0", "mass"), (".nan", "mass"), ("1e400", "mass")] {
        let text = format!(
            "parts:\n  slider:\n    stl: meshes/gearbox_slider.stl\ncomponents:\n- name: a\n  part: slider\n  mass: {bad}\n"
        );
        let path = dir.path().join("bad.yaml");
        std::fs::write(&path, text).unwrap();
        let e = Document::open(&path).unwrap_err().to_string();
        assert!(e.contains(what) && e.contains("bad.yaml"), "{bad}: {e}");
        assert!(e.contains(":7:"), "located on the mass line: {e}");
    }
}

/// `Sequence.revalidate` from a script: plan the wheel, move the gear up 1 mm, and
/// the broken steps are named with their reasons (the gear moved; the cup's way
/// down now hits the gear); moved back, every step holds again.
#[test]
fn revalidate_from_a_script_names_the_broken_steps() {
    let dir = common::project();
    let p = dir.path();
    common::copy_wheel(p);
    std::fs::write(
        p.join("scripts/reval.rhai"),
        r#"let d = open_doc("models/wheel.yaml");
let s = d.assembly_sequence();
assert(s.order == ["axis", "gear", "cup"], `${s.order}`);
assert(s.revalidate(d).is_empty(), "nothing moved: every step holds");
d.set_transform("gear", [0, 0, 2.5, 0, 0, 0]);
let broken = s.revalidate(d);
for b in broken { print(`broken ${b.index} ${b.part}: ${b.reason}`); }
assert(broken.len() == 2, `${broken}`);
assert(broken[0].index == 0 && broken[0].part == "gear", `${broken}`);
assert(broken[0].reason.contains("moved"), broken[0].reason);
assert(broken[1].part == "cup" && broken[1].reason.contains("hits gear"), broken[1].reason);
// A finer tolerance is accepted; a negative one is an error.
assert(s.revalidate(d, 0.001).len() == 2);
let bad = false;
try { s.revalidate(d, -1.0); } catch (e) { bad = true; }
assert(bad, "a negative tolerance is refused");
d.set_transform("gear", [0, 0, 1.5, 0, 0, 0]);
assert(s.revalidate(d).is_empty(), "moved back: every step holds");
print("revalidate ok");
"#,
    )
    .unwrap();
    let out = common::run_in(p, &["run", "scripts/reval.rhai"]);
    let text = common::text(&out);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("broken 0 gear:"), "{text}");
    assert!(text.contains("revalidate ok"), "{text}");
}

/// The safe length does not depend on the tessellation: the fine pegboard's pegs
/// (1200 facets of 0.0105 mm, about the tolerance) come out as far as the coarse
/// ones'. Before the exact check's depth walk, every crossing pair of the fine
/// meshes was within the tolerance and a peg pushed into its hole wall read as
/// touching, giving 0.89 mm instead of the whole shaft.
#[test]
fn fine_pegboard_safe_length_matches_the_coarse_one() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // The setup of the fine board (its blocking graph) on a loaded machine can take
    // longer than the default 30 s; this test is about the answer, not the budget.
    let o = SequenceOptions {
        mode: Mode::Geometry,
        time_limit_ms: Some(600_000.0),
        ..Default::default()
    };
    let mut lengths = Vec::new();
    for segments in [16, 1200] {
        let path = pegboard::pegboard_with(&dir.join(format!("s{segments}")), true, segments);
        let doc = Document::open(&path).unwrap();
        let mut cache = SceneCache::new();
        let up = Vec3::new(0.0, 0.0, 1.0);
        lengths.push(safe_length(&doc, &mut cache, "peg11", &up, &o).unwrap());
    }
    // the shaft is 5 mm long: free once it has left the plate
    assert!(lengths[0] >= 5.0, "{lengths:?}");
    assert_eq!(lengths[0], lengths[1], "coarse vs fine");
}
