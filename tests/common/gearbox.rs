//! The generator of `models/gearbox.yaml`'s meshes (mm), shared by the sequence tests
//! and bench: a 12-part gearbox built from boxes on a grid and solids of revolution.
//!
//! - `housing`: a 100 × 40 mm block; on the left a closed pocket whose left half is
//!   roofed (the slider must slide right under the opening, then lift: no straight
//!   insertion exists), on the right a 5 mm floor with a square bore for the post.
//! - `slider`: a 12 × 18 × 6 mm block in the pocket, under the roof.
//! - `cover`: a 4 mm plate on the housing's left block, closing the pocket's opening
//!   (so the slider must go in before it); four square holes for the screws.
//! - `screw1`–`screw4`: screws through the cover into the housing.
//! - `post`, `bushing`, `gear`, `washer`, `cap`: a shaft stack on the right; the cap
//!   covers the post's top, so everything on the post goes in before it.

#![allow(dead_code)]

use fitup::math::Point3;
use fitup::mesh::Mesh;

/// A closed mesh of the filled cells of a rectilinear grid (`xs`, `ys`, `zs`
/// increasing, mm): a quad on every face between a filled and an empty cell. All
/// quads use the grid's corners, so neighbouring faces share vertices (watertight);
/// `filled` must not make cells touch along an edge only.
pub fn blocks(xs: &[f64], ys: &[f64], zs: &[f64], filled: impl Fn(Point3) -> bool) -> Mesh {
    let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
    let g = [xs, ys, zs];
    let centre = |c: [usize; 3]| {
        Point3::new(
            0.5 * (xs[c[0]] + xs[c[0] + 1]),
            0.5 * (ys[c[1]] + ys[c[1] + 1]),
            0.5 * (zs[c[2]] + zs[c[2] + 1]),
        )
    };
    let full = |c: [isize; 3]| {
        let n = [nx as isize, ny as isize, nz as isize];
        (0..3).all(|a| c[a] >= 0 && c[a] < n[a])
            && filled(centre([c[0] as usize, c[1] as usize, c[2] as usize]))
    };
    let mut soup = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let c = [i as isize, j as isize, k as isize];
                if !full(c) {
                    continue;
                }
                for axis in 0..3 {
                    for side in [0isize, 1] {
                        let mut nb = c;
                        nb[axis] += 2 * side - 1;
                        if full(nb) {
                            continue;
                        }
                        // The face's four corners, counter-clockwise seen from outside.
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let at = |du: usize, dv: usize| {
                            let mut p = [0.0; 3];
                            let idx = [i, j, k];
                            p[axis] = g[axis][idx[axis] + side as usize];
                            p[u] = g[u][idx[u] + du];
                            p[v] = g[v][idx[v] + dv];
                            Point3::new(p[0], p[1], p[2])
                        };
                        let (a, b, c2, d) = (at(0, 0), at(1, 0), at(1, 1), at(0, 1));
                        if side == 1 {
                            soup.push([a, b, c2]);
                            soup.push([a, c2, d]);
                        } else {
                            soup.push([a, c2, b]);
                            soup.push([a, d, c2]);
                        }
                    }
                }
            }
        }
    }
    let mut m = Mesh::from_triangle_soup(soup).unwrap();
    m.orient_outward();
    m
}

/// A tube about +Z from `z0` to `z1` (mm) between radii `r_in` and `r_out`.
pub fn tube(r_in: f64, r_out: f64, z0: f64, z1: f64, segments: usize) -> Mesh {
    let at = |r: f64, z: f64, k: usize| {
        let a = std::f64::consts::TAU * (k % segments) as f64 / segments as f64;
        Point3::new(r * a.cos(), r * a.sin(), z)
    };
    let profile = [(r_in, z0), (r_out, z0), (r_out, z1), (r_in, z1)];
    let mut soup = Vec::new();
    for s in 0..4 {
        let (p, q) = (profile[s], profile[(s + 1) % 4]);
        for k in 0..segments {
            soup.push([at(p.0, p.1, k), at(p.0, p.1, k + 1), at(q.0, q.1, k + 1)]);
            soup.push([at(p.0, p.1, k), at(q.0, q.1, k + 1), at(q.0, q.1, k)]);
        }
    }
    let mut m = Mesh::from_triangle_soup(soup).unwrap();
    m.orient_outward();
    m
}

