//! `fitup.Robot`: forward and inverse kinematics, single and batch.

use crate::convert;
use crate::error::{Error, Result};
use fitup::kinematics::{IkError, IkOptions, IkSolution};
use fitup::math::Transform;
use numpy::{
    AllowTypeChange, PyArray1, PyArray2, PyArray3, PyArrayLike1, PyArrayLike2, PyArrayLike3,
};
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::sync::Arc;

/// A serial robot: kinematic tree, base (world → robot root), tool (flange → TCP),
/// joint limits and its inverse-kinematics solver (closed form for OPW and UR arms,
/// numeric otherwise).
///
/// Joint arrays are radians (mm for prismatic joints), in joint order; poses are
/// column-vector 4×4 arrays, world frame, mm. Batch forms take ``(N, dof)`` joints or
/// ``(N, 4, 4)`` poses and release the GIL.
#[pyclass(module = "fitup", name = "Robot", frozen)]
pub struct Robot {
    robot: Arc<fitup::kinematics::Robot>,
}

/// Solutions' joints one row after another: on the stack for up to eight 12-joint
/// solutions (every branch of a 6-axis arm without ±360° variants), on the heap beyond.
struct FlatRows {
    stack: [f64; FlatRows::STACK],
    len: usize,
    heap: Vec<f64>,
}

impl Default for FlatRows {
    fn default() -> Self {
        Self {
            stack: [0.0; Self::STACK],
            len: 0,
            heap: Vec::new(),
        }
    }
}

impl FlatRows {
    const STACK: usize = 96;

    fn extend(&mut self, row: &[f64]) {
        if self.heap.is_empty() {
            if let Some(s) = self.stack.get_mut(self.len..self.len + row.len()) {
                s.copy_from_slice(row);
                self.len += row.len();
                return;
            }
            self.heap.extend_from_slice(&self.stack[..self.len]);
        }
        self.heap.extend_from_slice(row);
    }

    fn as_slice(&self) -> &[f64] {
        if self.heap.is_empty() {
            &self.stack[..self.len]
        } else {
            &self.heap
        }
    }
}

impl Robot {
    /// Wraps a robot shared with a document (copy on write: nothing here changes it).
    pub(crate) fn from_shared(robot: Arc<fitup::kinematics::Robot>) -> Self {
        Self { robot }
    }

    fn check_width(&self, width: usize) -> Result<()> {
        if width == self.robot.dof() {
            Ok(())
        } else {
            Err(Error::Kinematics(
                fitup::kinematics::KinematicsError::JointCount {
                    expected: self.robot.dof(),
                    got: width,
                },
            ))
        }
    }

    /// Every solution for `target` near `reference`, sorted by distance to it; an
    /// unreachable target or one whose solutions all break a joint limit has none.
    fn solutions(&self, target: &Transform, reference: &[f64]) -> Result<Vec<IkSolution>> {
        match self
            .robot
            .inverse(target, reference, &IkOptions::every_branch())
        {
            Ok(s) => Ok(s),
            Err(IkError::Unreachable(_)) | Err(IkError::JointLimits { .. }) => Ok(Vec::new()),
            Err(e) => Err(e.into()),
        }
    }

    /// [`Robot::solutions`]' joints, row after row, into `out`, without an
    /// `IkSolution` (a `Vec`) per solution ([`fitup::kinematics::Robot::inverse_each`]):
    /// the same solutions in the same order.
    fn solutions_into(
        &self,
        target: &Transform,
        reference: &[f64],
        out: &mut FlatRows,
    ) -> Result<()> {
        match self
            .robot
            .inverse_each(target, reference, &IkOptions::every_branch(), |q| {
                out.extend(q)
            }) {
            Ok(_) | Err(IkError::Unreachable(_)) | Err(IkError::JointLimits { .. }) => Ok(()),
            Err(e) => Err(e.into()),
        }
    }

    fn reference(
        &self,
        reference: Option<PyArrayLike1<'_, f64, AllowTypeChange>>,
    ) -> Result<Vec<f64>> {
        let q = match reference {
            Some(r) => convert::joints_of(r.as_array()),
            None => vec![0.0; self.robot.dof()],
        };
        self.check_width(q.len())?;
        Ok(q)
    }
}

