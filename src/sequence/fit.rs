//! Fits: two components that interfere in the assembled pose (a press fit, an
//! insertion that ends in contact, a part modelled through another). Between such a
//! pair the removal checks allow exactly the overlap of the assembled pose and
//! nothing else: the larger part of the pair (by volume) is taken as having the
//! room the smaller one occupies assembled cut out of it (the hole a bolt modelled
//! through a plate stands for), carried with it, and the smaller one stays whole;
//! the two then must not overlap deeper than the tolerance. The same model whichever
//! of the two moves (a relative motion gives one answer). A press-fit pin
//! slides out along its bore (its overlap with the housing stays the ring it was,
//! or shrinks), a bar modelled through a block slides out along its length (the
//! overlap shrinks); moved sideways either one enters material it did not overlap,
//! and is blocked. Units: millimetres, assembly frame.
//!
//! The test is on lines: a grid of parallel lines [`FIT_SPACING`]-like apart
//! across the region where the two can meet, each cut by the two solids into
//! intervals. Along a line, a straight translation by up to `len` along the line
//! makes new overlap exactly when the moving part's intervals swept by `len` meet
//! `q`'s outside the assembled part's: interval arithmetic, exact for the whole
//! motion (continuous along the line); only features thinner than the spacing
//! across the lines can be missed. A pose is the same test with `len` 0.

use crate::collision::{Collider, SweepMethod};
use crate::math::{Aabb, Deadline, Point3, Transform, Vec3};
use crate::planning::{stepwise_edge_free, MotionValidator};
use std::sync::Arc;

/// Most lines one check casts (the spacing is widened to stay within it).
pub(crate) const MAX_FIT_LINES: usize = 20_000;

/// The intervals `[t0, t1]` inside a solid along a line, from its sorted crossing
/// parameters (pairs; an odd count — a line grazing an edge — gives `None`).
fn intervals(hits: &[f64]) -> Option<Vec<(f64, f64)>> {
    // Crossings closer than 1e-9 mm are one (a line through a shared edge).
    let mut h: Vec<f64> = Vec::with_capacity(hits.len());
    for &t in hits {
        if h.last().is_some_and(|&l| t - l < 1e-9) {
            continue;
        }
        h.push(t);
    }
    h.len()
        .is_multiple_of(2)
        .then(|| h.chunks(2).map(|c| (c[0], c[1])).collect())
}

/// One fit pair as the checks read it: the moving part `p` (its collider and
/// assembled pose) and `q` (collider, pose, assembled and still), the line spacing
/// and the tolerance; `p_carved`: `p` is the larger of the two (the room `q` takes
/// assembled is cut out of `p`), else `q` is.
#[derive(Clone)]
pub(crate) struct FitPairCheck {
    pub p: Arc<Collider>,
    pub p_home: Transform,
    pub q: Arc<Collider>,
    pub q_pose: Transform,
    pub p_carved: bool,
    pub spacing: f64,
    pub tolerance: f64,
}

impl FitPairCheck {
    /// Whether `p` at `pose` overlaps `q` anywhere `p` at its assembled pose does
    /// not (deeper than the tolerance).
    pub(crate) fn new_overlap(&self, pose: &Transform) -> bool {
        self.translation_overlap(pose, &Vec3::x(), 0.0)
    }

    /// Whether `p` moved from `from` straight along unit `d` (world) by anything up
    /// to `len` mm overlaps `q` anywhere `p` at its assembled pose does not.
    pub(crate) fn translation_overlap(&self, from: &Transform, d: &Vec3, len: f64) -> bool {
        let tol = self.tolerance;
        let bp = self.p.world_bounds(from);
        let moved = Aabb::new(bp.lo + d * len, bp.hi + d * len);
        let swept = Aabb::new(bp.lo.inf(&moved.lo), bp.hi.sup(&moved.hi));
        let qb = self.q.world_bounds(&self.q_pose);
        if swept.overlap(&qb).min() <= tol {
            return false;
        }
        let region = Aabb::new(swept.lo.sup(&qb.lo), swept.hi.inf(&qb.hi));
        // Lines along d across the region: a frame (u, v) across d.
        let (u, v) = crate::math::frame_across(d);
        let corners: Vec<Point3> = (0..8)
            .map(|k| {
                Point3::new(
                    if k & 1 == 0 { region.lo.x } else { region.hi.x },
                    if k & 2 == 0 { region.lo.y } else { region.hi.y },
                    if k & 4 == 0 { region.lo.z } else { region.hi.z },
                )
            })
            .collect();
        let range = |e: &Vec3| {
            corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                    let x = c.coords.dot(e);
                    (a.min(x), b.max(x))
                })
        };
        let ((u0, u1), (v0, v1), (s0, _)) = (range(&u), range(&v), range(d));
        let mut h = self.spacing.max(1e-3);
        let lines = |h: f64| ((u1 - u0) / h).ceil().max(1.0) * ((v1 - v0) / h).ceil().max(1.0);
        while lines(h) > MAX_FIT_LINES as f64 {
            h *= 1.25;
        }
        let (nu, nv) = (
            ((u1 - u0) / h).ceil().max(1.0) as usize,
            ((v1 - v0) / h).ceil().max(1.0) as usize,
        );
        // Off-grid offsets keep the lines off the edges of meshes drawn on round
        // numbers.
        let (ju, jv) = (0.381_966_011 * h, 0.618_033_988 * h);
        // The cut-out room: `p` assembled (still, in `q`) or `q` assembled carried
        // along with `p`.
        let room = if self.p_carved {
            from.then(&self.p_home.inverse()).then(&self.q_pose)
        } else {
            self.p_home
        };
        let inv = [from.inverse(), room.inverse(), self.q_pose.inverse()];
        let solids = [
            &self.p,
            if self.p_carved { &self.q } else { &self.p },
            &self.q,
        ];
        let mut hits = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let a = u0 + ju + i as f64 * h;
                let b = v0 + jv + j as f64 * h;
                if a > u1 || b > v1 {
                    continue;
                }
                let o = Point3::from(u * a + v * b + d * (s0 - 1.0));
                let mut cut: [Vec<(f64, f64)>; 3] = Default::default();
                let mut ok = true;
                for k in 0..3 {
                    solids[k].line_hits(&inv[k].apply(&o), &inv[k].apply_vector(d), &mut hits);
                    match intervals(&hits) {
                        Some(iv) => cut[k] = iv,
                        None => ok = false,
                    }
                }
                let hit = if self.p_carved {
                    carved_line_overlap(&cut[0], &cut[1], &cut[2], len, tol)
                } else {
                    line_overlap(&cut[0], &cut[1], &cut[2], len, tol)
                };
                if ok && hit {
                    return true;
                }
            }
        }
        false
    }
}

