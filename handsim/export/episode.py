"""A dataset run's record replayed again as an episode of ``handsim/Replay-v0``, checked against the record.

:func:`replay_record` rebuilds a trial's scene from its record (``record["trial"]``, the run's replay
parameters), checks that it still is the trial the run measured — the inputs' SHA-256, the model's hash,
the replay's summary numbers — and steps :class:`~handsim.envs.replay_env.ReplayEnv` through it with zero
residuals. The result (:class:`ReplayedEpisode`) holds plain arrays and is picklable, so that worker
processes can make episodes for one writer.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, fields
from pathlib import Path

import mujoco
import numpy as np

from handsim.envs.replay_env import ReplayEnv
from handsim.envs.replay_reward import STEP_NUMBERS
from handsim.errors import HandsimError
from handsim.export.errors import ExportError, RecordMismatchError
from handsim.export.record_checks import input_problems, replay_config, summary_problems
from handsim.runner.portable import record_trial
from handsim.sim.replay import ReplayConfig
from handsim.trials import LoadedTrial, load_trial, replay_trial

ENV_ID = "handsim/Replay-v0"
"""The environment the episodes are steps of."""
RESET_SEED = 0
"""Seed of every episode's ``reset`` (the environment draws nothing without ``random_start``)."""
MAX_WARNINGS_KEPT = 20
"""MuJoCo warnings described in an episode's metadata (the count is always kept)."""

STEP_INFO_KEYS = tuple(key for key in STEP_NUMBERS if key != "penetration")
"""Entries of the environment's ``info`` that exist only after a step (NaN in the reset row); ``penetration``
is read from the observation, which the reset row has too."""
INFO_DOCS = {
    "frame": "control frame index of the row's observation (0 = the reset state)",
    "time": "trajectory time of that frame, s",
    "contact_force": "total contact normal force on each hand link from all object parts, N "
    "(links in the order of metadata['handsim']['link_names']; the observation's contact_force)",
    "penetration": "deepest hand-object penetration, m (>= 0)",
    "tracking_error": "RMS of joint angle minus recorded target over the hand DoFs, rad (NaN at reset)",
    "object_drift": "largest distance of a recorded object from its recording, m (NaN at reset)",
    "reward_tracking": "reward term: joint tracking (NaN at reset)",
    "object_rotation_error": "largest rotation angle of a recorded object from its recording, rad "
    "(NaN at reset)",
    "reward_object": "reward term: recorded object following its recording (NaN at reset)",
    "reward_rotation": "reward term: recorded object's orientation following its recording (NaN at reset)",
    "reward_articulation": "reward term: articulated object's angle following its recording (NaN at reset)",
    "reward_held": "reward term: object held, scenes without recorded objects (NaN at reset)",
    "reward_penetration": "reward term: penetration penalty (NaN at reset)",
    "reward_action": "reward term: residual action penalty, 0 here (NaN at reset)",
    "diverged": "MuJoCo diverged during the step that reached this row (the episode terminates there)",
}
"""The per-row ``infos`` of an episode (one row per observation) and what each holds."""


@dataclass(frozen=True)
class EpisodeLayout:
    """What must be equal for episodes to share one Minari dataset.

    Attributes:
        observation_names: Name of every observation element (``hand_qpos/if_mcp_flex`` …).
        observation_slices: ``(group, start, stop)`` of every observation group.
        dof_names: Hand DoFs in actuator order: the action's elements.
        ctrl_range: ``(lower, upper)`` control range of each actuator, rad.
        link_names: Hand links with collision geometry: the ``contact_force`` elements.
        dt: Seconds per step (control frame).
    """

    observation_names: tuple[str, ...]
    observation_slices: tuple[tuple[str, int, int], ...]
    dof_names: tuple[str, ...]
    ctrl_range: tuple[tuple[float, float], ...]
    link_names: tuple[str, ...]
    dt: float

    def differences(self, other: EpisodeLayout) -> list[str]:
        """Names of the fields that differ from ``other``'s, with a short description of each."""
        out = []
        for f in fields(self):
            mine, theirs = getattr(self, f.name), getattr(other, f.name)
            if mine != theirs:
                if isinstance(mine, tuple) and len(mine) != len(theirs):
                    out.append(f"{f.name}: {len(mine)} vs {len(theirs)} elements")
                else:
                    out.append(f"{f.name}: {_first_difference(mine, theirs)}")
        return out


def _first_difference(a: object, b: object) -> str:
    if isinstance(a, tuple) and isinstance(b, tuple):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            if x != y:
                return f"element {i}: {x!r} vs {y!r}"
    return f"{a!r} vs {b!r}"


