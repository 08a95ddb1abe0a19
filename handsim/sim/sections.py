"""A replay's summary as typed sections, and the one place they become the record's ``summary`` dict.

Each section holds its numbers in the record's units under the record's key names (``_mm``, ``_deg``,
``_n``, ``_s`` in the names), so that :meth:`ReplaySummary.to_dict` writes the record without renaming or
converting anything. The numbers are computed where their section is built (per-frame statistics in
:mod:`handsim.sim.summary`, the hold's in :mod:`handsim.sim.result`); code that prints a replay reads the
sections, records and reports read the dict.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from handsim.sim.track import TrackVerdict


def _record(section: object) -> dict:
    """A section's fields as record keys, in field order (tuples as lists: JSON-ready)."""
    values = ((f.name, getattr(section, f.name)) for f in fields(section))  # type: ignore[arg-type]
    return {key: list(value) if isinstance(value, tuple) else value for key, value in values}


@dataclass(frozen=True)
class Contacts:
    """Hand–object penetration and contacts over every hand.

    Each is None in a scene without objects: never a 0 that reads as a clean result.

    Attributes:
        max_penetration_mm: Deepest hand–object penetration of any frame, mm.
        p95_penetration_mm: 95th percentile of the per-frame deepest penetration, mm.
        frames_penetrating_over_1mm: Frames deeper than 1 mm.
        contact_frames: Frames with a hand–object contact.
        max_contact_links: Most hand links touching an object in one frame.
        max_total_normal_force_n: Largest per-frame sum of the hand–object normal forces, N.
        truncated_contact_pairs: Contacts beyond what the per-frame arrays hold, summed over the frames.
    """

    max_penetration_mm: float | None
    p95_penetration_mm: float | None
    frames_penetrating_over_1mm: int | None
    contact_frames: int | None
    max_contact_links: int | None
    max_total_normal_force_n: float | None
    truncated_contact_pairs: int | None


@dataclass(frozen=True)
class Tracking:
    """How closely the hand followed its targets (None where there is no finite value).

    Attributes:
        mean_tracking_error_deg: Mean absolute joint angle error over frames and DoFs, degrees.
        max_tracking_error_deg: Largest absolute joint angle error, degrees.
        mean_tip_error_mm: Mean fingertip distance from where the targets put it, mm.
        max_tip_error_mm: Largest fingertip distance, mm.
    """

    mean_tracking_error_deg: float | None
    max_tracking_error_deg: float | None
    mean_tip_error_mm: float | None
    max_tip_error_mm: float | None


@dataclass(frozen=True)
class HandNumbers:
    """One hand's numbers in a scene with several, recorded as ``<hand>/<key>``.

    The contact numbers are None in a scene without objects; the others are as in :class:`Contacts` and
    :class:`Tracking`, over this hand's links, DoFs and fingertips.
    """

    hand: str
    max_penetration_mm: float | None
    frames_penetrating_over_1mm: int | None
    contact_frames: int | None
    max_contact_links: int | None
    max_total_normal_force_n: float | None
    mean_tracking_error_deg: float | None
    max_tracking_error_deg: float | None
    mean_tip_error_mm: float | None
    max_tip_error_mm: float | None

    def record(self) -> dict:
        """The record's ``<hand>/<key>`` entries."""
        return {f"{self.hand}/{key}": value for key, value in _record(self).items() if key != "hand"}


@dataclass(frozen=True)
class HingeDrift:
    """An articulated object's hinge against its recording, degrees.

    Attributes:
        mean_articulation_drift_deg: Mean absolute hinge angle error.
        final_articulation_drift_deg: The hinge angle error of the last frame (None where it is not finite).
    """

    mean_articulation_drift_deg: float | None
    final_articulation_drift_deg: float | None


@dataclass(frozen=True)
class ObjectDrift:
    """Recorded objects against their recorded tracks (a scene whose objects follow a recording).

    Attributes:
        mean_drift_mm: Mean object position error, mm.
        max_drift_mm: Largest object position error, mm.
        final_drift_mm: Largest object position error of the last frame, mm.
        within_tolerance: Fraction of the finite position errors within the drift tolerance.
        mean_rotation_drift_deg: Mean object rotation error, degrees.
        max_rotation_drift_deg: Largest object rotation error, degrees.
        max_articulation_drift_deg: Largest absolute hinge angle error, degrees (None without a hinge).
        hinge: The hinge's mean and final error when a hinge is tracked, else None (the record then has
            neither key).
    """

    mean_drift_mm: float | None
    max_drift_mm: float | None
    final_drift_mm: float | None
    within_tolerance: float
    mean_rotation_drift_deg: float | None
    max_rotation_drift_deg: float | None
    max_articulation_drift_deg: float | None
    hinge: HingeDrift | None = None

    def record(self) -> dict:
        """The record's drift entries (the hinge's only when it is tracked)."""
        found = {key: value for key, value in _record(self).items() if key != "hinge"}
        return found if self.hinge is None else {**found, **_record(self.hinge)}


