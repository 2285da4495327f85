//! Nearest-neighbour search over tree nodes in the planner's SE(3) metric
//! (`|Δt| + w·θ`, mm): a k-d tree over 7-D points (translation, unit quaternion),
//! not a linear scan.
//!
//! Pruning uses a lower bound that holds for any rotation weight `w`: the
//! translation part is at least the distance from the query's translation to a
//! cell's box, and the rotation angle between unit quaternions `q`, `q'` is
//! `θ = 2·acos|q·q'| ≥ 2·min(|q − q'|, |q + q'|)` (the chord of the 4-D angle
//! `θ/2` is `2·sin(θ/4) ≤ θ/2`), so `w·θ` is at least `2w` times the distance from
//! `±q` to the cell's quaternion box. The answer is exactly the linear scan's: the
//! same distance expression, ties to the lowest index, so the same seed gives the
//! same path whether or not the index is used.

use crate::math::Vec3;
use nalgebra::UnitQuaternion;

/// Points per leaf.
const LEAF: usize = 24;

/// The exact metric distance the linear scan computes (kept bit-identical).
#[cfg(test)]
#[inline]
pub(crate) fn metric(
    t: &Vec3,
    q: &UnitQuaternion<f64>,
    tt: &Vec3,
    tq: &UnitQuaternion<f64>,
    w: f64,
) -> f64 {
    metric_below(t, q, tt, tq, w, f64::INFINITY)
}

/// [`metric`], or `f64::INFINITY` when it is certainly above `bound` (then
/// neither a nearer node nor a tie): the chord bound of the module doc,
/// `θ ≥ 2·√(2 − 2|q·q'|)`, rules most candidates out before the arc cosine,
/// which took a sixth of a spirelli search's time.
#[inline]
pub(crate) fn metric_below(
    t: &Vec3,
    q: &UnitQuaternion<f64>,
    tt: &Vec3,
    tq: &UnitQuaternion<f64>,
    w: f64,
    bound: f64,
) -> f64 {
    let d = (t - tt).norm();
    // 2·acos|q·q'| is the angle between the rotations; nalgebra's `angle_to`
    // goes through atan2, which took most of a query's time.
    let dot = q.coords.dot(&tq.coords).abs().min(1.0);
    // Shrunk by 1e-9 so rounding never puts the bound above the true value.
    let low = (d + w * 2.0 * (2.0 - 2.0 * dot).max(0.0).sqrt()) * (1.0 - 1e-9);
    if low > bound {
        return f64::INFINITY;
    }
    d + w * 2.0 * crate::math::trig::acos(dot)
}

#[derive(Debug, Clone)]
struct Cell {
    lo: [f64; 7],
    hi: [f64; 7],
    /// The nodes `order[start..end]` (a leaf scans them).
    start: usize,
    end: usize,
    /// Inner cells: the two children (indices into `cells`).
    children: Option<(usize, usize)>,
    /// Inner cells: the split axis and the coordinate the children divide at.
    split: (usize, f64),
}

/// A static k-d tree over the first `len()` nodes of a tree; the planner's tree
/// rebuilds it as it grows and scans the few nodes added since.
#[derive(Debug, Clone, Default)]
pub(crate) struct KdIndex {
    order: Vec<usize>,
    points: Vec<[f64; 7]>,
    cells: Vec<Cell>,
}

fn point(t: &Vec3, q: &UnitQuaternion<f64>) -> [f64; 7] {
    let c = q.coords; // (i, j, k, w)
    [t.x, t.y, t.z, c[0], c[1], c[2], c[3]]
}

