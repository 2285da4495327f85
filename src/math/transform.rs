//! [`Transform`]: a rigid motion, stored as a nalgebra isometry, read and written in
//! the SolidWorks pose-matrix layout.

use super::{AngleConvention, Point3, Vec3};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, Unit, UnitQuaternion};
use std::fmt;

/// A rigid motion (rotation followed by translation), lengths in millimetres.
///
/// # Layout
/// The document and the scripting API use the SolidWorks pose matrix (seed 000,
/// formula (1)), which acts on **row vectors**: `[x' y' z' 1] = [x y z 1] · M` with
///
/// ```text
///     | a b c n |      rotation  a..i   (row 1 = image of the X axis, …)
/// M = | d e f o |      translation j k l (mm)
///     | g h i p |      scale m = 1, n = o = p = 0
///     | j k l m |
/// ```
///
/// Internally the motion is a column-vector isometry `p' = R p + t`; `R` is the
/// transpose of the `a..i` block.
///
/// # Composition
/// `a * b` is the matrix product in the row-vector layout above: apply `a` first,
/// then `b` (like `IMathTransform.Multiply`).
#[derive(Clone, Copy, PartialEq, Default)]
pub struct Transform {
    iso: Isometry3<f64>,
}

/// Why a 4×4 matrix is not a rigid pose matrix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TransformError {
    /// A value is NaN or infinite.
    #[error("the pose matrix has a non-finite value (NaN or infinity)")]
    NonFinite,
    /// The rotation block is not orthonormal with determinant +1.
    #[error("the rotation block a..i is not orthonormal (error {0:.2e} > 1e-6): scaling, shear or mirroring is not a rigid pose")]
    NotOrthonormal(f64),
    /// `m` is not 1.
    #[error("the scale m = {0} must be 1")]
    Scale(f64),
    /// `n o p` are not zero.
    #[error("the last column n o p = {0:?} must be 0 0 0")]
    Projective([f64; 3]),
    /// The axis of a rotation has zero length.
    #[error("the rotation axis has zero length")]
    ZeroAxis,
    /// [`Transform::orthonormalized`]: the block is farther from a rotation than
    /// rounding explains.
    #[error("the rotation block a..i is {0:.2e} from the nearest rotation (more than {max:.0e}): that is not rounding, it is scaling, shear or a wrong matrix", max = MAX_ORTHONORMALIZE)]
    FarFromRotation(f64),
}

/// How far (largest entry of `|RᵀR − I|`) a block may be from a rotation for
/// [`Transform::orthonormalized`]: numbers rounded to 3 significant digits are within
/// about 1e-3 of one.
pub const MAX_ORTHONORMALIZE: f64 = 1e-2;

/// A nalgebra isometry (column-vector convention, mm) is a pose: part frame → world.
///
/// # Examples
/// ```
/// use fitup::math::Transform;
/// use nalgebra::{Isometry3, Vector3};
/// let iso = Isometry3::translation(10.0, 0.0, 0.0);
/// let t: Transform = iso.into();
/// let back: Isometry3<f64> = t.into();
/// assert_eq!(back.translation.vector, Vector3::new(10.0, 0.0, 0.0));
/// ```
impl From<Isometry3<f64>> for Transform {
    fn from(iso: Isometry3<f64>) -> Self {
        Self::from_isometry(iso)
    }
}

/// The pose as a nalgebra isometry (column-vector convention, mm).
impl From<Transform> for Isometry3<f64> {
    fn from(t: Transform) -> Self {
        t.iso
    }
}

/// Orthonormality tolerance of the `a..i` block.
pub const ORTHONORMAL_TOLERANCE: f64 = 1e-6;

/// Orthonormality error (`|RᵀR − I|` max) below which `from_matrix` takes the block as
/// a rotation as it is: rounding of products of a few rotations stays far below it.
const EXACTLY_ORTHONORMAL: f64 = 1e-12;

