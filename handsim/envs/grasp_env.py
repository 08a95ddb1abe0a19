"""``handsim/Grasp-v0``: a hand above a catalogue object on the table; lift the object and hold it.

The hand is handsim's parametric default hand without its wrist DoFs, palm down
(:func:`handsim.sim.placement.hand_pose.hand_frame`: fingers along +x), its root welded to a mocap target
(``hand_root="weld"``): the weld replaces the arm, so the hand can carry the object up while contacts
still push back. The object rests on the table with its centre under a point
:data:`GRASP_AHEAD` ahead of the palm's centre, the palm ``hand_clearance`` above its top.

Two ways to move the root (``root_control``):

* ``"velocity"`` (default): the last 3 action elements command the root target's velocity (x, y, z, at
  most ``root_speed`` m/s each); the target is integrated every step, kept within ``root_range`` of its
  start (x, y either way, z up; down to the palm touching the table), and its orientation is held.
* ``"scripted"``: the action holds joint targets only; the root target goes down by ``hand_clearance``
  (the palm onto the object) in the first :data:`SCRIPT_DESCEND` s, waits until :data:`SCRIPT_LIFT_START`
  s and then rises at :data:`SCRIPT_LIFT_SPEED` m/s by ``lift_height`` + 5 cm: a finger-only task.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from handsim.builders import build_object, build_scene
from handsim.builders.catalog import get
from handsim.builders.hand import build_hand
from handsim.builders.objects import object_bounds
from handsim.builders.scene import resting_position
from handsim.datatypes.fingers import finger_of
from handsim.envs._base import DEFAULT_CAMERA, DEFAULT_SIZE, HandEnv
from handsim.envs._checks import nonnegative, positive, reset_options
from handsim.envs._observation import ContactSummary, ObservationLayout, add_state
from handsim.io.graspdb.default_skeleton import DEFAULT_BREADTH_RATIO, DEFAULT_HAND_LENGTH_M, default_skeleton
from handsim.sim.control import DEFAULT_CONTROL_RATE, substeps_for
from handsim.sim.placement.hand_pose import hand_frame
from handsim.sim.scene.compiled import SceneSetup, SimScene, compile_scene

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
GRASP_AHEAD = 0.03
"""The object's centre starts under the point this far ahead of the palm's centre along the fingers, m."""
CONTACT_LINKS = 3
"""``reward_contact`` is full when this many hand links touch the object."""
HOLD_SIDES = ("thumb", "fingers", "palm")
"""The sides a hand can press an object from (:func:`contact_sides`); ``reward_lift`` pays only while the
object is touched from at least two of them, so a lift is paid when the hand holds the object, not when a
stray knock sends it up."""
REACH_SCALE = 10.0
"""1/m: ``reward_reach = reach_weight · (1 − tanh(REACH_SCALE · distance))``."""
FALL_HEIGHT = -0.05
"""m: the episode terminates when the object's origin drops below this height (off the table)."""
SCRIPT_DESCEND = 0.3
"""Scripted root: seconds to lower the palm onto the object."""
SCRIPT_LIFT_START = 1.0
"""Scripted root: time the lift starts, s."""
SCRIPT_LIFT_SPEED = 0.1
"""Scripted root: lift speed, m/s."""


@dataclasses.dataclass(frozen=True)
class GraspScene:
    """A grasping scene and where things are in it.

    Attributes:
        scene: The compiled scene: the hand (root welded to a mocap target, palm down) and the object.
        grasp_offset: World offset from the hand root to the grasp point, m: under the palm where the
            object's centre sits when the object touches the palm (the root's orientation is held).
        root_floor: Lowest root height: the palm's lowest point on the table top, m.
        object_name: Catalogue name of the object.
    """

    scene: SimScene
    grasp_offset: np.ndarray
    root_floor: float
    object_name: str


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


