"""fitup from Python: assembly documents, interference, path planning, robots,
sequences, the results database and Rhai scripts — the Rust library, called
with the GIL released — plus ``fitup.batch`` for many jobs on a Dask cluster.

Units are millimetres and radians everywhere (joint arrays in radians, mm for
prismatic joints); ``Document.system_value`` alone is SI (metres, radians), like
the SolidWorks API. Poses are numpy ``(4, 4)`` arrays in the column-vector
convention (``p_world = T @ [x, y, z, 1]``, translation in ``T[:3, 3]``, part
frame → world): the transpose of the document's SolidWorks matrix. See
docs/python.md.
"""

from ._fitup import (  # noqa: F401
    Database,
    Document,
    Path,
    Robot,
    __version__,
    catalog_names,
    option_keys,
    planner_names,
    run_script,
)
from . import errors
from .errors import (  # noqa: F401
    DatabaseError,
    DocumentError,
    FitupError,
    InputError,
    RobotError,
    ScriptError,
    SequenceError,
    WorkspaceError,
)


def open(path):  # noqa: A001 - the library's name for it
    """Loads the document at ``path`` (same as ``Document(path)``)."""
    return Document(path)


def translation(x, y, z):
    """The pose matrix of a pure translation by ``(x, y, z)`` mm (4×4 numpy array)."""
    import numpy as np

    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def rotation(axis, angle, point=(0.0, 0.0, 0.0)):
    """The pose matrix of a rotation by ``angle`` radians (right hand) about the line
    through ``point`` (mm) along ``axis`` (4×4 numpy array)."""
    import numpy as np

    a = np.asarray(axis, dtype=float)
    n = np.linalg.norm(a)
    if not n > 0:
        raise InputError("the rotation axis has zero length", cause="zero axis")
    x, y, z = a / n
    c, s = np.cos(angle), np.sin(angle)
    r = np.array(
        [
            [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
            [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
            [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
        ]
    )
    p = np.asarray(point, dtype=float)
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = p - r @ p
    return t


__all__ = [
    "Database",
    "Document",
    "Path",
    "Robot",
    "catalog_names",
    "planner_names",
    "run_script",
    "open",
    "translation",
    "rotation",
    *errors.__all__,
]
