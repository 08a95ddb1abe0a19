"""Per-trial numbers from per-frame metrics: the hold outcome of a glove trial and the summary's sections."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from handsim.sim.curves import DEG, MM
from handsim.sim.curves import slip as slip_curve
from handsim.sim.metrics import FrameMetrics, HoldTracks
from handsim.sim.sections import (
    Contacts,
    FrameNumbers,
    HandNumbers,
    HandOnly,
    HingeDrift,
    ObjectDrift,
    Tracking,
)
from handsim.sim.specs import MetricSpec

NO_OBJECT = "not judged: no object (a hand-only sequence: nothing to touch, hold or drift)"
"""Why a replay without objects judges no hand–object contact, hold or drift."""


@dataclass(frozen=True)
class HoldOutcome:
    """Did the hand hold the released object through the hold window?

    Attributes:
        released_at: Trajectory time the support was switched off, s.
        window: Trajectory times (start, stop) the hold is judged over, s (start ≥ release).
        held: The object was not lost before the window's end; None: not judged (``reason`` says why).
        time_held: From release until lost (or the window's end, or the last frame simulated), s.
        lost_at: Time it was lost, s, or None.
        reason: Why it counts as lost (slip or contact gap), or why the hold is not judged; None when held.
        max_slip: Largest displacement relative to the hand root from release until lost or the window's
            end, m.
        drop: How far the object's origin fell in the world (−z) from release to the window's end, m.
    """

    released_at: float
    window: tuple[float, float]
    held: bool | None
    time_held: float
    lost_at: float | None
    reason: str | None
    max_slip: float
    drop: float

    @property
    def judged(self) -> bool:
        """The hold was judged (``held`` is True or False)."""
        return self.held is not None

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return asdict(self)


def not_judged(release_time: float, window: tuple[float, float], reason: str) -> HoldOutcome:
    """A hold outcome that is not judged, with the reason (it starts with ``not judged:``)."""
    return HoldOutcome(
        release_time, (max(release_time, window[0]), window[1]), None, 0.0, None, reason, 0.0, 0.0
    )


def window_long_enough(release_time: float, window: tuple[float, float], spec: MetricSpec) -> bool:
    """Whether the hold window lasts ``spec.min_hold_window`` after the release: else not judged.

    :func:`hold_outcome`'s first test, known before the run.
    """
    return not window[1] - max(release_time, window[0]) < spec.min_hold_window - 1e-9


def hold_outcome(
    frames: FrameMetrics | HoldTracks,
    object_z: np.ndarray,
    release_time: float,
    window: tuple[float, float],
    spec: MetricSpec,
    object_index: int = 0,
) -> HoldOutcome:
    """Judge holding after release, or say why it cannot be judged.

    The object is lost at the first slip beyond ``spec.slip_limit`` or contact gap longer than
    ``spec.contact_gap``. Holding is judged only over a window of at least ``spec.min_hold_window`` after
    the release: a shorter one (the grasp closes near the end of the recording, or the release falls after
    the window's end) is not judged, nor is a run that stopped (diverged) before the window ended without
    the object having been lost.

    Args:
        frames: Per-frame metrics, or just their hold tracks (the run may have stopped early, or still be
            going: a loss found in its first frames is the loss of the whole run).
        object_z: World height of the object's origin per frame, m.
        release_time: When the support was switched off, s.
        window: The hold window (trajectory times), s.
        spec: Thresholds.
        object_index: Which object.
    """
    t = frames.times
    start = max(release_time, window[0])
    if not window_long_enough(release_time, window, spec):
        length = window[1] - start
        return not_judged(
            release_time,
            window,
            f"not judged: the hold window after release lasts {max(length, 0.0):.3f} s, less than the "
            f"{spec.min_hold_window:g} s a hold is judged over (release at {release_time:.3f} s, window "
            f"{window[0]:.3f}–{window[1]:.3f} s)",
        )
    if t.shape[0] == 0 or release_time > t[-1] + 1e-9:
        return not_judged(
            release_time, window, f"not judged: the run stopped before the release at {release_time:.3f} s"
        )
    r = int(np.searchsorted(t, release_time - 1e-9))
    stop_index = int(np.searchsorted(t, window[1] + 1e-9))
    last = min(stop_index, t.shape[0]) - 1
    slip = slip_curve(frames.object_in_hand[:, object_index], r)
    contact = frames.hand_contact[:, object_index]
    lost, reason = None, None
    gap_start = None
    for k in range(r, last + 1):
        if slip[k] > spec.slip_limit:
            lost, reason = k, f"slipped {slip[k] * 100:.1f} cm relative to the hand"
            break
        if contact[k]:
            gap_start = None
        else:
            gap_start = k if gap_start is None else gap_start
            if t[k] - t[gap_start] >= spec.contact_gap:
                lost, reason = gap_start, f"no hand contact for {spec.contact_gap:g} s"
                break
    end = last if lost is None else lost
    held: bool | None = lost is None
    frame_dt = float(t[1] - t[0]) if t.shape[0] > 1 else 0.0
    if lost is None and t[-1] < window[1] - frame_dt - 1e-9:  # the schedule's frames end within one of it
        held = None
        reason = (
            f"not judged: the run stopped at {t[-1]:.3f} s, before the window's end at {window[1]:.3f} s, "
            "with the object still held"
        )
    return HoldOutcome(
        released_at=float(t[r]),
        window=(float(start), float(window[1])),
        held=held,
        time_held=float(t[end] - t[r]),
        lost_at=None if lost is None else float(t[lost]),
        reason=reason,
        max_slip=float(slip[r : end + 1].max()),
        drop=float(object_z[r] - object_z[last]),
    )


def _finite(x: np.ndarray, fn) -> float | None:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(fn(x)) if x.size else None


CONTACT_KEYS = tuple(f.name for f in fields(Contacts))
"""The summary's hand–object numbers (:class:`~handsim.sim.sections.Contacts`): None in a scene without
objects."""

HAND_KEYS = tuple(f.name for f in fields(HandNumbers) if f.name != "hand")
"""The summary's per-hand numbers of a scene with several hands, each as ``<hand>/<key>``."""

NO_CONTACTS = Contacts(**dict.fromkeys(CONTACT_KEYS))
"""The hand–object numbers of a scene without objects."""


def _contacts(count: np.ndarray, normal: np.ndarray, penetration: np.ndarray, truncated: int) -> Contacts:
    """Penetration and contact numbers of the hand links given.

    Args:
        count: Contacts per link × part (N, links, parts).
        normal: Normal force per link × part, N (N, links, parts).
        penetration: Deepest penetration per frame, m (N,).
        truncated: Contacts beyond the per-frame arrays, summed over the frames.
    """
    n = penetration.shape[0]
    return Contacts(
        max_penetration_mm=float(penetration.max() * MM) if n else 0.0,
        p95_penetration_mm=float(np.percentile(penetration, 95) * MM) if n else 0.0,
        frames_penetrating_over_1mm=int((penetration > 0.001).sum()),
        contact_frames=int((count.sum(axis=(1, 2)) > 0).sum()) if count.size else 0,
        max_contact_links=int((count.sum(axis=2) > 0).sum(axis=1).max()) if n and count.size else 0,
        max_total_normal_force_n=float(normal.sum(axis=(1, 2)).max()) if n and normal.size else 0.0,
        truncated_contact_pairs=truncated,
    )


def _tracking(tracking: np.ndarray, tips: np.ndarray) -> Tracking:
    """Joint tracking and fingertip numbers of the DoFs and tips given.

    Args:
        tracking: Joint tracking error, rad (N, dofs).
        tips: Fingertip error, m (N, tips).
    """
    return Tracking(
        mean_tracking_error_deg=_finite(np.abs(tracking) * DEG, np.mean),
        max_tracking_error_deg=_finite(np.abs(tracking) * DEG, np.max),
        mean_tip_error_mm=_finite(tips * MM, np.mean),
        max_tip_error_mm=_finite(tips * MM, np.max),
    )


def _hands(frames: FrameMetrics, objects: bool) -> tuple[HandNumbers, ...]:
    """Each hand's numbers in a scene with several hands (the contact numbers None without objects)."""
    if len(frames.hand_names) < 2:
        return ()
    found = []
    for h, name in enumerate(frames.hand_names):
        links, dofs, tips = frames.link_hand == h, frames.dof_hand == h, frames.tip_hand == h
        contacts = _contacts(
            frames.contact_count[:, links], frames.normal_force[:, links], frames.hand_penetration[:, h], 0
        )
        tracking = _tracking(frames.tracking_error[:, dofs], frames.tip_error[:, tips])
        own = {**asdict(contacts if objects else NO_CONTACTS), **asdict(tracking)}
        found.append(HandNumbers(name, **{key: own[key] for key in HAND_KEYS}))
    return tuple(found)


def _drift(frames: FrameMetrics, spec: MetricSpec) -> ObjectDrift | None:
    """The recorded objects against their tracks, or None where no object has a finite position error."""
    pos = frames.object_position_error
    if not np.isfinite(pos).any():
        return None
    hinge = None
    if np.isfinite(frames.articulation_error).any():
        hinge = HingeDrift(
            mean_articulation_drift_deg=_finite(np.abs(frames.articulation_error) * DEG, np.mean),
            final_articulation_drift_deg=_finite(np.abs(frames.articulation_error[-1]) * DEG, np.max),
        )
    return ObjectDrift(
        mean_drift_mm=_finite(pos * MM, np.mean),
        max_drift_mm=_finite(pos * MM, np.max),
        final_drift_mm=_finite(pos[-1] * MM, np.max),
        within_tolerance=float(np.mean(pos[np.isfinite(pos)] <= spec.drift_tolerance)),
        mean_rotation_drift_deg=_finite(frames.object_rotation_error * DEG, np.mean),
        max_rotation_drift_deg=_finite(frames.object_rotation_error * DEG, np.max),
        max_articulation_drift_deg=_finite(np.abs(frames.articulation_error) * DEG, np.max),
        hinge=hinge,
    )


def summarize(frames: FrameMetrics, spec: MetricSpec) -> FrameNumbers:
    """The per-trial numbers of the per-frame metrics (the record's units: ``_mm``, ``_deg``, ``_n``, ``_s``).

    Without objects (a hand-only sequence) the hand–object numbers (:data:`CONTACT_KEYS`: penetration,
    contacts, forces; each hand's too) are None, never a 0 that reads as a clean result;
    :func:`hand_only_summary` adds why and the hand's self-penetration.

    A scene with several hands adds each hand's :data:`HAND_KEYS` (recorded as ``<hand>/<key>``:
    ``right/…``, ``left/…``); the whole-scene numbers cover every hand.
    """
    n = frames.times.shape[0]
    objects = frames.object_in_hand.shape[1] > 0
    contacts = _contacts(
        frames.contact_count, frames.normal_force, frames.penetration, int(frames.truncated_pairs.sum())
    )
    return FrameNumbers(
        frames=int(n),
        duration_s=float(frames.times[-1] - frames.times[0]) if n else 0.0,
        contacts=contacts if objects else NO_CONTACTS,
        tracking=_tracking(frames.tracking_error, frames.tip_error),
        hands=_hands(frames, objects),
        drift=_drift(frames, spec),
    )


def hand_only_summary(frames: FrameMetrics, links: tuple[str, ...]) -> HandOnly:
    """The numbers of a replay without objects: hold and drift not judged (why), the hand through itself.

    Args:
        frames: Per-frame metrics of a scene without objects (with its self-penetration).
        links: The scene's hand links (the layout's ``link_names``), which the pairs index.

    Returns:
        ``hold_reason`` and ``drift_reason`` (:data:`NO_OBJECT`; no ``held``: a verdict is true or absent);
        the simulated hand's deepest self-penetration, its 95th percentile, the frames over 1 mm and the
        links and time of its deepest frame (None when no two links overlap); the same deepest numbers of
        the hand at its targets (the recording's own postures).

    Raises:
        ValueError: ``frames`` hold no self-penetration (a scene with objects).
    """
    n = frames.times.shape[0]
    if frames.self_penetration.shape[0] != n or frames.target_self_penetration.shape[0] != n:
        raise ValueError("hand_only_summary needs the self-penetration of a scene without objects")
    depth = frames.self_penetration
    target = frames.target_self_penetration
    links_at, at_s = _deepest(depth, frames.self_penetration_pair, frames.times, links)
    target_links, target_at_s = _deepest(target, frames.target_self_penetration_pair, frames.times, links)
    return HandOnly(
        hold_reason=NO_OBJECT,
        drift_reason=NO_OBJECT,
        max_self_penetration_mm=float(depth.max() * 1000.0) if n else None,
        p95_self_penetration_mm=float(np.percentile(depth, 95) * 1000.0) if n else None,
        frames_self_penetrating_over_1mm=int((depth > 0.001).sum()),
        self_penetration_links=links_at,
        self_penetration_at_s=at_s,
        max_target_self_penetration_mm=float(target.max() * 1000.0) if n else None,
        target_self_penetration_links=target_links,
        target_self_penetration_at_s=target_at_s,
    )


def _deepest(
    depth: np.ndarray, pair: np.ndarray, times: np.ndarray, links: tuple[str, ...]
) -> tuple[tuple[str, ...] | None, float | None]:
    """The two links and the time of the deepest frame (None, None when no two links overlap)."""
    k = int(np.argmax(depth)) if depth.size else -1
    if k < 0 or depth[k] <= 0.0:
        return None, None
    return tuple(links[i] for i in pair[k]), float(times[k])
