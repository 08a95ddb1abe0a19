"""A replay's inputs per control frame, and the raw loop that applies them: ``mj_step`` and nothing else.

Shared by ``benchmarks/replay.py`` (the raw ``mj_step`` floor a replay is compared with) and
``benchmarks/warp_gpu.py`` (the same loop on another machine, from exported arrays). Needs only MuJoCo and
NumPy, so it runs where handsim's other dependencies are not installed.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np


@dataclass(frozen=True)
class ReplayInputs:
    """What a replay sets each frame: controls, the welded roots' mocap targets, the scenario's switches.

    Attributes:
        ctrl: Actuator targets per frame (frames, nu).
        mocap: Mocap ids of the welded hand roots.
        root_pos: Their recorded positions per frame (frames, hands, 3); hands = 0 without a recorded root.
        root_quat: Their recorded orientations (w, x, y, z) per frame (frames, hands, 4).
        supports: Equality ids of the objects' supports, switched off after frame ``release``.
        geoms: The objects' collision geoms, switched on after frame ``contact``.
        contype: Their ``contype`` when on.
        conaffinity: Their ``conaffinity`` when on.
        frames: Control frames.
        substeps: MuJoCo steps per frame.
        contact: The contact frame (0: contacts on from the start).
        release: The release frame (-1: never).
    """

    ctrl: np.ndarray
    mocap: np.ndarray
    root_pos: np.ndarray
    root_quat: np.ndarray
    supports: np.ndarray
    geoms: np.ndarray
    contype: np.ndarray
    conaffinity: np.ndarray
    frames: int
    substeps: int
    contact: int
    release: int

    ARRAYS = ("ctrl", "mocap", "root_pos", "root_quat", "supports", "geoms", "contype", "conaffinity")

    @classmethod
    def from_driver(cls, driver) -> ReplayInputs:
        """The inputs of a :class:`handsim.sim.drive.ScheduleDriver`'s schedule and switches."""
        targets, schedule, switches = driver.targets, driver.schedule, driver.switches
        frames = schedule.frames
        return cls(
            ctrl=schedule.ctrl,
            mocap=targets.mocap,
            root_pos=np.zeros((frames, 0, 3)) if targets.root_pos is None else targets.root_pos,
            root_quat=np.zeros((frames, 0, 4)) if targets.root_quat is None else targets.root_quat,
            supports=targets.supports,
            geoms=targets.geoms,
            contype=targets.contype,
            conaffinity=targets.conaffinity,
            frames=frames,
            substeps=schedule.substeps,
            contact=switches.contact_frame,
            release=switches.release_frame,
        )

    @classmethod
    def from_arrays(cls, arrays: dict, info: dict) -> ReplayInputs:
        """The inputs :meth:`arrays` and :meth:`info` wrote (an exported ``.npz`` and its JSON)."""
        return cls(
            **{name: np.asarray(arrays[name]) for name in cls.ARRAYS},
            frames=int(info["frames"]),
            substeps=int(info["substeps"]),
            contact=int(info["contact_frame"]),
            release=int(info["release_frame"]),
        )

    def arrays(self) -> dict[str, np.ndarray]:
        """The per-frame arrays and ids, by name (for ``np.savez``)."""
        return {name: getattr(self, name) for name in self.ARRAYS}

    def info(self) -> dict[str, int]:
        """The frame counts and switch frames, JSON-ready."""
        return {
            "frames": self.frames,
            "substeps": self.substeps,
            "contact_frame": self.contact,
            "release_frame": self.release,
        }

    def contacts_off(self, model: mujoco.MjModel) -> mujoco.MjModel:
        """A copy of ``model`` with the objects' collisions off (before the contact frame)."""
        off = copy.deepcopy(model)
        self._set_contacts(off, False)
        return off

    def _set_contacts(self, model: mujoco.MjModel, on: bool) -> None:
        model.geom_contype[self.geoms] = self.contype if on else 0
        model.geom_conaffinity[self.geoms] = self.conaffinity if on else 0

    def run(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        qpos_out: np.ndarray | None = None,
        after_step: Callable[[], None] | None = None,
    ) -> None:
        """Replay every frame from ``data``'s state (frame 0), setting only the inputs.

        Args:
            model: A private model: the contact switch changes it in place.
            data: At the replay's start state.
            qpos_out: Filled with qpos at each frame (frames, nq), when given.
            after_step: Called after every single MuJoCo step, when given (the frame's steps are then taken
                one at a time: bitwise the same simulation).
        """
        if self.contact > 0:
            self._set_contacts(model, False)
        if qpos_out is not None:
            qpos_out[0] = data.qpos
        welded = self.root_pos.shape[1] > 0  # welded roots with a recorded pose
        for i in range(1, self.frames):
            if i - 1 == self.release:
                data.eq_active[self.supports] = 0
            if i - 1 == self.contact and self.contact > 0:
                self._set_contacts(model, True)
            if welded:
                data.mocap_pos[self.mocap] = self.root_pos[i]
                data.mocap_quat[self.mocap] = self.root_quat[i]
            data.ctrl[:] = self.ctrl[i]
            if after_step is None:
                mujoco.mj_step(model, data, nstep=self.substeps)
            else:
                for _ in range(self.substeps):
                    mujoco.mj_step(model, data)
                    after_step()
            if qpos_out is not None:
                qpos_out[i] = data.qpos