#[pymethods]
impl Robot {
    /// A robot of the built-in catalog (``catalog_names()``: ``"nachi_mz07"``, ``"ur5"``,
    /// ``"kuka_kr6_r700"``, …), base at the origin, tool at the flange.
    #[staticmethod]
    fn catalog(name: &str) -> Result<Self> {
        let robot = fitup::kinematics::robot_by_name(name).ok_or_else(|| Error::Unknown {
            what: "catalog robot",
            name: name.to_string(),
            hint: fitup::diagnostics::suggestion(name, fitup::kinematics::catalog_names()),
        })?;
        Ok(Self {
            robot: Arc::new(robot),
        })
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.robot.name().to_string()
    }

    /// Number of joints.
    #[getter]
    fn dof(&self) -> usize {
        self.robot.dof()
    }

    /// The IK solver: ``"opw"``, ``"ur"`` (closed form, every branch) or ``"numeric"``.
    #[getter]
    fn solver(&self) -> &'static str {
        self.robot.solver_name()
    }

    /// Joint limits as an ``(dof, 2)`` array ``[min, max]`` (rad/mm; ±inf when a
    /// joint has none).
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let rows = self.robot.joint_limits().into_iter().map(|l| match l {
            Some(l) => [l.min, l.max],
            None => [f64::NEG_INFINITY, f64::INFINITY],
        });
        convert::rows(py, rows, 2)
    }

    /// The base pose (world → robot root), 4×4, mm.
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        convert::pose_array(py, &self.robot.base())
    }

    /// The tool (flange → TCP), 4×4, mm.
    #[getter]
    fn tool<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        convert::pose_array(py, &self.robot.tool())
    }

    /// A copy with another base pose (world → robot root, 4×4, mm).
    fn with_base(&self, base: PyArrayLike2<'_, f64, AllowTypeChange>) -> Result<Self> {
        let t = convert::pose_of(base.as_array(), "base")?;
        Ok(Self {
            robot: Arc::new((*self.robot).clone().with_base(t)),
        })
    }

    /// A copy with another tool (flange → TCP, 4×4, mm).
    fn with_tool(&self, tool: PyArrayLike2<'_, f64, AllowTypeChange>) -> Result<Self> {
        let t = convert::pose_of(tool.as_array(), "tool")?;
        Ok(Self {
            robot: Arc::new((*self.robot).clone().with_tool(t)),
        })
    }

    /// Forward kinematics: the TCP pose (4×4, world, mm) for joints ``q`` (rad/mm).
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLike1<'py, f64, AllowTypeChange>,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        let t = self.robot.tcp_pose(&convert::joints_of(q.as_array()))?;
        Ok(convert::pose_array(py, &t))
    }

    /// Forward kinematics of many configurations: ``q`` is ``(N, dof)`` (rad/mm,
    /// read in place when C-ordered); returns the TCP poses ``(N, 4, 4)`` (world, mm).
    /// GIL released.
    fn fk_batch<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLike2<'py, f64, AllowTypeChange>,
    ) -> Result<Bound<'py, PyArray3<f64>>> {
        let q = q.as_array();
        self.check_width(q.ncols())?;
        // The rows are read in place (C layout), GIL released.
        let poses = py.detach(|| {
            convert::map_rows(q, |r| self.robot.tcp_pose(r))
                .into_iter()
                .collect::<std::result::Result<Vec<_>, _>>()
        })?;
        Ok(convert::poses_array(py, &poses))
    }

    /// World poses of every link of the kinematic tree for joints ``q``:
    /// ``(links, 4, 4)``.
    fn link_poses<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLike1<'py, f64, AllowTypeChange>,
    ) -> Result<Bound<'py, PyArray3<f64>>> {
        let poses = self.robot.link_poses(&convert::joints_of(q.as_array()))?;
        Ok(convert::poses_array(py, &poses))
    }

    /// Inverse kinematics, every branch: the joint solutions ``(K, dof)`` (rad/mm)
    /// that put the TCP at ``target`` (4×4, world, mm) within the joint limits,
    /// sorted by distance to ``reference`` (default all zeros). ``K = 0`` when the
    /// target is unreachable.
    #[pyo3(signature = (target, reference = None))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        target: convert::Matrix4,
        reference: Option<convert::Joints>,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        // Arguments read as `Matrix4` / `Joints`: a float64 array without numpy's
        // borrow bookkeeping (most of this call's cost beside the kinematics).
        let t = target.pose("target")?;
        let r = match reference {
            Some(convert::Joints(q)) => q,
            None => vec![0.0; self.robot.dof()],
        };
        self.check_width(r.len())?;
        // A closed-form call is a few µs: releasing the GIL would cost a fair share of
        // it. The numeric solver's restarts can take milliseconds: released.
        let mut rows = FlatRows::default();
        if self.robot.closed_form() {
            self.solutions_into(&t, &r, &mut rows)?;
        } else {
            py.detach(|| self.solutions_into(&t, &r, &mut rows))?;
        }
        Ok(convert::flat_rows(py, rows.as_slice(), self.robot.dof()))
    }

    /// Every branch for many targets (``(N, 4, 4)``, world, mm): a list of
    /// ``(K_i, dof)`` arrays (rad/mm), each as ``ik`` gives it; GIL released. A
    /// C-ordered array is read in place.
    #[pyo3(signature = (targets, reference = None))]
    fn ik_batch<'py>(
        &self,
        py: Python<'py>,
        targets: PyArrayLike3<'py, f64, AllowTypeChange>,
        reference: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    ) -> Result<Bound<'py, PyList>> {
        let ts = convert::poses_of(targets.as_array(), "targets")?;
        let r = self.reference(reference)?;
        let all = py.detach(|| {
            ts.iter()
                .map(|t| self.solutions(t, &r))
                .collect::<Result<Vec<_>>>()
        })?;
        let dof = self.robot.dof();
        let arrays: Vec<Bound<'py, PyArray2<f64>>> = all
            .into_iter()
            .map(|s| convert::rows(py, s.iter().map(|s| &s.joints), dof))
            .collect();
        Ok(PyList::new(py, arrays)?)
    }

    /// IK along a path of poses (``(N, 4, 4)``, world, mm): for each, the solution
    /// nearest to the previous one (the first nearest to ``start``), ``(N, dof)``
    /// (rad/mm); a row of NaN where a pose has no solution (the next is solved near
    /// the last one found). GIL released.
    #[pyo3(signature = (targets, start = None))]
    fn ik_path<'py>(
        &self,
        py: Python<'py>,
        targets: PyArrayLike3<'py, f64, AllowTypeChange>,
        start: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        let ts = convert::poses_of(targets.as_array(), "targets")?;
        let s = self.reference(start)?;
        let dof = self.robot.dof();
        let chain = py.detach(|| self.robot.inverse_chain(&ts, &s, &IkOptions::default()));
        // A pose without a solution is a row of NaN (`rows` pads a short row).
        let none: [f64; 0] = [];
        Ok(convert::rows(
            py,
            chain
                .iter()
                .map(|s| s.as_ref().map_or(&none[..], |s| &s.joints[..])),
            dof,
        ))
    }

    /// The joint index (0-based) of the first joint of ``q`` outside its limits, or
    /// None.
    fn limit_violation(&self, q: PyArrayLike1<'_, f64, AllowTypeChange>) -> Result<Option<usize>> {
        let q = convert::joints_of(q.as_array());
        self.check_width(q.len())?;
        Ok(self.robot.limit_violation(&q))
    }

    /// Joints as an array helper: zeros of the robot's width.
    fn zeros<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        convert::vector(py, vec![0.0; self.robot.dof()])
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot({:?}: {} joints, {} IK)",
            self.robot.name(),
            self.robot.dof(),
            self.robot.solver_name()
        )
    }
}

/// Names of the built-in catalog robots.
#[pyfunction]
pub fn catalog_names() -> Vec<&'static str> {
    fitup::kinematics::catalog_names()
}
