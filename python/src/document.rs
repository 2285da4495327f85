//! `fitup.Document`: an assembly document and every document-level request
//! (interference, sweeps, planning, robots, programs, sequences).

use crate::convert;
use crate::error::{Argument, Error, Result};
use crate::options;
use crate::path::Path;
use fitup::collision::Contact;
use fitup::document::{Dimension, DimensionKind};
use fitup::options::{AddMate, Check, Plan, Sequence, Sweep};
use fitup::planning::Control;
use fitup::workspace::{Revalidation, SceneCache, Workspace};
use numpy::{AllowTypeChange, PyArray2, PyArrayLike2, PyArrayLike3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::{Mutex, MutexGuard};

/// The document and the collision scene cache kept between calls (colliders are
/// built once per mesh).
pub(crate) struct Inner {
    pub(crate) doc: fitup::document::Document,
    pub(crate) scene: SceneCache,
}

/// An assembly document (YAML + meshes): parts, components at poses, mates,
/// dimensions, robots.
///
/// ``Document(path)`` loads and validates the file and its meshes and solves the mates;
/// errors are ``DocumentError`` with ``file``, ``line`` and ``column``. Poses are
/// column-vector 4×4 numpy arrays (part frame → world, mm); lengths mm, angles
/// radians. Long calls (planning, sequences, sweeps, interference) release the GIL;
/// calls on one document from several threads run one at a time.
#[pyclass(module = "fitup", name = "Document", frozen)]
pub struct Document {
    inner: Mutex<Inner>,
}

impl Document {
    pub(crate) fn lock(&self) -> Result<MutexGuard<'_, Inner>> {
        self.inner
            .lock()
            .map_err(|_| Error::Poisoned { what: "document" })
    }

    /// Runs `f` on the workspace of the document as it is now, GIL released.
    fn with_workspace<R: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&Workspace) -> Result<R> + Send,
    ) -> Result<R> {
        py.detach(|| {
            let mut inner = self.lock()?;
            let Inner { doc, scene } = &mut *inner;
            let ws = Workspace::new(doc, scene)?;
            f(&ws)
        })
    }
}

/// The indices of the named components, or of every component neither suppressed
/// nor hidden.
fn shown(doc: &fitup::document::Document, names: Option<Vec<String>>) -> Result<Vec<usize>> {
    Ok(match names {
        Some(n) => n
            .iter()
            .map(|c| doc.component_index(c))
            .collect::<std::result::Result<_, _>>()?,
        None => (0..doc.components().len())
            .filter(|&i| doc.components()[i].is_shown())
            .collect(),
    })
}

/// A mesh as numpy arrays: vertices `(N, 3)` and triangles `(M, 3)`.
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// Whose properties: exactly one of a component and a part.
fn owner<'a>(
    component: Option<&'a str>,
    part: Option<&'a str>,
) -> Result<fitup::document::PropertyOwner<'a>> {
    match (component, part) {
        (Some(c), None) => Ok(fitup::document::PropertyOwner::Component(c)),
        (None, Some(p)) => Ok(fitup::document::PropertyOwner::Part(p)),
        _ => Err(Error::Argument(Argument::OneOwner)),
    }
}

fn contact_dict<'py>(py: Python<'py>, c: &Contact) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let state = match c {
        Contact::Separate => "separate",
        Contact::Touching => "touching",
        Contact::Interfering { .. } => "interfering",
        // The library may add verdicts; say so rather than guess.
        #[allow(unreachable_patterns)]
        _ => "unknown",
    };
    d.set_item("state", state)?;
    d.set_item("depth_mm", c.depth())?;
    Ok(d)
}

#[pymethods]
impl Document {
    /// Loads the document at ``path`` (its meshes inside its project: the nearest
    /// folder holding ``fitup.toml``, else the document's folder).
    #[new]
    fn new(py: Python<'_>, path: std::path::PathBuf) -> Result<Self> {
        let doc = py.detach(|| fitup::document::Document::open(&path))?;
        Ok(Self {
            inner: Mutex::new(Inner {
                doc,
                scene: SceneCache::new(),
            }),
        })
    }

    /// The document's file.
    #[getter]
    fn path(&self) -> Result<std::path::PathBuf> {
        Ok(self.lock()?.doc.path().to_path_buf())
    }

    /// Component names in file order.
    fn components(&self) -> Result<Vec<String>> {
        Ok(self
            .lock()?
            .doc
            .components()
            .iter()
            .map(|c| c.name.clone())
            .collect())
    }

    /// Part names in file order.
    fn parts(&self) -> Result<Vec<String>> {
        Ok(self.lock()?.doc.parts().map(|p| p.name.clone()).collect())
    }

