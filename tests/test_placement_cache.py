"""The placement search at the cost of few collision queries, and its cache.

Bounds settle many poses without a collision query (:meth:`HandObjectCollider.screen`): they must never
contradict MuJoCo's own detection, and the search with them must be the search without them. The cache
(:mod:`handsim.sim.placement.cache`) must give back the computed placement bit for bit and never trust a
corrupt entry.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import pickle

import mujoco
import numpy as np
import pytest
import trimesh

import handsim.sim.placement.collide as collide
import handsim.sim.placement.place as placement_module
import handsim.sim.scenarios as scenarios
from handsim.assets import ASSETS_DIR
from handsim.builders import build_object, build_scene, default_hand
from handsim.builders.arctic_objects import arctic_object
from handsim.builders.catalog import get
from handsim.sim.placement.cache import entry_path, placement_key, read_entry
from handsim.sim.placement.collide import HandObjectCollider
from handsim.sim.placement.hand_pose import targets_qpos
from handsim.sim.placement.place import _searched, place_object
from handsim.sim.placement.search import SCREEN_MARGIN
from handsim.sim.scene.compiled import SimScene, compile_scene
from handsim.sim.specs import PlacementSpec
from handsim.trials import load_trial

TENNIS = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"


def _bits(value) -> object:
    """A value's exact content, comparable with ``==``: floats as hex, arrays as dtype, shape and bytes."""
    if dataclasses.is_dataclass(value):
        return (
            type(value).__name__,
            tuple((f.name, _bits(getattr(value, f.name))) for f in dataclasses.fields(value)),
        )
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, (tuple, list)):
        return (type(value).__name__, tuple(_bits(v) for v in value))
    if isinstance(value, dict):
        return ("dict", tuple((k, _bits(v)) for k, v in value.items()))
    if isinstance(value, (float, np.floating)):
        return (type(value).__name__, float(value).hex())
    return (type(value).__name__, value)


def _search_inputs(monkeypatch, tmp_path, **options) -> tuple[tuple, dict]:
    """The arguments ``glove_scene`` passes to ``place_object`` for the demo tennis-ball grasp."""
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "cache"))
    seen = []
    original = scenarios.place_object

    def recording(*args, **kwargs):
        seen.append((args, kwargs))
        return original(*args, **kwargs)

    monkeypatch.setattr(scenarios, "place_object", recording)
    load_trial(TENNIS, **options)
    return seen[0]


@pytest.mark.parametrize("obj", ["tennis_ball", "mug", "business_card"])
def test_the_bounds_never_contradict_mujocos_collision_detection(monkeypatch, tmp_path, obj):
    (scene, trajectory, grasp, *_), _ = _search_inputs(monkeypatch, tmp_path, obj=obj)
    collider = HandObjectCollider(scene, 0.002)
    collider.set_hand(targets_qpos(scene, trajectory, grasp.closed))
    mujoco_centre = collider.data.site_xpos[scene.layout.tip_sites].mean(axis=0)
    rng = np.random.default_rng(7)
    positions = mujoco_centre + rng.uniform(-0.12, 0.12, size=(600, 3))
    quat = np.array([np.sqrt(0.5), np.sqrt(0.5), 0.0, 0.0])
    clear, overlap = collider.bounds(positions, quat)
    depths = np.array([collider.touch_at(p, quat).depth for p in positions])
    links = np.array([collider.touch_at(p, quat).links.size for p in positions])
    assert clear.sum() > 0 and (links[clear] == 0).all()
    if obj == "business_card":  # a box bounds no depth: MuJoCo's capsule–box depths can fall far short
        assert np.isneginf(overlap).all()
        return
    assert (overlap > 0.002 + SCREEN_MARGIN).sum() > 0  # both bounds decide some poses
    assert (overlap <= depths + SCREEN_MARGIN / 10).all()  # EPA's tolerance, well inside the margin


def _screened_and_exact(monkeypatch, tmp_path, **options) -> tuple:
    """The search of ``_search_inputs(**options)`` with and without the bounds, checked to be the same one:
    every pose counted, the same feasible poses, ranked candidates and nearest pose, bit for bit."""
    (scene, trajectory, grasp, spec, *_), _ = _search_inputs(monkeypatch, tmp_path, **options)
    screened, ranked = _searched(scene, trajectory, grasp, spec, screen=True)
    exact, ranked_exact = _searched(scene, trajectory, grasp, spec, screen=False)
    assert screened.collider.queries + screened.screened == exact.collider.queries
    assert screened.feasible_poses == exact.feasible_poses
    assert _bits(ranked) == _bits(ranked_exact)
    assert _bits(screened.nearest) == _bits(exact.nearest)
    return screened, exact