/// The 3×3 block of a 4×4 SolidWorks-layout matrix as the rotation's matrix (the
/// block rows are the images of the axes, i.e. the columns of R), after checking
/// that every entry is finite and that the last row/column is (0, 0, 0, 1) within
/// `tolerance`.
fn rotation_block(m: &[[f64; 4]; 4], tolerance: f64) -> Result<Matrix3<f64>, TransformError> {
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(TransformError::NonFinite);
    }
    if (m[3][3] - 1.0).abs() > tolerance {
        return Err(TransformError::Scale(m[3][3]));
    }
    let npo = [m[0][3], m[1][3], m[2][3]];
    if npo.iter().any(|v| v.abs() > tolerance) {
        return Err(TransformError::Projective(npo));
    }
    Ok(Matrix3::new(
        m[0][0], m[1][0], m[2][0], //
        m[0][1], m[1][1], m[2][1], //
        m[0][2], m[1][2], m[2][2],
    ))
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        iso: Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.0),
            UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(1.0, 0.0, 0.0, 0.0)),
        ),
    };

    /// Wraps a nalgebra isometry (column-vector convention, mm).
    pub fn from_isometry(iso: Isometry3<f64>) -> Self {
        Self { iso }
    }

    /// The nalgebra isometry (column-vector convention, mm).
    pub fn isometry(&self) -> &Isometry3<f64> {
        &self.iso
    }

    /// A pure translation by `(x, y, z)` mm.
    pub fn from_translation(v: Vec3) -> Self {
        Self::from_isometry(Isometry3::from_parts(v.into(), UnitQuaternion::identity()))
    }

    /// A rotation of `angle` radians (right hand) about the line through `point` along
    /// `axis`.
    pub fn from_rotation_about(
        point: Point3,
        axis: Vec3,
        angle: f64,
    ) -> Result<Self, TransformError> {
        if !(point
            .coords
            .iter()
            .chain(axis.iter())
            .all(|v| v.is_finite())
            && angle.is_finite())
        {
            return Err(TransformError::NonFinite);
        }
        let axis = Unit::try_new(axis, 1e-12).ok_or(TransformError::ZeroAxis)?;
        let q = UnitQuaternion::from_axis_angle(&axis, angle);
        // p' = q (p - c) + c
        let t = point.coords - q * point.coords;
        Ok(Self::from_isometry(Isometry3::from_parts(t.into(), q)))
    }

    /// A rotation and translation from a unit quaternion and a translation (mm).
    pub fn from_parts(translation: Vec3, rotation: UnitQuaternion<f64>) -> Self {
        Self::from_isometry(Isometry3::from_parts(translation.into(), rotation))
    }

    /// The pose `X Y Z A B C`: position in mm, angles in **radians** in `conv`.
    pub fn from_xyzabc(xyz: Vec3, abc: [f64; 3], conv: AngleConvention) -> Self {
        Self::from_parts(xyz, conv.rotation(abc[0], abc[1], abc[2]))
    }

    /// The pose as `[x, y, z, a, b, c]`: mm and **radians** in `conv`.
    pub fn to_xyzabc(&self, conv: AngleConvention) -> [f64; 6] {
        let t = self.translation();
        let (a, b, c) = conv.angles(&self.iso.rotation);
        [t.x, t.y, t.z, a, b, c]
    }

    /// The pose as `[x, y, z, a, b, c]`: mm and **degrees** in `conv` — the pose
    /// triple users read and write (scripts, CSV, the database, printed poses).
    pub fn to_xyzabc_deg(&self, conv: AngleConvention) -> [f64; 6] {
        let [x, y, z, a, b, c] = self.to_xyzabc(conv);
        [x, y, z, a.to_degrees(), b.to_degrees(), c.to_degrees()]
    }

    /// Builds a transform from the 4×4 SolidWorks layout (rows as written in the
    /// document), checking that it is a rigid motion.
    pub fn from_matrix(m: &[[f64; 4]; 4]) -> Result<Self, TransformError> {
        let r = rotation_block(m, ORTHONORMAL_TOLERANCE)?;
        let err = (r.transpose() * r - Matrix3::identity()).abs().max();
        if err > ORTHONORMAL_TOLERANCE || r.determinant() < 0.0 {
            return Err(TransformError::NotOrthonormal(
                err.max(if r.determinant() < 0.0 { 2.0 } else { 0.0 }),
            ));
        }
        // An orthonormal block (every pose fitup writes, numpy's products of rotations)
        // is its own nearest rotation: the closed-form quaternion is exact, without
        // nalgebra's iterative projection, which started at the identity and took
        // several µs per pose (most of an IK call from Python, docs/performance.md).
        // A block only orthonormal within the tolerance (6-digit matrices) is still
        // projected, started at the closed-form guess.
        let closed = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
        let guess = UnitQuaternion::new_normalize(closed.into_inner());
        let rot = if err <= EXACTLY_ORTHONORMAL {
            guess
        } else {
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_eps(
                &r,
                f64::EPSILON,
                0,
                guess.to_rotation_matrix(),
            ))
        };
        Ok(Self::from_parts(Vec3::new(m[3][0], m[3][1], m[3][2]), rot))
    }

    /// The 4×4 matrix in the SolidWorks layout (see the type docs).
    pub fn to_matrix(&self) -> [[f64; 4]; 4] {
        let r = self.iso.rotation.to_rotation_matrix();
        let r = r.matrix();
        let t = self.iso.translation.vector;
        [
            [r[(0, 0)], r[(1, 0)], r[(2, 0)], 0.0],
            [r[(0, 1)], r[(1, 1)], r[(2, 1)], 0.0],
            [r[(0, 2)], r[(1, 2)], r[(2, 2)], 0.0],
            [t.x, t.y, t.z, 1.0],
        ]
    }

    /// The 16 numbers of `IMathTransform.ArrayData`: `a b c d e f g h i` (rotation),
    /// `j k l` (translation, **mm** — SolidWorks uses metres here), `m` (scale, 1),
    /// `n o p` (0).
    pub fn to_array_data(&self) -> [f64; 16] {
        let m = self.to_matrix();
        [
            m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1],
            m[2][2], //
            m[3][0], m[3][1], m[3][2], 1.0, 0.0, 0.0, 0.0,
        ]
    }

    /// Inverse of [`to_array_data`](Self::to_array_data).
    pub fn from_array_data(d: &[f64; 16]) -> Result<Self, TransformError> {
        Self::from_matrix(&[
            [d[0], d[1], d[2], d[13]],
            [d[3], d[4], d[5], d[14]],
            [d[6], d[7], d[8], d[15]],
            [d[9], d[10], d[11], d[12]],
        ])
    }

    /// The 16 numbers of `IMathTransform.ArrayData` in SolidWorks' own units: as
    /// [`to_array_data`](Self::to_array_data) with the translation `j k l` in
    /// **metres**.
    pub fn to_array_data_si(&self) -> [f64; 16] {
        let mut d = self.to_array_data();
        for v in &mut d[9..12] {
            *v /= 1000.0;
        }
        d
    }

    /// Inverse of [`to_array_data_si`](Self::to_array_data_si): SolidWorks'
    /// `IMathUtility.CreateTransform(ArrayData)`, translation in **metres**.
    pub fn from_array_data_si(d: &[f64; 16]) -> Result<Self, TransformError> {
        let mut mm = *d;
        for v in &mut mm[9..12] {
            *v *= 1000.0;
        }
        Self::from_array_data(&mm)
    }

    /// The rigid pose nearest to a 4×4 matrix whose rotation block was rounded (a
    /// spreadsheet's six digits, a CSV of a macro's output): the block's nearest
    /// rotation (polar decomposition), the translation as given (mm).
    ///
    /// Refused: non-finite values, a mirror (determinant < 0), a block farther than
    /// [`MAX_ORTHONORMALIZE`] from a rotation, and `m`, `n o p` off 1, 0 0 0 by more
    /// than that.
    ///
    /// # Examples
    /// ```
    /// use fitup::math::Transform;
    /// // 30° about Z, rounded to 4 digits
    /// let m = [[0.866, 0.5, 0.0, 0.0], [-0.5, 0.866, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [10.0, 0.0, 0.0, 1.0]];
    /// assert!(Transform::from_matrix(&m).is_err());
    /// let t = Transform::orthonormalized(&m)?;
    /// assert!((t.rotation().angle().to_degrees() - 30.0).abs() < 0.01);
    /// # Ok::<(), fitup::math::transform::TransformError>(())
    /// ```
    pub fn orthonormalized(m: &[[f64; 4]; 4]) -> Result<Self, TransformError> {
        let r = rotation_block(m, MAX_ORTHONORMALIZE)?;
        let err = (r.transpose() * r - Matrix3::identity()).abs().max();
        if r.determinant() <= 0.0 {
            return Err(TransformError::NotOrthonormal(2.0));
        }
        if err > MAX_ORTHONORMALIZE {
            return Err(TransformError::FarFromRotation(err));
        }
        let svd = r.svd(true, true);
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            return Err(TransformError::FarFromRotation(err));
        };
        let nearest = u * v_t;
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(nearest));
        Ok(Self::from_parts(Vec3::new(m[3][0], m[3][1], m[3][2]), rot))
    }

    /// The translation part (mm).
    pub fn translation(&self) -> Vec3 {
        self.iso.translation.vector
    }

    /// The rotation part.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        self.iso.rotation
    }

    /// The inverse motion.
    #[must_use]
    pub fn inverse(&self) -> Self {
        Self::from_isometry(self.iso.inverse())
    }

    /// `self` followed by `next` (row-vector product `self · next`).
    #[must_use]
    pub fn then(&self, next: &Self) -> Self {
        Self::from_isometry(next.iso * self.iso)
    }

    /// Maps a point (mm).
    pub fn apply(&self, p: &Point3) -> Point3 {
        self.iso * p
    }

    /// Maps a free vector (rotation only).
    pub fn apply_vector(&self, v: &Vec3) -> Vec3 {
        self.iso.rotation * v
    }

    /// Rotation angle (radians) and translation distance (mm) between two poses.
    pub fn distance_to(&self, other: &Self) -> (f64, f64) {
        (
            self.iso.rotation.angle_to(&other.iso.rotation),
            (self.translation() - other.translation()).norm(),
        )
    }

    /// Interpolates translation linearly and rotation by slerp, `s` in `[0, 1]`.
    pub fn interpolate(&self, other: &Self, s: f64) -> Self {
        let t = self.translation().lerp(&other.translation(), s);
        let q = self
            .iso
            .rotation
            .try_slerp(&other.iso.rotation, s, 1e-12)
            .unwrap_or(if s < 0.5 {
                self.iso.rotation
            } else {
                other.iso.rotation
            });
        Self::from_parts(t, q)
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        let q = self.iso.rotation.coords;
        self.iso
            .translation
            .vector
            .iter()
            .chain(q.iter())
            .all(|v| v.is_finite())
    }

    /// Approximate equality: rotation within `angle_tol` rad and translation within
    /// `dist_tol` mm.
    pub fn approx_eq(&self, other: &Self, dist_tol: f64, angle_tol: f64) -> bool {
        let (a, d) = self.distance_to(other);
        a <= angle_tol && d <= dist_tol
    }
}

