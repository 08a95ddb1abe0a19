"""``handsim correct TRIAL -o OUT.corrected.npz``: the smallest change to a recording that makes it physical.

Loads the trial as ``handsim replay`` does, corrects it (:mod:`handsim.correct`), writes the corrected trial
and prints its plausibility score: the finger and wrist corrections, the object's tracking before and after,
the moments of largest correction, and the verdict (corrected, not corrected with the best found and why, or
not judged). Exit codes: 0 the file was written (whatever the verdict: it is printed), 1 a handsim error,
2 a usage error (a file that is no trial, options that do not apply, an output name not ending in
``.corrected.npz``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from handsim.cli._common import (
    EXIT_INTERRUPTED,
    Commands,
    add_arctic_options,
    add_force,
    add_object_mass_options,
    argument_type,
    non_negative_int,
    output_dir,
    output_file,
    positive_int,
    trial_options_from_args,
    usage_error,
    write_text,
)
from handsim.correct.config import BUDGETS, CorrectionConfig, CorrectionError
from handsim.errors import HandsimError

if TYPE_CHECKING:
    from handsim.correct import Correction, CorrectionScore

LABEL = 14  # width of the label column
SUFFIX = ".corrected.npz"


def _line(label: str, text: str) -> None:
    print(f"{label:<{LABEL}}{text}")


def _tracking_text(t, objective: str) -> str:
    if objective == "hold":  # a glove grasp: the object against where the grasp placed it, over the hold
        return (
            f"{t.track} ({t.track_reason}); within 1 cm of its placement in {t.within_1cm * 100:.1f} % of "
            f"the hold's frames, mean displacement {t.mean_drift_mm:.1f} mm (max {t.max_drift_mm:.1f})"
        )
    return (
        f"within 1 cm in {t.within_1cm * 100:.1f} % of frames, mean drift {t.mean_drift_mm:.1f} mm "
        f"(max {t.max_drift_mm:.1f}), rotation {t.mean_rotation_deg:.1f}° mean; track {t.track}"
    )


def print_score(score: CorrectionScore) -> None:
    """The plausibility score's lines (also used for each trial of a dataset)."""
    _line(
        "fingers",
        f"correction {score.finger_rms_deg:.2f}° RMS, {score.finger_max_deg:.2f}° max "
        f"({score.finger_vs_replay_tracking:.2f}× pure replay's joint tracking error, "
        f"{score.before.joint_tracking_rms_deg:.2f}° RMS)",
    )
    if score.wrist_position_rms_mm is None:
        _line("wrist", "not corrected (no recorded wrist pose, or --no-wrist)")
    else:
        _line(
            "wrist",
            f"{score.wrist_position_rms_mm:.1f} mm RMS ({score.wrist_position_max_mm:.1f} max), "
            f"{score.wrist_rotation_rms_deg:.2f}° RMS ({score.wrist_rotation_max_deg:.2f}° max)",
        )
    _line("before", _tracking_text(score.before, score.objective))
    _line("after", _tracking_text(score.after, score.objective))
    for stretch in score.unsupported:
        _line("recording", stretch.describe())
    wrist = score.wrist_position_rms_mm is not None
    for i, m in enumerate(score.largest):
        _line(
            "largest" if i == 0 else "",
            f"{m.time_s:6.2f} s (frame {m.frame}): fingers {m.finger_rms_deg:.2f}° RMS, "
            f"{m.finger_max_deg:.2f}° max"
            + (f"; wrist {m.wrist_mm:.1f} mm, {m.wrist_deg:.2f}°" if wrist else ""),
        )
    _line(score.status, score.reason)
    if score.large:
        # lazy: the score module (the simulation stack), loaded by the correction already
        from handsim.correct.score import implausible_text

        _line("implausible", implausible_text(score))


def _weight(text: str) -> float:
    """A finite number ≥ 0 (a gain or a weight)."""
    value = float(text)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"expected a number ≥ 0, got {text!r}")
    return value


def _add_guidance_options(parser: argparse.ArgumentParser, default: CorrectionConfig) -> None:
    """``--guidance``, ``--guidance-rounds`` and ``--opposition-weight``."""
    _add_weight(
        parser, "--guidance", default.guidance, "GAIN",
        "contact guidance: the share of a virtual force carrying each object to its goal in the first "
        f"rounds' rollouts, annealed to zero; never in the result (default {default.guidance:g}: off)",
    )  # fmt: skip
    parser.add_argument(
        "--guidance-rounds", type=non_negative_int, default=default.guidance_rounds, metavar="N",
        help=f"rounds with guidance, at most all but the last (default {default.guidance_rounds})",
    )  # fmt: skip
    _add_weight(
        parser, "--opposition-weight", default.opposition_weight, "W",
        "glove grasps: the cost of a hold frame without an opposing grip, as 1 cm of slip costs 1 "
        f"(default {default.opposition_weight:g}; 0: off)",
    )  # fmt: skip


