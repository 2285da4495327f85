//! Properties of the interference methods (unit tests of `collision`).

use super::triangle::{tri_distance, tri_tri};
use super::*;
use crate::math::{Point3, Rng, Transform, Vec3};
use crate::mesh::Mesh;
use std::sync::Arc;

#[path = "../../tests/common/fixtures.rs"]
mod fixtures;

fn collider(m: Mesh) -> Collider {
    Collider::new(Arc::new(m)).expect("valid mesh")
}

fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Collider {
    collider(Mesh::cuboid(lo.into(), hi.into()))
}

fn at(x: f64, y: f64, z: f64) -> Transform {
    Transform::from_translation(Vec3::new(x, y, z))
}

fn random_pose(rng: &mut Rng, spread: f64) -> Transform {
    Transform::from_parts(
        Vec3::new(
            rng.range(-spread, spread),
            rng.range(-spread, spread),
            rng.range(-spread, spread),
        ),
        rng.rotation(),
    )
}

const TOL: f64 = DEFAULT_TOLERANCE;

/// [`sweep`] of `mover` along `motion` in pose checks at most `step` mm of
/// displacement apart, with the test tolerance.
fn stepwise_sweep(
    mover: &Collider,
    motion: &Motion,
    obstacles: &[Obstacle<'_>],
    step: f64,
) -> SweepHit {
    let options = SweepOptions {
        method: SweepMethod::displacement_steps(step),
        tolerance: TOL,
        ..Default::default()
    };
    sweep(mover, motion, obstacles, &options).unwrap()
}

#[test]
fn plate_on_table_touches_in_any_world_pose() {
    let table = cuboid([-50.0, -50.0, -20.0], [50.0, 50.0, 0.0]);
    let plate = cuboid([0.0, 0.0, 0.0], [30.0, 20.0, 5.0]);
    let mut rng = Rng::new(1);
    for k in 0..20 {
        let world = if k == 0 {
            Transform::IDENTITY
        } else {
            random_pose(&mut rng, 100.0)
        };
        let on = at(rng.range(-40.0, 10.0), rng.range(-40.0, 25.0), 0.0).then(&world);
        let c = contact(&plate, &on, &table, &world, TOL).unwrap();
        assert_eq!(c, Contact::Touching, "pose {k}");
        assert!(!interferes(&plate, &on, &table, &world, TOL).unwrap());
        // 0.5 mm into the table interferes with depth 0.5
        let sunk = at(0.0, 0.0, -0.5).then(&on);
        let c = contact(&plate, &sunk, &table, &world, TOL).unwrap();
        assert!(c.is_interfering(), "pose {k}: {c:?}");
        assert!((c.depth() - 0.5).abs() < 1e-6, "pose {k}: {c:?}");
        // 1 mm above is separate
        let above = at(0.0, 0.0, 1.0).then(&on);
        assert_eq!(
            contact(&plate, &above, &table, &world, TOL).unwrap(),
            Contact::Separate
        );
    }
}

#[test]
fn plate_flush_with_the_table_edge_touches() {
    let table = cuboid([0.0, 0.0, -20.0], [100.0, 100.0, 0.0]);
    let plate = cuboid([0.0, 0.0, 0.0], [100.0, 40.0, 5.0]);
    assert_eq!(
        contact(
            &plate,
            &at(0.0, 0.0, 0.0),
            &table,
            &Transform::IDENTITY,
            TOL
        )
        .unwrap(),
        Contact::Touching
    );
    // side by side, flush faces
    let other = cuboid([0.0, 0.0, 0.0], [100.0, 40.0, 5.0]);
    let c = contact(
        &plate,
        &Transform::IDENTITY,
        &other,
        &at(0.0, 40.0, 0.0),
        TOL,
    )
    .unwrap();
    assert_eq!(c, Contact::Touching);
}

#[test]
fn screw_in_a_hole_of_its_diameter_touches() {
    let plate = collider(fixtures::plate_with_hole(20.0, 4.0, 3.0, 32));
    let pin = collider(Mesh::cylinder(3.0, 10.0, 32));
    let screw = collider(fixtures::screw(3.0, 4.0, 5.0, 2.0, 32));
    let mut rng = Rng::new(2);
    for k in 0..10 {
        let world = if k == 0 {
            Transform::IDENTITY
        } else {
            random_pose(&mut rng, 50.0)
        };
        let through = at(0.0, 0.0, -3.0).then(&world);
        assert_eq!(
            contact(&pin, &through, &plate, &world, TOL).unwrap(),
            Contact::Touching,
            "pose {k}"
        );
        // the screw's head rests on the plate's top face
        assert_eq!(
            contact(&screw, &world, &plate, &world, TOL).unwrap(),
            Contact::Touching,
            "pose {k}"
        );
        // 0.2 mm off the axis, the pin cuts into the wall
        let off = at(0.2, 0.0, -3.0).then(&world);
        assert!(
            interferes(&pin, &off, &plate, &world, TOL).unwrap(),
            "pose {k}"
        );
    }
}

#[test]
fn one_mm_overlap_has_depth_one() {
    let a = cuboid([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]);
    let b = cuboid([0.0, 0.0, 0.0], [10.0, 6.0, 6.0]);
    let c = contact(&a, &Transform::IDENTITY, &b, &at(9.0, 2.0, 2.0), TOL).unwrap();
    assert!(
        matches!(
            c,
            Contact::Interfering {
                kind: InterferenceKind::SurfacesCross,
                ..
            }
        ),
        "{c:?}"
    );
    assert!((c.depth() - 1.0).abs() < 1e-9, "{c:?}");
    // flush sides but overlapping by 5 mm in Z: interference, not touching
    let c = contact(&a, &Transform::IDENTITY, &a, &at(0.0, 0.0, 5.0), TOL).unwrap();
    assert!((c.depth() - 5.0).abs() < 1e-9, "{c:?}");
    // within the tolerance: touching
    let c = contact(&a, &Transform::IDENTITY, &b, &at(9.995, 2.0, 2.0), TOL).unwrap();
    assert_eq!(c, Contact::Touching);
    let c = contact(&a, &Transform::IDENTITY, &b, &at(9.995, 2.0, 2.0), 0.001).unwrap();
    assert!(c.is_interfering());
}

#[test]
fn swallowed_part_is_contained() {
    let big = cuboid([0.0, 0.0, 0.0], [100.0, 100.0, 100.0]);
    let ball = collider(fixtures::sphere(10.0, 24, 12));
    let c = contact(
        &ball,
        &at(50.0, 40.0, 30.0),
        &big,
        &Transform::IDENTITY,
        TOL,
    )
    .unwrap();
    match c {
        Contact::Interfering {
            depth,
            kind:
                InterferenceKind::Contained {
                    inner: PairMember::First,
                },
        } => assert!((depth - 40.0).abs() < 1e-6, "{depth}"),
        other => panic!("{other:?}"),
    }
    let c2 = contact(
        &big,
        &Transform::IDENTITY,
        &ball,
        &at(50.0, 40.0, 30.0),
        TOL,
    )
    .unwrap();
    assert_eq!(c2, c.swapped());
    assert!(interferes(
        &big,
        &Transform::IDENTITY,
        &ball,
        &at(50.0, 40.0, 30.0),
        TOL
    )
    .unwrap());
    // identical coincident parts overlap completely
    assert!(
        contact(&big, &Transform::IDENTITY, &big, &Transform::IDENTITY, TOL)
            .unwrap()
            .is_interfering()
    );
    // outside: separate
    assert_eq!(
        contact(&ball, &at(150.0, 0.0, 0.0), &big, &Transform::IDENTITY, TOL).unwrap(),
        Contact::Separate
    );
}

#[test]
fn open_meshes_get_surface_checks_and_a_warning() {
    let mut open = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 10.0, 10.0));
    open.triangles.pop();
    let open = collider(open);
    assert!(matches!(
        open.warnings()[0],
        ColliderWarning::NotWatertight(_)
    ));
    let big = cuboid([-100.0; 3], [100.0; 3]);
    // inside but no containment can be decided for the open part... the big one is
    // solid, so the open part inside it is still reported as contained
    let c = contact(&open, &Transform::IDENTITY, &big, &Transform::IDENTITY, TOL).unwrap();
    assert!(c.is_interfering());
    // the big solid inside an open shell: no containment without an inside
    let small = cuboid([2.0; 3], [3.0; 3]);
    assert_eq!(
        contact(
            &small,
            &Transform::IDENTITY,
            &open,
            &Transform::IDENTITY,
            TOL
        )
        .unwrap(),
        Contact::Separate
    );
    // surfaces crossing still found
    assert!(interferes(&open, &Transform::IDENTITY, &big, &at(105.0, 0.0, 0.0), TOL).unwrap());
}

