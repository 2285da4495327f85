//! [`Aabb`]: the one axis-aligned box type of the crate (mm).

use super::{Point3, Vec3};

/// An axis-aligned box (mm), `lo <= hi` component-wise: the one box type of the
/// crate (part bounds, world boxes of components, cut cells, planning boxes).
///
/// Serialized as `{lo: [x, y, z], hi: [x, y, z]}` (mm).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(from = "AabbFile", into = "AabbFile")]
pub struct Aabb {
    /// Minimum corner, mm.
    pub lo: Point3,
    /// Maximum corner, mm.
    pub hi: Point3,
}

/// The serialized form of [`Aabb`].
#[derive(serde::Serialize, serde::Deserialize)]
struct AabbFile {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl From<AabbFile> for Aabb {
    fn from(f: AabbFile) -> Aabb {
        Aabb::new(f.lo, f.hi)
    }
}

impl From<Aabb> for AabbFile {
    fn from(b: Aabb) -> AabbFile {
        AabbFile {
            lo: b.lo.coords.into(),
            hi: b.hi.coords.into(),
        }
    }
}

impl Aabb {
    /// The box `lo..hi` (mm); points or vectors from the origin.
    pub fn new(lo: impl Into<Point3>, hi: impl Into<Point3>) -> Aabb {
        Aabb {
            lo: lo.into(),
            hi: hi.into(),
        }
    }

    /// The empty box (inverted), neutral for [`Aabb::grow`].
    pub const EMPTY: Aabb = Aabb {
        lo: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        hi: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    };

    /// Extends the box over `p`.
    pub fn grow(&mut self, p: &Point3) {
        self.lo = self.lo.inf(p);
        self.hi = self.hi.sup(p);
    }

    /// The smallest box containing both (mm); [`Aabb::EMPTY`] is neutral.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            lo: self.lo.inf(&other.lo),
            hi: self.hi.sup(&other.hi),
        }
    }

    /// The box moved by `offset` (mm).
    pub fn translated(&self, offset: &Vec3) -> Aabb {
        Aabb {
            lo: self.lo + offset,
            hi: self.hi + offset,
        }
    }

    /// The box around `points` (mm); [`Aabb::EMPTY`] for none.
    pub fn around<'a>(points: impl IntoIterator<Item = &'a Point3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |mut b, p| {
            b.grow(p);
            b
        })
    }

    /// Whether nothing was added.
    pub fn is_empty(&self) -> bool {
        self.lo.x > self.hi.x
    }

    /// The centre, mm.
    pub fn centre(&self) -> Point3 {
        nalgebra::center(&self.lo, &self.hi)
    }

    /// Half the edge lengths, mm.
    pub fn half_extents(&self) -> Vec3 {
        (self.hi - self.lo) * 0.5
    }

    /// The axis-aligned box (in the target frame) around this box moved by `iso`
    /// (a [`Transform`](crate::math::Transform) gives it with `.isometry()`): the
    /// tightest box containing the moved box.
    pub fn transformed(&self, iso: &nalgebra::Isometry3<f64>) -> Aabb {
        let c = iso * self.centre();
        let r = iso.rotation.to_rotation_matrix();
        let h = r.matrix().abs() * self.half_extents();
        Aabb {
            lo: c - h,
            hi: c + h,
        }
    }

    /// Per-axis overlap `min(hi) - max(lo)` (negative: a gap), mm.
    pub fn overlap(&self, other: &Aabb) -> Vec3 {
        self.hi.coords.inf(&other.hi.coords) - self.lo.coords.sup(&other.lo.coords)
    }

    /// Distance between the two boxes (0 when they overlap), mm.
    pub fn distance_to_box(&self, other: &Aabb) -> f64 {
        (self.lo - other.hi)
            .sup(&(other.lo - self.hi))
            .sup(&Vec3::zeros())
            .norm()
    }

    /// Distance from `p` to the box (0 inside), mm.
    pub fn distance_to_point(&self, p: &Point3) -> f64 {
        let d = (self.lo - p).sup(&(p - self.hi)).sup(&Vec3::zeros());
        d.norm()
    }
}
