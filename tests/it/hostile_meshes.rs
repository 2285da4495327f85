//! Hostile OBJ, PLY and glTF/GLB part meshes through the real binary (`fitup check`):
//! truncated and garbage files, NaN vertices, counts in headers that promise billions
//! of items (PLY element and list counts, glTF accessor counts, GLB chunk lengths), a
//! node hierarchy that loops, more triangles than the cap.
//!
//! Bounds of every case (not speed assertions: a case far past them is broken): exit 1
//! (never an abort), within the hostile runner's 20 s bound, peak resident memory
//! (GNU time or VmHWM)
//! under [`MAX_RSS_KB`], the message names the mesh file and the line or element; the
//! user's files are byte for byte as before. Every file is generated here.

use crate::common;
use common::glb;
use fitup::math::{Point3, Transform};
use fitup::mesh::{glb_bytes, GlbNode, Mesh};
use std::path::Path;

/// Peak resident memory every case stays under (kB): 300 MB, far below what the
/// headers ask for (a 4-billion-vertex PLY is 48 GB of positions).
const MAX_RSS_KB: u64 = 300 * 1024;

/// `fitup check cell.yaml` in `dir`, bounded in time (the hostile suites' one runner,
/// [`crate::hostile_bounds::run`]): exit code, output, peak RSS (kB).
fn check(dir: &Path) -> (Option<i32>, String, u64) {
    let r = crate::hostile_bounds::run(dir, &["check", "cell.yaml"]);
    (r.code, r.text, r.peak_kb)
}

/// A GLB of the unit cube, as its JSON and binary chunk.
fn cube_glb_parts() -> (serde_json::Value, Vec<u8>) {
    let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
    let glb = glb_bytes(&[GlbNode {
        name: "cube",
        mesh: &m,
        pose: Transform::IDENTITY,
    }])
    .unwrap();
    let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    (
        serde_json::from_slice(&glb[20..20 + n]).unwrap(),
        glb[20 + n + 8..].to_vec(),
    )
}

/// A binary little-endian PLY header with `vertices` float vertices and `faces`
/// faces (uint list count), then `body`.
fn ply(vertices: u64, faces: u64, body: &[u8]) -> Vec<u8> {
    let mut out = format!("ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face {faces}\nproperty list uint uint vertex_indices\nend_header\n").into_bytes();
    out.extend(body);
    out
}

fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

