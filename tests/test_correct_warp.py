"""The MuJoCo Warp rollout backend: the same rollouts as ``mujoco.rollout``, to float32, on Warp's CPU device.

What is pinned: a control vector's layout (MuJoCo's state order); asking for the backend without MuJoCo
Warp says how to install it; with it (``handsim[warp]``; these tests skip without), rollouts of the bundled
tennis-ball grasp agree with :class:`~handsim.correct.backend.CpuRollout`'s in every state and sensor, a
batch repeated gives the same bits on the CPU device whatever ran before, a contact switch gets a device
model of its own, buffers that overflow are enlarged and the batch rerun, and a correction planned on it
writes a file that replays bit for bit (the replay core commits it on the CPU).
"""

from __future__ import annotations

import sys

import mujoco
import numpy as np
import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.correct import CorrectionConfig, correct
from handsim.correct.backend import CONTROLS, SWITCHED_CONTROLS, CpuRollout, start_of
from handsim.correct.config import CorrectionError
from handsim.correct.planner import committed_driver
from handsim.correct.reference import build_reference
from handsim.correct.rollouts import rollout_backend
from handsim.correct.sampler import AnnealedSampler
from handsim.correct.warp_backend import control_layout
from handsim.sim.replay import ReplayConfig
from handsim.sim.stepper import Stepper
from handsim.trials import load_trial

BALL = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"
XFRC = int(mujoco.mjtState.mjSTATE_XFRC_APPLIED)


def _warp_installed() -> bool:
    try:
        import mujoco_warp  # noqa: F401
        import warp  # noqa: F401
    except ImportError:
        return False
    return True


needs_warp = pytest.mark.skipif(
    not _warp_installed(), reason="MuJoCo Warp is not installed (pip install 'handsim[warp]')"
)
"""With MuJoCo Warp only; such a test is slow: Warp compiles its kernels for the model on first use (about a
minute on a cold kernel cache)."""


@pytest.fixture(scope="module")
def ball():
    return load_trial(BALL)


def test_a_control_vector_is_laid_out_in_mujocos_state_order(ball):
    model = ball.scene.model
    layout = control_layout(model, int(SWITCHED_CONTROLS) | XFRC)
    ctrl, xfrc, eq, pos, quat = (
        int(b)
        for b in (
            mujoco.mjtState.mjSTATE_CTRL,
            mujoco.mjtState.mjSTATE_XFRC_APPLIED,
            mujoco.mjtState.mjSTATE_EQ_ACTIVE,
            mujoco.mjtState.mjSTATE_MOCAP_POS,
            mujoco.mjtState.mjSTATE_MOCAP_QUAT,
        )
    )
    assert list(layout) == [ctrl, xfrc, eq, pos, quat]
    assert layout[ctrl] == slice(0, model.nu)
    assert layout[xfrc] == slice(layout[ctrl].stop, layout[ctrl].stop + 6 * model.nbody)
    assert layout[quat].stop == mujoco.mj_stateSize(model, int(SWITCHED_CONTROLS) | XFRC)
    with pytest.raises(CorrectionError, match="does not set the control elements"):
        control_layout(model, int(CONTROLS) | int(mujoco.mjtState.mjSTATE_USERDATA))


def test_asking_for_warp_without_it_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco_warp", None)  # an import of it raises ImportError
    with pytest.raises(CorrectionError, match=r"pip install 'handsim\[warp\]'"):
        rollout_backend("warp")


def test_the_cli_says_at_once_that_warp_is_missing(monkeypatch, tmp_path, capsys):
    from handsim.cli import main

    monkeypatch.setitem(sys.modules, "mujoco_warp", None)
    out = tmp_path / "ball.corrected.npz"
    assert main(["correct", str(BALL), "-o", str(out), "--rollouts", "warp"]) == 1
    captured = capsys.readouterr()
    assert "pip install 'handsim[warp]'" in captured.err
    assert "trial" not in captured.out and not out.exists()  # refused before the trial was loaded


