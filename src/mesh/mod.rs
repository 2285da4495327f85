//! Triangle meshes of parts: reading STL, OBJ, PLY and glTF/GLB (one dispatch,
//! [`read_mesh_file`]), writing STL and GLB, STEP reading ([`step`], feature `step`),
//! validation, and the cache that keeps meshes between watch reruns.
//!
//! Coordinates are millimetres in the part frame (glTF's metres are converted, see
//! [`parse_gltf`]).
//!
//! # Examples
//!
//! A generated part, checked as a solid and written to STL and back:
//!
//! ```
//! use fitup::math::Point3;
//! use fitup::mesh::{parse_stl, write_stl, Mesh};
//!
//! let block = Mesh::cuboid(Point3::origin(), Point3::new(20.0, 10.0, 5.0));
//! assert!(block.inspect().is_watertight());
//! assert!((block.signed_volume() - 1000.0).abs() < 1e-9); // mm³, outward normals
//! let bounds = block.bounds().expect("a mesh with vertices has bounds");
//! assert_eq!(bounds.hi, Point3::new(20.0, 10.0, 5.0));
//!
//! let dir = tempfile::tempdir()?;
//! let file = dir.path().join("block.stl");
//! write_stl(&file, &block)?;
//! let back = parse_stl(&std::fs::read(&file)?)?;
//! assert_eq!(back.triangles.len(), block.triangles.len());
//! assert!((back.signed_volume() - 1000.0).abs() < 1e-3); // STL stores f32
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod cache;
mod error;
mod gltf;
mod mass;
mod obj;
mod ply;
mod shapes;
pub mod step;
#[cfg(feature = "step")]
mod step_ffi;
mod stl;

#[cfg(feature = "formats")]
pub use self::gltf::parse_gltf;
pub use self::gltf::{glb_bytes, GlbNode, GLB_ROOT, Z_UP_TO_Y_UP};
pub use cache::{MeshCache, StepMesh};
pub use error::{MeshError, MeshErrorKind};
pub use mass::{MassError, MassProperties, MassSpec};
pub use obj::parse_obj;
pub use ply::parse_ply;
pub use stl::{parse_stl, read_stl, stl_bytes, write_stl};

use std::path::{Path, PathBuf};

/// The most triangles one mesh file may hold, whatever its format. Every reader
/// counts before it stores: a header, accessor or face list that would pass the cap
/// is refused before its storage is allocated.
///
/// What the cap costs: a mesh of `n` triangles takes at most 84·n bytes once read
/// (worst case, no shared corners: 3n positions of 24 bytes and n index triples of 12;
/// a closed mesh shares corners and takes about 24·n), and reading it at most
/// [`READ_BYTES_PER_TRIANGLE`]·n more besides the file's own bytes (capped by
/// [`FileKind::Mesh`](crate::fsutil::FileKind::Mesh), 256 MiB). At the cap that is
/// under 700 MB for the reader (docs/document.md, "Mesh files", lists the measured
/// peaks per format).
pub const MAX_TRIANGLES: usize = 2_000_000;

/// The most vertices an indexed mesh file (OBJ, PLY, glTF accessors) may define: three
/// per triangle of [`MAX_TRIANGLES`] (a file that shares no corner), so that vertices
/// no face uses cannot fill the memory either.
pub const MAX_VERTICES: usize = 3 * MAX_TRIANGLES;

/// Bytes per triangle a reader may take beyond the mesh it returns (the welding table
/// and an indexed format's own vertex and face lists), at most: see [`MAX_TRIANGLES`].
pub const READ_BYTES_PER_TRIANGLE: usize = 192;

/// A mesh file format fitup reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MeshFormat {
    /// STL, ASCII or binary (`.stl`).
    Stl,
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Stanford PLY, ASCII or binary (`.ply`).
    Ply,
    /// glTF 2.0, JSON (`.gltf`) or binary (`.glb`); needs the `formats` feature.
    Gltf,
}

