"""handsim's parametric default hand as a MuJoCo spec.

The skeleton (:mod:`handsim.io.graspdb.default_skeleton`, plain data) built by
:func:`~handsim.builders.hand.build_hand` with the hand's breadth.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from handsim.io.graspdb.default_skeleton import DEFAULT_BREADTH_RATIO, DEFAULT_HAND_LENGTH_M, default_skeleton

if TYPE_CHECKING:
    import mujoco


def default_hand(
    hand_length_m: float = DEFAULT_HAND_LENGTH_M,
    hand_breadth_m: float | None = None,
    **build_options: object,
) -> mujoco.MjSpec:
    """The parametric default hand as a MuJoCo spec (see :func:`default_skeleton`, :func:`build_hand`).

    Args:
        hand_length_m: Wrist crease to middle fingertip, metres.
        hand_breadth_m: Breadth across the metacarpals, metres; 0.45 × length by default.
        **build_options: Passed to :func:`~handsim.builders.hand.build_hand` (e.g. ``mass``).

    Returns:
        An uncompiled spec.
    """
    breadth = DEFAULT_BREADTH_RATIO * hand_length_m if hand_breadth_m is None else hand_breadth_m
    from handsim.builders.hand import build_hand  # lazy: MuJoCo + SciPy; the skeleton and sizes need neither

    return build_hand(default_skeleton(hand_length_m, breadth), breadth=breadth, **build_options)