#[test]
fn verdicts_are_symmetric_and_fast_path_agrees() {
    let a = collider(fixtures::torus(20.0, 5.0, 32, 16));
    let b = collider(fixtures::sphere(12.0, 20, 10));
    let mut rng = Rng::new(3);
    let mut kinds = [0usize; 3];
    for _ in 0..300 {
        let (pa, pb) = (random_pose(&mut rng, 25.0), random_pose(&mut rng, 25.0));
        let ab = contact(&a, &pa, &b, &pb, TOL).unwrap();
        let ba = contact(&b, &pb, &a, &pa, TOL).unwrap();
        assert_eq!(ab.is_interfering(), ba.is_interfering());
        assert!((ab.depth() - ba.depth()).abs() < 1e-9, "{ab:?} {ba:?}");
        if let Contact::Interfering {
            kind: InterferenceKind::Contained { .. },
            ..
        } = ab
        {
            assert_eq!(ab, ba.swapped());
        }
        assert_eq!(
            ab.is_interfering(),
            interferes(&a, &pa, &b, &pb, TOL).unwrap()
        );
        kinds[match ab {
            Contact::Separate => 0,
            Contact::Touching => 1,
            Contact::Interfering { .. } => 2,
        }] += 1;
    }
    assert!(kinds[0] > 20 && kinds[2] > 20, "{kinds:?}");
}

#[test]
fn tree_traversal_matches_brute_force() {
    let a = collider(fixtures::torus(10.0, 3.0, 16, 8));
    let b = collider(fixtures::sphere(6.0, 12, 6));
    let mut rng = Rng::new(4);
    for _ in 0..100 {
        let (pa, pb) = (random_pose(&mut rng, 12.0), random_pose(&mut rng, 12.0));
        let ta: Vec<_> = a.tris().map(|t| t.map(|p| pa.apply(&p))).collect();
        let tb: Vec<_> = b.tris().map(|t| t.map(|p| pb.apply(&p))).collect();
        let mut depth = None::<f64>;
        let mut dist = f64::INFINITY;
        for x in &ta {
            for y in &tb {
                if let Some(d) = tri_tri(x, y, 1e-8, true) {
                    depth = Some(depth.unwrap_or(0.0).max(d));
                }
                dist = dist.min(tri_distance(x, y));
            }
        }
        let c = contact(&a, &pa, &b, &pb, TOL).unwrap();
        match depth {
            Some(d) if d > TOL => assert!((c.depth() - d).abs() < 1e-6, "{c:?} vs {d}"),
            Some(_) => assert!(c != Contact::Separate),
            None => assert!(!matches!(
                c,
                Contact::Touching
                    | Contact::Interfering {
                        kind: InterferenceKind::SurfacesCross,
                        ..
                    }
            )),
        }
        let d = surface_distance(&a, &pa, &b, &pb, 0.0).unwrap();
        assert!((d - dist).abs() < 1e-6, "{d} vs {dist}");
    }
}

/// A fine part across the faces of a coarse box (where the traversal drops subtrees
/// on one side of every plane of a leaf's triangles) agrees with all pairs.
#[test]
fn coarse_box_against_fine_part_matches_brute_force() {
    let a = collider(fixtures::torus(10.0, 3.0, 40, 12));
    let b = cuboid([-8.0, -8.0, -8.0], [8.0, 8.0, 8.0]);
    let mut rng = Rng::new(21);
    let mut kinds = [0usize; 3];
    for _ in 0..150 {
        let (pa, pb) = (random_pose(&mut rng, 10.0), random_pose(&mut rng, 10.0));
        let ta: Vec<_> = a.tris().map(|t| t.map(|p| pa.apply(&p))).collect();
        let tb: Vec<_> = b.tris().map(|t| t.map(|p| pb.apply(&p))).collect();
        let mut depth = None::<f64>;
        for x in &ta {
            for y in &tb {
                if let Some(d) = tri_tri(x, y, 1e-8, true) {
                    depth = Some(depth.unwrap_or(0.0).max(d));
                }
            }
        }
        let c = contact(&a, &pa, &b, &pb, TOL).unwrap();
        let hit = interferes(&a, &pa, &b, &pb, TOL).unwrap();
        assert_eq!(hit, matches!(c, Contact::Interfering { .. }), "{c:?}");
        match depth {
            Some(d) if d > TOL => {
                assert!(hit);
                assert!((c.depth() - d).abs() < 1e-6, "{c:?} vs {d}");
                kinds[0] += 1;
            }
            Some(_) => {
                assert!(c != Contact::Separate);
                kinds[1] += 1;
            }
            None => {
                assert!(matches!(
                    c,
                    Contact::Separate
                        | Contact::Interfering {
                            kind: InterferenceKind::Contained { .. },
                            ..
                        }
                ));
                kinds[2] += 1;
            }
        }
    }
    assert!(kinds[0] > 20 && kinds[2] > 20, "{kinds:?}");
}

#[test]
fn bad_input_is_refused() {
    let a = cuboid([0.0; 3], [1.0; 3]);
    let nan = Transform::from_translation(Vec3::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(
        contact(&a, &nan, &a, &Transform::IDENTITY, TOL),
        Err(CollisionError::BadPose(_))
    ));
    assert!(matches!(
        interferes(&a, &Transform::IDENTITY, &a, &nan, TOL),
        Err(CollisionError::BadPose(_))
    ));
    assert!(matches!(
        contact(&a, &Transform::IDENTITY, &a, &Transform::IDENTITY, -1.0),
        Err(CollisionError::BadTolerance(_))
    ));
    assert!(contact(&a, &Transform::IDENTITY, &a, &Transform::IDENTITY, f64::NAN).is_err());
    let flat = Mesh {
        vertices: vec![
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 0, 1]],
    };
    assert!(matches!(
        Collider::new(Arc::new(flat)),
        Err(CollisionError::BadMesh(_))
    ));
    let huge = Mesh::cuboid(Point3::origin(), Point3::new(1e12, 1.0, 1.0));
    assert!(matches!(
        Collider::new(Arc::new(huge)),
        Err(CollisionError::BadMesh(_))
    ));
    let bad_index = Mesh {
        vertices: vec![Point3::origin()],
        triangles: vec![[0, 1, 2]],
    };
    assert!(Collider::new(Arc::new(bad_index)).is_err());
    // large but accepted coordinates still give sane answers
    let far = 1e6;
    let c = contact(&a, &at(far, far, far), &a, &at(far + 0.5, far, far), TOL).unwrap();
    assert!(c.is_interfering(), "{c:?}");
    assert_eq!(
        contact(&a, &at(far, far, far), &a, &at(far + 1.0, far, far), TOL).unwrap(),
        Contact::Touching
    );
}

#[test]
fn degenerate_triangles_are_ignored_with_a_warning() {
    let mut m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
    m.triangles.push([0, 0, 1]);
    let c = collider(m);
    assert!(c
        .warnings()
        .iter()
        .any(|w| matches!(w, ColliderWarning::DegenerateTriangles(1))));
    assert_eq!(c.triangle_count(), 12);
}

#[test]
fn cells_of_a_solid_block_are_full_boxes() {
    let block = cuboid([0.0; 3], [10.0, 10.0, 10.0]);
    let cells = CutCells::derive(&block, CutSpec::Size(5.0)).unwrap();
    assert_eq!(cells.grid, [2, 2, 2]);
    assert_eq!(cells.cells.len(), 8);
    for c in &cells.cells {
        for k in 0..3 {
            assert!(
                (c.bounds.hi[k] - c.bounds.lo[k] - 5.0).abs() < 1e-12,
                "{c:?}"
            );
        }
    }
    // a 3x3x3 cut of a 9 mm cube: the centre cell has no surface but is full
    let cube = cuboid([0.0; 3], [9.0; 3]);
    let cells = CutCells::derive(&cube, CutSpec::Size(3.0)).unwrap();
    let centre = cells
        .cells
        .iter()
        .find(|c| c.index == [1, 1, 1])
        .expect("centre cell");
    assert_eq!(centre.bounds, Aabb::new([3.0; 3], [6.0; 3]));
}

