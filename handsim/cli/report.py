"""``handsim report``: replay every trial of a dataset, record each, and render the report.

Exit codes: 0 done (failed trials are recorded in the report, not an exit code); 1 a handsim error (a
malformed records file, records of other parameters in OUT, Ray missing …) or a run in which every trial
failed (the report is still written; stderr counts the errors by type); 2 a usage error (no dataset, no
trial in it, a control rate below 20 Hz, OUT a file); 130 interrupted (the records written so far are kept:
run the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from handsim.cli._common import (
    EXIT_INTERRUPTED,
    Commands,
    add_arctic_options,
    add_control_rate,
    non_negative_int,
    output_dir,
    positive_int,
    trial_options_from_args,
    usage_error,
)
from handsim.runner.records import read_records
from handsim.runner.run_summary import failure_counts, records_line

if TYPE_CHECKING:
    from handsim.trials import Discovery, TrialOptions


def _render(out: Path) -> int:
    """Render the report of ``out`` from its records; print where it is."""
    # lazy: the report stack, only when rendering a report
    from handsim.report import render_report

    files = render_report(out)
    for note in files.notes:
        print(f"note        {note}")
    print(f"report      {files.html}")
    print(f"markdown    {files.markdown}")
    print(f"json        {files.json}")
    return 0


def _render_only(out: Path) -> int:
    """Render the report of a run's records and print its line; exit 1 if every recorded trial failed."""
    code = _render(out)
    records = read_records(out)
    print(records_line(records))
    failed = sum(r["status"] == "error" for r in records)
    if records and failed == len(records):
        return _all_failed(failed, len(records), failure_counts(records))
    return code


