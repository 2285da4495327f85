//! `fitup.Path`: a planned path (found or not) and what it was planned with.

use crate::convert;
use fitup::planning::{MeshValidatorOptions, PlannedPath, PLANNER_NAMES};
use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A planned path for one component (``Document.plan_path``, ``plan_insertion``,
/// ``plan_disassembly``).
///
/// ``poses`` are the key poses, start first and goal last, as an ``(N, 4, 4)`` array
/// of column-vector pose matrices (part frame → world, mm); consecutive poses are
/// joined by straight edges (translation lerp + rotation slerp) that the validator
/// accepted. Empty (``N = 0``) when no path was found: ``reason`` says why.
#[pyclass(module = "fitup", name = "Path", frozen)]
pub struct Path {
    pub(crate) path: PlannedPath,
    /// The tolerance and edge check it was planned with (revalidation uses them).
    pub(crate) validator: MeshValidatorOptions,
    /// The component it moves.
    pub(crate) component: String,
    /// The planner's seed.
    pub(crate) seed: u64,
    /// The keyword options of the call, as JSON (stored with the path).
    pub(crate) options: serde_json::Value,
}

#[pymethods]
impl Path {
    /// Whether a path was found.
    #[getter]
    fn found(&self) -> bool {
        self.path.found()
    }

    /// Why no path was found (time limit, start in collision, …); None when found.
    #[getter]
    fn reason(&self) -> Option<String> {
        self.path.failure.map(|f| f.to_string())
    }

    /// Key poses, ``(N, 4, 4)``, column-vector matrices, mm, world frame.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        convert::poses_array(py, &self.path.poses)
    }

    /// Key-pose positions, ``(N, 3)``, mm, world frame.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let rows = self.path.poses.iter().map(|t| {
            let p = t.translation();
            [p.x, p.y, p.z]
        });
        convert::rows(py, rows, 3)
    }

    /// The component the path moves.
    #[getter]
    fn component(&self) -> &str {
        &self.component
    }

    /// The planner that made it (e.g. ``"rrt_connect"``,
    /// ``"lazy_disassemble_local_rrt+lazy_rrt_connect"``).
    #[getter]
    fn planner(&self) -> &'static str {
        self.path.planner
    }

    /// The seed it was planned with (same seed, same path, when the iteration limit
    /// and not the time limit ends the search).
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// Translation length after smoothing, mm.
    #[getter]
    fn length_mm(&self) -> f64 {
        self.path.length_mm
    }

    /// Total rotation along the path, radians.
    #[getter]
    fn rotation_rad(&self) -> f64 {
        self.path.rotation_rad
    }

    /// Planner iterations.
    #[getter]
    fn iterations(&self) -> usize {
        self.path.iterations
    }

    /// Collision checks made (poses + edges).
    #[getter]
    fn checks(&self) -> u64 {
        self.path.collision_checks()
    }

    /// Wall time of the whole call (search and smoothing), ms.
    #[getter]
    fn time_ms(&self) -> f64 {
        self.path.time_ms
    }

    /// How edges were checked (``continuous`` or the stepwise resolution).
    #[getter]
    fn resolution(&self) -> String {
        self.path.resolution.to_string()
    }

    /// Poses along the path at most ``step_mm`` mm (and as many degrees) apart,
    /// ``(M, 4, 4)``; key poses are kept. More than 1,000,000 poses is an
    /// ``InputError`` naming ``step_mm``, raised before anything is allocated.
    fn densify<'py>(&self, py: Python<'py>, step_mm: f64) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let poses = self
            .path
            .densify_as(step_mm, step_mm.to_radians(), "step_mm", step_mm)
            .map_err(|e| {
                crate::error::Error::Workspace(fitup::workspace::WorkspaceError::Limit(e))
            })?;
        Ok(convert::poses_array(py, &poses))
    }

    /// The path as a plain dict (picklable, for tables and batches): ``found``,
    /// ``reason``, ``planner``, ``component``, ``seed``, ``length_mm``,
    /// ``rotation_rad``, ``iterations``, ``checks``, ``time_ms``, ``key_poses`` and
    /// ``poses`` (the ``(N, 4, 4)`` array).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("found", self.found())?;
        d.set_item("reason", self.reason())?;
        d.set_item("planner", self.path.planner)?;
        d.set_item("component", &self.component)?;
        d.set_item("seed", self.seed)?;
        d.set_item("length_mm", self.path.length_mm)?;
        d.set_item("rotation_rad", self.path.rotation_rad)?;
        d.set_item("iterations", self.path.iterations)?;
        d.set_item("checks", self.path.collision_checks())?;
        d.set_item("time_ms", self.path.time_ms)?;
        d.set_item("key_poses", self.path.poses.len())?;
        d.set_item("poses", self.poses(py))?;
        Ok(d)
    }

    fn __len__(&self) -> usize {
        self.path.poses.len()
    }

    fn __repr__(&self) -> String {
        let p = &self.path;
        match &p.failure {
            None => format!(
                "Path({}: {} key poses, {:.1} mm, {:.1} deg, {} iterations, {:.1} ms)",
                p.planner,
                p.poses.len(),
                p.length_mm,
                p.rotation_rad.to_degrees(),
                p.iterations,
                p.time_ms
            ),
            Some(f) => format!(
                "Path({}: not found, {f}; {} iterations, {:.1} ms)",
                p.planner, p.iterations, p.time_ms
            ),
        }
    }
}

/// The planner names ``plan_path`` accepts.
#[pyfunction]
pub fn planner_names() -> Vec<&'static str> {
    PLANNER_NAMES.to_vec()
}
