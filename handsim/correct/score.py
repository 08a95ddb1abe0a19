"""The correction as a plausibility score: how far a recording had to move to become physically true.

Per trial: the finger correction's RMS and largest value (degrees), the wrist correction's RMS and largest
value (mm, degrees), the object's tracking before (pure replay) and after (the corrected replay) with the
replay's own verdict, and the moments where the correction is largest. The verdict:

* **corrected**: the corrected replay follows the recorded object (the replay's track verdict
  :data:`~handsim.sim.track.FOLLOWED`);
* **not corrected**: it does not (the replay's verdict is lost): no correction within the bounds was found
  that keeps the object on its track; the score is the best found, and the reason the replay's;
* **not judged**: the replay does not judge the track (the recording never moves the object beyond the
  tolerance, or the run diverged).

A glove hold's verdict reads the replay's hold the same way: **corrected** when the corrected replay holds
the object through the window, **not corrected** when it loses it or when its grip check does not accept the
hold (no opposing grip, a wedge, a link through the object: the correction did not make the grasp hold),
**not judged** only when no motion of the fingers could be judged (a window too short after the release, a
link too deep in the object before planning starts).

A correction is **large** (the recording implausible) beyond the acceptance's bounds
(:data:`PLAUSIBLE_FINGER_RATIO` times pure replay's own joint tracking error, or the wrist's
:data:`PLAUSIBLE_WRIST_MM` / :data:`PLAUSIBLE_WRIST_DEG` RMS): then the recording needed more than the
simulation's own servo error to be carried out.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from handsim.correct.config import CorrectionConfig
from handsim.correct.hold import HELD, NOT_HELD, hold_measures
from handsim.correct.reference import Reference
from handsim.correct.support import Finding, unsupported_stretches
from handsim.sim.grip_check import GripCheck
from handsim.sim.replay import ReplayResult
from handsim.sim.track import FOLLOWED, LOST

PLAUSIBLE_FINGER_RATIO = 2.0
"""A finger correction RMS up to this many times pure replay's joint tracking RMS is small: the servos'
own error of following the recording, twice over."""
PLAUSIBLE_WRIST_MM = 10.0
"""A wrist position correction RMS up to this is small, mm (the tracking error of a hand's wrist in marker or
glove-mounted capture is of this order)."""
PLAUSIBLE_WRIST_DEG = 5.0
"""A wrist rotation correction RMS up to this is small, degrees."""
EXPLAINS_WITHIN = 0.5
"""A stretch the recording cannot be followed in (:mod:`handsim.correct.support`) is named in a lost track's
reason when it starts at most this long after the loss, s, and has not ended before it: the fingers let go
over the frames before the recorded hand withdraws."""
LARGEST_FRAMES = 5
"""How many moments of largest correction the score lists."""
LARGEST_SEPARATION = 0.1
"""Seconds between two listed moments: they are distinct moments, not neighbouring frames of one."""


@dataclass(frozen=True)
class Tracking:
    """How the simulated object followed its recording in one replay.

    Attributes:
        within_1cm: Fraction of frames with the object within the replay's drift tolerance (1 cm).
        mean_drift_mm: Mean distance from the recording, mm.
        max_drift_mm: Largest distance, mm.
        mean_rotation_deg: Mean rotation from the recording, degrees.
        track: The replay's track verdict (followed, lost, not judged).
        track_reason: Its reason.
        joint_tracking_rms_deg: RMS of simulated minus recorded joint angles over the driven DoFs and the
            frames after the first, degrees (against the *recording*, not the corrected targets).
    """

    within_1cm: float
    mean_drift_mm: float
    max_drift_mm: float
    mean_rotation_deg: float
    track: str
    track_reason: str
    joint_tracking_rms_deg: float


@dataclass(frozen=True)
class Moment:
    """A frame where the correction is large.

    Attributes:
        frame: Control frame.
        time_s: Its trajectory time, s.
        finger_rms_deg: Finger correction RMS there, degrees.
        finger_max_deg: Largest finger correction there, degrees.
        wrist_mm: Largest wrist position correction there, mm (0 without wrist correction).
        wrist_deg: Largest wrist rotation correction there, degrees.
    """

    frame: int
    time_s: float
    finger_rms_deg: float
    finger_max_deg: float
    wrist_mm: float
    wrist_deg: float


@dataclass(frozen=True)
class CorrectionScore:
    """The plausibility score of a recording (module docstring).

    Attributes:
        status: ``"corrected"``, ``"not corrected"`` or ``"not judged"``.
        reason: One line for people.
        large: The correction exceeds the plausibility bounds (the recording is implausible).
        large_reason: Which bound, with the numbers, or "".
        finger_rms_deg: Finger correction RMS over the corrected targets and frames, degrees.
        finger_max_deg: Largest finger correction, degrees.
        finger_vs_replay_tracking: ``finger_rms_deg`` over pure replay's joint tracking RMS.
        wrist_position_rms_mm: Wrist position correction RMS over frames (and hands), mm; None without one.
        wrist_position_max_mm: Its largest value, mm.
        wrist_rotation_rms_deg: Wrist rotation correction RMS, degrees.
        wrist_rotation_max_deg: Its largest value, degrees.
        before: Pure replay's tracking.
        after: The corrected replay's tracking.
        largest: The moments of largest correction, largest first.
        objective: ``"track"`` (the objects follow their recorded tracks) or ``"hold"`` (a glove scene's
            object stays in the hand through the hold window; ``before``/``after`` then measure its
            displacement from where the grasp placed it, and their ``track`` is the hold verdict).
        unsupported: Where no motion near the recording can follow it (:mod:`handsim.correct.support`): an
            object no hand link comes near, held in the air (no hand link touching it, no surface under
            it), or a hinged part turned with no hand link touching it; a property of the recording, the
            same before and after.
    """

    status: str
    reason: str
    large: bool
    large_reason: str
    finger_rms_deg: float
    finger_max_deg: float
    finger_vs_replay_tracking: float
    wrist_position_rms_mm: float | None
    wrist_position_max_mm: float | None
    wrist_rotation_rms_deg: float | None
    wrist_rotation_max_deg: float | None
    before: Tracking
    after: Tracking
    largest: tuple[Moment, ...]
    objective: str = "track"
    unsupported: tuple[Finding, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready fields (each stretch in the air with its sentence, ``text``)."""
        result = asdict(self)
        result["unsupported"] = [u.to_dict() for u in self.unsupported]
        return result


