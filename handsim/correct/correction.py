"""``correct``: a trial in, its physically corrected motion, the committed simulation and its score out.

The steps: pure replay of the recording (the "before"); the receding-horizon optimisation
(:func:`~handsim.correct.planner.optimise`); the replay core's replay of the corrected recording (the
"after", bitwise the optimisation's committed simulation); the plausibility score
(:mod:`handsim.correct.score`). :func:`~handsim.correct.trial_file.write_corrected` stores it as a corrected
trial that ``handsim replay`` replays to the same simulation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.correct.config import CorrectionConfig, CorrectionError
from handsim.correct.planner import Plan, optimise
from handsim.correct.reference import Reference, build_reference
from handsim.correct.rollouts import rollout_backend
from handsim.correct.score import CorrectionScore, score
from handsim.sim.replay import ReplayConfig, ReplayResult, replay
from handsim.trials import LoadedTrial, load_trial


@dataclass(frozen=True)
class Correction:
    """A corrected trial.

    Attributes:
        loaded: The trial corrected (its scene and recording).
        config: The correction's parameters.
        reference: The recording at the control rate and the residual layout.
        plan: The optimisation's result (residuals, the corrected recording, the committed states).
        before: Pure replay of the recording.
        after: Replay of the corrected recording (its states are the plan's, bitwise).
        score: The plausibility score.
        backend: The rollout backend's name.
        threads: The threads it ran on (the result does not depend on them).
    """

    loaded: LoadedTrial
    config: CorrectionConfig
    reference: Reference
    plan: Plan
    before: ReplayResult
    after: ReplayResult
    score: CorrectionScore
    backend: str
    threads: int


def correct(
    loaded: LoadedTrial,
    config: CorrectionConfig | None = None,
    *,
    backend: str = "cpu",
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Correction:
    """Correct a loaded trial.

    Args:
        loaded: The trial (:func:`handsim.trials.load_trial`): a scene whose objects follow recorded tracks,
            or a glove scene whose placed object the hand must hold (:mod:`handsim.correct.hold`).
        config: The parameters (default :class:`CorrectionConfig`).
        backend: The rollout backend (:data:`~handsim.correct.rollouts.BACKENDS`).
        threads: Its threads; None: ``$HANDSIM_THREADS``, else every core. The result does not depend on it.
        progress: Called with (frames committed, frames) after each planning step.

    Returns:
        The correction.

    Raises:
        CorrectionError: The trial has neither a recorded object nor a hold to judge.
        TrajectoryError: The recording does not fit the scene.
    """
    config = config or CorrectionConfig()
    # the hold (a glove scene) is judged on the committed simulation alone, not the robustness ensemble
    replay_config = ReplayConfig(control_rate=config.control_rate, keep_states=True, ensemble=False)
    reference = build_reference(loaded.scene, loaded.trajectory, config, replay_config.metrics)
    before = replay(loaded.scene, loaded.trajectory, replay_config)
    rollouts = rollout_backend(backend, threads)
    try:
        plan = optimise(reference, config, rollouts, progress)
    finally:
        rollouts.close()
    after = replay(loaded.scene, plan.trajectory, replay_config)
    if after.states is None or not np.array_equal(after.states, plan.qpos):
        raise CorrectionError(
            "the replay of the corrected recording differs from the simulation the correction committed; "
            "the corrected file would not replay to what was optimised"
        )
    return Correction(
        loaded=loaded,
        config=config,
        reference=reference,
        plan=plan,
        before=before,
        after=after,
        score=score(reference, config, plan.residual, before, after),
        backend=rollouts.name,
        threads=rollouts.threads,
    )


def correct_trial(
    path: str | Path,
    config: CorrectionConfig | None = None,
    *,
    backend: str = "cpu",
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> Correction:
    """Find, load and correct the trial of a recording (``options``: :func:`handsim.trials.find_trial`'s).

    Raises:
        HandsimError: The trial cannot be loaded (the subclass and message say why), or
            :class:`CorrectionError` as :func:`correct`.
    """
    return correct(load_trial(path, **options), config, backend=backend, threads=threads, progress=progress)