def _add_weight(parser: argparse.ArgumentParser, flag: str, default: float, metavar: str, text: str) -> None:
    """A number option ≥ 0 (a gain or a weight)."""
    parser.add_argument(flag, type=argument_type(_weight), default=default, metavar=metavar, help=text)


def _config(args: argparse.Namespace) -> CorrectionConfig:
    budget = BUDGETS[args.budget]
    return CorrectionConfig(
        samples=args.samples or budget.samples,
        iterations=args.iterations or budget.iterations,
        horizon=args.horizon,
        wrist=not args.no_wrist,
        guidance=args.guidance,
        guidance_rounds=args.guidance_rounds,
        opposition_weight=args.opposition_weight,
        seed=args.seed,
    )


def _correct(args: argparse.Namespace) -> int:
    name = args.output.name.lower()
    try:
        config = _config(args)
    except CorrectionError as exc:
        return usage_error("correct", str(exc))
    if Path(args.trial).is_dir() and not name.endswith(".npz"):
        return _correct_dataset(args, config)
    if not name.endswith(SUFFIX):
        return usage_error("correct", f"-o {args.output}: a corrected trial's name ends in {SUFFIX!r}")
    # lazy: the simulation stack (MuJoCo), only when correcting
    from handsim.correct import correct, write_corrected
    from handsim.trials import TrialError, find_with_options, load_trial

    if args.rollouts == "warp":  # before the trial loads: a missing MuJoCo Warp is said at once
        _warp_notes(args.threads)
    options = dataclasses.replace(trial_options_from_args(args), grasp=args.grasp)
    try:
        loaded = load_trial(find_with_options(args.trial, options), progress=True)
    except TrialError as exc:
        return usage_error("correct", str(exc))
    trial = loaded.trial
    _line("trial", f"{trial.kind}  {trial.trajectory_path}")
    _line("hand", loaded.hand)
    started = time.perf_counter()
    last = [0.0]

    def progress(done: int, frames: int) -> None:
        now = time.perf_counter() - started
        if done == frames or now - last[0] >= 30.0:
            last[0] = now
            print(f"{'':<{LABEL}}frame {done}/{frames} ({now:.0f} s)", file=sys.stderr, flush=True)

    correction = correct(
        loaded, config, backend=args.rollouts or "cpu", threads=args.threads, progress=progress
    )
    _print_correction(correction, time.perf_counter() - started)
    _line("wrote", str(write_corrected(args.output, correction)))
    if args.json:
        # lazy: the record helpers, only with --json
        import json

        from handsim.correct.trial_file import corrected_header

        text = json.dumps(corrected_header(correction), indent=1, sort_keys=True, allow_nan=False)
        _line("wrote", str(write_text(args.json, text + "\n")))
    return 0


_ONE_TRIAL_ONLY = (
    ("density", "--density"),
    ("mass", "--mass"),
    ("force", "--force"),
    ("grasp", "--grasp"),
    ("threads", "--threads"),
    ("json", "--json"),
    ("rollouts", "--rollouts"),
)
"""Options of a single correction that a dataset run does not take (``dest``, flag)."""


