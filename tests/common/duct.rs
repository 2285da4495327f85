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
    duct_grid_of(dir, slices, 3, 4)
}

/// [`duct_grid`] with `nx` × `ny` tubes (`2 · nx · ny + 1` parts) on the same plate.
pub fn duct_grid_of(dir: &Path, slices: usize, nx: usize, ny: usize) -> PathBuf {
    let mut parts: Vec<(String, Mesh)> = Vec::new();
    let plate = boxes(
        &[([-20.0, -20.0, -40.0], [120.0, 150.0, -35.0])],
        &Transform::IDENTITY,
    );
    parts.push(("plate".into(), plate));
    for i in 0..nx {
        for j in 0..ny {
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

/// The grid of [`duct_grid`] with each tube one closed surface (a watertight solid,
/// as a CAD tessellation gives it: no faces inside the walls) whose eight wall faces
/// are cut in `strips` strips along the tube: `16 · strips + 16` triangles per tube.
/// (The bench's mesh-only scale row; used by the bench, not the tests.)
#[allow(dead_code)]
pub fn duct_grid_solid(dir: &Path, strips: usize) -> PathBuf {
    let mut parts: Vec<(String, Mesh)> = Vec::new();
    let plate = boxes(
        &[([-20.0, -20.0, -40.0], [120.0, 150.0, -35.0])],
        &Transform::IDENTITY,
    );
    parts.push(("plate".into(), plate));
    let (z0, z1) = (-35.0, 21.0);
    let outer = [(-7.0, -7.0), (7.0, -7.0), (7.0, 7.0), (-7.0, 7.0)];
    let inner = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
    for i in 0..3 {
        for j in 0..4 {
            let (dx, dy) = (40.0 * i as f64, 35.0 * j as f64);
            let p = |c: (f64, f64), z: f64| Point3::new(c.0 + dx, c.1 + dy, z);
            let mut soup: Vec<[Point3; 3]> = Vec::new();
            let h = (z1 - z0) / strips as f64;
            // The same bits for a level wherever it is used (the soup's vertices
            // are merged by their bits): the last level is the top itself.
            let level = |s: usize| if s == strips { z1 } else { z0 + h * s as f64 };
            for s in 0..strips {
                let (za, zb) = (level(s), level(s + 1));
                for k in 0..4 {
                    let (o0, o1) = (outer[k], outer[(k + 1) % 4]);
                    soup.push([p(o0, za), p(o1, za), p(o1, zb)]);
                    soup.push([p(o0, za), p(o1, zb), p(o0, zb)]);
                    // The inner walls face the bore (reversed).
                    let (i0, i1) = (inner[k], inner[(k + 1) % 4]);
                    soup.push([p(i0, za), p(i1, zb), p(i1, za)]);
                    soup.push([p(i0, za), p(i0, zb), p(i1, zb)]);
                }
            }
            for k in 0..4 {
                let (o0, o1, i0, i1) = (outer[k], outer[(k + 1) % 4], inner[k], inner[(k + 1) % 4]);
                // Bottom ring facing down, top ring facing up.
                soup.push([p(o0, z0), p(i1, z0), p(o1, z0)]);
                soup.push([p(o0, z0), p(i0, z0), p(i1, z0)]);
                soup.push([p(o0, z1), p(o1, z1), p(i1, z1)]);
                soup.push([p(o0, z1), p(i1, z1), p(i0, z1)]);
            }
            parts.push((
                format!("tube{i}{j}"),
                Mesh::from_triangle_soup(soup).unwrap(),
            ));
            let at = Transform::from_translation(Vec3::new(dx, dy, 0.0));
            let clip = boxes(&[([-4.0, -4.0, -30.0], [4.0, 4.0, 10.0])], &at);
            parts.push((format!("clip{i}{j}"), clip));
        }
    }
    let refs: Vec<(&str, Mesh)> = parts.iter().map(|(n, m)| (n.as_str(), m.clone())).collect();
    write_doc(dir, &refs)
}
