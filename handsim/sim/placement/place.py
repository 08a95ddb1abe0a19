"""Where to put the object a glove recording grasped: where it fits in the closing hand and is gripped best.

GraspDB14 records the hand, not the object, and a CyberGlove's calibration usually over-reports flexion:
at the closed frame the recorded fingers lie *inside* the object they held (fingertips 22–26 mm from the
thumb tip around a 64 mm ball in the shared recordings). So the object is placed where it fits in the hand
*before* closure, and the recorded closing then grips it — the fingers the recording closes past the object
stop at its surface and press on it.

The search (:func:`place_object`):

1. **Candidates** (:mod:`handsim.sim.placement.search`, on the poses of :mod:`handsim.sim.placement.poses`).
   At the closing-ramp frames of :attr:`PlacementSpec.search_fractions`
   (:func:`handsim.sim.placement.grasp_frame.closing_frames`), object poses on a grid over the hand's reach
   (24
   axis-aligned orientations unless the object is a sphere) are scored by MuJoCo's own collision detection
   (:class:`~handsim.sim.placement.collide.HandObjectCollider`): poses with at most
   :attr:`PlacementSpec.penetration` of penetration that touch the most hand links, ties to the pose nearest
   the fingertips' centre at the closed frame. The best :attr:`PlacementSpec.seeds` of each level are
   refined on a finer grid.
2. **Fit frame.** Each candidate's fit frame is the latest frame of the closing ramp at which the hand at its
   targets penetrates it at most :attr:`PlacementSpec.penetration`: its flexion fraction says how far the
   recorded closing passes the object (1.0: it fits at full closure).
3. **Grip.** From its fit frame to the release, the recorded closing grips each candidate held in place, and
   the grasp stability test (gravity along ±x ±y ±z, after DexGraspNet; :mod:`handsim.sim.placement.grip`)
   counts the
   directions the grip resists. The winner resists the most directions; ties go to the later fit (less
   over-closure assumed), then to the smaller mean displacement, then to more links and less penetration.
   A grip test ends once its grip can no longer resist as many directions as an earlier candidate's (the
   directions that failed most often so far run first): such a candidate can be neither the winner nor an
   alternative, nor does it resist all six, so the placement is the one of whole tests. (A run not made
   raises no error it would have raised: with threads, whether it is made depends on timing.)

Every pose within the tolerance is a candidate: when none touches the hand, the feasible pose nearest the
fingertips' centre is kept (with a note); only when no pose of any level is within the tolerance is the
placement infeasible, and then it says so with the numbers (the replay's hold is then not judged).

Speed: the poses of one orientation are first screened together by cheap bounds
(:meth:`HandObjectCollider.screen`): a pose that touches nothing, or that is surely deeper than the
tolerance plus :data:`~handsim.sim.placement.search.SCREEN_MARGIN`, is settled without a collision query;
so is a pose where the collider's probe, MuJoCo's detection on the one geom pair found deepest last, finds
it deeper than the tolerance (:meth:`HandObjectCollider.depth_links`). The result is the same as querying
every pose (an infeasible search is rerun without the bounds and the probe, so that its least penetration
is MuJoCo's). On several threads (:mod:`handsim.sim.parallel`) the next candidates'
grip tests run while the current one's does (:func:`~handsim.sim.parallel.map_until`): the candidates and
the count of poses tried are those of testing them one after the other. :func:`place_object` keeps each
result in the placement cache (:mod:`handsim.sim.placement.cache`).

The search's parameters and results (:class:`PlacementSpec`, :class:`Candidate`, :class:`Placement`) are in
:mod:`handsim.sim.placement.candidates`; this module runs the search, the grip tests and the cache.
"""

from __future__ import annotations

