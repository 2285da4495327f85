//! Round 3 of the hostile meshes: caps counted before allocation. Each case drives
//! `fitup check` on a generated file whose header, accessor or face list asks for far
//! more than the caps (glTF strip indices, a GLB instancing one mesh past the cap, a
//! binary PLY face list of 160 million items, one 100 MB ASCII PLY line, a binary STL
//! of 5 million facets, an OBJ of more vertices than the cap, a URDF of 8,000 spheres
//! on one link), and a few that must be *accepted* in bounded memory: a GLB whose
//! 16,000 nodes reuse one mesh of a million positions (decoded once, not per node),
//! and a binary STL exactly at the triangle cap with no shared corner (the cap's own
//! cost, [`AT_CAP_RSS_KB`]).
//!
//! Bounds (measured peak RSS: GNU time's `%M` or VmHWM, see
//! [`crate::hostile_bounds::run`]; not speed assertions): every refusal exits 1 with the
//! file, the line or element and the cap in its message, under [`REFUSED_RSS_KB`] (a
//! count refused from a header, under a quarter of the file's size: it was not read);
//! the user's files are byte for byte as before. The runs are killed after
//! [`HANG_BOUND`], a bound on a hang only.

use crate::common;
use std::path::Path;

/// Peak resident memory of every refusal (kB): 350 MB. The largest file here is
/// 160 MB (the PLY face list), held once while it is parsed; nothing past the caps is
/// allocated.
const REFUSED_RSS_KB: u64 = 350 * 1024;

/// Peak resident memory of reading a mesh at the triangle cap, 2,000,000 triangles
/// with no shared corner, and checking it (kB): 1 GB.
const AT_CAP_RSS_KB: u64 = 1024 * 1024;

/// When a refusal's run is taken for hung and killed: the refusals counted item by
/// item scan up to 180 MB of text (the ASCII STL), a few seconds alone but over 20 s
/// on the 2-core machine at load 8, so this is no speed bound.
const HANG_BOUND: std::time::Duration = std::time::Duration::from_secs(180);

/// The triangle cap (fitup::mesh::MAX_TRIANGLES) as the messages print it.
const CAP: &str = "more than 2000000 triangles";

/// A project folder with `name` (its bytes) as the one part of `cell.yaml`.
fn part_project(name: &str, bytes: &[u8]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::write(p.join(name), bytes).unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        format!("parts:\n  p:\n    stl: {name}\ncomponents:\n  - name: c\n    part: p\n"),
    )
    .unwrap();
    dir
}

/// `fitup check cell.yaml` in `p`, killed after [`HANG_BOUND`]: exit code, output,
/// peak RSS (kB).
fn check(p: &Path) -> (Option<i32>, String, u64) {
    let r = crate::hostile_bounds::run_within(p, &["check", "cell.yaml"], HANG_BOUND);
    (r.code, r.text, r.peak_kb)
}

/// Checks a refusal: exit 1, the needles, the memory bound, the files unchanged.
/// Returns the peak resident memory (kB).
fn refused(name: &str, bytes: &[u8], needles: &[&str]) -> u64 {
    let dir = part_project(name, bytes);
    let p = dir.path();
    let before = common::snapshot(p);
    let (code, text, peak) = check(p);
    eprintln!("{name}: peak {peak} kB ({} MB file)", bytes.len() >> 20);
    assert_eq!(code, Some(1), "{name}: {text}");
    assert!(!text.contains("panicked"), "{name}: {text}");
    assert!(text.contains("cell.yaml:3:"), "{name}: {text}");
    for n in needles {
        assert!(text.contains(n), "{name}: expected `{n}` in: {text}");
    }
    assert!(
        peak < REFUSED_RSS_KB,
        "{name}: peak {peak} kB, bound {REFUSED_RSS_KB}"
    );
    assert_eq!(common::snapshot(p), before, "{name}: user files changed");
    peak
}

/// A GLB of `json` (its buffer 0 is the binary chunk `bin`, padded to 4 bytes).
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    common::glb(json, &bin)
}

