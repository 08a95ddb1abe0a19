"""The inputs of a gravity stability test, checked before any run: the request, the state, the hand's target.

:func:`~handsim.sim.stability.gravity.stability_test` refuses what its runs could not simulate faithfully
— a scene with several hands, an object index out of range, a non-finite state or control (MuJoCo would
silently reset the state or replace the control) — before it copies the model or starts a run.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence

import numpy as np
import numpy.typing as npt

from handsim.errors import SimulationError
from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.layout import SceneLayout


def check_request(
    layout: SceneLayout,
    object_index: int,
    first: Sequence[str],
    needed: int | Callable[[], int],
    directions: Collection[str],
) -> None:
    """Check which object a test judges and the order of its runs.

    Args:
        layout: The scene's layout.
        object_index: Which object is judged (layout order).
        first: The directions to run first.
        needed: The test's ``needed`` (an int, or a function asked before each run).
        directions: The labels of the directions a test runs.

    Raises:
        ValueError: The scene has several hands (the tests hold one), ``object_index`` names no object, or
            ``first`` names an unknown direction or comes without ``needed``.
    """
    objects = layout.objects
    if len(layout.hands) > 1:
        raise ValueError(
            f"the stability tests hold one hand; the scene has {len(layout.hands)} "
            f"({[h.name for h in layout.hands]})"
        )
    if not 0 <= object_index < len(objects):
        raise ValueError(f"object_index {object_index} names no object; the scene has {len(objects)}")
    unknown = [label for label in first if label not in directions]
    if unknown:
        raise ValueError(f"first: unknown directions {unknown}; expected labels of {list(directions)}")
    if first and not callable(needed) and needed <= 0:
        raise ValueError("first orders the runs of a test with needed; without it the runs go to threads")


def checked_array(value: npt.ArrayLike, shape: tuple[int, ...], what: str) -> np.ndarray:
    """A float copy of ``value``, checked to have ``shape`` and to be finite.

    Args:
        value: The values.
        shape: Their expected shape.
        what: Their name in the messages (``"qpos"``).

    Raises:
        ValueError: ``value`` has another shape.
        SimulationError: A value is not finite.
    """
    array = np.asarray(value, dtype=float)
    if array.shape != shape:
        raise ValueError(f"{what} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise SimulationError(
            f"stability test {what}: non-finite value at index {int(np.flatnonzero(~np.isfinite(array))[0])}"
        )
    return array.copy()


def mocap_pose(
    scene: SimScene, qpos: np.ndarray, pos: npt.ArrayLike | None, quat: npt.ArrayLike | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The pose the hand's mocap target holds during the runs: given, or the root's in ``qpos``.

    Args:
        scene: The scene.
        qpos: The state to test (nq,).
        pos: The target's position (3,), m, or None for the root's.
        quat: Its orientation (w, x, y, z), or None for the root's; normalised.

    Returns:
        (position, unit quaternion), or None for a hand without a mocap target.

    Raises:
        ValueError: A pose is given for a hand without a mocap target, or the quaternion is zero.
        SimulationError: A given value is not finite.
    """
    layout = scene.layout
    if layout.mocap < 0:
        if pos is not None or quat is not None:
            raise ValueError(
                "mocap_pos/mocap_quat given, but the scene's hand has no mocap target (hand_root='fixed')"
            )
        return None
    root = qpos[layout.root_free_qpos : layout.root_free_qpos + 7]
    position = root[:3] if pos is None else checked_array(pos, (3,), "mocap_pos")
    orientation = root[3:] if quat is None else checked_array(quat, (4,), "mocap_quat")
    norm = np.linalg.norm(orientation)
    if not norm > 0:
        raise ValueError("mocap_quat must be a non-zero quaternion (w, x, y, z)")
    return position.copy(), orientation / norm
