//! STL input and output (ASCII and binary, read; binary, written atomically).
//!
//! Binary files are recognised by their size (`84 + 50·n` bytes for `n` facets), not by
//! their header: SolidWorks writes binary STL whose 80-byte header starts with
//! `solid`, which fools parsers that look at the first word.

use super::{Mesh, MeshError, MeshErrorKind, Welder, MAX_TRIANGLES};
use crate::math::Point3;
use std::path::Path;

/// Reads an STL file (ASCII or binary) into an indexed mesh (mm).
pub fn read_stl(path: &Path) -> Result<Mesh, MeshError> {
    if super::step::is_step_path(path) {
        return Err(MeshError::invalid(super::step::not_a_part_mesh()).in_file(path));
    }
    let bytes = crate::fsutil::read_file(path, crate::fsutil::FileKind::Mesh)
        .map_err(|e| MeshError::from(e).in_file(path))?;
    parse_stl(&bytes).map_err(|e| e.in_file(path))
}

/// Parses STL bytes (ASCII or binary). A mesh without facets, one whose facets all
/// have zero area ([`Mesh::has_area`]: nothing to collide with or show), a coordinate
/// beyond [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE) mm, or text after the last
/// `endsolid` other than further `solid … endsolid` blocks (multi-body exporters write
/// those; their facets are read too) is refused; ASCII errors name the line.
pub fn parse_stl(bytes: &[u8]) -> Result<Mesh, MeshError> {
    let (mesh, first_facet) = parse_any(bytes)?;
    if mesh.triangles.is_empty() {
        return Err(MeshError::new(
            MeshErrorKind::NoSurface,
            "the STL has no facets",
        ));
    }
    if !mesh.has_area() {
        let message = format!(
            "all {} facets have zero area (their corners are collinear or coincide): the mesh has no surface",
            mesh.triangles.len()
        );
        return Err(match first_facet {
            Some(line) => MeshError::new(MeshErrorKind::NoSurface, message).on_line(line),
            None => MeshError::new(MeshErrorKind::NoSurface, format!("binary STL: {message}")),
        });
    }
    Ok(mesh)
}

/// A coordinate that is not finite or beyond the accepted range.
/// The three coordinates (mm) after `keyword` on text line `line` (ASCII STL's
/// `vertex`, OBJ's `v`): each a number within the accepted range.
pub(super) fn read_xyz<'a>(
    words: &mut impl Iterator<Item = &'a str>,
    keyword: &str,
    line: usize,
) -> Result<[f64; 3], MeshError> {
    let mut xyz = [0.0; 3];
    for (k, c) in xyz.iter_mut().enumerate() {
        let w = words.next().ok_or_else(|| {
            MeshError::at(line, format!("`{keyword}` needs 3 numbers, found {k}"))
        })?;
        *c = w
            .parse::<f64>()
            .map_err(|_| MeshError::at(line, format!("`{}` is not a number", short(w))))?;
        check_coordinate(*c).map_err(|e| e.on_line(line))?;
    }
    Ok(xyz)
}

/// `v` as a coordinate: finite and within [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE)
/// mm, else a [`MeshErrorKind::Coordinate`] error, not yet located.
pub(super) fn check_coordinate(v: f64) -> Result<(), MeshError> {
    let max = crate::math::MAX_ABS_VALUE;
    let fault = |m: String| Err(MeshError::new(MeshErrorKind::Coordinate, m));
    if !v.is_finite() {
        fault(format!("coordinate {v} is not finite"))
    } else if v.abs() > max {
        fault(format!(
            "coordinate {v:e} is out of range (at most {max:e} mm)"
        ))
    } else {
        Ok(())
    }
}

/// The mesh, and for an ASCII file the line of its first facet.
fn parse_any(bytes: &[u8]) -> Result<(Mesh, Option<usize>), MeshError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * n == bytes.len() as u64 {
            if n > MAX_TRIANGLES as u64 {
                return Err(MeshError::too_many(MAX_TRIANGLES, "triangles")
                    .prefixed(&format!("a binary STL of {n} facets: ")));
            }
            return Ok((parse_binary(bytes)?, None));
        }
    }
    let head = bytes
        .iter()
        .skip_while(|b| b.is_ascii_whitespace())
        .take(5)
        .copied()
        .collect::<Vec<u8>>();
    if head.eq_ignore_ascii_case(b"solid") {
        return parse_ascii(bytes);
    }
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        return Err(MeshError::invalid(format!(
            "not an STL file: a binary STL with {n} facets would be {} bytes, this one is {}, and it does not start with `solid`",
            84 + 50 * n,
            bytes.len()
        )));
    }
    Err(MeshError::invalid(format!(
        "not an STL file: {} bytes is too short",
        bytes.len()
    )))
}

