"""The object's distance field and the hand's sample balls: the bounds the placement screen settles poses by.

Every bound is checked against an independent computation: exact signed distances to the object's convex
parts (depth from all of a hull's faces inside, trimesh's closest points outside), points drawn inside the
hand's geoms. The search screened by them must stay the search by collision queries (bit for bit).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.spatial import ConvexHull
from test_placement_cache import _bits, _search_inputs

import handsim.sim.object_field as object_field_module
from handsim.sim.collide import HandObjectCollider
from handsim.sim.hand_samples import hand_samples
from handsim.sim.object_field import object_field
from handsim.sim.placement import _searched


def _at_identity(collider: HandObjectCollider) -> list[np.ndarray]:
    """The object's colliding geoms' hull points in its own frame (its free joint at the identity)."""
    model, data, a = collider.model, collider.data, collider.obj.free_qpos
    data.qpos[a : a + 7] = [0, 0, 0, 1, 0, 0, 0]
    mujoco.mj_kinematics(model, data)
    parts = []
    for g in np.flatnonzero(collider.is_obj):
        mesh = int(model.geom_dataid[g])
        local = model.mesh_vert[
            model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]
        ]
        parts.append(data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T)
    return parts


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(P, T) distances from points (P, 3) to segments a–b (T, 3)."""
    ab = b - a
    t = np.clip(((points[:, None] - a[None]) * ab[None]).sum(-1) / (ab * ab).sum(-1)[None], 0.0, 1.0)
    return np.linalg.norm(points[:, None] - (a[None] + t[..., None] * ab[None]), axis=-1)


def _triangle_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(P,) least distance from each point to the triangles (T, 3, 3): the plane where the foot of the
    perpendicular falls inside a triangle, else the nearest edge."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    height = ((points[:, None] - a[None]) * normal[None]).sum(-1)  # (P, T)
    foot = points[:, None] - height[..., None] * normal[None]
    inside = np.ones(height.shape, dtype=bool)
    for p, q in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(q - p, foot - p[None]) * normal[None]).sum(-1) >= 0.0
    edges = np.minimum.reduce([_segment_distance(points, p, q) for p, q in ((a, b), (b, c), (c, a))])
    return np.where(inside, np.abs(height), edges).min(axis=1)


def _signed_distance(parts: list[np.ndarray], points: np.ndarray) -> np.ndarray:
    """Exact signed distance to the nearest convex part (negative inside: minus the deepest depth)."""
    best = np.full(len(points), np.inf)
    for vertices in parts:
        hull = ConvexHull(vertices)
        planes = hull.equations
        inside = (points @ planes[:, :3].T + planes[:, 3]).max(axis=1)
        outside = _triangle_distance(points, vertices[hull.simplices])
        best = np.minimum(best, np.where(inside <= 0.0, inside, outside))
    return best


@pytest.fixture(scope="module")
def mug_collider(tmp_path_factory) -> HandObjectCollider:
    monkeypatch = pytest.MonkeyPatch()
    try:
        (scene, *_), _ = _search_inputs(monkeypatch, tmp_path_factory.mktemp("mug"), obj="mug")
    finally:
        monkeypatch.undo()
    return HandObjectCollider(scene, 0.002)


def test_the_field_bounds_the_exact_signed_distance_of_the_mugs_parts(mug_collider, tmp_path):
    parts = _at_identity(mug_collider)
    geoms = np.flatnonzero(mug_collider.is_obj)
    field = object_field(mug_collider.model, mug_collider.data, geoms, 0.01, cache_dir=tmp_path)
    assert field is not None
    low, high = np.min([p.min(axis=0) for p in parts], axis=0), np.max([p.max(axis=0) for p in parts], axis=0)
    rng = np.random.default_rng(3)
    points = rng.uniform(low - 0.05, high + 0.05, size=(1500, 3))  # inside, near and beyond the grid
    exact = _signed_distance(parts, points)
    upper, lower = field.at(points)
    assert (upper >= exact - 1e-9).all()
    assert (lower <= np.maximum(exact, 0.0) + 1e-9).all()
    # tight enough to matter: most points within 5 mm of the surface are bounded within 6 mm each way
    near = np.abs(exact) < 0.005
    assert near.sum() > 50
    assert np.mean(upper[near] - exact[near] < 0.006) > 0.9
    assert np.mean(np.maximum(exact[near], 0.0) - lower[near] < 0.006) > 0.9