#[test]
fn cells_skip_holes_and_cover_the_material() {
    let plate_mesh = fixtures::perforated_plate((4, 4), 4.0, 8.0, 4.0, 2.0);
    let plate = collider(plate_mesh);
    let cells = CutCells::derive(&plate, CutSpec::Size(2.0)).unwrap();
    let boxes = cells.boxes();
    // no cell box inside a hole: the first hole spans x, y in [4, 8]
    let covering: Vec<_> = cells
        .cells
        .iter()
        .filter(|c| {
            c.bounds.lo[0] <= 6.0
                && c.bounds.hi[0] >= 6.0
                && c.bounds.lo[1] <= 6.0
                && c.bounds.hi[1] >= 6.0
        })
        .collect();
    assert!(covering.is_empty(), "{covering:?}");
    let mut rng = Rng::new(5);
    let bb = plate.bounds();
    let mut inside = 0;
    for _ in 0..2000 {
        let p = Point3::new(
            rng.range(bb.lo.x, bb.hi.x),
            rng.range(bb.lo.y, bb.hi.y),
            rng.range(bb.lo.z, bb.hi.z),
        );
        if plate.contains_point(&p) {
            inside += 1;
            assert!(
                boxes.iter().any(|b| b.distance_to_point(&p) <= 1e-12),
                "{p:?} not covered"
            );
        }
    }
    assert!(inside > 500);
    // explicit planes
    let by_planes = CutCells::derive(
        &plate,
        CutSpec::Planes {
            x: vec![10.0, 20.0],
            y: vec![],
            z: vec![1.0, 99.0],
        },
    )
    .unwrap();
    assert_eq!(by_planes.grid, [3, 1, 2]);
}

#[test]
fn bad_cell_requests_are_refused() {
    let block = cuboid([0.0; 3], [100.0; 3]);
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(
                CutCells::derive(&block, CutSpec::Size(s)),
                Err(CollisionError::BadCells(_))
            ),
            "{s}"
        );
    }
    let e = CutCells::derive(&block, CutSpec::Size(0.5)).unwrap_err();
    assert!(e.to_string().contains("8000000 cells"), "{e}");
    let e = CutCells::derive(&block, CutSpec::Size(1e-300)).unwrap_err();
    assert!(matches!(e, CollisionError::TooManyCells { .. }), "{e}");
    let planes = CutSpec::Planes {
        x: vec![f64::NAN],
        y: vec![],
        z: vec![],
    };
    assert!(CutCells::derive(&block, planes).is_err());
}

#[test]
fn cells_never_miss_an_exact_interference() {
    let plate = collider(fixtures::perforated_plate((5, 5), 4.0, 8.0, 4.0, 3.0));
    let pin = collider(Mesh::cylinder(1.8, 12.0, 16));
    let mut rng = Rng::new(6);
    for size in [1.0, 2.5, 6.0] {
        let pc = CutCells::derive(&plate, CutSpec::Size(size)).unwrap();
        let nc = CutCells::derive(&pin, CutSpec::Size(size)).unwrap();
        let fixed = PosedPart {
            collider: &plate,
            cells: Some(&pc),
            pose: Transform::IDENTITY,
        };
        for _ in 0..300 {
            let tilt = crate::math::AngleConvention::XyzFixed.rotation(
                rng.range(-0.3, 0.3),
                rng.range(-0.3, 0.3),
                rng.uniform() * 6.3,
            );
            let pose = Transform::from_parts(
                Vec3::new(
                    rng.range(0.0, 44.0),
                    rng.range(0.0, 44.0),
                    rng.range(-8.0, 2.0),
                ),
                tilt,
            );
            let m = PosedPart {
                collider: &pin,
                cells: Some(&nc),
                pose,
            };
            let exact = check(Method::Exact, &fixed, &m, TOL).unwrap();
            let cells = check(Method::Cells, &fixed, &m, TOL).unwrap();
            let aabb = check(Method::Aabb, &fixed, &m, TOL).unwrap();
            if exact != Contact::Separate {
                assert!(
                    cells != Contact::Separate,
                    "size {size}: {exact:?} vs {cells:?}"
                );
            }
            if cells != Contact::Separate {
                assert!(aabb != Contact::Separate);
            }
        }
    }
}

#[test]
fn disagreement_is_measured_and_reproducible() {
    let plate = collider(fixtures::perforated_plate((5, 5), 4.0, 8.0, 4.0, 3.0));
    let pin = collider(Mesh::cylinder(1.5, 12.0, 16));
    let pc = CutCells::derive(&plate, CutSpec::Size(2.0)).unwrap();
    let nc = CutCells::derive(&pin, CutSpec::Size(2.0)).unwrap();
    let fixed = [PosedPart {
        collider: &plate,
        cells: Some(&pc),
        pose: Transform::IDENTITY,
    }];
    // near a hole centre (6 + 8 k): sometimes in the clear, sometimes in the wall
    let sampler = |r: &mut Rng| {
        let c = |r: &mut Rng| 6.0 + 8.0 * r.below(5) as f64 + r.range(-0.8, 0.8);
        at(c(r), c(r), r.range(-8.0, 2.0))
    };
    let d1 = method_disagreement(&fixed, (&pin, Some(&nc)), sampler, 200, 9, TOL).unwrap();
    let d2 = method_disagreement(&fixed, (&pin, Some(&nc)), sampler, 200, 9, TOL).unwrap();
    assert_eq!(d1, d2);
    assert_eq!(d1.cells_false_negatives, 0);
    assert!(
        d1.exact_interfering > 0 && d1.exact_interfering < 200,
        "{d1:?}"
    );
    // boxes of the whole plate cover the holes: always interfering in this region
    assert!(
        d1.aabb_false_positives >= d1.cells_false_positives,
        "{d1:?}"
    );
}

#[test]
fn check_all_reports_touching_and_interfering_pairs() {
    let table = cuboid([-50.0, -50.0, -20.0], [50.0, 50.0, 0.0]);
    let plate = cuboid([0.0; 3], [20.0, 20.0, 5.0]);
    let parts = [
        PosedPart {
            collider: &table,
            cells: None,
            pose: Transform::IDENTITY,
        },
        PosedPart {
            collider: &plate,
            cells: None,
            pose: Transform::IDENTITY,
        },
        PosedPart {
            collider: &plate,
            cells: None,
            pose: at(10.0, 10.0, 0.0),
        },
        PosedPart {
            collider: &plate,
            cells: None,
            pose: at(200.0, 0.0, 0.0),
        },
    ];
    let found = check_all(&parts, Method::Exact, TOL).unwrap();
    let pairs: Vec<_> = found
        .iter()
        .map(|p| (p.a, p.b, p.contact.is_interfering()))
        .collect();
    assert_eq!(pairs, vec![(0, 1, false), (0, 2, false), (1, 2, true)]);
}

#[test]
fn collider_cache_reuses_trees_for_the_same_mesh() {
    let mut cache = ColliderCache::new();
    let m = Arc::new(Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0)));
    let a = cache.get(&m).unwrap();
    let b = cache.get(&m).unwrap();
    assert!(Arc::ptr_eq(&a, &b));
    let m2 = Arc::new((*m).clone());
    let c = cache.get(&m2).unwrap();
    assert!(!Arc::ptr_eq(&a, &c));
    assert_eq!(cache.build_count(), 2);
}

/// A 0.2 mm wall at x = 12.3 and a 1 mm thick plate at the origin that
/// [`along_x`] moves toward it.
fn thin_wall_scene() -> (Collider, Collider) {
    let wall = cuboid([12.3, -20.0, -20.0], [12.5, 20.0, 20.0]);
    let mover = cuboid([0.0, -5.0, -5.0], [1.0, 5.0, 5.0]);
    (wall, mover)
}

/// `collider` as the one obstacle of a sweep, at the identity.
fn fixed(collider: &Collider) -> [Obstacle<'_>; 1] {
    [Obstacle {
        collider,
        pose: Transform::IDENTITY,
    }]
}

/// A translation from the identity by `mm` along +X.
fn along_x(mm: f64) -> Motion {
    Motion::Translation {
        start: Transform::IDENTITY,
        offset: Vec3::new(mm, 0.0, 0.0),
    }
}