impl KdIndex {
    /// Nodes covered.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Builds the index over `translations[i]`, `rotations[i]`; `weight` (mm/rad)
    /// only steers which axis each cell is split on.
    pub fn build(translations: &[Vec3], rotations: &[UnitQuaternion<f64>], weight: f64) -> Self {
        let points: Vec<[f64; 7]> = translations
            .iter()
            .zip(rotations)
            .map(|(t, q)| point(t, q))
            .collect();
        let mut order: Vec<usize> = (0..points.len()).collect();
        let mut cells = Vec::with_capacity(2 * points.len() / LEAF + 1);
        if !points.is_empty() {
            split(&points, &mut order, 0, points.len(), weight, &mut cells);
        }
        Self {
            order,
            points,
            cells,
        }
    }

    /// The covered node nearest to `(tt, tq)` in the metric with rotation weight
    /// `w`, skipping nodes `skip` says are gone; ties to the lowest index. `best`
    /// is the incumbent `(index, distance)` (e.g. `(0, ∞)`).
    #[allow(clippy::too_many_arguments)]
    pub fn nearest(
        &self,
        translations: &[Vec3],
        rotations: &[UnitQuaternion<f64>],
        tt: &Vec3,
        tq: &UnitQuaternion<f64>,
        w: f64,
        skip: &dyn Fn(usize) -> bool,
        best: (usize, f64),
    ) -> (usize, f64) {
        let mut best = best;
        if self.cells.is_empty() {
            return best;
        }
        let q = point(tt, tq);
        self.search(0, translations, rotations, &q, tt, tq, w, skip, &mut best);
        best
    }

    /// Depth first, the child on the query's side of the split first; a cell is
    /// entered only when its lower bound does not exceed the best distance so far
    /// (the far child's bound is computed after the near child has tightened it).
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        c: usize,
        translations: &[Vec3],
        rotations: &[UnitQuaternion<f64>],
        q: &[f64; 7],
        tt: &Vec3,
        tq: &UnitQuaternion<f64>,
        w: f64,
        skip: &dyn Fn(usize) -> bool,
        best: &mut (usize, f64),
    ) {
        let cell = &self.cells[c];
        match cell.children {
            None => {
                for &i in &self.order[cell.start..cell.end] {
                    // The translation alone already too far: the scan's own reject.
                    if (translations[i] - tt).norm() > best.1 || skip(i) {
                        continue;
                    }
                    let d = metric_below(&translations[i], &rotations[i], tt, tq, w, best.1);
                    if d < best.1 || (d == best.1 && i < best.0) {
                        *best = (i, d);
                    }
                }
            }
            Some((a, b)) => {
                let (axis, at) = cell.split;
                let (near, far) = if q[axis] < at { (a, b) } else { (b, a) };
                for child in [near, far] {
                    if self.bound(child, q, w, best.1) <= best.1 {
                        self.search(child, translations, rotations, q, tt, tq, w, skip, best);
                    }
                }
            }
        }
    }

    /// A lower bound of the metric distance from the query point `q` to any point
    /// of cell `c` (slightly shrunk for rounding, so that it never exceeds the
    /// distance the scan computes).
    /// Stops early (returning the translation part alone) once that exceeds `cap`.
    // Three arrays indexed in lockstep: a range loop reads clearest.
    #[allow(clippy::needless_range_loop)]
    fn bound(&self, c: usize, q: &[f64; 7], w: f64, cap: f64) -> f64 {
        let cell = &self.cells[c];
        let gap = |x: f64, lo: f64, hi: f64| {
            if x < lo {
                lo - x
            } else if x > hi {
                x - hi
            } else {
                0.0
            }
        };
        let mut t2 = 0.0;
        for k in 0..3 {
            let g = gap(q[k], cell.lo[k], cell.hi[k]);
            t2 += g * g;
        }
        let t = t2.sqrt();
        if t > cap * (1.0 + 1e-9) + 1e-9 {
            return t * (1.0 - 1e-9) - 1e-9;
        }
        let (mut plus, mut minus) = (0.0, 0.0);
        for k in 3..7 {
            let g = gap(q[k], cell.lo[k], cell.hi[k]);
            plus += g * g;
            let g = gap(-q[k], cell.lo[k], cell.hi[k]);
            minus += g * g;
        }
        let chord = plus.min(minus).sqrt();
        (t + 2.0 * w * chord) * (1.0 - 1e-9) - 1e-9
    }
}