@dataclass(frozen=True)
class FrameSizes:
    """The correction's size per control frame (what a corrected file stores).

    Attributes:
        finger_rms: RMS over the corrected finger targets, rad (F,).
        finger_max: Largest absolute finger correction, rad (F,).
        wrist_position: Wrist position correction per corrected hand, m (F, H).
        wrist_rotation: Wrist rotation correction per corrected hand, rad (F, H).
    """

    finger_rms: np.ndarray
    finger_max: np.ndarray
    wrist_position: np.ndarray
    wrist_rotation: np.ndarray


def frame_sizes(reference: Reference, residual: np.ndarray) -> FrameSizes:
    """The correction's size per frame from the committed residuals (F, D)."""
    nf = reference.fingers
    fingers = residual[:, :nf]
    wrist = residual[:, nf:].reshape(residual.shape[0], -1, 6)
    return FrameSizes(
        finger_rms=np.sqrt(np.mean(fingers**2, axis=1)) if nf else np.zeros(residual.shape[0]),
        finger_max=np.max(np.abs(fingers), axis=1) if nf else np.zeros(residual.shape[0]),
        wrist_position=np.linalg.norm(wrist[..., :3], axis=-1),
        wrist_rotation=np.linalg.norm(wrist[..., 3:], axis=-1),
    )


def tracking(
    result: ReplayResult, reference: Reference, residual: np.ndarray, tolerance: float = 0.01
) -> Tracking:
    """The object's tracking in a replay of the recording corrected by ``residual`` (F, D; 0: pure replay).

    A glove scene's (``reference.goal``): the object's displacement from its placed pose over the hold,
    ``tolerance`` (m) the "within" distance, and the replay's hold verdict as its ``track``.
    """
    n = result.frames.times.shape[0]
    act = reference.actuators
    low, high = (reference.scene.layout.ctrl_range[act, i] for i in (0, 1))
    recorded = reference.schedule.ctrl[:n, act]
    own = recorded + residual[:n, : reference.fingers]
    # the replay's error is against its own (clipped) targets: moved onto the recording's
    against = result.frames.tracking_error[:, act] + np.clip(own, low, high) - np.clip(recorded, low, high)
    joints = math.degrees(float(np.sqrt(np.mean(against[1:] ** 2))))
    if reference.goal is not None:
        m = hold_measures(result, reference.goal, tolerance)
        return Tracking(
            m.within_1cm, m.mean_drift_mm, m.max_drift_mm, m.mean_rotation_deg, m.track, m.reason, joints
        )
    s = result.summary
    return Tracking(
        within_1cm=float(s["within_tolerance"]),
        mean_drift_mm=float(s["mean_drift_mm"]),
        max_drift_mm=float(s["max_drift_mm"]),
        mean_rotation_deg=float(s["mean_rotation_drift_deg"]),
        track=str(s.get("track")),
        track_reason=str(s.get("track_reason")),
        joint_tracking_rms_deg=joints,
    )


