//! What Open CASCADE returns, as plain data, and the one byte format it travels in:
//! from a child reader to its parent (`child.rs`), and into the tessellation store. Decoding checks
//! every length against the bytes left before allocating, so a damaged store file or a
//! confused child is refused, never trusted.

/// One distinct solid as the shim returns it.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawPart {
    pub name: String,
    pub solid_index: u32,
    pub solids_in_product: u32,
    /// xyz per vertex, mm, face meshes side by side.
    pub vertices: Vec<f64>,
    pub triangles: Vec<u32>,
    pub exact_volume: f64,
    pub faces: u32,
    pub unmeshed_faces: u32,
    pub first_unmeshed_face: u32,
}

/// One placed solid as the shim returns it.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawInstance {
    pub name: String,
    pub path: String,
    pub part: u32,
    /// Row-major 3 × 4 `[R | t]`, mm.
    pub matrix: Vec<f64>,
    pub scale: f64,
    /// The assembly occurrence holding it: 1-based index into
    /// [`RawModel::assemblies`], 0 at the top.
    pub parent: u32,
}

/// One placed assembly as the shim returns it (listed before what it holds).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawAssembly {
    pub name: String,
    pub path: String,
    pub product: String,
    /// As [`RawInstance::parent`]; always below this assembly's own index.
    pub parent: u32,
    /// Row-major 3 × 4 `[R | t]`, mm: assembly frame → root.
    pub matrix: Vec<f64>,
    pub scale: f64,
}

/// The shim's whole answer (see `src/mesh/step_ffi.rs` for the fields' meaning), and
/// the reader's peak memory (bytes, 0 when unknown).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RawModel {
    pub parts: Vec<RawPart>,
    pub instances: Vec<RawInstance>,
    pub length_unit: String,
    pub read_s: f64,
    pub transfer_s: f64,
    pub mesh_s: f64,
    pub shells_without_solid: u32,
    pub faces_without_solid: u32,
    pub open_shells: u32,
    pub first_open_shell: String,
    pub peak_memory: u64,
    pub assemblies: Vec<RawAssembly>,
}

// ---- the byte format ---------------------------------------------------------------

#[derive(Default)]
pub(super) struct Writer(pub(super) Vec<u8>);

impl Writer {
    pub(super) fn u32(&mut self, v: u32) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn f64(&mut self, v: f64) {
        self.0.extend(v.to_le_bytes());
    }
    pub(super) fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.extend(s.as_bytes());
    }
    pub(super) fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
    }
    pub(super) fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        for x in v {
            self.u32(*x);
        }
    }
}

/// Reads the byte format from a slice or a stream (a store entry is decoded as it is
/// read, never held whole), knowing how many bytes are left: every count is checked
/// against them before anything is allocated.
pub(super) struct Reader<'a> {
    src: Box<dyn std::io::Read + 'a>,
    left: u64,
}

/// The decoder's only failure: the bytes are not a model (what is wrong).
pub(super) type Bad = &'static str;

