"""Drop test: an object released above the table must come to rest on it, without MuJoCo warnings.

A cheap end-to-end check of an object model — collision hulls, mass, inertia and contact parameters
together: a wrong inertia makes the object spin or jitter, a broken hull lets it sink or explode.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.builders.scene import build_scene, resting_position
from handsim.sim.model import compile_spec
from handsim.sim.warnings import warning_counts

REST_SPEED = 0.005  # m/s and rad/s: the object counts as at rest below this (all of its DoF speeds)
REST_HOLD = 0.1  # seconds the object must stay below REST_SPEED


@dataclass(frozen=True)
class DropResult:
    """Outcome of :func:`drop_test`.

    Attributes:
        rest_time: Seconds after release at which the object came to rest for good, or None if it did not
            within the duration.
        final_height: Height of the object frame above its resting height at the end, metres (≈ 0 when it
            rests as placed; another value when it tipped over onto another face).
        max_speed: Largest object DoF speed in the last :data:`REST_HOLD` seconds (m/s or rad/s).
        mass: Total simulated mass of the object, kg.
        warnings: MuJoCo warning counts that were non-zero.
    """

    rest_time: float | None
    final_height: float
    max_speed: float
    mass: float
    warnings: dict[str, int]

    @property
    def ok(self) -> bool:
        """True if the object came to rest and MuJoCo raised no warning."""
        return self.rest_time is not None and not self.warnings


def drop_test(obj: mujoco.MjSpec, height: float = 0.05, duration: float = 2.0) -> DropResult:
    """Release an object ``height`` above the table (lowest point) and simulate ``duration`` seconds.

    Args:
        obj: An object spec from :func:`handsim.builders.build_object` (with its free joint).
        height: Gap between the object's lowest point and the table top at release, metres.
        duration: Simulated seconds.

    Returns:
        When it came to rest, where, its mass and any MuJoCo warnings.
    """
    rest = resting_position(obj)
    start = resting_position(obj, gap=height)
    model = compile_spec(build_scene(None, [obj], object_poses=[[*start, 1.0, 0.0, 0.0, 0.0]]))
    data = mujoco.MjData(model)
    free = model.joint("obj/free")
    root = model.jnt_bodyid[free.id]
    dof = slice(int(model.jnt_dofadr[free.id]), model.nv)  # the free joint and any hinge after it
    steps = round(duration / model.opt.timestep)
    calm_since: float | None = None
    recent: deque[float] = deque(maxlen=max(1, round(REST_HOLD / model.opt.timestep)))
    for _ in range(steps):
        mujoco.mj_step(model, data)
        speed = float(np.max(np.abs(data.qvel[dof])))
        recent.append(speed)
        if speed < REST_SPEED:
            calm_since = data.time if calm_since is None else calm_since
        else:
            calm_since = None
    rest_time = calm_since if calm_since is not None and data.time - calm_since >= REST_HOLD else None
    counts = {k: v for k, v in warning_counts(data).items() if v}
    return DropResult(
        rest_time=rest_time,
        final_height=float(data.qpos[model.jnt_qposadr[free.id] + 2] - rest[2]),
        max_speed=max(recent),
        mass=float(model.body_subtreemass[root]),
        warnings=counts,
    )
