//! OBJ, PLY and glTF/GLB part meshes read like STL (same mesh, same checks, cached the
//! same way), `fitup export` writes a GLB that an independent reader (the `gltf`
//! crate) finds the document in, and URDFs from real robots: a gripper's mimic finger
//! follows its leader and does not steal the flange, `.dae` visuals fall back to STL
//! collision meshes, primitives are meshed. Every file is generated here.

use crate::common;
use fitup::document::Document;
use fitup::kinematics::parse_urdf;
use fitup::math::{Point3, Transform, Vec3};
use fitup::mesh::{glb_bytes, write_stl, GlbNode, Mesh, MeshCache, GLB_ROOT, Z_UP_TO_Y_UP};
use std::f64::consts::PI;
use std::path::Path;

/// A box 20 × 10 × 5 mm from the origin: the part every format holds.
fn block() -> Mesh {
    Mesh::cuboid(Point3::origin(), Point3::new(20.0, 10.0, 5.0))
}

fn obj_text(m: &Mesh) -> String {
    let mut s = String::from("# block\no block\n");
    for v in &m.vertices {
        s += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for t in &m.triangles {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

fn ply_bytes(m: &Mesh, binary: bool) -> Vec<u8> {
    let format = if binary {
        "binary_little_endian"
    } else {
        "ascii"
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        m.vertices.len(),
        m.triangles.len()
    )
    .into_bytes();
    for v in &m.vertices {
        if binary {
            for c in [v.x, v.y, v.z] {
                out.extend(c.to_le_bytes());
            }
        } else {
            out.extend(format!("{} {} {}\n", v.x, v.y, v.z).bytes());
        }
    }
    for t in &m.triangles {
        if binary {
            out.push(3);
            for i in t {
                out.extend(i.to_le_bytes());
            }
        } else {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        }
    }
    out
}

/// The GLB of `m` split into its JSON and binary chunk (for a `.gltf` + `.bin`).
pub(crate) fn gltf_parts(m: &Mesh) -> (serde_json::Value, Vec<u8>) {
    let glb = glb_bytes(&[GlbNode {
        name: "block",
        mesh: m,
        pose: Transform::IDENTITY,
    }])
    .unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = glb[20 + json_len + 8..].to_vec();
    (json, bin)
}

/// A project folder with the block in every format and a document using each.
fn formats_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    let m = block();
    write_stl(&p.join("block.stl"), &m).unwrap();
    std::fs::write(p.join("block.obj"), obj_text(&m)).unwrap();
    std::fs::write(p.join("ascii.ply"), ply_bytes(&m, false)).unwrap();
    std::fs::write(p.join("binary.ply"), ply_bytes(&m, true)).unwrap();
    let glb = glb_bytes(&[GlbNode {
        name: "block",
        mesh: &m,
        pose: Transform::IDENTITY,
    }])
    .unwrap();
    std::fs::write(p.join("block.glb"), &glb).unwrap();
    // .gltf with an external buffer in a subfolder, and one with a data: URI.
    let (mut json, bin) = gltf_parts(&m);
    std::fs::create_dir(p.join("buffers")).unwrap();
    std::fs::write(p.join("buffers/block%.bin"), &bin).unwrap();
    json["buffers"][0]["uri"] = "buffers/block%25.bin".into();
    std::fs::write(
        p.join("external.gltf"),
        serde_json::to_vec_pretty(&json).unwrap(),
    )
    .unwrap();
    json["buffers"][0]["uri"] =
        format!("data:application/octet-stream;base64,{}", base64(&bin)).into();
    std::fs::write(p.join("embedded.gltf"), serde_json::to_vec(&json).unwrap()).unwrap();
    let names = [
        "block.stl",
        "block.obj",
        "ascii.ply",
        "binary.ply",
        "block.glb",
        "external.gltf",
        "embedded.gltf",
    ];
    let mut yaml = String::from("parts:\n");
    for (i, n) in names.iter().enumerate() {
        yaml += &format!("  p{i}:\n    stl: {n}\n");
    }
    yaml += "components:\n";
    for i in 0..names.len() {
        yaml += &format!("  - name: c{i}\n    part: p{i}\n    transform: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[{},0,0,1]]\n", 100 * i);
    }
    std::fs::write(p.join("cell.yaml"), yaml).unwrap();
    dir
}

fn base64(b: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in b.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Every format gives the STL's mesh: same closed solid, volume, bounds (glTF in
/// metres comes back in mm), checked by `fitup check` too.
#[test]
fn obj_ply_and_gltf_parts_load_as_the_same_solid() {
    let dir = formats_project();
    let doc = Document::open(&dir.path().join("cell.yaml")).unwrap();
    let reference = doc.part("p0").unwrap().mesh.clone();
    assert_eq!(doc.parts().count(), 7);
    for p in doc.parts() {
        let m = &p.mesh;
        assert!(m.inspect().is_watertight(), "{}: {:?}", p.stl, m.inspect());
        assert_eq!(m.triangles.len(), 12, "{}", p.stl);
        assert_eq!(m.vertices.len(), 8, "{}", p.stl);
        assert!(
            (m.signed_volume() - 1000.0).abs() < 1e-3,
            "{}: {}",
            p.stl,
            m.signed_volume()
        );
        let (a, b) = (m.bounds().unwrap(), reference.bounds().unwrap());
        assert!(
            (a.lo - b.lo).norm() < 1e-5 && (a.hi - b.hi).norm() < 1e-5,
            "{}: {a:?}",
            p.stl
        );
    }
    let o = common::run_in(dir.path(), &["check", "cell.yaml"]);
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(
        !common::text(&o).contains("not watertight"),
        "{}",
        common::text(&o)
    );
}

/// The cache keys every format by canonical path and stamp: a second lookup parses
/// nothing; a rewritten `.bin` buffer of a `.gltf` is seen (its stamp is tracked).
#[test]
fn the_mesh_cache_keys_every_format_like_stl() {
    let dir = formats_project();
    let p = dir.path();
    let files: Vec<_> = ["block.obj", "ascii.ply", "block.glb", "external.gltf"]
        .iter()
        .map(|f| p.join(f))
        .collect();
    let mut cache = MeshCache::new();
    for f in &files {
        cache.get(f).unwrap();
    }
    assert_eq!(cache.parse_count(), 4);
    for f in &files {
        cache.get(f).unwrap();
    }
    assert_eq!(
        cache.parse_count(),
        4,
        "unchanged files are not parsed again"
    );
    // A bigger block in the buffer file: the .gltf's own bytes are unchanged.
    std::thread::sleep(std::time::Duration::from_millis(20));
    let big = Mesh::cuboid(Point3::origin(), Point3::new(40.0, 10.0, 5.0));
    let (_, bin) = gltf_parts(&big);
    std::fs::write(p.join("buffers/block%.bin"), &bin).unwrap();
    let m = cache.get(&files[3]).unwrap();
    assert_eq!(cache.parse_count(), 5);
    assert!((m.bounds().unwrap().hi.x - 40.0).abs() < 1e-5);
}

/// A buffer URI leading out of the glTF's folder is refused, naming the buffer.
#[test]
fn a_gltf_buffer_outside_its_folder_is_refused() {
    let dir = formats_project();
    let p = dir.path();
    std::fs::create_dir(p.join("sub")).unwrap();
    let (mut json, _) = gltf_parts(&block());
    json["buffers"][0]["uri"] = "../buffers/block%25.bin".into();
    std::fs::write(
        p.join("sub/escape.gltf"),
        serde_json::to_vec(&json).unwrap(),
    )
    .unwrap();
    let e = fitup::mesh::read_mesh_file(&p.join("sub/escape.gltf"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("escape.gltf") && e.contains("buffers[0]") && e.contains("`..`"),
        "{e}"
    );
}

/// A cell of two parts and three components (one turned, one lifted) exported by
/// `fitup export`, read back with the `gltf` crate: the root turns +Z up into +Y up,
/// one child node per component with its name and its pose (translation in metres),
/// meshes shared per part with the part's vertex count and positions in metres.
#[test]
fn export_writes_a_glb_with_the_documents_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    write_stl(&p.join("block.stl"), &block()).unwrap();
    write_stl(&p.join("pin.stl"), &Mesh::cylinder(3.0, 30.0, 24)).unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        [
            "parts:\n  block:\n    stl: block.stl\n  pin:\n    stl: pin.stl\ncomponents:\n",
            "  - name: base\n    part: block\n    fixed: true\n",
            "  - name: lid\n    part: block\n    transform: [[0,1,0,0],[-1,0,0,0],[0,0,1,0],[5,40,5,1]]\n",
            "  - name: pin ½\n    part: pin\n    transform: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[10,5,250,1]]\n",
        ]
        .concat(),
    )
    .unwrap();
    let o = common::run_in(p, &["export", "cell.yaml", "cell.glb"]);
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(
        common::text(&o).contains("3 nodes, 2 meshes"),
        "{}",
        common::text(&o)
    );
    let doc = Document::open(&p.join("cell.yaml")).unwrap();
    let bytes = std::fs::read(p.join("cell.glb")).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.clone().unwrap();
    let scene = g.document.default_scene().unwrap();
    let roots: Vec<_> = scene.nodes().collect();
    assert_eq!(roots.len(), 1);
    assert_eq!(roots[0].name(), Some(GLB_ROOT));
    let root_m = roots[0].transform().matrix();
    for c in 0..4 {
        for r in 0..4 {
            assert_eq!(root_m[c][r] as f64, Z_UP_TO_Y_UP[4 * c + r]);
        }
    }
    let children: Vec<_> = roots[0].children().collect();
    assert_eq!(children.len(), doc.components().len());
    assert_eq!(g.document.meshes().len(), 2, "one mesh per part");
    for (node, (i, c)) in children.iter().zip(doc.components().iter().enumerate()) {
        assert_eq!(node.name(), Some(c.name.as_str()));
        let m = node.transform().matrix();
        let expected = c.transform.isometry().to_homogeneous();
        for col in 0..4 {
            for row in 0..4 {
                let want = expected[(row, col)] / if col == 3 && row < 3 { 1000.0 } else { 1.0 };
                assert!(
                    (m[col][row] as f64 - want).abs() < 1e-6,
                    "{}: [{col}][{row}] {} vs {want}",
                    c.name,
                    m[col][row]
                );
            }
        }
        let mesh = node.mesh().unwrap();
        let prim = mesh.primitives().next().unwrap();
        let pos = prim.get(&gltf::Semantic::Positions).unwrap();
        let part = doc.mesh_of(i);
        assert_eq!(pos.count(), part.vertices.len(), "{}", c.name);
        assert_eq!(prim.indices().unwrap().count(), 3 * part.triangles.len());
        // The first vertex, in metres.
        let view = pos.view().unwrap();
        let at = view.offset() + pos.offset();
        let f = |k: usize| {
            f32::from_le_bytes(blob[at + 4 * k..at + 4 * k + 4].try_into().unwrap()) as f64
        };
        let v = part.vertices[0];
        assert!((Vec3::new(f(0), f(1), f(2)) - v.coords / 1000.0).norm() < 1e-7);
    }
    // Read back as a part: the cell as placed, in mm (the root's turn undone).
    let back = fitup::mesh::read_mesh_file(&p.join("cell.glb")).unwrap();
    let b = back.bounds().unwrap();
    let want = doc.assembly_aabb().unwrap();
    assert!(
        (b.lo - want.lo).norm() < 1e-3 && (b.hi - want.hi).norm() < 1e-3,
        "{b:?} vs {want:?}"
    );
    // Its own output is replaced; the document's STL and a file fitup did not write are
    // not (unchanged), nor is anything written for a wrong extension.
    assert!(common::run_in(p, &["export", "cell.yaml", "cell.glb"])
        .status
        .success());
    let stl = std::fs::read(p.join("block.stl")).unwrap();
    std::fs::write(p.join("theirs.glb"), b"not ours").unwrap();
    let o = common::run_in(p, &["export", "cell.yaml", "theirs.glb"]);
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    assert!(
        common::text(&o).contains("did not write"),
        "{}",
        common::text(&o)
    );
    assert_eq!(std::fs::read(p.join("theirs.glb")).unwrap(), b"not ours");
    let o = common::run_in(p, &["export", "cell.yaml", "block.stl"]);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));
    assert_eq!(std::fs::read(p.join("block.stl")).unwrap(), stl);
    // In a script: the same bytes through the run's write rule.
    std::fs::write(
        p.join("export.rhai"),
        "let doc = open_doc(\"cell.yaml\");\ndoc.export_glb(\"script.glb\");\n",
    )
    .unwrap();
    let o = common::run_in(p, &["run", "export.rhai"]);
    assert!(o.status.success(), "{}", common::text(&o));
    assert_eq!(std::fs::read(p.join("script.glb")).unwrap(), bytes);
}

