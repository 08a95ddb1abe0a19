"""Exception hierarchy of handsim.

Every error the package raises on purpose is a :class:`HandsimError`. Errors about an input file say
which file, which line (or XML element) and which field was wrong, and what was expected, so a user can
fix the file without reading our code.
"""

from __future__ import annotations

from pathlib import Path


class HandsimError(Exception):
    """Base class of every error raised by handsim on purpose."""


class InputFileError(HandsimError):
    """A file is missing, unreadable, or of a type handsim does not read."""


class FormatError(HandsimError):
    """A file's content does not follow its format.

    Attributes:
        path: The file.
        line: 1-based line number, when the problem sits on one line.
        element: XML element (or other named location), when there is no useful line.
        field: The field that was wrong.
        reason: What was found and what was expected.
    """

    def __init__(
        self,
        path: str | Path,
        reason: str,
        *,
        line: int | None = None,
        element: str | None = None,
        field: str | None = None,
    ) -> None:
        self.path = str(path)
        self.line = line
        self.element = element
        self.field = field
        self.reason = reason
        where = self.path
        if line is not None:
            where += f":{line}"
        if element is not None:
            where += f" <{element}>"
        if field is not None:
            where += f" [{field}]"
        super().__init__(f"{where}: {reason}")


class OutOfRangeError(HandsimError):
    """A physical parameter (a mass, a density) lies outside its documented plausible range."""


class SkeletonError(HandsimError):
    """A skeleton is inconsistent (unknown joint, bad DoF, wrong array shape)."""


class TrajectoryError(HandsimError):
    """A trajectory is inconsistent with itself or with the hand it should drive."""


class MeshError(HandsimError):
    """A mesh cannot be used (empty, non-finite, degenerate, not watertight)."""


class ModelError(HandsimError):
    """A MuJoCo model could not be built or compiled."""


class SimulationError(HandsimError):
    """A simulation diverged or raised MuJoCo warnings that make its result meaningless."""


class RenderError(HandsimError):
    """Offscreen rendering failed: no OpenGL context (no display, no EGL/OSMesa), or an image too large."""
