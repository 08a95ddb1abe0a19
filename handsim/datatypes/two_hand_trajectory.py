"""One trajectory for a two-hand scene from one-hand trajectories of the same frames.

:func:`join_hands` puts one-hand trajectories of the same frames (ARCTIC's two MANO hands, a Tzionas
sequence's ``Model_Hand_R`` and ``Model_Hand_L``) into one trajectory for a two-hand scene.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.errors import TrajectoryError


def join_hands(
    hands: Mapping[str, Trajectory],
    *,
    objects: Mapping[str, ObjectTrack] | None = None,
    source: str | None = None,
    sha256: str | None = None,
) -> Trajectory:
    """One-hand trajectories of the same frames as one trajectory for a two-hand scene.

    Each hand's DoF columns are renamed ``<hand>/<dof>`` and its ``root_pose`` goes under
    ``hand_roots[hand]``; the hands' notes are prefixed ``<hand> hand: ``; their flags are kept (each once).

    Args:
        hands: Hand name (``"right"``, ``"left"``) → its trajectory (with a ``root_pose``), in scene order.
        objects: The object tracks; default: the first hand's.
        source: The recording; default: the first hand's ``source``.
        sha256: Its SHA-256; default: the first hand's.

    Returns:
        The trajectory (times of the first hand, seconds).

    Raises:
        TrajectoryError: No hand, a hand without a root pose, or hands whose frame counts or times differ
            (the message names each hand's source and frame count).
    """
    if not hands:
        raise TrajectoryError("join_hands needs at least one hand's trajectory")
    first = next(iter(hands.values()))
    counts = ", ".join(f"{name} {t.source or 'trajectory'}: {t.nframes} frames" for name, t in hands.items())
    if any(t.nframes != first.nframes or not np.array_equal(t.times, first.times) for t in hands.values()):
        raise TrajectoryError(
            f"the hands' trajectories must share their frames (the same count at the same times); {counts}"
        )
    rootless = [name for name, t in hands.items() if t.root_pose is None]
    if rootless:
        raise TrajectoryError(f"hands {rootless} have no root pose to follow; {counts}")
    flags = [f for t in hands.values() for f in t.flags]
    return Trajectory(
        times=first.times,
        dof_names=tuple(f"{name}/{d}" for name, t in hands.items() for d in t.dof_names),
        targets=np.hstack([t.targets for t in hands.values()]),
        valid=np.hstack([t.valid for t in hands.values()]),
        hand_roots={name: t.root_pose for name, t in hands.items()},
        objects=dict(first.objects if objects is None else objects),
        source=first.source if source is None else source,
        sha256=first.sha256 if sha256 is None else sha256,
        notes=tuple(f"{name} hand: {note}" for name, t in hands.items() for note in t.notes),
        flags=tuple(f for k, f in enumerate(flags) if f not in flags[:k]),
    )
