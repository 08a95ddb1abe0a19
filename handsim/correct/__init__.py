"""Physics correction: the smallest change to a recording that makes its simulated object follow its track.

* :func:`correct` / :func:`correct_trial` — a trial in, a :class:`Correction` out: the corrected motion
  (finger targets, and the wrist's mocap target where one is recorded), the committed simulation and its
  plausibility score (:class:`CorrectionScore`); :func:`write_corrected` stores it as a corrected trial
  (``NAME.corrected.npz``) that ``handsim replay`` replays bit for bit.
* :class:`CorrectionConfig` — every parameter with its reason; :data:`BUDGETS` — named search efforts.
* The method: annealed MPPI / predictive sampling in receding horizon (:mod:`handsim.correct.sampler`,
  :mod:`handsim.correct.planner`) on batched rollouts from a pluggable backend
  (:mod:`handsim.correct.rollouts`: ``mujoco.rollout`` on CPU threads, :mod:`handsim.correct.backend`; or
  MuJoCo Warp, :mod:`handsim.correct.warp_backend`, with ``handsim[warp]``).

Names are bound on first use, so that the command line reads the budgets (:mod:`handsim.correct.config`,
no MuJoCo) without importing the simulation.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from handsim.correct.config import BUDGETS, Budget, CorrectionConfig, CorrectionError

if TYPE_CHECKING:
    from handsim.correct.correction import Correction, correct, correct_trial
    from handsim.correct.score import CorrectionScore
    from handsim.correct.trial_file import write_corrected

_EXPORTS = {
    "Correction": "handsim.correct.correction",
    "correct": "handsim.correct.correction",
    "correct_trial": "handsim.correct.correction",
    "CorrectionScore": "handsim.correct.score",
    "write_corrected": "handsim.correct.trial_file",
}


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:  # lazy: start-up time, see the module docstring
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "BUDGETS",
    "Budget",
    "Correction",
    "CorrectionConfig",
    "CorrectionError",
    "CorrectionScore",
    "correct",
    "correct_trial",
    "write_corrected",
]