@dataclass(frozen=True)
class FrameNumbers:
    """What the per-frame metrics give before any verdict (:func:`handsim.sim.summary.summarize`).

    Attributes:
        frames: Frames simulated.
        duration_s: Trajectory time from the first to the last frame simulated, s.
        contacts: Hand–object penetration and contacts over every hand.
        tracking: Joint and fingertip tracking over every hand.
        hands: Each hand's numbers in a scene with several hands, else empty.
        drift: Recorded objects against their tracks, or None where no object has a finite error.
    """

    frames: int
    duration_s: float
    contacts: Contacts
    tracking: Tracking
    hands: tuple[HandNumbers, ...] = ()
    drift: ObjectDrift | None = None

    def record(self) -> dict:
        """The record's per-frame entries, in the record's order."""
        found = {"frames": self.frames, "duration_s": self.duration_s, **_record(self.contacts)}
        found.update(_record(self.tracking))
        for hand in self.hands:
            found.update(hand.record())
        return found if self.drift is None else {**found, **self.drift.record()}


@dataclass(frozen=True)
class HandOnly:
    """A replay without objects: why there is no contact, hold or drift, and the hand through itself.

    Attributes:
        hold_reason: Why no hold is judged (a hand-only sequence).
        drift_reason: Why no drift is measured (the same).
        max_self_penetration_mm: Deepest penetration of the simulated hand through itself, mm (None
            without frames).
        p95_self_penetration_mm: Its 95th percentile over the frames, mm (None without frames).
        frames_self_penetrating_over_1mm: Frames deeper than 1 mm.
        self_penetration_links: The two links of the deepest frame (None when no two links overlap).
        self_penetration_at_s: Its time, s (None when no two links overlap).
        max_target_self_penetration_mm: Deepest penetration of the hand at its targets (the recording's
            own postures), mm (None without frames).
        target_self_penetration_links: The two links of that deepest frame (None when none overlap).
        target_self_penetration_at_s: Its time, s (None when none overlap).
    """

    hold_reason: str
    drift_reason: str
    max_self_penetration_mm: float | None
    p95_self_penetration_mm: float | None
    frames_self_penetrating_over_1mm: int
    self_penetration_links: tuple[str, ...] | None
    self_penetration_at_s: float | None
    max_target_self_penetration_mm: float | None
    target_self_penetration_links: tuple[str, ...] | None
    target_self_penetration_at_s: float | None


@dataclass(frozen=True)
class TrackSection:
    """The verdict on the recorded objects' tracks and each hand's starting penetration.

    Attributes:
        verdict: The verdict (:func:`handsim.sim.track.track_verdict`).
        start_penetration_mm: Hand name (``""`` for a scene's only hand) → how deep it starts inside the
            objects, mm, from the scene's checks; empty where none ran.
    """

    verdict: TrackVerdict
    start_penetration_mm: dict[str, float]

    def record(self) -> dict:
        """The verdict's ``track…`` entries, then ``<hand>/start_penetration_mm`` of each hand checked."""
        start = {
            f"{name}/start_penetration_mm" if name else "start_penetration_mm": depth
            for name, depth in self.start_penetration_mm.items()
        }
        return {**self.verdict.summary(), **start}


@dataclass(frozen=True)
class HoldNumbers:
    """The glove scenario's hold outcome in the record's units.

    Attributes:
        held: The object was not lost before the window's end; None: not judged.
        hold_reason: Why it was lost, or why the hold is not judged; None when held.
        time_held_s: From the release until lost (or the window's end), s.
        max_slip_mm: Largest displacement relative to the hand root until lost or the window's end, mm.
        drop_mm: How far the object's origin fell from the release to the window's end, mm.
    """

    held: bool | None
    hold_reason: str | None
    time_held_s: float
    max_slip_mm: float
    drop_mm: float


