"""``handsim inspect`` and ``handsim calibrate``: look at a recording; fit a glove calibration."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from handsim.cli._common import Commands, add_arctic_options, output_file


def load_trajectory(path: str, skeleton_path: str | None, calibration_path: str | None):
    """Read a recording (with its skeleton and calibration when given) and check it.

    A GraspDB14 glove recording gets the phases of its own annotation and its single-sample spikes filled
    (:func:`handsim.glove.checks.check_recording`); the checks' result is None for other recordings.
    """
    # lazy: the readers and glove checks, only for this command
    from handsim.glove.checks import check_recording
    from handsim.io import read_skeleton, read_trajectory
    from handsim.io.graspdb.annotations import match_annotation
    from handsim.io.graspdb.calibration import load_calibration
    from handsim.io.text_files import require_file

    require_file(path)  # before its skeleton: a folder named x.MOTION is not "x.SKEL: file not found"
    if skeleton_path is None and Path(path).suffix.lower() == ".motion":
        skeleton_path = str(Path(path).with_suffix(".SKEL"))  # a Tzionas motion's own skeleton
    skeleton = read_skeleton(skeleton_path) if skeleton_path else None
    calibration = load_calibration(calibration_path) if calibration_path else None
    trajectory = read_trajectory(path, skeleton=skeleton, calibration=calibration)
    if trajectory.switch is None:  # not a CyberGlove recording
        return trajectory, skeleton, None
    trajectory, checks = check_recording(trajectory, match_annotation(path, trajectory.nframes))
    return trajectory, skeleton, checks


def _inspect_arctic(args: argparse.Namespace) -> int:
    # lazy: the ARCTIC and MANO readers, only for ARCTIC sequences
    from handsim.io.arctic.sequence import read_arctic_sequence
    from handsim.viz.trajectory_report import describe_arctic

    given = [flag for flag, value in (("--skeleton", args.skeleton), ("--calibration", args.calibration),
                                      ("--plot", args.plot)) if value]  # fmt: skip
    if given:
        raise SystemExit(
            f"handsim inspect: {' and '.join(given)} {'does' if len(given) == 1 else 'do'} not apply to an "
            "ARCTIC sequence (its hands are MANO's: their joint angles need the MANO models)"
        )
    sequence = read_arctic_sequence(args.trajectory)
    for line in describe_arctic(sequence, _arctic_sides(sequence, args)).lines():
        print(line)
    return 0


def _arctic_sides(sequence, args: argparse.Namespace):
    """The side check's verdict (a swapped one is a flag), or why it was not run: it needs the MANO files."""
    # lazy: the MANO models, the object and the check, only for ARCTIC sequences
    from handsim.errors import InputFileError
    from handsim.io.arctic.mano import MANO_DIR_ENV
    from handsim.trials.arctic import sequence_side_check

    if args.mano_dir is None and not os.environ.get(MANO_DIR_ENV):
        return (
            "not checked: the side check drives both MANO models (--mano-dir DIR with your MANO_RIGHT.pkl "
            "and MANO_LEFT.pkl, or HANDSIM_MANO_DIR)"
        )
    try:
        return sequence_side_check(sequence, args.mano_dir, args.templates)
    except InputFileError as exc:  # a missing MANO file or object template: the rest is still shown
        return f"not checked: {exc}"