#[test]
fn continuous_sweep_finds_the_thin_wall_that_steps_jump_over() {
    let (wall, mover) = thin_wall_scene();
    let obstacles = fixed(&wall);
    let motion = along_x(20.0);
    let stepped = stepwise_sweep(&mover, &motion, &obstacles, 5.0);
    assert!(!stepped.hit, "{stepped:?}");
    let cont = sweep(&mover, &motion, &obstacles, &SweepOptions::default()).unwrap();
    assert!(cont.hit && cont.with == Some(0));
    // first contact: the front face x = 1 reaches x = 12.3 (+ the tolerance)
    let x = cont.t * 20.0;
    assert!(x > 11.3 && x < 11.3 + 2.0 * TOL, "{x}");
    assert!(interferes(&mover, &cont.pose, &wall, &Transform::IDENTITY, TOL).unwrap());
    // fine stepwise scan: nothing earlier
    let fine = stepwise_sweep(&mover, &motion, &obstacles, TOL / 4.0);
    assert!(
        fine.hit && fine.t >= cont.t - TOL / 20.0,
        "{} vs {}",
        fine.t,
        cont.t
    );
}

#[test]
fn continuous_rotation_and_pose_sequences_find_first_contact() {
    let post = cuboid([30.0, -1.0, -5.0], [30.4, 1.0, 5.0]);
    let arm = cuboid([0.0, -1.0, -1.0], [40.0, 1.0, 1.0]);
    let obstacles = [Obstacle {
        collider: &post,
        pose: at(0.0, 20.0, 0.0),
    }];
    let rot = Motion::Rotation {
        start: Transform::IDENTITY,
        centre: Point3::origin(),
        axis: Vec3::z(),
        angle: 1.5,
    };
    let cont = sweep(&arm, &rot, &obstacles, &SweepOptions::default()).unwrap();
    assert!(cont.hit);
    let fine = stepwise_sweep(&arm, &rot, &obstacles, TOL / 2.0);
    assert!(
        fine.hit && (fine.t - cont.t).abs() * 1.5 * 40.0 < 2.0 * TOL,
        "{} vs {}",
        fine.t,
        cont.t
    );
    let poses = Motion::Poses(vec![
        Transform::IDENTITY,
        rot.pose_at(0.5),
        rot.pose_at(1.0),
    ]);
    let seq = sweep(&arm, &poses, &obstacles, &SweepOptions::default()).unwrap();
    assert!(seq.hit && interferes(&arm, &seq.pose, &post, &at(0.0, 20.0, 0.0), TOL).unwrap());
}

#[test]
fn sweeps_refuse_bad_motions() {
    let (wall, mover) = thin_wall_scene();
    let obstacles = fixed(&wall);
    let nan = along_x(f64::NAN);
    assert!(matches!(
        sweep(&mover, &nan, &obstacles, &SweepOptions::default()),
        Err(CollisionError::BadMotion(_))
    ));
    let zero_axis = Motion::Rotation {
        start: Transform::IDENTITY,
        centre: Point3::origin(),
        axis: Vec3::zeros(),
        angle: 1.0,
    };
    assert!(sweep(&mover, &zero_axis, &obstacles, &SweepOptions::default()).is_err());
    assert!(sweep(
        &mover,
        &Motion::Poses(vec![]),
        &obstacles,
        &SweepOptions::default()
    )
    .is_err());
    let ok = along_x(1e9);
    let tiny = SweepOptions {
        method: SweepMethod::displacement_steps(1e-6),
        tolerance: TOL,
        ..Default::default()
    };
    assert!(sweep(&mover, &ok, &obstacles, &tiny).is_err());
    let zero = SweepOptions {
        method: SweepMethod::displacement_steps(0.0),
        tolerance: TOL,
        ..Default::default()
    };
    assert!(sweep(&mover, &ok, &obstacles, &zero).is_err());
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(crate::test_support::proptest_config(64))]
        #[test]
        fn random_soups_and_poses_never_panic(
            coords in proptest::collection::vec(-1e3f64..1e3, 9..90),
            pose in proptest::array::uniform6(-50.0f64..50.0),
            tol in 0.0f64..1.0,
        ) {
            let n = coords.len() / 9;
            let soup = (0..n).map(|i| {
                let c = &coords[9 * i..9 * i + 9];
                [Point3::new(c[0], c[1], c[2]), Point3::new(c[3], c[4], c[5]), Point3::new(c[6], c[7], c[8])]
            });
            let Ok(mesh) = Mesh::from_triangle_soup(soup) else { return Ok(()); };
            let Ok(a) = Collider::new(Arc::new(mesh)) else { return Ok(()); };
            let b = cuboid([-10.0; 3], [10.0; 3]);
            let p = Transform::from_xyzabc(Vec3::new(pose[0], pose[1], pose[2]), [pose[3], pose[4], pose[5]], Default::default());
            let ab = contact(&a, &p, &b, &Transform::IDENTITY, tol).unwrap();
            let ba = contact(&b, &Transform::IDENTITY, &a, &p, tol).unwrap();
            prop_assert_eq!(ab.is_interfering(), ba.is_interfering());
            prop_assert_eq!(ab.is_interfering(), interferes(&a, &p, &b, &Transform::IDENTITY, tol).unwrap());
            let _ = CutCells::derive(&a, CutSpec::Size(50.0));
        }
    }
}

/// Every node's oriented box holds all the vertices under it (the traversal's
/// node test is only exact if the boxes are conservative).
#[test]
fn oriented_node_boxes_hold_their_triangles() {
    fn range(c: &Collider, i: usize) -> (usize, usize) {
        let n = &c.nodes[i];
        if n.count > 0 {
            (n.first as usize, (n.first + n.count) as usize)
        } else {
            let (l, r) = (range(c, n.first as usize), range(c, n.first as usize + 1));
            (l.0.min(r.0), l.1.max(r.1))
        }
    }
    for c in [
        collider(fixtures::torus(10.0, 3.0, 16, 8)),
        collider(fixtures::sphere(6.0, 12, 6)),
    ] {
        for (i, o) in c.obbs.iter().enumerate() {
            let (lo, hi) = range(&c, i);
            for p in (lo..hi).flat_map(|k| c.tri(k)) {
                let q = o.axes.tr_mul(&(p.coords - o.centre));
                assert!(q.iter().zip(o.half.iter()).all(|(q, h)| q.abs() <= *h));
            }
            // the fitted box is never larger than the axis-aligned one
            let h = c.nodes[i].bounds.half_extents();
            assert!(o.half.product() <= h.product() * (1.0 + 1e-9) + 1e-30);
        }
    }
}

/// Near misses and grazing contacts (where the node test decides) agree with the
/// brute-force verdict over all triangle pairs.
#[test]
fn near_misses_match_brute_force() {
    let a = collider(fixtures::torus(10.0, 3.0, 16, 8));
    let b = collider(fixtures::sphere(6.0, 12, 6));
    let mut rng = Rng::new(11);
    let mut seen = [0usize; 2];
    for k in 0..60 {
        let pa = random_pose(&mut rng, 3.0);
        let rb = rng.rotation();
        let dir = Vec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
        let pose = |s: f64| Transform::from_parts(pa.translation() + dir * s, rb);
        let (mut lo, mut hi) = (0.0, 60.0);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if surface_distance(&a, &pa, &b, &pose(mid), 0.0).unwrap() > 0.0 {
                hi = mid
            } else {
                lo = mid
            }
        }
        // just outside, and just inside, first contact
        let pb = pose(if k % 2 == 0 { hi + 0.01 } else { lo - 0.01 });
        let ta: Vec<_> = a.tris().map(|t| t.map(|p| pa.apply(&p))).collect();
        let tb: Vec<_> = b.tris().map(|t| t.map(|p| pb.apply(&p))).collect();
        let mut depth = 0.0f64;
        for x in &ta {
            for y in &tb {
                if let Some(d) = tri_tri(x, y, 1e-8, true) {
                    depth = depth.max(d);
                }
            }
        }
        let hit = interferes(&a, &pa, &b, &pb, 0.0).unwrap();
        assert_eq!(hit, depth > 0.0, "pose {k}: depth {depth}");
        seen[hit as usize] += 1;
    }
    assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
}

