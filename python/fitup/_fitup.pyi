"""Type stubs of the native module ``fitup._fitup`` (re-exported by ``fitup``).

Units: mm and radians. Poses: ``(4, 4)`` float arrays, column-vector convention
(``p_world = T @ [x, y, z, 1]``), part frame → world. Joint arrays: radians (mm
for prismatic joints).
"""

from os import PathLike
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Pose = npt.ArrayLike  # (4, 4)
_Poses = npt.ArrayLike  # (N, 4, 4)
_Joints = npt.ArrayLike  # (dof,)
_F64 = npt.NDArray[np.float64]
_StrPath = Union[str, "PathLike[str]"]

__version__: str

def catalog_names() -> List[str]:
    """Names of the built-in catalog robots."""
def planner_names() -> List[str]:
    """The planner names ``plan_path`` accepts."""
def option_keys(request: str) -> List[Dict[str, Any]]:
    """The keys of a request's options — the table every keyword argument of it is
    checked against, and that ``docs/api.md`` prints: a list of dicts ``key``,
    ``kind`` (``"number"``, ``"count"``, ``"bool"``, ``"text"``, ``"choice"``,
    ``"names"``, ``"vector"``, ``"box"``, ``"pose"``, ``"number_map"``,
    ``"switch"``), ``choices`` (the names of a choice, else None), ``unit`` and
    ``meaning``. ``request``: ``"planning"``, ``"narrow"``, ``"interference"``,
    ``"sweep"``, ``"sequence"``, ``"motion"`` or ``"drilling"``.
    """
def run_script(
    script: _StrPath,
    doc: Optional[_StrPath] = None,
    args: Optional[Mapping[str, Any]] = None,
    root: Optional[_StrPath] = None,
    db: Optional[str] = None,
    max_operations: Optional[int] = None,
    max_seconds: Optional[int] = None,
) -> Dict[str, Any]:
    """Runs the Rhai script ``script`` to completion, as ``fitup run`` does: sandboxed,
    file access bounded by its project (``root``, else the nearest folder holding
    ``fitup.toml``, else the script's folder).

    ``doc``: a document the script sees as ``doc``; ``args``: a dict the script sees
    as the map ``args`` (values typed like ``fitup run SCRIPT -- key=value``: ints,
    floats, ``true``/``false``, else text); ``db``: record the run in this results
    database (a file or ``postgres://`` URL; the script's ``open_db()`` of the same
    database files its results under the run); ``max_operations``: the operation
    limit (0 = none); ``max_seconds``: the wall-time limit of the run, seconds (default
    3600, as ``fitup run --max-seconds``; 0 = none): a script still running then stops
    with a ``ScriptError`` naming the limit, at the line it had reached.

    Returns a dict ``output`` (the printed lines), ``files_read``, ``files_written``,
    ``elapsed_s``, ``operations``. A failing script raises ``ScriptError`` with the
    script's ``file``, ``line`` and ``column`` and the ``output`` printed before it.
    The GIL is released while the script runs.
    """

