//! Seed 000's "finite subdivision": a part cut by arrays of planes into cells, one
//! box per cell, and the box tests of the `aabb` and `cells` methods.

use super::shape::Collider;
use super::{CellsFault, CollisionError, Contact, InterferenceKind, Method, PoseFault, PosedPart};
use crate::math::{Aabb, Point3, Rng, Transform};

/// Most cells a cut may make.
pub const MAX_CELLS: usize = 100_000;

/// How a part is cut (the feature's definition, stored in the document).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CutSpec {
    /// Cubic cells of this edge (mm): plane arrays along X, Y and Z starting at the
    /// min faces of the part's bounds, stopping at the far faces (seed 000).
    Size(f64),
    /// Explicit cut planes, positions in the part frame (mm) along each axis;
    /// positions outside the part's bounds are ignored.
    Planes {
        /// Planes `x = const`.
        x: Vec<f64>,
        /// Planes `y = const`.
        y: Vec<f64>,
        /// Planes `z = const`.
        z: Vec<f64>,
    },
}

/// One cell of a cut part: the part's material inside one grid cell.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Cell {
    /// Grid position (along X, Y, Z).
    pub index: [u32; 3],
    /// The box of the material in the cell, part frame, mm.
    pub bounds: Aabb,
}

/// The cut-cells feature: its definition and the cells derived from the mesh.
///
/// Each cell's box bounds the part's material inside the grid cell: the surface
/// clipped to the cell plus, for solid meshes, the cell corners inside the
/// material (so cells deep inside material are full boxes). Cells without
/// material are omitted, like the seed's cut bodies.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CutCells {
    /// The definition.
    pub spec: CutSpec,
    /// Grid cells along X, Y, Z.
    pub grid: [u32; 3],
    /// Cells with material.
    pub cells: Vec<Cell>,
}

fn boundaries(lo: f64, hi: f64, spec: &CutSpec, axis: usize) -> Result<Vec<f64>, CollisionError> {
    let mut v = vec![lo];
    match spec {
        CutSpec::Size(s) => {
            let n = ((hi - lo) / s).ceil().max(1.0) as usize;
            for k in 1..n {
                let p = lo + k as f64 * s;
                if p < hi {
                    v.push(p);
                }
            }
        }
        CutSpec::Planes { x, y, z } => {
            let planes = [x, y, z][axis];
            if let Some(p) = planes.iter().find(|p| !p.is_finite()) {
                return Err(CollisionError::BadCells(CellsFault::PlanePosition(*p)));
            }
            let mut inner: Vec<f64> = planes
                .iter()
                .copied()
                .filter(|&p| p > lo && p < hi)
                .collect();
            inner.sort_by(f64::total_cmp);
            inner.dedup();
            v.extend(inner);
        }
    }
    v.push(hi);
    Ok(v)
}

