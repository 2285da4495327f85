//! Mates and the mate solver.
//!
//! The solver mirrors what a SolidWorks rebuild does for the mates a robotic cell
//! uses: each mate places its second component relative to its first (the first
//! when the second is fixed) with the smallest rigid correction, and passes repeat
//! until every mate holds (Gauss–Seidel). Distances are mm, angles radians.

use super::reference::Reference;
use crate::math::{rotation_between, Point3, Transform, Vec3};
use nalgebra::{Unit, UnitQuaternion};

/// The kinds of mate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MateKind {
    /// Planes coplanar (normals opposed unless aligned), points coincident, a point on a
    /// plane or an axis, or two axes collinear.
    Coincident,
    /// Two axes collinear.
    Concentric,
    /// Two planes or axes parallel.
    Parallel,
    /// Two planes or axes perpendicular.
    Perpendicular,
    /// Planes parallel at a distance, or points / a point and a plane at a distance (mm).
    Distance,
    /// The angle between two planes' normals or two axes (radians).
    Angle,
}

impl MateKind {
    /// Parses the YAML name.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "coincident" => Self::Coincident,
            "concentric" => Self::Concentric,
            "parallel" => Self::Parallel,
            "perpendicular" => Self::Perpendicular,
            "distance" => Self::Distance,
            "angle" => Self::Angle,
            _ => return None,
        })
    }

    /// The YAML name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Coincident => "coincident",
            Self::Concentric => "concentric",
            Self::Parallel => "parallel",
            Self::Perpendicular => "perpendicular",
            Self::Distance => "distance",
            Self::Angle => "angle",
        }
    }

    /// Whether the mate has a driving dimension `D1@<name>`.
    pub fn has_dimension(self) -> bool {
        matches!(self, Self::Distance | Self::Angle)
    }
}

/// One side of a mate: a reference of a component.
#[derive(Debug, Clone, PartialEq)]
pub struct MateEntity {
    /// Index of the component in the document.
    pub component: usize,
    /// Reference name in the component's part (as written).
    pub reference: String,
    /// The reference in the part frame.
    pub geometry: Reference,
}

/// A mate between two entities.
#[derive(Debug, Clone, PartialEq)]
pub struct Mate {
    /// Mate name (its dimension is `D1@<name>`).
    pub name: String,
    /// What it constrains.
    pub kind: MateKind,
    /// The reference side and the moving side.
    pub entities: [MateEntity; 2],
    /// Driving value: mm for distance, radians for angle.
    pub value: Option<f64>,
    /// Directions aligned (true) or opposed (false); `None` = the kind's default.
    pub aligned: Option<bool>,
    /// Axis about which an angle is measured (signed angle), as `(component, axis)`.
    pub about: Option<MateEntity>,
    /// Suppressed: kept in the document, not solved.
    pub suppressed: bool,
}

impl Mate {
    /// Whether the mate's directions are aligned (SolidWorks' `MateAlign`): what it
    /// says, else its kind's default (coincident planes: anti-aligned), else what the
    /// poses show (the nearer of the two); `None` for mates of points.
    pub fn alignment(&self, poses: &[Transform]) -> Option<bool> {
        let (a, b) = world(self, poses);
        let (u, v) = (a.direction()?, b.direction()?);
        Some(
            self.aligned
                .or(default_aligned(self.kind, &a))
                .unwrap_or(u.dot(&v) >= 0.0),
        )
    }
}

/// Residual of a mate in the current poses: mm for positional, radians for angular
/// parts (the larger one).
pub(crate) fn residual(mate: &Mate, poses: &[Transform]) -> f64 {
    let (a, b) = world(mate, poses);
    let about = mate
        .about
        .as_ref()
        .map(|e| e.geometry.posed(&poses[e.component]));
    error(mate, &a, &b, about.as_ref())
}

fn world(mate: &Mate, poses: &[Transform]) -> (Reference, Reference) {
    let [ea, eb] = &mate.entities;
    (
        ea.geometry.posed(&poses[ea.component]),
        eb.geometry.posed(&poses[eb.component]),
    )
}

fn signed_angle(u: &Vec3, v: &Vec3, axis: &Vec3) -> f64 {
    let (u, v) = (u - axis * axis.dot(u), v - axis * axis.dot(v));
    axis.dot(&u.cross(&v)).atan2(u.dot(&v))
}

fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    a - t * ((a + std::f64::consts::PI) / t).floor()
}

/// Target direction for the mover's vector `v` given the reference vector `u`.
fn target_direction(mate: &Mate, u: &Vec3, v: &Vec3, default_aligned: Option<bool>) -> Vec3 {
    match mate.aligned.or(default_aligned) {
        Some(true) => *u,
        Some(false) => -u,
        // Either way: whichever is closer.
        None => {
            if u.dot(v) >= 0.0 {
                *u
            } else {
                -u
            }
        }
    }
}

fn default_aligned(kind: MateKind, a: &Reference) -> Option<bool> {
    match (kind, a) {
        (MateKind::Coincident | MateKind::Distance, Reference::Plane { .. }) => Some(false),
        _ => None,
    }
}

/// The distance a coincident or distance mate keeps (mm; coincident: 0).
fn kept_distance(mate: &Mate) -> f64 {
    if mate.kind == MateKind::Distance {
        mate.value.unwrap_or(0.0)
    } else {
        0.0
    }
}

fn error(mate: &Mate, a: &Reference, b: &Reference, about: Option<&Reference>) -> f64 {
    use Reference::*;
    let dir_err =
        |u: &Vec3, v: &Vec3| target_direction(mate, u, v, default_aligned(mate.kind, a)).angle(v);
    let value = mate.value.unwrap_or(0.0);
    let d = kept_distance(mate);
    match (mate.kind, a, b) {
        (
            MateKind::Coincident | MateKind::Distance,
            Plane {
                point: pa,
                normal: na,
            },
            Plane {
                point: pb,
                normal: nb,
            },
        ) => dir_err(na, nb).max((na.dot(&(pb - pa)) - d).abs()),
        (
            MateKind::Coincident | MateKind::Distance,
            Plane {
                point: pa,
                normal: na,
            },
            Point(pb),
        )
        | (
            MateKind::Coincident | MateKind::Distance,
            Point(pb),
            Plane {
                point: pa,
                normal: na,
            },
        ) => (na.dot(&(pb - pa)).abs() - d).abs(),
        (MateKind::Coincident | MateKind::Distance, Point(pa), Point(pb)) => {
            ((pb - pa).norm() - d).abs()
        }
        (
            MateKind::Coincident,
            Axis {
                point: pa,
                direction: da,
            },
            Point(pb),
        )
        | (
            MateKind::Coincident,
            Point(pb),
            Axis {
                point: pa,
                direction: da,
            },
        ) => {
            let r = pb - pa;
            (r - da * da.dot(&r)).norm()
        }
        (
            MateKind::Coincident | MateKind::Concentric,
            Axis {
                point: pa,
                direction: da,
            },
            Axis {
                point: pb,
                direction: db,
            },
        ) => {
            let r = pb - pa;
            dir_err(da, db).max((r - da * da.dot(&r)).norm())
        }
        (MateKind::Coincident, CoordinateSystem(fa), CoordinateSystem(fb)) => {
            let (angle, distance) = fa.distance_to(fb);
            angle.max(distance)
        }
        (MateKind::Parallel, _, _) => {
            let (u, v) = (
                a.direction().unwrap_or_default(),
                b.direction().unwrap_or_default(),
            );
            u.cross(&v).norm().asin()
        }
        (MateKind::Perpendicular, _, _) => {
            let (u, v) = (
                a.direction().unwrap_or_default(),
                b.direction().unwrap_or_default(),
            );
            u.dot(&v).abs().asin()
        }
        (MateKind::Angle, _, _) => {
            let (u, v) = (
                a.direction().unwrap_or_default(),
                b.direction().unwrap_or_default(),
            );
            match about.and_then(|r| r.direction()) {
                Some(axis) => wrap(signed_angle(&u, &v, &axis) - value).abs(),
                None => (u.angle(&v) - value).abs(),
            }
        }
        _ => f64::INFINITY,
    }
}

