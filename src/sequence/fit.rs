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
//! A *sliding* fit (no deeper than `slide_fit_mm`: a press fit, a card modelled a
//! little wider than the guides it slides down, a servo through a thin rib of its
//! mount) may also slide: a straight motion from the assembled pose along `d` is
//! allowed when, along every line parallel to `d`, each stretch of the moving part
//! overlaps only the stretches of the other it overlapped assembled, and each by no
//! more than assembled (within the tolerance). Along its bore or guides the overlap
//! then keeps its length or shrinks, whichever part is larger; across them, or
//! deeper into a blind bore, it grows or meets new material, and is refused. A
//! deeper fit (a bolt modelled through a plate without its hole) keeps the cut-out
//! model only: slid sideways its overlap keeps its length too, but through material
//! the hole does not cross.
//!
//! The test is on lines: a grid of parallel lines `spacing` apart (wider when more
//! than [`MAX_FIT_LINES`] would be cast)
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
/// assembled is cut out of `p`), else `q` is; `slides`: the fit is no deeper than
/// `slide_fit_mm` (a straight motion from the assembled pose may also slide, see
/// the module docs).
#[derive(Clone)]
pub(crate) struct FitPairCheck {
    pub p: Arc<Collider>,
    pub p_home: Transform,
    pub q: Arc<Collider>,
    pub q_pose: Transform,
    pub p_carved: bool,
    pub slides: bool,
    pub spacing: f64,
    pub tolerance: f64,
}

/// The lines of a check: `nu × nv` lines along `d` through `region`, `h` apart,
/// starting 1 mm before it; `origin(i, j)` is the start of line `(i, j)` or `None`
/// off the region.
struct Lines {
    u: Vec3,
    v: Vec3,
    d: Vec3,
    u0: f64,
    u1: f64,
    v0: f64,
    v1: f64,
    s0: f64,
    h: f64,
    nu: usize,
    nv: usize,
}

impl Lines {
    fn new(region: &Aabb, d: &Vec3, spacing: f64) -> Lines {
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
        let mut h = spacing.max(1e-3);
        let lines = |h: f64| ((u1 - u0) / h).ceil().max(1.0) * ((v1 - v0) / h).ceil().max(1.0);
        while lines(h) > MAX_FIT_LINES as f64 {
            h *= 1.25;
        }
        Lines {
            u,
            v,
            d: *d,
            u0,
            u1,
            v0,
            v1,
            s0,
            h,
            nu: ((u1 - u0) / h).ceil().max(1.0) as usize,
            nv: ((v1 - v0) / h).ceil().max(1.0) as usize,
        }
    }

    fn origin(&self, i: usize, j: usize) -> Option<Point3> {
        // Off-grid offsets keep the lines off the edges of meshes drawn on round
        // numbers.
        let a = self.u0 + 0.381_966_011 * self.h + i as f64 * self.h;
        let b = self.v0 + 0.618_033_988 * self.h + j as f64 * self.h;
        (a <= self.u1 && b <= self.v1)
            .then(|| Point3::from(self.u * a + self.v * b + self.d * (self.s0 - 1.0)))
    }
}

/// The intervals of `solid` at `pose` along the world line `o + t d` (`None`: a
/// line grazing an edge, an odd count of crossings).
fn cut(
    solid: &Collider,
    inv: &Transform,
    o: &Point3,
    d: &Vec3,
    hits: &mut Vec<f64>,
) -> Option<Vec<(f64, f64)>> {
    solid.line_hits(&inv.apply(o), &inv.apply_vector(d), hits);
    intervals(hits)
}

/// The longest overlap of `[a + s, b + s]` with `[c, e]` for `s` in `[s0, s1]`:
/// the overlap is concave in `s` where positive, flat around the shift that
/// centres one on the other, so its maximum is at that shift clamped to the range.
fn most_overlap((a, b): (f64, f64), (c, e): (f64, f64), s0: f64, s1: f64) -> f64 {
    let s = (0.5 * (c + e - a - b)).clamp(s0, s1);
    (b + s).min(e) - (a + s).max(c)
}

impl FitPairCheck {
    /// Whether `p` at `pose` overlaps `q` anywhere `p` at its assembled pose does
    /// not (deeper than the tolerance); a sliding fit: unless `pose` is the
    /// assembled one slid straight along a line within the slide rule.
    pub(crate) fn new_overlap(&self, pose: &Transform) -> bool {
        if let Some((d, s)) = self.slid(pose) {
            if !self.slide_overlap(&d, s, s) {
                return false;
            }
        }
        self.carved_overlap(pose, &Vec3::x(), 0.0)
    }