def score(
    reference: Reference,
    config: CorrectionConfig,
    residual: np.ndarray,
    before: ReplayResult,
    after: ReplayResult,
) -> CorrectionScore:
    """The plausibility score of a correction.

    Args:
        reference: The recording.
        config: The correction's parameters (its bounds, for the reason).
        residual: The committed residuals (F, D).
        before: Pure replay of the recording.
        after: Replay of the corrected recording.
    """
    sizes = frame_sizes(reference, residual)
    nf = reference.fingers
    fingers = residual[:, :nf]
    finger_rms = math.degrees(float(np.sqrt(np.mean(fingers**2)))) if nf else 0.0
    finger_max = math.degrees(float(np.max(np.abs(fingers)))) if nf else 0.0
    scale = config.position_scale
    was = tracking(before, reference, np.zeros_like(residual), scale)
    now = tracking(after, reference, residual, scale)
    ratio = finger_rms / was.joint_tracking_rms_deg if was.joint_tracking_rms_deg > 0 else math.inf
    wrist = bool(reference.hands)
    wp = 1000.0 * sizes.wrist_position if wrist else None
    wr = np.degrees(sizes.wrist_rotation) if wrist else None
    wp_rms = float(np.sqrt(np.mean(wp**2))) if wp is not None else None
    wr_rms = float(np.sqrt(np.mean(wr**2))) if wr is not None else None
    large = []
    if ratio > PLAUSIBLE_FINGER_RATIO:
        large.append(
            f"finger correction {finger_rms:.2f}° RMS is {ratio:.1f}× pure replay's joint tracking error "
            f"({was.joint_tracking_rms_deg:.2f}° RMS; small is ≤ {PLAUSIBLE_FINGER_RATIO:g}×)"
        )
    if wp_rms is not None and wp_rms > PLAUSIBLE_WRIST_MM:
        large.append(f"wrist moved {wp_rms:.1f} mm RMS (small is ≤ {PLAUSIBLE_WRIST_MM:g} mm)")
    if wr_rms is not None and wr_rms > PLAUSIBLE_WRIST_DEG:
        large.append(f"wrist turned {wr_rms:.1f}° RMS (small is ≤ {PLAUSIBLE_WRIST_DEG:g}°)")
    stretches = unsupported_stretches(reference)
    if reference.goal is None:
        status, reason = _verdict(now, config, wrist)
        if status == "not corrected":
            reason += unfollowable_clause(stretches, after.summary.get("track_lost_at_s"))
    else:
        gripped = after.grip is not None and not _deep_before_planning(after.grip, reference)
        status, reason = hold_verdict(was, now, config, gripped=gripped)
    return CorrectionScore(
        status=status,
        reason=reason,
        large=bool(large),
        large_reason="; ".join(large),
        finger_rms_deg=finger_rms,
        finger_max_deg=finger_max,
        finger_vs_replay_tracking=ratio,
        wrist_position_rms_mm=wp_rms,
        wrist_position_max_mm=None if wp is None else float(wp.max()),
        wrist_rotation_rms_deg=wr_rms,
        wrist_rotation_max_deg=None if wr is None else float(wr.max()),
        before=was,
        after=now,
        largest=_largest(reference, config, sizes),
        objective="track" if reference.goal is None else "hold",
        unsupported=stretches,
    )


def _deep_before_planning(grip: GripCheck, reference: Reference) -> bool:
    """Whether the grip check's deepest link is too deep at a frame the correction does not plan.

    The frames up to the first planned one are the recording's own (contacts switch on there): a link too
    deep in the object then is the recording's, which no correction changes, so the hold stays not judged.
    """
    start = float(reference.schedule.times[reference.plan_start])
    return grip.too_deep and grip.deepest_at <= start + 1e-9


def unfollowable_clause(stretches: tuple[Finding, ...], lost_at: float | None) -> str:
    """The clause for a lost track where the recording, after the loss, moves the object as nothing can.

    Held in the air or a part turned untouched (:mod:`handsim.correct.support`), from at most
    :data:`EXPLAINS_WITHIN` after the loss: what no motion near the recording can follow.
    """
    if lost_at is None:
        return ""
    near = [s for s in stretches if s.stop_s >= lost_at and s.start_s <= lost_at + EXPLAINS_WITHIN]
    return f"; {near[0].brief()}" if near else ""