impl MeshFormat {
    /// The format of a file by its extension (case-insensitive), if fitup reads it.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "stl" => MeshFormat::Stl,
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply,
            "gltf" | "glb" => MeshFormat::Gltf,
            _ => return None,
        })
    }

    /// The format of `bytes` read from `path`: binary glTF by its `glTF` magic
    /// whatever the name, else by the extension; an unknown extension is an error
    /// naming the formats fitup reads.
    pub fn detect(path: &Path, bytes: &[u8]) -> Result<MeshFormat, MeshError> {
        if bytes.starts_with(b"glTF") {
            return Ok(MeshFormat::Gltf);
        }
        Self::from_path(path).ok_or_else(|| {
            let ext = path
                .extension()
                .map(|e| format!("`.{}`", e.to_string_lossy()))
                .unwrap_or_else(|| "no extension".into());
            let hint = if ext.eq_ignore_ascii_case("`.dae`") {
                " (COLLADA is not read: export STL, OBJ, PLY or glTF)"
            } else {
                ""
            };
            MeshError::new(
                MeshErrorKind::Unsupported,
                format!(
                    "{ext} is not a mesh format fitup reads{hint}: .stl, .obj, .ply, .gltf, .glb"
                ),
            )
        })
    }
}

/// Parses mesh `bytes` of `format`; `folder` is where a `.gltf` finds its buffer files
/// (`None`: only embedded buffers). Returns the mesh (mm) and the other files read.
pub fn parse_mesh(
    bytes: &[u8],
    format: MeshFormat,
    folder: Option<&Path>,
) -> Result<(Mesh, Vec<PathBuf>), MeshError> {
    parse_mesh_with(bytes, format, folder, &|f: &Path| {
        crate::fsutil::read_file(f, crate::fsutil::FileKind::Mesh)
    })
}

/// [`parse_mesh`], reading a `.gltf`'s buffer files with `read` (the mesh cache reads
/// them through the project's held root).
pub(crate) fn parse_mesh_with(
    bytes: &[u8],
    format: MeshFormat,
    folder: Option<&Path>,
    read: &dyn Fn(&Path) -> Result<Vec<u8>, crate::fsutil::ReadError>,
) -> Result<(Mesh, Vec<PathBuf>), MeshError> {
    match format {
        MeshFormat::Stl => Ok((parse_stl(bytes)?, Vec::new())),
        MeshFormat::Obj => Ok((parse_obj(bytes)?, Vec::new())),
        MeshFormat::Ply => Ok((parse_ply(bytes)?, Vec::new())),
        #[cfg(feature = "formats")]
        MeshFormat::Gltf => gltf::parse_gltf_with(bytes, folder, read),
        #[cfg(not(feature = "formats"))]
        MeshFormat::Gltf => {
            let _ = (folder, read);
            Err(MeshError::new(
                MeshErrorKind::Unsupported,
                "glTF/GLB meshes need fitup built with the `formats` feature (on by default): rebuild with `--features formats`",
            ))
        }
    }
}

/// Reads a mesh file of any format fitup reads ([`MeshFormat::detect`]), with the
/// same checks whatever the format: coordinates finite and within
/// [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE) mm, at most [`MAX_TRIANGLES`]
/// triangles, at least one with an area, errors naming the file and the line (text
/// formats) or element. A mesh that is open is read; [`Mesh::inspect`] reports it.
///
/// # Examples
/// ```
/// let mesh = fitup::mesh::read_mesh_file(std::path::Path::new("models/meshes/screw.stl")).unwrap();
/// assert!(mesh.inspect().is_watertight());
/// let b = mesh.bounds().unwrap(); // part frame, mm
/// assert!(b.hi.z - b.lo.z > 1.0);
/// ```
pub fn read_mesh_file(path: &Path) -> Result<Mesh, MeshError> {
    read_mesh_with_files(path).map(|(m, _)| m)
}