/// The JSON of one mesh: `positions` float VEC3 at the start of the binary chunk,
/// then (when `indices` > 0) that many u32 indices, primitive `mode`; `nodes` nodes
/// using it, each moved 1 m along X from the last.
fn mesh_json(positions: usize, indices: usize, mode: u32, nodes: usize) -> serde_json::Value {
    use serde_json::json;
    let pos_bytes = positions * 12;
    let mut views = vec![json!({"buffer": 0, "byteOffset": 0, "byteLength": pos_bytes})];
    let mut accessors = vec![
        json!({"bufferView": 0, "componentType": 5126, "count": positions, "type": "VEC3",
        "min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]}),
    ];
    let mut prim = json!({"attributes": {"POSITION": 0}, "mode": mode});
    if indices > 0 {
        views.push(json!({"buffer": 0, "byteOffset": pos_bytes, "byteLength": indices * 4}));
        accessors.push(
            json!({"bufferView": 1, "componentType": 5125, "count": indices, "type": "SCALAR"}),
        );
        prim["indices"] = json!(1);
    }
    let node_list: Vec<_> = (0..nodes)
        .map(|i| json!({"mesh": 0, "translation": [i as f64, 0.0, 0.0]}))
        .collect();
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes).collect::<Vec<_>>()}],
        "nodes": node_list,
        "meshes": [{"primitives": [prim]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": pos_bytes + indices * 4}],
    })
}

/// Positions of a fan of triangles in the XY plane (m), `n` of them.
fn points(n: usize) -> Vec<u8> {
    (0..n)
        .flat_map(|i| {
            let a = i as f32 * 1e-3;
            [a.cos() * 0.1, a.sin() * 0.1, (i % 3) as f32 * 1e-3]
        })
        .flat_map(f32::to_le_bytes)
        .collect()
}

#[test]
fn gltf_strips_and_instancing_are_counted_before_they_are_decoded() {
    // 20 million strip indices (80 MB) over 3 positions: 20 M − 2 triangles.
    let n = 20_000_000;
    let mut bin = points(3);
    bin.extend((0..n as u32).flat_map(|i| (i % 3).to_le_bytes()));
    refused(
        "strip.glb",
        &glb(&mesh_json(3, n, 5, 1), &bin),
        &["strip.glb", "meshes[0] primitive 0", CAP],
    );
    // 100,000 triangles (300,000 positions, 3.6 MB) placed by 30 nodes: 3 M.
    let bin = points(300_000);
    refused(
        "instanced.glb",
        &glb(&mesh_json(300_000, 0, 4, 30), &bin),
        &["instanced.glb", CAP],
    );
}

/// A GLB whose 16,000 nodes reuse one mesh of a million positions (one triangle of
/// them indexed) is read in bounded time and memory: each node costs its triangle,
/// not the million positions again (that took 40 s).
#[test]
fn a_mesh_reused_by_many_nodes_is_decoded_once() {
    let mut bin = points(1_000_000);
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let dir = part_project("reuse.glb", &glb(&mesh_json(1_000_000, 3, 4, 16_000), &bin));
    // The runner's 20 s (not [`HANG_BOUND`]): decoding the million positions once per
    // node took 40 s.
    let r = crate::hostile_bounds::run(dir.path(), &["check", "cell.yaml"]);
    let (code, text, peak) = (r.code, r.text, r.peak_kb);
    eprintln!("reuse.glb: peak {peak} kB");
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains(" 16000 triangles"), "{text}");
    assert!(peak < REFUSED_RSS_KB, "peak {peak} kB");
}

#[test]
fn ply_face_lists_and_long_lines_are_counted_before_they_are_kept() {
    // One face whose list claims 160 million uchar corners (160 MB that are there).
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint uchar vertex_indices\nend_header\n".to_vec();
    ply.extend(
        [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|f| f.to_le_bytes()),
    );
    let n: u32 = 160_000_000;
    ply.extend(n.to_le_bytes());
    ply.resize(ply.len() + n as usize, 1);
    refused(
        "list.ply",
        &ply,
        &[
            "list.ply",
            "binary PLY, face 0",
            "a list of 160000000 corners",
            CAP,
        ],
    );
    drop(ply);
    // An ASCII face of 50 million corners on one 100 MB line.
    let mut text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint uint vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n50000000".to_vec();
    for _ in 0..50_000_000 / 2 {
        text.extend(b" 0 1 2 1");
    }
    text.push(b'\n');
    refused("line.ply", &text, &["line.ply:13:", "face 0", CAP]);
    // The same line as a vertex: more values than the properties, found without
    // splitting the line into a list.
    let mut text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uint uint vertex_indices\nend_header\n0 0 0".to_vec();
    for _ in 0..50_000_000 / 2 {
        text.extend(b" 1 2");
    }
    text.push(b'\n');
    refused(
        "values.ply",
        &text,
        &["values.ply:10:", "more values on the line"],
    );
    // A header that declares more faces than the cap (the bytes are there).
    let faces = 2_100_000u64;
    let mut ply = format!("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face {faces}\nproperty list uchar uchar vertex_indices\nend_header\n").into_bytes();
    ply.extend(
        [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|f| f.to_le_bytes()),
    );
    for _ in 0..faces {
        ply.extend([3u8, 0, 1, 2]);
    }
    refused(
        "faces.ply",
        &ply,
        &["faces.ply:7:", "declares 2100000 items", CAP],
    );
}

