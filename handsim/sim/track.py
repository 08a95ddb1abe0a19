"""The verdict on a recorded object's track: *followed*, *lost at t* (and where it went), or *not judged*.

A recorded-object trial (ARCTIC, Tzionas) replays hands that should carry, push and open the objects the
way the recording did. Its drift numbers say how far the objects strayed; this module says what that means:

* **Manipulated frames** come from the recording alone: the frames in which the recorded object has moved
  from its first pose by more than the follow tolerance (:class:`~handsim.sim.specs.TrackSpec`: position,
  rotation or hinge angle). In these frames an object left where it was would be off its recording, so
  only the hands can have put it there; frames before the recording moves it judge nothing.
* **Followed**: in every manipulated frame the simulated object is within the tolerance of its recording
  (the same tolerance: ManipTrans's 2 cm and 30°).
* **Lost at t**: it is not, first at a manipulated frame; ``t`` is when the excursion off its recording that
  led there began, and where it went is judged at that frame: *dropped* (below its recording while the
  recording held it up when it left), *knocked off* (below it while the recording still had it at rest where
  it started: off its support), *pushed* (away from it otherwise), *turned* (only its rotation is off) or
  *hinge* (only its articulation is).
* **Not judged**: the recording never moves the object that far, or the run stopped (diverged) first.

Beside the verdict, :func:`track_flags` flags what makes a verdict doubtful, so that no such trial reads
"valid yes" without a note: a world that does not fit the recorded hands (a static body in their path, from
the scene's checks), a hand deeper in an object than any grip presses (invalid), an object that ends on the
floor, and a hand that never touches the object (by name; notes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.rotations import quat_angle
from handsim.datatypes.trajectory import ObjectTrack
from handsim.sim.control import ControlSchedule
from handsim.sim.metrics import FrameMetrics
from handsim.sim.scene.clearance import static_geoms
from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.support import START_MOTION, collision_points
from handsim.sim.specs import TrackSpec

FOLLOWED, LOST, NOT_JUDGED = "followed", "lost", "not judged"
"""The verdict's outcomes."""


@dataclass(frozen=True)
class TrackVerdict:
    """The verdict on the recorded objects' tracks of a replay.

    Attributes:
        outcome: :data:`FOLLOWED`, :data:`LOST` or :data:`NOT_JUDGED`.
        reason: One line for people: the tolerance it was followed within, when and how it was lost, or why
            it is not judged; with the hands that never touch the object, by name.
        manipulated_frames: Frames the recording moves an object beyond the tolerance from its start
            (control frames; all objects together).
        followed_fraction: Of those simulated, the fraction in which the objects are within the tolerance
            (None without any).
        lost_at: Trajectory time of the loss, s, or None.
        lost_how: ``"dropped"``, ``"knocked off"``, ``"pushed"``, ``"turned"`` or ``"hinge"``, or None.
        lost_object: The track of the object lost, or None.
        untouched_hands: Hands that touch no recorded object in any frame (``""`` for a scene's only hand);
            contacts are read once a control frame, so a touch shorter than a frame can go unseen.
        on_floor: Tracks of the objects lying on the floor at the run's end where the recording does not
            put them.
    """

    outcome: str
    reason: str
    manipulated_frames: int
    followed_fraction: float | None
    lost_at: float | None = None
    lost_how: str | None = None
    lost_object: str | None = None
    untouched_hands: tuple[str, ...] = ()
    on_floor: tuple[str, ...] = ()

    def summary(self) -> dict:
        """The summary's ``track…`` keys (JSON-ready)."""
        return {
            "track": self.outcome,
            "track_reason": self.reason,
            "track_lost_at_s": self.lost_at,
            "track_lost_how": self.lost_how,
            "track_manipulated_frames": self.manipulated_frames,
            "track_followed_fraction": self.followed_fraction,
            "track_untouched_hands": list(self.untouched_hands),
            "track_on_floor": list(self.on_floor),
        }


def manipulated(track: ObjectTrack, spec: TrackSpec) -> np.ndarray:
    """The frames in which a recorded object has moved beyond the follow tolerance from its first pose.

    Args:
        track: The object's recorded track (any frame; its first valid sample is its start).
        spec: The tolerance.

    Returns:
        Per frame, bool (N,); invalid samples are never manipulated.
    """
    pose = np.asarray(track.pose, dtype=float)
    valid = np.ones(pose.shape[0], bool) if track.valid is None else np.asarray(track.valid, dtype=bool)
    if not valid.any():
        return np.zeros(pose.shape[0], bool)
    start = int(np.argmax(valid))
    moved = np.linalg.norm(pose[:, :3] - pose[start, :3], axis=1) > spec.position
    moved |= quat_angle(pose[:, 3:], pose[start, 3:]) > math.radians(spec.rotation_deg)
    if track.articulation is not None:
        angle = np.asarray(track.articulation, dtype=float)
        moved |= np.abs(angle - angle[start]) > math.radians(spec.articulation_deg)
    return moved & valid