@dataclass(frozen=True)
class ReplayedEpisode:
    """One trial replayed through ``handsim/Replay-v0`` with zero residuals (N steps).

    Attributes:
        trial_id: The record's id.
        observations: (N + 1, n) float64: the reset observation, then the one after every step.
        actions: (N, nu) float64: the joint targets the actuators held during each step (``data.ctrl``,
            rad, actuator order), i.e. the recorded targets clipped to the control ranges — not the
            environment's residual actions (which were all zero).
        rewards: (N,) the environment's rewards.
        terminations: (N,) bool: the step diverged.
        truncations: (N,) bool: the step reached the last frame.
        infos: Per-row arrays (N + 1 rows, :data:`INFO_DOCS`).
        layout: The observation and action layout.
        metadata: Flat episode metadata (``/`` separates levels): the trial, the record's summary,
            hold outcome and meta fields, the replay's warnings.
    """

    trial_id: str
    observations: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray
    infos: dict[str, np.ndarray]
    layout: EpisodeLayout
    metadata: dict


def flat_metadata(prefix: str, value: object, out: dict) -> None:
    """Add ``value`` to ``out`` as HDF5-storable attributes.

    Dicts become ``prefix/key`` entries (Minari reads ``/`` back as nesting); None is left out; numbers,
    booleans and strings are kept; anything else (lists) is stored as its JSON text.
    """
    if isinstance(value, dict):
        for key, item in value.items():
            flat_metadata(f"{prefix}/{key}" if prefix else str(key), item, out)
    elif value is None:
        return
    elif isinstance(value, bool | int | float | str):
        out[prefix] = value
    elif isinstance(value, np.generic):
        out[prefix] = value.item()
    else:
        out[prefix] = json.dumps(value, default=str)


def record_layout(record: dict, *, root: str | Path | None = None) -> EpisodeLayout:
    """The observation and action layout a record's episode would have, without replaying it.

    Checks what :func:`replay_record` checks before replaying (the record's fields, the inputs' SHA-256,
    the model's hash), then builds the trial's environment: an export compares every trial's layout
    before it replays any.

    Args:
        record: One line of a run's ``records.jsonl``.
        root: The folder relative input paths are relative to (the run's dataset folder).

    Returns:
        The layout.

    Raises:
        ExportError: The record lacks what an episode needs (trial, parameters, summary).
        RecordMismatchError: An input changed or is missing, the trial no longer loads, or its model differs.
    """
    rid, config, loaded = _loaded(record, root)
    env = _replay_env(rid, loaded, config)
    try:
        return episode_layout(env)
    finally:
        env.close()


def replay_record(
    record: dict, *, root: str | Path | None = None, rtol: float = 1e-6, atol: float = 1e-9
) -> ReplayedEpisode:
    """Replay a record's trial through ``handsim/Replay-v0`` with zero residuals, checked against the record.

    Checks, in order: the input files' SHA-256 (``record["inputs"]``), the model's hash
    (``record["model_sha256"]``), the replay's summary (``record["summary"]``, within ``rtol``/``atol``),
    and that the environment's states equal :func:`handsim.sim.replay.replay`'s bitwise.

    Args:
        record: One line of a run's ``records.jsonl`` (with ``id``, ``trial``, ``parameters.replay``,
            ``summary``; ``inputs`` and ``model_sha256`` are checked when present).
        root: The folder relative input paths are relative to (the run's dataset folder).
        rtol: Relative tolerance of the summary comparison.
        atol: Absolute tolerance of the summary comparison (in each key's unit: mm, deg, N …).

    Returns:
        The episode.

    Raises:
        ExportError: The record lacks what an episode needs (trial, parameters, summary).
        RecordMismatchError: The record cannot be reproduced: an input changed or is missing, the trial no
            longer loads, the model or the summary differ (the message lists every difference).
    """
    rid, config, loaded = _loaded(record, root)
    try:
        result = replay_trial(loaded, config)
    except HandsimError as exc:
        raise RecordMismatchError(f"trial {rid!r}: cannot be replayed any more: {exc}") from exc
    problems = summary_problems(record["summary"], result.summary, rtol, atol)
    if problems:
        then = (record.get("versions") or {}).get("mujoco", "not recorded")
        raise RecordMismatchError(
            f"trial {rid!r}: replaying it now gives other numbers than the record (mujoco "
            f"{mujoco.__version__} now, {then} in the run): {'; '.join(problems)}"
        )
    env = _replay_env(rid, loaded, config)
    try:
        episode = _rollout(env)
    finally:
        env.close()
    states, steps = episode.pop("qpos"), len(episode["rewards"])
    expected = states.shape[0] - 1 if result.diverged is None else states.shape[0]
    if steps != expected or not np.array_equal(states[: result.states.shape[0]], result.states):
        raise RecordMismatchError(
            f"trial {rid!r}: {ENV_ID} did not reproduce the replay core ({steps} steps, replay "
            f"{result.states.shape[0]} frames, diverged={result.diverged is not None}); this is a handsim "
            "bug, please report it"
        )
    metadata = _episode_metadata(record, result, loaded)
    return ReplayedEpisode(trial_id=rid, metadata=metadata, **episode)