def _inspect(args: argparse.Namespace) -> int:
    # lazy: the recording summaries, only for this command
    from handsim.viz.trajectory_report import describe

    if args.trajectory.endswith(".mano.npy"):
        return _inspect_arctic(args)
    arctic = [
        flag for flag, value in (("--mano-dir", args.mano_dir), ("--templates", args.templates)) if value
    ]
    if arctic:
        raise SystemExit(
            f"handsim inspect: {' and '.join(arctic)} apply to ARCTIC sequences (<seq>.mano.npy) only"
        )
    trajectory, skeleton, checks = load_trajectory(args.trajectory, args.skeleton, args.calibration)
    for line in describe(trajectory, skeleton).lines():
        print(line)
    segmentation = None
    if checks is not None:
        # lazy: the grasp segmentation, only for glove recordings
        from handsim.glove.segmentation import segment_grasps

        print(f"annotation {checks.annotation.note}")
        print(f"spikes     {checks.spike_text()}")
        for spike in checks.spikes:
            print(f"spike      {spike.describe()}")
        segmentation = segment_grasps(trajectory)
        for line in segmentation.lines():
            print(line)
        for flag in trajectory.flags:  # what the recording's checks flag (every replay of it says it too)
            print(f"flag       {flag.line()}")
    if args.plot:
        # lazy: matplotlib (an optional extra), only with --plot
        from handsim.viz.plotting import plot_trajectory

        print(f"plot       {plot_trajectory(trajectory, args.plot, skeleton, segmentation)}")
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    # lazy: the glove calibration and the raw-count reader, only for this command
    from handsim.glove import estimate_calibration
    from handsim.io.graspdb.calibration import save_calibration
    from handsim.io.graspdb.glove import read_graspdb_raw

    recording = read_graspdb_raw(args.recording)
    calibration = estimate_calibration(
        recording.counts, recording.switch, provenance=str(Path(args.recording))
    )
    for line in calibration.notes:
        print(f"note       {line}")
    for name, residual in zip(calibration.sensor_names, calibration.residuals or (), strict=False):
        print(f"residual   {name:8s} {residual:.4f} rad")
    print(f"wrote      {save_calibration(calibration, args.output)}")
    return 0


def register(commands: Commands) -> None:
    """Add the ``inspect`` and ``calibrate`` commands."""
    inspect = commands.add_parser(
        "inspect",
        help="summarise a recording: timing, phases, gaps, joint-limit violations (and a plot)",
        description="Read a recording (GraspDB14 CyberGlove rad file, or raw with --calibration; a "
        "Tzionas Model_Hand_*.MOTION with its sequence's objects) and print its duration and rate, the "
        "largest interval between samples, channels, phases (from the _annot- file beside it), gaps, and "
        "with --skeleton (a .MOTION's own .SKEL by default) the samples outside the joint limits; for a "
        "glove recording also its grasp episodes (frames and times, hold, peak flexion, truncated or "
        "complete, found from the annotation or automatically from the summed finger flexion; a calibration "
        "sequence is named as such). An ARCTIC "
        "raw_seqs/sXX/<seq>.mano.npy: frames, both hands (wrist travel, fitting error) and the object of "
        "the <seq>.object.npy beside it with its articulation range; with your MANO files (--mano-dir or "
        "HANDSIM_MANO_DIR) also whether 'right' and 'left' look swapped (the flag hands_swapped).",
    )
    inspect.add_argument("trajectory", metavar="TRAJECTORY")
    inspect.add_argument("--skeleton", metavar="SKELETON_FILE", help="hand skeleton: columns and limits")
    inspect.add_argument("--calibration", metavar="JSON", help="glove calibration for a raw-count file")
    inspect.add_argument(
        "--plot",
        type=output_file,
        metavar="PNG",
        help="write a plot of every DoF over time (a glove recording's with its summed finger flexion and "
        "grasp episodes on top)",
    )
    add_arctic_options(inspect)
    inspect.set_defaults(func=_inspect)

    calibrate = commands.add_parser(
        "calibrate",
        help="estimate a CyberGlove calibration from a recorded calibration sequence",
        description="Fit per-sensor gains and offsets to a raw calibration sequence (GraspDB14 protocol: "
        "the switch separates the poses; flat hand = 0, wedges = 25° ab/adduction, table edge = 45° MCP "
        "flexion) and write them as a calibration JSON file (see docs/cyberglove.md).",
    )
    calibrate.add_argument("recording", metavar="CALIB_RECORDING")
    calibrate.add_argument(
        "-o", "--output", type=output_file, required=True, metavar="JSON", help="calibration file to write"
    )
    calibrate.set_defaults(func=_calibrate)