impl Mate {
    /// Whether the mate's two entities (as they are now) fit its type and alignment
    /// ([`check_entities`]): [`DocumentError::MateEntity`] naming the mate if not.
    pub(crate) fn check_geometry(&self) -> Result<(), super::DocumentError> {
        let [a, b] = &self.entities;
        check_entities(self.kind, &a.geometry, &b.geometry, self.aligned).map_err(|e| {
            super::DocumentError::MateEntity {
                mate: self.name.clone().into(),
                source: Box::new(e),
            }
        })
    }
}

/// Whether the kind accepts these entity types (and, for coordinate systems, the
/// alignment); the error says what it needs.
pub(crate) fn check_entities(
    kind: MateKind,
    a: &Reference,
    b: &Reference,
    aligned: Option<bool>,
) -> Result<(), super::EntryError> {
    use Reference::*;
    let systems = [a, b]
        .iter()
        .filter(|r| matches!(r, CoordinateSystem(_)))
        .count();
    if systems == 2 && kind == MateKind::Coincident && aligned == Some(false) {
        return Err(super::EntryError::AntiAlignedSystems);
    }
    let ok = match kind {
        MateKind::Coincident => {
            systems != 1
                && !matches!(
                    (a, b),
                    (Plane { .. }, Axis { .. }) | (Axis { .. }, Plane { .. })
                )
        }
        MateKind::Concentric => matches!((a, b), (Axis { .. }, Axis { .. })),
        MateKind::Distance => matches!(
            (a, b),
            (Plane { .. }, Plane { .. })
                | (Point(_), Point(_))
                | (Plane { .. }, Point(_))
                | (Point(_), Plane { .. })
        ),
        MateKind::Parallel | MateKind::Perpendicular | MateKind::Angle => {
            a.direction().is_some() && b.direction().is_some()
        }
    };
    if ok {
        Ok(())
    } else {
        Err(super::EntryError::MateEntities {
            kind,
            a: a.kind_name(),
            b: b.kind_name(),
        })
    }
}

fn rotate_about(point: &Point3, q: UnitQuaternion<f64>) -> Transform {
    Transform::from_parts(point.coords - q * point.coords, q)
}

/// The world correction that makes `b` (on the mover) satisfy the mate against `a`.
fn correction(mate: &Mate, a: &Reference, b: &Reference, about: Option<&Reference>) -> Transform {
    use Reference::*;
    let d = kept_distance(mate);
    let translate = |v: Vec3| Transform::from_translation(v);
    let align = |u: &Vec3, v: &Vec3, at: &Point3| {
        let t = target_direction(mate, u, v, default_aligned(mate.kind, a));
        rotate_about(at, rotation_between(v, &t))
    };
    match (mate.kind, a, b) {
        (
            MateKind::Coincident | MateKind::Distance,
            Plane {
                point: pa,
                normal: na,
            },
            Plane {
                point: pb,
                normal: nb,
            },
        ) => {
            let r = align(na, nb, pb);
            r * translate(na * (d - na.dot(&(pb - pa))))
        }
        (
            MateKind::Coincident | MateKind::Distance,
            Plane {
                point: pa,
                normal: na,
            },
            Point(pb),
        ) => {
            let s = na.dot(&(pb - pa));
            let target = if s < 0.0 { -d } else { d };
            translate(na * (target - s))
        }
        (
            MateKind::Coincident | MateKind::Distance,
            Point(pb),
            Plane {
                point: pa,
                normal: na,
            },
        ) => {
            // The mover carries the plane: move it so that the point lies at the distance.
            let s = na.dot(&(pb - pa));
            let target = if s < 0.0 { -d } else { d };
            translate(-na * (target - s))
        }
        (MateKind::Coincident | MateKind::Distance, Point(pa), Point(pb)) => {
            let r = pb - pa;
            let dir = r.try_normalize(1e-12).unwrap_or_else(Vec3::x);
            translate(pa + dir * d - pb)
        }
        (
            MateKind::Coincident,
            Axis {
                point: pa,
                direction: da,
            },
            Point(pb),
        ) => {
            let r = pb - pa;
            translate(-(r - da * da.dot(&r)))
        }
        (
            MateKind::Coincident,
            Point(pb),
            Axis {
                point: pa,
                direction: da,
            },
        ) => {
            let r = pb - pa;
            translate(r - da * da.dot(&r))
        }
        (
            MateKind::Coincident | MateKind::Concentric,
            Axis {
                point: pa,
                direction: da,
            },
            Axis {
                point: pb,
                direction: db,
            },
        ) => {
            let rot = align(da, db, pb);
            let r = pb - pa;
            rot * translate(-(r - da * da.dot(&r)))
        }
        (MateKind::Coincident, CoordinateSystem(fa), CoordinateSystem(fb)) => {
            // b's system onto a's: b's pose followed by this is a's.
            fb.inverse() * *fa
        }
        (MateKind::Parallel | MateKind::Perpendicular | MateKind::Angle, _, _) => {
            angular_correction(mate, a, b, about)
        }
        _ => Transform::IDENTITY,
    }
}

