//! The independent re-check of an assembly sequence (issue 38), shared by
//! `tests/it/sequence_fits.rs` (generated products) and `tests/it/step_corpus.rs` (real
//! CAD exports, in the `step` test binary): the parts are taken out in reverse order
//! along their paths and straight on (0.25 mm steps), each pose asked against every
//! part placed before it — the exact interference query at the default tolerance for a
//! pair without a reported fit; for a pair with one, a volume test on a grid of points
//! (no point inside both the moved part and the other that the assembled part does not
//! hold: the overlap of the assembled pose and nothing else); the reported fits must be
//! exactly the pairs that interfere in the assembled pose. A reported fit no deeper
//! than `slide_fit_mm` may instead slide: a pose that is the assembled one moved
//! straight along `d` passes when, on every line parallel to `d` (a grid of its own,
//! cut by the meshes' triangles directly, not by the library's colliders), each
//! stretch of the moved part overlaps only the stretches of the other it overlapped
//! assembled, by no more than assembled (within the tolerance).

use fitup::collision::{interferes, Collider, DEFAULT_TOLERANCE};
use fitup::document::Document;
use fitup::math::{Aabb, Point3, Transform, Vec3};
use fitup::mesh::Mesh;
use fitup::sequence::{SequenceOptions, SequencePlan};
use fitup::workspace::{SceneCache, Workspace};

/// The independent check of one pose of `p` against `q` (assembled): a pair with a
/// reported fit may overlap only where the two overlapped assembled — the larger of
/// the two has the smaller's assembled room cut out of it, carried with it — and
/// any other pair may interfere by the tolerance.
pub(crate) struct Checker<'a> {
    doc: &'a Document,
    colliders: Vec<std::sync::Arc<Collider>>,
    poses: Vec<Transform>,
    /// The reported fits (by index).
    fits: Vec<(usize, usize)>,
    /// The tolerance the plan used (the default, or the document's mesh deflection).
    tolerance: f64,
    /// The reported fits' depths (by index pair, either order).
    depths: Vec<((usize, usize), f64)>,
    /// Fits no deeper than this may slide (the option the plan was made with).
    pub(crate) slide_fit_mm: f64,
    /// The slide lines already cut, per pair and direction.
    slide_cache: SlideCache,
}

/// A slide check's lines: the moving part, the still one, the direction (rounded).
type SlideKey = (usize, usize, [i64; 3]);

/// The slide lines cut so far.
type SlideCache =
    std::cell::RefCell<std::collections::HashMap<SlideKey, std::rc::Rc<Vec<SlideLine>>>>;

/// One line of a slide check: the moving part's intervals at its assembled pose and
/// the still part's, as parameters along the line.
struct SlideLine {
    p: Vec<(f64, f64)>,
    q: Vec<(f64, f64)>,
}

/// Most lines of one slide check.
const SLIDE_LINES: f64 = 12_000.0;

/// The world triangles of a mesh at a pose.
fn world_triangles(mesh: &Mesh, pose: &Transform) -> Vec<[Point3; 3]> {
    (0..mesh.triangles.len())
        .map(|i| mesh.triangle(i).map(|v| pose.apply(&v)))
        .collect()
}

