"""``handsim replay``: replay a recorded trial in MuJoCo and print how physical it was.

Exit codes: 0 replayed; 1 a handsim error (bad file, trajectory that does not fit the hand …);
2 a usage error, including a file that is no kind of trial and options that do not apply to it;
3 the simulation diverged (the summary covers the frames before the divergence, which is named);
4 replayed but not valid: a plausibility flag says the numbers mean nothing (one line per flag on stderr).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from typing import TYPE_CHECKING

from handsim.cli._common import (
    Commands,
    add_arctic_options,
    add_control_rate,
    add_force,
    add_object_mass_options,
    output_file,
    positive_number,
    usage_error,
    write_text,
)
from handsim.runner.records import json_ready

if TYPE_CHECKING:
    from handsim.sim.grip_check import GripCheck

EXIT_DIVERGED = 3
EXIT_NOT_VALID = 4
LABEL = 12  # width of the label column


def _print_grip(grip: GripCheck, limits: dict) -> None:
    """The grip check's lines: what touched, what opposed, the deepest link, the force against the servos."""
    pair = " against ".join(grip.opposing_links) if grip.opposing_links else "no opposing pair"
    share = "—" if grip.opposition is None else f"{grip.opposition:.0%}"
    _line(
        "grip check",
        f"{', '.join(grip.links) or 'no link'} touching over {grip.window[0]:.2f}–{grip.window[1]:.2f} s; "
        f"opposition in {share} of {grip.frames} frames ({pair}; at least "
        f"{limits['min_opposition']:.0%} needed)",
    )
    deepest = "no link inside the object"
    if grip.deepest_link is not None:
        deepest = f"{grip.deepest_link} {grip.max_depth * 1000:.1f} mm inside at {grip.deepest_at:.2f} s"
    _line(
        "",
        f"deepest: {deepest} (at most {grip.depth_limit * 1000:.3g} mm); grip force {grip.grip_force:.1f} N "
        f"against the servos' {grip.force_limit:.1f} N + weight {grip.weight:.2f} N",
    )


def _line(label: str, text: str) -> None:
    print(f"{label:<{LABEL}}{text}")


def _num(value: float | None, fmt: str = ".2f", unit: str = "") -> str:
    return "n/a" if value is None else f"{value:{fmt}}{unit}"


def _print_trial(loaded) -> None:
    trial = loaded.trial
    _line("trial", f"{trial.kind}  {trial.trajectory_path}")
    _line("hand", loaded.hand)
    for obj in loaded.objects:
        track = f", follows track {obj.track!r}" if obj.track else ""
        _line("object", f"{obj.name} ({obj.origin}{track}), {obj.mass * 1000:.1f} g")
    _print_checks(loaded)


PHASE_SOURCES = {
    "episode": "its grasp episode: closed where the hold starts, held to the hold's end",
    "phase": "the annotated 'grasp' phase",
    "peak flexion": "the finger flexion (no annotation used: the frames around peak flexion)",
}
"""How the replay summary names a glove trial's phase source (:attr:`GraspFrame.source`)."""


def _print_checks(loaded) -> None:
    """Which annotation and phase source a glove trial used, and the spikes filled in its recording."""
    # lazy: the record stack (MuJoCo), only after a replay
    from handsim.runner.trial_record import recording_checks

    found = recording_checks(loaded.checks, loaded.scene)
    if loaded.checks is not None:
        _line("annotation", loaded.checks.annotation.note)
    if found["phase_source"] is not None:
        _line("phases", f"grasp from {PHASE_SOURCES.get(found['phase_source'], found['phase_source'])}")
    episode = loaded.episode
    if episode is not None:
        origin = "the annotated 'grasp' phase" if episode.source == "annotation" else "the finger flexion"
        _line(
            "episode",
            f"{episode.index}: frames {episode.start}–{episode.stop - 1} of the recording, its hold from "
            f"{origin}; times below are the episode's own, from its first frame",
        )
    if loaded.checks is not None:
        _line("spikes", loaded.checks.spike_text())


