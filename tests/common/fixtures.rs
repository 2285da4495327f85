//! Closed, outward-oriented test parts generated in code (mm, part frame), used by
//! the collision unit tests and the interference benchmark (test scaffolding, not
//! part of the library): perforated plates, a plate with a round hole, screws,
//! spheres and tori. Included with `#[path]`; the including module provides
//! `Mesh`, `Point3` and `Vec3`.

#![allow(dead_code)]

use super::{Mesh, Point3, Vec3};

struct Builder {
    mesh: Mesh,
}

impl Builder {
    fn new() -> Self {
        Builder {
            mesh: Mesh {
                vertices: Vec::new(),
                triangles: Vec::new(),
            },
        }
    }

    fn vertex(&mut self, p: Point3) -> u32 {
        self.mesh.vertices.push(p);
        (self.mesh.vertices.len() - 1) as u32
    }

    /// A triangle wound so that its normal points along `outward`.
    fn tri(&mut self, t: [u32; 3], outward: Vec3) {
        let v = |i: u32| self.mesh.vertices[i as usize];
        let n = (v(t[1]) - v(t[0])).cross(&(v(t[2]) - v(t[0])));
        if n.dot(&outward) >= 0.0 {
            self.mesh.triangles.push(t);
        } else {
            self.mesh.triangles.push([t[0], t[2], t[1]]);
        }
    }

    fn quad(&mut self, q: [u32; 4], outward: Vec3) {
        self.tri([q[0], q[1], q[2]], outward);
        self.tri([q[0], q[2], q[3]], outward);
    }
}

/// A plate from `z = 0` to `z = thickness` with a `holes.0 × holes.1` grid of square
/// through holes of side `hole` at `pitch`, a `margin` of material around the grid;
/// its corner is at the origin. Size along X: `2 margin + (holes.0 - 1) pitch + hole`.
pub fn perforated_plate(
    holes: (usize, usize),
    hole: f64,
    pitch: f64,
    margin: f64,
    thickness: f64,
) -> Mesh {
    let lines = |n: usize| {
        let mut v = vec![0.0];
        for k in 0..n {
            v.push(margin + k as f64 * pitch);
            v.push(margin + k as f64 * pitch + hole);
        }
        v.push(2.0 * margin + (n.max(1) - 1) as f64 * pitch + hole);
        v
    };
    let (xs, ys) = (lines(holes.0), lines(holes.1));
    let (nx, ny) = (xs.len(), ys.len());
    let mut b = Builder::new();
    let mut ids = vec![[0u32; 2]; nx * ny];
    for (j, &y) in ys.iter().enumerate() {
        for (i, &x) in xs.iter().enumerate() {
            ids[j * nx + i] = [
                b.vertex(Point3::new(x, y, 0.0)),
                b.vertex(Point3::new(x, y, thickness)),
            ];
        }
    }
    let id = |i: usize, j: usize, top: usize| ids[j * nx + i][top];
    let solid = |i: isize, j: isize| {
        i >= 0
            && j >= 0
            && (i as usize) < nx - 1
            && (j as usize) < ny - 1
            && !(i % 2 == 1 && j % 2 == 1)
    };
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            if !solid(i as isize, j as isize) {
                continue;
            }
            for (top, n) in [(1, Vec3::z()), (0, -Vec3::z())] {
                b.quad(
                    [
                        id(i, j, top),
                        id(i + 1, j, top),
                        id(i + 1, j + 1, top),
                        id(i, j + 1, top),
                    ],
                    n,
                );
            }
            let (ii, jj) = (i as isize, j as isize);
            if !solid(ii - 1, jj) {
                b.quad(
                    [id(i, j, 0), id(i, j + 1, 0), id(i, j + 1, 1), id(i, j, 1)],
                    -Vec3::x(),
                );
            }
            if !solid(ii + 1, jj) {
                b.quad(
                    [
                        id(i + 1, j, 0),
                        id(i + 1, j + 1, 0),
                        id(i + 1, j + 1, 1),
                        id(i + 1, j, 1),
                    ],
                    Vec3::x(),
                );
            }
            if !solid(ii, jj - 1) {
                b.quad(
                    [id(i, j, 0), id(i + 1, j, 0), id(i + 1, j, 1), id(i, j, 1)],
                    -Vec3::y(),
                );
            }
            if !solid(ii, jj + 1) {
                b.quad(
                    [
                        id(i, j + 1, 0),
                        id(i + 1, j + 1, 0),
                        id(i + 1, j + 1, 1),
                        id(i, j + 1, 1),
                    ],
                    Vec3::y(),
                );
            }
        }
    }
    b.mesh
}