def contact_sides(link_names: tuple[str, ...] | list[str]) -> tuple[np.ndarray, ...]:
    """Indices of the hand links on each side of :data:`HOLD_SIDES` (thumb, the other fingers, palm).

    An object touched from two of these sides is squeezed between them, so the hand can carry it; links of
    one side alone (say the index and the middle finger) only push it.

    Args:
        link_names: The hand's link names, in the order of the per-link contact forces.

    Returns:
        One index array per side, in :data:`HOLD_SIDES` order (:func:`handsim.datatypes.fingers.finger_of`
        decides each link's finger; every finger but the thumb is on the ``"fingers"`` side).
    """
    fingers = [finger_of(name) for name in link_names]
    thumb = [i for i, f in enumerate(fingers) if f == "thumb"]
    palm = [i for i, f in enumerate(fingers) if f == "palm"]
    others = [i for i, f in enumerate(fingers) if f not in ("thumb", "palm")]
    return tuple(np.array(side, dtype=np.int64) for side in (thumb, others, palm))


def held_from_two_sides(link_forces: np.ndarray, sides: tuple[np.ndarray, ...]) -> bool:
    """Whether the object is touched from at least two sides (:func:`contact_sides`).

    Args:
        link_forces: Normal force on the object per hand link, N.
        sides: The link indices of each side, from :func:`contact_sides`.

    Returns:
        True when links of two or more sides push on the object: the hand holds it.
    """
    return sum(bool(np.any(link_forces[side] > 0.0)) for side in sides) >= 2


def _wristless_default_hand() -> mujoco.MjSpec:
    """The default hand without its wrist DoFs (the mocap weld moves and turns the root instead)."""
    skeleton = default_skeleton()
    root = skeleton.joints[0].name
    skeleton = dataclasses.replace(skeleton, dofs=tuple(d for d in skeleton.dofs if d.joint != root))
    return build_hand(skeleton, breadth=DEFAULT_BREADTH_RATIO * DEFAULT_HAND_LENGTH_M)


def _palm(scene: SimScene) -> tuple[np.ndarray, float]:
    """Centre of the root's collision geoms, and the height of the palm's lowest point under it.

    Measured with the hand open at rest (every DoF at 0 rad or its nearest limit).
    """
    model, layout = scene.model, scene.layout
    data = mujoco.MjData(model)
    data.qpos[layout.dof_qpos] = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    mujoco.mj_kinematics(model, data)
    geoms = [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] == layout.root_body and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]
    centre = data.geom_xpos[geoms].mean(axis=0)
    groups = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
    groups[np.unique(model.geom_group[geoms])] = 1
    hit = np.zeros(1, dtype=np.int32)
    below = 1.0
    dist = mujoco.mj_ray(
        model, data, centre - [0.0, 0.0, below], np.array([0.0, 0.0, 1.0]), groups, 1, -1, hit
    )
    bottom = centre[2] - below + dist if dist >= 0 else centre[2]
    return centre, float(bottom)


@functools.lru_cache(maxsize=8)
def grasp_scene(object_name: str = "tennis_ball", hand_clearance: float = 0.02) -> GraspScene:
    """Build (once per process and arguments) the scene of ``handsim/Grasp-v0``.

    Args:
        object_name: A catalogue object (:func:`handsim.builders.catalog.names`).
        hand_clearance: Gap between the palm's lowest point and the object's top at the start, m.

    Returns:
        The scene and its grasp geometry.

    Raises:
        UnknownObjectError: ``object_name`` is not in the catalogue (the message lists the names).
    """
    obj = build_object(get(object_name))
    hand = _wristless_default_hand()
    quat = hand_frame(compile_scene(build_scene(hand, obj, table=False)))
    probe = compile_scene(build_scene(hand, [], hand_pos=(0.0, 0.0, 0.0), hand_quat=quat, table=False))
    centre, bottom = _palm(probe)
    lower, upper = object_bounds(obj)
    mid = (lower + upper) / 2
    rest = resting_position(obj, xy=(-mid[0], -mid[1]))
    top = rest[2] + upper[2]
    grasp_xy = centre[:2] + np.array([GRASP_AHEAD, 0.0])  # fingers point along +x
    root = np.array([-grasp_xy[0], -grasp_xy[1], top + hand_clearance - bottom])
    spec = build_scene(
        hand,
        obj,
        hand_pos=root,
        hand_quat=quat,
        object_poses=[np.concatenate([rest, [1.0, 0.0, 0.0, 0.0]])],
        table=True,
        hand_root="weld",
    )
    half_height = (upper[2] - lower[2]) / 2
    offset = np.array([grasp_xy[0], grasp_xy[1], bottom - half_height - mid[2]])
    setup = SceneSetup(
        scenario="free",
        notes=(
            f"{object_name} on the table under the palm (centre {GRASP_AHEAD * 100:g} cm ahead of the "
            f"palm's centre), the palm {hand_clearance * 1000:g} mm above its top; "
            "hand root welded to a mocap target",
        ),
    )
    return GraspScene(
        scene=compile_scene(spec, setup), grasp_offset=offset, root_floor=-bottom, object_name=object_name
    )