fn uints(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

#[test]
fn hostile_obj_ply_and_glb_parts_get_located_errors_in_bounded_memory() {
    let tri = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let mut cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        (
            "truncated.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2".to_vec(),
            vec!["truncated.obj:4:", "at least 3 corners"],
        ),
        (
            "garbage.obj",
            vec![0xff, 0xfe, 0x00, 0x81, b'\n', 0x9c],
            vec!["garbage.obj:1:", "not UTF-8"],
        ),
        (
            "nan.obj",
            b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
            vec!["nan.obj:2:", "not finite"],
        ),
        (
            "bad_index.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n".to_vec(),
            vec!["bad_index.obj:4:", "past the 3 vertices"],
        ),
        (
            "count.ply",
            ply(4_000_000_000, 1, &tri),
            vec!["count.ply:3:", "declares 4000000000 items"],
        ),
        (
            "faces.ply",
            ply(3, 4_000_000_000, &tri),
            vec!["faces.ply:7:", "declares 4000000000 items"],
        ),
        (
            "list.ply",
            ply(
                3,
                1,
                &[tri.clone(), uints(&[4_000_000_000, 0, 1, 2])].concat(),
            ),
            vec!["list.ply", "face 0", "more than 2000000 triangles"],
        ),
        (
            "nan.ply",
            ply(
                3,
                1,
                &[
                    floats(&[f32::NAN, 0.0, 0.0]),
                    tri[12..].to_vec(),
                    uints(&[3, 0, 1, 2]),
                ]
                .concat(),
            ),
            vec!["nan.ply", "vertex 0", "not finite"],
        ),
        (
            "truncated.ply",
            ply(3, 1, &tri[..20]),
            vec!["truncated.ply:3:", "declares 3 items, but the 20 bytes"],
        ),
        (
            "cut.ply",
            ply(3, 1, &[tri.clone(), uints(&[3, 0, 1])].concat()),
            vec!["cut.ply", "face 0", "truncated"],
        ),
        (
            "garbage.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nbogus line\nend_header\n"
                .to_vec(),
            vec!["garbage.ply:5:", "unexpected `bogus`"],
        ),
        (
            "no_end.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\n".to_vec(),
            vec!["no_end.ply", "end_header"],
        ),
        (
            "garbage.glb",
            [b"glTF".as_slice(), &[7u8; 60]].concat(),
            vec!["garbage.glb", "glTF"],
        ),
    ];
    // A GLB whose JSON chunk claims 4 GB.
    let (json, bin) = cube_glb_parts();
    let mut long = glb(&json, &bin);
    long[12..16].copy_from_slice(&0xffff_fff0u32.to_le_bytes());
    cases.push(("chunk.glb", long, vec!["chunk.glb"]));
    // An accessor count of a trillion over a 96-byte buffer view.
    let mut j = json.clone();
    j["accessors"][0]["count"] = serde_json::json!(1_000_000_000_000u64);
    cases.push((
        "count.glb",
        glb(&j, &bin),
        vec!["count.glb", "accessors[0]", "larger than the data"],
    ));
    // An index count past its view, and an index past the positions.
    let mut j = json.clone();
    j["accessors"][1]["count"] = serde_json::json!(4_000_000_000u64);
    cases.push((
        "indices.glb",
        glb(&j, &bin),
        vec!["indices.glb", "accessors[1]"],
    ));
    let mut b = bin.clone();
    let at = 8 * 12; // the first index, after 8 positions
    b[at..at + 4].copy_from_slice(&999u32.to_le_bytes());
    cases.push((
        "index.glb",
        glb(&json, &b),
        vec!["index.glb", "index 999 is past the 8 positions"],
    ));
    // A NaN position.
    let mut b = bin.clone();
    b[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    cases.push((
        "nan.glb",
        glb(&json, &b),
        vec!["nan.glb", "accessors[0] element 0", "not finite"],
    ));
    // A node hierarchy that loops (the child is its own ancestor).
    let mut j = json.clone();
    j["nodes"][1]["children"] = serde_json::json!([0]);
    cases.push(("cycle.glb", glb(&j, &bin), vec!["cycle.glb", "nodes"]));
    // Half a file.
    let whole = glb(&json, &bin);
    cases.push((
        "truncated.glb",
        whole[..whole.len() / 2].to_vec(),
        vec!["truncated.glb"],
    ));
    // Invalid JSON in a .gltf: the line is named.
    cases.push((
        "bad.gltf",
        b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [,]\n}\n".to_vec(),
        vec!["bad.gltf:3:", "JSON"],
    ));
    // More triangles than the cap from one polygon line (7 million corners, 14 MB):
    // refused at the corner past the cap, not at the end of the line.
    let mut big = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf".to_vec();
    for _ in 0..7_000_000 / 3 {
        big.extend(b" 1 2 3");
    }
    big.push(b'\n');
    cases.push((
        "huge_face.obj",
        big,
        vec!["huge_face.obj:4:", "more than 2000000 triangles"],
    ));

    for (name, bytes, needles) in cases {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        std::fs::write(p.join("fitup.toml"), "").unwrap();
        std::fs::write(p.join(name), &bytes).unwrap();
        std::fs::write(
            p.join("cell.yaml"),
            format!("parts:\n  p:\n    stl: {name}\ncomponents:\n  - name: c\n    part: p\n"),
        )
        .unwrap();
        let before = common::snapshot(p);
        let (code, text, peak) = check(p);
        eprintln!("{name}: peak {peak} kB");
        assert_eq!(code, Some(1), "{name}: {text}");
        assert!(peak < MAX_RSS_KB, "{name}: peak {peak} kB");
        assert!(!text.contains("panicked"), "{name}: {text}");
        assert!(
            text.contains("cell.yaml:3:"),
            "{name}: the document line: {text}"
        );
        for n in needles {
            assert!(text.contains(n), "{name}: expected `{n}` in: {text}");
        }
        assert!(
            text.len() < 2000,
            "{name}: a short message: {} bytes",
            text.len()
        );
        assert_eq!(common::snapshot(p), before, "{name}: user files changed");
    }
}