def _loaded(record: dict, root: str | Path | None) -> tuple[str, ReplayConfig, LoadedTrial]:
    """The record's id, replay parameters and trial, loaded after checking its fields, inputs and model."""
    rid = str(record.get("id", "?"))
    if not isinstance(record.get("trial"), dict):
        raise ExportError(f"trial {rid!r}: the record has no trial (the files to load)")
    if not isinstance(record.get("summary"), dict):
        raise ExportError(f"trial {rid!r}: the record has no summary to check a new replay against")
    config = replay_config(record)
    problems = input_problems(record, root)
    if problems:
        raise RecordMismatchError(f"trial {rid!r}: its inputs changed since the run: {'; '.join(problems)}")
    try:
        loaded = load_trial(record_trial(record, root), metrics=config.metrics)
    except HandsimError as exc:
        raise RecordMismatchError(f"trial {rid!r}: cannot be replayed any more: {exc}") from exc
    _check_model(rid, record, loaded.scene.model_sha256)
    return rid, config, loaded


def _replay_env(rid: str, loaded: LoadedTrial, config: ReplayConfig) -> ReplayEnv:
    """The trial's ``handsim/Replay-v0`` as the run replayed it (the whole recording, no drift limit)."""
    try:
        return ReplayEnv(
            loaded.scene,
            loaded.trajectory,
            control_rate=config.control_rate,
            release_delay=config.metrics.release_delay,
            max_object_drift=None,
        )
    except HandsimError as exc:
        raise RecordMismatchError(f"trial {rid!r}: cannot be replayed any more: {exc}") from exc


def _check_model(rid: str, record: dict, model_sha256: str) -> None:
    recorded = record.get("model_sha256")
    if recorded and recorded != model_sha256:
        raise RecordMismatchError(
            f"trial {rid!r}: the model built now differs from the run's (model sha256 {model_sha256[:12]}… "
            f"now, {recorded[:12]}… in the record): the builders or the handsim version changed; run the "
            "dataset again"
        )


def episode_layout(env: ReplayEnv) -> EpisodeLayout:
    """The observation and action layout of a ``handsim/Replay-v0`` environment."""
    slices = env.unwrapped.observation_slices
    layout = env.unwrapped.scene.layout
    return EpisodeLayout(
        observation_names=tuple(env.unwrapped.observation_names),
        observation_slices=tuple((g, s.start, s.stop) for g, s in slices.items()),
        dof_names=tuple(layout.dof_names),
        ctrl_range=tuple((float(lo), float(hi)) for lo, hi in layout.ctrl_range),
        link_names=tuple(layout.link_names),
        dt=float(env.unwrapped.dt),
    )


def _rollout(env: ReplayEnv) -> dict:
    """Step ``env`` with zero residuals until it ends; the episode's arrays (and qpos per row)."""
    data = env.unwrapped.data
    obs, info = env.reset(seed=RESET_SEED)
    zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    observations, actions, rewards, terms, truncs, qpos = [obs], [], [], [], [], [data.qpos.copy()]
    infos = [info]
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(zero)
        observations.append(obs)
        actions.append(data.ctrl.copy())
        rewards.append(reward)
        terms.append(terminated)
        truncs.append(truncated)
        infos.append(info)
        qpos.append(data.qpos.copy())
        done = terminated or truncated
    slices = env.unwrapped.observation_slices
    obs_array = np.asarray(observations, dtype=np.float64)
    force, pen = slices["contact_force"], slices["penetration"]
    info_arrays = {
        "frame": np.array([i["frame"] for i in infos], dtype=np.int64),
        "time": np.array([i["time"] for i in infos], dtype=np.float64),
        "contact_force": obs_array[:, force].copy(),
        "penetration": obs_array[:, pen.start].copy(),
    }
    for key in STEP_INFO_KEYS:
        info_arrays[key] = np.array([math.nan] + [float(i[key]) for i in infos[1:]], dtype=np.float64)
    info_arrays["diverged"] = np.array([False] + [bool(i["diverged"]) for i in infos[1:]], dtype=bool)
    return {
        "observations": obs_array,
        "actions": np.asarray(actions, dtype=np.float64),
        "rewards": np.asarray(rewards, dtype=np.float64),
        "terminations": np.asarray(terms, dtype=bool),
        "truncations": np.asarray(truncs, dtype=bool),
        "infos": info_arrays,
        "layout": episode_layout(env),
        "qpos": np.asarray(qpos),
    }


def _episode_metadata(record: dict, result, loaded) -> dict:
    """The episode's metadata: who the trial is and what the run measured (plausibility fields)."""
    out: dict = {}
    flat_metadata(
        "",
        {
            "trial_id": record["id"],
            "status": record.get("status"),
            "kind": record.get("kind", loaded.trial.kind),
            "trial": json.dumps(loaded.trial.to_dict(), sort_keys=True),
            "inputs": json.dumps(record.get("inputs") or [], sort_keys=True),
            "parameters": json.dumps(record["parameters"]["replay"], sort_keys=True),
            "model_sha256": loaded.scene.model_sha256,
            "scenario": loaded.scene.setup.scenario,
            "hand": loaded.hand,
            "objects": json.dumps([o.name for o in loaded.objects]),
            "meta": record.get("meta") or {},
            "summary": record["summary"],
            "hold": record.get("hold") or {},
            "warnings": len(result.warnings),
            "warning_messages": json.dumps([w.describe() for w in result.warnings[:MAX_WARNINGS_KEPT]]),
            "diverged_at": None if result.diverged is None else result.diverged.describe(),
        },
        out,
    )
    return out