def test_the_search_screened_by_bounds_is_the_search_by_collision_queries(monkeypatch, tmp_path):
    screened, exact = _screened_and_exact(monkeypatch, tmp_path)
    assert screened.screened > 0 and exact.screened == 0
    assert screened.collider.queries < exact.collider.queries


@pytest.mark.slow
@pytest.mark.parametrize("obj", ["mug", "bowl", "business_card", "bottle_crate"])
def test_the_screened_search_is_the_search_by_collision_queries_on_catalogue_objects(
    monkeypatch, tmp_path, obj
):
    # convex meshes (mug, bowl) and boxes (card, crate): MuJoCo's capsule depths against a box can fall
    # far short of the true penetration, so boxes bound no depth and the two searches still agree
    _screened_and_exact(monkeypatch, tmp_path, obj=obj)


def test_a_cached_placement_is_the_computed_one_bit_for_bit(monkeypatch, tmp_path):
    args, kwargs = _search_inputs(monkeypatch, tmp_path)
    computed = place_object(*args, **kwargs, use_cache=False)

    def no_search(*_args, **_kwargs):
        raise AssertionError("searched although the placement was cached")

    monkeypatch.setattr(placement_module, "_place", no_search)
    cached = place_object(*args, **kwargs)  # written by load_trial's search
    assert _bits(cached) == _bits(computed)
    assert len(list((tmp_path / "cache" / "placement").rglob("*.pkl"))) == 1


def test_the_key_changes_with_the_spec_and_the_trajectory(monkeypatch, tmp_path):
    (scene, trajectory, grasp, spec, *_), _ = _search_inputs(monkeypatch, tmp_path)
    base = placement_key(scene, trajectory, grasp, {"spec": spec.to_dict()})
    other_spec = PlacementSpec(penetration=0.0025).to_dict()
    assert placement_key(scene, trajectory, grasp, {"spec": other_spec}) != base
    moved = trajectory.targets.copy()
    moved[0, 0] += 1e-12
    changed = dataclasses.replace(trajectory, targets=moved)
    assert placement_key(scene, changed, grasp, {"spec": spec.to_dict()}) != base
    assert placement_key(scene, trajectory, grasp, {"spec": spec.to_dict()}) == base


def test_a_corrupt_entry_is_ignored_with_a_note_and_replaced(monkeypatch, tmp_path):
    args, kwargs = _search_inputs(monkeypatch, tmp_path)
    (path,) = (tmp_path / "cache" / "placement").rglob("*.pkl")
    data = bytearray(path.read_bytes())
    data[-20] ^= 0xFF
    path.write_bytes(bytes(data))
    placement = place_object(*args, **kwargs)
    assert placement.note.endswith(
        f"; placement cache entry {path} was corrupt (checksum mismatch) and was replaced"
    )
    fresh = place_object(*args, **kwargs, use_cache=False)
    assert _bits(read_entry(path, path.stem, placement_module._CACHED_CLASSES)) == _bits(fresh)
    assert entry_path(tmp_path / "cache", path.stem) == path


def test_a_cache_that_cannot_be_written_gives_the_placement_with_a_note(monkeypatch, tmp_path):
    args, kwargs = _search_inputs(monkeypatch, tmp_path)
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the cache folder would be", encoding="utf-8")
    placement = place_object(*args, **kwargs, cache_dir=blocker)
    assert f"; could not write placement cache entry {blocker / 'placement'}" in placement.note
    fresh = place_object(*args, **kwargs, use_cache=False)
    assert _bits(dataclasses.replace(placement, note=fresh.note)) == _bits(fresh)


def test_the_contacts_of_an_articulated_objects_own_parts_are_not_the_hands(tmp_path):
    # An ARCTIC-style box whose lid sinks 1 mm into its base: their explicit contact pair (no contype filter
    # stops it) collides in the placement's collider too, and must count as no hand link and no depth.
    scene = _arctic_box(tmp_path, lid_bottom=-1.0)
    assert scene.model.npair > 0
    collider = HandObjectCollider(scene, 0.002)
    far = np.array([2.0, 2.0, 2.0])  # the object far from the hand: only its parts touch each other
    touch = collider.touch_at(far, np.array([1.0, 0.0, 0.0, 0.0]))
    assert collider.data.ncon > 0  # the parts' pair collided
    assert touch.links.size == 0 and touch.depth == 0.0
    assert collider.depth_links(far[None], np.array([1.0, 0.0, 0.0, 0.0])) == ([0.0], [0])


