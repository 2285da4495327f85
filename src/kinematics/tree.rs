//! [`KinematicTree`]: links with parents, joints and home transforms (seed 001's tree of
//! `CSTLModel` parts), and forward kinematics of every link.

use super::{Joint, JointKind, KinematicsError, LinkProblem, Mimic};
use crate::math::Transform;
use nalgebra::Isometry3;

/// One rigid body of a mechanism.
///
/// Its frame, in its parent's frame, is `home` followed by the joint motion
/// (see [`Joint`]): at joint value 0 the link sits at `home`. A root link (no parent)
/// is placed relative to the tree's base pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Optional name (for scripts and error messages).
    pub name: Option<String>,
    /// Index of the parent link; `None` for a root. Must be smaller than this link's
    /// own index (links are stored parents first).
    pub parent: Option<usize>,
    /// Pose of this link's frame in the parent frame at joint value 0 (mm).
    pub home: Transform,
    /// How this link moves relative to its parent.
    pub joint: Joint,
}

impl Link {
    /// A link with a name, parent, home pose and joint.
    pub fn new(
        name: impl Into<String>,
        parent: Option<usize>,
        home: Transform,
        joint: Joint,
    ) -> Self {
        Self {
            name: Some(name.into()),
            parent,
            home,
            joint,
        }
    }
}

/// A tree of links (any number of roots and branches), stored parents first.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KinematicTree {
    links: Vec<Link>,
    /// Per link: the joint it follows (URDF `<mimic>`); empty when none does.
    mimics: Vec<Option<Mimic>>,
}

impl KinematicTree {
    /// Checks and builds a tree: every parent index is smaller than its child's index,
    /// axes are finite and non-zero, points and home poses are finite, limits are
    /// finite with `min <= max`.
    pub fn new(links: Vec<Link>) -> Result<Self, KinematicsError> {
        for (i, link) in links.iter().enumerate() {
            let bad = |cause: LinkProblem| KinematicsError::InvalidLink {
                link: i,
                name: link.name.clone().unwrap_or_default(),
                cause,
            };
            if let Some(p) = link.parent {
                if p >= i {
                    return Err(bad(LinkProblem::ParentAfter { parent: p }));
                }
            }
            if !link.home.is_finite() {
                return Err(bad(LinkProblem::HomeNotFinite));
            }
            let j = &link.joint;
            if j.kind.is_movable() {
                let n = j.axis.norm();
                if !(n.is_finite() && (n - 1.0).abs() < 1e-9) {
                    return Err(bad(LinkProblem::AxisNotUnit));
                }
                if !j.point.coords.iter().all(|v| v.is_finite()) {
                    return Err(bad(LinkProblem::AxisPointNotFinite));
                }
            }
            if let Some(l) = j.limits {
                if !(l.min.is_finite() && l.max.is_finite() && l.min <= l.max) {
                    return Err(bad(LinkProblem::Limits {
                        min: l.min,
                        max: l.max,
                    }));
                }
            }
        }
        Ok(Self {
            links,
            mimics: Vec::new(),
        })
    }

    /// The same tree with mimic joints: `mimics[k] = (follower link, mimic)`. Both
    /// joints must be movable, the leader must not itself follow, and the multiplier
    /// and offset must be finite.
    pub fn with_mimics(mut self, mimics: &[(usize, Mimic)]) -> Result<Self, KinematicsError> {
        let mut table = vec![None; self.links.len()];
        for &(f, m) in mimics {
            let bad = |cause: LinkProblem| KinematicsError::InvalidLink {
                link: f,
                name: self
                    .links
                    .get(f)
                    .and_then(|l| l.name.clone())
                    .unwrap_or_default(),
                cause,
            };
            let movable = |i: usize| self.links.get(i).is_some_and(|l| l.joint.kind.is_movable());
            if !movable(f) || !movable(m.leader) || f == m.leader {
                return Err(bad(LinkProblem::MimicNotMovable));
            }
            if !(m.multiplier.is_finite() && m.offset.is_finite()) {
                return Err(bad(LinkProblem::MimicNotFinite));
            }
            table[f] = Some(m);
        }
        if let Some(f) =
            (0..table.len()).find(|&f| table[f].is_some_and(|m| table[m.leader].is_some()))
        {
            return Err(KinematicsError::InvalidLink {
                link: f,
                name: self.links[f].name.clone().unwrap_or_default(),
                cause: LinkProblem::MimicChain,
            });
        }
        self.mimics = if table.iter().any(Option::is_some) {
            table
        } else {
            Vec::new()
        };
        Ok(self)
    }

    /// The joint link `link` follows, if it is a mimic joint.
    pub fn mimic(&self, link: usize) -> Option<&Mimic> {
        self.mimics.get(link).and_then(Option::as_ref)
    }

    /// The links, parents first.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Number of links.
    pub fn len(&self) -> usize {
        self.links.len()
    }

