//! Coordinate systems as named references of parts (issue 37, capability 10:
//! SolidWorks' `CoordSys` features): read from and saved to the document, placed with
//! the component, mated coincident axis for axis (SolidWorks' `AddMate` between two
//! coordinate systems), refused where they are not a coordinate system. Every project
//! here is generated in code; poses are checked against 4×4 matrix products written
//! here, not against the library's composition.

use fitup::document::{Document, DocumentError, MateKind, MateSpec};
use fitup::math::Rng;
use fitup::math::{Transform, Vec3};
use nalgebra::Matrix4;

const CUBE: &str = "solid c\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 10 0\nvertex 10 0 0\nendloop\nendfacet\nfacet normal 0 0 -1\nouter loop\nvertex 10 0 0\nvertex 0 10 0\nvertex 10 10 0\nendloop\nendfacet\nendsolid c\n";

/// A base (fixed) and a block, each with `CS1`: the base's turned 30° about Z at
/// (60, 40, 75), the block's at (5, 5, 0) with X along the block's Y.
fn doc_text(extra_block_cs: &str) -> String {
    format!(
        "\
parts:
  base:
    stl: cube.stl
    planes:
      top: {{point: [0.0, 0.0, 75.0], normal: [0.0, 0.0, 1.0]}}
    coordinate_systems:
      CS1:
        origin: [60.0, 40.0, 75.0]
        x: [0.8660254037844387, 0.5, 0.0]
        y: [-0.5, 0.8660254037844387, 0.0]
  block:
    stl: cube.stl
    coordinate_systems:
      CS1:
        origin: [5.0, 5.0, 0.0]
        x: [0.0, 1.0, 0.0]
        y: [-1.0, 0.0, 0.0]
{extra_block_cs}components:
- name: base
  part: base
  fixed: true
- name: block
  part: block
  transform:
  - [1.0, 0.0, 0.0, 0.0]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [100.0, 50.0, 900.0, 1.0]
"
    )
}

fn project(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cube.stl"), CUBE).unwrap();
    let p = dir.path().join("doc.yaml");
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

/// The column-vector 4×4 of a pose from the row-vector document matrix.
fn column(t: &Transform) -> Matrix4<f64> {
    let m = t.to_matrix();
    Matrix4::from_fn(|i, j| m[j][i])
}

/// The column-vector 4×4 of origin + X + Y (Z = X × Y), built here.
fn system(o: [f64; 3], x: [f64; 3], y: [f64; 3]) -> Matrix4<f64> {
    let (x, y) = (Vec3::from(x).normalize(), Vec3::from(y).normalize());
    let z = x.cross(&y);
    let mut m = Matrix4::identity();
    for i in 0..3 {
        m[(i, 0)] = x[i];
        m[(i, 1)] = y[i];
        m[(i, 2)] = z[i];
        m[(i, 3)] = o[i];
    }
    m
}

fn base_cs() -> Matrix4<f64> {
    let c = 30f64.to_radians().cos();
    system([60.0, 40.0, 75.0], [c, 0.5, 0.0], [-0.5, c, 0.0])
}

fn block_cs() -> Matrix4<f64> {
    system([5.0, 5.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0])
}

fn max_diff(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    (a - b).abs().max()
}

fn cs_mate(a: &str, b: &str) -> MateSpec {
    MateSpec {
        name: "cs_mate".into(),
        kind: MateKind::Coincident,
        entities: [a.into(), b.into()],
        value: None,
        aligned: None,
        about: None,
    }
}

#[test]
fn coordinate_systems_load_posed_with_the_component() {
    let (_dir, p) = project(&doc_text(""));
    let doc = Document::open(&p).unwrap();
    let part = doc.part_coordinate_system("base", "CS1").unwrap();
    assert!(max_diff(&column(&part), &base_cs()) < 1e-12);
    let i = doc.component_index("block").unwrap();
    let world = doc.coordinate_system(i, "CS1").unwrap();
    let want = column(&doc.components()[i].transform) * block_cs();
    assert!(max_diff(&column(&world), &want) < 1e-12, "{world:?}");
    // SolidWorks' ArrayData: rows 0..3 are the system's axes, then the origin (m)
    let d = part.to_array_data_si();
    let c = 30f64.to_radians().cos();
    for (k, v) in [
        c, 0.5, 0.0, -0.5, c, 0.0, 0.0, 0.0, 1.0, 0.06, 0.04, 0.075, 1.0,
    ]
    .iter()
    .enumerate()
    {
        assert!(
            (d[k] - v).abs() < 1e-12,
            "ArrayData[{k}] = {} not {v}",
            d[k]
        );
    }
}

#[test]
fn a_coincident_mate_puts_one_system_on_the_other_from_any_pose() {
    let (_dir, p) = project(&doc_text(""));
    let mut rng = Rng::new(37);
    for round in 0..50 {
        let mut doc = Document::open(&p).unwrap();
        let start = Transform::from_parts(
            Vec3::new(
                rng.range(-500.0, 500.0),
                rng.range(-500.0, 500.0),
                rng.range(-500.0, 500.0),
            ),
            rng.rotation(),
        );
        doc.set_transform("block", start).unwrap();
        // both orders: the free side moves whichever side of the mate it is
        let spec = if round % 2 == 0 {
            cs_mate("base/CS1", "block/CS1")
        } else {
            cs_mate("block/CS1", "base/CS1")
        };
        doc.add_mate(&spec).unwrap();
        let i = doc.component_index("block").unwrap();
        // block pose · block CS = base CS (base is fixed at identity):
        // pose = base_cs · block_cs⁻¹ in column-vector form
        let want = base_cs() * block_cs().try_inverse().unwrap();
        let got = column(&doc.components()[i].transform);
        assert!(
            max_diff(&got, &want) < 1e-9,
            "round {round}: {got} vs {want}"
        );
        let (a, b) = (
            doc.coordinate_system(0, "CS1").unwrap(),
            doc.coordinate_system(i, "CS1").unwrap(),
        );
        assert!(a.approx_eq(&b, 1e-9, 1e-9));
    }
}

#[test]
fn the_mate_and_the_systems_survive_a_save() {
    let (dir, p) = project(&doc_text(""));
    let mut doc = Document::open(&p).unwrap();
    doc.add_mate(&cs_mate("base/CS1", "block/CS1")).unwrap();
    let out = dir.path().join("saved.yaml");
    doc.save_as(&out).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("coordinate_systems:"), "{text}");
    let back = Document::open(&out).unwrap();
    assert_eq!(back.mate("cs_mate").unwrap().kind, MateKind::Coincident);
    let i = back.component_index("block").unwrap();
    assert!(back.components()[i]
        .transform
        .approx_eq(&doc.components()[i].transform, 1e-9, 1e-12));
    assert!(
        max_diff(
            &column(&back.part_coordinate_system("block", "CS1").unwrap()),
            &block_cs()
        ) < 1e-12
    );
}