def _correct_dataset(args: argparse.Namespace, config: CorrectionConfig) -> int:
    """``handsim correct DATASET -o OUTDIR``: every trial corrected by the dataset runner, then the report."""
    # lazy: the runner (MuJoCo) and the trial loaders, only for a run
    from handsim.runner.correction_job import CorrectionJob
    from handsim.runner.execute import run_dataset
    from handsim.runner.records import read_records
    from handsim.trials import discover, select

    single = [flag for dest, flag in _ONE_TRIAL_ONLY if getattr(args, dest, None) not in (None, False)]
    if single:
        return usage_error(
            "correct",
            f"{', '.join(single)}: options of one trial's correction, not of a dataset run (each worker "
            "corrects on one thread; a dataset's trials take only --mano-dir and --templates)",
        )
    discovery = discover(args.trial, trial_options_from_args(args))
    entries = select(discovery.entries, args.only, args.limit)
    if not entries:
        return usage_error(
            "correct", f"no trial{f' matching {args.only!r}' if args.only else ''} in {args.trial}"
        )
    _line("dataset", f"{discovery.root}: {len(discovery.entries)} trials; correcting {len(entries)}")
    out = args.output
    try:
        summary = run_dataset(
            discovery if len(entries) == len(discovery.entries) else entries, out, workers=args.workers,
            backend=args.backend, address=args.address, job=CorrectionJob(config),
            command=["handsim", *sys.argv[1:]], progress=True,
        )  # fmt: skip
    except KeyboardInterrupt:
        print(f"handsim correct: interrupted; run the same command to resume ({out})", file=sys.stderr)
        return EXIT_INTERRUPTED
    for note in summary.notes:
        _line("note", note)
    _line("records", f"{out / 'records.jsonl'} ({len(summary.ran)} corrected now, {summary.skipped} resumed)")
    ids = {e.id for e in entries}
    records = [r for r in read_records(out) if r["id"] in ids]
    for record in records:
        _line("", _record_line(record))
    try:
        # lazy: the report (matplotlib for the plots), only after a run
        from handsim.report.correction import write_correction_report

        _line("report", str(write_correction_report(out)))
    except HandsimError as exc:
        _line("note", f"no report: {exc}")
    if summary.all_failed:
        print(
            f"handsim correct: error: every trial failed ({summary.failed} of {summary.trials})",
            file=sys.stderr,
        )
        return 1
    return 0


def _record_line(record: dict) -> str:
    """One line for a dataset trial's record: its verdict and size, or why it was not corrected."""
    c = record.get("correction") or {}
    if record["status"] == "error":
        error = record.get("error") or {}
        return f"{record['id']}: failed: {error.get('type')}: {error.get('message')}"
    if "finger_rms_deg" not in c:
        return f"{record['id']}: {c.get('status')}: {c.get('reason')}"
    text = f"{record['id']}: {c['status']}; fingers {c['finger_rms_deg']:.2f}° RMS"
    text += f" ({c['finger_max_deg']:.2f}° max)"
    if c.get("wrist_position_rms_mm") is not None:
        text += f"; wrist {c['wrist_position_rms_mm']:.1f} mm, {c['wrist_rotation_rms_deg']:.2f}° RMS"
    return text + (f"; implausible: {c['implausible']}" if c.get("implausible") else "")


def _print_correction(correction: Correction, seconds: float) -> None:
    plan, config = correction.plan, correction.config
    recorded = float(correction.reference.schedule.times[-1] - correction.reference.schedule.times[0])
    _line(
        "method",
        f"annealed MPPI in receding horizon: {config.samples} samples × {config.iterations} rounds, horizon "
        f"{config.horizon} frames, seed {config.seed}; {plan.rollouts} rollouts on "
        + (f"{correction.threads} thread(s)" if correction.backend == "cpu" else "MuJoCo Warp"),
    )
    per = seconds / recorded if recorded > 0 else math.nan
    _line("time", f"{seconds:.1f} s for {recorded:.2f} s recorded ({per:.1f} s per recorded second)")
    print_score(correction.score)