def _verdict(after: Tracking, config: CorrectionConfig, wrist: bool) -> tuple[str, str]:
    bounds = f"fingers ≤ {math.degrees(config.finger_bound):.1f}° per joint"
    if wrist:
        bounds += (
            f", wrist ≤ {config.wrist_position_bound * 1000:g} mm and "
            f"{math.degrees(config.wrist_rotation_bound):.1f}°"
        )
    if after.track == FOLLOWED:
        return "corrected", f"the object follows its recording: {after.track_reason}"
    if after.track == LOST:
        return (
            "not corrected",
            f"no correction within the bounds ({bounds}) was found that keeps the object on its track: "
            f"{after.track_reason}; best found: within 1 cm in {after.within_1cm * 100:.1f} % of frames, "
            f"mean drift {after.mean_drift_mm:.1f} mm",
        )
    return "not judged", f"the replay does not judge the track: {after.track_reason}"


def relative_size(score: CorrectionScore) -> float:
    """The correction's size against its plausibility bounds; above 1 the correction is large.

    The largest of the finger RMS over :data:`PLAUSIBLE_FINGER_RATIO` times pure replay's joint tracking
    error and the wrist's RMS over :data:`PLAUSIBLE_WRIST_MM` and :data:`PLAUSIBLE_WRIST_DEG`: what a
    dataset's corrections are ranked by.
    """
    sizes = [score.finger_vs_replay_tracking / PLAUSIBLE_FINGER_RATIO]
    if score.wrist_position_rms_mm is not None:
        sizes.append(score.wrist_position_rms_mm / PLAUSIBLE_WRIST_MM)
    if score.wrist_rotation_rms_deg is not None:
        sizes.append(score.wrist_rotation_rms_deg / PLAUSIBLE_WRIST_DEG)
    return float(max(sizes))


def implausible_text(score: CorrectionScore) -> str | None:
    """The sentence that calls a recording implausible, with the numbers; None for a small correction."""
    return f"the recording needs a large correction: {score.large_reason}" if score.large else None


def hold_verdict(
    before: Tracking, after: Tracking, config: CorrectionConfig, *, gripped: bool
) -> tuple[str, str]:
    """A glove correction's verdict: the corrected replay holds the object through the window, or not.

    ``gripped``: the corrected replay's grip check ran (the hold was judged on the object's motion, then
    examined for a grip). A hold it turned into "not judged" (no opposing grip, a wedge, a link through the
    object) is a correction that did not make the grasp hold: **not corrected**, with the check's reason.
    Only a hold the replay cannot judge whatever the fingers do (its window too short after the release, a
    placement that penetrates the hand, a link too deep in the object already at a frame the correction does
    not plan: ``gripped`` False) leaves the correction **not judged**.
    """
    bounds = f"fingers ≤ {math.degrees(config.finger_bound):.1f}° per joint"
    best = (
        f"best found: within 1 cm of its placement in {after.within_1cm * 100:.1f} % of the hold's frames, "
        f"mean displacement {after.mean_drift_mm:.1f} mm"
    )
    if after.track == HELD:
        what = "holds already in pure replay" if before.track == HELD else "now holds"
        return "corrected", f"the grasp {what} through its hold window: {after.track_reason}"
    if after.track == NOT_HELD:
        return (
            "not corrected",
            f"no correction within the bounds ({bounds}) was found that keeps the object in the hand: "
            f"{after.track_reason}; {best}",
        )
    if gripped:
        return (
            "not corrected",
            f"no correction within the bounds ({bounds}) was found whose hold the replay's grip check "
            f"accepts: {after.track_reason}; {best}",
        )
    return "not judged", f"the replay does not judge the hold: {after.track_reason}"


def _largest(reference: Reference, config: CorrectionConfig, sizes: FrameSizes) -> tuple[Moment, ...]:
    """The frames of largest correction (sized as the cost sizes it), :data:`LARGEST_SEPARATION` apart."""
    size = (sizes.finger_rms / config.finger_scale) ** 2
    if sizes.wrist_position.size:
        size = size + np.sum(
            (sizes.wrist_position / config.wrist_position_scale) ** 2
            + (sizes.wrist_rotation / config.wrist_rotation_scale) ** 2,
            axis=1,
        )
    times = reference.schedule.times
    chosen: list[int] = []
    for frame in np.argsort(-size, kind="stable"):
        if size[frame] <= 0 or len(chosen) == LARGEST_FRAMES:
            break
        if all(abs(times[frame] - times[c]) >= LARGEST_SEPARATION for c in chosen):
            chosen.append(int(frame))
    wrist = sizes.wrist_position.size > 0
    return tuple(
        Moment(
            frame=f,
            time_s=float(times[f]),
            finger_rms_deg=math.degrees(float(sizes.finger_rms[f])),
            finger_max_deg=math.degrees(float(sizes.finger_max[f])),
            wrist_mm=float(sizes.wrist_position[f].max()) * 1000.0 if wrist else 0.0,
            wrist_deg=math.degrees(float(sizes.wrist_rotation[f].max())) if wrist else 0.0,
        )
        for f in chosen
    )
