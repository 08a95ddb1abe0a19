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

from handsim.cli._common import (
    Commands,
    add_control_rate,
    add_trial_options,
    output_file,
    trial_options_from_args,
    usage_error,
    write_text,
)
from handsim.cli.replay_print import episode_line, print_line, print_summary, print_trial
from handsim.runner.records import json_ready
from handsim.trials.options import option_names

EXIT_DIVERGED = 3
EXIT_NOT_VALID = 4


def replay_options() -> tuple[str, ...]:
    """Every trial option (:class:`~handsim.trials.options.TrialOptions`), in the order ``--help`` lists them.

    The fields' order, but with ``--force`` right after the object mass it unlocks and ``--grasp`` among the
    glove options, before the ARCTIC ones.
    """
    names = [n for n in option_names() if n not in ("force", "grasp")]
    names.insert(names.index("mass") + 1, "force")
    names.insert(names.index("mano_dir"), "grasp")
    return tuple(names)


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
    from handsim.trials.registry import find_with_options

    config = ReplayConfig(control_rate=args.rate, keep_states=bool(args.video), stability_at=args.stability)
    try:
        trial = find_with_options(args.trajectory, trial_options_from_args(args))
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
    from handsim.trials import load_trial, replay_trial

    print_line("trial", f"{trial.kind}  {trial.trajectory_path}")
    for text in segmentation.lines():
        label, _, rest = text.partition(" ")
        print_line(label if label != "episode" else "", text if label == "episode" else rest.strip())
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
        result = replay_trial(loaded, config)
        outcomes.append(result)
        print_line(f"episode {episode.index}", episode_line(result))
        if args.json:
            records.append(
                {**result.to_dict(), "trial": loaded.trial.to_dict(), "episode": episode.to_dict()}
            )
    held = sum(r.summary.get("held") is True for r in outcomes)
    lost = sum(r.summary.get("held") is False for r in outcomes)
    robust = sum(
        r.summary.get("held") is True and (r.summary.get("hold_robustness") or 0) >= ROBUST for r in outcomes
    )
    print_line(
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
        print_line("wrote", str(write_text(args.json, text + "\n")))
    diverged = any(r.diverged is not None for r in outcomes)
    return EXIT_DIVERGED if diverged else 0


def _replay_trial(args: argparse.Namespace, trial, config) -> int:
    """Replay one trial (a glove recording's one episode) and print everything about it."""
    # lazy: the simulation stack, only when replaying
    from handsim.trials import load_trial, replay_trial

    loaded = load_trial(trial, metrics=config.metrics, progress=True)
    print_trial(loaded)
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
    result = replay_trial(loaded, config)
    print_summary(result)
    notes = [*loaded.notes, *loaded.scene.setup.notes, *result.notes]
    if args.verbose:
        notes = [*loaded.trajectory.notes, *notes]
    for note in notes:
        print_line("note", note)
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
        print_line("wrote", str(write_text(args.json, text + "\n")))
    if args.plot:
        # lazy: matplotlib (an optional extra), only with --plot
        from handsim.viz.replay_plots import plot_replay

        print_line("plot", str(plot_replay(result, args.plot)))
    if args.video:
        # lazy: the renderer and encoders, only with --video
        from handsim.viz.render import write_video

        width, height = args.size
        video = write_video(
            loaded.scene, result.states, result.frame_dt, args.video, camera=args.camera, width=width,
            height=height, shadows=not args.no_shadows,
        )  # fmt: skip
        print_line(
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
    add_trial_options(replay, replay_options())
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