def register(commands: Commands) -> None:
    """Add the ``correct`` command."""
    budgets = ", ".join(f"{n} ({b.samples} samples × {b.iterations} rounds)" for n, b in BUDGETS.items())
    default = CorrectionConfig()
    parser = commands.add_parser(
        "correct",
        help="correct a recording physically: the smallest change that makes its object follow its track",
        description="Optimise the recording's finger targets (and its wrist pose where one is recorded) "
        "so that the simulated object follows its recorded track while the motion stays as close as possible "
        "to the recording (sampling-based optimisation in receding horizon on MuJoCo rollouts; "
        "docs/correct.md). Writes the corrected trial (replay it with `handsim replay OUT.corrected.npz`) "
        "and prints how large the correction had to be: a recording that needs a large one is implausible. "
        "For trials whose objects follow recorded tracks (Tzionas sequences with objects, ARCTIC sequences) "
        "and glove grasps (a GraspDB14 recording or episode, a scripted grasp: the placed object held "
        "through the hold window). Given a dataset folder and an output folder, corrects every trial through "
        "the dataset runner (resumable; local cores or Ray) and writes OUT/correction.html. "
        "Deterministic for a seed with the default cpu rollouts; the result does not depend on the threads. "
        "The words it prints "
        "(corrected, not corrected, implausible, size …) are defined in docs/concepts.md.",
    )
    parser.add_argument(
        "trial",
        metavar="TRIAL",
        help="Tzionas Model_Hand_*.MOTION (or Models/NN), ARCTIC .mano.npy, GraspDB14 recording, "
        "NAME.grasp.json; or a dataset folder (with -o OUTDIR)",
    )
    parser.add_argument(
        "-o",
        "--output",
        type=_output,
        required=True,
        metavar="OUT",
        help="the corrected trial, NAME.corrected.npz; for a dataset folder, an output folder",
    )
    parser.add_argument(
        "--seed", type=non_negative_int, default=0, metavar="N", help="seed of the sampling (default 0)"
    )
    parser.add_argument(
        "--budget", choices=tuple(BUDGETS), default="standard",
        help=f"search effort per planning step: {budgets}; default standard",
    )  # fmt: skip
    parser.add_argument(
        "--samples",
        type=positive_int,
        default=None,
        metavar="N",
        help="samples per round (overrides --budget)",
    )
    parser.add_argument(
        "--iterations",
        type=positive_int,
        default=None,
        metavar="N",
        help="rounds per planning step (overrides --budget)",
    )
    parser.add_argument(
        "--horizon", type=positive_int, default=default.horizon, metavar="FRAMES",
        help=f"look-ahead in control frames (default {default.horizon}: "
        f"{default.horizon / default.control_rate:g} s)",
    )  # fmt: skip
    parser.add_argument(
        "--no-wrist", action="store_true", help="correct the fingers only, not the recorded wrist pose"
    )
    _add_guidance_options(parser, default)
    _add_rollout_options(parser)
    parser.add_argument(
        "--json",
        type=output_file,
        metavar="OUT.json",
        help="also write the file's header (provenance, score) as JSON",
    )
    add_object_mass_options(parser, forced=True)
    add_force(parser)
    add_arctic_options(parser)
    _add_dataset_options(parser)
    parser.set_defaults(func=_correct, simulates=True, command_parser=parser)


def _warp_notes(threads: int | None) -> None:
    """Check that MuJoCo Warp is there (else a handsim error), and say what it ignores or where it runs."""
    # lazy: MuJoCo Warp (an optional dependency), only with --rollouts warp
    from handsim.correct.warp_backend import DEVICE_ENV, import_warp

    warp, _ = import_warp()
    if threads is not None:
        _line("note", "--threads does not apply to --rollouts warp: every candidate is a world of one batch")
    if not os.environ.get(DEVICE_ENV) and not warp.is_cuda_available():
        _line("note", "no CUDA device: MuJoCo Warp runs on its CPU device, far slower than --rollouts cpu")


def _add_rollout_options(parser: argparse.ArgumentParser) -> None:
    """Where one trial's candidates are simulated: the backend and its threads."""
    parser.add_argument(
        "--threads", type=positive_int, default=None, metavar="N",
        help="rollout threads (default: $HANDSIM_THREADS, else every core); the result does not depend on it",
    )  # fmt: skip
    parser.add_argument(
        "--rollouts", choices=("cpu", "warp"), default=None,
        help="where the candidates are simulated: cpu (default: mujoco.rollout on --threads threads, bitwise "
        "deterministic) or warp (MuJoCo Warp on a GPU, pip install 'handsim[warp]'; float32, so the plan may "
        "differ from run to run; the corrected file still replays bit for bit)",
    )  # fmt: skip


def _output(text: str) -> Path:
    """An argparse type: a corrected trial's file (``….npz``), else a dataset run's output folder."""
    return output_file(text) if text.lower().endswith(".npz") else output_dir(text)


def _add_dataset_options(parser: argparse.ArgumentParser) -> None:
    """The options of a glove episode and of a dataset run."""
    options = {
        "--grasp": dict(
            type=positive_int, metavar="K",
            help="glove recordings: correct grasp episode K (1, 2 …; `handsim replay FILE` lists them)",
        ),
        "--workers": dict(
            type=positive_int, metavar="N", help="dataset: trials at once (default: all cores)"
        ),
        "--backend": dict(choices=("local", "ray"), default="local", help="dataset: process pool or Ray"),
        "--address": dict(
            metavar="ADDR",
            help="dataset with --backend ray: a Ray cluster (HOST:PORT or 'auto'); default: start one",
        ),
        "--only": dict(metavar="GLOB", help="dataset: correct only trials whose id matches"),
        "--limit": dict(type=non_negative_int, metavar="N", help="dataset: only the first N trials (by id)"),
    }  # fmt: skip
    for flag, settings in options.items():
        parser.add_argument(flag, **settings)
