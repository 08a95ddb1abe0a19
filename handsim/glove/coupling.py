"""Joints the glove does not measure: the DIP flexions, coupled to the PIP flexions.

The 18-sensor CyberGlove of GraspDB14 has no sensors over the distal interphalangeal joints (spec §3.2.2);
the glove software writes inferred values into the ``*-DIPJ`` columns of ``rad`` files, and ``raw`` files
hold 0 there (Table 4.3). :func:`couple_dip` replaces a finger's DIP flexion by a function of its PIP
flexion:

* a ratio, ``DIP = ratio · PIP`` — by default :data:`DIP_PIP_RATIO` = 2/3, the interdependence
  ``DIP = 2/3 PIP`` (spec 001, §2.3, after its reference [28]);
* ``"cyberglove"`` — the relation the GraspDB14 glove software used, measured on the three sample ``rad``
  files (:func:`cyberglove_dip`);
* None — off: keep the values the trajectory has (the glove software's, for a ``rad`` file).

Angles are joint targets (flexion positive, radians), as in :class:`~handsim.datatypes.trajectory.Trajectory`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError

DIP_PIP_RATIO = 2.0 / 3.0
"""Default coupling ratio: DIP flexion = 2/3 of PIP flexion (spec 001, §2.3)."""

CYBERGLOVE = "cyberglove"
"""Coupling mode reproducing the GraspDB14 glove software (:func:`cyberglove_dip`)."""

CYBERGLOVE_DIP_COEFFICIENTS = (0.17, 0.32)
"""``(a, b)`` of the glove software's relation ``dip = pip · |a − b · pip|`` (targets, radians)."""

FINGERS = ("if", "mf", "rf", "lf")
"""Fingers with a DIP joint, as DoF name prefixes: index, middle, ring, little."""

Coupling = float | str | None
"""One finger's coupling: a ratio, :data:`CYBERGLOVE`, or None (off)."""


def cyberglove_dip(pip: npt.ArrayLike) -> np.ndarray:
    """The DIP flexion the GraspDB14 glove software inferred from the PIP flexion.

    Measured on the three GraspDB14 sample ``rad`` files (3156 PIP/DIP pairs over four fingers and three
    actors): with flexion positive (joint targets, the negated file values),
    ``dip = pip · |0.17 − 0.32 · pip|`` holds for every sample to 5e-6 rad, the rounding of the files'
    five decimals. The DIP/PIP ratio therefore is not constant: 0.17 at a straight finger, 0 at
    pip = 0.53 rad, 0.33 at pip = 1.55 rad (the largest in the samples); never near 2/3.

    Args:
        pip: PIP flexion in radians, any shape.

    Returns:
        DIP flexion in radians, same shape.
    """
    a, b = CYBERGLOVE_DIP_COEFFICIENTS
    p = np.asarray(pip, dtype=float)
    return p * np.abs(a - b * p)


def couple_dip(
    trajectory: Trajectory, ratio: Coupling | Mapping[str, Coupling] = DIP_PIP_RATIO
) -> Trajectory:
    """Set each finger's DIP flexion from its PIP flexion.

    For every coupled finger ``f`` the column ``f_dip_flex`` is replaced by a function of
    ``f_pip_flex`` (see the module docstring), takes over the PIP's validity (and filled mask), and is
    listed in :attr:`Trajectory.computed`. A note states the coupling of every finger.

    Args:
        trajectory: Joint targets with ``<finger>_pip_flex`` and ``<finger>_dip_flex`` columns.
        ratio: One coupling for all fingers — a ratio (``DIP = ratio · PIP``), :data:`CYBERGLOVE`, or None
            to keep the DIP values as they are — or a mapping from finger (``"if"``, ``"mf"``, ``"rf"``,
            ``"lf"``) to such a coupling; fingers missing from the mapping are kept.

    Returns:
        The coupled trajectory (the input if every finger is kept, with a note saying so).

    Raises:
        TrajectoryError: A finger or coupling is unknown or not finite, or a coupled finger lacks its PIP
            or DIP column (the message lists the trajectory's DoFs).
    """
    per_finger = _per_finger(ratio)
    targets = trajectory.targets.copy()
    valid = trajectory.valid.copy()
    filled = None if trajectory.filled is None else trajectory.filled.copy()
    computed = list(trajectory.computed)
    said: list[str] = []
    for finger in FINGERS:
        coupling = per_finger.get(finger)
        dip, pip = f"{finger}_dip_flex", f"{finger}_pip_flex"
        if coupling is None:
            said.append(f"{dip} kept")
            continue
        missing = [d for d in (pip, dip) if d not in trajectory.dof_names]
        if missing:
            raise TrajectoryError(
                f"cannot couple the {finger} DIP: no DoF {' or '.join(map(repr, missing))}; "
                f"DoFs are {list(trajectory.dof_names)}"
            )
        i, j = trajectory.dof_names.index(dip), trajectory.dof_names.index(pip)
        if coupling == CYBERGLOVE:
            targets[:, i] = cyberglove_dip(targets[:, j])
            said.append(f"{dip} = {pip}·|0.17 − 0.32·{pip}| (GraspDB14 glove software)")
        else:
            targets[:, i] = float(coupling) * targets[:, j]
            said.append(f"{dip} = {float(coupling):.4g}·{pip}")
        valid[:, i] = valid[:, j]
        if filled is not None:
            filled[:, i] = filled[:, j]
        if dip not in computed:
            computed.append(dip)
    if all(per_finger.get(f) is None for f in FINGERS):
        note = "DIP coupling off: DIP values kept as they were (the glove software's, for a rad file)"
        return dataclasses.replace(trajectory, notes=(*trajectory.notes, note))
    return dataclasses.replace(
        trajectory,
        targets=targets,
        valid=valid,
        filled=filled,
        computed=tuple(computed),
        notes=(*trajectory.notes, "DIP coupling: " + "; ".join(said)),
    )


def _per_finger(ratio: Coupling | Mapping[str, Coupling]) -> dict[str, Coupling]:
    """The coupling of each finger, validated."""
    if isinstance(ratio, Mapping):
        unknown = [k for k in ratio if k not in FINGERS]
        if unknown:
            raise TrajectoryError(
                f"unknown fingers {unknown} in the DIP coupling; fingers are {list(FINGERS)}"
            )
        per = dict(ratio)
    else:
        per = dict.fromkeys(FINGERS, ratio)
    for finger, value in per.items():
        if value is None or value == CYBERGLOVE:
            continue
        ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
        if not ok or not np.isfinite(float(value)):
            raise TrajectoryError(
                f"DIP coupling of finger {finger!r} must be a finite ratio, {CYBERGLOVE!r} or None, "
                f"got {value!r}"
            )
    return per


__all__ = [
    "CYBERGLOVE",
    "CYBERGLOVE_DIP_COEFFICIENTS",
    "DIP_PIP_RATIO",
    "FINGERS",
    "Coupling",
    "couple_dip",
    "cyberglove_dip",
]