fn parse_binary(bytes: &[u8]) -> Result<Mesh, MeshError> {
    // 80-byte header, u32 count, then per facet: normal (3 f32), 3 vertices (9 f32),
    // u16 attribute. The size and the count (at most MAX_TRIANGLES) were checked by
    // the caller; facets go straight into the welder, no soup is kept.
    let mut mesh = Welder::new((bytes.len() - 84) / 50);
    for (i, facet) in bytes[84..].chunks_exact(50).enumerate() {
        let f = |k: usize| {
            let o = 12 + 4 * k;
            f32::from_le_bytes([facet[o], facet[o + 1], facet[o + 2], facet[o + 3]]) as f64
        };
        let corners = [
            Point3::new(f(0), f(1), f(2)),
            Point3::new(f(3), f(4), f(5)),
            Point3::new(f(6), f(7), f(8)),
        ];
        for v in corners.iter().flat_map(|c| c.coords.iter()) {
            check_coordinate(*v).map_err(|e| e.prefixed(&format!("binary STL facet {i}: ")))?;
        }
        mesh.push(corners);
    }
    mesh.finish()
}

/// `bytes` as text, or an error at the line of the first byte that is not UTF-8 (`what`
/// names the format).
pub(super) fn utf8_text<'a>(bytes: &'a [u8], what: &str) -> Result<&'a str, MeshError> {
    std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        MeshError::at(
            line,
            format!("{what} contains bytes that are not UTF-8 text"),
        )
    })
}

/// ASCII STL: `solid name / facet normal … / outer loop / vertex x y z ×3 / endloop /
/// endfacet / endsolid`, possibly several `solid … endsolid` blocks one after the other
/// (multi-body exports). Written by hand rather than through stl_io so that every
/// error carries its line number. Returns the mesh and the line of the first facet.
fn parse_ascii(bytes: &[u8]) -> Result<(Mesh, Option<usize>), MeshError> {
    let text = utf8_text(bytes, "ASCII STL")?;
    let mut soup = Welder::new(0);
    let mut corners: Vec<Point3> = Vec::with_capacity(3);
    let mut in_facet = false;
    // Inside a `solid … endsolid` block; `ended` is the line of the last `endsolid`.
    let mut in_solid = false;
    let mut ended: Option<usize> = None;
    let mut first_facet = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        // NUL padding (fixed-size buffers of some exporters) counts as blank.
        let mut words = raw
            .split(|c: char| c.is_whitespace() || c == '\0')
            .filter(|w| !w.is_empty());
        let Some(keyword) = words.next() else {
            continue;
        };
        let keyword = keyword.to_ascii_lowercase();
        if let (Some(end), false) = (ended, in_solid) {
            if keyword != "solid" {
                return Err(MeshError::at(
                    line,
                    format!(
                        "`{}` after `endsolid` (line {end}): only another `solid … endsolid` block may follow",
                        short(raw.trim())
                    ),
                ));
            }
        }
        match keyword.as_str() {
            "solid" if !in_solid => in_solid = true,
            // A repeated header before any facet (seen in hand-edited files).
            "solid" if soup.len() == 0 && !in_facet => {}
            "solid" => {
                return Err(MeshError::at(
                    line,
                    "`solid` inside a solid: the previous block has no `endsolid`",
                ))
            }
            "facet" => {
                if in_facet {
                    return Err(MeshError::at(
                        line,
                        "`facet` before the previous facet's `endfacet`",
                    ));
                }
                in_facet = true;
                first_facet.get_or_insert(line);
                corners.clear();
            }
            "outer" | "endloop" => {}
            "vertex" => {
                if !in_facet {
                    return Err(MeshError::at(line, "`vertex` outside a facet"));
                }
                let xyz = read_xyz(&mut words, "vertex", line)?;
                if corners.len() == 3 {
                    return Err(MeshError::at(line, "a facet has more than 3 vertices"));
                }
                corners.push(Point3::new(xyz[0], xyz[1], xyz[2]));
            }
            "endfacet" => {
                if corners.len() != 3 {
                    return Err(MeshError::at(
                        line,
                        format!("a facet has {} vertices, expected 3", corners.len()),
                    ));
                }
                if soup.len() >= MAX_TRIANGLES {
                    return Err(MeshError::too_many(MAX_TRIANGLES, "triangles").on_line(line));
                }
                soup.push([corners[0], corners[1], corners[2]]);
                in_facet = false;
            }
            "endsolid" => {
                if in_facet {
                    return Err(MeshError::at(
                        line,
                        "`endsolid` inside a facet (no `endfacet`)",
                    ));
                }
                ended = Some(line);
                in_solid = false;
            }
            other => {
                return Err(MeshError::at(
                    line,
                    format!("unexpected `{}` in ASCII STL", short(other)),
                ))
            }
        }
    }
    if in_facet {
        return Err(MeshError::at(
            text.lines().count(),
            "the file ends inside a facet (truncated?)",
        ));
    }
    if ended.is_none() && soup.len() == 0 {
        return Err(MeshError::at(
            text.lines().count().max(1),
            "no facets and no `endsolid` (truncated?)",
        ));
    }
    Ok((soup.finish()?, first_facet))
}

