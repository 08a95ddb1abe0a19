"""How a ``handsim/Grasp-v0`` action moves the hand: the hand's joint targets and the root's mocap target.

:class:`HandCommand` turns the hand's part of an action (a target per DoF or per finger group, as the
command itself or as its rate of change) into actuator controls; :class:`RootTarget` moves the mocap
target the hand's root is welded to (by the action's velocities, or along the scripted path). Both keep
their state in arrays of their own and no view into the simulation data, so they pickle as they are.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from handsim.envs._checks import nonnegative, positive
from handsim.sim.scene.layout import SceneLayout

ROOT_CONTROLS = ("velocity", "scripted")
ZERO_ACTIONS = ("open", "mid")
"""What a zero joint action means: the open hand of the reset, or the middle of each joint's range."""
HAND_ACTIONS = ("joints", "fingers")
"""What the hand's part of an action holds: one target per DoF, or one per finger group (:data:`FINGERS`)."""
HAND_CONTROLS = ("position", "rate")
"""How the hand's part of an action acts: it is the hand command itself, or the command's rate of change."""
DEFAULT_HAND_RATE = 2.5
"""``hand_control="rate"``: the hand command's largest change per second, action units (open to a full
flexion in 0.4 s, the scripted grasp's closing time; measured in ``docs/rl.md``)."""
FINGERS = (
    ("thumb_opposition", "th", False),
    ("thumb_flexion", "th", True),
    ("index", "if", True),
    ("middle", "mf", True),
    ("ring", "rf", True),
    ("little", "lf", True),
)
"""``hand_action="fingers"``: (action name, DoF name prefix, flexion DoFs or the others) per action element.

A finger's flexion DoFs (names with ``flex``) move together, each the same fraction of its own range
(tendon-coupled flexion, as in underactuated hands); the thumb's other DoFs (carpometacarpal abduction and
pronation, metacarpophalangeal abduction) together set its opposition. The other fingers' abduction and
pronation DoFs stay at the reset's open hand.
"""
ROOT_VELOCITIES = ("root_vx", "root_vy", "root_vz")
"""``root_control="velocity"``: the names of the action's last three elements."""
SCRIPT_DESCEND = 0.3
"""Scripted root: seconds to lower the palm onto the object."""
SCRIPT_LIFT_START = 1.0
"""Scripted root: time the lift starts, s."""
SCRIPT_LIFT_SPEED = 0.1
"""Scripted root: lift speed, m/s."""


def _choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ValueError(f"unknown {name} {value!r}; expected one of {list(choices)}")


@dataclasses.dataclass(frozen=True)
class HandConfig:
    """How the hand's part of an action acts, checked.

    Each attribute is the :class:`~handsim.envs.grasp_env.GraspEnv` keyword of the same name.

    Raises:
        ValueError: An unknown choice, or ``hand_rate`` not a finite number > 0.
    """

    zero_action: str
    hand_action: str
    hand_control: str
    hand_rate: float

    def __post_init__(self) -> None:
        _choice("zero_action", self.zero_action, ZERO_ACTIONS)
        _choice("hand_action", self.hand_action, HAND_ACTIONS)
        _choice("hand_control", self.hand_control, HAND_CONTROLS)
        object.__setattr__(self, "hand_rate", positive("hand_rate", self.hand_rate))


@dataclasses.dataclass(frozen=True)
class RootConfig:
    """How the hand's root moves, checked.

    Each attribute is the :class:`~handsim.envs.grasp_env.GraspEnv` keyword of the same name
    (``root_range`` becomes a tuple of 3 floats).

    Raises:
        ValueError: An unknown ``root_control``, a ``root_range`` that is not 3 finite numbers ≥ 0, or a
            ``root_speed`` that is not a finite number ≥ 0.
    """

    root_control: str
    root_speed: float
    root_range: tuple[float, float, float]

    def __post_init__(self) -> None:
        _choice("root_control", self.root_control, ROOT_CONTROLS)
        extent = np.asarray(self.root_range, dtype=float)
        if extent.shape != (3,) or not np.all(np.isfinite(extent)) or np.any(extent < 0):
            raise ValueError(f"root_range must be 3 finite numbers ≥ 0 (x, y, z), got {extent.tolist()}")
        object.__setattr__(self, "root_range", tuple(extent.tolist()))
        object.__setattr__(self, "root_speed", nonnegative("root_speed", self.root_speed))


def finger_coupling(dof_names: tuple[str, ...] | list[str]) -> np.ndarray:
    """The (DoFs × fingers) 0/1 matrix that spreads a ``hand_action="fingers"`` action over the DoFs.

    Args:
        dof_names: The hand's DoF names, actuator order (the default hand's ``th_…``, ``if_…`` names).

    Returns:
        Row per DoF, column per :data:`FINGERS` entry: 1 where the DoF belongs to that finger group.

    Raises:
        ValueError: A finger group has no DoF in ``dof_names`` (the hand is not the default hand).
    """
    coupling = np.zeros((len(dof_names), len(FINGERS)))
    for column, (name, prefix, flexion) in enumerate(FINGERS):
        for row, dof in enumerate(dof_names):
            if dof.startswith(prefix + "_") and ("flex" in dof) == flexion:
                coupling[row, column] = 1.0
        if not coupling[:, column].any():
            raise ValueError(f"hand_action='fingers': no DoF of {list(dof_names)} belongs to {name!r}")
    return coupling


