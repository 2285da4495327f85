"""fitup's exceptions.

Every error fitup raises is a ``FitupError``. Errors located in a file the user
wrote (a document's YAML, a mesh, a Rhai script, a motion program) carry
``file``, ``line`` and ``column`` (1-based; None when not known) and ``cause``
(the message without its location). They pickle, so a Dask or Ray worker's
error reaches the caller whole.
"""

from __future__ import annotations

from typing import List, Optional


class FitupError(Exception):
    """Base class of fitup's errors.

    Attributes: ``file`` (str or None), ``line`` and ``column`` (1-based int or
    None), ``cause`` (the message without the location), ``output`` (for a
    script: the lines it printed before it failed, else None).
    """

    def __init__(
        self,
        message: str,
        file: Optional[str] = None,
        line: Optional[int] = None,
        column: Optional[int] = None,
        cause: Optional[str] = None,
        output: Optional[List[str]] = None,
    ) -> None:
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column
        self.cause = cause if cause is not None else message
        self.output = output

    def __reduce__(self):
        return (
            type(self),
            (str(self), self.file, self.line, self.column, self.cause, self.output),
        )


class DocumentError(FitupError):
    """A document could not be loaded, saved or changed (YAML, meshes, names, values)."""


class WorkspaceError(FitupError):
    """An interference, sweep or planning request was refused (options, fixed
    components, a spent sweep budget)."""


class SequenceError(FitupError):
    """Assembly-sequence planning could not answer (interfering parts, no order, time)."""


class RobotError(FitupError):
    """Kinematics refused its input, or a motion program failed (file and line)."""


class DatabaseError(FitupError):
    """The results database refused (cannot open, read-only, busy, a refused query)."""


class ScriptError(FitupError):
    """A Rhai script failed (syntax, runtime error, assert), located in its file."""


class InputError(FitupError, ValueError):
    """A Python argument fitup cannot use: an array of the wrong shape, a matrix that
    is not a rigid pose, an unknown keyword or name."""


__all__ = [
    "FitupError",
    "DocumentError",
    "WorkspaceError",
    "SequenceError",
    "RobotError",
    "DatabaseError",
    "ScriptError",
    "InputError",
]