@pytest.fixture(scope="module")
def batch(ball):
    """Four perturbed 10-frame futures of the ball grasp from three frames after planning starts."""
    config = CorrectionConfig(samples=4, horizon=10)
    reference = build_reference(ball.scene, ball.trajectory, config, ReplayConfig().metrics)
    stepper = Stepper(reference.scene, reference.schedule.substeps, own_model=True)
    driver = committed_driver(reference, config, np.zeros((reference.frames, reference.size)), stepper)
    driver.reset()
    k = reference.plan_start + 3
    for f in range(k):
        driver.advance(driver.schedule.ctrl[f + 1])
    start = start_of(stepper.model, stepper.data)
    sampler = AnnealedSampler(reference, config, CpuRollout(1), stepper.model, np.random.default_rng(0))
    residual = np.random.default_rng(1).normal(0.0, 0.05, (4, config.horizon, reference.size))
    controls = sampler.controls(residual, k + np.arange(1, config.horizon + 1), start)
    return stepper.model, start, controls, sampler.spec(False)


@pytest.fixture(scope="module")
def warp_backend():
    if not _warp_installed():
        pytest.skip("MuJoCo Warp is not installed (pip install 'handsim[warp]')")
    from handsim.correct.warp_backend import WarpRollout

    backend = WarpRollout(device="cpu")
    yield backend
    backend.close()


def _assert_agree(states: np.ndarray, cpu: np.ndarray, model: mujoco.MjModel) -> None:
    """Positions to 1e-5 (m, rad) and velocities to 1e-2 (m/s, rad/s): float32 against float64 over 50 steps
    of a hand holding a ball (measured: 7e-7 and 2.3e-4)."""
    q = slice(1, 1 + model.nq)
    np.testing.assert_allclose(states[..., q], cpu[..., q], rtol=0, atol=1e-5)
    np.testing.assert_allclose(states[..., q.stop :], cpu[..., q.stop :], rtol=0, atol=1e-2)
    np.testing.assert_allclose(states[..., 0], cpu[..., 0], rtol=0, atol=1e-6)  # time


def _cpu(model, start, controls, spec):
    backend = CpuRollout(1)
    try:
        return backend.rollout(model, start, controls, spec, True)
    finally:
        backend.close()


@needs_warp
@pytest.mark.slow
def test_warp_rollouts_agree_with_mujoco_rollout(batch, warp_backend):
    model, start, controls, spec = batch
    cpu_states, cpu_sensors = _cpu(model, start, controls, spec)
    states, sensors = warp_backend.rollout(model, start, controls, spec, True)
    assert states.shape == cpu_states.shape and sensors.shape == cpu_sensors.shape
    _assert_agree(states, cpu_states, model)
    np.testing.assert_allclose(sensors, cpu_sensors, rtol=0, atol=1e-2 * np.abs(cpu_sensors).max())
    assert not np.allclose(states[:, -1], states[:, 0])  # the futures move


@needs_warp
@pytest.mark.slow
def test_a_warp_batch_repeats_bitwise_whatever_ran_before(batch, warp_backend):
    model, start, controls, spec = batch
    first, _ = warp_backend.rollout(model, start, controls, spec, True)
    warp_backend.rollout(model, start, controls[::-1].copy(), spec, True)  # other futures in between
    again, _ = warp_backend.rollout(model, start, controls, spec, True)
    assert np.array_equal(first, again)


@needs_warp
@pytest.mark.slow
def test_a_guiding_force_acts_as_on_the_cpu(batch, warp_backend):
    model, start, controls, spec = batch
    force = np.zeros((*controls.shape[:2], 6 * model.nbody))
    force[..., 6 * (model.nbody - 1) + 2] = 5.0  # 5 N up on the last body (the ball)
    n = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_CTRL)
    guided = np.concatenate([controls[..., :n], force, controls[..., n:]], axis=-1)
    cpu_states, _ = _cpu(model, start, guided, spec | XFRC)
    states, _ = warp_backend.rollout(model, start, guided, spec | XFRC, False)
    _assert_agree(states, cpu_states, model)
    plain, _ = warp_backend.rollout(model, start, controls, spec, False)
    assert np.abs(states[:, -1] - plain[:, -1]).max() > 1e-4  # the force moved something


@needs_warp
@pytest.mark.slow
def test_a_contact_switch_gets_its_own_device_model(batch, warp_backend):
    model, start, controls, spec = batch
    warp_backend.rollout(model, start, controls, spec, False)
    before = len(warp_backend._models)
    saved = model.geom_contype.copy()
    try:
        model.geom_contype[:] = 0
        states, _ = warp_backend.rollout(model, start, controls, spec, False)
        cpu_states, _ = _cpu(model, start, controls, spec)
    finally:
        model.geom_contype[:] = saved
    assert len(warp_backend._models) == before + 1
    _assert_agree(states, cpu_states, model)