/// The README's command, exactly: the demo cell exported, one node per component.
#[test]
fn readme_export_command() {
    let dir = common::project();
    let o = common::run_in(dir.path(), &["export", "models/cell.yaml", "out/cell.glb"]);
    assert!(o.status.success(), "{}", common::text(&o));
    let doc = Document::open(&dir.path().join("models/cell.yaml")).unwrap();
    let g =
        gltf::Gltf::from_slice(&std::fs::read(dir.path().join("out/cell.glb")).unwrap()).unwrap();
    let root = g.document.default_scene().unwrap().nodes().next().unwrap();
    let names: Vec<_> = root
        .children()
        .map(|n| n.name().unwrap_or("").to_string())
        .collect();
    let want: Vec<_> = doc.components().iter().map(|c| c.name.clone()).collect();
    assert_eq!(names, want);
}

/// A 6-axis OPW arm (ROS-Industrial layout) ending in `flange`, carrying a two-finger
/// gripper whose right finger mimics the left (multiplier −1, offset 1 mm), and a
/// link of each primitive. `link_1`'s visual is COLLADA, its collision mesh STL.
fn gripper_urdf() -> String {
    let j = |name: &str,
             kind: &str,
             parent: &str,
             child: &str,
             xyz: &str,
             axis: &str,
             extra: &str| {
        format!(
            "<joint name=\"{name}\" type=\"{kind}\"><origin xyz=\"{xyz}\"/><parent link=\"{parent}\"/><child link=\"{child}\"/><axis xyz=\"{axis}\"/><limit lower=\"-3\" upper=\"3\"/>{extra}</joint>\n"
        )
    };
    let mut s = String::from("<robot name=\"gripper_arm\">\n<link name=\"base_link\"><visual><geometry><box size=\"0.2 0.1 0.05\"/></geometry></visual></link>\n");
    s += "<link name=\"link_1\"><visual><geometry><mesh filename=\"package://arm/meshes/visual/link_1.dae\"/></geometry></visual><collision><geometry><mesh filename=\"package://arm/meshes/collision/link_1.stl\"/></geometry></collision></link>\n";
    s += "<link name=\"link_2\"><visual><origin xyz=\"0 0 0.3\"/><geometry><cylinder radius=\"0.04\" length=\"0.5\"/></geometry></visual></link>\n";
    s += "<link name=\"link_3\"/><link name=\"link_4\"/>\n<link name=\"link_5\"><visual><geometry><sphere radius=\"0.05\"/></geometry></visual></link>\n";
    s += "<link name=\"link_6\"/><link name=\"flange\"/><link name=\"gripper_base\"/><link name=\"finger_left\"/><link name=\"finger_right\"/>\n";
    s += &j(
        "joint_1",
        "revolute",
        "base_link",
        "link_1",
        "0 0 0.45",
        "0 0 1",
        "",
    );
    s += &j(
        "joint_2", "revolute", "link_1", "link_2", "0.15 0 0", "0 1 0", "",
    );
    s += &j(
        "joint_3", "revolute", "link_2", "link_3", "0 0 0.6", "0 1 0", "",
    );
    s += &j(
        "joint_4", "revolute", "link_3", "link_4", "0 0 0.12", "1 0 0", "",
    );
    s += &j(
        "joint_5", "revolute", "link_4", "link_5", "0.55 0 0", "0 1 0", "",
    );
    s += &j(
        "joint_6", "revolute", "link_5", "link_6", "0.1 0 0", "1 0 0", "",
    );
    s += "<joint name=\"to_flange\" type=\"fixed\"><origin xyz=\"0 0 0\" rpy=\"0 1.5707963267948966 0\"/><parent link=\"link_6\"/><child link=\"flange\"/></joint>\n";
    s += "<joint name=\"to_gripper\" type=\"fixed\"><origin xyz=\"0 0 0.05\"/><parent link=\"flange\"/><child link=\"gripper_base\"/></joint>\n";
    s += &j(
        "finger_joint",
        "prismatic",
        "gripper_base",
        "finger_left",
        "0 0.01 0.04",
        "0 1 0",
        "",
    );
    s += &j(
        "finger_mimic",
        "prismatic",
        "gripper_base",
        "finger_right",
        "0 -0.01 0.04",
        "0 1 0",
        "<mimic joint=\"finger_joint\" multiplier=\"-1\" offset=\"0.001\"/>",
    );
    s + "</robot>\n"
}

