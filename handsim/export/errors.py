"""Errors of the exports: each names the trial, file or option at fault and what to do about it."""

from __future__ import annotations

from handsim.errors import HandsimError


class ExportError(HandsimError):
    """An export cannot be made from the records and options given."""


class MissingExtraError(ExportError):
    """An optional dependency of an export is not installed (the message says which extra to install)."""


class DatasetExistsError(ExportError):
    """The dataset to write exists already (replace it with ``overwrite=True`` / ``--overwrite``)."""


class RecordMismatchError(ExportError):
    """Replaying a record does not give what the record says.

    An input file changed, the model built from the inputs differs, the replay diverges differently or its
    summary numbers differ. Exporting would write data other than what the run measured, so the export
    refuses (or, asked to, skips the trial and lists it).
    """


class LayoutMismatchError(ExportError):
    """Two trials of one export have different observation layouts, hands or control rates.

    A Minari dataset has one observation space and one action space: export such trials as separate
    datasets (select them with ``only``/``--only``).
    """