#[test]
fn what_is_not_a_coordinate_system_is_refused() {
    // axes that are not perpendicular, located at the system's line
    let bad = "  extra:\n    stl: cube.stl\n    coordinate_systems:\n      Skew:\n        origin: [0.0, 0.0, 0.0]\n        x: [1.0, 0.0, 0.0]\n        y: [0.1, 1.0, 0.0]\n";
    let (_dir, p) = project(&doc_text(bad));
    let e = Document::open(&p).unwrap_err();
    let s = e.to_string();
    assert!(s.contains("Skew") && s.contains("perpendicular"), "{s}");
    let loc = e.location().expect("located");
    let line = std::fs::read_to_string(&p)
        .unwrap()
        .lines()
        .position(|l| l.contains("Skew:"))
        .unwrap()
        + 1;
    assert_eq!(loc.line, Some(line), "{s}");
    let zero = bad.replace("[0.1, 1.0, 0.0]", "[0.0, 0.0, 0.0]");
    let (_dir, p) = project(&doc_text(&zero));
    assert!(Document::open(&p)
        .unwrap_err()
        .to_string()
        .contains("zero length"));

    let (_dir, p) = project(&doc_text(""));
    let mut doc = Document::open(&p).unwrap();
    let before = doc.to_file();
    // a system with a plane, anti-aligned systems
    assert!(doc.add_mate(&cs_mate("base/top", "block/CS1")).is_err());
    let mut anti = cs_mate("base/CS1", "block/CS1");
    anti.aligned = Some(false);
    let e = doc.add_mate(&anti).unwrap_err().to_string();
    assert!(e.contains("anti-aligned"), "{e}");
    assert_eq!(doc.to_file(), before, "nothing changed");
    // asked as a coordinate system, a plane says what it is
    match doc.part_coordinate_system("base", "top") {
        Err(DocumentError::NotACoordinateSystem { kind, .. }) => assert_eq!(kind, "plane"),
        other => panic!("{other:?}"),
    }
    match doc.part_coordinate_system("base", "CS2") {
        Err(e @ DocumentError::NotFound { .. }) => assert!(e.to_string().contains("CS1"), "{e}"),
        other => panic!("{other:?}"),
    }
    // flipping has nothing to flip
    doc.add_mate(&cs_mate("base/CS1", "block/CS1")).unwrap();
    assert!(doc.flip_mate("cs_mate").is_err());
}

#[test]
fn a_system_pair_leaves_no_freedom() {
    let (_dir, p) = project(&doc_text(""));
    let mut doc = Document::open(&p).unwrap();
    doc.add_mate(&cs_mate("base/CS1", "block/CS1")).unwrap();
    let m = doc.mate("cs_mate").unwrap().clone();
    assert_eq!(fitup::sequence::Freedom::of_mate(&doc, &m).count(), 0);
}
