"""A rest posture for the thumb DoFs the glove does not drive.

The CyberGlove drives one DoF of the thumb's trapeziometacarpal (TMC) joint: ``T-TMCJ`` → ``th_tmc_pron``
(:mod:`handsim.glove.sensors`). The skeleton's two other TMC DoFs, ``th_tmc_abd`` and ``th_tmc_flex``, are
driven by no sensor; the GraspDB14 MATLAB tools leave them at 0 (the skeleton's rest pose), and so does
handsim by default, which keeps the forward kinematics identical to the published joint trajectories.

:func:`apply_thumb_rest` holds them at a constant posture instead. The angles are the DoFs' own (degrees,
about the joint's local z for ``abd`` and local x for ``flex``, signs as in the skeleton file) and must lie in
the skeleton's limits. What the posture does on the real recordings is measured in ``docs/cyberglove.md``
("Thumb rest posture"); no posture is the default because none measured better than the rest pose.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.glove.sensors import driven_dofs

THUMB_REST_DOFS = ("th_tmc_abd", "th_tmc_flex")
"""The thumb DoFs no glove sensor drives, in the order :func:`apply_thumb_rest` takes their angles."""


def apply_thumb_rest(
    trajectory: Trajectory, skeleton: Skeleton, abduction_deg: float, flexion_deg: float
) -> Trajectory:
    """Hold the undriven thumb TMC DoFs at a constant posture through the whole recording.

    Args:
        trajectory: A glove recording as joint targets of ``skeleton``.
        skeleton: The hand it drives.
        abduction_deg: ``th_tmc_abd``, degrees (the DoF's own sign and axis).
        flexion_deg: ``th_tmc_flex``, degrees.

    Returns:
        The trajectory with both columns constant and valid in every frame (:func:`thumb_rest_note` says
        so for people).

    Raises:
        TrajectoryError: An angle is not finite or outside the DoF's limits, the skeleton lacks the DoF,
            or the recording drives it (then it is not undriven).
    """
    targets = np.array(trajectory.targets, copy=True)
    valid = np.array(trajectory.valid, copy=True)
    dofs = {d.name: d for d in skeleton.dofs}
    driven = set(driven_dofs())
    for name, degrees in zip(THUMB_REST_DOFS, (abduction_deg, flexion_deg), strict=True):
        if not math.isfinite(degrees):
            raise TrajectoryError(f"thumb rest {name}: expected a finite angle in degrees, got {degrees!r}")
        if name not in dofs or name not in trajectory.dof_names:
            raise TrajectoryError(
                f"thumb rest: the hand has no DoF {name!r} (a thumb rest needs th_tmc_abd and th_tmc_flex, "
                "as in the GraspDB14 skeleton and the parametric default hand)"
            )
        if name in driven:
            raise TrajectoryError(f"thumb rest: {name} is driven by a glove sensor, not undriven")
        dof = dofs[name]
        lower, upper = math.degrees(dof.lower), math.degrees(dof.upper)
        if not lower <= degrees <= upper:
            raise TrajectoryError(
                f"thumb rest {name} = {degrees:g} deg is outside the joint's limits {lower:g}..{upper:g} deg"
            )
        column = trajectory.dof_names.index(name)
        targets[:, column] = math.radians(degrees)
        valid[:, column] = True
    return dataclasses.replace(trajectory, targets=targets, valid=valid)


def thumb_rest_note(abduction_deg: float, flexion_deg: float) -> str:
    """The note a trial carries when :func:`apply_thumb_rest` held the thumb at this posture (degrees)."""
    return (
        f"thumb rest posture: th_tmc_abd {abduction_deg:g} deg, th_tmc_flex {flexion_deg:g} deg held "
        "through the recording (no glove sensor drives them; the GraspDB14 tools leave them at 0)"
    )
