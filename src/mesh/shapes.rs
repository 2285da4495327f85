//! Closed, outward-oriented meshes built in code: solids of revolution (screws, pins,
//! pegs) and perforated plates. Used for the bundled models, tests and benchmarks.

use super::{Mesh, MeshError};
use crate::math::Point3;

impl Mesh {
    /// A closed sphere of `radius` (mm) about the origin: `segments` facets around
    /// (at least 4) and half as many from pole to pole.
    pub fn uv_sphere(radius: f64, segments: usize) -> Mesh {
        let n = segments.max(4);
        let rings = n / 2;
        let profile: Vec<(f64, f64)> = (0..=rings)
            .map(|k| {
                let t = std::f64::consts::PI * k as f64 / rings as f64;
                // Exactly on the axis at the poles (the lathe requires it).
                let r = if k == 0 || k == rings {
                    0.0
                } else {
                    radius * t.sin()
                };
                (r, -radius * t.cos())
            })
            .collect();
        // A finite radius gives a valid profile; a bad one an empty mesh.
        Mesh::lathe(&profile, n).unwrap_or(Mesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
        })
    }

    /// A solid of revolution about +Z: `profile` lists `(radius, z)` pairs (mm) from
    /// the bottom to the top; the first and last must lie on the axis (radius 0).
    /// `segments` facets around (at least 3).
    pub fn lathe(profile: &[(f64, f64)], segments: usize) -> Result<Mesh, MeshError> {
        let n = segments.max(3);
        if profile.len() < 3 || profile[0].0 != 0.0 || profile[profile.len() - 1].0 != 0.0 {
            return Err(MeshError::invalid(
                "a lathe profile needs ≥ 3 points starting and ending on the axis",
            ));
        }
        if profile
            .iter()
            .any(|&(r, z)| !(r.is_finite() && z.is_finite()) || r < 0.0)
        {
            return Err(MeshError::invalid(
                "a lathe profile needs finite points with radius ≥ 0",
            ));
        }
        let at = |(r, z): (f64, f64), k: usize| {
            let a = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            Point3::new(r * a.cos(), r * a.sin(), z)
        };
        let mut soup = Vec::new();
        for w in profile.windows(2) {
            let (p, q) = (w[0], w[1]);
            for k in 0..n {
                let (p0, p1, q0, q1) = (at(p, k), at(p, k + 1), at(q, k), at(q, k + 1));
                // Profile going up with the solid on the axis side: (p0, p1, q1) faces out.
                if p.0 > 0.0 {
                    soup.push([p0, p1, q1]);
                }
                if q.0 > 0.0 {
                    soup.push([p0, q1, q0]);
                }
            }
        }
        let mut mesh = Mesh::from_triangle_soup(soup)?;
        mesh.orient_outward();
        Ok(mesh)
    }

    /// A plate of `nx × ny` square tiles of side `pitch` (mm), `thickness` thick, from
    /// the origin along +X, +Y, +Z; tile `(i, j)` has a round through hole of `radius`
    /// at its centre when `hole(i, j)`. Holes are `4·k`-gons; each tile edge has `k`
    /// segments so that neighbouring tiles share vertices (watertight).
    pub fn perforated_plate(
        nx: usize,
        ny: usize,
        pitch: f64,
        thickness: f64,
        radius: f64,
        k: usize,
        hole: impl Fn(usize, usize) -> bool,
    ) -> Result<Mesh, MeshError> {
        let k = k.max(1);
        if nx == 0
            || ny == 0
            || !(pitch > 0.0 && thickness > 0.0 && radius >= 0.0 && 2.0 * radius < pitch)
        {
            return Err(MeshError::invalid(
                "a perforated plate needs tiles, pitch > 0, thickness > 0 and 0 ≤ 2·radius < pitch",
            ));
        }
        let g = |i: usize| i as f64 * pitch / k as f64; // global subdivided grid coordinate
        let mut soup: Vec<[Point3; 3]> = Vec::new();
        fn quad(soup: &mut Vec<[Point3; 3]>, a: Point3, b: Point3, c: Point3, d: Point3) {
            soup.push([a, b, c]);
            soup.push([a, c, d]);
        }
        for i in 0..nx {
            for j in 0..ny {
                // Tile boundary, counter-clockwise seen from +Z, as global grid indices.
                let (x0, y0) = (i * k, j * k);
                let mut ring: Vec<(usize, usize)> = Vec::with_capacity(4 * k);
                ring.extend((0..k).map(|s| (x0 + s, y0)));
                ring.extend((0..k).map(|s| (x0 + k, y0 + s)));
                ring.extend((0..k).map(|s| (x0 + k - s, y0 + k)));
                ring.extend((0..k).map(|s| (x0, y0 + k - s)));
                let c = Point3::new((i as f64 + 0.5) * pitch, (j as f64 + 0.5) * pitch, 0.0);
                let m = ring.len();
                for z in [0.0, thickness] {
                    let top = z > 0.0;
                    let b = |s: usize| Point3::new(g(ring[s % m].0), g(ring[s % m].1), z);
                    if hole(i, j) {
                        let h = |s: usize| {
                            let p = b(s);
                            let d = (p - Point3::new(c.x, c.y, z)).normalize() * radius;
                            Point3::new(c.x + d.x, c.y + d.y, z)
                        };
                        for s in 0..m {
                            if top {
                                quad(&mut soup, b(s), b(s + 1), h(s + 1), h(s));
                            } else {
                                quad(&mut soup, b(s), h(s), h(s + 1), b(s + 1));
                            }
                        }
                        if top {
                            // The hole wall, facing the hole's axis.
                            for s in 0..m {
                                let lo = |s| Point3::new(h(s).x, h(s).y, 0.0);
                                quad(&mut soup, h(s), h(s + 1), lo(s + 1), lo(s));
                            }
                        }
                    } else {
                        let cz = Point3::new(c.x, c.y, z);
                        for s in 0..m {
                            if top {
                                soup.push([cz, b(s), b(s + 1)]);
                            } else {
                                soup.push([cz, b(s + 1), b(s)]);
                            }
                        }
                    }
                }
            }
        }
        // Outer walls, k segments per tile edge.
        let (w, h) = (nx * k, ny * k);
        let p = |x: usize, y: usize, z: f64| Point3::new(g(x), g(y), z);
        let t = thickness;
        for s in 0..w {
            quad(
                &mut soup,
                p(s, 0, 0.0),
                p(s + 1, 0, 0.0),
                p(s + 1, 0, t),
                p(s, 0, t),
            );
            quad(
                &mut soup,
                p(s + 1, h, 0.0),
                p(s, h, 0.0),
                p(s, h, t),
                p(s + 1, h, t),
            );
        }
        for s in 0..h {
            quad(
                &mut soup,
                p(w, s, 0.0),
                p(w, s + 1, 0.0),
                p(w, s + 1, t),
                p(w, s, t),
            );
            quad(
                &mut soup,
                p(0, s + 1, 0.0),
                p(0, s, 0.0),
                p(0, s, t),
                p(0, s + 1, t),
            );
        }
        Mesh::from_triangle_soup(soup)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screw_is_watertight_with_expected_volume() {
        let m = Mesh::lathe(
            &[
                (0.0, 0.0),
                (4.0, 0.0),
                (4.0, 10.0),
                (7.0, 10.0),
                (7.0, 15.0),
                (0.0, 15.0),
            ],
            64,
        )
        .unwrap();
        assert!(m.inspect().is_watertight(), "{:?}", m.inspect());
        let exact = std::f64::consts::PI * (16.0 * 10.0 + 49.0 * 5.0);
        let v = m.signed_volume();
        assert!(v > 0.98 * exact && v < exact, "{v} vs {exact}");
    }

    #[test]
    fn perforated_plate_is_watertight_with_holes() {
        let m = Mesh::perforated_plate(3, 2, 100.0, 10.0, 4.5, 8, |i, j| (i + j) % 2 == 0).unwrap();
        assert!(m.inspect().is_watertight(), "{:?}", m.inspect());
        let holes = 3.0;
        let hole_area = 0.5 * 32.0 * 4.5f64.powi(2) * (std::f64::consts::TAU / 32.0).sin(); // 32-gon (not regular, approx)
        let v = m.signed_volume();
        let full = 300.0 * 200.0 * 10.0;
        assert!(v < full && v > full - holes * 10.0 * hole_area * 1.1, "{v}");
        assert!(Mesh::perforated_plate(1, 1, 10.0, 1.0, 6.0, 4, |_, _| true).is_err());
    }
}
