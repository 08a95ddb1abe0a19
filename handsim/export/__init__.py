"""Exports of a dataset run's replayed trials to other formats.

* :func:`export_minari` (``handsim export minari OUT/ --dataset-id handsim/NAME-v0``): a Minari dataset of
  ``handsim/Replay-v0`` episodes (optional extra ``handsim[minari]``); :func:`recover_replay_env` rebuilds
  an episode's environment. A dataset appears whole or not at all (:mod:`handsim.export.staging`); one
  export per dataset id runs at a time (:class:`OutputBusyError` names the one running).

Importing this package does not import ``minari``; the export functions do, and say how to install it.
"""

from __future__ import annotations

from handsim.export.errors import (
    DatasetExistsError,
    ExportError,
    LayoutMismatchError,
    MissingExtraError,
    RecordMismatchError,
)
from handsim.export.minari_dataset import export_minari, recover_replay_env
from handsim.runner.output_lock import OutputBusyError

__all__ = [
    "DatasetExistsError",
    "ExportError",
    "LayoutMismatchError",
    "MissingExtraError",
    "OutputBusyError",
    "RecordMismatchError",
    "export_minari",
    "recover_replay_env",
]
