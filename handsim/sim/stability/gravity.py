"""Grasp stability at one state: gravity along ±x ±y ±z with the hand frozen, and ObMan's displacement.

:func:`stability_test` starts from a given state (``qpos``, zero velocity) six times, once per direction of
gravity along the world axes, and once more for the ObMan simulation displacement. In every run:

* the hand is **frozen at its targets**: its position actuators hold ``ctrl`` (and, for a welded root,
  the mocap target holds ``mocap_pos``/``mocap_quat``) and the hand is weightless. Only the objects
  carry weight: the model's gravity is switched off on a copy and each object body gets its weight
  ``m · g · direction`` applied at its centre of mass (``xfrc_applied``), which is exactly what gravity
  would apply to it. A hand whose targets press into the object squeezes it, as a real grip does;
* the objects' supports (``<prefix>support`` welds) are switched off;
* contacts of the environment (table and floor: the world body's geoms) are switched off unless the spec
  says otherwise, so that only the hand can hold the object — neither original protocol has a table.

A run that diverges (a MuJoCo warning after which the state is no longer the simulation of the inputs)
stops there and fails, with the warning recorded. Every parameter sits in a versioned
:class:`StabilitySpec` that is written into each result. See ``docs/stability.md`` for the protocols
this follows (DexGraspNet's six-direction test and ObMan's simulation displacement) and how ours differ.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from types import MappingProxyType

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import quat_angle
from handsim.sim.parallel import map_on_workers, sim_threads
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import StabilitySpec
from handsim.sim.stability.inputs import check_request, checked_array, mocap_pose
from handsim.sim.stepper import Stepper

CHECK_STEPS = 10
"""MuJoCo steps between two looks at a run (divergence; with ``stop_at_failure``, the displacement)."""
DIRECTIONS: Mapping[str, tuple[float, float, float]] = MappingProxyType(
    {
        "+x": (1.0, 0.0, 0.0),
        "-x": (-1.0, 0.0, 0.0),
        "+y": (0.0, 1.0, 0.0),
        "-y": (0.0, -1.0, 0.0),
        "+z": (0.0, 0.0, 1.0),
        "-z": (0.0, 0.0, -1.0),
    }
)
"""The six directions of gravity, world frame (unit vectors), in the order they are tested."""


@dataclass(frozen=True)
class DirectionResult:
    """One run of a stability test: gravity along one direction.

    Attributes:
        direction: ``"+x"`` … ``"-z"`` (world frame), or ``"obman"`` for the ObMan run.
        gravity: The gravity vector applied to the objects, m/s².
        success: The object stayed in contact (if required), moved less than the threshold (and turned
            less, if judged), and the run did not diverge.
        displacement: Distance between the object's centre of mass at the start and at the end, m; None if
            the run diverged or was not made (``stability_test(needed=…)``).
        rotation_deg: Angle of the object's rotation between the start and the end, degrees; None if the
            run diverged or was not made.
        in_contact_at_end: The object touches the hand at the end.
        links_in_contact: Hand links touching the object at the end (names without ``hand/``).
        simulated_time: Seconds simulated (the duration rounded to whole steps, or less if it diverged or
            stopped at the failure; 0 if it was not made).
        failure: Why it failed, for people; empty on success.
        warnings: MuJoCo warnings raised during the run, one line each.
    """

    direction: str
    gravity: tuple[float, float, float]
    success: bool
    displacement: float | None
    rotation_deg: float | None
    in_contact_at_end: bool
    links_in_contact: tuple[str, ...]
    simulated_time: float
    failure: str
    warnings: tuple[str, ...]

    def to_dict(self) -> dict:
        """The result, JSON-ready."""
        result = asdict(self)
        result["gravity"] = list(self.gravity)
        result["links_in_contact"] = list(self.links_in_contact)
        result["warnings"] = list(self.warnings)
        return result


@dataclass(frozen=True)
class StabilityResult:
    """Outcome of :func:`stability_test`.

    Attributes:
        directions: One result per gravity direction, in the order of :data:`DIRECTIONS`.
        success: Every direction succeeded.
        simulation_displacement: ObMan's metric: the object's centre-of-mass displacement after
            ``spec.obman_duration`` under gravity along ``spec.obman_direction`` with the hand static, m;
            None if that run diverged or was not made.
        obman: The ObMan run in full (its ``success`` applies this spec's thresholds; ObMan has none).
        object: Prefix of the tested object (``obj/``).
        in_contact_at_start: The object touched the hand in the given state.
        initial_penetration: Deepest hand–object penetration in the given state, m (≥ 0).
        spec: The :class:`StabilitySpec` as a dict (with its version).
        model_sha256: The scene's :attr:`~handsim.sim.scene.compiled.SimScene.model_sha256`.
        mujoco_version: The MuJoCo that simulated it.
    """

    directions: tuple[DirectionResult, ...]
    success: bool
    simulation_displacement: float | None
    obman: DirectionResult
    object: str
    in_contact_at_start: bool
    initial_penetration: float
    spec: dict
    model_sha256: str
    mujoco_version: str = field(default=mujoco.__version__)

    def direction(self, label: str) -> DirectionResult:
        """The result of one direction (``"+x"`` …).

        Raises:
            KeyError: No such direction; the message lists the valid labels.
        """
        for result in self.directions:
            if result.direction == label:
                return result
        raise KeyError(f"no direction {label!r}; expected one of {list(DIRECTIONS)}")

    def to_dict(self) -> dict:
        """The result, JSON-ready."""
        return {
            "success": self.success,
            "simulation_displacement": self.simulation_displacement,
            "directions": [d.to_dict() for d in self.directions],
            "obman": self.obman.to_dict(),
            "object": self.object,
            "in_contact_at_start": self.in_contact_at_start,
            "initial_penetration": self.initial_penetration,
            "spec": dict(self.spec),
            "model_sha256": self.model_sha256,
            "mujoco_version": self.mujoco_version,
        }


def stability_test(
    scene: SimScene,
    qpos: npt.ArrayLike,
    ctrl: npt.ArrayLike,
    *,
    spec: StabilitySpec | None = None,
    object_index: int = 0,
    mocap_pos: npt.ArrayLike | None = None,
    mocap_quat: npt.ArrayLike | None = None,
    stop_at_failure: bool = False,
    needed: int | Callable[[], int] = 0,
    first: Sequence[str] = (),
) -> StabilityResult:
    """Test whether the hand holds an object against gravity along ±x ±y ±z, and ObMan's displacement.

    Each run starts from ``qpos`` at rest, with the hand frozen at its targets and the objects under
    gravity (see the module docstring); the scene's model is not modified.

    Args:
        scene: A compiled scene with a hand and at least one object.
        qpos: The state to test (nq,), e.g. a replay's state at the grasp frame.
        ctrl: The hand's actuator targets (nu,), radians, held during every run.
        spec: The parameters (default :class:`StabilitySpec`).
        object_index: Which object of the scene is judged (layout order).
        mocap_pos: Position (3,) of the hand's mocap target, metres (``hand_root="weld"`` only); default:
            the root's position in ``qpos``, so the weld holds the hand where it is.
        mocap_quat: Orientation (4,) of the mocap target (w, x, y, z); default: the root's in ``qpos``.
        stop_at_failure: End a direction's run as soon as the object has moved ``spec.max_displacement``
            (checked every :data:`CHECK_STEPS` steps): the direction fails as it would at the end, its
            displacement and rotation are those at the stop, and ``simulated_time`` says how long it ran.
            For searches that only need the outcome; off for a full test.
        needed: End the whole test as soon as fewer than this many directions can still be resisted. The
            runs are then made one after the other (the directions of ``first``, the other directions in
            :data:`DIRECTIONS` order, ObMan's last), and the runs not made (ObMan's included, also when
            all six directions ran) are failures that say "not run", with no displacement; an error such a
            run would have raised is not raised. A function is asked before each run until the test stops
            (a search's best so far, which other threads may raise meanwhile; it must never fall). For a
            search that only needs a grip that could match the best one found so far; 0: every run is made
            (on threads when :func:`~handsim.sim.parallel.sim_threads` allows).
        first: With ``needed`` only: directions to run before the others (labels of :data:`DIRECTIONS`, e.g.
            those most likely to fail, so that a test out of reach ends sooner). The runs are independent,
            so a direction's result does not depend on when it runs; the results are in :data:`DIRECTIONS`
            order.

    Returns:
        The per-direction results, the overall success, the ObMan simulation displacement and the spec.

    Raises:
        ValueError: An array has the wrong shape, ``object_index`` names no object, mocap values are
            given for a scene without a mocap target, the scene has several hands (the tests hold one), or
            ``first`` names an unknown direction or comes without ``needed``.
        SimulationError: ``qpos``, ``ctrl`` or a mocap value is not finite (MuJoCo would silently reset
            the state or replace the control).
    """
    spec = spec or StabilitySpec()
    check_request(scene.layout, object_index, first, needed, DIRECTIONS)
    model = scene.model
    qpos = checked_array(qpos, (model.nq,), "qpos")
    ctrl = checked_array(ctrl, (model.nu,), "ctrl")
    mocap = mocap_pose(scene, qpos, mocap_pos, mocap_quat)
    frozen = frozen_model(model, spec)
    run = _Run(replace(scene, model=frozen), qpos, ctrl, mocap, object_index)
    jobs = _jobs(spec, frozen.opt.timestep)
    if callable(needed) or needed > 0:
        results = _until_out_of_reach(run, jobs, spec, stop_at_failure, needed, first)
    else:
        results = _on_threads(run, jobs, spec, stop_at_failure)
    directions, obman = tuple(results[:-1]), results[-1]
    return StabilityResult(
        directions=directions,
        success=all(d.success for d in directions),
        simulation_displacement=obman.displacement,
        obman=obman,
        object=scene.layout.objects[object_index].prefix,
        in_contact_at_start=run.start_contact,
        initial_penetration=run.start_penetration,
        spec=spec.to_dict(),
        model_sha256=scene.model_sha256,
    )


def _jobs(spec: StabilitySpec, timestep: float) -> list[tuple[str, np.ndarray, int]]:
    """(label, gravity vector, steps) of each run: the six directions in order, then ObMan's."""
    steps = max(1, round(spec.duration / timestep))
    obman_dir = np.asarray(spec.obman_direction) / np.linalg.norm(spec.obman_direction)
    obman_steps = max(1, round(spec.obman_duration / timestep))
    jobs = [(label, spec.gravity * np.asarray(unit), steps) for label, unit in DIRECTIONS.items()]
    jobs.append(("obman", spec.gravity * obman_dir, obman_steps))
    return jobs


def _on_threads(
    run: _Run, jobs: list[tuple[str, np.ndarray, int]], spec: StabilitySpec, stop_at_failure: bool
) -> list[DirectionResult]:
    """Every run of ``jobs``, in their order; independent (each starts from the same state), so on threads."""
    runs = [run, *(run.fork() for _ in range(min(sim_threads(), len(jobs)) - 1))]
    return map_on_workers(lambda worker, job: worker.direction(*job, spec, stop_at_failure), jobs, runs)


def _until_out_of_reach(
    run: _Run,
    jobs: list[tuple[str, np.ndarray, int]],
    spec: StabilitySpec,
    stop_at_failure: bool,
    needed: int | Callable[[], int],
    first: Sequence[str],
) -> list[DirectionResult]:
    """The runs of ``jobs`` one after the other until ``needed`` directions are out of reach, in jobs order.

    They run in the order of ``first``, then the other directions, ObMan's last. Each run made is the one
    :meth:`_Run.direction` makes alone; once fewer directions than ``needed`` (asked before each run until
    then, when a function) can still succeed, the rest are reported as failures not run.
    """
    by_label = {job[0]: job for job in jobs}
    order = [*dict.fromkeys([*first, *DIRECTIONS]), "obman"]
    bound = needed if callable(needed) else lambda: needed
    results: dict[str, DirectionResult] = {}
    directions = len(jobs) - 1
    stop = 0  # the count out of reach, once the test has stopped
    for label in order:
        _, gravity, steps = by_label[label]
        if not stop:
            failed = sum(not r.success for r in list(results.values())[:directions])
            count = bound()
            stop = count if directions - failed < count else 0
        if stop:
            results[label] = _not_run(label, gravity, stop)
        else:
            results[label] = run.direction(label, gravity, steps, spec, stop_at_failure)
    return [results[label] for label, _, _ in jobs]


def _not_run(label: str, gravity: np.ndarray, out_of_reach: int) -> DirectionResult:
    """The failure of a run not made: fewer than ``out_of_reach`` directions could still be resisted."""
    return DirectionResult(
        direction=label,
        gravity=tuple(float(x) for x in gravity),
        success=False,
        displacement=None,
        rotation_deg=None,
        in_contact_at_end=False,
        links_in_contact=(),
        simulated_time=0.0,
        failure=f"not run: fewer than {out_of_reach} directions could still be resisted",
        warnings=(),
    )


def frozen_model(model: mujoco.MjModel, spec: StabilitySpec) -> mujoco.MjModel:
    """A copy of the model without gravity and, unless the spec keeps them, without environment contacts.

    The objects' weight is applied as a force instead (:meth:`_Run._start`), so the hand is weightless.

    Args:
        model: The scene's model (not modified).
        spec: The test's parameters (``environment_contacts``).

    Returns:
        The copy the runs of :func:`stability_test` simulate.
    """
    frozen = copy.deepcopy(model)
    frozen.opt.gravity[:] = 0.0
    if not spec.environment_contacts:
        world = frozen.geom_bodyid == 0
        frozen.geom_contype[world] = 0
        frozen.geom_conaffinity[world] = 0
    return frozen


class _Run:
    """Runs of one stability test: the same start state, one gravity vector per run."""

    def __init__(
        self,
        scene: SimScene,
        qpos: np.ndarray,
        ctrl: np.ndarray,
        mocap: tuple[np.ndarray, np.ndarray] | None,
        object_index: int,
    ) -> None:
        self.scene = scene
        self.model = scene.model
        self.stepper = Stepper(scene, substeps=1)
        self.qpos, self.ctrl, self.mocap = qpos, ctrl, mocap
        layout = scene.layout
        self.object = layout.objects[object_index]
        first = sum(len(o.part_bodies) for o in layout.objects[:object_index])
        self.parts = np.arange(first, first + len(self.object.part_bodies))
        self.weighted = np.array([b for o in layout.objects for b in o.part_bodies], dtype=np.int64)
        self._start()
        data = self.stepper.data
        self.start_contact = bool(self._links_in_contact())
        found = data.sensordata[layout.penetration_adr[self.parts]]
        dist = data.sensordata[layout.penetration_adr[self.parts] + 1]
        depth = np.where(found > 0, np.maximum(-dist, 0.0), 0.0)
        self.start_penetration = float(depth.max()) if depth.size else 0.0

    def fork(self) -> _Run:
        """The same runs on a data of their own (for another thread); the start facts are shared."""
        forked = copy.copy(self)
        forked.stepper = Stepper(self.scene, substeps=1)
        return forked

    def _start(self, gravity: np.ndarray | None = None) -> None:
        """Reset to the start state at rest, supports off, objects weighted by ``gravity``; forward."""
        self.stepper.reset()
        data, model = self.stepper.data, self.model
        data.qpos[:] = self.qpos
        data.ctrl[:] = self.ctrl
        if self.mocap is not None:
            data.mocap_pos[self.scene.layout.mocap] = self.mocap[0]
            data.mocap_quat[self.scene.layout.mocap] = self.mocap[1]
        for obj in self.scene.layout.objects:
            if obj.support_eq >= 0:
                data.eq_active[obj.support_eq] = 0
        if gravity is not None:
            data.xfrc_applied[self.weighted, :3] = model.body_mass[self.weighted, None] * gravity
        mujoco.mj_forward(model, data)

    def _links_in_contact(self) -> tuple[str, ...]:
        """Hand links touching the judged object in the current state (names without ``hand/``)."""
        layout = self.scene.layout
        found = self.stepper.data.sensordata[layout.contact_adr[:, self.parts]]
        return tuple(name for name, n in zip(layout.link_names, found.sum(axis=1), strict=True) if n > 0)

    def _pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The judged object's centre of mass (its subtree's) and orientation in the current state."""
        data = self.stepper.data
        root = self.object.root_body
        return data.subtree_com[root].copy(), data.xquat[root].copy()

    def direction(
        self, label: str, gravity: np.ndarray, steps: int, spec: StabilitySpec, stop_at_failure: bool = False
    ) -> DirectionResult:
        """One run: from the start state, ``steps`` steps with the objects weighted by ``gravity``, judged."""
        self._start(gravity)
        com0, quat0 = self._pose()
        warnings: list[str] = []
        diverged = False
        done = 0
        com = self.stepper.data.subtree_com[self.object.root_body]
        stepper = self.stepper
        while done < steps:
            # MuJoCo steps CHECK_STEPS at a time in native code (bit for bit the single steps): fewer returns
            # to Python, so the runs on other threads are not kept waiting for the GIL.
            stepper.substeps = min(CHECK_STEPS, steps - done)
            events = stepper.step()
            done += stepper.substeps
            warnings.extend(e.describe() for e in events)
            if any(e.diverged for e in events):
                diverged = True
                break
            if stop_at_failure and np.linalg.norm(com - com0) >= spec.max_displacement:
                break
        vector = tuple(float(x) for x in gravity)
        simulated = done * float(self.model.opt.timestep)
        if diverged:
            return DirectionResult(
                direction=label, gravity=vector, success=False, displacement=None, rotation_deg=None,
                in_contact_at_end=False, links_in_contact=(), simulated_time=simulated,
                failure=warnings[-1], warnings=tuple(warnings),
            )  # fmt: skip
        mujoco.mj_forward(self.model, self.stepper.data)  # sensors and contacts of the final state
        com1, quat1 = self._pose()
        displacement = float(np.linalg.norm(com1 - com0))
        rotation = float(np.degrees(quat_angle(quat0, quat1)))
        links = self._links_in_contact()
        failures = []
        if spec.require_contact and not links:
            failures.append("lost contact with the hand")
        if not displacement < spec.max_displacement:
            failures.append(f"moved {displacement * 1000:.1f} mm ≥ {spec.max_displacement * 1000:.1f} mm")
        if spec.max_rotation_deg is not None and not rotation < spec.max_rotation_deg:
            failures.append(f"turned {rotation:.1f}° ≥ {spec.max_rotation_deg:.1f}°")
        return DirectionResult(
            direction=label, gravity=vector, success=not failures, displacement=displacement,
            rotation_deg=rotation, in_contact_at_end=bool(links), links_in_contact=links,
            simulated_time=simulated, failure="; ".join(failures), warnings=tuple(warnings),
        )  # fmt: skip