impl std::ops::Mul for Transform {
    type Output = Transform;
    /// Row-vector product: apply `self`, then `rhs`.
    fn mul(self, rhs: Transform) -> Transform {
        self.then(&rhs)
    }
}

/// The full-precision matrix, rows `[a b c 0] [d e f 0] [g h i 0] [j k l 1]` (mm).
impl fmt::Debug for Transform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.to_matrix();
        write!(f, "Transform[")?;
        for (i, row) in m.iter().enumerate() {
            if i > 0 {
                write!(f, "; ")?;
            }
            write!(f, "{:?} {:?} {:?} {:?}", row[0], row[1], row[2], row[3])?;
        }
        write!(f, "]")
    }
}

/// The pose for people: `X 10 Y 0 Z 5 A 0° B 0° C 90°` (mm and degrees, default
/// convention `xyz`, 0.001 resolution, see [`super::format`]).
impl fmt::Display for Transform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&super::format::xyzabc_deg(
            &self.to_xyzabc_deg(AngleConvention::default()),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn row_vector_layout_matches_seed_formula() {
        // Rotate 90° about Z then translate by (10, 0, 0): X axis maps to Y.
        let t = Transform::from_rotation_about(Point3::origin(), Vec3::z(), FRAC_PI_2).unwrap()
            * Transform::from_translation(Vec3::new(10.0, 0.0, 0.0));
        let m = t.to_matrix();
        // Row 1 (a b c) is the image of the X axis.
        assert!((m[0][1] - 1.0).abs() < 1e-12);
        // [1 0 0 1] · M = (10, 1, 0)
        let p = [1.0, 0.0, 0.0, 1.0];
        let out: Vec<f64> = (0..4)
            .map(|c| (0..4).map(|r| p[r] * m[r][c]).sum())
            .collect();
        let q = t.apply(&Point3::new(1.0, 0.0, 0.0));
        assert!((out[0] - q.x).abs() < 1e-12 && (out[1] - q.y).abs() < 1e-12);
        assert!((q - Point3::new(10.0, 1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn matrix_and_array_data_round_trip() {
        let t = Transform::from_xyzabc(
            Vec3::new(1.0, -2.0, 3.5),
            [0.3, -0.2, 1.1],
            AngleConvention::XyzFixed,
        );
        let back = Transform::from_matrix(&t.to_matrix()).unwrap();
        assert!(t.approx_eq(&back, 1e-12, 1e-12));
        let back = Transform::from_array_data(&t.to_array_data()).unwrap();
        assert!(t.approx_eq(&back, 1e-12, 1e-12));
    }

    /// The closed-form conversion gives the rotation nalgebra's projection gives (the
    /// old `from_matrix`), for exact blocks on every branch of the quaternion formula
    /// (half turns included) and for blocks rounded to 6 digits, which are projected.
    #[test]
    fn from_matrix_matches_the_nearest_rotation() {
        let mut angles = vec![
            [0.0, 0.0, 0.0],
            [PI - 1e-5, 0.0, 0.0],
            [0.0, PI - 1e-5, 0.0],
        ];
        angles.extend([[0.0, 0.0, PI], [0.3, -0.2, 1.1]]);
        angles.extend([[2.9, 1.4, -2.8], [-1.2, 0.1, 3.0], [1.0, 3.1, 0.5]]);
        for abc in angles {
            let t =
                Transform::from_xyzabc(Vec3::new(1.0, -2.0, 3.5), abc, AngleConvention::XyzFixed);
            for digits in [None, Some(1e6)] {
                let mut m = t.to_matrix();
                if let Some(scale) = digits {
                    m.iter_mut()
                        .flatten()
                        .for_each(|v| *v = (*v * scale).round() / scale);
                }
                let got = Transform::from_matrix(&m).unwrap();
                let r = Matrix3::new(
                    m[0][0], m[1][0], m[2][0], m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2],
                );
                let nearest = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
                assert!(
                    got.rotation().angle_to(&nearest) < 1e-12,
                    "{abc:?} {digits:?}"
                );
                if digits.is_none() {
                    assert!(got.approx_eq(&t, 1e-12, 1e-12), "{abc:?}");
                }
            }
        }
    }

    #[test]
    fn inverse_law() {
        let t = Transform::from_xyzabc(
            Vec3::new(5.0, 6.0, 7.0),
            [1.0, 0.5, -2.0],
            AngleConvention::ZyxMoving,
        );
        assert!((t * t.inverse()).approx_eq(&Transform::IDENTITY, 1e-12, 1e-12));
    }

    #[test]
    fn rejects_non_rigid() {
        let mut m = Transform::IDENTITY.to_matrix();
        m[0][0] = 2.0;
        assert!(matches!(
            Transform::from_matrix(&m),
            Err(TransformError::NotOrthonormal(_))
        ));
        let mut m = Transform::IDENTITY.to_matrix();
        m[0][0] = -1.0;
        assert!(Transform::from_matrix(&m).is_err(), "mirror");
        let mut m = Transform::IDENTITY.to_matrix();
        m[3][3] = 2.0;
        assert!(matches!(
            Transform::from_matrix(&m),
            Err(TransformError::Scale(_))
        ));
        let mut m = Transform::IDENTITY.to_matrix();
        m[1][1] = f64::NAN;
        assert!(matches!(
            Transform::from_matrix(&m),
            Err(TransformError::NonFinite)
        ));
    }

    #[test]
    fn rotation_about_point_keeps_point_fixed() {
        let c = Point3::new(10.0, 20.0, 30.0);
        let t = Transform::from_rotation_about(c, Vec3::new(1.0, 1.0, 0.0), 0.7).unwrap();
        assert!((t.apply(&c) - c).norm() < 1e-12);
        assert!(Transform::from_rotation_about(c, Vec3::zeros(), 1.0).is_err());
    }

    #[test]
    fn composition_order_is_row_vector() {
        let a = Transform::from_translation(Vec3::new(1.0, 0.0, 0.0));
        let b = Transform::from_rotation_about(Point3::origin(), Vec3::z(), FRAC_PI_2).unwrap();
        // a then b: (0,0,0) -> (1,0,0) -> (0,1,0)
        let p = (a * b).apply(&Point3::origin());
        assert!((p - Point3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    }
}