/// Along one line: whether `moving` swept forward by up to `len` meets `q` deeper
/// than `tol` outside `home` (grown by `tol`).
fn line_overlap(
    moving: &[(f64, f64)],
    home: &[(f64, f64)],
    q: &[(f64, f64)],
    len: f64,
    tol: f64,
) -> bool {
    for &(a, b) in moving {
        let (a, b) = (a, b + len);
        for &(c, e) in q {
            let (lo, hi) = (a.max(c + tol), b.min(e - tol));
            if hi - lo <= tol {
                continue;
            }
            // [lo, hi] must be covered by `home` grown by the tolerance.
            let mut at = lo;
            for &(x, y) in home {
                if x - tol <= at && y + tol > at {
                    at = y + tol;
                }
            }
            if at < hi {
                return true;
            }
        }
    }
    false
}

/// Along one line: whether `moving` less its cut-out `room` (grown by `tol`),
/// swept forward by up to `len`, meets `q` deeper than `tol`.
fn carved_line_overlap(
    moving: &[(f64, f64)],
    room: &[(f64, f64)],
    q: &[(f64, f64)],
    len: f64,
    tol: f64,
) -> bool {
    // The pieces of `moving` outside the room.
    let mut left: Vec<(f64, f64)> = Vec::new();
    for &(a, b) in moving {
        let mut at = a;
        for &(x, y) in room {
            let (x, y) = (x - tol, y + tol);
            if y <= at || x >= b {
                continue;
            }
            if x > at {
                left.push((at, x));
            }
            at = at.max(y);
        }
        if at < b {
            left.push((at, b));
        }
    }
    left.iter().any(|&(a, b)| {
        let (a, b) = (a, b + len);
        q.iter()
            .any(|&(c, e)| b.min(e - tol) - a.max(c + tol) > tol)
    })
}

/// A motion validator for a part among its fit partners (one [`FitPairCheck`]
/// each): a pose is free when it makes no new overlap with any; an edge without
/// rotation is checked whole along its lines, one that turns at poses `step_mm`
/// and 0.01 rad apart.
#[derive(Clone)]
pub(crate) struct FitPairValidator {
    pub pairs: Vec<FitPairCheck>,
    pub step_mm: f64,
    pub deadline: Option<Deadline>,
}

impl FitPairValidator {
    fn late(&self) -> bool {
        self.deadline.is_some_and(Deadline::passed)
    }
}

impl MotionValidator for FitPairValidator {
    fn is_free(&mut self, pose: &Transform) -> bool {
        !self.late() && self.pairs.iter().all(|c| !c.new_overlap(pose))
    }
    fn resolution(&self) -> SweepMethod {
        SweepMethod::Stepwise {
            step_mm: self.step_mm,
            step_rad: 0.01,
        }
    }
    fn tolerance(&self) -> f64 {
        self.pairs.first().map_or(0.0, |c| c.tolerance)
    }
    fn edge_free(&mut self, from: &Transform, to: &Transform) -> bool {
        if from.rotation().angle_to(&to.rotation()) < 1e-12 {
            let shift = to.translation() - from.translation();
            let len = shift.norm();
            if len < 1e-12 {
                return self.is_free(to);
            }
            let d = shift / len;
            return !self.late()
                && self
                    .pairs
                    .iter()
                    .all(|c| !c.translation_overlap(from, &d, len));
        }
        let step = self.step_mm;
        stepwise_edge_free(|p| self.is_free(p), from, to, step, 0.01)
    }
    fn set_deadline(&mut self, deadline: Option<Deadline>) {
        self.deadline = deadline;
    }
    fn fork(&self) -> Option<Box<dyn MotionValidator + Send>> {
        let mut copy = self.clone();
        copy.deadline = None;
        Some(Box::new(copy))
    }
}
