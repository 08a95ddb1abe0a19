"""Grasp segmentation: every closing of a glove recording is an episode, cut-off ones are truncated.

Sessions with known grasps are made by concatenating the shared GraspDB14 trials (one grasp each, spec
003 §3.7), with and without rests and seeded glove noise between them; the synthetic recordings (a long
closure, regrips, drift, calibration sequences) are written here. The shared session
``sessions/01_11_ex03-rad-004-grasp-su04.txt`` is checked against a count made by hand (see its test).
"""

from __future__ import annotations

import math
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

from handsim.cli import main
from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import TrajectoryError
from handsim.glove.calibration_sequence import CALIBRATE_HINT, recognise_calibration_sequence
from handsim.glove.checks import check_recording
from handsim.glove.phases import cut
from handsim.glove.segmentation import (
    ANNOTATION,
    AUTOMATIC,
    CALIBRATION,
    MIN_OPENING_S,
    PHASE_NAMES,
    find_grasp_episodes,
    segment_grasps,
    summed_flexion,
)
from handsim.glove.sensors import SENSOR_NAMES, driven_dofs
from handsim.io import read_trajectory
from handsim.io.graspdb.annotations import match_annotation

TRIALS = (
    "01_ex01-rad-002-grasp-su01.txt",
    "04_ex01-rad-045-grasp-su03.txt",
    "r_01_11_ex03-rad-004-grasp-su04.txt",
)
"""The shared GraspDB14 trials, one grasp each."""
SESSION = Path("sessions") / "01_11_ex03-rad-004-grasp-su04.txt"
RATE = 60.0
GLOVE_NOISE_RAD = math.radians(1.0)
"""Standard deviation of the seeded noise added per DoF and frame: one count of the glove's 8-bit sensors,
whose flexion steps are 0.014–0.018 rad (0.8–1.0°; :data:`handsim.glove.DEFAULT_GAINS`)."""


# --------------------------------------------------------------------------------------------------
# Helpers


def _trials(graspdb_dir: Path) -> list[Trajectory]:
    return [read_trajectory(graspdb_dir / name) for name in TRIALS]


def _session(
    parts: list[Trajectory], rests_s: tuple[float, ...], *, noise: str = "none", seed: int = 0
) -> tuple[Trajectory, list[tuple[int, int]]]:
    """The parts one after the other at 60 Hz, with a rest of ``rests_s[k]`` after part ``k``.

    A rest holds the posture the part ends with. ``noise``: ``"none"``, ``"rests"`` (seeded glove noise in
    the rests) or ``"all"`` (in every frame).

    Returns:
        The session and each part's frame span ``[start, stop)``.
    """
    rng = np.random.default_rng(seed)
    blocks, spans, rest_rows = [], [], []
    start = 0
    for k, part in enumerate(parts):
        blocks.append(np.asarray(part.targets, dtype=float))
        spans.append((start, start + part.nframes))
        start += part.nframes
        rest = round(rests_s[k] * RATE) if k < len(rests_s) else 0
        if rest:
            held = np.repeat(blocks[-1][-1:], rest, axis=0)
            rest_rows.append(np.arange(start, start + rest))
            blocks.append(held)
            start += rest
    targets = np.vstack(blocks)
    if noise != "none":
        rows = np.concatenate(rest_rows) if noise == "rests" else np.arange(targets.shape[0])
        targets[rows] += rng.normal(0.0, GLOVE_NOISE_RAD, (rows.shape[0], targets.shape[1]))
    n = targets.shape[0]
    session = Trajectory(
        np.arange(n) / RATE,
        parts[0].dof_names,
        targets,
        np.ones_like(targets, dtype=bool),
        switch=np.ones(n, dtype=bool),
        source="concatenated shared trials",
    )
    return session, spans


