//! numpy ↔ library values: poses, pose arrays, joint arrays. The one place where the
//! Python convention (column vectors, `T @ p`) meets the library's `Transform`
//! (SolidWorks row-vector matrix, `a * b` = a, then b).

use crate::error::{Error, Result};
use fitup::math::Transform;
use numpy::ndarray::{aview2, Array1, Array2, Array3, ArrayView1, ArrayView2, ArrayView3};
use numpy::{
    AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayLike1, PyArrayLike2,
    PyArrayMethods, PyUntypedArrayMethods,
};
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

/// A 4×4 argument's numbers as given (column-vector layout), or its shape when it is
/// not 4×4: a float64 array is read where it is (no copy of the array and none of
/// numpy's borrow bookkeeping, which cost more than the kinematics of one call: the 16
/// numbers are copied out at once, the GIL held); anything else (a list, another
/// dtype) is converted by numpy first, as a `PyArrayLike2` argument is.
pub enum Matrix4 {
    /// The numbers, `m[row][column]`.
    Numbers([[f64; 4]; 4]),
    /// The shape of an argument that is not 4×4.
    Shape(Vec<usize>),
}

impl Matrix4 {
    fn of_view(a: ArrayView2<'_, f64>) -> Self {
        if a.shape() != [4, 4] {
            return Self::Shape(a.shape().to_vec());
        }
        Self::Numbers(std::array::from_fn(|i| std::array::from_fn(|j| a[[i, j]])))
    }

    /// The pose (see [`pose_of`]).
    pub fn pose(&self, argument: &'static str) -> Result<Transform> {
        match self {
            Self::Numbers(c) => {
                let m = std::array::from_fn(|i| std::array::from_fn(|j| c[j][i]));
                Transform::from_matrix(&m).map_err(|source| Error::Pose { argument, source })
            }
            Self::Shape(shape) => Err(Error::Shape {
                argument,
                expected: "(4, 4)",
                shape: shape.clone(),
            }),
        }
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for Matrix4 {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(a) = ob.cast::<PyArray2<f64>>() {
            if a.shape() != [4, 4] {
                return Ok(Self::Shape(a.shape().to_vec()));
            }
            if a.is_c_contiguous() {
                if let Ok(v) = a.to_vec() {
                    return Ok(Self::Numbers(std::array::from_fn(|i| {
                        std::array::from_fn(|j| v[4 * i + j])
                    })));
                }
            }
            let mut m = [[0.0; 4]; 4];
            for (i, row) in m.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x = a.get_owned([i, j]).unwrap_or(f64::NAN);
                }
            }
            return Ok(Self::Numbers(m));
        }
        let a: PyArrayLike2<'py, f64, AllowTypeChange> = ob.extract()?;
        Ok(Self::of_view(a.as_array()))
    }
}

/// A joint array argument (rad, mm): a float64 array copied out where it is, as
/// [`Matrix4`] reads one; anything else converted by numpy first.
pub struct Joints(pub Vec<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for Joints {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(a) = ob.cast::<PyArray1<f64>>() {
            if let Ok(v) = a.to_vec() {
                return Ok(Self(v));
            }
        }
        let a: PyArrayLike1<'py, f64, AllowTypeChange> = ob.extract()?;
        Ok(Self(joints_of(a.as_array())))
    }
}

/// Rows of `width` numbers laid one after another (`flat.len()` a multiple of `width`)
/// as a new `(N, width)` array, copied once into numpy's own buffer.
pub fn flat_rows<'py>(py: Python<'py>, flat: &[f64], width: usize) -> Bound<'py, PyArray2<f64>> {
    match ArrayView2::from_shape((flat.len() / width.max(1), width), flat) {
        Ok(v) => PyArray2::from_array(py, &v),
        Err(_) => PyArray2::zeros(py, [0, width], false),
    }
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
