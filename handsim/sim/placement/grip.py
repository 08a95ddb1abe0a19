"""The grip a recorded closing makes on an object placed in the hand, and how well it holds.

:class:`GripBench` replays a glove scene exactly as :func:`handsim.sim.replay.replay` does up to the moment
its support lets the object go: the same control schedule, the object held by its support weld, hand–object
contacts acting from the candidate's contact frame. The fingers that the recording closes past the object
stop at its surface and press on it with their servos. Then the grasp stability test
(:func:`handsim.sim.stability.gravity.stability_test`: gravity along ±x ±y ±z in turn, hand frozen at its
targets,
after DexGraspNet) judges the grip: how many of the six directions it resists.

Before contacts act, the object collides with nothing, so the hand's motion up to a candidate's contact frame
does not depend on where the object is: the bench simulates it once (hand alone) and starts every candidate
from its state at that frame, with the object at rest at its pose (a replay's object has by then sagged on
its weld by a fraction of a millimetre). MuJoCo solves the hand's and the object's constraints as separate
islands but chooses the solver's warm start for all of them at once, by their summed cost; so the object could
in principle tip that choice at a step and change the hand's rounding. On the shared recordings' 29 ensemble
poses (winners included) the hand's state before contact was bit for bit that of the hand-alone run, on every
frame; the object's own state, the other way round, does depend on the hand's (``docs/replay.md``, "Ensemble
members cannot share their run before contact").
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import Trajectory
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScenarioSwitches, ScheduleDriver
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import StabilitySpec
from handsim.sim.stability.gravity import StabilityResult, stability_test
from handsim.sim.stepper import Stepper

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_NEVER = 1 << 62


@dataclass(frozen=True)
class GripResult:
    """How the recorded closing grips an object on its support, and how well the grip holds.

    Attributes:
        directions_held: Gravity directions (of six) the grip resisted.
        mean_displacement: Mean of the six directions' object displacements, m (a diverged direction, or
            one not run, counts as the stability spec's limit).
        normal_force: Sum of the hand–object contact normal forces at release, N.
        servo_torque: Sum of the absolute actuator torques of the finger flexion DoFs at release, N·m: what
            the servos exert because the recording closes past the object.
        links: Hand links touching the object at release (names).
        stability: The stability test in full.
    """

    directions_held: int
    mean_displacement: float
    normal_force: float
    servo_torque: float
    links: tuple[str, ...]
    stability: StabilityResult

    def to_dict(self) -> dict:
        """JSON-ready fields (without the stability test's details)."""
        return {
            "directions_held": self.directions_held,
            "mean_displacement_m": self.mean_displacement,
            "normal_force_n": self.normal_force,
            "servo_torque_nm": self.servo_torque,
            "links": list(self.links),
        }


def object_pose_variant(scene: SimScene, pose: npt.ArrayLike, object_index: int = 0) -> mujoco.MjModel:
    """A private copy of the scene's model with an object starting at ``pose`` (its support weld there too).

    Args:
        scene: A scene whose object is free, with or without a support weld.
        pose: (x, y, z, qw, qx, qy, qz) in the scene's world.
        object_index: Which object (layout order).
    """
    model = copy.deepcopy(scene.model)
    obj = scene.layout.objects[object_index]
    pose = np.asarray(pose, dtype=float)
    model.qpos0[obj.free_qpos : obj.free_qpos + 7] = pose
    if obj.support_eq >= 0:  # weld to the world: anchor on the object's origin, relative quaternion q*
        model.eq_data[obj.support_eq, 0:3] = pose[:3]
        model.eq_data[obj.support_eq, 3:6] = 0.0
        model.eq_data[obj.support_eq, 6:10] = pose[3:] * np.array([1.0, -1.0, -1.0, -1.0])
    return model


class GripBench:
    """Replays of one glove scene up to the release, for any object pose (see the module docstring).

    Args:
        scene: The glove scene (hand root fixed, the object on its support weld; a table or not).
        trajectory: The glove trajectory.
        control_rate: Control frames per second, as the replay will use.
        release_time: Trajectory time at which the support comes off (the grasp's closed time plus the
            release delay), s.
    """

    def __init__(
        self, scene: SimScene, trajectory: Trajectory, control_rate: float, release_time: float
    ) -> None:
        self.scene = scene
        self.schedule = control_schedule(scene, trajectory, control_rate)
        self.release = self.schedule.frame_at(release_time)
        stepper = Stepper(scene, self.schedule.substeps, own_model=True)
        driver = ScheduleDriver(stepper, self.schedule, ScenarioSwitches(contact_frame=_NEVER))
        driver.reset()
        size = mujoco.mj_stateSize(stepper.model, _STATE)
        self._states = np.empty((self.release + 1, size))
        mujoco.mj_getState(stepper.model, stepper.data, self._states[0], _STATE)
        for k in range(self.release):
            driver.advance(self.schedule.ctrl[k + 1])
            mujoco.mj_getState(stepper.model, stepper.data, self._states[k + 1], _STATE)
        layout = scene.layout
        self._flex = layout.actuators[
            np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names], dtype=bool)
        ]

    def grip(
        self,
        pose: npt.ArrayLike,
        contact_time: float,
        spec: StabilitySpec,
        object_index: int = 0,
        needed: int | Callable[[], int] = 0,
        first: Sequence[str] = (),
    ) -> GripResult:
        """Replay with the object at ``pose`` and contacts from ``contact_time`` up to the release; test it.

        Args:
            pose: The object's pose in the scene's world.
            contact_time: Trajectory time from which hand–object contacts act, s.
            spec: The stability test's parameters.
            object_index: Which object (layout order).
            needed: Stop the stability test once fewer than this many directions can still be resisted
                (:func:`~handsim.sim.stability.gravity.stability_test`; a function is asked before each
                direction):
                the result's ``directions_held`` is then below it, its ``mean_displacement`` counts the
                directions not run at the limit, and its stability test says which were not run. 0: the
                whole test.
            first: With ``needed``: the directions to test first (those most likely to fail).
        """
        scene, schedule = self.scene, self.schedule
        model = object_pose_variant(scene, pose, object_index)
        variant = replace(scene, model=model)
        contact = min(schedule.frame_at(contact_time), self.release)
        stepper = Stepper(variant, schedule.substeps)
        driver = ScheduleDriver(stepper, schedule, ScenarioSwitches(contact_frame=contact))
        data = stepper.data
        mujoco.mj_setState(model, data, self._states[contact], _STATE)
        obj = scene.layout.objects[object_index]
        data.qpos[obj.free_qpos : obj.free_qpos + 7] = pose
        data.qvel[obj.free_dof : obj.free_dof + 6] = 0.0
        mujoco.mj_forward(model, data)
        driver.frame = contact
        for k in range(contact, self.release):
            driver.advance(schedule.ctrl[k + 1])
        mujoco.mj_forward(model, data)
        layout = scene.layout
        normal = _normal_force(model, data, obj.part_bodies)
        torque = float(np.abs(data.actuator_force[self._flex]).sum())
        links = _links(
            model, data, dict(zip(layout.link_bodies.tolist(), layout.link_names, strict=True)), obj
        )
        stability = stability_test(
            variant,
            data.qpos.copy(),
            data.ctrl.copy(),
            spec=spec,
            object_index=object_index,
            stop_at_failure=True,
            needed=needed,
            first=first,
        )
        held = sum(d.success for d in stability.directions)
        moved = [
            spec.max_displacement if d.displacement is None else d.displacement for d in stability.directions
        ]
        return GripResult(
            directions_held=int(held),
            mean_displacement=float(np.mean(moved)),
            normal_force=normal,
            servo_torque=torque,
            links=links,
            stability=stability,
        )


def _normal_force(model: mujoco.MjModel, data: mujoco.MjData, parts: tuple[int, ...]) -> float:
    force = np.zeros(6)
    total = 0.0
    for i in range(data.ncon):
        contact = data.contact[i]
        b1, b2 = model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]
        if (b1 in parts) != (b2 in parts):
            mujoco.mj_contactForce(model, data, i, force)
            total += float(force[0])
    return total


def _links(model: mujoco.MjModel, data: mujoco.MjData, names: dict[int, str], obj) -> tuple[str, ...]:
    parts = set(obj.part_bodies)
    found = set()
    for i in range(data.ncon):
        contact = data.contact[i]
        b1, b2 = int(model.geom_bodyid[contact.geom1]), int(model.geom_bodyid[contact.geom2])
        if b1 in parts and b2 in names:
            found.add(names[b2])
        elif b2 in parts and b1 in names:
            found.add(names[b1])
    return tuple(sorted(found))