class HandCommand:
    """The hand command and the actuator controls it gives (see :class:`~handsim.envs.grasp_env.GraspEnv`).

    Args:
        layout: The scene's layout (DoF names, control ranges).
        config: How the hand's part of an action acts.
        dt: Seconds per environment step.

    Attributes:
        names: The names of the hand's action elements (DoFs, or :data:`FINGERS` names).
        size: How many there are.
        rate: Whether the action is the command's rate of change (``hand_control="rate"``).
        command: The hand command, action units (0: the open hand); changed in place.
    """

    def __init__(self, layout: SceneLayout, config: HandConfig, dt: float) -> None:
        nu = len(layout.dof_names)
        lo, hi = layout.ctrl_range[:, 0], layout.ctrl_range[:, 1]
        if config.zero_action == "open":  # 0: the reset's open hand; ±1: the limits
            rest = np.clip(0.0, lo, hi)
            self._mid, self._up, self._down = rest, hi - rest, rest - lo
        else:
            self._mid, self._up = (lo + hi) / 2, (hi - lo) / 2
            self._down = self._up
        self._ctrl = np.zeros(nu)
        fingers = config.hand_action == "fingers"
        self._coupling = finger_coupling(layout.dof_names) if fingers else None
        self._joints = np.zeros(nu)
        self.names = tuple(name for name, _, _ in FINGERS) if fingers else tuple(layout.dof_names)
        self.size = len(self.names)
        self.rate = config.hand_control == "rate"
        self._step = config.hand_rate * dt
        self.command = np.zeros(self.size)

    def action_description(self) -> str:
        """What the hand's part of an action holds (for the message of a wrong action)."""
        kind = "joint" if self._coupling is None else "finger"
        return f"{self.size} {kind}" + (" target rates" if self.rate else " targets")

    def reset(self) -> None:
        """Back to the open hand (command 0)."""
        self.command[:] = 0.0

    def apply(self, action: np.ndarray, out: np.ndarray) -> None:
        """Update the command from the hand's part of ``action``; write the controls it gives to ``out``.

        Args:
            action: The whole action, clipped to [−1, 1] (its first :attr:`size` elements are read).
            out: The actuator controls (``data.ctrl``).
        """
        command = self.command
        if self.rate:
            command += action[: self.size] * self._step
            np.clip(command, -1.0, 1.0, out=command)
        else:
            command[:] = action[: self.size]
        joints = command
        if self._coupling is not None:
            joints = np.matmul(self._coupling, joints, out=self._joints)
        np.multiply(joints, np.where(joints >= 0.0, self._up, self._down), out=self._ctrl)
        np.add(self._ctrl, self._mid, out=out)


class RootTarget:
    """The mocap target of the hand's root: moved by velocities, or along the scripted path.

    Args:
        model: The environment's model (the target's start is its mocap body's position).
        mocap: The target's mocap index.
        floor: Lowest root height (the palm on the table top), m.
        config: How the root moves.
        dt: Seconds per environment step.
        steps: Steps per episode (the scripted path's length).
        clearance: The palm's height above the object at the start, m (the scripted descent).
        lift_height: Height the object must reach, m (the scripted lift goes 5 cm higher).

    Attributes:
        names: The names of the root's action elements (none for the scripted root).
        start: The target's start position, m.
        target: The target's position now, m; changed in place.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        mocap: int,
        floor: float,
        config: RootConfig,
        dt: float,
        steps: int,
        clearance: float,
        lift_height: float,
    ) -> None:
        extent = np.asarray(config.root_range, dtype=float)
        self._mocap = mocap
        body = int(np.flatnonzero(model.body_mocapid == mocap)[0])
        self.start = np.array(model.body_pos[body], dtype=float)
        self._lo = self.start - extent
        self._lo[2] = floor  # down to the palm on the table top
        self._hi = self.start + extent
        self._step = config.root_speed * dt
        self.target = self.start.copy()
        scripted = config.root_control == "scripted"
        self._script = self._scripted(dt, steps, clearance, lift_height) if scripted else None
        self.names = () if scripted else ROOT_VELOCITIES

    def _scripted(self, dt: float, steps: int, clearance: float, lift_height: float) -> np.ndarray:
        """Root target per step (steps + 1, 3) of the scripted root."""
        t = np.arange(steps + 1) * dt
        down = np.clip(t / SCRIPT_DESCEND, 0.0, 1.0) * clearance
        up = np.clip((t - SCRIPT_LIFT_START) * SCRIPT_LIFT_SPEED, 0.0, lift_height + 0.05)
        targets = np.tile(self.start, (t.size, 1))
        targets[:, 2] += up - down
        return targets

    def reset(self, mocap_pos: np.ndarray) -> None:
        """Back to the start; the mocap target there (``mocap_pos``: ``data.mocap_pos``)."""
        self.target[:] = self.start
        mocap_pos[self._mocap] = self.target

    def move(self, velocity: np.ndarray, step: int, mocap_pos: np.ndarray) -> None:
        """Move the target for ``step`` and put the mocap target there.

        Args:
            velocity: The root's part of the action (fractions of ``root_speed``; unread when scripted).
            step: The step the target is for (the scripted path's index).
            mocap_pos: ``data.mocap_pos``.
        """
        target = self.target
        if self._script is not None:
            target[:] = self._script[step]
        else:
            target += velocity * self._step
            np.maximum(target, self._lo, out=target)
            np.minimum(target, self._hi, out=target)
        mocap_pos[self._mocap] = target
