"""Drop test: an object released above the table must come to rest on it, without MuJoCo warnings.

A cheap end-to-end check of an object model — collision hulls, mass, inertia and contact parameters
together: a wrong inertia makes the object spin or jitter, a broken hull lets it sink or explode.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.scene import build_scene, resting_position
from handsim.sim.scene.model import compile_spec
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
        hinge_span: Smallest and largest hinge angle over the run, radians (an articulated object), or None.
        hinge_range: The hinge's joint range, radians, or None (rigid or unlimited).
    """

    rest_time: float | None
    final_height: float
    max_speed: float
    mass: float
    warnings: dict[str, int]
    hinge_span: tuple[float, float] | None = None
    hinge_range: tuple[float, float] | None = None

    def hinge_outside(self) -> float:
        """How far the hinge went outside its range over the run, radians (0 when inside or unlimited)."""
        if self.hinge_span is None or self.hinge_range is None:
            return 0.0
        (lo, hi), (low, high) = self.hinge_span, self.hinge_range
        return max(0.0, low - lo, hi - high)

    @property
    def ok(self) -> bool:
        """True if the object came to rest and MuJoCo raised no warning."""
        return self.rest_time is not None and not self.warnings


def drop_test(
    obj: mujoco.MjSpec,
    height: float = 0.05,
    duration: float = 2.0,
    *,
    quat: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
    articulation: float = 0.0,
) -> DropResult:
    """Release an object ``height`` above the table (lowest point) and simulate ``duration`` seconds.

    Args:
        obj: An object spec from :func:`handsim.builders.build_object` (with its free joint).
        height: Gap between the object's lowest point and the table top at release, metres.
        duration: Simulated seconds.
        quat: The object's orientation at release (w, x, y, z), e.g. a recording's first frame.
        articulation: The hinge angle at release, radians (an articulated object; ignored otherwise).

    Returns:
        When it came to rest, where, its mass, any MuJoCo warnings and the hinge's span over the run.
    """
    q = np.asarray(quat, dtype=float)
    rest = resting_position(obj, quat=q)
    start = resting_position(obj, gap=height, quat=q)
    model = compile_spec(build_scene(None, [obj], object_poses=[[*start, *q]]))
    data = mujoco.MjData(model)
    free = model.joint("obj/free")
    root = model.jnt_bodyid[free.id]
    hinge = model.joint("obj/hinge").id if _has_joint(model, "obj/hinge") else None
    if hinge is not None:
        data.qpos[model.jnt_qposadr[hinge]] = articulation
    dof = slice(int(model.jnt_dofadr[free.id]), model.nv)  # the free joint and any hinge after it
    steps = round(duration / model.opt.timestep)
    calm_since: float | None = None
    recent: deque[float] = deque(maxlen=max(1, round(REST_HOLD / model.opt.timestep)))
    span = [np.inf, -np.inf]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        speed = float(np.max(np.abs(data.qvel[dof])))
        recent.append(speed)
        if speed < REST_SPEED:
            calm_since = data.time if calm_since is None else calm_since
        else:
            calm_since = None
        if hinge is not None:
            angle = float(data.qpos[model.jnt_qposadr[hinge]])
            span = [min(span[0], angle), max(span[1], angle)]
    rest_time = calm_since if calm_since is not None and data.time - calm_since >= REST_HOLD else None
    counts = {k: v for k, v in warning_counts(data).items() if v}
    limited = hinge is not None and bool(model.jnt_limited[hinge])
    return DropResult(
        rest_time=rest_time,
        final_height=float(data.qpos[model.jnt_qposadr[free.id] + 2] - rest[2]),
        max_speed=max(recent),
        mass=float(model.body_subtreemass[root]),
        warnings=counts,
        hinge_span=(span[0], span[1]) if hinge is not None else None,
        hinge_range=tuple(float(r) for r in model.jnt_range[hinge]) if limited else None,
    )


def _has_joint(model: mujoco.MjModel, name: str) -> bool:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name) >= 0
