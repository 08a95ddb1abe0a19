"""What ``handsim replay`` prints about one replayed trial: its files, checks, summary and verdicts."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from handsim.sim.grip_check import GripCheck
    from handsim.sim.placement.robustness import HoldRobustness
    from handsim.sim.result import ReplayResult
    from handsim.sim.sections import HandOnly, ObjectDrift, ReplaySummary
    from handsim.sim.stability.gravity import StabilityResult
    from handsim.sim.track import TrackVerdict
    from handsim.trials.base import LoadedTrial

LABEL = 12  # width of the label column
PHASE_SOURCES = {
    "episode": "its grasp episode: closed where the hold starts, held to the hold's end",
    "phase": "the annotated 'grasp' phase",
    "peak flexion": "the finger flexion (no annotation used: the frames around peak flexion)",
}
"""How the replay summary names a glove trial's phase source (:attr:`GraspFrame.source`)."""


def print_grip(grip: GripCheck, limits: dict) -> None:
    """The grip check's lines: what touched, what opposed, the deepest link, the force against the servos."""
    pair = " against ".join(grip.opposing_links) if grip.opposing_links else "no opposing pair"
    share = "—" if grip.opposition is None else f"{grip.opposition:.0%}"
    print_line(
        "grip check",
        f"{', '.join(grip.links) or 'no link'} touching over {grip.window[0]:.2f}–{grip.window[1]:.2f} s; "
        f"opposition in {share} of {grip.frames} frames ({pair}; at least "
        f"{limits['min_opposition']:.0%} needed)",
    )
    deepest = "no link inside the object"
    if grip.deepest_link is not None:
        deepest = f"{grip.deepest_link} {grip.max_depth * 1000:.1f} mm inside at {grip.deepest_at:.2f} s"
    print_line(
        "",
        f"deepest: {deepest} (at most {grip.depth_limit * 1000:.3g} mm); grip force {grip.grip_force:.1f} N "
        f"against the servos' {grip.force_limit:.1f} N + weight {grip.weight:.2f} N",
    )


def print_line(label: str, text: str) -> None:
    """Print one labelled line (the label in a fixed-width column)."""
    print(f"{label:<{LABEL}}{text}")


def num(value: float | None, fmt: str = ".2f", unit: str = "") -> str:
    """A number in ``fmt`` with its unit, or ``n/a`` when there is none."""
    return "n/a" if value is None else f"{value:{fmt}}{unit}"


def print_trial(loaded: LoadedTrial) -> None:
    """What was loaded: the trial's files, hand, objects and the loaders' notes."""
    trial = loaded.trial
    print_line("trial", f"{trial.kind}  {trial.trajectory_path}")
    print_line("hand", loaded.hand)
    for obj in loaded.objects:
        track = f", follows track {obj.track!r}" if obj.track else ""
        print_line("object", f"{obj.name} ({obj.origin}{track}), {obj.mass * 1000:.1f} g")
    print_checks(loaded)


def print_checks(loaded: LoadedTrial) -> None:
    """Which annotation and phase source a glove trial used, and the spikes filled in its recording."""
    # lazy: the record stack (MuJoCo), only after a replay
    from handsim.runner.trial_record import recording_checks

    found = recording_checks(loaded.checks, loaded.scene)
    if loaded.checks is not None:
        print_line("annotation", loaded.checks.annotation.note)
    if found["phase_source"] is not None:
        print_line("phases", f"grasp from {PHASE_SOURCES.get(found['phase_source'], found['phase_source'])}")
    episode = loaded.episode
    if episode is not None:
        origin = "the annotated 'grasp' phase" if episode.source == "annotation" else "the finger flexion"
        print_line(
            "episode",
            f"{episode.index}: frames {episode.start}–{episode.stop - 1} of the recording, its hold from "
            f"{origin}; times below are the episode's own, from its first frame",
        )
    if loaded.checks is not None:
        print_line("spikes", loaded.checks.spike_text())