impl<'a> Reader<'a> {
    /// A reader of `bytes`.
    pub(super) fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader {
            left: bytes.len() as u64,
            src: Box::new(bytes),
        }
    }

    /// A reader of `len` bytes from `src` (a file: buffered here).
    pub(super) fn stream(src: impl std::io::Read + 'a, len: u64) -> Reader<'a> {
        Reader {
            src: Box::new(std::io::BufReader::with_capacity(1 << 20, src)),
            left: len,
        }
    }

    /// Whether every byte was read.
    pub(super) fn is_empty(&self) -> bool {
        self.left == 0
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], Bad> {
        if self.left < N as u64 {
            return Err("truncated");
        }
        let mut b = [0u8; N];
        self.src.read_exact(&mut b).map_err(|_| "truncated")?;
        self.left -= N as u64;
        Ok(b)
    }

    pub(super) fn take(&mut self, n: usize) -> Result<Vec<u8>, Bad> {
        if self.left < n as u64 {
            return Err("truncated");
        }
        let mut b = vec![0u8; n];
        self.src.read_exact(&mut b).map_err(|_| "truncated")?;
        self.left -= n as u64;
        Ok(b)
    }
    pub(super) fn u32(&mut self) -> Result<u32, Bad> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(super) fn u64(&mut self) -> Result<u64, Bad> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub(super) fn f64(&mut self) -> Result<f64, Bad> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A count of items of `size` bytes each, checked against what is left.
    pub(super) fn count(&mut self, size: usize) -> Result<usize, Bad> {
        let n = self.u64()?;
        if n > self.left / size as u64 {
            return Err("a length past its end");
        }
        Ok(n as usize)
    }
    pub(super) fn str(&mut self) -> Result<String, Bad> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?).map_err(|_| "not UTF-8 text")
    }
    pub(super) fn f64s(&mut self) -> Result<Vec<f64>, Bad> {
        self.f64s_within(usize::MAX, "")
    }
    /// [`f64s`](Self::f64s) of at most `max` values (else `why`), counted first.
    pub(super) fn f64s_within(&mut self, max: usize, why: Bad) -> Result<Vec<f64>, Bad> {
        let n = self.count(8)?;
        if n > max {
            return Err(why);
        }
        (0..n).map(|_| self.f64()).collect()
    }
    /// [`u32s`](Self::u32s) of at most `max` values (else `why`), counted first.
    pub(super) fn u32s_within(&mut self, max: usize, why: Bad) -> Result<Vec<u32>, Bad> {
        let n = self.count(4)?;
        if n > max {
            return Err(why);
        }
        (0..n).map(|_| self.u32()).collect()
    }
}

pub(super) fn encode_model(w: &mut Writer, m: &RawModel) {
    encode_model_peak(w, m, m.peak_memory);
}

/// [`encode_model`] with `peak` written as the reader's peak memory (the store keeps
/// 0: encoded so rather than from a copy of the model).
pub(super) fn encode_model_peak(w: &mut Writer, m: &RawModel, peak: u64) {
    w.u64(m.parts.len() as u64);
    for p in &m.parts {
        w.str(&p.name);
        w.u32(p.solid_index);
        w.u32(p.solids_in_product);
        w.f64s(&p.vertices);
        w.u32s(&p.triangles);
        w.f64(p.exact_volume);
        w.u32(p.faces);
        w.u32(p.unmeshed_faces);
        w.u32(p.first_unmeshed_face);
    }
    w.u64(m.instances.len() as u64);
    for i in &m.instances {
        w.str(&i.name);
        w.str(&i.path);
        w.u32(i.part);
        w.f64s(&i.matrix);
        w.f64(i.scale);
        w.u32(i.parent);
    }
    w.str(&m.length_unit);
    w.f64(m.read_s);
    w.f64(m.transfer_s);
    w.f64(m.mesh_s);
    w.u32(m.shells_without_solid);
    w.u32(m.faces_without_solid);
    w.u32(m.open_shells);
    w.str(&m.first_open_shell);
    w.u64(peak);
    w.u64(m.assemblies.len() as u64);
    for a in &m.assemblies {
        w.str(&a.name);
        w.str(&a.path);
        w.str(&a.product);
        w.u32(a.parent);
        w.f64s(&a.matrix);
        w.f64(a.scale);
    }
}

#[cfg(test)]
pub(super) fn decode_model(r: &mut Reader) -> Result<RawModel, Bad> {
    decode_model_within(r, usize::MAX)
}