/// Whether some pose among `n` evenly spaced ones after `from` on the edge interferes.
fn sampled_edge_hits(
    m: &Collider,
    from: &Transform,
    to: &Transform,
    o: &Collider,
    po: &Transform,
    n: usize,
) -> bool {
    (1..=n).any(|k| {
        let p = from.interpolate(to, k as f64 / n as f64);
        interferes(m, &p, o, po, DEFAULT_TOLERANCE).unwrap()
    })
}

/// The continuous edge check never misses a crossing that dense sampling finds, on
/// random short edges (translation and rotation) around a torus: the sweep bounds
/// and the plane tests are conservative.
#[test]
fn edge_check_never_misses_what_sampling_sees() {
    let a = collider(fixtures::sphere(4.0, 12, 6));
    let b = collider(fixtures::torus(10.0, 3.0, 16, 8));
    let pb = Transform::IDENTITY;
    let mut rng = Rng::new(5);
    let mut seen = [0usize; 2];
    let opts = EdgeOptions::default();
    for k in 0..150 {
        let from = random_pose(&mut rng, 16.0);
        if interferes(&a, &from, &b, &pb, DEFAULT_TOLERANCE).unwrap() {
            continue;
        }
        let to = Transform::from_parts(
            from.translation() + Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 4.0,
            from.isometry().rotation
                * nalgebra::UnitQuaternion::from_scaled_axis(
                    Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3,
                ),
        );
        let sampled = sampled_edge_hits(&a, &from, &to, &b, &pb, 400);
        let swept = edge_interferes(&a, &from, &to, &b, &pb, &opts).unwrap();
        assert!(
            !sampled || swept,
            "edge {k}: sampling hits, the edge check does not"
        );
        seen[swept as usize] += 1;
    }
    assert!(seen[0] > 10 && seen[1] > 10, "{seen:?}");
}

/// A face gliding on a face and a peg sliding along a tight bore are free; pushing
/// into the face, or a thin wall anywhere on the edge, is not.
#[test]
fn edge_check_on_sliding_contacts_and_thin_walls() {
    let opts = EdgeOptions::default();
    let cube = cuboid([-5.0, -5.0, 0.0], [5.0, 5.0, 10.0]);
    let table = cuboid([-100.0, -100.0, -10.0], [100.0, 100.0, 0.0]);
    let id = Transform::IDENTITY;
    // resting on the table (touching), sliding 50 mm and turning about the normal
    let slide = at(50.0, 20.0, 0.0);
    assert!(!edge_interferes(&cube, &id, &slide, &table, &id, &opts).unwrap());
    let turn = Transform::from_rotation_about(Point3::origin(), Vec3::z(), 0.7).unwrap();
    assert!(!edge_interferes(&cube, &id, &turn, &table, &id, &opts).unwrap());
    // pressing 1 mm into it
    assert!(edge_interferes(&cube, &id, &at(10.0, 0.0, -1.0), &table, &id, &opts).unwrap());
    // tipping over an edge of the cube's base digs a corner in
    let tip = Transform::from_rotation_about(Point3::origin(), Vec3::x(), 0.2).unwrap();
    assert!(edge_interferes(&cube, &id, &tip, &table, &id, &opts).unwrap());
    // a 0.5 mm wall between two free poses
    let wall = cuboid([20.0, -50.0, -50.0], [20.5, 50.0, 50.0]);
    assert!(edge_interferes(&cube, &id, &at(40.0, 0.0, 0.0), &wall, &id, &opts).unwrap());
    assert!(!edge_interferes(&cube, &id, &at(14.9, 0.0, 0.0), &wall, &id, &opts).unwrap());
    // a Ø20 peg along a bore of radius 10.1 (64 facets each: the gap is 0.09 mm)
    let peg = collider(Mesh::cylinder(10.0, 100.0, 64));
    let block = collider(
        Mesh::lathe(
            &[
                (0.0, 0.0),
                (40.0, 0.0),
                (40.0, 70.0),
                (10.1, 70.0),
                (10.1, 10.0),
                (0.0, 10.0),
            ],
            64,
        )
        .unwrap(),
    );
    let seated = at(0.0, 0.0, 10.0);
    let out = at(0.0, 0.0, 75.0);
    assert!(!interferes(&peg, &out, &block, &id, DEFAULT_TOLERANCE).unwrap());
    assert!(!edge_interferes(&peg, &seated, &out, &block, &id, &opts).unwrap());
    assert!(!edge_interferes(&peg, &out, &seated, &block, &id, &opts).unwrap());
    // tilting in the bore jams
    let tilt = seated.then(
        &Transform::from_rotation_about(Point3::new(0.0, 0.0, 40.0), Vec3::x(), 0.05).unwrap(),
    );
    assert!(edge_interferes(&peg, &seated, &tilt, &block, &id, &opts).unwrap());
}

#[test]
fn edge_check_refuses_bad_input() {
    let c = cuboid([0.0; 3], [1.0; 3]);
    let id = Transform::IDENTITY;
    let nan = at(f64::NAN, 0.0, 0.0);
    assert!(edge_interferes(
        &c,
        &id,
        &nan,
        &c,
        &at(5.0, 0.0, 0.0),
        &EdgeOptions::default()
    )
    .is_err());
    let bad = EdgeOptions {
        contact_step: 0.0,
        ..Default::default()
    };
    assert!(edge_interferes(&c, &id, &at(1.0, 0.0, 0.0), &c, &at(5.0, 0.0, 0.0), &bad).is_err());
}

/// The trees (leaves of up to 8 triangles, oriented boxes whose axes are refitted
/// every few levels, depth-floor pruning) give the verdicts of a brute-force check
/// of every triangle pair, on random pairs of fine and coarse parts in random poses.
mod trees_against_brute_force {
    use super::*;
    use crate::math::Rng;
    use proptest::prelude::*;

    /// A lathe part of ~`2 · segments · rings` triangles with a wavy profile.
    fn wavy(segments: usize, rings: usize, phase: f64) -> Mesh {
        let mut profile = vec![(0.0, 0.0)];
        for k in 0..rings {
            let s = (k as f64 + 0.5) / rings as f64;
            profile.push((6.0 * (1.0 + 0.2 * (9.0 * s + phase).sin()), 14.0 * s));
        }
        profile.push((0.0, 14.0));
        Mesh::lathe(&profile, segments).unwrap()
    }

    fn shape(kind: u8, phase: f64) -> Collider {
        collider(match kind % 4 {
            0 => fixtures::torus(10.0, 3.0, 40, 12),
            1 => fixtures::sphere(6.0, 24, 12),
            2 => wavy(36, 14, phase),
            _ => Mesh::cuboid(Point3::new(-5.0, -4.0, -3.0), Point3::new(5.0, 4.0, 3.0)),
        })
    }

    /// Largest distance to `outer`'s surface of a centroid or edge midpoint of a
    /// triangle of `inner` lying inside `outer`, by brute force (mm).
    fn reach_bound(inner: &Collider, pi: &Transform, outer: &Collider, po: &Transform) -> f64 {
        let to_outer = po.isometry().inverse() * pi.isometry();
        let mut most = 0.0f64;
        for t in inner.tris() {
            let t = t.map(|p| to_outer * p);
            let c = nalgebra::center(&nalgebra::center(&t[0], &t[1]), &t[2]);
            for p in [
                c,
                nalgebra::center(&t[0], &t[1]),
                nalgebra::center(&t[1], &t[2]),
                nalgebra::center(&t[2], &t[0]),
            ] {
                if outer.contains_point(&p) {
                    most = most.max(outer.distance_to_point(&p, 0.0));
                }
            }
        }
        most
    }