def within(frames: FrameMetrics, index: int, spec: TrackSpec) -> np.ndarray:
    """Per simulated frame, whether object ``index`` is within the tolerance of its recording (bool)."""
    art = np.abs(frames.articulation_error[:, index])
    return (
        (frames.object_position_error[:, index] <= spec.position)
        & (frames.object_rotation_error[:, index] <= math.radians(spec.rotation_deg))
        & (np.isnan(art) | (art <= math.radians(spec.articulation_deg)))
    )


def _untouched(frames: FrameMetrics, objects: list[int]) -> tuple[str, ...]:
    """The hands none of whose links ever touch one of the objects."""
    if frames.link_hand is None:
        return ()
    touched = frames.contact_count[:, :, np.isin(frames.part_object, objects)].sum(axis=(0, 2)) > 0
    names = frames.hand_names or ("",)
    return tuple(name for h, name in enumerate(names) if not touched[frames.link_hand == h].any())


def _heights(scene: SimScene, qpos: np.ndarray, index: int, data: mujoco.MjData) -> float:
    """How high object ``index``'s lowest point lies above the scene's floors at ``qpos``, m (inf: none)."""
    model = scene.model
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    planes = [g for g in static_geoms(model) if int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_PLANE)]
    if not planes:
        return math.inf
    points = collision_points(model, data, scene.layout.objects[index].collision_geoms)
    return min(
        float(((points - data.geom_xpos[g]) @ data.geom_xmat[g].reshape(3, 3)[:, 2]).min()) for g in planes
    )


def _on_floor(
    scene: SimScene, schedule: ControlSchedule, qpos: np.ndarray, index: int, spec: TrackSpec, data
) -> bool:
    """Whether object ``index`` lies on the floor at the run's last frame where its recording does not."""
    last = qpos.shape[0] - 1
    if _heights(scene, qpos[last], index, data) > spec.floor_clearance:
        return False
    obj, track = scene.layout.objects[index], schedule.objects[index]
    recorded = qpos[last].copy()
    recorded[obj.free_qpos : obj.free_qpos + 7] = track.pose[last]
    if track.articulation is not None and obj.hinge_qpos >= 0:
        recorded[obj.hinge_qpos] = track.articulation[last]
    return _heights(scene, recorded, index, data) > spec.floor_clearance


_LOST_AS = {
    "dropped": "was dropped",
    "knocked off": "was knocked off its support",
    "pushed": "was pushed off its track",
    "turned": "turned off its track",
    "hinge": "has its hinge off the recording",
}
"""How a lost object's reason says it went."""


def _how(
    frames: FrameMetrics,
    schedule: ControlSchedule,
    qpos: np.ndarray,
    scene: SimScene,
    i: int,
    k: int,
    left: int,
    spec: TrackSpec,
) -> tuple[str, str]:
    """How object ``i`` left its recording: the kind and the numbers at its first manipulated frame off track.

    ``k`` is that frame, ``left`` the frame its excursion off the recording began: an object below its
    recording was knocked off its support when the recording still had it at rest there (within
    :data:`~handsim.sim.scene.support.START_MOTION` of its start), else dropped.
    """
    obj, track = scene.layout.objects[i], schedule.objects[i]
    offset = qpos[k, obj.free_qpos : obj.free_qpos + 3] - track.pose[k, :3]
    distance, aside = float(np.linalg.norm(offset)), float(np.linalg.norm(offset[:2]))
    turned = math.degrees(float(frames.object_rotation_error[k, i]))
    hinge = math.degrees(abs(float(frames.articulation_error[k, i])))
    if distance <= spec.position:
        how = "turned" if turned > spec.rotation_deg else "hinge"
    elif offset[2] < -spec.position and -offset[2] >= aside:
        resting = float(np.linalg.norm(track.pose[left, :3] - track.pose[0, :3])) <= START_MOTION
        how = "knocked off" if resting else "dropped"
    else:
        how = "pushed"
    touching = "a hand touching it" if frames.hand_contact[k, i] else "no hand touching it"
    hinge_text = "" if math.isnan(hinge) else f", hinge {hinge:.0f}° off"
    return how, (
        f"{distance * 100:.1f} cm from its recording, {offset[2] * 100:+.1f} cm vertically; turned "
        f"{turned:.0f}°{hinge_text}; {touching}"
    )