@needs_warp
@pytest.mark.slow
def test_overflowing_buffers_are_enlarged_and_the_batch_rerun(batch, monkeypatch):
    from handsim.correct.warp_backend import WarpRollout

    model, start, controls, spec = batch
    backend = WarpRollout(device="cpu")
    small = lambda self, device_model, model: (2 * 4**self._growth, 12 * 4**self._growth)  # noqa: E731
    monkeypatch.setattr(WarpRollout, "_sizes", small)
    states, _ = backend.rollout(model, start, controls, spec, False)
    assert backend._growth >= 1
    _assert_agree(states, _cpu(model, start, controls, spec)[0], model)
    monkeypatch.setattr(WarpRollout, "_sizes", lambda self, dm, m: (1, 4))
    backend._growth, backend._batches = 0, {}
    with pytest.raises(CorrectionError, match=r"MuJoCo Warp overflowed \(.+\) with buffers 8×"):
        backend.rollout(model, start, controls, spec, False)


@needs_warp
@pytest.mark.slow
def test_a_correction_planned_on_warp_replays_bit_for_bit(ball, monkeypatch, tmp_path):
    from handsim.correct import write_corrected
    from handsim.io.corrected import read_corrected
    from handsim.sim.replay import replay

    monkeypatch.setenv("HANDSIM_WARP_DEVICE", "cpu")
    correction = correct(ball, CorrectionConfig(samples=3, iterations=1, horizon=5), backend="warp")
    assert correction.backend == "warp" and correction.score.status == "corrected"
    path = write_corrected(tmp_path / "ball.corrected.npz", correction)
    header = read_corrected(path).header
    assert header["backend"] == "warp" and header["versions"]["mujoco_warp"]
    loaded = load_trial(path)
    again = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True, ensemble=False))
    assert np.array_equal(again.states, correction.plan.qpos)


@needs_warp
@pytest.mark.slow
def test_a_shorter_rollout_runs_in_the_longer_batch(batch, warp_backend):
    model, start, controls, spec = batch
    warp_backend.rollout(model, start, controls, spec, False)
    batches = len(warp_backend._batches)
    short = np.ascontiguousarray(controls[:, :23])
    states, sensors = warp_backend.rollout(model, start, short, spec, True)
    assert len(warp_backend._batches) == batches and states.shape[1] == 23
    cpu_states, cpu_sensors = _cpu(model, start, short, spec)
    _assert_agree(states, cpu_states, model)
    assert sensors.shape == cpu_sensors.shape


@needs_warp
@pytest.mark.slow
def test_mocap_roots_are_driven_as_on_the_cpu(warp_backend):
    """Tzionas sequence 20: its hand's root follows a mocap target (the ball grasp's hand is fixed)."""
    loaded = load_trial(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION")
    config = CorrectionConfig(samples=3, horizon=10)
    reference = build_reference(loaded.scene, loaded.trajectory, config, ReplayConfig().metrics)
    stepper = Stepper(reference.scene, reference.schedule.substeps)
    driver = committed_driver(reference, config, np.zeros((reference.frames, reference.size)), stepper)
    driver.reset()
    start = start_of(stepper.model, stepper.data)
    sampler = AnnealedSampler(reference, config, CpuRollout(1), stepper.model, np.random.default_rng(0))
    residual = np.random.default_rng(2).normal(0.0, 0.02, (3, config.horizon, reference.size))
    controls = sampler.controls(residual, np.arange(1, config.horizon + 1), start)
    model, spec = stepper.model, sampler.spec(False)
    assert model.nmocap == 1 and reference.hands  # the wrist residual moves the mocap target
    states, _ = warp_backend.rollout(model, start, controls, spec, False)
    cpu_states, _ = _cpu(model, start, controls, spec)
    position, quaternion = slice(1, 4), slice(4, 8)  # the welded root's free joint
    # measured: 3e-7 m and 3.4e-4 (float32 in the weld's rotation) while the root moves 27 mm
    np.testing.assert_allclose(states[..., position], cpu_states[..., position], rtol=0, atol=1e-5)
    np.testing.assert_allclose(states[..., quaternion], cpu_states[..., quaternion], rtol=0, atol=2e-3)
    assert np.abs(cpu_states[:, -1, position] - cpu_states[:, 0, position]).max() > 0.01  # the wrist moved
