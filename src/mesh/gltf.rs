//! glTF 2.0: part meshes read from `.gltf`/`.glb` (feature `formats`), and binary glTF
//! (GLB) written from placed meshes (always built: it needs no crate).
//!
//! # Units and axes
//! glTF lengths are metres and its up axis is +Y; fitup's are millimetres and +Z (the
//! robots' convention, and what Z-up CAD tools such as Blender convert to and from). A
//! part read from glTF is scaled by 1000 (m → mm) and turned +Y-up → +Z-up: glTF's
//! (x, y, z) m is (1000x, −1000z, 1000y) mm in the part frame. An export writes every
//! mesh in metres (f32) and every node's matrix with its translation in metres, under
//! one root node `fitup` that turns fitup's +Z-up world into glTF's +Y-up one (−90°
//! about X), so other viewers show the cell upright and reading the export back gives
//! fitup's coordinates.

use super::{Mesh, MeshError};
use crate::math::Transform;

/// One placed mesh of a GLB export: a glTF node named `name` showing `mesh` (part
/// frame, mm) at `pose` (part frame → fitup world, mm).
#[derive(Debug, Clone, Copy)]
pub struct GlbNode<'a> {
    /// The node's name (a component's name).
    pub name: &'a str,
    /// The mesh, shared between nodes when the same `&Mesh` is passed again.
    pub mesh: &'a Mesh,
    /// Part frame → world (mm).
    pub pose: Transform,
}

/// The name of the root node of an export (see the module docs).
pub const GLB_ROOT: &str = "fitup";

/// The root node's matrix (column-major): fitup's +Z up → glTF's +Y up, a rotation of
/// −90° about X.
pub const Z_UP_TO_Y_UP: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 0.0, -1.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// A binary glTF (GLB) of `nodes`: one glTF mesh per distinct [`Mesh`] (by address),
/// positions in metres as f32, `u32` indices, one child node of [`GLB_ROOT`] per entry
/// with its name and its pose as a column-major matrix whose translation is in metres
/// (none at the identity, glTF's default). Fails only when the result would pass GLB's 4 GiB size limit.
pub fn glb_bytes(nodes: &[GlbNode]) -> Result<Vec<u8>, MeshError> {
    use serde_json::json;
    let mut bin: Vec<u8> = Vec::new();
    let mut meshes: Vec<*const Mesh> = Vec::new();
    let (mut json_meshes, mut accessors, mut views) = (vec![], vec![], vec![]);
    let mut json_nodes = vec![json!({})]; // the root, filled in below
    let mut children = Vec::new();
    for node in nodes {
        let key: *const Mesh = node.mesh;
        let mesh_index = match meshes.iter().position(|&m| m == key) {
            Some(i) => i,
            None => {
                let m = node.mesh;
                let (lo, hi) = m
                    .bounds()
                    .map(|b| (b.lo.coords / 1000.0, b.hi.coords / 1000.0))
                    .unwrap_or_default();
                let pos_at = bin.len();
                for p in &m.vertices {
                    for c in [p.x, p.y, p.z] {
                        bin.extend(((c / 1000.0) as f32).to_le_bytes());
                    }
                }
                let idx_at = bin.len();
                for t in &m.triangles {
                    for &i in t {
                        bin.extend(i.to_le_bytes());
                    }
                }
                let v = views.len();
                views.push(json!({"buffer": 0, "byteOffset": pos_at, "byteLength": idx_at - pos_at, "target": 34962}));
                views.push(json!({"buffer": 0, "byteOffset": idx_at, "byteLength": bin.len() - idx_at, "target": 34963}));
                let a = accessors.len();
                // f32 bounds of the stored values (the spec's min/max are exact).
                let f = |x: f64| (x as f32) as f64;
                accessors.push(json!({
                    "bufferView": v, "componentType": 5126, "count": m.vertices.len(), "type": "VEC3",
                    "min": [f(lo.x), f(lo.y), f(lo.z)], "max": [f(hi.x), f(hi.y), f(hi.z)],
                }));
                accessors.push(json!({
                    "bufferView": v + 1, "componentType": 5125, "count": 3 * m.triangles.len(), "type": "SCALAR",
                }));
                json_meshes.push(json!({"primitives": [{"attributes": {"POSITION": a}, "indices": a + 1, "mode": 4}]}));
                meshes.push(key);
                meshes.len() - 1
            }
        };
        let mut matrix = pose_matrix(&node.pose);
        for t in &mut matrix[12..15] {
            *t /= 1000.0;
        }
        children.push(json_nodes.len());
        // The identity is glTF's default: written out, validators flag it
        // (NODE_MATRIX_DEFAULT), so a node at the identity carries no matrix.
        let mut json_node = json!({"name": node.name, "mesh": mesh_index});
        if matrix != IDENTITY_MATRIX {
            json_node["matrix"] = json!(matrix);
        }
        json_nodes.push(json_node);
    }
    json_nodes[0] = json!({"name": GLB_ROOT, "matrix": Z_UP_TO_Y_UP, "children": children});
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("fitup ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": json_nodes,
    });
    if !json_meshes.is_empty() {
        root["meshes"] = json!(json_meshes);
        root["accessors"] = json!(accessors);
        root["bufferViews"] = json!(views);
        root["buffers"] = json!([{"byteLength": bin.len()}]);
    }
    let mut text = serde_json::to_vec(&root).map_err(|e| MeshError::invalid(e.to_string()))?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total32 = u32::try_from(total).map_err(|_| {
        MeshError::invalid(format!("{total} bytes: larger than a GLB can be (4 GiB)"))
    })?;
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(total32.to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
    }
    Ok(out)
}

