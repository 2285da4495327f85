//! The pair walk against all pairs: every pruning test in it is conservative.

use super::super::containment::{shared_face_overlap, walk_margin};
use super::super::triangle::tri_tri;
use super::*;
use crate::math::{Point3, Rng};
use crate::mesh::Mesh;
use nalgebra::UnitQuaternion;
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Per pair of triangles (tree order) that meets or shares a face: the crossing
/// depth and the shared-face overlap, as bits (the same arithmetic must give the
/// same numbers).
type Met = BTreeMap<(u32, u32), (Option<u64>, u64)>;

fn setup(a: &Collider, pa: &Transform, b: &Collider, pb: &Transform) -> (Relative, f64, bool) {
    let shared = a.encloses_volume() && b.encloses_volume();
    (Relative::new(pa, pb), eps(a, b, pa, pb), shared)
}

fn record(met: &mut Met, k: (u32, u32), depth: Option<f64>, overlap: f64) {
    if depth.is_some() || overlap > 0.0 {
        met.insert(k, (depth.map(f64::to_bits), overlap.to_bits()));
    }
}

/// What the walk hands over, as `interferes` and `contact` test it.
fn walked(a: &Collider, pa: &Transform, b: &Collider, pb: &Transform) -> Met {
    let (rel, eps, shared) = setup(a, pa, b, pb);
    let oriented = a.is_solid() && b.is_solid();
    let mut met = Met::new();
    let margin = walk_margin(shared, eps);
    let floor = Cell::new(-1.0);
    let _ = for_each_triangle_pair::<()>(a, b, &rel, margin, shared, &floor, |fa, fb| {
        let depth = tri_tri_with(fa.t, fa.n, fb.t, fb.n, eps, oriented);
        let overlap = if shared {
            super::super::containment::shared_face_overlap_with(fa.t, fa.n, fb.t, fb.n)
        } else {
            0.0
        };
        record(&mut met, (fa.k, fb.k), depth, overlap);
        ControlFlow::Continue(())
    });
    met
}

/// Every pair of triangles, `b`'s moved into `a`'s frame as the walk moves them.
fn all_pairs(a: &Collider, pa: &Transform, b: &Collider, pb: &Transform) -> Met {
    let (rel, eps, shared) = setup(a, pa, b, pb);
    let oriented = a.is_solid() && b.is_solid();
    let mut met = Met::new();
    for ka in 0..a.triangle_count() {
        let ta = a.tri(ka);
        for kb in 0..b.triangle_count() {
            let tb = rel.tri(&b.tri(kb));
            let depth = tri_tri(&ta, &tb, eps, oriented);
            let overlap = if shared {
                shared_face_overlap(&ta, &tb)
            } else {
                0.0
            };
            record(&mut met, (ka as u32, kb as u32), depth, overlap);
        }
    }
    met
}

/// A block cut in `slices` closed boxes stacked along Z: encloses a volume, not
/// a 2-manifold (the shared-face rule applies, containment does not).
fn sliced(hi: [f64; 3], slices: usize) -> Mesh {
    let mut soup = Vec::new();
    let level = |k: usize| hi[2] * k as f64 / slices as f64;
    for s in 0..slices {
        let m = Mesh::cuboid(
            Point3::new(0.0, 0.0, level(s)),
            Point3::new(hi[0], hi[1], level(s + 1)),
        );
        soup.extend((0..m.triangles.len()).map(|k| m.triangle(k)));
    }
    Mesh::from_triangle_soup(soup).unwrap()
}

/// A box of `n × n` facets a side: many small coplanar faces.
fn fine_box(hi: [f64; 3], n: usize) -> Mesh {
    let mut soup = Vec::new();
    let c = Mesh::cuboid(Point3::origin(), Point3::from(hi));
    for k in 0..c.triangles.len() {
        soup.push(c.triangle(k));
    }
    // split every triangle n² ways (midpoint subdivision keeps it closed)
    for _ in 0..n {
        soup = soup
            .into_iter()
            .flat_map(|t: Tri| {
                let m = [0, 1, 2].map(|i| nalgebra::center(&t[i], &t[(i + 1) % 3]));
                [
                    [t[0], m[0], m[2]],
                    [m[0], t[1], m[1]],
                    [m[2], m[1], t[2]],
                    [m[0], m[1], m[2]],
                ]
            })
            .collect();
    }
    Mesh::from_triangle_soup(soup).unwrap()
}

