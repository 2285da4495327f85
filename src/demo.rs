//! The bundled demo cell of seed 000 (fig. 11): a table, two perforated plates and
//! five screws, generated in code so the committed `models/` can be re-derived.
//!
//! World frame: floor at z = 0, table top surface at z = 750 mm, table spanning
//! x ∈ [0, 1200], y ∈ [0, 800] mm.

use crate::document::file::{AxisFile, ComponentFile, DocumentFile, MateFile, PartFile, PlaneFile};
use crate::math::{Point3, Transform, Vec3};
use crate::mesh::{write_stl, Mesh, MeshError};
use indexmap::IndexMap;
use std::path::Path;

/// Table top surface height (mm).
pub const TABLE_TOP: f64 = 750.0;
/// Screw shank radius (mm); the plates' holes have radius [`HOLE_RADIUS`].
pub const SCREW_RADIUS: f64 = 4.0;
/// Plate hole radius (mm): 0.5 mm radial clearance around a screw.
pub const HOLE_RADIUS: f64 = 4.5;
/// Plate thickness (mm) = screw shank length, so an inserted screw's tip rests on the table.
pub const PLATE_THICKNESS: f64 = 10.0;

fn plane(point: [f64; 3], normal: [f64; 3]) -> PlaneFile {
    PlaneFile { point, normal }
}

fn axis(point: [f64; 3], direction: [f64; 3]) -> AxisFile {
    AxisFile { point, direction }
}

/// The table: a 1200 × 800 × 40 mm top on four 60 mm square legs.
pub fn table_mesh() -> Mesh {
    let mut m = Mesh::cuboid(
        Point3::new(0.0, 0.0, TABLE_TOP - 40.0),
        Point3::new(1200.0, 800.0, TABLE_TOP),
    );
    for (x, y) in [(20.0, 20.0), (1120.0, 20.0), (20.0, 720.0), (1120.0, 720.0)] {
        m.append(&Mesh::cuboid(
            Point3::new(x, y, 0.0),
            Point3::new(x + 60.0, y + 60.0, TABLE_TOP - 40.0),
        ));
    }
    m
}

/// An M8-like screw: shank r = 4 mm × 10 mm, head r = 7 mm × 5 mm, tip at the origin,
/// axis +Z.
pub fn screw_mesh() -> Result<Mesh, MeshError> {
    let h = PLATE_THICKNESS;
    Mesh::lathe(
        &[
            (0.0, 0.0),
            (SCREW_RADIUS, 0.0),
            (SCREW_RADIUS, h),
            (7.0, h),
            (7.0, h + 5.0),
            (0.0, h + 5.0),
        ],
        32,
    )
}

/// Tile centres (mm, plate frame) of the holes of a plate.
fn hole_centres(holes: &[(usize, usize)]) -> Vec<[f64; 3]> {
    holes
        .iter()
        .map(|&(i, j)| [(i as f64 + 0.5) * 100.0, (j as f64 + 0.5) * 100.0, 0.0])
        .collect()
}

fn plate_part(stl: &str, nx: usize, ny: usize, holes: &[(usize, usize)]) -> PartFile {
    let (w, d) = (nx as f64 * 100.0, ny as f64 * 100.0);
    let mut planes = IndexMap::new();
    planes.insert("bottom".into(), plane([0.0, 0.0, 0.0], [0.0, 0.0, -1.0]));
    planes.insert(
        "top_face".into(),
        plane([0.0, 0.0, PLATE_THICKNESS], [0.0, 0.0, 1.0]),
    );
    planes.insert(
        "front_edge".into(),
        plane([0.0, 0.0, 0.0], [0.0, -1.0, 0.0]),
    );
    planes.insert("left_edge".into(), plane([0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]));
    let mut axes = IndexMap::new();
    axes.insert(
        "center_axis".into(),
        axis([w / 2.0, d / 2.0, 0.0], [0.0, 0.0, 1.0]),
    );
    for (k, c) in hole_centres(holes).into_iter().enumerate() {
        axes.insert(format!("hole{}", k + 1), axis(c, [0.0, 0.0, 1.0]));
    }
    PartFile {
        stl: stl.into(),
        planes,
        axes,
        points: IndexMap::new(),
        features: vec![],
    }
}

const PLATE_A_HOLES: [(usize, usize); 3] = [(0, 0), (1, 1), (2, 0)];
const PLATE_B_HOLES: [(usize, usize); 2] = [(0, 0), (1, 1)];

fn mate(name: &str, kind: &str, a: &str, b: &str) -> MateFile {
    MateFile {
        name: name.into(),
        kind: kind.into(),
        entities: [a.into(), b.into()],
        value: None,
        aligned: None,
        about: None,
    }
}

fn component(name: &str, part: &str, fixed: bool, color: &str, t: Transform) -> ComponentFile {
    ComponentFile {
        name: name.into(),
        part: part.into(),
        fixed,
        color: Some(serde_yaml::Value::String(color.into())),
        transform: Some(t.to_matrix()),
    }
}

