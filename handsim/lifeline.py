"""Child processes that end with their parent: no worker outlives a ``kill -9`` of the handsim command.

Two mechanisms, both armed in every child handsim starts (the dataset run's pool workers, the CoACD
decomposition worker):

* :func:`die_with_parent` — Linux: the kernel sends the child ``SIGKILL`` when its parent dies
  (``prctl(PR_SET_PDEATHSIG)``), even while the child is busy in native code. (The kernel ties this to the
  parent *thread* that started the child: handsim starts its children from the thread that then waits for
  them, so that thread outlives them.)
* :func:`watch` — everywhere: a daemon thread blocks on something that ends only when the parent is gone
  (the parent's multiprocessing sentinel, or the child's stdin pipe, whose writing end only the parent
  holds) and then ends the process with :data:`EXIT_ORPHANED`.

This module imports the standard library only: the CoACD worker loads it by file path, without importing
handsim (and MuJoCo).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
from collections.abc import Callable

PR_SET_PDEATHSIG = 1
"""``prctl`` option: the signal the kernel sends this process when its parent dies (linux/prctl.h)."""
EXIT_ORPHANED = 1
"""Exit status of a child that ended because its parent died."""


def die_with_parent(parent_pid: int | None = None) -> bool:
    """Linux: have the kernel kill this process (``SIGKILL``) when its parent dies.

    Args:
        parent_pid: The parent's process id, when known: if the parent already died before this call
            (this process has another parent now), the process exits at once.

    Returns:
        True when armed; False where the system has no such request (not Linux, no C library).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        armed = libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False
    if parent_pid is not None and os.getppid() != parent_pid:
        os._exit(EXIT_ORPHANED)  # the parent died before the request was made
    return armed


def watch(parent_gone: Callable[[], object], name: str = "handsim-parent-watch") -> threading.Thread:
    """End this process once ``parent_gone()`` returns (a daemon thread calls it and waits).

    Args:
        parent_gone: Blocks until the parent process is gone (e.g. waits on its sentinel, or reads stdin
            to its end); any exception counts as gone.
        name: The thread's name.

    Returns:
        The started thread.
    """

    def run() -> None:
        try:
            parent_gone()
        finally:
            os._exit(EXIT_ORPHANED)  # from any thread, even while the main one is in native code

    thread = threading.Thread(target=run, name=name, daemon=True)
    thread.start()
    return thread