class Path:
    """A planned path for one component (``Document.plan_path``, ``plan_insertion``,
    ``plan_disassembly``).

    ``poses`` are the key poses, start first and goal last, as an ``(N, 4, 4)`` array
    of column-vector pose matrices (part frame → world, mm); consecutive poses are
    joined by straight edges (translation lerp + rotation slerp) that the validator
    accepted. Empty (``N = 0``) when no path was found: ``reason`` says why.
    """

    @property
    def found(self) -> bool:
        """Whether a path was found."""
    @property
    def reason(self) -> Optional[str]:
        """Why no path was found (time limit, start in collision, …); None when found."""
    @property
    def poses(self) -> _F64:
        """Key poses, ``(N, 4, 4)``, column-vector matrices, mm, world frame."""
    @property
    def positions(self) -> _F64:
        """Key-pose positions, ``(N, 3)``, mm, world frame."""
    @property
    def component(self) -> str:
        """The component the path moves."""
    @property
    def planner(self) -> str:
        """The planner that made it (e.g. ``"rrt_connect"``,
        ``"lazy_disassemble_local_rrt+lazy_rrt_connect"``).
        """
    @property
    def seed(self) -> int:
        """The seed it was planned with (same seed, same path, when the iteration limit
        and not the time limit ends the search).
        """
    @property
    def length_mm(self) -> float:
        """Translation length after smoothing, mm."""
    @property
    def rotation_rad(self) -> float:
        """Total rotation along the path, radians."""
    @property
    def iterations(self) -> int:
        """Planner iterations."""
    @property
    def checks(self) -> int:
        """Collision checks made (poses + edges)."""
    @property
    def time_ms(self) -> float:
        """Wall time of the whole call (search and smoothing), ms."""
    @property
    def resolution(self) -> str:
        """How edges were checked (``continuous`` or the stepwise resolution)."""
    def densify(self, step_mm: float) -> _F64:
        """Poses along the path at most ``step_mm`` mm (and as many degrees) apart,
        ``(M, 4, 4)``; key poses are kept. More than 1,000,000 poses is an
        ``InputError`` naming ``step_mm``, raised before anything is allocated.
        """
    def to_dict(self) -> Dict[str, Any]:
        """The path as a plain dict (picklable, for tables and batches): ``found``,
        ``reason``, ``planner``, ``component``, ``seed``, ``length_mm``,
        ``rotation_rad``, ``iterations``, ``checks``, ``time_ms``, ``key_poses`` and
        ``poses`` (the ``(N, 4, 4)`` array).
        """
    def __len__(self) -> int: ...

class Robot:
    """A serial robot: kinematic tree, base (world → robot root), tool (flange → TCP),
    joint limits and its inverse-kinematics solver (closed form for OPW and UR arms,
    numeric otherwise).

    Joint arrays are radians (mm for prismatic joints), in joint order; poses are
    column-vector 4×4 arrays, world frame, mm. Batch forms take ``(N, dof)`` joints or
    ``(N, 4, 4)`` poses and release the GIL.
    """

    @staticmethod
    def catalog(name: str) -> "Robot":
        """A robot of the built-in catalog (``catalog_names()``: ``"nachi_mz07"``, ``"ur5"``,
        ``"kuka_kr6_r700"``, …), base at the origin, tool at the flange.
        """
    @property
    def name(self) -> str:
        """The robot's name."""
    @property
    def dof(self) -> int:
        """Number of joints."""
    @property
    def solver(self) -> str:
        """The IK solver: ``"opw"``, ``"ur"`` (closed form, every branch) or ``"numeric"``."""
    @property
    def limits(self) -> _F64:
        """Joint limits as an ``(dof, 2)`` array ``[min, max]`` (rad/mm; ±inf when a
        joint has none).
        """
    @property
    def base(self) -> _F64:
        """The base pose (world → robot root), 4×4, mm."""
    @property
    def tool(self) -> _F64:
        """The tool (flange → TCP), 4×4, mm."""
    def with_base(self, base: _Pose) -> "Robot":
        """A copy with another base pose (world → robot root, 4×4, mm)."""
    def with_tool(self, tool: _Pose) -> "Robot":
        """A copy with another tool (flange → TCP, 4×4, mm)."""
    def fk(self, q: _Joints) -> _F64:
        """Forward kinematics: the TCP pose (4×4, world, mm) for joints ``q`` (rad/mm)."""
    def fk_batch(self, q: npt.ArrayLike) -> _F64:
        """Forward kinematics of many configurations: ``q`` is ``(N, dof)`` (rad/mm,
        read in place when C-ordered); returns the TCP poses ``(N, 4, 4)`` (world, mm).
        GIL released.
        """
    def link_poses(self, q: _Joints) -> _F64:
        """World poses of every link of the kinematic tree for joints ``q``:
        ``(links, 4, 4)``.
        """
    def ik(self, target: _Pose, reference: Optional[_Joints] = None) -> _F64:
        """Inverse kinematics, every branch: the joint solutions ``(K, dof)`` (rad/mm)
        that put the TCP at ``target`` (4×4, world, mm) within the joint limits,
        sorted by distance to ``reference`` (default all zeros). ``K = 0`` when the
        target is unreachable.
        """
    def ik_batch(self, targets: _Poses, reference: Optional[_Joints] = None) -> List[_F64]:
        """Every branch for many targets (``(N, 4, 4)``, world, mm): a list of
        ``(K_i, dof)`` arrays (rad/mm), each as ``ik`` gives it; GIL released. A
        C-ordered array is read in place.
        """
    def ik_path(self, targets: _Poses, start: Optional[_Joints] = None) -> _F64:
        """IK along a path of poses (``(N, 4, 4)``, world, mm): for each, the solution
        nearest to the previous one (the first nearest to ``start``), ``(N, dof)``
        (rad/mm); a row of NaN where a pose has no solution (the next is solved near
        the last one found). GIL released.
        """
    def limit_violation(self, q: _Joints) -> Optional[int]:
        """The joint index (0-based) of the first joint of ``q`` outside its limits, or
        None.
        """
    def zeros(self) -> _F64:
        """Joints as an array helper: zeros of the robot's width."""