def run_and_render(
    dataset: str | Path | Discovery,
    out: str | Path,
    *,
    only: str | None = None,
    limit: int | None = None,
    options: TrialOptions | None = None,
    **run: Any,
) -> int:
    """Discover, run and report on a dataset, printing what happens; the command's exit code.

    Shared by ``handsim report`` and ``handsim demo``.

    Args:
        dataset: A dataset folder or one recording, or a discovery made already.
        out: The output folder (resumed when it holds records of the same parameters).
        only: Run only trials whose id matches this glob.
        limit: Run only the first ``limit`` trials.
        options: Options for the trials of the kinds that take them (ARCTIC's ``mano_dir``, ``templates``).
        **run: :func:`handsim.runner.execute.run_dataset`'s keyword arguments (``workers``, ``backend``,
            ``address``, ``config``, ``frames``, ``command`` …), with a progress bar by default.

    Returns:
        0 done, 1 every trial failed (the errors counted on stderr), 2 no trial to run, 130 interrupted.

    Raises:
        HandsimError: The dataset is missing, OUT holds records of other parameters, Ray is missing …; a
            recording given alone misses a file it needs (as ``handsim replay`` says it).
    """
    # lazy: the runner (MuJoCo), the trial loaders and the report's file groups, only for a run
    from handsim.report.files import group_files
    from handsim.runner.execute import run_dataset
    from handsim.trials import Discovery, discover, select

    out = Path(out)
    discovery = dataset if isinstance(dataset, Discovery) else discover(dataset, options)
    entries = select(discovery.entries, only, limit)
    unknown = group_files({"path": u.path, "reason": u.reason} for u in discovery.unknown)
    for group in unknown:
        print(f"unknown     {group.what()}: {group.reason}")
    for group in group_files({"path": c.path, "reason": c.reason} for c in discovery.copies):
        print(f"copy        {group.what()}: {group.reason}")
    if not entries:
        if not only and not isinstance(dataset, Discovery) and Path(dataset).is_file():
            return _not_a_trial(dataset, options)
        what = f" matching {only!r}" if only else ""
        return usage_error("report", f"no trial{what} in {dataset}")
    print(
        f"dataset     {discovery.root}: {len(discovery.entries)} trials, {len(discovery.companions)} "
        f"companion and {len(discovery.unknown)} unknown files; running {len(entries)}"
    )
    source = discovery if len(entries) == len(discovery.entries) else entries
    try:
        # progress: a bar on a terminal, nothing in a log (handsim.progress)
        summary = run_dataset(source, out, **{"progress": True, **run})
    except KeyboardInterrupt:
        print(
            f"handsim report: interrupted; the finished trials are recorded in {out / 'records.jsonl'}: "
            "run the same command to resume",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    for note in summary.notes:
        print(f"note        {note}")
    print(f"records     {out / 'records.jsonl'} ({len(summary.ran)} run now, {summary.skipped} resumed)")
    code = _render(out)
    print(summary.line())
    if summary.all_failed:
        return _all_failed(summary.failed, summary.trials, summary.failures)
    return code


def _not_a_trial(path: str | Path, options: TrialOptions | None) -> int:
    """Why one recording given as the dataset is no trial, as ``handsim replay`` says it; the exit code.

    A missing file it needs (an ARCTIC sequence's ``.object.npy``) is a handsim error (raised: exit code 1);
    a file of no kind, or an option that does not apply, a usage error (2).
    """
    # lazy: the trial registry, only for a recording that is no trial
    from handsim.trials import TrialError
    from handsim.trials.registry import find_with_options

    try:
        find_with_options(path, options)
    except TrialError as exc:
        return usage_error("report", str(exc))
    return usage_error("report", f"no trial in {path}")


def _all_failed(failed: int, trials: int, failures: tuple[tuple[str, int, str], ...]) -> int:
    """Say that every trial failed, with the errors counted by type (:func:`failure_counts`); exit code 1."""
    counts = ", ".join(f"{n} {kind}" for kind, n, _ in failures)
    print(f"handsim report: error: every trial failed ({failed} of {trials}): {counts}", file=sys.stderr)
    for kind, n, first in failures:
        print(f"  {kind} ×{n}, first: {first}", file=sys.stderr)
    return 1


def _report(args: argparse.Namespace) -> int:
    # lazy: the simulation stack (MuJoCo, trimesh), only for a run
    from handsim.sim.replay import ReplayConfig

    if args.render_only is not None:
        out = Path(args.render_only or args.output or "")
        if not str(out) or not (out / "records.jsonl").is_file():
            return usage_error("report", f"--render-only needs a run's folder with records.jsonl, got {out}")
        return _render_only(out)
    if args.dataset is None or args.output is None:
        return usage_error("report", "give DATASET and -o OUT (or --render-only OUT)")
    if args.mano_dir is not None:
        # lazy: the MANO reader, only with --mano-dir
        from handsim.io.arctic.mano import find_mano_files

        find_mano_files(args.mano_dir)  # before any work: says which files are needed and where to put them
    config = ReplayConfig(control_rate=args.rate, stability_at=None if args.stability == "none" else "grasp")
    options = trial_options_from_args(args)
    return run_and_render(
        args.dataset, args.output, workers=args.workers, backend=args.backend, address=args.address,
        config=config, frames=args.frames, only=args.only, limit=args.limit,
        command=["handsim", *sys.argv[1:]], options=options,
    )  # fmt: skip


def register(commands: Commands) -> None:
    """Add the ``report`` command."""
    report = commands.add_parser(
        "report",
        help="replay every trial of a dataset and write a physics-plausibility report (HTML, Markdown, JSON)",
        description="Find the trials of a dataset folder (GraspDB14 recordings, Tzionas Models/NN sequences, "
        "ARCTIC raw_seqs), replay each in MuJoCo on all cores (or Ray), append one record per trial to "
        "OUT/records.jsonl, and render the report from the records. A killed run restarted with the same "
        "command resumes; a failing trial is recorded and the run goes on. The report's terms (outcomes, "
        "hold rate, robustness, fit at, on track …): docs/concepts.md. Exit codes: 0 done, 1 handsim "
        f"error or every trial failed, 2 usage error, {EXIT_INTERRUPTED} interrupted.",
    )
    report.add_argument("dataset", nargs="?", metavar="DATASET", help="dataset folder or one recording")
    report.add_argument(
        "-o", "--output", type=output_dir, metavar="OUT", help="output folder (records, frames, report)"
    )
    report.add_argument(
        "--workers",
        type=positive_int,
        metavar="N",
        help="trials at once (default: all cores; 1 = in-process)",
    )
    report.add_argument("--backend", choices=("local", "ray"), default="local", help="process pool or Ray")
    report.add_argument(
        "--address", metavar="ADDR",
        help="with --backend ray: a running Ray cluster (HOST:PORT, or 'auto' for the one `ray start` "
        "started on this machine); default: start a Ray of N CPUs for this run",
    )  # fmt: skip
    report.add_argument(
        "--frames",
        type=non_negative_int,
        default=4,
        metavar="N",
        help="frames rendered per trial (default 4)",
    )
    report.add_argument(
        "--limit", type=non_negative_int, metavar="N", help="run only the first N trials (by id)"
    )
    report.add_argument("--only", metavar="GLOB", help="run only trials whose id matches (e.g. '*su04*')")
    report.add_argument(
        "--stability", choices=("grasp", "none"), default="grasp",
        help="grasp stability tests at the end of the hold window of glove trials (default), or none",
    )  # fmt: skip
    add_control_rate(report)
    add_arctic_options(report)
    report.add_argument(
        "--render-only", nargs="?", const="", metavar="OUT",
        help="render the report of OUT (or -o OUT) from its records, without simulating",
    )  # fmt: skip
    report.set_defaults(func=_report, simulates=True, command_parser=report)