/// A square plate `[-half, half]²` from `z = 0` to `z = thickness` with a round
/// through hole of `radius` on the Z axis, faceted like [`Mesh::cylinder`] with the
/// same `segments` (rounded up to a multiple of 4), so a cylinder of that radius and
/// segment count fits it face to face.
pub fn plate_with_hole(half: f64, thickness: f64, radius: f64, segments: usize) -> Mesh {
    let n = segments.max(4).div_ceil(4) * 4;
    let mut b = Builder::new();
    let ring = |b: &mut Builder, z: f64| -> Vec<u32> {
        (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                b.vertex(Point3::new(radius * a.cos(), radius * a.sin(), z))
            })
            .collect()
    };
    let corners = |b: &mut Builder, z: f64| -> Vec<u32> {
        [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
            .iter()
            .map(|&(x, y)| b.vertex(Point3::new(half * x, half * y, z)))
            .collect()
    };
    let (r0, r1) = (ring(&mut b, 0.0), ring(&mut b, thickness));
    let (c0, c1) = (corners(&mut b, 0.0), corners(&mut b, thickness));
    for (r, c, up) in [(&r0, &c0, -Vec3::z()), (&r1, &c1, Vec3::z())] {
        for k in 0..n {
            let q = (4 * k) / n; // quadrant of the edge k → k+1
            b.tri([r[k], r[(k + 1) % n], c[q]], up);
            if (k + 1) % (n / 4) == 0 {
                b.tri([r[(k + 1) % n], c[q], c[(q + 1) % 4]], up);
            }
        }
    }
    for q in 0..4 {
        let (i, j) = (q, (q + 1) % 4);
        let mid = (b.mesh.vertices[c0[i] as usize] + b.mesh.vertices[c0[j] as usize].coords) * 0.5;
        b.quad([c0[i], c0[j], c1[j], c1[i]], mid.coords);
    }
    for k in 0..n {
        let j = (k + 1) % n;
        let mid = (b.mesh.vertices[r0[k] as usize] + b.mesh.vertices[r0[j] as usize].coords) * 0.5;
        b.quad([r0[k], r0[j], r1[j], r1[k]], -mid.coords);
    }
    b.mesh
}

/// A screw: a shank of `radius` from `z = 0` to `z = length` and a head of
/// `head_radius`, `head_height` on top (two closed cylinders sharing the plane
/// `z = length`).
pub fn screw(
    radius: f64,
    length: f64,
    head_radius: f64,
    head_height: f64,
    segments: usize,
) -> Mesh {
    // One closed solid (not a shank and a head touching): the lathe of the profile.
    let (h, r, rh) = (length, radius, head_radius);
    Mesh::lathe(
        &[
            (0.0, 0.0),
            (r, 0.0),
            (r, h),
            (rh, h),
            (rh, h + head_height),
            (0.0, h + head_height),
        ],
        segments,
    )
    .unwrap_or_else(|_| Mesh::cylinder(r, h, segments))
}

