"""``$HANDSIM_THREADS``: how many threads independent simulation runs use, read without importing MuJoCo.

:func:`handsim.sim.parallel.sim_threads` applies it; the ``handsim`` command checks it before any work
starts (a bad value is a usage error there, not a traceback once the trial has loaded).
"""

from __future__ import annotations

import os

THREADS_ENV = "HANDSIM_THREADS"
"""Environment variable: threads for independent simulation runs (a positive integer)."""


def threads_setting() -> int | None:
    """``$HANDSIM_THREADS`` as a positive integer, or None when it is unset or empty.

    Raises:
        ValueError: It is set but not a positive integer (the message names the variable and the value).
    """
    value = os.environ.get(THREADS_ENV, "").strip()
    if not value:
        return None
    try:
        threads = int(value)
    except ValueError:
        threads = 0
    if threads < 1:
        raise ValueError(f"${THREADS_ENV} must be a positive integer (threads), got {value!r}")
    return threads