/// The demo document (as its YAML schema), meshes named `meshes/*.stl`.
pub fn cell_document() -> DocumentFile {
    let mut parts = IndexMap::new();
    let mut table = PartFile {
        stl: "meshes/table.stl".into(),
        planes: IndexMap::new(),
        axes: IndexMap::new(),
        points: IndexMap::new(),
        features: vec![],
    };
    table.planes.insert(
        "top_face".into(),
        plane([0.0, 0.0, TABLE_TOP], [0.0, 0.0, 1.0]),
    );
    table.planes.insert(
        "front_edge".into(),
        plane([0.0, 0.0, TABLE_TOP], [0.0, -1.0, 0.0]),
    );
    table.axes.insert(
        "b_axis".into(),
        axis([800.0, 400.0, TABLE_TOP], [0.0, 0.0, 1.0]),
    );
    parts.insert("table".into(), table);
    parts.insert(
        "plate_a".into(),
        plate_part("meshes/plate_a.stl", 3, 2, &PLATE_A_HOLES),
    );
    parts.insert(
        "plate_b".into(),
        plate_part("meshes/plate_b.stl", 2, 2, &PLATE_B_HOLES),
    );
    let mut screw = PartFile {
        stl: "meshes/screw.stl".into(),
        planes: IndexMap::new(),
        axes: IndexMap::new(),
        points: IndexMap::new(),
        features: vec![],
    };
    screw
        .axes
        .insert("axis".into(), axis([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]));
    screw.planes.insert(
        "under_head".into(),
        plane([0.0, 0.0, PLATE_THICKNESS], [0.0, 0.0, -1.0]),
    );
    screw.points.insert("tip".into(), [0.0, 0.0, 0.0]);
    parts.insert("screw".into(), screw);

    let at = |x: f64, y: f64, z: f64| Transform::from_translation(Vec3::new(x, y, z));
    let mut components = vec![
        component("table", "table", true, "#8c8c8c", Transform::IDENTITY),
        component(
            "plate_a",
            "plate_a",
            true,
            "#4a7fb5",
            at(100.0, 150.0, TABLE_TOP),
        ),
        // Placed roughly; the mates put it on the table around `b_axis`.
        component(
            "plate_b",
            "plate_b",
            false,
            "#5aa06b",
            at(690.0, 310.0, TABLE_TOP + 3.0),
        ),
    ];
    let mut mates = vec![
        mate(
            "plate_b_on_table",
            "coincident",
            "table/top_face",
            "plate_b/bottom",
        ),
        mate(
            "plate_b_centred",
            "concentric",
            "table/b_axis",
            "plate_b/center_axis",
        ),
        MateFile {
            value: Some(0.0),
            about: Some("table/b_axis".into()),
            ..mate("角度1", "angle", "table/front_edge", "plate_b/front_edge")
        },
    ];
    for k in 1..=3 {
        let name = format!("screw{k}");
        // Start near the hole; the mates seat it.
        let c = hole_centres(&PLATE_A_HOLES)[k - 1];
        components.push(component(
            &name,
            "screw",
            false,
            "#d4a72c",
            at(100.0 + c[0] + 0.3, 150.0 + c[1], TABLE_TOP + 1.0),
        ));
        mates.push(mate(
            &format!("{name}_in_hole"),
            "concentric",
            &format!("plate_a/hole{k}"),
            &format!("{name}/axis"),
        ));
        mates.push(mate(
            &format!("{name}_seated"),
            "coincident",
            "plate_a/top_face",
            &format!("{name}/under_head"),
        ));
    }
    // Two loose screws standing on the table, to be inserted into plate_b's holes.
    components.push(component(
        "screw4",
        "screw",
        false,
        "#d4a72c",
        at(600.0, 650.0, TABLE_TOP),
    ));
    components.push(component(
        "screw5",
        "screw",
        false,
        "#d4a72c",
        at(650.0, 650.0, TABLE_TOP),
    ));
    DocumentFile {
        units: "mm".into(),
        description: Some("Seed 000 fig. 11 demo cell: a table, two plates, five screws (robots: models/mz07.yaml)".into()),
        parts,
        components,
        mates,
    }
}

/// Writes the demo cell to `dir/cell.yaml` and `dir/meshes/*.stl` (atomically).
pub fn write_cell(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir.join("meshes"))?;
    write_stl(&dir.join("meshes/table.stl"), &table_mesh())?;
    write_stl(
        &dir.join("meshes/plate_a.stl"),
        &Mesh::perforated_plate(3, 2, 100.0, PLATE_THICKNESS, HOLE_RADIUS, 8, |i, j| {
            PLATE_A_HOLES.contains(&(i, j))
        })?,
    )?;
    write_stl(
        &dir.join("meshes/plate_b.stl"),
        &Mesh::perforated_plate(2, 2, 100.0, PLATE_THICKNESS, HOLE_RADIUS, 8, |i, j| {
            PLATE_B_HOLES.contains(&(i, j))
        })?,
    )?;
    write_stl(&dir.join("meshes/screw.stl"), &screw_mesh()?)?;
    let text = cell_document().to_yaml()?;
    crate::fsutil::write_atomic(&dir.join("cell.yaml"), text.as_bytes())?;
    Ok(())
}