class GraspEnv(HandEnv):
    """Lift a catalogue object off the table and hold it (``handsim/Grasp-v0``).

    **Action** ``Box(-1, 1, (nu + 3,), float32)`` (``root_control="velocity"``) or ``(nu,)``
    (``"scripted"``): per hand DoF (actuator order, :attr:`dof_names`) a joint target; then the root
    target's velocity along world x, y, z as a fraction of ``root_speed``. Values are clipped to [−1, 1].
    ``zero_action="open"`` (default): 0 is the open hand of the reset (each DoF at 0 rad or its nearest
    limit), 0 … 1 goes linearly to the joint's upper limit and 0 … −1 to its lower one, so a policy's
    initial mean action holds the hand open; ``"mid"``: −1 … 1 mapped linearly onto the joint's range.
    ``hand_action="fingers"``: the hand's part is 6 values (:data:`FINGERS`: thumb opposition, thumb
    flexion, index, middle, ring, little), each given to every DoF of its group and mapped as above; the
    other DoFs get 0. :attr:`action_names` names the elements. ``hand_control="rate"``: the hand's part is
    the rate of change of that command instead (the **hand command**, the values above, starts at 0, the
    open hand, and moves by ``action · hand_rate · dt`` per step, kept in [−1, 1]; :attr:`hand_command`):
    a zero action holds the hand still, and exploration noise moves the fingers' targets smoothly rather
    than jolting them every step.

    **Observation** ``Box(-inf, inf, (n,), float64)``, named in :attr:`observation_names` and
    :attr:`observation_slices`: ``hand_qpos`` (nu, rad), ``root_pose`` (7), ``obj/pose`` (7: position m,
    quaternion w x y z); ``hand_qvel``, ``root_velocity`` (6), ``obj/velocity`` (6); ``root_target`` (3,
    the mocap target's position, m); ``object_to_grasp`` (3: the object's origin minus the grasp point
    under the palm, m); ``contact_force`` (per hand link, total normal force on the object, N);
    ``penetration`` (deepest, m); ``lift`` (the object's rise above its start, m); ``hold`` (time held
    so far / ``hold_time``, ≤ 1); ``progress`` (step / steps per episode); with ``hand_control="rate"``
    also ``hand_command`` (the hand command after the step's action, action units).

    **Reward** = the sum of the terms in ``info``:

    * ``reward_reach = reach_weight · (1 − tanh(10 · |object_to_grasp|))``;
    * ``reward_contact = contact_weight · min(links touching, 3) / 3``;
    * ``reward_lift = lift_weight · clip(lift / lift_height, 0, 1)`` while the hand holds the object
      (touched from two of :data:`HOLD_SIDES`: thumb, other fingers, palm), else 0;
    * ``reward_hold = hold_weight`` while the object is ``lift_height`` up and touched, else 0;
    * ``reward_penetration = −penetration_weight · penetration in mm`` (the deepest hand–object one);
    * ``reward_success = success_weight`` on the episode's last step (truncated at ``duration``, or ended
      by ``terminate_on_success``) when the object is held then (``success``), else 0: pays holding *to the
      end*, where ``reward_hold`` pays every step held (so lifting earlier earns more of it).

    **Success** (``info["success"]``, also ``info["is_success"]``): the object has been ``lift_height``
    above its start, touched by the hand, for the last ``hold_time`` seconds.

    **Episode**: the object starts at a seeded random offset (±``object_xy_noise``) on the table;
    truncated after ``duration`` seconds; terminated when MuJoCo diverges, the object falls off the table,
    or on success with ``terminate_on_success``, or (with ``max_penetration``) when the hand penetrates the
    object deeper than that: ``info["penetrated"]``.

    Args:
        object_name: Catalogue object (:func:`handsim.builders.catalog.names`).
        control_rate: Environment steps per second; rounded to whole MuJoCo steps.
        duration: Episode length, s.
        root_control: ``"velocity"`` or ``"scripted"`` (see the module).
        root_speed: Largest root target speed per axis, m/s (``"velocity"``).
        root_range: How far the root target may move from its start along x and y (either way) and up
            along z, m; down, it goes as far as the palm touching the table top.
        hand_clearance: Palm-to-object gap at the start, m.
        object_xy_noise: Half-width of the uniform random object offset at reset, m.
        lift_height: Height above its start the object must reach, m.
        hold_time: How long it must stay there, s.
        reach_weight: Weight of the reach term.
        contact_weight: Weight of the contact term.
        lift_weight: Weight of the lift term.
        hold_weight: Reward per step while holding.
        success_weight: Reward once, at the episode's last step, when the object is held then.
        penetration_weight: Penalty per millimetre of hand–object penetration.
        zero_action: What a zero joint action means, one of :data:`ZERO_ACTIONS`.
        hand_action: ``"joints"`` (a target per DoF) or ``"fingers"`` (a target per finger group,
            :data:`FINGERS`), one of :data:`HAND_ACTIONS`.
        hand_control: ``"position"`` (the action is the hand command) or ``"rate"`` (its rate of change),
            one of :data:`HAND_CONTROLS`.
        hand_rate: ``hand_control="rate"``: the command's largest change per second, action units.
        terminate_on_success: End the episode at success.
        max_penetration: None (default: never), or end the episode when the deepest hand–object
            penetration exceeds this, m: a hard constraint on physical plausibility, where the penalty
            (``penetration_weight``) only prices it.
        render_mode: None or ``"rgb_array"``.
        width: Rendered image width, pixels.
        height: Rendered image height, pixels.
        camera: Scene camera (``"hand_cam"``, ``"overview"``) or None (free camera).

    Raises:
        ValueError: A parameter is out of range.
        UnknownObjectError: ``object_name`` is not in the catalogue.
    """

    def __init__(
        self,
        object_name: str = "tennis_ball",
        *,
        control_rate: float = DEFAULT_CONTROL_RATE,
        duration: float = 3.0,
        root_control: str = "velocity",
        root_speed: float = 0.2,
        root_range: tuple[float, float, float] = (0.1, 0.1, 0.15),
        hand_clearance: float = 0.02,
        object_xy_noise: float = 0.01,
        lift_height: float = 0.05,
        hold_time: float = 0.5,
        reach_weight: float = 0.1,
        contact_weight: float = 0.1,
        lift_weight: float = 1.0,
        hold_weight: float = 1.0,
        success_weight: float = 0.0,
        penetration_weight: float = 0.2,
        zero_action: str = "open",
        hand_action: str = "joints",
        hand_control: str = "position",
        hand_rate: float = DEFAULT_HAND_RATE,
        terminate_on_success: bool = False,
        max_penetration: float | None = None,
        render_mode: str | None = None,
        width: int = DEFAULT_SIZE,
        height: int = DEFAULT_SIZE,
        camera: str | None = DEFAULT_CAMERA,
    ) -> None:
        if root_control not in ROOT_CONTROLS:
            raise ValueError(f"unknown root_control {root_control!r}; expected one of {list(ROOT_CONTROLS)}")
        if zero_action not in ZERO_ACTIONS:
            raise ValueError(f"unknown zero_action {zero_action!r}; expected one of {list(ZERO_ACTIONS)}")
        if hand_action not in HAND_ACTIONS:
            raise ValueError(f"unknown hand_action {hand_action!r}; expected one of {list(HAND_ACTIONS)}")
        if hand_control not in HAND_CONTROLS:
            raise ValueError(f"unknown hand_control {hand_control!r}; expected one of {list(HAND_CONTROLS)}")
        extent = np.asarray(root_range, dtype=float)
        if extent.shape != (3,) or not np.all(np.isfinite(extent)) or np.any(extent < 0):
            raise ValueError(f"root_range must be 3 finite numbers ≥ 0 (x, y, z), got {extent.tolist()}")
        clearance = nonnegative("hand_clearance", hand_clearance)
        built = grasp_scene(object_name, clearance)
        substeps = substeps_for(control_rate, built.scene.timestep)
        self._setup_sim(
            built.scene, substeps, render_mode=render_mode, width=width, height=height, camera=camera
        )
        self.object_name = object_name
        layout = self._scene.layout
        nu = len(layout.dof_names)
        self._steps = max(1, round(positive("duration", duration) / self.dt))
        self._lift_height = positive("lift_height", lift_height)
        self._hold_steps = max(1, math.ceil(nonnegative("hold_time", hold_time) / self.dt - 1e-9))
        self._noise = nonnegative("object_xy_noise", object_xy_noise)
        self._w_reach = nonnegative("reach_weight", reach_weight)
        self._w_contact = nonnegative("contact_weight", contact_weight) / CONTACT_LINKS
        self._w_lift = nonnegative("lift_weight", lift_weight) / self._lift_height
        self._w_hold = nonnegative("hold_weight", hold_weight)
        self._w_success = nonnegative("success_weight", success_weight)
        self._w_pen = nonnegative("penetration_weight", penetration_weight) * 1000.0  # per m
        self.zero_action = zero_action
        self._terminate_on_success = bool(terminate_on_success)
        limit = None if max_penetration is None else positive("max_penetration", max_penetration)
        self.max_penetration = limit
        self._pen_limit = math.inf if limit is None else limit
        self._scripted = root_control == "scripted"
        self.root_control = root_control
        lo, hi = layout.ctrl_range[:, 0], layout.ctrl_range[:, 1]
        if zero_action == "open":  # 0: the reset's open hand; ±1: the limits
            rest = np.clip(0.0, lo, hi)
            self._ctrl_mid, self._ctrl_up, self._ctrl_down = rest, hi - rest, rest - lo
        else:
            self._ctrl_mid, self._ctrl_up = (lo + hi) / 2, (hi - lo) / 2
            self._ctrl_down = self._ctrl_up
        self._ctrl = np.zeros(nu)
        self.hand_action = hand_action
        self._coupling = finger_coupling(layout.dof_names) if hand_action == "fingers" else None
        self._joint_action = np.zeros(nu)
        n_hand = nu if self._coupling is None else self._coupling.shape[1]
        self._n_hand = n_hand
        self.hand_control = hand_control
        self._rate = hand_control == "rate"
        self.hand_rate = positive("hand_rate", hand_rate)
        self._hand_step = self.hand_rate * self.dt
        self._command = np.zeros(n_hand)
        self.action_names = (
            tuple(layout.dof_names) if self._coupling is None else tuple(name for name, _, _ in FINGERS)
        ) + (() if root_control == "scripted" else ("root_vx", "root_vy", "root_vz"))
        self._mocap = layout.mocap
        self._obj = layout.objects[0]
        target_body = int(np.flatnonzero(self.model.body_mocapid == self._mocap)[0])
        self._root_start = np.array(self.model.body_pos[target_body], dtype=float)
        self._root_lo = self._root_start - extent
        self._root_lo[2] = built.root_floor  # down to the palm on the table top
        self._root_hi = self._root_start + extent
        self._root_step = nonnegative("root_speed", root_speed) * self.dt
        self._target = self._root_start.copy()
        self._script = self._scripted_targets(clearance) if self._scripted else None
        self._grasp_offset = np.asarray(built.grasp_offset, dtype=float)
        self._object_start_z = float(self.model.qpos0[self._obj.free_qpos + 2])

        obs = ObservationLayout()
        self._pos_slice, self._qpos_adr, self._vel_slice, self._qvel_adr = add_state(obs, self._scene)
        self._target_slice = obs.add("root_target", ("x", "y", "z"))
        self._rel_slice = obs.add("object_to_grasp", ("x", "y", "z"))
        self._contacts = ContactSummary(self._scene)
        self._force_slice = obs.add("contact_force", layout.link_names)
        self._sides = contact_sides(layout.link_names)
        self._pen_index = obs.add("penetration", ("depth",)).start
        self._lift_index = obs.add("lift", ("height",)).start
        self._hold_index = obs.add("hold", ("fraction",)).start
        self._progress_index = obs.add("progress", ("fraction",)).start
        names = self.action_names[:n_hand]
        self._command_slice = obs.add("hand_command", names) if self._rate else None
        root = obs.slices["root_pose"].start
        self._root_slice = slice(root, root + 3)
        pose = obs.slices[f"{self._obj.prefix}pose"].start
        self._object_slice = slice(pose, pose + 3)
        self.observation_names = tuple(obs.names)
        self.observation_slices = dict(obs.slices)
        self.observation_space = spaces.Box(-np.inf, np.inf, (obs.size,), np.float64)
        size = n_hand if self._scripted else n_hand + 3
        self.action_space = spaces.Box(-1.0, 1.0, (size,), np.float32)
        hand_doc = f"{nu} joint" if self._coupling is None else f"{n_hand} finger"
        hand_doc += " target rates" if self._rate else " targets"
        self._action_doc = hand_doc + ("" if self._scripted else " then 3 root velocities") + " in [-1, 1]"
        self._obs = np.zeros(obs.size)
        self._step_count = 0
        self._held = 0
        self._started = False
        self._views = (
            "_qpos",
            "_qvel",
            "_sensordata",
            "_data_ctrl",
            "_mocap_pos",
            "_obs_pos",
            "_obs_vel",
            "_obs_target",
            "_obs_rel",
            "_obs_force",
            "_obs_root",
            "_obs_object",
        )
        self._bind()

    def _scripted_targets(self, clearance: float) -> np.ndarray:
        """Root target per step (steps + 1, 3) of the scripted root."""
        t = np.arange(self._steps + 1) * self.dt
        down = np.clip(t / SCRIPT_DESCEND, 0.0, 1.0) * clearance
        up = np.clip((t - SCRIPT_LIFT_START) * SCRIPT_LIFT_SPEED, 0.0, self._lift_height + 0.05)
        targets = np.tile(self._root_start, (t.size, 1))
        targets[:, 2] += up - down
        return targets

    def _bind(self) -> None:
        data, obs = self._stepper.data, self._obs
        self._qpos, self._qvel, self._sensordata = data.qpos, data.qvel, data.sensordata
        self._data_ctrl, self._mocap_pos = data.ctrl, data.mocap_pos
        self._obs_pos, self._obs_vel = obs[self._pos_slice], obs[self._vel_slice]
        self._obs_target, self._obs_rel = obs[self._target_slice], obs[self._rel_slice]
        self._obs_force = obs[self._force_slice]
        self._obs_root, self._obs_object = obs[self._root_slice], obs[self._object_slice]

    @property
    def max_steps(self) -> int:
        """Steps per episode."""
        return self._steps

    @property
    def hand_command(self) -> np.ndarray:
        """The hand command (a copy, action units).

        The last action's hand part, or with ``hand_control="rate"`` the command its rates have moved to
        (0 after a reset).
        """
        return self._command.copy()

    # ---- gymnasium API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Open hand at its start pose above the object; the object at a seeded random offset.

        Args:
            seed: Seeds ``np_random`` (the object's offset).
            options: None or an empty dict: every episode starts the same way, so there is nothing to
                choose (an option is refused rather than ignored).

        Raises:
            TypeError: ``options`` is not a dict.
            ValueError: ``options`` holds any key.
        """
        reset_options(options, {}, type(self).__name__)
        super().reset(seed=seed)
        stepper, layout = self._stepper, self._scene.layout
        stepper.reset()
        data = stepper.data
        rest = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
        data.qpos[layout.dof_qpos] = rest
        data.ctrl[:] = rest
        if self._noise > 0:
            data.qpos[self._obj.free_qpos : self._obj.free_qpos + 2] += self.np_random.uniform(
                -self._noise, self._noise, 2
            )
        self._target[:] = self._root_start
        self._mocap_pos[self._mocap] = self._target
        self._command[:] = 0.0
        mujoco.mj_forward(self.model, data)
        self._step_count = 0
        self._held = 0
        self._started = True
        penetration, touching = self._observe()
        lift = float(self._obs[self._lift_index])
        grasped = held_from_two_sides(self._obs_force, self._sides)
        terms = self._terms(lift, penetration, touching, grasped, lifted=False, held_at_end=False)
        return self._obs.copy(), {
            **terms,
            "success": False,
            "is_success": False,
            "lift": lift,
            "links_touching": touching,
            "penetration": penetration,
        }

    def step(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Set the joint targets (and move the root target), then advance one control frame.

        Raises:
            ValueError: ``action`` has the wrong shape or a non-finite value.
            ResetNeeded: The episode is over (or was never started).
        """
        a, _, clipped = self._action(action)  # clipped to the action space
        if not self._started:
            raise gym.error.ResetNeeded("the episode is over or was never started: call reset()")
        n_hand = self._n_hand
        command = self._command
        if self._rate:
            command += a[:n_hand] * self._hand_step
            np.clip(command, -1.0, 1.0, out=command)
        else:
            command[:] = a[:n_hand]
        joints = command
        if self._coupling is not None:
            joints = np.matmul(self._coupling, joints, out=self._joint_action)
        np.multiply(joints, np.where(joints >= 0.0, self._ctrl_up, self._ctrl_down), out=self._ctrl)
        np.add(self._ctrl, self._ctrl_mid, out=self._data_ctrl)
        n = self._step_count + 1
        target = self._target
        if self._script is not None:
            target[:] = self._script[n]
        else:
            target += a[n_hand:] * self._root_step
            np.maximum(target, self._root_lo, out=target)
            np.minimum(target, self._root_hi, out=target)
        self._mocap_pos[self._mocap] = target
        events = self._stepper.step()  # the controls are in data.ctrl already
        self._step_count = n

        lift = self._object_lift()
        penetration, touching = self._observe(lift)
        lifted = lift >= self._lift_height and touching > 0
        self._held = self._held + 1 if lifted else 0
        self._obs[self._hold_index] = min(1.0, self._held / self._hold_steps)
        success = self._held >= self._hold_steps
        diverged = any(e.diverged for e in events) if events else False
        fell = float(self._obs_object[2]) < FALL_HEIGHT
        penetrated = penetration > self._pen_limit
        failed = diverged or fell or penetrated
        terminated = failed or (success and self._terminate_on_success)
        truncated = n >= self._steps and not terminated
        held_at_end = success and not failed and (terminated or truncated)
        grasped = held_from_two_sides(self._obs_force, self._sides)
        terms = self._terms(lift, penetration, touching, grasped, lifted, held_at_end)
        reward = sum(terms.values())
        if terminated or truncated:
            self._started = False
        info = {
            **terms,
            "success": success,
            "is_success": success,
            "lift": lift,
            "links_touching": touching,
            "penetration": penetration,
            "fell": fell,
            "penetrated": penetrated,
            "diverged": diverged,
            "action_clipped": clipped,
        }
        if events:
            info["warnings"] = tuple(e.describe() for e in events)
        return self._obs.copy(), reward, terminated, truncated, info

    def _terms(
        self, lift: float, penetration: float, touching: int, grasped: bool, lifted: bool, held_at_end: bool
    ) -> dict[str, float]:
        """The reward terms, by name, in the order they are summed (see the class).

        ``grasped`` (touched from two sides, :func:`held_from_two_sides`) gates ``reward_lift``: without
        it, random actions that knock the object upward would be paid for a lift the hand does not hold.
        """
        rel = self._obs_rel
        distance = math.sqrt(float(np.dot(rel, rel)))
        return {
            "reward_reach": self._w_reach * (1.0 - math.tanh(REACH_SCALE * distance)),
            "reward_contact": self._w_contact * min(touching, CONTACT_LINKS),
            "reward_lift": self._w_lift * min(max(lift, 0.0), self._lift_height) if grasped else 0.0,
            "reward_hold": self._w_hold if lifted else 0.0,
            "reward_penetration": -self._w_pen * penetration,
            "reward_success": self._w_success if held_at_end else 0.0,
        }

    def _object_lift(self) -> float:
        return float(self._qpos[self._obj.free_qpos + 2]) - self._object_start_z

    def _observe(self, lift: float | None = None) -> tuple[float, int]:
        """Fill the observation buffer (``hold`` only at reset: the step sets it).

        Returns:
            The penetration (m) and the number of hand links touching the object.
        """
        obs = self._obs
        penetration = self._observe_state()
        self._obs_target[:] = self._target
        np.subtract(self._obs_object, self._obs_root, out=self._obs_rel)
        self._obs_rel -= self._grasp_offset
        obs[self._lift_index] = self._object_lift() if lift is None else lift
        obs[self._progress_index] = self._step_count / self._steps
        if self._command_slice is not None:
            obs[self._command_slice] = self._command
        if lift is None:
            obs[self._hold_index] = 0.0
        return penetration, int(np.count_nonzero(self._obs_force))
