//! The bundled demo cell of seed 000 (fig. 11): a table, two perforated plates and
//! five screws, generated in code so the committed `models/` can be re-derived.
//!
//! World frame: floor at z = 0, table top surface at z = 750 mm, table spanning
//! x ∈ [0, 1200], y ∈ [0, 800] mm.

use crate::document::file::{
    AxisFile, ComponentFile, DocumentFile, LinkFile, MateFile, PartFile, PlaneFile, RobotFile,
};
use crate::math::{Point3, Transform, Vec3};
use crate::mesh::{write_stl, Mesh, MeshError};
use indexmap::IndexMap;
use std::f64::consts::FRAC_PI_2;
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
        planes,
        axes,
        ..PartFile::from_stl(stl)
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
        suppressed: false,
    }
}

fn component(name: &str, part: &str, fixed: bool, color: &str, t: Transform) -> ComponentFile {
    ComponentFile {
        fixed,
        color: Some(serde_yaml::Value::String(color.into())),
        ..ComponentFile::new(name, part, Some(t.to_matrix()))
    }
}

/// The demo document (as its YAML schema), meshes named `meshes/*.stl`.
pub fn cell_document() -> DocumentFile {
    let mut parts = IndexMap::new();
    let mut table = PartFile::from_stl("meshes/table.stl");
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
    let mut screw = PartFile::from_stl("meshes/screw.stl");
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
        mesh_deflection: None,
        parts,
        components,
        mates,
        robots: Vec::new(),
        equations: Vec::new(),
        assemblies: Vec::new(),
    }
}

/// What `fitup demo DIR` writes as `DIR/fitup.toml`: the mark of a project root.
pub const PROJECT_TOML: &str = "# Marks the root of a fitup project: scripts below this folder resolve their\n# paths against it and may use files inside it only (docs/scripting.md).\n";

/// Writes a demo project: `dir/fitup.toml` and the demo cell in `dir/models/`, the
/// layout of the fitup repository, so its example scripts run there unchanged.
pub fn write_project(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    write_cell(&dir.join("models"))?;
    crate::fsutil::write_atomic(
        &dir.join(crate::project::PROJECT_FILE),
        PROJECT_TOML.as_bytes(),
    )?;
    Ok(())
}

/// The files [`write_project`] writes, relative to its folder.
pub const PROJECT_FILES: &[&str] = &[
    crate::project::PROJECT_FILE,
    "models/cell.yaml",
    "models/meshes/table.stl",
    "models/meshes/plate_a.stl",
    "models/meshes/plate_b.stl",
    "models/meshes/screw.stl",
];