/// glTF's default node matrix (column-major), which a node leaves out.
const IDENTITY_MATRIX: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// A pose as glTF's column-major 4×4 matrix (mm, as the pose is).
fn pose_matrix(t: &Transform) -> [f64; 16] {
    let m = t.isometry().to_homogeneous();
    let mut out = [0.0; 16];
    for c in 0..4 {
        for r in 0..4 {
            out[4 * c + r] = m[(r, c)];
        }
    }
    out
}

#[cfg(feature = "formats")]
pub use read::parse_gltf;
#[cfg(feature = "formats")]
pub(crate) use read::parse_gltf_with;

#[cfg(feature = "formats")]
mod read {
    use super::super::stl::{check_coordinate, short};
    use super::super::{Mesh, MeshError, MeshErrorKind, Welder, MAX_TRIANGLES};
    use crate::math::Point3;
    use gltf::accessor::{DataType, Dimensions};
    use gltf::mesh::Mode;
    use std::path::{Path, PathBuf};

    /// The most node visits of one scene traversal (a node reached twice through a
    /// shared child is visited twice): bounds a file whose hierarchy repeats a subtree
    /// at every level.
    const MAX_NODE_VISITS: usize = 1_000_000;
    /// The deepest node hierarchy followed (a cycle would be infinitely deep).
    const MAX_DEPTH: usize = 256;

    /// Parses a glTF (`.gltf` JSON or `.glb` binary, told apart by GLB's `glTF`
    /// magic) into one mesh in mm (metres × 1000): the triangles of every primitive
    /// of every node of the default scene (else the first; else every root node),
    /// placed by the node hierarchy's transforms. Buffers come from the GLB's binary
    /// chunk, `data:` URIs (base64), or files named relative to `folder` (the glTF's
    /// folder; `None`: external files are refused) that stay inside it; those files
    /// are returned too (the cache watches them). Points and lines are skipped;
    /// strips and fans become triangles; bit-identical positions are merged.
    ///
    /// Refused, naming the JSON line (`.gltf`) or the element (`meshes[i]`,
    /// `accessors[j]`): invalid JSON or glTF, a sparse accessor, a position that is
    /// not `VEC3` float or is not finite or beyond
    /// [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE) mm once placed, an accessor
    /// whose count does not fit its buffer view (checked before anything is
    /// allocated), an index past its positions, more than [`MAX_TRIANGLES`]
    /// triangles, a file without triangles or whose triangles all have zero area.
    pub fn parse_gltf(
        bytes: &[u8],
        folder: Option<&Path>,
    ) -> Result<(Mesh, Vec<PathBuf>), MeshError> {
        parse_gltf_with(bytes, folder, &|f: &Path| {
            crate::fsutil::read_file(f, crate::fsutil::FileKind::Mesh)
        })
    }