    proptest! {
        #![proptest_config(crate::test_support::proptest_config(24))]
        #[test]
        fn verdicts_depths_and_distances_match_all_pairs(
            kinds in (0u8..4, 0u8..4),
            phase in 0.0f64..6.0,
            seed in 0u64..1_000_000,
            tol in prop_oneof![Just(0.0), Just(DEFAULT_TOLERANCE), 0.0f64..2.0],
        ) {
            let (a, b) = (shape(kinds.0, phase), shape(kinds.1, phase + 1.0));
            let mut rng = Rng::new(seed);
            let (pa, pb) = (random_pose(&mut rng, 7.0), random_pose(&mut rng, 7.0));
            let e = super::super::exact::eps(&a, &b, &pa, &pb);
            let ta: Vec<_> = a.tris().map(|t| t.map(|p| pa.apply(&p))).collect();
            let tb: Vec<_> = b.tris().map(|t| t.map(|p| pb.apply(&p))).collect();
            let (mut depth, mut dist) = (None::<f64>, f64::INFINITY);
            for x in &ta {
                for y in &tb {
                    if let Some(d) = tri_tri(x, y, e, true) {
                        depth = Some(depth.unwrap_or(0.0).max(d));
                    }
                    dist = dist.min(tri_distance(x, y));
                }
            }
            let c = contact(&a, &pa, &b, &pb, tol).unwrap();
            let hit = interferes(&a, &pa, &b, &pb, tol).unwrap();
            prop_assert_eq!(hit, c.is_interfering(), "{:?}", c);
            match depth {
                // verdicts within rounding of the tolerance may go either way
                Some(d) if (d - tol).abs() < 1e-6 => {}
                Some(d) if d > tol => {
                    prop_assert!(hit, "brute force depth {}, tree {:?}", d, c);
                    prop_assert!((c.depth() - d).abs() < 1e-6, "{:?} vs {}", c, d);
                }
                // every pair within the tolerance: touching, unless the depth walk
                // finds a point of one surface deeper inside the other solid; such a
                // depth is real (no sample point of the kind walked is deeper)
                Some(d) if d > 1e-6 => match c {
                    Contact::Touching => {}
                    Contact::Interfering { depth, kind: InterferenceKind::SurfacesCross } => {
                        let most = reach_bound(&a, &pa, &b, &pb).max(reach_bound(&b, &pb, &a, &pa));
                        prop_assert!(depth > tol && depth <= most + 1e-9, "{} vs {} (pairs {})", depth, most, d);
                    }
                    other => prop_assert!(false, "pairs {}: {:?}", d, other),
                },
                Some(_) => prop_assert!(c != Contact::Separate),
                None => prop_assert!(!matches!(
                    c,
                    Contact::Touching
                        | Contact::Interfering { kind: InterferenceKind::SurfacesCross, .. }
                ), "{:?}", c),
            }
            let d = surface_distance(&a, &pa, &b, &pb, 0.0).unwrap();
            prop_assert!((d - dist).abs() < 1e-6, "{} vs {}", d, dist);
        }
    }
}

/// A stepwise sweep honours `step_rad` as well as `step_mm`: a rotation whose
/// points move less than one `step_mm` in total is still stepped by angle.
#[test]
fn stepwise_sweep_steps_rotations_by_step_rad() {
    // a 1 mm post 30 mm from the axis at 0.5 rad; an arm 40 mm long turning 1 rad
    let (c, s) = (30.0 * 0.5f64.cos(), 30.0 * 0.5f64.sin());
    let post = cuboid([c - 0.5, s - 0.5, -5.0], [c + 0.5, s + 0.5, 5.0]);
    let arm = cuboid([0.0, -0.5, -0.5], [40.0, 0.5, 0.5]);
    let obstacles = fixed(&post);
    let motion = Motion::Rotation {
        start: Transform::IDENTITY,
        centre: Point3::origin(),
        axis: Vec3::z(),
        angle: 1.0,
    };
    let run = |method| {
        sweep(
            &arm,
            &motion,
            &obstacles,
            &SweepOptions {
                method,
                tolerance: TOL,
                ..Default::default()
            },
        )
        .unwrap()
    };
    // one 100 mm step covers the whole turn: only the ends are checked
    assert!(!run(SweepMethod::displacement_steps(100.0)).hit);
    let stepped = run(SweepMethod::Stepwise {
        step_mm: 100.0,
        step_rad: 0.01,
    });
    assert!(
        stepped.hit && stepped.t > 0.4 && stepped.t < 0.5,
        "{stepped:?}"
    );
    assert!(interferes(&arm, &stepped.pose, &post, &Transform::IDENTITY, TOL).unwrap());
}

/// The sweep's default contact step is exactly the contact gap at every tolerance,
/// and the clamp raises a contact step to half the tolerance.
#[test]
fn fine_continuous_steps_by_the_contact_gap() {
    let SweepMethod::Continuous { contact_step_mm } = SweepMethod::CONTINUOUS_FINE else {
        panic!("CONTINUOUS_FINE is continuous");
    };
    for tol in [0.0, 1e-4, 1e-3, 0.01, 0.3, 2.0] {
        assert_eq!(
            contact_step(contact_step_mm, tol),
            contact_gap(tol),
            "{tol}"
        );
    }
    assert_eq!(contact_step(0.05, 0.2), 0.1);
    assert_eq!(contact_step(0.05, 0.01), 0.05);
}

/// A box `[lo, hi]` with every face cut into `n × n` squares (two triangles each),
/// outward oriented and welded: facets of `(hi - lo) / n` mm.
fn fine_box(lo: [f64; 3], hi: [f64; 3], n: usize) -> Collider {
    let coord = |axis: usize, i: usize| lo[axis] + (hi[axis] - lo[axis]) * i as f64 / n as f64;
    let mut soup = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for (side, flip) in [(0, true), (n, false)] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: usize, dj: usize| {
                        let mut p = [0.0; 3];
                        p[axis] = coord(axis, side);
                        p[u] = coord(u, i + di);
                        p[v] = coord(v, j + dj);
                        Point3::new(p[0], p[1], p[2])
                    };
                    // u × v is +axis: counter-clockwise seen from +axis
                    let (p00, p10, p11, p01) =
                        (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
                    for t in [[p00, p10, p11], [p00, p11, p01]] {
                        soup.push(if flip { [t[0], t[2], t[1]] } else { t });
                    }
                }
            }
        }
    }
    let c = collider(Mesh::from_triangle_soup(soup).unwrap());
    assert!(c.is_solid(), "fine box must be watertight");
    c
}

/// Tolerance of the fine-mesh tests: larger than every facet used with it, so each
/// pair of crossing facets is within it and only the depth walk sees the overlap.
const FINE_TOL: f64 = 0.1;

#[test]
fn fine_boxes_pushed_half_a_mm_interfere_at_any_facet_size() {
    for (n, m) in [(25, 32), (40, 47), (50, 57)] {
        let a = fine_box([0.0, 0.0, 0.0], [2.0, 2.0, 2.0], n);
        let b = fine_box([0.0, 0.5, 0.5], [2.0, 1.5, 1.5], m);
        let facet = 2.0 / n.min(m) as f64;
        // b's end sunk 0.5 mm into a's side face
        let pb = at(1.5, 0.0, 0.0);
        for (x, px, y, py) in [
            (&a, Transform::IDENTITY, &b, pb),
            (&b, pb, &a, Transform::IDENTITY),
        ] {
            let c = contact(x, &px, y, &py, FINE_TOL).unwrap();
            assert!(
                matches!(
                    c,
                    Contact::Interfering {
                        kind: InterferenceKind::SurfacesCross,
                        ..
                    }
                ),
                "n {n}: {c:?}"
            );
            assert!(
                (c.depth() - 0.5).abs() <= facet,
                "n {n}: depth {}",
                c.depth()
            );
            assert!(interferes(x, &px, y, &py, FINE_TOL).unwrap(), "n {n}");
        }
        // resting face to face, and end to face, they touch
        for pb in [at(2.0, 0.0, 0.0), at(0.0, 0.0, 1.5)] {
            assert_eq!(
                contact(&a, &Transform::IDENTITY, &b, &pb, FINE_TOL).unwrap(),
                Contact::Touching
            );
            assert!(!interferes(&b, &pb, &a, &Transform::IDENTITY, FINE_TOL).unwrap());
        }
    }
}

