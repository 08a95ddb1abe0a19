"""The glove placement's grid search: candidate poses at each closing frame, their fit and contact frames.

Steps 1 and 2 of :mod:`handsim.sim.placement.place` (candidates on coarse and refined grids, ranked by what
the
recorded closing does to them; each candidate's fit frame and contact frame). The grip tests and the choice
of the winner are :func:`handsim.sim.placement.place.place_object`'s.
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import mujoco
import numpy as np

from handsim.datatypes.fingers import finger_of
from handsim.datatypes.rotations import quat_to_matrix
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.parallel import map_on_workers, sim_threads
from handsim.sim.placement.candidates import Candidate
from handsim.sim.placement.collide import CLEAR, DEEP, HandObjectCollider
from handsim.sim.placement.grasp_frame import GraspFrame, flexion_fraction
from handsim.sim.placement.hand_pose import targets_qpos
from handsim.sim.placement.poses import (
    axis_aligned_orientations,
    box_grid,
    distinct_orientations,
    grid_around,
    object_points,
)
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import PlacementSpec

MIN_THREAD_QUERIES = 64
"""Collision queries per thread below which :meth:`PlacementSearch._depths` stays on one thread."""
QUERY_CHUNK = 256
"""Most poses per :meth:`HandObjectCollider.depth_links` call (the unit dealt out to threads)."""
SCREEN_MARGIN = 0.002
"""A pose whose inscribed balls overlap the hand's by more than the penetration tolerance plus this is
settled as infeasible without a collision query, m. MuJoCo's capsule–mesh depths (native CCD) came out at
most 0.88 mm below the bound on the 613 000 queries of five catalogue mesh objects' searches (the mug, bowl,
glass, oval jar and bottle; never above MuJoCo's depth where that was under 4 mm), so the margin is 2.3× the
worst; the winner does not depend on it (docs/replay.md). Boxes and cylinders bound no depth at all."""
_FINGERS = frozenset({"index", "middle", "ring", "little"})


class PlacementSearch:
    """The grid search at one hand posture (see the module docstring)."""

    def __init__(
        self, scene: SimScene, trajectory: Trajectory, grasp: GraspFrame, spec: PlacementSpec, screen: bool
    ) -> None:
        self.scene, self.trajectory, self.grasp, self.spec = scene, trajectory, grasp, spec
        self.screen = screen  # settle poses by bounds where they decide the query (CLEAR, DEEP)
        self.screened = 0  # poses settled without a collision query
        self.pruned_deep = False  # some pose was settled as infeasible: the least penetration is not known
        self.collider = HandObjectCollider(scene, spec.touch)
        self._forks: list[HandObjectCollider] = []  # the collider's forks for other threads (_helpers)
        self.points = object_points(self.collider)
        self.quats = distinct_orientations(axis_aligned_orientations(), self.points)
        model, geoms = self.collider.model, np.flatnonzero(self.collider.is_obj)
        self.round = (  # one sphere about the object's origin: no turn changes it
            len(geoms) == 1
            and int(model.geom_type[geoms[0]]) == int(mujoco.mjtGeom.mjGEOM_SPHERE)
            and np.allclose(model.geom_pos[geoms[0]], 0.0)
        )
        self.radius = float(np.linalg.norm(self.points, axis=1).max())
        layout = scene.layout
        collider = self.collider
        collider.set_hand(targets_qpos(scene, trajectory, grasp.closed))
        mujoco.mj_kinematics(collider.model, collider.data)
        tips = collider.data.site_xpos[layout.tip_sites].copy()
        self.centre = tips.mean(axis=0)
        thumbs = [i for i, name in enumerate(layout.tip_names) if finger_of(name) == "thumb"]
        others = [i for i in range(len(tips)) if i not in thumbs]
        self.grasp_points = np.vstack(
            [self.centre, *((tips[t] + tips[o]) / 2 for t in thumbs for o in others)]
        )
        groups = [finger_of(name) for name in layout.link_names]
        labels = sorted(set(groups) | {"palm"})
        self._group_of_link = np.array([[g == label for label in labels] for g in groups], dtype=bool)
        self._palm = labels.index("palm")
        self._opposing = np.isin(labels, ["thumb", "palm"])  # _ranked: against a finger
        self._fingers = np.isin(labels, sorted(_FINGERS))
        self.feasible_poses = 0
        self.least: tuple[float, np.ndarray] | None = None  # least penetration seen, pose
        self.nearest: tuple[float, np.ndarray] | None = None  # feasible pose nearest the centre

    def _reach(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        collider, layout = self.collider, self.scene.layout
        mujoco.mj_kinematics(collider.model, collider.data)
        data = collider.data
        reach = np.vstack([data.xpos[layout.link_bodies], data.site_xpos[layout.tip_sites]])
        centres, radii = collider.hand_spheres()
        return reach.min(axis=0), reach.max(axis=0), centres, radii

    def _consider(self, poses: np.ndarray, depths: np.ndarray) -> None:
        """Count the poses (N, 7) with their depths (N,) into the least deep and the nearest feasible pose.

        As if they were taken one by one in order, each replacing the one kept only when strictly less
        deep (nearer): the first of the least deep (nearest) wins. The distance that decides the nearest is
        ``np.linalg.norm`` of each pose, computed for the few poses within rounding of the least.
        """
        if not len(depths):
            return
        first = int(np.argmin(depths))  # the first of the least deep
        if self.least is None or depths[first] < self.least[0]:
            self.least = (float(depths[first]), poses[first].copy())
        feasible = np.flatnonzero(depths <= self.spec.penetration)
        self.feasible_poses += feasible.size
        if not feasible.size:
            return
        offsets = poses[feasible, :3] - self.centre
        rough = np.sqrt((offsets * offsets).sum(axis=1))  # within a few ulp of np.linalg.norm's
        close = feasible[rough <= rough.min() * (1.0 + 1e-9) + 1e-300]
        exact = [float(np.linalg.norm(poses[i, :3] - self.centre)) for i in close]
        best = int(np.argmin(exact))  # the first of the nearest
        if self.nearest is None or exact[best] < self.nearest[0]:
            self.nearest = (exact[best], poses[close[best]].copy())

    def _verdicts(self, poses: np.ndarray) -> np.ndarray:
        """:meth:`HandObjectCollider.screen` of each pose (runs of one orientation screened together)."""
        verdicts = np.zeros(len(poses), dtype=np.int8)
        if not self.screen or not len(poses):
            return verdicts
        deep = self.spec.penetration + SCREEN_MARGIN
        for a, b in _orientation_runs(poses):
            verdicts[a:b] = self.collider.screen(poses[a:b, :3], poses[a, 3:], deep)
        return verdicts

    def _fits(self, frame: int, poses: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """The poses (N, 7) that fit (within the tolerance) and touch the hand at ``frame``, with their links.

        A pose the bounds settle as clear fits and touches nothing (depth 0); one settled as deep (by the
        bounds, or by the collider's probe: :meth:`HandObjectCollider.depth_links`) is left out; the others
        are collision queries.
        """
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        verdicts = self._verdicts(poses)
        clear, deep = verdicts == CLEAR, verdicts == DEEP
        asked = np.flatnonzero(~clear & ~deep)
        depths, links = np.zeros(len(poses)), np.zeros(len(poses), dtype=np.int64)
        if asked.size:
            depths[asked], links[asked] = zip(*self._depths(poses[asked]), strict=True)
            deep[asked[np.isinf(depths[asked])]] = True  # settled by the collider's probe
        self.screened += int(clear.sum() + deep.sum())
        self.pruned_deep = self.pruned_deep or bool(deep.any())
        kept = np.flatnonzero(~deep)
        self._consider(poses[kept], depths[kept])
        fitting = np.flatnonzero(~deep & (depths <= self.spec.penetration) & (links > 0))
        return [(poses[i].copy(), int(links[i])) for i in fitting]

    def _depths(self, poses: np.ndarray) -> list[tuple[float, int]]:
        """:meth:`HandObjectCollider.depth_links` of each pose, in order, the poses spread over threads.

        The poses (N, 7) go to it in runs of one orientation of at most :data:`QUERY_CHUNK`; each thread
        queries its own fork of the collider (the hand at the same posture; :mod:`handsim.sim.parallel`).
        Without screening the answers are those of one collider querying them all. When screening, a pose
        the probe finds deeper than the tolerance comes back settled (depth ``inf``) instead of with its
        depth: which poses do depends on each probe's history, so on threads on their timing, but every
        one of them is too deep, which is all the search concludes of it.
        """
        if not len(poses):
            return []
        spans = [
            (start, min(start + QUERY_CHUNK, b))
            for a, b in _orientation_runs(poses)
            for start in range(a, b, QUERY_CHUNK)
        ]

        def query(collider: HandObjectCollider, span: tuple[int, int]) -> tuple[list[float], list[int]]:
            return collider.depth_links(poses[span[0] : span[1], :3], poses[span[0], 3:], settle)

        settle = self.spec.penetration if self.screen else None
        threads = min(sim_threads(), len(poses) // MIN_THREAD_QUERIES, len(spans))
        if threads <= 1:
            parts = [query(self.collider, span) for span in spans]
        else:
            colliders = [self.collider, *self._helpers(threads - 1)]
            parts = map_on_workers(query, spans, colliders)
            self.collider.queries += sum(c.queries for c in colliders[1:])
        return [answer for depths, links in parts for answer in zip(depths, links, strict=True)]

    def _helpers(self, n: int) -> list[HandObjectCollider]:
        """``n`` forks of the collider at its posture, their query counts at 0.

        Kept for the level's next calls (a fork's probe copies the model: ~2 ms for the mug) and dropped at
        its end (:meth:`level`): each holds an ``MjData`` and a model copy (~18 MB for the mug).
        """
        while len(self._forks) < n:
            self._forks.append(self.collider.fork())
        for helper in self._forks[:n]:
            helper.follow(self.collider)
            helper.queries = 0
        return self._forks[:n]

    def _ranked(self, fitting: list[tuple[np.ndarray, int]]) -> list[tuple[tuple, np.ndarray]]:
        """Fitting poses ranked by what the recorded closing does to them (best first).

        At the closed frame a finger whose links lie deeper than the tolerance inside the object is one the
        recording closes past it: it will press on it. The key: the pressing fingers oppose each other (the
        thumb or the palm against a finger), how many finger groups press, how many links touch where it
        fits, and closeness to the fingertips' centre.
        """
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, self.grasp.closed))
        ranked: list[tuple[tuple, np.ndarray]] = []
        if not fitting:
            return ranked
        poses = np.array([pose for pose, _ in fitting])
        distances = np.concatenate(
            [self.collider.distances(poses[a:b, :3], poses[a, 3:]) for a, b in _orientation_runs(poses)]
        )
        # the groups pressing at each pose, (N, groups): a link deeper than the tolerance, or a palm link
        # within the touch distance
        groups = self._group_of_link
        pressing = (distances < -self.spec.penetration) @ groups
        pressing[:, self._palm] |= (np.isfinite(distances) @ groups)[:, self._palm]
        opposed = pressing[:, self._opposing].any(axis=1) & pressing[:, self._fingers].any(axis=1)
        counts = pressing.sum(axis=1).tolist()
        for (pose, links), oppose, count in zip(fitting, opposed.tolist(), counts, strict=True):
            key = (oppose, count, links, -float(np.linalg.norm(pose[:3] - self.centre)))
            ranked.append((key, pose))
        ranked.sort(key=lambda item: item[0], reverse=True)
        return ranked

    def level(self, frame: int) -> list[tuple[tuple, np.ndarray]]:
        """The seeds of one closing frame, each refined on finer grids around it: (key, pose), best first."""
        spec, collider = self.spec, self.collider
        collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        lo, hi, centres, radii = self._reach()
        coarse, steps = [np.zeros((0, 7))], {}
        for quat in self.quats:
            extent = self.points @ quat_to_matrix(quat).T
            # the object's box holds a point the closing converges on, and it lies within the hand's reach
            low = np.maximum(lo, self.grasp_points.min(axis=0) - spec.coarse_step) - extent.max(axis=0)
            high = np.minimum(hi, self.grasp_points.max(axis=0) + spec.coarse_step) - extent.min(axis=0)
            step = max(spec.coarse_step, float(np.prod(high - low) / spec.coarse_points) ** (1 / 3))
            grid = box_grid(low, high, step)
            gap = np.linalg.norm(grid[:, None, :] - centres[None], axis=-1) - radii - self.radius
            grid = grid[(gap <= spec.touch).any(axis=1)]  # can touch some link at all
            steps[tuple(quat)] = step
            coarse.append(_with_orientation(grid, quat))
        seeds = self._diverse(self._ranked(self._fits(frame, np.concatenate(coarse))), steps)
        refined = []
        for key, pose in seeds:
            span = steps[tuple(pose[3:])]
            while span > spec.fine_step + 1e-12:  # halve the spacing around the best pose until fine
                span /= 2
                around = _with_orientation(grid_around(pose[:3], 2 * span, span), pose[3:])
                best = self._ranked(self._fits(frame, around))
                if best and best[0][0] > key:
                    key, pose = best[0]
            refined.append((key, pose))
        self._forks.clear()  # not kept past the level (_helpers)
        return refined

    def _diverse(self, ranked: list, steps: dict) -> list:
        kept: list = []
        for key, pose in ranked:
            step = steps[tuple(pose[3:])]
            if all(
                not np.array_equal(pose[3:], other[3:]) or np.linalg.norm(pose[:3] - other[:3]) > 1.5 * step
                for _, other in kept
            ):
                kept.append((key, pose))
            if len(kept) == self.spec.seeds:
                break
        return kept

    def depth_at(self, frame: int, pose: np.ndarray) -> tuple[float, np.ndarray]:
        """Penetration and touching links of ``pose`` with the hand at the targets of ``frame``."""
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        touch = self.collider.touch_at(pose[:3], pose[3:])
        return touch.depth, touch.links

    def candidate(self, pose: np.ndarray) -> Candidate:
        """The candidate at ``pose`` with its fit frame, searched down from the closed frame.

        Its contact frame is left at its fit frame until :meth:`with_contact`.
        """
        grasp, tolerance = self.grasp, self.spec.penetration
        frame, depth, links = grasp.open, *self.depth_at(grasp.open, pose)
        for f in range(grasp.closed, grasp.open - 1, -1):
            d, touching = self.depth_at(f, pose)
            if d <= tolerance:
                frame, depth, links = f, d, touching
                break
        return Candidate(
            pose=pose,
            links=tuple(self.scene.layout.link_names[i] for i in links),
            depth=depth,
            fit_frame=frame,
            fit_fraction=flexion_fraction(self.trajectory, grasp, frame),
            contact_frame=frame,
            depth_before_contact=0.0,
        )

    def with_contact(self, candidate: Candidate) -> Candidate:
        """The candidate with its contact frame (hand–object contacts act from there).

        It is the first frame of the run of frames up to its fit frame in which the hand at its targets is
        within the tolerance of it, searched back to the closing's open frame at most: the object is reached
        during the closing, and the hand moving before it (at rest, reaching) does not touch it.
        """
        opened = min(self.grasp.open, candidate.fit_frame)
        for f in range(candidate.fit_frame - 1, opened - 1, -1):
            depth, _ = self.depth_at(f, candidate.pose)
            if depth > self.spec.penetration:
                return replace(candidate, contact_frame=f + 1, depth_before_contact=depth)
        return replace(candidate, contact_frame=opened, depth_before_contact=0.0)


def _orientation_runs(poses: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of consecutive poses (N, 7) with the same orientation."""
    starts = [0, *(np.flatnonzero((poses[1:, 3:] != poses[:-1, 3:]).any(axis=1)) + 1), len(poses)]
    return list(itertools.pairwise(starts))


def _with_orientation(positions: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Poses (N, 7): ``positions`` (N, 3) each with orientation ``quat``."""
    return np.hstack([positions, np.broadcast_to(quat, (len(positions), 4))])
