"""Readers: one per file format, each returning handsim's plain data types in SI units.

Entry points:

* :func:`read_skeleton` — ``.xmlskel`` (GraspDB14) or ``.SKEL`` (+ ``.LIMITS`` …, Tzionas/Ballan).
* :func:`read_trajectory` — GraspDB14 CyberGlove recordings (``.txt``, radians or raw counts with a
  calibration), Tzionas/Ballan hand ``.MOTION`` files (with the sequence's object tracks) and handsim's
  synthetic scripted grasps (``.grasp.json``, :mod:`handsim.io.scripted`).

GraspDB14 files beside a recording: phase annotations (:mod:`handsim.io.graspdb.annotations`) and glove
calibrations (:mod:`handsim.io.graspdb.calibration`: ``load_calibration``, ``save_calibration``). The
parametric default hand's skeleton, plain data from published proportions, is
:func:`handsim.io.graspdb.default_skeleton.default_skeleton`.

Other sources, with their own readers: ARCTIC (:mod:`handsim.io.arctic.sequence`: ``read_arctic_sequence``
— both hands and the object —, ``read_arctic_mano``, ``read_arctic_object``; templates in
:mod:`handsim.io.arctic.templates`), MANO models and poses (:mod:`handsim.io.arctic.mano`:
``read_mano_model``;
:mod:`handsim.io.arctic.mano_pose`: ``mano_pose_to_trajectory``), meshes (:mod:`handsim.io.mesh`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import InputFileError
from handsim.io.graspdb.glove import read_graspdb_glove
from handsim.io.graspdb.xmlskel import read_xmlskel
from handsim.io.scripted import read_scripted_grasp
from handsim.io.text_files import require_file
from handsim.io.tzionas.configs import config_dir_of
from handsim.io.tzionas.motion import read_tzionas_motion
from handsim.io.tzionas.sequence import read_tzionas_sequence
from handsim.io.tzionas.skeleton import read_tzionas_skeleton

if TYPE_CHECKING:
    from handsim.glove.calibration import GloveCalibration

SKELETON_SUFFIXES = {".xmlskel": "GraspDB14 skeleton", ".skel": "Tzionas/Ballan skeleton (+ .LIMITS)"}
TRAJECTORY_SUFFIXES = {
    ".txt": "GraspDB14 CyberGlove recording (radians, or raw counts with a calibration)",
    ".motion": "Tzionas/Ballan hand motion (with its .SKEL/.LIMITS, and the sequence's objects)",
    ".grasp.json": "handsim scripted grasp (synthetic closing motion of the parametric default hand)",
}


def _suffix_or_error(path: Path, known: dict[str, str], what: str) -> str:
    require_file(path)
    if what == "trajectory" and path.name.endswith((".mano.npy", ".object.npy")):
        raise InputFileError(
            f"{path}: an ARCTIC sequence (two MANO hands in <seq>.mano.npy, the object in <seq>.object.npy), "
            "not a one-hand trajectory: read it with handsim.io.arctic.sequence.read_arctic_sequence "
            "(`handsim inspect <seq>.mano.npy` summarises it)"
        )
    suffix = path.suffix.lower()
    if path.name.lower().endswith(".grasp.json"):
        suffix = ".grasp.json"
    if suffix not in known and not (what == "trajectory" and suffix == ""):
        listing = ", ".join(f"{k} ({v})" for k, v in known.items())
        raise InputFileError(f"{path}: unknown {what} file type {path.suffix!r}; handsim reads {listing}")
    return suffix


def read_skeleton(path: str | Path) -> Skeleton:
    """Read a hand skeleton, choosing the reader from the file extension.

    Args:
        path: A ``.xmlskel`` file, or a ``.SKEL`` file with its ``.LIMITS`` (and optionally ``.MOTION``,
            ``.OFF``, ``.SKIN``, ``.VOI``) beside it.

    Returns:
        The skeleton in SI units.

    Raises:
        InputFileError: Missing or unreadable file, or an extension handsim does not read.
        FormatError: The file does not follow its format (the message names file, line and field).
    """
    p = Path(path)
    suffix = _suffix_or_error(p, SKELETON_SUFFIXES, "skeleton")
    if suffix == ".xmlskel":
        return read_xmlskel(p)

    return read_tzionas_skeleton(p)


def read_trajectory(
    path: str | Path, skeleton: Skeleton | None = None, calibration: GloveCalibration | None = None
) -> Trajectory:
    """Read recorded hand motion as joint-angle targets.

    Args:
        path: A GraspDB14 CyberGlove recording (``*-rad-*.txt``, or ``*-raw-*.txt`` with ``calibration``;
            GraspDB14's FK-oracle files have no extension and are accepted too), or a Tzionas/Ballan
            ``Model_Hand_*.MOTION`` (its ``.SKEL``/``.LIMITS`` beside it; ``skeleton`` is not used — the
            columns are that skeleton's DoFs — and the objects of ``Configs/NN/MODELS_INFO.txt`` become
            object tracks), or a synthetic scripted grasp ``NAME.grasp.json`` (:mod:`handsim.io.scripted`;
            its columns are ``skeleton``'s DoFs, default the parametric hand of the file's ``hand_length``).
        skeleton: The hand the targets are for. Its DoF names become the trajectory's columns; DoFs the
            recording does not drive are held at 0 and listed in ``notes``. Without a skeleton, the
            columns are the DoFs the glove drives.
        calibration: For a raw-count recording (``*-raw-*``): the glove calibration that converts counts
            to radians (see :func:`handsim.glove.estimate_calibration`).

    Returns:
        The trajectory (times in s, targets in rad).

    Raises:
        InputFileError: Missing or unreadable file, or an unknown extension.
        FormatError: Malformed rows (the message names file, line and field), or a raw-count file.
    """
    p = Path(path)
    suffix = _suffix_or_error(p, TRAJECTORY_SUFFIXES, "trajectory")
    if suffix == ".motion":
        return _read_tzionas(p)
    if suffix == ".grasp.json":
        if calibration is not None:
            raise InputFileError(f"{p}: a scripted grasp is synthetic joint angles; it takes no calibration")

        return read_scripted_grasp(p, skeleton=skeleton)

    return read_graspdb_glove(p, skeleton=skeleton, calibration=calibration)


def _read_tzionas(path: Path) -> Trajectory:
    """A hand ``.MOTION`` with the sequence's object tracks when its ``Configs/NN`` lists them."""
    if not path.stem.startswith("Model_Hand"):
        raise InputFileError(
            f"{path}: not a hand motion (Model_Hand_*.MOTION); give the sequence's Model_Hand_*.MOTION, "
            "whose replay brings the objects of its Configs/NN (in Python, object motions alone are read "
            "with handsim.io.tzionas.motion.read_tzionas_object_motion)"
        )
    if (config_dir_of(path.parent) / "MODELS_INFO.txt").is_file():
        return read_tzionas_sequence(path.parent, hand=path.stem)
    return read_tzionas_motion(path.with_suffix(".SKEL"))


__all__ = ["read_skeleton", "read_trajectory"]