def _print_summary(result) -> None:
    # lazy: the simulation stack (MuJoCo), only after a replay
    from handsim.sim.summary import HAND_KEYS

    s = result.summary
    scene = result.scene
    _line("scenario", scene["scenario"])
    _line(
        "frames",
        f"{s['frames']} at {1.0 / result.frame_dt:g} Hz ({result.substeps} steps of "
        f"{result.frame_dt / result.substeps * 1000:g} ms), {s['duration_s']:.2f} s",
    )
    if result.warnings:
        names = sorted({w.name for w in result.warnings})
        _line(
            "warnings", f"{len(result.warnings)} ({', '.join(names)}); first: {result.warnings[0].describe()}"
        )
    else:
        _line("warnings", "none")
    if result.diverged is not None:
        d = result.diverged
        at = result.frames.times[-1] if result.frames.times.size else 0.0
        said = f"; MuJoCo: {d.message}" if d.message else ""
        _line(
            "DIVERGED",
            f"{d.name} at step {d.step} (frame {d.frame}, after t = {at:.3f} s, info {d.info}){said}",
        )
        _line("", "the numbers below cover the frames before the divergence")
    else:
        _line("diverged", "no")
    invalid = [f.code for f in result.flags if f.invalid]
    _line("valid", f"no ({', '.join(invalid)}): the numbers below judge nothing" if invalid else "yes")
    for flag in result.flags:
        _line("flag", flag.line())
    if s["max_penetration_mm"] is None:
        _line("penetration", s.get("hold_reason") or "not judged: no object")
    else:
        _line(
            "penetration",
            f"max {s['max_penetration_mm']:.2f} mm, p95 {s['p95_penetration_mm']:.2f} mm, "
            f"{s['frames_penetrating_over_1mm']} frames over 1 mm",
        )
        _line(
            "contact",
            f"{s['contact_frames']} of {s['frames']} frames; up to {s['max_contact_links']} links at once; "
            f"peak total normal force {s['max_total_normal_force_n']:.2f} N",
        )
    _line(
        "tracking",
        f"mean {_num(s['mean_tracking_error_deg'])}°, max {_num(s['max_tracking_error_deg'])}° (joint angle)",
    )
    _line(
        "tips", f"mean {_num(s['mean_tip_error_mm'], '.1f')} mm, max {_num(s['max_tip_error_mm'], '.1f')} mm"
    )
    limits = next((f for f in result.flags if f.code == "joint_limits"), None)
    _line(
        "limits",
        "no target beyond the joint limits"
        if limits is None
        else f"{limits.values['samples']} target samples beyond the joint limits in "
        f"{len(limits.values['dofs'])} DoFs (flag joint_limits above)",
    )
    if "max_self_penetration_mm" in s:
        _print_self_penetration(s)
    for hand in (h for h in ("right", "left") if f"{h}/contact_frames" in s):
        h = {key: s[f"{hand}/{key}"] for key in HAND_KEYS}
        touch = (
            ""
            if h["contact_frames"] is None  # no object: the penetration line says why
            else f"contact {h['contact_frames']} frames (up to {h['max_contact_links']} links, "
            f"{h['max_total_normal_force_n']:.2f} N); penetration max {h['max_penetration_mm']:.2f} mm; "
        )
        start = s.get(f"{hand}/start_penetration_mm")
        _line(
            hand,
            f"{touch}tracking mean {_num(h['mean_tracking_error_deg'])}°; "
            f"tips mean {_num(h['mean_tip_error_mm'], '.1f')} mm"
            + ("" if start is None else f"; starts {start:.1f} mm inside the object"),
        )
    if "mean_drift_mm" in s:
        tolerance = result.config["metrics"]["drift_tolerance"] * 100
        _line(
            "drift",
            f"mean {_num(s['mean_drift_mm'], '.1f')} mm, max {_num(s['max_drift_mm'], '.1f')} mm, "
            f"final {_num(s['final_drift_mm'], '.1f')} mm; within {tolerance:g} cm in "
            f"{s['within_tolerance'] * 100:.1f}% of frames",
        )
        mean, top = _num(s["mean_rotation_drift_deg"], ".1f"), _num(s["max_rotation_drift_deg"], ".1f")
        rotation = f"mean {mean}°, max {top}°"
        if s.get("max_articulation_drift_deg") is not None:
            rotation += f"; hinge max {s['max_articulation_drift_deg']:.1f}°"
        if s.get("mean_articulation_drift_deg") is not None:
            mean, final = s["mean_articulation_drift_deg"], s["final_articulation_drift_deg"]
            rotation += f", mean {mean:.1f}°, final {final:.1f}°"
        _line("rotation", rotation)
    if "track" in s:
        _print_track(s)
    placement = scene.get("placement") or {}
    if placement:
        links = placement.get("links", [])
        grasp = placement.get("grasp", {})
        grip = placement.get("grip") or {}
        _line(
            "placement",
            f"fits at frame {placement.get('fit_frame')} "
            f"(flexion fraction {placement.get('fit_fraction', 0):.2f} of the closing "
            f"{grasp.get('open')}–{grasp.get('closed')}, {grasp.get('source')}), "
            f"{len(links)} links touching ({', '.join(links)}), penetration "
            f"{placement.get('penetration_m', 0.0) * 1000:.2f} mm"
            + ("" if placement.get("feasible", True) else "; INFEASIBLE"),
        )
        if grip:
            _line(
                "grip",
                f"the recorded closing presses with {grip['normal_force_n']:.1f} N (servo torque "
                f"{grip['servo_torque_nm']:.2f} N·m); it resists {grip['directions_held']} of 6 gravity "
                f"directions; best of {placement.get('grip_tests')} grip tests, "
                f"{placement.get('candidates')} poses tried",
            )
        if scene.get("contact_frame", 0) > 0:
            _line(
                "contacts",
                f"hand–object contacts act from {result.frames.times[scene['contact_frame']]:.2f} s "
                "(before, the recorded hand reaches through where the object is placed)",
            )
    hold = result.hold
    if hold is None and "hold_reason" in s:
        _line("held", s["hold_reason"])
        _line("drift", s["drift_reason"])
    if hold is not None:
        _line(
            "release",
            f"at {hold.released_at:.2f} s (grasp closed at frame {placement.get('grasp', {}).get('closed')}, "
            f"+ {result.config['metrics']['release_delay']:g} s); hold window "
            f"{hold.window[0]:.2f}–{hold.window[1]:.2f} s",
        )
        if hold.held is None:
            _line("held", hold.reason or "not judged")
        else:
            verdict = "yes" if hold.held else f"no: lost at {hold.lost_at:.2f} s ({hold.reason})"
            _line("held", f"{verdict}; held {hold.time_held:.2f} s")
            _line("slip", f"max {hold.max_slip * 1000:.1f} mm relative to the hand")
            _line("drop", f"{hold.drop * 1000:.1f} mm (object origin, release to the window's end)")
    if result.grip is not None:
        _print_grip(result.grip, result.config["metrics"]["grip"])
    robustness = result.robustness
    if robustness is not None:
        lost = [m.label for m in robustness.members if m.held is False]
        unjudged = [m for m in robustness.members if m.held is None]
        factors = "; ".join(
            f"{factor} {counts['held']} of {counts['judged']}"
            for factor, counts in robustness.factors().items()
        )
        _line(
            "robustness",
            f"{_num(robustness.fraction)}: {robustness.held} of {robustness.judged} ensemble members held "
            f"({factors}: the winner, the next best placements, the winner moved ±2 mm and turned ±5°, the "
            "undriven DoFs turned and the sensors offset)" + (f"; lost: {', '.join(lost)}" if lost else ""),
        )
        for member in unjudged:
            _line("", f"{member.label}: {(member.reason or 'not judged').removeprefix('not judged: ')}")
    if result.release_stability is not None:
        directions = result.release_stability.directions
        held = [d.direction for d in directions if d.success]
        down = (result.scene.get("placement") or {}).get("gravity_along", "-z")
        _line(
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
        _line(
            "stability",
            f"{'stable' if stability.success else 'not stable'} ({passed} of {len(stability.directions)} "
            f"gravity directions held); ObMan displacement {_num(moved, '.1f')} mm",
        )


def _print_track(s: dict) -> None:
    """The verdict on a recorded object's track: followed, lost at t (how), or not judged (why)."""
    line = s["track_reason"]
    fraction, frames = s.get("track_followed_fraction"), s.get("track_manipulated_frames")
    if fraction is not None:
        line += f" [within tolerance in {fraction * 100:.1f}% of {frames} manipulated frames]"
    _line("track", line)


def _thumb_rest(text: str) -> tuple[float, float]:
    """An argparse type: ``ABD,FLEX`` in degrees, two finite numbers (the joint limits are the loader's)."""
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected ABD,FLEX: two angles in degrees, got {text!r}")
    return values


def _print_self_penetration(s: dict) -> None:
    """The hand through itself (scenes without objects), simulated and at the recorded targets."""

    def deepest(key: str) -> str:
        links = s[f"{key}_links"]
        return "" if links is None else f" ({' | '.join(links)} at {s[f'{key}_at_s']:.2f} s)"

    _line(
        "self-pen.",
        f"max {s['max_self_penetration_mm']:.2f} mm{deepest('self_penetration')}, p95 "
        f"{s['p95_self_penetration_mm']:.2f} mm, {s['frames_self_penetrating_over_1mm']} frames over 1 mm "
        "(simulated hand through itself)",
    )
    _line(
        "",
        f"max {s['max_target_self_penetration_mm']:.2f} mm{deepest('target_self_penetration')} "
        "at the recorded targets",
    )


def _grasp_index(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a grasp episode number (1, 2 …), got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a grasp episode number ≥ 1, got {value}")
    return value


def _stability_at(text: str) -> float | str:
    if text == "grasp":
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'grasp' or a time in seconds, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"expected 'grasp' or a time ≥ 0 s, got {text}")
    return value


def _replay(args: argparse.Namespace) -> int:
    if args.video:
        # lazy: MuJoCo and the video encoders, only with --video
        from handsim.viz.render import check_video

        check_video(args.video, *args.size)  # before the replay: a missing encoder is known at once
    # lazy: the simulation stack (MuJoCo, trimesh), only when replaying
    from handsim.sim.replay import ReplayConfig
    from handsim.trials import TrialError
    from handsim.trials.registry import find_trial

    config = ReplayConfig(control_rate=args.rate, keep_states=bool(args.video), stability_at=args.stability)
    try:
        trial = find_trial(
            args.trajectory,
            grasp=args.grasp,
            skeleton=args.skeleton,
            obj=args.object,
            calibration=args.calibration,
            units=args.units,
            density=args.density,
            mass=args.mass,
            hand_length=args.hand_length,
            collision=args.collision,
            thumb_rest=args.thumb_rest,
            force=args.force,
            mano_dir=args.mano_dir,
            templates=args.templates,
        )
        if args.grasp is None:
            trial, segmentation = _episodes(trial)
            if segmentation is not None and len(segmentation.complete) > 1:
                return _replay_episodes(args, trial, segmentation, config)
        return _replay_trial(args, trial, config)
    except TrialError as exc:
        return usage_error("replay", str(exc))


def _episodes(trial):
    """A glove trial's segmentation, and the trial of its one complete episode when it has exactly one.

    With none, the trial stays the whole recording: its replay measures the hand, and its hold is not
    judged, with the reason.
    """
    # lazy: the trial registry's readers, only when replaying
    from handsim.trials.registry import grasp_episodes, kind_named

    if kind_named(trial.kind).read is None:
        return trial, None
    segmentation = grasp_episodes(trial)
    if len(segmentation.complete) == 1:
        return dataclasses.replace(trial, grasp=segmentation.complete[0].index), segmentation
    return trial, segmentation


def _replay_episodes(args: argparse.Namespace, trial, segmentation, config) -> int:
    """Judge every complete grasp episode of a glove recording: one line each and a total."""
    # lazy: the simulation stack, only when replaying
    from handsim.report.aggregate import ROBUST
    from handsim.sim.replay import replay
    from handsim.trials import load_trial

    _line("trial", f"{trial.kind}  {trial.trajectory_path}")
    for text in segmentation.lines():
        label, _, rest = text.partition(" ")
        _line(label if label != "episode" else "", text if label == "episode" else rest.strip())
    complete = segmentation.complete
    if args.plot or args.video or args.stability is not None:
        return usage_error(
            "replay", f"the recording holds {len(complete)} grasp episodes: choose one with --grasp K for "
            "--plot, --video or --stability",
        )  # fmt: skip
    records, outcomes = [], []
    for episode in complete:
        loaded = load_trial(
            dataclasses.replace(trial, grasp=episode.index), metrics=config.metrics, progress=True
        )
        result = replay(loaded.scene, loaded.trajectory, config)
        outcomes.append(result)
        _line(f"episode {episode.index}", _episode_line(result))
        if args.json:
            records.append(
                {**result.to_dict(), "trial": loaded.trial.to_dict(), "episode": episode.to_dict()}
            )
    held = sum(r.summary.get("held") is True for r in outcomes)
    lost = sum(r.summary.get("held") is False for r in outcomes)
    robust = sum(
        r.summary.get("held") is True and (r.summary.get("hold_robustness") or 0) >= ROBUST for r in outcomes
    )
    _line(
        "total",
        f"{len(complete)} complete episodes judged of {len(segmentation.episodes)}: held {held} ({robust} "
        f"with robustness ≥ {ROBUST:g}), not held {lost}, not judged {len(complete) - held - lost}; "
        "details of one: --grasp K",
    )
    if args.json:
        text = json.dumps(
            json_ready({"segmentation": segmentation.to_dict(), "episodes": records}),
            indent=1,
            allow_nan=False,
        )
        _line("wrote", str(write_text(args.json, text + "\n")))
    diverged = any(r.diverged is not None for r in outcomes)
    return EXIT_DIVERGED if diverged else 0


def _episode_line(result) -> str:
    """One episode's verdict in a line: held or why not, robustness, the grip's check."""
    s = result.summary
    hold = result.hold
    if hold is None or hold.held is None:
        verdict = (hold.reason if hold is not None else s.get("hold_reason")) or "not judged"
    elif hold.held:
        verdict = f"held {hold.time_held:.2f} s, robustness {_num(s.get('hold_robustness'))}"
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


def _replay_trial(args: argparse.Namespace, trial, config) -> int:
    """Replay one trial (a glove recording's one episode) and print everything about it."""
    # lazy: the simulation stack, only when replaying
    from handsim.sim.replay import replay
    from handsim.trials import load_trial

    loaded = load_trial(trial, metrics=config.metrics, progress=True)
    _print_trial(loaded)
    if args.stability is not None and len(loaded.scene.layout.hands) > 1:
        return usage_error("replay", "--stability tests hold one hand; this trial has two (ARCTIC)")
    if args.stability == "grasp" and loaded.scene.setup.hold_window is None:
        return usage_error("replay", "--stability grasp is for glove trials; give a time in s")
    end = float(loaded.trajectory.times[-1])
    what = "recording" if loaded.episode is None else f"grasp episode {loaded.episode.index}"
    if isinstance(args.stability, float) and args.stability > end:
        return usage_error(
            "replay",
            f"--stability {args.stability:g} s is after the {what}'s end ({end:.3f} s)",
        )
    result = replay(loaded.scene, loaded.trajectory, config)
    _print_summary(result)
    notes = [*loaded.notes, *loaded.scene.setup.notes, *result.notes]
    if args.verbose:
        notes = [*loaded.trajectory.notes, *notes]
    for note in notes:
        _line("note", note)
    if args.json:
        # lazy: the record stack, only with --json
        from handsim.runner.trial_record import recording_checks
        from handsim.viz.replay_plots import replay_curves

        record = {
            **result.to_dict(),
            "trial": loaded.trial.to_dict(),
            "recording": recording_checks(loaded.checks, loaded.scene),
            "curves": replay_curves(result).to_dict(),
        }
        if loaded.episode is not None:
            record["episode"] = loaded.episode.to_dict()
        text = json.dumps(json_ready(record), indent=1, allow_nan=False)
        _line("wrote", str(write_text(args.json, text + "\n")))
    if args.plot:
        # lazy: matplotlib (an optional extra), only with --plot
        from handsim.viz.replay_plots import plot_replay

        _line("plot", str(plot_replay(result, args.plot)))
    if args.video:
        # lazy: the renderer and encoders, only with --video
        from handsim.viz.render import write_video

        width, height = args.size
        video = write_video(
            loaded.scene, result.states, result.frame_dt, args.video, camera=args.camera, width=width,
            height=height, shadows=not args.no_shadows,
        )  # fmt: skip
        _line(
            "video",
            f"{video.path} ({video.frames} frames at {video.fps:.1f} fps, {video.codec}, "
            f"camera {video.camera})",
        )
    if result.diverged is not None:
        return EXIT_DIVERGED
    invalid = [f for f in result.flags if f.invalid]
    for flag in invalid:
        print(f"handsim replay: not valid: {flag.reason}", file=sys.stderr)
    return EXIT_NOT_VALID if invalid else 0


def register(commands: Commands) -> None:
    """Add the ``replay`` command."""
    replay = commands.add_parser(
        "replay",
        help="replay a recorded trial in MuJoCo: penetration, contacts, tracking, object drift or hold",
        description="Replay a recording with collisions on and free objects and print how physical it was. "
        "A Tzionas Model_Hand_*.MOTION brings its hand (.SKEL/.LIMITS/.OFF/.SKIN beside it) and the "
        "sequence's objects (Configs/NN/MODELS_INFO.txt), which follow their recorded tracks: the summary "
        "gives their drift. A GraspDB14 glove recording drives the parametric default hand (or --skeleton), "
        "fixed palm down, holding the object (--object, else the one whose id the file name carries) placed "
        "where the grasp closes and released after it: the summary says whether it was held. An ARCTIC "
        "raw_seqs/sXX/<seq>.mano.npy drives both MANO hands (your MANO_RIGHT.pkl and MANO_LEFT.pkl: "
        "--mano-dir or HANDSIM_MANO_DIR) with the subject's betas, the object of meta/object_vtemplates free "
        "at its recorded pose and articulation: the summary gives each hand's numbers and the object's drift "
        "(docs/arctic.md). The terms of the summary (held, not judged, fit at, hold_robustness, grip check, "
        "followed/lost …) are defined in docs/concepts.md. "
        f"Exit codes: 0 done, 1 handsim error, 2 usage error or not a trial, {EXIT_DIVERGED} diverged, "
        f"{EXIT_NOT_VALID} not valid (a plausibility flag).",
    )
    replay.add_argument(
        "trajectory",
        metavar="TRAJECTORY",
        help="GraspDB14 .txt, Tzionas Model_Hand_*.MOTION, ARCTIC <seq>.mano.npy or a NAME.corrected.npz",
    )
    replay.add_argument("--skeleton", metavar="SKELETON_FILE", help="GraspDB14: the hand (.xmlskel or .SKEL)")
    replay.add_argument(
        "--object", metavar="NAME|MESH", help="GraspDB14: a catalogue name or a mesh file (give --units)"
    )
    replay.add_argument(
        "--calibration", metavar="JSON", help="GraspDB14: calibration of a raw-count recording"
    )
    replay.add_argument("--units", choices=("m", "mm"), help="units of a mesh file given as --object")
    add_object_mass_options(replay, forced=True)
    add_force(replay)
    replay.add_argument(
        "--hand-length", type=positive_number, default=None, metavar="M",
        help="GraspDB14 without --skeleton: parametric hand length, wrist crease to middle fingertip (0.19)",
    )  # fmt: skip
    replay.add_argument(
        "--collision", choices=("capsules", "mesh"), default=None,
        help="hand collision shapes (default capsules; mesh: per-bone hulls of a skinned .SKEL or MANO hand)",
    )  # fmt: skip
    replay.add_argument(
        "--thumb-rest", type=_thumb_rest, metavar="ABD,FLEX",
        help="GraspDB14: hold the thumb TMC DoFs no glove sensor drives (th_tmc_abd, th_tmc_flex) at these "
        "angles in degrees (default: 0,0 as the GraspDB14 tools; see docs/cyberglove.md)",
    )  # fmt: skip
    replay.add_argument(
        "--grasp", type=_grasp_index, metavar="K",
        help="glove recordings: replay grasp episode K only, with every detail (1-based, as `handsim "
        "inspect` lists them; default: judge every complete episode, one line each)",
    )  # fmt: skip
    add_arctic_options(replay)
    add_control_rate(replay)
    replay.add_argument(
        "--stability", type=_stability_at, metavar="grasp|SECONDS",
        help="also run the grasp stability tests on the state at this time (grasp: the hold window's end)",
    )  # fmt: skip
    replay.add_argument(
        "--json", type=output_file, metavar="JSON", help="write the result and per-frame curves as JSON"
    )
    replay.add_argument(
        "--plot",
        type=output_file,
        metavar="PNG",
        help="plot penetration, contacts, errors, drift/slip over time",
    )
    replay.add_argument(
        "--video", type=output_file, metavar="MP4|GIF", help="render the replay (mp4 needs handsim[video])"
    )
    replay.add_argument(
        "--camera", default="track", choices=("track", "frame", "hand_cam", "overview"),
        help="video camera: track (follows the hand; default), frame (aimed at every object and hand at "
        "each moment: both hands of an ARCTIC sequence), hand_cam or overview (the scene's)",
    )  # fmt: skip
    replay.add_argument(
        "--size", type=int, nargs=2, default=(640, 480), metavar=("W", "H"), help="video size (640 480)"
    )
    replay.add_argument(
        "--no-shadows", action="store_true", help="video without shadows (3-4x faster with software OpenGL)"
    )
    replay.add_argument(
        "-v", "--verbose", action="store_true", help="also print the recording reader's notes"
    )
    replay.set_defaults(func=_replay, simulates=True, command_parser=replay)
