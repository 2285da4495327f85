//! The pose of one part's frame in another's ([`Relative`]) and the oriented-box
//! test of the tree walks ([`obbs_meet`]): what the pair queries (`exact.rs`), the
//! containment test, distances and edge checks share.

use super::node::Obb;
use super::triangle::Tri;
use crate::math::{Transform, Vec3};
use nalgebra::{Isometry3, Matrix3};

/// The pose of `b`'s part frame in `a`'s part frame, with what the node test needs.
pub(crate) struct Relative {
    pub(super) iso: Isometry3<f64>,
    rot: Matrix3<f64>,
}

impl Relative {
    pub(crate) fn new(pa: &Transform, pb: &Transform) -> Self {
        let iso = pa.isometry().inverse() * pb.isometry();
        let rot = *iso.rotation.to_rotation_matrix().matrix();
        Relative { iso, rot }
    }

    /// Whether oriented boxes `a` (frame A) and `b` (frame B) come within `margin`:
    /// a bounding-sphere reject, then the separating-axis test on the 15 axes (faces
    /// of both boxes and edge cross products). Conservative: cross axes are not
    /// normalised (length ≤ 1), so the margin they apply is at least `margin`.
    #[inline]
    pub(crate) fn boxes_meet(&self, a: &Obb, b: &Obb, margin: f64) -> bool {
        obbs_meet(a, &self.obb(b), margin)
    }

    /// Lower bound of the distance between oriented boxes `a` (frame A) and `b`
    /// (frame B): the widest gap between their shadows on the six face normals, or
    /// between their bounding spheres.
    #[inline]
    pub(super) fn obb_gap(&self, a: &Obb, b: &Obb) -> f64 {
        let d = self.rot * b.centre + self.iso.translation.vector - a.centre;
        let (ha, hb) = (&a.half, &b.half);
        let mut gap = d.norm() - a.radius - b.radius;
        let r = a.axes.tr_mul(&(self.rot * b.axes));
        let t = a.axes.tr_mul(&d);
        let ar = r.abs();
        for i in 0..3 {
            let rb = hb[0] * ar[(i, 0)] + hb[1] * ar[(i, 1)] + hb[2] * ar[(i, 2)];
            gap = gap.max(t[i].abs() - ha[i] - rb);
        }
        for j in 0..3 {
            let ra = ha[0] * ar[(0, j)] + ha[1] * ar[(1, j)] + ha[2] * ar[(2, j)];
            let tj = t[0] * r[(0, j)] + t[1] * r[(1, j)] + t[2] * r[(2, j)];
            gap = gap.max(tj.abs() - ra - hb[j]);
        }
        gap.max(0.0)
    }

    pub(super) fn tri(&self, t: &Tri) -> Tri {
        [self.iso * t[0], self.iso * t[1], self.iso * t[2]]
    }

    /// Oriented box `b` (frame B) in frame A.
    #[inline]
    pub(crate) fn obb(&self, b: &Obb) -> Obb {
        Obb {
            centre: self.rot * b.centre + self.iso.translation.vector,
            axes: self.rot * b.axes,
            half: b.half,
            radius: b.radius,
        }
    }
}

/// [`Relative::boxes_meet`] with `b` already in `a`'s frame: a bounding-sphere
/// reject, then the separating-axis test on the 15 axes (faces of both boxes,
/// then edge cross products). Conservative: cross axes are not normalised
/// (length ≤ 1), so the margin they apply is at least `margin`.
#[inline]
pub(crate) fn obbs_meet(a: &Obb, b: &Obb, margin: f64) -> bool {
    let d = b.centre - a.centre;
    let reach = a.radius + b.radius + margin;
    if d.norm_squared() > reach * reach {
        return false;
    }
    // b's axes and the centre offset in a's box frame. Boxes keep their thinnest
    // axis first: a's, then b's thinnest face axis are tried before the rest is
    // computed, since most pairs that miss are told apart by one of them.
    let (ha, hb) = (&a.half, &b.half);
    let ac = [a.axes.column(0), a.axes.column(1), a.axes.column(2)];
    let bc = [b.axes.column(0), b.axes.column(1), b.axes.column(2)];
    let mut r = Matrix3::<f64>::zeros();
    // the small bias keeps near-parallel axes conservative
    let mut ar = Matrix3::<f64>::zeros();
    let mut t = Vec3::zeros();
    let entry = |r: &mut Matrix3<f64>, ar: &mut Matrix3<f64>, i: usize, j: usize| {
        let v = ac[i].dot(&bc[j]);
        r[(i, j)] = v;
        ar[(i, j)] = v.abs() + 1e-12;
    };
    t[0] = ac[0].dot(&d);
    for j in 0..3 {
        entry(&mut r, &mut ar, 0, j);
    }
    if t[0].abs() > ha[0] + hb[0] * ar[(0, 0)] + hb[1] * ar[(0, 1)] + hb[2] * ar[(0, 2)] + margin {
        return false;
    }
    t[1] = ac[1].dot(&d);
    t[2] = ac[2].dot(&d);
    entry(&mut r, &mut ar, 1, 0);
    entry(&mut r, &mut ar, 2, 0);
    let t0 = t[0] * r[(0, 0)] + t[1] * r[(1, 0)] + t[2] * r[(2, 0)];
    if t0.abs() > ha[0] * ar[(0, 0)] + ha[1] * ar[(1, 0)] + ha[2] * ar[(2, 0)] + hb[0] + margin {
        return false;
    }
    for i in 1..3 {
        entry(&mut r, &mut ar, i, 1);
        entry(&mut r, &mut ar, i, 2);
        let rb = hb[0] * ar[(i, 0)] + hb[1] * ar[(i, 1)] + hb[2] * ar[(i, 2)];
        if t[i].abs() > ha[i] + rb + margin {
            return false;
        }
    }
    for j in 1..3 {
        let ra = ha[0] * ar[(0, j)] + ha[1] * ar[(1, j)] + ha[2] * ar[(2, j)];
        let tj = t[0] * r[(0, j)] + t[1] * r[(1, j)] + t[2] * r[(2, j)];
        if tj.abs() > ra + hb[j] + margin {
            return false;
        }
    }
    // axis a_i × b_j
    for i in 0..3 {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        for j in 0..3 {
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            let ra = ha[i1] * ar[(i2, j)] + ha[i2] * ar[(i1, j)];
            let rb = hb[j1] * ar[(i, j2)] + hb[j2] * ar[(i, j1)];
            let tl = t[i2] * r[(i1, j)] - t[i1] * r[(i2, j)];
            if tl.abs() > ra + rb + margin {
                return false;
            }
        }
    }
    true
}