impl CutCells {
    /// Cuts the part of `collider` by `spec`.
    ///
    /// Errors: a cell size that is not a finite number > 0, non-finite plane
    /// positions, or more than [`MAX_CELLS`] grid cells (the message names the count).
    pub fn derive(collider: &Collider, spec: CutSpec) -> Result<CutCells, CollisionError> {
        let b = collider.bounds();
        let ext = b.hi - b.lo;
        let counts: [f64; 3] = match &spec {
            CutSpec::Size(s) => {
                if !(s.is_finite() && *s > 0.0) {
                    return Err(CollisionError::BadCells(CellsFault::CellSize(*s)));
                }
                [0, 1, 2].map(|k| (ext[k] / s).ceil().max(1.0))
            }
            CutSpec::Planes { x, y, z } => [x, y, z].map(|p| p.len() as f64 + 1.0),
        };
        let total = counts[0] * counts[1] * counts[2];
        if total > MAX_CELLS as f64 {
            return Err(CollisionError::TooManyCells {
                count: total.min(u128::MAX as f64) as u128,
                nx: counts[0].min(u64::MAX as f64) as u64,
                ny: counts[1].min(u64::MAX as f64) as u64,
                nz: counts[2].min(u64::MAX as f64) as u64,
                limit: MAX_CELLS,
            });
        }
        let planes = [
            boundaries(b.lo.x, b.hi.x, &spec, 0)?,
            boundaries(b.lo.y, b.hi.y, &spec, 1)?,
            boundaries(b.lo.z, b.hi.z, &spec, 2)?,
        ];
        let n = [0, 1, 2].map(|k| planes[k].len() - 1);
        let at = |i: usize, j: usize, k: usize| (k * n[1] + j) * n[0] + i;
        let mut boxes = vec![Aabb::EMPTY; n[0] * n[1] * n[2]];
        // range of cells a coordinate interval touches (closed)
        let span = |axis: usize, lo: f64, hi: f64| {
            let p = &planes[axis];
            let first = p[1..p.len() - 1].partition_point(|&v| v < lo);
            let last = p[1..p.len() - 1].partition_point(|&v| v <= hi);
            first..=last.min(n[axis] - 1)
        };
        let solid = collider.is_solid();
        for t in collider.tris() {
            let mut tb = Aabb::EMPTY;
            t.iter().for_each(|p| tb.grow(p));
            let poly: Vec<Point3> = t.to_vec();
            // A face lying in a cut plane bounds material on one side only: it belongs
            // to the cell its outward normal leaves through (else hole cells whose
            // walls are cut planes would get boxes).
            let normal = (t[1] - t[0]).cross(&(t[2] - t[0]));
            // a clip reduced to a cell face by a triangle that leaves the cell there
            // bounds material outside it
            let grazes = |poly: &[Point3], axis: usize, cell: usize| {
                let flat = t[1][axis] == t[0][axis] && t[2][axis] == t[0][axis];
                let p = &planes[axis];
                !flat
                    && (poly.iter().all(|q| q[axis] == p[cell])
                        || poly.iter().all(|q| q[axis] == p[cell + 1]))
            };
            let keep = |axis: usize, cell: usize| {
                let c = t[0][axis];
                if !solid || t[1][axis] != c || t[2][axis] != c {
                    return true;
                }
                let p = &planes[axis];
                !((p[cell + 1] == c && normal[axis] < 0.0) || (p[cell] == c && normal[axis] > 0.0))
            };
            for i in span(0, tb.lo.x, tb.hi.x) {
                if !keep(0, i) {
                    continue;
                }
                let px = clip(
                    &clip(&poly, 0, planes[0][i], true),
                    0,
                    planes[0][i + 1],
                    false,
                );
                if px.is_empty() || grazes(&px, 0, i) {
                    continue;
                }
                let mut bx = Aabb::EMPTY;
                px.iter().for_each(|p| bx.grow(p));
                for j in span(1, bx.lo.y, bx.hi.y) {
                    if !keep(1, j) {
                        continue;
                    }
                    let py = clip(
                        &clip(&px, 1, planes[1][j], true),
                        1,
                        planes[1][j + 1],
                        false,
                    );
                    if py.is_empty() || grazes(&py, 1, j) {
                        continue;
                    }
                    let mut by = Aabb::EMPTY;
                    py.iter().for_each(|p| by.grow(p));
                    for k in span(2, by.lo.z, by.hi.z) {
                        if !keep(2, k) {
                            continue;
                        }
                        let pz = clip(
                            &clip(&py, 2, planes[2][k], true),
                            2,
                            planes[2][k + 1],
                            false,
                        );
                        if grazes(&pz, 2, k) {
                            continue;
                        }
                        let cell = &mut boxes[at(i, j, k)];
                        pz.iter().for_each(|p| cell.grow(p));
                    }
                }
            }
        }
        if solid {
            // A corner is classified for each of its cells by a point a hair inside
            // that cell: grid lines often lie in face planes (the first planes are the
            // bounds' faces) where parity is undefined, and a corner on the material's
            // boundary belongs only to the cells the material extends into.
            let h = (0..3)
                .flat_map(|a| planes[a].windows(2).map(|w| w[1] - w[0]))
                .fold(f64::INFINITY, f64::min);
            let (dx, dy, dz) = (0.613e-6 * h, 0.707e-6 * h, 0.577e-6 * h);
            let mut xs = Vec::new();
            for (k, &z) in planes[2].iter().enumerate() {
                for (j, &y) in planes[1].iter().enumerate() {
                    for (up_y, up_z) in [(false, false), (false, true), (true, false), (true, true)]
                    {
                        let cj = if up_y { j } else { j.wrapping_sub(1) };
                        let ck = if up_z { k } else { k.wrapping_sub(1) };
                        if cj >= n[1] || ck >= n[2] {
                            continue;
                        }
                        let sy = if up_y { dy } else { -dy };
                        let sz = if up_z { dz } else { -dz };
                        collider.x_line_crossings(y + sy, z + sz, &mut xs);
                        if xs.is_empty() {
                            continue;
                        }
                        xs.sort_by(f64::total_cmp);
                        for (i, &x) in planes[0].iter().enumerate() {
                            for up_x in [false, true] {
                                let ci = if up_x { i } else { i.wrapping_sub(1) };
                                if ci >= n[0] {
                                    continue;
                                }
                                let probe = if up_x { x + dx } else { x - dx };
                                let beyond = xs.len() - xs.partition_point(|&c| c <= probe);
                                if beyond % 2 == 1 {
                                    boxes[at(ci, cj, ck)].grow(&Point3::new(x, y, z));
                                }
                            }
                        }
                    }
                }
            }
        }
        let mut cells = Vec::new();
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let bx = &boxes[at(i, j, k)];
                    if !bx.is_empty() {
                        cells.push(Cell {
                            index: [i as u32, j as u32, k as u32],
                            bounds: *bx,
                        });
                    }
                }
            }
        }
        Ok(CutCells {
            spec,
            grid: n.map(|v| v as u32),
            cells,
        })
    }

    /// The cells' boxes, part frame, mm.
    pub fn boxes(&self) -> Vec<Aabb> {
        self.cells.iter().map(|c| c.bounds).collect()
    }
}

