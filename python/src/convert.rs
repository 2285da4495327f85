//! numpy ↔ library values: poses, pose arrays, joint arrays. The one place where the
//! Python convention (column vectors, `T @ p`) meets the library's `Transform`
//! (SolidWorks row-vector matrix, `a * b` = a, then b).

use crate::error::{Error, Result};
use fitup::math::Transform;
use numpy::ndarray::{aview2, Array1, Array2, Array3, ArrayView1, ArrayView2, ArrayView3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;

/// The column-vector 4×4 matrix of a pose (mm): the transpose of the document's
/// row-vector matrix.
pub fn matrix(t: &Transform) -> [[f64; 4]; 4] {
    let m = t.to_matrix();
    let mut c = [[0.0; 4]; 4];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = m[j][i];
        }
    }
    c
}

/// A pose from a column-vector 4×4 view (mm), checked to be a rigid motion.
pub fn pose_of(a: ArrayView2<'_, f64>, argument: &'static str) -> Result<Transform> {
    if a.shape() != [4, 4] {
        return Err(Error::Shape {
            argument,
            expected: "(4, 4)",
            shape: a.shape().to_vec(),
        });
    }
    let mut m = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            m[j][i] = a[[i, j]];
        }
    }
    Transform::from_matrix(&m).map_err(|source| Error::Pose { argument, source })
}

/// Poses from an `(N, 4, 4)` view; a single `(4, 4)` is one pose.
pub fn poses_of(a: ArrayView3<'_, f64>, argument: &'static str) -> Result<Vec<Transform>> {
    if a.shape()[1..] != [4, 4] {
        return Err(Error::Shape {
            argument,
            expected: "(N, 4, 4)",
            shape: a.shape().to_vec(),
        });
    }
    a.outer_iter().map(|p| pose_of(p, argument)).collect()
}

/// A pose as a new `(4, 4)` numpy array: one copy of 16 numbers from the stack into
/// numpy's own buffer (cheaper, for one small array, than handing numpy a Rust buffer
/// with the owner object that needs).
pub fn pose_array<'py>(py: Python<'py>, t: &Transform) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_array(py, &aview2(&matrix(t)))
}

/// Poses as a new `(N, 4, 4)` numpy array, written once into the buffer numpy then
/// owns (not copied again).
pub fn poses_array<'py>(py: Python<'py>, ts: &[Transform]) -> Bound<'py, PyArray3<f64>> {
    let mut flat = Vec::with_capacity(ts.len() * 16);
    for t in ts {
        flat.extend(matrix(t).iter().flatten());
    }
    // 16 numbers per pose: the shape always fits (the default, an empty array, is
    // never taken; it keeps this panic-free).
    Array3::from_shape_vec((ts.len(), 4, 4), flat)
        .unwrap_or_default()
        .into_pyarray(py)
}

/// A vector of numbers as a numpy array (the Vec's buffer becomes numpy's).
pub fn vector<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from_vec(v).into_pyarray(py)
}

/// Rows as an `(N, width)` array, written once into the buffer numpy then owns; a
/// row shorter than `width` is padded with NaN (none is: the library's rows have the
/// robot's width). `width` fixes the shape when there are no rows.
pub fn rows<'py, R: AsRef<[f64]>>(
    py: Python<'py>,
    rows: impl IntoIterator<Item = R>,
    width: usize,
) -> Bound<'py, PyArray2<f64>> {
    let mut flat = Vec::new();
    let mut n = 0;
    for r in rows {
        let r = r.as_ref();
        flat.extend((0..width).map(|j| r.get(j).copied().unwrap_or(f64::NAN)));
        n += 1;
    }
    Array2::from_shape_vec((n, width), flat)
        .unwrap_or_default()
        .into_pyarray(py)
}

/// `f` of each row of `a` (`(N, width)`) as a slice: the array's own memory for a
/// C-contiguous array (numpy's default layout), a copy of the row only for other
/// layouts.
pub fn map_rows<T>(a: ArrayView2<'_, f64>, mut f: impl FnMut(&[f64]) -> T) -> Vec<T> {
    a.outer_iter()
        .map(|r| match r.as_slice() {
            Some(s) => f(s),
            None => f(&r.to_vec()),
        })
        .collect()
}

/// A joint array (rad, mm for prismatic joints) as a Vec.
pub fn joints_of(a: ArrayView1<'_, f64>) -> Vec<f64> {
    a.iter().copied().collect()
}