/// The intervals inside a closed mesh along the lines `u a + v b + t d` of a grid
/// (`a = a0 + i h`, `b = b0 + j h`, `n.0 × n.1` lines): each triangle is handed to
/// the lines its shadow across `d` covers, and cut there (Möller–Trumbore, `t` of
/// any sign). A line with an odd count of crossings (through an edge) gives `None`.
fn grid_intervals(
    tris: &[[Point3; 3]],
    (u, v, d): (&Vec3, &Vec3, &Vec3),
    (a0, b0, h): (f64, f64, f64),
    n: (usize, usize),
) -> Vec<Option<Vec<(f64, f64)>>> {
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); n.0 * n.1];
    for (k, t) in tris.iter().enumerate() {
        let us = t.map(|p| p.coords.dot(u));
        let vs = t.map(|p| p.coords.dot(v));
        let lo = |x: [f64; 3], o: f64| ((x[0].min(x[1]).min(x[2]) - o) / h).ceil().max(0.0);
        let hi = |x: [f64; 3], o: f64| ((x[0].max(x[1]).max(x[2]) - o) / h).floor();
        let (i0, i1) = (lo(us, a0), hi(us, a0).min(n.0 as f64 - 1.0));
        let (j0, j1) = (lo(vs, b0), hi(vs, b0).min(n.1 as f64 - 1.0));
        if i1 < i0 || j1 < j0 {
            continue;
        }
        for i in i0 as usize..=i1 as usize {
            for j in j0 as usize..=j1 as usize {
                cells[i * n.1 + j].push(k as u32);
            }
        }
    }
    let mut out = Vec::with_capacity(n.0 * n.1);
    for i in 0..n.0 {
        for j in 0..n.1 {
            let o = Point3::from(u * (a0 + i as f64 * h) + v * (b0 + j as f64 * h));
            let mut ts: Vec<f64> = cells[i * n.1 + j]
                .iter()
                .filter_map(|&k| {
                    let [p0, p1, p2] = tris[k as usize];
                    let (e1, e2) = (p1 - p0, p2 - p0);
                    let pv = d.cross(&e2);
                    let det = e1.dot(&pv);
                    if det.abs() < 1e-14 {
                        return None;
                    }
                    let s = o - p0;
                    let bu = s.dot(&pv) / det;
                    let qv = s.cross(&e1);
                    let bv = d.dot(&qv) / det;
                    (bu >= 0.0 && bv >= 0.0 && bu + bv <= 1.0).then(|| e2.dot(&qv) / det)
                })
                .collect();
            ts.sort_by(f64::total_cmp);
            ts.dedup_by(|b, a| *b - *a < 1e-9);
            out.push(
                ts.len()
                    .is_multiple_of(2)
                    .then(|| ts.chunks(2).map(|c| (c[0], c[1])).collect()),
            );
        }
    }
    out
}

/// Most grid points one fit check asks (the grid is as fine as this allows).
const GRID_POINTS: f64 = 4_000.0;

