"""Drive a stepper through a control schedule: the one per-frame loop body of replays and environments.

Each control frame ``k → k+1`` applies, before stepping: the scenario's switches that fall on frame ``k``
(hand–object contacts on at the scene's contact time; the objects' supports off at the release time plus
the release delay), and the root's mocap target of ``t_k+1``. The joint targets are the caller's:
:func:`handsim.sim.replay.replay` gives the schedule's, an environment its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.sim.control import ControlSchedule
from handsim.sim.scene.compiled import SimScene
from handsim.sim.stepper import Stepper, WarningEvent


@dataclass(frozen=True)
class ScenarioSwitches:
    """The frames at whose start a scenario switches something.

    Attributes:
        contact_frame: Hand–object contacts act from this frame on; before it the objects collide with
            nothing (they hang on their supports). 0: from the start.
        release_frame: The objects' supports are switched off at this frame; -1: never.
    """

    contact_frame: int = 0
    release_frame: int = -1


def scenario_switches(scene: SimScene, schedule: ControlSchedule, release_delay: float) -> ScenarioSwitches:
    """The switch frames of ``scene``'s setup on ``schedule``'s frames.

    Args:
        scene: The scene (its :class:`~handsim.sim.scene.compiled.SceneSetup` holds the times).
        schedule: The control frames.
        release_delay: Seconds after the setup's release time at which the supports go off.
    """
    setup = scene.setup
    contact = 0 if setup.contact_time is None else schedule.frame_at(setup.contact_time)
    release = -1 if setup.release_time is None else schedule.frame_at(setup.release_time + release_delay)
    return ScenarioSwitches(contact_frame=contact, release_frame=release)


@dataclass(frozen=True)
class DriveTargets:
    """What a :class:`ScheduleDriver` writes besides the controls: read by the native vector env too.

    Attributes:
        supports: Equality ids of the objects' supports (welds released at ``switches.release_frame``).
        geoms: The objects' collision geoms (switched off until ``switches.contact_frame``).
        contype: Their ``contype`` when switched on.
        conaffinity: Their ``conaffinity`` when switched on.
        mocap: Mocap body ids of the welded hand roots, in hand order.
        root_qpos: Free-joint qpos address of each welded root.
        root_pos: Recorded root positions per frame and welded hand, m (frames, hands, 3), or None.
        root_quat: Recorded root orientations (w, x, y, z) per frame and welded hand, or None.
        all_mocap: Every mocap body is a welded root, in order (whole-array copies suffice).
    """

    supports: np.ndarray
    geoms: np.ndarray
    contype: np.ndarray
    conaffinity: np.ndarray
    mocap: np.ndarray
    root_qpos: tuple[int, ...]
    root_pos: np.ndarray | None
    root_quat: np.ndarray | None
    all_mocap: bool


class ScheduleDriver:
    """Steps a :class:`~handsim.sim.stepper.Stepper` frame by frame through a schedule.

    Switching contacts changes the stepper's model: give it a private one (``Stepper(own_model=True)``,
    or an environment's own copy) when ``switches.contact_frame > 0``.

    Args:
        stepper: The stepper (its scene is the schedule's).
        schedule: The control frames.
        switches: When the scenario switches (:func:`scenario_switches`).
    """

    def __init__(self, stepper: Stepper, schedule: ControlSchedule, switches: ScenarioSwitches) -> None:
        layout = stepper.scene.layout
        self.stepper, self.schedule, self.switches = stepper, schedule, switches
        self.frame = 0
        model = stepper.model
        supports = np.array([o.support_eq for o in layout.objects if o.support_eq >= 0], dtype=np.int64)
        geoms = np.array([g for o in layout.objects for g in o.collision_geoms], dtype=np.int64)
        roots = schedule.root_poses
        welded = [h for h in layout.hands if h.mocap >= 0]
        mocap = np.array([h.mocap for h in welded], dtype=np.int64)
        self.targets = DriveTargets(
            supports=supports,
            geoms=geoms,
            contype=model.geom_contype[geoms].copy(),
            conaffinity=model.geom_conaffinity[geoms].copy(),
            mocap=mocap,
            root_qpos=tuple(h.root_free_qpos for h in welded),
            root_pos=None if roots is None else np.ascontiguousarray(roots[:, :, :3]),
            root_quat=None if roots is None else np.ascontiguousarray(roots[:, :, 3:]),
            # every mocap body is a welded root, in order: whole-array copies instead of fancy indexing
            all_mocap=bool(np.array_equal(mocap, np.arange(model.nmocap))),
        )
        self._bind()

    def _bind(self) -> None:
        """Views into the stepper's data used every frame (recreated after unpickling)."""
        self._data = self.stepper.data
        self._mocap_pos, self._mocap_quat = self._data.mocap_pos, self._data.mocap_quat

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        for name in ("_data", "_mocap_pos", "_mocap_quat"):
            del state[name]  # views into the stepper's data: recreated from the unpickled stepper
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._bind()

    def reset(self, frame: int = 0) -> None:
        """Put the scene in the recorded state of ``frame``, with the switches as they are then.

        The hand at its targets, its root at its recorded pose, recorded objects at their recorded poses
        (at frame 0 an articulated object's hinge at the scene's settled start angle, where it has one:
        :attr:`~handsim.sim.scene.compiled.SceneSetup.start_articulation`); velocities zero; warnings
        cleared.
        """
        stepper, schedule, data = self.stepper, self.schedule, self._data
        layout = stepper.scene.layout
        stepper.reset()
        data.qpos[layout.dof_qpos] = np.clip(
            schedule.ctrl[frame], layout.ctrl_range[:, 0], layout.ctrl_range[:, 1]
        )
        data.ctrl[:] = schedule.ctrl[frame]
        if self.targets.root_pos is not None:
            data.mocap_pos[self.targets.mocap] = self.targets.root_pos[frame]
            data.mocap_quat[self.targets.mocap] = self.targets.root_quat[frame]
            for h, adr in enumerate(self.targets.root_qpos):
                data.qpos[adr : adr + 7] = schedule.root_poses[frame, h]
        start = stepper.scene.setup.start_articulation
        for index, track in schedule.objects.items():
            obj = layout.objects[index]
            data.qpos[obj.free_qpos : obj.free_qpos + 7] = track.pose[frame]
            if track.articulation is not None and obj.hinge_qpos >= 0:
                settled = start[index] if frame == 0 and index < len(start) else math.nan
                angle = track.articulation[frame] if math.isnan(settled) else settled
                data.qpos[obj.hinge_qpos] = self._in_range(obj.hinge_qpos, angle)
        release = self.switches.release_frame
        data.eq_active[self.targets.supports] = 0 if 0 <= release < frame else 1
        self._set_contacts(frame >= self.switches.contact_frame)
        mujoco.mj_forward(stepper.model, data)
        self.frame = frame

    def _in_range(self, qpos_adr: int, angle: float) -> float:
        """``angle`` clamped to the range of the limited hinge at ``qpos_adr``.

        A recording may start past a hinge's stop (an ARCTIC lid fitted below its closed pose; the scene's
        notes say so).
        """
        model = self.stepper.model
        joint = int(np.flatnonzero(model.jnt_qposadr == qpos_adr)[0])
        if not model.jnt_limited[joint]:
            return float(angle)
        low, high = model.jnt_range[joint]
        return float(np.clip(angle, low, high))

    def advance(self, ctrl: npt.ArrayLike | None = None) -> tuple[WarningEvent, ...]:
        """Step from frame ``k`` to ``k+1``: the switches of ``k``, the root target of ``k+1``, then the step.

        Args:
            ctrl: Joint targets held during the frame, or None for those already in ``data.ctrl``.

        Returns:
            The frame's warnings (see :meth:`Stepper.step`).
        """
        k, targets = self.frame, self.targets
        if k == self.switches.release_frame:
            self._data.eq_active[targets.supports] = 0
        if k == self.switches.contact_frame and k > 0:
            self._set_contacts(True)
        if targets.root_pos is not None:
            if targets.all_mocap:
                self._mocap_pos[:] = targets.root_pos[k + 1]
                self._mocap_quat[:] = targets.root_quat[k + 1]
            else:
                self._mocap_pos[targets.mocap] = targets.root_pos[k + 1]
                self._mocap_quat[targets.mocap] = targets.root_quat[k + 1]
        events = self.stepper.step(ctrl)
        self.frame = k + 1
        return events

    def _set_contacts(self, on: bool) -> None:
        if self.switches.contact_frame <= 0:
            return  # contacts always on: the model is never touched
        model = self.stepper.model
        model.geom_contype[self.targets.geoms] = self.targets.contype if on else 0
        model.geom_conaffinity[self.targets.geoms] = self.targets.conaffinity if on else 0