/// [`write_project`] for `fitup demo`: every file first passes the write rule
/// ([`crate::project::check_output`]; `force` is `--force`), so nothing is written when
/// one of them may not be replaced — and never through a symbolic link or over a
/// folder or FIFO, even with `force`.
pub fn write_project_checked(dir: &Path, force: bool) -> Result<(), Box<dyn std::error::Error>> {
    let rule = crate::project::OutputRule::forced(force);
    for file in PROJECT_FILES {
        let path = dir.join(file);
        crate::project::check_output(&path, &rule)
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    write_project(dir)
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

/// Height of the pedestals the two arms of the robot cell stand on (mm): the MZ07's
/// tool point at the zero configuration is then 48 mm above the table top.
pub const PEDESTAL_HEIGHT: f64 = 600.0;

/// Link meshes of the NACHI MZ07 (seed 000 table 2), drawn in the robot base frame at
/// the zero configuration (`drawn_at_zero`): `(part name, mesh)` for the base and links
/// 1–6. Simple solids around the D-H geometry: shoulder axis at (50, y, 340), elbow axis
/// at (50, y, 670), forearm along X at z = 715, wrist centre (390, 0, 715), flange at
/// (390, 0, 635), tool point at (390, 0, 198.1) (link 6 carries the tool spindle).
pub fn mz07_link_meshes() -> Vec<(String, Mesh)> {
    let p = Point3::new;
    let along_y = |r: f64, y0: f64, y1: f64, x: f64, z: f64| {
        // A Z cylinder turned onto +Y (rotation about X by −90°), then placed.
        let turn = Transform::from_rotation_about(Point3::origin(), Vec3::x(), -FRAC_PI_2)
            .unwrap_or(Transform::IDENTITY);
        Mesh::cylinder(r, y1 - y0, 32)
            .transformed(&(turn * Transform::from_translation(Vec3::new(x, y0, z))))
    };
    let along_x = |r: f64, x0: f64, x1: f64, z: f64| {
        let turn = Transform::from_rotation_about(Point3::origin(), Vec3::y(), FRAC_PI_2)
            .unwrap_or(Transform::IDENTITY);
        Mesh::cylinder(r, x1 - x0, 32)
            .transformed(&(turn * Transform::from_translation(Vec3::new(x0, 0.0, z))))
    };
    let z_cyl = |r: f64, z0: f64, z1: f64, x: f64| {
        Mesh::cylinder(r, z1 - z0, 32)
            .transformed(&Transform::from_translation(Vec3::new(x, 0.0, z0)))
    };
    let base = z_cyl(110.0, 0.0, 180.0, 0.0);
    let mut link1 = z_cyl(90.0, 180.0, 290.0, 0.0);
    link1.append(&Mesh::cuboid(p(-70.0, -75.0, 290.0), p(110.0, 75.0, 390.0)));
    let mut link2 = along_y(60.0, -130.0, -75.0, 50.0, 340.0);
    link2.append(&Mesh::cuboid(p(15.0, -125.0, 340.0), p(85.0, -80.0, 670.0)));
    link2.append(&along_y(50.0, -130.0, -75.0, 50.0, 670.0));
    let mut link3 = Mesh::cuboid(p(0.0, -70.0, 640.0), p(130.0, 70.0, 770.0));
    link3.append(&along_y(45.0, -75.0, 75.0, 50.0, 670.0));
    let mut link4 = along_x(42.0, 130.0, 340.0, 715.0);
    link4.append(&Mesh::cuboid(p(340.0, -45.0, 690.0), p(350.0, 45.0, 740.0)));
    let mut link5 = along_y(35.0, -40.0, 40.0, 390.0, 715.0);
    link5.append(&z_cyl(32.0, 675.0, 680.0, 390.0));
    let mut link6 = z_cyl(30.0, 635.0, 672.0, 390.0);
    link6.append(&z_cyl(12.0, 260.0, 635.0, 390.0));
    link6.append(
        &Mesh::frustum(1.0, 8.0, 61.9, 16)
            .transformed(&Transform::from_translation(Vec3::new(390.0, 0.0, 198.1))),
    );
    let names = ["base", "link1", "link2", "link3", "link4", "link5", "link6"];
    names
        .iter()
        .map(|n| format!("mz07_{n}"))
        .zip([base, link1, link2, link3, link4, link5, link6])
        .collect()
}

fn mz07_parts(parts: &mut IndexMap<String, PartFile>) {
    for (name, _) in mz07_link_meshes() {
        parts.insert(
            name.clone(),
            PartFile::from_stl(format!("meshes/{name}.stl")),
        );
    }
}

/// One MZ07 of a document: its link components (named `<name>_base`, `<name>_link1`…)
/// and its robot entry, placed at `base`, with dimensions `D1@<feature>n`.
fn mz07_robot(
    name: &str,
    base: [[f64; 4]; 4],
    feature: &str,
    color: &str,
) -> (Vec<ComponentFile>, RobotFile) {
    let robot = crate::kinematics::Catalog::NachiMz07.robot();
    let mut components = Vec::new();
    let mut links = Vec::new();
    for (i, (part, _)) in mz07_link_meshes().into_iter().enumerate() {
        let comp = format!("{name}_{}", part.trim_start_matches("mz07_"));
        components.push(ComponentFile {
            transform: Some(base),
            ..component(&comp, &part, i == 0, color, Transform::IDENTITY)
        });
        links.push(LinkFile {
            component: Some(comp),
            dimension: (i > 0).then(|| format!("{feature}{i}")),
            ..LinkFile::default()
        });
    }
    let robot_file = RobotFile {
        name: name.into(),
        catalog: Some("nachi_mz07".into()),
        dh: None,
        urdf: None,
        package_path: Vec::new(),
        base: Some(base),
        tool: Some(robot.tool().to_matrix()),
        flange: None,
        tip: None,
        drawn_at_zero: true,
        links,
        joints: Some(vec![0.0; 6]),
    };
    (components, robot_file)
}

/// `models/mz07.yaml`: one NACHI MZ07 at the origin, its links driven by the
/// dimensions `D1@角度1` … `D1@角度6` (seed 000 §3.3), tool point 436.9 mm below the
/// flange.
pub fn mz07_document() -> DocumentFile {
    let mut parts = IndexMap::new();
    mz07_parts(&mut parts);
    let (components, robot) =
        mz07_robot("mz07", Transform::IDENTITY.to_matrix(), "角度", "#e8b020");
    robot_document(
        "NACHI MZ07 (seed 000 table 2): joints driven by D1@角度1..6, degrees",
        parts,
        components,
        robot,
    )
}

/// A document of `parts` and `components` with one robot and no mates.
fn robot_document(
    description: &str,
    parts: IndexMap<String, PartFile>,
    components: Vec<ComponentFile>,
    robot: RobotFile,
) -> DocumentFile {
    DocumentFile {
        units: "mm".into(),
        description: Some(description.into()),
        mesh_deflection: None,
        parts,
        components,
        mates: vec![],
        robots: vec![robot],
        equations: Vec::new(),
        assemblies: Vec::new(),
    }
}

/// `models/cell_robots.yaml`: the demo cell of [`cell_document`] with two MZ07 arms on
/// pedestals on either side of the table (seed 000's demo has two arms): `mz07_a` at
/// (600, −350) facing +Y, `mz07_b` at (600, 1150) facing −Y; dimensions `D1@a角度n`,
/// `D1@b角度n`. The pedestals are marked `fixture: true` (not part of the product);
/// the table and what is on it are the product a sequence is planned for.
pub fn cell_robots_document() -> DocumentFile {
    let mut doc = cell_document();
    doc.description = Some("Seed 000 demo cell with two NACHI MZ07 arms beside the table".into());
    mz07_parts(&mut doc.parts);
    doc.parts
        .insert("pedestal".into(), PartFile::from_stl("meshes/pedestal.stl"));
    for (name, y, s, feature, color) in [
        ("mz07_a", -350.0, 1.0, "a角度", "#e8b020"),
        ("mz07_b", 1150.0, -1.0, "b角度", "#d06020"),
    ] {
        let at = Vec3::new(600.0, y, 0.0);
        // The pedestals carry the arms, not the product: marked `fixture: true` so
        // `fitup plan-sequence` leaves them out with its defaults (they touch nothing
        // of the product, and support checking would refuse them). The table stays
        // in: the plates sit on it, it is the base the sequence starts from.
        doc.components.push(ComponentFile {
            fixture: true,
            ..component(
                &format!("{name}_pedestal"),
                "pedestal",
                true,
                "#606060",
                Transform::from_translation(at),
            )
        });
        // Turned ±90° about Z (written exactly, so the file holds clean 0s and 1s).
        let base = [
            [0.0, s, 0.0, 0.0],
            [-s, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [at.x, at.y, PEDESTAL_HEIGHT, 1.0],
        ];
        let (components, robot) = mz07_robot(name, base, feature, color);
        doc.components.extend(components);
        doc.robots.push(robot);
    }
    doc
}

/// The pedestal under each arm of the robot cell: 300 × 300 mm, [`PEDESTAL_HEIGHT`]
/// high, centred on its origin.
pub fn pedestal_mesh() -> Mesh {
    Mesh::cuboid(
        Point3::new(-150.0, -150.0, 0.0),
        Point3::new(150.0, 150.0, PEDESTAL_HEIGHT),
    )
}

/// Writes `dir/mz07.yaml`, `dir/cell_robots.yaml` and their meshes (the cell's meshes
/// too, through [`write_cell`]).
pub fn write_robots(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    write_cell(dir)?;
    for (name, mesh) in mz07_link_meshes() {
        write_stl(&dir.join(format!("meshes/{name}.stl")), &mesh)?;
    }
    write_stl(&dir.join("meshes/pedestal.stl"), &pedestal_mesh())?;
    for (file, doc) in [
        ("mz07.yaml", mz07_document()),
        ("cell_robots.yaml", cell_robots_document()),
    ] {
        crate::fsutil::write_atomic(&dir.join(file), doc.to_yaml()?.as_bytes())?;
    }
    Ok(())
}

/// The link meshes of `models/urdf/fitup_arm6.urdf` (file stem, mesh), in **metres**
/// as URDF meshes are (the URDF's default scale 1 makes them mm on import), each in
/// its link frame except `link_2`, whose visual origin lifts it 0.05 m.
pub fn arm6_link_meshes() -> Vec<(&'static str, Mesh)> {
    let m = |x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64| {
        Mesh::cuboid(Point3::new(x0, y0, z0), Point3::new(x1, y1, z1))
    };
    vec![
        ("base_link", m(-0.15, -0.15, 0.0, 0.15, 0.15, 0.40)),
        ("link_1", m(-0.10, -0.10, 0.0, 0.20, 0.10, 0.04)),
        ("link_2", Mesh::cylinder(0.06, 0.5, 24)),
        ("link_3", m(-0.06, -0.06, 0.0, 0.06, 0.06, 0.10)),
        ("link_4", m(0.08, -0.05, -0.05, 0.50, 0.05, 0.05)),
        ("link_5", m(0.0, -0.04, -0.04, 0.08, 0.04, 0.04)),
        ("link_6", m(0.0, -0.04, -0.04, 0.02, 0.04, 0.04)),
    ]
}

/// Writes `urdf/meshes/<link>.stl` for [`arm6_link_meshes`] under `dir` (the meshes
/// `models/urdf/fitup_arm6.urdf` names through `package://`) and `urdf/obstacle.stl`
/// (a 200 mm cube, mm).
pub fn write_arm6_meshes(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir.join("urdf/meshes"))?;
    for (name, mesh) in arm6_link_meshes() {
        write_stl(&dir.join(format!("urdf/meshes/{name}.stl")), &mesh)?;
    }
    // The obstacle of `models/urdf/arm6_cell.yaml`: a document part, so in mm.
    let obstacle = Mesh::cuboid(Point3::origin(), Point3::new(200.0, 200.0, 200.0));
    write_stl(&dir.join("urdf/obstacle.stl"), &obstacle)?;
    Ok(())
}

/// Boxes `(min, max)` (mm) as one mesh of closed shells.
fn boxes(list: &[([f64; 3], [f64; 3])]) -> Mesh {
    let mut m = Mesh::cuboid(Point3::from(list[0].0), Point3::from(list[0].1));
    for (lo, hi) in &list[1..] {
        m.append(&Mesh::cuboid(Point3::from(*lo), Point3::from(*hi)));
    }
    m
}

/// Where the fixtures of the precision manipulator's rotary table hold the wheel's
/// gear and cup (work frame, mm): pads 1 mm high, 15 mm either side of the seat of
/// the axis at the centre.
pub const MICRO_FIXTURES: [(&str, [f64; 3]); 3] = [
    ("axis", [0.0, 0.0, 1.0]),
    ("gear", [15.0, 0.0, 1.0]),
    ("cup", [-15.0, 0.0, 1.0]),
];

/// The meshes of `models/micro_cell.yaml` (part name, mesh), drawn in the world
/// frame at joints 0 (`drawn_at_zero`): the base slab, the two table carriages,
/// the rotary table with its three fixture pads, the probe stage's three slides,
/// the probes' hub and the two probes (needles 0.6 mm square whose tips end 0.5 mm
/// below the grasp point, at z = [`PROBE_HEIGHT`](crate::kinematics::PROBE_HEIGHT)),
/// and the frame (column and beam) that carries the probe stage.
pub fn micro_meshes() -> Vec<(&'static str, Mesh)> {
    let h = crate::kinematics::PROBE_HEIGHT;
    let mut table = Mesh::cylinder(30.0, 10.0, 48)
        .transformed(&Transform::from_translation(Vec3::new(0.0, 0.0, -10.0)));
    for (_, [x, y, z]) in MICRO_FIXTURES {
        table.append(&Mesh::cuboid(
            Point3::new(x - 4.0, y - 4.0, 0.0),
            Point3::new(x + 4.0, y + 4.0, z),
        ));
    }
    vec![
        (
            "micro_base",
            boxes(&[([-120.0, -100.0, -40.0], [120.0, 100.0, -30.0])]),
        ),
        (
            "micro_table_x",
            boxes(&[([-60.0, -25.0, -30.0], [60.0, 25.0, -20.0])]),
        ),
        (
            "micro_table_y",
            boxes(&[([-25.0, -60.0, -20.0], [25.0, 60.0, -10.0])]),
        ),
        ("micro_table_c", table),
        (
            "micro_probe_x",
            boxes(&[([-15.0, 20.0, 30.0], [15.0, 50.0, 36.0])]),
        ),
        (
            "micro_probe_y",
            boxes(&[([-8.0, 14.0, 26.0], [8.0, 22.0, 30.0])]),
        ),
        (
            "micro_probe_z",
            boxes(&[([-4.0, 8.0, 12.0], [4.0, 16.0, 26.0])]),
        ),
        (
            "micro_probe_r",
            boxes(&[
                ([-7.0, -0.5, h + 4.5], [7.0, 0.5, h + 5.5]),
                // Overlapping the bar (no shared vertices or faces: one closed shell
                // each, watertight).
                ([-1.0, 0.2, h + 4.6], [1.0, 8.0, h + 5.4]),
            ]),
        ),
        (
            "micro_finger_a",
            boxes(&[([-0.6, -0.3, h - 0.5], [0.0, 0.3, h + 4.5])]),
        ),
        (
            "micro_finger_b",
            boxes(&[([0.0, -0.3, h - 0.5], [0.6, 0.3, h + 4.5])]),
        ),
        (
            "micro_frame",
            boxes(&[
                ([-18.0, 122.0, -30.0], [18.0, 133.0, 40.0]),
                ([-20.0, 40.0, 37.0], [20.0, 135.0, 43.0]),
            ]),
        ),
    ]
}

/// `models/micro_cell.yaml`: seed 003's two-finger precision manipulator (the
/// catalog's `precision_2finger`, robot `micro`) on its base, each link displayed by
/// a component `micro_<link>`, and the frame that carries the probe stage (a fixed
/// component, not a link: the simulator checks the machine against it).
pub fn micro_cell_document() -> DocumentFile {
    let mut parts = IndexMap::new();
    let mut components = Vec::new();
    let mut links = Vec::new();
    for (name, _) in micro_meshes() {
        parts.insert(
            name.to_string(),
            PartFile::from_stl(format!("meshes/{name}.stl")),
        );
        let color = match name {
            "micro_frame" | "micro_base" => "#707070",
            "micro_finger_a" | "micro_finger_b" => "#d04040",
            n if n.starts_with("micro_table") => "#3070b0",
            _ => "#c0a030",
        };
        components.push(component(
            name,
            name,
            matches!(name, "micro_frame" | "micro_base"),
            color,
            Transform::IDENTITY,
        ));
        if name != "micro_frame" {
            links.push(LinkFile {
                component: Some(name.to_string()),
                ..LinkFile::default()
            });
        }
    }
    let robot = RobotFile {
        name: "micro".into(),
        catalog: Some(crate::kinematics::PRECISION_NAME.into()),
        dh: None,
        urdf: None,
        package_path: Vec::new(),
        base: Some(Transform::IDENTITY.to_matrix()),
        tool: None,
        flange: None,
        tip: None,
        drawn_at_zero: true,
        links,
        joints: Some(vec![0.0; 9]),
    };
    robot_document(
        "Seed 003 section 4.1: two-finger precision manipulator. XY table (±50 mm) with a rotary table (±720°), probe stage (±3 mm in X and Y, ±10 mm in Z), two probes turning about their closing axis (±100°), each tip 0 to 6 mm from the grasp point. Joints: probe_x, probe_y, probe_z, probe_r, table_x, table_y, table_c, finger_a, finger_b (mm, degrees). Generated by fitup::demo::write_micro.",
        parts,
        components,
        robot,
    )
}

/// Writes `dir/micro_cell.yaml` and its meshes (atomically).
pub fn write_micro(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir.join("meshes"))?;
    for (name, mesh) in micro_meshes() {
        write_stl(&dir.join(format!("meshes/{name}.stl")), &mesh)?;
    }
    let text = micro_cell_document().to_yaml()?;
    crate::fsutil::write_atomic(&dir.join("micro_cell.yaml"), text.as_bytes())?;
    Ok(())
}