def test_the_batched_queries_are_mujocos_contacts_pose_by_pose():
    # distances reduces many queries' contacts at once; the reference reads MuJoCo's contacts one pose at a
    # time, each contact's link from its hand geom's body
    scene = compile_scene(build_scene(default_hand(), build_object(get("mug"))))
    collider = HandObjectCollider(scene, 0.002)
    collider.set_hand(scene.model.qpos0)
    model, data = collider.model, mujoco.MjData(collider.model)
    data.qpos[:] = collider.data.qpos
    mujoco.mj_kinematics(model, data)
    link_of = {int(body): i for i, body in enumerate(scene.layout.link_bodies)}
    palm = data.xpos[scene.layout.link_bodies[0]].copy()
    quat = np.array([0.5, 0.5, -0.5, 0.5])
    positions = palm + np.stack(np.meshgrid(*[np.linspace(-0.08, 0.08, 9)] * 3), axis=-1).reshape(-1, 3)
    expected = np.full((len(positions), len(link_of)), np.inf)
    a = collider.obj.free_qpos
    for row, pos in zip(expected, positions, strict=True):
        data.qpos[a : a + 7] = [*pos, *quat]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_collision(model, data)
        for c in data.contact:
            bodies = [int(model.geom_bodyid[g]) for g in c.geom]
            link = next((link_of[b] for b in bodies if b in link_of), None)
            if link is not None and c.dist <= 0.002:
                row[link] = min(row[link], c.dist)
    distances = collider.distances(positions, quat)
    np.testing.assert_array_equal(distances, expected)
    depths, links = collider.depth_links(positions, quat)
    assert depths == [max(0.0, -float(r.min())) for r in expected]
    assert links == [int(np.isfinite(r).sum()) for r in expected]
    assert all(type(d) is float for d in depths)
    assert sum(d > 0 for d in depths) > 50 and sum(n > 1 for n in links) > 50  # deep poses, several links
    touch = collider.touch_at(positions[40], quat)  # 8 links within the touch distance
    assert touch.links.size > 1
    np.testing.assert_array_equal(touch.distance, expected[40])
    assert touch.depth == depths[40]
    assert touch.links.tolist() == np.flatnonzero(np.isfinite(expected[40])).tolist()
    assert collider.depth_links(positions[:0], quat) == ([], [])


def _arctic_box(tmp_path, lid_bottom: float) -> SimScene:
    """The default hand and an ARCTIC-style box (a 12 × 6 × 16 cm base, its lid from ``lid_bottom`` mm up)."""
    folder = tmp_path / "box"
    folder.mkdir()
    for name, (low, high) in (("bottom", (-60.0, 0.0)), ("top", (lid_bottom, 10.0))):
        box = trimesh.creation.box(extents=(120.0, high - low, 160.0))
        box.apply_translation([-60.0, (low + high) / 2, 0.0])
        box.export(folder / f"{name}.obj")
    return compile_scene(build_scene(default_hand(), build_object(arctic_object(folder))))


def _palm_grid(scene: SimScene, half: float = 0.08, count: int = 9) -> tuple[HandObjectCollider, np.ndarray]:
    """A collider of the scene with the hand at rest, and a cubic grid of ``count``³ positions within
    ± ``half`` (m) of the palm."""
    collider = HandObjectCollider(scene, 0.002)
    collider.set_hand(scene.model.qpos0)
    mujoco.mj_kinematics(collider.model, collider.data)
    palm = collider.data.xpos[scene.layout.link_bodies[0]].copy()
    axis = np.linspace(-half, half, count)
    return collider, palm + np.stack(np.meshgrid(axis, axis, axis), axis=-1).reshape(-1, 3)


def _mug_grid() -> tuple[HandObjectCollider, np.ndarray, np.ndarray]:
    """A collider of the mug in the default hand at rest, a grid of positions about the palm and a turn."""
    collider, positions = _palm_grid(compile_scene(build_scene(default_hand(), build_object(get("mug")))))
    return collider, positions, np.array([0.5, 0.5, -0.5, 0.5])


def test_the_probe_settles_only_poses_the_full_query_finds_too_deep():
    # A pose settled by the probe (one geom pair's MuJoCo contacts) is one the full query reports deeper
    # than the tolerance; every other pose's answer is the full query's, and settled poses are not counted
    # as queries.
    collider, positions, quat = _mug_grid()
    full_depths, full_links = collider.depth_links(positions, quat)
    asked = collider.queries
    depths, links = collider.depth_links(positions, quat, settle=0.002)
    settled = [i for i, d in enumerate(depths) if d == np.inf]
    assert len(settled) > 50  # the grid goes deep into the mug: the probe settles many poses
    assert all(full_depths[i] > 0.002 for i in settled)
    assert all(links[i] == 0 for i in settled)
    kept = [i for i in range(len(positions)) if i not in settled]
    assert [depths[i] for i in kept] == [full_depths[i] for i in kept]
    assert [links[i] for i in kept] == [full_links[i] for i in kept]
    assert collider.queries == 2 * asked - len(settled)


