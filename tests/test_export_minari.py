"""Minari export: a dataset round-trips; the data are a direct Replay-v0 rollout's; every promised error."""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import handsim  # noqa: F401  (registers handsim/Replay-v0)
from handsim.errors import InputFileError
from handsim.export import (
    DatasetExistsError,
    ExportError,
    LayoutMismatchError,
    MissingExtraError,
    RecordMismatchError,
    export_minari,
    recover_replay_env,
)
from handsim.export.episode import INFO_DOCS, STEP_INFO_KEYS, replay_record
from handsim.runner.portable import portable_record
from handsim.sim.replay import ReplayConfig, replay
from handsim.trials import Trial, find_trial, load_trial
from tests.helpers import write_short_grasp

minari = pytest.importorskip("minari", reason="the Minari export needs: pip install 'handsim[minari]'")
pytest.importorskip("h5py", reason="minari's HDF5 storage needs h5py: pip install 'minari[hdf5]'")

DATASET_ID = "handsim/tzionas20-v0"
TRIAL_ID = "tzionas/Models/20"


def _sha256(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _record(trial: Trial, *, record_id: str = TRIAL_ID, status: str = "ok") -> dict:
    """A dataset run's record of ``trial``, as the runner writes one (replayed here)."""
    loaded = load_trial(trial)
    config = ReplayConfig()
    result = replay(loaded.scene, loaded.trajectory, config)
    files = [("trajectory", trial.trajectory_path), ("skeleton", trial.skeleton_path)]
    files += [("object", o.what) for o in trial.objects]
    inputs = [
        {"role": role, "path": path, "sha256": _sha256(path)}
        for role, path in files
        if path is not None and Path(path).is_file()
    ]
    return {
        "schema": 1,
        "id": record_id,
        "kind": trial.kind,
        "status": status,
        "meta": {"object": "cube", "sequence": "20"},
        "trial": trial.to_dict(),
        "parameters": {"replay": config.to_dict()},
        "summary": result.summary,
        "hold": None if result.hold is None else result.hold.to_dict(),
        "model_sha256": loaded.scene.model_sha256,
        "inputs": inputs,
    }


def _write_records(folder: Path, *records: dict) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return folder


@pytest.fixture(scope="module")
def datasets_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("minari_datasets")


@pytest.fixture(autouse=True)
def _minari_path(monkeypatch: pytest.MonkeyPatch, datasets_root: Path) -> None:
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(datasets_root))


@pytest.fixture(scope="module")
def record() -> dict:
    """The bundled Tzionas sequence 20 (hand + cube), replayed once like a dataset run does."""
    from handsim.assets import TZIONAS_DIR

    return _record(find_trial(TZIONAS_DIR / "Models" / "20"))


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory, record: dict) -> Path:
    """A run's folder: the good record, a diverged one and one that failed with an error."""
    diverged = {"schema": 1, "id": "x/diverged", "status": "diverged", "trial": record["trial"]}
    error = {"schema": 1, "id": "x/error", "status": "error", "error": {"message": "file not found"}}
    return _write_records(tmp_path_factory.mktemp("run"), error, record, diverged)


@pytest.fixture(scope="module")
def dataset(run_dir: Path, datasets_root: Path):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MINARI_DATASETS_PATH", str(datasets_root))
        export_minari(run_dir, DATASET_ID)
        return minari.load_dataset(DATASET_ID)


@pytest.fixture(scope="module")
def rollout() -> dict:
    """A direct rollout of the registered handsim/Replay-v0 (the bundled sequence 20), zero residuals."""
    env = gym.make("handsim/Replay-v0")
    obs, _ = env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    out = {"observations": [obs], "ctrl": [], "rewards": [], "terminated": [], "truncated": [], "infos": []}
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(zero)
        out["observations"].append(obs)
        out["ctrl"].append(env.unwrapped.data.ctrl.copy())
        out["rewards"].append(reward)
        out["terminated"].append(terminated)
        out["truncated"].append(truncated)
        out["infos"].append(info)
        done = terminated or truncated
    out["schedule"] = env.unwrapped.schedule
    out["ctrl_range"] = env.unwrapped.scene.layout.ctrl_range.copy()
    out["observation_names"] = env.unwrapped.observation_names
    out["observation_slices"] = env.unwrapped.observation_slices
    env.close()
    return {k: np.asarray(v) if isinstance(v, list) and k != "infos" else v for k, v in out.items()}