import pickle
import threading
from collections.abc import Iterator
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from handsim.cache import CorruptEntryError, default_cache_dir, write_failed
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.parallel import map_until
from handsim.sim.placement.cache import entry_path, placement_key, read_entry, write_entry
from handsim.sim.placement.candidates import Candidate, Placement
from handsim.sim.placement.grasp_frame import GraspFrame, closing_frames
from handsim.sim.placement.grip import GripBench, GripResult
from handsim.sim.placement.hand_pose import targets_qpos
from handsim.sim.placement.poses import perturbed_poses
from handsim.sim.placement.search import PlacementSearch
from handsim.sim.scene.compiled import SimScene
from handsim.sim.self_contact import SelfCollider, SelfPenetration
from handsim.sim.specs import PlacementSpec
from handsim.sim.stability.gravity import DIRECTIONS, DirectionResult, StabilityResult

_CACHED_CLASSES = {
    (cls.__module__, cls.__qualname__): cls
    for cls in (Placement, Candidate, GripResult, StabilityResult, DirectionResult, SelfPenetration)
}
"""What a placement cache entry may hold besides arrays and plain values."""


def _searched(
    scene: SimScene, trajectory: Trajectory, grasp: GraspFrame, spec: PlacementSpec, screen: bool
) -> tuple[PlacementSearch, list[tuple[tuple, int, np.ndarray]]]:
    """The search at every level and its seeds ranked by what the closing presses (ties: the later fit)."""
    search = PlacementSearch(scene, trajectory, grasp, spec, screen)
    ranked: list[tuple[tuple, int, np.ndarray]] = []
    for level, frame in enumerate(closing_frames(trajectory, grasp, spec.search_fractions)):
        for key, pose in search.level(frame):
            if all(not np.allclose(pose, other, atol=1e-9) for _, _, other in ranked):
                ranked.append((key, -level, pose))
    ranked.sort(key=lambda item: item[:2], reverse=True)
    return search, ranked


def place_object(
    scene: SimScene,
    trajectory: Trajectory,
    grasp: GraspFrame,
    spec: PlacementSpec,
    release_delay: float,
    control_rate: float,
    shift: float = 0.0,
    turn_deg: float = 0.0,
    *,
    use_cache: bool = True,
    cache_dir: str | Path | None = None,
) -> Placement:
    """Search the object pose that fits in the closing hand and that the recorded closing grips best.

    Args:
        scene: A scene with the hand (fixed root) and one free object on its support weld, no table.
        trajectory: The glove trajectory.
        grasp: Its grasp frames (:func:`handsim.sim.placement.grasp_frame.grasp_frame`).
        spec: The search's parameters.
        release_delay: Seconds after the closed frame at which the support comes off: the grip is tested
            at that time.
        control_rate: Control frames per second of the replay the grip tests reproduce.
        shift: Distance the robustness ensemble moves the winner along each axis, m (0: no moves).
        turn_deg: Angle it turns the winner about each axis, degrees (0: no turns).
        use_cache: Read and write the placement cache (:mod:`handsim.sim.placement.cache`): a hit gives
            the stored placement bit for bit. When False, neither.
        cache_dir: Root of the cache; :func:`handsim.cache.default_cache_dir` when None.

    Returns:
        The placement (see the module docstring); never raises for want of a feasible pose: an infeasible
        placement says so (``feasible`` False, with the least penetration seen in the note).
    """
    arguments = {
        "spec": spec.to_dict(),
        "release_delay": release_delay,
        "control_rate": control_rate,
        "shift": shift,
        "turn_deg": turn_deg,
    }
    if not use_cache:
        return _place(scene, trajectory, grasp, spec, release_delay, control_rate, shift, turn_deg)
    key = placement_key(scene, trajectory, grasp, arguments)
    root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = entry_path(root, key)
    notes = []
    if path.is_file():
        try:
            return read_entry(path, key, _CACHED_CLASSES)
        except CorruptEntryError as e:
            notes.append(f"placement cache entry {path} was corrupt ({e}) and was replaced")
    placement = _place(scene, trajectory, grasp, spec, release_delay, control_rate, shift, turn_deg)
    try:
        write_entry(path, key, placement)
    except OSError as e:  # a read-only cache folder, a file in its place, a full disk
        notes.append(write_failed(root, path, e, "placement"))
    except (pickle.PicklingError, TypeError) as e:  # a result that will not pickle
        notes.append(f"could not write placement cache entry {path}: {e}")
    return replace(placement, note="; ".join([placement.note, *notes])) if notes else placement


