"""The receding horizon: plan from the committed state, commit a few frames with the replay core, repeat.

From the recording's first frame (the replay's own start: :meth:`~handsim.sim.drive.ScheduleDriver.reset`),
each planning step asks :class:`~handsim.correct.sampler.AnnealedSampler` for the residuals of the next
``horizon`` frames from the current state, then **commits** the first ``commit`` frames: it writes them into
the corrected recording, turns that into its control schedule with
:func:`~handsim.sim.control.control_schedule` (as ``handsim replay`` will), and steps the replay core's own
:class:`~handsim.sim.drive.ScheduleDriver` through them. The next step plans from the state that reached,
starting from the previous plan shifted by the frames committed (warm start). Planning covers the
reference's ``plan_start … plan_stop`` (every frame for recorded tracks; a glove scene's from the first frame
after contacts switch on to the hold window's end, :mod:`handsim.correct.hold`); the frames outside keep the
recording, stepped by the same driver with the scene's own switches (contacts on, the supports' release).

So the committed simulation is the replay of the corrected recording, frame by frame: the states this loop
records are bitwise those of :func:`handsim.sim.replay.replay` of the final corrected recording (pinned in
``tests/test_correct.py``), and a corrected file that stores it replays to exactly what was optimised.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from handsim.correct.backend import RolloutBackend, start_of
from handsim.correct.config import CorrectionConfig, CorrectionError
from handsim.correct.reference import Reference
from handsim.correct.sampler import AnnealedSampler, interpolate, knot_count
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScheduleDriver
from handsim.sim.stepper import Stepper


@dataclass(frozen=True)
class Plan:
    """A receding-horizon correction.

    Attributes:
        residual: The committed residual per control frame (F, D) (:mod:`handsim.correct.reference`);
            row 0 is zero (the recording's own start).
        trajectory: The corrected recording at the control rate.
        qpos: The committed simulation's state per frame (F, nq).
        planning_steps: Planning steps taken.
        rollouts: Candidate futures simulated.
        steps: MuJoCo steps simulated by the rollouts.
        seconds: Wall time of the loop, s.
        costs: The chosen plan's simulated cost per planning step.
        nominal_costs: The cost of the shifted previous plan per planning step (what not planning would
            have cost).
    """

    residual: np.ndarray
    trajectory: Trajectory
    qpos: np.ndarray
    planning_steps: int
    rollouts: int
    steps: int
    seconds: float
    costs: np.ndarray
    nominal_costs: np.ndarray


def committed_driver(
    reference: Reference, config: CorrectionConfig, residual: np.ndarray, stepper: Stepper
) -> ScheduleDriver:
    """The replay core's driver of the recording corrected by ``residual``, on ``stepper`` (not reset).

    Its schedule is :func:`~handsim.sim.control.control_schedule` of the corrected recording: what ``handsim
    replay`` drives when it replays the corrected file.
    """
    schedule = control_schedule(reference.scene, reference.corrected(residual), config.control_rate)
    return ScheduleDriver(stepper, schedule, reference.switches)


def optimise(
    reference: Reference,
    config: CorrectionConfig,
    backend: RolloutBackend,
    progress: Callable[[int, int], None] | None = None,
) -> Plan:
    """Correct the whole recording in receding horizon (module docstring).

    Args:
        reference: The recording (:func:`~handsim.correct.reference.build_reference`).
        config: The parameters; ``config.seed`` seeds the perturbations.
        backend: The rollout backend.
        progress: Called with (frames committed, frames) after each planning step.

    Returns:
        The plan and its committed simulation.

    Raises:
        CorrectionError: The committed simulation diverged.
    """
    schedule = reference.schedule
    frames, size = reference.frames, reference.size
    # a private model where contacts switch on during the run (the replay core's own choice)
    stepper = Stepper(reference.scene, schedule.substeps, own_model=reference.switches.contact_frame > 0)
    model, data = stepper.model, stepper.data
    sampler = AnnealedSampler(reference, config, backend, model, np.random.default_rng(config.seed))
    residual = np.zeros((frames, size))
    driver = committed_driver(reference, config, residual, stepper)
    driver.reset()
    qpos = np.empty((frames, model.nq))
    qpos[0] = data.qpos
    _commit(driver, qpos, 0, reference.plan_start)  # the recording's, until the hand can act on the object
    knot = config.knot
    nominal = np.zeros((knot_count(config.horizon, knot), size))
    costs, nominal_costs = [], []
    rollouts = steps = 0
    started = time.perf_counter()
    k, stop = reference.plan_start, reference.plan_stop
    while k < stop:
        ahead = min(config.horizon, frames - 1 - k)
        step = sampler.plan(k, ahead, nominal[: knot_count(ahead, knot)], start_of(model, data))
        costs.append(step.cost)
        nominal_costs.append(step.nominal_cost)
        rollouts += step.rollouts
        steps += step.rollouts * ahead * schedule.substeps
        commit = min(config.commit, stop - k)
        ahead_frames = np.arange(1, commit + 1)
        residual[k + 1 : k + 1 + commit] = reference.in_range(
            interpolate(step.knots, knot, ahead_frames), k + ahead_frames
        )
        driver = committed_driver(reference, config, residual, stepper)
        driver.frame = k  # the state is the committed one at k: the driver goes on from there
        _commit(driver, qpos, k, k + commit)
        nominal = interpolate(step.knots[None], knot, commit + knot * np.arange(nominal.shape[0]))[0]
        nominal[0] = residual[k + commit]  # the next plan starts from what was committed
        k += commit
        if progress is not None:
            progress(k, frames - 1)
    _commit(driver, qpos, k, frames - 1)  # after the hold window: the recording's
    return Plan(
        residual=residual,
        trajectory=reference.corrected(residual),
        qpos=qpos,
        planning_steps=len(costs),
        rollouts=rollouts,
        steps=steps,
        seconds=time.perf_counter() - started,
        costs=np.asarray(costs),
        nominal_costs=np.asarray(nominal_costs),
    )


def _commit(driver: ScheduleDriver, qpos: np.ndarray, start: int, stop: int) -> None:
    """Step the committed simulation from frame ``start`` to ``stop``, recording ``qpos`` per frame.

    Raises:
        CorrectionError: The committed simulation diverged.
    """
    data = driver.stepper.data
    for f in range(start, stop):
        stop_event = next((e for e in driver.advance(driver.schedule.ctrl[f + 1]) if e.diverged), None)
        if stop_event is not None:
            raise CorrectionError(f"the committed simulation diverged: {stop_event.describe()}")
        qpos[f + 1] = data.qpos