def print_summary(result: ReplayResult) -> None:
    """Everything a replay measured and judged, one labelled line per finding."""
    measured = result.measured
    _print_run(result)
    _print_contacts(measured)
    _print_tracking(result)
    if measured.hand_only is not None:
        print_self_penetration(measured.hand_only)
    _print_hands(measured)
    if measured.numbers.drift is not None:
        _print_drift(measured.numbers.drift, result.config["metrics"]["drift_tolerance"])
    if measured.track is not None:
        print_track(measured.track.verdict)
    placement = result.scene.get("placement") or {}
    if placement:
        _print_placement(result, placement)
    _print_hold(result, placement)
    if result.grip is not None:
        print_grip(result.grip, result.config["metrics"]["grip"])
    if result.robustness is not None:
        _print_robustness(result.robustness)
    if result.release_stability is not None:
        _print_release_stability(result.release_stability, placement)
    if result.stability is not None:
        _print_stability(result.stability)


def episode_line(result: ReplayResult) -> str:
    """One episode's verdict in a line: held or why not, robustness, the grip's check."""
    measured = result.measured
    hold = result.hold
    if hold is None or hold.held is None:
        verdict = (hold.reason if hold is not None else measured.hold_reason) or "not judged"
    elif hold.held:
        robustness = None if measured.hold is None else measured.hold.robustness.hold_robustness
        verdict = f"held {hold.time_held:.2f} s, robustness {num(robustness)}"
    else:
        verdict = f"not held: lost at {hold.lost_at:.2f} s ({hold.reason})"
    grip = result.grip
    if grip is not None and hold is not None and hold.held is not None:
        pair = " against ".join(grip.opposing_links) if grip.opposing_links else "no opposing pair"
        verdict += (
            f"; grip {pair} in {grip.opposition or 0:.0%} of the window, deepest "
            f"{grip.max_depth * 1000:.1f} mm, {grip.grip_force:.1f} N of ≤ {grip.force_limit:.0f} N"
        )
    return verdict


def _print_run(result: ReplayResult) -> None:
    """The scenario, the frames simulated, the warnings, the divergence and the plausibility flags."""
    numbers = result.measured.numbers
    print_line("scenario", result.scene["scenario"])
    print_line(
        "frames",
        f"{numbers.frames} at {1.0 / result.frame_dt:g} Hz ({result.substeps} steps of "
        f"{result.frame_dt / result.substeps * 1000:g} ms), {numbers.duration_s:.2f} s",
    )
    if result.warnings:
        names = sorted({w.name for w in result.warnings})
        print_line(
            "warnings", f"{len(result.warnings)} ({', '.join(names)}); first: {result.warnings[0].describe()}"
        )
    else:
        print_line("warnings", "none")
    if result.diverged is not None:
        d = result.diverged
        at = result.frames.times[-1] if result.frames.times.size else 0.0
        said = f"; MuJoCo: {d.message}" if d.message else ""
        print_line(
            "DIVERGED",
            f"{d.name} at step {d.step} (frame {d.frame}, after t = {at:.3f} s, info {d.info}){said}",
        )
        print_line("", "the numbers below cover the frames before the divergence")
    else:
        print_line("diverged", "no")
    invalid = [f.code for f in result.flags if f.invalid]
    print_line("valid", f"no ({', '.join(invalid)}): the numbers below judge nothing" if invalid else "yes")
    for flag in result.flags:
        print_line("flag", flag.line())


def _print_contacts(measured: ReplaySummary) -> None:
    """Hand–object penetration and contacts, or why there are none (no object)."""
    contacts = measured.numbers.contacts
    if contacts.max_penetration_mm is None:
        print_line("penetration", measured.hold_reason or "not judged: no object")
        return
    print_line(
        "penetration",
        f"max {contacts.max_penetration_mm:.2f} mm, p95 {contacts.p95_penetration_mm:.2f} mm, "
        f"{contacts.frames_penetrating_over_1mm} frames over 1 mm",
    )
    print_line(
        "contact",
        f"{contacts.contact_frames} of {measured.numbers.frames} frames; up to {contacts.max_contact_links} "
        f"links at once; peak total normal force {contacts.max_total_normal_force_n:.2f} N",
    )


