"""What ``handsim replay`` prints about one replayed trial: its files, checks, summary and verdicts."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from handsim.sim.grip_check import GripCheck

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


def print_trial(loaded) -> None:
    """What was loaded: the trial's files, hand, objects and the loaders' notes."""
    trial = loaded.trial
    print_line("trial", f"{trial.kind}  {trial.trajectory_path}")
    print_line("hand", loaded.hand)
    for obj in loaded.objects:
        track = f", follows track {obj.track!r}" if obj.track else ""
        print_line("object", f"{obj.name} ({obj.origin}{track}), {obj.mass * 1000:.1f} g")
    print_checks(loaded)


def print_checks(loaded) -> None:
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


def print_summary(result) -> None:
    """Everything a replay measured and judged, one labelled line per finding."""
    # lazy: the simulation stack (MuJoCo), only after a replay
    from handsim.sim.summary import HAND_KEYS

    s = result.summary
    scene = result.scene
    print_line("scenario", scene["scenario"])
    print_line(
        "frames",
        f"{s['frames']} at {1.0 / result.frame_dt:g} Hz ({result.substeps} steps of "
        f"{result.frame_dt / result.substeps * 1000:g} ms), {s['duration_s']:.2f} s",
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
    if s["max_penetration_mm"] is None:
        print_line("penetration", s.get("hold_reason") or "not judged: no object")
    else:
        print_line(
            "penetration",
            f"max {s['max_penetration_mm']:.2f} mm, p95 {s['p95_penetration_mm']:.2f} mm, "
            f"{s['frames_penetrating_over_1mm']} frames over 1 mm",
        )
        print_line(
            "contact",
            f"{s['contact_frames']} of {s['frames']} frames; up to {s['max_contact_links']} links at once; "
            f"peak total normal force {s['max_total_normal_force_n']:.2f} N",
        )
    print_line(
        "tracking",
        f"mean {num(s['mean_tracking_error_deg'])}°, max {num(s['max_tracking_error_deg'])}° (joint angle)",
    )
    print_line(
        "tips", f"mean {num(s['mean_tip_error_mm'], '.1f')} mm, max {num(s['max_tip_error_mm'], '.1f')} mm"
    )
    limits = next((f for f in result.flags if f.code == "joint_limits"), None)
    print_line(
        "limits",
        "no target beyond the joint limits"
        if limits is None
        else f"{limits.values['samples']} target samples beyond the joint limits in "
        f"{len(limits.values['dofs'])} DoFs (flag joint_limits above)",
    )
    if "max_self_penetration_mm" in s:
        print_self_penetration(s)
    for hand in (h for h in ("right", "left") if f"{h}/contact_frames" in s):
        h = {key: s[f"{hand}/{key}"] for key in HAND_KEYS}
        touch = (
            ""
            if h["contact_frames"] is None  # no object: the penetration line says why
            else f"contact {h['contact_frames']} frames (up to {h['max_contact_links']} links, "
            f"{h['max_total_normal_force_n']:.2f} N); penetration max {h['max_penetration_mm']:.2f} mm; "
        )
        start = s.get(f"{hand}/start_penetration_mm")
        print_line(
            hand,
            f"{touch}tracking mean {num(h['mean_tracking_error_deg'])}°; "
            f"tips mean {num(h['mean_tip_error_mm'], '.1f')} mm"
            + ("" if start is None else f"; starts {start:.1f} mm inside the object"),
        )
    if "mean_drift_mm" in s:
        tolerance = result.config["metrics"]["drift_tolerance"] * 100
        print_line(
            "drift",
            f"mean {num(s['mean_drift_mm'], '.1f')} mm, max {num(s['max_drift_mm'], '.1f')} mm, "
            f"final {num(s['final_drift_mm'], '.1f')} mm; within {tolerance:g} cm in "
            f"{s['within_tolerance'] * 100:.1f}% of frames",
        )
        mean, top = num(s["mean_rotation_drift_deg"], ".1f"), num(s["max_rotation_drift_deg"], ".1f")
        rotation = f"mean {mean}°, max {top}°"
        if s.get("max_articulation_drift_deg") is not None:
            rotation += f"; hinge max {s['max_articulation_drift_deg']:.1f}°"
        if s.get("mean_articulation_drift_deg") is not None:
            mean, final = s["mean_articulation_drift_deg"], s["final_articulation_drift_deg"]
            rotation += f", mean {mean:.1f}°, final {final:.1f}°"
        print_line("rotation", rotation)
    if "track" in s:
        print_track(s)
    placement = scene.get("placement") or {}
    if placement:
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
        if scene.get("contact_frame", 0) > 0:
            print_line(
                "contacts",
                f"hand–object contacts act from {result.frames.times[scene['contact_frame']]:.2f} s "
                "(before, the recorded hand reaches through where the object is placed)",
            )
    hold = result.hold
    if hold is None and "hold_reason" in s:
        print_line("held", s["hold_reason"])
        print_line("drift", s["drift_reason"])
    if hold is not None:
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
    if result.grip is not None:
        print_grip(result.grip, result.config["metrics"]["grip"])
    robustness = result.robustness
    if robustness is not None:
        lost = [m.label for m in robustness.members if m.held is False]
        unjudged = [m for m in robustness.members if m.held is None]
        factors = "; ".join(
            f"{factor} {counts['held']} of {counts['judged']}"
            for factor, counts in robustness.factors().items()
        )
        print_line(
            "robustness",
            f"{num(robustness.fraction)}: {robustness.held} of {robustness.judged} ensemble members held "
            f"({factors}: the winner, the next best placements, the winner moved ±2 mm and turned ±5°, the "
            "undriven DoFs turned and the sensors offset)" + (f"; lost: {', '.join(lost)}" if lost else ""),
        )
        for member in unjudged:
            print_line("", f"{member.label}: {(member.reason or 'not judged').removeprefix('not judged: ')}")
    if result.release_stability is not None:
        directions = result.release_stability.directions
        held = [d.direction for d in directions if d.success]
        down = (result.scene.get("placement") or {}).get("gravity_along", "-z")
        print_line(
            "at release",
            f"{len(held)} of {len(directions)} gravity directions held ({', '.join(held) or 'none'}); "
            + (
                "the hold itself is judged palm down"
                if down == "-z"
                else f"the hold itself is judged with gravity along the grip's {down} (hand turned)"
            ),
        )
    stability = result.stability
    if stability is not None:
        passed = sum(d.success for d in stability.directions)
        displacement = stability.simulation_displacement
        moved = None if displacement is None else displacement * 1000
        print_line(
            "stability",
            f"{'stable' if stability.success else 'not stable'} ({passed} of {len(stability.directions)} "
            f"gravity directions held); ObMan displacement {num(moved, '.1f')} mm",
        )


def print_track(s: dict) -> None:
    """The verdict on a recorded object's track: followed, lost at t (how), or not judged (why)."""
    line = s["track_reason"]
    fraction, frames = s.get("track_followed_fraction"), s.get("track_manipulated_frames")
    if fraction is not None:
        line += f" [within tolerance in {fraction * 100:.1f}% of {frames} manipulated frames]"
    print_line("track", line)


def print_self_penetration(s: dict) -> None:
    """The hand through itself (scenes without objects), simulated and at the recorded targets."""

    def deepest(key: str) -> str:
        links = s[f"{key}_links"]
        return "" if links is None else f" ({' | '.join(links)} at {s[f'{key}_at_s']:.2f} s)"

    print_line(
        "self-pen.",
        f"max {s['max_self_penetration_mm']:.2f} mm{deepest('self_penetration')}, p95 "
        f"{s['p95_self_penetration_mm']:.2f} mm, {s['frames_self_penetrating_over_1mm']} frames over 1 mm "
        "(simulated hand through itself)",
    )
    print_line(
        "",
        f"max {s['max_target_self_penetration_mm']:.2f} mm{deepest('target_self_penetration')} "
        "at the recorded targets",
    )


def episode_line(result) -> str:
    """One episode's verdict in a line: held or why not, robustness, the grip's check."""
    s = result.summary
    hold = result.hold
    if hold is None or hold.held is None:
        verdict = (hold.reason if hold is not None else s.get("hold_reason")) or "not judged"
    elif hold.held:
        verdict = f"held {hold.time_held:.2f} s, robustness {num(s.get('hold_robustness'))}"
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
