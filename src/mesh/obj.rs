//! Wavefront OBJ input: `v` positions and `f` faces (polygons fan-triangulated), mm.
//!
//! Written by hand (not through a crate) so that every error names its line and a
//! hostile file cannot make the reader allocate more than the file's own size: the
//! vertices and triangles kept are what the lines hold, capped by
//! [`MAX_TRIANGLES`](super::MAX_TRIANGLES).

use super::stl::{read_xyz, short, utf8_text};
use super::{finish_read, MeshError, MeshErrorKind, MAX_TRIANGLES, MAX_VERTICES};
use crate::math::Point3;

/// Attribute and grouping statements that carry no geometry fitup uses (texture
/// coordinates, normals, groups, materials, smoothing, lines and points): skipped.
const IGNORED: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "g",
    "o",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "l",
    "p",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "shadow_obj",
    "trace_obj",
    "maplib",
    "usemap",
];

/// Free-form geometry, which would need a surface tessellator.
const FREE_FORM: &[&str] = &[
    "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole", "scrv", "sp",
    "end", "con", "ctech", "stech",
];

/// Parses OBJ bytes into a mesh (mm: OBJ has no units, fitup reads them as STL's).
///
/// `v x y z [w]` (extra colour numbers after `z` are allowed) and `f i j k …` with
/// `i`, `i/t`, `i//n` or `i/t/n` corners, 1-based or negative (relative) indices; a
/// line ending in `\` continues on the next (errors name the statement's first line);
/// a polygon of n corners becomes n − 2 triangles around its first corner. A vertex
/// no face uses is dropped, bit-identical positions are merged. Refused, at its line:
/// text that is not UTF-8, a number that does not parse or is beyond
/// [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE), an index 0 or past the vertices
/// defined so far, a face of fewer than 3 corners, free-form geometry, an unknown
/// statement, more than [`MAX_TRIANGLES`] triangles; a file without faces or whose
/// faces all have zero area ([`super::Mesh::has_area`]).
pub fn parse_obj(bytes: &[u8]) -> Result<super::Mesh, MeshError> {
    let text = utf8_text(bytes, "OBJ")?;
    let mut vertices: Vec<Point3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut first_face = None;
    let mut corners: Vec<u32> = Vec::new();
    for (line, raw) in logical_lines(text) {
        let content = raw.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let xyz = read_xyz(&mut words, "v", line)?;
                // `w` or vertex colours may follow; they must still be numbers.
                for w in words {
                    w.parse::<f64>().map_err(|_| {
                        MeshError::at(line, format!("`{}` is not a number", short(w)))
                    })?;
                }
                if vertices.len() >= MAX_VERTICES {
                    return Err(MeshError::too_many(MAX_VERTICES, "vertices").on_line(line));
                }
                vertices.push(Point3::new(xyz[0], xyz[1], xyz[2]));
            }
            "f" | "fo" => {
                corners.clear();
                for w in words {
                    // Counted before it is kept: one line of millions of corners
                    // stops at the cap, not at the end of the line.
                    if triangles.len() + corners.len().saturating_sub(1) > MAX_TRIANGLES {
                        return Err(MeshError::too_many(MAX_TRIANGLES, "triangles").on_line(line));
                    }
                    let index = w.split('/').next().unwrap_or("");
                    let n: i64 = index.parse().map_err(|_| {
                        MeshError::at(line, format!("`{}` is not a vertex index", short(w)))
                    })?;
                    let count = vertices.len() as i64;
                    let resolved = match n {
                        0 => {
                            return Err(MeshError::at(
                                line,
                                "vertex index 0: OBJ indices start at 1 (or are negative, counting back)",
                            ))
                        }
                        n if n > 0 => n - 1,
                        n => count + n,
                    };
                    if resolved < 0 || resolved >= count {
                        return Err(MeshError::at(
                            line,
                            format!(
                                "vertex index {n} refers past the {count} vertices defined before this line"
                            ),
                        )
                        .kind(MeshErrorKind::Index));
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(MeshError::at(
                        line,
                        format!("a face needs at least 3 corners, this one has {}", corners.len()),
                    ));
                }
                if triangles.len() + corners.len() - 2 > MAX_TRIANGLES {
                    return Err(MeshError::too_many(MAX_TRIANGLES, "triangles").on_line(line));
                }
                first_face.get_or_insert(line);
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            k if IGNORED.contains(&k) => {}
            k if FREE_FORM.contains(&k) => {
                return Err(MeshError::at(
                    line,
                    format!("`{k}`: free-form curves and surfaces are not supported (export the part as a polygon mesh)"),
                )
                .kind(MeshErrorKind::Unsupported))
            }
            other => {
                return Err(MeshError::at(
                    line,
                    format!("unexpected `{}` in OBJ", short(other)),
                ))
            }
        }
    }
    finish_read("OBJ", "faces", vertices, triangles, first_face)
}