def _print_tracking(result: ReplayResult) -> None:
    """Joint and fingertip tracking, and the targets beyond the joint limits."""
    tracking = result.measured.numbers.tracking
    print_line(
        "tracking",
        f"mean {num(tracking.mean_tracking_error_deg)}°, max {num(tracking.max_tracking_error_deg)}° "
        "(joint angle)",
    )
    print_line(
        "tips",
        f"mean {num(tracking.mean_tip_error_mm, '.1f')} mm, max {num(tracking.max_tip_error_mm, '.1f')} mm",
    )
    limits = next((f for f in result.flags if f.code == "joint_limits"), None)
    print_line(
        "limits",
        "no target beyond the joint limits"
        if limits is None
        else f"{limits.values['samples']} target samples beyond the joint limits in "
        f"{len(limits.values['dofs'])} DoFs (flag joint_limits above)",
    )


def _print_hands(measured: ReplaySummary) -> None:
    """Each hand's line in a scene with several (right first), with its starting penetration."""
    hands = {h.hand: h for h in measured.numbers.hands}
    start_of = {} if measured.track is None else measured.track.start_penetration_mm
    for name in (n for n in ("right", "left") if n in hands):
        h = hands[name]
        touch = (
            ""
            if h.contact_frames is None  # no object: the penetration line says why
            else f"contact {h.contact_frames} frames (up to {h.max_contact_links} links, "
            f"{h.max_total_normal_force_n:.2f} N); penetration max {h.max_penetration_mm:.2f} mm; "
        )
        start = start_of.get(name)
        print_line(
            name,
            f"{touch}tracking mean {num(h.mean_tracking_error_deg)}°; "
            f"tips mean {num(h.mean_tip_error_mm, '.1f')} mm"
            + ("" if start is None else f"; starts {start:.1f} mm inside the object"),
        )


def _print_drift(drift: ObjectDrift, tolerance_m: float) -> None:
    """Recorded objects against their tracks: position, rotation and hinge."""
    tolerance = tolerance_m * 100
    print_line(
        "drift",
        f"mean {num(drift.mean_drift_mm, '.1f')} mm, max {num(drift.max_drift_mm, '.1f')} mm, "
        f"final {num(drift.final_drift_mm, '.1f')} mm; within {tolerance:g} cm in "
        f"{drift.within_tolerance * 100:.1f}% of frames",
    )
    mean, top = num(drift.mean_rotation_drift_deg, ".1f"), num(drift.max_rotation_drift_deg, ".1f")
    rotation = f"mean {mean}°, max {top}°"
    if drift.max_articulation_drift_deg is not None:
        rotation += f"; hinge max {drift.max_articulation_drift_deg:.1f}°"
    hinge = drift.hinge
    if hinge is not None and hinge.mean_articulation_drift_deg is not None:
        mean, final = hinge.mean_articulation_drift_deg, hinge.final_articulation_drift_deg
        rotation += f", mean {mean:.1f}°, final {final:.1f}°"
    print_line("rotation", rotation)


def _print_placement(result: ReplayResult, placement: dict) -> None:
    """Where a glove trial's object was placed, the grip the recorded closing makes, when contacts act."""
    links = placement.get("links", [])
    grasp = placement.get("grasp", {})
    grip = placement.get("grip") or {}
    print_line(
        "placement",
        f"fits at frame {placement.get('fit_frame')} "
        f"(flexion fraction {placement.get('fit_fraction', 0):.2f} of the closing "
        f"{grasp.get('open')}–{grasp.get('closed')}, {grasp.get('source')}), "
        f"{len(links)} links touching ({', '.join(links)}), penetration "
        f"{placement.get('penetration_m', 0.0) * 1000:.2f} mm"
        + ("" if placement.get("feasible", True) else "; INFEASIBLE"),
    )
    if grip:
        print_line(
            "grip",
            f"the recorded closing presses with {grip['normal_force_n']:.1f} N (servo torque "
            f"{grip['servo_torque_nm']:.2f} N·m); it resists {grip['directions_held']} of 6 gravity "
            f"directions; best of {placement.get('grip_tests')} grip tests, "
            f"{placement.get('candidates')} poses tried",
        )
    scene = result.scene
    if scene.get("contact_frame", 0) > 0:
        print_line(
            "contacts",
            f"hand–object contacts act from {result.frames.times[scene['contact_frame']]:.2f} s "
            "(before, the recorded hand reaches through where the object is placed)",
        )


