use super::*;
use crate::collision::node::LEAF_SIZE;
use crate::collision::tree::symmetric_eigenvectors;
use crate::math::Rng;
use nalgebra::Matrix3;

/// Two facets folded at a right angle get a leaf each, the same two unfolded
/// into a square share one; a finely meshed flat plate and a fine sphere keep
/// leaves of several;
/// nodes are the size [`Collider`]'s memory note counts (184 bytes with their
/// oriented boxes).
#[test]
fn bent_groups_are_split_and_flat_patches_kept() {
    let tree = |mesh: Mesh| {
        let c = Collider::new(Arc::new(mesh)).unwrap();
        let leaves = c.nodes.iter().filter(|x| x.count > 0).count();
        assert_eq!(
            c.nodes.iter().map(|x| x.count as usize).sum::<usize>(),
            c.triangle_count()
        );
        assert!(c.nodes.iter().all(|x| x.count as usize <= LEAF_SIZE));
        assert_eq!(c.nodes.len(), 2 * leaves - 1);
        (c, leaves)
    };
    let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    let pair = |fourth: Point3| {
        let vertices = vec![
            p(0.0, 0.0, 0.0),
            p(10.0, 0.0, 0.0),
            p(0.0, 10.0, 0.0),
            fourth,
        ];
        Mesh::new(vertices, vec![[0, 1, 2], [1, 3, 2]]).unwrap()
    };
    // a square, then folded along its diagonal by a right angle
    assert_eq!(tree(pair(p(10.0, 10.0, 0.0))).1, 1, "flat");
    let h = 50f64.sqrt();
    assert_eq!(tree(pair(p(5.0, 5.0, h))).1, 2, "folded");
    // a 64 × 64 grid of squares, two triangles each, in one plane
    let cells = 64usize;
    let mut vertices = Vec::new();
    for i in 0..=cells {
        for j in 0..=cells {
            vertices.push(Point3::new(i as f64, j as f64, 0.0));
        }
    }
    let at = |i: usize, j: usize| (i * (cells + 1) + j) as u32;
    let mut triangles = Vec::new();
    for i in 0..cells {
        for j in 0..cells {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let (plate, leaves) = tree(Mesh::new(vertices, triangles).unwrap());
    let mean = plate.triangle_count() as f64 / leaves as f64;
    assert!(mean > 1.5, "leaves of {mean} triangles on average");
    // a fine sphere (facets 5.6° apart) keeps leaves of up to four
    let (sphere, leaves) = tree(Mesh::uv_sphere(10.0, 64));
    let mean = sphere.triangle_count() as f64 / leaves as f64;
    assert!(mean > 3.5, "leaves of {mean} triangles on average");
    assert_eq!(
        std::mem::size_of::<Node>() + std::mem::size_of::<Obb>(),
        184
    );
}

/// The Jacobi solver's axes are orthonormal and diagonalise the matrix, for
/// random covariances and the awkward cases (repeated eigenvalues, rank 1 and 2,
/// zero, huge entries).
#[test]
fn jacobi_axes_diagonalise_symmetric_matrices() {
    let mut rng = Rng::new(7);
    let mut cases: Vec<Matrix3<f64>> = vec![
        Matrix3::zeros(),
        Matrix3::identity(),
        Matrix3::from_diagonal(&Vec3::new(3.0, 3.0, 1.0)),
        Matrix3::from_diagonal(&Vec3::new(0.0, 0.0, 1e12)),
    ];
    for _ in 0..500 {
        let g = Matrix3::from_fn(|_, _| rng.normal() * 10f64.powf(rng.range(-3.0, 6.0)));
        let rank = rng.below(3) + 1;
        let mut m = Matrix3::zeros();
        for k in 0..rank {
            let c = g.column(k);
            m += c * c.transpose();
        }
        cases.push(m);
    }
    for (k, m) in cases.into_iter().enumerate() {
        let start = if k % 2 == 0 {
            Matrix3::identity()
        } else {
            *rng.rotation().to_rotation_matrix().matrix()
        };
        let v = symmetric_eigenvectors(&m, &start, 1e-6);
        let ortho = v.transpose() * v - Matrix3::identity();
        assert!(ortho.abs().max() < 1e-12, "not orthonormal: {v} for {m}");
        let d = v.transpose() * m * v;
        let off = d[(0, 1)].abs().max(d[(0, 2)].abs()).max(d[(1, 2)].abs());
        assert!(
            off <= 1e-5 * m.abs().max().max(1e-300),
            "off-diagonal {off} left for {m}"
        );
    }
}

/// A nearest-point search given a hint returns exactly what the search without
/// one returns (distance, triangle, point), whatever the hint: near, far or out
/// of range; points on, inside, beside and far from a sphere's and a box's
/// surfaces, and at their vertices and edge midpoints (ties between
/// faces).
#[test]
fn a_hint_changes_no_nearest_point() {
    let sphere = Collider::new(Arc::new(crate::mesh::Mesh::uv_sphere(7.0, 24))).unwrap();
    let cube = Collider::new(Arc::new(crate::mesh::Mesh::cuboid(
        Point3::new(-5.0, -3.0, -1.0),
        Point3::new(5.0, 3.0, 1.0),
    )))
    .unwrap();
    let mut rng = Rng::new(31);
    let mut off_surface = 0;
    for c in [&sphere, &cube] {
        let n = c.triangle_count();
        let mut points: Vec<Point3> = Vec::new();
        for k in 0..n {
            let t = c.tri(k);
            points.extend([t[0], nalgebra::center(&t[0], &t[1])]);
        }
        for _ in 0..2000 {
            let spread = [0.01, 1.0, 10.0, 100.0][rng.below(4)];
            let t = c.tri(rng.below(n));
            let v = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            points.push(t[0] + v * spread);
        }
        for p in points {
            let want = c.closest(&p, 0.0);
            for hint in [Some(want.1), Some(rng.below(n)), Some(n + 5), None] {
                let got = c.closest_from(&p, 0.0, hint);
                assert_eq!(
                    (got.0.to_bits(), got.1, got.2),
                    (want.0.to_bits(), want.1, want.2),
                    "{p:?} hint {hint:?}"
                );
            }
            off_surface += usize::from(want.0 > 0.0);
        }
    }
    assert!(off_surface > 1000);
}

/// The walk's stack keeps last-in first-out order across its spill to the heap.
#[test]
fn the_walk_stack_spills_in_order() {
    let mut s = WalkStack::new();
    for v in 0..200u32 {
        s.push(v);
        if v % 3 == 0 {
            assert_eq!(s.pop(), Some(v));
            s.push(v);
        }
    }
    for v in (0..200u32).rev() {
        assert_eq!(s.pop(), Some(v));
    }
    assert_eq!(s.pop(), None);
}