/// [`read_mesh_file`], with the other files read (a `.gltf`'s buffers).
pub(crate) fn read_mesh_with_files(path: &Path) -> Result<(Mesh, Vec<PathBuf>), MeshError> {
    if let Ok(f) = std::fs::File::open(path).and_then(|f| {
        f.metadata()?
            .is_file()
            .then_some(f)
            .ok_or_else(|| std::io::Error::other("not a file"))
    }) {
        precheck(&f, path).map_err(|e| e.in_file(path))?;
    }
    let bytes = crate::fsutil::read_file(path, crate::fsutil::FileKind::Mesh)
        .map_err(|e| MeshError::from(e).in_file(path))?;
    let format = MeshFormat::detect(path, &bytes).map_err(|e| e.in_file(path))?;
    parse_mesh(&bytes, format, path.parent()).map_err(|e| e.in_file(path))
}

/// The caps a file's first bytes already tell, checked before the file is read whole:
/// a binary STL's facet count (its size is `84 + 50·n`) and a PLY header's vertex and
/// face counts. So a 250 MB STL of 5 million facets is refused having read 84 bytes.
pub(crate) fn precheck(file: &std::fs::File, path: &Path) -> Result<(), MeshError> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileExt;
        let len = file.metadata().map(|m| m.len()).unwrap_or(0);
        let mut head = vec![0u8; 4096];
        let mut got = 0;
        while got < head.len() {
            match file.read_at(&mut head[got..], got as u64) {
                Ok(0) | Err(_) => break,
                Ok(n) => got += n,
            }
        }
        head.truncate(got);
        let format = MeshFormat::from_path(path);
        if head.len() >= 84 && format == Some(MeshFormat::Stl) {
            let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
            if 84 + 50 * n == len && n > MAX_TRIANGLES as u64 {
                return Err(MeshError::too_many(MAX_TRIANGLES, "triangles")
                    .prefixed(&format!("a binary STL of {n} facets: ")));
            }
        }
        if format == Some(MeshFormat::Ply) && head.starts_with(b"ply") {
            ply::precheck(&head)?;
        }
    }
    #[cfg(not(unix))]
    let _ = (file, path);
    Ok(())
}

/// The end of every indexed reader (OBJ, PLY): no triangles or none with an area is
/// refused (at `first_line`, the first face's line, when known); unused vertices are
/// dropped and bit-identical positions merged.
fn finish_read(
    format: &str,
    what: &str,
    vertices: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
    first_line: Option<usize>,
) -> Result<Mesh, MeshError> {
    if triangles.is_empty() {
        return Err(MeshError::new(
            MeshErrorKind::NoSurface,
            format!("the {format} has no {what}"),
        ));
    }
    let mut w = Welder::new(triangles.len());
    for t in &triangles {
        w.push(t.map(|i| vertices[i as usize]));
    }
    drop((vertices, triangles));
    let mesh = w.finish()?;
    if !mesh.has_area() {
        let message = format!(
            "all {} triangles have zero area (their corners are collinear or coincide): the mesh has no surface",
            mesh.triangles.len()
        );
        return Err(match first_line {
            Some(line) => MeshError::new(MeshErrorKind::NoSurface, message).on_line(line),
            None => MeshError::new(MeshErrorKind::NoSurface, format!("{format}: {message}")),
        });
    }
    Ok(mesh)
}

use crate::math::{Point3, Vec3};
use std::collections::HashMap;
use std::hash::{BuildHasher, Hasher};

/// The hash of the integer-keyed maps of mesh welding and edge counting (a third of
/// opening and preparing a 10k-triangle part went to SipHash): a folded 64 × 64-bit
/// multiply per word, keyed by a per-map random seed so that a crafted file cannot
/// aim keys at one bucket.
#[derive(Clone, Copy)]
struct FoldState(u64);

impl FoldState {
    fn new() -> FoldState {
        FoldState(std::collections::hash_map::RandomState::new().hash_one(0x5eed_u64))
    }
}

impl BuildHasher for FoldState {
    type Hasher = FoldHasher;
    fn build_hasher(&self) -> FoldHasher {
        FoldHasher(self.0)
    }
}

