//! Mass properties of closed triangle meshes: volume, surface area, mass, centre of
//! mass and inertia tensor, exact for the polyhedron the mesh bounds (the signed
//! tetrahedra of every triangle with a reference point, integrated in closed form:
//! D. Eberly, "Polyhedral Mass Properties (Revisited)", the formulas trimesh uses).
//!
//! Units: lengths in **mm**, mass in **kg**, density in **kg/m³** (SolidWorks'
//! material density unit: steel 7850, aluminium 2700), inertia in **kg·mm²**.
//! Properties are expressed in the frame the mesh's coordinates are in (the part
//! frame for a part's mesh); [`MassProperties::moved`] carries them through a pose,
//! [`MassProperties::in_frame`] re-expresses them in any coordinate system, and
//! [`MassProperties::combine`] adds bodies (a selection, an assembly).
//!
//! # Examples
//!
//! A 20 × 10 × 5 mm steel block:
//!
//! ```
//! use fitup::math::{Point3, Transform, Vec3};
//! use fitup::mesh::{MassProperties, Mesh};
//!
//! let block = Mesh::cuboid(Point3::origin(), Point3::new(20.0, 10.0, 5.0));
//! let m = MassProperties::of_mesh(&block, 7850.0)?;
//! assert!((m.volume - 1000.0).abs() < 1e-9); // mm³
//! assert!((m.mass - 7.85e-3).abs() < 1e-15); // kg
//! assert!((m.centre_of_mass - Point3::new(10.0, 5.0, 2.5)).norm() < 1e-12);
//! // Ixx about the centre of mass: m (b² + c²) / 12, kg·mm²
//! assert!((m.inertia[(0, 0)] - 7.85e-3 * (100.0 + 25.0) / 12.0).abs() < 1e-12);
//! // The same block placed 100 mm along X in the world:
//! let world = m.moved(&Transform::from_translation(Vec3::new(100.0, 0.0, 0.0)));
//! assert!((world.centre_of_mass.x - 110.0).abs() < 1e-12);
//! # Ok::<(), fitup::mesh::MassError>(())
//! ```

use super::Mesh;
use crate::math::{Point3, Transform, Vec3};
use nalgebra::Matrix3;

/// mm³ → m³.
const MM3_TO_M3: f64 = 1e-9;

/// Why mass properties cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MassError {
    /// The mesh does not bound a volume: holes, non-manifold or inconsistently
    /// oriented edges.
    #[error(
        "the mesh is not a closed solid ({boundary} open edges, {non_manifold} non-manifold, \
         {misoriented} misoriented): it bounds no volume, so it has no mass properties"
    )]
    NotClosed {
        /// Edges used by one triangle.
        boundary: usize,
        /// Edges used by more than two triangles.
        non_manifold: usize,
        /// Edges traversed twice the same way.
        misoriented: usize,
    },
    /// The enclosed volume is zero (a flat or empty mesh).
    #[error("the mesh encloses no volume (|V| = {0:e} mm³)")]
    NoVolume(f64),
    /// A density or mass that is not a finite number > 0.
    #[error("{what} must be a finite number > 0, not {value}")]
    BadValue {
        /// `density (kg/m³)` or `mass (kg)`.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// Nothing to combine.
    #[error("no bodies to combine")]
    Empty,
}

/// What gives a body its mass: a density, or its total mass (then the density is the
/// mass over the volume, as SolidWorks' "override mass").
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassSpec {
    /// Density, kg/m³.
    Density(f64),
    /// Total mass, kg.
    Mass(f64),
}

/// Mass properties of a body or a set of bodies, in one frame (mm, kg).
///
/// `inertia` is the inertia **tensor** about the centre of mass with the frame's axes
/// (kg·mm²): diagonal `Ixx = ∫(y² + z²) dm`, off-diagonal `Ixy = −∫xy dm` (the physics
/// convention of trimesh, URDF and pinocchio). SolidWorks' `IMassProperty` reports the
/// products of inertia without the minus sign: its `Lxy` is `−inertia[(0, 1)]`
/// ([`MassProperties::solidworks_moments`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Volume, mm³.
    pub volume: f64,
    /// Surface area, mm².
    pub area: f64,
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass, mm.
    pub centre_of_mass: Point3,
    /// Inertia tensor about the centre of mass, frame axes, kg·mm².
    pub inertia: Matrix3<f64>,
}