    /// Whether the tree has no link.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// The index of the link called `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.links
            .iter()
            .position(|l| l.name.as_deref() == Some(name))
    }

    /// Indices from a root down to `link` (inclusive), or `None` if out of range.
    pub fn path_from_root(&self, link: usize) -> Option<Vec<usize>> {
        let mut path = Vec::new();
        let mut cur = Some(link);
        while let Some(i) = cur {
            let l = self.links.get(i)?;
            path.push(i);
            cur = l.parent;
        }
        path.reverse();
        Some(path)
    }

    /// World poses of every link, given the pose of the tree's base (roots are placed
    /// in the base frame) and one value per link (`values[i]` is link `i`'s joint
    /// value, rad or mm; ignored for fixed joints and for mimic joints, which take
    /// `multiplier · values[leader] + offset`). Values must be finite.
    pub fn link_poses(
        &self,
        base: &Transform,
        values: &[f64],
    ) -> Result<Vec<Transform>, KinematicsError> {
        if values.len() != self.links.len() {
            return Err(KinematicsError::JointCount {
                expected: self.links.len(),
                got: values.len(),
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(KinematicsError::NonFiniteJoint(i));
        }
        let mut out: Vec<Isometry3<f64>> = Vec::with_capacity(self.links.len());
        for (i, (link, &v)) in self.links.iter().zip(values).enumerate() {
            let v = match self.mimic(i) {
                Some(m) => m.multiplier * values[m.leader] + m.offset,
                None => v,
            };
            let parent = match link.parent {
                Some(p) => out[p],
                None => *base.isometry(),
            };
            out.push(parent * link.joint.motion(v) * link.home.isometry());
        }
        Ok(out.into_iter().map(Transform::from_isometry).collect())
    }

    /// Number of movable (revolute or prismatic) links.
    pub fn movable_count(&self) -> usize {
        self.links
            .iter()
            .filter(|l| l.joint.kind != JointKind::Fixed)
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{Joint, JointLimits};
    use crate::math::{Point3, Vec3};
    use std::f64::consts::FRAC_PI_2;

    /// Planar 2R arm in the XY plane with a prismatic tip, derived by hand:
    /// link 1 rotates about Z at the origin, link 2 about Z at (100, 0, 0) in link 1,
    /// the tip slides along link 2's X axis, starting 50 mm past joint 2.
    fn planar() -> KinematicTree {
        KinematicTree::new(vec![
            Link::new(
                "l1",
                None,
                Transform::IDENTITY,
                Joint::revolute(Vec3::z(), Point3::origin()),
            ),
            Link::new(
                "l2",
                Some(0),
                Transform::from_translation(Vec3::new(100.0, 0.0, 0.0)),
                Joint::revolute(Vec3::z(), Point3::new(100.0, 0.0, 0.0)),
            ),
            Link::new(
                "tip",
                Some(1),
                Transform::from_translation(Vec3::new(50.0, 0.0, 0.0)),
                Joint::prismatic(Vec3::x()).with_limits(JointLimits::new(0.0, 30.0)),
            ),
        ])
        .unwrap()
    }

    #[test]
    fn planar_fk_matches_hand_derivation() {
        let tree = planar();
        let (t1, t2, d) = (0.3_f64, -0.7_f64, 12.0);
        let poses = tree.link_poses(&Transform::IDENTITY, &[t1, t2, d]).unwrap();
        // Hand: joint 2 at R(t1)(100,0); link 2 frame origin there too (its home is the
        // translation to joint 2); the tip at joint2 + (50 + d)·(cos(t1+t2), sin(t1+t2)).
        let j2 = Vec3::new(100.0 * t1.cos(), 100.0 * t1.sin(), 0.0);
        assert!((poses[1].translation() - j2).norm() < 1e-12);
        let tip = j2 + (50.0 + d) * Vec3::new((t1 + t2).cos(), (t1 + t2).sin(), 0.0);
        assert!((poses[2].translation() - tip).norm() < 1e-12);
        let x = poses[2].apply_vector(&Vec3::x());
        assert!((x - Vec3::new((t1 + t2).cos(), (t1 + t2).sin(), 0.0)).norm() < 1e-12);
    }

    #[test]
    fn base_pose_moves_everything() {
        let tree = planar();
        let base = Transform::from_rotation_about(Point3::new(5.0, 0.0, 0.0), Vec3::x(), FRAC_PI_2)
            .unwrap();
        let local = tree
            .link_poses(&Transform::IDENTITY, &[0.1, 0.2, 3.0])
            .unwrap();
        let world = tree.link_poses(&base, &[0.1, 0.2, 3.0]).unwrap();
        for (l, w) in local.iter().zip(&world) {
            assert!((*l * base).approx_eq(w, 1e-12, 1e-12));
        }
    }

    #[test]
    fn rejects_bad_trees_and_values() {
        let bad_parent = KinematicTree::new(vec![Link::new(
            "a",
            Some(0),
            Transform::IDENTITY,
            Joint::fixed(),
        )]);
        assert!(bad_parent.is_err());
        let zero_axis = KinematicTree::new(vec![Link::new(
            "a",
            None,
            Transform::IDENTITY,
            Joint::revolute(Vec3::zeros(), Point3::origin()),
        )]);
        assert!(zero_axis.is_err());
        let tree = planar();
        assert!(tree.link_poses(&Transform::IDENTITY, &[0.0, 0.0]).is_err());
        assert!(tree
            .link_poses(&Transform::IDENTITY, &[0.0, f64::NAN, 0.0])
            .is_err());
        assert_eq!(tree.path_from_root(2), Some(vec![0, 1, 2]));
        assert_eq!(tree.find("tip"), Some(2));
    }
}