/// The mimic finger neither becomes the flange nor counts as a joint: the arm keeps 6
/// joints and the closed form; the follower moves by −1 × the leader + 1 mm.
#[test]
fn a_gripper_with_a_mimic_finger_keeps_the_arm_closed_form() {
    let u = parse_urdf(Path::new("arm.urdf"), &gripper_urdf(), None).unwrap();
    let r = &u.robot;
    let tree = r.tree();
    assert_eq!(tree.links()[r.flange()].name.as_deref(), Some("flange"));
    assert_eq!(r.dof(), 6);
    assert_eq!(r.solver_name(), "opw", "{:?}", r.analytic_rejection());
    let left = tree.find("finger_left").unwrap();
    let right = tree.find("finger_right").unwrap();
    let m = tree.mimic(right).unwrap();
    assert_eq!((m.leader, m.multiplier, m.offset), (left, -1.0, 1.0));
    // The leader is off the arm's chain: held at 0, so the follower sits at +1 mm.
    let home = r.link_poses(&[0.0; 6]).unwrap();
    let base = home[tree.find("gripper_base").unwrap()];
    let y = |p: &Transform| (*p * base.inverse()).translation().y;
    assert!(
        (y(&home[right]) - (-10.0 + 1.0)).abs() < 1e-9,
        "{}",
        y(&home[right])
    );
    // Driven through the tree: the leader at 7 mm puts the follower at −7 + 1 mm.
    let mut values = vec![0.0; tree.len()];
    values[left] = 7.0;
    values[right] = 1234.0; // ignored: a follower takes its leader's value
    let poses = tree.link_poses(&Transform::IDENTITY, &values).unwrap();
    let rel = |i: usize| {
        (poses[i] * poses[tree.find("gripper_base").unwrap()].inverse())
            .translation()
            .y
    };
    assert!((rel(left) - 17.0).abs() < 1e-9 && (rel(right) - (-10.0 - 7.0 + 1.0)).abs() < 1e-9);
    // Naming the leader finger as the tip: 7 joints, the follower follows joint 7.
    let u = parse_urdf(Path::new("arm.urdf"), &gripper_urdf(), Some("finger_left")).unwrap();
    assert_eq!(u.robot.dof(), 7);
    let q = [0.1, 0.2, -0.3, 0.4, 0.5, 0.6, 4.0];
    let p = u.robot.link_poses(&q).unwrap();
    let t = u.robot.tree();
    let gb = p[t.find("gripper_base").unwrap()].inverse();
    assert!(
        ((p[t.find("finger_right").unwrap()] * gb).translation().y - (-10.0 - 4.0 + 1.0)).abs()
            < 1e-9
    );
    // A tip moved by a mimic joint is refused, naming it.
    let e = parse_urdf(Path::new("arm.urdf"), &gripper_urdf(), Some("finger_right")).unwrap_err();
    assert!(
        e.to_string().contains("finger_right") && e.to_string().contains("mimic"),
        "{e}"
    );
}