    /// Whether `p` moved from `from` straight along unit `d` (world) by anything up
    /// to `len` mm overlaps `q` anywhere `p` at its assembled pose does not; a
    /// sliding fit: unless the motion lies on a line through the assembled pose and
    /// keeps to the slide rule.
    pub(crate) fn translation_overlap(&self, from: &Transform, d: &Vec3, len: f64) -> bool {
        if let Some(a) = self.offset_along(from, d) {
            if !self.slide_overlap(d, a, a + len) {
                return false;
            }
        }
        self.carved_overlap(from, d, len)
    }

    /// A sliding fit's `pose` as the assembled one moved straight along unit `d`
    /// by `s` > 0 mm (same orientation), else `None`.
    fn slid(&self, pose: &Transform) -> Option<(Vec3, f64)> {
        if !self.slides || pose.rotation().angle_to(&self.p_home.rotation()) > 1e-9 {
            return None;
        }
        let shift = pose.translation() - self.p_home.translation();
        let s = shift.norm();
        (s > 1e-9).then(|| (shift / s, s))
    }

    /// For a sliding fit, where `from` lies on the line through the assembled pose
    /// along unit `d` (same orientation): the assembled pose moved by `a` along `d`.
    fn offset_along(&self, from: &Transform, d: &Vec3) -> Option<f64> {
        if !self.slides || from.rotation().angle_to(&self.p_home.rotation()) > 1e-9 {
            return None;
        }
        let shift = from.translation() - self.p_home.translation();
        let a = shift.dot(d);
        ((shift - d * a).norm() <= 1e-9 * (1.0 + a.abs())).then_some(a)
    }

    /// The slide rule for `p` at its assembled pose moved along unit `d` by every
    /// `s` in `[s0, s1]`: whether, along some line parallel to `d`, a stretch of `p`
    /// overlaps a stretch of `q` it did not overlap assembled, or one it did by more
    /// than assembled (each beyond the tolerance). Exact in `s` (interval
    /// arithmetic), on lines `spacing` apart.
    fn slide_overlap(&self, d: &Vec3, s0: f64, s1: f64) -> bool {
        let tol = self.tolerance;
        let bp = self.p.world_bounds(&self.p_home);
        let (a, b) = (
            Aabb::new(bp.lo + d * s0, bp.hi + d * s0),
            Aabb::new(bp.lo + d * s1, bp.hi + d * s1),
        );
        let swept = Aabb::new(a.lo.inf(&b.lo), a.hi.sup(&b.hi));
        let qb = self.q.world_bounds(&self.q_pose);
        if swept.overlap(&qb).min() <= tol {
            return false;
        }
        let region = Aabb::new(swept.lo.sup(&qb.lo), swept.hi.inf(&qb.hi));
        let lines = Lines::new(&region, d, self.spacing);
        let (inv_p, inv_q) = (self.p_home.inverse(), self.q_pose.inverse());
        let mut hits = Vec::new();
        for i in 0..lines.nu {
            for j in 0..lines.nv {
                let Some(o) = lines.origin(i, j) else {
                    continue;
                };
                let Some(ps) = cut(&self.p, &inv_p, &o, d, &mut hits) else {
                    continue;
                };
                if ps.is_empty() {
                    continue;
                }
                let Some(qs) = cut(&self.q, &inv_q, &o, d, &mut hits) else {
                    continue;
                };
                for &pi in &ps {
                    for &qk in &qs {
                        let home = most_overlap(pi, qk, 0.0, 0.0);
                        let allowed = if home > tol { home + tol } else { tol };
                        if most_overlap(pi, qk, s0.min(s1), s0.max(s1)) > allowed {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }

    /// The cut-out model: whether `p` moved from `from` along unit `d` by up to
    /// `len` mm meets `q` outside the room of the assembled pose.
    fn carved_overlap(&self, from: &Transform, d: &Vec3, len: f64) -> bool {
        let tol = self.tolerance;
        let bp = self.p.world_bounds(from);
        let moved = Aabb::new(bp.lo + d * len, bp.hi + d * len);
        let swept = Aabb::new(bp.lo.inf(&moved.lo), bp.hi.sup(&moved.hi));
        let qb = self.q.world_bounds(&self.q_pose);
        if swept.overlap(&qb).min() <= tol {
            return false;
        }
        let region = Aabb::new(swept.lo.sup(&qb.lo), swept.hi.inf(&qb.hi));
        let lines = Lines::new(&region, d, self.spacing);
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
        for i in 0..lines.nu {
            for j in 0..lines.nv {
                let Some(o) = lines.origin(i, j) else {
                    continue;
                };
                let mut cuts: [Vec<(f64, f64)>; 3] = Default::default();
                let mut ok = true;
                for k in 0..3 {
                    match cut(solids[k], &inv[k], &o, d, &mut hits) {
                        Some(iv) => cuts[k] = iv,
                        None => ok = false,
                    }
                }
                let hit = if self.p_carved {
                    carved_line_overlap(&cuts[0], &cuts[1], &cuts[2], len, tol)
                } else {
                    line_overlap(&cuts[0], &cuts[1], &cuts[2], len, tol)
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
