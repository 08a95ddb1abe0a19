"""What a dataset run's record says about its replay, and whether it still holds: parameters, inputs, summary.

:func:`~handsim.export.episode.replay_record` reads a record's replay parameters with :func:`replay_config`
and refuses it when an input changed (:func:`input_problems`) or the new replay's summary differs from the
recorded one (:func:`summary_problems`).
"""

from __future__ import annotations

import math
from pathlib import Path

from handsim.export.errors import ExportError
from handsim.runner.trial_record import sha256_file
from handsim.sim.replay import ReplayConfig
from handsim.sim.specs import MetricSpec

UNCHECKED_SUMMARY_KEYS = frozenset({"stable", "simulation_displacement_mm"})
"""Summary keys of the grasp stability tests: not re-run by an export (they are not part of an episode)."""


def replay_config(record: dict) -> ReplayConfig:
    """The replay parameters a record was made with (``record["parameters"]["replay"]``).

    The stability tests are not re-run (``stability_at=None``) and the states are kept.

    Raises:
        ExportError: The record has no replay parameters, or they are not this handsim's (another metric
            spec version, unknown fields).
    """
    rid = record.get("id", "?")
    params = (record.get("parameters") or {}).get("replay")
    if not isinstance(params, dict):
        raise ExportError(f"trial {rid!r}: the record has no parameters.replay (the replay configuration)")
    metrics = params.get("metrics") or {}
    if not isinstance(metrics, dict):
        raise ExportError(f"trial {rid!r}: parameters.replay.metrics is not an object")
    version = metrics.get("version", MetricSpec.version)
    if version != MetricSpec.version:
        raise ExportError(
            f"trial {rid!r}: recorded with metric spec version {version!r}; this handsim measures with "
            f"version {MetricSpec.version!r}: run the dataset again (handsim report) with this handsim"
        )
    try:
        spec = MetricSpec.from_dict(metrics)
        return ReplayConfig(
            control_rate=float(params.get("control_rate", ReplayConfig.control_rate)),
            metrics=spec,
            keep_states=True,
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise ExportError(f"trial {rid!r}: parameters.replay are not this handsim's: {exc}") from exc


def input_problems(record: dict, root: str | Path | None = None) -> list[str]:
    """Input files of a record that are missing or whose bytes changed (SHA-256), one line each.

    Args:
        record: The record (``inputs``: ``role``, ``path``, ``sha256``).
        root: The folder relative input paths are relative to (the run's dataset folder, ``run.json``'s
            ``dataset``); None: the current folder.

    Inputs without a ``sha256`` (unreadable during the run) and folders are not checked.
    """
    problems = []
    for entry in record.get("inputs") or ():
        path, expected = entry.get("path"), entry.get("sha256")
        if not path or not expected:
            continue
        p = Path(path)
        if not p.is_absolute() and root is not None:
            p = Path(root) / p
        role = entry.get("role", "input")
        if p.is_dir():
            continue
        if not p.is_file():
            problems.append(f"{role} {p} is missing")
            continue
        digest = sha256_file(p)
        if digest is None:
            problems.append(f"{role} {p} cannot be read")
            continue
        if digest != expected:
            problems.append(f"{role} {p} changed: sha256 {digest[:12]}… now, {expected[:12]}… in the record")
    return problems


def summary_problems(recorded: dict, replayed: dict, rtol: float, atol: float) -> list[str]:
    """Keys whose numbers differ between a record's summary and a new replay's, one line each.

    Numbers are equal within ``rtol``/``atol`` (each key in its own unit); booleans, integers and None
    exactly. Records store NaN and infinities as None (JSON has neither), so those count as None. Keys
    only one side has and the stability keys (:data:`UNCHECKED_SUMMARY_KEYS`) are skipped.
    """
    problems = []
    for key in sorted(set(recorded) & set(replayed) - UNCHECKED_SUMMARY_KEYS):
        a, b = _json_number(recorded[key]), _json_number(replayed[key])
        floats = _is_number(a) and _is_number(b) and (isinstance(a, float) or isinstance(b, float))
        same = _close(float(a), float(b), rtol, atol) if floats else a == b
        if not same:
            problems.append(f"{key}: {a!r} in the record, {b!r} replayed now")
    return problems


def _json_number(x: object) -> object:
    """None for a NaN or an infinity (as a record stores them), else ``x``."""
    return None if isinstance(x, float) and not math.isfinite(x) else x


def _is_number(x: object) -> bool:
    """Whether ``x`` is an int or a float (a boolean is not a number here)."""
    return isinstance(x, int | float) and not isinstance(x, bool)


def _close(a: float, b: float, rtol: float, atol: float) -> bool:
    """Whether two numbers are equal within ``rtol`` (relative) or ``atol`` (absolute)."""
    return math.isclose(a, b, rel_tol=rtol, abs_tol=atol)