impl MassProperties {
    /// The mass properties of the solid a closed, consistently oriented mesh bounds,
    /// with uniform `density_kg_m3` (kg/m³). An inward-oriented mesh is read as the
    /// same solid (its normals are flipped).
    ///
    /// Errors: [`MassError::NotClosed`] for a mesh with holes or non-manifold or
    /// misoriented edges, [`MassError::NoVolume`], [`MassError::BadValue`].
    pub fn of_mesh(mesh: &Mesh, density_kg_m3: f64) -> Result<Self, MassError> {
        Self::of_mesh_with(mesh, MassSpec::Density(density_kg_m3))
    }

    /// [`of_mesh`](Self::of_mesh) with the mass given either way ([`MassSpec`]).
    pub fn of_mesh_with(mesh: &Mesh, spec: MassSpec) -> Result<Self, MassError> {
        match spec {
            MassSpec::Density(v) | MassSpec::Mass(v) if !(v.is_finite() && v > 0.0) => {
                return Err(MassError::BadValue {
                    what: if matches!(spec, MassSpec::Density(_)) {
                        "density (kg/m³)"
                    } else {
                        "mass (kg)"
                    },
                    value: v,
                });
            }
            _ => {}
        }
        let report = mesh.inspect();
        if !report.is_watertight() {
            return Err(MassError::NotClosed {
                boundary: report.boundary_edges,
                non_manifold: report.non_manifold_edges,
                misoriented: report.misoriented_edges,
            });
        }
        let unit = volume_integrals(mesh);
        // relative to the part's own size, wherever it stands
        let size = mesh.bounds().map(|b| (b.hi - b.lo).norm()).unwrap_or(0.0);
        if unit.volume.abs().partial_cmp(&(1e-12 * size * size * size))
            != Some(std::cmp::Ordering::Greater)
        {
            return Err(MassError::NoVolume(unit.volume));
        }
        let density_per_mm3 = match spec {
            MassSpec::Density(d) => d * MM3_TO_M3,
            MassSpec::Mass(m) => m / unit.volume,
        };
        Ok(MassProperties {
            volume: unit.volume,
            area: unit.area,
            mass: unit.volume * density_per_mm3,
            centre_of_mass: unit.centre,
            inertia: unit.inertia * density_per_mm3,
        })
    }

    /// The density, kg/m³ (mass over volume).
    pub fn density(&self) -> f64 {
        self.mass / (self.volume * MM3_TO_M3)
    }

    /// The same body moved by `pose` (its frame → the new frame, e.g. part frame →
    /// world): the centre of mass is mapped through the pose, the tensor rotated.
    pub fn moved(&self, pose: &Transform) -> Self {
        let r = pose.rotation().to_rotation_matrix();
        let r = r.matrix();
        MassProperties {
            centre_of_mass: pose.apply(&self.centre_of_mass),
            inertia: r * self.inertia * r.transpose(),
            ..*self
        }
    }

    /// The properties expressed in the coordinate system `frame` (its pose in the
    /// current frame, e.g. a coordinate system's pose in the world): centre of mass in
    /// the frame's coordinates, tensor along its axes. SolidWorks' "output coordinate
    /// system" (`IMassProperty.SetCoordinateSystem`).
    pub fn in_frame(&self, frame: &Transform) -> Self {
        self.moved(&frame.inverse())
    }

    /// The inertia tensor about `point` (same frame, mm) with the frame's axes,
    /// kg·mm² (parallel-axis theorem): SolidWorks' "moments of inertia taken at the
    /// output coordinate system" for `point` = the origin.
    pub fn inertia_about(&self, point: &Point3) -> Matrix3<f64> {
        let d = self.centre_of_mass - point;
        self.inertia + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * self.mass
    }

    /// The principal moments (kg·mm², ascending) and their axes (unit vectors, a
    /// right-handed set, in the frame), as SolidWorks' `PrincipleMomentsOfInertia`
    /// and `PrincipleAxesOfInertia`.
    pub fn principal(&self) -> ([f64; 3], [Vec3; 3]) {
        let eig = nalgebra::SymmetricEigen::new(self.inertia);
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let moments = idx.map(|i| eig.eigenvalues[i]);
        let mut axes = idx.map(|i| eig.eigenvectors.column(i).into_owned());
        // A right-handed set whatever order the solver gave.
        if axes[0].cross(&axes[1]).dot(&axes[2]) < 0.0 {
            axes[2] = -axes[2];
        }
        (moments, axes)
    }