def _print_hold(result: ReplayResult, placement: dict) -> None:
    """The glove hold: the release, held or why not, slip and drop; a scene without objects: why none."""
    hold = result.hold
    hand_only = result.measured.hand_only
    if hold is None and hand_only is not None:
        print_line("held", hand_only.hold_reason)
        print_line("drift", hand_only.drift_reason)
    if hold is None:
        return
    print_line(
        "release",
        f"at {hold.released_at:.2f} s (grasp closed at frame {placement.get('grasp', {}).get('closed')}, "
        f"+ {result.config['metrics']['release_delay']:g} s); hold window "
        f"{hold.window[0]:.2f}–{hold.window[1]:.2f} s",
    )
    if hold.held is None:
        print_line("held", hold.reason or "not judged")
    else:
        verdict = "yes" if hold.held else f"no: lost at {hold.lost_at:.2f} s ({hold.reason})"
        print_line("held", f"{verdict}; held {hold.time_held:.2f} s")
        print_line("slip", f"max {hold.max_slip * 1000:.1f} mm relative to the hand")
        print_line("drop", f"{hold.drop * 1000:.1f} mm (object origin, release to the window's end)")


def _print_robustness(robustness: HoldRobustness) -> None:
    """The hold over the robustness ensemble: held of judged, per factor, the members lost or not judged."""
    lost = [m.label for m in robustness.members if m.held is False]
    unjudged = [m for m in robustness.members if m.held is None]
    factors = "; ".join(
        f"{factor} {counts['held']} of {counts['judged']}" for factor, counts in robustness.factors().items()
    )
    print_line(
        "robustness",
        f"{num(robustness.fraction)}: {robustness.held} of {robustness.judged} ensemble members held "
        f"({factors}: the winner, the next best placements, the winner moved ±2 mm and turned ±5°, the "
        "undriven DoFs turned and the sensors offset)" + (f"; lost: {', '.join(lost)}" if lost else ""),
    )
    for member in unjudged:
        print_line("", f"{member.label}: {(member.reason or 'not judged').removeprefix('not judged: ')}")


def _print_release_stability(stability: StabilityResult, placement: dict) -> None:
    """The grip at the release against six gravity directions, and which one the hold is judged with."""
    directions = stability.directions
    held = [d.direction for d in directions if d.success]
    down = placement.get("gravity_along", "-z")
    print_line(
        "at release",
        f"{len(held)} of {len(directions)} gravity directions held ({', '.join(held) or 'none'}); "
        + (
            "the hold itself is judged palm down"
            if down == "-z"
            else f"the hold itself is judged with gravity along the grip's {down} (hand turned)"
        ),
    )


def _print_stability(stability: StabilityResult) -> None:
    """The grasp stability tests asked for (``--stability``)."""
    passed = sum(d.success for d in stability.directions)
    displacement = stability.simulation_displacement
    moved = None if displacement is None else displacement * 1000
    print_line(
        "stability",
        f"{'stable' if stability.success else 'not stable'} ({passed} of {len(stability.directions)} "
        f"gravity directions held); ObMan displacement {num(moved, '.1f')} mm",
    )


def print_track(verdict: TrackVerdict) -> None:
    """The verdict on a recorded object's track: followed, lost at t (how), or not judged (why)."""
    line = verdict.reason
    if verdict.followed_fraction is not None:
        line += (
            f" [within tolerance in {verdict.followed_fraction * 100:.1f}% of {verdict.manipulated_frames} "
            "manipulated frames]"
        )
    print_line("track", line)


def print_self_penetration(hand_only: HandOnly) -> None:
    """The hand through itself (scenes without objects), simulated and at the recorded targets."""

    def deepest(links: tuple[str, ...] | None, at_s: float | None) -> str:
        return "" if links is None else f" ({' | '.join(links)} at {at_s:.2f} s)"

    h = hand_only
    print_line(
        "self-pen.",
        f"max {h.max_self_penetration_mm:.2f} mm"
        f"{deepest(h.self_penetration_links, h.self_penetration_at_s)}, p95 "
        f"{h.p95_self_penetration_mm:.2f} mm, {h.frames_self_penetrating_over_1mm} frames over 1 mm "
        "(simulated hand through itself)",
    )
    print_line(
        "",
        f"max {h.max_target_self_penetration_mm:.2f} mm"
        f"{deepest(h.target_self_penetration_links, h.target_self_penetration_at_s)} at the recorded targets",
    )