/// At most 40 characters of a token or line, for messages (a line may be megabytes).
pub(super) fn short(s: &str) -> String {
    if s.chars().count() <= 40 {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(40).collect::<String>())
    }
}

/// A mesh as the bytes of a binary STL (f32 coordinates, mm, normals from the
/// winding), for writers that go through the output rule.
pub fn stl_bytes(mesh: &Mesh) -> Vec<u8> {
    let triangles: Vec<stl_io::Triangle> = (0..mesh.triangles.len())
        .map(|i| {
            let [a, b, c] = mesh.triangle(i);
            let n = mesh.triangle_normal(i);
            let v = |p: Point3| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32]);
            stl_io::Triangle {
                normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: [v(a), v(b), v(c)],
            }
        })
        .collect();
    let mut bytes = Vec::with_capacity(84 + 50 * triangles.len());
    // writing into a Vec cannot fail
    let _ = stl_io::write_stl(&mut bytes, triangles.iter());
    bytes
}

/// Writes a binary STL atomically (temporary file in the same folder, then rename), so
/// a reader never sees a half-written file.
pub fn write_stl(path: &Path, mesh: &Mesh) -> Result<(), MeshError> {
    let bytes = stl_bytes(mesh);
    crate::fsutil::write_atomic(path, &bytes)
        .map_err(|e| MeshError::new(MeshErrorKind::Write, e.to_string()).in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_ascii() -> String {
        let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 2.0, 3.0));
        let mut s = String::from("solid cube\n");
        for i in 0..m.triangles.len() {
            s += "  facet normal 0 0 0\n    outer loop\n";
            for p in m.triangle(i) {
                s += &format!("      vertex {} {} {}\n", p.x, p.y, p.z);
            }
            s += "    endloop\n  endfacet\n";
        }
        s + "endsolid cube\n"
    }

    #[test]
    fn ascii_and_binary_agree() {
        let ascii = parse_stl(cube_ascii().as_bytes()).unwrap();
        assert_eq!(ascii.triangles.len(), 12);
        assert!(ascii.inspect().is_watertight());
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cube.stl");
        write_stl(&p, &ascii).unwrap();
        let binary = read_stl(&p).unwrap();
        assert_eq!(binary, ascii);
    }

    #[test]
    fn binary_with_solid_header_is_binary() {
        let m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sw.stl");
        write_stl(&p, &m).unwrap();
        let mut bytes = std::fs::read(&p).unwrap();
        bytes[..12].copy_from_slice(b"solid SW2024");
        assert_eq!(parse_stl(&bytes).unwrap().triangles.len(), 12);
    }

    #[test]
    fn errors_name_the_line() {
        let bad = cube_ascii().replacen("vertex 0 0 0", "vertex 0 zero 0", 1);
        let e = parse_stl(bad.as_bytes()).unwrap_err();
        assert!(e.line.is_some() && e.message.contains("zero"), "{e}");
        let truncated: String = cube_ascii().lines().take(5).collect::<Vec<_>>().join("\n");
        let e = parse_stl(truncated.as_bytes()).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        assert!(parse_stl(b"hello").is_err());
        let mut junk = vec![0u8; 200];
        junk[80] = 7;
        assert!(parse_stl(&junk).unwrap_err().message.contains("434 bytes"));
    }

    /// One facet with collinear corners, as ASCII.
    const FLAT: &str = "solid d\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 1 1\nvertex 2 2 2\nendloop\nendfacet\nendsolid d\n";

    #[test]
    fn a_mesh_of_zero_area_facets_is_refused_with_file_and_line() {
        let e = parse_stl(FLAT.as_bytes()).unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
        assert!(e.message.contains("all 1 facets have zero area"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("flat.stl");
        std::fs::write(&p, FLAT).unwrap();
        let e = read_stl(&p).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("{}:2: all 1 facets", p.display())),
            "{e}"
        );
        // Binary: the same rule, named by file.
        let flat = parse_ascii(FLAT.as_bytes()).unwrap().0;
        let b = dir.path().join("flat_bin.stl");
        write_stl(&b, &flat).unwrap();
        let e = read_stl(&b).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("{}: binary STL: all 1 facets", b.display())),
            "{e}"
        );
        // One good facet among flat ones is enough: the flat ones are skipped later.
        let mixed = cube_ascii().replacen("endsolid cube", &FLAT[8..FLAT.len() - 11], 1)
            + "endsolid cube\n";
        assert_eq!(parse_stl(mixed.as_bytes()).unwrap().triangles.len(), 13);
    }

    #[test]
    fn text_after_endsolid_is_refused_but_further_solids_are_read() {
        let cube = cube_ascii();
        let n = cube.lines().count();
        let e = parse_stl(format!("{cube}\ngarbage here\n").as_bytes()).unwrap_err();
        assert_eq!(e.line, Some(n + 2), "{e}");
        assert!(e.message.contains("`garbage here` after `endsolid`"), "{e}");
        assert!(e.message.contains(&format!("(line {n})")), "{e}");
        // Two bodies in one file (multi-body exporters): both are read.
        let two = format!("{cube}{}", cube.replace("vertex ", "vertex 10"));
        assert_eq!(parse_stl(two.as_bytes()).unwrap().triangles.len(), 24);
        // Blank lines and NUL padding after the end are not content.
        let padded = format!("{cube}\n  \n\0\0\0\n");
        assert!(parse_stl(padded.as_bytes()).is_ok());
        // A second `solid` before the first block ends is an error at its line.
        let nested = cube.replacen("  facet", "solid again\n  facet", 2);
        let e = parse_stl(nested.as_bytes()).unwrap_err();
        assert!(e.message.contains("`solid` inside a solid"), "{e}");
        // A long garbage line is quoted short.
        let long = format!("{cube}{}\n", "x".repeat(100_000));
        let e = parse_stl(long.as_bytes()).unwrap_err();
        assert!(e.message.len() < 300, "{}", e.message.len());
    }

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(256))]

        #[test]
        fn never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400)) {
            let _ = parse_stl(&bytes);
        }

        /// A vertex is accepted exactly when it is finite and within 1e9 mm, in ASCII
        /// (error at its line) and binary files alike.
        #[test]
        fn vertex_range_is_enforced(v in proptest::prop_oneof![
            proptest::num::f64::ANY,
            -2e9f64..2e9,
            proptest::strategy::Just(1e39),
        ]) {
            let ok = v.is_finite() && v.abs() <= crate::math::MAX_ABS_VALUE;
            let ascii = cube_ascii().replacen("vertex 0 0 0", &format!("vertex 0 {v:e} 0"), 1);
            let line = ascii.lines().position(|l| l.contains(&format!("{v:e}"))).map(|l| l + 1);
            match parse_stl(ascii.as_bytes()) {
                Ok(_) => proptest::prop_assert!(ok, "{v:e} accepted"),
                Err(e) => {
                    proptest::prop_assert!(!ok, "{v:e} refused: {e}");
                    proptest::prop_assert_eq!(e.line, line);
                }
            }
            let mut m = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
            m.vertices[0].y = v;
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("b.stl");
            if write_stl(&p, &m).is_ok() {
                // Binary STL stores f32: what counts is the value read back.
                let stored = v as f32 as f64;
                let ok = stored.is_finite() && stored.abs() <= crate::math::MAX_ABS_VALUE;
                proptest::prop_assert_eq!(read_stl(&p).is_ok(), ok, "{:e}", v);
            }
        }

        #[test]
        fn never_panics_on_mangled_ascii(cut in 0usize..600, junk in "[ -~\\n]{0,40}") {
            let mut s = cube_ascii();
            let at = cut.min(s.len());
            s.insert_str(at, &junk);
            let _ = parse_stl(s.as_bytes());
        }
    }
}
