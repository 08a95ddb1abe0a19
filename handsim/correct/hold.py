"""The hold objective of a glove scene: the object stays where the grasp placed it, through the hold window.

A glove scene (a GraspDB14 recording's grasp episode, a scripted grasp) has no recorded object track: the
object is placed into the hand at the grasp, hangs on a support until the release, and the replay judges
whether the hand then holds it through the scene's hold window (:func:`handsim.sim.summary.hold_outcome`:
lost at the first slip beyond the slip limit relative to the hand, or a contact gap). The correction's goal
for such a scene is that hold: the object's "track" is its placed pose, counted from the release to the
window's end, so the cost of :mod:`handsim.correct.cost` measures the object's displacement from where the
grasp placed it while the hand must hold it; over the same frames it adds the opposition term
(:mod:`handsim.correct.grip`), the grip the replay's grip check asks for.

A glove scene holds the hand still (its root is fixed in the world: the glove records no wrist pose), so the
object's displacement in the world *is* its displacement relative to the hand, the quantity the hold is
judged by; only the fingers are corrected.

Planning starts where the hand can act on the object: at the first frame after hand–object contacts are
switched on (before, the object collides with nothing and no finger correction can move it; the frames
before are the recording's), and ends at the hold window's end (after it, nothing is judged: the rest is
the recording's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from handsim.correct.config import CorrectionError
from handsim.datatypes.rotations import quat_angle
from handsim.sim.control import ControlSchedule
from handsim.sim.drive import ScenarioSwitches
from handsim.sim.replay import ReplayResult
from handsim.sim.scene.compiled import SimScene

HELD, NOT_HELD, NOT_JUDGED = "held", "not held", "not judged"
"""The hold verdicts a glove correction's tracking carries (the replay's ``held`` True, False, None)."""


@dataclass(frozen=True)
class HoldGoal:
    """Where the object must stay, and when.

    Attributes:
        qpos: Address of the object's free joint in ``qpos``.
        placed: The object's pose where the grasp placed it (the model's initial pose), scene world (7,).
        valid: Control frames at which the hold is judged: the release to the window's end (F,).
        plan_start: First frame planned from (contacts act in the steps after it).
        plan_stop: Last frame whose residual is planned (the window's end).
    """

    qpos: int
    placed: np.ndarray
    valid: np.ndarray
    plan_start: int
    plan_stop: int


def is_hold_scene(scene: SimScene) -> bool:
    """Whether a scene's object is placed into the hand and its hold judged (a glove scene)."""
    setup = scene.setup
    return bool(scene.layout.objects) and setup.release_time is not None and setup.hold_window is not None


def hold_goal(
    scene: SimScene, schedule: ControlSchedule, switches: ScenarioSwitches, source: str
) -> HoldGoal:
    """The hold goal of a glove scene on its control frames.

    Raises:
        CorrectionError: The scene moves its hand (a glove scene holds it still), or its release falls on
            or after the hold window's end (nothing to hold).
    """
    layout = scene.layout
    if any(h.mocap >= 0 or h.root_free_qpos >= 0 for h in layout.hands):
        raise CorrectionError(
            f"{source}: a glove scene whose hand moves; the hold objective measures the object against a "
            "hand held still"
        )
    obj = layout.objects[0]
    frames = schedule.frames
    release = switches.release_frame
    end = schedule.frame_at(scene.setup.hold_window[1])
    if not 0 <= release < end:
        raise CorrectionError(
            f"{source}: the object is released at frame {release}, not before the hold window ends (frame "
            f"{end}): there is no hold to correct"
        )
    valid = np.zeros(frames, bool)
    valid[release : end + 1] = True
    start = switches.contact_frame + 1 if switches.contact_frame > 0 else 0
    return HoldGoal(
        qpos=obj.free_qpos,
        placed=np.array(scene.model.qpos0[obj.free_qpos : obj.free_qpos + 7], dtype=float),
        valid=valid,
        plan_start=min(start, end),
        plan_stop=end,
    )


@dataclass(frozen=True)
class HoldMeasures:
    """How the object stayed in the hand in one replay (the fields of a score's tracking).

    Attributes:
        within_1cm: Fraction of the hold's frames with the object within 1 cm of its placed position.
        mean_drift_mm: Mean displacement from the placed position over those frames, mm.
        max_drift_mm: Largest displacement, mm.
        mean_rotation_deg: Mean rotation from the placed orientation, degrees.
        track: :data:`HELD`, :data:`NOT_HELD` or :data:`NOT_JUDGED` (the replay's hold verdict).
        reason: The replay's reason (where and how the object was lost, or why the hold is not judged).
    """

    within_1cm: float
    mean_drift_mm: float
    max_drift_mm: float
    mean_rotation_deg: float
    track: str
    reason: str


def hold_measures(result: ReplayResult, goal: HoldGoal, tolerance: float) -> HoldMeasures:
    """The hold measures of a glove replay kept with its states.

    Args:
        result: The replay (``keep_states``); its ``hold`` is the verdict.
        goal: The hold goal.
        tolerance: The "within" distance, m (the correction's ``position_scale``).
    """
    states = result.states
    rows = min(states.shape[0], goal.valid.shape[0]) if states is not None else 0
    chosen = np.flatnonzero(goal.valid[:rows])
    pose = states[chosen, goal.qpos : goal.qpos + 7] if chosen.size else np.zeros((0, 7))
    distance = np.linalg.norm(pose[:, :3] - goal.placed[:3], axis=1)
    angle = quat_angle(pose[:, 3:], np.broadcast_to(goal.placed[3:], pose[:, 3:].shape))
    hold = result.hold
    held = None if hold is None else hold.held
    track = HELD if held is True else NOT_HELD if held is False else NOT_JUDGED
    if hold is None:
        reason = "the replay judges no hold"
    elif held is True:
        reason = f"held {hold.time_held:.2f} s, slip at most {hold.max_slip * 1000:.1f} mm"
    elif held is False:
        reason = f"lost at {hold.lost_at:.2f} s: {hold.reason}"
    else:
        reason = str(hold.reason)
    return HoldMeasures(
        within_1cm=float(np.mean(distance <= tolerance)) if distance.size else math.nan,
        mean_drift_mm=float(distance.mean() * 1000) if distance.size else math.nan,
        max_drift_mm=float(distance.max() * 1000) if distance.size else math.nan,
        mean_rotation_deg=float(np.degrees(angle).mean()) if angle.size else math.nan,
        track=track,
        reason=reason,
    )