    /// SolidWorks' moments of inertia at the centre of mass, `[Lxx, Lxy, Lxz, Lyx,
    /// Lyy, Lyz, Lzx, Lzy, Lzz]` (kg·mm²): the tensor with the products' sign flipped
    /// (`Lxy = ∫xy dm`).
    pub fn solidworks_moments(&self) -> [f64; 9] {
        let i = &self.inertia;
        [
            i[(0, 0)],
            -i[(0, 1)],
            -i[(0, 2)],
            -i[(1, 0)],
            i[(1, 1)],
            -i[(1, 2)],
            -i[(2, 0)],
            -i[(2, 1)],
            i[(2, 2)],
        ]
    }

    /// The properties of several bodies together (same frame): masses, volumes and
    /// areas add, the centre of mass is the mass-weighted mean, the tensors are moved
    /// to it by the parallel-axis theorem and added.
    ///
    /// Errors: [`MassError::Empty`] for no bodies.
    pub fn combine<'a>(
        bodies: impl IntoIterator<Item = &'a MassProperties>,
    ) -> Result<Self, MassError> {
        let bodies: Vec<&MassProperties> = bodies.into_iter().collect();
        if bodies.is_empty() {
            return Err(MassError::Empty);
        }
        let mass: f64 = bodies.iter().map(|b| b.mass).sum();
        // Weighted about the first body's centre: no precision lost far from the origin.
        let origin = bodies[0].centre_of_mass;
        let offset: Vec3 = bodies
            .iter()
            .map(|b| (b.centre_of_mass - origin) * b.mass)
            .sum::<Vec3>()
            / mass;
        let centre = origin + offset;
        let inertia = bodies
            .iter()
            .map(|b| b.inertia_about(&centre))
            .sum::<Matrix3<f64>>();
        Ok(MassProperties {
            volume: bodies.iter().map(|b| b.volume).sum(),
            area: bodies.iter().map(|b| b.area).sum(),
            mass,
            centre_of_mass: centre,
            inertia,
        })
    }
}

/// Volume, area, centroid and unit-density inertia (about the centroid) of a closed
/// mesh.
struct UnitIntegrals {
    volume: f64,
    area: f64,
    centre: Point3,
    inertia: Matrix3<f64>,
}