/// A binary STL of `n` facets, none sharing a corner with another.
fn distinct_stl(n: u32) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend(n.to_le_bytes());
    for i in 0..n {
        let (x, y) = ((i % 2000) as f32, (i / 2000) as f32);
        out.extend([0u8; 12]);
        for v in [[x, y, 0.0], [x + 0.5, y, 0.25], [x, y + 0.5, 0.5]] {
            for c in v {
                out.extend(c.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

#[test]
fn stl_and_obj_counts_past_the_caps_are_refused_before_reading() {
    // 5 million facets (250 MB): refused from its 84-byte header.
    let n: u32 = 5_000_000;
    let mut stl = vec![0u8; 80];
    stl.extend(n.to_le_bytes());
    stl.resize(84 + 50 * n as usize, 0);
    let peak = refused(
        "big.stl",
        &stl,
        &["big.stl", "a binary STL of 5000000 facets", CAP],
    );
    // Refused before reading: the facets were never read in (8 MB measured).
    let quarter_kb = stl.len() as u64 / 4 / 1024;
    assert!(
        peak < quarter_kb,
        "big.stl: peak {peak} kB, a quarter of the file {quarter_kb} kB"
    );
    drop(stl);
    // An ASCII STL past the cap: counted facet by facet.
    let facet = b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
    let mut ascii = b"solid s\n".to_vec();
    for _ in 0..2_000_001 {
        ascii.extend(facet);
    }
    ascii.extend(b"endsolid s\n");
    refused("ascii.stl", &ascii, &["ascii.stl:14000008:", CAP]);
    drop(ascii);
    // More vertices than the cap (6,000,000), none used.
    let mut obj = Vec::with_capacity(50_000_000);
    for _ in 0..6_000_001 {
        obj.extend(b"v 0 0 0\n");
    }
    refused(
        "vertices.obj",
        &obj,
        &["vertices.obj:6000001:", "more than 6000000 vertices"],
    );
}

/// The cap's own cost: 2,000,000 triangles sharing no corner (6 million distinct
/// positions, the worst case for welding) are read and checked within
/// [`AT_CAP_RSS_KB`]; one more triangle is refused.
#[test]
fn a_mesh_at_the_triangle_cap_is_read_within_the_stated_memory() {
    let dir = part_project("cap.stl", &distinct_stl(2_000_000));
    // About 8 s alone on the 2-core machine (welding 6 million distinct positions);
    // bounded at 90 s for a loaded machine.
    let r = crate::hostile_bounds::run_within(
        dir.path(),
        &["check", "cell.yaml"],
        std::time::Duration::from_secs(90),
    );
    let (code, text, peak) = (r.code, r.text, r.peak_kb);
    eprintln!("cap.stl (2,000,000 distinct triangles): peak {peak} kB");
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("2000000 triangles"), "{text}");
    assert!(
        peak < AT_CAP_RSS_KB,
        "peak {peak} kB, bound {AT_CAP_RSS_KB}"
    );
    refused("over.stl", &distinct_stl(2_000_001), &["over.stl", CAP]);
}

/// A URDF of 8,000 spheres on one link (490 KB) passed 1.5 GB: the primitives are
/// counted against the cap as they are made, and refused at the sphere's line.
#[test]
fn urdf_primitives_are_counted_against_the_cap() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    let mut urdf = String::from("<robot name=\"r\">\n  <link name=\"base\"/>\n  <joint name=\"j1\" type=\"revolute\">\n    <parent link=\"base\"/><child link=\"arm\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\"/>\n  </joint>\n  <link name=\"arm\">\n");
    for i in 0..8000 {
        urdf += &format!(
            "    <visual><origin xyz=\"{} 0 0\"/><geometry><sphere radius=\"0.01\"/></geometry></visual>\n",
            i as f64 * 0.03
        );
    }
    urdf += "  </link>\n</robot>\n";
    std::fs::write(p.join("r.urdf"), &urdf).unwrap();
    std::fs::write(
        p.join("cell.yaml"),
        "robots:\n- name: r\n  urdf: r.urdf\n  joints: [0]\n",
    )
    .unwrap();
    let before = common::snapshot(p);
    let r = crate::hostile_bounds::run(p, &["check", "cell.yaml"]);
    eprintln!("8,000 spheres: peak {} kB", r.peak_kb);
    assert_eq!(r.code, Some(1), "{}", r.text);
    assert!(r.text.contains("r.urdf:"), "{}", r.text);
    assert!(r.text.contains(CAP), "{}", r.text);
    assert!(r.peak_kb < REFUSED_RSS_KB, "peak {} kB", r.peak_kb);
    assert_eq!(common::snapshot(p), before);
}

/// Peak resident memory of a document whose URDF robots reach
/// [`fitup::document::robot::MAX_URDF_TRIANGLES`] and are refused at the next link
/// mesh (kB).
const URDF_TOTAL_RSS_KB: u64 = 1024 * 1024;

/// A URDF (12 KB) whose 40 links each name one 1,000,000-triangle STL: each link's
/// mesh is a scaled, placed copy, so the document made 40 million triangles (400 links
/// of a 1.9 M-triangle STL: 16 GB in 2 min 12 s). The URDF robots of a document share
/// one count, checked before each copy: refused at the fifth link's `<mesh>` line,
/// within the stated memory; two robots naming the same URDF share the count too.
#[test]
fn urdf_link_meshes_are_counted_together_before_they_are_copied() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(p.join("fitup.toml"), "").unwrap();
    std::fs::write(p.join("big.stl"), distinct_stl(1_000_000)).unwrap();
    let mut urdf = String::from("<robot name=\"r\">\n<link name=\"l0\"/>\n");
    for j in 1..=40 {
        urdf += &format!(
            "<link name=\"l{j}\"><visual><geometry><mesh filename=\"big.stl\"/></geometry></visual></link>\n<joint name=\"j{j}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{j}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\"/></joint>\n",
            j - 1
        );
    }
    urdf += "</robot>\n";
    std::fs::write(p.join("r.urdf"), &urdf).unwrap();
    std::fs::write(p.join("cell.yaml"), "robots:\n- name: r\n  urdf: r.urdf\n").unwrap();
    let before = common::snapshot(p);
    let r = crate::hostile_bounds::run_within(
        p,
        &["check", "cell.yaml"],
        std::time::Duration::from_secs(120),
    );
    eprintln!("40 links of 1 M triangles: peak {} kB", r.peak_kb);
    assert_eq!(r.code, Some(1), "{}", r.text);
    let line = urdf.lines().position(|l| l.contains("\"l5\"")).unwrap() + 1;
    assert!(r.text.contains(&format!("r.urdf:{line}:")), "{}", r.text);
    assert!(r.text.contains("link `l5`"), "{}", r.text);
    assert!(r.text.contains("MAX_URDF_TRIANGLES"), "{}", r.text);
    assert!(r.peak_kb < URDF_TOTAL_RSS_KB, "peak {} kB", r.peak_kb);
    assert_eq!(common::snapshot(p), before);
    // Two robots of 3 links each (3 M triangles apiece): the second is refused.
    let short: String = (1..=3)
        .map(|j| {
            format!(
                "<link name=\"l{j}\"><visual><geometry><mesh filename=\"big.stl\"/></geometry></visual></link>\n<joint name=\"j{j}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{j}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\"/></joint>\n",
                j - 1
            )
        })
        .collect();
    std::fs::write(
        p.join("r3.urdf"),
        format!("<robot name=\"r\">\n<link name=\"l0\"/>\n{short}</robot>\n"),
    )
    .unwrap();
    std::fs::write(
        p.join("two.yaml"),
        "robots:\n- name: a\n  urdf: r3.urdf\n- name: b\n  urdf: r3.urdf\n",
    )
    .unwrap();
    let before = common::snapshot(p);
    let r = crate::hostile_bounds::run_within(
        p,
        &["check", "two.yaml"],
        std::time::Duration::from_secs(120),
    );
    assert_eq!(r.code, Some(1), "{}", r.text);
    assert!(
        r.text.contains("robot `b`") && r.text.contains("MAX_URDF_TRIANGLES"),
        "{}",
        r.text
    );
    assert!(r.peak_kb < URDF_TOTAL_RSS_KB, "peak {} kB", r.peak_kb);
    assert_eq!(common::snapshot(p), before);
}