def _hands(names: tuple[str, ...]) -> str:
    """``the left hand and the right hand`` (``the hand`` for a scene's only hand)."""
    return " and ".join(f"the {n} hand" if n else "the hand" for n in names)


def _never_touch(names: tuple[str, ...]) -> str:
    """``the left hand never touches`` (or ``… never touch`` for several)."""
    return f"{_hands(names)} never touch{'es' if len(names) == 1 else ''}"


def track_verdict(
    scene: SimScene,
    schedule: ControlSchedule,
    frames: FrameMetrics,
    qpos: np.ndarray,
    diverged: bool,
    spec: TrackSpec | None = None,
    scratch: mujoco.MjData | None = None,
) -> TrackVerdict | None:
    """Judge whether the simulated objects followed their recorded tracks over the manipulated frames.

    Args:
        scene: The replayed scene (scenario ``recorded``).
        schedule: Its control schedule (the recorded tracks in the scene's world).
        frames: The per-frame metrics of the frames simulated.
        qpos: The state at each frame simulated.
        diverged: The run stopped at a divergence (its frames end early).
        spec: The tolerances (default :class:`~handsim.sim.specs.TrackSpec`).
        scratch: An ``MjData`` of the scene's model that may be overwritten (None: a new one).

    Returns:
        The verdict, or None for a scene with no recorded object track (a glove trial, a hand-only sequence).
    """
    spec = spec or TrackSpec()
    setup = scene.setup
    tracked = [i for i, key in enumerate(setup.object_tracks) if key and i in schedule.objects]
    if setup.scenario != "recorded" or not tracked or qpos.shape[0] == 0:
        return None
    data = mujoco.MjData(scene.model) if scratch is None else scratch
    n = qpos.shape[0]
    untouched = _untouched(frames, tracked)
    floor = tuple(setup.object_tracks[i] for i in tracked if _on_floor(scene, schedule, qpos, i, spec, data))
    total, judged, kept, first_loss = 0, 0, 0, None
    for i in tracked:
        moved = manipulated(schedule.objects[i], spec)
        total += int(moved.sum())
        ok = within(frames, i, spec)
        simulated = moved[:n]
        judged += int(simulated.sum())
        kept += int((simulated & ok).sum())
        lost = np.flatnonzero(simulated & ~ok)
        if lost.size:
            k = int(lost[0])
            back = np.flatnonzero(ok[:k])
            left = int(back[-1]) + 1 if back.size else 0  # where the excursion that loses it began
            if first_loss is None or left < first_loss[1]:
                first_loss = (i, left, k)
    fraction = kept / judged if judged else None
    touch = f"; {_never_touch(untouched)} it" if untouched else ""
    common = {"untouched_hands": untouched, "on_floor": floor}
    tolerance = f"{spec.position * 100:g} cm, {spec.rotation_deg:g}°, hinge {spec.articulation_deg:g}°"
    if first_loss is not None:
        i, left, k = first_loss
        how, text = _how(frames, schedule, qpos, scene, i, k, left, spec)
        name = setup.object_tracks[i]
        at, judged_at = float(frames.times[left]), float(frames.times[k])
        where = (
            text
            if left == k
            else f"off its recording from then; at {judged_at:.2f} s, when first judged, {text}"
        )
        ends = "; it ends on the floor" if name in floor else ""
        return TrackVerdict(
            LOST, f"lost at {at:.2f} s: the {name} {_LOST_AS[how]} ({where}){ends}{touch}", total, fraction,
            at, how, name, **common,
        )  # fmt: skip
    names = ", ".join(setup.object_tracks[i] for i in tracked)
    if total == 0:
        reason = f"not judged: the recording never moves the {names} beyond {tolerance} from its start"
        return TrackVerdict(NOT_JUDGED, reason + touch, 0, None, **common)
    if judged < total and diverged:
        reason = (
            f"not judged: the run stopped at {float(frames.times[-1]):.2f} s with the {names} still "
            f"followed over {judged} of its {total} manipulated frames"
        )
        return TrackVerdict(NOT_JUDGED, reason + touch, total, fraction, **common)
    reason = f"followed: the {names} within {tolerance} of its recording over its {total} manipulated frames"
    return TrackVerdict(FOLLOWED, reason + touch, total, fraction, **common)