@dataclass(frozen=True)
class GripNumbers:
    """The grip over a judged hold window (:class:`~handsim.sim.grip_check.GripCheck`); all None without.

    Attributes:
        grip_links: Hand links that touched the object in the window.
        grip_opposition: Share of the examined frames with an opposing pair.
        grip_opposing_links: The opposing pair found in most frames.
        deepest_link: The link deepest in the object.
        deepest_link_mm: Its depth, mm.
        grip_force_n: Median finger and thumb normal force on the object, N.
        grip_force_limit_n: Median of what their servos can press with, N.
    """

    grip_links: tuple[str, ...] | None = None
    grip_opposition: float | None = None
    grip_opposing_links: tuple[str, ...] | None = None
    deepest_link: str | None = None
    deepest_link_mm: float | None = None
    grip_force_n: float | None = None
    grip_force_limit_n: float | None = None


@dataclass(frozen=True)
class Closure:
    """A glove placement's recording-quality numbers (None where the placement has none).

    Attributes:
        fit_fraction: The flexion fraction of the recorded closing at which the object fits.
        grip_normal_force_n: The normal force of the placement's grip test, N.
        grip_servo_torque_nm: The servo torque of that test, N·m.
        grip_directions_held: Gravity directions of six that grip resisted.
        self_penetration_at_closure_mm: The hand through itself at the closed frame, mm.
    """

    fit_fraction: float | None
    grip_normal_force_n: float | None
    grip_servo_torque_nm: float | None
    grip_directions_held: int | None
    self_penetration_at_closure_mm: float | None


@dataclass(frozen=True)
class Robustness:
    """The hold over the robustness ensemble and the grip at the release (None where not tested).

    Attributes:
        hold_robustness: Held members over judged members of the ensemble.
        hold_robustness_factors: The same per factor (held, judged, fraction).
        release_directions_held: Gravity directions of six held from the state at the release.
    """

    hold_robustness: float | None
    hold_robustness_factors: dict | None
    release_directions_held: int | None


@dataclass(frozen=True)
class HoldSection:
    """Everything the glove scenario judges about holding: outcome, grip, placement quality, robustness."""

    hold: HoldNumbers
    grip: GripNumbers
    closure: Closure
    robustness: Robustness

    def record(self) -> dict:
        """The record's hold entries, in the record's order."""
        parts = (self.hold, self.grip, self.closure, self.robustness)
        return {key: value for part in parts for key, value in _record(part).items()}


@dataclass(frozen=True)
class StabilityNumbers:
    """The grasp stability tests asked for (``ReplayConfig.stability_at``).

    Attributes:
        stable: Every gravity direction held.
        simulation_displacement_mm: ObMan's simulation displacement, mm (None where not measured).
    """

    stable: bool
    simulation_displacement_mm: float | None


@dataclass(frozen=True)
class ReplaySummary:
    """A replay's summary by section; :meth:`to_dict` is the record's ``summary``.

    Attributes:
        numbers: What the per-frame metrics give.
        hand_only: A scene without objects: why nothing is judged, and the hand through itself; else None.
        diverged: The run stopped at a divergence.
        warnings: MuJoCo warnings during the run.
        track: Recorded objects: the verdict on their tracks, else None.
        valid: No plausibility flag makes the replay invalid.
        hold: The glove scenario's hold, grip, placement quality and robustness, else None.
        stability: The grasp stability tests when asked for and run, else None.
    """

    numbers: FrameNumbers
    hand_only: HandOnly | None
    diverged: bool
    warnings: int
    track: TrackSection | None
    valid: bool
    hold: HoldSection | None = None
    stability: StabilityNumbers | None = None

    @property
    def hold_reason(self) -> str | None:
        """Why the hold was lost or not judged (a glove hold's, or a scene without objects'), else None."""
        if self.hold is not None:
            return self.hold.hold.hold_reason
        return None if self.hand_only is None else self.hand_only.hold_reason

    def to_dict(self) -> dict:
        """The record's ``summary`` (JSON-ready; SI-derived units in the key names)."""
        found = self.numbers.record()
        if self.hand_only is not None:
            found.update(_record(self.hand_only))
        found.update(diverged=self.diverged, warnings=self.warnings)
        if self.track is not None:
            found.update(self.track.record())
        found["valid"] = self.valid
        if self.hold is not None:
            found.update(self.hold.record())
        if self.stability is not None:
            found.update(_record(self.stability))
        return found