/// The rotation that makes `b`'s direction (on the mover) parallel, perpendicular or
/// at the mate's angle (radians) to `a`'s; an angle mate with an `about` axis turns
/// about that axis.
fn angular_correction(
    mate: &Mate,
    a: &Reference,
    b: &Reference,
    about: Option<&Reference>,
) -> Transform {
    let value = mate.value.unwrap_or(0.0);
    let (u, v) = (
        a.direction().unwrap_or_default(),
        b.direction().unwrap_or_default(),
    );
    let at = b.anchor();
    match (
        mate.kind,
        about.and_then(|r| Some((r.anchor(), r.direction()?))),
    ) {
        (MateKind::Angle, Some((ap, axis))) => {
            let delta = wrap(value - signed_angle(&u, &v, &axis));
            rotate_about(
                &ap,
                UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), delta),
            )
        }
        (kind, _) => {
            let target_angle = match kind {
                MateKind::Parallel => {
                    if u.dot(&v) >= 0.0 {
                        0.0
                    } else {
                        std::f64::consts::PI
                    }
                }
                MateKind::Perpendicular => std::f64::consts::FRAC_PI_2,
                _ => value,
            };
            let axis = u
                .cross(&v)
                .try_normalize(1e-12)
                .unwrap_or_else(|| crate::math::perpendicular(&u));
            let delta = target_angle - u.angle(&v);
            rotate_about(
                &at,
                UnitQuaternion::from_axis_angle(&Unit::new_unchecked(axis), delta),
            )
        }
    }
}

/// Why the mates could not all be satisfied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mate `{mate}` cannot be satisfied (residual {residual:.3e}): the mates conflict or both sides are fixed")]
pub struct SolveError {
    /// The worst mate.
    pub mate: String,
    /// Its residual (mm or rad).
    pub residual: f64,
}

/// Residual below which a mate holds (mm or rad).
pub const SOLVE_TOLERANCE: f64 = 1e-9;

/// Moves non-fixed components until every mate holds. `fixed[i]` components never
/// move. On failure the poses are left as the last pass made them; the caller keeps a
/// copy to roll back.
pub fn solve(mates: &[Mate], poses: &mut [Transform], fixed: &[bool]) -> Result<(), SolveError> {
    if mates.is_empty() {
        return Ok(());
    }
    for _pass in 0..200 {
        let mut worst = 0.0f64;
        for mate in mates {
            let [ea, eb] = &mate.entities;
            let (a, b) = world(mate, poses);
            let about = mate
                .about
                .as_ref()
                .map(|e| e.geometry.posed(&poses[e.component]));
            let err = error(mate, &a, &b, about.as_ref());
            worst = worst.max(err);
            if err <= SOLVE_TOLERANCE * 0.1 {
                continue;
            }
            if !fixed[eb.component] {
                let c = correction(mate, &a, &b, about.as_ref());
                poses[eb.component] = poses[eb.component] * c;
            } else if !fixed[ea.component] {
                // Swap roles: the first side moves. Build the reversed mate's correction
                // by solving for b's frame and applying the inverse to a.
                let c = correction(mate, &a, &b, about.as_ref());
                poses[ea.component] = poses[ea.component] * c.inverse();
            }
        }
        if worst <= SOLVE_TOLERANCE {
            return Ok(());
        }
    }
    let (mate, residual) = mates
        .iter()
        .map(|m| (m.name.clone(), residual(m, poses)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or_default();
    if residual <= SOLVE_TOLERANCE {
        return Ok(());
    }
    Err(SolveError { mate, residual })
}
