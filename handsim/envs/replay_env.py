"""``handsim/Replay-v0``: follow a recorded trajectory; the policy corrects the recorded joint targets.

One environment step is one control frame of :func:`handsim.sim.control.control_schedule`: the hand's
actuators hold the recorded targets of the next frame plus the policy's residual, the mocap root (a
recorded root pose) moves to the next frame's pose, and MuJoCo runs ``frame_skip`` steps in one
``mj_step`` call of :class:`~handsim.sim.stepper.Stepper` — the same stepping, targets and sensors as
:func:`handsim.sim.replay.replay`. With zero actions the environment reproduces ``replay`` bitwise.

Default scene: the bundled Tzionas et al. sequence 20 (MIT): the right hand following its recorded root
pose through a mocap weld, the 53 mm cube free on the table (:func:`default_replay_inputs`).
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Sequence
from typing import Any, NamedTuple

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from handsim.datatypes.trajectory import Trajectory
from handsim.envs._base import DEFAULT_CAMERA, DEFAULT_SIZE, HandEnv
from handsim.envs._observation import POSE_LABELS, ContactSummary, ObservationLayout, add_state
from handsim.envs.recordings import RecordingError, check_trial_options, load_recording, recording_paths
from handsim.sim.compiled import SimScene
from handsim.sim.control import DEFAULT_CONTROL_RATE, ControlSchedule, control_schedule
from handsim.sim.drive import ScheduleDriver, scenario_switches
from handsim.sim.metrics import MetricSpec

DEFAULT_SEQUENCE = ("Models", "20")
"""The bundled Tzionas sequence under :data:`handsim.assets.TZIONAS_DIR`."""
STEP_NUMBERS = (
    "reward_tracking",
    "reward_object",
    "reward_rotation",
    "reward_articulation",
    "reward_held",
    "reward_penetration",
    "reward_action",
    "tracking_error",
    "object_drift",
    "object_rotation_error",
    "penetration",
)
"""The numbers a step (and a reset) puts in ``info`` besides ``frame``, ``time``, ``diverged``,
``action_clipped`` (and the reset's ``recording``); the ``reward_*`` ones sum to the reward."""
_DRIFT = STEP_NUMBERS.index("object_drift")
_HELD_LINKS = 2
"""Hand links touching an object that make it ``held`` (a grasp needs two opposing contacts)."""
REWARD_TERMS = tuple(key for key in STEP_NUMBERS if key.startswith("reward_"))
"""The reward's terms, in the order they are summed."""


class _Track(NamedTuple):
    """A recorded object as the observation and reward read it (indices into the observation)."""

    pose: int  # the object's pose (x y z qw qx qy qz)
    position_error: int  # err_<prefix>position (3)
    rotation_error: int  # err_<prefix>rotation (3)
    ref: np.ndarray  # recorded poses (frames, 7)
    valid: np.ndarray  # (frames,) bool
    hinge: int  # the object's hinge angle, or -1
    hinge_error: int  # err_<prefix>hinge, or -1
    ref_hinge: np.ndarray | None  # recorded angles (frames,)


def rotation_error(ref: np.ndarray, q: np.ndarray, out: np.ndarray) -> float:
    """The rotation taking ``q`` to ``ref`` (``ref ⊗ q⁻¹``, world frame) as a rotation vector.

    Args:
        ref: Recorded orientation, unit quaternion w x y z.
        q: Simulated orientation, unit quaternion w x y z.
        out: Where the rotation vector goes (3,), rad; its norm is the angle in [0, π].

    Returns:
        The angle, rad.
    """
    w1, x1, y1, z1 = (float(v) for v in ref)
    w2, x2, y2, z2 = (float(v) for v in q)
    w = w1 * w2 + x1 * x2 + y1 * y2 + z1 * z2
    x = -w1 * x2 + x1 * w2 - y1 * z2 + z1 * y2
    y = -w1 * y2 + x1 * z2 + y1 * w2 - z1 * x2
    z = -w1 * z2 - x1 * y2 + y1 * x2 + z1 * w2
    if w < 0.0:  # the shorter way round
        w, x, y, z = -w, -x, -y, -z
    sine = math.sqrt(x * x + y * y + z * z)
    if sine < 1e-12:
        out[0], out[1], out[2] = 2.0 * x, 2.0 * y, 2.0 * z
        return 2.0 * sine
    angle = 2.0 * math.atan2(sine, w)
    f = angle / sine
    out[0], out[1], out[2] = f * x, f * y, f * z
    return angle


@functools.lru_cache(maxsize=1)
def default_replay_inputs() -> tuple[SimScene, Trajectory]:
    """The default scene and trajectory, built once per process (about 2 s).

    Returns:
        The bundled Tzionas sequence 20 as a recorded-object scene (:func:`~handsim.sim.scenarios.
        recorded_scene`: the hand of ``Model_Hand_R.SKEL`` and the cube) and its trajectory.
    """
    from handsim.assets import TZIONAS_DIR
    from handsim.builders import build_hand, build_object
    from handsim.io import read_skeleton
    from handsim.io.tzionas_objects import read_tzionas_object
    from handsim.io.tzionas_sequence import read_tzionas_sequence
    from handsim.sim.scenarios import recorded_scene

    folder = TZIONAS_DIR.joinpath(*DEFAULT_SEQUENCE)
    trajectory = read_tzionas_sequence(folder)
    hand = build_hand(read_skeleton(folder / "Model_Hand_R.SKEL"))
    cube = build_object(read_tzionas_object(folder / "Model_Object_Cube.SKEL"))
    return recorded_scene(hand, trajectory, {"cube": cube}), trajectory


def _nonnegative(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be a finite number ≥ 0, got {value}")
    return value


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {value}")
    return value


RecordingsArg = str | os.PathLike | Sequence[str | os.PathLike]


def _recordings(
    scene: SimScene | None, trajectory: Trajectory | RecordingsArg | None, trial_options: dict[str, Any]
) -> tuple[tuple[SimScene, Trajectory], ...]:
    """The (scene, trajectory) pairs an environment samples from, from its ``scene``/``trajectory`` keywords.

    Raises:
        RecordingError: Unknown keywords, an empty list, trial options without recording paths, or a
            scene with recording paths.
        ValueError: Only one of ``scene`` and a :class:`Trajectory` is given.
    """
    check_trial_options(trial_options, "ReplayEnv")
    if trajectory is not None and not isinstance(trajectory, Trajectory):
        if scene is not None:
            raise RecordingError(
                "give a scene with a Trajectory, or recording paths without a scene (each recording builds "
                "its own)"
            )
        return tuple(load_recording(p, **trial_options) for p in recording_paths(trajectory))
    if trial_options:
        raise RecordingError(
            f"trial options {sorted(trial_options)} need recording paths: trajectory=PATH or a list of paths"
        )
    if scene is None and trajectory is None:
        return (default_replay_inputs(),)
    if scene is None or trajectory is None:
        raise ValueError(
            "pass both scene and trajectory, or neither for the bundled Tzionas sequence 20; "
            f"got scene={'None' if scene is None else 'a scene'}, "
            f"trajectory={'None' if trajectory is None else 'a trajectory'}"
        )
    return ((scene, trajectory),)


def _layout_mismatch(recordings: Sequence, names: tuple[str, ...], other: tuple[str, ...]) -> str:
    """Why recordings cannot share one environment: their observations differ (the first difference)."""
    first = next(
        (i for i, (a, b) in enumerate(zip(names, other, strict=False)) if a != b), min(len(names), len(other))
    )
    a = names[first] if first < len(names) else "(end)"
    b = other[first] if first < len(other) else "(end)"
    return (
        f"the {len(recordings)} recordings do not share one observation layout ({len(other)} and "
        f"{len(names)} elements; element {first} is {b!r} in one and {a!r} in another): sample only "
        "recordings of the same hand and objects in one environment"
    )


class ReplayEnv(HandEnv):
    """Follow a recorded hand trajectory in a scene with free objects (``handsim/Replay-v0``).

    **Action** ``Box(-1, 1, (nu,), float32)``: a residual per hand DoF (actuator order,
    :attr:`dof_names`). The actuators get ``clip(ref + residual_scale · clip(action, -1, 1), ctrl range)``
    where ``ref`` is the recorded target of the frame the step drives towards.

    **Observation** ``Box(-inf, inf, (n,), float64)``, named element by element in
    :attr:`observation_names` and group by group in :attr:`observation_slices`:

    * ``hand_qpos`` (nu, rad), then ``root_pose`` (7: position m, quaternion w x y z; scenes whose hand
      root follows a recorded pose), then per object ``<prefix>pose`` (7) and ``<prefix>hinge`` (rad,
      articulated objects);
    * ``hand_qvel`` (nu, rad/s), ``root_velocity`` (6), per object ``<prefix>velocity`` (6: linear m/s in
      the world frame, angular rad/s in the body frame) and ``<prefix>hinge_velocity``;
    * the references of the next step: ``ref_ctrl`` (nu, the recorded targets clipped to the joint
      ranges), ``ref_root_pose`` (7), per recorded object ``ref_<prefix>pose`` (7) and
      ``ref_<prefix>hinge``; with ``reference_window=K`` the same groups for the K − 1 frames after it
      (``ref2_ctrl`` …);
    * errors to the reference of the frame reached: ``err_hand_qpos`` (nu, rad), ``err_fingertips`` (3 per
      fingertip, m), per recorded object ``err_<prefix>position`` (3, m), ``err_<prefix>rotation`` (3: the
      rotation vector of ``q_ref ⊗ q⁻¹``, rad) and ``err_<prefix>hinge`` (rad);
    * ``contact_force`` (one per hand link with collision geometry: the total contact normal force on
      every object part, N), ``penetration`` (the deepest hand–object penetration, m),
      ``contact_state`` (fraction of links touching; ``held``: 1 when at least 2 links touch);
    * ``progress``: frame index / last frame index, in [0, 1].

    **Reward** = the sum of the terms in ``info`` (errors measured at the frame reached):

    * ``reward_tracking = tracking_weight · exp(−mean((q − ref)²) / tracking_sigma²)``;
    * ``reward_object = object_weight · mean over recorded objects of exp(−d² / object_sigma²)``, d the
      distance of the object's origin from its recording (0 on frames where no track is valid);
    * ``reward_rotation = rotation_weight · mean over recorded objects of exp(−θ² / rotation_sigma²)``;
    * ``reward_articulation = articulation_weight · mean over articulated ones of exp(−e² / sigma²)``;
    * ``reward_held = held_weight · held`` in scenes without recorded object tracks (glove scenes);
    * ``reward_penetration = −penetration_weight · penetration in mm``;
    * ``reward_action = −action_weight · mean(action²)``.

    ``reset`` info carries the reset state's values of :data:`STEP_NUMBERS` too.

    **Episode**: starts at frame 0 (or a random frame with ``random_start``, or ``options={"frame": k}``),
    the hand joints moved by seeded noise with ``reset_noise_scale``;
    truncated at the schedule's last frame; terminated when MuJoCo diverges (``info["diverged"]``) or a
    recorded object ends up more than ``max_object_drift`` from its recording (``info["object_drift"]``).

    Args:
        scene: A compiled scene (:mod:`handsim.sim.scenarios`), or None with ``trajectory`` None for the
            bundled Tzionas sequence 20 (:func:`default_replay_inputs`).
        trajectory: The trajectory the scene replays; or, without a scene, a recording path or a list of
            them (any trial kind, :mod:`handsim.envs.recordings`): each episode follows one, drawn from
            the seeded ``np_random`` at reset (or ``options={"recording": i}``).
        control_rate: Control frames (environment steps) per second; rounded to whole MuJoCo steps.
        residual_scale: Largest residual, rad: a number or one per DoF.
        tracking_weight: Weight of the joint tracking term.
        tracking_sigma: Joint error scale of the tracking term, rad.
        object_weight: Weight of the object term.
        object_sigma: Distance scale of the object term, m.
        penetration_weight: Penalty per millimetre of penetration.
        action_weight: Penalty on the mean squared action.
        rotation_weight: Weight of the object rotation term.
        rotation_sigma: Angle scale of the rotation term, rad.
        articulation_weight: Weight of the articulation term.
        articulation_sigma: Angle scale of the articulation term, rad.
        held_weight: Weight of the held term (scenes without recorded object tracks).
        max_object_drift: Terminate when a recorded object is farther than this from its recording, m;
            None never terminates for it (settable later: :meth:`set_max_object_drift`).
        release_delay: Scenes with supports (glove scenario): they are switched off this long after the
            scene's ``release_time``, s (:attr:`handsim.sim.metrics.MetricSpec.release_delay`).
        random_start: Reset to a frame drawn from the environment's seeded ``np_random``.
        reference_window: How many future frames of references the observation holds (≥ 1).
        reset_noise_scale: Half-width of the uniform noise on each hand joint at reset, rad.
        render_mode: None or ``"rgb_array"``.
        width: Rendered image width, pixels.
        height: Rendered image height, pixels.
        camera: Scene camera to render from (``"hand_cam"``, ``"overview"``) or None (free camera).
        **trial_options: With recording paths: :func:`handsim.trials.find_trial`'s keywords.

    Raises:
        ValueError: A parameter is out of range, or only one of ``scene`` and ``trajectory`` is given.
        RecordingError: A bad recording keyword (unknown option, empty list, a two-hand scene, recordings
            whose observations differ).
        HandsimError: A recording cannot be found, read or built (the subclass says why).
        TrajectoryError: The trajectory does not fit the scene (see
            :func:`~handsim.sim.control.control_schedule`).
    """

    _action_doc = "one residual in [-1, 1] per hand DoF"

    def __init__(
        self,
        scene: SimScene | None = None,
        trajectory: Trajectory | None = None,
        *,
        control_rate: float = DEFAULT_CONTROL_RATE,
        residual_scale: float | npt.ArrayLike = 0.1,
        tracking_weight: float = 1.0,
        tracking_sigma: float = 0.05,
        object_weight: float = 1.0,
        object_sigma: float = 0.01,
        penetration_weight: float = 0.1,
        action_weight: float = 0.01,
        rotation_weight: float = 0.5,
        rotation_sigma: float = 0.2,
        articulation_weight: float = 0.5,
        articulation_sigma: float = 0.1,
        held_weight: float = 0.5,
        max_object_drift: float | None = 0.1,
        release_delay: float = MetricSpec.release_delay,
        random_start: bool = False,
        reference_window: int = 1,
        reset_noise_scale: float = 0.0,
        render_mode: str | None = None,
        width: int = DEFAULT_SIZE,
        height: int = DEFAULT_SIZE,
        camera: str | None = DEFAULT_CAMERA,
        **trial_options: Any,
    ) -> None:
        recordings = _recordings(scene, trajectory, trial_options)
        self._control_rate = float(control_rate)
        self._render_args = {"render_mode": render_mode, "width": width, "height": height, "camera": camera}
        self._w_track = _nonnegative("tracking_weight", tracking_weight)
        self._inv_sigma2_track = 1.0 / _positive("tracking_sigma", tracking_sigma) ** 2
        self._w_object = _nonnegative("object_weight", object_weight)
        self._inv_sigma2_object = 1.0 / _positive("object_sigma", object_sigma) ** 2
        self._w_pen = _nonnegative("penetration_weight", penetration_weight) * 1000.0  # per m
        self._w_rot = _nonnegative("rotation_weight", rotation_weight)
        self._inv_sigma2_rot = 1.0 / _positive("rotation_sigma", rotation_sigma) ** 2
        self._w_art = _nonnegative("articulation_weight", articulation_weight)
        self._inv_sigma2_art = 1.0 / _positive("articulation_sigma", articulation_sigma) ** 2
        self._w_held = _nonnegative("held_weight", held_weight)
        self.max_object_drift = max_object_drift
        if (
            isinstance(reference_window, bool)
            or int(reference_window) != reference_window
            or reference_window < 1
        ):
            raise ValueError(f"reference_window must be a whole number ≥ 1, got {reference_window!r}")
        self._window = int(reference_window)
        self._noise = _nonnegative("reset_noise_scale", reset_noise_scale)
        self._random_start = bool(random_start)
        self._action_weight = _nonnegative("action_weight", action_weight)
        self._residual_scale = residual_scale
        self._release_delay = _nonnegative("release_delay", release_delay)
        self._recordings = recordings
        self._recording = -1
        names = None
        # every recording is configured once here: its errors surface now, and all must observe alike
        for index in reversed(range(len(recordings))):
            self._configure(index)
            if names is not None and names != self.observation_names:
                raise RecordingError(_layout_mismatch(recordings, names, self.observation_names))
            names = self.observation_names

    def _configure(self, index: int) -> None:
        """Build the simulation, references and observation layout of recording ``index``."""
        if index == self._recording:
            return
        if self._recording >= 0:
            self.close()
        scene, trajectory = self._recordings[index]
        schedule = control_schedule(scene, trajectory, self._control_rate)
        if schedule.frames < 2:
            raise ValueError(f"the trajectory gives {schedule.frames} control frame; an episode needs ≥ 2")
        self._setup_sim(scene, schedule.substeps, **self._render_args)
        self._recording = index
        self._schedule = schedule
        layout = self._scene.layout
        nu = len(layout.dof_names)
        self._w_action = self._action_weight / max(nu, 1)
        residual_scale = self._residual_scale
        scale = np.asarray(residual_scale, dtype=float)
        if scale.shape not in ((), (nu,)) or not np.all(np.isfinite(scale)) or np.any(scale < 0):
            raise ValueError(
                f"residual_scale must be a number ≥ 0 or {nu} of them (one per DoF), got {scale.tolist()}"
            )
        self._scale = np.broadcast_to(scale, (nu,)).copy()

        # per frame: the recorded targets, and the bounds that clip(ref + residual) stays within
        lo, hi = layout.ctrl_range[:, 0], layout.ctrl_range[:, 1]
        ctrl = np.ascontiguousarray(schedule.ctrl, dtype=float)
        self._ref_ctrl = np.clip(ctrl, lo, hi)
        self._ctrl_lo = np.clip(ctrl - self._scale, lo, hi)
        self._ctrl_hi = np.clip(ctrl + self._scale, lo, hi)
        self._ctrl_ref = ctrl
        self._last = schedule.frames - 1
        self._times = schedule.times
        root = schedule.root_pose
        switches = scenario_switches(self._scene, schedule, self._release_delay)
        self._driver = ScheduleDriver(self._stepper, schedule, switches)

        obs = ObservationLayout()
        self._pos_slice, self._qpos_adr, self._vel_slice, self._qvel_adr = add_state(obs, self._scene)
        groups: list[tuple[str, tuple[str, ...]]] = [("ctrl", layout.dof_names)]
        refs = [self._ref_ctrl]
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
        for j in range(1, self._window + 1):
            for group, labels in groups:
                obs.add(f"ref_{group}" if j == 1 else f"ref{j}_{group}", labels)
        self._ref_slice = slice(first, obs.size)
        self._window_steps = np.arange(1, self._window + 1)
        # a track without any valid sample may hold NaN: observed as 0 (its reward term skips those frames)
        self._refs = np.nan_to_num(np.hstack(refs).astype(float), nan=0.0, posinf=0.0, neginf=0.0)
        self._err_hand = obs.add("err_hand_qpos", layout.dof_names)
        # fingertips: recorded positions by forward kinematics of each frame's recorded state
        self._tip_sensors = (np.asarray(layout.tip_adr, dtype=np.int64)[:, None] + np.arange(3)).ravel()
        self._ref_tips = self._recorded_tips(layout.tip_sites)
        tip_labels = [f"{name}/{axis}" for name in layout.tip_names for axis in "xyz"]
        self._err_tips = obs.add("err_fingertips", tip_labels)
        self._tracks = []  # per recorded object: what _features and _reward read, see _Track
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
            self._tracks.append(
                _Track(pose, position, rotation, ref, valid, hinge_index, err_hinge, ref_hinge)
            )
        self._contacts = ContactSummary(self._scene)
        self._force_slice = obs.add("contact_force", layout.link_names)
        self._pen_index = obs.add("penetration", ("depth",)).start
        self._contact_index = obs.add("contact_state", ("touching_links", "held")).start
        self._progress_index = obs.add("progress", ("fraction",)).start
        self._hand_slice = obs.slices["hand_qpos"]
        self._hold_term = not self._tracks  # scenes without recorded objects: the held term
        self.observation_names = tuple(obs.names)
        self.observation_slices = dict(obs.slices)
        self.observation_space = spaces.Box(-np.inf, np.inf, (obs.size,), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (nu,), np.float32)
        self._obs = np.zeros(obs.size)
        self._started = False
        self._views = (
            "_qpos",
            "_qvel",
            "_sensordata",
            "_data_ctrl",
            "_obs_pos",
            "_obs_vel",
            "_obs_refs",
            "_obs_force",
        )
        self._bind()

    def _recorded_tips(self, sites: np.ndarray) -> np.ndarray:
        """World positions of the fingertip sites in each frame's recorded state (frames, tips · 3), m."""
        data = self._stepper.data
        tips = np.empty((self._schedule.frames, 3 * len(sites)))
        for frame in range(self._schedule.frames):
            self._driver.reset(frame)  # hand at its targets, root at its recorded pose (mj_forward)
            tips[frame] = data.site_xpos[sites].ravel()
        return tips

    def _bind(self) -> None:
        data, obs = self._stepper.data, self._obs
        self._qpos, self._qvel, self._sensordata = data.qpos, data.qvel, data.sensordata
        self._data_ctrl = data.ctrl
        self._obs_pos, self._obs_vel = obs[self._pos_slice], obs[self._vel_slice]
        self._obs_refs, self._obs_force = obs[self._ref_slice], obs[self._force_slice]

    # ---- public facts -----------------------------------------------------------------------------------
    @property
    def schedule(self) -> ControlSchedule:
        """The control frames the episode follows."""
        return self._schedule

    @property
    def max_object_drift(self) -> float | None:
        """The drift that terminates an episode, m (None: never); settable between episodes.

        A curriculum: ``vec_env.env_method("set_max_object_drift", d)`` in Stable-Baselines3, or
        :meth:`ReplayVectorEnv.set_max_object_drift`.
        """
        return None if math.isinf(self._max_drift) else self._max_drift

    @max_object_drift.setter
    def max_object_drift(self, value: float | None) -> None:
        self._max_drift = math.inf if value is None else _positive("max_object_drift", value)

    def set_max_object_drift(self, value: float | None) -> None:
        """Set :attr:`max_object_drift` (a method, for ``env_method`` calls of vectorised training)."""
        self.max_object_drift = value

    @property
    def recording(self) -> int:
        """Index of the recording the episode follows (in the order given; 0 with one)."""
        return self._recording

    @property
    def recordings(self) -> int:
        """How many recordings the environment samples from."""
        return len(self._recordings)

    @property
    def frame(self) -> int:
        """Index of the control frame the simulation is at."""
        return self._driver.frame

    # ---- gymnasium API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Put the scene at its recorded state of frame 0 (or of ``options["frame"]``, or a random frame).

        Raises:
            ValueError: ``options["frame"]`` is not a frame before the last.
        """
        super().reset(seed=seed)
        options = options or {}
        count = len(self._recordings)
        if "recording" in options:
            index = int(options["recording"])
            if not 0 <= index < count:
                raise ValueError(f"options['recording'] must be in [0, {count - 1}], got {index}")
        else:
            index = int(self.np_random.integers(0, count)) if count > 1 else 0
        self._configure(index)
        if "frame" in options:
            start = int(options["frame"])
            if not 0 <= start < self._last:
                raise ValueError(f"options['frame'] must be a frame in [0, {self._last - 1}], got {start}")
        elif self._random_start:
            start = int(self.np_random.integers(0, self._last))
        else:
            start = 0
        self._driver.reset(start)
        if self._noise > 0.0:
            self._perturb()
        self._started = True
        penetration = self._observe()
        _, numbers = self._reward(self._obs, start, 0.0, penetration)
        info = {"frame": start, "time": float(self._times[start]), "recording": index}
        info.update(zip(STEP_NUMBERS, numbers, strict=True))
        return self._obs.copy(), info

    def _perturb(self) -> None:
        """Reset noise: each hand joint moved by U(−s, s) rad (within its range), from ``np_random``."""
        layout = self._scene.layout
        data = self._stepper.data
        noise = self.np_random.uniform(-self._noise, self._noise, len(layout.dof_names))
        q = data.qpos[layout.dof_qpos] + noise
        data.qpos[layout.dof_qpos] = np.clip(q, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
        mujoco.mj_forward(self.model, data)

    def step(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control frame with the recorded targets plus the residual ``action``.

        Raises:
            ValueError: ``action`` has the wrong shape or a non-finite value.
            ResetNeeded: The episode is over (or was never started).
        """
        a, squares, clipped = self._action(action)
        k = self._driver.frame
        if k >= self._last or not self._started:
            raise gym.error.ResetNeeded(
                "the episode is over (last frame reached or terminated): call reset()"
                if self._started
                else "call reset() before step()"
            )
        n = k + 1
        self._controls(a, n, self._data_ctrl)
        events = self._driver.advance()  # the controls are in data.ctrl already
        penetration = self._observe()
        reward, numbers = self._reward(self._obs, n, squares, penetration)
        drift = numbers[_DRIFT]
        diverged = any(e.diverged for e in events) if events else False
        terminated = diverged or drift > self._max_drift
        truncated = n >= self._last and not terminated
        if terminated:
            self._started = False
        info = {"frame": n, "time": float(self._times[n])}
        info.update(zip(STEP_NUMBERS, numbers, strict=True))
        info["diverged"] = diverged
        info["action_clipped"] = clipped
        if events:
            info["warnings"] = tuple(e.describe() for e in events)
        return self._obs.copy(), reward, terminated, truncated, info

    def _controls(self, action: np.ndarray, frame: int | np.ndarray, out: np.ndarray) -> None:
        """The actuator controls towards ``frame``: ``clip(ref + residual_scale · action, ctrl range)``.

        Elementwise, so one world (``action`` (nu,), ``frame`` an int) and many (``action`` (worlds, nu),
        ``frame`` (worlds,)) give bitwise the same controls.

        Args:
            action: Actions already clipped to the action space.
            frame: The frame each world steps towards.
            out: Where the controls go (``data.ctrl``, or a batch's controls).
        """
        np.multiply(action, self._scale, out=out)
        out += self._ctrl_ref[frame]
        np.maximum(out, self._ctrl_lo[frame], out=out)
        np.minimum(out, self._ctrl_hi[frame], out=out)

    def _features(self, obs: np.ndarray, frame: int, sensordata: np.ndarray) -> None:
        """Fill the reference window, the errors to the reference and the contact state of one world.

        Reads the world's state and contact forces already in ``obs``; the single environment and the
        vector environment both call it, world by world, so their observations are bitwise equal.

        Args:
            obs: The world's observation (obs_size,), changed in place.
            frame: The frame the world is at.
            sensordata: The world's sensor values (the fingertip positions MuJoCo's position sensors
                took in the last ``mj_step``, i.e. at the start of its last substep).
        """
        obs[self._ref_slice] = self._refs[np.minimum(frame + self._window_steps, self._last)].ravel()
        np.subtract(self._ref_ctrl[frame], obs[self._hand_slice], out=obs[self._err_hand])
        np.subtract(self._ref_tips[frame], sensordata[self._tip_sensors], out=obs[self._err_tips])
        for t in self._tracks:
            if t.valid[frame]:
                ref = t.ref[frame]
                np.subtract(
                    ref[:3], obs[t.pose : t.pose + 3], out=obs[t.position_error : t.position_error + 3]
                )
                rotation_error(
                    ref[3:], obs[t.pose + 3 : t.pose + 7], obs[t.rotation_error : t.rotation_error + 3]
                )
                if t.hinge_error >= 0:
                    obs[t.hinge_error] = t.ref_hinge[frame] - obs[t.hinge]
            else:
                obs[t.position_error : t.rotation_error + 3] = 0.0
                if t.hinge_error >= 0:
                    obs[t.hinge_error] = 0.0
        touching = int(np.count_nonzero(obs[self._force_slice] > 0.0))
        links = self._contacts.links
        obs[self._contact_index] = touching / links if links else 0.0
        obs[self._contact_index + 1] = 1.0 if touching >= _HELD_LINKS else 0.0

    def _reward(self, obs: np.ndarray, frame: int, squares: float, penetration: float) -> tuple[float, tuple]:
        """The reward of one world that reached ``frame`` with observation ``obs`` (features filled).

        Args:
            obs: The world's observation (obs_size,).
            frame: The frame reached.
            squares: Sum of squares of the (clipped) action.
            penetration: Deepest hand–object penetration, m.

        Returns:
            The reward (its terms summed in :data:`REWARD_TERMS` order) and the values of
            :data:`STEP_NUMBERS`.
        """
        err = obs[self._err_hand]
        mean_sq = float(np.dot(err, err)) / err.size if err.size else 0.0
        r_track = self._w_track * math.exp(-mean_sq * self._inv_sigma2_track)
        r_object = r_rot = r_art = drift = turn = 0.0
        tracked = hinged = 0
        for t in self._tracks:
            if not t.valid[frame]:
                continue
            delta = obs[t.position_error : t.position_error + 3]
            d2 = float(np.dot(delta, delta))
            r_object += math.exp(-d2 * self._inv_sigma2_object)
            drift = max(drift, math.sqrt(d2))
            rot = obs[t.rotation_error : t.rotation_error + 3]
            a2 = float(np.dot(rot, rot))
            r_rot += math.exp(-a2 * self._inv_sigma2_rot)
            turn = max(turn, math.sqrt(a2))
            tracked += 1
            if t.hinge_error >= 0:
                e = float(obs[t.hinge_error])
                r_art += math.exp(-e * e * self._inv_sigma2_art)
                hinged += 1
        if tracked:
            r_object *= self._w_object / tracked
            r_rot *= self._w_rot / tracked
        if hinged:
            r_art *= self._w_art / hinged
        r_held = self._w_held * float(obs[self._contact_index + 1]) if self._hold_term else 0.0
        r_pen = -self._w_pen * penetration
        r_action = -self._w_action * squares
        reward = r_track + r_object + r_rot + r_art + r_held + r_pen + r_action
        numbers = (r_track, r_object, r_rot, r_art, r_held, r_pen, r_action, math.sqrt(mean_sq), drift, turn)
        return reward, (*numbers, penetration)

    def _observe(self) -> float:
        """Fill the observation buffer from the state; returns the penetration, m."""
        obs = self._obs
        penetration = self._observe_state()
        frame = self._driver.frame
        self._features(obs, frame, self._sensordata)
        obs[self._progress_index] = frame / self._last
        return penetration