/// Centres (x, y) of the four screws in the housing frame (mm).
pub const SCREWS: [(f64, f64); 4] = [(10.0, 5.0), (30.0, 5.0), (10.0, 35.0), (30.0, 35.0)];

/// The gearbox's meshes, each in its part frame, with the file it is stored in.
/// `segments`: facets around the round parts (32 for the bundled model; more for the
/// bench's fine variant).
pub fn gearbox_meshes(segments: usize) -> Vec<(&'static str, Mesh)> {
    let inside = |v: f64, lo: f64, hi: f64| v > lo && v < hi;
    let in_screw_hole = |p: &Point3| {
        SCREWS
            .iter()
            .any(|&(x, y)| inside(p.x, x - 2.0, x + 2.0) && inside(p.y, y - 2.0, y + 2.0))
    };
    let mut xs = vec![
        0.0, 5.0, 8.0, 12.0, 20.0, 28.0, 32.0, 35.0, 40.0, 65.0, 75.0, 100.0,
    ];
    xs.sort_by(f64::total_cmp);
    let ys = [0.0, 3.0, 7.0, 10.0, 15.0, 25.0, 30.0, 33.0, 37.0, 40.0];
    let housing = blocks(&xs, &ys, &[0.0, 5.0, 12.0, 20.0], |p| {
        if p.z < 5.0 {
            // The floor, with the post's square bore.
            return !(inside(p.x, 65.0, 75.0) && inside(p.y, 15.0, 25.0));
        }
        if p.x > 40.0 {
            return false;
        }
        let pocket = inside(p.x, 5.0, 35.0) && inside(p.y, 10.0, 30.0) && p.z < 12.0;
        let opening = inside(p.x, 20.0, 35.0) && inside(p.y, 10.0, 30.0) && p.z > 12.0;
        let hole = p.z > 12.0 && in_screw_hole(&p);
        !(pocket || opening || hole)
    });
    let slider = Mesh::cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(12.0, 18.0, 6.0));
    let cover = blocks(&xs[..9], &ys, &[0.0, 4.0], |p| !in_screw_hole(&p));
    // Screw: shaft r 1.8 (in a 4 mm square hole) 10 mm long, head r 3.5 2 mm high;
    // the head's underside at z = 10.
    let screw = Mesh::lathe(
        &[
            (0.0, 0.0),
            (1.8, 0.0),
            (1.8, 10.0),
            (3.5, 10.0),
            (3.5, 12.0),
            (0.0, 12.0),
        ],
        segments,
    )
    .unwrap();
    // Post: r 4.6 through the 10 mm square bore (z 0..5), a collar r 8 (z 5..7), the
    // shaft up to z 30.
    let post = Mesh::lathe(
        &[
            (0.0, 0.0),
            (4.6, 0.0),
            (4.6, 5.0),
            (8.0, 5.0),
            (8.0, 7.0),
            (4.6, 7.0),
            (4.6, 30.0),
            (0.0, 30.0),
        ],
        segments,
    )
    .unwrap();
    let bushing = tube(5.0, 8.0, 0.0, 5.0, segments);
    let gear = tube(5.0, 16.0, 0.0, 5.0, segments);
    let washer = tube(5.0, 7.0, 0.0, 1.0, segments);
    // Cap: a sleeve r 7 over the post's top, bore r 5 up to 12.5 mm, closed above.
    let cap = Mesh::lathe(
        &[
            (0.0, 12.5),
            (5.0, 12.5),
            (5.0, 0.0),
            (7.0, 0.0),
            (7.0, 14.0),
            (0.0, 14.0),
        ],
        segments,
    )
    .unwrap();
    vec![
        ("models/meshes/gearbox_housing.stl", housing),
        ("models/meshes/gearbox_slider.stl", slider),
        ("models/meshes/gearbox_cover.stl", cover),
        ("models/meshes/gearbox_screw.stl", screw),
        ("models/meshes/gearbox_post.stl", post),
        ("models/meshes/gearbox_bushing.stl", bushing),
        ("models/meshes/gearbox_gear.stl", gear),
        ("models/meshes/gearbox_washer.stl", washer),
        ("models/meshes/gearbox_cap.stl", cap),
    ]
}