def _place(
    scene: SimScene,
    trajectory: Trajectory,
    grasp: GraspFrame,
    spec: PlacementSpec,
    release_delay: float,
    control_rate: float,
    shift: float,
    turn_deg: float,
) -> Placement:
    """The search of :func:`place_object`, without the cache."""
    search, ranked = _searched(scene, trajectory, grasp, spec, screen=True)
    if search.nearest is None and search.pruned_deep:  # infeasible: the least penetration needs every query
        search, ranked = _searched(scene, trajectory, grasp, spec, screen=False)
    times = np.asarray(trajectory.times, dtype=float)
    bench = GripBench(scene, trajectory, control_rate, float(times[grasp.closed]) + release_delay)
    grips = _GripTests(bench, times, spec, len(ranked))
    tested, queries = _grip_tested(search, ranked, grips)
    best, feasible, note = _winner(search, tested, grips, queries)
    return Placement(
        best=best,
        alternatives=_alternatives(tested, best, spec.alternatives),
        perturbations=_perturbations(search, best, shift, turn_deg) if feasible else (),
        feasible=feasible,
        queries=queries,
        grip_tests=len(tested) + (1 if not tested and feasible else 0),
        feasible_poses=search.feasible_poses,
        object_points=search.points,
        self_penetration=SelfCollider(scene)(targets_qpos(scene, trajectory, grasp.closed)),
        spec=spec.to_dict(),
        note=note,
    )


class _GripTests:
    """The grip tests of the ranked candidates, each ended once it cannot matter.

    A candidate whose grip can no longer resist as many directions as an earlier one's is neither the
    winner nor an alternative, nor does it count towards the stop (it does not resist all six): its test
    ends there. So that such a test ends sooner, the directions that failed most often in the tests so far
    run first (the directions are independent: the whole tests are the same in any order). The tests may
    run on several threads (:func:`~handsim.sim.parallel.map_until`): the counts they share live here.
    """

    def __init__(self, bench: GripBench, times: np.ndarray, spec: PlacementSpec, count: int) -> None:
        """Tests on ``bench`` (trajectory ``times``, s) with ``spec``'s grip test, of ``count`` candidates."""
        self._bench, self._times, self._spec = bench, times, spec
        self._held = [-1] * count  # directions held by each ranked candidate's finished test (-1: not yet)
        self._failures = dict.fromkeys(DIRECTIONS, 0)  # the runs made that failed, per direction
        self._counting = threading.Lock()

    def whole(self, candidate: Candidate) -> Candidate:
        """The candidate with its whole grip test."""
        return self._with_grip(candidate)

    def ranked(self, ranked_candidate: tuple[int, Candidate]) -> Candidate:
        """The candidate of rank ``ranked_candidate[0]`` with its grip test, ended once it cannot matter."""
        rank, candidate = ranked_candidate
        first = sorted(DIRECTIONS, key=lambda label: -self._failures[label])
        result = self._with_grip(candidate, needed=partial(self._needed, rank), first=first)
        with self._counting:
            for d in result.grip.stability.directions:
                self._failures[d.direction] += not d.success and d.simulated_time > 0  # the runs made
        self._held[rank] = result.grip.directions_held
        return result

    def enough(self, grips: list[Candidate]) -> bool:
        """Whether more of ``grips`` resist every direction than the alternatives kept besides the best."""
        return sum(c.grip.directions_held == len(DIRECTIONS) for c in grips) > self._spec.alternatives

    def _needed(self, rank: int) -> int:
        """Directions the test of rank ``rank`` must still be able to resist to matter.

        Asked before each direction: on threads, earlier tests may finish meanwhile.
        """
        return max(self._held[:rank], default=0)

    def _with_grip(self, candidate: Candidate, **stop) -> Candidate:
        """The candidate with its grip test (``stop``: :meth:`GripBench.grip`'s ``needed`` and ``first``)."""
        contact = float(self._times[candidate.contact_frame])
        return replace(candidate, grip=self._bench.grip(candidate.pose, contact, self._spec.grip, **stop))


