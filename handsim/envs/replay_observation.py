"""What a ``handsim/Replay-v0`` world observes: its state, the recorded references, the errors to them.

:class:`ReplayObservation` lays out one recording's observation (named element by element) and fills the
part that is not a plain gather of the state: the reference window, the errors to the reference of the
frame reached and the contact state. :class:`~handsim.envs.replay_env.ReplayEnv` and
:class:`~handsim.envs.replay_vector_env.ReplayVectorEnv` both call :meth:`ReplayObservation.features`, world
by world, so their observations are bitwise equal.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from handsim.datatypes.rotations import quat_error_rotvec
from handsim.envs._observation import POSE_LABELS, ContactSummary, ObservationLayout, add_state
from handsim.sim.control import ControlSchedule
from handsim.sim.drive import ScheduleDriver
from handsim.sim.scene.compiled import SimScene

HELD_LINKS = 2
"""Hand links touching an object that make it ``held`` (a grasp needs two opposing contacts)."""


class ObjectTrack(NamedTuple):
    """A recorded object as the observation and reward read it (indices into the observation)."""

    pose: int  # the object's pose (x y z qw qx qy qz)
    position_error: int  # err_<prefix>position (3)
    rotation_error: int  # err_<prefix>rotation (3)
    ref: np.ndarray  # recorded poses (frames, 7)
    valid: np.ndarray  # (frames,) bool
    hinge: int  # the object's hinge angle, or -1
    hinge_error: int  # err_<prefix>hinge, or -1
    ref_hinge: np.ndarray | None  # recorded angles (frames,)


class ReplayObservation:
    """The observation of one recording: its layout, its references and the features filled per step.

    The groups, in order (see :class:`~handsim.envs.replay_env.ReplayEnv` for their units): the state
    (:func:`~handsim.envs._observation.add_state`), the reference window (``ref_…``, ``ref2_…`` …),
    ``err_hand_qpos``, ``err_fingertips``, per recorded object ``err_<prefix>position``,
    ``err_<prefix>rotation`` and ``err_<prefix>hinge``, ``contact_force``, ``penetration``,
    ``contact_state`` and ``progress``.

    Building it resets ``driver`` to every frame once (the recorded fingertip positions): reset the
    scene before stepping.

    Args:
        scene: The environment's scene.
        schedule: The control frames the recording gives.
        driver: The schedule's driver on the environment's stepper.
        ref_ctrl: The recorded targets clipped to the joint ranges (frames, nu), rad.
        window: How many future frames of references the observation holds (≥ 1).

    Attributes:
        names: One name per element, ``<group>/<label>``.
        slices: The slice of each group.
        size: Number of elements.
        pos_slice, qpos_adr, vel_slice, qvel_adr, contacts, force_slice, pen_index: Where the state goes
            (:class:`~handsim.envs._base.ObservedState`).
        ref_tips: The fingertip sites' world positions in each frame's recorded state (frames, tips · 3), m.
        tracks: The recorded objects (:class:`ObjectTrack`).
        contact_index: The index of ``contact_state/touching_links`` (``held`` follows it).
        progress_index: The progress's index.
        err_hand: The slice of ``err_hand_qpos``.
        last: The last frame's index.
    """

    def __init__(
        self,
        scene: SimScene,
        schedule: ControlSchedule,
        driver: ScheduleDriver,
        ref_ctrl: np.ndarray,
        window: int,
    ) -> None:
        layout = scene.layout
        self.last = schedule.frames - 1
        self._ref_ctrl = ref_ctrl
        root = schedule.root_pose
        obs = ObservationLayout()
        self.pos_slice, self.qpos_adr, self.vel_slice, self.qvel_adr = add_state(obs, scene)
        groups: list[tuple[str, tuple[str, ...]]] = [("ctrl", layout.dof_names)]
        refs = [ref_ctrl]
        if root is not None:
            groups.append(("root_pose", POSE_LABELS))
            refs.append(root)
        tracks = []
        for index, track in sorted(schedule.objects.items()):
            obj = layout.objects[index]
            groups.append((f"{obj.prefix}pose", POSE_LABELS))
            refs.append(track.pose)
            hinge = track.articulation is not None and obj.hinge_qpos >= 0
            if hinge:
                groups.append((f"{obj.prefix}hinge", ("angle",)))
                refs.append(np.asarray(track.articulation, dtype=float)[:, None])
            valid = np.ones(schedule.frames, bool) if track.valid is None else np.asarray(track.valid, bool)
            tracks.append((obj, track, hinge, valid))
        # the window: references of the next K frames, frame-major ("ref_" the next, "ref2_" the one after)
        first = obs.size
        for j in range(1, window + 1):
            for group, labels in groups:
                obs.add(f"ref_{group}" if j == 1 else f"ref{j}_{group}", labels)
        self._ref_slice = slice(first, obs.size)
        self._window = window
        self._window_steps = np.arange(1, window + 1)
        # a track without any valid sample may hold NaN: observed as 0 (its reward term skips those frames)
        self._refs = np.nan_to_num(np.hstack(refs).astype(float), nan=0.0, posinf=0.0, neginf=0.0)
        self.err_hand = obs.add("err_hand_qpos", layout.dof_names)
        # fingertips: recorded positions by forward kinematics of each frame's recorded state
        self._tip_sensors = (np.asarray(layout.tip_adr, dtype=np.int64)[:, None] + np.arange(3)).ravel()
        self.ref_tips = _recorded_tips(driver, schedule.frames, layout.tip_sites)
        tip_labels = [f"{name}/{axis}" for name in layout.tip_names for axis in "xyz"]
        self._err_tips = obs.add("err_fingertips", tip_labels)
        self.tracks: list[ObjectTrack] = []  # per recorded object: what features and the reward read
        for obj, track, hinge, valid in tracks:
            pose = obs.slices[f"{obj.prefix}pose"].start
            position = obs.add(f"err_{obj.prefix}position", ("x", "y", "z")).start
            rotation = obs.add(f"err_{obj.prefix}rotation", ("rx", "ry", "rz")).start
            ref = np.nan_to_num(np.asarray(track.pose, dtype=float), nan=0.0)
            hinge_index = err_hinge = -1
            ref_hinge = None
            if hinge:
                hinge_index = obs.slices[f"{obj.prefix}hinge"].start
                err_hinge = obs.add(f"err_{obj.prefix}hinge", ("angle",)).start
                ref_hinge = np.nan_to_num(np.asarray(track.articulation, dtype=float), nan=0.0)
            self.tracks.append(
                ObjectTrack(pose, position, rotation, ref, valid, hinge_index, err_hinge, ref_hinge)
            )
        self.contacts = ContactSummary(scene)
        self.force_slice = obs.add("contact_force", layout.link_names)
        self.pen_index = obs.add("penetration", ("depth",)).start
        self.contact_index = obs.add("contact_state", ("touching_links", "held")).start
        self.progress_index = obs.add("progress", ("fraction",)).start
        self._hand_slice = obs.slices["hand_qpos"]
        self.names = tuple(obs.names)
        self.slices = dict(obs.slices)
        self.size = obs.size

    def features(self, obs: np.ndarray, frame: int, sensordata: np.ndarray) -> None:
        """Fill the reference window, the errors to the reference and the contact state of one world.

        Reads the world's state and contact forces already in ``obs``; the single environment and the
        vector environment both call it, world by world, so their observations are bitwise equal.

        Args:
            obs: The world's observation (obs_size,), changed in place.
            frame: The frame the world is at.
            sensordata: The world's sensor values (the fingertip positions MuJoCo's position sensors
                took in the last ``mj_step``, i.e. at the start of its last substep).
        """
        after = frame + 1
        if after + self._window <= self.last + 1:  # the next K frames: a view, no index array
            obs[self._ref_slice] = self._refs[after : after + self._window].ravel()
        else:  # the window runs past the last frame: the last frame repeats
            obs[self._ref_slice] = self._refs[np.minimum(frame + self._window_steps, self.last)].ravel()
        np.subtract(self._ref_ctrl[frame], obs[self._hand_slice], out=obs[self.err_hand])
        np.subtract(self.ref_tips[frame], sensordata[self._tip_sensors], out=obs[self._err_tips])
        for t in self.tracks:
            if t.valid[frame]:
                ref = t.ref[frame]
                np.subtract(
                    ref[:3], obs[t.pose : t.pose + 3], out=obs[t.position_error : t.position_error + 3]
                )
                quat_error_rotvec(
                    ref[3:], obs[t.pose + 3 : t.pose + 7], obs[t.rotation_error : t.rotation_error + 3]
                )
                if t.hinge_error >= 0:
                    obs[t.hinge_error] = t.ref_hinge[frame] - obs[t.hinge]
            else:
                obs[t.position_error : t.rotation_error + 3] = 0.0
                if t.hinge_error >= 0:
                    obs[t.hinge_error] = 0.0
        touching = int(np.count_nonzero(obs[self.force_slice] > 0.0))
        links = self.contacts.links
        obs[self.contact_index] = touching / links if links else 0.0
        obs[self.contact_index + 1] = 1.0 if touching >= HELD_LINKS else 0.0


def _recorded_tips(driver: ScheduleDriver, frames: int, sites: np.ndarray) -> np.ndarray:
    """World positions of the fingertip sites in each frame's recorded state (frames, tips · 3), m."""
    data = driver.stepper.data
    tips = np.empty((frames, 3 * len(sites)))
    for frame in range(frames):
        driver.reset(frame)  # hand at its targets, root at its recorded pose (mj_forward)
        tips[frame] = data.site_xpos[sites].ravel()
    return tips