# ---- round trip -------------------------------------------------------------------------------------------


def test_dataset_loads_with_one_episode_per_exported_trial(dataset, rollout) -> None:
    assert len(dataset) == 1
    episode = dataset[0]
    steps = rollout["schedule"].frames - 1
    assert len(episode) == steps == 616
    assert episode.observations.shape == (steps + 1, len(rollout["observation_names"]))
    assert episode.actions.shape == (steps, rollout["ctrl_range"].shape[0])
    assert dataset.total_steps == steps


def test_observations_rewards_and_ends_equal_a_direct_replay_env_rollout(dataset, rollout) -> None:
    episode = dataset[0]
    np.testing.assert_array_equal(episode.observations, rollout["observations"])
    np.testing.assert_array_equal(episode.rewards, rollout["rewards"])
    np.testing.assert_array_equal(episode.terminations, rollout["terminated"])
    np.testing.assert_array_equal(episode.truncations, rollout["truncated"])
    assert not episode.terminations.any() and episode.truncations[-1] and not episode.truncations[:-1].any()


def test_actions_are_the_absolute_targets_applied_within_the_ctrl_ranges(dataset, rollout) -> None:
    episode = dataset[0]
    np.testing.assert_array_equal(episode.actions, rollout["ctrl"])
    lo, hi = rollout["ctrl_range"].T
    np.testing.assert_array_equal(episode.actions, np.clip(rollout["schedule"].ctrl[1:], lo, hi))
    np.testing.assert_array_equal(dataset.action_space.low, lo)
    np.testing.assert_array_equal(dataset.action_space.high, hi)
    assert all(dataset.action_space.contains(a) for a in episode.actions)
    assert dataset.observation_space.shape == (len(rollout["observation_names"]),)


def test_infos_have_one_row_per_observation_with_contacts_and_errors(dataset, rollout) -> None:
    episode = dataset[0]
    rows = len(episode) + 1
    assert set(episode.infos) == set(INFO_DOCS)
    assert all(value.shape[0] == rows for value in episode.infos.values())
    force = rollout["observation_slices"]["contact_force"]
    np.testing.assert_array_equal(episode.infos["contact_force"], episode.observations[:, force])
    assert episode.infos["contact_force"].shape[1] == force.stop - force.start
    assert episode.infos["contact_force"].max() > 0  # the hand grasps the cube
    assert (episode.infos["penetration"] >= 0).all()
    np.testing.assert_array_equal(episode.infos["frame"], np.arange(rows))
    for key in STEP_INFO_KEYS:
        assert np.isnan(episode.infos[key][0])
        np.testing.assert_array_equal(episode.infos[key][1:], [i[key] for i in rollout["infos"]])
    terms = sum(episode.infos[k][1:] for k in STEP_INFO_KEYS if k.startswith("reward_"))
    np.testing.assert_allclose(terms, episode.rewards, rtol=0, atol=1e-12)
    assert not episode.infos["diverged"].any()


def test_episode_metadata_identifies_the_trial_and_carries_the_record_plausibility(dataset, record) -> None:
    meta = next(iter(dataset.storage.get_episode_metadata([0])))
    assert meta["trial_id"] == TRIAL_ID
    assert meta["status"] == "ok"
    assert Trial.from_dict(json.loads(meta["trial"])) == Trial.from_dict(record["trial"])
    assert meta["meta"] == {"object": "cube", "sequence": "20"}
    for key in ("max_penetration_mm", "mean_drift_mm", "max_drift_mm", "frames"):
        assert meta["summary"][key] == record["summary"][key]
    assert meta["model_sha256"] == record["model_sha256"]


