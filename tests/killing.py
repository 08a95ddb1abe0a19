"""Run ``handsim ARGS`` and kill it with SIGKILL (or stop it) at a chosen call: what ``kill -9`` leaves.

Usage: ``python tests/killing.py MODULE:ATTR N before|after kill|stop [MATCH] -- ARGS...``

The callable ``MODULE:ATTR`` (``os:rename``, ``handsim.export.minari_writer:MinariWriter.add``) is wrapped
before the command runs: at its ``N``-th call (counting only calls whose ``repr`` of the arguments contains
``MATCH``, when given) the process sends itself ``SIGKILL`` (``kill``) or ``SIGSTOP`` (``stop``: it stays,
frozen, holding what it holds, until the test kills it), before or after the real call. A kill placed this
way lands at one exact step of the code under test, which polling from outside cannot hit (the two renames
of a dataset swap are microseconds apart). Nothing in handsim knows about it: the process dies as under an
operator's ``kill -9``.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys


def _arm(target: str, count: int, when: str, action: str, match: str | None) -> None:
    module_name, _, path = target.partition(":")
    owner = importlib.import_module(module_name)
    *parents, name = path.split(".")
    for parent in parents:
        owner = getattr(owner, parent)
    real = getattr(owner, name)
    sig = signal.SIGKILL if action == "kill" else signal.SIGSTOP
    calls = 0

    def wrapper(*args, **kwargs):
        nonlocal calls
        hit = match is None or match in repr(args)
        calls += hit
        now = hit and calls == count
        if now and when == "before":
            os.kill(os.getpid(), sig)
        result = real(*args, **kwargs)
        if now and when == "after":
            os.kill(os.getpid(), sig)
        return result

    setattr(owner, name, wrapper)


def main(argv: list[str]) -> int:
    split = argv.index("--")
    spec, args = argv[:split], argv[split + 1 :]
    target, count, when, action, *match = spec
    if when not in ("before", "after") or action not in ("kill", "stop"):
        raise SystemExit(f"usage: {__doc__.splitlines()[2]}")
    _arm(target, int(count), when, action, match[0] if match else None)
    from handsim.cli import main as handsim

    return handsim(args)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
