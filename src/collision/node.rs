//! The tree's node and its oriented box: what the collider keeps per node and the
//! walks test, apart from how the tree is built (`tree.rs`) and what the collider
//! is (`shape.rs`).

use crate::math::{Aabb, Vec3};
use nalgebra::Matrix3;

/// Most triangles per BVH leaf. A leaf pair's triangles are culled by plane before
/// pairing, which beats two more levels of box tests where a few facets of a fine
/// tessellation lie close together; a group bent round a corner or a tube is split
/// further (`tree::SPLIT_GAIN`).
pub(crate) const LEAF_SIZE: usize = 4;

/// A node of the tree: `count > 0`: a leaf over the triangles
/// `order[first..first + count]`;
/// otherwise children `first` and `first + 1`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub(crate) bounds: Aabb,
    pub(crate) first: u32,
    pub(crate) count: u32,
}

/// An oriented box (part frame, mm) fitted to a node's triangles: `axes` columns are
/// orthonormal directions, `half` the half extents along them. Far tighter than the
/// node's axis-aligned box for a surface patch that is tilted in the part frame, which
/// is what prunes near misses in the exact traversal.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Obb {
    pub(crate) centre: Vec3,
    pub(crate) axes: Matrix3<f64>,
    pub(crate) half: Vec3,
    /// `half.norm()`, kept: the bounding-sphere reject of every node pair reads it.
    pub(crate) radius: f64,
}

impl Obb {
    pub(crate) const BLANK: Obb = Obb {
        centre: Vec3::new(0.0, 0.0, 0.0),
        axes: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        half: Vec3::new(0.0, 0.0, 0.0),
        radius: 0.0,
    };

    /// The box with these centre, axes and half extents.
    #[inline]
    pub(crate) fn new(centre: Vec3, axes: Matrix3<f64>, half: Vec3) -> Obb {
        Obb {
            centre,
            axes,
            half,
            radius: half.norm(),
        }
    }

    /// The box with extents `lo..hi` along the columns of `axes` (coordinates
    /// `axesᵀ·p`), or the axis-aligned `aabb` when that is smaller; padded so rounding
    /// never leaves a vertex outside.
    pub(super) fn from_extents(axes: &Matrix3<f64>, lo: Vec3, hi: Vec3, aabb: &Aabb) -> Obb {
        let ha = aabb.half_extents();
        let half = (hi - lo) * 0.5;
        let usable = axes.iter().all(|v| v.is_finite()) && half.iter().all(|v| v.is_finite());
        let (centre, axes, half) = if usable && half.product() < ha.product() {
            (axes * ((lo + hi) * 0.5), *axes, half)
        } else {
            (aabb.centre().coords, Matrix3::identity(), ha)
        };
        let pad = 1e-12 * (centre.amax() + half.amax());
        // thinnest axis first: the separating-axis test tries it first, and a
        // surface patch's box is most often told apart along its thin side
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| half[i].total_cmp(&half[j]));
        let axes = Matrix3::from_columns(&order.map(|k| axes.column(k).into_owned()));
        let half = Vec3::from(order.map(|k| half[k]));
        Obb::new(centre, axes, half.add_scalar(pad))
    }
}