/// See [`FoldState`].
struct FoldHasher(u64);

impl Hasher for FoldHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    #[inline]
    fn write_u64(&mut self, v: u64) {
        let p = u128::from(self.0 ^ v) * 0x9e37_79b9_7f4a_7c15_u128;
        self.0 = (p as u64) ^ ((p >> 64) as u64);
    }
    #[inline]
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    #[inline]
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

/// Builds an indexed mesh triangle by triangle, merging bit-identical positions as it
/// goes: what every reader feeds, so no reader keeps a triangle soup (72 bytes per
/// triangle) besides the mesh. The table holds only 32-bit vertex numbers (about 5
/// bytes per slot; a map keyed by the coordinates took 33), hashed by the positions'
/// bits with [`FoldState`].
pub(crate) struct Welder {
    table: hashbrown::HashTable<u32>,
    hasher: FoldState,
    vertices: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
}

/// The bits a position is welded by (+0.0 and −0.0 are the same point).
#[inline]
fn weld_key(p: &Point3) -> [u64; 3] {
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

impl Welder {
    /// A welder for about `triangles` triangles (a count already checked against
    /// [`MAX_TRIANGLES`]). The triangle list and a table of one slot per triangle
    /// (a closed mesh has about half as many vertices) are reserved; pages of the
    /// reservation not yet used take no memory.
    pub(crate) fn new(triangles: usize) -> Welder {
        let triangles = triangles.min(MAX_TRIANGLES);
        Welder {
            table: hashbrown::HashTable::with_capacity(triangles),
            hasher: FoldState::new(),
            vertices: Vec::new(),
            triangles: Vec::with_capacity(triangles),
        }
    }

    /// Triangles so far.
    pub(crate) fn len(&self) -> usize {
        self.triangles.len()
    }

    /// The vertex number of `p`, merged with an equal position seen before.
    fn vertex(&mut self, p: &Point3) -> u32 {
        let key = weld_key(p);
        let hasher = self.hasher;
        let hash = |k: &[u64; 3]| {
            let mut h = hasher.build_hasher();
            for w in k {
                h.write_u64(*w);
            }
            h.finish()
        };
        let vertices = &mut self.vertices;
        match self.table.entry(
            hash(&key),
            |&i| weld_key(&vertices[i as usize]) == key,
            |&i| hash(&weld_key(&vertices[i as usize])),
        ) {
            hashbrown::hash_table::Entry::Occupied(e) => *e.get(),
            hashbrown::hash_table::Entry::Vacant(e) => {
                let i = vertices.len() as u32;
                vertices.push(*p);
                e.insert(i);
                i
            }
        }
    }

    /// Adds one triangle (the caller has checked the cap and the coordinates).
    pub(crate) fn push(&mut self, tri: [Point3; 3]) {
        let ids = [
            self.vertex(&tri[0]),
            self.vertex(&tri[1]),
            self.vertex(&tri[2]),
        ];
        self.triangles.push(ids);
    }

    /// The mesh (coordinates checked once more by [`Mesh::new`]).
    pub(crate) fn finish(self) -> Result<Mesh, MeshError> {
        drop(self.table);
        Mesh::new(self.vertices, self.triangles)
    }
}

/// An indexed triangle mesh in the part frame (mm). Triangles are counter-clockwise
/// seen from outside when the mesh is oriented (STL convention).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Vertex positions, mm.
    pub vertices: Vec<Point3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// What [`Mesh::inspect`] found about a mesh's soundness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshReport {
    /// Triangles with (near) zero area.
    pub degenerate_triangles: usize,
    /// Edges used by exactly one triangle (holes in the surface).
    pub boundary_edges: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges traversed twice in the same direction (inconsistent winding).
    pub misoriented_edges: usize,
}

impl MeshReport {
    /// A closed, consistently oriented 2-manifold: inside and outside are defined,
    /// so containment ("one part swallowed by another") can be tested.
    pub fn is_watertight(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.misoriented_edges == 0
    }
}

