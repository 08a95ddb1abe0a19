"""``handsim export minari``: a dataset run's replayed trials as a Minari dataset.

Exit codes: 0 written; 1 a handsim error (minari not installed, the dataset exists, another export of it
runs, no records, a trial that no longer reproduces its record …); 2 a usage error. What the export found
and put right before it began (what a killed export left, a stale lock) is printed as ``note`` lines.
"""

from __future__ import annotations

import argparse
import sys

from handsim.cli._common import Commands, positive_int


def _run_minari(args: argparse.Namespace) -> int:
    # lazy: MuJoCo and Minari (an optional extra), only for the export
    from handsim.export import export_minari
    from handsim.runner.execute import default_workers

    dataset = export_minari(
        args.out_dir,
        args.dataset_id,
        only=args.only,
        include_failed=args.include_failed,
        skip_mismatched=args.skip_mismatched,
        overwrite=args.overwrite,
        workers=default_workers() if args.workers is None else args.workers,
        rtol=args.rtol,
        atol=args.atol,
        author=args.author,
        author_email=args.author_email,
        code_permalink=args.code_permalink,
        progress=True,  # a bar on a terminal, nothing in a log (handsim.progress)
        on_note=lambda note: print(f"note        {note}", flush=True),
        command=["handsim", *sys.argv[1:]],
    )
    info = dataset.storage.metadata["handsim"]
    print(f"dataset     {args.dataset_id}")
    print(f"written to  {dataset.storage.data_path.parent}")
    print(f"episodes    {dataset.total_episodes} ({dataset.total_steps} steps of {info['dt']:g} s)")
    print(
        f"spaces      observation {dataset.observation_space.shape[0]} float64, action "
        f"{dataset.action_space.shape[0]} absolute joint targets (rad)"
    )
    for skipped in info["skipped"]:
        print(f"skipped     {skipped['id']} ({skipped['status']}): {skipped['reason']}")
    print(f"load it     minari.load_dataset({args.dataset_id!r})")
    return 0


def register(commands: Commands) -> None:
    """Add the ``export`` command (``export minari``)."""
    export = commands.add_parser(
        "export",
        help="export a dataset run's replayed trials (minari)",
        description="Export the trials a dataset run (handsim report DATASET -o OUT) replayed.",
    )
    formats = export.add_subparsers(dest="format", metavar="FORMAT", required=True)
    minari = formats.add_parser(
        "minari",
        help="write a Minari dataset (needs: pip install 'handsim[minari]')",
        description="Replay every trial of OUT/records.jsonl again through handsim/Replay-v0 with zero "
        "residuals, check it against its record (input SHA-256, model hash, summary numbers) and write "
        "the episodes as a Minari dataset under MINARI_DATASETS_PATH (default ~/.minari/datasets): "
        "observations as the environment's, actions = the absolute joint targets applied (not the "
        "environment's residuals), the environment's rewards, infos with contact forces, penetration, "
        "tracking error and object drift; each episode's metadata holds its trial id and the record's "
        "plausibility numbers. Diverged and failed trials are skipped and listed. Every trial's layout is "
        "checked before any is replayed. The dataset appears whole or not at all, also under kill -9: it "
        "is built aside and moved into place when complete (an --overwrite keeps the old one until then), "
        "and the next export puts right what a killed one left, printing a note.",
    )
    minari.add_argument("out_dir", metavar="OUT", help="the folder handsim report wrote (with records.jsonl)")
    minari.add_argument(
        "--dataset-id",
        required=True,
        metavar="ID",
        help="Minari dataset id, namespace/name-vN (handsim/NAME-v0)",
    )
    minari.add_argument(
        "--only", action="append", metavar="GLOB",
        help="export only the trial ids matching this shell pattern (repeatable)",
    )  # fmt: skip
    minari.add_argument(
        "--include-failed", action="store_true",
        help="also export diverged trials (the episode terminates at the divergence)",
    )  # fmt: skip
    minari.add_argument(
        "--skip-mismatched", action="store_true",
        help="skip (and list) trials that no longer reproduce their record instead of refusing the export",
    )  # fmt: skip
    minari.add_argument("--overwrite", action="store_true", help="replace an existing dataset of that id")
    minari.add_argument(
        "--workers", type=positive_int, default=None, metavar="N",
        help="processes replaying trials (default: all cores; 1 = in this process)",
    )  # fmt: skip
    minari.add_argument(
        "--rtol", type=float, default=1e-6, help="relative tolerance comparing summaries (default 1e-6)"
    )
    minari.add_argument(
        "--atol", type=float, default=1e-9, help="absolute tolerance comparing summaries (default 1e-9)"
    )
    minari.add_argument("--author", help="dataset author for Minari's metadata (left out if not given)")
    minari.add_argument(
        "--author-email", metavar="EMAIL", help="the author's contact (left out if not given)"
    )
    minari.add_argument(
        "--code-permalink", metavar="URL", help="link to the code that made the data (left out if not given)"
    )
    minari.set_defaults(func=_run_minari, simulates=True, command_parser=minari)
