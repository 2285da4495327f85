//! fitup from Python: the native module `fitup._fitup`, re-exported by the Python
//! package `fitup` (python/fitup/).
//!
//! Library first: every call here converts Python values (numpy arrays, keyword
//! arguments) to the library's types, calls the library with the GIL released, and
//! converts the answer back. No geometry, planning or kinematics is written here.
//!
//! Units are the library's: **millimetres and radians** everywhere (joint arrays in
//! radians, mm for prismatic joints); `system_value` of a dimension alone is SI
//! (metres, radians), like the SolidWorks API.
//!
//! Poses are numpy 4×4 arrays in the **column-vector** convention of numpy, trimesh,
//! pinocchio and the robotics textbooks: `p_world = T @ [x, y, z, 1]`, translation
//! (mm) in `T[:3, 3]`, `A @ B` = apply `B`, then `A`. That is the transpose of the
//! document's SolidWorks row-vector matrix (`Transform::to_matrix`, translation in the
//! last row); the conversion is written once, in [`convert`].

use pyo3::prelude::*;

mod convert;
mod database;
mod document;
mod error;
mod options;
mod path;
mod robot;
mod script;

/// The native module (`fitup._fitup`).
#[pymodule]
fn _fitup(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<document::Document>()?;
    m.add_class::<path::Path>()?;
    m.add_class::<robot::Robot>()?;
    m.add_class::<database::Database>()?;
    m.add_function(wrap_pyfunction!(script::run_script, m)?)?;
    m.add_function(wrap_pyfunction!(robot::catalog_names, m)?)?;
    m.add_function(wrap_pyfunction!(path::planner_names, m)?)?;
    m.add_function(wrap_pyfunction!(options::option_keys, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