/// A UV sphere of `radius` about the origin with `slices` around and `stacks` from
/// pole to pole: `2 slices (stacks - 1)` triangles.
pub fn sphere(radius: f64, slices: usize, stacks: usize) -> Mesh {
    let (ns, nt) = (slices.max(3), stacks.max(2));
    let mut b = Builder::new();
    let south = b.vertex(Point3::new(0.0, 0.0, -radius));
    let north = b.vertex(Point3::new(0.0, 0.0, radius));
    let rings: Vec<Vec<u32>> = (1..nt)
        .map(|s| {
            let phi = std::f64::consts::PI * s as f64 / nt as f64 - std::f64::consts::FRAC_PI_2;
            (0..ns)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / ns as f64;
                    b.vertex(Point3::new(
                        radius * phi.cos() * a.cos(),
                        radius * phi.cos() * a.sin(),
                        radius * phi.sin(),
                    ))
                })
                .collect()
        })
        .collect();
    let out = |b: &Builder, t: [u32; 3]| {
        t.iter().fold(Vec3::zeros(), |s, &i| {
            s + b.mesh.vertices[i as usize].coords
        })
    };
    for k in 0..ns {
        let j = (k + 1) % ns;
        let t = [south, rings[0][k], rings[0][j]];
        let o = out(&b, t);
        b.tri(t, o);
        let last = &rings[nt - 2];
        let t = [north, last[k], last[j]];
        let o = out(&b, t);
        b.tri(t, o);
        for s in 0..nt - 2 {
            let q = [rings[s][k], rings[s][j], rings[s + 1][j], rings[s + 1][k]];
            let o = out(&b, [q[0], q[1], q[2]]) + b.mesh.vertices[q[3] as usize].coords;
            b.quad(q, o);
        }
    }
    b.mesh
}

/// A torus about the Z axis: tube centre radius `major`, tube radius `minor`,
/// `n` segments around Z and `m` around the tube: `2 n m` triangles.
pub fn torus(major: f64, minor: f64, n: usize, m: usize) -> Mesh {
    let (n, m) = (n.max(3), m.max(3));
    let mut b = Builder::new();
    let mut centres = Vec::with_capacity(n);
    let ids: Vec<Vec<u32>> = (0..n)
        .map(|i| {
            let u = std::f64::consts::TAU * i as f64 / n as f64;
            centres.push(Vec3::new(major * u.cos(), major * u.sin(), 0.0));
            (0..m)
                .map(|k| {
                    let v = std::f64::consts::TAU * k as f64 / m as f64;
                    let r = major + minor * v.cos();
                    b.vertex(Point3::new(r * u.cos(), r * u.sin(), minor * v.sin()))
                })
                .collect()
        })
        .collect();
    for i in 0..n {
        let i2 = (i + 1) % n;
        for k in 0..m {
            let k2 = (k + 1) % m;
            let q = [ids[i][k], ids[i2][k], ids[i2][k2], ids[i][k2]];
            let p = b.mesh.vertices[q[0] as usize].coords;
            b.quad(q, p - centres[i]);
        }
    }
    b.mesh
}

#[cfg(test)]
mod tests {
    // A bench that includes this file without the test harness drops the tests.
    #[allow(unused_imports)]
    use super::*;

    #[test]
    fn generated_parts_are_closed_with_the_expected_volume() {
        let p = perforated_plate((3, 2), 2.0, 5.0, 3.0, 1.5);
        assert!(p.inspect().is_watertight(), "{:?}", p.inspect());
        let (w, h) = (2.0 * 3.0 + 2.0 * 5.0 + 2.0, 2.0 * 3.0 + 5.0 + 2.0);
        let v = (w * h - 6.0 * 4.0) * 1.5;
        assert!(
            (p.signed_volume() - v).abs() < 1e-9,
            "{} vs {v}",
            p.signed_volume()
        );

        let h = plate_with_hole(10.0, 2.0, 3.0, 32);
        assert!(h.inspect().is_watertight(), "{:?}", h.inspect());
        let hole = Mesh::cylinder(3.0, 2.0, 32).signed_volume();
        assert!((h.signed_volume() - (400.0 * 2.0 - hole)).abs() < 1e-9);

        let s = sphere(5.0, 24, 12);
        assert!(s.inspect().is_watertight(), "{:?}", s.inspect());
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 125.0;
        assert!(s.signed_volume() > 0.9 * exact && s.signed_volume() < exact);

        let t = torus(10.0, 2.0, 32, 16);
        assert!(t.inspect().is_watertight(), "{:?}", t.inspect());
        let exact = 2.0 * std::f64::consts::PI.powi(2) * 10.0 * 4.0;
        assert!(t.signed_volume() > 0.9 * exact && t.signed_volume() < exact);
    }
}
