"""Contact guidance annealed to zero, and the opposition term of a glove hold.

Fast by construction: the 25-frame slice of the bundled Tzionas sequence 20 that ``tests/test_correct.py``
corrects, with a few samples; the bundled scripted tennis-ball grasp for the opposition term, fed synthetic
contact-sensor rows. What is pinned: the guidance's gain ends at exactly zero; a guided correction's
committed simulation is the replay of its corrected file, bit for bit (no virtual force in it), and the
same for a seed whatever the threads; a guided rollout leaves nothing behind in the next, unguided one; the
opposition term is zero for a grip pressed from two sides and positive without.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR
from handsim.correct import CorrectionConfig, correct, write_corrected
from handsim.correct.backend import CpuRollout, start_of
from handsim.correct.config import CorrectionError
from handsim.correct.grip import Opposition
from handsim.correct.guidance import guidance_schedule
from handsim.correct.planner import committed_driver
from handsim.correct.reference import build_reference
from handsim.correct.sampler import AnnealedSampler
from handsim.correct.trial_file import corrected_bytes
from handsim.datatypes.fingers import finger_of
from handsim.io.corrected import read_corrected
from handsim.sim.replay import ReplayConfig, replay
from handsim.sim.stepper import Stepper
from handsim.trials import load_trial
from tests.test_correct import FAST, SEQ20, _slice

GUIDED = dataclasses.replace(FAST, guidance=1.0, guidance_rounds=1)
"""The tests' correction with guidance in the first of its two rounds."""


@pytest.fixture(scope="module")
def slipping():
    return _slice(load_trial(SEQ20), 125, 150)


@pytest.fixture(scope="module")
def guided(slipping):
    return correct(slipping, GUIDED, threads=2)


@pytest.mark.parametrize(("iterations", "rounds"), [(2, 1), (3, 1), (3, 2), (4, 3)])
def test_the_guidance_schedule_anneals_to_exactly_zero(iterations, rounds):
    gains = guidance_schedule(CorrectionConfig(iterations=iterations, guidance=0.8, guidance_rounds=rounds))
    assert gains.shape == (iterations,) and gains[0] == 0.8
    assert np.all(np.diff(gains) < 0) if rounds == iterations - 1 else np.all(np.diff(gains) <= 0)
    assert np.count_nonzero(gains) == rounds and np.all(gains[rounds:] == 0.0)
    assert not np.any(guidance_schedule(CorrectionConfig(iterations=iterations)))  # off by default


def test_the_last_round_is_always_unguided_and_a_negative_gain_is_refused():
    for iterations, rounds in ((1, 1), (2, 2), (3, 5)):
        gains = guidance_schedule(
            CorrectionConfig(iterations=iterations, guidance=1.0, guidance_rounds=rounds)
        )
        assert gains[-1] == 0.0 and np.count_nonzero(gains) == iterations - 1
    with pytest.raises(CorrectionError, match="guidance must be a number ≥ 0"):
        CorrectionConfig(guidance=-1.0)


def test_a_guided_correction_replays_bit_for_bit_without_any_virtual_force(guided, tmp_path):
    assert np.array_equal(guided.after.states, guided.plan.qpos)  # the replay core: no xfrc_applied at all
    path = write_corrected(tmp_path / "guided.corrected.npz", guided)
    stored = read_corrected(path)
    assert stored.header["method"]["guidance"] == 1.0
    loaded = load_trial(path)
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True))
    assert np.array_equal(result.states, stored.arrays["simulated_qpos"])


def test_a_guided_correction_is_the_same_for_a_seed_whatever_the_threads(slipping, guided):
    again = correct(slipping, GUIDED, threads=1)
    assert corrected_bytes(again) == corrected_bytes(guided)
    unguided = correct(slipping, FAST, threads=1)
    assert not np.array_equal(unguided.plan.residual, guided.plan.residual)  # guidance steered the search


def test_a_guided_rollout_leaves_no_force_in_the_next_unguided_one(slipping):
    config = GUIDED
    reference = build_reference(slipping.scene, slipping.trajectory, config)
    stepper = Stepper(slipping.scene, reference.schedule.substeps)
    committed_driver(reference, config, np.zeros((reference.frames, reference.size)), stepper).reset()
    model = stepper.model
    begin = start_of(model, stepper.data)  # the recording's first frame: the cube at rest on its stand
    frames = np.arange(1, 11)
    residual = np.zeros((3, 10, reference.size))
    backend = CpuRollout(1)
    try:
        sampler = AnnealedSampler(reference, config, backend, model, np.random.default_rng(0))
        plain = sampler.simulate(begin, residual, frames)
        nq = model.nq
        wrench = sampler.guidance.wrenches(1.0, begin.state[1 : 1 + nq], begin.state[1 + nq :], 0, frames)
        body = sampler.guidance.bodies[0]
        assert np.all(wrench.reshape(10, -1, 6)[:, body, 2] > 0)  # it carries the cube's weight at least
        assert not np.any(np.delete(wrench.reshape(10, -1, 6), body, axis=1))  # on the object alone
        pushed = sampler.simulate(begin, residual, frames, wrench)
        assert not np.array_equal(pushed, plain)
        assert np.array_equal(sampler.simulate(begin, residual, frames), plain)
    finally:
        backend.close()


@pytest.fixture(scope="module")
def opposition():
    ball = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")
    config = CorrectionConfig()
    reference = build_reference(ball.scene, ball.trajectory, config)
    return Opposition(reference, config), reference


def _pressing(opposition: Opposition, reference, forces: dict[str, float]) -> np.ndarray:
    """One sensor row per frame with the named groups' first link pressing on the ball with those forces."""
    scene = reference.scene
    rows = np.zeros((reference.frames, scene.model.nsensordata))
    names = scene.layout.link_names
    for group, force in forces.items():
        adr = next(
            a
            for n, a in zip(names, scene.layout.contact_adr[:, 0], strict=True)
            if finger_of(n) == group and a >= 0
        )
        rows[:, adr] = 1.0  # one contact found
        rows[:, adr + 1] = force  # its normal force (the slot's layout: count, force …)
    return rows


def test_the_opposition_term_is_zero_for_an_opposing_grip_and_positive_without(opposition):
    term, reference = opposition
    frames = np.arange(reference.frames)
    hold = reference.goal.valid
    assert term.active and hold.any()
    strong = 2.0 * term.force
    assert not np.any(term(_pressing(term, reference, {"thumb": strong, "index": strong}), frames))
    assert not np.any(term(_pressing(term, reference, {"middle": strong, "palm": strong}), frames))
    alone = term(_pressing(term, reference, {"index": strong, "middle": strong}), frames)  # one side only
    assert np.all(alone[hold] == 1.0) and not np.any(alone[~hold])
    assert np.all(term(np.zeros((reference.frames, reference.scene.model.nsensordata)), frames)[hold] == 1.0)
    half = term(_pressing(term, reference, {"thumb": 0.5 * term.force, "index": strong}), frames)
    assert np.allclose(half[hold], 0.25)  # the weaker side at half the force: (1 − ½)²


def test_the_opposition_term_is_off_for_recorded_tracks_and_at_weight_zero(slipping, opposition):
    reference = build_reference(slipping.scene, slipping.trajectory, CorrectionConfig())
    assert not Opposition(reference, CorrectionConfig()).active
    _, ball = opposition
    assert not Opposition(ball, CorrectionConfig(opposition_weight=0.0)).active