def _glove(flexion: np.ndarray, *, source: str = "synthetic", switch: np.ndarray | None = None) -> Trajectory:
    """A glove trajectory at 60 Hz whose summed finger flexion is ``flexion`` (spread over its DoFs)."""
    names = driven_dofs()
    flex = np.array(["flex" in n and not n.startswith("root") for n in names])
    targets = np.zeros((flexion.shape[0], len(names)))
    targets[:, flex] = flexion[:, None] / flex.sum()
    return Trajectory(
        np.arange(flexion.shape[0]) / RATE,
        names,
        targets,
        np.ones_like(targets, dtype=bool),
        switch=np.ones(flexion.shape[0], dtype=bool) if switch is None else switch,
        source=source,
    )


def _ramp(t: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """0 before ``t0``, 1 after ``t1``, a smooth step between."""
    x = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    return 3 * x**2 - 2 * x**3


def _closings(t: np.ndarray, starts: list[float], hold_s: float, low: float, high: float) -> np.ndarray:
    """Closings from ``low`` to ``high`` rad starting at each of ``starts`` (0.3 s up, hold, 0.3 s down)."""
    f = np.full(t.shape, low)
    for s in starts:
        f += (high - low) * (_ramp(t, s, s + 0.3) - _ramp(t, s + 0.3 + hold_s, s + 0.6 + hold_s))
    return f


def _times(episode_phase: Phase, t: np.ndarray) -> tuple[float, float]:
    return float(t[episode_phase.start]), float(t[episode_phase.stop - 1])


# --------------------------------------------------------------------------------------------------
# Sessions made of the shared trials


@pytest.mark.parametrize(
    ("rests_s", "noise", "seed"),
    [
        ((), "none", 0),
        ((0.4, 3.0, 1.5), "rests", 1),
        ((2.5, 0.7, 6.0), "all", 7),
    ],
    ids=["back-to-back", "rests-with-noise", "noise-everywhere"],
)
def test_a_session_of_the_shared_trials_is_segmented_into_exactly_their_grasps(
    graspdb_dir, rests_s, noise, seed
):
    session, spans = _session(_trials(graspdb_dir), rests_s, noise=noise, seed=seed)
    segmentation = segment_grasps(session)
    assert segmentation.source == AUTOMATIC
    assert len(segmentation.episodes) == len(TRIALS)
    flexion = summed_flexion(session)
    for episode, (start, stop) in zip(segmentation.episodes, spans, strict=True):
        assert not episode.truncated
        hold = episode.hold
        assert start <= hold.start < hold.stop <= stop  # each trial's grasp is held within the trial
        assert flexion[episode.peak_frame] == pytest.approx(flexion[start:stop].max(), abs=0.2)
        assert [p.name for p in episode.phases] == list(PHASE_NAMES)
    # the annotated grasp of r_01_11 (frames 81–163 of the trial) is what the hold covers
    start = spans[2][0]
    hold = segmentation.episodes[2].hold
    annotated = set(range(start + 81, start + 164))
    assert len(annotated & set(range(hold.start, hold.stop))) >= 0.8 * len(annotated)


def test_a_session_cut_mid_grasp_at_both_ends_has_truncated_first_and_last_episodes(graspdb_dir):
    session, _ = _session(_trials(graspdb_dir), (1.0, 1.0))
    whole = segment_grasps(session).episodes
    first, last = whole[0].hold, whole[2].hold
    part = cut(session, Phase("part", (first.start + first.stop) // 2, (last.start + last.stop) // 2))
    episodes = segment_grasps(part).episodes
    assert [e.truncated for e in episodes] == [True, False, True]
    assert episodes[0].note == "the file starts with the hand closed or closing"
    assert episodes[0].phase("approach") is None and episodes[0].phase("closure") is None
    assert episodes[0].hold.start == 0
    assert episodes[2].note == "the file ends before the release"
    assert episodes[2].phase("release") is None and episodes[2].hold.stop == part.nframes


def test_a_session_cut_while_the_hand_closes_starts_with_a_truncated_episode(graspdb_dir):
    session, _ = _session(_trials(graspdb_dir), (1.0, 1.0))
    closure = segment_grasps(session).episodes[0].phase("closure")
    assert closure is not None
    part = cut(session, Phase("part", (closure.start + closure.stop) // 2, session.nframes))
    episodes = segment_grasps(part).episodes
    assert [e.truncated for e in episodes] == [True, False, False]
    assert episodes[0].phase("closure").start == 0


def test_the_annotated_trial_takes_its_episode_from_the_annotation(graspdb_dir):
    path = graspdb_dir / "r_01_11_ex03-rad-004-grasp-su04.txt"
    raw = read_trajectory(path)
    trajectory, _ = check_recording(raw, match_annotation(path, raw.nframes))
    segmentation = segment_grasps(trajectory)
    assert segmentation.source == ANNOTATION
    [episode] = segmentation.episodes
    flexion = summed_flexion(trajectory)
    reach = flexion[24:81]
    most_open = 24 + int(np.flatnonzero(reach == reach.min())[-1])  # the last frame at its least flexion
    assert episode.phases == (
        Phase("approach", 24, most_open),
        Phase("closure", most_open, 81),
        Phase("hold", 81, 164),
        Phase("release", 164, 233),
    )
    assert (episode.start, episode.stop, episode.truncated, episode.source) == (24, 233, False, ANNOTATION)
    assert episode.peak_flexion == pytest.approx(float(flexion.max()))


def _task_cycles(trajectory: Trajectory) -> np.ndarray:
    """The frames at which the little finger's PIP sensor peaks: once in each cycle of the session's task.

    Peaks standing at least 0.4 of the sensor's 5th–95th percentile spread above their surroundings, at
    least 1 s apart (the cycles last about 3.8 s).
    """
    from scipy.signal import find_peaks  # lazy: only this test needs SciPy's peak finder

    pip = trajectory.column("lf_pip_flex")
    lo, hi = np.percentile(pip, [5, 95])
    return find_peaks(pip, prominence=0.4 * (hi - lo), distance=round(RATE))[0]


def test_the_shared_session_has_the_closings_counted_by_hand_but_for_a_few(graspdb_dir):
    """The count, made by hand on plots of the session (11,857 frames, 197.5 s) and its sensors.

    The task repeats in cycles of about 3.8 s in which every finger flexes once, the index first; the
    little finger's PIP sensor peaks sharply once per cycle, 51 times (:func:`_task_cycles`): at 1.1 s,
    before the hand has opened since the file started (no complete closing), then 50 times from 6.7 s to
    194.3 s, after which the hand opens to 3.9 rad and rests. Each of those 50 cycles is a closing and an
    opening of the hand, none cut off by the file: a person counts 50 grasps.

    The segmentation finds 51 complete episodes, none truncated, and places them in the cycles (each
    episode counted in the cycle of its peak) as follows: 45 cycles hold one episode each; three (13.3,
    62.2, 65.8 s) hold two, where the summed flexion closes and opens twice in the cycle by as much (from
    58 to 67 s it closes at 60.6, 62.2, 64.4 and 65.8 s, each time rising 1.4–1.7 rad from the open hand
    and falling back); two (58.3, 124.0 s) hold none: their closings rise less than two fifths of the
    range (1.33 rad) from the hand's last opening (about 1.2 and 1.1 rad).
    """
    raw = read_trajectory(graspdb_dir / SESSION)
    trajectory, _ = check_recording(raw, match_annotation(graspdb_dir / SESSION, raw.nframes))
    segmentation = segment_grasps(trajectory)
    assert segmentation.source == AUTOMATIC
    assert (len(segmentation.episodes), len(segmentation.complete)) == (51, 51)
    assert len(segment_grasps(raw).complete) == 51  # the same with the last row's glitch (21 rad) left in
    lo, hi = segmentation.open_closed
    assert f"{lo:.2f} {hi:.2f}" == "4.09 7.40"
    cycles = _task_cycles(trajectory)
    assert len(cycles) == 51 and round(float(trajectory.times[cycles[0]]), 1) == 1.1
    bounds = np.r_[0, (cycles[1:] + cycles[:-1]) // 2, trajectory.nframes]
    per_cycle = np.bincount(
        [int(np.searchsorted(bounds, e.peak_frame, side="right")) - 1 for e in segmentation.episodes],
        minlength=len(cycles),
    )
    assert per_cycle[0] == 0
    assert np.bincount(per_cycle[1:]).tolist() == [2, 45, 3]
    empty = [round(float(trajectory.times[c]), 1) for c in cycles[1:][per_cycle[1:] == 0]]
    assert empty == [58.3, 124.0]
    starts = [e.start for e in segmentation.episodes]
    stops = [e.stop for e in segmentation.episodes]
    assert all(a < b <= c for a, b, c in zip(starts, stops, starts[1:], strict=False))  # in order, disjoint


def test_segmentation_is_deterministic(graspdb_dir):
    session, _ = _session(_trials(graspdb_dir), (0.4, 3.0, 1.5), noise="rests", seed=3)
    again, _ = _session(_trials(graspdb_dir), (0.4, 3.0, 1.5), noise="rests", seed=3)
    assert segment_grasps(session).to_dict() == segment_grasps(again).to_dict()


# --------------------------------------------------------------------------------------------------
# Synthetic recordings


def test_a_long_closure_with_spikes_and_a_regrip_is_one_episode_held_over_the_whole_closed_stretch():
    # a pen held from 0.95 s to 34.2 s (GraspDB14's object-interaction trials): closing in 0.35 s, a
    # manipulating hand (±1 rad), a 0.47 s flexion spike, a 0.2 s regrip that loosens the hand to 40 %
    rng = np.random.default_rng(0)
    t = np.arange(round(35.5 * RATE)) / RATE
    closed = _ramp(t, 0.95, 1.3) - _ramp(t, 34.2, 34.55)
    flexion = 1.0 + 9.0 * closed + closed * (np.sin(2 * np.pi * 0.3 * t) + rng.normal(0, 0.1, t.shape))
    flexion += 4.0 * (_ramp(t, 5.0, 5.2) - _ramp(t, 5.27, 5.47))
    flexion -= 5.4 * (_ramp(t, 12.0, 12.1) - _ramp(t, 12.1, 12.2))
    flexion[int(20 * RATE)] += 10.0  # a single-sample glitch
    [episode] = segment_grasps(_glove(flexion)).episodes
    assert not episode.truncated
    hold_start, hold_end = _times(episode.hold, t)
    assert 0.95 < hold_start < 1.3 and 34.2 < hold_end < 34.4  # closed at 1.3 s, released from 34.2 s


@pytest.mark.parametrize(
    ("opening_s", "depth", "episodes"),
    [(0.2, 0.6, 1), (MIN_OPENING_S + 0.2, 0.6, 2), (0.2, 0.9, 2)],
    ids=["brief-partial", "long-partial", "brief-full"],
)
def test_only_brief_partial_openings_are_regrips_inside_one_episode(opening_s, depth, episodes):
    # the hand closes from 1 to 9 rad, then opens by `depth` of the way back for `opening_s` and closes again
    t = np.arange(round(8 * RATE)) / RATE
    flexion = 1.0 + 8.0 * (_ramp(t, 1.0, 1.3) - _ramp(t, 6.0, 6.3))
    flexion -= 8.0 * depth * (_ramp(t, 3.0, 3.1) - _ramp(t, 3.1 + opening_s, 3.2 + opening_s))
    assert len(find_grasp_episodes(flexion, t)) == episodes


def test_partial_closings_between_grasps_are_not_episodes():
    # closings to 9 rad at 1, 5 and 9 s; between them the hand closes by a third of the way (3.7 rad)
    t = np.arange(round(12 * RATE)) / RATE
    flexion = _closings(t, [1.0, 5.0, 9.0], 1.0, 1.0, 9.0) + _closings(t, [3.2, 7.2], 0.4, 0.0, 2.7)
    episodes = find_grasp_episodes(flexion, t)
    assert [
        (float(t[e.hold.start]) < held < float(t[e.hold.stop - 1]))
        for e, held in zip(episodes, [1.8, 5.8, 9.8], strict=True)
    ] == [True] * 3


def test_closings_are_measured_from_the_open_hand_before_them_when_the_glove_drifts():
    # ten closings of 4 rad while the open hand's reading drifts up by 3 rad over the recording
    t = np.arange(round(40 * RATE)) / RATE
    flexion = _closings(t, [1.0 + 3.8 * k for k in range(10)], 1.0, 1.0, 5.0) + 3.0 * t / t[-1]
    episodes = find_grasp_episodes(flexion, t)
    assert len(episodes) == 10 and not any(e.truncated for e in episodes)


def test_a_resting_hand_has_no_episodes_and_says_why():
    t = np.arange(round(10 * RATE)) / RATE
    flexion = 2.0 + 0.5 * np.sin(2 * np.pi * 0.2 * t)
    segmentation = segment_grasps(_glove(flexion))
    assert segmentation.episodes == ()
    assert segmentation.note == (
        "the summed finger flexion spans 1.00 rad (1.50–2.50 rad), under the 2 rad a closing needs: the "
        "fingers barely move"
    )


def test_a_closing_shorter_than_two_tenths_of_a_second_is_a_twitch():
    t = np.arange(round(4 * RATE)) / RATE
    flexion = (
        1.0
        + 6.0 * (_ramp(t, 1.0, 1.1) - _ramp(t, 1.15, 1.25))
        + 6.0 * (_ramp(t, 2.0, 2.2) - _ramp(t, 2.8, 3.0))
    )
    [episode] = find_grasp_episodes(flexion, t)
    assert 2.0 < t[episode.peak_frame] < 3.0


# --------------------------------------------------------------------------------------------------
# Calibration sequences


TOUCH_FINGERS = ("I", "M", "R", "L")


def _calibration_sequence(
    order: tuple[str, ...] = TOUCH_FINGERS, segments: int = 21
) -> tuple[np.ndarray, np.ndarray]:
    """File values (rad, flexion negative) and switch of a calibration take following spec 003 §3.5.

    Every segment lasts 1 s; the switch toggles at each, starting ON. Segment 5 is a fist; in segments 18
    and 19 the thumb touches the fingers of ``order`` one after the other (each finger flexes 60° at MCP and
    PIP for 0.2 s).
    """
    per = round(RATE)
    values = np.zeros((segments * per, 23))
    switch = np.repeat(np.arange(segments) % 2 == 0, per)
    column = {name: i for i, name in enumerate(SENSOR_NAMES)}
    fist = [column[f"{f}-{j}"] for f in ("I", "M", "R", "L") for j in ("MCPJ", "PIPJ")]
    values[5 * per : 6 * per, fist] = -math.radians(80.0)
    for segment in (18, 19):
        if segment >= segments:
            continue
        for k, finger in enumerate(order):
            rows = slice(segment * per + 10 + 12 * k, segment * per + 22 + 12 * k)
            values[rows, [column[f"{finger}-MCPJ"], column[f"{finger}-PIPJ"]]] = -math.radians(60.0)
            values[rows, column["T-MCPJ"]] = -math.radians(30.0)
    return values, switch


def _write_rad(path: Path, values: np.ndarray, switch: np.ndarray) -> Path:
    """A GraspDB14 ``rad`` recording: time stamp, switch, 23 values, a trailing space."""
    start = datetime(2014, 11, 28, 8, 33, 9)
    lines = []
    for i, (row, on) in enumerate(zip(values, switch, strict=True)):
        d = start + timedelta(microseconds=round(1e6 * i / RATE))
        seconds = d.second + d.microsecond / 1e6
        stamp = f"{d.year:04d} {d.month:02d} {d.day:02d} {d.hour:02d} {d.minute:02d} {seconds:08.5f}"
        lines.append(f"{stamp} {int(on)} {' '.join(f'{v:.5f}' for v in row)} ")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_calibration_sequence_is_recognised_by_its_content_and_has_no_episodes(tmp_path):
    trajectory = read_trajectory(_write_rad(tmp_path / "take.txt", *_calibration_sequence()))
    segmentation = segment_grasps(trajectory)
    assert (segmentation.source, segmentation.episodes) == (CALIBRATION, ())
    assert segmentation.calibration is not None
    assert (segmentation.calibration.by_name, segmentation.calibration.by_content) == (False, True)
    assert segmentation.lines() == [
        f"episodes   none: {CALIBRATE_HINT}: 21 switch segments starting ON and the thumb-to-finger touches "
        "of spec §3.5 in segment 18 (index, middle, ring, little flex at 18.2, 18.4, 18.6, 18.8 s) and "
        "segment 19 (index, middle, ring, little flex at 19.2, 19.4, 19.6, 19.8 s)"
    ]


def test_a_calibration_sequence_is_recognised_by_its_graspdb14_name(tmp_path):
    values, switch = _calibration_sequence(segments=17)  # a take cut short: no touches
    trajectory = read_trajectory(_write_rad(tmp_path / "00_calib-rad-su01.txt", values, switch))
    calibration = recognise_calibration_sequence(trajectory)
    assert calibration is not None and (calibration.by_name, calibration.by_content) == (True, False)
    assert calibration.note == (
        "the file name 00_calib-rad-su01.txt holds '_calib-'; its content does not show the protocol (17 "
        "switch segments starting ON, not 20 or 21 starting ON)"
    )


@pytest.mark.parametrize(
    ("order", "segments"),
    [(("M", "I", "R", "L"), 21), (("L", "R", "M", "I"), 20), (TOUCH_FINGERS, 19)],
    ids=["index-after-middle", "reversed", "too-few-segments"],
)
def test_a_recording_whose_touches_or_switch_do_not_follow_the_protocol_is_no_calibration_sequence(
    tmp_path, order, segments
):
    trajectory = read_trajectory(_write_rad(tmp_path / "take.txt", *_calibration_sequence(order, segments)))
    assert recognise_calibration_sequence(trajectory) is None


def test_a_recording_with_the_switch_on_throughout_is_no_calibration_sequence(graspdb_dir):
    for name in TRIALS:
        assert recognise_calibration_sequence(read_trajectory(graspdb_dir / name)) is None


# --------------------------------------------------------------------------------------------------
# Bad input


def test_a_trajectory_without_finger_flexion_dofs_is_refused_with_its_dofs_listed():
    t = np.arange(10) / RATE
    trajectory = Trajectory(t, ("root_abd",), np.zeros((10, 1)), np.ones((10, 1), bool), source="wrist.txt")
    with pytest.raises(TrajectoryError) as exc:
        segment_grasps(trajectory)
    assert str(exc.value) == (
        "wrist.txt: no finger flexion DoFs (names containing 'flex', not the wrist's 'root_…') to find "
        "grasps from; its DoFs are ['root_abd']"
    )


def test_a_non_finite_flexion_names_the_file_the_dof_and_the_frame():
    flexion = np.ones(30)
    trajectory = _glove(flexion, source="gappy.txt")
    trajectory.targets[12, trajectory.dof_names.index("mf_pip_flex")] = np.nan
    with pytest.raises(TrajectoryError) as exc:
        segment_grasps(trajectory)
    assert str(exc.value) == (
        "gappy.txt: DoF 'mf_pip_flex' is not finite at frame 12 (nan); fill the gaps first "
        "(handsim.glove.fill_gaps)"
    )


@pytest.mark.parametrize(
    ("flexion", "times", "message"),
    [
        (
            np.ones(5),
            np.arange(4.0),
            "flexion and times must be 1-D arrays of one non-zero length, got shapes (5,) and (4,)",
        ),
        (
            np.ones((5, 2)),
            np.arange(5.0),
            "flexion and times must be 1-D arrays of one non-zero length, got shapes (5, 2) and (5,)",
        ),
        (np.array([1.0, np.inf, 1.0]), np.arange(3.0), "flexion is not finite at frame 1"),
        (
            np.ones(3),
            np.array([0.0, 1.0, 1.0]),
            "times must strictly increase; sample 2 is not after sample 1",
        ),
    ],
)
def test_find_grasp_episodes_refuses_bad_arrays(flexion, times, message):
    with pytest.raises(TrajectoryError) as exc:
        find_grasp_episodes(flexion, times)
    assert str(exc.value) == message


def test_an_unknown_episode_phase_lists_the_phases():
    t = np.arange(round(4 * RATE)) / RATE
    [episode] = find_grasp_episodes(_closings(t, [1.0], 1.0, 1.0, 9.0), t)
    with pytest.raises(
        TrajectoryError,
        match=r"no episode phase 'grasp'; phases are \['approach', 'closure', 'hold', 'release'\]",
    ):
        episode.phase("grasp")


# --------------------------------------------------------------------------------------------------
# handsim inspect


def test_inspect_lists_the_episodes_of_the_shared_session(capsys, graspdb_dir):
    assert main(["inspect", str(graspdb_dir / SESSION)]) == 0
    lines = capsys.readouterr().out.splitlines()
    episodes = [line for line in lines if line.startswith("episode ")]
    assert len(episodes) == 51
    assert (
        "episodes   51 (51 complete, 0 truncated), automatic: hysteresis on the summed finger flexion (open "
        "4.09 rad, closed 7.40 rad; a closing rises 0.4 of the range, 1.33 rad, above the open hand)"
    ) in lines
    assert episodes[:2] == [
        "episode   1 frames 137–421 (2.28–7.01 s), hold 4.45–6.88 s, peak flexion 6.35 rad, complete, "
        "automatic",
        "episode   2 frames 426–591 (7.10–9.85 s), hold 9.43–9.68 s, peak flexion 6.18 rad, complete, "
        "automatic",
    ]
    raw = read_trajectory(graspdb_dir / SESSION)
    checked, _ = check_recording(raw, match_annotation(graspdb_dir / SESSION, raw.nframes))
    assert episodes == segment_grasps(checked).lines()[1:]  # inspect segments the recording as checked


def test_inspect_names_a_truncated_episode_and_plots_the_episodes(capsys, tmp_path):
    t = np.arange(round(6 * RATE)) / RATE
    values = np.zeros((t.shape[0], 23))
    flexion = _closings(t, [1.0, 4.8], 1.0, 0.5, 8.0)  # the second is cut by the end of the file
    flex_columns = [i for i, s in enumerate(SENSOR_NAMES) if s.endswith(("MCPJ", "PIPJ", "DIPJ", "IPJ"))]
    values[:, flex_columns] = -flexion[:, None] / len(flex_columns)
    path = _write_rad(tmp_path / "two_closings.txt", values, np.ones(t.shape[0], bool))
    plot = tmp_path / "episodes.png"
    assert main(["inspect", str(path), "--plot", str(plot)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(",")[-2:] for line in lines if line.startswith("episode ")] == [
        [" complete", " automatic"],
        [" truncated", " automatic (the file ends before the release)"],
    ]
    assert plot.stat().st_size > 10_000 and plot.read_bytes()[:4] == b"\x89PNG"


def test_inspect_lists_a_calibration_sequence_as_one(capsys, tmp_path):
    path = _write_rad(tmp_path / "00_calib-rad-su01.txt", *_calibration_sequence())
    assert main(["inspect", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    [line] = [line for line in lines if line.startswith("episode")]
    assert line.startswith(
        f"episodes   none: {CALIBRATE_HINT}: the file name 00_calib-rad-su01.txt holds '_calib-'; 21 switch"
    )
