"""A compiled, instrumented scene with the choices its scenario made: what :func:`replay` runs.

:class:`SimScene` is plain and picklable (``mujoco.MjModel`` pickles), so the same scene can be sent to a
worker process or a Ray task.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import mujoco
import numpy as np

from handsim.sim.scene.layout import SceneLayout, instrument, scene_layout
from handsim.sim.scene.model import compile_spec

SCENARIOS = ("free", "recorded", "glove")
"""``free``: nothing recorded about objects. ``recorded``: object tracks to follow and compare against.
``glove``: the object is placed by search, held by a support and released after the grasp closes."""
IDENTITY_POSE = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class SceneSetup:
    """What a scenario decided when it built the scene.

    Attributes:
        scenario: One of :data:`SCENARIOS`.
        world_from_recording: Pose (x, y, z, qw, qx, qy, qz) mapping the trajectory's frame into the
            scene's world frame (z up, table top z = 0); applied to root poses and object tracks.
        object_tracks: Per scene object (in layout order), the key of its track in
            ``Trajectory.objects``, or "" for an object without one.
        contact_time: Trajectory time (s) from which hand–object contacts act; before it the objects
            collide with nothing and hang on their supports (glove scenario: the hand reaches through
            where the placed object will be). None: from the start.
        release_time: Trajectory time (s) at which the objects' supports are switched off; None: never.
        hold_window: Trajectory times (start, stop) in s over which holding is judged, or None.
        grasp_time: Trajectory time (s) of the grasp frame the object was placed for, or None.
        placement: Summary of the object placement search (glove scenario), JSON-ready.
        notes: Decisions made while building, for the user to see.
        start_articulation: Per scene object (layout order), the hinge angle a replay from frame 0 starts it
            at, rad (NaN: the recorded one, clamped into the hinge's range); empty: every object recorded.
            A scenario sets it where the recorded angle would start the parts inside each other
            (:func:`handsim.sim.scene.settle.settle_hinge`).
        checks: What the scenario's checks before the run found (the world against the recorded hands, the
            parts' and hands' overlap at the start), JSON-ready; empty where none ran.
        unjudged: Why the hold is not judged whatever the run shows (``not judged: …``: a glove recording
            whose only grasp episodes are cut off by the file), or None.
    """

    scenario: str = "free"
    world_from_recording: tuple[float, ...] = IDENTITY_POSE
    object_tracks: tuple[str, ...] = ()
    contact_time: float | None = None
    release_time: float | None = None
    hold_window: tuple[float, float] | None = None
    grasp_time: float | None = None
    placement: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    start_articulation: tuple[float, ...] = ()
    checks: dict = field(default_factory=dict)
    unjudged: str | None = None

    def __post_init__(self) -> None:
        if self.scenario not in SCENARIOS:
            raise ValueError(f"unknown scenario {self.scenario!r}; expected one of {list(SCENARIOS)}")
        if len(self.world_from_recording) != 7 or not np.all(np.isfinite(self.world_from_recording)):
            raise ValueError("world_from_recording must be 7 finite numbers (x, y, z, qw, qx, qy, qz)")


@dataclass(frozen=True)
class SimScene:
    """A compiled scene ready to replay.

    Attributes:
        model: The compiled model (with the metric sensors).
        layout: Index arrays of its hand, objects and sensors.
        setup: The scenario's choices.
        model_sha256: SHA-256 of the compiled model (:func:`model_digest`): same model, same hash.
    """

    model: mujoco.MjModel
    layout: SceneLayout
    setup: SceneSetup
    model_sha256: str

    @property
    def timestep(self) -> float:
        """Simulation step, seconds."""
        return float(self.model.opt.timestep)


def compile_scene(spec: mujoco.MjSpec, setup: SceneSetup | None = None) -> SimScene:
    """Instrument a copy of a scene spec with the metric sensors and compile it.

    Args:
        spec: A scene from :func:`handsim.builders.build_scene` (left unchanged).
        setup: The scenario's choices (default: a free scene).

    Returns:
        The compiled scene.

    Raises:
        ModelError: The spec does not compile, or is not a handsim scene.
    """
    model = compile_spec(instrument(spec.copy()))
    return SimScene(
        model=model, layout=scene_layout(model), setup=setup or SceneSetup(), model_sha256=model_digest(model)
    )


def model_digest(model: mujoco.MjModel) -> str:
    """SHA-256 of a compiled model's binary form (MuJoCo's MJB, :func:`mujoco.mj_saveModel`), hex.

    Every number the simulation reads is in it, with the names; the same spec compiled again gives the same
    bytes (for a mug scene: 9 ms, where its MJCF with the meshes inlined took 120 ms to write).
    """
    buffer = np.empty(mujoco.mj_sizeModel(model), dtype=np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    return hashlib.sha256(buffer.tobytes()).hexdigest()