/// Eberly's closed-form integrals over the signed tetrahedra, taken about a point
/// near the mesh (the box centre) so that a part far from its origin keeps its
/// precision; sign-normalised so an inward-oriented mesh gives the same solid.
fn volume_integrals(mesh: &Mesh) -> UnitIntegrals {
    let o = mesh
        .bounds()
        .map(|b| nalgebra::center(&b.lo, &b.hi))
        .unwrap_or_else(Point3::origin);
    // 1, x, y, z, x², y², z², xy, yz, zx
    let mut s = [0.0f64; 10];
    let mut area = 0.0;
    for i in 0..mesh.triangles.len() {
        let [p0, p1, p2] = mesh.triangle(i).map(|p| p - o);
        let d = (p1 - p0).cross(&(p2 - p0));
        area += 0.5 * d.norm();
        let sub = |w0: f64, w1: f64, w2: f64| {
            let t0 = w0 + w1;
            let f1 = t0 + w2;
            let t1 = w0 * w0;
            let t2 = t1 + w1 * t0;
            let f2 = t2 + w2 * f1;
            let f3 = w0 * t1 + w1 * t2 + w2 * f2;
            let g0 = f2 + w0 * (f1 + w0);
            let g1 = f2 + w1 * (f1 + w1);
            let g2 = f2 + w2 * (f1 + w2);
            (f1, f2, f3, g0, g1, g2)
        };
        let (f1x, f2x, f3x, g0x, g1x, g2x) = sub(p0.x, p1.x, p2.x);
        let (_f1y, f2y, f3y, g0y, g1y, g2y) = sub(p0.y, p1.y, p2.y);
        let (_f1z, f2z, f3z, g0z, g1z, g2z) = sub(p0.z, p1.z, p2.z);
        s[0] += d.x * f1x;
        s[1] += d.x * f2x;
        s[2] += d.y * f2y;
        s[3] += d.z * f2z;
        s[4] += d.x * f3x;
        s[5] += d.y * f3y;
        s[6] += d.z * f3z;
        s[7] += d.x * (p0.y * g0x + p1.y * g1x + p2.y * g2x);
        s[8] += d.y * (p0.z * g0y + p1.z * g1y + p2.z * g2y);
        s[9] += d.z * (p0.x * g0z + p1.x * g1z + p2.x * g2z);
    }
    let mult = [
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 24.0,
        1.0 / 24.0,
        1.0 / 60.0,
        1.0 / 60.0,
        1.0 / 60.0,
        1.0 / 120.0,
        1.0 / 120.0,
        1.0 / 120.0,
    ];
    for (v, m) in s.iter_mut().zip(mult) {
        *v *= m;
    }
    if s[0] < 0.0 {
        // inward-oriented: every integral changes sign with the orientation
        for v in &mut s {
            *v = -*v;
        }
    }
    let volume = s[0];
    if volume == 0.0 {
        return UnitIntegrals {
            volume,
            area,
            centre: o,
            inertia: Matrix3::zeros(),
        };
    }
    let c = Vec3::new(s[1], s[2], s[3]) / volume;
    let ixx = s[5] + s[6] - volume * (c.y * c.y + c.z * c.z);
    let iyy = s[4] + s[6] - volume * (c.z * c.z + c.x * c.x);
    let izz = s[4] + s[5] - volume * (c.x * c.x + c.y * c.y);
    let ixy = -(s[7] - volume * c.x * c.y);
    let iyz = -(s[8] - volume * c.y * c.z);
    let izx = -(s[9] - volume * c.z * c.x);
    UnitIntegrals {
        volume,
        area,
        centre: o + c,
        inertia: Matrix3::new(ixx, ixy, izx, ixy, iyy, iyz, izx, iyz, izz),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
    }

    #[test]
    fn box_matches_closed_form() {
        let (a, b, c) = (30.0, 20.0, 10.0);
        let mesh = Mesh::cuboid(
            Point3::new(5.0, -7.0, 100.0),
            Point3::new(5.0 + a, 13.0, 110.0),
        );
        let m = MassProperties::of_mesh(&mesh, 2700.0).unwrap();
        let mass = 2700.0 * a * b * c * 1e-9;
        assert!(close(m.volume, a * b * c, 1e-12));
        assert!(close(m.mass, mass, 1e-12));
        assert!(close(m.area, 2.0 * (a * b + b * c + c * a), 1e-12));
        assert!((m.centre_of_mass - Point3::new(20.0, 3.0, 105.0)).norm() < 1e-10);
        assert!(close(
            m.inertia[(0, 0)],
            mass * (b * b + c * c) / 12.0,
            1e-10
        ));
        assert!(close(
            m.inertia[(1, 1)],
            mass * (a * a + c * c) / 12.0,
            1e-10
        ));
        assert!(close(
            m.inertia[(2, 2)],
            mass * (a * a + b * b) / 12.0,
            1e-10
        ));
        for (i, j) in [(0, 1), (1, 2), (0, 2)] {
            assert!(m.inertia[(i, j)].abs() < 1e-12 * mass * a * a);
        }
        assert!(close(m.density(), 2700.0, 1e-12));
    }

    /// A prism over a regular n-gon: the faceted cylinder's own closed form
    /// (polygon area n r² sin(2π/n) / 2, and the polygon's polar moment).
    #[test]
    fn faceted_cylinder_matches_the_polygon_formulas() {
        let (r, h, n) = (8.0, 40.0, 24usize);
        let mesh = Mesh::cylinder(r, h, n);
        let m = MassProperties::of_mesh(&mesh, 1000.0).unwrap();
        let area = n as f64 * r * r * (2.0 * PI / n as f64).sin() / 2.0;
        let vol = area * h;
        assert!(close(m.volume, vol, 1e-12));
        let mass = vol * 1e-6;
        // A regular n-gon's second moment about a central axis in its plane:
        // J/2 with J = n r⁴ sin(2π/n) (2 + cos(2π/n)) / 12 (per unit area density).
        let t = 2.0 * PI / n as f64;
        let jz = n as f64 * r.powi(4) * t.sin() * (2.0 + t.cos()) / 12.0;
        let izz = jz * h * 1e-6;
        let ixx = jz / 2.0 * h * 1e-6 + mass * h * h / 12.0;
        assert!(
            close(m.inertia[(2, 2)], izz, 1e-10),
            "{} {}",
            m.inertia[(2, 2)],
            izz
        );
        assert!(close(m.inertia[(0, 0)], ixx, 1e-10));
        assert!(close(m.inertia[(1, 1)], ixx, 1e-10));
        assert!((m.centre_of_mass - Point3::new(0.0, 0.0, h / 2.0)).norm() < 1e-12);
        // fine facets approach the round cylinder
        let fine = MassProperties::of_mesh(&Mesh::cylinder(r, h, 2000), 1000.0).unwrap();
        assert!(close(fine.volume, PI * r * r * h, 1e-5));
        assert!(close(
            fine.inertia[(2, 2)],
            PI * r * r * h * 1e-6 * r * r / 2.0,
            1e-5
        ));
    }

    #[test]
    fn moving_and_combining_agree_with_one_mesh() {
        let a = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 20.0, 30.0));
        let pose = Transform::from_rotation_about(
            Point3::new(3.0, 1.0, 2.0),
            Vec3::new(1.0, 2.0, 3.0),
            0.7,
        )
        .unwrap()
        .then(&Transform::from_translation(Vec3::new(500.0, -40.0, 7.0)));
        let direct = MassProperties::of_mesh(&a.transformed(&pose), 7850.0).unwrap();
        let moved = MassProperties::of_mesh(&a, 7850.0).unwrap().moved(&pose);
        assert!((direct.centre_of_mass - moved.centre_of_mass).norm() < 1e-9);
        assert!((direct.inertia - moved.inertia).abs().max() < 1e-9 * direct.inertia.abs().max());
        // in_frame undoes moved
        let back = moved.in_frame(&pose);
        assert!((back.centre_of_mass - Point3::new(5.0, 10.0, 15.0)).norm() < 1e-9);
        // two boxes side by side = one long box
        let left = Mesh::cuboid(Point3::origin(), Point3::new(10.0, 10.0, 10.0));
        let right = Mesh::cuboid(Point3::new(10.0, 0.0, 0.0), Point3::new(20.0, 10.0, 10.0));
        let long = Mesh::cuboid(Point3::origin(), Point3::new(20.0, 10.0, 10.0));
        let parts = [
            MassProperties::of_mesh(&left, 1000.0).unwrap(),
            MassProperties::of_mesh(&right, 1000.0).unwrap(),
        ];
        let both = MassProperties::combine(&parts).unwrap();
        let one = MassProperties::of_mesh(&long, 1000.0).unwrap();
        assert!((both.centre_of_mass - one.centre_of_mass).norm() < 1e-12);
        assert!((both.inertia - one.inertia).abs().max() < 1e-12);
        assert!(close(both.mass, one.mass, 1e-14));
    }

    #[test]
    fn principal_axes_of_a_rotated_box() {
        let mesh = Mesh::cuboid(Point3::origin(), Point3::new(40.0, 20.0, 10.0));
        let pose = Transform::from_rotation_about(Point3::origin(), Vec3::new(0.0, 0.0, 1.0), 0.5)
            .unwrap();
        let m = MassProperties::of_mesh(&mesh, 1000.0).unwrap().moved(&pose);
        let (moments, axes) = m.principal();
        let mass = m.mass;
        assert!(close(moments[0], mass * (400.0 + 100.0) / 12.0, 1e-10));
        assert!(close(moments[2], mass * (1600.0 + 400.0) / 12.0, 1e-10));
        // the smallest moment is about the long edge, rotated 0.5 rad about Z
        let long = Vec3::new(0.5f64.cos(), 0.5f64.sin(), 0.0);
        assert!(axes[0].dot(&long).abs() > 1.0 - 1e-12);
        // SolidWorks' products carry the other sign
        let sw = m.solidworks_moments();
        assert_eq!(sw[1], -m.inertia[(0, 1)]);
    }

    #[test]
    fn inward_and_far_away_meshes() {
        let mut inward = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 2.0, 3.0));
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        let m = MassProperties::of_mesh(&inward, 1000.0).unwrap();
        assert!(close(m.volume, 6.0, 1e-12));
        // a mm-sized part 1e6 mm from the origin keeps its precision
        let far = Mesh::cuboid(
            Point3::new(1e6, 1e6, 1e6),
            Point3::new(1e6 + 1.0, 1e6 + 2.0, 1e6 + 3.0),
        );
        let f = MassProperties::of_mesh(&far, 1000.0).unwrap();
        assert!(close(f.volume, 6.0, 1e-9));
        assert!(close(f.inertia[(0, 0)], f.mass * (4.0 + 9.0) / 12.0, 1e-6));
    }

    #[test]
    fn refusals() {
        let mut open = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        open.triangles.pop();
        assert!(matches!(
            MassProperties::of_mesh(&open, 1000.0),
            Err(MassError::NotClosed { boundary: 3, .. })
        ));
        let cube = Mesh::cuboid(Point3::origin(), Point3::new(1.0, 1.0, 1.0));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                MassProperties::of_mesh(&cube, bad),
                Err(MassError::BadValue { .. })
            ));
        }
        let m = MassProperties::of_mesh_with(&cube, MassSpec::Mass(2.0)).unwrap();
        assert!(close(m.mass, 2.0, 1e-15) && close(m.density(), 2e9, 1e-12));
        assert!(matches!(
            MassProperties::combine(&[]),
            Err(MassError::Empty)
        ));
    }
}