/// Sutherland–Hodgman clip of a convex polygon to the closed half-space
/// `p[axis] >= at` (`keep_above`) or `p[axis] <= at`.
fn clip(poly: &[Point3], axis: usize, at: f64, keep_above: bool) -> Vec<Point3> {
    let inside = |p: &Point3| {
        if keep_above {
            p[axis] >= at
        } else {
            p[axis] <= at
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (i, p) in poly.iter().enumerate() {
        let q = &poly[(i + 1) % poly.len()];
        let (pi, qi) = (inside(p), inside(q));
        if pi {
            out.push(*p);
        }
        if pi != qi {
            let s = (at - p[axis]) / (q[axis] - p[axis]);
            let mut x = p + (q - p) * s;
            x[axis] = at;
            out.push(x);
        }
    }
    out
}

/// The boxes method on two sets of part-frame boxes: each box is moved to the world
/// and replaced by the world axis-aligned box around it (as the seed reads cut
/// bodies' boxes in the assembly frame); two boxes interfere when they overlap by
/// more than `tolerance` (mm) along all three axes, touch when they overlap by at
/// least -1e-9 × size. Depth: the largest, over box pairs, of the smallest axis
/// overlap.
pub(crate) fn boxes_contact(
    a: &[Aabb],
    pa: &Transform,
    b: &[Aabb],
    pb: &Transform,
    tolerance: f64,
) -> Result<Contact, CollisionError> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(CollisionError::BadTolerance(tolerance));
    }
    if !(pa.is_finite() && pb.is_finite()) {
        return Err(CollisionError::BadPose(PoseFault::Part));
    }
    let world = |boxes: &[Aabb], p: &Transform| -> Vec<Aabb> {
        boxes.iter().map(|x| x.transformed(p.isometry())).collect()
    };
    let (wa, wb) = (world(a, pa), world(b, pb));
    let union = |v: &[Aabb]| v.iter().fold(Aabb::EMPTY, |u, x| u.union(x));
    let (ua, ub) = (union(&wa), union(&wb));
    let scale = ua.hi.coords.amax().max(ub.hi.coords.amax()).abs().max(1.0);
    let slack = 1e-9 * scale;
    let near = |x: &Aabb, u: &Aabb| x.overlap(u).min() >= -slack;
    let wb: Vec<Aabb> = wb.into_iter().filter(|x| near(x, &ua)).collect();
    let mut touching = false;
    let mut depth = f64::NEG_INFINITY;
    for x in wa.iter().filter(|x| near(x, &ub)) {
        for y in &wb {
            let o = x.overlap(y).min();
            if o > tolerance {
                depth = depth.max(o);
            } else if o >= -slack {
                touching = true;
            }
        }
    }
    Ok(if depth > tolerance {
        Contact::Interfering {
            depth,
            kind: InterferenceKind::BoxesOverlap,
        }
    } else if touching {
        Contact::Touching
    } else {
        Contact::Separate
    })
}