def track_flags(
    scene: SimScene, frames: FrameMetrics, verdict: TrackVerdict | None, spec: TrackSpec | None = None
) -> list[Flag]:
    """The flags of a recorded-object replay that make its verdict doubtful (empty without a verdict).

    * ``static_body_in_path`` (invalid): the scene's checks found a static body the recorded hands pass
      through that could not be moved out of their way (:mod:`handsim.sim.arctic_scene`);
    * ``deep_penetration`` (invalid): a hand deeper than ``spec.max_penetration`` inside an object;
    * ``object_on_floor`` (a note): an object ends on the floor where its recording does not put it;
    * ``hand_never_touches`` (a note): a hand never touches a recorded object, by name.

    Args:
        scene: The replayed scene.
        frames: Its per-frame metrics.
        verdict: Its verdict (:func:`track_verdict`).
        spec: The tolerances.
    """
    if verdict is None:
        return []
    spec = spec or TrackSpec()
    invalid = (_static_body_flag(scene.setup.checks), _deep_penetration_flag(frames, spec))
    return [flag for flag in invalid if flag is not None] + _note_flags(verdict, frames, spec)


def _static_body_flag(checks: dict) -> Flag | None:
    """``static_body_in_path`` when the scene's checks found the world does not fit the recorded hands."""
    if not (checks and checks.get("world_fits") is False):
        return None
    deepest = max(checks.get("passages", []), key=lambda p: p["depth_mm"], default=None)
    where = "" if deepest is None else (
        f": the recorded {deepest['site']} goes {deepest['depth_mm']:.0f} mm into the "
        f"{deepest['body']} at {deepest['time_s']:.2f} s"
    )  # fmt: skip
    return Flag(
        "static_body_in_path",
        True,
        f"no placement of the static bodies fits the recorded hands{where} (the scene's notes say "
        "which): the hands are pushed off their recording there",
        {"passages": checks.get("passages", []), "blocked": checks.get("blocked", [])},
    )


def _deep_penetration_flag(frames: FrameMetrics, spec: TrackSpec) -> Flag | None:
    """``deep_penetration`` when a hand goes deeper than ``spec.max_penetration`` inside an object."""
    deep = []
    names = frames.hand_names or ("",)
    penetration = (
        frames.hand_penetration if frames.hand_penetration is not None else frames.penetration[:, None]
    )
    for h, name in enumerate(names):
        depth = penetration[:, h]
        if depth.size and float(depth.max()) > spec.max_penetration:
            k = int(np.argmax(depth))
            over = int((depth > spec.max_penetration).sum())
            deep.append((name, float(depth.max()), float(frames.times[k]), over))
    if not deep:
        return None
    text = "; ".join(
        f"{_hands((name,))} {d * 1000:.1f} mm at {t:.2f} s ({over} frames over)" for name, d, t, over in deep
    )
    return Flag(
        "deep_penetration",
        True,
        f"a hand passes through an object, deeper than {spec.max_penetration * 1000:g} mm (more than "
        f"any grip presses a finger in): {text}",
        {
            "hands": {n or "hand": {"depth_mm": d * 1000, "at_s": t, "frames": o} for n, d, t, o in deep},
            "threshold_mm": spec.max_penetration * 1000,
        },
    )


def _note_flags(verdict: TrackVerdict, frames: FrameMetrics, spec: TrackSpec) -> list[Flag]:
    """The flags that are notes, not invalid verdicts.

    ``object_on_floor``: an object ends on the floor where its recording does not put it;
    ``hand_never_touches``: the hands that never touch a recorded object, by name.
    """
    notes = []
    if verdict.on_floor:
        notes.append(
            Flag(
                "object_on_floor",
                False,
                f"the {', '.join(verdict.on_floor)} ends on the floor (within "
                f"{spec.floor_clearance * 1000:g} mm), where its recording does not put it",
                {"objects": list(verdict.on_floor), "clearance_mm": spec.floor_clearance * 1000},
            )
        )
    if verdict.untouched_hands:
        notes.append(
            Flag(
                "hand_never_touches",
                False,
                f"{_never_touch(verdict.untouched_hands)} the recorded object in any of the run's "
                f"{frames.times.shape[0]} frames (contacts are read once a frame)",
                {"hands": [n or "hand" for n in verdict.untouched_hands]},
            )
        )
    return notes