def test_the_probe_is_not_used_where_it_cannot_pay_or_cannot_be_trusted(tmp_path):
    # A ball's full query costs what a probe does: not probed. An articulated object's explicit part pair
    # would collide in the probe too (its contacts are not the hand's): not probed.
    ball = compile_scene(build_scene(default_hand(), build_object(get("tennis_ball"))))
    box = _arctic_box(tmp_path, lid_bottom=0.0)
    for scene in (ball, box):
        collider, positions = _palm_grid(scene, half=0.05, count=7)
        quat = np.array([1.0, 0.0, 0.0, 0.0])
        expected = collider.depth_links(positions, quat)
        assert max(expected[0]) > 0.002  # deep poses a probe could have settled
        assert collider.depth_links(positions, quat, settle=0.002) == expected


def test_a_fork_probes_on_its_own_model():
    # The probe switches geom pairs on and off in a model of its own: a fork (another thread's collider)
    # must not share it, and its answers are the original's; so are a pickled copy's.
    collider, positions, quat = _mug_grid()
    collider.depth_links(positions, quat, settle=0.002)
    fork = collider.fork()
    assert fork.model is collider.model
    answers = fork.depth_links(positions, quat, settle=0.002)
    assert fork._probe is not None and fork._probe.model is not collider._probe.model
    full_depths, _ = collider.depth_links(positions, quat)
    assert all(d == f or (d == np.inf and f > 0.002) for d, f in zip(answers[0], full_depths, strict=True))
    copied = pickle.loads(pickle.dumps(collider))  # the probe (views into its model) is made again
    assert copied.depth_links(positions, quat, settle=0.002) == answers


def test_a_query_that_runs_out_of_contact_memory_is_an_error_not_a_wrong_depth():
    # With too little arena memory MuJoCo drops contacts (mjWARN_CONTACTFULL) and goes on: the depths would
    # be wrong, silently. 30 kB holds the mug's contacts at most poses of the grid, not at all.
    from handsim.errors import SimulationError

    spec = build_scene(default_hand(), build_object(get("mug")))
    spec.memory = 30_000
    collider, positions = _palm_grid(compile_scene(spec))
    quat = np.array([0.5, 0.5, -0.5, 0.5])
    assert collider.depth_links(positions[:3], quat) == ([0.0] * 3, [0] * 3)  # far poses: no contacts
    for settle in (None, 0.002):
        with pytest.raises(SimulationError, match=r"ran out of MuJoCo's contact memory .* 30000 bytes"):
            collider.depth_links(positions, quat, settle=settle)


def test_a_meshs_inscribed_ball_is_solved_once_per_process_and_never_shared():
    box = np.array(list(itertools.product([-0.01, 0.03], [0.0, 0.02], [0.0, 0.04])))  # 4 × 2 × 4 cm
    centre, radius = collide._inscribed_ball(box.tobytes(), box.shape)
    assert radius == pytest.approx(0.01 - 1e-6, abs=1e-9) and centre[1] == pytest.approx(0.01, abs=1e-9)
    scene = compile_scene(build_scene(default_hand(), build_object(get("mug"))))
    mesh = int(np.flatnonzero(scene.model.geom_type == mujoco.mjtGeom.mjGEOM_MESH)[-1])
    first = collide._core(scene.model, mesh)
    hits = collide._inscribed_ball.cache_info().hits
    first[0][:] = np.nan  # a caller changing its centre changes nobody else's
    again = collide._core(scene.model, mesh)
    assert collide._inscribed_ball.cache_info().hits == hits + 1
    assert np.isfinite(again[0]).all() and again[2] > 0


@pytest.mark.parametrize("duplicate", ["deepcopy", "pickle"])
def test_a_copied_collider_queries_its_own_data(duplicate):
    scene = compile_scene(build_scene(default_hand(), build_object(get("tennis_ball"))))
    collider = HandObjectCollider(scene, 0.002)
    twin = copy.deepcopy(collider) if duplicate == "deepcopy" else pickle.loads(pickle.dumps(collider))
    pos, quat = np.array([0.3, 0.1, 0.2]), np.array([1.0, 0.0, 0.0, 0.0])
    twin.touch_at(pos, quat)
    a = twin.obj.free_qpos
    np.testing.assert_array_equal(twin.data.qpos[a : a + 7], [*pos, *quat])
    assert not np.shares_memory(twin.data.qpos, collider.data.qpos)