/// The cells method for two cut parts (a convenience over [`super::check`]).
pub fn cells_contact(
    a: &Collider,
    cells_a: &CutCells,
    pa: &Transform,
    b: &Collider,
    cells_b: &CutCells,
    pb: &Transform,
    tolerance: f64,
) -> Result<Contact, CollisionError> {
    super::check(
        Method::Cells,
        &PosedPart {
            collider: a,
            cells: Some(cells_a),
            pose: *pa,
        },
        &PosedPart {
            collider: b,
            cells: Some(cells_b),
            pose: *pb,
        },
        tolerance,
    )
}

/// How often the approximate methods disagree with the exact one over random poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Disagreement {
    /// Poses tried.
    pub samples: usize,
    /// Poses where the exact method reports interference.
    pub exact_interfering: usize,
    /// Poses where the cells method reports interference.
    pub cells_interfering: usize,
    /// Cells says interfering, exact does not.
    pub cells_false_positives: usize,
    /// Exact says interfering, cells does not.
    pub cells_false_negatives: usize,
    /// Whole-part boxes say interfering, exact does not.
    pub aabb_false_positives: usize,
    /// Exact says interfering, whole-part boxes do not.
    pub aabb_false_negatives: usize,
}

impl Disagreement {
    /// Fraction of poses where cells and exact differ.
    pub fn cells_rate(&self) -> f64 {
        (self.cells_false_positives + self.cells_false_negatives) as f64
            / self.samples.max(1) as f64
    }

    /// Fraction of poses where whole-part boxes and exact differ.
    pub fn aabb_rate(&self) -> f64 {
        (self.aabb_false_positives + self.aabb_false_negatives) as f64 / self.samples.max(1) as f64
    }
}

/// Compares the cells and aabb methods with the exact one on `samples` poses of
/// `moving` drawn by `sample_pose` from an [`Rng`] seeded with `seed`, against the
/// parts of `fixed` (the moving part is checked against each; a pose counts as
/// interfering when it interferes with any of them).
pub fn method_disagreement(
    fixed: &[PosedPart],
    moving: (&Collider, Option<&CutCells>),
    mut sample_pose: impl FnMut(&mut Rng) -> Transform,
    samples: usize,
    seed: u64,
    tolerance: f64,
) -> Result<Disagreement, CollisionError> {
    let mut rng = Rng::new(seed);
    let mut d = Disagreement {
        samples,
        ..Default::default()
    };
    for _ in 0..samples {
        let m = PosedPart {
            collider: moving.0,
            cells: moving.1,
            pose: sample_pose(&mut rng),
        };
        let mut verdict = [false; 3];
        for f in fixed {
            for (v, method) in verdict
                .iter_mut()
                .zip([Method::Exact, Method::Cells, Method::Aabb])
            {
                if !*v {
                    *v = super::check(method, f, &m, tolerance)?.is_interfering();
                }
            }
        }
        let [exact, cells, aabb] = verdict;
        d.exact_interfering += exact as usize;
        d.cells_interfering += cells as usize;
        d.cells_false_positives += (cells && !exact) as usize;
        d.cells_false_negatives += (exact && !cells) as usize;
        d.aabb_false_positives += (aabb && !exact) as usize;
        d.aabb_false_negatives += (exact && !aabb) as usize;
    }
    Ok(d)
}
