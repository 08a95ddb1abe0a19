"""A dataset run's correction job: each trial corrected (``handsim correct DATASET``), one record per trial.

:func:`correction_outcome` is what a backend runs per trial in place of the replay's
:func:`~handsim.runner.worker.trial_outcome`: it loads the trial, corrects it
(:func:`handsim.correct.correct`) and returns the record and the corrected trial's bytes
(``corrected/<safe-id>.corrected.npz``, written by the parent process like rendered frames). Records hold the
correction's score, its curves (strided and rounded as a replay record's) and the corrected file's SHA-256;
they are deterministic except for ``timing``, and the same for any backend and thread count (the correction
does not depend on the threads).

A trial that cannot be corrected by its nature (no object, or objects neither recorded nor placed into the
hand) is not a failure: its record says ``"ok"`` with the correction's status ``"not correctable"`` and the
reason.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass

from handsim.correct.config import CorrectionConfig, CorrectionError
from handsim.runner.records import json_ready
from handsim.runner.renders import safe_id
from handsim.runner.trial_record import curve_indices, rounded, versions
from handsim.runner.worker import TrialOutcome, error_of, identity_record
from handsim.trials import TrialEntry, load_trial

CORRECTED_DIR = "corrected"
"""Folder of a correction run's corrected trials, under its output folder."""
NOT_CORRECTABLE = "not correctable"
"""The correction status of a trial that cannot be corrected by its nature (the reason says why)."""


@dataclass(frozen=True)
class CorrectionJob:
    """The parameters of a correction run (what a backend hands each trial with it).

    Attributes:
        config: The correction's parameters (the seed among them).
    """

    config: CorrectionConfig

    def parameters(self, frames: int) -> dict:
        """The ``parameters`` of the run's records (``frames`` is unused: a correction renders none)."""
        return json_ready({"correction": self.config.to_dict()})

    def base_record(self, entry: TrialEntry, frames: int) -> dict:
        """A trial's record before it runs: identity, inputs, parameters, versions; status ``"error"``."""
        return {
            **identity_record(entry),
            "parameters": self.parameters(frames),
            "versions": versions(),
            "model_sha256": None,
            "scenario": None,
            "correction": None,
            "curves": None,
            "corrected_file": None,
            "notes": [],
            "error": None,
            "timing": None,
        }


def corrected_path(trial_id: str) -> str:
    """A trial's corrected file, relative to the run's output folder."""
    return f"{CORRECTED_DIR}/{safe_id(trial_id)}.corrected.npz"


def _curves(correction) -> dict:
    # lazy: the curves need the simulation stack, imported in the worker only
    from handsim.correct.curves import correction_curves, goal_window

    full = correction_curves(
        correction.reference, correction.plan.residual, correction.before, correction.after
    )
    idx = curve_indices(full["time_s"].shape[0])
    out: dict = {name: rounded(values[idx]) for name, values in full.items()}
    window = goal_window(correction.reference)
    out["hold_window_s"] = None if window is None else list(window)
    out["stride"] = int(idx[1] - idx[0]) if idx.size > 1 else 1
    return out


def correction_outcome(entry: TrialEntry, job: CorrectionJob, frames: int = 0) -> TrialOutcome:
    """Correct one trial and build its record, writing nothing.

    Args:
        entry: The trial.
        job: The correction's parameters.
        frames: Unused (a correction renders no frames); part of every backend's call.

    Returns:
        The record and the corrected trial's bytes (under :data:`CORRECTED_DIR`).
    """
    # lazy: the simulation stack (MuJoCo), in the worker only
    from handsim.correct.correction import correct
    from handsim.correct.score import implausible_text, relative_size
    from handsim.correct.trial_file import corrected_bytes

    start = time.perf_counter()
    timing = {"load_s": 0.0, "correct_s": 0.0, "total_s": 0.0}
    record = job.base_record(entry, frames)
    files: dict[str, bytes] = {}
    try:
        loaded = load_trial(entry.trial)
        timing["load_s"] = time.perf_counter() - start
        record["model_sha256"] = loaded.scene.model_sha256
        record["scenario"] = loaded.scene.setup.scenario
        record["notes"] = [*loaded.notes, *loaded.scene.setup.notes]
        try:
            correction = correct(loaded, job.config)
        except CorrectionError as exc:  # by its nature: listed with its reason, not a failure
            record.update(status="ok", correction={"status": NOT_CORRECTABLE, "reason": str(exc)})
        else:
            data = corrected_bytes(correction)
            path = corrected_path(entry.id)
            files[path] = data
            score = correction.score
            verdict = {
                **score.to_dict(),
                "size": relative_size(score),
                "implausible": implausible_text(score),
            }
            record.update(
                status="ok",
                correction=json_ready(verdict),
                curves=_curves(correction),
                corrected_file={"path": path, "sha256": hashlib.sha256(data).hexdigest()},
            )
        timing["correct_s"] = time.perf_counter() - start - timing["load_s"]
    except Exception as exc:  # a failing trial is recorded, never stops the run
        record.update(status="error", error=error_of(exc))
    timing["total_s"] = time.perf_counter() - start
    record["timing"] = {k: round(v, 3) for k, v in timing.items()}
    return TrialOutcome(record, files)
