//! Stanford PLY input (ASCII, binary little- and big-endian): the `vertex` element's
//! `x y z` and the `face` element's index list, mm.
//!
//! Written by hand so that counts in the header cannot make the reader allocate: an
//! element count is checked against the bytes left before anything is reserved (a
//! binary item takes at least its fixed properties' size, an ASCII one at least one
//! byte per property), and storage grows only with what is actually read. ASCII
//! errors name the line; binary errors name the element and item.

use super::stl::{check_coordinate, short};
use super::{finish_read, MeshError, MeshErrorKind, MAX_TRIANGLES, MAX_VERTICES};
use crate::math::Point3;

/// The longest header accepted (bytes): real headers are a few hundred bytes.
const MAX_HEADER: usize = 64 << 10;

#[derive(Clone, Copy, PartialEq, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value at the start of `b` (at least `size` bytes).
    fn read(self, b: &[u8], little: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if little {
                    <$t>::from_le_bytes(a) as f64
                } else {
                    <$t>::from_be_bytes(a) as f64
                }
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => num!(i16, 2),
            Scalar::U16 => num!(u16, 2),
            Scalar::I32 => num!(i32, 4),
            Scalar::U32 => num!(u32, 4),
            Scalar::F32 => num!(f32, 4),
            Scalar::F64 => num!(f64, 8),
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar(Scalar, String),
    List(Scalar, Scalar, String),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    line: usize,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// Parses PLY bytes into a mesh (mm: PLY has no units, fitup reads them as STL's).
///
/// Needs a `vertex` element with `x`, `y` and `z` properties and a `face` element
/// with a `vertex_indices` (or `vertex_index`) list; other elements and properties
/// (normals, colours, edges, materials) are skipped; polygons are fan-triangulated,
/// bit-identical positions merged. Refused: a bad header (at its line), a count that
/// the rest of the file cannot hold, a coordinate that is not finite or beyond
/// [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE), an index past the vertices, a face
/// of fewer than 3 corners, a truncated body, more than [`MAX_TRIANGLES`] triangles;
/// a file without faces or whose faces all have zero area.
pub fn parse_ply(bytes: &[u8]) -> Result<super::Mesh, MeshError> {
    let (format, elements, body) = header(bytes)?;
    let header_lines = bytes[..body].iter().filter(|&&b| b == b'\n').count();
    let rest = &bytes[body..];
    for e in &elements {
        // Each item needs at least one byte per property (binary: its size).
        let min_item: u64 = e
            .properties
            .iter()
            .map(|p| match (format, p) {
                (Format::Ascii, _) => 2,
                (_, Property::Scalar(s, _)) => s.size() as u64,
                (_, Property::List(c, _, _)) => c.size() as u64,
            })
            .sum::<u64>()
            .max(1);
        if e.count.saturating_mul(min_item) > rest.len() as u64 {
            return Err(MeshError::at(
                e.line,
                format!(
                    "element `{}` declares {} items, but the {} bytes after the header hold at most {}",
                    short(&e.name),
                    e.count,
                    rest.len(),
                    rest.len() as u64 / min_item
                ),
            ));
        }
    }
    let vertex = elements.iter().position(|e| e.name == "vertex");
    let face = elements.iter().position(|e| e.name == "face");
    // The caps, from the header's counts, before anything is stored.
    check_counts(&elements)?;
    let (Some(vi), Some(fi)) = (vertex, face) else {
        return Err(MeshError::at(
            1,
            "a PLY mesh needs a `vertex` and a `face` element",
        ));
    };
    let xyz: Vec<usize> = ["x", "y", "z"]
        .iter()
        .map(|n| {
            elements[vi]
                .properties
                .iter()
                .position(|p| matches!(p, Property::Scalar(_, name) if name == n))
                .ok_or_else(|| {
                    MeshError::at(
                        elements[vi].line,
                        format!("the `vertex` element has no scalar `{n}` property"),
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    let indices = elements[fi]
        .properties
        .iter()
        .position(|p| {
            matches!(p, Property::List(_, _, name) if name == "vertex_indices" || name == "vertex_index")
        })
        .ok_or_else(|| {
            MeshError::at(
                elements[fi].line,
                "the `face` element has no `vertex_indices` list",
            )
        })?;
    if let Property::List(_, item, _) = &elements[fi].properties[indices] {
        if !item.is_integer() {
            return Err(MeshError::at(
                elements[fi].line,
                "the `vertex_indices` list must hold integers",
            ));
        }
    }
    let mut reader = Reader {
        format,
        bytes: rest,
        pos: 0,
        line: header_lines,
        words: "".split_ascii_whitespace(),
    };
    let mut vertices: Vec<Point3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut first_face = None;
    let mut values: Vec<f64> = Vec::new();
    for (ei, e) in elements.iter().enumerate() {
        for item in 0..e.count {
            reader
                .start_item()
                .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
            let mut coords = [0.0; 3];
            for (pi, p) in e.properties.iter().enumerate() {
                match p {
                    Property::Scalar(s, _) => {
                        let v = reader
                            .value(*s)
                            .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
                        if ei == vi {
                            if let Some(k) = xyz.iter().position(|&x| x == pi) {
                                check_coordinate(v).map_err(|m| {
                                    reader_error(format, reader.line, &e.name, item, m)
                                })?;
                                coords[k] = v;
                            }
                        }
                    }
                    Property::List(c, s, _) => {
                        let n = reader
                            .value(*c)
                            .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
                        let fail = |m: String| {
                            reader_error(format, reader.line, &e.name, item, MeshError::invalid(m))
                        };
                        if !(n >= 0.0 && n.fract() == 0.0) {
                            return Err(fail(format!("list length {n} is not a count")));
                        }
                        let keep = ei == fi && pi == indices;
                        // Checked before reading: a list cannot be longer than what
                        // is left (binary: its items' bytes; ASCII: the line's words),
                        // and a face list cannot pass the triangle cap.
                        if keep && n - 2.0 + triangles.len() as f64 > MAX_TRIANGLES as f64 {
                            let cap = MeshError::too_many(MAX_TRIANGLES, "triangles");
                            let cap = cap.prefixed(&format!("a list of {n} corners: "));
                            return Err(reader_error(format, reader.line, &e.name, item, cap));
                        }
                        if format == Format::Ascii {
                            let left = reader.words.clone().count();
                            if n > left as f64 {
                                return Err(fail(format!(
                                    "a list of {n} items, but the line has {left} values left"
                                )));
                            }
                        } else {
                            let left = reader.bytes.len().saturating_sub(reader.pos) as f64;
                            if n * s.size() as f64 > left {
                                return Err(fail(format!(
                                    "a list of {n} items does not fit in the {left} bytes left (truncated?)"
                                )));
                            }
                        }
                        values.clear();
                        for _ in 0..n as usize {
                            let v = reader
                                .value(*s)
                                .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
                            // Only the face list is kept; other lists are read past.
                            if keep {
                                values.push(v);
                            }
                        }
                        if keep {
                            face_triangles(&values, vertices.len(), &mut triangles)
                                .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
                            first_face.get_or_insert(reader.line);
                        }
                    }
                }
            }
            reader
                .end_item()
                .map_err(|m| reader_error(format, reader.line, &e.name, item, m))?;
            if ei == vi {
                vertices.push(Point3::new(coords[0], coords[1], coords[2]));
            }
        }
    }
    let first = (format == Format::Ascii).then_some(first_face).flatten();
    finish_read("PLY", "faces", vertices, triangles, first)
}

/// The header's caps from the file's first bytes (when `end_header` is among them):
/// the same refusals [`parse_ply`] makes, before the file is read whole.
pub(super) fn precheck(head: &[u8]) -> Result<(), MeshError> {
    let Ok((_, elements, _)) = header(head) else {
        return Ok(()); // the whole read says what is wrong
    };
    check_counts(&elements)
}

/// The caps against the header's counts: vertices, and triangles (every face makes at
/// least one).
fn check_counts(elements: &[Element]) -> Result<(), MeshError> {
    for e in elements {
        let (cap, what) = match e.name.as_str() {
            "vertex" => (MAX_VERTICES, "vertices"),
            "face" => (MAX_TRIANGLES, "triangles"),
            _ => continue,
        };
        if e.count > cap as u64 {
            return Err(MeshError::too_many(cap, what)
                .prefixed(&format!(
                    "element `{}` declares {} items: ",
                    e.name, e.count
                ))
                .on_line(e.line));
        }
    }
    Ok(())
}

/// An error in the body, located: ASCII at its line, binary naming the element and item.
fn reader_error(format: Format, line: usize, element: &str, item: u64, e: MeshError) -> MeshError {
    let element = short(element);
    match format {
        Format::Ascii => e
            .prefixed(&format!("{element} {item}: "))
            .on_line(line.max(1)),
        _ => e.prefixed(&format!("binary PLY, {element} {item}: ")),
    }
}

/// Appends the fan triangles of one face (indices as read) to `out`.
fn face_triangles(
    idx: &[f64],
    vertex_count: usize,
    out: &mut Vec<[u32; 3]>,
) -> Result<(), MeshError> {
    if idx.len() < 3 {
        return Err(MeshError::invalid(format!(
            "a face needs at least 3 corners, this one has {}",
            idx.len()
        )));
    }
    let mut c = Vec::with_capacity(idx.len());
    for &v in idx {
        if !(v >= 0.0 && v.fract() == 0.0 && (v as usize) < vertex_count) {
            return Err(MeshError::new(
                MeshErrorKind::Index,
                format!("vertex index {v} is not one of the {vertex_count} vertices read before the faces"),
            ));
        }
        c.push(v as u32);
    }
    for k in 1..c.len() - 1 {
        out.push([c[0], c[k], c[k + 1]]);
    }
    Ok(())
}

/// The body reader: ASCII by lines of words (one item per line), binary by offset.
struct Reader<'a> {
    format: Format,
    bytes: &'a [u8],
    pos: usize,
    /// ASCII: the 1-based line of the current item.
    line: usize,
    /// ASCII: the words of the current item's line not yet read (an iterator over the
    /// line: a line of millions of values is not split into a list).
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl<'a> Reader<'a> {
    fn start_item(&mut self) -> Result<(), MeshError> {
        if self.format != Format::Ascii {
            return Ok(());
        }
        // Skip blank lines and `comment` lines some writers leave in the body.
        loop {
            if self.pos >= self.bytes.len() {
                return Err(MeshError::invalid(
                    "the file ends before this item (truncated?)",
                ));
            }
            let end = self.bytes[self.pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.bytes.len(), |k| self.pos + k);
            let raw = &self.bytes[self.pos..end];
            self.pos = (end + 1).min(self.bytes.len().max(end));
            self.line += 1;
            let text = std::str::from_utf8(raw)
                .map_err(|_| MeshError::invalid("the line is not UTF-8 text"))?;
            let t = text.trim();
            if t.is_empty() || t.starts_with("comment") {
                continue;
            }
            self.words = t.split_ascii_whitespace();
            return Ok(());
        }
    }

    fn end_item(&mut self) -> Result<(), MeshError> {
        match self.words.next() {
            Some(w) if self.format == Format::Ascii => Err(MeshError::invalid(format!(
                "`{}`: more values on the line than the header's properties",
                short(w)
            ))),
            _ => Ok(()),
        }
    }

    fn value(&mut self, s: Scalar) -> Result<f64, MeshError> {
        match self.format {
            Format::Ascii => {
                let w = self.words.next().ok_or_else(|| {
                    MeshError::invalid("fewer values on the line than the header's properties")
                })?;
                let v: f64 = w
                    .parse()
                    .map_err(|_| MeshError::invalid(format!("`{}` is not a number", short(w))))?;
                if s.is_integer() && v.fract() != 0.0 {
                    return Err(MeshError::invalid(format!(
                        "`{}` is not an integer",
                        short(w)
                    )));
                }
                Ok(v)
            }
            f => {
                let n = s.size();
                let b = self.bytes.get(self.pos..self.pos + n).ok_or_else(|| {
                    MeshError::invalid("the file ends inside this item (truncated?)")
                })?;
                self.pos += n;
                Ok(s.read(b, f == Format::Little))
            }
        }
    }
}

/// The header: the format, the elements, and the offset of the body.
fn header(bytes: &[u8]) -> Result<(Format, Vec<Element>, usize), MeshError> {
    if !bytes.starts_with(b"ply") {
        return Err(MeshError::at(
            1,
            "not a PLY file: it does not start with `ply`",
        ));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line = 0;
    loop {
        if pos >= bytes.len() || pos > MAX_HEADER {
            return Err(MeshError::at(
                line.max(1),
                if pos > MAX_HEADER {
                    format!("no `end_header` in the first {MAX_HEADER} bytes")
                } else {
                    "the header has no `end_header` (truncated?)".to_string()
                },
            ));
        }
        let end = bytes[pos..]
            .iter()
            .take(MAX_HEADER + 1)
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| pos + k);
        let raw = &bytes[pos..end];
        pos = end + 1;
        line += 1;
        let text = std::str::from_utf8(raw)
            .map_err(|_| MeshError::at(line, "the PLY header is not text"))?;
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let mut word = |what: &str| {
            words
                .next()
                .ok_or_else(|| MeshError::at(line, format!("`{keyword}` needs {what}")))
        };
        match keyword {
            "ply" if line == 1 => {}
            "comment" | "obj_info" => {}
            "format" => {
                let f = word("a format")?;
                format = Some(match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => {
                        return Err(MeshError::at(
                            line,
                            format!("unknown PLY format `{}`", short(other)),
                        ))
                    }
                });
            }
            "element" => {
                let name = word("a name")?.to_string();
                let c = word("a count")?;
                let count: u64 = c.parse().map_err(|_| {
                    MeshError::at(line, format!("element count `{}` is not a count", short(c)))
                })?;
                elements.push(Element {
                    name,
                    count,
                    properties: Vec::new(),
                    line,
                });
            }
            "property" => {
                let t = word("a type")?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| MeshError::at(line, "`property` before any `element`"))?;
                let ty = |s: &str| {
                    Scalar::parse(s).ok_or_else(|| {
                        MeshError::at(line, format!("unknown property type `{}`", short(s)))
                    })
                };
                if t == "list" {
                    let c = ty(words.next().unwrap_or(""))?;
                    let i = ty(words.next().unwrap_or(""))?;
                    if !c.is_integer() {
                        return Err(MeshError::at(
                            line,
                            "a list's count type must be an integer",
                        ));
                    }
                    let name = words
                        .next()
                        .ok_or_else(|| MeshError::at(line, "`property list` needs a name"))?;
                    e.properties.push(Property::List(c, i, name.to_string()));
                } else {
                    let s = ty(t)?;
                    let name = words
                        .next()
                        .ok_or_else(|| MeshError::at(line, "`property` needs a name"))?;
                    e.properties.push(Property::Scalar(s, name.to_string()));
                }
            }
            "end_header" => break,
            other => {
                return Err(MeshError::at(
                    line,
                    format!("unexpected `{}` in the PLY header", short(other)),
                ))
            }
        }
    }
    let format = format.ok_or_else(|| MeshError::at(1, "the PLY header has no `format` line"))?;
    Ok((format, elements, pos.min(bytes.len())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    /// The unit cube as PLY in `format`, with a colour property and an extra element.
    pub(crate) fn cube_ply(format: &str) -> Vec<u8> {
        let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 2.0, 3.0));
        let mut out = format!(
            "ply\nformat {format} 1.0\ncomment made by a test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face {}\nproperty list uchar int vertex_indices\nelement edge 0\nproperty int vertex1\nend_header\n",
            m.vertices.len(),
            m.triangles.len()
        )
        .into_bytes();
        let big = format == "binary_big_endian";
        for v in &m.vertices {
            if format == "ascii" {
                out.extend(format!("{} {} {} 255\n", v.x, v.y, v.z).bytes());
            } else {
                for c in [v.x, v.y, v.z] {
                    let f = c as f32;
                    out.extend(if big {
                        f.to_be_bytes()
                    } else {
                        f.to_le_bytes()
                    });
                }
                out.push(255);
            }
        }
        for t in &m.triangles {
            if format == "ascii" {
                out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
            } else {
                out.push(3);
                for &i in t {
                    let i = i as i32;
                    out.extend(if big {
                        i.to_be_bytes()
                    } else {
                        i.to_le_bytes()
                    });
                }
            }
        }
        out
    }

    #[test]
    fn ascii_and_binary_cubes_read_alike() {
        for f in ["ascii", "binary_little_endian", "binary_big_endian"] {
            let m = parse_ply(&cube_ply(f)).unwrap();
            assert_eq!((m.vertices.len(), m.triangles.len()), (8, 12), "{f}");
            assert!(m.inspect().is_watertight(), "{f}");
            assert!((m.signed_volume() - 6.0).abs() < 1e-9, "{f}");
        }
    }

    #[test]
    fn errors_are_located() {
        let ascii = String::from_utf8(cube_ply("ascii")).unwrap();
        // Line 14 is the first vertex.
        let e = parse_ply(ascii.replacen("0 0 0 255", "0 zero 0 255", 1).as_bytes()).unwrap_err();
        assert_eq!(e.line, Some(14), "{e}");
        assert!(e.message.contains("`zero` is not a number"), "{e}");
        let e = parse_ply(ascii.replacen("3 0 2 1", "3 0 2 100", 1).as_bytes()).unwrap_err();
        assert!(e.message.contains("index 100"), "{e}");
        let e = parse_ply(
            ascii
                .replacen("element vertex 8", "element vertex 99999999999", 1)
                .as_bytes(),
        )
        .unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("declares 99999999999 items"), "{e}");
        let bin = cube_ply("binary_little_endian");
        let e = parse_ply(&bin[..bin.len() - 3]).unwrap_err();
        assert!(
            e.message.contains("face 11") && e.message.contains("truncated"),
            "{e}"
        );
    }
}