#[test]
fn fine_cylinders_side_by_side_interfere_by_their_overlap() {
    // 2 mm radius: facets 0.0105 to 0.0039 mm wide, about the default tolerance;
    // the axes 3.5 mm apart overlap the solids by 0.5 mm
    for n in [1200, 1600, 2400, 3200] {
        let a = collider(Mesh::cylinder(2.0, 4.0, n));
        let b = collider(Mesh::cylinder(2.0, 4.0, n + 100));
        let facet = std::f64::consts::TAU * 2.0 / n as f64;
        let pb = at(3.5, 0.0, 0.0);
        let c = contact(&a, &Transform::IDENTITY, &b, &pb, TOL).unwrap();
        let swapped = contact(&b, &pb, &a, &Transform::IDENTITY, TOL).unwrap();
        for c in [c, swapped] {
            assert!(c.is_interfering(), "n {n}: {c:?}");
            // facets wider than the tolerance cross deeper than it pair by pair:
            // the depth is then the pair depth (docs/interference.md)
            if facet < TOL {
                assert!(
                    (c.depth() - 0.5).abs() <= facet + 1e-3,
                    "n {n}: depth {}",
                    c.depth()
                );
            }
        }
        assert!(interferes(&b, &pb, &a, &Transform::IDENTITY, TOL).unwrap());
        // tangent (4 mm apart) they touch or are apart, never interfere
        let side = at(4.0, 0.0, 0.0);
        assert!(!contact(&a, &Transform::IDENTITY, &b, &side, TOL)
            .unwrap()
            .is_interfering());
        assert!(!interferes(&a, &Transform::IDENTITY, &b, &side, TOL).unwrap());
    }
}

#[test]
fn fine_pin_pushed_into_its_hole_wall_interferes_by_the_push() {
    let n = 2400; // 0.0079 mm facets on a 3 mm radius
    let plate = collider(fixtures::plate_with_hole(20.0, 4.0, 3.0, n));
    let pin = collider(Mesh::cylinder(3.0, 10.0, n));
    let odd = collider(Mesh::cylinder(3.0, 10.0, n + 44));
    for pin in [&pin, &odd] {
        // seated on the axis: touching, whatever the tessellation
        let through = at(0.0, 0.0, -3.0);
        assert_eq!(
            contact(pin, &through, &plate, &Transform::IDENTITY, TOL).unwrap(),
            Contact::Touching
        );
        assert!(!interferes(&plate, &Transform::IDENTITY, pin, &through, TOL).unwrap());
        // 0.5 mm sideways into the wall
        let off = at(0.5, 0.0, -3.0);
        for c in [
            contact(pin, &off, &plate, &Transform::IDENTITY, TOL).unwrap(),
            contact(&plate, &Transform::IDENTITY, pin, &off, TOL).unwrap(),
        ] {
            assert!(c.is_interfering(), "{c:?}");
            assert!((c.depth() - 0.5).abs() <= 0.02, "depth {}", c.depth());
        }
        assert!(interferes(pin, &off, &plate, &Transform::IDENTITY, TOL).unwrap());
    }
}

/// The minimum triangle–triangle distance between two posed meshes by brute force
/// over every pair, with parry3d-f64's triangle distance (independent of fitup's
/// `tri_distance` and of the BVH search), mm.
fn brute_distance(a: &Mesh, pa: &Transform, b: &Mesh, pb: &Transform) -> f64 {
    use parry3d_f64::math::{Pose, Rot3, Vector};
    use parry3d_f64::shape::Triangle;
    let tris = |m: &Mesh, p: &Transform| -> Vec<Triangle> {
        (0..m.triangles.len())
            .map(|i| {
                let t = m.triangle(i).map(|v| p.apply(&v));
                let v = |q: Point3| Vector::new(q.x, q.y, q.z);
                Triangle::new(v(t[0]), v(t[1]), v(t[2]))
            })
            .collect()
    };
    let (ta, tb) = (tris(a, pa), tris(b, pb));
    let id = Pose::from_parts(Vector::ZERO, Rot3::IDENTITY);
    let mut best = f64::INFINITY;
    for x in &ta {
        for y in &tb {
            let d = parry3d_f64::query::distance(&id, x, &id, y)
                .unwrap()
                .distance;
            best = best.min(d);
        }
    }
    best
}

/// A closed box with a closed box-shaped cavity: outer shell outward, inner shell
/// facing into the cavity (`lo`..`hi` outer, `ilo`..`ihi` cavity, mm).
fn hollow_box(lo: f64, hi: f64, ilo: f64, ihi: f64) -> Mesh {
    let mut m = Mesh::cuboid(Point3::new(lo, lo, lo), Point3::new(hi, hi, hi));
    let inner = Mesh::cuboid(Point3::new(ilo, ilo, ilo), Point3::new(ihi, ihi, ihi));
    let flipped = Mesh::new(
        inner.vertices.clone(),
        inner.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
    )
    .unwrap();
    m.append(&flipped);
    m
}

/// `clearance` and `contact` agree on interlocked, touching, contained and caged
/// pairs over many random poses near the contact: Touching ⇒ clearance ≤ tol,
/// Interfering ⇒ 0, clearance > tol ⇒ Separate, at every tolerance; and a
/// positive clearance is the brute-force minimum triangle distance.
#[test]
fn clearance_agrees_with_contact_and_brute_force() {
    use nalgebra::UnitQuaternion;
    let turn_x = Transform::from_parts(
        Vec3::zeros(),
        UnitQuaternion::from_axis_angle(&Vec3::x_axis(), std::f64::consts::FRAC_PI_4),
    );
    // (name, mesh a, mesh b, b's designed pose: touching or contained)
    let pairs: Vec<(&str, Mesh, Mesh, Transform)> = vec![
        // a ring around a rod, touching on the ring's inside (same facet angles)
        (
            "ring on rod",
            fixtures::torus(20.0, 3.0, 16, 8),
            Mesh::cylinder(17.0, 40.0, 16),
            at(0.0, 0.0, -20.0),
        ),
        // large triangles: a cube's edge on the interior of a slab's top facets
        (
            "edge on facets",
            Mesh::cuboid(
                Point3::new(-10.0, -10.0, -10.0),
                Point3::new(10.0, 10.0, 0.0),
            ),
            Mesh::cuboid(Point3::new(-5.0, -5.0, -5.0), Point3::new(5.0, 5.0, 5.0)),
            turn_x.then(&at(0.0, 0.0, 5.0 * std::f64::consts::SQRT_2)),
        ),
        // a cube inside a cavity, against its wall
        (
            "cube in cavity",
            hollow_box(-20.0, 20.0, -10.0, 10.0),
            Mesh::cuboid(Point3::new(-4.0, -4.0, -4.0), Point3::new(4.0, 4.0, 4.0)),
            at(6.0, 0.0, 0.0),
        ),
        // a small cube inside a solid block (contained: interfering, clearance 0)
        (
            "cube in block",
            Mesh::cuboid(
                Point3::new(-20.0, -20.0, -20.0),
                Point3::new(20.0, 20.0, 20.0),
            ),
            Mesh::cuboid(Point3::new(-4.0, -4.0, -4.0), Point3::new(4.0, 4.0, 4.0)),
            at(3.0, 0.0, 0.0),
        ),
    ];
    let mut rng = Rng::new(22);
    let mut seen = std::collections::HashMap::new();
    for (name, ma, mb, designed) in &pairs {
        let (a, b) = (collider(ma.clone()), collider(mb.clone()));
        for k in 0..120 {
            let spread = [0.0, 1e-3, 0.05, 0.5, 3.0][k % 5];
            let turn = UnitQuaternion::from_scaled_axis(
                Vec3::new(rng.normal(), rng.normal(), rng.normal()) * (spread * 0.02),
            );
            let shift = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * spread;
            let world = random_pose(&mut rng, 50.0);
            let pb = designed
                .then(&Transform::from_parts(shift, turn))
                .then(&world);
            let clr = clearance(&a, &world, &b, &pb, 1000.0).unwrap();
            for tol in [0.0, TOL, 0.1] {
                let c = contact(&a, &world, &b, &pb, tol).unwrap();
                *seen
                    .entry((
                        *name,
                        format!("{c:?}")
                            .split([' ', '{', '('])
                            .next()
                            .unwrap()
                            .to_string(),
                    ))
                    .or_insert(0) += 1;
                let why = format!("{name} pose {k} tol {tol}: {c:?}, clearance {clr}");
                match c {
                    Contact::Touching => assert!(clr <= tol, "{why}"),
                    Contact::Interfering { .. } => assert_eq!(clr, 0.0, "{why}"),
                    Contact::Separate => {}
                }
                if clr > tol {
                    assert_eq!(c, Contact::Separate, "{why}");
                }
            }
            if k % 3 == 0 {
                let brute = brute_distance(ma, &world, mb, &pb);
                let contained = matches!(
                    contact(&a, &world, &b, &pb, TOL).unwrap(),
                    Contact::Interfering {
                        kind: InterferenceKind::Contained { .. },
                        ..
                    }
                );
                if clr > 0.0 {
                    assert!(
                        (clr - brute).abs() <= 1e-7 * (1.0 + brute),
                        "{name} pose {k}: clearance {clr}, brute force {brute}"
                    );
                } else {
                    assert!(
                        contained || brute <= 1e-6,
                        "{name} pose {k}: clearance 0, brute force {brute}"
                    );
                }
            }
        }
    }
    // every pair was seen in contact; the ring and the caged and resting cubes
    // also touching, the last two also apart (a ring round a rod cannot move apart)
    for (name, ..) in &pairs {
        let n = |state: &str| seen.get(&(*name, state.to_string())).copied().unwrap_or(0);
        assert!(n("Interfering") > 0, "{name}: {seen:?}");
        if *name != "cube in block" {
            assert!(n("Touching") > 0, "{name}: {seen:?}");
        }
        if matches!(*name, "edge on facets" | "cube in cavity") {
            assert!(n("Separate") > 0, "{name}: {seen:?}");
        }
    }
}