impl Checker<'_> {
    fn fit(&self, p: usize, q: usize) -> bool {
        self.fits.contains(&(p, q)) || self.fits.contains(&(q, p))
    }

    /// Whether the reported fit of `p` and `q` may slide (no deeper than
    /// `slide_fit_mm`).
    fn slides(&self, p: usize, q: usize) -> bool {
        self.depths
            .iter()
            .any(|&((a, b), depth)| (a, b) == (p.min(q), p.max(q)) && depth <= self.slide_fit_mm)
    }

    /// The lines of the slide check of `p` along unit `d` against `q`: every line
    /// along `d` on which `p` slid any distance can meet `q`.
    fn slide_lines(&self, p: usize, q: usize, d: &Vec3) -> std::rc::Rc<Vec<SlideLine>> {
        let key = (p, q, d.map(|x| (x * 1e6).round() as i64).into());
        if let Some(l) = self.slide_cache.borrow().get(&key) {
            return l.clone();
        }
        let (u, v) = fitup::math::frame_across(d);
        let span = |b: &Aabb, e: &Vec3| {
            (0..8).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), k| {
                let c = Vec3::new(
                    if k & 1 == 0 { b.lo.x } else { b.hi.x },
                    if k & 2 == 0 { b.lo.y } else { b.hi.y },
                    if k & 4 == 0 { b.lo.z } else { b.hi.z },
                );
                (lo.min(c.dot(e)), hi.max(c.dot(e)))
            })
        };
        let (bp, bq) = (
            self.colliders[p].world_bounds(&self.poses[p]),
            self.colliders[q].world_bounds(&self.poses[q]),
        );
        let across = |e: &Vec3| {
            let (a, b) = (span(&bp, e), span(&bq, e));
            (a.0.max(b.0), a.1.min(b.1))
        };
        let ((u0, u1), (v0, v1)) = (across(&u), across(&v));
        let mut lines = Vec::new();
        if u1 > u0 && v1 > v0 {
            let h = ((u1 - u0) * (v1 - v0) / SLIDE_LINES).sqrt().max(1e-3);
            let n = (
                ((u1 - u0) / h).ceil() as usize,
                ((v1 - v0) / h).ceil() as usize,
            );
            // Offsets of its own (not the library's), off round numbers.
            let (a0, b0) = (u0 + 0.271_828 * h, v0 + 0.732_050 * h);
            let cut = |i: usize| {
                grid_intervals(
                    &world_triangles(self.doc.mesh_of(i), &self.poses[i]),
                    (&u, &v, d),
                    (a0, b0, h),
                    n,
                )
            };
            for (lp, lq) in cut(p).into_iter().zip(cut(q)) {
                if let (Some(p), Some(q)) = (lp, lq) {
                    if !p.is_empty() && !q.is_empty() {
                        lines.push(SlideLine { p, q });
                    }
                }
            }
        }
        let lines = std::rc::Rc::new(lines);
        self.slide_cache.borrow_mut().insert(key, lines.clone());
        lines
    }

    /// Whether `p` at `pose` is refused by the slide rule against `q`: `pose` is
    /// not the assembled one moved straight (same orientation), or along some line
    /// of the motion a stretch of `p` overlaps a stretch of `q` it did not overlap
    /// assembled, or one it did by more (beyond the tolerance).
    fn slide_hits(&self, p: usize, pose: &Transform, q: usize) -> bool {
        let home = &self.poses[p];
        if pose.rotation().angle_to(&home.rotation()) > 1e-9 {
            return true;
        }
        let shift = pose.translation() - home.translation();
        let s = shift.norm();
        if s < 1e-9 {
            return true;
        }
        let tol = self.tolerance;
        self.slide_lines(p, q, &(shift / s)).iter().any(|line| {
            line.p.iter().any(|&(a, b)| {
                line.q.iter().any(|&(c, e)| {
                    let over = |s: f64| (b + s).min(e) - (a + s).max(c);
                    let home = over(0.0);
                    over(s) > if home > tol { home + tol } else { tol }
                })
            })
        })
    }

    /// The surface distance of `p` and `q` at their poses, asked up to `bound` mm.
    pub(crate) fn clearance(&self, p: usize, q: usize, bound: f64) -> f64 {
        fitup::collision::clearance(
            &self.colliders[p],
            &self.poses[p],
            &self.colliders[q],
            &self.poses[q],
            bound,
        )
        .unwrap()
    }

    /// Whether `p` at `pose` is refused against `q`.
    pub(crate) fn hits(&self, p: usize, pose: &Transform, q: usize) -> bool {
        let (cp, cq, pq) = (&self.colliders[p], &self.colliders[q], &self.poses[q]);
        if !self.fit(p, q) {
            return interferes(cp, pose, cq, pq, self.tolerance).unwrap();
        }
        // The volume both `p` at `pose` and `q` hold, sampled on a grid: each point
        // deeper than the tolerance in both must lie in the cut-out room (or within
        // the tolerance of it): `p` assembled when `q` is the larger, else `q`
        // assembled carried along with `p`.
        let volume = |i: usize| self.doc.mesh_of(i).signed_volume().abs();
        let p_carved = volume(p) > volume(q) || (volume(p) == volume(q) && p < q);
        let room_of = |w: &Point3| -> (bool, Point3) {
            if p_carved {
                (
                    true,
                    self.poses[q]
                        .inverse()
                        .apply(&self.poses[p].apply(&pose.inverse().apply(w))),
                )
            } else {
                (false, self.poses[p].inverse().apply(w))
            }
        };
        let tol = self.tolerance;
        let (bp, bq) = (cp.world_bounds(pose), cq.world_bounds(pq));
        let lo = bp.lo.sup(&bq.lo);
        let hi = bp.hi.inf(&bq.hi);
        let size = hi - lo;
        if size.min() <= tol {
            return false;
        }
        let g = (size.x * size.y * size.z / GRID_POINTS).cbrt();
        let n = size.map(|v| (v / g).ceil().max(1.0) as usize);
        let deep =
            |c: &Collider, x: &Point3| c.contains_point(x) && c.distance_to_point(x, tol) > tol;
        let (inv_p, inv_q) = (pose.inverse(), pq.inverse());
        for i in 0..n.x {
            for j in 0..n.y {
                for k in 0..n.z {
                    let w = Point3::new(
                        lo.x + (i as f64 + 0.5) * size.x / n.x as f64,
                        lo.y + (j as f64 + 0.5) * size.y / n.y as f64,
                        lo.z + (k as f64 + 0.5) * size.z / n.z as f64,
                    );
                    if deep(cp, &inv_p.apply(&w)) && deep(cq, &inv_q.apply(&w)) {
                        let (in_q, h) = room_of(&w);
                        let room: &Collider = if in_q { cq } else { cp };
                        if !room.contains_point(&h) && room.distance_to_point(&h, tol) > tol {
                            // Outside the room: refused unless the fit slides
                            // and the pose is a slide the rule allows.
                            return !self.slides(p, q) || self.slide_hits(p, pose, q);
                        }
                    }
                }
            }
        }
        false
    }
}

