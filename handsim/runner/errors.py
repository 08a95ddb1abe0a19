"""The runner's error: a dataset run that cannot start."""

from __future__ import annotations

from handsim.errors import HandsimError


class RunnerError(HandsimError):
    """A dataset run that cannot start (bad option, records of other parameters, Ray missing …)."""