def test_dataset_metadata_documents_the_layout_and_lists_skipped_trials(dataset, rollout) -> None:
    info = dataset.storage.metadata["handsim"]
    assert info["observation_names"] == list(rollout["observation_names"])
    assert info["observation_slices"] == {
        g: [s.start, s.stop] for g, s in rollout["observation_slices"].items()
    }
    assert len(info["action_names"]) == dataset.action_space.shape[0]
    assert "NOT the actions of handsim/Replay-v0" in info["action"]
    assert info["exported"] == [TRIAL_ID]
    assert [(s["id"], s["status"]) for s in info["skipped"]] == [
        ("x/diverged", "diverged"),
        ("x/error", "error"),
    ]
    assert "file not found" in info["skipped"][1]["reason"]
    assert dataset.spec.env_spec is None  # the env is rebuilt from the trial, not from an id
    metadata = dataset.storage.metadata
    assert "absolute joint position targets" in metadata["description"]
    assert "code_permalink" not in metadata and "author" not in metadata  # nothing invented


def test_recover_replay_env_rebuilds_the_episode_environment(dataset) -> None:
    env = recover_replay_env(dataset, 0)
    obs, _ = env.reset(seed=0)
    episode = dataset[0]
    np.testing.assert_array_equal(obs, episode.observations[0])
    obs, *_ = env.step(np.zeros(env.action_space.shape))
    np.testing.assert_array_equal(obs, episode.observations[1])
    np.testing.assert_array_equal(env.data.ctrl, episode.actions[0])
    assert list(env.observation_names) == dataset.storage.metadata["handsim"]["observation_names"]
    with pytest.raises(ExportError, match=r"episode_index must be in \[0, 0\], got 1"):
        recover_replay_env(dataset, 1)


@pytest.mark.slow
def test_cli_export_in_worker_processes_gives_the_same_arrays(dataset, record, tmp_path, capsys) -> None:
    from handsim.cli import export as export_cli

    run = _write_records(tmp_path / "run", {**record, "id": "b/20"}, {**record, "id": "a/20"})
    parser = argparse.ArgumentParser(prog="handsim")
    export_cli.register(parser.add_subparsers())
    args = parser.parse_args(
        ["export", "minari", str(run), "--dataset-id", "handsim/twice-v0", "--workers", "2"]
    )
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "episodes    2 (1232 steps of 0.01 s)" in out
    assert "minari.load_dataset('handsim/twice-v0')" in out
    again = minari.load_dataset("handsim/twice-v0")
    ids = [m["trial_id"] for m in again.storage.get_episode_metadata([0, 1])]
    assert ids == ["a/20", "b/20"]  # sorted by trial id, not by the order of the lines
    for episode in again:
        np.testing.assert_array_equal(episode.observations, dataset[0].observations)
        np.testing.assert_array_equal(episode.actions, dataset[0].actions)
        np.testing.assert_array_equal(episode.rewards, dataset[0].rewards)
        for key, value in dataset[0].infos.items():
            np.testing.assert_array_equal(episode.infos[key], value)


# ---- refusals and errors ----------------------------------------------------------------------------------


def test_export_raises_error_if_minari_is_not_installed(run_dir, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "minari", None)
    with pytest.raises(MissingExtraError, match=r"pip install 'handsim\[minari\]'"):
        export_minari(run_dir, "handsim/none-v0")


