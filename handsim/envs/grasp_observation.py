"""What a ``handsim/Grasp-v0`` world observes: its state, the root target, the object to the grasp point.

:class:`GraspObservation` lays out the observation (named element by element) and fills the part that
is not a plain gather of the state (:meth:`~handsim.envs._base.HandEnv._observe_state` gathers that).
"""

from __future__ import annotations

import numpy as np

from handsim.envs._observation import ContactSummary, ObservationLayout, add_state
from handsim.sim.scene.compiled import SimScene


class GraspObservation:
    """The observation of a grasping scene: its layout and the features filled per step.

    The groups, in order (see :class:`~handsim.envs.grasp_env.GraspEnv` for their units): the state
    (:func:`~handsim.envs._observation.add_state`), ``root_target``, ``object_to_grasp``,
    ``contact_force``, ``penetration``, ``lift``, ``hold``, ``progress`` and, when the hand's action is
    a rate, ``hand_command``.

    Args:
        scene: The environment's scene (one hand with a welded root, one free object).
        command_names: The hand command's element names for the ``hand_command`` group, or None for none.

    Attributes:
        names, slices, size: The layout: a name per element (``<group>/<label>``), the slice of each group
            and the number of elements.
        pos_slice, qpos_adr, vel_slice, qvel_adr, contacts, force_slice, pen_index: Where the state goes
            (:class:`~handsim.envs._base.ObservedState`).
        rel_slice: The slice of ``object_to_grasp``.
        hold_index: The index of ``hold`` (the environment sets it: the task counts the steps held).
    """

    def __init__(self, scene: SimScene, command_names: tuple[str, ...] | None) -> None:
        layout = scene.layout
        obs = ObservationLayout()
        self.pos_slice, self.qpos_adr, self.vel_slice, self.qvel_adr = add_state(obs, scene)
        self._target = obs.add("root_target", ("x", "y", "z"))
        self.rel_slice = obs.add("object_to_grasp", ("x", "y", "z"))
        self.contacts = ContactSummary(scene)
        self.force_slice = obs.add("contact_force", layout.link_names)
        self.pen_index = obs.add("penetration", ("depth",)).start
        self._lift = obs.add("lift", ("height",)).start
        self.hold_index = obs.add("hold", ("fraction",)).start
        self._progress = obs.add("progress", ("fraction",)).start
        self._command = None if command_names is None else obs.add("hand_command", command_names)
        root = obs.slices["root_pose"].start
        self._root = slice(root, root + 3)
        pose = obs.slices[f"{layout.objects[0].prefix}pose"].start
        self._object = slice(pose, pose + 3)
        self.names = tuple(obs.names)
        self.slices = dict(obs.slices)
        self.size = obs.size

    def features(
        self,
        obs: np.ndarray,
        target: np.ndarray,
        grasp_offset: np.ndarray,
        lift: float,
        progress: float,
        command: np.ndarray,
    ) -> int:
        """Fill the root target, the object to the grasp point, the lift, the progress and the command.

        Reads the state and contact forces already in ``obs``.

        Args:
            obs: The observation, changed in place.
            target: The root's mocap target, m.
            grasp_offset: World offset from the hand root to the grasp point, m.
            lift: The object's rise above its start, m.
            progress: Step / steps per episode.
            command: The hand command (observed when the layout has ``hand_command``).

        Returns:
            The number of hand links touching the object.
        """
        obs[self._target] = target
        rel = obs[self.rel_slice]
        np.subtract(obs[self._object], obs[self._root], out=rel)
        rel -= grasp_offset
        obs[self._lift] = lift
        obs[self._progress] = progress
        if self._command is not None:
            obs[self._command] = command
        return int(np.count_nonzero(obs[self.force_slice]))