class Document:
    """An assembly document (YAML + meshes): parts, components at poses, mates,
    dimensions, robots.

    ``Document(path)`` loads and validates the file and its meshes and solves the mates;
    errors are ``DocumentError`` with ``file``, ``line`` and ``column``. Poses are
    column-vector 4×4 numpy arrays (part frame → world, mm); lengths mm, angles
    radians. Long calls (planning, sequences, sweeps, interference) release the GIL;
    calls on one document from several threads run one at a time.
    """

    def __init__(self, path: _StrPath) -> None: ...
    @property
    def path(self) -> Any:
        """The document's file."""
    def components(self) -> List[str]:
        """Component names in file order."""
    def parts(self) -> List[str]:
        """Part names in file order."""
    def component(self, name: str) -> Dict[str, Any]:
        """One component as a dict: ``name``, ``part``, ``fixed``, ``pose`` (4×4, mm),
        ``mass`` (kg or None), ``threaded``, ``color`` (RGB in 0..1 or None),
        ``suppressed``, ``hidden``, ``properties`` (its own custom properties as
        ``(name, text)`` pairs in document order), ``part_file`` (its part's file).
        """
    def pose(self, name: str) -> _F64:
        """The pose of component ``name``: 4×4 column-vector matrix, part frame → world, mm."""
    def set_pose(self, name: str, pose: _Pose) -> None:
        """Sets the pose of component ``name`` (4×4, mm; a rigid motion). Fixed and
        robot-driven components are refused; mates are not re-solved.
        """
    def reference(self, component: str, name: str) -> Dict[str, Any]:
        """A reference (plane, axis, point or coordinate system of the component's part)
        in the world at the component's pose: a dict ``kind`` (``"plane"``, ``"axis"``,
        ``"point"``, ``"coordinate_system"``), ``point`` (mm, ``(3,)``; a coordinate
        system's origin), ``direction`` (the unit normal or axis direction, None for a
        point or a coordinate system) and ``pose`` (a coordinate system's 4×4
        column-vector pose, system → world, mm; None for the others).
        """
    def coordinate_system(self, component: str, name: str) -> _F64:
        """Coordinate system ``name`` of component ``component``'s part in the world: its
        4×4 column-vector pose (system → world, mm), SolidWorks'
        ``CoordinateSystemFeatureData.Transform`` times ``Transform2``.
        """
    def part_coordinate_system(self, part: str, name: str) -> _F64:
        """Coordinate system ``name`` of part ``part`` in the part frame: its 4×4
        column-vector pose (system → part, mm).
        """
    def world_mesh(self, components: Optional[List[str]] = None, frame: Optional[_Pose] = None) -> Tuple[_F64, _F64]:
        """The meshes of ``components`` (names; default: every component neither
        suppressed nor hidden) at their poses, in the coordinate system ``frame`` (its
        4×4 pose in the world; default the world): ``(vertices (N, 3) mm, triangles
        (M, 3))``, what ``export_stl`` writes.
        """
    def export_stl(self, path: _StrPath, components: Optional[List[str]] = None, frame: Optional[_Pose] = None, overwrite: bool = False) -> int:
        """Writes ``world_mesh(components, frame)`` as binary STL (mm) to ``path``: never
        over a file the document was built from (its YAML, sub-documents, meshes, STEP
        files, URDFs), not even with ``overwrite`` (``DocumentError``: "a source of the
        open document"); over another existing file only when fitup wrote it or with
        ``overwrite``.
        """
    def export_glb(self, path: _StrPath, overwrite: bool = False, *, components: Optional[List[str]] = None, frame: Optional[_Pose] = None) -> int:
        """Writes the document as binary glTF (one node per component neither
        suppressed nor hidden, at its pose; metres, +Y up) to ``path``; returns the
        nodes written. With ``components`` (names; default every one neither
        suppressed nor hidden) or ``frame`` (its 4×4 pose in the world, mm), each
        component's mesh is written with its pose baked in, in the coordinates of
        ``frame`` (default the world): one node per component, no node matrix, what
        ``world_mesh([name], frame)`` gives; a suppressed one is refused. The write
        rule is ``export_stl``'s: never over a file the document was built from, not
        even with ``overwrite``.
        """
    def mates(self) -> List[Dict[str, Any]]:
        """Every mate in document order as dicts: ``name``, ``type``, ``entities``
        (``component/reference`` twice), ``value`` (mm or degrees, None), ``aligned``
        (None for mates of points), ``suppressed``, ``active`` (solved: neither it nor
        a component it joins is suppressed).
        """
    def add_mate(self, name: str, type: str, a: str, b: str, **options: Any) -> None:
        """Adds a mate of ``type`` (``"coincident"``, ``"concentric"``, ``"parallel"``,
        ``"perpendicular"``, ``"distance"``, ``"angle"``) between entities ``a`` and
        ``b`` (``component/reference``) and solves it. Keywords (the mate table of
        docs/api.md): ``value`` (mm or degrees), ``aligned``, ``about``.
        """
    def delete_mate(self, name: str) -> None:
        """Deletes a mate; nothing moves."""
    def flip_mate(self, name: str) -> None:
        """Flips a mate between aligned and anti-aligned and re-solves."""
    def set_mate_aligned(self, name: str, aligned: Optional[bool]) -> None:
        """Sets a mate aligned (True), anti-aligned (False) or to its kind's default
        (None), and re-solves.
        """
    def set_mate_suppressed(self, name: str, suppressed: bool) -> None:
        """Suppresses or unsuppresses a mate and re-solves."""
    def sub_assemblies(self) -> List[str]:
        """Every sub-assembly's full name (``Cart-1``, ``Cart-1/Axle-1``), parents first."""
    def children(self, name: Optional[str] = None) -> List[str]:
        """The direct children (sub-assemblies, then components, by full name) of
        sub-assembly ``name``, or of the top level for None.
        """
    def parent(self, name: str) -> Optional[str]:
        """The parent sub-assembly of a component or sub-assembly; None at the top level."""
    def sub_assembly_pose(self, name: str) -> _F64:
        """A sub-assembly's pose in the assembly frame: 4×4 column-vector matrix, mm."""
    def set_sub_assembly_pose(self, name: str, pose: _Pose) -> None:
        """Moves a sub-assembly, and everything in it rigidly, to ``pose`` (4×4, mm,
        assembly frame). Refused when a component inside is fixed.
        """
    def add_sub_assembly(self, name: str, pose: Optional[_Pose] = None) -> None:
        """Adds an empty sub-assembly ``name`` (a full name whose parent exists) at
        ``pose`` (4×4, mm; identity when None).
        """
    def sub_assembly_file(self, name: str) -> Optional[str]:
        """The document file a sub-assembly holds (its ``file:`` key, relative to the
        document holding the entry), or None for a group of this document.
        """
    def sub_assembly_suppressed(self, name: str) -> bool:
        """Whether a sub-assembly is suppressed, itself or by a suppressed sub-assembly
        holding it.
        """
    def set_sub_assembly_suppressed(self, name: str, suppressed: bool) -> None:
        """Suppresses (or unsuppresses) a sub-assembly and everything it holds at every
        level, then re-solves; saved with the document (or its sub-document).
        """
    def saved_sub_documents(self) -> List[str]:
        """The sub-document files the last ``save`` wrote besides the document's own."""
    def remove_component(self, name: str, with_mates: bool = False) -> List[str]:
        """Removes a component. With ``with_mates=False`` a component that has mates is
        refused (the error names them); with ``True`` its mates are deleted with it
        (unless an equation uses one of their dimensions). Returns the deleted mates'
        names.
        """
    def equations(self) -> List[Dict[str, Any]]:
        """The equations in order (SolidWorks' ``IEquationMgr``), each a dict: ``text``
        (``"name" = expression``), ``name`` (the global variable or dimension it
        sets), ``expression``, ``value`` (at the last rebuild: mm, degrees, or no unit
        for a global variable) and ``global`` (True for a global variable).
        """
    def add_equation(self, text: str, index: Optional[int] = None) -> int:
        """Adds an equation (``'"Factor" = 2'``, ``'"D1@lift" = 10 * "Factor"'``) at
        ``index`` (None: at the end) and rebuilds; returns its index. Refused, with
        nothing changed, when it does not evaluate (``DocumentError`` naming the
        equation and the cause).
        """
    def set_equation(self, index: int, text: str) -> None:
        """Replaces equation ``index`` (0-based) by ``text`` and rebuilds."""
    def delete_equation(self, index: int) -> None:
        """Deletes equation ``index`` and rebuilds; what it set keeps its value."""
    def global_variable(self, name: str) -> float:
        """A global variable's value (no unit)."""
    def set_global_variable(self, name: str, value: float) -> None:
        """Sets a global variable (its equation becomes ``"name" = value``) and
        rebuilds: the dimensions it drives and the mates follow.
        """
    def set_suppressed(self, name: str, suppressed: bool) -> None:
        """Suppresses or unsuppresses a component (not checked, planned around,
        sequenced, weighed or exported; its mates inactive) and re-solves.
        """
    def set_hidden(self, name: str, hidden: bool) -> None:
        """Hides (checked, not exported) or shows a component."""
    def properties(self, component: Optional[str] = None, part: Optional[str] = None) -> List[Tuple[str, str]]:
        """The custom properties of a component or a part (give exactly one), as
        ``(name, text)`` pairs in document order.
        """
    def set_property(
        self,
        key: str,
        value: Union[str, float, int, bool],
        component: Optional[str] = None,
        part: Optional[str] = None,
    ) -> None:
        """Sets a custom property of a component or a part (a str, number or bool, kept
        as text).
        """
    def remove_property(
        self, key: str, component: Optional[str] = None, part: Optional[str] = None
    ) -> Optional[str]:
        """Deletes a custom property; returns its value (None when there was none)."""
    def part_file(self, part: str) -> Any:
        """A part's geometry file (its mesh or STEP file)."""
    def add_part(self, name: str, file: str) -> str:
        """Adds a part whose geometry is ``file`` (relative to the document's folder,
        inside its project): a mesh (STL, OBJ, PLY, glTF), or a STEP file
        (``.step``/``.stp``), which becomes a ``step:`` part tessellated with the
        default deflection (the module is built without STEP import, so a STEP file is
        refused with the command that adds it to ``fitup``); returns its name.
        """
    def add_component(self, part: str, pose: Optional[_Pose] = None, name: Optional[str] = None) -> str:
        """Adds a component of ``part`` at ``pose`` (4×4, mm; identity when None), named
        ``name`` or ``part-N`` with the first free N; returns its name.
        """
    def add_urdf_robot(self, name: str, urdf: str, base: Optional[_Pose] = None, package_path: Optional[Sequence[str]] = None) -> str:
        """Adds the robot of the URDF file ``urdf`` (relative to the document's folder,
        inside its project) under ``name``, its root at ``base`` (4×4, mm; identity
        when None): its links' meshes become components ``<name>:<link>``.
        ``package_path``: folders (relative to the document's folder) where
        ``package://NAME/…`` meshes of other packages are found (an arm and a gripper
        from two packages), saved as the entry's ``package_path:``. Returns the
        robot's name.
        """
    def rename_component(self, old: str, new: str) -> None:
        """Renames a component; mates and robots follow."""
    def replace_part(self, name: str, part: str) -> None:
        """Makes component ``name`` an instance of ``part`` (its mates' references must
        exist in it) and re-solves.
        """
    def set_reference(
        self,
        part: str,
        name: str,
        kind: str,
        point: Optional[Sequence[float]] = None,
        direction: Optional[Sequence[float]] = None,
        x: Optional[Sequence[float]] = None,
        y: Optional[Sequence[float]] = None,
        pose: Optional[_Pose] = None,
    ) -> None:
        """Adds or replaces a reference of a part in the part frame (mm): ``kind``
        ``"plane"`` (``direction`` is the normal), ``"axis"``, ``"point"`` or
        ``"coordinate_system"`` (its ``pose``, 4×4 column-vector, system → part; or
        ``point`` as its origin with axes ``x`` and ``y``, Z = X × Y).
        """
    def set_fixed(self, name: str, fixed: bool) -> None:
        """Marks a component fixed (never moved by mates or planners) or free."""
    def dimensions(self) -> List[str]:
        """Full names of the driving dimensions (``D1@<mate>`` and robot joints)."""
    def system_value(self, name: str) -> float:
        """A dimension's value in SolidWorks' ``SystemValue`` units: metres for lengths,
        radians for angles.
        """
    def set_system_value(self, name: str, value: float) -> None:
        """Sets a dimension in SI units (metres or radians), as ``IDimension.SystemValue``,
        and re-solves the mates; on failure nothing changes.
        """
    def dimension(self, name: str) -> Dict[str, Any]:
        """A dimension as a dict: ``name``, ``kind`` (``"length"``/``"angle"``), ``value``
        (mm or rad), ``system_value`` (m or rad), ``document_value`` (mm or degrees,
        as the file holds it).
        """
    def save(self) -> None:
        """Writes the document back to its file atomically (refused when the file changed
        on disk since it was loaded).
        """
    def save_as(self, path: _StrPath) -> None:
        """Writes the document to ``path`` atomically and makes it the document's file.
        Refuses a file the document was read from (its meshes, sub-documents, STEP
        files, URDFs) and any existing file that is not a fitup document; over its own
        file it is ``save``.
        """
    def to_yaml(self) -> str:
        """The document as YAML text (what ``save`` writes)."""
    def contacts(self, **options: Any) -> List[Dict[str, Any]]:
        """Every pair that touches or interferes: a list of dicts ``a``, ``b``, ``state``
        (``"touching"``/``"interfering"``), ``depth_mm``.

        Keywords (the interference table of docs/api.md): ``method`` (``"exact"``,
        ``"aabb"`` or ``"cells"``), ``tolerance`` (mm: crossings up to this depth are
        touching).
        """
    def interferences(self, **options: Any) -> List[Dict[str, Any]]:
        """Every interfering pair (as ``contacts``, interfering only; the same
        keywords).
        """
    def contact(self, a: str, b: str, **options: Any) -> Dict[str, Any]:
        """The verdict for components ``a`` and ``b``: a dict ``state``
        (``"separate"``, ``"touching"``, ``"interfering"``) and ``depth_mm``;
        keywords as ``contacts``.
        """
    def overlap(self, a: str, b: str, time_limit_ms: Optional[float] = None) -> Dict[str, Any]:
        """How much interfering components ``a`` and ``b`` overlap: a dict ``volume_mm3``
        (the intersection volume, SolidWorks' interference volume), ``depth_mm`` (the
        shortest translation of ``a`` that clears ``b``) and ``direction`` (unit
        vector, world). Exact for closed meshes; zeros when they only touch.
        """
    def mass_properties(
        self,
        components: Optional[List[str]] = None,
        density: Optional[float] = None,
        frame: Optional[_Pose] = None,
    ) -> Dict[str, Any]:
        """Mass properties of ``components`` (names; every component not suppressed when
        None) together, in world
        coordinates, or in the coordinate system ``frame`` (a 4×4 pose, mm) when given:
        a dict ``volume_mm3``, ``area_mm2``, ``mass_kg``, ``density_kg_m3``,
        ``centre_of_mass`` (mm), ``inertia`` (3×3 tensor about the centre of mass,
        kg·mm², physics sign as trimesh), ``principal_moments``, ``principal_axes``
        (rows). A component's ``mass`` (kg) in the document wins over ``density``
        (kg/m³, default 1000).
        """
    def interferes(self, a: str, b: str, **options: Any) -> bool:
        """Whether components ``a`` and ``b`` interfere (crossing deeper than
        ``tolerance`` mm, or one solid inside the other); keywords as ``contacts``.
        """
    def clearance(self, a: str, b: str, stop_mm: Optional[float] = None) -> float:
        """The distance between the surfaces of ``a`` and ``b`` (mm): 0 when they touch,
        cross or one lies inside the other; ``stop_mm`` (default 1000) when nothing is
        nearer.
        """
    def sweep(self, name: str, waypoints: _Poses, **options: Any) -> Dict[str, Any]:
        """Sweeps component ``name`` from its pose through ``waypoints`` (``(N, 4, 4)``,
        world, mm; translation lerp + rotation slerp between them) and returns the first
        contact: a dict ``hit``, ``t`` (0..1 along the motion), ``pose`` (4×4),
        ``with`` (the component hit, or None).

        Keywords (the sweep table of docs/api.md): ``method`` (``"continuous"``
        default: no obstacle is jumped over; ``"step"``), ``step`` (mm),
        ``tolerance`` (mm), ``time_limit_ms``.
        """
    def plan_path(self, name: str, goal: _Pose, **options: Any) -> Path:
        """Plans a collision-free path for component ``name`` from its pose (or
        ``start``) to ``goal`` (4×4, world, mm) among all the other components.

        Keywords: the planning table of docs/api.md, the keys of a script's options
        map: ``planner`` (``"rrt_connect"`` default; see ``planner_names()``),
        ``seed`` (same seed, same path), ``time_limit_ms`` (budget of the whole
        call), ``max_iterations``, ``step`` (mm), ``goal_bias``, ``smoothing``,
        ``narrow`` (bool or dict), ``fallback_share``, ``L``, ``dis``, ``radius``,
        ``tolerance`` (mm), ``edge`` (``"continuous"``/``"step"``), ``contact_step``,
        ``edge_step`` (mm), ``edge_step_deg`` (degrees), ``bounds``
        (``[[min xyz], [max xyz]]`` mm, for the part origin), ``margin`` (mm),
        ``rotation`` (bool), ``rotation_weight`` (mm per rad), ``disassemble``,
        ``start`` (4×4).
        A path that is not found is returned with ``found == False`` and a ``reason``.
        """
    def plan_insertion(self, name: str, goal: _Pose, **options: Any) -> Path:
        """Seed 002's insertion: plans the disassembly from whichever end (start or
        ``goal``) lies inside the box of the other components until the part leaves
        it, and joins the other end with RRT-Connect; the way into tight clearances.
        ``goal``: the seated pose (4×4, world, mm). Keywords as ``plan_path``.
        """
    def plan_disassembly(self, name: str, **options: Any) -> Path:
        """Seed 002's "can be disassembled, can be assembled": plans from the component's
        assembled pose until its box leaves the box of the other components, then
        reverses the path so it ends assembled. Planner ``"local_rrt"`` by default
        (``"rrt"``, ``"biased_rrt"`` too); keywords as ``plan_path``.
        """
    def revalidate(self, path: Path) -> Dict[str, Any]:
        """Checks ``path`` again against the document as it is now, with the tolerance
        and edge check it was planned with: a dict ``ok``, and when blocked
        ``segment`` (the first blocked edge) and ``pose`` (4×4).
        """
    def follow(self, path: Path, step_mm: float) -> int:
        """Moves the path's component along ``path`` in steps of at most ``step_mm`` (and
        as many degrees); it ends at the path's last pose. Returns the number of steps.
        """
    def robots(self) -> List[str]:
        """Robot names."""
    def robot(self, name: str) -> Robot:
        """Robot ``name`` as a ``Robot`` (its kinematics with the document's base and
        tool; a copy: moving it does not move the document's robot).
        """
    def joints(self, robot: str) -> _F64:
        """The joints of robot ``name`` (rad, mm for prismatic joints)."""
    def set_joints(self, robot: str, joints: _Joints) -> None:
        """Sets the joints of robot ``robot`` (rad, mm for prismatic joints; within the
        limits); its link components move. A new value for a joint an equation drives
        raises DocumentError naming the equation.
        """
    def run_program(
        self, robot: str, file: Optional[_StrPath] = None, text: Optional[str] = None
    ) -> Dict[str, _F64]:
        """Runs a motion program (Line/Circle/Joint commands, ``.prg``) on robot
        ``robot`` from its current joints: ``file`` names a program file, or ``text``
        gives the program itself. The robot ends where the program ends. Returns the
        trajectory as a dict of arrays: ``t`` (s, ``(N,)``), ``joints`` (rad/mm,
        ``(N, dof)``), ``tcp`` (``(N, 4, 4)``, world, mm). Errors name file and line.
        """
    def plan_sequence(self, **options: Any) -> Dict[str, Any]:
        """Plans the assembly sequences (seed 003's task layer) and returns the plan as a
        dict (the JSON of ``fitup plan-sequence --json``): ``sequences`` best first,
        each with ``order``, ``mounts``, ``tasks`` (mating directions, safe lengths,
        grasps, mm), and ``rejected``, ``precedence``, ``time_ms``.

        Keywords: the sequence table of docs/api.md, the keys of a script's
        ``assembly_sequence`` map: ``mode`` (``"mates"``/``"geometry"``), ``base``,
        ``order``, ``max_sequences``, ``time_limit_ms`` (the whole call), ``seed``,
        ``tolerance`` (mm), ``slide_fit_mm`` (mm), ``components``, ``exclude``,
        ``threaded``, ``masses``,
        ``support``, ``contact_gap_mm``, ``gravity`` (a down vector),
        ``tight_clearance_mm``, ``planner_fallback``, ``fallback_time_limit_ms``,
        ``max_tilt_deg`` (degrees; ``max_tilt`` in radians is deprecated),
        ``sphere_directions``, ``probe_mm``, ``step_mm``, ``small_base_ratio``.
        Interferences of the assembled pose come back as ``fits`` (each allowed its
        depth in the removal checks), parts held across a clearance as
        ``support_gaps``, groups of parts nothing modelled holds together as
        ``separate_groups``.
        """

