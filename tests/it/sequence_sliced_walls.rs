//! Issue 26: parts whose meshes are closed but not 2-manifold (walls cut in stacked
//! closed slices, as the bench's sliced duct and many CAD exports), sliding into an
//! equal neighbour. Every face such a part pushes into the neighbour lies in the
//! plane of one of the neighbour's faces or meets them edge-on, so no pair of
//! triangles crosses; the sequencer must still see the neighbour block the way.
//! Each returned path is re-checked here by plain box arithmetic (the parts are
//! unions of axis-aligned boxes), not by the collision engine.

use fitup::document::Document;
use fitup::math::Transform;
use fitup::mesh::Mesh;
use fitup::sequence::{plan_sequence, SequenceOptions};
use fitup::workspace::SceneCache;

use crate::common::duct;

type Boxes = Vec<([f64; 3], [f64; 3])>;

/// A block `lo..hi` cut in `slices` stacked boxes along Z, as one closed,
/// non-manifold mesh (the slices share their faces).
fn sliced(lo: [f64; 3], hi: [f64; 3], slices: usize) -> Mesh {
    // One expression per level, so the two slices meeting there share its bits.
    let level = |k: usize| lo[2] + (hi[2] - lo[2]) * k as f64 / slices as f64;
    let list: Boxes = (0..slices)
        .map(|s| ([lo[0], lo[1], level(s)], [hi[0], hi[1], level(s + 1)]))
        .collect();
    duct::boxes(&list, &Transform::IDENTITY)
}

/// A frame (plate, two side walls, a back wall and a roof) with a pocket open only
/// toward +Y, block `a` in the pocket (1 mm clear of walls and roof) and block `b`,
/// equal to `a` in X and Z, outside it against `a`'s open face. `a` can only leave
/// along +Y, which `b` blocks: `a` must go in before `b`.
fn pocket() -> Vec<(&'static str, Boxes)> {
    vec![
        (
            "frame",
            vec![
                ([-20.0, -20.0, -5.0], [20.0, 40.0, 0.0]),
                ([-10.0, -10.0, 0.0], [-8.0, 7.0, 21.0]),
                ([8.0, -10.0, 0.0], [10.0, 7.0, 21.0]),
                ([-8.0, -10.0, 0.0], [8.0, -8.0, 21.0]),
                ([-10.0, -10.0, 21.0], [10.0, 7.0, 23.0]),
            ],
        ),
        ("a", vec![([-7.0, -7.0, 0.0], [7.0, 7.0, 20.0])]),
        ("b", vec![([-7.0, 7.0, 0.0], [7.0, 21.0, 20.0])]),
    ]
}

/// Whether boxes `p` moved by `t` and boxes `q` overlap deeper than `tol` (mm) on
/// every axis.
fn overlap(p: &Boxes, t: &Transform, q: &Boxes, tol: f64) -> bool {
    let shift = t.translation();
    p.iter().any(|(lo, hi)| {
        q.iter().any(|(qlo, qhi)| {
            (0..3).all(|k| (hi[k] + shift[k]).min(qhi[k]) - (lo[k] + shift[k]).max(qlo[k]) > tol)
        })
    })
}

#[test]
fn an_equal_sliced_neighbour_blocks_the_way() {
    let dir = tempfile::tempdir().unwrap();
    let parts = pocket();
    let meshes: Vec<(&str, Mesh)> = parts
        .iter()
        .map(|(name, list)| {
            let mesh = if *name == "frame" {
                duct::boxes(list, &Transform::IDENTITY)
            } else {
                sliced(list[0].0, list[0].1, 12)
            };
            (*name, mesh)
        })
        .collect();
    let doc = Document::open(&duct::write_doc(dir.path(), &meshes)).unwrap();
    let o = SequenceOptions {
        time_limit_ms: Some(60_000.0),
        ..SequenceOptions::default()
    };
    let plan = plan_sequence(&doc, &mut SceneCache::new(), &o).unwrap();
    let boxes_of = |name: &str| &parts.iter().find(|(n, _)| *n == name).unwrap().1;
    assert!(
        plan.complete && !plan.sequences.is_empty(),
        "{}",
        plan.summary()
    );
    for s in &plan.sequences {
        let order = s.order();
        // Before the fix the sequencer also returned frame, b, a: `a` pushed out
        // through `b` (every triangle pair at depth 0 on the way).
        assert_eq!(order, ["frame", "a", "b"], "{}", plan.summary());
        // The box arithmetic re-check: each task's path, 0.1 mm steps, against
        // the parts placed before it.
        for (k, t) in s.tasks.iter().enumerate() {
            let moving = boxes_of(&t.part);
            for w in t.path.poses.windows(2) {
                let (from, to) = (w[0].translation(), w[1].translation());
                assert!(
                    w[0].distance_to(&w[1]).0 < 1e-12,
                    "{}: a turning path",
                    t.part
                );
                let n = ((to - from).norm() / 0.1).ceil().max(1.0) as usize;
                for i in 0..=n {
                    let at = from + (to - from) * (i as f64 / n as f64);
                    let pose = Transform::from_translation(at);
                    for placed in &order[..k + 1] {
                        assert!(
                            !overlap(moving, &pose, boxes_of(placed), 0.01),
                            "{} passes through {placed} at {at:?}",
                            t.part
                        );
                    }
                }
            }
        }
    }
}