class _Draws:
    """The ranked candidates, drawn lazily in rank order, with the collider's query count after each draw."""

    def __init__(self, search: PlacementSearch, ranked: list[tuple[tuple, int, np.ndarray]]) -> None:
        """Draws of the ranked seeds (key, level, pose) of ``search``."""
        self._search, self._ranked = search, ranked
        self.queries: list[int] = []  # the collider's query count after each candidate drawn

    def __iter__(self) -> Iterator[tuple[int, Candidate]]:
        """(rank, candidate with its fit and contact frames) of each seed, best ranked first."""
        search = self._search
        for rank, (_, _, pose) in enumerate(self._ranked):
            candidate = search.with_contact(search.candidate(pose))
            self.queries.append(search.collider.queries)
            yield rank, candidate


def _grip_tested(
    search: PlacementSearch, ranked: list[tuple[tuple, int, np.ndarray]], grips: _GripTests
) -> tuple[list[Candidate], int]:
    """The ranked candidates with their grip tests, best first, and the count of poses tried.

    In rank order, until enough grips resist every direction; the next candidates' grip tests run on the
    other threads meanwhile (each is independent: the same result as testing them one after the other).
    The candidates drawn past the stop leave no trace in the count of poses tried.
    """
    draws = _Draws(search, ranked)
    tested = map_until(grips.ranked, draws, grips.enough)
    queries = draws.queries[len(tested) - 1] if tested else search.collider.queries
    tested.sort(key=Candidate.score, reverse=True)
    return tested, queries + search.screened


def _winner(
    search: PlacementSearch, tested: list[Candidate], grips: _GripTests, queries: int
) -> tuple[Candidate, bool, str]:
    """The placed candidate, whether it is feasible, and the placement's note.

    The best grip test's candidate; without one, the feasible pose nearest the fingertips' centre (with its
    whole grip test); without that, the least penetrating pose seen (infeasible).
    """
    grasp, tolerance = search.grasp, search.spec.penetration
    if tested:
        best = tested[0]
        note = (
            f"object placed where it fits at frame {best.fit_frame} (flexion fraction "
            f"{best.fit_fraction:.2f} of the closing {grasp.open}–{grasp.closed}), touching "
            f"{len(best.links)} links ({', '.join(best.links)}), penetration {best.depth * 1000:.2f} mm; the "
            f"recorded closing grips it against {best.grip.directions_held} of 6 gravity directions; best of "
            f"{len(tested)} grip tests, {queries} poses tried, {search.feasible_poses} within "
            f"{tolerance * 1000:g} mm"
        )
        return best, True, note
    if search.nearest is not None:
        best = grips.whole(search.with_contact(search.candidate(search.nearest[1])))
        note = (
            f"no object pose within {tolerance * 1000:g} mm of penetration touches the hand on the "
            f"closing ramp: placed nearest the fingertips' centre without penetration ({queries} poses tried)"
        )
        return best, True, note
    depth, pose = search.least if search.least is not None else (np.inf, np.array([0, 0, 0, 1, 0, 0, 0.0]))
    note = (
        f"no object pose on the closing ramp penetrates the hand less than "
        f"{tolerance * 1000:g} mm: the least penetrating of {queries} poses tried goes "
        f"{depth * 1000:.1f} mm deep; placement infeasible, the hold is not judged"
    )
    return search.with_contact(search.candidate(pose)), False, note


def _alternatives(tested: list[Candidate], best: Candidate, count: int) -> tuple[Candidate, ...]:
    """Up to ``count`` of the tested candidates after the best that resist as many directions as it."""
    return tuple(c for c in tested[1:] if c.grip.directions_held == best.grip.directions_held)[:count]


def _perturbations(
    search: PlacementSearch, best: Candidate, shift: float, turn_deg: float
) -> tuple[tuple[str, Candidate], ...]:
    """The robustness ensemble: the winner moved by ``shift`` (m) and turned by ``turn_deg`` (degrees)."""
    if not (shift > 0 or turn_deg > 0):
        return ()
    points = None if search.round else search.points
    return tuple(
        (label, search.with_contact(search.candidate(pose)))
        for label, pose in perturbed_poses(best.pose, shift, turn_deg, points)
    )