    /// [`parse_gltf`], reading buffer files with `read`.
    pub(crate) fn parse_gltf_with(
        bytes: &[u8],
        folder: Option<&Path>,
        read: &dyn Fn(&Path) -> Result<Vec<u8>, crate::fsutil::ReadError>,
    ) -> Result<(Mesh, Vec<PathBuf>), MeshError> {
        check_json_size(bytes)?;
        let gltf = gltf::Gltf::from_slice(bytes).map_err(load_error)?;
        let doc = &gltf.document;
        let mut files = Vec::new();
        let mut buffers: Vec<Vec<u8>> = Vec::new();
        let mut total: u64 = 0;
        let cap = crate::fsutil::FileKind::Mesh.max_bytes();
        for b in doc.buffers() {
            let here = format!("buffers[{}]", b.index());
            let data = match b.source() {
                gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                    MeshError::invalid(format!("{here}: no binary chunk in the file"))
                })?,
                gltf::buffer::Source::Uri(uri) => {
                    if let Some(rest) = uri.strip_prefix("data:") {
                        let (_, b64) = rest.split_once(";base64,").ok_or_else(|| {
                            MeshError::invalid(format!("{here}: a `data:` URI that is not base64"))
                        })?;
                        base64(b64).map_err(|e| e.prefixed(&format!("{here}: ")))?
                    } else {
                        let file =
                            external(folder, uri).map_err(|e| e.prefixed(&format!("{here}: ")))?;
                        let data = read(&file).map_err(|e| {
                            MeshError::new(MeshErrorKind::Read, format!("{here}: {e}"))
                        })?;
                        files.push(file);
                        data
                    }
                }
            };
            if (data.len() as u64) < b.length() as u64 {
                return Err(MeshError::invalid(format!(
                    "{here}: declares {} bytes, holds {} (truncated?)",
                    b.length(),
                    data.len()
                )));
            }
            total += data.len() as u64;
            if total > cap {
                return Err(MeshError::invalid(format!(
                    "{here}: the buffers add up to more than {cap} bytes, the limit for a mesh"
                )));
            }
            buffers.push(data);
        }
        let roots = scene_roots(doc);
        let mut mesh = Welder::new(0);
        // glTF's +Y up → fitup's +Z up: the inverse (transpose) of the export's root.
        let up = nalgebra::Matrix4::from_column_slice(&super::Z_UP_TO_Y_UP).transpose();
        let mut skipped = 0usize;
        // Two walks of the scene: the first only counts every node's triangles (and
        // checks the primitives), so a file past the cap — by instancing too — is
        // refused before one triangle is made; the second places and welds them.
        let mut counted = 0usize;
        for counting in [true, false] {
            let mut stack: Vec<(gltf::Node, nalgebra::Matrix4<f64>, usize)> =
                roots.iter().rev().map(|n| (n.clone(), up, 0)).collect();
            let mut visits = 0usize;
            while let Some((node, parent, depth)) = stack.pop() {
                visits += 1;
                if visits > MAX_NODE_VISITS || depth > MAX_DEPTH {
                    return Err(MeshError::new(
                    MeshErrorKind::TooLarge,
                    format!(
                        "nodes[{}]: the node hierarchy is deeper than {MAX_DEPTH} levels or repeats subtrees past {MAX_NODE_VISITS} visits (a cycle?)",
                        node.index()
                    ),
                ));
                }
                let local = node.transform().matrix();
                let local = nalgebra::Matrix4::from_fn(|r, c| local[c][r] as f64);
                let world = parent * local;
                if let Some(m) = node.mesh() {
                    let here = match m.name() {
                        Some(n) => format!("meshes[{}] `{}`", m.index(), short(n)),
                        None => format!("meshes[{}]", m.index()),
                    };
                    for (pi, prim) in m.primitives().enumerate() {
                        let at = |e: MeshError| e.prefixed(&format!("{here} primitive {pi}: "));
                        if !matches!(
                            prim.mode(),
                            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
                        ) {
                            skipped += usize::from(!counting);
                            continue;
                        }
                        // Only views into the buffers: nothing of the primitive is decoded
                        // or allocated, so a mesh that many nodes reuse costs each node its
                        // triangles, never its positions again.
                        let view = Primitive::new(&prim, &buffers).map_err(at)?;
                        // Counted before any triangle is made (every node's instance
                        // counts: instancing cannot pass the cap either).
                        if counting {
                            counted += view.triangles;
                            if counted > MAX_TRIANGLES {
                                return Err(at(MeshError::too_many(MAX_TRIANGLES, "triangles")));
                            }
                            continue;
                        }
                        // A mirroring transform turns the winding inside out: swap back.
                        let mirrored = world.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
                        for t in 0..view.triangles {
                            let [a, b, c] = view.triangle(t, &world).map_err(at)?;
                            mesh.push(if mirrored { [a, c, b] } else { [a, b, c] });
                        }
                    }
                }
                for c in node.children().collect::<Vec<_>>().into_iter().rev() {
                    stack.push((c, world, depth + 1));
                }
            }
        }
        if mesh.len() == 0 {
            let why = if skipped > 0 {
                format!(" ({skipped} primitives of points or lines were skipped)")
            } else {
                String::new()
            };
            return Err(MeshError::new(
                MeshErrorKind::NoSurface,
                format!("the glTF's scene has no triangles{why}"),
            ));
        }
        let mesh = mesh.finish()?;
        if !mesh.has_area() {
            return Err(MeshError::new(
                MeshErrorKind::NoSurface,
                format!(
                    "all {} triangles have zero area (their corners are collinear or coincide): the mesh has no surface",
                    mesh.triangles.len()
                ),
            ));
        }
        Ok((mesh, files))
    }

    /// The nodes a scene starts from: the default scene's, else the first scene's,
    /// else (a file without scenes) every node that is no other node's child.
    fn scene_roots(doc: &gltf::Document) -> Vec<gltf::Node<'_>> {
        match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().collect(),
            None => {
                let mut child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !child[n.index()]).collect()
            }
        }
    }

    /// One primitive's positions and corner list as views into the buffers (checked
    /// against their buffer views when made), and how many triangles it makes.
    struct Primitive<'b> {
        positions: Elements<'b>,
        /// The index accessor; `None`: the positions in order.
        indices: Option<Elements<'b>>,
        mode: Mode,
        triangles: usize,
    }

    /// The elements of one accessor: its bytes from the first element, the stride,
    /// the count, the element size and the accessor's number (for messages).
    struct Elements<'b> {
        bytes: &'b [u8],
        stride: usize,
        count: usize,
        size: usize,
        accessor: usize,
    }

    impl<'b> Primitive<'b> {
        fn new(prim: &gltf::Primitive, buffers: &'b [Vec<u8>]) -> Result<Self, MeshError> {
            let pos = prim
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| MeshError::invalid("no POSITION attribute"))?;
            if pos.data_type() != DataType::F32
                || pos.dimensions() != Dimensions::Vec3
                || pos.normalized()
            {
                return Err(MeshError::new(
                    MeshErrorKind::Unsupported,
                    format!(
                        "accessors[{}]: POSITION must be a float VEC3 (quantized positions are not supported)",
                        pos.index()
                    ),
                ));
            }
            let positions = accessor_bytes(&pos, buffers, 12)?;
            let indices = match prim.indices() {
                None => None,
                Some(a) => {
                    let size = match a.data_type() {
                        DataType::U8 => 1,
                        DataType::U16 => 2,
                        DataType::U32 => 4,
                        other => {
                            return Err(MeshError::invalid(format!(
                                "accessors[{}]: indices of type {other:?} (must be unsigned)",
                                a.index()
                            )))
                        }
                    };
                    if a.dimensions() != Dimensions::Scalar {
                        return Err(MeshError::invalid(format!(
                            "accessors[{}]: indices must be scalars",
                            a.index()
                        )));
                    }
                    Some(accessor_bytes(&a, buffers, size)?)
                }
            };
            let corners = indices.as_ref().unwrap_or(&positions).count;
            let triangles = match prim.mode() {
                Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
                _ => corners / 3,
            };
            Ok(Primitive {
                positions,
                indices,
                mode: prim.mode(),
                triangles,
            })
        }

        /// The position number of corner `k` of the corner list.
        fn corner(&self, k: usize) -> Result<usize, MeshError> {
            let Some(ix) = &self.indices else {
                return Ok(k);
            };
            let e = &ix.bytes[k * ix.stride..];
            let v = match ix.size {
                1 => u32::from(e[0]),
                2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            } as usize;
            if v >= self.positions.count {
                return Err(MeshError::new(
                    MeshErrorKind::Index,
                    format!(
                        "accessors[{}] element {k}: index {v} is past the {} positions",
                        ix.accessor, self.positions.count
                    ),
                ));
            }
            Ok(v)
        }

        /// Position `i` placed by `world` and scaled to mm, checked.
        fn point(&self, i: usize, world: &nalgebra::Matrix4<f64>) -> Result<Point3, MeshError> {
            let p = &self.positions;
            let e = &p.bytes[i * p.stride..i * p.stride + 12];
            let f = |k: usize| {
                f32::from_le_bytes([e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]]) as f64
            };
            let (x, y, z) = (f(0), f(1), f(2));
            for c in [x, y, z] {
                if !c.is_finite() {
                    return Err(MeshError::new(
                        MeshErrorKind::Coordinate,
                        format!(
                            "accessors[{}] element {i}: coordinate {c} is not finite",
                            p.accessor
                        ),
                    ));
                }
            }
            let q = world * nalgebra::Vector4::new(x, y, z, 1.0);
            let q = Point3::new(q.x * 1000.0, q.y * 1000.0, q.z * 1000.0);
            for c in q.coords.iter() {
                check_coordinate(*c).map_err(|e| {
                    e.prefixed(&format!("accessors[{}] element {i}: ", p.accessor))
                        .suffixed(" (mm, once placed)")
                })?;
            }
            Ok(q)
        }

        /// Triangle `t` (of [`Primitive::triangles`]) placed by `world`.
        fn triangle(
            &self,
            t: usize,
            world: &nalgebra::Matrix4<f64>,
        ) -> Result<[Point3; 3], MeshError> {
            let ks = match self.mode {
                Mode::TriangleStrip if t.is_multiple_of(2) => [t, t + 1, t + 2],
                Mode::TriangleStrip => [t + 1, t, t + 2],
                Mode::TriangleFan => [0, t + 1, t + 2],
                _ => [3 * t, 3 * t + 1, 3 * t + 2],
            };
            let mut out = [Point3::origin(); 3];
            for (o, k) in out.iter_mut().zip(ks) {
                *o = self.point(self.corner(k)?, world)?;
            }
            Ok(out)
        }
    }

    /// The most JSON objects (`{…}`) a glTF's JSON may hold: real files have one per
    /// node, mesh, accessor and view, thousands; a parsed object takes a few hundred
    /// bytes, so a file of millions of `{}` would take gigabytes to parse.
    const MAX_JSON_OBJECTS: usize = 1_000_000;

    /// Counts the JSON's objects (outside strings) before it is parsed: past
    /// [`MAX_JSON_OBJECTS`] the file is refused, in one pass and no allocation.
    fn check_json_size(bytes: &[u8]) -> Result<(), MeshError> {
        let json = if bytes.starts_with(b"glTF") && bytes.len() >= 20 {
            let n = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
            &bytes[20..(20usize.saturating_add(n)).min(bytes.len())]
        } else {
            bytes
        };
        let (mut objects, mut in_string, mut escaped) = (0usize, false, false);
        let mut line = 1;
        for &b in json {
            if b == b'\n' {
                line += 1;
            }
            if in_string {
                match b {
                    _ if escaped => escaped = false,
                    b'\\' => escaped = true,
                    b'"' => in_string = false,
                    _ => {}
                }
            } else if b == b'"' {
                in_string = true;
            } else if b == b'{' {
                objects += 1;
                if objects > MAX_JSON_OBJECTS {
                    return Err(MeshError::too_many(MAX_JSON_OBJECTS, "JSON objects")
                        .prefixed("the glTF JSON has ")
                        .on_line(line));
                }
            }
        }
        Ok(())
    }

    /// A load error of the `gltf` crate, located: the JSON line, or the elements
    /// validation names.
    fn load_error(e: gltf::Error) -> MeshError {
        match e {
            gltf::Error::Deserialize(j) => {
                MeshError::at(j.line().max(1), format!("not valid glTF JSON: {j}"))
            }
            gltf::Error::Validation(list) => {
                let shown: Vec<String> = list
                    .iter()
                    .take(3)
                    .map(|(path, err)| format!("{path}: {err}"))
                    .collect();
                let more = list.len().saturating_sub(3);
                let more = if more > 0 {
                    format!(" (and {more} more)")
                } else {
                    String::new()
                };
                MeshError::invalid(format!("invalid glTF: {}{more}", shown.join("; ")))
            }
            other => MeshError::invalid(format!("not a valid glTF/GLB file: {other}")),
        }
    }

    /// An external buffer file: a relative URI (percent-decoded) inside `folder`.
    fn external(folder: Option<&Path>, uri: &str) -> Result<PathBuf, MeshError> {
        let unreadable = |m: String| MeshError::new(MeshErrorKind::Read, m);
        let folder = folder.ok_or_else(|| {
            MeshError::new(
                MeshErrorKind::Unsupported,
                "external buffer files are not read here (use a .glb)",
            )
        })?;
        let decoded = percent_decode(uri)?;
        let rel = Path::new(&decoded);
        if decoded.contains("://")
            || rel.is_absolute()
            || rel.components().any(|c| {
                !matches!(
                    c,
                    std::path::Component::Normal(_) | std::path::Component::CurDir
                )
            })
        {
            return Err(unreadable(format!(
                "buffer `{}`: only files beside the glTF or below its folder are read (no absolute path, `..` or URL)",
                short(uri)
            )));
        }
        let base = folder
            .canonicalize()
            .map_err(|e| unreadable(format!("{}: {e}", folder.display())))?;
        let file = base
            .join(rel)
            .canonicalize()
            .map_err(|e| unreadable(format!("buffer `{}`: {e}", short(uri))))?;
        if !file.starts_with(&base) {
            return Err(unreadable(format!(
                "buffer `{}` leads outside the glTF's folder (a symbolic link)",
                short(uri)
            )));
        }
        Ok(file)
    }

    fn percent_decode(s: &str) -> Result<String, MeshError> {
        let b = s.as_bytes();
        let mut out = Vec::with_capacity(b.len());
        let mut i = 0;
        while i < b.len() {
            if b[i] == b'%' {
                let hex = b
                    .get(i + 1..i + 3)
                    .and_then(|h| std::str::from_utf8(h).ok())
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                    .ok_or_else(|| {
                        MeshError::invalid(format!("`{}` has a bad %-escape", short(s)))
                    })?;
                out.push(hex);
                i += 3;
            } else {
                out.push(b[i]);
                i += 1;
            }
        }
        String::from_utf8(out)
            .map_err(|_| MeshError::invalid(format!("`{}` is not UTF-8 once decoded", short(s))))
    }

    fn base64(s: &str) -> Result<Vec<u8>, MeshError> {
        let mut out = Vec::with_capacity(s.len() / 4 * 3);
        let (mut acc, mut bits) = (0u32, 0u32);
        for (k, c) in s.bytes().enumerate() {
            let v = match c {
                b'A'..=b'Z' => c - b'A',
                b'a'..=b'z' => c - b'a' + 26,
                b'0'..=b'9' => c - b'0' + 52,
                b'+' | b'-' => 62,
                b'/' | b'_' => 63,
                b'=' => break,
                _ => {
                    return Err(MeshError::invalid(format!(
                        "byte {k} of the base64 data is not base64"
                    )))
                }
            };
            acc = (acc << 6) | u32::from(v);
            bits += 6;
            if bits >= 8 {
                bits -= 8;
                out.push((acc >> bits) as u8);
            }
        }
        Ok(out)
    }

    /// The elements of `acc` (`elem` bytes each): the whole extent is checked against
    /// its view and buffer before anything is read.
    fn accessor_bytes<'b>(
        acc: &gltf::Accessor,
        buffers: &'b [Vec<u8>],
        elem: usize,
    ) -> Result<Elements<'b>, MeshError> {
        let here = format!("accessors[{}]", acc.index());
        if acc.sparse().is_some() {
            return Err(MeshError::new(
                MeshErrorKind::Unsupported,
                format!("{here}: sparse accessors are not supported"),
            ));
        }
        let view = acc
            .view()
            .ok_or_else(|| MeshError::invalid(format!("{here}: no buffer view (all zeros)")))?;
        let data = buffers
            .get(view.buffer().index())
            .ok_or_else(|| MeshError::invalid(format!("{here}: no such buffer")))?;
        let vend = view
            .offset()
            .checked_add(view.length())
            .filter(|&e| e <= data.len())
            .ok_or_else(|| {
                MeshError::invalid(format!(
                    "bufferViews[{}]: reaches past its buffer's {} bytes",
                    view.index(),
                    data.len()
                ))
            })?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(MeshError::invalid(format!(
                "{here}: stride {stride} is smaller than an element ({elem} bytes)"
            )));
        }
        let count = acc.count();
        let start = view.offset() + acc.offset();
        if count > 0 {
            let need = (count as u128 - 1) * stride as u128 + elem as u128 + start as u128;
            if need > vend as u128 {
                return Err(MeshError::invalid(format!(
                    "{here}: {count} elements need {need} bytes, its buffer view ends at {vend} (a count larger than the data)"
                )));
            }
        }
        Ok(Elements {
            bytes: &data[start.min(vend)..vend],
            stride,
            count,
            size: elem,
            accessor: acc.index(),
        })
    }
}