/// A stepwise sweep counts its steps against the shared cap before the first check:
/// 20 mm at 1e-12 mm is 2e13 steps, refused at once naming `step`, not after the
/// time budget.
#[test]
fn stepwise_sweeps_refuse_more_steps_than_the_cap() {
    let (wall, mover) = thin_wall_scene();
    let obstacles = fixed(&wall);
    let motion = along_x(20.0);
    let options = SweepOptions {
        method: SweepMethod::displacement_steps(1e-12),
        ..SweepOptions::default()
    };
    let before = crate::collision::effort();
    let e = sweep(&mover, &motion, &obstacles, &options).unwrap_err();
    assert!(
        matches!(
            &e,
            CollisionError::Limit(crate::math::LimitError::TooMany { argument: "step", cap, .. })
                if *cap == crate::math::MAX_SAMPLES
        ),
        "{e}"
    );
    // Refused before any check: no pair of the two trees was visited.
    assert_eq!(
        crate::collision::effort(),
        before,
        "refused before any check"
    );
    // Within the cap the same sweep runs and finds the wall.
    let fine = SweepOptions {
        method: SweepMethod::displacement_steps(0.1),
        ..SweepOptions::default()
    };
    assert!(sweep(&mover, &motion, &obstacles, &fine).unwrap().hit);
    // ... and the count above would have seen its checks.
    assert!(
        crate::collision::effort() > before,
        "a sweep that runs visits pairs"
    );
}

/// The deadline-bounded checks give up once their deadline has passed and
/// otherwise answer as the unbounded ones: a fine cylinder inside a slightly
/// wider and taller one (thousands of side-by-side facet pairs to walk, none
/// crossing, caps 0.1 mm apart, so nothing ends the walk early).
#[test]
fn bounded_checks_give_up_at_a_passed_deadline_and_agree_before_it() {
    let a = collider(Mesh::cylinder(10.0, 100.0, 1024));
    let b = collider(Mesh::cylinder(10.001, 100.2, 1024));
    let pa = Transform::IDENTITY;
    let pb = Transform::from_translation(Vec3::new(0.0, 0.0, -0.1));
    let tol = DEFAULT_TOLERANCE;
    let past = std::time::Instant::now();
    assert_eq!(contact_until(&a, &pa, &b, &pb, tol, past).unwrap(), None);
    assert_eq!(interferes_until(&a, &pa, &b, &pb, tol, past).unwrap(), None);
    let later = std::time::Instant::now() + std::time::Duration::from_secs(600);
    let full = contact(&a, &pa, &b, &pb, tol).unwrap();
    assert!(full.depth() > 0.0, "{full:?}");
    assert_eq!(
        contact_until(&a, &pa, &b, &pb, tol, later).unwrap(),
        Some(full)
    );
    assert_eq!(
        interferes_until(&a, &pa, &b, &pb, tol, later).unwrap(),
        Some(interferes(&a, &pa, &b, &pb, tol).unwrap())
    );
}

/// A screw drawn out of the hole it sits in, line to line (shank and hole faceted
/// alike, its head resting on the plate), along its axis and at random poses of the
/// whole: the continuous check finds the way out free, as dense static checks do;
/// from 0.3 mm into the hole's wall the same motion interferes. The shank's facets
/// along the hole and the head's face leaving the plate are what the translation's
/// swept reach (`edge.rs`) clears without stepping.
#[test]
fn a_screw_drawn_out_of_its_hole_line_to_line_is_free_all_the_way() {
    let plate = collider(fixtures::plate_with_hole(20.0, 4.0, 3.0, 32));
    let screw = collider(fixtures::screw(3.0, 4.0, 5.0, 2.0, 32));
    let opts = EdgeOptions::default();
    let mut rng = Rng::new(5);
    for k in 0..6 {
        let world = if k == 0 {
            Transform::IDENTITY
        } else {
            random_pose(&mut rng, 50.0)
        };
        // the shank through the plate (z = 0 to 4), the head on its top face
        let seated = world;
        let out = at(0.0, 0.0, 12.0).then(&world);
        let pushed = at(0.3, 0.0, 0.0).then(&world);
        let pushed_out = at(0.3, 0.0, 12.0).then(&world);
        assert!(!interferes(&screw, &seated, &plate, &world, TOL).unwrap());
        let dense_hit = |from: &Transform, to: &Transform| {
            (0..=600).any(|n| {
                let p = from.interpolate(to, f64::from(n) / 600.0);
                interferes(&screw, &p, &plate, &world, TOL).unwrap()
            })
        };
        assert!(!dense_hit(&seated, &out), "pose {k}");
        assert!(
            !edge_interferes(&screw, &seated, &out, &plate, &world, &opts).unwrap(),
            "pose {k}"
        );
        assert!(dense_hit(&pushed, &pushed_out), "pose {k}");
        assert!(
            edge_interferes(&screw, &pushed, &pushed_out, &plate, &world, &opts).unwrap(),
            "pose {k}"
        );
    }
}

/// `sweep` of a screw drawn out of its hole line to line: free all the way out, and
/// stopped where its head meets a cover 4 mm above it, at the first interfering
/// pose (the pose 0.01 mm before is free). A translation is checked as one
/// continuous edge, not pose by pose along the sliding contact (1.4 s before at 32
/// facets, a 10 s time-out at 512; now milliseconds).
#[test]
fn a_sweep_draws_a_screw_out_of_its_hole_and_stops_at_the_cover() {
    for n in [32, 512] {
        let plate = collider(fixtures::plate_with_hole(20.0, 4.0, 3.0, n));
        let screw = collider(fixtures::screw(3.0, 4.0, 5.0, 2.0, n));
        let cover = collider(Mesh::cuboid(
            Point3::new(-10.0, -10.0, 10.0),
            Point3::new(10.0, 10.0, 12.0),
        ));
        // the screw from `start` 12 mm up, against `obstacles`
        let up = |start: Transform, obstacles: &[Obstacle]| {
            let motion = Motion::Translation {
                start,
                offset: Vec3::new(0.0, 0.0, 12.0),
            };
            sweep(&screw, &motion, obstacles, &SweepOptions::default()).unwrap()
        };
        let alone = [Obstacle {
            collider: &plate,
            pose: Transform::IDENTITY,
        }];
        let out = up(Transform::IDENTITY, &alone);
        assert!(!out.hit, "{n} facets: {out:?}");
        let pushed = up(at(0.3, 0.0, 0.0), &alone);
        assert!(pushed.hit && pushed.t == 0.0, "{n} facets: {pushed:?}");
        let covered = [
            alone[0],
            Obstacle {
                collider: &cover,
                pose: Transform::IDENTITY,
            },
        ];
        let hit = up(Transform::IDENTITY, &covered);
        // the head's top (z = 6) reaches the cover (z = 10) after 4 mm
        let z = hit.pose.translation().z;
        assert!(hit.hit && hit.with == Some(1), "{n} facets: {hit:?}");
        assert!((z - 4.0).abs() <= 0.02, "{n} facets: stopped at {z}");
        assert!(interferes(&screw, &hit.pose, &cover, &Transform::IDENTITY, TOL).unwrap());
        assert!(!interferes(
            &screw,
            &at(0.0, 0.0, z - 0.01),
            &cover,
            &Transform::IDENTITY,
            TOL
        )
        .unwrap());
    }
}
