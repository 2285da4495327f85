use super::raw::{RawInstance, RawPart};
use super::*;

fn one_box() -> RawModel {
    let m = Mesh::cuboid(
        crate::math::Point3::origin(),
        crate::math::Point3::new(2.0, 3.0, 4.0),
    );
    RawModel {
        parts: vec![RawPart {
            name: "block".into(),
            solid_index: 1,
            solids_in_product: 1,
            vertices: m.vertices.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
            triangles: m.triangles.iter().flatten().copied().collect(),
            exact_volume: 24.0,
            faces: 6,
            unmeshed_faces: 0,
            first_unmeshed_face: 0,
        }],
        instances: vec![RawInstance {
            name: "block-1".into(),
            path: "block-1".into(),
            part: 0,
            matrix: vec![1., 0., 0., 5., 0., 1., 0., 0., 0., 0., 1., 0.],
            scale: 1.0,
            parent: 0,
        }],
        length_unit: "MM".into(),
        ..RawModel::default()
    }
}

/// Open CASCADE's sphere faces put several nodes at a pole: welded, their
/// triangles collapse. The solid imports closed, without them, at its volume; a
/// solid really open is refused, the message naming open edges only (issue 38).
#[test]
fn collapsed_pole_triangles_do_not_refuse_a_closed_solid() {
    let soup = crate::mesh::tests::pole_sphere_soup(10.0, 24, 12);
    let raw = |soup: &[[crate::math::Point3; 3]]| {
        let mut model = one_box();
        let part = &mut model.parts[0];
        part.vertices = soup
            .iter()
            .flatten()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        part.triangles = (0..3 * soup.len() as u32).collect();
        part.exact_volume = 4.0 / 3.0 * std::f64::consts::PI * 1000.0;
        model
    };
    let start = std::time::Instant::now();
    let o = StepOptions::default();
    let m = from_raw(Path::new("s.step"), &o, &raw(&soup), false, start).unwrap();
    let mesh = &m.parts[0].mesh;
    assert_eq!(
        mesh.triangles.len(),
        soup.len() - 2 * 24,
        "collapsed ones left out"
    );
    assert!(mesh.inspect().is_watertight() && mesh.inspect().degenerate_triangles == 0);
    let v = mesh.signed_volume() / m.parts[0].exact_volume;
    assert!(v > 0.95 && v < 1.0, "{v}");
    let mut open = soup.clone();
    open.remove(1); // a triangle with area, at the pole
    let Err(e) = from_raw(Path::new("s.step"), &o, &raw(&open), false, start) else {
        panic!("a sphere with a hole imported");
    };
    let e = e.to_string();
    assert!(
        e.contains("3 open, 0 non-manifold")
            && e.contains("open edges: a face missing")
            && !e.contains("non-manifold edges:"),
        "{e}"
    );
}

#[test]
fn a_raw_model_is_checked_and_placed() {
    let start = std::time::Instant::now();
    let o = StepOptions::default();
    let m = from_raw(Path::new("b.step"), &o, &one_box(), false, start).unwrap();
    assert!((m.placed_mesh().unwrap().bounds().unwrap().lo.x - 5.0).abs() < 1e-12);
    assert!((m.placed_exact_volume() - 24.0).abs() < 1e-12);
    // A part index past the parts, a NaN placement, a face without triangles.
    let mut bad = one_box();
    bad.instances[0].part = 7;
    assert!(matches!(
        from_raw(Path::new("b.step"), &o, &bad, false, start),
        Err(StepError::BadPlacement { .. })
    ));
    let mut bad = one_box();
    bad.instances[0].matrix[0] = f64::NAN;
    assert!(from_raw(Path::new("b.step"), &o, &bad, false, start).is_err());
    let mut bad = one_box();
    bad.parts[0].unmeshed_faces = 1;
    bad.parts[0].first_unmeshed_face = 4;
    let e = from_raw(Path::new("b.step"), &o, &bad, false, start).unwrap_err();
    assert!(
        e.to_string()
            .contains("solid `block-1`: face 4 of 6 did not mesh"),
        "{e}"
    );
}
