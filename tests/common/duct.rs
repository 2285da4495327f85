//! Generated assemblies without mates for the sequence tests and bench: boxes as
//! meshes, a document writer, and a grid of clips in tubes (issue 26).

use fitup::math::{Point3, Transform, Vec3};
use fitup::mesh::Mesh;
use std::path::{Path, PathBuf};

/// Boxes `(lo, hi)` (mm, local frame) as one mesh, moved by `t`.
pub fn boxes(list: &[([f64; 3], [f64; 3])], t: &Transform) -> Mesh {
    let mut soup = Vec::new();
    for (lo, hi) in list {
        let m = Mesh::cuboid(Point3::from(*lo), Point3::from(*hi));
        for k in 0..m.triangles.len() {
            let [a, b, c] = m.triangle(k);
            soup.push([t.apply(&a), t.apply(&b), t.apply(&c)]);
        }
    }
    Mesh::from_triangle_soup(soup).unwrap()
}

/// A document in `dir` with one component per mesh (identity pose: the meshes are
/// written where they sit) and no mates; returns its path.
pub fn write_doc(dir: &Path, parts: &[(&str, Mesh)]) -> PathBuf {
    let mut y = String::from("parts:\n");
    for (name, mesh) in parts {
        fitup::mesh::write_stl(&dir.join(format!("{name}.stl")), mesh).unwrap();
        y += &format!("  {name}:\n    stl: {name}.stl\n");
    }
    y += "components:\n";
    for (name, _) in parts {
        y += &format!("- {{name: {name}, part: {name}}}\n");
    }
    let path = dir.join("product.yaml");
    std::fs::write(&path, y).unwrap();
    path
}

/// A 25-part assembly without mates: a plate carrying a 3 × 4 grid of open tubes
/// (10 × 10 mm inside, 56 mm long, their walls cut in `slices` slices along the tube:
/// 48 triangles per slice) with a clip in each, 1 mm clear of its walls.
pub fn duct_grid(dir: &Path, slices: usize) -> PathBuf {
    let mut parts: Vec<(String, Mesh)> = Vec::new();
    let plate = boxes(
        &[([-20.0, -20.0, -40.0], [120.0, 150.0, -35.0])],
        &Transform::IDENTITY,
    );
    parts.push(("plate".into(), plate));
    for i in 0..3 {
        for j in 0..4 {
            let at = Transform::from_translation(Vec3::new(40.0 * i as f64, 35.0 * j as f64, 0.0));
            // Walls cut in slices along the tube: many triangles per sweep.
            let mut walls = Vec::new();
            let h = 56.0 / slices as f64;
            for s in 0..slices {
                let (z0, z1) = (-35.0 + h * s as f64, -35.0 + h * (s + 1) as f64);
                walls.push(([5.0, -7.0, z0], [7.0, 7.0, z1]));
                walls.push(([-7.0, -7.0, z0], [-5.0, 7.0, z1]));
                walls.push(([-5.0, 5.0, z0], [5.0, 7.0, z1]));
                walls.push(([-5.0, -7.0, z0], [5.0, -5.0, z1]));
            }
            parts.push((format!("tube{i}{j}"), boxes(&walls, &at)));
            let clip = boxes(&[([-4.0, -4.0, -30.0], [4.0, 4.0, 10.0])], &at);
            parts.push((format!("clip{i}{j}"), clip));
        }
    }
    let refs: Vec<(&str, Mesh)> = parts.iter().map(|(n, m)| (n.as_str(), m.clone())).collect();
    write_doc(dir, &refs)
}
