//! A generated 10-part assembly with mates, shared by the sequence tests and bench.

use fitup::mesh::Mesh;
use std::path::{Path, PathBuf};

/// A 3 × 3 pegboard written to `dir`: a 30 mm plate 5 mm thick with nine 4 mm holes
/// and nine pegs seated in them (each concentric with its hole, head coincident with
/// the plate's top); the plate is `fixed` or free. Returns the document's path.
pub fn pegboard(dir: &Path, plate_fixed: bool) -> PathBuf {
    pegboard_with(dir, plate_fixed, 16)
}

/// [`pegboard`] with `segments` facets around each hole and peg (a multiple of 4):
/// the bench's fine variant tessellates it to ~150 000 triangles.
pub fn pegboard_with(dir: &Path, plate_fixed: bool, segments: usize) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let (pitch, t, r) = (10.0, 5.0, 2.0);
    let plate = Mesh::perforated_plate(3, 3, pitch, t, r, segments / 4, |_, _| true).unwrap();
    fitup::mesh::write_stl(&dir.join("plate.stl"), &plate).unwrap();
    let rs = r * (std::f64::consts::PI / segments as f64).cos() * 0.97;
    let peg = Mesh::lathe(
        &[
            (0.0, 0.0),
            (rs, 0.0),
            (rs, t),
            (1.6 * r, t),
            (1.6 * r, t + 2.0),
            (0.0, t + 2.0),
        ],
        segments,
    )
    .unwrap();
    fitup::mesh::write_stl(&dir.join("peg.stl"), &peg).unwrap();
    let mut y = String::from(
        "parts:\n  plate:\n    stl: plate.stl\n    planes:\n      top: {point: [0, 0, 5], normal: [0, 0, 1]}\n    axes:\n",
    );
    let at = |i: usize| pitch * (i as f64 + 0.5);
    for i in 0..3 {
        for j in 0..3 {
            y += &format!(
                "      hole{i}{j}: {{point: [{}, {}, 0], direction: [0, 0, 1]}}\n",
                at(i),
                at(j)
            );
        }
    }
    y += "  peg:\n    stl: peg.stl\n    planes:\n      under_head: {point: [0, 0, 5], normal: [0, 0, -1]}\n    axes:\n      axis: {point: [0, 0, 0], direction: [0, 0, 1]}\n";
    y += &format!("components:\n- {{name: plate, part: plate, fixed: {plate_fixed}}}\n");
    let mut mates = String::from("mates:\n");
    for i in 0..3 {
        for j in 0..3 {
            y += &format!("- name: peg{i}{j}\n  part: peg\n  transform: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[{},{},0,1]]\n", at(i), at(j));
            mates += &format!("- {{name: peg{i}{j}_axis, type: concentric, entities: [plate/hole{i}{j}, peg{i}{j}/axis]}}\n");
            mates += &format!("- {{name: peg{i}{j}_seat, type: coincident, entities: [plate/top, peg{i}{j}/under_head]}}\n");
        }
    }
    let path = dir.join("pegboard.yaml");
    std::fs::write(&path, y + mates.as_str()).unwrap();
    path
}