/// [`decode_model`] refusing, before it allocates them, a part of more than
/// `max_part_triangles` triangles or more than three vertices a triangle allowed (what
/// could never become one mesh: [`MAX_TRIANGLES`](crate::mesh::MAX_TRIANGLES)).
pub(super) fn decode_model_within(
    r: &mut Reader,
    max_part_triangles: usize,
) -> Result<RawModel, Bad> {
    // The smallest encoded part is 52 bytes, the smallest instance 40, the smallest
    // assembly 44.
    let n = r.count(52)?;
    let mut parts = Vec::with_capacity(n);
    let max_corners = max_part_triangles.saturating_mul(3);
    for _ in 0..n {
        let name = r.str()?;
        let solid_index = r.u32()?;
        let solids_in_product = r.u32()?;
        let vertices = r.f64s_within(
            max_corners.saturating_mul(3),
            "a part with more vertices than one mesh may hold",
        )?;
        let triangles = r.u32s_within(
            max_corners,
            "a part with more triangles than one mesh may hold",
        )?;
        if vertices.len() % 3 != 0 || triangles.len() % 3 != 0 {
            return Err("a mesh with a partial vertex or triangle");
        }
        parts.push(RawPart {
            name,
            solid_index,
            solids_in_product,
            vertices,
            triangles,
            exact_volume: r.f64()?,
            faces: r.u32()?,
            unmeshed_faces: r.u32()?,
            first_unmeshed_face: r.u32()?,
        });
    }
    let n = r.count(40)?;
    let mut instances = Vec::with_capacity(n);
    for _ in 0..n {
        instances.push(RawInstance {
            name: r.str()?,
            path: r.str()?,
            part: r.u32()?,
            matrix: r.f64s()?,
            scale: r.f64()?,
            parent: r.u32()?,
        });
    }
    let mut m = RawModel {
        parts,
        instances,
        length_unit: r.str()?,
        read_s: r.f64()?,
        transfer_s: r.f64()?,
        mesh_s: r.f64()?,
        shells_without_solid: r.u32()?,
        faces_without_solid: r.u32()?,
        open_shells: r.u32()?,
        first_open_shell: r.str()?,
        peak_memory: r.u64()?,
        assemblies: Vec::new(),
    };
    let n = r.count(44)?;
    m.assemblies.reserve_exact(n);
    for _ in 0..n {
        m.assemblies.push(RawAssembly {
            name: r.str()?,
            path: r.str()?,
            product: r.str()?,
            parent: r.u32()?,
            matrix: r.f64s()?,
            scale: r.f64()?,
        });
    }
    Ok(m)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// One part of one triangle placed once, named `name`: the tests' model (here
    /// and in the tessellation store's tests).
    pub(crate) fn sample_model(name: &str) -> RawModel {
        RawModel {
            parts: vec![RawPart {
                name: name.into(),
                solid_index: 1,
                solids_in_product: 1,
                vertices: vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.5],
                triangles: vec![0, 1, 2],
                exact_volume: 12.5,
                faces: 3,
                ..RawPart::default()
            }],
            instances: vec![RawInstance {
                name: "peg-1".into(),
                path: "cell/peg-1".into(),
                part: 0,
                matrix: (0..12).map(f64::from).collect(),
                scale: 1.0,
                parent: 1,
            }],
            assemblies: vec![RawAssembly {
                name: "cell".into(),
                path: "cell".into(),
                product: "cell".into(),
                parent: 0,
                matrix: (0..12).map(f64::from).collect(),
                scale: 1.0,
            }],
            length_unit: "MILLIMETRE".into(),
            ..RawModel::default()
        }
    }

    /// The sample with every field set, for the codec.
    fn model() -> RawModel {
        let mut m = sample_model("peg ✓");
        let p = &mut m.parts[0];
        (p.solids_in_product, p.unmeshed_faces, p.first_unmeshed_face) = (2, 1, 2);
        (m.read_s, m.first_open_shell, m.peak_memory) = (0.25, "x".into(), 7);
        m
    }

    #[test]
    fn a_model_round_trips_and_every_cut_is_refused() {
        let mut w = Writer::default();
        encode_model(&mut w, &model());
        let back = decode_model(&mut Reader::new(&w.0)).unwrap();
        assert_eq!(back, model());
        // Every truncation fails cleanly (no panic, no huge allocation).
        for n in 0..w.0.len() {
            assert!(
                decode_model(&mut Reader::new(&w.0[..n])).is_err(),
                "cut at {n}"
            );
        }
        // A count claiming 2^60 items is refused before allocating.
        let mut huge = Writer::default();
        huge.u64(1 << 60);
        assert_eq!(
            decode_model(&mut Reader::new(&huge.0)).unwrap_err(),
            "a length past its end"
        );
    }
}