fn shape(kind: u8) -> Collider {
    let mesh = match kind % 6 {
        0 => Mesh::cuboid(Point3::origin(), Point3::new(10.0, 6.0, 4.0)),
        1 => sliced([10.0, 6.0, 4.0], 3),
        2 => fine_box([10.0, 6.0, 4.0], 2),
        3 => {
            // open: a box without its top
            let mut m = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 6.0, 4.0));
            m.triangles.retain(|t| {
                let z = |i: u32| m.vertices[i as usize].z;
                !(z(t[0]) == 4.0 && z(t[1]) == 4.0 && z(t[2]) == 4.0)
            });
            m
        }
        4 => crate::mesh::Mesh::uv_sphere(4.0, 16),
        _ => Mesh::cylinder(3.0, 8.0, 24),
    };
    Collider::new(Arc::new(mesh)).unwrap()
}

/// Poses that put faces in one plane and edges on faces (multiples of a
/// quarter turn, a half-millimetre grid), nudged a few f32 roundings or a
/// microradian off, or anywhere.
fn pose(rng: &mut Rng, style: u8) -> Transform {
    let grid = |rng: &mut Rng| (rng.range(-20.0, 20.0) * 2.0).round() / 2.0;
    let quarter = |rng: &mut Rng| {
        let axis = [Vec3::x_axis(), Vec3::y_axis(), Vec3::z_axis()][rng.below(3)];
        UnitQuaternion::from_axis_angle(&axis, std::f64::consts::FRAC_PI_2 * rng.below(4) as f64)
    };
    match style % 4 {
        0 => Transform::from_parts(
            Vec3::new(grid(rng), grid(rng), grid(rng)) / 2.0,
            quarter(rng) * quarter(rng),
        ),
        1 => Transform::from_parts(
            Vec3::new(grid(rng), grid(rng), grid(rng)) / 2.0
                + Vec3::new(rng.range(-3e-5, 3e-5), 0.0, rng.range(-3e-5, 3e-5)),
            UnitQuaternion::from_scaled_axis(Vec3::new(0.0, rng.range(-2e-6, 2e-6), 0.0))
                * quarter(rng),
        ),
        2 => Transform::from_parts(
            Vec3::new(grid(rng), grid(rng), grid(rng)) / 2.0,
            UnitQuaternion::from_scaled_axis(Vec3::new(rng.range(-3e-5, 3e-5), 0.0, 0.0)),
        ),
        _ => Transform::from_parts(
            Vec3::new(
                rng.range(-8.0, 8.0),
                rng.range(-8.0, 8.0),
                rng.range(-8.0, 8.0),
            ),
            rng.rotation(),
        ),
    }
}

proptest! {
    #![proptest_config(crate::test_support::proptest_config(160))]
    /// The walk hands over exactly the pairs that meet or share a face, with the
    /// same depths and overlaps to the bit, as testing every pair: solids, closed
    /// slices, fine and open meshes, in flush, nearly flush and random poses.
    #[test]
    fn the_walk_misses_no_pair_that_meets(
        kinds in (0u8..6, 0u8..6),
        styles in (0u8..4, 0u8..4),
        seed in 0u64..1_000_000,
    ) {
        let (a, b) = (shape(kinds.0), shape(kinds.1));
        let mut rng = Rng::new(seed);
        let (pa, pb) = (pose(&mut rng, styles.0), pose(&mut rng, styles.1));
        let all = all_pairs(&a, &pa, &b, &pb);
        prop_assert_eq!(walked(&a, &pa, &b, &pb), all);
    }
}

/// The same at poses where many pairs meet (the property above draws mostly
/// parts apart): each part at the other's faces.
#[test]
fn the_walk_misses_no_pair_in_contact() {
    let mut rng = Rng::new(5);
    let mut met = 0;
    for k in 0..400 {
        let (a, b) = (shape(k as u8), shape((k / 6) as u8));
        let pa = Transform::IDENTITY;
        let p = pose(&mut rng, (k % 3) as u8);
        let pb = Transform::from_parts(p.translation() / 4.0, p.rotation());
        let all = all_pairs(&a, &pa, &b, &pb);
        met += all.len();
        assert_eq!(walked(&a, &pa, &b, &pb), all, "{k}: {pb:?}");
    }
    assert!(met > 4000, "{met}");
}