#[cfg(all(test, feature = "formats"))]
mod tests {
    use super::*;
    use crate::math::{Point3, Vec3};

    #[test]
    fn an_export_reads_back_in_mm_with_shared_meshes() {
        let cube = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 20.0, 30.0));
        let at = Transform::from_translation(Vec3::new(100.0, 0.0, 0.0));
        let glb = glb_bytes(&[
            GlbNode {
                name: "a",
                mesh: &cube,
                pose: Transform::IDENTITY,
            },
            GlbNode {
                name: "b",
                mesh: &cube,
                pose: at,
            },
        ])
        .unwrap();
        let g = gltf::Gltf::from_slice(&glb).unwrap();
        assert_eq!(g.document.meshes().len(), 1, "one mesh for one part");
        // The node at the identity leaves out glTF's default matrix; the other has one.
        let chunk = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + chunk]).unwrap();
        let nodes = json["nodes"].as_array().unwrap();
        let matrix = |name: &str| {
            let n = nodes.iter().find(|n| n["name"] == name).unwrap();
            n.get("matrix").cloned()
        };
        assert_eq!(matrix("a"), None);
        assert!(matrix("b").is_some());
        // Read back in fitup's frame and mm: the two boxes where they were placed.
        let (m, files) = parse_gltf(&glb, None).unwrap();
        assert!(files.is_empty());
        assert!(m.inspect().is_watertight());
        assert!(
            (m.signed_volume() - 2.0 * 6000.0).abs() < 1e-3 * 6000.0,
            "{}",
            m.signed_volume()
        );
        let b = m.bounds().unwrap();
        assert!((b.lo - Point3::origin()).norm() < 1e-4, "{b:?}");
        assert!(
            (b.hi - Point3::new(110.0, 20.0, 30.0)).norm() < 1e-4,
            "{b:?}"
        );
    }
}