/// Splits `order[start..end]` into a cell (and its children), returns its index.
fn split(
    points: &[[f64; 7]],
    order: &mut [usize],
    start: usize,
    end: usize,
    weight: f64,
    cells: &mut Vec<Cell>,
) -> usize {
    let mut lo = [f64::INFINITY; 7];
    let mut hi = [f64::NEG_INFINITY; 7];
    for &i in &order[start..end] {
        for k in 0..7 {
            lo[k] = lo[k].min(points[i][k]);
            hi[k] = hi[k].max(points[i][k]);
        }
    }
    let me = cells.len();
    cells.push(Cell {
        lo,
        hi,
        start,
        end,
        children: None,
        split: (0, 0.0),
    });
    if end - start <= LEAF {
        return me;
    }
    // Widest axis in metric units (a quaternion coordinate counts 2w mm).
    let scale = |k: usize| if k < 3 { 1.0 } else { 2.0 * weight };
    let axis = (0..7)
        .max_by(|&a, &b| ((hi[a] - lo[a]) * scale(a)).total_cmp(&((hi[b] - lo[b]) * scale(b))))
        .unwrap_or(0);
    let mid = (start + end) / 2;
    // Ties by index: the split (and so every answer) is a function of the input.
    order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
        points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b))
    });
    let at = points[order[mid]][axis];
    let a = split(points, order, start, mid, weight, cells);
    let b = split(points, order, mid, end, weight, cells);
    cells[me].children = Some((a, b));
    cells[me].split = (axis, at);
    me
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rng;

    /// The index answers exactly what a linear scan answers (index and distance),
    /// on clustered poses, for several weights, with some nodes skipped.
    #[test]
    fn the_index_agrees_with_the_linear_scan() {
        let mut rng = Rng::new(7);
        let n = 3000;
        let mut ts = Vec::new();
        let mut qs = Vec::new();
        for k in 0..n {
            let c = if k % 3 == 0 { 0.0 } else { 50.0 };
            ts.push(Vec3::new(
                c + rng.uniform() * 20.0,
                rng.uniform() * 100.0,
                rng.uniform() * 5.0,
            ));
            qs.push(rng.rotation());
        }
        let skip = |i: usize| i % 17 == 5;
        for w in [0.5, 10.0, 80.0] {
            let index = KdIndex::build(&ts, &qs, w);
            assert_eq!(index.len(), n);
            for _ in 0..300 {
                let tt = Vec3::new(
                    rng.uniform() * 80.0 - 10.0,
                    rng.uniform() * 100.0,
                    rng.uniform() * 5.0,
                );
                let tq = rng.rotation();
                let mut scan = (0, f64::INFINITY);
                for i in 0..n {
                    if skip(i) {
                        continue;
                    }
                    let d = metric(&ts[i], &qs[i], &tt, &tq, w);
                    if d < scan.1 {
                        scan = (i, d);
                    }
                }
                let got = index.nearest(&ts, &qs, &tt, &tq, w, &skip, (0, f64::INFINITY));
                assert_eq!(got, scan, "w {w}");
            }
        }
    }

    /// Equal poses: the lowest index wins, as in the scan.
    #[test]
    fn ties_go_to_the_lowest_index() {
        let ts = vec![Vec3::new(1.0, 2.0, 3.0); 50];
        let qs = vec![UnitQuaternion::identity(); 50];
        let index = KdIndex::build(&ts, &qs, 10.0);
        let got = index.nearest(
            &ts,
            &qs,
            &Vec3::zeros(),
            &UnitQuaternion::identity(),
            10.0,
            &|i| i < 3,
            (0, f64::INFINITY),
        );
        assert_eq!(got.0, 3);
    }
}