def test_export_raises_error_if_h5py_is_not_installed(run_dir, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(
        MissingExtraError, match=r"HDF5 storage, which needs h5py: pip install 'handsim\[minari\]'"
    ):
        export_minari(run_dir, "handsim/none-v0")


def test_export_raises_error_if_the_dataset_exists(dataset, run_dir) -> None:
    with pytest.raises(DatasetExistsError, match=r"'handsim/tzionas20-v0' exists already .* --overwrite"):
        export_minari(run_dir, DATASET_ID)


def test_export_raises_error_if_records_are_missing(tmp_path) -> None:
    with pytest.raises(InputFileError, match=r"records\.jsonl does not exist"):
        export_minari(tmp_path, "handsim/missing-v0")


def test_export_raises_error_if_records_are_empty(tmp_path) -> None:
    (tmp_path / "records.jsonl").write_text("")
    with pytest.raises(ExportError, match=r"holds no record: nothing to export"):
        export_minari(tmp_path, "handsim/empty-v0")


@pytest.mark.parametrize("bad", ["handsim/no-version", "handsim/bad name-v0", ""])
def test_export_raises_error_if_the_dataset_id_is_malformed(run_dir, bad) -> None:
    with pytest.raises(ExportError, match=r"is not a Minari id with a version: use 'namespace/name-v0'"):
        export_minari(run_dir, bad)


def test_export_raises_error_if_only_matches_no_trial(run_dir) -> None:
    with pytest.raises(ExportError, match=r"--only graspdb/\* matches none of the 3 trial ids"):
        export_minari(run_dir, "handsim/only-v0", only="graspdb/*")


def test_export_raises_error_if_every_selected_trial_failed(run_dir) -> None:
    with pytest.raises(ExportError, match=r"no trial to export: 1 skipped \(x/diverged: diverged"):
        export_minari(run_dir, "handsim/failed-v0", only="x/div*")


def test_include_failed_replays_diverged_trials(run_dir, datasets_root) -> None:
    # the diverged record here has no summary: it is attempted (not skipped), and says what it lacks
    with pytest.raises(ExportError, match=r"trial 'x/diverged': the record has no summary"):
        export_minari(run_dir, "handsim/failed-v0", only="x/div*", include_failed=True)
    assert not (datasets_root / "handsim" / "failed-v0").exists()


def test_export_refuses_a_record_whose_input_file_changed(record, tmp_path, datasets_root) -> None:
    changed = json.loads(json.dumps(record))
    changed["inputs"][0]["sha256"] = "0" * 64
    run = _write_records(tmp_path / "run", changed)
    with pytest.raises(
        RecordMismatchError, match=r"inputs changed since the run: trajectory .*MOTION changed"
    ):
        export_minari(run, "handsim/changed-v0")
    assert not (datasets_root / "handsim" / "changed-v0").exists()


def test_relative_input_paths_are_checked_in_the_runs_dataset_folder(record, tmp_path) -> None:
    from handsim.assets import TZIONAS_DIR

    moved = json.loads(json.dumps(record))
    for entry in moved["inputs"]:  # as the runner writes them: relative to run.json's dataset folder
        entry["path"] = Path(entry["path"]).relative_to(TZIONAS_DIR).as_posix()
    moved["inputs"][0]["sha256"] = "0" * 64
    run = _write_records(tmp_path / "run", moved)
    (run / "run.json").write_text(json.dumps({"dataset": str(TZIONAS_DIR)}))
    motion = TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"
    with pytest.raises(
        RecordMismatchError, match=rf"trajectory {motion} changed: sha256 [0-9a-f]{{12}}… now"
    ):
        export_minari(run, "handsim/relative-v0")


def test_a_record_with_dataset_relative_paths_replays_from_the_runs_dataset_folder(record) -> None:
    from handsim.assets import TZIONAS_DIR

    portable = portable_record(record, str(TZIONAS_DIR))  # as the runner writes it
    assert portable["trial"]["trajectory_path"] == "Models/20/Model_Hand_R.MOTION"
    episode = replay_record(portable, root=TZIONAS_DIR)
    loaded = json.loads(episode.metadata["trial"])  # the files as loaded: absolute
    assert loaded["trajectory_path"] == str(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION")
    assert loaded["objects"][0]["what"] == str(TZIONAS_DIR / "Models" / "20" / "Model_Object_Cube.SKEL")


def test_export_refuses_a_record_whose_summary_differs_or_skips_it_when_asked(record, tmp_path) -> None:
    wrong = json.loads(json.dumps(record))
    wrong["id"] = "a/wrong"  # sorted first: the refusal comes before any episode is made
    wrong["summary"]["max_penetration_mm"] += 0.5
    run = _write_records(tmp_path / "run", record, wrong)
    with pytest.raises(RecordMismatchError, match=r"trial 'a/wrong': replaying it now gives other numbers.*"):
        export_minari(run, "handsim/wrong-v0", workers=1)
    data = export_minari(run, "handsim/wrong-v0", skip_mismatched=True)
    assert len(data) == 1
    (skipped,) = data.storage.metadata["handsim"]["skipped"]
    assert skipped["id"] == "a/wrong" and "max_penetration_mm" in skipped["reason"]


def test_failed_overwrite_keeps_the_dataset_it_would_replace(dataset, record, tmp_path) -> None:
    changed = json.loads(json.dumps(record))
    changed["inputs"][1]["sha256"] = "0" * 64
    run = _write_records(tmp_path / "run", changed)
    with pytest.raises(RecordMismatchError, match=r"skeleton .*SKEL changed"):
        export_minari(run, DATASET_ID, overwrite=True)
    kept = minari.load_dataset(DATASET_ID)
    np.testing.assert_array_equal(kept[0].observations, dataset[0].observations)


@pytest.mark.slow
def test_export_refuses_trials_with_different_layouts_in_one_dataset(record, graspdb_dir, tmp_path) -> None:
    glove = _record(find_trial(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt"), record_id="graspdb/01")
    run = _write_records(tmp_path / "run", record, glove)
    with pytest.raises(LayoutMismatchError, match=r"trial 'tzionas/Models/20' does not fit .* 'graspdb/01'"):
        export_minari(run, "handsim/mixed-v0")
    glove_data = export_minari(run, "handsim/glove-v0", only="graspdb/*")  # the glove scenario on its own
    assert len(glove_data) == 1
    meta = next(iter(glove_data.storage.get_episode_metadata([0])))
    assert meta["scenario"] == "glove"
    assert meta["summary"]["held"] == glove["summary"]["held"]
    assert meta["hold"]["held"] == glove["hold"]["held"]
    assert glove_data.storage.metadata["handsim"]["skipped"] == []


def test_trials_of_different_layouts_are_refused_before_any_is_replayed(
    record, tmp_path, datasets_root, monkeypatch
) -> None:
    from handsim.export import episode_replays

    grasp = write_short_grasp(tmp_path)  # the default hand, 27 DoFs
    scripted = _record(find_trial(grasp), record_id="a/cube")
    run = _write_records(tmp_path / "run", record, scripted, {**scripted, "id": "b/cube"})

    def replayed(*args, **kwargs):
        raise AssertionError("a trial was replayed before every layout was compared")

    monkeypatch.setattr(episode_replays, "replay_record", replayed)
    with pytest.raises(LayoutMismatchError) as caught:
        export_minari(run, "mixed/hands-v0")
    assert str(caught.value).startswith(
        "trial 'tzionas/Models/20' does not fit the dataset begun with trial 'a/cube': observation_names: "
        "156 vs 205 elements;"
    )
    assert (
        ". The 3 trials have 2 layouts: 2 like 'a/cube' (27 DoFs, 156 observations), 1 like "
        "'tzionas/Models/20' (31 DoFs, 205 observations). A Minari dataset has one observation and action "
        "space: export such trials as separate datasets (--only)"
    ) in str(caught.value)
    assert not (datasets_root / "mixed").exists()  # no namespace, no dataset, no work folder left
    assert not (datasets_root / ".handsim-export").exists()