class Database:
    """The results database: runs, paths with their key poses, trajectories, document
    snapshots (``docs/database.md``).

    ``Database(target)``: a SQLite file (created when missing; relative paths from the
    current folder) or a ``postgres://user@host:port/db`` URL, which a batch on a
    cluster shares. Every stored result is one transaction. Poses come back as
    column-vector 4×4 arrays (mm), exactly as stored (quaternions).
    """

    def __init__(self, target: str) -> None: ...
    @property
    def target(self) -> str:
        """The database, without a password."""
    def start_run(self, script: str, document: Optional[str] = None) -> int:
        """Records the start of a run (``script``: what ran, e.g. a batch job's
        description; ``document``: its document). Returns the run's id.
        """
    def finish_run(self, run_id: int, status: str, output: str = "") -> None:
        """Records the end of run ``run_id``: ``status`` ``"ok"``, ``"failed"`` or
        ``"cancelled"`` and its output text.
        """
    def save_path(self, name: str, path: Path, run_id: Optional[int] = None) -> int:
        """Stores ``path`` (found or not, with its key poses, planner, seed and options)
        under ``name``; ``run_id`` files it under a run. Returns its id.
        """
    def paths(self, **filter: Any) -> List[Dict[str, Any]]:
        """Stored paths, oldest first, as dicts: ``id``, ``run_id``, ``name``,
        ``created_at``, ``component``, ``seed``, ``planner``, ``found``, ``reason``,
        ``length_mm``, ``time_ms``, ``poses`` (``(N, 4, 4)``). Filters (the
        path-filter table of docs/api.md, a script's ``paths`` map): ``name``,
        ``planner``, ``component``, ``since`` (UTC time or date prefix), ``run`` (a
        run id; ``run_id`` is its deprecated spelling).
        """
    def runs(self) -> List[Dict[str, Any]]:
        """Recorded runs, oldest first, as dicts: ``id``, ``script``, ``document``,
        ``started_at``, ``finished_at``, ``status``, ``output``, ``fitup_version``.
        """
    def query(self, sql: str, params: Sequence[Any] = ..., **limits: Any) -> Tuple[List[str], List[List[Any]]]:
        """A read-only SQL query (SELECT/WITH/VALUES; writes, ATTACH and settings are
        refused) with ``?`` parameters, within the time, row and byte limits
        ``max_seconds``, ``max_rows``, ``max_bytes`` (keywords; the query-limits table
        of docs/api.md). Returns ``(columns, rows)``.
        """