    /// One component as a dict: ``name``, ``part``, ``fixed``, ``pose`` (4×4, mm),
    /// ``mass`` (kg or None), ``threaded``, ``color`` (RGB in 0..1 or None),
    /// ``suppressed``, ``hidden``, ``properties`` (its own custom properties as
    /// ``(name, text)`` pairs in document order), ``part_file`` (its part's file).
    fn component<'py>(&self, py: Python<'py>, name: &str) -> Result<Bound<'py, PyDict>> {
        let inner = self.lock()?;
        let c = inner.doc.component(name)?;
        let d = PyDict::new(py);
        d.set_item("name", &c.name)?;
        d.set_item("part", &c.part)?;
        d.set_item("fixed", c.fixed)?;
        d.set_item("pose", convert::pose_array(py, &c.transform))?;
        d.set_item("mass", c.mass)?;
        d.set_item("threaded", c.threaded)?;
        d.set_item("color", c.color.map(|c| c.to_vec()))?;
        d.set_item("suppressed", c.is_suppressed())?;
        d.set_item("hidden", c.hidden)?;
        d.set_item(
            "properties",
            c.properties.clone().into_iter().collect::<Vec<_>>(),
        )?;
        d.set_item("part_file", inner.doc.part(&c.part)?.mesh_path.clone())?;
        Ok(d)
    }

    /// The pose of component ``name``: 4×4 column-vector matrix, part frame → world, mm.
    fn pose<'py>(&self, py: Python<'py>, name: &str) -> Result<Bound<'py, PyArray2<f64>>> {
        let inner = self.lock()?;
        Ok(convert::pose_array(
            py,
            &inner.doc.component(name)?.transform,
        ))
    }

    /// Sets the pose of component ``name`` (4×4, mm; a rigid motion). Fixed and
    /// robot-driven components are refused; mates are not re-solved.
    fn set_pose(&self, name: &str, pose: PyArrayLike2<'_, f64, AllowTypeChange>) -> Result<()> {
        let t = convert::pose_of(pose.as_array(), "pose")?;
        self.lock()?.doc.set_transform(name, t)?;
        Ok(())
    }

    /// A reference (plane, axis, point or coordinate system of the component's part)
    /// in the world at the component's pose: a dict ``kind`` (``"plane"``, ``"axis"``,
    /// ``"point"``, ``"coordinate_system"``), ``point`` (mm, ``(3,)``; a coordinate
    /// system's origin), ``direction`` (the unit normal or axis direction, None for a
    /// point or a coordinate system) and ``pose`` (a coordinate system's 4×4
    /// column-vector pose, system → world, mm; None for the others).
    fn reference<'py>(
        &self,
        py: Python<'py>,
        component: &str,
        name: &str,
    ) -> Result<Bound<'py, PyDict>> {
        let inner = self.lock()?;
        let i = inner.doc.component_index(component)?;
        let r = inner.doc.world_reference(i, name)?;
        let d = PyDict::new(py);
        d.set_item("kind", r.kind_name())?;
        let p = r.anchor();
        d.set_item("point", convert::vector(py, vec![p.x, p.y, p.z]))?;
        d.set_item(
            "direction",
            r.direction()
                .map(|v| convert::vector(py, vec![v.x, v.y, v.z])),
        )?;
        d.set_item(
            "pose",
            r.coordinate_system().map(|f| convert::pose_array(py, &f)),
        )?;
        Ok(d)
    }

    /// Coordinate system ``name`` of component ``component``'s part in the world: its
    /// 4×4 column-vector pose (system → world, mm), SolidWorks'
    /// ``CoordinateSystemFeatureData.Transform`` times ``Transform2``.
    fn coordinate_system<'py>(
        &self,
        py: Python<'py>,
        component: &str,
        name: &str,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        let inner = self.lock()?;
        let i = inner.doc.component_index(component)?;
        Ok(convert::pose_array(
            py,
            &inner.doc.coordinate_system(i, name)?,
        ))
    }

    /// Coordinate system ``name`` of part ``part`` in the part frame: its 4×4
    /// column-vector pose (system → part, mm).
    fn part_coordinate_system<'py>(
        &self,
        py: Python<'py>,
        part: &str,
        name: &str,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        let inner = self.lock()?;
        Ok(convert::pose_array(
            py,
            &inner.doc.part_coordinate_system(part, name)?,
        ))
    }

    /// Every mate in document order as dicts: ``name``, ``type``, ``entities``
    /// (``component/reference`` twice), ``value`` (mm or degrees, None), ``aligned``
    /// (None for mates of points), ``suppressed``, ``active`` (solved: neither it nor
    /// a component it joins is suppressed).
    fn mates<'py>(&self, py: Python<'py>) -> Result<Vec<Bound<'py, PyDict>>> {
        let inner = self.lock()?;
        let doc = &inner.doc;
        let mut out = Vec::new();
        for m in doc.mates() {
            let d = PyDict::new(py);
            d.set_item("name", &m.name)?;
            d.set_item("type", m.kind.name())?;
            let entities: Vec<String> = m
                .entities
                .iter()
                .map(|e| format!("{}/{}", doc.components()[e.component].name, e.reference))
                .collect();
            d.set_item("entities", entities)?;
            d.set_item(
                "value",
                m.value.map(|v| {
                    if m.kind == fitup::document::MateKind::Angle {
                        v.to_degrees()
                    } else {
                        v
                    }
                }),
            )?;
            d.set_item("aligned", doc.mate_alignment(&m.name)?)?;
            d.set_item("suppressed", m.suppressed)?;
            d.set_item("active", doc.mate_active(m))?;
            out.push(d);
        }
        Ok(out)
    }

    /// Adds a mate of ``type`` (``"coincident"``, ``"concentric"``, ``"parallel"``,
    /// ``"perpendicular"``, ``"distance"``, ``"angle"``) between entities ``a`` and
    /// ``b`` (``component/reference``) and solves it. Keywords (the mate table of
    /// docs/api.md): ``value`` (mm or degrees), ``aligned``, ``about``.
    #[pyo3(signature = (name, r#type, a, b, **options))]
    fn add_mate(
        &self,
        py: Python<'_>,
        name: &str,
        r#type: &str,
        a: &str,
        b: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> Result<()> {
        let (o, _) = options::read::<AddMate>(py, options)?;
        let spec = o.spec(name, r#type, a, b)?;
        self.lock()?.doc.add_mate(&spec)?;
        Ok(())
    }

    /// Deletes a mate; nothing moves.
    fn delete_mate(&self, name: &str) -> Result<()> {
        self.lock()?.doc.delete_mate(name)?;
        Ok(())
    }

    /// Flips a mate between aligned and anti-aligned and re-solves.
    fn flip_mate(&self, name: &str) -> Result<()> {
        self.lock()?.doc.flip_mate(name)?;
        Ok(())
    }

    /// Sets a mate aligned (True), anti-aligned (False) or to its kind's default
    /// (None), and re-solves.
    fn set_mate_aligned(&self, name: &str, aligned: Option<bool>) -> Result<()> {
        self.lock()?.doc.set_mate_aligned(name, aligned)?;
        Ok(())
    }

    /// Suppresses or unsuppresses a mate and re-solves.
    fn set_mate_suppressed(&self, name: &str, suppressed: bool) -> Result<()> {
        self.lock()?.doc.set_mate_suppressed(name, suppressed)?;
        Ok(())
    }

    /// Removes a component. With ``with_mates=False`` a component that has mates is
    /// refused (the error names them); with ``True`` its mates are deleted with it
    /// (unless an equation uses one of their dimensions). Returns the deleted mates'
    /// names.
    #[pyo3(signature = (name, with_mates = false))]
    fn remove_component(&self, name: &str, with_mates: bool) -> Result<Vec<String>> {
        let mates = if with_mates {
            fitup::document::RemoveMates::Delete
        } else {
            fitup::document::RemoveMates::Refuse
        };
        let deleted = self.lock()?.doc.remove_component(name, mates)?;
        Ok(deleted.into_iter().map(|m| m.name).collect())
    }

    /// Every sub-assembly's full name (``Cart-1``, ``Cart-1/Axle-1``), parents first.
    fn sub_assemblies(&self) -> Result<Vec<String>> {
        Ok(self
            .lock()?
            .doc
            .sub_assemblies()
            .iter()
            .map(|a| a.name.clone())
            .collect())
    }

    /// The direct children (sub-assemblies, then components, by full name) of
    /// sub-assembly ``name``, or of the top level for None.
    #[pyo3(signature = (name = None))]
    fn children(&self, name: Option<&str>) -> Result<Vec<String>> {
        Ok(self.lock()?.doc.children(name)?)
    }

    /// The parent sub-assembly of a component or sub-assembly; None at the top level.
    fn parent(&self, name: &str) -> Result<Option<String>> {
        Ok(self.lock()?.doc.parent_of(name)?)
    }

    /// A sub-assembly's pose in the assembly frame: 4×4 column-vector matrix, mm.
    fn sub_assembly_pose<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        let inner = self.lock()?;
        Ok(convert::pose_array(
            py,
            &inner.doc.sub_assembly(name)?.transform,
        ))
    }

    /// Moves a sub-assembly, and everything in it rigidly, to ``pose`` (4×4, mm,
    /// assembly frame). Refused when a component inside is fixed.
    fn set_sub_assembly_pose(
        &self,
        name: &str,
        pose: PyArrayLike2<'_, f64, AllowTypeChange>,
    ) -> Result<()> {
        let t = convert::pose_of(pose.as_array(), "pose")?;
        self.lock()?.doc.set_sub_assembly_transform(name, t)?;
        Ok(())
    }

    /// Adds an empty sub-assembly ``name`` (a full name whose parent exists) at
    /// ``pose`` (4×4, mm; identity when None).
    #[pyo3(signature = (name, pose = None))]
    fn add_sub_assembly(
        &self,
        name: &str,
        pose: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
    ) -> Result<()> {
        let t = match pose {
            Some(p) => convert::pose_of(p.as_array(), "pose")?,
            None => fitup::math::Transform::IDENTITY,
        };
        self.lock()?.doc.add_sub_assembly(name, t)?;
        Ok(())
    }

    /// The document file a sub-assembly holds (its ``file:`` key, relative to the
    /// document holding the entry), or None for a group of this document.
    fn sub_assembly_file(&self, name: &str) -> Result<Option<String>> {
        Ok(self
            .lock()?
            .doc
            .sub_assembly(name)?
            .file
            .as_ref()
            .map(|f| f.file.clone()))
    }

    /// Whether a sub-assembly is suppressed, itself or by a suppressed sub-assembly
    /// holding it.
    fn sub_assembly_suppressed(&self, name: &str) -> Result<bool> {
        Ok(self.lock()?.doc.sub_assembly_suppressed(name)?)
    }

    /// Suppresses (or unsuppresses) a sub-assembly and everything it holds at every
    /// level, then re-solves; saved with the document (or its sub-document).
    fn set_sub_assembly_suppressed(&self, name: &str, suppressed: bool) -> Result<()> {
        self.lock()?
            .doc
            .set_sub_assembly_suppressed(name, suppressed)?;
        Ok(())
    }

    /// The sub-document files the last ``save`` wrote besides the document's own.
    fn saved_sub_documents(&self) -> Result<Vec<String>> {
        Ok(self
            .lock()?
            .doc
            .saved_sub_documents()
            .iter()
            .map(|p| p.to_string_lossy().into_owned())
            .collect())
    }

    /// The equations in order (SolidWorks' ``IEquationMgr``), each a dict: ``text``
    /// (``"name" = expression``), ``name`` (the global variable or dimension it
    /// sets), ``expression``, ``value`` (at the last rebuild: mm, degrees, or no unit
    /// for a global variable) and ``global`` (True for a global variable).
    fn equations<'py>(&self, py: Python<'py>) -> Result<Vec<Bound<'py, PyDict>>> {
        let inner = self.lock()?;
        let mut out = Vec::with_capacity(inner.doc.equations().len());
        for e in inner.doc.equations() {
            let d = PyDict::new(py);
            d.set_item("text", e.text())?;
            d.set_item("name", &e.target)?;
            d.set_item("expression", &e.expression)?;
            d.set_item("value", e.value)?;
            d.set_item("global", e.is_global())?;
            out.push(d);
        }
        Ok(out)
    }

    /// Adds an equation (``'"Factor" = 2'``, ``'"D1@lift" = 10 * "Factor"'``) at
    /// ``index`` (None: at the end) and rebuilds; returns its index. Refused, with
    /// nothing changed, when it does not evaluate (``DocumentError`` naming the
    /// equation and the cause).
    #[pyo3(signature = (text, index = None))]
    fn add_equation(&self, text: &str, index: Option<usize>) -> Result<usize> {
        Ok(self.lock()?.doc.add_equation(index, text)?)
    }

    /// Replaces equation ``index`` (0-based) by ``text`` and rebuilds.
    fn set_equation(&self, index: usize, text: &str) -> Result<()> {
        self.lock()?.doc.set_equation(index, text)?;
        Ok(())
    }

    /// Deletes equation ``index`` and rebuilds; what it set keeps its value.
    fn delete_equation(&self, index: usize) -> Result<()> {
        self.lock()?.doc.delete_equation(index)?;
        Ok(())
    }

    /// A global variable's value (no unit).
    fn global_variable(&self, name: &str) -> Result<f64> {
        Ok(self.lock()?.doc.global_variable(name)?)
    }

    /// Sets a global variable (its equation becomes ``"name" = value``) and
    /// rebuilds: the dimensions it drives and the mates follow.
    fn set_global_variable(&self, name: &str, value: f64) -> Result<()> {
        self.lock()?.doc.set_global_variable(name, value)?;
        Ok(())
    }

    /// Suppresses or unsuppresses a component (not checked, planned around,
    /// sequenced, weighed or exported; its mates inactive) and re-solves.
    fn set_suppressed(&self, name: &str, suppressed: bool) -> Result<()> {
        self.lock()?.doc.set_suppressed(name, suppressed)?;
        Ok(())
    }

    /// Hides (checked, not exported) or shows a component.
    fn set_hidden(&self, name: &str, hidden: bool) -> Result<()> {
        self.lock()?.doc.set_hidden(name, hidden)?;
        Ok(())
    }

    /// The custom properties of a component or a part (give exactly one), as
    /// ``(name, text)`` pairs in document order.
    #[pyo3(signature = (component = None, part = None))]
    fn properties(
        &self,
        component: Option<&str>,
        part: Option<&str>,
    ) -> Result<Vec<(String, String)>> {
        let owner = owner(component, part)?;
        Ok(self
            .lock()?
            .doc
            .properties(owner)?
            .clone()
            .into_iter()
            .collect())
    }

    /// Sets a custom property of a component or a part (a str, number or bool, kept
    /// as text).
    #[pyo3(signature = (key, value, component = None, part = None))]
    fn set_property(
        &self,
        key: &str,
        value: &Bound<'_, PyAny>,
        component: Option<&str>,
        part: Option<&str>,
    ) -> Result<()> {
        let owner = owner(component, part)?;
        let text = if let Ok(s) = value.extract::<String>() {
            s
        } else if let Ok(b) = value.extract::<bool>() {
            b.to_string()
        } else if let Ok(i) = value.extract::<i64>() {
            i.to_string()
        } else if let Ok(f) = value.extract::<f64>() {
            f.to_string()
        } else {
            return Err(Error::Argument(Argument::PropertyValue {
                key: key.to_string(),
            }));
        };
        self.lock()?.doc.set_property(owner, key, &text)?;
        Ok(())
    }

    /// Deletes a custom property; returns its value (None when there was none).
    #[pyo3(signature = (key, component = None, part = None))]
    fn remove_property(
        &self,
        key: &str,
        component: Option<&str>,
        part: Option<&str>,
    ) -> Result<Option<String>> {
        let owner = owner(component, part)?;
        Ok(self.lock()?.doc.remove_property(owner, key)?)
    }

    /// A part's geometry file (its mesh or STEP file).
    fn part_file(&self, part: &str) -> Result<std::path::PathBuf> {
        Ok(self.lock()?.doc.part(part)?.mesh_path.clone())
    }

    /// Adds a part whose geometry is ``file`` (relative to the document's folder,
    /// inside its project): a mesh (STL, OBJ, PLY, glTF), or a STEP file
    /// (``.step``/``.stp``), which becomes a ``step:`` part tessellated with the
    /// default deflection (the module is built without STEP import, so a STEP file is
    /// refused with the command that adds it to ``fitup``); returns its name.
    fn add_part(&self, name: &str, file: &str) -> Result<String> {
        Ok(self.lock()?.doc.add_part_file(name, file)?)
    }

    /// Adds a component of ``part`` at ``pose`` (4×4, mm; identity when None), named
    /// ``name`` or ``part-N`` with the first free N; returns its name.
    #[pyo3(signature = (part, pose = None, name = None))]
    fn add_component(
        &self,
        part: &str,
        pose: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
        name: Option<&str>,
    ) -> Result<String> {
        let t = match pose {
            Some(p) => convert::pose_of(p.as_array(), "pose")?,
            None => fitup::math::Transform::IDENTITY,
        };
        let mut inner = self.lock()?;
        let name = name.map_or_else(|| inner.doc.next_instance_name(part), str::to_string);
        let i = inner.doc.add_component(&name, part, t)?;
        Ok(inner.doc.components()[i].name.clone())
    }

    /// Adds the robot of the URDF file ``urdf`` (relative to the document's folder,
    /// inside its project) under ``name``, its root at ``base`` (4×4, mm; identity
    /// when None): its links' meshes become components ``<name>:<link>``.
    /// ``package_path``: folders (relative to the document's folder) where
    /// ``package://NAME/…`` meshes of other packages are found (an arm and a gripper
    /// from two packages), saved as the entry's ``package_path:``. Returns the
    /// robot's name.
    #[pyo3(signature = (name, urdf, base = None, package_path = None))]
    fn add_urdf_robot(
        &self,
        name: &str,
        urdf: &str,
        base: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
        package_path: Option<Vec<String>>,
    ) -> Result<String> {
        let base = base
            .map(|b| convert::pose_of(b.as_array(), "base"))
            .transpose()?;
        let mut inner = self.lock()?;
        let dir = inner
            .doc
            .path()
            .parent()
            .unwrap_or(std::path::Path::new("."))
            .to_path_buf();
        let packages: Vec<std::path::PathBuf> = package_path
            .unwrap_or_default()
            .iter()
            .map(|p| dir.join(p))
            .collect();
        let packages: Vec<&std::path::Path> = packages.iter().map(|p| p.as_path()).collect();
        let i = inner
            .doc
            .add_urdf_robot(name, &dir.join(urdf), base, &packages)?;
        Ok(inner.doc.robots()[i].name().to_string())
    }

    /// Renames a component; mates and robots follow.
    fn rename_component(&self, old: &str, new: &str) -> Result<()> {
        self.lock()?.doc.rename_component(old, new)?;
        Ok(())
    }

    /// Makes component ``name`` an instance of ``part`` (its mates' references must
    /// exist in it) and re-solves.
    fn replace_part(&self, name: &str, part: &str) -> Result<()> {
        self.lock()?.doc.set_component_part(name, part)?;
        Ok(())
    }

    /// Adds or replaces a reference of a part in the part frame (mm): ``kind``
    /// ``"plane"`` (``direction`` is the normal), ``"axis"``, ``"point"`` or
    /// ``"coordinate_system"`` (its ``pose``, 4×4 column-vector, system → part; or
    /// ``point`` as its origin with axes ``x`` and ``y``, Z = X × Y).
    #[pyo3(signature = (part, name, kind, point = None, direction = None, x = None, y = None, pose = None))]
    #[allow(clippy::too_many_arguments)]
    fn set_reference(
        &self,
        part: &str,
        name: &str,
        kind: &str,
        point: Option<[f64; 3]>,
        direction: Option<[f64; 3]>,
        x: Option<[f64; 3]>,
        y: Option<[f64; 3]>,
        pose: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
    ) -> Result<()> {
        use fitup::document::Reference;
        use fitup::math::{Point3, Vec3};
        let v = |a: [f64; 3]| Vec3::new(a[0], a[1], a[2]);
        let need = |a: Option<[f64; 3]>, k: &'static str| {
            a.map(v).ok_or_else(|| {
                Error::Argument(Argument::Needs {
                    kind: kind.to_string(),
                    argument: k,
                })
            })
        };
        let r = match kind {
            "coordinate_system" => match pose {
                Some(p) => Reference::CoordinateSystem(convert::pose_of(p.as_array(), "pose")?),
                None => Reference::CoordinateSystem(
                    fitup::document::coordinate_system(
                        need(point, "point` (or `pose")?,
                        need(x, "x")?,
                        need(y, "y")?,
                    )
                    .map_err(|source| Error::CoordinateSystem {
                        argument: "x, y",
                        source,
                    })?,
                ),
            },
            "plane" => Reference::Plane {
                point: Point3::from(need(point, "point")?),
                normal: need(direction, "direction")?,
            },
            "axis" => Reference::Axis {
                point: Point3::from(need(point, "point")?),
                direction: need(direction, "direction")?,
            },
            "point" => Reference::Point(Point3::from(need(point, "point")?)),
            other => return Err(Error::Argument(Argument::ReferenceKind(other.to_string()))),
        };
        self.lock()?.doc.set_reference(part, name, r)?;
        Ok(())
    }

    /// The meshes of ``components`` (names; default: every component neither
    /// suppressed nor hidden) at their poses, in the coordinate system ``frame`` (its
    /// 4×4 pose in the world; default the world): ``(vertices (N, 3) mm, triangles
    /// (M, 3))``, what ``export_stl`` writes.
    #[pyo3(signature = (components = None, frame = None))]
    fn world_mesh<'py>(
        &self,
        py: Python<'py>,
        components: Option<Vec<String>>,
        frame: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
    ) -> Result<MeshArrays<'py>> {
        let frame = frame
            .map(|f| convert::pose_of(f.as_array(), "frame"))
            .transpose()?;
        let inner = self.lock()?;
        let which = shown(&inner.doc, components)?;
        let mesh = fitup::workspace::world_mesh(&inner.doc, &which, frame.as_ref())?;
        let v = convert::rows(py, mesh.vertices.iter().map(|p| [p.x, p.y, p.z]), 3);
        let t = convert::rows(py, mesh.triangles.iter().map(|t| t.map(f64::from)), 3);
        Ok((v, t))
    }

    /// Writes ``world_mesh(components, frame)`` as binary STL (mm) to ``path``: never
    /// over a file the document was built from (its YAML, sub-documents, meshes, STEP
    /// files, URDFs), not even with ``overwrite`` (``DocumentError``: "a source of the
    /// open document"); over another existing file only when fitup wrote it or with
    /// ``overwrite``.
    #[pyo3(signature = (path, components = None, frame = None, overwrite = false))]
    fn export_stl(
        &self,
        py: Python<'_>,
        path: std::path::PathBuf,
        components: Option<Vec<String>>,
        frame: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
        overwrite: bool,
    ) -> Result<usize> {
        let frame = frame
            .map(|f| convert::pose_of(f.as_array(), "frame"))
            .transpose()?;
        py.detach(|| {
            let inner = self.lock()?;
            let which = shown(&inner.doc, components)?;
            Ok(fitup::workspace::export_stl(
                &inner.doc,
                &path,
                &which,
                frame.as_ref(),
                overwrite,
            )?)
        })
    }

    /// Writes the document as binary glTF (one node per component neither
    /// suppressed nor hidden, at its pose; metres, +Y up) to ``path``; returns the
    /// nodes written. With ``components`` (names; default every one neither
    /// suppressed nor hidden) or ``frame`` (its 4×4 pose in the world, mm), each
    /// component's mesh is written with its pose baked in, in the coordinates of
    /// ``frame`` (default the world): one node per component, no node matrix, what
    /// ``world_mesh([name], frame)`` gives; a suppressed one is refused. The write
    /// rule is ``export_stl``'s: never over a file the document was built from, not
    /// even with ``overwrite``.
    #[pyo3(signature = (path, overwrite = false, *, components = None, frame = None))]
    fn export_glb(
        &self,
        py: Python<'_>,
        path: std::path::PathBuf,
        overwrite: bool,
        components: Option<Vec<String>>,
        frame: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
    ) -> Result<usize> {
        let frame = frame
            .map(|f| convert::pose_of(f.as_array(), "frame"))
            .transpose()?;
        let baked = components.is_some() || frame.is_some();
        py.detach(|| {
            let inner = self.lock()?;
            if !baked {
                return Ok(inner.doc.export_glb(&path, overwrite)?.nodes);
            }
            let which = shown(&inner.doc, components)?;
            Ok(
                fitup::workspace::export_glb(&inner.doc, &path, &which, frame.as_ref(), overwrite)?
                    .nodes,
            )
        })
    }

    /// Marks a component fixed (never moved by mates or planners) or free.
    fn set_fixed(&self, name: &str, fixed: bool) -> Result<()> {
        self.lock()?.doc.set_fixed(name, fixed)?;
        Ok(())
    }

    /// Full names of the driving dimensions (``D1@<mate>`` and robot joints).
    fn dimensions(&self) -> Result<Vec<String>> {
        Ok(self.lock()?.doc.dimensions())
    }

    /// A dimension's value in SolidWorks' ``SystemValue`` units: metres for lengths,
    /// radians for angles.
    fn system_value(&self, name: &str) -> Result<f64> {
        Ok(self.lock()?.doc.dimension(name)?.system_value())
    }

    /// Sets a dimension in SI units (metres or radians), as ``IDimension.SystemValue``,
    /// and re-solves the mates; on failure nothing changes.
    fn set_system_value(&self, name: &str, value: f64) -> Result<()> {
        let mut inner = self.lock()?;
        let kind = inner.doc.dimension(name)?.kind;
        inner
            .doc
            .set_dimension(name, Dimension::from_system(kind, value))?;
        Ok(())
    }

    /// A dimension as a dict: ``name``, ``kind`` (``"length"``/``"angle"``), ``value``
    /// (mm or rad), ``system_value`` (m or rad), ``document_value`` (mm or degrees,
    /// as the file holds it).
    fn dimension<'py>(&self, py: Python<'py>, name: &str) -> Result<Bound<'py, PyDict>> {
        let d = self.lock()?.doc.dimension(name)?;
        let out = PyDict::new(py);
        let kind = match d.kind {
            DimensionKind::Length => "length",
            DimensionKind::Angle => "angle",
            #[allow(unreachable_patterns)]
            _ => "other",
        };
        out.set_item("name", &d.name)?;
        out.set_item("kind", kind)?;
        out.set_item("value", d.value)?;
        out.set_item("system_value", d.system_value())?;
        out.set_item("document_value", d.document_value())?;
        Ok(out)
    }

    /// Writes the document back to its file atomically (refused when the file changed
    /// on disk since it was loaded).
    fn save(&self, py: Python<'_>) -> Result<()> {
        py.detach(|| Ok(self.lock()?.doc.save()?))
    }

    /// Writes the document to ``path`` atomically and makes it the document's file.
    /// Refuses a file the document was read from (its meshes, sub-documents, STEP
    /// files, URDFs) and any existing file that is not a fitup document; over its own
    /// file it is ``save``.
    fn save_as(&self, py: Python<'_>, path: std::path::PathBuf) -> Result<()> {
        py.detach(|| Ok(self.lock()?.doc.save_as(&path)?))
    }

    /// The document as YAML text (what ``save`` writes).
    fn to_yaml(&self) -> Result<String> {
        Ok(self.lock()?.doc.to_yaml())
    }

    /// Every pair that touches or interferes: a list of dicts ``a``, ``b``, ``state``
    /// (``"touching"``/``"interfering"``), ``depth_mm``.
    ///
    /// Keywords (the interference table of docs/api.md): ``method`` (``"exact"``,
    /// ``"aabb"`` or ``"cells"``), ``tolerance`` (mm: crossings up to this depth are
    /// touching).
    #[pyo3(signature = (**options))]
    fn contacts<'py>(
        &self,
        py: Python<'py>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> Result<Vec<Bound<'py, PyDict>>> {
        let o = options::read::<Check>(py, options)?.0.check_options();
        let pairs = self.with_workspace(py, |ws| {
            Ok(ws
                .contacts(&o)?
                .into_iter()
                .map(|p| {
                    (
                        ws.name(p.a).to_string(),
                        ws.name(p.b).to_string(),
                        ws.with_separation_depth(p.a, p.b, p.contact),
                    )
                })
                .collect::<Vec<_>>())
        })?;
        pairs
            .into_iter()
            .map(|(a, b, c)| {
                let d = contact_dict(py, &c)?;
                d.set_item("a", a)?;
                d.set_item("b", b)?;
                Ok(d)
            })
            .collect::<PyResult<_>>()
            .map_err(Error::from)
    }

    /// Every interfering pair (as ``contacts``, interfering only; the same
    /// keywords).
    #[pyo3(signature = (**options))]
    fn interferences<'py>(
        &self,
        py: Python<'py>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> Result<Vec<Bound<'py, PyDict>>> {
        Ok(self
            .contacts(py, options)?
            .into_iter()
            .filter(|d| {
                d.get_item("state")
                    .ok()
                    .flatten()
                    .and_then(|s| s.extract::<String>().ok())
                    .is_some_and(|s| s == "interfering")
            })
            .collect())
    }

    /// The verdict for components ``a`` and ``b``: a dict ``state``
    /// (``"separate"``, ``"touching"``, ``"interfering"``) and ``depth_mm``;
    /// keywords as ``contacts``.
    #[pyo3(signature = (a, b, **options))]
    fn contact<'py>(
        &self,
        py: Python<'py>,
        a: &str,
        b: &str,
        options: Option<&Bound<'py, PyDict>>,
    ) -> Result<Bound<'py, PyDict>> {
        let o = options::read::<Check>(py, options)?.0.check_options();
        let c = self.with_workspace(py, |ws| {
            let c = ws.contact(a, b, &o)?;
            Ok(ws.with_separation_depth(ws.index(a)?, ws.index(b)?, c))
        })?;
        Ok(contact_dict(py, &c)?)
    }

    /// How much interfering components ``a`` and ``b`` overlap: a dict ``volume_mm3``
    /// (the intersection volume, SolidWorks' interference volume), ``depth_mm`` (the
    /// shortest translation of ``a`` that clears ``b``) and ``direction`` (unit
    /// vector, world). Exact for closed meshes; zeros when they only touch.
    #[pyo3(signature = (a, b, time_limit_ms = None))]
    fn overlap<'py>(
        &self,
        py: Python<'py>,
        a: &str,
        b: &str,
        time_limit_ms: Option<f64>,
    ) -> Result<Bound<'py, PyDict>> {
        let mut o = fitup::workspace::OverlapOptions::default();
        if let Some(t) = time_limit_ms {
            o.time_limit_ms = t;
        }
        let v = self.with_workspace(py, |ws| Ok(ws.overlap(a, b, &o)?))?;
        let d = PyDict::new(py);
        d.set_item("volume_mm3", v.volume)?;
        d.set_item("depth_mm", v.depth)?;
        d.set_item(
            "direction",
            v.direction.iter().copied().collect::<Vec<f64>>(),
        )?;
        Ok(d)
    }

    /// Mass properties of ``components`` (names; every component not suppressed when
    /// None) together, in world
    /// coordinates, or in the coordinate system ``frame`` (a 4×4 pose, mm) when given:
    /// a dict ``volume_mm3``, ``area_mm2``, ``mass_kg``, ``density_kg_m3``,
    /// ``centre_of_mass`` (mm), ``inertia`` (3×3 tensor about the centre of mass,
    /// kg·mm², physics sign as trimesh), ``principal_moments``, ``principal_axes``
    /// (rows). A component's ``mass`` (kg) in the document wins over ``density``
    /// (kg/m³, default 1000).
    #[pyo3(signature = (components = None, density = None, frame = None))]
    fn mass_properties<'py>(
        &self,
        py: Python<'py>,
        components: Option<Vec<String>>,
        density: Option<f64>,
        frame: Option<PyArrayLike2<'_, f64, AllowTypeChange>>,
    ) -> Result<Bound<'py, PyDict>> {
        let mut o = fitup::workspace::MassOptions::default();
        if let Some(d) = density {
            o.density = d;
        }
        let frame = frame
            .map(|f| convert::pose_of(f.as_array(), "frame"))
            .transpose()?;
        let m = {
            let inner = self.lock()?;
            let which: Vec<usize> = match &components {
                Some(names) => names
                    .iter()
                    .map(|n| inner.doc.component_index(n))
                    .collect::<std::result::Result<_, _>>()?,
                None => (0..inner.doc.components().len())
                    .filter(|&i| !inner.doc.components()[i].is_suppressed())
                    .collect(),
            };
            fitup::workspace::mass_properties(&inner.doc, &which, &o)?
        };
        let m = match frame {
            Some(f) => m.in_frame(&f),
            None => m,
        };
        let (moments, axes) = m.principal();
        let d = PyDict::new(py);
        d.set_item("volume_mm3", m.volume)?;
        d.set_item("area_mm2", m.area)?;
        d.set_item("mass_kg", m.mass)?;
        d.set_item("density_kg_m3", m.density())?;
        d.set_item(
            "centre_of_mass",
            m.centre_of_mass
                .coords
                .iter()
                .copied()
                .collect::<Vec<f64>>(),
        )?;
        d.set_item(
            "inertia",
            (0..3)
                .map(|i| (0..3).map(|j| m.inertia[(i, j)]).collect::<Vec<f64>>())
                .collect::<Vec<_>>(),
        )?;
        d.set_item("principal_moments", moments.to_vec())?;
        d.set_item(
            "principal_axes",
            axes.iter()
                .map(|a| a.iter().copied().collect::<Vec<f64>>())
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// Whether components ``a`` and ``b`` interfere (crossing deeper than
    /// ``tolerance`` mm, or one solid inside the other); keywords as ``contacts``.
    #[pyo3(signature = (a, b, **options))]
    fn interferes(
        &self,
        py: Python<'_>,
        a: &str,
        b: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> Result<bool> {
        let o = options::read::<Check>(py, options)?.0.check_options();
        self.with_workspace(py, |ws| Ok(ws.interferes(a, b, &o)?))
    }

    /// The distance between the surfaces of ``a`` and ``b`` (mm): 0 when they touch,
    /// cross or one lies inside the other; ``stop_mm`` (default 1000) when nothing is
    /// nearer.
    #[pyo3(signature = (a, b, stop_mm = None))]
    fn clearance(&self, py: Python<'_>, a: &str, b: &str, stop_mm: Option<f64>) -> Result<f64> {
        let stop_mm = stop_mm.unwrap_or(fitup::workspace::DEFAULT_CLEARANCE_SEARCH_MM);
        self.with_workspace(py, |ws| Ok(ws.clearance(a, b, stop_mm)?))
    }

    /// Sweeps component ``name`` from its pose through ``waypoints`` (``(N, 4, 4)``,
    /// world, mm; translation lerp + rotation slerp between them) and returns the first
    /// contact: a dict ``hit``, ``t`` (0..1 along the motion), ``pose`` (4×4),
    /// ``with`` (the component hit, or None).
    ///
    /// Keywords (the sweep table of docs/api.md): ``method`` (``"continuous"``
    /// default: no obstacle is jumped over; ``"step"``), ``step`` (mm),
    /// ``tolerance`` (mm), ``time_limit_ms``.
    #[pyo3(signature = (name, waypoints, **options))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        name: &str,
        waypoints: PyArrayLike3<'py, f64, AllowTypeChange>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> Result<Bound<'py, PyDict>> {
        let poses = convert::poses_of(waypoints.as_array(), "waypoints")?;
        let o = options::read::<Sweep>(py, options)?.0.sweep_options();
        let (hit, with) = self.with_workspace(py, |ws| {
            let hit = ws.sweep_through(name, &poses, &o)?;
            let with = hit.with.map(|i| ws.name(i).to_string());
            Ok((hit, with))
        })?;
        let d = PyDict::new(py);
        d.set_item("hit", hit.hit)?;
        d.set_item("t", hit.t)?;
        d.set_item("pose", convert::pose_array(py, &hit.pose))?;
        d.set_item("with", with)?;
        Ok(d)
    }

    /// Plans a collision-free path for component ``name`` from its pose (or
    /// ``start``) to ``goal`` (4×4, world, mm) among all the other components.
    ///
    /// Keywords: the planning table of docs/api.md, the keys of a script's options
    /// map: ``planner`` (``"rrt_connect"`` default; see ``planner_names()``),
    /// ``seed`` (same seed, same path), ``time_limit_ms`` (budget of the whole
    /// call), ``max_iterations``, ``step`` (mm), ``goal_bias``, ``smoothing``,
    /// ``narrow`` (bool or dict), ``fallback_share``, ``L``, ``dis``, ``radius``,
    /// ``tolerance`` (mm), ``edge`` (``"continuous"``/``"step"``), ``contact_step``,
    /// ``edge_step`` (mm), ``edge_step_deg`` (degrees), ``bounds``
    /// (``[[min xyz], [max xyz]]`` mm, for the part origin), ``margin`` (mm),
    /// ``rotation`` (bool), ``rotation_weight`` (mm per rad), ``disassemble``,
    /// ``start`` (4×4).
    /// A path that is not found is returned with ``found == False`` and a ``reason``.
    #[pyo3(signature = (name, goal, **options))]
    fn plan_path(
        &self,
        py: Python<'_>,
        name: &str,
        goal: PyArrayLike2<'_, f64, AllowTypeChange>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> Result<Path> {
        let goal = convert::pose_of(goal.as_array(), "goal")?;
        self.plan(py, name, Some(goal), options, "rrt_connect", false)
    }

    /// Seed 002's insertion: plans the disassembly from whichever end (start or
    /// ``goal``) lies inside the box of the other components until the part leaves
    /// it, and joins the other end with RRT-Connect; the way into tight clearances.
    /// ``goal``: the seated pose (4×4, world, mm). Keywords as ``plan_path``.
    #[pyo3(signature = (name, goal, **options))]
    fn plan_insertion(
        &self,
        py: Python<'_>,
        name: &str,
        goal: PyArrayLike2<'_, f64, AllowTypeChange>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> Result<Path> {
        let goal = convert::pose_of(goal.as_array(), "goal")?;
        self.plan(py, name, Some(goal), options, "rrt_connect", true)
    }

    /// Seed 002's "can be disassembled, can be assembled": plans from the component's
    /// assembled pose until its box leaves the box of the other components, then
    /// reverses the path so it ends assembled. Planner ``"local_rrt"`` by default
    /// (``"rrt"``, ``"biased_rrt"`` too); keywords as ``plan_path``.
    #[pyo3(signature = (name, **options))]
    fn plan_disassembly(
        &self,
        py: Python<'_>,
        name: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> Result<Path> {
        self.plan(py, name, None, options, "local_rrt", false)
    }

    /// Checks ``path`` again against the document as it is now, with the tolerance
    /// and edge check it was planned with: a dict ``ok``, and when blocked
    /// ``segment`` (the first blocked edge) and ``pose`` (4×4).
    fn revalidate<'py>(&self, py: Python<'py>, path: &Path) -> Result<Bound<'py, PyDict>> {
        let r = self.with_workspace(py, |ws| {
            Ok(ws.revalidate(&path.component, &path.path, &path.validator)?)
        })?;
        let d = PyDict::new(py);
        match r {
            Revalidation::Valid => d.set_item("ok", true)?,
            Revalidation::Blocked { segment, pose } => {
                d.set_item("ok", false)?;
                d.set_item("segment", segment)?;
                d.set_item("pose", convert::pose_array(py, &pose))?;
            }
            #[allow(unreachable_patterns)]
            _ => d.set_item("ok", false)?,
        }
        Ok(d)
    }

    /// Moves the path's component along ``path`` in steps of at most ``step_mm`` (and
    /// as many degrees); it ends at the path's last pose. Returns the number of steps.
    fn follow(&self, py: Python<'_>, path: &Path, step_mm: f64) -> Result<usize> {
        py.detach(|| {
            let mut inner = self.lock()?;
            Ok(fitup::workspace::follow(
                &mut inner.doc,
                &path.component,
                &path.path,
                step_mm,
                |_, _, _| Control::Continue,
            )?)
        })
    }

    /// Robot names.
    fn robots(&self) -> Result<Vec<String>> {
        Ok(self
            .lock()?
            .doc
            .robots()
            .iter()
            .map(|r| r.name().to_string())
            .collect())
    }

    /// Robot ``name`` as a ``Robot`` (its kinematics with the document's base and
    /// tool; a copy: moving it does not move the document's robot).
    fn robot(&self, name: &str) -> Result<crate::robot::Robot> {
        let inner = self.lock()?;
        let r = inner.doc.robot(name)?;
        Ok(crate::robot::Robot::from_shared(r.shared_robot()))
    }

    /// The joints of robot ``name`` (rad, mm for prismatic joints).
    fn joints<'py>(
        &self,
        py: Python<'py>,
        robot: &str,
    ) -> Result<Bound<'py, numpy::PyArray1<f64>>> {
        let inner = self.lock()?;
        Ok(convert::vector(
            py,
            inner.doc.robot(robot)?.joints().to_vec(),
        ))
    }

    /// Sets the joints of robot ``robot`` (rad, mm for prismatic joints; within the
    /// limits); its link components move. A new value for a joint an equation drives
    /// raises DocumentError naming the equation.
    fn set_joints(
        &self,
        robot: &str,
        joints: numpy::PyArrayLike1<'_, f64, AllowTypeChange>,
    ) -> Result<()> {
        let q = convert::joints_of(joints.as_array());
        let mut inner = self.lock()?;
        let i = inner.doc.robot_index(robot)?;
        inner.doc.set_robot_joints(i, &q)?;
        Ok(())
    }

    /// Runs a motion program (Line/Circle/Joint commands, ``.prg``) on robot
    /// ``robot`` from its current joints: ``file`` names a program file, or ``text``
    /// gives the program itself. The robot ends where the program ends. Returns the
    /// trajectory as a dict of arrays: ``t`` (s, ``(N,)``), ``joints`` (rad/mm,
    /// ``(N, dof)``), ``tcp`` (``(N, 4, 4)``, world, mm). Errors name file and line.
    #[pyo3(signature = (robot, file = None, text = None))]
    fn run_program<'py>(
        &self,
        py: Python<'py>,
        robot: &str,
        file: Option<std::path::PathBuf>,
        text: Option<String>,
    ) -> Result<Bound<'py, PyDict>> {
        let program = match (file, text) {
            (Some(f), None) => fitup::kinematics::read_program(&f)?,
            (None, Some(t)) => fitup::kinematics::parse_program("<python>", &t)?,
            _ => {
                return Err(Error::Option {
                    option: "file",
                    value: "file and text".into(),
                    expected: "either `file` or `text`, not both or neither",
                })
            }
        };
        let traj = py.detach(|| {
            let mut inner = self.lock()?;
            let i = inner.doc.robot_index(robot)?;
            Ok::<_, Error>(inner.doc.run_robot_program(
                i,
                &program,
                &fitup::kinematics::MotionOptions::default(),
            )?)
        })?;
        let dof = traj.joint_kinds.len();
        let t: Vec<f64> = traj.samples.iter().map(|s| s.t).collect();

        let tcp: Vec<fitup::math::Transform> = traj.samples.iter().map(|s| s.tcp).collect();
        let d = PyDict::new(py);
        d.set_item("t", convert::vector(py, t))?;
        d.set_item(
            "joints",
            convert::rows(py, traj.samples.iter().map(|s| &s.joints), dof),
        )?;
        d.set_item("tcp", convert::poses_array(py, &tcp))?;
        Ok(d)
    }

    /// Plans the assembly sequences (seed 003's task layer) and returns the plan as a
    /// dict (the JSON of ``fitup plan-sequence --json``): ``sequences`` best first,
    /// each with ``order``, ``mounts``, ``tasks`` (mating directions, safe lengths,
    /// grasps, mm), and ``rejected``, ``precedence``, ``time_ms``.
    ///
    /// Keywords: the sequence table of docs/api.md, the keys of a script's
    /// ``assembly_sequence`` map: ``mode`` (``"mates"``/``"geometry"``), ``base``,
    /// ``order``, ``max_sequences``, ``time_limit_ms`` (the whole call), ``seed``,
    /// ``tolerance`` (mm), ``slide_fit_mm`` (mm), ``components``, ``exclude``,
    /// ``threaded``, ``masses``,
    /// ``support``, ``contact_gap_mm``, ``gravity`` (a down vector),
    /// ``tight_clearance_mm``, ``planner_fallback``, ``fallback_time_limit_ms``,
    /// ``max_tilt_deg`` (degrees; ``max_tilt`` in radians is deprecated),
    /// ``sphere_directions``, ``probe_mm``, ``step_mm``, ``small_base_ratio``.
    /// Interferences of the assembled pose come back as ``fits`` (each allowed its
    /// depth in the removal checks), parts held across a clearance as
    /// ``support_gaps``, groups of parts nothing modelled holds together as
    /// ``separate_groups``.
    #[pyo3(signature = (**options))]
    fn plan_sequence<'py>(
        &self,
        py: Python<'py>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> Result<Bound<'py, PyAny>> {
        let o = options::read::<Sequence>(py, options)?.0.sequence_options();
        let json = py.detach(|| {
            let mut inner = self.lock()?;
            let Inner { doc, scene } = &mut *inner;
            Ok::<_, Error>(fitup::sequence::plan_sequence(doc, scene, &o)?.to_json())
        })?;
        Ok(py.import("json")?.call_method1("loads", (json,))?)
    }

    fn __repr__(&self) -> String {
        match self.lock() {
            Ok(i) => format!(
                "Document({:?}: {} components, {} robots)",
                i.doc.path().display().to_string(),
                i.doc.components().len(),
                i.doc.robots().len()
            ),
            Err(_) => "Document(<poisoned>)".into(),
        }
    }
}

impl Document {
    fn plan(
        &self,
        py: Python<'_>,
        name: &str,
        goal: Option<fitup::math::Transform>,
        options: Option<&Bound<'_, PyDict>>,
        default_planner: &str,
        disassemble: bool,
    ) -> Result<Path> {
        let (o, json) = options::read::<Plan>(py, options)?;
        let seed = o.seed;
        let mut request = o
            .request(default_planner)
            .map_err(|e| Error::Workspace(fitup::workspace::WorkspaceError::Plan(e)))?;
        request.disassemble |= disassemble;
        let path = self.with_workspace(py, |ws| {
            Ok(match &goal {
                Some(g) => ws.plan_path(name, g, &request, None)?,
                None => ws.plan_disassembly(name, &request, None)?,
            })
        })?;
        Ok(Path {
            path,
            validator: request.validator,
            component: fitup::document::nfc_name(name).into_owned(),
            seed,
            options: json,
        })
    }
}