pub(crate) fn checker<'a>(doc: &'a Document, plan: &SequencePlan) -> Checker<'a> {
    let mut cache = SceneCache::new();
    let ws = Workspace::new(doc, &mut cache).unwrap();
    let scene = ws.scene();
    let idx = |n: &str| doc.component_index(n).unwrap();
    Checker {
        doc,
        colliders: scene.colliders.clone(),
        poses: scene.poses.clone(),
        fits: plan.fits.iter().map(|f| (idx(&f.a), idx(&f.b))).collect(),
        tolerance: DEFAULT_TOLERANCE.max(doc.mesh_deflection().unwrap_or(0.0)),
        depths: plan
            .fits
            .iter()
            .map(|f| {
                let (a, b) = (idx(&f.a), idx(&f.b));
                ((a.min(b), a.max(b)), f.depth)
            })
            .collect(),
        slide_fit_mm: SequenceOptions::default().slide_fit_mm,
        slide_cache: Default::default(),
    }
}

/// The reported fits are exactly the pairs that interfere in the assembled pose
/// (default tolerance, or the document's mesh deflection when coarser, as the plan
/// says it used), each deeper than that.
pub(crate) fn fits_are_exact(c: &Checker, plan: &SequencePlan) {
    assert_eq!(
        plan.tolerance, c.tolerance,
        "the tolerance the plan says it used"
    );
    let n = c.colliders.len();
    for p in 0..n {
        for q in p + 1..n {
            let (cp, cq) = (&c.colliders[p], &c.colliders[q]);
            let (pp, pq) = (&c.poses[p], &c.poses[q]);
            let interfering = interferes(cp, pp, cq, pq, c.tolerance).unwrap();
            let names = (&c.doc.components()[p].name, &c.doc.components()[q].name);
            assert_eq!(
                interfering,
                c.fit(p, q),
                "{names:?}: interfering {interfering}, fits {:?}",
                plan.fits
            );
        }
    }
    for f in &plan.fits {
        assert!(f.depth > c.tolerance, "{f:?}");
    }
}

/// The dense removal re-check (see the module docs).
pub(crate) fn dense_removal(c: &Checker, plan: &SequencePlan) {
    assert!(!plan.sequences.is_empty());
    let doc = c.doc;
    for s in &plan.sequences {
        let order = s.order();
        let idx = super::component_indices(doc, &order);
        assert_eq!(super::distinct(&idx), doc.components().len(), "{order:?}");
        for k in (0..s.tasks.len()).rev() {
            let t = &s.tasks[k];
            let p = idx[k + 1];
            let before = &idx[..k + 1];
            let bounds = |i: usize, pose: &Transform| c.colliders[i].world_bounds(pose);
            let region = before
                .iter()
                .map(|&q| bounds(q, &c.poses[q]))
                .reduce(|a, b| Aabb::new(a.lo.inf(&b.lo), a.hi.sup(&b.hi)))
                .unwrap();
            let check = |pose: &Transform, what: &str| {
                for &q in before {
                    assert!(
                        !c.hits(p, pose, q),
                        "{order:?}: removing {} ({what}, at {:?}, mating {:?}) hits {}",
                        t.part,
                        pose.translation(),
                        t.mating_direction,
                        doc.components()[q].name
                    );
                }
            };
            let way: Vec<Transform> = t.path.poses.iter().rev().copied().collect();
            assert!(
                way[0].approx_eq(&c.poses[p], 1e-9, 1e-9),
                "starts assembled"
            );
            check(&way[0], "assembled");
            // Every 0.25 mm and 0.01 rad along the planned path.
            for q in t.path.densify(0.25, 0.01).expect("a finite path") {
                check(&q, "along its path");
            }
            let out =
                super::straight_on_until_clear(&way, -t.mating_direction, 0.25, &region, |at| {
                    bounds(p, at)
                });
            for at in out {
                check(&at, "straight on");
            }
        }
    }
}