def test_the_field_is_made_once_per_object_and_not_for_spheres(mug_collider, monkeypatch, tmp_path):
    geoms = np.flatnonzero(mug_collider.is_obj)
    first = object_field(mug_collider.model, mug_collider.data, geoms, 0.01, cache_dir=tmp_path)
    assert object_field(mug_collider.model, mug_collider.data, geoms, 0.01, cache_dir=tmp_path) is first
    (ball_scene, *_), _ = _search_inputs(monkeypatch, tmp_path)  # the demo tennis ball: one sphere
    ball = HandObjectCollider(ball_scene, 0.002)
    assert object_field(ball.model, ball.data, np.flatnonzero(ball.is_obj), 0.01, cache_dir=tmp_path) is None


def test_the_field_is_kept_on_disk_bit_for_bit_and_a_corrupt_entry_is_replaced(mug_collider, tmp_path):
    model, data, geoms = mug_collider.model, mug_collider.data, np.flatnonzero(mug_collider.is_obj)
    object_field_module._CACHE.clear()
    made = object_field(model, data, geoms, 0.01, cache_dir=tmp_path)
    entries = list((tmp_path / "field").rglob("*.pkl"))
    assert len(entries) == 1
    object_field_module._CACHE.clear()
    read = object_field(model, data, geoms, 0.01, cache_dir=tmp_path)
    assert read is not made and _bits(read) == _bits(made)
    entries[0].write_bytes(entries[0].read_bytes()[:-10] + b"0123456789")
    object_field_module._CACHE.clear()
    again = object_field(model, data, geoms, 0.01, cache_dir=tmp_path)
    assert _bits(again) == _bits(made)
    object_field_module._CACHE.clear()
    assert _bits(object_field(model, data, geoms, 0.01, cache_dir=tmp_path)) == _bits(made)  # replaced


def test_hand_balls_lie_inside_their_geoms_and_cover_them(mug_collider):
    model = mug_collider.model
    geoms = mug_collider._hand_geoms
    samples = hand_samples(model, geoms, 0.0025)
    rng = np.random.default_rng(5)
    kinds = set()
    for g in geoms:
        mine = samples.geom == g
        local, inside, cover = samples.local[mine], samples.inside[mine], samples.cover[mine]
        kind = int(model.geom_type[g])
        kinds.add(kind)
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            radius, half = model.geom_size[g][:2]
            depth = radius - np.linalg.norm(local[:, :2], axis=1) - np.maximum(np.abs(local[:, 2]) - half, 0)
            direction = rng.normal(size=(2000, 3))
            direction /= np.linalg.norm(direction, axis=1)[:, None]
            drawn = direction * radius * rng.uniform(0, 1, (2000, 1)) ** (1 / 3)
            drawn[:, 2] += rng.uniform(-half, half, 2000)
        else:
            assert kind == mujoco.mjtGeom.mjGEOM_MESH
            mesh = int(model.geom_dataid[g])
            vertices = model.mesh_vert[
                model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]
            ]
            planes = ConvexHull(vertices).equations
            depth = -(local @ planes[:, :3].T + planes[:, 3]).max(axis=1)
            box = rng.uniform(vertices.min(axis=0), vertices.max(axis=0), size=(20000, 3))
            drawn = box[(box @ planes[:, :3].T + planes[:, 3]).max(axis=1) <= 0][:2000]
        balls = np.isfinite(inside)
        assert balls.any() and (inside[balls] <= depth[balls] + 1e-12).all()  # each ball inside its geom
        covers = np.isfinite(cover)
        gap = np.linalg.norm(drawn[:, None] - local[covers][None], axis=-1) - cover[covers][None]
        assert (gap.min(axis=1) <= 1e-12).all()  # every point of the geom lies in a covering ball
    assert kinds == {int(mujoco.mjtGeom.mjGEOM_CAPSULE), int(mujoco.mjtGeom.mjGEOM_MESH)}


@pytest.mark.slow
def test_the_mug_search_screened_by_the_field_is_the_search_by_collision_queries(monkeypatch, tmp_path):
    (scene, trajectory, grasp, spec, *_), _ = _search_inputs(monkeypatch, tmp_path, obj="mug")
    screened, ranked = _searched(scene, trajectory, grasp, spec, screen=True)
    assert screened.collider._field is not None
    exact, ranked_exact = _searched(scene, trajectory, grasp, spec, screen=False)
    assert screened.collider.queries + screened.screened == exact.collider.queries
    assert screened.collider.queries < exact.collider.queries / 3  # what the field is for
    assert screened.feasible_poses == exact.feasible_poses
    assert _bits(ranked) == _bits(ranked_exact)
    assert _bits(screened.nearest) == _bits(exact.nearest)
