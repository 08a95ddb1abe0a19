"""Replay a recorded trajectory in a scene with collisions on and free objects: the one replay core.

``replay(scene, trajectory, config)`` is pure (same inputs, bitwise-same result on one machine), takes
picklable inputs and returns a small result, so it runs in-process, in a process pool or as a Ray task.
The gymnasium environments drive the same :class:`~handsim.sim.drive.ScheduleDriver` and schedule.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from handsim.datatypes.trajectory import Trajectory
from handsim.sim.control import DEFAULT_CONTROL_RATE, ControlSchedule, control_schedule
from handsim.sim.drive import ScenarioSwitches, ScheduleDriver, scenario_switches
from handsim.sim.grip_check import GripCheck, check_grip
from handsim.sim.memory import check_replay_memory
from handsim.sim.metrics import FrameMetrics, HoldTracks, frame_metrics, hold_tracks
from handsim.sim.parallel import sim_threads
from handsim.sim.placement.robustness import HoldRobustness, Judge, Outcome, hold_robustness, member_outcomes
from handsim.sim.plausibility import check_control_rate, is_valid, replay_flags
from handsim.sim.result import ReplayResult, hold_section, scene_facts, stability_numbers, trajectory_facts
from handsim.sim.scene.compiled import SimScene
from handsim.sim.sections import ReplaySummary, TrackSection
from handsim.sim.specs import MetricSpec
from handsim.sim.stability.gravity import StabilityResult, stability_test
from handsim.sim.stepper import Stepper, WarningEvent
from handsim.sim.summary import (
    HoldOutcome,
    hand_only_summary,
    hold_outcome,
    not_judged,
    summarize,
    window_long_enough,
)
from handsim.sim.track import track_flags, track_verdict

MEMBER_FIRST_LOOK = 0.1
"""Seconds after the release at which a robustness-ensemble member's run is first looked at for a loss
(then at doubling intervals: 0.2 s, 0.4 s …), so that a member that loses its object stops simulating soon
after (:func:`member_verdict`). Not physics: only how often a run is looked at; the verdicts are the same
at any value. 0.1 s is the contact gap that loses an object (:class:`~handsim.sim.specs.MetricSpec`);
members lost in the shared recordings lost it 0.04–0.10 s after the release."""


@dataclass(frozen=True)
class ReplayConfig:
    """How to replay.

    Attributes:
        control_rate: Control frames per second (rounded to a whole number of steps per frame); at least
            :func:`~handsim.sim.plausibility.min_control_rate` (20 Hz at the default metrics).
        metrics: Thresholds and scenario parameters (versioned, written into each result).
        keep_states: Keep ``qpos`` of every frame in the result (for rendering videos); off by default to
            keep results small.
        stability_at: Run the grasp stability tests (:func:`~handsim.sim.stability.gravity.stability_test`)
            on the
            state at this trajectory time, s; ``"grasp"``: at the end of the scene's hold window (glove
            scenario); None: no test.
        ensemble: Glove scenario: judge the hold over the scene's robustness ensemble too
            (:mod:`handsim.sim.placement.robustness`) and test the grip at the release in six gravity
            directions.

    Raises:
        ValueError: ``control_rate`` is not a number or below the minimum, or ``stability_at`` is a
            string other than ``"grasp"``.
    """

    control_rate: float = DEFAULT_CONTROL_RATE
    metrics: MetricSpec = field(default_factory=MetricSpec)
    keep_states: bool = False
    stability_at: float | str | None = None
    ensemble: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "control_rate", check_control_rate(self.control_rate, self.metrics))
        if isinstance(self.stability_at, str) and self.stability_at != "grasp":
            raise ValueError(
                f"stability_at must be a time in seconds, 'grasp' or None, got {self.stability_at!r}"
            )

    def to_dict(self) -> dict:
        """JSON-ready parameters."""
        return {
            "control_rate": self.control_rate,
            "metrics": self.metrics.to_dict(),
            "keep_states": self.keep_states,
            "stability_at": self.stability_at,
            "ensemble": self.ensemble,
        }


def run_schedule(
    driver: ScheduleDriver,
    frames: int | None = None,
    until: Callable[[np.ndarray, np.ndarray], bool] | None = None,
    checks: Sequence[int] = (),
) -> tuple[np.ndarray, np.ndarray, list[WarningEvent], WarningEvent | None]:
    """Step through the frames of the driver's schedule from its current state (frame 0).

    During frame ``k`` (from ``t_k`` to ``t_k+1``) the actuators and the root's mocap target hold the
    references of ``t_k+1``, so the state at ``t_k+1`` is compared with what it was driven towards.

    Args:
        driver: The driver, at frame 0.
        frames: Simulate only the first ``frames`` frames (at least 1; the simulation is causal, so these
            rows are bitwise those of the whole run); None: every frame of the schedule.
        until: Asked with the qpos and sensor rows so far once the row of each frame in ``checks`` is
            recorded; True stops the run there (its rows are still those of the whole run).
        checks: The frames at which ``until`` is asked (in any order; frame 0, the start, and frames past
            the run's last are not asked).

    Returns:
        qpos and sensordata at each frame time (rows up to the divergence when there is one, or up to where
        ``until`` stopped it), the warnings, and the divergence.
    """
    model, data = driver.stepper.model, driver.stepper.data
    schedule = driver.schedule
    n = schedule.frames if frames is None else max(1, min(int(frames), schedule.frames))
    qpos = np.empty((n, model.nq))
    sensors = np.empty((n, model.nsensordata))
    qpos[0], sensors[0] = data.qpos, data.sensordata
    ctrl = schedule.ctrl
    warnings: list[WarningEvent] = []
    advance = driver.advance
    pending = iter([*sorted({int(c) for c in checks if 0 < c < n}), n] if until is not None else [n])
    check = next(pending)
    for k in range(n - 1):
        events = advance(ctrl[k + 1])
        if events:
            warnings.extend(events)
            stop = next((e for e in events if e.diverged), None)
            if stop is not None:
                return qpos[: k + 1], sensors[: k + 1], warnings, stop
        qpos[k + 1] = data.qpos
        sensors[k + 1] = data.sensordata
        if k + 1 == check:  # until is not None: only then are there checks before n
            if until(qpos[: k + 2], sensors[: k + 2]):  # type: ignore[misc]
                return qpos[: k + 2], sensors[: k + 2], warnings, None
            check = next(pending)
    return qpos, sensors, warnings, None


def replay(scene: SimScene, trajectory: Trajectory, config: ReplayConfig | None = None) -> ReplayResult:
    """Replay ``trajectory`` in ``scene`` and measure it.

    Args:
        scene: A compiled scene (:func:`handsim.sim.compile_scene`, or a scenario builder in
            :mod:`handsim.sim.scenarios`).
        trajectory: Joint targets (and root pose / object tracks as the scene's setup needs).
        config: Replay parameters (default :class:`ReplayConfig`).

    Returns:
        The result; a diverged run stops at the divergence and says so (``diverged``); a replay whose
        inputs cannot give a meaningful answer is flagged (``flags``, ``summary["valid"]`` false).

    Raises:
        TrajectoryError: The trajectory does not fit the scene (see :func:`control_schedule`).
        RecordingTooLongError: It would need more memory than the limit (:mod:`handsim.sim.memory`).
        SimulationError: A target is not finite.
    """
    config = config or ReplayConfig()
    spec = config.metrics
    schedule = control_schedule(scene, trajectory, config.control_rate)
    check_replay_memory(scene.model, schedule.frames, 1.0 / schedule.frame_dt, trajectory.source)
    switches = scenario_switches(scene, schedule, spec.release_delay)
    driver = _driver_at_start(scene, schedule, switches)
    release = switches.release_frame

    def judge(variant: SimScene, controls: ControlSchedule) -> Outcome:  # an ensemble member's verdict
        return member_verdict(variant, controls, spec)

    ahead = _members_ahead(scene, schedule, release, config, judge)
    try:
        qpos, sensors, warnings, diverged = run_schedule(driver)
        frames = frame_metrics(scene, schedule, qpos, sensors, scratch=driver.stepper.data)  # the run is over
        numbers = summarize(frames, spec)
        hand_only = None if scene.layout.objects else hand_only_summary(frames, scene.layout.link_names)
        verdict = track_verdict(
            scene, schedule, frames, qpos, diverged is not None, scratch=driver.stepper.data
        )
        flags = (
            *replay_flags(scene, trajectory, schedule, switches, frames),
            *track_flags(scene, frames, verdict),
        )
        judged = _judged_hold(_Run(scene, schedule, frames, qpos, sensors, release), config, judge, ahead)
    finally:
        _drop(ahead)  # members judged ahead: waited for (unneeded when the run diverged first, or an error)
    hold, grip, robustness, release_stability = judged
    stability = _stability(scene, schedule, qpos, config)
    measured = ReplaySummary(
        numbers=numbers,
        hand_only=hand_only,
        diverged=diverged is not None,
        warnings=len(warnings),
        track=None if verdict is None else TrackSection(verdict, _start_penetration(scene)),
        valid=is_valid(flags),
        hold=hold_section(hold, grip, scene.setup.placement, robustness, release_stability),
        stability=stability_numbers(stability),
    )
    return ReplayResult(
        frames=frames,
        measured=measured,
        warnings=tuple(warnings),
        diverged=diverged,
        hold=hold,
        robustness=robustness,
        release_stability=release_stability,
        stability=stability,
        states=qpos if config.keep_states else None,
        frame_dt=schedule.frame_dt,
        substeps=schedule.substeps,
        steps=(qpos.shape[0] - 1) * schedule.substeps + (schedule.substeps if diverged else 0),
        config=config.to_dict(),
        scene=scene_facts(scene, switches),
        trajectory=trajectory_facts(trajectory),
        notes=(*schedule.notes, *([diverged.describe()] if diverged else ())),
        flags=flags,
        grip=grip,
    )


@dataclass(frozen=True)
class _Run:
    """The winner's run as the hold is judged from it: scene, schedule, metrics, states, release frame."""

    scene: SimScene
    schedule: ControlSchedule
    frames: FrameMetrics
    qpos: np.ndarray
    sensors: np.ndarray
    release: int


def _judged_hold(
    run: _Run, config: ReplayConfig, judge: Judge, ahead: Future[list[tuple[str, str, Outcome]]] | None
) -> tuple[HoldOutcome | None, GripCheck | None, HoldRobustness | None, StabilityResult | None]:
    """The glove hold of the run: its outcome and grip, the ensemble's robustness and the release test.

    All None where the scene judges no hold (:func:`_judges_hold`); the robustness and the release test only
    with ``config.ensemble`` and a judged outcome. Members judged ahead (``ahead``) are waited for after the
    release test, and their error comes first, as without threads.
    """
    scene, schedule, qpos, release, spec = run.scene, run.schedule, run.qpos, run.release, config.metrics
    if not _judges_hold(scene, release):
        return None, None, None, None
    hold, grip = _hold(scene, schedule, run.frames, qpos, run.sensors, release, spec)
    if not (config.ensemble and hold.judged):
        return hold, grip, None, None
    if ahead is None:
        robustness = hold_robustness(scene, schedule, spec, hold, judge)
        return hold, grip, robustness, _release_stability(scene, schedule, qpos, release, spec)
    try:  # the release test while the members finish
        release_stability = _release_stability(scene, schedule, qpos, release, spec)
    except Exception:
        ahead.result()
        raise
    return hold, grip, hold_robustness(scene, schedule, spec, hold, judge, ahead.result()), release_stability


def _start_penetration(scene: SimScene) -> dict[str, float]:
    """Each hand's starting penetration of the objects from the scene's checks, mm (empty where none ran).

    Keyed by hand name (``""`` for a scene's only hand); :func:`handsim.sim.arctic_scene.arctic_scene`
    measures it.
    """
    return dict(scene.setup.checks.get("start_penetration_mm") or {})


def _members_ahead(
    scene: SimScene,
    schedule: ControlSchedule,
    release: int,
    config: ReplayConfig,
    judge: Judge,
) -> Future[list[tuple[str, str, Outcome]]] | None:
    """The robustness ensemble's members judged beside the winner's run, when threads are to spare.

    The members do not depend on the winner's run, only on whether its hold is judged; that is known before
    the run (a feasible placement, a window long enough after the release) unless the run diverges first,
    and then the members' answers are dropped (:func:`_drop`). With one thread (a dataset run's workers)
    nothing runs ahead: the members are judged after the run, as the results are the same either way.
    """
    setup, spec = scene.setup, config.metrics
    if (
        not config.ensemble
        or not setup.placement.get("ensemble")
        or not _placed(scene)
        or not _judges_hold(scene, release)
        or not window_long_enough(float(schedule.times[release]), setup.hold_window, spec)
        or sim_threads() <= 1  # last: asked only where the members will run (a bad setting raises there)
    ):
        return None
    pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="handsim-sim")
    try:
        return pool.submit(member_outcomes, scene, schedule, spec, judge)
    finally:
        pool.shutdown(wait=False)  # its one thread ends with the task


def _drop(ahead: Future | None) -> None:
    """Wait for members judged ahead whose answers are not needed (nothing runs on after the replay)."""
    if ahead is not None:
        ahead.exception()  # waits; an error of an answer nobody asked for is not the replay's


def _placed(scene: SimScene) -> bool:
    """Whether the glove placement found a feasible pose (a scene without a placement search: True)."""
    return scene.setup.placement.get("feasible", True) is not False


def _hold(
    scene: SimScene,
    schedule: ControlSchedule,
    frames: FrameMetrics | HoldTracks,
    qpos: np.ndarray,
    sensors: np.ndarray,
    release: int,
    spec: MetricSpec,
) -> tuple[HoldOutcome, GripCheck | None]:
    """The hold outcome of a glove replay and its grip, or not judged when the placement was infeasible.

    A judged outcome stands only where the grip does (:mod:`handsim.sim.grip_check`): no hand link deeper in
    the object than the grip limit from the contact frame until the object is lost or the window ends, and a
    held object pressed from opposing sides with forces the servos can make over the hold window. Else the
    outcome is not judged, with the check's reason.
    """
    window = scene.setup.hold_window
    released = float(schedule.times[release])
    if not _placed(scene):
        reason = (
            "not judged: the object could not be placed without penetrating the hand "
            "(the placement note says how deep)"
        )
        return not_judged(released, window, reason), None
    if scene.setup.unjudged is not None:
        return not_judged(released, window, scene.setup.unjudged), None
    obj = scene.layout.objects[0]
    outcome = hold_outcome(frames, qpos[:, obj.free_qpos + 2], released, window, spec)
    if not outcome.judged:
        return outcome, None
    end = outcome.window[1] if outcome.lost_at is None else outcome.lost_at
    since = min(float(scene.setup.contact_time), outcome.window[0])
    window = (outcome.window[0], end)
    grip = check_grip(
        scene, qpos, sensors, schedule.times, window, spec.grip, since, grip=outcome.held is True
    )
    reason = grip.depth_failure(spec.grip) or (grip.grip_failure(spec.grip) if outcome.held else None)
    if reason is not None:
        outcome = replace(outcome, held=None, reason=reason)
    return outcome, grip


def member_verdict(scene: SimScene, schedule: ControlSchedule, spec: MetricSpec) -> Outcome:
    """Whether a robustness-ensemble member held its object, and why not: simulated until that is decided.

    A member's verdict (held, and why not) reads its frames up to the hold window's end and no later
    (:func:`~handsim.sim.summary.hold_outcome`), and the simulation is causal: so the frames after the
    window, which the member's :func:`replay` would also simulate, are not simulated. Nor are those after
    the object is lost: the run is looked at :data:`MEMBER_FIRST_LOOK` after the release and then at
    doubling intervals, and a loss found in the frames so far is the loss of the whole run (the verdict
    takes the first one). Held and reason are bitwise those of ``replay(scene, trajectory).hold`` (pinned
    in ``tests/test_replay.py``).

    Args:
        scene: The member's scene (:func:`handsim.sim.placement.robustness.ensemble_scenes`).
        schedule: The control schedule of the trajectory on the ensemble's scenes (one for all members: they
            differ only in the object's starting pose and contact time, not in the hand or the frames).
        spec: The replay's metric parameters.

    Returns:
        ``(held, reason)`` as :class:`~handsim.sim.summary.HoldOutcome` gives them, or None when the scene
        has no hold to judge (no release, window or object).
    """
    switches = scenario_switches(scene, schedule, spec.release_delay)
    release = switches.release_frame
    if not _judges_hold(scene, release):
        return None
    driver = _driver_at_start(scene, schedule, switches)
    times = schedule.times
    window_end = scene.setup.hold_window[1]
    last = int(np.searchsorted(times, window_end + 1e-9))  # frames up to the window's end
    looks, after = [], MEMBER_FIRST_LOOK
    while times[release] + after < window_end:
        looks.append(int(np.searchsorted(times, times[release] + after - 1e-9)))
        after *= 2.0

    height = scene.layout.objects[0].free_qpos + 2  # the object's world height in qpos
    released = float(times[release])

    def lost(qpos: np.ndarray, sensors: np.ndarray) -> bool:  # a loss so far is the loss of the whole run
        tracks = hold_tracks(scene, schedule, sensors)
        return hold_outcome(tracks, qpos[:, height], released, scene.setup.hold_window, spec).held is False

    until = lost if _placed(scene) else None  # an unplaced object is never lost: run to the window's end
    qpos, sensors, _, _ = run_schedule(driver, frames=last, until=until, checks=looks)
    outcome, _ = _hold(scene, schedule, hold_tracks(scene, schedule, sensors), qpos, sensors, release, spec)
    return outcome.held, outcome.reason


def _driver_at_start(
    scene: SimScene, schedule: ControlSchedule, switches: ScenarioSwitches
) -> ScheduleDriver:
    """A driver of the scene's scenario on a fresh stepper (a private model when contacts switch), reset."""
    stepper = Stepper(scene, schedule.substeps, own_model=switches.contact_frame > 0)
    driver = ScheduleDriver(stepper, schedule, switches)
    driver.reset()
    return driver


def _judges_hold(scene: SimScene, release_frame: int) -> bool:
    """Whether a replay of the scene judges holding: a release, a hold window and an object."""
    return release_frame >= 0 and scene.setup.hold_window is not None and bool(scene.layout.objects)


def _release_stability(
    scene: SimScene, schedule: ControlSchedule, qpos: np.ndarray, release: int, spec: MetricSpec
) -> StabilityResult | None:
    """The stability tests on the state at the release frame (None when the run stopped before it)."""
    if release >= qpos.shape[0]:
        return None
    return stability_test(scene, qpos[release], schedule.ctrl[release], spec=spec.stability)


def _stability(
    scene: SimScene, schedule: ControlSchedule, qpos: np.ndarray, config: ReplayConfig
) -> StabilityResult | None:
    """The stability tests at ``config.stability_at`` (None when not asked, or the run diverged before)."""
    at = config.stability_at
    if at is None or not scene.layout.objects:
        return None
    if at == "grasp":
        if scene.setup.hold_window is None:
            raise ValueError("stability_at='grasp' needs a scene with a hold window (the glove scenario)")
        at = scene.setup.hold_window[1]
    frame = schedule.frame_at(float(at))
    if frame >= qpos.shape[0]:
        return None  # the run diverged before that frame
    root = schedule.root_pose
    return stability_test(
        scene,
        qpos[frame],
        schedule.ctrl[frame],
        spec=config.metrics.stability,
        mocap_pos=None if root is None else root[frame, :3],
        mocap_quat=None if root is None else root[frame, 3:],
    )