impl Mesh {
    /// Builds a mesh, checking indices and coordinates.
    pub fn new(vertices: Vec<Point3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if let Some(i) = vertices
            .iter()
            .position(|p| !p.coords.iter().all(|v| v.is_finite()))
        {
            return Err(MeshError::invalid(format!(
                "vertex {i} has a non-finite coordinate"
            )));
        }
        let n = vertices.len() as u32;
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
            return Err(MeshError::invalid(format!(
                "triangle {t} refers to a vertex past the {n} vertices"
            )));
        }
        Ok(Self {
            vertices,
            triangles,
        })
    }

    /// Builds an indexed mesh from triangle soup, merging bit-identical vertices (as
    /// STL stores every corner separately).
    pub fn from_triangle_soup(
        corners: impl IntoIterator<Item = [Point3; 3]>,
    ) -> Result<Self, MeshError> {
        let mut w = Welder::new(0);
        for tri in corners {
            w.push(tri);
        }
        w.finish()
    }

    /// The length areas are measured against (mm): the larger of the bounding box's
    /// diagonal and its largest coordinate magnitude, at least 1 mm (0 coordinates
    /// far from the origin lose precision, so the scale grows with them).
    pub fn area_scale(&self) -> f64 {
        self.bounds()
            .map(|b| {
                (b.hi - b.lo)
                    .norm()
                    .max(b.lo.coords.amax())
                    .max(b.hi.coords.amax())
            })
            .unwrap_or(1.0)
            .max(1.0)
    }

    /// Whether triangle `i` has an area that counts, relative to `scale`
    /// ([`Mesh::area_scale`]): twice its area above `1e-24·scale²`. The one rule for
    /// "no surface": the collision layer keeps only these triangles, and a mesh file
    /// without any is refused when it is read.
    pub fn triangle_has_area(&self, i: usize, scale: f64) -> bool {
        let t = self.triangle(i);
        (t[1] - t[0]).cross(&(t[2] - t[0])).norm() > 1e-24 * scale * scale
    }

    /// Whether any triangle has an area ([`Mesh::triangle_has_area`]).
    pub fn has_area(&self) -> bool {
        let scale = self.area_scale();
        (0..self.triangles.len()).any(|i| self.triangle_has_area(i, scale))
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Point3; 3] {
        let t = self.triangles[i];
        [
            self.vertices[t[0] as usize],
            self.vertices[t[1] as usize],
            self.vertices[t[2] as usize],
        ]
    }

    /// Axis-aligned bounds in the part frame (mm); `None` for an empty mesh.
    pub fn bounds(&self) -> Option<crate::math::Aabb> {
        if self.vertices.is_empty() {
            return None;
        }
        Some(crate::math::Aabb::around(&self.vertices))
    }

    /// Flips every triangle when the mesh is inward-oriented (negative signed volume),
    /// so a closed mesh's normals point out whatever the generator's handedness.
    pub fn orient_outward(&mut self) {
        if self.signed_volume() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Signed volume (mm³): positive for a closed outward-oriented mesh.
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|i| {
                let [a, b, c] = self.triangle(i);
                a.coords.dot(&b.coords.cross(&c.coords)) / 6.0
            })
            .sum()
    }

    /// Checks for degenerate triangles, holes, non-manifold edges and inconsistent
    /// winding. Edges are counted over the triangles with three distinct vertices: a
    /// collapsed triangle (two corners one vertex) is only counted as degenerate.
    pub fn inspect(&self) -> MeshReport {
        let mut report = MeshReport::default();
        let scale = self
            .bounds()
            .map(|b| (b.hi - b.lo).norm())
            .unwrap_or(1.0)
            .max(1e-9);
        // (forward, backward) counts
        let mut edges: HashMap<(u32, u32), (u32, u32), FoldState> =
            HashMap::with_capacity_and_hasher(3 * self.triangles.len() / 2, FoldState::new());
        for (i, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = self.triangle(i);
            if (b - a).cross(&(c - a)).norm() <= 1e-12 * scale * scale {
                report.degenerate_triangles += 1;
            }
            // A collapsed triangle (two corners one vertex: a tessellator's pole or apex
            // after welding) is a segment, no surface: its edge is not counted, so it
            // cannot make a closed mesh "non-manifold".
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                continue;
            }
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                let e = edges.entry((u.min(v), u.max(v))).or_default();
                if u < v {
                    e.0 += 1
                } else {
                    e.1 += 1
                }
            }
        }
        for &(f, b) in edges.values() {
            match f + b {
                1 => report.boundary_edges += 1,
                2 if f != 1 => report.misoriented_edges += 1,
                2 => {}
                _ => report.non_manifold_edges += 1,
            }
        }
        report
    }

    /// The mesh moved by `t` (used to bake a pose into exported geometry).
    pub fn transformed(&self, t: &crate::math::Transform) -> Mesh {
        Mesh {
            vertices: self.vertices.iter().map(|p| t.apply(p)).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// Appends another mesh (no vertex merging).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// An axis-aligned box from `min` to `max` (mm), outward oriented, 12 triangles.
    pub fn cuboid(min: Point3, max: Point3) -> Mesh {
        let v = |x: bool, y: bool, z: bool| {
            Point3::new(
                if x { max.x } else { min.x },
                if y { max.y } else { min.y },
                if z { max.z } else { min.z },
            )
        };
        let vertices = vec![
            v(false, false, false),
            v(true, false, false),
            v(true, true, false),
            v(false, true, false),
            v(false, false, true),
            v(true, false, true),
            v(true, true, true),
            v(false, true, true),
        ];
        let triangles = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        Mesh {
            vertices,
            triangles,
        }
    }

    /// A closed cylinder of `radius` and `height` (mm) along +Z from the origin, with
    /// `segments` facets around (at least 3).
    pub fn cylinder(radius: f64, height: f64, segments: usize) -> Mesh {
        Self::frustum(radius, radius, height, segments)
    }

    /// A closed truncated cone along +Z from the origin: radius `r0` at z = 0 and `r1`
    /// at z = `height` (mm).
    pub fn frustum(r0: f64, r1: f64, height: f64, segments: usize) -> Mesh {
        let n = segments.max(3);
        let mut vertices = Vec::with_capacity(2 * n + 2);
        for (r, z) in [(r0, 0.0), (r1, height)] {
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                vertices.push(Point3::new(r * a.cos(), r * a.sin(), z));
            }
        }
        vertices.push(Point3::new(0.0, 0.0, 0.0));
        vertices.push(Point3::new(0.0, 0.0, height));
        let (bc, tc) = (2 * n as u32, 2 * n as u32 + 1);
        let mut triangles = Vec::with_capacity(4 * n);
        for i in 0..n as u32 {
            let j = (i + 1) % n as u32;
            let (n32, b0, b1) = (n as u32, i, j);
            triangles.push([b0, b1, b1 + n32]);
            triangles.push([b0, b1 + n32, b0 + n32]);
            triangles.push([bc, b1, b0]);
            triangles.push([tc, b0 + n32, b1 + n32]);
        }
        Mesh {
            vertices,
            triangles,
        }
    }

    /// Unit normal of triangle `i` from its winding (zero for a degenerate one).
    pub fn triangle_normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (b - a)
            .cross(&(c - a))
            .try_normalize(0.0)
            .unwrap_or_else(Vec3::zeros)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn primitives_are_watertight_with_positive_volume() {
        let b = Mesh::cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 3.0, 4.0));
        assert!(b.inspect().is_watertight(), "{:?}", b.inspect());
        assert!((b.signed_volume() - 24.0).abs() < 1e-9);
        let c = Mesh::cylinder(5.0, 10.0, 64);
        assert!(c.inspect().is_watertight(), "{:?}", c.inspect());
        let exact = std::f64::consts::PI * 25.0 * 10.0;
        assert!(c.signed_volume() > 0.98 * exact && c.signed_volume() < exact);
    }

    #[test]
    fn inspect_finds_holes_and_flipped_faces() {
        let mut b = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        b.triangles.pop();
        assert_eq!(b.inspect().boundary_edges, 3);
        let mut b = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        b.triangles[0].swap(1, 2);
        assert!(b.inspect().misoriented_edges > 0);
    }

    /// A sphere meshed the way Open CASCADE meshes a sphere face: a (u, v) grid whose
    /// pole rows are many nodes at one point, each grid cell two triangles. Welded, the
    /// cells at the poles leave collapsed triangles (two corners one vertex); they have
    /// no surface and do not make the closed sphere non-manifold (issue 38).
    pub(crate) fn pole_sphere(r: f64, nu: usize, nv: usize) -> Mesh {
        Mesh::from_triangle_soup(pole_sphere_soup(r, nu, nv)).unwrap()
    }

    /// [`pole_sphere`]'s triangles before welding, every corner its own point.
    pub(crate) fn pole_sphere_soup(r: f64, nu: usize, nv: usize) -> Vec<[Point3; 3]> {
        use std::f64::consts::{PI, TAU};
        let node = |i: usize, j: usize| {
            let (u, v) = (
                TAU * i as f64 / nu as f64,
                -PI / 2.0 + PI * j as f64 / nv as f64,
            );
            let (x, y, z) = (r * v.cos() * u.cos(), r * v.cos() * u.sin(), r * v.sin());
            // The seam and the poles as the same bits, as a welder needs them.
            let snap = |c: f64| if c.abs() < 1e-12 * r { 0.0 } else { c };
            let i = i % nu;
            let (x, y) = if j == 0 || j == nv {
                (0.0, 0.0)
            } else {
                (x, y)
            };
            let (x, y) = if i == 0 { (r * v.cos(), 0.0) } else { (x, y) };
            Point3::new(snap(x), snap(y), snap(z))
        };
        let mut soup = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let (a, b, c, d) = (
                    node(i, j),
                    node(i + 1, j),
                    node(i + 1, j + 1),
                    node(i, j + 1),
                );
                soup.push([a, b, c]);
                soup.push([a, c, d]);
            }
        }
        soup
    }

    #[test]
    fn collapsed_pole_triangles_leave_a_sphere_closed() {
        let m = pole_sphere(10.0, 24, 12);
        let collapsed = m
            .triangles
            .iter()
            .filter(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
            .count();
        assert_eq!(collapsed, 2 * 24, "one per cell at each pole");
        let report = m.inspect();
        assert!(report.is_watertight(), "{report:?}");
        assert_eq!(report.degenerate_triangles, collapsed);
        assert!(m.signed_volume() > 0.95 * 4.0 / 3.0 * std::f64::consts::PI * 1000.0);
        // A real non-manifold edge still counts: a third triangle on a cube's edge.
        let mut b = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        let [u, v, _] = b.triangles[0];
        b.vertices.push(Point3::new(-1.0, -1.0, -1.0));
        b.triangles.push([u, v, b.vertices.len() as u32 - 1]);
        assert!(b.inspect().non_manifold_edges > 0, "{:?}", b.inspect());
    }

    #[test]
    fn soup_welding_merges_shared_corners() {
        let b = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        let soup: Vec<_> = (0..b.triangles.len()).map(|i| b.triangle(i)).collect();
        let m = Mesh::from_triangle_soup(soup).unwrap();
        assert_eq!(m.vertices.len(), 8);
        assert!(m.inspect().is_watertight());
    }

    #[test]
    fn rejects_bad_indices_and_nan() {
        assert!(Mesh::new(vec![Point3::origin()], vec![[0, 0, 1]]).is_err());
        assert!(Mesh::new(vec![Point3::new(f64::NAN, 0.0, 0.0)], vec![]).is_err());
    }
}