/// In a document: `link_1` loads from its STL collision mesh (the visual is `.dae`),
/// the box, cylinder and sphere links are meshed with their volumes, the flange is
/// `flange`, `tip:` moves it, and no warning is left.
#[test]
fn a_urdf_document_robot_loads_collision_meshes_and_primitives() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::create_dir_all(p.join("arm/urdf")).unwrap();
    std::fs::create_dir_all(p.join("arm/meshes/collision")).unwrap();
    std::fs::write(p.join("arm/urdf/arm.urdf"), gripper_urdf()).unwrap();
    // A 0.1 m cube in metres (URDF mesh units).
    write_stl(
        &p.join("arm/meshes/collision/link_1.stl"),
        &Mesh::cuboid(Point3::new(-0.05, -0.05, 0.0), Point3::new(0.05, 0.05, 0.1)),
    )
    .unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        "robots:\n- name: g\n  urdf: arm/urdf/arm.urdf\n",
    )
    .unwrap();
    let doc = Document::open(&p.join("cell.yaml")).unwrap();
    assert!(doc.warnings().is_empty(), "{:?}", doc.warnings());
    let robot = doc.robots()[0].robot();
    assert_eq!(robot.solver_name(), "opw");
    assert_eq!(
        robot.tree().links()[robot.flange()].name.as_deref(),
        Some("flange")
    );
    let volume = |c: &str| doc.mesh_of(doc.component_index(c).unwrap()).signed_volume();
    assert!(
        (volume("g:link_1") - 1e6).abs() < 1.0,
        "{}",
        volume("g:link_1")
    );
    let cases = [
        ("g:base_link", 200.0 * 100.0 * 50.0, 1e-9),
        ("g:link_2", PI * 40.0 * 40.0 * 500.0, 0.005),
        ("g:link_5", 4.0 / 3.0 * PI * 50f64.powi(3), 0.01),
    ];
    for (c, exact, tol) in cases {
        let v = volume(c);
        assert!((v - exact).abs() <= tol * exact, "{c}: {v} vs {exact}");
        assert!(
            doc.mesh_of(doc.component_index(c).unwrap())
                .inspect()
                .is_watertight(),
            "{c}"
        );
    }
    // The cylinder's visual origin lifts it 300 mm: centred at z = 300 in link_2.
    let b = doc
        .mesh_of(doc.component_index("g:link_2").unwrap())
        .bounds()
        .unwrap();
    assert!(
        (b.lo.z - 50.0).abs() < 1e-9 && (b.hi.z - 550.0).abs() < 1e-9,
        "{b:?}"
    );
    // `tip:` names the arm's last link.
    std::fs::write(
        p.join("tip.yaml"),
        "robots:\n- name: g\n  urdf: arm/urdf/arm.urdf\n  tip: link_6\n",
    )
    .unwrap();
    let doc = Document::open(&p.join("tip.yaml")).unwrap();
    let robot = doc.robots()[0].robot();
    assert_eq!(
        robot.tree().links()[robot.flange()].name.as_deref(),
        Some("link_6")
    );
    std::fs::write(
        p.join("bad_tip.yaml"),
        "robots:\n- name: g\n  urdf: arm/urdf/arm.urdf\n  tip: nowhere\n",
    )
    .unwrap();
    let e = Document::open(&p.join("bad_tip.yaml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad_tip.yaml") && e.contains("nowhere"), "{e}");
}