/// The statements of OBJ text with their first line numbers (1-based): a line whose
/// last character other than white space is `\` continues on the next one (Wavefront's
/// line continuation), joined with a space in its place.
fn logical_lines(text: &str) -> impl Iterator<Item = (usize, std::borrow::Cow<'_, str>)> {
    let mut physical = text.lines().enumerate();
    std::iter::from_fn(move || {
        let (i, first) = physical.next()?;
        let Some(head) = first.trim_end().strip_suffix('\\') else {
            return Some((i + 1, std::borrow::Cow::Borrowed(first)));
        };
        let mut joined = String::from(head);
        for (_, next) in physical.by_ref() {
            joined.push(' ');
            match next.trim_end().strip_suffix('\\') {
                Some(part) => joined.push_str(part),
                None => {
                    joined.push_str(next);
                    break;
                }
            }
        }
        Some((i + 1, std::borrow::Cow::Owned(joined)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE: &str = "# a cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nvn 0 0 1\n\
f 1 3 2\nf 1 4 3\nf 5 6 7 8\nf 1/1/1 2/2/1 6/3/1\nf 1 6 5\nf -7 -6 -2\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4//1 1//1 5//1\nf 4 5 8\n";

    #[test]
    fn a_cube_with_quads_and_relative_indices_is_closed() {
        let m = parse_obj(CUBE.as_bytes()).unwrap();
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.vertices.len(), 8);
        assert!(m.inspect().is_watertight(), "{:?}", m.inspect());
        assert!((m.signed_volume() - 1.0).abs() < 1e-12);
    }

    /// Wavefront's `\` line continuation (read by trimesh): a statement split over
    /// lines, with spaces or `\r` after the backslash, reads as the joined line; line
    /// numbers of later statements stay those of the file.
    #[test]
    fn backslash_continues_a_statement_on_the_next_line() {
        let split = CUBE
            .replacen("f 1 3 2\n", "f 1 \\\n3 \\  \r\n2\n", 1)
            .replacen("v 1 1 1\n", "v 1\\\n1 \\\n1\n", 1)
            .replacen("f 5 6 7 8\n", "f 5 6 \\\n\\\n7 8\n", 1);
        assert_eq!(split.matches('\\').count(), 6);
        let m = parse_obj(split.as_bytes()).unwrap();
        assert_eq!(m, parse_obj(CUBE.as_bytes()).unwrap());
        // An error in a continued statement names its first line; one after it, its own.
        let bad = split.replacen("f 1 \\\n3", "f 1 \\\n99", 1);
        let first = split.lines().position(|l| l.starts_with("f 1 \\")).unwrap() + 1;
        assert_eq!(first, 13);
        assert_eq!(parse_obj(bad.as_bytes()).unwrap_err().line, Some(first));
        let late = split.replacen("f 4 5 8", "f 4 5 x", 1);
        let lines = late.lines().count();
        assert_eq!(parse_obj(late.as_bytes()).unwrap_err().line, Some(lines));
        // A backslash on the last line ends the file.
        assert!(parse_obj(format!("{CUBE}f 1 2 \\").as_bytes()).is_err());
    }

    #[test]
    fn errors_name_their_line() {
        let cases = [
            (
                CUBE.replacen("v 1 0 0", "v 1 x 0", 1),
                3,
                "`x` is not a number",
            ),
            (
                CUBE.replacen("f 1 3 2", "f 1 3 99", 1),
                11,
                "past the 8 vertices",
            ),
            (CUBE.replacen("f 1 3 2", "f 1 0 2", 1), 11, "index 0"),
            (
                CUBE.replacen("f 1 3 2", "f 1 3", 1),
                11,
                "at least 3 corners",
            ),
            (CUBE.replacen("v 1 0 0", "v 1 nan 0", 1), 3, "not finite"),
            (CUBE.replacen("v 1 0 0", "v 1 2e9 0", 1), 3, "out of range"),
            (CUBE.replacen("vn 0 0 1", "curv 0 1 2", 1), 10, "free-form"),
            (
                CUBE.replacen("vn 0 0 1", "bogus", 1),
                10,
                "unexpected `bogus`",
            ),
        ];
        for (text, line, needle) in cases {
            let e = parse_obj(text.as_bytes()).unwrap_err();
            assert_eq!(e.line, Some(line), "{e}");
            assert!(e.message.contains(needle), "{e}");
        }
        let e = parse_obj(b"v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n").unwrap_err();
        assert!(e.message.contains("zero area") && e.line == Some(4), "{e}");
        assert!(parse_obj(b"v 0 0 0\n")
            .unwrap_err()
            .message
            .contains("no faces"));
    }
}
